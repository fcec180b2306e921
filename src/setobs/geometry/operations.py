"""More set operations on constrained zonotopes: cuts, hulls, differences, uncertain maps.

Each function states whether its result is **exact** (the same set, up to the
``O(eps)`` rounding of matrix products that every operation of the library
has, with the rounding of centres and right-hand sides tracked in
:attr:`~setobs.ConstrainedZonotope.c_err` and
:attr:`~setobs.ConstrainedZonotope.b_err`), an **outer** approximation (a
superset) or an **inner** approximation (a subset). Where an LP decides (a
support value that bounds a slack, a redundancy test), its certified bound is
used on the outward side, so an exact operation never loses a point.

=========================================  ========  =========================================
function                                   result    reference
=========================================  ========  =========================================
:func:`empty_set`                          exact     (CORA ``conZonotope.empty``)
:func:`intersect_halfspace`                exact     Raghuraman and Koeln (2022), Sec. 3
:func:`intersect_strip`                    exact     Scott et al. (2016), eq. (13)
:func:`intersect_polytope`                 exact     Raghuraman and Koeln (2022), Sec. 3
:func:`convex_hull`                        exact     Raghuraman and Koeln (2022), Theorem 5
:func:`from_vertices`                      exact     V-representation as a constrained zonotope
:func:`pontryagin_difference` ``exact``    exact     intersection over the vertices of ``W``
:func:`pontryagin_difference` ``inner``    inner     generator matching (Vinod et al. 2025)
:func:`interval_matrix_map`                outer     Althoff (2010), Theorem 3.3, on the hull
:func:`quad_map`                           outer     Althoff (2013), quadratic map; CORA quadMap
=========================================  ========  =========================================
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._rounding import gamma, round_down, round_up
from .._validation import as_matrix, as_vector, check_real_scalar
from ..exceptions import (
    ArgumentError,
    DimensionError,
    EmptySetError,
    InvalidValueError,
    SolverError,
    UnboundedSetError,
)
from ..tolerances import PONTRYAGIN_MATCH_RTOL
from .box import Box, box_center_radius
from .zonotope import (
    ConstrainedZonotope,
    hull_with_status,
    support_unwarned,
    trusted_cz,
)

__all__ = [
    "convex_hull",
    "empty_set",
    "from_vertices",
    "intersect_halfspace",
    "intersect_polytope",
    "intersect_strip",
    "interval_matrix_map",
    "pontryagin_difference",
    "quad_map",
]


def empty_set(n: int) -> ConstrainedZonotope:
    """The empty set of ``R^n`` as a constrained zonotope.

    Represented by one factor ``|xi| <= 1`` with the constraint ``xi = 2``: every
    operation of the library accepts it, :meth:`~ConstrainedZonotope.is_empty`
    certifies it empty (the normalised violation is at least 1/2), and the LP
    queries raise :class:`~setobs.EmptySetError`.

    Parameters
    ----------
    n : int
        Dimension.

    Examples
    --------
    >>> E = empty_set(3)
    >>> E.dim, bool(E.is_empty())
    (3, True)
    """
    if int(n) != n or n < 1:
        raise InvalidValueError(f"n must be a positive integer, got {n!r}")
    n = int(n)
    return trusted_cz(np.zeros((n, 1)), np.zeros(n), np.ones((1, 1)), np.array([2.0]),
                      np.ones(1))


def _lower_support(Z: ConstrainedZonotope, a: NDArray[np.float64]) -> float:
    """Certified lower bound of ``min_{z in Z} a^T z`` (``-inf`` if none is certified).

    The LP bound is combined with the bound of the factor box, which needs no
    LP, so that a failed LP on a set with bounded factors still gives a finite
    certified value.
    """
    lp = -support_unwarned(Z, -a)
    if np.isfinite(Z.h).all():
        with np.errstate(over="ignore", invalid="ignore"):  # (beyond double: no bound)
            w = Z.G.T @ a
            k = Z.n_gen + Z.dim + 2
            box = float(a @ Z.c) - float(np.abs(w) @ Z.h)
            err = gamma(k) * (float(np.abs(a) @ np.abs(Z.c)) + 2.0 * float(
                (np.abs(Z.G).T @ np.abs(a)) @ Z.h)) + float(np.abs(a) @ Z.c_err)
            low = float(round_down(box - err * (1.0 + gamma(k))))
        if np.isfinite(low):
            lp = max(lp, low)
    return lp


def intersect_strip(Z: ConstrainedZonotope, C: ArrayLike, y: ArrayLike,
                    radius: ArrayLike) -> ConstrainedZonotope:
    """``{z in Z : |C z - y| <= radius}`` (elementwise): exact.

    The strip is the generalised intersection of ``Z`` with the box
    ``[y - radius, y + radius]`` under ``C`` (Scott et al. 2016, eq. (13)); one
    factor and one constraint per row. The box ends are rounded outward.
    (CORA's ``intersectStrip`` returns an outer approximation of the same set,
    for several strips at once; this one is exact.)

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    C : array_like, shape (m, n)
        Strip normals (one per row).
    y : array_like, shape (m,)
        Strip centres.
    radius : array_like, shape (m,) or float
        Strip half-widths, nonnegative and finite.

    Examples
    --------
    >>> Z = ConstrainedZonotope.from_box([-1.0, -1.0], [1.0, 1.0])
    >>> S = intersect_strip(Z, [[1.0, 1.0]], [0.0], 0.5)
    >>> bool(S.contains([0.4, -0.1])), bool(S.contains([0.9, 0.9]))
    (True, False)
    """
    C_a = as_matrix("C", C, cols=Z.dim)
    m = C_a.shape[0]
    y_a = as_vector("y", y, size=m)
    r = np.broadcast_to(np.asarray(radius, dtype=np.float64), (m,)).copy() \
        if np.ndim(radius) == 0 else as_vector("radius", radius, size=m)
    if not np.isfinite(r).all() or (r < 0).any():
        raise InvalidValueError(f"radius must be finite and nonnegative, got {r}")
    lo = np.nextafter(y_a - r, -np.inf)
    hi = np.nextafter(y_a + r, np.inf)
    return Z.intersect(ConstrainedZonotope.from_box(lo, hi), C_a)


def intersect_halfspace(Z: ConstrainedZonotope, a: ArrayLike, beta: float
                        ) -> ConstrainedZonotope:
    """``{z in Z : a^T z <= beta}``: exact.

    With ``sigma`` a certified lower bound of ``min_{z in Z} a^T z`` (one LP),
    the half-space cut equals the generalised intersection of ``Z`` with the
    interval ``[sigma, beta]`` under ``a^T``: the lower end cuts nothing, so the
    result is exact (the slack factor of Raghuraman and Koeln 2022, Sec. 3,
    bounded by a certified support value). If ``Z`` lies in the half-space
    (certified ``max a^T z <= beta``) it is returned unchanged; if it misses it
    (certified ``min a^T z > beta``), the result is :func:`empty_set`.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    a : array_like, shape (n,)
        Normal.
    beta : float
        Offset.

    Raises
    ------
    UnboundedSetError
        If ``a^T z`` is not bounded below on ``Z``: the cut of a set with a
        lineality direction not orthogonal to ``a`` is a half-line-like set,
        which an extended constrained zonotope cannot represent.

    Examples
    --------
    CORA's ``test_conZonotope_and`` (second case): the vertices of the cut are
    ``(1, 0), (3, 1), (3, 2), (1, 3)``.

    >>> Z = ConstrainedZonotope([[3.0, 0.0, 1.0], [0.0, 2.0, 1.0]], [0.0, 0.0],
    ...                         A=[[1.0, 0.0, 1.0]], b=[1.0])
    >>> V = intersect_halfspace(Z, [1.0, -2.0], 1.0).vertices()
    >>> sorted(map(tuple, (V.round(6) + 0.0).tolist()))   # + 0.0: no -0.0 from rounding
    [(1.0, 0.0), (1.0, 3.0), (3.0, 1.0), (3.0, 2.0)]
    """
    av = as_vector("a", a, size=Z.dim)
    b = check_real_scalar("beta", beta)
    return intersect_polytope(Z, av[None, :], [b])


def intersect_polytope(Z: ConstrainedZonotope, H: ArrayLike, k: ArrayLike,
                       E: ArrayLike | None = None, f: ArrayLike | None = None
                       ) -> ConstrainedZonotope:
    """``{z in Z : H z <= k, E z = f}``: exact.

    The equalities are intersected first (:meth:`~ConstrainedZonotope.intersect_affine`).
    Each inequality row ``i`` then costs up to two LPs on the result: a row
    with certified ``max H_i z <= k_i`` is redundant and dropped; a row with
    certified ``min H_i z > k_i`` makes the set empty (:func:`empty_set` is
    returned); the other rows become the generalised intersection with the box
    ``[sigma, k]`` under ``H``, ``sigma`` the certified lower supports (exact:
    see :func:`intersect_halfspace`).

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    H : array_like, shape (m, n)
        Inequality normals.
    k : array_like, shape (m,)
        Inequality offsets.
    E : array_like, shape (p, n), optional
        Equality rows.
    f : array_like, shape (p,), optional
        Equality right-hand sides (with ``E``).

    Raises
    ------
    UnboundedSetError
        If some ``H_i z`` is unbounded below on the set (see
        :func:`intersect_halfspace`).
    """
    H_a = as_matrix("H", H, cols=Z.dim)
    k_a = as_vector("k", k, size=H_a.shape[0])
    if (E is None) != (f is None):
        raise ArgumentError("E and f must be given together (or both omitted)")
    if E is not None:
        Z = Z.intersect_affine(E, f)
    lower = np.empty(H_a.shape[0])
    keep = np.ones(H_a.shape[0], dtype=bool)
    try:
        for i, row in enumerate(H_a):
            if support_unwarned(Z, row) <= k_a[i]:
                keep[i] = False
                continue
            lower[i] = _lower_support(Z, row)
            if lower[i] > k_a[i]:
                return empty_set(Z.dim)
            if not np.isfinite(lower[i]):
                raise UnboundedSetError(
                    f"H[{i}] z is not bounded below on the set: the cut is not a polytope "
                    "plus a subspace, which a constrained zonotope cannot represent")
    except EmptySetError:
        return empty_set(Z.dim)
    if not keep.any():
        return Z
    return Z.intersect(ConstrainedZonotope.from_box(lower[keep], k_a[keep]), H_a[keep])


def _bounded_factors(Z: ConstrainedZonotope, what: str) -> ConstrainedZonotope:
    """``Z`` with every factor bounded (rescaled if needed), or an error."""
    if not Z.has_unbounded_factors:
        return Z
    from .reduction import rescale

    R = rescale(Z)
    if R.has_unbounded_factors:
        raise UnboundedSetError(f"{what} needs a bounded set; this one is unbounded (or not "
                                "certifiably bounded)")
    return R


def convex_hull(Z: ConstrainedZonotope, W: ConstrainedZonotope) -> ConstrainedZonotope:
    """Convex hull of ``Z`` and ``W``: exact (Raghuraman and Koeln 2022, Theorem 5).

    Every point is ``lam z + (1 - lam) w`` with ``lam = (1 + mu)/2``,
    ``mu in [-1, 1]``. With ``eta_1 = lam xi_1`` and ``eta_2 = (1 - lam) xi_2``
    the constraints become linear: ``A_1 eta_1 = lam b_1``,
    ``A_2 eta_2 = (1 - lam) b_2``, and the bounds ``|eta_1| <= lam h_1``,
    ``|eta_2| <= (1 - lam) h_2`` are written with one slack factor each side
    (``s = h (1 + sigma)``, ``|sigma| <= 1``, covers the slack's range
    ``[0, 2 lam h]``). The result has ``3 (n_g1 + n_g2) + 1`` factors and
    ``n_c1 + n_c2 + 2 (n_g1 + n_g2)`` constraints; :func:`~setobs.geometry.reduce_exact`
    removes what is redundant. An empty operand gives the other set (``lam``
    is forced to 0 or 1).

    Parameters
    ----------
    Z, W : ConstrainedZonotope
        Bounded sets of the same dimension. Unbounded factors are first
        bounded by :func:`~setobs.geometry.rescale` (the closed convex hull of
        unbounded sets need not be a polytope plus a subspace).

    Raises
    ------
    UnboundedSetError
        If a set is unbounded.

    Examples
    --------
    >>> P = convex_hull(ConstrainedZonotope.point([0.0, 0.0]),
    ...                 ConstrainedZonotope.from_box([1.0, 1.0], [2.0, 2.0]))
    >>> bool(P.contains([0.5, 0.5])), bool(P.contains([0.0, 1.0]))
    (True, False)
    """
    if not isinstance(W, ConstrainedZonotope):
        raise ArgumentError(f"convex_hull expects a ConstrainedZonotope, got {type(W).__name__}")
    if W.dim != Z.dim:
        raise DimensionError(f"convex hull: dimensions differ ({Z.dim} vs {W.dim})")
    Z = _bounded_factors(Z, "convex_hull")
    W = _bounded_factors(W, "convex_hull")
    g1, g2 = Z.n_con, W.n_con
    n1, n2 = Z.n_gen, W.n_gen
    m = n1 + n2
    # columns: eta_1 (n1), eta_2 (n2), mu (1), sigma (2 m)
    G = np.hstack([Z.G, W.G, ((Z.c - W.c) / 2.0)[:, None], np.zeros((Z.dim, 2 * m))])
    c = (Z.c + W.c) / 2.0
    A = np.zeros((g1 + g2 + 2 * m, 3 * m + 1))
    b = np.zeros(g1 + g2 + 2 * m)
    A[:g1, :n1] = Z.A
    A[:g1, m] = -Z.b / 2.0
    b[:g1] = Z.b / 2.0
    A[g1:g1 + g2, n1:m] = W.A
    A[g1:g1 + g2, m] = W.b / 2.0
    b[g1:g1 + g2] = W.b / 2.0
    hh = np.concatenate([Z.h, W.h])
    sign_mu = np.concatenate([-np.ones(n1), np.ones(n2)])  # lam for Z, 1 - lam for W
    r0 = g1 + g2
    eye = np.eye(m)
    for s, block in ((1.0, 0), (-1.0, 1)):  # eta <= bound and -eta <= bound
        rows = slice(r0 + block * m, r0 + (block + 1) * m)
        A[rows, :m] = s * eye
        A[rows, m] = sign_mu * hh / 2.0
        A[rows, m + 1 + block * m: m + 1 + (block + 1) * m] = np.diag(hh)
        b[rows] = -hh / 2.0
    h = np.concatenate([Z.h, W.h, [1.0], np.ones(2 * m)])
    # The centre's rounding, and the rounding of the generator (c1 - c2)/2 (its
    # factor mu is in [-1, 1]), go into c_err; b_1/2 and b_2/2 are exact, and the
    # uncertainty of b_i enters through lam b_i with lam in [0, 1].
    cerr = Z.c_err + W.c_err + 2.0 * gamma(3) * (np.abs(Z.c) + np.abs(W.c))
    berr = np.concatenate([Z.b_err, W.b_err, np.zeros(2 * m)])
    return trusted_cz(G, c, A, b, h, min(Z.unbounded_radius, W.unbounded_radius), cerr, berr)


def from_vertices(V: ArrayLike) -> ConstrainedZonotope:
    """The convex hull of points (V-representation), as a constrained zonotope: exact.

    ``z = sum lam_i v_i`` with ``lam_i = (1 + xi_i)/2 in [0, 1]`` and
    ``sum lam_i = 1``: ``G = V^T / 2``, ``c = V^T 1 / 2`` and the single
    constraint ``1^T xi = 2 - m``. Points that are not vertices are kept (they
    cost a factor each, not exactness); :func:`~setobs.geometry.reduce_exact`
    removes factors the constraint makes redundant.

    Parameters
    ----------
    V : array_like, shape (m, n)
        The points, one per row (``m >= 1``).

    Examples
    --------
    >>> T = from_vertices([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> bool(T.contains([0.25, 0.25])), bool(T.contains([0.6, 0.6]))
    (True, False)
    """
    Va = as_matrix("V", V)
    m = Va.shape[0]
    if m == 0 or Va.shape[1] == 0:
        raise DimensionError(f"from_vertices needs at least one point of dimension >= 1, got "
                             f"an array of shape {Va.shape}")
    G = Va.T / 2.0
    c = Va.sum(axis=0) / 2.0
    cerr = gamma(m) * np.abs(Va).sum(axis=0) / 2.0
    return trusted_cz(G, c, np.ones((1, m)), np.array([2.0 - m]), np.ones(m), cerr=cerr)


def _zonotope_data(W: ConstrainedZonotope | Box) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(D, c)`` with ``W = {D eta + c : |eta| <= 1}`` for a box or an unconstrained set."""
    if isinstance(W, Box):
        if not W.is_bounded:
            raise UnboundedSetError("the subtrahend box must be bounded")
        c, r = box_center_radius(W.lo, W.hi)
        keep = r > 0
        return np.diag(r)[:, keep], c
    if not isinstance(W, ConstrainedZonotope):
        raise ArgumentError("the subtrahend must be a ConstrainedZonotope (a zonotope) or a Box, "
                            f"got {type(W).__name__}")
    if W.n_con or W.has_unbounded_factors:
        raise InvalidValueError("the subtrahend must be a zonotope or a box (no constraints, "
                             "bounded factors); for a general set use an outer zonotope of it "
                             "(an inner approximation of the difference results)")
    if W.c_err.any():
        raise InvalidValueError("the subtrahend carries centre rounding (c_err); pass its "
                             "enclosing box instead")
    keep = (W.h > 0) & W.G.any(axis=0)
    return W.G[:, keep] * W.h[keep], W.c


def _zonotope_vertices(D: NDArray[np.float64], c: NDArray[np.float64]) -> NDArray[np.float64]:
    """Points ``c + D s`` (``s`` in {-1, 1}^m) whose hull is the zonotope: its vertices."""
    n, m = D.shape
    if m == 0:
        return c[None, :]
    if n == 1:
        r = float(np.abs(D).sum())
        return np.array([[c[0] - r], [c[0] + r]])
    if n == 2:
        # the 2m vertices of a zonogon, by sorting the generators by angle
        Dp = np.where((D[1] < 0) | ((D[1] == 0) & (D[0] < 0)), -D, D)
        order = np.argsort(np.arctan2(Dp[1], Dp[0]))
        Dp = Dp[:, order]
        start = c - Dp.sum(axis=1)
        pts = [start]
        for j in range(m):
            pts.append(pts[-1] + 2.0 * Dp[:, j])
        for j in range(m - 1):
            pts.append(pts[-1] - 2.0 * Dp[:, j])
        return np.array(pts)
    if m > 16:
        raise InvalidValueError(f"the exact difference enumerates the subtrahend's vertices; "
                             f"2^{m} sign patterns is too many: use method='inner'")
    signs = np.array(np.meshgrid(*([[-1.0, 1.0]] * m), indexing="ij")).reshape(m, -1)
    return (c[:, None] + D @ signs).T


def pontryagin_difference(Z: ConstrainedZonotope, W: ConstrainedZonotope | Box | ArrayLike,
                          method: str = "exact") -> ConstrainedZonotope:
    """Pontryagin difference ``Z - W = {z : z + W subset Z}`` for a zonotope or box ``W``.

    ``method="exact"``: ``Z - W = intersection over the vertices v of W of
    (Z - v)`` (``Z`` is convex, so ``z + W subset Z`` iff ``z + v in Z`` for
    every vertex). The copies share one factor set per vertex:
    ``n_v n_g`` factors, ``n_v n_c + (n_v - 1) n`` constraints, with ``n_v``
    the number of vertices (``2 m`` for ``m`` generators in the plane,
    ``2^m`` in general, so refused above ``m = 16``). Exact, like CORA's
    ``minkDiff(..., 'exact')``.

    ``method="inner"``: an inner approximation, labelled as such. With ``D``
    the generators of ``W``, an LP finds ``Gamma`` with ``G Gamma = D`` and
    ``A Gamma = 0`` minimising ``sum_j (|Gamma| 1)_j / h_j``; then
    ``{G xi + c - c_W : A xi = b, |xi| <= h - |Gamma| 1}`` is inside the
    difference (for ``|eta| <= 1``, ``xi + Gamma eta`` is a factor of ``Z``
    that gives ``z + D eta``; the generator matching of Vinod et al.,
    CORA's ``'inner:Vinod'``). ``Gamma`` is refined by least squares and
    accepted only if the residual ``[G; A] Gamma - [D; 0]`` is below
    :data:`~setobs.tolerances.PONTRYAGIN_MATCH_RTOL` of the data: the inner
    claim holds up to that residual (the part of ``W`` the matching misses),
    which is not absorbed. If no matching exists, or the shrunk factor box is
    empty, the result is :func:`empty_set` (the inner approximation may be
    empty when the difference is not).

    Parameters
    ----------
    Z : ConstrainedZonotope
        The minuend.
    W : ConstrainedZonotope, Box or array_like
        A zonotope (no constraints, bounded factors), a box, or a vector (a
        translation: ``Z - w``).
    method : {"exact", "inner"}
        See above.

    Raises
    ------
    DimensionError
        If the dimensions differ.
    InvalidValueError
        For a subtrahend with constraints, or too many generators for
        ``"exact"``.

    Examples
    --------
    >>> Z = ConstrainedZonotope.from_box([-2.0, -1.0], [2.0, 1.0])
    >>> D = pontryagin_difference(Z, Box([-0.5, -0.5], [0.5, 0.5]))
    >>> box = D.interval_hull()
    >>> bool(np.allclose(box.lo, [-1.5, -0.5]) and np.allclose(box.hi, [1.5, 0.5]))
    True
    """
    if method not in ("exact", "inner"):
        raise InvalidValueError(f"method must be 'exact' or 'inner', got {method!r}")
    if not isinstance(W, ConstrainedZonotope | Box):
        w = as_vector("W", W, size=Z.dim)
        return Z.minkowski_sum(-w)
    if W.dim != Z.dim:
        raise DimensionError(f"Pontryagin difference: dimensions differ ({Z.dim} vs {W.dim})")
    D, cw = _zonotope_data(W)
    if method == "exact":
        pts = _zonotope_vertices(D, cw)
        # the vertices' rounding (sums of up to m generators) is carried in c_err
        verr = gamma(D.shape[1] + 2) * (np.abs(cw) + np.abs(D).sum(axis=1)) * 2.0
        out = Z.minkowski_sum(-pts[0], err=verr)
        for v in pts[1:]:
            out = out.intersect(Z.minkowski_sum(-v, err=verr))
        return out
    return _inner_difference(Z, D, cw)


def _inner_difference(Z: ConstrainedZonotope, D: NDArray[np.float64],
                      cw: NDArray[np.float64]) -> ConstrainedZonotope:
    from scipy.optimize import linprog
    from scipy.sparse import csr_matrix, hstack, identity, kron

    m = D.shape[1]
    if m == 0:
        return Z.minkowski_sum(-cw)
    ng, nc = Z.n_gen, Z.n_con
    M = np.vstack([Z.G, Z.A])
    rhs = np.vstack([D, np.zeros((nc, m))])
    # variables: Gamma+ (ng x m), Gamma- (ng x m) column-major per column of W, t (ng)
    # [M, -M] Gamma_col = rhs_col ; sum_col (G+ + G-)_j <= t_j
    Ms = csr_matrix(M)
    Im = identity(m, format="csr")
    A_eq = hstack([kron(Im, Ms), kron(Im, -Ms), csr_matrix((M.shape[0] * m, ng))])
    b_eq = rhs.T.reshape(-1)
    ones = csr_matrix(np.ones((1, m)))
    Ig = identity(ng, format="csr")
    A_ub = hstack([kron(ones, Ig), kron(ones, Ig), -Ig])
    fin = np.isfinite(Z.h) & (Z.h > 0)
    weight = np.where(fin, 1.0 / np.where(fin, Z.h, 1.0), 1e-6)
    weight[Z.h == 0] = 1e6
    cost = np.concatenate([np.zeros(2 * ng * m), weight])
    res = linprog(cost, A_ub=A_ub, b_ub=np.zeros(ng), A_eq=A_eq, b_eq=b_eq,
                  bounds=(0, None), method="highs")
    if res.status == 2:  # infeasible: W's generators are not all matched
        return empty_set(Z.dim)
    if res.status != 0:
        raise SolverError(f"the matching LP of the inner difference failed: {res.message}",
                          status=str(res.status))
    x = res.x
    Gam = (x[: ng * m] - x[ng * m: 2 * ng * m]).reshape(m, ng).T
    # least-squares refinement of the equality residual
    R = rhs - M @ Gam
    Gam = Gam + np.linalg.lstsq(M, R, rcond=None)[0]
    R = rhs - M @ Gam
    scale = max(1.0, float(np.abs(rhs).max()), float(np.abs(M).max()))
    if np.abs(R).max() > PONTRYAGIN_MATCH_RTOL * scale:
        return empty_set(Z.dim)
    shrink = round_up(np.abs(Gam).sum(axis=1) * (1.0 + gamma(m + 1)))
    new_h = Z.h - shrink
    if (new_h < 0).any():
        return empty_set(Z.dim)
    new_h = round_down(np.maximum(new_h, 0.0))
    return trusted_cz(Z.G, Z.c - cw, Z.A, Z.b, new_h, Z.unbounded_radius, Z.c_err, Z.b_err)


def interval_matrix_map(Z: ConstrainedZonotope, M_lo: ArrayLike, M_hi: ArrayLike
                        ) -> ConstrainedZonotope:
    """Outer bound of ``{M z : M in [M_lo, M_hi], z in Z}`` (an interval matrix).

    With ``M = M_c + dM``, ``|dM| <= M_r`` elementwise (``M_c``, ``M_r`` the
    centre and radius, ``M_r`` rounded up to cover the rounding of ``M_c``):
    ``M z = M_c z + dM z`` and ``|dM z| <= M_r |z| <= M_r z_max`` with
    ``z_max = max(|lo|, |hi|)`` from the certified interval hull. So the set is
    inside ``M_c Z + [-M_r z_max, M_r z_max]``: Althoff's method (Althoff 2010,
    Theorem 3.3, which bounds ``|z|`` by ``|c| + sum |g_i|`` for a zonotope;
    the certified hull is never wider). Outer; exact when ``M_lo = M_hi``.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    M_lo, M_hi : array_like, shape (m, n)
        Elementwise bounds of the matrix (``M_lo <= M_hi``).

    Raises
    ------
    EmptySetError
        If ``Z`` is certified empty.

    Examples
    --------
    >>> Z = ConstrainedZonotope.from_box([1.0], [2.0])
    >>> box = interval_matrix_map(Z, [[0.5]], [[1.5]]).interval_hull()
    >>> bool(box.lo[0] <= 0.5 and box.hi[0] >= 3.0)
    True
    """
    lo = as_matrix("M_lo", M_lo, cols=Z.dim)
    hi = as_matrix("M_hi", M_hi, rows=lo.shape[0], cols=Z.dim)
    if (lo > hi).any():
        raise InvalidValueError("M_lo must be elementwise <= M_hi")
    Mc, Mr = box_center_radius(lo, hi)  # elementwise: |M - Mc| <= Mr for every M in [lo, hi]
    box, _ = hull_with_status(Z)
    zmax = np.maximum(np.abs(box.lo), np.abs(box.hi))
    with np.errstate(invalid="ignore"):
        prod = np.where(Mr > 0, Mr * zmax[None, :], 0.0)
    rad = prod.sum(axis=1)
    rad = np.where(np.isfinite(rad), round_up(rad * (1.0 + gamma(Z.dim + 1))), np.inf)
    out = Z.linear_map(Mc)
    if not rad.any():
        return out
    return out + ConstrainedZonotope.from_box(-rad, rad)


def quad_map(Z: ConstrainedZonotope, Q: ArrayLike) -> ConstrainedZonotope:
    """Outer bound of the quadratic map ``{(z^T Q_1 z, ..., z^T Q_m z) : z in Z}``.

    With ``z = c + G xi`` (``A xi = b``, ``|xi| <= h``), each output is
    ``c^T Q_i c + c^T (Q_i + Q_i^T) G xi + xi^T M_i xi``, ``M_i = G^T Q_i G``. The
    linear part stays on the factors ``xi`` (with their constraints); each product
    of factors becomes a new factor shared by all outputs, as in Althoff's
    quadratic map of zonotopes (Althoff 2013; CORA's ``quadMap``):
    ``xi_j^2 = h_j^2 / 2 + (h_j^2 / 2) eta_jj`` and ``xi_j xi_k = h_j h_k eta_jk``,
    ``|eta| <= 1``. Outer, because the new factors forget that they are products
    of the old ones (``n_g (n_g + 1) / 2`` new factors: reduce the order after).
    The rounding of the coefficients is bounded (Higham's ``gamma`` of the dot
    products against ``|c|^T |Q_i| |c| + 2 |c|^T |Q_i| |G| h + (|G| h)^T |Q_i| (|G| h)``)
    and carried in :attr:`~ConstrainedZonotope.c_err`, and the centre's own
    uncertainty enters as bounded factors, so the result contains the exact image.

    Parameters
    ----------
    Z : ConstrainedZonotope
        A set with bounded factors.
    Q : array_like, shape (m, n, n)
        The matrices ``Q_i`` (a single ``n x n`` matrix gives ``m = 1``).

    Raises
    ------
    UnboundedSetError
        If a factor of ``Z`` is unbounded.

    Examples
    --------
    ``x^2`` over ``[-1, 1]`` is ``[0, 1]``:

    >>> R = quad_map(ConstrainedZonotope.from_box([-1.0], [1.0]), [[[1.0]]])
    >>> box = R.interval_hull()
    >>> bool(box.lo[0] <= 0.0 and abs(box.lo[0]) < 1e-12 and abs(box.hi[0] - 1.0) < 1e-12)
    True
    """
    Qa = np.asarray(Q, dtype=np.float64)
    if Qa.ndim == 2:
        Qa = Qa[None]
    if Qa.ndim != 3 or Qa.shape[1:] != (Z.dim, Z.dim):
        raise DimensionError(f"Q must have shape (m, {Z.dim}, {Z.dim}), got {np.shape(Q)}")
    for i in range(Qa.shape[0]):
        as_matrix(f"Q[{i}]", Qa[i], rows=Z.dim, cols=Z.dim)  # (finite, real)
    if not np.isfinite(Z.h).all():
        raise UnboundedSetError("quad_map needs bounded factors (h finite)")
    G, c, h = Z.G, Z.c, Z.h
    if Z.c_err.any():  # the centre's uncertainty as bounded factors
        e = np.flatnonzero(Z.c_err)
        E = np.zeros((Z.dim, e.size))
        E[e, np.arange(e.size)] = Z.c_err[e]
        G, h = np.hstack([G, E]), np.concatenate([h, np.ones(e.size)])
    n, n_g = Z.dim, G.shape[1]
    # (products of three data entries may overflow; the data guard of trusted_cz then
    # refuses the result, naming quad_map, instead of a set with inf or NaN data)
    with np.errstate(over="ignore", invalid="ignore"):
        return _quad_map_data(Z, Qa, G, c, h, n, n_g)


def _quad_map_data(Z, Qa, G, c, h, n, n_g) -> ConstrainedZonotope:
    """The body of :func:`quad_map` (inputs validated)."""
    QG = np.einsum("ikl,lj->ikj", Qa, G)                      # Q_i G
    M = np.einsum("kj,ikl->ijl", G, QG)                        # G^T Q_i G
    Qc = np.einsum("ikl,l->ik", Qa, c)                         # Q_i c
    lin = np.einsum("k,ikj->ij", c, QG) + Qc @ G               # c^T (Q_i + Q_i^T) G
    cQc = np.einsum("k,ikl,l->i", c, Qa, c)
    diag = np.einsum("ijj->ij", M)
    h2 = h * h
    centre = cQc + 0.5 * (diag * h2).sum(axis=1)
    sq = 0.5 * diag * h2                                       # eta_jj
    ju, ku = np.triu_indices(n_g, 1)
    cross = (M[:, ju, ku] + M[:, ku, ju]) * (h[ju] * h[ku])    # eta_jk
    # rounding of every coefficient, bounded against the magnitudes it came from
    absQ = np.abs(Qa)
    r = np.abs(G) @ h
    ac = np.abs(c)
    mag = (np.einsum("k,ikl,l->i", ac, absQ, ac) + 2.0 * np.einsum("k,ikl,l->i", ac, absQ, r)
           + np.einsum("k,ikl,l->i", r, absQ, r))
    err = round_up(mag * (2.0 * gamma(2 * n + 2 * n_g + 8)))
    # the linear part keeps the (original) factors and their constraints; the new ones
    # are the products (zero columns dropped)
    Q_cols = np.hstack([sq, cross])
    keep = np.flatnonzero(np.abs(Q_cols).max(axis=0) > 0.0)
    G_out = np.hstack([lin, Q_cols[:, keep]])
    n_new = keep.size
    # (the centre-error factors, like the products, are unconstrained)
    A_out = np.hstack([Z.A, np.zeros((Z.n_con, G.shape[1] - Z.n_gen + n_new))])
    h_out = np.concatenate([h, np.ones(n_new)])
    return trusted_cz(G_out, centre, A_out, Z.b, h_out, Z.unbounded_radius, err, Z.b_err,
                      op="quad_map")
