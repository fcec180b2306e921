"""Worst-case error of point estimates over the set of disturbances consistent with the data."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._deprecation import renamed
from .exceptions import InvalidValueError
from .results import time_axis

__all__ = ["ComparisonTable", "compare", "worst_case_error"]


def worst_case_error(estimates: ArrayLike, lo: ArrayLike, hi: ArrayLike) -> NDArray[np.float64]:
    """``max_{d in [lo, hi]} ||d_hat - d||_inf`` per step (exact over the box).

    For the interval hull ``[lo, hi]`` of the consistent set this equals the
    worst-case infinity-norm error over the consistent set itself (each
    coordinate's extremes are attained in the set). ``inf`` while unbounded;
    NaN estimates give NaN.

    Parameters
    ----------
    estimates, lo, hi : array_like, shape (N, q)
    """
    E = np.atleast_2d(np.asarray(estimates, float))  # NaN allowed: "no estimate yet"
    L = np.atleast_2d(np.asarray(lo, float))
    H = np.atleast_2d(np.asarray(hi, float))
    if not (E.shape == L.shape == H.shape):
        raise InvalidValueError(f"shapes differ: estimates {E.shape}, lo {L.shape}, hi {H.shape}")
    with np.errstate(invalid="ignore"):
        per = np.maximum(np.abs(E - L), np.abs(H - E))
    return per.max(axis=1)


@dataclass(frozen=True)
class ComparisonTable:
    """Point estimates scored against the consistent set (the protocol of :mod:`setobs.results`).

    Per observer and step: ``worst_case_error`` (worst-case infinity-norm error
    of the estimate over the consistent set), ``optimal`` (that of the
    worst-case-optimal estimate: the interval-hull centre, the reference SMFDO's
    ``error_bound``),
    ``ratio = worst_case_error / optimal`` (>= 1) and ``outside`` (the estimate
    lies outside the consistent set's interval hull).

    Attributes
    ----------
    observers : list of str
        Observer names, in the order given.
    worst_case_error : dict of str to ndarray, shape (N,)
        Per observer.
    optimal : ndarray, shape (N,)
        The optimal worst-case error (the reference's ``error_bound``).
    outside : dict of str to ndarray of bool, shape (N,)
        Per observer.
    worst_case_error_2, optimal_2 : dict / ndarray, optional
        The same in the Euclidean norm (``compare(..., euclidean=True)``).
    dt : float or None
        Sampling time (for the time index).
    """

    observers: list[str]
    worst_case_error: dict[str, NDArray[np.float64]]
    optimal: NDArray[np.float64]
    outside: dict[str, NDArray[np.bool_]]
    worst_case_error_2: dict[str, NDArray[np.float64]] | None = None
    optimal_2: NDArray[np.float64] | None = None
    dt: float | None = None

    error = renamed("error", "worst_case_error")

    @property
    def rows(self) -> list[dict]:
        """One row per observer and step (a tidy table)."""
        out = []
        for name in self.observers:
            for k, (e, o, f) in enumerate(zip(self.worst_case_error[name], self.optimal,
                                              self.outside[name], strict=True)):
                ratio = float(e / o) if (o > 0 and np.isfinite(o) and np.isfinite(e)) else np.nan
                out.append({"observer": name, "k": k, "worst_case_error": float(e),
                            "optimal": float(o), "ratio": ratio, "outside": bool(f)})
        return out

    def to_pandas(self) -> Any:
        """The tidy table (:attr:`rows`) as a ``pandas.DataFrame``, with a ``time``
        column when the sampling time is known.

        Returns
        -------
        pandas.DataFrame
            Columns ``observer, k, [time,] worst_case_error, optimal, ratio, outside``.
        """
        import pandas as pd

        df = pd.DataFrame(self.rows)
        if self.dt and len(df):
            df.insert(2, "time", df["k"] * self.dt)
        return df

    def summary(self, start: int = 0) -> Any:
        """Per observer (index ``observer``), over steps ``k >= start`` where everything is
        finite: ``steps``, mean ``worst_case_error``, ``max_worst_case_error``, mean
        ``optimal``, mean ``ratio`` and the fraction of steps ``outside``.

        Parameters
        ----------
        start : int
            First step counted (skip the transient).

        Returns
        -------
        pandas.DataFrame
            One row per observer.
        """
        import pandas as pd

        ok = np.isfinite(self.optimal) & (np.arange(self.optimal.size) >= start)
        out = []
        for name in self.observers:
            e = self.worst_case_error[name]
            m = ok & np.isfinite(e)
            ratio = e[m] / np.where(self.optimal[m] > 0, self.optimal[m], np.nan)
            out.append({
                "steps": int(m.sum()),
                "worst_case_error": float(np.mean(e[m])) if m.any() else np.nan,
                "max_worst_case_error": float(np.max(e[m])) if m.any() else np.nan,
                "optimal": float(np.mean(self.optimal[m])) if m.any() else np.nan,
                "ratio": float(np.nanmean(ratio)) if m.any() else np.nan,
                "outside": float(self.outside[name][m].mean()) if m.any() else np.nan,
            })
        return pd.DataFrame(out, index=pd.Index(self.observers, name="observer"))

    def plot(self, ax: Any = None, logy: bool = True) -> Any:
        """Worst-case error of each observer and the optimal bound, per step or time.

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default: the current axes).
        logy : bool
            Logarithmic error axis.

        Returns
        -------
        matplotlib Axes
            The axes drawn on.
        """
        import matplotlib.pyplot as plt

        ax = plt.gca() if ax is None else ax
        t = time_axis(self.optimal.size, self.dt)
        for name in self.observers:
            ax.plot(t, self.worst_case_error[name], lw=1.0, label=name)
        ax.plot(t, self.optimal, "k", lw=1.5, label="optimal (exact SMFDO)")
        ax.set_xlabel("time [s]" if self.dt else "k")
        ax.set_ylabel("worst-case error")
        if logy:
            ax.set_yscale("log")
        ax.legend(loc="best", fontsize=7)
        return ax

    def to_markdown(self, start: int = 0) -> str:
        """The summary as a Markdown table.

        Parameters
        ----------
        start : int
            First step counted.

        Returns
        -------
        str
            The table.
        """
        lines = ["| observer | steps | mean worst-case error | optimal | mean ratio | outside |",
                 "|---|---|---|---|---|---|"]
        for name, s in self.summary(start).iterrows():
            lines.append(f"| {name} | {int(s['steps'])} | {s['worst_case_error']:.4g} | "
                         f"{s['optimal']:.4g} | {s['ratio']:.3g} | {s['outside']:.2%} |")
        return "\n".join(lines)


def compare(estimates: Mapping[str, ArrayLike], reference, *, euclidean: bool = False,
            allow_inconsistent: bool = False) -> ComparisonTable:
    """Score point estimates against the consistent set of an SMFDO run.

    Parameters
    ----------
    estimates : mapping name -> array (N, q)
        Point estimates (e.g. ``observer.run(Y).estimate``).
    reference : SMFDOResult
        SMFDO result on the same data (exact mode gives the true consistent
        set; windowed mode an outer approximation, so scores are upper bounds).
    euclidean : bool
        Also compute Euclidean worst-case errors ``max_v ||d_hat - v||_2`` over
        the vertices ``v`` of the consistent set, and the optimal (Chebyshev)
        worst-case error. Needs the SMFDO run with ``keep_sets=True``; steps where the set
        is unbounded give ``inf``.
    allow_inconsistent : bool
        Score against a reference whose run skipped or reset measurements
        (``on_inconsistent="skip"`` / ``"reset"``). Refused by default: at and
        after such steps its bands are not the model's consistent set (a reset
        loses the guarantee; a skip assumes the sample was an outlier), so
        "optimal" would not mean optimal.

    Raises
    ------
    ValueError
        If the reference run has skipped or reset steps and
        ``allow_inconsistent`` is false.
    """
    status = np.asarray(getattr(reference, "status", np.zeros(0, dtype="<U9")))
    bad = np.flatnonzero((status == "skipped") | (status == "reset"))
    if bad.size and not allow_inconsistent:
        kinds = sorted(set(status[bad].tolist()))
        raise InvalidValueError(
            f"the reference SMFDO run has {bad.size} step(s) with status {kinds} (first at "
            f"record step {bad[0]}): its measurements there were inconsistent with the model, "
            "so its bands are not the consistent set and its error bound is not the optimal "
            "error. Fix the model or the uncertainty sets, or pass "
            "allow_inconsistent=True to compare anyway")
    lo, hi = np.asarray(reference.lo), np.asarray(reference.hi)
    dt = getattr(reference, "dt", None)
    optimal = np.asarray(reference.error_bound, float)
    err, out = {}, {}
    for name, est in estimates.items():
        E = np.asarray(est, float)
        err[name] = worst_case_error(E, lo, hi)
        with np.errstate(invalid="ignore"):
            out[name] = np.any((E < lo) | (E > hi), axis=1)
    if not euclidean:
        return ComparisonTable(list(estimates), err, optimal, out, dt=dt)
    from .setmembership.estimates import chebyshev_center

    steps = reference.steps
    if any(s.disturbance_set is None for s in steps):
        raise InvalidValueError("euclidean=True needs the SMFDO run with keep_sets=True")
    N = len(steps)
    opt2 = np.full(N, np.inf)
    err2 = {name: np.full(N, np.inf) for name in estimates}
    for k, st in enumerate(steps):
        if not np.all(np.isfinite(st.lo)) or not np.all(np.isfinite(st.hi)):
            continue
        V = st.disturbance_set.vertices()
        opt2[k] = chebyshev_center(st.disturbance_set).worst_case_error
        for name, est in estimates.items():
            e = np.asarray(est, float)[k]
            err2[name][k] = (np.linalg.norm(V - e, axis=1).max() if np.all(np.isfinite(e))
                             else np.nan)
    return ComparisonTable(list(estimates), err, optimal, out, err2, opt2, dt=dt)
