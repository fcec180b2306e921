"""The fast fixed-structure LP path against the HiGHS reference, exact optima and its own limits."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from setobs import EmptySetError
from setobs.lp.factor import FactorPolytope
from setobs.lp.fastlp import FixedStructureLP
from tests.conftest import exact_extremes, random_cz

RTOL = 1e-8


def _agree(fast: float, ref: float) -> bool:
    if np.isinf(fast) or np.isinf(ref):
        return fast == ref
    return abs(fast - ref) <= RTOL * (1.0 + abs(ref))


def _random_structure(rng, free_p=0.15):
    m = int(rng.integers(0, 13))
    n = m + int(rng.integers(1, 11))
    A = rng.normal(size=(m, n)) * 10.0 ** rng.uniform(-1, 1)
    free = rng.random(n) < free_p
    W = rng.normal(size=(6, n))
    return A, np.vstack([W, -W]), free


def test_fast_lp_equals_highs_on_12000_random_instances():
    """>= 10 000 random LPs (with free factors): every fast bound equals HiGHS's to 1e-8."""
    rng = np.random.default_rng(2026)
    total = solved = 0
    for _ in range(200):
        A, W, free = _random_structure(rng)
        S = FixedStructureLP(A, W, free)
        assert S.usable, S.reason
        for _ in range(5):
            h = np.where(free, np.inf, rng.uniform(0.0, 3.0, free.size))
            xi = np.where(free, rng.normal(size=free.size), rng.uniform(-1, 1, free.size) * h)
            b = A @ xi
            bounds, ok = S.minimize_all(b, h)
            fp = FactorPolytope(A, b, h)
            for i in range(W.shape[0]):
                total += 1
                if not ok[i]:
                    continue
                solved += 1
                ref = fp.minimize(W[i]).bound
                assert _agree(bounds[i], ref), (bounds[i], ref)
    assert total >= 10_000
    assert solved >= 0.99 * total  # the fast path is not a fallback in disguise


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_fast_bound_never_exceeds_the_exact_minimum(seed):
    """Outward after certification: checked against rational vertex enumeration."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    W = np.vstack([Z.G, -Z.G])
    S = FixedStructureLP(Z.A, W, np.isinf(Z.h))
    bounds, ok = S.minimize_all(Z.b, Z.h)
    for i in range(2):
        e = np.zeros(2)
        e[i] = 1.0
        lo, hi = exact_extremes(Z, e)
        c = Fraction(float(Z.c[i]))
        for bnd, good, exact in ((bounds[i], ok[i], lo - c), (bounds[2 + i], ok[2 + i], c - hi)):
            if good:
                assert Fraction(bnd) <= exact
                assert float(exact - Fraction(bnd)) <= RTOL * (1 + abs(float(exact)))


def test_degenerate_instances_are_exact_or_flagged():
    rng = np.random.default_rng(4)
    checked = 0
    for _ in range(60):
        m, n = 6, 12
        A = rng.normal(size=(m, n))
        A[:, 6:9] = A[:, 0:3]  # duplicated columns (dual degeneracy)
        h = rng.uniform(0.5, 2.0, n)
        h[10] = 0.0  # a fixed factor
        # a vertex of the box: primal degenerate right-hand side
        xi = np.sign(rng.normal(size=n)) * h
        b = A @ xi
        W = np.vstack([rng.normal(size=(3, n)), np.zeros((1, n))])
        W[1, 6:9] = W[1, 0:3]
        S = FixedStructureLP(A, np.vstack([W, -W]), np.zeros(n, bool))
        bounds, ok = S.minimize_all(b, h)
        fp = FactorPolytope(A, b, h)
        for i in np.flatnonzero(ok):
            assert _agree(bounds[i], fp.minimize(S.W[i]).bound)
            checked += 1
    assert checked >= 300


def test_infeasible_instances_are_handed_to_the_reference():
    rng = np.random.default_rng(5)
    A = rng.normal(size=(4, 7))
    h = np.ones(7)
    b = A @ np.ones(7) * 3.0 + 10.0  # far outside A [-1, 1]^7 in some row
    W = np.vstack([np.eye(7)[:2], -np.eye(7)[:2]])
    S = FixedStructureLP(A, W, np.zeros(7, bool))
    _, ok = S.minimize_all(b, h)
    assert not ok.any()
    with pytest.raises(EmptySetError):
        FactorPolytope(A, b, h).minimize(W[0])


def test_unbounded_directions_are_minus_inf_like_the_reference():
    # x = xi_0 (free), y = xi_1 (free) with xi_0 + xi_1 + xi_2 = 0.5, |xi_2| <= 1.
    A = np.array([[1.0, 1.0, 1.0]])
    W = np.array([[1.0, 0, 0], [-1.0, 0, 0], [1.0, 1.0, 0], [-1.0, -1.0, 0]])
    free = np.array([True, True, False])
    S = FixedStructureLP(A, W, free)
    h = np.array([np.inf, np.inf, 1.0])
    bounds, ok = S.minimize_all(np.array([0.5]), h)
    assert ok.all()
    fp = FactorPolytope(A, np.array([0.5]), h)
    for i in range(4):
        assert _agree(bounds[i], fp.minimize(W[i]).bound)
    assert np.isinf(bounds[:2]).all()
    # every multiplier a step reports is written, the unbounded directions' too (zero):
    # the window's allowances |y| b_err read them all (a stale row once gave NaN there)
    state = S.new_state()
    state.ys[:] = np.nan
    b2, ok2 = S.minimize_all(np.array([0.5]), h, state)
    assert ok2.all() and np.isfinite(state.ys).all() and np.array_equal(b2, bounds)
    assert (state.ys[:2] == 0.0).all()
    # xi_0 + xi_1 = 0.5 - xi_2 is in [-0.5, 1.5]
    assert bounds[2] <= -0.5 and bounds[2] > -0.5 - 1e-12
    assert bounds[3] <= -1.5 and bounds[3] > -1.5 - 1e-12


def test_redundant_rows_need_consistent_data():
    """More rows than the row rank (more measurements than new factors, l > q)."""
    A = np.array([[1.0, 2.0, 0.5], [2.0, 4.0, 1.0], [0.0, 1.0, -1.0]])  # row 2 = 2 row 1
    W = np.vstack([np.eye(3), -np.eye(3)])
    S = FixedStructureLP(A, W, np.zeros(3, bool))
    assert S.usable and S.Q0.shape[1] == 1
    h = np.ones(3)
    b = A @ np.array([0.2, -0.1, 0.3])
    bounds, ok = S.minimize_all(b, h)
    assert ok.all()
    fp = FactorPolytope(A, b, h)
    assert all(_agree(bounds[i], fp.minimize(W[i]).bound) for i in range(6))
    # data off the row space (an outlier): the reference decides (here: empty)
    _, ok = S.minimize_all(b + np.array([0.0, 1.0, 0.0]), h)
    assert not ok.any()
    with pytest.raises(EmptySetError):
        FactorPolytope(A, b + np.array([0.0, 1.0, 0.0]), h).minimize(W[0])


def test_structures_needing_rank_decisions_are_refused():
    A = np.array([[1.0, 2.0, 0.0], [1.0, 2.0 + 1e-9, 0.0]])  # nearly dependent rows
    S = FixedStructureLP(A, np.eye(3), np.zeros(3, bool))
    assert not S.usable and "redundant" in S.reason
    _, ok = S.minimize_all(np.array([1.0, 1.0]), np.ones(3))
    assert not ok.any()
    with pytest.raises(ValueError, match="unbounded factors"):
        S.minimize_all(np.array([1.0, 2.0]), np.array([1.0, np.inf, 1.0]))


def test_warm_start_survives_new_data():
    rng = np.random.default_rng(8)
    A = rng.normal(size=(5, 9))
    W = np.vstack([np.eye(9)[:3], -np.eye(9)[:3]])
    S = FixedStructureLP(A, W, np.zeros(9, bool))
    state = S.new_state()
    pivots = 0
    for _ in range(200):  # many rhs on the same bases: refactorisations happen
        h = rng.uniform(0.5, 2, 9)
        b = A @ (rng.uniform(-1, 1, 9) * h)
        bounds, ok = S.minimize_all(b, h, state)
        pivots += int(state.npiv.sum())
        assert ok.all()
        fp = FactorPolytope(A, b, h)
        assert all(_agree(bounds[i], fp.minimize(W[i]).bound) for i in range(6))
    assert pivots > 0  # the state really was carried from call to call


def _window_lp(rng, n_state=6, steps=10, l=4):
    """The SMFDO window's LP shape (states eliminated): ``A``, the hull objectives of the
    last state (pairs ``(w, -w)``) and the factor bounds."""
    m = steps * l
    A = np.zeros((m, n_state + steps * (n_state + l)))
    Phi = rng.normal(size=(n_state, n_state))
    Phi *= 0.95 / np.abs(np.linalg.eigvals(Phi)).max()
    C = rng.normal(size=(l, n_state))
    M = np.eye(n_state)
    for t in range(steps):  # y_t = C (Phi^t z0 + sum Phi^(t-s) w_s) + v_t
        M = Phi @ M
        A[t * l:(t + 1) * l, :n_state] = C @ M
        for s in range(t + 1):
            P = np.linalg.matrix_power(Phi, t - s)
            col = n_state + s * (n_state + l)
            A[t * l:(t + 1) * l, col:col + n_state] = C @ P
        col = n_state + t * (n_state + l) + n_state
        A[t * l:(t + 1) * l, col:col + l] = np.eye(l)
    n = A.shape[1]
    W = np.zeros((2 * n_state, n))
    for i in range(n_state):  # the last state's coordinates: Phi^steps z0 + ...
        row = np.zeros(n)
        Mk = np.linalg.matrix_power(Phi, steps)
        row[:n_state] = Mk[i]
        for s in range(steps):
            col = n_state + s * (n_state + l)
            row[col:col + n_state] = np.linalg.matrix_power(Phi, steps - 1 - s)[i]
        W[2 * i], W[2 * i + 1] = row, -row
    h = np.concatenate([np.full(n_state, 2.0)] + [np.r_[np.full(n_state, 0.01),
                                                        np.full(l, 0.05)]] * steps)
    return A, W, h


def test_window_like_lps_with_many_boxed_noise_factors():
    """The SMFDO window's LP shape: a few state factors and many small boxed noise
    factors entering banded rows (random 6-state plant, window 10: 40 x 106). The
    bound-flipping dual simplex, then the primal simplex from the previous
    objective's basis, agree with HiGHS on every objective and every new data
    set, with the warm state carried (there the short-step dual needed 500-2000
    pivots per LP and ran into its iteration limit)."""
    rng = np.random.default_rng(33)
    A, W, h = _window_lp(rng)
    n = A.shape[1]
    S = FixedStructureLP(A, W, np.zeros(n, bool))
    state = S.new_state()
    solved = total = 0
    for _ in range(15):
        xi = rng.uniform(-1, 1, n) * h
        b = A @ xi
        bounds, ok = S.minimize_all(b, h, state)
        fp = FactorPolytope(A, b, h)
        for i in range(W.shape[0]):
            total += 1
            if ok[i]:
                solved += 1
                assert _agree(bounds[i], fp.minimize(W[i]).bound), i
    assert solved == total


@pytest.mark.parametrize("rel_gap", [1e-3, 0.05])
def test_the_early_stop_stays_below_the_minimum_within_its_gap(rel_gap):
    """``rel_gap``: on window-shaped LPs with new data at every call, each bound is at
    most the exact minimum (HiGHS) and below it by at most ``rel_gap`` times the pair's
    width at the previous call (plus rounding), and the chain needs fewer iterations
    than to the optimum. Objectives not in pairs ``(w, -w)`` ignore it."""
    A, W, h = _window_lp(np.random.default_rng(33))
    n = A.shape[1]
    S = FixedStructureLP(A, W, np.zeros(n, bool))
    assert S.paired
    exact_state, early_state = S.new_state(), S.new_state()
    rng = np.random.default_rng(4)
    width = None
    early = 0
    for _ in range(12):
        b = A @ (rng.uniform(-1, 1, n) * h)
        _, ok0 = S.minimize_all(b, h, exact_state)
        bounds, ok = S.minimize_all_unchecked(b, h, early_state, rel_gap=rel_gap)
        assert ok0.all() and ok.all()
        fp = FactorPolytope(A, b, h)
        ref = np.array([fp.minimize(w).bound for w in W])
        assert (bounds <= ref + 1e-9 * (1 + np.abs(ref))).all()
        if width is not None:  # (the first call has no previous widths: to the optimum)
            slack = 1.01 * rel_gap * np.repeat(width, 2) + 1e-8 * (1 + np.abs(ref))
            assert (ref - bounds <= slack).all()
            early += int((ref - bounds > 1e-8 * (1 + np.abs(ref))).sum())
        else:
            np.testing.assert_allclose(bounds, ref, rtol=1e-8, atol=1e-8)
        width = -bounds[1::2] - bounds[0::2]
    assert early > 0  # (some bounds did stop short of the minimum)
    assert early_state.iters.sum() < exact_state.iters.sum()
    unpaired = FixedStructureLP(A, np.vstack([W[0::2], W[1::2]]), np.zeros(n, bool))
    assert not unpaired.paired


def test_the_reduced_data_are_the_lp_the_simplex_solves():
    """``reduced_data``: the reduced LP (here without free factors: the equilibrated copy)
    solved by HiGHS (scipy's linprog) has the minima of ``minimize_all``."""
    from scipy.optimize import linprog

    A, W, h = _window_lp(np.random.default_rng(5), steps=4)
    n = A.shape[1]
    S = FixedStructureLP(A, W, np.zeros(n, bool))
    b = A @ (np.random.default_rng(6).uniform(-1, 1, n) * h)
    bounds, ok = S.minimize_all(b, h)
    hB, bred, consistent = S.reduced_data(b, h)
    assert ok.all() and consistent
    for i in range(W.shape[0]):
        r = linprog(S.Wred[i], A_eq=S.Ared, b_eq=bred, bounds=np.c_[-hB, hB], method="highs")
        assert r.status == 0
        assert abs(r.fun - bounds[i]) <= 1e-7 * (1 + abs(bounds[i]))
