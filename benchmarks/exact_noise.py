"""Benchmark: exact mode with noise against the whole-history LP.

Exact mode with process and measurement noise keeps the whole-history LP and
warm-starts it from step to step (``setobs.setmembership._history``). Here, on
240-step records of our own plants with noise on every state and output and a
known input (``benchmarks/state_estimation.py``: the bicycle model, 4 states and
2 outputs; the two masses, 4 states and 1 output; a random 6-state plant with 4
outputs), with ``state_bounds=True``:

* the time per update around k = 30, 60, 120, 180, 239 (median of 11 steps);
* the unit of the issue's target, in the same run: **one** whole-history LP of
  the state at the same k, built here with scipy.sparse (every state, noise and
  measurement a variable or a row, as ``tests.oracles.history_lp_highs``) and
  solved from scratch by ``scipy.optimize.linprog`` (HiGHS, tolerances 1e-10);
  the build is not timed, the median over the 2 n directions is;
* the largest distance of exact mode's bounds (``margin=0``: as certified, without
  the SMFDO's outward margin of 1e-9 of ``max(1, |bound|)``) from that LP's
  optimum over the checked steps, relative to ``max(1, |bound|)`` and to the
  band's width, whether any bound was narrower than the LP's (it may be, by the
  LP's own tolerance: the LP is a float solve, not certified), and whether the
  truth stayed inside at every step;
* on the bicycle model up to k = 120, the set recursion that exact mode used
  with noise before (``fast=False``), in the same run.

Target: at most 8 history-LP times per step over the record, equal to the LP
within 1e-6. Writes ``benchmarks/results/exact_noise.json``.

Run: ``python benchmarks/exact_noise.py [--steps 240] [--no-reference]``.
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

HERE = Path(__file__).resolve().parent
_sys.path.insert(0, str(HERE.parent))
_sys.path.insert(0, str(HERE))

from tests.oracles import solve_state_history_lp, state_history_lp  # noqa: E402

import setobs as so  # noqa: E402
from _common import stamp, state_bands  # noqa: E402
from state_estimation import random_system, record, two_mass, vehicle  # noqa: E402

CHECK = (30, 60, 120, 180, 239)


def study(name, plant, N, reference_k):
    A, B, C, rw, rv = plant
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, N, 0)
    X0 = so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n))
    sys = so.LinearSystem(A, np.zeros((n, 0)), C, B)
    kw = dict(process_noise=rw, measurement_noise=rv, state_bounds=True, initial_state_set=X0)
    # margin=0: the bounds as certified (the default outward margin of 1e-9 of
    # max(1, |bound|) alone is 1e-4 of the bicycle's position band at k = 239)
    obs = so.SMFDO(sys, window=None, margin=0.0, **kw)
    times, lo, hi = state_bands(obs, Y, U)
    inside = bool(np.all((X >= lo) & (X <= hi)))
    rows = []
    for k in CHECK:
        if k >= N:
            continue
        rlo, rhi, lp_times = solve_state_history_lp(
            *state_history_lp(A, B, C, Y, U, k, rw, rv, (X0.lo, X0.hi)), n)
        unit = statistics.median(lp_times)
        step = statistics.median(times[max(0, k - 5):k + 6])
        dev = np.maximum(rlo - lo[k], hi[k] - rhi)
        rows.append({"k": k, "ms_per_update": 1e3 * step, "one_history_lp_ms": 1e3 * unit,
                     "per_history_lp": step / unit,
                     "max_deviation_rel_magnitude": float(
                         np.max(np.abs(dev) / np.maximum(1.0, np.abs(np.r_[rlo, rhi]).reshape(
                             2, -1).max(axis=0)))),
                     "max_deviation_rel_width": float(np.max(np.abs(dev) / (rhi - rlo))),
                     "narrower_than_lp": bool(np.any(dev < 0))})
        r = rows[-1]
        print(f"{name:9s} k={k:3d} {r['ms_per_update']:7.1f} ms/update, one LP "
              f"{r['one_history_lp_ms']:6.1f} ms: {r['per_history_lp']:5.2f} LP; deviation "
              f"{r['max_deviation_rel_magnitude']:.1e} of |x|, "
              f"{r['max_deviation_rel_width']:.1e} of the width", flush=True)
    out = {"system": name, "n": n, "l": C.shape[0], "steps": N, "checked": rows,
           "worst_per_history_lp": max(r["per_history_lp"] for r in rows),
           "total_s": float(sum(times)), "truth_inside": inside, "stats": dict(obs.stats)}
    if reference_k:
        ref = so.SMFDO(sys, window=None, fast=False, **kw)
        rt = []
        for k in range(reference_k + 1):
            t0 = time.perf_counter()
            ref.step(Y[k], None if U is None else U[k])
            rt.append(time.perf_counter() - t0)
        out["set_recursion_ms_per_update"] = {
            str(k): 1e3 * statistics.median(rt[max(0, k - 5):k + 6])
            for k in CHECK if k <= reference_k}
        print(f"{name:9s} set recursion (before): {out['set_recursion_ms_per_update']}",
              flush=True)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=240)
    ap.add_argument("--no-reference", action="store_true")
    ap.add_argument("--out", default=str(HERE / "results" / "exact_noise.json"))
    args = ap.parse_args()
    ref_k = 0 if args.no_reference else 120
    systems = [study("vehicle", vehicle(), args.steps, ref_k),
               study("two_mass", two_mass(), args.steps, 0),
               study("random_6", random_system(6, 4, 3), args.steps, 0)]
    out = {"benchmark": "exact_noise", "target_per_history_lp": 8.0,
           "target_deviation": 1e-6, "systems": systems,
           "targets_met": all(s["worst_per_history_lp"] <= 8.0 and s["truth_inside"]
                              and all(r["max_deviation_rel_magnitude"] <= 1e-6
                                      for r in s["checked"]) for s in systems),
           "machine": platform.machine(), "python": platform.python_version(),
           "setobs": so.__version__}
    Path(args.out).write_text(json.dumps({**stamp(), **out}, indent=2) + "\n")
    print("targets met:", out["targets_met"])


if __name__ == "__main__":
    main()
