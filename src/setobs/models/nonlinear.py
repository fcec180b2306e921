"""The nonlinear model of the set estimators, and the one reader of symbols and expressions.

``x+ = f(x, u, d)``, ``y = h(x, u, d)``: states ``x``, known inputs ``u`` and
disturbances ``d`` that change by a bounded increment (``d+ = d + dd``, the SMFDO's model,
eq. (4) of Li-Cong-Dong; the increment's set belongs to the estimator, as the noise sets
do). :class:`NonlinearModel` is what :class:`setobs.NonlinearSetObserver` takes; it
converts from and to the exosystem model of the modular-observer paper
(:class:`setobs.models.NonlinearSystem`, ``w+ = s(w)``). :func:`symbols` and
:func:`expressions` read variables and expressions (sympy objects, names, strings,
callables) for every nonlinear model of the package (needs sympy, the ``nonlinear``
extra).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .._lazy import optional_import
from ..exceptions import ArgumentError, DimensionError

__all__ = ["NonlinearModel", "expressions", "symbols"]


def sympy_module(feature: str = "nonlinear models") -> Any:
    """sympy, or a :class:`~setobs.exceptions.MissingDependencyError` naming the extra."""
    return optional_import("sympy", extra="nonlinear", feature=feature)


def symbols(given: Sequence[Any] | int | str, what: str, prefix: str | None = None
            ) -> list[Any]:
    """Variables as sympy symbols.

    Parameters
    ----------
    given : int, str, or sequence of sympy symbols or names
        An int ``m`` makes ``<prefix>0 .. <prefix>{m-1}`` (only with ``prefix``); a string
        is one name.
    what : str
        The argument's name, for the error message.
    prefix : str, optional
        The names' stem for an int.

    Returns
    -------
    list of sympy.Symbol

    Raises
    ------
    ArgumentError
        When an entry is neither a symbol nor a name, or an int is given without a prefix.
    """
    sp = sympy_module()
    if isinstance(given, int | np.integer) and not isinstance(given, bool):
        if prefix is None:
            raise ArgumentError(f"{what} must be sympy symbols or their names, got {given!r}")
        return list(sp.symbols(f"{prefix}0:{int(given)}"))
    if isinstance(given, str):
        given = [given]
    out = [sp.Symbol(g) if isinstance(g, str) else g for g in given]
    if not all(isinstance(v, sp.Symbol) for v in out):
        raise ArgumentError(f"{what} must be sympy symbols or their names, got {given!r}")
    return out


def expressions(given: Any, what: str, variables: Sequence[Any],
                call_with: tuple[list[Any], ...] | None = None, size: int | None = None
                ) -> list[Any]:
    """Expressions in ``variables`` as sympy expressions.

    Parameters
    ----------
    given : expression, str, number, sequence or array of them, or callable
        One expression (a sympy expression, a string, a number) or several; a callable
        (not a sympy object) is called with ``call_with`` and its result read the same way.
    what : str
        The argument's name, for the error messages.
    variables : sequence of sympy.Symbol
        The symbols a string's names refer to.
    call_with : tuple of lists of symbols, optional
        The arguments of a callable ``given`` (default: ``(variables,)``).
    size : int, optional
        The number of components required.

    Returns
    -------
    list of sympy expressions

    Raises
    ------
    ArgumentError
        When an entry cannot be read as an expression.
    DimensionError
        When ``size`` is given and the count differs.
    """
    sp = sympy_module()
    if callable(given) and not isinstance(given, sp.Basic):
        given = given(*(call_with if call_with is not None else (list(variables),)))
    if isinstance(given, str | sp.Basic) or np.isscalar(given) or not (
            isinstance(given, Sequence | np.ndarray) or hasattr(given, "tolist")):
        given = [given]
    if hasattr(given, "tolist") and not isinstance(given, list | tuple):
        given = list(np.ravel(np.asarray(given.tolist(), dtype=object)))
    names = {str(v): v for v in variables}
    try:
        out = [sp.sympify(e, locals=names) for e in given]
    except (sp.SympifyError, TypeError) as exc:
        raise ArgumentError(f"{what}: cannot read {given!r} as sympy expressions ({exc})") \
            from exc
    if size is not None and len(out) != size:
        raise DimensionError(f"{what} must have {size} components, got {len(out)}")
    return out


def _names(given: Sequence[str] | None, symbols_: Sequence[Any]) -> tuple[str, ...]:
    return tuple(given) if given else tuple(map(str, symbols_))


class NonlinearModel:
    """``x+ = f(x, u, d)``, ``y = h(x, u, d)``, ``d+ = d + dd``: the set estimators' model.

    Parameters
    ----------
    f : sequence of sympy expressions or strings, or callable
        The state map, one component per state; a callable is called as
        ``f(states, inputs, disturbances)`` with lists of symbols.
    h : sequence of sympy expressions or strings, or callable
        The output map, as ``f``.
    states : sequence of sympy symbols or names
        The state variables (at least one).
    inputs : sequence of sympy symbols or names, optional
        Known inputs.
    disturbances : sequence of sympy symbols or names, optional
        Unknown inputs with bounded increments (their sets are the estimator's).
    dt : float, optional
        Sampling time (for time axes).
    state_names, input_names, disturbance_names, output_names : sequence of str, optional
        Names used in reports (default: the symbols' names and ``y0 ..``).

    Raises
    ------
    ArgumentError
        When the variables are not distinct symbols or an expression uses a symbol that
        is none of them.
    DimensionError
        When there is no state or ``f`` has not one component per state.

    Examples
    --------
    >>> import setobs as so
    >>> m = so.NonlinearModel(["x + 0.1 * v", "v - 0.1 * sin(x)"], ["x"], ["x", "v"])
    >>> m.n, m.l, m.p, m.q
    (2, 1, 0, 0)
    """

    def __init__(self, f: Any, h: Any, states: Sequence[Any], inputs: Sequence[Any] = (),
                 disturbances: Sequence[Any] = (), *, dt: float | None = None,
                 state_names: Sequence[str] | None = None,
                 input_names: Sequence[str] | None = None,
                 disturbance_names: Sequence[str] | None = None,
                 output_names: Sequence[str] | None = None) -> None:
        xs = symbols(states, "states")
        us = symbols(inputs, "inputs")
        ds = symbols(disturbances, "disturbances")
        if not xs:
            raise DimensionError("there must be at least one state")
        variables = [*xs, *us, *ds]
        if len(set(variables)) != len(variables):
            raise ArgumentError("the states, inputs and disturbances must be distinct symbols")
        args = (xs, us, ds)
        fx = expressions(f, "f", variables, args)
        hx = expressions(h, "h", variables, args)
        if len(fx) != len(xs):
            raise DimensionError(f"f must have {len(xs)} components (one per state), "
                                 f"got {len(fx)}")
        allowed = set(variables)
        for what, ex in (("f", fx), ("h", hx)):
            extra = set().union(*(e.free_symbols for e in ex)) - allowed
            if extra:
                raise ArgumentError(f"{what} uses {sorted(map(str, extra))}, which are not "
                                    "among the states, inputs or disturbances")
        self.f, self.h = tuple(fx), tuple(hx)
        self.states, self.inputs, self.disturbances = tuple(xs), tuple(us), tuple(ds)
        self.dt = None if dt is None else float(dt)
        self.state_names = _names(state_names, xs)
        self.input_names = _names(input_names, us)
        self.disturbance_names = _names(disturbance_names, ds)
        self.output_names = (tuple(output_names) if output_names
                             else tuple(f"y{i}" for i in range(len(hx))))

    @property
    def n(self) -> int:
        """Number of states."""
        return len(self.states)

    @property
    def p(self) -> int:
        """Number of known inputs."""
        return len(self.inputs)

    @property
    def q(self) -> int:
        """Number of disturbances."""
        return len(self.disturbances)

    @property
    def l(self) -> int:
        """Number of outputs."""
        return len(self.h)

    @classmethod
    def from_exosystem(cls, system: Any) -> NonlinearModel:
        """The model of an exosystem system ``x+ = f(x, w)``, ``w+ = s(w)``, ``y = h(x, w)``.

        A constant exosystem (``s(w) = w``) gives ``w`` as the disturbances (their
        increments then bounded by the estimator's ``increment_set``); any other ``s``
        makes ``w`` states with their own dynamics.

        Parameters
        ----------
        system : NonlinearSystem
            The modular-observer paper's model (:class:`setobs.models.NonlinearSystem`).

        Returns
        -------
        NonlinearModel
        """
        if not all(hasattr(system, a) for a in ("f", "h", "s", "x", "w")):
            raise ArgumentError(f"from_exosystem needs a NonlinearSystem, got "
                                f"{type(system).__name__}")
        names = dict(dt=system.dt, output_names=system.output_names)
        if list(system.s) == list(system.w):
            return cls(list(system.f), list(system.h), list(system.x), (), list(system.w),
                       state_names=system.state_names,
                       disturbance_names=system.disturbance_names, **names)
        return cls([*system.f, *system.s], list(system.h), [*system.x, *system.w],
                   state_names=(*system.state_names, *system.disturbance_names), **names)

    def to_exosystem(self) -> Any:
        """The modular-observer paper's model with a constant exosystem (``w+ = w``).

        Returns
        -------
        NonlinearSystem
            ``x+ = f(x, w)``, ``w+ = w``, ``y = h(x, w)`` with ``w`` the disturbances.

        Raises
        ------
        ArgumentError
            When the model has known inputs or no disturbance (the exosystem model has
            neither inputs nor a disturbance-free form); the system itself refuses a
            model whose origin is not an equilibrium.
        """
        from .exosystem import NonlinearSystem

        if self.p or not self.q:
            raise ArgumentError(
                f"the exosystem model has no inputs and at least one disturbance; this "
                f"model has {self.p} inputs and {self.q} disturbances")
        return NonlinearSystem(list(self.f), list(self.h), list(self.states),
                               list(self.disturbances), dt=self.dt,
                               state_names=self.state_names,
                               disturbance_names=self.disturbance_names,
                               output_names=self.output_names)

    def functions(self) -> tuple[Callable[..., Any], Callable[..., Any]]:
        """``f`` and ``h`` as NumPy functions of ``(x, u, d)`` (vectors), for simulators.

        Returns
        -------
        tuple of callables
            ``f(x, u, d) -> x+`` and ``h(x, u, d) -> y``, each an ``ndarray``.
        """
        sp = sympy_module()
        variables = [*self.states, *self.inputs, *self.disturbances]
        fl = sp.lambdify(variables, list(self.f), "numpy")
        hl = sp.lambdify(variables, list(self.h), "numpy")

        def call(fn: Callable[..., Any]) -> Callable[..., Any]:
            def numeric(x: Any, u: Any = (), d: Any = ()) -> Any:
                args = [*np.ravel(x), *np.ravel(u), *np.ravel(d)]
                return np.asarray(fn(*args), dtype=np.float64)
            return numeric

        return call(fl), call(hl)

    def __repr__(self) -> str:
        return (f"NonlinearModel(n={self.n}, p={self.p}, q={self.q}, l={self.l}; "
                f"states {', '.join(self.state_names)})")
