"""Benchmark: the SMFDO with measurement noise on the 20 000-sample HSM150 motor record.

Window 10, position quantised to one encoder count (the noise set), 1 kHz. The
whole record on the fast path (total time, time per step, fast-path share),
in the same run as:

* the noise-free step on the same model: a noise-free record simulated from the
  motor model with the record's own input and a smoothly varying load torque
  (the measured record itself is inconsistent without a noise set);
* the reference path (set operations + HiGHS) on a sample of the record.

Two settings of the increment bound: ``2 Mn`` per sample (any jump within the
rig's nominal torque: consistent at one count) and 1e-3 N m per sample with
three counts of noise (quantisation plus the sampling-time jitter the record
shows). Writes ``benchmarks/results/smfdo_noise.json``.

Run: ``python benchmarks/smfdo_noise.py [--data PATH] [--steps N]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys as _sys
import time
from pathlib import Path

import numpy as np
from scipy.io import loadmat

import setobs as so

_sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.datasets import HSM150  # (the data stay outside the package)

from _common import stamp


def timed_run(obs, Y, U):
    t0 = time.perf_counter()
    res = obs.run(Y, U)
    return time.perf_counter() - t0, res


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=str(HSM150) if HSM150 else None)
    ap.add_argument("--steps", type=int, default=20_000)
    ap.add_argument("--reference-steps", type=int, default=500)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results"
                                         / "smfdo_noise.json"))
    args = ap.parse_args()
    if not args.data:
        raise SystemExit("the HSM150 record was not found: pass --data PATH")
    m = loadmat(args.data, squeeze_me=True)
    data = m["data"][: args.steps]
    J, B, T, Mn = (float(m[k]) for k in ("J", "B", "Tvz", "Mn"))
    sys = so.examples.servo_motor(J, B, T)
    count = 2 * np.pi / 10_000
    Y, U = data[:, 2:3], data[:, 4:5]
    N = len(Y)
    rows = []
    for label, inc, noise in (("1 count, |dd| <= 2 Mn", 2 * Mn, count),
                              ("3 counts, |dd| <= 1e-3", 1e-3, 3 * count)):
        obs = so.SMFDO(sys, window=10, increment_set=[inc], measurement_noise=noise)
        t, res = timed_run(obs, Y, U)
        rows.append({"setting": label, "path": "fast", "steps": N, "total_s": t,
                     "us_per_step": 1e6 * t / N, "fast_steps": obs.stats["fast"],
                     "consistent": res.consistent,
                     "median_radius_Nm": float(np.median(res.error_bound[20:]))})
        if label.startswith("3"):
            n_ref = min(args.reference_steps, N)
            ref = so.SMFDO(sys, window=10, increment_set=[inc], measurement_noise=noise,
                           fast=False)
            t_ref, res_ref = timed_run(ref, Y[:n_ref], U[:n_ref])
            rows.append({"setting": label, "path": "reference", "steps": n_ref,
                         "total_s": t_ref, "us_per_step": 1e6 * t_ref / n_ref,
                         "max_abs_diff_vs_fast": float(np.nanmax(np.abs(
                             res_ref.hi[20:] - res.hi[20:n_ref])))})
    # Noise-free step on the same model (the measured record needs noise: simulate).
    rng = np.random.default_rng(0)
    D = 0.04 + np.concatenate([[0.0], np.cumsum(rng.uniform(-1e-3, 1e-3, N - 1))])
    Ysim = sys.simulate(D[:, None], U[:N])[0]
    obs = so.SMFDO(sys, window=10, increment_set=[1e-3])
    t0, _ = timed_run(obs, Ysim, U)
    rows.append({"setting": "noise-free (simulated), |dd| <= 1e-3", "path": "fast",
                 "steps": N, "total_s": t0, "us_per_step": 1e6 * t0 / N,
                 "fast_steps": obs.stats["fast"]})
    noisy = [r for r in rows if r["path"] == "fast" and "count" in r["setting"]]
    for r in noisy:
        r["step_cost_vs_noise_free"] = r["us_per_step"] / rows[-1]["us_per_step"]
    for r in rows:
        print(f"{r['setting']:>40} [{r['path']:>9}]: {r['total_s']:6.2f} s for {r['steps']} "
              f"steps, {r['us_per_step']:7.1f} us/step"
              + (f" ({r['step_cost_vs_noise_free']:.2f}x noise-free)"
                 if "step_cost_vs_noise_free" in r else ""))
    out = {"benchmark": "smfdo_noise", "record": "HSM150 idf_pos_0.06_1 (1 kHz, 20 000)",
           "window": 10, "setobs": so.__version__, "python": platform.python_version(),
           "machine": platform.machine(), "cpus": os.cpu_count(), "results": rows}
    Path(args.out).write_text(json.dumps({**stamp(), **out}, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
