"""Exact mode's ``ok`` means within ``EXACT_RTOL`` (1e-6) of the width of the exact set.

On a held-out 30-state plant exact mode's bounds were 2e-4 to 4.4e-4 of the width
outside the whole-history LP with status ``ok``: the certification gap that
``BoxLP._explained`` accepts (the basic columns' reduced-cost inaccuracy times their
ranges) let an inexact multiplier through. Here the solver's duals are made inexact on
purpose (relative noise on HiGHS's row duals): the multiplier refined from the basis
(``BoxLP.refined_multiplier``) restores the exact bounds; without it the step says ``inexact``
with a gap that covers the true excess. Oracle: the whole-history LP of every state and
noise sample as a variable (:func:`tests.oracles.history_lp_highs`, unscaled HiGHS).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import setobs as so
from setobs.exceptions import SolverWarning
from setobs.lp import boxlp
from setobs.tolerances import EXACT_RTOL
from tests.oracles import history_lp_highs, noisy_record


class _NoisyDuals:
    """A HiGHS model whose reported row duals carry relative noise ``eps``."""

    def __init__(self, hs, eps: float, rng) -> None:
        self._hs, self._eps, self._rng = hs, eps, rng

    def __getattr__(self, name):
        return getattr(self._hs, name)

    def getSolution(self):  # (HiGHS's name)
        sol = self._hs.getSolution()
        y = np.asarray(sol.row_dual, dtype=np.float64)
        noisy = y * (1.0 + self._eps * self._rng.uniform(-1, 1, y.size))

        class _Sol:
            col_value = sol.col_value
            row_dual = noisy
        return _Sol()


def _plant():
    rng = np.random.default_rng(3)
    n, l = 5, 2
    A = rng.normal(size=(n, n))
    A *= 0.9 / np.abs(np.linalg.eigvals(A)).max()
    B, C = rng.normal(size=(n, 1)), rng.normal(size=(l, n))
    U = rng.normal(size=(30, 1))
    rw, rv = 0.01, 0.02
    X, Y = noisy_record(A, B, C, U, rw, rv, rng)
    return A, B, C, U, X, Y, rw, rv


def _run(monkeypatch, refine: bool):
    A, B, C, U, X, Y, rw, rv = _plant()
    n = A.shape[0]
    real = boxlp.BoxLP.build_model
    rng = np.random.default_rng(0)

    def build(self, cols, w, ranged=False):
        hs = real(self, cols, w, ranged)
        return None if hs is None else _NoisyDuals(hs, 1e-4, rng)

    monkeypatch.setattr(boxlp.BoxLP, "build_model", build)
    calls = []
    refined = boxlp.BoxLP.refined_multiplier

    def counted(self, hs, cols, w):
        calls.append(1)
        return refined(self, hs, cols, w) if refine else None

    monkeypatch.setattr(boxlp.BoxLP, "refined_multiplier", counted)
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((n, 0)), C, B), window=None,
                   process_noise=rw, measurement_noise=rv, state_bounds=True,
                   initial_state_set=so.Box(-np.ones(n), np.ones(n)))
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        res = obs.run(Y, U)
    assert ((res.state_lo <= X) & (X <= res.state_hi)).all()
    assert len(calls) >= 10  # (the whole-history LP ran, its duals were off)
    return res, rec, (A, B, C, U, Y, rw, rv)


@pytest.mark.parametrize("refine", [True, False])
def test_an_inexact_multiplier_is_refined_or_reported(monkeypatch, refine):
    res, rec, (A, B, C, U, Y, rw, rv) = _run(monkeypatch, refine)
    n, l = A.shape[0], C.shape[0]
    for k in (12, 29):
        lo, hi = history_lp_highs(A, np.zeros((n, 0)), C, Y, k, np.zeros(0), U=U, Gamma=B,
                                  x_box=(-np.ones(n), np.ones(n)),
                                  noise_w=(np.eye(n), np.full(n, rw)),
                                  noise_v=(np.eye(l), np.full(l, rv)), states=True,
                                  unscaled=True)
        w = hi - lo
        excess = (lo - res.state_lo[k]) + (res.state_hi[k] - hi)
        assert (excess >= -1e-8 * w).all()  # outward
        st = res.steps[k]
        if st.status == "ok":
            assert (excess <= 2 * EXACT_RTOL * w + 1e-9).all(), (k, (excess / w).max())
        else:
            assert st.status == "inexact" and st.gap > EXACT_RTOL
        # the reported gap (a fraction of the reported band) covers the true excess, up
        # to the oracle's tolerance and the reported margin
        w_rep = res.state_hi[k] - res.state_lo[k]
        assert (excess <= (st.gap + 1e-6) * w_rep).all(), (k, st.gap, (excess / w_rep).max())
    inexact = res.status == "inexact"
    if refine:
        assert not inexact.any()
        assert not [r for r in rec if issubclass(r.category, SolverWarning)]
    else:
        # without the refinement the noisy duals leave gaps far above 1e-6: said, and warned
        assert inexact.sum() >= 10
        assert [r for r in rec if "certificate's gap" in str(r.message)]


@pytest.mark.slow
def test_a_30_state_cascade_is_ok_only_within_the_tolerance():
    """A 30-tank cascade with 21 levels measured (other constants than the benchmark's,
    a feedback from the last tank to the first), exact mode over 40 steps against the
    unscaled tight-tolerance HiGHS whole-history LP: every ``ok`` band within
    ``EXACT_RTOL`` of the exact width, every band's excess within its step's gap."""
    from scipy.linalg import expm

    n, l = 30, 21
    Ac = (np.diag(-np.ones(n)) + np.diag(np.ones(n - 1), -1)) * 0.35
    Ac[0, n - 1] = 0.05
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[0, n] = Ac, 0.4
    E = expm(M)
    A, B = E[:n, :n], E[:n, n:]
    skip = set(np.round(np.linspace(0, n - 1, n - l + 2)[1:-1]).astype(int))
    C = np.eye(n)[[i for i in range(n) if i not in skip]]
    rng = np.random.default_rng(1)
    U = np.sin(0.05 * np.arange(40))[:, None] + 0.2 * rng.normal(size=(40, 1))
    rw, rv = 0.01, 0.02
    X, Y = noisy_record(A, B, C, U, rw, rv, rng)
    box = (-2 * np.ones(n), 2 * np.ones(n))
    res = so.SMFDO(so.LinearSystem(A, np.zeros((n, 0)), C, B), window=None, process_noise=rw,
                   measurement_noise=rv, state_bounds=True,
                   initial_state_set=so.Box(*box)).run(Y, U)
    assert ((res.state_lo <= X) & (X <= res.state_hi)).all()
    for k in (20, 39):
        lo, hi = history_lp_highs(A, np.zeros((n, 0)), C, Y, k, np.zeros(0), U=U, Gamma=B,
                                  x_box=box, noise_w=(np.eye(n), np.full(n, rw)),
                                  noise_v=(np.eye(l), np.full(l, rv)), states=True,
                                  unscaled=True)
        w = hi - lo
        excess = (lo - res.state_lo[k]) + (res.state_hi[k] - hi)
        st = res.steps[k]
        assert (excess >= -1e-7 * w).all()
        w_rep = res.state_hi[k] - res.state_lo[k]
        assert (excess <= (st.gap + 1e-6) * w_rep).all()
        if st.status == "ok":
            assert (excess <= 2 * EXACT_RTOL * w).all()
