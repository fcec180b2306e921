"""Closed form of ``s`` SMFDO steps from a start set: the fast path of Algorithm 1.

Running eqs. (20)-(21) of Li-Cong-Dong ``s`` times from a start set
``S = {c_S + G_S xi_S : A_S xi_S = b_S, |xi_S| <= h_S}`` gives the constrained
zonotope (the closed form (24) when ``S`` is the interval hull of
``Z_(k-delta)``)

.. math::  Z = \\{c + G \\xi : A \\xi = b, |\\xi| \\le h\\},
           \\quad \\xi = (\\xi_S, \\xi_{\\Delta,1}, \\dots, \\xi_{\\Delta,s}),

with ``G = [A_o^s G_S, A_o^(s-1) B_o G_D, ..., B_o G_D]`` and ``A`` stacking
``A_S``, the increment set's constraints and ``C_o G_j`` for every posterior
``j``. ``G`` and ``A`` depend only on the system, the increment set, the start
set's generators and ``s``; the data enter only ``b`` and ``c`` (affinely) and
the reset box enters only ``c_S`` and ``h_S``. So the LPs of the interval hull
have a fixed structure and go through
:class:`setobs.lp.fastlp.FixedStructureLP`.

Rounding. ``c`` and ``b`` are affine in the data with coefficient matrices
computed once (``Mc = A_o^j``, ``-C_o A_o^j``, ``A_o^(j-1-i) Gamma_o``,
``sum_t A_o^t B c_D``). Each computed coefficient ``X`` carries an elementwise bound
``E >= |X - X*|`` on its distance to the exact ``X*`` of the float model, and
``|X| + E >= |X*|``. The powers are the computed ``Â_j`` of
:class:`~._powers.PowerTable`, whose bound ``F_j`` sums the rounding of each product
carried by the *exact* later powers (``F_j = sum_i P_(j-i) D_i``, ``P >= |A_o^k|``:
see :mod:`._powers` for the proof); every other coefficient is one product of a
bounded power with a float matrix (``E = |M| F + gamma |M| |Â|``) or a sum of such
(recursive summation, Higham (4.4)). So, for data ``c_S``, ``u`` known to ``c_S_err``,
``data_rtol |u|``,

.. math::  |c - c^*| \\le E_c |c_S| + E_u |u| + E_\\kappa
           + (|M_c| + E_c) c_{S,err} + (|M_u| + E_u)\\,\\mathrm{data\\_rtol}\\,|u|
           + \\gamma\\,(|M_c| |c_S| + |M_u| |u| + |\\kappa|),

the last term the rounding of evaluating ``c`` itself (the kernel's sums), and the same
for ``b``; the kernel (:func:`._kernels.assemble`) adds exactly these terms, rounded up.
None of them grows with ``|A_o|^j``: on a stable plant they decay with the powers
(before, the textbook ``gamma |A_o|^j`` grew like ``rho(|A_o|)^j``, 48 per step on a
7-state plant with ``cond(A_o) = 2e4``, and window 10 bands reached ``1e5``;
``tests/setmembership/test_window_allowance.py``). A restart carries no error: its
box and rows are certified hulls, exact data. The representation error of the data
(a relative ``data_rtol`` on every ``y`` and ``u``) is added. The rounding of the generator
and constraint matrices (``C_o A_o^j G_S``, relative ``gK``) acts on the
factors; their image in a measurement row has the size of ``y`` unless the
prediction cancels, so ``gK |y|`` is added on every measurement row (the
*model allowance*). The LP certificate covers the resulting ``b_err`` and the
hull covers ``c_err``, so the bounds contain the set for the exact data even
when large states cancel against large measurements (``|y| ~ 1e15``). Where the
allowances take more than ``ALLOWANCE_RTOL`` of a reported band (large ``|y|`` against
a narrow band) the step says ``"inexact"`` (:func:`allowance_fraction`).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._blas import SMALL_BLAS_DIM
from .._lazy import lazy_module
from .._rounding import gamma
from ..exceptions import InvalidValueError
from ..geometry import ConstrainedZonotope
from ..geometry.zonotope import trusted_cz
from ..lp.fastlp import FixedStructureLP, LPState, hull_objectives
from ._powers import power_table, quiet, up

# The compiled assembly (numba) loads on the first window, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")
_EMPTY = np.zeros(0)

#: The window's hull LPs stop when their duality gap is at most this fraction of the
#: coordinate's width at the previous window step (``rel_gap`` of
#: :meth:`setobs.lp.fastlp.FixedStructureLP.minimize_all_unchecked`): each bound is
#: certified, and within that gap of the window LP's optimum: within one step a band is
#: at most ``2 WINDOW_REL_GAP`` of its width *at the previous step* wider than the
#: window's exact hull, and the restarts carry that into later windows. An absolute
#: amount, not a fraction of the band: where the set collapses to a point at a step that
#: band is many times its own (rounding-level) width wider. The excess over the stop off
#: and the iterations it saves, measured on random stable plants and the cascades:
#: ``benchmarks/results/early_stop.json`` (the performance page).
WINDOW_REL_GAP = 1e-3


def allowance_fraction(lo, hi, alw, margin: float, rows=None) -> float:
    """The largest fraction of a finite band's reported width (``hi - lo`` plus the
    reported outward margin ``2 margin max(1, |lo|, |hi|)``) taken by its rounding
    allowances ``alw`` (:meth:`WindowModel.hull`), over the bands ``rows`` (default
    all: the reported ones, :attr:`~._model.SMFDOModel.reported_rows`); allowances
    within the margin ``margin max(1, |lo|, |hi|)`` count as 0."""
    if rows is not None:
        lo, hi, alw = lo[rows], hi[rows], alw[rows]
    width = hi - lo
    fin = np.isfinite(width)
    if not fin.any():
        return 0.0
    scale = np.maximum(1.0, np.maximum(np.abs(lo[fin]), np.abs(hi[fin])))
    rep = width[fin] + 2.0 * margin * scale
    a = alw[fin]
    # (an allowance within the reported margin, margin * max(1, |end|), is the rounding
    # that margin is there for: a band pinned to a point by its data, whose width is
    # that margin, is not "inexact" for a rounding-level allowance)
    with np.errstate(divide="ignore", invalid="ignore"):
        frac = np.where((rep > 0) & (a > margin * scale), a / rep, 0.0)
    return float(np.max(frac, initial=0.0))


def model_rtol(s: int, N: int, p: int, nD: int) -> float:
    """Relative rounding bound of ``s`` steps of the recursion's products (Higham's
    ``gamma`` of their depth, doubled): the *model allowance* per measurement."""
    return 2.0 * gamma((s + 2) * (N + p + nD + 3) + 8)


class WindowModel:
    """``s`` prior/posterior steps of Algorithm 1 from a start set, in closed form.

    Immutable after construction (shared by all SMFDOs of a process with the
    same structure); the LP warm-start state is passed to :meth:`hull`.

    Parameters
    ----------
    A_o, B_o, C_o, Gamma_o : ndarray
        Observable-coordinate matrices of the augmented system. ``B_o`` maps
        the per-step uncertainty ``increment`` into the state: with process
        noise it is ``[B_o, E_o]`` and ``increment`` is ``[[dd]] x W``.
    increment : ConstrainedZonotope
        The (fixed) per-step uncertainty set (the increment set ``[[dd]]``,
        possibly times the process-noise set).
    G_S, A_S : ndarray
        Generators and constraints of the start set.
    free_S : ndarray of bool
        Unbounded factors of the start set.
    s : int
        Number of prior/posterior steps.
    first_posterior : bool
        Intersect the start set with the measurement before the first prior
        (the start is ``Z_0^-``, Algorithm 1 line 2), so ``s + 1`` measurements
        are used; otherwise ``s``.
    P : ndarray or None
        Extra objective rows (``P`` of Algorithm 1, line 14) when the hull of
        ``P Z`` is not a coordinate selection of the hull of ``Z``.
    unbounded_radius : float
        Radius on unbounded factors (certification).
    noise : ConstrainedZonotope or None
        Measurement-noise set in the coordinates of ``C_o`` (``y = C_o z + v``,
        ``v in noise``): each posterior is the generalised intersection
        ``Z ∩_(C_o) (y - noise)`` (Scott et al. 2016, eq. (13)), which adds the
        noise factors and constraints (the noise factors have zero generator
        columns: they enter only the constraints).
    masks : sequence of bool arrays, optional
        Measured outputs of each posterior (``s + first_posterior`` of them,
        oldest first); default all. Unmeasured rows are left out; a posterior
        with nothing measured is a pure prediction.
    """

    @quiet  # (overflowing coefficients of an unstable plant: inf, the LPs then decline)
    def __init__(self, A_o, B_o, C_o, Gamma_o, *, increment: ConstrainedZonotope,
                 G_S, A_S, free_S, s: int, first_posterior: bool,
                 P: NDArray[np.float64] | None, unbounded_radius: float,
                 noise: ConstrainedZonotope | None = None, masks=None) -> None:
        N, nS = G_S.shape
        GD, AD = increment.G, increment.A
        nD, cD = GD.shape[1], increment.c
        l, p = C_o.shape[0], Gamma_o.shape[1]
        n_y = s + int(first_posterior)
        if masks is None:
            masks = [np.ones(l, dtype=bool)] * n_y
        masks = [np.asarray(m, dtype=bool) for m in masks]
        if len(masks) != n_y or any(m.shape != (l,) for m in masks):
            raise InvalidValueError(f"masks must be {n_y} boolean vectors of length {l}")
        nV = 0 if noise is None else noise.n_gen
        n_noisy = sum(bool(m.any()) for m in masks) if nV else 0
        n_x = nS + s * nD  # factors with generator columns
        n_g = n_x + n_noisy * nV
        self.s, self.first_posterior, self.N = s, first_posterior, N
        self.l, self.p = l, p
        absB, absC = np.abs(B_o), np.abs(C_o)
        # The powers A_o^j with rounding bounds that do not compound (:mod:`._powers`).
        # Every coefficient below is a float matrix X with an error bound E >= |X - X*|
        # (X* its exact value from the float model) and the magnitude |X| + E >= |X*|.
        tab = power_table(A_o, s)
        gN = 2.0 * gamma(N + 2)                 # one product with an N-term sum
        gev = 2.0 * gamma(N + s * p + 4)        # assemble's evaluation of c and b
        # Rows: start constraints, then per posterior: increment rows (for steps
        # >= 1), the noise set's own rows and the measured C_o rows.
        # b = b0 + Bc c_S + Bu u + scatter(y); the start set's own b_S enters
        # through b0 (set per call by the caller's b_S). Each coefficient has an
        # error twin (its rounding error plus the rounding of its evaluation in
        # assemble) and the two matrix coefficients a magnitude twin (what an
        # uncertainty of c_S or u is carried with); ``e0`` collects absolute errors
        # carried by the sets' centres and right-hand sides.
        rows_A = [np.hstack([A_S, np.zeros((A_S.shape[0], n_g - nS))])]
        self.nS_rows = A_S.shape[0]
        blocks: list[tuple[NDArray[np.float64], ...]] = []
        # (b0, Bc, Bu, err(b0), err(Bc), err(Bu), |Bc|*, |Bu|*, e0)
        y_pos: list[int] = []
        G = np.zeros((N, n_x))
        G[:, :nS] = G_S
        # c_j = Mc c_S + Mu u_flat + kappa with Mc = A^j, Mu's block i = A^(j-1-i) Gamma,
        # kappa = sum_(t<j) A^t B c_D
        Mc, Ec = np.eye(N), np.zeros((N, N))
        Mu, Eu = np.zeros((N, s * p)), np.zeros((N, s * p))
        kappa, Ek, kappa_e = np.zeros(N), np.zeros(N), np.zeros(N)
        AG = [tab.apply(t, Gamma_o) for t in range(s)] if p else []
        BcD = B_o @ cD
        BcD_err = gN * (absB @ np.abs(cD))      # BcD's own rounding
        BcD_e = absB @ increment.c_err          # the increment set's centre error
        kappa_sum_abs = np.zeros(N)
        row = self.nS_rows
        v_col = n_x
        if noise is not None and nV:
            GV, AV, cV = noise.G, noise.A, noise.c
            cV_e = noise.c_err
        y_sel: list[bool] = []

        def posterior(mask) -> None:
            nonlocal row, v_col
            y_sel.extend(mask.tolist())
            m = int(mask.sum())
            if not m:
                return
            if noise is not None and nV:
                if AV.shape[0]:
                    Arow = np.zeros((AV.shape[0], n_g))
                    Arow[:, v_col:v_col + nV] = AV
                    rows_A.append(Arow)
                    zN0, zU0 = np.zeros((AV.shape[0], N)), np.zeros((AV.shape[0], s * p))
                    blocks.append((noise.b.copy(), zN0, zU0, np.zeros(AV.shape[0]), zN0,
                                   zU0, zN0, zU0, noise.b_err.copy()))
                    row += AV.shape[0]
            Arow = np.zeros((m, n_g))
            Arow[:, :n_x] = C_o[mask] @ G
            Cm, aC = C_o[mask], absC[mask]
            b0 = -(Cm @ kappa)
            b0_err = aC @ Ek + gN * (aC @ np.abs(kappa))
            e0 = aC @ kappa_e
            if nV:
                Arow[:, v_col:v_col + nV] = GV[mask]
                b0 = b0 - cV[mask]
                b0_err = b0_err + gN * np.abs(b0)
                e0 = e0 + cV_e[mask]
                v_col += nV
            rows_A.append(Arow)
            bc, bu = -(Cm @ Mc), -(Cm @ Mu)
            bc_err = aC @ Ec + gN * (aC @ np.abs(Mc)) + gev * np.abs(bc)
            bu_err = aC @ Eu + gN * (aC @ np.abs(Mu)) + gev * np.abs(bu)
            b0_err = b0_err + gev * np.abs(b0)
            blocks.append((b0, bc, bu, up(b0_err, N), up(bc_err, N), up(bu_err, N),
                           up(aC @ (np.abs(Mc) + Ec), N), up(aC @ (np.abs(Mu) + Eu), N),
                           up(e0, N)))
            y_pos.extend(range(row, row + m))
            row += m

        if first_posterior:
            posterior(masks[0])
        for j in range(1, s + 1):
            blk = slice(nS + (j - 1) * nD, nS + j * nD)
            G = A_o @ G
            G[:, blk] += B_o @ GD
            Mc, Ec = tab.powers[j], tab.F[j]
            if p:  # block i of the inputs: A^(j-1-i) Gamma
                for i in range(j):
                    Mu[:, i * p:(i + 1) * p], Eu[:, i * p:(i + 1) * p] = AG[j - 1 - i]
            # kappa += fl(A^(j-1) B c_D), recursive summation (Higham (4.4))
            v, ev = tab.apply(j - 1, BcD)
            kappa = kappa + v
            kappa_sum_abs = kappa_sum_abs + np.abs(v)
            Ek = up(Ek + ev + tab.P[j - 1] @ BcD_err, N) + gamma(j + 1) * kappa_sum_abs
            kappa_e = up(kappa_e + tab.P[j - 1] @ BcD_e, N)
            if AD.shape[0]:
                Arow = np.zeros((AD.shape[0], n_g))
                Arow[:, blk] = AD
                rows_A.append(Arow)
                zN, zU = np.zeros((AD.shape[0], N)), np.zeros((AD.shape[0], s * p))
                blocks.append((increment.b.copy(), zN, zU, np.zeros(AD.shape[0]), zN, zU,
                               zN, zU, increment.b_err.copy()))
                row += AD.shape[0]
            posterior(masks[j - 1 + int(first_posterior)])
        Mc_err = up(Ec + gev * np.abs(Mc), N)
        Mu_err = up(Eu + gev * np.abs(Mu), N)
        kappa_err = up(Ek + gev * np.abs(kappa), N)
        self.A = np.vstack(rows_A) if rows_A else np.zeros((0, n_g))
        m = self.A.shape[0]
        nz = m - self.nS_rows
        parts = [np.concatenate([blk[i] for blk in blocks]) if nz else None for i in range(9)]
        self.b_const = parts[0] if nz else np.zeros(0)
        self.b_c = parts[1] if nz else np.zeros((0, N))
        self.b_u = parts[2] if nz else np.zeros((0, s * p))
        self._b_const_a = parts[3] if nz else np.zeros(0)
        self._b_c_a = parts[4] if nz else np.zeros((0, N))
        self._b_u_a = parts[5] if nz else np.zeros((0, s * p))
        self._b_c_m = parts[6] if nz else np.zeros((0, N))
        self._b_u_m = parts[7] if nz else np.zeros((0, s * p))
        self._b_abs_err = parts[8] if nz else np.zeros(0)
        self.y_pos = np.asarray(y_pos, dtype=np.int64) - self.nS_rows
        self._y_idx = np.flatnonzero(np.asarray(y_sel, dtype=bool)).astype(np.int64)
        self.masks = tuple(masks)
        self.n_y = n_y
        self.G = np.hstack([G, np.zeros((N, n_g - n_x))])
        self.c_c, self.c_u, self.c_const = Mc.copy(), Mu, kappa
        self._c_c_a, self._c_u_a, self._c_const_a = Mc_err, Mu_err, kappa_err
        self._c_c_m, self._c_u_m = up(np.abs(Mc) + Ec, N), up(np.abs(Mu) + Eu, N)
        self._c_abs_err = kappa_e
        # Depth of the products (s steps of N-term sums, plus assembly) for gamma.
        self._gK = model_rtol(s, N, p, nD + nV)
        noise_h = np.tile(noise.h, n_noisy) if noise is not None and nV else np.zeros(0)
        self.h_D = np.concatenate([np.tile(increment.h, s), noise_h])
        self.free = np.concatenate([np.asarray(free_S, dtype=bool), np.isinf(self.h_D)])
        W = self.G if P is None else np.vstack([self.G, P @ self.G])
        self.n_dir = W.shape[0]
        self.P = P
        self._absP = None if P is None else np.abs(P)
        self.unbounded_radius = unbounded_radius
        self.lp = FixedStructureLP(self.A, hull_objectives(W), self.free, unbounded_radius)
        #: every matrix of the step has all dimensions below ``SMALL_BLAS_DIM`` (BLAS
        #: then runs single-threaded by itself: ``setobs._blas``)
        self.blas_small = max(self.A.shape[0], self.A.shape[1], W.shape[0]) < SMALL_BLAS_DIM

    @property
    def usable(self) -> bool:
        """Whether the fast LP path can be used for this structure."""
        return self.lp.usable

    def new_state(self) -> LPState:
        """A fresh LP warm-start state for one user of this structure."""
        return self.lp.new_state()

    def assemble(self, c_S, b_S, h_S, Y, U, *, c_S_err=None, b_S_err=None,
                 data_rtol: float = 0.0, Y_err=None):
        """Centre, ``b``, ``h`` and the error bounds of ``c`` and ``b`` for the data.

        Parameters
        ----------
        c_S, b_S, h_S : ndarray
            The start set's centre, constraint right-hand side and factor bounds.
        Y : ndarray, shape (n_y, l)
            Measurements (in the coordinates of ``C_o``); only the entries of
            the structure's masks are read (the others may be NaN).
        U : ndarray, shape (s, p)
            Inputs.
        c_S_err, b_S_err : ndarray, optional
            Error bounds carried by the start set.
        data_rtol : float
            Relative uncertainty of every ``y`` and ``u`` (representation error).
        Y_err : ndarray, shape (n_y, l), optional
            Further absolute uncertainty of each measurement (e.g. the rounding
            of subtracting a feedthrough ``D_u u``).

        Returns
        -------
        c, b, h, c_err, b_err : ndarray
        y_scale : float
            The largest ``|y|`` of the measurements read (what ``b``'s rounding
            is relative to: :meth:`hull`).
        """
        f64 = np.float64
        empty = _EMPTY
        return _kernels.assemble(
            np.ascontiguousarray(c_S, dtype=f64), np.ascontiguousarray(b_S, dtype=f64),
            np.ascontiguousarray(h_S, dtype=f64), np.ascontiguousarray(Y, dtype=f64).reshape(-1),
            self._y_idx, np.ascontiguousarray(U, dtype=f64).reshape(-1) if self.p else empty,
            empty if b_S_err is None else np.ascontiguousarray(b_S_err, dtype=f64),
            empty if c_S_err is None else np.ascontiguousarray(c_S_err, dtype=f64),
            empty if Y_err is None else np.ascontiguousarray(Y_err, dtype=f64).reshape(-1),
            self.b_const, self.b_c, self.b_u, self._b_const_a, self._b_c_a, self._b_u_a,
            self._b_c_m, self._b_u_m, self._b_abs_err, self.y_pos, self.c_const, self.c_c,
            self.c_u, self._c_const_a, self._c_c_a, self._c_u_a, self._c_c_m, self._c_u_m,
            self._c_abs_err, self.h_D, self._gK, float(data_rtol))

    def hull(self, c, b, h, y_scale: float, state: LPState, b_err, c_err):
        """Certified hull bounds of ``Z`` (and of ``P Z``), or ``None`` if any LP failed.

        ``y_scale`` is the magnitude of the measurements (``b`` is ``y - C_o c_j``,
        where the two cancel; its rounding is relative to them). The bounds hold
        for every ``b`` within ``b_err`` and every centre within ``c_err``.
        Returns ``(lo, hi, alw)``: the bounds of length ``N`` (+ ``q`` with ``P``),
        rounded outward exactly as :meth:`ConstrainedZonotope.interval_hull` does, and
        the rounding allowances in each band (``|y_lo|^T b_err + |y_hi|^T b_err +
        2 c_err``, ``y`` the certified multipliers: :func:`allowance_fraction`).
        """
        bounds, ok = self.lp.minimize_all_unchecked(b, h, state, y_scale, b_err,
                                                    WINDOW_REL_GAP)
        if not ok.all():
            return None
        if self.P is None:
            cc, cc_err = c, c_err
        else:
            Pc = self.P @ c
            k = self.P.shape[1]
            pe = (self._absP @ (c_err + gamma(k + 1) * np.abs(c))) * (1.0 + gamma(k + 2))
            cc, cc_err = np.concatenate([c, Pc]), np.concatenate([c_err, pe])
        lo, hi, crossed_not = _kernels.hull_bounds(bounds, cc, cc_err)
        if not crossed_not:
            return None
        alw = np.abs(state.ys) @ b_err if b_err.size else np.zeros(bounds.size)
        return lo, hi, alw[0::2] + alw[1::2] + 2.0 * cc_err

    def to_cz(self, c, b, h, c_err=None, b_err=None) -> ConstrainedZonotope:
        """The set itself (for ``keep_sets`` and the reference path)."""
        return trusted_cz(self.G, c, self.A, b, h, self.unbounded_radius, c_err, b_err)


class ClosedForm(NamedTuple):
    """A posterior as the closed form's data (the fast path's step): the structure and
    the step's ``c``, ``b``, ``h`` with their rounding bounds; the set is built on first
    use (:meth:`to_cz`)."""

    model: WindowModel
    c: NDArray[np.float64]
    b: NDArray[np.float64]
    h: NDArray[np.float64]
    c_err: NDArray[np.float64] | None
    b_err: NDArray[np.float64] | None

    def to_cz(self) -> ConstrainedZonotope:
        """The posterior as a constrained zonotope."""
        return self.model.to_cz(self.c, self.b, self.h, self.c_err, self.b_err)


class ModelCache:
    """Window structures shared by all SMFDOs of a process (keyed by a digest of the
    matrices they depend on), so that a Monte Carlo campaign sets each up once.

    The structures are immutable (each SMFDO keeps its own LP warm-start state);
    the cache is locked, and bounded by the memory of its entries.
    """

    def __init__(self, max_bytes: int = 256 * 2**20) -> None:
        self._items: OrderedDict[tuple, tuple[WindowModel, int]] = OrderedDict()
        self._lock = threading.Lock()
        self._bytes = 0
        self.max_bytes = max_bytes

    @staticmethod
    def _size(model: WindowModel) -> int:
        lp = model.lp
        arrays = (model.A, model.G, model.b_c, lp.Ared, lp.Q2, lp.Q0, lp.binv0, lp.W, lp.Wred,
                  lp.yU, lp.pinvU)
        return int(sum(a.nbytes for a in arrays if a is not None))

    def get(self, key: tuple, build: Callable[[], WindowModel]) -> WindowModel:
        """The structure under ``key``, built by ``build`` (outside the lock) if absent.

        Parameters
        ----------
        key : tuple
            The structure's key (the model's digest and the structure's own key).
        build : callable
            Builds the structure when it is not cached.
        """
        with self._lock:
            hit = self._items.get(key)
            if hit is not None:
                self._items.move_to_end(key)
                return hit[0]
        model = build()  # outside the lock: building takes a while
        size = self._size(model)
        with self._lock:
            if key not in self._items:
                self._items[key] = (model, size)
                self._bytes += size
                while self._bytes > self.max_bytes and len(self._items) > 1:
                    _, (_, sz) = self._items.popitem(last=False)
                    self._bytes -= sz
        return model

    def __len__(self) -> int:
        return len(self._items)


#: The process's one cache of window structures.
MODEL_CACHE = ModelCache()
