"""Old path of :mod:`setobs.models.linear` (``LinearSystem``, ``AugmentedSystem``): the
names are re-exported from there."""

from .models.linear import AugmentedSystem, DisturbanceInputs, LinearSystem, require_system

__all__ = ["AugmentedSystem", "DisturbanceInputs", "LinearSystem", "require_system"]
