"""Independent oracles for the SMFDO tests: an exact rational LP and the whole-history LP.

Nothing here imports setobs. :func:`exact_lp_min` solves a small LP exactly
(``fractions.Fraction``, two-phase dense simplex with Bland's rule), so that
"does the certified bound contain the optimum, and how close is it" is decided
without floating point. :func:`history_lp` builds the whole-history LP of the
SMFDO in the *original* coordinates: variables ``x_0``, ``d_0`` and every
increment, the system matrices and the data taken as the exact rationals they
are in floating point.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction

import numpy as np


def _F(v: float) -> Fraction:
    return Fraction(float(v))


def _gauss_jordan_step(rows: list[list[Fraction]], r: int, q: int) -> None:
    """In place: scale row ``r`` so that ``rows[r][q] = 1`` and clear column ``q`` elsewhere."""
    pv = rows[r][q]
    rows[r] = [v / pv for v in rows[r]]
    for i in range(len(rows)):
        if i != r and rows[i][q] != 0:
            f = rows[i][q]
            rows[i] = [a - f * b for a, b in zip(rows[i], rows[r], strict=True)]


def exact_lp_min(c: Sequence[Fraction], A: Sequence[Sequence[Fraction]], b: Sequence[Fraction],
                 lo: Sequence[Fraction | None], hi: Sequence[Fraction | None]
                 ) -> Fraction | None:
    """Exact ``min c^T x`` s.t. ``A x = b``, ``lo <= x <= hi`` (``None``: no bound).

    Returns the optimum, or ``None`` if the LP is unbounded below. Raises
    ``ValueError`` if it is infeasible. Variables are shifted and split into
    nonnegative parts (standard form); phase 1 uses one artificial per row.
    """
    n = len(c)
    # x = lo + s (s >= 0, s <= hi - lo) or x = hi - s, or x = s+ - s- (free)
    cols: list[tuple[int, Fraction]] = []  # (original var, sign) per standard column
    const = [Fraction(0)] * n
    ub_rows: list[tuple[int, Fraction]] = []  # (standard column, upper bound)
    for j in range(n):
        if lo[j] is not None:
            const[j] = lo[j]
            cols.append((j, Fraction(1)))
            if hi[j] is not None:
                ub_rows.append((len(cols) - 1, hi[j] - lo[j]))
        elif hi[j] is not None:
            const[j] = hi[j]
            cols.append((j, Fraction(-1)))
        else:
            cols.append((j, Fraction(1)))
            cols.append((j, Fraction(-1)))
    m0 = len(b)
    ns = len(cols)
    n_slack = len(ub_rows)
    N = ns + n_slack
    rows: list[list[Fraction]] = []
    rhs: list[Fraction] = []
    for i in range(m0):
        row = [A[i][j] * sg for (j, sg) in cols] + [Fraction(0)] * n_slack
        rows.append(row)
        rhs.append(b[i] - sum(A[i][j] * const[j] for j in range(n)))
    for t, (col, ub) in enumerate(ub_rows):
        row = [Fraction(0)] * N
        row[col] = Fraction(1)
        row[ns + t] = Fraction(1)
        rows.append(row)
        rhs.append(ub)
    cost = [c[j] * sg for (j, sg) in cols] + [Fraction(0)] * n_slack
    m = len(rows)
    for i in range(m):
        if rhs[i] < 0:
            rows[i] = [-v for v in rows[i]]
            rhs[i] = -rhs[i]
    # tableau with artificials
    T = [rows[i] + [Fraction(1) if k == i else Fraction(0) for k in range(m)] + [rhs[i]]
         for i in range(m)]
    basis = [N + i for i in range(m)]
    total = N + m

    def pivot(r: int, q: int) -> None:
        _gauss_jordan_step(T, r, q)
        basis[r] = q

    def simplex(obj: list[Fraction], allowed: int) -> bool:
        """Minimise obj over the tableau; False if unbounded (Bland's rule)."""
        while True:
            red = []
            for j in range(allowed):
                if j in basis:
                    continue
                rc = obj[j] - sum(obj[basis[i]] * T[i][j] for i in range(m))
                if rc < 0:
                    red.append(j)
            if not red:
                return True
            q = min(red)
            best = None
            for i in range(m):
                if T[i][q] > 0:
                    ratio = T[i][-1] / T[i][q]
                    if best is None or ratio < best[0] or (ratio == best[0]
                                                            and basis[i] < basis[best[1]]):
                        best = (ratio, i)
            if best is None:
                return False
            pivot(best[1], q)

    phase1 = [Fraction(0)] * N + [Fraction(1)] * m
    simplex(phase1, total)
    if sum(T[i][-1] for i in range(m) if basis[i] >= N) != 0:
        raise ValueError("infeasible LP")
    # drive artificials out of the basis where possible
    for i in range(m):
        if basis[i] >= N:
            for j in range(N):
                if T[i][j] != 0:
                    pivot(i, j)
                    break
    obj = cost + [Fraction(0)] * m
    # forbid artificials: remove their columns from consideration
    if not simplex(obj, N):
        return None
    val = sum(cost[basis[i]] * T[i][-1] for i in range(m) if basis[i] < N)
    return val + sum(c[j] * const[j] for j in range(n))


def history_lp(Phi, G, Xi, Y, U, Gamma, r_inc, k, x_box=None, d_box=None, y_rtol=0.0,
               noise_w=None, noise_v=None, Du=None):
    """The whole-history LP of ``d_k`` in exact rationals (original coordinates).

    Variables ``v = (x_0, d_0, dd_0 .. dd_(k-1), w_0 .. w_(k-1), nu_0 .. nu_k, e)``;
    ``x_(j+1) = Phi x_j + Gamma u_j + G d_j + E w_j``, ``d_(j+1) = d_j + dd_j``,
    ``Xi x_j + F nu_j = y_j - Du u_j + e_j`` on the measured (non-NaN) entries of
    ``y_j``, with ``|e| <= y_rtol |y|`` (the data's representation error; ``0``:
    exact data), ``|dd_j| <= r_inc``, ``noise_w = (E, r_w)``: ``|w_j| <= r_w``,
    ``noise_v = (F, r_v)``: ``|nu_j| <= r_v``; ``x_box``/``d_box``: optional
    ``(lo, hi)`` for ``x_0``/``d_0``.

    Returns ``(A, b, lo, hi, Md)`` with ``d_k = Md v``.
    """
    Phi_f = [[_F(v) for v in row] for row in np.atleast_2d(Phi)]
    G_f = [[_F(v) for v in row] for row in np.atleast_2d(G)]
    Xi_f = [[_F(v) for v in row] for row in np.atleast_2d(Xi)]
    n, q = len(Phi_f), len(G_f[0])
    E_f = [[_F(v) for v in row] for row in np.atleast_2d(noise_w[0])] if noise_w else None
    F_f = [[_F(v) for v in row] for row in np.atleast_2d(noise_v[0])] if noise_v else None
    nw = len(E_f[0]) if E_f else 0
    nvv = len(F_f[0]) if F_f else 0
    w0 = n + q + k * q
    v0 = w0 + k * nw
    nv = v0 + (k + 1) * nvv
    # x_j = Mx v + ox, d_j = Md v (rows as Fraction lists)
    Mx = [[Fraction(int(i == j)) for j in range(nv)] for i in range(n)]
    ox = [Fraction(0)] * n
    Md = [[Fraction(int(j == n + i)) for j in range(nv)] for i in range(q)]
    A, b, yvals = [], [], []
    for j in range(k + 1):
        for i in range(len(Xi_f)):
            if np.isnan(Y[j][i]):
                continue
            row = [sum(Xi_f[i][t] * Mx[t][col] for t in range(n)) for col in range(nv)]
            for t in range(nvv):
                row[v0 + j * nvv + t] += F_f[i][t]
            A.append(row)
            yj = _F(Y[j][i])
            if Du is not None:
                yj -= sum(_F(Du[i][t]) * _F(U[j][t]) for t in range(len(Du[0])))
            b.append(yj - sum(Xi_f[i][t] * ox[t] for t in range(n)))
            yvals.append(_F(Y[j][i]))
        if j == k:
            break
        newMx = [[sum(Phi_f[i][t] * Mx[t][col] for t in range(n))
                  + sum(G_f[i][t] * Md[t][col] for t in range(q)) for col in range(nv)]
                 for i in range(n)]
        for i in range(n):
            for t in range(nw):
                newMx[i][w0 + j * nw + t] += E_f[i][t]
        newox = [sum(Phi_f[i][t] * ox[t] for t in range(n)) for i in range(n)]
        if U is not None and Gamma is not None and np.size(Gamma):
            Gam_f = [[_F(v) for v in row] for row in np.atleast_2d(Gamma)]
            for i in range(n):
                newox[i] += sum(Gam_f[i][t] * _F(U[j][t]) for t in range(len(Gam_f[0])))
        Mx, ox = newMx, newox
        Md = [row[:] for row in Md]
        for i in range(q):
            Md[i][n + q + j * q + i] += 1
    lo: list[Fraction | None] = []
    hi: list[Fraction | None] = []
    for i in range(n):
        lo.append(None if x_box is None else _F(x_box[0][i]))
        hi.append(None if x_box is None else _F(x_box[1][i]))
    for i in range(q):
        lo.append(None if d_box is None else _F(d_box[0][i]))
        hi.append(None if d_box is None else _F(d_box[1][i]))
    for _ in range(k):
        for i in range(q):
            lo.append(-_F(r_inc[i]))
            hi.append(_F(r_inc[i]))
    for _ in range(k):
        for t in range(nw):
            lo.append(-_F(noise_w[1][t]))
            hi.append(_F(noise_w[1][t]))
    for _ in range(k + 1):
        for t in range(nvv):
            lo.append(-_F(noise_v[1][t]))
            hi.append(_F(noise_v[1][t]))
    # ox enters b: Xi x_j = y_j  ->  Xi Mx v = y_j - Xi ox  (already in b)
    if y_rtol:
        rho = _F(y_rtol)
        ne = len(A)
        for i in range(ne):
            A[i] = A[i] + [Fraction(-1) if t == i else Fraction(0) for t in range(ne)]
            lo.append(-rho * abs(yvals[i]))
            hi.append(rho * abs(yvals[i]))
        Md = [row + [Fraction(0)] * ne for row in Md]
    return A, b, lo, hi, Md


def exact_history_bounds(Phi, G, Xi, Y, k, r_inc, U=None, Gamma=None, x_box=None, d_box=None,
                         y_rtol=0.0, noise_w=None, noise_v=None, Du=None):
    """Exact ``(lo, hi)`` of each ``d_k`` component over the whole history (Fractions);
    see :func:`history_lp` for the noise and missing-sample arguments."""
    A, b, lo, hi, Md = history_lp(Phi, G, Xi, Y, U, Gamma, r_inc, k, x_box, d_box, y_rtol,
                                  noise_w, noise_v, Du)
    out_lo, out_hi = [], []
    for row in Md:
        mn = exact_lp_min(row, A, b, lo, hi)
        mx = exact_lp_min([-v for v in row], A, b, lo, hi)
        out_lo.append(mn)
        out_hi.append(None if mx is None else -mx)
    return out_lo, out_hi


def solve_exact(M: list[list[Fraction]], r: list[Fraction]) -> list[Fraction] | None:
    """Solve a square system exactly (Gauss-Jordan); ``None`` if singular."""
    n = len(M)
    aug = [[*row, r[i]] for i, row in enumerate(M)]
    for col in range(n):
        piv = next((i for i in range(col, n) if aug[i][col] != 0), None)
        if piv is None:
            return None
        aug[col], aug[piv] = aug[piv], aug[col]
        _gauss_jordan_step(aug, col, col)
    return [aug[i][n] for i in range(n)]


def exact_hpolytope_vertices(H: np.ndarray, k: np.ndarray) -> list[list[Fraction]]:
    """Exact vertices of the full-dimensional polytope ``{x : H x <= k}`` (Fractions).

    Candidates come from scipy's ``HalfspaceIntersection`` (floating point); each
    is made exact by solving its ``n`` nearest-active facets in rational
    arithmetic, and kept only if it satisfies every inequality exactly and has
    ``n`` linearly independent active facets (a vertex by definition). Near-
    degenerate candidates that fail are re-tried with other active sets.
    """
    from itertools import combinations

    from scipy.optimize import linprog
    from scipy.spatial import HalfspaceIntersection

    n = H.shape[1]
    nrm = np.linalg.norm(H, axis=1)
    res = linprog(np.r_[np.zeros(n), -1.0], A_ub=np.hstack([H, nrm[:, None]]), b_ub=k,
                  bounds=[(None, None)] * n + [(0, None)], method="highs")
    cand = HalfspaceIntersection(np.hstack([H, -k[:, None]]), res.x[:n]).intersections
    Hf = [[Fraction(float(v)) for v in row] for row in H]
    kf = [Fraction(float(v)) for v in k]
    out: dict[tuple, list[Fraction]] = {}
    for v in cand:
        resid = np.abs(H @ v - k) / nrm
        near = list(np.argsort(resid)[: n + 3])
        for act in combinations(near, n):
            x = solve_exact([Hf[i] for i in act], [kf[i] for i in act])
            if x is None:
                continue
            slack = [kf[i] - sum(Hf[i][j] * x[j] for j in range(n)) for i in range(len(kf))]
            if min(slack) < 0:
                continue
            out[tuple(x)] = x
            break
    return list(out.values())


def history_lp_highs(Phi, G, Xi, Y, k, r_inc, U=None, Gamma=None, x_box=None, d_box=None,
                     noise_w=None, noise_v=None, Du=None, r_inc_set=None, y_rtol=0.0,
                     states=False, unscaled=False):
    """``(lo, hi)`` of ``d_k`` (``states``: of ``x_k``) over the whole history by a
    sparse float LP (HiGHS).

    For long horizons where :func:`exact_history_bounds` is too slow. Every
    state is a variable (``x_0 .. x_k``, ``d_0 .. d_k``, the increments and the
    noise), so no power of ``Phi`` is formed: ``x_(j+1) = Phi x_j + Gamma u_j +
    G d_j + E w_j``, ``d_(j+1) = d_j + dd_j``, ``Xi x_j + F nu_j = y_j - Du u_j``
    on the measured (non-NaN) entries; ``|dd_j| <= r_inc`` or, with
    ``r_inc_set = (H, h)``, ``H dd_j <= h``; ``noise_w = (E, r_w)``,
    ``noise_v = (F, r_v)`` boxes; ``x_box``, ``d_box``: optional ``(lo, hi)``;
    ``y_rtol``: each measurement is known to ``y_rtol |y|`` (a slack per row; the
    float simulation's data are consistent only up to their rounding).
    Tight solver tolerances (1e-10); the optimum is a float, not certified.
    ``unscaled``: each LP on a fresh ``highspy`` model with HiGHS's scaling off, by the
    dual simplex (through ``linprog`` HiGHS scales, and on the 30-tank cascade's history
    its cold solves took more than 15 minutes at ``k`` = 40).
    """
    import scipy.sparse as sp
    from scipy.optimize import linprog

    Phi, G, Xi = (np.atleast_2d(np.asarray(M, float)) for M in (Phi, G, Xi))
    n, q = Phi.shape[0], G.shape[1]
    E, r_w = (None, None) if noise_w is None else (np.atleast_2d(noise_w[0]), noise_w[1])
    F, r_v = (None, None) if noise_v is None else (np.atleast_2d(noise_v[0]), noise_v[1])
    nw = 0 if E is None else E.shape[1]
    nv = 0 if F is None else F.shape[1]
    ix = lambda j: j * n  # noqa: E731
    o_d = (k + 1) * n
    idd = lambda j: o_d + j * q  # noqa: E731
    o_dd = o_d + (k + 1) * q
    o_w = o_dd + k * q
    o_v = o_w + k * nw
    o_e = o_v + (k + 1) * nv
    n_meas = int(sum((~np.isnan(Y[j])).sum() for j in range(k + 1))) if y_rtol else 0
    nvar = o_e + n_meas
    e_bounds = []
    rows, cols, vals, rhs = [], [], [], []
    r = 0

    def put(i, js, M):
        M = np.atleast_2d(M)
        for a in range(M.shape[0]):
            for b in range(M.shape[1]):
                if M[a, b] != 0.0:
                    rows.append(i + a)
                    cols.append(js + b)
                    vals.append(M[a, b])

    for j in range(k):
        put(r, ix(j + 1), np.eye(n))
        put(r, ix(j), -Phi)
        put(r, idd(j), -G)
        if nw:
            put(r, o_w + j * nw, -E)
        u = np.zeros(n) if U is None or Gamma is None else np.asarray(Gamma) @ U[j]
        rhs.extend(u)
        r += n
        put(r, idd(j + 1), np.eye(q))
        put(r, idd(j), -np.eye(q))
        put(r, o_dd + j * q, -np.eye(q))
        rhs.extend(np.zeros(q))
        r += q
    for j in range(k + 1):
        m = ~np.isnan(Y[j])
        for i in np.flatnonzero(m):
            put(r, ix(j), Xi[i:i + 1])
            if nv:
                put(r, o_v + j * nv, F[i:i + 1])
            yv = Y[j][i] - (0.0 if Du is None else float(np.asarray(Du)[i] @ U[j]))
            if y_rtol:
                put(r, o_e + len(e_bounds), -np.ones((1, 1)))
                e_bounds.append(y_rtol * abs(Y[j][i]))
            rhs.append(yv)
            r += 1
    A_eq = sp.csr_array((vals, (rows, cols)), shape=(r, nvar))
    bounds = [(None, None)] * nvar
    if x_box is not None:
        for i in range(n):
            bounds[ix(0) + i] = (x_box[0][i], x_box[1][i])
    if d_box is not None:
        for i in range(q):
            bounds[idd(0) + i] = (d_box[0][i], d_box[1][i])
    A_ub = b_ub = None
    if r_inc_set is None:
        rr = np.broadcast_to(np.asarray(r_inc, float), (q,))
        for j in range(k):
            for i in range(q):
                bounds[o_dd + j * q + i] = (-rr[i], rr[i])
    else:
        Hs, hs = np.atleast_2d(r_inc_set[0]), np.asarray(r_inc_set[1], float)
        ur, uc, uv = [], [], []
        for j in range(k):
            for a in range(Hs.shape[0]):
                for b in range(q):
                    ur.append(j * Hs.shape[0] + a)
                    uc.append(o_dd + j * q + b)
                    uv.append(Hs[a, b])
        A_ub = sp.csr_array((uv, (ur, uc)), shape=(k * Hs.shape[0], nvar))
        b_ub = np.tile(hs, k)
    for j in range(k):
        for i in range(nw):
            bounds[o_w + j * nw + i] = (-r_w[i], r_w[i])
    for j in range(k + 1):
        for i in range(nv):
            bounds[o_v + j * nv + i] = (-r_v[i], r_v[i])
    for t, eb in enumerate(e_bounds):
        bounds[o_e + t] = (-eb, eb)
    opts = {"primal_feasibility_tolerance": 1e-10, "dual_feasibility_tolerance": 1e-10}
    first, count = (ix(k), n) if states else (idd(k), q)
    if unscaled:
        return _history_unscaled(A_eq, np.asarray(rhs), A_ub, b_ub, bounds, first, count,
                                 opts)
    lo, hi = np.empty(count), np.empty(count)
    for i in range(count):
        for sgn in (1.0, -1.0):
            cst = np.zeros(nvar)
            cst[first + i] = sgn
            # (HiGHS's default can end "Not Set" on long, ill-scaled chains: the dual
            # simplex, then the interior point with crossover, are tried before giving up)
            for method in ("highs", "highs-ds", "highs-ipm"):
                res = linprog(cst, A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=np.asarray(rhs),
                              bounds=bounds, method=method, options=opts)
                if res.status in (0, 2, 3):
                    break
            if res.status == 3:
                val = -np.inf if sgn > 0 else np.inf
            elif res.status != 0:
                raise RuntimeError(f"HiGHS: {res.message}")
            else:
                val = res.fun if sgn > 0 else -res.fun
            if sgn > 0:
                lo[i] = val
            else:
                hi[i] = val
    return lo, hi


def _history_unscaled(A_eq, b_eq, A_ub, b_ub, bounds, first, count, opts):
    """:func:`history_lp_highs`'s bounds by ``highspy`` directly: a fresh model per LP,
    HiGHS's scaling off, the dual simplex, the options ``opts``."""
    import highspy
    import scipy.sparse as sp

    M = sp.csr_array(A_eq if A_ub is None else sp.vstack([A_eq, A_ub]))
    starts, index = M.indptr[:-1].astype(np.int32), M.indices.astype(np.int32)
    every = np.arange(M.shape[1], dtype=np.int32)
    rlo = np.r_[b_eq, np.full(0 if A_ub is None else A_ub.shape[0], -np.inf)]
    rhi = np.r_[b_eq, [] if A_ub is None else b_ub]
    clo = np.array([-np.inf if b[0] is None else b[0] for b in bounds], dtype=float)
    chi = np.array([np.inf if b[1] is None else b[1] for b in bounds], dtype=float)
    lo, hi = np.empty(count), np.empty(count)
    for i in range(count):
        for sgn in (1.0, -1.0):
            h = highspy.Highs()
            h.setOptionValue("output_flag", False)
            h.setOptionValue("simplex_scale_strategy", 0)
            h.setOptionValue("simplex_strategy", 1)
            for key, val in opts.items():
                h.setOptionValue(key, val)
            cost = np.zeros(M.shape[1])
            cost[first + i] = sgn
            h.passModel(highspy.HighsLp())
            h.addVars(M.shape[1], clo, chi)
            h.changeColsCost(M.shape[1], every, cost)
            h.addRows(M.shape[0], rlo, rhi, M.nnz, starts, index, M.data)
            h.run()
            status = h.getModelStatus()
            if status == highspy.HighsModelStatus.kUnbounded:
                val = -np.inf
            elif status != highspy.HighsModelStatus.kOptimal:
                raise RuntimeError(f"HiGHS: {h.modelStatusToString(status)}")
            else:
                val = h.getInfo().objective_function_value
            if sgn > 0:
                lo[i] = val
            else:
                hi[i] = -val
    return lo, hi


def noisy_record(A, B, C, U, rw, rv, rng):
    """Simulate ``x+ = A x + B u + w``, ``y = C x + v`` from ``x_0`` uniform in
    ``[-1, 1]^n``, with ``w`` and ``v`` uniform in ``[-rw, rw]`` and ``[-rv, rv]``
    (drawn in that order: ``x_0``, then ``v_k``, ``w_k`` per step): states and
    measurements ``(X, Y)``."""
    n, l = A.shape[0], C.shape[0]
    x = rng.uniform(-1, 1, n)
    X, Y = [], []
    for k in range(len(U)):
        X.append(x.copy())
        Y.append(C @ x + rng.uniform(-rv, rv, l))
        x = A @ x + B @ U[k] + rng.uniform(-rw, rw, n)
    return np.array(X), np.array(Y)


def state_history_lp(A, B, C, Y, U, k, rw, rvs, box):
    """``(A_eq, b_eq, bounds, ix)`` of the whole-history LP of the state ``x_k`` of
    ``x_(j+1) = A x_j + B u_j + w_j``, ``y_j = C x_j + v_j``, ``|w| <= rw``,
    ``|v_j| <= rvs[j]`` (or a scalar ``rvs``), ``x_0`` in the box ``(lo, hi)``:
    every state and noise sample a variable (scipy.sparse); ``x_k`` is
    ``x[ix : ix + n]``. Measurements are all taken (no NaN)."""
    import scipy.sparse as sp

    n, l = A.shape[0], C.shape[0]
    rvs = np.broadcast_to(np.asarray(rvs, dtype=float), (k + 1,))
    nx, nw, nv = (k + 1) * n, k * n, (k + 1) * l
    rows, cols, vals, rhs = [], [], [], []
    r = 0
    for j in range(k):  # x_(j+1) - A x_j - w_j = B u_j
        for a in range(n):
            rows += [r] * (n + 2)
            cols += [(j + 1) * n + a, *range(j * n, j * n + n), nx + j * n + a]
            vals += [1.0, *(-A[a]), -1.0]
            rhs.append(float(B[a] @ U[j]))
            r += 1
    for j in range(k + 1):  # C x_j + v_j = y_j
        for i in range(l):
            rows += [r] * (n + 1)
            cols += [*range(j * n, j * n + n), nx + nw + j * l + i]
            vals += [*C[i], 1.0]
            rhs.append(float(Y[j, i]))
            r += 1
    A_eq = sp.csr_array((vals, (rows, cols)), shape=(r, nx + nw + nv))
    bounds = [(float(box[0][a]), float(box[1][a])) for a in range(n)] + \
        [(None, None)] * (nx - n) + [(-rw, rw)] * nw + \
        [(-rvs[j], rvs[j]) for j in range(k + 1) for _ in range(l)]
    return A_eq, np.array(rhs), bounds, k * n


def solve_state_history_lp(A_eq, b_eq, bounds, ix, n):
    """``(lo, hi, times)``: the optima of the ``2 n`` LPs of :func:`state_history_lp`
    (scipy's HiGHS from scratch, tolerances 1e-10) and each solve's time."""
    import time

    from scipy.optimize import linprog

    times, lo, hi = [], np.empty(n), np.empty(n)
    for a in range(n):
        for sg, out in ((1.0, lo), (-1.0, hi)):
            c = np.zeros(A_eq.shape[1])
            c[ix + a] = sg
            t0 = time.perf_counter()
            res = linprog(c, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs",
                          options={"primal_feasibility_tolerance": 1e-10,
                                   "dual_feasibility_tolerance": 1e-10})
            times.append(time.perf_counter() - t0)
            if res.status != 0:
                raise RuntimeError(f"HiGHS: {res.message}")
            out[a] = sg * res.fun
    return lo, hi, times


def slab_lp_extremes(M, A, b, tol, bounds):
    """Min and max of each row of ``M v`` over ``|A v - b| <= tol`` with the variable
    ``bounds`` (scipy's HiGHS; a failed solve fails the test)."""
    from scipy.optimize import linprog

    A_ub, b_ub = np.vstack([A, -A]), np.r_[b + tol, tol - b]
    lo, hi = np.empty(M.shape[0]), np.empty(M.shape[0])
    for i in range(M.shape[0]):
        for sgn in (1.0, -1.0):
            r = linprog(sgn * M[i], A_ub=A_ub, b_ub=b_ub, bounds=bounds, method="highs")
            assert r.status == 0, r.message
            (lo if sgn > 0 else hi)[i] = sgn * r.fun
    return lo, hi


def outward_sum_cases(seed: int, n: int = 200):
    """Random ``c`` (magnitudes 1e-8 to 1e8), centre errors ``e`` (half of them zero),
    offsets ``low <= 0 <= upp``; three ``low`` are ``-inf`` and two ``upp`` ``+inf``."""
    rng = np.random.default_rng(seed)
    c = rng.normal(size=n) * 10.0 ** rng.integers(-8, 8, n)
    e = np.where(rng.random(n) < 0.5, 0.0, np.abs(c) * 1e-15)
    low = -np.abs(rng.normal(size=n)) * 10.0 ** rng.integers(-8, 8, n)
    upp = np.abs(rng.normal(size=n))
    low[:3], upp[3:5] = -np.inf, np.inf
    return c, e, low, upp


def assert_outward_sums(lo, hi, c, e, low, upp) -> None:
    """``[lo, hi]`` contains ``[c - e + low, c + e + upp]`` in exact rational arithmetic
    (and is infinite exactly where the offset is)."""
    for i in range(len(c)):
        if np.isfinite(low[i]):
            assert Fraction(lo[i]) <= Fraction(c[i]) - Fraction(e[i]) + Fraction(low[i])
        else:
            assert lo[i] == -np.inf
        if np.isfinite(upp[i]):
            assert Fraction(hi[i]) >= Fraction(c[i]) + Fraction(e[i]) + Fraction(upp[i])
        else:
            assert hi[i] == np.inf


def assert_box_covers(c, r, lo, hi) -> None:
    """``[c - r, c + r]`` contains ``[lo, hi]`` in exact rational arithmetic."""
    for i in range(len(c)):
        assert Fraction(c[i]) - Fraction(r[i]) <= Fraction(lo[i])
        assert Fraction(c[i]) + Fraction(r[i]) >= Fraction(hi[i])


def nonlinear_inner_bounds(F, H, X0, rw, rv, Y, U, X, k, states, shrink=0.999):
    """An *inner* bound of the exact state set at step ``k`` of ``x+ = F(x, u) + w``,
    ``y = H(x, u) + v`` (``|w| <= rw``, ``|v| <= rv``, ``x_0`` in the box ``X0 = (lo,
    hi)``): for each state ``i`` in ``states``, histories that minimize and maximize
    ``x_k[i]`` (SLSQP over ``x_0`` and ``w_0 .. w_(k-1)``, single shooting, started
    from the true history ``X``), kept only when feasible for the unshrunk bounds (the
    optimizer works on bounds shrunk by ``shrink`` so that its answer is strictly
    feasible). Every value returned is attained by a history consistent with the data,
    so ``[lo, hi]`` lies inside the exact set's hull (the truth's ``X[k]`` where no
    better feasible point was found)."""
    from scipy.optimize import minimize

    n = len(X0[0])
    lo_b = np.concatenate([X0[0], np.full(k * n, -rw * shrink)])
    hi_b = np.concatenate([X0[1], np.full(k * n, rw * shrink)])

    def traj(z):
        x = z[:n]
        ws = z[n:].reshape(k, n)
        out = [x]
        for j in range(k):
            x = F(x, U[j]) + ws[j]
            out.append(x)
        return out

    def slack(z, s):
        xs = traj(z)
        r = np.concatenate([Y[j] - H(xs[j], U[j]) for j in range(k + 1)])
        return np.concatenate([s * rv - r, s * rv + r])

    z0 = np.concatenate([X[0], (X[1:k + 1] - np.array([F(X[j], U[j]) for j in range(k)]))
                         .ravel()])
    lo, hi = X[k].copy(), X[k].copy()
    for i in states:
        for sgn in (1.0, -1.0):
            res = minimize(lambda z, i=i, sgn=sgn: -sgn * traj(z)[k][i], np.clip(z0, lo_b, hi_b),
                           method="SLSQP", bounds=list(zip(lo_b, hi_b, strict=True)),
                           constraints=[{"type": "ineq", "fun": lambda z: slack(z, shrink)}],
                           options={"maxiter": 300, "ftol": 1e-12})
            z = np.clip(res.x, lo_b, hi_b)
            if slack(z, 1.0).min() >= 0.0 and np.all(np.abs(z[n:]) <= rw):
                v = traj(z)[k][i]
                lo[i], hi[i] = min(lo[i], v), max(hi[i], v)
    return lo, hi


def nonlinear_inner_bounds_ms(F, H, X0, rw, rv, Y, U, X, k, states, shrink=0.999,
                              starts=2, seed=0, maxiter=400):
    """An *inner* bound of the exact state set at step ``k`` of ``x+ = F(x, u) + w``,
    ``y = H(x, u) + v`` (``|w| <= rw``, ``|v| <= rv`` elementwise; ``x_0`` in ``X0``, a
    box ``(lo, hi)`` or a zonotope ``("zonotope", c, G)`` of ``c + G xi``, ``|xi| <= 1``),
    by *multiple* shooting: SLSQP over ``x_0``'s parameters and ``x_1 .. x_k``, with the
    process and measurement bounds as inequality constraints (shrunk by ``shrink`` so the
    optimizer's answer is strictly feasible; Jacobians by central differences, block by
    block), minimising and maximising ``x_k[i]`` for ``i`` in ``states``, from the true
    history and from ``starts - 1`` others (the truth with its noise redrawn). A value is
    kept only when its history is feasible for the unshrunk bounds, checked in floating
    point from the optimizer's states (``w_j = x_(j+1) - F(x_j, u_j)``, ``v_j = y_j -
    H(x_j, u_j)``, ``x_0`` in ``X0``): every value returned is attained by a history
    consistent with the data, so ``[lo, hi]`` lies inside the exact set's hull."""
    from scipy.optimize import minimize

    X = np.asarray(X, float)
    Y = np.asarray(Y, float)
    n = X.shape[1]
    rw = np.broadcast_to(np.asarray(rw, float), (n,)).copy()
    rv = np.broadcast_to(np.asarray(rv, float), (Y.shape[1],)).copy()
    if isinstance(X0[0], str):
        c0, G0 = np.asarray(X0[1], float), np.asarray(X0[2], float)
        m = G0.shape[1]
        p_lo, p_hi = -np.ones(m), np.ones(m)
        xi_true = np.linalg.lstsq(G0, X[0] - c0, rcond=None)[0]
    else:
        c0, G0 = np.zeros(n), np.eye(n)
        m = n
        p_lo, p_hi = np.asarray(X0[0], float), np.asarray(X0[1], float)
        xi_true = X[0].copy()
    meas = [np.flatnonzero(~np.isnan(Y[j])) for j in range(k + 1)]

    def states_of(z):
        x0 = c0 + G0 @ z[:m]
        return np.vstack([x0, z[m:].reshape(k, n)])

    def cons(z, s):
        xs = states_of(z)
        w = np.array([xs[j + 1] - F(xs[j], U[j]) for j in range(k)]).reshape(k, n)
        v = [Y[j][meas[j]] - H(xs[j], U[j])[meas[j]] for j in range(k + 1)]
        out = [(s * rw - w).ravel(), (s * rw + w).ravel()]
        for j in range(k + 1):
            out += [s * rv[meas[j]] - v[j], s * rv[meas[j]] + v[j]]
        return np.concatenate(out)

    def jac_block(fun, x, u, eps=1e-7):
        cols = []
        for i in range(n):
            d = np.zeros(n)
            d[i] = eps * max(1.0, abs(x[i]))
            cols.append((fun(x + d, u) - fun(x - d, u)) / (2 * d[i]))
        return np.array(cols).T

    def cons_jac(z, s):
        xs = states_of(z)
        nz = m + k * n
        rows_w = np.zeros((k * n, nz))
        for j in range(k):
            Jf = jac_block(F, xs[j], U[j])
            rows_w[j * n:(j + 1) * n, m + j * n:m + (j + 1) * n] = np.eye(n)
            if j == 0:
                rows_w[:n, :m] = -Jf @ G0
            else:
                rows_w[j * n:(j + 1) * n, m + (j - 1) * n:m + j * n] = -Jf
        blocks = [-rows_w, rows_w]
        for j in range(k + 1):
            Jh = jac_block(H, xs[j], U[j])[meas[j]]
            r = np.zeros((meas[j].size, nz))
            if j == 0:
                r[:, :m] = -Jh @ G0
            else:
                r[:, m + (j - 1) * n:m + j * n] = -Jh
            blocks += [-r, r]
        return np.vstack(blocks)

    def feasible(z):
        if np.any(z[:m] < p_lo) or np.any(z[:m] > p_hi):
            return False
        return bool(cons(z, 1.0).min() >= 0.0)

    rng = np.random.default_rng(seed)
    inits = [np.concatenate([xi_true, X[1:k + 1].ravel()])]
    for _ in range(starts - 1):
        x = X[0].copy()
        traj = []
        for j in range(k):
            x = F(x, U[j]) + rw * rng.uniform(-1, 1, n)
            traj.append(x)
        inits.append(np.concatenate([xi_true, np.ravel(traj)]))
    bounds = list(zip(np.concatenate([p_lo, np.full(k * n, -np.inf)]),
                      np.concatenate([p_hi, np.full(k * n, np.inf)]), strict=True))
    lo, hi = X[k].copy(), X[k].copy()
    for i in states:
        for sgn in (1.0, -1.0):
            e = np.zeros(m + k * n)
            e[m + (k - 1) * n + i] = -sgn
            for z0 in inits:
                res = minimize(lambda z, e=e: e @ z, z0, jac=lambda z, e=e: e, method="SLSQP",
                               bounds=bounds,
                               constraints=[{"type": "ineq", "fun": lambda z: cons(z, shrink),
                                             "jac": lambda z: cons_jac(z, shrink)}],
                               options={"maxiter": maxiter, "ftol": 1e-12})
                z = res.x.copy()
                z[:m] = np.clip(z[:m], p_lo, p_hi)
                if feasible(z):
                    v = states_of(z)[k][i]
                    lo[i], hi[i] = min(lo[i], v), max(hi[i], v)
    return lo, hi
