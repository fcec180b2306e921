"""Old path of :mod:`setobs.models.exosystem` (``NonlinearSystem``): the name is
re-exported from there; the set estimators' model is :class:`setobs.models.NonlinearModel`."""

from .models.exosystem import NonlinearSystem

__all__ = ["NonlinearSystem"]
