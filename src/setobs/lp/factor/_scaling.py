"""Exact (power-of-two) row scales of the factor polytope's rows, and correctly rounded
residuals."""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from ..._rounding import two_prod
from ...tolerances import MAX_MAGNITUDE

__all__ = ["equilibration", "exact_residual", "row_scale"]


def equilibration(A: NDArray[np.float64], b: NDArray[np.float64],
                  b_err: NDArray[np.float64] | None = None) -> NDArray[np.float64] | None:
    """Power-of-two row scales ``s`` that bring each row of ``A`` to an infinity norm in
    ``[1/2, 1)`` (``A / s``, ``b / s`` are exact; ``b`` does not set the scale: its size
    is the solution's, e.g. states of ``1e8`` carried by unbounded factors, and rows
    scaled down by it fell back), or ``None`` when the rows'
    sizes are within a factor of ``2^10`` of each other and of ``2^+-20`` of unit size:
    HiGHS's own scaling and the compiled simplex's equilibration of the working copy
    handle those (and a thin set of the soundness campaign, rows of 190 to 8000, came
    out 2e-5 looser re-scaled: ``window_open_gap_set.npz``). A row whose ``b`` or
    ``b_err`` would exceed ``MAX_MAGNITUDE`` once scaled keeps its scale (no overflow).

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Constraint matrix.
    b : ndarray, shape (m,)
        Right-hand side.
    b_err : ndarray, shape (m,), optional
        Bound on the rounding error of ``b``.
    """
    r = np.abs(A).max(axis=1, initial=0.0)
    r = r[r > 0.0]
    if r.size == 0:
        return None
    top, low = float(r.max()), float(r.min())
    if top <= 2.0 ** 20 and low >= 2.0 ** -20 and top <= 1024.0 * low:
        return None
    r = np.abs(A).max(axis=1, initial=0.0)
    e = np.frexp(np.where(r > 0.0, r, 1.0))[1]
    s = np.where(r > 0.0, np.ldexp(1.0, e), 1.0)
    big = np.abs(b) if b_err is None else np.maximum(np.abs(b), b_err)
    return np.where(big > MAX_MAGNITUDE * np.minimum(s, 1.0), 1.0, s)


def row_scale(A: NDArray[np.float64], b: NDArray[np.float64],
              b_err: NDArray[np.float64] | None) -> NDArray[np.float64]:
    """Power-of-two row scales (so that scaling is exact in floating point); 1 for a
    row whose ``b_err`` would exceed ``MAX_MAGNITUDE`` once scaled (see
    :func:`equilibration`)."""
    s = np.maximum(np.abs(A).max(axis=1, initial=0.0), np.abs(b))
    m, e = np.frexp(np.where(s > 0.0, s, 1.0))
    s = np.ldexp(1.0, np.where(m == 0.5, e - 1, e))
    if b_err is not None:
        s = np.where(b_err > MAX_MAGNITUDE * np.minimum(s, 1.0), 1.0, s)
    return s


def exact_residual(b: NDArray[np.float64], M: NDArray[np.float64],
                   x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Correctly rounded ``b - M^T x``, entry by entry (Dekker's TwoProduct and
    :func:`math.fsum`); NaN where the exact sum is beyond double precision."""
    prods = two_prod(M, x)
    out = np.empty(b.size)
    for j in range(b.size):
        terms = [b[j]]
        for block in prods:
            terms.extend((-block[:, j]).tolist())
        try:
            out[j] = math.fsum(terms)
        except (ValueError, OverflowError):
            out[j] = np.nan
    return out
