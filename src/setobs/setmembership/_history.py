"""Exact mode with noise: the whole-history LP, kept and warm-started from step to step.

With measurement or process noise the exact posterior's complexity grows with
every step (the paper example with a noise box: 44, 107, 264 facets at
``k = 2, 3, 4``), so neither the H-representation recursion (:mod:`._hrep`)
nor the set recursion (dense generators and constraints that grow with ``k``)
keeps its cost. The exact set's interval hull is the whole-history LP, and that
LP is sparse when every state is a variable. :class:`HistoryLP` keeps it in one
HiGHS model: each step *adds* the step's variables and rows, and the hull's
``2 N`` LPs are re-solved from the previous basis (a handful of simplex
iterations each), instead of solving a dense LP of the whole history from
scratch.

The LP
------
From a start step ``k0`` whose posterior ``Z_(k0) = {c + G xi : A xi = b,
|xi| <= h}`` has finite factor bounds (the set recursion's posterior there),
the variables are ``xi``, the states ``z_j`` (``j = k0 .. k``), and per step
the factors ``sigma_j`` of the per-step uncertainty (the increment set
``[[dd]] = {c_D + G_D sigma : A_D sigma = b_D, |sigma| <= h_D}`` and the
process-noise set ``W`` alike) and ``nu_j`` of the measurement-noise set ``V``:

.. math::
   z_{k_0} - G\\xi = c,\\quad A\\xi = b,\\\\
   z_{j+1} - A_o z_j - B_o G_D\\sigma^D_j - E_o G_W\\sigma^W_j
       = \\Gamma_o u_j + B_o c_D + E_o c_W,\\quad A_D\\sigma^D_j = b_D,\\ A_W\\sigma^W_j = b_W,\\\\
   C_{o,m} z_{j+1} + G_{V,m}\\nu_{j+1} = y_{j+1,m} - c_{V,m},\\quad A_V\\nu_{j+1} = b_V,

(eqs. (20)-(21) of the SMFDO with noise, written step by step; ``m`` the
measured rows), every factor in its box, and every state ``z_j`` in the
interval image of the previous step's certified hull (an *implied* bound:
``z_j`` of any history consistent with the data lies in the prior of
``IH(Z_(j-1))``, so the bound leaves the LP's feasible set unchanged; it
makes every variable bounded, which the certificate needs). The LP's
projection on ``z_k`` is the exact posterior ``Z_k``; its optimum in direction
``w`` is the support value of the whole-history LP.

Certificate
-----------
For any row multipliers ``y`` and ``r = w - A^T y`` (weak duality over the
variable box ``[l, u]``),

.. math::  \\min \\{w^\\top x : Ax = b,\\ l \\le x \\le u\\}
           \\ge y^\\top b + \\sum_j \\min(r_j l_j, r_j u_j),

whatever the solver's accuracy. ``r`` is computed in floating point with the
forward error bound ``gamma(k_j + 2) (|w_j| + |A_j|^T |y|)`` of its
``k_j``-term column sums (doubled), which enters as ``err_j max(|l_j|, |u_j|)``;
``y^T b`` is correctly rounded; a right-hand side known only to ``+- b_err``
(the rounding of the products that formed it, the data's representation)
costs ``|y|^T b_err``; the sums' own rounding is bounded by ``gamma`` of their
length and the result rounded down once more. The stored matrices ``A_o``,
``C_o``, ``G_V`` enter as variables' coefficients, without products; the
products ``B_o G_D`` and ``E_o G_W`` carry their rounding into ``b_err``
(times the factor bounds). So a reported bound holds for the stored model and
data; the solver only decides how tight it is (its tolerances are 1e-10).

Anything HiGHS does not solve to optimality (an infeasible LP: data that may
contradict the model; a numerical failure) returns ``None``, and the set
recursion decides the step with its certified emptiness test and retries
(:meth:`HistoryLP.to_cz` gives it the exact posterior).

The model grows by ``N + n_D + n_W + n_V`` columns per step, so the cost per
step grows with the record's length (about linearly); it stays a small
multiple of *one* whole-history LP solved from scratch
(``benchmarks/results/exact_mode.json``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from .._rounding import UNIT_ROUNDOFF, exact_dot, gamma, round_down, round_up
from ..exceptions import InternalError
from ..geometry import ConstrainedZonotope
from ..geometry.zonotope import trusted_cz
from ..tolerances import HISTORY_GAP_RTOL

__all__ = ["HistoryLP"]

highspy = lazy_module("highspy")
sparse = lazy_module("scipy.sparse")

#: Relative widening of the implied bounds of a new state (they only need to
#: contain the prior; a generous margin costs nothing).
_PRIOR_SLACK = 1e-9

_TINY = np.finfo(np.float64).tiny


class HistoryLP:
    """The whole-history LP of exact mode, grown by one step per measurement.

    Parameters
    ----------
    A_o, Gamma_o, C_o : ndarray
        The model in the observer's internal coordinates.
    B_o, E_o : ndarray
        Maps of the increment and of the process noise into ``z`` (``(N, 0)``
        when absent).
    rows : ndarray, shape (m, N)
        Objective rows beyond the coordinates of ``z`` (``P``, the state map).
    data_rtol : float
        Relative uncertainty of the data (inputs and measurements).
    """

    def __init__(self, A_o, Gamma_o, C_o, B_o, E_o, rows, data_rtol: float) -> None:
        self.A_o, self.Gamma_o, self.C_o = A_o, Gamma_o, C_o
        self.B_o, self.E_o = B_o, E_o
        self.N = A_o.shape[0]
        self.objectives = np.vstack([np.eye(self.N), rows]) if rows.shape[0] else np.eye(self.N)
        self.data_rtol = data_rtol
        # columns: bounds; rows: right-hand side, its uncertainty; entries (COO)
        self._lo: list[NDArray[np.float64]] = []
        self._hi: list[NDArray[np.float64]] = []
        self._s: list[NDArray[np.float64]] = []  # (HiGHS's column scales, powers of two)
        self._b: list[NDArray[np.float64]] = []
        self._berr: list[NDArray[np.float64]] = []
        self._ent: list[tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]] = []
        self._n_col = 0
        self._n_row = 0
        self._z = np.zeros(0, dtype=np.int64)  # columns of the newest state
        self.box: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self.steps = 0
        self.retries = 0  # solves that were not optimal with a tight certificate
        self._models: list = []
        self._warm: list[bool] = []
        self._ranged: list[bool] = []
        self._undo: list[tuple] = []
        self._products: dict[int, tuple] = {}
        self._cache = None

    @property
    def state_columns(self) -> NDArray[np.int64]:
        """Indices of the newest state's variables ``z_k`` among the LP's columns."""
        return self._z

    def lp(self):
        """The LP as ``(A, b, b_err, lo, hi)``: ``A x = b`` (a ``scipy.sparse`` array;
        the right-hand side known to ``+- b_err``), ``lo <= x <= hi``."""
        lo, hi, b, berr, A, _, _, _ = self._arrays()
        return A, b, berr, lo, hi

    # ------------------------------------------------------------------ building
    @classmethod
    def start(cls, Z: ConstrainedZonotope, lo: NDArray[np.float64], hi: NDArray[np.float64],
              **kw) -> HistoryLP | None:
        """The LP of the posterior ``Z`` (certified hull ``[lo, hi]``), or ``None`` when
        a factor bound or the hull is infinite."""
        if not (np.isfinite(Z.h).all() and np.isfinite(lo).all() and np.isfinite(hi).all()):
            return None
        H = cls(**kw)
        N, ng = H.N, Z.n_gen
        xi = H._add_cols(-Z.h, Z.h)
        z = H._add_cols(lo, hi)
        # z - G xi = c ; A xi = b
        r0 = H._n_row
        rr = [np.arange(N), np.repeat(np.arange(N), ng)]
        cc = [z, np.tile(xi, N)]
        vv = [np.ones(N), -Z.G.ravel()]
        if Z.n_con:
            rr.append(N + np.repeat(np.arange(Z.n_con), ng))
            cc.append(np.tile(xi, Z.n_con))
            vv.append(Z.A.ravel())
        H._add_rows(r0 + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                    np.concatenate([Z.c, Z.b]), np.concatenate([Z.c_err, Z.b_err]))
        H._z = z
        H.box = (np.asarray(lo, float), np.asarray(hi, float))
        H._undo.clear()
        return H

    def _add_cols(self, lo, hi) -> NDArray[np.int64]:
        lo = np.asarray(lo, dtype=np.float64)
        hi = np.asarray(hi, dtype=np.float64)
        idx = np.arange(self._n_col, self._n_col + lo.size)
        # HiGHS sees x = s xi with s a power of two near the column's half range
        # (exact): its absolute tolerances then apply relative to each variable's
        # range. Unscaled, a noise factor of range 1e-3 violated its bound by 6e-11
        # "within tolerance", and on a thin set that moved the optimum by 4e-8.
        # (At most 2^20 either way: HiGHS drops coefficients below 1e-9, and a
        # column pinned to a width of 1e-11 scaled to unit range lost all of them.)
        half = 0.5 * (hi - lo)
        e = np.clip(np.frexp(np.where(half > 0, half, 1.0))[1], -20, 20)
        s = np.where(np.isfinite(half), np.ldexp(1.0, e), 1.0)
        self._lo.append(lo)
        self._hi.append(hi)
        self._s.append(s)
        self._n_col += lo.size
        self._undo.append(("cols", lo.size))
        for hs in self._models:
            hs.addCols(lo.size, np.zeros(lo.size), lo / s, hi / s, 0,
                       np.zeros(lo.size, np.int32), np.zeros(0, np.int32), np.zeros(0))
        return idx

    def _add_rows(self, r, c, v, b, berr) -> None:
        """Rows ``sum_c v x_c = b`` (``r`` absolute row indices, all new)."""
        keep = v != 0.0
        r, c, v = r[keep], c[keep], v[keep]
        nr = b.size
        self._b.append(np.asarray(b, dtype=np.float64))
        self._berr.append(np.asarray(berr, dtype=np.float64))
        self._ent.append((r, c, v))
        self._undo.append(("rows", nr))
        if self._models and nr:
            order = np.lexsort((c, r))
            r, c, v = r[order], c[order], v[order]
            v = v * np.concatenate(self._s)[c]
            starts = np.searchsorted(r, self._n_row + np.arange(nr)).astype(np.int32)
            ci = c.astype(np.int32)
            rlo, rhi = self._row_bounds(self._b[-1], self._berr[-1])
            bb = self._b[-1]
            for hs, ranged in zip(self._models, self._ranged, strict=True):
                if ranged:
                    hs.addRows(nr, rlo, rhi, v.size, starts, ci, v)
                else:
                    hs.addRows(nr, bb, bb, v.size, starts, ci, v)
        self._n_row += nr
        self._cache = None

    def _step_set(self, S: ConstrainedZonotope | None, M: NDArray[np.float64]):
        """``(M G_S, |M G_S| h_S, M c_S, err)`` of a per-step set (cached by identity)."""
        if S is None or S.dim == 0 or M.shape[1] == 0:
            return None
        hit = self._products.get(id(M))
        if hit is not None and hit[0] is S:
            return hit[1]
        if len(self._products) > 8:
            self._products.clear()
        MG = M @ S.G
        absM = np.abs(M)
        reach = absM @ (np.abs(S.G) @ S.h)
        Mc = M @ S.c
        g = gamma(M.shape[1] + 2)
        # |M G - fl(M G)| h and |M c - fl(M c)|, the centre's own uncertainty
        err = g * (reach + absM @ np.abs(S.c)) + absM @ S.c_err
        out = (MG, np.abs(MG) @ S.h, Mc, err * (1.0 + gamma(4)))
        self._products[id(M)] = (S, out)
        return out

    def push(self, e) -> None:
        """Add the step of entry ``e`` (``y``, ``u``, ``dd``, ``w``, ``v``, ``yerr`` of
        :class:`~setobs.setmembership._setup.Entry`): the new state, the factors
        of its uncertainty sets, the dynamics and the measurement rows."""
        if self.box is None:
            raise InternalError("HistoryLP.push: the last step has no hull yet (call hull)")
        self._undo = []
        N = self.N
        lo0, hi0 = self.box
        m0 = 0.5 * lo0 + 0.5 * hi0
        rho0 = round_up(np.maximum(hi0 - m0, m0 - lo0))
        absA = np.abs(self.A_o)
        c = self.A_o @ m0
        reach = absA @ rho0
        scale = absA @ np.abs(m0) + reach
        err = np.zeros(N)
        if e.u is not None and self.Gamma_o.shape[1]:
            gu = self.Gamma_o @ e.u
            agu = np.abs(self.Gamma_o) @ np.abs(e.u)
            c = c + gu
            scale = scale + agu
            err = err + (gamma(self.Gamma_o.shape[1] + 2) + self.data_rtol) * agu
        else:
            gu = np.zeros(N)
        sets = [(e.dd, self.B_o), (e.w, self.E_o)]
        blocks = []
        rhs = gu.copy()
        rhs_abs = np.abs(gu)
        for S, M in sets:
            pr = self._step_set(S, M)
            if pr is None:
                continue
            MG, reach_S, Mc, err_S = pr
            c = c + Mc
            rhs = rhs + Mc
            rhs_abs = rhs_abs + np.abs(Mc)
            reach = reach + reach_S
            scale = scale + np.abs(Mc) + reach_S
            err = err + err_S
            blocks.append((MG, S))
        # the implied box of z_(k+1): c +- (reach + every rounding), widened generously
        g = gamma(2 * (N + len(blocks) + 2) + 4)
        r = reach + err + g * (scale + np.abs(c))
        r = r * (1.0 + _PRIOR_SLACK) + _PRIOR_SLACK * (np.abs(c) + r) + _TINY
        zlo, zhi = round_down(c - r), round_up(c + r)
        z_prev = self._z
        z = self._add_cols(zlo, zhi)
        # dynamics: z+ - A_o z - sum M G sigma = Gamma u + sum M c
        base = self._n_row
        rr = [np.arange(N), np.repeat(np.arange(N), N)]
        cc = [z, np.tile(z_prev, N)]
        vv = [np.ones(N), -self.A_o.ravel()]
        extra_rows = []
        for MG, S in blocks:
            sig = self._add_cols(-S.h, S.h)
            rr.append(np.repeat(np.arange(N), sig.size))
            cc.append(np.tile(sig, N))
            vv.append(-MG.ravel())
            if S.n_con:
                extra_rows.append((sig, S))
        # the rhs's own sum (each term's rounding is in err)
        b_err = err + gamma(len(blocks) + 2) * rhs_abs
        self._add_rows(base + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                       rhs, b_err)
        for sig, S in extra_rows:
            self._constraint_rows(sig, S)
        # measurement
        y = e.y
        msk = ~np.isnan(y)
        if msk.any():
            Cm = self.C_o[msk]
            ym = y[msk]
            yerr = self.data_rtol * np.abs(ym)
            if e.yerr is not None:
                yerr = yerr + e.yerr[msk]
            nm = Cm.shape[0]
            rr = [np.repeat(np.arange(nm), N)]
            cc = [np.tile(z, nm)]
            vv = [Cm.ravel()]
            V = e.v
            if V is None:
                bm, berr_m = ym, yerr
            else:
                nu = self._add_cols(-V.h, V.h)
                GV = V.G[msk]
                rr.append(np.repeat(np.arange(nm), nu.size))
                cc.append(np.tile(nu, nm))
                vv.append(GV.ravel())
                bm = ym - V.c[msk]
                berr_m = yerr + V.c_err[msk] + UNIT_ROUNDOFF * np.abs(bm) * 2.0
            base = self._n_row
            self._add_rows(base + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                           bm, berr_m)
            if V is not None and V.n_con:
                self._constraint_rows(nu, V)
        self._z_prev, self._z = z_prev, z
        self._box_prev, self.box = self.box, None
        self._moved = True
        self.steps += 1

    def _constraint_rows(self, cols, S: ConstrainedZonotope) -> None:
        base = self._n_row
        rr = base + np.repeat(np.arange(S.n_con), cols.size)
        self._add_rows(rr, np.tile(cols, S.n_con), S.A.ravel(), S.b, S.b_err)

    def pop(self) -> None:
        """Undo the last :meth:`push` (the model is rebuilt on the next solve)."""
        for kind, n in reversed(self._undo):
            if kind == "cols":
                self._lo.pop()
                self._hi.pop()
                self._s.pop()
                self._n_col -= n
            else:
                self._b.pop()
                self._berr.pop()
                self._ent.pop()
                self._n_row -= n
        self._undo = []
        self._z, self.box = self._z_prev, self._box_prev
        self.steps -= 1
        self._models = []
        self._cache = None

    # ------------------------------------------------------------------ solving
    def _arrays(self):
        if self._cache is None:
            lo = np.concatenate(self._lo)
            hi = np.concatenate(self._hi)
            b = np.concatenate(self._b) if self._b else np.zeros(0)
            berr = np.concatenate(self._berr) if self._berr else np.zeros(0)
            r = np.concatenate([e[0] for e in self._ent])
            c = np.concatenate([e[1] for e in self._ent])
            v = np.concatenate([e[2] for e in self._ent])
            A = sparse.csc_array((v, (r, c)), shape=(self._n_row, self._n_col))
            A.sum_duplicates()
            AT = A.T.tocsr()
            absAT = abs(AT)
            k = int(np.diff(A.indptr).max(initial=0))
            self._cache = (lo, hi, b, berr, A, AT, absAT, k)
        return self._cache

    @staticmethod
    def _row_bounds(b, berr):
        """Ranged rows ``b +- b_err`` (the set the certificate covers), for an LP that
        HiGHS calls infeasible at exactly ``b``: a thin set, carried by the set
        recursion with its rounding. (Not by default: ranged rows cost 2-7x the
        simplex iterations.)"""
        pos = berr > 0
        return np.where(pos, round_down(b - berr), b), np.where(pos, round_up(b + berr), b)

    def _build(self, w: NDArray[np.float64], ranged: bool = False):
        """A HiGHS model of the LP with objective ``w`` on the newest state."""
        from ..geometry.lp import FactorPolytope

        lo, hi, b, berr, A, _, _, _ = self._arrays()
        s = np.concatenate(self._s)
        hs = FactorPolytope.new_highs()
        hs.setOptionValue("simplex_strategy", 1)  # (cold: the dual simplex)
        cost = np.zeros(self._n_col)
        cost[self._z] = w
        As = A @ sparse.diags_array(s)  # (exact: powers of two)
        lp = highspy.HighsLp()
        lp.num_col_ = self._n_col
        lp.num_row_ = self._n_row
        lp.col_cost_ = cost * s
        lp.col_lower_ = lo / s
        lp.col_upper_ = hi / s
        lp.row_lower_, lp.row_upper_ = self._row_bounds(b, berr) if ranged else (b, b)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = As.indptr.astype(np.int32)
        lp.a_matrix_.index_ = As.indices.astype(np.int32)
        lp.a_matrix_.value_ = As.data.astype(np.float64)
        lp.a_matrix_.num_col_ = self._n_col
        lp.a_matrix_.num_row_ = self._n_row
        if hs.passModel(lp) == highspy.HighsStatus.kError:
            return None
        return hs

    def certify(self, w_cols: NDArray[np.int64], w: NDArray[np.float64],
                y: NDArray[np.float64]) -> float:
        """Certified lower bound of ``min w^T x_(w_cols)`` from row multipliers ``y``."""
        lo, hi, b, berr, _, AT, absAT, k = self._arrays()
        r = -(AT @ y)
        r[w_cols] += w
        s = absAT @ np.abs(y)
        s[w_cols] += np.abs(w)
        err = 2.0 * gamma(k + 2) * s
        terms = np.minimum(r * lo, r * hi)
        s1 = float(terms.sum())
        a1 = float(np.abs(terms).sum())
        s2 = float((err * np.maximum(np.abs(lo), np.abs(hi))).sum())
        s3 = float(np.abs(y) @ berr)
        t1 = exact_dot([y], b)
        n = lo.size + b.size
        tot = t1 + s1 - s2 - s3
        bound_err = UNIT_ROUNDOFF * abs(t1) + 2.0 * gamma(n + 4) * (a1 + s2 + s3) + \
            4.0 * UNIT_ROUNDOFF * (abs(tot) + abs(t1) + a1 + s2 + s3) + 8.0 * n * _TINY
        return float(round_down(tot - bound_err))

    def hull(self) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """Certified bounds of ``z_k`` and of the objective rows over the exact posterior
        (``lo``, ``hi`` over the rows of :attr:`objectives`), or ``None`` when a solve
        is not optimal or its certificate not tight.

        One HiGHS model per objective (min and max of each row), each grown with
        the history and warm-started from its own last optimal basis: the
        direction's optimal history at step ``k`` is close to that at ``k - 1``.
        """
        W = self.objectives
        z = self._z
        idx = z.astype(np.int32)
        n_obj = 2 * W.shape[0]
        if len(self._models) != n_obj:
            models = [self._build(sign * w) for w in W for sign in (1.0, -1.0)]
            if any(hs is None for hs in models):
                return None
            self._models = models
            self._warm = [False] * n_obj
            self._ranged = [False] * n_obj
            self._moved = False
        lo = np.empty(W.shape[0])
        hi = np.empty(W.shape[0])
        limit = 50 * (self._n_row + self._n_col) + 10_000
        zs = np.concatenate(self._s)[z]
        z_prev = self._z_prev.astype(np.int32) if self._moved else None
        for j, hs in enumerate(self._models):
            i, sign = j // 2, (1.0 if j % 2 == 0 else -1.0)
            ws = sign * W[i]
            if self._moved:  # (the objective moves to the newest state)
                hs.changeColsCost(z_prev.size, z_prev, np.zeros(z_prev.size))
                hs.changeColsCost(idx.size, idx, ws * zs)
            bound = self._solve(j, ws, limit)
            if bound is None:
                self._models = []  # (fresh models next time)
                return None
            if sign > 0:
                lo[i] = bound
            else:
                hi[i] = -bound
        self._moved = False
        self.box = (lo[:self.N].copy(), hi[:self.N].copy())
        return lo, hi

    def _solve(self, j: int, ws: NDArray[np.float64], limit: int) -> float | None:
        """Certified ``min ws^T z_k`` on model ``j``: from its last optimal basis with
        the primal simplex (its phase 1 for the step's new rows: 2-8x fewer
        iterations than the dual here), then the dual simplex, then a fresh model,
        then a fresh model with ranged rows (:meth:`_row_bounds`); ``None`` if none
        is optimal with a tight certificate."""
        opt = highspy.HighsModelStatus.kOptimal
        for attempt in range(4):
            if attempt >= 2:  # a fresh model; the last with ranged rows
                hs = self._build(ws, ranged=attempt == 3)
                if hs is None:
                    return None
                self._models[j] = hs
                self._ranged[j] = attempt == 3
            hs = self._models[j]
            hs.setOptionValue("simplex_strategy", 4 if attempt == 0 and self._warm[j] else 1)
            hs.setOptionValue("simplex_iteration_limit", limit)
            hs.run()
            if hs.getModelStatus() != opt:
                self.retries += 1
                continue
            obj = float(hs.getInfo().objective_function_value)
            y = np.asarray(hs.getSolution().row_dual, dtype=np.float64)
            bound = self.certify(self._z, ws, y)
            if np.isfinite(bound) and obj - bound <= HISTORY_GAP_RTOL * (1.0 + abs(obj)):
                self._warm[j] = True
                return bound
            self.retries += 1
        return None

    # ------------------------------------------------------------------ as a set
    def to_cz(self) -> ConstrainedZonotope:
        """The posterior as a constrained zonotope (every variable a factor, centred
        in its bounds; equal to the exact set up to the certified ``b_err``)."""
        lo, hi, b, berr, A, _, _, k = self._arrays()
        m = 0.5 * lo + 0.5 * hi
        rho = round_up(np.maximum(hi - m, m - lo))
        Ad = A.toarray()
        As = Ad * rho[None, :]
        rhs = b - Ad @ m
        absA = np.abs(Ad)
        g = gamma(k + 3)
        berr2 = berr + g * (np.abs(b) + absA @ np.abs(m) + absA @ rho) + \
            UNIT_ROUNDOFF * (absA @ rho)
        G = np.zeros((self.N, lo.size))
        G[np.arange(self.N), self._z] = rho[self._z]
        return trusted_cz(G, m[self._z].copy(), As, rhs, np.ones(lo.size),
                          berr=berr2 * (1.0 + gamma(4)))

    # ------------------------------------------------------------------ pickling
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_models"] = []  # (HiGHS models do not pickle: rebuilt on demand)
        state["_cache"] = None
        state["_products"] = {}
        return state
