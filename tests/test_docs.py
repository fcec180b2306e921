"""The documentation site builds from the repository with warnings as errors.

The documented command is ``python -m sphinx -W -b html docs docs/_build/html``; the
build renders the API reference (autosummary + numpydoc: a malformed docstring
section is an error), the user guide (one page per capability, ``docs/guide/``), the
performance page (generated from ``benchmarks/results/``), the references and the
notebooks (executed, with their figures). The test renders the notebooks as the session
executed them (``tests/notebooks.py``; each is executed once per session).
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.notebooks import NOTEBOOKS

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("sphinx")
pytest.importorskip("numpydoc")
pytest.importorskip("myst_nb")


def test_docs_build_without_warnings(tmp_path, executed_notebooks):
    # the notebooks as the test session executed them (each once: tests/notebooks.py)
    for path in NOTEBOOKS:
        executed_notebooks.run(path)
    out = tmp_path / "html"
    env = {**os.environ, "SETOBS_EXECUTED_NOTEBOOKS": str(executed_notebooks.out)}
    proc = subprocess.run(
        [sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
         "-d", str(tmp_path / "doctrees"), str(ROOT / "docs"), str(out)],
        capture_output=True, text=True, cwd=ROOT, timeout=1200, env=env)
    warnings = [line for line in proc.stderr.splitlines() if "IPKernelApp" not in line]
    assert proc.returncode == 0, "\n".join(warnings[-40:])
    # the pages exist and carry what they promise
    api = (out / "api.html").read_text()
    assert "SMFDO" in api and "ConstrainedZonotope" in api
    refs = (out / "references.html").read_text()
    assert "Automatica" in refs and "10.1109/ACCESS.2019.2929269" in refs
    nb = (out / "notebooks" / "03_set_membership_do.html").read_text()
    assert "<img" in nb  # the notebook was executed and its figures rendered
    assert (out / "generated" / "setobs.setmembership.SMFDO.html").exists()
    # one page per capability, each linked from the guide's index
    guide = (out / "guide.html").read_text()
    for page in sorted((ROOT / "docs" / "guide").glob("*.md")):
        assert (out / "guide" / f"{page.stem}.html").exists(), page.stem
        assert f'href="guide/{page.stem}.html"' in guide, page.stem
    assert "NonlinearSetObserver" in (out / "guide" / "nonlinear_set.html").read_text()
    # the performance page, a section per results file with its commit
    perf = (out / "performance.html").read_text()
    for res in sorted((ROOT / "benchmarks" / "results").glob("*.json")):
        assert f"benchmarks/results/{res.name}" in perf, res.name
