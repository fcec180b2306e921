"""Certified state bounds: ``SMFDO(..., state_bounds=True)``, and a
system without disturbances (q = 0) as a set-membership state observer.

Oracle: the whole-history LP of the state (``tests.oracles.history_lp_highs``, scipy's
HiGHS with every state a variable; no setobs code):
variables ``x_0`` (free), ``d_0`` (free), the increments and the process noise; the
outputs within the measurement-noise radius."""

from __future__ import annotations

import numpy as np
import pytest

import setobs as so
from tests.oracles import history_lp_highs


def state_history_lp(Phi, G, Xi, Y, k, rw, rv, r_inc=1.0):
    """Bounds of ``x_k`` over every history consistent with ``Y[:k+1]``:
    ``x+ = Phi x + G d + w`` (``|w| <= rw``), ``d+ = d + dd`` (``|dd| <= r_inc``),
    ``|y - Xi x| <= rv``; ``x_0``, ``d_0`` free (``tests.oracles.history_lp_highs``)."""
    n, l = Phi.shape[0], Xi.shape[0]
    return history_lp_highs(
        Phi, G, Xi, Y, k, r_inc, states=True,
        noise_w=(np.eye(n), np.full(n, rw)) if rw else None,
        noise_v=(np.eye(l), np.full(l, rv)) if rv else None)


def _record(Phi, G, Xi, N, rw, rv, rng, r_inc=1.0):
    n, q = Phi.shape[0], G.shape[1]
    x, d = rng.normal(size=n), rng.normal(size=q)
    X, Y = [], []
    for _ in range(N):
        X.append(x.copy())
        Y.append(Xi @ x + rng.uniform(-rv, rv, Xi.shape[0]))
        x = Phi @ x + G @ d + rng.uniform(-rw, rw, n)
        d = d + rng.uniform(-r_inc, r_inc, q)
    return np.array(X), np.array(Y)


PHI3 = np.array([[0.8, 0.3, 0.0], [-0.2, 0.7, 0.4], [0.1, 0.0, 0.6]])
XI3 = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


def test_q0_is_a_set_membership_state_observer_equal_to_the_history_lp():
    """q = 0, process and measurement noise: exact mode equals the whole-history LP of
    the state (1e-6 of the width), windows 3 and 10 contain it, all contain the truth;
    the windows' fast path gives the state bounds as extra rows of its LPs."""
    rng = np.random.default_rng(3)
    rw, rv = 0.02, 0.05
    G0 = np.zeros((3, 0))
    X, Y = _record(PHI3, G0, XI3, 25, rw, rv, rng)
    sys = so.LinearSystem(PHI3, G0, XI3)
    res = {}
    for w in (3, 10, None):
        obs = so.SMFDO(sys, window=w, process_noise=rw, measurement_noise=rv,
                       state_bounds=True)
        res[w] = obs.run(Y)
        r = res[w]
        assert obs.stats["fast"] > 0 or w is None  # (with noise: the set recursion)
        assert r.lo.shape == (25, 0) and r.state_lo.shape == (25, 3)
        assert np.all((X >= r.state_lo) & (X <= r.state_hi))
        assert set(r.status) == {"ok"}
    for k in (2, 8, 16, 24):
        lo, hi = state_history_lp(PHI3, G0, XI3, Y, k, rw, rv)
        width = (hi - lo).max()
        ex = res[None]
        assert np.abs(ex.state_lo[k] - lo).max() <= 1e-6 * width
        assert np.abs(ex.state_hi[k] - hi).max() <= 1e-6 * width
        for w in (3, 10):
            assert (res[w].state_lo[k] <= lo + 1e-9).all()
            assert (res[w].state_hi[k] >= hi - 1e-9).all()
    df = res[10].to_pandas()
    assert list(df.columns) == ["error_bound", "status", "x0_lo", "x0_hi", "x1_lo", "x1_hi",
                                "x2_lo", "x2_hi"]


def test_state_bounds_with_a_disturbance_equal_the_history_lp():
    """q = 1 with measurement noise: the state bounds of exact mode equal the
    whole-history LP (disturbance, increments and state as its variables), the
    windowed ones (fast path: extra rows of its LPs) contain it, and the
    disturbance bands are unchanged (to 1e-10) by asking for state bounds."""
    rng = np.random.default_rng(5)
    G1 = np.array([[0.0], [1.0], [0.5]])
    rv, r_inc = 0.02, 0.1
    X, Y = _record(PHI3, G1, XI3, 20, 0.0, rv, rng, r_inc)
    sys = so.LinearSystem(PHI3, G1, XI3)
    kw = dict(increment_set=r_inc, measurement_noise=rv)
    for w in (10, None):
        plain = so.SMFDO(sys, window=w, **kw).run(Y)
        obs = so.SMFDO(sys, window=w, state_bounds=True, **kw)
        r = obs.run(Y)
        # (the same sets; the LPs' bases differ, so the certified digits may too)
        np.testing.assert_allclose(r.lo, plain.lo, rtol=0, atol=1e-10)
        np.testing.assert_allclose(r.hi, plain.hi, rtol=0, atol=1e-10)
        assert np.all((X >= r.state_lo) & (X <= r.state_hi))
        assert obs.stats["fast"] > 0 or w is None
        for k in (5, 12, 19):
            lo, hi = state_history_lp(PHI3, G1, XI3, Y, k, 0.0, rv, r_inc)
            width = (hi - lo).max()
            if w is None:
                assert np.abs(r.state_lo[k] - lo).max() <= 1e-6 * width
                assert np.abs(r.state_hi[k] - hi).max() <= 1e-6 * width
            else:
                assert (r.state_lo[k] <= lo + 1e-9).all() and (r.state_hi[k] >= hi - 1e-9).all()


def test_a_state_of_the_unobservable_part_is_unbounded_without_a_bounded_initial_set():
    """x_1 never reaches the output: with X0 = R^n nothing bounds it."""
    sys = so.LinearSystem(np.diag([0.5, 0.9]), np.zeros((2, 0)), [[1.0, 0.0]])
    r = so.SMFDO(sys, window=3, measurement_noise=0.1, state_bounds=True).run(
        np.zeros((6, 1)))
    assert np.isinf(r.state_lo[:, 1]).all() and np.isinf(r.state_hi[:, 1]).all()
    # x_0 (k) = 0.5^k x_0 (0) with |x_0(j)| <= 0.1 for every j: |x_0(k)| <= 0.1 0.5^k
    ref = 0.1 * 0.5 ** np.arange(6)
    assert np.all(r.state_hi[:, 0] >= ref) and np.all(r.state_hi[:, 0] <= ref + 1e-8)
    assert np.all(r.state_lo[:, 0] <= -ref) and np.all(r.state_lo[:, 0] >= -ref - 1e-8)


def test_a_stable_unobservable_state_is_bounded_by_the_initial_set_and_the_noise():
    """An unobservable state: x_1+ = 0.9 x_1 + w_1, |x_1(0)| <= 1, |w| <= 0.05, unmeasured:
    |x_1(k)| <= 0.9^k + 0.05 (1 - 0.9^k) / 0.1 (closed form), in every mode."""
    sys = so.LinearSystem(np.diag([0.5, 0.9]), np.zeros((2, 0)), [[1.0, 0.0]])
    k = np.arange(40)
    ref = 0.9 ** k + 0.5 * (1 - 0.9 ** k)
    for w in (3, None):
        r = so.SMFDO(sys, window=w, measurement_noise=0.1, process_noise=0.05,
                     state_bounds=True, initial_state_set=so.Box([-1, -1], [1, 1])).run(
            np.zeros((40, 1)))
        assert np.all(r.state_hi[:, 1] >= ref) and np.all(r.state_hi[:, 1] <= ref + 1e-8)
        assert np.all(r.state_lo[:, 1] <= -ref) and np.all(r.state_lo[:, 1] >= -ref - 1e-8)


def test_an_unobservable_state_driven_by_the_observable_one_holds_the_history_lp():
    """x_1+ = 0.3 x_0 + 0.9 x_1 + w_1 with only x_0 measured: the tracked bound of x_1
    (observable part's hull through A_21, a zonotope of x_1) contains the
    whole-history LP of the state and the truth, within 2 % of its width."""
    Phi = np.array([[0.5, 0.0], [0.3, 0.9]])
    C = np.array([[1.0, 0.0]])
    rng = np.random.default_rng(0)
    rw, rv = 0.05, 0.1
    x, X, Y = rng.uniform(-1, 1, 2), [], []
    for _ in range(30):
        X.append(x.copy())
        Y.append(C @ x + rng.uniform(-rv, rv, 1))
        x = Phi @ x + rng.uniform(-rw, rw, 2)
    X, Y = np.array(X), np.array(Y)
    sys = so.LinearSystem(Phi, np.zeros((2, 0)), C)
    box = (-np.ones(2), np.ones(2))
    for w in (3, None):
        r = so.SMFDO(sys, window=w, process_noise=rw, measurement_noise=rv, state_bounds=True,
                     initial_state_set=so.Box(*box)).run(Y)
        assert np.all((X >= r.state_lo) & (X <= r.state_hi))
        for k in (0, 5, 29):
            lo, hi = history_lp_highs(Phi, np.zeros((2, 0)), C, Y, k, 0.0, states=True,
                                      x_box=box, noise_w=(np.eye(2), np.full(2, rw)),
                                      noise_v=(np.eye(1), np.full(1, rv)))
            width = hi - lo
            assert (r.state_lo[k] <= lo + 1e-9).all() and (r.state_hi[k] >= hi - 1e-9).all()
            assert ((r.state_hi[k] - r.state_lo[k]) <= 1.02 * width).all()


def test_disturbance_observers_refuse_a_system_without_disturbances():
    sys = so.LinearSystem(PHI3, np.zeros((3, 0)), XI3)
    with pytest.raises(so.DesignError, match="q = 0"):
        so.observers.PIO(sys)
    with pytest.raises(TypeError, match="state_bounds"):
        so.SMFDO(sys, window=3, measurement_noise=0.1, state_bounds="yes")


def test_a_model_without_disturbances_from_control_matrices_and_statespace():
    """``from_matrices(..., disturbance_inputs=[])`` and a ``control.StateSpace`` with
    ``disturbance_inputs=[]``: q = 0 with the control input kept; the SMFDO's state
    bounds with inputs contain the truth and equal the whole-history LP in exact
    mode (inputs subtracted from the record by the oracle's own simulation)."""
    control = pytest.importorskip("control")
    A = np.array([[0.9, 0.2], [-0.1, 0.7]])
    B = np.array([[0.0], [1.0]])
    C = np.array([[1.0, 0.0]])
    s = so.LinearSystem.from_matrices(A=A, B=B, C=C, disturbance_inputs=[])
    assert (s.q, s.p) == (0, 1)
    ss = control.ss(A, B, C, 0, dt=0.1)
    rng = np.random.default_rng(9)
    N, rv = 15, 0.05
    U = rng.normal(size=(N, 1))
    x, X, Y, Yfree, xf = rng.normal(size=2), [], [], [], np.zeros(2)
    for k in range(N):
        X.append(x.copy())
        v = rng.uniform(-rv, rv, 1)
        Y.append(C @ x + v)
        Yfree.append(C @ (x - xf) + v)  # the record of the input-free system
        x = A @ x + B @ U[k]
        xf = A @ xf + B @ U[k]  # the input's own response
    X, Y, Yfree = np.array(X), np.array(Y), np.array(Yfree)
    r = so.SMFDO(ss, window=None, disturbance_inputs=[], measurement_noise=rv,
                 state_bounds=True).run(Y, U)
    assert np.all((X >= r.state_lo) & (X <= r.state_hi))
    # the input's response is known: the bounds of x are those of (x - xf) shifted
    xf = np.zeros(2)
    XF = []
    for k in range(N):
        XF.append(xf.copy())
        xf = A @ xf + B @ U[k]
    for k in (4, 14):
        lo, hi = state_history_lp(A, np.zeros((2, 0)), C, Yfree, k, 0.0, rv)
        width = (hi - lo).max()
        assert np.abs(r.state_lo[k] - (lo + XF[k])).max() <= 1e-6 * width
        assert np.abs(r.state_hi[k] - (hi + XF[k])).max() <= 1e-6 * width


def test_the_state_band_is_plotted_from_the_certified_bounds():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rng = np.random.default_rng(2)
    X, Y = _record(PHI3, np.zeros((3, 0)), XI3, 12, 0.02, 0.05, rng)
    sys = so.LinearSystem(PHI3, np.zeros((3, 0)), XI3)
    r = so.SMFDO(sys, window=3, process_noise=0.02, measurement_noise=0.05,
                 state_bounds=True).run(Y)
    fig, ax = plt.subplots()
    r.plot(ax=ax, truth=X, component=1, states=True)
    band = ax.collections[0].get_paths()[0].vertices
    fin = np.isfinite(r.state_lo[:, 1]) & np.isfinite(r.state_hi[:, 1])  # (k = 0: unbounded)
    assert not fin[0] and fin[1:].all()
    assert np.isclose(band[:, 1].min(), r.state_lo[fin, 1].min())
    assert np.isclose(band[:, 1].max(), r.state_hi[fin, 1].max())
    assert ax.get_ylabel().startswith("x1")
    plt.close(fig)
    plain = so.SMFDO(so.LinearSystem(PHI3, np.ones((3, 1)), XI3), window=3,
                     measurement_noise=0.05).run(Y)
    with pytest.raises(so.InvalidValueError, match="state_bounds=True"):
        plain.plot(states=True)


def test_exact_mode_state_bounds_on_the_h_representation_path():
    """The paper example in other state coordinates (``x' = T x``, so that the state is
    no coordinate of the SMFDO's internal set), noise-free: exact mode runs 22 of 25
    steps on the H-representation path with the state map as extra rows of its LPs,
    and equals the whole-history LP of the state within 1e-6 of the width."""
    from tests.setmembership.test_smfdo import simulate

    s0 = so.examples.chang2006()
    T = np.array([[1.0, 0.5, 0.0], [0.0, 1.0, -0.3], [0.2, 0.0, 1.0]])
    Ti = np.linalg.inv(T)
    s = so.LinearSystem(T @ s0.Phi @ Ti, T @ s0.G, s0.Xi @ Ti)
    x0 = T @ np.array([0.2, -0.5, 0.3])
    Y, D = simulate(s, 25, np.random.default_rng(7), x0=x0, d0=[1.0, -2.0])
    X = s.simulate(D, x0=x0)[1]
    obs = so.SMFDO(s, window=None, state_bounds=True)
    r = obs.run(Y)
    assert obs.stats["fast"] >= 20
    assert np.all((X >= r.state_lo) & (X <= r.state_hi))
    for k in (5, 12, 24):
        lo, hi = state_history_lp(s.Phi, s.G, s.Xi, Y, k, 0.0, 0.0, 1.0)
        width = (hi - lo).max()
        assert np.abs(r.state_lo[k] - lo).max() <= 1e-6 * width
        assert np.abs(r.state_hi[k] - hi).max() <= 1e-6 * width
