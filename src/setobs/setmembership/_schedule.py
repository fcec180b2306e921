"""The window's schedule (Algorithm 1, lines 12-13): how each step starts (eq. (24)'s
restart from a hull, the whole history from ``Z_0^-``, or one more recursion step), the
re-run's data, and the restart set (the box, cut by the polytope restart's carried-back
rows, :mod:`._restart`); shared by the window engine and the reference engine."""

from __future__ import annotations

import numpy as np

from .._lazy import lazy_module
from ..geometry import Box, ConstrainedZonotope
from ..geometry.zonotope import trusted_cz
from ._model import Entry, SMFDOModel
from ._restart import RestartPolytope
from ._state import SMFDOState

# The compiled restart data (numba) loads on the first window, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")
_EMPTY = np.zeros(0)

__all__ = ["TRANSIENT_RATIO", "TRANSIENT_WAIT", "in_transient", "init_lags", "polytope_now",
           "restart_cz", "restart_rows", "restart_start", "start_mode", "support_at",
           "window_hist"]

#: The polytope restart's first restart also waits while the hull it would restart from
#: (at ``k - delta``) is more than this many times as wide as the newest hull in some
#: coordinate: the transient from a wide initial set, which a restart would carry into
#: the window (with and without the wait on a slow 30-tank cascade:
#: ``benchmarks/results/window_worst.json``; in development runs, without the
#: :data:`TRANSIENT_WAIT` cap, a ratio of 1.5 kept the whole history there until the
#: restart's growth limit, at 7 times the cost, for little).
TRANSIENT_RATIO = 2.0
#: ... but at most this many windows beyond the window (the whole history's LP grows
#: with every step it waits).
TRANSIENT_WAIT = 2


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
    """Steps the first restart waits for beyond the window. With the polytope restart, the
    restart at ``t`` carries back only the hulls known at ``t``: a restart in the first
    steps is shallow (wider than the exact set). Until it can carry back its full depth
    (``restart_lags``) each step is the whole history from ``Z_0^-``, the exact set, as long
    as that LP is no larger than the polytope window's: ``N + k f`` against ``N + R + delta
    f`` factors (``f`` per step, ``R`` the polytope's rows), so at most ``R // f`` steps
    (its LPs are cold: a longer wait costs more than it gains), and while the restart hull
    is still in its transient (:data:`TRANSIENT_RATIO`; at most :data:`TRANSIENT_WAIT`
    windows). None with the box restart (eq. (24) as the paper runs it)."""
    if not polytope_now(m, s) or m.restart_poly is None:
        return 0
    f = m.fixed_step_set().n_gen + (0 if m.V_fixed is None else m.V_fixed.n_gen)
    lags = min(m.restart_lags, m.restart_poly.F_all.shape[0] // max(f, 1))
    win = m.window_length()
    if len(s.hulls) >= win and in_transient(s.hulls[-win], s.hulls[-1]):
        return max(lags, TRANSIENT_WAIT * win)
    return lags


def in_transient(old: Box, new: Box) -> bool:
    """Whether ``old`` is more than :data:`TRANSIENT_RATIO` times as wide as ``new`` in a
    coordinate where both are finite (and ``new`` not flat)."""
    wo, wn = old.hi - old.lo, new.hi - new.lo
    ok = np.isfinite(wo) & np.isfinite(wn) & (wn > 0.0)
    return bool(ok.any() and np.any(wo[ok] > TRANSIENT_RATIO * wn[ok]))


def window_hist(m: SMFDOModel, s: SMFDOState, entry: Entry) -> list[Entry]:
    """The data of the window's re-run ending at ``entry`` (eq. (24))."""
    win = m.window_length()
    return [*s.hist[-(win - 1):], entry] if win > 1 else [entry]


def polytope_now(m: SMFDOModel, s: SMFDOState) -> bool:
    """Whether the next restart carries the polytope's rows (``restart="auto"``: the
    choice of the last probe)."""
    return m.restart == "polytope" or (m.restart == "auto" and s.poly_restart)


def restart_rows(m: SMFDOModel, s: SMFDOState, poly: bool = True, support: bool = True):
    """The restart set at ``t = k - delta``: its hull's bounds, and the carried-back
    rows ``F`` with their ranges (none with ``poly`` false or ``restart="box"``;
    :mod:`setobs.setmembership._restart`), intersected with the window's own support
    values of ``Z_t`` in the rows' directions where they were computed at ``t`` (and
    ``support``)."""
    win = m.window_length()
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
        box_t = s.hulls[-m.window_length()]
        c_S, h_S = _kernels.box_start(box_t.lo, box_t.hi)
        return c_S, _EMPTY, h_S, np.zeros((0, c_S.size))
    lo, hi, F, rlo, rhi = restart_rows(m, s, poly, support)
    return (*RestartPolytope.start_data(lo, hi, F, rlo, rhi), F)


def restart_cz(m: SMFDOModel, s: SMFDOState) -> ConstrainedZonotope:
    """The restart set as a constrained zonotope (the reference path)."""
    c_S, b_S, h_S, F = restart_start(m, s, polytope_now(m, s))
    G_S, A_S = RestartPolytope.structure(F)
    return trusted_cz(G_S, c_S, A_S, b_S, h_S)


