"""The factor polytope's LP with its rows as the intervals ``[b - b_err, b + b_err]`` the
certificate covers (exact for the certified set when decided), with the unbounded factors
pivoted out first."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ...tolerances import RELAXED_EXACT_GAP
from .. import highs
from ._reports import LPResult
from ._scaling import exact_residual

if TYPE_CHECKING:
    from .polytope import FactorPolytope

__all__ = ["decided", "free_pivot", "reduced", "within_b_err"]


def within_b_err(fp: FactorPolytope, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                 w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None,
                 scale: float) -> LPResult | None:
    """``min w^T xi`` over ``|A xi - b| <= b_err``, ``|xi| <= h`` (the set the
    certificate covers), or ``None`` unless it is decided with the gap closed.
    (Parameters as for the method of :class:`FactorPolytope` it serves.)
    """
    be = fp.b_err
    if be is None or not np.any(be):
        return None
    if fp.any_unbounded and fp.A[:, fp.unbounded].any():
        out = reduced(fp, w, w_err, w_pair)
        if out is not None:
            return out
    for options in (None, *highs.RETRY_SETTINGS):
        hs = fp.build(fp.b - be, fp.b + be, np.zeros(fp.n_g), options)
        if hs is None or fp.solve_objective(hs, w, scale) != "optimal":
            continue
        sol = hs.getSolution()
        out = decided(fp,
            w, w_err, w_pair, np.asarray(sol.row_dual, dtype=np.float64) * scale,
            np.asarray(sol.col_value, dtype=np.float64), hs)
        if out is not None:
            return out
    return None


def decided(fp: FactorPolytope, w, w_err, w_pair, y, x, hs=None) -> LPResult | None:
    """The answer of the interval-row LP from a multiplier ``y`` and a point ``x``:
    ``x`` in the certified set and the gap closed (with the duals of the basis
    of ``hs`` refined where the solver's are not accurate enough), or ``None``."""
    if not fp.point_is_feasible(x, row_allowance=fp.b_err):
        return None
    bound = fp.certify(w, y, w_err, w_pair)
    obj = float(w @ x)
    bound = fp.tightened(w, w_err, w_pair, hs, y, bound, obj, RELAXED_EXACT_GAP)
    if not np.isfinite(bound) or obj - bound > RELAXED_EXACT_GAP * (1.0 + abs(obj)):
        return None
    return LPResult(bound, obj, x, "optimal")


def reduced(fp: FactorPolytope, w, w_err, w_pair) -> LPResult | None:
    """:meth:`minimize_within_b_err` with the unbounded factors pivoted out.

    The LP is ``min w^T xi`` over ``A_u xi_u + A_b xi_b = b + e``,
    ``|e| <= b_err``, ``|xi_b| <= h`` (``u``: unbounded factors). With
    ``A_u = U S V^T`` (numerical rank ``r``), ``N`` an orthonormal basis of its
    left null space and ``A_u^T M = w_u``, it is the same LP as
    ``min (w_b - A_b^T M)^T xi_b + M^T e`` subject to
    ``N^T A_b xi_b - N^T e = N^T b`` (``xi_u`` is then fixed by the rest), up
    to the constant ``M^T b``. A record whose states are of size 1e9 (an
    unknown initial state, ``X0 = R^n``) gives rows of that size, consistent
    only to their ``b_err`` (1e-16 relative), on which HiGHS says
    "infeasible" under every setting; pivoted out, the rows are of the size of
    the increments and the solve is routine. Only the LP is solved this way:
    its multiplier ``y = M + N y_N`` (the reduced cost of ``e``) is certified
    on the stored data by :meth:`certify`, and its point is checked against
    the certified set.
    """
    unb = fp.unbounded
    be = fp.b_err
    if be is None:  # exact rows: minimize_within_b_err's other paths decide
        return None
    Au, Ab = fp.A[:, unb], fp.A[:, ~unb]
    Ur, Sr, Vr, N, xi0, r0, A2, b2, pos = fp.pivot()
    wu = w[unb]
    with np.errstate(over="ignore", invalid="ignore"):
        M = Ur @ ((Vr.T @ wu) / Sr)
    if not np.isfinite(M).all():  # (singular values beyond double precision)
        return None
    # w_u outside the row space of A_u: unbounded below (the other paths decide)
    if np.abs(Au.T @ M - wu).max(initial=0.0) > 1e3 * np.finfo(np.float64).eps * float(
            (np.abs(wu) + np.abs(Au).T @ np.abs(M)).max(initial=0.0)):
        return None
    hb = fp.h[~unb]
    w2 = np.concatenate([w[~unb] - Ab.T @ M, M[pos] * be[pos]])
    ones = np.ones(int(pos.sum()))
    scale = fp.objective_scale(w2)
    hs = highs.new_model()
    if not highs.pass_dense(hs, A2, np.concatenate([-hb, -ones]), np.concatenate([hb, ones]),
                            b2, b2, w2 / scale):
        return None
    if highs.solve(hs) != "optimal":
        return None
    sol = hs.getSolution()
    y = M + N @ (np.asarray(sol.row_dual, dtype=np.float64) * scale)
    col = np.asarray(sol.col_value, dtype=np.float64)
    x = np.empty(fp.n_g)
    x[~unb] = col[:hb.size]
    e = np.zeros(fp.n_c)
    e[pos] = col[hb.size:] * be[pos]
    x[unb] = xi0 + Vr @ ((Ur.T @ (r0 + e - Ab @ x[~unb])) / Sr)
    return decided(fp, w, w_err, w_pair, y, x)


def free_pivot(fp: FactorPolytope) -> tuple:
    """The objective-independent parts of :func:`reduced` (computed once per polytope,
    :meth:`FactorPolytope.pivot`): ``A_u = U_r S_r V_r^T`` (numerical rank ``r``), the left
    null space ``N``, the centre ``xi_0`` and its residual ``r_0``, the reduced
    rows ``[N^T A_b, -N^T diag(b_err)]`` and right-hand side ``N^T r_0``, and the
    rows with ``b_err > 0``."""
    unb = fp.unbounded
    be = np.zeros(fp.n_c) if fp.b_err is None else fp.b_err  # (called with b_err only)
    Au, Ab = fp.A[:, unb], fp.A[:, ~unb]
    U, S, Vt = np.linalg.svd(Au)
    eps = np.finfo(np.float64).eps
    r = int(np.count_nonzero(S > S[0] * max(Au.shape) * eps)) if S[0] > 0 else 0
    Ur, Vr, Sr, N = U[:, :r], Vt[:r].T, S[:r], U[:, r:]
    # Centred at the least-squares point xi_0 of A_u xi_u = b (refined, residual
    # correctly rounded): N^T A_u is zero only to rounding, and times xi_u ~ 1e11
    # that would shift the reduced rows by 1e-4; times xi_u - xi_0 it does not.
    xi0 = Vr @ ((Ur.T @ fp.b) / Sr)
    for _ in range(2):
        r0 = exact_residual(fp.b, Au.T, xi0)
        xi0 = xi0 + Vr @ ((Ur.T @ r0) / Sr)
    r0 = exact_residual(fp.b, Au.T, xi0)
    pos = be > 0.0  # e_i = b_err_i t_i, |t_i| <= 1 (columns of the data's size)
    A2 = np.hstack([N.T @ Ab, -N.T[:, pos] * be[pos]])
    return (Ur, Sr, Vr, N, xi0, r0, A2, N.T @ r0, pos)
