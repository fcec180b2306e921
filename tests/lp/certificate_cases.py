"""Inputs for the certificate's bit-for-bit test, and one run of the certificate on them.

Run in two processes (``tests/lp/test_certificate.py``): compiled, and with
``NUMBA_DISABLE_JIT=1`` (the certificate's text, interpreted). Each case is the
argument tuple of :func:`setobs.lp.certificate.lower_bound`.
"""

from __future__ import annotations

import numpy as np


def cases(n_cases: int = 160) -> list[tuple]:
    """Random LPs of every kind the certificate sees: scales spread over 6 decades,
    asymmetric, one-sided, zero-width and unbounded columns, ``b_err`` and ``w_err``,
    exact objectives ``M^T v``, exact reduced costs, near-optimal and random multipliers."""
    from setobs.lp.certificate import csc_of

    rng = np.random.default_rng(20261127)
    out = []
    for t in range(n_cases):
        m = int(rng.integers(1, 7))
        n = m + int(rng.integers(1, 9))
        A = rng.normal(size=(m, n)) * 10.0 ** rng.uniform(-3, 3, size=(1, n))
        A[rng.random((m, n)) < 0.3] = 0.0
        lo = -rng.uniform(0.0, 3.0, n)
        hi = rng.uniform(0.0, 3.0, n)
        kind = rng.random(n)
        lo[kind < 0.1] = 0.0
        hi[(kind >= 0.1) & (kind < 0.15)] = lo[(kind >= 0.1) & (kind < 0.15)]
        f = int(rng.integers(0, 3)) if t % 2 else 0
        fidx = np.sort(rng.choice(n, size=min(f, n - 1), replace=False)).astype(np.int64)
        lo[fidx], hi[fidx] = -np.inf, np.inf
        x = np.clip(rng.normal(size=n), np.where(np.isinf(lo), -5, lo),
                    np.where(np.isinf(hi), 5, hi))
        b = A @ x
        y_opt = rng.normal(size=m)
        w = A.T @ y_opt + rng.normal(size=n) * (np.isfinite(lo))
        if t % 3 == 0:
            M = rng.normal(size=(2, n))
            v = rng.normal(size=2)
            w = M.T @ v
        else:
            M, v = np.zeros((0, n)), np.zeros(0)
        pinvU = (np.ascontiguousarray(np.linalg.pinv(A[:, fidx].T)) if fidx.size
                 else np.zeros((m, 0)))
        b_err = np.abs(b) * 1e-12 if t % 4 == 1 else np.zeros(0)
        w_err = np.abs(w) * 1e-14 if t % 5 == 2 else np.zeros(0)
        y = y_opt + (10.0 ** rng.uniform(-12, 0)) * rng.normal(size=m)
        indptr, indices, data = csc_of(A)
        Ad = np.ascontiguousarray(A) if t % 2 == 0 else np.zeros((0, 0))
        out.append((w, indptr, indices, data, b, lo, hi, y, fidx, pinvU, 1e8, 1e-10,
                    b_err, w_err, M, v, bool(t % 7 == 3), Ad))
    return out


def run_all() -> list[tuple[str, str, list[str]]]:
    """The certificate on every case: ``(bound, slack, y)`` as exact hex strings."""
    from setobs.lp.certificate import lower_bound

    res = []
    for args in cases():
        args = list(args)
        args[7] = args[7].copy()
        bound, slack = lower_bound(*args)
        res.append((float(bound).hex(), float(slack).hex(), [float(v).hex() for v in args[7]]))
    return res
