"""Shared pieces of the benchmarks: the straightforward cvxpy path used as the baseline."""

from __future__ import annotations

import cvxpy as cp
import numpy as np


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
