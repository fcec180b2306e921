"""Linear discrete-time systems with an unknown disturbance input."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import expm

from .._validation import as_matrix, as_vector, readonly
from ..exceptions import (
    ArgumentError,
    DimensionError,
    ImmutableError,
    InvalidValueError,
    MissingDependencyError,
)

__all__ = ["AugmentedSystem", "DisturbanceInputs", "LinearSystem", "require_system"]

#: Which inputs of a state-space model are disturbances: indices or input names.
DisturbanceInputs = Sequence[int | str] | int | str | None


@dataclass(frozen=True)
class AugmentedSystem:
    """The augmented system ``z = [x; d]`` of Li-Cong-Dong, eqs. (9)-(11)
    (:meth:`LinearSystem.augmented`; with ``order=2``, ``z = [x; d; Delta d]``).

    ``z[k+1] = A z[k] + Gamma_bar u[k] + E dd[k]``, ``y[k] = C z[k]``, with
    ``A = [[Phi, G], [0, I_q]]``, ``Gamma_bar = [Gamma; 0]``, ``E = [0; I_q]``,
    ``C = [Xi, 0]`` (shapes below for ``order=1``).

    Attributes
    ----------
    A : ndarray, shape (n + q, n + q)
        ``[[Phi, G], [0, I_q]]``.
    Gamma : ndarray, shape (n + q, p)
        ``[Gamma; 0]``.
    E : ndarray, shape (n + q, q)
        ``[0; I_q]``.
    C : ndarray, shape (l, n + q)
        ``[Xi, 0]``.
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


def _own_default(labels: list[str], prefix: str) -> list[str] | None:
    """python-control's generated labels (``x[0], x[1], ...``) become setobs's own
    defaults (``x0, x1, ...``: ``None``), so that a table's columns are spelled the same
    (``x0_lo``) whether the model came from python-control or from a model file; names
    a user gave are kept."""
    if all(lab == f"{prefix}[{i}]" for i, lab in enumerate(labels)):
        return None
    return labels


class LinearSystem:
    """``x[k+1] = Phi x[k] + Gamma u[k] + G d[k]``, ``y[k] = Xi x[k] + D_u u[k]``.

    .. warning::

       The positional order is ``(Phi, G, Xi, Gamma)``: the **second** matrix
       is the *disturbance* input matrix, not the control input matrix.
       ``LinearSystem(A, B, C)`` declares every column of ``B`` a disturbance.
       With control-engineering names use the keyword-only
       :meth:`from_matrices` (``A=, B=, C=, D=, G=``) or
       :meth:`from_statespace` (python-control).

    Parameters
    ----------
    Phi : array_like, shape (n, n)
        State matrix.
    G : array_like, shape (n, q)
        Disturbance input matrix; ``np.zeros((n, 0))`` for a model without
        disturbances (``q = 0``: for state estimation with
        ``SMFDO(..., state_bounds=True)``; the disturbance observers refuse it).
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
        On non-square ``Phi``, mismatched ``G``/``Xi``/``Gamma``.
    InvalidValueError
        On NaN or inf.

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
    Du: NDArray[np.float64]
    G: NDArray[np.float64]
    Gamma: NDArray[np.float64]
    Phi: NDArray[np.float64]
    Xi: NDArray[np.float64]
    disturbance_names: tuple[str, ...]
    dt: float | None
    input_names: tuple[str, ...]
    output_names: tuple[str, ...]
    state_names: tuple[str, ...]

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
        if n == 0:
            raise DimensionError("Phi is 0 x 0: a system needs at least one state")
        G_a = as_matrix("G", G, rows=n)
        Xi_a = as_matrix("Xi", Xi, cols=n)
        if Gamma is None:
            Gamma_a = np.zeros((n, 0))
        else:
            Gamma_a = as_matrix("Gamma", Gamma, rows=n)
        if Xi_a.shape[0] == 0:
            raise DimensionError("Xi must have at least one row (one output)")
        if dt is not None and not dt > 0:
            raise InvalidValueError(f"dt must be positive, got {dt}")
        l, p = Xi_a.shape[0], Gamma_a.shape[1]
        if Du is None:
            Du_a = np.zeros((l, p))
        else:
            if p == 0 and np.size(Du) == 0:
                Du_a = np.zeros((l, 0))
            else:
                if p == 0:
                    raise ArgumentError("Du is given but the system has no inputs (Gamma)")
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
        raise ImmutableError("LinearSystem is immutable")

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
        *,
        Du: ArrayLike | None = None,
        **names: Any,
    ) -> LinearSystem:
        """Zero-order-hold discretisation of ``dx/dt = H x + D u + F f``, ``y = C x + Du u``.

        ``Phi = expm(H T)``, ``Gamma = int_0^T expm(H s) ds D`` and, for a
        disturbance held constant over a sample, ``G = int_0^T expm(H s) ds F``
        (Fu-Wang, eq. (3); Chang 2006). Computed exactly with one matrix
        exponential of the block matrix ``[[H, [D F]], [0, 0]] T`` (Van Loan).

        Parameters
        ----------
        H : array_like, shape (n, n)
            Continuous state matrix.
        D : array_like, shape (n, p) or None
            Continuous input matrix (``None``: no control inputs).
        F : array_like, shape (n, q)
            Continuous disturbance matrix.
        C : array_like, shape (l, n)
            Output matrix.
        T : float
            Sampling period (positive).
        Du : array_like, shape (l, p), optional
            Feedthrough of the control inputs.
        **names
            Signal names passed to :class:`LinearSystem` (``state_names=``,
            ``disturbance_names=``, ``output_names=``, ``input_names=``).

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
            raise InvalidValueError(f"T must be positive, got {T}")
        m, q = D_a.shape[1], F_a.shape[1]
        M = np.zeros((n + m + q, n + m + q))
        M[:n, :n] = H_a
        M[:n, n:] = np.hstack([D_a, F_a])
        E = expm(M * T)
        Phi = E[:n, :n]
        Gamma = E[:n, n : n + m]
        G = E[:n, n + m :]
        return cls(Phi, G, C_a, Gamma if m else None, Du=Du if m else None, dt=float(T),
                   **names)

    @classmethod
    def from_matrices(
        cls,
        *,
        A: ArrayLike,
        C: ArrayLike,
        B: ArrayLike | None = None,
        D: ArrayLike | None = None,
        G: ArrayLike | None = None,
        disturbance_inputs: Sequence[int | str] | int | str | None = None,
        dt: float | None = None,
        continuous: bool = False,
        state_names: Sequence[str] | None = None,
        input_names: Sequence[str] | None = None,
        output_names: Sequence[str] | None = None,
        disturbance_names: Sequence[str] | None = None,
    ) -> LinearSystem:
        """From control-engineering matrices, keyword-only: ``A, B, C, D`` and disturbances.

        The disturbances are stated explicitly, in one of two ways:

        * ``G`` given: ``B`` (optional) holds the control inputs only and ``G``
          the disturbance input matrix;
        * ``G`` omitted: ``disturbance_inputs`` names the columns of ``B`` that
          are disturbances (indices, or names from ``input_names``); the other
          columns are control inputs.

        Parameters
        ----------
        A, C : array_like
            State and output matrices.
        B : array_like, optional
            Input matrix (all inputs, or the control inputs when ``G`` is given).
        D : array_like, optional
            Feedthrough with one column per column of ``B``; the columns of the
            disturbance inputs must be zero (the disturbance has no feedthrough).
        G : array_like, optional
            Disturbance input matrix.
        disturbance_inputs : sequence of int or str, optional
            Disturbance columns of ``B`` (when ``G`` is omitted); an empty
            sequence states that there are none (``q = 0``: a model for state
            estimation, ``SMFDO(..., state_bounds=True)``).
        dt : float, optional
            Sampling time. Required with ``continuous=True``.
        continuous : bool
            ``A, B, G`` describe ``dx/dt = A x + B u + G d``: discretise with a
            zero-order hold at ``dt`` (:meth:`from_continuous`).
        state_names, input_names, output_names, disturbance_names : sequence of str, optional
            Signal names; ``input_names`` lists the names of the columns of ``B``.

        Raises
        ------
        DimensionError
            On bad shapes, a disturbance given twice or not at all, a nonzero
            ``D`` column of a disturbance, or ``continuous=True`` without ``dt``.

        Examples
        --------
        >>> LinearSystem.from_matrices(A=[[1.0, 0.1], [0.0, 1.0]], B=[[0.0], [0.1]],
        ...                            C=[[1.0, 0.0]], G=[[0.0], [0.1]], dt=0.1)
        LinearSystem(n=2, q=1, l=1, p=1, dt=0.1)
        """
        A_a = as_matrix("A", A)
        n = A_a.shape[0]
        C_a = as_matrix("C", C, cols=n)
        B_a = np.zeros((n, 0)) if B is None else as_matrix("B", B, rows=n)
        m = B_a.shape[1]
        D_a = np.zeros((C_a.shape[0], m)) if D is None or (m == 0 and np.size(D) == 0) \
            else as_matrix("D", D, rows=C_a.shape[0], cols=m)
        in_names = None if input_names is None else _names("input_names", "u", input_names, m)
        if G is not None:
            if disturbance_inputs is not None:
                raise ArgumentError("give either G or disturbance_inputs, not both")
            Gd = as_matrix("G", G, rows=n)
            Bu, Du, u_names = B_a, D_a, in_names
        else:
            if disturbance_inputs is None:
                raise ArgumentError(
                    "state which inputs are disturbances: give G (disturbance input matrix) "
                    "or disturbance_inputs (columns of B)")
            idx = _input_indices("disturbance_inputs", disturbance_inputs, m, in_names)
            rest = [i for i in range(m) if i not in idx]
            if np.any(D_a[:, idx] != 0):
                raise InvalidValueError("the D columns of the disturbance inputs must be zero: "
                                     "the disturbance has no feedthrough (y = C x + D_u u)")
            Gd, Bu, Du = B_a[:, idx], B_a[:, rest], D_a[:, rest]
            if in_names is not None:
                u_names = [in_names[i] for i in rest]
                if disturbance_names is None:
                    disturbance_names = [in_names[i] for i in idx]
            else:
                u_names = None
        if not Bu.shape[1]:  # no control inputs
            Bu = Du = u_names = None
        names = {"state_names": state_names, "output_names": output_names,
                 "disturbance_names": disturbance_names, "input_names": u_names}
        if continuous:
            if dt is None:
                raise ArgumentError("a continuous-time model needs the sampling time dt "
                                     "to be discretised (zero-order hold)")
            return cls.from_continuous(A_a, Bu, Gd, C_a, dt, Du=Du, **names)
        return cls(A_a, Gd, C_a, Bu, Du=Du, dt=dt, **names)

    @classmethod
    def from_statespace(cls, ss: Any, disturbance_inputs: Sequence[int | str] | int | str,
                        *, dt: float | None = None) -> LinearSystem:
        """From a ``control.StateSpace`` (python-control), stating which inputs are disturbances.

        Parameters
        ----------
        ss : control.StateSpace
            Discrete-time model, or continuous-time model with ``dt`` given
            (then discretised with a zero-order hold, the disturbance held
            constant over a sample). Its ``D`` columns of the control inputs
            become the feedthrough ``Du``; those of the disturbances must be zero.
            Signal names (``ss.input_labels``, ...) are kept, except python-control's
            generated ones (``x[0]``, ``u[1]``, ...), which become setobs's defaults
            (``x0``, ``u1``, ...: one spelling of a table's columns, ``x0_lo``).
        disturbance_inputs : sequence of int or str
            Indices or names (``ss.input_labels``) of the inputs that are
            disturbances; the others are control inputs (empty: no disturbance,
            a model for state estimation).
        dt : float, optional
            Sampling time for a continuous-time ``ss`` (must equal ``ss.dt``
            when ``ss`` is discrete with a numeric sampling time).

        See Also
        --------
        to_statespace : the way back.
        """
        A, B, C, D = (np.asarray(M, dtype=float) for M in (ss.A, ss.B, ss.C, ss.D))
        labels = {key: list(getattr(ss, f"{key}_labels", None) or [])
                  for key in ("state", "input", "output")}
        names = {f"{key}_names": (_own_default(v, {"state": "x", "input": "u", "output": "y"}[key])
                                if len(v) == dim else None)
                 for (key, v), dim in
                 zip(labels.items(), (A.shape[0], B.shape[1], C.shape[0]), strict=True)}
        ss_dt = ss.dt
        continuous = ss_dt is not None and ss_dt is not True and float(ss_dt) == 0.0
        if continuous:
            if dt is None:
                raise ArgumentError(
                    "the StateSpace model is continuous-time: give the sampling time to "
                    "discretise it (zero-order hold), LinearSystem.from_statespace(ss, "
                    "disturbance_inputs, dt=Ts), or discretise it first (control.c2d)")
        else:
            if dt is not None and ss_dt not in (None, True) and float(ss_dt) != float(dt):
                raise InvalidValueError(f"dt = {dt} differs from the model's sampling time "
                                     f"{ss_dt}")
            if dt is None:
                dt = None if ss_dt in (None, True) else float(ss_dt)
        if names["input_names"] is None and labels["input"]:
            # python-control's generated input labels (u[0], ...) still name the inputs
            gen = labels["input"]
            items = ([disturbance_inputs] if isinstance(disturbance_inputs, str)
                     else disturbance_inputs)
            if isinstance(items, list | tuple) and any(isinstance(i, str) for i in items):
                for i in items:
                    if isinstance(i, str) and i not in gen:
                        raise InvalidValueError(f"disturbance_inputs: no input named {i!r} "
                                             f"(inputs {gen})")
                disturbance_inputs = [gen.index(i) if isinstance(i, str) and i in gen else i
                                      for i in items]
        return cls.from_matrices(A=A, B=B, C=C, D=D, disturbance_inputs=disturbance_inputs,
                                 dt=dt, continuous=continuous, **names)

    def simulate(self, D: ArrayLike, U: ArrayLike | None = None,
                 x0: ArrayLike | None = None) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Noise-free response ``x(k+1) = Phi x + Gamma u + G d``, ``y(k) = Xi x + Du u``.

        Parameters
        ----------
        D : array_like, shape (N, q)
            Disturbance sequence ``d(0), ..., d(N-1)``.
        U : array_like, shape (N, p), optional
            Input sequence (required when the system has inputs).
        x0 : array_like, shape (n,), optional
            Initial state (default zero).

        Returns
        -------
        Y : ndarray, shape (N, l)
            Measurements ``y(0), ..., y(N-1)``.
        X : ndarray, shape (N, n)
            States ``x(0), ..., x(N-1)``.

        Raises
        ------
        DimensionError
            If a sequence has the wrong shape, or ``U`` is missing for a system
            with inputs.
        """
        Da = as_matrix("D", D, cols=self.q)
        N = Da.shape[0]
        if self.p and U is None:
            raise ArgumentError(f"U is required: the system has {self.p} input(s)")
        Ua = as_matrix("U", U, rows=N, cols=self.p) if self.p else np.zeros((N, 0))
        x = np.zeros(self.n) if x0 is None else as_vector("x0", x0, size=self.n).copy()
        X = np.empty((N, self.n))
        for k in range(N):
            X[k] = x
            x = self.Phi @ x + self.Gamma @ Ua[k] + self.G @ Da[k]
        Y = X @ self.Xi.T + (Ua @ self.Du.T if self.p else 0.0)
        return Y, X

    def to_statespace(self) -> Any:
        """This system as a discrete-time ``control.StateSpace`` (python-control).

        Inputs are ``[u; d]`` (the control inputs, then the disturbances, with
        their names), ``B = [Gamma, G]``, ``D = [Du, 0]``; the sampling time is
        :attr:`dt` (``True``, unspecified, when unknown).
        """
        try:
            import control
        except ImportError as exc:  # pragma: no cover - exercised only without control
            raise MissingDependencyError("LinearSystem.to_statespace needs python-control "
                                         "(pip install control)") from exc
        B = np.hstack([self.Gamma, self.G])
        D = np.hstack([self.Du, np.zeros((self.l, self.q))])
        return control.ss(np.array(self.Phi), B, np.array(self.Xi), D,
                          self.dt if self.dt is not None else True,
                          inputs=list(self.input_names) + list(self.disturbance_names),
                          outputs=list(self.output_names), states=list(self.state_names))

    # ------------------------------------------------------------------ augmented form
    def augmented(self, order: int = 1) -> AugmentedSystem:
        """The system with the disturbance (and its differences) as states.

        ``order=1``: ``z = [x; d]`` of Li-Cong-Dong, eqs. (9)-(11) (a constant
        disturbance driven by its increment ``dd``). ``order=2``:
        ``z = [x; d; Delta d]`` of Fu-Wang's higher-order observer (eqs. (7)-(9)
        with ``d = G d*``), ``A = [[Phi, G, 0], [0, I, I], [0, 0, I]]``, driven by
        the second difference.

        Parameters
        ----------
        order : {1, 2}
            Number of disturbance blocks.
        """
        if order not in (1, 2):
            raise InvalidValueError(f"order must be 1 or 2, got {order!r}")
        n, q, p, l = self.n, self.q, self.p, self.l
        N = n + order * q
        A = np.zeros((N, N))
        A[:n, :n], A[:n, n : n + q] = self.Phi, self.G
        for i in range(order):
            blk = slice(n + i * q, n + (i + 1) * q)
            A[blk, blk] = np.eye(q)
            if i + 1 < order:
                A[blk, n + (i + 1) * q : n + (i + 2) * q] = np.eye(q)
        Gamma = np.vstack([self.Gamma, np.zeros((order * q, p))])
        E = np.vstack([np.zeros((N - q, q)), np.eye(q)])
        C = np.hstack([self.Xi, np.zeros((l, order * q))])
        return AugmentedSystem(A, Gamma, E, C)

    def transformed(self, T: ArrayLike, *, output_scale: ArrayLike | None = None,
                    disturbance_scale: ArrayLike | None = None) -> LinearSystem:
        """The same system in state coordinates ``x' = T x`` (and scaled outputs/disturbances).

        ``Phi' = T Phi T^-1``, ``G' = T G diag(s_d)^-1``, ``Xi' = diag(s_y) Xi T^-1``:
        every structural property (ranks, zeros, relative degrees, existence
        verdicts) is invariant under this map.

        Parameters
        ----------
        T : array_like, shape (n, n)
            Nonsingular state transformation ``x' = T x``.
        output_scale : array_like, shape (l,), optional
            Scale ``s_y`` of each output (default ones).
        disturbance_scale : array_like, shape (q,), optional
            Scale ``s_d`` of each disturbance (default ones).
        """
        T_a = as_matrix("T", T, rows=self.n, cols=self.n)
        Ti = np.linalg.inv(T_a)
        sd = np.ones(self.q) if disturbance_scale is None else np.asarray(disturbance_scale, float)
        sy = np.ones(self.l) if output_scale is None else np.asarray(output_scale, float)
        return LinearSystem(T_a @ self.Phi @ Ti, (T_a @ self.G) / sd, (sy[:, None] * self.Xi) @ Ti,
                            T_a @ self.Gamma if self.p else None,
                            Du=sy[:, None] * self.Du if self.p else None, dt=self.dt)


def _input_indices(name: str, indices: Any, m: int,
                   labels: Sequence[str] | None = None) -> list[int]:
    """Validated, distinct input indices in ``[0, m)`` (at least one); names are
    looked up in ``labels``."""
    if isinstance(indices, int | np.integer | str) and not isinstance(indices, bool):
        indices = [indices]
    try:
        items = list(indices)
    except TypeError:
        raise ArgumentError(f"{name} must be a sequence of input indices, "
                            f"got {indices!r}") from None
    out = []
    for i in items:
        if isinstance(i, str):
            if labels is None or i not in labels:
                known = "no input names" if labels is None else f"inputs {list(labels)}"
                raise InvalidValueError(f"{name}: no input named {i!r} ({known})")
            i = list(labels).index(i)
        if isinstance(i, bool | np.bool_) or not isinstance(i, int | np.integer | float
                                                            | np.floating):
            raise ArgumentError(f"{name} must hold integer input indices, got {i!r}")
        if float(i) != int(i):
            raise ArgumentError(f"{name} must hold integer input indices, got {i!r}")
        j = int(i)
        if not 0 <= j < m:
            raise DimensionError(f"{name}: index {j} is out of range for {m} input(s) "
                                 f"(valid: 0..{m - 1})")
        if j in out:
            raise InvalidValueError(f"{name}: index {j} is given twice")
        out.append(j)
    return out  # (empty: no disturbance, a model for state estimation)


def _is_statespace(obj: Any) -> bool:
    return all(hasattr(obj, a) for a in ("A", "B", "C", "D", "dt"))


def require_system(sys: Any, name: str = "sys", *,
                   disturbance_inputs: DisturbanceInputs = None) -> LinearSystem:
    """``sys`` as a :class:`LinearSystem`, or a ``TypeError`` saying what to do.

    A ``control.StateSpace`` is accepted when ``disturbance_inputs`` states
    which of its inputs are disturbances (:meth:`LinearSystem.from_statespace`;
    a continuous-time model must be converted there, with its sampling time);
    without that statement it is refused: guessing would misread the model.

    Parameters
    ----------
    sys : object
        A :class:`LinearSystem` or a ``control.StateSpace``.
    name : str
        Argument name for the error message.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    """
    if isinstance(sys, LinearSystem):
        if disturbance_inputs is not None:
            raise ArgumentError(f"disturbance_inputs applies to a state-space model; {name} is "
                                "already a LinearSystem (its disturbances are G's columns)")
        return sys
    if _is_statespace(sys):
        if disturbance_inputs is None:
            raise ArgumentError(
                f"{name} is a {type(sys).__name__}: say which of its inputs are disturbances "
                "with disturbance_inputs=[...] (indices or input names), or convert it with "
                "LinearSystem.from_statespace(ss, disturbance_inputs=[...])")
        return LinearSystem.from_statespace(sys, disturbance_inputs)
    if all(hasattr(sys, a) for a in ("A", "B", "C", "D")):
        raise ArgumentError(
            f"{name} must be a LinearSystem, got {type(sys).__name__}: convert a state-space "
            "model with LinearSystem.from_statespace(ss, disturbance_inputs=[...]) (it must "
            "know which inputs are disturbances)")
    raise ArgumentError(f"{name} must be a LinearSystem, got {type(sys).__name__}")
