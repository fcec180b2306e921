"""The nonlinear modular design (modular-observer paper, eqs. (28), (31), (35) and
Proposition 7) by power series, against independent computations.

The closed forms used here are built in sympy from the example's linearizing
coordinates ``xi = 2x/(1+x)``, ``eta = w/(1+w)`` (``xi+ = xi/2 - eta``,
``eta+ = eta``, ``y = xi + eta``) and *checked to satisfy* the functional
equations symbolically before the series are compared with them.
"""

from __future__ import annotations

import itertools
import pickle
import warnings

import numpy as np
import pytest
from scipy.linalg import solve_sylvester

from setobs.analysis import diagnose
from setobs.analysis.modular import (
    design_modular,
    design_simultaneous,
    nonlinear_modular_conditions,
)
from setobs.analysis.powerseries import Monomials, invert, taylor
from setobs.exceptions import DesignError

sp = pytest.importorskip("sympy")
from setobs.examples import modular_example  # noqa: E402
from setobs.nonlinear import NonlinearSystem  # noqa: E402

x, w = sp.symbols("x w")
XI = 2 * x / (1 + x)
ETA = w / (1 + w)
F_EX = (x - w) / (2 + x + (2 * x + 3) * w)
H_EX = XI + ETA
A0, B0, AW, BW = 0.4, 1.0, 0.6, 1.0


def _closed_forms():
    """Phi0, Xi, Psi of the example in closed form, from the linear (xi, eta) system:
    Phi0 = c xi with c (1/2 - A0) = B0; the simultaneous Phi = T (xi, eta) with
    T Fz - A T = B Hz; Xi from Phi_0(Xi, w) = Phi0(x); Psi = Phi_w(Xi, w)."""
    Fz, Hz = np.array([[0.5, -1.0], [0.0, 1.0]]), np.array([[1.0, 1.0]])
    T = solve_sylvester(-np.diag([A0, AW]), Fz, np.array([[B0], [BW]]) @ Hz)
    c = B0 / (0.5 - A0)
    phi0 = c * XI
    xi_corr = XI - sp.Float(T[0, 1] / T[0, 0]) * ETA   # xi(Xi(x, w))
    Xi = xi_corr / (2 - xi_corr)
    Psi = sp.Float(T[1, 0]) * xi_corr + sp.Float(T[1, 1]) * ETA
    return phi0, Xi, Psi


def test_the_closed_forms_satisfy_the_functional_equations():
    """The reference solutions really solve (31), (28) and (35) (exact f, h; 30 digits)."""
    phi0, Xi, Psi = _closed_forms()
    y = sp.Symbol("y")
    # eq. (32): phi0(x, y) = Phi0^{-1}(A0 Phi0(x) + B0 y); Phi0^{-1}(z) = xi^{-1}(z / c)
    c = B0 / (0.5 - A0)
    inv = lambda z: (z / c) / (2 - z / c)  # noqa: E731
    phi0_xy = inv(A0 * phi0 + B0 * y)
    r31 = phi0.subs(x, F_EX.subs(w, 0)) - A0 * phi0 - B0 * H_EX.subs(w, 0)
    hXi = H_EX.subs(x, Xi)
    G1 = phi0_xy.subs(y, hXi)
    r28 = Xi.subs({x: G1}, simultaneous=True) - F_EX.subs(x, Xi)
    r35 = Psi.subs({x: G1}, simultaneous=True) - AW * Psi - BW * hXi
    for pt in itertools.product((-0.3, 0.1, 0.35), (-0.2, 0.05, 0.3)):
        for r in (r31, r28, r35):
            assert abs(float(sp.N(r.subs({x: pt[0], w: pt[1]}), 30))) < 1e-12


def test_series_converge_to_the_closed_forms_and_residuals_fall_with_the_order():
    phi0, Xi, Psi = _closed_forms()
    f_phi0, f_xi, f_psi = (sp.lambdify((x, w), e) for e in (phi0, Xi, Psi))
    pts = np.random.default_rng(3).uniform(-0.12, 0.12, size=(25, 2))
    errs, res = [], []
    sys = modular_example()
    for order in (3, 6, 9, 12):
        d = design_modular(sys, A0, B0, AW, BW, order=order)
        e = max(max(abs(d.Phi0_at(p[:1])[0] - f_phi0(*p)), abs(d.Xi_at(p[:1], p[1:])[0]
                    - f_xi(*p)), abs(d.Psi_at(p[:1], p[1:])[0] - f_psi(*p))) for p in pts)
        errs.append(e)
        res.append(d.residuals(pts))
    assert all(b < 0.2 * a for a, b in itertools.pairwise(errs)), errs
    assert errs[-1] < 1e-4
    for key in ("31", "28", "35"):
        seq = [r[key] for r in res]
        assert all(b < 0.2 * a for a, b in itertools.pairwise(seq)), (key, seq)


def test_the_corrector_has_the_linear_part_of_eq_48():
    """Xi_1 = [I, W] with K_x W - W S = K_y Q - P (the nonlinear counterpart of
    Sec. VIII's eq. (48)); for the example K_x = A0 (scalar), K_y = B0 / T0,
    F = 1/2, P = -1/2, H = 2, Q = 1, S = 1, so W = (K_y Q - P) / (A0 - 1)."""
    d = design_modular(modular_example(), A0, B0, AW, BW, order=4)
    T0 = 2 * B0 / (0.5 - A0)           # Phi0 = c xi, xi'(0) = 2
    Ky = B0 / T0
    W = (Ky * 1.0 + 0.5) / (A0 - 1.0)   # A0 W - W = Ky Q - P
    np.testing.assert_allclose(d.Xi[0, 1:3], [1.0, W], rtol=1e-12)
    # Xi(x, 0) = x: no pure-x terms beyond degree 1
    bv = d.basis_v
    pure_x = [i for i, e in enumerate(bv.exponents) if e[1] == 0 and e[0] >= 2]
    assert np.abs(d.Xi[0, pure_x]).max() < 1e-12


def test_proposition7_the_modular_and_simultaneous_designs_agree_as_series():
    """Proposition 7 coefficient by coefficient (truncated compositions are exact up
    to the order): Phi0(x) = Phi_0(x, 0); Phi_0(Xi(x, w), w) = Phi0(x);
    Psi = Phi_w(Xi(x, w), w). The simultaneous design solves (22)-(23) on the
    extended system, the modular one (31), (28), (35): different equations."""
    sys = modular_example()
    order = 8
    d = design_modular(sys, A0, B0, AW, BW, order=order)
    P0, Pw = design_simultaneous(sys, A0, B0, AW, BW, order=order)
    bv, bx = d.basis_v, d.basis_x
    x_in_v = bx.embed(bv, [0])
    np.testing.assert_allclose(P0.C[:, x_in_v], d.Phi0.C, atol=1e-9)
    ident_w = np.zeros((1, len(bv)))
    ident_w[0, 2] = 1.0
    M = bv.substitution(np.vstack([d.Xi, ident_w]))
    lifted = np.zeros((1, len(bv)))
    lifted[:, x_in_v] = d.Phi0.C
    scale = np.abs(lifted).max()
    assert np.abs(P0.C @ M - lifted).max() < 1e-9 * scale
    assert np.abs(Pw.C @ M - d.Psi.C).max() < 1e-9 * np.abs(d.Psi.C).max()
    # and at points, the residuals fall with the order
    pts = np.random.default_rng(4).uniform(-0.15, 0.15, size=(15, 2))
    r = [design_modular(sys, A0, B0, AW, BW, order=o).proposition7_residuals(
        design_simultaneous(sys, A0, B0, AW, BW, order=o), pts) for o in (4, 8, 12)]
    for key in ("ii", "iii"):
        assert r[1][key] < 0.2 * r[0][key] and r[2][key] < 0.2 * r[1][key]
    assert max(q["i"] for q in r) < 1e-12


def test_series_inverse_and_substitution_between_bases():
    """invert() against sympy's inverse of 20x/(1+x) (x = z/(20 - z)), and a
    substitution into a basis with more variables."""
    bx = Monomials(1, 9)
    C = taylor([20 * x / (1 + x)], [x], bx)
    G = invert(C, bx)
    z = sp.Symbol("z")
    np.testing.assert_allclose(G, taylor([z / (20 - z)], [z], bx), rtol=1e-12, atol=1e-15)
    b2 = Monomials(2, 4)
    F = taylor([x + x * w], [x, w], b2)
    comp = Monomials(1, 4).substitution(F, b2)
    cq = taylor([x - x**2], [x], Monomials(1, 4))
    expect = taylor([(x + x * w) - (x + x * w) ** 2], [x, w], b2)[0]
    np.testing.assert_allclose(cq[0] @ comp, expect, atol=1e-14)


def test_conditions_report_and_refusals():
    sys = modular_example()
    rep = nonlinear_modular_conditions(sys, A0, AW, order=6)
    assert rep.exists and not rep.numbers["Poincare domain"]
    assert abs(rep.numbers["min divisor"] - 0.1) < 1e-12  # |0.4 - 0.5|, |0.6 - 0.5|
    # A0 = 0.25 = 0.5^2 resonates with F = 1/2 at degree 2 (Prop. 2, assumption 2)
    bad = nonlinear_modular_conditions(sys, 0.25, AW, order=6)
    assert not bad.exists and "resonance" in bad.reason
    with pytest.raises(DesignError, match="resonance"):
        design_modular(sys, 0.25, 1.0, AW, 1.0, order=4)
    # x not seen by the output: (H, F) unobservable
    un = NonlinearSystem([x / 2 + w], [w + w**2], [x], [w])
    r = nonlinear_modular_conditions(un)
    assert not r.exists and "(H, F) is not observable" in r.reason
    d = diagnose(un)
    assert not d["nonlinear modular observer"].exists


def test_diagnose_has_the_nonlinear_row_and_the_linearizations_rows():
    """The example has Q != 0: only the nonlinear row. A model with y = x + x^2
    (Q = 0, S = I): the linear rows are those of its linearization."""
    d = diagnose(modular_example())
    assert [v.design for v in d.verdicts] == ["nonlinear modular observer"]
    assert any("Proposition 3, assumption 3" in n for n in d.notes)
    m = NonlinearSystem([0.6 * x + 0.1 * sp.sin(x) + w], [x + x**2], [x], [w])
    d2 = diagnose(m)
    assert d2.existing[-1] == "nonlinear modular observer"
    assert "modular observer" in d2.existing and d2.zeros is not None
    assert "nonlinear modular observer" in repr(d2) and "| nonlinear modular" in d2.to_markdown()


def test_model_validation():
    with pytest.raises(ValueError, match="equilibrium"):
        NonlinearSystem([x + 1], [x], [x], [w])
    a = sp.Symbol("a")
    with pytest.raises(ValueError, match="neither states nor disturbances"):
        NonlinearSystem([a * x], [x], [x], [w])
    with pytest.raises(ValueError, match="w only"):
        NonlinearSystem([x], [x], [x], [w], s=[w + x])
    m = pickle.loads(pickle.dumps(modular_example()))
    np.testing.assert_allclose(m.f_num([0.5], [0.2]), (0.5 - 0.2) / (2.5 + 4 * 0.2))
    d = design_modular(m, A0, B0, AW, BW, order=4)
    d2 = pickle.loads(pickle.dumps(d))
    np.testing.assert_allclose(d2.Psi_at([0.1], [0.1]), d.Psi_at([0.1], [0.1]))


def test_extension_along_the_observer_map_reaches_beyond_the_radius():
    """x~ = 1 is on the edge of Phi0's series (pole at x = -1): the truncated series
    there is 0 or 20, the closed form 10. extend_to_z carries the series outward by
    eq. (31) (and (35) for Psi) along x -> f(x, 0) and recovers the closed forms."""
    phi0, _, Psi = _closed_forms()
    d = design_modular(modular_example(), A0, B0, AW, BW, order=12)
    assert abs(d.Phi0_at([1.0])[0] - 10.0) > 5.0
    z = d.extend_to_z([1.0], [0.0])
    np.testing.assert_allclose(z, [float(phi0.subs(x, 1)), float(Psi.subs({x: 1, w: 0}))],
                               rtol=1e-5)


def test_diagnostics_by_order_fall_inside_the_radius_and_warn_beyond_the_pole():
    """The residuals of (31), (28), (35) by truncation order. Near the
    equilibrium (default points, half the radius estimate) each falls at every order and
    nothing is flagged; the smallest divisor is 0.1 (|Aw - 0.5| = |A0 - 0.5|, by hand:
    the linearization's eigenvalues are 1/2 and 1). At |w| > 1, beyond the exact
    solution's pole at w = -1 (its closed form, ``_closed_forms``), the series diverge:
    the residual of (28) grows with the order and a DesignWarning says so."""
    from setobs.exceptions import DesignWarning

    d = design_modular(modular_example(), A0, B0, AW, BW, order=7)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DesignWarning)
        g = d.diagnostics()
    assert g.orders == tuple(range(1, 8)) and g.growing == ()
    assert g.min_divisor == pytest.approx(0.1)
    for key in ("31", "28", "35"):
        assert all(b < a for a, b in itertools.pairwise(g.residuals[key])), key
    with pytest.warns(DesignWarning, match=r"eq\. \(28\)"):
        far = d.diagnostics(points=[[0.0, 1.5], [0.3, -1.2]])
    assert "28" in far.growing and far.residuals["28"][-1] > 10 * far.residuals["28"][0]
    assert "| 7 |" in far.to_markdown()


def test_truncated_design_equals_a_design_at_that_order():
    """The series are solved degree by degree: truncating an order-7 design at 4 gives the
    order-4 design's coefficients (to rounding)."""
    d7 = design_modular(modular_example(), A0, B0, AW, BW, order=7).truncated(4)
    d4 = design_modular(modular_example(), A0, B0, AW, BW, order=4)
    n4 = len(d4.basis_v)
    np.testing.assert_allclose(d7.Xi[:, :n4], d4.Xi, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(d7.Psi.C[:, :n4], d4.Psi.C, rtol=1e-10, atol=1e-12)
    assert not d7.Xi[:, n4:].any()


def test_near_resonance_and_a_nearly_singular_linear_part_warn_at_design_time():
    """A0 = 0.2503 against 0.5^2 = 0.25: divisor 3e-4 (by hand), near resonance; and two
    observer eigenvalues 1e-7 apart on the two-state pendulum make the rows of T0
    (``T0 F - A0 T0 = B0 H``, row i = H (F - a_i I)^-1) equal to within ~1e-7: nearly
    singular (1e-9 apart it is refused as singular; 1e-3 apart it is fine)."""
    from setobs.exceptions import DesignWarning

    with pytest.warns(DesignWarning, match="smallest divisor 3.00e-04"):
        design_modular(modular_example(), 0.2503, B0, AW, BW, order=3)
    dt = 0.05
    th, om, tau = sp.symbols("theta omega tau")
    pend = NonlinearSystem([th + dt * om, om + dt * (-9.81 * sp.sin(th) - om + tau)], [th],
                           [th, om], [tau], dt=dt)
    with pytest.warns(DesignWarning, match="T0 is nearly singular"):
        design_modular(pend, [0.7, 0.7 + 1e-7], None, [0.8], None, order=2)
    with pytest.raises(DesignError, match="singular"):
        design_modular(pend, [0.7, 0.7 + 1e-9], None, [0.8], None, order=2)
    with warnings.catch_warnings():
        warnings.simplefilter("error", DesignWarning)
        design_modular(pend, [0.7, 0.701], None, [0.8], None, order=2)
