"""The SMFDO's mutable state: what one run has seen and carries from step to step, and
what an engine answers for a step.

:class:`~setobs.SMFDO` holds a frozen :class:`~setobs.setmembership._model.SMFDOModel`
and one :class:`SMFDOState`; its engines (:mod:`setobs.setmembership.engines`) read
both, keep their own books (each engine's state object), and answer a step with an
:class:`Outcome`, hand it off (:class:`Handoff`) or decline;
:func:`setobs.setmembership._commit.commit` records each answer in the state.
:meth:`~setobs.SMFDO.reset` replaces it by a fresh one (the counters of
:attr:`stats` and the one-time warnings go on) and the engines' books too.
"""

from __future__ import annotations

import copy
from collections import deque
from typing import NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

from ..exceptions import InternalError, SkipLimitError
from ..geometry import Box, ConstrainedZonotope
from ..lp.fastlp import LPState
from ._bounded import BoundedHistory
from ._closed_form import ClosedForm
from ._history import HistoryLP
from ._hrep import HState
from ._model import Entry
from ._unobservable import UnobservableTracker

__all__ = ["Handoff", "Outcome", "Posterior", "Resumes", "SMFDOState"]

#: The carried posterior: a constrained zonotope (the set recursion), exact mode's
#: H-representation or whole-history LP, the closed form's data (a fast window step),
#: or ``None`` before the first step.
Posterior = ConstrainedZonotope | HState | HistoryLP | BoundedHistory | ClosedForm | None


class Outcome(NamedTuple):
    """An engine's answer for one step, before it is committed: the posterior (a set,
    or an engine's own representation of it), the certified hulls of ``P Z``, of
    ``Z`` and of the state, the disturbance set (``keep_sets``), the status, the
    recursion depth the posterior was reached with, the entry as used (a skipped
    step drops its measurement), and whether the step's window was small enough for
    BLAS to stay single-threaded by itself, and (the polytope restart) the certified
    ranges of the restart rows ``F z`` over the posterior (its support values in the
    carried directions, :mod:`._restart`), or ``None``, and the step's gap: the largest
    fraction of a band's width that its bounds may exceed the mode's exact bounds by
    (the window's rounding allowances, exact mode's certification gap)."""

    Z_src: Posterior
    box: Box
    box_o: Box | None
    Zd: ConstrainedZonotope | None
    box_x: Box | None
    status: str
    depth: int
    entry: Entry
    blas_small: bool = False
    support: tuple | None = None
    gap: float = 0.0

    def with_posterior(self, Z_src: Posterior) -> Outcome:
        """The same outcome carrying another representation of its posterior."""
        return self._replace(Z_src=Z_src)

    def with_status(self, status: str) -> Outcome:
        """The same outcome with another status."""
        return self._replace(status=status)


class Resumes(Protocol):
    """An engine that hands steps off: it carries the reference engine's answer on."""

    def resume(self, out: Outcome, handoff: Handoff) -> Outcome:
        """The answer ``out`` to the handed-off step, carried on by the engine."""
        ...


class Handoff(NamedTuple):
    """An engine's hand-off of a step it cannot decide: the loop runs the reference
    engine from ``start`` (the engine's exact posterior as a set), then gives the
    answer back to ``owner.resume`` (which carries its own representation on); if the
    reference engine raises, the state's posterior goes back to ``carried``."""

    owner: Resumes
    start: ConstrainedZonotope
    carried: Posterior


class SMFDOState:
    """Everything a step changes (the window's history and restart hulls, the carried
    posterior, warm-start states, counters and flags).

    Parameters
    ----------
    window : int or None
        The model's window.
    restart_lags : int
        Earlier hulls the polytope restart carries back.
    tracker : object or None
        The model's tracker of the unobservable part (copied: it advances with the data).
    previous : SMFDOState, optional
        The state being replaced (its :attr:`stats` and one-time warnings go on).
    """

    k: int
    hulls: deque[Box]
    hull_u: deque[NDArray[np.float64]]
    support: deque[tuple | None]
    hist: list[Entry]
    Z_src: Posterior
    from_initial: bool
    windowing: bool
    poly_restart: bool
    u_pending: NDArray[np.float64] | None
    states: dict[tuple, LPState]
    retired_iterations: NDArray[np.int64]
    depth: int
    first_inconsistent: int | None
    last_y: NDArray[np.float64]
    ubar: UnobservableTracker | None
    ubar_prev: tuple[NDArray[np.float64], NDArray[np.float64]] | None
    startup_Z: ConstrainedZonotope | None
    startup_steps: int
    skipped: int
    run_length: int
    set_hulls: dict[int, tuple]
    box_o_last: Box | None
    warned_inconsistent: bool
    warned_inexact: bool
    warned_fallback: bool
    in_run: bool
    blas_small: bool
    stats: dict[str, int]

    def __init__(self, window: int | None, restart_lags: int,
                 tracker: UnobservableTracker | None,
                 previous: SMFDOState | None = None) -> None:
        self.k = -1
        # hulls of Z_(k-delta) .. Z_(k-1): the restart boxes of eq. (24)
        # (with the polytope restart also the restart_depth - 1 hulls before, and the
        # inputs entering each of them)
        keep = (window or 1) + restart_lags
        self.hulls = deque(maxlen=keep)
        self.hull_u = deque(maxlen=keep)
        # beside each hull: the ranges of the restart rows F z over that posterior (its
        # support values, when the window computed them), else None
        self.support = deque(maxlen=keep)
        # the data (y_j, u_(j-1), dd_(j-1)) since k = 0 (while the recursion still
        # runs from Z_0^-) or of the last delta steps (once the window restarts)
        self.hist = []
        self.Z_src = None  # (the posterior, :data:`Posterior`)
        self.from_initial = True  # no reset since k = 0 (the closed forms from Z_0^- apply)
        self.windowing = False  # the window has restarted from a hull at least once
        # restart="auto": the polytope restart is in use (the window engine's probes
        # choose; the schedule and the reference engine read it)
        self.poly_restart = True
        self.u_pending = None
        self.states = {}  # LP warm-start states, one per structure
        self.retired_iterations = np.zeros(2, dtype=np.int64)  # (of dropped states)
        self.depth = 0  # recursion steps since the start set of the current posterior
        self.first_inconsistent = None
        self.last_y = np.zeros(0)  # the last step's measurement (balanced units)
        self.ubar = copy.deepcopy(tracker)  # the unobservable part's tracker
        self.ubar_prev = None  # (the hull of Z_(k-1): the tracker's input)
        self.startup_Z = None  # the start-up's joint set of (z_o, zbar) (see _unobservable)
        self.startup_steps = 0
        self.skipped = 0  # skipped steps since k = 0 (max_skip_fraction)
        self.run_length = 0  # the record length run() is processing (0: update() alone)
        self.set_hulls = {}  # hulls of the per-step sets it uses
        self.box_o_last = None  # certified hull of the last posterior
        self.warned_inconsistent = False
        self.warned_inexact = False
        self.in_run = False
        self.blas_small = False  # the last step's window is small (see SMFDO.update)
        if previous is None:
            self.stats = {"fast": 0, "reference": 0, "fallback": 0, "skipped": 0, "reset": 0,
                          "mask_reference": 0, "polytope_restarts": 0, "support_restarts": 0}
            self.warned_fallback = False
        else:
            self.stats = previous.stats
            self.warned_fallback = previous.warned_fallback

    def posterior(self) -> ConstrainedZonotope | None:
        """The carried posterior as a constrained zonotope (a fast-path step's set is
        built from its closed form on first access, and kept)."""
        src = self.Z_src
        if isinstance(src, HState | HistoryLP | BoundedHistory):
            return src.to_cz()
        if isinstance(src, ClosedForm):
            Z = src.to_cz()
            self.Z_src = Z
            return Z
        return src

    def last_posterior(self) -> ConstrainedZonotope:
        """:meth:`posterior`, which a step after the first has."""
        Z = self.posterior()
        if Z is None:
            raise InternalError(f"step {self.k + 1} has no posterior of step {self.k} to go on "
                                "from")
        return Z

    def count_skip(self, k: int, max_skip_fraction: float) -> None:
        """Count a skipped step; stop once more than ``max_skip_fraction`` of the
        samples (of the record being run, else of the steps so far; at least
        ``1 / max_skip_fraction`` samples, so that one outlier of a short record may
        be skipped) were skipped."""
        self.skipped += 1
        f = max_skip_fraction
        total = self.run_length or k + 1
        if f > 0:
            total = max(total, int(np.ceil(1.0 / f)))
        if self.skipped > f * total:
            raise SkipLimitError(
                f"{self.skipped} of the {k + 1} samples so far were skipped as inconsistent "
                f"(more than max_skip_fraction = {100 * f:g} % of {total} samples; the "
                f"first at step {self.first_inconsistent}): so many samples contradict the "
                "model that the bounds, not the samples, are wrong", k,
                "what to do: calibrate the noise bound (setobs.calibrate_noise, or `setobs "
                "estimate --calibrate`; max_outliers= names the samples that raise it most, "
                "run(ignore=) leaves them out), use larger bounds, or, if these samples "
                "really are outliers, a larger max_skip_fraction")

    def retire_states(self) -> None:
        """Drop the LP warm-start states (keeping their iteration counts)."""
        for st in self.states.values():
            self.retired_iterations += st.iters
        self.states.clear()

    def iterations(self) -> tuple[int, int]:
        """Simplex iterations so far, ``(primal, dual)``, of every warm-start state."""
        tot = self.retired_iterations.copy()
        for st in self.states.values():
            tot += st.iters
        return int(tot[0]), int(tot[1])
