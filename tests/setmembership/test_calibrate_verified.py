"""Calibration's promise: ``minimal`` is the LP optimum to 1e-6
(relative) and the recommended ``radii`` make the record consistent, or the status says
they could not be checked (reproducer ``calibration_recommended_inconsistent.py``: on a
20 000-sample record of a marginally stable plant ``minimal`` was 3.7e-4 short and
``radii`` inconsistent, status ``optimal``, no warning).

Oracles, written here and sharing nothing with the library:

* the LP with the states eliminated (``x_k = Phi^k x_0 + forced response``, computed in
  ``numpy.longdouble``), an LP in ``(x_0, alpha)`` of 3 variables and ``2 N`` rows, for
  models without disturbance and process noise;
* the whole-record LP with every state, disturbance and noise a variable (HiGHS through
  scipy, tolerances 1e-10), for the optimum and for feasibility at fixed radii.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.optimize import linprog

import setobs as so
from setobs.exceptions import SolverWarning

OPTS = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}


def marginal_record(seed: int, n: int, N: int, rv: float = 1e-2):
    """The reproducer's generator: a random model with spectral radius exactly 1, q = 0,
    one input and one output, uniform noise ``|v| <= rv``."""
    rng = np.random.default_rng(seed)
    while True:
        Phi = rng.normal(size=(n, n))
        Phi *= 1.0 / max(abs(np.linalg.eigvals(Phi)))
        Xi = rng.normal(size=(1, n))
        O = np.vstack([Xi @ np.linalg.matrix_power(Phi, k) for k in range(n)])
        if np.linalg.matrix_rank(O) == n:
            G, Gam = rng.normal(size=(n, 0)), rng.normal(size=(n, 1))
            break
    x = rng.normal(size=n)
    _ = rng.normal(size=0)
    U = rng.uniform(-1, 1, (N, 1))
    Y = np.empty((N, 1))
    for k in range(N):
        Y[k] = Xi @ x + rng.uniform(-rv, rv, 1)
        x = Phi @ x + Gam @ U[k]
        _ = rng.uniform(-1, 1, 0)
    return so.LinearSystem(Phi, G, Xi, Gam), Y, U


def eliminated_optimum(sys, Y, U) -> float:
    """min alpha with the states eliminated in extended precision (q = 0, no w)."""
    N, n = Y.shape[0], sys.n
    Pl = np.array(sys.Phi, dtype=np.longdouble)
    xi = np.array(sys.Xi[0], dtype=np.longdouble)
    gam = np.array(sys.Gamma[:, 0], dtype=np.longdouble)
    xf = np.zeros(n, dtype=np.longdouble)
    Pk = np.eye(n, dtype=np.longdouble)
    H, f = np.empty((N, n)), np.empty(N)
    for k in range(N):
        H[k] = (xi @ Pk).astype(float)
        f[k] = float(xi @ xf)
        xf = Pl @ xf + gam * np.longdouble(U[k, 0])
        Pk = Pl @ Pk
    res = Y[:, 0] - f
    A = np.vstack([np.hstack([-H, -np.ones((N, 1))]), np.hstack([H, -np.ones((N, 1))])])
    r = linprog(np.r_[np.zeros(n), 1.0], A_ub=A, b_ub=np.concatenate([-res, res]),
                bounds=[(None, None)] * n + [(0, None)], method="highs", options=OPTS)
    assert r.status == 0
    return float(r.x[-1])


def record_lp(sys, Y, U, inc, rw=None, alpha=None):
    """The whole-record LP: min alpha (or feasibility at ``alpha``) over x_k, d_k, w_k with
    x_(k+1) = Phi x_k + Gamma u_k + G d_k + w_k, |d_(k+1) - d_k| <= inc, |w| <= rw,
    |y_k - Xi x_k| <= alpha (HiGHS). Returns the optimum, or whether it is feasible."""
    N, n, q, l = Y.shape[0], sys.n, sys.q, sys.l
    nw = n if rw is not None else 0
    nx, nd, nwv = n * N, q * N, nw * (N - 1)
    nv = nx + nd + nwv + 1
    ia = nv - 1
    rows, cols, vals, beq = [], [], [], []
    r = 0
    for k in range(N - 1):
        for i in range(n):
            rows.append(r), cols.append(n * (k + 1) + i), vals.append(1.0)
            for j in range(n):
                if sys.Phi[i, j]:
                    rows.append(r), cols.append(n * k + j), vals.append(-sys.Phi[i, j])
            for j in range(q):
                if sys.G[i, j]:
                    rows.append(r), cols.append(nx + q * k + j), vals.append(-sys.G[i, j])
            if nw:
                rows.append(r), cols.append(nx + nd + n * k + i), vals.append(-1.0)
            beq.append(float(sys.Gamma[i] @ U[k]) if U is not None else 0.0)
            r += 1
    Aeq = sp.csr_matrix((vals, (rows, cols)), shape=(r, nv))
    rows, cols, vals, bub = [], [], [], []
    r = 0
    for k in range(N):
        for i in range(l):
            if np.isnan(Y[k, i]):
                continue
            for s in (1.0, -1.0):
                for j in range(n):
                    if sys.Xi[i, j]:
                        rows.append(r), cols.append(n * k + j), vals.append(-s * sys.Xi[i, j])
                rows.append(r), cols.append(ia), vals.append(-1.0)
                bub.append(-s * Y[k, i])
                r += 1
    for k in range(N - 1):
        for j in range(q):
            for s in (1.0, -1.0):
                rows += [r, r]
                cols += [nx + q * (k + 1) + j, nx + q * k + j]
                vals += [s, -s]
                bub.append(float(inc[j]))
                r += 1
    Aub = sp.csr_matrix((vals, (rows, cols)), shape=(r, nv))
    bounds = [(None, None)] * (nx + nd) + [(-float(rw[i % n]), float(rw[i % n]))
                                          for i in range(nwv)]
    c = np.zeros(nv)
    if alpha is None:
        c[ia] = 1.0
        bounds.append((0, None))
    else:
        bounds.append((alpha, alpha))
    res = linprog(c, A_ub=Aub, b_ub=bub, A_eq=Aeq, b_eq=beq, bounds=bounds, method="highs",
                  options=OPTS)
    if alpha is None:
        assert res.status == 0, res.message
        return float(res.x[ia])
    assert res.status in (0, 2), res.message
    return res.status == 0


def calibrate_quietly(*args, **kwargs):
    with warnings.catch_warnings(record=True) as wl:
        warnings.simplefilter("always")
        cal = so.calibrate_noise(*args, holdout=0, **kwargs)
    return cal, [w for w in wl if issubclass(w.category, SolverWarning)]


def test_the_reproducer_minimal_is_the_optimum_and_radii_are_consistent():
    """The reported record: minimal within 1e-6 of the states-eliminated optimum (it
    was 3.7e-4 short), radii consistent for HiGHS, no warning."""
    sys_, Y, U = marginal_record(302, 2, 20_000)
    cal, warned = calibrate_quietly(sys_, Y, U, increment=[])
    opt = eliminated_optimum(sys_, Y, U)
    assert abs(cal.minimal[0] / opt - 1.0) <= 1e-6, (cal.minimal[0], opt)
    assert cal.radii[0] >= opt
    assert record_lp(sys_, Y, U, np.zeros(0), alpha=float(cal.radii[0]))
    assert abs(record_lp(sys_, Y, U, np.zeros(0)) / opt - 1.0) <= 1e-6  # (the oracles agree)
    assert cal.status == "optimal" and not warned
    assert cal.info["refined"] and cal.info["verified_noise"][0] <= cal.radii[0]


@pytest.mark.parametrize(("seed", "n", "N"), [(7, 2, 6000), (11, 3, 6000), (23, 2, 12_000)])
def test_held_out_marginal_plants(seed, n, N):
    sys_, Y, U = marginal_record(seed, n, N)
    cal, warned = calibrate_quietly(sys_, Y, U, increment=[])
    opt = eliminated_optimum(sys_, Y, U)
    assert abs(cal.minimal[0] / opt - 1.0) <= 1e-6, (seed, cal.minimal[0], opt)
    assert cal.radii[0] >= opt and record_lp(sys_, Y, U, np.zeros(0), alpha=float(cal.radii[0]))
    assert cal.status == "optimal" and not warned


def _disturbed_record(seed: int, N: int, rw: float | None):
    """A stable 3-state plant with a disturbance (q = 1), increments within 1e-3, process
    noise within ``rw``, noise within 1e-2; a few missing samples."""
    rng = np.random.default_rng(seed)
    Phi = np.array([[0.95, 0.01, 0.0], [0.0, 0.9, 0.02], [0.0, -0.05, 0.9]])
    G = np.array([[0.0], [0.01], [0.0]])
    Xi = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    Gam = np.array([[0.0], [0.01], [0.02]])
    U = rng.uniform(-1, 1, (N, 1))
    x, d = rng.normal(size=3), 0.5
    Y = np.empty((N, 2))
    for k in range(N):
        Y[k] = Xi @ x + rng.uniform(-1e-2, 1e-2, 2)
        x = Phi @ x + Gam @ U[k] + G[:, 0] * d + (0.0 if rw is None
                                                  else rng.uniform(-rw, rw, 3))
        d += rng.uniform(-1e-3, 1e-3)
    Y[rng.random((N, 2)) < 0.02] = np.nan
    return so.LinearSystem(Phi, G, Xi, Gam), Y, U


@pytest.mark.parametrize(("seed", "rw"), [(1, None), (2, 1e-4)])
def test_disturbance_process_noise_and_missing_samples(seed, rw):
    """With a disturbance, process noise and missing samples: against the whole-record
    LP (optimum, and feasibility at the radii)."""
    sys_, Y, U = _disturbed_record(seed, 600, rw)
    kw = {} if rw is None else {"process_noise": rw}
    cal, warned = calibrate_quietly(sys_, Y, U, increment=1e-3, **kw)
    rws = None if rw is None else np.full(3, rw)
    opt = record_lp(sys_, Y, U, [1e-3], rws)
    assert abs(cal.scale / opt - 1.0) <= 1e-6, (cal.scale, opt)
    assert record_lp(sys_, Y, U, [1e-3], rws, alpha=float(cal.radii.max()))
    assert np.all(cal.radii >= opt) and cal.status == "optimal" and not warned


def test_an_unstable_plant_under_feedback_is_flagged_not_silently_trusted():
    """An open-loop unstable model (pole 1.4) identified under a stabilising feedback:
    the data are bounded, but no forward trajectory can be checked over 3000 samples
    (the rounding grows like 1.4^k). The answer says so (status and warning) instead of
    claiming verified radii."""
    rng = np.random.default_rng(4)
    N = 3000
    Phi, Gam, Xi = np.array([[1.4]]), np.array([[1.0]]), np.array([[1.0]])
    x, Y, U = 0.3, np.empty((N, 1)), np.empty((N, 1))
    for k in range(N):
        Y[k] = x + rng.uniform(-1e-3, 1e-3)
        U[k] = -1.1 * Y[k, 0] + rng.uniform(-0.1, 0.1)
        x = 1.4 * x + U[k, 0]
    sys_ = so.LinearSystem(Phi, np.zeros((1, 0)), Xi, Gam)
    cal, warned = calibrate_quietly(sys_, Y, U, increment=[])
    assert cal.status == "unverified"
    assert warned and "could not be checked" in str(warned[0].message)
    assert cal.radii[0] >= cal.minimal[0]
