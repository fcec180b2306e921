"""Exact conversion between constrained zonotopes and polytopes (pycddlib).

pycddlib (cddlib by K. Fukuda) does the vertex enumeration and facet
computation; it runs in floating point here (``pycddlib-standalone`` ships
without GMP), with cdd's own redundancy removal.
"""

from __future__ import annotations

from dataclasses import dataclass

import cdd
import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog
from scipy.spatial import ConvexHull, QhullError

from .._validation import as_matrix, as_vector
from ..exceptions import EmptySetError, SolverError, UnboundedSetError
from .lp import _gamma
from .zonotope import ConstrainedZonotope

__all__ = ["HRep", "cz_from_hpolytope", "to_hrep", "vertices"]


@dataclass(frozen=True)
class HRep:
    """H-representation ``{x : H x <= k, E x = f}``.

    Attributes
    ----------
    H, k : ndarray
        Inequalities ``H x <= k`` (facets).
    E, f : ndarray
        Equalities ``E x = f`` (the affine hull when the set is flat).
    """

    H: NDArray[np.float64]
    k: NDArray[np.float64]
    E: NDArray[np.float64]
    f: NDArray[np.float64]

    def contains(self, x: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``x`` satisfies all inequalities and equalities within ``tol``."""
        xv = np.asarray(x, dtype=float)
        return bool((self.H @ xv <= self.k + tol).all() and
                    (np.abs(self.E @ xv - self.f) <= tol).all())


def _bounded_factors(Z: ConstrainedZonotope) -> ConstrainedZonotope:
    if not Z.has_unbounded_factors:
        return Z
    Zr = Z.rescale()
    if Zr.has_unbounded_factors:
        raise UnboundedSetError("vertex enumeration needs a bounded set; this one is unbounded "
                                "(or has factors that are not certifiably bounded)")
    return Zr


def _factor_vertices(Z: ConstrainedZonotope) -> NDArray[np.float64]:
    """Vertices of ``{xi : A xi = b, |xi| <= h}`` by cdd."""
    n_g = Z.n_gen
    if n_g == 0:
        if Z.n_con and np.abs(Z.b).max() > 0:
            raise EmptySetError("the set is empty")
        return np.zeros((1, 0))
    eye = np.eye(n_g)
    rows = [np.hstack([Z.h[:, None], -eye]), np.hstack([Z.h[:, None], eye])]
    if Z.n_con:
        rows.append(np.hstack([Z.b[:, None], -Z.A]))
    M = np.vstack(rows)
    mat = cdd.matrix_from_array(M.tolist(), rep_type=cdd.RepType.INEQUALITY)
    if Z.n_con:
        mat.lin_set = set(range(2 * n_g, 2 * n_g + Z.n_con))
    poly = cdd.polyhedron_from_matrix(mat)
    gen = np.array(cdd.copy_generators(poly).array, dtype=float).reshape(-1, n_g + 1)
    if gen.shape[0] == 0:
        raise EmptySetError("the set is empty")
    pts = gen[gen[:, 0] == 1.0, 1:]
    if pts.shape[0] == 0:
        raise EmptySetError("the set is empty")
    return pts


def _extreme_points(P: NDArray[np.float64]) -> NDArray[np.float64]:
    """Remove non-extreme and duplicate points.

    Full-dimensional point sets go through Qhull: cdd's floating-point
    redundancy removal (pycddlib-standalone has no exact arithmetic) was
    measured to drop a true vertex of a 2-D set that sticks out 2.3e-4 beyond
    the chord of its neighbours (``tests/geometry/test_polytope_and_plot.py``).
    Flat point sets, which Qhull rejects, use cdd's canonicalisation.
    """
    P = np.unique(np.round(P, 12), axis=0) if P.shape[0] > 1 else P
    if P.shape[0] <= 1:
        return P
    if P.shape[1] == 1:
        return np.array([P.min(axis=0), P.max(axis=0)])
    if P.shape[0] > P.shape[1] and np.linalg.matrix_rank(P[1:] - P[0]) == P.shape[1]:
        try:
            return P[np.sort(ConvexHull(P).vertices)]
        except QhullError:
            pass
    mat = cdd.matrix_from_array(np.hstack([np.ones((P.shape[0], 1)), P]).tolist(),
                                rep_type=cdd.RepType.GENERATOR)
    cdd.matrix_canonicalize(mat)
    out = np.array(mat.array, dtype=float).reshape(-1, P.shape[1] + 1)
    return out[:, 1:]


def vertices(Z: ConstrainedZonotope) -> NDArray[np.float64]:
    """Vertices of a bounded constrained zonotope, one per row.

    In dimension 1 the vertices are the interval-hull ends; in dimension 2 they
    come from the LP-based polygon construction
    (:func:`setobs.geometry.plotting.polygon_2d`, polynomial in the number of
    factors). Otherwise the vertices of the factor polytope are enumerated
    with cdd, mapped through ``xi -> G xi + c`` and reduced to the extreme
    points: exponential in the number of factors in the worst case.

    Raises
    ------
    UnboundedSetError
        If the set is unbounded.
    EmptySetError
        If the set is empty.
    """
    if Z.dim <= 2 and Z.n_gen > 8:
        box = Z.interval_hull()
        if not box.is_bounded:
            raise UnboundedSetError("vertex enumeration needs a bounded set; this one is "
                                    "unbounded")
        if Z.dim == 1:
            return np.unique(np.array([[box.lo[0]], [box.hi[0]]]), axis=0)
        from .plotting import polygon_2d

        return polygon_2d(Z)
    Zb = _bounded_factors(Z)
    xi = _factor_vertices(Zb)
    return _extreme_points(xi @ Zb.G.T + Zb.c)


def to_hrep(Z: ConstrainedZonotope) -> HRep:
    """H-representation (facets and affine hull) of a bounded constrained zonotope."""
    V = vertices(Z)
    n = Z.dim
    mat = cdd.matrix_from_array(np.hstack([np.ones((V.shape[0], 1)), V]).tolist(),
                                rep_type=cdd.RepType.GENERATOR)
    poly = cdd.polyhedron_from_matrix(mat)
    ineq = cdd.copy_inequalities(poly)
    arr = np.array(ineq.array, dtype=float).reshape(-1, n + 1)
    lin = sorted(ineq.lin_set)
    is_lin = np.zeros(arr.shape[0], dtype=bool)
    is_lin[lin] = True
    # cdd rows are [k, -H] meaning k - H x >= 0 (and = 0 for linearity rows).
    H = -arr[~is_lin, 1:]
    k = arr[~is_lin, 0]
    E = -arr[is_lin, 1:]
    f = arr[is_lin, 0]
    return HRep(H, k, E, f)


def _scott_cz(H, k, lo, hi) -> ConstrainedZonotope:
    """Scott et al. (2016), Theorem 1: ``{x in box : H x <= k}`` as a constrained zonotope."""
    n = H.shape[1]
    m = H.shape[0]
    c = 0.5 * lo + 0.5 * hi
    dx = np.nextafter(np.maximum(hi - c, c - lo), np.inf)
    # sigma = k - H x ranges over [0, dsig] on the box: dsig = k - min_box H x.
    hmin = H @ c - np.abs(H) @ dx
    dsig = np.maximum(k - hmin, 0.0)
    dsig = np.nextafter(dsig * (1 + 4 * np.finfo(float).eps * (n + 2)), np.inf)
    G = np.hstack([np.diag(dx), np.zeros((n, m))])
    A = np.hstack([H * dx, np.diag(dsig / 2.0)])
    b = k - H @ c - dsig / 2.0
    g = _gamma(n + 3) * (1.0 + _gamma(n + 4))
    berr = g * (np.abs(k) + np.abs(H) @ np.abs(c) + dsig / 2.0)
    return ConstrainedZonotope._trusted(G, c, A, b, np.ones(n + m), berr=berr)


def cz_from_hpolytope(H: ArrayLike, k: ArrayLike) -> ConstrainedZonotope:
    """Constrained zonotope equal to the bounded polytope ``{x : H x <= k}``.

    Scott et al. (2016), Theorem 1: with a box ``[lo, hi]`` containing the
    polytope, ``x = c + diag(dx) xi_x`` and slack ``sigma = k - H x`` in
    ``[0, dsig]`` written as ``dsig/2 (1 + xi_s)``.

    The box is certified: an approximate hull from HiGHS is inflated to a box
    ``B``; the constrained zonotope of ``P ∩ B`` is built and its certified
    interval hull computed. If that hull lies strictly inside ``B`` then, by
    convexity, ``P ⊆ B`` and the representation is exact; otherwise ``B`` is
    enlarged and the check repeated.

    Raises
    ------
    EmptySetError
        If the polytope is empty.
    UnboundedSetError
        If it is unbounded.
    """
    H_a = as_matrix("H", H)
    k_a = as_vector("k", k, size=H_a.shape[0])
    n = H_a.shape[1]
    lo = np.empty(n)
    hi = np.empty(n)
    for i in range(n):
        for sgn in (1.0, -1.0):
            cost = np.zeros(n)
            cost[i] = sgn
            res = linprog(cost, A_ub=H_a, b_ub=k_a, bounds=[(None, None)] * n, method="highs")
            if res.status == 2:
                raise EmptySetError("the H-polytope is empty")
            if res.status == 3:
                raise UnboundedSetError(f"the H-polytope is unbounded along coordinate {i}")
            if res.status != 0:
                raise SolverError(f"linprog failed: {res.message}", status=str(res.status))
            if sgn > 0:
                lo[i] = res.fun
            else:
                hi[i] = -res.fun
    width = np.maximum(hi - lo, 0.0)
    scale = max(float(np.abs(np.concatenate([lo, hi])).max()), 1.0)
    pad = 0.01 * width + 1e-6 * scale
    for _ in range(8):
        B_lo, B_hi = lo - pad, hi + pad
        Z = _scott_cz(H_a, k_a, B_lo, B_hi)
        box = Z.interval_hull()
        if (box.lo > B_lo).all() and (box.hi < B_hi).all():
            return _scott_cz(H_a, k_a, np.maximum(box.lo, B_lo), np.minimum(box.hi, B_hi))
        pad = pad * 10.0
    raise SolverError("could not certify a bounding box of the H-polytope")

