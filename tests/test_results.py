"""One result protocol: estimate, to_pandas, plot(ax), summary (a DataFrame), unpacking."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np
import pandas as pd
import pytest

import setobs as so
from setobs.observers import PIO, HigherOrderObserver


@pytest.fixture(scope="module")
def data():
    sys = so.LinearSystem.from_matrices(A=so.examples.chang2006().Phi,
                                        G=so.examples.chang2006().G,
                                        C=so.examples.chang2006().Xi, dt=0.1)
    rng = np.random.default_rng(3)
    d, D = np.array([0.5, -0.2]), []
    for _ in range(40):
        D.append(d.copy())
        d = d + rng.uniform(-0.05, 0.05, 2)
    D = np.array(D)
    return sys, sys.simulate(D)[0], D


def test_every_result_has_the_protocol(data):
    sys, Y, _ = data
    smfdo = so.SMFDO(sys, window=8, increment_set=[0.05, 0.05]).run(Y)
    pio = PIO(sys).run(Y)
    table = so.compare.compare({"PIO": pio.estimate}, smfdo)
    for res in (smfdo, pio, table):
        assert isinstance(res.summary(), pd.DataFrame)
        assert res.summary().index.name == "observer"
        assert isinstance(res.to_pandas(), pd.DataFrame)
        fig, ax = plt.subplots()
        assert res.plot(ax=ax) is ax and len(ax.lines) >= 1
        plt.close(fig)
    for res in (smfdo, pio):
        assert res.estimate.shape == (40, 2)
        df = res.to_pandas()
        assert df.index.name == "time"
        np.testing.assert_allclose(df.index.to_numpy(), 0.1 * np.arange(40))
        np.testing.assert_array_equal(df["d0"].to_numpy(), res.estimate[:, 0])


def test_unpacking_like_python_control(data):
    sys, Y, _ = data
    t, est = PIO(sys).run(Y)
    np.testing.assert_allclose(t, 0.1 * np.arange(40))
    assert est.shape == (40, 2)
    t2, est2, lo, hi = so.SMFDO(sys, window=8, increment_set=[0.05, 0.05]).run(Y)
    np.testing.assert_array_equal(t2, t)
    fin = np.isfinite(lo) & np.isfinite(hi)
    np.testing.assert_allclose(est2[fin], 0.5 * lo[fin] + 0.5 * hi[fin])


def test_summaries_against_independent_numbers(data):
    sys, Y, D = data
    res = so.SMFDO(sys, window=8, increment_set=[0.05, 0.05]).run(Y)
    s = res.summary(truth=D, start=10).loc["SMFDO"]
    err = np.abs(res.estimate[10:] - D[10:]).max(axis=1)
    assert s["error_inf"] == pytest.approx(err.mean())
    assert s["max_error_inf"] == pytest.approx(err.max())
    half = 0.5 * (res.hi[10:] - res.lo[10:]).max(axis=1)  # worst case of the centre in [lo, hi]
    assert s["error_bound"] == pytest.approx(half.mean(), rel=1e-12)
    assert s["max_error_bound"] == pytest.approx(half.max(), rel=1e-12)
    assert s["truth_inside"] == 1.0  # sound
    pio = PIO(sys).run(Y)
    p = pio.summary(truth=D, start=10).loc["PIO"]
    assert p["error_inf"] == pytest.approx(np.abs(pio.estimate[10:] - D[10:]).max(axis=1).mean())
    # compare: worst-case error of each estimate over the box [lo, hi], by its closed form
    ho = HigherOrderObserver(sys).run(Y).estimate
    table = so.compare.compare({"HO": ho}, res)
    k = 25
    worst = np.maximum(ho[k] - res.lo[k], res.hi[k] - ho[k]).max()
    assert table.worst_case_error["HO"][k] == pytest.approx(worst)
    assert table.summary(start=10).loc["HO", "ratio"] >= 1.0


def test_old_names_warn(data):
    sys, Y, _ = data
    r = PIO(sys).run(Y)
    with pytest.warns(DeprecationWarning, match="estimate"):
        np.testing.assert_array_equal(r.d_hat, r.estimate)
