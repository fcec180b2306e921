"""Hybrid zonotopes against independent oracles: brute-force enumeration of the binary
assignments (each leaf built here from the data and queried through the constrained
zonotope's certified queries), pycddlib's vertex enumeration of the leaves in 2-D, and
points sampled from the operands (soundness of the operations)."""

from __future__ import annotations

import itertools
import pickle

import numpy as np
import pytest

import setobs as so
from setobs.exceptions import (
    ArgumentError,
    DimensionError,
    EmptySetError,
    ImmutableError,
    InvalidValueError,
)
from setobs.geometry import HybridZonotope, from_vertices, vertices

CZ = so.ConstrainedZonotope
REL = 1e-9  # (agreement with enumeration: 1e-9 of the set's scale)


def random_hybrid(rng, n=2, ng=4, nb=3, nc=2, spread=3.0):
    """A hybrid zonotope with at least one non-empty leaf (``b`` from a feasible point)."""
    Gc = rng.normal(size=(n, ng))
    Gb = spread * rng.normal(size=(n, nb))
    Ac = rng.normal(size=(nc, ng))
    Ab = rng.normal(size=(nc, nb))
    xi = rng.uniform(-0.6, 0.6, ng)
    beta = rng.choice([-1.0, 1.0], nb)
    b = Ac @ xi + Ab @ beta
    return HybridZonotope(Gc, Gb, rng.normal(size=n), Ac, Ab, b), (Gc, Gb, Ac, Ab, b)


@pytest.fixture(params=["compiled", "numpy"])
def set_ops(request, monkeypatch):
    """The hybrid set operations' construction: the compiled one (the default) or the
    NumPy one (the reference and the fallback); a test that takes this fixture checks
    both against its oracle."""
    if request.param == "numpy":
        import setobs.geometry.hybrid as hybrid_module

        monkeypatch.setattr(hybrid_module, "compiled_ops", None)
    return request.param


def leaves(H):
    """Every assignment's constrained zonotope, built from the public data."""
    out = []
    for v in itertools.product([-1.0, 1.0], repeat=H.n_bin):
        v = np.array(v)
        out.append((v, CZ(H.Gc, H.c + H.Gb @ v, H.Ac, H.b - H.Ab @ v, H.h)))
    return out


def enumerated_support(H, d):
    """max over the non-empty leaves of their certified support (``-inf``: all empty)."""
    best = -np.inf
    for _, L in leaves(H):
        try:
            best = max(best, L.support(d))
        except EmptySetError:
            pass
    return best


def scale(H):
    return 1.0 + np.abs(H.c).max() + np.abs(H.Gc).sum() + np.abs(H.Gb).sum()


def searches_equal_enumeration(H, d, early_limit=None):
    """Both searches' support values in direction ``d`` equal the enumerated leaves' (and
    an early stop at ``early_limit`` nodes lies above them)."""
    want = enumerated_support(H, d)
    for search in ("best", "depth"):
        got = H.support_bounds(d, search=search)
        assert got.status == "optimal"
        assert abs(got.value - want) <= REL * scale(H), (search, got, want)
        assert got.attained <= got.value
        if early_limit is not None:
            early = H.support_bounds(d, node_limit=early_limit, search=search)
            assert early.value >= want - REL * scale(H)


@pytest.mark.parametrize("seed", range(6))
def test_support_and_hull_equal_enumeration(seed):
    rng = np.random.default_rng(seed)
    H, _ = random_hybrid(rng, n=3, ng=5, nb=4, nc=2)
    s = scale(H)
    for _ in range(4):
        searches_equal_enumeration(H, rng.normal(size=3))
    box = H.interval_hull()
    for i in range(3):
        e = np.eye(3)[i]
        assert abs(box.hi[i] - enumerated_support(H, e)) <= REL * s
        assert abs(box.lo[i] + enumerated_support(H, -e)) <= REL * s


def test_ten_binary_factors_agree_with_the_1024_leaves():
    rng = np.random.default_rng(11)
    H, _ = random_hybrid(rng, n=2, ng=6, nb=10, nc=3, spread=1.0)
    d = np.array([0.6, -0.8])
    got = H.support_bounds(d)
    assert got.status == "optimal"
    assert abs(got.value - enumerated_support(H, d)) <= REL * scale(H)
    # the search needs far fewer LPs than the leaves
    assert got.nodes < 2 ** 10


@pytest.mark.parametrize("seed", range(8))
def test_early_stops_are_outer(seed):
    rng = np.random.default_rng(100 + seed)
    H, _ = random_hybrid(rng, n=2, ng=4, nb=6, nc=3)
    d = rng.normal(size=2)
    # a value the set attains: a leaf's LP maximiser (a point of the leaf)
    attained = max(float(d @ L.support_point(d)) for _, L in leaves(H) if not L.is_empty())
    exact = enumerated_support(H, d)
    for limit in (1, 2, 3, 5):
        for search in ("best", "depth"):
            out = H.support_bounds(d, node_limit=limit, search=search)
            assert out.value >= attained - 1e-12 * scale(H), (limit, search, out)
            if out.status != "optimal":
                assert out.value >= exact - REL * scale(H)
                assert out.gap >= 0.0
    out = H.support_bounds(d, time_limit=1e-9)
    assert out.value >= exact - REL * scale(H)
    assert out.status in ("optimal", "time_limit")


@pytest.mark.parametrize("seed", range(10))
def test_emptiness_and_containment_equal_enumeration(seed):
    rng = np.random.default_rng(200 + seed)
    n, ng, nb, nc = 2, 3, 4, 3
    Gc, Gb = rng.normal(size=(n, ng)), 2.0 * rng.normal(size=(n, nb))
    Ac, Ab = rng.normal(size=(nc, ng)), rng.normal(size=(nc, nb))
    # half of the cases: b at a feasible point; the others random (often every leaf empty)
    if seed % 2:
        b = Ac @ rng.uniform(-0.5, 0.5, ng) + Ab @ rng.choice([-1.0, 1.0], nb)
    else:
        b = 3.0 * rng.normal(size=nc)
    H = HybridZonotope(Gc, Gb, np.zeros(n), Ac, Ab, b)
    L = leaves(H)
    nonempty = [Z for _, Z in L if not Z.is_empty()]
    rep = H.emptiness()
    assert rep.empty == (not nonempty)
    if rep.empty:
        with pytest.raises(EmptySetError):
            H.support([1.0, 0.0])
    else:
        # the witness is in some leaf
        assert any(Z.contains(rep.witness, tol=1e-7) for Z in nonempty)
    # containment at points of the leaves and at random points
    pts = [Z.sample(3, rng=rng) for Z in nonempty[:3]]
    pts.append(rng.normal(scale=3.0, size=(6, n)))
    for x in np.vstack(pts):
        want = any(Z.contains(x) for Z in nonempty)
        assert H.contains(x) == want


def test_union_is_the_operands_and_its_relaxation_their_convex_hull(set_ops):
    rng = np.random.default_rng(3)
    ops = [CZ(rng.normal(size=(2, 3)), 4.0 * rng.normal(size=2),
              rng.normal(size=(1, 3)), rng.uniform(-0.3, 0.3, 1)) for _ in range(5)]
    U = HybridZonotope.from_union(ops)
    assert U.n_bin == 5
    for _ in range(6):
        d = rng.normal(size=2)
        want = max(Z.support(d) for Z in ops)
        assert abs(U.support(d) - want) <= REL * 20
        # sharp: the relaxation's support is the convex hull's, max over the operands
        assert abs(U.relaxation.support(d) - want) <= REL * 20
    for Z in ops:
        for x in Z.sample(5, rng=rng):
            assert U.contains(x)
    for x in rng.normal(scale=6.0, size=(20, 2)):
        assert U.contains(x) == any(Z.contains(x) for Z in ops)
    # the leaves: one per operand (the other assignments violate the selector's row)
    assert len(U.to_constrained_zonotopes()) == 5


def test_leaves_of_a_union_of_polygons_have_the_polygons_vertices():
    """pycddlib's vertex enumeration of each leaf against the polygons given."""
    rng = np.random.default_rng(4)
    polys = []
    for k in range(4):
        t = np.sort(rng.uniform(0, 2 * np.pi, 5))
        polys.append(np.column_stack([np.cos(t), np.sin(t)]) + np.array([3.0 * k, (-1) ** k]))
    U = HybridZonotope.from_vertices(polys)
    got = [vertices(L) for L in U.to_constrained_zonotopes()]
    assert len(got) == 4
    for P in polys:
        matches = [V for V in got if V.shape == P.shape
                   and np.abs(np.sort(V, axis=0) - np.sort(P, axis=0)).max() < 1e-7]
        assert len(matches) == 1


def test_union_of_hybrid_zonotopes_enumerates_to_all_their_leaves(set_ops):
    rng = np.random.default_rng(5)
    H1, _ = random_hybrid(rng, n=2, ng=3, nb=2, nc=1)
    H2, _ = random_hybrid(rng, n=2, ng=2, nb=3, nc=2)
    Z3 = CZ.from_box([5.0, 5.0], [6.0, 7.0])
    U = H1 | H2 | Z3
    s = scale(H1) + scale(H2) + 10.0
    for _ in range(5):
        d = rng.normal(size=2)
        want = max(enumerated_support(H1, d), enumerated_support(H2, d), Z3.support(d))
        assert abs(U.support(d) - want) <= REL * s


def test_operations_agree_with_enumeration_of_the_operands(set_ops):
    rng = np.random.default_rng(6)
    H1, _ = random_hybrid(rng, n=2, ng=3, nb=2, nc=1)
    H2, _ = random_hybrid(rng, n=2, ng=3, nb=2, nc=1)
    M = rng.normal(size=(3, 2))
    L1 = [Z for _, Z in leaves(H1) if not Z.is_empty()]
    L2 = [Z for _, Z in leaves(H2) if not Z.is_empty()]
    s = 10 * (scale(H1) + scale(H2))
    for _ in range(3):
        d3, d2 = rng.normal(size=3), rng.normal(size=2)
        assert abs((M @ H1).support(d3) - max((M @ Z).support(d3) for Z in L1)) <= REL * s
        assert abs((H1 + H2).support(d2)
                   - max(Z.support(d2) + W.support(d2) for Z in L1 for W in L2)) <= REL * s
        dd = rng.normal(size=4)
        assert abs(H1.cartesian(H2).support(dd)
                   - max(Z.cartesian(W).support(dd) for Z in L1 for W in L2)) <= REL * s
    B = CZ.from_box([-1.0, -1.0], [1.0, 1.0])
    cut = H1 & B
    pairs = [Z & B for Z in L1]
    live = [Z for Z in pairs if not Z.is_empty()]
    assert cut.is_empty() == (not live)
    if live:
        d2 = rng.normal(size=2)
        assert abs(cut.support(d2) - max(Z.support(d2) for Z in live)) <= REL * s


def test_random_chains_never_lose_a_sampled_point(set_ops):
    rng = np.random.default_rng(7)
    for trial in range(4):
        ops = [CZ(rng.normal(size=(2, 3)), 3.0 * rng.normal(size=2)) for _ in range(3)]
        U = HybridZonotope.from_union(ops)
        W = CZ(0.5 * rng.normal(size=(2, 2)), rng.normal(size=2))
        M = rng.normal(size=(2, 2))
        a, beta = rng.normal(size=2), 0.5
        chain = (M @ (U + W)).intersect_halfspace(a, beta)
        for _ in range(15):
            p = ops[rng.integers(3)].sample(1, rng=rng)[0]
            q = W.sample(1, rng=rng)[0]
            z = M @ (p + q)
            if a @ z <= beta - 1e-9:
                assert chain.contains(z), trial
        box = chain.interval_hull() if not chain.is_empty() else None
        if box is not None:
            # the hull contains the hull of the sampled points that passed the cut
            assert np.all(box.lo <= box.hi)


def test_halfspace_and_polytope_cuts_equal_enumeration(set_ops):
    rng = np.random.default_rng(8)
    polys = [rng.normal(size=(6, 2)) + np.array([4.0 * k, 0.0]) for k in range(3)]
    U = HybridZonotope.from_vertices(polys)
    Hm = np.array([[1.0, 0.0], [0.0, 1.0]])
    k = np.array([5.0, 0.2])
    cut = U.intersect_polytope(Hm, k)
    pieces = [from_vertices(P).intersect_polytope(Hm, k) for P in polys]
    live = [Z for Z in pieces if not Z.is_empty()]
    for _ in range(4):
        d = rng.normal(size=2)
        assert abs(cut.support(d) - max(Z.support(d) for Z in live)) <= 1e-8
    # a cut that misses everything is empty; one that keeps everything returns the set
    assert U.intersect_halfspace([1.0, 0.0], -100.0).is_empty()
    assert U.intersect_halfspace([1.0, 0.0], 100.0) is U


def test_bad_input_and_conventions():
    with pytest.raises(DimensionError, match="Gc"):
        HybridZonotope(np.eye(3), [[1.0], [0.0]], [0.0, 0.0])
    with pytest.raises(ArgumentError, match="together"):
        HybridZonotope(np.eye(2), [[1.0], [0.0]], [0.0, 0.0], Ac=[[1.0, 0.0]])
    with pytest.raises(DimensionError):
        HybridZonotope(np.eye(2), [[1.0], [0.0]], [0.0, 0.0], Ac=[[1.0, 0.0, 1.0]], b=[0.0])
    with pytest.raises(InvalidValueError, match="h must be nonnegative"):
        HybridZonotope(np.eye(2), [[1.0], [0.0]], [0.0, 0.0], h=[1.0, -1.0])
    with pytest.raises(ArgumentError, match="at least one"):
        HybridZonotope.from_union([])
    with pytest.raises(ArgumentError, match="unbounded"):
        HybridZonotope.from_union([CZ(np.eye(2), [0.0, 0.0], h=[np.inf, 1.0]),
                                   CZ.from_box([0, 0], [1, 1])])
    with pytest.raises(DimensionError, match="dimension"):
        HybridZonotope.from_union([CZ.from_box([0], [1]), CZ.from_box([0, 0], [1, 1])])
    with pytest.raises(ArgumentError, match="hybrid or constrained"):
        HybridZonotope.from_union([np.eye(2)])
    H = HybridZonotope(np.eye(2), [[2.0], [0.0]], [0.0, 0.0])
    with pytest.raises(ImmutableError):
        H.c = np.zeros(2)
    with pytest.raises(ArgumentError, match="search"):
        H.support_bounds([1.0, 0.0], search="breadth")
    with pytest.raises(InvalidValueError, match="node_limit"):
        H.support_bounds([1.0, 0.0], node_limit=0)
    with pytest.raises(InvalidValueError, match="time_limit"):
        H.support_bounds([1.0, 0.0], time_limit=-1.0)
    with pytest.raises(InvalidValueError, match="tol"):
        H.emptiness(tol=float("nan"))
    with pytest.raises(InvalidValueError, match="node_limit"):
        H.emptiness(node_limit=0)
    H2 = pickle.loads(pickle.dumps(H))
    assert np.array_equal(H2.Gb, H.Gb) and np.array_equal(H2.binary, H.binary)
    # unbounded continuous factors are allowed; the support is then +inf where they reach
    Hu = HybridZonotope(np.eye(2), [[2.0], [0.0]], [0.0, 0.0], h=[np.inf, 1.0])
    assert Hu.support([1.0, 0.0]) == np.inf
    assert abs(Hu.support([0.0, 1.0]) - 1.0) < 1e-9


def test_pwa_reachable_sets_equal_the_union_over_mode_sequences(set_ops):
    """The reachable sets of a two-mode piecewise-affine system (a set that straddles the
    switching line) against the sets of every mode sequence, propagated one by one."""
    from setobs.geometry import pwa_reachable_sets

    def rot(t):
        return np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])

    P1, P2 = CZ.from_box([-4.0, -4.0], [0.0, 4.0]), CZ.from_box([0.0, -4.0], [4.0, 4.0])
    modes = [(P1, 0.95 * rot(1.2), [0.4, 0.0]), (P2, 0.9 * rot(-0.9), [-0.5, 0.1])]
    X0 = CZ.from_box([-1.0, -0.5], [1.0, 0.5])
    W = CZ.from_box([-0.05, -0.05], [0.05, 0.05])
    K = 4
    Xs = pwa_reachable_sets(modes, X0, K, disturbance=W)
    assert len(Xs) == K + 1
    # linear growth: each step adds the graph's factors once
    assert Xs[2].n_bin - Xs[1].n_bin == Xs[4].n_bin - Xs[3].n_bin == 2
    rng = np.random.default_rng(9)
    for k in (1, 2, 4):
        seqs = []
        for sig in itertools.product(range(2), repeat=k):
            S = X0
            for m in sig:
                P, A, f = modes[m]
                S = A @ (S & P) + np.asarray(f) + W
            if not S.is_empty():
                seqs.append(S)
        assert len(seqs) >= 2
        for _ in range(4):
            d = rng.normal(size=2)
            want = max(S.support(d) for S in seqs)
            assert abs(Xs[k].support(d) - want) <= 1e-8, k
    # a point simulated forward (the truth) is inside
    x = np.array([0.3, -0.2])
    for k in range(1, K + 1):
        m = 0 if x[0] <= 0.0 else 1
        _, A, f = modes[m]
        x = A @ x + np.asarray(f) + rng.uniform(-0.05, 0.05, 2)
        assert Xs[k].contains(x)
    with pytest.raises(ArgumentError, match="at least one mode"):
        pwa_reachable_sets([], X0, 2)
    with pytest.raises(DimensionError):
        pwa_reachable_sets([(CZ.from_box([0], [1]), [[1.0]], [0.0])], X0, 2)
    with pytest.raises(InvalidValueError, match="steps"):
        pwa_reachable_sets(modes, X0, -1)


def test_projection_equals_the_leaves_projections(set_ops):
    rng = np.random.default_rng(10)
    H, _ = random_hybrid(rng, n=3, ng=4, nb=3, nc=2)
    Hp = H.project([2, 0])
    L = [Z.project([2, 0]) for _, Z in leaves(H) if not Z.is_empty()]
    for _ in range(3):
        d = rng.normal(size=2)
        assert abs(Hp.support(d) - max(Z.support(d) for Z in L)) <= REL * scale(H)


def _supports_agree_with_leaves(R, live, rng, dirs=6, tol=1e-8):
    """``R``'s support equals the max over the constrained zonotopes ``live`` (and is
    never below it) in random directions."""
    for _ in range(dirs):
        d = rng.normal(size=R.dim)
        want = max(Z.support(d) for Z in live)
        got = R.support(d)
        assert got >= want - 1e-12 * (1.0 + abs(want))
        assert got - want <= tol, (got, want)


def test_remove_redundancy_fixes_the_binaries_a_cut_decides():
    """Four squares in a row, cut at x <= 4.5: the two on the right are gone, so their
    selectors are fixed (and their copies pinned); the leaves are the two squares left."""
    rng = np.random.default_rng(31)
    sets = [CZ.from_box([3.0 * i - 1, -1.0], [3.0 * i + 1, 1.0]) for i in range(4)]
    H = HybridZonotope.from_union(sets).intersect_halfspace([1.0, 0.0], 4.5)
    R = H.remove_redundancy()
    assert R.n_bin == 2 and H.n_bin == 4
    assert R.n_cont < H.n_cont and R.n_con < H.n_con
    live = [Z.intersect_halfspace([1.0, 0.0], 4.5) for Z in sets[:2]]
    _supports_agree_with_leaves(R, live, rng)
    # the leaves left: the squares at 0 and 3, each a box ([-1, 1] or [2, 4] on x)
    boxes = sorted((Z.interval_hull().lo[0], Z.interval_hull().hi[0])
                   for Z in R.to_constrained_zonotopes())
    assert np.allclose(boxes, [(-1.0, 1.0), (2.0, 4.0)], atol=1e-9)
    # a cut that leaves one square: no binary left, the set is that square
    R1 = HybridZonotope.from_union(sets).intersect_halfspace([1.0, 0.0], 1.5).remove_redundancy()
    assert R1.n_bin == 0
    assert np.allclose(R1.interval_hull().lo, [-1.0, -1.0], atol=1e-9)
    assert np.allclose(R1.interval_hull().hi, [1.0, 1.0], atol=1e-9)


def test_remove_redundancy_drops_unused_parts_dependent_rows_and_implied_bounds():
    rng = np.random.default_rng(32)
    H, (Gc, Gb, Ac, Ab, b) = random_hybrid(rng, n=2, ng=4, nb=3, nc=2)
    live = [Z for _, Z in leaves(H) if not Z.is_empty()]
    # a binary factor that appears nowhere, a zero continuous factor, a repeated row
    # (twice the first), and a continuous factor with a bound the rows imply: x5 = 0.3 x1
    # in a new row (|x5| <= 0.3 < 1, so its bound is redundant and it is eliminated)
    n = 2
    Gc2 = np.hstack([Gc, np.zeros((n, 1)), rng.normal(size=(n, 1))])
    Gb2 = np.hstack([Gb, rng.normal(size=(n, 1))])  # used in G only: kept (it matters)
    Gb3 = np.hstack([Gb2, np.zeros((n, 1))])  # nowhere: dropped
    Ac2 = np.vstack([np.hstack([Ac, np.zeros((2, 2))]), 2.0 * np.hstack([Ac[:1], [[0, 0]]]),
                     np.hstack([[[0.3, 0, 0, 0]], [[0.0, -1.0]]])])
    Ab3 = np.vstack([np.hstack([Ab, np.zeros((2, 2))]), np.hstack([2.0 * Ab[:1], [[0, 0]]]),
                     np.zeros((1, 5))])
    b3 = np.concatenate([b, 2.0 * b[:1], [0.0]])
    # (x6 = 0.3 x1 enters G: the set changes, and the oracle below is built from it)
    H3 = HybridZonotope(Gc2, Gb3, H.c, Ac2, Ab3, b3)
    R = H3.remove_redundancy()
    assert R.n_bin == 4  # the unused binary factor is gone, the one in G stays
    assert R.n_con <= 2  # the repeated row and the implied row are gone
    assert R.n_cont <= 4  # the zero factor and the eliminated one
    live3 = [Z for _, Z in leaves(H3) if not Z.is_empty()]
    assert len(live3) >= 2
    _supports_agree_with_leaves(R, live3, rng)
    # and the untouched random set keeps its support
    _supports_agree_with_leaves(H.remove_redundancy(), live, rng)


@pytest.mark.parametrize("seed", range(6))
def test_remove_redundancy_keeps_the_leaves_of_random_sets(seed):
    rng = np.random.default_rng(400 + seed)
    H, _ = random_hybrid(rng, n=2, ng=4, nb=5, nc=3)
    # cut through the set so that some assignments die
    d0 = rng.normal(size=2)
    H = H.intersect_halfspace(d0, 0.5 * (H.support(d0) - H.support(-d0)))
    live = [Z for _, Z in leaves(H) if not Z.is_empty()]
    R = H.remove_redundancy()
    assert R.n_bin <= H.n_bin and R.n_con <= H.n_con
    _supports_agree_with_leaves(R, live, rng, tol=REL * scale(H))
    got = [Z for Z in R.to_constrained_zonotopes() if not Z.is_empty()]
    assert len(got) == len(live)  # (the fixed binaries removed only empty leaves)
    for x in np.vstack([Z.sample(3, rng=rng) for Z in live]):
        assert R.contains(x, tol=1e-7)


def test_remove_redundancy_of_an_empty_set_is_the_empty_set():
    sets = [CZ.from_box([3.0 * i - 1, -1.0], [3.0 * i + 1, 1.0]) for i in range(3)]
    U = HybridZonotope.from_union(sets)
    # each cut keeps the relaxation (the convex hull) but no square: x in [1.5, 1.8]
    H = U.intersect_halfspace([1.0, 0.0], 1.8).intersect_halfspace([-1.0, 0.0], -1.5)
    assert H.is_empty()
    R = H.remove_redundancy()
    assert R.is_empty() and R.n_bin == 0


def test_a_pinned_factor_keeps_its_range_outward():
    """``x2 + x3 = 2 - 1e-12`` with ``|x2|, |x3| <= 1`` pins both to ``[1 - 1e-12, 1]`` (at
    their bounds, so they cannot be eliminated) while ``x2``'s generator is ``1e6``: the
    set is ``[-1, 1] + 1e6 [1 - 1e-12, 1] + {-2, 2}`` (closed form), and the reduced set's
    supports must reach its ends (the pinned range carried in the centre's error)."""
    delta = 1e-12
    H = HybridZonotope([[1.0, 1e6, 0.0]], [[2.0]], [0.0], [[0.0, 1.0, 1.0]], [[0.0]],
                       [2.0 - delta])
    R = H.remove_redundancy()
    assert (R.n_cont, R.n_con, R.n_bin) == (1, 0, 1)
    hi, lo = 1.0 + 1e6 + 2.0, -1.0 + 1e6 * (1.0 - delta) - 2.0
    assert hi <= R.support([1.0]) <= hi + 1e-6
    assert -lo <= R.support([-1.0]) <= -lo + 1e-6


@pytest.mark.parametrize("rows", [0, 10_000])
def test_both_node_engines_equal_enumeration(rows, monkeypatch):
    """The searches' nodes on one warm model: HiGHS's (forced here by a row limit of 0;
    emptiness then on each node's own constrained zonotope) and the compiled dual
    simplex's (limit above every set's rows) agree with the leaves, on random sets cut so
    that some assignments are infeasible: support values, early stops, emptiness and
    containment."""
    import setobs.geometry.hybrid as hybrid_module

    monkeypatch.setattr(hybrid_module, "NODE_COMPILED_MAX_ROWS", rows)
    rng = np.random.default_rng(77)
    for _ in range(3):
        H, _ = random_hybrid(rng, n=3, ng=5, nb=5, nc=3)
        d0 = rng.normal(size=3)
        H = H.intersect_halfspace(d0, 0.5 * (H.support(d0) - H.support(-d0)))
        for _ in range(3):
            searches_equal_enumeration(H, rng.normal(size=3), early_limit=2)
        # emptiness and containment on the same nodes, against the leaves
        live = [Z for _, Z in leaves(H) if not Z.is_empty()]
        assert H.emptiness().empty == (not live)
        pts = [Z.sample(2, rng=rng) for Z in live[:3]] + [rng.normal(scale=3.0, size=(4, 3))]
        for x in np.vstack(pts):
            assert H.contains(x) == any(Z.contains(x) for Z in live)
    # a set every node of which is empty (the cut misses every leaf's box)
    sets = [CZ.from_box([3.0 * i - 1, -1.0], [3.0 * i + 1, 1.0]) for i in range(3)]
    E = HybridZonotope.from_union(sets).intersect_halfspace([1.0, 0.0], 1.8)
    E = E.intersect_halfspace([-1.0, 0.0], -1.5)
    rep = E.emptiness()
    assert rep.empty and rep.status == "empty"


def test_a_union_keeps_its_operands_rounding_bounds(set_ops):
    """Operands that carry centre and right-hand-side uncertainty (``c_err``, ``b_err``,
    made large here so that they show): the union's supports must reach each operand's
    certified support, which widens by them (the operands' own queries are the oracle)."""
    from setobs.geometry.zonotope import trusted_cz

    rng = np.random.default_rng(12)
    G, A = rng.normal(size=(2, 4)), rng.normal(size=(1, 4))
    b = A @ rng.uniform(-0.5, 0.5, 4)
    Z1 = trusted_cz(G, np.zeros(2), A, b, np.ones(4), cerr=np.array([0.3, 0.0]))
    Z2 = trusted_cz(G, np.array([5.0, 0.0]), A, b, np.ones(4), berr=np.array([0.2]))
    U = HybridZonotope.from_union([Z1, Z2])
    for d in rng.normal(size=(8, 2)):
        want = max(Z1.support(d), Z2.support(d))
        got = U.support(d)
        assert got >= want - 1e-12 * (1.0 + abs(want)), (d, got, want)
        # (outer by at most the other operand's uncertainty)
        assert got <= want + 0.3 * np.abs(d).sum() + 1e-9


def test_the_compiled_and_numpy_constructions_build_the_same_sets(monkeypatch):
    """The compiled union, Minkowski sum and generalised intersection against the NumPy
    construction (the reference) on operands of every kind (constrained zonotopes with and
    without rows, hybrid ones with binaries, rounding bounds on centres and right-hand
    sides): the same relaxation entry for entry (to the order of the sums), the same
    binary flags, rounding bounds within a few units of each other and both nonnegative."""
    import setobs.geometry.hybrid as hybrid_module
    from setobs.geometry.zonotope import trusted_cz

    rng = np.random.default_rng(31)
    H1, _ = random_hybrid(rng, n=3, ng=4, nb=2, nc=2)
    H2, _ = random_hybrid(rng, n=3, ng=2, nb=1, nc=1)
    G, A = rng.normal(size=(3, 4)), rng.normal(size=(2, 4))
    Z1 = trusted_cz(G, rng.normal(size=3), A, A @ rng.uniform(-0.5, 0.5, 4), np.ones(4),
                    cerr=np.array([1e-9, 0.0, 2e-9]), berr=np.array([0.0, 3e-9]))
    Z2 = CZ(rng.normal(size=(3, 2)), rng.normal(size=3))
    M = rng.normal(size=(3, 3))

    def build():
        U = HybridZonotope.from_union([H1, Z1, Z2, H2])
        return [U, U + Z1, U + H2, U & Z1, H1.intersect(H2, M), (M @ U).intersect(Z2, M)]

    compiled = build()
    monkeypatch.setattr(hybrid_module, "compiled_ops", None)
    reference = build()
    for X, Y in zip(compiled, reference, strict=True):
        RX, RY = X.relaxation, Y.relaxation
        assert np.array_equal(X.binary, Y.binary)
        for a, b in ((RX.G, RY.G), (RX.c, RY.c), (RX.A, RY.A), (RX.b, RY.b), (RX.h, RY.h)):
            assert a.shape == b.shape
            assert np.allclose(a, b, rtol=1e-13, atol=1e-13 * (1.0 + np.abs(b).max(initial=0)))
        for a, b in ((RX.c_err, RY.c_err), (RX.b_err, RY.b_err)):
            assert (a >= 0).all() and (b >= 0).all()
            assert np.allclose(a, b, rtol=1e-6, atol=1e-30)


def test_a_union_whose_data_would_overflow_is_refused():
    """The union scales a copy's generator by its factor's bound (``-h_j G_j``): data of
    1e100 each give 1e200, above MAX_MAGNITUDE, which the data guard refuses (with the
    compiled construction too: it hands over to the NumPy one, which raises)."""
    from setobs.exceptions import MagnitudeError

    big = CZ(1e100 * np.eye(2), np.zeros(2), h=[1e100, 1e100])
    with pytest.raises(MagnitudeError, match="union"):
        HybridZonotope.from_union([big, CZ.from_box([0.0, 0.0], [1.0, 1.0])])


def test_the_compiled_hybrid_operations_leak_no_reference_or_memory():
    """The compiled union, sum and intersection read their operands' arrays by slot and
    build new objects: the operands' arrays keep their reference counts, and thousands of
    rounds keep no memory."""
    import sys
    import tracemalloc

    from setobs.geometry.zonotope import trusted_cz

    rng = np.random.default_rng(41)
    H, _ = random_hybrid(rng, n=3, ng=3, nb=2, nc=2)
    G, A = rng.normal(size=(3, 3)), rng.normal(size=(1, 3))
    Z = trusted_cz(G, rng.normal(size=3), A, A @ rng.uniform(-0.5, 0.5, 3), np.ones(3),
                   cerr=np.full(3, 1e-9), berr=np.array([1e-9]))
    R = rng.normal(size=(3, 3))
    shared = [H.c, H.b, H.binary, Z.G, Z.c, Z.A, Z.b, Z.c_err, Z.b_err, R]
    before = [sys.getrefcount(x) for x in shared]

    def run(k):
        for _ in range(k):
            U = HybridZonotope.from_union([H, Z, H])
            U + Z
            U + H
            U.intersect(Z, R)
            H & U.project([0, 1, 2])

    run(10)
    tracemalloc.start()
    run(100)
    first, _ = tracemalloc.get_traced_memory()
    run(1000)
    second, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert [sys.getrefcount(x) for x in shared] == before
    assert second - first < 20_000


def test_a_hybrid_class_layout_the_extension_does_not_write_is_refused():
    """The compiled hybrid operations write HybridZonotope's and its rows' slots by offset:
    a class with another slot is refused at binding, and the binding in force stays."""
    import setobs.geometry.hybrid as hybrid_module

    ops = hybrid_module.compiled_ops
    if ops is None:
        pytest.skip("no compiled extension")
    names = HybridZonotope.__slots__
    extra = type("WithExtra", (), {"__slots__": (*names, "_extra")})
    with pytest.raises(TypeError, match="slot _extra"):
        ops.bind_hybrid(extra, extra)
    # the binding in force is unchanged: a compiled union sets every slot
    U = HybridZonotope.from_union([CZ.point([0.0]), CZ.point([1.0])])
    for name in names:
        getattr(U, name)  # (AttributeError if the extension left a slot unset)
    assert U.contains([1.0]) and not U.contains([0.5])
