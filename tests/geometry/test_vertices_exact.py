"""Exact vertices where the set's facets meet exactly: points, boxes, segments and
parallelotopes. Oracles: the box's own corners and closed forms written in
the test; scipy's linprog (each vertex is the unique maximiser of a functional) and
Qhull (every returned point is a vertex of their hull)."""

from __future__ import annotations

import itertools
from fractions import Fraction

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import ConvexHull

import setobs as so
from tests.conftest import exact_factor_vertices
from tests.oracles import assert_box_covers


def _rows(V):
    return sorted(map(tuple, np.asarray(V).tolist()))


def test_box_corners_are_exact():
    lo, hi = [-1.0, 0.0, 2.0], [1.0, 3.0, 2.5]
    V = so.ConstrainedZonotope.from_box(lo, hi).vertices()
    assert _rows(V) == _rows(list(itertools.product(*zip(lo, hi, strict=True))))


@pytest.mark.parametrize("Z", [
    so.ConstrainedZonotope(np.zeros((1, 1)), [4.0]),
    so.ConstrainedZonotope.from_box([4.0], [4.0]),
    so.ConstrainedZonotope(np.zeros((2, 0)), [4.0, -0.1]),
])
def test_a_point_is_one_exact_vertex(Z):
    V = Z.vertices()
    assert V.shape == (1, Z.dim) and np.array_equal(V[0], Z.c)


def test_a_segment_in_space_has_its_two_exact_ends():
    Z = so.ConstrainedZonotope([[0.5], [0.0], [0.25]], [1.0, 2.0, 3.0])
    Z = so.ConstrainedZonotope(Z.G, Z.c, h=[2.0])
    assert _rows(Z.vertices()) == [(0.0, 2.0, 2.5), (2.0, 2.0, 3.5)]


def test_a_flat_parallelogram_in_3d():
    G = np.array([[1.0, 0.5], [0.0, 1.0], [0.25, 0.0]])
    Z = so.ConstrainedZonotope(G, [0.0, 1.0, 0.0])
    expect = [tuple(np.array([0.0, 1.0, 0.0]) + G @ np.array(s)) for s in
              itertools.product((-1.0, 1.0), repeat=2)]
    assert _rows(Z.vertices()) == sorted(expect)  # (dyadic data: exact in floats)


@pytest.mark.parametrize("seed", range(5))
def test_random_parallelotopes_against_linprog_and_qhull(seed):
    rng = np.random.default_rng(seed)
    n = 3
    G, c, h = rng.normal(size=(n, n)), rng.normal(size=n), rng.uniform(0.1, 2.0, n)
    Z = so.ConstrainedZonotope(G, c, h=h)
    V = Z.vertices()
    assert V.shape == (2 ** n, n)
    assert sorted(ConvexHull(V).vertices.tolist()) == list(range(2 ** n))
    Ginv_T = np.linalg.inv(G).T
    for v in V:
        # the vertex's signs, and the functional it alone maximises
        s = np.sign(np.linalg.solve(G, v - c))
        d = Ginv_T @ s
        r = linprog(-(G.T @ d), bounds=list(zip(-h, h, strict=True)), method="highs")
        assert r.status == 0
        best = d @ c - r.fun
        assert abs(d @ v - best) <= 1e-12 * (1 + abs(best))


def test_sets_outside_the_closed_form_still_use_the_verified_construction():
    # constraints, too many generators, a rounding error on the centre
    Zc = so.ConstrainedZonotope(np.eye(2), [0.0, 0.0], A=[[1.0, 1.0]], b=[0.0])
    assert _rows(np.round(Zc.vertices(), 12)) == [(-1.0, 1.0), (1.0, -1.0)]
    Zm = so.ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0])
    assert len(Zm.vertices()) == 6  # a hexagon


def test_box_radius_is_rounded_up_only_where_inexact():
    """Oracle: exact rational arithmetic. The radius covers both ends from the rounded
    centre; where the differences are exact it is the half-width itself."""
    from setobs.geometry.box import box_center_radius

    c, r = box_center_radius(np.array([-1.0, 0.0, 2.0]), np.array([1.0, 3.0, 2.5]))
    assert c.tolist() == [0.0, 1.5, 2.25] and r.tolist() == [1.0, 1.5, 0.25]
    rng = np.random.default_rng(4)
    lo = rng.normal(size=500) * 10.0 ** rng.integers(-12, 12, 500)
    hi = lo + np.abs(rng.normal(size=500)) * 10.0 ** rng.integers(-14, 3, 500)
    c, r = box_center_radius(lo, hi)
    assert_box_covers(c, r, lo, hi)


def exact_ends(Z: so.ConstrainedZonotope) -> list[Fraction]:
    """Exact min and max of ``c + g xi`` over the exact factor vertices (rationals)."""
    c = Fraction(float(Z.c[0]))
    vals = [c + sum((Fraction(float(g)) * x for g, x in zip(Z.G[0], xi, strict=True)),
                    Fraction(0)) for xi in exact_factor_vertices(Z.A, Z.b, Z.h)]
    return [min(vals), max(vals)]


def test_a_constrained_1d_point_is_one_exact_vertex():
    """{3 + 0.5 (xi_1 + xi_2) : xi_1 + xi_2 = 2, |xi| <= 1} = {4} (the only factor point is
    (1, 1)); the certified hull's ends were 4 -+ 4e-16, two vertices."""
    Z = so.ConstrainedZonotope([[0.5, 0.5]], [3.0], A=[[1.0, 1.0]], b=[2.0], h=[1.0, 1.0])
    assert Z.vertices().tolist() == [[4.0]]
    Z = so.ConstrainedZonotope([[1.0, 1.0]], [3.0], A=[[1.0, 1.0]], b=[1.0], h=[1.0, 1.0])
    assert Z.vertices().tolist() == [[4.0]]  # a whole edge of factors maps to 4


def test_a_constrained_1d_segment_has_exact_ends():
    # xi_1 = xi_2, so 3 + xi_1 + xi_2 ranges over [1, 5]
    Z = so.ConstrainedZonotope([[1.0, 1.0]], [3.0], A=[[1.0, -1.0]], b=[0.0], h=[1.0, 1.0])
    assert Z.vertices().tolist() == [[1.0], [5.0]]


@pytest.mark.parametrize("seed", range(20))
def test_random_1d_ends_are_the_nearest_floats_to_the_exact_ends(seed):
    rng = np.random.default_rng(seed)
    n_g = int(rng.integers(2, 6))
    n_c = int(rng.integers(1, n_g))
    A = rng.normal(size=(n_c, n_g))
    Z = so.ConstrainedZonotope(rng.normal(size=(1, n_g)), rng.normal(size=1), A=A,
                               b=A @ rng.uniform(-0.7, 0.7, n_g), h=rng.uniform(0.5, 2.0, n_g))
    lo, hi = exact_ends(Z)
    assert Z.vertices().ravel().tolist() == [float(lo), float(hi)]  # int / int: nearest


def test_1d_ends_with_a_carried_rounding_bound_stay_outward():
    """A measured right-hand side (``b_err``) makes the set uncertain: the ends are the
    certified outward ones, which contain the exact ends of the set as stored."""
    Z = so.ConstrainedZonotope([[0.1, 0.2]], [0.3]).intersect_affine(
        [[1.0]], [0.3 + 0.07], y_err=[1e-12])
    assert Z.n_con == 1
    lo, hi = exact_ends(so.ConstrainedZonotope(Z.G, Z.c, Z.A, Z.b, Z.h))
    V = Z.vertices().ravel()
    assert Fraction(float(V[0])) < lo and Fraction(float(V[-1])) > hi


def test_a_box_cut_out_by_constraints_has_its_float_corners():
    """[0, 2] x [1, 3] cut by [-1, 1] x [0, 2] is [0, 1] x [1, 2] (its corners were
    3e-16 off); a box with a forced-zero factor likewise."""
    P = so.ConstrainedZonotope.from_box([0.0, 1.0], [2.0, 3.0]).intersect(
        so.ConstrainedZonotope.from_box([-1.0, 0.0], [1.0, 2.0]))
    assert _rows(P.vertices()) == [(0.0, 1.0), (0.0, 2.0), (1.0, 1.0), (1.0, 2.0)]
    Z = so.ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 0.0]], [1.0, 2.0],
                               A=[[0.0, 0.0, 1.0]], b=[0.0])
    assert _rows(Z.vertices()) == [(0.0, 1.0), (0.0, 3.0), (2.0, 1.0), (2.0, 3.0)]


@pytest.mark.parametrize("seed", range(6))
def test_constrained_vertices_are_the_nearest_floats_to_exact_vertices(seed):
    """Every vertex returned is the rounding of the image of an exact factor vertex, and
    they are as many as the extreme points (Qhull) of those images."""
    rng = np.random.default_rng(40 + seed)
    n, n_g = 2 + seed % 2, 5
    n_c = 1 + seed % 2
    A = rng.normal(size=(n_c, n_g))
    Z = so.ConstrainedZonotope(rng.normal(size=(n, n_g)), rng.normal(size=n), A=A,
                               b=A @ rng.uniform(-0.6, 0.6, n_g), h=rng.uniform(0.5, 2.0, n_g))
    c = [Fraction(float(v)) for v in Z.c]
    images = {tuple(float(ci + sum((Fraction(float(g)) * x for g, x in zip(Gi, xi, strict=True)),
                                   Fraction(0)))
                    for ci, Gi in zip(c, Z.G, strict=True))
              for xi in exact_factor_vertices(Z.A, Z.b, Z.h)}
    V = Z.vertices()
    assert set(_rows(V)) <= images
    pts = np.array(sorted(images))
    assert len(V) == len(ConvexHull(pts).vertices)


def test_a_bounded_set_with_a_free_factor():
    """A factor without bound (``h = inf``) pinned by a constraint: the verified points
    (no exact rationals of an infinite bound)."""
    Z = so.ConstrainedZonotope([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0.0, 0.0],
                               A=[[1.0, 0.0, -1.0]], b=[0.0], h=[1.0, 1.0, np.inf])
    assert _rows(Z.vertices()) == [(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)]
