"""python-control in and out, keyword constructors, names in reports."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.signal import cont2discrete

import setobs as so
from setobs import LinearSystem
from setobs.exceptions import ArgumentError, DimensionError, InvalidValueError
from tests.printed import has_number

control = pytest.importorskip("control")

J, Bf, TS = 1.2e-4, 7.03e-5, 1e-3
A_C = np.array([[0.0, 1.0], [0.0, -Bf / J]])
B_C = np.array([[0.0, 0.0], [1.0 / J, -1.0 / J]])  # inputs: tau, tau_L


def _motor_ss(dt=0):
    return control.ss(A_C, B_C, [[1.0, 0.0]], [[0.0, 0.0]], dt, inputs=["tau", "tau_L"],
                      outputs=["theta"], states=["theta", "omega"])


def test_continuous_statespace_is_discretised_with_a_zero_order_hold():
    """Against scipy's cont2discrete (ZOH) of the same model; names travel."""
    sys = LinearSystem.from_statespace(_motor_ss(), disturbance_inputs=["tau_L"], dt=TS)
    Ad, Bd, *_ = cont2discrete((A_C, B_C, np.eye(2), np.zeros((2, 2))), TS, method="zoh")
    np.testing.assert_allclose(sys.Phi, Ad, rtol=1e-12)
    np.testing.assert_allclose(sys.Gamma, Bd[:, :1], rtol=1e-12)
    np.testing.assert_allclose(sys.G, Bd[:, 1:], rtol=1e-12)
    assert (sys.input_names, sys.disturbance_names) == (("tau",), ("tau_L",))
    assert sys.state_names == ("theta", "omega") and sys.output_names == ("theta",)
    assert sys.dt == TS
    # the library's own servo-motor example is the same model
    ex = so.examples.servo_motor()
    np.testing.assert_allclose(sys.Phi, ex.Phi, rtol=1e-12)
    np.testing.assert_allclose(sys.G, ex.G, rtol=1e-12)


def test_discrete_statespace_keeps_feedthrough_and_round_trips():
    rng = np.random.default_rng(0)
    A, B = 0.5 * rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
    C, D = rng.normal(size=(2, 3)), np.hstack([rng.normal(size=(2, 2)), np.zeros((2, 1))])
    ss = control.ss(A, B, C, D, 0.1, inputs=["u1", "u2", "w"], outputs=["p", "v"])
    sys = LinearSystem.from_statespace(ss, disturbance_inputs="w")
    np.testing.assert_array_equal(sys.Du, D[:, :2])
    assert sys.dt == 0.1 and sys.input_names == ("u1", "u2")
    back = sys.to_statespace()
    assert back.dt == 0.1 and list(back.input_labels) == ["u1", "u2", "w"]
    assert list(back.output_labels) == ["p", "v"]
    for name in "ABCD":
        np.testing.assert_array_equal(getattr(back, name), getattr(ss, name))
    # python-control's own simulation of the exported model = the model's equations
    N = 30
    U = rng.normal(size=(N, 2))
    Dd = np.cumsum(rng.normal(size=(N, 1)), axis=0)
    resp = control.forced_response(back, T=np.arange(N) * 0.1, U=np.hstack([U, Dd]).T)
    Y, _ = sys.simulate(Dd, U)
    np.testing.assert_allclose(resp.outputs.T, Y, rtol=1e-10, atol=1e-10)


def test_from_matrices_both_ways_of_stating_the_disturbance():
    A, B, C = [[1.0, 0.1], [0.0, 1.0]], [[0.0, 0.0], [0.1, -0.1]], [[1.0, 0.0]]
    a = LinearSystem.from_matrices(A=A, B=B, C=C, disturbance_inputs=[1],
                                   input_names=["u", "load"])
    b = LinearSystem.from_matrices(A=A, B=[[0.0], [0.1]], C=C, G=[[0.0], [-0.1]])
    for name in ("Phi", "G", "Xi", "Gamma"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert a.disturbance_names == ("load",) and a.input_names == ("u",)
    c = LinearSystem.from_matrices(A=A_C, B=B_C, C=[[1.0, 0.0]], disturbance_inputs=1,
                                   continuous=True, dt=TS)
    np.testing.assert_allclose(c.Phi, so.examples.servo_motor().Phi, rtol=1e-12)


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({}, ArgumentError, "state which inputs are disturbances"),
    ({"G": [[1.0], [0.0]], "disturbance_inputs": [0]}, ArgumentError,
     "either G or disturbance_inputs"),
    ({"disturbance_inputs": ["load"]}, InvalidValueError, "no input named 'load'"),
    ({"disturbance_inputs": [0], "D": [[1.0, 0.0]]}, InvalidValueError,
     "D columns of the disturbance"),
    ({"disturbance_inputs": [0], "continuous": True}, ArgumentError,
     "needs the sampling time dt"),
    ({"disturbance_inputs": [2]}, DimensionError, "index 2 is out of range"),
])
def test_from_matrices_bad_input(kwargs, error, match):
    with pytest.raises(error, match=match):
        LinearSystem.from_matrices(A=np.eye(2), B=np.ones((2, 2)), C=[[1.0, 0.0]], **kwargs)


def test_from_matrices_is_keyword_only():
    with pytest.raises(TypeError):
        LinearSystem.from_matrices(np.eye(2), np.ones((2, 1)), [[1.0, 0.0]])


def test_statespace_accepted_wherever_a_system_is_taken():
    """With disturbance_inputs stated: diagnose, the SMFDO and the observers give the
    same results as on the converted LinearSystem; without it a clear TypeError."""
    ss = _motor_ss()
    sys = LinearSystem.from_statespace(ss, ["tau_L"], dt=TS)
    dss = control.c2d(ss, TS)
    rep = so.analysis.diagnose(dss, disturbance_inputs=["tau_L"])
    assert rep.existing == so.analysis.diagnose(sys).existing
    rng = np.random.default_rng(1)
    Y, U = np.cumsum(rng.normal(size=(20, 1)), axis=0) * 1e-3, rng.normal(size=(20, 1)) * 0.01
    r1 = so.SMFDO(dss, increment_set=[0.1], measurement_noise=1e-3,
                  disturbance_inputs=[1]).run(Y, U)
    r2 = so.SMFDO(sys, increment_set=[0.1], measurement_noise=1e-3).run(Y, U)
    np.testing.assert_allclose(r1.lo, r2.lo, rtol=1e-9, atol=1e-12)
    p1 = so.observers.PIO(dss, disturbance_inputs="tau_L").run(Y, U).estimate
    np.testing.assert_allclose(p1, so.observers.PIO(sys).run(Y, U).estimate, rtol=1e-9)
    with pytest.raises(TypeError, match=r"say which of its inputs are disturbances"):
        so.analysis.diagnose(ss)
    with pytest.raises(ArgumentError, match=r"continuous-time: give the sampling time.*dt=Ts"):
        so.analysis.diagnose(ss, disturbance_inputs=[1])
    with pytest.raises(TypeError, match="already a LinearSystem"):
        so.analysis.diagnose(sys, disturbance_inputs=[0])
    with pytest.raises(InvalidValueError, match="differs from the model's sampling time"):
        LinearSystem.from_statespace(dss, [1], dt=0.5)


def test_signal_names_in_the_diagnosis():
    sys = LinearSystem.from_statespace(_motor_ss(), ["tau_L"], dt=TS)
    text = repr(so.analysis.diagnose(sys))
    assert "disturbances (tau_L); outputs (theta); inputs (tau)" in text
    assert has_number(text, 0.001, rtol=1e-9, after="sampling time")
    assert "signals" not in repr(so.analysis.diagnose(so.examples.chang2006()))


def test_positional_constructor_warns_loudly_in_its_docstring():
    assert "second** matrix" in LinearSystem.__doc__
    assert "from_matrices" in LinearSystem.__doc__


def test_simulate_against_scipy_dlsim():
    from scipy.signal import dlsim

    sys = so.examples.servo_motor()
    rng = np.random.default_rng(5)
    N = 50
    D, U = rng.normal(size=(N, sys.q)), rng.normal(size=(N, sys.p))
    x0 = np.array([0.1, -0.2])
    Y, X = sys.simulate(D, U, x0=x0)
    # scipy: inputs [u, d] through B = [Gamma, G], D = [Du, 0]
    B = np.hstack([sys.Gamma, sys.G])
    Dm = np.hstack([sys.Du, np.zeros((sys.l, sys.q))])
    _, y_ref, x_ref = dlsim((sys.Phi, B, sys.Xi, Dm, 1.0), np.hstack([U, D]), x0=x0)
    np.testing.assert_allclose(Y, y_ref, rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(X, x_ref, rtol=1e-12, atol=1e-14)
    with pytest.raises(so.ArgumentError, match="U is required"):
        sys.simulate(D)


def test_augmented_order_two_propagates_x_d_and_the_increment():
    """``z = [x; d; Delta d]``: one step of ``A z + Gamma u + E w`` against the plant
    ``x+ = Phi x + G d + Gamma u``, ``d+ = d + Delta d``, ``Delta d+ = Delta d + w``."""
    rng = np.random.default_rng(3)
    sys = so.LinearSystem(rng.normal(size=(3, 3)), rng.normal(size=(3, 2)),
                          rng.normal(size=(2, 3)), Gamma=rng.normal(size=(3, 1)))
    aug = sys.augmented(order=2)
    x, d, dd, u, w = (rng.normal(size=k) for k in (3, 2, 2, 1, 2))
    z1 = aug.A @ np.concatenate([x, d, dd]) + aug.Gamma @ u + aug.E @ w
    np.testing.assert_allclose(z1, np.concatenate([sys.Phi @ x + sys.G @ d + sys.Gamma @ u,
                                                   d + dd, dd + w]), atol=1e-12)
    np.testing.assert_allclose(aug.C @ np.concatenate([x, d, dd]), sys.Xi @ x, atol=1e-12)
    with pytest.raises(so.InvalidValueError, match="order"):
        sys.augmented(order=3)
