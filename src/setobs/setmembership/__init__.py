"""Set-membership disturbance observation: the SMFDO and worst-case-optimal estimates."""

from .estimates import PointEstimate, chebyshev_center, interval_center
from .smfdo import (
    SMFDO,
    ExistenceError,
    ModelInvalidatedError,
    ModelInvalidatedWarning,
    SMFDOResult,
    SMFDOStep,
)

__all__ = [
    "SMFDO",
    "ExistenceError",
    "ModelInvalidatedError",
    "ModelInvalidatedWarning",
    "PointEstimate",
    "SMFDOResult",
    "SMFDOStep",
    "chebyshev_center",
    "interval_center",
]
