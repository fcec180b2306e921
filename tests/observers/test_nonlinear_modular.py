"""The nonlinear modular observer (modular-observer paper, Secs. IV-VII): Figure 3's
behaviour from the series design, the assigned error dynamics, and the linear case
against the existing Sec. VIII observer."""

from __future__ import annotations

import itertools
import pickle
import warnings

import numpy as np
import pytest
from scipy.linalg import solve_sylvester

from setobs import LinearSystem
from setobs.exceptions import InvalidValueError
from setobs.observers import ModularObserver

sp = pytest.importorskip("sympy")
from setobs.analysis.modular import design_modular  # noqa: E402
from setobs.examples import modular_example  # noqa: E402
from setobs.nonlinear import NonlinearSystem  # noqa: E402
from setobs.observers import NonlinearModularObserver  # noqa: E402

A0, B0, AW, BW = 0.4, 1.0, 0.6, 1.0


def _fig3(order, coordinates="linearizing", N=80):
    sys = modular_example()
    X, W, Y = sys.simulate([2.0], [1.0], N)
    obs = NonlinearModularObserver(sys, A0, B0, AW, BW, order=order, x0=[1.0], w0=[0.0],
                                   coordinates=coordinates)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return X, W, obs.run(Y)


def test_figure3_offset_of_the_disturbance_free_estimate():
    """x~ neglects w and settles at a wrong value; the closed form of the offset in
    the linear coordinates: y* = xi* + eta = -1 + 1/2, z0* = B0 y*/(1 - A0),
    xi(x~*) = z0*/c with c = B0/(1/2 - A0), x~* = xi/(2 - xi) = -1/25; the true x
    settles at the fixed point -1/3 of x = (x - 1)/(5 + 3x)."""
    X, _, res = _fig3(12)
    assert abs(X[-1, 0] + 1 / 3) < 1e-12
    c = B0 / (0.5 - A0)
    xi = (B0 * -0.5 / (1 - A0)) / c
    np.testing.assert_allclose(res.x_tilde[-1, 0], xi / (2 - xi), atol=1e-9)
    assert abs(res.x_tilde[-1, 0] - X[-1, 0]) > 0.29  # the permanent offset


def test_figure3_corrected_and_disturbance_estimates_converge_as_the_order_grows():
    """From the series design (no closed form typed in): the final errors of x^ and
    w^ shrink with the truncation order, geometrically."""
    errs, flagged = [], []
    for order in (4, 7, 10, 13):
        X, W, res = _fig3(order)
        errs.append(max(abs(res.x_hat[-1, 0] - X[-1, 0]), abs(res.estimate[-1, 0] - W[-1, 0])))
        flagged.append(int(res.untrusted[40:-1].sum()))  # (the last step cannot be checked)
        assert res.estimate.shape == (80, 1) and res.x_hat.shape == (80, 1)
    assert all(b < 0.3 * a for a, b in itertools.pairwise(errs)), errs
    assert errs[-1] < 1e-3
    # the trust flag (an error estimate above 1e-3): at order 4 the final error is
    # above it, at order 13 (1.2e-4) below
    assert errs[0] > 1e-2 and flagged[0] == 39 and flagged[-1] == 0


def test_original_coordinates_fail_at_figure3_and_flag_it():
    """Eqs. (32), (36), (26) evaluated in the original coordinates need Psi and Xi at
    w^ near 1, the edge of the series' radius in w: the estimate does not converge
    with the order there, and the run says so (a warning and result.untrusted)."""
    sys = modular_example()
    x = [2.0]  # the truth, simulated here: x+ = (x - w) / (2 + x + (2x + 3) w), w = 1
    for _ in range(59):
        x.append((x[-1] - 1.0) / (5.0 + 3.0 * x[-1]))
    X = np.array(x)[:, None]
    Y = 2 * X / (1 + X) + 0.5
    obs = NonlinearModularObserver(sys, A0, B0, AW, BW, order=12, x0=[1.0],
                                   coordinates="original")
    with pytest.warns(RuntimeWarning, match="consistent with the model and the data"):
        res = obs.run(Y)
    err = np.maximum(np.abs(res.estimate[:, 0] - 1.0), np.abs(res.x_hat[:, 0] - X[:, 0]))
    assert err[-1] > 0.1                      # the failure ...
    assert res.untrusted[err > 0.1].all()     # ... and every step of it flagged


def test_both_realisations_agree_near_the_equilibrium():
    """Small disturbance and states: eqs. (32)/(36) in original coordinates and
    (30)/(34) in linearizing coordinates are the same observer up to truncation."""
    sys = modular_example()
    _X, _W, Y = sys.simulate([0.1], [0.05], 40)
    out = {}
    for c in ("linearizing", "original"):
        obs = NonlinearModularObserver(sys, A0, B0, AW, BW, order=10, coordinates=c)
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            out[c] = obs.run(Y)
    np.testing.assert_allclose(out["linearizing"].estimate, out["original"].estimate, atol=1e-7)
    np.testing.assert_allclose(out["linearizing"].x_hat, out["original"].x_hat, atol=1e-7)
    assert abs(out["original"].estimate[-1, 0] - 0.05) < 1e-7


def test_error_decay_ratio_tends_to_the_slowest_assigned_eigenvalue():
    """In the linearizing coordinates the errors obey e+ = A e, so the estimation
    errors decay at max(lambda_0, lambda_w) = 0.6; the disturbance-free part alone
    (w = 0) at lambda_0 = 0.4."""
    sys = modular_example()
    X, W, Y = sys.simulate([0.3], [0.2], 45)
    design = design_modular(sys, A0, B0, AW, BW, order=14)
    res = NonlinearModularObserver(design).run(Y)
    e = np.abs(res.x_hat - X).max(axis=1) + np.abs(res.estimate - W).max(axis=1)
    ratio = e[21:31] / e[20:30]
    np.testing.assert_allclose(ratio, 0.6, atol=0.01)
    X0, _, Y0 = sys.simulate([0.3], [0.0], 30)
    r0 = NonlinearModularObserver(design).run(Y0)
    e0 = np.abs(r0.x_tilde - X0)[:, 0]
    np.testing.assert_allclose(e0[11:21] / e0[10:20], 0.4, atol=0.01)


def test_the_linear_case_is_the_sec_viii_modular_observer():
    """f = F x + P w, h = H x, s = w: with A0 = F - L0 H, B0 = L0 (so T0 = I),
    Aw = S - Lw H V and Bw = Lw + Psi_x L0 (Psi_x from Aw Psi_x - Psi_x (F - L0 H)
    = -Lw H, so Psi_w = I), the design reproduces ModularObserver (eqs. (47)-(52))
    exactly, in both realisations."""
    F = np.array([[0.8, 0.3], [-0.1, 0.6]])
    P = np.array([[1.0], [0.5]])
    H = np.array([[1.0, 0.0]])
    L0 = np.array([[0.7], [0.2]])
    Lw = np.array([[0.3]])
    lin = ModularObserver(LinearSystem(F, P, H), L0=L0, Lw=Lw)
    Fc = F - L0 @ H
    V = solve_sylvester(-Fc, np.eye(1), P)   # eq. (48): V S - Fc V = P (Q = 0)
    Aw = np.eye(1) - Lw @ H @ V
    Psi_x = solve_sylvester(Aw, -Fc, -Lw @ H)
    Bw = Lw + Psi_x @ L0
    x1, x2, w = sp.symbols("x1 x2 w")
    xs = sp.Matrix([x1, x2])
    f = list(sp.Matrix(F) * xs + sp.Matrix(P) * w)
    nl = NonlinearSystem(f, [x1], [x1, x2], [w])
    rng = np.random.default_rng(5)
    Y = rng.normal(size=(50, 1))
    ref = lin.run(Y)
    design = design_modular(nl, Fc, L0, Aw, Bw, order=3)
    bv = design.basis_v
    assert np.abs(design.Xi[:, bv.block[2].start:]).max() < 1e-12
    np.testing.assert_allclose(design.Xi[:, bv.block[1]], np.hstack([np.eye(2), V]), atol=1e-12)
    for c in ("linearizing", "original"):
        res = NonlinearModularObserver(design, coordinates=c).run(Y)
        np.testing.assert_allclose(res.estimate, ref.estimate, atol=1e-10)
        np.testing.assert_allclose(res.x_hat, ref.x_hat, atol=1e-10)


def test_interface_pickling_and_bad_input():
    sys = modular_example()
    obs = NonlinearModularObserver(sys, A0, B0, AW, BW, order=5)
    _X, _W, Y = sys.simulate([0.1], [0.05], 10)
    first = obs.run(Y)
    obs.reset()
    steps = np.array([obs.step(y) for y in Y])
    np.testing.assert_array_equal(steps, first.estimate)
    assert first.estimate[0, 0] == 0.0          # w^_0 from no data
    back = pickle.loads(pickle.dumps(obs))
    np.testing.assert_array_equal(back.run(Y).estimate, first.estimate)
    assert set(obs.gains) == {"A0", "B0", "Aw", "Bw"}
    assert list(first.to_pandas().columns) == ["w", "x_hat_0"]
    with pytest.raises(TypeError, match="either a ModularDesign"):
        NonlinearModularObserver(obs.design, A0)
    with pytest.raises(ValueError, match="coordinates"):
        NonlinearModularObserver(obs.design, coordinates="z")
    with pytest.raises(TypeError, match="A0 and Aw"):
        NonlinearModularObserver(sys)
    with pytest.raises(Exception, match="inputs"):
        obs.step([0.1], [1.0])


def test_refusals_name_the_problem():
    """An unstable A0 (1.5: the estimates grew to 2e57 with no error) or a
    marginal Aw (eigenvalue -1) is refused at design time; so is an order whose series
    would take minutes (25 on the paper's plant: 351 monomials, 51 s), with its size
    and the way out; order 0 is refused as before."""
    from setobs.analysis.modular import design_modular
    from setobs.examples import modular_example
    from setobs.exceptions import DesignError

    sys = modular_example()
    with pytest.raises(DesignError, match=r"A0 has spectral radius 1\.5"):
        design_modular(sys, 1.5, 1.0, 0.6, 1.0, order=5)
    with pytest.raises(DesignError, match="Aw has spectral radius 1 "):
        design_modular(sys, 0.4, 1.0, -1.0, 1.0, order=5)
    with pytest.raises(InvalidValueError, match=r"351 monomials.*max_terms = 250"):
        NonlinearModularObserver(sys, 0.4, 1.0, 0.6, 1.0, order=25)
    with pytest.raises(InvalidValueError, match="integer >= 1"):
        NonlinearModularObserver(sys, 0.4, 1.0, 0.6, 1.0, order=0)
    d = design_modular(sys, 0.4, 1.0, 0.6, 1.0, order=4, max_terms=15)  # C(6, 2) = 15
    assert d.order == 4
    with pytest.raises(InvalidValueError, match="21 monomials"):
        design_modular(sys, 0.4, 1.0, 0.6, 1.0, order=5, max_terms=15)
