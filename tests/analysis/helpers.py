"""Systems built with known structure, for testing verdicts against their construction."""

from __future__ import annotations

import numpy as np
from scipy.linalg import block_diag

from setobs import LinearSystem


def siso_with_zeros(zeros, poles, rng=None) -> LinearSystem:
    """Controllable canonical form of ``prod(z - zeros) / prod(z - poles)`` (d -> y).

    The finite invariant zeros are exactly ``zeros`` (numerator and denominator
    coprime for generic poles).
    """
    den = np.poly(poles).real
    num = np.poly(zeros).real if len(zeros) else np.array([1.0])
    n = len(poles)
    A = np.zeros((n, n))
    A[:-1, 1:] = np.eye(n - 1)
    A[-1] = -den[1:][::-1]
    B = np.zeros((n, 1))
    B[-1, 0] = 1.0
    C = np.zeros((1, n))
    C[0, : len(num)] = num[::-1]
    return LinearSystem(A, B, C)


def block_system(*systems: LinearSystem) -> LinearSystem:
    """Block-diagonal (decoupled) combination; its zeros are the union of the parts' zeros."""
    return LinearSystem(block_diag(*(s.Phi for s in systems)), block_diag(*(s.G for s in systems)),
                        block_diag(*(s.Xi for s in systems)))


def random_similarity(sys: LinearSystem, rng: np.random.Generator, decades: float = 3.0
                      ) -> LinearSystem:
    """A random dense similarity (orthogonal x diag in [0.3, 3], condition <= 10) with
    random output and disturbance scalings over ``2 * decades`` orders of magnitude.

    (A dense similarity of condition 1e6 destroys six digits of the data itself; the
    balancing step undoes diagonal scalings exactly, not dense ill-conditioning.)
    """
    n = sys.n
    Q, _ = np.linalg.qr(rng.normal(size=(n, n)))
    T = np.diag(10.0 ** rng.uniform(-0.5, 0.5, n)) @ Q
    return sys.transformed(T, output_scale=10.0 ** rng.uniform(-decades, decades, sys.l),
                           disturbance_scale=10.0 ** rng.uniform(-decades, decades, sys.q))


def diagonal_rescaling(sys: LinearSystem, rng: np.random.Generator, decades: float = 3.0
                       ) -> LinearSystem:
    """Pure diagonal rescaling of states, outputs and disturbances (exact structure kept)."""
    T = np.diag(10.0 ** rng.uniform(-decades, decades, sys.n))
    return sys.transformed(T, output_scale=10.0 ** rng.uniform(-decades, decades, sys.l),
                           disturbance_scale=10.0 ** rng.uniform(-decades, decades, sys.q))


def with_unobservable_disturbance(rng: np.random.Generator) -> tuple[LinearSystem, np.ndarray]:
    """Kalman-structured system whose second disturbance drives only unobservable states.

    States ``(x_o in R^3, x_u in R^2)``; ``y`` sees only ``x_o``; ``x_u`` never
    feeds ``x_o``. Disturbance 1 enters ``x_o``, disturbance 2 only ``x_u``.
    Returns the system and the unrecoverable direction ``e_2``.
    """
    Ao = rng.normal(size=(3, 3)) * 0.4
    Au = rng.normal(size=(2, 2)) * 0.4
    A21 = rng.normal(size=(2, 3))
    A = np.block([[Ao, np.zeros((3, 2))], [A21, Au]])
    G = np.zeros((5, 2))
    G[:3, 0] = rng.normal(size=3)
    G[3:, 1] = rng.normal(size=2)
    C = np.hstack([rng.normal(size=(2, 3)), np.zeros((2, 2))])
    return LinearSystem(A, G, C), np.array([0.0, 1.0])
