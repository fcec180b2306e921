"""What a new user meets first: messages that say what to do, plots that
show the band, no machine paths, and a repository that ignores its virtual env."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import setobs as so

REPO = Path(__file__).parents[1]


def test_inconsistency_says_what_to_do():
    """The API raises by default; the error names the step and the remedies."""
    sys_ = so.LinearSystem([[1.0]], [[1.0]], [[1.0]])
    Y = np.array([[0.0], [0.0], [0.0], [5.0]])           # a jump |dd| <= 0.1 cannot explain
    with pytest.raises(so.ModelInvalidatedError) as info:
        so.SMFDO(sys_, window=None, increment_set=[0.1], measurement_noise=0.01).run(Y)
    msg = str(info.value)
    assert info.value.step == 3 and "step k=3" in msg
    for remedy in ("calibrate_noise", "--calibrate", "measurement_noise", "on_inconsistent='skip'",
                   "'reset'"):
        assert remedy in msg, remedy
    import pickle

    again = pickle.loads(pickle.dumps(info.value))
    assert str(again) == msg and again.step == 3     # the hint is not appended twice


def test_missing_yaml_names_the_right_package(monkeypatch, tmp_path):
    """The hint names the distribution (pyyaml), not the import name (yaml)."""
    from setobs.io import load_model

    monkeypatch.setitem(sys.modules, "yaml", None)     # "import yaml" raises ImportError
    f = tmp_path / "m.yaml"
    f.write_text("Phi: [[1]]\nG: [[1]]\nXi: [[1]]\n")
    with pytest.raises((ImportError, ValueError), match=r"pip install pyyaml\)"):
        load_model(f)


def test_estimate_plot_shows_the_steady_band_with_units():
    """A start-up transient of +-1000 before a band of width 0.1: the y range is
    set by the band, and the label carries the unit."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from setobs.plotting import plot_estimate_band

    class Res:
        names = ("tau_L",)
        dt = 1e-3

    N = 1000
    r = Res()
    r.estimate = np.full((N, 1), 0.04)
    r.lo, r.hi = r.estimate - 0.05, r.estimate + 0.05
    r.lo[:20], r.hi[:20] = -1000.0, 1000.0
    ax = plot_estimate_band(r, unit="N m")
    lo, hi = ax.get_ylim()
    assert -0.03 < lo < -0.01 and 0.09 < hi < 0.11
    assert ax.get_ylabel() == "tau_L [N m]"
    plt.close("all")
    # without a transient the automatic range is left alone
    r.lo[:20], r.hi[:20] = -0.01, 0.09
    ax = plot_estimate_band(r)
    lo, hi = ax.get_ylim()
    assert lo <= -0.01 and hi >= 0.09 and ax.get_ylabel() == "tau_L"
    plt.close("all")


def test_no_machine_paths_in_the_repository():
    """Data are found through $SETOBS_DATA or ../shared/data next to the repository."""
    out = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True)
    if out.returncode != 0:
        pytest.skip("not a git repository")
    pattern = re.compile(r"[\"'`(]/work/")
    hits = [f for f in out.stdout.split()
            if f.endswith((".py", ".ipynb", ".md", ".rst", ".yaml", ".toml", ".cfg"))
            and pattern.search((REPO / f).read_text(errors="replace"))]
    assert not hits, hits


def test_virtual_environments_are_ignored_by_git():
    out = subprocess.run(["git", "check-ignore", ".venv/x", "venv/x"], cwd=REPO,
                         capture_output=True, text=True)
    if out.returncode == 128:   # not a git checkout (an sdist): nothing to check
        pytest.skip("not a git repository")
    assert out.stdout.split() == [".venv/x", "venv/x"]


def test_a_missing_record_says_where_it_comes_from(tmp_path, monkeypatch):
    """``so.io.find_record``: ``$SETOBS_DATA``, then ``shared/data`` beside the checkout
    that holds the current directory; a missing record names its public source and the
    variable to set (the notebooks and the guide stop with this, not a StopIteration)."""
    name = "hsm150/idf_pos_0.06_1.mat"
    monkeypatch.setenv("SETOBS_DATA", str(tmp_path / "data"))
    monkeypatch.chdir(tmp_path)
    with pytest.raises(so.RecordNotFoundError, match="malik-robert/HSM150-data") as err:
        so.io.find_record(name)
    assert "SETOBS_DATA=" in str(err.value) and isinstance(err.value, FileNotFoundError)
    assert str(tmp_path / "data") in str(err.value)
    # beside a checkout: <repo>/../shared/data, found from a folder inside the repository
    repo = tmp_path / "work" / "repo"
    (repo / "notebooks").mkdir(parents=True)
    (repo / "pyproject.toml").write_text("")
    shared = tmp_path / "work" / "shared" / "data" / "hsm150"
    shared.mkdir(parents=True)
    (shared / "idf_pos_0.06_1.mat").write_bytes(b"")
    monkeypatch.chdir(repo / "notebooks")
    assert so.io.find_record(name) == shared / "idf_pos_0.06_1.mat"
    # $SETOBS_DATA first
    (tmp_path / "data" / "hsm150").mkdir(parents=True)
    (tmp_path / "data" / "hsm150" / "idf_pos_0.06_1.mat").write_bytes(b"")
    assert so.io.find_record(name) == tmp_path / "data" / name
