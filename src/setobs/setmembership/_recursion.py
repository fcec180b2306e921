"""The SMFDO's set recursion (eqs. (20)-(21)), its consistency verdicts and step statuses."""

from __future__ import annotations

import warnings

import numpy as np

from .._lazy import lazy_module
from .._rounding import UNIT_ROUNDOFF
from ..exceptions import (
    EmptySetError,
    ModelInvalidatedError,
    ModelInvalidatedWarning,
    SolverWarning,
)
from ..geometry import Box, ConstrainedZonotope
from ..geometry.box import trusted_box
from ..geometry.zonotope import absorb_center_error, hull_with_status, trusted_cz
from ..tolerances import CENTER_ERROR_ABSORB_RTOL
from ._setup import Entry
from ._steps import SMFDOStep
from ._window import model_rtol

__all__ = ["ON_INCONSISTENT", "SetRecursion"]

# The compiled margins (numba) load on the first step, not on import.
_kernels = lazy_module("setobs.setmembership._kernels")

#: ``on_inconsistent`` choices.
ON_INCONSISTENT = ("raise", "skip", "reset")


class SetRecursion:
    """The set recursion of the SMFDO (a mixin of :class:`~setobs.SMFDO`): prior and
    posterior, the reference step with its inconsistency policy and fallback
    flag, and the committed step's reported bounds."""

    # ------------------------------------------------------------------ recursion
    def _prior(self, Z: ConstrainedZonotope, e: Entry, model=None) -> ConstrainedZonotope:
        """Eq. (20) with process noise: ``A_o Z + B_o Z^Delta + E_o W + Gamma_o u``
        (``model``: the start-up's joint model instead, :class:`._unobservable.StartupModel`).

        The centre's rounding bound goes through ``A_o`` as factors once it is
        above rounding level (:func:`~setobs.geometry.zonotope.absorb_center_error`).
        """
        A, B, E, Gam = ((self.A_o, self.B_o, self._E_o, self.Gamma_o) if model is None
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

    def _posterior(self, Zp: ConstrainedZonotope, e: Entry,
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
        nD = self._inc_fixed.n_gen if self._inc_fixed is not None else self.sys.q
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

    def _reference_step(self, k: int, mode: str, e: Entry) -> SMFDOStep:
        """One step on the set recursion (eqs. (20)-(21), or the window's re-run from
        the restart box): the bounds, and the consistency verdict and status."""
        self.stats["reference"] += 1
        if k == 0:
            Zp = self._Z0_prior
            depth = 0
        elif mode == "box":
            # Lines 12-13 / eq. (24): re-run the last delta steps from IH(Z_(k-delta))
            # (cut by the carried-back rows of the polytope restart).
            Z = self._restart_cz()
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
            Zd, box, box_o, fell_back, box_x = self._bounds(Z)
        except EmptySetError:
            msg = (f"the measurement at step k={k} is inconsistent with the model and the "
                   "uncertainty sets (empty posterior)")
            if self.on_inconsistent == "raise":
                raise self._invalidated(msg, k) from None
            # One-step prior from the last valid posterior (the windowed re-run may
            # pass through the same inconsistency again).
            Zp1 = self._Z0_prior if k == 0 else self._prior(self._Z, e)
            if self.on_inconsistent == "skip":
                # The measurement is dropped, here and in the window's history.
                e = e.skipped()
                Z = Zp1
                depth = self._depth + 1 if k else 0
                Zd, box, box_o, fell_back, box_x = self._bounds(Z)
                status = "skipped"
            else:
                Z = self._handle_empty(k, Zp1, e, msg)
                depth = 0
                Zd, box, box_o, fell_back, box_x = self._bounds(Z)
                # The window restarts from the reset set: eq. (24) is applied again
                # only once delta consistent steps have been collected.
                self._hulls.clear()
                self._hull_u.clear()
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
                    ModelInvalidatedWarning, stacklevel=4)
        if fell_back:
            status = "fallback" if status == "ok" else status
            self.stats["fallback"] += 1
            if not self._warned_fallback:
                self._warned_fallback = True
                warnings.warn(
                    f"SMFDO step k={k}: an LP failed under every solver setting; the bounds "
                    "of this step are wider (still certified) and flagged status='fallback' "
                    "(warned once per observer)", SolverWarning, stacklevel=4)
        self._depth = depth
        return self._commit(k, mode, Z, box, box_o, Zd if self.keep_sets else None, e,
                            status, box_x)

    def _commit(self, k, mode, Z_src, box, box_o, Zd, e: Entry, status,
                box_x: Box | None = None) -> SMFDOStep:
        self.k = k
        self._last_y = e.y
        self._Z_src = Z_src
        self._box_o_last = box_o
        if mode == "box":
            self._windowing = True
        # the outward margin, the centre and the half-widths in one compiled call
        has_o = box_o is not None
        ho_lo, ho_hi, lo, hi, est, rad, finite = _kernels.reported(
            box_o.lo if has_o else box.lo, box_o.hi if has_o else box.hi, box.lo, box.hi,
            self.margin)
        if self.window is not None:  # (exact mode runs the plain recursion: no history)
            self._hist.append(e)  # e.dd is None at k = 0 (never used)
            # The restart box of eq. (24) gets the same relative margin as the
            # reported bounds: the set recursion itself rounds (O(eps)), and a
            # box without margin can make a thin set (states pinned to rounding
            # level) empty at a later step.
            self._hulls.append(trusted_box(ho_lo, ho_hi))
            self._hull_u.append(np.zeros(self.sys.p) if e.u is None else e.u)
            if self._windowing and len(self._hist) > self.window:
                del self._hist[:len(self._hist) - self.window]
        if status == "ok" and not finite:
            status = "unbounded"
        x_lo = x_hi = None
        if box_x is not None:
            x_lo, x_hi = self._outward(box_x.lo, box_x.hi)
            if self._ubar is None:
                x_lo[self._x_free], x_hi[self._x_free] = -np.inf, np.inf
            else:
                x_lo, x_hi = self._add_unobservable(k, e, box_o, x_lo, x_hi)
        # (first_inconsistent: the first skipped or reset step since k = 0)
        return SMFDOStep(k, est, lo, hi, rad, Zd, status, x_lo, x_hi,
                         self.first_inconsistent is not None)

    def _add_unobservable(self, k: int, e: Entry, box_o: Box, x_lo, x_hi):
        """States on the unobservable part: the observable part's bound (``x_lo``,
        ``x_hi`` on those rows) plus the tracked range of ``Mx_bar zbar_k``
        (:mod:`setobs.setmembership._unobservable`); advances the tracker."""
        T = self._ubar
        f = self._x_free
        joint = None
        if k == 0:
            T.reset()
            self._startup_Z = None
            self._startup_steps = 0
            if not self._hull_feeds_tracker(box_o):
                joint = self._startup_step(e, None)
        elif self._startup_Z is not None:
            # the start-up: the joint set of (z_o, zbar) over the whole history so far
            joint = self._startup_step(e, self._startup_Z)
            if joint is not None and np.isfinite(joint[2].lo).all() \
                    and np.isfinite(joint[2].hi).all():
                T.start_from(joint[2].lo, joint[2].hi)
                if self._hull_feeds_tracker(box_o):
                    self._startup_Z = None  # (the tracker goes on from here)
            else:
                T.lost = True
        elif self._ubar_prev is None:  # (no hull of the previous step: unbounded, soundly)
            T.lost = True
        else:
            dd = None if e.dd is None else self._hull_pair(e.dd)
            w = None if e.w is None else self._hull_pair(e.w)
            T.advance(*self._ubar_prev, e.u, dd, w)
        self._ubar_prev = (box_o.lo, box_o.hi)
        lo_b, hi_b = T.support(self._Mx_bar)
        x_lo, x_hi = x_lo.copy(), x_hi.copy()
        x_lo[f], x_hi[f] = self._outward(x_lo[f] + lo_b, x_hi[f] + hi_b)
        if joint is not None:  # (both bounds are certified: the tighter of each end)
            jl, jh = self._outward(joint[1].lo[f], joint[1].hi[f])
            x_lo[f], x_hi[f] = np.maximum(x_lo[f], jl), np.minimum(x_hi[f], jh)
        return x_lo, x_hi

    @staticmethod
    def _hull_feeds_tracker(box_o: Box) -> bool:
        """Whether the filter's hull is finite (in every coordinate: one that ``A_21``
        does not read may still feed one it reads at the next step)."""
        return bool(np.isfinite(box_o.lo).all() and np.isfinite(box_o.hi).all())

    def _startup_step(self, e: Entry, Z: ConstrainedZonotope | None):
        """One step of the start-up's joint recursion (``Z``: the joint posterior of the
        previous step, ``None`` at ``k = 0``): ``(Z_k, hull of the state, hull of
        zbar)``, or ``None`` when it ends (``STARTUP_STEPS`` reached, an empty or
        numerically failed set: the tracker is then lost, as before)."""
        from ._unobservable import STARTUP_STEPS

        M = self._startup
        self._startup_Z = None
        if self._startup_steps >= STARTUP_STEPS:
            return None
        self._startup_steps += 1
        try:
            Zp = M.Z0 if Z is None else self._prior(Z, e, M)
            Zk = self._posterior(Zp, e, self._startup_steps, M.C)
            # (a fallback is still a certified hull, only wider: not flagged here)
            box_x = hull_with_status(M.X @ Zk)[0]
            box_b = hull_with_status(M.bar @ Zk)[0]
        except (EmptySetError, ArithmeticError):
            return None
        self._startup_Z = Zk
        return Zk, box_x, box_b

    def _hull_pair(self, S: ConstrainedZonotope):
        """Certified hull of a per-step set (the fixed sets' once)."""
        if S.dim == 0:
            return None
        hit = self._set_hulls.get(id(S))
        if hit is not None and hit[0] is S:
            return hit[1]
        box = S.interval_hull()
        if len(self._set_hulls) > 8:
            self._set_hulls.clear()
        self._set_hulls[id(S)] = (S, (box.lo, box.hi))
        return box.lo, box.hi

    def _bounds(self, Z: ConstrainedZonotope):
        """Disturbance set ``P Z``, its hull, (windowed mode) the hull of ``Z``, whether
        an LP fell back, and (``state_bounds``) the hull of the state ``M_x Z``."""
        fb_o = False
        box_o = None
        if self.window is not None or self._history_on or (self.state_bounds and (
                self._X_coords is not None or self._ubar is not None)):
            box_o, fb_o = hull_with_status(Z)
        box_x, fb_x = None, False
        if self.state_bounds:
            if self._X_coords is not None:
                box_x = self._coordinate_states(box_o.lo, box_o.hi)
            else:  # (the same factor polytope: its HiGHS model is reused)
                box_x, fb_x = hull_with_status(self._Mx @ Z)
        Zd = self.P @ Z
        if box_o is not None and self._P_coords is not None:
            j = self._P_coords
            return Zd, Box(box_o.lo[j], box_o.hi[j]), box_o, fb_o or fb_x, box_x
        box_d, fb_d = hull_with_status(Zd)
        return Zd, box_d, box_o, fb_o or fb_d or fb_x, box_x

    def _outward(self, lo, hi):
        """``lo``, ``hi`` widened by the relative margin (``margin * max(1, |end|)``)."""
        return _kernels.outward_margin(np.asarray(lo, dtype=np.float64),
                                       np.asarray(hi, dtype=np.float64), self.margin)

    def _handle_empty(self, k: int, Zp: ConstrainedZonotope, e: Entry, msg: str):
        """``on_inconsistent="reset"``: the posterior of an inflated box of ``Zp``."""
        try:
            hull, _ = hull_with_status(Zp)
        except EmptySetError:
            raise self._invalidated(msg + " (the prior itself is empty)", k) from None
        w = np.where(np.isfinite(hull.width), hull.width, 0.0)
        scale = 1.0 + float(np.abs(np.where(np.isfinite(hull.lo), hull.lo, 0.0)).max(initial=0.0))
        factor = self.reset_inflation
        for _ in range(40):  # inflate geometrically until the measurement is explainable
            pad = factor * (w + scale)
            Zr = self._posterior(self._box_cz(Box(hull.lo - pad, hull.hi + pad)), e, 0)
            if not Zr.is_empty():
                return Zr
            factor *= 4.0
        raise self._invalidated(msg + " (no reset box explains it)", k)

    def _invalidated(self, msg: str, k: int) -> ModelInvalidatedError:
        """The error for step ``k``, its advice naming what this model has (an increment
        set, or for a model without disturbances the process noise)."""
        hint = ModelInvalidatedError.HINT if self.sys.q else ModelInvalidatedError.HINT_STATE
        return ModelInvalidatedError(msg, k, hint)
