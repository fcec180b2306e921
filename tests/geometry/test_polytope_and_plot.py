"""Polytope conversion (verified vertices and facets) and 2-D plotting."""

from __future__ import annotations

from fractions import Fraction

import cdd
import matplotlib.pyplot as plt
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from matplotlib.patches import Polygon
from scipy.spatial import ConvexHull

from setobs import ConstrainedZonotope, EmptySetError, UnboundedSetError
from setobs.geometry import polygon_2d
from tests.conftest import cdd_vertices, exact_factor_vertices, random_cz
from tests.oracles import exact_hpolytope_vertices

seeds = st.integers(0, 2**32 - 1)


def as_set(P, decimals=7):
    return {tuple(np.round(p, decimals) + 0.0) for p in P}


def hull_vertices(P):
    """Extreme points with scipy's Qhull (independent of cdd)."""
    return P[ConvexHull(P).vertices]


def test_vertices_of_triangle():
    Z = ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0],
                            A=[[1.0, 1.0, 1.0]], b=[1.0])
    assert as_set(Z.vertices()) == {(0.0, 0.0), (2.0, 0.0), (0.0, 2.0)}


@given(seeds)
def test_vertices_match_qhull(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=1)
    V = Z.vertices()
    P = cdd_vertices(Z)
    if np.linalg.matrix_rank(P - P.mean(axis=0), tol=1e-9) < 2:
        return  # flat set: Qhull needs full dimension
    assert as_set(V, 6) == as_set(hull_vertices(P), 6)


@given(seeds)
def test_hrep_round_trip(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=4, n_c=1)
    H = Z.to_hrep()
    for v in Z.vertices():
        assert H.contains(v, tol=1e-8)
    if H.E.shape[0] == 0:
        W = ConstrainedZonotope.from_hpolytope(H.H, H.k)
        for _ in range(4):
            d = rng.normal(size=2)
            assert W.support(d) == pytest.approx(Z.support(d), abs=1e-7)


@given(seeds)
def test_from_hpolytope_matches_cdd(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 4))
    # A random bounded polytope: random halfspaces around the origin plus a box.
    Hr = rng.normal(size=(6, n))
    H = np.vstack([Hr, np.eye(n), -np.eye(n)])
    k = np.concatenate([rng.uniform(0.5, 2.0, 6), np.full(2 * n, 3.0)])
    Z = ConstrainedZonotope.from_hpolytope(H, k)
    mat = cdd.matrix_from_array(np.hstack([k[:, None], -H]).tolist(),
                                rep_type=cdd.RepType.INEQUALITY)
    gen = np.array(cdd.copy_generators(cdd.polyhedron_from_matrix(mat)).array)
    V = gen[:, 1:]
    box = Z.interval_hull()
    np.testing.assert_allclose(box.lo, V.min(axis=0), atol=1e-7)
    np.testing.assert_allclose(box.hi, V.max(axis=0), atol=1e-7)
    for _ in range(4):
        d = rng.normal(size=n)
        assert Z.support(d) == pytest.approx((V @ d).max(), abs=1e-7)
    assert Z.contains(V.mean(axis=0))


def test_from_hpolytope_errors():
    with pytest.raises(UnboundedSetError, match="unbounded"):
        ConstrainedZonotope.from_hpolytope([[1.0, 0.0]], [1.0])
    with pytest.raises(EmptySetError, match="empty"):
        ConstrainedZonotope.from_hpolytope([[1.0], [-1.0]], [0.0, -1.0])


def test_vertices_of_unbounded_set_raises():
    with pytest.raises(UnboundedSetError, match="bounded"):
        ConstrainedZonotope.full_space(2).vertices()


def test_vertices_of_set_with_pinned_unbounded_factor():
    # x = xi_u with xi_u + xi_b = 0, |xi_b| <= 1: the interval [-1, 1].
    Z = ConstrainedZonotope([[1.0, 0.0]], [0.0], [[1.0, 1.0]], [0.0], [np.inf, 1.0])
    assert as_set(Z.vertices()) == {(-1.0,), (1.0,)}


@given(seeds)
def test_polygon_2d_matches_vertices(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=1)
    P = polygon_2d(Z)
    V = Z.vertices()
    if len(V) >= 3:
        assert as_set(P, 6) == as_set(V, 6)
        # Counter-clockwise order: positive signed area.
        x, y = P[:, 0], P[:, 1]
        assert 0.5 * (x @ np.roll(y, -1) - y @ np.roll(x, -1)) > 0


def test_plot_returns_artist_on_given_and_current_axes():
    Z = ConstrainedZonotope.from_box([0, 0, 0], [1, 2, 3])
    fig, ax = plt.subplots()
    art = Z.plot(ax=ax, dims=(0, 2), facecolor="C1")
    assert isinstance(art, Polygon) and art in ax.patches
    assert as_set(art.get_xy()[:-1]) == {(0, 0), (1, 0), (1, 3), (0, 3)}
    plt.close(fig)
    fig2 = plt.figure()
    art2 = Z.plot()  # ax=None: current axes
    assert art2 in plt.gca().patches
    plt.close(fig2)
    with pytest.raises(UnboundedSetError):
        ConstrainedZonotope.full_space(2).plot()


def test_vertex_that_float_cdd_redundancy_removal_dropped():
    """A true vertex 2.3e-4 outside the chord of its neighbours (found by hypothesis in CI):
    cdd's floating-point canonicalisation removed it; the certified support proves it."""
    Z = random_cz(np.random.default_rng(1013598), n=2, n_g=5, n_c=1)
    V = Z.vertices()
    assert as_set(V, 6) == as_set(polygon_2d(Z), 6)
    v = np.array([1.514899, -3.210643])
    k = int(np.argmin(np.linalg.norm(V - v, axis=1)))
    assert np.linalg.norm(V[k] - v) < 1e-5
    # neighbours in angular order around the centroid
    ang = np.arctan2(*(V - V.mean(axis=0)).T[::-1])
    order = list(np.argsort(ang))
    i = order.index(k)
    a, c = V[order[i - 1]], V[order[(i + 1) % len(order)]]
    e = c - a
    nrm = np.array([e[1], -e[0]]) / np.linalg.norm(e)
    if nrm @ (V[k] - a) < 0:
        nrm = -nrm
    assert Z.support(nrm) - nrm @ a > 2e-4  # the set reaches past the chord


# ------------------------------------------------------------------ hardening: vertex enumeration
def _intersection_of_random_hulls(seed, points):
    rng = np.random.default_rng(seed)
    E1 = ConvexHull(rng.random((points, 3))).equations
    E2 = ConvexHull(rng.random((points, 3))).equations
    Z = ConstrainedZonotope.from_hpolytope(E1[:, :3], -E1[:, 3]).intersect(
        ConstrainedZonotope.from_hpolytope(E2[:, :3], -E2[:, 3]))
    E = np.vstack([E1, E2])
    return Z, E[:, :3], -E[:, 3]


def _check_against_exact_vertices(Z, H, k):
    exact = exact_hpolytope_vertices(H, k)
    X = np.array([[float(v) for v in x] for x in exact])
    V = Z.vertices()
    # same vertex set: each returned point is an exact vertex and vice versa
    assert len(V) == len(X), (len(V), len(X))
    dist = np.linalg.norm(V[:, None, :] - X[None, :, :], axis=2)
    assert dist.min(axis=1).max() < 1e-8 and dist.min(axis=0).max() < 1e-8
    # the H-representation contains every exact vertex (certified offsets) and is
    # tight: each facet offset is within 1e-8 of the exact support in its normal
    hr = Z.to_hrep()
    for x in exact:
        for a, off in zip(hr.H, hr.k, strict=True):
            assert sum(Fraction(float(a[j])) * x[j] for j in range(3)) <= Fraction(float(off))
    for a, off in zip(hr.H, hr.k, strict=True):
        assert off - (X @ a).max() < 1e-8
    assert hr.E.shape[0] == 0 and hr.contains(X.mean(axis=0))


def test_vertices_of_the_intersection_of_two_random_3d_hulls():
    """Reported: 2 points returned where the set has 35; to_hrep then excluded the interior."""
    Z, H, k = _intersection_of_random_hulls(31, 12)
    assert len(Z.vertices()) == 35
    _check_against_exact_vertices(Z, H, k)


@pytest.mark.parametrize("seed", [0, 4])
def test_vertices_on_coras_randomized_intersection_test(seed):
    """CORA's testLong_conZonotope_and in 3-D (hulls of 100 random points, ~120 generators):
    cdd dropped up to 59 of 128 vertices (seed 4: 12 of 144 returned)."""
    Z, H, k = _intersection_of_random_hulls(seed, 100)
    assert Z.n_gen > 100
    _check_against_exact_vertices(Z, H, k)


@given(seeds)
def test_vertices_of_random_3d_sets_equal_exact_enumeration(seed):
    """Against exact rational vertex enumeration of the factor polytope (conftest)."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=3, n_g=5, n_c=1)
    verts = exact_factor_vertices(Z.A, Z.b, Z.h)
    P = np.array([[float(v) for v in xi] for xi in verts]) @ Z.G.T + Z.c
    V = Z.vertices()
    if np.linalg.matrix_rank(P - P.mean(axis=0), tol=1e-7) < 3:
        # flat: every returned point is one of the exact points
        assert np.linalg.norm(V[:, None] - P[None], axis=2).min(axis=1).max() < 1e-7
        return
    ref = hull_vertices(P)
    assert as_set(V, 6) == as_set(ref, 6)


def test_flat_3d_set_has_an_affine_hull():
    # the square [0, 1]^2 x {0.5} in R^3
    Z = ConstrainedZonotope.from_box([0, 0, 0.5], [1, 1, 0.5])
    assert as_set(Z.vertices()) == {(0, 0, 0.5), (1, 0, 0.5), (0, 1, 0.5), (1, 1, 0.5)}
    hr = Z.to_hrep()
    assert hr.E.shape == (1, 3)
    np.testing.assert_allclose(np.abs(hr.E[0]), [0, 0, 1], atol=1e-12)
    assert hr.contains([0.5, 0.5, 0.5]) and not hr.contains([0.5, 0.5, 0.6])
