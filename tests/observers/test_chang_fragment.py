"""Chang fragment (descriptor observer with sensor noise): Lemma 4 and Theorem 1's O(T^2).

Lemma 4 is checked on the exact ZOH lumped disturbance computed here (matrix
exponentials and Gauss-Legendre quadrature, independent of the library's
sampling code); Theorem 1's order on the sampled plant through
``studies.error_orders``. Finding pinned: the O(T^2) bound needs an error system
whose contraction stays away from 1 as ``T`` shrinks (fixed discrete poles); the
DARE gain with fixed weights (eqs. (18)-(19)) loses the order.
"""

import numpy as np
import pytest
from scipy.linalg import expm

from setobs.observers import DescriptorObserver
from setobs.studies import error_orders

TS = [0.1, 0.05, 0.025, 0.0125]
H = np.array([[0, 1, 0], [-1, -1, 0], [0, 0, -1.0]])
FC = np.array([[0, 0], [1, 0], [0, 1.0]])
C = np.array([[1.0, 0, 0], [0, 0, 1.0], [0, 1.0, 0]])
FN = np.array([[0.0], [0.0], [1.0]])           # sensor noise on the third output


def f(t):
    return np.array([0.3 * np.sin(t) + 0.5 * np.cos(0.3 * t), 0.2 * np.cos(0.5 * t) + 2.0])


def slope(T, e):
    return float(np.polyfit(np.log(T), np.log(e), 1)[0])


def test_lemma4_lumped_disturbance_orders():
    """(1) ||(I - G G^+) f(k)|| = O(T^2) and (2) ||f(k+1) - f(k)|| = O(T^2).

    (1) holds with a margin: it is O(T^3) here. With ``f(k) = int_0^T e^{Hs} F
    f((k+1)T - s) ds = G f((k+1)T) - (T^2/2) F f'((k+1)T) + O(T^3)`` the
    ``T^2`` term lies in ``range(F)``, which ``range(G) = range(T F + O(T^2))``
    contains up to ``O(T)``, so the projection leaves ``O(T^3)``."""
    gx, gw = np.polynomial.legendre.leggauss(10)
    out1, out2 = [], []
    for T in TS:
        G = np.linalg.solve(H, expm(H * T) - np.eye(3)) @ FC     # int_0^T e^{Hs} ds F
        proj = np.eye(3) - G @ np.linalg.pinv(G)
        taus, ws = 0.5 * T * (gx + 1), 0.5 * T * gw
        kern = [expm(H * t) @ FC for t in taus]
        ks = np.arange(int(5.0 / T), int(15.0 / T))
        fk = np.array([sum(w * K @ f((k + 1) * T - t) for w, K, t in zip(ws, kern, taus,
                                                                          strict=True))
                       for k in ks])
        out1.append(np.abs(fk @ proj.T).max())
        out2.append(np.abs(np.diff(fk, axis=0)).max())
    assert slope(TS, out1) > 1.9                                  # the lemma's bound
    assert slope(TS, out1) == pytest.approx(3.0, abs=0.1)          # the measured order
    assert slope(TS, out2) == pytest.approx(2.0, abs=0.1)


def test_theorem1_order_with_fixed_poles_and_independence_of_the_noise():
    poles = [0.1, 0.2, 0.3, 0.35, 0.4, 0.5]
    obs = {"desc": lambda s: DescriptorObserver(s, FN, poles=poles)}
    clean = error_orders(H, FC, C, f, TS, observers=obs)
    noisy = error_orders(H, FC, C, f, TS, observers=obs,
                         noise=lambda t: (FN @ [0.05 * np.sin(37.0 * t)]).ravel())
    e = clean.errors["desc"]
    assert clean.slope("desc") > 1.85                       # Theorem 1: O(T^2)
    assert np.log2(e[-2] / e[-1]) > 1.9
    # the sensor noise is reconstructed as a state: it does not reach the error at all
    np.testing.assert_allclose(noisy.errors["desc"], e, rtol=1e-6)


def test_dare_gain_with_fixed_weights_loses_the_order():
    res = error_orders(H, FC, C, f, TS, observers={"dare": lambda s: DescriptorObserver(s, FN)})
    assert res.slope("dare") < 0.3
    assert res.errors["dare"][-1] > 0.5 * res.errors["dare"][0]


def test_descriptor_poles_bad_input():
    from setobs import LinearSystem
    from setobs.exceptions import DesignError

    sys = LinearSystem.from_continuous(H, None, FC, C, 0.1)
    with pytest.raises(DesignError, match="6 error poles"):
        DescriptorObserver(sys, FN, poles=[0.1, 0.2])
    with pytest.raises(DesignError, match="not both"):
        DescriptorObserver(sys, FN, np.eye(6), poles=[0.1] * 6)
