"""Every public object pickles and deep-copies (Dask's process scheduler, notebooks).

LinearSystem, ConstrainedZonotope and Box failed on unpickle ("is
immutable"); SMFDO (a lambda inside), Diagnosis and the observers followed.
"""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import setobs as so
from setobs import observers as obs
from setobs.exceptions import DimensionError, EmptySetError, SolverError
from setobs.geometry import Box, ConstrainedZonotope
from setobs.geometry.zonotope import factor_polytope
from setobs.setmembership import ExistenceError, ModelInvalidatedError
from setobs.studies import ObserverSpec, Scenario, rng_for_run


def _roundtrips(obj):
    return [pickle.loads(pickle.dumps(obj)), copy.deepcopy(obj)]


def _records():
    sc = Scenario(system="chang2006", horizon=60, increment=1.0, x0_box=1.0)
    return sc.build_system(), sc.simulate(rng_for_run(0, 0))


def test_value_objects_round_trip_equal():
    sys_ = so.examples.chang2006()
    for s in _roundtrips(sys_):
        for name in ("Phi", "G", "Xi", "Gamma"):
            assert np.array_equal(getattr(s, name), getattr(sys_, name))
            assert not getattr(s, name).flags.writeable  # still immutable
        assert s.state_names == sys_.state_names and s.dt == sys_.dt
        with pytest.raises(AttributeError):
            s.Phi = None
    b = Box([0.0, -1.0], [1.0, np.inf])
    for c in _roundtrips(b):
        assert c == b and not c.lo.flags.writeable
    Z = ConstrainedZonotope.from_hpolytope([[1, 1], [1, -1], [-1, 1], [-1, -1]], [1, 1, 1, 1])
    Z.interval_hull()  # fills the LP cache (a HiGHS model, which does not pickle)
    for W in _roundtrips(Z):
        for name in ("G", "c", "A", "b", "h", "b_err", "c_err"):
            assert np.array_equal(getattr(W, name), getattr(Z, name))
        assert W.interval_hull() == Z.interval_hull()
    fp = factor_polytope(Z)
    for f in _roundtrips(fp):
        assert f.minimize(np.ones(Z.n_gen)).bound == fp.minimize(np.ones(Z.n_gen)).bound


def test_reports_and_results_round_trip():
    sys_, tr = _records()
    d = so.analysis.diagnose(sys_)
    for c in _roundtrips(d):
        assert repr(c) == repr(d)
    res = so.SMFDO(sys_, window=5).run(tr.Y)
    for c in _roundtrips(res):
        assert np.array_equal(c.lo, res.lo, equal_nan=True)
        assert list(c.status) == list(res.status)
    for c in _roundtrips(Z := so.ConstrainedZonotope.from_box([0, 0, 0], [1, 1, 1]).to_hrep()):
        assert np.array_equal(c.H, Z.H)
    specs = (Scenario(system="chang2006", horizon=5), ObserverSpec("S", "smfdo", {"window": 3}))
    for spec in specs:
        for c in _roundtrips(spec):
            assert c == spec


@pytest.mark.parametrize("window", [5, None])
def test_an_smfdo_pickled_mid_run_continues_identically(window):
    sys_, tr = _records()
    a = so.SMFDO(sys_, window=window)
    a.run(tr.Y[:30])
    copies = _roundtrips(a)
    rest = a.run(tr.Y[30:])
    for b in copies:
        other = b.run(tr.Y[30:])
        assert np.array_equal(other.lo, rest.lo, equal_nan=True)
        assert np.array_equal(other.hi, rest.hi, equal_nan=True)


def test_point_observers_round_trip_and_run_identically():
    sys_, tr = _records()
    for o in (obs.PIO(sys_), obs.HigherOrderObserver(sys_), obs.ModularObserver(sys_)):
        ref = o.run(tr.Y).estimate
        for c in _roundtrips(o):
            assert np.array_equal(c.run(tr.Y).estimate, ref, equal_nan=True)
    ex1 = so.examples.chen_gao_lin_example1()
    Y = np.random.default_rng(0).normal(size=(20, ex1.l))
    U = np.zeros((20, ex1.p))
    for o in (obs.VariantMBESO(ex1), obs.DelayedUIO(ex1)):
        ref = o.run(Y, U).estimate
        for c in _roundtrips(o):
            assert np.array_equal(c.run(Y, U).estimate, ref, equal_nan=True)
    ex4, ex5 = so.examples.chen_gao_lin_example4(), so.examples.chen_gao_lin_example5()
    for o, s in ((obs.EHGSO(ex4, 0.4), ex4), (obs.GESO(ex5), ex5)):
        Y = np.random.default_rng(1).normal(size=(20, s.l))
        ref = o.run(Y).estimate
        for c in _roundtrips(o):
            assert np.array_equal(c.run(Y).estimate, ref, equal_nan=True)


def test_exceptions_round_trip_with_their_attributes():
    rep = so.analysis.bounded_do_exists(so.examples.chang2006())
    cases = [SolverError("m", status="Unknown"), ModelInvalidatedError("m", 7),
             ExistenceError("m", rep), obs.DesignError("m", condition="c"),
             DimensionError("m"), EmptySetError("m")]
    for e in cases:
        for c in _roundtrips(e):
            assert type(c) is type(e) and str(c) == str(e)
            for attr in ("status", "step", "condition"):
                assert getattr(c, attr, None) == getattr(e, attr, None)
    assert _roundtrips(cases[2])[0].report.verdict == "yes"


def test_an_smfdo_with_a_callable_increment_set_pickles_when_the_callable_does():
    sys_, tr = _records()
    a = so.SMFDO(sys_, window=5, increment_set=_unit_box)
    b = pickle.loads(pickle.dumps(a))
    assert np.array_equal(a.run(tr.Y).lo, b.run(tr.Y).lo, equal_nan=True)


def _unit_box(k):
    return ConstrainedZonotope.from_box([-1.0, -1.0], [1.0, 1.0])
