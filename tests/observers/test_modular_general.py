"""Modular Luenberger observer in the general form of Sec. VIII.

A general exosystem ``S`` (a harmonic disturbance), a nonzero ``Q`` and the
paper's gains (49)-(52) beside the default DARE/placement ones. Oracles: the
eigenvalues the construction must give, a simulation of (45)-(46) written here,
and, for one output, the simultaneous Luenberger observer of the augmented
system placed at the same eigenvalues (the paper's "exactly the same as the
standard linear result").
"""

import numpy as np
import pytest

from setobs import LinearSystem
from setobs.exceptions import DesignError
from setobs.observers import ModularObserver, modular_paper_gains
from setobs.observers._gains import place_gain

F = np.array([[0.9, 0.2, 0.0], [-0.1, 0.8, 0.1], [0.0, 0.05, 0.7]])
P = np.array([[0.1, 0.0], [0.0, 0.1], [0.05, 0.02]])
H = np.array([[1.0, 0.0, 0.5]])
OM = 0.3
S = np.array([[np.cos(OM), np.sin(OM)], [-np.sin(OM), np.cos(OM)]])   # harmonic exosystem
Q = np.array([[0.2, -0.1]])
A0 = np.diag([0.2, 0.3, 0.4])
B0 = np.array([[1.0], [1.0], [1.0]])
AW = np.diag([0.5, 0.6])
BW = np.array([[1.0], [1.0]])
SYS = LinearSystem(F, P, H)


def simulate(N=120, seed=0):
    rng = np.random.default_rng(seed)
    x, w = rng.normal(size=3), rng.normal(size=2)
    X, W, Y = [], [], []
    for _ in range(N):
        X.append(x)
        W.append(w)
        Y.append(H @ x + Q @ w)
        x, w = F @ x + P @ w, S @ w
    return np.array(X), np.array(W), np.array(Y)


def test_paper_gains_give_the_chosen_eigenvalues():
    g = modular_paper_gains(SYS, A0, B0, AW, BW, S=S, Q=Q)
    assert np.allclose(np.sort(np.linalg.eigvals(F - g["L0"] @ H).real), [0.2, 0.3, 0.4])
    M = S - g["Lw"] @ (H @ g["V"] + Q)
    assert np.allclose(np.sort(np.linalg.eigvals(M).real), [0.5, 0.6])
    # eq. (48) and the similarities the construction stands on
    assert np.allclose(g["V"] @ S - (F - g["L0"] @ H) @ g["V"], P - g["L0"] @ Q)
    assert np.allclose(g["T0"] @ (F - g["L0"] @ H), A0 @ g["T0"])
    assert np.allclose(g["R"] @ M, AW @ g["R"])


def test_general_form_tracks_a_harmonic_disturbance_through_a_feedthrough():
    X, W, Y = simulate()
    g = modular_paper_gains(SYS, A0, B0, AW, BW, S=S, Q=Q)
    res = ModularObserver(SYS, g["L0"], g["Lw"], S=S, Q=Q).run(Y)
    err_w = np.abs(res.estimate - W).max(axis=1)
    err_x = np.abs(res.x_hat - X).max(axis=1)
    assert err_w[-1] < 1e-8 and err_x[-1] < 1e-8
    # the error decays at the slowest chosen eigenvalue (0.6), not faster, not slower
    k = np.arange(20, 50)                     # after the transient, above round-off
    ratio = np.exp(np.polyfit(k, np.log(err_w[20:50]), 1)[0])
    assert ratio == pytest.approx(0.6, abs=0.02)
    # the default gains (DARE + placement) work as well
    res2 = ModularObserver(SYS, S=S, Q=Q).run(Y)
    assert np.abs(res2.estimate[-1] - W[-1]).max() < 1e-6
    # the constant-disturbance form (S = I, Q = 0) is refused here: one output cannot
    # separate two constant disturbances (rank(Xi V) = 1 < q)
    with pytest.raises(DesignError, match="rank"):
        ModularObserver(SYS)


def test_single_output_modular_equals_the_simultaneous_luenberger_observer():
    """Sec. VIII: the modular design equals the standard one with the same eigenvalues."""
    _, _, Y = simulate(60, seed=1)
    g = modular_paper_gains(SYS, A0, B0, AW, BW, S=S, Q=Q)
    mod = ModularObserver(SYS, g["L0"], g["Lw"], S=S, Q=Q).run(Y)
    Aa = np.block([[F, P], [np.zeros((2, 3)), S]])
    Ca = np.hstack([H, Q])
    K = place_gain(Aa, Ca, [0.2, 0.3, 0.4, 0.5, 0.6])
    z = np.zeros(5)
    est = []
    for y in Y:
        est.append(z.copy())
        z = Aa @ z + K @ (y - Ca @ z)
    est = np.array(est)
    np.testing.assert_allclose(mod.estimate, est[:, 3:], atol=1e-8)
    np.testing.assert_allclose(mod.x_hat, est[:, :3], atol=1e-8)


def test_general_form_refusals():
    lam = float(np.linalg.eigvals(F).real.min())        # the real eigenvalue of F
    with pytest.raises(DesignError, match=r"eq\. \(48\) has no unique solution"):
        ModularObserver(SYS, L0=np.zeros((3, 1)), S=np.diag([lam, 0.3]))
    with pytest.raises(DesignError, match=r"T0 of eq\. \(50\) is singular"):
        modular_paper_gains(SYS, A0, np.zeros((3, 1)), AW, BW, S=S, Q=Q)
    with pytest.raises(DesignError, match="not detectable"):
        # w reaches neither the state nor the output: the disturbance module sees nothing
        ModularObserver(LinearSystem(F, np.zeros((3, 2)), H), S=S, Q=np.zeros((1, 2)))
