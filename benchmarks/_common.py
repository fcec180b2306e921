"""Shared pieces of the benchmarks: random sets, timing, and the straightforward cvxpy path
used as the baseline."""

from __future__ import annotations

import datetime
import statistics
import subprocess
import time
from pathlib import Path

import cvxpy as cp
import numpy as np
from scipy.optimize import linprog

from setobs import ConstrainedZonotope


def hull_cvxpy(Z) -> tuple[np.ndarray, np.ndarray]:
    """Interval hull of a constrained zonotope with a fresh cvxpy problem per LP (Clarabel)."""
    lo, hi = np.empty(Z.dim), np.empty(Z.dim)
    for i in range(Z.dim):
        for sgn in (1.0, -1.0):
            xi = cp.Variable(Z.n_gen)
            cons = [cp.abs(xi) <= Z.h] + ([Z.A @ xi == Z.b] if Z.n_con else [])
            prob = cp.Problem(cp.Minimize(sgn * (Z.G[i] @ xi)), cons)
            prob.solve(solver=cp.CLARABEL)
            if prob.status != cp.OPTIMAL:
                raise RuntimeError(f"cvxpy status {prob.status}")
            val = sgn * prob.value + Z.c[i]
            if sgn > 0:
                lo[i] = val
            else:
                hi[i] = val
    return lo, hi


def make_cz(n: int, n_g: int, n_c: int, rng: np.random.Generator) -> ConstrainedZonotope:
    G = rng.normal(size=(n, n_g))
    c = rng.normal(size=n)
    A = rng.normal(size=(n_c, n_g))
    xi0 = rng.uniform(-0.5, 0.5, size=n_g)
    return ConstrainedZonotope(G, c, A, A @ xi0)


def timeit(fn, *args, repeats: int) -> tuple[float, list[float], object]:
    out = fn(*args)  # warm-up (imports, first-call overhead)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn(*args)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), times, out


def state_bands(obs, Y, U) -> tuple[list[float], np.ndarray, np.ndarray]:
    """Run a state-bounding SMFDO over a record (``U[k]`` with ``Y[k]``): the time
    of each update and the state bands ``(times, lo, hi)``."""
    times, lo, hi = [], [], []
    for k in range(len(Y)):
        t0 = time.perf_counter()
        st = obs.step(Y[k], None if U is None else U[k])
        times.append(time.perf_counter() - t0)
        lo.append(st.state_lo)
        hi.append(st.state_hi)
    return times, np.array(lo), np.array(hi)


def count_solves(solves: list[tuple[int, float]]):
    """Route every HiGHS solve of setobs through a counter that appends ``(simplex
    iterations, seconds)`` to ``solves``; returns the plain solve (to put back:
    ``setobs.lp.highs.solve = plain``)."""
    from setobs.lp import highs

    plain = highs.solve

    def counted(hs, **kw):
        t0 = time.perf_counter()
        st = plain(hs, **kw)
        solves.append((int(hs.getInfo().simplex_iteration_count), time.perf_counter() - t0))
        return st

    highs.solve = counted
    return plain


def linprog_unit(repeats: int = 30) -> float:
    """Median time (s) of one 45 x 40 ``scipy.optimize.linprog`` (HiGHS): the unit of the
    speed targets, timed in the same run as what it measures."""
    rng = np.random.default_rng(0)
    A = rng.normal(size=(45, 40))
    x0 = rng.uniform(-0.5, 0.5, 40)
    b = A @ x0 + rng.uniform(0.0, 0.5, 45)
    c = rng.normal(size=40)
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        r = linprog(c, A_ub=A, b_ub=b, bounds=[(-1, 1)] * 40, method="highs")
        ts.append(time.perf_counter() - t0)
        assert r.status == 0
    return statistics.median(ts)


def stamp() -> dict[str, str]:
    """``{"commit": ..., "date": ...}``: the checkout's commit and today's date, for the
    head of a results file (what produced its figures, and when)."""
    commit = subprocess.run(["git", "rev-parse", "HEAD"], capture_output=True, text=True,
                            cwd=Path(__file__).parent).stdout.strip()
    return {"commit": commit, "date": datetime.date.today().isoformat()}
