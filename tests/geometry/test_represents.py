"""``represents`` and ``is_equal(tol=)`` against independent constructions.

Oracles: sets whose kind is known by construction (polygons and polytopes written as
vertices or half-spaces: a hexagon, a triangle, a rotated cube, the octahedron, a
3-D zonotope converted to its H-representation by scipy's Qhull), and the
Hausdorff distance of shifted sets in closed form.
"""

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from setobs import ConstrainedZonotope
from setobs.exceptions import InvalidValueError
from setobs.geometry import represents


def hpoly(H, k):
    return ConstrainedZonotope.from_hpolytope(np.asarray(H, float), np.asarray(k, float))


def qhull_hrep(V):
    hull = ConvexHull(V)
    return hull.equations[:, :-1], -hull.equations[:, -1]


def test_polygons_with_constraints():
    """A regular hexagon from its vertices is a zonotope (centrally symmetric) though
    written with constraints; a triangle and a pentagon are not; a square from its
    four half-planes is a box, and rotated it is a zonotope but not a box."""
    ang = np.linspace(0.0, 2.0 * np.pi, 7)[:-1]
    hexagon = ConstrainedZonotope.from_vertices(np.c_[np.cos(ang), np.sin(ang)])
    assert hexagon.n_con > 0 and hexagon.represents("zonotope")
    ang5 = np.linspace(0.0, 2.0 * np.pi, 6)[:-1]
    assert not ConstrainedZonotope.from_vertices(np.c_[np.cos(ang5), np.sin(ang5)]).represents(
        "zonotope")
    tri = ConstrainedZonotope.from_vertices([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    assert not tri.represents("zonotope") and not tri.represents("box")
    sq = hpoly([[1, 0], [-1, 0], [0, 1], [0, -1]], [1, 2, 3, 4])
    assert sq.represents("box") and sq.represents("zonotope") and not sq.represents("point")
    c, s = np.cos(0.3), np.sin(0.3)
    rot = hpoly([[c, s], [-c, -s], [-s, c], [s, -c]], [1, 1, 1, 1])
    assert rot.represents("zonotope") and not rot.represents("box")


def test_three_dimensional_polytopes():
    """A random 3-D zonotope (5 generators) converted to its Qhull facets is a zonotope;
    the octahedron (triangular faces) is not; a rotated cube is a zonotope, not a box;
    a box cut by a redundant half-space is still a box."""
    rng = np.random.default_rng(3)
    G = rng.normal(size=(3, 5))
    signs = ((np.arange(32)[:, None] >> np.arange(5)) & 1) * 2.0 - 1.0
    H, k = qhull_hrep(signs @ G.T)
    Z = hpoly(H, k)
    assert Z.n_con > 0 and Z.represents("zonotope")
    octa = hpoly([[a, b, c] for a in (1, -1) for b in (1, -1) for c in (1, -1)], np.ones(8))
    assert not octa.represents("zonotope") and not octa.represents("box")
    Q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    cube = hpoly(np.vstack([Q, -Q]), np.ones(6))
    assert cube.represents("zonotope") and not cube.represents("box")
    boxcut = hpoly(np.vstack([np.eye(3), -np.eye(3), [[1.0, 1.0, 1.0]]]), [1, 1, 1, 1, 1, 1, 5])
    assert boxcut.represents("box")
    cut = hpoly(np.vstack([np.eye(3), -np.eye(3), [[1.0, 1.0, 1.0]]]), [1, 1, 1, 1, 1, 1, 2.5])
    assert not cut.represents("box")


def test_flat_sets_are_tested_in_their_affine_hull():
    """A hexagon placed in a plane of R^3 (a flat polytope) is a zonotope; a triangle
    there is not; a segment is."""
    ang = np.linspace(0.0, 2.0 * np.pi, 7)[:-1]
    P = np.c_[np.cos(ang), np.sin(ang), np.zeros(6)] @ np.linalg.qr(
        np.random.default_rng(1).normal(size=(3, 3)))[0]
    assert ConstrainedZonotope.from_vertices(P).represents("zonotope")
    assert not ConstrainedZonotope.from_vertices(P[[0, 2, 4]]).represents("zonotope")
    assert ConstrainedZonotope.from_vertices(P[[0, 3]]).represents("zonotope")


def test_points_with_a_tolerance():
    """A set fixed by its constraints (``xi_1 = 0.25``) is the point 0.25 up to rounding;
    a segment of length 1e-6 is a point only with a tolerance above it."""
    Z = ConstrainedZonotope([[1.0, 0.0]], [0.0], A=[[1.0, 0.0]], b=[0.25], h=[1.0, 0.0])
    assert Z.represents("point")
    seg = ConstrainedZonotope([[5e-7]], [3.0])
    assert not seg.represents("point", tol=1e-7) and seg.represents("point", tol=2e-6)
    assert not seg.represents("origin", tol=2e-6) and seg.represents("origin", tol=4.0)


def test_unbounded_and_bad_input():
    strip = ConstrainedZonotope(np.eye(2), np.zeros(2), h=[np.inf, 1.0])
    assert not strip.represents("zonotope") and not strip.represents("box")
    assert not strip.represents("point")
    with pytest.raises(ValueError, match="kind"):
        represents(strip, "ellipsoid")
    with pytest.raises(InvalidValueError, match="tol"):
        strip.represents("point", tol=-1.0)
    with pytest.raises(NotImplementedError, match="corners"):
        ConstrainedZonotope.from_box(-np.ones(13), np.ones(13)).intersect_polytope(
            [np.ones(13)], [20.0]).represents("box")


@pytest.mark.parametrize("shift", [1e-3, 0.1])
def test_is_equal_with_a_tolerance_is_the_hausdorff_distance(shift):
    """A polygon and its translate by ``(s, 0)`` are at Hausdorff distance ``s``
    (infinity norm): equal for ``tol >= s`` (with margin), not for ``tol < s``."""
    Z = ConstrainedZonotope.from_vertices([[0.0, 0.0], [2.0, 0.0], [1.0, 1.5], [-0.5, 1.0]])
    W = Z + np.array([shift, 0.0])
    assert Z.is_equal(W, tol=1.01 * shift).holds is True
    r = Z.is_equal(W, tol=0.9 * shift)
    assert r.holds is False and r.witness is not None
    assert Z.is_equal(W).holds is False
