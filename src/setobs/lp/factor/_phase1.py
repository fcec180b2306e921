"""Emptiness of the factor polytope by a certified phase-1 LP, and the LP with its rows
relaxed by the smallest violation found (an outer bound when the exact LP is undecided)."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..._lazy import lazy_module
from ..._rounding import gamma, round_down
from .. import highs
from ._compiled import COMPILED_MAX_ROWS, compiled_relaxed
from ._reports import EmptinessReport, LPResult

if TYPE_CHECKING:
    from .polytope import FactorPolytope

# the compiled simplex (numba): compiles or loads on the first compiled query
_simplex = lazy_module("setobs.lp._simplex")
# the one certificate (compiled; loads with the first certified bound)
_certificate = lazy_module("setobs.lp.certificate")
_INF = np.inf  # HiGHS's kHighsInf

__all__ = ["phase1", "phase1_highs", "phase1_report", "relaxed_rows"]


def phase1(fp: FactorPolytope, tol: float) -> EmptinessReport:
    """:meth:`FactorPolytope.emptiness`'s verdict at ``tol``: the compiled phase 1 where
    every bound is finite and the rows are few, else (or undecided there) HiGHS's."""
    if fp.n_c == 0:
        return EmptinessReport(False, 0.0, 0.0, tol, np.zeros(fp.n_g))
    if not fp.any_unbounded and fp.n_c <= COMPILED_MAX_ROWS:
        # every bound finite: the compiled phase 1, scaled and certified in one call
        code, lower_inf, found, xc = _simplex.emptiness(
            fp.A, fp.b, fp.h, np.zeros(fp.n_c) if fp.b_err is None else fp.b_err,
            fp.unbounded_radius, 50 * (fp.n_c + fp.n_g))
        if code == _simplex.OPTIMAL:
            empty = bool(lower_inf > tol)
            # undecided (no certificate above tol, no point within it): HiGHS decides
            if empty or found <= tol:
                return EmptinessReport(empty, float(lower_inf), float(found), tol,
                                       None if empty else xc)
    scale = fp.row_scale()
    As = fp.A / scale[:, None]
    bs = fp.b / scale
    solved = phase1_highs(fp, As, bs)
    if solved is None:
        fp.fallbacks += 1
        return EmptinessReport(False, 0.0, np.nan, tol)
    return phase1_report(fp, As, bs, scale, *solved, tol)


def phase1_highs(fp: FactorPolytope, As: NDArray[np.float64], bs: NDArray[np.float64]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """``(y, xi)`` of the phase-1 LP by HiGHS (with retries), or ``None``."""
    n_c, n_g = fp.n_c, fp.n_g
    lo, up = fp.col_bounds()
    big = np.hstack([As, np.eye(n_c), -np.eye(n_c)])
    lo_c = np.concatenate([lo, np.zeros(2 * n_c)])
    up_c = np.concatenate([up, np.full(2 * n_c, _INF)])
    cost = np.concatenate([np.zeros(n_g), np.ones(2 * n_c)])
    for options in (None, *highs.RETRY_SETTINGS):
        hs = highs.new_model(options)
        if not highs.pass_dense(hs, big, lo_c, up_c, bs, bs, cost):
            continue
        hs.run()
        if highs.status(hs) == "optimal":
            sol = hs.getSolution()
            return (np.asarray(sol.row_dual, dtype=np.float64),
                    np.asarray(sol.col_value, dtype=np.float64)[:n_g])
    return None


def phase1_report(fp: FactorPolytope, As, bs, scale, y, x, tol: float) -> EmptinessReport:
    """The certified verdict of a phase-1 solution ``(y, x)`` (scaled rows)."""
    n_c, n_g = fp.n_c, fp.n_g
    # Certified bound with the scaled data (exact: power-of-two scales); the
    # objective is zero in xi, so L(y) <= ||y||_1 * min ||As xi - bs||_inf.
    lower, y = _certificate.lagrangian_lower_bound(
        np.zeros(n_g), As, bs, fp.h, y, unbounded_radius=fp.unbounded_radius,
        unbounded_pinv=np.linalg.pinv(As[:, fp.unbounded].T) if fp.any_unbounded else None,
        b_err=None if fp.b_err is None else fp.b_err / scale,
    )
    norm1 = float(np.abs(y).sum()) * (1.0 + 2.0 * gamma(n_c + 1))
    if norm1 > 0.0 and np.isfinite(lower) and lower > 0.0:
        lower_inf = round_down(lower / norm1)
    else:
        lower_inf = 0.0  # no positive certificate
    xc = np.clip(x, -fp.h, fp.h)
    found = float(np.abs(As @ xc - bs).max())
    empty = bool(lower_inf > tol)
    return EmptinessReport(empty, lower_inf, found, tol, None if empty else xc)


def relaxed_rows(fp: FactorPolytope, w: NDArray[np.float64],
                 w_err: NDArray[np.float64] | None = None,
                 w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
                 ) -> LPResult:
    """:meth:`FactorPolytope.minimize_relaxed`: certified ``min w^T xi`` with the rows
    relaxed to ``|A xi - b| <= delta``.

    Used when the set is not certified empty but the exact LP is infeasible
    or its certified bounds cross: the relaxed feasible set contains every
    point that satisfies the normalised constraints within the emptiness
    tolerance, so its certified bound is an outer bound in the sense of
    :meth:`FactorPolytope.emptiness` (and a valid bound for the exact set). If the
    relaxed LP does not solve either, the ``"fallback"`` answer of
    :meth:`FactorPolytope.minimize` is returned.
    (Parameters as for the method of :class:`FactorPolytope` it serves.)
    """
    with fp.lock:
        rep = fp.emptiness()
        found = rep.violation_found if np.isfinite(rep.violation_found) else 1.0
        delta = fp.row_scale() * max(2.0 * found, 2.0 * rep.tol)
        scale = fp.objective_scale(w)
        y: NDArray[np.float64] | None = None
        x: NDArray[np.float64] | None = None
        for options in (None, *highs.RETRY_SETTINGS):
            hs = fp.build(fp.b - delta, fp.b + delta, w / scale, options)
            if hs is None:
                continue
            hs.run()
            st = highs.status(hs)
            if st == "unbounded":
                return LPResult(-np.inf, -np.inf, None, "unbounded")
            if st == "optimal":
                y = np.asarray(hs.getSolution().row_dual, dtype=np.float64) * scale
                x = np.asarray(hs.getSolution().col_value, dtype=np.float64)
                break
        if y is None:
            out = compiled_relaxed(fp, w, delta, w_err, w_pair)
            if out is not None:
                return out
            fp.fallbacks += 1
            y, x = np.zeros(fp.n_c), None
        bound, y = fp.certify_with(w, y, w_err, w_pair)
        obj = float(w @ x) if x is not None else np.nan
        status = "optimal" if x is not None else "fallback"
        if np.isinf(bound):
            return LPResult(-np.inf, obj, x, "unbounded" if x is not None else status)
        # Relaxed rows |A xi - b| <= delta add -sum |y_i| delta_i to the bound.
        relax = float(np.abs(y) @ delta) * (1.0 + 2.0 * gamma(fp.n_c + 1))
        return LPResult(round_down(bound - relax), obj, x, status)
