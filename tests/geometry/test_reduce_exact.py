"""reduce_exact: the same set with less representation (Scott et al. 2016, Sec. 4.2, exact variant).

Geometry is compared with an independent LP (scipy's linprog on each
representation's own factor polytope); the certified support functions of the
result must stay outward of that value.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.optimize import linprog

import setobs as so
from setobs import ConstrainedZonotope
from setobs.exceptions import EmptySetError
from setobs.geometry import reduce_exact
from tests.conftest import random_cz


def lp_support(Z: ConstrainedZonotope, d: np.ndarray) -> float:
    """max d^T z over Z by scipy/HiGHS on the factor polytope (independent of setobs' LP layer)."""
    bounds = [(None, None) if np.isinf(h) else (-h, h) for h in Z.h]
    kw = {"A_eq": Z.A, "b_eq": Z.b} if Z.n_con else {}
    res = linprog(-(Z.G.T @ d), bounds=bounds, method="highs", **kw)
    assert res.status == 0, res.message
    return float(-res.fun + d @ Z.c)


def assert_same_set(Z, R, rng, k=12, rtol=1e-9):
    for _ in range(k):
        d = rng.normal(size=Z.dim)
        ref = lp_support(Z, d)
        tol = rtol * (1.0 + abs(ref))
        assert lp_support(R, d) == pytest.approx(ref, abs=tol)
        # certified support of the result: outward, and tight
        s = R.support(d)
        assert s >= ref - 1e-12 * (1.0 + abs(ref))
        assert s <= ref + tol


def test_implied_slack_is_removed_and_a_cutting_one_kept(rng):
    G = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    # |x1 + x2| <= 3 on the unit square: implied
    Z = ConstrainedZonotope(G, [0.0, 0.0], A=[[1.0, 1.0, 1.0]], b=[0.0], h=[1.0, 1.0, 3.0])
    R = reduce_exact(Z)
    assert (R.n_gen, R.n_con) == (2, 0)
    for d in rng.normal(size=(8, 2)):
        assert R.support(d) == pytest.approx(abs(d[0]) + abs(d[1]), abs=1e-12)
    # |x1 + x2| <= 1 cuts two corners: nothing can go
    W = ConstrainedZonotope(G, [0.0, 0.0], A=[[1.0, 1.0, 1.0]], b=[0.0], h=[1.0, 1.0, 1.0])
    RW = reduce_exact(W)
    assert (RW.n_gen, RW.n_con) == (3, 1)
    assert RW.support([1.0, 1.0]) == pytest.approx(1.0, abs=1e-12)
    assert RW.support([1.0, 0.0]) == pytest.approx(1.0, abs=1e-12)


def test_fixed_factor_moves_into_the_centre():
    # xi3 = 0.5 by the constraint: the set is the unit square shifted by 0.5 * (2, -1)
    Z = ConstrainedZonotope([[1.0, 0.0, 2.0], [0.0, 1.0, -1.0]], [1.0, 1.0],
                            A=[[0.0, 0.0, 1.0]], b=[0.5], h=[1.0, 1.0, 1.0])
    R = reduce_exact(Z)
    assert (R.n_gen, R.n_con) == (2, 0)
    assert np.allclose(R.c, [2.0, 0.5], atol=1e-15)
    assert np.allclose(np.abs(R.G), np.eye(2))


def test_unbounded_factors_are_eliminated_exactly(rng):
    # the strip {|x2| <= 1} (an unbounded factor along x1) intersected with the
    # line x1 = x2 / 2 + 0.3: a segment
    Z = ConstrainedZonotope([[1.0, 0.0], [0.0, 1.0]], [0.0, 0.0], h=[np.inf, 1.0])
    L = Z.intersect_affine([[1.0, -0.5]], [0.3])
    assert L.has_unbounded_factors
    R = reduce_exact(L)
    assert not R.has_unbounded_factors and R.n_con == 0
    assert R.support([1.0, 0.0]) == pytest.approx(0.8, abs=1e-14)
    assert R.support([-1.0, 0.0]) == pytest.approx(0.2, abs=1e-14)
    # a set with a lineality space keeps it
    P = ConstrainedZonotope([[1.0, 0.0, 0.0], [0.0, 1.0, 1.0]], [0.0, 0.0], A=[[0.0, 1.0, -1.0]],
                            b=[0.0], h=[np.inf, 1.0, np.inf])
    RP = reduce_exact(P)
    assert RP.support([1.0, 0.0]) == np.inf
    assert RP.support([0.0, 1.0]) == pytest.approx(2.0, abs=1e-14)


def test_empty_set_is_reported():
    Z = ConstrainedZonotope([[1.0, 1.0]], [0.0], A=[[1.0, 1.0]], b=[3.0])
    with pytest.raises(EmptySetError):
        reduce_exact(Z)


def _with_redundancy(rng, Z):
    """Z plus an implied slack row and a factor fixed by an unbounded elimination."""
    n_g = Z.n_gen
    a = rng.normal(size=n_g)
    bmax = float(np.abs(a) @ Z.h)
    # a^T xi + s = 0 with |s| <= 1.5 max|a^T xi|: implied
    A = np.vstack([np.hstack([Z.A, np.zeros((Z.n_con, 2))]),
                   np.hstack([a, [1.0, 0.0]]),
                   np.hstack([rng.normal(size=n_g), [0.0, 1.0]])])
    b = np.concatenate([Z.b, [0.0, 0.7]])
    G = np.hstack([Z.G, rng.normal(size=(Z.dim, 1)), rng.normal(size=(Z.dim, 1))])
    h = np.concatenate([Z.h, [1.5 * bmax + 1.0, np.inf]])
    return ConstrainedZonotope(G, Z.c, A, b, h)


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_random_sets_keep_their_geometry(seed):
    rng = np.random.default_rng(seed)
    base = random_cz(rng, n=int(rng.integers(1, 4)), n_g=int(rng.integers(2, 6)))
    Z = _with_redundancy(rng, base)
    R = reduce_exact(Z)
    # the implied slack row and the row of the unbounded factor are gone
    assert R.n_con <= Z.n_con - 2
    assert not R.has_unbounded_factors
    assert_same_set(Z, R, rng)
    # idempotent in size
    R2 = reduce_exact(R)
    assert R2.n_con <= R.n_con and R2.n_gen <= R.n_gen


def test_exact_mode_posterior_of_the_paper_example(rng):
    """The exact-mode set at k = 5 of Li-Cong-Dong's example: by eqs. (20)-(24) it has
    n + q = 5 free factors (x_0, d_0), q = 2 increment factors per step (10) and
    l = 2 rows per measurement (12): (15, 12), a count from the algorithm's definition.
    reduce_exact gives the same set (supports in random directions against scipy's
    linprog over the original representation, ``lp_support``) with at most 2 rows and
    6 factors: the 5 free factors go with 5 rows exactly, and the increments' bounds
    the data imply are redundant."""
    from benchmarks.smfdo import data

    sys, Y, _ = data(8)
    obs = so.SMFDO(sys, window=None, fast=False)  # the whole-history set recursion
    for y in Y[:6]:
        obs.step(y)
    Z = obs.posterior_set
    R = Z.reduce_exact()
    assert (Z.n_gen, Z.n_con) == (15, 12)
    assert R.n_con <= 2 and R.n_gen <= 6
    assert_same_set(Z, R, rng, rtol=1e-9)
