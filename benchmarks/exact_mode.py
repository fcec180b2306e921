"""Benchmark: the SMFDO's exact mode (``window=None``) on the paper example.

Measures, in one run:

* the H-representation recursion (the default exact path, ``fast=True``):
  median time per update around k = 100, 1 000 and 10 000 on one record, and
  the size of the carried representation (normals, vertices) over k;
* the whole-history set recursion (``fast=False``, the exact mode before the
  H-representation) on the same record up to k = 150, in the same run;
* the exact-mode Fig. 1(b) campaign (SMFDO exact + PIO, local processes on
  both cores) on a sample of runs, extrapolated to 5000 runs;
* a system whose exact set grows (the paper example with measurement noise):
  the exact set's vertices and facets over the first steps, and the time per
  update of the default exact mode (which leaves such sets to the whole-history
  set recursion) up to k = 300;
* time per exact-mode update around k = 50, 100 and 150 (the H recursion and
  the whole-history recursion, whose dense solves BLAS threads hit), under three BLAS
  settings, each on an idle machine and with the other core busy (a spinning
  process, as in a two-process campaign): the library's single-threaded BLAS
  kernels (default), the same with the limit switched off
  (``SETOBS_BLAS_LIMIT=0``: the behaviour before it existed) and
  ``OPENBLAS_NUM_THREADS=1`` set by the user;
* the size of the exact-mode representation (generators, constraints) over k,
  and what :meth:`ConstrainedZonotope.reduce_exact` makes of it (it stops
  eliminating when its certified rounding budget is spent; see its notes).

Each setting runs in a fresh subprocess (BLAS thread pools are per process).
Writes ``benchmarks/results/exact_mode.json``.

Run: ``python benchmarks/exact_mode.py [--kmax 150] [--long 10100] [--runs 200]``.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import subprocess
import sys
import time
from pathlib import Path

from _common import stamp

HERE = Path(__file__).resolve().parent


def ms_around(times: list[float], ks, half: int = 5) -> dict[str, float]:
    """Median time per update (ms) over ``times[k - half : k + half]`` for each ``k`` recorded."""
    return {str(k): 1e3 * statistics.median(times[max(0, k - half):k + half])
            for k in ks if k < len(times)}


def child(kmax: int) -> dict:
    sys.path.insert(0, str(HERE.parent))
    import numpy as np
    from benchmarks.smfdo import data, time_updates

    import setobs as so

    sysm, Y, _ = data(kmax + 1)
    out = {}
    for name, fast in (("ms_per_update", True), ("whole_history_ms_per_update", False)):
        times, _ = time_updates(so.SMFDO(sysm, window=None, fast=fast), Y[:kmax + 1], 0)
        out[name] = ms_around(times, (50, 100, 150))
        out["total_s" if fast else "whole_history_total_s"] = float(np.sum(times))
    return out


def sizes(kmax: int) -> list[dict]:
    from benchmarks.smfdo import data

    import setobs as so

    sysm, Y, _ = data(kmax + 1)
    obs = so.SMFDO(sysm, window=None)
    rows = []
    for k, y in enumerate(Y[:kmax + 1]):
        obs.step(y)
        if k in (2, 5, 10, 20, 30, 50, 100, 150):
            Z = obs.posterior_set
            t0 = time.perf_counter()
            R = Z.reduce_exact()
            rows.append({"k": k, "n_gen": Z.n_gen, "n_con": Z.n_con, "reduced_n_gen": R.n_gen,
                         "reduced_n_con": R.n_con, "reduce_s": time.perf_counter() - t0})
    return rows


def h_recursion(long: int) -> dict:
    """Per-update times and representation sizes of the default exact path."""
    from benchmarks.smfdo import data, time_updates

    import setobs as so
    from setobs.setmembership._hrep import HState

    sysm, Y, _ = data(long)
    obs = so.SMFDO(sysm, window=None)
    times, sizes_k = [], []
    for k, y in enumerate(Y):
        t0 = time.perf_counter()
        obs.step(y)
        times.append(time.perf_counter() - t0)
        st = obs.exact_representation
        if k in (10, 100, 300, 1000, 3000, 10000) and isinstance(st, HState):
            sizes_k.append({"k": k, "normals": int(st.H.shape[0]),
                            "vertices": int(st.V.shape[0]),
                            "posterior_n_gen": obs.posterior_set.n_gen,
                            "posterior_n_con": obs.posterior_set.n_con})
    out = ms_around(times, (100, 1000, 10000), half=50)
    rtimes, _ = time_updates(so.SMFDO(sysm, window=None, fast=False), Y[:151], 0)
    old = ms_around(rtimes, (50, 100, 145))
    return {"ms_per_update": out, "steps": long, "total_s": float(sum(times)),
            "stats": dict(obs.stats), "representation": sizes_k,
            "set_recursion_ms_per_update": old}


def growing(kmax: int, kcount: int) -> dict:
    """A system whose exact set grows: the paper example with measurement noise.

    The exact set's facets (its non-redundant constraints) and vertices at
    k = 2..kcount come from an exact polytope conversion of the whole-history
    posterior (``to_hrep``, ``vertices``: pycddlib/Qhull); the time per update
    is the default exact mode's (which leaves these sets to the whole-history
    set recursion).
    """
    import numpy as np
    from benchmarks.smfdo import time_updates
    from tests.datasets import noisy_record

    import setobs as so
    from setobs.exceptions import SetobsError
    from setobs.geometry.polytope import to_hrep

    sysm, inc, shape = so.examples.chang2006(), np.array([0.2, 0.1]), np.array([1.0, 2.0])
    noise = 0.05 * shape
    Y = noisy_record(sysm, max(kmax, kcount) + 1, np.random.default_rng(0), inc, noise)
    obs = so.SMFDO(sysm, window=None, increment_set=inc, measurement_noise=noise)
    times, _ = time_updates(obs, Y[:kmax + 1], 0)
    ms = ms_around(times, (5, 25, 50, 100, 200, 300))
    whole = so.SMFDO(sysm, window=None, fast=False, increment_set=inc,
                     measurement_noise=noise)
    rows = []
    for k, y in enumerate(Y[:kcount + 1]):
        whole.step(y)
        if k < 2:
            continue
        Z = whole.posterior_set
        t0 = time.perf_counter()
        try:
            facets, verts = to_hrep(Z).H.shape[0], Z.vertices().shape[0]
        except SetobsError as exc:  # Qhull gives up on the larger sets
            rows.append({"k": k, "error": str(exc).splitlines()[0][:120]})
            break
        rows.append({"k": k, "facets": int(facets), "vertices": int(verts),
                     "representation_n_gen": Z.n_gen, "representation_n_con": Z.n_con,
                     "enumeration_s": time.perf_counter() - t0})
    return {"system": "chang2006, |dd| <= (0.2, 0.1), |v| <= (0.05, 0.1)",
            "ms_per_update": ms, "stats": dict(obs.stats), "exact_set": rows}


def exact_campaign(runs: int) -> dict:
    from setobs.studies import ObserverSpec, Scenario, run_campaign

    sc = Scenario(system="chang2006", horizon=100, increment=1.0, x0_box=1.0)
    specs = [ObserverSpec("SMFDO exact", "smfdo", {"window": None}),
             ObserverSpec("PIO (printed gains)", "pio_printed")]
    t0 = time.perf_counter()
    run_campaign(sc, specs, runs, reference_window=None, progress=False)
    wall = time.perf_counter() - t0
    return {"runs": runs, "horizon": 100, "wall_s": wall,
            "extrapolated_5000_runs_min": 5000 * wall / runs / 60}


def run_setting(name: str, env_extra: dict, load: bool, kmax: int) -> dict:
    env = {k: v for k, v in os.environ.items()
           if k not in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "SETOBS_BLAS_LIMIT")}
    env.update(env_extra)
    spinner = None
    if load:
        spinner = subprocess.Popen([sys.executable, "-c", "while True: pass"])
    try:
        res = subprocess.run([sys.executable, __file__, "--child", "--kmax", str(kmax)],
                             env=env, capture_output=True, text=True, check=True)
    finally:
        if spinner is not None:
            spinner.kill()
    row = json.loads(res.stdout.strip().splitlines()[-1])
    row.update({"setting": name, "other_core_busy": load})
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kmax", type=int, default=150)
    ap.add_argument("--long", type=int, default=10100)
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--grow-k", type=int, default=300)
    ap.add_argument("--grow-count", type=int, default=5)
    ap.add_argument("--child", action="store_true")
    ap.add_argument("--out", default=str(HERE / "results" / "exact_mode.json"))
    args = ap.parse_args()
    if args.child:
        print(json.dumps(child(args.kmax)))
        return
    sys.path.insert(0, str(HERE.parent))
    hrec = h_recursion(args.long)
    print("H-representation recursion: " + ", ".join(
        f"k={k}: {v:.2f} ms" for k, v in hrec["ms_per_update"].items()))
    print("set recursion (before):    " + ", ".join(
        f"k={k}: {v:.1f} ms" for k, v in hrec["set_recursion_ms_per_update"].items()))
    for r in hrec["representation"]:
        print(f"  k={r['k']:5d}: {r['normals']} normals, {r['vertices']} vertices")
    grow = growing(args.grow_k, args.grow_count)
    print("growing exact set (" + grow["system"] + "): " + ", ".join(
        f"k={r['k']}: {r['facets']} facets / {r['vertices']} vertices" if "facets" in r
        else f"k={r['k']}: {r['error']}" for r in grow["exact_set"]))
    print("  time per update (whole-history set recursion): " + ", ".join(
        f"k={k}: {v:.1f} ms" for k, v in grow["ms_per_update"].items()))
    camp = exact_campaign(args.runs)
    print(f"exact campaign: {camp['runs']} runs in {camp['wall_s']:.1f} s -> 5000 runs "
          f"~ {camp['extrapolated_5000_runs_min']:.1f} min")
    settings = [("library limit (default)", {}),
                ("limit off, default BLAS threads", {"SETOBS_BLAS_LIMIT": "0"}),
                ("OPENBLAS_NUM_THREADS=1", {"OPENBLAS_NUM_THREADS": "1"})]
    rows = []
    for load in (False, True):
        for name, env in settings:
            r = run_setting(name, env, load, args.kmax)
            rows.append(r)
            print(f"{name:>32} busy={load!s:5}: " + ", ".join(
                f"k={k}: {v:5.2f} ms" for k, v in r["ms_per_update"].items())
                + "; whole history " + ", ".join(
                f"k={k}: {v:6.1f} ms" for k, v in r["whole_history_ms_per_update"].items()))
    sys.path.insert(0, str(HERE.parent))
    size_rows = sizes(args.kmax)
    for s in size_rows:
        print(f"k={s['k']:4d}: representation {s['n_gen']:4d} gen / {s['n_con']:4d} con -> "
              f"reduce_exact {s['reduced_n_gen']:4d} / {s['reduced_n_con']:4d} "
              f"({s['reduce_s'] * 1e3:.0f} ms)")
    import setobs as so

    out = {"benchmark": "exact_mode", "system": "chang2006 (Li-Cong-Dong eq. 25)",
           "increment": "|dd_i| <= 1", "setobs": so.__version__,
           "python": platform.python_version(), "machine": platform.machine(),
           "cpus": os.cpu_count(), "h_recursion": hrec, "exact_campaign": camp,
           "growing_system": grow,
           "targets": {"ms_per_update_k1000": 0.5, "ms_per_update_k10000": 0.5,
                       "campaign_5000_runs_min": 5},
           "targets_met": {"k1000": hrec["ms_per_update"].get("1000", 1e9) <= 0.5,
                           "k10000": hrec["ms_per_update"].get("10000", 1e9) <= 0.5,
                           "campaign": camp["extrapolated_5000_runs_min"] <= 5},
           "blas_timings_k_le_150": rows, "posterior_set_representation": size_rows}
    Path(args.out).write_text(json.dumps({**stamp(), **out}, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
