"""The data guard of every set-building path: a set's data are finite and at most
:data:`~setobs.tolerances.MAX_MAGNITUDE` in magnitude (:func:`check_set_data`)."""

from __future__ import annotations

import numpy as np

from ..exceptions import MagnitudeError
from ..tolerances import MAX_MAGNITUDE

__all__ = ["DATA_NAMES", "check_set_data", "first_bad_numpy"]

DATA_NAMES = ("G", "c", "A", "b", "h", "c_err", "b_err")


def first_bad_numpy(arrays) -> tuple[int, int, float] | None:
    """:func:`_setops.check_data` in NumPy (any array-likes; the fallback)."""
    for k, a in enumerate(arrays):
        if a is None:
            continue
        a = np.asarray(a, dtype=np.float64)
        if not a.size:
            continue
        mag = np.abs(a)
        if mag.max() <= MAX_MAGNITUDE:  # (a NaN makes the maximum NaN: not <=)
            continue
        with np.errstate(invalid="ignore"):
            bad = ~(mag <= MAX_MAGNITUDE)
        if k == 4:
            bad &= ~np.isposinf(a)  # h: +inf is an unbounded factor
        if bad.any():
            i = int(np.flatnonzero(bad.reshape(-1))[0])
            return k, i, float(a.reshape(-1)[i])
    return None


def check_set_data(op: str, G, c, A, b, h, cerr=None, berr=None, compiled=None) -> None:
    """Refuse set data that are not finite or exceed :data:`MAX_MAGNITUDE` in magnitude.

    The guard of every set-building path (the constructor's validation, the trusted
    constructors of :mod:`setobs.geometry.zonotope` and the compiled operations, which fall
    back to the NumPy code on such results so that this raises): a set's ``G``, ``c``,
    ``A``, ``b``, ``c_err`` and ``b_err`` hold finite entries of at most ``MAX_MAGNITUDE``
    in magnitude, and ``h`` such entries or ``+inf``. Within that bound no single operation
    or LP on the set overflows double precision (products of two entries are at most
    ``1e300``), so no set with inf or NaN data, whose queries would answer wrongly or not at
    all, is ever built.

    Parameters
    ----------
    op : str
        The operation, named in the message.
    G, c, A, b, h : ndarray
        The set's data.
    cerr, berr : ndarray or None
        The rounding bounds of ``c`` and ``b`` (``None``: exact).
    compiled : module or None
        The compiled construction (``_setops``: its ``check_data``), or ``None`` (the
        NumPy check).

    Raises
    ------
    MagnitudeError
        Naming the operation, the array, the first bad entry and its value.
    """
    bad = None
    if compiled is not None:
        bad = compiled.check_data(G, c, A, b, h, cerr, berr)
        if bad is NotImplemented:
            bad = first_bad_numpy((G, c, A, b, h, cerr, berr))
    else:
        bad = first_bad_numpy((G, c, A, b, h, cerr, berr))
    if bad is None:
        return
    k, i, v = bad
    arr = np.asarray((G, c, A, b, h, cerr, berr)[k])
    idx = tuple(int(j) for j in np.unravel_index(i, arr.shape)) if arr.ndim > 1 else (i,)
    what = "NaN" if np.isnan(v) else f"an entry of {v:.3g}"
    raise MagnitudeError(
        f"{op}: the result's {DATA_NAMES[k]} would hold {what} (first at index {idx}); a "
        f"set's data must be finite and at most {MAX_MAGNITUDE:.0e} in magnitude "
        "(setobs.tolerances.MAX_MAGNITUDE: products of larger numbers overflow double "
        "precision): rescale the units, or the matrix of the operation")
