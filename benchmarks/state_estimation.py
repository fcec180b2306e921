"""Benchmark: guaranteed state estimation, tightness against cost.

Physical systems of our own, all with bounded process noise on every state and
bounded measurement noise on every output (``q = 0``, ``state_bounds=True``):

* ``two_mass``: two masses and springs, lightly damped (4 states, 1 output), 0.1 s;
* ``vehicle``: a linear bicycle model (lateral velocity, yaw rate, heading, lateral
  position; 4 states; yaw rate and position measured; steering the known input),
  0.05 s;
* ``tanks_n``: a cascade of ``n`` linearised tanks (level of every third tank
  measured, inflow to the first the known input), 1 s;
* ``random_6``: a random stable system with 6 states and 4 outputs;
* ``cv_target``: a planar constant-velocity target (positions measured to +-0.1, dt =
  0.01 s, process noise on the velocities a regular decagon of radius 0.0017; every
  eigenvalue 1);
* ``tanks_30_21``: the 30-tank cascade with 21 of its levels measured.

For each: the SMFDO with windows 3 / 10 / 20 and the polytope restart and the box
restart (eq. (24)), window 10 with ``restart="auto"`` (the default), exact mode where
it finishes, and a constrained-zonotope filter in the style of Scott et al. (2016)
written with setobs's own geometry (prior ``A Z + Gamma u + W``, generalised
intersection with the measurement, constraints eliminated to ``n`` and generators
reduced to ``8 n`` (or what the constraints left need), interval hull by certified
LPs). Width of every state's band against the whole-history LP of the state
(``tests.oracles.history_lp_highs``) at every fifth step after a burn-in (three steps
for n > 6; mean and worst ratio), and time per step; in the same run the median time of one 45 x 40
``scipy.optimize.linprog`` (HiGHS), the unit of the issue's speed targets, timed before
and after every run, the faster of the two (``linprog_ms`` of each row; the machine's
speed drifts by up to 30 %).

Writes ``benchmarks/results/state_estimation.json``.

Run: ``python benchmarks/state_estimation.py [--steps N] [--quick]`` (plants with
more than 6 states: 40 steps, the box and the default restart only);
``--r30 STEPS`` runs only a random 30-state plant with 21 outputs (dense ``A``; windows
3, 5 and 10 and exact mode, widths against the whole-history LP at three steps) into
``state_estimation_r30.json``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys as _sys
import time
from pathlib import Path

import numpy as np
from scipy.linalg import expm

import setobs as so

_sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
_sys.path.insert(0, str(Path(__file__).resolve().parent))
from tests.oracles import history_lp_highs, noisy_record

from _common import linprog_unit, stamp, state_bands


def c2d(Ac, Bc, Ts):
    n, p = Bc.shape
    M = np.zeros((n + p, n + p))
    M[:n, :n], M[:n, n:] = Ac, Bc
    E = expm(M * Ts)
    return E[:n, :n], E[:n, n:]


def two_mass():
    k1, k2, c1, c2, m1, m2 = 1.0, 0.5, 0.2, 0.1, 1.0, 0.5
    Ac = np.array([[0, 1, 0, 0], [-(k1 + k2) / m1, -(c1 + c2) / m1, k2 / m1, c2 / m1],
                   [0, 0, 0, 1], [k2 / m2, c2 / m2, -k2 / m2, -c2 / m2]])
    A, B = c2d(Ac, np.array([[0.0], [1.0], [0.0], [0.0]]), 0.1)
    return A, B, np.array([[1.0, 0.0, 0.0, 0.0]]), 0.002, 0.01


def vehicle():
    # bicycle model at 20 m/s: m = 1500 kg, Iz = 2500 kg m^2, a = 1.2, b = 1.6 m,
    # cornering stiffnesses 80 / 90 kN/rad; states (v_y, r, psi, y)
    m, Iz, a, b, Cf, Cr, V = 1500.0, 2500.0, 1.2, 1.6, 8e4, 9e4, 20.0
    Ac = np.array([
        [-(Cf + Cr) / (m * V), -V - (a * Cf - b * Cr) / (m * V), 0, 0],
        [-(a * Cf - b * Cr) / (Iz * V), -(a * a * Cf + b * b * Cr) / (Iz * V), 0, 0],
        [0, 1, 0, 0], [1, 0, V, 0]])
    Bc = np.array([[Cf / m], [a * Cf / Iz], [0.0], [0.0]])
    A, B = c2d(Ac, Bc, 0.05)
    C = np.array([[0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.0, 1.0]])
    return A, B, C, 0.005, 0.02


def tanks(n):
    # x_i' = (q_(i-1) - q_i) / S with q_i = k x_i (linearised outflow), inflow u to tank 0
    Ac = (np.diag(-np.ones(n)) + np.diag(np.ones(n - 1), -1)) * 0.2
    Bc = np.zeros((n, 1))
    Bc[0, 0] = 0.5
    A, B = c2d(Ac, Bc, 1.0)
    C = np.eye(n)[::3]
    return A, B, C, 0.01, 0.02


def tanks_outputs(n, l):
    """The cascade of :func:`tanks` with ``l`` of its ``n`` levels measured, spread along it
    (``n = 30``, ``l = 21``: the tanks whose index is not 2, 5 or 8 modulo 10)."""
    A, B, _, rw, rv = tanks(n)
    skip = set(np.round(np.linspace(0, n - 1, n - l + 2)[1:-1]).astype(int)) if l < n else set()
    C = np.eye(n)[[i for i in range(n) if i not in skip]]
    assert C.shape[0] == l
    return A, B, C, rw, rv


def cv_target(dt=0.01, rv=0.1, sides=10, radius=0.0017):
    """A planar constant-velocity target: states ``(p_x, p_y, v_x, v_y)``, positions measured
    with ``+-rv``, process noise on the velocities a regular ``sides``-gon of circumradius
    ``radius`` (a zonotope of ``sides / 2`` generators), every eigenvalue 1. Returns the
    process noise as ``(E, G_w)``: ``w = E G_w xi``, ``|xi| <= 1``."""
    A = np.eye(4)
    A[0, 2] = A[1, 3] = dt
    B = np.zeros((4, 1))
    C = np.eye(4)[:2]
    g = sides // 2
    ang = np.pi * np.arange(g) / g
    # the Minkowski sum of g segments at angles k pi / g, each of length 2 r sin(pi / sides):
    # the regular polygon with circumradius r
    Gw = radius * np.sin(np.pi / sides) * np.vstack([np.cos(ang), np.sin(ang)])
    E = np.zeros((4, 2))
    E[2, 0] = E[3, 1] = 1.0
    return A, B, C, (E, Gw), rv


def random_system(n, l, seed):
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    A *= 0.95 / np.abs(np.linalg.eigvals(A)).max()
    return A, rng.normal(size=(n, 1)) * 0.2, rng.normal(size=(l, n)), 0.01, 0.05


def record(A, B, C, rw, rv, N, seed):
    rng = np.random.default_rng(seed)
    U = np.sin(0.05 * np.arange(N))[:, None] + 0.2 * rng.normal(size=(N, B.shape[1]))
    if not isinstance(rw, tuple):
        X, Y = noisy_record(A, B, C, U, rw, rv, rng)
        return X, Y, U
    E, Gw = rw  # (process noise E G_w xi, |xi| <= 1)
    x = rng.uniform(-1, 1, A.shape[0])
    X, Y = [], []
    for k in range(N):
        X.append(x.copy())
        Y.append(C @ x + rng.uniform(-rv, rv, C.shape[0]))
        x = A @ x + B @ U[k] + E @ (Gw @ rng.uniform(-1, 1, Gw.shape[1]))
    return np.array(X), np.array(Y), U


def noise_model(rw, n):
    """The SMFDO's process-noise keywords and the history LP's ``noise_w`` for a box radius
    ``rw`` or a zonotope ``(E, G_w)``."""
    if not isinstance(rw, tuple):
        return {"process_noise": rw}, (np.eye(n), np.full(n, rw))
    E, Gw = rw
    return ({"process_noise": so.ConstrainedZonotope(Gw, np.zeros(Gw.shape[0])),
             "process_noise_matrix": E}, (E @ Gw, np.ones(Gw.shape[1])))


def cz_filter(A, B, C, rw, rv, X0, Y, U, max_con, max_gen):
    """Scott-2016-style constrained-zonotope filter on setobs's geometry: the peer."""
    n = A.shape[0]
    W = (rw[0] @ so.ConstrainedZonotope(rw[1], np.zeros(rw[1].shape[0]))
         if isinstance(rw, tuple) else
         so.ConstrainedZonotope.from_box(-rw * np.ones(n), rw * np.ones(n)))
    Z = X0
    lo, hi = [], []
    stalled = 0
    for k in range(len(Y)):
        if k:
            Z = (A @ Z + W).minkowski_sum(B @ U[k - 1])
        Yset = so.ConstrainedZonotope.from_box(Y[k] - rv, Y[k] + rv)
        Z = Z.intersect(Yset, R=C)
        if Z.n_con > max_con:
            Z = Z.eliminate_constraints(max_con)
            stalled += Z.n_con > max_con  # (it stops at its rounding budget)
        if Z.n_gen > max_gen:
            Z = Z.reduce_order(max(max_gen, n + Z.n_con + n))
        box = Z.interval_hull()
        lo.append(box.lo)
        hi.append(box.hi)
    return np.array(lo), np.array(hi), stalled


def ratios(lo, hi, ref, ks):
    if ref is None:
        return float("nan"), float("nan"), float("nan")
    r = np.array([(hi[k] - lo[k]) / (ref[k][1] - ref[k][0]) for k in ks])
    return float(r.mean()), float(r.max()), float(r.min())


def study(name, A, B, C, rw, rv, N, windows, exact, peer, seed=0,
          restarts=("polytope", "box")):
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, N, seed)
    X0 = so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n))
    sys = so.LinearSystem(A, np.zeros((n, 0)), C, B)
    burn = min(25, N // 3)
    ks = list(range(burn, N, 5)) if n <= 6 else list(np.linspace(burn, N - 1, 3).astype(int))
    nkw, noise_w = noise_model(rw, n)
    t0 = time.perf_counter()
    try:
        if n > 30:  # (its HiGHS solves take tens of minutes: timings only)
            raise RuntimeError("not run above 30 states")
        ref = {k: history_lp_highs(A, np.zeros((n, 0)), C, Y, k, 0.0, U=U, Gamma=B,
                                   states=True, x_box=(X0.lo, X0.hi),
                                   noise_w=noise_w,
                                   noise_v=(np.eye(C.shape[0]), np.full(C.shape[0], rv)))
               for k in ks}
    except RuntimeError as exc:  # (the oracle's HiGHS fails on some large LPs)
        print(f"{name}: no history LP ({exc}); timings only", flush=True)
        ref = None
    t_lp = (time.perf_counter() - t0) / len(ks) if ref is not None else None
    rows = []
    kw = dict(measurement_noise=rv, state_bounds=True, initial_state_set=X0, **nkw)
    runs = [(w, r) for w in windows for r in restarts]
    runs += [(10, "auto")] if 10 in windows else []
    if exact:
        runs.append((None, "exact"))
    for w, restart in runs:
        unit0 = linprog_unit()  # (around every run: the machine's speed drifts by 30 %)
        obs = so.SMFDO(sys, window=w, **kw) if w is None else so.SMFDO(
            sys, window=w, restart=restart, **kw)
        t0 = time.perf_counter()
        res = obs.run(Y, U)
        dt = (time.perf_counter() - t0) / N
        unit = min(unit0, linprog_unit())  # (the faster: the ratio errs high)
        inside = bool(np.all((X >= res.state_lo) & (X <= res.state_hi)))
        mean, worst, best = ratios(res.state_lo, res.state_hi, ref, ks)
        rows.append({"system": name, "n": n, "l": C.shape[0], "estimator": "SMFDO",
                     "window": w, "restart": restart, "ms_per_step": 1e3 * dt,
                     "per_linprog": dt / unit, "linprog_ms": 1e3 * unit,
                     "width_ratio_mean": mean,
                     "width_ratio_worst": worst, "width_ratio_min": best,
                     "truth_inside": inside, "stats": dict(obs.stats),
                     **iteration_fields(obs, N, dt)})
        print(f"{name:9s} w={w!s:4s} {restart:8s} {1e3 * dt:8.2f} ms/step "
              f"({dt / unit:6.2f} LP)  ratio {mean:.3f} / {worst:.3f} (min {best:.4f})"
              f"  inside {inside}", flush=True)
    if peer:
        unit0 = linprog_unit()
        t0 = time.perf_counter()
        lo, hi, stalled = cz_filter(A, B, C, rw, rv, so.ConstrainedZonotope.from_box(X0.lo, X0.hi),
                           Y, U, max_con=n, max_gen=8 * n)
        dt = (time.perf_counter() - t0) / N
        unit = min(unit0, linprog_unit())
        mean, worst, best = ratios(lo, hi, ref, ks)
        inside = bool(np.all((X >= lo - 1e-9) & (X <= hi + 1e-9)))
        rows.append({"system": name, "n": n, "l": C.shape[0], "estimator": "CZ filter",
                     "window": None, "restart": None, "ms_per_step": 1e3 * dt,
                     "per_linprog": dt / unit, "linprog_ms": 1e3 * unit,
                     "width_ratio_mean": mean,
                     "width_ratio_worst": worst, "width_ratio_min": best,
                     "truth_inside": inside, "elimination_stalled_steps": int(stalled)})
        print(f"{name:9s} CZ filter          {1e3 * dt:8.2f} ms/step ({dt / unit:6.2f} LP)"
              f"  ratio {mean:.3f} / {worst:.3f}", flush=True)
    return rows, t_lp


def r30_timing(steps: int) -> list[dict]:
    """Window 10 (box and the default restart), windows 5 and 3 (box) and exact mode on a
    random 30-state plant with 21 outputs (dense ``A``): time per step after the window
    has filled, simplex iterations, and each run's state-band widths against the
    whole-history LP of the state (``tests.oracles.history_lp_highs``, independent of the
    SMFDO's LPs) at three steps after the window has filled (and against window 10's)."""
    A, B, C, rw, rv = random_system(30, 21, 5)
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, steps, 0)
    X0 = so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n))
    nkw, noise_w = noise_model(rw, n)
    ks = sorted({min(k, steps - 1) for k in (10, (10 + steps) // 2, steps - 1)})
    t0 = time.perf_counter()
    ref = {k: history_lp_highs(A, np.zeros((n, 0)), C, Y, k, 0.0, U=U, Gamma=B, states=True,
                               x_box=(X0.lo, X0.hi), noise_w=noise_w,
                               noise_v=(np.eye(C.shape[0]), np.full(C.shape[0], rv)))
           for k in ks}
    t_ref = (time.perf_counter() - t0) / len(ks)
    print(f"random_30: history LP at k = {ks}: {t_ref:.1f} s per step", flush=True)
    rows, widths = [], {}
    for w, restart in ((10, "box"), (10, "auto"), (5, "box"), (3, "box"), (None, "exact")):
        unit0 = linprog_unit()
        sys_ = so.LinearSystem(A, np.zeros((n, 0)), C, B)
        kw = dict(measurement_noise=rv, state_bounds=True, initial_state_set=X0, **nkw)
        obs = (so.SMFDO(sys_, window=w, restart=restart, **kw) if w is not None
               else so.SMFDO(sys_, window=None, **kw))
        times, lo, hi = state_bands(obs, Y, U)
        widths[(w, restart)] = hi - lo
        dt = statistics.median(times[10:]) if steps > 10 else statistics.median(times)
        unit = min(unit0, linprog_unit())
        inside = bool(np.all((X >= lo) & (X <= hi)))
        mean, worst, best = ratios(lo, hi, ref, ks)
        rat10 = widths[(w, restart)][ks] / widths[(10, "box")][ks]
        print(f"random_30 w={w!s:4s} {restart:5s} {1e3 * dt:8.1f} ms/step ({dt / unit:8.1f} LP)"
              f"  width / history LP: {mean:.4f} / {worst:.4f} (min {best:.6f})", flush=True)
        rows.append({"system": "random_30_21", "n": n, "l": C.shape[0], "estimator": "SMFDO",
                     "window": w, "restart": restart, "ms_per_step": 1e3 * dt,
                     "per_linprog": dt / unit, "linprog_ms": 1e3 * unit, "steps": steps,
                     "truth_inside": inside, "width_ratio_mean": mean,
                     "width_ratio_worst": worst, "width_ratio_min": best,
                     "width_vs_window10_box_mean": float(rat10.mean()),
                     "width_vs_window10_box_worst": float(rat10.max()),
                     "stats": dict(obs.stats),
                     **iteration_fields(obs, steps, float(np.mean(times)))})
    rows.append({"system": "random_30_21", "estimator": "history LP (HiGHS, tests.oracles)",
                 "window": None, "restart": None, "checked_steps": ks, "s_per_checked_step": t_ref})
    return rows


def iteration_fields(obs, steps: int, dt: float) -> dict:
    """The simplex's work per step (primal and dual iterations: pivots and bound flips)
    and the step's time per iteration (an upper bound on one iteration's cost)."""
    p, d = obs.simplex_iterations
    it = (p + d) / steps
    return {"simplex_iterations_per_step": it, "primal_share": p / max(p + d, 1),
            "step_us_per_iteration": 1e6 * dt / it if it else None}


def target(what: str, row: dict | None, limit: float, key: str = "per_linprog",
           at_least: bool = False) -> dict:
    """One of the state-estimation targets against its row: the measured value, whether it is met,
    and (speed) the iterations per step the limit allows at the measured cost of one."""
    if row is None:
        return {"target": what, "limit": limit, "measured": None, "met": None}
    val = row[key]
    out = {"target": what, "limit": limit, "measured": val,
           "met": bool(val >= limit if at_least else val <= limit)}
    if key == "per_linprog" and row.get("step_us_per_iteration"):
        # at the measured time per iteration, the limit's time buys this many
        out["iterations_per_step"] = row["simplex_iterations_per_step"]
        out["iterations_the_limit_allows"] = (limit * row["linprog_ms"] * 1e3
                                              / row["step_us_per_iteration"])
    return out


def find(rows, system, window, restart, estimator="SMFDO"):
    for r in rows:
        if (r["system"], r["window"], r["restart"], r["estimator"]) == (
                system, window, restart, estimator):
            return r
    return None


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=120)
    ap.add_argument("--quick", action="store_true", help="two-mass and vehicle only")
    ap.add_argument("--n60", action="store_true",
                    help="also the 60-tank cascade (tens of minutes today)")
    ap.add_argument("--r30", type=int, default=0, metavar="STEPS",
                    help="only a random 30-state plant with 21 outputs (dense A), windows "
                         "3, 5 and 10 and exact mode against the whole-history LP, STEPS "
                         "steps (about 3 s per step at window 10); writes "
                         "state_estimation_r30.json")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"
                                         / "state_estimation.json"))
    args = ap.parse_args()
    unit = linprog_unit()
    print(f"one 45 x 40 linprog (HiGHS): {1e3 * unit:.3f} ms", flush=True)
    if args.r30:
        r30 = r30_timing(args.r30)
        out = {"linprog_45x40_ms": 1e3 * unit, "rows": r30,
               "targets": [target("random 30-state plant, 21 outputs, window 10, default "
                                  "restart (target: at most 10 linprog)",
                                  find(r30, "random_30_21", 10, "auto"), 10.0),
                           target("random 30-state plant, window 10, mean width / exact at "
                                  "most 1.05", find(r30, "random_30_21", 10, "auto"), 1.05,
                                  "width_ratio_mean"),
                           target("random 30-state plant, window 10, worst width / exact at "
                                  "most 1.5", find(r30, "random_30_21", 10, "auto"), 1.5,
                                  "width_ratio_worst"),
                           target("random 30-state plant, exact mode: never narrower than the "
                                  "history LP (smallest ratio at least 1 - 1e-6)",
                                  find(r30, "random_30_21", None, "exact"), 1.0 - 1e-6,
                                  "width_ratio_min", at_least=True),
                           target("random 30-state plant, exact mode: at most 30 linprog per "
                                  "step", find(r30, "random_30_21", None, "exact"), 30.0)],
               "machine": platform.platform(), "python": platform.python_version()}
        path = Path(args.out).with_name("state_estimation_r30.json")
        path.write_text(json.dumps({**stamp(), **out}, indent=1))
        print(f"wrote {path}")
        return
    N = args.steps
    cases = [("two_mass", *two_mass(), (3, 10, 20), True, True),
             ("vehicle", *vehicle(), (3, 10, 20), True, True),
             ("cv_target", *cv_target(), (3, 10), True, True)]
    if not args.quick:
        cases += [("random_6", *random_system(6, 4, 3), (3, 10), True, False),
                  ("tanks_6", *tanks(6), (10,), False, True),
                  ("tanks_15", *tanks(15), (10,), False, False),
                  ("tanks_30", *tanks(30), (10,), False, False),
                  ("tanks_30_21", *tanks_outputs(30, 21), (10,), True, False)]
    if args.n60:
        cases.append(("tanks_60", *tanks(60), (10,), False, False))
    rows, lp_times = [], {}
    for name, A, B, C, rw, rv, windows, exact, peer in cases:
        big = A.shape[0] > 6  # (large plants: 40 steps, no polytope-only run)
        r, t_lp = study(name, A, B, C, rw, rv, min(N, 40) if big else N, windows, exact,
                        peer, restarts=("box",) if big else ("polytope", "box"))
        rows += r
        lp_times[name] = t_lp
    # growth of the window-10 step with n (tanks; the default restart="auto")
    pts = [(r["n"], r["ms_per_step"]) for r in rows
           if r["system"].startswith("tanks") and r["window"] == 10
           and r["restart"] == "auto"]
    growth = None
    if len(pts) >= 2:
        ln = np.log(np.array(pts, dtype=float))
        growth = float(np.polyfit(ln[:, 0], ln[:, 1], 1)[0])
    targets = [target("random 6-state plant, 4 outputs, window 10, noise, state bounds, "
                      "default restart (target: at most 0.5 linprog)",
                      find(rows, "random_6", 10, "auto"), 0.5),
               target("30-tank cascade, 21 outputs, window 10, default restart: at most 5 "
                      "linprog", find(rows, "tanks_30_21", 10, "auto"), 5.0),
               target("30-tank cascade, 21 outputs, window 10, default restart: at most 400 "
                      "simplex iterations per step", find(rows, "tanks_30_21", 10, "auto"),
                      400.0, "simplex_iterations_per_step"),
               target(f"30-tank cascade, 21 outputs, exact mode with noise ({min(N, 40)} "
                      "steps): at most 30 linprog per step on average",
                      find(rows, "tanks_30_21", None, "exact"), 30.0)]
    for name in ("two_mass", "vehicle", "cv_target", "random_6", "tanks_6", "tanks_15",
                 "tanks_30", "tanks_30_21"):
        r10 = find(rows, name, 10, "auto")
        if r10 is not None and np.isfinite(r10["width_ratio_mean"]):
            worst = 1.5 if name == "tanks_30_21" else 1.25
            targets.append(target(f"{name}, window 10, mean width / exact at most 1.05",
                                  r10, 1.05, "width_ratio_mean"))
            targets.append(target(f"{name}, window 10, worst width / exact at most {worst}",
                                  r10, worst, "width_ratio_worst"))
            targets.append(target(f"{name}, window 10, never narrower than the exact set "
                                  "(smallest ratio at least 1 - 1e-9)", r10, 1.0 - 1e-9,
                                  "width_ratio_min", at_least=True))
        r3 = find(rows, name, 3, "polytope")
        if r3 is not None and np.isfinite(r3["width_ratio_mean"]):
            targets.append(target(f"{name}, window 3 (polytope restart), mean width / exact "
                                  "at most 1.5", r3, 1.5, "width_ratio_mean"))
    out = {"linprog_45x40_ms": 1e3 * unit, "steps": N, "rows": rows, "targets": targets,
           "history_lp_s_per_step_checked": lp_times,
           "tanks_window10_growth_exponent": growth,
           "machine": platform.platform(), "python": platform.python_version()}
    Path(args.out).write_text(json.dumps({**stamp(), **out}, indent=1))
    print(f"growth exponent (tanks, window 10): {growth}")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
