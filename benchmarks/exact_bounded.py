"""Exact mode with noise over a bounded history (``setobs.setmembership._bounded``) on
three 30-state plants: the cost per step, the history length it keeps, and its bounds
against an independent whole-history LP.

Plants (each with noise on every state and every output, ``x_0`` in a box):

* ``fast cascade``: the 30-tank cascade with 21 levels measured of
  ``state_estimation.py`` (slowest mode 0.82 per step), 235 steps, ``|x_0| <= 2``: the
  record of ``exact_long.py`` (the whole-history LP, for the comparison);
* ``slow cascade``: unequal tanks sampled at ``dt = 0.1`` (``window_worst.py``; slowest
  mode 0.995 per step), ``|x_0| <= 5``;
* ``dense random``: a dense random 30-state plant (spectral radius 0.9), 12 random
  outputs.

Per step: milliseconds and linprog units (:func:`_common.linprog_unit`), HiGHS's simplex
iterations (every solve of the step) and microseconds per iteration, the outer LP's
history length, the status. At the ``--check`` steps every state band is compared with
``tests.oracles.history_lp_highs`` (states as variables, each LP on a fresh HiGHS model,
unscaled): the largest excess over it as a fraction of the width (the bounds' distance
from the exact set), the largest deficit (inside it: never above the oracle's own
tolerance), and the truth inside.

The bounded history is exact mode's default (``_bounded.BOUNDED``); this benchmark
makes sure it is on. Run:
``python benchmarks/exact_bounded.py [--plants fast,slow,dense] [--steps 235,120,120]``;
writes ``benchmarks/results/exact_bounded.json``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

from tests.oracles import history_lp_highs  # noqa: E402

import setobs as so  # noqa: E402
from _common import count_solves, linprog_unit, stamp  # noqa: E402
from setobs.lp import highs  # noqa: E402
from setobs.setmembership import _bounded  # noqa: E402
from state_estimation import noisy_record, record, tanks_outputs  # noqa: E402
from window_worst import slow_cascade  # noqa: E402


def plant(name: str, N: int):
    """``(A, B, C, rw, rv, R0, X, Y, U)`` of a plant and its record."""
    if name == "fast":
        A, B, C, rw, rv = tanks_outputs(30, 21)
        X, Y, U = record(A, B, C, rw, rv, N, 0)
        return A, B, C, rw, rv, 2.0, X, Y, U
    rng = np.random.default_rng(3)
    if name == "slow":
        A, B, C = slow_cascade()
        rw, rv, R0 = 1e-3, 1e-2, 5.0
    else:
        M = rng.normal(size=(30, 30))
        A = 0.9 * M / np.max(np.abs(np.linalg.eigvals(M)))
        B = rng.normal(size=(30, 1))
        C = rng.normal(size=(12, 30))
        rw, rv, R0 = 1e-2, 1e-2, 2.0
    U = np.sin(0.05 * np.arange(N))[:, None] + 0.2 * rng.normal(size=(N, 1))
    X, Y = noisy_record(A, B, C, U, rw, rv, rng)
    return A, B, C, rw, rv, R0, X, Y, U


def run(name: str, N: int, checks_at: set[int]) -> dict:
    A, B, C, rw, rv, R0, X, Y, U = plant(name, N)
    n, ny = A.shape[0], C.shape[0]
    X0 = so.Box(-R0 * np.ones(n), R0 * np.ones(n))
    if name != "fast":  # (the record starts in [-1, 1]^n: inside)
        assert np.all(np.abs(X[0]) <= R0)
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((n, 0)), C, B), window=None,
                   measurement_noise=rv, state_bounds=True, initial_state_set=X0,
                   process_noise=rw)
    solves: list[tuple[int, float]] = []
    plain = count_solves(solves)
    unit = linprog_unit()
    steps, checks = [], []
    lo, hi = np.empty((N, n)), np.empty((N, n))
    try:
        for k in range(N):
            solves.clear()
            t0 = time.perf_counter()
            est = obs.step(Y[k], U[k])
            dt = time.perf_counter() - t0
            lo[k], hi[k] = est.state_lo, est.state_hi
            length = obs.history_length
            its = sum(s[0] for s in solves)
            steps.append({"k": k, "ms": 1e3 * dt, "iterations": its,
                          "us_per_iteration": 1e6 * sum(s[1] for s in solves) / max(its, 1),
                          "history": length, "status": est.status})
            if k % 10 == 0:
                unit = min(unit, linprog_unit())
            print(f"{name} k={k:3d} {1e3 * dt:8.1f} ms it {its:5d} L {length} {est.status}",
                  file=sys.stderr, flush=True)
            if k in checks_at:
                with highs_plain(plain):
                    ref = history_lp_highs(A, np.zeros((n, 0)), C, Y, k, 0.0, U=U, Gamma=B,
                                           states=True, x_box=(X0.lo, X0.hi),
                                           noise_w=(np.eye(n), np.full(n, rw)),
                                           noise_v=(np.eye(ny), np.full(ny, rv)),
                                           unscaled=True)
                wid = ref[1] - ref[0]
                excess = np.maximum(ref[0] - lo[k], hi[k] - ref[1]) / wid
                checks.append({"k": k, "status": est.status,
                               "largest_excess_over_width": float(excess.max()),
                               "largest_deficit_over_width": float(max(0.0, -excess.min())),
                               "mean_width": float(wid.mean())})
                print(f"  check k={k}: {checks[-1]}", file=sys.stderr, flush=True)
    finally:
        highs.solve = plain
    ms = np.array([s["ms"] for s in steps])
    its = np.array([s["iterations"] for s in steps])
    st = [s["status"] for s in steps]
    hist = [s["history"] for s in steps if s["history"] is not None]
    blocks = {}
    for a in range(0, N, 40):
        sl = slice(a, min(a + 40, N))
        blocks[f"{a}-{min(a + 40, N) - 1}"] = {
            "mean_per_linprog": float(ms[sl].mean() / 1e3 / unit),
            "mean_iterations": float(its[sl].mean()),
            "mean_us_per_iteration": float(np.mean([s["us_per_iteration"]
                                                    for s in steps[sl]])),
            "mean_history": float(np.mean([s["history"] or 0 for s in steps[sl]]))}
    return {"plant": name, "steps": N, "linprog_ms": 1e3 * unit,
            "mean_per_linprog": float(ms.mean() / 1e3 / unit),
            "mean_iterations": float(its.mean()),
            "statuses": {s: st.count(s) for s in sorted(set(st))},
            "longest_history": max(hist) if hist else None,
            "final_history": hist[-1] if hist else None,
            "truth_inside": bool(np.all((X[:N] >= lo) & (X[:N] <= hi))),
            "blocks": blocks, "checks": checks, "per_step": steps}


class highs_plain:
    """The oracle's solves uncounted (it builds its own models through scipy/highspy)."""

    def __init__(self, plain):
        self.plain = plain

    def __enter__(self):
        self.saved, highs.solve = highs.solve, self.plain

    def __exit__(self, *exc):
        highs.solve = self.saved


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plants", default="fast,slow,dense")
    ap.add_argument("--steps", default="235,120,120")
    ap.add_argument("--check", default="60,119,234")
    ap.add_argument("--out", default=str(HERE / "results" / "exact_bounded.json"))
    ap.add_argument("--keep", action="store_true",
                    help="keep the other plants' runs already in --out (each its own stamp)")
    args = ap.parse_args()
    names = args.plants.split(",")
    Ns = [int(v) for v in args.steps.split(",")]
    checks_at = {int(c) for c in args.check.split(",") if c}
    _bounded.BOUNDED = True
    out = {**stamp(), "target_mean_per_linprog": 30.0,
           "constants": {c: getattr(_bounded, c) for c in ("CUT_START", "CUT_RETRY",
                                                           "TRIAL_STEPS", "INNER_HISTORY",
                                                           "DROP_FRACTION", "MIN_HISTORY",
                                                           "POINT_BATCHES")},
           "whole_history_reference": "exact_long.json (the fast cascade's record, the "
                                      "whole-history LP)", "plants": []}
    if args.keep and Path(args.out).exists():
        old = json.loads(Path(args.out).read_text())
        out["plants"] = [{**p, "stamp": p.get("stamp", {k: old.get(k) for k in stamp()})}
                         for p in old["plants"] if p["plant"] not in names]
    for name, N in zip(names, Ns, strict=True):
        out["plants"].append({**run(name, N, checks_at), "stamp": stamp()})
        Path(args.out).write_text(json.dumps(out, indent=1))
    print(json.dumps([{k: v for k, v in p.items() if k != "per_step"} for p in out["plants"]],
                     indent=1))


if __name__ == "__main__":
    main()
