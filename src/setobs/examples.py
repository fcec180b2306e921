"""Every system printed in the seed papers, as ready constructors.

Each function returns a :class:`~setobs.systems.LinearSystem` (the modular-observer
paper's nonlinear example a :class:`~setobs.nonlinear.NonlinearSystem`) and says in
its docstring where the numbers come from. Where text extraction damaged a matrix,
the reconstruction is stated.
"""

from __future__ import annotations

import numpy as np

from .exceptions import InvalidValueError
from .models.exosystem import NonlinearSystem
from .models.linear import LinearSystem

__all__ = [
    "chang2006",
    "chen_gao_lin_example1",
    "chen_gao_lin_example2",
    "chen_gao_lin_example4",
    "chen_gao_lin_example5",
    "modular_example",
    "servo_motor",
]


def chang2006() -> LinearSystem:
    """The Chang (2006) PIO example, used by Li-Cong-Dong and by Fu-Wang.

    Li-Cong-Dong, eq. (25): ``Phi``, ``G``, ``Xi`` (``Gamma = 0``); the same
    matrices are ``A``, ``E``, ``C`` of the Fu-Wang example (Sec. IV), which
    takes them from J.-L. Chang, IEEE TAC 51(5), 2006. n = 3, q = 2, l = 2.

    Examples
    --------
    >>> chang2006()
    LinearSystem(n=3, q=2, l=2, p=0)
    """
    Phi = [[0.9630, 0.0181, 0.0187],
           [0.1808, 0.8195, -0.0514],
           [-0.1116, 0.0344, 0.9586]]
    G = [[0.0996, 0.0213],
         [0.0050, 0.1277],
         [0.1510, 0.0406]]
    Xi = [[1.0, 0.0, -1.0],
          [-1.0, 1.0, 1.0]]
    return LinearSystem(Phi, G, Xi)


def chen_gao_lin_example1() -> LinearSystem:
    """Chen-Gao-Lin (MB-ESO paper), Sec. V-A, Example 1 (also Example 3).

    ``A_0`` (9x9), ``E_0`` (printed transposed, 3x9) and ``C_0`` (3x9) as
    printed; ``B_0`` is omitted in the paper. The paper states relative degrees
    ``{2, 4, 3}``, no invariant zeros, and
    ``V_0 = [[2, 0.5, 0.25], [0.35, 1.5, 0.5], [0.4, 0.6, 0.5]]``.
    """
    A0 = [
        [-0.24, 1.88, -0.28, -0.016, 0, 0, -0.08, 0.04, -0.04],
        [-0.12, 0.44, -0.14, -0.008, 0, 0, -0.04, 0.02, -0.02],
        [0, 0, 0, 1, 0.8, 0, 0, 0, 0],
        [0, 0, 0, 0, 1, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 1, 0, 0, 0],
        [-0.5, 0.8, -0.1, -0.1, -0.6, -0.4, -0.8, -0.14, 0.04],
        [0, 0, 0, 0, 0, 0, 0, 1, -1],
        [-0.4, 0.6, -0.1, -0.07, -0.4, 0, -0.2, -0.1, 0.4],
        [-0.4, 0.6, -0.1, -0.07, -0.4, 0, -0.2, -0.1, -0.6],
    ]
    E0T = [
        [4, 2, 0, 0, 0, 0.35, 0, 0.4, 0.4],
        [1, 0.5, 0, 0, 0, 1.5, 0, 0.6, 0.6],
        [0.5, 0.25, 0, 0, 0, 0.5, 0, 0.5, 0.5],
    ]
    C0 = [
        [1, -2, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 1, -0.8, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 1, 0, 0],
    ]
    return LinearSystem(A0, np.array(E0T).T, C0)


def chen_gao_lin_example2(sample_time: str = "20ms") -> LinearSystem:
    """Chen-Gao-Lin, Sec. V-A, Example 2: the series elastic actuator (SEA).

    Parameters
    ----------
    sample_time : {"20ms", "1ms"}
        The paper prints the model discretised at 20 ms and at 1 ms. Both have
        relative degrees ``{2, 2}`` and diagonal ``V_0``; the 1 ms model has
        entries near ``1e-6`` and ``4e-5`` (a test of scale-aware rank decisions).

    Notes
    -----
    ``C_0`` is printed transposed for 20 ms; both are ``[[1,0,0,0],[0,0,1,0]]``.
    The control input matrix ``B_0`` is kept as ``Gamma``.
    """
    if sample_time == "20ms":
        A0 = [[0, 1, 0, 0],
              [-0.6587, 1.6494, 3.4847e-4, 0],
              [0, 0, 0, 1],
              [1.7991, 0, -0.9829, 1.8929]]
        B0 = [[0], [0], [0], [74.96]]
        E0 = [[0, 0], [0.0145, 0], [0, 0], [0, 74.96]]
        dt = 0.02
    elif sample_time == "1ms":
        A0 = [[0, 1, 0, 0],
              [-0.9793, 1.9793, 1.056e-6, 0],
              [0, 0, 0, 1],
              [0.0046, 0, -0.9991, 1.9989]]
        B0 = [[0], [0], [0], [0.1904]]
        E0 = [[0, 0], [4.3984e-5, 0], [0, 0], [0, 0.1904]]
        dt = 0.001
    else:
        raise InvalidValueError(f"sample_time must be '20ms' or '1ms', got {sample_time!r}")
    C0 = [[1, 0, 0, 0], [0, 0, 1, 0]]
    return LinearSystem(A0, E0, C0, B0, dt=dt)


def chen_gao_lin_example4() -> LinearSystem:
    """Chen-Gao-Lin, Sec. V-B, Example 4: a 9-state system in normal form.

    Notes
    -----
    **Reconstructed.** The printed ``A_0`` has only 8 rows although ``n = 9``
    (relative degrees ``2 + 4 + 3``). In normal form with those degrees the
    chain of the second output is ``x3 -> x4 -> x5 -> x6``, and the printed rows
    give ``x3+ = x4``, ``x4+ = x5`` and then a full row that carries the
    disturbance entry ``1.5`` at state 6. The missing row is ``x5+ = x6``,
    i.e. ``[0 0 0 0 0 1 0 0 0]``, inserted as row 5. This reconstruction
    reproduces the printed ``V_0 = diag(2, 1.5, 0.5)`` and relative degrees
    ``{2, 4, 3}`` (checked in the tests).
    """
    A0 = [
        [0, 1, 0, 0, 0, 0, 0, 0, 0],
        [-0.12, 0.2, -0.14, -0.12, 0, 0, -0.04, 0.02, 0],
        [0, 0, 0, 1, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 1, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 1, 0, 0, 0],  # reconstructed (missing in the printed text)
        [-0.5, -0.2, -0.1, -0.18, -0.6, -0.4, -0.8, -0.14, -0.1],
        [0, 0, 0, 0, 0, 0, 0, 1, 0],
        [0, 0, 0, 0, 0, 0, 0, 0, 1],
        [-0.4, -0.2, -0.1, -0.15, -0.4, 0, -0.2, -0.1, -0.7],
    ]
    E0T = [
        [0, 2, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 1.5, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 0, 0, 0.5],
    ]
    C0 = [
        [1, 0, 0, 0, 0, 0, 0, 0, 0],
        [0, 0, 1, 0, 0, 0, 0, 0, 0],
        [0, 0, 0, 0, 0, 0, 1, 0, 0],
    ]
    return LinearSystem(A0, np.array(E0T, dtype=float).T, C0)


def chen_gao_lin_example5(zeros: tuple[float, float] = (0.4, 0.4)) -> LinearSystem:
    """Chen-Gao-Lin, Sec. V-B, Example 5: a SISO two-mass spring with placed zeros.

    ``A_0 = [[0,1,0,0],[b110,b111,b120,0],[0,0,0,1],[b210,0,b220,b221]]``,
    ``E_0 = e_2``, ``C_0 = e_1^T`` with ``b110 = -0.264``, ``b111 = 1.03``,
    ``b120 = 0.02``, ``b210 = 0.02``. The numerator of the transfer function
    from ``f`` to ``y`` is ``z^2 - b221 z - b220`` (paper), so zeros ``(z1, z2)``
    give ``b221 = z1 + z2`` and ``b220 = -z1 z2``.

    Parameters
    ----------
    zeros : (float, float)
        The two invariant zeros (the paper uses both at 0, 0.2, 0.4, 0.6, 0.8).
    """
    z1, z2 = (float(z) for z in zeros)
    b110, b111, b120, b210 = -0.264, 1.03, 0.02, 0.02
    b221, b220 = z1 + z2, -z1 * z2
    A0 = [[0, 1, 0, 0], [b110, b111, b120, 0], [0, 0, 0, 1], [b210, 0, b220, b221]]
    return LinearSystem(A0, [[0], [1], [0], [0]], [[1, 0, 0, 0]])


def servo_motor(J: float = 1.2e-4, B: float = 7.03e-5, dt: float = 1e-3, *,
                measure_velocity: bool = False) -> LinearSystem:
    """A servo motor with an unknown load torque: ``J dw/dt = tau - B w - tau_L``.

    States ``x = (theta, omega)`` (rad, rad/s), control input the commanded
    torque ``tau`` (N m), disturbance the load/friction torque ``tau_L`` (N m),
    which enters like the input with the opposite sign; output the position
    ``theta`` (and the velocity with ``measure_velocity=True``). Zero-order-hold
    discretisation at ``dt`` (:meth:`LinearSystem.from_continuous`). The
    defaults are the HSM150 lab rig's (``J = 1.2e-4 kg m^2``, ``B = 7.03e-5 N m s``,
    1 kHz), whose measured identification record the noise tests and
    benchmarks use (``shared/data/hsm150``, not shipped).

    Parameters
    ----------
    J : float
        Inertia (kg m^2).
    B : float
        Viscous friction (N m s/rad).
    dt : float
        Sampling time (s).
    measure_velocity : bool
        Also measure the velocity (a second output).

    Examples
    --------
    >>> servo_motor()
    LinearSystem(n=2, q=1, l=1, p=1, dt=0.001)
    """
    H = [[0.0, 1.0], [0.0, -B / J]]
    C = [[1.0, 0.0], [0.0, 1.0]] if measure_velocity else [[1.0, 0.0]]
    outputs = ["theta", "omega"] if measure_velocity else ["theta"]
    return LinearSystem.from_continuous(H, [[0.0], [1.0 / J]], [[0.0], [-1.0 / J]], C, dt,
                                        state_names=["theta", "omega"],
                                        disturbance_names=["tau_L"], input_names=["tau"],
                                        output_names=outputs)


def modular_example() -> NonlinearSystem:
    """The modular-observer paper's nonlinear example (Section VI, eq. (40)); needs sympy.

    ``x+ = (x - w)/(2 + x + (2x + 3) w)``, ``w+ = w``,
    ``y = 2x/(1 + x) + w/(1 + w)``: a scalar state and a constant (step)
    disturbance. The printed equation is damaged by text extraction; this is
    the reconstruction consistent with the paper's closed-form solution: in
    ``xi = 2x/(1 + x)``, ``eta = w/(1 + w)`` the system is linear
    (``xi+ = xi/2 - eta``, ``eta+ = eta``, ``y = xi + eta``).
    """
    return NonlinearSystem(lambda x, w: [(x[0] - w[0]) / (2 + x[0] + (2 * x[0] + 3) * w[0])],
                           lambda x, w: [2 * x[0] / (1 + x[0]) + w[0] / (1 + w[0])],
                           ["x"], ["w"])
