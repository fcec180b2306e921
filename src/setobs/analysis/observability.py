"""Observability matrices, observability index, and the orthonormal observability decomposition."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigvals

from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import RANK_RTOL
from ._linalg import RankDecision, balance_system, min_margin, not_inside_unit_circle, orth_rows

__all__ = [
    "ObservabilityDecomposition",
    "ObservabilityReport",
    "augmented_observability",
    "observability",
    "observability_decomposition",
    "observability_matrix",
]


def observability_matrix(A: ArrayLike, C: ArrayLike, blocks: int | None = None
                         ) -> NDArray[np.float64]:
    """``O = [C; C A; ...; C A^(blocks-1)]`` (Li-Cong-Dong, eq. (16); default ``blocks = n``).

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    C : array_like, shape (l, n)
        Output matrix.
    blocks : int, optional
        Number of block rows (default ``n``).
    """
    A_a = np.atleast_2d(np.asarray(A, dtype=float))
    C_a = np.atleast_2d(np.asarray(C, dtype=float))
    N = A_a.shape[0] if blocks is None else int(blocks)
    rows = [C_a]
    for _ in range(N - 1):
        rows.append(rows[-1] @ A_a)
    return np.vstack(rows)


@dataclass(frozen=True)
class ObservabilityReport:
    """Observable subspace of a pair ``(A, C)`` from an orthogonal staircase.

    Attributes
    ----------
    n : int
        State dimension.
    n_observable : int
        Dimension of the observable subspace (rank of the observability matrix).
    index : int
        Observability index ``mu``: the number of blocks ``C A^k`` needed.
    observable_rows : ndarray, shape (n_observable, n)
        Orthonormal basis (rows) of the observable directions ``row(O)``, in
        the original coordinates.
    unobservable_rows : ndarray, shape (n - n_observable, n)
        Orthonormal basis (rows) of the unobservable subspace ``ker(O)``.
    unobservable_modes : ndarray of complex
        Eigenvalues of ``A`` restricted to the unobservable subspace.
    decisions : list of RankDecision
    """

    n: int
    n_observable: int
    index: int
    observable_rows: NDArray[np.float64]
    unobservable_rows: NDArray[np.float64]
    unobservable_modes: NDArray[np.complex128]
    decisions: list[RankDecision] = field(default_factory=list)

    @property
    def observable(self) -> bool:
        """Whether the pair is observable."""
        return self.n_observable == self.n

    @property
    def detectable(self) -> bool:
        """Whether every unobservable mode is strictly inside the unit circle.

        Modes within ``UNIT_CIRCLE_TOL`` of the circle count as not stable (a mode
        at ``z = 1`` computed as ``0.99999999`` is still a mode at ``z = 1``).
        """
        return self.unstable_unobservable_modes.size == 0

    @property
    def unstable_unobservable_modes(self) -> NDArray[np.complex128]:
        """Unobservable modes on or outside the unit circle (within ``UNIT_CIRCLE_TOL``)."""
        m = self.unobservable_modes
        return not_inside_unit_circle(m)

    @property
    def margin_decades(self) -> float:
        """Smallest margin of the rank decisions (decades)."""
        return min_margin(self.decisions)

    def __repr__(self) -> str:
        return (f"ObservabilityReport(n_observable={self.n_observable} of {self.n}, "
                f"index={self.index}, detectable={self.detectable}, "
                f"margin={self.margin_decades:.1f} decades)")


def _staircase(Ab: NDArray[np.float64], Cb: NDArray[np.float64], rtol: float):
    """Orthogonal observability staircase on balanced data: rows spanning row(O)."""
    n = Ab.shape[0]
    scaleA = max(float(np.linalg.norm(Ab, 2)), 1e-300)
    Q, _, dec = orth_rows(Cb, rtol)
    decisions = [dec]
    basis = Q
    block = Q
    index = 1 if Q.shape[0] else 0
    while basis.shape[0] < n and block.shape[0]:
        new = block @ Ab
        R = new - (new @ basis.T) @ basis
        Qn, _, d = orth_rows(R, rtol, scale=scaleA)
        decisions.append(d)
        if Qn.shape[0] == 0:
            break
        # Re-orthogonalise against the basis (twice is enough).
        Qn = Qn - (Qn @ basis.T) @ basis
        Qn, _, _ = orth_rows(Qn, 1e-3)
        basis = np.vstack([basis, Qn])
        block = Qn
        index += 1
    return basis, index, decisions


def observability(A: ArrayLike, C: ArrayLike, *, rtol: float = RANK_RTOL) -> ObservabilityReport:
    """Observable subspace, observability index and unobservable modes of ``(A, C)``.

    Computed by an orthogonal staircase (no explicit powers ``A^k``) on a
    balanced realisation; the bases are mapped back to the original
    coordinates and re-orthonormalised, so the result does not depend on the
    scaling of states or outputs.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    C : array_like, shape (l, n)
        Output matrix.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    """
    A_a = np.atleast_2d(np.asarray(A, dtype=float))
    C_a = np.atleast_2d(np.asarray(C, dtype=float))
    n = A_a.shape[0]
    Ab, _, Cb, dx, _, _ = balance_system(A_a, np.zeros((n, 0)), C_a)
    basis_b, index, decisions = _staircase(Ab, Cb, rtol)
    n_o = basis_b.shape[0]
    # Unobservable subspace in balanced coordinates: complement of the basis rows;
    # in original coordinates x = Dx x_b, so kernel vectors map by Dx.
    _, null_b, _ = orth_rows(basis_b, 1e-6) if n_o else (None, np.eye(n), None)
    null_orig = (dx[:, None] * null_b.T).T if null_b.shape[0] else np.zeros((0, n))
    if null_orig.shape[0]:
        qn, _ = np.linalg.qr(null_orig.T)
        unobs = qn.T
        _, obs, _ = orth_rows(unobs, 1e-6)  # orthogonal complement: observable directions
        modes = eigvals(unobs @ A_a @ unobs.T) if unobs.shape[0] else np.zeros(0, complex)
    else:
        unobs = np.zeros((0, n))
        obs = np.eye(n)
        modes = np.zeros(0, dtype=complex)
    return ObservabilityReport(n, n_o, index, obs, unobs, np.asarray(modes, dtype=complex),
                               decisions)


@dataclass(frozen=True)
class ObservabilityDecomposition:
    """Orthonormal observability decomposition of the augmented system (Li-Cong-Dong, (12)-(14)).

    ``T = [T_o; T_obar]`` is orthogonal, ``z_tilde = T D^-1 z`` with ``z = [x; d]``
    and ``D = diag(state_scale)`` (identity unless a balanced decomposition was
    asked for); with ``A_b = D^-1 A D``, ``C_b = diag(output_scale)^-1 C D``:
    ``A_tilde = T A_b T^T = [[A_o, 0], [A_21, A_obar]]``,
    ``B_tilde = T D^-1 [0; I_q]``, ``Gamma_tilde = T D^-1 [Gamma; 0]``,
    ``C_tilde = C_b T^T = [C_o, 0]``; measurements enter as
    ``y_b = diag(output_scale)^-1 y``.

    Attributes
    ----------
    T_o, T_obar : ndarray
        Rows of ``T`` spanning the observable and the unobservable part.
    A_o, A_21, A_obar : ndarray
        Blocks of ``A_tilde``.
    B_o, B_obar : ndarray
        Blocks of ``B_tilde`` (where ``dd`` enters).
    Gamma_o, Gamma_obar : ndarray
        Blocks of ``Gamma_tilde`` (where ``u`` enters).
    C_o : ndarray
        Nonzero block of ``C_tilde``.
    report : ObservabilityReport
        The rank decisions behind the split.
    state_scale, output_scale : ndarray or None
        The balancing ``D`` and output scaling (``None``: identity).
    """

    T_o: NDArray[np.float64]
    T_obar: NDArray[np.float64]
    A_o: NDArray[np.float64]
    A_21: NDArray[np.float64]
    A_obar: NDArray[np.float64]
    B_o: NDArray[np.float64]
    B_obar: NDArray[np.float64]
    Gamma_o: NDArray[np.float64]
    Gamma_obar: NDArray[np.float64]
    C_o: NDArray[np.float64]
    report: ObservabilityReport
    state_scale: NDArray[np.float64] | None = None
    output_scale: NDArray[np.float64] | None = None

    @property
    def T(self) -> NDArray[np.float64]:
        """The orthogonal transformation ``[T_o; T_obar]``."""
        return np.vstack([self.T_o, self.T_obar])

    @property
    def N_o(self) -> int:
        """Dimension of the observable part of the augmented system."""
        return int(self.T_o.shape[0])


def augmented_observability(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> ObservabilityReport:
    """Observability report of the augmented pair ``(A, C)`` of eqs. (9)-(11).

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    aug = sys.augmented()
    return observability(aug.A, aug.C, rtol=rtol)


def observability_decomposition(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL,
                                balance: bool = False,
                                disturbance_scale: ArrayLike | None = None
                                ) -> ObservabilityDecomposition:
    """Orthonormal observability decomposition of the augmented system, eqs. (12)-(14).

    Parameters
    ----------
    balance : bool
        Decompose a balanced realisation (diagonal power-of-two scaling of the
        augmented states and of the outputs, LAPACK ``gebal`` on
        ``[[A, E S], [C, 0]]``): the decomposition is then orthogonal in
        balanced coordinates (``state_scale``, ``output_scale`` record the
        scaling). Badly scaled models (entries from ``1e-9`` to ``1e7``) give
        well-conditioned observable coordinates this way.
    disturbance_scale : array_like, shape (q,), optional
        Magnitudes ``S`` of the disturbance increments, used by the balancing.
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    aug = sys.augmented()
    A, E, C, Gam = aug.A, aug.E, aug.C, aug.Gamma
    dz = dy = None
    if balance:
        S = np.ones(sys.q) if disturbance_scale is None else np.asarray(disturbance_scale,
                                                                        dtype=float)
        S = np.where(np.isfinite(S) & (S > 0), S, 1.0)
        _, _, _, dz, _, dy = balance_system(A, E * S, C)
        A = A / dz[:, None] * dz[None, :]
        E = E / dz[:, None]
        Gam = Gam / dz[:, None]
        C = C / dy[:, None] * dz[None, :]
    rep = observability(A, C, rtol=rtol)
    T_o, T_ob = rep.observable_rows, rep.unobservable_rows
    N_o = T_o.shape[0]
    T = np.vstack([T_o, T_ob])
    At = T @ A @ T.T
    Bt = T @ E
    Gt = T @ Gam
    Ct = C @ T.T
    return ObservabilityDecomposition(
        T_o, T_ob, At[:N_o, :N_o], At[N_o:, :N_o], At[N_o:, N_o:], Bt[:N_o], Bt[N_o:],
        Gt[:N_o], Gt[N_o:], Ct[:, :N_o], rep, dz, dy,
    )

