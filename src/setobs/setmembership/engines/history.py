"""Exact mode's engine with noise: the whole-history LP (:mod:`.._history`), grown by one
block per step and certified by the one certificate."""

from __future__ import annotations

import numpy as np

from ...exceptions import SetobsError
from ...geometry.reduction import reduce_exact
from ...tolerances import EXACT_RTOL
from .. import _bounded
from .._bounded import BoundedHistory
from .._closed_form import allowance_fraction
from .._history import HistoryLP
from .._model import Entry, SMFDOModel
from .._state import Handoff, Outcome, SMFDOState

__all__ = ["HISTORY_RETRY", "HistoryEngine"]

#: Steps after a failed start of exact mode's whole-history LP (an unbounded
#: posterior, or free factors that could not be eliminated) before the next try.
HISTORY_RETRY = 4


class HistoryEngine:
    """Exact mode with noise: the whole-history LP, grown by one block per step; it
    declines (``None``) until the posterior is bounded, and hands a step it cannot
    decide (an infeasible LP: the data may contradict the model; a numerical failure)
    off to the reference engine (a :class:`~.._state.Handoff`: the loop runs that from
    the exact posterior), then goes on with the step as that decided it
    (:meth:`resume`)."""

    def __init__(self) -> None:
        #: first step at which a failed start is tried again (:data:`HISTORY_RETRY`)
        self.retry_at = 0

    def reset(self) -> None:
        """Forget the back-off (a new run)."""
        self.retry_at = 0

    def try_step(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str,
                 e: Entry) -> Outcome | Handoff | None:
        """The step's :class:`~.._state.Outcome` on the whole-history LP, a hand-off, or
        ``None``."""
        if k == 0:
            return None
        H = s.Z_src
        if not isinstance(H, HistoryLP | BoundedHistory):
            H = self._start(m, s, k)
            if H is None:
                return None
        H.push(e)
        out = H.hull()
        if out is None:
            H.pop()
            return Handoff(self, H.to_cz(), H)
        box_o, box, box_x, _ = m.split_hull(*out)
        s.stats["fast"] += 1
        # "ok" only when every band is certified within EXACT_RTOL of its width of the
        # whole-history set (the multipliers refined from the basis where the solver's
        # left a gap: lp.boxlp.BoxLP.refined_multiplier); else "inexact", with the gap
        gap = allowance_fraction(*out, H.gaps, m.margin, m.reported_rows)
        return Outcome(H, box, box_o, None, box_x, "inexact" if gap > EXACT_RTOL else "ok",
                       0, e, gap=gap)

    def _start(self, m: SMFDOModel, s: SMFDOState, k: int
               ) -> HistoryLP | BoundedHistory | None:
        """Exact mode's whole-history LP from the current posterior, once it is
        bounded; ``None`` before (the set recursion goes on)."""
        box = s.box_o_last
        if k < self.retry_at or box is None or not (
                np.isfinite(box.lo).all() and np.isfinite(box.hi).all()):
            return None
        Z = s.posterior()
        if Z is None:
            return None
        H: HistoryLP | None
        try:
            if np.isinf(Z.h).any():  # (X0 = R^n: its factors pivoted out, exactly)
                Z = reduce_exact(Z)
            H = HistoryLP.start(Z, box.lo, box.hi, A_o=m.A_o, Gamma_o=m.Gamma_o, C_o=m.C_o,
                                B_o=m.B_o, E_o=m.E_o, rows=m.hull_rows, data_rtol=m.data_rtol)
        except SetobsError:
            H = None
        if H is None:
            self.retry_at = k + HISTORY_RETRY
            return None
        if _bounded.BOUNDED:
            return BoundedHistory(H, m.margin, m.reported_rows)
        return H

    @staticmethod
    def resume(out: Outcome, handoff: Handoff) -> Outcome:
        """The reference engine's answer to a handed-off step, with the history going on:
        the step as that decided it (a skipped step's measurement dropped) pushed onto the
        carried LP, whose box is the step's certified hull; a reset (or an unbounded hull)
        leaves the set recursion's posterior to carry on.

        Parameters
        ----------
        out : Outcome
            The reference engine's answer.
        handoff : Handoff
            This engine's hand-off (its carried whole-history LP).
        """
        H = handoff.carried
        box = out.box_o
        if isinstance(H, HistoryLP | BoundedHistory) \
                and out.status in ("ok", "inexact", "fallback", "skipped") \
                and box is not None and np.isfinite(box.lo).all() \
                and np.isfinite(box.hi).all():
            H.push(out.entry)
            H.box = (box.lo.copy(), box.hi.copy())
            if isinstance(H, BoundedHistory) and H.cut and out.status == "ok":
                # (decided from the outer cut's set, which contains the exact one: the
                # bounds are sound but not certified exact)
                out = out.with_status("inexact")
            return out.with_posterior(H)
        return out
