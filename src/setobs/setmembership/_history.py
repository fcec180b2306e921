"""Exact mode with noise: the whole-history LP, kept and warm-started from step to step.

With measurement or process noise the exact posterior's complexity grows with
every step (the paper example with a noise box: 44, 107, 264 facets at
``k = 2, 3, 4``), so neither the H-representation recursion (:mod:`._hrep`)
nor the set recursion (dense generators and constraints that grow with ``k``)
keeps its cost. The exact set's interval hull is the whole-history LP, and that
LP is sparse when every state is a variable. :class:`HistoryLP` assembles it
in a :class:`setobs.lp.boxlp.BoxLP` (one HiGHS model per objective): each step
*adds* the step's variables and rows, and the hull's ``2 N`` LPs are re-solved
from the previous basis (a handful of simplex iterations each), instead of
solving a dense LP of the whole history from scratch.

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

whatever the solver's accuracy: the one certificate of the package
(:mod:`setobs.lp.certificate`, with its rounding analysis), over the variable box
with the right-hand side known to ``+- b_err`` (the rounding of the products that
formed it, the data's representation). The stored matrices ``A_o``, ``C_o``,
``G_V`` enter as variables' coefficients, without products; the products
``B_o G_D`` and ``E_o G_W`` carry their rounding into ``b_err`` (times the factor
bounds). So a reported bound holds for the stored model and data; the solver
only decides how tight it is (its tolerances are 1e-10).

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

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._rounding import UNIT_ROUNDOFF, gamma, round_down, round_up
from ..exceptions import InternalError
from ..geometry import ConstrainedZonotope
from ..geometry.zonotope import trusted_cz
from ..lp.boxlp import BoxLP

__all__ = ["HistoryLP"]

#: Relative widening of the implied bounds of a new state (they only need to
#: contain the prior; a generous margin costs nothing).
_PRIOR_SLACK = 1e-9

#: The implied bounds' radius is this many times the prior's (the LP's feasible set is
#: the same). Tight implied bounds are active at many optimal vertices of the
#: whole-history LP, and that degeneracy stalled HiGHS on a 30-tank cascade with 21
#: outputs (``benchmarks/results/exact_long_tight_bounds.json``, against 16 times the
#: radius in ``exact_long.json``). Wider bounds only widen the certificate's
#: basic-column term, which the accepted gap explains.
IMPLIED_WIDEN = 16.0

_TINY = np.finfo(np.float64).tiny
_EMPTY = np.zeros(0, dtype=np.int64)


class _Block(NamedTuple):
    """One state's place in the LP: its columns ``z``; its own columns (``z`` and the
    measurement's factors) and rows (the measurement and its factors' constraints);
    the transition into it (the step's factors; the dynamics and their constraints)."""

    z: NDArray[np.int64]
    cols: NDArray[np.int64]
    rows: NDArray[np.int64]
    tcols: NDArray[np.int64]
    trows: NDArray[np.int64]


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
        self.gaps = np.zeros(0)  # (the certified gap of each band: hull)
        self.A_o, self.Gamma_o, self.C_o = A_o, Gamma_o, C_o
        self.B_o, self.E_o = B_o, E_o
        self.N = A_o.shape[0]
        self.objectives = np.vstack([np.eye(self.N), rows]) if rows.shape[0] else np.eye(self.N)
        self.data_rtol = data_rtol
        self.box_lp = BoxLP()  # (the LP itself: columns, rows, warm models)
        self._z = np.zeros(0, dtype=np.int64)  # columns of the newest state
        self.box: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self._box_prev: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None
        self.steps = 0
        self._products: dict[int, tuple] = {}
        # the LP's blocks, for cutting it (drop_oldest): the head (the first state's
        # start set: the start posterior's factors and rows, or a hull of points, or
        # nothing for a box) and per state its own columns and rows (z_j, the
        # measurement's factors and rows) and the transition into it (the step's
        # factors, the dynamics and the factors' constraint rows)
        self._head = (_EMPTY, _EMPTY)
        self._states: list[_Block] = []

    @property
    def retries(self) -> int:
        """Solves that were not optimal with a tight certificate."""
        return self.box_lp.retries

    @property
    def state_columns(self) -> NDArray[np.int64]:
        """Indices of the newest state's variables ``z_k`` among the LP's columns."""
        return self._z

    def lp(self):
        """The LP as ``(A, b, b_err, lo, hi)``: ``A x = b`` (a ``scipy.sparse`` array;
        the right-hand side known to ``+- b_err``), ``lo <= x <= hi``."""
        lo, hi, b, berr, A, _, _ = self.box_lp.arrays()
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
        xi = H.box_lp.add_cols(-Z.h, Z.h)
        z = H.box_lp.add_cols(lo, hi)
        # z - G xi = c ; A xi = b
        r0 = H.box_lp.n_row
        rr = [np.arange(N), np.repeat(np.arange(N), ng)]
        cc = [z, np.tile(xi, N)]
        vv = [np.ones(N), -Z.G.ravel()]
        if Z.n_con:
            rr.append(N + np.repeat(np.arange(Z.n_con), ng))
            cc.append(np.tile(xi, Z.n_con))
            vv.append(Z.A.ravel())
        H.box_lp.add_rows(r0 + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                          np.concatenate([Z.c, Z.b]), np.concatenate([Z.c_err, Z.b_err]))
        H._z = z
        H.box = (np.asarray(lo, float), np.asarray(hi, float))
        H._head = (xi, r0 + np.arange(N + Z.n_con))
        H._states = [_Block(z, z, _EMPTY, _EMPTY, _EMPTY)]
        H.box_lp.begin()
        return H

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
        :class:`~setobs.setmembership._model.Entry`): the new state, the factors
        of its uncertainty sets, the dynamics and the measurement rows."""
        if self.box is None:
            raise InternalError("HistoryLP.push: the last step has no hull yet (call hull)")
        lp = self.box_lp
        lp.begin()
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
        r = IMPLIED_WIDEN * r * (1.0 + _PRIOR_SLACK) + _PRIOR_SLACK * (np.abs(c) + r) + _TINY
        zlo, zhi = round_down(c - r), round_up(c + r)
        z_prev = self._z
        c0, r0 = lp.n_col, lp.n_row
        z = lp.add_cols(zlo, zhi)
        # dynamics: z+ - A_o z - sum M G sigma = Gamma u + sum M c
        base = lp.n_row
        rr = [np.arange(N), np.repeat(np.arange(N), N)]
        cc = [z, np.tile(z_prev, N)]
        vv = [np.ones(N), -self.A_o.ravel()]
        extra_rows = []
        for MG, S in blocks:
            sig = lp.add_cols(-S.h, S.h)
            rr.append(np.repeat(np.arange(N), sig.size))
            cc.append(np.tile(sig, N))
            vv.append(-MG.ravel())
            if S.n_con:
                extra_rows.append((sig, S))
        # the rhs's own sum (each term's rounding is in err)
        b_err = err + gamma(len(blocks) + 2) * rhs_abs
        lp.add_rows(base + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                    rhs, b_err)
        for sig, S in extra_rows:
            self._constraint_rows(sig, S)
        c1, r1 = lp.n_col, lp.n_row
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
                nu = lp.add_cols(-V.h, V.h)
                GV = V.G[msk]
                rr.append(np.repeat(np.arange(nm), nu.size))
                cc.append(np.tile(nu, nm))
                vv.append(GV.ravel())
                bm = ym - V.c[msk]
                berr_m = yerr + V.c_err[msk] + UNIT_ROUNDOFF * np.abs(bm) * 2.0
            base = lp.n_row
            lp.add_rows(base + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                        bm, berr_m)
            if V is not None and V.n_con:
                self._constraint_rows(nu, V)
        self._z_prev, self._z = z_prev, z
        self._box_prev, self.box = self.box, None
        self.steps += 1
        own = np.concatenate([z, np.arange(c1, lp.n_col)])
        self._states.append(_Block(z, own, np.arange(r1, lp.n_row),
                                   np.arange(c0 + N, c1), np.arange(r0, r1)))

    def _constraint_rows(self, cols, S: ConstrainedZonotope) -> None:
        base = self.box_lp.n_row
        rr = base + np.repeat(np.arange(S.n_con), cols.size)
        self.box_lp.add_rows(rr, np.tile(cols, S.n_con), S.A.ravel(), S.b, S.b_err)

    def pop(self) -> None:
        """Undo the last :meth:`push` (the model is rebuilt on the next solve)."""
        self.box_lp.undo()
        self._z, self.box = self._z_prev, self._box_prev
        self.steps -= 1
        self._states.pop()

    # ------------------------------------------------------------------ cutting
    @property
    def length(self) -> int:
        """Steps of history in the LP (its states less one)."""
        return len(self._states) - 1

    def state_cols(self) -> NDArray[np.int64]:
        """The columns of every state in the LP, oldest first (``(length + 1) N``)."""
        return np.concatenate([b.z for b in self._states])

    def drop_oldest(self, lo: NDArray[np.float64], hi: NDArray[np.float64],
                    duals: NDArray[np.float64] | None = None, count: int = 1) -> None:
        """Cut the LP's oldest ``count`` steps: remove the head (the start set's rows, or
        earlier cuts), the oldest states with their measurements and the transitions out
        of them; the next state becomes the first, in the box ``[lo, hi]`` (its certified
        hull: a set that contains every state of a history consistent with the data).
        The HiGHS models keep their bases (:meth:`setobs.lp.boxlp.BoxLP.delete`).

        With ``duals`` (row multipliers of this LP, one row per objective: those of its
        last certified bounds), each becomes a *cut* on the new first state, which
        replaces what is removed (:meth:`_cuts`): the aggregate of the removed rows by
        the multiplier, with the removed variables at their worst in their boxes,

        .. math::  (A_{R,z}^\top y_R)^\top z \\ge y_R^\top b_R
                   - \\sum_{i \\in D} \\max(r_i l_i, r_i u_i),\\quad r = A_{R,D}^\top y_R,

        valid for every point of the LP (weak duality over the removed part), and with
        the objective's own multiplier it keeps that objective's bound unchanged.

        Parameters
        ----------
        lo, hi : ndarray
            The new first state's box.
        duals : ndarray, shape (m, n_row), optional
            Multipliers whose cuts replace the removed steps.
        count : int
            Steps removed.
        """
        if not 1 <= count < len(self._states):
            raise InternalError(f"HistoryLP.drop_oldest: {count} of {self.length} steps")
        hc, hr = self._head
        new = self._states[count]
        cols = np.unique(np.concatenate(
            [hc] + [b.cols for b in self._states[:count]]
            + [b.tcols for b in self._states[1:count + 1]]))
        rows = np.unique(np.concatenate(
            [hr] + [b.rows for b in self._states[:count]]
            + [b.trows for b in self._states[1:count + 1]]))
        lo = round_down(np.asarray(lo, float))
        hi = round_up(np.asarray(hi, float))
        cuts = None if duals is None else self._cuts(duals, rows, cols, new.z, lo, hi)
        self.box_lp.delete(cols, rows, demote=new.z)

        def col(i):
            return i - np.searchsorted(cols, i)

        def row(i):
            return i - np.searchsorted(rows, i)

        self._states = [_Block(col(b.z), col(b.cols), row(b.rows), col(b.tcols), row(b.trows))
                        for b in self._states[count:]]
        first = self._states[0]
        self._states[0] = _Block(first.z, first.cols, first.rows, _EMPTY, _EMPTY)
        self._head = (_EMPTY, _EMPTY)
        self._z = col(self._z)
        self._z_prev = self._z  # (no undo across a cut: BoxLP.delete ends the block)
        self._box_prev = self.box
        self.box_lp.set_bounds(first.z, lo, hi)
        if cuts is not None:
            Gc, rhs, top = cuts
            lp = self.box_lp
            t = lp.add_cols(np.zeros(rhs.size), top)
            m = rhs.size
            base = lp.n_row
            N = self.N
            rr = [np.repeat(np.arange(m), N), np.arange(m)]
            cc = [np.tile(first.z, m), t]
            vv = [Gc.ravel(), -np.ones(m)]
            lp.add_rows(base + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                        rhs, np.zeros(m))
            self._head = (t, base + np.arange(m))
            lp.begin()

    def _cuts(self, Y, rows, cols, z, zlo, zhi):
        """The cuts ``G z - t = rhs``, ``0 <= t <= top`` of the multipliers ``Y`` over
        the removed ``rows`` and ``cols`` (:meth:`drop_oldest`), every product's rounding
        taken off ``rhs`` (so each holds exactly for every point of the LP); ``None``
        when none is finite."""
        clo, chi, b, berr, A, _, _ = self.box_lp.arrays()
        Ar = A[rows]  # (rows of the removed part: entries only in cols and z)
        A_D = Ar[:, cols]
        A_z = Ar[:, z]
        Yr = Y[:, rows]
        aY = np.abs(Yr)
        g = gamma(max(rows.size, 1) + 4)
        G = np.asarray((A_z.T @ Yr.T).T)
        r = np.asarray((A_D.T @ Yr.T).T)
        lD, uD = clo[cols], chi[cols]
        mag = np.maximum(np.abs(lD), np.abs(uD))
        worst = np.maximum(r * lD, r * uD).sum(axis=1)
        beta = Yr @ b[rows] - aY @ berr[rows] - worst
        absAD = abs(A_D)
        absAz = abs(A_z)
        err = g * (aY @ np.abs(b[rows]) + aY @ berr[rows] + np.abs(r) @ mag) \
            + g * np.asarray((absAD.T @ aY.T).T) @ mag \
            + g * np.asarray((absAz.T @ aY.T).T) @ np.maximum(np.abs(zlo), np.abs(zhi))
        rhs = round_down(beta - err * (1.0 + gamma(4)))
        top = np.maximum(G, 0.0) @ zhi + np.minimum(G, 0.0) @ zlo - rhs
        top = round_up(np.maximum(top, 0.0) * (1.0 + g) + g * (np.abs(G) @ np.maximum(
            np.abs(zlo), np.abs(zhi)) + np.abs(rhs)) + _TINY)
        big = np.abs(G).max(axis=1, initial=0.0)
        ok = np.isfinite(rhs) & np.isfinite(top) & (big > 0)
        if not ok.any():
            return None
        G, rhs, top, big = G[ok], rhs[ok], top[ok], big[ok]
        # each cut scaled by a power of two to unit size (exact), the repeated ones once
        sc = np.ldexp(1.0, -np.frexp(big)[1])[:, None]
        G, rhs, top = G * sc, rhs * sc[:, 0], top * sc[:, 0]
        _, keep = np.unique(np.round(G, 12), axis=0, return_index=True)
        keep = np.sort(keep)
        return G[keep], rhs[keep], top[keep]

    def attach_hull(self, P: NDArray[np.float64]) -> None:
        """Restrict the first state to the convex hull of the rows of ``P``: ``z = P^T
        lam``, ``sum lam = 1``, ``lam >= 0`` (replacing any head but a box). Each row a
        state of a history consistent with the data, the LP's values are those of such
        histories (an inner bound of the exact set's support).

        Parameters
        ----------
        P : ndarray, shape (m, N)
            The points.
        """
        if self._head[0].size or self._head[1].size:
            raise InternalError("HistoryLP.attach_hull: the first state has a head")
        m = P.shape[0]
        lp = self.box_lp
        lp.begin()
        lam = lp.add_cols(np.zeros(m), np.ones(m))
        N = self.N
        z = self._states[0].z
        base = lp.n_row
        rr = [np.arange(N), np.repeat(np.arange(N), m), np.full(m, N)]
        cc = [z, np.tile(lam, N), lam]
        vv = [np.ones(N), -P.T.ravel(), np.ones(m)]
        lp.add_rows(base + np.concatenate(rr), np.concatenate(cc), np.concatenate(vv),
                    np.r_[np.zeros(N), 1.0], np.zeros(N + 1))
        self._head = (lam, base + np.arange(N + 1))
        lp.begin()

    def clone(self) -> HistoryLP:
        """A copy of the LP (its data and block structure; the HiGHS model starts from
        this one's basis: :meth:`setobs.lp.boxlp.BoxLP.clone`)."""
        other = HistoryLP.__new__(HistoryLP)
        other.__dict__.update(self.__dict__)
        other.box_lp = self.box_lp.clone()
        other._states = list(self._states)
        other._products = {}
        other.gaps = self.gaps.copy()
        return other

    # ------------------------------------------------------------------ solving
    def certify(self, w_cols: NDArray[np.int64], w: NDArray[np.float64],
                y: NDArray[np.float64]) -> float:
        """Certified lower bound of ``min w^T x_(w_cols)`` from row multipliers ``y``
        (:meth:`setobs.lp.boxlp.BoxLP.certify`)."""
        return self.box_lp.certify(w_cols, w, y)

    def hull(self) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """Certified bounds of ``z_k`` and of the objective rows over the exact posterior
        (``lo``, ``hi`` over the rows of :attr:`objectives`), or ``None`` when a solve
        is not optimal or its certificate not tight.

        One HiGHS model per objective (min and max of each row), each grown with
        the history and warm-started from its own last optimal basis: the
        direction's optimal history at step ``k`` is close to that at ``k - 1``.
        """
        W = self.objectives
        signed = np.empty((2 * W.shape[0], W.shape[1]))
        signed[0::2], signed[1::2] = W, -W
        mins = self.box_lp.minimize_all(self._z, signed)
        if mins is None:
            return None
        lo, hi = mins[0::2], -mins[1::2]
        self.box = (lo[:self.N].copy(), hi[:self.N].copy())
        g = self.box_lp.last_gaps
        #: the certified gap of each band (lower plus upper end): the exact set's band
        #: lies within it of ``[lo, hi]``, inside
        self.gaps = g[0::2] + g[1::2]
        return lo, hi

    # ------------------------------------------------------------------ as a set
    def to_cz(self) -> ConstrainedZonotope:
        """The posterior as a constrained zonotope (every variable a factor, centred
        in its bounds; equal to the exact set up to the certified ``b_err``)."""
        lo, hi, b, berr, A, _, k = self.box_lp.arrays()
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
        state["_products"] = {}
        return state
