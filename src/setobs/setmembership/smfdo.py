"""The set-membership filter-based disturbance observer (Li-Cong-Dong, Algorithm 1)."""

from __future__ import annotations

import hashlib
import numbers
import threading
import warnings
from collections import OrderedDict, deque
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._blas import with_single_threaded_blas
from .._deprecation import renamed
from .._lazy import progress_bar
from .._rounding import UNIT_ROUNDOFF, gamma, pow2_inverse, round_down, round_up
from .._validation import as_matrix, as_vector, check_real_scalar
from ..analysis import bounded_do_exists, observability_decomposition
from ..exceptions import (
    DimensionError,
    EmptySetError,
    ExistenceError,
    ModelInvalidatedError,
    ModelInvalidatedWarning,
    SolverWarning,
)
from ..geometry import Box, ConstrainedZonotope
from ..geometry.box import box_center, box_center_radius, trusted_box
from ..geometry.zonotope import absorb_center_error, hull_with_status, trusted_cz
from ..results import error_summary, time_axis, time_index
from ..systems import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import (
    CENTER_ERROR_ABSORB_RTOL,
    DATA_RTOL,
    HREP_CONVERT_RTOL,
    UNBOUNDED_RADIUS,
)
from ._hrep import (
    MAX_VERTICES,
    HState,
    snap_normals,
    step_geometry,
    structure_A,
    tidy_vertices,
    vertices_match,
)
from ._window import WindowModel, model_rtol

__all__ = [
    "SMFDO",
    "STEP_STATUSES",
    "ExistenceError",
    "ModelInvalidatedError",
    "ModelInvalidatedWarning",
    "SMFDOResult",
    "SMFDOStep",
]

#: Values of :attr:`SMFDOStep.status`.
STEP_STATUSES = ("ok", "unbounded", "fallback", "reset", "skipped")

#: ``on_inconsistent`` choices.
ON_INCONSISTENT = ("raise", "skip", "reset")

#: Distinct missing-sample patterns an SMFDO sets up fast-path structures for;
#: steps with further patterns go to the reference path.
MAX_MASK_STRUCTURES = 64

#: LP budget of converting a bounded posterior to the H-representation of exact
#: mode (a beneath-beyond vertex enumeration); beyond it the set recursion goes on.
H_CONVERSION_LPS = 150

#: Complexity beyond which exact mode leaves the H-representation recursion for
#: the set recursion (vertices, normals): measurement noise can make the exact
#: set's complexity grow quickly (the paper example with a noise box: 44, 107,
#: 264 facets and 178, 361, 754 vertices at k = 2, 3, 4; benchmarks/exact_mode.py),
#: and then the vertex geometry costs more than the whole-history LPs.
H_MAX_VERTICES = MAX_VERTICES
H_MAX_NORMALS = 64
#: Exact mode converts a posterior whose facets are confirmed only to
#: ``VERTEX_RTOL`` (not ``HREP_CONVERT_RTOL``) when its box is at most this many
#: times wider than one step's uncertainty: converted earlier, in the transient
#: before the data bound the set (widths 1e3 to 1e5 times the later ones), that
#: tolerance became 1e-6 of the later width (issue 32, campaign seed 36).
H_LAX_SIZE_FACTOR = 1e3


@dataclass(frozen=True)
class SMFDOStep:
    """One step of the SMFDO.

    Attributes
    ----------
    k : int
        Time step.
    estimate : ndarray, shape (q,)
        Centre of the disturbance interval hull (Algorithm 1, line 15);
        NaN where the set is still unbounded.
    lo, hi : ndarray, shape (q,)
        Certified interval hull of the disturbance set (``+-inf`` while unbounded).
    error_bound : float
        Certified bound on the infinity-norm error of ``estimate``:
        ``max_i (hi_i - lo_i) / 2``, its worst case over the computed set (the
        optimal worst-case error in exact mode, an upper bound on it with a
        window).
    disturbance_set : ConstrainedZonotope or None
        ``P Z_k`` when requested (``keep_sets=True``).
    status : str
        ``"ok"``; ``"unbounded"`` (some bound is infinite, e.g. before the data
        pin the disturbance down); ``"fallback"`` (an LP failed under every
        solver setting: the bounds are still certified, but wider); ``"reset"``
        (the posterior was empty and ``on_inconsistent="reset"`` restarted the
        filter: the guarantee is lost at this step); ``"skipped"`` (the
        posterior was empty and ``on_inconsistent="skip"`` dropped the
        measurement: the bounds are the prediction, sound if the sample was an
        outlier).
    """

    k: int
    estimate: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    error_bound: float
    disturbance_set: ConstrainedZonotope | None = None
    status: str = "ok"

    radius = renamed("radius", "error_bound")

    def contains(self, d: ArrayLike) -> bool:
        """Whether ``d`` lies in ``[lo, hi]``.

        Parameters
        ----------
        d : array_like, shape (q,)
            A disturbance value.
        """
        dv = as_vector("d", d, size=self.lo.size)
        return bool(np.all((dv >= self.lo) & (dv <= self.hi)))


@dataclass(frozen=True)
class SMFDOResult:
    """Batch result of :meth:`SMFDO.run` (the protocol of :mod:`setobs.results`).

    Arrays of shape ``(N, q)`` (``error_bound``, ``status``: ``(N,)``). Unpacks as
    ``t, estimate, lo, hi = smfdo.run(Y)``.

    Attributes
    ----------
    estimate : ndarray, shape (N, q)
        Centre of the certified interval (worst-case optimal for the infinity
        norm); NaN while unbounded.
    lo, hi : ndarray, shape (N, q)
        Certified interval hull of the consistent disturbances (``-inf``/``inf``
        while unbounded).
    error_bound : ndarray, shape (N,)
        Certified bound on the infinity-norm error of :attr:`estimate`:
        ``max_i (hi_i - lo_i) / 2`` (in exact mode the ``optimal`` metric).
    steps : list of SMFDOStep
        The per-step records.
    status : ndarray of str, shape (N,)
        Per-step status (:data:`STEP_STATUSES`).
    first_inconsistent : int or None
        The first time step ``k`` of this record whose measurement was
        inconsistent with the model (status ``"skipped"`` or ``"reset"``): a
        fault-detection result (the model, the uncertainty sets or the sensor
        failed there). ``None`` if every measurement was consistent.
    dt : float or None
        The system's sampling time (for time axes).
    names : tuple of str
        The disturbance names (for tables and plot labels).
    """

    estimate: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    error_bound: NDArray[np.float64]
    steps: list[SMFDOStep]
    status: NDArray[np.str_] = field(default_factory=lambda: np.zeros(0, dtype="<U9"))
    first_inconsistent: int | None = None
    dt: float | None = None
    names: tuple[str, ...] = ()

    radius = renamed("radius", "error_bound")

    @property
    def time(self) -> NDArray[np.float64]:
        """Time axis ``k dt`` (or ``k`` when the sampling time is unknown)."""
        return time_axis(self.lo.shape[0], self.dt)

    def __iter__(self):
        return iter((self.time, self.estimate, self.lo, self.hi))

    def plot(self, ax: Any = None, truth: ArrayLike | None = None, component: int = 0) -> Any:
        """Estimate, certified interval and truth of one component
        (:func:`setobs.plotting.plot_estimate_band`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default: the current axes).
        truth : array_like, shape (N, q), optional
            The true disturbance.
        component : int
            Disturbance component.

        Returns
        -------
        matplotlib Axes
            The axes drawn on.
        """
        from ..plotting import plot_estimate_band

        return plot_estimate_band(self, truth=truth, component=component, ax=ax)

    def summary(self, truth: ArrayLike | None = None, start: int = 0) -> Any:
        """One row (index ``"SMFDO"``) over steps ``k >= start``: ``error_bound`` (mean
        certified error bound over the bounded steps; the ``optimal`` worst-case
        error in exact mode), ``max_error_bound``, ``unbounded`` steps,
        ``inconsistent`` steps and, with the truth, ``error_inf``, ``max_error_inf``,
        ``error_2`` and ``truth_inside`` (fraction of steps whose certified interval
        holds the truth).

        Parameters
        ----------
        truth : array_like, shape (N, q), optional
            The true disturbance.
        start : int
            First step counted.

        Returns
        -------
        pandas.DataFrame
            The summary row.
        """
        r = self.error_bound[start:]
        fin = np.isfinite(r)
        st = self.status[start:] if self.status.size else np.zeros(0, dtype="<U9")
        extra: dict[str, Any] = {
            "error_bound": float(r[fin].mean()) if fin.any() else np.inf,
            "max_error_bound": float(r[fin].max()) if fin.any() else np.inf,
            "unbounded": int((~fin).sum()),
            "inconsistent": int(np.isin(st, ("skipped", "reset")).sum()),
        }
        if truth is not None:
            D = as_matrix("truth", truth, cols=self.lo.shape[1])
            inside = np.all((D >= self.lo) & (D <= self.hi), axis=1)[start:]
            extra["truth_inside"] = float(inside.mean()) if inside.size else np.nan
        return error_summary("SMFDO", self.estimate, truth, start, extra)

    def to_pandas(self, dt: float | None = None, names: Sequence[str] | None = None) -> Any:
        """A ``pandas.DataFrame``: per disturbance ``name``, ``name_lo``, ``name_hi``
        (the estimate and its certified interval), then ``error_bound`` and ``status``.

        The index is the time ``k dt`` (named ``"time"``) when a sampling time is
        known (``dt`` or the system's), else the step ``k``.

        Parameters
        ----------
        dt : float, optional
            Sampling time (default: the system's).
        names : sequence of str, optional
            Disturbance names (default: the system's).

        Returns
        -------
        pandas.DataFrame
            The table.
        """
        import pandas as pd

        N, q = self.lo.shape
        nm = list(names) if names is not None else (list(self.names) or
                                                      [f"d{i}" for i in range(q)])
        if len(nm) != q:
            raise DimensionError(f"names must have {q} entries, got {len(nm)}")
        cols: dict[str, Any] = {}
        for i, name in enumerate(nm):
            cols[name] = self.estimate[:, i]
            cols[f"{name}_lo"] = self.lo[:, i]
            cols[f"{name}_hi"] = self.hi[:, i]
        cols["error_bound"] = self.error_bound
        cols["status"] = self.status if self.status.size == N else np.full(N, "ok")
        return pd.DataFrame(cols, index=time_index(N, dt if dt is not None else self.dt))

    @property
    def consistent(self) -> bool:
        """Whether no step was skipped or reset (the bands are the model's sets)."""
        return self.first_inconsistent is None

    def violations(self, D: ArrayLike) -> int:
        """Number of steps at which the true disturbance ``D[k]`` is outside ``[lo, hi]``.

        Parameters
        ----------
        D : array_like, shape (N, q)
            The true disturbance.

        Raises
        ------
        DimensionError
            If ``D`` does not have the shape ``(N, q)`` of the result.
        """
        N, q = self.lo.shape
        if np.shape(D) != (N, q):
            raise DimensionError(f"D must have shape ({N}, {q}) like the result, "
                                 f"got {np.shape(D)}")
        Da = as_matrix("D", D, cols=q)
        out = (Da < self.lo) | (Da > self.hi)
        return int(out.any(axis=1).sum())


IncrementSpec = (ConstrainedZonotope | Box | ArrayLike | Callable[[int], ConstrainedZonotope]
                 | None)


class _ModelCache:
    """Window structures shared by all SMFDOs of a process (keyed by a digest of the
    matrices they depend on), so that a Monte Carlo campaign sets each up once.

    The structures are immutable (each SMFDO keeps its own LP warm-start state);
    the cache is locked, and bounded by the memory of its entries.
    """

    def __init__(self, max_bytes: int = 256 * 2**20) -> None:
        self._items: OrderedDict[tuple, tuple[WindowModel, int]] = OrderedDict()
        self._lock = threading.Lock()
        self._bytes = 0
        self.max_bytes = max_bytes

    @staticmethod
    def _size(model: WindowModel) -> int:
        lp = model.lp
        return int(model.A.nbytes + model.G.nbytes + model.b_c.nbytes + lp.Ared.nbytes
                   + lp.Q2.nbytes + lp.Q0.nbytes + lp.binv0.nbytes + lp.W.nbytes
                   + lp.Wred.nbytes + lp.yU.nbytes + lp.pinvU.nbytes)

    def get(self, key: tuple, build: Callable[[], WindowModel]) -> WindowModel:
        with self._lock:
            hit = self._items.get(key)
            if hit is not None:
                self._items.move_to_end(key)
                return hit[0]
        model = build()  # outside the lock: building takes a while
        size = self._size(model)
        with self._lock:
            if key not in self._items:
                self._items[key] = (model, size)
                self._bytes += size
                while self._bytes > self.max_bytes and len(self._items) > 1:
                    _, (_, sz) = self._items.popitem(last=False)
                    self._bytes -= sz
        return model

    def __len__(self) -> int:
        return len(self._items)


MODEL_CACHE = _ModelCache()


def check_window(window: object) -> int | None:
    if window is None:
        return None
    if isinstance(window, bool | np.bool_) or not isinstance(window, numbers.Real):
        raise TypeError(f"window must be a positive integer or None (exact mode), "
                        f"got {window!r}")
    w = float(window)
    if not np.isfinite(w) or w != int(w) or w < 1:
        raise DimensionError(f"window must be a positive integer or None (exact mode), "
                             f"got {window!r}")
    return int(w)


def _as_set(name: str, value: object, dim: int) -> ConstrainedZonotope | None:
    """A ConstrainedZonotope from a CZ, a Box, or None; anything else is refused."""
    if value is None:
        return None
    if isinstance(value, Box):
        value = ConstrainedZonotope.from_box(value.lo, value.hi)
    if not isinstance(value, ConstrainedZonotope):
        raise TypeError(
            f"{name} must be a ConstrainedZonotope or a Box (e.g. Box(lo, hi)), got "
            f"{type(value).__name__}")
    if value.dim != dim:
        raise DimensionError(f"{name} must have dimension {dim}, got {value.dim}")
    return value


NoiseSpec = (ConstrainedZonotope | Box | ArrayLike | Callable[[int], object] | None)


def _noise_set(name: str, value: object, dim: int) -> ConstrainedZonotope | None:
    """A bounded noise set from a CZ, a Box, per-channel radii (a vector, or a scalar
    for every channel), or None (no noise)."""
    if value is None:
        return None
    if isinstance(value, Box | ConstrainedZonotope):
        value = _as_set(name, value, dim)
        if not value.is_bounded:
            raise DimensionError(
                f"{name} must be bounded (an output that is not measured at a step is "
                "NaN in Y, not unbounded noise)")
        return value
    if isinstance(value, str | bytes) or callable(value):
        raise TypeError(f"{name} must be a ConstrainedZonotope, a Box, per-channel radii "
                        f"or a callable k -> set, got {type(value).__name__}")
    r = np.asarray(value)
    if r.ndim == 0:
        r = np.full(dim, check_real_scalar(name, value, nonnegative=True))
    r = as_vector(name, r, size=dim)
    if (r < 0).any():
        raise DimensionError(f"{name} radii must be nonnegative, got {r}")
    return ConstrainedZonotope.from_box(-r, r)


class _Entry(NamedTuple):
    """One step's data: ``y_k`` (balanced units, NaN = not measured), ``u_(k-1)``,
    the increment set ``[[dd_(k-1)]]``, the process-noise set ``W_(k-1)`` and the
    measurement-noise set ``F_b V_k`` (internal coordinates; ``None``: no noise),
    and an absolute uncertainty of ``y_k`` (the feedthrough's rounding) or ``None``."""

    y: NDArray[np.float64]
    u: NDArray[np.float64] | None
    dd: ConstrainedZonotope | None
    w: ConstrainedZonotope | None
    v: ConstrainedZonotope | None
    yerr: NDArray[np.float64] | None

    def skipped(self) -> _Entry:
        """The same step with its measurement dropped."""
        return self._replace(y=np.full_like(self.y, np.nan), yerr=None)


def _normalize_free_columns(Z: ConstrainedZonotope) -> ConstrainedZonotope:
    """The same set with every unbounded factor's column ``[G; A]`` scaled to unit norm.

    An unbounded factor's scale is arbitrary (``h = inf``), but it sets the
    conditioning of every LP over the set: ``R^n`` mapped into balanced
    coordinates has columns of norms from ``1e-4`` to ``1e4`` on badly scaled
    models. Powers of two keep the scaling exact.
    """
    free = np.isinf(Z.h)
    if not free.any():
        return Z
    norms = np.linalg.norm(np.vstack([Z.G, Z.A]), axis=0)
    s = np.where(free, pow2_inverse(norms), 1.0)
    return trusted_cz(Z.G * s, Z.c, Z.A * s, Z.b, Z.h, Z.unbounded_radius, Z.c_err,
                                        Z.b_err)


class SMFDO:
    """Set-membership filter-based disturbance observer (Li-Cong-Dong, Algorithm 1).

    Parameters
    ----------
    sys : LinearSystem
        ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``, ``d+ = d + dd``.
    window : int or None
        Filtering interval ``delta``. ``None`` selects the **exact mode**: no
        reset, so the posterior is exactly ``[[d_k | u_0:k-1, y_0:k]]`` when the
        uncertainty sets are exact (Theorem 3). Once the posterior is bounded
        it is carried as a certified H-representation (facets and box) and
        advanced one step at a time (:mod:`setobs.setmembership._hrep`), so a
        step costs what the *set's* complexity costs, not ``k`` (about 3 ms on
        the paper example at any ``k``). Sets of growing complexity (more than
        ``H_MAX_VERTICES`` vertices or ``H_MAX_NORMALS`` facets: typically with
        measurement noise), time-varying uncertainty sets and ``fast=False``
        keep the whole history in one constrained zonotope instead, whose
        cost grows with ``k``.
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
        issues one :class:`ModelInvalidatedWarning` per record, :meth:`update`
        one per observer.
    reset : {"raise", "box"}, optional
        Deprecated spelling of ``on_inconsistent`` (``"box"`` is ``"reset"``).
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
        Use the fast exact path in windowed mode (default). The closed form of
        the recursion (the window's (24), or the history from ``Z_0^-`` before
        the window is full) has a constraint matrix and generators
        that do not depend on the data, so each structure is set up once per
        process and its interval-hull LPs are solved by a compiled,
        warm-started dual simplex whose bounds are certified exactly as on the
        HiGHS path (:mod:`setobs.geometry.fastlp`). Any LP the fast path
        cannot solve and certify tightly (infeasible, degenerate beyond its
        tolerances, ambiguous unboundedness), a time-varying increment set,
        the steps after a ``reset="box"`` go to the reference path (the set
        operations plus HiGHS, with retries). In exact mode the fast path is
        the H-representation recursion (see ``window``; its LPs go through the
        same compiled simplex). ``False`` forces the reference path (the
        whole-history set recursion in exact mode). ``stats`` counts the steps
        of each path.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances; the others are control inputs.

    Attributes
    ----------
    stats : dict
        Steps on the ``"fast"`` and ``"reference"`` paths, ``"fallback"``
        steps (an LP failed under every solver setting), ``"skipped"`` and
        ``"reset"`` steps (inconsistent measurements) and ``"mask_reference"``
        (steps with a missing-sample pattern beyond the fast path's budget of
        :data:`MAX_MASK_STRUCTURES` structures, computed on the reference path).
    first_inconsistent : int or None
        First step (since the last :meth:`reset_state`) whose measurement was
        inconsistent with the model (skipped or reset).

    Raises
    ------
    ExistenceError
        If Theorem 1 fails (carries the analysis report).
    DimensionError
        If ``window < mu_o - 1`` (observability index of the augmented pair),
        on badly shaped sets or out-of-range parameters.
    TypeError
        On arguments of the wrong kind (e.g. a ``control.StateSpace``: convert
        it with :meth:`LinearSystem.from_statespace`).

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
    bounds are natural. Measured on the paper example (notebook 03, pinned by
    ``tests/setmembership/test_window_coordinates.py``): in the model's
    coordinates the mean error is 1.47 with ``window=3``, in five random
    rotations of ``x`` 1.55 to 1.62; with ``window=10`` 1.050 to 1.059
    (one rotation slightly better than the model's); exact mode 1.018 in all.

    One SMFDO is not meant to be used from two threads at once; different
    SMFDOs (of the same system or not) run safely in different threads: each
    keeps its own warm-start state, and only immutable structures are shared.
    """

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
        disturbance_inputs: DisturbanceInputs = None,
    ) -> None:
        sys = require_system(sys, "sys", disturbance_inputs=disturbance_inputs)
        window = check_window(window)
        if reset is not None:
            if reset not in ("raise", "box"):
                raise ValueError(f"reset must be 'raise' or 'box', got {reset!r}")
            if on_inconsistent != "raise":
                raise ValueError("give on_inconsistent only (reset is its deprecated "
                                 "spelling)")
            warnings.warn("SMFDO(reset=...) is deprecated: use on_inconsistent='raise' | "
                          "'skip' | 'reset'", DeprecationWarning, stacklevel=2)
            on_inconsistent = "reset" if reset == "box" else "raise"
        if on_inconsistent not in ON_INCONSISTENT:
            raise ValueError(f"on_inconsistent must be one of {ON_INCONSISTENT}, got "
                             f"{on_inconsistent!r}")
        self.reset_inflation = check_real_scalar("reset_inflation", reset_inflation,
                                                 positive=True)
        self.margin = check_real_scalar("margin", margin, nonnegative=True)
        self.data_rtol = check_real_scalar("data_rtol", data_rtol, nonnegative=True)
        if self.data_rtol > 1e-6:
            raise DimensionError(f"data_rtol is a rounding-level tolerance (<= 1e-6), got "
                                 f"{data_rtol!r}; bound measurement noise with a set")
        report = bounded_do_exists(sys)
        if not report.decided:
            raise ExistenceError(
                "whether a bounded disturbance observer exists is undecidable at this "
                "precision (Li-Cong-Dong, Theorem 1/Remark 1: a rank decision of the "
                "observability staircase is in the grey zone; an ill-conditioned state "
                "basis does this: use a better-conditioned realisation)", report)
        if not report.satisfied:
            raise ExistenceError(
                "no bounded disturbance observer exists for this system (Li-Cong-Dong, "
                f"Theorem 1 / Remark 1): N_o = {report.N_o} < n_o + q = "
                f"{report.n_o + report.q}", report)
        self.sys = sys
        self.existence = report
        n, q = sys.n, sys.q
        X0 = _as_set("initial_state_set", initial_state_set, n)
        D0 = _as_set("initial_disturbance_set", initial_disturbance_set, q)
        self._inc_spec = increment_set
        self._inc_fixed = self._fixed_increment(increment_set)
        inc_scale = None
        if self._inc_fixed is not None:
            inc_scale = 0.5 * self._inc_fixed.interval_hull().width
        dec = observability_decomposition(sys, balance=True, disturbance_scale=inc_scale)
        self.decomposition = dec
        self.mu_o = dec.report.index
        if window is not None and window < self.mu_o - 1:
            raise DimensionError(
                f"window (delta) = {window} is too small: Algorithm 1 needs "
                f"delta >= mu_o - 1 = {self.mu_o - 1} (mu_o = observability index "
                "of the augmented pair)")
        self.window = window
        self.on_inconsistent = on_inconsistent
        self.keep_sets = bool(keep_sets)
        T_o = dec.T_o
        dz, dy = dec.state_scale, dec.output_scale
        self._dy = dy
        # Noise: E (n x n_w) and F (l x n_v), sets in w- and v-space; internally
        # E_o = T_o D^-1 [E; 0] (the observable part: the unobservable one does
        # not feed it) and F_b = diag(1/dy) F (balanced outputs; dy are powers of
        # two, so the scaling is exact).
        l = sys.l
        E = np.eye(n) if process_noise_matrix is None else as_matrix(
            "process_noise_matrix", process_noise_matrix, rows=n)
        F = np.eye(l) if measurement_noise_matrix is None else as_matrix(
            "measurement_noise_matrix", measurement_noise_matrix, rows=l)
        if process_noise_matrix is not None and process_noise is None:
            raise ValueError("process_noise_matrix is given without process_noise")
        if measurement_noise_matrix is not None and measurement_noise is None:
            raise ValueError("measurement_noise_matrix is given without measurement_noise")
        self._E_o = (T_o / dz[None, :]) @ np.vstack([E, np.zeros((q, E.shape[1]))])
        self._F_b = F / dy[:, None]
        self._w_spec, self._v_spec = process_noise, measurement_noise
        self._W_fixed = None if callable(process_noise) else _noise_set(
            "process_noise", process_noise, E.shape[1])
        self._V_fixed = None if callable(measurement_noise) else self._v_internal(
            _noise_set("measurement_noise", measurement_noise, F.shape[1]))
        self._noise_varies = callable(process_noise) or callable(measurement_noise)
        Du = sys.Du
        self._Du = Du if (sys.p and np.any(Du != 0)) else None
        target = np.hstack([np.zeros((q, n)), np.eye(q)])
        P = target @ (dz[:, None] * T_o.T)
        # d must not depend on the unobservable coordinates: [0 I] D T_obar^T = 0.
        leak = np.abs(target @ (dz[:, None] * dec.T_obar.T)).max(initial=0.0)
        if leak > 1e-8 * np.abs(dz[n:]).max():
            raise ExistenceError("P T_o = [0 I] has no solution (fragile Theorem 1 verdict)",
                                 report)
        self.P = P
        # When P selects coordinates exactly (e.g. T_o = I for a fully observable
        # augmented pair), the hull of P Z is the selected coordinates of the hull of Z:
        # the same LPs, so no extra solves are needed (windowed mode).
        sel = (np.count_nonzero(P, axis=1) == 1) & (np.abs(P).max(axis=1) == 1.0) & \
            (P.max(axis=1) == 1.0)
        self._P_coords = np.argmax(P, axis=1) if sel.all() else None
        self.T_o = T_o
        self.A_o, self.B_o, self.Gamma_o, self.C_o = dec.A_o, dec.B_o, dec.Gamma_o, dec.C_o
        X0 = ConstrainedZonotope.full_space(n) if X0 is None else X0
        D0 = ConstrainedZonotope.full_space(q) if D0 is None else D0
        self._Z0_prior = _normalize_free_columns((T_o / dz[None, :]) @ X0.cartesian(D0))
        self.fast = bool(fast)
        self.stats = {"fast": 0, "reference": 0, "fallback": 0, "skipped": 0, "reset": 0,
                      "mask_reference": 0}
        # The per-step uncertainty of the closed form: [[dd]] (x W), entering by
        # B_o ([B_o, E_o] with process noise).
        inc = self._inc_fixed
        if inc is not None and self._W_fixed is not None:
            self._step_set = inc.cartesian(self._W_fixed)
            self._B_step = np.hstack([self.B_o, self._E_o])
        else:
            self._step_set, self._B_step = inc, self.B_o
        self._digest = self._structure_digest() if self.fast else b""
        # Window restart from a bounded hull only; after this many steps of
        # growth from Z_0^- (numerically unbounded hulls), restart anyway.
        self._grow_limit = 4 * ((window or 0) + self.mu_o) + 16
        self._warned_fallback = False
        # Exact mode's H-representation recursion (setmembership._hrep): fixed
        # uncertainty sets; their vertices are computed on first use.
        self._hrep = (window is None and self.fast and self._inc_fixed is not None
                      and not self._noise_varies)
        self._h_images: list[NDArray[np.float64]] | None = None
        self._h_floor_value: float | None = None
        self._h_noise: dict[bytes, list] = {}
        self.reset_state()

    # ------------------------------------------------------------------ setup helpers
    def _v_internal(self, V: ConstrainedZonotope | None) -> ConstrainedZonotope | None:
        """``F_b V``: a measurement-noise set in balanced output units."""
        return None if V is None else self._F_b @ V

    def _process_noise(self, k: int) -> ConstrainedZonotope | None:
        """``W_k`` (in the noise space of ``E``), or ``None``."""
        if not callable(self._w_spec):
            return self._W_fixed
        return _noise_set(f"process_noise({k})", self._w_spec(k), self._E_o.shape[1])

    def _measurement_noise(self, k: int) -> ConstrainedZonotope | None:
        """``F_b V_k`` (balanced output units), or ``None``."""
        if not callable(self._v_spec):
            return self._V_fixed
        return self._v_internal(_noise_set(f"measurement_noise({k})", self._v_spec(k),
                                           self._F_b.shape[1]))

    def _fixed_increment(self, spec: IncrementSpec) -> ConstrainedZonotope | None:
        """The increment set when it does not depend on ``k`` (validated), else None."""
        q = self.sys.q
        if spec is None:
            return ConstrainedZonotope.from_box(-np.ones(q), np.ones(q))
        if isinstance(spec, Box | ConstrainedZonotope):
            spec = _as_set("increment_set", spec, q)
            if not spec.is_bounded:
                raise DimensionError("increment_set must be bounded")
            return spec
        if callable(spec):
            return None
        r = as_vector("increment_set", spec, size=q)
        if (r < 0).any():
            raise DimensionError("increment_set bounds must be nonnegative")
        return ConstrainedZonotope.from_box(-r, r)

    def _increment(self, k: int) -> ConstrainedZonotope:
        """The increment set ``[[dd_k]]``."""
        if self._inc_fixed is not None:
            return self._inc_fixed
        dd = self._inc_spec(k)  # type: ignore[operator]
        if isinstance(dd, Box):
            dd = ConstrainedZonotope.from_box(dd.lo, dd.hi)
        if not isinstance(dd, ConstrainedZonotope):
            raise TypeError(f"increment_set({k}) must return a ConstrainedZonotope or a Box, "
                            f"got {type(dd).__name__}")
        if dd.dim != self.sys.q:
            raise DimensionError(f"increment_set({k}) has dimension {dd.dim}, "
                                 f"expected {self.sys.q}")
        return dd

    def _structure_digest(self) -> bytes:
        """Fingerprint of everything a window structure depends on (shared cache key)."""
        hsh = hashlib.blake2b(digest_size=20)
        inc = self._step_set
        Z0 = self._Z0_prior
        parts = [self.A_o, self._B_step, self.C_o, self.Gamma_o, self.P, Z0.G, Z0.A,
                 np.isinf(Z0.h)]
        for S in (inc, self._V_fixed):
            if S is not None:
                parts += [S.G, S.c, S.A, S.b, S.h, S.b_err, S.c_err]
            parts.append(np.array([S is None]))
        for a in parts:
            a = np.ascontiguousarray(a)
            hsh.update(str(a.shape).encode())
            hsh.update(a.tobytes())
        r_inc = inc.unbounded_radius if inc else 0.0
        hsh.update(repr((self._P_coords is None, min(Z0.unbounded_radius, r_inc),
                         self.window)).encode())
        return hsh.digest()

    def __copy__(self) -> SMFDO:
        """An independent copy (``copy.copy`` is ``copy.deepcopy`` here): the
        estimator's state (window history, warm-start bases, carried sets) is
        mutable, and a shallow copy shared it, so running the copy changed the
        original's later results (a false invalidation on consistent data)."""
        import copy

        return copy.deepcopy(self)

    def reset_state(self) -> None:
        """Forget all data and start again at ``k = 0``."""
        self.k = -1
        win = self.window
        # hulls of Z_(k-delta) .. Z_(k-1): the restart boxes of eq. (24)
        self._hulls: deque[Box] = deque(maxlen=win or 1)
        # the data (y_j, u_(j-1), dd_(j-1)) since k = 0 (while the recursion still
        # runs from Z_0^-) or of the last delta steps (once the window restarts)
        self._hist: list[_Entry] = []
        # the posterior, either a set or (model, c, b, h, c_err, b_err) of the fast path
        self._Z_src: object = None
        self._from_initial = True  # no reset since k = 0 (the closed forms from Z_0^- apply)
        self._windowing = False  # the window has restarted from a hull at least once
        self._u_pending: NDArray[np.float64] | None = None
        self._states: dict[tuple, object] = {}  # LP warm-start states, one per structure
        self._mask_keys: set[bytes] = set()  # missing-sample patterns with a structure
        self._depth = 0  # recursion steps since the start set of the current posterior
        self.first_inconsistent: int | None = None
        self._last_y = np.zeros(0)  # the last step's measurement (balanced units)
        self._h_fails = 0  # failed conversions to the H-representation in a row
        self._h_retry_at = 0  # first step at which the next conversion is tried
        self._warned_inconsistent = False
        self._in_run = False

    @property
    def _Z(self) -> ConstrainedZonotope | None:
        src = self._Z_src
        if isinstance(src, HState):
            return src.to_cz()
        if isinstance(src, tuple):
            model, c, b, h, c_err, b_err = src
            src = model.to_cz(c, b, h, c_err, b_err)
            self._Z_src = src
        return src  # type: ignore[return-value]

    @property
    def posterior_set(self) -> ConstrainedZonotope | None:
        """The current posterior set ``Z_k^+`` (eq. (21)) of the internal state, or ``None``.

        In the observer's internal coordinates ``z_o`` (see :attr:`restart_box`);
        ``None`` before the first measurement. A fast-path step's set is
        built from its closed form on first access.
        """
        return self._Z

    @property
    def exact_representation(self) -> HState | None:
        """Exact mode's carried H-representation of the posterior, or ``None``.

        ``H``, ``g`` (certified ``H z <= g``), ``lo``, ``hi`` (certified box)
        and ``V`` (approximate vertices) in the internal coordinates ``z_o``;
        ``None`` while the set recursion carries the posterior (windowed mode,
        before the posterior is bounded, or for sets too complex for it).
        """
        src = self._Z_src
        return src if isinstance(src, HState) else None

    @property
    def fast_path_instance(self) -> tuple[WindowModel, NDArray[np.float64], NDArray[np.float64],
                                          NDArray[np.float64]] | None:
        """``(model, c, b, h)`` of the last step if the compiled fast path solved it, else ``None``.

        For diagnostics and benchmarks: the window model (fixed structure), the
        centre of the posterior, and the data-dependent right-hand side and
        factor bounds of its LPs.
        """
        src = self._Z_src
        if not isinstance(src, tuple):
            return None
        model, c, b, h, _, _ = src
        return model, c, b, h

    @property
    def hull_from_state(self) -> bool:
        """Whether the disturbance is a coordinate subset of the internal state ``z_o``.

        Then the disturbance interval hull is read off the state's hull (no
        extra LPs); otherwise it has LPs of its own.
        """
        return self._P_coords is not None

    @property
    def restart_box(self) -> Box | None:
        """The box the window restarts from at the next step (eq. (24)), or ``None``.

        ``IH(Z_(k+1-delta))`` with the outward margin, in the observer's internal
        coordinates ``z_o = T_o D^-1 [x; d]`` (see the class notes; for a fully
        observable augmented pair of a well-scaled model, ``T_o = I``, ``D = I``);
        ``None`` in exact mode and until ``delta`` steps have been seen.
        """
        if self.window is None or len(self._hulls) < self.window:
            return None
        return Box(*self._restart_bounds(self._hulls[0]))

    def _start_mode(self, k: int) -> str:
        """How step ``k`` is computed: ``"box"`` (eq. (24), restart from IH(Z_(k-delta))),
        ``"init"`` (the whole history from Z_0^-), or ``"recursive"`` (one more step)."""
        win = self.window
        if win is not None and len(self._hulls) == win:
            lo, _ = self._restart_bounds(self._hulls[0])
            if (self._windowing or not self._from_initial or k > self._grow_limit
                    or np.isfinite(lo).all()):
                return "box"
        return "init" if self._from_initial else "recursive"

    # ------------------------------------------------------------------ fast path
    def _window_hist(self, entry: _Entry) -> list[_Entry]:
        """The data of the window's re-run ending at ``entry`` (eq. (24))."""
        win = self.window
        return [*self._hist[-(win - 1):], entry] if win > 1 else [entry]

    def _fast_step(self, k: int, mode: str, entry: _Entry):
        """Hulls of ``Z_k`` (and ``P Z_k``) by the closed form, or ``None`` (reference path)."""
        if (not self.fast or self._inc_fixed is None or self._noise_varies
                or mode == "recursive"):
            return None
        if self.window is None:
            # Exact mode: each closed form would be used once, and a cold simplex on
            # it costs more than the set recursion with HiGHS (84 vs 28 ms per step at
            # k = 100 on the paper example): the reference path is used.
            return None
        N = self.A_o.shape[0]
        P_extra = None if self._P_coords is not None else self.P
        inc, B_step, V = self._step_set, self._B_step, self._V_fixed
        hist = self._window_hist(entry) if mode == "box" else [*self._hist, entry]
        Y = np.array([e.y for e in hist])
        measured = ~np.isnan(Y)
        if measured.all():
            masks, mkey = None, b""
        else:
            masks = list(measured)
            mkey = np.packbits(measured).tobytes() + len(hist).to_bytes(4, "little")
            # ("init" structures are new at every step anyway: no budget there)
            if mode == "box" and mkey not in self._mask_keys:
                if len(self._mask_keys) >= MAX_MASK_STRUCTURES:
                    self.stats["mask_reference"] += 1
                    return None
                self._mask_keys.add(mkey)
        if mode == "box":
            win = self.window
            lo, hi = self._restart_bounds(self._hulls[0])
            free = np.isinf(lo)
            c_S, h_S = box_center_radius(lo, hi)
            b_S = np.zeros(0)
            c_S_err = b_S_err = None
            key = ("box", free.tobytes(), mkey)
            unbounded_radius = min(UNBOUNDED_RADIUS, inc.unbounded_radius)

            def build() -> WindowModel:
                return WindowModel(self.A_o, B_step, self.C_o, self.Gamma_o, increment=inc,
                                   G_S=np.eye(N), A_S=np.zeros((0, N)), free_S=free, s=win,
                                   first_posterior=False, P=P_extra,
                                   unbounded_radius=unbounded_radius, noise=V, masks=masks)
        else:  # "init": the whole history from Z_0^-
            Z0 = self._Z0_prior
            c_S, b_S, h_S = Z0.c, Z0.b, Z0.h
            c_S_err, b_S_err = Z0.c_err, Z0.b_err
            key = ("init", k, mkey)
            unbounded_radius = min(Z0.unbounded_radius, inc.unbounded_radius)

            def build() -> WindowModel:
                return WindowModel(self.A_o, B_step, self.C_o, self.Gamma_o, increment=inc,
                                   G_S=Z0.G, A_S=Z0.A, free_S=np.isinf(Z0.h), s=k,
                                   first_posterior=True, P=P_extra,
                                   unbounded_radius=unbounded_radius, noise=V, masks=masks)
        model = MODEL_CACHE.get((self._digest, *key), build)
        if not model.usable:
            return None
        if key[0] == "box":
            state = self._states.get(key)
            if state is None:
                state = self._states[key] = model.new_state()
        else:  # each "init" structure is used once per run: a cold start
            state = model.new_state()
        if self.sys.p:
            steps = hist if len(hist) == model.s else hist[1:]
            U = np.array([e.u for e in steps])
        else:
            U = np.zeros((model.s, 0))
        Y_err = None
        if self._Du is not None:
            Y_err = np.array([np.zeros(self.sys.l) if e.yerr is None else e.yerr
                              for e in hist])
        c, b, h, c_err, b_err = model.assemble(c_S, b_S, h_S, Y, U, c_S_err=c_S_err,
                                               b_S_err=b_S_err, data_rtol=self.data_rtol,
                                               Y_err=Y_err)
        y_scale = float(np.abs(Y[measured]).max(initial=0.0))
        out = model.hull(c, b, h, y_scale, state, b_err, c_err)
        if out is None:
            return None
        lo, hi = out
        box_o = trusted_box(lo[:N], hi[:N])
        if self._P_coords is not None:
            j = self._P_coords
            box = trusted_box(lo[j], hi[j])
        else:
            box = trusted_box(lo[N:], hi[N:])
        return (model, c, b, h, c_err, b_err), box, box_o

    # ------------------------------------------------------------------ exact mode
    def _to_hstate(self, Z: ConstrainedZonotope) -> HState | None:
        """The H-representation of a bounded posterior (certified facets and box,
        :func:`setobs.geometry.polytope.to_hrep`'s construction), or ``None``."""
        from ..exceptions import SetobsError
        from ..geometry.polytope import BUDGET_STATUS, verified_facets
        from ..geometry.zonotope import support_unwarned

        try:
            box, _ = hull_with_status(Z)
            if not box.is_bounded:
                return None
            try:
                V, F, gF, flats = verified_facets(Z, max_lps=H_CONVERSION_LPS,
                                                  rtol=HREP_CONVERT_RTOL,
                                                  max_facets=4 * H_MAX_NORMALS)
            except SetobsError as exc:
                if getattr(exc, "status", "") == BUDGET_STATUS:
                    return None  # too complex for the H-recursion: no lax retry
                # Facets confirmed to VERTEX_RTOL of the set's size only: an
                # excess of that size, absolute, outlives a later contraction of
                # the set. Not while the set is far larger than one step's
                # uncertainty (the transient before the data bound it).
                if float(np.max(box.hi - box.lo)) > H_LAX_SIZE_FACTOR * self._h_floor():
                    raise
                V, F, gF, flats = verified_facets(Z, max_lps=H_CONVERSION_LPS,
                                                  max_facets=4 * H_MAX_NORMALS)
            g_flat = [support_unwarned(Z, f) for f in flats] + \
                [support_unwarned(Z, -f) for f in flats]
        except SetobsError:
            return None
        # Flat only where the data make it so (the measured rows without noise): a
        # set whose width is below the enumeration's tolerance relative to its
        # coordinates (growing states) is left to the set recursion.
        n_flat = int((~np.isnan(self._last_y)).sum()) if self._V_fixed is None else 0
        if flats.shape[0] > n_flat:
            return None
        H = np.vstack([F, flats, -flats])
        g = np.concatenate([gF, np.asarray(g_flat, dtype=float)])
        if not np.isfinite(g).all() or V.shape[0] > H_MAX_VERTICES or \
                H.shape[0] > H_MAX_NORMALS or not vertices_match(V, H, g):
            return None
        return HState(H, g, box.lo, box.hi, V)

    def _h_floor(self) -> float:
        """Largest width of one step's uncertainty in ``z_o`` (``B_o`` times the
        increment set, with ``E_o`` times the process noise)."""
        if self._h_floor_value is None:
            w = hull_with_status(self._B_step @ self._step_set)[0]
            self._h_floor_value = float(np.max(w.hi - w.lo, initial=0.0))
        return self._h_floor_value

    def _h_setup(self) -> list[NDArray[np.float64]]:
        """Vertices of the increment (and process-noise) sets mapped into the state."""
        if self._h_images is None:
            from ..geometry.polytope import vertices

            images = [vertices(self._inc_fixed) @ self.B_o.T]
            if self._W_fixed is not None:
                images.append(vertices(self._W_fixed) @ self._E_o.T)
            self._h_images = images
        return self._h_images

    def _h_clips(self, y: NDArray[np.float64], m: NDArray[np.bool_]) -> list:
        """The measurement of eq. (21) as hyperplanes (no noise) or half-spaces of
        ``y - F_b V`` (its H-representation on the measured rows, computed once
        per missing-sample pattern)."""
        C = self.C_o[m]
        ym = y[m]
        V = self._V_fixed
        if V is None:
            return [(C[i], float(ym[i]), True) for i in range(C.shape[0])]
        key = m.tobytes()
        hr = self._h_noise.get(key)
        if hr is None:
            from ..geometry.polytope import to_hrep

            hr = self._h_noise[key] = to_hrep(V.project(np.flatnonzero(m).tolist()))
        # v = y - C z in V_m:  H_v (y - C z) <= k_v,  E_v (y - C z) = f_v
        out = [(-(hv @ C), float(kv - hv @ ym), False) for hv, kv in zip(hr.H, hr.k,
                                                                         strict=True)]
        out += [(-(ev @ C), float(fv - ev @ ym), True) for ev, fv in zip(hr.E, hr.f,
                                                                        strict=True)]
        return out

    def _h_back_off(self, step: int) -> None:
        """After a failed conversion or step: the next conversion is tried at
        ``step + 2^fails`` (at most 64 steps later)."""
        self._h_fails += 1
        self._h_retry_at = step + min(2 ** self._h_fails, 64)

    def _hrep_step(self, e: _Entry):
        """One exact step by the H-representation recursion (:mod:`._hrep`), or
        ``None`` (the reference path decides it)."""
        st = self._Z_src
        if not isinstance(st, HState):
            if not isinstance(st, ConstrainedZonotope) or self.k + 1 < self._h_retry_at:
                return None
            st = self._to_hstate(st)
            if st is None:  # not bounded yet, or the conversion failed
                self._h_back_off(self.k + 1)
                return None
            self._h_fails = 0
            self._Z_src = st
        N = self.A_o.shape[0]
        y = e.y
        m = ~np.isnan(y)
        shift = np.zeros(N)
        if self.sys.p and e.u is not None:
            shift = self.Gamma_o @ e.u
        flat_cand = None
        if self._V_fixed is None and m.any():
            Cm = self.C_o[m]
            flat_cand = Cm / np.linalg.norm(Cm, axis=1)[:, None]
        geo = step_geometry(st.V, self.A_o, shift, self._h_setup(),
                            self._h_clips(y, m) if m.any() else [], flat_cand)
        if geo is None or geo[0].shape[0] > H_MAX_VERTICES or geo[1].shape[0] > H_MAX_NORMALS:
            # too complex, or the approximate geometry sees no consistent point: the
            # set recursion decides this step; back off before converting again
            self._h_back_off(self.k + 2)
            return None
        V_new, H_new = geo
        H_new = snap_normals(H_new, st.H)
        inc, B_step, Vn = self._step_set, self._B_step, self._V_fixed
        P_rows = [H_new] if self._P_coords is not None else [self.P, H_new]
        P_ext = np.vstack(P_rows)
        mkey = m.tobytes()
        key = ("hrep", st.H.shape, st.H.tobytes(), H_new.shape, H_new.tobytes(), mkey)
        H_prev = st.H

        def build() -> WindowModel:
            mp = H_prev.shape[0]
            G_S = np.hstack([np.eye(N), np.zeros((N, mp))])
            return WindowModel(self.A_o, B_step, self.C_o, self.Gamma_o, increment=inc,
                               G_S=G_S, A_S=structure_A(H_prev),
                               free_S=np.zeros(N + mp, dtype=bool), s=1,
                               first_posterior=False, P=P_ext,
                               unbounded_radius=min(UNBOUNDED_RADIUS, inc.unbounded_radius),
                               noise=Vn, masks=[m])

        model = MODEL_CACHE.get((self._digest, *key), build)
        if not model.usable:
            return None
        state = self._states.get(key)
        if state is None:
            if len(self._states) > 64:
                self._states.clear()
            state = self._states[key] = model.new_state()
        c_S, b_S, h_S, b_S_err = st.start()
        U = (e.u if e.u is not None else np.zeros(self.sys.p))[None, :] if self.sys.p \
            else np.zeros((1, 0))
        Y_err = None if e.yerr is None else e.yerr[None, :]
        c, b, h, c_err, b_err = model.assemble(c_S, b_S, h_S, y[None, :], U,
                                               b_S_err=b_S_err, data_rtol=self.data_rtol,
                                               Y_err=Y_err)
        y_scale = float(np.abs(y[m]).max(initial=0.0))
        out = model.hull(c, b, h, y_scale, state, b_err, c_err)
        if out is None:
            return None
        lo, hi = out
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
            return None
        box_o = trusted_box(lo[:N], hi[:N])
        if self._P_coords is not None:
            j = self._P_coords
            box = trusted_box(lo[j], hi[j])
            g = hi[N:]
        else:
            q = self.P.shape[0]
            box = trusted_box(lo[N:N + q], hi[N:N + q])
            g = hi[N + q:]
        Zd = self.P @ model.to_cz(c, b, h, c_err, b_err) if self.keep_sets else None
        # The carried set covers the rounding of the objectives' products with the
        # generators (P_ext G, the model's G = [A_o, 0, B_o G_D]), which the LP
        # certificate takes as given: gamma-bounded, on the factor ranges. (Not the
        # reported bounds' relative margin: that, carried from step to step, grows
        # with the set recursion's gain and costs exactness.)
        rng_z = np.abs(model.G) @ h
        gm = gamma(2 * (N + model.G.shape[1]) + 4)
        lo_c = round_down(box_o.lo - gm * rng_z)
        hi_c = round_up(box_o.hi + gm * rng_z)
        g = round_up(g + gm * (np.abs(H_new) @ rng_z))
        V_t = tidy_vertices(V_new, H_new, g)
        if not vertices_match(V_t, H_new, g):
            # The normals from the approximate geometry miss a facet: carrying
            # {H z <= g} would be an outer set from the next step on. This step's
            # bounds are exact (its LPs ran over the exact set); carry that set.
            self._h_back_off(self.k + 1)
            return model.to_cz(c, b, h, c_err, b_err), box, box_o, Zd
        return HState(H_new, g, lo_c, hi_c, V_t), box, box_o, Zd

    # ------------------------------------------------------------------ recursion
    def _prior(self, Z: ConstrainedZonotope, e: _Entry) -> ConstrainedZonotope:
        """Eq. (20) with process noise: ``A_o Z + B_o Z^Delta + E_o W + Gamma_o u``.

        The centre's rounding bound goes through ``A_o`` as factors once it is
        above rounding level (:func:`~setobs.geometry.zonotope.absorb_center_error`).
        """
        Z = absorb_center_error(Z, CENTER_ERROR_ABSORB_RTOL)
        Zp = self.A_o @ Z + self.B_o @ e.dd
        if e.w is not None:
            Zp = Zp + self._E_o @ e.w
        u = e.u
        if u is not None and self.sys.p:
            v = self.Gamma_o @ u
            err = self.data_rtol * (np.abs(self.Gamma_o) @ np.abs(u)) if self.data_rtol \
                else None
            Zp = Zp.minkowski_sum(v, err=err)
        return Zp

    def _posterior(self, Zp: ConstrainedZonotope, e: _Entry,
                   depth: int) -> ConstrainedZonotope:
        """Eq. (21): ``Zp ∩ {z : C_o z in y - F_b V}`` on the measured rows of ``y``
        (balanced units); with no noise set, ``{z : C_o z = y}``; with nothing
        measured, ``Zp`` (a prediction step).

        ``y`` is known to within ``data_rtol |y|`` plus the model allowance of
        ``depth`` recursion steps (see :mod:`setobs.setmembership._window`) and
        the feedthrough's rounding.
        """
        y = e.y
        m = ~np.isnan(y)
        if not m.any():
            return Zp
        nD = self._inc_fixed.n_gen if self._inc_fixed is not None else self.sys.q
        nV = 0 if e.v is None else e.v.n_gen
        rtol = self.data_rtol + model_rtol(depth, self.A_o.shape[0], self.sys.p, nD + nV)
        ym = y[m]
        y_err = rtol * np.abs(ym)
        if e.yerr is not None:
            y_err = y_err + e.yerr[m]
        C = self.C_o if m.all() else self.C_o[m]
        if e.v is None:
            return Zp.intersect_affine(C, ym, y_err=y_err)
        V = e.v
        # the set y - V_m (rows m of F_b V): centre y - c_V (rounded once), the
        # noise's own constraints, generators -G_V
        cY = ym - V.c[m]
        cY_err = UNIT_ROUNDOFF * np.abs(cY) + V.c_err[m] + y_err
        Yset = trusted_cz(-V.G[m], cY, V.A, V.b, V.h, V.unbounded_radius, cY_err,
                                            V.b_err)
        return Zp.intersect(Yset, R=C)

    @staticmethod
    def _restart_bounds(box: Box) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Bounds of the restart box: a coordinate unbounded on one side is made
        free both ways (an outer answer; extended CZs have no one-sided boxes)."""
        lo, hi = box.lo, box.hi
        free = np.isinf(lo) | np.isinf(hi)
        if free.any():
            lo, hi = np.where(free, -np.inf, lo), np.where(free, np.inf, hi)
        return lo, hi

    @classmethod
    def _box_cz(cls, box: Box) -> ConstrainedZonotope:
        return ConstrainedZonotope.from_box(*cls._restart_bounds(box))

    def _entry(self, y: ArrayLike, u_prev: ArrayLike | None, u: ArrayLike | None
               ) -> tuple[_Entry, NDArray[np.float64] | None]:
        """Validate one step's data and collect its uncertainty sets; also returns the
        validated current input ``u_k`` (or ``None``)."""
        p = self.sys.p
        yraw = as_vector("y", y, size=self.sys.l, allow_nan=True)
        uv = None
        if u_prev is not None:
            uv = as_vector("u_prev", u_prev, size=p)
        elif p and self.k >= 0:
            if self._u_pending is None:
                raise DimensionError(
                    f"u_prev (length {p}) is required after the first step of a "
                    "system with inputs")
            uv = self._u_pending
        uk = None
        if u is not None:
            if not p:
                raise DimensionError("u is given but the system has no inputs")
            uk = as_vector("u", u, size=p)
        k = self.k + 1
        yerr = None
        if self._Du is not None:
            if uk is None:
                raise DimensionError(
                    "u (the input at this step) is required: the system has a "
                    "feedthrough D_u (y = Xi x + D_u u)")
            Du = self._Du
            absDu_u = np.abs(Du) @ np.abs(uk)
            yraw = yraw - Du @ uk
            # rounding of D_u u (gamma_p) and of the subtraction, the input's and
            # the measurement's representation errors
            yerr = ((gamma(p + 1) + self.data_rtol) * absDu_u + UNIT_ROUNDOFF * np.abs(yraw)
                    + self.data_rtol * np.abs(yraw + Du @ uk)) * (1.0 + gamma(p + 3))
            yerr = np.where(np.isnan(yerr), 0.0, yerr) / self._dy
        yv = yraw / self._dy
        if k > 0:
            dd = self._increment(k - 1)
            w = self._process_noise(k - 1)
        else:
            dd = w = None
        return _Entry(yv, uv, dd, w, self._measurement_noise(k), yerr), uk

    @with_single_threaded_blas
    def update(self, y: ArrayLike, u_prev: ArrayLike | None = None, *,
               u: ArrayLike | None = None) -> SMFDOStep:
        """Process the measurement ``y_k`` (and the input ``u_(k-1)`` applied before it).

        Parameters
        ----------
        y : array_like, shape (l,)
            Measurement at step ``k``; NaN entries are outputs not measured at
            this step (all NaN: a prediction step).
        u_prev : array_like, shape (p,), optional
            Known input ``u_(k-1)`` (ignored at ``k = 0``). May be omitted right
            after :meth:`run` was given ``U`` with ``N`` rows (its last row is
            ``u_(k-1)``), or after an ``update`` that was given ``u``.
        u : array_like, shape (p,), optional
            The input ``u_k`` at this step: required when the system has a
            feedthrough ``D_u`` (``y_k = Xi x_k + D_u u_k + F v_k``).

        Raises
        ------
        ModelInvalidatedError
            If no state and disturbance history explains the data
            (``on_inconsistent="raise"``).
        """
        e, self._u_pending = self._entry(y, u_prev, u)
        k = self.k + 1
        mode = "init" if k == 0 else self._start_mode(k)
        if self._hrep and k > 0:
            hstep = self._hrep_step(e)
            if hstep is not None:
                self.stats["fast"] += 1
                hst, box, box_o, Zd = hstep
                self._depth = 0
                return self._commit(k, mode, hst, box, box_o, Zd, e, "ok")
        fast = self._fast_step(k, mode, e)
        if fast is not None:
            self.stats["fast"] += 1
            Z_src, box, box_o = fast
            Zd = None
            if self.keep_sets:
                model, c, b, h, c_err, b_err = Z_src
                Z_src = model.to_cz(c, b, h, c_err, b_err)
                Zd = self.P @ Z_src
            self._depth = k if mode == "init" else self.window
            return self._commit(k, mode, Z_src, box, box_o, Zd, e, "ok")
        self.stats["reference"] += 1
        if k == 0:
            Zp = self._Z0_prior
            depth = 0
        elif mode == "box":
            # Lines 12-13 / eq. (24): re-run the last delta steps from IH(Z_(k-delta)).
            Z = self._box_cz(self._hulls[0])
            Zp = None
            hist = self._window_hist(e)
            for i, ei in enumerate(hist):
                Zp = self._prior(Z, ei)
                if i < len(hist) - 1:
                    Z = self._posterior(Zp, ei, i + 1)
            depth = len(hist)
        else:
            Zp = self._prior(self._Z, e)
            depth = self._depth + 1
        Z = self._posterior(Zp, e, depth)
        status = "ok"
        try:
            Zd, box, box_o, fell_back = self._bounds(Z)
        except EmptySetError:
            msg = (f"the measurement at step k={k} is inconsistent with the model and the "
                   "uncertainty sets (empty posterior)")
            if self.on_inconsistent == "raise":
                raise ModelInvalidatedError(msg, k) from None
            # One-step prior from the last valid posterior (the windowed re-run may
            # pass through the same inconsistency again).
            Zp1 = self._Z0_prior if k == 0 else self._prior(self._Z, e)
            if self.on_inconsistent == "skip":
                # The measurement is dropped, here and in the window's history.
                e = e.skipped()
                Z = Zp1
                depth = self._depth + 1 if k else 0
                Zd, box, box_o, fell_back = self._bounds(Z)
                status = "skipped"
            else:
                Z = self._handle_empty(k, Zp1, e, msg)
                depth = 0
                Zd, box, box_o, fell_back = self._bounds(Z)
                # The window restarts from the reset set: eq. (24) is applied again
                # only once delta consistent steps have been collected.
                self._hulls.clear()
                self._hist.clear()
                self._from_initial = False
                self._windowing = False
                status = "reset"
            self.stats[status] += 1
            if self.first_inconsistent is None:
                self.first_inconsistent = k
            if not self._in_run and not self._warned_inconsistent:
                self._warned_inconsistent = True
                warnings.warn(
                    f"{msg}: {'skipped' if status == 'skipped' else 'reset'} "
                    "(status recorded per step; warned once per observer)",
                    ModelInvalidatedWarning, stacklevel=2)
        if fell_back:
            status = "fallback" if status == "ok" else status
            self.stats["fallback"] += 1
            if not self._warned_fallback:
                self._warned_fallback = True
                warnings.warn(
                    f"SMFDO step k={k}: an LP failed under every solver setting; the bounds "
                    "of this step are wider (still certified) and flagged status='fallback' "
                    "(warned once per observer)", SolverWarning, stacklevel=2)
        self._depth = depth
        return self._commit(k, mode, Z, box, box_o, Zd if self.keep_sets else None, e,
                            status)

    def _commit(self, k, mode, Z_src, box, box_o, Zd, e: _Entry, status) -> SMFDOStep:
        self.k = k
        self._last_y = e.y
        self._Z_src = Z_src
        if mode == "box":
            self._windowing = True
        if self.window is not None:  # (exact mode runs the plain recursion: no history)
            self._hist.append(e)  # e.dd is None at k = 0 (never used)
            # The restart box of eq. (24) gets the same relative margin as the
            # reported bounds: the set recursion itself rounds (O(eps)), and a
            # box without margin can make a thin set (states pinned to rounding
            # level) empty at a later step.
            self._hulls.append(trusted_box(*self._outward(box_o.lo, box_o.hi)))
            if self._windowing and len(self._hist) > self.window:
                del self._hist[:len(self._hist) - self.window]
        lo, hi = self._outward(box.lo, box.hi)
        est = box_center(lo, hi)
        rad = float(np.max(0.5 * (hi - lo), initial=0.0))
        if status == "ok" and not (np.isfinite(lo).all() and np.isfinite(hi).all()):
            status = "unbounded"
        return SMFDOStep(k, est, lo, hi, rad, Zd, status)

    def _bounds(self, Z: ConstrainedZonotope):
        """Disturbance set ``P Z``, its hull, (windowed mode) the hull of ``Z``, and
        whether an LP fell back."""
        fb_o = False
        box_o = None
        if self.window is not None:
            box_o, fb_o = hull_with_status(Z)
        Zd = self.P @ Z
        if box_o is not None and self._P_coords is not None:
            j = self._P_coords
            return Zd, Box(box_o.lo[j], box_o.hi[j]), box_o, fb_o
        box_d, fb_d = hull_with_status(Zd)
        return Zd, box_d, box_o, fb_o or fb_d

    def _outward(self, lo, hi):
        a, b = np.abs(lo), np.abs(hi)
        if np.isinf(a).any() or np.isinf(b).any():
            a[np.isinf(a)] = 0.0
            b[np.isinf(b)] = 0.0
        scale = np.maximum(1.0, np.maximum(a, b))
        return lo - self.margin * scale, hi + self.margin * scale

    def _handle_empty(self, k: int, Zp: ConstrainedZonotope, e: _Entry, msg: str):
        """``on_inconsistent="reset"``: the posterior of an inflated box of ``Zp``."""
        try:
            hull, _ = hull_with_status(Zp)
        except EmptySetError:
            raise ModelInvalidatedError(msg + " (the prior itself is empty)", k) from None
        w = np.where(np.isfinite(hull.width), hull.width, 0.0)
        scale = 1.0 + float(np.abs(np.where(np.isfinite(hull.lo), hull.lo, 0.0)).max(initial=0.0))
        factor = self.reset_inflation
        for _ in range(40):  # inflate geometrically until the measurement is explainable
            pad = factor * (w + scale)
            Zr = self._posterior(self._box_cz(Box(hull.lo - pad, hull.hi + pad)), e, 0)
            if not Zr.is_empty():
                return Zr
            factor *= 4.0
        raise ModelInvalidatedError(msg + " (no reset box explains it)", k)

    @with_single_threaded_blas
    def run(self, Y: ArrayLike, U: ArrayLike | None = None, *,
            progress: bool = False) -> SMFDOResult:
        """Process a whole record from the current state.

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measurements ``y_0 .. y_(N-1)`` (continuing from the current step
            when the observer has already seen data). NaN entries: not
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

        Returns
        -------
        SMFDOResult
            ``estimate``, ``lo``, ``hi`` of shape ``(N, q)``, ``error_bound`` and
            ``status`` ``(N,)``, ``first_inconsistent``.

        Warns
        -----
        ModelInvalidatedWarning
            Once, if measurements of this record were skipped or reset.
        """
        Ya = as_matrix("Y", Y, cols=self.sys.l, allow_nan=True)
        N = Ya.shape[0]
        Ua = None
        if not self.sys.p and U is not None and np.size(U):
            raise DimensionError("U is given but the system has no inputs (no Gamma): pass "
                                 "U=None, or build the system with its input matrix")
        if self.sys.p:
            if U is None:
                raise DimensionError(f"U is required: the system has {self.sys.p} input(s)")
            Ua = as_matrix("U", U, cols=self.sys.p)
            if Ua.shape[0] not in (N, N - 1):
                raise DimensionError(f"U must have N or N-1 = {N}/{N - 1} rows, got {Ua.shape[0]}")
            if self._Du is not None and Ua.shape[0] != N:
                raise DimensionError(
                    f"U must have N = {N} rows: the system has a feedthrough D_u, so "
                    "y_k needs u_k")
            if self.k >= 0 and self._u_pending is None and N:
                raise DimensionError(
                    "the input applied before the first step of this record is unknown: "
                    "give the previous run() its U with N rows (the last row is that "
                    "input), or continue with update(y, u_prev)")
        steps = []
        with_u = self._Du is not None
        bar = progress_bar(progress, total=N, unit="step", desc="SMFDO", mininterval=0.5)
        self._in_run = True
        try:
            for j in range(N):
                if j % 200 == 0 and j:
                    bar.update(200)
                u = Ua[j - 1] if (Ua is not None and j >= 1) else None
                steps.append(self.update(Ya[j], u, u=Ua[j] if with_u else None))
            bar.update(N - bar.n)
        finally:
            self._in_run = False
            bar.close()
        if Ua is not None and Ua.shape[0] == N and N:
            self._u_pending = Ua[N - 1].copy()
        q = self.sys.q
        status = np.array([s.status for s in steps], dtype="<U9")
        bad = np.flatnonzero((status == "skipped") | (status == "reset"))
        first = int(steps[bad[0]].k) if bad.size else None
        if bad.size:
            what = self.on_inconsistent
            warnings.warn(
                f"{bad.size} of {N} measurements were inconsistent with the model and the "
                f"uncertainty sets (first at k={first}) and were "
                f"{'skipped' if what == 'skip' else 'handled by a reset'}: the bands at "
                "those steps are not the model's consistent sets (see result.status, "
                "result.first_inconsistent)", ModelInvalidatedWarning,
                stacklevel=3)  # run -> the BLAS-limit wrapper -> the caller
        return SMFDOResult(
            np.array([s.estimate for s in steps]).reshape(N, q),
            np.array([s.lo for s in steps]).reshape(N, q),
            np.array([s.hi for s in steps]).reshape(N, q),
            np.array([s.error_bound for s in steps]),
            steps,
            status,
            first,
            self.sys.dt,
            tuple(self.sys.disturbance_names),
        )

    def __repr__(self) -> str:
        mode = "exact" if self.window is None else f"window={self.window}"
        return f"SMFDO({self.sys!r}, {mode}, k={self.k})"
