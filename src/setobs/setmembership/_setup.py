"""The SMFDO's model (frozen): coordinates, uncertainty and noise sets, the recursion's
algebra, data entries."""

from __future__ import annotations

import hashlib
import numbers
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import lazy_module
from .._rounding import UNIT_ROUNDOFF, gamma, pow2_inverse, round_down, round_up
from .._validation import as_matrix, as_vector, check_real_scalar
from ..analysis import bounded_do_exists, observability_decomposition
from ..exceptions import (
    ArgumentError,
    DimensionError,
    ExistenceError,
    ImmutableError,
    InvalidValueError,
    ModelInvalidatedError,
)
from ..geometry import Box, ConstrainedZonotope
from ..geometry.box import trusted_box
from ..geometry.zonotope import absorb_center_error, hull_with_status, trusted_cz
from ..models.linear import LinearSystem
from ..tolerances import CENTER_ERROR_ABSORB_RTOL
from ._restart import RestartPolytope
from ._window import WindowModel, model_rtol

# The compiled margins (numba) load on the first step, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")

__all__ = ["MODEL_CACHE", "Entry", "IncrementSpec", "ModelCache", "NoiseSpec", "SMFDOModel",
           "as_set", "check_window", "noise_set", "normalize_free_columns"]

IncrementSpec = (ConstrainedZonotope | Box | ArrayLike | Callable[[int], ConstrainedZonotope]
                 | None)


class ModelCache:
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


MODEL_CACHE = ModelCache()


def check_window(window: object) -> int | None:
    if window is None:
        return None
    if isinstance(window, bool | np.bool_) or not isinstance(window, numbers.Real):
        raise ArgumentError(f"window must be a positive integer or None (exact mode), "
                            f"got {window!r}")
    w = float(window)
    if not np.isfinite(w) or w != int(w) or w < 1:
        raise InvalidValueError(f"window must be a positive integer or None (exact mode), "
                             f"got {window!r}")
    return int(w)


def as_set(name: str, value: object, dim: int) -> ConstrainedZonotope | None:
    """A ConstrainedZonotope from a CZ, a Box, or None; anything else is refused."""
    if value is None:
        return None
    if isinstance(value, Box):
        value = ConstrainedZonotope.from_box(value.lo, value.hi)
    if not isinstance(value, ConstrainedZonotope):
        raise ArgumentError(
            f"{name} must be a ConstrainedZonotope or a Box (e.g. Box(lo, hi)), got "
            f"{type(value).__name__}")
    if value.dim != dim:
        raise DimensionError(f"{name} must have dimension {dim}, got {value.dim}")
    return value


NoiseSpec = (ConstrainedZonotope | Box | ArrayLike | Callable[[int], object] | None)


def noise_set(name: str, value: object, dim: int) -> ConstrainedZonotope | None:
    """A bounded noise set from a CZ, a Box, per-channel radii (a vector, or a scalar
    for every channel), or None (no noise)."""
    if value is None:
        return None
    if isinstance(value, Box | ConstrainedZonotope):
        value = as_set(name, value, dim)
        if not value.is_bounded:
            raise InvalidValueError(
                f"{name} must be bounded (an output that is not measured at a step is "
                "NaN in Y, not unbounded noise)")
        return value
    if isinstance(value, str | bytes) or callable(value):
        raise ArgumentError(f"{name} must be a ConstrainedZonotope, a Box, per-channel radii "
                            f"or a callable k -> set, got {type(value).__name__}")
    r = np.asarray(value)
    if r.ndim == 0:
        r = np.full(dim, check_real_scalar(name, value, nonnegative=True))
    r = as_vector(name, r, size=dim)
    if (r < 0).any():
        raise InvalidValueError(f"{name} radii must be nonnegative, got {r}")
    return ConstrainedZonotope.from_box(-r, r)


class Entry(NamedTuple):
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

    def skipped(self) -> Entry:
        """The same step with its measurement dropped."""
        return self._replace(y=np.full_like(self.y, np.nan), yerr=None)


def normalize_free_columns(Z: ConstrainedZonotope) -> ConstrainedZonotope:
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


class SMFDOModel:
    """The SMFDO's model: everything its arguments determine, computed once, then frozen.

    Theorem 1's check, the observable coordinates (balanced), the uncertainty and
    noise sets in them, the maps of the reported quantities (``P``, the state map),
    the restart polytope's structure, and the recursion's algebra on them (eqs.
    (20)-(21): :meth:`prior`, :meth:`posterior`, :meth:`bounds`). Steps never change
    it (assigning an attribute raises :class:`~setobs.exceptions.ImmutableError`):
    the estimator's mutable state is :class:`setobs.setmembership._state.SMFDOState`,
    and :class:`~setobs.SMFDO` runs its engines over the two.
    """

    # ------------------------------------------------------------------ setup helpers
    def extra_rows(self) -> NDArray[np.float64]:
        """The rows the fast paths bound beyond the coordinates of ``z``: ``P`` unless it
        selects coordinates, then the state map unless it does (state bounds); kept
        as ``_hull_rows``."""
        parts = [] if self.P_coords is not None else [self.P]
        if self.state_bounds and self.X_coords is None:
            parts.append(self.Mx)
        return np.vstack(parts) if parts else np.zeros((0, self.A_o.shape[0]))

    def split_hull(self, lo: NDArray[np.float64], hi: NDArray[np.float64]):
        """The fast paths' hull bounds (the coordinates of ``z``, then the rows of
        ``_hull_rows``, then any rows of the caller's) as ``(box_o, box, box_x,
        rest)``: the hulls of ``z``, of ``P z`` and (``state_bounds``, else ``None``)
        of the state, and the index of the caller's rows."""
        N = self.A_o.shape[0]
        box_o = trusted_box(lo[:N], hi[:N])
        at = N
        if self.P_coords is not None:
            j = self.P_coords
            box = trusted_box(lo[j], hi[j])
        else:
            q = self.P.shape[0]
            box = trusted_box(lo[N:N + q], hi[N:N + q])
            at += q
        box_x = None
        if self.state_bounds:
            if self.X_coords is not None:
                box_x = self.coordinate_states(lo[:N], hi[:N])
            else:
                n = self.sys.n
                box_x = trusted_box(lo[at:at + n], hi[at:at + n])
                at += n
        return box_o, box, box_x, at

    def _reported_rows(self) -> NDArray[np.int64]:
        """The rows of the fast paths' hull bounds (:meth:`split_hull`'s order) whose
        bands the step reports: ``P z`` and, with ``state_bounds``, the states (a state
        that is a coordinate of ``z`` by that coordinate's row; its band is that row's
        scaled by a power-free factor, so the same fraction of it)."""
        N = self.A_o.shape[0]
        rows = [np.asarray(self.P_coords, dtype=np.int64) if self.P_coords is not None
                else np.arange(N, N + self.P.shape[0])]
        at = N + (0 if self.P_coords is not None else self.P.shape[0])
        if self.state_bounds:
            if self.X_coords is not None:
                nz = self.X_scale != 0
                rows.append(np.asarray(self.X_coords, dtype=np.int64)[nz])
            else:
                rows.append(np.arange(at, at + self.sys.n))
        return np.unique(np.concatenate(rows)) if rows else np.zeros(0, dtype=np.int64)

    def coordinate_states(self, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> Box:
        """The states' box from the box of ``z_o`` when the state map has at most one
        nonzero per row (``x_i = s_i z_j``): the products rounded outward (exact for
        powers of two); a zero row (a state on the unobservable part only) gets
        ``[0, 0]`` here."""
        j, sc = self.X_coords, self.X_scale
        with np.errstate(invalid="ignore"):  # (0 * inf on a zero row: set to 0 below)
            a, b = sc * lo[j], sc * hi[j]
        zero = sc == 0.0
        a[zero] = b[zero] = 0.0  # (0 * inf)
        xlo, xhi = np.minimum(a, b), np.maximum(a, b)
        exact = (sc == 1.0) | zero
        xlo = np.where(exact, xlo, round_down(xlo))
        xhi = np.where(exact, xhi, round_up(xhi))
        return trusted_box(xlo, xhi)

    def v_internal(self, V: ConstrainedZonotope | None) -> ConstrainedZonotope | None:
        """``F_b V``: a measurement-noise set in balanced output units."""
        return None if V is None else self.F_b @ V

    def _unobservable_tracker(self, dec, dz, X0, D0, E):
        """The tracker of the unobservable coordinates, or ``None`` when ``X0`` (with
        ``D0``) does not bound them (:mod:`setobs.setmembership._unobservable`)."""
        from ._unobservable import UnobservableTracker

        n, q = self.sys.n, self.sys.q
        if X0 is None or not X0.is_bounded:
            return None
        Tb = dec.T_obar / dz[None, :]
        S = Tb[:, :n] @ X0
        if q:
            if np.any(Tb[:, n:] != 0.0):
                if D0 is None or not D0.is_bounded:
                    return None
                S = S + Tb[:, n:] @ D0
        hull = S.interval_hull()
        if not (np.isfinite(hull.lo).all() and np.isfinite(hull.hi).all()):
            return None
        E_bar = Tb @ np.vstack([E, np.zeros((q, E.shape[1]))])
        return UnobservableTracker(dec.A_21, dec.A_obar, dec.B_obar, dec.Gamma_obar, E_bar,
                                   hull.lo, hull.hi, self.data_rtol)

    def _startup_model(self, dec, dz, X0, D0, E):
        """The joint recursion of the start-up (:class:`._unobservable.StartupModel`)."""
        from ._unobservable import StartupModel

        n, q = self.sys.n, self.sys.q
        No, nb = dec.T_o.shape[0], dec.T_obar.shape[0]
        Tf = dec.T / dz[None, :]
        A = np.block([[dec.A_o, np.zeros((No, nb))], [dec.A_21, dec.A_obar]])
        B = np.vstack([dec.B_o, dec.B_obar])
        Gam = np.vstack([dec.Gamma_o, dec.Gamma_obar])
        Ef = Tf @ np.vstack([E, np.zeros((q, E.shape[1]))])
        C = np.hstack([dec.C_o, np.zeros((dec.C_o.shape[0], nb))])
        X = np.hstack([np.eye(n), np.zeros((n, q))]) @ (dz[:, None] * dec.T.T)
        bar = np.hstack([np.zeros((nb, No)), np.eye(nb)])
        prior = X0 if not q else X0.cartesian(
            ConstrainedZonotope.full_space(q) if D0 is None else D0)
        Z0 = normalize_free_columns(Tf @ prior)
        return StartupModel(A, B, Ef, Gam, C, X, bar, Z0)

    def process_noise(self, k: int) -> ConstrainedZonotope | None:
        """``W_k`` (in the noise space of ``E``), or ``None``."""
        if not callable(self.w_spec):
            return self.W_fixed
        return noise_set(f"process_noise({k})", self.w_spec(k), self.E_o.shape[1])

    def measurement_noise(self, k: int) -> ConstrainedZonotope | None:
        """``F_b V_k`` (balanced output units), or ``None``."""
        if not callable(self.v_spec):
            return self.V_fixed
        return self.v_internal(noise_set(f"measurement_noise({k})", self.v_spec(k),
                                           self.F_b.shape[1]))

    def _fixed_increment(self, spec: IncrementSpec) -> ConstrainedZonotope | None:
        """The increment set when it does not depend on ``k`` (validated), else None."""
        q = self.sys.q
        if spec is None:
            return ConstrainedZonotope.from_box(-np.ones(q), np.ones(q))
        if isinstance(spec, Box | ConstrainedZonotope):
            spec = as_set("increment_set", spec, q)
            if not spec.is_bounded:
                raise InvalidValueError("increment_set must be bounded")
            return spec
        if callable(spec):
            return None
        r = as_vector("increment_set", spec, size=q)
        if (r < 0).any():
            raise InvalidValueError("increment_set bounds must be nonnegative")
        return ConstrainedZonotope.from_box(-r, r)

    def increment(self, k: int) -> ConstrainedZonotope:
        """The increment set ``[[dd_k]]``."""
        if self.inc_fixed is not None:
            return self.inc_fixed
        dd = self.inc_spec(k)  # type: ignore[operator]
        if isinstance(dd, Box):
            dd = ConstrainedZonotope.from_box(dd.lo, dd.hi)
        if not isinstance(dd, ConstrainedZonotope):
            raise ArgumentError(f"increment_set({k}) must return a ConstrainedZonotope or a Box, "
                                f"got {type(dd).__name__}")
        if dd.dim != self.sys.q:
            raise DimensionError(f"increment_set({k}) has dimension {dd.dim}, "
                                 f"expected {self.sys.q}")
        return dd

    def _structure_digest(self) -> bytes:
        """Fingerprint of everything a window structure depends on (shared cache key)."""
        hsh = hashlib.blake2b(digest_size=20)
        inc = self.step_set
        Z0 = self.Z0_prior
        parts = [self.A_o, self.B_step, self.C_o, self.Gamma_o, self.P, Z0.G, Z0.A,
                 np.isinf(Z0.h), self.hull_rows]
        for S in (inc, self.V_fixed):
            if S is not None:
                parts += [S.G, S.c, S.A, S.b, S.h, S.b_err, S.c_err]
            parts.append(np.array([S is None]))
        for a in parts:
            a = np.ascontiguousarray(a)
            hsh.update(str(a.shape).encode())
            hsh.update(a.tobytes())
        r_inc = inc.unbounded_radius if inc else 0.0
        hsh.update(repr((self.P_coords is None, min(Z0.unbounded_radius, r_inc),
                         self.window)).encode())
        return hsh.digest()

    def entry(self, y: ArrayLike, u_prev: ArrayLike | None, u: ArrayLike | None, k: int,
              u_pending: NDArray[np.float64] | None
              ) -> tuple[Entry, NDArray[np.float64] | None]:
        """Validate step ``k``'s data and collect its uncertainty sets (``u_pending``: the
        input carried from the last step, if any); also returns the validated current
        input ``u_k`` (or ``None``)."""
        p = self.sys.p
        yraw = as_vector("y", y, size=self.sys.l, allow_nan=True)
        uv = None
        if u_prev is not None:
            uv = as_vector("u_prev", u_prev, size=p)
        elif p and k > 0:
            if u_pending is None:
                raise ArgumentError(
                    f"u_prev (length {p}) is required after the first step of a "
                    "system with inputs")
            uv = u_pending
        uk = None
        if u is not None:
            if not p:
                raise ArgumentError("u is given but the system has no inputs")
            uk = as_vector("u", u, size=p)
        yerr = None
        if self.Du is not None:
            if uk is None:
                raise ArgumentError(
                    "u (the input at this step) is required: the system has a "
                    "feedthrough D_u (y = Xi x + D_u u)")
            Du = self.Du
            absDu_u = np.abs(Du) @ np.abs(uk)
            yraw = yraw - Du @ uk
            # rounding of D_u u (gamma_p) and of the subtraction, the input's and
            # the measurement's representation errors
            yerr = ((gamma(p + 1) + self.data_rtol) * absDu_u + UNIT_ROUNDOFF * np.abs(yraw)
                    + self.data_rtol * np.abs(yraw + Du @ uk)) * (1.0 + gamma(p + 3))
            yerr = np.where(np.isnan(yerr), 0.0, yerr) / self.dy
        yv = yraw / self.dy
        if k > 0:
            dd = self.increment(k - 1)
            w = self.process_noise(k - 1)
        else:
            dd = w = None
        return Entry(yv, uv, dd, w, self.measurement_noise(k), yerr), uk

    def __init__(self, sys: LinearSystem, window: int | None, on_inconsistent: str,
                 increment_set: IncrementSpec, initial_state_set, initial_disturbance_set,
                 measurement_noise: NoiseSpec, process_noise: NoiseSpec,
                 measurement_noise_matrix, process_noise_matrix, keep_sets: bool,
                 fast: bool, *, margin: float, data_rtol: float, state_bounds: bool,
                 restart: str, restart_depth: int, reset_inflation: float,
                 max_skip_fraction: float) -> None:
        """The arguments of :class:`~setobs.SMFDO` (its scalar options validated there)."""
        self.margin, self.data_rtol, self.state_bounds = margin, data_rtol, state_bounds
        self.restart, self.restart_depth = restart, restart_depth
        self.reset_inflation, self.max_skip_fraction = reset_inflation, max_skip_fraction
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
        X0 = as_set("initial_state_set", initial_state_set, n)
        D0 = as_set("initial_disturbance_set", initial_disturbance_set, q)
        self.inc_spec = increment_set
        self.inc_fixed = self._fixed_increment(increment_set)
        inc_scale = None
        if self.inc_fixed is not None:
            inc_scale = 0.5 * self.inc_fixed.interval_hull().width
        dec = observability_decomposition(sys, balance=True, disturbance_scale=inc_scale)
        self.decomposition = dec
        self.mu_o = dec.report.index
        if window is not None and window < self.mu_o - 1:
            raise InvalidValueError(
                f"window (delta) = {window} is too small: Algorithm 1 needs "
                f"delta >= mu_o - 1 = {self.mu_o - 1} (mu_o = observability index "
                "of the augmented pair)")
        self.window = window
        self.on_inconsistent = on_inconsistent
        self.keep_sets = bool(keep_sets)
        T_o = dec.T_o
        dz, dy = dec.state_scale, dec.output_scale
        self.dy = dy
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
            raise InvalidValueError("process_noise_matrix is given without process_noise")
        if measurement_noise_matrix is not None and measurement_noise is None:
            raise InvalidValueError("measurement_noise_matrix is given without measurement_noise")
        self.E_o = (T_o / dz[None, :]) @ np.vstack([E, np.zeros((q, E.shape[1]))])
        self.F_b = F / dy[:, None]
        self.w_spec, self.v_spec = process_noise, measurement_noise
        self.W_fixed = None if callable(process_noise) else noise_set(
            "process_noise", process_noise, E.shape[1])
        self.V_fixed = None if callable(measurement_noise) else self.v_internal(
            noise_set("measurement_noise", measurement_noise, F.shape[1]))
        self.noise_varies = callable(process_noise) or callable(measurement_noise)
        Du = sys.Du
        self.Du = Du if (sys.p and np.any(Du != 0)) else None
        target = np.hstack([np.zeros((q, n)), np.eye(q)])
        P = target @ (dz[:, None] * T_o.T)
        # d must not depend on the unobservable coordinates: [0 I] D T_obar^T = 0.
        leak = np.abs(target @ (dz[:, None] * dec.T_obar.T)).max(initial=0.0)
        if leak > 1e-8 * np.abs(dz[n:]).max(initial=0.0):
            raise ExistenceError("P T_o = [0 I] has no solution (fragile Theorem 1 verdict)",
                                 report)
        self.P = P
        # State bounds: x = [I 0] D T^T z on the observable coordinates z; a state that
        # depends on the unobservable ones is reported unbounded.
        sel_n = np.hstack([np.eye(n), np.zeros((n, q))])
        Mx = sel_n @ (dz[:, None] * T_o.T)
        Mx_bar = sel_n @ (dz[:, None] * dec.T_obar.T)
        x_leak = np.abs(Mx_bar).max(axis=1, initial=0.0)
        self.x_free = x_leak > 1e-8 * np.abs(dz[:n])
        # ... unless the unobservable part is bounded by X0: then
        # x = Mx z_o + Mx_bar zbar with zbar tracked outside the LPs.
        self.ubar = self._unobservable_tracker(dec, dz, X0, D0, E) \
            if self.x_free.any() else None
        self.startup = None if self.ubar is None else self._startup_model(dec, dz, X0, D0, E)
        self.Mx_bar = Mx_bar[self.x_free]
        self.Mx = Mx if self.ubar is not None else np.where(self.x_free[:, None], 0.0, Mx)
        # A state map with at most one nonzero per row (a scaled coordinate of z_o:
        # balancing by powers of two, a sign) is read off the hull of z_o, not
        # bounded by LPs of its own (the random 6-state benchmark solved each of
        # its 24 window LPs twice).
        selx = np.count_nonzero(self.Mx, axis=1) <= 1
        self.X_coords = np.argmax(np.abs(self.Mx), axis=1) if selx.all() else None
        self.X_scale = None if self.X_coords is None else \
            self.Mx[np.arange(n), self.X_coords]
        # When P selects coordinates exactly (e.g. T_o = I for a fully observable
        # augmented pair), the hull of P Z is the selected coordinates of the hull of Z:
        # the same LPs, so no extra solves are needed (windowed mode).
        sel = (np.count_nonzero(P, axis=1) == 1) & (np.abs(P).max(axis=1) == 1.0) & \
            (P.max(axis=1) == 1.0)
        self.P_coords = np.argmax(P, axis=1) if sel.all() else None
        self.T_o = T_o
        self.A_o, self.B_o, self.Gamma_o, self.C_o = dec.A_o, dec.B_o, dec.Gamma_o, dec.C_o
        self.hull_rows = self.extra_rows()
        X0 = ConstrainedZonotope.full_space(n) if X0 is None else X0
        if q:
            D0 = ConstrainedZonotope.full_space(q) if D0 is None else D0
            X0 = X0.cartesian(D0)
        self.Z0_prior = normalize_free_columns((T_o / dz[None, :]) @ X0)
        self.fast = bool(fast)
        # The per-step uncertainty of the closed form: [[dd]] (x W), entering by
        # B_o ([B_o, E_o] with process noise).
        inc = self.inc_fixed
        if inc is not None and self.W_fixed is not None:
            self.step_set = inc.cartesian(self.W_fixed)
            self.B_step = np.hstack([self.B_o, self.E_o])
        else:
            self.step_set, self.B_step = inc, self.B_o
        self.digest = self._structure_digest() if self.fast else b""
        # Window restart from a bounded hull only; after this many steps of
        # growth from Z_0^- (numerically unbounded hulls), restart anyway.
        self.grow_limit = 4 * ((window or 0) + self.mu_o) + 16
        # Exact mode's H-representation recursion (setmembership._hrep): fixed
        # uncertainty sets; their vertices are computed on first use.
        # With noise, the exact set's complexity grows with every step: exact mode
        # keeps the whole-history LP instead (setmembership._history).
        noisy = self.W_fixed is not None or self.V_fixed is not None or self.noise_varies
        self.history_on = window is None and self.fast and not self.keep_sets and noisy
        self.hrep_on = (window is None and self.fast and self.inc_fixed is not None
                        and not self.noise_varies and not self.history_on)
        self.restart_poly: RestartPolytope | None = None
        if (window is not None and restart != "box" and self.step_set is not None
                and not self.noise_varies and restart_depth > 1):
            self.restart_poly = RestartPolytope(
                self.A_o, self.Gamma_o, self.B_step, self.step_set, restart_depth,
                self.data_rtol)
        self.restart_lags = 0 if self.restart_poly is None else self.restart_poly.lags
        #: the rows of the fast paths' hull bounds whose bands a step reports
        #: (:meth:`_reported_rows`): what a step's gap is measured on
        self.reported_rows = self._reported_rows()
        self._frozen = True

    def __setattr__(self, name: str, value: object) -> None:
        if getattr(self, "_frozen", False):
            raise ImmutableError(f"the SMFDO's model is fixed at construction (cannot set "
                                 f"{name}); build a new SMFDO")
        object.__setattr__(self, name, value)

    # ------------------------------------------------------------------ the recursion
    def prior(self, Z: ConstrainedZonotope, e: Entry, model=None) -> ConstrainedZonotope:
        """Eq. (20) with process noise: ``A_o Z + B_o Z^Delta + E_o W + Gamma_o u``
        (``model``: the start-up's joint model instead, :class:`._unobservable.StartupModel`).

        The centre's rounding bound goes through ``A_o`` as factors once it is
        above rounding level (:func:`~setobs.geometry.zonotope.absorb_center_error`).
        """
        A, B, E, Gam = ((self.A_o, self.B_o, self.E_o, self.Gamma_o) if model is None
                        else (model.A, model.B, model.E, model.Gamma))
        Z = absorb_center_error(Z, CENTER_ERROR_ABSORB_RTOL)
        Zp = A @ Z + B @ e.dd
        if e.w is not None:
            Zp = Zp + E @ e.w
        u = e.u
        if u is not None and self.sys.p:
            v = Gam @ u
            err = self.data_rtol * (np.abs(Gam) @ np.abs(u)) if self.data_rtol \
                else None
            Zp = Zp.minkowski_sum(v, err=err)
        return Zp

    def posterior(self, Zp: ConstrainedZonotope, e: Entry,
                   depth: int, C_full=None) -> ConstrainedZonotope:
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
        nD = self.inc_fixed.n_gen if self.inc_fixed is not None else self.sys.q
        nV = 0 if e.v is None else e.v.n_gen
        Cf = self.C_o if C_full is None else C_full
        rtol = self.data_rtol + model_rtol(depth, Cf.shape[1], self.sys.p, nD + nV)
        ym = y[m]
        y_err = rtol * np.abs(ym)
        if e.yerr is not None:
            y_err = y_err + e.yerr[m]
        C = Cf if m.all() else Cf[m]
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

    def bounds(self, Z: ConstrainedZonotope):
        """Disturbance set ``P Z``, its hull, (windowed mode) the hull of ``Z``, whether
        an LP fell back, and (``state_bounds``) the hull of the state ``M_x Z``."""
        fb_o = False
        box_o = None
        if self.window is not None or self.history_on or (self.state_bounds and (
                self.X_coords is not None or self.ubar is not None)):
            box_o, fb_o = hull_with_status(Z)
        box_x, fb_x = None, False
        if self.state_bounds:
            if self.X_coords is not None:
                box_x = self.coordinate_states(box_o.lo, box_o.hi)
            else:  # (the same factor polytope: its HiGHS model is reused)
                box_x, fb_x = hull_with_status(self.Mx @ Z)
        Zd = self.P @ Z
        if box_o is not None and self.P_coords is not None:
            j = self.P_coords
            return Zd, Box(box_o.lo[j], box_o.hi[j]), box_o, fb_o or fb_x, box_x
        box_d, fb_d = hull_with_status(Zd)
        return Zd, box_d, box_o, fb_o or fb_d or fb_x, box_x

    def outward(self, lo, hi):
        """``lo``, ``hi`` widened by the relative margin (``margin * max(1, |end|)``)."""
        return _kernels.outward_margin(np.asarray(lo, dtype=np.float64),
                                       np.asarray(hi, dtype=np.float64), self.margin)

    @staticmethod
    def hull_feeds_tracker(box_o: Box) -> bool:
        """Whether the filter's hull is finite (in every coordinate: one that ``A_21``
        does not read may still feed one it reads at the next step)."""
        return bool(np.isfinite(box_o.lo).all() and np.isfinite(box_o.hi).all())

    def invalidated(self, msg: str, k: int) -> ModelInvalidatedError:
        """The error for step ``k``, its advice naming what this model has (an increment
        set, or for a model without disturbances the process noise)."""
        hint = ModelInvalidatedError.HINT if self.sys.q else ModelInvalidatedError.HINT_STATE
        return ModelInvalidatedError(msg, k, hint)

    # ------------------------------------------------------------------ restart boxes
    @staticmethod
    def restart_bounds(box: Box) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Bounds of the restart box: a coordinate unbounded on one side is made
        free both ways (an outer answer; extended CZs have no one-sided boxes)."""
        lo, hi = box.lo, box.hi
        free = np.isinf(lo) | np.isinf(hi)
        if free.any():
            lo, hi = np.where(free, -np.inf, lo), np.where(free, np.inf, hi)
        return lo, hi

    @classmethod
    def box_cz(cls, box: Box) -> ConstrainedZonotope:
        """A box as a constrained zonotope (:meth:`restart_bounds`)."""
        return ConstrainedZonotope.from_box(*cls.restart_bounds(box))
