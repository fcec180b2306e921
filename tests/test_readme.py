"""Every code block of the README runs as written, in order, in a scratch directory.

* ``python`` blocks run in one namespace (a later block may continue an earlier
  one, as the README says where it does);
* the plain block after the ``diagnose`` snippet is its output, compared line
  by line: words as words, numbers within one unit of their last printed digit
  (:mod:`tests.printed`: the digits move with the BLAS build and the CPU);
* a ``yaml`` block preceded by ``<!-- file: NAME -->`` is written to ``NAME``;
* ``bash`` blocks run line by line through :func:`setobs.cli.main`, except the
  quick start, which ``.ci/run`` executes verbatim on a fresh environment.

The measured record is found where the README says: ``$SETOBS_DATA`` (set here to
the folder that holds ``hsm150/``) or ``../shared/data``; the bash lines' only
expansion, ``${SETOBS_DATA:-../shared/data}``, is done here as bash would.
"""

from __future__ import annotations

import contextlib
import io
import os
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

README = (Path(__file__).parents[1] / "README.md").read_text()
BLOCK = re.compile(r"(?:<!-- file: (\S+) -->\n)?```(\w*)\n(.*?)```", re.S)
BLOCKS = [(m.group(2), m.group(3), m.group(1)) for m in BLOCK.finditer(README)]
QUICK_START = README.split("## Quick start")[1].split("```bash\n")[1].split("```")[0]


def test_blocks_are_found():
    langs = [lang for lang, _, _ in BLOCKS]
    assert langs.count("python") >= 6 and langs.count("bash") >= 3 and "yaml" in langs
    assert all(lang in ("python", "bash", "yaml", "") for lang in langs)


@pytest.mark.skipif(HSM150 is None, reason="the HSM150 record is not available here")
def test_every_block_runs(tmp_path, monkeypatch):
    import matplotlib.pyplot as plt

    from setobs.cli import main

    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("SETOBS_DATA", str(HSM150.parent.parent))
    ns: dict = {}
    last_out = ""
    invalidated = 0
    ran = {"python": 0, "bash": 0, "yaml": 0, "output": 0}
    for lang, code, fname in BLOCKS:
        if lang == "python":
            buf = io.StringIO()
            with contextlib.redirect_stdout(buf), warnings.catch_warnings(record=True) as seen:
                warnings.simplefilter("always")
                exec(compile(code, "README.md", "exec"), ns)
            last_out = buf.getvalue()
            invalidated += sum(issubclass(w.category, so.ModelInvalidatedWarning) for w in seen)
            plt.close("all")
            if last_out.startswith("| observer"):  # a table the README prints below it
                missing = [ln for ln in last_out.strip().splitlines() if not line_in(ln, README)]
                assert not missing, missing
        elif lang == "":  # the output of the block before it
            assert not same_printout(last_out, code), same_printout(last_out, code)
        elif lang == "yaml":
            assert fname, "a yaml block needs a <!-- file: NAME --> line"
            (tmp_path / fname).write_text(code)
        elif lang == "bash":
            if code == QUICK_START:
                continue  # .ci/run runs it verbatim
            for line in code.strip().splitlines():
                line = line.replace("${SETOBS_DATA:-../shared/data}",
                                    os.environ.get("SETOBS_DATA", "../shared/data"))
                args = shlex.split(line, comments=True)
                assert args[0] == "setobs", line
                buf = io.StringIO()
                with contextlib.redirect_stdout(buf):
                    assert main([*args[1:], *(["--no-progress"] if args[1] == "estimate"
                                              else [])]) == 0, line
                plt.close("all")
        ran[lang or "output"] += 1
    assert ran["python"] >= 6 and ran["bash"] >= 2 and ran["yaml"] == 2 and ran["output"] == 1
    # what the blocks promise: the glitch of the noise example gives one warning
    assert invalidated == 1
    assert ns["res"] is not None
    assert (tmp_path / "motor_bounds" / "estimate.csv").exists()
    assert (tmp_path / "physics_only" / "estimate.csv").exists()
    # the record section leads with the useful, calibrated band (+-0.017 N m with the
    # polytope restart, the exact set's width there: tests/setmembership/test_restart.py;
    # +-0.036 with the paper's box restart) and shows the physics-only bound (+-1.47 N m)
    # as the contrast
    import pandas as pd

    half = {d: float(pd.read_csv(tmp_path / d / "estimate.csv")["error_bound"][100:].median())
            for d in ("motor_bounds", "physics_only")}
    assert 0.015 < half["motor_bounds"] < 0.02 and 1.3 < half["physics_only"] < 1.6, half
    assert README.index("--calibrate --states") < README.index("--increment 0.78 --noise")
    # the record section's promises: calibrated on 70 %, validated on the rest, every
    # velocity band consistent with the central difference, no band collapsed
    cal = ns["cal"]
    assert cal.split == 14_000 and cal.minimal[0] < cal.validated[0] < cal.radii[0]
    assert ns["miss"].sum() == 0 and float(((ns["hi"] - ns["lo"])[50:]).min()) > 0.3
    states = pd.read_csv(tmp_path / "motor_bounds" / "estimate.csv")
    assert {"theta_lo", "theta_hi", "omega_lo", "omega_hi"} <= set(states.columns)
    assert set(ns["df"].columns) <= set(states.columns) | {"time"}
    assert (tmp_path / "study_out").exists()


def test_quick_start_is_the_ci_command():
    ci = (Path(__file__).parents[1] / ".ci" / "run").read_text()
    assert "## Quick start" in ci and len(QUICK_START.strip().splitlines()) == 2
