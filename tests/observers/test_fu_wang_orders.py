"""Fu-Wang's error-order claims (PIO O(T^2), higher-order observer O(T^3)), checked.

The paper prints only the discrete model (Chang 2006, T unknown). Two plants:

* **minimum phase** (documented here): ``x1' = x2, x2' = -x1 - x2 + f1,
  x3' = -x3 + f2``, ``y = (x1, x3)``. The claims hold: the steady-state state
  error falls with slopes close to 2 (PIO) and 3 (higher-order).
* **the paper's example**, reconstructed as a continuous plant with
  ``T0 = 0.1``: ``H = logm(A)/T0`` and ``F`` with ``int_0^T0 e^{Hs} ds F = E``
  (so the printed ``A``, ``E`` are reproduced exactly at ``T0``). Its invariant
  zero ``1.26095`` is a right-half-plane zero near ``+2.3 rad/s``; no observer can
  reconstruct the disturbance faster than that zero allows, and the errors do
  **not** decrease at the claimed orders (slopes ~0.2-0.4): a finding, pinned here.

Both observers use fixed discrete poles (as in the paper's example), the
disturbance is ``f(t) = [0.3 sin t + 0.5 cos 0.3t, 0.2 cos 0.5t + 2]`` (the
paper's ``d*(k)`` with ``t = k T0``), and the lumped ZOH disturbance of
Fu-Wang eq. (3) is integrated by 10-point Gauss-Legendre quadrature.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import expm, logm

import setobs as so
from setobs.studies import error_orders

TS = [0.1, 0.05, 0.025, 0.0125]


def f(t):
    return np.array([0.3 * np.sin(t) + 0.5 * np.cos(0.3 * t), 0.2 * np.cos(0.5 * t) + 2.0])


def test_orders_hold_on_a_minimum_phase_plant():
    H = np.array([[0, 1, 0], [-1, -1, 0], [0, 0, -1.0]])
    Fc = np.array([[0, 0], [1, 0], [0, 1.0]])
    C = np.array([[1.0, 0, 0], [0, 0, 1.0]])
    res = error_orders(H, Fc, C, f, TS)
    e = res.errors
    assert res.slope("PIO") > 1.6  # claimed 2
    assert res.slope("HO") > 2.5  # claimed 3
    # Local slope between the two finest sampling times approaches the claims.
    assert np.log2(e["PIO"][-2] / e["PIO"][-1]) > 1.9
    assert np.log2(e["HO"][-2] / e["HO"][-1]) > 2.7
    assert np.all(e["HO"] < e["PIO"])


def test_orders_fail_on_the_papers_nonminimum_phase_example():
    A = so.examples.chang2006()
    T0 = 0.1
    H = np.real(logm(A.Phi)) / T0
    Fc = np.linalg.solve(np.linalg.solve(H, expm(H * T0) - np.eye(3)), A.G)
    np.testing.assert_allclose(so.LinearSystem.from_continuous(H, None, Fc, A.Xi, T0).G, A.G,
                               atol=1e-12)
    z = so.analysis.invariant_zeros(A).zeros[0].real
    assert np.log(z) / T0 > 2.0  # right-half-plane zero of the continuous plant
    res = error_orders(H, Fc, A.Xi, f, TS)
    e = res.errors
    assert res.slope("PIO") < 0.6 and res.slope("HO") < 0.8  # far from 2 and 3
    assert e["PIO"][-1] > 0.4 * e["PIO"][0]  # essentially no decrease
