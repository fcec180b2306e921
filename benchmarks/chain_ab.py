"""Benchmark: A/B of the objective chain and of the restarts' support values.

Each variant runs in a fresh process (the fast path's structures are cached per process
and keep the order they were built with):

* ``window``: window 10 (default restart) with the objective chain
  (``setobs.lp.fastlp.PRIMAL_CHAIN``, ``CHAIN_ORDER``) on and off: time per step and
  simplex iterations per step;
* ``exact``: exact mode with noise with ``setobs.lp.boxlp``'s chain on (for any number
  of bounds) and off (one HiGHS model per bound): time per step;
* ``support``: the constant-velocity target at window 10 with the restart's support
  values on and off (``setobs.setmembership.engines.window.SUPPORT_RANGES``), restart depth
  30 and 60: mean / worst width against the whole-history LP (from k = 25, every fifth
  step).

Plants and records are those of ``benchmarks/state_estimation.py``; time per step in
units of one 45 x 40 ``scipy.optimize.linprog`` timed around each run (the faster).
Writes ``benchmarks/results/chain_ab.json``.

Run: ``python benchmarks/chain_ab.py``.
"""

from __future__ import annotations

import json
import platform
import subprocess
import sys
import time
from pathlib import Path

from _common import stamp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

CASES = [("window", "random_6", 120), ("window", "vehicle", 120),
         ("window", "tanks_30_21", 30),
         ("exact", "two_mass", 120), ("exact", "vehicle", 120), ("exact", "random_6", 120),
         ("exact", "tanks_30_21", 30),
         ("support", "cv_target", 120)]


def plant(name):
    from state_estimation import cv_target, random_system, tanks_outputs, two_mass, vehicle

    return {"two_mass": two_mass, "vehicle": vehicle, "cv_target": cv_target,
            "random_6": lambda: random_system(6, 4, 3),
            "tanks_30_21": lambda: tanks_outputs(30, 21)}[name]()


def one(kind: str, name: str, N: int, on: bool, depth: int) -> dict:
    """One variant, in this process."""
    import numpy as np
    from tests.oracles import history_lp_highs

    import setobs as so
    from _common import linprog_unit
    from setobs.lp import boxlp, fastlp
    from setobs.setmembership.engines import window as window_engine
    from state_estimation import noise_model, record

    fastlp.PRIMAL_CHAIN = fastlp.CHAIN_ORDER = on if kind == "window" else True
    boxlp.CHAIN = on if kind == "exact" else True
    boxlp.CHAIN_MIN_OBJECTIVES = 1
    window_engine.SUPPORT_RANGES = on if kind == "support" else True
    A, B, C, rw, rv = plant(name)
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, N, 0)
    nkw, noise_w = noise_model(rw, n)
    X0 = so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n))
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((n, 0)), C, B),
                   window=None if kind == "exact" else 10, restart_depth=depth,
                   measurement_noise=rv, state_bounds=True, initial_state_set=X0, **nkw)
    unit0 = linprog_unit()
    t0 = time.perf_counter()
    res = obs.run(Y, U)
    dt = (time.perf_counter() - t0) / N
    unit = min(unit0, linprog_unit())
    p, d = obs.simplex_iterations
    out = {"kind": kind, "system": name, "steps": N, "on": on, "restart_depth": depth,
           "ms_per_step": 1e3 * dt, "per_linprog": dt / unit, "linprog_ms": 1e3 * unit,
           "simplex_iterations_per_step": (p + d) / N,
           "truth_inside": bool(np.all((X >= res.state_lo) & (X <= res.state_hi))),
           "stats": dict(obs.stats)}
    if kind == "support":
        ks = list(range(25, N, 5))
        r = []
        for k in ks:
            lo, hi = history_lp_highs(A, np.zeros((n, 0)), C, Y, k, 0.0, U=U, Gamma=B,
                                      states=True, x_box=(X0.lo, X0.hi), noise_w=noise_w,
                                      noise_v=(np.eye(C.shape[0]),
                                               np.full(C.shape[0], rv)))
            r.append((res.state_hi[k] - res.state_lo[k]) / (hi - lo))
        r = np.array(r)
        out.update(width_ratio_mean=float(r.mean()), width_ratio_worst=float(r.max()),
                   width_ratio_min=float(r.min()))
    return out


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--one":
        kind, name, N, on, depth = sys.argv[2:7]
        print(json.dumps(one(kind, name, int(N), on == "1", int(depth))))
        return
    rows = []
    for kind, name, N in CASES:
        for depth in ((30, 60) if kind == "support" else (60,)):
            for on in (True, False):
                proc = subprocess.run([sys.executable, __file__, "--one", kind, name, str(N),
                                       "1" if on else "0", str(depth)],
                                      capture_output=True, text=True, check=True)
                row = json.loads(proc.stdout.strip().splitlines()[-1])
                rows.append(row)
                extra = (f"  ratio {row['width_ratio_mean']:.3f} / "
                         f"{row['width_ratio_worst']:.3f}" if kind == "support" else "")
                print(f"{kind:8s} {name:12s} depth {depth} on={on!s:5s} "
                      f"{row['ms_per_step']:9.2f} ms/step ({row['per_linprog']:8.2f} LP) "
                      f"it {row['simplex_iterations_per_step']:8.0f}{extra}", flush=True)
    out = {"rows": rows, "machine": platform.platform(), "python": platform.python_version()}
    path = HERE / "results" / "chain_ab.json"
    path.write_text(json.dumps({**stamp(), **out}, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
