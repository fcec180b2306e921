"""Exception hierarchy of :mod:`setobs`.

Every exception derives from :class:`SetobsError`; where a built-in exception
has the same meaning the subclass also derives from it, so that
``except ValueError`` keeps working for bad input.
"""

from __future__ import annotations

from typing import Any

# (The base layer imports nothing above it: the report's type,
# setobs.analysis.existence.BoundedDOReport, is named in the docstring only.)

__all__ = [
    "ArgumentError",
    "DesignError",
    "DesignWarning",
    "DimensionError",
    "DomainError",
    "EmptySetError",
    "ExistenceError",
    "ImmutableError",
    "InternalError",
    "InvalidValueError",
    "MagnitudeError",
    "MissingDataWarning",
    "MissingDependencyError",
    "ModelFileError",
    "ModelInvalidatedError",
    "ModelInvalidatedWarning",
    "NotFoundError",
    "NotSupportedError",
    "RecordNotFoundError",
    "SetobsError",
    "SkipLimitError",
    "SolverError",
    "SolverWarning",
    "UnboundedSetError",
]


class SetobsError(Exception):
    """Base class of all errors raised by :mod:`setobs`."""


class DimensionError(SetobsError, ValueError):
    """An array has the wrong shape, or holds NaN/inf where it must not."""


class InvalidValueError(SetobsError, ValueError):
    """An argument of the right kind has a value the function cannot take (out of its
    range, an unknown option name, inconsistent with another argument)."""


class ArgumentError(SetobsError, TypeError):
    """An argument of the wrong kind (a string where a number is needed, a set where a
    matrix is needed)."""


class NotSupportedError(SetobsError, NotImplementedError):
    """A combination of arguments the library does not implement (the message says
    what to use instead)."""


class ImmutableError(SetobsError, AttributeError):
    """An attempt to change an immutable object (sets, boxes, systems): operations
    return new objects."""


class NotFoundError(SetobsError, KeyError):
    """A name looked up in a report or a table that is not there."""


class MissingDependencyError(SetobsError, ImportError):
    """An optional package a feature needs is not installed (the message names the
    extra to install)."""


class InternalError(SetobsError, RuntimeError):
    """A state the library's own logic should never reach: please report it."""


class MagnitudeError(SetobsError, OverflowError):
    """An operation would build a set whose data (``G``, ``c``, ``A``, ``b``, their
    rounding bounds ``c_err``, ``b_err``, or a finite ``h``) hold NaN, inf, or entries
    above :data:`setobs.tolerances.MAX_MAGNITUDE` in magnitude, where the products of the
    next operation or LP would overflow double precision. The message names the
    operation, the array and the entry; rescale the units (or the matrix) instead.
    """


class DomainError(SetobsError, ValueError):
    """An interval evaluation left a function's domain (``sqrt`` or ``log`` of a box
    reaching below 0, a division by a box holding 0): the message names the
    sub-expression and the box (:mod:`setobs.interval`)."""


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


class DesignError(SetobsError, ValueError):
    """The observer design's existence condition fails for this system.

    Attributes
    ----------
    condition : str
        The condition that failed.
    """

    def __init__(self, message: str, condition: str = "") -> None:
        super().__init__(message)
        self.condition = condition

    def __reduce__(self):
        return (type(self), (str(self), self.condition))


class DesignWarning(RuntimeWarning):
    """The observer design was made, but a diagnostic says not to trust it far: a small
    divisor (near resonance), a nearly singular linear part, or series residuals that
    grow with the truncation order at the points checked."""


class ExistenceError(SetobsError, ValueError):
    """No bounded disturbance observer exists for the system (Theorem 1 fails).

    Attributes
    ----------
    report : setobs.analysis.existence.BoundedDOReport
        The analysis report (ranks, margins, unrecoverable directions).
    """

    def __init__(self, message: str, report: Any) -> None:
        super().__init__(message)
        self.report = report

    def __reduce__(self):
        return (type(self), (str(self), self.report))


class ModelInvalidatedError(SetobsError, RuntimeError):
    """The data are inconsistent with the model: the posterior set is (certified) empty.

    Attributes
    ----------
    step : int
        The time step ``k`` at which the measurement could not be explained.
    """

    #: What a user can do about it, appended to every message (a model with disturbances).
    HINT = ("what to do: if the sample is an outlier or a fault, it is found; if the model "
            "and the record are right, the bounds are too small: calibrate the noise bound "
            "(setobs.calibrate_noise, or `setobs estimate --calibrate`), use a larger "
            "measurement_noise / increment_set, or pass on_inconsistent='skip' (drop such "
            "samples) or 'reset' (restart, losing the guarantee at that step)")
    #: The same for a model without disturbances (state estimation: no increment set).
    HINT_STATE = ("what to do: if the sample is an outlier or a fault, it is found; if the "
                  "model and the record are right, the bounds are too small: calibrate the "
                  "noise bound (setobs.calibrate_noise(..., process_noise=...), or `setobs "
                  "estimate --calibrate --process-noise ...`), use a larger "
                  "measurement_noise / process_noise, or pass on_inconsistent='skip' (drop "
                  "such samples) or 'reset' (restart, losing the guarantee at that step)")

    def __init__(self, message: str, step: int, hint: str | None = None) -> None:
        hint = self.HINT if hint is None else hint
        if hint not in message:
            message = f"{message}; {hint}"
        super().__init__(message)
        self.step = step
        self.hint = hint

    def __reduce__(self):
        return (type(self), (str(self), self.step, self.hint))


class SkipLimitError(ModelInvalidatedError):
    """With ``on_inconsistent="skip"``, more than ``max_skip_fraction`` of the samples
    were skipped: the bounds, not the samples, are wrong (the message says how many)."""


class ModelInvalidatedWarning(RuntimeWarning):
    """Measurements were inconsistent with the model and were skipped, or the
    filter was reset (``on_inconsistent="skip"`` or ``"reset"``)."""


class MissingDataWarning(UserWarning):
    """Most of a record's samples are missing (NaN): the estimator ran, but its bands
    are mostly predictions (:data:`setobs.tolerances.MISSING_WARN_FRACTION`)."""


class ModelFileError(SetobsError, ValueError):
    """A model or record file cannot be read or is inconsistent (one-line message)."""


class RecordNotFoundError(SetobsError, FileNotFoundError):
    """A measured record the package does not ship is not where it was looked for (the
    message says where it comes from and how to point setobs at it)."""
