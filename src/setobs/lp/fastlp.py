"""Fast certified LPs over factor polytopes whose *structure* is fixed.

Many queries share the constraint matrix and the objectives and differ only in
the right-hand side and the factor bounds: the SMFDO's interval hulls in
windowed mode (Li-Cong-Dong, eq. (24)) solve ``2 (N_o + q)`` LPs per step over
``{xi : A xi = b, |xi| <= h}`` with ``A`` and the objectives fixed once the
window is full; only ``b`` (the data) and ``h`` (the reset box) change.

:class:`FixedStructureLP` exploits that:

* **free factors eliminated once.** For the unbounded factors ``U``
  (``h = inf``) the objective must satisfy ``w_U = A_U^T y_U`` (otherwise the
  LP is unbounded below, decided once per direction); the remaining LP is
  ``min (w_B - A_B^T y_U)^T xi_B`` subject to ``Q2^T A_B xi_B = Q2^T b``,
  ``|xi_B| <= h_B`` with ``Q2`` an orthonormal basis of ``range(A_U)^perp``;
* **a compiled bounded dual simplex** (:mod:`setobs.lp._simplex`,
  numba) with an explicit basis inverse, **warm-started per direction** from
  the previous optimal basis: with ``A`` and ``w`` fixed that basis stays dual
  feasible whatever ``b`` and ``h`` are, so a new right-hand side typically
  costs zero to three pivots;
* **the same certificate as the HiGHS path**: the multiplier ``y = y_U + Q2 z``
  is certified on the original data by the one certificate,
  :func:`setobs.lp.certificate.lower_bound`, called compiled from the kernel.

The structure is immutable once built and can be shared (across SMFDOs,
processes' caches, threads); the warm-start state (bases, basis inverses,
buffers) lives in an :class:`LPState` owned by the caller, so concurrent users
of one structure never see each other's state and a result never depends on
what else ran before it.

The fast path never decides anything it cannot certify: an LP is reported
solved (``ok``) only if its certified bound is finite and within ``1e-9 (1 +
|obj|)`` of the simplex objective. Infeasible, iteration-limited, numerically
delicate and ambiguous cases are flagged so that the caller can hand them to
the reference path (:class:`setobs.lp.factor.FactorPolytope`), which decides
emptiness with a certified phase-1 LP.
"""

from __future__ import annotations

import copy

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from .._blas import with_single_threaded_blas, with_single_threaded_blas_unless_small
from .._lazy import lazy_module
from .._rounding import pow2_inverse
from ..exceptions import DimensionError, InvalidValueError
from ..tolerances import (
    EQUILIBRATION_FLOOR,
    FASTLP_BOUNDED_CLEAR,
    FASTLP_CONSISTENCY_RTOL,
    FASTLP_GAP_RTOL,
    FASTLP_RANK_GREY,
    FASTLP_UNBOUNDED_CLEAR,
    UNBOUNDED_RADIUS,
    UNBOUNDED_REDUCED_COST_TOL,
)

# The compiled simplex (numba) compiles/loads on the first batch, not on import.
_simplex = lazy_module("setobs.lp._simplex")
_certificate = lazy_module("setobs.lp.certificate")

__all__ = ["CHAIN_ORDER", "PRIMAL_CHAIN", "FixedStructureLP", "LPState", "chain_order",
           "hull_objectives"]

_EMPTY = np.zeros(0)


def _paired(W: NDArray[np.float64]) -> bool:
    """Whether the objectives come in pairs ``(w, -w)`` (:func:`hull_objectives`)."""
    return W.shape[0] % 2 == 0 and bool(np.array_equal(W[0::2], -W[1::2]))


def _floored(norms: NDArray[np.float64]) -> NDArray[np.float64]:
    top = float(norms.max(initial=0.0))
    return np.where(norms < EQUILIBRATION_FLOOR * top, top, norms)


#: The objective chain: after the first LP of a data set, every LP starts by the primal
#: simplex from the optimal vertex of an LP already solved on the same data (the one
#: best for its objective); with ``False`` each LP picks that start or the dual simplex
#: from its own last basis, whichever was cheaper when last used (``solve_batch``).
#: Measured on window 10 (``benchmarks/chain_ab.py``, linprog per step, with and without
#: the chain and its order): a 30-tank cascade with 21 outputs 213 against 919, a random
#: 6-state plant 3.8 against 5.0, a bicycle model 2.2 against 2.3; starting each LP from
#: the previous LP's vertex alone
#: (not the best one) cost up to 10 times as many pivots on the restart rows' directions.
PRIMAL_CHAIN = True
#: Whether the LPs are solved in the chain order (:func:`chain_order`) rather than as
#: listed (7-10 % fewer iterations on the same plants); read when a structure is built.
CHAIN_ORDER = True


def chain_order(n_lp: int) -> NDArray[np.int64]:
    """The order in which one data set's LPs are solved: for hull objectives ``[W_0, -W_0,
    W_1, -W_1, ...]`` the minima ``W_0, W_1, ...`` then the maxima backwards, ``...,
    -W_1, -W_0`` (each from an optimal vertex already found: the objective chain).

    Parameters
    ----------
    n_lp : int
        Number of objectives.
    """
    if not CHAIN_ORDER or n_lp % 2:
        return np.arange(n_lp, dtype=np.int64)
    return np.concatenate([np.arange(0, n_lp, 2), np.arange(n_lp - 1, 0, -2)]).astype(np.int64)


def hull_objectives(W: NDArray[np.float64]) -> NDArray[np.float64]:
    """Objectives ``[W_0, -W_0, W_1, -W_1, ...]`` of the interval hull of ``{W z}``.

    Parameters
    ----------
    W : ndarray, shape (d, n)
        Map from the factors to the coordinates of the hull.
    """
    W2 = np.empty((2 * W.shape[0], W.shape[1]))
    W2[0::2] = W
    W2[1::2] = -W
    return W2


class LPState:
    """Warm-start state of one user of a :class:`FixedStructureLP` (mutable, not shared).

    Holds, per objective, the simplex basis, the nonbasic bound flags, the
    explicit basis inverse (stored transposed), the pivot counter and the pivot
    counts of its two warm starts, the simplex iterations so far (``iters``: primal,
    dual), plus the output buffers.
    Create it with :meth:`FixedStructureLP.new_state`; an SMFDO keeps one per
    structure it uses, so its results depend only on its own data.

    Parameters
    ----------
    lp : FixedStructureLP
        The structure the state belongs to (fixes the sizes and the initial basis).
    """

    __slots__ = ("bases", "binv", "bounds", "codes", "est", "iters", "npiv", "objs", "upper",
                 "ys")

    def __init__(self, lp: FixedStructureLP) -> None:
        n_lp = lp.n_lp
        self.bases = np.ascontiguousarray(np.tile(lp.basis0, (n_lp, 1)))
        self.upper = np.zeros((n_lp, lp.bidx.size), dtype=np.bool_)
        self.binv = np.ascontiguousarray(np.tile(lp.binv0, (n_lp, 1, 1)))
        self.npiv = np.zeros(n_lp, dtype=np.int64)
        # pivots of each LP's two warm starts (own last basis, dual simplex; the
        # previous LP's basis, primal simplex) when last used
        self.est = np.zeros((n_lp, 2))
        # primal and dual simplex iterations (pivots and bound flips) so far
        self.iters = np.zeros(2, dtype=np.int64)
        self.bounds = np.empty(n_lp)
        self.objs = np.empty(n_lp)
        self.codes = np.full(n_lp, -1, dtype=np.int64)  # (none solved yet)
        self.ys = np.zeros((n_lp, lp.m))  # (read by the window's allowances)


class FixedStructureLP:
    """The LPs ``min W[i]^T xi`` over ``{A xi = b, |xi_j| <= h_j}`` for varying ``b``, ``h``.

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Constraint matrix (fixed).
    W : ndarray, shape (n_lp, n)
        Objectives (fixed).
    free : ndarray of bool, shape (n,)
        Factors with ``h = inf`` (fixed); the others must get finite bounds.
    unbounded_radius : float
        Radius on unbounded factors used in certification (see
        :mod:`setobs.lp.factor`).

    Attributes
    ----------
    usable : bool
        False if the structure needs rank decisions the reference path does not
        make (redundant equality rows, nearly dependent free columns); every
        :meth:`minimize_all` then reports nothing solved.
    reason : str
        Why the structure is not usable ("" if usable).

    Notes
    -----
    The reduced LP is built and solved on an equilibrated copy ``R A S``
    (power-of-two scalings to unit column, then unit row norms): the rank
    decisions (redundant rows, dependent free columns) and the simplex then
    see the structure, not the units. On a badly scaled model (increments of
    ``7980`` and ``0.0185``, outputs from ``1e-9`` to ``1e2``) the unscaled
    reduced matrix has singular values down to ``1e-13`` of its norm where the
    equilibrated one has ``2e-2``. The multiplier maps back exactly
    (``y = R y'``) and is certified on the original data.

    Immutable after construction (thread-safe to share); the warm-start state
    is an :class:`LPState` passed to :meth:`minimize_all`.
    """

    @with_single_threaded_blas
    def __init__(self, A: NDArray[np.float64], W: NDArray[np.float64],
                 free: NDArray[np.bool_], unbounded_radius: float = UNBOUNDED_RADIUS) -> None:
        self.A = np.ascontiguousarray(A, dtype=np.float64)
        self.W = np.ascontiguousarray(W, dtype=np.float64)
        self.free = np.asarray(free, dtype=bool)
        if self.A.ndim != 2 or self.W.ndim != 2 or self.W.shape[1] != self.A.shape[1] \
                or self.free.shape != (self.A.shape[1],):
            raise DimensionError(
                f"FixedStructureLP needs the shapes A (m, n), W (n_lp, n), free (n,): got A "
                f"{self.A.shape}, W {self.W.shape}, free {self.free.shape}")
        for name, M in (("A", self.A), ("W", self.W)):
            if not np.isfinite(M).all():
                i = np.unravel_index(int(np.argmax(~np.isfinite(M))), M.shape)
                raise InvalidValueError(f"FixedStructureLP: {name} must be finite, got "
                                        f"{M[i]} at index {tuple(map(int, i))}")
        self.csc = _certificate.csc_of(self.A)  # (the certificate's form of A)
        self.unbounded_radius = float(unbounded_radius)
        m, n = self.A.shape
        self.m, self.n = m, n
        self.n_lp = self.W.shape[0]
        self.order = chain_order(self.n_lp)  # (the order solve_batch solves them in)
        self.paired = _paired(self.W)  # (rel_gap applies: hull objectives)
        self.fidx = np.flatnonzero(self.free).astype(np.int64)
        self.bidx = np.flatnonzero(~self.free).astype(np.int64)
        self.usable = True
        self.reason = ""
        f = self.fidx.size
        # (overflow on data of extreme dynamic range is checked: the reduction is then
        # declined, below)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            self._reduce(f, m)

    def _reduce(self, f: int, m: int) -> None:
        """The equilibrated working copy and the reduction of the unbounded factors
        (the body of ``__init__``)."""
        # Equilibration by powers of two (exact): unit column norms, then unit
        # row norms. Working copy A' = R A S, W' = W S, factor bounds h / S; the
        # multiplier of the working LP maps back as y = R y'.
        S = pow2_inverse(_floored(np.linalg.norm(self.A, axis=0)))
        R = pow2_inverse(_floored(np.linalg.norm(self.A * S, axis=1)))
        self.S_B = np.ascontiguousarray(S[self.bidx])
        self.R = np.ascontiguousarray(R)
        As = R[:, None] * self.A * S
        Ws = self.W * S
        A_U = As[:, self.fidx]
        A_B = As[:, self.bidx]
        # pinv(A'UNIT_ROUNDOFF^T) for the working copy; the certificate refines y on the
        # original columns with pinv(A_U^T) = R pinv(A'UNIT_ROUNDOFF^T) S_U (A_U of full
        # column rank; any approximation only affects tightness, not validity)
        self.pinvU = np.ascontiguousarray(
            np.linalg.pinv(A_U.T) if (f and m) else np.zeros((m, f)))
        self.pinvU_orig = np.ascontiguousarray(R[:, None] * self.pinvU * S[self.fidx][None, :])
        # Rank decisions relative to the norm of the whole (equilibrated) matrix.
        anorm = float(np.linalg.norm(As, 2)) if As.size else 0.0
        if f and m:
            Us, s, _ = np.linalg.svd(A_U, full_matrices=True)
            rank = int((s > FASTLP_RANK_GREY * anorm).sum())
            if ((s > 1e-14 * anorm) & (s <= FASTLP_RANK_GREY * anorm)).any():
                self._unusable("nearly dependent unbounded factor columns")
            Q2 = Us[:, rank:]
        else:
            Q2 = np.eye(m)
        W_U = Ws[:, self.fidx]
        yU = W_U @ self.pinvU.T if f else np.zeros((self.n_lp, m))
        self.yU = np.ascontiguousarray(yU)
        self.dirstat = np.zeros(self.n_lp, dtype=np.int64)
        if f:
            # Residual of w_U on range(A_U^T), relative to the whole reduced-cost
            # computation |W| + |yU| |A| (norm-wise: a column of rounding-level
            # entries must not make its own residual look large).
            res = W_U - yU @ A_U
            scale = (np.abs(Ws) + np.abs(yU) @ np.abs(As)).max(axis=1)
            rel = np.abs(res).max(axis=1) / np.maximum(scale, np.finfo(float).tiny)
            self.dirstat[rel > FASTLP_BOUNDED_CLEAR] = 2
            self.dirstat[rel > FASTLP_UNBOUNDED_CLEAR] = 1
        self.Wred = np.ascontiguousarray(Ws[:, self.bidx] - yU @ A_B)
        if not (np.isfinite(self.pinvU).all() and np.isfinite(yU).all()
                and np.isfinite(self.Wred).all()):
            # (data of extreme dynamic range: a pseudo-inverse beyond double precision)
            self._unusable("non-finite reduction of the unbounded factors")
            self.Wred = np.zeros_like(self.Wred)
            self.yU = np.zeros_like(self.yU)
        # Redundant rows (more measurements than new factors, e.g. l > q in the
        # SMFDO): keep an orthonormal basis U1 of the row space of Q2^T A_B; the
        # data must then satisfy the left-null-space equations Q0^T b = 0 up to
        # rounding, which minimize_all checks before trusting the reduced LP.
        A_red = Q2.T @ A_B
        Q0 = np.zeros((m, 0))
        if A_red.size:
            Ur, sv, _ = np.linalg.svd(A_red, full_matrices=True)
            rank = int((sv > FASTLP_RANK_GREY * anorm).sum())
            if ((sv > 1e-14 * anorm) & (sv <= FASTLP_RANK_GREY * anorm)).any():
                self._unusable("nearly redundant equality rows")
            if rank < A_red.shape[0]:
                Q0 = Q2 @ Ur[:, rank:]
                Q2 = Q2 @ Ur[:, :rank]
                A_red = Ur[:, :rank].T @ A_red
        elif Q2.shape[1]:
            Q0, Q2, A_red = Q2, np.zeros((m, 0)), np.zeros((0, A_B.shape[1]))
        self.Q2 = np.ascontiguousarray(Q2)
        self.Q0 = np.ascontiguousarray(Q0)
        self._absAB = np.abs(A_B)
        self._absQ0 = np.abs(self.Q0)
        self.Ared = np.ascontiguousarray(A_red)
        self.sp = _simplex.sparse_pattern(self.Ared)
        mr = self.Ared.shape[0]
        self.mr = mr
        basis = np.arange(0, dtype=np.int64)
        binv = np.zeros((0, 0))
        if mr and self.usable:
            _, _, piv = scipy.linalg.qr(self.Ared, pivoting=True, mode="economic")
            basis = np.sort(piv[:mr]).astype(np.int64)
            binv = np.ascontiguousarray(np.linalg.inv(self.Ared[:, basis]).T)  # (transposed)
        self.basis0 = basis
        self.binv0 = binv
        self.maxit = 20 * (mr + 5)

    @classmethod
    def bounded(cls, A: NDArray[np.float64], W: NDArray[np.float64]) -> FixedStructureLP:
        """The structure of ``min W[i]^T xi`` over ``{A xi = b, |xi| <= h}`` with every
        ``h_j`` finite, built without rank decisions: one artificial column per row
        (``[A | I]``, artificial bounds ``0``, so the LP is unchanged) gives a
        nonsingular initial basis whatever the rank of ``A``. Pass ``h`` extended by
        ``m`` zeros (:meth:`minimize_all`); the multipliers are those of the rows of
        ``A``, certified on ``[A | I]`` (the artificial terms vanish with their zero
        bounds), so the bounds hold for the original LP. A redundant row keeps its
        artificial in the basis at zero; an inconsistent one makes the LP infeasible
        (reported not solved).

        Parameters
        ----------
        A : ndarray, shape (m, n)
            Constraint matrix.
        W : ndarray, shape (n_lp, n)
            Objectives.
        """
        self = object.__new__(cls)
        m, n = A.shape
        Aa = np.empty((m, n + m))
        Aa[:, :n] = A
        Aa[:, n:] = np.eye(m)
        Wa = np.zeros((W.shape[0], n + m))
        Wa[:, :n] = W
        self.A, self.W = Aa, Wa
        self.csc = _certificate.csc_of(Aa)
        self.m, self.n, self.n_lp = m, n + m, Wa.shape[0]
        self.order = chain_order(self.n_lp)
        self.paired = _paired(Wa)
        self.free = np.zeros(n + m, dtype=bool)
        self.unbounded_radius = UNBOUNDED_RADIUS
        self.fidx = np.zeros(0, dtype=np.int64)
        self.bidx = np.arange(n + m, dtype=np.int64)
        self.usable, self.reason = True, ""
        S = pow2_inverse(_floored(np.sqrt((Aa * Aa).sum(axis=0))))
        As = Aa * S
        R = pow2_inverse(_floored(np.sqrt((As * As).sum(axis=1))))
        As *= R[:, None]
        self.S_B, self.R = S, R
        self.pinvU = self.pinvU_orig = np.zeros((m, 0))
        self.yU = np.zeros((self.n_lp, m))
        self.dirstat = np.zeros(self.n_lp, dtype=np.int64)
        self.Wred = np.ascontiguousarray(Wa * S)
        self.Q2 = np.eye(m)
        self.Q0 = self._absQ0 = np.zeros((m, 0))
        self._absAB = np.abs(As)
        self.Ared = As
        self.sp = _simplex.sparse_pattern(As)
        self.mr = m
        self.basis0 = np.arange(n, n + m, dtype=np.int64)
        self.binv0 = np.diag(1.0 / (R * S[n:]))
        self.maxit = 20 * (m + 5)
        return self

    def with_objectives(self, W: NDArray[np.float64]) -> FixedStructureLP:
        """The same bounded structure (:meth:`bounded`) with other objectives: the
        matrices and their scaling are shared, so a state of this structure warm-starts
        the other's LPs (the same ``A``: any basis stays a basis).

        Parameters
        ----------
        W : ndarray, shape (n_lp, n)
            Objectives over the original factors (without the artificial columns).
        """
        if self.fidx.size or self.W.shape[1] != W.shape[1] + self.m:
            raise InvalidValueError("with_objectives applies to structures made by bounded()")
        out = copy.copy(self)
        n = W.shape[1]
        Wa = np.zeros((W.shape[0], n + self.m))
        Wa[:, :n] = W
        out.W, out.n_lp = Wa, Wa.shape[0]
        out.order = chain_order(out.n_lp)
        out.paired = _paired(Wa)
        out.yU = np.zeros((out.n_lp, self.m))
        out.dirstat = np.zeros(out.n_lp, dtype=np.int64)
        out.Wred = np.ascontiguousarray(Wa * self.S_B)
        return out

    def _unusable(self, why: str) -> None:
        self.usable = False
        self.reason = why

    def new_state(self) -> LPState:
        """A fresh warm-start state (initial basis from QR with pivoting)."""
        return LPState(self)

    @with_single_threaded_blas_unless_small(lambda lp: max(lp.m, lp.n))
    def minimize_all(self, b: NDArray[np.float64], h: NDArray[np.float64],
                     state: LPState | None = None, *, b_err: NDArray[np.float64] | None = None,
                     return_duals: bool = False, gaps: NDArray[np.float64] | None = None):
        """Certified lower bounds of ``min W[i]^T xi`` for all ``i``.

        Parameters
        ----------
        b : ndarray, shape (m,)
        h : ndarray, shape (n,)
            Factor bounds: ``inf`` exactly on the structure's free factors.
        state : LPState, optional
            Warm-start state, updated in place (default: a fresh one, i.e. a
            cold start).
        b_err : ndarray, shape (m,), optional
            Bound on the uncertainty of ``b``; the bounds hold for every
            right-hand side within it.
        return_duals : bool
            Also return the certified multipliers (one row per objective) and
            the simplex objectives.
        gaps : ndarray, shape (n_lp // 2,), optional
            For objectives in pairs ``(w, -w)`` (hull objectives; ignored otherwise): each
            LP of pair ``t`` that the objective chain solves stops once its duality gap is
            at most ``gaps[t]`` (nonnegative, finite), and is accepted with that gap. The
            bounds are certified either way, each within its gap of the minimum
            (:meth:`minimize_all_unchecked`'s ``rel_gap``, with absolute gaps).

        Returns
        -------
        bounds : ndarray, shape (n_lp,)
            Certified lower bounds (``-inf`` for directions unbounded below);
            meaningful only where ``ok``.
        ok : ndarray of bool, shape (n_lp,)
            Solved and certified tight; the others must go to the reference path.
        ys : ndarray, shape (n_lp, m)
            The multipliers (only with ``return_duals``).
        objectives : ndarray, shape (n_lp,)
            The simplex objectives (only with ``return_duals``).
        """
        h = np.asarray(h, dtype=np.float64)
        _certificate.check_lp_shapes(self.m, self.n, b=b, h=h, b_err=b_err)
        if not np.array_equal(np.isinf(h), self.free):
            raise InvalidValueError("the unbounded factors differ from the structure's")
        st = self.new_state() if state is None else state
        rel_gap = 0.0
        if gaps is not None and self.paired:
            g = np.asarray(gaps, dtype=np.float64)
            if g.shape != (self.n_lp // 2,) or not (np.isfinite(g).all() and (g >= 0).all()):
                raise InvalidValueError(f"gaps must be {self.n_lp // 2} finite nonnegative "
                                        f"numbers (one per pair of objectives), got {gaps!r}")
            # (the kernel's early stop is rel_gap times the pair's last width: a width of
            # exactly the gap, with rel_gap 1)
            st.bounds[:] = np.repeat(-0.5 * g, 2)
            st.codes[:] = _simplex.OPTIMAL
            rel_gap = 1.0
        bounds, ok = self.minimize_all_unchecked(np.ascontiguousarray(b, dtype=np.float64),
                                                 np.ascontiguousarray(h), st, b_err=b_err,
                                                 rel_gap=rel_gap)
        if return_duals:
            return bounds.copy(), ok, st.ys.copy(), st.objs.copy()
        return bounds.copy(), ok

    def reduced_data(self, b: NDArray[np.float64], h: NDArray[np.float64],
                     b_scale: float = 0.0, b_err: NDArray[np.float64] | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64], bool]:
        """The reduced LP's data, as the simplex sees it: ``min Wred[i]^T x`` subject to
        ``Ared x = bred``, ``|x| <= hB`` (for benchmarks and diagnostics, e.g. to hand the
        same LPs to another solver).

        Parameters
        ----------
        b : ndarray, shape (m,)
        h : ndarray, shape (n,)
        b_scale : float
            Magnitude of the terms ``b`` was computed from.
        b_err : ndarray, shape (m,), optional
            Bound on the uncertainty of ``b`` (the consistency check allows it).

        Returns
        -------
        hB : ndarray
            Bounds of the reduced LP's variables.
        bred : ndarray
            Its right-hand side.
        consistent : bool
            Whether ``b`` satisfies the redundant rows up to rounding and ``b_err`` (else
            the reduced LP is not the LP).
        """
        berr = _EMPTY if b_err is None else np.ascontiguousarray(b_err, dtype=np.float64)
        return _simplex.prepare(
            np.ascontiguousarray(b, dtype=np.float64), np.ascontiguousarray(h, dtype=np.float64),
            berr, self.bidx, self.S_B, self.R, self.Q0, self._absQ0, self._absAB, self.Q2,
            float(b_scale), FASTLP_CONSISTENCY_RTOL)

    def minimize_all_unchecked(self, b: NDArray[np.float64], h: NDArray[np.float64],
                               st: LPState, b_scale: float = 0.0,
                               b_err: NDArray[np.float64] | None = None, rel_gap: float = 0.0
                               ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """:meth:`minimize_all` for contiguous float arrays with the right free factors.

        ``b_scale`` is the magnitude of the terms ``b`` was computed from (its
        rounding errors are relative to it, not to ``b`` after cancellation).
        The returned bounds are the state's buffer, reused by the next call.

        Parameters
        ----------
        b : ndarray, shape (m,)
            Right-hand side (contiguous float64).
        h : ndarray, shape (n,)
            Factor bounds: ``inf`` exactly on the structure's free factors.
        st : LPState
            Warm-start state, updated in place.
        b_scale : float
            Magnitude of the terms ``b`` was computed from.
        b_err : ndarray, shape (m,), optional
            Bound on the uncertainty of ``b``; the bounds hold for every right-hand side
            within it.
        rel_gap : float
            For objectives in pairs ``(w, -w)`` (:func:`hull_objectives`; ignored
            otherwise): each LP solved by the objective chain stops once its duality
            gap is at most ``rel_gap`` times the pair's width at ``st``'s last data set,
            and its certified bound is accepted within that gap of the minimum (0: every
            LP to its optimum). The bounds are certified either way.
        """
        bounds, codes = st.bounds, st.codes
        if not self.usable:
            return bounds, np.zeros(self.n_lp, dtype=bool)
        # (data consistent with the redundant rows, up to rounding and b_err?)
        hB, bred, consistent = self.reduced_data(b, h, b_scale, b_err)
        if not consistent:
            return bounds, np.zeros(self.n_lp, dtype=bool)
        berr = (np.zeros(self.m) if b_err is None
                else np.ascontiguousarray(b_err, dtype=np.float64))
        args = ((self.A, self.csc, self.fidx, self.pinvU_orig, self.Ared, self.sp, self.W,
                 self.Wred, self.yU, self.Q2, self.R, self.dirstat, self.order),
                (b, h, berr, bred, hB),
                (st.bases, st.upper, st.binv, st.npiv, st.est, st.iters),
                (self.maxit, self.unbounded_radius, UNBOUNDED_REDUCED_COST_TOL,
                 FASTLP_GAP_RTOL, PRIMAL_CHAIN, float(rel_gap) if self.paired else 0.0),
                (bounds, st.objs, codes, st.ys))
        _simplex.solve_batch(*args)
        stuck = (codes == _simplex.ITERATION_LIMIT) | (codes == _simplex.NUMERICAL)
        if stuck.any():
            # A warm start can cycle on a degenerate vertex (the HSM150 record, window
            # 10, k = 3680: 300 dual iterations on a 10-row LP whose optimum sits on
            # the restart box's bound; cold, it solves). Those LPs once more from the
            # structure's initial basis with the dual simplex; the solved ones restart
            # from their own optimal bases (no pivots) and are certified again.
            st.bases[stuck] = self.basis0
            st.upper[stuck] = False
            st.binv[stuck] = self.binv0
            st.npiv[stuck] = 0
            st.est[stuck] = 0.0
            _simplex.solve_batch(*args)
        return bounds, codes == _simplex.OPTIMAL
