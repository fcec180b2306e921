"""The common interface of point observers."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._deprecation import renamed
from .._validation import as_matrix, as_vector
from ..exceptions import ArgumentError, DesignError, DimensionError, NotSupportedError
from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..results import error_summary, time_axis, time_index

__all__ = ["DesignError", "ObserverResult", "PointObserver", "StateSpaceObserver"]


@dataclass(frozen=True)
class ObserverResult:
    """Output of :meth:`PointObserver.run` (the protocol of :mod:`setobs.results`).

    Unpacks as ``t, estimate = observer.run(Y)``.

    Attributes
    ----------
    estimate : ndarray, shape (N, q)
        Disturbance estimates (NaN where not yet available, e.g. during a delay).
    x_hat : ndarray, shape (N, n) or None
        State estimates, for observers that have one.
    delay : int
        Steps by which ``estimate[k]`` lags ``d[k]`` by design (0 for causal estimates).
    gains : dict
        The gains used.
    dt : float or None
        The system's sampling time (for time axes).
    names : tuple of str
        The disturbance names.
    observer : str
        The observer's name (row label of :meth:`summary`).
    information : str
        The measurements ``estimate[k]`` uses: ``"y_0..y_(k-1)"`` (the papers'
        observers, a one-step prediction) or ``"y_0..y_k"`` (as the SMFDO).
    """

    estimate: NDArray[np.float64]
    x_hat: NDArray[np.float64] | None
    delay: int
    gains: dict = field(default_factory=dict)
    dt: float | None = None
    names: tuple[str, ...] = ()
    observer: str = "observer"
    information: str = "y_0..y_(k-1)"

    d_hat = renamed("d_hat", "estimate", "the same name as SMFDOResult's")

    @property
    def time(self) -> NDArray[np.float64]:
        """Time axis ``k dt`` (or ``k`` when the sampling time is unknown)."""
        return time_axis(self.estimate.shape[0], self.dt)

    def __iter__(self):
        return iter((self.time, self.estimate))

    def to_pandas(self) -> Any:
        """A ``pandas.DataFrame``: one column per disturbance (the estimate), then the
        state estimates ``x_hat_<i>`` if any; indexed by time or step.

        Returns
        -------
        pandas.DataFrame
            The table.
        """
        import pandas as pd

        N = self.estimate.shape[0]
        q = self.estimate.shape[1]
        names = list(self.names) if len(self.names) == q else [f"d{i}" for i in range(q)]
        cols = dict(zip(names, self.estimate.T, strict=True))
        if self.x_hat is not None:
            cols.update({f"x_hat_{i}": col for i, col in enumerate(self.x_hat.T)})
        return pd.DataFrame(cols, index=time_index(N, self.dt))

    def plot(self, ax: Any = None, truth: ArrayLike | None = None, component: int = 0) -> Any:
        """Draw the estimate of one disturbance component (and the truth, if given).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default: the current axes).
        truth : array_like, shape (N, q), optional
            The true disturbance.
        component : int
            Disturbance component.

        Returns
        -------
        matplotlib Axes
            The axes drawn on.
        """
        from ..plotting import plot_estimate_band

        return plot_estimate_band(self, truth=truth, component=component, ax=ax,
                                  label=self.observer)

    def summary(self, truth: ArrayLike | None = None, start: int = 0) -> Any:
        """One row (index ``observer``): steps, delay and, with the truth, the mean and
        worst actual errors ``error_inf``, ``max_error_inf``, ``error_2`` over ``k >= start``.

        Parameters
        ----------
        truth : array_like, shape (N, q), optional
            The true disturbance.
        start : int
            First step counted (skip the transient).

        Returns
        -------
        pandas.DataFrame
            The summary row.
        """
        return error_summary(self.observer, self.estimate, truth, start, {"delay": self.delay})


class PointObserver:
    """Base class: ``reset()``, ``step(y, u)`` and ``run(Y, U)`` on a :class:`LinearSystem`.

    ``step(y_k, u_k)`` consumes the measurement at step ``k`` and the input
    applied at step ``k`` (which affects ``x_(k+1)``), and returns the current
    disturbance estimate (NaN while unavailable).

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The plant.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    """

    name = "observer"

    def __init__(self, sys: LinearSystem, *,
                 disturbance_inputs: DisturbanceInputs = None) -> None:
        self.sys = require_system(sys, disturbance_inputs=disturbance_inputs)
        if self.sys.q == 0:
            raise DesignError(
                f"{type(self).__name__} estimates disturbances and the system has none "
                "(q = 0); for certified state bounds use SMFDO(sys, state_bounds=True)")
        self.delay = 0
        self.information = "predicted"

    @property
    def information_pattern(self) -> str:
        """The measurements the estimate of ``d_k`` uses: ``"y_0..y_(k-1)"`` or ``"y_0..y_k"``."""
        return ("y_0..y_k" if getattr(self, "information", "predicted") == "filtered"
                else "y_0..y_(k-1)")

    @property
    def gains(self) -> dict[str, Any]:
        """The design's gain matrices, keyed by the paper's symbols (for reports).

        Only gains: no covariance, transition matrix, eigenvalue or delay (those
        are attributes of their own)."""
        return {}

    def reset(self) -> None:  # pragma: no cover - overridden
        """Restart from the initial estimate."""
        raise NotSupportedError("a subclass implements this")

    def _check(self, y: ArrayLike, u: ArrayLike | None):
        """``y_k`` with the feedthrough's ``Du u_k`` taken off (the designs see
        ``Xi x_k``), and ``u_k``, validated."""
        yv = as_vector("y", y, size=self.sys.l)
        if self.sys.p:
            if u is None:
                raise ArgumentError(f"u is required: the system has {self.sys.p} input(s) "
                                     "(pass zeros explicitly if none was applied)")
            uv = as_vector("u", u, size=self.sys.p)
            if np.any(self.sys.Du != 0):
                yv = yv - self.sys.Du @ uv
        else:
            uv = np.zeros(0)
        return yv, uv

    def step(self, y: ArrayLike, u: ArrayLike | None = None) -> NDArray[np.float64]:
        """Process ``y_k`` (and ``u_k``); return the disturbance estimate ``d_hat_k``.

        Parameters
        ----------
        y : array_like, shape (l,)
            Measurement ``y_k`` (with a feedthrough, ``Du u_k`` is taken off here, as
            the set estimators do).
        u : array_like, shape (p,), optional
            Input ``u_k`` applied at step ``k`` (required when the system has inputs).
        """
        raise NotSupportedError("a subclass implements this")  # pragma: no cover

    def state_estimate(self) -> NDArray[np.float64] | None:
        """Current state estimate (``None`` if the observer has none)."""
        return None

    def run(self, Y: ArrayLike, U: ArrayLike | None = None) -> ObserverResult:
        """Run over a record from a fresh start: :meth:`reset`, then :meth:`continue_run`.

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measured outputs.
        U : array_like, shape (N, p), optional
            Applied inputs (``U[k]`` with ``Y[k]``; required when the system has inputs).

        Returns
        -------
        ObserverResult
            As :meth:`continue_run`.
        """
        self.reset()
        return self.continue_run(Y, U)

    def continue_run(self, Y: ArrayLike, U: ArrayLike | None = None) -> ObserverResult:
        """Run over a record from the current estimate (what :meth:`run` does after
        :meth:`reset`).

        With a feedthrough (``sys.Du != 0``), :meth:`step` takes ``Du u_k`` off ``y_k``
        (``U`` is then required).

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measured outputs (NaN rows are missing samples where the observer supports
            them).
        U : array_like, shape (N, p), optional
            Applied inputs (required when the system has inputs).
        """
        Ya = as_matrix("Y", Y, cols=self.sys.l)
        N = Ya.shape[0]
        Ua = None
        if self.sys.p and U is None:
            raise ArgumentError(f"U is required: the system has {self.sys.p} input(s) "
                                 f"({', '.join(self.sys.input_names)}); pass zeros explicitly "
                                 "if none was applied")
        if U is not None:
            Ua = as_matrix("U", U, cols=self.sys.p)
            if Ua.shape[0] < N:
                raise DimensionError(f"U must have at least {N} rows, got {Ua.shape[0]}")
        D = np.empty((N, self.sys.q))
        X = None
        for k in range(N):
            D[k] = self.step(Ya[k], None if Ua is None else Ua[k])
            xh = self.state_estimate()
            if xh is not None:
                if X is None:
                    X = np.full((N, self.sys.n), np.nan)
                X[k] = xh
        return ObserverResult(D, X, self.delay, self.gains, dt=self.sys.dt,
                              names=tuple(self.sys.disturbance_names), observer=self.name,
                              information=self.information_pattern)

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.sys!r})"


class StateSpaceObserver(PointObserver):
    """A linear observer ``xi+ = transition xi + output_gain y + input_matrix u``,
    ``d_hat = disturbance_map xi`` (+ optional delay line).

    Subclasses set these (and ``state_map`` for the state estimate), the
    initial state ``xi0`` and an optional per-channel output delay. The names
    are roles, not a paper's symbols (``F``, ``K``, ``M``, ``H`` mean other
    things in the papers); for the Luenberger-type designs ``transition`` is
    also the error dynamics' matrix.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The plant.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    """

    def _init_state_space(self, transition, output_gain, input_matrix, disturbance_map,
                          state_map=None, xi0=None, channel_delays=None,
                          output_map=None) -> None:
        self.transition, self.output_gain = transition, output_gain
        self.input_matrix, self.disturbance_map = input_matrix, disturbance_map
        self.state_map = state_map
        self.xi0 = (np.zeros(transition.shape[0]) if xi0 is None
                    else np.asarray(xi0, float))
        self.channel_delays = channel_delays
        self.output_map = output_map
        self.reset()

    def reset(self) -> None:
        """Restart from ``xi0``."""
        self.xi = self.xi0.copy()
        self._last = None
        if self.channel_delays is not None:
            dmax = int(max(self.channel_delays))
            self._buf: deque = deque(maxlen=dmax + 1)

    def step(self, y: ArrayLike, u: ArrayLike | None = None) -> NDArray[np.float64]:
        yv, uv = self._check(y, u)
        d = self.disturbance_map @ self.xi  # the estimate at k uses data up to k-1 (papers)
        self._xk = self.xi.copy()
        self.xi = (self.transition @ self.xi + self.output_gain @ yv
                   + (self.input_matrix @ uv if uv.size else 0.0))
        if self.information == "filtered":
            # with the disturbance model d_(k+1) = d_k the updated disturbance state is
            # the estimate of d_k from y_0..y_k (see PIO's ``information``)
            d = self.disturbance_map @ self.xi
        if self.channel_delays is not None:
            self._buf.append(d)
            out = np.full(d.shape, np.nan)
            for i, di in enumerate(self.channel_delays):
                if len(self._buf) > di:
                    out[i] = self._buf[-1 - di][i]
            d = out
        if self.output_map is not None:
            d = self.output_map @ d
        return d

    def state_estimate(self) -> NDArray[np.float64] | None:
        return None if self.state_map is None else self.state_map @ self._xk
