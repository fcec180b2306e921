"""Point observers: the papers' claims, one interface, and the comparison with the SMFDO."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import place_poles

import setobs as so
from setobs.observers import (
    MBESO,
    PIO,
    DesignError,
    HigherOrderObserver,
    ModularObserver,
    VariantMBESO,
    design_higher_order,
    design_pio,
    mbeso_impulse_response,
)

FW_POLES = [0.1, 0.2, 0.3 + 0.5j, 0.3 - 0.5j, 0.4]


def simulate(sys, F, x0=None, U=None):
    if U is None and sys.p:
        U = np.zeros((F.shape[0], sys.p))
    return sys.simulate(F, U, x0=x0)[0]


def h_closed_form(k, r, w):
    """Eq. (54), written out independently of the library's implementation."""
    from math import factorial

    if 1 <= k <= r + 1:
        return 1.0
    return sum(np.prod([k + j for j in range(-i + 1, 0)]) / factorial(i - 1)
               * (1 - w) ** (i - 1) * w ** (k - i) for i in range(1, r + 2))


def predicted_error(F, f_hat0, degrees, omegas, lag_shift=None):
    """sum_j h(j) Delta f(k - j), with Delta f(-1) = f(0) - f_hat(0) (initial error)."""
    N, p = F.shape
    dF = np.vstack([F[:1] - f_hat0, np.diff(F, axis=0)])  # dF[m] = Delta f(m - 1)
    out = np.zeros((N, p))
    for i in range(p):
        h = [h_closed_form(j, degrees[i], omegas[i]) for j in range(N + 1)]
        for k in range(N):
            out[k, i] = sum(h[j] * dF[k - j + 1, i] for j in range(1, k + 2))
    return out


# ------------------------------------------------------------------ MB-ESO (Chen-Gao-Lin)
def test_theorem2_example4_deadbeat_mbeso():
    rng = np.random.default_rng(0)
    sys = so.examples.chen_gao_lin_example4()
    F = rng.normal(size=(60, 3))
    res = MBESO(sys, omega=0.0).run(simulate(sys, F))
    for i, r in enumerate((2, 4, 3)):
        k = np.arange(r + 2, 60)
        np.testing.assert_allclose(res.estimate[k, i], F[k - r - 1, i], atol=1e-8)


def test_theorem3_example1_variant_mbeso_delay_5():
    rng = np.random.default_rng(1)
    sys = so.examples.chen_gao_lin_example1()
    F = rng.normal(loc=[1, 2, 3], scale=np.sqrt([0.1, 0.2, 0.3]), size=(80, 3))
    obs = VariantMBESO(sys, omega=0.0)
    res = obs.run(simulate(sys, F))
    assert obs.delay == 5 and res.delay == 5
    k = np.arange(8, 80)
    np.testing.assert_allclose(res.estimate[k], F[k - 5], atol=1e-8)
    assert np.isnan(res.estimate[0]).any()  # delay line not yet filled


@pytest.mark.parametrize("omega", [0.2, 0.4, 0.6])
def test_theorem4_error_is_the_convolution_of_eq54(omega):
    rng = np.random.default_rng(2)
    sys = so.examples.chen_gao_lin_example4()
    F = np.cumsum(rng.normal(size=(50, 3)), axis=0)
    res = MBESO(sys, omega=omega).run(simulate(sys, F))
    pred = predicted_error(F, np.zeros(3), (2, 4, 3), [omega] * 3)
    np.testing.assert_allclose(F - res.estimate, pred, atol=1e-9)


def test_theorem4_monotonicity_from_the_observer_itself():
    """Impulse responses simulated from the designed observers: decreasing in k (k > r+1)
    and increasing in omega, and equal to eq. (54)."""
    sys = so.examples.chen_gao_lin_example4()
    a = sys.augmented()
    resp = {}
    for w in (0.2, 0.4, 0.6):
        obs = MBESO(sys, omega=w)
        Fcl = a.A - obs.L @ a.C
        e = a.E[:, 1].copy()  # Delta f_2 (r = 4)
        h = []
        for _ in range(30):
            h.append(e[-3 + 1])
            e = Fcl @ e
        resp[w] = np.array(h)
        np.testing.assert_allclose(resp[w], [mbeso_impulse_response(k, 4, w)
                                             for k in range(1, 31)], atol=1e-9)
        assert np.all(np.diff(resp[w][5:]) < 0)
    assert np.all(resp[0.2][5:] < resp[0.4][5:]) and np.all(resp[0.4][5:] < resp[0.6][5:])


def test_theorem5_variant_error_eq70():
    rng = np.random.default_rng(3)
    sys = so.examples.chen_gao_lin_example1()
    V0 = so.analysis.relative_degrees(sys).V0
    F = np.cumsum(rng.normal(size=(50, 3)), axis=0)
    w = 0.3
    res = VariantMBESO(sys, omega=w).run(simulate(sys, F))
    # f_new = V0 f; channel i delayed by r_max - r_i; f_hat = V0^-1 f_new_hat (eqs. 21-22).
    Fn = F @ V0.T
    pred_new = predicted_error(Fn, np.zeros(3), (2, 4, 3), [w] * 3)
    fnew_hat = Fn - pred_new
    delayed = np.full_like(fnew_hat, np.nan)
    for i, r in enumerate((2, 4, 3)):
        s = 4 - r
        delayed[s:, i] = fnew_hat[: 50 - s, i] if s else fnew_hat[:, i]
    pred = delayed @ np.linalg.inv(V0).T
    k = np.arange(4, 50)
    np.testing.assert_allclose(res.estimate[k], pred[k], atol=1e-8)


def test_mbeso_design_errors_name_the_condition():
    with pytest.raises(DesignError, match="Assumption 1") as info:
        MBESO(so.examples.chang2006())
    assert info.value.condition == "Assumption 1"
    with pytest.raises(DesignError, match="diagonal V0") as info:
        MBESO(so.examples.chen_gao_lin_example1())
    assert info.value.condition == "V0 diagonal"
    with pytest.raises(DesignError, match=r"omega must lie in \[0, 1\)"):
        MBESO(so.examples.chen_gao_lin_example4(), omega=1.2)


def test_mbeso_on_the_sea_models():
    """SEA (Example 2): MB-ESO with deadbeat eigenvalues recovers step disturbances."""
    for ts in ("20ms", "1ms"):
        sys = so.examples.chen_gao_lin_example2(ts)
        F = np.zeros((80, 2))
        F[10:, 0], F[15:, 1] = 1.5, 2.0
        U = np.ones((80, 1))
        res = MBESO(sys, omega=0.0).run(simulate(sys, F, U=U), U)
        np.testing.assert_allclose(res.estimate[40:], F[40:], atol=1e-6)


# ------------------------------------------------------------------ Fu-Wang / Chang
def test_designed_gains_place_exactly_the_stated_poles():
    sys = so.examples.chang2006()
    g = design_pio(sys, FW_POLES)
    poles = so.analysis.pio_error_poles(sys, g["P"], g["L"]).poles
    np.testing.assert_allclose(np.sort_complex(poles), np.sort_complex(FW_POLES), atol=1e-8)
    ho = design_higher_order(sys, [*FW_POLES, 0.5, 0.45])
    ep = so.analysis.higher_order_error_poles(sys.Phi, sys.Xi, ho["P0"], ho["L0"], ho["L1"],
                                              E=sys.G)
    np.testing.assert_allclose(np.sort_complex(ep.poles),
                               np.sort_complex([*FW_POLES, 0.5, 0.45]), atol=1e-8)


def test_printed_baseline_is_unstable_and_diverges():
    sys = so.examples.chang2006()
    base = PIO.chang2006_baseline(sys)
    assert not base.error_poles.stable
    F = np.tile([0.5, 2.0], (60, 1))
    res = base.run(simulate(sys, F, x0=[0, 1, 0]))
    assert np.abs(res.estimate[-1] - F[-1]).max() > 1e3  # the pole at -1.37 blows up
    good = PIO(sys).run(simulate(sys, F, x0=[0, 1, 0]))
    np.testing.assert_allclose(good.estimate[-1], F[-1], atol=1e-6)


def test_higher_order_tracks_ramps_pio_does_not():
    """A ramp disturbance: the double-integrator model of the HO observer tracks it
    with zero steady-state error; the PIO lags with a constant error."""
    sys = so.examples.chang2006()
    F = np.outer(np.arange(200) * 0.01, [1.0, -0.5])
    Y = simulate(sys, F)
    ho = HigherOrderObserver(sys).run(Y)
    pio = PIO(sys).run(Y)
    assert np.abs(ho.estimate[-1] - F[-1]).max() < 1e-6
    assert np.abs(pio.estimate[-1] - F[-1]).max() > 1e-3


# ------------------------------------------------------------------ modular observer
def test_modular_equals_simultaneous_design_with_same_eigenvalues():
    sys = so.examples.chen_gao_lin_example5((0.3, 0.7))  # single output: gains are unique
    mod = ModularObserver(sys, w_poles=[0.6])
    eig = np.concatenate([np.linalg.eigvals(sys.Phi - mod.L0 @ sys.Xi), [0.6]])
    a = sys.augmented()
    K = place_poles(a.A.T, a.C.T, eig).gain_matrix.T
    # The modular observer is the augmented Luenberger observer with gain [L0 + V Lw; Lw].
    np.testing.assert_allclose(K, np.vstack([mod.L0 + mod.V @ mod.Lw, mod.Lw]), atol=1e-7)
    rng = np.random.default_rng(4)
    F = np.cumsum(rng.normal(size=(60, 1)), axis=0) * 0.1
    Y = simulate(sys, F)
    simultaneous = PIO(sys, K[:4], K[4:]).run(Y)
    np.testing.assert_allclose(mod.run(Y).estimate, simultaneous.estimate, atol=1e-8)


def test_modular_error_is_block_triangular():
    sys = so.examples.chang2006()
    mod = ModularObserver(sys)
    V = mod.V
    # Sylvester (48) with S = I, Q = 0: V - (Phi - L0 Xi) V = G.
    np.testing.assert_allclose(V - (sys.Phi - mod.L0 @ sys.Xi) @ V, sys.G, atol=1e-12)
    F = np.tile([1.0, -1.0], (400, 1))
    res = mod.run(simulate(sys, F, x0=[0.5, 0.0, -0.5]))
    np.testing.assert_allclose(res.estimate[-1], F[-1], atol=1e-6)
    assert res.x_hat.shape == (400, 3)


# ------------------------------------------------------------------ one interface + compare
def test_every_observer_runs_through_one_interface():
    cases = [
        (MBESO, so.examples.chen_gao_lin_example4()),
        (VariantMBESO, so.examples.chen_gao_lin_example1()),
        (PIO, so.examples.chang2006()),
        (HigherOrderObserver, so.examples.chang2006()),
        (ModularObserver, so.examples.chang2006()),
        (so.observers.DelayedUIO, so.examples.chen_gao_lin_example4()),
        (lambda s: so.observers.DescriptorObserver(s, np.ones((s.l, 1))),
         so.LinearSystem(so.examples.chang2006().Phi, so.examples.chang2006().G[:, :1],
                         np.vstack([so.examples.chang2006().Xi, [[0.0, 1.0, 0.0]]]))),
    ]
    # Example 1 has p = 3 outputs for k = 3 disturbances and l = 1 noise channel:
    # Assumption 2 (p >= k + l) fails and the descriptor observer says so.
    with pytest.raises(DesignError, match="Assumptions 2-3"):
        so.observers.DescriptorObserver(so.examples.chen_gao_lin_example1(), np.ones((3, 1)))
    for cls, sys in cases:
        obs = cls(sys)
        # oracle: a constant disturbance d*, simulated here (x+ = Phi x + G d*, y = Xi x);
        # every observer is designed for it, so its estimate must end at d*
        d_star = 0.5 + 0.25 * np.arange(sys.q)
        x, Y = np.zeros(sys.n), []
        for _ in range(300):
            Y.append(sys.Xi @ x)
            x = sys.Phi @ x + sys.G @ d_star
        Y = np.array(Y)
        res = obs.run(Y)
        assert res.estimate.shape == (300, sys.q)
        np.testing.assert_allclose(res.estimate[-1], d_star, atol=1e-6)
        assert isinstance(res.gains, dict) and res.gains
        obs.reset()  # step by step: the same estimates as run
        steps = np.array([obs.step(y) for y in Y])
        np.testing.assert_allclose(steps, res.estimate, rtol=0, atol=1e-12)
        with pytest.raises(so.DimensionError, match="y must have length"):
            obs.step(np.zeros(sys.l + 1))


def test_compare_every_observer_is_at_least_the_optimal_radius():
    rng = np.random.default_rng(6)
    sys = so.examples.chang2006()
    N = 60
    F = np.cumsum(rng.uniform(-1, 1, size=(N, 2)), axis=0)
    Y = simulate(sys, F, x0=[0.2, -0.1, 0.3])
    X0 = so.ConstrainedZonotope.from_box(-np.ones(3), np.ones(3))
    ref = so.SMFDO(sys, window=None, initial_state_set=X0).run(Y)
    est = {"PIO": PIO(sys).run(Y).estimate, "HO": HigherOrderObserver(sys).run(Y).estimate,
           "modular": ModularObserver(sys).run(Y).estimate, "SMFDO": ref.estimate}
    table = so.compare.compare(est, ref)
    fin = np.isfinite(ref.error_bound)
    for name in ("PIO", "HO", "modular"):
        assert np.all(table.worst_case_error[name][fin] >= ref.error_bound[fin] - 1e-9)
    # Independent scores: the consistent box from a whole-history LP (scipy, no setobs);
    # worst-case infinity-norm error of an estimate e over [lo, hi] is
    # max_i max(e_i - lo_i, hi_i - e_i), and the optimum is the largest half-width.
    from tests.setmembership.test_smfdo import history_lp_bounds

    for k in (10, 35, 59):
        lo, hi = history_lp_bounds(sys, Y, None, -np.ones(3), np.ones(3), 1.0, k)
        optimum = 0.5 * (hi - lo).max()
        assert table.optimal[k] == pytest.approx(optimum, abs=1e-6)
        for name, e in est.items():
            worst = np.maximum(e[k] - lo, hi - e[k]).max()
            assert table.worst_case_error[name][k] == pytest.approx(worst, abs=1e-6)
        # the centre is optimal
        assert table.worst_case_error["SMFDO"][k] == pytest.approx(optimum, abs=1e-6)
        assert table.worst_case_error["PIO"][k] > optimum
    summ = table.summary(start=5)
    assert summ.loc["PIO", "ratio"] > 1.0
    assert "| PIO |" in table.to_markdown(start=5)
    assert len(table.rows) == 4 * N


# ------------------------------------------------------------------ delayed UIO
def test_delayed_uio_equals_variant_mbeso_on_example1():
    """Chen-Gao-Lin Theorems 1 and 3: tau = r_max + 1 = 5 and identical estimates."""
    from setobs.observers import DelayedUIO

    rng = np.random.default_rng(1)
    sys = so.examples.chen_gao_lin_example1()
    F = rng.normal(loc=[1, 2, 3], scale=np.sqrt([0.1, 0.2, 0.3]), size=(80, 3))
    Y = simulate(sys, F)
    uio = DelayedUIO(sys)
    assert uio.tau == 5 and uio.delay == 5
    res = uio.run(Y)
    assert np.isnan(res.estimate[:5]).all()
    k = np.arange(20, 80)
    np.testing.assert_allclose(res.estimate[k], F[k - 5], atol=1e-8)
    var = VariantMBESO(sys).run(Y)
    np.testing.assert_allclose(res.estimate[k], var.estimate[k], atol=1e-8)
    # With the paper's eigenvalues at 0.67 the error decays geometrically.
    slow = DelayedUIO(sys, poles=0.67).run(Y)
    assert np.abs(slow.estimate[70:] - F[65:75]).max() < 1e-6


def test_delayed_uio_refused_for_chang():
    from setobs.observers import DelayedUIO

    with pytest.raises(DesignError, match=r"1\.26095") as info:
        DelayedUIO(so.examples.chang2006())
    assert info.value.condition == "condition (b)"


def test_compare_euclidean_scores():
    rng = np.random.default_rng(8)
    sys = so.examples.chang2006()
    F = np.cumsum(rng.uniform(-1, 1, size=(25, 2)), axis=0)
    Y = simulate(sys, F, x0=[0.2, -0.1, 0.3])
    X0 = so.ConstrainedZonotope.from_box(-np.ones(3), np.ones(3))
    ref = so.SMFDO(sys, window=None, initial_state_set=X0, keep_sets=True).run(Y)
    est = {"PIO": PIO(sys).run(Y).estimate, "IH centre": ref.estimate}
    t = so.compare.compare(est, ref, euclidean=True)
    fin = np.isfinite(t.optimal_2)
    assert fin.sum() > 15
    for name in est:  # nothing beats the Chebyshev radius
        assert np.all(t.worst_case_error_2[name][fin] >= t.optimal_2[fin] - 1e-6)
    # The interval-hull centre's Euclidean error is at most sqrt(q) times the optimum.
    assert np.all(t.worst_case_error_2["IH centre"][fin] <= np.sqrt(2) * t.optimal_2[fin] + 1e-6)
    with pytest.raises(ValueError, match="keep_sets=True"):
        so.compare.compare(est, so.SMFDO(sys, window=None, initial_state_set=X0).run(Y),
                           euclidean=True)


def test_vertices_of_many_generator_2d_sets_match_cdd():
    """The verified LP vertices agree with cdd's enumeration of the factor polytope + Qhull."""
    from scipy.spatial import ConvexHull

    from tests.conftest import cdd_vertices

    rng = np.random.default_rng(12)
    for _ in range(3):
        A = rng.normal(size=(2, 10))
        Z = so.ConstrainedZonotope(rng.normal(size=(2, 10)), [0, 0], A,
                                   A @ rng.uniform(-0.5, 0.5, 10))
        V = Z.vertices()
        P = cdd_vertices(Z)
        ref = P[ConvexHull(P).vertices]
        assert {tuple(np.round(v, 6)) for v in V} == {tuple(np.round(v, 6)) for v in ref}


# ------------------------------------------------------------------ descriptor observer
def _noisy_system(rng):
    n = 3
    sys = so.LinearSystem(rng.normal(size=(n, n)) * 0.4, rng.normal(size=(n, 1)),
                          rng.normal(size=(3, n)))
    return sys, rng.normal(size=(3, 1))


def test_descriptor_observer_is_exact_under_arbitrary_sensor_noise():
    """The noise is a state of the descriptor model: with a constant disturbance the
    estimates become exact whatever the noise (error dynamics (17) with p = 0)."""
    from setobs.observers import DescriptorObserver

    rng = np.random.default_rng(0)
    sys, Fn = _noisy_system(rng)
    obs = DescriptorObserver(sys, Fn)
    x, d = rng.normal(size=3), np.array([1.5])
    Nn = rng.normal(size=(80, 1)) * 5.0
    Y0, X = sys.simulate(np.tile(d, (80, 1)), x0=x)
    Y = Y0 + Nn @ Fn.T
    res = obs.run(Y)
    np.testing.assert_allclose(res.estimate[40:], 1.5, atol=1e-9)
    np.testing.assert_allclose(res.x_hat[40:], np.array(X)[40:], atol=1e-9)
    np.testing.assert_allclose(obs.noise_estimate(), Nn[-1], atol=1e-9)
    # A PIO on the same data, blind to the noise structure, is far off.
    assert np.abs(PIO(sys).run(np.array(Y)).estimate[40:] - 1.5).max() > 0.1


def test_descriptor_observer_dare_gain_eqs_18_19():
    from setobs.observers import DescriptorObserver

    rng = np.random.default_rng(1)
    sys, Fn = _noisy_system(rng)
    obs = DescriptorObserver(sys, Fn)
    A, C, P, L = obs.A_w, obs.C_w, obs.P_dare, obs.L
    Rw = np.eye(3)
    # eq. (19): A P A^T - A P C^T (R + C P C^T)^-1 C P A^T + Q = P
    lhs = A @ P @ A.T - A @ P @ C.T @ np.linalg.solve(Rw + C @ P @ C.T, C @ P @ A.T) + np.eye(5)
    np.testing.assert_allclose(lhs, P, atol=1e-8)
    np.testing.assert_allclose(L, A @ P @ C.T @ np.linalg.inv(Rw + C @ P @ C.T), atol=1e-12)
    assert np.abs(np.linalg.eigvals(A - L @ C)).max() < 1.0


def test_descriptor_observer_design_errors():
    from setobs.observers import DescriptorObserver

    rng = np.random.default_rng(2)
    sys, _ = _noisy_system(rng)
    with pytest.raises(DesignError, match="full column rank"):
        DescriptorObserver(sys, np.ones((3, 2)))
    # Two noise channels and one disturbance on three outputs: p >= k + l holds (3 = 1 + 2),
    # but with only two outputs it cannot: Assumption 2 fails.
    two = so.LinearSystem(sys.Phi, sys.G, sys.Xi[:2])
    with pytest.raises(DesignError, match="Assumptions 2-3"):
        DescriptorObserver(two, rng.normal(size=(2, 2)))
