"""The models: linear systems, the exosystem model of the modular observer, the nonlinear
model of the set estimators, and the interval evaluator of their expressions.

* :class:`LinearSystem` (``x+ = Phi x + Gamma u + G d``, ``y = Xi x + Du u``: Li-Cong-Dong,
  eqs. (2)-(3)) and :class:`AugmentedSystem` (:mod:`.linear`);
* :class:`NonlinearSystem` (``x+ = f(x, w)``, ``w+ = s(w)``, ``y = h(x, w)``: the
  modular-observer paper's eq. (3); :mod:`.exosystem`);
* :class:`NonlinearModel` (``x+ = f(x, u, d)``, ``y = h(x, u, d)``, ``d+ = d + dd``: what
  :class:`setobs.NonlinearSetObserver` takes) with :func:`symbols` and
  :func:`expressions`, the one reader of variables and expressions (:mod:`.nonlinear`);
* :func:`interval_function` (:mod:`.interval`), the outward-rounded interval evaluator.

The old paths ``setobs.systems``, ``setobs.nonlinear`` and ``setobs.interval`` re-export
these names.
"""

from .exosystem import NonlinearSystem
from .interval import IntervalFunction, interval_function
from .linear import AugmentedSystem, DisturbanceInputs, LinearSystem, require_system
from .nonlinear import NonlinearModel, expressions, symbols

__all__ = [
    "AugmentedSystem",
    "DisturbanceInputs",
    "IntervalFunction",
    "LinearSystem",
    "NonlinearModel",
    "NonlinearSystem",
    "expressions",
    "interval_function",
    "require_system",
    "symbols",
]
