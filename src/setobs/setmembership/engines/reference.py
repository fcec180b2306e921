"""The reference engine of the SMFDO: the set recursion (eqs. (20)-(21)) that always answers.

Every step the other engines decline (or cannot decide: an LP that is not
optimal, data that may contradict the model) is decided here, on constrained
zonotopes with certified hulls, emptiness tests and retries. This engine owns the
``on_inconsistent`` policy: a certified empty posterior raises
:class:`~setobs.ModelInvalidatedError`, drops the measurement (``"skip"``), or
restarts from an inflated box (``"reset"``); and it flags a step whose LP fell
back to a wider certified bound.
"""

from __future__ import annotations

import warnings

import numpy as np

from ...exceptions import EmptySetError, ModelInvalidatedWarning, SolverWarning
from ...geometry import Box, ConstrainedZonotope
from ...geometry.zonotope import hull_with_status
from .._model import Entry, SMFDOModel
from .._recursion import bounds, posterior, prior
from .._schedule import restart_cz, window_hist
from .._state import Outcome, SMFDOState

__all__ = ["ReferenceEngine"]


class ReferenceEngine:
    """The set recursion: prior and posterior (eqs. (20)-(21)) from the last posterior,
    from ``Z_0^-`` at ``k = 0``, or the window's re-run from its restart set
    (eq. (24)); it always answers."""

    def reset(self) -> None:
        """Nothing to forget: the reference engine keeps no books of its own."""

    def try_step(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str, e: Entry) -> Outcome:
        """One step on the set recursion (eqs. (20)-(21), or the window's re-run from
        the restart box): the bounds, and the consistency verdict and status."""
        s.stats["reference"] += 1
        if k == 0:
            Zp: ConstrainedZonotope = m.Z0_prior
            depth = 0
        elif mode == "box":
            # Lines 12-13 / eq. (24): re-run the last delta steps from IH(Z_(k-delta))
            # (cut by the carried-back rows of the polytope restart).
            Z = restart_cz(m, s)
            hist = window_hist(m, s, e)
            for i, ei in enumerate(hist[:-1], start=1):
                Z = posterior(m, prior(m, Z, ei), ei, i)
            Zp = prior(m, Z, e)
            depth = len(hist)
        else:
            Zp = prior(m, s.last_posterior(), e)
            depth = s.depth + 1
        Z = posterior(m, Zp, e, depth)
        status = "ok"
        try:
            Zd, box, box_o, fell_back, box_x = bounds(m, Z)
        except EmptySetError:
            msg = (f"the measurement at step k={k} is inconsistent with the model and the "
                   "uncertainty sets (empty posterior)")
            if m.on_inconsistent == "raise":
                raise m.invalidated(msg, k) from None
            # One-step prior from the last valid posterior (the windowed re-run may
            # pass through the same inconsistency again).
            Zp1 = m.Z0_prior if k == 0 else prior(m, s.last_posterior(), e)
            if m.on_inconsistent == "skip":
                # The measurement is dropped, here and in the window's history.
                e = e.skipped()
                Z = Zp1
                depth = s.depth + 1 if k else 0
                Zd, box, box_o, fell_back, box_x = bounds(m, Z)
                status = "skipped"
            else:
                Z = self._handle_empty(m, k, Zp1, e, msg)
                depth = 0
                Zd, box, box_o, fell_back, box_x = bounds(m, Z)
                # The window restarts from the reset set: eq. (24) is applied again
                # only once delta consistent steps have been collected.
                s.hulls.clear()
                s.hull_u.clear()
                s.support.clear()
                s.hist.clear()
                s.from_initial = False
                s.windowing = False
                status = "reset"
            s.stats[status] += 1
            if s.first_inconsistent is None:
                s.first_inconsistent = k
            if not s.in_run and not s.warned_inconsistent:
                s.warned_inconsistent = True
                warnings.warn(
                    f"{msg}: {'skipped' if status == 'skipped' else 'reset'} "
                    "(status recorded per step; warned once per observer)",
                    ModelInvalidatedWarning, stacklevel=4)
        if fell_back:
            status = "fallback" if status == "ok" else status
            s.stats["fallback"] += 1
            if not s.warned_fallback:
                s.warned_fallback = True
                warnings.warn(
                    f"SMFDO step k={k}: an LP failed under every solver setting; the bounds "
                    "of this step are wider (still certified) and flagged status='fallback' "
                    "(warned once per observer)", SolverWarning, stacklevel=4)
        return Outcome(Z, box, box_o, Zd if m.keep_sets else None, box_x, status, depth, e)

    def _handle_empty(self, m: SMFDOModel, k: int, Zp: ConstrainedZonotope, e: Entry, msg: str):
        """``on_inconsistent="reset"``: the posterior of an inflated box of ``Zp``."""
        try:
            hull, _ = hull_with_status(Zp)
        except EmptySetError:
            raise m.invalidated(msg + " (the prior itself is empty)", k) from None
        w = np.where(np.isfinite(hull.width), hull.width, 0.0)
        scale = 1.0 + float(np.abs(np.where(np.isfinite(hull.lo), hull.lo, 0.0)).max(initial=0.0))
        factor = m.reset_inflation
        for _ in range(40):  # inflate geometrically until the measurement is explainable
            pad = factor * (w + scale)
            Zr = posterior(m, m.box_cz(Box(hull.lo - pad, hull.hi + pad)), e, 0)
            if not Zr.is_empty():
                return Zr
            factor *= 4.0
        raise m.invalidated(msg + " (no reset box explains it)", k)
