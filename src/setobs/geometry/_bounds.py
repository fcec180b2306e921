"""The rounding bounds of the set operations' centres and right-hand sides: the one
specification of them, which the compiled construction (``_setops.c``) mirrors entry for
entry (``tests/geometry/test_compiled_set_operations.py`` checks the two agree).

Elementwise bounds on the rounding errors of centres and right-hand sides (``None`` means
exact, so that exact sets cost nothing). Each helper returns the bound of the new vector:
carried errors plus the rounding of the operation (Higham's gamma bounds), inflated once
more for the rounding of the bound.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._rounding import UNIT_ROUNDOFF, gamma

__all__ = ["add_err", "cat_err", "diff_err", "map_err", "sum_err"]


def add_err(e1: NDArray[np.float64] | None, e2: NDArray[np.float64] | None
            ) -> NDArray[np.float64] | None:
    """The bound of a sum of two bounded vectors (``None``: exact)."""
    if e1 is None:
        return e2
    if e2 is None:
        return e1
    return (e1 + e2) * (1.0 + 2.0 * UNIT_ROUNDOFF)


def cat_err(e1, n1: int, e2, n2: int) -> NDArray[np.float64] | None:
    """Concatenated bounds of two stacked vectors (``None``: exact)."""
    if e1 is None and e2 is None:
        return None
    return np.concatenate([np.zeros(n1) if e1 is None else e1,
                           np.zeros(n2) if e2 is None else e2])


_GAMMA2 = gamma(2)


def sum_err(s, err) -> NDArray[np.float64] | None:
    """Bound for the rounding of ``s = fl(a + v)`` plus the bound ``err`` carried by
    ``a`` and ``v``: ``|fl(a + v) - (a + v)| <= u |a + v| <= gamma_1 |s|``, and
    ``gamma_2 |s|`` also covers the rounding of that product (zero where ``s = 0``:
    a floating-point sum is zero only if exact)."""
    new = np.abs(s)
    if not np.count_nonzero(new):  # (count_nonzero: ~0.3 us against ~1.4 for .any())
        return err
    new *= _GAMMA2
    return new if err is None else add_err(err, new)


def map_err(M, c, err) -> NDArray[np.float64] | None:
    """Bound for ``fl(M c)`` given the bound ``err`` carried by ``c``."""
    if err is None and not np.count_nonzero(c):
        return None
    k = M.shape[1]
    base = gamma(k + 1) * np.abs(c)
    if err is not None:
        base += err
    out = np.abs(M) @ base
    out *= 1.0 + gamma(k + 2)
    return out


def diff_err(y, C, c, cerr, yerr) -> NDArray[np.float64] | None:
    """Bound for ``fl(y - C c)`` given the bounds carried by ``c`` and ``y``."""
    k = C.shape[1]
    absC = np.abs(C)
    base = absC @ np.abs(c)
    base += np.abs(y)
    base *= gamma(k + 1)
    if cerr is not None:
        base += absC @ cerr
    if yerr is not None:
        base += yerr
    if not np.count_nonzero(base):
        return None
    base *= 1.0 + gamma(k + 3)
    return base
