"""The command line on good and bad input."""

from __future__ import annotations

import json

import numpy as np
import pytest
import yaml
from scipy.io import savemat

import setobs as so
from setobs.cli import main
from tests.printed import has_number


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
    assert has_number(capsys.readouterr().out, 1.26095, after="finite invariant zeros:")


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
        ('{"Phi": [[1]], "Xi": [[1]]}', ".json", "disturbance channels are not stated"),
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
    assert out.count("Diagnosis") == 6 and has_number(out, 1.26095)  # every example, Chang's zero
    assert "V0 is not diagonal" in out  # Example 1
    assert main(["check", "cgl1", "--format", "markdown"]) == 0
    assert "| variant MB-ESO | yes |" in capsys.readouterr().out


# ---------------------------------------------------------------------------- models
J_, B_ = 1.2e-4, 7.03e-5
MOTOR_CT = {"A": [[0.0, 1.0], [0.0, -B_ / J_]], "B": [[0.0, 0.0], [1 / J_, -1 / J_]],
            "C": [[1.0, 0.0]], "D": [[0.0, 0.0]], "continuous": True,
            "input_names": ["tau", "tau_L"], "disturbance_inputs": ["tau_L"],
            "output_names": ["theta"]}


@pytest.mark.parametrize("fmt", ["yaml", "json", "mat", "npz"])
def test_model_files_in_control_naming(tmp_path, fmt):
    """A, B, C, D with disturbance_inputs and a continuous-time flag: the same model
    as the library's servo motor (ZOH at the record's sampling time)."""
    from setobs.io import load_model

    d = dict(MOTOR_CT)
    f = tmp_path / f"m.{fmt}"
    if fmt == "yaml":
        f.write_text(yaml.safe_dump(d))
    elif fmt == "json":
        f.write_text(json.dumps(d))
    else:  # MATLAB convention: Ts = 0 is continuous; indices for the disturbance inputs
        arrs = {k: np.asarray(d[k]) for k in "ABCD"}
        arrs |= {"Ts": 0.0, "disturbance_inputs": np.array([1]),
                 "input_names": np.array(["tau", "tau_L"])}
        if fmt == "mat":
            savemat(f, arrs)
        else:
            np.savez(f, **arrs)
    sys_ = load_model(f, dt=1e-3)
    ref = so.examples.servo_motor()
    np.testing.assert_allclose(sys_.Phi, ref.Phi, rtol=1e-12)
    np.testing.assert_allclose(sys_.G, ref.G, rtol=1e-12)
    np.testing.assert_allclose(sys_.Gamma, ref.Gamma, rtol=1e-12)
    assert sys_.dt == 1e-3 and sys_.q == 1 and sys_.p == 1
    assert sys_.input_names == ("tau",) and sys_.disturbance_names == ("tau_L",)


def test_check_discretises_a_continuous_model_with_its_Ts(tmp_path, capsys):
    """`setobs check` no longer analyses continuous-time matrices as discrete: the
    servo motor's invariant zero is -0.9998 after ZOH at 1 ms (none in continuous
    time, where treating A as discrete would put the pole at 1 + ... on the wrong
    side)."""
    f = tmp_path / "m.yaml"
    f.write_text(yaml.safe_dump({**MOTOR_CT, "Ts": 1e-3}))
    assert main(["check", str(f)]) == 0
    out = capsys.readouterr().out
    assert has_number(out, -0.999805, rtol=1e-6, after="finite invariant zeros:")
    assert has_number(out, 0.001, rtol=1e-9, after="sampling time")
    f2 = tmp_path / "m2.yaml"
    f2.write_text(yaml.safe_dump(MOTOR_CT))
    assert main(["check", str(f2)]) == 2
    assert "continuous-time model needs a sampling time" in capsys.readouterr().err


# ---------------------------------------------------------------------------- estimate
def _motor_record(tmp_path, N=400, seed=0, noise=1e-4, gap=None):
    """Own simulation of the ZOH motor with a slowly varying load torque; CSV with
    a header, time column, position and commanded torque."""
    rng = np.random.default_rng(seed)
    sys_ = so.examples.servo_motor()
    tau = 0.05 + 0.01 * np.sin(np.arange(N) * 0.02)
    d = 0.03 + np.cumsum(rng.uniform(-1e-3, 1e-3, N))
    Y = sys_.simulate(d[:, None], tau[:, None])[0][:, 0] + noise * rng.uniform(-1, 1, N)
    if gap is not None:
        Y[gap] = np.nan
    f = tmp_path / "rec.csv"
    lines = ["t,theta,tau"] + [
        f"{k * 1e-3:.6f},{'' if np.isnan(y) else repr(float(y))},{float(u)!r}"
        for k, (y, u) in enumerate(zip(Y, tau, strict=True))]
    f.write_text("\n".join(lines) + "\n")
    return f, d


def test_estimate_end_to_end_contains_the_truth(tmp_path, capsys):
    rec, d = _motor_record(tmp_path, gap=slice(200, 210))
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump(MOTOR_CT))
    out = tmp_path / "out"
    assert main(["estimate", str(rec), "--model", str(model), "--outputs", "theta",
                 "--inputs", "tau", "--time", "t", "--increment", "1e-3", "--noise", "1e-4",
                 "--out", str(out), "--no-progress"]) == 0
    text = capsys.readouterr().out
    assert "steps 400" in text and "first inconsistent step: none" in text
    import pandas as pd

    df = pd.read_csv(out / "estimate.csv")
    assert list(df.columns) == ["time", "tau_L", "tau_L_lo", "tau_L_hi", "error_bound", "status"]
    np.testing.assert_allclose(df["time"], np.arange(400) * 1e-3, atol=1e-9)
    ok = np.isfinite(df["tau_L_lo"])
    assert ok.sum() > 350
    assert np.all(df["tau_L_lo"][ok] <= d[ok] + 1e-12) and np.all(d[ok] <= df["tau_L_hi"][ok]
                                                                   + 1e-12)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == 400 and summary["first_inconsistent_step"] is None
    assert abs(summary["sampling_time"] - 1e-3) < 1e-12
    assert (out / "estimate.png").stat().st_size > 10_000


def test_estimate_states_writes_certified_state_bounds(tmp_path, capsys):
    """--states: the CSV gains ``<state>_lo``/``_hi`` columns holding the simulated
    states (own simulation, the model's discretisation)."""
    rec, d = _motor_record(tmp_path)
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump(MOTOR_CT))
    out = tmp_path / "out"
    assert main(["estimate", str(rec), "--model", str(model), "--outputs", "theta",
                 "--inputs", "tau", "--time", "t", "--increment", "1e-3", "--noise", "1e-4",
                 "--out", str(out), "--no-progress", "--no-plot", "--states"]) == 0
    import pandas as pd

    df = pd.read_csv(out / "estimate.csv")
    sys_ = so.examples.servo_motor()
    tau = 0.05 + 0.01 * np.sin(np.arange(400) * 0.02)
    X = sys_.simulate(d[:, None], tau[:, None])[1]
    from setobs.io import load_model

    names = load_model(str(model), dt=1e-3).state_names  # (none in the file: x0, x1)
    assert list(df.columns)[-4:] == [f"{n}_{b}" for n in names for b in ("lo", "hi")]
    for i, name in enumerate(names):
        lo, hi = df[f"{name}_lo"].to_numpy(), df[f"{name}_hi"].to_numpy()
        ok = np.isfinite(lo) & np.isfinite(hi)
        assert ok.sum() > 390
        assert np.all(lo[ok] <= X[ok, i] + 1e-12) and np.all(X[ok, i] <= hi[ok] + 1e-12)


def test_estimate_calibrate_and_inconsistent_data(tmp_path, capsys):
    """--calibrate finds a smallest bound at most the simulated noise, validates it on
    the last 30 % and uses it with its 10 % safety, and the record accepts it; a too
    small bound reports the first inconsistent step (not a crash); skipping stops at
    max_skip_fraction."""
    rec, _ = _motor_record(tmp_path, noise=2e-4)
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump(MOTOR_CT))
    args = ["estimate", str(rec), "--model", str(model), "--outputs", "1", "--inputs", "2",
            "--dt", "1e-3", "--increment", "1e-3", "--no-plot", "--no-progress"]
    assert main([*args, "--calibrate", "--out", str(tmp_path / "a")]) == 0
    text = capsys.readouterr().out
    noise = float(text.split("calibrated noise: theta ")[1].split()[0])
    smallest = float(text.split("smallest bound theta ")[1].split()[0])
    validated = float(text.split("validated theta ")[1].split()[0])
    assert 0 < smallest <= validated <= 2e-4 * (1 + 1e-6) + 1e-7
    assert noise == pytest.approx(1.1 * validated, rel=1e-4)  # (printed to 6 digits)
    assert "first inconsistent step: none" in text
    # --safety 0: the validated bound itself (it still explains the record)
    assert main([*args, "--calibrate", "--safety", "0", "--out", str(tmp_path / "s")]) == 0
    text = capsys.readouterr().out
    noise0 = float(text.split("calibrated noise: theta ")[1].split()[0])
    assert noise0 == pytest.approx(validated, rel=1e-4)
    assert json.loads((tmp_path / "s" / "summary.json").read_text())[
        "calibration"]["safety"] == 0.0
    assert main([*args, "--safety", "0", "--noise", "1e-3", "--out", str(tmp_path / "t")]) == 2
    assert "apply to --calibrate only" in capsys.readouterr().err
    # too small a bound: by default the run stops at the first inconsistent sample,
    # exit 1, with the step, its time and what to do (it used to skip silently)
    assert main([*args, "--noise", "1e-6", "--out", str(tmp_path / "b")]) == 1
    err = capsys.readouterr().err
    step = int(err.split("at step ")[1].split()[0])
    assert has_number(err, step * 1e-3, rtol=1e-9, after="(t =")
    assert "--calibrate" in err and "--on-inconsistent skip" in err
    assert not (tmp_path / "b" / "summary.json").exists()
    # skipping is explicit and stops once more than 1 % of the samples were skipped
    assert main([*args, "--noise", "1e-6", "--on-inconsistent", "skip",
                 "--out", str(tmp_path / "d")]) == 1
    err = capsys.readouterr().err
    assert "more than max_skip_fraction = 1 % of 400 samples" in err
    assert "--max-skip-fraction" in err
    # with the limit raised, a run that skips more than 1 % says so on stderr
    assert main([*args, "--noise", "1e-6", "--on-inconsistent", "skip",
                 "--max-skip-fraction", "1", "--out", str(tmp_path / "c")]) == 0
    summary = json.loads((tmp_path / "c" / "summary.json").read_text())
    assert summary["first_inconsistent_step"] == step
    skipped = summary["statuses"].get("skipped", 0)
    assert skipped > 0.01 * 400
    err = capsys.readouterr().err
    assert f"warning: {skipped} of 400 samples" in err and "--calibrate" in err


def test_estimate_help_states_the_inconsistency_policy(capsys):
    with pytest.raises(SystemExit):
        main(["estimate", "--help"])
    text = " ".join(capsys.readouterr().out.split())
    assert "'raise' (default) stops at the first one with exit code 1" in text
    assert "'skip' drops such samples" in text and "'reset' restarts" in text


def test_estimate_takes_the_time_axis_from_the_models_Ts(tmp_path, capsys):
    """A record without a time column and no --dt: the model file's Ts gives the
    time axis (CSV, summary, plot); without any sampling time the CSV has steps."""
    import pandas as pd

    rec, _ = _motor_record(tmp_path, N=60)
    raw = np.loadtxt(rec, delimiter=",", skiprows=1)
    notime = tmp_path / "notime.csv"
    np.savetxt(notime, raw[:, 1:], delimiter=",", header="theta,tau", comments="")
    sys_ = so.examples.servo_motor()
    model = tmp_path / "d.yaml"
    model.write_text(yaml.safe_dump({"Phi": sys_.Phi.tolist(), "G": sys_.G.tolist(),
                                     "Xi": sys_.Xi.tolist(), "Gamma": sys_.Gamma.tolist(),
                                     "Ts": 1e-3}))
    args = ["estimate", str(notime), "--model", str(model), "--outputs", "theta",
            "--inputs", "tau", "--increment", "1e-3", "--noise", "1e-4", "--no-progress",
            "--unit", "N m"]
    assert main([*args, "--out", str(tmp_path / "a")]) == 0
    df = pd.read_csv(tmp_path / "a" / "estimate.csv")
    np.testing.assert_allclose(df["time"], np.arange(60) * 1e-3, rtol=0, atol=1e-15)
    assert json.loads((tmp_path / "a" / "summary.json").read_text())["sampling_time"] == 0.001
    no_ts = tmp_path / "n.yaml"
    no_ts.write_text(yaml.safe_dump({"Phi": sys_.Phi.tolist(), "G": sys_.G.tolist(),
                                     "Xi": sys_.Xi.tolist(), "Gamma": sys_.Gamma.tolist()}))
    args[args.index(str(model))] = str(no_ts)
    assert main([*args, "--out", str(tmp_path / "b"), "--no-plot"]) == 0
    df = pd.read_csv(tmp_path / "b" / "estimate.csv")
    assert "time" not in df.columns and list(df["step"]) == list(range(60))
    assert json.loads((tmp_path / "b" / "summary.json").read_text())["sampling_time"] is None


def test_sampling_time_from_a_time_column_is_rounded(tmp_path):
    """Steps of a time column printed in ms average to 0.0009999999999998899 in
    floating point; the record's sampling time is 0.001."""
    from setobs.io import load_record

    t = np.arange(2000) * 1e-3 + 0.123456789
    f = tmp_path / "r.csv"
    np.savetxt(f, np.column_stack([t, np.sin(t)]), delimiter=",", header="t,y", comments="")
    rec = load_record(f, outputs="y", time="t")
    assert rec.dt == 0.001


@pytest.mark.parametrize(("extra", "match"), [
    (["--outputs", "nope"], "no column 'nope'"),
    (["--outputs", "theta", "--increment", "-1"], "--increment must be finite and nonneg"),
    (["--outputs", "theta", "--increment", "1,2"],
     "--increment needs one value (the model has one channel), got 2"),
    (["--outputs", "theta", "--window", "ten"], "--window must be an integer"),
    (["--outputs", "theta,t"], "the model has 1 output(s), the record 2"),
    (["--outputs", "theta", "--no-inputs"], "name the input columns with --inputs"),
    (["--outputs", "theta", "--dt", "0.5"], "disagrees with the time column"),
])
def test_estimate_bad_options_exit_2(tmp_path, capsys, extra, match):
    rec, _ = _motor_record(tmp_path, N=30)
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump(MOTOR_CT))
    args = ["estimate", str(rec), "--model", str(model), "--time", "t", "--inputs", "tau",
            "--increment", "1e-3", "--no-plot", "--no-progress", "--out", str(tmp_path / "o")]
    if "--increment" in extra:
        i = args.index("--increment")
        del args[i : i + 2]
    if "--no-inputs" in extra:
        i = args.index("--inputs")
        del args[i : i + 2]
        extra = [e for e in extra if e != "--no-inputs"]
    assert main([*args, *extra]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("setobs: error:") and match in err and "\n" not in err, err


def test_estimate_bad_record_files(tmp_path, capsys):
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump(MOTOR_CT))
    bad = tmp_path / "bad.csv"
    bad.write_text("t,theta,tau\n0,1,x\n")
    cases = [(tmp_path / "missing.csv", "no such file"), (bad, "non-numeric entry")]
    npz = tmp_path / "two.npz"
    np.savez(npz, a=np.zeros((5, 3)), b=np.zeros((5, 3)))
    cases.append((npz, "name the data matrix with --variable"))
    for f, match in cases:
        assert main(["estimate", str(f), "--model", str(model), "--outputs", "1",
                     "--inputs", "2", "--dt", "1e-3", "--increment", "1"]) == 2
        err = capsys.readouterr().err.strip()
        assert match in err and "\n" not in err, err


def test_study_on_the_users_own_model_file(tmp_path, capsys):
    """A study YAML naming a model file (relative to the YAML): the campaign runs
    on that plant (here the paper example written in A, B, C naming with G)."""
    s = so.examples.chang2006()
    (tmp_path / "plant.yaml").write_text(yaml.safe_dump(
        {"A": s.Phi.tolist(), "G": s.G.tolist(), "C": s.Xi.tolist(), "Ts": 0.1}))
    cfg = {"scenario": {"system": "plant.yaml", "horizon": 15},
           "observers": [{"name": "SMFDO", "kind": "smfdo", "params": {"window": 5}}],
           "runs": 2, "seed": 1, "out": str(tmp_path / "out")}
    f = tmp_path / "study.yaml"
    f.write_text(yaml.safe_dump(cfg))
    assert main(["study", str(f), "--processes", "1"]) == 0
    meta = json.loads((tmp_path / "out" / "metadata.json").read_text())
    assert meta["scenario"]["system"].endswith("plant.yaml")
    import pandas as pd

    table = pd.read_csv(tmp_path / "out" / "results.csv")
    assert len(table) == 2 * 15 and (table["truth_inside"] == 1).all()


def test_check_continuous_model_needs_and_takes_dt(tmp_path, capsys):
    from setobs.cli import main

    f = tmp_path / "m.yaml"
    f.write_text("A: [[0, 1], [0, -1]]\nB: [[0], [1]]\nC: [[1, 0]]\ncontinuous: true\n"
                 "disturbance_inputs: [0]\n")
    assert main(["check", str(f)]) == 2
    assert "needs a sampling time" in capsys.readouterr().err
    assert main(["check", str(f), "--dt", "0.01", "--format", "json"]) == 0
    out = json.loads(capsys.readouterr().out)
    # position measured, d enters the velocity: (x, d) is observable from y, so Theorem 1
    # holds (rank [O, IbarOG] = rank O + q)
    assert {d["design"]: d["exists"] for d in out["designs"]}["SMFDO"] is True


def test_estimate_a_model_without_disturbances_is_a_state_estimation(tmp_path, capsys):
    """A model file with ``disturbance_inputs: []`` (q = 0): no --increment (it is refused
    there, and required with a disturbance), --process-noise on the states, the state
    bounds written without --states and holding the own simulation's states, and a plot
    with one panel per state."""
    A = [[0.9, 0.2], [-0.1, 0.8]]
    model = tmp_path / "q0.yaml"
    model.write_text(yaml.safe_dump({"A": A, "B": [[0.0], [1.0]], "C": [[1.0, 0.0]],
                                     "Ts": 0.1, "disturbance_inputs": [],
                                     "input_names": ["u"], "output_names": ["y"]}))
    rng = np.random.default_rng(4)
    N, rw, rv = 120, 0.01, 0.02
    x, X, lines = np.array([0.5, -0.5]), [], ["y,u"]
    for _k in range(N):
        u = float(np.sin(0.1 * _k))
        X.append(x.copy())
        lines.append(f"{float(x[0] + rng.uniform(-rv, rv))!r},{u!r}")
        x = np.array(A) @ x + np.array([0.0, 1.0]) * u + rng.uniform(-rw, rw, 2)
    X = np.array(X)
    rec = tmp_path / "rec.csv"
    rec.write_text("\n".join(lines) + "\n")
    out = tmp_path / "out"
    base = ["estimate", str(rec), "--model", str(model), "--outputs", "y", "--inputs", "u",
            "--noise", str(rv), "--process-noise", str(rw), "--no-progress"]
    assert main([*base, "--out", str(out), "--window", "3"]) == 0
    import pandas as pd

    df = pd.read_csv(out / "estimate.csv")
    assert list(df.columns) == ["time", "error_bound", "status", "x0_lo", "x0_hi", "x1_lo",
                                "x1_hi"]
    for i in range(2):
        lo, hi = df[f"x{i}_lo"].to_numpy(), df[f"x{i}_hi"].to_numpy()
        ok = np.isfinite(lo) & np.isfinite(hi)
        assert ok.sum() >= N - 2
        assert np.all(lo[ok] <= X[ok, i]) and np.all(X[ok, i] <= hi[ok])
    summary = json.loads((out / "summary.json").read_text())
    assert summary["restart"] == "auto"
    assert summary["process_noise"] == pytest.approx([rw, rw], rel=1e-12)
    import matplotlib.image as mpimg

    h, w = mpimg.imread(out / "estimate.png").shape[:2]
    assert h == round(4 * 2.6 * 110) and w == 8 * 110  # two panels per state
    capsys.readouterr()
    assert main([*base, "--increment", "1e-3", "--out", str(tmp_path / "b")]) == 2
    assert "no disturbance" in capsys.readouterr().err
    motor = tmp_path / "m.yaml"
    motor.write_text(yaml.safe_dump(MOTOR_CT))
    assert main(["estimate", str(rec), "--model", str(motor), "--outputs", "y",
                 "--inputs", "u", "--dt", "1e-3", "--out", str(tmp_path / "c")]) == 2
    assert "--increment" in capsys.readouterr().err


def test_estimate_asks_for_a_noise_bound_and_help_shows_every_default(tmp_path, capsys):
    # without --noise or --calibrate the run took zero noise on a
    # measured record and stopped "inconsistent at step k"
    rec, _ = _motor_record(tmp_path, N=60)
    model = tmp_path / "m.yaml"
    model.write_text(yaml.safe_dump(MOTOR_CT))
    base = ["estimate", str(rec), "--model", str(model), "--outputs", "theta", "--inputs",
            "tau", "--time", "t", "--increment", "1e-3", "--no-plot", "--no-progress"]
    assert main([*base, "--out", str(tmp_path / "a")]) == 2
    err = capsys.readouterr().err
    assert "no measurement-noise bound given" in err
    assert "--noise" in err and "--calibrate" in err and "--noise 0" in err
    # an explicit zero is exact measurements, as asked: this noisy record is then
    # inconsistent (exit 1), where a bound of the simulated noise explains it
    assert main([*base, "--noise", "0", "--out", str(tmp_path / "b")]) == 1
    capsys.readouterr()
    assert main([*base, "--noise", "1e-4", "--out", str(tmp_path / "c")]) == 0
    capsys.readouterr()
    for cmd in ("estimate", "demo", "check", "study"):
        with pytest.raises(SystemExit):
            main([cmd, "--help"])
        # every option's entry (from a line "  --name" to the next) states its default
        entries: list[str] = []
        for line in capsys.readouterr().out.splitlines():
            if line.startswith("  -"):
                entries.append(line)
            elif entries and line.startswith("    "):
                entries[-1] += " " + line.strip()
            elif not line.startswith("   "):
                entries.append("")  # (a section heading or usage ends an entry)
        options = [e for e in entries if e.startswith("  --")]
        assert options, cmd
        for e in options:
            if e.split()[0] in ("--model", "--outputs"):  # (required)
                continue
            assert "default" in e, (cmd, e)
