"""The recursion of the SMFDO (Li-Cong-Dong, Algorithm 1, lines 5-11 and 14): the prior
(eq. (20)), the posterior (eq. (21)) and the bounds of a posterior (line 14), on
constrained zonotopes over the model (:class:`._model.SMFDOModel`).

The reference engine runs them step by step and over the window's re-run (eq. (24));
the start-up of the unobservable part runs them on its joint model."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._rounding import UNIT_ROUNDOFF
from ..geometry import Box, ConstrainedZonotope
from ..geometry.zonotope import absorb_center_error, hull_with_status, trusted_cz
from ..tolerances import CENTER_ERROR_ABSORB_RTOL
from ._closed_form import model_rtol
from ._model import Entry, SMFDOModel
from ._unobservable import StartupModel

__all__ = ["bounds", "posterior", "prior"]


def prior(m: SMFDOModel, Z: ConstrainedZonotope, e: Entry,
          model: StartupModel | None = None) -> ConstrainedZonotope:
    """Eq. (20) with process noise: ``A_o Z + B_o Z^Delta + E_o W + Gamma_o u``
    (``model``: the start-up's joint model instead, :class:`._unobservable.StartupModel`).

    The centre's rounding bound goes through ``A_o`` as factors once it is
    above rounding level (:func:`~setobs.geometry.zonotope.absorb_center_error`).
    """
    A, B, E, Gam = ((m.A_o, m.B_o, m.E_o, m.Gamma_o) if model is None
                    else (model.A, model.B, model.E, model.Gamma))
    Z = absorb_center_error(Z, CENTER_ERROR_ABSORB_RTOL)
    Zp = A @ Z if e.dd is None else A @ Z + B @ e.dd  # (dd: from step 1 on)
    if e.w is not None:
        Zp = Zp + E @ e.w
    u = e.u
    if u is not None and m.sys.p:
        v = Gam @ u
        err = m.data_rtol * (np.abs(Gam) @ np.abs(u)) if m.data_rtol else None
        Zp = Zp.minkowski_sum(v, err=err)
    return Zp


def posterior(m: SMFDOModel, Zp: ConstrainedZonotope, e: Entry, depth: int,
              C_full: NDArray[np.float64] | None = None) -> ConstrainedZonotope:
    """Eq. (21): ``Zp ∩ {z : C_o z in y - F_b V}`` on the measured rows of ``y``
    (balanced units); with no noise set, ``{z : C_o z = y}``; with nothing
    measured, ``Zp`` (a prediction step).

    ``y`` is known to within ``data_rtol |y|`` plus the model allowance of
    ``depth`` recursion steps (see :mod:`setobs.setmembership._closed_form`) and
    the feedthrough's rounding.
    """
    y = e.y
    meas = ~np.isnan(y)
    if not meas.any():
        return Zp
    nD = m.inc_fixed.n_gen if m.inc_fixed is not None else m.sys.q
    nV = 0 if e.v is None else e.v.n_gen
    Cf = m.C_o if C_full is None else C_full
    rtol = m.data_rtol + model_rtol(depth, Cf.shape[1], m.sys.p, nD + nV)
    ym = y[meas]
    y_err = rtol * np.abs(ym)
    if e.yerr is not None:
        y_err = y_err + e.yerr[meas]
    C = Cf if meas.all() else Cf[meas]
    if e.v is None:
        return Zp.intersect_affine(C, ym, y_err=y_err)
    V = e.v
    # the set y - V_m (rows m of F_b V): centre y - c_V (rounded once), the
    # noise's own constraints, generators -G_V
    cY = ym - V.c[meas]
    cY_err = UNIT_ROUNDOFF * np.abs(cY) + V.c_err[meas] + y_err
    Yset = trusted_cz(-V.G[meas], cY, V.A, V.b, V.h, V.unbounded_radius, cY_err, V.b_err)
    return Zp.intersect(Yset, R=C)


def bounds(m: SMFDOModel, Z: ConstrainedZonotope
           ) -> tuple[ConstrainedZonotope, Box, Box | None, bool, Box | None]:
    """Disturbance set ``P Z``, its hull, (windowed mode) the hull of ``Z``, whether
    an LP fell back, and (``state_bounds``) the hull of the state ``M_x Z``."""
    fb_o = False
    box_o = None
    if m.window is not None or m.history_on or (m.state_bounds and (
            m.X_coords is not None or m.ubar is not None)):
        box_o, fb_o = hull_with_status(Z)
    box_x, fb_x = None, False
    if m.state_bounds:
        if m.X_coords is not None and box_o is not None:  # (box_o: computed above)
            box_x = m.coordinate_states(box_o.lo, box_o.hi)
        else:  # (the same factor polytope: its HiGHS model is reused)
            box_x, fb_x = hull_with_status(m.Mx @ Z)
    Zd = m.P @ Z
    if box_o is not None and m.P_coords is not None:
        j = m.P_coords
        return Zd, Box(box_o.lo[j], box_o.hi[j]), box_o, fb_o or fb_x, box_x
    box_d, fb_d = hull_with_status(Zd)
    return Zd, box_d, box_o, fb_o or fb_d or fb_x, box_x
