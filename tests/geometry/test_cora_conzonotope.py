"""Cases translated from CORA's conZonotope unit tests (TUMcps/CORA, unitTests/contSet/conZonotope).

CORA writes a set as ``conZonotope([c, G], A, b)``; here ``ConstrainedZonotope(G, c, A, b)``.
CORA's expected values are used as written. Conventions that differ are stated
where they occur (CORA's support function of the empty set is ``-inf``; setobs
raises :class:`~setobs.EmptySetError`, because an empty set in a set-membership
run is an inconsistency to report, not a number).
"""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from setobs import ConstrainedZonotope
from setobs.exceptions import EmptySetError
from setobs.geometry import Box, pontryagin_difference, to_hrep

from .test_breadth_operations import as_set, exact_vertices_of


def cora(Z, A=None, b=None):
    Z = np.asarray(Z, dtype=float)
    return ConstrainedZonotope(Z[:, 1:], Z[:, 0], A=A, b=b)


CZ1 = ([[0, 3, 0, 1], [0, 0, 2, 1]], [[1, 0, 1]], [1])
CZ2 = ([[0, 1.5, -1.5, 0.5], [0, 1, 0.5, -1]], [[1, 1, 1]], [1])


def same_points(V, ref, tol=1e-6):
    V, ref = np.atleast_2d(V), np.atleast_2d(ref)
    d = np.linalg.norm(V[:, None, :] - ref[None, :, :], axis=2)
    return d.min(axis=1).max() < tol and d.min(axis=0).max() < tol


def collinear_free(V):
    """Qhull's extreme points (CORA's removeCollinearVertices2D)."""
    return V[ConvexHull(V).vertices] if len(V) > 2 else V


# ---------------------------------------------------------------- test_conZonotope_and
def test_and_two_conzonotopes():
    V = (cora(*CZ1) & cora(*CZ2)).vertices()
    ref = np.array([[1, 3, 1, 3], [11 / 8, -1 / 8, -11 / 12, -7 / 12]]).T
    assert same_points(collinear_free(V), ref)


def test_and_halfspace():
    V = cora(*CZ1).intersect_polytope([[1, -2]], [1]).vertices()
    assert same_points(V, np.array([[1, 3, 3, 1], [0, 1, 2, 3]]).T)


def test_and_polytope_with_an_equality():
    V = cora(*CZ1).intersect_polytope([[-2, -0.5], [1, 0]], [-4.25, 2.5],
                                      E=[[1, -2]], f=[1]).vertices()
    assert same_points(V, np.array([[2, 2.5], [0.5, 0.75]]).T)


# ---------------------------------------------------------------- test_conZonotope_convHull
def test_convhull_two_sets_vertices_subset_of_the_operands():
    c1 = cora(*CZ2)
    c2 = cora([[4, 2, 0, 0], [4, 1, 1, 0]], [[1, 1, -1]], [0])
    V = collinear_free(c1.convex_hull(c2).vertices())
    ops = np.vstack([c1.vertices(), c2.vertices()])
    d = np.linalg.norm(V[:, None] - ops[None], axis=2).min(axis=1)
    assert d.max() < 1e-6                       # CORA: compareMatrices(V_, [V1, V2], 'subset')


def test_convhull_with_a_polytope():
    c1 = cora(*CZ2)
    c2 = cora([[4, 2, 0, 0], [4, 1, 1, 0]], [[1, 1, -1]], [0])
    hr = to_hrep(c2)
    P2 = ConstrainedZonotope.from_hpolytope(hr.H, hr.k)
    V = collinear_free(c1.convex_hull(P2).vertices())
    ops = np.vstack([c1.vertices(), c2.vertices()])
    assert np.linalg.norm(V[:, None] - ops[None], axis=2).min(axis=1).max() < 1e-6


def test_convhull_three_sets():
    c1 = cora(*CZ2)
    c2 = cora([[4, 2, 0, 0], [4, 1, 1, 0]], [[1, 1, -1]], [0])
    c3 = cora([[-4, 3, 0, 1], [5, 0, 2, 1]], [[1, 0, 1]], [1])
    V = collinear_free(c1.convex_hull(c2).convex_hull(c3).vertices())
    ops = np.vstack([c1.vertices(), c2.vertices(), c3.vertices()])
    assert np.linalg.norm(V[:, None] - ops[None], axis=2).min(axis=1).max() < 1e-5
    # and it is the whole hull (stronger than CORA's subset check)
    assert same_points(V, ops[ConvexHull(ops).vertices], 1e-6)


# ---------------------------------------------------------------- test_conZonotope_minkDiff
def _minkdiff_case():
    cz = ConstrainedZonotope([[1.5, -1.5, 0.5], [1, 0.5, -1]], [1, 0], A=[[1, 1, 1]], b=[1])
    return cz, Box([-0.5, 0.0], [1.0, 2.0])


def test_minkdiff_with_a_vector():
    cz, _ = _minkdiff_case()
    assert np.allclose(pontryagin_difference(cz, [2, -1]).c, cz.c - [2, -1])


def test_minkdiff_exact_equals_the_polytope_difference():
    cz, I = _minkdiff_case()
    hr = to_hrep(cz)
    # polytope difference: shift each facet by the box's support in its normal
    lo, hi = I.lo, I.hi
    kk = hr.k - np.array([np.maximum(h * lo, h * hi).sum() for h in hr.H])
    D = pontryagin_difference(cz, I, "exact")
    assert as_set(D.vertices(), 6) == as_set(exact_vertices_of(hr.H, kk), 6)


@pytest.mark.parametrize("method", ["inner"])
def test_minkdiff_inner_is_contained_in_the_exact(method):
    """CORA's 'inner:Vinod' / 'inner:vertices': contained in the true difference."""
    cz, I = _minkdiff_case()
    exact = pontryagin_difference(cz, I, "exact")
    inner = pontryagin_difference(cz, I, method)
    assert inner.is_empty() or inner.is_subset(exact).holds is True


# ---------------------------------------------------------------- test_conZonotope_contains
def test_contains_points():
    cz = cora(*CZ2)
    p_in = np.array([[0, 1, 0, 0, 1, -1, -2], [0, 0, 2, -1, 1, 0, -1]]).T
    p_out = np.array([[3, 0, 1, -2, 3], [1, -2, 2, 0, -1]]).T
    assert all(cz.contains(p) for p in p_in)
    assert not any(cz.contains(p) for p in p_out)


# ---------------------------------------------------------------- test_conZonotope_isequal
def test_isequal_cases():
    c1 = cora(*CZ1)
    assert c1.is_equal(c1).holds is True
    assert c1.is_equal(c1 + 1e-8 * np.ones(2)).holds is False      # above our 1e-9 tolerance
    c1b = ConstrainedZonotope(c1.G, c1.c, A=c1.A, b=[1 + np.finfo(float).eps])
    assert c1.is_equal(c1b).holds is True
    assert c1.is_equal(cora(*CZ2)).holds is False
    # compensate for the small offset by a tolerance (CORA: isequal(cZ1, cZ1 + 1e-8, 1e-6))
    assert c1.is_equal(c1 + 1e-8 * np.ones(2), tol=1e-6).holds is True
    assert c1.is_equal(c1 + 1e-4 * np.ones(2), tol=1e-6).holds is False


# ---------------------------------------------------------------- test_conZonotope_representsa
def test_representsa_cases():
    assert ConstrainedZonotope.empty(2).represents("empty")
    assert not cora(*CZ1).represents("empty")
    # origin
    assert not ConstrainedZonotope.empty(2).represents("origin")
    assert ConstrainedZonotope.point(np.zeros(3)).represents("origin")
    assert ConstrainedZonotope(np.zeros((2, 2)), np.zeros(2)).represents("origin")
    assert not ConstrainedZonotope(np.zeros((2, 1)), np.ones(2)).represents("origin")
    assert not ConstrainedZonotope([[1.0], [0.0], [-1.0]], np.zeros(3)).represents("origin")
    below = ConstrainedZonotope([[0.02, -0.1], [0.2, 0.05]], [0.5, 0.5])
    assert below.represents("origin", tol=1.0)
    # zonotope
    assert ConstrainedZonotope([[1, -1, 0], [2, 1, 3]], [1, 2]).represents("zonotope")
    # CORA expects False here: its check is syntactic (a conZonotope with constraints is
    # "not a zonotope"). setobs decides the geometry: with xi_3 = 1 - xi_1 the set is
    # {(2 xi_1 + 1, 2 xi_2 - xi_1 + 1) : xi_1 in [0, 1], xi_2 in [-1, 1]}, the affine
    # image of a box, i.e. the parallelogram with vertices (1, -1), (1, 3), (3, -2),
    # (3, 2) (by hand): a zonotope.
    c1 = cora(*CZ1)
    assert same_points(c1.vertices(), [[1, -1], [1, 3], [3, -2], [3, 2]])
    assert c1.represents("zonotope")
    assert not cora(*CZ2).represents("zonotope")  # (a triangle: not centrally symmetric)
    # interval
    assert ConstrainedZonotope([[1, 0], [0, 2]], [1, 2]).represents("box")
    # point
    assert ConstrainedZonotope.point([1.0, 2.0]).represents("point")
    assert not ConstrainedZonotope([[1, 0], [0, 2]], [1, 2]).represents("point")


# ---------------------------------------------------------------- test_conZonotope_empty, uminus
def test_empty():
    E = ConstrainedZonotope.empty(3)
    assert E.dim == 3 and E.is_empty()


def test_uminus():
    cz = ConstrainedZonotope([[2, 0, 2], [0, 2, 2]], [0, 0], A=[[2, -4, 2]], b=[0])
    n = -cz
    assert (n.c == -cz.c).all() and (n.G == -cz.G).all()
    assert (n.A == cz.A).all() and (n.b == cz.b).all()
    assert n.is_equal(-1.0 * np.eye(2) @ cz).holds is True
    assert (-ConstrainedZonotope.empty(2)).is_empty()


# ---------------------------------------------------------------- test_conZonotope_cartProd
def test_cartprod():
    c1 = ConstrainedZonotope([[3, 0, 1], [0, 2, 1]], [0, 0], A=[[1, 0, 1]], b=[1])
    c2 = ConstrainedZonotope([[1.5, -1.5, 0.5], [1, 0.5, -1]], [1, 0], A=[[1, 1, 1]], b=[1])
    got = c1.cartesian(c2)
    G = np.zeros((4, 6))
    G[:2, :3], G[2:, 3:] = c1.G, c2.G
    A = np.zeros((2, 6))
    A[0, :3], A[1, 3:] = c1.A, c2.A
    true = ConstrainedZonotope(G, [0, 0, 1, 0], A=A, b=[1, 1])
    assert got.is_equal(true).holds is True
    I2 = ConstrainedZonotope.from_box([2, 3], [4, 3])
    true_i = ConstrainedZonotope(np.block([[c1.G, np.zeros((2, 2))],
                                           [np.zeros((2, 3)), np.diag([1.0, 0.0])]]),
                                 [0, 0, 3, 3], A=[[1, 0, 1, 0, 0]], b=[1])
    assert c1.cartesian(I2).is_equal(true_i).holds is True


# ---------------------------------------------------------------- test_conZonotope_supportFunc
def test_support_function_values_and_points():
    cz = cora(*CZ2)
    assert cz.support([1, 0]) == pytest.approx(3.5)
    assert cz.support([0, 1]) == pytest.approx(2.5)
    assert -cz.support([-1, 0]) == pytest.approx(-2.5, abs=1e-6)
    assert -cz.support([0, -1]) == pytest.approx(-1.5)
    pts = [cz.support_point(d) for d in ([-0.2, 1], [-1, -1], [1, -0.2])]
    assert np.allclose(pts, [[-0.5, 2.5], [-2.5, -1.5], [3.5, -0.5]], atol=1e-8)
    cz2 = cora([[0, 1, 0, 1], [0, 1, 2, -1]], [[-2, 1, -1]], [2])
    assert cz2.support([1, 0]) == pytest.approx(0.0, abs=1e-9)
    assert cz2.support([0, 1]) == pytest.approx(3.0)
    assert -cz2.support([-1, 0]) == pytest.approx(-2.0)
    assert -cz2.support([0, -1]) == pytest.approx(-2.0)
    cz3 = cora([[0, 3, 0, 1, -2], [0, 0, 2, 1, 1]], [[0, 0, 0, 1]], [0.5])
    assert (cz3.support([1, 0]), cz3.support([0, 1])) == (pytest.approx(3), pytest.approx(3.5))
    assert -cz3.support([-1, 0]) == pytest.approx(-5)
    assert -cz3.support([0, -1]) == pytest.approx(-2.5)


def test_support_function_of_the_empty_set_raises():
    """CORA returns -inf; setobs raises (the documented convention)."""
    with pytest.raises(EmptySetError):
        ConstrainedZonotope.empty(2).support([1.0, 1.0])
