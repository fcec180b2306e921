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
* :func:`reduce_order` — outer generator-order reduction by Girard's method on
  the lifted zonotope ``{[G; A] xi + [c; -b]}`` (Scott et al. 2016, Sec. 4.3):
  the smallest bounded generators are replaced by their interval hull.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import qr

from ..exceptions import DimensionError
from ..tolerances import ZERO_TOL
from .lp import _gamma
from .zonotope import ConstrainedZonotope

__all__ = ["reduce_order", "remove_redundancy", "rescale"]


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
    return ConstrainedZonotope._trusted(G, c, A, b, h, Z.radius, Z.c_err, berr)


def rescale(Z: ConstrainedZonotope) -> ConstrainedZonotope:
    """Shrink and recentre factor intervals to their certified hull (Scott et al. 2016, Sec. 4).

    For each factor ``j``, certified bounds ``[l_j, u_j]`` of ``xi_j`` over
    ``{xi : A xi = b, |xi| <= h}`` are computed (``2 n_g`` LPs); with
    ``m = (l + u)/2``, ``r = (u - l)/2`` (rounded up), the set is rewritten as
    ``{G eta + (c + G m) : A eta = b - A m, |eta| <= r}``. Factors with
    ``r_j = 0`` are removed. Unbounded factors with an infinite bound are kept.

    Raises
    ------
    EmptySetError
        If ``Z`` is certified empty.
    """
    n_g = Z.n_gen
    if n_g == 0:
        return Z
    fp = Z._lp()
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
    finite = np.isfinite(lo) & np.isfinite(hi)
    m = np.where(finite, 0.5 * np.where(finite, lo, 0.0) + 0.5 * np.where(finite, hi, 0.0), 0.0)
    r = np.where(finite, np.maximum(np.where(finite, hi, 0.0) - m, m - np.where(finite, lo, 0.0)),
                 Z.h)
    r = np.where(finite & (r > 0), np.nextafter(r, np.inf), r)
    r = np.maximum(r, 0.0)
    c = Z.c + Z.G @ m
    b = Z.b - Z.A @ m
    # rounding of the recentring (Higham's bounds), on top of what Z carried
    g = _gamma(n_g + 2) * (1.0 + _gamma(n_g + 3))
    cerr = Z.c_err + g * (np.abs(Z.c) + np.abs(Z.G) @ np.abs(m))
    berr = Z.b_err + g * (np.abs(Z.b) + np.abs(Z.A) @ np.abs(m))
    keep = r > 0
    return ConstrainedZonotope._trusted(Z.G[:, keep], c, Z.A[:, keep], b, r[keep], Z.radius,
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
    DimensionError
        If ``max_generators`` is below ``n + n_c + (number of unbounded factors)``,
        the fewest a reduction of this kind can reach in general.
    """
    if int(max_generators) != max_generators or max_generators < 0:
        raise DimensionError(f"max_generators must be a nonnegative integer, got {max_generators}")
    if Z.n_gen <= max_generators:
        return Z
    n, n_c = Z.dim, Z.n_con
    unb = np.isinf(Z.h)
    n_unb = int(unb.sum())
    floor = n + n_c + n_unb
    if max_generators < floor:
        raise DimensionError(
            f"max_generators must be at least n + n_c + n_unbounded = {floor}, got {max_generators}"
        )
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
    return ConstrainedZonotope._trusted(G, Z.c, A, Z.b, h, Z.radius, Z.c_err, Z.b_err)

