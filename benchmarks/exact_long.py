"""Exact mode with noise over a long record of the 30-tank cascade with 21 outputs: the
cost per step as the whole-history LP grows, and where it goes.

Per step: milliseconds and linprog units (:func:`_common.linprog_unit`, timed before and
after, the faster kept), HiGHS's simplex iterations and its number of solves (every
``hs.run()`` of the step, counted around :func:`setobs.lp.highs.solve`), the time spent
inside those solves, the LP's size, and which engine decided the step
(``SMFDO.stats``). At the ``--check`` steps the hull is compared with the independent
whole-history LP (``tests.oracles.history_lp_highs``, states as variables, each LP on a
fresh HiGHS model without scaling).

Run: ``python benchmarks/exact_long.py [--steps 235] [--check 40,120,186,234]``; writes
``benchmarks/results/exact_long.json``.
"""

from __future__ import annotations

import argparse
import gc
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).parent))

from tests.oracles import history_lp_highs

import setobs as so
from _common import count_solves, linprog_unit, stamp
from setobs.lp import highs
from state_estimation import noise_model, record, tanks_outputs


def summary(steps, X, lo, hi, obs, unit, checks, N) -> dict:
    """The results so far (``completed_steps`` of the ``N`` asked for)."""
    K = len(steps)
    ms = np.array([s["ms"] for s in steps])
    its = np.array([s["iterations"] for s in steps])
    blocks = {}
    for a, b in ((0, 40), (40, 80), (80, 120), (120, 160), (160, 200), (200, N)):
        if a < K:
            sl = slice(a, min(b, K))
            blocks[f"{a}-{min(b, K) - 1}"] = {
                "mean_per_linprog": float(ms[sl].mean() / 1e3 / unit),
                "max_per_linprog": float(ms[sl].max() / 1e3 / unit),
                "mean_iterations": float(its[sl].mean()),
                "mean_ms_per_iteration": float(sum(s["solve_ms"] for s in steps[sl])
                                               / max(1, its[sl].sum())),
                "mean_solves": float(np.mean([s["solves"] for s in steps[sl]]))}
    return {"system": "tanks_30_21", "steps": N, "completed_steps": K,
            "linprog_ms": 1e3 * unit, "mean_per_linprog": float(ms.mean() / 1e3 / unit),
            "truth_inside": bool(np.all((X >= lo) & (X <= hi))),
            "stats": dict(obs.stats), "blocks": blocks, "checks": checks,
            "target_mean_per_linprog": 30.0, "per_step": steps}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=235)
    ap.add_argument("--check", default="40,120,186,234",
                    help="steps compared with the oracle (comma-separated)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "exact_long.json"))
    args = ap.parse_args()
    N = args.steps
    A, B, C, rw, rv = tanks_outputs(30, 21)
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, N, 0)
    X0 = so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n))
    nkw, noise_w = noise_model(rw, n)
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((n, 0)), C, B), window=None,
                   measurement_noise=rv, state_bounds=True, initial_state_set=X0, **nkw)
    solves: list[tuple[int, float]] = []
    plain = count_solves(solves)
    steps, checks = [], []
    checks_at = {int(c) for c in args.check.split(",") if c}
    unit = linprog_unit()
    lo = np.empty((N, n))
    hi = np.empty((N, n))
    for k in range(N):
        solves.clear()
        before = dict(obs.stats)
        t0 = time.perf_counter()
        est = obs.step(Y[k], U[k])
        dt = time.perf_counter() - t0
        lo[k], hi[k] = est.state_lo, est.state_hi
        engine = [key for key, v in obs.stats.items()
                  if isinstance(v, int) and v > before.get(key, 0)]
        hist = [o for o in gc.get_objects() if type(o).__name__ == "HistoryLP"]
        size = [int(hist[0].box_lp.n_row), int(hist[0].box_lp.n_col)] if len(hist) == 1 else None
        steps.append({"k": k, "ms": 1e3 * dt, "iterations": sum(s[0] for s in solves),
                      "solves": len(solves), "solve_ms": 1e3 * sum(s[1] for s in solves),
                      "lp_size": size, "engine": engine})
        if k % 10 == 0:
            unit = min(unit, linprog_unit())
        print(f"k={k:3d} {1e3 * dt:8.1f} ms {dt / unit:7.1f} LP  it {steps[-1]['iterations']:5d}"
              f"  solves {len(solves):3d}  {engine}", file=sys.stderr, flush=True)
        # (a partial file every step: the run may be stopped before its end)
        Path(args.out).write_text(json.dumps(
            summary(steps, X[:k + 1], lo[:k + 1], hi[:k + 1], obs, unit, checks, N), indent=1))
        if k in checks_at:
            ref = history_lp_highs(A, np.zeros((n, 0)), C, Y, k, 0.0, U=U, Gamma=B, states=True,
                                   x_box=(X0.lo, X0.hi), noise_w=noise_w,
                                   noise_v=(np.eye(C.shape[0]), np.full(C.shape[0], rv)),
                                   unscaled=True)
            wid = ref[1] - ref[0]
            dev = float(np.max(np.maximum(np.abs(lo[k] - ref[0]), np.abs(hi[k] - ref[1])) / wid))
            checks.append({"k": k, "largest_distance_over_width": dev,
                           "narrower": bool(np.any(lo[k] > ref[0] + 1e-9 * wid)
                                            or np.any(hi[k] < ref[1] - 1e-9 * wid))})
            print(f"  check k={k}: largest distance {dev:.2e} of the width", file=sys.stderr,
                  flush=True)
    highs.solve = plain
    out = summary(steps, X, lo, hi, obs, unit, checks, N)
    Path(args.out).write_text(json.dumps({**stamp(), **out}, indent=1))
    print(json.dumps({k: v for k, v in out.items() if k != "per_step"}, indent=1))


if __name__ == "__main__":
    main()
