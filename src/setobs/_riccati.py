"""The steady-state Kalman predictor gain (discrete LQE), shared by the observers and the checks."""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import solve_discrete_are

from .exceptions import DesignError

__all__ = ["lqe_gain"]


def lqe_gain(A: ArrayLike, C: ArrayLike, Q: ArrayLike, R: ArrayLike, *,
             return_solution: bool = False) -> Any:
    """Steady-state Kalman predictor gain (discrete LQE) for ``x+ = A x + w``, ``y = C x + v``.

    ``L = A P C^T (C P C^T + R)^-1`` with ``P`` the stabilising solution of
    ``P = A P A^T - A P C^T (C P C^T + R)^-1 C P A^T + Q`` (``cov w = Q``,
    ``cov v = R``), so that ``x^+ = A x^ + L (y - C x^)`` is the one-step
    predictor of the Kalman filter in steady state. The one copy of this formula:
    the LQE designs, the modular observer's default ``L0``, the descriptor
    observer's eq. (18) and the modular existence check all call it.

    Parameters
    ----------
    A : array_like, shape (n, n)
        State matrix.
    C : array_like, shape (l, n)
        Output matrix.
    Q : array_like, shape (n, n)
        Process-noise covariance (symmetric positive semidefinite).
    R : array_like, shape (l, l)
        Measurement-noise covariance (symmetric positive definite).
    return_solution : bool
        Also return the Riccati solution ``P``.

    Returns
    -------
    L : ndarray, shape (n, l)
        The gain.
    P : ndarray, shape (n, n)
        The stabilising Riccati solution (only with ``return_solution``).

    Raises
    ------
    DesignError
        If the Riccati equation has no stabilising solution (e.g. an
        undetectable pair, or a noise-free mode on the unit circle).
    """
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    Q = np.asarray(Q, dtype=float)
    R = np.asarray(R, dtype=float)
    if Q.shape != A.shape:
        raise DesignError(f"process covariance must be {A.shape}, got {Q.shape}", "covariance")
    if R.shape != (C.shape[0], C.shape[0]):
        raise DesignError(f"measurement covariance must be {(C.shape[0],) * 2}, got {R.shape}",
                          "covariance")
    for name, M in (("process", Q), ("measurement", R)):
        if not np.allclose(M, M.T) or np.linalg.eigvalsh(0.5 * (M + M.T)).min() < 0:
            raise DesignError(f"the {name} covariance must be symmetric positive semidefinite",
                              "covariance")
    if np.linalg.eigvalsh(0.5 * (R + R.T)).min() <= 0:
        raise DesignError("the measurement covariance must be positive definite", "covariance")
    try:
        P = solve_discrete_are(A.T, C.T, Q, R)
    except (np.linalg.LinAlgError, ValueError) as exc:
        raise DesignError(f"no stabilising Riccati solution (discrete LQE): {exc}",
                          "LQE") from None
    L = A @ P @ C.T @ np.linalg.inv(C @ P @ C.T + R)
    if np.abs(np.linalg.eigvals(A - L @ C)).max() >= 1.0:
        raise DesignError("the LQE gain does not stabilise the error system (a noise-free "
                          "mode on the unit circle?)", "LQE")
    return (L, P) if return_solution else L
