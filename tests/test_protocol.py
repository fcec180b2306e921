"""One protocol for every estimator: ``reset()``, ``step(y, u=None)``, ``run(Y, U=None)``
with ``U[k]`` going with ``Y[k]`` (the input applied at the time of the measurement), ``run``
always from ``reset()``, ``continue_run`` going on from the current step.

One campaign loop runs over the point observers, the SMFDO (windowed and exact) and the
nonlinear set observer on a servo motor with a known input, in this test's own simulation
(``x+ = Phi x + Gamma u + G d``, ``y = Xi x``). Oracles: the truth of that simulation (a
set estimator's band holds the disturbance at every step, a point observer ends at the
constant load torque: an input taken one step off would bias both) and the protocol's
own identities (``run`` equals ``reset`` and a ``step`` loop; ``run`` twice is the same;
``run`` of a first part then ``continue_run`` of the rest is ``run`` of the whole).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import setobs as so

N, SPLIT, LOAD = 80, 37, 0.04


def record():
    sys = so.examples.servo_motor()
    rng = np.random.default_rng(3)
    U = 0.05 + 0.02 * rng.uniform(-1, 1, size=(N, 1))
    x, Y = np.array([0.1, -0.2]), []
    for k in range(N):
        Y.append(sys.Xi @ x)
        x = sys.Phi @ x + sys.Gamma @ U[k] + sys.G[:, 0] * LOAD
    return sys, np.array(Y), U, np.full((N, 1), LOAD)


def linear_as_nonlinear(sys):
    """The same plant as a NonlinearModel (states th, om; input tau; disturbance tl)."""
    def row(M, names):
        return " + ".join(f"({float(v)!r})*{n}" for v, n in zip(M, names, strict=True) if v)

    f = [" + ".join(filter(None, (row(sys.Phi[i], ["th", "om"]), row(sys.Gamma[i], ["tau"]),
                                  row(sys.G[i], ["tl"])))) for i in range(2)]
    h = [row(sys.Xi[0], ["th", "om"])]
    return so.NonlinearModel(f, h, ["th", "om"], ["tau"], ["tl"])


def estimators(sys):
    O = so.observers
    noise = dict(increment_set=[1e-4], measurement_noise=1e-5)
    return {
        "PIO": (lambda: O.PIO(sys), "point"),
        "higher-order": (lambda: O.HigherOrderObserver(sys), "point"),
        # (its default design converges slowly on this plant: the protocol only)
        "modular": (lambda: O.ModularObserver(sys), "protocol"),
        # (an invariant zero near -1 on this plant: its estimate still alternates by
        # +-1.2 after 80 steps, decaying slowly; the protocol only)
        "delayed UIO": (lambda: O.DelayedUIO(sys), "protocol"),
        "SMFDO window 10": (lambda: so.SMFDO(sys, window=10, **noise), "set"),
        "SMFDO exact": (lambda: so.SMFDO(sys, window=None, **noise), "set"),
        "nonlinear set observer": (lambda: so.NonlinearSetObserver(
            linear_as_nonlinear(sys), process_noise=None, measurement_noise=1e-5,
            increment_set=1e-4, initial_state_set=so.Box([-1.0, -2.0], [1.0, 2.0]),
            initial_disturbance_set=so.Box([-1.0], [1.0])), "set"),
    }


def estimate_of(out) -> np.ndarray:
    return np.asarray(getattr(out, "estimate", out), dtype=float)


@pytest.mark.parametrize("name", list(estimators(so.examples.servo_motor())))
def test_one_campaign_loop_over_every_estimator(name):
    sys, Y, U, D = record()
    make, kind = estimators(sys)[name]
    est = make()
    res = est.run(Y, U)
    # the truth: inside every band, or the point estimate at the constant load
    if kind == "set":
        assert np.all((res.lo[5:] <= D[5:]) & (D[5:] <= res.hi[5:]))
        assert float(np.max(res.hi[-1] - res.lo[-1])) < 0.05
    elif kind == "point":
        assert abs(res.estimate[-1, 0] - LOAD) < 1e-3 * (1 + LOAD), res.estimate[-1]
    # run is reset and a step loop, from any state
    est.run(Y[:SPLIT], U[:SPLIT])
    est.reset()
    stepped = np.array([estimate_of(est.step(Y[k], U[k])) for k in range(N)])
    np.testing.assert_allclose(stepped, res.estimate, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(est.run(Y, U).estimate, res.estimate, rtol=1e-12, atol=1e-12)
    # continue_run goes on where the first part stopped
    est.run(Y[:SPLIT], U[:SPLIT])
    rest = est.continue_run(Y[SPLIT:], U[SPLIT:])
    np.testing.assert_allclose(rest.estimate, res.estimate[SPLIT:], rtol=1e-12, atol=1e-12)
    # a system with inputs needs them at every step
    est.reset()
    with pytest.raises(so.ArgumentError, match="u is required"):
        est.step(Y[0])


def test_the_old_verbs_warn_and_keep_their_meaning():
    sys, Y, U, _ = record()
    make, _ = estimators(sys)["SMFDO window 10"]
    ref = make().run(Y, U)
    obs = make()
    with pytest.warns(DeprecationWarning, match="reset"):
        obs.reset_state()
    with pytest.warns(DeprecationWarning, match="step"):
        first = obs.update(Y[0])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        # update(y_k, u_(k-1)): the input before the measurement
        old = [first] + [obs.update(Y[k], U[k - 1]) for k in range(1, N)]
    np.testing.assert_allclose([s.estimate for s in old], ref.estimate, rtol=1e-12)
    nl_make, _ = estimators(sys)["nonlinear set observer"]
    nl = nl_make()
    with pytest.warns(DeprecationWarning, match="step"):
        a = nl.update(Y[0], U[0])
    b = nl_make().step(Y[0], U[0])
    np.testing.assert_array_equal(a.state_lo, b.state_lo)


def test_a_feedthrough_is_taken_off_by_step_for_every_estimator():
    """``y = Xi x + Du u``: every estimator's ``step(y_k, u_k)`` takes ``Du u_k`` off the
    raw measurement itself (its ``run`` is that loop), so a step loop on the raw record
    reaches the load and keeps the truth in the bands; a point observer fed ``y`` with
    the feedthrough left in would be biased by ``Du u`` (about 0.5 * 0.05 here)."""
    base, _, U, D = record()
    Du = np.array([[0.5]])
    sys = so.LinearSystem(base.Phi, base.G, base.Xi, base.Gamma, Du=Du, dt=base.dt)
    x, Y = np.array([0.1, -0.2]), []
    for k in range(N):
        Y.append(sys.Xi @ x + Du @ U[k])
        x = sys.Phi @ x + sys.Gamma @ U[k] + sys.G[:, 0] * LOAD
    Y = np.array(Y)
    for name in ("PIO", "higher-order", "SMFDO window 10", "SMFDO exact"):
        make, kind = estimators(sys)[name]
        est = make()
        stepped = [est.step(Y[k], U[k]) for k in range(N)]
        np.testing.assert_allclose(np.array([estimate_of(s) for s in stepped]),
                                   make().run(Y, U).estimate, rtol=1e-12, atol=1e-12)
        if kind == "set":
            lo, hi = np.array([s.lo for s in stepped]), np.array([s.hi for s in stepped])
            assert np.all((lo[5:] <= D[5:]) & (D[5:] <= hi[5:])), name
        else:
            assert abs(estimate_of(stepped[-1])[0] - LOAD) < 1e-3 * (1 + LOAD), name
