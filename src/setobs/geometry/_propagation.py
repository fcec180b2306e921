"""Compiled kernels (numba) of the interval constraint propagation of
:mod:`setobs.geometry.reduction` (:func:`~setobs.geometry.reduction.propagated_factor_ranges`,
Scott et al. 2016, Sec. 4.2): the same arithmetic as the vectorised form, one pass over
the nonzero entries per sweep instead of a dozen ``(n_c, n_g)`` temporaries.

The sums of a row (``sum_k A_ik m_k`` and the others) are accumulated in the kernel's
own order; the rounding term ``2 gamma_(n_g + 8) (|b_i| + |A_i| (|m| + r))`` bounds the
error of any order of evaluation, so the ranges stay outer.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def row_ranges(A, b, lo, hi, b_err, g2, scale):  # pragma: no cover - compiled
    """For every factor ``j``, the intersection over rows ``i`` (``A_ij != 0``) of the
    ranges ``(b_i - sum_(k != j) A_ik xi_k) / A_ij`` with ``xi_k`` in ``[lo_k, hi_k]``,
    widened by ``b_err`` (length ``n_c``, or 0: none) and by ``g2 (|b_i| + |A_i| (|m| +
    r)) / |A_ij|``, the radius then scaled by ``scale``; a row bounds ``xi_j`` only if every
    other factor in it is bounded (:func:`setobs.geometry.reduction._row_ranges`). NaN
    propagates as in numpy's ``max`` / ``min``."""
    m, n = A.shape
    fin = np.empty(n, np.bool_)
    mid = np.empty(n)
    rad = np.empty(n)
    for k in range(n):
        f = np.isfinite(lo[k]) and np.isfinite(hi[k])
        fin[k] = f
        mid[k] = 0.5 * (lo[k] + hi[k]) if f else 0.0
        rad[k] = 0.5 * (hi[k] - lo[k]) if f else 0.0
    low = np.full(n, -np.inf)
    upp = np.full(n, np.inf)
    has_err = b_err.size > 0
    for i in range(m):
        S = 0.0
        Rr = 0.0
        E = 0.0
        ninf = 0
        for k in range(n):
            a = A[i, k]
            if a != 0.0:
                aa = abs(a)
                S += a * mid[k]
                Rr += aa * rad[k]
                E += aa * (abs(mid[k]) + rad[k])
                if not fin[k]:
                    ninf += 1
        err = g2 * (abs(b[i]) + E)
        if has_err:
            err = err + b_err[i]
        base = b[i] - S
        for j in range(n):
            a = A[i, j]
            if a == 0.0:
                continue
            aa = abs(a)
            centre = (base + a * mid[j]) / a
            others = ninf - (0 if fin[j] else 1)
            if others > 0:
                r = np.inf
            else:
                r = (max(Rr - aa * rad[j], 0.0) + err) / aa
                r *= scale
            lw = centre - r
            up = centre + r
            if lw != lw or low[j] != low[j]:
                low[j] = np.nan
            elif lw > low[j]:
                low[j] = lw
            if up != up or upp[j] != upp[j]:
                upp[j] = np.nan
            elif up < upp[j]:
                upp[j] = up
    return low, upp


@njit(cache=True)
def propagate(A, b, h, sweeps, b_err, g2, scale, tol):  # pragma: no cover - compiled
    """Jacobi sweeps of :func:`row_ranges` from ``[-h, h]``, each bound tightened to its
    range where the two do not cross, until no bound moves by more than ``tol`` of its
    factor's bound (``h``, or 1 where ``h`` is 0 or infinite) or after ``sweeps``
    sweeps: ``(E_lo, E_hi, R_lo, R_hi)`` as
    :func:`setobs.geometry.reduction.propagated_factor_ranges`."""
    n = h.size
    lo = -h.copy()
    hi = h.copy()
    R_lo = np.full(n, -np.inf)
    R_hi = np.full(n, np.inf)
    for _ in range(max(sweeps, 1)):
        R_lo, R_hi = row_ranges(A, b, lo, hi, b_err, g2, scale)
        moved = False
        for j in range(n):
            nl = lo[j] if R_lo[j] != R_lo[j] else max(lo[j], R_lo[j])
            nh = hi[j] if R_hi[j] != R_hi[j] else min(hi[j], R_hi[j])
            if R_lo[j] != R_lo[j] or R_hi[j] != R_hi[j] or not nl <= nh:
                nl, nh = lo[j], hi[j]
            s = h[j] if (np.isfinite(h[j]) and h[j] > 0.0) else 1.0
            d1 = abs(nl - lo[j])
            d2 = abs(nh - hi[j])
            # (inf - inf, an unbounded factor's bound: NaN, counts as moved)
            if d1 != d1 or d2 != d2 or d1 / s > tol or d2 / s > tol:
                moved = True
            lo[j] = nl
            hi[j] = nh
        if not moved:
            break
    return lo, hi, R_lo, R_hi
