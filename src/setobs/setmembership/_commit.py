"""The one commit of an SMFDO step: an engine's answer recorded in the estimator's state.

Every engine (:mod:`setobs.setmembership.engines`) answers a step with an
:class:`~._state.Outcome`, hands it off or declines; :meth:`setobs.SMFDO.step` commits
the answer here: the window's history and restart hulls, the reported
bounds (with their outward margin), and the states' bounds with the tracked
unobservable part (:mod:`._unobservable`).
"""

from __future__ import annotations

import warnings

import numpy as np

from .._lazy import lazy_module
from ..exceptions import EmptySetError, SolverWarning
from ..geometry import Box, ConstrainedZonotope
from ..geometry.box import trusted_box
from ..geometry.zonotope import hull_with_status
from ._model import Entry, SMFDOModel
from ._recursion import posterior, prior
from ._set_estimates import SetEstimateStep
from ._state import Outcome, SMFDOState
from ._unobservable import STARTUP_STEPS

__all__ = ["add_unobservable", "commit", "hull_pair", "startup_step"]

# The compiled margins (numba) load on the first step, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")


def commit(m: SMFDOModel, s: SMFDOState, k: int, mode: str, out: Outcome) -> SetEstimateStep:
    """Record step ``k`` (an engine's :class:`~._state.Outcome`, reached in ``mode``) in
    the state: the posterior, the window's history and restart hull (eq. (24)), the
    reported bounds with the outward margin, the state bounds with the unobservable
    part, and the step's status (``"unbounded"`` where a bound is infinite)."""
    e, box, box_o, box_x, status = out.entry, out.box, out.box_o, out.box_x, out.status
    s.depth = out.depth
    s.blas_small = out.blas_small
    s.k = k
    s.last_y = e.y
    s.Z_src = out.Z_src
    s.box_o_last = box_o
    if mode == "box":
        s.windowing = True
    # the outward margin, the centre and the half-widths in one compiled call
    hull = box_o if box_o is not None else box
    ho_lo, ho_hi, lo, hi, est, rad, finite = _kernels.reported(
        hull.lo, hull.hi, box.lo, box.hi, m.margin)
    if m.window is not None:  # (exact mode runs the plain recursion: no history)
        s.hist.append(e)  # e.dd is None at k = 0 (never used)
        # The restart box of eq. (24) gets the same relative margin as the
        # reported bounds: the set recursion itself rounds (O(eps)), and a
        # box without margin can make a thin set (states pinned to rounding
        # level) empty at a later step.
        s.hulls.append(trusted_box(ho_lo, ho_hi))
        s.hull_u.append(np.zeros(m.sys.p) if e.u is None else e.u)
        # (the restart rows' ranges get the same margin as the hull)
        s.support.append(None if out.support is None else m.outward(*out.support))
        if s.windowing and len(s.hist) > m.window:
            del s.hist[:len(s.hist) - m.window]
    if status == "ok" and not finite:
        status = "unbounded"
    if status == "inexact" and not s.warned_inexact:
        s.warned_inexact = True
        what = ("the window's rounding allowances (the closed form's c_err / b_err)"
                if m.window is not None else
                "the certificate's gap (an inexact multiplier, or a cut history's open bracket)")
        warnings.warn(
            f"SMFDO step k={k}: {what} take {100 * out.gap:.3g} % of a band's width; the "
            "bounds are certified but wider than the mode's exact bounds, flagged "
            "status='inexact' with the fraction in step.gap (warned once per observer)",
            SolverWarning, stacklevel=5)
    x_lo = x_hi = None
    if box_x is not None:
        x_lo, x_hi = m.outward(box_x.lo, box_x.hi)
        if m.ubar is None or box_o is None:  # (box_o: computed whenever ubar is)
            x_lo[m.x_free], x_hi[m.x_free] = -np.inf, np.inf
        else:
            x_lo, x_hi = add_unobservable(m, s, k, e, box_o, x_lo, x_hi)
    # (first_inconsistent: the first skipped or reset step since k = 0)
    return SetEstimateStep(k, est, lo, hi, rad, out.Zd, status, x_lo, x_hi,
                     s.first_inconsistent is not None, float(out.gap))


def add_unobservable(m, s, k: int, e: Entry, box_o: Box, x_lo, x_hi):
    """States on the unobservable part: the observable part's bound (``x_lo``,
    ``x_hi`` on those rows) plus the tracked range of ``Mx_bar zbar_k``
    (:mod:`setobs.setmembership._unobservable`); advances the tracker."""
    T = s.ubar
    f = m.x_free
    joint = None
    if k == 0:
        T.reset()
        s.startup_Z = None
        s.startup_steps = 0
        if not m.hull_feeds_tracker(box_o):
            joint = startup_step(m, s, e, None)
    elif s.startup_Z is not None:
        # the start-up: the joint set of (z_o, zbar) over the whole history so far
        joint = startup_step(m, s, e, s.startup_Z)
        if joint is not None and np.isfinite(joint[2].lo).all() \
                and np.isfinite(joint[2].hi).all():
            T.start_from(joint[2].lo, joint[2].hi)
            if m.hull_feeds_tracker(box_o):
                s.startup_Z = None  # (the tracker goes on from here)
        else:
            T.lost = True
    elif s.ubar_prev is None:  # (no hull of the previous step: unbounded, soundly)
        T.lost = True
    else:
        dd = None if e.dd is None else hull_pair(m, s, e.dd)
        w = None if e.w is None else hull_pair(m, s, e.w)
        T.advance(*s.ubar_prev, e.u, dd, w)
    s.ubar_prev = (box_o.lo, box_o.hi)
    lo_b, hi_b = T.support(m.Mx_bar)
    x_lo, x_hi = x_lo.copy(), x_hi.copy()
    x_lo[f], x_hi[f] = m.outward(x_lo[f] + lo_b, x_hi[f] + hi_b)
    if joint is not None:  # (both bounds are certified: the tighter of each end)
        jl, jh = m.outward(joint[1].lo[f], joint[1].hi[f])
        x_lo[f], x_hi[f] = np.maximum(x_lo[f], jl), np.minimum(x_hi[f], jh)
    return x_lo, x_hi


def startup_step(m, s, e: Entry, Z: ConstrainedZonotope | None):
    """One step of the start-up's joint recursion (``Z``: the joint posterior of the
    previous step, ``None`` at ``k = 0``): ``(Z_k, hull of the state, hull of
    zbar)``, or ``None`` when it ends (``STARTUP_STEPS`` reached, an empty or
    numerically failed set: the tracker is then lost, as before)."""
    M = m.startup
    s.startup_Z = None
    if s.startup_steps >= STARTUP_STEPS:
        return None
    s.startup_steps += 1
    try:
        Zp = M.Z0 if Z is None else prior(m, Z, e, M)
        Zk = posterior(m, Zp, e, s.startup_steps, M.C)
        # (a fallback is still a certified hull, only wider: not flagged here)
        box_x = hull_with_status(M.X @ Zk)[0]
        box_b = hull_with_status(M.bar @ Zk)[0]
    except (EmptySetError, ArithmeticError):
        return None
    s.startup_Z = Zk
    return Zk, box_x, box_b


def hull_pair(m, s, S: ConstrainedZonotope):
    """Certified hull of a per-step set (the fixed sets' once)."""
    if S.dim == 0:
        return None
    hit = s.set_hulls.get(id(S))
    if hit is not None and hit[0] is S:
        return hit[1]
    box = S.interval_hull()
    if len(s.set_hulls) > 8:
        s.set_hulls.clear()
    s.set_hulls[id(S)] = (S, (box.lo, box.hi))
    return box.lo, box.hi
