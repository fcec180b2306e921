"""Conversion between constrained zonotopes and polytopes, verified by certified LPs.

Vertices and facets come from support LPs on the set itself (a beneath-beyond
construction with the LP as oracle); every facet is confirmed by a certified
support value, so the conversion is exact up to a stated tolerance or it
refuses. Vertex enumeration of the factor polytope with cddlib was tried first
and dropped: ``pycddlib-standalone`` has no exact arithmetic, and its
floating-point enumeration lost up to 59 of 128 vertices of 3-D sets with 120
generators (CORA's randomized intersection test).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._rounding import gamma
from .._validation import as_matrix, as_vector
from ..exceptions import DimensionError, EmptySetError, SolverError, UnboundedSetError
from ..tolerances import VERTEX_RTOL
from .box import box_center_radius
from .results import HRep
from .zonotope import (
    ConstrainedZonotope,
    hull_with_status,
    support_point_factors,
    trusted_cz,
    unit_scaled,
)

__all__ = ["HRep", "cz_from_hpolytope", "polygon_2d", "to_hrep", "vertices"]


#: ``SolverError.status`` of a vertex enumeration stopped at its budget of LPs or
#: facets (the set is more complex than the caller asked for; its accuracy is not
#: in question).
BUDGET_STATUS = "budget"


class _VerifiedHull:
    """Vertices of a bounded constrained zonotope from certified support LPs.

    A beneath-beyond construction in the affine hull with the LP as oracle:
    the affine hull is found by support LPs in directions orthogonal to the span
    found so far (a direction is *flat* when its certified width is below the
    tolerance); then, from a simplex of support points, every facet of the
    hull of the points found is tested by a support LP in its normal: a point
    beyond it is added (queried in a slightly perturbed normal, so that it is a
    vertex of the set, not an interior point of a face), otherwise the facet is
    *confirmed* by the certified support value. The result is verified by
    construction: the set lies within the confirmed half-spaces (certified),
    and the returned points are the solver's support points (vertices up to
    its feasibility tolerance).
    """

    def __init__(self, Z: ConstrainedZonotope, rtol: float = VERTEX_RTOL,
                 max_lps: int = 20_000, max_facets: int | None = None) -> None:
        box, _ = hull_with_status(Z)
        if not box.is_bounded:
            raise UnboundedSetError("vertex enumeration needs a bounded set; this one is "
                                    "unbounded (or not certifiably bounded)")
        n = Z.dim
        self.Z = Z
        self.scale = max(1.0, float(np.abs(np.concatenate([box.lo, box.hi])).max()))
        self.tol = rtol * self.scale
        self.lps = 0
        self.max_lps = max_lps
        self.max_facets = max_facets
        self.rng = np.random.default_rng(0)
        self.vertex_rows: NDArray[np.intp] | None = None  # rows of the points (run())
        # --- affine hull
        _, p0, xi0 = self._query(np.eye(n)[0])
        self.p0 = p0
        pts = [p0]
        self.factors = [xi0]  # the factors of each point found (rows of Y)
        basis = np.zeros((n, 0))
        flat: list[NDArray[np.float64]] = []
        while basis.shape[1] + len(flat) < n:
            Q = _complement(np.hstack([basis, *(f[:, None] for f in flat)]) if flat
                            else basis, n)
            u = Q[:, 0]
            s_plus, q_plus, xi_plus = self._query(u)
            s_minus, q_minus, xi_minus = self._query(-u)
            if s_plus + s_minus <= self.tol:
                flat.append(u)
                continue
            q = q_plus if abs(u @ (q_plus - p0)) >= abs(u @ (q_minus - p0)) else q_minus
            v = q - p0 - basis @ (basis.T @ (q - p0))
            if np.linalg.norm(v) <= 0.1 * self.tol:  # the LP's point did not move: refuse
                raise SolverError("vertex enumeration: the support LPs are inconsistent "
                                  "(width certified but no point found)")
            basis = np.hstack([basis, (v / np.linalg.norm(v))[:, None]])
            pts.append(q)
            self.factors.append(xi_plus if q is q_plus else xi_minus)
        self.basis = basis
        self.flat = np.array(flat).reshape(-1, n)
        self.points = np.array(pts)

    def _query(self, d: NDArray[np.float64]
               ) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
        """Certified support value, the LP's maximiser and its factors (one LP)."""
        self.lps += 1
        if self.lps > self.max_lps:
            raise SolverError(f"vertex enumeration did not converge within {self.max_lps} "
                              "LPs", BUDGET_STATUS)
        return support_point_factors(self.Z, d)

    def run(self) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(vertices, normals, offsets)``: the vertices and the confirmed facets
        ``normals @ x <= offsets`` (certified support values, global coordinates)."""
        d = self.basis.shape[1]
        p0, B = self.p0, self.basis
        if d == 0:
            return self.p0[None, :], np.zeros((0, p0.size)), np.zeros(0)
        if d == 1:
            u = B[:, 0]
            s1, a, _ = self._query(u)
            s2, b, _ = self._query(-u)
            return np.array([b, a]), np.array([u, -u]), np.array([s1, s2])
        from scipy.spatial import ConvexHull, QhullError

        Y = (self.points - p0) @ B  # local coordinates
        confirmed: dict[tuple, tuple[NDArray[np.float64], float]] = {}
        while True:
            try:
                hull = ConvexHull(Y)
            except QhullError as exc:
                raise SolverError(f"vertex enumeration: Qhull failed ({exc})") from None
            if self.max_facets is not None and hull.equations.shape[0] > self.max_facets and \
                    len({self._key(eq) for eq in hull.equations}) > self.max_facets:
                raise SolverError(f"vertex enumeration: more than {self.max_facets} facets",
                                  BUDGET_STATUS)
            added = False
            for eq in hull.equations:
                a_loc, off = eq[:-1], -eq[-1]
                key = self._key(eq)
                if key in confirmed:
                    continue
                g = B @ a_loc
                beta = off + g @ p0
                s, _, _ = self._query(g)
                if s <= beta + self.tol:
                    confirmed[key] = (g, s)
                    continue
                # a point beyond: ask a generic nearby direction for a vertex
                e = self.rng.normal(size=g.size)
                e -= g * (g @ e)
                e -= self.flat.T @ (self.flat @ e) if self.flat.size else 0.0
                e = e / max(np.linalg.norm(e), 1e-300)
                _, q, xi = self._query(g + 1e-6 * e)
                if g @ q <= beta + 0.5 * self.tol:
                    _, q, xi = self._query(g)
                yq = (q - p0) @ B
                if np.min(np.linalg.norm(Y - yq, axis=1)) <= self.tol:
                    raise SolverError("vertex enumeration: a support point beyond a facet "
                                      "repeats a known point (LP accuracy)")
                Y = np.vstack([Y, yq])
                self.factors.append(xi)
                added = True
                break
            if not added:
                break
        self.vertex_rows = hull.vertices
        verts = p0 + Y[hull.vertices] @ B.T
        # the final hull's facets, each confirmed (merged when Qhull split one)
        final = {self._key(eq) for eq in hull.equations}
        keep = [confirmed[k] for k in final]
        normals = np.array([g for g, _ in keep]).reshape(-1, p0.size)
        offsets = np.array([s for _, s in keep])
        return verts, normals, offsets

    def _key(self, eq: NDArray[np.float64]) -> tuple:
        return tuple(np.round(np.concatenate([eq[:-1], [-eq[-1] / self.scale]]), 9))


def verified_facets(Z: ConstrainedZonotope, max_lps: int = 20_000,
                    rtol: float = VERTEX_RTOL, max_facets: int | None = None
                    ) -> tuple[NDArray[np.float64], ...]:
    """``(vertices, normals, offsets, flat)`` of a bounded set by :class:`_VerifiedHull`.

    ``normals @ x <= offsets`` are the confirmed facets (certified offsets);
    ``flat`` (rows) are the directions of certified width below the tolerance.

    Parameters
    ----------
    Z : ConstrainedZonotope
        A bounded set.
    max_lps : int
        LP budget (:class:`~setobs.SolverError` with status :data:`BUDGET_STATUS`
        beyond it).
    rtol : float
        Tolerance, relative to the set's size, within which a facet is confirmed.
    max_facets : int, optional
        Facet budget (the same error) as soon as the hull of the points
        found has more distinct facets (each a Qhull call on more points: in 7
        dimensions 15 000 simplicial facets and 0.1 s per call by 70 points).
    """
    vh = _VerifiedHull(Z, rtol=rtol, max_lps=max_lps, max_facets=max_facets)
    V, H, k = vh.run()
    return V, H, k, vh.flat


def _complement(M: NDArray[np.float64], n: int) -> NDArray[np.float64]:
    """Orthonormal basis (columns) of the orthogonal complement of ``range(M)``."""
    if M.shape[1] == 0:
        return np.eye(n)
    U, _, _ = np.linalg.svd(M, full_matrices=True)
    return U[:, M.shape[1]:]


def vertices(Z: ConstrainedZonotope) -> NDArray[np.float64]:
    """Vertices of a bounded constrained zonotope, one per row (verified).

    Computed by support LPs (a beneath-beyond construction with the LP as
    oracle, see :class:`_VerifiedHull`), polynomial in the number of vertices
    and facets. Exact or refused: every facet of the hull of the returned
    points is confirmed by a certified support value (the set lies within
    ``VERTEX_RTOL`` times its size of that hull), otherwise
    :class:`~setobs.SolverError` is raised. In dimension 1 the vertices are
    the ends of the set, each the float nearest to the exact end where exact rational
    arithmetic verifies the LP's optimum (:func:`_exact_ends_1d`), otherwise the
    certified (outward-rounded) interval-hull ends. In higher dimensions each vertex is
    the nearest floats to an exact point of the set found from the solver's (a box cut
    out by constraints gets its float corners), up to :data:`MAX_EXACT_VERTICES`
    vertices; points, boxes and parallelotopes without constraints in closed form.

    Parameters
    ----------
    Z : ConstrainedZonotope
        A bounded set.

    Raises
    ------
    UnboundedSetError
        If the set is unbounded.
    EmptySetError
        If the set is (certified) empty.
    SolverError
        If the construction cannot be verified.
    """
    V = _parallelotope_vertices(Z)
    if V is not None:
        return V
    Zs, f = unit_scaled(Z)
    if Zs is not Z:  # the same construction at unit magnitude, scaled back exactly
        return vertices(Zs) * f
    if Z.dim == 1:
        box, _ = hull_with_status(Z)
        if not box.is_bounded:
            raise UnboundedSetError("vertex enumeration needs a bounded set; this one is "
                                    "unbounded")
        ends = _exact_ends_1d(Z)
        if ends is None:
            ends = np.array([box.lo[0], box.hi[0]])
        return np.unique(ends).reshape(-1, 1)
    vh = _VerifiedHull(Z)
    V, _, _ = vh.run()
    return _exact_vertices(Z, V, vh)


def _exact_vertices(Z: ConstrainedZonotope, V: NDArray[np.float64], vh: _VerifiedHull
                    ) -> NDArray[np.float64]:
    """``V`` with each vertex replaced by the nearest floats to an exact point of the set
    where one is found: the solver's factors made exactly feasible in rational
    arithmetic (:func:`_exact_feasible`), ``c + G xi`` summed exactly and rounded once,
    kept only within the construction's tolerance of the vertex. A box cut out by
    constraints gets its float corners (they were off by a few 1e-16). With a carried
    rounding bound (``c_err``, ``b_err``) these are the vertices of the set as stored,
    which the construction's tolerance covers as it covers the solver's points. Skipped
    for sets with unbounded factors, larger than :data:`MAX_EXACT_END_SIZE` or with more
    than :data:`MAX_EXACT_VERTICES` vertices (about 1 ms of rational arithmetic per vertex
    at 20 generators and 5 constraints)."""
    if (vh.vertex_rows is None or Z.n_gen * max(Z.n_con, 1) > MAX_EXACT_END_SIZE
            or len(vh.vertex_rows) > MAX_EXACT_VERTICES or not np.isfinite(Z.h).all()):
        return V
    from fractions import Fraction

    A, b, h = _rational_factor_data(Z)
    G = [[Fraction(float(v)) for v in row] for row in Z.G]
    c = [Fraction(float(v)) for v in Z.c]
    out = V.copy()
    for k, row in enumerate(vh.vertex_rows):
        xi = _exact_feasible(A, b, h, vh.factors[row])
        if xi is None:
            continue
        x = np.array([float(ci + sum((g * v for g, v in zip(Gi, xi, strict=True)), Fraction(0)))
                      for ci, Gi in zip(c, G, strict=True)])
        if np.abs(x - V[k]).max() <= vh.tol:
            out[k] = x
    return out


#: Largest ``n_gen * max(n_con, 1)`` of a set whose vertices :func:`vertices` makes exact
#: in rational arithmetic (1-D: verifies its ends; above it, the certified outward ends
#: are returned, and in higher dimensions the verified construction's points).
MAX_EXACT_END_SIZE = 400

#: Most vertices a set may have for :func:`vertices` to make each one exact (the floats
#: nearest to an exact point of the set); above it the verified construction's points
#: are returned.
MAX_EXACT_VERTICES = 64


def _exact_ends_1d(Z: ConstrainedZonotope) -> NDArray[np.float64] | None:
    """The ends ``min`` and ``max`` of a bounded 1-D set ``{c + g xi : A xi = b, |xi| <= h}``
    as the floats nearest to the exact ends, or ``None`` where this cannot be verified.

    For each end, the solver's optimal point gives an exactly feasible point ``xi`` (its
    factors at a bound are put at the bound, the others solved from ``A xi = b`` in
    rational arithmetic; a face's extra freedom keeps the solver's values) and a
    multiplier ``y`` (``a_j^T y = w_j`` for the factors not at a bound and those whose
    reduced cost is zero at the dual LP's float optimum, solved in rational arithmetic).
    Then ``w^T xi`` is at least the minimum and the Lagrangian bound
    ``b^T y - sum_j h_j |w_j - a_j^T y|`` at most (weak duality): where the two are
    equal, both are the exact minimum, and ``c + g^T xi`` rounded once is the nearest
    float to the end. ``None`` when a rounding bound is carried (``c_err``, ``b_err``:
    the set is then not exactly known), the set is larger than
    :data:`MAX_EXACT_END_SIZE`, or the two values differ.
    """
    if (np.any(Z.c_err != 0.0) or np.any(Z.b_err != 0.0) or not np.isfinite(Z.h).all()
            or Z.n_gen * max(Z.n_con, 1) > MAX_EXACT_END_SIZE):
        return None
    from fractions import Fraction

    from .zonotope import factor_polytope

    A, b, h = _rational_factor_data(Z)
    c = Fraction(float(Z.c[0]))
    fp = factor_polytope(Z)
    ends = []
    for sign in (1, -1):  # min g xi, then min -g xi (an int sign: Fraction * float is a float)
        w = sign * Z.G[0]
        res = fp.minimize(w)
        if res.status != "optimal" or res.point is None:
            return None
        value = _exact_lp_minimum(Z, A, b, h, w, np.asarray(res.point, dtype=np.float64))
        if value is None:
            return None
        ends.append(float(c + sign * value))  # int / int: correctly rounded
    return np.array([ends[0], ends[1]])


def _rational_factor_data(Z: ConstrainedZonotope) -> tuple[list, list, list]:
    """``A``, ``b`` and ``h`` of a set with finite factor bounds, as exact rationals."""
    from fractions import Fraction

    return ([[Fraction(float(v)) for v in row] for row in Z.A],
            [Fraction(float(v)) for v in Z.b], [Fraction(float(v)) for v in Z.h])


def _exact_lp_minimum(Z: ConstrainedZonotope, A, b, h, w_float, xi_hat) -> object | None:
    """The exact ``min w^T xi`` over ``{A xi = b, |xi| <= h}`` verified from the solver's
    minimiser ``xi_hat``, or ``None`` (see :func:`_exact_ends_1d`); ``A``, ``b``, ``h``:
    ``Z``'s data as rationals, ``w_float``: the objective."""
    from fractions import Fraction

    n_g, m = len(h), len(b)
    w = [Fraction(float(v)) for v in w_float]
    xi = _exact_feasible(A, b, h, xi_hat)
    if xi is None:
        return None
    free = [j for j in range(n_g) if abs(xi[j]) != h[j]]
    primal = sum((w[j] * xi[j] for j in range(n_g)), Fraction(0))
    tight = set(free)
    y_hat = np.zeros(m)
    if m:  # the dual LP in floats: its zero reduced costs say which equations y solves
        from scipy.optimize import linprog

        Af, wf = Z.A, w_float
        eye = np.eye(n_g)
        dual_lp = linprog(np.concatenate([-Z.b, Z.h]),
                          A_ub=np.block([[-Af.T, -eye], [Af.T, -eye]]),
                          b_ub=np.concatenate([-wf, wf]),
                          bounds=[(None, None)] * m + [(0, None)] * n_g, method="highs")
        if dual_lp.status == 0:
            y_hat = dual_lp.x[:m]
            reduced = wf - Af.T @ y_hat
            tight |= {j for j in range(n_g) if abs(reduced[j]) <= 1e-9 * (1.0 + abs(wf[j]))}
    for T in (sorted(tight), free):
        y = _rational_solve([[A[i][j] for i in range(m)] for j in T], [w[j] for j in T],
                            [Fraction(float(v)) for v in y_hat])
        if y is None:
            continue
        dual = sum((b[i] * y[i] for i in range(m)), Fraction(0)) - sum(
            (h[j] * abs(w[j] - sum((A[i][j] * y[i] for i in range(m)), Fraction(0)))
             for j in range(n_g)), Fraction(0))
        if dual == primal:
            return primal
    return None


def _exact_feasible(A, b, h, xi_hat) -> list | None:
    """A point of ``{A xi = b, |xi| <= h}`` (rationals) near the solver's ``xi_hat``: its
    entries within ``1e-9`` (relative) of a bound put at the bound, the others solved
    from ``A xi = b`` (those without a pivot keep the solver's values); ``None`` if
    that system is inconsistent or its solution leaves the bounds."""
    from fractions import Fraction

    n_g = len(h)
    xi: list = [None] * n_g
    free = []
    for j in range(n_g):
        x = float(xi_hat[j])
        hj = float(h[j])
        if hj == 0.0 or abs(x) >= hj * (1.0 - 1e-9):
            xi[j] = h[j] if x > 0 else -h[j]
        else:
            free.append(j)
    rhs = [b[i] - sum((A[i][j] * xi[j] for j in range(n_g) if xi[j] is not None),
                      Fraction(0)) for i in range(len(b))]
    sol = _rational_solve([[A[i][j] for j in free] for i in range(len(b))], rhs,
                          [Fraction(float(xi_hat[j])) for j in free])
    if sol is None:
        return None
    for j, v in zip(free, sol, strict=True):
        if abs(v) > h[j]:
            return None
        xi[j] = v
    return xi


def _rational_solve(M: list, r: list, default: list) -> list | None:
    """A solution of ``M x = r`` in rationals (Gauss-Jordan), the unknowns without a pivot
    at ``default``; ``None`` if the system is inconsistent."""
    from fractions import Fraction

    rows = [[*row, ri] for row, ri in zip(M, r, strict=True)]
    k = len(default)
    pivots: list[tuple[int, int]] = []
    i0 = 0
    for col in range(k):
        p = next((i for i in range(i0, len(rows)) if rows[i][col] != 0), None)
        if p is None:
            continue
        rows[i0], rows[p] = rows[p], rows[i0]
        piv = rows[i0][col]
        rows[i0] = [v / piv for v in rows[i0]]
        for i in range(len(rows)):
            if i != i0 and rows[i][col] != 0:
                f = rows[i][col]
                rows[i] = [a - f * bb for a, bb in zip(rows[i], rows[i0], strict=True)]
        pivots.append((i0, col))
        i0 += 1
    if any(row[k] != 0 for row in rows[i0:]):
        return None
    x = list(default)
    pivot_cols = {col for _, col in pivots}
    for i, col in pivots:
        x[col] = rows[i][k] - sum((rows[i][j] * x[j] for j in range(k)
                                   if j not in pivot_cols and rows[i][j] != 0), Fraction(0))
    return x


#: Largest number of independent generators whose 2^m sign combinations
#: :func:`vertices` enumerates in closed form.
MAX_CLOSED_FORM_GENERATORS = 10


def _parallelotope_vertices(Z: ConstrainedZonotope) -> NDArray[np.float64] | None:
    """The vertices of a set whose generators are linearly independent and that has no
    constraints (points, boxes, segments, parallelotopes, also lower-dimensional ones),
    in closed form, or ``None``.

    Such a set is ``{c + G xi : |xi| <= h}`` with ``G`` of full column rank (the
    columns with ``h_j > 0``), so its vertices are exactly the ``2^m`` points ``c +
    sum_j s_j h_j g_j``, ``s`` in ``{-1, 1}^m`` (distinct by independence). Each is
    summed in exact rational arithmetic and rounded once to the nearest float: a
    vertex that is a float is returned exactly (a box's corners, the point ``{4}``).
    Not used when the centre carries a rounding error (``c_err``), the set is
    unbounded, or the columns are not clearly independent (smallest singular value
    below ``1e-8`` of the largest; the verified construction decides those).
    """
    if Z.n_con or not np.isfinite(Z.h).all() or np.any(Z.c_err != 0.0):
        return None
    live = (Z.h > 0) & np.any(Z.G != 0.0, axis=0)
    G, h = Z.G[:, live], Z.h[live]
    m = G.shape[1]
    if m > min(Z.dim, MAX_CLOSED_FORM_GENERATORS):
        return None
    if m:
        sv = np.linalg.svd(G, compute_uv=False)
        if not sv[-1] > 1e-8 * sv[0]:
            return None
    from fractions import Fraction
    from itertools import product

    c = [Fraction(float(v)) for v in Z.c]
    # the half-edges h_j g_j, exact
    E = [[Fraction(float(G[i, j])) * Fraction(float(h[j])) for i in range(Z.dim)]
         for j in range(m)]
    out = np.empty((2 ** m, Z.dim))
    for r, signs in enumerate(product((-1, 1), repeat=m)):
        for i in range(Z.dim):
            out[r, i] = float(c[i] + sum((s * E[j][i] for j, s in enumerate(signs)),
                                         Fraction(0)))
    return out


def to_hrep(Z: ConstrainedZonotope) -> HRep:
    """H-representation (facets and affine hull) of a bounded constrained zonotope.

    The facets are those confirmed by :func:`vertices`' construction, with the
    certified support values as offsets, so ``{x : H x <= k}`` contains the set
    (outer by at most ``VERTEX_RTOL`` times its size). ``E x = f`` is the affine
    hull: the directions in which the set's certified width is below that
    tolerance (``f`` from a point of the set).

    Parameters
    ----------
    Z : ConstrainedZonotope
        A bounded set.
    """
    Zs, f = unit_scaled(Z)
    if Zs is not Z:  # at unit magnitude, scaled back exactly
        hr = to_hrep(Zs)
        return HRep(hr.H, hr.k * f, hr.E, hr.f * f)
    n = Z.dim
    if n == 1:
        V = vertices(Z)
        lo, hi = float(V.min()), float(V.max())
        if hi - lo <= VERTEX_RTOL * max(1.0, abs(lo), abs(hi)):
            return HRep(np.zeros((0, 1)), np.zeros(0), np.ones((1, 1)), np.array([lo]))
        return HRep(np.array([[1.0], [-1.0]]), np.array([hi, -lo]), np.zeros((0, 1)),
                    np.zeros(0))
    vh = _VerifiedHull(Z)
    _, H, k = vh.run()
    E = vh.flat
    f = E @ vh.p0
    return HRep(H, k, E, f)


def hpolytope_in_box(H: NDArray[np.float64], k: NDArray[np.float64], lo: NDArray[np.float64],
                     hi: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
    """``{x in [lo, hi] : H x <= k}`` as ``x = c + xi_x``, ``H xi_x + xi_s = b``.

    Scott et al. (2016), Theorem 1, unscaled: ``|xi_x| <= dx`` (the box) and the
    slack ``sigma = k - H x`` in ``[0, dsig]`` written as ``dsig/2 + xi_s``,
    ``|xi_s| <= dsig/2``. Returns ``(c, dx, dsig, b, b_err)``: ``dsig`` is
    rounded up (it covers ``k - min_box H x``), ``b = k - H c - dsig/2`` and
    ``b_err`` bounds its rounding.

    Parameters
    ----------
    H, k : ndarray
        Half-spaces ``H x <= k``.
    lo, hi : ndarray
        A box containing the polytope.
    """
    n = H.shape[1]
    c, dx = box_center_radius(lo, hi)
    # sigma = k - H x ranges over [0, dsig] on the box: dsig = k - min_box H x.
    hmin = H @ c - np.abs(H) @ dx
    dsig = np.maximum(k - hmin, 0.0)
    dsig = np.nextafter(dsig * (1 + 4 * np.finfo(float).eps * (n + 2)), np.inf)
    b = k - H @ c - dsig / 2.0
    g = gamma(n + 3) * (1.0 + gamma(n + 4))
    berr = g * (np.abs(k) + np.abs(H) @ np.abs(c) + dsig / 2.0)
    return c, dx, dsig, b, berr


def _scott_cz(H, k, lo, hi) -> ConstrainedZonotope:
    """Scott et al. (2016), Theorem 1: ``{x in box : H x <= k}`` as a constrained zonotope."""
    n = H.shape[1]
    m = H.shape[0]
    c, dx, dsig, b, berr = hpolytope_in_box(H, k, lo, hi)
    G = np.hstack([np.diag(dx), np.zeros((n, m))])
    A = np.hstack([H * dx, np.diag(dsig / 2.0)])
    return trusted_cz(G, c, A, b, np.ones(n + m), berr=berr)


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

    Parameters
    ----------
    H : array_like, shape (m, n)
        Half-space normals.
    k : array_like, shape (m,)
        Offsets.

    Raises
    ------
    EmptySetError
        If the polytope is empty.
    UnboundedSetError
        If it is unbounded.
    """
    from scipy.optimize import linprog

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


def polygon_2d(Z: ConstrainedZonotope) -> NDArray[np.float64]:
    """Vertices (counter-clockwise) of a bounded 2-D constrained zonotope.

    The verified vertices of :func:`setobs.geometry.polytope.vertices` (support
    LPs, every edge confirmed by a certified support value), in angular order.

    Parameters
    ----------
    Z : ConstrainedZonotope
        A bounded 2-D set.

    Raises
    ------
    DimensionError
        If ``Z`` is not 2-D.
    UnboundedSetError
        If ``Z`` is unbounded.
    """
    if Z.dim != 2:
        raise DimensionError(f"polygon_2d needs a 2-D set, got dimension {Z.dim}")
    try:
        P = vertices(Z)
    except UnboundedSetError:
        raise UnboundedSetError("cannot draw an unbounded set; intersect it with a box "
                                "first") from None
    if len(P) <= 2:
        return P
    ctr = P.mean(axis=0)
    return P[np.argsort(np.arctan2(P[:, 1] - ctr[1], P[:, 0] - ctr[0]))]
