"""Linear discrete-time systems with an unknown disturbance input."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from ._validation import as_matrix, readonly
from .exceptions import DimensionError

__all__ = ["AugmentedSystem", "LinearSystem", "require_system"]


@dataclass(frozen=True)
class AugmentedSystem:
    """The augmented system ``z = [x; d]`` of Li-Cong-Dong, eqs. (9)-(11).

    ``z[k+1] = A z[k] + Gamma_bar u[k] + E dd[k]``, ``y[k] = C z[k]``, with
    ``A = [[Phi, G], [0, I_q]]``, ``Gamma_bar = [Gamma; 0]``, ``E = [0; I_q]``,
    ``C = [Xi, 0]``.
    """

    A: NDArray[np.float64]
    Gamma: NDArray[np.float64]
    E: NDArray[np.float64]
    C: NDArray[np.float64]


def _names(param: str, prefix: str, given: Sequence[str] | None, count: int
           ) -> tuple[str, ...]:
    if given is None:
        return tuple(f"{prefix}{i}" for i in range(count))
    names = tuple(str(s) for s in given)
    if len(names) != count:
        raise DimensionError(f"{param} must have {count} entries, got {len(names)}")
    return names


class LinearSystem:
    """``x[k+1] = Phi x[k] + Gamma u[k] + G d[k]``, ``y[k] = Xi x[k] + D_u u[k]``.

    Parameters
    ----------
    Phi : array_like, shape (n, n)
        State matrix.
    G : array_like, shape (n, q)
        Disturbance input matrix.
    Xi : array_like, shape (l, n)
        Output matrix.
    Gamma : array_like, shape (n, p), optional
        Control input matrix (default: no inputs, ``p = 0``).
    Du : array_like, shape (l, p), optional
        Direct feedthrough of the known inputs to the outputs (``D`` of a
        python-control or MATLAB state-space model; default zero). The
        disturbance has no feedthrough.
    state_names, disturbance_names, output_names, input_names : sequence of str, optional
        Names used in reports.
    dt : float, optional
        Sampling time, if the model came from a continuous-time one.

    Raises
    ------
    DimensionError
        On non-square ``Phi``, mismatched ``G``/``Xi``/``Gamma``, NaN or inf.

    Notes
    -----
    The notation follows Li-Cong-Dong, eqs. (2)-(3). Arrays are copied and
    read-only; the disturbance obeys ``d[k+1] = d[k] + dd[k]`` (eq. (4)).
    """

    __slots__ = (
        "Du",
        "G",
        "Gamma",
        "Phi",
        "Xi",
        "disturbance_names",
        "dt",
        "input_names",
        "output_names",
        "state_names",
    )

    def __init__(
        self,
        Phi: ArrayLike,
        G: ArrayLike,
        Xi: ArrayLike,
        Gamma: ArrayLike | None = None,
        *,
        Du: ArrayLike | None = None,
        state_names: Sequence[str] | None = None,
        disturbance_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        input_names: Sequence[str] | None = None,
        dt: float | None = None,
    ) -> None:
        Phi_a = as_matrix("Phi", Phi)
        n = Phi_a.shape[0]
        if Phi_a.shape[1] != n:
            raise DimensionError(f"Phi must be square, got shape {Phi_a.shape}")
        G_a = as_matrix("G", G, rows=n)
        Xi_a = as_matrix("Xi", Xi, cols=n)
        if Gamma is None:
            Gamma_a = np.zeros((n, 0))
        else:
            Gamma_a = as_matrix("Gamma", Gamma, rows=n)
        if G_a.shape[1] == 0:
            raise DimensionError("G must have at least one column (one disturbance)")
        if Xi_a.shape[0] == 0:
            raise DimensionError("Xi must have at least one row (one output)")
        if dt is not None and not dt > 0:
            raise DimensionError(f"dt must be positive, got {dt}")
        l, p = Xi_a.shape[0], Gamma_a.shape[1]
        if Du is None:
            Du_a = np.zeros((l, p))
        else:
            if p == 0 and np.size(Du) == 0:
                Du_a = np.zeros((l, 0))
            else:
                if p == 0:
                    raise DimensionError("Du is given but the system has no inputs (Gamma)")
                Du_a = as_matrix("Du", Du, rows=l, cols=p)
        set_ = object.__setattr__
        set_(self, "Du", readonly(Du_a))
        set_(self, "Phi", readonly(Phi_a))
        set_(self, "G", readonly(G_a))
        set_(self, "Xi", readonly(Xi_a))
        set_(self, "Gamma", readonly(Gamma_a))
        set_(self, "state_names", _names("state_names", "x", state_names, n))
        set_(self, "disturbance_names",
             _names("disturbance_names", "d", disturbance_names, G_a.shape[1]))
        set_(self, "output_names", _names("output_names", "y", output_names, Xi_a.shape[0]))
        set_(self, "input_names", _names("input_names", "u", input_names, Gamma_a.shape[1]))
        set_(self, "dt", None if dt is None else float(dt))

    def __setattr__(self, name: str, value: object) -> None:
        raise AttributeError("LinearSystem is immutable")

    def __getstate__(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in self.__slots__}

    def __setstate__(self, state: dict[str, Any]) -> None:
        # pickling and deepcopy: rebuild the read-only arrays
        if "Du" not in state:  # pickled before Du existed
            state = {**state, "Du": np.zeros((state["Xi"].shape[0], state["Gamma"].shape[1]))}
        for name, val in state.items():
            if isinstance(val, np.ndarray):
                val = readonly(np.array(val))
            object.__setattr__(self, name, val)

    # ------------------------------------------------------------------ sizes
    @property
    def n(self) -> int:
        """Number of states."""
        return int(self.Phi.shape[0])

    @property
    def q(self) -> int:
        """Number of disturbances."""
        return int(self.G.shape[1])

    @property
    def l(self) -> int:
        """Number of outputs."""
        return int(self.Xi.shape[0])

    @property
    def p(self) -> int:
        """Number of control inputs."""
        return int(self.Gamma.shape[1])

    def __repr__(self) -> str:
        dt = f", dt={self.dt:g}" if self.dt is not None else ""
        return f"LinearSystem(n={self.n}, q={self.q}, l={self.l}, p={self.p}{dt})"

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_continuous(
        cls,
        H: ArrayLike,
        D: ArrayLike | None,
        F: ArrayLike,
        C: ArrayLike,
        T: float,
        **names: Any,
    ) -> LinearSystem:
        """Zero-order-hold discretisation of ``dx/dt = H x + D u + F f``, ``y = C x``.

        ``Phi = expm(H T)``, ``Gamma = int_0^T expm(H s) ds D`` and, for a
        disturbance held constant over a sample, ``G = int_0^T expm(H s) ds F``
        (Fu-Wang, eq. (3); Chang 2006). Computed exactly with one matrix
        exponential of the block matrix ``[[H, [D F]], [0, 0]] T`` (Van Loan).

        Raises
        ------
        DimensionError
            On bad shapes or a non-positive ``T``.
        """
        H_a = as_matrix("H", H)
        n = H_a.shape[0]
        if H_a.shape[1] != n:
            raise DimensionError(f"H must be square, got shape {H_a.shape}")
        D_a = np.zeros((n, 0)) if D is None else as_matrix("D", D, rows=n)
        F_a = as_matrix("F", F, rows=n)
        C_a = as_matrix("C", C, cols=n)
        if not T > 0:
            raise DimensionError(f"T must be positive, got {T}")
        m, q = D_a.shape[1], F_a.shape[1]
        M = np.zeros((n + m + q, n + m + q))
        M[:n, :n] = H_a
        M[:n, n:] = np.hstack([D_a, F_a])
        E = expm(M * T)
        Phi = E[:n, :n]
        Gamma = E[:n, n : n + m]
        G = E[:n, n + m :]
        return cls(Phi, G, C_a, Gamma if m else None, dt=float(T), **names)

    @classmethod
    def from_statespace(cls, ss: Any, disturbance_inputs: Sequence[int]) -> LinearSystem:
        """From a discrete-time ``control.StateSpace`` (python-control, optional).

        Parameters
        ----------
        ss : control.StateSpace
            Discrete-time model. Its ``D`` columns of the control inputs become
            the feedthrough ``Du``; those of the disturbances must be zero.
        disturbance_inputs : sequence of int
            Indices of the inputs that are disturbances; the others are controls.
        """
        try:
            import control  # noqa: F401  (lazy: optional dependency)
        except ImportError as exc:  # pragma: no cover - exercised only without control
            raise ImportError("LinearSystem.from_statespace needs python-control "
                              "(pip install control)") from exc
        A, B, C, D = (np.asarray(M, dtype=float) for M in (ss.A, ss.B, ss.C, ss.D))
        if not ss.dt:
            raise DimensionError("the StateSpace model must be discrete-time (dt > 0 or True)")
        idx = _input_indices("disturbance_inputs", disturbance_inputs, B.shape[1])
        rest = [i for i in range(B.shape[1]) if i not in idx]
        if np.any(D[:, idx] != 0):
            raise DimensionError("the D columns of the disturbance inputs must be zero: "
                                 "the disturbance has no feedthrough (y = Xi x + D_u u)")
        dt = None if ss.dt is True else float(ss.dt)
        return cls(A, B[:, idx], C, B[:, rest] if rest else None,
                   Du=D[:, rest] if rest else None, dt=dt)

    # ------------------------------------------------------------------ augmented form
    def augmented(self) -> AugmentedSystem:
        """The augmented system ``z = [x; d]`` of Li-Cong-Dong, eqs. (9)-(11)."""
        n, q, p, l = self.n, self.q, self.p, self.l
        A = np.block([[self.Phi, self.G], [np.zeros((q, n)), np.eye(q)]])
        Gamma = np.vstack([self.Gamma, np.zeros((q, p))])
        E = np.vstack([np.zeros((n, q)), np.eye(q)])
        C = np.hstack([self.Xi, np.zeros((l, q))])
        return AugmentedSystem(A, Gamma, E, C)

    def transformed(self, T: ArrayLike, *, output_scale: ArrayLike | None = None,
                    disturbance_scale: ArrayLike | None = None) -> LinearSystem:
        """The same system in state coordinates ``x' = T x`` (and scaled outputs/disturbances).

        ``Phi' = T Phi T^-1``, ``G' = T G diag(s_d)^-1``, ``Xi' = diag(s_y) Xi T^-1``:
        every structural property (ranks, zeros, relative degrees, existence
        verdicts) is invariant under this map.
        """
        T_a = as_matrix("T", T, rows=self.n, cols=self.n)
        Ti = np.linalg.inv(T_a)
        sd = np.ones(self.q) if disturbance_scale is None else np.asarray(disturbance_scale, float)
        sy = np.ones(self.l) if output_scale is None else np.asarray(output_scale, float)
        return LinearSystem(T_a @ self.Phi @ Ti, (T_a @ self.G) / sd, (sy[:, None] * self.Xi) @ Ti,
                            T_a @ self.Gamma if self.p else None,
                            Du=sy[:, None] * self.Du if self.p else None, dt=self.dt)


def _input_indices(name: str, indices: Any, m: int) -> list[int]:
    """Validated, distinct input indices in ``[0, m)`` (at least one)."""
    if isinstance(indices, int | np.integer) and not isinstance(indices, bool):
        indices = [indices]
    try:
        items = list(indices)
    except TypeError:
        raise TypeError(f"{name} must be a sequence of input indices, got {indices!r}") from None
    out = []
    for i in items:
        if isinstance(i, bool | np.bool_) or not isinstance(i, int | np.integer | float
                                                            | np.floating):
            raise TypeError(f"{name} must hold integer input indices, got {i!r}")
        if float(i) != int(i):
            raise DimensionError(f"{name} must hold integer input indices, got {i!r}")
        j = int(i)
        if not 0 <= j < m:
            raise DimensionError(f"{name}: index {j} is out of range for {m} input(s) "
                                 f"(valid: 0..{m - 1})")
        if j in out:
            raise DimensionError(f"{name}: index {j} is given twice")
        out.append(j)
    if not out:
        raise DimensionError(f"{name} must name at least one input (the disturbances)")
    return out


def require_system(sys: Any, name: str = "sys") -> LinearSystem:
    """``sys`` if it is a :class:`LinearSystem`; otherwise a ``TypeError`` saying what to do.

    A ``control.StateSpace`` (or anything with ``A, B, C, D``) is refused with
    a pointer to :meth:`LinearSystem.from_statespace`, which needs to know
    which inputs are disturbances.
    """
    if isinstance(sys, LinearSystem):
        return sys
    if all(hasattr(sys, a) for a in ("A", "B", "C", "D")):
        raise TypeError(
            f"{name} must be a LinearSystem, got {type(sys).__name__}: convert a state-space "
            "model with LinearSystem.from_statespace(ss, disturbance_inputs=[...]) (it must "
            "know which inputs are disturbances)")
    raise TypeError(f"{name} must be a LinearSystem, got {type(sys).__name__}")
