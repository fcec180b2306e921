"""Verdicts at calibrated noise bounds on random systems (the verdict campaign).

Each seed draws a 2-5-state system (up to two decades of diagonal scaling of
states, outputs and disturbances, 0-2 inputs, 10 % missing entries) and a record
with noise and increments uniform in their boxes. The noise bound is calibrated
(``calibrate_noise`` with the true noise radii as shape). Then:

* windows 3 and 10 (where Algorithm 1 allows them) and exact mode run at the
  recommended bound: every ``fallback`` step is counted;
* exact mode is compared with an independent whole-history LP (scipy's HiGHS,
  ``tests.setmembership.test_verdicts.history_lp_noisy``) at k = 10, 20, 29: a
  difference above 1e-6 of the interval width is counted;
* exact mode at 0.9 times the calibrated minimum must raise
  ``ModelInvalidatedError`` (records the model explains without noise, whose
  minimum is at rounding level, are skipped).

Systems for which Theorem 1 fails are skipped. Writes
``benchmarks/results/verdict_campaign.json``.

The per-seed work is ``tests.setmembership.test_verdicts.campaign_seed`` (the
same as the tests' campaign: ``test_verdict_campaign_short`` and the slow
``test_verdict_campaign_200_systems``).

Run: ``python benchmarks/verdict_campaign.py [--seeds 0 60] [--workers 2]``.
"""

from __future__ import annotations

import argparse
import json
import sys as _sys
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

_sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.setmembership.test_verdicts import campaign_failures, campaign_seed

from _common import stamp


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", nargs=2, type=int, default=[0, 60])
    ap.add_argument("--workers", type=int, default=2)
    args = ap.parse_args()
    t0 = time.perf_counter()
    with ProcessPoolExecutor(max_workers=args.workers) as ex:
        rows = list(ex.map(campaign_seed, range(*args.seeds)))
    ran = [r for r in rows if "skipped" not in r]
    summary = {
        "systems": len(ran), "skipped": len(rows) - len(ran),
        "fallback_steps": sum(sum(r["fallback"].values()) for r in ran),
        **campaign_failures(rows),
        "invalidated_at_0.9": sum(r["invalidated_at_0.9"] is True for r in ran),
        "noise_free_fits": sum(r["invalidated_at_0.9"] is None for r in ran),
        "largest_exact_vs_lp": max((v for r in ran for v in r["lp_excess"].values()),
                                   default=0.0),
        "seconds": round(time.perf_counter() - t0, 1),
        "workers": args.workers,
    }
    print(json.dumps(summary, indent=1))
    path = Path(__file__).parent / "results" / "verdict_campaign.json"
    path.write_text(json.dumps({**stamp(), "summary": summary, "runs": rows}, indent=1) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
