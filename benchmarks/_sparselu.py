"""A sparse LU of a simplex basis, for measuring what one would cost on exact mode's LPs
(``exact_floor.py``): not used by setobs.

The left-looking factorisation of Gilbert and Peierls (1988) with threshold partial
pivoting, in the form of Davis's CSparse ``cs_lu`` (T. A. Davis, *Direct Methods for
Sparse Linear Systems*, SIAM 2006, sections 6.2-6.3), after the triangularisation simplex
codes use (column singletons first, row singletons last: no fill), and its solves: with a
dense right-hand side, and with a sparse one over the nonzero pattern found by a
depth-first search (Gilbert-Peierls; the "hyper-sparse" solve of Hall and McKinnon 2005),
in time proportional to the flops.

The basis is ``B = A[:, cols]`` for an ``m x n`` matrix ``A`` given column-wise (``indptr,
indices, data``) and ``m`` distinct column indices ``cols``. In each column, after the
solve with the columns of ``L`` so far, the pivot is, among the rows not yet pivotal whose
entry is at least ``threshold`` times the largest such entry, the triangular part's own
row, else the one with the fewest nonzeros in ``B``. The result is ``P B Q = L U`` with
``L`` unit lower triangular and ``U`` upper triangular, both stored by columns in pivot
order. A column whose largest such entry is at most ``SINGULAR_RTOL`` times its largest in
``B`` makes the basis singular (``ok = False``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: Smallest pivot accepted, relative to the largest entry of the basis column.
SINGULAR_RTOL = 1e-11


@njit(cache=True)
def _peel(ptr, idx, tptr, tidx, cnt, tcnt, on, ton, out, tout, stack):
    """Remove singletons of one side of ``B`` one after another: a line ``j`` (of the
    side stored by ``ptr, idx``; the other side by ``tptr, tidx``) with one entry left,
    in the cross line ``r``, goes with ``r``; ``cnt``/``tcnt`` count the entries left in
    each line. Writes the pairs to ``out, tout``; returns their number."""
    top = 0
    for j in range(on.size):
        if on[j] and cnt[j] == 1:
            stack[top] = j
            top += 1
    n = 0
    while top > 0:
        top -= 1
        j = stack[top]
        if not on[j] or cnt[j] != 1:
            continue
        r = -1
        for p in range(ptr[j], ptr[j + 1]):
            if ton[idx[p]]:
                r = idx[p]
        on[j] = False
        ton[r] = False
        out[n] = j
        tout[n] = r
        n += 1
        for p in range(ptr[j], ptr[j + 1]):
            tcnt[idx[p]] -= 1
        for p in range(tptr[r], tptr[r + 1]):
            j2 = tidx[p]
            if on[j2]:
                cnt[j2] -= 1
                if cnt[j2] == 1:
                    stack[top] = j2
                    top += 1
    return n


@njit(cache=True)
def triangular_order(m, indptr, indices, cols):
    """Column order and preferred pivot rows of ``B = A[:, cols]`` (the positions in
    ``cols``): first the column singletons, removed one after another with their rows
    (each pivots on its one remaining row: no fill), last the row singletons of what is
    left, removed likewise and taken in reverse (each pivots on its row: no fill), and
    the rest (the nucleus) between them by increasing count in the nucleus's rows.

    Returns ``(q, prefer, n_nucleus)``: ``prefer[k]`` is the row the ``k``-th column
    pivots on, ``-1`` in the nucleus.
    """
    # B column-wise over the positions k (cp, ci) and row-wise (rp, rk)
    rowcnt = np.zeros(m, np.int64)
    colcnt = np.empty(m, np.int64)
    cp = np.zeros(m + 1, np.int64)
    for k in range(m):
        c = cols[k]
        colcnt[k] = indptr[c + 1] - indptr[c]
        cp[k + 1] = cp[k] + colcnt[k]
        for p in range(indptr[c], indptr[c + 1]):
            rowcnt[indices[p]] += 1
    ci = np.empty(cp[m], np.int64)
    rp = np.zeros(m + 1, np.int64)
    for i in range(m):
        rp[i + 1] = rp[i] + rowcnt[i]
    fillp = rp[:m].copy()
    rk = np.empty(rp[m], np.int64)
    for k in range(m):
        c = cols[k]
        ci[cp[k]:cp[k + 1]] = indices[indptr[c]:indptr[c + 1]]
        for p in range(indptr[c], indptr[c + 1]):
            i = indices[p]
            rk[fillp[i]] = k
            fillp[i] += 1
    col_on = np.ones(m, np.bool_)
    row_on = np.ones(m, np.bool_)
    stack = np.empty(m + rp[m], np.int64)
    front_q = np.empty(m, np.int64)
    front_r = np.empty(m, np.int64)
    nf = _peel(cp, ci, rp, rk, colcnt, rowcnt, col_on, row_on, front_q, front_r, stack)
    back_r = np.empty(m, np.int64)
    back_q = np.empty(m, np.int64)
    nb = _peel(rp, rk, cp, ci, rowcnt, colcnt, row_on, col_on, back_r, back_q, stack)
    q = np.empty(m, np.int64)
    prefer = np.full(m, -1, np.int64)
    q[:nf] = front_q[:nf]
    prefer[:nf] = front_r[:nf]
    # the nucleus: by increasing count in its rows
    nn = m - nf - nb
    ncnt = np.empty(nn, np.int64)
    nk = np.empty(nn, np.int64)
    t = 0
    for k in range(m):
        if col_on[k]:
            cnt = 0
            for p in range(cp[k], cp[k + 1]):
                if row_on[ci[p]]:
                    cnt += 1
            nk[t] = k
            ncnt[t] = cnt
            t += 1
    srt = np.argsort(ncnt, kind="mergesort")
    for t in range(nn):
        q[nf + t] = nk[srt[t]]
    for t in range(nb):
        q[nf + nn + t] = back_q[nb - 1 - t]
        prefer[nf + nn + t] = back_r[nb - 1 - t]
    return q, prefer, nn


@njit(cache=True)
def _room(Ii, Ix, used, need):
    """``(Ii, Ix)``, or copies of their first ``used`` entries in arrays twice as long, so
    that ``need`` more entries fit."""
    if used + need <= Ii.size:
        return Ii, Ix
    grow = 2 * Ii.size + need
    Ii2 = np.empty(grow, np.int64)
    Ix2 = np.empty(grow)
    Ii2[:used] = Ii[:used]
    Ix2[:used] = Ix[:used]
    return Ii2, Ix2


@njit(cache=True)
def lu_factor(m, indptr, indices, data, cols, threshold):
    """``P B Q = L U`` of ``B = A[:, cols]`` (module notes).

    Returns ``(ok, Lp, Li, Lx, Up, Ui, Ux, pinv, q)``: ``L`` and ``U`` column-wise with
    row indices in pivot order (each ``U`` column's diagonal last, each ``L`` column's
    unit diagonal first), ``pinv[i]`` the pivot step of row ``i``, ``q[k]`` the position
    in ``cols`` of the ``k``-th pivot column; ``ok`` is ``False`` for a singular basis.
    """
    q, prefer, _ = triangular_order(m, indptr, indices, cols)
    rowcnt = np.zeros(m, np.int64)
    nnz = 0
    for k in range(m):
        c = cols[k]
        nnz += indptr[c + 1] - indptr[c]
        for p in range(indptr[c], indptr[c + 1]):
            rowcnt[indices[p]] += 1
    cap = 4 * nnz + m
    Lp = np.zeros(m + 1, np.int64)
    Up = np.zeros(m + 1, np.int64)
    Li = np.empty(cap, np.int64)
    Lx = np.empty(cap)
    Ui = np.empty(cap, np.int64)
    Ux = np.empty(cap)
    pinv = np.full(m, -1, np.int64)
    x = np.zeros(m)
    xi = np.empty(m, np.int64)
    pstack = np.empty(m, np.int64)
    mark = np.zeros(m, np.int64)
    lnz = 0
    unz = 0
    for k in range(m):
        Lp[k] = lnz
        Up[k] = unz
        Li, Lx = _room(Li, Lx, lnz, m)  # (a column adds at most m entries to each)
        Ui, Ux = _room(Ui, Ux, unz, m)
        c = cols[q[k]]
        # pattern of x = L^-1 B[:, q_k]: reach of the column's rows in L's graph
        stamp = k + 1
        top = _reach(Lp, Li, True, False, indices[indptr[c]:indptr[c + 1]], pinv, xi, pstack,
                     mark, stamp)
        for p in range(top, m):
            x[xi[p]] = 0.0
        colmax = 0.0
        for p in range(indptr[c], indptr[c + 1]):
            x[indices[p]] = data[p]
            colmax = max(colmax, abs(data[p]))
        for px in range(top, m):  # the sparse triangular solve, in topological order
            j = xi[px]
            J = pinv[j]
            if J < 0:
                continue
            xj = x[j]
            for p in range(Lp[J] + 1, Lp[J + 1]):
                x[Li[p]] -= Lx[p] * xj
        # pivot: the largest entry among rows not yet pivotal, then the sparsest row
        # within the threshold of it
        big = 0.0
        for px in range(top, m):
            i = xi[px]
            if pinv[i] < 0:
                big = max(big, abs(x[i]))
            else:
                Ui[unz] = pinv[i]
                Ux[unz] = x[i]
                unz += 1
        if not (big > SINGULAR_RTOL * colmax) or not np.isfinite(big):
            for px in range(top, m):
                x[xi[px]] = 0.0
            return False, Lp, Li, Lx, Up, Ui, Ux, pinv, q
        ipiv = -1
        best = 1 << 62
        r = prefer[k]
        if r >= 0 and pinv[r] < 0 and abs(x[r]) >= threshold * big:
            best = -1  # (the triangular part's own row: no fill)
            ipiv = r
        for px in range(top, m):
            i = xi[px]
            if pinv[i] < 0 and abs(x[i]) >= threshold * big and rowcnt[i] < best:
                best = rowcnt[i]
                ipiv = i
        piv = x[ipiv]
        Ui[unz] = k
        Ux[unz] = piv
        unz += 1
        pinv[ipiv] = k
        Li[lnz] = ipiv
        Lx[lnz] = 1.0
        lnz += 1
        for px in range(top, m):
            i = xi[px]
            if pinv[i] < 0:
                Li[lnz] = i
                Lx[lnz] = x[i] / piv
                lnz += 1
            x[i] = 0.0
    Lp[m] = lnz
    Up[m] = unz
    for p in range(lnz):  # L's rows in pivot order
        Li[p] = pinv[Li[p]]
    return True, Lp, Li[:lnz], Lx[:lnz], Up, Ui[:unz], Ux[:unz], pinv, q


@njit(cache=True)
def lu_solve(Lp, Li, Lx, Up, Ui, Ux, pinv, q, b, out):
    """``out = B^-1 b`` from :func:`lu_factor` (``out[k]`` multiplies ``cols[k]``)."""
    m = b.size
    x = np.empty(m)
    for i in range(m):  # x = P b
        x[pinv[i]] = b[i]
    # (the triangular steps written out here and in lu_solve_sparse: as a shared compiled
    # helper they cost 3-5x, 46 -> 159-230 us on a 2295-row basis)
    for j in range(m):  # L x = x (unit diagonal first)
        xj = x[j]
        if xj != 0.0:
            for p in range(Lp[j] + 1, Lp[j + 1]):
                x[Li[p]] -= Lx[p] * xj
    for j in range(m - 1, -1, -1):  # U x = x (diagonal last)
        d = Up[j + 1] - 1
        x[j] /= Ux[d]
        xj = x[j]
        if xj != 0.0:
            for p in range(Up[j], d):
                x[Ui[p]] -= Ux[p] * xj
    for k in range(m):  # out = Q x
        out[q[k]] = x[k]


@njit(cache=True)
def lu_solve_transposed(Lp, Li, Lx, Up, Ui, Ux, pinv, q, c, out):
    """``out = B^-T c`` from :func:`lu_factor` (``c[k]`` belongs to ``cols[k]``)."""
    m = c.size
    x = np.empty(m)
    for k in range(m):  # x = Q^T c
        x[k] = c[q[k]]
    for j in range(m):  # U^T x = x
        s = x[j]
        d = Up[j + 1] - 1
        for p in range(Up[j], d):
            s -= Ux[p] * x[Ui[p]]
        x[j] = s / Ux[d]
    for j in range(m - 1, -1, -1):  # L^T x = x
        s = x[j]
        for p in range(Lp[j] + 1, Lp[j + 1]):
            s -= Lx[p] * x[Li[p]]
        x[j] = s
    for i in range(m):  # out = P^T x
        out[i] = x[pinv[i]]


@njit(cache=True)
def _reach(Gp, Gi, skip_first, skip_last, bi, col_of, xi, pstack, mark, stamp):
    """Nonzero pattern of ``G^-1 b`` for a triangular ``G`` (CSC; its diagonal stored
    first or last, skipped) and the pattern ``bi`` of ``b``: ``xi[top:]`` in topological
    order (CSparse ``cs_reach`` and ``cs_dfs``). Node ``j``'s edges are column
    ``col_of[j]`` of ``G`` (none where it is ``-1``: in :func:`lu_factor`, a row not yet
    pivotal). Returns ``top``."""
    top = xi.size
    for t in range(bi.size):
        j0 = bi[t]
        if mark[j0] == stamp:
            continue
        head = 0
        xi[0] = j0
        while head >= 0:  # (the stack grows up from xi[0], the pattern down from xi[-1])
            j = xi[head]
            J = col_of[j]
            if mark[j] != stamp:
                mark[j] = stamp
                pstack[head] = 0 if J < 0 else Gp[J] + (1 if skip_first else 0)
            done = True
            pend = 0 if J < 0 else Gp[J + 1] - (1 if skip_last else 0)
            p = pstack[head]
            while p < pend:
                i = Gi[p]
                if mark[i] != stamp:
                    pstack[head] = p + 1
                    head += 1
                    xi[head] = i
                    done = False
                    break
                p += 1
            if done:
                head -= 1
                top -= 1
                xi[top] = j
    return top


@njit(cache=True)
def lu_solve_sparse(Lp, Li, Lx, Up, Ui, Ux, pinv, bi, bx, x, xi, pstack, mark, stamp, ident):
    """``z = U^-1 L^-1 P b`` for a sparse ``b`` (rows ``bi``, values ``bx``), by the two
    triangular solves over their reach only. ``x`` (length ``m``) must be zero on entry;
    on return ``x[xi[top:]]`` holds ``z`` on its pattern (pivot order: ``B^-1 b`` is
    ``Q z``), which the caller zeroes again; ``mark`` uses ``stamp`` and ``stamp + 1``;
    ``ident`` is ``arange(m)``. Returns ``top``."""
    m = x.size
    nb = bi.size
    pb = np.empty(nb, np.int64)
    for t in range(nb):
        pb[t] = pinv[bi[t]]
        x[pb[t]] = bx[t]
    top = _reach(Lp, Li, True, False, pb, ident, xi, pstack, mark, stamp)
    for px in range(top, m):
        j = xi[px]
        xj = x[j]
        if xj != 0.0:
            for p in range(Lp[j] + 1, Lp[j + 1]):
                x[Li[p]] -= Lx[p] * xj
    pat = xi[top:].copy()
    top = _reach(Up, Ui, False, True, pat, ident, xi, pstack, mark, stamp + 1)
    for px in range(top, m):
        j = xi[px]
        d = Up[j + 1] - 1
        x[j] /= Ux[d]
        xj = x[j]
        if xj != 0.0:
            for p in range(Up[j], d):
                x[Ui[p]] -= Ux[p] * xj
    return top


@njit(cache=True)
def ftran_columns(Lp, Li, Lx, Up, Ui, Ux, pinv, indptr, indices, data, qs):
    """:func:`lu_solve_sparse` of the columns ``qs`` of ``A`` one after another (a
    simplex's ``B^-1 a_q``, timed as a batch): the total size of the results' patterns."""
    m = pinv.size
    x = np.zeros(m)
    xi = np.empty(m, np.int64)
    pstack = np.empty(m, np.int64)
    mark = np.zeros(m, np.int64)
    ident = np.arange(m)
    total = 0
    for t in range(qs.size):
        c = qs[t]
        top = lu_solve_sparse(Lp, Li, Lx, Up, Ui, Ux, pinv, indices[indptr[c]:indptr[c + 1]],
                              data[indptr[c]:indptr[c + 1]], x, xi, pstack, mark, 2 * t + 1,
                              ident)
        total += m - top
        for px in range(top, m):
            x[xi[px]] = 0.0
    return total
