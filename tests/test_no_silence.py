"""Places where a useless or misleading answer came back without a word:
a record with nothing measured, advice that names what the model does not
have, a printed result of half a megabyte, hull LPs on rows scaled by 2^+-30.

Oracles: counts and extremes computed here from the result's arrays; scipy's linprog
on the unscaled set for the hull LPs; the models' own parameters for the advice.
"""

from __future__ import annotations

import pickle
import warnings

import numpy as np
import pytest
from scipy.optimize import linprog

import setobs as so
from setobs.cli import main
from setobs.exceptions import (
    InvalidValueError,
    MissingDataWarning,
    ModelInvalidatedError,
    SolverWarning,
)
from setobs.tolerances import MISSING_WARN_FRACTION


# ------------------------------------------------------------------ missing samples
def test_a_record_with_nothing_measured_is_refused(tmp_path, capsys):
    sys_ = so.examples.chang2006()
    with pytest.raises(InvalidValueError, match=r"no measured .* all 50 samples are missing"):
        so.SMFDO(sys_, window=5).run(np.full((50, 2), np.nan))
    rec = tmp_path / "r.csv"
    rec.write_text("t,y\n" + "".join(f"{0.1 * k:.1f},nan\n" for k in range(20)))
    model = tmp_path / "m.yaml"
    model.write_text("Phi: [[0.5]]\nG: [[1.0]]\nXi: [[1.0]]\n")
    assert main(["estimate", str(rec), "--model", str(model), "--outputs", "y",
                 "--time", "t", "--increment", "0.1", "--noise", "0.1", "--no-plot",
                 "--out", str(tmp_path / "o")]) == 2
    assert "no measured" in capsys.readouterr().err


def test_a_mostly_missing_record_warns_with_its_fraction():
    sys_ = so.examples.chang2006()
    Y = sys_.simulate(np.ones((60, 2)))[0]
    sparse = Y.copy()
    sparse[np.arange(60) % 5 != 0] = np.nan              # 80 % missing
    with pytest.warns(MissingDataWarning, match=r"80\.0 % of the record's output samples"):
        so.SMFDO(sys_, window=5).run(sparse)
    some = Y.copy()
    some[::3] = np.nan                                   # 33 % missing: below the limit
    assert np.isnan(some).mean() < MISSING_WARN_FRACTION
    with warnings.catch_warnings():
        warnings.simplefilter("error", MissingDataWarning)
        so.SMFDO(sys_, window=5).run(some)
    # a continuation of a run with data may predict: no refusal
    obs = so.SMFDO(sys_, window=5)
    obs.run(Y[:10])
    with pytest.warns(MissingDataWarning):
        res = obs.continue_run(np.full((3, 2), np.nan))
    assert res.lo.shape == (3, 2)


# ------------------------------------------------------------------ advice
def test_invalidation_advice_names_what_the_model_has():
    """A model without disturbances has no increment set (it refuses one): the advice
    names its process and measurement noise. A model with one still names the
    increment set. The advice survives pickling once, not twice."""
    state = so.LinearSystem([[0.9]], np.zeros((1, 0)), [[1.0]])
    with pytest.raises(so.DimensionError):
        so.SMFDO(state, increment_set=[0.1])
    Y = np.array([[0.0], [5.0], [0.0]])
    with pytest.raises(ModelInvalidatedError) as info:
        so.SMFDO(state, window=2, measurement_noise=0.01, process_noise=0.01).run(Y)
    msg = str(info.value)
    assert "process_noise" in msg and "measurement_noise" in msg
    assert "increment_set" not in msg
    back = pickle.loads(pickle.dumps(info.value))
    assert str(back) == msg and back.step == info.value.step
    dist = so.LinearSystem([[0.9]], [[1.0]], [[1.0]])
    with pytest.raises(ModelInvalidatedError, match="increment_set"):
        so.SMFDO(dist, window=2, increment_set=[0.01], measurement_noise=0.01,
                 initial_disturbance_set=so.Box([0.0], [0.0])).run(Y)


# ------------------------------------------------------------------ printing a result
def test_printing_a_long_result_is_a_summary():
    """A 2000-step result with state bounds prints in a few kB (it was 509 kB): the
    statuses counted, the widest bands named, the table's first and last rows."""
    sys_ = so.examples.chang2006()
    rng = np.random.default_rng(0)
    D = np.cumsum(rng.uniform(-0.05, 0.05, (2000, 2)), axis=0)
    Y = sys_.simulate(D)[0] + rng.uniform(-0.01, 0.01, (2000, 2))
    res = so.SMFDO(sys_, window=3, increment_set=[0.05, 0.05], measurement_noise=0.01,
                   initial_state_set=so.Box(-np.ones(3) * 5, np.ones(3) * 5),
                   state_bounds=True).run(Y)
    text = repr(res)
    assert str(res) == text and len(text) < 4000
    kinds, counts = np.unique(res.status, return_counts=True)
    for k, c in zip(kinds, counts, strict=True):
        assert f"{k} {c}" in text
    w = res.hi - res.lo
    fin = np.isfinite(w)
    k, i = np.unravel_index(int(np.argmax(np.where(fin, w, -np.inf))), w.shape)
    assert f"{res.names[i]} at k = {k}, [{res.lo[k, i]:.6g}, {res.hi[k, i]:.6g}]" in text
    assert "SetEstimateResult: 2000 steps" in text and "1999" in text
    row = res.summary(start=10).iloc[0]
    half = 0.5 * (res.state_hi[10:] - res.state_lo[10:])
    ok = np.isfinite(half).all(axis=1)
    assert row["state_error_bound"] == pytest.approx(half[ok].max(axis=1).mean(), rel=1e-12)
    assert row["max_state_error_bound"] == pytest.approx(half[ok].max(), rel=1e-12)
    assert row["state_unbounded"] == int((~ok).sum())


# ------------------------------------------------------------------ row scaling
def test_hull_lps_on_rows_scaled_by_powers_of_two_are_tight_and_quiet():
    """The same sets with each constraint row (and its right-hand side) scaled by
    2^k, |k| <= 30: no fallback warning, and the hull is the unscaled set's (within
    1e-9 of linprog on the unscaled LP). Before, 2 of 250 fell back to bounds 1.5e-2 of
    the scale wide and others were up to 1.5 (relative) loose without a word."""
    rng = np.random.default_rng(1)
    checked = 0
    for _ in range(120):
        n, ng = int(rng.integers(2, 5)), int(rng.integers(4, 12))
        nc = int(rng.integers(1, min(ng, 6)))
        G, c = rng.normal(size=(n, ng)), rng.normal(size=n)
        A = rng.normal(size=(nc, ng))
        b = A @ rng.uniform(-0.5, 0.5, ng)
        s = 2.0 ** rng.integers(-30, 31, nc)
        Zs = so.ConstrainedZonotope(G, c, A * s[:, None], b * s)
        with warnings.catch_warnings():
            warnings.simplefilter("error", SolverWarning)
            box = Zs.interval_hull()
        for i in range(n):
            # min of sign * z_i over the unscaled set: c_i sign + min sign G_i xi
            for sign, end in ((1.0, box.lo[i]), (-1.0, -box.hi[i])):
                r = linprog(sign * G[i], A_eq=A, b_eq=b, bounds=[(-1, 1)] * ng,
                            method="highs")
                assert r.status == 0
                exact = sign * c[i] + r.fun
                tol = 1e-9 * (1 + abs(exact))
                assert end <= exact + tol and end >= exact - tol, (end, exact)
        checked += 1
    assert checked == 120


def test_compiled_construction_is_documented_as_equal_up_to_rounding():
    doc = so.geometry.compiled_set_operations.__doc__
    assert "up to rounding" in doc and "same error bounds" in doc
