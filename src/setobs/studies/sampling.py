"""Error order versus sampling period: a sampled-data study of the point observers.

Fu and Wang claim that the PIO's state error is ``O(T^2)`` and the higher-order
observer's ``O(T^3)`` in the sampling period ``T`` (their Theorems 1 and 2).
:func:`error_orders` measures the steady-state errors of both observers on a
continuous plant sampled at several periods, with the exact lumped ZOH
disturbance of their eq. (3) (integrated by Gauss–Legendre quadrature), and
:meth:`ErrorOrders.slope` gives the measured order (a log–log fit).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from ..exceptions import InvalidValueError
from ..models.linear import LinearSystem

__all__ = ["ErrorOrders", "error_orders"]


@dataclass(frozen=True)
class ErrorOrders:
    """Steady-state state errors per observer and sampling period.

    Attributes
    ----------
    periods : ndarray, shape (m,)
        Sampling periods ``T``.
    errors : dict of str to ndarray, shape (m,)
        ``max_k ||x(k) - x_hat(k)||_inf`` over the steady-state part, per observer.
    """

    periods: NDArray[np.float64]
    errors: dict[str, NDArray[np.float64]]

    def slope(self, name: str) -> float:
        """Measured order: slope of ``log(error)`` against ``log(T)`` (least squares).

        Parameters
        ----------
        name : str
            Observer name (a key of :attr:`errors`).

        Returns
        -------
        float
            The fitted slope.
        """
        return float(np.polyfit(np.log(self.periods), np.log(self.errors[name]), 1)[0])


def error_orders(H: ArrayLike, F: ArrayLike, C: ArrayLike,
                 disturbance: Callable[[float], ArrayLike], periods: Sequence[float], *,
                 tmax: float = 40.0, t_steady: float = 25.0,
                 quadrature_points: int = 10,
                 observers: Mapping[str, Callable[[LinearSystem], Any]] | None = None,
                 noise: Callable[[float], ArrayLike] | None = None) -> ErrorOrders:
    """Steady-state state errors of point observers at several sampling periods.

    The plant ``x' = H x + F f(t)``, ``y = C x`` (+ ``noise(t)``) is sampled
    exactly: ``x(k+1) = e^{HT} x(k) + int_0^T e^{Hs} F f((k+1)T - s) ds``
    (Fu–Wang eq. (3); the integral by Gauss–Legendre quadrature). By default the
    PIO and the higher-order observer run with their default (fixed discrete)
    poles, as in the paper's example; ``observers`` replaces them.

    Parameters
    ----------
    H : array_like, shape (n, n)
        Continuous state matrix.
    F : array_like, shape (n, q)
        Continuous disturbance matrix.
    C : array_like, shape (l, n)
        Output matrix.
    disturbance : callable
        ``t -> f(t)``, shape (q,).
    periods : sequence of float
        Sampling periods ``T`` (at least two, positive).
    tmax : float
        Length of each simulation.
    t_steady : float
        Start of the steady-state part over which the error maximum is taken.
    quadrature_points : int
        Gauss–Legendre points per sampling interval.
    observers : mapping of str to callable, optional
        ``name -> factory(sys)`` returning an observer with a state estimate
        (``run(Y).x_hat``), built for each sampled system (default
        ``{"PIO": PIO, "HO": HigherOrderObserver}``).
    noise : callable, optional
        ``t -> n(t)``, shape (l,): added to the sampled outputs (sensor noise).

    Returns
    -------
    ErrorOrders
        The errors; ``.slope(name)`` is the measured order of each observer.

    Raises
    ------
    InvalidValueError
        If fewer than two periods are given, a period is not positive, or
        ``t_steady >= tmax``.
    """
    from ..observers import PIO, HigherOrderObserver

    if observers is None:
        observers = {"PIO": PIO, "HO": HigherOrderObserver}
    if not observers:
        raise InvalidValueError("observers: at least one observer factory")
    Ts = np.asarray(periods, dtype=float)
    if Ts.ndim != 1 or Ts.size < 2 or not np.all(Ts > 0):
        raise InvalidValueError("periods: at least two positive sampling periods")
    if not 0 <= t_steady < tmax:
        raise InvalidValueError(f"t_steady={t_steady} must lie in [0, tmax={tmax})")
    Hm = np.asarray(H, dtype=float)
    Fm = np.asarray(F, dtype=float)
    Cm = np.asarray(C, dtype=float)
    gx, gw = np.polynomial.legendre.leggauss(quadrature_points)
    errs: dict[str, list[float]] = {name: [] for name in observers}
    for T in Ts:
        sys = LinearSystem.from_continuous(Hm, None, Fm, Cm, float(T))
        N = round(tmax / T)
        taus, ws = 0.5 * T * (gx + 1), 0.5 * T * gw
        kern = [expm(Hm * t) @ Fm for t in taus]
        x, X, Y = np.zeros(Hm.shape[0]), [], []
        for k in range(N):
            X.append(x)
            Y.append(Cm @ x if noise is None
                     else Cm @ x + np.asarray(noise(k * T), dtype=float))
            lumped = sum(w * (K @ np.asarray(disturbance((k + 1) * T - t), dtype=float))
                         for w, K, t in zip(ws, kern, taus, strict=True))
            x = sys.Phi @ x + lumped
        Xa, Ya = np.array(X), np.array(Y)
        ss = slice(int(t_steady / T), N)
        for name, factory in observers.items():
            x_hat = factory(sys).run(Ya).x_hat
            errs[name].append(float(np.abs(Xa[ss] - x_hat[ss]).max()))
    return ErrorOrders(Ts, {k: np.array(v) for k, v in errs.items()})
