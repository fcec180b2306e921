"""The SMFDO's mutable state: what one run has seen and carries from step to step.

:class:`~setobs.SMFDO` holds a frozen :class:`~setobs.setmembership._setup.SMFDOModel`
and one :class:`SMFDOState`; its engines (:mod:`._exact`, :mod:`._windowed`,
:mod:`._recursion`) read both and write only the state, and
:func:`setobs.setmembership._commit.commit` records each step in it.
:meth:`~setobs.SMFDO.reset_state` replaces it by a fresh one (the counters of
:attr:`stats` and the one-time warnings go on).
"""

from __future__ import annotations

import copy
from collections import deque
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from ..exceptions import SkipLimitError
from ..geometry import Box, ConstrainedZonotope
from ..lp.fastlp import LPState
from ._history import HistoryLP
from ._hrep import HState

__all__ = ["Outcome", "SMFDOState"]


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

    Z_src: object
    box: Box
    box_o: Box | None
    Zd: ConstrainedZonotope | None
    box_x: Box | None
    status: str
    depth: int
    entry: object
    blas_small: bool = False
    support: tuple | None = None
    gap: float = 0.0

    def with_posterior(self, Z_src: object) -> Outcome:
        """The same outcome carrying another representation of its posterior."""
        return self._replace(Z_src=Z_src)


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

    def __init__(self, window: int | None, restart_lags: int, tracker: object | None,
                 previous: SMFDOState | None = None) -> None:
        self.k = -1
        # hulls of Z_(k-delta) .. Z_(k-1): the restart boxes of eq. (24)
        # (with the polytope restart also the restart_depth - 1 hulls before, and the
        # inputs entering each of them)
        keep = (window or 1) + restart_lags
        self.hulls: deque[Box] = deque(maxlen=keep)
        self.hull_u: deque[NDArray[np.float64]] = deque(maxlen=keep)
        # beside each hull: the ranges of the restart rows F z over that posterior (its
        # support values, when the window computed them), else None
        self.support: deque[tuple | None] = deque(maxlen=keep)
        # the data (y_j, u_(j-1), dd_(j-1)) since k = 0 (while the recursion still
        # runs from Z_0^-) or of the last delta steps (once the window restarts)
        self.hist: list = []
        # the posterior: a set, an HState, a HistoryLP, or (model, c, b, h, c_err, b_err)
        # of the fast path
        self.Z_src: object = None
        self.from_initial = True  # no reset since k = 0 (the closed forms from Z_0^- apply)
        self.windowing = False  # the window has restarted from a hull at least once
        self.u_pending: NDArray[np.float64] | None = None
        self.states: dict[tuple, LPState] = {}  # LP warm-start states, one per structure
        self.retired_iterations = np.zeros(2, dtype=np.int64)  # (of dropped states)
        self.mask_keys: set[bytes] = set()  # missing-sample patterns with a structure
        self.depth = 0  # recursion steps since the start set of the current posterior
        self.first_inconsistent: int | None = None
        self.last_y = np.zeros(0)  # the last step's measurement (balanced units)
        self.ubar = copy.deepcopy(tracker)  # the unobservable part's tracker
        self.ubar_prev = None  # (the hull of Z_(k-1): the tracker's input)
        self.startup_Z = None  # the start-up's joint set of (z_o, zbar) (see _unobservable)
        self.startup_steps = 0
        self.skipped = 0  # skipped steps since k = 0 (max_skip_fraction)
        self.run_length = 0  # the record length run() is processing (0: update() alone)
        self.auto_poly = True  # restart="auto": the polytope restart is in use
        self.auto_count = 0  # window steps on the fast path
        # steps between its probes (doubling while they agree) and the window step of the
        # next one (0: not yet set, _windowed.AUTO_PROBE)
        self.auto_period = 0
        self.auto_next = 0
        # the polytope restart's support values at every step (probed; None: not decided)
        self.sup_on: bool | None = None
        self.sup_miss = 0  # probes in a row at which they did not pay
        self.set_hulls: dict[int, tuple] = {}  # hulls of the per-step sets it uses
        self.h_fails = 0  # failed conversions to the H-representation in a row
        self.h_retry_at = 0  # first step at which the next conversion is tried
        self.hist_retry_at = 0  # (the same for exact mode's whole-history LP)
        self.box_o_last: Box | None = None  # certified hull of the last posterior
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
        if isinstance(src, HState | HistoryLP):
            return src.to_cz()
        if isinstance(src, tuple):
            model, c, b, h, c_err, b_err = src
            src = model.to_cz(c, b, h, c_err, b_err)
            self.Z_src = src
        return src  # type: ignore[return-value]

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
