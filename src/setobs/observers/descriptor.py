"""State and unknown-input observer with sensor noise via a descriptor model (Chang fragment)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import as_matrix
from ..analysis import observability
from ..models.linear import DisturbanceInputs, LinearSystem
from ._gains import lqe_gain, place_gain
from .base import DesignError, PointObserver

__all__ = ["DescriptorObserver"]


class DescriptorObserver(PointObserver):
    """Descriptor observer for ``x+ = Phi x + Gamma u + G d``, ``y = Xi x + F n`` (Chang fragment).

    **Reconstructed** from the surviving fragment of Chang's report (its displayed
    eqs. (8)-(16) are missing, although the text refers to (9), the observer, and
    (16), which Lemma 4 turns into (17); eqs. (2), (6)-(7), (17)-(19) and Lemmas 1-4
    survive):

    * descriptor augmentation (6)-(7): ``z = [x; n]``,
      ``E z(k+1) = Abar z(k) + Bbar [u(k); y(k)] + [G d(k); 0]``,
      ``y = Cbar z`` with ``E = diag(I_n, 0_l)``, ``Abar = [[Phi, 0], [-F^+ Xi, -I_l]]``,
      ``Bbar = diag(Gamma, F^+)``, ``Cbar = [Xi, F]``, ``F^+ = (F^T F)^-1 F^T``
      (the second row is ``0 = -F^+ Xi x - n + F^+ y``, exact since ``F^+ F = I``);
    * regularisation with ``K = [0; F^+]``: ``R = E + K Cbar`` is invertible
      (Lemma 1 (2): ``rank [E; Cbar] = n + l``) and
      ``R z(k+1) = Abar z(k) + Bbar v(k) + [G d; 0] + K y(k+1)`` is exact;
    * the disturbance as a state, ``w = [z; d]``, ``d(k+1) = d(k)`` (Lemma 4: the
      neglected terms are ``O(T^2)``): ``w+ = A_w w + B_w [v; y(k+1)] + p``,
      ``y = C_w w``, and the observer ``w^+ = A_w w^ + B_w [v; y(k+1)] + L (y - C_w w^)``
      with error ``w~+ = (A_w - L C_w) w~ + p`` (eq. (17));
    * the gain from the DARE (18)-(19): ``L = A_w P C_w^T (R_w + C_w P C_w^T)^-1``.

    The sensor noise is reconstructed as a state, so it does not enter the error
    dynamics: with a constant disturbance the estimates become exact whatever the
    noise (checked in the tests).

    Parameters
    ----------
    sys : LinearSystem
    F : array_like, shape (l_y, l_n)
        Sensor-noise matrix of full column rank.
    Q_w, R_w : array_like, optional
        DARE weights (default identities).
    poles : sequence of complex, optional
        Place the ``n + l_n + q`` error poles of ``A_w - L C_w`` instead of
        solving the DARE ("the conventional pole assignment method" of the
        fragment, before eq. (18)). Theorem 1's ``O(T^2)`` bound assumes the
        error system's contraction stays bounded away from 1 as ``T`` shrinks:
        fixed discrete poles do that, a DARE with fixed weights does not
        (its poles drift towards 1; see ``tests/observers/test_chang_fragment.py``).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    """

    name = "descriptor observer"

    def __init__(self, sys: LinearSystem, F: ArrayLike, Q_w: ArrayLike | None = None,
                 R_w: ArrayLike | None = None,
                 *, poles: Sequence[complex] | None = None,
                 disturbance_inputs: DisturbanceInputs = None) -> None:
        super().__init__(sys, disturbance_inputs=disturbance_inputs)
        self.information = "filtered"  # step k uses y_(k-1) and y_k (eq. of the augmentation)
        sys = self.sys
        n, q, ly, p = sys.n, sys.q, sys.l, sys.p
        F_a = as_matrix("F", F, rows=ly)
        ln = F_a.shape[1]
        if np.linalg.matrix_rank(F_a) != ln:
            raise DesignError("F must have full column rank", "rank F = l")
        Fp = np.linalg.solve(F_a.T @ F_a, F_a.T)
        E = np.block([[np.eye(n), np.zeros((n, ln))], [np.zeros((ln, n + ln))]])
        Abar = np.block([[sys.Phi, np.zeros((n, ln))], [-Fp @ sys.Xi, -np.eye(ln)]])
        Bbar = np.block([[sys.Gamma, np.zeros((n, ly))], [np.zeros((ln, p)), Fp]])
        Cbar = np.hstack([sys.Xi, F_a])
        K = np.vstack([np.zeros((n, ly)), Fp])
        R = E + K @ Cbar
        Ri = np.linalg.inv(R)
        nz = n + ln
        A_w = np.block([[Ri @ Abar, Ri @ np.vstack([sys.G, np.zeros((ln, q))])],
                        [np.zeros((q, nz)), np.eye(q)]])
        B_w = np.vstack([Ri @ np.hstack([Bbar, K]), np.zeros((q, p + 2 * ly))])
        C_w = np.hstack([Cbar, np.zeros((ly, q))])
        rep = observability(A_w, C_w)
        if not rep.detectable:
            raise DesignError("the augmented descriptor pair (A_w, C_w) is not detectable "
                              "(Assumptions 2-3 of the fragment fail)", "Assumptions 2-3")
        if poles is not None:
            if Q_w is not None or R_w is not None:
                raise DesignError("give poles or the DARE weights Q_w, R_w, not both", "design")
            if len(poles) != nz + q:
                raise DesignError(f"poles: {nz + q} error poles are needed (n + l_n + q), "
                                  f"got {len(poles)}", "poles")
            L, P = place_gain(A_w, C_w, poles), None
        else:
            Qw = np.eye(nz + q) if Q_w is None else as_matrix("Q_w", Q_w, nz + q, nz + q)
            Rw = np.eye(ly) if R_w is None else as_matrix("R_w", R_w, ly, ly)
            L, P = lqe_gain(A_w, C_w, Qw, Rw, return_solution=True)  # eqs. (18)-(19)
        self.A_w, self.B_w, self.C_w, self.L, self.P_dare = A_w, B_w, C_w, L, P
        self.noise_matrix, self.n_noise = F_a, ln
        self.reset()

    @property
    def gains(self) -> dict:
        return {"L": self.L}

    def reset(self) -> None:
        """Restart with ``w^(0) = 0``."""
        self.w = np.zeros(self.A_w.shape[0])
        self._prev: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None

    def step(self, y: ArrayLike, u: ArrayLike | None = None) -> NDArray[np.float64]:
        yv, uv = self._check(y, u)
        if self._prev is not None:
            y0, u0 = self._prev
            v = np.concatenate([u0, y0, yv])
            self.w = self.A_w @ self.w + self.B_w @ v + self.L @ (y0 - self.C_w @ self.w)
        self._prev = (yv, uv)
        return self.w[-self.sys.q :].copy()

    def state_estimate(self) -> NDArray[np.float64] | None:
        return self.w[: self.sys.n].copy()

    def noise_estimate(self) -> NDArray[np.float64]:
        """Current estimate of the sensor noise ``n(k)``."""
        return self.w[self.sys.n : self.sys.n + self.n_noise].copy()
