"""The nonlinear modular observer's design by power series (modular-observer paper).

For ``x+ = f(x, w)``, ``w+ = s(w)``, ``y = h(x, w)`` (eq. (3)) the modular
observer (Section IV, eqs. (24)-(26)) is

* an identity observer for the disturbance-free part,
  ``x~+ = phi0(x~, y) = Phi0^{-1}(Phi0(f(x~, 0)) + B0 (y - h(x~, 0)))`` (eq. (32)),
  with ``Phi0`` solving the LFE (31) ``Phi0(f(x, 0)) = A0 Phi0(x) + B0 h(x, 0)``;
* a corrector ``x^ = Xi(x~, w^)`` solving the FE (28)
  ``Xi(phi0(x~, h(Xi(x~, w^), w^)), s(w^)) = f(Xi(x~, w^), w^)``;
* a disturbance observer ``w^+ = phi_w(x~, w^, y)``, the solution of the algebraic
  equation (36) ``Psi(phi0(x~, y), phi_w) = Psi(phi0(x~, y^), s(w^)) + Bw (y - y^)``
  with ``y^ = h(Xi(x~, w^), w^)`` and ``Psi`` solving the LFE (35)
  ``Psi(phi0(x~, h(Xi, w^)), s(w^)) = Aw Psi(x~, w^) + Bw h(Xi(x~, w^), w^)``.

In the coordinates ``z0 = Phi0(x~)``, ``zw = Psi(x~, w^)`` the observer is
linear, ``z0+ = A0 z0 + B0 y``, ``zw+ = Aw zw + Bw y`` (eqs. (30), (34)), with the
eigenvalues of ``A0`` and ``Aw``.

:func:`design_modular` solves (31), (28) and (35) by the power-series method of
Section VII around the equilibrium ``(0, 0)``: each degree ``d`` of each
unknown solves a Sylvester equation (for (28): ``Xi_d o L - K_x Xi_d = r_d``,
``L`` the linear part of ``(phi0(x~, h(Xi, w^)), s(w^))``, ``K_x = F - K_y H``
the linear part of ``phi0`` in ``x~``; its linear part ``[I, W]`` solves
``K_x W - W S = K_y Q - P``, the nonlinear counterpart of Sec. VIII's eq. (48)).
The simultaneous design (22)-(23) is :func:`design_simultaneous`; Proposition 7
relates the two and is checked by :meth:`ModularDesign.proposition7_residuals`.
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_sylvester

from .._validation import as_matrix
from ..exceptions import DesignError, DesignWarning, DimensionError, InvalidValueError
from ..tolerances import (
    ILL_CONDITIONED_RTOL,
    NEAR_RESONANCE_RTOL,
    NEWTON_RTOL,
    RESIDUAL_GROWTH_FACTOR,
    RESONANCE_RTOL,
)
from ._linalg import rank_decision
from .existence import ExistenceReport
from .observability import observability
from .powerseries import LFESolution, Monomials, invert, min_divisor, solve_lfe, taylor

__all__ = ["DesignDiagnostics", "ModularDesign", "design_modular", "design_simultaneous",
           "newton", "nonlinear_modular_conditions", "radius_estimate"]

#: Iteration cap of Newton's method on the implicit maps (eqs. (32), (36)).
NEWTON_MAXITER = 50


def _as_square(name: str, A: ArrayLike, n: int) -> NDArray[np.float64]:
    a = np.asarray(A, dtype=float)
    if a.ndim == 0:
        a = a.reshape(1, 1)
    if a.ndim == 1:  # eigenvalues: a diagonal matrix
        a = np.diag(a)
    return as_matrix(name, a, rows=n, cols=n)


def _as_gain(name: str, B: ArrayLike | None, r: int, p: int) -> NDArray[np.float64]:
    if B is None:
        return np.ones((r, p))
    b = np.asarray(B, dtype=float)
    if b.ndim < 2:
        b = b.reshape(r, p)
    return as_matrix(name, b, rows=r, cols=p)


def newton(fun: Any, jac: Any, u0: NDArray[np.float64], target: NDArray[np.float64]
           ) -> tuple[NDArray[np.float64], bool]:
    """Solve ``fun(u) = target`` by Newton's method from ``u0``.

    Returns the last iterate and whether the step fell below
    :data:`NEWTON_RTOL` (relative) within :data:`NEWTON_MAXITER` iterations with a
    finite, nonsingular Jacobian.
    """
    u = np.array(u0, dtype=float)
    for _ in range(NEWTON_MAXITER):
        r = fun(u) - target
        try:
            du = np.linalg.solve(jac(u), r)
        except np.linalg.LinAlgError:
            return u, False
        if not np.all(np.isfinite(du)):
            return u, False
        u = u - du
        if np.abs(du).max() <= NEWTON_RTOL * max(1.0, float(np.abs(u).max())):
            return u, True
    return u, False


class _Poly:
    """A polynomial map (coefficients over a basis) with its Jacobian, for evaluation."""

    def __init__(self, C: NDArray[np.float64], basis: Monomials) -> None:
        self.C = np.asarray(C, dtype=float)
        self.basis = basis
        self.D = np.stack([basis.derivative(self.C, j) for j in range(basis.n_vars)])

    def __call__(self, v: ArrayLike) -> NDArray[np.float64]:
        return self.C @ self.basis.monomials(v)

    def jacobian(self, v: ArrayLike) -> NDArray[np.float64]:
        return (self.D @ self.basis.monomials(v)).T  # (r, n_vars)


@dataclass(frozen=True)
class DesignDiagnostics:
    """Diagnostics of a modular design (:meth:`ModularDesign.diagnostics`).

    Attributes
    ----------
    orders : tuple of int
        The truncation orders checked (1 to the design's).
    residuals : dict
        ``"31"``, ``"28"``, ``"35"``: the largest residual at the points, per order.
    min_divisor : float
        The smallest divisor of the non-resonance condition (assumption 2).
    radius : dict
        Root-test radius estimates of ``Phi0``, ``Xi`` and ``Psi``.
    growing : tuple of str
        The equations whose residual at the full order exceeds
        :data:`~setobs.tolerances.RESIDUAL_GROWTH_FACTOR` times its smallest.
    points : ndarray, shape (N, n + q)
        Where the residuals were evaluated.
    """

    orders: tuple[int, ...]
    residuals: dict[str, tuple[float, ...]]
    min_divisor: float
    radius: dict[str, float]
    growing: tuple[str, ...]
    points: NDArray[np.float64]

    def to_markdown(self) -> str:
        """The residuals by order as a Markdown table, then the divisor and radii."""
        lines = ["| order | (31) | (28) | (35) |", "|---|---|---|---|"]
        for i, k in enumerate(self.orders):
            lines.append(f"| {k} | " + " | ".join(f"{self.residuals[e][i]:.2e}"
                                                 for e in ("31", "28", "35")) + " |")
        lines.append("")
        lines.append(f"smallest divisor {self.min_divisor:.3g}; radius estimates "
                     + ", ".join(f"{k} {v:.3g}" for k, v in self.radius.items())
                     + ("; growing with the order: " + ", ".join(self.growing)
                        if self.growing else ""))
        return "\n".join(lines)


@dataclass
class ModularDesign:
    """The power-series design of the nonlinear modular observer (:func:`design_modular`).

    Attributes
    ----------
    system : NonlinearSystem
    order : int
        Truncation degree of every series.
    A0, B0, Aw, Bw : ndarray
        The assigned linear dynamics ``z0+ = A0 z0 + B0 y``, ``zw+ = Aw zw + Bw y``.
    Phi0 : LFESolution
        Solution of the LFE (31) over the states' basis.
    Phi0_inverse : ndarray
        Coefficients of ``Phi0^{-1}`` (the states' basis).
    phi0 : ndarray
        Coefficients of ``phi0(x, y)`` (eq. (32)) over the basis of ``(x, y)``.
    Xi : ndarray
        Coefficients of the corrector ``Xi(x~, w^)`` (FE (28)) over the basis of
        ``(x, w)``.
    Psi : LFESolution
        Solution of the LFE (35) over the basis of ``(x, w)``.
    report : ExistenceReport
        The solvability conditions (:func:`nonlinear_modular_conditions` at these
        eigenvalues).
    """

    system: Any
    order: int
    A0: NDArray[np.float64]
    B0: NDArray[np.float64]
    Aw: NDArray[np.float64]
    Bw: NDArray[np.float64]
    Phi0: LFESolution
    Phi0_inverse: NDArray[np.float64]
    phi0: NDArray[np.float64]
    Xi: NDArray[np.float64]
    Psi: LFESolution
    report: ExistenceReport
    _cache: dict = field(default_factory=dict, repr=False)

    # series bases ---------------------------------------------------------------------
    @property
    def basis_x(self) -> Monomials:
        """Basis of the states ``x``."""
        return self.Phi0.basis

    @property
    def basis_v(self) -> Monomials:
        """Basis of ``(x, w)``."""
        return self.Psi.basis

    def _p(self, name: str) -> _Poly:
        p = self._cache.get(name)
        if p is None:
            C, basis = {"Phi0": (self.Phi0.C, self.basis_x), "Xi": (self.Xi, self.basis_v),
                        "Psi": (self.Psi.C, self.basis_v)}[name]
            p = self._cache[name] = _Poly(C, basis)
        return p

    def __getstate__(self) -> dict[str, Any]:
        state = self.__dict__.copy()
        state["_cache"] = {}
        return state

    # the maps at points ----------------------------------------------------------------
    def Phi0_at(self, x: ArrayLike) -> NDArray[np.float64]:
        """``Phi0(x)`` (the truncated series)."""
        return self._p("Phi0")(x)

    def Xi_at(self, x: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        """The corrector ``Xi(x~, w^)`` (the truncated series)."""
        return self._p("Xi")(np.concatenate([np.ravel(x), np.ravel(w)]))

    def Psi_at(self, x: ArrayLike, w: ArrayLike) -> NDArray[np.float64]:
        """``Psi(x~, w^)`` (the truncated series)."""
        return self._p("Psi")(np.concatenate([np.ravel(x), np.ravel(w)]))

    def Phi0_solve(self, z: ArrayLike, guess: ArrayLike) -> tuple[NDArray[np.float64], bool]:
        """``x`` with ``Phi0(x) = z`` by Newton from ``guess``; and whether it converged."""
        p = self._p("Phi0")
        return newton(p, p.jacobian, np.asarray(guess, float), np.asarray(z, float))

    def phi0_at(self, x: ArrayLike, y: ArrayLike, guess: ArrayLike | None = None
                ) -> tuple[NDArray[np.float64], bool]:
        """Eq. (32): ``Phi0^{-1}(Phi0(f(x, 0)) + B0 (y - h(x, 0)))``, by Newton.

        The observer property (27), ``phi0(x, h(x, 0)) = f(x, 0)``, holds exactly
        for the truncated ``Phi0`` too.
        """
        sys = self.system
        x = np.asarray(x, float)
        w0 = np.zeros(sys.q)
        fx = sys.f_num(x, w0)
        z = self.Phi0_at(fx) + self.B0 @ (np.asarray(y, float) - sys.h_num(x, w0))
        return self.Phi0_solve(z, fx if guess is None else guess)

    def Psi_solve_w(self, x: ArrayLike, z: ArrayLike, guess: ArrayLike
                    ) -> tuple[NDArray[np.float64], bool]:
        """``w`` with ``Psi(x, w) = z`` by Newton from ``guess`` (eq. (36)'s unknown)."""
        p = self._p("Psi")
        x = np.ravel(np.asarray(x, float))
        m = x.size

        def fun(w):
            return p(np.concatenate([x, w]))

        def jac(w):
            return p.jacobian(np.concatenate([x, w]))[:, m:]

        return newton(fun, jac, np.asarray(guess, float), np.asarray(z, float))

    def _observer_map(self, x: NDArray[np.float64], w: NDArray[np.float64]
                      ) -> tuple[NDArray[np.float64], ...]:
        """The map of (28) and (35) at ``(x~, w^)``: ``Xi``, ``y = h(Xi, w^)``,
        ``phi0(x~, y)`` (eq. (32)) and ``s(w^)``."""
        xi = self.Xi_at(x, w)
        y = self.system.h_num(xi, w)
        return xi, y, self.phi0_at(x, y)[0], self.system.s_num(w)

    # the linearizing coordinates z = (Phi0(x~), Psi(x~, w^)) (eqs. (30), (34)) ----------
    def readout(self) -> NDArray[np.float64]:
        """Coefficients, over the basis of ``z = (z0, zw)``, of ``(x~, w^, x^)`` as
        functions of ``z``: the series inverse of ``(x~, w^) -> (Phi0(x~), Psi(x~, w^))``
        and the corrector ``x^ = Xi(x~, w^)`` composed with it.

        Returns
        -------
        ndarray, shape (2 n + q, len(basis_v))
            Rows: ``x~`` (n), ``w^`` (q), ``x^`` (n).
        """
        R = self._cache.get("readout_C")
        if R is None:
            bv, m = self.basis_v, self.system.n
            Z = np.zeros((m + self.system.q, len(bv)))
            Z[:m, self.basis_x.embed(bv, range(m))] = self.Phi0.C
            Z[m:] = self.Psi.C
            Lam = invert(Z, bv)
            R = self._cache["readout_C"] = np.vstack([Lam, self.Xi @ bv.substitution(Lam)])
        return R

    def extend_to_z(self, x: ArrayLike, w: ArrayLike, *, radius: float | None = None,
                    max_steps: int = 30) -> NDArray[np.float64]:
        """``z = (Phi0(x~), Psi(x~, w^))`` at a point possibly outside the series' radius.

        The functional equations carry the series outward along the observer's own
        map: (31) gives ``Phi0(x) = A0^{-1}(Phi0(f(x, 0)) - B0 h(x, 0))`` and (35)
        gives ``Psi(v) = Aw^{-1}(Psi(G(v)) - Bw h(Xi(v), w))`` with
        ``G(v) = (phi0(x, h(Xi(v), w)), s(w))``; they are applied while the point
        is outside ``radius`` (default: half :meth:`radius_estimate` of each
        series) and its size still decreases, at most ``max_steps`` times.

        Parameters
        ----------
        x, w : array_like
            The point ``(x~, w^)``.
        radius : float, optional
        max_steps : int

        Returns
        -------
        ndarray, shape (n + q,)
        """
        sys = self.system
        x, w = np.ravel(np.asarray(x, float)), np.ravel(np.asarray(w, float))
        m, w0 = sys.n, np.zeros(sys.q)
        r0 = 0.5 * radius_estimate(self.Phi0.C, self.basis_x) if radius is None else radius
        rw = 0.5 * radius_estimate(self.Psi.C, self.basis_v) if radius is None else radius

        def step0(u):  # (31) along x -> f(x, 0)
            return sys.f_num(u, w0), self.B0 @ sys.h_num(u, w0)

        def step_w(v):  # (35) along v -> G(v)
            _, yv, nx, sw = self._observer_map(v[:m], v[m:])
            return np.concatenate([nx, sw]), self.Bw @ yv

        z0 = _carry_out(x, r0, max_steps, step0, self.Phi0_at, self.A0)
        zw = _carry_out(np.concatenate([x, w]), rw, max_steps, step_w,
                        lambda v: self.Psi_at(v[:m], v[m:]), self.Aw)
        return np.concatenate([z0, zw])

    # checks ------------------------------------------------------------------------------
    def residuals(self, points: ArrayLike) -> dict[str, float]:
        """Largest residuals of the LFE (31), the FE (28) and the LFE (35) at ``points``
        (rows ``(x, w)``), with the model's exact ``f``, ``h``, ``s`` and ``phi0`` by (32).

        Parameters
        ----------
        points : array_like, shape (N, n + q)

        Returns
        -------
        dict
            ``"31"``, ``"28"``, ``"35"``: the largest absolute residual.
        """
        sys = self.system
        m = sys.n
        out = {"31": 0.0, "28": 0.0, "35": 0.0}
        w0 = np.zeros(sys.q)
        for v in np.atleast_2d(np.asarray(points, float)):
            x, w = v[:m], v[m:]
            r31 = (self.Phi0_at(sys.f_num(x, w0)) - self.A0 @ self.Phi0_at(x)
                   - self.B0 @ sys.h_num(x, w0))
            xi, yv, x_next, sw = self._observer_map(x, w)
            r28 = self.Xi_at(x_next, sw) - sys.f_num(xi, w)
            r35 = self.Psi_at(x_next, sw) - self.Aw @ self.Psi_at(x, w) - self.Bw @ yv
            for key, r in (("31", r31), ("28", r28), ("35", r35)):
                out[key] = max(out[key], float(np.abs(r).max()))
        return out

    def truncated(self, order: int) -> ModularDesign:
        """The same design truncated at a lower ``order``: the series are solved degree by
        degree, so their terms up to ``order`` are those of a design at that order.

        Parameters
        ----------
        order : int
            The degree kept (``1 <= order <= self.order``).
        """
        if not 1 <= order <= self.order:
            raise InvalidValueError(f"order must be in [1, {self.order}], got {order}")

        def cut(C: NDArray[np.float64], basis: Monomials) -> NDArray[np.float64]:
            out = np.array(C, dtype=float)
            if order < basis.order:
                out[:, basis.block[order + 1].start:] = 0.0
            return out

        bx, bv = self.basis_x, self.basis_v
        bxy = Monomials(self.system.n + self.system.l, self.order)
        return dataclasses.replace(
            self, order=order,
            Phi0=LFESolution(bx, cut(self.Phi0.C, bx), self.Phi0.conditions),
            Phi0_inverse=cut(self.Phi0_inverse, bx), phi0=cut(self.phi0, bxy),
            Xi=cut(self.Xi, bv), Psi=LFESolution(bv, cut(self.Psi.C, bv), self.Psi.conditions),
            _cache={})

    def diagnostics(self, points: ArrayLike | None = None) -> DesignDiagnostics:
        """Residuals of (31), (28) and (35) by truncation order, the smallest divisor and
        the series' radius estimates; a :class:`~setobs.exceptions.DesignWarning` when a
        residual grows with the order (the series diverge at those points: do not run
        the observer there, or lower the order).

        Parameters
        ----------
        points : array_like, shape (N, n + q), optional
            Where to check, rows ``(x, w)``, e.g. the states and disturbances the
            observer will meet. Default: 20 points (fixed seed) uniform in the box of
            half-width half the smallest radius estimate of ``Phi0``, ``Xi``, ``Psi``.

        Returns
        -------
        DesignDiagnostics
        """
        radii = {"Phi0": radius_estimate(self.Phi0.C, self.basis_x),
                 "Xi": radius_estimate(self.Xi, self.basis_v),
                 "Psi": radius_estimate(self.Psi.C, self.basis_v)}
        if points is None:
            rho = min(radii.values())
            half = 0.5 * (rho if np.isfinite(rho) else 1.0)
            points = np.random.default_rng(0).uniform(
                -half, half, size=(20, self.system.n + self.system.q))
        pts = np.atleast_2d(np.asarray(points, dtype=float))
        if pts.shape[1] != self.system.n + self.system.q:
            raise DimensionError(f"points must have n + q = {self.system.n + self.system.q} "
                                 f"columns, got {pts.shape[1]}")
        orders = tuple(range(1, self.order + 1))
        res: dict[str, list[float]] = {"31": [], "28": [], "35": []}
        for k in orders:
            r = self.truncated(k).residuals(pts)
            for key in res:
                res[key].append(r[key])
        growing = tuple(key for key, seq in res.items()
                        if seq[-1] > RESIDUAL_GROWTH_FACTOR * min(seq) and seq[-1] > 0.0)
        out = DesignDiagnostics(orders, {k: tuple(v) for k, v in res.items()},
                                float(self.report.numbers.get("min divisor", np.nan)),
                                radii, growing, pts)
        if growing:
            warnings.warn(
                "modular design: the residuals of eq. " + ", ".join(f"({k})" for k in growing)
                + f" grow with the order at the points checked (at order {self.order}: "
                + ", ".join(f"{res[k][-1]:.2e}" for k in growing) + ", smallest "
                + ", ".join(f"{min(res[k]):.2e}" for k in growing)
                + "): the series diverge there", DesignWarning, stacklevel=2)
        return out

    def proposition7_residuals(self, simultaneous: tuple[LFESolution, LFESolution],
                               points: ArrayLike) -> dict[str, float]:
        """Proposition 7 at ``points`` (rows ``(x, w)``), against the simultaneous design
        ``(Phi_0, Phi_w)`` of (22)-(23) (:func:`design_simultaneous` with the same
        ``A0, B0, Aw, Bw``):

        * ``"i"``: ``Phi0(x) - Phi_0(x, 0)``;
        * ``"ii"``: ``Phi_0(Xi(x, w), w) - Phi0(x)`` (eq. (38));
        * ``"iii"``: ``Psi(x, w) - Phi_w(Xi(x, w), w)``.

        Returns
        -------
        dict
            The largest absolute value of each.
        """
        P0, Pw = simultaneous
        m = self.system.n
        out = {"i": 0.0, "ii": 0.0, "iii": 0.0}
        for v in np.atleast_2d(np.asarray(points, float)):
            x, w = v[:m], v[m:]
            xi = self.Xi_at(x, w)
            ri = self.Phi0_at(x) - P0(np.concatenate([x, np.zeros_like(w)]))[0]
            rii = P0(np.concatenate([xi, w]))[0] - self.Phi0_at(x)
            riii = self.Psi_at(x, w) - Pw(np.concatenate([xi, w]))[0]
            for key, r in (("i", ri), ("ii", rii), ("iii", riii)):
                out[key] = max(out[key], float(np.abs(r).max()))
        return out


def _carry_out(v: NDArray[np.float64], radius: float, max_steps: int, step: Any,
               series: Any, A: NDArray[np.float64]) -> NDArray[np.float64]:
    """``Phi(v)`` for an LFE ``Phi(F(v)) = A Phi(v) + off(v)``: step ``v -> F(v)`` while
    ``v`` is outside ``radius`` and shrinks (at most ``max_steps``), evaluate the series
    there and undo the steps, ``Phi(v) = A^{-1}(Phi(F(v)) - off(v))``."""
    offs = []
    while np.abs(v).max() > radius and len(offs) < max_steps:
        nxt, off = step(v)
        if np.abs(nxt).max() >= np.abs(v).max():
            break
        offs.append(off)
        v = nxt
    z = series(v)
    for off in reversed(offs):
        z = np.linalg.solve(A, z - off)
    return z


def radius_estimate(C: NDArray[np.float64], basis: Monomials) -> float:
    """Root-test estimate of a series' radius of convergence (in the max norm).

    ``min over the upper half of the degrees d of (|C_d| / |C_1|)^(-1/(d-1))``,
    ``|.|`` the largest absolute coefficient; ``inf`` for a linear map.
    """
    c1 = float(np.abs(C[:, basis.block[1]]).max())
    out = np.inf
    for d in range(max(2, (basis.order + 1) // 2), basis.order + 1):
        cd = float(np.abs(C[:, basis.block[d]]).max())
        if cd > 1e-14 * max(c1, 1e-300):
            out = min(out, (cd / c1) ** (-1.0 / (d - 1)))
    return out


def _model_series(system: Any, basis_v: Monomials) -> tuple[NDArray[np.float64], ...]:
    v = list(system.x) + list(system.w)
    return (taylor(system.f, v, basis_v), taylor(system.s, v, basis_v),
            taylor(system.h, v, basis_v))


def nonlinear_modular_conditions(system: Any, A0: ArrayLike | None = None,
                                 Aw: ArrayLike | None = None, *, order: int = 7
                                 ) -> ExistenceReport:
    """Proposition 3's local solvability conditions for the modular design.

    Decides on the linearization ``F, P, S, H, Q`` at the origin: (i) ``(H, F)``
    observable (the LFE (31) then has an invertible solution for suitable
    ``A0, B0``, Proposition 2); (ii) the extended pair
    ``([H, Q], [[F, P], [0, S]])`` observable (Proposition 3, assumption 1, and
    with it the invertibility of ``Psi`` in ``w``, Proposition 7 iii); (iii) the
    eigenvalues of ``F`` and ``S`` together in the Poincaré domain (all inside
    or all outside the unit disc, assumption 3). With ``A0``, ``Aw`` given, it
    also reports non-resonance (assumption 2) up to ``order`` and the smallest
    divisor.

    Assumption 3 fails for every constant disturbance (``S = I``), the paper's
    own example included; the series may still converge (a Siegel-type
    situation: the divisors stay away from zero), so this is reported as a note
    in ``reason`` and not as a verdict: the verdict follows (i), (ii) and
    non-resonance.

    Parameters
    ----------
    system : NonlinearSystem
    A0, Aw : array_like, optional
        Observer matrices (or their eigenvalues) for the non-resonance check.
    order : int
        Degree up to which non-resonance is checked.

    Returns
    -------
    ExistenceReport
        ``design="nonlinear modular observer"``.
    """
    lin = system.linearization()
    F, P, S, H, Q = (lin[k] for k in "FPSHQ")
    m, mu = F.shape[0], S.shape[0]
    Fe = np.block([[F, P], [np.zeros((mu, m)), S]])
    He = np.hstack([H, Q])
    obs0 = observability(F, H).n_observable == m
    obs_e = observability(Fe, He).n_observable == m + mu
    lam = np.concatenate([np.linalg.eigvals(F), np.linalg.eigvals(S)])
    poincare = bool(np.all(np.abs(lam) < 1.0) or np.all(np.abs(lam) > 1.0))
    nums: dict[str, Any] = {"eig F": np.linalg.eigvals(F), "eig S": np.linalg.eigvals(S),
                            "(H, F) observable": obs0, "extended pair observable": obs_e,
                            "Poincare domain": poincare}
    why = []
    if not obs0:
        why.append("(H, F) is not observable: the LFE (31) has no invertible solution")
    if not obs_e:
        why.append("the extended linearization ([H, Q], [[F, P], [0, S]]) is not observable")
    resonant = False
    if A0 is not None and Aw is not None:
        a0 = np.linalg.eigvals(_as_square("A0", A0, m))
        aw = np.linalg.eigvals(_as_square("Aw", Aw, mu))
        lamF = np.linalg.eigvals(F)
        d31 = min_divisor(a0, lamF, 1, order)
        d28 = min(min_divisor(a0, lam, 2, order), min_divisor(a0, np.linalg.eigvals(S), 1, 1))
        d35 = min_divisor(aw, lam, 1, order)
        md = min(d31, d28, d35)
        nums["min divisor"] = md
        scale = max(1.0, float(np.abs(np.concatenate([a0, aw])).max()))
        resonant = md <= RESONANCE_RTOL * scale
        if resonant:
            why.append(f"resonance: an eigenvalue of A0 or Aw equals a product of eigenvalues "
                       f"of F and S up to degree {order} (smallest divisor {md:.2e})")
    exists = obs0 and obs_e and not resonant
    if not poincare:
        why.append("note: eigenvalues of F and S on the unit circle or on both sides of it "
                   "(Proposition 3, assumption 3 fails; the series may still converge)")
    return ExistenceReport(exists, "linearization observable (Prop. 2-3), non-resonant", nums,
                           "; ".join(why), design="nonlinear modular observer",
                           source="modular observer Prop. 3-7, Sec. VII")


def design_simultaneous(system: Any, A0: ArrayLike, B0: ArrayLike | None, Aw: ArrayLike,
                        Bw: ArrayLike | None, *, order: int = 7
                        ) -> tuple[LFESolution, LFESolution]:
    """The simultaneous design: the LFEs (22) and (23) for ``(Phi_0, Phi_w)`` on the
    extended system ``(x, w)+ = (f(x, w), s(w))`` (Section III), by power series.

    Parameters
    ----------
    system : NonlinearSystem
    A0, B0, Aw, Bw : array_like
        As in :func:`design_modular`.
    order : int
        Truncation degree.

    Returns
    -------
    (LFESolution, LFESolution)
        ``Phi_0`` and ``Phi_w`` over the basis of ``(x, w)``.
    """
    m, mu, p = system.n, system.q, system.l
    A0a, Awa = _as_square("A0", A0, m), _as_square("Aw", Aw, mu)
    B0a, Bwa = _as_gain("B0", B0, m, p), _as_gain("Bw", Bw, mu, p)
    basis_v = Monomials(m + mu, order)
    f_v, s_v, h_v = _model_series(system, basis_v)
    Fe = np.vstack([f_v, s_v])
    return (solve_lfe(Fe, h_v, A0a, B0a, basis_v), solve_lfe(Fe, h_v, Awa, Bwa, basis_v))


#: Largest number of monomials in ``(x, w)`` up to the order that :func:`design_modular`
#: accepts by default. The design's time grows about with its cube: on the paper's
#: example (two variables) 210 terms (order 19) took 6 s and 351 (order 25) 51 s; three
#: variables, 220 terms (order 9), 2.5 s.
MAX_SERIES_TERMS: int = 250


def design_modular(system: Any, A0: ArrayLike, B0: ArrayLike | None, Aw: ArrayLike,
                   Bw: ArrayLike | None, *, order: int = 7,
                   max_terms: int = MAX_SERIES_TERMS) -> ModularDesign:
    """Solve the modular design's equations (31), (28), (35) by power series (Section VII).

    Parameters
    ----------
    system : NonlinearSystem
        ``x+ = f(x, w)``, ``w+ = s(w)``, ``y = h(x, w)`` with an equilibrium at 0.
    A0 : array_like, shape (n, n), or its n eigenvalues
        Dynamics of the disturbance-free observer in its linearizing coordinates.
    B0 : array_like, shape (n, l), optional
        Default: ones.
    Aw : array_like, shape (q, q), or its q eigenvalues
        Dynamics of the disturbance observer in its linearizing coordinates.
    Bw : array_like, shape (q, l), optional
        Default: ones.
    order : int
        Truncation degree of the series (at least 1).
    max_terms : int
        Largest number of monomials in ``(x, w)`` up to ``order`` (default
        :data:`MAX_SERIES_TERMS`); a larger design is refused with its size, so that
        a high order does not silently take minutes.

    Returns
    -------
    ModularDesign

    Raises
    ------
    DesignError
        When a condition fails: ``A0`` or ``Aw`` not Schur stable (the observer's
        errors in the linearizing coordinates evolve with them, so they would grow),
        resonance at some degree, ``Phi0``'s linear part singular ((H, F)
        unobservable or (A0, B0) badly chosen), or ``Psi`` not invertible in ``w``.
    DimensionError
        For ``order < 1`` or a series larger than ``max_terms``.

    Examples
    --------
    The paper's example with ``lambda_0 = 0.4``, ``lambda_w = 0.6`` (Section VI):

    >>> from setobs.examples import modular_example
    >>> d = design_modular(modular_example(), 0.4, 1.0, 0.6, 1.0, order=6)
    >>> round(float(d.Phi0.C[0, 1]), 9)   # Phi0 = 20 x/(1 + x): slope 20
    20.0
    """
    m, mu, p = system.n, system.q, system.l
    A0a, Awa = _as_square("A0", A0, m), _as_square("Aw", Aw, mu)
    B0a, Bwa = _as_gain("B0", B0, m, p), _as_gain("Bw", Bw, mu, p)
    if isinstance(order, bool) or not isinstance(order, int | np.integer) or order < 1:
        raise InvalidValueError(f"order (the degree of the power series) must be an integer >= 1, "
                             f"got {order!r}")
    n_terms = math.comb(m + mu + order, order)
    if n_terms > max_terms:
        raise InvalidValueError(
            f"order {order} needs {n_terms} monomials in the {m + mu} variables (x, w), more "
            f"than max_terms = {max_terms}; the design's time grows about with the cube of "
            f"that (351 terms took 51 s on a two-variable plant): lower the order or raise "
            f"max_terms")
    eigs = {"A0": np.linalg.eigvals(A0a), "Aw": np.linalg.eigvals(Awa)}
    for name, ev in eigs.items():
        rho = float(np.abs(ev).max(initial=0.0))
        if not rho < 1.0:
            raise DesignError(
                f"modular design: {name} has spectral radius {rho:.4g} >= 1; the observer's "
                f"errors in the linearizing coordinates evolve with it and would not decay "
                f"(choose its eigenvalues inside the unit circle)", f"{name} Schur stable")
    report = nonlinear_modular_conditions(system, A0a, Awa, order=order)
    basis_x = Monomials(m, order)
    basis_v = Monomials(m + mu, order)
    basis_xy = Monomials(m + p, order)
    blk = basis_v.block
    f_v, s_v, h_v = _model_series(system, basis_v)
    x_in_v = basis_x.embed(basis_v, range(m))
    # (31): Phi0(f(x, 0)) = A0 Phi0(x) + B0 h(x, 0) over the states' basis
    Phi0 = solve_lfe(f_v[:, x_in_v], h_v[:, x_in_v], A0a, B0a, basis_x)
    if not Phi0.conditions.T_invertible:
        raise DesignError("modular design: Phi0's linear part T0 (T0 F - A0 T0 = B0 H) is "
                          "singular: " + (Phi0.conditions.reason() or "choose (A0, B0) "
                                          "controllable"), "invertible Phi0")
    Ginv = invert(Phi0.C, basis_x)
    # (32) as a series in (x, y): Phi0^{-1}(A0 Phi0(x) + B0 y), equal to
    # Phi0^{-1}(Phi0(f(x, 0)) + B0 (y - h(x, 0))) up to the order since (31) holds there
    inner = np.zeros((m, len(basis_xy)))
    inner[:, basis_x.embed(basis_xy, range(m))] = A0a @ Phi0.C
    inner[:, basis_xy.block[1].start + m:basis_xy.block[1].stop] = B0a
    phi0 = Ginv @ basis_x.substitution(inner, basis_xy)
    Kx = phi0[:, basis_xy.block[1]][:, :m]
    Ky = phi0[:, basis_xy.block[1]][:, m:]
    F, P = f_v[:, blk[1]][:, :m], f_v[:, blk[1]][:, m:]
    H, Q = h_v[:, blk[1]][:, :m], h_v[:, blk[1]][:, m:]
    S = s_v[:, blk[1]][:, m:]
    # identity rows for x and w as series over (x, w)
    ident = np.zeros((m + mu, len(basis_v)))
    ident[:, blk[1]] = np.eye(m + mu)

    def maps(Xi: NDArray[np.float64]) -> tuple[NDArray[np.float64], ...]:
        """(h(Xi, w), G = (phi0(x, h(Xi, w)), s(w)), f(Xi, w)) as series over (x, w)."""
        M1 = basis_v.substitution(np.vstack([Xi, ident[m:]]))
        hX = h_v @ M1
        G = np.vstack([phi0 @ basis_xy.substitution(np.vstack([ident[:m], hX]), basis_v), s_v])
        return hX, G, f_v @ M1

    # (28), degree 1: Xi_1 = [I, W] with Kx W - W S = Ky Q - P
    W = solve_sylvester(Kx, -S, Ky @ Q - P)
    Xi = np.zeros((m, len(basis_v)))
    Xi[:, blk[1]] = np.hstack([np.eye(m), W])
    Kop = F - Ky @ H  # = Kx: what Xi_d's own degree-d terms contribute besides Xi_d o L
    for d in range(2, order + 1):
        _, G, fX = maps(Xi)
        MG = basis_v.substitution(G)
        r = (Xi @ MG - fX)[:, blk[d]]
        Xi[:, blk[d]] = solve_sylvester(-Kop, MG[blk[d], blk[d]], -r)
    hX, G, _ = maps(Xi)
    # (35): Psi(G) = Aw Psi + Bw h(Xi, w)
    Psi = solve_lfe(G, hX, Awa, Bwa, basis_v)
    Psi_w = Psi.C[:, blk[1]][:, m:]
    if rank_decision(Psi_w).rank < mu:
        raise DesignError("modular design: d Psi/d w is singular at 0, the algebraic equation "
                          "(36) has no unique solution (choose (Aw, Bw) differently)",
                          "invertible Psi")
    _warn_conditioning(report, Phi0.T, Psi_w, np.concatenate(list(eigs.values())))
    return ModularDesign(system, int(order), A0a, B0a, Awa, Bwa, Phi0, Ginv, phi0, Xi, Psi,
                         report)


def _warn_conditioning(report: ExistenceReport, T0: NDArray[np.float64],
                       Psi_w: NDArray[np.float64], eigs: NDArray[np.complex128]) -> None:
    """:class:`DesignWarning` for a design that is made but fragile: a smallest divisor
    near resonance (the coefficients grow like its inverse) or a nearly singular linear
    part of ``Phi0`` or ``Psi`` (the inverse maps amplify by the inverse ratio)."""
    md = float(report.numbers.get("min divisor", np.inf))
    scale = max(1.0, float(np.abs(eigs).max(initial=0.0)))
    if md <= NEAR_RESONANCE_RTOL * scale:
        warnings.warn(f"modular design: smallest divisor {md:.2e}, near resonance (below "
                      f"{NEAR_RESONANCE_RTOL:g}): the series' coefficients grow like its "
                      "inverse; move the eigenvalues of A0 or Aw away from the products of "
                      "the linearization's eigenvalues", DesignWarning, stacklevel=3)
    for name, M in (("Phi0's linear part T0", T0), ("d Psi / d w", Psi_w)):
        sv = np.linalg.svd(M, compute_uv=False)
        if sv.size and sv.min() <= ILL_CONDITIONED_RTOL * sv.max():
            warnings.warn(f"modular design: {name} is nearly singular (singular values "
                          f"{sv.min():.2e} to {sv.max():.2e}): its inverse amplifies errors by "
                          f"{sv.max() / max(sv.min(), 1e-300):.1e}", DesignWarning,
                          stacklevel=3)
