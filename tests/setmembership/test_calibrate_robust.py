"""Noise calibration on real-record-like LPs: never a crash, always a checked answer
(HiGHS's dual simplex once segfaulted on such an LP).

The oracle is independent of the library: the same problem written in
input-output form (an ARX recursion of the noise-free output, no state chain) in
cvxpy and solved by Clarabel at tight tolerances; its trajectory, simulated forward
with increments clipped into their bound (the model is stable, so nothing drifts),
gives a noise level that some exactly consistent trajectory needs -- an upper bound
on the optimum that no solver tolerance can undercut.
"""

from __future__ import annotations

import gzip
import subprocess
import sys as _sys
from pathlib import Path

import numpy as np
import pytest

import setobs as so
from setobs.exceptions import SolverError
from setobs.lp import conic

DATA = Path(__file__).parents[1] / "data" / "regressions" / "exchanger_calib_1000.mps.gz"
# The ARX(2,2) model in observer canonical form, as it stands in the regression LP:
# input and disturbance enter through the same channel (an input disturbance).
PHI = np.array([[1.129724858651233, 1.0], [-0.19786074938197754, 0.0]])
GV = np.array([-0.1321102055506695, -0.353464921688055])


def exchanger_model() -> so.LinearSystem:
    return so.LinearSystem(PHI, GV.reshape(2, 1), [[1.0, 0.0]], Gamma=GV.reshape(2, 1))


def regression_record(tmp_path: Path):
    """The record inside the shipped LP: y_k are the output rows' bounds, the input
    the dynamics' right-hand side divided by the input column."""
    import highspy

    mps = tmp_path / "exchanger.mps"
    mps.write_bytes(gzip.decompress(DATA.read_bytes()))
    h = highspy._Highs() if hasattr(highspy, "_Highs") else highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.readModel(str(mps))
    lp = h.getLp()
    N = 1000
    rl = np.asarray(lp.row_lower_)
    rhs = rl[3 * N - 1:].reshape(N - 1, 2)           # after 2N output and N-1 increment rows
    U = (rhs[:, 0] / GV[0]).reshape(-1, 1)
    np.testing.assert_allclose(U[:, 0] * GV[1], rhs[:, 1], rtol=1e-12)
    return rl[:N].reshape(-1, 1), U


def exchanger_like(N: int, rng: np.random.Generator):
    """A record of the same kind: outputs near 93-101 quantised to 1e-4, inputs in
    [0.1, 0.7] held for 50-400 samples, a slow model mismatch of about 2 and noise."""
    U = np.empty((N, 1))
    k = 0
    while k < N:
        L = int(rng.integers(50, 400))
        U[k:k + L] = np.round(rng.uniform(0.1, 0.7), 2)
        k += L
    d = -13.8 + np.cumsum(rng.uniform(-5e-3, 5e-3, N))
    x = np.linalg.solve(np.eye(2) - PHI, GV * (U[0, 0] + d[0]))
    t = np.arange(N)
    bias = 1.5 * np.sin(t / 150.0) + 0.5 * np.sin(t / 23.0)
    Y = np.empty((N, 1))
    for k in range(N):
        Y[k] = np.round(x[0] + bias[k] + 0.3 * rng.standard_normal(), 4)
        x = PHI @ x + GV * (U[k, 0] + d[k])
    return Y, U


def io_oracle(Y, U, inc):
    """min alpha over the noise-free output z and the disturbance d:
    z_(k+1) = a1 z_k + a2 z_(k-1) + g1 s_k + g2 s_(k-1), s = u + d, |d_(k+1) - d_k| <= inc,
    |y - z| <= alpha; then the forward simulation of its trajectory (increments
    clipped) and the noise that exactly consistent trajectory needs."""
    # imported here, not at collection: cvxpy loads scs's single-threaded OpenBLAS,
    # which the BLAS-limit tests would then see in every later test
    cp = pytest.importorskip("cvxpy")
    N = Y.shape[0]
    y, u = Y[:, 0], U[:N - 1, 0]
    a1, a2 = PHI[0, 0], PHI[1, 0]
    g1, g2 = GV
    z, d, a, x20 = cp.Variable(N), cp.Variable(N), cp.Variable(), cp.Variable()
    s = u + d[:N - 1]
    cons = [z[1] == a1 * z[0] + x20 + g1 * s[0],
            z[2:] == a1 * z[1:-1] + a2 * z[:-2] + g1 * s[1:] + g2 * s[:-1],
            cp.abs(cp.diff(d)) <= inc, cp.abs(y - z) <= a]
    prob = cp.Problem(cp.Minimize(a), cons)
    prob.solve(solver="CLARABEL", tol_gap_abs=1e-11, tol_gap_rel=1e-11, tol_feas=1e-11,
               max_iter=500)
    assert prob.status == "optimal"
    dv = d.value
    dsim = dv[0] + np.concatenate([[0.0], np.cumsum(np.clip(np.diff(dv), -inc, inc))])
    x = np.array([z.value[0], x20.value])
    out = np.empty(N)
    for k in range(N):
        out[k] = x[0]
        if k < N - 1:
            x = PHI @ x + GV * (u[k] + dsim[k])
    return float(prob.value), float(np.max(np.abs(y - out)))


def test_regression_lp_is_solved_not_crashed(tmp_path):
    """The LP on which HiGHS segfaulted: the optimum is 2.1221930, proved from both
    sides (the independent solve, and a forward-simulated trajectory that is exactly
    consistent at 2.1221931). The issue quoted 2.12218 from a solve at cvxpy's default
    tolerances (1e-8), which stops 1e-5 short: a number checked, not copied."""
    Y, U = regression_record(tmp_path)
    cal = so.calibrate_noise(exchanger_model(), Y, U, increment=1e-3, holdout=0)
    opt, upper = io_oracle(Y, U, 1e-3)
    assert 2.122192 < opt <= upper < 2.1221935
    assert cal.status == "optimal" and cal.info["solver"] == "clarabel"
    assert abs(cal.scale - opt) <= 1e-6 * opt
    assert cal.info["lower_bound"] <= cal.scale * (1 + 1e-9)
    assert cal.radii[0] >= upper          # the recommended bound admits a consistent trajectory


@pytest.mark.parametrize("N", [500, 1500, 4000])
def test_sweep_of_lengths_and_increments_matches_independent_solve(N):
    """Record lengths 500-4000, increments 5e-4 - 1e-2 on an exchanger-like record
    (on which HiGHS's dual simplex stopped with "Not Set" in 8 of 16 cases): every
    calibration agrees with the independent input-output solve to 1e-6."""
    Y, U = exchanger_like(N, np.random.default_rng(N))
    sys_ = exchanger_model()
    for inc in (5e-4, 2e-3, 1e-2):
        cal = so.calibrate_noise(sys_, Y, U, increment=inc, holdout=0)
        opt, upper = io_oracle(Y, U, inc)
        assert opt <= upper * (1 + 1e-9)
        assert abs(cal.scale - opt) <= 1e-6 * opt, (N, inc, cal.scale, opt)
        assert cal.radii[0] >= min(upper, opt * (1 + 1e-6)), (N, inc)


def test_inputs_may_have_one_row_fewer_without_feedthrough(tmp_path):
    """U[k] acts between y_k and y_(k+1), so N - 1 rows suffice without a feedthrough
    (this raised a broadcasting error)."""
    Y, U = regression_record(tmp_path)
    assert U.shape[0] == Y.shape[0] - 1
    a = so.calibrate_noise(exchanger_model(), Y[:300], U[:299], increment=1e-3)
    b = so.calibrate_noise(exchanger_model(), Y[:300], U[:300], increment=1e-3)
    assert a.scale == pytest.approx(b.scale, rel=1e-9)


def _failing(A, b, c, m_eq, time_limit):
    raise RuntimeError("solver crashed")


def _wrong_point(A, b, c, m_eq, time_limit):
    return np.zeros(A.shape[1]), 0.0, "optimal"   # claims alpha = 0: violates the outputs


def test_chain_moves_on_and_checks_answers(monkeypatch):
    """A solver that raises, and one that returns a point violating the LP, are passed
    over (and named); the next solver answers."""
    sys_ = so.LinearSystem([[1.0]], [[1.0]], [[1.0]])
    Y = np.array([[0.0], [1.0], [0.0], [1.0], [0.0]])
    chain = (("broken", _failing), ("liar", _wrong_point), *conic.SOLVER_CHAIN)
    monkeypatch.setattr(conic, "SOLVER_CHAIN", chain)
    cal = so.calibrate_noise(sys_, Y, increment=0.0)
    assert abs(cal.minimal[0] - 0.5) < 1e-8
    failed = " | ".join(cal.info["failed_attempts"])
    assert "broken: RuntimeError: solver crashed" in failed
    assert "liar: optimal, rejected: constraint violation" in failed


def test_chain_ends_in_a_solver_error_not_a_crash(monkeypatch):
    monkeypatch.setattr(conic, "SOLVER_CHAIN", (("broken", _failing), ("liar", _wrong_point)))
    with pytest.raises(SolverError, match=r"failed under every solver.*broken.*liar"):
        so.calibrate_noise(so.LinearSystem([[1.0]], [[1.0]], [[1.0]]),
                           np.array([[0.0], [1.0], [0.0]]), increment=0.0)


def test_noise_free_record_gets_the_documented_floor():
    """A record the model explains exactly: the minimum is 0 to solver accuracy and
    the recommended radius is CALIBRATION_ATOL times the record's spread (here 4),
    not a fixed absolute number."""
    sys_ = so.LinearSystem([[1.0]], [[1.0]], [[1.0]])
    Y = np.array([[0.0], [1.0], [2.0], [3.0], [4.0], [5.0], [6.0], [7.0], [8.0]])
    cal = so.calibrate_noise(sys_, Y, increment=0.0, holdout=0)
    assert cal.minimal[0] < 1e-9
    assert cal.info["data_scale"] == pytest.approx(4.0)
    floor = so.tolerances.CALIBRATION_ATOL * 4.0
    assert floor <= cal.radii[0] <= floor + 1e-9 + 1e-6 * cal.minimal[0]
    with pytest.raises(ValueError, match="time_limit must be positive"):
        so.calibrate_noise(sys_, Y, increment=0.0, time_limit=0.0)


def test_calibration_prints_nothing():
    """No solver banner or log on stdout (HiGHS printed its banner on every process)."""
    code = ("import numpy as np, setobs as so\n"
            "s = so.examples.chang2006()\n"
            "Y = s.simulate(np.ones((30, 2)))[0]\n"
            "so.calibrate_noise(s, Y, increment=0.1)\n"
            "so.SMFDO(s, window=3, fast=False).run(Y)\n"
            "so.SMFDO(s, window=None).run(Y)\n")
    out = subprocess.run([_sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=300, check=True)
    assert out.stdout == ""
