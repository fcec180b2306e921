"""Old path of :mod:`setobs.models.interval` (the interval evaluator): the names are
re-exported from there."""

from .models.interval import LIBM_ULPS, IntervalFunction, interval_function

__all__ = ["LIBM_ULPS", "IntervalFunction", "interval_function"]
