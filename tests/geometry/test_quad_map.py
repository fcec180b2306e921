"""The quadratic map (CORA's quadMap).

Oracles: CORA's test_zonotope_quadMap values (computed by hand there), closed forms
(``x^2`` on an interval), and points of the set (rational vertices of the factor
polytope, random convex combinations) mapped in exact rational arithmetic, which the
result must contain.
"""

from fractions import Fraction

import numpy as np
import pytest

from setobs import ConstrainedZonotope
from setobs.exceptions import DimensionError, UnboundedSetError
from setobs.geometry import quad_map
from tests.conftest import exact_factor_vertices, random_cz


def test_cora_zonotope_case():
    """CORA's test_zonotope_quadMap (quadMapSingle): centre (102.5, -16.25) and the
    generators (27.5, -5.75), (35, -9.5), (95, -14), (110, -26), (125, -32)."""
    Z = ConstrainedZonotope([[-3.0, -2.0], [2.0, 3.0]], [-4.0, 1.0])
    R = quad_map(Z, [[[1, -2], [-3, 4]], [[0.5, 0], [2, -1]]])
    np.testing.assert_allclose(R.c, [102.5, -16.25], rtol=1e-12)
    got = np.array(sorted(map(tuple, R.G.T.tolist())))
    want = np.array(sorted([(27.5, -5.75), (35.0, -9.5), (95.0, -14.0), (110.0, -26.0),
                            (125.0, -32.0)]))
    np.testing.assert_allclose(got, want, rtol=1e-12)


def test_square_on_an_interval():
    """``x^2`` over ``[1, 3]``: with ``x = 2 + xi``, ``x^2 = 4 + 4 xi + xi^2`` and
    ``xi^2`` replaced by ``0.5 + 0.5 eta`` (``|eta| <= 1``), so the hull is
    ``[4 - 4 + 0, 4 + 4 + 1] = [0, 9]`` (by hand; the true range is [1, 9]: outer)."""
    R = quad_map(ConstrainedZonotope.from_box([1.0], [3.0]), [[[1.0]]])
    box = R.interval_hull()
    assert box.lo[0] <= 0.0 + 1e-12 and box.lo[0] >= -1e-12
    assert box.hi[0] >= 9.0 and box.hi[0] - 9.0 < 1e-12


def _exact_image(x, Q):
    xf = [Fraction(float(v)) for v in x]
    return [sum(Fraction(float(Qi[k, l])) * xf[k] * xf[l] for k in range(len(xf))
                for l in range(len(xf))) for Qi in Q]


@pytest.mark.parametrize("seed", range(5))
def test_contains_the_image_of_the_sets_points(seed):
    """Random constrained zonotopes: the images of the exact factor vertices and of
    random convex combinations, mapped in rational arithmetic and rounded outward,
    are in the result (its certified support in the +-coordinate directions
    covers them, and the points pass ``contains``)."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=4, n_c=1)
    Q = rng.normal(size=(2, 2, 2))
    R = quad_map(Z, Q)
    verts = exact_factor_vertices(Z.A, Z.b, Z.h)
    Gf = [[Fraction(float(v)) for v in row] for row in Z.G]
    cf = [Fraction(float(v)) for v in Z.c]
    pts = []
    W = rng.dirichlet(np.ones(len(verts)), size=15)
    for w in [*np.eye(len(verts)), *W]:
        xi = [sum(Fraction(float(wk)) * v[j] for wk, v in zip(w, verts, strict=True))
              for j in range(Z.n_gen)]
        x = [cf[i] + sum(Gf[i][j] * xi[j] for j in range(Z.n_gen)) for i in range(2)]
        pts.append(_exact_image([float(v) for v in x], Q))
    box = R.interval_hull()
    for y in pts:
        assert all(Fraction(box.lo[i]) <= y[i] <= Fraction(box.hi[i]) for i in range(2))
        assert R.contains(np.array([float(v) for v in y]))


def test_large_centre_rounding_is_covered():
    """A set far from the origin (``z = c + xi``, ``c = 1e8 + 0.5``, ``|xi| <= 1``):
    ``z^2`` at the ends, exact, is inside the certified hull, whose upper end is
    ``(c + 1)^2`` (by hand) up to the rounding bound (~30 at 1e16), below 1e3."""
    Z = ConstrainedZonotope([[1.0]], [1e8 + 0.5])
    R = quad_map(Z, [[[1.0]]])
    box = R.interval_hull()
    for x in (Fraction(1e8 + 0.5) - 1, Fraction(1e8 + 0.5) + 1):
        assert Fraction(box.lo[0]) <= x * x <= Fraction(box.hi[0])
    assert box.hi[0] - float((Fraction(1e8 + 0.5) + 1) ** 2) < 1e3


def test_refusals():
    strip = ConstrainedZonotope(np.eye(2), np.zeros(2), h=[np.inf, 1.0])
    with pytest.raises(UnboundedSetError):
        quad_map(strip, np.eye(2))
    with pytest.raises(DimensionError, match="shape"):
        quad_map(ConstrainedZonotope.from_box([0.0, 0.0], [1.0, 1.0]), np.eye(3))
