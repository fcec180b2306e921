"""Geometry that does not depend on the units.

For a set and its image under ``x -> s x`` (``s`` from 1e-12 to 1e12) the
vertices, volume, samples, containment and distance are the same answer, scaled.
Oracles: Qhull (scipy's ConvexHull) of the generating points for the vertices,
facets and volume; the unit-scale answer for the others, compared after scaling.
Reproducers: tiny_polytope_vertices_sample.py, distance_large_scale.py.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import ConvexHull

from setobs import ConstrainedZonotope

SCALES = [1e-12, 1e-10, 1e-8, 1.0, 1e8, 1e12]


def _points():
    return np.random.default_rng(0).standard_normal((8, 3))


@pytest.mark.parametrize("s", SCALES)
def test_vertices_volume_and_samples_of_a_scaled_polytope(s):
    V = _points() * s
    P = ConstrainedZonotope.from_vertices(V)
    hull = ConvexHull(V)
    true = V[hull.vertices]
    got = P.vertices()
    assert got.shape[0] == true.shape[0]           # 1e-8: 2 of 8 were missing
    far = max(np.min(np.linalg.norm(got - v, axis=1)) for v in true)
    assert far <= 1e-9 * s
    assert P.volume().value == pytest.approx(hull.volume, rel=1e-9)   # 1e-8: 2 % low
    S = P.sample(200, rng=1)                        # 1e-10: OverflowError
    excess = (S @ hull.equations[:, :-1].T + hull.equations[:, -1]).max()
    assert excess <= 1e-12 * s                      # 1e-8: points outside
    # the same answer, scaled: samples and the H-representation
    S1 = ConstrainedZonotope.from_vertices(_points()).sample(200, rng=1)
    np.testing.assert_allclose(S / s, S1, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("s", SCALES)
def test_distance_of_a_scaled_polytope(s):
    """1e8: SolverError (Clarabel: primal infeasible) on a nonempty polytope."""
    for seed in range(4):
        rng = np.random.default_rng(seed)
        V = rng.standard_normal((4, 3))
        c = rng.standard_normal(3) * 3
        p = V.mean(0) + rng.standard_normal(3) * 3
        ref = ConstrainedZonotope.from_vertices(V + c).distance(p)
        r = ConstrainedZonotope.from_vertices((V + c) * s).distance(p * s)
        assert r.distance / s == pytest.approx(ref.distance, rel=1e-6)   # the QP (IPM)
        assert r.lower <= r.distance and r.lower / s == pytest.approx(ref.lower, rel=1e-6)


@pytest.mark.parametrize("s", SCALES)
def test_containment_is_relative_to_the_sets_size(s):
    """A box 0.1 % outside its container is not inside, at any scale (at 1e-8 it
    was "inside" under an absolute tolerance); 0.1 % inside is inside."""
    W = ConstrainedZonotope.from_box([-s, -s], [s, s])
    out = ConstrainedZonotope.from_box([-s, -s], [1.001 * s, s])
    inn = ConstrainedZonotope.from_box([-s, -s], [0.999 * s, s])
    r = out.is_subset(W)
    assert r.holds is False and r.witness is not None and r.witness[0] > s
    assert inn.is_subset(W).holds is True
