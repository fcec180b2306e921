"""Structural analysis: observability, invariant zeros, relative degrees, existence checks.

The tolerance policy for every rank and zero decision is stated in
:mod:`setobs.tolerances` (balanced data, relative threshold, reported margins).
"""

from ._linalg import RankDecision
from .diagnose import Diagnosis, diagnose
from .existence import (
    BoundedDOReport,
    ErrorPoles,
    ExistenceReport,
    bounded_do_exists,
    fu_wang_eq10_matrix,
    higher_order_conditions,
    higher_order_error_poles,
    ibar,
    modular_conditions,
    pio_conditions,
    pio_error_poles,
)
from .observability import (
    ObservabilityDecomposition,
    ObservabilityReport,
    augmented_observability,
    observability,
    observability_decomposition,
    observability_matrix,
)
from .structure import (
    RelativeDegreeResult,
    UIOReport,
    markov_toeplitz,
    relative_degrees,
    uio_conditions,
    uio_delay,
)
from .zeros import ZerosResult, invariant_zeros, system_zeros

__all__ = [
    "BoundedDOReport",
    "Diagnosis",
    "ErrorPoles",
    "ExistenceReport",
    "ObservabilityDecomposition",
    "ObservabilityReport",
    "RankDecision",
    "RelativeDegreeResult",
    "UIOReport",
    "ZerosResult",
    "augmented_observability",
    "bounded_do_exists",
    "diagnose",
    "fu_wang_eq10_matrix",
    "higher_order_conditions",
    "higher_order_error_poles",
    "ibar",
    "invariant_zeros",
    "markov_toeplitz",
    "modular_conditions",
    "observability",
    "observability_decomposition",
    "observability_matrix",
    "pio_conditions",
    "pio_error_poles",
    "relative_degrees",
    "system_zeros",
    "uio_conditions",
    "uio_delay",
]
