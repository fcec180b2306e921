"""Computed powers of the observable dynamics with a bound on their rounding that does
not compound: the error scale of the window's closed form and of its restart rows.

The closed form of ``s`` steps (:mod:`._closed_form`) and the restart rows
(:mod:`._restart`) read the powers ``A^k`` (``A = A_o``) through products computed in
floating point. The textbook bound on such a product, ``gamma |A|^k`` (Higham,
Lemma 3.5 iterated), is valid but grows like the spectral radius of ``|A|``, not of
``A``: on a stable plant with ``rho(A) = 0.7`` and ``cond(A) = 2e4``, ``|A|^k`` grows
about 48 times per step while ``A^k`` decays, and the window's allowances
(``c_err``, ``b_err``) reached ``1e5`` at window 10 while the window's own set was
0.4 wide (``shared/data/regressions/window_allowance_growth.py``).

The bound here follows the error instead of the magnitudes. With
``Â_k = fl(A Â_(k-1))``, ``Â_0 = I``, each step's rounding ``δ_k = Â_k - A Â_(k-1)``
obeys ``|δ_k| <= gamma_N |A| |Â_(k-1)| =: D_k`` (Higham, eq. (3.13)), and unrolling
``Â_k - A^k = A (Â_(k-1) - A^(k-1)) + δ_k`` gives, exactly,

.. math::  \\hat A_k - A^k = \\sum_{i=1}^{k} A^{k-i} \\delta_i,
           \\qquad |\\hat A_k - A^k| \\le F_k := \\sum_{i=1}^{k} P_{k-i} D_i,

where ``P_j := |Â_j| + F_j >= |A^j|`` bounds the exact powers (``P_0 = I``,
``F_0 = 0``). Every term is a computed product of nonnegative matrices and is
rounded up by ``1 + 2 gamma`` of its depth (a nonnegative product computed in
floating point is at most ``1 / (1 - gamma)`` times the computed value). ``F_k`` is of
the size ``gamma sum_i |A^(k-i)| |A| |A^(i-1)|``: it decays with the powers
themselves, so it never compounds. A product ``M A^k`` computed as ``fl(M Â_k)``
is then off the exact one by at most ``|M| F_k + gamma_N |M| |Â_k|``
(:meth:`PowerTable.left`); ``P_k`` is the magnitude that an uncertainty of ``z``
is carried with.

Overflow (an unstable plant over a long window) gives ``inf``, never ``NaN``:
an infinite bound is sound, and the bands that use it are infinite.

A table is built by the structure that reads it (a window's closed form, a restart's
rows: ``O(k^2)`` products of ``N x N`` matrices up to ``k``, once per structure, and
the structures are cached) and extended on demand; nothing is kept at module level.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._rounding import gamma

__all__ = ["PowerTable", "power_table", "quiet", "up"]


#: (an unstable plant over a long window overflows: an infinite bound is sound, and no
#: warning is due for it; ``NaN`` from ``inf * 0`` is made ``inf`` where it matters)
quiet = np.errstate(over="ignore", invalid="ignore")


@quiet
def up(X: NDArray[np.float64], depth: int) -> NDArray[np.float64]:
    """A computed nonnegative quantity of rounding depth ``depth`` made an upper bound
    of its exact value (``X (1 + 2 gamma(depth + 2))``; ``NaN`` from ``inf * 0``
    becomes ``inf``)."""
    out = X * (1.0 + 2.0 * gamma(depth + 2))
    if not np.isfinite(out).all():
        out = np.where(np.isnan(out), np.inf, out)
    return out


class PowerTable:
    """``Â_k`` and the bounds ``F_k >= |Â_k - A^k|``, ``P_k >= |A^k|`` for ``k <= K``.

    Parameters
    ----------
    A : ndarray, shape (N, N)
        The matrix (taken as exact).

    Notes
    -----
    See the module docstring for the recursion and its proof. Grows on demand
    (:meth:`extend`); owned by the structure that builds it.
    """

    def __init__(self, A: NDArray[np.float64]) -> None:
        A = np.ascontiguousarray(A, dtype=np.float64)
        N = A.shape[0]
        self.A, self.absA, self.N = A, np.abs(A), N
        self.powers: list[NDArray[np.float64]] = [np.eye(N)]
        self.F: list[NDArray[np.float64]] = [np.zeros((N, N))]
        self.P: list[NDArray[np.float64]] = [np.eye(N)]
        self._D: list[NDArray[np.float64]] = []
        # gamma of one product's rounding (N terms), doubled for the bound's own rounding
        self._gN = 2.0 * gamma(N + 2)

    @quiet
    def extend(self, K: int) -> PowerTable:
        """Make sure the table reaches ``k = K`` (returns ``self``)."""
        N = self.N
        while len(self.powers) <= K:
            k = len(self.powers)
            prev = self.powers[-1]
            Ak = self.A @ prev
            D = self._gN * (self.absA @ np.abs(prev))
            self._D.append(up(D, N))
            # F_k = sum_{i=1..k} P_(k-i) D_i  (P_(k-1), ..., P_0 against D_1, ..., D_k)
            Pst = np.array(self.P[::-1])
            Fk = np.matmul(Pst, np.array(self._D)).sum(axis=0)
            Fk = up(Fk, k * (N + 1))
            if not np.isfinite(Ak).all():
                Ak = np.where(np.isnan(Ak), np.inf, Ak)
                Fk = np.full((N, N), np.inf)
            self.F.append(Fk)
            self.P.append(up(np.abs(Ak) + Fk, 1))
            self.powers.append(Ak)
        return self

    @quiet
    def left(self, M: NDArray[np.float64], k: int
             ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``fl(M Â_k)`` and a bound on its distance to the exact ``M A^k``
        (``|M| F_k + gamma_N |M| |Â_k|``, rounded up)."""
        self.extend(k)
        Ak = self.powers[k]
        out = M @ Ak
        aM = np.abs(M)
        err = aM @ self.F[k] + (2.0 * gamma(self.N + 2)) * (aM @ np.abs(Ak))
        return out, up(err, self.N + 2)

    @quiet
    def apply(self, k: int, X: NDArray[np.float64]
              ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``fl(Â_k X)`` and a bound on its distance to the exact ``A^k X``."""
        self.extend(k)
        Ak = self.powers[k]
        out = Ak @ X
        aX = np.abs(X)
        err = self.F[k] @ aX + (2.0 * gamma(self.N + 2)) * (np.abs(Ak) @ aX)
        return out, up(err, self.N + 2)


def power_table(A: NDArray[np.float64], K: int) -> PowerTable:
    """A :class:`PowerTable` of ``A`` extended to ``k = K``."""
    return PowerTable(A).extend(K)
