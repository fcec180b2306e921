"""Names mean one thing: the renamed attributes, the gain dictionaries, the deprecation aliases."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import setobs as so
from setobs.examples import chang2006
from setobs.geometry import Box
from setobs.observers import (
    MBESO,
    PIO,
    DelayedUIO,
    DescriptorObserver,
    HigherOrderObserver,
    ModularObserver,
)
from setobs.setmembership import interval_center


def _designs():
    sys = chang2006()
    yield PIO(sys), sys
    yield HigherOrderObserver(sys), sys
    yield ModularObserver(sys), sys
    desc = so.LinearSystem(sys.Phi, sys.G[:, :1], np.vstack([sys.Xi, [[0.0, 1.0, 0.0]]]))
    yield DescriptorObserver(desc, np.ones((desc.l, 1))), desc
    yield MBESO(so.examples.chen_gao_lin_example4()), so.examples.chen_gao_lin_example4()
    yield DelayedUIO(so.examples.chen_gao_lin_example4()), so.examples.chen_gao_lin_example4()
    yield so.observers.EHGSO(so.examples.chen_gao_lin_example4(), 0.4), \
        so.examples.chen_gao_lin_example4()
    ex5 = so.examples.chen_gao_lin_example5()
    yield so.observers.GESO(ex5), ex5


def test_gains_hold_only_gains_on_the_measurements():
    """Every entry multiplies measurements: its column count is a multiple of ``l``
    (``(tau + 1) l`` for the delayed UIO's stacked window), and it is a matrix."""
    for obs, sys in _designs():
        assert obs.gains, type(obs).__name__
        for key, g in obs.gains.items():
            g = np.asarray(g)
            assert g.ndim == 2, (type(obs).__name__, key)
            assert g.shape[1] % sys.l == 0, (type(obs).__name__, key, g.shape)


def test_transition_is_the_error_dynamics_of_the_pio():
    """PIO error ``[e; eps]+ = [[Phi - P Xi, G], [-L Xi, I]] [e; eps]`` (Chang 2006),
    built here from the gains alone."""
    sys = chang2006()
    obs = PIO(sys)
    P, L = obs.gains["P"], obs.gains["L"]
    F = np.block([[sys.Phi - P @ sys.Xi, sys.G], [-L @ sys.Xi, np.eye(sys.q)]])
    np.testing.assert_allclose(obs.transition, F, atol=1e-12)


def test_radius_meanings_are_separate_names():
    b = Box([0.0, -1.0], [2.0, 3.0])
    np.testing.assert_array_equal(b.half_width, [1.0, 2.0])
    Z = so.ConstrainedZonotope.from_box([0.0, -1.0], [2.0, 3.0])
    est = interval_center(Z)
    assert est.worst_case_error == pytest.approx(2.0)  # max half-width, closed form
    assert Z.unbounded_radius == so.tolerances.UNBOUNDED_RADIUS


@pytest.mark.parametrize(("make", "old", "new"), [
    (lambda: Box([0.0], [2.0]), "radius", "half_width"),
    (lambda: interval_center(so.ConstrainedZonotope.from_box([0.0], [2.0])), "radius",
     "worst_case_error"),
    (lambda: so.SMFDO(chang2006(), window=3).run(np.zeros((6, 2))), "radius", "error_bound"),
    (lambda: PIO(chang2006()).run(np.zeros((4, 2))), "d_hat", "estimate"),
])
def test_old_names_warn_and_read_the_new_attribute(make, old, new):
    obj = make()
    with pytest.warns(DeprecationWarning, match=f"use .{new}"):
        value = getattr(obj, old)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_array_equal(value, getattr(obj, new))
