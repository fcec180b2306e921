"""Campaigns: reproducible per run, identical locally and on Dask, resumable."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import setobs as so
from setobs.exceptions import InvalidValueError
from setobs.studies import ObserverSpec, Scenario, rng_for_run, run_campaign, run_one

SPECS = [ObserverSpec("SMFDO d=5", "smfdo", {"window": 5}), ObserverSpec("PIO", "pio"),
         ObserverSpec("HO", "higher_order")]


def test_runs_are_reproducible_alone():
    sc = Scenario(horizon=30)
    a = sc.simulate(rng_for_run(7, 3))
    b = sc.simulate(rng_for_run(7, 3))
    c = sc.simulate(rng_for_run(7, 4))
    np.testing.assert_array_equal(a.Y, b.Y)
    assert not np.array_equal(a.D, c.D)
    assert np.abs(np.diff(a.D, axis=0)).max() <= 1.0  # increments stay in the box


def test_smfdo_rows_are_sound_and_scores_are_consistent():
    rows = pd.DataFrame(run_one(Scenario(horizon=40), SPECS, run=0, reference_window=None))
    smf = rows[rows.observer == "SMFDO d=5"]
    assert (smf.truth_inside[smf.k > 0] == 1.0).all()
    # Worst-case error over the exact consistent set >= the actual error.
    fin = np.isfinite(rows.worst_case_error)
    assert (rows.worst_case_error[fin] >= rows.error_inf[fin] - 1e-9).all()


def test_local_and_dask_give_identical_tables(tmp_path):
    """Bit for bit: local processes, Dask's default threaded workers, Dask processes.

    On LocalCluster(processes=False, threads_per_worker=2) the SMFDOs of
    concurrent runs shared warm-start state and the campaign aborted.
    """
    distributed = pytest.importorskip("distributed")
    sc = Scenario(horizon=120)
    specs = [*SPECS, ObserverSpec("SMFDO d=10", "smfdo", {"window": 10})]
    local = run_campaign(sc, specs, runs=4, processes=2, progress=False)
    serial = run_campaign(sc, specs, runs=4, processes=1, progress=False)
    pd.testing.assert_frame_equal(local.table, serial.table, check_exact=True)
    for processes in (False, True):
        with distributed.LocalCluster(n_workers=2 if processes else 1,
                                      threads_per_worker=1 if processes else 2,
                                      processes=processes, dashboard_address=None) as cluster, \
                distributed.Client(cluster) as client:
            remote = run_campaign(sc, specs, runs=4, client=client, progress=False)
        pd.testing.assert_frame_equal(local.table, remote.table, check_exact=True)
        assert remote.metadata["backend"] == "dask"
    assert local.metadata["backend"] == "processes"
    smf = local.table[local.table.observer.str.startswith("SMFDO") & (local.table.k > 0)]
    assert (smf.truth_inside == 1.0).all()


def test_resumable_output_and_metadata(tmp_path):
    sc = Scenario(horizon=20, generator="sinusoid", increment=0.1)
    first = run_campaign(sc, SPECS[:2], runs=2, processes=1, out_dir=tmp_path, progress=False)
    (tmp_path / "run_00001.csv").unlink()
    again = run_campaign(sc, SPECS[:2], runs=2, processes=1, out_dir=tmp_path, progress=False)
    pd.testing.assert_frame_equal(first.table, again.table)
    meta = json.loads((tmp_path / "metadata.json").read_text())
    assert meta["runs"] == 2 and meta["scenario"]["generator"] == "sinusoid"
    assert "numpy" in meta["versions"] and "SeedSequence" in meta["seeding"]
    assert (tmp_path / "results.csv").exists()


@pytest.mark.parametrize("gen", ["random_walk", "steps", "sinusoid", "gaussian"])
def test_generators(gen):
    sc = Scenario(system="cgl1", horizon=30, generator=gen, increment=3.0, x0_box=None)
    tr = sc.simulate(rng_for_run(0, 0))
    assert tr.D.shape == (30, 3) and np.isfinite(tr.Y).all()
    if gen == "gaussian":
        assert abs(tr.D[:, 2].mean() - 3.0) < 0.6


def test_bad_scenarios():

    with pytest.raises(InvalidValueError, match="unknown system"):
        Scenario(system="nope")
    with pytest.raises(InvalidValueError, match="unknown generator"):
        Scenario(generator="chirp")
    with pytest.raises(InvalidValueError, match="unknown observer kind"):
        ObserverSpec("x", "particle_filter")


def test_paper_claims_fig1b_on_own_simulations():
    """Li-Cong-Dong Sec. V, Fig. 1(b), on 8 runs simulated here, not by the campaign
    (x+ = Phi x + G d, y = Xi x with the paper's example; d a random walk with
    increments uniform in [-1, 1]^2 from 0; x0 uniform in [-1, 1]^3; the truth d is
    known), scored by each run's mean |d^ - d|_inf over k >= 10:

    * ">40 % better than the SFODO baseline": against a PIO with working gains at the
      stated poles (the printed baseline gains are unstable, so that comparison is
      moot), in every run: 8 of 8, a one-sided sign test's p = 1/256;
    * "no significant improvement from delta = 3 to 20": does NOT hold; delta = 3 is
      worse than 20 by more than 15 % in every run, while 10 -> 20 changes the mean
      error by less than 8 %. Pinned here; the notebook runs the 5000-run campaign and
      the audit's independent code agreed.
    """
    sys = so.examples.chang2006()
    X0 = so.ConstrainedZonotope.from_box(-np.ones(3), np.ones(3))
    errs: dict[str, list[float]] = {"d3": [], "d10": [], "d20": [], "PIO": []}
    for run in range(8):
        rng = np.random.default_rng(100 + run)
        x, d, Y, D = rng.uniform(-1, 1, 3), np.zeros(2), [], []
        for _ in range(70):
            Y.append(sys.Xi @ x)
            D.append(d.copy())
            x = sys.Phi @ x + sys.G @ d
            d = d + rng.uniform(-1, 1, 2)
        Y, D = np.array(Y), np.array(D)
        for name, w in (("d3", 3), ("d10", 10), ("d20", 20)):
            est = so.SMFDO(sys, window=w, restart="box", increment_set=np.ones(2),
                           initial_state_set=X0).run(Y).estimate
            errs[name].append(np.abs(est - D).max(axis=1)[10:].mean())
        est = so.observers.PIO(sys).run(Y).estimate
        errs["PIO"].append(np.abs(est - D).max(axis=1)[10:].mean())
    e = {k: np.array(v) for k, v in errs.items()}
    assert (1 - e["d10"] / e["PIO"] > 0.4).all()
    assert (1 - e["d20"] / e["d3"] > 0.15).all()  # delta = 3 is significantly worse
    assert abs(1 - e["d20"].mean() / e["d10"].mean()) < 0.08  # 10 -> 20: small


@pytest.mark.slow
def test_paper_claims_fig1b_larger_campaign():
    """The same claims on 60 runs x 100 steps (run with ``pytest -m slow``)."""
    specs = [ObserverSpec("d3", "smfdo", {"window": 3, "restart": "box"}),  # (Algorithm 1)
             ObserverSpec("d10", "smfdo", {"window": 10, "restart": "box"}),
             ObserverSpec("d20", "smfdo", {"window": 20, "restart": "box"}),
             ObserverSpec("PIO", "pio")]
    res = run_campaign(Scenario(horizon=100), specs, runs=60, reference_window=20,
                       progress=False)
    e = res.summary(start=10)["error_inf"]
    assert 1 - e["d10"] / e["PIO"] > 0.4
    assert 1 - e["d20"] / e["d3"] > 0.15
    assert abs(1 - e["d20"] / e["d10"]) < 0.08
    t = res.table
    smfdo = t[t.observer.isin(["d3", "d10", "d20"]) & (t.k > 0)]
    assert (smfdo.truth_inside == 1.0).all()  # soundness over all runs


def test_scenario_takes_a_linear_system(tmp_path):
    """The user's own LinearSystem in a campaign: the SMFDO rows contain the truth;
    the metadata holds the matrices as JSON."""
    import setobs as so

    base = so.examples.chang2006()
    sys_ = so.LinearSystem(base.Phi, base.G, base.Xi, disturbance_names=["a", "b"])
    sc = Scenario(system=sys_, horizon=12)
    res = run_campaign(sc, [ObserverSpec("SMFDO", "smfdo", {"window": 5})], 2, processes=1,
                       out_dir=tmp_path / "o")
    assert (res.table["truth_inside"] == 1).all()
    meta = json.loads((tmp_path / "o" / "metadata.json").read_text())
    np.testing.assert_allclose(meta["scenario"]["system"]["Phi"], sys_.Phi)
    with pytest.raises(TypeError, match="example name, a model file or a LinearSystem"):
        Scenario(system=3)
