"""The power-series solution of the observer-linearization LFE (modular-observer
paper, Section VII), against closed forms of the paper's example (Section VI).

In the coordinates ``xi = 2x/(1+x)``, ``eta = w/(1+w)`` the example
``x+ = (x - w)/(2 + x + (2x + 3)w)``, ``w+ = w``, ``y = 2x/(1+x) + w/(1+w)`` is
linear (``xi+ = xi/2 - eta``, ``eta+ = eta``, ``y = xi + eta``), so the LFEs have
closed-form solutions the truncated series must converge to.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.linalg import solve_sylvester

from setobs.analysis.powerseries import Monomials, lfe_conditions, solve_lfe, taylor
from setobs.exceptions import DesignError

sp = pytest.importorskip("sympy")
x, w = sp.symbols("x w")
F_EX = (x - w) / (2 + x + (2 * x + 3) * w)
H_EX = 2 * x / (1 + x) + w / (1 + w)


def test_disturbance_free_lfe_31_is_the_closed_form():
    """Eq. (31) with A0 = 0.4, B0 = 1: f(x, 0) = x/(2 + x), h(x, 0) = 2x/(1 + x);
    Phi0 = c xi with c (1/2 - 0.4) = 1, i.e. Phi0 = 20 x/(1 + x) = 20 sum (-1)^(k+1) x^k."""
    basis = Monomials(1, 12)
    sol = solve_lfe(taylor([F_EX.subs(w, 0)], [x], basis),
                    taylor([H_EX.subs(w, 0)], [x], basis), [[0.4]], [[1.0]], basis)
    k = np.arange(1, 13)
    np.testing.assert_allclose(sol.C[0, 1:], 20.0 * (-1.0) ** (k + 1), rtol=1e-9)
    assert sol.C[0, 0] == 0.0 and sol.conditions.satisfied


def test_simultaneous_lfe_converges_to_the_closed_form_as_the_order_grows():
    """Eqs. (22)-(23) with A = diag(0.4, 0.6), B = (1, 1): the exact solution is
    Phi = T (xi(x), eta(w)) with T Fz - A T = B Hz for the linear (xi, eta) system."""
    A, B = np.diag([0.4, 0.6]), np.array([[1.0], [1.0]])
    Fz, Hz = np.array([[0.5, -1.0], [0.0, 1.0]]), np.array([[1.0, 1.0]])
    T = solve_sylvester(-A, Fz, B @ Hz)
    pts = np.random.default_rng(0).uniform(-0.25, 0.25, size=(40, 2))
    exact = np.column_stack([2 * pts[:, 0] / (1 + pts[:, 0]), pts[:, 1] / (1 + pts[:, 1])]) @ T.T
    errs = []
    for order in (2, 4, 6, 8, 10):
        basis = Monomials(2, order)
        sol = solve_lfe(taylor([F_EX, w], [x, w], basis), taylor([H_EX], [x, w], basis),
                        A, B, basis)
        errs.append(np.abs(sol(pts) - exact).max())
    assert all(b < 0.5 * a for a, b in itertools.pairwise(errs))
    assert errs[-1] < 1e-4
    # the linear part is the closed form's Jacobian: d(xi)/dx = 2, d(eta)/dw = 1 at 0
    np.testing.assert_allclose(sol.T, T @ np.diag([2.0, 1.0]), rtol=1e-12)


def test_lfe_residual_decreases_with_the_order():
    """The residual Phi(F(v)) - A Phi(v) - B h(v) of the truncated solution,
    evaluated with the true (untruncated) f and h, shrinks with the order."""
    A, B = np.diag([0.4, 0.6]), np.array([[1.0], [1.0]])
    fn = sp.lambdify((x, w), F_EX)
    hn = sp.lambdify((x, w), H_EX)
    pts = np.random.default_rng(1).uniform(-0.2, 0.2, size=(30, 2))
    Fv = np.column_stack([fn(pts[:, 0], pts[:, 1]), pts[:, 1]])
    hv = hn(pts[:, 0], pts[:, 1])
    res = []
    for order in (3, 6, 9):
        basis = Monomials(2, order)
        sol = solve_lfe(taylor([F_EX, w], [x, w], basis), taylor([H_EX], [x, w], basis),
                        A, B, basis)
        r = sol(Fv) - sol(pts) @ A.T - hv[:, None] @ B.T
        res.append(np.abs(r).max())
    assert res[1] < 0.1 * res[0] and res[2] < 0.1 * res[1]


def test_a_linear_system_gives_its_linear_transformation_exactly():
    """F, h linear: the series stops at degree 1 and satisfies the LFE to rounding."""
    rng = np.random.default_rng(2)
    F1 = np.array([[0.5, 0.2, 0.0], [0.0, 0.3, 0.1], [0.0, 0.0, 1.0]])
    H1 = rng.normal(size=(1, 3))
    A, B = np.diag([0.1, 0.2, 0.35]), np.ones((3, 1))
    basis = Monomials(3, 4)
    F = np.zeros((3, len(basis)))
    F[:, basis.block[1]] = F1
    h = np.zeros((1, len(basis)))
    h[:, basis.block[1]] = H1
    sol = solve_lfe(F, h, A, B, basis)
    assert np.abs(sol.C[:, basis.block[2].start:]).max() <= 1e-13
    v = rng.normal(size=(10, 3))
    np.testing.assert_allclose(sol(v @ F1.T), sol(v) @ A.T + (v @ H1.T) @ B.T, atol=1e-12)


def test_resonance_is_refused_and_reported():
    """lambda(F) = 0.5 and an observer eigenvalue 0.25 = 0.5^2: the degree-2
    equation is singular (Proposition 2, assumption 2)."""
    basis = Monomials(1, 3)
    F = taylor([x / (2 + x)], [x], basis)
    h = taylor([x], [x], basis)
    cond = lfe_conditions(F[:, basis.block[1]], h[:, basis.block[1]], [[0.25]], [[1.0]], 3)
    assert not cond.nonresonant and cond.min_divisor < 1e-12
    with pytest.raises(DesignError, match="resonance"):
        solve_lfe(F, h, [[0.25]], [[1.0]], basis)
    ok = lfe_conditions(F[:, basis.block[1]], h[:, basis.block[1]], [[0.3]], [[1.0]], 3)
    assert ok.satisfied and abs(ok.min_divisor - 0.05) < 1e-12


def test_monomial_products_and_substitution_match_sympy():
    """Truncated products and a polynomial substitution against sympy's expansion."""
    basis = Monomials(2, 4)
    p = x + 2 * w - x * w + 3 * x**2
    q = 1 - w + x**3
    cp, cq = taylor([p], [x, w], basis)[0], taylor([q], [x, w], basis)[0]
    prod = basis.multiply(cp, cq)
    expect = taylor([sp.expand(p * q)], [x, w], basis)[0]  # truncated by taylor
    np.testing.assert_allclose(prod, expect, atol=1e-14)
    F = taylor([x + w**2, 0.5 * w - x * w], [x, w], basis)
    MF = basis.substitution(F)
    comp = cp @ MF
    sub = sp.expand(p.subs({x: x + w**2, w: 0.5 * w - x * w}, simultaneous=True))
    np.testing.assert_allclose(comp, taylor([sub], [x, w], basis)[0], atol=1e-13)
