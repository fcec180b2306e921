"""setobs: set-membership geometry and disturbance observers for linear discrete-time systems."""

from . import geometry, tolerances
from .exceptions import (
    DimensionError,
    EmptySetError,
    SetobsError,
    SolverError,
    UnboundedSetError,
)
from .geometry import Box, ConstrainedZonotope

__version__ = "0.1.0"

__all__ = [
    "Box",
    "ConstrainedZonotope",
    "DimensionError",
    "EmptySetError",
    "SetobsError",
    "SolverError",
    "UnboundedSetError",
    "__version__",
    "geometry",
    "tolerances",
]
