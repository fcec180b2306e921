"""Point observers on one interface (``reset``, ``step``, ``run``), from the seed papers.

Gain names
----------
Constructor arguments keep each paper's symbols, so a design can be checked
against its paper; the symbols are not shared between observers:

===================================  =============================================================
observer                             gains (multiply the output innovation unless stated)
===================================  =============================================================
:class:`PIO`, :class:`GESO`           ``P`` (n, l) into the state, ``L`` (q, l) into the disturbance
:class:`HigherOrderObserver`         ``P0`` (n, l) into the state, ``L0``, ``L1`` (q, l) into the
                                     disturbance (Fu-Wang eq. (10))
:class:`ModularObserver`             ``L0`` (n, l) of the disturbance-free observer, ``Lw`` (q, l)
                                     of the disturbance observer
:class:`MBESO`, :class:`EHGSO`        ``L`` (n + p, p) on the extended state (from ``omega``)
:class:`DelayedUIO`                  ``K`` on the stacked window ``Y[k:k+tau]`` (eq. (23))
:class:`DescriptorObserver`          ``L`` on the descriptor state (eq. (18)); its ``F`` is the
                                     sensor-noise matrix, not a gain
:class:`NonlinearModularObserver`    ``A0``, ``B0`` and ``Aw``, ``Bw``: the linear dynamics of the
                                     linearizing coordinates (eqs. (30), (34)), not output gains
===================================  =============================================================

``observer.gains`` (and ``ObserverResult.gains``) holds exactly these, keyed
by the symbols above: no covariance, transition matrix, eigenvalue or delay.
A :class:`StateSpaceObserver`'s realisation has role names (``transition``,
``output_gain``, ``input_matrix``, ``disturbance_map``, ``state_map``);
``transition`` is also available on the :class:`DelayedUIO` (its ``J``).
"""

from .base import DesignError, ObserverResult, PointObserver, StateSpaceObserver
from .descriptor import DescriptorObserver
from .luenberger import (
    CHANG2006_PIO_GAINS,
    FU_WANG_HO_GAINS,
    GESO,
    PIO,
    HigherOrderObserver,
    ModularObserver,
    design_higher_order,
    design_pio,
    modular_paper_gains,
)
from .mbeso import (
    EHGSO,
    MBESO,
    VariantMBESO,
    decoupled_gain,
    mbeso_error_bound,
    mbeso_impulse_response,
    mbeso_l1_norm,
)
from .nonlinear import NonlinearModularObserver, NonlinearObserverResult
from .uio import DelayedUIO

__all__ = [
    "CHANG2006_PIO_GAINS",
    "EHGSO",
    "FU_WANG_HO_GAINS",
    "GESO",
    "MBESO",
    "PIO",
    "DelayedUIO",
    "DescriptorObserver",
    "DesignError",
    "HigherOrderObserver",
    "ModularObserver",
    "NonlinearModularObserver",
    "NonlinearObserverResult",
    "ObserverResult",
    "PointObserver",
    "StateSpaceObserver",
    "VariantMBESO",
    "decoupled_gain",
    "design_higher_order",
    "design_pio",
    "mbeso_error_bound",
    "mbeso_impulse_response",
    "mbeso_l1_norm",
    "modular_paper_gains",
]
