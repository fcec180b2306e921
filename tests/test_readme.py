"""Every code block of the README and of the guide's pages runs as written, in order, in a
scratch directory.

* the pages run in the README's order and then the guide's (``docs/guide.md``'s
  toctree), in one directory (a later page may use a file an earlier one wrote: the
  record page's ``motor.yaml``), each page in its own namespace, its ``python`` blocks in
  order (a later block may continue an earlier one);
* a plain block after a ``python`` block is its output, compared line by line: words as
  words, numbers within one unit of their last printed digit (:mod:`tests.printed`: the
  digits move with the BLAS build and the CPU);
* a ``yaml`` block preceded by ``<!-- file: NAME -->`` is written to ``NAME``;
* ``bash`` blocks run line by line through :func:`setobs.cli.main`, except the
  README's quick start, which ``.ci/run`` executes verbatim on a fresh environment;
  ``text`` blocks are shown, not run.

The measured record is found where the pages say: ``$SETOBS_DATA`` (set here to the
folder that holds ``hsm150/``); the bash lines' only expansion, ``$SETOBS_DATA``, is done
here as bash would.
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import warnings
from pathlib import Path

import matplotlib
import pytest

import setobs as so
from tests.datasets import HSM150
from tests.printed import line_in, same_printout

matplotlib.use("Agg")

ROOT = Path(__file__).parents[1]
README = (ROOT / "README.md").read_text()
GUIDE_ORDER = re.findall(r"^guide/(\w+)$", (ROOT / "docs" / "guide.md").read_text(), re.M)
PAGES = {"README": README, **{name: (ROOT / "docs" / "guide" / f"{name}.md").read_text()
                              for name in GUIDE_ORDER}}
BLOCK = re.compile(r"(?:<!-- file: (\S+) -->\n)?```(\w*)\n(.*?)```", re.S)
QUICK_START = README.split("## Quick start")[1].split("```bash\n")[1].split("```")[0]


def blocks(text: str) -> list[tuple[str, str, str | None]]:
    return [(m.group(2), m.group(3), m.group(1)) for m in BLOCK.finditer(text)]


def test_blocks_are_found():
    assert len(GUIDE_ORDER) == 11 and set(GUIDE_ORDER) == {
        p.stem for p in (ROOT / "docs" / "guide").glob("*.md")}
    langs = [lang for text in PAGES.values() for lang, _, _ in blocks(text)]
    assert langs.count("python") >= 12 and langs.count("bash") >= 3 and "yaml" in langs
    assert all(lang in ("python", "bash", "yaml", "text", "") for lang in langs)
    assert len([lang for lang, _, _ in blocks(README) if lang == "python"]) >= 6


def test_readme_is_short_and_links_every_guide_page():
    """The README is the front door: at most about 250 lines, one link per guide page."""
    assert len(README.splitlines()) <= 250
    for name in GUIDE_ORDER:
        assert f"(docs/guide/{name}.md)" in README, name


def run_page(name: str, text: str, ran: dict, seen_invalidated: list) -> dict:
    from matplotlib import pyplot as plt

    from setobs.cli import main

    ns: dict = {}
    last_out = ""
    for lang, code, fname in blocks(text):
        if lang == "python":
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf), warnings.catch_warnings(record=True) as seen:
                warnings.simplefilter("always")
                exec(compile(code, f"{name}.md", "exec"), ns)
            last_out = buf.getvalue()
            seen_invalidated.append(
                sum(issubclass(w.category, so.ModelInvalidatedWarning) for w in seen))
            plt.close("all")
            if last_out.startswith("| observer"):  # a table the page prints below it
                missing = [ln for ln in last_out.strip().splitlines() if not line_in(ln, text)]
                assert not missing, (name, missing)
        elif lang == "":  # the output of the block before it
            assert not same_printout(last_out, code), (name, same_printout(last_out, code))
        elif lang == "yaml":
            assert fname, f"{name}: a yaml block needs a <!-- file: NAME --> line"
            Path(fname).write_text(code)
        elif lang == "bash":
            if code == QUICK_START:
                continue  # .ci/run runs it verbatim
            for line in code.strip().splitlines():
                line = line.replace("$SETOBS_DATA", str(HSM150.parent.parent))
                args = shlex.split(line, comments=True)
                assert args[0] == "setobs", line
                buf = io.StringIO()
                with contextlib.redirect_stdout(buf):
                    assert main([*args[1:], *(["--no-progress"] if args[1] == "estimate"
                                              else [])]) == 0, line
                plt.close("all")
        ran[lang or "output"] += 1
    return ns


@pytest.mark.skipif(HSM150 is None, reason="the HSM150 record is not available here")
def test_every_block_runs(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SETOBS_DATA", str(HSM150.parent.parent))
    ran = {"python": 0, "bash": 0, "yaml": 0, "output": 0, "text": 0}
    invalidated: list[int] = []
    spaces = {name: run_page(name, text, ran, invalidated) for name, text in PAGES.items()}
    assert ran["python"] >= 12 and ran["bash"] >= 2 and ran["yaml"] == 2 and ran["output"] == 2
    # what the blocks promise: the glitch of the noise example gives one warning
    assert sum(invalidated) == 1
    assert spaces["smfdo"]["res"] is not None
    assert (tmp_path / "motor_bounds" / "estimate.csv").exists()
    assert (tmp_path / "physics_only" / "estimate.csv").exists()
    # the record page leads with the useful, calibrated band (+-0.017 N m with the
    # polytope restart, the exact set's width there: tests/setmembership/test_restart.py;
    # +-0.036 with the paper's box restart) and shows the physics-only bound (+-1.47 N m)
    # as the contrast
    import pandas as pd

    half = {d: float(pd.read_csv(tmp_path / d / "estimate.csv")["error_bound"][100:].median())
            for d in ("motor_bounds", "physics_only")}
    assert 0.015 < half["motor_bounds"] < 0.02 and 1.3 < half["physics_only"] < 1.6, half
    records = PAGES["records"]
    assert records.index("--calibrate --states") < records.index("--increment 0.78 --noise")
    # the record page's promises: calibrated on 70 %, validated on the rest, every
    # velocity band consistent with the central difference, no band collapsed
    ns = spaces["records"]
    cal = ns["cal"]
    assert cal.split == 14_000 and cal.minimal[0] < cal.validated[0] < cal.radii[0]
    assert ns["miss"].sum() == 0 and float(((ns["hi"] - ns["lo"])[50:]).min()) > 0.3
    states = pd.read_csv(tmp_path / "motor_bounds" / "estimate.csv")
    assert {"theta_lo", "theta_hi", "omega_lo", "omega_hi"} <= set(states.columns)
    assert set(ns["df"].columns) <= set(states.columns) | {"time"}
    assert (tmp_path / "study_out").exists()
    # the README's own examples: the truth inside the SMFDO's and the state bands
    readme = spaces["README"]
    assert readme["res"] is not None and readme["report"]["SMFDO"].exists


def test_quick_start_is_the_ci_command():
    ci = (ROOT / ".ci" / "run").read_text()
    assert "## Quick start" in ci and len(QUICK_START.strip().splitlines()) == 2
