"""Axis-aligned boxes (interval vectors), the result type of interval hulls."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._deprecation import renamed
from .._validation import as_vector, readonly
from ..exceptions import ImmutableError, InvalidValueError

__all__ = ["Box", "box_center", "box_center_radius"]


def box_center(lo: NDArray[np.float64], hi: NDArray[np.float64]) -> NDArray[np.float64]:
    """Midpoints ``(lo + hi) / 2``; NaN where a coordinate is unbounded.

    Parameters
    ----------
    lo, hi : ndarray, shape (n,)
        Bounds.
    """
    with np.errstate(invalid="ignore"):
        mid = 0.5 * lo + 0.5 * hi
    return np.where(np.isfinite(mid), mid, np.nan)


def box_center_radius(lo: NDArray[np.float64], hi: NDArray[np.float64]
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Centre and outward-rounded radii of a box: ``[lo, hi] in c + [-rad, rad]``.

    The representation of a box as a set with generators ``I`` and factor
    bounds ``rad`` (:meth:`ConstrainedZonotope.from_box`, Scott et al.'s
    Theorem 1, the reduction's recentring): the centre is the rounded
    midpoint, and the radius covers both ends from it (the larger distance,
    rounded up where its subtraction was inexact: ``[0, 3]`` and ``[-1, 1]``
    keep their corners exactly). An unbounded coordinate has centre 0 and
    radius ``inf``.

    Parameters
    ----------
    lo, hi : ndarray, shape (n,)
        Bounds (``lo <= hi``).
    """
    free = ~(np.isfinite(lo) & np.isfinite(hi))
    anyfree = free.any()
    lo_f = np.where(free, 0.0, lo) if anyfree else lo
    hi_f = np.where(free, 0.0, hi) if anyfree else hi
    c = 0.5 * lo_f + 0.5 * hi_f
    d_hi, d_lo = hi_f - c, c - lo_f
    rad = np.maximum(d_hi, d_lo)
    # rounded up only where a difference was inexact (Knuth's TwoSum error): where both
    # are exact, [c - rad, c + rad] covers [lo, hi] as is (a box's corners stay its own)
    exact = (_sum_error(hi_f, -c, d_hi) == 0) & (_sum_error(c, -lo_f, d_lo) == 0)
    rad = np.where((rad > 0) & ~exact, np.nextafter(rad, np.inf), rad)
    return c, (np.where(free, np.inf, rad) if anyfree else rad)


def _sum_error(a: NDArray[np.float64], b: NDArray[np.float64],
               s: NDArray[np.float64]) -> NDArray[np.float64]:
    """``a + b - s`` exactly for ``s = fl(a + b)`` (Knuth's TwoSum; finite values)."""
    bv = s - a
    av = s - bv
    return (a - av) + (b - bv)


class Box:
    """The box ``prod_i [lo_i, hi_i]``; bounds may be infinite.

    Parameters
    ----------
    lo, hi : array_like, shape (n,)
        Lower and upper bounds, ``lo <= hi``; ``lo`` may be ``-inf`` and ``hi``
        may be ``+inf``.

    Notes
    -----
    The centre of a box is the worst-case-optimal point estimate for the
    infinity norm over the box (it minimises ``max_{x in box} ||x - e||_inf``);
    it is also optimal for the Euclidean norm over the box itself. Unbounded
    coordinates have no centre and give NaN in :attr:`center`.

    Examples
    --------
    >>> b = Box([0.0, -1.0], [2.0, 1.0])
    >>> b.center.tolist(), b.half_width.tolist()
    ([1.0, 0.0], [1.0, 1.0])
    """

    __slots__ = ("_hi", "_lo")

    def __init__(self, lo: ArrayLike, hi: ArrayLike) -> None:
        lo_a = as_vector("lo", lo, allow_inf=True)
        hi_a = as_vector("hi", hi, size=lo_a.size, allow_inf=True)
        if np.isposinf(lo_a).any() or np.isneginf(hi_a).any():
            raise InvalidValueError("lo must not be +inf and hi must not be -inf")
        if (lo_a > hi_a).any():
            i = int(np.argmax(lo_a > hi_a))
            raise InvalidValueError(
                f"lo must not exceed hi (index {i}: lo={lo_a[i]}, hi={hi_a[i]})")
        object.__setattr__(self, "_lo", readonly(lo_a))
        object.__setattr__(self, "_hi", readonly(hi_a))

    @classmethod
    def _trusted(cls, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> Box:
        """A box from float64 vectors already known to be valid (``lo <= hi``); no copy."""
        box = object.__new__(cls)
        lo.flags.writeable = False
        hi.flags.writeable = False
        object.__setattr__(box, "_lo", lo)
        object.__setattr__(box, "_hi", hi)
        return box

    def __setattr__(self, name: str, value: object) -> None:
        raise ImmutableError("Box is immutable")

    def __reduce__(self):
        return (Box, (np.array(self._lo), np.array(self._hi)))

    @property
    def lo(self) -> NDArray[np.float64]:
        """Lower bounds (read-only)."""
        return self._lo

    @property
    def hi(self) -> NDArray[np.float64]:
        """Upper bounds (read-only)."""
        return self._hi

    @property
    def dim(self) -> int:
        """Dimension ``n``."""
        return int(self._lo.size)

    @property
    def is_bounded(self) -> bool:
        """Whether every bound is finite."""
        return bool(np.isfinite(self._lo).all() and np.isfinite(self._hi).all())

    @property
    def center(self) -> NDArray[np.float64]:
        """Midpoints ``(lo + hi) / 2``; NaN where a coordinate is unbounded."""
        return box_center(self._lo, self._hi)

    radius = renamed("radius", "half_width", "'radius' means a worst-case error elsewhere")

    @property
    def half_width(self) -> NDArray[np.float64]:
        """Half-widths ``(hi - lo) / 2`` (``inf`` where unbounded)."""
        return 0.5 * (self._hi - self._lo)

    @property
    def width(self) -> NDArray[np.float64]:
        """Widths ``hi - lo`` (``inf`` where unbounded)."""
        return self._hi - self._lo

    def contains(self, x: ArrayLike, tol: float = 0.0) -> bool:
        """Whether ``lo - tol <= x <= hi + tol`` componentwise.

        Parameters
        ----------
        x : array_like, shape (n,)
            The point.
        tol : float
            Allowed excess beyond the bounds.
        """
        xv = as_vector("x", x, size=self.dim)
        return bool(((xv >= self._lo - tol) & (xv <= self._hi + tol)).all())

    def __repr__(self) -> str:
        rows = ", ".join(f"[{lo:.6g}, {hi:.6g}]" for lo, hi in zip(self._lo, self._hi, strict=True))
        return f"Box({rows})"

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Box):
            return NotImplemented
        return bool(np.array_equal(self._lo, other._lo) and np.array_equal(self._hi, other._hi))

    __hash__ = None  # type: ignore[assignment]


def trusted_box(lo: NDArray[np.float64], hi: NDArray[np.float64]) -> Box:
    """Package-internal: a :class:`Box` from float64 vectors known to be valid; no copy.

    The arrays are made read-only. Not in ``__all__``; no stability promise.
    """
    return Box._trusted(lo, hi)
