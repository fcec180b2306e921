"""Exact mode with noise over a bounded history (``setmembership._bounded``): the
whole-history LP cut to its last steps, with the outer and inner cut LPs' bracket.

Oracles: ``tests.oracles.history_lp_highs`` (the whole-history LP written
independently in the plant's coordinates and solved from scratch by scipy's HiGHS),
scipy ``linprog`` on the cut LP's own data for ``BoxLP.delete``, and the simulated truth.
The first cut is made early (``CUT_START`` small) so that a short record is cut.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest
from scipy.optimize import linprog

import setobs as so
from setobs.lp.boxlp import BoxLP
from setobs.setmembership import _bounded
from tests.oracles import history_lp_highs

A = np.array([[0.95, 0.1, 0.0, 0.0], [-0.2, 0.9, 0.05, 0.0],
              [0.0, 0.0, 0.98, 0.1], [0.0, 0.05, -0.1, 0.97]])
B = np.array([[0.0], [0.1], [0.0], [0.05]])
C = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.0]])
RW, RV = 0.01, 0.02
BOX = (-2.0 * np.ones(4), 2.0 * np.ones(4))


@pytest.fixture
def early_cut(monkeypatch):
    """The bounded history on, its first cut tried from step 13 (10 steps deep)."""
    monkeypatch.setattr(_bounded, "BOUNDED", True)
    monkeypatch.setattr(_bounded, "CUT_ROWS", 0)
    monkeypatch.setattr(_bounded, "CUT_START", 10)
    monkeypatch.setattr(_bounded, "CUT_RETRY", 3)
    monkeypatch.setattr(_bounded, "INNER_HISTORY", 15)


def _record(N, seed=0):
    rng = np.random.default_rng(seed)
    U = np.sin(0.1 * np.arange(N))[:, None]
    x = rng.uniform(-1, 1, 4)
    X, Y = [], []
    for _ in range(N):
        X.append(x.copy())
        Y.append(C @ x + rng.uniform(-RV, RV, 2))
        x = A @ x + B @ U[len(X) - 1] + rng.uniform(-RW, RW, 4)
    return np.array(X), np.array(Y), U


def _observer():
    return so.SMFDO(so.LinearSystem(A, np.zeros((4, 0)), C, B), window=None,
                    process_noise=RW, measurement_noise=RV, state_bounds=True, margin=0.0,
                    initial_state_set=so.Box(*BOX))


def _steps(obs, Y, U):
    N = Y.shape[0]
    lo, hi, st, L = np.empty((N, 4)), np.empty((N, 4)), [], []
    for k in range(N):
        e = obs.step(Y[k], U[k])
        lo[k], hi[k] = e.state_lo, e.state_hi
        st.append(e.status)
        L.append(obs.history_length)
    return lo, hi, st, L


def _oracle(Y, U, k):
    return history_lp_highs(A, np.zeros((4, 0)), C, Y, k, 0.0, U=U, Gamma=B, states=True,
                            x_box=BOX, noise_w=(np.eye(4), np.full(4, RW)),
                            noise_v=(np.eye(2), np.full(2, RV)))


def _check_against_oracle(Y, U, lo, hi, st, ks):
    """Never inside the whole-history LP (to its solver's 1e-9 of the width); a step
    called exact within 1e-6 of the width (EXACT_RTOL). Returns the excess of each
    checked step as a fraction of its widest band."""
    excess = {}
    for k in ks:
        olo, ohi = _oracle(Y, U, k)
        w = (ohi - olo).max()
        assert np.all(lo[k] <= olo + 1e-9 * w) and np.all(hi[k] >= ohi - 1e-9 * w), k
        excess[k] = max((olo - lo[k]).max(), (hi[k] - ohi).max()) / w
        if st[k] == "ok":
            assert excess[k] <= 1e-6, (k, excess[k])
    return excess


@pytest.mark.filterwarnings("ignore::setobs.SolverWarning")
def test_the_cut_history_stays_sound_and_exact_within_the_tolerance(early_cut):
    """The history is cut (the LP holds fewer steps than the record) and stays cut;
    every checked step is outside the independent whole-history LP and, where called
    exact, within 1e-6 of its width; the truth is inside at every step."""
    X, Y, U = _record(60)
    lo, hi, st, L = _steps(_observer(), Y, U)
    assert np.all((X >= lo) & (X <= hi))
    cut = [k for k in range(1, 60) if L[k] is not None and L[k] < k]
    assert cut and cut[0] <= 35 and cut == list(range(cut[0], 60))
    assert max(L[40:]) <= 30  # (bounded: the whole history would hold 40-59 steps)
    after = [k for k in cut if st[k] == "ok"]
    assert len(after) >= 0.8 * len(cut)
    excess = _check_against_oracle(Y, U, lo, hi, st, range(cut[0], 60, 3))
    # (the cut costs something: the outer LP is not the whole-history LP itself)
    assert max(excess.values()) > 1e-12


@pytest.mark.filterwarnings("ignore::setobs.SolverWarning")
def test_missing_samples_after_the_cut_grow_the_history(early_cut):
    """Seven missing samples after the cut: the history grows through the gap (no
    drop while the bracket is open) and shrinks after; sound and honest throughout."""
    X, Y, U = _record(60)
    Y[35:42] = np.nan
    lo, hi, st, L = _steps(_observer(), Y, U)
    assert np.all((X >= lo) & (X <= hi))
    assert L[34] is not None and L[34] < 34
    assert max(L[35:45]) > L[34] and L[59] < 59
    _check_against_oracle(Y, U, lo, hi, st, (36, 39, 42, 45, 50, 55, 59))


def test_off_the_lp_keeps_the_whole_history(early_cut, monkeypatch):
    """With the bounded history off the LP holds every step (the whole history)."""
    monkeypatch.setattr(_bounded, "BOUNDED", False)
    _, Y, U = _record(40)
    _, _, st, L = _steps(_observer(), Y, U)
    assert L[39] == 39 and all(s == "ok" for s in st)


@pytest.mark.filterwarnings("ignore::setobs.SolverWarning")
def test_a_copy_and_a_pickle_of_a_cut_history_stay_sound(early_cut):
    """A copy and a pickle taken after the cut (HiGHS models rebuilt cold from the
    copied data) go on sound, within 1e-6 of the width of the original's bands."""
    X, Y, U = _record(60, seed=2)
    obs = _observer()
    obs.run(Y[:40], U[:40])
    assert obs.history_length is not None and obs.history_length < 39
    twins = [copy.copy(obs), pickle.loads(pickle.dumps(obs))]
    a = obs.continue_run(Y[40:], U[40:])
    w = (a.state_hi - a.state_lo).max()
    for t in twins:
        b = t.continue_run(Y[40:], U[40:])
        assert np.all((X[40:] >= b.state_lo) & (X[40:] <= b.state_hi))
        np.testing.assert_allclose(b.state_lo, a.state_lo, rtol=0, atol=1e-6 * w)
        np.testing.assert_allclose(b.state_hi, a.state_hi, rtol=0, atol=1e-6 * w)


def _random_lp(rng, n_col=14, n_row=8):
    Aeq = rng.normal(size=(n_row, n_col)) * (rng.random((n_row, n_col)) < 0.5)
    x0 = rng.uniform(-0.5, 0.5, n_col)
    return Aeq, Aeq @ x0, -np.ones(n_col), np.ones(n_col)


def test_delete_keeps_the_rest_of_the_lp():
    """``BoxLP.delete`` after a warm solve: the kept LP's minima equal scipy's on the
    kept data (rows and columns re-indexed), and so do a clone's."""
    rng = np.random.default_rng(3)
    Aeq, b, lo, hi = _random_lp(rng)
    lp = BoxLP()
    cols = lp.add_cols(lo, hi)
    r, c = np.nonzero(Aeq)
    lp.add_rows(r, c, Aeq[r, c], b, np.zeros(b.size))
    W = rng.normal(size=(3, cols.size))
    assert lp.minimize_all(cols, W) is not None
    # remove two rows and the columns only they touch
    gone_r = np.array([1, 5])
    only = np.flatnonzero((Aeq[gone_r] != 0).any(axis=0) & ~(np.delete(Aeq, gone_r, 0) != 0)
                          .any(axis=0))
    lp.delete(only, gone_r)
    keep_c = np.setdiff1d(np.arange(cols.size), only)
    A2, b2 = np.delete(Aeq, gone_r, 0)[:, keep_c], np.delete(b, gone_r)
    W2 = W[:, keep_c]
    new_cols = np.arange(keep_c.size, dtype=np.int64)
    other = lp.clone()
    for got in (lp.minimize_all(new_cols, W2), other.minimize_all(new_cols, W2)):
        assert got is not None
        for j in range(W2.shape[0]):
            ref = linprog(W2[j], A_eq=A2, b_eq=b2, bounds=np.column_stack([lo[keep_c], hi[keep_c]]),
                          method="highs")
            assert ref.status == 0
            # certified: at most the optimum, within the certificate's slack of it
            assert got[j] <= ref.fun + 1e-9
            assert got[j] >= ref.fun - 1e-7 * (1.0 + abs(ref.fun))
