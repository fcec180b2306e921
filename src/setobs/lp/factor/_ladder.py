"""The HiGHS path of :meth:`FactorPolytope.minimize`: the retry ladder over solver
settings (the module notes of :mod:`setobs.lp.factor`), then the compiled retry, the
interval rows, the relaxed rows, and the fallback."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ...exceptions import EmptySetError
from ...tolerances import LP_REFINE_GAP, PRIMAL_RESIDUAL_RTOL, RELAXED_EXACT_GAP
from .. import highs
from ._reports import LPResult

if TYPE_CHECKING:
    from .polytope import FactorPolytope

__all__ = ["highs_ladder", "nearly_feasible"]


def highs_ladder(fp: FactorPolytope, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                 w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None
                 ) -> LPResult:
    """:meth:`FactorPolytope.minimize` for a caller that holds the polytope's lock: the
    retry ladder of the module notes (:mod:`setobs.lp.factor`).
    (Parameters as for the method of :class:`FactorPolytope` it serves.)
    """
    if fp.n_c == 0:
        # No constraints: the minimum over the box is analytic and exact.
        bound = fp.certify(w, np.zeros(0), w_err, w_pair)
        if not np.isfinite(bound):
            return LPResult(-np.inf, -np.inf, None, "unbounded")
        point = -np.sign(w) * np.where(fp.unbounded, 0.0, fp.h)
        return LPResult(bound, float(w @ point), point, "optimal")
    # HiGHS sees the objective divided by a power of two (exact), so that its
    # tolerances act on a unit-size problem; certification uses the true w.
    scale = fp.objective_scale(w)
    best = -np.inf  # best certified bound of any multiplier (fallback answer)
    infeasible_claims = 0
    open_gap: LPResult | None = None  # the best "optimal" whose gap stayed open
    attempts = [None, *highs.RETRY_SETTINGS, "perturbed"]
    for i, options in enumerate(attempts):
        perturbed = options == "perturbed"
        hs = fp.highs_model() if i == 0 else fp.build(
            fp.b, fp.b, np.zeros(fp.n_g),
            None if perturbed or isinstance(options, str) else options)
        if hs is None:
            continue
        st = fp.solve_objective(hs, fp.perturbed_objective(w) if perturbed else w, scale)
        if perturbed and st == "unbounded":
            continue  # (says nothing about the true objective)
        if st == "optimal":
            sol = hs.getSolution()
            y = np.asarray(sol.row_dual, dtype=np.float64) * scale
            x = np.asarray(sol.col_value, dtype=np.float64)
            bound = fp.certify(w, y, w_err, w_pair)
            if not fp.point_is_feasible(x):
                # "Optimal" at an infeasible point: its objective, and the
                # multiplier certified near it, may undercut the minimum.
                # Certified all the same. Exact only if the objective plus the
                # first-order cost of the rows' residual, |y|^T |A x - b|, still
                # meets the certified bound (HiGHS's 1.3e-6 relative residual on
                # a state-bound LP, with its gap at 1e-7); else the next attempt.
                out = nearly_feasible(fp, w, w_err, w_pair, hs, y, x, bound)
                if out is not None:
                    return out
                best = max(best, bound)
                continue
            obj = float(w @ x)
            bound = fp.tightened(w, w_err, w_pair, hs, y, bound, obj, LP_REFINE_GAP)
            if np.isinf(bound):
                return LPResult(-np.inf, obj, x, "unbounded")
            if obj - bound > RELAXED_EXACT_GAP * (1.0 + abs(obj)):
                # Certified, but not tight (duals inaccurate on a nearly degenerate
                # set, 1e-3 of its width once): the next settings may close it.
                if open_gap is None or bound > open_gap.bound:
                    open_gap = LPResult(bound, obj, x, "fallback")
                continue
            return LPResult(bound, obj, x, "optimal")
        if st == "unbounded":
            return LPResult(-np.inf, -np.inf, None, "unbounded")
        if st == "infeasible":
            rep = fp.emptiness()
            if rep.empty:
                raise EmptySetError(
                    "the set is empty (certified: every point violates a normalised "
                    f"constraint by at least {rep.violation_lower_bound:.3g})"
                )
            # "Infeasible" without a certificate: a hard LP, not a verdict. The
            # other settings decide it; the relaxed LP is the last resort.
            infeasible_claims += 1
            continue
        # Undecided: keep whatever multiplier the solver left (certified, it
        # is a valid bound however poor), then retry with other settings.
        y = np.asarray(hs.getSolution().row_dual, dtype=np.float64)
        if y.size == fp.n_c and np.isfinite(y).all():
            best = max(best, fp.certify(w, y * scale, w_err, w_pair))
    out = fp.try_compiled(w, w_err, w_pair)
    if out is not None:
        return out
    # The rows are known to within b_err (the rounding of the operations that
    # formed b, the data's representation): at magnitudes where b_err exceeds
    # the solver's tolerance (states of 1e9, outputs of 1e10) the float rows
    # may be inconsistent while the certified set is not ("infeasible"), or too
    # ill-scaled for any setting (no status). Its LP has the rows as intervals
    # [b - b_err, b + b_err]; the certificate already holds for every such b,
    # so a minimiser there with the gap closed is exact.
    out = fp.minimize_within_b_err(w, w_err, w_pair, scale)
    if out is not None:
        return out
    if open_gap is not None:
        fp.fallbacks += 1
        return LPResult(max(open_gap.bound, best), open_gap.objective, open_gap.point,
                        "fallback")
    if infeasible_claims:
        # Not certified empty, but no setting found a feasible optimum: the LP
        # with rows relaxed by the smallest violation found is a valid outer
        # bound, wider than the exact one (so a fallback, counted).
        rel = fp.minimize_relaxed(w, w_err, w_pair)
        if rel.status == "optimal":
            # Exact after all when the relaxed minimiser satisfies the exact rows
            # (then its objective bounds the minimum from above) and closes the
            # gap: a degenerate LP that HiGHS mislabelled, decided.
            if (rel.point is not None and fp.point_is_feasible(rel.point)
                    and rel.objective - rel.bound
                    <= RELAXED_EXACT_GAP * (1.0 + abs(rel.objective))):
                return rel
            fp.fallbacks += 1
            return LPResult(max(rel.bound, best), rel.objective, rel.point, "fallback")
        if rel.status == "unbounded":
            return rel
        best = max(best, rel.bound)
    best = max(best, fp.certify(w, np.zeros(fp.n_c), w_err, w_pair))
    fp.fallbacks += 1
    return LPResult(best, np.nan, None, "fallback")


def nearly_feasible(fp: FactorPolytope, w, w_err, w_pair, hs, y, x, bound) -> LPResult | None:
    """An "optimal" answer at a point slightly off the rows, accepted as exact when
    ``w^T x + |y|^T max(|A x - b| - b_err, 0)`` (the objective corrected by the
    sensitivity of the optimum to the residual) is within :data:`RELAXED_EXACT_GAP`
    of the certified bound (duals of the basis tried too), the point in its
    box; else ``None``. A gross residual (3e-3 once) does not pass."""
    if not np.isfinite(x).all():
        return None
    over = np.abs(x) - fp.h
    if (over > PRIMAL_RESIDUAL_RTOL * (1.0 + np.where(fp.unbounded, 0.0, fp.h))).any():
        return None
    resid = np.abs(fp.A @ x - fp.b)
    if fp.b_err is not None:
        resid = np.maximum(resid - fp.b_err, 0.0)
    bound, yb = fp.basis_bound(w, w_err, w_pair, hs, y, bound)
    obj = float(w @ x) + float(np.abs(yb) @ resid)
    if not np.isfinite(bound) or obj - bound > RELAXED_EXACT_GAP * (1.0 + abs(obj)):
        return None
    return LPResult(bound, obj, x, "optimal")
