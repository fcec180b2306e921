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
* **a compiled bounded dual simplex** (:mod:`setobs.geometry._simplex`,
  numba) with an explicit basis inverse, **warm-started per direction** from
  the previous optimal basis: with ``A`` and ``w`` fixed that basis stays dual
  feasible whatever ``b`` and ``h`` are, so a new right-hand side typically
  costs zero to three pivots;
* **the same certificate as the HiGHS path**: the multiplier ``y = y_U + Q2 z``
  is certified on the original data by the Lagrangian bound of
  :func:`setobs.geometry.lp.lagrangian_lower_bound` (compiled, same error
  analysis, exact products and summation for the free factors' reduced costs).

The fast path never decides anything it cannot certify: an LP is reported
solved (``ok``) only if its certified bound is finite and within ``1e-9 (1 +
|obj|)`` of the simplex objective. Infeasible, iteration-limited, numerically
delicate and ambiguous cases are flagged so that the caller can hand them to
the reference path (:class:`setobs.geometry.lp.FactorPolytope`), which decides
emptiness with a certified phase-1 LP.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg
from numpy.typing import NDArray

from ..tolerances import UNBOUNDED_RADIUS, UNBOUNDED_REDUCED_COST_TOL
from . import _simplex

__all__ = ["FixedStructureLP", "hull_from_bounds", "hull_objectives"]

#: Relative least-squares residual of ``w_U`` on ``range(A_U^T)`` above which a
#: direction is unbounded below, and below which it is bounded; in between the
#: direction is left to the reference path.
_UNBOUNDED_CLEAR = 1e-6
_BOUNDED_CLEAR = 1e-12
#: Accepted gap between the certified bound and the simplex objective.
GAP_RTOL = 1e-9
#: Relative size of the singular values that make a structure unusable (rank
#: decisions between these and 1 would have to be made; the reference path
#: does not make them, so the fast path does not either).
_RANK_GREY = 1e-6
#: Relative residual of the data on the left null space of ``A`` (redundant rows)
#: above which the reduced LP is not trusted (the reference path decides emptiness).
_CONSISTENCY_RTOL = 1e-11


def hull_objectives(W: NDArray[np.float64]) -> NDArray[np.float64]:
    """Objectives ``[W_0, -W_0, W_1, -W_1, ...]`` of the interval hull of ``{W z}``."""
    W2 = np.empty((2 * W.shape[0], W.shape[1]))
    W2[0::2] = W
    W2[1::2] = -W
    return W2


def hull_from_bounds(bounds: NDArray[np.float64], c: NDArray[np.float64]
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """Interval hull ``c + [bounds[0::2], -bounds[1::2]]`` of the objectives of
    :func:`hull_objectives`, rounded outward as
    :meth:`ConstrainedZonotope.interval_hull` does; ``None`` if the certified
    bounds cross (emptiness must then be decided by the reference path)."""
    low, upp = bounds[0::2], -bounds[1::2]
    if (low > upp).any():
        return None
    with np.errstate(invalid="ignore"):
        lo = np.where(np.isfinite(low), np.nextafter(low + c, -np.inf), -np.inf)
        hi = np.where(np.isfinite(upp), np.nextafter(upp + c, np.inf), np.inf)
    return lo, hi


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
    radius : float
        Radius on unbounded factors used in certification (see
        :mod:`setobs.geometry.lp`).

    Attributes
    ----------
    usable : bool
        False if the structure needs rank decisions the reference path does not
        make (redundant equality rows, nearly dependent free columns); every
        :meth:`minimize_all` then reports nothing solved.
    reason : str
        Why the structure is not usable ("" if usable).
    """

    def __init__(self, A: NDArray[np.float64], W: NDArray[np.float64],
                 free: NDArray[np.bool_], radius: float = UNBOUNDED_RADIUS) -> None:
        self.A = np.ascontiguousarray(A, dtype=np.float64)
        self.W = np.ascontiguousarray(W, dtype=np.float64)
        self.free = np.asarray(free, dtype=bool)
        self.radius = float(radius)
        m, n = self.A.shape
        self.m, self.n = m, n
        self.n_lp = self.W.shape[0]
        self.fidx = np.flatnonzero(self.free).astype(np.int64)
        self.bidx = np.flatnonzero(~self.free).astype(np.int64)
        self.usable = True
        self.reason = ""
        f = self.fidx.size
        A_U = self.A[:, self.fidx]
        A_B = self.A[:, self.bidx]
        self.pinvU = np.ascontiguousarray(
            np.linalg.pinv(A_U.T) if (f and m) else np.zeros((m, f)))
        # Rank decisions are relative to the norm of the whole matrix A (a block
        # of rounding-level entries is zero, whatever its own scale).
        anorm = float(np.linalg.norm(self.A, 2)) if self.A.size else 0.0
        if f and m:
            Us, s, _ = np.linalg.svd(A_U, full_matrices=True)
            rank = int((s > _RANK_GREY * anorm).sum())
            if ((s > 1e-14 * anorm) & (s <= _RANK_GREY * anorm)).any():
                self._unusable("nearly dependent unbounded factor columns")
            Q2 = Us[:, rank:]
        else:
            Q2 = np.eye(m)
        self.Q2 = np.ascontiguousarray(Q2)
        W_U = self.W[:, self.fidx]
        yU = W_U @ self.pinvU.T if f else np.zeros((self.n_lp, m))
        self.yU = np.ascontiguousarray(yU)
        self.dirstat = np.zeros(self.n_lp, dtype=np.int64)
        if f:
            res = W_U - yU @ A_U
            scale = np.abs(W_U) + np.abs(yU) @ np.abs(A_U)
            rel = (np.abs(res) / np.maximum(scale, np.finfo(float).tiny)).max(axis=1)
            self.dirstat[rel > _BOUNDED_CLEAR] = 2
            self.dirstat[rel > _UNBOUNDED_CLEAR] = 1
        self.Wred = np.ascontiguousarray(self.W[:, self.bidx] - yU @ A_B)
        # Redundant rows (more measurements than new factors, e.g. l > q in the
        # SMFDO): keep an orthonormal basis U1 of the row space of Q2^T A_B; the
        # data must then satisfy the left-null-space equations Q0^T b = 0 up to
        # rounding, which minimize_all checks before trusting the reduced LP.
        A_red = Q2.T @ A_B
        Q0 = np.zeros((m, 0))
        if A_red.size:
            Ur, sv, _ = np.linalg.svd(A_red, full_matrices=True)
            rank = int((sv > _RANK_GREY * anorm).sum())
            if ((sv > 1e-14 * anorm) & (sv <= _RANK_GREY * anorm)).any():
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
        self.Ared = np.ascontiguousarray(A_red)
        self.AredT = np.ascontiguousarray(self.Ared.T)
        mr, nb = self.Ared.shape
        self.mr = mr
        basis = np.arange(0, dtype=np.int64)
        binv = np.zeros((0, 0))
        if mr and self.usable:
            _, _, piv = scipy.linalg.qr(self.Ared, pivoting=True, mode="economic")
            basis = np.sort(piv[:mr]).astype(np.int64)
            binv = np.linalg.inv(self.Ared[:, basis])
        self.bases = np.ascontiguousarray(np.tile(basis, (self.n_lp, 1)))
        self.upper = np.zeros((self.n_lp, nb), dtype=np.bool_)
        self.binv = np.ascontiguousarray(np.tile(binv, (self.n_lp, 1, 1)))
        self.npiv = np.zeros(self.n_lp, dtype=np.int64)
        self.maxit = 20 * (mr + 5)
        self._bounds = np.empty(self.n_lp)
        self._objs = np.empty(self.n_lp)
        self._codes = np.empty(self.n_lp, dtype=np.int64)
        self.calls = 0
        self.failures = 0

    def _unusable(self, why: str) -> None:
        self.usable = False
        self.reason = why

    def minimize_all(self, b: NDArray[np.float64], h: NDArray[np.float64]
                     ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Certified lower bounds of ``min W[i]^T xi`` for all ``i``.

        Parameters
        ----------
        b : ndarray, shape (m,)
        h : ndarray, shape (n,)
            Factor bounds: ``inf`` exactly on the structure's free factors.

        Returns
        -------
        bounds : ndarray, shape (n_lp,)
            Certified lower bounds (``-inf`` for directions unbounded below);
            meaningful only where ``ok``.
        ok : ndarray of bool, shape (n_lp,)
            Solved and certified tight; the others must go to the reference path.
        """
        h = np.asarray(h, dtype=np.float64)
        if not np.array_equal(np.isinf(h), self.free):
            raise ValueError("the unbounded factors differ from the structure's")
        bounds, ok = self._minimize_all(np.ascontiguousarray(b, dtype=np.float64),
                                        np.ascontiguousarray(h))
        return bounds.copy(), ok

    def _minimize_all(self, b: NDArray[np.float64], h: NDArray[np.float64],
                      b_scale: float = 0.0) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """:meth:`minimize_all` for contiguous float arrays with the right free factors.

        ``b_scale`` is the magnitude of the terms ``b`` was computed from (its
        rounding errors are relative to it, not to ``b`` after cancellation).
        The returned bounds are a buffer reused by the next call.
        """
        self.calls += 1
        bounds, codes = self._bounds, self._codes
        if not self.usable:
            self.failures += 1
            return bounds, np.zeros(self.n_lp, dtype=bool)
        hB = np.ascontiguousarray(h[self.bidx]) if self.fidx.size else h
        if self.Q0.shape[1]:
            # data consistent with the redundant rows (up to rounding)?
            scale = max(float(np.abs(b).max(initial=0.0)), b_scale,
                        float((self._absAB @ hB).max(initial=0.0)), 1e-300)
            if float(np.abs(self.Q0.T @ b).max()) > _CONSISTENCY_RTOL * scale:
                self.failures += 1
                return bounds, np.zeros(self.n_lp, dtype=bool)
        bred = self.Q2.T @ b
        _simplex.solve_batch(
            self.A, b, h, self.fidx, self.pinvU, self.Ared, self.AredT, bred, hB, self.W, self.Wred,
            self.yU, self.Q2, self.dirstat, self.bases, self.upper, self.binv, self.npiv,
            self.maxit, self.radius, UNBOUNDED_REDUCED_COST_TOL, GAP_RTOL, bounds,
            self._objs, codes)
        ok = codes == _simplex.OPTIMAL
        if not ok.all():
            self.failures += 1
        return bounds, ok
