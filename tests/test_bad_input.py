"""Every bad input of the list gives a clear error naming the argument.

Library: ``DimensionError`` (a ``ValueError``) or ``TypeError`` with ``match=``; CLI:
one line on stderr and exit code 2. Each case was silently accepted, mis-blamed or
crashed with a traceback before.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
import yaml

import setobs as so
from setobs import Box, ConstrainedZonotope, DimensionError, LinearSystem
from setobs.cli import main
from setobs.exceptions import ArgumentError, InvalidValueError
from setobs.studies import ObserverSpec, Scenario, run_campaign

CHANG = so.examples.chang2006()
nan, inf = np.nan, np.inf


# ------------------------------------------------------------------ SMFDO parameters
@pytest.mark.parametrize(("kwargs", "exc", "match"), [
    ({"margin": -1e-9}, InvalidValueError, "margin must be nonnegative"),
    ({"margin": nan}, InvalidValueError, "margin must be finite"),
    ({"reset_inflation": 0.0}, InvalidValueError, "reset_inflation must be positive"),
    ({"reset_inflation": -2.0}, InvalidValueError, "reset_inflation must be positive"),
    ({"reset_inflation": nan}, InvalidValueError, "reset_inflation must be finite"),
    ({"window": nan}, InvalidValueError, "window must be a positive integer or None"),
    ({"window": inf}, InvalidValueError, "window must be a positive integer or None"),
    ({"window": [10]}, TypeError, "window must be a positive integer or None"),
    ({"window": True}, TypeError, "window must be a positive integer or None"),
    ({"window": 2.5}, InvalidValueError, "window must be a positive integer or None"),
    ({"window": 0}, InvalidValueError, "window must be a positive integer or None"),
    ({"data_rtol": 0.01}, InvalidValueError, "data_rtol is a rounding-level tolerance"),
    ({"initial_state_set": np.zeros((3, 2))}, TypeError,
     "initial_state_set must be a ConstrainedZonotope or a Box"),
    ({"initial_disturbance_set": [0.0, 1.0]}, TypeError,
     "initial_disturbance_set must be a ConstrainedZonotope or a Box"),
    ({"initial_state_set": Box([0, 0], [1, 1])}, DimensionError,
     "initial_state_set must have dimension 3, got 2"),
    ({"increment_set": [1.0, -1.0]}, InvalidValueError, "increment_set bounds must be nonnegative"),
])
def test_smfdo_parameters(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        so.SMFDO(CHANG, **kwargs)


def test_a_box_is_accepted_where_a_set_is_expected():
    Y = np.zeros((12, 2))
    a = so.SMFDO(CHANG, window=5, initial_state_set=Box(-np.ones(3), np.ones(3)),
                 increment_set=Box(-np.ones(2), np.ones(2))).run(Y)
    b = so.SMFDO(CHANG, window=5,
                 initial_state_set=ConstrainedZonotope.from_box(-np.ones(3), np.ones(3))).run(Y)
    assert np.array_equal(a.lo, b.lo, equal_nan=True)


def test_a_callable_increment_set_returning_an_array_is_named():
    obs = so.SMFDO(CHANG, window=5, increment_set=lambda k: np.ones(2))
    obs.step([0.0, 0.0])
    with pytest.raises(TypeError, match=r"increment_set\(0\) must return a ConstrainedZonotope"):
        obs.step([0.0, 0.0])


@pytest.mark.parametrize("bad", [
    lambda: LinearSystem(CHANG.Phi + 0j, CHANG.G, CHANG.Xi),
    lambda: LinearSystem(CHANG.Phi, CHANG.G * (1 + 1j), CHANG.Xi),
    lambda: ConstrainedZonotope(np.eye(2) * 1j, [0, 0]),
    lambda: so.SMFDO(CHANG).step(np.array([1.0, 2.0]) + 1e-3j),
    lambda: so.SMFDO(CHANG).run(np.zeros((3, 2), dtype=complex) + 1j),
])
def test_complex_arrays_are_refused_not_cast(bad):
    with pytest.raises(ArgumentError, match="must be real"):
        bad()


def test_complex_arrays_with_zero_imaginary_part_are_refused_too():
    with pytest.raises(ArgumentError, match="must be real"):
        LinearSystem(CHANG.Phi.astype(complex), CHANG.G, CHANG.Xi)


def test_violations_with_the_wrong_shape():
    res = so.SMFDO(CHANG, window=5).run(np.zeros((6, 2)))
    with pytest.raises(DimensionError, match=r"D must have shape \(6, 2\)"):
        res.violations(np.zeros((6, 1)))
    with pytest.raises(DimensionError, match=r"D must have shape \(6, 2\)"):
        res.violations(np.zeros(2))  # broadcast over all steps before
    with pytest.raises(DimensionError, match=r"D must have shape \(6, 2\)"):
        res.violations(np.zeros((5, 2)))


def test_cz_with_b_of_the_wrong_length_blames_b():
    with pytest.raises(DimensionError, match=r"b must have one entry per row of A \(2\), got 3"):
        ConstrainedZonotope(np.eye(2), [0, 0], A=np.ones((2, 2)), b=[1, 2, 3])


# ------------------------------------------------------------------ systems
@pytest.mark.parametrize(("idx", "exc", "match"), [
    ([-1], DimensionError, "index -1 is out of range for 3 input"),
    ([3], DimensionError, "index 3 is out of range for 3 input"),
    ([0, 0], InvalidValueError, "index 0 is given twice"),
    ([0.5], ArgumentError, "must hold integer input indices, got 0.5"),
    (["a"], InvalidValueError, r"no input named 'a' \(inputs \['u\[0\]'"),
    ([1.5j], TypeError, "must hold integer input indices"),
    ([True], TypeError, "must hold integer input indices"),
    (None, ArgumentError, "state which inputs are disturbances"),
    (object(), TypeError, "must be a sequence of input indices"),
])
def test_from_statespace_indices(idx, exc, match):
    control = pytest.importorskip("control")
    ss = control.ss(np.diag([0.5, 0.3]), np.ones((2, 3)), np.eye(2), 0, dt=0.1)
    with pytest.raises(exc, match=match):
        LinearSystem.from_statespace(ss, idx)


def test_from_statespace_accepts_numpy_integers():
    control = pytest.importorskip("control")
    ss = control.ss(np.diag([0.5, 0.3]), np.eye(2), np.eye(2), 0, dt=0.1)
    s = LinearSystem.from_statespace(ss, np.array([1]))
    assert s.q == 1 and s.p == 1


@pytest.mark.parametrize("fn", [
    so.analysis.bounded_do_exists, so.analysis.diagnose, so.analysis.invariant_zeros,
    so.analysis.relative_degrees, so.analysis.uio_conditions, so.analysis.pio_conditions,
    so.analysis.modular_conditions, so.analysis.higher_order_conditions,
    so.analysis.augmented_observability, so.analysis.observability_decomposition,
    so.observers.PIO, so.SMFDO,
])
def test_analysis_functions_name_what_to_do_with_a_statespace(fn):
    control = pytest.importorskip("control")
    ss = control.ss(CHANG.Phi, CHANG.G, CHANG.Xi, 0, dt=1.0)
    with pytest.raises(TypeError, match=r"LinearSystem.from_statespace"):
        fn(ss)
    for bad in ((CHANG.Phi, CHANG.G, CHANG.Xi), None):
        with pytest.raises(TypeError, match=r"must be a LinearSystem, got (tuple|NoneType)"):
            fn(bad)


# ------------------------------------------------------------------ campaigns
def test_every_smfdo_parameter_of_a_spec_is_honoured_or_refused():
    with pytest.raises(InvalidValueError, match=r"unknown parameter\(s\) \['windw'\]"):
        ObserverSpec("S", "smfdo", {"windw": 10})
    with pytest.raises(InvalidValueError, match=r"unknown parameter\(s\) \['gain'\].*accepted"):
        ObserverSpec("P", "pio", {"gain": 1.0})
    with pytest.raises(InvalidValueError, match="window must be a positive integer"):
        ObserverSpec("S", "smfdo", {"window": inf})
    with pytest.raises(InvalidValueError, match="unknown parameter"):
        ObserverSpec("P", "pio_printed", {"P": 1})
    # honoured: fast=False and a different increment set change what runs
    from setobs.studies import run_one

    sc = Scenario(horizon=12)
    rows = run_one(sc, [ObserverSpec("a", "smfdo", {"window": 4}),
                        ObserverSpec("b", "smfdo", {"window": 4, "increment_set": 3.0}),
                        ObserverSpec("c", "smfdo", {"window": 4, "fast": False})], run=0)
    import pandas as pd

    t = pd.DataFrame(rows).set_index(["observer", "k"])
    late = t.xs(11, level="k")
    assert late.loc["b", "error_bound"] > late.loc["a", "error_bound"]  # the wider increment set
    assert abs(late.loc["c", "error_bound"] - late.loc["a", "error_bound"]) < 1e-7


def test_observer_names_must_be_distinct():
    with pytest.raises(InvalidValueError, match="observer names must be distinct"):
        run_campaign(Scenario(horizon=5), [ObserverSpec("x", "pio"), ObserverSpec("x", "smfdo")],
                     runs=1, processes=1, progress=False)


def test_bad_parameters_fail_before_any_run():
    with pytest.raises(InvalidValueError, match="too small"):
        run_campaign(Scenario(horizon=5), [ObserverSpec("s", "smfdo", {"window": 1})],
                     runs=100, processes=1, progress=False)


@pytest.mark.parametrize("runs", [2.7, True, "3", 0])
def test_runs_must_be_a_positive_integer(runs):
    with pytest.raises(InvalidValueError, match="runs must be a positive integer"):
        run_campaign(Scenario(horizon=5), [ObserverSpec("p", "pio")], runs=runs,
                     processes=1, progress=False)


def test_resuming_into_a_directory_of_another_campaign_is_refused(tmp_path):
    sc = Scenario(horizon=6)
    run_campaign(sc, [ObserverSpec("p", "pio")], runs=2, processes=1, out_dir=tmp_path,
                 progress=False)
    with pytest.raises(InvalidValueError, match=r"different campaign.*scenario"):
        run_campaign(Scenario(horizon=7), [ObserverSpec("p", "pio")], runs=2, processes=1,
                     out_dir=tmp_path, progress=False)
    with pytest.raises(InvalidValueError, match=r"different campaign.*base_seed"):
        run_campaign(sc, [ObserverSpec("p", "pio")], runs=2, processes=1, out_dir=tmp_path,
                     base_seed=1, progress=False)
    with pytest.raises(InvalidValueError, match=r"different campaign.*observers"):
        run_campaign(sc, [ObserverSpec("p", "higher_order")], runs=2, processes=1,
                     out_dir=tmp_path, progress=False)
    (tmp_path / "request.json").unlink()
    with pytest.raises(InvalidValueError, match="without a record"):
        run_campaign(sc, [ObserverSpec("p", "pio")], runs=2, processes=1, out_dir=tmp_path,
                     progress=False)


# ------------------------------------------------------------------ CLI
def _study(tmp_path, **cfg):
    base = {"scenario": {"system": "chang2006", "horizon": 8},
            "observers": [{"name": "S", "kind": "smfdo", "params": {"window": 4}}],
            "runs": 1, "out": str(tmp_path / "out")}
    base.update(cfg)
    f = tmp_path / "study.yaml"
    f.write_text(yaml.safe_dump(base))
    return f


@pytest.mark.parametrize(("cfg", "match"), [
    ({"observers": [{"name": "S", "kind": "smfdo", "params": {"windw": 4}}]},
     "unknown parameter"),
    ({"observers": [{"name": "P", "kind": "pio", "params": {"poles": "fast"}}]}, "pole"),
    ({"runs": 2.7}, "runs must be an integer, got 2.7"),
    ({"observers": [{"name": "S", "kind": "smfdo"}, {"name": "S", "kind": "pio"}]},
     "observer names must be distinct"),
    ({"observers": [{"name": "S", "kind": "smfdo", "params": {"window": float("inf")}}]},
     "window must be a positive integer"),
    ({"reference_window": 0.5}, "reference_window"),
])
def test_study_bad_configs_exit_2_with_one_line(tmp_path, capsys, cfg, match):
    assert main(["study", str(_study(tmp_path, **cfg)), "--processes", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("setobs: error:") and match in err and "\n" not in err


@pytest.mark.parametrize("content", [
    {"Phi": "abc", "G": [[1]], "Xi": [[1]]},
    {"Phi": [[1, [2]]], "G": [[1]], "Xi": [[1]]},
    {"Phi": {"a": 1}, "G": [[1]], "Xi": [[1]]},
    {"Phi": [[[1]]], "G": [[1]], "Xi": [[1]]},
])
def test_check_with_a_non_matrix_entry(tmp_path, capsys, content):
    f = tmp_path / "sys.json"
    f.write_text(json.dumps(content))
    assert main(["check", str(f)]) == 2
    err = capsys.readouterr().err.strip()
    assert "matrix 'Phi'" in err and "\n" not in err


def test_no_command_is_an_error(capsys):
    assert main([]) == 2
    assert "a command is required" in capsys.readouterr().err


def test_a_closed_pipe_is_not_an_error():
    """``setobs check all | head -1``: exit 0, nothing on stderr."""
    proc = subprocess.run(f"{sys.executable} -m setobs check all | head -1", shell=True,
                          capture_output=True, text=True, timeout=300,
                          executable="/bin/bash")
    assert proc.stdout.strip() == "## chang2006"
    assert "Broken pipe" not in proc.stderr and "Traceback" not in proc.stderr
    status = subprocess.run(f"set -o pipefail; {sys.executable} -m setobs check all | head -1",
                            shell=True, capture_output=True, text=True, timeout=300,
                            executable="/bin/bash")
    assert status.returncode == 0


# ------------------------------------------------------------------ round 2
_P, _G, _X = CHANG.Phi, CHANG.G, CHANG.Xi


def _nonlinear_order_zero():
    from setobs.observers import NonlinearModularObserver

    return NonlinearModularObserver(so.examples.modular_example(), A0=0.4, B0=1.0, Aw=0.6,
                                    Bw=1.0, order=0, x0=[1.0])


@pytest.mark.parametrize(("make", "error", "match"), [
    (lambda: LinearSystem(np.diag([1e200, 0.5, 0.5]), _G, _X),
     InvalidValueError, r"Phi has an entry of 1e\+200 .* at most 1e\+150"),
    (lambda: LinearSystem(np.zeros((0, 0)), np.zeros((0, 1)), np.zeros((1, 0))),
     DimensionError, "a system needs at least one state"),
    (lambda: so.SMFDO(CHANG, window=10).run(np.zeros((5, 2)), np.ones((5, 1))),
     ArgumentError, "U is given but the system has no inputs"),
    (lambda: so.calibrate_noise(CHANG, np.zeros((5, 2)), np.ones((5, 1)), increment=1.0),
     ArgumentError, "U is given but the system has no inputs"),
    (lambda: so.SMFDO(CHANG, window=10).run(np.full((5, 2), 1e300)),
     InvalidValueError, r"Y has an entry of 1e\+300"),
    (lambda: ConstrainedZonotope.from_vertices(np.zeros((0, 2))),
     DimensionError, "from_vertices needs at least one point"),
    (_nonlinear_order_zero, InvalidValueError, "order .* must be an integer >= 1, got 0"),
])
def test_round2_inputs_get_a_clear_error(make, error, match):
    with pytest.raises(error, match=match):
        make()


def test_round2_cli_inputs_get_one_line_and_exit_2(tmp_path, capsys):
    (tmp_path / "m.yaml").write_text("Phi: [[1.0, 0.1], [0.0, 0.9]]\nG: [[0.0], [0.1]]\n"
                                     "Xi: [[1.0, 0.0]]\n")
    (tmp_path / "big.yaml").write_text("Phi: [[1e200, 0.0], [0.0, 0.9]]\nG: [[0.0], [0.1]]\n"
                                       "Xi: [[1.0, 0.0]]\n")
    (tmp_path / "huge.csv").write_text(
        "t,y\n" + "".join(f"{k * 0.01},{1e308 if k % 2 else -1e308}\n" for k in range(20)))
    cases = [
        (["check", str(tmp_path / "big.yaml")], "at most 1e+150"),
        (["estimate", str(tmp_path / "huge.csv"), "--model", str(tmp_path / "m.yaml"),
          "--outputs", "y", "--increment", "0.01", "--noise", "0", "--no-plot",
          "--out", str(tmp_path / "o")], "Y has an entry of -1e+308"),
        (["estimate", str(tmp_path / "huge.csv"), "--model", str(tmp_path / "m.yaml"),
          "--outputs", "y", "--increment", "0.01,0.02", "--no-plot",
          "--out", str(tmp_path / "o")], "--increment needs one value"),
    ]
    import warnings

    for args, match in cases:
        with warnings.catch_warnings():
            warnings.simplefilter("error")      # no overflow warnings before the error
            assert main(args) == 2, args
        err = capsys.readouterr().err.strip()
        assert err.startswith("setobs: error:") and match in err and "\n" not in err, err
