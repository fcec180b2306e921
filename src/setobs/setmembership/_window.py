"""Closed form of ``s`` SMFDO steps from a start set: the fast path of Algorithm 1.

Running eqs. (20)-(21) of Li-Cong-Dong ``s`` times from a start set
``S = {c_S + G_S xi_S : A_S xi_S = b_S, |xi_S| <= h_S}`` gives the constrained
zonotope (the closed form (24) when ``S`` is the interval hull of
``Z_(k-delta)``)

.. math::  Z = \\{c + G \\xi : A \\xi = b, |\\xi| \\le h\\},
           \\quad \\xi = (\\xi_S, \\xi_{\\Delta,1}, \\dots, \\xi_{\\Delta,s}),

with ``G = [A_o^s G_S, A_o^(s-1) B_o G_D, ..., B_o G_D]`` and ``A`` stacking
``A_S``, the increment set's constraints and ``C_o G_j`` for every posterior
``j``. ``G`` and ``A`` depend only on the system, the increment set, the start
set's generators and ``s``; the data enter only ``b`` and ``c`` (affinely) and
the reset box enters only ``c_S`` and ``h_S``. So the LPs of the interval hull
have a fixed structure and go through
:class:`setobs.geometry.fastlp.FixedStructureLP`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..geometry import ConstrainedZonotope
from ..geometry.fastlp import FixedStructureLP, hull_from_bounds, hull_objectives


class WindowModel:
    """``s`` prior/posterior steps of Algorithm 1 from a start set, in closed form.

    Parameters
    ----------
    A_o, B_o, C_o, Gamma_o : ndarray
        Observable-coordinate matrices of the augmented system.
    increment : ConstrainedZonotope
        The (fixed) increment set ``[[dd]]``.
    G_S, A_S : ndarray
        Generators and constraints of the start set.
    free_S : ndarray of bool
        Unbounded factors of the start set.
    s : int
        Number of prior/posterior steps.
    first_posterior : bool
        Intersect the start set with the measurement before the first prior
        (the start is ``Z_0^-``, Algorithm 1 line 2), so ``s + 1`` measurements
        are used; otherwise ``s``.
    P : ndarray or None
        Extra objective rows (``P`` of Algorithm 1, line 14) when the hull of
        ``P Z`` is not a coordinate selection of the hull of ``Z``.
    radius : float
        Radius on unbounded factors (certification).
    """

    def __init__(self, A_o, B_o, C_o, Gamma_o, increment: ConstrainedZonotope,
                 G_S, A_S, free_S, s: int, first_posterior: bool,
                 P: NDArray[np.float64] | None, radius: float) -> None:
        N, nS = G_S.shape
        GD, AD = increment.G, increment.A
        nD, cD = GD.shape[1], increment.c
        l, p = C_o.shape[0], Gamma_o.shape[1]
        n_g = nS + s * nD
        self.s, self.first_posterior, self.N = s, first_posterior, N
        self.l, self.p = l, p
        n_y = s + int(first_posterior)
        # Rows: start constraints, then per posterior: increment rows (for steps
        # >= 1) and C_o rows. b = b0 + Bc c_S + Bu u + scatter(y); the start set's
        # own b_S enters through b0 (set per call by the caller's b_S).
        rows_A = [np.hstack([A_S, np.zeros((A_S.shape[0], n_g - nS))])]
        self.nS_rows = A_S.shape[0]
        const_rows: list[NDArray[np.float64]] = []   # constant b part per row block
        c_rows: list[NDArray[np.float64]] = []       # coefficient of c_S
        u_rows: list[NDArray[np.float64]] = []       # coefficient of u_flat
        y_pos: list[int] = []
        G = np.zeros((N, n_g))
        G[:, :nS] = G_S
        Mc = np.eye(N)                 # c_j = Mc c_S + Mu u_flat + kappa
        Mu = np.zeros((N, s * p))
        kappa = np.zeros(N)
        row = self.nS_rows
        BcD = B_o @ cD

        def posterior() -> None:
            nonlocal row
            rows_A.append(C_o @ G)
            const_rows.append(-C_o @ kappa)
            c_rows.append(-C_o @ Mc)
            u_rows.append(-C_o @ Mu)
            y_pos.extend(range(row, row + l))
            row += l

        if first_posterior:
            posterior()
        for j in range(1, s + 1):
            blk = slice(nS + (j - 1) * nD, nS + j * nD)
            G = A_o @ G
            G[:, blk] += B_o @ GD
            Mc = A_o @ Mc
            Mu = A_o @ Mu
            if p:
                Mu[:, (j - 1) * p:j * p] += Gamma_o
            kappa = A_o @ kappa + BcD
            if AD.shape[0]:
                Arow = np.zeros((AD.shape[0], n_g))
                Arow[:, blk] = AD
                rows_A.append(Arow)
                const_rows.append(increment.b.copy())
                c_rows.append(np.zeros((AD.shape[0], N)))
                u_rows.append(np.zeros((AD.shape[0], s * p)))
                row += AD.shape[0]
            posterior()
        self.A = np.vstack(rows_A) if rows_A else np.zeros((0, n_g))
        m = self.A.shape[0]
        nz = m - self.nS_rows
        self.b_const = np.concatenate(const_rows) if nz else np.zeros(0)
        self.b_c = np.vstack(c_rows) if nz else np.zeros((0, N))
        self.b_u = np.vstack(u_rows) if nz else np.zeros((0, s * p))
        self.y_pos = np.asarray(y_pos, dtype=np.int64) - self.nS_rows
        self.n_y = n_y
        self.G = G
        self.c_c, self.c_u, self.c_const = Mc, Mu, kappa
        self.h_D = np.tile(increment.h, s)
        self.free = np.concatenate([np.asarray(free_S, dtype=bool), np.isinf(self.h_D)])
        W = G if P is None else np.vstack([G, P @ G])
        self.n_dir = W.shape[0]
        self.P = P
        self.radius = radius
        self.lp = FixedStructureLP(self.A, hull_objectives(W), self.free, radius)

    @property
    def usable(self) -> bool:
        """Whether the fast LP path can be used for this structure."""
        return self.lp.usable

    def assemble(self, c_S, b_S, h_S, Y, U):
        """Centre, ``b`` and ``h`` of the set for data ``Y`` (``n_y x l``), ``U`` (``s x p``)."""
        u = U.reshape(-1) if self.p else np.zeros(0)
        b_tail = self.b_const + self.b_c @ c_S
        if self.p:
            b_tail = b_tail + self.b_u @ u
        b_tail[self.y_pos] += Y.reshape(-1)
        b = np.concatenate([b_S, b_tail]) if self.nS_rows else b_tail
        c = self.c_c @ c_S + self.c_const
        if self.p:
            c = c + self.c_u @ u
        h = np.concatenate([h_S, self.h_D])
        return c, b, h

    def hull(self, c, b, h, y_scale: float):
        """Certified hull bounds of ``Z`` (and of ``P Z``), or ``None`` if any LP failed.

        ``y_scale`` is the magnitude of the measurements (``b`` is ``y - C_o c_j``,
        where the two cancel; its rounding is relative to them). Returns
        ``(lo, hi)`` of length ``N`` (+ ``q`` with ``P``), rounded outward
        exactly as :meth:`ConstrainedZonotope.interval_hull` does.
        """
        bounds, ok = self.lp._minimize_all(b, h, y_scale)
        if not ok.all():
            return None
        cc = c if self.P is None else np.concatenate([c, self.P @ c])
        return hull_from_bounds(bounds, cc)

    def to_cz(self, c, b, h) -> ConstrainedZonotope:
        """The set itself (for ``keep_sets`` and the reference path)."""
        return ConstrainedZonotope._trusted(self.G, c, self.A, b, h, self.radius)
