"""Which noise bound fits my data? One sparse LP over the whole record.

The record ``y_0 .. y_(N-1)`` is consistent with the model

    x[k+1] = Phi x[k] + Gamma u[k] + G d[k] + w[k],    |w[k]| <= r_w   (optional)
    d[k+1] = d[k] + dd[k],                             |dd[k]| <= beta r_dd
    y[k]   = Xi x[k] + Du u[k] + v[k],                 |v[k]|  <= alpha r_v

for given increment and process-noise boxes exactly when some trajectory
``(x_k, d_k)`` satisfies all these (in)equalities: a linear feasibility problem
in ``(x, d)``. The smallest consistent noise scale ``alpha`` (or per-channel
radii) is therefore one linear program over the whole record, sparse and
banded, solved on centred, scaled data by an interior-point method (Clarabel)
with checked answers and a fallback chain. This is the same consistency the exact SMFDO decides
step by step (its set becomes empty exactly when no trajectory exists), which
the tests check by bisection.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from typing import Any, Literal, NamedTuple, overload

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from .._validation import as_inputs, as_matrix, as_vector, check_real_scalar
from ..exceptions import (
    ArgumentError,
    DimensionError,
    InvalidValueError,
    SolverError,
    SolverWarning,
)
from ..geometry import Box
from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import (
    CALIBRATION_ACTIVE_RTOL,
    CALIBRATION_ATOL,
    CALIBRATION_CHECK_TOL,
    CALIBRATION_RTOL,
)

__all__ = ["NoiseCalibration", "NoiseTradeoff", "Outlier", "calibrate_noise",
           "noise_tradeoff"]


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


def _radii(name: str, value: Any, dim: int) -> NDArray[np.float64]:
    """Per-channel radii from a scalar, a vector or a symmetric Box."""
    if isinstance(value, Box):
        if not (np.allclose(value.lo, -value.hi) and np.isfinite(value.hi).all()):
            raise InvalidValueError(f"{name}: calibration takes boxes centred at 0; got "
                                 f"[{value.lo}, {value.hi}]")
        value = value.hi
    if value is None or isinstance(value, str | bytes) or callable(value) or hasattr(value, "G"):
        raise ArgumentError(f"{name} must be per-channel radii (a number or a vector) or a "
                            f"symmetric Box, got {type(value).__name__}")
    r = np.asarray(value, dtype=float)
    if r.ndim == 0:
        r = np.full(dim, float(r))
    r = as_vector(name, r, size=dim)
    if (r < 0).any() or not np.isfinite(r).all():
        raise InvalidValueError(f"{name} radii must be finite and nonnegative, got {r}")
    return r


class _RecordLP:
    """The LP data of one record, centred and scaled; re-solved for several increments.

    Centring: the trajectory is written as ``x_k = x_bar + x~_k``, ``d_k = d_bar + d~_k``
    with ``(x_bar, d_bar)`` the least-squares equilibrium at the record's mean input
    and output, an exact substitution (the dynamics' right-hand side takes the
    constant ``(Phi - I) x_bar + G d_bar``). Scaling: every datum (outputs, inputs,
    increment and process-noise radii) is divided by ``sigma``, the largest centred
    output, which divides the whole solution by it (the LP is homogeneous in data and
    variables). On the heat-exchanger record of the regression suite (outputs near
    100, noise near 2) this turns variables of size 100 into variables of size 1.
    """

    def __init__(self, sys: LinearSystem, Y: NDArray, U: NDArray | None,
                 process_noise: NDArray | None) -> None:
        self.sys = sys
        n, q, l = sys.n, sys.q, sys.l
        N = Y.shape[0]
        self.N = N
        self.Y, self.U, self.process_noise = Y, U, process_noise
        nx = (n + q) * N
        self.nx = nx
        # ---- outputs: residual r_k = y_k - Du u_k - Xi x_k for measured entries
        feed = U is not None and sys.p and np.any(sys.Du != 0)
        Yc = Y - (U[:N] @ sys.Du.T if feed and U is not None else 0.0)
        mask = np.isfinite(Yc)
        kk, ii = np.nonzero(mask)
        self.kk, self.ii = kk, ii
        yout = Yc[kk, ii]
        self.samples = int(mask.any(axis=1).sum())
        bu = (U[:N - 1] @ sys.Gamma.T if (U is not None and N > 1)
              else np.zeros((max(N - 1, 0), n)))
        # ---- centring: the least-squares equilibrium at the mean input and output
        ybar = np.array([yout[ii == i].mean() if np.any(ii == i) else 0.0 for i in range(l)])
        ubar = bu.mean(axis=0) if N > 1 else np.zeros(n)
        K = np.block([[sys.Phi - np.eye(n), sys.G], [sys.Xi, np.zeros((l, q))]])
        z = np.linalg.lstsq(K, np.concatenate([-ubar, ybar]), rcond=None)[0]
        if not np.isfinite(z).all():  # pragma: no cover - lstsq of finite data is finite
            z = np.zeros(n + q)
        self.x_bar, self.d_bar = z[:n], z[n:]
        yout = yout - (sys.Xi @ self.x_bar)[ii]
        bu = bu + ((sys.Phi - np.eye(n)) @ self.x_bar + sys.G @ self.d_bar)
        # ---- scaling: the largest centred output (1 for a record the equilibrium explains)
        spread = float(np.max(np.abs(yout))) if yout.size else 0.0
        self.sigma = spread if spread > 0.0 and np.isfinite(spread) else 1.0
        if not np.isfinite(self.sigma) or not np.isfinite(bu).all():
            raise InvalidValueError("the record's outputs or inputs are too large to calibrate "
                                 "in double precision")
        self.yout = yout / self.sigma
        self.bu = bu.reshape(-1) / self.sigma
        self.w = None if process_noise is None else process_noise / self.sigma
        # x_k at columns k*(n+q) .. +n, d_k at +n .. +n+q
        if N > 1:
            # ---- dynamics: x_{k+1} - Phi x_k - G d_k = Gamma u_k (+ w_k)
            base = sp.kron(sp.eye(N - 1), sp.hstack([sp.csr_matrix(-sys.Phi),
                                                      sp.csr_matrix(-sys.G)]), format="csr")
            left = sp.hstack([base, sp.csr_matrix((n * (N - 1), n + q))], format="csr")
            shift = sp.kron(sp.eye(N - 1), sp.hstack([sp.eye(n), sp.csr_matrix((n, q))]))
            right = sp.hstack([sp.csr_matrix((n * (N - 1), n + q)), shift], format="csr")
            self.Mdyn = (left + right).tocsr()
            # ---- increments: d_{k+1} - d_k
            dsel = sp.kron(sp.eye(N - 1), sp.hstack([sp.csr_matrix((q, n)), sp.eye(q)]))
            self.Minc = (sp.hstack([sp.csr_matrix((q * (N - 1), n + q)), dsel])
                         - sp.hstack([dsel, sp.csr_matrix((q * (N - 1), n + q))])).tocsr()
        else:
            self.Mdyn = sp.csr_matrix((0, nx))
            self.Minc = sp.csr_matrix((0, nx))
        cols, data, rr = [], [], []
        for j in range(n):
            cols.append(kk * (n + q) + j)
            data.append(sys.Xi[ii, j])
            rr.append(np.arange(kk.size))
        self.Mout = sp.csr_matrix((np.concatenate(data), (np.concatenate(rr),
                                   np.concatenate(cols))), shape=(kk.size, nx))

    # ------------------------------------------------------------------ the LP
    def _conic(self, inc: NDArray, weights: NDArray, per_channel: bool,
               fixed: NDArray | None = None, lower: NDArray | None = None):
        """The LP as ``min c^T z, A z + s = b, s in {0}^m_eq x R_+^m``: variables the
        centred, scaled trajectory, then the noise variables ``a`` (scalar mode:
        ``|r_ki| <= a w_i / max w``) or ``s_i`` (per channel: ``|r_ki| <= s_i``).

        ``fixed`` (one entry per measured row, NaN where the row's bound is the
        variable one): rows whose bound is a given number (scaled units), as the
        first part of a record with its calibrated bound; ``lower``: lower bounds of
        the noise variables (``a`` or ``s``, scaled)."""
        l, m = self.sys.l, self.yout.size
        nv = l if per_channel else 1
        wn = weights / np.max(weights)
        free = np.ones(m, dtype=bool) if fixed is None else np.isnan(fixed)
        if per_channel:
            S = sp.csr_matrix((np.ones(int(free.sum())), (np.flatnonzero(free),
                                                          self.ii[free])), shape=(m, l))
        else:
            S = sp.csr_matrix(np.where(free, wn[self.ii], 0.0).reshape(-1, 1))
        ybound = np.zeros(m) if fixed is None else np.where(free, 0.0, fixed)
        Z = sp.csr_matrix
        eq_A, eq_b, in_A, in_b = [], [], [], []
        N = self.N
        if N > 1:
            Mdyn, nd = self.Mdyn, self.Mdyn.shape[0]
            if self.w is None or not np.any(self.w):
                eq_A.append(sp.hstack([Mdyn, Z((nd, nv))]))
                eq_b.append(self.bu)
            else:
                rw = np.tile(self.w, N - 1)
                in_A += [sp.hstack([Mdyn, Z((nd, nv))]), sp.hstack([-Mdyn, Z((nd, nv))])]
                in_b += [self.bu + rw, rw - self.bu]
            ni = self.Minc.shape[0]
            r = np.tile(inc / self.sigma, N - 1)
            in_A += [sp.hstack([self.Minc, Z((ni, nv))]), sp.hstack([-self.Minc, Z((ni, nv))])]
            in_b += [r, r]
        in_A += [sp.hstack([self.Mout, -S]), sp.hstack([-self.Mout, -S]),
                 sp.hstack([Z((nv, self.nx)), -sp.eye(nv)])]
        in_b += [self.yout + ybound, ybound - self.yout,
                 np.zeros(nv) if lower is None else -np.asarray(lower, dtype=float)]
        m_eq = sum(a.shape[0] for a in eq_A)
        A = sp.vstack(eq_A + in_A, format="csc")
        b = np.concatenate(eq_b + in_b)
        c = np.zeros(self.nx + nv)
        c[self.nx:] = 1.0 / wn if per_channel else 1.0
        return A, b, c, m_eq

    def solve(self, inc: NDArray, weights: NDArray, per_channel: bool,
              time_limit: float = 120.0, fixed: NDArray | None = None,
              lower: NDArray | None = None) -> _LPSolution:
        """The smallest consistent noise: ``alpha`` (``|r_ki| <= alpha weights_i``) or,
        per channel, ``s`` minimising ``sum_i s_i / weights_i`` (``|r_ki| <= s_i``).

        The solver chain ends in an answer or a :class:`SolverError`, never a crash:
        Clarabel (interior point) at tight tolerances, then Clarabel with robust
        settings, then HiGHS's interior point through scipy. Each answer is checked
        on the centred, scaled LP (every row within ``CALIBRATION_CHECK_TOL``, the
        noise variables at least the largest residual of the returned trajectory)
        before it is accepted. HiGHS's dual simplex, which this function used
        before, segfaulted or stopped with "Not Set" on real records (the
        heat-exchanger LP of the regression suite) and took 10-15 s on the
        20 000-sample motor record, where Clarabel takes about 1 s.

        The answer is then refined (:meth:`_refine`): the solvers' tolerances are
        relative to the data, and the data are the signal (the record's spread), so
        a first answer is accurate to ``1e-10`` of the *signal*; on a long record of
        a marginally stable plant that left the optimum 4e-4 (relative) short
        (``calibration_recommended_inconsistent.py``).
        """
        A, b, c, m_eq = self._conic(inc, weights, per_channel, fixed, lower)
        free = None if fixed is None else np.isnan(fixed)
        first = self._chain(A, b, c, m_eq, weights, per_channel, time_limit, self.yout,
                            free=free)
        return self._refine(first, A, b, c, m_eq, weights, per_channel, time_limit, free)

    @overload
    def _chain(self, A, b: NDArray, c: NDArray, m_eq: int, weights: NDArray,
               per_channel: bool, time_limit: float, yout: NDArray,
               raise_on_failure: Literal[True] = ..., free: NDArray | None = None
               ) -> _LPSolution: ...

    @overload
    def _chain(self, A, b: NDArray, c: NDArray, m_eq: int, weights: NDArray,
               per_channel: bool, time_limit: float, yout: NDArray,
               raise_on_failure: bool = ..., free: NDArray | None = None
               ) -> _LPSolution | None: ...

    def _chain(self, A, b: NDArray, c: NDArray, m_eq: int, weights: NDArray,
               per_channel: bool, time_limit: float, yout: NDArray,
               raise_on_failure: bool = True, free: NDArray | None = None
               ) -> _LPSolution | None:
        """Solve ``min c^T z, A z + s = b`` by the solver chain; the checked answer
        (see :meth:`solve`), or ``None`` / a :class:`SolverError` if none is."""
        tried = []
        for name, attempt in SOLVER_CHAIN:
            try:
                z, lower, status = attempt(A, b, c, m_eq, time_limit)
            except Exception as exc:
                tried.append(f"{name}: {type(exc).__name__}: {exc}")
                continue
            if z is None:
                tried.append(f"{name}: {status}")
                continue
            ok, why, v = self._accept(z, A, b, m_eq, weights, per_channel, yout, free)
            if ok:
                return _LPSolution(z[:self.nx], v, lower, status, name, tuple(tried))
            tried.append(f"{name}: {status}, rejected: {why}")
        if not raise_on_failure:
            return None
        raise SolverError("the calibration LP failed under every solver (" + "; ".join(tried)
                          + "); check the record for non-finite or extreme values, or "
                          "shorten it", "; ".join(tried))

    def _refine(self, sol: _LPSolution, A, b: NDArray, c: NDArray, m_eq: int,
                weights: NDArray, per_channel: bool, time_limit: float,
                free: NDArray | None = None) -> _LPSolution:
        """One round of iterative refinement (Gleixner, Steffy and Wolter, "Iterative
        refinement for linear programming", INFORMS J. Comput. 28(3), 2016): the LP is
        re-solved for the correction ``delta`` of the trajectory ``x~`` found,
        ``A delta + s = b - A x~`` (the noise variables are not shifted), scaled by the
        largest entry of that right-hand side. Its data are now the residuals (the
        noise level), not the signal, so the solver's relative tolerances act on the
        residuals: on the 20 000-sample marginally stable record the optimum moves from
        4e-4 (relative) short to within 1e-9 of the states-eliminated LP in extended
        precision. The refined answer replaces the first only if the chain answers."""
        nx = self.nx
        shift = b - A[:, :nx] @ sol.x
        s2 = float(np.max(np.abs(shift), initial=0.0))
        if not (np.isfinite(s2) and s2 > 0.0):
            return sol
        yres = (self.yout - self.Mout @ sol.x) / s2
        fine = self._chain(A, shift / s2, c, m_eq, weights, per_channel, time_limit, yres,
                           raise_on_failure=False, free=free)
        if fine is None:
            return _LPSolution(sol.x, sol.v, sol.lower, sol.status, sol.solver,
                               (*sol.failed, "refinement: no solver answered"))
        x = sol.x + s2 * fine.x
        v = s2 * fine.v
        return _LPSolution(x, v, s2 * fine.lower, _worse(sol.status, fine.status),
                           sol.solver if fine.solver == sol.solver
                           else f"{sol.solver}, refined by {fine.solver}",
                           sol.failed + fine.failed, True)

    def _accept(self, z: NDArray, A, b: NDArray, m_eq: int, weights: NDArray,
                per_channel: bool, yout: NDArray, free: NDArray | None = None
                ) -> tuple[bool, str, NDArray]:
        """Check a solver's point on the scaled LP; return the noise variables it proves
        (``yout``: the scaled outputs the trajectory variables are measured against;
        ``free``: the rows whose bound is the noise variable, default all)."""
        if not np.isfinite(z).all():
            return False, "non-finite solution", z
        res = A @ z - b
        scale = 1.0 + np.max(np.abs(z[:self.nx]), initial=0.0)
        viol = max(np.max(np.abs(res[:m_eq]), initial=0.0),
                   np.max(res[m_eq:], initial=0.0))
        if viol > CALIBRATION_CHECK_TOL * scale:
            return False, f"constraint violation {viol:.3g}", z
        # the noise the returned trajectory needs (outward: at least the solver's value)
        r = np.abs(yout - self.Mout @ z[:self.nx])
        ii = self.ii
        if free is not None:
            r, ii = r[free], ii[free]
        wn = weights / np.max(weights)
        if per_channel:
            need = np.array([np.max(r[ii == i], initial=0.0) for i in range(self.sys.l)])
            v = np.maximum(z[self.nx:], need)
        else:
            v = np.array([max(float(z[self.nx]), float(np.max(r / wn[ii], initial=0.0)))])
        return True, "", np.maximum(v, 0.0)


def _worse(a: str, b: str) -> str:
    """The less accurate of two solver statuses."""
    return a if a != "optimal" else b


def _clarabel_attempt(robust: bool):
    def attempt(A, b, c, m_eq, time_limit):
        import clarabel

        st = clarabel.DefaultSettings()
        st.verbose = False
        st.time_limit = float(time_limit)
        if robust:
            st.max_iter = 1000
            st.static_regularization_constant = 1e-7
            st.iterative_refinement_max_iter = 50
            st.tol_gap_abs = st.tol_gap_rel = st.tol_feas = 1e-8
        else:
            st.max_iter = 300
            st.tol_gap_abs = st.tol_gap_rel = st.tol_feas = 1e-10
        P = sp.csc_matrix((A.shape[1], A.shape[1]))
        cones = [clarabel.ZeroConeT(m_eq), clarabel.NonnegativeConeT(A.shape[0] - m_eq)]
        if m_eq == 0:
            cones = cones[1:]
        sol = clarabel.DefaultSolver(P, c, A.tocsc(), b, cones, st).solve()
        S = clarabel.SolverStatus
        good = (S.Solved, S.AlmostSolved) if robust else (S.Solved,)
        name = str(sol.status).rsplit(".", 1)[-1]
        if sol.status not in good:
            return None, np.nan, name
        status = "optimal" if sol.status == S.Solved else "almost optimal"
        return np.asarray(sol.x, dtype=float), float(sol.obj_val_dual), status
    return attempt


def _highs_ipm_attempt(A, b, c, m_eq, time_limit):
    from scipy.optimize import linprog

    r = linprog(c, A_ub=A[m_eq:], b_ub=b[m_eq:], A_eq=A[:m_eq] if m_eq else None,
                b_eq=b[:m_eq] if m_eq else None, bounds=(None, None), method="highs-ipm",
                options={"time_limit": float(time_limit), "presolve": False})
    if r.status != 0 or r.x is None:
        return None, np.nan, f"HiGHS status {r.status} ({r.message})"
    lower = getattr(r, "fun", np.nan)
    return np.asarray(r.x, dtype=float), float(lower), "optimal"


#: The solvers :func:`calibrate_noise` tries, in order: ``(name, attempt)`` with
#: ``attempt(A, b, c, m_eq, time_limit) -> (z or None, dual bound, status)`` for
#: ``min c^T z, A z + s = b, s in {0}^m_eq x R_+``. Each answer is checked before
#: it is accepted (``_RecordLP._accept``); the tests insert failing solvers here.
SOLVER_CHAIN = (("clarabel", _clarabel_attempt(False)),
          ("clarabel (robust settings)", _clarabel_attempt(True)),
          ("HiGHS interior point (scipy)", _highs_ipm_attempt))


class _LPSolution(NamedTuple):
    x: NDArray[np.float64]       # the centred, scaled trajectory
    v: NDArray[np.float64]       # the noise variables (scaled), proved by the trajectory
    lower: float                 # the solver's dual objective (scaled; NaN if unknown)
    status: str                  # "optimal" or "almost optimal"
    solver: str
    failed: tuple[str, ...]      # earlier attempts of the chain and why they were passed over
    refined: bool = False        # whether the refinement round answered


def _witness_noise(lp: _RecordLP, x: NDArray[np.float64], inc: NDArray[np.float64]
                   ) -> tuple[NDArray[np.float64], dict[str, float]]:
    """Per-channel noise that an exactly consistent trajectory needs, from the LP's
    trajectory ``x`` (centred, scaled): the check of the recommended radii.

    The trajectory is rebuilt in the original units as one of the model, in extended
    precision (``numpy.longdouble``): ``d'`` follows the LP's disturbance by
    increments clipped into their bound (shrunk by two units in the last place, so
    that the rounded sum stays within it), ``x'`` is simulated from the LP's ``x_0``
    with the LP's process noise clipped into its bound (``w' = clip(x_(k+1) - Phi x'_k
    - ..., r_w)``: the noise steers ``x'`` back to the LP's trajectory) and the
    record's inputs. So increments and noise are within their bounds exactly, and
    ``x'`` satisfies the dynamics up to the rounding ``e_k`` of each step, bounded by
    Higham's ``gamma`` on the absolute products (``|e_k| <= E``). The exact trajectory
    from ``x'_0`` with the same ``d'``, ``w'`` differs from ``x'`` by ``sum_(j<k)
    Phi^(k-1-j) e_j``, whose effect on output ``i`` is at most ``S_i E`` with
    ``S_i = sum_(m<N) ||Xi_i Phi^m||_1`` (the powers in double precision, doubled
    for their own rounding). The returned noise is, per channel, the largest
    ``|y - Du u - Xi x'|`` (its own rounding bound added) plus ``S_i E``: radii at or
    above it make the record consistent. It is infinite when the plant is unstable
    enough that ``S_i`` overflows (the trajectory cannot be checked this way).
    """
    L = np.longdouble
    sys = lp.sys
    n, q, l, p = sys.n, sys.q, sys.l, sys.p
    N = lp.N
    Z = x.reshape(N, n + q)
    sig = L(lp.sigma)
    Xh = np.asarray(lp.x_bar, dtype=L) + sig * Z[:, :n].astype(L)
    Dh = np.asarray(lp.d_bar, dtype=L) + sig * Z[:, n:].astype(L)
    Phi, G, Xi = (np.asarray(M, dtype=L) for M in (sys.Phi, sys.G, sys.Xi))
    aPhi, aG = np.abs(Phi), np.abs(G)
    U = None if lp.U is None or not p else np.asarray(lp.U, dtype=L)
    Gam = np.asarray(sys.Gamma, dtype=L)
    aGam = np.abs(Gam)
    rw = None if lp.process_noise is None else np.asarray(lp.process_noise, dtype=L)
    incL = np.asarray(inc, dtype=L)
    u_l = float(np.finfo(L).eps) / 2.0
    g_terms = n + q + p + 3
    g = g_terms * u_l / (1.0 - g_terms * u_l)
    Xs = np.empty((N, n), dtype=L)
    Ms = np.zeros((max(N - 1, 0), n), dtype=L)  # each step's |products| + |result|
    xk, dk = Xh[0].copy(), Dh[0].copy()
    for k in range(N):
        Xs[k] = xk
        if k == N - 1:
            break
        pred = Phi @ xk
        mag = aPhi @ np.abs(xk)
        if q:
            pred = pred + G @ dk
            mag = mag + aG @ np.abs(dk)
        if U is not None:
            pred = pred + Gam @ U[k]
            mag = mag + aGam @ np.abs(U[k])
        if rw is not None:
            room = np.maximum(rw - 2 * np.spacing(np.abs(pred) + rw), L(0))
            w = np.clip(Xh[k + 1] - pred, -room, room)
            pred = pred + w
            mag = mag + np.abs(w)
        Ms[k] = mag + np.abs(pred)
        xk = pred
        if q:
            room = np.maximum(incL - 2 * np.spacing(np.abs(dk) + incL), L(0))
            dk = dk + np.clip(Dh[k + 1] - dk, -room, room)
    E = float(g * Ms.max(initial=L(0)))
    # output residuals and their rounding
    Yr = np.asarray(lp.Y, dtype=L)
    out = Xs @ Xi.T
    omag = np.abs(Xs) @ np.abs(Xi).T + np.abs(Yr)
    if U is not None and np.any(sys.Du != 0):
        Du = np.asarray(sys.Du, dtype=L)
        out = out + U[:N] @ Du.T
        omag = omag + np.abs(U[:N]) @ np.abs(Du).T
    go = (n + p + 2) * u_l / (1.0 - (n + p + 2) * u_l)
    with np.errstate(invalid="ignore"):
        res = np.abs(Yr - out) + go * omag
    res = np.where(np.isfinite(lp.Y), res, L(0)).astype(np.float64)
    need = np.nextafter(res.max(axis=0), np.inf)
    # S_i = sum_m ||Xi_i Phi^m||_1 (doubled): the outputs' sensitivity to the rounding
    S = np.zeros(l)
    if E > 0.0:
        P = np.array(sys.Xi, dtype=np.float64)
        with np.errstate(over="ignore", invalid="ignore"):
            for _ in range(N):
                S += np.abs(P).sum(axis=1)
                if not np.isfinite(S).all():
                    S[:] = np.inf
                    break
                P = P @ sys.Phi
        S *= 2.0
    with np.errstate(invalid="ignore"):
        drift = np.where(S > 0.0, S * E, 0.0)
    need = need + np.nextafter(drift, np.inf)
    return need, {"rounding_bound": E, "drift_bound": float(np.max(drift, initial=0.0))}


def _setup(sys, Y, U, increment, shape, process_noise, disturbance_inputs):
    """Validated inputs of both entry points: the system, the record's LP, the
    increment radii and the noise shape."""
    sys, Ya, Ua = _prepare(sys, Y, U, disturbance_inputs)
    inc = _radii("increment", increment, sys.q)
    w = None if process_noise is None else _radii("process_noise", process_noise, sys.n)
    return sys, _RecordLP(sys, Ya, Ua, w), inc, _shape(shape, sys.l)


def _prepare(sys, Y, U, disturbance_inputs):
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    Ya = as_matrix("Y", Y, cols=sys.l, allow_nan=True)
    Ua = as_inputs(sys.p, U)
    if Ua is not None:
        if Ua.shape[0] < Ya.shape[0] - 1 or (np.any(sys.Du != 0) and Ua.shape[0] < Ya.shape[0]):
            raise DimensionError(f"U must have N = {Ya.shape[0]} rows (N - 1 without a "
                                 f"feedthrough), got {Ua.shape[0]}")
    if not np.isfinite(Ya).any():
        raise InvalidValueError("Y has no measured (finite) entry")
    return sys, Ya, Ua


#: Relative safety the recommended radii of a validated calibration add to
#: ``validated``: a bound that is attained exactly collapses a band there (see
#: :func:`calibrate_noise`'s notes; on the motor record, 10 % leaves a narrowest
#: velocity band of 0.4-0.8 rad/s where the smallest bound leaves 0.02-0.05).
SAFETY_MARGIN = 0.1


def calibrate_noise(sys: LinearSystem, Y: ArrayLike, U: ArrayLike | None = None, *,
                    increment: Any, shape: Any = None, per_channel: bool = False,
                    process_noise: Any = None,
                    disturbance_inputs: DisturbanceInputs = None,
                    time_limit: float = 120.0, holdout: float = 0.3,
                    max_outliers: int = 0,
                    safety: float = SAFETY_MARGIN) -> NoiseCalibration:
    """The smallest measurement-noise bound that makes a record consistent, calibrated on
    the first part of the record and validated on the rest.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The model (a ``StateSpace`` with ``disturbance_inputs``).
    Y : array_like, shape (N, l)
        The record; NaN entries are not measured.
    U : array_like, shape (N, p), optional
        Inputs (required when the system has inputs; ``U[k]`` acts between
        ``y_k`` and ``y_(k+1)``, as in :meth:`SMFDO.run`).
    increment : float, array_like or Box
        Increment radii ``r_dd`` (``|d_(k+1) - d_k| <= r_dd``), as for the SMFDO.
    shape : float, array_like or Box, optional
        Noise shape ``r_v``: the result is the smallest ``alpha`` with
        ``|v_k| <= alpha r_v`` (default ``r_v = 1`` on every channel).
    per_channel : bool
        Instead of a scaling, per-channel radii ``s`` minimising
        ``sum_i s_i / r_v,i`` (one point of the Pareto set: the channels trade
        off against each other through the shared trajectory).
    process_noise : float, array_like or Box, optional
        Process-noise radii ``|w_k| <= r_w`` (state space, identity matrix).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances; the others are control inputs.
    time_limit : float
        Seconds each solver of the chain may take (a hard limit; default 120).
    holdout : float
        Fraction of the record (its last samples) held out to validate the bound
        (default 0.3; 0: calibrate on the whole record, no validation).
    max_outliers : int
        Up to this many samples removed, one at a time, each the one whose removal
        lowers the first part's smallest bound most (re-solving for each candidate among
        the samples where the bound is attained); named in ``outliers`` (default 0).
    safety : float
        Relative safety the recommended ``radii`` add to ``validated`` (default
        ``SAFETY_MARGIN`` = 0.1, see the notes; 0: the radii are ``validated``, and a
        band may collapse where it is attained). Ignored with ``holdout=0``.

    Returns
    -------
    NoiseCalibration
        ``minimal`` (the first part's smallest bound), ``validated`` (the smallest
        bound, at least ``minimal``, with which the whole record is consistent when the
        first part keeps ``minimal``), ``margin`` (``validated / minimal - 1``),
        ``radii`` (``validated (1 + safety)``, padded and checked on the whole
        record: the bound to use), ``active_samples``,
        ``outliers``, ``scale``, ``worst_step``;
        :meth:`NoiseCalibration.describe` says it in words.

    Raises
    ------
    SolverError
        If no solver of the chain returns a checked optimum (never a silent answer).

    Warns
    -----
    SolverWarning
        When the answer comes from a solve at reduced accuracy (``status`` is
        ``"almost optimal"``): the bound is still consistent, perhaps not the smallest.

    Notes
    -----
    *Validation.* "Calibrated on 70 % of the record, the bound needed a margin of
    ``m`` to explain the other 30 %": ``minimal`` is the smallest bound of the first
    ``1 - holdout`` of the record; ``validated`` the smallest bound for the rest, the
    first part keeping ``minimal`` (the same LP on the whole record, the first part's
    rows at ``minimal``, the rest's at a variable bound of at least ``minimal``). The
    default ``holdout = 0.3`` is there so that a band does not collapse: at the
    smallest bound of a record the bound is attained somewhere (an active sample), and
    there the consistent set is pinned to a point and its band to a width near zero
    (the motor record at its minimum of 2.68 counts: velocity bands of 0.02 rad/s that
    miss an independent velocity). ``validated`` is itself the smallest bound of a
    problem, so some sample attains it and its band collapses there too (the motor
    record: 2.68 counts, the whole record's minimum, set by glitches in its last
    third). The recommended ``radii`` are therefore ``validated (1 + safety)``,
    by default 10 % above it, so that no sample sits exactly at the bound (the motor record: 2.94
    counts, narrowest velocity band 0.83 rad/s against 0.02 at the minimum, every band
    consistent with a central-difference velocity and its own error bound). Applying
    the measured margin once more instead ("what the last 30 % needed, allowed again
    for data not yet seen") gave 14 times the minimum on a 25-sample record: the margin
    is reported, not compounded. With ``holdout=0`` the radii are the whole record's
    minimum, padded only for the solver's accuracy.

    Consistency is the exact SMFDO's (Li-Cong-Dong, Algorithm 1 with
    ``delta`` = the whole record, eqs. (20)-(21) with noise): the posterior set
    is empty exactly when no trajectory ``(x_k, d_k)`` explains the data within
    the sets, which is the LP's feasibility. A windowed SMFDO forgets old data
    and may accept a smaller bound.

    The LP is solved on centred, scaled data (see ``_RecordLP``) by a solver chain
    that ends in a checked answer or a :class:`SolverError` (Clarabel, then
    Clarabel with robust settings, then HiGHS's interior point); ``info`` names
    the solver, the dual lower bound and the attempts passed over.

    The recommended ``radii`` are ``target (1 + CALIBRATION_RTOL) +
    CALIBRATION_ATOL * spread`` (``target``: ``validated (1 + safety)``, or ``minimal``
    with ``holdout=0``), then checked, with ``spread`` the largest deviation of a
    measured output from the record's equilibrium (``info["data_scale"]``): a
    record that the model explains exactly (no noise at all) gets radii of about
    ``1e-9 spread``, not 0 -- the solver's accuracy, not a noise level.

    Examples
    --------
    >>> import numpy as np, setobs as so
    >>> sys = so.LinearSystem([[1.0]], [[1.0]], [[1.0]])
    >>> Y = np.array([[0.0], [1.0], [0.0], [1.0]])     # alternating: |dd| <= 0 fits with noise 1/2
    >>> round(float(calibrate_noise(sys, Y, increment=0.0).minimal[0]), 6)
    0.5
    """
    sys, Ya, Ua = _prepare(sys, Y, U, disturbance_inputs)
    inc = _radii("increment", increment, sys.q)
    w = None if process_noise is None else _radii("process_noise", process_noise, sys.n)
    r_v = _shape(shape, sys.l)
    limit = _time_limit(time_limit)
    N = Ya.shape[0]
    split = _split(Ya, holdout)
    k_out = _max_outliers(max_outliers)
    safety = check_real_scalar("safety", safety, nonnegative=True)
    wmax = float(np.max(r_v))
    ignore = np.zeros(N, dtype=bool)

    def fit(ignored):
        """The first part's LP (without the ignored samples): (lp, solution, bound)."""
        Yf = Ya if split is None else Ya[:split]
        Yf = np.where(ignored[:Yf.shape[0], None], np.nan, Yf)
        if not np.isfinite(Yf).any():
            raise InvalidValueError("no measured sample is left in the calibrated part")
        Uf = Ua if (Ua is None or split is None) else Ua[:split]
        lp = _RecordLP(sys, Yf, Uf, w)
        sol = lp.solve(inc, r_v, per_channel, limit)
        return lp, sol, radii_of(lp, sol)

    def radii_of(lp, sol):
        """The radii of the LP's noise variable (per channel, or a scale of the shape)."""
        return sol.v * lp.sigma if per_channel else float(sol.v[0]) * lp.sigma / wmax * r_v

    def objective(bound):
        return float(np.sum(bound / r_v))

    lp_f, res_f, minimal = fit(ignore)
    outliers: list[Outlier] = []
    for _ in range(k_out):  # greedy: the active sample whose removal lowers the bound most
        best = None
        for k in _active(lp_f, res_f, minimal)[:MAX_OUTLIER_CANDIDATES]:
            trial = ignore.copy()
            trial[k] = True
            try:
                cand = fit(trial)
            except InvalidValueError:  # (no measured sample left in the calibrated part)
                continue
            if best is None or objective(cand[2]) < objective(best[1][2]):
                best = (k, cand)
        if best is None or objective(best[1][2]) >= objective(minimal) * (1.0 - 1e-9):
            break
        k, cand = best
        outliers.append(Outlier(int(k), minimal, cand[2]))
        ignore[k] = True
        lp_f, res_f, minimal = cand
    scale = None if per_channel else float(minimal[0] / r_v[0])
    active = _active(lp_f, res_f, minimal)
    # the whole record with the first part's bound: the smallest bound of the rest
    val_active = np.zeros(0, dtype=np.int64)
    if split is None:
        lp, res, validated = lp_f, res_f, minimal
    else:
        Yw = np.where(ignore[:, None], np.nan, Ya)
        lp = _RecordLP(sys, Yw, Ua, w)
        fixed = np.where(lp.kk < split, minimal[lp.ii] / lp.sigma, np.nan)
        lower = (minimal / lp.sigma if per_channel or scale is None
                 else np.array([scale * wmax / lp.sigma]))
        res = lp.solve(inc, r_v, per_channel, limit, fixed=fixed, lower=lower)
        validated = np.maximum(minimal, radii_of(lp, res))
        # within the LP's accuracy of minimal: no margin (the radii are checked below)
        validated = np.where(validated <= minimal * (1.0 + CALIBRATION_ACTIVE_RTOL), minimal,
                             validated)
        if np.any(validated > minimal):
            held = _active(lp, res, validated)
            val_active = held[held >= split]
    # the bound to use: validated with a safety, so that no sample sits exactly at it
    target = validated if split is None else validated * (1.0 + safety)
    standard = target + (CALIBRATION_RTOL * target + CALIBRATION_ATOL * lp.sigma)
    # the check: the noise an exactly consistent trajectory needs (see _witness_noise)
    need, wit = _witness_noise(lp, res.x, inc)
    status = _worse(res_f.status, res.status)
    if np.isfinite(need).all():
        # per channel, or (a scale) the same multiple of the shape on every channel
        cand = need if per_channel else np.nextafter(
            float(np.max(need / r_v)) * (1.0 + 4.0 * np.finfo(float).eps) * r_v, np.inf)
        radii = standard if np.all(cand <= standard) else np.maximum(standard, cand)
        padding = float(np.max(radii / np.where(standard > 0, standard, 1.0) - 1.0))
    else:
        radii, padding = standard, float("nan")
        status = "unverified"
    resid = np.abs(lp_f.yout - lp_f.Mout @ res_f.x)
    worst = np.zeros(sys.l, dtype=np.int64)
    for i in range(sys.l):
        sel = lp_f.ii == i
        if sel.any():
            worst[i] = int(lp_f.kk[sel][np.argmax(resid[sel])])
    lower_b = res_f.lower * lp_f.sigma / (1.0 if per_channel else wmax)
    info = {"objective": objective(minimal) if per_channel else scale,
            "lower_bound": float(lower_b), "solver": res_f.solver,
            "failed_attempts": res_f.failed + (() if res is res_f else res.failed),
            "data_scale": lp.sigma, "refined": res_f.refined and res.refined,
            "verified_noise": need, "padding": padding, **wit}
    if status == "unverified":
        warnings.warn("calibrate_noise: the recommended radii could not be checked against "
                      "an exactly consistent trajectory (the plant is too unstable over "
                      f"{lp.N} samples for the check: drift bound {wit['drift_bound']:.3g}); "
                      "they are the LP optimum padded by CALIBRATION_RTOL and "
                      "CALIBRATION_ATOL, unverified: check them with the SMFDO, or calibrate "
                      "a shorter record", SolverWarning, stacklevel=2)
    elif padding > PADDING_WARN:
        warnings.warn(f"calibrate_noise: the recommended radii are {padding:.3g} (relative) "
                      "above the LP optimum's usual padding: the exactly consistent "
                      "trajectory that checks them needs that much more (a long record of "
                      "an unstable or marginally stable plant); they are consistent, the "
                      "optimum may be less accurate", SolverWarning, stacklevel=2)
    elif status != "optimal":
        warnings.warn(f"calibrate_noise: {res_f.solver} returned an inaccurate optimum "
                      f"({status}); the recommended radii are checked against an "
                      "exactly consistent trajectory and make the record consistent, but "
                      "may not be the smallest", SolverWarning, stacklevel=2)
    return NoiseCalibration(
        radii, minimal, scale, inc, worst, lp.samples, status, info, validated=validated,
        active_samples=active, outliers=tuple(outliers),
        validated_samples=val_active,
        holdout=0.0 if split is None else float(holdout), split=split, record_length=N,
        dt=sys.dt, output_names=tuple(sys.output_names),
        safety=0.0 if split is None else float(safety))


#: Candidates :func:`calibrate_noise` tries per outlier round (the active samples with
#: the largest residuals; each costs one LP).
MAX_OUTLIER_CANDIDATES = 8


def _active(lp: _RecordLP, sol: _LPSolution, bound: NDArray[np.float64]) -> NDArray[np.int64]:
    """The samples at which the LP's trajectory attains the bound (its active rows),
    the largest residuals (relative to the bound) first."""
    r = np.abs(lp.yout - lp.Mout @ sol.x) * lp.sigma
    b = bound[lp.ii]
    tol = CALIBRATION_ACTIVE_RTOL * b + CALIBRATION_ATOL * lp.sigma
    hit = (r >= b - tol) & (b > 0)
    if not hit.any():
        return np.zeros(0, dtype=np.int64)
    rel = r[hit] / b[hit]
    ks = lp.kk[hit][np.argsort(-rel, kind="stable")]
    _, first = np.unique(ks, return_index=True)
    return ks[np.sort(first)].astype(np.int64)


def _split(Y: NDArray[np.float64], holdout: float) -> int | None:
    """The first held-out row for ``holdout`` (a fraction in ``[0, 1)``), or ``None``."""
    h = check_real_scalar("holdout", holdout, nonnegative=True)
    if h >= 1.0:
        raise InvalidValueError(f"holdout must be a fraction in [0, 1), got {holdout!r}")
    if h == 0.0:
        return None
    N = Y.shape[0]
    split = max(1, min(int(np.ceil((1.0 - h) * N)), N - 1))  # (both parts nonempty)
    meas = np.asarray(np.isfinite(Y).any(axis=1))
    if N < 2 or not meas[:split].any() or not meas[split:].any():
        raise InvalidValueError(
            f"holdout={holdout!r} leaves no measured sample in one of the parts of a "
            f"{N}-sample record (calibrated: rows 0-{split - 1}); use a longer record or "
            "holdout=0 (no validation)")
    return split


def _max_outliers(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise InvalidValueError(f"max_outliers must be a nonnegative integer, got {value!r}")
    return int(value)


def _shape(shape: Any, l: int) -> NDArray[np.float64]:
    r_v = np.ones(l) if shape is None else _radii("shape", shape, l)
    if (r_v <= 0).any():
        raise InvalidValueError(f"shape radii must be positive, got {r_v}")
    return r_v


#: Padding of the recommended radii beyond the usual (relative) above which
#: :func:`calibrate_noise` warns.
PADDING_WARN = 1e-3


def _time_limit(value: float) -> float:
    t = float(value)
    if not (t > 0.0):
        raise InvalidValueError(f"time_limit must be positive (seconds), got {value!r}")
    return t


def noise_tradeoff(sys: LinearSystem, Y: ArrayLike, U: ArrayLike | None = None, *,
                   increment: Any, betas: ArrayLike | None = None, shape: Any = None,
                   process_noise: Any = None,
                   disturbance_inputs: DisturbanceInputs = None) -> NoiseTradeoff:
    """The trade-off between the increment bound and the noise bound for a record.

    For each ``beta`` in ``betas`` (default 13 points, log-spaced over
    ``[1e-3, 1e3]``), the smallest noise scale ``alpha`` with which the record
    is consistent when ``|dd| <= beta * increment`` (one LP each, see
    :func:`calibrate_noise`). Pairs above the curve are consistent, pairs
    below are not; ``alpha`` never increases with ``beta``.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The model.
    Y : array_like, shape (N, l)
        Measurements (NaN: missing).
    U : array_like, shape (N, p), optional
        Inputs (required when the system has inputs).
    increment : array_like or Box or ConstrainedZonotope
        Shape of the increment bound ``|dd| <= beta * increment``.
    betas : array_like, optional
        Increment scales (default 13 points log-spaced over ``[1e-3, 1e3]``).
    shape : array_like, optional
        Shape of the noise bound (per-channel radii; default ones).
    process_noise : array_like or Box or ConstrainedZonotope, optional
        Bound of the process noise ``w`` (as in :class:`SMFDO`).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances; the others are control inputs.
    """
    sys, lp, inc, r_v = _setup(sys, Y, U, increment, shape, process_noise, disturbance_inputs)
    b = np.logspace(-3, 3, 13) if betas is None else np.asarray(betas, dtype=float).reshape(-1)
    if b.size == 0 or (b < 0).any() or not np.isfinite(b).all():
        raise InvalidValueError(f"betas must be finite and nonnegative, got {b}")
    wmax = float(np.max(r_v))
    order = np.argsort(b, kind="stable")
    alpha = np.empty(b.size)
    alpha[order] = [float(lp.solve(beta * inc, r_v, False).v[0]) * lp.sigma / wmax
                    for beta in b[order]]
    # A trajectory consistent at one increment scale is consistent at every larger one,
    # so the running minimum over increasing beta is still a proved consistent noise
    # level; it removes the solver-accuracy wiggle where the true curve is flat at 0.
    alpha[order] = np.minimum.accumulate(alpha[order])
    return NoiseTradeoff(b, alpha, inc, r_v, tuple(sys.output_names))
