"""Noise calibration: the LP optimum against a bisection with the exact SMFDO's own
consistency check, closed forms, the trade-off curve, bad input."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import setobs as so
from setobs.exceptions import ArgumentError, DimensionError, InvalidValueError
from setobs.setmembership import ModelInvalidatedWarning
from tests.datasets import HSM150, noisy_record


def _consistent(sys, Y, U, inc, radii, process_noise=None):
    """The exact SMFDO (whole history) finds a nonempty set at every step."""
    obs = so.SMFDO(sys, window=None, increment_set=inc, measurement_noise=radii,
                   process_noise=process_noise, on_inconsistent="skip", data_rtol=0.0,
                   max_skip_fraction=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelInvalidatedWarning)
        return obs.run(Y, U).consistent


def _bisect(pred, lo, hi, rel=1e-4):
    """Smallest ``a`` in ``[lo, hi]`` with ``pred(a)`` (monotone), to ``rel``."""
    assert pred(hi) and not pred(lo)
    while hi - lo > rel * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if pred(mid) else (mid, hi)
    return lo, hi


@pytest.mark.parametrize("case", [0, 1, pytest.param(2, marks=pytest.mark.slow)])
def test_scale_matches_bisection_with_the_exact_smfdo(case):
    """On short records of the paper example and of the servo motor (with input),
    the LP's smallest noise scale brackets the exact SMFDO's consistency threshold:
    inconsistent just below, consistent at the recommended bound."""
    rng = np.random.default_rng(case)
    if case < 2:
        sys, U, inc, shape = so.examples.chang2006(), None, np.array([0.2, 0.1]), [1.0, 2.0]
    else:
        sys = so.examples.servo_motor()
        U = 0.05 * np.ones((25, 1))
        inc, shape = np.array([0.01]), [1e-3]
    Y = noisy_record(sys, 25, rng, inc, 0.05 * np.asarray(shape), U)
    cal = so.calibrate_noise(sys, Y, U, increment=inc, shape=shape, holdout=0)
    radii = np.asarray(shape, float)
    lo, hi = _bisect(lambda a: _consistent(sys, Y, U, inc, a * radii), 0.0, 1.0)
    assert lo <= cal.scale * (1 + 1e-3) and cal.scale <= hi * (1 + 1e-3), (lo, hi, cal.scale)
    assert _consistent(sys, Y, U, inc, cal.radii)
    assert not _consistent(sys, Y, U, inc, 0.99 * cal.minimal)
    np.testing.assert_allclose(cal.minimal, cal.scale * radii)
    assert np.all(cal.radii > cal.minimal)


def test_closed_form_constant_disturbance_alternating_output():
    """x+ = x + d, y = x, |dd| = 0: y alternating 0, 1, 0, 1 fits a trajectory
    x_k = c + k d only within |v| >= 1/2 (best: d = 0, c = 1/2)."""
    sys = so.LinearSystem([[1.0]], [[1.0]], [[1.0]])
    Y = np.array([[0.0], [1.0], [0.0], [1.0], [0.0]])
    cal = so.calibrate_noise(sys, Y, increment=0.0)
    assert abs(cal.minimal[0] - 0.5) < 1e-9
    # a missing sample changes the answer: without y_1 and y_3 the data are constant
    Y2 = Y.copy()
    Y2[[1, 3]] = np.nan
    assert so.calibrate_noise(sys, Y2, increment=0.0).minimal[0] < 1e-9


def test_per_channel_and_process_noise():
    """Two independent channels (diagonal system): per-channel radii are each
    channel's own closed-form minimum; process noise lowers the needed bound."""
    sys = so.LinearSystem(np.eye(2), np.eye(2), np.eye(2))
    Y = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 3.0], [1.0, 0.0], [0.0, 3.0]])
    cal = so.calibrate_noise(sys, Y, increment=0.0, per_channel=True)
    # channel 0: alternating 0/1 -> 1/2; channel 1: 0, 0, 3, 0, 3 -> 3/2
    np.testing.assert_allclose(cal.minimal, [0.5, 1.5], atol=1e-9)
    assert cal.scale is None and cal.worst_step.shape == (2,)
    with_w = so.calibrate_noise(sys, Y, increment=0.0, per_channel=True, process_noise=0.25)
    assert np.all(with_w.minimal < cal.minimal - 0.1)


def test_tradeoff_curve_is_monotone_and_consistent_with_calibration():
    rng = np.random.default_rng(5)
    sys = so.examples.chang2006()
    Y = noisy_record(sys, 40, rng, np.array([0.3, 0.3]), 0.02)
    curve = so.noise_tradeoff(sys, Y, increment=[1.0, 1.0], betas=[0.01, 0.1, 1.0, 10.0])
    assert np.all(np.diff(curve.alpha) <= 1e-9)
    one = so.calibrate_noise(sys, Y, increment=[0.1, 0.1], holdout=0)
    assert abs(curve.alpha[1] - one.scale) <= 1e-7
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ax = curve.plot()
    assert ax.get_xscale() == "log" and len(ax.lines) == 1
    plt.close("all")


@pytest.mark.parametrize(("kwargs", "exc", "match"), [
    ({"increment": -1.0}, InvalidValueError, "nonnegative"),
    ({"increment": [1.0]}, DimensionError, "increment"),
    ({"increment": "big"}, TypeError, "per-channel radii"),
    ({"increment": 1.0, "shape": 0.0}, InvalidValueError, "shape radii must be positive"),
    ({"increment": 1.0, "shape": so.Box([0, 0], [1, 1])}, InvalidValueError, "centred at 0"),
])
def test_bad_input(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        so.calibrate_noise(so.examples.chang2006(), np.zeros((5, 2)), **kwargs)


def test_input_required_and_no_data():
    with pytest.raises(ArgumentError, match="U is required"):
        so.calibrate_noise(so.examples.servo_motor(), np.zeros((5, 1)), increment=1.0)
    with pytest.raises(InvalidValueError, match="no measured"):
        so.calibrate_noise(so.examples.chang2006(), np.full((5, 2), np.nan), increment=1.0)


@pytest.mark.skipif(HSM150 is None, reason="the HSM150 record is not available here")
def test_servo_motor_record_needs_about_one_encoder_count():
    """The first 2000 samples of the real record with |dd| <= 2 Mn: the needed
    position noise is within the sensor's quantisation (one encoder count,
    2 pi / 10 000 rad) but not zero (quantised data are not explained exactly),
    and the windowed SMFDO accepts the record with the recommended bound."""
    from scipy.io import loadmat

    m = loadmat(HSM150, squeeze_me=True)
    data = m["data"][:2000]
    sys = so.examples.servo_motor(float(m["J"]), float(m["B"]), float(m["Tvz"]))
    cal = so.calibrate_noise(sys, data[:, 2:3], data[:, 4:5], increment=2 * float(m["Mn"]))
    count = 2 * np.pi / 10_000
    assert 0.1 * count < cal.minimal[0] < count
    res = so.SMFDO(sys, window=10, increment_set=[2 * float(m["Mn"])],
                   measurement_noise=cal.radii).run(data[:, 2:3], data[:, 4:5])
    assert res.consistent
