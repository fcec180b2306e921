"""Point observers on one interface (``reset``, ``step``, ``run``), from the seed papers."""

from .base import DesignError, ObserverResult, PointObserver, StateSpaceObserver
from .descriptor import DescriptorObserver
from .luenberger import (
    CHANG2006_PIO_GAINS,
    FU_WANG_HO_GAINS,
    PIO,
    HigherOrderObserver,
    ModularObserver,
    design_higher_order,
    design_pio,
)
from .mbeso import MBESO, VariantMBESO, decoupled_gain, mbeso_impulse_response
from .uio import DelayedUIO

__all__ = [
    "CHANG2006_PIO_GAINS",
    "FU_WANG_HO_GAINS",
    "MBESO",
    "PIO",
    "DelayedUIO",
    "DescriptorObserver",
    "DesignError",
    "HigherOrderObserver",
    "ModularObserver",
    "ObserverResult",
    "PointObserver",
    "StateSpaceObserver",
    "VariantMBESO",
    "decoupled_gain",
    "design_higher_order",
    "design_pio",
    "mbeso_impulse_response",
]
