"""A box-bounded LP grown block by block, solved per objective from its last basis.

.. math::  \\min \\{ w^\\top x_S : A x = b,\\ l \\le x \\le u \\}

with every variable bounded and the right-hand side known to ``+- b_err``. The
whole-history LP of exact mode (:mod:`setobs.setmembership._history`) is one:
each step *adds* columns (the step's variables) and rows (its equations), and
the objective moves to the newest block's columns ``S``. :class:`BoxLP` keeps
one HiGHS model per objective, grown with the LP and re-solved from its own last
optimal basis (the direction's optimum at one step is close to that at the
previous one), and reports each minimum through the one certificate
(:func:`setobs.lp.certificate.lower_bound`): a bound holds for the stored data
whatever the solver did; a solve that is not optimal with a tight certificate
gives ``None``, and the caller decides with a certified test of its own.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from .._rounding import round_down, round_up
from ..exceptions import InternalError
from ..tolerances import HISTORY_GAP_RTOL
from . import highs

__all__ = ["CHAIN", "CHAIN_MIN_OBJECTIVES", "HIGHS_SCALING", "BoxLP"]

#: :meth:`BoxLP.minimize_all` solves the objectives as a chain on one HiGHS model (each
#: from the previous one's optimal vertex by the primal simplex; the model grown once per
#: block) rather than each on its own model from its own last basis, when there are at
#: least :data:`CHAIN_MIN_OBJECTIVES` of them.
CHAIN = True

#: Fewest objectives solved as a chain. Exact mode with noise, linprog per step, chain
#: against one model per objective (``benchmarks/chain_ab.py``): a 30-tank cascade with 21
#: outputs (60 objectives, 30 steps) 71 against 149, a random 6-state plant (12) and a
#: bicycle model (8) about the same (22.6 / 22.1, 6.1 / 6.3), a two-mass plant (8) 13.1
#: against 6.5: with few objectives each one's own last basis, which the data move little,
#: is the cheaper start.
CHAIN_MIN_OBJECTIVES = 12

#: Simplex iterations allowed to a warm start by the primal simplex (the first attempt
#: of :meth:`BoxLP._solve`) before the dual simplex takes over from where it stopped. A
#: healthy warm start takes tens of iterations; on the whole-history LP of a 30-tank
#: cascade with 21 outputs the primal stalled from ``k`` = 85 on (up to 184 000
#: iterations, 66 s, for one bound; 524 s for the step), where the dual simplex finished
#: the same bounds in 3 500-7 500 (a prototype run on a record of
#: ``benchmarks/exact_long.py``).
WARM_PRIMAL_LIMIT = 2000

#: Whether HiGHS scales the models :class:`BoxLP` builds itself (``scaled`` of
#: :func:`setobs.lp.highs.new_model`): it does not. :meth:`BoxLP.add_cols`
#: already scales each column by a power of two to its range. On the whole-history LP of
#: a 30-tank cascade with 21 outputs (``A_o`` the ``expm`` of a chain: entries from 0.8
#: down to 1e-50), HiGHS's scaling on top made its recoveries stall: steps 186 and 187
#: took 39 s and 117 s and a cold model at ``k`` = 184 did not finish in six minutes;
#: without it the record's 235 steps complete, three of them through a cold model (7.1 s
#: at most; ``benchmarks/results/exact_long.json``). In development runs the cold dual
#: simplex for one bound at ``k`` = 110 took 9 800 iterations scaled against 6 700
#: unscaled in this class, and 28 800 (stopped at 15 s) against 3 300 on the same LP with
#: free states and no column scaling.
HIGHS_SCALING = False

sparse = lazy_module("scipy.sparse")
_certificate = lazy_module("setobs.lp.certificate")


class BoxLP:
    """An LP ``A x = b (+- b_err), lo <= x <= hi`` that grows by columns and rows.

    Blocks are added with :meth:`add_cols` and :meth:`add_rows`; :meth:`begin` marks
    the start of a block that :meth:`undo` removes again. :meth:`minimize_all` solves
    a list of objectives over some columns, each on its own warm HiGHS model.
    """

    def __init__(self) -> None:
        self._lo: list[NDArray[np.float64]] = []
        self._hi: list[NDArray[np.float64]] = []
        self._s: list[NDArray[np.float64]] = []  # (HiGHS's column scales, powers of two)
        self._b: list[NDArray[np.float64]] = []
        self._berr: list[NDArray[np.float64]] = []
        self._ent: list[tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]]] = []
        self.n_col = 0
        self.n_row = 0
        #: solves that were not optimal with a tight certificate
        self.retries = 0
        self._models: list = []
        self._warm: list[bool] = []
        self._ranged: list[bool] = []
        self._cols = np.zeros(0, dtype=np.int64)  # (the columns the objectives are on)
        self._undo: list[tuple[str, int]] = []
        self._cache = None
        #: each objective's certified gap at the last :meth:`minimize_all`: how far its
        #: bound may lie below the LP's minimum (``obj - bound`` plus what the solver's
        #: point misses of its rows, :meth:`_gap`)
        self.last_gaps = np.zeros(0)
        #: columns whose values at each objective's optimum :meth:`minimize_all` keeps
        #: in :attr:`last_points` (``None``: none)
        self.record: NDArray[np.int64] | None = None
        #: the solver's optimal point on :attr:`record`, one row per objective of the
        #: last :meth:`minimize_all` (unscaled)
        self.last_points = np.zeros((0, 0))
        # (a basis a clone's first model starts from: clone)
        self._seed: tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.float64]] | None = None
        #: whether :meth:`minimize_all` keeps each objective's certified multiplier in
        #: :attr:`last_duals`
        self.keep_duals = False
        #: the row multipliers of the last :meth:`minimize_all`'s certified bounds, one
        #: row per objective (each a valid multiplier: any gives a valid cut)
        self.last_duals = np.zeros((0, 0))
        self._y = np.zeros(0)

    # ------------------------------------------------------------------ building
    def begin(self) -> None:
        """Start a block: :meth:`undo` removes what is added from here on."""
        self._undo = []

    def add_cols(self, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.int64]:
        """Add variables with bounds ``[lo, hi]``; return their column indices.

        Parameters
        ----------
        lo, hi : ndarray
            Bounds (finite: the certificate needs every variable bounded).

        Returns
        -------
        ndarray of int64
            The new columns.
        """
        lo = np.asarray(lo, dtype=np.float64)
        hi = np.asarray(hi, dtype=np.float64)
        idx = np.arange(self.n_col, self.n_col + lo.size)
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
        self.n_col += lo.size
        self._undo.append(("cols", lo.size))
        for hs in self._models:
            hs.addCols(lo.size, np.zeros(lo.size), lo / s, hi / s, 0,
                       np.zeros(lo.size, np.int32), np.zeros(0, np.int32), np.zeros(0))
        self._cache = None
        return idx

    def add_rows(self, r: NDArray[np.int64], c: NDArray[np.int64], v: NDArray[np.float64],
                 b: NDArray[np.float64], berr: NDArray[np.float64]) -> None:
        """Add the rows ``sum_c v x_c = b`` (``+- berr``).

        Parameters
        ----------
        r, c, v : ndarray
            The entries: absolute row indices (all new, from :attr:`n_row` on),
            columns, values.
        b, berr : ndarray
            The new rows' right-hand side and its uncertainty.
        """
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
            starts = np.searchsorted(r, self.n_row + np.arange(nr)).astype(np.int32)
            ci = c.astype(np.int32)
            rlo, rhi = self._row_bounds(self._b[-1], self._berr[-1])
            bb = self._b[-1]
            for hs, ranged in zip(self._models, self._ranged, strict=True):
                if ranged:
                    hs.addRows(nr, rlo, rhi, v.size, starts, ci, v)
                else:
                    hs.addRows(nr, bb, bb, v.size, starts, ci, v)
        self.n_row += nr
        self._cache = None

    def undo(self) -> None:
        """Remove the block added since :meth:`begin` (the models are rebuilt on the
        next solve)."""
        for kind, n in reversed(self._undo):
            if kind == "cols":
                self._lo.pop()
                self._hi.pop()
                self._s.pop()
                self.n_col -= n
            else:
                self._b.pop()
                self._berr.pop()
                self._ent.pop()
                self.n_row -= n
        self._undo = []
        self._models = []
        self._cache = None

    # ------------------------------------------------------------------ cutting
    def _merge(self) -> None:
        """The blocks as one block each (columns, rows), for an edit by index."""
        if len(self._lo) > 1:
            self._lo, self._hi, self._s = ([np.concatenate(x)] for x in
                                           (self._lo, self._hi, self._s))
        if len(self._b) > 1:
            self._b, self._berr = [np.concatenate(self._b)], [np.concatenate(self._berr)]
            ent = self._ent
            self._ent = [(np.concatenate([e[0] for e in ent]), np.concatenate([e[1] for e in ent]),
                          np.concatenate([e[2] for e in ent]))]

    def delete(self, cols: NDArray[np.int64], rows: NDArray[np.int64],
               demote: NDArray[np.int64] | None = None) -> None:
        """Remove columns and rows; the rest are re-indexed in order (an index ``i``
        becomes ``i`` minus the removed indices below it). No kept row may have an entry
        in a removed column. Each HiGHS model is cut the same way (``deleteRows``,
        ``deleteCols``) and keeps its basis: the statuses of what is kept, with as many
        basic columns of ``demote`` made nonbasic (or slacks of kept rows made basic) as
        the count of basic variables must change to match the rows.

        Parameters
        ----------
        cols, rows : ndarray of int64
            The columns and rows to remove.
        demote : ndarray of int64, optional
            Kept columns (indices before the cut) preferred for leaving the basis.
        """
        cols = np.unique(np.asarray(cols, dtype=np.int64))
        rows = np.unique(np.asarray(rows, dtype=np.int64))
        if not (cols.size or rows.size):
            return
        self._merge()
        lo_all, s_all = self._lo[0], self._s[0]  # (before the cut: a clone's seed is padded)
        r, c, v = self._ent[0] if self._ent else (np.zeros(0, np.int64),) * 2 + (np.zeros(0),)
        gone_r = np.isin(r, rows)
        gone_c = np.isin(c, cols)
        if (gone_c & ~gone_r).any():
            raise InternalError("BoxLP.delete: a kept row has an entry in a removed column")
        keep_e = ~gone_r
        if self._ent:
            r, c = r[keep_e], c[keep_e]
            self._ent = [(r - np.searchsorted(rows, r), c - np.searchsorted(cols, c),
                          v[keep_e])]
        kc = np.ones(self.n_col, dtype=bool)
        kc[cols] = False
        kr = np.ones(self.n_row, dtype=bool)
        kr[rows] = False
        self._lo, self._hi, self._s = ([x[0][kc]] for x in (self._lo, self._hi, self._s))
        if self._b:
            self._b, self._berr = [self._b[0][kr]], [self._berr[0][kr]]
        pref = np.zeros(self.n_col, dtype=bool)
        if demote is not None:
            pref[np.asarray(demote, dtype=np.int64)] = True
        self.n_col, self.n_row = int(kc.sum()), int(kr.sum())
        for hs in self._models:
            self._cut_model(hs, cols, rows, kc, kr, pref[kc])
        if self._seed is not None:
            got = self._padded_seed(kc.size, kr.size, lo_all, s_all)
            self._seed = None if got is None else (got[0][kc], got[1][kr], got[2][kc])
        oc = self._cols[kc[self._cols]] if self._cols.size else self._cols
        self._cols = oc - np.searchsorted(cols, oc)
        self._undo = []
        self._cache = None

    @staticmethod
    def _basis_codes(hs, n_col: int, n_row: int):
        """A model's basis as status codes and its point, ``(col codes, row codes, x)``;
        ``None`` when the basis is not valid or not of ``n_col`` columns and ``n_row``
        rows."""
        basis = hs.getBasis()
        if not basis.valid:
            return None
        cs = np.array([int(st) for st in basis.col_status], dtype=np.int64)
        rs = np.array([int(st) for st in basis.row_status], dtype=np.int64)
        x = np.asarray(hs.getSolution().col_value, dtype=np.float64)
        if cs.size != n_col or rs.size != n_row or x.size != n_col:
            return None
        return cs, rs, x

    def _cut_model(self, hs, cols, rows, kc, kr, pref) -> None:
        """Cut one HiGHS model and give it its basis back, repaired to a square count."""
        got = self._basis_codes(hs, kc.size, kr.size)
        if rows.size:
            hs.deleteRows(rows.size, rows.astype(np.int32))
        if cols.size:
            hs.deleteCols(cols.size, cols.astype(np.int32))
        if got is not None:
            cs, rs, x = got
            self._set_statuses(hs, cs[kc], rs[kr], x[kc], pref)

    def _set_statuses(self, hs, cs, rs, x, pref) -> bool:
        """Set a basis from status codes (HiGHS's ``HighsBasisStatus`` values), made
        square: surplus basic columns (those of ``pref`` first) put at their nearer
        bound, missing ones made up by basic slacks; ``False`` if HiGHS refuses it."""
        BASIC = int(highs.highspy.HighsBasisStatus.kBasic)
        LOWER = int(highs.highspy.HighsBasisStatus.kLower)
        UPPER = int(highs.highspy.HighsBasisStatus.kUpper)
        cs, rs = cs.copy(), rs.copy()
        extra = int((cs == BASIC).sum() + (rs == BASIC).sum()) - rs.size
        if extra > 0:
            cand = np.flatnonzero(cs == BASIC)
            cand = np.concatenate([cand[pref[cand]], cand[~pref[cand]]])[:extra]
            lo = np.concatenate(self._lo)
            hi = np.concatenate(self._hi)
            s = np.concatenate(self._s)
            xs = x[cand]
            near_lo = np.abs(xs - lo[cand] / s[cand]) <= np.abs(hi[cand] / s[cand] - xs)
            cs[cand] = np.where(near_lo, LOWER, UPPER)
        elif extra < 0:
            cand = np.flatnonzero(rs != BASIC)[: -extra]
            rs[cand] = BASIC
        b = highs.highspy.HighsBasis()
        b.col_status = [highs.highspy.HighsBasisStatus(int(v)) for v in cs]
        b.row_status = [highs.highspy.HighsBasisStatus(int(v)) for v in rs]
        b.valid = True
        return hs.setBasis(b) == highs.highspy.HighsStatus.kOk

    def set_bounds(self, cols: NDArray[np.int64], lo: NDArray[np.float64],
                   hi: NDArray[np.float64]) -> None:
        """Change the bounds of some columns (finite), in the data and in every model.

        Parameters
        ----------
        cols : ndarray of int64
            The columns.
        lo, hi : ndarray
            Their new bounds.
        """
        cols = np.asarray(cols, dtype=np.int64)
        self._merge()
        self._lo[0][cols] = lo
        self._hi[0][cols] = hi
        s = self._s[0][cols]
        for hs in self._models:
            hs.changeColsBounds(cols.size, cols.astype(np.int32), lo / s, hi / s)
        self._cache = None

    def clone(self) -> BoxLP:
        """A copy of the LP's data, without HiGHS models: its first model starts from the
        basis of this one's (its first model's last basis, cut as this LP is cut later)."""
        other = BoxLP()
        self._merge()
        other._lo, other._hi, other._s = [self._lo[0].copy()], [self._hi[0].copy()], \
            [self._s[0].copy()]
        if self._b:
            other._b, other._berr = [self._b[0].copy()], [self._berr[0].copy()]
            r, c, v = self._ent[0]
            other._ent = [(r.copy(), c.copy(), v.copy())]
        other.n_col, other.n_row = self.n_col, self.n_row
        if self._models:
            other._seed = self._basis_codes(self._models[0], self.n_col, self.n_row)
        return other

    def _padded_seed(self, n_col, n_row, lo, scale):
        """The clone's seed basis padded to ``n_col`` columns and ``n_row`` rows (what
        was added since it was taken: columns at their lower bound ``lo`` / ``scale``,
        rows' slacks basic); ``None`` when it has more than that."""
        if self._seed is None:
            return None
        cs, rs, x = self._seed
        nc, nr = n_col - cs.size, n_row - rs.size
        if nc < 0 or nr < 0:
            return None
        LOWER = int(highs.highspy.HighsBasisStatus.kLower)
        BASIC = int(highs.highspy.HighsBasisStatus.kBasic)
        return (np.concatenate([cs, np.full(nc, LOWER, dtype=np.int64)]),
                np.concatenate([rs, np.full(nr, BASIC, dtype=np.int64)]),
                np.concatenate([x, lo[cs.size:] / scale[cs.size:]]))

    def _seeded(self, hs) -> bool:
        """Give a fresh model the clone's seed basis, padded for what was added since
        (:meth:`_padded_seed`); whether it took."""
        got = self._padded_seed(self.n_col, self.n_row, np.concatenate(self._lo),
                                np.concatenate(self._s))
        self._seed = None
        if got is None:
            return False
        cs, rs, x = got
        return self._set_statuses(hs, cs, rs, x, np.zeros(cs.size, dtype=bool))

    # ------------------------------------------------------------------ the data
    def arrays(self):
        """``(lo, hi, b, b_err, A, csc, k)``: the bounds, the right-hand side and its
        uncertainty, ``A`` (a ``scipy.sparse`` CSC array), its ``(indptr, indices,
        data)`` for the certificate, and the most entries in one column."""
        if self._cache is None:
            lo = np.concatenate(self._lo)
            hi = np.concatenate(self._hi)
            b = np.concatenate(self._b) if self._b else np.zeros(0)
            berr = np.concatenate(self._berr) if self._berr else np.zeros(0)
            r = np.concatenate([e[0] for e in self._ent])
            c = np.concatenate([e[1] for e in self._ent])
            v = np.concatenate([e[2] for e in self._ent])
            A = sparse.csc_array((v, (r, c)), shape=(self.n_row, self.n_col))
            A.sum_duplicates()
            csc = (A.indptr.astype(np.int64), A.indices.astype(np.int64), A.data)
            k = int(np.diff(A.indptr).max(initial=0))
            self._cache = (lo, hi, b, berr, A, csc, k)
        return self._cache

    @staticmethod
    def _row_bounds(b, berr):
        """Ranged rows ``b +- b_err`` (the set the certificate covers), for an LP that
        HiGHS calls infeasible at exactly ``b``: a thin set, carried by the set
        recursion with its rounding. (Not by default: ranged rows cost 2-7x the
        simplex iterations.)"""
        pos = berr > 0
        return np.where(pos, round_down(b - berr), b), np.where(pos, round_up(b + berr), b)

    # ------------------------------------------------------------------ solving
    def certify(self, cols: NDArray[np.int64], w: NDArray[np.float64],
                y: NDArray[np.float64]) -> float:
        """Certified lower bound of ``min w^T x_cols`` from row multipliers ``y``.

        Parameters
        ----------
        cols : ndarray of int64
            The objective's columns.
        w : ndarray
            Its coefficients.
        y : ndarray, shape (n_row,)
            Any multiplier.

        Returns
        -------
        float
            The bound (:func:`setobs.lp.certificate.lower_bound` over the box).
        """
        lo, hi, b, berr, A, csc, _ = self.arrays()
        wf = np.zeros(lo.size)
        wf[cols] = w
        bound, _, _ = _certificate.certified_lower_bound(wf, A, b, lo, hi, y, b_err=berr, csc=csc)
        return bound

    def build_model(self, cols: NDArray[np.int64], w: NDArray[np.float64],
                    ranged: bool = False):
        """A fresh HiGHS model of the LP with objective ``w`` on ``cols``.

        Parameters
        ----------
        cols : ndarray of int64
            The objective's columns.
        w : ndarray
            Its coefficients.
        ranged : bool
            Rows as the ranges ``b +- b_err`` (:meth:`_row_bounds`) instead of ``b``.

        Returns
        -------
        highspy.Highs or None
            The model (columns scaled by powers of two), or ``None`` if HiGHS refused
            the data.
        """
        lo, hi, b, berr, A, _, _ = self.arrays()
        s = np.concatenate(self._s)
        hs = highs.new_model(scaled=HIGHS_SCALING)  # (cold: the dual simplex)
        cost = np.zeros(self.n_col)
        cost[cols] = w
        As = A @ sparse.diags_array(s)  # (exact: powers of two)
        rlo, rhi = self._row_bounds(b, berr) if ranged else (b, b)
        if not highs.pass_csc(hs, self.n_row, cost * s, lo / s, hi / s, rlo, rhi,
                              As.indptr, As.indices, As.data):
            return None
        return hs

    def minimize_all(self, cols: NDArray[np.int64], W: NDArray[np.float64]
                     ) -> NDArray[np.float64] | None:
        """Certified ``min W[j]^T x_cols`` for every row ``j``, or ``None`` when a solve
        is not optimal with a tight certificate.

        One HiGHS model per row of ``W``, kept across calls and grown with the LP:
        when ``cols`` moved since the last call (a new block's columns), each
        model's objective moves with them and it restarts from its last optimal
        basis.

        Parameters
        ----------
        cols : ndarray of int64
            The objectives' columns.
        W : ndarray, shape (n_obj, cols.size)
            The objectives.

        Returns
        -------
        ndarray or None
            The certified minima.
        """
        if CHAIN and W.shape[0] >= CHAIN_MIN_OBJECTIVES:
            return self._minimize_chain(cols, W)
        n_obj = W.shape[0]
        if len(self._models) != n_obj:
            models = [self.build_model(cols, w) for w in W]
            if any(hs is None for hs in models):
                return None
            self._models = models
            self._warm = [False] * n_obj
            self._ranged = [False] * n_obj
            self._cols = cols
        moved = not np.array_equal(cols, self._cols)
        idx = cols.astype(np.int32)
        prev = self._cols.astype(np.int32)
        scale = np.concatenate(self._s)[cols]
        limit = highs.simplex_limit(self.n_row, self.n_col)
        out = np.empty(n_obj)
        gaps = np.empty(n_obj)
        pts = self._points_buffer(n_obj)
        duals = np.empty((n_obj, self.n_row)) if self.keep_duals else None
        for j, hs in enumerate(self._models):
            if moved:  # (the objective moves to the new columns)
                hs.changeColsCost(prev.size, prev, np.zeros(prev.size))
                hs.changeColsCost(idx.size, idx, W[j] * scale)
            got = self._solve(j, cols, W[j], limit)
            if got is None:
                self._models = []  # (fresh models next time)
                return None
            out[j], gaps[j] = got
            self._keep_point(pts, j, self._models[j])
            if duals is not None:
                duals[j] = self._y
        self._cols = cols
        self.last_gaps = gaps
        self.last_points = pts
        if duals is not None:
            self.last_duals = duals
        return out

    def _minimize_chain(self, cols: NDArray[np.int64], W: NDArray[np.float64]
                        ) -> NDArray[np.float64] | None:
        """:meth:`minimize_all` as an objective chain: one HiGHS model, grown once per
        block; the objectives in :func:`setobs.lp.fastlp.chain_order`, the first from
        the model's last optimal basis, each next one from the previous one's optimal
        vertex (the same data: a primal feasible start, so the primal simplex's phase 2
        only)."""
        from .fastlp import chain_order

        n_obj = W.shape[0]
        order = chain_order(n_obj)
        if len(self._models) != 1:
            hs = self.build_model(cols, W[order[0]])
            if hs is None:
                return None
            self._models, self._warm, self._ranged = [hs], [self._seeded(hs)], [False]
            self._cols = cols
        moved = not np.array_equal(cols, self._cols)
        idx = cols.astype(np.int32)
        if moved:  # (the objective moves to the new columns)
            prev = self._cols.astype(np.int32)
            self._models[0].changeColsCost(prev.size, prev, np.zeros(prev.size))
        scale = np.concatenate(self._s)[cols]
        limit = highs.simplex_limit(self.n_row, self.n_col)
        out = np.empty(n_obj)
        gaps = np.empty(n_obj)
        pts = self._points_buffer(n_obj)
        duals = np.empty((n_obj, self.n_row)) if self.keep_duals else None
        for j in order:
            self._models[0].changeColsCost(idx.size, idx, W[j] * scale)
            got = self._solve(0, cols, W[j], limit)
            if got is None:
                self._models = []  # (a fresh model next time)
                return None
            out[j], gaps[j] = got
            self._keep_point(pts, j, self._models[0])
            if duals is not None:
                duals[j] = self._y
        self._cols = cols
        self.last_gaps = gaps
        self.last_points = pts
        if duals is not None:
            self.last_duals = duals
        return out

    def _points_buffer(self, n_obj: int) -> NDArray[np.float64]:
        return np.full((n_obj, 0 if self.record is None else self.record.size), np.nan)

    def _keep_point(self, pts, j: int, hs) -> None:
        """Row ``j`` of :attr:`last_points`: the solver's point on :attr:`record`."""
        if self.record is not None:
            x = self._point(hs)
            if x is not None:
                pts[j] = x[self.record]

    def _solve(self, j: int, cols, w: NDArray[np.float64], limit: int
               ) -> tuple[float, float] | None:
        """Certified ``min w^T x_cols`` on model ``j``: from its last optimal basis with
        the primal simplex (its phase 1 for the new rows: 2-8x fewer iterations than
        the dual on the whole-history LP) for at most :data:`WARM_PRIMAL_LIMIT`
        iterations, then the dual simplex from where it stopped, then a fresh model
        from the basis the warm start began with by the primal simplex, then a fresh
        model cold by the primal simplex, then one with ranged rows
        (:meth:`_row_bounds`); ``None`` if none is optimal with a tight certificate.
        Returns ``(bound, gap)``: the certified bound and its certified gap
        (:meth:`_gap`). A multiplier whose bound leaves a gap above the tolerance is
        first refined from the solver's basis (:meth:`refined_multiplier`); the better of the two
        certified bounds is kept (each is a valid lower bound).

        (The fresh model from the warm basis: on the 30-tank cascade's whole-history LP
        at ``k`` = 186, 9 500 x 15 000, HiGHS's warm primal stopped undecided after 163
        iterations and its dual at once; a cold model had not finished after six
        minutes, where a fresh model restarts from an optimal basis of the step at no
        cost beyond one factorisation: ``benchmarks/exact_long.py``.)"""
        start = self._models[j].getBasis() if self._warm[j] else None
        for attempt in range(5):
            if attempt == 2 and start is None:
                continue
            if attempt >= 2:  # a fresh model: from the warm start's basis, cold, ranged
                hs = self.build_model(cols, w, ranged=attempt == 4)
                if hs is None:
                    return None
                if attempt == 2 and not highs.set_basis(hs, start):
                    continue
                self._models[j] = hs
                self._ranged[j] = attempt == 4
            hs = self._models[j]
            warm = attempt == 0 and self._warm[j]
            # (a fresh model by the primal simplex: HiGHS's dual ratio test can fail at
            # once, "excessive dual values", on a cold start of this LP)
            if highs.solve(hs, primal=warm or attempt in (2, 3),
                           iteration_limit=min(limit, WARM_PRIMAL_LIMIT) if warm else limit
                           ) != "optimal":
                self.retries += 1
                continue
            obj = float(hs.getInfo().objective_function_value)
            y = np.asarray(hs.getSolution().row_dual, dtype=np.float64)
            bound = self.certify(cols, w, y)
            tol = HISTORY_GAP_RTOL * (1.0 + abs(obj))
            if not (np.isfinite(bound) and obj - bound <= tol):
                y2 = self.refined_multiplier(hs, cols, w)
                if y2 is not None:
                    b2 = self.certify(cols, w, y2)
                    if np.isfinite(b2) and not b2 <= bound:
                        bound, y = b2, y2
            if np.isfinite(bound) and (obj - bound <= tol
                                       or obj - bound <= tol + self._explained(hs, cols, w, y)):
                self._warm[j] = True
                self._y = y
                return bound, self._gap(hs, obj, bound, y)
            self.retries += 1
        return None

    def refined_multiplier(self, hs, cols: NDArray[np.int64], w: NDArray[np.float64]
                           ) -> NDArray[np.float64] | None:
        """The multiplier of the solver's final basis, recomputed and refined in extended
        precision (:func:`setobs.lp.highs.basis_duals`, by a sparse LU here). The solver's
        own duals carry its tolerances (1e-10 relative to its scaled model); this one
        makes the basic columns' reduced costs vanish to rounding, which is what the
        certificate charges for.

        Parameters
        ----------
        hs : highspy.Highs
            A model of this LP that has been solved.
        cols : ndarray of int64
            The objective's columns.
        w : ndarray
            Its coefficients.

        Returns
        -------
        ndarray or None
            The row multiplier, or ``None`` when the basis is not square or singular.
        """
        A = self.arrays()[4]
        wf = np.zeros(A.shape[1])
        wf[cols] = w
        return highs.basis_duals(hs, A, wf)

    def _gap(self, hs, obj: float, bound: float, y: NDArray[np.float64]) -> float:
        """The certified gap of an accepted bound: ``obj - bound`` plus the cost of the
        solver's point's residual, ``|y|^T max(|A x - b| - b_err, 0)`` (at a point off
        its rows the objective may undercut the minimum by about that). The LP's minimum
        lies within that of the bound, above it."""
        x = self._point(hs)
        gap = max(obj - bound, 0.0) + (0.0 if x is None else self._point_cost(x, y))
        return round_up(gap) if gap > 0 else 0.0

    def _point(self, hs) -> NDArray[np.float64] | None:
        """The solver's point in this LP's (unscaled) columns, or ``None``."""
        x = np.asarray(hs.getSolution().col_value, dtype=np.float64)
        return x * np.concatenate(self._s) if x.size == self.n_col else None

    def _point_cost(self, x: NDArray[np.float64], y: NDArray[np.float64]) -> float:
        """``|y|^T max(|A x - b| - b_err, 0)``: how much a point off its rows may let the
        objective undercut the minimum."""
        _, _, b, berr, A, _, _ = self.arrays()
        return float(np.abs(y) @ np.maximum(np.abs(A @ x - b) - berr, 0.0))

    def _explained(self, hs, cols, w: NDArray[np.float64], y: NDArray[np.float64]) -> float:
        """What the solver's precision explains of a certification gap ``obj - bound``:

        * the multiplier's inaccuracy, ``sum |r_j| (hi_j - lo_j)`` over the *basic*
          columns, whose reduced costs ``r = w - A^T y`` vanish for the exact multiplier
          of the solver's basis (the certificate charges each ``|r_j|`` times the
          distance to a bound);
        * the point's residual, ``|y|^T max(|A x - b| - b_err, 0)``: "optimal" at a point
          slightly off the rows, the objective can undercut the minimum by about that
          much (the criterion of :meth:`setobs.lp.factor.FactorPolytope.minimize`).

        On the whole-history LP of a 30-tank cascade with 21 outputs (1 200 rows, column
        scales up to 2^20, HiGHS's tolerances 1e-10) the gap reached 1.06e-7 at ``k`` =
        22 (1.05e-7 of it the first term) and 1.23e-8 at ``k`` = 25 (1.44e-8 the second),
        above ``HISTORY_GAP_RTOL``, and every such step went to the set recursion (seconds
        each). A wrong basis leaves dual-infeasible *nonbasic* columns or a gross
        residual, which this does not excuse; a point off its box is not accepted. The
        bound itself is certified either way."""
        lo, hi, _, _, A, _, _ = self.arrays()
        basic, _ = highs.basis(hs)
        x = self._point(hs)
        if basic.size != lo.size or x is None:
            return 0.0
        slop = 1e-9 * (1.0 + np.maximum(np.abs(lo), np.abs(hi)))
        if not (np.isfinite(x).all() and (x >= lo - slop).all() and (x <= hi + slop).all()):
            return 0.0
        wf = np.zeros(lo.size)
        wf[cols] = w
        r = wf - A.T @ y
        multiplier = float(np.sum(np.abs(r[basic]) * (hi[basic] - lo[basic])))
        return (multiplier + self._point_cost(x, y)) * (1.0 + 1e-6)

    # ------------------------------------------------------------------ pickling
    def __getstate__(self) -> dict:
        state = self.__dict__.copy()
        state["_models"] = []  # (HiGHS models do not pickle: rebuilt on demand)
        state["_cache"] = None
        return state
