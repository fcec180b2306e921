"""The SMFDO under threads, bad scaling, large data, solver trouble.

Every test here failed on the code before the hardening. Oracles are independent
of the code under test: the simulator of ``test_smfdo``, the exact rational LP of
``tests/oracles.py`` (original coordinates, Fractions), scipy's HiGHS.
"""

from __future__ import annotations

import importlib.util
import threading
import warnings
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest

import setobs as so
from setobs import ConstrainedZonotope, DimensionError, LinearSystem
from tests.oracles import exact_history_bounds, exact_lp_min
from tests.setmembership.test_smfdo import history_lp_bounds, simulate

REGRESSIONS = Path(__file__).resolve().parents[1] / "data" / "regressions"
#: The data's representation error the oracle grants each y (the SMFDO's default data_rtol).
DATA_RTOL = 2 * np.finfo(float).eps


def _float_bounds(lo, hi):
    return (np.array([-np.inf if v is None else float(v) for v in lo]),
            np.array([np.inf if v is None else float(v) for v in hi]))


def _assert_contains_exact(res_lo, res_hi, lo, hi):
    """Certified bounds contain the exact ones (compared in exact arithmetic)."""
    for a, b in zip(res_lo, lo, strict=True):
        if b is not None:
            assert Fraction(float(a)) <= b
    for a, b in zip(res_hi, hi, strict=True):
        if b is not None:
            assert Fraction(float(a)) >= b


# ------------------------------------------------------------------ 1. threads
def test_threads_running_smfdos_of_the_same_system_stay_sound_and_deterministic():
    sys_ = so.examples.chang2006()
    records = [simulate(sys_, 300, np.random.default_rng(s), np.zeros(3), [0.3, -0.2], 1.0)
               for s in range(4)]
    # alone, one after the other (the reference results)
    alone = [so.SMFDO(sys_, window=10).run(Y) for Y, _ in records]
    for _ in range(5):
        out: dict[int, object] = {}

        def work(i, out=out):
            try:
                out[i] = so.SMFDO(sys_, window=10).run(records[i][0])
            except Exception as exc:  # pragma: no cover - recorded and asserted below
                out[i] = exc

        threads = [threading.Thread(target=work, args=(i,)) for i in range(4)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        for i in range(4):
            assert not isinstance(out[i], Exception), out[i]
            assert out[i].violations(records[i][1]) == 0
            # bit for bit what the same record gives alone: nothing leaks between runs
            assert np.array_equal(out[i].lo, alone[i].lo, equal_nan=True)
            assert np.array_equal(out[i].hi, alone[i].hi, equal_nan=True)


def test_a_run_does_not_depend_on_the_runs_before_it():
    sys_ = so.examples.chang2006()
    Y1, _ = simulate(sys_, 150, np.random.default_rng(1), np.zeros(3), [0, 0], 1.0)
    Y2, _ = simulate(sys_, 150, np.random.default_rng(2), np.ones(3), [1, 0], 1.0)
    Y3, _ = simulate(sys_, 150, np.random.default_rng(3), -np.ones(3), [0, 1], 1.0)
    first = so.SMFDO(sys_, window=10).run(Y1)
    so.SMFDO(sys_, window=10).run(Y2)
    so.SMFDO(sys_, window=10).run(Y3)
    again = so.SMFDO(sys_, window=10).run(Y1)
    assert np.array_equal(first.lo, again.lo, equal_nan=True)
    assert np.array_equal(first.hi, again.hi, equal_nan=True)


# ------------------------------------------------------------------ 2. exact mode, scaling
def _load_exact_wide():
    spec = importlib.util.spec_from_file_location("exact_wide", REGRESSIONS / "exact_wide.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _exact_tol(lo, hi, Y):
    """1e-8 relative to the bounds, plus 1e-10 relative to the data (the rounding allowance)."""
    fin = np.concatenate([lo[np.isfinite(lo)], hi[np.isfinite(hi)]])
    return 1e-8 * (1.0 + np.abs(fin).max(initial=0.0)) + 1e-10 * np.abs(Y).max()


def test_exact_mode_on_a_badly_scaled_system_equals_the_exact_lp():
    m = _load_exact_wide()
    Y, D = m.simulate(8)
    sys_ = LinearSystem(m.Phi, m.G, m.Xi)
    runs = [so.SMFDO(sys_, window=None, increment_set=m.increment_radius, fast=fast).run(Y)
            for fast in (True, False)]
    for k in (3, 5):
        # The float simulator's data are consistent with the model only up to their
        # rounding: the oracle gives each y its representation error (DATA_RTOL).
        lo_x, hi_x = exact_history_bounds(m.Phi, m.G, m.Xi, Y, k, m.increment_radius,
                                          y_rtol=DATA_RTOL)
        lo, hi = _float_bounds(lo_x, hi_x)
        tol = _exact_tol(lo, hi, Y[:k + 1])
        for res in runs:  # fast path and reference path
            assert res.violations(D) == 0
            _assert_contains_exact(res.lo[k], res.hi[k], lo_x, hi_x)
            assert np.abs(res.lo[k] - lo).max() <= tol and np.abs(res.hi[k] - hi).max() <= tol
            # reported: d2 in [-1.36e7, 1.09e7] at k = 5 where it is ~[-0.358, -0.321]
            assert res.hi[k, 1] - res.lo[k, 1] < 0.04


def test_exact_mode_with_a_large_initial_state_equals_the_exact_lp():
    sys_ = so.examples.chang2006()
    rng = np.random.default_rng(5)
    Y, D = simulate(sys_, 9, rng, rng.normal(size=3) * 1e5, rng.uniform(-1, 1, 2), 1.0)
    k = 8
    lo_x, hi_x = exact_history_bounds(sys_.Phi, sys_.G, sys_.Xi, Y, k, np.ones(2),
                                      y_rtol=DATA_RTOL)
    lo, hi = _float_bounds(lo_x, hi_x)
    tol = _exact_tol(lo, hi, Y[:k + 1])
    for fast in (True, False):
        res = so.SMFDO(sys_, window=None, fast=fast).run(Y)
        assert res.violations(D) == 0
        _assert_contains_exact(res.lo[k], res.hi[k], lo_x, hi_x)
        # was 2.3 % wider than the LP
        assert np.abs(res.lo[k] - lo).max() <= tol and np.abs(res.hi[k] - hi).max() <= tol


# ------------------------------------------------------------------ 3. |y| near 1e15
@pytest.mark.parametrize("fast", [True, pytest.param(False, marks=pytest.mark.slow)])
def test_huge_measurements_widen_the_bands_instead_of_excluding_the_truth(fast):
    """x+ = 1.1 x + d, y = x: the state grows past 1e15, where one ulp exceeds d's effect.

    With the box restart (eq. (24), window 3) the band is at least the last
    measurements' ulps wide. The polytope restart carries 30 steps back, to
    measurements 1.1^30 = 17 times smaller, so it may be narrower than that (d moves
    by at most 1 per step): there only soundness is asserted."""
    sys_ = LinearSystem([[1.1]], [[1.0]], [[1.0]])
    Y, D = simulate(sys_, 420, np.random.default_rng(0), [1.0], [0.3], 1.0)
    assert np.abs(Y).max() > 1e16
    import warnings

    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always", so.SolverWarning)
        res = so.SMFDO(sys_, window=3, fast=fast, restart="box").run(Y)
        poly = so.SMFDO(sys_, window=3, fast=fast).run(Y)
    assert res.violations(D) == 0 and poly.violations(D) == 0
    # the bands widen with |y| eps, as they must (each y is known only to an ulp)
    big = np.abs(Y[:, 0]) > 1e15
    assert (res.hi[big, 0] - res.lo[big, 0] > 2 * DATA_RTOL * np.abs(Y[big, 0])).all()
    # Where an ulp of y approaches d's effect (|y| eps > 1e-2 of the increment
    # bound), HiGHS may call a thin set infeasible; its relaxed LP is then a counted
    # fallback, never an "ok": only there.
    near = np.abs(Y[:, 0]) * np.finfo(float).eps > 1e-2 * 1.0
    assert not (res.status == "fallback")[~near].any()


# ------------------------------------------------------------------ 4. tf2ss with 1e-16 entries
def _tf2ss_system():
    Phi = [[0.903186139, 1.665e-16], [-1.0, 2.776e-16]]
    return LinearSystem(Phi, [[1.0], [0.0]], [[-1.11122815, 0.42058229]], [[1.0], [0.0]])


def test_rounding_level_entries_do_not_make_the_fast_path_unbounded():
    sys_ = _tf2ss_system()
    rng = np.random.default_rng(1)
    U = rng.normal(size=(40, 1))
    Y, D = simulate(sys_, 40, rng, [0.0, 0.0], [0.2], 0.01, U)
    for window in (10, None):
        obs = so.SMFDO(sys_, window=window, increment_set=[0.01])
        rf = obs.run(Y, U)
        if window is not None:
            assert obs.stats["fast"] >= 38  # no silent hand-over either
        assert np.isfinite(rf.error_bound[2:]).all()  # was inf on every step
        assert rf.violations(D) == 0
    # exact mode against the exact LP
    k = 6
    lo_x, hi_x = exact_history_bounds(sys_.Phi, sys_.G, sys_.Xi, Y, k, [0.01], U=U,
                                      Gamma=sys_.Gamma, y_rtol=DATA_RTOL)
    _assert_contains_exact(rf.lo[k], rf.hi[k], lo_x, hi_x)
    lo, hi = _float_bounds(lo_x, hi_x)
    assert np.abs(rf.lo[k] - lo).max() < 1e-8 and np.abs(rf.hi[k] - hi).max() < 1e-8


# ------------------------------------------------------------------ 5. hull of a bounded 1-D set
def test_interval_hull_of_the_regression_set_is_finite_and_exact():
    z = np.load(REGRESSIONS / "hull_inf_set.npz")
    G, c, A, b, h = (z[k] for k in ("G", "c", "A", "b", "h"))
    box = ConstrainedZonotope(G, c, A, b, h).interval_hull()
    assert box.is_bounded  # was [-inf, inf]
    Af = [[Fraction(float(v)) for v in row] for row in A]
    bf = [Fraction(float(v)) for v in b]
    lo = [None if np.isinf(v) else -Fraction(float(v)) for v in h]
    hi = [None if np.isinf(v) else Fraction(float(v)) for v in h]
    w = [Fraction(float(v)) for v in G[0]]
    mn = exact_lp_min(w, Af, bf, lo, hi) + Fraction(float(c[0]))
    mx = -exact_lp_min([-v for v in w], Af, bf, lo, hi) + Fraction(float(c[0]))
    assert Fraction(box.lo[0]) <= mn and Fraction(box.hi[0]) >= mx
    assert float(mn) - box.lo[0] < 1e-10 and box.hi[0] - float(mx) < 1e-10


# ------------------------------------------------------------------ 7. window = mu_o - 1
@pytest.mark.parametrize("fast", [True, False])
def test_the_documented_minimum_window_gives_bounded_sets(fast):
    sys_ = LinearSystem(np.diag([0.5, -0.3]), [[1.0], [1.0]], [[1.0, 1.0]])
    Y, D = simulate(sys_, 60, np.random.default_rng(0), [0.0, 0.0], [0.2], 1.0)
    obs = so.SMFDO(sys_, window=2, fast=fast)
    assert obs.mu_o == 3
    res = obs.run(Y)
    assert np.isfinite(res.error_bound[2:]).all()  # was +-inf forever
    assert res.violations(D) == 0
    exact = so.SMFDO(sys_, window=None, fast=False).run(Y)
    # windowed contains exact (the reference engine's: see the next test), up to the
    # rounding allowances (which grow with the exact mode's depth): 1e-8 relative
    tol = 1e-8 * (1.0 + np.abs(np.nan_to_num(exact.lo, posinf=0, neginf=0)))
    assert (res.lo <= exact.lo + tol).all() and (res.hi >= exact.hi - tol).all()


@pytest.mark.xfail(strict=False, reason="known defect, machine-dependent: on some machines "
                   "exact mode's H-representation step (the first after the conversion, "
                   "k = 4; the set is flat, y has no noise) is 8e-4 wider than the exact "
                   "rational LP at k = 4 and 5 while its status says ok; fast=False is exact")
def test_exact_mode_on_the_minimum_window_plant_equals_the_rational_lp():
    sys_ = LinearSystem(np.diag([0.5, -0.3]), [[1.0], [1.0]], [[1.0, 1.0]])
    Y, _ = simulate(sys_, 60, np.random.default_rng(0), [0.0, 0.0], [0.2], 1.0)
    exact = so.SMFDO(sys_, window=None).run(Y[:8])
    for k in (4, 5):
        lo, hi = exact_history_bounds(sys_.Phi, sys_.G, sys_.Xi, Y, k, [1.0])
        assert abs(exact.lo[k, 0] - float(lo[0])) <= 1e-9 * (1 + abs(float(lo[0])))
        assert abs(exact.hi[k, 0] - float(hi[0])) <= 1e-9 * (1 + abs(float(hi[0])))


# ------------------------------------------------------------------ 8. run() continued
def test_a_record_split_in_two_runs_equals_the_whole_history_lp():
    sys_ = LinearSystem(so.examples.chang2006().Phi, so.examples.chang2006().G,
                        so.examples.chang2006().Xi, [[1.0], [0.0], [0.5]])
    rng = np.random.default_rng(0)
    U = rng.normal(size=(16, 1))
    Y, D = simulate(sys_, 16, rng, [0.1, 0.2, 0.3], [0.2, 0.1], 1.0, U)
    obs = so.SMFDO(sys_, window=None)
    obs.run(Y[:8], U[:8])          # N rows: the last one is u_7, needed at k = 8
    second = obs.continue_run(Y[8:], U[8:])
    assert second.violations(D[8:]) == 0
    for k in (8, 12):
        lo, hi = history_lp_bounds(sys_, Y, U, [None] * 3, [None] * 3, 1.0, k)
        np.testing.assert_allclose(second.lo[k - 8], lo, atol=1e-6)
        np.testing.assert_allclose(second.hi[k - 8], hi, atol=1e-6)


def test_continuing_without_the_pending_input_is_refused():
    sys_ = LinearSystem(so.examples.chang2006().Phi, so.examples.chang2006().G,
                        so.examples.chang2006().Xi, [[1.0], [0.0], [0.5]])
    obs = so.SMFDO(sys_, window=10)
    Y = np.zeros((6, 2))
    obs.run(Y[:3], np.zeros((2, 1)))  # N-1 rows: u_2 unknown
    with pytest.raises(DimensionError, match="input applied before the first step"):
        obs.continue_run(Y[3:], np.zeros((3, 1)))


# ------------------------------------------------------------------ 10. solver trouble
@pytest.mark.parametrize("fast", [True, False])
def test_consistent_data_never_abort_a_run(fast):
    """Increments of exactly +-1: HiGHS ended 'Unknown' on these sets (SolverError)."""
    sys_ = LinearSystem([[0.086, -0.036], [-0.172, -0.994]], [[-0.357], [-0.096]],
                        [[-0.315, 1.384]])
    for seed in (2, 7, 9, 18, 23, 25):
        rng = np.random.default_rng(seed)
        Y, D = simulate(sys_, 60, rng, rng.normal(size=2), [0.0], 1.0, signs=True)
        res = so.SMFDO(sys_, window=20, fast=fast).run(Y)
        assert res.violations(D) == 0
        assert set(res.status) <= {"ok", "unbounded", "fallback"}


def test_a_fallback_step_is_flagged_and_warned_once(monkeypatch):
    from setobs.exceptions import SolverWarning
    from tests.conftest import cripple_highs, disable_compiled_lps

    cripple_highs(monkeypatch)
    disable_compiled_lps(monkeypatch)
    sys_ = so.examples.chang2006()
    Y, D = simulate(sys_, 12, np.random.default_rng(0), np.zeros(3), [0, 0], 1.0)
    with pytest.warns(SolverWarning, match="warned once") as rec:
        res = so.SMFDO(sys_, window=5, fast=False).run(Y)
    assert sum(issubclass(w.category, SolverWarning) for w in rec) == 1
    assert (res.status[1:] == "fallback").any()
    assert res.violations(D) == 0  # wider, still outer


# ------------------------------------------------------------------ 11. |y| ~ 1e8
@pytest.mark.parametrize("fast", [True, False])
def test_no_false_invalidation_with_large_measurements(fast):
    sys_ = LinearSystem([[1.2, 0.1], [0.0, 0.9]], [[1.0], [0.5]], np.eye(2))
    Y, D = simulate(sys_, 110, np.random.default_rng(0), [1e6, 1e5], [0.0], 1.0)
    assert np.abs(Y).max() > 1e13
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        res = so.SMFDO(sys_, window=3, fast=fast).run(Y)  # raised at k = 25 (|y| ~ 1e8)
    assert res.violations(D) == 0
    # at |y| ~ 1e13 the fast path's rounding allowances (the model's, gK |y|, about 1)
    # take about 1 % of the disturbance band: those steps say so, warned once
    gaps = np.array([st.gap for st in res.steps])
    inexact = res.status == "inexact"
    assert (gaps[inexact] > 1e-2).all() and (gaps[res.status == "ok"] <= 1e-2).all()
    assert len([r for r in rec if "rounding allowances" in str(r.message)]) == int(inexact.any())
    if not fast:
        assert not inexact.any()
