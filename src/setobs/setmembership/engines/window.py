"""The window engine of the SMFDO (Algorithm 1, lines 12-13): the closed-form step of the
window (eq. (24)) from its restart set (:mod:`.._schedule`), or of the whole history from
``Z_0^-`` while the window fills, by the compiled warm-started simplex; with
``restart="auto"`` its probes choose the restart, and they decide whether the window
computes the support values the polytope restart uses (measured in
``benchmarks/results/chain_ab.json`` and ``state_estimation.json``)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ...geometry import ConstrainedZonotope
from ...tolerances import ALLOWANCE_RTOL, UNBOUNDED_RADIUS
from .._closed_form import MODEL_CACHE, ClosedForm, WindowModel, allowance_fraction
from .._model import Entry, SMFDOModel
from .._restart import RestartPolytope
from .._schedule import polytope_now, restart_start, support_at, window_hist
from .._state import Outcome, SMFDOState

__all__ = ["AUTO_GAIN", "AUTO_GAIN_MAX", "AUTO_PROBE", "AUTO_PROBE_MAX", "MAX_MASK_STRUCTURES",
           "SUPPORT_GAIN", "SUPPORT_MAX_RATIO", "SUPPORT_RANGES", "SUPPORT_START_ROWS",
           "WindowBooks", "WindowEngine", "polytope_pays", "support_rows"]

#: Distinct missing-sample patterns an SMFDO sets up fast-path structures for;
#: steps with further patterns go to the reference path.
MAX_MASK_STRUCTURES = 64

#: ``restart="auto"``: every this many window steps the other restart is computed too (a
#: probe); after a probe that keeps the choice the interval doubles, up to
#: :data:`AUTO_PROBE_MAX`; a probe that changes it resets the interval.
AUTO_PROBE = 16
#: ``restart="auto"``: the longest interval between probes.
AUTO_PROBE_MAX = 64
#: ``restart="auto"``: the polytope is kept while its bands are narrower than the box
#: restart's by more than this fraction of the box's widths on average over the
#: coordinates, or by more than :data:`AUTO_GAIN_MAX` in some coordinate (the gains of
#: the two restarts run apart on the benchmark plants: ``benchmarks/state_estimation.py``).
AUTO_GAIN = 1e-2
#: ``restart="auto"``: the gain in one coordinate that keeps the polytope whatever the
#: mean (:data:`AUTO_GAIN`).
AUTO_GAIN_MAX = 5e-2


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


#: Whether the polytope restart takes its rows' ranges also from the windows' own support
#: values in the rows' directions (:func:`restart_rows`), computed as extra objectives of
#: the window steps while a probe finds that they pay (:data:`SUPPORT_GAIN`).
SUPPORT_RANGES = True

#: The support values are computed at every window step unless, at the last two probes,
#: the restart with them gave bands narrower than the restart without them by at most this
#: fraction of their width on average (then at every ``AUTO_PROBE``-th step, a probe);
#: their gain and cost: ``benchmarks/results/chain_ab.json``.
SUPPORT_GAIN = 0.02

#: The support values are computed only when the restart has at most this many rows per
#: coordinate of ``z`` (their ``2 R`` objectives against the hull's ``2 N``).
SUPPORT_MAX_RATIO = 8

#: The support values start on (until the probes decide) when the window LP has at most
#: this many rows (restart rows plus measurements), else off (the probes turn them on
#: where they pay).
SUPPORT_START_ROWS = 100


@dataclass
class WindowBooks:
    """The window engine's own state (replaced at :meth:`~setobs.SMFDO.reset`): the
    missing-sample patterns with a structure, and the probes' books (``restart="auto"``,
    the support values)."""

    #: missing-sample patterns with a structure (:data:`MAX_MASK_STRUCTURES`)
    mask_keys: set[bytes] = field(default_factory=set)
    #: window steps on the fast path
    auto_count: int = 0
    #: steps between the restart's probes (doubling while they agree), and the window
    #: step of the next one (0: not yet set, :data:`AUTO_PROBE`)
    auto_period: int = 0
    auto_next: int = 0
    #: the support values at every step (probed; ``None``: not decided yet)
    sup_on: bool | None = None
    #: probes in a row at which they did not pay
    sup_miss: int = 0


def support_rows(m: SMFDOModel, b: WindowBooks, k: int, poly: bool) -> np.ndarray:
    """The restart rows ``F`` whose ranges the window step ``k`` computes over its
    posterior with the polytope restart: at every step while they pay (``b.sup_on``,
    :data:`SUPPORT_GAIN`), else every ``AUTO_PROBE`` steps (a probe); none otherwise,
    with more than :data:`SUPPORT_MAX_RATIO` rows per coordinate, or with
    :data:`SUPPORT_RANGES` off."""
    R = m.restart_poly
    if not SUPPORT_RANGES or R is None or not R.lags or not poly:
        return np.zeros((0, m.A_o.shape[0]))
    if b.sup_on is None:  # (the first window step: on for a small window LP)
        b.sup_on = R.F_all.shape[0] + (m.window or 0) * m.C_o.shape[0] <= SUPPORT_START_ROWS
    if (R.F_all.shape[0] > SUPPORT_MAX_RATIO * R.N
            or not (b.sup_on or k % AUTO_PROBE == 0)):
        return np.zeros((0, m.A_o.shape[0]))
    return R.F_all


class WindowEngine:
    """The windowed SMFDO's closed-form step (Algorithm 1, lines 12-13, eq. (24)): the
    window's LPs from its restart set (with the polytope restart's carried-back rows),
    or the whole history's from ``Z_0^-`` while the window fills, by the compiled
    warm-started simplex; it declines (``None``) in exact mode, with time-varying
    sets, on a ``"recursive"`` step, or when an LP is not certified."""

    def __init__(self) -> None:
        self.books = WindowBooks()

    def reset(self) -> None:
        """Forget the books (a new run)."""
        self.books = WindowBooks()

    def try_step(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str,
                 e: Entry) -> Outcome | None:
        """The step's :class:`~._state.Outcome` by the closed form, or ``None``."""
        fast = self._closed_form(m, s, k, mode, e)
        if fast is None:
            return None
        s.stats["fast"] += 1
        form, box, box_o, box_x, _, support, gap = fast
        Zd = None
        Z_src: ClosedForm | ConstrainedZonotope = form
        if m.keep_sets:
            Z = form.to_cz()
            Z_src, Zd = Z, m.P @ Z
        depth = k if mode == "init" or m.window is None else m.window
        status = "inexact" if gap > ALLOWANCE_RTOL else "ok"
        return Outcome(Z_src, box, box_o, Zd, box_x, status, depth, e,
                       form.model.blas_small, support, gap)

    def _closed_form(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str, entry: Entry):
        """Hulls of ``Z_k``, ``P Z_k`` (and of the state, ``state_bounds``) by the closed
        form, or ``None`` (reference path)."""
        if (not m.fast or m.inc_fixed is None or m.noise_varies
                or mode == "recursive"):
            return None
        if m.window is None:
            # Exact mode: each closed form would be used once, and a cold simplex on
            # it costs more than the set recursion with HiGHS: the reference path.
            return None
        b = self.books
        hist = window_hist(m, s, entry) if mode == "box" else [*s.hist, entry]
        Y = np.array([e.y for e in hist])
        measured = ~np.isnan(Y)
        if measured.all():
            masks, mkey = None, b""
        else:
            masks = list(measured)
            mkey = np.packbits(measured).tobytes() + len(hist).to_bytes(4, "little")
            # ("init" structures are new at every step anyway: no budget there)
            if mode == "box" and mkey not in b.mask_keys:
                if len(b.mask_keys) >= MAX_MASK_STRUCTURES:
                    s.stats["mask_reference"] += 1
                    return None
                b.mask_keys.add(mkey)
        if mode != "box" or m.restart_poly is None:
            return self._window_solve(m, s, k, mode, hist, Y, measured, masks, mkey,
                                      polytope_now(m, s))
        poly = polytope_now(m, s)
        first = self._window_solve(m, s, k, mode, hist, Y, measured, masks, mkey, poly)
        if first is not None and poly and support_at(s, m.window) is not None and (
                not b.sup_on or k % AUTO_PROBE == 0):
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
                b.sup_miss = 0 if gain > SUPPORT_GAIN else b.sup_miss + 1
                b.sup_on = b.sup_miss < 2
        if m.restart != "auto":
            s.stats["polytope_restarts"] += first is not None
            return first
        # restart="auto": the current choice, and at the probes the other one too; the
        # polytope is kept while it is narrower than the box by more than AUTO_GAIN of
        # its widths on average or AUTO_GAIN_MAX in some coordinate (both are sound:
        # the tighter is reported)
        b.auto_count += 1
        if not b.auto_next:
            b.auto_period = b.auto_next = AUTO_PROBE
        if first is None or b.auto_count < b.auto_next:
            s.stats["polytope_restarts"] += first is not None and s.poly_restart
            return first
        other = self._window_solve(m, s, k, mode, hist, Y, measured, masks, mkey,
                                   not s.poly_restart)
        if other is None:
            b.auto_next = b.auto_count + AUTO_PROBE
            return first
        poly_out, box_out = (first, other) if s.poly_restart else (other, first)
        keep = polytope_pays(poly_out[4], box_out[4])
        # (the interval doubles while the probes agree with the choice)
        b.auto_period = (min(2 * b.auto_period, AUTO_PROBE_MAX) if keep == s.poly_restart
                         else AUTO_PROBE)
        b.auto_next = b.auto_count + b.auto_period
        s.poly_restart = keep
        s.stats["polytope_restarts"] += 1
        return poly_out

    def _window_solve(self, m: SMFDOModel, s: SMFDOState, k: int, mode: str, hist, Y,
                      measured, masks, mkey, poly: bool, support: bool = True):
        """One closed-form step (the window's from its restart set, with the carried-back
        rows if ``poly`` and their support values if ``support``, or the history's from
        ``Z_0^-``): the posterior's data, its hulls and their widths, the support values
        of the restart rows over it (or ``None``), or ``None``."""
        inc, B_step, V = m.fixed_step_set(), m.B_step, m.V_fixed
        # with the polytope restart the window also bounds F z (the restart rows) over
        # its posterior: the support values a later restart from this step uses
        sup_rows = support_rows(m, self.books, k, poly)
        rows = np.vstack([m.hull_rows, sup_rows]) if sup_rows.shape[0] else m.hull_rows
        P_extra = rows if rows.shape[0] else None
        key: tuple
        if mode == "box":
            win = m.window_length()
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
        lo, hi, alw = out
        frac = allowance_fraction(lo, hi, alw, m.margin, m.reported_rows)
        box_o, box, box_x, at = m.split_hull(lo, hi)
        n_sup = sup_rows.shape[0]
        ranges = (lo[at:at + n_sup], hi[at:at + n_sup]) if n_sup else None
        return (ClosedForm(model, c, b, h, c_err, b_err), box, box_o, box_x,
                hi[:at] - lo[:at], ranges, frac)
