"""States on the unobservable part driven by the disturbance or by observable states not
yet pinned down (reproducer ``unobservable_driven_state_unbounded.py``:
``x2+ = 0.5 x2 + d + w2`` with only ``x1`` measured kept a band of +-inf for the whole
record, exact and windowed, although the whole-history LP bounds it from ``k = 1``).

Oracle: the whole-history LP of the states in the original coordinates
(``tests.oracles.history_lp_highs``, every state, disturbance and noise a variable,
HiGHS at tolerances 1e-10) and the truth of records simulated here. The library's band
must contain the LP's at every step (it is an outer bound), be finite wherever the LP's
is, and equal it at the first step (the start-up's joint set is the exact set there).
"""

from __future__ import annotations

import numpy as np
import pytest

import setobs as so
from setobs.geometry import Box
from tests.oracles import history_lp_highs


def _simulate(Phi, G, Xi, Gamma, N, rng, r, x0, d0, U=None, missing=0.0):
    n, q, l = Phi.shape[0], G.shape[1], Xi.shape[0]
    x, d = np.array(x0, float), np.array(d0, float)
    X, Y = [], []
    for k in range(N):
        X.append(x.copy())
        Y.append(Xi @ x + rng.uniform(-r, r, l))
        x = Phi @ x + G @ d + rng.uniform(-r, r, n)
        if U is not None:
            x = x + Gamma @ U[k]
        d = d + rng.uniform(-r, r, q)
    Y = np.array(Y)
    if missing:
        Y[1:][rng.random(Y[1:].shape) < missing] = np.nan
    return np.array(X), Y


def _plants():
    """(name, Phi, G, Xi, Gamma, free states): the reproducer; a free state driven by an
    observable state that the data pin down one step after the disturbance; two free
    states in a non-normal block with an input, two outputs and missing samples."""
    yield ("reproducer", np.diag([0.8, 0.5]), np.array([[1.0], [1.0]]),
           np.array([[1.0, 0.0]]), None, [1])
    yield ("delayed", np.array([[1.0, 0.1, 0.0], [0.0, 0.9, 0.0], [0.0, 1.0, 0.5]]),
           np.array([[0.0], [1.0], [0.0]]), np.array([[1.0, 0.0, 0.0]]), None, [2])
    yield ("non-normal", np.array([[0.9, 0.2, 0.0, 0.0], [-0.1, 0.8, 0.0, 0.0],
                                   [0.0, 0.0, 0.6, 2.0], [0.3, 0.0, 0.0, 0.5]]),
           np.array([[0.0], [1.0], [1.0], [0.0]]),
           np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0]]),
           np.array([[1.0], [0.0], [0.0], [0.0]]), [2, 3])


@pytest.mark.parametrize("window", [None, 10])
@pytest.mark.parametrize("plant", list(_plants()), ids=lambda p: p[0])
def test_free_states_are_bounded_from_the_first_step_the_lp_bounds_them(plant, window):
    name, Phi, G, Xi, Gamma, free = plant
    n = Phi.shape[0]
    r, N = 0.01, 20
    rng = np.random.default_rng(len(name))
    U = None if Gamma is None else rng.uniform(-1, 1, (N, 1))
    X, Y = _simulate(Phi, G, Xi, Gamma, N, rng, r, rng.uniform(-0.9, 0.9, n), [0.3], U,
                     missing=0.1 if name == "non-normal" else 0.0)
    sys_ = so.LinearSystem(Phi, G, Xi, Gamma)
    obs = so.SMFDO(sys_, window=window, increment_set=[r], process_noise=r,
                   measurement_noise=r, initial_state_set=Box(-np.ones(n), np.ones(n)),
                   state_bounds=True)
    res = obs.run(Y, U)
    box = (-np.ones(n), np.ones(n))
    for k in range(N):
        lo, hi = history_lp_highs(Phi, G, Xi, Y, k, r, U=U, Gamma=Gamma, x_box=box,
                                  noise_w=(np.eye(n), np.full(n, r)),
                                  noise_v=(np.eye(Xi.shape[0]), np.full(Xi.shape[0], r)),
                                  states=True)
        assert np.all((X[k] >= res.state_lo[k]) & (X[k] <= res.state_hi[k])), (name, k)
        for i in free:
            a, b = res.state_lo[k, i], res.state_hi[k, i]
            tol = 1e-7 * (1.0 + abs(lo[i]) + abs(hi[i]))
            assert a <= lo[i] + tol and b >= hi[i] - tol, (name, k, i, (a, b), (lo[i], hi[i]))
            if np.isfinite(lo[i]) and np.isfinite(hi[i]):
                assert np.isfinite(a) and np.isfinite(b), (name, k, i)
                # (a sanity bound on the tracker's looseness, not a target)
                assert b - a <= 20.0 * (hi[i] - lo[i]) + 1e-6, (name, k, i)
            if k == 1:  # the start-up's joint set: the whole-history set itself
                assert abs(a - lo[i]) <= 1e-6 and abs(b - hi[i]) <= 1e-6, (name, k, i)
    assert np.isfinite(res.state_hi[1:, free]).all()
