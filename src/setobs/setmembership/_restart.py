"""The window's restart set: a polytope that keeps the exact set's shape.

Eq. (24) of Li-Cong-Dong restarts the window from the interval hull of
``Z_t`` (``t = k - delta``), a box that forgets every correlation of the
state (how much wider than the exact set that leaves the window on the benchmark
plants: ``benchmarks/results/state_estimation.json``). This module restarts it
instead from

.. math::  S_t = \\mathrm{IH}(Z_t) \\cap \\bigcap_{j=1}^{m-1}
           \\{z : \\ell_j \\le F_j z \\le u_j\\},

whose normals ``F_j`` are the coordinate axes carried back ``j`` steps through
the dynamics (the rows of ``A_o^-j``, each scaled to unit max-norm), and whose
offsets come from the hulls already computed at the earlier steps ``t - j``.

Soundness. Let ``X_t`` be the exact set at ``t`` (every state consistent with
all the data up to ``t``). Every ``z_t in X_t`` has a history with
``z_(t-j) in X_(t-j) ⊆ IH(Z_(t-j))`` (each window's hull is an outer bound,
by induction on ``t``) and, by eq. (20),

.. math::  F_j z_t = (F_j A_o^j) z_{t-j} + \\sum_{i=0}^{j-1} F_j A_o^i
           (\\Gamma_o u_{t-1-i} + B c_D + B G_D \\xi_i), \\quad |\\xi_i| \\le h_D,

with ``B = B_step`` and ``(c_D, G_D, h_D)`` the per-step uncertainty set (its
constraints dropped: an outer bound). Each term is bounded over a box in
closed form, so ``[l_j, u_j]`` is a valid range of ``F_j z_t`` and
``X_t ⊆ S_t``. Every matrix here is a float matrix taken as exact; the
computed products ``F_j A_o^i`` (``fl(F_j Â_i)`` with the computed powers) differ
from the exact ones by at most ``|F_j| E_i + gamma_N |F_j| |Â_i|`` elementwise, with
``E_i`` the powers' own bound of :mod:`._powers` (which decays with ``A_o^i`` instead
of growing like ``|A_o|^i``, the bound this module used before), and the ranges are
widened by those bounds, by the data's representation error and by the rounding of
their own assembly. A row with an unbounded term (an
unbounded increment factor or an unbounded hull coordinate) is left out.

Support values. The window's step at ``t`` also bounds ``F_j z`` over its own posterior
``Z_t`` (the rows of ``F`` as extra objectives of the same LPs, certified by the same
weak-duality bound as its hull, then widened by the reported margin): ``[s_lo, s_hi]
⊇ {F_j z : z in Z_t} ⊇ {F_j z : z in X_t}``, since ``Z_t ⊇ X_t`` by the same induction.
So it is a valid range of ``F_j z_t`` too, and so is the intersection of the two ranges
(:func:`setobs.setmembership._schedule.restart_rows`); where they would cross (only for
data that contradict the model) the carried range is kept and the LP decides. The
carried range bounds ``F_j z_t`` through the boxes of ``Z_(t-j)`` and the noise's box
terms; the support value sees the window's polytope itself, so it is narrower where
the carried terms add up (a constant-velocity target, every eigenvalue 1).

As a set with fixed structure: factors ``(xi_0, eta)``, ``z = c + xi_0`` with
``|xi_0| <= r`` (the hull at ``t``: centre ``c``, radii ``r``) and
``F xi_0 - eta = mid - F c``, ``|eta| <= rad`` (the rows' midpoints and
radii); ``G_S = [I 0]``, ``A_S = [F -I]``. Only ``c``, ``b`` and ``h`` depend
on the data, so the window's closed form keeps one LP structure (and one warm
start) per set of kept rows.

Measured (``benchmarks/state_estimation.py``): the shape, not the number of
facets, is what matters; axis-plus-diagonal normals do far worse than the
carried-back axes.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from .._rounding import gamma
from ..geometry import ConstrainedZonotope
from ..geometry.box import box_center_radius
from ._powers import power_table, quiet, up

__all__ = ["DEFAULT_RESTART_DEPTH", "RestartPolytope"]

# The compiled rows' ranges (numba) load on the first polytope restart, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")
_EMPTY = np.zeros(0)

#: Number of hulls (``m``: the one at ``t`` and ``m - 1`` earlier ones) a window
#: restart combines by default. Every lag ``1 .. m - 1`` is used: on a lightly damped
#: 4-state plant (window 10) all 29 give mean / worst width ratios 1.044 / 1.18 to the
#: exact set, about three lags per doubling 1.073 / 1.58, powers of two 1.19 / 2.94 (the
#: normals of an oscillatory plant keep turning: far lags add shape, not duplicates).
#: A constant-velocity target's carried rows turn slowly (most are left out as nearly
#: parallel): 29 lags keep 10 rows (window 10 1.08 / 1.27 times the exact set with the
#: support values), 59 keep 22 (1.03 / 1.18; ``benchmarks/chain_ab.py``).
DEFAULT_RESTART_DEPTH = 60

#: Most carried-back rows a restart adds: each is a row and a slack column of every LP
#: of the window. The rows of the smallest lags are kept first (after the parallel
#: filter), so a large state keeps few lags (N = 30: 4), and a plant whose carried rows
#: are mostly parallel (a constant-velocity target: 2 of its 4 per lag turn slowly) keeps
#: rows from lags far beyond ``MAX_ROWS / N``.
MAX_ROWS = 120

#: Rows whose normal is within this cosine of a kept one's (or of an axis) are left
#: out (see :class:`RestartPolytope`).
PARALLEL_COS = 0.999

#: Largest condition number of ``A_o`` for which the carried-back normals are used
#: (a nearly singular ``A_o``, e.g. a pure delay, restarts from the box).
MAX_COND = 1e8


def _row_normalize(M: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rows scaled by powers of two to max-norm in [1/2, 1] (exact scaling)."""
    s = np.abs(M).max(axis=1)
    s[s == 0.0] = 1.0
    _, e = np.frexp(s)
    return np.ldexp(M, -e[:, None])


class RestartPolytope:
    """Fixed part of the restart set ``S_t`` of a window (see the module docstring).

    Immutable after construction.

    Parameters
    ----------
    A_o, Gamma_o : ndarray
        Observable-coordinate dynamics and input matrix.
    B_step : ndarray
        Map of the per-step uncertainty into the state.
    step_set : ConstrainedZonotope
        The per-step uncertainty set (fixed).
    depth : int
        ``m``: the hull at ``t`` and up to ``m - 1`` earlier ones.
    data_rtol : float
        Relative representation error of every input.
    """

    @quiet  # (overflowing rows of an unstable plant: inf, the rows then left out)
    def __init__(self, A_o, Gamma_o, B_step, step_set: ConstrainedZonotope, depth: int,
                 data_rtol: float) -> None:
        N, p = A_o.shape[0], Gamma_o.shape[1]
        self.N, self.p, self.data_rtol = N, p, float(data_rtol)
        # (every lag up to depth - 1 is carried; of the rows left after the parallel
        # filter below, the first MAX_ROWS are kept)
        lags = max(int(depth) - 1, 0)
        if lags and (not np.isfinite(A_o).all() or np.linalg.cond(A_o) > MAX_COND):
            lags = 0
        self.lags = lags
        if not lags:
            self.F_all = np.zeros((0, N))
            return
        Ainv = np.linalg.inv(A_o)
        tab = power_table(A_o, lags)
        absGam = np.abs(Gamma_o)
        absB = np.abs(B_step)
        cD, GD, hD = step_set.c, step_set.G, step_set.h
        gN = 2.0 * gamma(N + 2)
        gD = 2.0 * gamma(max(N, GD.shape[1]) + 2)
        BcD = B_step @ cD
        BcD_err = gD * (absB @ np.abs(cD))      # rounding of B c_D
        BcD_e = absB @ step_set.c_err            # the set's centre error
        BG = B_step @ GD
        absBG = absB @ np.abs(GD)
        BG_err = gD * absBG
        hD_f = np.where(np.isinf(hD), 0.0, hD)
        inf_cols = np.isinf(hD)
        # Per lag j = 1..lags (stacked, then the kept rows taken): F_j and fl(F_j A_o^j)
        # with its error bound (:mod:`._powers`: it does not compound with j), the
        # inputs' map [F_j Gamma, F_j A Gamma, ...] (by u age) with its error and
        # magnitude, sum_i F_j A^i B c_D with its error and carried set error, the
        # reach sum_i |F_j A^i B G_D| h_D with its error, and whether a row reaches an
        # unbounded factor.
        F, Gj, Ej = [], [], []
        Hu = np.zeros((lags, N, lags * p))
        Hu_e = np.zeros((lags, N, lags * p))
        Hu_m = np.zeros((lags, N, lags * p))
        K, K_err, K_e = np.zeros((lags, N)), np.zeros((lags, N)), np.zeros((lags, N))
        S, S_err = np.zeros((lags, N)), np.zeros((lags, N))
        unb = np.zeros((lags, N), dtype=bool)
        # Rows nearly parallel to a row of a smaller lag (or to an axis) are left out:
        # for a plant with one fast-decaying mode the rows of A_o^-j converge to its
        # left eigenvector, and near-duplicate rows make the LP degenerate (slow, and
        # undecided by the fast path) without adding shape. The lags are carried until
        # MAX_ROWS rows are kept.
        keep_rows: list[bool] = []
        kept = np.eye(N)
        Fj = np.eye(N)
        J = 0
        for j in range(1, lags + 1):
            if kept.shape[0] - N >= MAX_ROWS:
                break
            J = j
            Fj = _row_normalize(Fj @ Ainv)
            for v in Fj / np.linalg.norm(Fj, axis=1)[:, None]:
                ok = kept.shape[0] - N < MAX_ROWS and np.abs(kept @ v).max() < PARALLEL_COS
                keep_rows.append(bool(ok))
                if ok:
                    kept = np.vstack([kept, v])
            k_abs = np.zeros(N)
            for i in range(j):  # H = fl(F_j Â_i), EH >= |H - F_j A^i|
                H, EH = tab.left(Fj, i)
                aH = np.abs(H)
                mH = aH + EH
                if p:
                    X = H @ Gamma_o
                    Xe = up(EH @ absGam + gN * (aH @ absGam), N)
                    Hu[j - 1][:, i * p:(i + 1) * p] = X
                    Hu_e[j - 1][:, i * p:(i + 1) * p] = Xe
                    Hu_m[j - 1][:, i * p:(i + 1) * p] = up(np.abs(X) + Xe, 1)
                t = H @ BcD
                K[j - 1] += t
                k_abs += np.abs(t)
                K_err[j - 1] += up(EH @ np.abs(BcD) + gN * (aH @ np.abs(BcD))
                                   + mH @ BcD_err, N) + gamma(j + 1) * k_abs
                K_e[j - 1] += up(mH @ BcD_e, N)
                HB = H @ BG
                S[j - 1] += np.abs(HB) @ hD_f
                eHB = EH @ absBG + gN * (aH @ np.abs(BG)) + mH @ BG_err
                S_err[j - 1] += up(eHB @ hD_f + gamma(N + 2) * (np.abs(HB) @ hD_f), N)
                if inf_cols.any():
                    unb[j - 1] |= ((mH @ absBG)[:, inf_cols] != 0).any(axis=1)
            H, EH = tab.left(Fj, j)
            F.append(Fj)
            Gj.append(H)
            Ej.append(EH)
        # (the sums of S over the lags: their own rounding)
        S_err += gamma(lags + 2) * S
        Fall = np.array(F).reshape(-1, N)
        keep = np.array(keep_rows, dtype=bool)
        self.F_all = Fall[keep]
        self.row_lag = np.repeat(np.arange(J), N)[keep]  # (lag - 1) of each kept row
        if not self.F_all.shape[0]:  # (every carried row parallel to an axis)
            self.lags = 0
            self.F_all = np.zeros((0, N))
            return
        # the lags the kept rows reach (a row of lag j reads the inputs of the j last
        # steps only: the further input columns are zero)
        self.lags = used = int(self.row_lag.max()) + 1
        self.G = np.array(Gj).reshape(-1, N)[keep]
        self.G_a = np.abs(self.G)
        self.G_e = np.array(Ej).reshape(-1, N)[keep]
        Hu, Hu_e, Hu_m = (M[:J].reshape(J * N, lags * p)[keep][:, :used * p]
                          for M in (Hu, Hu_e, Hu_m))
        self.Hu, self.Hu_e, self.Hu_m = (np.ascontiguousarray(M) for M in (Hu, Hu_e, Hu_m))
        self.K, self.K_err, self.K_e = (M[:J].reshape(-1)[keep] for M in (K, K_err, K_e))
        self.S, self.S_err = S[:J].reshape(-1)[keep], S_err[:J].reshape(-1)[keep]
        self.unbounded = unb[:J].reshape(-1)[keep]
        # the evaluation of a row's range in :meth:`rows` (sums of 1 + N + lags p
        # terms), doubled for the bounds' own rounding
        self._g = 2.0 * gamma(N + used * p + 6)

    def rows(self, box_t, boxes, inputs):
        """Ranges of ``F_j z_t`` (the carried-back rows) from the earlier hulls.

        Every row is always given (one structure per model): a row whose earlier
        hull is not known yet (the first steps, after a reset) or whose range is
        unbounded gets its range over the hull at ``t`` itself (redundant, and
        sound); a row unbounded there too is returned with ``lo = -inf``,
        ``hi = inf`` (a free slack).

        Parameters
        ----------
        box_t : Box
            ``IH(Z_t)``.
        boxes : sequence of Box
            ``IH(Z_(t-1)), IH(Z_(t-2)), ...`` (newest first; as many as known).
        inputs : sequence of ndarray
            ``u_(t-1), u_(t-2), ...``: the inputs entering ``z_t``, ``z_(t-1)``, ...
            (at least as many as ``boxes``).

        Returns
        -------
        lo, hi : ndarray, shape (len(F_all),)
            Ranges of the rows of :attr:`F_all`.
        """
        N, L = self.N, self.lags
        avail = np.arange(1, L + 1) <= len(boxes)
        lo_b = np.array([boxes[j].lo if avail[j] else box_t.lo for j in range(L)])
        hi_b = np.array([boxes[j].hi if avail[j] else box_t.hi for j in range(L)])
        U = _EMPTY
        if self.p:
            n_u = min(len(inputs), L)
            U = np.zeros(L * self.p)
            U[:n_u * self.p] = np.asarray(inputs[:n_u], dtype=float).reshape(-1)
        return _kernels.restart_rows(
            lo_b, hi_b, avail, np.ascontiguousarray(box_t.lo), np.ascontiguousarray(box_t.hi),
            self.F_all, self.row_lag, self.G, self.G_a, self.G_e, self.K, self.K_err,
            self.K_e, self.S, self.S_err, self.unbounded, self.Hu, self.Hu_e, self.Hu_m, U,
            self.data_rtol, self._g, gamma(N + 3))

    @staticmethod
    def start_data(box_lo, box_hi, F, lo, hi):
        """The restart set's data: ``c_S``, ``b_S``, ``h_S`` (factors ``xi_0`` then the
        rows' slacks; ``G_S = [I 0]``, ``A_S = [F -I]``), rounding covered by ``h``
        (a row with an infinite range has a free slack)."""
        c, r = box_center_radius(box_lo, box_hi)
        if not F.shape[0]:  # the box restart (eq. (24))
            return c, np.zeros(0), r
        fin = np.isfinite(r)
        c0 = np.where(fin, c, 0.0)
        mid, rad = box_center_radius(lo, hi)  # (an infinite range: centre 0, radius inf)
        b = mid - F @ c0
        # the slack's range covers [lo, hi] around the rounded b: rounding of F c and
        # of the difference (relative to their magnitudes), upward
        slop = gamma(F.shape[1] + 3) * (np.abs(mid) + np.abs(F) @ np.abs(c0) + rad)
        return c, b, np.concatenate([r, np.nextafter(rad + slop, np.inf)])

    @staticmethod
    def structure(F):
        """``G_S`` and ``A_S`` of the restart set for the kept rows ``F``."""
        R, N = F.shape
        G_S = np.hstack([np.eye(N), np.zeros((N, R))])
        A_S = np.hstack([F, -np.eye(R)])
        return G_S, A_S
