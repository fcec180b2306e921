"""Point observers for real use: defaults that work on every approved system, the LQE
gain design, and U required when the system has inputs."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import place_poles

import setobs as so
from setobs.exceptions import ArgumentError
from setobs.observers import (
    MBESO,
    PIO,
    DelayedUIO,
    DesignError,
    HigherOrderObserver,
    ModularObserver,
    VariantMBESO,
)
from setobs.observers._gains import lqe_gain, place_gain

CLASSES = {"PIO": PIO, "higher-order observer": HigherOrderObserver,
           "modular observer": ModularObserver, "delayed UIO": DelayedUIO,
           "MB-ESO": MBESO, "variant MB-ESO": VariantMBESO}


def _random_system(rng):
    n, q, l = int(rng.integers(1, 5)), int(rng.integers(1, 3)), int(rng.integers(1, 4))
    Phi = rng.normal(size=(n, n))
    Phi *= rng.uniform(0.3, 1.1) / max(abs(np.linalg.eigvals(Phi)).max(), 1e-9)
    if rng.random() < 0.3:  # integer entries: exact structure, repeated/zero eigenvalues
        Phi = np.round(Phi, 0)
    G, Xi = rng.normal(size=(n, q)), rng.normal(size=(l, n))
    if rng.random() < 0.3:  # an unmeasured state
        Xi[:, -1] = 0.0
    return so.LinearSystem(Phi, G, Xi)


def _square_system(rng, diagonal):
    """n = q = l with Xi, G invertible: no invariant zeros (the MB-ESOs' Assumption
    1); ``Xi G`` diagonal when ``diagonal`` (the MB-ESO's V0)."""
    n = int(rng.integers(1, 4))
    Phi = rng.normal(size=(n, n))
    Phi *= rng.uniform(0.3, 0.95) / np.abs(np.linalg.eigvals(Phi)).max()
    Xi = rng.normal(size=(n, n)) + 2 * np.eye(n)
    V0 = np.diag(rng.uniform(0.5, 2.0, n)) if diagonal else rng.normal(size=(n, n)) + 2 * np.eye(n)
    return so.LinearSystem(Phi, np.linalg.solve(Xi, V0), Xi)


def _simulate_constant(sys, d, x0, N):
    """``x+ = Phi x + G d`` with a constant ``d``, ``y = Xi x``."""
    U = np.zeros((N, sys.p)) if sys.p else None
    return sys.simulate(np.tile(np.asarray(d, float), (N, 1)), U, x0=x0)[0]


def test_every_approved_design_constructs_and_converges_on_random_systems():
    """150 random systems (1-4 states, 1-2 disturbances, 1-3 outputs, some with
    integer or unmeasured structure) and 10 square ones for the MB-ESOs: every
    observer ``diagnose`` approves constructs with its default poles, its
    recursion is stable, and on a record with a constant disturbance its
    estimate converges to it (own simulator)."""
    rng = np.random.default_rng(0)
    tried = {}
    systems = [_random_system(rng) for _ in range(150)]
    systems += [_square_system(rng, diagonal=i % 2 == 0) for i in range(10)]
    for sys in systems:
        for design in so.analysis.diagnose(sys).existing:
            if design == "SMFDO":
                continue
            obs = CLASSES[design](sys)
            rho = float(np.abs(np.linalg.eigvals(obs.transition)).max())
            assert rho < 1.0, (design, sys.Phi, rho)
            tried[design] = tried.get(design, 0) + 1
            if rho > 0.97 or np.abs(np.linalg.eigvals(sys.Phi)).max() > 1.0:
                # too slow to converge in a short record / the plant's state grows
                # until rounding dominates the output: the spectral radius decides
                continue
            N = int(np.ceil(np.log(1e-9) / np.log(max(rho, 1e-3)))) + 40
            d = rng.normal(size=sys.q)
            Y = _simulate_constant(sys, d, rng.normal(size=sys.n), N)
            est = obs.run(Y).estimate
            np.testing.assert_allclose(est[-1], d, atol=1e-5 * (1 + np.abs(d).max()),
                                       err_msg=design)
    # all of the designs were exercised
    assert set(tried) == set(CLASSES) and min(tried.values()) >= 3, tried


@pytest.mark.parametrize("design", [PIO, HigherOrderObserver])
def test_default_poles_for_small_augmented_states(design):
    """n + q = 2 and 3 (the old default list cut a conjugate pair in half)."""
    for Phi, G, Xi in (([[0.5]], [[1.0]], [[1.0]]),
                       ([[0.9, 0.1], [0.0, 0.8]], [[0.0], [1.0]], [[1.0, 0.0]])):
        obs = design(so.LinearSystem(Phi, G, Xi))
        assert np.abs(np.linalg.eigvals(obs.transition)).max() <= 0.5 + 1e-9


def test_delayed_uio_on_the_single_output_servo_motor():
    """diagnose approves the delayed UIO for the servo motor (zero at -0.9998,
    inside the unit circle); its dead-beat default used to be refused by
    scipy (a pole repeated more often than the one output)."""
    sys = so.examples.servo_motor()
    assert "delayed UIO" in so.analysis.diagnose(sys).existing
    obs = DelayedUIO(sys)
    zeros = so.analysis.invariant_zeros(sys).zeros
    eig = np.linalg.eigvals(obs.J)
    # the invariant zero is an error pole that no gain moves; the rest are dead-beat
    assert np.min(np.abs(eig - zeros[0])) < 1e-6
    assert np.sort(np.abs(eig))[:-1].max() < 1e-4


def test_place_gain_against_scipy_and_ackermann():
    """Distinct poles: the same spectrum as scipy's placement; a triple pole with
    one output (Ackermann): the characteristic polynomial is exactly (z - 0.3)^3,
    checked on the coefficients of the closed loop."""
    A = np.array([[1.0, 1.0, 0.0], [0.0, 1.0, 1.0], [0.0, 0.0, 1.0]])
    C = np.array([[1.0, 0.0, 0.0]])
    L = place_gain(A, C, [0.1, 0.2, 0.3])
    L_ref = place_poles(A.T, C.T, [0.1, 0.2, 0.3]).gain_matrix.T
    np.testing.assert_allclose(L, L_ref, rtol=1e-8)
    L3 = place_gain(A, C, [0.3, 0.3, 0.3])
    np.testing.assert_allclose(np.poly(A - L3 @ C), np.poly([0.3, 0.3, 0.3]), atol=1e-10)


def test_place_gain_on_a_detectable_unobservable_pair():
    """The unobservable mode 0.5 stays; the observable part gets the poles."""
    A = np.diag([1.0, 0.5])
    C = np.array([[1.0, 0.0]])
    L = place_gain(A, C, [0.2, 0.1])
    np.testing.assert_allclose(np.sort(np.linalg.eigvals(A - L @ C).real), [0.2, 0.5])
    with pytest.raises(DesignError, match="not detectable"):
        place_gain(np.diag([1.0, 1.5]), C, [0.2, 0.1])
    with pytest.raises(DesignError, match="closed under conjugation"):
        place_gain(A, np.eye(2), [0.2 + 0.1j, 0.1])


def _kalman_gain_by_iteration(A, C, Q, R, steps=5000):
    """Riccati difference equation of the predictor, iterated to convergence in
    Joseph form (the plain form loses symmetry and definiteness here)."""
    P = np.eye(A.shape[0])
    for _ in range(steps):
        K = A @ P @ C.T @ np.linalg.inv(C @ P @ C.T + R)
        Acl = A - K @ C
        P = Acl @ P @ Acl.T + K @ R @ K.T + Q
        P = 0.5 * (P + P.T)
    return A @ P @ C.T @ np.linalg.inv(C @ P @ C.T + R)


def test_lqe_gain_is_the_converged_kalman_predictor_gain():
    rng = np.random.default_rng(1)
    A = rng.normal(size=(3, 3))
    A *= 0.95 / np.abs(np.linalg.eigvals(A)).max()
    C = rng.normal(size=(2, 3))
    Q, R = np.diag([0.1, 0.2, 0.3]), np.diag([0.5, 0.05])
    np.testing.assert_allclose(lqe_gain(A, C, Q, R), _kalman_gain_by_iteration(A, C, Q, R),
                               rtol=1e-8, atol=1e-10)


def test_pio_and_higher_order_lqe_designs():
    """PIO(design='lqe'): the Kalman predictor gain of the augmented model (9)-(11)
    with covariances blockdiag(process, increment) and the measurement's (own
    Riccati iteration); the higher-order observer's from the model (x, d*, dd*)."""
    sys = so.examples.chang2006()
    obs = PIO(sys, design="lqe", process_cov=1e-4, increment_cov=[1.0, 0.5],
              measurement_cov=0.01)
    a = sys.augmented()
    Q = np.diag([1e-4] * 3 + [1.0, 0.5])
    K = _kalman_gain_by_iteration(a.A, a.C, Q, 0.01 * np.eye(2))
    np.testing.assert_allclose(np.vstack([obs.P, obs.L]), K, rtol=1e-7, atol=1e-9)
    assert obs.error_poles.stable
    ho = HigherOrderObserver(sys, design="lqe", process_cov=1e-4, increment_cov=1.0,
                             measurement_cov=0.01)
    n, q = sys.n, sys.q
    A = np.block([[sys.Phi, sys.G, np.zeros((n, q))],
                  [np.zeros((q, n)), np.eye(q), np.eye(q)],
                  [np.zeros((q, n + q)), np.eye(q)]])
    C = np.hstack([sys.Xi, np.zeros((2, 2 * q))])
    Q = np.diag([1e-4] * n + [0.0] * q + [1.0] * q)
    K = _kalman_gain_by_iteration(A, C, Q, 0.01 * np.eye(2), steps=20000)
    np.testing.assert_allclose(np.vstack([ho.P0, ho.L0 + ho.L1, ho.L0]), K,
                               rtol=1e-6, atol=1e-8)
    assert np.abs(np.linalg.eigvals(ho.transition)).max() < 1


@pytest.mark.parametrize(("kwargs", "match"), [
    ({"design": "kalman"}, "design must be 'poles' or 'lqe'"),
    ({"design": "lqe"}, "needs increment_cov"),
    ({"design": "lqe", "increment_cov": 1.0}, "needs measurement_cov"),
    ({"design": "lqe", "increment_cov": 1.0, "measurement_cov": 0.0}, "positive definite"),
    ({"design": "lqe", "increment_cov": [1.0], "measurement_cov": 1.0}, "must have 2 entries"),
    ({"design": "lqe", "poles": [0.1] * 5, "increment_cov": 1.0, "measurement_cov": 1.0},
     "not both"),
])
def test_lqe_bad_input(kwargs, match):
    with pytest.raises(DesignError, match=match):
        PIO(so.examples.chang2006(), **kwargs)


def test_U_is_required_when_the_system_has_inputs():
    sys = so.examples.servo_motor()
    obs = PIO(sys)
    Y = np.zeros((5, 1))
    with pytest.raises(ArgumentError, match=r"U is required: the system has 1 input\(s\) \(tau\)"):
        obs.run(Y)
    with pytest.raises(ArgumentError, match="u is required"):
        obs.step(Y[0])
    assert np.isfinite(obs.run(Y, np.zeros((5, 1))).estimate).all()
