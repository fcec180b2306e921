"""Compiled kernels of the windowed SMFDO's step (numba): the assembly of the closed
form's data (:meth:`setobs.setmembership._closed_form.WindowModel.assemble`) and the
outward margin and centre of the reported bounds (:func:`setobs.setmembership._commit.commit`).

Each replaces a dozen or more small numpy calls (about 1.5 us each) on vectors of a
few to a few hundred entries; the noise-free step of the paper example spent about
half its time in such calls. Floating-point semantics are numpy's (no fast-math);
sums are taken in another order than BLAS's, which the rounding bounds cover (they
are Higham's ``gamma`` bounds of the products' depth, valid for any order, and the
bounds' own rounding is covered by their final factor ``1 + gK``).

These kernels are private; their callers are the interface. They are loaded on the
first windowed step, not on import.
"""

from __future__ import annotations

import numpy as np
from numba import njit

_U = np.finfo(np.float64).eps / 2.0


@njit(cache=True)
def _matvec_add(out, M, v, a):
    """``out += a * (M @ v)`` (row by row)."""
    for i in range(M.shape[0]):
        s = 0.0
        for j in range(M.shape[1]):
            s += M[i, j] * v[j]
        out[i] += a * s


@njit(cache=True)
def _affine(k, Mc, c_S, Mu, u):
    """``k + Mc c_S + Mu u`` (a new vector; the input term only with inputs)."""
    out = k.copy()
    _matvec_add(out, Mc, c_S, 1.0)
    if u.size:
        _matvec_add(out, Mu, u, 1.0)
    return out


@njit(cache=True)
def assemble(c_S, b_S, h_S, Yf, y_idx, u, b_S_err, c_S_err, Y_err,
             b_const, b_c, b_u, b_const_a, b_c_a, b_u_a, b_c_m, b_u_m, b_abs_err, y_pos,
             c_const, c_c, c_u, c_const_a, c_c_a, c_u_a, c_c_m, c_u_m, c_abs_err, h_D,
             gK, data_rtol):
    """``c, b, h, c_err, b_err`` of the window's closed form for the data (the
    arithmetic of :meth:`WindowModel.assemble`, which documents the error terms) and
    the magnitude of the measurements read, ``max |y|``.

    ``Yf`` is the window's measurements flattened and ``y_idx`` the entries of it the
    structure reads (in its row order); ``u`` is empty without inputs; ``b_S_err``
    and ``c_S_err`` are empty when the start set is exact; ``Y_err`` (like ``Yf``)
    is empty without a further measurement uncertainty. The ``*_a`` arrays are the
    coefficients' error bounds (their rounding and that of this evaluation), the
    ``*_m`` arrays bounds on their exact magnitudes (an uncertainty of ``c_S`` or
    ``u`` is carried with them).
    """
    nS, nt, N = b_S.size, b_const.size, c_const.size
    has_u = u.size > 0
    au = np.abs(u)
    acS = np.abs(c_S)
    # b's tail and c: affine in the data; their error bounds: the error twins on the
    # data's magnitudes
    bt = _affine(b_const, b_c, c_S, b_u, u)
    c = _affine(c_const, c_c, c_S, c_u, u)
    eb = _affine(b_const_a, b_c_a, acS, b_u_a, au)
    ec = _affine(c_const_a, c_c_a, acS, c_u_a, au)
    # the measurement rows: y added, its representation error, the rounding of the
    # addition (none where the rest is zero) and the model allowance gK |y|
    y_scale = 0.0
    for t in range(y_pos.size):
        i = y_pos[t]
        y = Yf[y_idx[t]]
        rest = bt[i]
        ya = abs(y)
        y_scale = max(y_scale, ya)
        bt[i] = rest + y
        e = (data_rtol + gK) * ya
        if rest != 0.0:
            e += _U * (abs(rest) + ya)
        eb[i] += e
        if Y_err.size:
            eb[i] += Y_err[y_idx[t]]
    for i in range(nt):
        eb[i] += b_abs_err[i]
    for i in range(N):
        ec[i] += c_abs_err[i]
    if has_u and data_rtol != 0.0:
        _matvec_add(eb, b_u_m, au, data_rtol)
        _matvec_add(ec, c_u_m, au, data_rtol)
    if c_S_err.size and np.any(c_S_err != 0.0):
        _matvec_add(eb, b_c_m, c_S_err, 1.0)
        _matvec_add(ec, c_c_m, c_S_err, 1.0)
    gf = 1.0 + gK  # rounding of the bounds themselves
    b = np.empty(nS + nt)
    b_err = np.empty(nS + nt)
    for i in range(nS):
        b[i] = b_S[i]
        b_err[i] = b_S_err[i] * gf if b_S_err.size else 0.0
    for i in range(nt):
        b[nS + i] = bt[i]
        b_err[nS + i] = eb[i] * gf
    for i in range(N):
        ec[i] *= gf
    h = np.empty(h_S.size + h_D.size)
    h[:h_S.size] = h_S
    h[h_S.size:] = h_D
    return c, b, h, ec, b_err, y_scale


@njit(cache=True)
def outward_margin(lo, hi, margin):
    """``lo - margin * s``, ``hi + margin * s`` with ``s = max(1, |lo|, |hi|)`` over
    the finite ends (an infinite end stays infinite and does not scale the other)."""
    n = lo.size
    lo2, hi2 = np.empty(n), np.empty(n)
    for i in range(n):
        a, b = abs(lo[i]), abs(hi[i])
        if not np.isfinite(a):
            a = 0.0
        if not np.isfinite(b):
            b = 0.0
        s = max(1.0, max(a, b))
        lo2[i] = lo[i] - margin * s
        hi2[i] = hi[i] + margin * s
    return lo2, hi2


@njit(cache=True)
def reported(lo_o, hi_o, lo, hi, margin):
    """The step's reported data: the restart hull with the margin, the bounds with the
    margin, their centre (NaN where unbounded), the largest half-width and whether
    every bound is finite."""
    ho_lo, ho_hi = outward_margin(lo_o, hi_o, margin)
    lo2, hi2 = outward_margin(lo, hi, margin)
    n = lo2.size
    est = np.empty(n)
    rad = 0.0
    finite = True
    for i in range(n):
        mid = 0.5 * lo2[i] + 0.5 * hi2[i]
        est[i] = mid if np.isfinite(mid) else np.nan
        r = 0.5 * (hi2[i] - lo2[i])
        if not (np.isfinite(lo2[i]) and np.isfinite(hi2[i])):
            finite = False
        if not r <= rad:  # (inf counts; NaN cannot occur: lo <= hi)
            rad = r
    return ho_lo, ho_hi, lo2, hi2, est, rad, finite


@njit(cache=True)
def hull_bounds(bounds, c, c_err):
    """The interval hull ``c + [bounds[0::2], -bounds[1::2]]`` from the certified lower
    bounds of the objectives ``[W_0, -W_0, W_1, ...]``, widened by ``c_err`` and
    rounded outward as :func:`setobs._rounding.outward_interval` does: ``lo =
    down(down(c - c_err) + low)`` (``c`` as is where ``c_err = 0``, ``-inf`` where
    ``low`` is infinite) and ``hi`` likewise; ``ok`` is False if some certified
    bounds cross (emptiness is then the reference path's to decide)."""
    n = c.size
    lo, hi = np.empty(n), np.empty(n)
    ok = True
    for i in range(n):
        low, upp = bounds[2 * i], -bounds[2 * i + 1]
        if low > upp:
            ok = False
        e = c_err[i]
        c_lo = np.nextafter(c[i] - e, -np.inf) if e > 0 else c[i]
        c_hi = np.nextafter(c[i] + e, np.inf) if e > 0 else c[i]
        lo[i] = np.nextafter(low + c_lo, -np.inf) if np.isfinite(low) else -np.inf
        hi[i] = np.nextafter(upp + c_hi, np.inf) if np.isfinite(upp) else np.inf
    return lo, hi, ok


@njit(cache=True)
def box_start(lo, hi):
    """Centre and radii of the box restart (eq. (24)) from the hull ``[lo, hi]``: a
    coordinate unbounded on either side is free both ways (centre 0, radius inf; an
    outer answer), the others get the rounded midpoint and a radius that covers both
    ends from it (:func:`setobs.geometry.box.box_center_radius`)."""
    n = lo.size
    c, r = np.empty(n), np.empty(n)
    for i in range(n):
        if not (np.isfinite(lo[i]) and np.isfinite(hi[i])):
            c[i], r[i] = 0.0, np.inf
            continue
        c[i], r[i] = _center_radius(lo[i], hi[i])
    return c, r


@njit(cache=True)
def _sum_exact(a, b, s):
    """Whether ``s = fl(a + b)`` is exact (Knuth's TwoSum error is zero)."""
    bv = s - a
    av = s - bv
    return (a - av) + (b - bv) == 0.0


@njit(cache=True)
def _center_radius(lo, hi):
    """:func:`box_start` of one coordinate: ``(c, r)`` (``(0, inf)`` if unbounded; the
    radius rounded up only where a difference was inexact, as
    :func:`setobs.geometry.box.box_center_radius` does)."""
    if not (np.isfinite(lo) and np.isfinite(hi)):
        return 0.0, np.inf
    c = 0.5 * lo + 0.5 * hi
    d_hi, d_lo = hi - c, c - lo
    r = max(d_hi, d_lo)
    if r > 0 and not (_sum_exact(hi, -c, d_hi) and _sum_exact(c, -lo, d_lo)):
        r = np.nextafter(r, np.inf)
    return c, r


@njit(cache=True)
def restart_rows(lo_b, hi_b, avail, lo_t, hi_t, F, row_lag, G, G_a, G_e, K, K_err, K_e, S,
                 S_err, unbounded, Hu, Hu_e, Hu_m, U, data_rtol, g, g_t):
    """Ranges of the restart polytope's rows (the arithmetic of
    :meth:`setobs.setmembership._restart.RestartPolytope.rows`, which documents it):
    row ``r`` from the earlier hull ``lo_b[row_lag[r]]``, ``hi_b[...]`` (``avail``:
    known), else, or when that is unbounded, over the hull ``[lo_t, hi_t]`` itself
    (``g_t``: the rounding factor ``gamma(N + 3)`` of that product). ``G_e``,
    ``K_err``, ``S_err``, ``Hu_e``: the coefficients' error bounds; ``K_e``: the
    carried error of the sets' centres; ``Hu_m``: the inputs' coefficients'
    magnitudes; ``g``: the rounding of this evaluation."""
    L, N = lo_b.shape
    R = F.shape[0]
    c0 = np.zeros((L, N))
    r0 = np.zeros((L, N))
    fin = np.zeros((L, N), np.bool_)
    for j in range(L):
        for i in range(N):
            c, r = _center_radius(lo_b[j, i], hi_b[j, i])
            if np.isfinite(r):
                fin[j, i] = True
                c0[j, i], r0[j, i] = c, r
    aU = np.abs(U)
    lo, hi = np.empty(R), np.empty(R)
    bad = np.zeros(R, np.bool_)
    for k in range(R):
        j = row_lag[k]
        b = unbounded[k] or not avail[j]
        mid, rad = K[k], S[k]
        mag = abs(K[k]) + S[k]
        err = K_e[k] + K_err[k] + S_err[k]
        for i in range(N):
            if (G_a[k, i] != 0.0 or G_e[k, i] != 0.0) and not fin[j, i]:
                b = True
            z = abs(c0[j, i]) + r0[j, i]
            mid += G[k, i] * c0[j, i]
            rad += G_a[k, i] * r0[j, i]
            mag += G_a[k, i] * z
            err += G_e[k, i] * z
        if U.size:
            tu = 0.0
            for i in range(U.size):
                mid += Hu[k, i] * U[i]
                mag += abs(Hu[k, i]) * aU[i]
                err += Hu_e[k, i] * aU[i]
                tu += Hu_m[k, i] * aU[i]
            err += data_rtol * tu
        err += g * mag
        # the range's own assembly (three roundings of terms up to its magnitude)
        err += 4.0 * _U * (abs(mid) + rad + err)
        lo[k], hi[k] = mid - (rad + err), mid + (rad + err)
        if not (np.isfinite(lo[k]) and np.isfinite(hi[k])):
            b = True
        bad[k] = b
    if bad.any():
        # the rows' ranges over the hull at t itself: F c -+ (|F| r + rounding)
        ct, rt = np.zeros(N), np.zeros(N)
        ft = np.zeros(N, np.bool_)
        for i in range(N):
            c, r = _center_radius(lo_t[i], hi_t[i])
            if np.isfinite(r):
                ft[i] = True
                ct[i], rt[i] = c, r
        for k in range(R):
            if not bad[k]:
                continue
            m0, r1, s = 0.0, 0.0, 0.0
            unb = False
            for i in range(N):
                a = abs(F[k, i])
                m0 += F[k, i] * ct[i]
                r1 += a * rt[i]
                s += a * abs(ct[i])
                if a > 0 and not ft[i]:
                    unb = True
            r1 = r1 + g_t * (s + r1)
            lo[k] = -np.inf if unb else m0 - r1
            hi[k] = np.inf if unb else m0 + r1
    return lo, hi
