"""Fu-Wang, Sec. IV, Figs. 1-10: the higher-order observer against the PIO on the paper's
``d*(k)``, with a verdict per claim (notebook 05 draws the figures).

The printed gains do not work (the PIO's error system is unstable; the printed
higher-order gains have a root at z = 1, see test_observers.py), so both observers
use gains designed at the paper's poles {0.1, 0.2, 0.3 +- 0.5j, 0.4} (+ {0.5, 0.45}
for the two extra poles of the higher-order observer). Metric: the Euclidean norm of
the disturbance estimate error averaged over the figure's window (transient
1 <= k <= 50, Figs. 1-6; steady state 50 <= k <= 200, Figs. 7-8; the same under
measurement noise of standard deviation 0.001, Figs. 9-10). The issue's
independent run gave: steady state 0.061 (higher-order) vs 0.117 (PIO), transient
3.87 vs 1.24, under noise 0.29 vs 0.14.
"""

from __future__ import annotations

import numpy as np
import pytest

import setobs as so
from setobs.observers import PIO, HigherOrderObserver

N = 201


def dstar(k):
    """Fu-Wang's d*(k) (Sec. IV)."""
    return np.stack([0.3 * np.sin(0.1 * k) + 0.5 * np.cos(0.03 * k),
                     0.2 * np.cos(0.05 * k) + 2.0], axis=-1)


def runs(noise=0.0, seed=0):
    sys = so.examples.chang2006()
    D = dstar(np.arange(N))
    Y, X = sys.simulate(D, x0=[0, 1, 0])  # x(0) = [0 1 0], estimates start at 0
    Y = Y + noise * np.random.default_rng(seed).standard_normal(Y.shape)
    out = {}
    for name, obs in (("PIO", PIO(sys)), ("HO", HigherOrderObserver(sys))):
        r = obs.run(Y)
        out[name] = (np.linalg.norm(r.estimate - D, axis=1), r.estimate,
                     np.linalg.norm(r.x_hat - X, axis=1), r.x_hat)
    return out


def test_designed_gains_are_at_the_papers_poles():
    sys = so.examples.chang2006()
    np.testing.assert_allclose(np.sort_complex(PIO(sys).error_poles.poles),
                               np.sort_complex([0.1, 0.2, 0.3 + 0.5j, 0.3 - 0.5j, 0.4]),
                               atol=1e-8)
    assert HigherOrderObserver(sys).error_poles.stable


def test_figs7_8_steady_state_reproduced():
    """Figs. 7-8: the higher-order observer is better in steady state: reproduced."""
    out = runs()
    ho, pio = out["HO"][0][50:].mean(), out["PIO"][0][50:].mean()
    assert ho == pytest.approx(0.0613, abs=5e-4) and pio == pytest.approx(0.1166, abs=5e-4)
    assert out["HO"][2][50:].mean() < 0.6 * out["PIO"][2][50:].mean()  # states too (Fig. 7)


def test_figs1_6_transient_claim_differs():
    """Figs. 1-6: 'evidently better at transient state' and smaller change rates: not
    reproduced with working gains; the higher-order observer's transient is about three
    times larger (3.87 vs 1.24) and its estimates change faster. The plant's invariant
    zero 1.26095 (outside the unit circle) drives a large transient for any fast
    observer; the higher-order observer has two more poles to place."""
    out = runs()
    ho, pio = out["HO"][0][1:51].mean(), out["PIO"][0][1:51].mean()
    assert ho == pytest.approx(3.866, abs=0.01) and pio == pytest.approx(1.242, abs=0.01)
    assert out["HO"][2][1:51].mean() > 2 * out["PIO"][2][1:51].mean()  # states (Figs. 1, 3)
    for col in (1, 3):  # change rates of the estimated disturbances and states (Figs. 5, 2)
        rate = {n: np.abs(np.diff(out[n][col][:51], axis=0)).mean() for n in out}
        assert rate["HO"] > rate["PIO"]


def test_figs9_10_noise_claim_differs():
    """Figs. 9-10: 'less affected by noise': not reproduced; with noise 0.001 the
    higher-order observer's steady-state error is about twice the PIO's (0.29 vs 0.14 in
    the audit's independent run; 0.28 vs 0.13 over the 3 seeds here, 0.30 vs 0.14 over
    20), over seeds. Its extra difference term amplifies the measurement noise."""
    clean = runs()
    for seed in range(3):
        noisy = runs(noise=0.001, seed=seed)
        ho, pio = noisy["HO"][0][50:].mean(), noisy["PIO"][0][50:].mean()
        assert 0.2 < ho < 0.4 and 0.12 < pio < 0.17 and ho > 1.6 * pio
        # the part due to the noise alone (estimates' deviation from the noise-free run)
        dev = {n: np.linalg.norm(noisy[n][1][50:] - clean[n][1][50:], axis=1).mean()
               for n in noisy}
        assert dev["HO"] > 3 * dev["PIO"]
