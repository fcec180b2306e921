"""The window engine of the SMFDO (Algorithm 1, lines 12-13): the window's restart and its
closed-form step; the restart's mode and data (shared with the reference engine)."""

from __future__ import annotations

import numpy as np

from .._lazy import lazy_module
from ..geometry import Box, ConstrainedZonotope
from ..geometry.zonotope import trusted_cz
from ..tolerances import ALLOWANCE_RTOL, UNBOUNDED_RADIUS
from ._restart import RestartPolytope
from ._setup import MODEL_CACHE, Entry, SMFDOModel
from ._state import Outcome, SMFDOState
from ._window import WindowModel, allowance_fraction

# The compiled restart data (numba) loads on the first window, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")
_EMPTY = np.zeros(0)

__all__ = ["AUTO_GAIN", "AUTO_GAIN_MAX", "AUTO_PROBE", "AUTO_PROBE_MAX", "MAX_MASK_STRUCTURES",
           "SUPPORT_GAIN", "SUPPORT_MAX_RATIO", "SUPPORT_RANGES", "SUPPORT_START_ROWS",
           "WindowEngine", "init_lags", "polytope_now", "polytope_pays", "restart_cz",
           "restart_rows", "restart_start", "start_mode", "support_at", "support_rows",
           "window_hist"]

#: Distinct missing-sample patterns an SMFDO sets up fast-path structures for;
#: steps with further patterns go to the reference path.
MAX_MASK_STRUCTURES = 64

#: ``restart="auto"``: every this many window steps the other restart is computed too (a
#: probe); after a probe that keeps the choice the interval doubles, up to
#: :data:`AUTO_PROBE_MAX` (a probe of the polytope costs up to 7 box-restart steps on a
#: 30-tank cascade); a probe that changes it resets the interval.
AUTO_PROBE = 16
#: ``restart="auto"``: the longest interval between probes.
AUTO_PROBE_MAX = 64
#: ``restart="auto"``: the polytope is kept while its bands are narrower than the box
#: restart's by more than this fraction of the box's widths on average over the
#: coordinates, or by more than :data:`AUTO_GAIN_MAX` in some coordinate. Measured
#: (``benchmarks/state_estimation.py``'s plants, window 10, the two restarts run apart,
#: gains per step from step 26): a two-mass plant and a constant-velocity target gain
#: 50 % and 59 % on average (median over the steps), a bicycle model 0.14 %, 6-, 15- and
#: 30-tank cascades 0.01-0.18 % (at most 2.7 % in one coordinate), a random 6-state plant
#: nothing. (Until the rule took the mean, 1 % in any one coordinate kept the polytope on
#: the 30-tank cascade with 21 outputs at 7 times the box restart's cost for 0.1 % on
#: average.)
AUTO_GAIN = 1e-2
#: ``restart="auto"``: the gain in one coordinate that keeps the polytope whatever the
#: mean (:data:`AUTO_GAIN`).
AUTO_GAIN_MAX = 5e-2


def start_mode(m: SMFDOModel, s: SMFDOState, k: int) -> str:
    """How step ``k`` is computed: ``"box"`` (eq. (24), restart from IH(Z_(k-delta))),
    ``"init"`` (the whole history from Z_0^-), or ``"recursive"`` (one more step)."""
    win = m.window
    if win is not None and len(s.hulls) >= win and (
            s.windowing or not s.from_initial or k > m.grow_limit
            or (k >= win + init_lags(m, s)
                and np.isfinite(m.restart_bounds(s.hulls[-win])[0]).all())):
        return "box"
    return "init" if s.from_initial else "recursive"


def init_lags(m: SMFDOModel, s: SMFDOState) -> int:
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
    if not polytope_now(m, s) or m.restart_poly is None:
        return 0
    f = m.step_set.n_gen + (0 if m.V_fixed is None else m.V_fixed.n_gen)
    return min(m.restart_lags, m.restart_poly.F_all.shape[0] // max(f, 1))


def polytope_pays(wp: np.ndarray, wb: np.ndarray) -> bool:
    """``restart="auto"``'s rule at a probe: whether the polytope restart's widths ``wp``
    are narrower than the box restart's ``wb`` by more than :data:`AUTO_GAIN` of ``wb``
    on average over the coordinates, or by more than :data:`AUTO_GAIN_MAX` in one
    (coordinates with a non-finite or zero width in either are left out)."""
    fin = np.isfinite(wb) & np.isfinite(wp) & (wb > 0.0)
    if not fin.any():
        return False
    gain = (wb[fin] - wp[fin]) / wb[fin]
    return bool(gain.mean() > AUTO_GAIN or gain.max() > AUTO_GAIN_MAX)


def window_hist(m: SMFDOModel, s: SMFDOState, entry: Entry) -> list[Entry]:
    """The data of the window's re-run ending at ``entry`` (eq. (24))."""
    win = m.window
    return [*s.hist[-(win - 1):], entry] if win > 1 else [entry]


def polytope_now(m: SMFDOModel, s: SMFDOState) -> bool:
    """Whether the next restart carries the polytope's rows (``restart="auto"``: the
    choice of the last probe)."""
    return m.restart == "polytope" or (m.restart == "auto" and s.auto_poly)


def restart_rows(m: SMFDOModel, s: SMFDOState, poly: bool = True, support: bool = True):
    """The restart set at ``t = k - delta``: its hull's bounds, and the carried-back
    rows ``F`` with their ranges (none with ``poly`` false or ``restart="box"``;
    :mod:`setobs.setmembership._restart`), intersected with the window's own support
    values of ``Z_t`` in the rows' directions where they were computed at ``t`` (and
    ``support``)."""
    win = m.window
    box_t = s.hulls[-win]
    lo, hi = m.restart_bounds(box_t)
    R = m.restart_poly
    if R is None or not R.lags or not poly:
        return lo, hi, np.zeros((0, lo.size)), np.zeros(0), np.zeros(0)
    n_h = len(s.hulls)
    J = min(R.lags, n_h - win)
    boxes = [s.hulls[n_h - win - j] for j in range(1, J + 1)]
    inputs = [s.hull_u[n_h - win - i] for i in range(J)]
    rlo, rhi = R.rows(Box(lo, hi), boxes, inputs)
    sup = support_at(s, win)
    if sup is not None and support:
        # the window's own support values of Z_t in the rows' directions (computed at
        # t): another outer range of F z_t over X_t, so the intersection is one too
        rlo2, rhi2 = np.maximum(rlo, sup[0]), np.minimum(rhi, sup[1])
        if (rlo2 <= rhi2).all():  # (crossed only if the data contradict the model:
            rlo, rhi = rlo2, rhi2  # the carried ranges then, and the LP decides)
            s.stats["support_restarts"] += 1
    return lo, hi, R.F_all, rlo, rhi


def support_at(s: SMFDOState, win: int) -> tuple | None:
    """The support values of ``Z_t`` (``t = k - delta``) in the restart rows' directions,
    if the window computed them at ``t``."""
    return s.support[-win] if len(s.support) == len(s.hulls) >= win else None


def restart_start(m: SMFDOModel, s: SMFDOState, poly: bool, support: bool = True):
    """The restart set's data ``c_S``, ``b_S``, ``h_S`` (generators ``[I 0]``,
    constraints ``[F -I]``: :meth:`RestartPolytope.start_data`) and its rows ``F``;
    the box restart (eq. (24), no rows) in one compiled call."""
    R = m.restart_poly
    if R is None or not R.lags or not poly:
        box_t = s.hulls[-m.window]
        c_S, h_S = _kernels.box_start(box_t.lo, box_t.hi)
        return c_S, _EMPTY, h_S, np.zeros((0, c_S.size))
    lo, hi, F, rlo, rhi = restart_rows(m, s, poly, support)
    return (*RestartPolytope.start_data(lo, hi, F, rlo, rhi), F)


#: Whether the polytope restart takes its rows' ranges also from the windows' own support
#: values in the rows' directions (:func:`restart_rows`), computed as extra objectives of
#: the window steps while a probe finds that they pay (:data:`SUPPORT_GAIN`).
SUPPORT_RANGES = True

#: The support values are computed at every window step unless, at the last two probes,
#: the restart with them gave bands narrower than the restart without them by at most this
#: fraction of their width on average (then at every ``AUTO_PROBE``-th step, a probe).
#: Measured (window 10, ``benchmarks/chain_ab.py``): a constant-velocity target (22 rows)
#: goes from 1.15 / 1.66 to 1.03 / 1.18 times the exact set (mean / worst) at 1.4 times
#: the cost. (Development runs, not in a results file: a random 6-state plant gained
#: nothing, and a 30-tank cascade little at 4 times the cost; with the largest gain of any
#: band as the criterion instead of the mean they stayed on there.)
SUPPORT_GAIN = 0.02

#: The support values are computed only when the restart has at most this many rows per
#: coordinate of ``z`` (their ``2 R`` objectives against the hull's ``2 N``). The
#: constant-velocity target keeps 5.5 per coordinate; in development runs (not in a
#: results file) a lightly damped two-mass plant with 30 per coordinate gained about 1 %
#: of width at about 15 times the cost.
SUPPORT_MAX_RATIO = 8

#: The support values start on (until the probes decide) when the window LP has at most
#: this many rows (restart rows plus measurements), else off (the probes turn them on
#: where they pay). In development runs (not in a results file) a 30-tank cascade with 21
#: outputs (330 rows) paid about 4 times the cost for its first window steps before two
#: probes turned them off, and the constant-velocity target (42 rows) was markedly wider
#: in its first restarts when they started off.
SUPPORT_START_ROWS = 100


def support_rows(m: SMFDOModel, s: SMFDOState, k: int, poly: bool) -> np.ndarray:
    """The restart rows ``F`` whose ranges the window step ``k`` computes over its
    posterior with the polytope restart: at every step while they pay (``s.sup_on``,
    :data:`SUPPORT_GAIN`), else every ``AUTO_PROBE`` steps (a probe); none otherwise,
    with more than :data:`SUPPORT_MAX_RATIO` rows per coordinate, or with
    :data:`SUPPORT_RANGES` off."""
    R = m.restart_poly
    if not SUPPORT_RANGES or R is None or not R.lags or not poly:
        return np.zeros((0, m.A_o.shape[0]))
    if s.sup_on is None:  # (the first window step: on for a small window LP)
        s.sup_on = R.F_all.shape[0] + m.window * m.C_o.shape[0] <= SUPPORT_START_ROWS
    if (R.F_all.shape[0] > SUPPORT_MAX_RATIO * R.N
            or not (s.sup_on or k % AUTO_PROBE == 0)):
        return np.zeros((0, m.A_o.shape[0]))
    return R.F_all


def restart_cz(m: SMFDOModel, s: SMFDOState) -> ConstrainedZonotope:
    """The restart set as a constrained zonotope (the reference path)."""
    c_S, b_S, h_S, F = restart_start(m, s, polytope_now(m, s))
    G_S, A_S = RestartPolytope.structure(F)
    return trusted_cz(G_S, c_S, A_S, b_S, h_S)


class WindowEngine:
    """The windowed SMFDO's closed-form step (Algorithm 1, lines 12-13, eq. (24)): the
    window's LPs from its restart set (with the polytope restart's carried-back rows),
    or the whole history's from ``Z_0^-`` while the window fills, by the compiled
    warm-started simplex; it declines (``None``) in exact mode, with time-varying
    sets, on a ``"recursive"`` step, or when an LP is not certified."""

    def try_step(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str,
                 e: Entry) -> Outcome | None:
        """The step's :class:`~._state.Outcome` by the closed form, or ``None``."""
        fast = self._closed_form(m, s, k, mode, e)
        if fast is None:
            return None
        s.stats["fast"] += 1
        Z_src, box, box_o, box_x, _, support, gap = fast
        Zd = None
        if m.keep_sets:
            model, c, b, h, c_err, b_err = Z_src
            Z_src = model.to_cz(c, b, h, c_err, b_err)
            Zd = m.P @ Z_src
        depth = k if mode == "init" else m.window
        status = "inexact" if gap > ALLOWANCE_RTOL else "ok"
        return Outcome(Z_src, box, box_o, Zd, box_x, status, depth, e,
                       fast[0][0].blas_small, support, gap)

    def _closed_form(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str, entry: Entry):
        """Hulls of ``Z_k``, ``P Z_k`` (and of the state, ``state_bounds``) by the closed
        form, or ``None`` (reference path)."""
        if (not m.fast or m.inc_fixed is None or m.noise_varies
                or mode == "recursive"):
            return None
        if m.window is None:
            # Exact mode: each closed form would be used once, and a cold simplex on
            # it costs more than the set recursion with HiGHS (84 vs 28 ms per step at
            # k = 100 on the paper example): the reference path is used.
            return None
        hist = window_hist(m, s, entry) if mode == "box" else [*s.hist, entry]
        Y = np.array([e.y for e in hist])
        measured = ~np.isnan(Y)
        if measured.all():
            masks, mkey = None, b""
        else:
            masks = list(measured)
            mkey = np.packbits(measured).tobytes() + len(hist).to_bytes(4, "little")
            # ("init" structures are new at every step anyway: no budget there)
            if mode == "box" and mkey not in s.mask_keys:
                if len(s.mask_keys) >= MAX_MASK_STRUCTURES:
                    s.stats["mask_reference"] += 1
                    return None
                s.mask_keys.add(mkey)
        if mode != "box" or m.restart_poly is None:
            return self._window_solve(m, s, k, mode, hist, Y, measured, masks, mkey,
                                      polytope_now(m, s))
        poly = polytope_now(m, s)
        first = self._window_solve(m, s, k, mode, hist, Y, measured, masks, mkey, poly)
        if first is not None and poly and support_at(s, m.window) is not None and (
                not s.sup_on or k % AUTO_PROBE == 0):
            # the support values' probe: the same restart without them (the carried
            # ranges alone). They are computed at every step until two probes in a row
            # find them narrowing the bands by at most SUPPORT_GAIN of their width on
            # average, then only every AUTO_PROBE steps until one finds more (both
            # restarts are sound: the tighter is reported)
            other = self._window_solve(m, s, k, mode, hist, Y, measured, masks, mkey, True,
                                       support=False)
            if other is not None:
                wo, wf = other[4], first[4]
                fin = np.isfinite(wo) & np.isfinite(wf) & (wo > 0.0)
                gain = float(np.mean((wo[fin] - wf[fin]) / wo[fin])) if fin.any() else 0.0
                s.sup_miss = 0 if gain > SUPPORT_GAIN else s.sup_miss + 1
                s.sup_on = s.sup_miss < 2
        if m.restart != "auto":
            s.stats["polytope_restarts"] += first is not None
            return first
        # restart="auto": the current choice, and at the probes the other one too; the
        # polytope is kept while it is narrower than the box by more than AUTO_GAIN of
        # its widths on average or AUTO_GAIN_MAX in some coordinate (both are sound:
        # the tighter is reported)
        s.auto_count += 1
        if not s.auto_next:
            s.auto_period = s.auto_next = AUTO_PROBE
        if first is None or s.auto_count < s.auto_next:
            s.stats["polytope_restarts"] += first is not None and s.auto_poly
            return first
        other = self._window_solve(m, s, k, mode, hist, Y, measured, masks, mkey,
                                   not s.auto_poly)
        if other is None:
            s.auto_next = s.auto_count + AUTO_PROBE
            return first
        poly_out, box_out = (first, other) if s.auto_poly else (other, first)
        keep = polytope_pays(poly_out[4], box_out[4])
        # (the interval doubles while the probes agree with the choice)
        s.auto_period = (min(2 * s.auto_period, AUTO_PROBE_MAX) if keep == s.auto_poly
                         else AUTO_PROBE)
        s.auto_next = s.auto_count + s.auto_period
        s.auto_poly = keep
        s.stats["polytope_restarts"] += 1
        return poly_out

    def _window_solve(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str, hist, Y,
                      measured, masks, mkey, poly: bool, support: bool = True):
        """One closed-form step (the window's from its restart set, with the carried-back
        rows if ``poly`` and their support values if ``support``, or the history's from
        ``Z_0^-``): the posterior's data, its hulls and their widths, the support values
        of the restart rows over it (or ``None``), or ``None``."""
        inc, B_step, V = m.step_set, m.B_step, m.V_fixed
        # with the polytope restart the window also bounds F z (the restart rows) over
        # its posterior: the support values a later restart from this step uses
        sup_rows = support_rows(m, s, k, poly)
        P_extra = np.vstack([m.hull_rows, sup_rows]) if sup_rows.shape[0] else m.hull_rows
        P_extra = P_extra if P_extra.shape[0] else None
        if mode == "box":
            win = m.window
            c_S, b_S, h_S, F = restart_start(m, s, poly, support)
            free = np.isinf(h_S)
            c_S_err = b_S_err = None
            key = ("box", F.shape[0], free.tobytes(), mkey, sup_rows.shape[0])
            unbounded_radius = min(UNBOUNDED_RADIUS, inc.unbounded_radius)

            def build() -> WindowModel:
                G_S, A_S = RestartPolytope.structure(F)
                return WindowModel(m.A_o, B_step, m.C_o, m.Gamma_o, increment=inc,
                                   G_S=G_S, A_S=A_S, free_S=free, s=win,
                                   first_posterior=False, P=P_extra,
                                   unbounded_radius=unbounded_radius, noise=V, masks=masks)
        else:  # "init": the whole history from Z_0^-
            Z0 = m.Z0_prior
            c_S, b_S, h_S = Z0.c, Z0.b, Z0.h
            c_S_err, b_S_err = Z0.c_err, Z0.b_err
            key = ("init", k, mkey, sup_rows.shape[0])
            unbounded_radius = min(Z0.unbounded_radius, inc.unbounded_radius)

            def build() -> WindowModel:
                return WindowModel(m.A_o, B_step, m.C_o, m.Gamma_o, increment=inc,
                                   G_S=Z0.G, A_S=Z0.A, free_S=np.isinf(Z0.h), s=k,
                                   first_posterior=True, P=P_extra,
                                   unbounded_radius=unbounded_radius, noise=V, masks=masks)
        model = MODEL_CACHE.get((m.digest, *key), build)
        if not model.usable:
            return None
        if key[0] == "box":
            state = s.states.get(key)
            if state is None:
                state = s.states[key] = model.new_state()
        else:  # each "init" structure is used once per run: a cold start
            state = model.new_state()
        if m.sys.p:
            steps = hist if len(hist) == model.s else hist[1:]
            U = np.array([e.u for e in steps])
        else:
            U = np.zeros((model.s, 0))
        Y_err = None
        if m.Du is not None:
            Y_err = np.array([np.zeros(m.sys.l) if e.yerr is None else e.yerr
                              for e in hist])
        c, b, h, c_err, b_err, y_scale = model.assemble(
            c_S, b_S, h_S, Y, U, c_S_err=c_S_err, b_S_err=b_S_err, data_rtol=m.data_rtol,
            Y_err=Y_err)
        out = model.hull(c, b, h, y_scale, state, b_err, c_err)
        if out is None:
            return None
        frac = allowance_fraction(*out, m.margin, m.reported_rows)
        out = out[:2]
        box_o, box, box_x, at = m.split_hull(*out)
        n_sup = sup_rows.shape[0]
        support = (out[0][at:at + n_sup], out[1][at:at + n_sup]) if n_sup else None
        return ((model, c, b, h, c_err, b_err), box, box_o, box_x, out[1][:at] - out[0][:at],
                support, frac)
