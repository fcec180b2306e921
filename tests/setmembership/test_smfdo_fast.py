"""The SMFDO's fast path against the reference path, LP by LP and step by step."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import setobs as so
from setobs import ConstrainedZonotope, LinearSystem
from setobs.lp.factor import FactorPolytope
from setobs.setmembership import ModelInvalidatedError, ModelInvalidatedWarning
from setobs.setmembership import smfdo as smfdo_module
from setobs.studies import Scenario, rng_for_run
from tests.oracles import noisy_record
from tests.setmembership.test_smfdo import random_runs, simulate

RTOL = 1e-8


def _close(a, b, rtol=RTOL):
    a, b = np.asarray(a), np.asarray(b)
    fin = np.isfinite(b)
    assert np.array_equal(np.isfinite(a), fin)
    assert np.array_equal(a[~fin], b[~fin])
    scale = 1.0 + np.abs(b[fin])
    assert np.all(np.abs(a[fin] - b[fin]) <= rtol * scale), np.max(np.abs(a[fin] - b[fin]) / scale)


def _three_state_with_input():
    """An unobservable mode, an input, and a rotated state basis (``P`` not a coordinate)."""
    Phi = np.array([[0.9, 0.0, 0.0], [0.3, 0.5, 0.0], [0.1, 0.0, 0.7]])
    sys = LinearSystem(Phi, [[1.0], [0.0], [0.3]], [[1.0, 0, 0], [0, 0, 1.0]],
                       [[1.0], [0.5], [0.0]])
    Q, _ = np.linalg.qr(np.random.default_rng(0).normal(size=(3, 3)))
    return sys.transformed(Q)


def _chang_runs(n_runs):
    sc = Scenario(system="chang2006", horizon=100, increment=1.0, x0_box=1.0)
    return sc, [sc.simulate(rng_for_run(0, r)) for r in range(n_runs)]


def _diamond_record():
    """Chang 2006 with increments in the diamond |dd_1| + |dd_2| <= 1 (a CZ with a
    constraint): the system, the set, 80 measurements and the true disturbances."""
    sys = so.examples.chang2006()
    diamond = ConstrainedZonotope.from_hpolytope(
        [[1, 1], [1, -1], [-1, 1], [-1, -1]], [1, 1, 1, 1])
    rng = np.random.default_rng(4)
    d, Ds = np.array([0.5, -1.0]), []
    for _ in range(80):
        Ds.append(d.copy())
        v = rng.uniform(-1, 1, 2)
        d = d + v / max(1.0, np.abs(v).sum())
    return sys, diamond, list(sys.simulate(np.array(Ds))[0]), Ds


def _lp_instances(obs, Y, U=None):
    """Run ``obs`` and yield every fast-path step's (model, b, h)."""
    for j, y in enumerate(Y):
        before = obs.stats["fast"]
        obs.step(y, None if U is None else U[j])
        if obs.stats["fast"] > before:
            model, _, b, h = obs.fast_path_instance
            yield model, b, h


def test_fast_lps_equal_highs_on_10000_real_smfdo_instances():
    """Every LP of the fast path on real SMFDO steps equals the HiGHS reference to 1e-8."""
    sc, trs = _chang_runs(9)
    sys = sc.build_system()
    cases = [(so.SMFDO(sys, window=10, increment_set=sc.increment_set(2),
                       initial_state_set=sc.initial_state_set(3)), tr.Y, None) for tr in trs]
    s3 = _three_state_with_input()
    rng = np.random.default_rng(1)
    U = rng.normal(size=(300, 1))
    Y, _ = simulate(s3, 300, rng, rng.normal(size=3), [0.5], 0.3, U)
    X0 = ConstrainedZonotope.from_box(-5 * np.ones(3), 5 * np.ones(3))
    cases.append((so.SMFDO(s3, window=4, increment_set=[0.3], initial_state_set=X0,
                           initial_disturbance_set=ConstrainedZonotope.from_box([-3.0], [3.0])),
                  Y, U))
    n_lp = 0
    for obs, Y, U in cases:
        for model, b, h in _lp_instances(obs, Y, U):
            bounds, ok = model.lp.minimize_all(b, h)
            assert ok.all()
            fp = FactorPolytope(model.A, b, h, unbounded_radius=model.unbounded_radius)
            for i, w in enumerate(model.lp.W):
                ref = fp.minimize(w).bound
                if np.isinf(ref):
                    assert bounds[i] == ref
                else:
                    assert abs(bounds[i] - ref) <= RTOL * (1 + abs(ref)), (bounds[i], ref)
                n_lp += 1
    assert n_lp >= 10_000


@pytest.mark.parametrize("window", [3, 10])
def test_fast_equals_reference_on_the_paper_example(window):
    sc, trs = _chang_runs(3)
    sys = sc.build_system()
    kw = dict(window=window, increment_set=sc.increment_set(2),
              initial_state_set=sc.initial_state_set(3),
              restart="polytope")  # (restart="auto" probes on the fast path only)
    for tr in trs:
        fast = so.SMFDO(sys, **kw)
        rf, rr = fast.run(tr.Y), so.SMFDO(sys, fast=False, **kw).run(tr.Y)
        _close(rf.lo, rr.lo)
        _close(rf.hi, rr.hi)
        assert rf.violations(tr.D) == 0
        assert fast.stats["fast"] == 100 and fast.stats["reference"] == 0
        assert fast.stats["fallback"] == 0


def test_fast_equals_reference_with_inputs_rotated_basis_and_constrained_increments():
    rng = np.random.default_rng(3)
    s3 = _three_state_with_input()
    U = rng.normal(size=(120, 1))
    Y, D = simulate(s3, 120, rng, rng.normal(size=3), [0.5], 0.3, U)
    # bounded initial sets: with free factors, the rotated basis leaves rounding-level
    # (1e-17) coefficients on them and both paths agree on useless bounds (see the note
    # in the fast-path docs)
    X0 = ConstrainedZonotope.from_box(-5 * np.ones(3), 5 * np.ones(3))
    D0 = ConstrainedZonotope.from_box([-3.0], [3.0])
    for kw in (dict(window=4, increment_set=[0.3], initial_state_set=X0,
                    initial_disturbance_set=D0),
               dict(window=6, increment_set=[0.3], initial_state_set=X0,
                    initial_disturbance_set=D0)):
        fast = so.SMFDO(s3, **kw)
        assert not fast.hull_from_state  # the P Z hull has its own LPs
        rf, rr = fast.run(Y, U), so.SMFDO(s3, fast=False, **kw).run(Y, U)
        _close(rf.lo, rr.lo)
        _close(rf.hi, rr.hi)
        assert rf.violations(D) == 0
        assert fast.stats["fast"] >= 110
    # Chang 2006 with the diamond |dd_1| + |dd_2| <= 1 (a CZ with a constraint)
    sys, diamond, Ys, Ds = _diamond_record()
    kw = dict(window=5, increment_set=diamond)
    fast = so.SMFDO(sys, keep_sets=True, **kw)
    rf = fast.run(np.array(Ys))
    # The windowed recursion with this increment set amplifies perturbations of
    # the restart boxes enormously (a margin of 0 instead of 1e-9 moves bounds by
    # O(0.1) after 60 steps; see test_windowed_recursion_amplifies_rounding), so
    # the two paths, which round differently, are compared step by step on the
    # same set instead of run against run: every fast step's hull equals HiGHS's
    # hull of the set it describes.
    for k in range(5, 80, 7):
        S = rf.steps[k].disturbance_set
        hull = ConstrainedZonotope(S.G, S.c, S.A, S.b, S.h).interval_hull()  # HiGHS path
        _close(rf.lo[k], hull.lo, 1e-8)
        _close(rf.hi[k], hull.hi, 1e-8)
    assert rf.violations(np.array(Ds)) == 0
    assert so.SMFDO(sys, fast=False, **kw).run(np.array(Ys)).violations(np.array(Ds)) == 0
    assert fast.stats["fast"] >= 75


def test_windowed_recursion_amplifies_rounding():
    """A finding pinned: the window's restart (eq. (24)) is not contractive.

    Chang 2006 with the diamond increment set and delta = 5: changing the outward
    margin of the restart boxes from 1e-9 to 0 moves the bounds by more than 1e-3
    within 80 steps. (Both runs stay sound.) Run-level comparisons of windowed
    results therefore need tolerances far above the rounding level.
    """
    sys, diamond, Ys, Ds = _diamond_record()
    Y = np.array(Ys)
    a = so.SMFDO(sys, window=5, increment_set=diamond).run(Y)
    b = so.SMFDO(sys, window=5, increment_set=diamond, margin=0.0).run(Y)
    fin = np.isfinite(a.lo) & np.isfinite(b.lo)
    assert np.abs(a.lo[fin] - b.lo[fin]).max() > 1e-3
    assert a.violations(np.array(Ds)) == 0 and b.violations(np.array(Ds)) == 0


@pytest.mark.usefixtures("exact_window_lps")
def test_random_systems_fast_equals_reference():
    for sys, step, Y, D, w in random_runs(np.random.default_rng(21), 6, 60):
        kw = dict(window=w, increment_set=np.full(sys.q, step))
        fast = so.SMFDO(sys, **kw)
        rf, rr = fast.run(Y), so.SMFDO(sys, fast=False, **kw).run(Y)
        _close(rf.lo, rr.lo)
        _close(rf.hi, rr.hi)
        assert rf.violations(D) == 0


def _noisy_random_plant():
    """A random 6-state plant with 4 outputs, process and measurement noise, 40 steps, and
    the SMFDO's keywords for window 10 with the box restart and state bounds."""
    rng = np.random.default_rng(3)
    n, l = 6, 4
    A = rng.normal(size=(n, n))
    A *= 0.95 / np.abs(np.linalg.eigvals(A)).max()
    B, C = rng.normal(size=(n, 1)) * 0.2, rng.normal(size=(l, n))
    rw, rv, N = 0.01, 0.05, 40
    U = np.sin(0.05 * np.arange(N))[:, None]
    X, Y = noisy_record(A, B, C, U, rw, rv, rng)
    sys = so.LinearSystem(A, np.zeros((n, 0)), C, B)
    kw = dict(window=10, restart="box", process_noise=rw, measurement_noise=rv,
              state_bounds=True, initial_state_set=so.Box(-2 * np.ones(n), 2 * np.ones(n)))
    return sys, kw, X, Y, U


@pytest.mark.usefixtures("exact_window_lps")
def test_noisy_window_lps_stay_on_the_fast_path():
    """A random 6-state plant with 4 outputs, process and measurement noise, window 10
    (the window LP is 40 x 106, most factors small noise boxes): the compiled
    simplex decides every step (the short-step dual simplex ran into its iteration
    limit on two thirds of them, which went to the reference path at 25x the cost),
    and its bands equal the reference path's (the set recursion with HiGHS)."""
    sys, kw, X, Y, U = _noisy_random_plant()
    obs = so.SMFDO(sys, **kw)
    rf = obs.run(Y, U)
    ref = so.SMFDO(sys, fast=False, **kw)
    rr = ref.run(Y, U)
    assert obs.stats["reference"] == 0
    assert np.all((X >= rf.state_lo) & (X <= rf.state_hi))
    _close(rf.state_lo, rr.state_lo)
    _close(rf.state_hi, rr.state_hi)
    # the simplex's work is counted: none on the reference path; on the fast path both
    # simplices ran (the primal for the hull's further bounds of each data set, the
    # dual at least on the first)
    primal, dual = obs.simplex_iterations
    assert primal > 0 and dual > 0
    assert ref.simplex_iterations == (0, 0)


def test_the_window_lps_early_stop_is_outward_and_small(monkeypatch):
    """The default window (its hull LPs stop within ``WINDOW_REL_GAP = 1e-3`` of the
    coordinate's previous width, ``setobs.setmembership._closed_form``) on the random
    6-state plant of the test above: its bands contain the reference path's (the set
    recursion with HiGHS, every LP to its optimum) and are at most 1 % wider, the truth
    is inside, and the simplex needs fewer iterations than with the LPs solved to their
    optimum."""
    from setobs.setmembership import _closed_form

    assert _closed_form.WINDOW_REL_GAP == 1e-3
    sys, kw, X, Y, U = _noisy_random_plant()
    obs = so.SMFDO(sys, **kw)
    rf = obs.run(Y, U)
    rr = so.SMFDO(sys, fast=False, **kw).run(Y, U)
    assert obs.stats["reference"] == 0
    assert np.all((X >= rf.state_lo) & (X <= rf.state_hi))
    tol = 1e-9 * (1 + np.abs(rr.state_lo))
    assert (rf.state_lo <= rr.state_lo + tol).all()
    assert (rf.state_hi >= rr.state_hi - 1e-9 * (1 + np.abs(rr.state_hi))).all()
    ratio = (rf.state_hi - rf.state_lo) / (rr.state_hi - rr.state_lo)
    assert ratio.max() <= 1.01
    monkeypatch.setattr(_closed_form, "WINDOW_REL_GAP", 0.0)
    exact = so.SMFDO(sys, **kw)
    exact.run(Y, U)
    assert sum(obs.simplex_iterations) < sum(exact.simplex_iterations)


def test_the_early_stops_excess_is_the_documented_one(monkeypatch):
    """The README and ``WINDOW_REL_GAP``'s comment once said "within 0.2 %" (twice the
    gap): carried by the restarts the excess over the stop off is larger. On the plant
    with the widest excess of ``benchmarks/results/early_stop.json`` (seed 28 of
    ``tests.datasets.random_stable_record``: 1.1 %) it is above 0.2 % and within the
    documented 1.1 % (after the first window; outward)."""
    from setobs.setmembership import _closed_form
    from tests.datasets import random_stable_record

    sys, Y, rw, rv = random_stable_record(28)
    n = sys.n
    kw = dict(window=10, restart="box", process_noise=rw, measurement_noise=rv,
              state_bounds=True, initial_state_set=so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n)))
    rf = so.SMFDO(sys, **kw).run(Y)
    monkeypatch.setattr(_closed_form, "WINDOW_REL_GAP", 0.0)
    r0 = so.SMFDO(sys, **kw).run(Y)
    w1, w0 = (rf.state_hi - rf.state_lo)[10:], (r0.state_hi - r0.state_lo)[10:]
    excess = (w1 - w0) / w0
    assert excess.min() >= -1e-9
    assert 2e-3 < excess.max() <= 0.011
    # and the documentation does not claim twice the gap: the guide defers to the
    # performance page, which shows early_stop.json's figures
    from pathlib import Path

    root = Path(__file__).parents[2]
    pages = [root / "README.md", *sorted((root / "docs" / "guide").glob("*.md"))]
    text = " ".join(" ".join(p.read_text().split()) for p in pages)
    assert "to within 0.2 %" not in text
    assert "`early_stop`" in (root / "docs" / "guide" / "state_estimation.md").read_text()
    # (the constant's comment cites the results file instead of repeating its figures)
    comment = Path(_closed_form.__file__).read_text()
    assert "early_stop.json" in comment and "1.1 %" not in comment


def _with_outlier():
    sc, trs = _chang_runs(1)
    Y = trs[0].Y.copy()
    Y[40] += 50.0
    return sc, Y


def test_outlier_raises_at_the_same_step_on_both_paths():
    sc, Y = _with_outlier()
    sys = sc.build_system()
    for fast in (True, False):
        obs = so.SMFDO(sys, window=10, fast=fast)
        with pytest.raises(ModelInvalidatedError) as err:
            obs.run(Y)
        assert err.value.step == 40


def test_outlier_reset_goes_through_the_reference_path_and_agrees():
    sc, Y = _with_outlier()
    sys = sc.build_system()
    out, msgs = {}, {}
    for fast in (True, False):
        obs = so.SMFDO(sys, window=10, on_inconsistent="reset", fast=fast)
        with warnings.catch_warnings(record=True) as rec:
            warnings.simplefilter("always")
            out[fast] = obs.run(Y)
        msgs[fast] = [str(w.message) for w in rec
                      if issubclass(w.category, ModelInvalidatedWarning)]
        assert len(msgs[fast]) == 1 and "first at k=40" in msgs[fast][0]
        if fast:
            # after the reset the window restarts from the reset set (reference path)
            # until it is full again, then the fast path resumes
            assert obs.stats["reference"] >= 10 and obs.stats["fast"] >= 40
    assert msgs[True] == msgs[False]  # the same resets at the same steps
    assert np.array_equal(out[True].status, out[False].status)
    assert list(out[True].status[[40, 42]]) == ["reset", "reset"]
    # The two paths bound their rounding differently (closed form vs set operations)
    # and the windowed recursion amplifies such differences (see
    # test_windowed_recursion_amplifies_rounding): 1e-7 after two resets.
    _close(out[True].lo, out[False].lo, 1e-7)
    _close(out[True].hi, out[False].hi, 1e-7)


def test_time_varying_increment_set_uses_the_reference_path():
    sc, trs = _chang_runs(1)
    sys = sc.build_system()
    box = ConstrainedZonotope.from_box(-np.ones(2), np.ones(2))
    obs = so.SMFDO(sys, window=5, increment_set=lambda k: box)
    r1 = obs.run(trs[0].Y)
    assert (obs.stats["fast"], obs.stats["reference"], obs.stats["fallback"]) == (0, 100, 0)
    r2 = so.SMFDO(sys, window=5, restart="box").run(trs[0].Y)  # (callables: the box)
    _close(r1.lo, r2.lo)
    _close(r1.hi, r2.hi)


def test_keep_sets_on_the_fast_path():
    sc, trs = _chang_runs(1)
    sys = sc.build_system()
    obs = so.SMFDO(sys, window=10, increment_set=sc.increment_set(2),
                   initial_state_set=sc.initial_state_set(3), keep_sets=True)
    res = obs.run(trs[0].Y[:40])
    assert obs.stats["fast"] == 40
    for k in (5, 20, 39):
        S = res.steps[k].disturbance_set
        hull = ConstrainedZonotope(S.G, S.c, S.A, S.b, S.h).interval_hull()  # HiGHS path
        _close(res.lo[k], hull.lo, 1e-8)
        _close(res.hi[k], hull.hi, 1e-8)
        assert S.contains(trs[0].D[k])


def test_window_structures_are_shared_between_instances():
    sc, trs = _chang_runs(2)
    sys = sc.build_system()
    kw = dict(window=7, increment_set=sc.increment_set(2),
              initial_state_set=sc.initial_state_set(3))
    so.SMFDO(sys, **kw).run(trs[0].Y)
    n_models = len(smfdo_module.MODEL_CACHE)
    obs = so.SMFDO(sys, **kw)
    obs.run(trs[1].Y)
    assert len(smfdo_module.MODEL_CACHE) == n_models
    assert obs.stats["fast"] == 100
