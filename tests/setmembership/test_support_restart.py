"""The window's restart with ranges from its own support values.

The restart polytope's rows ``F`` (the axes carried back through the dynamics) get their
ranges from the hulls of earlier steps carried forward with the noise, intersected with
the support values of the window's posterior ``Z_t`` in the rows' directions, computed at
``t`` as extra objectives. Checked against the whole-history LP (HiGHS, every state a
variable: ``tests.oracles.history_lp_highs``), an independent computation of the exact
set, on a planar constant-velocity target of our own (every eigenvalue 1, where carried
ranges grow with every lag).
"""

from __future__ import annotations

import numpy as np
import pytest

import setobs as so
from setobs.setmembership.engines import window as window_engine
from tests.oracles import history_lp_highs

DT, RV, RADIUS, SIDES = 0.01, 0.1, 0.0017, 10


def cv_target():
    """``(A, C, E, G_w)``: positions measured; process noise on the velocities a regular
    decagon of circumradius ``RADIUS`` (5 generators of length ``RADIUS sin(pi / 10)``)."""
    A = np.eye(4)
    A[0, 2] = A[1, 3] = DT
    C = np.eye(4)[:2]
    E = np.zeros((4, 2))
    E[2, 0] = E[3, 1] = 1.0
    ang = np.pi * np.arange(SIDES // 2) / (SIDES // 2)
    Gw = RADIUS * np.sin(np.pi / SIDES) * np.vstack([np.cos(ang), np.sin(ang)])
    return A, C, E, Gw


def record(N, seed, corners):
    """States and measurements; with ``corners`` the noise factors and the measurement
    noise on their boxes' corners."""
    A, C, E, Gw = cv_target()
    rng = np.random.default_rng(seed)
    x = np.array([0.3, -0.2, 0.5, 0.4]) + rng.uniform(-0.5, 0.5, 4)
    X, Y = [], []
    for _ in range(N):
        X.append(x.copy())
        v = RV * (rng.choice([-1.0, 1.0], 2) if corners else rng.uniform(-1, 1, 2))
        Y.append(C @ x + v)
        xi = rng.choice([-1.0, 1.0], Gw.shape[1]) if corners else rng.uniform(-1, 1, Gw.shape[1])
        x = A @ x + E @ (Gw @ xi)
    return np.array(X), np.array(Y)


def observer(window=10, **kw):
    A, C, E, Gw = cv_target()
    return so.SMFDO(so.LinearSystem(A, np.zeros((4, 0)), C), window=window,
                    process_noise=so.ConstrainedZonotope(Gw, np.zeros(2)),
                    process_noise_matrix=E, measurement_noise=RV, state_bounds=True,
                    initial_state_set=so.Box(-2.0 * np.ones(4), 2.0 * np.ones(4)), **kw)


@pytest.fixture(scope="module")
def exact_cv():
    """The record and the exact state bounds at every tenth step from 60 on, by the
    whole-history LP, independent of the SMFDO's closed forms. (The transient is left
    out: the first restarts start from the early, wide sets, and on this record window 10
    is 1.37, 1.32 and 1.27 times the exact set at k = 30, 40 and 50 in its worst
    coordinate, then at most 1.07.)"""
    A, C, E, Gw = cv_target()
    N = 160
    X, Y = record(N, 0, corners=False)
    ks = list(range(60, N, 10))
    ref = {k: history_lp_highs(A, np.zeros((4, 0)), C, Y, k, 0.0, states=True,
                               x_box=(-2.0 * np.ones(4), 2.0 * np.ones(4)),
                               noise_w=(E @ Gw, np.ones(Gw.shape[1])),
                               noise_v=(np.eye(2), np.full(2, RV))) for k in ks}
    return X, Y, ks, ref


def ratios(res, ks, ref):
    return np.array([(res.state_hi[k] - res.state_lo[k]) / (ref[k][1] - ref[k][0])
                     for k in ks])


def test_window_10_is_within_the_target_of_the_exact_set(exact_cv):
    """Window 10 with the default restart: mean / worst width at most 1.05 / 1.25 times
    the exact set's, never narrower than it, the truth inside at every step; the
    restarts used the support values."""
    X, Y, ks, ref = exact_cv
    obs = observer()
    res = obs.run(Y)
    assert np.all((X >= res.state_lo) & (X <= res.state_hi))
    r = ratios(res, ks, ref)
    assert r.min() >= 1.0 - 1e-9
    assert r.mean() <= 1.05 and r.max() <= 1.25, (r.mean(), r.max())
    assert obs.stats["support_restarts"] > 0.5 * len(Y)


def test_without_the_support_values_the_same_window_is_wider(exact_cv, monkeypatch):
    """The carried ranges alone (the restart before this change): wider on the same record
    against the same exact set (1.10 / 1.31 on a held-out target of this kind with 29
    lags; here, with 59, 1.05 against 1.02 on average)."""
    X, Y, ks, ref = exact_cv
    with_support = ratios(observer().run(Y), ks, ref)
    monkeypatch.setattr(window_engine, "SUPPORT_RANGES", False)
    obs = observer()
    res = obs.run(Y)
    assert np.all((X >= res.state_lo) & (X <= res.state_hi))
    assert obs.stats["support_restarts"] == 0
    r = ratios(res, ks, ref)
    assert r.min() >= 1.0 - 1e-9
    assert r.mean() > with_support.mean() + 0.02, (r.mean(), with_support.mean())
    assert r.max() > with_support.max(), (r.max(), with_support.max())


@pytest.mark.parametrize("window", [3, 10])
@pytest.mark.parametrize("restart", ["polytope", "auto"])
def test_the_truth_stays_inside_with_noise_on_the_corners(window, restart):
    """Noise on its sets' corners (the LPs' degenerate vertices): the truth inside every
    band at every step, with the support values in use."""
    for seed in (1, 2):
        X, Y = record(120, seed, corners=True)
        obs = observer(window, restart=restart)
        res = obs.run(Y)
        assert np.all((X >= res.state_lo) & (X <= res.state_hi)), (seed, window, restart)
        assert obs.stats["support_restarts"] > 0


def test_the_support_values_are_outer_bounds_of_the_true_rows():
    """Each stored support range (the posterior's ``F z`` over the window) holds ``F x_k`` of
    the true state at every step that computed one (every step while they pay, else the
    probes')."""
    X, Y = record(80, 3, corners=True)
    obs = observer(restart="polytope")
    F = obs.model.restart_poly.F_all
    seen = 0
    for k in range(len(Y)):
        obs.step(Y[k])
        sup = obs._state.support[-1]
        if sup is None:
            continue
        seen += 1
        fx = F @ X[k]  # (z = x here: every state observable, no transformation)
        assert np.all(sup[0] <= fx) and np.all(fx <= sup[1]), k
    assert seen >= 10
