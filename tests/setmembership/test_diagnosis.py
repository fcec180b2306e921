"""Fault diagnosis with several models against an independent oracle: a whole-history
feasibility LP written here (scipy's linprog) decides whether a mode could have produced
the record up to a step; the mode that produced it is never excluded (own simulator)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import setobs as so
from setobs.exceptions import ArgumentError
from setobs.setmembership import diagnose_modes

A = np.array([[0.9, 0.2], [0.0, 0.8]])
B = np.array([[0.0], [1.0]])
C = np.array([[1.0, 0.0]])
RW, RV, R0 = 0.01, 0.05, 1.0
MODES = {"nominal": (A, B), "actuator at 20 %": (A, 0.2 * B),
         "leak": (np.array([[0.7, 0.2], [0.0, 0.8]]), B)}


def simulate(Am, Bm, N, rng):
    U = rng.normal(size=(N, 1))
    x = rng.uniform(-R0, R0, 2)
    Y = []
    for k in range(N):
        Y.append(C @ x + rng.uniform(-RV, RV, 1))
        x = Am @ x + Bm @ U[k] + rng.uniform(-RW, RW, 2)
    return np.array(Y), U


def feasible(Am, Bm, Y, U, k):
    """Whether some start in the box and noises in theirs explain y_0..y_k (an LP in
    x_0 and w_0..w_(k-1): x_j = A^j x_0 + sum A^(j-1-i) (B u_i + w_i))."""
    n = 2
    nv = n + n * k
    rows, rhs = [], []
    for j in range(k + 1):
        M = np.zeros((n, nv))
        off = np.zeros(n)
        M[:, :n] = np.linalg.matrix_power(Am, j)
        for i in range(j):
            P = np.linalg.matrix_power(Am, j - 1 - i)
            M[:, n + n * i: n + n * (i + 1)] = P
            off += P @ (Bm @ U[i])
        r = C @ M
        rows += [r[0], -r[0]]
        rhs += [Y[j, 0] - C[0] @ off + RV, -(Y[j, 0] - C[0] @ off) + RV]
    bounds = [(-R0, R0)] * n + [(-RW, RW)] * (n * k)
    res = linprog(np.zeros(nv), A_ub=np.array(rows), b_ub=np.array(rhs), bounds=bounds,
                  method="highs")
    assert res.status in (0, 2)
    return res.status == 0


def observers():
    return {name: so.SMFDO(so.LinearSystem(Am, np.zeros((2, 0)), C, Bm), window=10,
                           measurement_noise=[RV], process_noise=[RW, RW],
                           initial_state_set=so.Box([-R0, -R0], [R0, R0]), state_bounds=True,
                           on_inconsistent="skip", max_skip_fraction=0.5)
            for name, (Am, Bm) in MODES.items()}


@pytest.mark.parametrize("truth", list(MODES))
def test_the_true_mode_stays_and_every_exclusion_is_confirmed(truth):
    rng = np.random.default_rng(list(MODES).index(truth))
    Y, U = simulate(*MODES[truth], 40, rng)
    out = diagnose_modes(observers(), Y, U)
    assert truth in out.consistent and truth not in out.excluded
    assert len(out.excluded) >= 1  # these faults are large enough to be seen in 40 steps
    for name, k in out.excluded.items():
        # no history of that mode explains the data up to the step it was excluded at
        assert not feasible(*MODES[name], Y, U, k), (name, k)
    assert out.results[truth] is not None
    assert truth in repr(out)


def test_bad_input():
    with pytest.raises(ArgumentError, match="at least one"):
        diagnose_modes({}, np.zeros((3, 1)))
    obs = observers()["nominal"]
    strict = so.SMFDO(so.LinearSystem(A, np.zeros((2, 0)), C, B), window=10,
                      measurement_noise=[RV], process_noise=[RW, RW],
                      initial_state_set=so.Box([-R0, -R0], [R0, R0]), state_bounds=True)
    with pytest.raises(ArgumentError, match="on_inconsistent"):
        diagnose_modes({"a": obs, "b": strict}, np.zeros((3, 1)))
    with pytest.raises(ArgumentError, match="expected an SMFDO"):
        diagnose_modes({"a": object()}, np.zeros((3, 1)))
