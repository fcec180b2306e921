"""Bounds of the unobservable part of the state.

In the coordinates of the observability staircase (``z_tilde = T D^-1 [x; d]``,
:class:`~setobs.analysis.ObservabilityDecomposition`) the augmented system is

.. math::  z_{o,k+1} = A_o z_{o,k} + \\dots, \\qquad
           \\bar z_{k+1} = A_{21} z_{o,k} + \\bar A \\bar z_k + \\bar B \\Delta d_k
           + \\bar\\Gamma u_k + \\bar E w_k,

and ``x = D_x (T_o^T z_o + T_obar^T zbar)``. The measurements say nothing about
``zbar`` beyond what the dynamics carry, so a state that depends on it was
reported unbounded. But ``zbar`` is bounded by the initial set, the process noise,
the increments and the observable part's bounds: from a zonotope
``Zbar_0 ⊇ IH(T_obar D^-1 X_0)``, each step

.. math::  \\bar Z_{k+1} = \\bar A \\bar Z_k \\oplus A_{21} \\mathrm{IH}(Z_k)
           \\oplus \\bar B\\, \\mathrm{IH}([\\Delta d_k]) \\oplus \\bar E\\,
           \\mathrm{IH}(W_k) \\oplus \\bar\\Gamma u_k

contains ``zbar_(k+1)`` whenever ``Zbar_k`` contains ``zbar_k`` (``z_o,k`` lies in
the certified hull ``IH(Z_k)`` of the observable set, the noise in its hull): an
outer bound by induction, finite at every ``k`` when ``X_0`` is bounded in those
directions, and bounded in ``k`` when ``A_obar`` is stable (a zonotope, not a box, so
a stable non-normal ``A_obar`` does not blow up by wrapping). The state's bound
is the observable part's certified LP bound plus the support of ``Zbar_k`` in the
state's row. Rounding: every product's error is bounded by Higham's ``gamma`` on
the absolute-value products and added as a box generator; generators beyond
``MAX_ORDER n_bar`` are boxed (Girard's reduction, outer).

The start-up (:class:`StartupModel`). The recursion above needs ``IH(Z_k)`` finite in
the coordinates that ``A_21`` reads, but at the first steps the observable part is
not yet pinned down by the data (a disturbance ``d_0`` that is free until ``y_1``
shows it: ``x2+ = 0.5 x2 + d`` with only ``x1`` measured). Its filtered hull at
step ``k`` is then infinite, although the data up to ``k + 1`` bound it, and the
whole-history LP bounds ``zbar_(k+1)``. So until the filter's hull is finite the
SMFDO carries the *joint* set of all augmented coordinates ``(z_o, zbar)``: the set
recursion of eqs. (20)-(21) on ``A_tilde = [[A_o, 0], [A_21, A_obar]]``, ``C_tilde
= [C_o, 0]``, from ``T D^-1 (X_0 x D_0)``, which is the exact set of the whole
history (no reduction). Its certified hull gives the states' bounds at those steps
(as tight as the whole-history LP), and once both its ``zbar`` hull and the
filter's hull of ``z_o`` are finite (every coordinate: one that ``A_21`` does not read
feeds one it reads through ``A_o``) the tracker starts from that ``zbar`` box (an
outer bound of ``zbar_k``) and goes on as above. The joint set grows by the step's
noise and increment factors, so it is kept for at most ``STARTUP_STEPS`` steps
(then the states on ``zbar`` are reported unbounded, as before).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from .._rounding import gamma
from ..geometry import ConstrainedZonotope
from ..geometry.box import box_center_radius

__all__ = ["StartupModel", "UnobservableTracker"]

#: Generators kept per unobservable dimension (Girard's reduction beyond twice it).
MAX_ORDER = 10
#: Most steps the start-up's joint set is carried (see the module notes).
STARTUP_STEPS = 64


class StartupModel(NamedTuple):
    """The joint recursion of the start-up (see the module notes): the model on all
    augmented coordinates ``z_tilde = (z_o, zbar)`` (balanced units)."""

    A: NDArray[np.float64]        # A_tilde
    B: NDArray[np.float64]        # B_tilde (the increment)
    E: NDArray[np.float64]        # T D^-1 [E; 0] (the process noise)
    Gamma: NDArray[np.float64]    # Gamma_tilde
    C: NDArray[np.float64]        # C_tilde = [C_o, 0]
    X: NDArray[np.float64]        # the state map x = [I 0] D T^T z_tilde
    bar: NDArray[np.float64]      # the rows that select zbar
    Z0: ConstrainedZonotope       # the prior T D^-1 (X_0 x D_0)


class UnobservableTracker:
    """Outer zonotope of the unobservable coordinates ``zbar_k`` (see the module).

    Parameters
    ----------
    A_21, A_bar, B_bar, Gamma_bar, E_bar : ndarray
        Blocks of the staircase form (balanced units): ``zbar`` from ``z_o``, from
        ``zbar``, from the increment, the input and the process noise.
    lo0, hi0 : ndarray
        Certified hull of ``zbar_0`` (finite).
    data_rtol : float
        Relative representation error of every input.
    """

    def __init__(self, A_21, A_bar, B_bar, Gamma_bar, E_bar, lo0, hi0, data_rtol: float):
        self.A_21, self.A_bar, self.B_bar = A_21, A_bar, B_bar
        self.Gamma_bar, self.E_bar = Gamma_bar, E_bar
        self._abs = [np.abs(M) for M in (A_21, A_bar, B_bar, Gamma_bar, E_bar)]
        self.data_rtol = float(data_rtol)
        n_u = A_bar.shape[0]
        self._g = 2.0 * gamma(n_u + A_21.shape[1] + B_bar.shape[1] + Gamma_bar.shape[1]
                              + E_bar.shape[1] + MAX_ORDER * 2 * n_u + 8)
        self.c0, r = box_center_radius(lo0, hi0)
        self.G0 = np.diag(r)
        self.reset()

    def reset(self) -> None:
        """Back to ``Zbar_0``."""
        self.c, self.G = self.c0.copy(), self.G0.copy()
        self.lost = False

    def start_from(self, lo, hi) -> None:
        """Restart from the certified box ``[lo, hi]`` of ``zbar_k`` (finite)."""
        self.c, r = box_center_radius(lo, hi)
        self.G = np.diag(r)
        self.lost = False

    def advance(self, lo_o, hi_o, u, dd_box, w_box) -> None:
        """``Zbar_k -> Zbar_(k+1)`` from the hull ``[lo_o, hi_o]`` of ``Z_k``, the input
        ``u_k`` (or ``None``) and the hulls of the increment and noise sets (``(lo, hi)``
        or ``None``)."""
        if self.lost:
            return
        aA21, aA, aB, aGam, aE = self._abs
        c, G = self.c, self.G
        parts_c = [self.A_bar @ c]
        cols = [self.A_bar @ G]
        mag = aA @ np.abs(c) + (aA @ np.abs(G)).sum(axis=1)
        for M, aM, box in ((self.A_21, aA21, (lo_o, hi_o)), (self.B_bar, aB, dd_box),
                           (self.E_bar, aE, w_box)):
            if box is None or not M.shape[1]:
                continue
            lo, hi = box
            used = aM.max(axis=0) > 0
            if not (np.isfinite(lo[used]).all() and np.isfinite(hi[used]).all()):
                self.lost = True  # (a coupled coordinate is unbounded: so is zbar)
                self.c = np.full_like(c, np.nan)
                return
            m, r = box_center_radius(np.where(used, lo, 0.0), np.where(used, hi, 0.0))
            parts_c.append(M @ m)
            cols.append(M * r[None, :])
            mag = mag + aM @ (np.abs(m) + r)
        if u is not None and self.Gamma_bar.shape[1]:
            parts_c.append(self.Gamma_bar @ u)
            tu = aGam @ np.abs(u)
            mag = mag + tu * (1.0 + self.data_rtol / self._g)
        c_new = np.sum(parts_c, axis=0)
        err = self._g * (mag + np.abs(c_new))
        G_new = np.hstack([*cols, np.diag(err)])
        G_new = G_new[:, np.abs(G_new).max(axis=0) > 0]
        n_u = c.size
        if G_new.shape[1] > 2 * MAX_ORDER * n_u:
            L = np.abs(G_new)
            score = L.sum(axis=0) - L.max(axis=0)
            order = np.argsort(score)[::-1]
            keep, boxed = order[:MAX_ORDER * n_u - n_u], order[MAX_ORDER * n_u - n_u:]
            s = np.abs(G_new[:, boxed]).sum(axis=1)
            s = np.nextafter(s * (1.0 + gamma(boxed.size + 1)), np.inf)
            G_new = np.hstack([G_new[:, np.sort(keep)], np.diag(s)])
        self.c, self.G = c_new, G_new

    def support(self, M: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """Certified range ``(lo, hi)`` of ``M zbar`` over ``Zbar_k`` (``-inf, inf`` once
        lost)."""
        if self.lost:
            return np.full(M.shape[0], -np.inf), np.full(M.shape[0], np.inf)
        mid = M @ self.c
        rad = np.abs(M @ self.G).sum(axis=1)
        aM = np.abs(M)
        err = gamma(self.c.size + self.G.shape[1] + 2) * (
            aM @ np.abs(self.c) + (aM @ np.abs(self.G)).sum(axis=1) + rad)
        return mid - (rad + err), mid + (rad + err)
