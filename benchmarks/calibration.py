"""Benchmark: noise calibration (one sparse HiGHS LP) on the 20 000-sample HSM150 record.

The smallest position-noise bound that makes the whole motor record consistent
with ``|dd| <= 2 Mn`` (the rig's nominal torque, twice: any jump), for record
lengths 2 000 / 5 000 / 10 000 / 20 000 samples (target: 20 000 in <= 10 s
on this 2-core machine, ``holdout=0``: the record's own smallest bound), the validated
calibration the README runs with (``|dd| <= 1e-3`` N m per sample, calibrated on 70 %,
validated on the rest, 10 % safety), and the trade-off curve on a decimated record
(every 10th sample, 100 Hz model). Writes ``benchmarks/results/calibration.json``.

Run: ``python benchmarks/calibration.py [--data PATH]``.
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


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", default=str(HSM150) if HSM150 else None)
    args = ap.parse_args()
    if not args.data:
        raise SystemExit("the HSM150 record is not available (give --data PATH)")
    m = loadmat(args.data, squeeze_me=True)
    data = m["data"]
    J, B, Ts, Mn = (float(m[k]) for k in ("J", "B", "Tvz", "Mn"))
    sys = so.examples.servo_motor(J, B, Ts)
    count = 2 * np.pi / 10_000
    rows = []
    for N in (2_000, 5_000, 10_000, 20_000):
        t0 = time.perf_counter()
        cal = so.calibrate_noise(sys, data[:N, 2:3], data[:N, 4:5], increment=2 * Mn,
                                 holdout=0)
        dt = time.perf_counter() - t0
        rows.append({"samples": N, "seconds": round(dt, 3),
                     "minimal_noise_rad": float(cal.minimal[0]),
                     "minimal_noise_counts": round(float(cal.minimal[0]) / count, 4)})
        print(rows[-1])
    t0 = time.perf_counter()
    val = so.calibrate_noise(sys, data[:, 2:3], data[:, 4:5], increment=1e-3)
    t_val = time.perf_counter() - t0
    validated = {"increment_Nm": 1e-3, "holdout": val.holdout, "seconds": round(t_val, 3),
                 "minimal_counts": round(float(val.minimal[0]) / count, 4),
                 "validated_counts": round(float(val.validated[0]) / count, 4),
                 "margin": round(float(val.margin[0]), 4),
                 "radii_counts": round(float(val.radii[0]) / count, 4),
                 "active_samples": val.active_samples.tolist()}
    print("validated:", validated)
    dec = 10
    sys_d = so.examples.servo_motor(J, B, Ts * dec)
    Y, U = data[::dec, 2:3], data[::dec, 4:5]
    t0 = time.perf_counter()
    curve = so.noise_tradeoff(sys_d, Y, U, increment=2 * Mn, shape=count,
                              betas=np.logspace(-3, 1, 9))
    t_curve = time.perf_counter() - t0
    print("trade-off (decimated x10):", np.round(curve.alpha, 4).tolist(), f"{t_curve:.2f} s")
    out = {
        "what": "calibrate_noise on the HSM150 record (position, one output), |dd| <= 2 Mn",
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version()},
        "runs": rows,
        "validated_1e-3": validated,
        "tradeoff_decimated_10": {"beta": curve.beta.tolist(), "alpha_counts": curve.alpha.tolist(),
                                  "increment_Nm": float(2 * Mn), "seconds": round(t_curve, 3)},
    }
    path = Path(__file__).parent / "results" / "calibration.json"
    path.write_text(json.dumps({**stamp(), **out}, indent=2) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
