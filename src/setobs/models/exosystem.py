"""Nonlinear discrete-time systems with an exosystem disturbance (needs sympy).

``x(k+1) = f(x(k), w(k))``, ``w(k+1) = s(w(k))``, ``y(k) = h(x(k), w(k))``: the
system (3) of the modular-observer paper, for its nonlinear modular observer
(:class:`setobs.observers.NonlinearModularObserver`, designed by
:func:`setobs.analysis.modular.design_modular`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import as_vector
from ..exceptions import DimensionError, InvalidValueError
from ..tolerances import EQUILIBRIUM_ATOL
from .nonlinear import expressions, symbols, sympy_module

__all__ = ["NonlinearSystem"]



class NonlinearSystem:
    """``x+ = f(x, w)``, ``w+ = s(w)``, ``y = h(x, w)`` (modular-observer paper, eq. (3)).

    The origin must be an equilibrium (``f(0, 0) = 0``, ``s(0) = 0``,
    ``h(0, 0) = 0``): the power-series design of Section VII expands there.
    Shift the coordinates of a model whose operating point is elsewhere.

    Parameters
    ----------
    f : sequence of sympy expressions, or callable
        The state map; a callable is called as ``f(x, w)`` with lists of sympy
        symbols and returns the components (or one expression for one state).
    h : sequence of sympy expressions, or callable
        The output map, as ``f``.
    x : int or sequence of sympy symbols or names
        The state variables (an int ``m`` makes ``x0 .. x{m-1}``).
    w : int or sequence of sympy symbols or names
        The disturbance variables.
    s : sequence of sympy expressions, or callable, optional
        The exosystem ``w+ = s(w)`` (a callable is called as ``s(w)``); default
        ``w+ = w``, a constant (step) disturbance.
    dt : float, optional
        Sampling time (for time axes).
    state_names, disturbance_names, output_names : sequence of str, optional
        Names used in reports (default: the symbols' names and ``y0 ..``).

    Raises
    ------
    ValueError
        When the origin is not an equilibrium.

    Examples
    --------
    The paper's example (Section VI, eq. (40)):

    >>> import setobs.examples as ex
    >>> sys = ex.modular_example()
    >>> sys.n, sys.q, sys.l
    (1, 1, 1)
    """

    p = 0  #: known inputs: none

    def __init__(self, f: Any, h: Any, x: Sequence[Any] | int, w: Sequence[Any] | int,
                 s: Any = None, *, dt: float | None = None,
                 state_names: Sequence[str] | None = None,
                 disturbance_names: Sequence[str] | None = None,
                 output_names: Sequence[str] | None = None) -> None:
        self.x = symbols(x, "x", prefix="x")
        self.w = symbols(w, "w", prefix="w")
        if not self.x or not self.w:
            raise DimensionError("need at least one state and one disturbance")
        xw = [*self.x, *self.w]
        self.f = expressions(f, "f", xw, (self.x, self.w), len(self.x))
        self.h = expressions(h, "h", xw, (self.x, self.w))
        self.s = (list(self.w) if s is None
                  else expressions(s, "s", self.w, (self.w,), len(self.w)))
        free = set().union(*(e.free_symbols for e in self.f + self.h + self.s))
        extra = free - set(self.x) - set(self.w)
        if extra:
            raise InvalidValueError(
                f"the model has symbols that are neither states nor disturbances: "
                f"{sorted(map(str, extra))} (substitute their values first)")
        if any(e.free_symbols - set(self.w) for e in self.s):
            raise InvalidValueError("s(w) must depend on w only")
        self.dt = None if dt is None else float(dt)
        self.state_names = tuple(state_names) if state_names else tuple(map(str, self.x))
        self.disturbance_names = (tuple(disturbance_names) if disturbance_names
                                  else tuple(map(str, self.w)))
        self.output_names = (tuple(output_names) if output_names
                             else tuple(f"y{i}" for i in range(len(self.h))))
        self._compiled: dict[str, Callable[..., Any]] = {}
        z = np.zeros(self.n), np.zeros(self.q)
        for name, val in (("f(0, 0)", self.f_num(*z)), ("s(0)", self.s_num(z[1])),
                          ("h(0, 0)", self.h_num(*z))):
            if not np.all(np.isfinite(val)) or np.abs(val).max() > EQUILIBRIUM_ATOL:
                raise InvalidValueError(
                    f"{name} = {val}: the origin must be an equilibrium (shift the "
                    "coordinates to the operating point)")

    # dimensions, as LinearSystem names them --------------------------------------
    @property
    def n(self) -> int:
        """Number of states ``m``."""
        return len(self.x)

    @property
    def q(self) -> int:
        """Number of disturbances ``mu``."""
        return len(self.w)

    @property
    def l(self) -> int:
        """Number of outputs ``p``."""
        return len(self.h)

    @property
    def Du(self) -> NDArray[np.float64]:
        """No known inputs: an ``(l, 0)`` feedthrough."""
        return np.zeros((self.l, 0))

    # numeric functions -------------------------------------------------------------
    def _fn(self, name: str) -> Callable[..., Any]:
        fn = self._compiled.get(name)
        if fn is None:
            sp = sympy_module()
            if name == "s":
                fn = sp.lambdify([self.w], self.s, "numpy")
            else:
                fn = sp.lambdify([self.x, self.w], getattr(self, name), "numpy")
            self._compiled[name] = fn
        return fn

    def f_num(self, x: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        """``f(x, w)`` at one point (compiled by ``sympy.lambdify``).

        Parameters
        ----------
        x : array_like, shape (n,)
        w : array_like, shape (q,)
        """
        return np.asarray(self._fn("f")(np.asarray(x, float), np.asarray(w, float)), float)

    def h_num(self, x: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        """``h(x, w)`` at one point.

        Parameters
        ----------
        x : array_like, shape (n,)
        w : array_like, shape (q,)
        """
        return np.asarray(self._fn("h")(np.asarray(x, float), np.asarray(w, float)), float)

    def s_num(self, w: ArrayLike) -> NDArray[np.float64]:
        """``s(w)`` at one point.

        Parameters
        ----------
        w : array_like, shape (q,)
        """
        return np.asarray(self._fn("s")(np.asarray(w, float)), float)

    def linearization(self) -> dict[str, NDArray[np.float64]]:
        """Jacobians at the origin: ``F = f_x``, ``P = f_w``, ``S = s_w``, ``H = h_x``,
        ``Q = h_w`` (Proposition 3's notation).

        Returns
        -------
        dict
            The five matrices.
        """
        sp = sympy_module()
        at0 = {v: 0 for v in self.x + self.w}

        def jac(exprs, vars_):
            return np.array(sp.Matrix(exprs).jacobian(vars_).subs(at0), dtype=float)

        return {"F": jac(self.f, self.x), "P": jac(self.f, self.w), "S": jac(self.s, self.w),
                "H": jac(self.h, self.x), "Q": jac(self.h, self.w)}

    def simulate(self, x0: ArrayLike, w0: ArrayLike, N: int, *,
                 W: ArrayLike | None = None) -> tuple[NDArray[np.float64], ...]:
        """Simulate ``N`` steps.

        Parameters
        ----------
        x0 : array_like, shape (n,)
        w0 : array_like, shape (q,)
            Initial disturbance (ignored when ``W`` is given).
        N : int
        W : array_like, shape (N, q), optional
            A disturbance record to use instead of the exosystem.

        Returns
        -------
        X, W, Y : ndarray
            States (N, n), disturbances (N, q) and outputs (N, l).
        """
        X = np.empty((N, self.n))
        Wout = np.empty((N, self.q))
        Y = np.empty((N, self.l))
        x = as_vector("x0", x0, size=self.n)
        w = as_vector("w0", w0, size=self.q)
        Wa = None if W is None else np.asarray(W, float)
        if Wa is not None and Wa.shape != (N, self.q):
            raise DimensionError(f"W must have shape ({N}, {self.q})")
        for k in range(N):
            if Wa is not None:
                w = Wa[k]
            X[k], Wout[k], Y[k] = x, w, self.h_num(x, w)
            x = self.f_num(x, w)
            w = self.s_num(w)
        return X, Wout, Y

    # pickling: the compiled functions are rebuilt on demand --------------------------
    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_compiled"] = {}
        return state

    def __repr__(self) -> str:
        return (f"NonlinearSystem(f={self.f}, s={self.s}, h={self.h}, x={self.x}, "
                f"w={self.w})")
