"""Benchmark: how much wider the window's early stop makes the bands.

The window's hull LPs stop once their certified duality gap is at most ``WINDOW_REL_GAP``
times the coordinate's width at the previous window step
(:mod:`setobs.setmembership._closed_form`). Each bound is certified; within one step a band is
at most ``2 WINDOW_REL_GAP`` of its width wider than the window LP's hull, but the
restart box carries a step's widening into the next windows, so over a record the bands
can widen by more. This measures it: random stable plants (3-8 states, 1-3 outputs,
noise uniform or on the corners, window 10, restart ``auto`` and ``box``) run with the
default gap and with the gap off (every LP to its optimum), and the relative excess of
each band over the gap-off band, ``(w_gap - w_off) / w_off``, over every finite band
after the first window, and the same excess against the larger of the band's width and
its width a step before (the scale of the rule: where the set collapses to a point at a
step the band's own width is at rounding level).

Writes ``benchmarks/results/early_stop.json`` (stamped with the commit and the date).
Run: ``python benchmarks/early_stop.py [PLANTS]``.
"""

from __future__ import annotations

import json
import sys
import warnings
from pathlib import Path

import numpy as np

import setobs as so
from setobs.setmembership import _closed_form

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))
from tests.datasets import random_stable_record  # noqa: E402

from _common import stamp  # noqa: E402


def bands(sysm, Y, rw, rv, restart: str, gap: float) -> np.ndarray:
    old = _closed_form.WINDOW_REL_GAP
    _closed_form.WINDOW_REL_GAP = gap
    try:
        n = sysm.n
        obs = so.SMFDO(sysm, window=10, restart=restart, process_noise=rw,
                       measurement_noise=rv, state_bounds=True,
                       initial_state_set=so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n)))
        res = obs.run(Y)
    finally:
        _closed_form.WINDOW_REL_GAP = old
    return res.state_hi - res.state_lo


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 40
    warnings.simplefilter("ignore")
    rows = []
    for seed in range(count):
        sysm, Y, rw, rv = random_stable_record(seed)
        for restart in ("auto", "box"):
            w0 = bands(sysm, Y, rw, rv, restart, 0.0)
            for gap in (1e-4, 1e-3):
                w1 = bands(sysm, Y, rw, rv, restart, gap)
                fin = np.isfinite(w0) & np.isfinite(w1) & (w0 > 0)
                fin[:10] = False
                ex = (w1[fin] - w0[fin]) / w0[fin]
                # (against the larger of the band's width and its width a step before,
                # the scale the stop's rule is relative to: a band that collapses at a
                # step, a set pinned to a point, is not measured against its collapse)
                scale = np.maximum(w0, np.vstack([w0[:1], w0[:-1]]))
                ex_prev = (w1[fin] - w0[fin]) / scale[fin]
                rows.append({"seed": seed, "n": sysm.n, "l": sysm.l, "restart": restart,
                             "rel_gap": gap, "mean_excess": float(ex.mean()),
                             "max_excess": float(ex.max()), "min_excess": float(ex.min()),
                             "max_excess_prev": float(ex_prev.max()),
                             "collapsed_bands": int((w0[fin] < 1e-6 * scale[fin]).sum())})
            print(seed, restart, [f"{r['max_excess']:.2e}" for r in rows[-2:]], flush=True)
    summary = {}
    for gap in (1e-4, 1e-3):
        sel = [r for r in rows if r["rel_gap"] == gap]
        mx = np.array([r["max_excess"] for r in sel])
        mean = np.array([r["mean_excess"] for r in sel])
        prev = np.array([r["max_excess_prev"] for r in sel])
        summary[str(gap)] = {"max_excess": float(mx.max()),
                             "p95_of_run_max": float(np.quantile(mx, 0.95)),
                             "median_of_run_max": float(np.median(mx)),
                             "mean_excess": float(mean.mean()),
                             "median_of_run_mean": float(np.median(mean)),
                             "min_excess": float(min(r["min_excess"] for r in sel)),
                             "max_excess_of_the_larger_width": float(prev.max()),
                             "p95_excess_of_the_larger_width": float(np.quantile(prev, 0.95)),
                             "runs_with_collapsed_bands": int(sum(r["collapsed_bands"] > 0
                                                                  for r in sel))}
    out = {**stamp(), "plants": count, "window": 10, "steps": 120, "summary": summary,
           "rows": rows}
    path = HERE / "results" / "early_stop.json"
    path.write_text(json.dumps(out, indent=1) + "\n")
    print(json.dumps(summary, indent=1))


if __name__ == "__main__":
    main()
