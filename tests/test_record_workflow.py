"""A record in the workflow: model files that refuse misspelt keys and carry units, one
spelling of the result's columns in the API and the CLI, state bands drawn around
their centre."""

from __future__ import annotations

import json

import matplotlib
import numpy as np
import pytest
import yaml

import setobs as so
from setobs.cli import main
from setobs.io import MODEL_KEYS, ModelFileError, load_model, model_units

matplotlib.use("Agg")

A = [[0.9, 0.2], [-0.1, 0.8]]
BASE = {"A": A, "B": [[0.0], [1.0]], "C": [[1.0, 0.0]], "Ts": 0.1,
        "disturbance_inputs": [], "input_names": ["u"], "output_names": ["y"]}


@pytest.mark.parametrize("suffix", [".yaml", ".json"])
def test_misspelt_keys_are_refused_with_the_known_keys(tmp_path, suffix):
    bad = {**BASE, "state_name": ["p", "v"], "Tss": 0.1}
    f = tmp_path / f"m{suffix}"
    f.write_text(yaml.safe_dump(bad) if suffix == ".yaml" else json.dumps(bad))
    with pytest.raises(ModelFileError) as err:
        load_model(f)
    msg = str(err.value)
    assert "'state_name' (did you mean 'state_names'?)" in msg and "'Tss'" in msg
    for key in ("state_names", "disturbance_inputs", "units", "Phi", "continuous"):
        assert key in msg and key in MODEL_KEYS
    # the CLI: one line, exit 2
    assert main(["check", str(f)]) == 2


def test_units_are_a_mapping_of_the_models_signals(tmp_path):
    f = tmp_path / "m.yaml"
    f.write_text(yaml.safe_dump({**BASE, "state_names": ["p", "v"],
                                 "units": {"p": "m", "v": "m/s", "u": "N"}}))
    assert model_units(f) == {"p": "m", "v": "m/s", "u": "N"}
    assert load_model(f).state_names == ("p", "v")
    f.write_text(yaml.safe_dump({**BASE, "units": {"p": "m"}}))
    with pytest.raises(ModelFileError, match=r"unknown signal\(s\) \['p'\].*x0, x1, y, u"):
        load_model(f)
    f.write_text(yaml.safe_dump({**BASE, "units": ["m", "m/s"]}))
    with pytest.raises(ModelFileError, match="units must be a mapping"):
        load_model(f)


def _record(tmp_path, N=80):
    rng = np.random.default_rng(7)
    rw, rv = 0.01, 0.02
    x, X, lines = np.array([0.5, -0.5]), [], ["y,u"]
    for k in range(N):
        u = float(np.sin(0.1 * k))
        X.append(x.copy())
        lines.append(f"{float(x[0] + rng.uniform(-rv, rv))!r},{u!r}")
        x = np.array(A) @ x + np.array([0.0, 1.0]) * u + rng.uniform(-rw, rw, 2)
    rec = tmp_path / "rec.csv"
    rec.write_text("\n".join(lines) + "\n")
    return rec, np.array(X), rw, rv


def test_one_spelling_of_the_columns_in_the_api_and_the_cli(tmp_path, capsys):
    """The same model from python-control (generated labels ``x[0]``) and from a model
    file (default names): ``to_pandas()`` and the CLI's CSV have the same columns."""
    control = pytest.importorskip("control")
    import pandas as pd

    rec, X, rw, rv = _record(tmp_path)
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump(BASE))
    out = tmp_path / "out"
    assert main(["estimate", str(rec), "--model", str(model), "--outputs", "y", "--inputs",
                 "u", "--noise", str(rv), "--process-noise", str(rw), "--no-progress",
                 "--no-plot", "--out", str(out)]) == 0
    cli = pd.read_csv(out / "estimate.csv")
    ss = control.ss(A, [[0.0], [1.0]], [[1.0, 0.0]], 0, 0.1)
    assert list(ss.state_labels) == ["x[0]", "x[1]"]          # python-control's spelling
    sys_ = so.LinearSystem.from_statespace(ss, disturbance_inputs=[])
    assert sys_.state_names == ("x0", "x1") and sys_.input_names == ("u0",)
    data = pd.read_csv(rec)
    res = so.SMFDO(sys_, window=10, increment_set=np.zeros(0), measurement_noise=rv,
                   process_noise=rw, state_bounds=True).run(data[["y"]].to_numpy(),
                                                             data[["u"]].to_numpy())
    api = res.to_pandas()
    assert ["time", *api.columns] == list(cli.columns)
    # and the same bands (the same model, record and bounds), containing the truth
    for c in ("x0_lo", "x0_hi", "x1_lo", "x1_hi"):
        np.testing.assert_allclose(api[c].to_numpy(), cli[c].to_numpy(), rtol=1e-9,
                                   atol=1e-12)
    ok = np.isfinite(api["x1_lo"].to_numpy())
    assert np.all(api["x1_lo"].to_numpy()[ok] <= X[ok, 1] + 1e-12)
    assert np.all(X[ok, 1] <= api["x1_hi"].to_numpy()[ok] + 1e-12)
    # python-control's generated input labels still select the disturbance
    ss2 = control.ss(A, [[0.0, 0.0], [1.0, 1.0]], [[1.0, 0.0]], 0, 0.1)
    s2 = so.LinearSystem.from_statespace(ss2, disturbance_inputs=["u[1]"])
    assert s2.q == 1 and s2.p == 1 and s2.disturbance_names == ("d0",)
    with pytest.raises(so.InvalidValueError, match=r"no input named 'w'.*u\[0\]"):
        so.LinearSystem.from_statespace(ss2, disturbance_inputs=["w"])


def test_cli_units_from_the_model_file_and_the_command_line(tmp_path, capsys):
    import matplotlib.image as mpimg

    rec, _, rw, rv = _record(tmp_path, N=40)
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump({**BASE, "state_names": ["p", "v"],
                                     "units": {"p": "m", "v": "m/s"}}))
    out = tmp_path / "out"
    base = ["estimate", str(rec), "--model", str(model), "--outputs", "y", "--inputs", "u",
            "--noise", str(rv), "--process-noise", str(rw), "--no-progress"]
    assert main([*base, "--unit", "v=km/h", "--out", str(out)]) == 0
    s = json.loads((out / "summary.json").read_text())
    assert s["units"] == {"p": "m", "v": "km/h"}
    h, _w = mpimg.imread(out / "estimate.png").shape[:2]
    assert h == round(4 * 2.6 * 110)                           # two panels per state
    capsys.readouterr()
    assert main([*base, "--unit", "q=m", "--out", str(out)]) == 2
    assert "no signal 'q'" in capsys.readouterr().err
    assert main([*base, "--unit", "m", "--out", str(out)]) == 2   # no disturbance to label
    assert "name the signal" in capsys.readouterr().err


def test_state_band_is_drawn_around_its_centre():
    """The lower panel is the band minus its centre (+- the half-width, computed here
    from lo and hi) and the reference minus the centre; labels carry name and unit."""
    import matplotlib.pyplot as plt

    from setobs.plotting import plot_state_band

    N = 200
    t = np.arange(N) * 1e-3
    truth = 3000.0 * t[:, None] * np.array([1.0, 0.0]) + np.array([0.0, 140.0])
    half = np.column_stack([np.full(N, 0.002), 0.4 + 0.3 * np.sin(t * 50)])
    shift = np.column_stack([0.001 * np.cos(t * 30), 0.1 * np.sin(t * 20)])
    from setobs.setmembership import SMFDOResult

    res = SMFDOResult(np.zeros((N, 0)), np.zeros((N, 0)), np.zeros((N, 0)),
                      np.zeros(N), [], np.full(N, "ok"), None, 1e-3, (),
                      state_lo=truth + shift - half, state_hi=truth + shift + half,
                      state_names=("theta", "omega"))
    top, dev = plot_state_band(res, component=1, truth=truth, unit="rad/s")
    assert top.get_ylabel() == "omega [rad/s]" and dev.get_ylabel() == "omega - centre [rad/s]"
    verts = dev.collections[0].get_paths()[0].vertices
    ys = verts[:, 1]
    assert ys.max() == pytest.approx(half[:, 1].max(), rel=1e-9)
    assert ys.min() == pytest.approx(-half[:, 1].max(), rel=1e-9)
    line = next(ln for ln in dev.get_lines() if ln.get_label() == "truth - centre")
    np.testing.assert_allclose(line.get_ydata(), -shift[:, 1], atol=1e-9)
    # the band is inside its panel's range: not squashed by a 0-3300 axis
    lo, hi = dev.get_ylim()
    assert lo <= -half[:, 1].max() and hi >= half[:, 1].max() and hi - lo < 10
    with pytest.raises(so.DimensionError, match=r"component must be in 0\.\.1"):
        plot_state_band(res, component=2)
    plt.close("all")
