"""Compiled kernels of the fast LP path (numba): a dense bounded dual simplex (with
the bound-flipping ratio test and dual steepest-edge pricing), a bounded primal
simplex for the next objective on the same data, and calls of the one certificate,
:func:`setobs.lp.certificate.lower_bound`.

These kernels are private; :class:`setobs.lp.fastlp.FixedStructureLP` is
the interface. The simplex only *proposes* a multiplier; every bound returned
to the user is certified by :func:`~setobs.lp.certificate.lower_bound` (valid for any
multiplier), exactly
as on the HiGHS path, so soundness never depends on the simplex.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..tolerances import FASTLP_PRIMAL_RTOL
from .certificate import csc_of, gamma_k, lower_bound

#: Pivots after which the explicit basis inverse is recomputed from scratch.
REFACTOR_EVERY = 32
#: ``npiv`` value that forces a refactorisation on the next iteration.
FORCE_REFACTOR = 1 << 30
#: Relative size of the cost perturbation against dual degeneracy (see solve_batch).
PERTURB = 1e-7
#: Per data set, the pivot count remembered for the warm start not used decays by
#: this factor (solve_batch), so that it is tried again after a few sets.
EST_DECAY = 0.9
#: Cost of a dual pivot in primal pivots (solve_batch's choice of warm start, used only
#: without the objective chain): measured 9.5 against 4.5 us on 40 x 106 window LPs when
#: the dual recomputed the basic solution each pivot; it now updates it along the pivot
#: and the bound flips, as the primal does (not measured again).
DUAL_PIVOT_COST = 2.0

# Return codes of the simplex (also used by the batch kernel).
OPTIMAL = 0
INFEASIBLE = 1  # dual unbounded: the LP is (numerically) infeasible
ITERATION_LIMIT = 2
NUMERICAL = 3  # tiny pivot or singular refactorisation
AMBIGUOUS = 4  # unboundedness of the direction not decided clearly
NOT_CERTIFIED = 5  # the certified bound is -inf or far from the objective


@njit(cache=True)
def refactor(cols, basis, BinvT):
    """``BinvT = inv(A[:, basis])^T`` (``cols``: ``A`` column by column, sparse,
    :func:`sparse_pattern`; the inverse is kept transposed, see :func:`_entering_column`);
    False if singular or inaccurate.

    By blocks: the basic columns with a single nonzero (slack-like columns: the noise
    factors of a window LP, 128 of a 30-tank cascade's 210 basic columns) in distinct
    rows ``R1`` are a diagonal block ``D``; with the rows ``R2`` and columns ``C2`` left,
    the row- and column-permuted basis is block triangular, ``[[D, X], [0, N]]``, whose
    inverse is ``[[D^-1, -D^-1 X N^-1], [0, N^-1]]``: only the nucleus ``N`` is inverted
    densely (LAPACK ``getrf``/``getri``; at 210 rows a nucleus of 82). On that cascade's
    window bases this took 0.30 ms against 1.1 ms for the inverse of the whole basis, which
    every ``m / 2`` pivots had been about a sixth of a window step's time; the step went
    from 33.5 to 28 ms (development runs, not in a results file; the benchmark is
    ``benchmarks/window_cost.py``). The inverse's own work per pivot is small beside it
    (1.3 us for ``B^-1 a_q``, 1.9 us for the pivot row, a few for the update at 210 rows:
    measured inside the compiled code), so a sparse LU with a product-form update, which
    replaces those, buys little here. The inverse is accepted only if ``B (B^-1 1) = 1`` holds to
    ``1e-9`` relative to ``|B| |B^-1 1|`` (one O(m^2) residual): an ill-conditioned or
    singular basis is reported (``NUMERICAL``). Soundness does not depend on it (every
    multiplier is certified).
    """
    indptr, indices, data = cols
    m = basis.size
    # the singleton columns and their rows (a second singleton in a taken row stays in
    # the nucleus, which is then singular)
    rowof = np.full(m, -1, np.int64)
    posof = np.full(m, -1, np.int64)  # the basis position of row i's singleton
    for k in range(m):
        j = basis[k]
        cnt = indptr[j + 1] - indptr[j]
        if cnt == 0:
            return False
        if cnt == 1:
            r = indices[indptr[j]]
            if posof[r] < 0:
                posof[r] = k
                rowof[k] = r
    t = 0
    for k in range(m):
        if rowof[k] < 0:
            t += 1
    c2 = np.empty(t, np.int64)  # basis positions of the nucleus's columns
    r2 = np.empty(t, np.int64)  # its rows
    inr2 = np.full(m, -1, np.int64)  # row i's index in r2
    a = 0
    for k in range(m):
        if rowof[k] < 0:
            c2[a] = k
            a += 1
    a = 0
    for i in range(m):
        if posof[i] < 0:
            r2[a] = i
            inr2[i] = a
            a += 1
    BinvT[:, :] = 0.0
    Ninv = np.empty((t, t))
    # XN[k] = (X N^-1)[k, :] for the singleton at basis position k (X: the rows R1 of
    # the nucleus's columns)
    XN = np.zeros((m, t))
    if t > 0:
        N = np.zeros((t, t))
        for q in range(t):
            j = basis[c2[q]]
            for p in range(indptr[j], indptr[j + 1]):
                i = indices[p]
                if inr2[i] >= 0:
                    N[inr2[i], q] = data[p]
        try:
            Ninv = np.linalg.inv(N)
        except Exception:  # singular (getrf's zero pivot)
            return False
        for q in range(t):  # (B^-1)[c2[q], r2[p]] = Ninv[q, p]
            for p in range(t):
                BinvT[r2[p], c2[q]] = Ninv[q, p]
        for q in range(t):
            j = basis[c2[q]]
            for p in range(indptr[j], indptr[j + 1]):
                k = posof[indices[p]]
                if k >= 0:
                    xq = data[p]
                    for a in range(t):
                        XN[k, a] += xq * Ninv[q, a]
    for k in range(m):
        r = rowof[k]
        if r < 0:
            continue
        dk = data[indptr[basis[k]]]
        BinvT[r, k] = 1.0 / dk
        for a in range(t):  # row k of B^-1 on the rows R2: -XN[k] / d_k
            BinvT[r2[a], k] = -XN[k, a] / dk
    # the residual of B (B^-1 1) = 1: v = B^-1 1 (v[k] = sum_i BinvT[i, k])
    v = np.zeros(m)
    for i in range(m):
        for k in range(m):
            v[k] += BinvT[i, k]
    res = np.full(m, -1.0)
    sabs = np.ones(m)
    for k in range(m):
        j = basis[k]
        for p in range(indptr[j], indptr[j + 1]):
            tt = data[p] * v[k]
            res[indices[p]] += tt
            sabs[indices[p]] += abs(tt)
    for i in range(m):
        if not abs(res[i]) <= 1e-9 * sabs[i]:  # (also catches NaN)
            return False
    return True


@njit(cache=True)
def _refactor_interval(m):
    """Pivots between refactorisations of an ``m``-row basis (both simplices): every
    ``REFACTOR_EVERY``, every ``m / 2`` for larger bases (a refactorisation costs
    ``O(t^3 + m^2)`` for a nucleus of ``t`` rows (:func:`refactor`), a pivot ``O(m^2)`` at
    most; at ``m`` = 210, with the whole basis inverted, every ``m / 4`` pivots was a
    third of a pivot's cost)."""
    return max(REFACTOR_EVERY, m // 2)


@njit(cache=True)
def sparse_pattern(A):
    """``(rows, cols)`` of a dense matrix, exact zeros left out: ``rows = (indptr, indices,
    data)`` row by row (the columns ascending) and ``cols`` the same column by column.

    The simplices' loops over ``A`` (pivot row, entering column, basic solution, reduced
    costs, residual) run over these: the window LPs are 4-40 % nonzeros (a 30-tank
    cascade's 210 x 540 window 16 %), and a product that skips exact zeros adds the same
    terms in the same order as the dense loop, so every iterate is the dense loop's.
    """
    cols = csc_of(A)
    rows = csc_of(np.ascontiguousarray(A.T))
    return rows, cols


@njit(cache=True)
def primal_residual(rows, b, x):
    """``max_i |A_i x - b_i| / (1 + |b_i| + |A_i| |x|)`` (``rows``: ``A`` row by row,
    :func:`sparse_pattern`)."""
    indptr, indices, data = rows
    worst = 0.0
    for i in range(b.size):
        r = -b[i]
        s = 1.0 + abs(b[i])
        for p in range(indptr[i], indptr[i + 1]):
            t = data[p] * x[indices[p]]
            r += t
            s += abs(t)
        worst = max(worst, abs(r) / s)
    return worst


@njit(cache=True)
def _reduced_costs(rows, w, basis, BinvT, y, d):
    """``y = B^-T w_B`` and ``d = w - A^T y`` (rows of ``BinvT`` and of ``A``, sparse)."""
    indptr, indices, data = rows
    m = basis.size
    wB = np.empty(m)
    for k in range(m):
        wB[k] = w[basis[k]]
    # y_i = sum_k wB_k (B^-1)[k, i], each summed in the order k = 0, 1, ..., four rows
    # of BinvT at a time (four independent sums: the same values, four times the
    # throughput of one)
    i = 0
    while i + 4 <= m:
        s0 = s1 = s2 = s3 = 0.0
        for k in range(m):
            wk = wB[k]
            s0 += wk * BinvT[i, k]
            s1 += wk * BinvT[i + 1, k]
            s2 += wk * BinvT[i + 2, k]
            s3 += wk * BinvT[i + 3, k]
        y[i] = s0
        y[i + 1] = s1
        y[i + 2] = s2
        y[i + 3] = s3
        i += 4
    while i < m:
        s0 = 0.0
        for k in range(m):
            s0 += wB[k] * BinvT[i, k]
        y[i] = s0
        i += 1
    d[:] = w
    for i in range(m):
        yi = y[i]
        if yi != 0.0:
            for p in range(indptr[i], indptr[i + 1]):
                d[indices[p]] -= yi * data[p]


@njit(cache=True)
def _basic_solution(cols, b, h, basis, upper, isb, BinvT, x, rhs):
    """The basic solution: each nonbasic ``x_j`` at the bound ``upper[j]`` selects, then
    ``x_B = B^-1 (b - N x_N)`` (``cols``: ``A`` column by column, sparse)."""
    indptr, indices, data = cols
    m = basis.size
    rhs[:] = b
    for j in range(h.size):
        if isb[j]:
            continue
        xj = h[j] if upper[j] else -h[j]
        x[j] = xj
        if xj != 0.0:
            for p in range(indptr[j], indptr[j + 1]):
                rhs[indices[p]] -= xj * data[p]
    acc = np.empty(m)
    _inverse_times(BinvT, rhs, acc)
    for i in range(m):
        x[basis[i]] = acc[i]


@njit(cache=True)
def _inverse_times(BinvT, v, out):
    """``out = B^-1 v`` (a row of ``BinvT`` per nonzero of ``v``, contiguous ``axpy``)."""
    m = v.size
    out[:] = 0.0
    for k in range(m):
        vk = v[k]
        if vk != 0.0:
            for i in range(m):
                out[i] += BinvT[k, i] * vk


@njit(cache=True)
def _entering_column(BinvT, cols, q, col):
    """``col = B^-1 a_q`` (``cols``: ``A`` column by column, sparse); returns ``max |col|``.

    The inverse is kept transposed (``BinvT[k, i] = (B^-1)[i, k]``) so that this product
    and the basic solution are contiguous ``axpy`` over the nonzeros of ``a_q``, and the
    eta update touches only the rows of ``BinvT`` whose entry in the pivot column is
    nonzero (the inverse of a window basis is about 20 % nonzeros): on a 30-tank
    cascade's 210 x 540 window LP a pivot went from 100 to about 40 us. Each ``col[i]``
    sums the same terms in the same order as the row-wise product, so the iterates are
    unchanged.
    """
    indptr, indices, data = cols
    m = col.size
    col[:] = 0.0
    for p in range(indptr[q], indptr[q + 1]):
        k = indices[p]
        v = data[p]
        for i in range(m):
            col[i] += BinvT[k, i] * v
    cmax = 0.0
    for i in range(m):
        cmax = max(cmax, abs(col[i]))
    return cmax


@njit(cache=True)
def _eta_update(BinvT, col, r):
    """Rank-one update of the explicit inverse (kept transposed) for pivot row ``r`` of
    ``col = B^-1 a_q``: row ``r`` of ``B^-1`` divided by the pivot, then each other row
    ``i`` less ``col[i]`` times it (only the columns where row ``r`` is nonzero change)."""
    m = col.size
    piv = col[r]
    for k in range(m):
        t = BinvT[k, r] / piv
        if t != 0.0:
            for i in range(m):
                BinvT[k, i] -= col[i] * t
        BinvT[k, r] = t


@njit(cache=True)
def _start(basis, w, n):
    """The basic-column flags of ``basis`` and the reduced-cost tolerance
    ``1e-12 max |w|`` (both simplices)."""
    isb = np.zeros(n, np.bool_)
    for i in range(basis.size):
        isb[basis[i]] = True
    wmax = 0.0
    for j in range(n):
        wmax = max(wmax, abs(w[j]))
    return isb, 1e-12 * wmax


@njit(cache=True)
def _pivot_row(BinvT, rows, r, sgn, alpha):
    """``alpha = sgn * (B^-1)[r, :] A`` (``rows``: ``A`` row by row, sparse)."""
    indptr, indices, data = rows
    alpha[:] = 0.0
    for k in range(BinvT.shape[0]):
        bk = sgn * BinvT[k, r]
        if bk != 0.0:
            for p in range(indptr[k], indptr[k + 1]):
                alpha[indices[p]] += bk * data[p]


@njit(cache=True)
def dual_simplex(A, sp, b, h, w, basis, upper, BinvT, npiv, x, y, maxit, nit):
    """Bounded dual simplex for ``min w^T x, A x = b, |x_j| <= h_j`` (all ``h`` finite).

    ``sp`` is ``A``'s sparse pattern (:func:`sparse_pattern`). ``basis`` (m
    column indices), ``upper`` (nonbasic at ``+h``), ``BinvT`` (the basis
    inverse) and ``npiv[0]`` (pivots since the last refactorisation) are the
    warm-start state, updated in place. Every basis is made dual feasible by
    putting each nonbasic variable at the bound its reduced cost selects, so any
    previous basis (same ``A`` and ``w``, new ``b`` and ``h``) is a valid start.
    Dual steepest-edge pricing of the leaving row, the bound-flipping ("long
    step") ratio test with Harris's tolerance at its stop; the basis inverse is
    updated by a rank-one (eta) update and recomputed every ``REFACTOR_EVERY``
    pivots (``m / 2`` for larger bases). The reduced costs are updated along
    the pivot row, the basic solution along the pivot and the bound flips (one
    product with the inverse for all flips of an iteration, where the solution had
    been recomputed at each: the first of a 30-tank cascade's window LPs of a step went from
    4.2-4.7 to 2.3-2.5 ms for the same 101-113 pivots), both recomputed after each
    refactorisation and before optimality or infeasibility is declared. Inner
    loops are written as contiguous ``axpy`` updates (vectorisable without
    reassociation).

    On return ``x`` is the basic solution and ``y = B^{-T} w_B`` the row
    multiplier (the code is ``OPTIMAL`` when every basic ``x_j`` is within
    ``1e-9 (1 + h_j)`` of its range; among the rows beyond it, the leaving row
    maximises violation^2 / ||row of B^-1||^2).
    """
    m, n = A.shape
    isb, dtol = _start(basis, w, n)
    ptol = 1e-9
    d = np.empty(n)
    alpha = np.empty(n)
    rhs = np.empty(m)
    col = np.empty(m)
    cand = np.empty(n, np.int64)
    tj = np.empty(n)
    vrow = np.empty(m, np.int64)
    vval = np.empty(m)
    vrel = np.empty(m)
    vbeta = np.empty(m)
    need_full = True  # recompute y, d and x from scratch
    clean = False  # d and x were recomputed and no pivot since
    fresh = False  # x was recomputed and no pivot or bound flip since
    indptr, indices, data = sp[1]
    refactor_at = _refactor_interval(m)
    for it in range(maxit + 1):
        if npiv[0] >= refactor_at:
            if not refactor(sp[1], basis, BinvT):
                return NUMERICAL
            npiv[0] = 0
            need_full = True
        full_x = need_full
        if need_full:
            _reduced_costs(sp[0], w, basis, BinvT, y, d)
            need_full = False
            clean = True
        # every nonbasic variable at the bound its reduced cost selects; between full
        # recomputations x_B follows the flips, x_B += B^-1 (sum_j a_j (old_j - new_j))
        nflip = 0
        if not full_x:
            rhs[:] = 0.0
        for j in range(n):
            if isb[j]:
                d[j] = 0.0
                continue
            s = d[j]
            up = upper[j]
            if s > dtol:
                up = False
            elif s < -dtol:
                up = True
            if up != upper[j]:
                upper[j] = up
                if not full_x:
                    xj = h[j] if up else -h[j]
                    dx = x[j] - xj
                    x[j] = xj
                    if dx != 0.0:
                        nflip += 1
                        for pp in range(indptr[j], indptr[j + 1]):
                            rhs[indices[pp]] += dx * data[pp]
        if full_x:
            _basic_solution(sp[1], b, h, basis, upper, isb, BinvT, x, rhs)
            fresh = True
        elif nflip > 0:
            _inverse_times(BinvT, rhs, col)
            for i in range(m):
                x[basis[i]] += col[i]
            fresh = False
        # leaving row: among the violations beyond the tolerance (relative to the
        # variable's own range; columns are equilibrated), the largest by dual
        # steepest edge, violation^2 / ||row i of B^-1||^2 (Forrest-Goldfarb; the
        # explicit inverse gives the exact weights)
        nv = 0
        for i in range(m):
            j = basis[i]
            v = x[j]
            if v < -h[j]:
                viol = -h[j] - v
            elif v > h[j]:
                viol = v - h[j]
            else:
                continue
            rel = viol / (ptol * (1.0 + h[j]))
            if rel <= 1.0:
                continue
            vrow[nv] = i
            vval[nv] = viol
            vrel[nv] = rel
            nv += 1
        # the weights ||row i of B^-1||^2 of the violated rows (columns of BinvT, summed
        # row by row of BinvT: contiguous reads, each weight in the order k = 0, 1, ...)
        for t in range(nv):
            vbeta[t] = 0.0
        for k in range(m):
            for t in range(nv):
                bk = BinvT[k, vrow[t]]
                vbeta[t] += bk * bk
        r = -1
        worst = 0.0
        score = 0.0
        for t in range(nv):
            sc = vval[t] * vval[t] / max(vbeta[t], 1e-300)
            if sc > score:
                score = sc
                worst = vrel[t]
                r = vrow[t]
        if r < 0:
            if clean:
                return OPTIMAL
            need_full = True  # confirm with freshly computed reduced costs
            continue
        if it == maxit:
            return ITERATION_LIMIT
        p = basis[r]
        sgn = 1.0 if x[p] < -h[p] else -1.0
        _pivot_row(BinvT, sp[0], r, sgn, alpha)
        amax = 0.0
        for j in range(n):
            if isb[j] or h[j] == 0.0:
                alpha[j] = 0.0
            else:
                amax = max(amax, abs(alpha[j]))
        atol = 1e-9 * amax
        # Bound-flipping ratio test (the "long step" of the bounded dual simplex;
        # Maros 2003, Koberstein 2005): every candidate's reduced cost reaches zero
        # at its breakpoint t_j = |d_j| / |alpha_j|; passing it flips x_j to its
        # other bound, which lowers the slope of the dual objective (the leaving
        # row's violation) by |alpha_j| (2 h_j). The step goes on to the breakpoint
        # where the slope turns nonpositive; the flips need no bookkeeping, since
        # each iteration puts every nonbasic variable at the bound its reduced cost
        # selects. (The short step, one breakpoint per pivot, needed 500-2000
        # pivots on 40 x 106 window LPs with many noise factors.)
        nc = 0
        for j in range(n):
            a = alpha[j]
            if (not upper[j] and a < -atol) or (upper[j] and a > atol):
                dj = max(-d[j] if upper[j] else d[j], 0.0)
                cand[nc] = j
                tj[nc] = dj / abs(a)
                nc += 1
        if nc == 0:
            if not fresh:  # (decided on a freshly computed x only)
                need_full = True
                continue
            return INFEASIBLE
        order = np.argsort(tj[:nc])
        slope = worst * ptol * (1.0 + h[p])  # the violation, in x units
        kstop = -1
        for t in range(nc):
            j = cand[order[t]]
            slope -= abs(alpha[j]) * 2.0 * h[j]
            if slope <= 0.0:
                kstop = t
                break
        if kstop < 0:
            if not fresh:
                need_full = True
                continue
            return INFEASIBLE  # the dual objective grows without bound
        # Harris's pass at the stop: among the candidates whose breakpoint is within
        # the reduced-cost tolerance of it, the largest pivot
        j0 = cand[order[kstop]]
        t0 = tj[order[kstop]]
        q = j0
        best = abs(alpha[j0])
        for t in range(kstop + 1, nc):
            j = cand[order[t]]
            a = abs(alpha[j])
            if tj[order[t]] * a > t0 * a + dtol:
                break
            if a > best:
                best = a
                q = j
        cmax = _entering_column(BinvT, sp[1], q, col)
        if abs(col[r]) <= 1e-11 * cmax:
            npiv[0] = FORCE_REFACTOR  # refactor on the next call
            return NUMERICAL
        # reduced costs along the pivot row: d_j -= (d_q / alpha_q) alpha_j, and the
        # leaving variable's d_p = -sgn d_q / alpha_q (alpha is the signed row; the
        # columns masked out of alpha, fixed at h = 0, keep stale costs they never use)
        theta = d[q] / alpha[q]
        for j in range(n):
            a = alpha[j]
            if a != 0.0:
                d[j] -= theta * a
        d[q] = 0.0
        d[p] = -sgn * theta
        _eta_update(BinvT, col, r)
        basis[r] = q
        isb[p] = False
        isb[q] = True
        upper[p] = sgn < 0.0
        # x_p goes to that bound; the new basis's x_B moves by -dx B'^-1 a_p, whose entries
        # are -col[i] / col[r] (i != r) and 1 / col[r] (row r, now x_q)
        xp = h[p] if upper[p] else -h[p]
        dx = xp - x[p]
        x[p] = xp
        cr = col[r]
        for i in range(m):
            if i != r:
                x[basis[i]] += dx * (col[i] / cr)
        x[q] -= dx / cr
        npiv[0] += 1
        nit[0] += 1
        clean = False
        fresh = False
    return ITERATION_LIMIT


@njit(cache=True)
def primal_simplex(A, sp, b, h, w, basis, upper, BinvT, npiv, x, y, maxit, nit,
                   gap_stop=0.0, x_given=False):
    """Bounded primal simplex for ``min w^T x, A x = b, |x_j| <= h_j`` from a primal
    feasible basis (the optimal basis of another objective on the same data).

    The state (``basis``, ``upper``, ``BinvT``, ``npiv``) is that of
    :func:`dual_simplex` and updated in place. Devex pricing (Forrest-Goldfarb's
    reference framework; the weights start at 1 on every call), Harris's two-pass
    ratio test, bound flips of the entering variable without a basis change.
    The basic solution and the reduced costs are updated by each pivot (``x_B``
    along the entering column, ``d`` along the pivot row) and recomputed from
    scratch after each refactorisation and before optimality is declared, so
    ``x`` and ``y = B^{-T} w_B`` on an ``OPTIMAL`` return are those of the final
    basis. Returns ``NUMERICAL`` when the start is not primal feasible within the
    tolerance of :func:`dual_simplex` (the caller goes to the dual simplex then).
    On a change of objective only, the optimal basis of the last objective needs
    a handful of pivots where the dual simplex needs about as many as from scratch
    (``setobs.setmembership._history`` saw the same with HiGHS: 1-60 pivots
    against ~150).

    ``gap_stop > 0`` stops it (``OPTIMAL``) once the duality gap of the current basis is
    at most that: with ``y`` the basis's multiplier and ``d = w - A^T y``, the
    Lagrangian bound ``b^T y - sum_j h_j |d_j|`` is below the basic solution's objective
    by exactly ``sum 2 h_j |d_j|`` over the nonbasic columns whose reduced cost would
    improve it (the others, at their bound, and the basic columns contribute nothing),
    a sum the pricing loop forms anyway. The caller certifies the bound of ``y`` either
    way; it is then within ``gap_stop`` (and rounding) of the minimum.

    ``x_given``: ``x`` already holds the basic solution of the start, as computed from
    scratch for this basis, inverse and data (the objective chain's start: another LP's
    optimal vertex on the same data), so the first computation is skipped unless a
    refactorisation comes first.
    """
    m, n = A.shape
    isb, dtol = _start(basis, w, n)
    ptol = 1e-9
    ref = np.ones(n)  # devex weights
    d = np.empty(n)
    rhs = np.empty(m)
    col = np.empty(m)
    alpha = np.empty(n)
    need_full = True  # recompute x, y and d from scratch
    clean = False  # x and d were recomputed and no pivot since
    first = True
    refactor_at = _refactor_interval(m)
    for it in range(maxit + 1):
        if npiv[0] >= refactor_at:
            if not refactor(sp[1], basis, BinvT):
                return NUMERICAL
            npiv[0] = 0
            need_full = True
            x_given = False
        if need_full:
            if not x_given:
                _basic_solution(sp[1], b, h, basis, upper, isb, BinvT, x, rhs)
            x_given = False
            if first:
                for i in range(m):
                    j = basis[i]
                    if abs(x[j]) > h[j] + ptol * (1.0 + h[j]):
                        return NUMERICAL  # not primal feasible: not this method's start
                first = False
            _reduced_costs(sp[0], w, basis, BinvT, y, d)
            for i in range(m):
                d[basis[i]] = 0.0
            need_full = False
            clean = True
        # entering: the largest d_j^2 / devex weight
        q = -1
        best = 0.0
        gap = 0.0
        for j in range(n):
            if isb[j] or h[j] == 0.0:
                continue
            dj = d[j]
            if (not upper[j] and dj < -dtol) or (upper[j] and dj > dtol):
                gap += 2.0 * h[j] * abs(dj)
                sc = dj * dj / ref[j]
                if sc > best:
                    best = sc
                    q = j
        if q >= 0 and gap <= gap_stop:
            # (within the caller's gap: on freshly computed x and d, as for optimality)
            if clean:
                return OPTIMAL
            need_full = True
            continue
        if q < 0:
            if clean:
                return OPTIMAL
            need_full = True  # confirm on freshly computed x and d
            continue
        if it == maxit:
            return ITERATION_LIMIT
        dirq = 1.0 if not upper[q] else -1.0  # x_q moves up from -h or down from +h
        cmax = _entering_column(BinvT, sp[1], q, col)  # x_B changes by -theta dirq col
        atol = 1e-9 * cmax
        # Harris pass 1: the largest step keeping every basic variable within its
        # bounds relaxed by the tolerance
        tmax = 2.0 * h[q]
        for i in range(m):
            c = dirq * col[i]
            j = basis[i]
            tol = ptol * (1.0 + h[j])
            if c > atol:
                t = (x[j] + h[j] + tol) / c
            elif c < -atol:
                t = (h[j] - x[j] + tol) / (-c)
            else:
                continue
            if t < tmax:
                tmax = t
        if tmax == np.inf:
            return AMBIGUOUS
        # pass 2: among the rows that block within tmax, the largest |col|
        r = -1
        bestc = 0.0
        tr = np.inf
        for i in range(m):
            c = dirq * col[i]
            j = basis[i]
            if c > atol:
                t = (x[j] + h[j]) / c
            elif c < -atol:
                t = (h[j] - x[j]) / (-c)
            else:
                continue
            if t <= tmax and abs(c) > bestc:
                bestc = abs(c)
                r = i
                tr = max(t, 0.0)
        nit[0] += 1
        if r < 0 or 2.0 * h[q] <= tr:
            # the entering variable reaches its other bound: x_B moves along col
            step = 2.0 * h[q] * dirq
            for i in range(m):
                x[basis[i]] -= step * col[i]
            upper[q] = not upper[q]
            x[q] = h[q] if upper[q] else -h[q]
            clean = False
            continue
        if abs(col[r]) <= 1e-11 * cmax:
            npiv[0] = FORCE_REFACTOR
            return NUMERICAL
        p = basis[r]
        # pivot row (old inverse), then the updates of x, d and the devex weights
        _pivot_row(BinvT, sp[0], r, 1.0, alpha)
        aq = alpha[q]  # = col[r]
        step = tr * dirq
        for i in range(m):
            x[basis[i]] -= step * col[i]
        x[q] = (h[q] if upper[q] else -h[q]) + step
        upper[p] = dirq * col[r] < 0.0  # (it rose to +h) or fell to -h
        x[p] = h[p] if upper[p] else -h[p]
        theta = d[q] / aq
        wq = ref[q]
        for j in range(n):
            if isb[j] or j == q:
                continue
            a = alpha[j]
            if a != 0.0:
                d[j] -= theta * a
                t = (a / aq) * (a / aq) * wq
                if t > ref[j]:
                    ref[j] = t
        d[q] = 0.0
        d[p] = -theta
        ref[p] = max(wq / (aq * aq), 1.0)
        _eta_update(BinvT, col, r)
        basis[r] = q
        isb[p] = False
        isb[q] = True
        npiv[0] += 1
        clean = False
    return ITERATION_LIMIT


@njit(cache=True)
def prepare(b, h, b_err, bidx, S_B, R, Q0, absQ0, absAB, Q2, b_scale, rtol):
    """The reduced LP's data for one set: ``hB = h[bidx] / S_B`` and ``bred = Q2^T (R b)``,
    and whether ``b`` is consistent with the redundant rows: ``|Q0^T (R b)| <= rtol *
    scale + |Q0|^T (R b_err)``, ``scale`` the largest of ``|R b|``, ``b_scale max R``
    and ``|A_B| hB`` (``b_err`` empty: exact). Equilibration by powers of two is exact.
    """
    m = b.size
    hB = np.empty(bidx.size)
    for j in range(bidx.size):
        hB[j] = h[bidx[j]] / S_B[j]
    bs = R * b
    ok = True
    if Q0.shape[1]:
        scale = 1e-300
        rmax = 0.0
        for i in range(m):
            scale = max(scale, abs(bs[i]))
            rmax = max(rmax, R[i])
        scale = max(scale, b_scale * rmax)
        for i in range(m):
            s = 0.0
            for j in range(hB.size):
                s += absAB[i, j] * hB[j]
            scale = max(scale, s)
        for k in range(Q0.shape[1]):
            v, sl = 0.0, rtol * scale
            for i in range(m):
                v += Q0[i, k] * bs[i]
                if b_err.size:
                    sl += absQ0[i, k] * (R[i] * b_err[i])
            if abs(v) > sl:
                ok = False
    bred = np.zeros(Q2.shape[1])
    for i in range(m):
        bi = bs[i]
        if bi != 0.0:
            for j in range(Q2.shape[1]):
                bred[j] += Q2[i, j] * bi
    return hB, bred, ok


@njit(cache=True)
def solve_batch(structure, data, state, params, out):
    """All LPs ``min Wfull[i]^T xi`` of one set: reduced simplex, then certification.

    The arguments are grouped by lifetime (all tuples, in this order):

    * ``structure = (A, csc, fidx, pinvU, Ared, sp, Wfull, Wred, yU, Q2, R, dirstat,
      order)`` (``csc``: ``A``'s ``(indptr, indices, data)`` for the certificate; ``sp``:
      ``Ared``'s :func:`sparse_pattern`, for the simplices' loops; ``order``:
      the order the LPs are solved in, :func:`~setobs.lp.fastlp.chain_order`): fixed for a
      set structure (:class:`~setobs.lp.fastlp.FixedStructureLP`);
    * ``data = (b, h, b_err, bred, hB)``: this set's right-hand side and bounds;
    * ``state = (bases, upper, binv, npiv, est, iters)``: the warm-start state, updated
      in place (``est[i]``: the pivots of LP ``i``'s two warm starts when last used;
      ``iters``: the primal and dual simplex iterations so far, pivots and bound flips);
    * ``params = (maxit, radius, tol_unb, gap_rtol, chain, rel_gap)``: iteration limit,
      tolerances, whether every LP after the first starts by the primal simplex from
      the best optimal vertex found so far (the objective chain), rather than by the
      cheaper of its two warm starts when last used, and the primal simplex's early
      stop: with ``rel_gap > 0`` and objectives in pairs ``(w, -w)`` (hull objectives),
      each LP after the first stops once its duality gap is at most ``rel_gap`` times
      the pair's width at the last data set (``-bounds[i ^ 1] - bounds[i]`` where both
      were solved; :func:`primal_simplex`), and is accepted with that gap;
    * ``out = (bounds, objs, codes, ys)``: results, written in place.

    ``dirstat[i]``: 0 solve, 1 unbounded below (decided at set-up), 2 ambiguous.
    The reduced LP (of the equilibrated copy ``R A S``: free factors
    eliminated, rows projected on ``Q2``) is solved warm from ``bases[i]``; its
    multiplier ``z`` lifts to ``y = R (yU[i] + Q2 z)``, which is certified on
    the *original* data. ``codes[i] = OPTIMAL`` only if the
    certified bound is finite and within ``gap_rtol (1 + |obj|)`` of the
    simplex objective. ``ys[i]`` receives the certified multiplier.
    """
    A, csc, fidx, pinvU, Ared, sp, Wfull, Wred, yU, Q2, R, dirstat, order = structure
    indptr, indices, cdata = csc
    b, h, b_err, bred, hB = data
    neg_h = -h
    no_err = np.zeros(0)
    no_pair = np.zeros((0, h.size))
    bases, upper, binv, npiv, est, iters = state
    maxit, radius, tol_unb, gap_rtol, chain, rel_gap = params
    nit = np.zeros(1, np.int64)
    bounds, objs, codes, ys = out
    n_lp = Wfull.shape[0]
    mr, nb = Ared.shape
    x = np.zeros(nb)
    z = np.zeros(mr)
    m = A.shape[0]
    y = np.zeros(m)
    wp = np.empty(nb)
    keep_b = np.empty(mr, np.int64)
    keep_u = np.empty(nb, np.bool_)
    xs = np.empty((n_lp, nb))  # optimal basic solutions of this data set's LPs
    # the early stop: each pair's width at the last data set (its certified bounds)
    gstop = np.zeros(n_lp)
    if rel_gap > 0.0 and n_lp % 2 == 0:
        for i in range(n_lp):
            wd = -bounds[i ^ 1] - bounds[i]
            if (codes[i] == OPTIMAL and codes[i ^ 1] == OPTIMAL and np.isfinite(wd)
                    and wd > 0.0):
                gstop[i] = rel_gap * wd
    solved = np.zeros(n_lp, np.bool_)
    wnz = np.empty(nb, np.int64)
    # Q2 = I (no redundant rows): the multiplier's lift needs no product
    q2_eye = mr == m
    if q2_eye:
        for k in range(m):
            for t2 in range(mr):
                if Q2[k, t2] != (1.0 if k == t2 else 0.0):
                    q2_eye = False
    for ii in range(n_lp):
        i = order[ii]
        if dirstat[i] == 1:
            bounds[i] = -np.inf
            objs[i] = -np.inf
            codes[i] = OPTIMAL
            ys[i, :] = 0.0  # (no multiplier: the bound is -inf, its allowance none)
            continue
        if dirstat[i] == 2:
            codes[i] = AMBIGUOUS
            continue
        # Two warm starts. (1) The dual simplex from this LP's own last basis (the
        # last data set): dual-degenerate LPs (many columns with zero cost, e.g.
        # noise factors that enter only the constraints) stall it, so it solves with
        # the costs perturbed first (ties broken deterministically), then finishes
        # with the true costs. (2) After the first LP of the set, the primal simplex
        # from the previous LP's optimal basis (the same data, another objective).
        # Which is cheaper depends on the family: a window restarting from the
        # carried-back polytope changes little from step to step (two masses: 5
        # pivots warm, 15-70 primal), noise-dominated windows change a lot (random
        # 6-state plant: ~130 warm, 50-110 primal). est[i] holds each one's pivots
        # when last used, decaying while unused (so the other is tried again);
        # the cheaper is tried first. With ``chain`` (the default,
        # setobs.lp.fastlp.PRIMAL_CHAIN) (2) is always tried first: summed over a
        # step's LPs it was cheaper on every plant measured, though (1) was cheaper
        # for single LPs. The result is certified below on the original data
        # either way.
        wmax = 0.0
        for j in range(nb):
            wmax = max(wmax, abs(Wred[i, j]))
        for j in range(nb):
            frac = (j * 0.6180339887498949) % 1.0
            sg = 1.0 if frac < 0.5 else -1.0
            wp[j] = Wred[i, j] + sg * PERTURB * wmax * (1.0 + frac)
        code = ITERATION_LIMIT
        # the primal start: the solved LP of this data set whose optimal vertex is
        # best for this objective (hull objectives come as +-e_i: the previous one,
        # the opposite bound, is often the worst start)
        src = -1
        best_v = np.inf
        nnz = 0
        for j in range(nb):  # (over the objective's nonzeros: the same sums)
            if Wred[i, j] != 0.0:
                wnz[nnz] = j
                nnz += 1
        for j2 in range(n_lp):
            if solved[j2]:
                v = 0.0
                for t2 in range(nnz):
                    j = wnz[t2]
                    v += Wred[i, j] * xs[j2, j]
                if v < best_v:
                    best_v = v
                    src = j2
        use_primal = src >= 0 and (chain or est[i, 1] < est[i, 0])
        if use_primal:
            keep_b[:] = bases[i]
            keep_u[:] = upper[i]
            bases[i, :] = bases[src]
            upper[i, :] = upper[src]
            binv[i, :, :] = binv[src]
            npiv[i] = npiv[src]
            nit[0] = 0
            x[:] = xs[src]  # (src's basic solution, computed from scratch at its optimum)
            code = primal_simplex(Ared, sp, bred, hB, Wred[i], bases[i], upper[i],
                                  binv[i], npiv[i:i + 1], x, z, maxit, nit, gstop[i], True)
            est[i, 1] = nit[0] if code == OPTIMAL else 1e9
            est[i, 0] *= EST_DECAY
            iters[0] += nit[0]
            if code != OPTIMAL:  # (from the last data set's basis of this LP instead)
                bases[i, :] = keep_b
                upper[i, :] = keep_u
                npiv[i] = FORCE_REFACTOR  # (its inverse: recomputed from the basis)
        if code != OPTIMAL:
            nit[0] = 0
            code = dual_simplex(Ared, sp, bred, hB, wp, bases[i], upper[i], binv[i],
                                npiv[i:i + 1], x, z, maxit, nit)
            if code == OPTIMAL or code == ITERATION_LIMIT:
                code = dual_simplex(Ared, sp, bred, hB, Wred[i], bases[i], upper[i],
                                    binv[i], npiv[i:i + 1], x, z, maxit, nit)
            if not use_primal:
                est[i, 0] = DUAL_PIVOT_COST * nit[0] if code == OPTIMAL else 1e9
                est[i, 1] *= EST_DECAY
            iters[1] += nit[0]
        if code != OPTIMAL:
            codes[i] = code
            continue
        # The basic solution must satisfy the reduced equations: an inaccurate basis
        # inverse gives a point whose objective (and a multiplier certified near it)
        # undercuts the true minimum while the gap below looks closed.
        if primal_residual(sp[0], bred, x) > FASTLP_PRIMAL_RTOL:
            codes[i] = NOT_CERTIFIED
            continue
        xs[i, :] = x
        solved[i] = True
        obj = 0.0
        oabs = 0.0
        for j in range(nb):
            t = Wred[i, j] * x[j]
            obj += t
            oabs += abs(t)
        for k in range(m):
            t = yU[i, k] * (R[k] * b[k])
            obj += t
            oabs += abs(t)
            s = yU[i, k]
            if q2_eye:  # (the same sum: the other terms are exact zeros)
                s += z[k]
            else:
                for t2 in range(mr):
                    s += Q2[k, t2] * z[t2]
            y[k] = R[k] * s
        bnd, slack = lower_bound(Wfull[i], indptr, indices, cdata, b, neg_h, h, y, fidx,
                                 pinvU, radius, tol_unb, b_err, no_err, no_pair, no_err,
                                 False, A)
        ys[i, :] = y
        bounds[i] = bnd
        objs[i] = obj
        # accepted gap: the tolerance, what precision alone explains (the b_err
        # term, rounding terms, reduced costs at rounding level: see lower_bound),
        # the objective's own rounding (large b cancel in it), and the early stop's
        # gap. A wrong basis leaves a gap well above these.
        allowed = (gap_rtol * (1.0 + abs(obj)) + slack + 4.0 * gamma_k(nb + m + 2) * oabs
                   + 1.01 * gstop[i])
        if not np.isfinite(bnd) or obj - bnd > allowed:
            codes[i] = NOT_CERTIFIED
        else:
            codes[i] = OPTIMAL


@njit(cache=True)
def phase1(As, bs, h, maxit):
    """The phase-1 LP of :meth:`setobs.lp.factor.FactorPolytope.emptiness` (every
    ``h_j`` finite) by the dual simplex: ``min sum(s+ + s-)`` subject to
    ``As xi + s+ - s- = bs``, ``|xi| <= h``, ``s+-`` in ``[0, 2 S]``, written with the
    shifted slacks ``s+- = S + t+-``, ``|t+-| <= S`` (the shifts cancel in the rows),
    so that every variable has a symmetric bound. ``S = 1 + sum |bs|`` exceeds any
    optimal slack (``xi = 0`` violates by ``sum |bs|`` in all). The slack columns
    ``t+`` are the initial basis (``B = I``). The costs are first perturbed (the
    ``xi`` columns cost nothing: dual degenerate), then the true costs finish from
    that basis, as in :func:`solve_batch`. Returns ``(code, xi, y)``: the simplex's
    point and row multiplier, which the caller certifies.
    """
    m, n = As.shape
    N = n + 2 * m
    A = np.zeros((m, N))
    A[:, :n] = As
    S = 1.0
    for i in range(m):
        A[i, n + i] = 1.0
        A[i, n + m + i] = -1.0
        S += abs(bs[i])
    sp = sparse_pattern(A)
    H = np.empty(N)
    H[:n] = h
    H[n:] = S
    w = np.zeros(N)
    w[n:] = 1.0
    wp = np.empty(N)
    for j in range(N):
        frac = (j * 0.6180339887498949) % 1.0
        sg = 1.0 if frac < 0.5 else -1.0
        wp[j] = w[j] + sg * PERTURB * (1.0 + frac)
    basis = np.arange(n, n + m).astype(np.int64)
    upper = np.zeros(N, np.bool_)
    BinvT = np.eye(m)
    npiv = np.zeros(1, np.int64)
    nit = np.zeros(1, np.int64)
    x = np.zeros(N)
    y = np.zeros(m)
    code = dual_simplex(A, sp, bs, H, wp, basis, upper, BinvT, npiv, x, y, maxit, nit)
    if code == OPTIMAL:
        code = dual_simplex(A, sp, bs, H, w, basis, upper, BinvT, npiv, x, y, maxit, nit)
    return code, x[:n].copy(), y


@njit(cache=True)
def emptiness(A, b, h, b_err, radius, maxit):
    """The whole phase-1 emptiness test of
    :meth:`setobs.lp.factor.FactorPolytope.emptiness` for every ``h_j`` finite, in one
    call: the rows scaled by powers of two (the smallest at least
    ``max(max_j |A_ij|, |b_i|)``, exact), :func:`phase1`, the certificate
    (:func:`~setobs.lp.certificate.lower_bound` of the zero objective, ``b_err`` scaled
    alike) divided by
    ``||y||_1`` and rounded down, and the phase-1 point clipped to its bounds with
    its largest scaled row violation. Returns ``(code, lower_inf, found, xi)``;
    ``code != OPTIMAL`` means nothing was decided.
    """
    m, n = A.shape
    As = np.empty((m, n))
    bs = np.empty(m)
    be = np.empty(m)
    for i in range(m):
        s = abs(b[i])
        for j in range(n):
            s = max(s, abs(A[i, j]))
        if s > 0.0:
            mant, ex = math.frexp(s)
            sc = math.ldexp(1.0, ex - 1 if mant == 0.5 else ex)
        else:
            sc = 1.0
        for j in range(n):
            As[i, j] = A[i, j] / sc
        bs[i] = b[i] / sc
        be[i] = b_err[i] / sc
    code, x, y = phase1(As, bs, h, maxit)
    if code != OPTIMAL:
        return code, 0.0, np.nan, x
    for j in range(n):
        if not (np.isfinite(x[j])):
            return NUMERICAL, 0.0, np.nan, x
    for i in range(m):
        if not np.isfinite(y[i]):
            return NUMERICAL, 0.0, np.nan, x
    indptr, indices, cdata = csc_of(As)
    lower, _ = lower_bound(np.zeros(n), indptr, indices, cdata, bs, -h, h, y,
                           np.zeros(0, np.int64), np.zeros((m, 0)), radius, 0.0, be,
                           np.zeros(0), np.zeros((0, n)), np.zeros(0), False, As)
    norm1 = 0.0
    for i in range(m):
        norm1 += abs(y[i])
    norm1 *= 1.0 + 2.0 * gamma_k(m + 1)
    lower_inf = 0.0
    if norm1 > 0.0 and np.isfinite(lower) and lower > 0.0:
        lower_inf = np.nextafter(lower / norm1, -np.inf)
    found = 0.0
    for j in range(n):
        x[j] = min(max(x[j], -h[j]), h[j])
    for i in range(m):
        r = -bs[i]
        for j in range(n):
            r += As[i, j] * x[j]
        found = max(found, abs(r))
    return OPTIMAL, lower_inf, found, x
