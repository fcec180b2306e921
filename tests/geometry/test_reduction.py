"""Reduction never loses a point; the exact reductions keep the set unchanged."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from setobs import ConstrainedZonotope
from setobs.geometry import reduce_order, remove_redundancy, rescale
from tests.conftest import random_cz, sample_points

seeds = st.integers(0, 2**32 - 1)


def same_supports(Z, W, rng, k=6, tol=1e-7):
    for _ in range(k):
        d = rng.normal(size=Z.dim)
        assert W.support(d) == pytest.approx(Z.support(d), abs=tol * (1 + abs(Z.support(d))))


def test_remove_redundancy_drops_exactly_what_is_redundant(rng):
    # xi4 unused (zero columns), xi5 fixed (h=0); rows: zero row, duplicate, scaled copy,
    # and a sum of two rows (dependent).
    G = np.array([[1.0, 0.0, 1.0, 0.0, 3.0], [0.0, 1.0, 1.0, 0.0, 1.0]])
    A = np.array([
        [1.0, 1.0, 1.0, 0.0, 2.0],
        [0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 1.0, 0.0, 2.0],
        [2.0, 2.0, 2.0, 0.0, 4.0],
        [1.0, -1.0, 0.0, 0.0, 0.0],
        [2.0, 0.0, 1.0, 0.0, 2.0],
    ])
    b = np.array([0.5, 0.0, 0.5, 1.0, 0.2, 0.7])
    Z = ConstrainedZonotope(G, [0.0, 0.0], A, b, [1.0, 1.0, 1.0, 1.0, 0.0])
    R = remove_redundancy(Z)
    assert R.n_gen == 3 and R.n_con == 2
    same_supports(Z, R, rng)


def test_remove_redundancy_keeps_inconsistent_rows():
    Z = ConstrainedZonotope(np.eye(2), [0, 0], [[1.0, 1.0], [1.0, 1.0], [0.0, 0.0]],
                            [0.5, 0.6, 0.0])
    assert Z.is_empty()
    R = Z.remove_redundancy()
    assert R.n_con == 2 and R.is_empty()
    Z0 = ConstrainedZonotope(np.eye(2), [0, 0], [[0.0, 0.0]], [1.0])
    assert Z0.remove_redundancy().is_empty()


@given(seeds)
def test_remove_redundancy_random(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    # Append dependent rows (random combinations) and a zero generator.
    T = rng.normal(size=(2, 2))
    A = np.vstack([Z.A, T @ Z.A])
    b = np.concatenate([Z.b, T @ Z.b])
    W = ConstrainedZonotope(np.hstack([Z.G, np.zeros((2, 1))]), Z.c,
                            np.hstack([A, np.zeros((4, 1))]), b, np.append(Z.h, 2.0))
    R = W.remove_redundancy()
    assert R.n_con == 2 and R.n_gen == 5
    same_supports(Z, R, rng)


@given(seeds)
def test_rescale_keeps_the_set_and_shrinks_factors(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    R = rescale(Z)
    assert R.n_gen <= Z.n_gen
    same_supports(Z, R, rng)
    for p in sample_points(Z, rng, 10):
        assert R.contains(p)


def test_rescale_bounds_unbounded_factors():
    X = ConstrainedZonotope.from_box([-1, -1], [1, 1]).cartesian(
        ConstrainedZonotope.full_space(1))
    M = np.array([[1.0, 0.1, 0.0], [0.0, 1.0, 0.1], [0.0, 0.0, 1.0]])
    Z = (M @ X).intersect_affine([[0.0, 1.0, 0.0]], [0.3])
    R = Z.rescale()
    assert not R.has_unbounded_factors
    # Free factor d in [-7, 13] becomes centre 3 with radius 10 (closed form).
    assert R.interval_hull().lo[2] == pytest.approx(-7.0, abs=1e-9)
    assert R.interval_hull().hi[2] == pytest.approx(13.0, abs=1e-9)
    same_supports(Z, R, np.random.default_rng(0))


@given(seeds)
def test_reduce_order_is_outer(seed):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=1)
    k = 2 + 1 + int(rng.integers(0, 2))  # n + n_c (+1)
    R = reduce_order(Z, k)
    assert R.n_gen <= k
    for p in sample_points(Z, rng, 15):
        assert R.contains(p, tol=1e-9)
    for _ in range(6):
        d = rng.normal(size=2)
        assert R.support(d) >= Z.support(d) - 1e-9


def test_reduce_order_keeps_unbounded_factors_and_noop():
    Z = ConstrainedZonotope(np.hstack([np.eye(2), np.ones((2, 6))]), [0, 0],
                            h=[np.inf, 1, 1, 1, 1, 1, 1, 1])
    R = Z.reduce_order(4)
    assert R.n_gen <= 4 and R.has_unbounded_factors
    assert R.support([1.0, 0.0]) == np.inf
    assert R.support([0.0, 1.0]) >= Z.support([0.0, 1.0]) - 1e-12
    assert Z.reduce_order(10) is Z
