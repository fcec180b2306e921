"""NonlinearSetObserver at its defaults, on plants it was not tuned on: a forced Van der
Pol oscillator (one of two states measured), a six-tank cascade with other constants and
a feedback term, the two-state example of Rego et al. 2020 (a constrained-zonotope
initial set, a nonlinear output); every band against an *inner* bound of the exact set
from a nonlinear optimizer (multiple shooting, feasible histories checked feasible:
``tests.oracles.nonlinear_inner_bounds_ms``). Plus what must not abort, and the
adaptive sizes' rule."""

from __future__ import annotations

import numpy as np
import pytest

sp = pytest.importorskip("sympy")

import setobs as so  # noqa: E402
from tests.oracles import nonlinear_inner_bounds_ms  # noqa: E402


def _record(f, h, xs, us, x0, U, rw, rv, rng, corners=False):
    F = sp.lambdify([list(xs), list(us)], f)
    H = sp.lambdify([list(xs), list(us)], h)
    Fn = lambda x, u: np.array(F(x, u), dtype=float)  # noqa: E731
    Hn = lambda x, u: np.array(H(x, u), dtype=float)  # noqa: E731
    x = np.array(x0, float)
    X, Y = [], []
    for k in range(len(U)):
        X.append(x.copy())
        draw = (lambda m: rng.choice([-1.0, 1.0], m)) if corners else \
            (lambda m: rng.uniform(-1, 1, m))
        Y.append(Hn(x, U[k]) + rv * draw(len(h)))
        x = Fn(x, U[k]) + rw * draw(len(f))
    return np.array(X), np.array(Y), Fn, Hn


def van_der_pol(seed: int = 0, N: int = 200, corners: bool = False):
    """Forward Euler, dt = 0.05, mu = 1, u = 0.5 sin(0.3 k dt), x1 measured; |w| <= (1e-3,
    2e-3), |v| <= 0.02, X0 = x0 +- 0.2."""
    x1, x2, u = sp.symbols("x1 x2 u")
    dt = 0.05
    f = [x1 + dt * x2, x2 + dt * ((1 - x1**2) * x2 - x1 + u)]
    h = [x1]
    rw, rv = np.array([1e-3, 2e-3]), 0.02
    rng = np.random.default_rng(seed)
    x0 = np.array([1.0, 0.5]) + rng.uniform(-0.1, 0.1, 2)
    U = 0.5 * np.sin(0.3 * np.arange(N) * dt)[:, None]
    X, Y, F, H = _record(f, h, [x1, x2], [u], x0, U, rw, rv, rng, corners)
    return dict(f=f, h=h, xs=[x1, x2], us=[u], rw=rw, rv=rv, X0=so.Box(x0 - 0.2, x0 + 0.2),
                X=X, Y=Y, U=U, F=F, H=H, unmeasured=[1])


def feedback_tanks(n: int = 6, seed: int = 5, N: int = 40):
    """Torricelli tanks with other constants than ``tank_cascade`` and a feedback term on
    the first tank (``-0.05 (x_0 - 2)``); every other level measured."""
    xs = sp.symbols(f"x0:{n}")
    u = sp.Symbol("u")
    T = 0.4
    a = [0.45 + 0.03 * ((3 * i) % 4) for i in range(n)]
    f = [xs[i] + T * ((0.35 * u - 0.05 * (xs[0] - 2.0) if i == 0
                       else a[i - 1] * sp.sqrt(xs[i - 1])) - a[i] * sp.sqrt(xs[i]))
         for i in range(n)]
    h = [xs[i] for i in range(0, n, 2)]
    rw, rv = 0.003, 0.01
    rng = np.random.default_rng(seed)
    U = 1.0 + 0.4 * np.sin(0.13 * np.arange(N))[:, None]
    X, Y, F, H = _record(f, h, xs, [u], rng.uniform(1.5, 2.5, n), U, rw, rv, rng)
    return dict(f=f, h=h, xs=list(xs), us=[u], rw=rw, rv=rv,
                X0=so.Box(np.ones(n), 3.0 * np.ones(n)), X=X, Y=Y, U=U, F=F, H=H,
                unmeasured=list(range(1, n, 2)))


REGO_C = np.array([5.0, 0.5])
REGO_G = np.array([[0.5, 1.0, -0.5], [0.5, 0.5, 0.0]])


def rego_example(seed: int = 0, N: int = 100, corners: bool = False):
    """Rego, Raffo, Scott, Raimondo (Automatica 2020), the two-state example (its settings
    as in the ZETA toolbox's demos): ``x1+ = x1 (3 - x1/7 - 4 x2/(4 + x1)) + w1``,
    ``x2+ = x2 (-2 + 3 x1/(4 + x1)) + w2``, ``y = (x1 - sin(x2/2), (1 - x1) x2) + v``,
    X0 the zonotope ``c + G xi``, |w| <= 0.5, |v| <= 0.2; x0 drawn in X0."""
    x1, x2 = sp.symbols("x1 x2")
    f = [x1 * (3 - x1 / 7 - 4 * x2 / (4 + x1)), x2 * (-2 + 3 * x1 / (4 + x1))]
    h = [x1 - sp.sin(x2 / 2), (1 - x1) * x2]
    rng = np.random.default_rng(seed)
    x0 = REGO_C + REGO_G @ rng.uniform(-1, 1, 3)
    U = np.zeros((N, 0))
    X, Y, F, H = _record(f, h, [x1, x2], [], x0, U, 0.5, 0.2, rng, corners)
    return dict(f=f, h=h, xs=[x1, x2], us=[], rw=0.5, rv=0.2,
                X0=so.ConstrainedZonotope(REGO_G, REGO_C), X=X, Y=Y, U=U, F=F, H=H,
                unmeasured=[0, 1])


def estimate(case, **kw):
    obs = so.NonlinearSetObserver(case["f"], case["h"], case["xs"], case["us"],
                                  process_noise=case["rw"], measurement_noise=case["rv"],
                                  initial_state_set=case["X0"], **kw)
    return obs.run(case["Y"], case["U"] if case["U"].shape[1] else None)


def inner(case, k, starts=2):
    X0 = case["X0"]
    box = ("zonotope", REGO_C, REGO_G) if isinstance(X0, so.ConstrainedZonotope) else \
        (X0.lo, X0.hi)
    return nonlinear_inner_bounds_ms(case["F"], case["H"], box, case["rw"], case["rv"],
                                     case["Y"], case["U"], case["X"], k, case["unmeasured"],
                                     starts=starts)


def inside(case, res) -> bool:
    return bool(np.all((case["X"] >= res.state_lo) & (case["X"] <= res.state_hi)))


def test_the_oscillators_unmeasured_band_is_within_three_times_the_exact_sets():
    """At the defaults the unmeasured x2's band holds the inner bound (histories attained
    by the optimizer) at k = 50, 100 and 199, and is at most 3 times as wide at k = 50 and
    100 (measured: 1.01, 1.01; the previous defaults 16 / 4 gave 4 and 9). At k = 199 the
    width depends on the LP answers' choices within their tolerances: see the next test."""
    case = van_der_pol()
    res = estimate(case)
    assert inside(case, res) and set(res.status) == {"ok"}
    for k in (50, 100, 199):
        lo, hi = inner(case, k)
        assert res.state_lo[k, 1] <= lo[1] and hi[1] <= res.state_hi[k, 1]
        assert hi[1] - lo[1] > 0.05  # (the oracle found a spread, not the truth alone)
        if k < 199:
            assert (res.state_hi[k, 1] - res.state_lo[k, 1]) <= 3.0 * (hi[1] - lo[1])


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="the oscillator's late band is bistable in the "
                   "hulls' early stop (a known limit of the defaults)")
def test_the_oscillators_late_band_is_within_three_times_for_any_hull_gap(monkeypatch):
    """The late band (k = 199) at most 3 times the inner bound's width for every early
    stop of the step's hulls near the default (``HULL_REL_GAP`` 1e-3; each bound certified,
    within its gap of the exact hull). It is not: from k = 145, where a hull's bound moved
    by 1.3e-4 of its width (both answers within the gap), the run takes one of two courses:
    at k = 199 x2's band is 0.125 on the narrow one and 0.545 on the wide one (from k = 182
    x1's band sits at the measurement's and x2's grows), against the inner bound's 0.093
    (1.3 and 5.9 times). Which one depends on the simplex's path (the basis factorization,
    ties) as much as on the gap: with the compiled simplex's dense inverse, gap 5e-4 takes
    the wide course and 1e-3 and 2e-3 the narrow one; with a sparse LU in its place (the
    same pivot rules), 1e-3 took the wide one and the others the narrow one. Development
    runs, not in a results file."""
    import setobs.setmembership.nonlinear as nl

    case = van_der_pol()
    lo, hi = inner(case, 199)
    widths = []
    for gap in (5e-4, 1e-3, 2e-3):
        monkeypatch.setattr(nl, "HULL_REL_GAP", gap)
        res = estimate(case)
        widths.append(res.state_hi[199, 1] - res.state_lo[199, 1])
    assert max(widths) <= 3.0 * (hi[1] - lo[1])


@pytest.mark.parametrize("ks, starts", [((30,), 1),
                                        pytest.param((10, 20, 30), 2, marks=pytest.mark.slow)])
def test_a_held_out_cascade_is_within_1_3_times_the_exact_set(ks, starts):
    """Six tanks with a feedback term: mean width of the unmeasured levels at most 1.3
    times the inner bound (measured 1.07 at k = 10, 20, 30; the previous default form
    and sizes gave 1.49)."""
    case = feedback_tanks()
    res = estimate(case)
    assert inside(case, res)
    un = case["unmeasured"]
    ratios = []
    for k in ks:
        lo, hi = inner(case, k, starts=starts)
        assert np.all(res.state_lo[k, un] <= lo[un]) and np.all(hi[un] <= res.state_hi[k, un])
        ratios.append(np.mean((res.state_hi[k, un] - res.state_lo[k, un]) / (hi - lo)[un]))
    assert np.mean(ratios) <= 1.3


@pytest.mark.parametrize("seed", [0, pytest.param(1, marks=pytest.mark.slow),
                                  pytest.param(2, marks=pytest.mark.slow)])
def test_the_rego_example_runs_and_holds_the_truth(seed):
    """No exception, the truth inside, and at k = 30 the bands hold the inner bound from
    the zonotope initial set and are at most 2 times as wide on average (measured mean
    hull radius 0.11 against 0.15 for Taylor alone and 0.20 for the mean-value form)."""
    case = rego_example(seed)
    res = estimate(case)
    assert inside(case, res)
    lo, hi = inner(case, 30)
    assert np.all(res.state_lo[30] <= lo) and np.all(hi <= res.state_hi[30])
    assert np.mean((res.state_hi[30] - res.state_lo[30]) / (hi - lo)) <= 2.0


def test_the_truth_is_inside_with_noise_on_the_corners():
    """Every noise sample on a corner of its box (the bounds attained): the oscillator
    (150 steps) and the Rego example (60 steps), by default, hold the truth."""
    for case in (van_der_pol(3, N=150, corners=True), rego_example(4, N=60, corners=True)):
        res = estimate(case)
        assert inside(case, res)


@pytest.mark.slow
def test_the_rego_example_never_aborts_over_twenty_seeds():
    for seed in range(20):
        case = rego_example(seed)
        res = estimate(case)
        assert inside(case, res), seed


def test_auto_is_never_wider_than_a_single_form_at_the_same_sizes():
    """Fixed sizes (no adaptation), the same record: "auto" takes row by row the narrower
    enclosure (and re-linearizes h), so its bands are at most each single form's, step by
    step, up to 1 % (the sets' shapes differ after the first step, so the order is not
    exact)."""
    for case in (rego_example(3, N=40), feedback_tanks(N=30)):
        kw = dict(reduction_growth=None, max_generators=60, max_constraints=12)
        w = {m: (lambda r: r.state_hi - r.state_lo)(estimate(case, method=m, **kw))
             for m in ("auto", "mean-value", "taylor")}
        for m in ("mean-value", "taylor"):
            assert np.all(w["auto"].mean(axis=1) <= 1.01 * w[m].mean(axis=1)), m


def test_the_sizes_grow_while_a_reduction_would_widen_the_hull():
    """The rule, checked from the outside: at every step below the caps where the growth
    is measured (every other step), the kept (reduced) posterior's own certified hull is
    at most ``reduction_growth`` wider than the step's bands in every coordinate; the
    sizes never shrink and stay within the caps, and they start below them."""
    case = van_der_pol(N=80)
    obs = so.NonlinearSetObserver(case["f"], case["h"], case["xs"], case["us"],
                                  process_noise=case["rw"], measurement_noise=case["rv"],
                                  initial_state_set=case["X0"])
    g0, c0 = obs.sizes
    assert g0 < obs.max_generators and c0 < obs.max_constraints
    prev = (g0, c0)
    for k in range(80):
        st = obs.step(case["Y"][k], case["U"][k])
        g, c = st.stats["generators"], st.stats["constraints"]
        assert prev[0] <= g <= obs.max_generators and prev[1] <= c <= obs.max_constraints
        prev = (g, c)
        Z = obs.posterior
        assert Z.n_gen <= g and Z.n_con <= c
        measured = not np.isnan(st.stats["reduction_growth"])
        if k % 2 and g < obs.max_generators:  # (below the caps: every other step)
            assert not measured or st.stats["unreduced_constraints"] <= c
        if g < obs.max_generators and c < obs.max_constraints and measured:
            hb = Z.interval_hull()
            w = st.state_hi - st.state_lo
            assert np.all(hb.hi - hb.lo <= (1.0 + obs.reduction_growth) * w + 1e-12)
    assert prev != (g0, c0)  # (this record makes them grow)


def test_default_sizes_follow_the_model():
    """Defaults from n, the outputs and the noise: the constraints leave room for one
    step's measurement rows within the compiled simplex's rows, the generators follow at
    the model's ratio of generators to constraints per step."""
    from setobs.lp.factor import COMPILED_MAX_ROWS

    g0, c0, gc, cc = so.NonlinearSetObserver.default_sizes(2, 1, 2, 1)
    assert (c0, cc) == (8, COMPILED_MAX_ROWS - 1) and (g0, gc) == (40, 5 * cc)
    g0, c0, gc, cc = so.NonlinearSetObserver.default_sizes(30, 15, 30, 15)
    assert cc == COMPILED_MAX_ROWS - 15 and gc == 5 * cc and c0 == cc


def test_a_state_domain_at_the_functions_exact_limit_is_accepted():
    """``sqrt(x + 1)`` with ``state_domain`` x >= -1, exactly its domain's edge (was
    refused with a domain error over [-5e-324, ...]): the run goes on, the truth inside."""
    x = sp.Symbol("x")
    f = [0.9 * x + 0.1 * sp.sqrt(x + 1) - 0.05]
    rng = np.random.default_rng(2)
    U = np.zeros((30, 0))
    X, Y, _, _ = _record(f, [x], [x], [], [-0.9], U, 1e-3, 0.02, rng)
    res = so.NonlinearSetObserver(f, [x], [x], process_noise=1e-3, measurement_noise=0.02,
                                  initial_state_set=so.Box([-1.0], [-0.5]),
                                  state_domain=so.Box([-1.0], [np.inf])).run(Y)
    assert np.all((X >= res.state_lo) & (X <= res.state_hi))
    assert (res.state_lo >= -1.0).all()


def test_an_unknown_function_is_named_with_the_close_match():
    with pytest.raises(so.NotSupportedError, match=r"sinn .*not a known function: did you "
                                                   r"mean sin\?"):
        so.NonlinearSetObserver(["sinn(x)"], ["x"], ["x"], process_noise=0.1,
                                measurement_noise=0.1, initial_state_set=so.Box([0.0], [1.0]))


def test_an_inconsistency_names_the_initial_set():
    """An initial set that misses the truth: the certified inconsistency's advice names
    it."""
    case = van_der_pol(N=20)
    X0 = so.Box(case["X"][0] + 1.0, case["X"][0] + 1.2)
    with pytest.raises(so.ModelInvalidatedError) as err:
        so.NonlinearSetObserver(case["f"], case["h"], case["xs"], case["us"],
                                process_noise=case["rw"], measurement_noise=case["rv"],
                                initial_state_set=X0).run(case["Y"], case["U"])
    assert "initial_state_set" in str(err.value.hint)


@pytest.mark.parametrize("which", ["rego", "tanks"])
def test_the_polyhedral_relaxation_holds_every_sampled_state(which):
    """The lifted set holds ``(x, a(x))`` -- every auxiliary at its node's true value --
    for states sampled in the set and the box (certified point containment of the lifted
    constrained zonotope, an LP), and every output ``g(x)`` lies within its affine form's
    radius: the relaxation's rows hold where they must (the tanks' box reaches below
    ``sqrt``'s domain: only states inside it are sampled)."""
    from setobs.setmembership._relax import Relaxation

    if which == "rego":
        case = rego_example(0)
        lo, hi = np.array([4.0, -0.5]), np.array([6.5, 1.5])
    else:
        case = feedback_tanks(n=3)
        lo, hi = np.array([-0.1, 0.5, 1.0]), np.array([1.0, 2.5, 2.2])
    xs, us = case["xs"], case["us"]
    R = Relaxation(sp, case["f"], xs, us)
    u = np.ones(len(us))
    X = so.ConstrainedZonotope.from_box(lo, hi)
    Xl, P, q, r, _, _ = R.lift(X, lo, hi, u)
    aux = [(R.aux_of[j], sp.lambdify([xs, us], nd[1])) for j, nd in enumerate(R.nodes)
           if j in R.aux_of]
    F = sp.lambdify([xs, us], case["f"])
    rng = np.random.default_rng(1)
    pts = rng.uniform(lo, np.maximum(hi, lo), (60, len(xs)))
    if which == "tanks":
        pts = np.maximum(pts, 0.0)  # (the model holds at true states: levels >= 0)
    for x in pts:
        v = np.zeros(Xl.dim)
        v[:len(xs)] = x
        for i, fn in aux:
            v[i] = float(fn(x, u))
        assert Xl.contains(v)
        fx = np.array(F(x, u), dtype=float)
        assert np.all(np.abs(P @ v + q - fx) <= r + 1e-12 * (1 + np.abs(fx)))


def test_the_intersected_forms_hold_every_sampled_image_and_are_no_wider(monkeypatch):
    """``intersect_forms=True`` on a curved map over a wide box (both forms differ in
    slope there): the prediction from ``X_0`` holds ``f(x)`` for states sampled in
    ``X_0`` (certified point containment, an LP), it carries the coupling rows, and its
    support function is nowhere above the row-wise prediction's (the coupled set is a
    subset of the narrower form's image), below it in some directions. (The polyhedral
    relaxation, which "auto" takes on so wide a box, is kept out.)"""
    import setobs.setmembership.nonlinear as nlm

    monkeypatch.setattr(nlm, "POLYHEDRAL_MAX_DIM", 0)
    f = ["x1 + 0.3*x2*x1**2", "x2 - 0.2*x1**3 + 0.1*exp(x2)"]
    kw = dict(process_noise=None, measurement_noise=0.01,
              initial_state_set=so.Box([-1.0, -0.5], [1.5, 1.0]), reduction_growth=None)
    plain = so.NonlinearSetObserver(f, ["x1"], ["x1", "x2"], **kw)
    both = so.NonlinearSetObserver(f, ["x1"], ["x1", "x2"], intersect_forms=True, **kw)
    plain.step([np.nan])
    both.step([np.nan])
    assert both.prior.n_con > plain.prior.n_con  # (the coupling rows)
    gain = []
    for a in np.linspace(0.0, 2.0 * np.pi, 13)[:-1]:
        d = np.array([np.cos(a), np.sin(a)])
        sb, sp_ = both.prior.support(d), plain.prior.support(d)
        assert sb <= sp_ + 1e-9
        gain.append(sp_ - sb)
    assert max(gain) > 5e-3  # (narrower in some direction: 0.0087 here)
    F = sp.lambdify([sp.symbols("x1 x2")], [sp.sympify(e) for e in f])
    rng = np.random.default_rng(2)
    for x in rng.uniform([-1.0, -0.5], [1.5, 1.0], (40, 2)):
        assert both.prior.contains(np.array(F(x), dtype=float))


def test_the_intersected_forms_in_the_measurement_keep_the_truth_and_are_no_wider():
    """On the Rego example (``h`` nonlinear: both forms' strips in the measurement), with
    ``intersect_forms=True`` the truth is inside every band over 40 steps (noise on the
    corners), and the first posterior's certified hull is inside the row-wise one's."""
    case = rego_example(3, N=40, corners=True)
    kw = dict(process_noise=case["rw"], measurement_noise=case["rv"],
              initial_state_set=case["X0"])
    res = so.NonlinearSetObserver(case["f"], case["h"], case["xs"], case["us"],
                                  intersect_forms=True, **kw).run(case["Y"])
    assert inside(case, res)
    one = [so.NonlinearSetObserver(case["f"], case["h"], case["xs"], case["us"],
                                   intersect_forms=flag, **kw).step(case["Y"][0])
           for flag in (False, True)]
    assert np.all(one[1].state_lo >= one[0].state_lo - 1e-9)
    assert np.all(one[1].state_hi <= one[0].state_hi + 1e-9)
