"""Relative degrees, ``V0``, UIO conditions and the UIO delay (Chen-Gao-Lin)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import PRODUCT_RTOL, RANK_RTOL, UNIT_CIRCLE_TOL
from ._linalg import RankDecision, balance_system, not_inside_unit_circle, rank_decision
from .zeros import ZerosResult, invariant_zeros

__all__ = [
    "RelativeDegreeResult",
    "UIOReport",
    "markov_toeplitz",
    "relative_degrees",
    "uio_conditions",
    "uio_delay",
]


@dataclass(frozen=True)
class RelativeDegreeResult:
    """Disturbance relative degrees and ``V0`` (Chen-Gao-Lin, Lemma 2 and eq. (9)).

    Attributes
    ----------
    degrees : tuple of int or None
        ``r_i = min{k >= 1 : c_i A^(k-1) E != 0}``; ``None`` if output ``i``
        never sees the disturbance.
    V0 : ndarray or None
        Rows ``c_i A^(r_i - 1) E`` (``None`` if some ``r_i`` is undefined).
    nonsingular : bool
        Whether ``V0`` is square and nonsingular (rank decision on balanced data).
    diagonal : bool
        Whether ``V0`` is square and diagonal (off-diagonal entries below the
        threshold on balanced data).
    sum_equals_n : bool
        Whether ``r_1 + ... + r_p = n`` (with ``V0`` nonsingular this is
        condition 2 of Lemma 2, equivalent to "no invariant zeros").
    n : int
        State dimension of the extended system.
    decision : RankDecision or None
        The rank decision behind ``nonsingular`` (``None`` when ``V0`` is not square or
        undefined).
    """

    degrees: tuple[int | None, ...]
    V0: NDArray[np.float64] | None
    nonsingular: bool
    diagonal: bool
    sum_equals_n: bool
    n: int
    decision: RankDecision | None = None

    @property
    def lemma2_no_zeros(self) -> bool:
        """Condition 2 of Lemma 2: ``V0`` nonsingular and ``sum(r_i) = n``."""
        return self.nonsingular and self.sum_equals_n

    @property
    def r_max(self) -> int | None:
        """Largest relative degree."""
        if any(r is None for r in self.degrees):
            return None
        return int(max(self.degrees))  # type: ignore[type-var]

    def __repr__(self) -> str:
        return (f"RelativeDegreeResult(degrees={self.degrees}, nonsingular={self.nonsingular}, "
                f"diagonal={self.diagonal}, sum={sum(r or 0 for r in self.degrees)} vs n={self.n})")


def relative_degrees(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> RelativeDegreeResult:
    """Disturbance relative degrees ``r_i`` and ``V0`` of ``(Phi, G, Xi)``.

    A row ``c_i A^(k-1) E`` counts as nonzero when its norm exceeds
    ``PRODUCT_RTOL`` times its rounding-error scale (see
    :mod:`setobs.tolerances`), computed on the balanced system (so the verdict
    does not depend on the scaling of states, outputs or disturbances). ``rtol``
    decides the rank and diagonality of ``V0``. ``V0`` itself is returned in the
    original coordinates.

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
    >>> from setobs.examples import chen_gao_lin_example1
    >>> relative_degrees(chen_gao_lin_example1()).degrees
    (2, 4, 3)
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    A, E, C = sys.Phi, sys.G, sys.Xi
    n = sys.n
    Ab, Eb, Cb, _, _, _ = balance_system(A, E, C)
    refs = _product_scales(Ab, Eb, n + 1)
    degrees: list[int | None] = []
    for i in range(sys.l):
        row = Cb[i]
        nc = max(float(np.linalg.norm(row)), 1e-300)
        r = None
        M = Eb
        for k in range(1, n + 1):
            if np.linalg.norm(row @ M) > PRODUCT_RTOL * nc * refs[k - 1]:
                r = k
                break
            M = Ab @ M
        degrees.append(r)
    if any(r is None for r in degrees):
        return RelativeDegreeResult(tuple(degrees), None, False, False, False, n)
    V0 = np.vstack([C[i] @ np.linalg.matrix_power(A, r - 1) @ E for i, r in enumerate(degrees)])
    V0b = np.vstack([Cb[i] @ np.linalg.matrix_power(Ab, r - 1) @ Eb
                     for i, r in enumerate(degrees)])
    # Row-normalise the balanced V0 before deciding (row scaling keeps rank/diagonality).
    V0n = V0b / np.maximum(np.linalg.norm(V0b, axis=1, keepdims=True), 1e-300)
    square = V0.shape[0] == V0.shape[1]
    dec = rank_decision(V0n, rtol) if square else None
    nonsingular = bool(square and dec is not None and dec.rank == V0.shape[0])
    off = V0n - np.diag(np.diag(V0n)) if square else V0n
    diagonal = bool(square and np.abs(off).max(initial=0.0) <= rtol)
    total = int(sum(degrees))  # type: ignore[arg-type]
    return RelativeDegreeResult(tuple(degrees), V0, nonsingular, diagonal, total == n, n, dec)


def _product_scales(A, E, count):
    """Rounding-error scales of ``A^k E`` (k = 0..count-1): ``max(||A^k E||, ||A|| ||A^(k-1) E||)``.

    A computed ``C A^k E`` is accurate to about ``eps`` times
    ``||C|| * scale_k``; a threshold ``rtol * ||C|| * scale_k`` therefore
    separates true zeros (computed as rounding noise) from true nonzeros
    without the blow-up of the a-priori bound ``||A||^k`` for non-normal ``A``.
    """
    nA = float(np.linalg.norm(A, 2))
    scales = []
    M = E
    prev = None
    for _ in range(count):
        cur = float(np.linalg.norm(M, 2))
        scales.append(max(cur, nA * prev if prev is not None else 0.0, 1e-300))
        prev = cur
        M = A @ M
    return scales


def markov_toeplitz(A: ArrayLike, E: ArrayLike, C: ArrayLike, tau: int) -> NDArray[np.float64]:
    """Block lower-triangular Toeplitz ``M_tau`` of the Markov parameters (Chen-Gao-Lin eq. (26)).

    Block ``(i, j)`` is ``H_(i-j)`` with ``H_0 = 0`` and ``H_i = C A^(i-1) E``:
    ``Y[k:k+tau] = O_tau x(k) + M_tau U[k:k+tau]`` for ``x+ = A x + E u``, ``y = C x``.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    E : array_like, shape (n, m)
        Input matrix.
    C : array_like, shape (l, n)
        Output matrix.
    tau : int
        Delay: ``tau + 1`` block rows and columns.

    Returns
    -------
    ndarray, shape ((tau + 1) l, (tau + 1) m)
    """
    A_a, E_a, C_a = (np.atleast_2d(np.asarray(M, dtype=float)) for M in (A, E, C))
    l, m = C_a.shape[0], E_a.shape[1]
    H = [np.zeros((l, m))]
    P = E_a
    for _ in range(tau):
        H.append(C_a @ P)
        P = A_a @ P
    M = np.zeros(((tau + 1) * l, (tau + 1) * m))
    for i in range(tau + 1):
        for j in range(i + 1):
            M[i * l : (i + 1) * l, j * m : (j + 1) * m] = H[i - j]
    return M


def uio_delay(A: ArrayLike, E: ArrayLike, C: ArrayLike, *, rtol: float = RANK_RTOL,
              max_delay: int | None = None) -> tuple[int | None, list[RankDecision]]:
    """Minimal delay of a delayed UIO, Chen-Gao-Lin eqs. (25)-(26).

    ``tau = min{mu >= 0 : rank M_mu = q + rank M_(mu-1)}`` with the block-Toeplitz
    ``M_mu`` of ``H_0 = 0`` and ``H_i = C A^(i-1) E`` (``q = rank E``). Returns
    ``(None, decisions)`` if no ``mu <= max_delay`` (default ``n + 2``) works:
    the unknown input is not reconstructable with any delay.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    E : array_like, shape (n, q)
        Unknown-input matrix.
    C : array_like, shape (l, n)
        Output matrix.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    max_delay : int, optional
        Largest delay tried (default ``n``).
    """
    A_a = np.atleast_2d(np.asarray(A, dtype=float))
    E_a = np.asarray(E, dtype=float).reshape(A_a.shape[0], -1)
    C_a = np.asarray(C, dtype=float).reshape(-1, A_a.shape[0])
    Ab, Eb, Cb, _, _, _ = balance_system(A_a, E_a, C_a)
    q = rank_decision(Eb, rtol).rank
    n = A_a.shape[0]
    mu_max = n + 2 if max_delay is None else int(max_delay)
    # Rounding scale of H_i = C A^(i-1) E: the threshold must not be relative to
    # M itself, which is pure rounding noise while the true H_i vanish.
    nC = max(float(np.linalg.norm(Cb, 2)), 1e-300)
    refs = _product_scales(Ab, Eb, mu_max + 2)
    # M_mu is the leading block of M_mu_max (block lower-triangular Toeplitz)
    M_all = markov_toeplitz(Ab, Eb, Cb, mu_max)
    lb, mb = Cb.shape[0], Eb.shape[1]
    decisions = []
    prev = 0
    for mu in range(mu_max + 1):
        M = M_all[: (mu + 1) * lb, : (mu + 1) * mb]
        # No row normalisation either: a rounding-noise row (an exact zero computed
        # as 1e-17) would become a fake independent row.
        ref = nC * max(refs[: max(mu, 1)])
        d = rank_decision(M, PRODUCT_RTOL, scale=ref)
        decisions.append(d)
        if d.rank == q + prev:
            return mu, decisions
        prev = d.rank
    return None, decisions


@dataclass(frozen=True)
class UIOReport:
    """UIO existence conditions (Chen-Gao-Lin, Sec. III-A) and the delay.

    Attributes
    ----------
    condition_a : bool
        ``rank(Xi G) = rank(G)`` (needed for a real-time, undelayed UIO).
    condition_b : bool
        ``rank [[zI - Phi, -G], [Xi, 0]] = n + rank(G)`` for all ``|z| >= 1``:
        full normal rank and every invariant zero strictly inside the unit
        circle (strong detectability). Sufficient for a delayed UIO.
    strongly_detectable : bool
        Same as ``condition_b``.
    delay : int or None
        Minimal delay ``tau`` of eqs. (25)-(26) for the augmented system (14),
        ``None`` if not reconstructable.
    zeros : ZerosResult
    rank_XiG, rank_G : int
        The two ranks of condition (a).
    unstable_zeros : ndarray of complex
        Invariant zeros with ``|z| >= 1`` (those that break condition (b)).
    decisions : list of RankDecision
        Every rank decision taken.
    """

    condition_a: bool
    condition_b: bool
    delay: int | None
    rank_XiG: int
    rank_G: int
    zeros: ZerosResult
    unstable_zeros: NDArray[np.complex128]
    decisions: list[RankDecision] = field(default_factory=list)

    @property
    def strongly_detectable(self) -> bool:
        """Condition (b)."""
        return self.condition_b

    @property
    def realtime_uio_exists(self) -> bool:
        """Conditions (a) and (b): a full-state UIO without delay exists."""
        return self.condition_a and self.condition_b

    @property
    def delayed_uio_exists(self) -> bool:
        """Condition (b) alone: a delayed UIO exists (with ``delay`` steps)."""
        return self.condition_b and self.delay is not None


def uio_conditions(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL,
                   unit_tol: float = UNIT_CIRCLE_TOL) -> UIOReport:
    """UIO conditions (a), (b) for ``(Phi, G, Xi)`` and the delay for the augmented system.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    unit_tol : float
        Zeros with ``|z|`` within this of 1 count as on the unit circle
        (:data:`setobs.tolerances.UNIT_CIRCLE_TOL`).
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    _, Gb, Xb, _, _, _ = balance_system(sys.Phi, sys.G, sys.Xi)
    dG = rank_decision(Gb, rtol)
    dXG = rank_decision(Xb @ Gb, rtol, scale=float(np.linalg.norm(Xb, 2) * np.linalg.norm(Gb, 2)))
    z = invariant_zeros(sys, rtol=rtol)
    unstable = not_inside_unit_circle(z.zeros, unit_tol)
    cond_b = z.normal_rank == sys.n + dG.rank and unstable.size == 0
    aug = sys.augmented()
    tau, dd = uio_delay(aug.A, aug.E, aug.C, rtol=rtol)
    return UIOReport(dXG.rank == dG.rank, bool(cond_b), tau, dXG.rank, dG.rank, z, unstable,
                     [dG, dXG, *dd])
