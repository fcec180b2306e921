"""Complexity reduction of constrained zonotopes. None of these loses a point.

* :func:`remove_redundancy` — exact up to a rank tolerance: drops factors with
  ``h_j = 0`` or with zero columns in both ``G`` and ``A``, and constraint rows
  that are (numerically) linear combinations of the others in ``[A | b]``.
  Dropping a constraint can only enlarge the set, so a too-generous tolerance
  costs tightness, never soundness; inconsistent rows are kept, so emptiness is
  preserved.
* :func:`rescale` — Scott et al. (2016), Sec. 4: shrink each factor interval to
  the certified interval hull of that factor over the factor polytope and
  recentre. The set is unchanged (the new factor box lies inside the old one
  and contains the factor polytope). Unbounded factors that turn out bounded
  become bounded.
* :func:`reduce_exact` — exact: removes factor bounds that the constraints
  already imply (certified), eliminates each freed factor together with one
  constraint row (Scott et al. 2016, Sec. 4.2, with the bound check made
  certified instead of an outer approximation), and drops unused factors.
* :func:`reduce_order` — outer generator-order reduction by Girard's method on
  the lifted zonotope ``{[G; A] xi + [c; -b]}`` (Scott et al. 2016, Sec. 4.3):
  the smallest bounded generators are replaced by their interval hull. When
  the requested order is below what that can reach (``n + n_c``), constraints
  are first eliminated by :func:`eliminate_constraints`.
* :func:`eliminate_constraints` — outer: Scott et al. (2016), Sec. 4.2, with
  the Hausdorff-error heuristic of their eq. (A.8) choosing the factor whose
  bound is dropped.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import cho_factor, cho_solve, qr

from .._lazy import lazy_module
from .._rounding import UNIT_ROUNDOFF, gamma
from ..exceptions import EmptySetError, InvalidValueError
from ..lp.factor import COMPILED_MAX_ROWS
from ..tolerances import (
    ELIMINATION_ERR_RTOL,
    ELIMINATION_PIVOT_TOL,
    PINNED_FACTOR_RTOL,
    REDUNDANT_BOUND_MARGIN,
    ZERO_TOL,
)
from .box import box_center_radius
from .zonotope import ConstrainedZonotope, factor_polytope, trusted_cz

# The compiled propagation (numba) loads on the first elimination, not on import.
_prop = lazy_module("setobs.geometry._propagation")

__all__ = [
    "eliminate_constraints",
    "hausdorff_heuristic",
    "hausdorff_heuristics",
    "propagated_factor_ranges",
    "reduce_exact",
    "reduce_order",
    "relaxed_overshoots",
    "remove_redundancy",
    "rescale",
]


def remove_redundancy(Z: ConstrainedZonotope, tol: float = ZERO_TOL) -> ConstrainedZonotope:
    """Remove unused factors and dependent constraint rows.

    Parameters
    ----------
    Z : ConstrainedZonotope
    tol : float
        Relative rank tolerance for dependent rows (rows of ``[A | b]`` are
        first scaled to unit Euclidean norm; a row is dependent when its
        pivoted-QR diagonal is below ``tol`` times the largest).

    Returns
    -------
    ConstrainedZonotope
        A representation of a superset of ``Z`` that equals ``Z`` when the
        dropped rows are exactly dependent.
    """
    G, c, A, b, h = Z.G, Z.c, Z.A, Z.b, Z.h
    berr = Z.b_err
    # Factors fixed at zero, or appearing nowhere, are unused.
    keep_f = (h > 0) & (G.any(axis=0) | A.any(axis=0))
    G, A, h = G[:, keep_f], A[:, keep_f], h[keep_f]
    # Constraint rows: drop the all-zero consistent ones, then dependent ones.
    aug = np.hstack([A, b[:, None]])
    nz = aug.any(axis=1)
    aug, A, b, berr = aug[nz], A[nz], b[nz], berr[nz]
    if A.shape[0] > 1:
        norms = np.linalg.norm(aug, axis=1)
        _, R, piv = qr((aug / norms[:, None]).T, mode="economic", pivoting=True)
        d = np.abs(np.diag(R))
        rank = int((d > tol * d[0]).sum()) if d.size else 0
        rows = np.sort(piv[:rank])
        A, b, berr = A[rows], b[rows], berr[rows]
    return trusted_cz(G, c, A, b, h, Z.unbounded_radius, Z.c_err, berr)


def rescale(Z: ConstrainedZonotope) -> ConstrainedZonotope:
    """Shrink and recentre factor intervals to their certified hull (Scott et al. 2016, Sec. 4).

    For each factor ``j``, certified bounds ``[l_j, u_j]`` of ``xi_j`` over
    ``{xi : A xi = b, |xi| <= h}`` are computed (``2 n_g`` LPs); with
    ``m = (l + u)/2``, ``r = (u - l)/2`` (rounded up), the set is rewritten as
    ``{G eta + (c + G m) : A eta = b - A m, |eta| <= r}``. Factors with
    ``r_j = 0`` are removed. Unbounded factors with an infinite bound are kept.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.

    Raises
    ------
    EmptySetError
        If ``Z`` is certified empty.
    """
    n_g = Z.n_gen
    if n_g == 0:
        return Z
    fp = factor_polytope(Z)
    lo = np.empty(n_g)
    hi = np.empty(n_g)
    for j in range(n_g):
        e = np.zeros(n_g)
        e[j] = 1.0
        lo[j] = fp.minimize(e).bound
        hi[j] = -fp.minimize(-e).bound
    # Never widen beyond the original bound.
    lo = np.maximum(lo, -Z.h)
    hi = np.minimum(hi, Z.h)
    # lo = -h and hi = h where unbounded (the interval of a factor is bounded or R)
    m, r = box_center_radius(lo, hi)
    c = Z.c + Z.G @ m
    b = Z.b - Z.A @ m
    # rounding of the recentring (Higham's bounds), on top of what Z carried
    g = gamma(n_g + 2) * (1.0 + gamma(n_g + 3))
    cerr = Z.c_err + g * (np.abs(Z.c) + np.abs(Z.G) @ np.abs(m))
    berr = Z.b_err + g * (np.abs(Z.b) + np.abs(Z.A) @ np.abs(m))
    keep = r > 0
    return trusted_cz(Z.G[:, keep], c, Z.A[:, keep], b, r[keep], Z.unbounded_radius,
                                        cerr, berr)


def reduce_order(Z: ConstrainedZonotope, max_generators: int) -> ConstrainedZonotope:
    """Outer generator-order reduction (Girard's method on the lifted zonotope).

    The lifted generators ``l_j = h_j [G_j; A_j]`` of bounded factors are ranked
    by ``||l_j||_1 - ||l_j||_inf`` (the cost of boxing them); the smallest are
    replaced by one axis-aligned generator per nonzero row of ``sum |l_j|``.
    Unbounded factors are kept.

    Parameters
    ----------
    Z : ConstrainedZonotope
    max_generators : int
        Upper bound on the number of generators of the result.

    Returns
    -------
    ConstrainedZonotope
        A superset of ``Z`` with at most ``max_generators`` generators.

    Raises
    ------
    InvalidValueError
        If ``max_generators`` is below ``n + (number of unbounded factors)``,
        the fewest a reduction of this kind can reach in general.

    Notes
    -----
    Girard's step keeps ``n + n_c`` generators at least. Below that (a set
    converted from a polytope has ``n_g = n + n_c``), constraints are first
    eliminated (:func:`eliminate_constraints`, outer) down to
    ``max_generators - n - n_unbounded``.
    """
    if int(max_generators) != max_generators or max_generators < 0:
        raise InvalidValueError(
            f"max_generators must be a nonnegative integer, got {max_generators}")
    if Z.n_gen <= max_generators:
        return Z
    n, n_c = Z.dim, Z.n_con
    unb = np.isinf(Z.h)
    n_unb = int(unb.sum())
    if max_generators < n + n_unb:
        raise InvalidValueError(
            f"max_generators must be at least n + n_unbounded = {n + n_unb}, got {max_generators}"
        )
    if max_generators < n + n_c + n_unb:
        Z = eliminate_constraints(Z, max_generators - n - n_unb)
        if Z.n_gen <= max_generators:
            return Z
        n_c = Z.n_con
        unb = np.isinf(Z.h)
        n_unb = int(unb.sum())
        if max_generators < n + n_c + n_unb:
            raise InvalidValueError(
                f"could not eliminate enough constraints to reach {max_generators} generators "
                f"(n = {n}, n_c = {n_c} left, {n_unb} unbounded factors)")
    bnd = np.flatnonzero(~unb)
    L = np.vstack([Z.G[:, bnd], Z.A[:, bnd]]) * Z.h[bnd]
    score = np.abs(L).sum(axis=0) - np.abs(L).max(axis=0, initial=0.0)
    n_keep = max_generators - n_unb - (n + n_c)
    order = np.argsort(score, kind="stable")[::-1]
    keep_b = bnd[np.sort(order[:n_keep])]
    boxed = bnd[order[n_keep:]]
    Lb = np.vstack([Z.G[:, boxed], Z.A[:, boxed]]) * Z.h[boxed]
    s = np.abs(Lb).sum(axis=1)
    # Outward rounding of the box half-widths.
    s = np.where(s > 0, np.nextafter(s * (1.0 + 4.0 * np.finfo(float).eps * Lb.shape[1]), np.inf),
                 0.0)
    rows = np.flatnonzero(s > 0)
    box = np.zeros((n + n_c, rows.size))
    box[rows, np.arange(rows.size)] = s[rows]
    cols = np.concatenate([keep_b, np.flatnonzero(unb)])
    G = np.hstack([Z.G[:, cols], box[:n]])
    A = np.hstack([Z.A[:, cols], box[n:]])
    h = np.concatenate([Z.h[cols], np.ones(rows.size)])
    return trusted_cz(G, Z.c, A, Z.b, h, Z.unbounded_radius, Z.c_err, Z.b_err)


def _factor_ranges(Z: ConstrainedZonotope, cols: NDArray[np.int_], both: bool = False
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Certified ``[lo_j, hi_j]`` of the factors ``cols`` over the factor polytope (``hi_j``
    left at ``inf`` where ``lo_j`` reaches the bound ``-h_j``, unless ``both``)."""
    fp = factor_polytope(Z)
    lo = np.full(cols.size, -np.inf)
    hi = np.full(cols.size, np.inf)
    W = np.zeros((2 * cols.size, Z.n_gen))
    W[2 * np.arange(cols.size), cols] = 1.0
    W[2 * np.arange(cols.size) + 1, cols] = -1.0
    fast, ok = fp.minimize_many(W)  # (the compiled batch, where every bound is finite)
    e = np.zeros(Z.n_gen)
    for t, j in enumerate(cols):
        e[j] = 1.0
        lo[t] = fast[2 * t] if ok[2 * t] else fp.minimize(e).bound
        if both or lo[t] > -Z.h[j]:  # (else the bound is active: the other side not needed)
            hi[t] = -fast[2 * t + 1] if ok[2 * t + 1] else -fp.minimize(-e).bound
        e[j] = 0.0
    return lo, hi


def reduce_exact(Z: ConstrainedZonotope) -> ConstrainedZonotope:
    """The same set with fewer factors and constraints (nothing is approximated).

    Three exact steps, each decided by certified LP bounds (where a decision
    is not certain, the factor or row stays):

    1. **Implied bounds.** For each bounded factor ``xi_j`` that appears in a
       constraint, certified bounds ``[l_j, u_j]`` of ``xi_j`` over the factor
       polytope ``F = {xi : A xi = b, |xi| <= h}`` are computed (two LPs). If
       ``-h_j < l_j`` and ``u_j < h_j`` (by the relative margin
       :data:`REDUNDANT_BOUND_MARGIN`), the bound ``|xi_j| <= h_j`` is
       redundant and is dropped (``h_j = inf``). All such bounds can be dropped
       *together*: removing one redundant bound leaves ``F`` unchanged (a
       point of the relaxed set with ``|xi_j| > h_j`` would, by convexity, give
       a point of ``F`` on the segment to any point of ``F`` with ``xi_j = ±h_j``),
       so the bounds of the others are computed on the same ``F``. A factor
       fixed by the constraints (``l_j = u_j`` inside its bound) is a special case.
    2. **Elimination** (Scott et al. 2016, Sec. 4.2; exact here because the
       bound of the eliminated factor is redundant or infinite): each factor
       without a bound that appears in a constraint row ``i`` is solved for,
       ``xi_j = (b_i - sum_(k != j) A_ik xi_k) / A_ij``, and substituted into
       ``G``, ``c``, ``A``, ``b``; the row and the factor disappear. Pivots are
       chosen by size relative to their row (partial pivoting; none below
       :data:`ELIMINATION_PIVOT_TOL`). The rounding of ``c`` and ``b`` is
       added to :attr:`~ConstrainedZonotope.c_err` and
       :attr:`~ConstrainedZonotope.b_err` (and the uncertainty ``b_err`` of
       the pivot row moves into ``c_err``), as everywhere in the library.
       These bounds are propagated elementwise, so over a long chain of
       eliminations they compound (each one moves a row's uncertainty into
       ``c`` and back into the other rows, decorrelated): elimination stops
       before the tracked rounding of ``c`` or ``b`` exceeds
       :data:`ELIMINATION_ERR_RTOL` times the size of the set's data (or what
       ``Z`` already carried). Redundant bounds of factors that are not
       eliminated are kept.
    3. **Unused parts.** Factors with ``h_j = 0`` or with zero columns in both
       ``G`` and ``A`` are dropped; rows that are exactly zero are dropped
       (an exactly zero row with a right-hand side certified nonzero makes
       the set empty).

    Parameters
    ----------
    Z : ConstrainedZonotope

    Returns
    -------
    ConstrainedZonotope
        The same set (up to the rounding of the eliminated matrices, ``O(eps)``
        relative, as in every set operation of the library).

    Raises
    ------
    EmptySetError
        If ``Z`` is certified empty.

    Notes
    -----
    Cost: ``2`` LPs per bounded factor that appears in a constraint, plus the
    elimination (``O(n_c (n + n_c) n_g)``). A set without constraints is
    returned with only step 3 applied. Measured on the exact-mode sets of the
    paper example (``benchmarks/exact_mode.py``): at ``k = 5`` the
    representation ``(15 generators, 12 constraints)`` reduces to ``(4, 1)``;
    on longer histories the rounding budget stops the elimination early.

    Examples
    --------
    The square ``[-1, 1]^2`` with the redundant constraint ``|x_1 + x_2| <= 3``
    written as ``x_1 + x_2 + s = 0`` with a slack ``|s| <= 3``:

    >>> Z = ConstrainedZonotope([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0.0, 0.0],
    ...                         A=[[1.0, 1.0, 1.0]], b=[0.0], h=[1.0, 1.0, 3.0])
    >>> R = reduce_exact(Z)
    >>> (R.n_gen, R.n_con)
    (2, 0)
    """
    return reduce_exact_among(Z, np.ones(Z.n_gen, dtype=bool))[0]


def reduce_exact_among(Z: ConstrainedZonotope, eligible: NDArray[np.bool_],
                       pin: bool = False) -> tuple[ConstrainedZonotope, NDArray[np.int64]]:
    """:func:`reduce_exact` where only the factors ``eligible`` may lose their bound and be
    eliminated (the others are kept unless unused), and the positions in ``Z`` of the
    factors that remain, in their new order (package-internal: a hybrid zonotope's binary
    factors are never eliminated, and their flags follow the kept positions).

    With ``pin``, an eligible factor that keeps its bound (one end of its range reaches
    it, so it cannot be eliminated) and whose certified range ``[lo_j, hi_j]`` has a
    half-width ``r_j`` of at most :data:`PINNED_FACTOR_RTOL` ``h_j`` is *pinned*: replaced
    by the range's centre ``m_j`` (moved into ``c`` and ``b``), ``|G_j| r_j`` and
    ``|A_j| r_j`` and the rounding added to ``c_err`` and ``b_err``, so the set it
    stands for still contains ``Z`` (a constraint that forces a factor to one value, as
    a union's selector does to a dropped operand's copies, is certified to within the
    LP's accuracy, never exactly)."""
    G, c, A, b, h = Z.G.copy(), Z.c.copy(), Z.A.copy(), Z.b.copy(), Z.h.copy()
    cerr, berr = Z.c_err.copy(), Z.b_err.copy()
    # 1. implied bounds (certified): such factors become free to eliminate; their
    # bounds h stay (exact either way, and bounded factors keep the LPs well posed)
    free = np.isinf(h) & eligible
    if A.shape[0]:
        cand = np.flatnonzero(np.isfinite(h) & (h > 0) & A.any(axis=0) & eligible)
        if cand.size:
            lo, hi = _factor_ranges(Z, cand, both=pin)
            free[cand] = (lo > -h[cand] * (1.0 - REDUNDANT_BOUND_MARGIN)) & \
                (hi < h[cand] * (1.0 - REDUNDANT_BOUND_MARGIN))
            if pin:
                m, r = box_center_radius(np.maximum(lo, -h[cand]), np.minimum(hi, h[cand]))
                sel = (r <= PINNED_FACTOR_RTOL * h[cand]) & ~free[cand]
                P, mP, rP = cand[sel], m[sel], r[sel]
                if P.size:
                    g = gamma(P.size + 2) * (1.0 + gamma(P.size + 3))
                    GP, AP = G[:, P], A[:, P]
                    cerr = cerr + np.abs(GP) @ rP + g * (np.abs(c) + np.abs(GP) @ np.abs(mP))
                    berr = berr + np.abs(AP) @ rP + g * (np.abs(b) + np.abs(AP) @ np.abs(mP))
                    c = c + GP @ mP
                    b = b - AP @ mP
                    G[:, P] = 0.0
                    A[:, P] = 0.0
                    h[P] = 0.0
                    free[P] = False
        elif Z.is_empty():  # no LP was needed; still decide emptiness
            raise EmptySetError("the set is empty")
    # 2. eliminate free factors with constraint rows, while the tracked rounding
    # of c and b stays within its budget; 3. drop the unused parts
    return _eliminate_and_trim(Z, G, c, A, b, h, cerr, berr, free,
                               _budgets(G, c, A, b, h, cerr, berr))


def _eliminate_and_trim(Z: ConstrainedZonotope, G, c, A, b, h, cerr, berr, free, budgets
                        ) -> tuple[ConstrainedZonotope, NDArray[np.int64]]:
    """:func:`_eliminate_free` on the factors ``free``, then drop the exactly zero rows and
    the unused factors (``h = 0``, or zero columns in ``G`` and ``A``): the set ``Z``'s
    data after those exact steps, as a set, and the kept factors' positions in ``Z``."""
    G, c, A, b, h, cerr, berr, _, pos = _eliminate_free(G, c, A, b, h, cerr, berr, free,
                                                        budgets)
    A, b, berr = _drop_zero_rows(A, b, berr)
    keep = (h > 0) & (G.any(axis=0) | A.any(axis=0))
    out = trusted_cz(G[:, keep], c, A[:, keep], b, h[keep], Z.unbounded_radius, cerr, berr)
    return out, pos[keep]


def _drop_zero_rows(A, b, berr):
    """Drop exactly zero constraint rows (``0 = b_i``); a right-hand side certified
    nonzero (beyond its uncertainty ``berr``) makes the set empty."""
    zero_r = ~A.any(axis=1)
    if not zero_r.any():
        return A, b, berr
    if (np.abs(b[zero_r]) > berr[zero_r]).any():
        raise EmptySetError("the set is empty (a constraint 0 = b_i with b_i != 0)")
    return A[~zero_r], b[~zero_r], berr[~zero_r]


def _budgets(G, c, A, b, h, cerr, berr) -> tuple[float, float]:
    """Rounding budgets of ``c`` and ``b`` for a chain of eliminations: the error already
    carried plus ``ELIMINATION_ERR_RTOL`` of the data's size. (It was the larger of
    the two, so a set that had carried its error past that size, e.g. after 25 steps
    of a filter, had no room left and every later elimination stalled.)"""
    fin = np.where(np.isfinite(h), h, 0.0)
    c_budget = float(cerr.max(initial=0.0)) + ELIMINATION_ERR_RTOL * (
        1.0 + float(np.abs(c).max(initial=0.0)) + float((np.abs(G) @ fin).max(initial=0.0)))
    b_budget = float(berr.max(initial=0.0)) + ELIMINATION_ERR_RTOL * (
        1.0 + float(np.abs(b).max(initial=0.0)) + float((np.abs(A) @ fin).max(initial=0.0)))
    return c_budget, b_budget


def _eliminate_free(G, c, A, b, h, cerr, berr, free, budgets, max_steps: int | None = None):
    """Eliminate factors flagged ``free`` with constraint rows (Scott et al. 2016, Sec. 4.2).

    Each step solves a constraint row for one free factor,
    ``xi_j = (b_i - sum_(k != j) A_ik xi_k) / A_ij``, and substitutes it into
    ``G``, ``c``, ``A``, ``b`` (partial pivoting, no pivot below
    :data:`ELIMINATION_PIVOT_TOL` of its row), carrying the rounding of ``c``
    and ``b`` (and the uncertainty of the pivot row) into ``cerr`` and
    ``berr``; it stops before that rounding exceeds ``budgets``. Returns the
    new arrays, the number of steps taken and the remaining factors' positions
    in the given ones.
    """
    c_budget, b_budget = budgets
    g2 = 2.0 * gamma(4)
    steps = 0
    pos = np.arange(G.shape[1])
    while A.shape[0] and (max_steps is None or steps < max_steps):
        unb = np.flatnonzero(free)
        if not unb.size:
            break
        rowmax = np.abs(A).max(axis=1)
        rel = np.abs(A[:, unb]) / np.where(rowmax > 0, rowmax, 1.0)[:, None]
        i, jj = np.unravel_index(int(np.argmax(rel)), rel.shape)
        if not rel[i, jj] >= ELIMINATION_PIVOT_TOL:
            break
        j = int(unb[jj])
        piv = A[i, j]
        ai = A[i] / piv
        t = b[i] / piv
        g = G[:, j].copy()
        gt = g * t
        c1 = c + gt
        cerr1 = cerr + (np.abs(g) * berr[i] / abs(piv) + g2 * (np.abs(c1) + np.abs(gt))) \
            * (1.0 + g2)
        col = A[:, j].copy()
        colt = col * t
        b1 = b - colt
        berr1 = berr + (np.abs(col) * berr[i] / abs(piv) + g2 * (np.abs(b1) + np.abs(colt))) \
            * (1.0 + g2)
        keep_r = np.arange(A.shape[0]) != i
        if cerr1.max(initial=0.0) > c_budget or berr1[keep_r].max(initial=0.0) > b_budget:
            break  # the certified rounding would grow past its budget: stop here
        c, cerr, b, berr = c1, cerr1, b1, berr1
        G = G - np.outer(g, ai)
        A = A - np.outer(col, ai)
        keep_c = np.arange(G.shape[1]) != j
        G, A, h, free = G[:, keep_c], A[keep_r][:, keep_c], h[keep_c], free[keep_c]
        b, berr, pos = b[keep_r], berr[keep_r], pos[keep_c]
        steps += 1
    return G, c, A, b, h, cerr, berr, steps, pos


def relaxed_overshoots(Z: ConstrainedZonotope, cand: ArrayLike) -> NDArray[np.float64]:
    """Relative overshoots ``r_j = max(0, max |xi_j| / h_j - 1)`` of the factors ``cand``
    over the factor set with ``xi_j``'s own bound dropped (certified; the ``"lp"`` mode
    of :func:`eliminate_constraints`).

    Where every bound is finite (and the rows are at most
    :data:`~setobs.lp.factor.COMPILED_MAX_ROWS`), by the compiled simplex: with ``xi_j``'s bound
    dropped, ``|xi_j|`` is still at most its one-sweep propagated range ``R0_j`` (an
    outer bound over the relaxed set: each row bounds ``xi_j`` by the other factors'
    own bounds, rounding included), so the relaxed set is the bounded polytope with
    ``h_j = R0_j`` and its two LPs are solved on one structure whose state carries the
    basis from candidate to candidate (certified bounds). The others, and any LP not
    solved there, on HiGHS.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    cand : array_like of int
        The factors.

    Returns
    -------
    ndarray, shape (n_gen,)
        ``r_j`` for the factors in ``cand`` (``inf`` where the relaxed set is unbounded
        in ``xi_j``); ``inf`` for the others.
    """
    cand = np.asarray(cand, dtype=int).reshape(-1)
    r = np.full(Z.n_gen, np.inf)
    h = Z.h
    if not cand.size:
        return r
    todo = list(cand)
    if np.isfinite(h).all() and 0 < Z.n_con <= COMPILED_MAX_ROWS:
        from ..lp.fastlp import FixedStructureLP

        R0_lo, R0_hi = _row_ranges(Z.A, Z.b, -h, h, Z.b_err)
        reach0 = np.maximum(-R0_lo, R0_hi)
        base = FixedStructureLP.bounded(Z.A, np.zeros((2, Z.n_gen)))
        state = None
        zeros = np.zeros(Z.n_con)
        todo = []
        for j in cand:
            if not np.isfinite(reach0[j]):
                continue  # (unbounded when relaxed: never chosen)
            if reach0[j] <= h[j]:
                r[j] = 0.0  # the bound is implied (by one row already)
                continue
            W = np.zeros((2, Z.n_gen))
            W[0, j], W[1, j] = 1.0, -1.0
            lp = base.with_objectives(W)
            state = lp.new_state() if state is None else state
            hj = h.copy()
            hj[j] = reach0[j]
            bounds, ok = lp.minimize_all(Z.b, np.concatenate([hj, zeros]), state,
                                         b_err=Z.b_err if Z.b_err.any() else None)
            if ok.all():
                reach = max(-bounds[0], -bounds[1])
                r[j] = max(0.0, reach / h[j] - 1.0)
            else:
                todo.append(j)
    for j in todo:
        r[j] = _overshoot(Z, int(j))
    return r


def _overshoot(Z: ConstrainedZonotope, j: int) -> float:
    """Relative overshoot ``r_j = max(0, max|xi_j| / h_j - 1)`` of factor ``j`` when its
    bound is dropped (certified outer range of ``xi_j`` over the relaxed factor set)."""
    h = Z.h.copy()
    hj = h[j]
    h[j] = np.inf
    R = trusted_cz(Z.G, Z.c, Z.A, Z.b, h, Z.unbounded_radius, Z.c_err, Z.b_err)
    fp = factor_polytope(R)
    e = np.zeros(Z.n_gen)
    e[j] = 1.0
    lo = fp.minimize(e).bound
    hi = -fp.minimize(-e).bound
    reach = max(-lo, hi)
    return float(max(0.0, reach / hj - 1.0)) if np.isfinite(reach) else np.inf


def hausdorff_heuristic(Z: ConstrainedZonotope, j: int, r: float) -> float:
    """Hausdorff-error heuristic of dropping factor ``j``'s bound (Scott et al. 2016, eq. (A.8)).

    ``min ||G D d||^2 + ||d||^2`` subject to ``A D d = 0`` and ``d_j = r``, with
    ``D = diag(h)`` (the factors in units of their bounds), solved through its
    KKT system.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set (bounded factors).
    j : int
        The factor whose bound would be dropped.
    r : float
        Its relative overshoot (see :func:`eliminate_constraints`).
    """
    D = np.where(np.isfinite(Z.h), Z.h, 1.0)
    GD = Z.G * D
    AD = Z.A * D
    ng, nc = Z.n_gen, Z.n_con
    Q = GD.T @ GD + np.eye(ng)
    C = np.vstack([AD, np.eye(ng)[j]])
    K = np.block([[Q, C.T], [C, np.zeros((nc + 1, nc + 1))]])
    rhs = np.concatenate([np.zeros(ng + nc), [r]])
    sol = np.linalg.lstsq(K, rhs, rcond=None)[0]
    d = sol[:ng]
    return float(np.sum((GD @ d) ** 2) + np.sum(d**2))


#: ``n_gen * n_con`` above which :func:`eliminate_constraints` (``method="auto"``) bounds
#: the overshoots by interval propagation instead of LPs. Below it the LP mode's
#: ``2 n_g`` LPs per step cost a few milliseconds; above it they dominate (a 3-D
#: polytope with 60 facets, ``63 x 60``: seconds per eliminated constraint).
FAST_ELIMINATION_SIZE: int = 400

#: Candidates of the fast elimination whose overshoot is then computed exactly (two
#: certified LPs each, :func:`relaxed_overshoots`): the propagated overshoots rank the
#: factors, the exact ones of the best few choose. On the 60-facet polytope (30
#: eliminations) the support excess fell from 0.17 (propagation alone) to 0.016 for
#: 5 ms per eliminated constraint instead of 1.2 (4: 0.026, 16: 0.019).
FAST_ELIMINATION_REFINE: int = 8

#: Sweeps of the interval propagation of :func:`propagated_factor_ranges` (it stops
#: earlier once no bound moves by more than ``PROPAGATION_MOVE`` of its factor's bound).
PROPAGATION_SWEEPS: int = 10
PROPAGATION_MOVE: float = 1e-3


def _row_ranges(A: NDArray[np.float64], b: NDArray[np.float64],
                lo: NDArray[np.float64], hi: NDArray[np.float64],
                b_err: NDArray[np.float64] | None = None
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """For every factor ``j``, the intersection over rows ``i`` (``A_ij != 0``) of the
    ranges ``(b_i - sum_(k != j) A_ik xi_k) / A_ij`` with ``xi_k`` in ``[lo_k, hi_k]``
    (interval arithmetic in midpoint-radius form; a half-infinite bound counts as
    unbounded), widened by the uncertainty ``b_err`` of ``b`` and by a bound on the
    rounding of the evaluation, ``2 gamma_(n_g + 8) (|b_i| + |A_i| (|m| + r)) / |A_ij|``
    (every term of the row's sums in any order, the exclusion of ``j`` and the division),
    the radius then scaled by ``1 + 4 u``, so that the ranges are outer in floating point
    too. Compiled (:func:`setobs.geometry._propagation.row_ranges`)."""
    return _prop.row_ranges(*_kernel_args(A, b, lo, hi, b_err))


def _kernel_args(A, b, lo, hi, b_err):
    A = np.ascontiguousarray(A, dtype=np.float64)
    be = np.zeros(0) if b_err is None else np.ascontiguousarray(b_err, dtype=np.float64)
    return (A, np.ascontiguousarray(b, dtype=np.float64),
            np.ascontiguousarray(lo, dtype=np.float64),
            np.ascontiguousarray(hi, dtype=np.float64), be,
            2.0 * gamma(A.shape[1] + 8), 1.0 + 4.0 * UNIT_ROUNDOFF)



def propagated_factor_ranges(A: ArrayLike, b: ArrayLike, h: ArrayLike,
                             sweeps: int = PROPAGATION_SWEEPS,
                             b_err: ArrayLike | None = None
                             ) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                        NDArray[np.float64], NDArray[np.float64]]:
    """Factor bounds by interval constraint propagation (Scott et al. 2016, Sec. 4.2).

    Starting from ``E_j = [-h_j, h_j]``, each sweep computes for every factor the
    range ``R_j`` the equality constraints imply given the current bounds of the
    other factors, ``R_j = cap_i (b_i - sum_(k != j) A_ik E_k) / A_ij``, and
    tightens ``E_j <- E_j cap R_j`` (Jacobi sweeps, vectorised).

    Parameters
    ----------
    A : array_like, shape (n_c, n_g)
    b : array_like, shape (n_c,)
    h : array_like, shape (n_g,)
        Factor bounds (``inf`` allowed).
    sweeps : int
        Largest number of sweeps.
    b_err : array_like, shape (n_c,), optional
        Uncertainty of ``b``: the bounds hold for every right-hand side within it.

    Returns
    -------
    E_lo, E_hi : ndarray, shape (n_g,)
        Tightened bounds ``E_j``: outer bounds of ``xi_j`` over the factor set (each
        range is widened by a bound on its rounding, so they are outer in floating
        point as well).
    R_lo, R_hi : ndarray, shape (n_g,)
        The ranges ``R_j`` implied by the constraints and the other factors' ``E_k``
        in the last sweep (``+-inf`` where no row bounds ``xi_j``). ``R_j`` strictly
        inside ``(-h_j, h_j)`` means ``xi_j``'s bound is redundant (the argument of
        :func:`reduce_exact`, step 1).

    Notes
    -----
    Cost ``O(n_c n_g)`` per sweep, no LP: this is the "iterative method" Scott et
    al. use for the ranges (CORA's ``reduceConstraints`` does the same).
    :func:`eliminate_constraints` shrinks the factor bounds to ``E`` (the set is
    unchanged: ``E`` contains every factor's range) and ranks the choices by ``R``.
    """
    h_a = np.ascontiguousarray(h, dtype=np.float64)
    A_a, b_a, _, _, be, g2, scale = _kernel_args(A, b, h_a, h_a, b_err)
    # (a bound crossing its range -- rounding or an empty set -- keeps the old one)
    return _prop.propagate(A_a, b_a, h_a, int(sweeps), be, g2, scale, PROPAGATION_MOVE)


def hausdorff_heuristics(Z: ConstrainedZonotope, r: NDArray[np.float64]) -> NDArray[np.float64]:
    """:func:`hausdorff_heuristic` for every factor at once (Scott et al. 2016, eq. (A.8)).

    ``min d^T Q d`` subject to ``A D d = 0``, ``d_j = r_j`` (``Q = (G D)^T G D + I``)
    is ``r_j^2 / S_jj`` with ``S = Q^-1 - Q^-1 (AD)^T (AD Q^-1 (AD)^T)^+ AD Q^-1``
    (the Schur complement of the KKT system), and ``Q^-1 = I - (GD)^T (I + GD (GD)^T)^-1
    GD`` (Woodbury: an ``n x n`` solve): one factorisation for all ``j`` instead of one
    ``(n_g + n_c + 1)``-square solve each.

    Parameters
    ----------
    Z : ConstrainedZonotope
    r : ndarray, shape (n_g,)
        Relative overshoots (``inf``: never chosen, heuristic ``inf``).
    """
    D = np.where(np.isfinite(Z.h), Z.h, 1.0)
    GD = Z.G * D
    AD = Z.A * D
    n = Z.dim
    K = np.eye(n) + GD @ GD.T
    # (Q^-1 never formed: its diagonal and Q^-1 (AD)^T from the n x n_g solve, O(n n_g n_c)
    # instead of O(n_g^2 n_c))
    Y = np.linalg.solve(K, GD)
    q_diag = 1.0 - np.einsum("ij,ij->j", GD, Y)
    X = AD.T - GD.T @ (Y @ AD.T)
    M = AD @ X
    Sdiag = q_diag - np.einsum("jk,jk->j", X, _psd_solve(M, X.T).T)
    out = np.full(Z.n_gen, np.inf)
    fin = np.isfinite(r)
    tiny = 1e-12 * float(np.abs(q_diag).max(initial=1.0))
    pos = fin & (Sdiag > tiny)
    with np.errstate(over="ignore"):  # (an overshoot past 1e154: inf, never chosen)
        out[pos] = r[pos] ** 2 / Sdiag[pos]
    out[fin & ~pos & (r == 0.0)] = 0.0  # a factor the constraints fix, inside its bound
    return out


def _psd_solve(M: NDArray[np.float64], B: NDArray[np.float64]) -> NDArray[np.float64]:
    """``M^+ B`` for a symmetric positive semidefinite ``M``: by Cholesky where ``M`` is
    well conditioned (its factor's diagonal within 1e6 of itself), else the
    pseudo-inverse (dependent rows)."""
    if M.size:
        try:
            L = cho_factor(M, lower=True, check_finite=False)
        except np.linalg.LinAlgError:
            L = None
        if L is not None:
            d = np.abs(np.diag(L[0]))
            if d.min() > 1e-6 * d.max():
                return cho_solve(L, B, check_finite=False)
    return np.linalg.pinv(M, hermitian=True) @ B


def _eliminate_fast(Z: ConstrainedZonotope, max_constraints: int,
                    refine: int = FAST_ELIMINATION_REFINE, batch: int = 1
                    ) -> ConstrainedZonotope:
    """:func:`eliminate_constraints` with overshoots from interval propagation."""
    # exact first: factors already unbounded go with a row each (no LP needed)
    G, c, A, b, h, cerr, berr = Z.G, Z.c, Z.A, Z.b, Z.h, Z.c_err, Z.b_err
    budgets = _budgets(G, c, A, b, h, cerr, berr)
    Z = _eliminate_and_trim(Z, G, c, A, b, h, cerr, berr, np.isinf(h), budgets)[0]
    while Z.n_con > max_constraints:
        h = Z.h
        bounded = np.isfinite(h) & (h > 0) & Z.A.any(axis=0)
        # the relaxed set stays bounded in xi_j iff some row bounds it by the other
        # factors' own bounds (one sweep from h), so only such factors are candidates
        R0_lo, R0_hi = _row_ranges(Z.A, Z.b, -h, h)
        cand = bounded & np.isfinite(R0_lo) & np.isfinite(R0_hi)
        E_lo, E_hi, R_lo, R_hi = propagated_factor_ranges(Z.A, Z.b, h, b_err=Z.b_err)
        # Scott et al.'s rescaling, symmetric (no recentring, so no rounding): the bounds
        # shrink to the outer ranges E, which leaves the set as it is, and a bound
        # dropped later relaxes from there
        shrunk = np.minimum(h, np.maximum(-E_lo, E_hi))
        if (shrunk < h).any():
            h = shrunk
            Z = trusted_cz(Z.G, Z.c, Z.A, Z.b, h, Z.unbounded_radius, Z.c_err, Z.b_err)
        reach = np.maximum(-R_lo, R_hi)  # (inside the one-sweep range, which is finite)
        reach = np.where(np.isfinite(reach), reach, np.maximum(-R0_lo, R0_hi))
        r = np.full(Z.n_gen, np.inf)
        with np.errstate(over="ignore"):  # (a tiny bound: inf, never chosen)
            r[cand] = np.maximum(0.0, reach[cand] / h[cand] - 1.0)
        score = hausdorff_heuristics(Z, r)
        # the propagated overshoots rank; the exact ones of the best few decide
        top = np.argsort(score, kind="stable")[:refine]
        top = top[np.isfinite(score[top])]
        if top.size > 1:
            score = hausdorff_heuristics(Z, relaxed_overshoots(Z, top))
        if batch > 1:
            Z, eliminated = _drop_bounds(Z, score, budgets,
                                         min(batch, Z.n_con - max_constraints))
        else:
            Z, eliminated = _drop_best_bound(Z, score, budgets)
        if not eliminated:
            break  # no candidate could be eliminated
    return Z


def _drop_bounds(Z: ConstrainedZonotope, score: NDArray[np.float64],
                 budgets: tuple[float, float], count: int) -> tuple[ConstrainedZonotope, int]:
    """Up to ``count`` eliminations in the order of one ``score`` (a batch of
    :func:`_drop_best_bound` without recomputing the scores): before each, the candidate
    is checked again on the current rows (bounded, in a row, and bounded by some row
    through the other factors' own bounds, so the result stays bounded). Returns the set
    and the number eliminated."""
    G, c, A, b, h, cerr, berr = Z.G, Z.c, Z.A, Z.b, Z.h, Z.c_err, Z.b_err
    ids = np.arange(Z.n_gen)
    done = 0
    for j0 in np.argsort(score, kind="stable"):
        if done >= count or not np.isfinite(score[j0]) or not A.shape[0]:
            break
        where = np.flatnonzero(ids == j0)
        if not where.size:
            continue
        j = int(where[0])
        if not (np.isfinite(h[j]) and h[j] > 0 and A[:, j].any()):
            continue
        rows = A[:, j] != 0.0  # (xi_j's one-sweep range: only the rows that hold it)
        R0_lo, R0_hi = _row_ranges(A[rows], b[rows], -h, h)
        if not (np.isfinite(R0_lo[j]) and np.isfinite(R0_hi[j])):
            continue
        out = _drop_one(G, c, A, b, h, cerr, berr, j, budgets)
        if out is None:
            continue
        G, c, A, b, h, cerr, berr = out
        ids = np.delete(ids, j)
        done += 1
    if not done:
        return Z, 0
    return trusted_cz(G, c, A, b, h, Z.unbounded_radius, cerr, berr), done


def eliminate_constraints(Z: ConstrainedZonotope, max_constraints: int,
                          method: str = "auto", refine: int | None = None,
                          batch: int = 1) -> ConstrainedZonotope:
    """Outer constraint elimination down to ``max_constraints`` (Scott et al. 2016, Sec. 4.2).

    With ``method="lp"``, first :func:`reduce_exact` removes what can be removed
    without loss. Then, while there are too many constraints, for every bounded
    factor ``xi_j`` that appears in a constraint the *overshoot* ``r_j`` is
    computed: the certified range of ``xi_j`` over the factor set with its own
    bound dropped (two LPs), as a multiple of ``h_j``, minus one. Dropping that bound
    enlarges the set by at most what ``xi_j`` gains beyond ``h_j``; the factor
    with the smallest Hausdorff-error heuristic of Scott et al. (2016),
    eq. (A.8) (``min ||G D d||^2 + ||d||^2`` with ``A D d = 0``,
    ``d_j = r_j``; an infinite ``r_j`` is never chosen) loses its bound and is
    eliminated with one constraint row (exactly, as in :func:`reduce_exact`).
    The result is an outer approximation (exact where ``r_j = 0``).

    With ``method="fast"`` the ranges come from interval constraint propagation
    (:func:`propagated_factor_ranges`, Scott et al.'s iterative method) and the
    heuristic of every factor from one factorisation
    (:func:`hausdorff_heuristics`); the :data:`FAST_ELIMINATION_REFINE` best
    candidates then get their exact overshoots (:func:`relaxed_overshoots`, two LPs
    each) and those decide. Only unbounded factors are eliminated exactly beforehand.
    Whatever bound is dropped, the result
    ``{G xi + c : A xi = b, |xi_k| <= h_k, k != j}`` contains the set (dropping a
    bound only enlarges the factor set, and eliminating an unbounded factor with
    a row is exact), so the overshoots only steer the choice; the candidates are
    restricted to factors that some row bounds through the other factors' own bounds,
    so the result stays bounded.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    max_constraints : int
        Largest number of constraints of the result.
    method : {"auto", "fast", "lp"}
        How the overshoots are computed: certified LPs for every candidate (``"lp"``,
        after :func:`reduce_exact`; the tightest) or interval propagation refined by
        the exact overshoots of the best few (``"fast"``, milliseconds). ``"auto"``
        (default) uses ``"fast"`` when ``n_gen * n_con`` exceeds
        :data:`FAST_ELIMINATION_SIZE`.
    refine : int, optional
        With ``"fast"``: how many of the best-ranked candidates get their exact
        overshoots (default :data:`FAST_ELIMINATION_REFINE`; 0 or 1: none, interval
        propagation alone decides, no LP).
    batch : int
        With ``"fast"``: eliminations per evaluation of the heuristics (default 1: the
        scores are recomputed after each). A larger batch takes the next candidates in
        the same order, each checked again on the current rows, so one factorisation
        and one propagation serve up to ``batch`` eliminated constraints.

    Returns
    -------
    ConstrainedZonotope
        A superset of ``Z`` with at most ``max_constraints`` constraints, or
        with as few as could be reached when every remaining candidate has an
        infinite overshoot, too small a pivot, or would exceed the rounding
        budget (check ``n_con``; :func:`reduce_order` raises in that case).

    Raises
    ------
    EmptySetError
        If ``Z`` is certified empty.

    Notes
    -----
    Cost per eliminated constraint: ``"lp"``, two LPs per candidate factor (on the
    compiled simplex where every bound is finite) plus one factorisation for the
    heuristics; ``"fast"``, ``O(n_c n_g)`` per propagation sweep, the same
    factorisation and ``2 FAST_ELIMINATION_REFINE`` LPs. CORA's ``reduceConstraints`` and ZonoOpt's
    ``constraint_reduction`` follow the same paper with the interval ranges. On a
    3-D polytope with 60 facets (63 generators, 60 constraints),
    ``benchmarks/geometry_ops.py`` records the time per eliminated constraint and
    the support-function widths of both modes against ZonoOpt's.

    Examples
    --------
    A square written as a polytope (four slack factors, two constraints after
    exact reduction) shrinks to a zonotope, which is a superset:

    >>> from setobs.geometry import cz_from_hpolytope
    >>> Z = cz_from_hpolytope([[1.0, 1.0], [-1.0, -1.0], [1.0, -1.0], [-1.0, 1.0]],
    ...                       [1.0, 1.0, 1.0, 1.0])
    >>> R = eliminate_constraints(Z, 0)
    >>> R.n_con, bool(R.contains([0.5, 0.5]))
    (0, True)
    """
    if int(max_constraints) != max_constraints or max_constraints < 0:
        raise InvalidValueError(
            f"max_constraints must be a nonnegative integer, got {max_constraints!r}")
    if method not in ("auto", "fast", "lp"):
        raise InvalidValueError(f"method must be 'auto', 'fast' or 'lp', got {method!r}")
    if Z.n_con <= max_constraints:
        return Z
    if int(batch) != batch or batch < 1:
        raise InvalidValueError(f"batch must be a positive integer, got {batch!r}")
    if refine is not None and (int(refine) != refine or refine < 0):
        raise InvalidValueError(f"refine must be a nonnegative integer, got {refine!r}")
    if method == "fast" or (method == "auto" and Z.n_gen * Z.n_con > FAST_ELIMINATION_SIZE):
        return _eliminate_fast(Z, max_constraints,
                               FAST_ELIMINATION_REFINE if refine is None else int(refine),
                               int(batch))
    Z = reduce_exact(Z)
    budgets = _budgets(Z.G, Z.c, Z.A, Z.b, Z.h, Z.c_err, Z.b_err)
    while Z.n_con > max_constraints:
        cand = np.flatnonzero(np.isfinite(Z.h) & (Z.h > 0) & Z.A.any(axis=0))
        r = relaxed_overshoots(Z, cand)
        Z, eliminated = _drop_best_bound(Z, hausdorff_heuristics(Z, r), budgets)
        if not eliminated:
            break  # no candidate could be eliminated
    return Z


def _drop_best_bound(Z: ConstrainedZonotope, score: NDArray[np.float64],
                     budgets: tuple[float, float]) -> tuple[ConstrainedZonotope, bool]:
    """Drop the bound of the factor with the smallest finite ``score`` that can be
    eliminated with a row (within the rounding ``budgets``) and eliminate it: the
    relaxed set, a superset of ``Z``. Returns ``(set, whether one was eliminated)``."""
    for j in np.argsort(score, kind="stable"):
        if not np.isfinite(score[j]):
            break
        out = _drop_one(Z.G, Z.c, Z.A, Z.b, Z.h, Z.c_err, Z.b_err, int(j), budgets)
        if out is not None:
            G, c, A, b, h, cerr, berr = out
            return trusted_cz(G, c, A, b, h, Z.unbounded_radius, cerr, berr), True
    return Z, False


def _drop_one(G, c, A, b, h, cerr, berr, j: int, budgets: tuple[float, float]):
    """Factor ``j``'s bound dropped and the factor eliminated with one row (the relaxed
    set: a superset), the rows left all zero removed: the new arrays, or ``None`` where
    no row can take it within the rounding ``budgets``."""
    hj = h.copy()
    hj[j] = np.inf
    free = np.zeros(h.size, dtype=bool)
    free[j] = True
    G, c, A, b, h, cerr, berr, steps, _ = _eliminate_free(G, c, A, b, hj, cerr, berr, free,
                                                          budgets, max_steps=1)
    if not steps:
        return None
    A, b, berr = _drop_zero_rows(A, b, berr)
    return G, c, A, b, h, cerr, berr
