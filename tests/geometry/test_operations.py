"""Semantics of the exact set operations.

Soundness by sampling (images of sampled points are contained) and tightness
by LP witnesses computed independently with scipy's ``linprog`` on the joint
formulation, or by closed-form support-function identities.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from scipy.linalg import block_diag
from scipy.optimize import linprog

from setobs import ConstrainedZonotope
from tests.conftest import random_cz, sample_points

seeds = st.integers(0, 2**32 - 1)
TOL = 1e-7


def lp_support(G, c, A, b, h, d):
    """Independent support value: scipy/HiGHS on the factor formulation, no certification."""
    res = linprog(-(G.T @ d), A_eq=A if A.shape[0] else None, b_eq=b if A.shape[0] else None,
                  bounds=list(zip(-h, h, strict=True)), method="highs")
    assert res.status == 0, res.message
    return -res.fun + d @ c


@given(seeds)
def test_minkowski_sum(seed):
    rng = np.random.default_rng(seed)
    Z1 = random_cz(rng, n=2)
    Z2 = random_cz(rng, n=2)
    S = Z1 + Z2
    assert S.minkowski_sum(Z2).n_gen == S.n_gen + Z2.n_gen
    for p, q in zip(sample_points(Z1, rng, 8), sample_points(Z2, rng, 8), strict=True):
        assert S.contains(p + q)
    for _ in range(3):
        d = rng.normal(size=2)
        assert S.support(d) == pytest.approx(Z1.support(d) + Z2.support(d), abs=TOL)
    v = np.array([1.5, -2.0])
    for W in (Z1 + v, v + Z1, Z1.minkowski_sum(v)):
        np.testing.assert_allclose(W.interval_hull().lo, Z1.interval_hull().lo + v, atol=TOL)
    np.testing.assert_allclose((Z1 - v).c, Z1.c - v)


@given(seeds)
def test_linear_map(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=3)
    m = int(rng.integers(1, 5))
    M = rng.normal(size=(m, 3))
    W = M @ Z
    assert W.dim == m
    np.testing.assert_array_equal(W.G, Z.linear_map(M).G)
    for p in sample_points(Z, rng, 10):
        assert W.contains(M @ p)
    for _ in range(3):
        d = rng.normal(size=m)
        assert W.support(d) == pytest.approx(Z.support(M.T @ d), abs=TOL * (1 + abs(W.support(d))))


def test_linear_map_singular_and_operator_dispatch():
    Z = ConstrainedZonotope.from_box([-1, -1], [1, 1])
    P = np.array([[1.0, 1.0]]) @ Z  # ndarray @ Z goes to __rmatmul__
    box = P.interval_hull()
    assert box.lo[0] == pytest.approx(-2.0) and box.hi[0] == pytest.approx(2.0)
    assert (np.zeros((2, 2)) @ Z).interval_hull().width.max() == 0.0
    with pytest.raises(TypeError):
        Z * 2.0


@given(seeds)
def test_cartesian(seed):
    rng = np.random.default_rng(seed)
    Z1, Z2 = random_cz(rng), random_cz(rng)
    P = Z1.cartesian(Z2)
    assert P.dim == Z1.dim + Z2.dim
    for p, q in zip(sample_points(Z1, rng, 6), sample_points(Z2, rng, 6), strict=True):
        assert P.contains(np.concatenate([p, q]))
    d1, d2 = rng.normal(size=Z1.dim), rng.normal(size=Z2.dim)
    assert P.support(np.concatenate([d1, d2])) == pytest.approx(
        Z1.support(d1) + Z2.support(d2), abs=TOL)


@given(seeds)
def test_intersect_affine(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=3, n_g=5, n_c=1)
    C = rng.normal(size=(1, 3))
    z0 = sample_points(Z, rng, 1)[0]
    y = C @ z0
    W = Z.intersect_affine(C, y)
    assert W.contains(z0)
    assert not W.is_empty()
    A = np.vstack([Z.A, C @ Z.G])
    b = np.concatenate([Z.b, y - C @ Z.c])
    for _ in range(3):
        d = rng.normal(size=3)
        ref = lp_support(Z.G, Z.c, A, b, Z.h, d)
        assert W.support(d) == pytest.approx(ref, abs=1e-6 * (1 + abs(ref)))
    # A measurement the set cannot produce empties it.
    far = Z.support(C[0]) + 1.0
    assert Z.intersect_affine(C, [far]).is_empty()


@given(seeds)
def test_generalized_intersection(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=4)
    R = rng.normal(size=(1, 2))
    z0 = sample_points(Z, rng, 1)[0]
    # W: an interval around R z0, so the result is non-empty and z0 is in it.
    W = ConstrainedZonotope([[0.3]], R @ z0 + rng.uniform(-0.2, 0.2, 1))
    X = Z.intersect(W, R)
    assert X.contains(z0)
    # Independent joint LP: variables (xi_Z, xi_W).
    A = np.vstack([
        np.hstack([Z.A, np.zeros((Z.n_con, 1))]),
        np.hstack([R @ Z.G, -W.G]),
    ])
    b = np.concatenate([Z.b, W.c - R @ Z.c])
    G = np.hstack([Z.G, np.zeros((2, 1))])
    h = np.concatenate([Z.h, W.h])
    for _ in range(3):
        d = rng.normal(size=2)
        ref = lp_support(G, Z.c, A, b, h, d)
        assert X.support(d) == pytest.approx(ref, abs=1e-6 * (1 + abs(ref)))
    # Plain intersection with itself is itself.
    same = Z.intersect(Z)
    d = rng.normal(size=2)
    assert same.support(d) == pytest.approx(Z.support(d), abs=TOL)


def test_intersection_of_boxes_closed_form():
    B1 = ConstrainedZonotope.from_box([0, 0], [2, 2])
    B2 = ConstrainedZonotope.from_box([1, -1], [3, 1])
    box = B1.intersect(B2).interval_hull()
    np.testing.assert_allclose(box.lo, [1, 0], atol=1e-12)
    np.testing.assert_allclose(box.hi, [2, 1], atol=1e-12)
    assert B1.intersect(ConstrainedZonotope.from_box([5, 5], [6, 6])).is_empty()


@given(seeds)
def test_projection(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=3)
    P = Z.project([2, 0])
    d = rng.normal(size=2)
    full = np.zeros(3)
    full[[2, 0]] = d
    assert P.support(d) == pytest.approx(Z.support(full), abs=TOL)
    for p in sample_points(Z, rng, 5):
        assert P.contains(p[[2, 0]])


def test_operations_return_new_objects():
    Z = ConstrainedZonotope.from_box([-1, -1], [1, 1])
    G0 = Z.G.copy()
    _ = Z + Z, np.eye(2) @ Z, Z.cartesian(Z), Z.intersect_affine([[1, 0]], [0]), Z.project([0])
    np.testing.assert_array_equal(Z.G, G0)
    assert Z.n_con == 0


def test_block_structure_of_sum_is_exact():
    Z1 = ConstrainedZonotope([[1.0, 1.0]], [0.0], [[1.0, -1.0]], [0.5])
    Z2 = ConstrainedZonotope([[2.0]], [1.0], [[1.0]], [0.25], [0.5])
    S = Z1 + Z2
    np.testing.assert_array_equal(S.A, block_diag(Z1.A, Z2.A))
    np.testing.assert_array_equal(S.b, [0.5, 0.25])
    # Z1 = {xi1 + xi2 : xi1 - xi2 = 0.5}: xi2 in [-1, 0.5], x = 2 xi2 + 0.5 in [-1.5, 1.5];
    # Z2 = {2 * 0.25 + 1} = {1.5}; the sum is [0, 3].
    box = S.interval_hull()
    assert box.lo[0] == pytest.approx(0.0, abs=1e-12) and box.hi[0] == pytest.approx(3.0)
    assert box.lo[0] <= 0.0 and box.hi[0] >= 3.0


def test_center_error_carried_as_factors_follows_the_map_not_its_absolute_value():
    """A stable A (spectral radius 0.9) whose |A| has spectral radius 1.17: 100 linear
    maps of a box centred at 100. The hull of ``A^100 Z`` in exact rational
    arithmetic is the oracle. The centre's rounding bound mapped through ``|A|``
    grows like 1.17^k and ends far above the set's width; carried as factors
    (``absorb_center_error``, as the SMFDO's set recursion does) it decays with
    ``A^k`` and the certified hull stays within 1e-9 of the width of the oracle."""
    from fractions import Fraction

    from setobs.geometry.zonotope import absorb_center_error

    R = np.array([[0.6, 1.5], [-1.5, 0.6]])
    A = 0.9 / abs(np.linalg.eigvals(R)).max() * R
    assert max(abs(np.linalg.eigvals(np.abs(A)))) > 1.15
    c0, G0 = np.array([100.0, -50.0]), np.array([[1.0, 0.2], [0.0, 0.5]])
    K = 100
    Af = [[Fraction(float(v)) for v in row] for row in A]
    M = [[Fraction(int(i == j)) for j in range(2)] for i in range(2)]
    for _ in range(K):
        M = [[sum(Af[i][t] * M[t][j] for t in range(2)) for j in range(2)] for i in range(2)]
    MG = [[sum(M[i][t] * Fraction(float(G0[t, j])) for t in range(2)) for j in range(2)]
          for i in range(2)]
    centre = [sum(M[i][t] * Fraction(float(c0[t])) for t in range(2)) for i in range(2)]
    rad = [sum(abs(v) for v in MG[i]) for i in range(2)]
    lo = np.array([float(centre[i] - rad[i]) for i in range(2)])
    hi = np.array([float(centre[i] + rad[i]) for i in range(2)])
    width = hi - lo

    plain = carried = ConstrainedZonotope(G0, c0)
    for _ in range(K):
        plain = A @ plain
        carried = A @ absorb_center_error(carried, 1e-13)
    for Z, ok in ((carried, True), (plain, False)):
        box = Z.interval_hull()
        assert (box.lo <= lo).all() and (box.hi >= hi).all()  # sound either way
        excess = float(np.max(np.maximum(lo - box.lo, box.hi - hi) / width))
        assert (excess <= 1e-9) == ok, excess
    assert carried.n_gen < G0.shape[1] + 2 * K  # absorbed now and then, not every step
    # a centre at zero: the threshold follows the set's reach, not |c| = 0
    Z0 = ConstrainedZonotope(G0, np.zeros(2)).minkowski_sum(np.zeros(2), err=[1e-20, 1e-20])
    assert absorb_center_error(Z0, 1e-13) is Z0
    Zbig = ConstrainedZonotope(G0, np.zeros(2)).minkowski_sum(np.zeros(2), err=[1e-3, 0.0])
    Za = absorb_center_error(Zbig, 1e-13)
    assert Za.n_gen == 3 and not Za.c_err.any()
    box_a, box_b = Za.interval_hull(), Zbig.interval_hull()
    np.testing.assert_allclose([box_a.lo, box_a.hi], [box_b.lo, box_b.hi], rtol=0, atol=1e-15)
