"""Benchmark: certified interval hull vs a naive cvxpy formulation.

For random non-empty constrained zonotopes of sizes (n, n_gen, n_con) in
{(5, 45, 40), (5, 100, 90), (10, 200, 150)}, time in the same run:

* ``setobs``: ``ConstrainedZonotope.interval_hull()`` on a fresh object (so the
  HiGHS model is built inside the timing; 2n LPs re-solved on one model, plus
  certification);
* ``cvxpy``: a fresh ``cvxpy.Problem`` per LP (2n problems) solved with Clarabel.

Writes medians, the ratio, and the disagreement (ours minus cvxpy's bound,
outward positive) to ``benchmarks/results/interval_hull.json``. Negative
differences of order 1e-8 are Clarabel's interior-point accuracy: its reported
optimum can lie slightly outside the true set, whereas setobs' bounds are
certified (checked exactly against rational vertex enumeration in the tests).

Run: ``python benchmarks/interval_hull.py [--repeats N]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
from importlib import metadata
from pathlib import Path

import cvxpy as cp
import numpy as np

import setobs
from _common import hull_cvxpy, make_cz, stamp, timeit
from setobs import ConstrainedZonotope

SIZES = [(5, 45, 40), (5, 100, 90), (10, 200, 150)]


def hull_setobs(Z: ConstrainedZonotope) -> tuple[np.ndarray, np.ndarray]:
    fresh = ConstrainedZonotope(Z.G, Z.c, Z.A, Z.b, Z.h)  # no cached model or hull
    box = fresh.interval_hull()
    return box.lo, box.hi


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "interval_hull.json"))
    args = ap.parse_args()
    rng = np.random.default_rng(2026)
    rows = []
    for n, n_g, n_c in SIZES:
        Z = make_cz(n, n_g, n_c, rng)
        t_ours, _, (lo, hi) = timeit(hull_setobs, Z, repeats=args.repeats)
        t_cvx, _, (lo_c, hi_c) = timeit(hull_cvxpy, Z, repeats=max(3, args.repeats // 2))
        outward = np.concatenate([lo_c - lo, hi - hi_c])  # >= 0 means ours is outside
        row = {
            "n": n, "n_gen": n_g, "n_con": n_c, "lps": 2 * n,
            "setobs_median_s": t_ours,
            "cvxpy_clarabel_median_s": t_cvx,
            "speedup": t_cvx / t_ours,
            "setobs_per_lp_us": 1e6 * t_ours / (2 * n),
            "max_outward_difference": float(outward.max()),
            "min_outward_difference": float(outward.min()),
        }
        rows.append(row)
        print(f"(n, n_gen, n_con) = ({n:3d}, {n_g:4d}, {n_c:4d}): setobs {1e3 * t_ours:8.2f} ms, "
              f"cvxpy+Clarabel {1e3 * t_cvx:8.1f} ms, speed-up x{t_cvx / t_ours:6.1f}, "
              f"ours-minus-cvxpy outward in [{outward.min():.1e}, {outward.max():.1e}]")
    result = {
        "benchmark": "interval_hull",
        "description": " ".join(__doc__.split("\n\n")[1:4]).replace("\n", " "),
        "setobs": setobs.__version__,
        "highspy": metadata.version("highspy"),
        "cvxpy": cp.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "repeats": args.repeats,
        "results": rows,
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({**stamp(), **result}, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
