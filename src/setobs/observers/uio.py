"""Delayed unknown-input observer (Sundaram & Hadjicostis 2007; Chen-Gao-Lin eqs. (23)-(26))."""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import lstsq, svd

from .._format import format_complex_list
from ..analysis import markov_toeplitz, uio_conditions, uio_delay
from ..models.linear import DisturbanceInputs, LinearSystem
from ._gains import place_gain
from .base import DesignError, PointObserver

__all__ = ["DelayedUIO"]


class DelayedUIO(PointObserver):
    """Delayed UIO for the augmented system (14) of Chen-Gao-Lin (eqs. (23)-(26)).

    ``X_hat(k+1) = J X_hat(k) + K (Y[k:k+tau] - N_tau U[k:k+tau]) + B u(k)``
    with ``Y[k:k+tau] = O_tau X(k) + M_tau DeltaF[k:k+tau] + N_tau U[k:k+tau]``.
    The gain ``K = F + Z Pi`` has ``F M_tau = [E, 0, ..., 0]`` (particular
    solution) and ``Pi = I - M_tau M_tau^+``, so ``K M_tau = [E 0 ... 0]`` and the
    error obeys ``e(k+1) = J e(k)`` with ``J = A - K O_tau`` (eq. (24)); ``Z``
    places the eigenvalues of ``J`` (default: all at 0, nilpotent).

    ``tau`` is the minimal delay of eqs. (25)-(26). The estimate of ``d(k)``
    (the ``f`` part of ``X_hat(k)``) becomes available at step ``k + tau``:
    ``run(Y).estimate[t]`` estimates ``d(t - tau)`` and is NaN for ``t < tau``.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The plant.
    poles : sequence of complex or float
        Eigenvalues of ``J = A - K O_tau`` (one value: all at it; default 0, a dead-beat
        error).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.

    Raises
    ------
    DesignError
        If condition (b) (strong detectability) fails, or no finite delay exists.
    """

    name = "delayed UIO"

    def __init__(self, sys: LinearSystem, poles: Sequence[complex] | float = 0.0,
                 *, disturbance_inputs: DisturbanceInputs = None) -> None:
        super().__init__(sys, disturbance_inputs=disturbance_inputs)
        sys = self.sys
        cond = uio_conditions(sys)
        if not cond.delayed_uio_exists:
            zs = format_complex_list(cond.unstable_zeros)
            raise DesignError("delayed UIO needs condition (b) (strong detectability); "
                              f"invariant zeros on/outside the unit circle: {zs or 'n/a'}",
                              "condition (b)")
        a = sys.augmented()
        A, E, C, B = a.A, a.E, a.C, a.Gamma
        N = A.shape[0]
        tau, _ = uio_delay(A, E, C)
        if tau is None:
            raise DesignError("no finite delay satisfies eq. (25)", "eq. (25)")
        self.delay = tau
        O = np.vstack([C @ np.linalg.matrix_power(A, i) for i in range(tau + 1)])
        M = markov_toeplitz(A, E, C, tau)
        Nu = markov_toeplitz(A, B, C, tau) if sys.p else np.zeros((O.shape[0], 0))
        target = np.hstack([E, np.zeros((N, tau * E.shape[1]))])
        F = lstsq(M.T, target.T)[0].T
        if np.abs(F @ M - target).max() > 1e-8 * max(1.0, np.abs(target).max()):
            raise DesignError("F M_tau = [E 0 ... 0] has no solution", "eq. (25)")
        Pi = np.eye(M.shape[0]) - M @ np.linalg.pinv(M)
        A1 = A - F @ O
        U, s, _ = svd(Pi @ O)
        r = int((s > 1e-10 * max(s[0], 1.0)).sum())
        Cbar = U[:, :r].T @ Pi @ O
        pol = np.full(N, float(poles)) if np.ndim(poles) == 0 else np.asarray(poles, complex)
        if pol.size != N:
            raise DesignError(f"need {N} poles, got {pol.size}", "poles")
        Zbar = place_gain(A1, Cbar, pol, check="radius")
        K = F + Zbar @ U[:, :r].T @ Pi
        self.J, self.K, self.O_tau, self.M_tau, self.Nu, self.B = A - K @ O, K, O, M, Nu, B
        self.tau = tau
        self.reset()

    def reset(self) -> None:
        """Restart with ``X_hat(0) = 0`` and empty data buffers."""
        self.X = np.zeros(self.J.shape[0])
        self._Y: deque = deque(maxlen=self.tau + 1)
        self._U: deque = deque(maxlen=self.tau + 1)

    def step(self, y: ArrayLike, u: ArrayLike | None = None) -> NDArray[np.float64]:
        yv, uv = self._check(y, u)
        self._Y.append(yv)
        self._U.append(uv)
        q = self.sys.q
        if len(self._Y) < self.tau + 1:
            return np.full(q, np.nan)
        Ystack = np.concatenate(list(self._Y))
        Ustack = np.concatenate(list(self._U)) if self.sys.p else np.zeros(0)
        d = self.X[-q:].copy()  # estimate of d(k), k = t - tau
        u_k = self._U[0]
        self.X = (self.J @ self.X + self.K @ (Ystack - (self.Nu @ Ustack if self.sys.p else 0.0))
                  + (self.B @ u_k if self.sys.p else 0.0))
        return d

    @property
    def gains(self) -> dict:
        return {"K": self.K}

    @property
    def transition(self) -> NDArray[np.float64]:
        """The error dynamics' matrix ``J = A - K O_tau`` (eq. (24))."""
        return self.J
