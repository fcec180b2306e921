"""The one validation helper for matrices and vectors (python-control ``_ssmatrix`` style).

Messages say which matrix, which dimension, the expected and the actual value.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .exceptions import ArgumentError, DimensionError, InvalidValueError
from .tolerances import MAX_MAGNITUDE

__all__ = ["as_inputs", "as_matrix", "as_vector", "check_real_scalar", "readonly"]


def readonly(a: NDArray[Any]) -> NDArray[Any]:
    """Return ``a`` (already a private copy) marked read-only."""
    a.flags.writeable = False
    return a


def _to_float(name: str, value: ArrayLike, what: str) -> NDArray[np.float64]:
    """A float64 copy of ``value``; complex, non-numeric and ragged input is refused."""
    if type(value) is np.ndarray and value.dtype == np.float64:
        return value.copy()  # the common case, without the checks below (~2 us)
    if isinstance(value, str | bytes) or value is None:
        raise ArgumentError(f"{name} must be a real numeric {what}, got {value!r}")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise ArgumentError(f"{name} must be a real numeric {what}: {exc}") from None
    if np.iscomplexobj(raw):
        hint = (" (its imaginary part is zero: pass .real)" if not np.any(np.imag(raw) != 0)
                else "")
        raise ArgumentError(f"{name} must be real, got a complex array{hint}")
    if raw.dtype.kind not in "biuf":
        if raw.dtype.kind == "O":
            try:
                return np.array(raw.tolist(), dtype=np.float64, copy=True)
            except (TypeError, ValueError) as exc:
                raise ArgumentError(f"{name} must be a real numeric {what}: {exc}") from None
        raise ArgumentError(f"{name} must be a real numeric {what}, got dtype {raw.dtype}")
    return np.array(raw, dtype=np.float64, copy=True)


def check_real_scalar(name: str, value: object, *, positive: bool = False,
                      nonnegative: bool = False) -> float:
    """A finite real number (not a bool), optionally positive or nonnegative.

    Raises
    ------
    TypeError
        If ``value`` is not a real number.
    InvalidValueError
        If it is NaN, infinite, or out of range.
    """
    if isinstance(value, bool | np.bool_) or not isinstance(value, int | float | np.integer
                                                             | np.floating):
        raise ArgumentError(f"{name} must be a real number, got {value!r}")
    v = float(value)
    if not np.isfinite(v):
        raise InvalidValueError(f"{name} must be finite, got {value!r}")
    if positive and not v > 0:
        raise InvalidValueError(f"{name} must be positive, got {value!r}")
    if nonnegative and v < 0:
        raise InvalidValueError(f"{name} must be nonnegative, got {value!r}")
    return v


def _check_finite(name: str, a: NDArray[np.float64], allow_inf: bool,
                  allow_nan: bool = False) -> None:
    # the common case in one pass: every entry finite and in range (a NaN makes the
    # maximum NaN and the comparison false)
    if not a.size or np.abs(a).max() <= MAX_MAGNITUDE:
        return
    if not allow_nan and np.isnan(a).any():
        idx = tuple(int(i) for i in np.argwhere(np.isnan(a))[0])
        raise InvalidValueError(f"{name} contains NaN (first at index {idx})")
    if not allow_inf and np.isinf(a).any():
        idx = tuple(int(i) for i in np.argwhere(np.isinf(a))[0])
        raise InvalidValueError(f"{name} contains inf (first at index {idx}); it must be finite")
    with np.errstate(invalid="ignore"):
        big = np.abs(a) > MAX_MAGNITUDE
    big &= np.isfinite(a)
    if big.any():
        idx = tuple(int(i) for i in np.argwhere(big)[0])
        raise InvalidValueError(
            f"{name} has an entry of {a[idx]:.3g} (first at index {idx}): entries must be at "
            f"most {MAX_MAGNITUDE:.0e} in magnitude (products of such numbers overflow double "
            "precision); rescale the units")


def as_matrix(
    name: str,
    value: ArrayLike,
    rows: int | None = None,
    cols: int | None = None,
    *,
    allow_inf: bool = False,
    allow_nan: bool = False,
) -> NDArray[np.float64]:
    """Validate and copy a 2-D float matrix.

    Parameters
    ----------
    name : str
        Name used in error messages (e.g. ``"G"``).
    value : array_like
        The matrix. A 1-D input is accepted only when one dimension is
        prescribed as 1 or can be inferred unambiguously; otherwise 2-D is required.
    rows, cols : int, optional
        Required number of rows / columns.
    allow_inf : bool
        Whether ``+-inf`` entries are allowed.
    allow_nan : bool
        Whether NaN entries are allowed (e.g. "not measured" in a record).

    Returns
    -------
    ndarray
        A new C-contiguous float64 array of shape ``(rows, cols)``.

    Raises
    ------
    DimensionError
        On a wrong number of dimensions or a wrong shape.
    InvalidValueError
        On NaN, inf, or entries above ``MAX_MAGNITUDE``.
    ArgumentError
        On complex or non-numeric entries.
    """
    a = _to_float(name, value, "matrix")
    if a.ndim == 1 and a.size == 0 and rows is not None and cols is not None:
        a = a.reshape(rows, cols) if rows * cols == 0 else a
    if a.ndim == 1:
        if rows == 1 or (cols is not None and cols == a.size and rows is None):
            a = a.reshape(1, -1)
        elif cols == 1 or (rows is not None and rows == a.size):
            a = a.reshape(-1, 1)
    if a.ndim != 2:
        raise DimensionError(
            f"{name} must be a 2-D matrix, got an array with {a.ndim} dimension(s)"
        )
    if rows is not None and a.shape[0] != rows:
        raise DimensionError(
            f"{name} must have {rows} rows, got {a.shape[0]} (shape {a.shape})"
        )
    if cols is not None and a.shape[1] != cols:
        raise DimensionError(
            f"{name} must have {cols} columns, got {a.shape[1]} (shape {a.shape})"
        )
    _check_finite(name, a, allow_inf, allow_nan)
    return np.ascontiguousarray(a)


def as_vector(
    name: str,
    value: ArrayLike,
    size: int | None = None,
    *,
    allow_inf: bool = False,
    allow_nan: bool = False,
) -> NDArray[np.float64]:
    """Validate and copy a 1-D float vector (a column or row matrix is flattened).

    Raises
    ------
    DimensionError
        On a wrong size or more than one non-singleton dimension.
    InvalidValueError
        On NaN, inf, or entries above ``MAX_MAGNITUDE``.
    ArgumentError
        On complex or non-numeric entries.
    """
    a = _to_float(name, value, "vector")
    if a.ndim == 0:
        a = a.reshape(1)
    elif a.ndim == 2 and 1 in a.shape:
        a = a.reshape(-1)
    if a.ndim != 1:
        raise DimensionError(f"{name} must be a vector, got an array of shape {a.shape}")
    if size is not None and a.size != size:
        raise DimensionError(f"{name} must have length {size}, got {a.size}")
    _check_finite(name, a, allow_inf, allow_nan)
    return a


def as_inputs(p: int, U: ArrayLike | None) -> NDArray[np.float64] | None:
    """A record's known inputs ``U`` as an ``(N, p)`` matrix: required when the system has
    inputs (``p > 0``), refused when it has none (``None`` then).

    Parameters
    ----------
    p : int
        The system's number of known inputs.
    U : array_like or None
        The inputs, one row per sample.

    Raises
    ------
    ArgumentError
        If ``U`` is missing for a system with inputs, or given to one without.
    DimensionError
        If it does not have ``p`` columns.
    """
    if not p:
        if U is not None and np.size(U):
            raise ArgumentError("U is given but the system has no inputs (no Gamma): pass "
                                "U=None, or build the system with its input matrix")
        return None
    if U is None:
        raise ArgumentError(f"U is required: the system has {p} input(s)")
    return as_matrix("U", U, cols=p)
