"""The set-membership filter-based disturbance observer (Li-Cong-Dong, Algorithm 1).

:class:`SMFDO` holds a frozen model (:class:`._model.SMFDOModel`, built by
:func:`._model.build_model` from the validated :class:`._model.SMFDOOptions`), a mutable
state (:class:`._state.SMFDOState`) and its engines (:mod:`.engines`, one per file, each
with its own books), each of which answers a step, hands it off or declines: the
H-representation recursion (:mod:`.engines.hrep`) and the whole-history LP
(:mod:`.engines.history`) of exact mode, the window's closed form
(:mod:`.engines.window`, its schedule in :mod:`._schedule`), and the reference set
recursion of eqs. (20)-(21) (:mod:`._recursion`), which always answers and owns the
``on_inconsistent`` policy (:mod:`.engines.reference`). :meth:`SMFDO.step` runs them in
that order, is the only dispatcher (a hand-off runs the reference engine and gives its
answer back) and commits the answer (:func:`._commit.commit`).

Notes
-----
Implementation of Algorithm 1 in observable coordinates of the augmented
system (9)-(14). The coordinates are those of an orthogonal observability
staircase of a *balanced* realisation (diagonal power-of-two scaling of
states and outputs, :func:`setobs.analysis.observability_decomposition`
with ``balance=True``): ``z_o = T_o D^-1 z``. For a well-scaled model
(the paper's example) ``D = I``; for a badly scaled one (entries from
``1e-9`` to ``1e7``) the LPs stay well conditioned. Then:

* line 2: ``Z_0^- = T_o D^-1 ([[x_0]] x [[d_0]])``;
* line 3: ``P T_o D^-1 = [0 I]`` on the observable part, so
  ``P = [0 I] D T_o^T`` (verified);
* lines 5-11, eqs. (20)-(21): prior
  ``Z_k^- = A_o Z_(k-1) + B_o Z_(k-1)^Delta + Gamma_o u_(k-1)`` and posterior
  ``Z_k = Z_k^- ∩ {z : C_o z = y_k}``;
* lines 12-13, eq. (24): for ``k >= delta``, the same ``delta`` steps re-run
  from the interval hull of ``Z_(k-delta)``. One deviation, needed for the
  documented minimum ``delta = mu_o - 1``: while that hull is unbounded
  (``Z_j`` is bounded only from ``j = mu_o - 1`` on), the recursion keeps
  running from ``Z_0^-`` (the exact set, tighter than any restart), so the
  window restarts only from a bounded hull;
* lines 14-15: ``Z_k^d = P Z_k``, estimate = centre of its interval hull.

*Coordinates of the restart box.* The window restarts from an interval
hull, and a box is not invariant under a change of state coordinates: the
windowed sets (and estimates) depend on the coordinates of the model, the
exact mode (``window=None``) does not. The library restarts in the
internal coordinates ``z_o`` above, which for a fully observable,
well-scaled model are the model's own ``[x; d]``: the disturbance stays a
coordinate (so its hull is not widened by a rotation), and the model's
state coordinates are usually the physical ones in which independent
bounds are natural. On the paper example the model's coordinates are about as
good as random rotations of ``x`` with a window, and exact mode is the same in all
(notebook 03; ``tests/setmembership/test_window_coordinates.py``).

*Exact mode.* Once the posterior is bounded it is carried as a certified
H-representation (facets and box) and advanced one step at a time
(:mod:`setobs.setmembership._hrep`), so a step costs what the *set's* complexity
costs, not ``k`` (``benchmarks/results/exact_mode.json``). With process or
measurement noise the exact set gains facets at every step; exact mode then keeps
the whole-history LP itself, sparse, in HiGHS, warm-started from step to step and
certified by the one certificate (:mod:`setobs.setmembership._history`;
``benchmarks/results/exact_noise.json``). Without noise, sets of growing complexity (more
than ``H_MAX_VERTICES`` vertices or ``H_MAX_NORMALS`` facets), time-varying
increment sets, ``keep_sets`` with noise and ``fast=False`` keep the whole history
in one constrained zonotope instead. Either way the cost grows with ``k``, except
on the H-representation.

*The engines.* The closed form of the recursion (the window's (24), or the
history from ``Z_0^-`` before the window is full) has a constraint matrix and
generators that do not depend on the data, so each structure is set up once per
process and its interval-hull LPs are solved by a compiled, warm-started dual
simplex whose bounds are certified exactly as on the HiGHS path
(:mod:`setobs.lp.fastlp`). Any LP it cannot solve and certify tightly
(infeasible, degenerate beyond its tolerances, ambiguous unboundedness), a
time-varying increment set, and the steps after a reset go to the reference
engine (the set operations plus HiGHS, with retries). In exact mode the fast
engines are the H-representation recursion (its LPs through the same compiled
simplex) and, with noise, the whole-history LP (each step adds its variables and
rows, each bound re-solves from its own last optimal basis), unless
``keep_sets``; a step that LP does not decide (data that may contradict the model)
goes to the reference engine, from the exact posterior.

*The window's restart.* ``restart="polytope"`` cuts the box of eq. (24) by rows
whose normals are the coordinate axes carried back through the dynamics (rows of
``A_o^-j``; at most ``MAX_ROWS`` of them, the smallest lags first, rows
nearly parallel to a kept one left out), with ranges from the hulls of the
``restart_depth - 1`` earlier steps carried forward, intersected with the window's
own support values in the rows' directions where the step at ``k - delta``
computed them (extra objectives of its LPs: computed while a probe every
``AUTO_PROBE`` steps finds they narrow the bands by more than ``SUPPORT_GAIN``
on average, and only for at most ``SUPPORT_MAX_RATIO`` rows per coordinate). It is an
outer bound of the exact set at ``k - delta`` whatever the data, and keeps its shape:
its widths against the exact set and the box restart's, and its cost, are in
``benchmarks/results/state_estimation.json`` and ``chain_ab.json`` (the performance
page); where the box restart is already nearly exact the two agree. Its LPs are
larger than the box restart's. It is used with fixed uncertainty sets and an invertible,
well-conditioned ``A_o``; otherwise (callables, a pure delay) the window restarts
from the box. With ``restart="auto"`` the other restart is computed too at a probe
(after ``AUTO_PROBE`` window steps on the fast path, the interval doubling up to
``AUTO_PROBE_MAX`` while the probes keep the choice), and the polytope stays in
use while it is narrower than the box restart by more than ``AUTO_GAIN`` of
the widths on average, or ``AUTO_GAIN_MAX`` in some coordinate (where the
shape does not matter the step keeps the box restart's cost); on a probe step the
narrower one is reported; the reference path
(``fast=False``) keeps the polytope. With the polytope, the first restart waits for
its depth (up to ``restart_lags`` steps beyond the window, while the whole history
is no larger an LP than the window's) and, from a wide initial set, for the transient
to pass (while the hull it would restart from is more than ``TRANSIENT_RATIO`` times as
wide as the newest one, at most ``TRANSIENT_WAIT`` windows); until then each step is
the whole history from the initial set, the exact set (a restart from a shallow
polytope, or from the transient, is wider than it).
"""


from __future__ import annotations

import warnings
from typing import Generic, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._blas import single_threaded_blas, with_single_threaded_blas
from .._lazy import progress_bar
from .._validation import as_inputs, as_matrix
from ..analysis.existence import BoundedDOReport
from ..analysis.observability import ObservabilityDecomposition
from ..exceptions import (
    ArgumentError,
    DimensionError,
    ExistenceError,
    ImmutableError,
    InternalError,
    InvalidValueError,
    MissingDataWarning,
    ModelInvalidatedError,
    ModelInvalidatedWarning,
)
from ..geometry import Box, ConstrainedZonotope
from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import DATA_RTOL, MISSING_WARN_FRACTION
from ._bounded import BoundedHistory
from ._closed_form import MODEL_CACHE as MODEL_CACHE  # (re-exported: one cache per process)
from ._closed_form import ClosedForm, WindowModel
from ._commit import commit
from ._history import HistoryLP
from ._hrep import HState
from ._model import IncrementSpec, NoiseSpec, SMFDOModel, SMFDOOptions, build_model
from ._restart import DEFAULT_RESTART_DEPTH
from ._schedule import start_mode
from ._set_estimates import (
    STEP_STATUSES,
    SetEstimateResult,
    SetEstimateStep,
    SMFDOResult,
    SMFDOStep,
)
from ._state import Handoff, SMFDOState
from .engines.history import HistoryEngine
from .engines.hrep import HRepEngine
from .engines.reference import ReferenceEngine
from .engines.window import WindowEngine

__all__ = [
    "SMFDO",
    "STEP_STATUSES",
    "ExistenceError",
    "ModelInvalidatedError",
    "ModelInvalidatedWarning",
    "SMFDOResult",
    "SMFDOStep",
    "SetEstimateResult",
    "SetEstimateStep",
]

_T = TypeVar("_T")


class _Delegated(Generic[_T]):
    """A read-only attribute of the SMFDO that lives on its model or its state."""

    def __init__(self, where: str, name: str) -> None:
        self.where, self.name = where, name

    def __get__(self, obj: object, owner: type | None = None) -> _T:
        if obj is None:
            return self  # type: ignore[return-value]  # (the class attribute itself)
        return getattr(getattr(obj, self.where), self.name)

    def __set__(self, obj: object, value: object) -> None:
        raise ImmutableError(f"SMFDO.{self.name} is fixed (build a new SMFDO, or "
                             "reset() to start again)")


class SMFDO:
    """Set-membership filter-based disturbance observer (Li-Cong-Dong, Algorithm 1).

    Parameters
    ----------
    sys : LinearSystem
        ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``, ``d+ = d + dd``.
    window : int or None
        Filtering interval ``delta``. ``None`` selects the **exact mode**: no
        reset, so the posterior is exactly ``[[d_k | u_0:k-1, y_0:k]]`` when the
        uncertainty sets are exact (Theorem 3); how its steps are computed, and
        what they cost, is in the module notes (*Exact mode*).
    increment_set : ConstrainedZonotope, Box, array_like, callable or None
        Bounded set containing ``dd_k``: a CZ, a :class:`Box`, a vector ``r``
        meaning the box ``|dd_i| <= r_i``, or a callable ``k -> CZ`` for a
        time-varying set. Default: the unit box ``|dd_i| <= 1``
        (Li-Cong-Dong, eqs. (27)-(28)).
    initial_state_set : ConstrainedZonotope or Box, optional
        Set containing ``x_0`` (default ``R^n``).
    initial_disturbance_set : ConstrainedZonotope or Box, optional
        Set containing ``d_0`` (default ``R^q``, as in Algorithm 1, line 1).
    measurement_noise : ConstrainedZonotope, Box, array_like, callable or None
        Bounded set ``V`` of the measurement noise: ``y_k = Xi x_k + D_u u_k + F v_k``,
        ``v_k in V`` (``F = I`` by default, so ``V`` lives in output space): a
        CZ, a :class:`Box`, per-channel radii (``|v_i| <= r_i``; a scalar for
        all channels) or a callable ``k -> set`` (time-varying). Default: none
        (``y = Xi x + D_u u`` exactly, up to ``data_rtol``). The posterior is
        the generalised intersection with ``y - D_u u - F V``.
    process_noise : ConstrainedZonotope, Box, array_like, callable or None
        Bounded set ``W`` of the process noise: ``x_(k+1) = Phi x + Gamma u + G d
        + E w_k``, ``w_k in W`` (``E = I`` by default: ``W`` in state space).
        Same forms as ``measurement_noise``.
    measurement_noise_matrix, process_noise_matrix : array_like, optional
        ``F`` (``l x n_v``) and ``E`` (``n x n_w``) when the noise enters
        through a matrix (default the identity).
    on_inconsistent : {"raise", "skip", "reset"}
        What to do when no state and disturbance history explains a
        measurement (certified empty posterior: an outlier, a sensor fault, or
        a model or uncertainty set that is wrong). ``"raise"`` (default):
        :class:`ModelInvalidatedError` with the step. ``"skip"``: the
        measurement is dropped (from the window's history too) and the step's
        set is the prediction from the last posterior, status ``"skipped"`` --
        sound if the sample was an outlier. ``"reset"``: restart from the
        interval hull of the prediction, inflated by ``reset_inflation`` (times 4
        until the measurement is explainable) and intersected with the
        measurement; the window restarts from that set and the step's status is
        ``"reset"`` (the guarantee is lost at that step by construction). The
        first inconsistent step is :attr:`first_inconsistent`; :meth:`run`
        issues one :class:`ModelInvalidatedWarning` per record, :meth:`step`
        one per observer.
    reset : {"raise", "box"}, optional
        Deprecated spelling of ``on_inconsistent`` (``"box"`` is ``"reset"``).
    max_skip_fraction : float
        With ``on_inconsistent="skip"``: once more than this fraction of the samples
        were skipped (of the record given to :meth:`run`, or of the steps so far for
        :meth:`step`; counted over at least ``1 / max_skip_fraction`` samples, so
        that a short record may lose one outlier; 0: no skip at all), the run stops
        with a :class:`SkipLimitError` (a :class:`ModelInvalidatedError`) naming the
        fraction (default 0.01: a
        bound that 80 % of a record contradicts is a wrong bound, not outliers).
        Every step from the first skipped or reset one on is flagged
        (``step.after_skip``, ``result.after_skip``): its bands hold for the model with
        those samples discarded, not for the record.
    reset_inflation : float
        Positive initial inflation factor of the reset box.
    margin : float
        Nonnegative relative outward margin added to reported bounds, and to the
        interval hulls that restart the window (eq. (24)), to cover the
        ``O(eps)`` rounding of the generator and constraint matrices of the set
        recursion (the rounding of centres and right-hand sides is tracked and
        certified; see :mod:`setobs.geometry.zonotope`).
    data_rtol : float
        Relative uncertainty of every measurement ``y`` and input ``u`` at
        rounding level (default ``2 eps``: the representation error plus a few
        roundings in the code that produced the data). The bounds hold for all
        data within it, so large measurements (``|y| ~ 1e15``, where one ulp
        exceeds the disturbance's effect) widen the bands instead of excluding
        the truth. Measurement noise is not rounding: bound it with a set.
    keep_sets : bool
        Store ``P Z_k`` in each step result.
    fast : bool
        Use the fast engines (default): the window's closed form, and in exact
        mode the H-representation or the whole-history LP (module notes: *The
        engines*). Any step they cannot solve and certify tightly goes to the
        reference set recursion; ``False`` forces it. ``stats`` counts the steps
        of each path.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances; the others are control inputs.
    state_bounds : bool
        Also give the certified interval hull of the consistent states ``x_k`` at
        every step (``step.state_lo``, ``step.state_hi``; ``result.state_lo``,
        ``result.state_hi``, ``N x n``), from the same sets and LPs. With no
        disturbance (``q = 0``) the SMFDO is a set-membership state observer: the
        worst-case-optimal state set in exact mode, an outer bound of it with a
        window. A state on the unobservable part of the augmented pair is bounded
        from ``initial_state_set`` when that set bounds it (tracked outside the LPs,
        an outer bound by induction), else reported unbounded.
    restart : {"auto", "polytope", "box"}
        The set each window restarts from (windowed mode). ``"box"``: the
        interval hull of ``Z_(k-delta)``, eq. (24) of Li-Cong-Dong literally.
        ``"polytope"``: that box cut by up to ``(restart_depth - 1) N_o`` rows
        carried back through the dynamics (at most 120), with ranges from the earlier
        hulls and the window's own support values (an outer bound of the exact set
        whatever the data; the proof is in the developer notes). ``"auto"``
        (default): the polytope while it is narrower than the box by ``AUTO_GAIN`` on
        average or ``AUTO_GAIN_MAX`` somewhere, checked at probes. Both are certified;
        the module notes (*The window's restart*) give the rule, widths and costs.
    restart_depth : int
        ``m >= 1``: the hull at ``k - delta`` and up to ``m - 1`` earlier ones
        (default 60; the restart keeps at most 120 rows, the smallest lags first, so
        that a large state keeps its LPs small; 1 is the box).

    Attributes
    ----------
    stats : dict
        Steps on the ``"fast"`` and ``"reference"`` paths, ``"fallback"``
        steps (an LP failed under every solver setting), ``"skipped"`` and
        ``"reset"`` steps (inconsistent measurements) and ``"mask_reference"``
        (steps with a missing-sample pattern beyond the fast path's budget of
        :data:`MAX_MASK_STRUCTURES` structures, computed on the reference path),
        ``"polytope_restarts"`` (fast window steps restarted from the polytope, see
        ``restart``), ``"support_restarts"`` (its rows cut by support values).
    first_inconsistent : int or None
        First step (since the last :meth:`reset`) whose measurement was
        inconsistent with the model (skipped or reset).

    Raises
    ------
    ExistenceError
        If Theorem 1 fails (carries the analysis report).
    DimensionError
        On badly shaped sets.
    InvalidValueError
        If ``window < mu_o - 1`` (observability index of the augmented pair), or on
        out-of-range parameters.
    TypeError
        On arguments of the wrong kind (e.g. a ``control.StateSpace``: convert
        it with :meth:`LinearSystem.from_statespace`).

    Notes
    -----
    The coordinates, the lines of Algorithm 1 and the window's restart box are
    described in the module notes (:mod:`setobs.setmembership.smfdo`).

    One SMFDO is not meant to be used from two threads at once; different
    SMFDOs (of the same system or not) run safely in different threads: each
    keeps its own warm-start state, and only immutable structures are shared.

    Examples
    --------
    The paper's example (Li-Cong-Dong, eq. (25)) with a constant disturbance, measured
    exactly: the certified band holds it, and the window's worst-case error is small.

    >>> import numpy as np
    >>> import setobs as so
    >>> sys = so.examples.chang2006()
    >>> d = np.array([0.5, -0.2])
    >>> x, Y = np.zeros(3), []
    >>> for k in range(30):
    ...     Y.append(sys.Xi @ x)
    ...     x = sys.Phi @ x + sys.G @ d
    >>> res = so.SMFDO(sys, window=10, increment_set=[1e-3, 1e-3]).run(np.array(Y))
    >>> bool(np.all((res.lo[-1] <= d) & (d <= res.hi[-1]))), bool(res.error_bound[-1] < 0.01)
    (True, True)
    """

    # The model's and the state's public attributes, read-only (Attributes above; the
    # model's are fixed at construction, the state's change with each step).
    sys: _Delegated[LinearSystem] = _Delegated("model", "sys")
    existence: _Delegated[BoundedDOReport] = _Delegated("model", "existence")
    decomposition: _Delegated[ObservabilityDecomposition] = _Delegated("model", "decomposition")
    mu_o: _Delegated[int] = _Delegated("model", "mu_o")
    window: _Delegated[int | None] = _Delegated("model", "window")
    on_inconsistent: _Delegated[str] = _Delegated("model", "on_inconsistent")
    keep_sets: _Delegated[bool] = _Delegated("model", "keep_sets")
    fast: _Delegated[bool] = _Delegated("model", "fast")
    margin: _Delegated[float] = _Delegated("model", "margin")
    data_rtol: _Delegated[float] = _Delegated("model", "data_rtol")
    state_bounds: _Delegated[bool] = _Delegated("model", "state_bounds")
    restart: _Delegated[str] = _Delegated("model", "restart")
    restart_depth: _Delegated[int] = _Delegated("model", "restart_depth")
    reset_inflation: _Delegated[float] = _Delegated("model", "reset_inflation")
    max_skip_fraction: _Delegated[float] = _Delegated("model", "max_skip_fraction")
    P: _Delegated[NDArray[np.float64]] = _Delegated("model", "P")
    T_o: _Delegated[NDArray[np.float64]] = _Delegated("model", "T_o")
    A_o: _Delegated[NDArray[np.float64]] = _Delegated("model", "A_o")
    B_o: _Delegated[NDArray[np.float64]] = _Delegated("model", "B_o")
    Gamma_o: _Delegated[NDArray[np.float64]] = _Delegated("model", "Gamma_o")
    C_o: _Delegated[NDArray[np.float64]] = _Delegated("model", "C_o")
    k: _Delegated[int] = _Delegated("_state", "k")
    stats: _Delegated[dict[str, int]] = _Delegated("_state", "stats")
    first_inconsistent: _Delegated[int | None] = _Delegated("_state", "first_inconsistent")

    def __init__(
        self,
        sys: LinearSystem,
        window: int | None = 10,
        increment_set: IncrementSpec = None,
        initial_state_set: ConstrainedZonotope | Box | None = None,
        *,
        initial_disturbance_set: ConstrainedZonotope | Box | None = None,
        measurement_noise: NoiseSpec = None,
        process_noise: NoiseSpec = None,
        measurement_noise_matrix: ArrayLike | None = None,
        process_noise_matrix: ArrayLike | None = None,
        on_inconsistent: str = "raise",
        reset: str | None = None,
        reset_inflation: float = 1.0,
        margin: float = 1e-9,
        data_rtol: float = DATA_RTOL,
        keep_sets: bool = False,
        fast: bool = True,
        state_bounds: bool = False,
        restart: str = "auto",
        restart_depth: int = DEFAULT_RESTART_DEPTH,
        disturbance_inputs: DisturbanceInputs = None,
        max_skip_fraction: float = 0.01,
    ) -> None:
        sys = require_system(sys, "sys", disturbance_inputs=disturbance_inputs)
        options = SMFDOOptions(
            window, increment_set, initial_state_set, initial_disturbance_set,
            measurement_noise, process_noise, measurement_noise_matrix, process_noise_matrix,
            on_inconsistent, reset_inflation, margin, data_rtol, keep_sets, fast,
            state_bounds, restart, restart_depth, max_skip_fraction, reset=reset)
        self.model: SMFDOModel = build_model(sys, options)
        m = self.model
        # The engines, tried in this order until one answers (the reference recursion,
        # last, always does): the H-representation (exact mode without noise), the
        # whole-history LP (exact mode with noise), the window's closed form.
        self._reference = ReferenceEngine()
        engines: list[HRepEngine | HistoryEngine | WindowEngine | ReferenceEngine] = []
        if m.hrep_on:
            engines.append(HRepEngine())
        if m.history_on:
            engines.append(HistoryEngine())
        self._engines = (*engines, WindowEngine(), self._reference)
        self._state = SMFDOState(m.window, m.restart_lags, m.ubar)

    def __copy__(self) -> SMFDO:
        """An independent copy (``copy.copy`` is ``copy.deepcopy`` here): the
        estimator's state (window history, warm-start bases, carried sets) is
        mutable, and a shallow copy shared it, so running the copy changed the
        original's later results (a false invalidation on consistent data)."""
        import copy

        return copy.deepcopy(self)

    def reset(self) -> None:
        """Forget all data and start again at ``k = 0``."""
        m = self.model
        self._state = SMFDOState(m.window, m.restart_lags, m.ubar, previous=self._state)
        for engine in self._engines:
            engine.reset()

    def reset_state(self) -> None:
        """Deprecated name of :meth:`reset`."""
        warnings.warn("SMFDO.reset_state() is deprecated: use reset() (the estimators' one "
                      "protocol: reset, step, run)", DeprecationWarning, stacklevel=2)
        self.reset()

    @property
    def posterior_set(self) -> ConstrainedZonotope | None:
        """The current posterior set ``Z_k^+`` (eq. (21)) of the internal state, or ``None``.

        In the observer's internal coordinates ``z_o`` (see :attr:`restart_box`);
        ``None`` before the first measurement. A fast-path step's set is
        built from its closed form on first access.
        """
        return self._state.posterior()

    @property
    def exact_representation(self) -> HState | None:
        """Exact mode's carried H-representation of the posterior, or ``None``.

        ``H``, ``g`` (certified ``H z <= g``), ``lo``, ``hi`` (certified box)
        and ``V`` (approximate vertices) in the internal coordinates ``z_o``;
        ``None`` while the set recursion carries the posterior (windowed mode,
        before the posterior is bounded, or for sets too complex for it).
        """
        src = self._state.Z_src
        return src if isinstance(src, HState) else None

    @property
    def fast_path_instance(self) -> tuple[WindowModel, NDArray[np.float64], NDArray[np.float64],
                                          NDArray[np.float64]] | None:
        """``(model, c, b, h)`` of the last step if the compiled fast path solved it, else ``None``.

        For diagnostics and benchmarks: the window model (fixed structure), the
        centre of the posterior, and the data-dependent right-hand side and
        factor bounds of its LPs.
        """
        src = self._state.Z_src
        if not isinstance(src, ClosedForm):
            return None
        return src.model, src.c, src.b, src.h

    @property
    def history_length(self) -> int | None:
        """Steps of history exact mode's LP holds with noise (the whole record until its
        history is cut, then the outer cut LP's: :mod:`._bounded`), or ``None`` when no
        such LP carries the posterior (windowed mode, exact mode without noise, before
        the posterior is bounded)."""
        src = self._state.Z_src
        if isinstance(src, HistoryLP | BoundedHistory):
            return src.length
        return None

    @property
    def hull_from_state(self) -> bool:
        """Whether the disturbance is a coordinate subset of the internal state ``z_o``.

        Then the disturbance interval hull is read off the state's hull (no
        extra LPs); otherwise it has LPs of its own.
        """
        return self.model.P_coords is not None

    @property
    def restart_box(self) -> Box | None:
        """The box the window restarts from at the next step (eq. (24)), or ``None``.

        ``IH(Z_(k+1-delta))`` with the outward margin, in the observer's internal
        coordinates ``z_o = T_o D^-1 [x; d]`` (see the class notes; for a fully
        observable augmented pair of a well-scaled model, ``T_o = I``, ``D = I``);
        ``None`` in exact mode and until ``delta`` steps have been seen.
        """
        win, hulls = self.model.window, self._state.hulls
        if win is None or len(hulls) < win:
            return None
        return Box(*self.model.restart_bounds(hulls[-win]))

    @property
    def restart_lags(self) -> int:
        """How many earlier hulls the window's restart carries back (``0``: it restarts
        from the box, eq. (24): ``restart="box"``, exact mode, time-varying sets or a
        singular ``A_o``; else the largest lag of its rows, at most ``restart_depth - 1``)."""
        return self.model.restart_lags

    @property
    def simplex_iterations(self) -> tuple[int, int]:
        """Iterations of the compiled simplex so far, ``(primal, dual)`` (pivots and
        bound flips over every LP of the fast paths): the work behind the steps' time,
        for benchmarks and for choosing a window."""
        return self._state.iterations()

    def step(self, y: ArrayLike, u: ArrayLike | None = None) -> SetEstimateStep:
        """Process the measurement ``y_k`` with the input ``u_k`` of the same step.

        The estimators' one record convention: ``u_k`` is applied at the time of
        ``y_k`` (it moves ``x_k`` to ``x_(k+1)``, and enters ``y_k`` through a
        feedthrough ``D_u``), so a record's ``U[k]`` goes with ``Y[k]``.

        Parameters
        ----------
        y : array_like, shape (l,)
            Measurement at step ``k``; NaN entries are outputs not measured at
            this step (all NaN: a prediction step).
        u : array_like, shape (p,), optional
            The input ``u_k`` (required when the system has inputs).

        Returns
        -------
        SetEstimateStep
            Step ``k``'s certified bounds and status.

        Raises
        ------
        ModelInvalidatedError
            If no state and disturbance history explains the data
            (``on_inconsistent="raise"``).
        """
        if self.sys.p and u is None:
            raise ArgumentError(f"u is required: the system has {self.sys.p} input(s) (pass "
                                "zeros explicitly if none was applied)")
        if not self.sys.p and u is not None and np.size(u) == 0:
            u = None  # (a record's empty input row of a system without inputs)
        return self._step(y, None, u)

    def update(self, y: ArrayLike, u_prev: ArrayLike | None = None, *,
               u: ArrayLike | None = None) -> SetEstimateStep:
        """Deprecated: :meth:`step` takes ``u_k`` with ``y_k``; ``update`` took the input
        ``u_(k-1)`` applied before ``y_k`` (and ``u_k`` as ``u=`` with a feedthrough).

        Parameters
        ----------
        y : array_like, shape (l,)
            Measurement at step ``k``.
        u_prev : array_like, shape (p,), optional
            Known input ``u_(k-1)`` (ignored at ``k = 0``).
        u : array_like, shape (p,), optional
            The input ``u_k`` at this step.
        """
        warnings.warn("SMFDO.update(y, u_prev) is deprecated: use step(y, u) with the input "
                      "of the same step (U[k] with Y[k])", DeprecationWarning, stacklevel=2)
        return self._step(y, u_prev, u)

    def _step(self, y: ArrayLike, u_prev: ArrayLike | None, u: ArrayLike | None
              ) -> SetEstimateStep:
        """One step with the input before it (``u_prev``, else the one carried from the
        last step) and the current one (``u``): :meth:`_update` under the BLAS policy,
        and the skip limit."""
        if self._state.blas_small:
            # the last step was a window small enough for BLAS to run single-threaded
            # by itself (setobs._blas.SMALL_BLAS_DIM): the limit's four thread-count
            # calls (a tenth of such a step) are skipped; only speed depends on it
            step = self._update(y, u_prev, u)
        else:
            with single_threaded_blas():
                step = self._update(y, u_prev, u)
        if step.status == "skipped":
            self._state.count_skip(step.k, self.model.max_skip_fraction)
        return step

    def _update(self, y: ArrayLike, u_prev: ArrayLike | None, u: ArrayLike | None
                ) -> SetEstimateStep:
        """:meth:`step`'s step (the caller sets the BLAS threads): the first engine that
        answers (the reference recursion always does), and one commit."""
        m, s = self.model, self._state
        s.blas_small = False
        k = s.k + 1
        e, s.u_pending = m.entry(y, u_prev, u, k, s.u_pending)
        mode = "init" if k == 0 else start_mode(m, s, k)
        for engine in self._engines:
            out = engine.try_step(m, s, k, mode, e)
            if isinstance(out, Handoff):
                # the engine cannot decide this step: the reference engine does, from the
                # engine's exact posterior, and the engine carries its answer on
                s.Z_src, s.depth = out.start, 0
                try:
                    answer = self._reference.try_step(m, s, k, mode, e)
                except ModelInvalidatedError:
                    s.Z_src = out.carried  # (the observer is left as before the step)
                    raise
                out = out.owner.resume(answer, out)
            if out is not None:
                return commit(m, s, k, mode, out)
        raise InternalError("no engine answered (the reference recursion always does)")

    def run(self, Y: ArrayLike, U: ArrayLike | None = None, *,
            progress: bool = False, ignore: ArrayLike | None = None) -> SetEstimateResult:
        """Process a whole record from the start: :meth:`reset`, then
        :meth:`continue_run` (its parameters, returns and warnings).

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measurements ``y_0 .. y_(N-1)``.
        U : array_like, shape (N, p) or (N-1, p), optional
            Inputs aligned with ``Y`` (``U[k]`` with ``Y[k]``).
        progress : bool
            Show a progress bar.
        ignore : array_like, optional
            Samples to ignore (a mask or indices).

        Returns
        -------
        SetEstimateResult
            The record's certified bands.
        """
        self.reset()
        return self.continue_run(Y, U, progress=progress, ignore=ignore)

    @with_single_threaded_blas
    def continue_run(self, Y: ArrayLike, U: ArrayLike | None = None, *,
                     progress: bool = False, ignore: ArrayLike | None = None
                     ) -> SetEstimateResult:
        """Process a record continuing from the current state (what :meth:`run` does
        after :meth:`reset`).

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measurements ``y_k .. y_(k+N-1)``, continuing from the current step
            when the observer has already seen data. NaN entries: not
            measured (a row of NaN is a prediction step).
        U : array_like, shape (N, p) or (N-1, p), optional
            Inputs aligned with ``Y``: ``U[j]`` is applied at the time of
            ``Y[j]``, so ``U[j-1]`` is used at record step ``j`` (and ``U[j]``
            too when the system has a feedthrough ``D_u``: then ``U`` needs
            ``N`` rows). When a record is split into consecutive calls, pass
            ``U`` with ``N`` rows: its last row is the input before the first
            step of the next call.
        progress : bool
            Show a progress bar (tqdm, on stderr) over the record.
        ignore : array_like, optional
            Samples to ignore: a boolean mask of length ``N`` or sample indices (e.g.
            :attr:`NoiseCalibration.ignored <setobs.setmembership.NoiseCalibration.ignored>`,
            the outliers a calibration removed); their measurements are treated as
            missing (NaN), so the bands hold for the record without them.

        Returns
        -------
        SetEstimateResult
            ``estimate``, ``lo``, ``hi`` of shape ``(N, q)``, ``error_bound`` and
            ``status`` ``(N,)``, ``first_inconsistent``.

        Warns
        -----
        ModelInvalidatedWarning
            Once, if measurements of this record were skipped or reset.
        """
        Ya, Ua = _check_record(self.model, self._state, Y, U, ignore)
        N = Ya.shape[0]
        steps = []
        with_u = self.model.Du is not None
        bar = progress_bar(progress, total=N, unit="step", desc="SMFDO", mininterval=0.5)
        st = self._state
        st.in_run = True
        st.run_length = N + max(self.k + 1, 0)
        try:
            for j in range(N):
                if j % 200 == 0 and j:
                    bar.update(200)
                u = Ua[j - 1] if (Ua is not None and j >= 1) else None
                steps.append(self._step(Ya[j], u, Ua[j] if with_u else None))
            bar.update(N - bar.n)
        finally:
            st.in_run = False
            st.run_length = 0
            bar.close()
        if Ua is not None and Ua.shape[0] == N and N:
            self._state.u_pending = Ua[N - 1].copy()
        return _result(self.model, steps)

    def __repr__(self) -> str:
        mode = "exact" if self.window is None else f"window={self.window}"
        return f"SMFDO({self.sys!r}, {mode}, k={self.k})"


def _check_record(m: SMFDOModel, st: SMFDOState, Y: ArrayLike, U: ArrayLike | None,
                  ignore: ArrayLike | None):
    """A record's ``Y`` (ignored samples as NaN) and ``U``, validated against the model
    and the state (:meth:`SMFDO.run`'s arguments)."""
    sys = m.sys
    Ya = as_matrix("Y", Y, cols=sys.l, allow_nan=True)
    N = Ya.shape[0]
    if ignore is not None:
        Ya[_ignore_mask(ignore, N)] = np.nan
    if Ya.size:
        missing = float(np.isnan(Ya).mean())
        if missing == 1.0 and st.k < 0:
            raise InvalidValueError(
                f"Y has no measured (finite) entry: all {N} samples are missing (NaN), "
                "so every band would be the prior's; check the record's columns and "
                "its missing-value marker")
        if missing > MISSING_WARN_FRACTION:
            warnings.warn(
                f"{100 * missing:.1f} % of the record's output samples are missing "
                f"(NaN; warned above {100 * MISSING_WARN_FRACTION:g} %, "
                "setobs.tolerances.MISSING_WARN_FRACTION): the bands are mostly "
                "predictions", MissingDataWarning, stacklevel=4)
    Ua = as_inputs(sys.p, U)
    if Ua is not None:
        if Ua.shape[0] not in (N, N - 1):
            raise DimensionError(f"U must have N or N-1 = {N}/{N - 1} rows, got {Ua.shape[0]}")
        if m.Du is not None and Ua.shape[0] != N:
            raise DimensionError(
                f"U must have N = {N} rows: the system has a feedthrough D_u, so "
                "y_k needs u_k")
        if st.k >= 0 and st.u_pending is None and N:
            raise DimensionError(
                "the input applied before the first step of this record is unknown: "
                "give the previous run() its U with N rows (the last row is that "
                "input), or continue with update(y, u_prev)")
    return Ya, Ua


def _result(m: SMFDOModel, steps: list[SetEstimateStep]) -> SetEstimateResult:
    """The run's result from its steps (warning once if a step was skipped or reset)."""
    sys, N, q = m.sys, len(steps), m.sys.q
    status = np.array([s.status for s in steps], dtype="<U9")
    bad = np.flatnonzero((status == "skipped") | (status == "reset"))
    first = int(steps[bad[0]].k) if bad.size else None
    if bad.size:
        warnings.warn(
            f"{bad.size} of {N} measurements were inconsistent with the model and the "
            f"uncertainty sets (first at k={first}) and were "
            f"{'skipped' if m.on_inconsistent == 'skip' else 'handled by a reset'}: the "
            "bands at those steps are not the model's consistent sets (see result.status, "
            "result.first_inconsistent)", ModelInvalidatedWarning,
            stacklevel=4)  # _result -> run -> the BLAS-limit wrapper -> the caller
    x_lo = x_hi = None
    x_names: tuple[str, ...] = ()
    if m.state_bounds:
        n = sys.n
        x_lo = np.array([s.state_lo for s in steps]).reshape(N, n)
        x_hi = np.array([s.state_hi for s in steps]).reshape(N, n)
        x_names = tuple(sys.state_names)
    return SetEstimateResult(
        np.array([s.estimate for s in steps]).reshape(N, q),
        np.array([s.lo for s in steps]).reshape(N, q),
        np.array([s.hi for s in steps]).reshape(N, q),
        np.array([s.error_bound for s in steps]), steps, status, first, sys.dt,
        tuple(sys.disturbance_names), x_lo, x_hi, x_names,
        np.array([s.after_skip for s in steps], dtype=bool))


def _ignore_mask(ignore: ArrayLike, N: int) -> NDArray[np.bool_]:
    """``ignore`` (a boolean mask of length ``N`` or sample indices) as a mask."""
    a = np.asarray(ignore)
    if a.dtype == bool:
        if a.shape != (N,):
            raise DimensionError(f"ignore must be a boolean mask of length N = {N} or sample "
                                 f"indices, got a mask of shape {a.shape}")
        return a
    if a.size and (a.dtype.kind not in "iu" or a.ndim != 1):
        raise ArgumentError("ignore must be a boolean mask of length N or a 1-D array of "
                             f"sample indices, got {a.dtype} of shape {a.shape}")
    if a.size and (a.min() < 0 or a.max() >= N):
        raise InvalidValueError(f"ignore holds sample indices outside [0, {N - 1}]")
    m = np.zeros(N, dtype=bool)
    m[a.astype(np.int64)] = True
    return m
