"""Set-membership disturbance observation: the SMFDO and worst-case-optimal estimates."""

from ..exceptions import SkipLimitError
from .calibrate import NoiseCalibration, NoiseTradeoff, calibrate_noise, noise_tradeoff
from .diagnosis import ModeDiagnosis, diagnose_modes
from .estimates import PointEstimate, chebyshev_center, interval_center
from .nonlinear import NonlinearSetObserver
from .smfdo import (
    SMFDO,
    ExistenceError,
    ModelInvalidatedError,
    ModelInvalidatedWarning,
    SetEstimateResult,
    SetEstimateStep,
    SMFDOResult,
    SMFDOStep,
)

__all__ = [
    "SMFDO",
    "ExistenceError",
    "ModeDiagnosis",
    "ModelInvalidatedError",
    "ModelInvalidatedWarning",
    "NoiseCalibration",
    "NoiseTradeoff",
    "NonlinearSetObserver",
    "PointEstimate",
    "SMFDOResult",
    "SMFDOStep",
    "SetEstimateResult",
    "SetEstimateStep",
    "SkipLimitError",
    "calibrate_noise",
    "chebyshev_center",
    "diagnose_modes",
    "interval_center",
    "noise_tradeoff",
]
