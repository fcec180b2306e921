"""Benchmark: a notebook at the papers' sizes (``FULL = True``), timed cell by cell.

Copies the notebook into a fresh temporary directory (so its resumable campaigns
start from nothing), sets ``FULL = True`` in its first code cell, executes it in a
Jupyter kernel (nbclient) and records the wall time of every code cell and the
total, with what each cell printed (the full-size numbers the README quotes). The
notebook budget is the test suite's cell timeout (600 s per cell).

Writes ``benchmarks/results/notebook_<stem>_full.json``.

Run: ``python benchmarks/notebook_full.py [notebook]`` (default
``notebooks/03_set_membership_do.ipynb``).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import tempfile
import time
from pathlib import Path

import nbclient
import nbformat

from _common import stamp

ROOT = Path(__file__).resolve().parents[1]
CELL_BUDGET = 600.0  # seconds: tests/test_notebooks.py's cell timeout


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("notebook", nargs="?", default="notebooks/03_set_membership_do.ipynb")
    args = ap.parse_args()
    src = (ROOT / args.notebook).resolve()
    nb = nbformat.read(src, as_version=4)
    first = next(c for c in nb.cells if c.cell_type == "code")
    if "FULL = False" not in first.source:
        raise SystemExit(f"{src.name}: the first code cell does not set FULL = False")
    first.source = first.source.replace("FULL = False", "FULL = True", 1)
    cells = []
    with tempfile.TemporaryDirectory() as tmp:
        shutil.copy(src, tmp)
        client = nbclient.NotebookClient(nb, timeout=None, kernel_name="python3",
                                         resources={"metadata": {"path": tmp}})
        t_all = time.perf_counter()
        with client.setup_kernel():
            for i, cell in enumerate(nb.cells):
                if cell.cell_type != "code":
                    continue
                t0 = time.perf_counter()
                client.execute_cell(cell, i)
                first_line = cell.source.splitlines()[0] if cell.source else ""
                printed = "".join(o.get("text", "") for o in cell.get("outputs", [])
                                  if o.get("output_type") == "stream")
                cells.append({"cell": i, "seconds": round(time.perf_counter() - t0, 2),
                              "first_line": first_line[:80], "printed": printed.splitlines()})
                print(f"cell {i:3d}: {cells[-1]['seconds']:8.1f} s  {first_line[:60]}",
                      flush=True)
        total = time.perf_counter() - t_all
    out = {
        "notebook": args.notebook,
        "total_seconds": round(total, 1),
        "longest_cell_seconds": max(c["seconds"] for c in cells),
        "cell_budget_seconds": CELL_BUDGET,
        "every_cell_within_budget": all(c["seconds"] <= CELL_BUDGET for c in cells),
        "cells": cells,
        "machine": {"cpus": os.cpu_count(), "python": platform.python_version(),
                    "platform": platform.platform()},
        "date": time.strftime("%Y-%m-%d"),
    }
    path = ROOT / "benchmarks" / "results" / f"notebook_{src.stem[:2]}_full.json"
    path.write_text(json.dumps({**stamp(), **out}, indent=2) + "\n")
    print(f"total {total:.1f} s -> {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
