"""Benchmark: the Li-Cong-Dong Fig. 1(b) campaign and the cost of its interval hulls.

Chang 2006 system, increments uniform in [-1, 1]^2, 100 steps, SMFDO delta = 10
and the PIO baseline. Measured in one run, side by side:

* time per SMFDO step on the fast path (default) and on the reference path
  (``fast=False``: set operations + HiGHS), for delta = 3, 10, 20, and the exact
  mode up to k = 100 (reference path);
* time per interval hull of ``P Z_k`` (delta = 10, steady state) on the fast
  path (compiled warm-started dual simplex, certified), with highspy and the
  model reused across the 2q directions (the library's reference path), and
  with a fresh cvxpy problem per LP (Clarabel) on a small sample;
* campaign wall time: ``--runs`` runs (default 5000) of SMFDO delta = 10 + the
  PIO on local processes (both cores); shorter campaigns for delta = 3 and 20
  and for the exact mode, extrapolated to 5000 runs.

Writes ``benchmarks/results/smfdo_campaign.json``. Targets: hull of
``P Z_k`` >= 20x faster than highspy reuse, <= 150 us per step (delta = 10),
5000 runs in <= 2 minutes.

Run: ``python benchmarks/smfdo_campaign.py [--runs N]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
from pathlib import Path

import numpy as np

import setobs as so
from _common import hull_cvxpy, stamp
from setobs.lp.fastlp import FixedStructureLP, hull_objectives
from setobs.studies import ObserverSpec, Scenario, rng_for_run, run_campaign


def step_times(sys, sc, window, fast, trs, k_from):
    obs = so.SMFDO(sys, window=window, increment_set=sc.increment_set(2),
                   initial_state_set=sc.initial_state_set(3), fast=fast)
    obs.step(trs[0].Y[0])  # compile / warm caches
    out = []
    for tr in trs:
        obs.reset()
        for k, y in enumerate(tr.Y):
            t0 = time.perf_counter()
            obs.step(y)
            if k >= k_from:
                out.append(time.perf_counter() - t0)
    return statistics.median(out), obs.stats


def hull_PZ_times(sys, sc, trs):
    """Per-step hull of P Z_k (delta = 10, steady state): fast vs highspy reuse, same sets."""
    obs = so.SMFDO(sys, window=10, increment_set=sc.increment_set(2),
                   initial_state_set=sc.initial_state_set(3))
    inst = []
    for tr in trs:
        obs.reset()
        for k, y in enumerate(tr.Y):
            obs.step(y)
            if k >= 15 and obs.fast_path_instance is not None:
                inst.append(obs.fast_path_instance)
    model = inst[0][0]
    lp = FixedStructureLP(model.A, hull_objectives(obs.P @ model.G), model.free,
                          model.unbounded_radius)
    state = lp.new_state()  # warm-started from step to step, as in the SMFDO
    fast_t, ref_t, sets, maxdiff = [], [], [], 0.0
    for m, c, b, h in inst:
        if m is not model:
            continue
        Pc = obs.P @ c
        t0 = time.perf_counter()
        bounds, ok = lp.minimize_all_unchecked(b, h, state)
        lo = np.nextafter(bounds[0::2] + Pc, -np.inf)
        hi = np.nextafter(Pc - bounds[1::2], np.inf)
        fast_t.append(time.perf_counter() - t0)
        assert ok.all()
        S = obs.P @ m.to_cz(c, b, h)  # a fresh set: no cached LP model
        t0 = time.perf_counter()
        box = S.interval_hull()
        ref_t.append(time.perf_counter() - t0)
        sets.append(S)
        maxdiff = max(maxdiff, float(np.max(np.abs(np.r_[lo - box.lo, hi - box.hi])
                                            / (1 + np.abs(np.r_[box.lo, box.hi])))))
    cvx_t = []
    for S in sets[:: max(1, len(sets) // 8)][:8]:
        t0 = time.perf_counter()
        hull_cvxpy(S)
        cvx_t.append(time.perf_counter() - t0)
    return (statistics.median(fast_t), statistics.median(ref_t), statistics.median(cvx_t),
            len(fast_t), maxdiff)


def campaign(sc, window, runs):
    specs = [ObserverSpec(f"SMFDO d={window}", "smfdo", {"window": window}),
             ObserverSpec("PIO (printed gains)", "pio_printed")]
    t0 = time.perf_counter()
    run_campaign(sc, specs, runs, reference_window=window, progress=False)
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=5000)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "smfdo_campaign.json"))
    args = ap.parse_args()
    sc = Scenario(system="chang2006", horizon=100, increment=1.0, x0_box=1.0)
    sys = sc.build_system()
    trs = [sc.simulate(rng_for_run(0, r)) for r in range(20)]
    res = {"benchmark": "smfdo_campaign", "setobs": so.__version__,
           "python": platform.python_version(), "machine": platform.machine(),
           "cpus": os.cpu_count()}
    steps = {}
    for window in (3, 10, 20):
        fast_med, stats = step_times(sys, sc, window, True, trs, 25)
        ref_med, _ = step_times(sys, sc, window, False, trs[:3], 25)
        steps[f"delta={window}"] = {"fast_median_us": 1e6 * fast_med,
                                    "reference_median_us": 1e6 * ref_med,
                                    "speedup": ref_med / fast_med, "fast_path_steps": stats}
    ex_med, _ = step_times(sys, sc, None, True, trs[:2], 0)
    steps["exact (k = 0..99, reference path)"] = {"median_us": 1e6 * ex_med}
    res["smfdo_step"] = steps
    fast_h, ref_h, cvx_h, n_h, maxdiff = hull_PZ_times(sys, sc, trs)
    res["hull_PZ_delta10"] = {
        "fast_median_us": 1e6 * fast_h, "highspy_reuse_median_us": 1e6 * ref_h,
        "cvxpy_fresh_median_us": 1e6 * cvx_h, "speedup_vs_highspy": ref_h / fast_h,
        "speedup_vs_cvxpy": cvx_h / fast_h, "sets": n_h,
        "max_rel_difference_vs_highspy": maxdiff}
    camp = {}
    wall = campaign(sc, 10, args.runs)
    camp["delta=10"] = {"runs": args.runs, "wall_s": wall,
                        "extrapolated_5000_runs_min": 5000 * wall / args.runs / 60}
    small = max(1, min(args.runs, 500))
    for window in (3, 20):
        wall = campaign(sc, window, small)
        camp[f"delta={window}"] = {"runs": small, "wall_s": wall,
                                   "extrapolated_5000_runs_min": 5000 * wall / small / 60}
    ex_runs = max(1, min(args.runs, 16))
    wall = campaign(sc, None, ex_runs)
    camp["exact"] = {"runs": ex_runs, "wall_s": wall,
                     "extrapolated_5000_runs_min": 5000 * wall / ex_runs / 60}
    res["campaign_smfdo_plus_pio"] = camp
    res["targets"] = {"smfdo_step_us": 150, "hull_speedup_vs_highspy": 20,
                      "campaign_5000_runs_min": 2}
    res["targets_met"] = {
        "smfdo_step": steps["delta=10"]["fast_median_us"] <= 150,
        "hull_speedup": res["hull_PZ_delta10"]["speedup_vs_highspy"] >= 20,
        "campaign": camp["delta=10"]["extrapolated_5000_runs_min"] <= 2}
    print(json.dumps(res, indent=2))
    Path(args.out).write_text(json.dumps({**stamp(), **res}, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
