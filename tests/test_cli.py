"""The command line runs the demo and its numbers are right."""

from __future__ import annotations

import re

from setobs.cli import main


def test_demo_prints_certified_interval(capsys):
    assert main(["demo"]) == 0
    out = capsys.readouterr().out
    # Closed form: x2 + 0.1 d = 0.3 with x2 in [-1, 1] +- 0.01*0 -> d in [-7.01, 13.01]
    # (the increment adds +-0.01 to d).
    m = re.search(r"disturbance interval\s*: \[(-?[\d.]+), (-?[\d.]+)\]", out)
    assert m is not None
    assert float(m.group(1)) == -7.01 and float(m.group(2)) == 13.01
    assert "estimate (centre): 3.0000" in out


def test_help(capsys):
    assert main([]) == 0
    assert "demo" in capsys.readouterr().out


def test_diagnose_all_examples(capsys):
    assert main(["diagnose", "all"]) == 0
    out = capsys.readouterr().out
    assert out.count("Diagnosis") == 6
    assert "1.26095" in out  # the Chang zero
    assert "V0 is not diagonal" in out  # Example 1


def test_diagnose_markdown(capsys):
    assert main(["diagnose", "cgl1", "--markdown"]) == 0
    assert "| variant MB-ESO | yes |" in capsys.readouterr().out
