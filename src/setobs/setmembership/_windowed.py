"""The windowed SMFDO (Algorithm 1, lines 12-13): the window's restart and its closed-form
fast step."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module
from ..geometry import Box, ConstrainedZonotope
from ..geometry.zonotope import trusted_cz
from ..tolerances import UNBOUNDED_RADIUS
from ._restart import RestartPolytope
from ._setup import MODEL_CACHE, Entry
from ._window import WindowModel

# The compiled restart data (numba) loads on the first window, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")
_EMPTY = np.zeros(0)

__all__ = ["AUTO_GAIN", "AUTO_PROBE", "MAX_MASK_STRUCTURES", "WindowedSteps"]

#: Distinct missing-sample patterns an SMFDO sets up fast-path structures for;
#: steps with further patterns go to the reference path.
MAX_MASK_STRUCTURES = 64

#: ``restart="auto"``: every this many window steps the other restart is computed too.
AUTO_PROBE = 16
#: ``restart="auto"``: the polytope is kept while it is narrower than the box restart
#: by more than this fraction of the box's width in some coordinate.
AUTO_GAIN = 1e-2


class WindowedSteps:
    """Windowed steps of the SMFDO (a mixin of :class:`~setobs.SMFDO`): the restart
    mode of each step, the window's history and the compiled fast path."""

    def _start_mode(self, k: int) -> str:
        """How step ``k`` is computed: ``"box"`` (eq. (24), restart from IH(Z_(k-delta))),
        ``"init"`` (the whole history from Z_0^-), or ``"recursive"`` (one more step)."""
        win = self.window
        if win is not None and len(self._hulls) >= win and (
                self._windowing or not self._from_initial or k > self._grow_limit
                or (k >= win + self._init_lags()
                    and np.isfinite(self._restart_bounds(self._hulls[-win])[0]).all())):
            return "box"
        return "init" if self._from_initial else "recursive"

    def _init_lags(self) -> int:
        """Steps the first restart waits for beyond the window. With the polytope
        restart, the restart at ``t`` carries back only the hulls known at ``t``: a
        restart in the first steps is shallow (up to 27 % wider than the exact set on
        the 4-state benchmark plant). Until it can carry back its full depth
        (``restart_lags``) each step is the whole history from ``Z_0^-``, the exact
        set, as long as that LP is no larger than the polytope window's: ``N + k f``
        against ``N + R + delta f`` factors (``f`` per step, ``R`` the polytope's
        rows), so at most ``R // f`` steps (cold LPs: a longer wait made a noisy
        6-state plant's first 120 steps 5 times as costly). None with the box
        restart (eq. (24) as the paper runs it)."""
        if not self._polytope_now() or self._restart_poly is None:
            return 0
        f = self._step_set.n_gen + (0 if self._V_fixed is None else self._V_fixed.n_gen)
        return min(self._restart_lags, self._restart_poly.F_all.shape[0] // max(f, 1))

    # ------------------------------------------------------------------ fast path
    def _window_hist(self, entry: Entry) -> list[Entry]:
        """The data of the window's re-run ending at ``entry`` (eq. (24))."""
        win = self.window
        return [*self._hist[-(win - 1):], entry] if win > 1 else [entry]

    def _fast_step(self, k: int, mode: str, entry: Entry):
        """Hulls of ``Z_k``, ``P Z_k`` (and of the state, ``state_bounds``) by the closed
        form, or ``None`` (reference path)."""
        if (not self.fast or self._inc_fixed is None or self._noise_varies
                or mode == "recursive"):
            return None
        if self.window is None:
            # Exact mode: each closed form would be used once, and a cold simplex on
            # it costs more than the set recursion with HiGHS (84 vs 28 ms per step at
            # k = 100 on the paper example): the reference path is used.
            return None
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
        if mode != "box" or self._restart_poly is None or self.restart != "auto":
            out = self._window_solve(k, mode, hist, Y, measured, masks, mkey,
                                     self._polytope_now())
            if out is not None and mode == "box" and self._restart_poly is not None:
                self.stats["polytope_restarts"] += 1
            return out
        # restart="auto": the current choice, and every AUTO_PROBE window steps the
        # other one too; the polytope is kept while it is narrower somewhere by more
        # than AUTO_GAIN of the box's width (both are sound: the tighter is reported)
        first = self._window_solve(k, mode, hist, Y, measured, masks, mkey, self._auto_poly)
        self._auto_count += 1
        if first is None or self._auto_count % AUTO_PROBE:
            self.stats["polytope_restarts"] += first is not None and self._auto_poly
            return first
        other = self._window_solve(k, mode, hist, Y, measured, masks, mkey,
                                   not self._auto_poly)
        if other is None:
            return first
        poly, box = (first, other) if self._auto_poly else (other, first)
        wp, wb = poly[-1], box[-1]
        fin = np.isfinite(wb) & np.isfinite(wp)
        self._auto_poly = bool(np.any(wb[fin] - wp[fin] > AUTO_GAIN * wb[fin]))
        self.stats["polytope_restarts"] += 1
        return poly

    def _window_solve(self, k: int, mode: str, hist, Y, measured, masks, mkey, poly: bool):
        """One closed-form step (the window's from its restart set, with the carried-back
        rows if ``poly``, or the history's from ``Z_0^-``): the posterior's data, its
        hulls and their widths, or ``None``."""
        P_extra = self._hull_rows if self._hull_rows.shape[0] else None
        inc, B_step, V = self._step_set, self._B_step, self._V_fixed
        if mode == "box":
            win = self.window
            c_S, b_S, h_S, F = self._restart_start(poly)
            free = np.isinf(h_S)
            c_S_err = b_S_err = None
            key = ("box", F.shape[0], free.tobytes(), mkey)
            unbounded_radius = min(UNBOUNDED_RADIUS, inc.unbounded_radius)

            def build() -> WindowModel:
                G_S, A_S = RestartPolytope.structure(F)
                return WindowModel(self.A_o, B_step, self.C_o, self.Gamma_o, increment=inc,
                                   G_S=G_S, A_S=A_S, free_S=free, s=win,
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
        c, b, h, c_err, b_err, y_scale = model.assemble(
            c_S, b_S, h_S, Y, U, c_S_err=c_S_err, b_S_err=b_S_err, data_rtol=self.data_rtol,
            Y_err=Y_err)
        out = model.hull(c, b, h, y_scale, state, b_err, c_err)
        if out is None:
            return None
        box_o, box, box_x, _ = self.split_hull(*out)
        return (model, c, b, h, c_err, b_err), box, box_o, box_x, out[1] - out[0]

    def _polytope_now(self) -> bool:
        """Whether the next restart carries the polytope's rows (``restart="auto"``: the
        choice of the last probe)."""
        return self.restart == "polytope" or (self.restart == "auto" and self._auto_poly)

    def _restart_rows(self, poly: bool = True):
        """The restart set at ``t = k - delta``: its hull's bounds, and the carried-back
        rows ``F`` with their ranges (none with ``poly`` false or ``restart="box"``;
        :mod:`setobs.setmembership._restart`)."""
        win = self.window
        box_t = self._hulls[-win]
        lo, hi = self._restart_bounds(box_t)
        R = self._restart_poly
        if R is None or not R.lags or not poly:
            return lo, hi, np.zeros((0, lo.size)), np.zeros(0), np.zeros(0)
        n_h = len(self._hulls)
        J = min(R.lags, n_h - win)
        boxes = [self._hulls[n_h - win - j] for j in range(1, J + 1)]
        inputs = [self._hull_u[n_h - win - i] for i in range(J)]
        rlo, rhi = R.rows(Box(lo, hi), boxes, inputs)
        return lo, hi, R.F_all, rlo, rhi

    def _restart_start(self, poly: bool):
        """The restart set's data ``c_S``, ``b_S``, ``h_S`` (generators ``[I 0]``,
        constraints ``[F -I]``: :meth:`RestartPolytope.start_data`) and its rows ``F``;
        the box restart (eq. (24), no rows) in one compiled call."""
        R = self._restart_poly
        if R is None or not R.lags or not poly:
            box_t = self._hulls[-self.window]
            c_S, h_S = _kernels.box_start(box_t.lo, box_t.hi)
            return c_S, _EMPTY, h_S, np.zeros((0, c_S.size))
        lo, hi, F, rlo, rhi = self._restart_rows(poly)
        return (*RestartPolytope.start_data(lo, hi, F, rlo, rhi), F)

    def _restart_cz(self) -> ConstrainedZonotope:
        """The restart set as a constrained zonotope (the reference path)."""
        c_S, b_S, h_S, F = self._restart_start(self._polytope_now())
        G_S, A_S = RestartPolytope.structure(F)
        return trusted_cz(G_S, c_S, A_S, b_S, h_S)

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
