"""Study: what holds window 10's worst coordinate against the exact set on a long cascade.

Two 30-tank cascades with 21 of their levels measured (the tanks at 3, 6, 9, ... 26 not),
process noise ``|w| <= rw``, measurement noise ``|v| <= rv``, the initial box ``|x_0| <= R0``:

* ``fast``: :func:`state_estimation.tanks_outputs` (equal tanks, sampled at ``dt = 1``: the
  slowest mode decays by 0.82 per step);
* ``slow``: tanks of unequal outflow coefficients (0.05-0.3, seeded), sampled at
  ``dt = 0.1``: the slowest mode decays by 0.995 per step, so an unmeasured level is
  known from a history far longer than the window; ``R0`` wide against the noise.

For each, exact mode (the whole-history LP: the reference) and window 10 under the
restart variants: the box (eq. (24)), the default ``"auto"`` (and without the first
restart's wait for the transient, ``TRANSIENT_RATIO``), the polytope restart, its
support values at every step (``SUPPORT_START_ROWS`` and ``SUPPORT_MAX_RATIO`` lifted), and
the polytope with more rows (``MAX_ROWS``; at 30 states the default 120 rows carry the box
back only 4 steps). Per variant: the mean and worst ratio of the state bands' widths to
the exact ones over steps ``20 .. N - 1`` and every state, the seconds per step, whether
the truth stayed inside; and the worst ratio from step ``delta`` on (the transient from
the wide initial set included: the first restart's wait, ``TRANSIENT_RATIO`` of
:mod:`setobs.setmembership._schedule`). Windows 20 and 30 for comparison.

Writes ``benchmarks/results/window_worst.json``. Run:
``python benchmarks/window_worst.py [--steps 60]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import setobs as so  # noqa: E402
from _common import linprog_unit, stamp  # noqa: E402
from setobs.setmembership import _restart, _schedule  # noqa: E402
from setobs.setmembership.engines import window as window_engine  # noqa: E402
from state_estimation import c2d, record, tanks_outputs  # noqa: E402

BURN = 20


def slow_cascade(n: int = 30, l: int = 21, dt: float = 0.1, seed: int = 7):
    """Tanks of unequal outflow coefficients sampled fast: ``A`` close to ``I``."""
    rng = np.random.default_rng(seed)
    k = rng.uniform(0.05, 0.3, n)
    Ac = np.diag(-k) + np.diag(k[:-1], -1)
    Bc = np.zeros((n, 1))
    Bc[0, 0] = 0.5
    A, B = c2d(Ac, Bc, dt)
    skip = set(np.round(np.linspace(0, n - 1, n - l + 2)[1:-1]).astype(int))
    C = np.eye(n)[[i for i in range(n) if i not in skip]]
    return A, B, C


def variants(window: int):
    """``(name, SMFDO keywords, MAX_ROWS, support values always, or "no wait": the
    first restart's transient wait off)``."""
    out = [("box", dict(window=window, restart="box"), None, False),
           ("auto (default)", dict(window=window), None, False),
           ("auto, no transient wait", dict(window=window), None, "no wait"),
           ("polytope", dict(window=window, restart="polytope"), None, False),
           ("polytope, support values always", dict(window=window, restart="polytope"), None,
            True),
           ("polytope, 240 rows, support always", dict(window=window, restart="polytope"),
            240, True),
           ("polytope, 600 rows, support always", dict(window=window, restart="polytope"),
            600, True)]
    return out


def run_plant(name, A, B, C, rw, rv, R0, N):
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, N, 0)
    sys_ = so.LinearSystem(A, np.zeros((n, 0)), C, B)
    kw = dict(measurement_noise=rv, process_noise=rw, state_bounds=True,
              initial_state_set=so.Box(-R0 * np.ones(n), R0 * np.ones(n)))
    unmeasured = np.flatnonzero(np.abs(C).sum(axis=0) == 0)
    t0 = time.perf_counter()
    exact = so.SMFDO(sys_, window=None, **kw).run(Y, U)
    t_exact = (time.perf_counter() - t0) / N
    We = exact.state_hi - exact.state_lo
    rows = []
    runs = [*variants(10), ("auto, window 20", dict(window=20), None, False),
            ("auto, window 30", dict(window=30), None, False)]
    defaults = (_restart.MAX_ROWS, window_engine.SUPPORT_START_ROWS,
                window_engine.SUPPORT_MAX_RATIO, _schedule.TRANSIENT_RATIO)
    for label, extra, max_rows, support in runs:
        _restart.MAX_ROWS = max_rows or defaults[0]
        if support == "no wait":
            _schedule.TRANSIENT_RATIO = np.inf
        elif support:
            window_engine.SUPPORT_START_ROWS = window_engine.SUPPORT_MAX_RATIO = 10**9
        try:
            unit0 = linprog_unit()
            obs = so.SMFDO(sys_, **{**kw, **extra})
            t0 = time.perf_counter()
            res = obs.run(Y, U)
            dt = (time.perf_counter() - t0) / N
            unit = min(unit0, linprog_unit())
        finally:
            (_restart.MAX_ROWS, window_engine.SUPPORT_START_ROWS,
             window_engine.SUPPORT_MAX_RATIO, _schedule.TRANSIENT_RATIO) = defaults
        r_all = (res.state_hi - res.state_lo) / We
        r = r_all[BURN:]
        k, j = np.unravel_index(int(np.argmax(r)), r.shape)
        row = {"plant": name, "variant": label, "window": extra["window"],
               "width_ratio_mean": float(r.mean()), "width_ratio_worst": float(r.max()),
               "worst_step": int(BURN + k), "worst_state": int(j),
               "worst_state_measured": bool(j not in unmeasured),
               "width_ratio_mean_unmeasured": float(r[:, unmeasured].mean()),
               # (from the window's first restart on: the initial set's transient included)
               "width_ratio_worst_from_window": float(r_all[extra["window"]:].max()),
               "restart_lags": obs.restart_lags, "s_per_step": dt, "per_linprog": dt / unit,
               "truth_inside": bool(np.all((X >= res.state_lo) & (X <= res.state_hi))),
               "polytope_restarts": obs.stats["polytope_restarts"],
               "support_restarts": obs.stats["support_restarts"]}
        rows.append(row)
        print(f"{name:5s} {label:36s} {row['width_ratio_mean']:.4f} / "
              f"{row['width_ratio_worst']:.3f} (state {j}, k {BURN + k}; from the window "
              f"{row['width_ratio_worst_from_window']:.3f})  "
              f"{dt:.3f} s/step ({dt / unit:.1f} LP)  inside {row['truth_inside']}",
              flush=True)
    return rows, t_exact


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=60)
    ap.add_argument("--out", default=str(HERE / "results" / "window_worst.json"))
    args = ap.parse_args()
    warnings.simplefilter("ignore")  # (the exact runs' once-per-observer 'inexact' notes)
    A, B, C, rw, rv = tanks_outputs(30, 21)
    fast, t_fast = run_plant("fast", A, B, C, rw, rv, 2.0, args.steps)
    As, Bs, Cs = slow_cascade()
    slow, t_slow = run_plant("slow", As, Bs, Cs, 0.001, 0.01, 5.0, args.steps)
    out = {**stamp(), "benchmark": "window_worst", "steps": args.steps, "burn_in": BURN,
           "plants": {"fast": {"rw": rw, "rv": rv, "R0": 2.0, "dt": 1.0,
                               "exact_s_per_step": t_fast},
                      "slow": {"rw": 0.001, "rv": 0.01, "R0": 5.0, "dt": 0.1,
                               "exact_s_per_step": t_slow}},
           "rows": fast + slow}
    Path(args.out).write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
