"""The SMFDO's arguments made sets: the window, uncertainty and noise sets (validated),
and the scaling of unbounded factors."""

from __future__ import annotations

import numbers

import numpy as np

from .._rounding import pow2_inverse
from .._validation import as_vector, check_real_scalar
from ..exceptions import ArgumentError, DimensionError, InvalidValueError
from ..geometry import Box, ConstrainedZonotope
from ..geometry.zonotope import trusted_cz

__all__ = ["as_set", "check_window", "noise_set", "normalize_free_columns"]


def check_window(window: object) -> int | None:
    """``window`` validated: a positive integer, or ``None`` (exact mode)."""
    if window is None:
        return None
    if isinstance(window, bool | np.bool_) or not isinstance(window, numbers.Real):
        raise ArgumentError(f"window must be a positive integer or None (exact mode), "
                            f"got {window!r}")
    w = float(window)
    if not np.isfinite(w) or w != int(w) or w < 1:
        raise InvalidValueError(f"window must be a positive integer or None (exact mode), "
                                f"got {window!r}")
    return int(w)


def as_set(name: str, value: object, dim: int) -> ConstrainedZonotope | None:
    """A ConstrainedZonotope from a CZ, a Box, or None; anything else is refused."""
    if value is None:
        return None
    if isinstance(value, Box):
        value = ConstrainedZonotope.from_box(value.lo, value.hi)
    if not isinstance(value, ConstrainedZonotope):
        raise ArgumentError(
            f"{name} must be a ConstrainedZonotope or a Box (e.g. Box(lo, hi)), got "
            f"{type(value).__name__}")
    if value.dim != dim:
        raise DimensionError(f"{name} must have dimension {dim}, got {value.dim}")
    return value


def noise_set(name: str, value: object, dim: int) -> ConstrainedZonotope | None:
    """A bounded noise set from a CZ, a Box, per-channel radii (a vector, or a scalar
    for every channel), or None (no noise)."""
    if value is None:
        return None
    if isinstance(value, Box | ConstrainedZonotope):
        Z = as_set(name, value, dim)
        if Z is None or not Z.is_bounded:
            raise InvalidValueError(
                f"{name} must be bounded (an output that is not measured at a step is "
                "NaN in Y, not unbounded noise)")
        return Z
    if isinstance(value, str | bytes) or callable(value):
        raise ArgumentError(f"{name} must be a ConstrainedZonotope, a Box, per-channel radii "
                            f"or a callable k -> set, got {type(value).__name__}")
    r = np.asarray(value)
    if r.ndim == 0:
        r = np.full(dim, check_real_scalar(name, value, nonnegative=True))
    r = as_vector(name, r, size=dim)
    if (r < 0).any():
        raise InvalidValueError(f"{name} radii must be nonnegative, got {r}")
    return ConstrainedZonotope.from_box(-r, r)


def normalize_free_columns(Z: ConstrainedZonotope) -> ConstrainedZonotope:
    """The same set with every unbounded factor's column ``[G; A]`` scaled to unit norm.

    An unbounded factor's scale is arbitrary (``h = inf``), but it sets the
    conditioning of every LP over the set: ``R^n`` mapped into balanced
    coordinates has columns of norms from ``1e-4`` to ``1e4`` on badly scaled
    models. Powers of two keep the scaling exact.
    """
    free = np.isinf(Z.h)
    if not free.any():
        return Z
    norms = np.linalg.norm(np.vstack([Z.G, Z.A]), axis=0)
    s = np.where(free, pow2_inverse(norms), 1.0)
    return trusted_cz(Z.G * s, Z.c, Z.A * s, Z.b, Z.h, Z.unbounded_radius, Z.c_err, Z.b_err)
