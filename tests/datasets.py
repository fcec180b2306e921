"""Records for the tests and benchmarks: where the shared measured ones are (never
copied into the repository or package), and a simulated noisy one.

Measured records are looked up in ``$SETOBS_DATA``, then ``<repo>/../shared/data``
(relative to the repository, never a machine path); tests that need a record skip
when it is absent, and fail when ``SETOBS_REQUIRE_DATA=1``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

_REPO = Path(__file__).resolve().parents[1]


def shared_data(relative: str) -> Path | None:
    """The first existing ``<data dir>/<relative>``, or ``None``."""
    roots = [os.environ.get("SETOBS_DATA"), _REPO.parent / "shared" / "data"]
    for root in roots:
        if root and (Path(root) / relative).exists():
            return Path(root) / relative
    return None


HSM150 = shared_data("hsm150/idf_pos_0.06_1.mat")

if HSM150 is None and os.environ.get("SETOBS_REQUIRE_DATA") == "1":
    raise RuntimeError("SETOBS_REQUIRE_DATA=1 but the HSM150 record was not found "
                       "($SETOBS_DATA, <repo>/../shared/data): the tests "
                       "that need it would silently skip")


def noisy_record(sys, N, rng, r_inc, r_v, U=None):
    """``N`` outputs of ``sys`` with ``|dd_i| <= r_inc`` increments and ``|v_i| <= r_v`` noise.

    ``x_0`` and ``d_0`` uniform in ``[-1, 1]``; per step the draws in the order
    noise, increment (uniform in their boxes); ``U`` the inputs, if any.
    """
    x, d = rng.uniform(-1, 1, sys.n), rng.uniform(-1, 1, sys.q)
    V, D = np.empty((N, sys.l)), np.empty((N, sys.q))
    for k in range(N):
        V[k] = r_v * rng.uniform(-1, 1, sys.l)
        D[k] = d
        d = d + r_inc * rng.uniform(-1, 1, sys.q)
    return sys.simulate(D, U, x0=x)[0] + V


def random_stable_record(seed: int, N: int = 120):
    """A random stable plant without disturbance and its record (the plants of
    ``benchmarks/early_stop.py``): 3-8 states, 1-3 outputs, spectral radius 0.5-0.98,
    process and measurement noise radii ``rw``, ``rv`` from 1e-3 to 1e-1, uniform or on
    the corners (half the seeds), ``x_0`` uniform in ``[-1, 1]^n``. Returns
    ``(system, Y, rw, rv)``."""
    import setobs as so

    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 9))
    l = int(rng.integers(1, 4))
    A = rng.normal(size=(n, n))
    A *= rng.uniform(0.5, 0.98) / np.abs(np.linalg.eigvals(A)).max()
    C = rng.normal(size=(l, n))
    rw, rv = 10.0 ** rng.uniform(-3, -1), 10.0 ** rng.uniform(-3, -1)
    corners = rng.random() < 0.5
    x = rng.uniform(-1, 1, n)
    Y = []
    for _ in range(N):
        v = rng.choice([-rv, rv], l) if corners else rng.uniform(-rv, rv, l)
        w = rng.choice([-rw, rw], n) if corners else rng.uniform(-rw, rw, n)
        Y.append(C @ x + v)
        x = A @ x + w
    return so.LinearSystem(A, np.zeros((n, 0)), C), np.array(Y), rw, rv
