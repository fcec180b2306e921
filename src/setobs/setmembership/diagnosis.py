"""Set-based fault diagnosis with several models: one set observer per mode (the
nominal plant and one model per fault), a mode excluded once the data are certified
inconsistent with it.

A mode's observer (:class:`~setobs.SMFDO`, with ``on_inconsistent="skip"``) reports a
step inconsistent only when the set of states consistent with the data and that mode's
model is certified empty (its window's or exact LP's phase-1 certificate; a window's set
contains the exact one, so its emptiness proves the exact set empty). So an excluded mode
cannot have produced the record within its stated bounds; the mode that did is never
excluded (the soundness of each observer). Modes that stay consistent are those the
data cannot tell apart: the diagnosis says which faults remain possible, not which one
happened. In the hybrid-zonotope view (:mod:`setobs.geometry.hybrid`) the states
consistent with some mode are the union of the modes' sets, a leaf per mode; excluding a
mode is certifying its leaf empty.
"""

from __future__ import annotations

import dataclasses
import warnings
from collections.abc import Mapping

from numpy.typing import ArrayLike

from ..exceptions import ArgumentError, ModelInvalidatedWarning, SkipLimitError
from .smfdo import SMFDO, SetEstimateResult

__all__ = ["ModeDiagnosis", "diagnose_modes"]


@dataclasses.dataclass(frozen=True)
class ModeDiagnosis:
    """Which modes a record excludes, and when.

    Attributes
    ----------
    excluded : dict
        Mode name -> the first step at which the data were certified inconsistent with it.
    consistent : tuple of str
        The modes never excluded (in the order given).
    results : dict
        Mode name -> the observer's result on the record (``None`` when its run stopped at
        its ``max_skip_fraction``).
    """

    excluded: dict[str, int]
    consistent: tuple[str, ...]
    results: dict[str, SetEstimateResult | None]

    def __repr__(self) -> str:
        ex = ", ".join(f"{k} at step {v}" for k, v in self.excluded.items()) or "none"
        return f"ModeDiagnosis(consistent={list(self.consistent)}, excluded: {ex})"


def diagnose_modes(observers: Mapping[str, SMFDO], Y: ArrayLike, U: ArrayLike | None = None
                   ) -> ModeDiagnosis:
    """Run one set observer per mode on a record and exclude the modes the data are
    certified inconsistent with (the module docstring).

    Parameters
    ----------
    observers : mapping of str to SMFDO
        Per mode its observer, built with ``on_inconsistent="skip"`` (each is reset and
        run on the whole record).
    Y : array_like, shape (N, l)
        The measurements.
    U : array_like, shape (N, p), optional
        The inputs.

    Returns
    -------
    ModeDiagnosis

    Raises
    ------
    ArgumentError
        On no observers, or an observer that does not skip inconsistent samples (it
        would stop at the first one instead of reporting it).
    """
    if not observers:
        raise ArgumentError("diagnose_modes needs at least one mode's observer")
    for name, obs in observers.items():
        if not isinstance(obs, SMFDO):
            raise ArgumentError(f"mode {name!r}: expected an SMFDO, got {type(obs).__name__}")
        if obs.on_inconsistent != "skip":
            raise ArgumentError(f"mode {name!r}: build its observer with on_inconsistent="
                                f"'skip' (it has {obs.on_inconsistent!r})")
    excluded: dict[str, int] = {}
    results: dict[str, SetEstimateResult | None] = {}
    for name, obs in observers.items():
        res: SetEstimateResult | None
        with warnings.catch_warnings():
            # (an excluded mode's inconsistent samples are the finding, not a warning)
            warnings.simplefilter("ignore", ModelInvalidatedWarning)
            try:
                res = obs.run(Y, U)
            except SkipLimitError:
                res = None
        results[name] = res
        first = obs.first_inconsistent
        if first is not None:
            excluded[name] = int(first)
    consistent = tuple(name for name in observers if name not in excluded)
    return ModeDiagnosis(excluded=excluded, consistent=consistent, results=results)

