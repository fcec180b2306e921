"""Results of the set estimators (the SMFDO and the nonlinear set observer): one step
(:class:`SetEstimateStep`) and a run (:class:`SetEstimateResult`); ``SMFDOStep`` and
``SMFDOResult`` are their former names."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._deprecation import renamed
from .._validation import as_matrix, as_vector
from ..exceptions import DimensionError, InvalidValueError
from ..geometry import ConstrainedZonotope
from ..results import error_summary, time_axis, time_index

__all__ = ["STEP_STATUSES", "SMFDOResult", "SMFDOStep", "SetEstimateResult", "SetEstimateStep"]

#: Values of :attr:`SetEstimateStep.status`.
STEP_STATUSES = ("ok", "unbounded", "fallback", "inexact", "reset", "skipped")


@dataclass(frozen=True)
class SetEstimateStep:
    """One step of a set estimator (:class:`~setobs.SMFDO`,
    :class:`~setobs.NonlinearSetObserver`).

    Attributes
    ----------
    k : int
        Time step.
    estimate : ndarray, shape (q,)
        Centre of the disturbance interval hull (Algorithm 1, line 15);
        NaN where the set is still unbounded.
    lo, hi : ndarray, shape (q,)
        Certified interval hull of the disturbance set (``+-inf`` while unbounded).
    error_bound : float
        Certified bound on the infinity-norm error of ``estimate``:
        ``max_i (hi_i - lo_i) / 2``, its worst case over the computed set (the
        optimal worst-case error in exact mode, an upper bound on it with a
        window).
    disturbance_set : ConstrainedZonotope or None
        ``P Z_k`` when requested (``keep_sets=True``).
    status : str
        ``"ok"``; ``"unbounded"`` (some bound is infinite, e.g. before the data
        pin the disturbance down); ``"fallback"`` (an LP failed under every
        solver setting: the bounds are still certified, but wider); ``"inexact"``
        (certified, but the step's own bound on how much wider than the mode's
        exact bounds they may be, :attr:`gap`, is above its tolerance: the window's
        rounding allowances above ``ALLOWANCE_RTOL`` = 1 % of a band's width, or
        exact mode's certification gap above ``EXACT_RTOL`` = 1e-6); ``"reset"``
        (the posterior was empty and ``on_inconsistent="reset"`` restarted the
        filter: the guarantee is lost at this step); ``"skipped"`` (the
        posterior was empty and ``on_inconsistent="skip"`` dropped the
        measurement: the bounds are the prediction, sound if the sample was an
        outlier).
    state_lo, state_hi : ndarray, shape (n,), or None
        Certified interval hull of the consistent states ``x_k`` (with
        ``state_bounds=True``; ``+-inf`` for a state that depends on the
        unobservable part, or while unbounded), else ``None``.
    after_skip : bool
        Whether a step up to this one (this one included) was skipped or reset
        (``on_inconsistent``): the bands then hold for the model with the skipped
        samples discarded (or from the reset set), not for the record itself.
    gap : float
        The largest fraction of a band's width by which the bounds may exceed the
        mode's exact bounds, as far as the step knows: the window's rounding
        allowances (the LP certificate's ``|y|^T b_err`` at both ends and
        ``2 c_err``), exact mode's certification gap; 0 for the set recursion.
    stats : dict or None
        The estimator's own diagnostics of the step, where it keeps any
        (:class:`setobs.NonlinearSetObserver`: the sizes kept, the reduction's growth
        of the hull, the re-linearizations, a note on what fell back).
    """

    k: int
    estimate: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    error_bound: float
    disturbance_set: ConstrainedZonotope | None = None
    status: str = "ok"
    state_lo: NDArray[np.float64] | None = None
    state_hi: NDArray[np.float64] | None = None
    after_skip: bool = False
    gap: float = 0.0
    stats: dict[str, Any] | None = None

    radius = renamed("radius", "error_bound")

    def contains(self, d: ArrayLike) -> bool:
        """Whether ``d`` lies in ``[lo, hi]``.

        Parameters
        ----------
        d : array_like, shape (q,)
            A disturbance value.
        """
        dv = as_vector("d", d, size=self.lo.size)
        return bool(np.all((dv >= self.lo) & (dv <= self.hi)))


@dataclass(frozen=True)
class SetEstimateResult:
    """A set estimator's run over a record (:meth:`SMFDO.run <setobs.SMFDO.run>`,
    :meth:`NonlinearSetObserver.run <setobs.NonlinearSetObserver.run>`; the protocol of
    :mod:`setobs.results`).

    Arrays of shape ``(N, q)`` (``error_bound``, ``status``: ``(N,)``). Unpacks as
    ``t, estimate, lo, hi = smfdo.run(Y)``.

    Attributes
    ----------
    estimate : ndarray, shape (N, q)
        Centre of the certified interval (worst-case optimal for the infinity
        norm); NaN while unbounded.
    lo, hi : ndarray, shape (N, q)
        Certified interval hull of the consistent disturbances (``-inf``/``inf``
        while unbounded).
    error_bound : ndarray, shape (N,)
        Certified bound on the infinity-norm error of :attr:`estimate`:
        ``max_i (hi_i - lo_i) / 2`` (in exact mode the ``optimal`` metric).
    steps : list of SetEstimateStep
        The per-step records.
    status : ndarray of str, shape (N,)
        Per-step status (:data:`STEP_STATUSES`).
    first_inconsistent : int or None
        The first time step ``k`` of this record whose measurement was
        inconsistent with the model (status ``"skipped"`` or ``"reset"``): a
        fault-detection result (the model, the uncertainty sets or the sensor
        failed there). ``None`` if every measurement was consistent.
    dt : float or None
        The system's sampling time (for time axes).
    names : tuple of str
        The disturbance names (for tables and plot labels).
    state_lo, state_hi : ndarray, shape (N, n), or None
        Certified interval hulls of the consistent states (``state_bounds=True``).
    state_names : tuple of str
        The state names (for tables).
    after_skip : ndarray of bool, shape (N,)
        True from the first skipped or reset step on (:attr:`SetEstimateStep.after_skip`):
        those bands hold for the model with the skipped samples discarded, not for
        the record.
    """

    estimate: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    error_bound: NDArray[np.float64]
    steps: list[SetEstimateStep]
    status: NDArray[np.str_] = field(default_factory=lambda: np.zeros(0, dtype="<U9"))
    first_inconsistent: int | None = None
    dt: float | None = None
    names: tuple[str, ...] = ()
    state_lo: NDArray[np.float64] | None = None
    state_hi: NDArray[np.float64] | None = None
    state_names: tuple[str, ...] = ()
    after_skip: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))

    radius = renamed("radius", "error_bound")

    @property
    def gap(self) -> NDArray[np.float64]:
        """Per-step :attr:`SetEstimateStep.gap`, shape ``(N,)``: the largest fraction of a band
        by which the step's bounds may exceed its mode's exact bounds (status
        ``"inexact"`` above the tolerance)."""
        return np.array([st.gap for st in self.steps], dtype=np.float64)

    @property
    def stats(self) -> dict[str, NDArray[Any]]:
        """The steps' :attr:`SetEstimateStep.stats` as arrays of shape ``(N,)``, one per key
        (NaN, or ``""`` for text, where a step has none); empty when no step keeps any."""
        keys: dict[str, None] = {}
        for st in self.steps:
            keys.update(dict.fromkeys(st.stats or ()))
        out: dict[str, NDArray[Any]] = {}
        for key in keys:
            vals = [None if st.stats is None else st.stats.get(key) for st in self.steps]
            if all(isinstance(v, str) or v is None for v in vals):
                out[key] = np.array(["" if v is None else v for v in vals], dtype=object)
            else:
                out[key] = np.array([np.nan if v is None else v for v in vals], dtype=float)
        return out

    @property
    def time(self) -> NDArray[np.float64]:
        """Time axis ``k dt`` (or ``k`` when the sampling time is unknown)."""
        return time_axis(self.lo.shape[0], self.dt)

    def __repr__(self) -> str:
        """A summary like pandas': the size, the counts of statuses, the widest band, and
        the table's first and last rows (a few kB whatever the record's length; the
        whole table is :meth:`to_pandas`)."""
        N, q = self.lo.shape
        n = 0 if self.state_lo is None else self.state_lo.shape[1]
        what = [f"q = {q} disturbance{'s' if q != 1 else ''}"] if q else []
        if n:
            what.append(f"n = {n} state bounds")
        lines = [f"SetEstimateResult: {N} steps" + (f", {', '.join(what)}" if what else "")]
        st = self.status if self.status.size == N else np.full(N, "ok")
        kinds, counts = np.unique(st, return_counts=True)
        first = self.first_inconsistent
        lines.append("statuses: " + ", ".join(f"{k} {c}" for k, c in zip(kinds, counts,
                                                                          strict=True))
                     + f"; first inconsistent step: {'none' if first is None else first}")
        for label, lo, hi, names in (("disturbance", self.lo, self.hi, self.names),
                                     ("state", self.state_lo, self.state_hi,
                                      self.state_names)):
            if lo is None or hi is None or not lo.size:
                continue
            with np.errstate(invalid="ignore"):
                w = hi - lo
            fin = np.isfinite(w)
            nm = list(names) or [f"{label[0]}{i}" for i in range(lo.shape[1])]
            if not fin.any():
                lines.append(f"widest {label} band: all unbounded")
                continue
            k, i = np.unravel_index(int(np.argmax(np.where(fin, w, -np.inf))), w.shape)
            unb = int((~fin.all(axis=1)).sum())
            lines.append(f"widest {label} band (finite): {nm[i]} at k = {k}, "
                         f"[{lo[k, i]:.6g}, {hi[k, i]:.6g}]"
                         + (f"; {unb} step(s) with an unbounded {label}" if unb else ""))
        try:
            table = self.to_pandas().to_string(max_rows=10, max_cols=12, min_rows=10)
        except Exception:  # pragma: no cover - pandas is a dependency; never fail a repr
            table = ""
        return "\n".join([*lines, table]) if table else "\n".join(lines)

    __str__ = __repr__

    def __iter__(self):
        return iter((self.time, self.estimate, self.lo, self.hi))

    def plot(self, ax: Any = None, truth: ArrayLike | None = None, component: int = 0,
             states: bool = False) -> Any:
        """Estimate, certified interval and truth of one component
        (:func:`setobs.plotting.plot_estimate_band`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default: the current axes).
        truth : array_like, shape (N, q), optional
            The true disturbance (with ``states``: the true states, ``N x n``).
        component : int
            Disturbance component (with ``states``: state component).
        states : bool
            Draw the certified state interval ``[state_lo, state_hi]`` (and its
            centre) instead (a result of ``state_bounds=True``); for a state whose
            band is narrow against its range (a motor angle) use
            :func:`setobs.plotting.plot_state_band`, which draws it around its centre.

        Returns
        -------
        matplotlib Axes
            The axes drawn on.
        """
        from ..plotting import plot_estimate_band

        if not states:
            return plot_estimate_band(self, truth=truth, component=component, ax=ax)
        if self.state_lo is None or self.state_hi is None:
            raise InvalidValueError("no state bounds in this result: run the SMFDO with "
                                 "state_bounds=True")
        lo, hi = self.state_lo, self.state_hi
        with np.errstate(invalid="ignore"):
            mid = np.where(np.isfinite(lo) & np.isfinite(hi), 0.5 * (lo + hi), np.nan)
        n = lo.shape[1]
        view = SetEstimateResult(mid, lo, hi, self.error_bound, self.steps, self.status,
                           self.first_inconsistent, self.dt,
                           self.state_names or tuple(f"x{i}" for i in range(n)))
        return plot_estimate_band(view, truth=truth, component=component, ax=ax)

    def summary(self, truth: ArrayLike | None = None, start: int = 0) -> Any:
        """One row (index ``"SMFDO"``) over steps ``k >= start``: ``error_bound`` (mean
        certified error bound over the bounded steps; the ``optimal`` worst-case
        error in exact mode), ``max_error_bound``, ``unbounded`` steps,
        ``inconsistent`` steps; with state bounds ``state_error_bound`` (mean over the
        steps whose state bounds are all finite of the largest state half-width),
        ``max_state_error_bound`` and ``state_unbounded`` (steps with an infinite state
        bound); and, with the truth, ``error_inf``, ``max_error_inf``, ``error_2`` and
        ``truth_inside`` (fraction of steps whose certified interval holds the truth).

        Parameters
        ----------
        truth : array_like, shape (N, q), optional
            The true disturbance.
        start : int
            First step counted.

        Returns
        -------
        pandas.DataFrame
            The summary row.
        """
        r = self.error_bound[start:]
        fin = np.isfinite(r)
        st = self.status[start:] if self.status.size else np.zeros(0, dtype="<U9")
        extra: dict[str, Any] = {
            "error_bound": float(r[fin].mean()) if fin.any() else np.inf,
            "max_error_bound": float(r[fin].max()) if fin.any() else np.inf,
            "unbounded": int((~fin).sum()),
            "inconsistent": int(np.isin(st, ("skipped", "reset")).sum()),
        }
        if self.state_lo is not None and self.state_hi is not None:
            with np.errstate(invalid="ignore"):
                half = 0.5 * (self.state_hi[start:] - self.state_lo[start:])
            fin_x = np.isfinite(half).all(axis=1)
            hb = half.max(axis=1, initial=0.0)[fin_x]
            extra["state_error_bound"] = float(hb.mean()) if hb.size else np.inf
            extra["max_state_error_bound"] = float(hb.max()) if hb.size else np.inf
            extra["state_unbounded"] = int((~fin_x).sum())
        if truth is not None:
            D = as_matrix("truth", truth, cols=self.lo.shape[1])
            inside = np.all((D >= self.lo) & (D <= self.hi), axis=1)[start:]
            extra["truth_inside"] = float(inside.mean()) if inside.size else np.nan
        return error_summary("SMFDO", self.estimate, truth, start, extra)

    def to_pandas(self, dt: float | None = None, names: Sequence[str] | None = None) -> Any:
        """A ``pandas.DataFrame``: per disturbance ``name``, ``name_lo``, ``name_hi``
        (the estimate and its certified interval), then ``error_bound`` and ``status``;
        with state bounds, per state ``name_lo`` and ``name_hi`` after them. A run with
        skipped or reset steps has an ``after_skip`` column after ``status``.

        The index is the time ``k dt`` (named ``"time"``) when a sampling time is
        known (``dt`` or the system's), else the step ``k``.

        Parameters
        ----------
        dt : float, optional
            Sampling time (default: the system's).
        names : sequence of str, optional
            Disturbance names (default: the system's).

        Returns
        -------
        pandas.DataFrame
            The table.
        """
        import pandas as pd

        N, q = self.lo.shape
        nm = list(names) if names is not None else (list(self.names) or
                                                      [f"d{i}" for i in range(q)])
        if len(nm) != q:
            raise DimensionError(f"names must have {q} entries, got {len(nm)}")
        cols: dict[str, Any] = {}
        for i, name in enumerate(nm):
            cols[name] = self.estimate[:, i]
            cols[f"{name}_lo"] = self.lo[:, i]
            cols[f"{name}_hi"] = self.hi[:, i]
        cols["error_bound"] = self.error_bound
        cols["status"] = self.status if self.status.size == N else np.full(N, "ok")
        if self.after_skip.size == N and self.after_skip.any():
            cols["after_skip"] = self.after_skip
        if self.state_lo is not None and self.state_hi is not None:
            n = self.state_lo.shape[1]
            xn = list(self.state_names) or [f"x{i}" for i in range(n)]
            for i, name in enumerate(xn):
                cols[f"{name}_lo"] = self.state_lo[:, i]
                cols[f"{name}_hi"] = self.state_hi[:, i]
        return pd.DataFrame(cols, index=time_index(N, dt if dt is not None else self.dt))

    @property
    def consistent(self) -> bool:
        """Whether no step was skipped or reset (the bands are the model's sets)."""
        return self.first_inconsistent is None

    def violations(self, D: ArrayLike) -> int:
        """Number of steps at which the true disturbance ``D[k]`` is outside ``[lo, hi]``.

        Parameters
        ----------
        D : array_like, shape (N, q)
            The true disturbance.

        Raises
        ------
        DimensionError
            If ``D`` does not have the shape ``(N, q)`` of the result.
        """
        N, q = self.lo.shape
        if np.shape(D) != (N, q):
            raise DimensionError(f"D must have shape ({N}, {q}) like the result, "
                                 f"got {np.shape(D)}")
        Da = as_matrix("D", D, cols=q)
        out = (Da < self.lo) | (Da > self.hi)
        return int(out.any(axis=1).sum())


#: Former name of :class:`SetEstimateStep`.
SMFDOStep = SetEstimateStep
#: Former name of :class:`SetEstimateResult`.
SMFDOResult = SetEstimateResult
