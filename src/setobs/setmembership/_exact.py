"""Exact mode of the SMFDO: the H-representation recursion (:mod:`._hrep`) driven step by step."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._rounding import gamma, round_down, round_up
from ..geometry import ConstrainedZonotope
from ..geometry.zonotope import hull_with_status
from ..tolerances import (
    HREP_CONVERT_RTOL,
    UNBOUNDED_RADIUS,
)
from ._history import HistoryLP
from ._hrep import (
    HState,
    snap_normals,
    step_geometry,
    structure_A,
    tidy_vertices,
    vertices_match,
)
from ._setup import MODEL_CACHE, Entry
from ._window import WindowModel

__all__ = ["HISTORY_RETRY", "H_CONVERSION_LPS", "H_LAX_SIZE_FACTOR", "H_MAX_NORMALS",
           "H_MAX_VERTICES", "ExactSteps"]

#: LP budget of converting a bounded posterior to the H-representation of exact
#: mode (a beneath-beyond vertex enumeration); beyond it the set recursion goes on.
H_CONVERSION_LPS = 150

#: Complexity beyond which exact mode leaves the H-representation recursion for
#: the set recursion (vertices, normals): measurement noise can make the exact
#: set's complexity grow quickly (the paper example with a noise box: 44, 107,
#: 264 facets and 178, 361, 754 vertices at k = 2, 3, 4; benchmarks/exact_mode.py),
#: and then the vertex geometry costs more than the whole-history LPs.
H_MAX_VERTICES = 128
H_MAX_NORMALS = 64


#: Steps after a failed start of exact mode's whole-history LP (an unbounded
#: posterior, or free factors that could not be eliminated) before the next try.
HISTORY_RETRY = 4


#: Exact mode converts a posterior whose facets are confirmed only to
#: ``VERTEX_RTOL`` (not ``HREP_CONVERT_RTOL``) when its box is at most this many
#: times wider than one step's uncertainty: converted earlier, in the transient
#: before the data bound the set (widths 1e3 to 1e5 times the later ones), that
#: tolerance became 1e-6 of the later width (the verdict campaign on random systems,
#: seed 36).
H_LAX_SIZE_FACTOR = 1e3


class ExactSteps:
    """Exact-mode steps of the SMFDO (a mixin of :class:`~setobs.SMFDO`): conversion of
    a bounded posterior to an H-representation and one certified step of it."""

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

            # (no disturbance, q = 0: the point {0}, neutral in the Minkowski sum)
            images = [vertices(self._inc_fixed) @ self.B_o.T if self.sys.q
                      else np.zeros((1, self.A_o.shape[0]))]
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

    def _hrep_step(self, e: Entry):
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
        # rows beyond z: P (unless it selects coordinates), the state map (state
        # bounds, unless it selects coordinates), then the new facet normals
        P_ext = np.vstack([self._hull_rows, H_new])
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
                self._retire_states()
            state = self._states[key] = model.new_state()
        c_S, b_S, h_S, b_S_err = st.start()
        U = (e.u if e.u is not None else np.zeros(self.sys.p))[None, :] if self.sys.p \
            else np.zeros((1, 0))
        Y_err = None if e.yerr is None else e.yerr[None, :]
        c, b, h, c_err, b_err, y_scale = model.assemble(
            c_S, b_S, h_S, y[None, :], U, b_S_err=b_S_err, data_rtol=self.data_rtol,
            Y_err=Y_err)
        out = model.hull(c, b, h, y_scale, state, b_err, c_err)
        if out is None:
            return None
        lo, hi = out
        if not (np.isfinite(lo).all() and np.isfinite(hi).all()):
            return None
        box_o, box, box_x, at = self.split_hull(lo, hi)
        g = hi[at:]
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
            return model.to_cz(c, b, h, c_err, b_err), box, box_o, Zd, box_x
        return HState(H_new, g, lo_c, hi_c, V_t), box, box_o, Zd, box_x

    # ------------------------------------------------------------------ with noise
    def _history_kw(self) -> dict:
        return dict(A_o=self.A_o, Gamma_o=self.Gamma_o, C_o=self.C_o, B_o=self.B_o,
                    E_o=self._E_o, rows=self._hull_rows, data_rtol=self.data_rtol)

    def _history_start(self, k: int) -> HistoryLP | None:
        """Exact mode's whole-history LP (:mod:`._history`) from the current posterior,
        once it is bounded; ``None`` before (the set recursion goes on)."""
        from ..exceptions import SetobsError
        from ..geometry.reduction import reduce_exact

        box = self._box_o_last
        if k < self._hist_retry_at or box is None or not (
                np.isfinite(box.lo).all() and np.isfinite(box.hi).all()):
            return None
        Z = self._Z
        if Z is None:
            return None
        try:
            if np.isinf(Z.h).any():  # (X0 = R^n: its factors pivoted out, exactly)
                Z = reduce_exact(Z)
            H = HistoryLP.start(Z, box.lo, box.hi, **self._history_kw())
        except SetobsError:
            H = None
        if H is None:
            self._hist_retry_at = k + HISTORY_RETRY
        return H

    def _history_step(self, k: int, mode: str, e: Entry):
        """One exact step with noise on the whole-history LP, or ``None`` (not started:
        the set recursion decides)."""
        H = self._Z_src
        if not isinstance(H, HistoryLP):
            H = self._history_start(k)
            if H is None:
                return None
        H.push(e)
        out = H.hull()
        if out is None:
            H.pop()
            return self._history_fallback(k, mode, e, H)
        box_o, box, box_x, _ = self.split_hull(*out)
        self.stats["fast"] += 1
        self._depth = 0
        return self._commit(k, mode, H, box, box_o, None, e, "ok", box_x)

    def _history_fallback(self, k: int, mode: str, e: Entry, H: HistoryLP):
        """A step the history LP did not decide (infeasible: the data may contradict
        the model; a numerical failure): the set recursion decides it from the exact
        posterior (:meth:`HistoryLP.to_cz`), with its certified emptiness test and
        retries; the history then goes on with the step as that decided it."""
        from ..exceptions import ModelInvalidatedError

        self._Z_src = H.to_cz()
        self._depth = 0
        try:
            step = self._reference_step(k, mode, e)
        except ModelInvalidatedError:
            self._Z_src = H  # (the observer is left as before the step)
            raise
        box = self._box_o_last
        if step.status in ("ok", "fallback", "skipped") and box is not None and \
                np.isfinite(box.lo).all() and np.isfinite(box.hi).all():
            H.push(e.skipped() if step.status == "skipped" else e)
            H.box = (box.lo.copy(), box.hi.copy())
            self._Z_src = H
        return step
