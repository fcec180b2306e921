"""The models in one place: ``NonlinearModel`` (the set estimators' model), its conversion
from and to the exosystem model, the one reader of symbols and expressions, and the old
import paths.

Oracles: the modular-observer paper's eq. (40) typed here; trajectories computed here in
closed form or by plain Python arithmetic; a simulator written in the test for the truth
inside the set observer's bands.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

import setobs as so

sp = pytest.importorskip("sympy")


def test_the_exosystem_example_is_eq_40_with_w_a_disturbance():
    x, w = sp.symbols("x w")
    model = so.NonlinearModel.from_exosystem(so.examples.modular_example())
    assert [str(s) for s in model.states] == ["x"] and [str(d) for d in model.disturbances] \
        == ["w"]
    f40 = (x - w) / (2 + x + (2 * x + 3) * w)
    h40 = 2 * x / (1 + x) + w / (1 + w)
    assert sp.simplify(model.f[0] - f40) == 0 and sp.simplify(model.h[0] - h40) == 0
    # and back: the same system (its maps evaluated at a point, by hand)
    back = model.to_exosystem()
    xv, wv = 0.3, 0.2
    assert back.f_num([xv], [wv])[0] == pytest.approx((xv - wv) / (2 + xv + (2 * xv + 3) * wv))
    assert back.s_num([wv])[0] == pytest.approx(wv)


def test_a_moving_exosystem_becomes_states():
    """``w+ = 0.5 w``: ``w`` is a state of the model with that dynamics, no disturbance."""
    x, w = sp.symbols("x w")
    ex = so.NonlinearSystem([0.5 * x + w], [x], [x], [w], s=[0.5 * w])
    model = so.NonlinearModel.from_exosystem(ex)
    assert model.n == 2 and model.q == 0 and model.state_names == ("x", "w")
    f, h = model.functions()
    z = np.array([1.0, 2.0])
    for _ in range(5):  # closed form: w_k = 2 / 2^k, x_(k+1) = x_k / 2 + w_k
        z = f(z)
    xk, wk = 1.0, 2.0
    for _ in range(5):
        xk, wk = 0.5 * xk + wk, 0.5 * wk
    assert z == pytest.approx([xk, wk], rel=1e-15) and h(z) == pytest.approx([xk])
    with pytest.raises(so.ArgumentError, match="0 disturbances"):
        model.to_exosystem()


def test_the_reader_takes_names_strings_callables_and_refuses_the_rest():
    m = so.NonlinearModel(lambda x, u, d: [x[0] * u[0] + d[0]], "sin(x)", "x", ["u"], ["d"])
    assert (m.n, m.p, m.q, m.l) == (1, 1, 1, 1)
    f, h = m.functions()
    assert f([2.0], [3.0], [0.5])[0] == pytest.approx(6.5)
    assert h([0.5], [3.0], [0.5])[0] == pytest.approx(math.sin(0.5))
    with pytest.raises(so.ArgumentError, match="not among the states"):
        so.NonlinearModel(["x + y"], ["x"], ["x"])
    with pytest.raises(so.DimensionError, match="f must have 2 components"):
        so.NonlinearModel(["x"], ["x"], ["x", "v"])
    with pytest.raises(so.ArgumentError, match="distinct"):
        so.NonlinearModel(["x"], ["x"], ["x"], ["x"])
    with pytest.raises(so.ArgumentError, match="sympy symbols or their names"):
        so.NonlinearModel(["x"], ["x"], [1.5])
    with pytest.raises(so.ArgumentError, match="cannot read"):
        so.NonlinearModel(["x +* 2"], ["x"], ["x"])
    assert pickle.loads(pickle.dumps(m)).f == m.f


def test_the_set_observer_takes_the_model_and_holds_the_truth():
    """The oscillator of the README, given as a model and as raw maps: both hold the
    truth of a simulator written here (the measurement noise on its corners)."""
    f = ["x1 + 0.1 * x2", "x2 + 0.1 * (-x1 + 0.5 * (1 - x1**2) * x2)"]
    model = so.NonlinearModel(f, ["x1"], ["x1", "x2"], dt=0.1)
    kw = dict(process_noise=1e-3, measurement_noise=1e-2,
              initial_state_set=so.Box([0.9, -0.1], [1.1, 0.1]))
    z, X, Y = np.array([1.0, 0.0]), [], []
    for k in range(25):
        X.append(z.copy())
        Y.append([z[0] + 0.01 * (-1.0) ** k])
        z = np.array([z[0] + 0.1 * z[1], z[1] + 0.1 * (-z[0] + 0.5 * (1 - z[0] ** 2) * z[1])])
    X = np.array(X)
    for obs in (so.NonlinearSetObserver(model, **kw),
                so.NonlinearSetObserver(f, ["x1"], ["x1", "x2"], **kw)):
        res = obs.run(np.array(Y))
        assert np.all((res.state_lo <= X) & (X <= res.state_hi))
        assert np.all(res.state_hi[-1] - res.state_lo[-1] < 0.2)
    assert so.NonlinearSetObserver(model, **kw).run(np.array(Y)).time[1] == pytest.approx(0.1)
    with pytest.raises(so.ArgumentError, match="from the model"):
        so.NonlinearSetObserver(model, ["x1"], **kw)
    with pytest.raises(so.ArgumentError, match="needs a NonlinearModel"):
        so.NonlinearSetObserver(f, **kw)


def test_the_old_paths_are_the_new_objects():
    import setobs.interval
    import setobs.nonlinear
    import setobs.systems

    assert setobs.systems.LinearSystem is so.models.LinearSystem is so.LinearSystem
    assert setobs.systems.AugmentedSystem is so.models.AugmentedSystem
    assert setobs.nonlinear.NonlinearSystem is so.models.NonlinearSystem
    assert setobs.interval.interval_function is so.models.interval_function
