"""Exception hierarchy of :mod:`setobs`.

Every exception derives from :class:`SetobsError`; where a built-in exception
has the same meaning the subclass also derives from it, so that
``except ValueError`` keeps working for bad input.
"""

from __future__ import annotations

__all__ = [
    "DimensionError",
    "EmptySetError",
    "SetobsError",
    "SolverError",
    "SolverWarning",
    "UnboundedSetError",
]


class SetobsError(Exception):
    """Base class of all errors raised by :mod:`setobs`."""


class DimensionError(SetobsError, ValueError):
    """An array has the wrong shape, or holds NaN/inf where it must not."""


class EmptySetError(SetobsError, ValueError):
    """An operation that needs a non-empty set was given a (certified) empty set."""


class UnboundedSetError(SetobsError, ValueError):
    """An operation that needs a bounded set was given an unbounded one."""


class SolverError(SetobsError, RuntimeError):
    """A numerical solver did not reach a usable, verified status.

    Attributes
    ----------
    status : str
        The solver's own status string.
    """

    def __init__(self, message: str, status: str = "") -> None:
        super().__init__(message)
        self.status = status

    def __reduce__(self):
        return (type(self), (str(self), self.status))


class SolverWarning(RuntimeWarning):
    """A solver failed on every retry and a wider certified outer answer was returned.

    The answer is still a guaranteed outer bound (it may be ``+-inf``); only its
    tightness was lost.
    """
