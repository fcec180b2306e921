"""Interval hull, support function, emptiness and containment against independent oracles."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from setobs import ConstrainedZonotope, EmptySetError
from tests.conftest import cdd_vertices, exact_extremes, random_cz, sample_points

seeds = st.integers(0, 2**32 - 1)


def assert_hull_never_inside(Z, box):
    """Exact rational comparison: the certified box is never inside the true set."""
    for i in range(Z.dim):
        e = np.zeros(Z.dim)
        e[i] = 1.0
        lo_exact, hi_exact = exact_extremes(Z, e)
        assert Fraction(float(box.lo[i])) <= lo_exact
        assert Fraction(float(box.hi[i])) >= hi_exact


@given(seeds)
def test_interval_hull_equals_vertex_box_and_is_never_inside(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng)
    box = Z.interval_hull()
    V = cdd_vertices(Z)
    scale = 1.0 + np.abs(V).max()
    np.testing.assert_allclose(box.lo, V.min(axis=0), atol=1e-7 * scale)
    np.testing.assert_allclose(box.hi, V.max(axis=0), atol=1e-7 * scale)
    assert_hull_never_inside(Z, box)


@given(seeds)
def test_support_equals_vertex_maximum_and_is_never_below(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng)
    V = cdd_vertices(Z)
    for _ in range(3):
        d = rng.normal(size=Z.dim)
        s = Z.support(d)
        vmax = float((V @ d).max())
        assert s == pytest.approx(vmax, abs=1e-7 * (1 + abs(vmax)))
        assert Fraction(float(s)) >= exact_extremes(Z, d)[1]


@given(seeds)
def test_badly_scaled_sets_remain_certified(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, scale=10.0 ** rng.uniform(-6, 6))
    box = Z.interval_hull()
    assert_hull_never_inside(Z, box)
    for i in range(Z.dim):
        e = np.zeros(Z.dim)
        e[i] = 1.0
        lo_exact, hi_exact = exact_extremes(Z, e)
        width = float(hi_exact - lo_exact) + 1e-300
        assert float(box.hi[i] - box.lo[i]) <= width * (1 + 1e-6) + 1e-9 * float(
            abs(hi_exact) + abs(lo_exact))


def test_zonotope_hull_is_analytic():
    Z = ConstrainedZonotope([[1.0, 2.0], [0.0, -1.0]], [1.0, 0.0], h=[1.0, 0.5])
    box = Z.interval_hull()
    np.testing.assert_allclose(box.lo, [-1.0, -0.5])
    np.testing.assert_allclose(box.hi, [3.0, 0.5])


def test_interval_hull_of_triangle_closed_form():
    # {xi in [-1,1]^3 : xi1 + xi2 + xi3 = 1} mapped by x = (xi1 + xi3, xi2 + xi3): triangle
    # with vertices (0,0), (2,0), (0,2) -> hull [0,2]^2.
    Z = ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0],
                            A=[[1.0, 1.0, 1.0]], b=[1.0])
    box = Z.interval_hull()
    np.testing.assert_allclose(box.lo, [0.0, 0.0], atol=1e-12)
    np.testing.assert_allclose(box.hi, [2.0, 2.0], atol=1e-12)
    assert box.lo[0] <= 0.0 and box.hi[0] >= 2.0
    assert Z.support([1.0, 1.0]) == pytest.approx(2.0, abs=1e-12)
    assert Z.support([-1.0, 0.0]) == pytest.approx(0.0, abs=1e-12)


# --------------------------------------------------------------------- unbounded factors
def test_full_space():
    R3 = ConstrainedZonotope.full_space(3)
    box = R3.interval_hull()
    assert np.all(box.lo == -np.inf) and np.all(box.hi == np.inf)
    assert R3.support([0.0, 1.0, 0.0]) == np.inf
    assert 0.0 <= R3.support([0.0, 0.0, 0.0]) < 1e-290  # certified: outward underflow guard
    assert not R3.is_bounded and not R3.is_empty()
    assert R3.contains([1e6, -3.0, 2.0])


def test_slab_mixed_bounded_unbounded_hull():
    S = ConstrainedZonotope.from_box([-1.0, -np.inf], [1.0, np.inf])
    box = S.interval_hull()
    assert box.lo[0] == pytest.approx(-1.0) and box.hi[0] == pytest.approx(1.0)
    assert box.lo[1] == -np.inf and box.hi[1] == np.inf
    assert S.support([1.0, 0.0]) == pytest.approx(1.0)
    assert S.support([1.0, 1e-3]) == np.inf
    assert np.isnan(box.center[1])
    # Projections: one coordinate is bounded, the other is the whole line.
    assert S.project([0]).is_bounded
    assert not S.project([1]).is_bounded


def test_affine_set_is_a_point_or_a_line():
    C = np.array([[1.0, 1.0, 0.0], [0.0, 1.0, 1.0], [1.0, 0.0, 0.0]])
    y = np.array([1.0, 2.0, 3.0])
    P = ConstrainedZonotope.affine_set(C, y)
    z = np.linalg.solve(C, y)
    box = P.interval_hull()
    assert P.is_bounded
    assert np.all(box.lo <= z) and np.all(box.hi >= z)
    np.testing.assert_allclose(box.lo, z, atol=1e-9)
    np.testing.assert_allclose(box.hi, z, atol=1e-9)
    L = ConstrainedZonotope.affine_set(C[:2], y[:2])  # a line along (1, -1, 1)
    assert L.support([1.0, -1.0, 1.0]) == np.inf
    # Orthogonal to the line: the support is the (constant) value d^T z on the line.
    d = np.array([1.0, 1.0, 0.0])  # = row 0 of C
    assert L.support(d) == pytest.approx(1.0, abs=1e-9)
    assert L.support(d) >= 1.0
    assert -L.support(-d) <= 1.0


def test_unbounded_disturbance_pinned_by_measurements():
    """The paper's pattern: box x R^q, mapped and intersected, becomes bounded."""
    rng = np.random.default_rng(3)
    X = ConstrainedZonotope.from_box([-1, -1], [1, 1]).cartesian(
        ConstrainedZonotope.full_space(1))
    M = np.array([[1.0, 0.1, 0.0], [0.0, 1.0, 0.1], [0.0, 0.0, 1.0]])
    Z = (M @ X).intersect_affine([[0.0, 1.0, 0.0]], [0.3])
    box = Z.interval_hull()
    # Closed form: x2' = x2 + 0.1 d = 0.3, x2 in [-1, 1] -> d in [-7, 13].
    assert box.lo[2] == pytest.approx(-7.0, abs=1e-9) and box.lo[2] <= -7.0
    assert box.hi[2] == pytest.approx(13.0, abs=1e-9) and box.hi[2] >= 13.0
    # Sampled feasible points (free factor = d) lie in the certified box.
    for _ in range(200):
        x = rng.uniform(-1, 1, 2)
        d = (0.3 - x[1]) / 0.1
        z = M @ np.array([x[0], x[1], d])
        assert box.contains(z)
        assert Z.contains(z, tol=1e-9)


def test_unbounded_factors_sampled_soundness(rng):
    """Random sets with free factors pinned by constraints: sampled points in the hull."""
    for _ in range(20):
        n, n_b, n_u = 3, 4, 2
        G = rng.normal(size=(n, n_b + n_u))
        c = rng.normal(size=n)
        A = rng.normal(size=(n_u + 1, n_b + n_u))
        h = np.concatenate([rng.uniform(0.5, 1.5, n_b), np.full(n_u, np.inf)])
        xi0 = np.concatenate([rng.uniform(-0.5, 0.5, n_b) * h[:n_b], rng.normal(size=n_u)])
        Z = ConstrainedZonotope(G, c, A, A @ xi0, h)
        box = Z.interval_hull()
        assert box.is_bounded  # n_u + 1 generic rows pin the free factors
        Au = A[:, n_b:]
        Ab = A[:, :n_b]
        # Parametrise feasible points: choose xi_b, solve for xi_u, keep if consistent.
        for _ in range(300):
            xb = rng.uniform(-1, 1, n_b) * h[:n_b]
            xu, *_ = np.linalg.lstsq(Au, A @ xi0 - Ab @ xb, rcond=None)
            if np.abs(Ab @ xb + Au @ xu - A @ xi0).max() < 1e-12:
                z = G @ np.concatenate([xb, xu]) + c
                assert box.contains(z, tol=1e-9)


# --------------------------------------------------------------------- emptiness
@pytest.mark.parametrize(
    ("A", "b", "h", "empty"),
    [
        ([[1.0], [1.0]], [0.5, 0.6], [1.0], True),  # contradictory duplicates
        ([[1.0], [1.0]], [0.5, 0.5], [1.0], False),  # consistent duplicates
        ([[1.0, 1.0], [2.0, 2.0]], [1.0, 2.0], [1.0, 1.0], False),  # rank-deficient, consistent
        ([[1.0, 1.0], [2.0, 2.0]], [1.0, 2.5], [1.0, 1.0], True),  # rank-deficient, inconsistent
        ([[1.0, 1.0]], [2.0], [1.0, 1.0], False),  # touches a corner
        ([[1.0, 1.0]], [2.1], [1.0, 1.0], True),  # misses the box
        ([[0.0, 0.0]], [1.0], [1.0, 1.0], True),  # 0 = 1
        ([[1.0, 0.0], [1.0, 0.0]], [1.0, 2.0], [np.inf, 1.0], True),  # free factor, inconsistent
        ([[1.0, 1.0], [1.0, 1.0]], [1.0, 2.0], [np.inf, 1.0], True),
        ([[1.0, 1.0]], [50.0], [np.inf, 1.0], False),  # free factor absorbs it
        ([[1.0, 1.0, 0.0], [0.0, 1.0, 1.0], [1.0, 2.0, 1.0]], [1.0, 1.0, 2.5],
         [1.0, 1.0, 1.0], True),  # third row = sum of first two, wrong rhs
    ],
)
def test_emptiness(A, b, h, empty):
    A = np.array(A)
    Z = ConstrainedZonotope(np.eye(A.shape[1]), np.zeros(A.shape[1]), A, b, h)
    assert Z.is_empty() is empty
    if empty:
        assert Z.emptiness().violation_lower_bound > 0
        with pytest.raises(EmptySetError, match="empty"):
            Z.interval_hull()
        with pytest.raises(EmptySetError, match="empty"):
            Z.support(np.ones(A.shape[1]))
    else:
        Z.interval_hull()


def test_emptiness_tolerance_is_outward():
    # Misses the box by 1e-12 after normalisation: reported non-empty (within tol) ...
    Z = ConstrainedZonotope(np.eye(2), [0.0, 0.0], [[1.0, 1.0]], [2.0 + 2e-12], [1.0, 1.0])
    assert not Z.is_empty()
    box = Z.interval_hull()  # ... and its hull still contains the nearby corner
    assert box.contains([1.0, 1.0])
    # A resolvable gap: the certified violation bound is positive and never exceeds the
    # closed form (b - 2) / s, with s = 4 the power-of-two scale of the row [1, 1, b].
    gap = 1e-6
    Z2 = ConstrainedZonotope(np.eye(2), [0.0, 0.0], [[1.0, 1.0]], [2.0 + gap], [1.0, 1.0])
    rep = Z2.emptiness(tol=0.0)
    assert rep.empty
    assert 0.5 * gap / 4 < rep.violation_lower_bound <= gap / 4


def test_point_set_and_empty_generators():
    P = ConstrainedZonotope.point([1.0, -2.0])
    assert P.interval_hull().lo.tolist() == [1.0, -2.0]
    assert P.contains([1.0, -2.0]) and not P.contains([1.0, -1.999])
    E = ConstrainedZonotope(np.zeros((1, 0)), [0.0], np.zeros((1, 0)), [1.0])
    assert E.is_empty()
    with pytest.raises(EmptySetError):
        E.interval_hull()


# --------------------------------------------------------------------- containment
def test_contains_agrees_with_cdd_hrep(rng):
    for _ in range(15):
        Z = random_cz(rng, n=2, n_g=4, n_c=1)
        H = Z.to_hrep()
        inside = sample_points(Z, rng, 10)
        for x in inside:
            assert Z.contains(x)
        box = Z.interval_hull()
        for _ in range(30):
            x = rng.uniform(box.lo - 0.5, box.hi + 0.5)
            slack = np.concatenate([H.k - H.H @ x, -np.abs(H.E @ x - H.f)])
            if slack.min() > 1e-6:
                assert Z.contains(x)
            elif slack.min() < -1e-6:
                assert not Z.contains(x)


def test_contains_rejects_a_point_beyond_a_facet():
    Z = ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0],
                            A=[[1.0, 1.0, 1.0]], b=[1.0])
    assert Z.contains([1.0, 1.0])  # on the hypotenuse
    assert not Z.contains([1.0 + 1e-6, 1.0])
    assert Z.contains([1.0 + 1e-6, 1.0], tol=1e-5)
    assert not Z.contains([-1e-3, 0.5])
