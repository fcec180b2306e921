"""Floating-point error bounds and directed rounding shared by the certified computations.

Every certified bound in the package (LP duals, interval hulls, support values,
reductions, the SMFDO's closed forms) moves its floating-point value outward by
a bound built from these pieces (Higham, *Accuracy and Stability of Numerical
Algorithms*, 2nd ed., SIAM 2002, Lemma 3.1 and eq. (3.4)).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["UNIT_ROUNDOFF", "gamma", "pow2_inverse", "round_down", "round_up"]

#: Unit roundoff ``u = eps / 2`` of IEEE double precision.
UNIT_ROUNDOFF: float = float(np.finfo(np.float64).eps / 2.0)


def gamma(k: int) -> float:
    """Higham's ``gamma_k = k u / (1 - k u)``: relative error bound of a length-``k`` dot product.

    Parameters
    ----------
    k : int
        Number of floating-point operations in sequence (``k u < 1``).

    Returns
    -------
    float
        The bound.
    """
    return k * UNIT_ROUNDOFF / (1.0 - k * UNIT_ROUNDOFF)


def round_up(x: ArrayLike) -> NDArray[np.float64] | float:
    """The next floating-point number above ``x`` (elementwise; a float for a scalar).

    Parameters
    ----------
    x : array_like
        Values.

    Returns
    -------
    float or ndarray
        ``nextafter(x, +inf)``.
    """
    out = np.nextafter(x, np.inf)
    return float(out) if np.ndim(out) == 0 else out


def round_down(x: ArrayLike) -> NDArray[np.float64] | float:
    """The next floating-point number below ``x`` (elementwise; a float for a scalar).

    Parameters
    ----------
    x : array_like
        Values.

    Returns
    -------
    float or ndarray
        ``nextafter(x, -inf)``.
    """
    out = np.nextafter(x, -np.inf)
    return float(out) if np.ndim(out) == 0 else out


def pow2_inverse(v: NDArray[np.float64]) -> NDArray[np.float64]:
    """Powers of two ``s`` with ``s v`` in ``[0.5, 1)`` (1 where ``v`` is zero).

    Scaling by a power of two is exact, so equilibrating with these factors adds
    no rounding error.

    Parameters
    ----------
    v : ndarray
        Nonnegative values.

    Returns
    -------
    ndarray
        The scale factors.
    """
    out = np.ones(v.size)
    pos = v > 0
    out[pos] = np.ldexp(1.0, -np.frexp(v[pos])[1])
    return out
