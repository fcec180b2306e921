"""SMFDO against an independent whole-history LP, soundness, boundedness, estimates, errors."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import setobs as so
from setobs import ConstrainedZonotope, DimensionError, LinearSystem
from setobs.exceptions import ArgumentError, InvalidValueError
from setobs.setmembership import (
    ExistenceError,
    ModelInvalidatedError,
    ModelInvalidatedWarning,
    chebyshev_center,
    interval_center,
)
from setobs.tolerances import FASTLP_GAP_RTOL


def simulate(sys, N, rng, x0, d0, step=1.0, U=None, signs=False):
    """x+ = Phi x + Gamma u + G d, y = Xi x, d+ = d + dd with |dd_i| <= step_i
    (uniform; ``signs``: dd_i = +-step_i, the corners of the box)."""
    d = np.array(d0, float)
    step = np.broadcast_to(np.asarray(step, float), (sys.q,))
    D = []
    for _ in range(N):
        D.append(d.copy())
        d = d + (rng.choice([-1.0, 1.0], sys.q) * step if signs
                 else rng.uniform(-step, step, sys.q))
    D = np.array(D)
    if U is None and sys.p:
        U = np.zeros((N, sys.p))
    return sys.simulate(D, U, x0=x0)[0], D


def history_lp_bounds(sys, Y, U, x_lo, x_hi, step, k):
    """Independent reference: bounds of d_k over the whole history (scipy/HiGHS, no setobs).

    Variables v = (x0, d0, dd_0..dd_(k-1)); x_j and d_j are affine in v.
    """
    n, q = sys.n, sys.q
    nv = n + q + k * q
    # x_j = Mx_j v + ox_j, d_j = Md_j v
    Mx = np.zeros((n, nv))
    Mx[:, :n] = np.eye(n)
    ox = np.zeros(n)
    Md = np.zeros((q, nv))
    Md[:, n : n + q] = np.eye(q)
    A_eq, b_eq = [], []
    for j in range(k + 1):
        A_eq.append(sys.Xi @ Mx)
        b_eq.append(Y[j] - sys.Xi @ ox)
        if j == k:
            break
        u = U[j] if U is not None else np.zeros(sys.p)
        Mx = sys.Phi @ Mx + sys.G @ Md
        ox = sys.Phi @ ox + sys.Gamma @ u
        Md = Md.copy()
        Md[:, n + q + j * q : n + q + (j + 1) * q] += np.eye(q)
    A_eq = np.vstack(A_eq)
    b_eq = np.concatenate(b_eq)
    bounds = ([(lo, hi) for lo, hi in zip(x_lo, x_hi, strict=True)] + [(None, None)] * q
              + [(-step, step)] * (k * q))
    lo = np.empty(q)
    hi = np.empty(q)
    for i in range(q):
        for sgn in (1.0, -1.0):
            res = linprog(sgn * Md[i], A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
            if res.status == 3:
                val = -np.inf if sgn > 0 else np.inf
            else:
                assert res.status == 0, res.message
                val = sgn * res.fun
            if sgn > 0:
                lo[i] = val
            else:
                hi[i] = val
    return lo, hi


def box(lo, hi):
    return ConstrainedZonotope.from_box(lo, hi)


# ------------------------------------------------------------------- exact mode vs LP
def test_exact_mode_equals_history_lp_on_the_paper_example():
    rng = np.random.default_rng(7)
    sys = so.examples.chang2006()
    X0 = (-np.ones(3), np.ones(3))
    Y, D = simulate(sys, 25, rng, x0=[0.2, -0.5, 0.3], d0=[1.0, -2.0])
    obs = so.SMFDO(sys, window=None, initial_state_set=box(*X0))
    res = obs.run(Y)
    for k in (0, 1, 2, 5, 12, 24):
        lo, hi = history_lp_bounds(sys, Y, None, *X0, 1.0, k)
        for a, b in ((res.lo[k], lo), (res.hi[k], hi)):
            fin = np.isfinite(b)
            assert np.array_equal(np.isfinite(a), fin)
            np.testing.assert_allclose(a[fin], b[fin], atol=1e-6)
    assert res.violations(D) == 0


def test_exact_mode_equals_history_lp_random_systems_with_inputs():
    rng = np.random.default_rng(11)
    checked = 0
    while checked < 5:
        n, q = int(rng.integers(2, 5)), int(rng.integers(1, 3))
        l = q + int(rng.integers(0, 2))
        sys = LinearSystem(rng.normal(size=(n, n)) * 0.4, rng.normal(size=(n, q)),
                           rng.normal(size=(l, n)), rng.normal(size=(n, 1)))
        if not so.analysis.bounded_do_exists(sys).satisfied:
            continue
        U = rng.normal(size=(15, 1))
        X0 = (-2 * np.ones(n), 2 * np.ones(n))
        step = 0.5
        Y, D = simulate(sys, 15, rng, rng.uniform(-1, 1, n), rng.normal(size=q), step, U)
        obs = so.SMFDO(sys, window=None, increment_set=np.full(q, step),
                       initial_state_set=box(*X0))
        res = obs.run(Y, U)
        for k in (3, 8, 14):
            lo, hi = history_lp_bounds(sys, Y, U, *X0, step, k)
            fin = np.isfinite(lo)
            np.testing.assert_allclose(res.lo[k][fin], lo[fin], atol=1e-6)
            np.testing.assert_allclose(res.hi[k][fin], hi[fin], atol=1e-6)
        assert res.violations(D) == 0
        checked += 1


# ------------------------------------------------------------------- windowed mode
def test_windowed_contains_exact_at_every_step():
    rng = np.random.default_rng(3)
    sys = so.examples.chang2006()
    Y, D = simulate(sys, 40, rng, x0=[0.0, 1.0, 0.0], d0=[0.3, 2.0])
    X0 = box(-2 * np.ones(3), 2 * np.ones(3))
    exact = so.SMFDO(sys, window=None, initial_state_set=X0).run(Y)
    for w in (2, 5, 10):
        win = so.SMFDO(sys, window=w, initial_state_set=X0).run(Y)
        # Both are certified outer bounds of their own sets; their certification
        # slack differs at the 1e-9 level, so compare with a 1e-7 relative tolerance.
        tol = 1e-7 * (1 + np.abs(np.where(np.isfinite(exact.lo), exact.lo, 0)))
        assert np.all(win.lo <= exact.lo + tol)
        tol = 1e-7 * (1 + np.abs(np.where(np.isfinite(exact.hi), exact.hi, 0)))
        assert np.all(win.hi >= exact.hi - tol)
        assert win.violations(D) == 0
    # Early steps: unbounded -> +-inf and NaN estimate, not a made-up number.
    assert np.all(np.isinf(exact.lo[0])) and np.all(np.isnan(exact.estimate[0]))


def test_windowed_width_stays_bounded_over_2000_steps():
    rng = np.random.default_rng(5)
    sys = so.examples.chang2006()
    Y, D = simulate(sys, 2000, rng, x0=[0.0, 1.0, 0.0], d0=[0.0, 0.0])
    res = so.SMFDO(sys, window=3).run(Y)
    assert res.violations(D) == 0
    # The disturbance itself wanders far (random walk), the error bound does not grow.
    assert np.abs(D).max() > 20
    r = res.error_bound[10:]
    assert np.isfinite(r).all()
    assert r[-500:].max() <= 1.5 * r[:500].max()


def random_runs(rng, count, N):
    """Random systems (q + 1 outputs) satisfying Theorem 1, with data and a valid window.

    Yields ``(sys, step, Y, D, window)``; increments are uniform in ``|dd_i| <= step``.
    """
    runs = 0
    while runs < count:
        n, q = int(rng.integers(2, 5)), int(rng.integers(1, 3))
        sys = LinearSystem(rng.normal(size=(n, n)) * 0.5, rng.normal(size=(n, q)),
                           rng.normal(size=(q + 1, n)))
        if not so.analysis.bounded_do_exists(sys).satisfied:
            continue
        step = float(rng.uniform(0.1, 2.0))
        Y, D = simulate(sys, N, rng, rng.normal(size=n) * 3, rng.normal(size=q) * 5, step)
        w = max(int(rng.integers(1, 6)), so.SMFDO(sys).mu_o - 1)
        yield sys, step, Y, D, w
        runs += 1


def test_soundness_many_random_runs():
    for sys, step, Y, D, w in random_runs(np.random.default_rng(21), 15, 80):
        res = so.SMFDO(sys, window=w, increment_set=np.full(sys.q, step)).run(Y)
        assert res.violations(D) == 0


# ------------------------------------------------------------------- estimates
def test_chebyshev_center_closed_form_triangle():
    # Triangle (0,0), (2,0), (1,2) as a constrained zonotope.
    T = ConstrainedZonotope.from_hpolytope([[0, -1], [2, 1], [-2, 1]], [0, 4, 0])
    ih = interval_center(T)
    np.testing.assert_allclose(ih.point, [1.0, 1.0], atol=1e-9)
    ch = chebyshev_center(T)
    np.testing.assert_allclose(ch.point, [1.0, 0.75], atol=1e-6)
    assert ch.worst_case_error == pytest.approx(1.25, abs=1e-6)
    V = T.vertices()
    ih_euclid = np.linalg.norm(V - ih.point, axis=1).max()
    assert ih_euclid == pytest.approx(np.sqrt(2), abs=1e-9)
    assert ch.worst_case_error < ih_euclid - 0.1
    # The interval-hull centre is optimal for the infinity norm: radius 1.
    assert ih.worst_case_error == pytest.approx(1.0, abs=1e-9)


def test_chebyshev_equals_interval_center_on_boxes():
    B = box([0.0, -1.0], [2.0, 3.0])
    ch, ih = chebyshev_center(B), interval_center(B)
    np.testing.assert_allclose(ch.point, ih.point, atol=1e-6)
    assert ch.worst_case_error == pytest.approx(np.hypot(1.0, 2.0), abs=1e-6)


def test_chebyshev_beats_or_ties_interval_center_on_smfdo_sets():
    rng = np.random.default_rng(9)
    sys = so.examples.chang2006()
    Y, D = simulate(sys, 12, rng, x0=[0.0, 1.0, 0.0], d0=[0.5, 0.5])
    obs = so.SMFDO(sys, window=None, keep_sets=True,
                   initial_state_set=box(-np.ones(3), np.ones(3)))
    steps = obs.run(Y).steps
    for st in steps[4:]:
        S = st.disturbance_set
        ch = chebyshev_center(S)
        V = S.vertices()
        ih_r2 = np.linalg.norm(V - st.estimate, axis=1).max()
        assert ch.worst_case_error <= ih_r2 + 1e-7
        assert S.contains(D[st.k], tol=1e-7)


# ------------------------------------------------------------------- errors
def test_window_too_small():
    sys = so.examples.chen_gao_lin_example1()  # mu_o = 5 for the augmented pair
    msg = r"window \(delta\) = 2 is too small: .* >= mu_o - 1 = 4"
    with pytest.raises(InvalidValueError, match=msg):
        so.SMFDO(sys, window=2)


def test_theorem1_failing_carries_report():
    sys = LinearSystem(np.diag([0.5, 0.3, 0.2]), np.eye(3)[:, :2], [[1.0, 0.0, 0.0]])
    with pytest.raises(ExistenceError, match="Theorem 1") as info:
        so.SMFDO(sys)
    assert info.value.report.corollary1


def test_bad_measurements():
    obs = so.SMFDO(so.examples.chang2006())
    with pytest.raises(DimensionError, match="y must have length 2, got 3"):
        obs.step([0.0, 0.0, 0.0])
    with pytest.raises(InvalidValueError, match="y contains inf"):
        obs.step([np.inf, 0.0])  # (NaN means "not measured")
    with pytest.raises(DimensionError, match="Y must have 2 columns"):
        obs.run(np.zeros((5, 3)))
    sysu = LinearSystem(np.eye(2) * 0.5, [[1.0], [0.0]], [[1.0, 0.0], [0.0, 1.0]], [[0.0], [1.0]])
    with pytest.raises(ArgumentError, match="U is required"):
        so.SMFDO(sysu, window=3).run(np.zeros((4, 2)))
    with pytest.raises(ArgumentError, match="u is required"):
        so.SMFDO(sysu, window=3).step([0.0, 0.0])
    with pytest.raises(DimensionError, match="u must have length 1, got 2"):
        so.SMFDO(sysu, window=3).step([0.0, 0.0], [1.0, 2.0])


def test_inconsistent_data_raises_or_resets():
    rng = np.random.default_rng(2)
    sys = so.examples.chang2006()
    Y, D = simulate(sys, 30, rng, x0=[0.0, 0.0, 0.0], d0=[0.0, 0.0], step=0.1)
    Y[20] += 100.0  # an outlier no bounded increment can explain
    obs = so.SMFDO(sys, window=5, increment_set=[0.1, 0.1],
                   initial_state_set=box(-np.ones(3), np.ones(3)))
    with pytest.raises(ModelInvalidatedError, match="step k=20") as info:
        obs.run(Y)
    assert info.value.step == 20
    obs2 = so.SMFDO(sys, window=5, increment_set=[0.1, 0.1], on_inconsistent="reset",
                    initial_state_set=box(-np.ones(3), np.ones(3)))
    with pytest.warns(ModelInvalidatedWarning) as rec:
        res = obs2.run(Y)
    # First reset at the outlier; the set that explains the outlier may be reset once
    # more when the next (true) measurement contradicts it. One warning per run.
    assert len(rec) == 1 and "first at k=20" in str(rec[0].message)
    assert res.first_inconsistent == 20 and obs2.first_inconsistent == 20
    assert res.status[20] == "reset" and not res.consistent
    assert 1 <= obs2.stats["reset"] <= 3
    assert np.isfinite(res.lo[25:]).all()
    assert ((D[25:] >= res.lo[25:]) & (D[25:] <= res.hi[25:])).all()


def test_time_varying_increment_set_matches_history_lp():
    """A callable increment set: quiet (|dd| <= 0.05) for k < 10, then |dd| <= 1."""
    rng = np.random.default_rng(4)
    sys = so.examples.chang2006()
    steps = np.where(np.arange(20) < 10, 0.05, 1.0)
    d, D = np.array([0.5, -0.5]), []
    for k in range(20):
        D.append(d.copy())
        d = d + rng.uniform(-steps[k], steps[k], 2)
    D = np.array(D)
    Y = sys.simulate(D)[0]
    sets = {r: ConstrainedZonotope.from_box([-r, -r], [r, r]) for r in (0.05, 1.0)}
    X0 = box(-np.ones(3), np.ones(3))
    res = so.SMFDO(sys, window=None, increment_set=lambda k: sets[float(steps[k])],
                   initial_state_set=X0).run(Y)
    assert res.violations(D) == 0
    # The time-varying set is used: tighter than the constant |dd| <= 1 filter while quiet.
    const = so.SMFDO(sys, window=None, increment_set=[1.0, 1.0], initial_state_set=X0).run(Y)
    assert np.all(res.error_bound[5:] <= const.error_bound[5:] + 1e-9)  # tighter while quiet
    assert res.error_bound[9] < 0.5 * const.error_bound[9]


def test_increment_set_validation():
    sys = so.examples.chang2006()
    with pytest.raises(InvalidValueError, match="increment_set must be bounded"):
        so.SMFDO(sys, increment_set=ConstrainedZonotope.full_space(2))
    with pytest.raises(DimensionError, match="increment_set must have dimension 2"):
        so.SMFDO(sys, increment_set=ConstrainedZonotope.from_box([0], [1]))
    with pytest.raises(InvalidValueError, match="nonnegative"):
        so.SMFDO(sys, increment_set=[-1.0, 1.0])
    with pytest.raises(DimensionError, match="initial_state_set must have dimension 3"):
        so.SMFDO(sys, initial_state_set=ConstrainedZonotope.full_space(2))


def test_coordinate_shortcut_equals_direct_hull_of_PZ():
    """When P selects coordinates, the bounds come from IH(Z_k): the same LPs as IH(P Z_k).

    Both are certified bounds of the same LPs, reached by different solvers and
    warm-start sequences, so they agree to the certification gap (not bit for bit)."""
    rng = np.random.default_rng(13)
    sys = so.examples.chang2006()
    Y, _ = simulate(sys, 30, rng, x0=[0.1, 0.2, 0.3], d0=[0.0, 1.0])
    obs = so.SMFDO(sys, window=5, keep_sets=True,
                   initial_state_set=box(-np.ones(3), np.ones(3)))
    assert obs.hull_from_state
    for st in obs.run(Y).steps[1:]:
        direct = st.disturbance_set.interval_hull()
        # the documented outward margin: margin * max(1, |lo|, |hi|) per coordinate
        scale = np.maximum(1.0, np.maximum(np.abs(direct.lo), np.abs(direct.hi)))
        lo, hi = direct.lo - obs.margin * scale, direct.hi + obs.margin * scale
        # (each path accepts a certified bound within FASTLP_GAP_RTOL (1 + |objective|)
        # of its optimum: on the whole-history sets of the first steps the two
        # differed by 2.4e-10)
        tol = 2.0 * FASTLP_GAP_RTOL
        np.testing.assert_allclose(st.lo, lo, rtol=tol, atol=tol)
        np.testing.assert_allclose(st.hi, hi, rtol=tol, atol=tol)


# ------------------------------------------------------------------ eq. (24), independently
def _window_lp_bounds(sys, box, Y_window, step):
    """Bounds of d at the end of a window, by scipy's LP in the original coordinates.

    Variables: z = [x; d] at the window's start, in ``box``; increments in
    ``[-step, step]``; ``z+ = [[Phi, G], [0, I]] z + [0; I] dd``, ``[Xi, 0] z = y`` for
    every measurement of the window (eq. (24): delta priors and posteriors).
    """
    n, q = sys.n, sys.q
    A = np.block([[sys.Phi, sys.G], [np.zeros((q, n)), np.eye(q)]])
    C = np.hstack([sys.Xi, np.zeros((sys.l, q))])
    s = len(Y_window)
    M = np.hstack([np.eye(n + q), np.zeros((n + q, s * q))])  # z_j = M v
    A_eq, b_eq = [], []
    for j, y in enumerate(Y_window):
        M = A @ M
        M[n:, n + q + j * q:n + q + (j + 1) * q] += np.eye(q)
        A_eq.append(C @ M)
        b_eq.append(y)
    bounds = [(lo, hi) for lo, hi in zip(box.lo, box.hi, strict=True)] + [(-step, step)] * (s * q)
    out = np.empty((2, q))
    for i in range(q):
        for t, sgn in enumerate((1.0, -1.0)):
            r = linprog(sgn * M[n + i], A_eq=np.vstack(A_eq), b_eq=np.concatenate(b_eq),
                        bounds=bounds, method="highs")
            assert r.status == 0, r.message
            out[t, i] = sgn * r.fun
    return out[0], out[1]


@pytest.mark.parametrize("fast", [True, False])
@pytest.mark.parametrize("window", [3, 10])
def test_windowed_step_equals_an_independent_lp_over_the_window(window, fast):
    """Eq. (24) (``restart="box"``): step k equals the LP over (restart box, the
    window's increments and measurements), built here from the original model, not
    from the observer's sets."""
    rng = np.random.default_rng(13)
    sys = so.examples.chang2006()
    Y, D = simulate(sys, 60, rng, x0=[0.2, -0.5, 0.3], d0=[1.0, -2.0])
    obs = so.SMFDO(sys, window=window, fast=fast, restart="box")
    # the internal coordinates are the original ones here (checked, not assumed)
    assert np.array_equal(obs.T_o, np.eye(5))
    assert np.array_equal(obs.decomposition.state_scale, np.ones(5))
    checked = 0
    for k in range(60):
        box = obs.restart_box
        st = obs.step(Y[k])
        if box is None or k < 2 * window:
            continue
        lo, hi = _window_lp_bounds(sys, box, Y[k - window + 1:k + 1], 1.0)
        scale = 1.0 + np.abs(np.concatenate([lo, hi]))
        assert (np.abs(st.lo - lo) <= 1e-7 * scale[:2]).all()
        assert (np.abs(st.hi - hi) <= 1e-7 * scale[2:]).all()
        assert st.contains(D[k])
        checked += 1
    assert checked >= 20
