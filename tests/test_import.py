"""`import setobs` stays light; optional packages fail with an actionable message."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

import setobs as so
from setobs._lazy import optional_import

HEAVY = ["numba", "highspy", "cdd", "cvxpy", "clarabel", "pandas", "tqdm", "yaml", "matplotlib",
         "scipy.signal", "scipy.optimize", "scipy.spatial", "scipy.stats", "dask",
         "concurrent.futures.process"]


def test_import_loads_no_heavy_engine():
    code = ("import sys, json, setobs\n"
            f"print(json.dumps([m for m in {HEAVY!r} if m in sys.modules]))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(out.stdout) == []


def test_lazy_engines_still_work_after_import():
    # the deferred HiGHS, numba simplex and Qhull load on first use and give the right answer
    Z = so.ConstrainedZonotope(np.eye(2), np.zeros(2), [[1.0, 1.0]], [1.5])
    box = Z.interval_hull()
    lo, hi = box.lo, box.hi
    # xi1 + xi2 = 1.5 with |xi| <= 1: each coordinate lies in [0.5, 1]
    assert np.all(lo <= 0.5 + 1e-12) and np.all(lo >= 0.5 - 1e-9)
    assert np.all(hi >= 1.0 - 1e-12) and np.all(hi <= 1.0 + 1e-9)
    V = Z.vertices()
    assert sorted(map(tuple, np.round(V, 12))) == [(0.5, 1.0), (1.0, 0.5)]


@pytest.mark.parametrize("module, extra", [("yaml", "yaml"), ("tqdm.auto", "progress"),
                                           ("cvxpy", "qp")])
def test_missing_optional_package_names_the_extra(monkeypatch, module, extra):
    monkeypatch.setitem(sys.modules, module.split(".")[0], None)  # import now raises
    if "." in module:
        monkeypatch.setitem(sys.modules, module, None)
    with pytest.raises(ImportError, match=rf'pip install "setobs\[{extra}\]"'):
        optional_import(module, extra=extra, feature="this feature")


def test_progress_without_tqdm_raises_clearly(monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    obs = so.SMFDO(so.examples.chang2006(), window=3)
    with pytest.raises(ImportError, match=r"setobs\[progress\]"):
        obs.run(np.zeros((5, 2)), progress=True)
    # without progress the run does not need tqdm
    assert obs.run(np.zeros((5, 2))).estimate.shape == (5, 2)
