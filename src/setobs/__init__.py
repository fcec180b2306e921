"""setobs: set-membership geometry and disturbance observers for linear discrete-time systems."""

from . import analysis, examples, geometry, tolerances
from .exceptions import (
    DimensionError,
    EmptySetError,
    SetobsError,
    SolverError,
    UnboundedSetError,
)
from .geometry import Box, ConstrainedZonotope
from .systems import LinearSystem

__version__ = "0.1.0"

__all__ = [
    "Box",
    "ConstrainedZonotope",
    "DimensionError",
    "EmptySetError",
    "LinearSystem",
    "SetobsError",
    "SolverError",
    "UnboundedSetError",
    "__version__",
    "analysis",
    "examples",
    "geometry",
    "tolerances",
]
