"""Model-based extended state observers (Chen-Gao-Lin): MB-ESO (16), variant MB-ESO (20)-(22),
the error bound of Theorem 4 and the per-channel EHGSO baseline of their Example 4."""

from __future__ import annotations

from collections.abc import Sequence
from math import comb, factorial

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import block_diag, lstsq

from .._format import format_complex_list
from ..analysis import invariant_zeros, relative_degrees
from ..exceptions import InvalidValueError
from ..models.linear import DisturbanceInputs, LinearSystem
from ._gains import place_gain
from .base import DesignError, StateSpaceObserver

__all__ = ["EHGSO", "MBESO", "VariantMBESO", "decoupled_gain", "mbeso_error_bound",
           "mbeso_impulse_response", "mbeso_l1_norm"]


def mbeso_impulse_response(k: int, r: int, omega: float) -> float:
    """``h_i(k)`` of Chen-Gao-Lin eq. (54): response of ``f_i - f_hat_i`` to unit ``Delta f_i``.

    Parameters
    ----------
    k : int
        Step after the unit increment.
    r : int
        Relative degree ``r_i`` of the channel.
    omega : float
        Observer eigenvalue ``omega_i`` of the channel (in ``[0, 1)``).
    """
    if k < 1:
        return 0.0
    if k <= r + 1:
        return 1.0
    total = 0.0
    for i in range(1, r + 2):
        prod = 1.0
        for j in range(-i + 1, 0):
            prod *= k + j
        total += prod / factorial(i - 1) * (1 - omega) ** (i - 1) * omega ** (k - i)
    return total


def mbeso_l1_norm(r: int, omega: float) -> float:
    """``||h_i||_L1 = sum_k h_i(k) = (r_i + 1) / (1 - omega_i)``: the L1 norm of eq. (54).

    Chen-Gao-Lin, Theorem 4(iv), prove this sum finite by a ratio test, eqs.
    (65)-(68). Its value follows from eq. (62) at ``z = 1`` (``h_i >= 0``, so the
    L1 norm is the DC gain): ``sum_iota (1 - omega)^(iota-1) / (1 - omega)^iota``
    over ``iota = 1..r+1``.

    Parameters
    ----------
    r : int
        Relative degree ``r_i`` of the channel.
    omega : float
        Observer eigenvalue ``omega_i`` of the channel (in ``[0, 1)``).

    Examples
    --------
    >>> mbeso_l1_norm(2, 0.0), mbeso_l1_norm(2, 0.5)
    (3.0, 6.0)
    """
    if not 0.0 <= omega < 1.0:
        raise InvalidValueError(f"omega must lie in [0, 1), got {omega}")
    return (int(r) + 1) / (1.0 - float(omega))


def mbeso_error_bound(degrees: Sequence[int], omega: float | Sequence[float],
                      increment_bound: float | Sequence[float]) -> NDArray[np.float64]:
    """Bound on ``|f_i(k) - f_hat_i(k)|`` of the MB-ESO (16) for ``|Delta f_i| <= delta_i``.

    By eq. (53) the error is ``h_i * Delta f_i``, so (Theorem 4(iv), Remark 5)
    ``|f_i - f_hat_i| <= ||h_i||_L1 delta_i = (r_i + 1) delta_i / (1 - omega_i)``
    (:func:`mbeso_l1_norm`). The bound is attained: a ramp ``Delta f_i = delta_i``
    drives the error to it. It holds once the initial error has been absorbed (the
    initial error counts as the increment ``Delta f(-1) = f(0) - f_hat(0)``).

    Parameters
    ----------
    degrees : sequence of int
        Relative degrees ``r_i``.
    omega : float or sequence of float
        Observer eigenvalues ``omega_i``.
    increment_bound : float or sequence of float
        ``delta_i >= sup_k |Delta f_i(k)|``.

    Returns
    -------
    ndarray, shape (p,)
        The per-channel bounds.
    """
    p = len(degrees)
    om = _omegas(omega, p)
    delta = np.broadcast_to(np.asarray(increment_bound, float), (p,))
    if np.any(delta < 0) or not np.all(np.isfinite(delta)):
        raise InvalidValueError(f"increment_bound must be finite and nonnegative, got {delta}")
    return np.array([mbeso_l1_norm(r, w) * d for r, w, d in zip(degrees, om, delta,
                                                                   strict=True)])


def decoupled_gain(A: NDArray[np.float64], E: NDArray[np.float64], C: NDArray[np.float64],
                   degrees: Sequence[int], V0: NDArray[np.float64],
                   omegas: Sequence[float]) -> tuple[NDArray[np.float64], float]:
    """Gain ``L`` that decouples the MB-ESO error into ``p`` blocks with eigenvalues ``omega_i``.

    Chen-Gao-Lin construct ``L`` through the canonical forms (33)-(40) and (75):
    after ``e3 = W e`` the closed loop is the block-diagonal observer companion
    ``J`` of eq. (56) (block ``i`` of size ``r_i + 1``, characteristic polynomial
    ``(z - omega_i)^(r_i+1)``), output ``i`` reads the first coordinate of block
    ``i`` up to an output recombination ``R`` (eq. (38)), and ``Delta f`` enters
    the last coordinate of block ``i`` through row ``i`` of ``V0`` (eq. (44)).
    These conditions are *linear* in ``(W, K = W L, R)``:

    ``W A - J W - K C = 0``, ``Cbar_J W = R C``, ``W E = E_J``,

    so ``W``, ``K``, ``R`` are obtained from one least-squares solve (its
    residual is returned; it is zero when the construction exists) and
    ``L = W^-1 K``. The tests check the resulting error responses against
    eq. (54) and the delays of Theorems 1-3.

    Parameters
    ----------
    A, E, C : ndarray
        The extended system (Chen-Gao-Lin eq. (6)): ``A`` (n + p, n + p), ``E`` (n + p, p),
        ``C`` (p, n + p).
    degrees : sequence of int
        Relative degrees ``r_i`` (Lemma 2).
    V0 : ndarray, shape (p, p)
        Nonsingular ``V0`` of eq. (9).
    omegas : sequence of float
        Eigenvalue ``omega_i`` of block ``i``.

    Returns
    -------
    L : ndarray, shape (n + p, p)
    residual : float
        Relative residual of the linear conditions.
    """
    N, p = A.shape[0], C.shape[0]
    blocks = []
    CJ = np.zeros((p, N))
    EJ = np.zeros((N, p))
    off = 0
    for i in range(p):
        m = int(degrees[i]) + 1
        w = float(omegas[i])
        Jb = np.zeros((m, m))
        Jb[:-1, 1:] = np.eye(m - 1)
        Jb[:, 0] = [(-1) ** (k + 2) * comb(m, k + 1) * w ** (k + 1) for k in range(m)]  # eq. (56)
        blocks.append(Jb)
        CJ[i, off] = 1.0
        EJ[off + m - 1, :] = V0[i]
        off += m
    if off != N:
        raise DesignError(f"sum(r_i + 1) = {off} differs from n + p = {N}: the augmented system "
                          "does not have the structure of Lemma 3", "Assumption 1")
    J = block_diag(*blocks)
    eye = np.eye(N)
    M = np.vstack([
        np.hstack([np.kron(eye, A.T) - np.kron(J, eye), -np.kron(eye, C.T),
                   np.zeros((N * N, p * p))]),
        np.hstack([np.kron(CJ, eye), np.zeros((p * N, N * p)), -np.kron(np.eye(p), C.T)]),
        np.hstack([np.kron(eye, E.T), np.zeros((N * p, N * p + p * p))]),
    ])
    rhs = np.concatenate([np.zeros(N * N + p * N), EJ.reshape(-1)])
    sol = lstsq(M, rhs)[0]
    residual = float(np.linalg.norm(M @ sol - rhs) / max(np.linalg.norm(rhs), 1e-300))
    W = sol[: N * N].reshape(N, N)
    K = sol[N * N : N * N + N * p].reshape(N, p)
    return np.linalg.solve(W, K), residual


def _omegas(omega: float | Sequence[float], p: int) -> list[float]:
    om = [float(omega)] * p if np.ndim(omega) == 0 else [float(w) for w in omega]  # type: ignore[arg-type]
    if len(om) != p:
        raise DesignError(f"omega must be a scalar or have {p} entries, got {len(om)}")
    if any(not (0.0 <= w < 1.0) for w in om):
        raise DesignError(f"omega must lie in [0, 1) (discrete-time eigenvalues), got {om}")
    return om


def _bandwidth_omega(sys: LinearSystem, omega, bandwidth):
    """``omega = exp(-bandwidth dt)``: a continuous-time bandwidth (rad/s) as the discrete
    eigenvalue (the conversion of Chen-Gao-Lin's Fig. 6)."""
    if bandwidth is None:
        return omega
    if np.any(np.asarray(omega, float) != 0.0):
        raise DesignError("give omega (discrete eigenvalues) or bandwidth (rad/s), not both",
                          "omega")
    if sys.dt is None:
        raise DesignError("bandwidth (rad/s) needs the system's sampling time dt", "dt")
    bw = np.asarray(bandwidth, float)
    if np.any(bw <= 0) or not np.all(np.isfinite(bw)):
        raise DesignError(f"bandwidth must be positive and finite (rad/s), got {bandwidth}",
                          "omega")
    om = np.exp(-bw * sys.dt)
    return float(om) if om.ndim == 0 else [float(w) for w in om]


def _check_assumption1(sys: LinearSystem, name: str):
    if sys.q != sys.l:
        raise DesignError(f"{name} needs as many disturbances as outputs (q = {sys.q}, "
                          f"l = {sys.l})", "q = l")
    z = invariant_zeros(sys)
    if not z.full_normal_rank or z.zeros.size:
        zs = format_complex_list(z.zeros)
        raise DesignError(f"{name} requires Assumption 1 (no invariant zeros); zeros: "
                          f"{zs or 'pencil not of full normal rank'}", "Assumption 1")
    return relative_degrees(sys)


class _ExtendedStateObserver(StateSpaceObserver):
    """A Luenberger observer of the extended state ``X = [x; f]`` (MB-ESO, EHGSO)."""

    def _init_extended(self, A, L, C, B, x0, d0, channel_delays=None,
                       output_map=None) -> None:
        """Realise ``X_hat+ = (A - L C) X_hat + L y + B u``, ``d_hat`` the ``f`` part of
        ``X_hat``, from ``[x0; d0]``."""
        n, q = self.sys.n, self.sys.q
        xi0 = np.concatenate([np.zeros(n) if x0 is None else np.asarray(x0, float),
                              np.zeros(q) if d0 is None else np.asarray(d0, float)])
        self._init_state_space(A - L @ C, L, B, np.hstack([np.zeros((q, n)), np.eye(q)]),
                               np.hstack([np.eye(n), np.zeros((n, q))]), xi0, channel_delays,
                               output_map)


class MBESO(_ExtendedStateObserver):
    """MB-ESO of Chen-Gao-Lin, eq. (16): Luenberger observer of the augmented system (14).

    ``X_hat(k+1) = A X_hat(k) + B u(k) + L (y(k) - C X_hat(k))`` with the
    decoupling gain of :func:`decoupled_gain` (eigenvalues of subsystem ``i`` at
    ``omega_i``). ``d_hat(k)`` is the ``f`` part of ``X_hat(k)``.

    Parameters
    ----------
    sys : LinearSystem
    omega : float or sequence of float
        Observer eigenvalues per subsystem, in ``[0, 1)`` (0: deadbeat).
    x0, d0 : array_like, optional
        Initial state and disturbance estimates (default zero).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    bandwidth : float or sequence of float, optional
        Observer bandwidth ``omega_o`` in rad/s instead of ``omega``: the eigenvalue
        is ``exp(-bandwidth dt)`` (needs ``sys.dt``; Chen-Gao-Lin, Fig. 6).

    Raises
    ------
    DesignError
        If ``q != l``, Assumption 1 fails, or ``V0`` is not diagonal (Theorem 2:
        use :class:`VariantMBESO`).

    Notes
    -----
    With ``omega = 0``: ``f_hat_i(k) = f_i(k - r_i - 1)`` (Theorem 2); in general
    ``f - f_hat = diag(h_i) * Delta f`` with ``h_i`` of eq. (54) (Theorem 4).
    """

    name = "MB-ESO"

    def __init__(self, sys: LinearSystem, omega: float | Sequence[float] = 0.0,
                 x0: ArrayLike | None = None, d0: ArrayLike | None = None,
                 *, disturbance_inputs: DisturbanceInputs = None,
                 bandwidth: float | Sequence[float] | None = None) -> None:
        super().__init__(sys, disturbance_inputs=disturbance_inputs)
        sys = self.sys
        omega = _bandwidth_omega(sys, omega, bandwidth)
        rd = _check_assumption1(sys, "MB-ESO")
        if not rd.diagonal:
            raise DesignError("MB-ESO (16) needs a diagonal V0 (Theorem 2); V0 = "
                              f"{np.round(rd.V0, 6).tolist()}: use VariantMBESO", "V0 diagonal")
        self._build(sys.G, rd.degrees, rd.V0, _omegas(omega, sys.q), x0, d0)

    def _build(self, Gdist, degrees, V0, omegas, x0, d0, channel_delays=None, output_map=None):
        sys = self.sys
        n, q = sys.n, sys.q
        A = np.block([[sys.Phi, Gdist], [np.zeros((q, n)), np.eye(q)]])
        E = np.vstack([np.zeros((n, q)), np.eye(q)])
        C = np.hstack([sys.Xi, np.zeros((q, q))])
        B = np.vstack([sys.Gamma, np.zeros((q, sys.p))])
        L, res = decoupled_gain(A, E, C, degrees, V0, omegas)
        if res > 1e-8:
            raise DesignError(f"decoupling gain construction failed (residual {res:.2e})",
                              "decoupling")
        self.L, self.omegas, self.degrees, self.V0 = L, omegas, tuple(degrees), V0
        self.residual = res
        self._init_extended(A, L, C, B, x0, d0, channel_delays, output_map)

    @property
    def gains(self) -> dict:
        return {"L": self.L}


class VariantMBESO(MBESO):
    """Variant MB-ESO, Chen-Gao-Lin eqs. (18)-(22), for a non-diagonal ``V0``.

    The disturbance is rescaled, ``f_new = V0 f`` (so ``V0_new = I``), the MB-ESO
    (20) estimates ``f_new``, channel ``i`` is delayed by ``r_max - r_i`` (21) so
    that all channels share the delay ``r_max + 1``, and ``f_hat = V0^-1 f_new_hat``
    (22). With ``omega = 0``: ``f_hat(k) = f(k - r_max - 1)`` (Theorem 3).
    ``d_hat`` is NaN until every channel's delay line is filled.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system.
    omega : float or sequence of float
        Observer eigenvalues per subsystem, in ``[0, 1)`` (0: deadbeat).
    x0, d0 : array_like, optional
        Initial state and disturbance estimates (default zero).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    bandwidth : float or sequence of float, optional
        Observer bandwidth in rad/s instead of ``omega`` (see :class:`MBESO`).

    Notes
    -----
    Theorem 5 / Remark 4: the error of the scaled disturbance ``f_new = V0 f``
    is ``h_i * Delta f_new_i`` (eq. (73)), monotone in ``omega`` and ``k``;
    the error of ``f`` itself is ``V0^-1`` times it (eq. (69)) and need not be.
    :meth:`scaled_estimate` returns ``V0 f_hat``.
    """

    name = "variant MB-ESO"

    def __init__(self, sys: LinearSystem, omega: float | Sequence[float] = 0.0,
                 x0: ArrayLike | None = None, d0: ArrayLike | None = None,
                 *, disturbance_inputs: DisturbanceInputs = None,
                 bandwidth: float | Sequence[float] | None = None) -> None:
        StateSpaceObserver.__init__(self, sys, disturbance_inputs=disturbance_inputs)
        sys = self.sys
        omega = _bandwidth_omega(sys, omega, bandwidth)
        rd = _check_assumption1(sys, "variant MB-ESO")
        V0inv = np.linalg.inv(rd.V0)
        r = rd.degrees
        rmax = max(r)  # type: ignore[type-var]
        delays = [rmax - ri for ri in r]  # type: ignore[operator]
        d0n = None if d0 is None else rd.V0 @ np.asarray(d0, float)
        self._build(sys.G @ V0inv, r, np.eye(sys.q), _omegas(omega, sys.q), x0, d0n,
                    channel_delays=delays, output_map=V0inv)
        self.V0 = rd.V0
        self.channel_delays = delays
        self.delay = int(rmax) + 1 if all(w == 0 for w in self.omegas) else 0

    def scaled_estimate(self, estimate: ArrayLike) -> NDArray[np.float64]:
        """``V0 f_hat``: the estimate of the scaled disturbance ``f_new = V0 f`` (eq. (18)).

        Parameters
        ----------
        estimate : array_like, shape (N, q)
            ``run(Y).estimate`` of this observer.

        Returns
        -------
        ndarray, shape (N, q)
            The delayed estimate of ``f_new`` of eq. (21), row by row.
        """
        return np.asarray(estimate, float) @ self.V0.T


class EHGSO(_ExtendedStateObserver):
    """Extended high-gain state observers, one per output channel (Chen-Gao-Lin, Example 4).

    The EHGSO of Freidovich and Khalil (2008; Chen-Gao-Lin's [28]) observes a
    single-output system in normal form ``xi_1+ = xi_2, ..., xi_r+ = phi0(x) +
    sigma`` through the chain ``xi`` and the extended state ``sigma``; the observer
    runs the nominal model ``phi0`` and its gains are those of the bare chain of
    ``r + 1`` integrators (``xi_1 .. xi_r, sigma``), here with characteristic
    polynomial ``(z - omega)^(r+1)``. Applied to a MIMO system channel by channel
    (Chen-Gao-Lin's [41]) with all model information and measurements (their
    Fig. 9), in the coordinates

    ``xi_ij = c_i Phi^(j-1) x`` (``j = 1..r_i``), ``sigma_i = V0_i f``

    (a basis under Assumption 1, where ``sum r_i = n``): channel ``i`` injects only
    ``y_i - xi_hat_i1``, into its own chain and ``sigma_i``. The model terms
    ``c_i Phi^(r_i) x`` are not cancelled by the gain, so the error dynamics are
    coupled and their eigenvalues are not at ``omega`` (``error_poles``);
    ``sigma_hat_i`` estimates ``V0_i f`` plus a state-error term. The MB-ESO's
    gain (:func:`decoupled_gain`) differs exactly in cancelling those terms.
    ``f_hat = V0^-1 sigma_hat``, the ``f`` part of the augmented estimate.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system (Assumption 1: ``q = l``, no invariant zeros).
    omega : float or sequence of float
        The root of each channel's chain polynomial ``(z - omega_i)^(r_i+1)``, in
        ``[0, 1)``.
    x0, d0 : array_like, optional
        Initial state and disturbance estimates (default zero).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.

    Attributes
    ----------
    error_poles : ndarray
        Eigenvalues of the coupled error dynamics ``A - L C``.

    Raises
    ------
    DesignError
        If Assumption 1 fails, or the channel designs are unstable once coupled
        (on Chen-Gao-Lin's Example 4: for ``omega`` below 0.4 or above 0.6).
    """

    name = "EHGSO"

    def __init__(self, sys: LinearSystem, omega: float | Sequence[float] = 0.0,
                 x0: ArrayLike | None = None, d0: ArrayLike | None = None,
                 *, disturbance_inputs: DisturbanceInputs = None) -> None:
        super().__init__(sys, disturbance_inputs=disturbance_inputs)
        sys = self.sys
        rd = _check_assumption1(sys, "EHGSO")
        n, q = sys.n, sys.q
        om = _omegas(omega, q)
        a = sys.augmented()
        A, C = a.A, a.C
        # normal-form coordinates z = T [x; f], channel by channel (xi_i1..xi_ir_i, sigma_i)
        T = np.zeros((n + q, n + q))
        blocks, row = [], 0
        for i, r in enumerate(rd.degrees):
            for j in range(r):
                T[row + j, :n] = sys.Xi[i] @ np.linalg.matrix_power(sys.Phi, j)
            T[row + r, n:] = rd.V0[i]
            blocks.append((row, r + 1))
            row += r + 1
        if row != n + q or np.linalg.matrix_rank(T) < n + q:
            raise DesignError("the normal-form coordinates of the channels are not a basis "
                              "(Assumption 1)", "Assumption 1")
        Tinv = np.linalg.inv(T)
        Lz = np.zeros((n + q, q))
        for i, (o, m) in enumerate(blocks):
            chain = np.eye(m, k=1)  # xi_1 -> ... -> xi_r -> sigma, sigma+ = sigma
            chain[-1, -1] = 1.0
            e1 = np.eye(1, m)
            Lz[o : o + m, i] = place_gain(chain, e1, [om[i]] * m)[:, 0]
        L = Tinv @ Lz
        self.L, self.omegas, self.degrees, self.V0 = L, om, tuple(rd.degrees), rd.V0
        self.error_poles = np.linalg.eigvals(A - L @ C)
        rho = float(np.abs(self.error_poles).max())
        if rho >= 1.0:
            raise DesignError(f"the per-channel EHGSO designs are unstable once coupled "
                              f"(spectral radius {rho:.4g})", "stable gains")
        self._init_extended(A, L, C, a.Gamma, x0, d0)

    @property
    def gains(self) -> dict:
        return {"L": self.L}
