"""Scale-aware numerical rank decisions and balancing (the analysis tolerance policy)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray
from scipy.linalg import matrix_balance, svd

from ..tolerances import FRAGILE_MARGIN_DECADES, RANK_RTOL, UNIT_CIRCLE_TOL

__all__ = ["RankDecision", "balance_system", "min_margin", "not_inside_unit_circle", "orth_rows",
           "rank_decision"]


@dataclass(frozen=True)
class RankDecision:
    """A numerical rank with the numbers it was decided on.

    Attributes
    ----------
    rank : int
        The decided rank.
    singular_values : ndarray
        All singular values, descending.
    threshold : float
        Singular values above it count as nonzero.
    """

    rank: int
    singular_values: NDArray[np.float64]
    threshold: float

    @property
    def smallest_kept(self) -> float:
        """Smallest singular value counted as nonzero (``inf`` if rank 0)."""
        return float(self.singular_values[self.rank - 1]) if self.rank else np.inf

    @property
    def largest_dropped(self) -> float:
        """Largest singular value counted as zero (0 if full rank)."""
        s = self.singular_values
        return float(s[self.rank]) if self.rank < s.size else 0.0

    @property
    def margin_decades(self) -> float:
        """Distance of the decision from the threshold, in decades (log10).

        ``min(log10(smallest_kept / threshold), log10(threshold / largest_dropped))``;
        ``inf`` when nothing is close. Small margins mean a fragile verdict.
        """
        t = max(self.threshold, np.finfo(float).tiny)
        a = np.log10(self.smallest_kept / t) if self.rank else np.inf
        b = np.log10(t / self.largest_dropped) if self.largest_dropped > 0 else np.inf
        return float(min(a, b))

    @property
    def fragile(self) -> bool:
        """Whether the margin is below ``FRAGILE_MARGIN_DECADES``."""
        return self.margin_decades < FRAGILE_MARGIN_DECADES

    def __repr__(self) -> str:
        return (f"RankDecision(rank={self.rank}, margin={self.margin_decades:.1f} decades, "
                f"kept>={self.smallest_kept:.3g}, dropped<={self.largest_dropped:.3g}, "
                f"threshold={self.threshold:.3g})")


def min_margin(decisions: list[RankDecision]) -> float:
    """Smallest margin (decades) of a list of rank decisions (``inf`` if none)."""
    return min((d.margin_decades for d in decisions), default=np.inf)


def rank_decision(M: NDArray[np.float64], rtol: float = RANK_RTOL,
                  scale: float | None = None) -> RankDecision:
    """Numerical rank of ``M``: singular values above ``rtol * scale`` (default ``||M||_2``)."""
    if M.size == 0:
        return RankDecision(0, np.zeros(0), 0.0)
    s = svd(M, compute_uv=False)
    ref = float(s[0]) if scale is None else float(scale)
    thr = rtol * ref
    r = int((s > thr).sum()) if ref > 0 else 0
    return RankDecision(r, s, thr)


def orth_rows(M: NDArray[np.float64], rtol: float = RANK_RTOL, scale: float | None = None
              ) -> tuple[NDArray[np.float64], NDArray[np.float64], RankDecision]:
    """Orthonormal bases of the row space of ``M`` and of its orthogonal complement.

    Returns ``(R, N, decision)`` with ``R`` (rank x cols) spanning the row space
    and ``N`` ((cols - rank) x cols) spanning ``ker(M)``.
    """
    cols = M.shape[1]
    if M.shape[0] == 0:
        return np.zeros((0, cols)), np.eye(cols), RankDecision(0, np.zeros(0), 0.0)
    _, s, Vt = svd(M, full_matrices=True)
    ref = float(s[0]) if scale is None else float(scale)
    thr = rtol * ref
    r = int((s > thr).sum()) if ref > 0 else 0
    return Vt[:r], Vt[r:], RankDecision(r, s, thr)


def balance_system(
    A: NDArray[np.float64], B: NDArray[np.float64], C: NDArray[np.float64]
) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
           NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """Balance ``(A, B, C)`` with one diagonal scaling of states, inputs and outputs.

    LAPACK's balancing (``gebal``, scaling only, powers of two: exact) is applied
    to the square matrix ``[[A, B], [C, 0]]`` (padded), so that rows and
    columns of states, inputs and outputs have comparable norms. Ranks, invariant
    zeros and relative degrees are unchanged by these scalings.

    Returns
    -------
    Ab, Bb, Cb : ndarrays
        ``Dx^-1 A Dx``, ``Dx^-1 B Du``, ``Dy^-1 C Dx``: the state scaling
        from LAPACK's balancing, inputs and outputs then scaled to unit column
        and row norms.
    dx, du, dy : ndarrays
        The scalings (states, inputs, outputs).
    """
    n, m = B.shape
    p = C.shape[0]
    k = max(m, p)
    N = n + k
    S = np.zeros((N, N))
    S[:n, :n] = A
    S[:n, n : n + m] = B
    S[n : n + p, :n] = C
    # Zero rows/columns (e.g. an output that sees nothing) make gebal's scaling
    # degenerate; give them a unit diagonal so they are scaled neutrally.
    empty = ~(S.any(axis=0) | S.any(axis=1))
    S[empty, empty] = 1.0
    if N:
        _, (sc, _) = matrix_balance(S, permute=False, separate=True)
    else:
        sc = np.ones(0)
    dx = sc[:n]
    Ab = A * (1.0 / dx)[:, None] * dx[None, :]
    # Inputs and outputs: gebal cannot scale a row whose matching column of the
    # padded matrix is zero (outputs scaled by 1e8 and 1e-8 came out unscaled,
    # and a rank-2 C looked rank 1). Equilibrate them directly instead: unit
    # column norms of Dx^-1 B, unit row norms of C Dx (powers of two, exact).
    Bx = (1.0 / dx)[:, None] * B
    Cx = C * dx[None, :]
    du = 1.0 / _pow2_norm(np.linalg.norm(Bx, axis=0))
    dy = _pow2_norm(np.linalg.norm(Cx, axis=1))
    Bb = Bx * du[None, :]
    Cb = Cx / dy[:, None]
    return Ab, Bb, Cb, dx, du, dy


def _pow2_norm(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Powers of two close to ``v`` (1 where ``v`` is zero)."""
    out = np.ones(v.size)
    pos = v > 0
    out[pos] = np.ldexp(1.0, np.frexp(v[pos])[1] - 1)
    return out


def not_inside_unit_circle(values: NDArray, tol: float = UNIT_CIRCLE_TOL) -> NDArray:
    """The entries with ``|z| >= 1 - tol``: on or outside the unit circle.

    A value within ``tol`` of the circle counts as on it (a mode at ``z = 1``
    computed as ``0.99999999`` is still a mode at ``z = 1``).

    Parameters
    ----------
    values : ndarray
        Eigenvalues, zeros or poles.
    tol : float
        Distance from the circle that still counts as on it.
    """
    v = np.asarray(values)
    return v[np.abs(v) >= 1.0 - tol]
