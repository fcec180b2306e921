"""The performance page: every results file is stamped with its commit and date, every
benchmark stamps what it writes, and the page (generated when the docs are built) has a
section per results file that carries the file's own figures.

Oracle: the results files themselves, read here with ``json``; each checker is also shown
an unstamped file.
"""

from __future__ import annotations

import ast
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "benchmarks" / "results"
sys.path.insert(0, str(ROOT / "docs"))
import performance_page  # noqa: E402

COMMIT = re.compile(r"^[0-9a-f]{40}$")
DATE = re.compile(r"^\d{4}-\d{2}-\d{2}$")


def unstamped(results: Path) -> list[str]:
    """Results files without a full commit hash and an ISO date."""
    bad = []
    for p in sorted(results.glob("*.json")):
        d = json.loads(p.read_text())
        if not (COMMIT.match(str(d.get("commit", ""))) and DATE.match(str(d.get("date", "")))):
            bad.append(p.name)
    for p in sorted(results.glob("*.md")):
        if not re.match(r"<!-- commit [0-9a-f]{40}, \d{4}-\d{2}-\d{2}", p.read_text()):
            bad.append(p.name)
    return bad


def writers_without_stamp(scripts: list[Path]) -> list[str]:
    """Benchmark scripts with a ``write_text`` call whose argument does not call ``stamp``
    (directly, or through a variable assigned from it in the same function)."""
    bad = []
    for p in scripts:
        tree = ast.parse(p.read_text())
        for fn in ast.walk(tree):
            if not isinstance(fn, ast.FunctionDef):
                continue
            stamped = any(isinstance(n, ast.Call) and getattr(n.func, "id", "") == "stamp"
                          for n in ast.walk(fn))
            for n in ast.walk(fn):
                if (isinstance(n, ast.Call) and isinstance(n.func, ast.Attribute)
                        and n.func.attr == "write_text" and not stamped):
                    bad.append(f"{p.name}:{n.lineno}")
    return bad


def test_every_results_file_is_stamped():
    assert unstamped(RESULTS) == []


def test_every_benchmark_stamps_what_it_writes():
    scripts = [p for p in sorted((ROOT / "benchmarks").glob("*.py")) if p.name != "_common.py"]
    assert len(scripts) >= 15
    assert writers_without_stamp(scripts) == []


def test_the_checkers_see_an_unstamped_file(tmp_path):
    (tmp_path / "a.json").write_text(json.dumps({"commit": "0" * 40, "date": "2026-01-02"}))
    (tmp_path / "b.json").write_text(json.dumps({"x": 1}))
    (tmp_path / "c.md").write_text("| a |\n")
    assert unstamped(tmp_path) == ["b.json", "c.md"]
    script = tmp_path / "bench.py"
    script.write_text("def main(path):\n    path.write_text('{}')\n")
    assert writers_without_stamp([script]) == ["bench.py:2"]
    assert "no commit recorded" in performance_page.render(tmp_path)


def test_the_page_has_every_file_with_its_stamp_and_figures():
    page = performance_page.render(RESULTS)
    for p in sorted(RESULTS.glob("*.json")):
        d = json.loads(p.read_text())
        assert f"## {p.stem}\n" in page
        section = page.split(f"## {p.stem}\n", 1)[1].split("\n## ", 1)[0]
        assert f"`benchmarks/results/{p.name}`" in section
        assert d["commit"][:10] in section and d["date"] in section
    # figures read from the files appear as the page prints numbers (4 significant digits)
    nl = json.loads((RESULTS / "nonlinear_set.json").read_text())
    section = page.split("## nonlinear_set\n", 1)[1].split("\n## ", 1)[0]
    for target in nl["targets"]:
        assert f"{target['value']:.4g}" in section, target
    held_out = nl["tightness"]["held-out six tanks (feedback)"]["variants"]["auto (default)"]
    assert all(f"{v:.4g}" in section for v in held_out["band_over_inner"].values())
    cal = json.loads((RESULTS / "calibration.json").read_text())["validated_1e-3"]
    section = page.split("## calibration\n", 1)[1].split("\n## ", 1)[0]
    assert f"{cal['validated_counts']:.4g}" in section
    md = (RESULTS / "observer_comparison.md").read_text().splitlines()
    assert all(line in page for line in md[1:] if line.strip())
