"""Exact mode with noise: the whole-history LP kept from step to step.

Oracles: ``tests.oracles.history_lp_highs`` (the whole-history LP written
independently, in the plant's own coordinates, solved by scipy's HiGHS from
scratch), scipy ``linprog`` on the module's own LP for the certificate (weak
duality must hold for *any* multipliers), and the simulated truth.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from scipy.optimize import linprog

import setobs as so
from setobs.geometry import ConstrainedZonotope
from setobs.setmembership._history import HistoryLP
from setobs.setmembership._model import Entry
from tests.oracles import history_lp_highs, solve_state_history_lp, state_history_lp


def _plant():
    """A lightly damped 4-state plant, 2 outputs, one known input (the bicycle-like
    structure of benchmarks/state_estimation.py, small enough for a test)."""
    A = np.array([[0.95, 0.1, 0.0, 0.0], [-0.2, 0.9, 0.05, 0.0],
                  [0.0, 0.0, 0.98, 0.1], [0.0, 0.05, -0.1, 0.97]])
    B = np.array([[0.0], [0.1], [0.0], [0.05]])
    C = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
    return A, B, C


def _record(N, rw, rv, seed=0, x0=None):
    A, B, C = _plant()
    rng = np.random.default_rng(seed)
    U = np.sin(0.1 * np.arange(N))[:, None]
    x = rng.uniform(-1, 1, 4) if x0 is None else np.asarray(x0, float)
    X, Y = [], []
    for k in range(N):
        X.append(x.copy())
        Y.append(C @ x + rng.uniform(-rv, rv, 2))
        x = A @ x + B @ U[k] + rng.uniform(-rw, rw, 4)
    return np.array(X), np.array(Y), U


def _oracle(Y, U, k, rw, rv, box):
    A, B, C = _plant()
    return history_lp_highs(A, np.zeros((4, 0)), C, Y, k, 0.0, U=U, Gamma=B, states=True,
                            x_box=box, noise_w=(np.eye(4), np.full(4, rw)),
                            noise_v=(np.eye(2), np.full(2, rv)))


def _assert_lp(res, Y, U, ks, rw, rv, box):
    """The state bands at steps ``ks`` equal the whole-history LP within 1e-7 of the
    widest band."""
    for k in ks:
        lo, hi = _oracle(Y, U, k, rw, rv, box)
        tol = 1e-7 * (hi - lo).max()
        np.testing.assert_allclose(res.state_lo[k], lo, rtol=0, atol=tol)
        np.testing.assert_allclose(res.state_hi[k], hi, rtol=0, atol=tol)


@pytest.mark.parametrize("bounded_x0", [True, False])
def test_exact_mode_with_noise_is_the_whole_history_lp(bounded_x0):
    """Every state's band equals the whole-history LP within 1e-7 of the band's
    width, at steps up to 70 (certified bounds as reported with margin=0), and
    the truth is inside at every step. With X0 = R^n the LP starts from the
    posterior whose free factors are pivoted out."""
    rw, rv = 0.01, 0.02
    X, Y, U = _record(71, rw, rv)
    A, B, C = _plant()
    kw = dict(process_noise=rw, measurement_noise=rv, state_bounds=True, margin=0.0)
    box = None
    if bounded_x0:
        kw["initial_state_set"] = so.Box(-2.0 * np.ones(4), 2.0 * np.ones(4))
        box = (-2.0 * np.ones(4), 2.0 * np.ones(4))
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((4, 0)), C, B), window=None, **kw)
    res = obs.run(Y, U)
    assert np.all((X >= res.state_lo) & (X <= res.state_hi))
    assert set(res.status) == {"ok"} if bounded_x0 else set(res.status[4:]) == {"ok"}
    _assert_lp(res, Y, U, (8, 25, 50, 70), rw, rv, box)
    # (most steps on the history LP, not on the set recursion it replaces)
    assert obs.stats["fast"] >= 60


def test_exact_mode_with_noise_and_missing_samples():
    """Missing outputs (NaN) and whole missing samples: still the LP (which leaves
    those rows out), truth inside."""
    rw, rv = 0.005, 0.02
    X, Y, U = _record(61, rw, rv, seed=3)
    Y[10:14, 0] = np.nan
    Y[30] = np.nan
    Y[45:48, 1] = np.nan
    A, B, C = _plant()
    box = (-2.0 * np.ones(4), 2.0 * np.ones(4))
    res = so.SMFDO(so.LinearSystem(A, np.zeros((4, 0)), C, B), window=None, process_noise=rw,
                   measurement_noise=rv, state_bounds=True, margin=0.0,
                   initial_state_set=so.Box(*box)).run(Y, U)
    assert np.all((X >= res.state_lo) & (X <= res.state_hi))
    _assert_lp(res, Y, U, (12, 30, 47, 60), rw, rv, box)


def test_an_inconsistent_sample_is_certified_by_the_set_recursion_and_the_lp_goes_on():
    """An outlier: raised at its step (``on_inconsistent="raise"``); skipped, the
    bands equal the LP without that sample, before and after it."""
    rw, rv = 0.005, 0.02
    X, Y, U = _record(50, rw, rv, seed=5)
    Y[30, 1] += 1.0
    A, B, C = _plant()
    sys = so.LinearSystem(A, np.zeros((4, 0)), C, B)
    box = (-2.0 * np.ones(4), 2.0 * np.ones(4))
    kw = dict(process_noise=rw, measurement_noise=rv, state_bounds=True, margin=0.0,
              initial_state_set=so.Box(*box))
    with pytest.raises(so.ModelInvalidatedError) as err:
        so.SMFDO(sys, window=None, **kw).run(Y, U)
    assert err.value.step == 30
    obs = so.SMFDO(sys, window=None, on_inconsistent="skip", **kw)
    with pytest.warns(so.ModelInvalidatedWarning):
        res = obs.run(Y, U)
    assert list(np.flatnonzero(res.status == "skipped")) == [30]
    assert np.all((X >= res.state_lo) & (X <= res.state_hi))
    Ym = Y.copy()
    Ym[30] = np.nan
    _assert_lp(res, Ym, U, (29, 30, 31, 49), rw, rv, box)
    assert obs.stats["fast"] >= 40


def test_a_copy_and_a_pickle_go_on_like_the_original():
    """Mid-record copies (their HiGHS models rebuilt cold) give the same bands
    as the original within the certificate's accepted gap."""
    rw, rv = 0.01, 0.02
    _, Y, U = _record(60, rw, rv, seed=2)
    A, B, C = _plant()
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((4, 0)), C, B), window=None, process_noise=rw,
                   measurement_noise=rv, state_bounds=True,
                   initial_state_set=so.Box(-2.0 * np.ones(4), 2.0 * np.ones(4)))
    obs.run(Y[:30], U[:30])
    twins = [copy.copy(obs), pickle.loads(pickle.dumps(obs))]
    a = obs.continue_run(Y[30:], U[30:])
    for t in twins:
        b = t.continue_run(Y[30:], U[30:])
        np.testing.assert_allclose(b.state_lo, a.state_lo, rtol=0, atol=1e-8)
        np.testing.assert_allclose(b.state_hi, a.state_hi, rtol=0, atol=1e-8)


def test_time_varying_noise_sets():
    """Callable noise bounds (a larger measurement noise on odd steps): the LP with
    each step's own sets (the oracle's noise bounds per step)."""
    rw = 0.01
    rv_k = lambda k: 0.04 if k % 2 else 0.02  # noqa: E731
    A, B, C = _plant()
    rng = np.random.default_rng(7)
    N = 41
    U = np.sin(0.1 * np.arange(N))[:, None]
    x = rng.uniform(-1, 1, 4)
    X, Y = [], []
    for k in range(N):
        X.append(x.copy())
        Y.append(C @ x + rng.uniform(-rv_k(k), rv_k(k), 2))
        x = A @ x + B @ U[k] + rng.uniform(-rw, rw, 4)
    X, Y = np.array(X), np.array(Y)
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((4, 0)), C, B), window=None, process_noise=rw,
                   measurement_noise=lambda k: np.full(2, rv_k(k)), state_bounds=True,
                   margin=0.0, initial_state_set=so.Box(-2.0 * np.ones(4), 2.0 * np.ones(4)))
    res = obs.run(Y, U)
    assert np.all((X >= res.state_lo) & (X <= res.state_hi))
    # the oracle with each step's own noise bound
    for k in (20, 40):
        lo, hi, _ = solve_state_history_lp(
            *state_history_lp(A, B, C, Y, U, k, rw, [rv_k(j) for j in range(k + 1)],
                              (-2.0 * np.ones(4), 2.0 * np.ones(4))), 4)
        w = hi - lo
        np.testing.assert_allclose(res.state_lo[k], lo, rtol=0, atol=1e-7 * w.max())
        np.testing.assert_allclose(res.state_hi[k], hi, rtol=0, atol=1e-7 * w.max())
    assert obs.stats["fast"] >= 30


# ----------------------------------------------------------------- the certificate
def _small_history(steps=6, seed=0):
    """A HistoryLP of a 2-state model grown by ``steps`` steps of noisy data."""
    rng = np.random.default_rng(seed)
    A = np.array([[1.0, 0.1], [-0.3, 0.9]])
    Gam = np.array([[0.0], [0.1]])
    C = np.array([[1.0, 0.0]])
    E = np.eye(2)
    W = ConstrainedZonotope.from_box([-0.01, -0.01], [0.01, 0.01])
    V = ConstrainedZonotope(np.array([[0.05, 0.02]]), np.zeros(1), A=np.array([[1.0, -1.0]]),
                            b=np.array([0.1]), h=np.array([1.0, 1.0]))
    Z0 = ConstrainedZonotope.from_box([-1.0, -1.0], [1.0, 1.0])
    H = HistoryLP.start(Z0, -np.ones(2), np.ones(2), A_o=A, Gamma_o=Gam, C_o=C,
                        B_o=np.zeros((2, 0)), E_o=E, rows=np.zeros((0, 2)), data_rtol=1e-15)
    x = rng.uniform(-0.5, 0.5, 2)
    for k in range(steps):
        u = np.array([np.sin(k)])
        x = A @ x + Gam @ u + rng.uniform(-0.01, 0.01, 2)
        nu2 = rng.uniform(-1.0, 0.9)  # (nu1 = nu2 + 0.1: a point of V)
        y = C @ x + 0.05 * (nu2 + 0.1) + 0.02 * nu2
        H.push(Entry(y, u, None, W, V, None))
        assert H.hull() is not None  # (the next push starts from this hull)
    return H


def _lp_min(H, w):
    A, b, _, lo, hi = H.lp()
    c = np.zeros(A.shape[1])
    c[H.state_columns] = w
    res = linprog(c, A_eq=A, b_eq=b, bounds=list(zip(lo, hi, strict=True)), method="highs",
                  options={"primal_feasibility_tolerance": 1e-10,
                           "dual_feasibility_tolerance": 1e-10})
    assert res.status == 0
    return res.fun, res.eqlin.marginals


def test_the_certificate_is_a_lower_bound_for_any_multipliers():
    """Weak duality: ``certify`` gives at most the LP's minimum for random and
    perturbed multipliers (a sign error or a missing term would break this), and
    equals it to 1e-9 with scipy's optimal duals."""
    H = _small_history()
    rng = np.random.default_rng(1)
    for w in (np.array([1.0, 0.0]), np.array([0.0, -1.0]), np.array([0.6, 0.8])):
        fmin, y_opt = _lp_min(H, w)
        assert H.certify(H.state_columns, w, y_opt) == pytest.approx(fmin, abs=1e-9)
        for scale in (1e-6, 1e-3, 1.0, 10.0):
            y = y_opt + scale * rng.normal(size=y_opt.size)
            assert H.certify(H.state_columns, w, y) <= fmin + 1e-12
        assert H.certify(H.state_columns, w, np.zeros(y_opt.size)) <= fmin


def test_the_hull_is_certified_and_the_set_as_a_cz_is_the_same_set():
    """``hull`` equals the LP's optima (scipy) from below within 1e-9, and the
    posterior as a constrained zonotope (for the set recursion) has the same
    interval hull within its certified rounding."""
    H = _small_history(steps=8, seed=4)
    lo, hi = H.hull()
    for i in range(2):
        w = np.eye(2)[i]
        fmin, _ = _lp_min(H, w)
        fmax = -_lp_min(H, -w)[0]
        assert fmin - 1e-9 <= lo[i] <= fmin + 1e-12
        assert fmax - 1e-12 <= hi[i] <= fmax + 1e-9
    box = H.to_cz().interval_hull()
    np.testing.assert_allclose(box.lo, lo, atol=1e-9)
    np.testing.assert_allclose(box.hi, hi, atol=1e-9)
    assert np.all(box.lo <= lo + 1e-12) and np.all(box.hi >= hi - 1e-12)
