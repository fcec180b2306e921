"""setobs: set-membership geometry and disturbance observers for linear discrete-time systems."""

from . import (
    analysis,
    compare,
    examples,
    geometry,
    observers,
    plotting,
    setmembership,
    studies,
    tolerances,
)
from .exceptions import (
    DesignError,
    DesignWarning,
    DimensionError,
    EmptySetError,
    ExistenceError,
    MagnitudeError,
    MissingDataWarning,
    ModelFileError,
    ModelInvalidatedError,
    ModelInvalidatedWarning,
    SetobsError,
    SolverError,
    SolverWarning,
    UnboundedSetError,
)
from .geometry import Box, ConstrainedZonotope
from .nonlinear import NonlinearSystem
from .setmembership import SMFDO, calibrate_noise, noise_tradeoff
from .systems import LinearSystem

__version__ = "0.1.0"

__all__ = [
    "SMFDO",
    "Box",
    "ConstrainedZonotope",
    "DesignError",
    "DesignWarning",
    "DimensionError",
    "EmptySetError",
    "ExistenceError",
    "LinearSystem",
    "MagnitudeError",
    "MissingDataWarning",
    "ModelFileError",
    "ModelInvalidatedError",
    "ModelInvalidatedWarning",
    "NonlinearSystem",
    "SetobsError",
    "SolverError",
    "SolverWarning",
    "UnboundedSetError",
    "__version__",
    "analysis",
    "calibrate_noise",
    "compare",
    "examples",
    "geometry",
    "noise_tradeoff",
    "observers",
    "plotting",
    "setmembership",
    "studies",
    "tolerances",
]
