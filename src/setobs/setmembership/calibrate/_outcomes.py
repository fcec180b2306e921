"""What a calibration answers: the calibrated bound (:class:`NoiseCalibration`), a sample
that raised it (:class:`Outlier`) and the width against the bound (:class:`NoiseTradeoff`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["NoiseCalibration", "NoiseTradeoff", "Outlier"]


@dataclass(frozen=True)
class NoiseCalibration:
    """Result of :func:`calibrate_noise`.

    Attributes
    ----------
    radii : ndarray, shape (l,)
        Recommended per-channel measurement-noise radii: with a held-out part
        ``validated (1 + safety)``, else ``minimal`` (see
        :func:`calibrate_noise`'s notes), moved
        outward by ``CALIBRATION_RTOL`` (relative) and ``CALIBRATION_ATOL`` times
        the record's spread (``info["data_scale"]``), and checked before they are
        returned: a trajectory of the model, rebuilt from the LP's in extended
        precision with increments and process noise exactly within their bounds,
        explains every sample within them, its rounding's propagated effect included
        (``info["verified_noise"]`` is the noise it needs). Where that check needs
        more than the padding, the radii are raised to it (``info["padding"]``, the
        relative excess; a ``SolverWarning`` above ``PADDING_WARN``); where it cannot
        be made (``status == "unverified"``), a ``SolverWarning`` says so. A
        noise-free record gets about ``1e-9`` times its spread, not 0.
    minimal : ndarray, shape (l,)
        The smallest radii with which the calibrated part (the first ``1 - holdout``
        of the record, without the outliers) is consistent, to about ``1e-9``
        relative: the LP is solved twice, the second time for the correction of the
        first trajectory (iterative refinement), so that the solver's tolerances act
        on the residuals rather than on the signal.
    scale : float or None
        ``alpha``: the smallest consistent multiple of ``shape`` (``None`` in
        per-channel mode).
    increment : ndarray, shape (q,)
        The increment radii used.
    worst_step : ndarray, shape (l,)
        For each channel, a step where the optimal trajectory's residual
        ``|y - Xi x - Du u|`` reaches the bound (where the data are tightest).
    samples : int
        Measured samples used (rows with at least one finite entry).
    status : str
        ``"optimal"``; ``"almost optimal"`` when the chain's robust attempt
        answered at reduced accuracy; ``"unverified"`` when the radii could not be
        checked (both with a ``SolverWarning``).
    validated : ndarray, shape (l,)
        The smallest radii, at least ``minimal``, with which the whole record is
        consistent when its calibrated part keeps ``minimal`` (equal to ``minimal``
        with ``holdout=0``).
    active_samples : ndarray of int
        The samples at which ``minimal`` is attained (the LP's active rows, within
        ``CALIBRATION_ACTIVE_RTOL``), the tightest first: glitches and outliers show up here
        (:attr:`active_times`).
    validated_samples : ndarray of int
        The samples of the held-out part at which ``validated`` is attained (where it
        needed the margin; empty with no margin or without a held-out part), the
        tightest first: at exactly ``validated`` the bands collapse there.
    outliers : tuple of Outlier
        The samples removed (``max_outliers``), in order, with the bound with and
        without each.
    holdout, split, record_length, dt, output_names :
        The fraction held out, its first row (``None`` without), the record's length,
        its sampling time and output names (for :meth:`describe`).
    safety : float
        The relative safety ``radii`` add to ``validated`` (0 without a held-out part).
    info : dict
        Solver details: ``objective`` (the LP's optimal value), ``lower_bound``
        (the solver's dual bound on it), ``solver``, ``failed_attempts``,
        ``data_scale`` (the record's spread, which scales ``CALIBRATION_ATOL``),
        ``refined`` (whether the refinement round answered), ``verified_noise``,
        ``padding``, ``rounding_bound`` and ``drift_bound`` (the check's per-step
        rounding and its propagated effect on the outputs).
    """

    radii: NDArray[np.float64]
    minimal: NDArray[np.float64]
    scale: float | None
    increment: NDArray[np.float64]
    worst_step: NDArray[np.int64]
    samples: int
    status: str
    info: dict[str, Any] = field(default_factory=dict)
    validated: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    active_samples: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64))
    outliers: tuple[Outlier, ...] = ()
    validated_samples: NDArray[np.int64] = field(
        default_factory=lambda: np.zeros(0, dtype=np.int64))
    holdout: float = 0.0
    split: int | None = None
    record_length: int = 0
    dt: float | None = None
    output_names: tuple[str, ...] = ()
    safety: float = 0.0

    @property
    def ignored(self) -> NDArray[np.int64]:
        """The samples removed as outliers (sorted): pass ``ignore=`` them to the SMFDO
        (:meth:`ignore_mask`) to run with the same record as the calibration."""
        return np.array(sorted(o.sample for o in self.outliers), dtype=np.int64)

    def ignore_mask(self, N: int | None = None) -> NDArray[np.bool_]:
        """A boolean mask of length ``N`` (default the record's), True at :attr:`ignored`.

        Parameters
        ----------
        N : int, optional
            Length of the mask (default: the calibrated record's length).
        """
        m = np.zeros(self.record_length if N is None else int(N), dtype=bool)
        m[self.ignored[self.ignored < m.size]] = True
        return m

    @property
    def margin(self) -> NDArray[np.float64]:
        """``validated / minimal - 1`` (0 where ``minimal`` is 0): what the held-out part
        needed beyond the rest."""
        m = self.minimal
        return np.where(m > 0, self.validated / np.where(m > 0, m, 1.0) - 1.0, 0.0)

    @property
    def active_times(self) -> NDArray[np.float64] | None:
        """Times ``k dt`` of :attr:`active_samples` (``None`` without a sampling time)."""
        return (None if self.dt is None
                else np.asarray(self.active_samples * self.dt, dtype=np.float64))

    def describe(self) -> str:
        """What the calibration found, in words (the CLI prints it): the part of the
        record calibrated on, the margin its bound needed to explain the rest, where
        the bound is attained, the outliers removed."""
        names = list(self.output_names) or [f"y{i}" for i in range(self.minimal.size)]
        fmt = lambda v: ", ".join(f"{n} {x:.6g}" for n, x in zip(names, v, strict=True))  # noqa: E731
        at = lambda k: f"{k}" + ("" if self.dt is None else f" (t = {k * self.dt:.6g} s)")  # noqa: E731
        lines = []
        if self.split is None:
            lines.append(f"calibrated on the whole record ({self.samples} measured samples): "
                         f"smallest bound {fmt(self.minimal)}; no part held out to validate it "
                         "(holdout=0)")
        else:
            pct = 100.0 * self.split / max(self.record_length, 1)
            lines.append(f"calibrated on {pct:.0f} % of the record (samples 0-{self.split - 1})"
                         f": smallest bound {fmt(self.minimal)}")
            lines.append(f"the bound needed a margin of {fmt(100.0 * self.margin)} % to "
                         f"explain the other {100.0 - pct:.0f} %: validated {fmt(self.validated)}")
        for what, ks, shown in (("smallest", self.active_samples, 12),
                                ("validated", self.validated_samples, 6)):
            if ks.size:
                more = "" if ks.size <= shown else f" and {ks.size - shown} more"
                lines.append(f"the {what} bound is attained at sample(s) "
                             + ", ".join(at(int(k)) for k in ks[:shown]) + more)
        for o in self.outliers:
            lines.append(f"outlier removed: sample {at(o.sample)}: bound "
                         f"{fmt(o.bound_with)} with it, {fmt(o.bound_without)} without")
        extra = "" if self.split is None else \
            f"validated + {100.0 * self.safety:.3g} % safety, "
        lines.append(f"recommended radii ({extra}checked on the whole record): "
                     f"{fmt(self.radii)}")
        return "\n".join(lines)

    def __repr__(self) -> str:
        s = "" if self.scale is None else f", scale={self.scale:.6g}"
        v = "" if self.split is None else \
            f", validated={np.array2string(self.validated, precision=6)}"
        return (f"NoiseCalibration(radii={np.array2string(self.radii, precision=6)}{s}{v}, "
                f"samples={self.samples})")


@dataclass(frozen=True)
class Outlier:
    """A sample removed by :func:`calibrate_noise` (``max_outliers``): the one whose
    removal lowered the first part's smallest bound most at its round.

    Attributes
    ----------
    sample : int
        The sample (row of ``Y``).
    bound_with, bound_without : ndarray, shape (l,)
        The smallest bound of the first part with the sample and without it.
    """

    sample: int
    bound_with: NDArray[np.float64]
    bound_without: NDArray[np.float64]


@dataclass(frozen=True)
class NoiseTradeoff:
    """Result of :func:`noise_tradeoff`: for each increment scale ``beta`` (radii
    ``beta * increment``), the smallest consistent noise scale ``alpha`` (radii
    ``alpha * shape``).

    Parameters
    ----------
    beta : ndarray, shape (m,)
        Increment scales.
    alpha : ndarray, shape (m,)
        Smallest consistent noise scale for each ``beta``.
    increment : ndarray, shape (q,)
        The increment shape.
    shape : ndarray, shape (l,)
        The noise shape.
    output_names : tuple of str
        Output names (for labels).
    """

    beta: NDArray[np.float64]
    alpha: NDArray[np.float64]
    increment: NDArray[np.float64]
    shape: NDArray[np.float64]
    output_names: tuple[str, ...] = ()

    def plot(self, ax: Any = None) -> Any:
        """The trade-off curve: noise scale against increment scale (matplotlib).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default the current axes).
        """
        import matplotlib.pyplot as plt

        if ax is None:
            ax = plt.gca()
        ax.plot(self.beta, self.alpha, "o-")
        ax.set_xlabel("increment bound scale beta (|dd| <= beta r_dd)")
        ax.set_ylabel("smallest consistent noise scale alpha")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title("which bounds fit the record: consistent above the curve")
        ax.grid(True, which="both", alpha=0.3)
        return ax
