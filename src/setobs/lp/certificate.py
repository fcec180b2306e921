"""The certificate: a rigorous lower bound of an LP's minimum from any multiplier.

Every bound setobs reports -- an interval hull, a support value, an emptiness
verdict, a disturbance band -- is, in the end, the minimum of a linear function
over a polytope

.. math::  \\min \\{ w^\\top x : A x = b,\\ l \\le x \\le u \\},

and every such minimum is reported through :func:`lower_bound`, written once
here. Whatever solver proposed the multiplier (HiGHS, the compiled simplex of
:mod:`setobs.lp._simplex`, nothing at all), the bound holds for the stored data.

Weak duality
------------
For any row multiplier ``y`` and reduced costs ``r = w - A^T y``, every feasible
``x`` has ``w^T x = y^T b + r^T x``, so

.. math::  \\min_x w^\\top x \\;\\ge\\; y^\\top b + \\sum_j \\min(r_j l_j,\\, r_j u_j)

whatever the accuracy of ``y``: the solver only decides how *tight* the bound
is, never whether it is valid. A column with ``l_j = -inf`` and ``u_j = +inf``
(an unbounded factor ``h_j = inf``) contributes ``-inf`` unless ``r_j = 0``; for
those columns ``y`` is refined by a pseudo-inverse correction in double-double
form ``y1 + y2`` and their reduced costs are evaluated exactly, and the bound
then holds for every ``x`` with ``|x_j| <= radius`` on them (the term
``radius * sum |r_j|``); when the relative residual stays above ``tol_unb`` the
answer is ``-inf``, which is always outer.

Rounding analysis
-----------------
Evaluated in floating point with unit roundoff ``u``, ``gamma_k = k u / (1 - k u)``
(Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., Lemma 3.1):

* ``r_j`` is a sum of ``2 k_j + 1`` terms (``k_j`` the stored entries of column
  ``j``; exact zeros contribute nothing), so ``|r_j - fl(r_j)| <= gamma_(2 k_j + 1)
  s_j`` with ``s_j = |w_j| + |A_j|^T (|y1| + |y2|)``; the bound used is
  ``e_j = 2 gamma_(2 k_j + 2) s_j`` (the factor 2 covers the rounding of ``s_j``
  and of ``e_j`` itself) plus an underflow guard and, when ``w`` was itself
  computed, ``(1 + 4u) w_err_j``. With ``exact=True`` every ``r_j`` is instead
  summed exactly (Dekker's TwoProduct and Shewchuk's summation) and ``e_j`` is
  the error of rounding that exact sum once;
* the objective may be given as an exact product ``w = M^T v`` (``M`` with rows):
  the exact reduced costs then take ``M^T v`` in TwoProduct form and ``w``'s
  rounding never enters;
* ``r_j x_j >= min(r_j l_j, r_j u_j) - e_j max(|l_j|, |u_j|)`` for the true
  ``r_j`` (a column bounded on one side only, ``l_j <= x_j``, needs the true
  ``r_j >= 0``, certified by ``fl(r_j) >= e_j``, and then contributes
  ``r_j l_j - e_j |l_j|``; otherwise the bound is ``-inf``); the sums
  ``P = sum min(...)`` (absolute sum ``P_abs``) and ``Q = sum e_j max(...)`` are
  each off by at most ``gamma_(n+1)`` of their absolute sum;
* ``y^T b`` is summed exactly from TwoProducts and rounded (error ``t1_err``);
* a right-hand side known only to ``|b - b_stored| <= b_err`` costs ``tb = (1 +
  gamma_(m+2)) sum (|y1_i| + |y2_i|) b_err_i``: the bound holds for every such ``b``;
* the result ``t1 + P - Q - tb`` is lowered by ``t1_err (1 + 4u) + 2 (gamma_(n+3)
  (P_abs + Q + tb) + 2u (|t1| + P_abs + Q + tb)) + 8 (n + m + 1) tiny`` and moved
  one ulp further down (the subtraction itself rounds to nearest).

A NaN anywhere (data beyond double precision's range) gives ``-inf``: nothing
certified, still outer.

One text, two executions
------------------------
The functions below are plain Python in the subset numba compiles; the compiled
simplex calls them compiled, and :func:`certified_lower_bound` (the entry point
of the HiGHS paths) calls the compiled twin too. The test
``tests/lp/test_certificate.py`` runs the same battery with ``NUMBA_DISABLE_JIT=1``
(the text as written, interpreted) and compiled, and requires every bound and
multiplier to agree bit for bit; it checks the bound itself against exact
rational arithmetic.
"""

from __future__ import annotations

import numpy as np
from numba import njit
from numpy.typing import NDArray

from ..exceptions import DimensionError, InvalidValueError
from ..tolerances import UNBOUNDED_RADIUS, UNBOUNDED_REDUCED_COST_TOL

__all__ = ["certified_lower_bound", "csc_of", "lagrangian_lower_bound", "lower_bound"]

U = np.finfo(np.float64).eps / 2.0
TINY = np.finfo(np.float64).tiny
_EMPTY_I = np.zeros(0, dtype=np.int64)
_NO_DENSE = np.zeros((0, 0))


@njit(cache=True)
def gamma_k(k):
    """Higham's ``gamma_k = k u / (1 - k u)``."""
    return k * U / (1.0 - k * U)


@njit(cache=True)
def two_prod_terms(a, b, terms, k):
    """Append the exact pair ``p + e = a * b`` (Dekker's TwoProduct) to ``terms`` at ``k``."""
    p = a * b
    t = 134217729.0 * a
    ah = t - (t - a)
    al = a - ah
    t = 134217729.0 * b
    bh = t - (t - b)
    bl = b - bh
    e = ((ah * bh - p) + ah * bl + al * bh) + al * bl
    terms[k] = p
    terms[k + 1] = e
    return k + 2


@njit(cache=True)
def exact_sum_bound(terms, nterms, partials):
    """Shewchuk's exact summation; returns ``(s, bound, err)`` with ``|sum| <= bound``
    and ``|sum - s| <= err``.

    The partials are an exact, non-overlapping representation of the sum; ``s``
    is their floating-point sum and ``err = gamma_(p+1) sum |partials|``.
    """
    npart = 0
    for t in range(nterms):
        xv = terms[t]
        i = 0
        for k in range(npart):
            yv = partials[k]
            if abs(xv) < abs(yv):
                xv, yv = yv, xv
            hi = xv + yv
            lo = yv - (hi - xv)
            if lo != 0.0:
                partials[i] = lo
                i += 1
            xv = hi
        partials[i] = xv
        npart = i + 1
    s = 0.0
    sabs = 0.0
    for k in range(npart):
        s += partials[k]
        sabs += abs(partials[k])
    err = gamma_k(npart + 1) * sabs
    return s, abs(s) + err, err


@njit(cache=True)
def csc_of(A):
    """``(indptr, indices, data)`` of a dense matrix, column by column, exact zeros left out."""
    m, n = A.shape
    indptr = np.zeros(n + 1, dtype=np.int64)
    nnz = 0
    for j in range(n):
        for i in range(m):
            if A[i, j] != 0.0:
                nnz += 1
        indptr[j + 1] = nnz
    indices = np.empty(nnz, dtype=np.int64)
    data = np.empty(nnz)
    p = 0
    for j in range(n):
        for i in range(m):
            if A[i, j] != 0.0:
                indices[p] = i
                data[p] = A[i, j]
                p += 1
    return indptr, indices, data


@njit(cache=True)
def _column_terms(j, w, M, v, indptr, indices, data, y1, y2, terms):
    """The exact terms of ``w_j - A_j^T (y1 + y2)`` (``w_j = M_j^T v`` when ``M`` has rows)."""
    nt = 0
    if M.shape[0] > 0:
        for i in range(M.shape[0]):
            nt = two_prod_terms(M[i, j], v[i], terms, nt)
    else:
        terms[0] = w[j]
        nt = 1
    for p in range(indptr[j], indptr[j + 1]):
        i = indices[p]
        nt = two_prod_terms(-data[p], y1[i], terms, nt)
        nt = two_prod_terms(-data[p], y2[i], terms, nt)
    return nt


@njit(cache=True)
def _refine(w, indptr, indices, data, fidx, pinvU, y):
    """``y += pinvU (w_U - A_U^T y)``: one correction on the unbounded columns."""
    f = fidx.size
    res = np.empty(f)
    for kk in range(f):
        j = fidx[kk]
        s = w[j]
        for p in range(indptr[j], indptr[j + 1]):
            s -= data[p] * y[indices[p]]
        res[kk] = s
    for i in range(y.size):
        s = 0.0
        for kk in range(f):
            s += pinvU[i, kk] * res[kk]
        y[i] += s


@njit(cache=True)
def _all_finite(x):
    for i in range(x.size):
        if not np.isfinite(x[i]):
            return False
    return True


@njit(cache=True)
def lower_bound(w, indptr, indices, data, b, lo, hi, y, fidx, pinvU, radius, tol_unb,
                b_err, w_err, M, v, exact, Ad):
    """Certified lower bound of ``min {w^T x : A x = b, lo <= x <= hi}`` from any ``y``.

    The one certificate of the package (module notes: weak duality and its
    rounding analysis).

    Parameters
    ----------
    w : ndarray, shape (n,)
        Objective (as stored; see ``w_err`` and ``M, v``).
    indptr, indices, data : ndarray
        ``A`` (``m x n``) column by column (:func:`csc_of`, or a ``scipy.sparse``
        CSC array's fields).
    b : ndarray, shape (m,)
        Right-hand side.
    lo, hi : ndarray, shape (n,)
        Variable bounds; a column with ``lo = -inf`` and ``hi = +inf`` must be listed
        in ``fidx``.
    y : ndarray, shape (m,)
        Any multiplier; on return it holds the refined multiplier ``y1 + y2`` (rounded).
    fidx : ndarray of int64
        The unbounded columns.
    pinvU : ndarray, shape (m, fidx.size)
        ``pinv(A[:, fidx]^T)`` (any matrix gives a valid bound; this one makes it tight).
    radius : float
        Bound assumed on ``|x_j|`` for ``j`` in ``fidx``.
    tol_unb : float
        Largest relative reduced cost of an unbounded column treated as zero.
    b_err : ndarray, shape (m,) or (0,)
        ``|b_true - b| <= b_err`` (empty: exact).
    w_err : ndarray, shape (n,) or (0,)
        ``|w_true - w| <= w_err`` (empty: exact; unused where ``M`` has rows and the
        reduced cost is exact).
    M, v : ndarray, shapes (k, n) and (k,)
        ``w_true = M^T v`` when ``k > 0`` (the unbounded columns' and, with
        ``exact``, every column's reduced cost use it exactly).
    exact : bool
        Every reduced cost summed exactly (``O(nnz)`` TwoProducts), not bounded by
        ``gamma``: for multipliers of size 1e4, where the forward bound alone opens gaps.
    Ad : ndarray, shape (m, n) or (0, 0)
        ``A`` dense as well, when the caller has it: the reduced costs are then summed
        row by row (the same terms in the same order; about twice as fast on the
        window LPs), else column by column from the CSC arrays.

    Returns
    -------
    bound : float
        Certified lower bound (``-inf`` when nothing can be certified).
    slack : float
        The part of ``objective - bound`` that precision alone explains (``tb``,
        the rounding terms, and reduced costs at rounding level, which are zero
        for an exact optimal multiplier but cannot be below ``u s_j`` for a
        rounded one); ``inf`` with a bound of ``-inf``.
    """
    m = b.size
    n = w.size
    f = fidx.size
    k = M.shape[0]
    maxnnz = 0
    for j in range(n):
        maxnnz = max(maxnnz, indptr[j + 1] - indptr[j])
    size = max(4 * maxnnz + 2 * k + 1, 4 * m + 1)
    terms = np.empty(size)
    partials = np.empty(size)
    has_werr = w_err.size > 0
    y1 = y.copy()
    y2 = np.zeros(m)
    ru = np.zeros(f)
    ru_bound = np.zeros(f)
    guard = 2.0 * (2 * maxnnz + 2 * k + 1) * TINY  # (TwoProduct is exact barring underflow)
    if f > 0 and m > 0:
        _refine(w, indptr, indices, data, fidx, pinvU, y1)
        _refine(w, indptr, indices, data, fidx, pinvU, y1)
        if not _all_finite(y1):
            return -np.inf, np.inf
        for it in range(3):
            nz = False
            for kk in range(f):
                j = fidx[kk]
                nt = _column_terms(j, w, M, v, indptr, indices, data, y1, y2, terms)
                s, bnd, _ = exact_sum_bound(terms, nt, partials)
                ru[kk] = s
                ru_bound[kk] = bnd + guard
                if s != 0.0:
                    nz = True
            if it == 2 or not nz:
                break
            for i in range(m):  # y2 += pinvU ru
                s = 0.0
                for kk in range(f):
                    s += pinvU[i, kk] * ru[kk]
                y2[i] += s
            if not _all_finite(y2):
                return -np.inf, np.inf
    elif f > 0:
        for kk in range(f):
            nt = _column_terms(fidx[kk], w, M, v, indptr, indices, data, y1, y2, terms)
            s, bnd, _ = exact_sum_bound(terms, nt, partials)
            ru[kk] = s
            ru_bound[kk] = bnd + guard
    # reduced costs, their scale and their error bound, column by column
    r = np.empty(n)
    sc = np.empty(n)
    e = np.empty(n)
    if Ad.shape[0] == m and Ad.shape[1] == n and m > 0:
        # The same sums over the dense A, row by row (a contiguous, vectorised loop):
        # per column the same terms in the same order as the column loop below, its
        # zeros adding exact zeros (a zero's sign aside, the same values).
        for j in range(n):
            r[j] = w[j]
            sc[j] = abs(w[j])
        for i in range(m):
            a1, a2 = y1[i], y2[i]
            ay = abs(a1) + abs(a2)
            if ay == 0.0:
                continue
            for j in range(n):
                r[j] -= Ad[i, j] * a1
            if a2 != 0.0:
                for j in range(n):
                    r[j] -= Ad[i, j] * a2
            for j in range(n):
                sc[j] += abs(Ad[i, j]) * ay
    else:
        for j in range(n):
            s = w[j]
            a = abs(w[j])
            for p in range(indptr[j], indptr[j + 1]):
                i = indices[p]
                s -= data[p] * y1[i]
                s -= data[p] * y2[i]
                a += abs(data[p]) * (abs(y1[i]) + abs(y2[i]))
            r[j] = s
            sc[j] = a
    for j in range(n):
        cnt = indptr[j + 1] - indptr[j]
        g = 2.0 * (2 * cnt + 1) * TINY
        if exact:
            nt = _column_terms(j, w, M, v, indptr, indices, data, y1, y2, terms)
            s, _, err = exact_sum_bound(terms, nt, partials)
            r[j] = s
            e[j] = 2.0 * err + U * abs(s) + guard
            if has_werr and k == 0:
                e[j] += w_err[j] * (1.0 + 4.0 * U)
        else:
            e[j] = 2.0 * gamma_k(2 * cnt + 2) * sc[j] + g
            if has_werr:
                e[j] += w_err[j] * (1.0 + 4.0 * U)
    Q = 0.0
    if f > 0:
        scale_all = TINY
        for j in range(n):
            scale_all = max(scale_all, sc[j])
        su = 0.0
        for kk in range(f):
            rb = ru_bound[kk]
            if has_werr and k == 0:
                rb += w_err[fidx[kk]] * (1.0 + 4.0 * U)
            rel = (rb - guard) / scale_all
            if not (rel <= tol_unb):
                return -np.inf, np.inf
            su += rb
        Q = radius * su * (1.0 + gamma_k(f + 1))
    slack = Q
    P = 0.0
    Pabs = 0.0
    for j in range(n):
        lj = lo[j]
        hj = hi[j]
        if lj == -np.inf and hj == np.inf:
            continue  # (in fidx: the radius term above)
        if lj == 0.0 and hj == 0.0:
            continue
        rj = r[j]
        if hj == np.inf:  # (x_j >= lj only: the true r_j must be >= 0)
            if not (rj >= e[j]):
                return -np.inf, np.inf
            pj = rj * lj
            mj = abs(lj)
        elif lj == -np.inf:  # (x_j <= hj only: the true r_j must be <= 0)
            if not (-rj >= e[j]):
                return -np.inf, np.inf
            pj = rj * hj
            mj = abs(hj)
        else:
            pj = min(rj * lj, rj * hj) if rj != 0.0 else 0.0
            mj = max(abs(lj), abs(hj))
        P += pj
        Pabs += abs(pj)
        Q += e[j] * mj
        slack += (min(abs(rj), 64.0 * U * sc[j]) + e[j]) * mj
    # t1 = y^T b from exact products, summed exactly
    nt = 0
    for i in range(m):
        nt = two_prod_terms(y1[i], b[i], terms, nt)
        nt = two_prod_terms(y2[i], b[i], terms, nt)
    t1, _, t1_err = exact_sum_bound(terms, nt, partials)
    t1_err += 4.0 * (m + 1) * TINY
    tb = 0.0
    if b_err.size > 0:
        for i in range(m):
            tb += (abs(y1[i]) + abs(y2[i])) * b_err[i]
        tb *= 1.0 + gamma_k(m + 2)
    for i in range(m):
        y[i] = y1[i] + y2[i]
    total = Pabs + Q + tb
    err = t1_err * (1.0 + 4.0 * U) + 2.0 * (gamma_k(n + 3) * total
                                            + 2.0 * U * (abs(t1) + total)) \
        + 8.0 * (n + m + 1) * TINY
    bound = np.nextafter(t1 + P - Q - tb - err, -np.inf)
    if bound != bound:  # (NaN: data beyond double precision; nothing certified)
        return -np.inf, np.inf
    return bound, slack + tb + 2.0 * err


def _as_csc(A) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]:
    if hasattr(A, "tocsc"):  # (scipy.sparse)
        C = A.tocsc()
        C.sum_duplicates()
        return (C.indptr.astype(np.int64), C.indices.astype(np.int64),
                np.asarray(C.data, dtype=np.float64))
    return csc_of(np.ascontiguousarray(A, dtype=np.float64))


def check_lp_shapes(m: int, n: int, **arrays) -> None:
    """Raise :class:`~setobs.exceptions.DimensionError` naming the argument whose shape
    does not fit an LP with ``m`` rows and ``n`` columns, and
    :class:`~setobs.exceptions.InvalidValueError` for one holding NaN (or, for ``b``,
    ``w``, ``b_err``, ``w_err``, an infinite entry; ``lo`` may hold ``-inf`` and
    ``hi`` ``+inf``, ``h`` ``+inf``). ``None`` arguments are skipped. The compiled
    kernels do no bounds checks: a short ``lo`` or ``hi`` was read past its end.
    The multiplier ``y`` is checked for its shape only: any values are allowed (a
    non-finite one certifies nothing)."""
    want = {"w": (n,), "b": (m,), "y": (m,), "lo": (n,), "hi": (n,), "h": (n,),
            "b_err": (m,), "w_err": (n,)}
    for name, a in arrays.items():
        if a is None:
            continue
        shape = np.shape(a)
        if shape != want[name]:
            raise DimensionError(f"{name} must have shape {want[name]} for an LP of {m} rows "
                                 f"and {n} columns (A is {m} x {n}), got {shape}")
        if name == "y":
            continue
        v = np.asarray(a, dtype=np.float64)
        bad = np.isnan(v)
        if bad.any():
            raise InvalidValueError(f"{name} holds NaN (first at index {int(np.argmax(bad))})"
                                    ": pass numbers")
        bad = ~np.isfinite(v)
        if name in ("w", "b", "b_err", "w_err") and bad.any():
            i = int(np.argmax(bad))
            raise InvalidValueError(f"{name} must be finite, got {v[i]} at index {i}")
        if name in ("b_err", "w_err", "h") and (v < 0).any():
            i = int(np.argmax(v < 0))
            raise InvalidValueError(f"{name} must be nonnegative, got {v[i]} at index {i}")
    lo, hi = arrays.get("lo"), arrays.get("hi")
    if lo is not None and hi is not None:
        lo, hi = np.asarray(lo, dtype=np.float64), np.asarray(hi, dtype=np.float64)
        bad = (lo > hi) | (lo == np.inf) | (hi == -np.inf)
        if bad.any():
            j = int(np.argmax(bad))
            raise InvalidValueError(f"the bounds need lo <= hi, lo < inf and hi > -inf: "
                                    f"column {j} has [{lo[j]}, {hi[j]}]")


def certified_lower_bound(
    w: NDArray[np.float64],
    A,
    b: NDArray[np.float64],
    lo: NDArray[np.float64],
    hi: NDArray[np.float64],
    y: NDArray[np.float64],
    *,
    b_err: NDArray[np.float64] | None = None,
    w_err: NDArray[np.float64] | None = None,
    w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    unbounded_radius: float = UNBOUNDED_RADIUS,
    unbounded_pinv: NDArray[np.float64] | None = None,
    exact_residual: bool = False,
    csc: tuple | None = None,
) -> tuple[float, NDArray[np.float64], float]:
    """Certified lower bound of ``min {w^T x : A x = b, lo <= x <= hi}`` from any ``y``.

    The entry point of :func:`lower_bound` (the compiled certificate) for Python callers.

    Parameters
    ----------
    w : ndarray, shape (n,)
        Objective.
    A : ndarray or scipy.sparse array, shape (m, n)
        Equality constraints.
    b : ndarray, shape (m,)
        Right-hand side.
    lo, hi : ndarray, shape (n,)
        Variable bounds (``-inf``/``+inf`` together mark an unbounded column).
    y : ndarray, shape (m,)
        Any multiplier (typically a solver's row duals); not modified.
    b_err : ndarray, optional
        ``|b_true - b| <= b_err``: the bound holds for every such right-hand side.
    w_err : ndarray, optional
        ``|w_true - w| <= w_err`` (``w`` computed in floating point).
    w_pair : (M, v), optional
        ``w_true = M^T v`` exactly.
    unbounded_radius : float
        Bound assumed on the unbounded columns.
    unbounded_pinv : ndarray, optional
        ``pinv(A[:, unbounded]^T)``; computed if omitted.
    exact_residual : bool
        Every reduced cost summed exactly (see :func:`lower_bound`).
    csc : tuple, optional
        ``A``'s ``(indptr, indices, data)`` when the caller keeps them.

    Returns
    -------
    bound : float
        Certified lower bound (``-inf`` when nothing can be certified).
    y : ndarray
        The refined multiplier the bound was certified for.
    slack : float
        The part of a gap that precision alone explains (see :func:`lower_bound`).

    Raises
    ------
    DimensionError
        An argument whose shape does not fit ``A`` (named).
    InvalidValueError
        NaN, an infinite ``w``, ``b`` or error bound, or ``lo > hi``.
    """
    if np.ndim(A) != 2:
        raise DimensionError(f"A must be a matrix (m, n), got shape {np.shape(A)}")
    m, n = (int(d) for d in A.shape)
    check_lp_shapes(m, n, w=w, b=b, lo=lo, hi=hi, y=y, b_err=b_err, w_err=w_err)
    if w_pair is not None and (np.ndim(w_pair[0]) != 2 or np.shape(w_pair[0])[1] != n
                               or np.shape(w_pair[1]) != (np.shape(w_pair[0])[0],)):
        raise DimensionError(f"w_pair must be (M, v) with M of shape (k, {n}) and v of shape "
                             f"(k,), got {np.shape(w_pair[0])} and {np.shape(w_pair[1])}")
    if csc is not None and (len(csc[0]) != n + 1):
        raise DimensionError(f"csc must have the shape of A's (indptr, indices, data): "
                             f"{n + 1} column pointers, got {len(csc[0])}")
    w = np.ascontiguousarray(w, dtype=np.float64)
    indptr, indices, data = csc if csc is not None else _as_csc(A)
    unb = np.isinf(lo) & np.isinf(hi)
    fidx = np.flatnonzero(unb).astype(np.int64) if unb.any() else _EMPTY_I
    if fidx.size and m:
        if unbounded_pinv is None:
            Ad = A.toarray() if hasattr(A, "toarray") else np.asarray(A, dtype=np.float64)
            with np.errstate(over="ignore", invalid="ignore"):
                unbounded_pinv = np.linalg.pinv(Ad[:, fidx].T)
        pinvU = np.ascontiguousarray(unbounded_pinv, dtype=np.float64)
        if not np.isfinite(pinvU).all():
            # (a pseudo-inverse beyond double precision: no refinement, no bound)
            return -np.inf, np.array(y, dtype=np.float64), np.inf
    else:
        pinvU = np.zeros((m, fidx.size))
    if w_pair is not None:
        M = np.ascontiguousarray(w_pair[0], dtype=np.float64)
        v = np.ascontiguousarray(w_pair[1], dtype=np.float64)
    else:
        M, v = np.zeros((0, n)), np.zeros(0)
    Ad = A if (isinstance(A, np.ndarray) and A.dtype == np.float64 and A.ndim == 2
               and A.flags.c_contiguous) else _NO_DENSE
    yy = np.array(y, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        bound, slack = lower_bound(
            w, indptr, indices, data, np.ascontiguousarray(b, dtype=np.float64),
            np.ascontiguousarray(lo, dtype=np.float64), np.ascontiguousarray(hi, dtype=np.float64),
            yy, fidx, pinvU, float(unbounded_radius), float(UNBOUNDED_REDUCED_COST_TOL),
            np.zeros(0) if b_err is None else np.ascontiguousarray(b_err, dtype=np.float64),
            np.zeros(0) if w_err is None else np.ascontiguousarray(w_err, dtype=np.float64),
            M, v, bool(exact_residual), Ad)
    return float(bound), yy, float(slack)


def lagrangian_lower_bound(
    w: NDArray[np.float64],
    A: NDArray[np.float64],
    b: NDArray[np.float64],
    h: NDArray[np.float64],
    y: NDArray[np.float64],
    *,
    w_err: NDArray[np.float64] | None = None,
    unbounded_radius: float = UNBOUNDED_RADIUS,
    unbounded_pinv: NDArray[np.float64] | None = None,
    w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    b_err: NDArray[np.float64] | None = None,
    exact_residual: bool = False,
) -> tuple[float, NDArray[np.float64]]:
    """Certified lower bound of ``min {w^T xi : A xi = b, |xi| <= h}`` from any ``y``:
    :func:`certified_lower_bound` with ``lo = -h``, ``hi = h`` (a factor polytope).

    Parameters
    ----------
    w, A, b, h, y :
        Objective, the factor polytope (``h_j = inf``: an unbounded factor), multiplier.
    w_err, unbounded_radius, unbounded_pinv, w_pair, b_err, exact_residual :
        See :func:`certified_lower_bound`.

    Returns
    -------
    bound : float
        Certified lower bound.
    y : ndarray
        The refined multiplier used.
    """
    h = np.asarray(h, dtype=np.float64)
    if np.ndim(A) != 2:
        raise DimensionError(f"A must be a matrix (m, n), got shape {np.shape(A)}")
    check_lp_shapes(A.shape[0], A.shape[1], h=h)
    bound, yy, _ = certified_lower_bound(
        w, A, b, -h, h, y, b_err=b_err, w_err=w_err, w_pair=w_pair,
        unbounded_radius=unbounded_radius, unbounded_pinv=unbounded_pinv,
        exact_residual=exact_residual)
    return bound, yy
