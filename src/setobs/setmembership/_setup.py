"""Model preparation of the SMFDO: coordinates, uncertainty and noise sets, data entries."""

from __future__ import annotations

import hashlib
import numbers
import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._rounding import UNIT_ROUNDOFF, gamma, pow2_inverse, round_down, round_up
from .._validation import as_matrix, as_vector, check_real_scalar
from ..analysis import bounded_do_exists, observability_decomposition
from ..exceptions import ArgumentError, DimensionError, ExistenceError, InvalidValueError
from ..geometry import Box, ConstrainedZonotope
from ..geometry.box import trusted_box
from ..geometry.zonotope import trusted_cz
from ..systems import LinearSystem
from ._window import WindowModel

__all__ = ["MODEL_CACHE", "Entry", "IncrementSpec", "ModelCache", "ModelSetup", "NoiseSpec",
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


class ModelSetup:
    """The SMFDO's model preparation (a mixin of :class:`~setobs.SMFDO`): the
    observable coordinates, the uncertainty and noise sets in them, and the
    measured data as step entries."""

    # ------------------------------------------------------------------ setup helpers
    def _extra_rows(self) -> NDArray[np.float64]:
        """The rows the fast paths bound beyond the coordinates of ``z``: ``P`` unless it
        selects coordinates, then the state map unless it does (state bounds); kept
        as ``_hull_rows``."""
        parts = [] if self._P_coords is not None else [self.P]
        if self.state_bounds and self._X_coords is None:
            parts.append(self._Mx)
        return np.vstack(parts) if parts else np.zeros((0, self.A_o.shape[0]))

    def split_hull(self, lo: NDArray[np.float64], hi: NDArray[np.float64]):
        """The fast paths' hull bounds (the coordinates of ``z``, then the rows of
        ``_hull_rows``, then any rows of the caller's) as ``(box_o, box, box_x,
        rest)``: the hulls of ``z``, of ``P z`` and (``state_bounds``, else ``None``)
        of the state, and the index of the caller's rows."""
        N = self.A_o.shape[0]
        box_o = trusted_box(lo[:N], hi[:N])
        at = N
        if self._P_coords is not None:
            j = self._P_coords
            box = trusted_box(lo[j], hi[j])
        else:
            q = self.P.shape[0]
            box = trusted_box(lo[N:N + q], hi[N:N + q])
            at += q
        box_x = None
        if self.state_bounds:
            if self._X_coords is not None:
                box_x = self._coordinate_states(lo[:N], hi[:N])
            else:
                n = self.sys.n
                box_x = trusted_box(lo[at:at + n], hi[at:at + n])
                at += n
        return box_o, box, box_x, at

    def _coordinate_states(self, lo: NDArray[np.float64], hi: NDArray[np.float64]) -> Box:
        """The states' box from the box of ``z_o`` when the state map has at most one
        nonzero per row (``x_i = s_i z_j``): the products rounded outward (exact for
        powers of two); a zero row (a state on the unobservable part only) gets
        ``[0, 0]`` here."""
        j, sc = self._X_coords, self._X_scale
        with np.errstate(invalid="ignore"):  # (0 * inf on a zero row: set to 0 below)
            a, b = sc * lo[j], sc * hi[j]
        zero = sc == 0.0
        a[zero] = b[zero] = 0.0  # (0 * inf)
        xlo, xhi = np.minimum(a, b), np.maximum(a, b)
        exact = (sc == 1.0) | zero
        xlo = np.where(exact, xlo, round_down(xlo))
        xhi = np.where(exact, xhi, round_up(xhi))
        return trusted_box(xlo, xhi)

    def _v_internal(self, V: ConstrainedZonotope | None) -> ConstrainedZonotope | None:
        """``F_b V``: a measurement-noise set in balanced output units."""
        return None if V is None else self._F_b @ V

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

    def _process_noise(self, k: int) -> ConstrainedZonotope | None:
        """``W_k`` (in the noise space of ``E``), or ``None``."""
        if not callable(self._w_spec):
            return self._W_fixed
        return noise_set(f"process_noise({k})", self._w_spec(k), self._E_o.shape[1])

    def _measurement_noise(self, k: int) -> ConstrainedZonotope | None:
        """``F_b V_k`` (balanced output units), or ``None``."""
        if not callable(self._v_spec):
            return self._V_fixed
        return self._v_internal(noise_set(f"measurement_noise({k})", self._v_spec(k),
                                           self._F_b.shape[1]))

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

    def _increment(self, k: int) -> ConstrainedZonotope:
        """The increment set ``[[dd_k]]``."""
        if self._inc_fixed is not None:
            return self._inc_fixed
        dd = self._inc_spec(k)  # type: ignore[operator]
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
        inc = self._step_set
        Z0 = self._Z0_prior
        parts = [self.A_o, self._B_step, self.C_o, self.Gamma_o, self.P, Z0.G, Z0.A,
                 np.isinf(Z0.h), self._hull_rows]
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

    def _entry(self, y: ArrayLike, u_prev: ArrayLike | None, u: ArrayLike | None
               ) -> tuple[Entry, NDArray[np.float64] | None]:
        """Validate one step's data and collect its uncertainty sets; also returns the
        validated current input ``u_k`` (or ``None``)."""
        p = self.sys.p
        yraw = as_vector("y", y, size=self.sys.l, allow_nan=True)
        uv = None
        if u_prev is not None:
            uv = as_vector("u_prev", u_prev, size=p)
        elif p and self.k >= 0:
            if self._u_pending is None:
                raise ArgumentError(
                    f"u_prev (length {p}) is required after the first step of a "
                    "system with inputs")
            uv = self._u_pending
        uk = None
        if u is not None:
            if not p:
                raise ArgumentError("u is given but the system has no inputs")
            uk = as_vector("u", u, size=p)
        k = self.k + 1
        yerr = None
        if self._Du is not None:
            if uk is None:
                raise ArgumentError(
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
        return Entry(yv, uv, dd, w, self._measurement_noise(k), yerr), uk

    def _prepare_model(self, sys: LinearSystem, window: int | None, on_inconsistent: str,
                       increment_set: IncrementSpec, initial_state_set, initial_disturbance_set,
                       measurement_noise: NoiseSpec, process_noise: NoiseSpec,
                       measurement_noise_matrix, process_noise_matrix, keep_sets: bool,
                       fast: bool) -> None:
        """Theorem 1's check, the observable coordinates (balanced), the sets and noise
        maps in them, and the structures of the fast paths (the arguments of
        :class:`~setobs.SMFDO`, validated)."""
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
        self._inc_spec = increment_set
        self._inc_fixed = self._fixed_increment(increment_set)
        inc_scale = None
        if self._inc_fixed is not None:
            inc_scale = 0.5 * self._inc_fixed.interval_hull().width
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
            raise InvalidValueError("process_noise_matrix is given without process_noise")
        if measurement_noise_matrix is not None and measurement_noise is None:
            raise InvalidValueError("measurement_noise_matrix is given without measurement_noise")
        self._E_o = (T_o / dz[None, :]) @ np.vstack([E, np.zeros((q, E.shape[1]))])
        self._F_b = F / dy[:, None]
        self._w_spec, self._v_spec = process_noise, measurement_noise
        self._W_fixed = None if callable(process_noise) else noise_set(
            "process_noise", process_noise, E.shape[1])
        self._V_fixed = None if callable(measurement_noise) else self._v_internal(
            noise_set("measurement_noise", measurement_noise, F.shape[1]))
        self._noise_varies = callable(process_noise) or callable(measurement_noise)
        Du = sys.Du
        self._Du = Du if (sys.p and np.any(Du != 0)) else None
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
        self._x_free = x_leak > 1e-8 * np.abs(dz[:n])
        # ... unless the unobservable part is bounded by X0: then
        # x = Mx z_o + Mx_bar zbar with zbar tracked outside the LPs.
        self._ubar = self._unobservable_tracker(dec, dz, X0, D0, E) \
            if self._x_free.any() else None
        self._startup = None if self._ubar is None else self._startup_model(dec, dz, X0, D0, E)
        self._Mx_bar = Mx_bar[self._x_free]
        self._Mx = Mx if self._ubar is not None else np.where(self._x_free[:, None], 0.0, Mx)
        # A state map with at most one nonzero per row (a scaled coordinate of z_o:
        # balancing by powers of two, a sign) is read off the hull of z_o, not
        # bounded by LPs of its own (the random 6-state benchmark solved each of
        # its 24 window LPs twice).
        selx = np.count_nonzero(self._Mx, axis=1) <= 1
        self._X_coords = np.argmax(np.abs(self._Mx), axis=1) if selx.all() else None
        self._X_scale = None if self._X_coords is None else \
            self._Mx[np.arange(n), self._X_coords]
        # When P selects coordinates exactly (e.g. T_o = I for a fully observable
        # augmented pair), the hull of P Z is the selected coordinates of the hull of Z:
        # the same LPs, so no extra solves are needed (windowed mode).
        sel = (np.count_nonzero(P, axis=1) == 1) & (np.abs(P).max(axis=1) == 1.0) & \
            (P.max(axis=1) == 1.0)
        self._P_coords = np.argmax(P, axis=1) if sel.all() else None
        self.T_o = T_o
        self.A_o, self.B_o, self.Gamma_o, self.C_o = dec.A_o, dec.B_o, dec.Gamma_o, dec.C_o
        self._hull_rows = self._extra_rows()
        X0 = ConstrainedZonotope.full_space(n) if X0 is None else X0
        if q:
            D0 = ConstrainedZonotope.full_space(q) if D0 is None else D0
            X0 = X0.cartesian(D0)
        self._Z0_prior = normalize_free_columns((T_o / dz[None, :]) @ X0)
        self.fast = bool(fast)
        self.stats = {"fast": 0, "reference": 0, "fallback": 0, "skipped": 0, "reset": 0,
                      "mask_reference": 0, "polytope_restarts": 0}
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
        # With noise, the exact set's complexity grows with every step: exact mode
        # keeps the whole-history LP instead (setmembership._history).
        noisy = self._W_fixed is not None or self._V_fixed is not None or self._noise_varies
        self._history_on = window is None and self.fast and not self.keep_sets and noisy
        self._hrep = (window is None and self.fast and self._inc_fixed is not None
                      and not self._noise_varies and not self._history_on)
        self._h_images: list[NDArray[np.float64]] | None = None
        self._h_floor_value: float | None = None
        self._h_noise: dict[bytes, list] = {}
