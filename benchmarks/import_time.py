"""Benchmark: the cost of ``import setobs`` (heavy engines are imported on first use).

Each measurement is a fresh interpreter running ``import setobs`` (wall time of
the import statement, median of ``--repeat`` runs, after one warm-up run so the
file cache is hot). It records the modules the import leaves loaded (numba,
HiGHS, pycddlib, cvxpy, pandas, ... must not be among them), the cost of the
first use of each lazily imported engine, and, with ``--before REV``, the same
import measured on the sources of an earlier git revision (extracted with
``git archive``) for a before/after comparison in one run. Writes
``benchmarks/results/import_time.json``.

Run: ``python benchmarks/import_time.py [--before REV] [--repeat 7]``.
"""

from __future__ import annotations

import argparse
import json
import platform
import statistics
import subprocess
import sys
import tarfile
import tempfile
from io import BytesIO
from pathlib import Path

from _common import stamp

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ["numba", "llvmlite", "highspy", "cdd", "cvxpy", "clarabel", "pandas", "tqdm", "yaml",
         "matplotlib", "scipy.signal", "scipy.optimize", "scipy.spatial", "scipy.stats",
         "multiprocessing"]

_PROBE = """
import sys, time, json
t = time.perf_counter()
import setobs
dt = time.perf_counter() - t
heavy = {heavy!r}
print(json.dumps({{"seconds": dt, "loaded": [m for m in heavy if m in sys.modules]}}))
"""

_FIRST_USE = {
    "first LP (HiGHS)": (
        "so.ConstrainedZonotope(np.eye(2), np.zeros(2), [[1.0, 1.0]], [0.5]).interval_hull()"),
    "first fast-path step (numba)": (
        "so.SMFDO(so.examples.chang2006(), window=3).run(np.zeros((6, 2)))"),
    "first pole placement (scipy.signal)": (
        "so.observers.PIO(so.examples.chang2006(), poles=[0.1, 0.2, 0.3, 0.4, 0.5])"),
}


def _run(code: str, src: Path) -> dict:
    env = {"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin"}
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(src: Path, repeat: int) -> dict:
    """Median import time of ``setobs`` from the sources in ``src``."""
    code = _PROBE.format(heavy=HEAVY)
    _run(code, src)  # warm the file cache
    runs = [_run(code, src) for _ in range(repeat)]
    return {"median_s": statistics.median(r["seconds"] for r in runs),
            "min_s": min(r["seconds"] for r in runs),
            "heavy_modules_loaded": runs[0]["loaded"]}


def first_use(src: Path, repeat: int) -> dict:
    """Time of the first call that loads each deferred engine (after ``import setobs``)."""
    out = {}
    for label, stmt in _FIRST_USE.items():
        code = ("import time, json\nimport numpy as np\nimport setobs as so\n"
                f"t = time.perf_counter()\n{stmt}\n"
                "print(json.dumps({'seconds': time.perf_counter() - t}))")
        _run(code, src)
        out[label] = statistics.median(_run(code, src)["seconds"] for _ in range(repeat))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", help="git revision to measure for comparison")
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    res = {"python": platform.python_version(), "machine": platform.machine(),
           "repeat": args.repeat, "after": measure(ROOT / "src", args.repeat),
           "first_use_s": first_use(ROOT / "src", max(1, args.repeat // 2))}
    if args.before:
        blob = subprocess.run(["git", "-C", str(ROOT), "archive", args.before, "src"],
                              capture_output=True, check=True).stdout
        with tempfile.TemporaryDirectory() as tmp:
            with tarfile.open(fileobj=BytesIO(blob)) as tar:
                tar.extractall(tmp, filter="data")
            res["before"] = {"revision": args.before, **measure(Path(tmp) / "src", args.repeat)}
        res["speedup"] = res["before"]["median_s"] / res["after"]["median_s"]
    path = ROOT / "benchmarks" / "results" / "import_time.json"
    path.write_text(json.dumps({**stamp(), **res}, indent=2) + "\n")
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
