"""Cuts, hulls, differences, uncertain maps and constraint elimination.

Oracles: exact rational vertex enumeration (the factor polytope's vertices, and
the vertices of H-polytopes solved in Fractions), scipy's Qhull, sampling of
the interval matrix, and closed forms.
"""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

from setobs import ConstrainedZonotope
from setobs.exceptions import (
    ArgumentError,
    DimensionError,
    EmptySetError,
    InvalidValueError,
    UnboundedSetError,
)
from setobs.geometry import (
    Box,
    convex_hull,
    cz_from_hpolytope,
    eliminate_constraints,
    empty_set,
    from_vertices,
    intersect_halfspace,
    intersect_polytope,
    intersect_strip,
    interval_matrix_map,
    pontryagin_difference,
    reduce_order,
)
from setobs.geometry.reduction import hausdorff_heuristic

from ..conftest import exact_factor_vertices, random_cz
from ..oracles import exact_hpolytope_vertices

seeds = st.integers(0, 2**31 - 1)


def as_set(P, decimals=6):
    return {tuple(np.round(p, decimals) + 0.0) for p in np.atleast_2d(P)}


def exact_points(Z):
    """The set is the convex hull of these points (exact factor vertices, mapped)."""
    verts = exact_factor_vertices(Z.A, Z.b, Z.h)
    return np.array([[float(v) for v in xi] for xi in verts]) @ Z.G.T + Z.c


def hrep_of_points(P):
    """Facets ``H x <= k`` of the hull of points, by Qhull."""
    eq = ConvexHull(P).equations
    return eq[:, :-1], -eq[:, -1]


def exact_vertices_of(H, k):
    return np.array([[float(v) for v in x] for x in exact_hpolytope_vertices(H, k)])


def full_dim_cz(seed, n=2):
    rng = np.random.default_rng(seed)
    for _ in range(50):
        Z = random_cz(rng, n=n, n_g=int(rng.integers(n + 1, n + 4)), n_c=1)
        P = exact_points(Z)
        if len(P) > n and np.linalg.matrix_rank(P - P.mean(axis=0), tol=1e-6) == n:
            vol = ConvexHull(P).volume
            if vol > 1e-2:
                return Z, P
    raise AssertionError("no full-dimensional sample")


# ---------------------------------------------------------------- half-spaces, strips, polytopes
@settings(max_examples=25, deadline=None)
@given(seeds)
def test_halfspace_cut_equals_exact_polytope_cut(seed):
    Z, P = full_dim_cz(seed)
    rng = np.random.default_rng(seed + 1)
    a = rng.normal(size=2)
    vals = P @ a
    beta = float(np.quantile(vals, rng.uniform(0.2, 0.8)))
    R = intersect_halfspace(Z, a, beta)
    H, k = hrep_of_points(P)
    ref = exact_vertices_of(np.vstack([H, a]), np.concatenate([k, [beta]]))
    assert as_set(R.vertices(), 5) == as_set(ref, 5)


def test_halfspace_cut_containing_and_missing():
    Z = ConstrainedZonotope.from_box([0.0, 0.0], [1.0, 1.0])
    assert intersect_halfspace(Z, [1.0, 1.0], 2.5) is Z          # whole set inside
    E = intersect_halfspace(Z, [1.0, 1.0], -0.5)                 # misses the set
    assert E.is_empty() and E.dim == 2
    # touching in one vertex: the cut is that point
    T = intersect_halfspace(Z, [1.0, 1.0], 0.0)
    box = T.interval_hull()
    assert np.allclose(box.lo, 0.0, atol=1e-9) and np.allclose(box.hi, 0.0, atol=1e-9)


def test_halfspace_cut_of_unbounded_sets():
    # a strip in x2 (free x1) cut by x2 <= 0.5 stays representable
    S = ConstrainedZonotope([[1.0, 0.0], [0.0, 1.0]], [0.0, 0.0], h=[np.inf, 1.0])
    C = intersect_halfspace(S, [0.0, 1.0], 0.5)
    box = C.interval_hull()
    assert box.lo[0] == -np.inf and box.hi[0] == np.inf
    assert box.hi[1] == pytest.approx(0.5, abs=1e-9) and box.lo[1] == pytest.approx(-1.0)
    # cutting along the free direction gives a half-strip: not representable
    with pytest.raises(UnboundedSetError, match="not bounded below"):
        intersect_halfspace(S, [-1.0, 0.0], 0.0)


@settings(max_examples=15, deadline=None)
@given(seeds)
def test_strip_equals_two_halfspaces(seed):
    Z, P = full_dim_cz(seed)
    rng = np.random.default_rng(seed + 2)
    a = rng.normal(size=2)
    vals = P @ a
    y = float(np.median(vals))
    r = float(0.25 * (vals.max() - vals.min()))
    S = intersect_strip(Z, [a], [y], r)
    H, k = hrep_of_points(P)
    ref = exact_vertices_of(np.vstack([H, a, -a]), np.concatenate([k, [y + r, r - y]]))
    assert as_set(S.vertices(), 5) == as_set(ref, 5)


@settings(max_examples=15, deadline=None)
@given(seeds)
def test_polytope_cut_equals_exact(seed):
    Z, P = full_dim_cz(seed)
    rng = np.random.default_rng(seed + 3)
    Hc = rng.normal(size=(3, 2))
    centre = P.mean(axis=0)
    kc = Hc @ centre + rng.uniform(0.05, 1.0, size=3) * np.abs(Hc @ (P - centre).T).max(axis=1)
    R = intersect_polytope(Z, Hc, kc)
    H, k = hrep_of_points(P)
    ref = exact_vertices_of(np.vstack([H, Hc]), np.concatenate([k, kc]))
    assert as_set(R.vertices(), 5) == as_set(ref, 5)
    # redundant rows are dropped, not encoded
    R2 = intersect_polytope(Z, np.vstack([Hc, [1.0, 0.0]]), np.concatenate([kc, [1e6]]))
    assert R2.n_con == R.n_con


def test_intersections_with_the_empty_set_are_empty():
    Z = ConstrainedZonotope.from_box([0.0], [1.0])
    assert intersect_halfspace(Z.intersect(empty_set(1)), [1.0], 0.5).is_empty()
    assert intersect_polytope(empty_set(2), [[1.0, 0.0]], [0.0]).is_empty()


# ---------------------------------------------------------------- convex hull, vertices
@settings(max_examples=20, deadline=None)
@given(seeds)
def test_convex_hull_equals_qhull_of_both_point_clouds(seed):
    Z, P = full_dim_cz(seed)
    W, Q = full_dim_cz(seed + 7)
    W = W + np.array([2.0, -1.0])
    Q = Q + np.array([2.0, -1.0])
    CH = convex_hull(Z, W)
    allp = np.vstack([P, Q])
    ref = allp[ConvexHull(allp).vertices]
    assert as_set(CH.vertices(), 5) == as_set(ref, 5)


def test_convex_hull_in_3d_and_with_points():
    rng = np.random.default_rng(3)
    Z = ConstrainedZonotope.from_box([0, 0, 0], [1, 1, 1])
    p = ConstrainedZonotope.point([2.0, 2.0, 2.0])
    CH = convex_hull(Z, p)
    cube = np.array([[i, j, k] for i in (0, 1) for j in (0, 1) for k in (0, 1)], float)
    allp = np.vstack([cube, [[2, 2, 2]]])
    ref = allp[ConvexHull(allp).vertices]
    assert as_set(CH.vertices(), 5) == as_set(ref, 5)
    for x in rng.dirichlet(np.ones(len(allp)), size=20) @ allp:
        assert CH.contains(x)
    assert not CH.contains([2.0, 2.0, 2.1])


def test_convex_hull_with_empty_and_unbounded():
    Z = ConstrainedZonotope.from_box([0.0, 0.0], [1.0, 2.0])
    CH = convex_hull(Z, empty_set(2))
    assert as_set(CH.vertices()) == as_set(Z.vertices())
    # a bounded set with an unbounded factor is rescaled first
    Zb = ConstrainedZonotope([[1.0, 1.0]], [0.0], A=[[1.0, -1.0]], b=[0.0], h=[1.0, np.inf])
    CH = convex_hull(Zb, ConstrainedZonotope.point([5.0]))
    box = CH.interval_hull()
    assert box.lo[0] == pytest.approx(-2.0, abs=1e-7) and box.hi[0] == pytest.approx(5.0)
    with pytest.raises(UnboundedSetError):
        convex_hull(ConstrainedZonotope.full_space(1), ConstrainedZonotope.point([0.0]))
    with pytest.raises(DimensionError, match="dimensions differ"):
        convex_hull(Z, ConstrainedZonotope.point([0.0]))


@settings(max_examples=20, deadline=None)
@given(seeds, st.integers(2, 3))
def test_from_vertices_equals_qhull(seed, n):
    rng = np.random.default_rng(seed)
    P = rng.normal(size=(int(rng.integers(n + 1, 12)), n))
    Z = from_vertices(P)
    ref = P[ConvexHull(P).vertices]
    assert as_set(Z.vertices(), 5) == as_set(ref, 5)


def test_from_vertices_single_point_and_segment():
    assert as_set(from_vertices([[1.5, -2.0]]).vertices()) == {(1.5, -2.0)}
    S = from_vertices([[0.0], [3.0], [1.0]])
    box = S.interval_hull()
    assert box.lo[0] == pytest.approx(0.0, abs=1e-12) and box.hi[0] == pytest.approx(3.0)


# ---------------------------------------------------------------- Pontryagin difference
def _support_of_zonotope(h, D, c):
    return float(h @ c + np.abs(h @ D).sum())


@settings(max_examples=15, deadline=None)
@given(seeds)
def test_exact_pontryagin_difference_equals_hrep_difference(seed):
    """P - W = {x : H x <= k - sigma_W(H_i)} for the facets of P (polytope identity)."""
    Z, P = full_dim_cz(seed)
    rng = np.random.default_rng(seed + 5)
    H, k = hrep_of_points(P)
    width = P.max(axis=0) - P.min(axis=0)
    D = rng.normal(size=(2, 3)) * 0.08 * width.min()
    cw = rng.normal(size=2) * 0.05
    W = ConstrainedZonotope.from_zonotope(D, cw)
    kk = np.array([k[i] - _support_of_zonotope(H[i], D, cw) for i in range(len(k))])
    R = pontryagin_difference(Z, W)
    cheb = linprog(np.r_[0.0, 0.0, -1.0], A_ub=np.hstack([H, np.linalg.norm(H, axis=1)[:, None]]),
                   b_ub=kk, bounds=[(None, None)] * 2 + [(None, None)], method="highs")
    if -cheb.fun < 0:              # the difference is empty
        assert R.is_empty()
        return
    if -cheb.fun < 1e-3 * width.min():
        return                     # too thin for a vertex comparison
    ref = exact_vertices_of(H, kk)
    assert as_set(R.vertices(), 5) == as_set(ref, 5)
    # the inner method is inside the exact difference
    I = pontryagin_difference(Z, W, method="inner")
    if not I.is_empty():
        assert (H @ I.vertices().T <= kk[:, None] + 1e-7).all()


def test_pontryagin_difference_with_a_box_in_3d_and_vectors():
    Z = ConstrainedZonotope.from_box([-2.0, -1.0, 0.0], [2.0, 1.0, 3.0])
    R = pontryagin_difference(Z, Box([-0.5, -0.25, -1.0], [0.5, 0.25, 1.0]))
    box = R.interval_hull()
    assert np.allclose(box.lo, [-1.5, -0.75, 1.0]) and np.allclose(box.hi, [1.5, 0.75, 2.0])
    assert np.allclose(pontryagin_difference(Z, [1.0, 0.0, 0.0]).interval_hull().lo,
                       [-3.0, -1.0, 0.0])
    # too large a subtrahend: the difference is empty
    assert pontryagin_difference(Z, Box([-3.0, 0, 0], [3.0, 0, 0])).is_empty()


def test_inner_pontryagin_difference_is_exact_for_matching_generators():
    # Z = box of radius 2, W = box of radius 0.5: the matching is Gamma = I/4 * ...
    Z = ConstrainedZonotope.from_box([-2.0, -2.0], [2.0, 2.0])
    W = ConstrainedZonotope.from_box([-0.5, -0.5], [0.5, 0.5])
    I = pontryagin_difference(Z, W, method="inner")
    box = I.interval_hull()
    assert np.allclose(box.lo, -1.5) and np.allclose(box.hi, 1.5)
    # a diagonal segment cannot be matched without using both factors
    seg = ConstrainedZonotope.from_zonotope([[0.5], [0.5]], [0.0, 0.0])
    I2 = pontryagin_difference(Z, seg, method="inner")
    assert np.allclose(I2.interval_hull().hi, 1.5)


def test_pontryagin_difference_rejects_sets_with_constraints():
    Z = ConstrainedZonotope.from_box([-2.0, -2.0], [2.0, 2.0])
    T = from_vertices([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    with pytest.raises(InvalidValueError, match="zonotope or a box"):
        pontryagin_difference(Z, T)
    with pytest.raises(ValueError, match="method must be"):
        pontryagin_difference(Z, Box([0, 0], [1, 1]), method="outer")
    with pytest.raises(DimensionError, match="dimensions differ"):
        pontryagin_difference(Z, Box([0], [1]))


# ---------------------------------------------------------------- interval matrix map
@settings(max_examples=10, deadline=None)
@given(seeds)
def test_interval_matrix_map_contains_every_sampled_image(seed):
    Z, P = full_dim_cz(seed)
    rng = np.random.default_rng(seed + 11)
    Mc = rng.normal(size=(2, 2))
    Mr = rng.uniform(0.0, 0.3, size=(2, 2))
    R = interval_matrix_map(Z, Mc - Mr, Mc + Mr)
    H, k = hrep_of_points(np.vstack(R.vertices()))
    # every vertex matrix (16) and random matrices, applied to every vertex of Z
    corners = [Mc + Mr * np.array(s).reshape(2, 2)
               for s in np.array(np.meshgrid(*[[-1, 1]] * 4)).reshape(4, -1).T]
    mats = corners + [Mc + Mr * rng.uniform(-1, 1, size=(2, 2)) for _ in range(30)]
    imgs = np.vstack([P @ M.T for M in mats])
    assert (H @ imgs.T <= k[:, None] + 1e-9 * (1 + np.abs(k[:, None]))).all()


def test_interval_matrix_map_point_matrix_is_the_linear_map():
    Z = ConstrainedZonotope([[1.0, 0.5], [0.0, 1.0]], [0.3, -0.2], A=[[1.0, 1.0]], b=[0.2])
    M = np.array([[2.0, -1.0], [0.5, 1.0]])
    assert as_set(interval_matrix_map(Z, M, M).vertices()) == as_set((M @ Z).vertices())


def test_interval_matrix_map_closed_form_of_a_box():
    # [0.5, 1.5] * [1, 2] = [0.5, 3]; the method gives 1 * [1, 2] + [-0.5 * 2, 0.5 * 2]
    R = interval_matrix_map(ConstrainedZonotope.from_box([1.0], [2.0]), [[0.5]], [[1.5]])
    box = R.interval_hull()
    assert box.lo[0] == pytest.approx(0.0) and box.hi[0] == pytest.approx(3.0)
    with pytest.raises(InvalidValueError, match="M_lo must be"):
        interval_matrix_map(ConstrainedZonotope.from_box([1.0], [2.0]), [[1.0]], [[0.0]])


# ---------------------------------------------------------------- constraint elimination
def _polytope_cz(seed, n=2, points=100):
    rng = np.random.default_rng(seed)
    pts = rng.random((points, n))
    hull = ConvexHull(pts)
    H, k = hull.equations[:, :-1], -hull.equations[:, -1]
    return cz_from_hpolytope(H, k), pts[hull.vertices]


@pytest.mark.parametrize("method", ["lp", "fast"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_constraint_elimination_is_outer(seed, method):
    """CORA's testFlaky_conZonotope_reduce: the vertices stay inside after eliminating
    (with certified-LP overshoots and with interval propagation)."""
    Z, V = _polytope_cz(seed)
    for target in (Z.n_con - 1, Z.n_con - 2, 2, 0):
        R = eliminate_constraints(Z, target, method=method)
        assert R.n_con <= target
        assert all(R.contains(v) for v in V)


def test_constraint_elimination_works_on_a_set_that_already_carries_rounding_error():
    """A set whose right-hand side carries a certified error larger than the elimination
    budget's relative size (a filter after 25 steps: 2e-12 against 1e-12) still has
    its constraints eliminated (it stalled: the budget was the larger of the two, not
    the carried error plus the room), and stays outer (vertices inside)."""
    from setobs.geometry.zonotope import trusted_cz

    Z, V = _polytope_cz(1)
    Ze = trusted_cz(Z.G, Z.c, Z.A, Z.b, Z.h, Z.unbounded_radius, Z.c_err,
                    np.full(Z.n_con, 1e-9))
    for target in (Z.n_con - 1, 2, 0):
        R = eliminate_constraints(Ze, target)
        assert R.n_con <= target
        assert all(R.contains(v) for v in V)


def test_reduce_order_can_shrink_sets_converted_from_polytopes():
    Z, V = _polytope_cz(4, n=3, points=40)
    assert Z.n_gen == Z.dim + Z.n_con   # the old floor: nothing could be reduced
    for m in (Z.n_gen - 1, Z.n_gen - 2, 6, 3):
        R = reduce_order(Z, m)
        assert R.n_gen <= m
        assert all(R.contains(v) for v in V)
    with pytest.raises(InvalidValueError, match="at least n"):
        reduce_order(Z, 2)


def test_elimination_of_a_redundant_bound_is_exact():
    # square |x| <= 1 and the redundant slack |x1 + x2| <= 3: one constraint, removed exactly
    Z = ConstrainedZonotope([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0.0, 0.0],
                            A=[[1.0, 1.0, 1.0]], b=[0.0], h=[1.0, 1.0, 3.0])
    R = eliminate_constraints(Z, 0)
    assert R.n_con == 0
    assert as_set(R.vertices()) == {(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)}


def test_elimination_result_is_one_relaxed_set():
    """Eliminating the triangle's one constraint drops one factor's bound: the result is
    exactly one of the three parallelograms ``xi_j = 1 - sum_(k != j) xi_k``, others in
    [-1, 1] (vertices by hand)."""
    G = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    Z = ConstrainedZonotope(G, [0.0, 0.0], A=[[1.0, 1.0, 1.0]], b=[1.0])
    R = eliminate_constraints(Z, 0)
    assert R.n_con == 0
    cands = []
    for j in range(3):
        others = [k for k in range(3) if k != j]
        pts = [sum((G[:, k] - G[:, j]) * s for k, s in zip(others, signs, strict=True))
               + G[:, j] for signs in ((-1, -1), (-1, 1), (1, -1), (1, 1))]
        cands.append(as_set(np.array(pts), 5))
    assert as_set(R.vertices(), 5) in cands


def testhausdorff_heuristic_is_the_qp_of_scott_a8():
    """Eq. (A.8) solved independently with cvxpy."""
    cp = pytest.importorskip("cvxpy")
    rng = np.random.default_rng(5)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    for j in range(5):
        d = cp.Variable(5)
        D = Z.h
        prob = cp.Problem(cp.Minimize(cp.sum_squares((Z.G * D) @ d) + cp.sum_squares(d)),
                          [(Z.A * D) @ d == 0, d[j] == 0.7])
        prob.solve()
        assert hausdorff_heuristic(Z, j, 0.7) == pytest.approx(prob.value, rel=1e-5)


# ---------------------------------------------------------------- operators and the empty set
def test_negation_and_and_operators():
    Z = ConstrainedZonotope([[2.0, 0.0, 2.0], [0.0, 2.0, 2.0]], [0.0, 0.0],
                            A=[[2.0, -4.0, 2.0]], b=[0.0])
    N = -Z
    assert (N.G == -Z.G).all() and (N.c == -Z.c).all() and (N.A == Z.A).all()
    assert as_set(N.vertices()) == as_set(-Z.vertices())
    W = ConstrainedZonotope.from_box([0.0, 0.0], [5.0, 5.0])
    assert as_set((Z & W).vertices()) == as_set(Z.intersect(W).vertices())
    with pytest.raises(TypeError, match="pontryagin_difference"):
        Z - W
    with pytest.raises(TypeError):
        Z & np.ones(2)


def test_empty_set_behaves_in_every_operation():
    E = ConstrainedZonotope.empty(3)
    assert E.dim == 3 and E.is_empty()
    assert E.emptiness().witness is None
    with pytest.raises(EmptySetError):
        E.interval_hull()
    Z = ConstrainedZonotope.from_box([0, 0, 0], [1, 1, 1])
    assert (Z + E).is_empty() and (Z & E).is_empty() and (np.eye(3) @ E).is_empty()
    assert (-E).is_empty() and Z.cartesian(E).is_empty()
    with pytest.raises(InvalidValueError, match="positive integer"):
        empty_set(0)


@settings(max_examples=25, deadline=None)
@given(seeds)
def test_emptiness_witness_is_in_the_set(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng)
    rep = Z.emptiness()
    assert not rep.empty
    assert rep.witness is not None and rep.witness.shape == (Z.dim,)
    assert Z.contains(rep.witness)
    # and the witness is a convex combination of the exact points (independent check)
    P = exact_points(Z)
    if P.shape[0] > Z.dim and np.linalg.matrix_rank(P - P.mean(axis=0), tol=1e-7) == Z.dim \
            and Z.dim > 1:
        H, k = hrep_of_points(P)
        assert (H @ rep.witness <= k + 1e-6).all()


def test_witness_fraction_free_example():
    # the triangle x, y >= 0, x + y <= 2: the witness is in it
    T = ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0],
                            A=[[1.0, 1.0, 1.0]], b=[1.0])
    w = T.emptiness().witness
    assert w[0] >= -1e-9 and w[1] >= -1e-9 and w.sum() <= 2 + 1e-9


# ---------------------------------------------------------------- bad input
def test_bad_input_names_the_argument():
    from setobs.geometry import sample, volume

    Z = ConstrainedZonotope.from_box([0.0, 0.0], [1.0, 1.0])
    cases = [
        (lambda: intersect_strip(Z, [[1.0, 0.0]], [0.0], -1.0), InvalidValueError, "radius"),
        (lambda: intersect_strip(Z, [[1.0, 0.0]], [0.0, 1.0], 1.0), DimensionError, "y"),
        (lambda: intersect_polytope(Z, [[1.0, 0.0]], [0.0], E=[[1.0, 0.0]]), ArgumentError,
         "E and f"),
        (lambda: intersect_halfspace(Z, [1.0], 0.0), DimensionError, "a"),
        (lambda: intersect_halfspace(Z, [1.0, 0.0], np.nan), InvalidValueError, "beta"),
        (lambda: interval_matrix_map(Z, np.eye(2), np.eye(3)), DimensionError, "M_hi"),
        (lambda: eliminate_constraints(Z, -1), InvalidValueError, "max_constraints"),
        (lambda: sample(Z, -1), InvalidValueError, "n must be"),
        (lambda: sample(Z, 3, thin=0), InvalidValueError, "thin must be"),
        (lambda: sample(Z, 3, method="gibbs"), ValueError, "method must be"),
        (lambda: volume(Z, confidence=1.5), InvalidValueError, "confidence"),
        (lambda: from_vertices([1.0, 2.0]), DimensionError, "V"),
        (lambda: convex_hull(Z, np.eye(2)), TypeError, "ConstrainedZonotope"),
    ]
    for fn, exc, msg in cases:
        with pytest.raises(exc, match=msg):
            fn()
    with pytest.raises(UnboundedSetError, match="bounded"):
        sample(ConstrainedZonotope.full_space(2), 3)
