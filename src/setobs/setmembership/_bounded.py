"""Exact mode with noise over a bounded history: the whole-history LP cut to its last
``L`` steps, with a certified bracket that says when the cut costs nothing.

The whole-history LP (:mod:`._history`) grows by a block per step, and so does its
cost. :class:`BoundedHistory` keeps it only until a cut pays, then solves two LPs over
the last ``L`` steps ``s .. k`` (the same rows as the whole-history LP's, eqs.
(20)-(21) of the SMFDO with noise written step by step), which differ in the first
state ``z_s``:

* the **outer** LP: ``z_s`` in its certified hull ``B_s`` (the bounds this class
  reported at step ``s``) and in the *cuts* that replace the removed steps
  (:meth:`~._history.HistoryLP.drop_oldest`: per objective, the removed rows
  aggregated by that objective's certified multiplier, the removed variables at their
  worst in their boxes; with the objective's own multiplier the cut keeps its bound,
  so a cut LP starts where the longer one stood);
* the **inner** LP: ``z_s`` in the convex hull of points ``P_s``, each the state at
  ``s`` of a history consistent with the data.

Proof (soundness, and what "exact" means)
-----------------------------------------
Let ``X_j`` be the exact posterior (the projection on ``z_j`` of the histories from
the start set consistent with the data up to ``j``).

1. *Outer.* By induction ``X_s`` is inside ``B_s``: the bounds reported at step ``s``
   are certified outer bounds of the LP that step solved, whose feasible set
   contains every consistent history (by the induction hypothesis at its own first
   state; at the start, the whole-history LP is exact). A history consistent with the
   data up to ``k`` restricted to ``s .. k`` satisfies the cut LP's rows and has
   ``z_s`` in ``X_s``, so in ``B_s``; it satisfies every cut, each an aggregate (weak
   duality) of rows it satisfied and boxes it lay in before they were
   removed, with every product's rounding taken off the cut's right-hand side; the
   implied bounds of the later states contain the prior of the previous certified
   hull, so they cut none of these histories.
   So the outer LP's minimum of ``w^T z_k`` is at most the exact one, and its
   certified lower bound (:mod:`setobs.lp.certificate`) is a sound bound: **the
   reported bounds contain the exact set whatever the cut.**
2. *Inner.* A point of ``P_s`` is the state at ``s`` of a consistent history; the set
   of consistent histories is convex (linear rows, boxes), so a convex combination of
   such points is the state of the combined history, and any solution of the inner LP
   extends to a history consistent with the data up to ``k``. The inner LP's optimal
   histories are therefore consistent histories (to the solver's tolerance), and
   their states at ``s + 1 .. k`` are the next points (``P_(s+1)`` ...): the
   induction that the points stay feasible. At the first cut the points come from
   the whole-history LP's own optima (consistent histories).
3. *Bracket.* The exact minimum lies between the outer LP's certified bound and the
   inner LP's value at its solver's point (the minimum plus the certified gap of
   :meth:`setobs.lp.boxlp.BoxLP.minimize_all`, which also charges the point's row
   residual). A band's gap is the sum of its two ends' brackets; the step is called
   exact (``"ok"``) only when every band's gap is within ``EXACT_RTOL`` of its width,
   as for the whole-history LP's certificate gap.

The history length ``L`` is chosen per step: after a step whose largest gap fraction
is at most :data:`DROP_FRACTION` of the tolerance the oldest step is dropped (``L``
stays), at most :data:`DROP_FRACTION` cubed two are dropped (``L`` shrinks), else
none (``L`` grows by one: the fallback, toward the whole history). The inner LP drops
its oldest steps only on a closed bracket and keeps at least :data:`INNER_HISTORY`
steps; the outer LP keeps at least as many as the inner one. The first cut is tried
once the whole-history LP has :data:`CUT_ROWS` rows (:data:`CUT_START` steps deep, each
later try :data:`CUT_RETRY` deeper): its two LPs are solved beside the whole-history
LP, which decides those steps, and the whole history is dropped only after
:data:`TRIAL_STEPS` closed brackets (at the cut's own step the bracket closes by
construction, so that step proves nothing); a step the whole-history LP itself leaves
inexact puts the try off to the next step.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..exceptions import InternalError
from ..tolerances import EXACT_RTOL
from ._closed_form import allowance_fraction
from ._history import HistoryLP

__all__ = ["BOUNDED", "CUT_RETRY", "CUT_ROWS", "CUT_START", "DROP_FRACTION", "INNER_HISTORY",
           "MIN_HISTORY", "POINT_BATCHES", "TRIAL_STEPS", "BoundedHistory"]

#: Steps of history the first cut keeps: tried (on copies, the whole-history LP deciding
#: the step) once it drops :data:`CUT_RETRY` steps.
CUT_START = 20

#: Rows the whole-history LP has before a first cut is tried: below, its cost is small
#: and the whole history is kept (exact by its certificate alone). The 30-tank cascade
#: with 21 outputs passes it at about step 20, a 4-state plant with 2 outputs at about
#: step 170.
CUT_ROWS = 1000

#: Steps between two tries of the first cut when one did not close its bracket (the
#: history then longer by as many steps).
CUT_RETRY = 10

#: A step whose largest gap fraction is at most this times ``EXACT_RTOL`` drops the
#: oldest step before the next one (at most its cube: two steps).
DROP_FRACTION = 0.25

#: Steps on which a first cut's bracket must close (its LPs solved beside the
#: whole-history LP, which decides those steps) before the whole history is dropped. At
#: the step a cut is made its bracket closes by construction (the cuts carry that step's
#: multipliers, the points are that step's optima), so that step proves nothing.
TRIAL_STEPS = 3

#: Fewest steps of history kept.
MIN_HISTORY = 2

#: Whether exact mode with noise cuts its history (:class:`BoundedHistory`) or keeps
#: the whole-history LP (:class:`~._history.HistoryLP`) for the whole record. A cut
#: history can end a step "inexact" where the whole one is exact: on the 4-state plant of
#: tests/setmembership/test_bounded_history.py with its first cut forced at step 13 and
#: a missing sample, the bracket opened to 2.7e-6 of a band's width on a step after the
#: cut (development runs, not in a results file); :data:`CUT_ROWS` keeps short records
#: of small plants whole.
BOUNDED = True

#: Steps of history the inner LP keeps (the outer LP keeps at least as many). On the
#: 30-tank cascade with 21 outputs, 20 steps left the inner LP's deficit at about 1e-7
#: of the width, and 10 steps above the tolerance (development runs, not in a results
#: file).
INNER_HISTORY = 20

#: The inner LP's points at a state: those of the inner LPs' optima of the last this
#: many steps (each step gives one point per objective).
POINT_BATCHES = 4


class BoundedHistory:
    """Exact mode's LP over a bounded history (the module docstring: the outer and
    inner cut LPs and the proof).

    Parameters
    ----------
    whole : HistoryLP
        The whole-history LP from the start posterior, with its hull at the start step.
    margin : float
        The reported outward margin (for the gap fractions).
    rows : ndarray or None
        The reported bands (:attr:`~._model.SMFDOModel.reported_rows`).
    """

    def __init__(self, whole: HistoryLP, margin: float, rows=None) -> None:
        self.whole: HistoryLP | None = whole
        self.outer: HistoryLP | None = None
        self.inner: HistoryLP | None = None
        self.margin, self.rows = margin, rows
        self.k = 0  # (steps since the start: the newest state's index)
        self.first = 0  # (the index of the outer LP's first state)
        self.inner_first = 0  # (and of the inner LP's)
        if whole.box is None:
            raise InternalError("BoundedHistory needs the whole-history LP with its hull at "
                                "the start step (HistoryLP.box is None); this is a bug in "
                                "setobs, please report it")
        self.boxes: dict[int, tuple[NDArray[np.float64], NDArray[np.float64]]] = {
            0: whole.box}
        self.points: dict[int, list[NDArray[np.float64]]] = {}
        self.gaps = np.zeros(0)
        self.try_length = CUT_START
        self.next_try = CUT_START + CUT_RETRY
        #: a first cut on trial: its outer and inner LPs and the steps its bracket closed
        self.trial: tuple[HistoryLP, HistoryLP, int] | None = None

    # ------------------------------------------------------------------ the interface
    @property
    def active(self) -> HistoryLP:
        """The LP whose bounds are reported (the whole history, or the outer cut)."""
        H = self.whole if self.whole is not None else self.outer
        assert H is not None
        return H

    @property
    def cut(self) -> bool:
        """Whether the history is cut (the bounds are the outer LP's)."""
        return self.whole is None

    @property
    def box(self):
        """The last certified hull of the newest state."""
        return self.active.box

    @box.setter
    def box(self, value) -> None:
        for H in self._lps():
            H.box = value
        self.boxes[self.k] = value

    @property
    def length(self) -> int:
        """Steps of history the reported LP holds (:attr:`HistoryLP.length`)."""
        return self.active.length

    @property
    def steps(self) -> int:
        """Steps pushed since the start."""
        return self.k

    @property
    def retries(self) -> int:
        """Solves that were not optimal with a tight certificate."""
        return sum(H.retries for H in self._lps())

    @property
    def state_columns(self) -> NDArray[np.int64]:
        """The newest state's columns in the reported LP."""
        return self.active.state_columns

    def lp(self):
        """The reported LP (:meth:`HistoryLP.lp`)."""
        return self.active.lp()

    def to_cz(self):
        """The reported LP's posterior as a constrained zonotope (the exact set's, or
        with a cut a set that contains it: :meth:`HistoryLP.to_cz`)."""
        return self.active.to_cz()

    def _lps(self) -> list[HistoryLP]:
        out = [H for H in (self.whole, self.outer, self.inner) if H is not None]
        return out + list(self.trial[:2]) if self.trial is not None else out

    def push(self, e) -> None:
        """Add the step of entry ``e`` to the LPs."""
        box = self.active.box  # (the implied bounds: the reported certified hull's)
        for H in self._lps():
            H.box = box
            H.push(e)
        self.k += 1

    def pop(self) -> None:
        """Undo the last :meth:`push`."""
        for H in self._lps():
            H.pop()
        self.boxes.pop(self.k, None)
        self.points.pop(self.k, None)
        self.k -= 1

    # ------------------------------------------------------------------ solving
    def hull(self) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """Certified bounds of the newest state and of the objective rows (the whole
        history's, or the outer cut's with the bracket in :attr:`gaps`), or ``None``
        when the reported LP's solve is not optimal with a tight certificate."""
        if self.whole is not None:
            return self._whole_hull(self.whole)
        return self._cut_hull()

    def _whole_hull(self, H: HistoryLP):
        H.box_lp.record = H.state_cols()
        due = self.k >= self.next_try and H.box_lp.n_row >= CUT_ROWS
        H.box_lp.keep_duals = due
        out = H.hull()
        if out is None:
            return None
        self.gaps = H.gaps
        if H.box is not None:
            self.boxes[self.k] = H.box
        self._keep_points(H, self.k - self.try_length - CUT_RETRY)
        if self.trial is not None:
            self._judge_trial()
        elif due and self._fraction(out, H.gaps) > EXACT_RTOL:
            # (the whole-history LP's own certificate gap is open, and a cut's bracket
            # cannot close where the uncut LP's does not in practice: the next step)
            self.next_try = self.k + 1
        elif due:
            self._try_cut(H)
        return out

    def _judge_trial(self) -> None:
        """Solve the first cut on trial; drop the whole history after
        :data:`TRIAL_STEPS` closed brackets, give the cut up at an open one."""
        assert self.trial is not None
        O, I, closed = self.trial
        got = O.hull()
        gaps = None if got is None else self._bracket(O, I, got)
        if gaps is None or self._fraction(got, gaps) > DROP_FRACTION * EXACT_RTOL:
            self.trial = None
            self.first = self.inner_first = 0
            return
        if closed + 1 < TRIAL_STEPS:
            self.trial = (O, I, closed + 1)
            return
        self.trial = None
        self.whole, self.outer, self.inner = None, O, I
        self._forget()

    def _cut_hull(self):
        O, I = self.outer, self.inner
        assert O is not None and I is not None
        out = O.hull()
        if out is None:
            return None
        self.boxes[self.k] = O.box
        got = self._bracket(O, I, out)
        if got is None:
            self.gaps = np.full(out[0].size, np.inf)
            return out
        self.gaps = got
        frac = self._fraction(out, got)
        limit = DROP_FRACTION * EXACT_RTOL
        want = 2 if frac <= limit * DROP_FRACTION ** 2 else 1 if frac <= limit else 0
        # (the inner LP first, to INNER_HISTORY at the fewest: an open bracket grows both)
        for _ in range(want):
            if I.length <= INNER_HISTORY or not self._drop_inner(I):
                break
        drops = min(want, O.length - max(MIN_HISTORY, I.length))
        if drops > 0:
            j = self.first + drops
            O.drop_oldest(*self.boxes[j], duals=O.box_lp.last_duals, count=drops)
            self.first = j
        self._forget()
        return out

    def _fraction(self, out, gaps: NDArray[np.float64]) -> float:
        """The largest gap as a fraction of its band's width (as the step's status reads
        it: :func:`~._closed_form.allowance_fraction`)."""
        lo, hi = out
        return allowance_fraction(lo, hi, gaps, self.margin, self.rows)

    def _bracket(self, O: HistoryLP, I: HistoryLP, out) -> NDArray[np.float64] | None:
        """The bands' gaps between the outer bounds ``out`` and the inner LP's values
        (``None`` when the inner LP is not solved): its points kept for later cuts."""
        I.box_lp.record = I.state_cols()
        got = I.hull()
        if got is None:
            return None
        g = I.box_lp.last_gaps
        lo_in = got[0] + g[0::2]  # (a consistent history's value at the minimum)
        hi_in = got[1] - g[1::2]
        self._keep_points(I, self.inner_first + 1)
        lo, hi = out
        return np.maximum(lo_in - lo, 0.0) + np.maximum(hi - hi_in, 0.0)

    def _keep_points(self, H: HistoryLP, first: int) -> None:
        """The states of the last solves' optimal histories (``H``'s points, its states
        from ``first`` on) as points of those states (:data:`POINT_BATCHES` kept)."""
        pts = H.box_lp.last_points
        if pts.size == 0 or not np.isfinite(pts).all():
            return
        N = H.N
        n_states = pts.shape[1] // N
        base = self.k - n_states + 1
        for i in range(max(0, first - base), n_states):
            batch = self.points.setdefault(base + i, [])
            batch.append(pts[:, i * N:(i + 1) * N])
            del batch[:-POINT_BATCHES]
        for j in [j for j in self.points if j < first]:
            del self.points[j]

    def _hull_points(self, j: int) -> NDArray[np.float64] | None:
        got = self.points.get(j)
        if not got:
            return None
        return np.unique(np.vstack(got), axis=0)

    # ------------------------------------------------------------------ cutting
    def _try_cut(self, H: HistoryLP) -> None:
        """Put a first cut on trial: copies of the whole-history LP cut to
        ``L`` = :data:`CUT_START` steps (each later try :data:`CUT_RETRY` deeper), judged
        on the next :data:`TRIAL_STEPS` steps (:meth:`_judge_trial`)."""
        self.next_try = self.k + CUT_RETRY + TRIAL_STEPS
        s = self.k - self.try_length
        si = max(s, self.k - INNER_HISTORY)
        P = self._hull_points(si)
        self.try_length += CUT_RETRY
        duals = H.box_lp.last_duals
        if P is None or s < 1 or duals.size == 0:
            return
        O, I = H.clone(), H.clone()
        O.drop_oldest(*self.boxes[s], duals=duals, count=s)
        O.box_lp.keep_duals = True
        I.drop_oldest(*self.boxes[si], count=si)
        I.attach_hull(P)
        self.first, self.inner_first = s, si
        self.trial = (O, I, 0)

    def _drop_inner(self, I: HistoryLP) -> bool:
        """Drop the inner LP's oldest step (its next state in the hull of its points);
        ``False`` when that state has no points yet."""
        j = self.inner_first + 1
        P = self._hull_points(j)
        if P is None:
            return False
        I.drop_oldest(*self.boxes[j])
        I.attach_hull(P)
        self.inner_first = j
        return True

    def _forget(self) -> None:
        for j in [j for j in self.boxes if j < min(self.first, self.inner_first)]:
            del self.boxes[j]
        for j in [j for j in self.points if j < self.inner_first]:
            del self.points[j]
