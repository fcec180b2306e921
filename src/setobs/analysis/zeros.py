"""Invariant zeros of ``(Phi, G, Xi)`` by pencil reduction (Emami-Naeini & Van Dooren 1982)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigvals, svd

from .._format import format_complex_list
from ..exceptions import InternalError
from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import RANK_RTOL, UNIT_CIRCLE_TOL
from ._linalg import RankDecision, balance_system, min_margin, not_inside_unit_circle, rank_decision

__all__ = ["ZerosResult", "invariant_zeros", "system_zeros"]


@dataclass(frozen=True)
class ZerosResult:
    """Finite invariant zeros and the decisions behind them.

    Attributes
    ----------
    zeros : ndarray of complex
        Finite invariant zeros (sorted by modulus).
    normal_rank : int
        Normal rank of the Rosenbrock pencil ``[[Phi - zI, G], [Xi, 0]]``.
    full_normal_rank : bool
        Whether ``normal_rank = n + q`` (the pencil has full column rank: the
        system is left invertible).
    decisions : list of RankDecision
        Every rank decision taken during the reduction.
    method : str
        ``"reduction"`` (staircase reduction to a regular pencil without
        infinite eigenvalues).
    n : int
        State dimension.
    q : int
        Number of disturbance channels.
    """

    zeros: NDArray[np.complex128]
    normal_rank: int
    full_normal_rank: bool
    n: int
    q: int
    decisions: list[RankDecision] = field(default_factory=list)
    method: str = "reduction"

    @property
    def margin_decades(self) -> float:
        """Smallest margin (decades) of any rank decision taken."""
        return min_margin(self.decisions)

    def outside_or_on_unit_circle(self, tol: float = UNIT_CIRCLE_TOL) -> NDArray[np.complex128]:
        """Zeros with ``|z| >= 1 - tol``.

        Parameters
        ----------
        tol : float
            Zeros with ``|z| >= 1 - tol`` count as on the circle (default
            ``UNIT_CIRCLE_TOL``).
        """
        return not_inside_unit_circle(self.zeros, tol)

    def __repr__(self) -> str:
        zs = format_complex_list(self.zeros)
        return (f"ZerosResult(zeros=[{zs}], normal_rank={self.normal_rank} of {self.n + self.q}, "
                f"margin={self.margin_decades:.1f} decades)")


def _reduce(A, B, C, D, rtol, scale, decisions):
    """Emami-Naeini & Van Dooren's REDUCE: same finite zeros, ``D`` of full row rank.

    One step: compress the rows of ``D``; the rows of ``[C D]`` with zero
    ``D``-part, ``[C2 0]``, are column-compressed to ``[0 C22]``; since
    ``C22`` has full column rank those states are forced to zero, and the
    pencil deflates (by unimodular row operations) to the system
    ``(A11, B1, [A21; C11], [B2; D1])`` of order ``n - rho``.
    """
    while True:
        n = A.shape[0]
        p = D.shape[0]
        if p == 0:
            return A, B, C, D
        if D.size:
            U = svd(D, full_matrices=True)[0]
            dec = rank_decision(D, rtol, scale)
            decisions.append(dec)
            sigma = dec.rank
        else:
            U, sigma = np.eye(p), 0
        Cu = U.T @ C
        Du = U.T @ D
        C1, D1, C2 = Cu[:sigma], Du[:sigma], Cu[sigma:]
        if C2.shape[0] == 0:
            return A, B, C1, D1
        if n == 0:
            return A, B, C1, D1
        V2t = svd(C2, full_matrices=True)[2]
        dec2 = rank_decision(C2, rtol, scale)
        decisions.append(dec2)
        rho = dec2.rank
        if rho == 0:
            return A, B, C1, D1  # zero rows: part of the left null structure
        V = np.hstack([V2t[rho:].T, V2t[:rho].T])
        At = V.T @ A @ V
        Bt = V.T @ B
        C1t = C1 @ V
        k = n - rho
        A, B, C, D = (At[:k, :k], Bt[:k], np.vstack([At[k:, :k], C1t[:, :k]]),
                      np.vstack([Bt[k:], D1]))


def system_zeros(
    A: ArrayLike, B: ArrayLike, C: ArrayLike, D: ArrayLike | None = None, *,
    rtol: float = RANK_RTOL,
) -> ZerosResult:
    """Finite invariant zeros of the pencil ``[[A - zI, B], [C, D]]``.

    Algorithm (Emami-Naeini & Van Dooren, Automatica 18(4), 1982):

    1. balance ``(A, B, C)`` with one diagonal scaling (exact powers of two);
    2. REDUCE the system until ``D`` has full row rank, then REDUCE the dual,
       so that ``D`` also has full column rank. Each step removes infinite
       zeros and Kronecker (null-space) structure *exactly*, by orthogonal
       compressions and deflation, never by thresholding huge eigenvalues;
    3. compress the columns of ``[C D]`` to ``[0 D_f]`` with an orthogonal ``W``;
       the zeros are the eigenvalues of the regular pencil formed by the first
       columns of ``[A - zI, B] W``.

    Rank decisions use ``rtol`` relative to the norm of the balanced system
    matrix; each is recorded with its margin.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    B : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (l, n)
        Output matrix.
    D : array_like, shape (l, m), optional
        Feedthrough (default zero).
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    """
    A_a = np.atleast_2d(np.asarray(A, dtype=float))
    B_a = np.asarray(B, dtype=float).reshape(A_a.shape[0], -1)
    C_a = np.asarray(C, dtype=float).reshape(-1, A_a.shape[0])
    n, m = B_a.shape
    p = C_a.shape[0]
    D_a = np.zeros((p, m)) if D is None else np.asarray(D, dtype=float).reshape(p, m)
    Ab, Bb, Cb, _, du, dy = balance_system(A_a, B_a, C_a)
    Db = (1.0 / dy)[:, None] * D_a * du[None, :]
    scale = float(np.linalg.norm(np.block([[Ab, Bb], [Cb, Db]]), 2)) or 1.0
    decisions: list[RankDecision] = []
    # Normal rank: rank of the pencil at a random point (generic).
    rng = np.random.default_rng(12345)
    z0 = complex(rng.uniform(-2, 2), rng.uniform(-2, 2))
    P0 = np.block([[Ab - z0 * np.eye(n), Bb], [Cb, Db]])
    nr_dec = rank_decision(P0, rtol, scale * (1 + abs(z0)))
    decisions.append(nr_dec)
    normal_rank = nr_dec.rank
    A1, B1, C1, D1 = _reduce(Ab, Bb, Cb, Db, rtol, scale, decisions)
    Ad, Bd, Cd, Dd = _reduce(A1.T, C1.T, B1.T, D1.T, rtol, scale, decisions)
    Ar, Br, Cr, Dr = Ad.T, Cd.T, Bd.T, Dd.T
    nf = Ar.shape[0]
    if nf == 0:
        zeros = np.zeros(0, dtype=complex)
    else:
        CD = np.hstack([Cr, Dr])
        if CD.shape[0] == 0:
            zeros = eigvals(Ar).astype(complex)
        else:
            # Column compression [C D] W = [0 D_f]: W's last columns span the row space.
            Vt = svd(CD, full_matrices=True)[2]
            dec = rank_decision(CD, rtol, scale)
            decisions.append(dec)
            r = dec.rank
            W = np.hstack([Vt[r:].T, Vt[:r].T])
            AB = np.hstack([Ar, Br]) @ W
            E = np.hstack([np.eye(nf), np.zeros((nf, Br.shape[1]))]) @ W
            k = W.shape[1] - r
            if k != nf:
                raise InternalError(
                    f"pencil reduction did not end square ({nf} x {k}); please report this system"
                )
            zeros = eigvals(AB[:, :k], E[:, :k]).astype(complex)
            if not np.all(np.isfinite(zeros)):
                raise InternalError("pencil reduction left infinite eigenvalues; please report")
    zeros = zeros[np.argsort(np.abs(zeros), kind="stable")]
    return ZerosResult(zeros, normal_rank, normal_rank == n + m, n, m, decisions)


def invariant_zeros(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> ZerosResult:
    """Finite invariant zeros of ``(Phi, G, Xi)``: where ``[[Phi - zI, G], [Xi, 0]]`` loses rank.

    Robust to infinite zeros (no huge spurious values): see :func:`system_zeros`.
    When python-control with slycot is installed, ``compare_with_slycot`` in the
    tests cross-checks the result.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).

    Examples
    --------
    >>> from setobs.examples import chang2006
    >>> z = invariant_zeros(chang2006()).zeros
    >>> [round(float(v.real), 5) for v in z]
    [1.26095]
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    return system_zeros(sys.Phi, sys.G, sys.Xi, rtol=rtol)
