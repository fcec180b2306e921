"""The command line on good and bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from scipy.io import savemat

import setobs as so
from setobs.cli import main


def test_demo_writes_table_and_png(tmp_path, capsys):
    png = tmp_path / "demo.png"
    assert main(["demo", "--out", str(png), "--steps", "40"]) == 0
    out = capsys.readouterr().out
    assert "SMFDO exact" in out and "PIO (printed gains, baseline)" in out
    assert png.exists() and png.stat().st_size > 10_000
    # SMFDO rows report zero violations.
    for line in out.splitlines():
        if line.startswith("SMFDO"):
            assert line.rstrip().endswith(" 0")


def _chang_dict():
    s = so.examples.chang2006()
    return {"Phi": s.Phi.tolist(), "G": s.G.tolist(), "Xi": s.Xi.tolist()}


@pytest.mark.parametrize("fmt", ["json", "yaml", "npz", "mat"])
def test_check_reads_every_format(tmp_path, capsys, fmt):
    d = _chang_dict()
    f = tmp_path / f"sys.{fmt}"
    if fmt == "json":
        f.write_text(json.dumps(d))
    elif fmt == "yaml":
        f.write_text(yaml.safe_dump(d))
    elif fmt == "npz":
        np.savez(f, **{k: np.array(v) for k, v in d.items()})
    else:  # MATLAB users: A, E, C names
        savemat(f, {"A": np.array(d["Phi"]), "E": np.array(d["G"]), "C": np.array(d["Xi"])})
    assert main(["check", str(f)]) == 0
    assert "1.26095" in capsys.readouterr().out


def test_check_output_formats(tmp_path, capsys):
    f = tmp_path / "sys.json"
    f.write_text(json.dumps(_chang_dict()))
    assert main(["check", str(f), "--format", "json"]) == 0
    data = json.loads(capsys.readouterr().out)
    verdicts = {v["design"]: v["exists"] for v in data["designs"]}
    assert verdicts["SMFDO"] and not verdicts["MB-ESO"]
    assert main(["check", str(f), "--format", "markdown"]) == 0
    assert "| design | exists |" in capsys.readouterr().out


@pytest.mark.parametrize(
    ("content", "suffix", "match"),
    [
        (None, ".json", "no such file"),
        ("{not json", ".json", "could not read"),
        ('{"Phi": [[1]], "Xi": [[1]]}', ".json", "missing matrix 'G'"),
        ('{"Phi": [[1, 2]], "G": [[1]], "Xi": [[1]]}', ".json", "Phi must be square"),
        ("x", ".txt", "unsupported file type"),
    ],
)
def test_check_bad_input_exits_2(tmp_path, capsys, content, suffix, match):
    f = tmp_path / f"bad{suffix}"
    if content is not None:
        f.write_text(content)
    assert main(["check", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("setobs: error:") and match in err and "\n" not in err


def test_study_from_yaml(tmp_path, capsys):
    cfg = {"scenario": {"system": "chang2006", "horizon": 20},
           "observers": [{"name": "SMFDO", "kind": "smfdo", "params": {"window": 5}},
                         {"name": "PIO", "kind": "pio"}],
           "runs": 2, "seed": 1, "out": str(tmp_path / "out")}
    f = tmp_path / "study.yaml"
    f.write_text(yaml.safe_dump(cfg))
    assert main(["study", str(f), "--processes", "1"]) == 0
    out = capsys.readouterr().out
    assert "SMFDO" in out and "results.csv" in out
    assert (tmp_path / "out" / "summary.png").exists()


def test_study_bad_config_exits_2(tmp_path, capsys):
    f = tmp_path / "study.yaml"
    f.write_text(yaml.safe_dump({"scenario": {"system": "nope"}, "observers": []}))
    assert main(["study", str(f)]) == 2
    assert "unknown system" in capsys.readouterr().err
    f.write_text(yaml.safe_dump({"banana": 1}))
    assert main(["study", str(f)]) == 2
    assert "unknown keys" in capsys.readouterr().err


def test_help_everywhere(capsys):
    for cmd in (["--help"], ["demo", "--help"], ["check", "--help"], ["study", "--help"]):
        with pytest.raises(SystemExit) as info:
            main(cmd)
        assert info.value.code == 0
    assert "study" in capsys.readouterr().out
    with pytest.raises(SystemExit) as info:
        main(["check"])  # missing argument: argparse exits 2
    assert info.value.code == 2


def test_check_example_names_and_all(capsys):
    assert main(["check", "all"]) == 0
    out = capsys.readouterr().out
    assert out.count("Diagnosis") == 6 and "1.26095" in out  # every example, Chang's zero
    assert "V0 is not diagonal" in out  # Example 1
    assert main(["check", "cgl1", "--format", "markdown"]) == 0
    assert "| variant MB-ESO | yes |" in capsys.readouterr().out
