"""The README's real-data section runs as written (with the record's path resolved)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from tests.datasets import HSM150

README = (Path(__file__).parents[1] / "README.md").read_text()
SECTION = README.split("<!-- real-data:start")[1].split("<!-- real-data:end -->")[0]
BLOCKS = re.findall(r"```(\w+)\n(.*?)```", SECTION, re.S)
RECORD = "../shared/data/hsm150/idf_pos_0.06_1.mat"


def _block(lang):
    (code,) = [c for lang_, c in BLOCKS if lang_ == lang]
    return code


@pytest.mark.skipif(HSM150 is None, reason="the HSM150 record is not available here")
def test_python_snippet_runs(capsys):
    code = _block("python")
    assert RECORD in code
    exec(compile(code.replace(RECORD, str(HSM150)), "README.md", "exec"), {})
    out = capsys.readouterr().out
    assert "NoiseCalibration(radii=" in out and "True" in out and "tau_L_lo" in out


@pytest.mark.skipif(HSM150 is None, reason="the HSM150 record is not available here")
def test_shell_snippet_runs(tmp_path, capsys, monkeypatch):
    import shlex

    from setobs.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "motor.yaml").write_text(_block("yaml"))
    args = shlex.split(_block("bash").replace(RECORD, str(HSM150)))
    assert args[0] == "setobs"
    assert main([*args[1:], "--no-progress"]) == 0
    assert (tmp_path / "motor_bounds" / "estimate.csv").exists()
    assert "first inconsistent step: none" in capsys.readouterr().out
