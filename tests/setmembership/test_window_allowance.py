"""The window's rounding allowances on stable, ill-conditioned plants.

The closed form's ``c_err`` / ``b_err`` were bounded by ``gamma |A_o|^j`` products, which
grow like the spectral radius of ``|A_o|`` (48 per step on the plant of
``shared/data/regressions/window_allowance_growth.py``) while ``A_o^j`` decays: window
10 bands reached 1e5 there at k = 11 while exact mode stayed at 0.3, status ``ok``.
Oracle: the whole-history LP of every state and noise sample as a variable
(:func:`tests.oracles.history_lp_highs`: no power of ``Phi`` is formed).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import setobs as so
from setobs.exceptions import SolverWarning
from setobs.geometry import Box
from setobs.setmembership import _closed_form
from setobs.setmembership._closed_form import ModelCache
from setobs.setmembership._powers import PowerTable
from setobs.setmembership.engines import window as window_engine
from setobs.tolerances import ALLOWANCE_RTOL
from tests.oracles import history_lp_highs


def modal_blocks(rng, n: int, rho: float) -> np.ndarray:
    """A real block-diagonal ``J`` of modulus at most ``rho`` (one eigenvalue at ``rho``):
    rotation blocks and real eigenvalues in random order."""
    blocks, m = [], 0
    while m < n:
        if n - m >= 2 and rng.random() < 0.5:
            r = rho if m == 0 else rho * rng.uniform(0.3, 1.0)
            th = rng.uniform(0.1, 3.0)
            blocks.append(r * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]]))
            m += 2
        else:
            blocks.append(np.array([[rho if m == 0 else rho * rng.uniform(-1.0, 1.0)]]))
            m += 1
    J = np.zeros((n, n))
    i = 0
    for B in blocks:
        J[i:i + B.shape[0], i:i + B.shape[0]] = B
        i += B.shape[0]
    return J


def ill_conditioned_plant(seed: int, q: int, n: int = 7, rho: float = 0.7):
    """A stable plant ``T J T^-1`` (eigenvalues of modulus <= ``rho``, one at ``rho``)
    whose eigenvector basis is far from orthogonal, two outputs, ``q`` disturbances."""
    rng = np.random.default_rng(seed)
    J = modal_blocks(rng, n, rho)
    T = rng.normal(size=(n, n)) + 2 * np.eye(n)
    Phi = T @ J @ np.linalg.inv(T)
    Xi = rng.normal(size=(2, n))
    G = rng.normal(size=(n, q))
    return so.LinearSystem(Phi, G, Xi), rng


def corner_record(sysm, rng, N, rw, rv, rdd, box):
    """States, disturbances and measurements with every noise sample on a corner."""
    n, q, l = sysm.n, sysm.q, sysm.l
    x = np.where(rng.random(n) < 0.5, box[0], box[1])
    d = rng.uniform(-1, 1, q)
    X, D, Y = [], [], []
    for _ in range(N):
        X.append(x.copy())
        D.append(d.copy())
        Y.append(sysm.Xi @ x + rng.choice([-1.0, 1.0], l) * rv)
        x = sysm.Phi @ x + sysm.G @ d + rng.choice([-1.0, 1.0], n) * rw
        d = d + rng.choice([-1.0, 1.0], q) * rdd
    return np.array(X), np.array(D).reshape(N, q), np.array(Y)


def test_power_bounds_contain_the_exact_powers_and_do_not_compound():
    # exact rational powers of a float matrix: the computed powers are within F_k of
    # them, and F_k decays with the powers instead of growing like |A|^k
    from fractions import Fraction

    sysm, _ = ill_conditioned_plant(8, 0)
    A, n = sysm.Phi, sysm.n
    tab = PowerTable(A).extend(12)
    Af = [[Fraction(v) for v in row] for row in A]
    P = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    absA_k = np.eye(n)
    for k in range(1, 13):
        P = [[sum(Af[i][t] * P[t][j] for t in range(n)) for j in range(n)] for i in range(n)]
        absA_k = np.abs(A) @ absA_k
        dev = np.array([[abs(Fraction(tab.powers[k][i, j]) - P[i][j]) for j in range(n)]
                        for i in range(n)], dtype=float)
        assert (dev <= tab.F[k]).all()
        assert (np.abs(np.array(P, dtype=float)) <= tab.P[k]).all()
        # the bound is at most 1e4 times the true rounding of the chain, and far
        # below the textbook gamma |A|^k
        assert tab.F[k].max() <= 1e4 * max(dev.max(), 1e-16 * np.abs(tab.powers[k]).max())
    # |A|^12 is about 1e18 times the powers here; the bound stays at rounding level
    assert absA_k.max() > 1e15 * np.abs(tab.powers[12]).max()
    assert tab.F[12].max() < 1e-11


@pytest.mark.parametrize(("seed", "q"), [
    (5, 0), (8, 1), (21, 1),
    pytest.param(5, 1, marks=pytest.mark.slow), pytest.param(8, 0, marks=pytest.mark.slow),
    pytest.param(21, 0, marks=pytest.mark.slow)])
def test_window_bands_stay_near_the_whole_history_lp_on_ill_conditioned_plants(seed, q):
    sysm, rng = ill_conditioned_plant(seed, q)
    n, N = sysm.n, 36
    assert np.linalg.cond(sysm.Phi) > 1e3
    assert np.abs(np.linalg.eigvals(np.abs(sysm.Phi))).max() > 20  # |Phi|^k grows
    assert np.abs(np.linalg.eigvals(sysm.Phi)).max() < 0.71
    rw, rv, rdd = 1e-2, 1e-2, 1e-3
    box = (-np.ones(n), np.ones(n))
    X, _, Y = corner_record(sysm, rng, N, rw, rv, rdd, box)
    kw = dict(process_noise=rw * np.ones(n), measurement_noise=rv * np.ones(2),
              initial_state_set=Box(*box), state_bounds=True)
    if q:
        kw["increment_set"] = Box(-rdd * np.ones(q), rdd * np.ones(q))
    with warnings.catch_warnings():
        warnings.simplefilter("error", SolverWarning)  # no 'inexact' warning either
        res = so.SMFDO(sysm, window=10, **kw).run(Y)
    assert set(res.status) <= {"ok", "unbounded"}
    assert ((res.state_lo <= X) & (X <= res.state_hi)).all()
    for k in (12, 24, 35):
        lo, hi = history_lp_highs(sysm.Phi, sysm.G, sysm.Xi, Y, k, rdd * np.ones(q),
                                  x_box=box, noise_w=(np.eye(n), rw * np.ones(n)),
                                  noise_v=(np.eye(2), rv * np.ones(2)), states=True)
        w_lp, w_win = hi - lo, res.state_hi[k] - res.state_lo[k]
        # outward (up to the LP's own tolerance) and within a small factor
        assert (w_win >= w_lp * (1 - 1e-6) - 1e-9).all()
        assert (w_win <= 3.0 * w_lp + 1e-9).all(), (k, (w_win / w_lp).max())
        if q:
            dlo, dhi = history_lp_highs(sysm.Phi, sysm.G, sysm.Xi, Y, k, rdd * np.ones(q),
                                        x_box=box, noise_w=(np.eye(n), rw * np.ones(n)),
                                        noise_v=(np.eye(2), rv * np.ones(2)))
            wd = res.hi[k] - res.lo[k]
            assert (wd >= (dhi - dlo) * (1 - 1e-6) - 1e-9).all()
            assert (wd <= 3.0 * (dhi - dlo) + 1e-9).all(), (k, wd, dhi - dlo)
        assert res.steps[k].gap < 1e-6


def test_a_step_whose_allowance_dominates_says_so(monkeypatch):
    # a model allowance far above rounding: the allowances then take much of the
    # band; the step is certified but not 'ok', its gap says how much, one warning
    sysm, rng = ill_conditioned_plant(3, 0, n=4)
    n = sysm.n
    box = (-np.ones(n), np.ones(n))
    X, _, Y = corner_record(sysm, rng, 20, 1e-3, 1e-3, 0.0, box)
    # (gK about 1e-3: an allowance of 1e-3 |y| on every measurement row; a cache of
    # its own, so that no other test meets these structures)
    real_rtol = _closed_form.model_rtol
    monkeypatch.setattr(_closed_form, "model_rtol", lambda *a: 1e-3)
    monkeypatch.setattr(window_engine, "MODEL_CACHE", ModelCache())
    obs = so.SMFDO(sysm, window=4, process_noise=1e-3 * np.ones(n),
                   measurement_noise=1e-3 * np.ones(2), initial_state_set=Box(*box),
                   state_bounds=True)
    with pytest.warns(SolverWarning, match="rounding allowances") as rec:
        res = obs.run(Y)
    assert sum("rounding allowances" in str(w.message) for w in rec) == 1
    inexact = res.status == "inexact"
    assert inexact.any()
    gaps = res.gap
    assert gaps.shape == (20,)
    assert (gaps[inexact] > ALLOWANCE_RTOL).all()
    assert (gaps[res.status == "ok"] <= ALLOWANCE_RTOL).all()
    assert ((res.state_lo <= X) & (X <= res.state_hi)).all()
    # the gap is what the allowance costs: before the first restart (k < window, every
    # step from the initial set) the band's excess over the same run with the model's
    # true rounding allowance is within the step's gap of the band
    monkeypatch.setattr(_closed_form, "model_rtol", real_rtol)
    monkeypatch.setattr(window_engine, "MODEL_CACHE", ModelCache())
    ref = so.SMFDO(sysm, window=4, process_noise=1e-3 * np.ones(n),
                   measurement_noise=1e-3 * np.ones(2), initial_state_set=Box(*box),
                   state_bounds=True).run(Y)
    for k in range(4):
        w1 = res.state_hi[k] - res.state_lo[k]
        w0 = ref.state_hi[k] - ref.state_lo[k]
        assert (w1 - w0 <= (gaps[k] + 1e-9) * w1).all(), (k, gaps[k], ((w1 - w0) / w1).max())
        assert (w1 >= w0).all()


def _reported_plant():
    """The plant and record of ``shared/data/regressions/window_allowance_growth.py``
    (its generator and draws: seed 0, a 7-state plant with spectral radius 0.7 and
    ``cond(Phi) = 2e4``, two outputs, no disturbance, noise on the corners, simulated in
    long double)."""
    rng = np.random.default_rng(0)
    n = int(rng.integers(2, 9))
    l = int(rng.integers(1, min(n, 3) + 1))
    p = int(rng.integers(0, 2))
    J = modal_blocks(rng, n, 0.7)
    T = rng.normal(size=(n, n)) + 2 * np.eye(n)
    Phi = T @ J @ np.linalg.inv(T)
    Xi = rng.normal(size=(l, n))
    Gamma = rng.normal(size=(n, p)) if p else None
    sysm = so.LinearSystem(Phi, np.zeros((n, 0)), Xi, Gamma)
    rw = 10.0 ** rng.uniform(-3, -1) * np.ones(n)
    rv = 10.0 ** rng.uniform(-3, -1) * np.ones(l)
    rng.uniform(-3, -1)  # (the disturbance's radius: no disturbance here)
    box = (-rng.uniform(0.5, 2, n), rng.uniform(0.5, 2, n))
    x0 = np.where(rng.random(n) < 0.5, box[0], box[1])
    ld = np.longdouble
    x = np.array(x0, dtype=ld)
    rng.normal(size=0)
    X, Y, U = [], [], []
    for _ in range(40):
        u = rng.uniform(-1, 1, p)
        v = rng.choice([-1.0, 1.0], l) * rv
        X.append(x.copy())
        Y.append(Xi.astype(ld) @ x + v.astype(ld))
        U.append(u)
        w = rng.choice([-1.0, 1.0], n) * rw
        x = Phi.astype(ld) @ x + (Gamma.astype(ld) @ u.astype(ld) if p else 0) + w.astype(ld)
    return (sysm, box, rw, rv, np.array(X, dtype=float), np.array(Y, dtype=float),
            np.array(U, dtype=float).reshape(40, p))


def test_the_reported_plant_keeps_its_bands():
    # window 10 and 20 bands were 2e5 at k = 15 and 1e5-1e22 by k = 25-39, status ok
    sysm, box, rw, rv, X, Y, U = _reported_plant()
    n, l = sysm.n, sysm.l
    assert n == 7 and l == 2 and np.linalg.cond(sysm.Phi) > 1e4
    kw = dict(process_noise=rw, measurement_noise=rv, state_bounds=True,
              initial_state_set=Box(*box))
    lo, hi = history_lp_highs(sysm.Phi, sysm.G, sysm.Xi, Y, 39, np.zeros(0),
                              U=U if sysm.p else None, Gamma=sysm.Gamma if sysm.p else None,
                              x_box=box, noise_w=(np.eye(n), rw), noise_v=(np.eye(l), rv),
                              states=True)
    for window, restart in ((10, "box"), (20, "polytope")):
        res = so.SMFDO(sysm, window=window, restart=restart, **kw).run(Y, U if sysm.p else None)
        assert set(res.status) == {"ok"}
        assert ((res.state_lo <= X) & (X <= res.state_hi)).all()
        w = res.state_hi[39] - res.state_lo[39]
        assert (w >= (hi - lo) * (1 - 1e-6)).all() and (w <= 1.2 * (hi - lo)).all()
        assert (res.state_hi - res.state_lo).max() < 5.0  # (the initial box is 4 wide)

