"""Floating-point error bounds and directed rounding shared by the certified computations.

Every certified bound in the package (LP duals, interval hulls, support values,
reductions, the SMFDO's closed forms) moves its floating-point value outward by
a bound built from these pieces (Higham, *Accuracy and Stability of Numerical
Algorithms*, 2nd ed., SIAM 2002, Lemma 3.1 and eq. (3.4)).
"""

from __future__ import annotations

import math
from typing import overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = ["UNIT_ROUNDOFF", "exact_dot", "gamma", "pow2_inverse", "round_down", "round_up",
           "two_prod"]

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


@overload
def round_up(x: float) -> float: ...


@overload
def round_up(x: NDArray[np.float64]) -> NDArray[np.float64]: ...


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


@overload
def round_down(x: float) -> float: ...


@overload
def round_down(x: NDArray[np.float64]) -> NDArray[np.float64]: ...


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


def outward_interval(c: NDArray[np.float64], c_err: NDArray[np.float64] | None,
                     low: NDArray[np.float64], upp: NDArray[np.float64],
                     offset: NDArray[np.bool_] | None = None
                     ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``[c + low, c + upp]`` widened by ``c_err`` and rounded outward.

    The one rounding of an interval hull from certified factor-space bounds
    (the reference path's :meth:`ConstrainedZonotope.interval_hull` and the
    compiled fast path's ``setobs.setmembership._kernels.hull_bounds``):
    ``lo = down(down(c - c_err) + low)``, ``hi = up(up(c + c_err) + upp)``,
    with ``c`` used as is where ``c_err = 0`` and ``-inf``/``inf`` where a
    bound is infinite.

    Parameters
    ----------
    c : ndarray, shape (n,)
        Centre.
    c_err : ndarray, shape (n,) or None
        Bound on the error of ``c`` (``None``: exact).
    low, upp : ndarray, shape (n,)
        Certified bounds of the offset from ``c``.
    offset : ndarray of bool, shape (n,), optional
        Coordinates that have an offset (default all); the others get the
        rounded bounds of ``c`` alone.

    Returns
    -------
    lo, hi : ndarray, shape (n,)
    """
    c = np.asarray(c, dtype=np.float64)
    if c_err is None:
        c_lo = c_hi = c
    else:
        e = np.asarray(c_err, dtype=np.float64)
        c_lo = np.where(e > 0, np.nextafter(c - e, -np.inf), c)
        c_hi = np.where(e > 0, np.nextafter(c + e, np.inf), c)
    with np.errstate(invalid="ignore"):
        lo = np.where(np.isfinite(low), np.nextafter(low + c_lo, -np.inf), -np.inf)
        hi = np.where(np.isfinite(upp), np.nextafter(upp + c_hi, np.inf), np.inf)
    if offset is not None:
        lo = np.where(offset, lo, c_lo)
        hi = np.where(offset, hi, c_hi)
    return lo, hi


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
    # (frexp gives the exponent 0 at zero, so that entry's factor is 2^0 = 1)
    return np.ldexp(1.0, -np.frexp(np.ravel(v))[1])


def _split(a: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Dekker's split of doubles into 26-bit halves (``a = hi + lo`` exactly)."""
    t = 134217729.0 * a  # 2**27 + 1
    hi = t - (t - a)
    return hi, a - hi


def two_prod(M: NDArray[np.float64], v: NDArray[np.float64]
             ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Exact products ``M * v[:, None] = p + e`` (Dekker's TwoProduct).

    Parameters
    ----------
    M : ndarray, shape (m, n)
        Matrix.
    v : ndarray, shape (m,)
        Row factors.

    Returns
    -------
    p, e : ndarray
        The rounded products and their exact errors (barring underflow).
    """
    p = M * v[:, None]
    mh, ml = _split(M)
    vh, vl = _split(np.broadcast_to(v[:, None], M.shape))
    return p, ((mh * vh - p) + mh * vl + ml * vh) + ml * vl


def exact_dot(ys: list[NDArray[np.float64]], b: NDArray[np.float64]) -> float:
    """Correctly rounded ``(y_1 + y_2 + ...)^T b`` (exact Dekker products, :func:`math.fsum`).

    Parameters
    ----------
    ys : list of ndarray
        The terms of the multiplier.
    b : ndarray
        The vector.
    """
    if b.size == 0:
        return 0.0
    terms: list[float] = []
    for y in ys:
        p, e = two_prod(b[:, None], y)
        terms += p[:, 0].tolist() + e[:, 0].tolist()
    return math.fsum(terms)
