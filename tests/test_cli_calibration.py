"""``setobs estimate --calibrate`` against the API on the same record, for both model
kinds (reproducer ``cli_calibrate_ignores_process_noise.sh``: with a
model without disturbance the CLI ignored ``--process-noise``, printed a calibrated
noise of 4261 rad and wrote +-4261 rad bands, exit 0, where the API gives 1.35 counts).

The API side builds its model independently of the CLI's model files: python-control's
``ss`` with the model files' numbers, discretised by ``LinearSystem.from_statespace`` (as
the reproducer does). The
record: the first 4000 samples of the HSM150 motor record, written to a CSV here.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

import setobs as so
from setobs.cli import main
from tests.datasets import HSM150

pytestmark = pytest.mark.skipif(HSM150 is None, reason="the HSM150 record is not here")
REGRESSIONS = Path(__file__).resolve().parent / "data" / "regressions"
COUNT = 2 * np.pi / 10_000
N = 4000
W = [4.2e-4, 0.84]


@pytest.fixture(scope="module")
def record(tmp_path_factory):
    from scipy.io import loadmat

    m = loadmat(HSM150, squeeze_me=True)
    data = m["data"][:N]
    d = tmp_path_factory.mktemp("rec")
    path = d / "motor.csv"
    np.savetxt(path, data[:, [0, 2, 4]], delimiter=",", header="time,theta,tau",
               comments="")
    return path, data[:, 2:3], data[:, 4:5]


def _api_system(with_load: bool):
    """The model files' numbers (B / J = 0.5858333, 1 / J = 8333.333, as printed there)
    in python-control, discretised by ``from_statespace``."""
    control = pytest.importorskip("control")
    A = [[0, 1], [0, -0.5858333]]
    if with_load:
        ss = control.ss(A, [[0, 0], [8333.333, -8333.333]], [[1, 0]], 0,
                        inputs=["tau", "tau_L"], outputs=["theta"])
        return so.LinearSystem.from_statespace(ss, disturbance_inputs=["tau_L"], dt=1e-3)
    ss = control.ss(A, [[0], [8333.333]], [[1, 0]], 0, inputs=["tau"], outputs=["theta"])
    return so.LinearSystem.from_statespace(ss, disturbance_inputs=[], dt=1e-3)


def _read(out: Path):
    import pandas as pd

    return pd.read_csv(out / "estimate.csv"), json.loads((out / "summary.json").read_text())


def test_state_model_calibrates_with_its_process_noise(record, tmp_path, capsys):
    """The reproducer's command on the record: the CLI's calibrated bound and its state
    bands are the API's (calibrate_noise with process_noise, then the SMFDO)."""
    path, Y, U = record
    model = tmp_path / "motor_q0.yaml"
    shutil.copy(REGRESSIONS / "motor_q0.yaml", model)
    out = tmp_path / "cli"
    assert main(["estimate", str(path), "--model", str(model), "--outputs", "theta",
                 "--inputs", "tau", "--time", "time", "--process-noise", ",".join(map(str, W)),
                 "--calibrate", "--out", str(out), "--no-plot", "--no-progress"]) == 0
    printed = capsys.readouterr().out
    df, summary = _read(out)
    sys_ = _api_system(with_load=False)
    cal = so.calibrate_noise(sys_, Y, U, increment=[], process_noise=W)
    cli_radii = np.array(summary["calibration"]["radii"])
    np.testing.assert_allclose(cli_radii, cal.radii, rtol=1e-6)
    assert 0.1 * COUNT < cal.radii[0] < 3 * COUNT          # (it was 4261 rad)
    assert f"theta {cal.radii[0]:.6g}" in printed
    res = so.SMFDO(sys_, window=10, measurement_noise=cli_radii, process_noise=W,
                   state_bounds=True).run(Y, U)
    for i, name in enumerate(("theta", "omega")):
        np.testing.assert_allclose(df[f"{name}_lo"], res.state_lo[:, i], rtol=1e-6, atol=1e-9)
        np.testing.assert_allclose(df[f"{name}_hi"], res.state_hi[:, i], rtol=1e-6, atol=1e-9)
    assert np.nanmax(df["theta_hi"] - df["theta_lo"]) < 10 * COUNT


def test_disturbance_model_calibrates_like_the_api(record, tmp_path, capsys):
    """The README's motor model with the load torque as a disturbance, --increment 1e-3,
    --calibrate, per channel: the same bound and the same load-torque band as the API."""
    path, Y, U = record
    model = tmp_path / "motor.yaml"
    model.write_text("A: [[0, 1], [0, -0.5858333]]\nB: [[0, 0], [8333.333, -8333.333]]\n"
                     "C: [[1, 0]]\ncontinuous: true\ninput_names: [tau, tau_L]\n"
                     "disturbance_inputs: [tau_L]\noutput_names: [theta]\n")
    out = tmp_path / "cli"
    assert main(["estimate", str(path), "--model", str(model), "--outputs", "theta",
                 "--inputs", "tau", "--time", "time", "--increment", "1e-3", "--calibrate",
                 "--per-channel", "--time-limit", "60", "--out", str(out), "--no-plot",
                 "--no-progress"]) == 0
    capsys.readouterr()
    df, summary = _read(out)
    assert summary["calibration"]["per_channel"] is True
    sys_ = _api_system(with_load=True)
    cal = so.calibrate_noise(sys_, Y, U, increment=1e-3, per_channel=True)
    cli_radii = np.array(summary["calibration"]["radii"])
    np.testing.assert_allclose(cli_radii, cal.radii, rtol=1e-6)
    res = so.SMFDO(sys_, window=10, increment_set=[1e-3], measurement_noise=cli_radii).run(Y, U)
    np.testing.assert_allclose(df["tau_L_lo"], res.lo[:, 0], rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(df["tau_L_hi"], res.hi[:, 0], rtol=1e-6, atol=1e-9)


def test_calibration_options_without_calibrate_are_refused(record, tmp_path, capsys):
    path = record[0]
    model = tmp_path / "motor_q0.yaml"
    shutil.copy(REGRESSIONS / "motor_q0.yaml", model)
    base = ["estimate", str(path), "--model", str(model), "--outputs", "theta", "--inputs",
            "tau", "--time", "time", "--noise", "1e-3", "--no-plot", "--out", str(tmp_path)]
    for extra in (["--per-channel"], ["--time-limit", "5"]):
        assert main([*base, *extra]) == 2
        assert "apply to --calibrate only" in capsys.readouterr().err
