"""Truncated multivariate power series and the observer-linearization equation.

The nonlinear modular observer (modular-observer paper, Sections III-VII) is
designed by solving *linear functional equations* (LFEs) of the form

.. math::  \\Phi(F(v)) = A\\,\\Phi(v) + B\\,h(v),

eq. (17) for one system, eq. (31) for the disturbance-free part
``F = f(x, 0)``, eqs. (22)-(23) for the extended system ``F = (f(x, w), s(w))``,
by the power-series method of Section VII: with ``F(0) = 0`` and ``h(0) = 0``
the linear part ``T`` of ``Phi`` solves the Sylvester equation
``T F_1 - A T = B H_1`` (assumption 1 of Proposition 2), and each homogeneous
part ``Phi_d`` of degree ``d >= 2`` solves

.. math::  \\Phi_d \\circ F_1 - A\\,\\Phi_d = B\\,h_d - [\\Phi_{<d} \\circ F]_d,

a Sylvester equation on the coefficients of degree ``d`` that is uniquely
solvable exactly when no eigenvalue of ``A`` equals a product
``prod lambda_i^m_i`` (``sum m_i = d``) of eigenvalues of ``F_1``
(non-resonance, assumption 2 of Proposition 2).

A polynomial map is a coefficient matrix over the monomials of the variables
up to the truncation degree, ordered by degree (:class:`Monomials`);
compositions are truncated at that degree. Taylor coefficients of sympy
expressions (or of Python callables that accept sympy symbols) come from
:func:`taylor`.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import solve_sylvester

from .._lazy import optional_import
from ..exceptions import DesignError, InvalidValueError
from ..tolerances import RESONANCE_RTOL
from ._linalg import rank_decision
from .observability import observability

__all__ = ["LFEConditions", "LFESolution", "Monomials", "invert", "lfe_conditions", "min_divisor",
           "series_tail", "solve_lfe", "taylor"]


class Monomials:
    """The monomials of ``n_vars`` variables up to degree ``order``, by degree.

    Index 0 is the constant; then degree 1 (the variables in order), degree
    2, ... Within a degree, exponents in reverse lexicographic order (the
    first variable's highest power first).

    Parameters
    ----------
    n_vars : int
        Number of variables.
    order : int
        Truncation degree.
    """

    def __init__(self, n_vars: int, order: int) -> None:
        if n_vars < 1 or order < 1:
            raise InvalidValueError("need at least one variable and order >= 1")
        self.n_vars, self.order = int(n_vars), int(order)
        exps: list[tuple[int, ...]] = []
        for d in range(order + 1):
            exps += sorted((e for e in itertools.product(range(d + 1), repeat=n_vars)
                            if sum(e) == d), reverse=True)
        self.exponents = np.array(exps, dtype=int)
        self.index = {e: i for i, e in enumerate(exps)}
        self.degree = self.exponents.sum(axis=1)
        #: slices of each degree's block
        self.block = [slice(int(np.searchsorted(self.degree, d)),
                            int(np.searchsorted(self.degree, d, side="right")))
                      for d in range(order + 1)]
        # a + b for every pair with deg(a) + deg(b) <= order (-1: truncated)
        M = len(exps)
        self._sum = np.full((M, M), -1, dtype=int)
        for i, a in enumerate(exps):
            for j, b in enumerate(exps):
                if self.degree[i] + self.degree[j] <= order:
                    self._sum[i, j] = self.index[tuple(x + y for x, y in zip(a, b, strict=True))]

    def __len__(self) -> int:
        return self.exponents.shape[0]

    def multiply(self, a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
        """The truncated product of two series.

        Parameters
        ----------
        a, b : ndarray, shape (len(self),)
            Coefficient vectors.
        """
        out = np.zeros(len(self))
        for i in np.flatnonzero(a):
            ok = self._sum[i] >= 0
            np.add.at(out, self._sum[i, ok], a[i] * b[ok])
        return out

    def substitution(self, F: NDArray[np.float64], target: Monomials | None = None
                     ) -> NDArray[np.float64]:
        """Matrix ``MF`` with row ``alpha`` the series of ``v^alpha`` at ``v = F(u)``.

        So a map with coefficients ``C`` (over this basis) composed with ``F``
        has coefficients ``C @ MF`` over ``target`` (truncated at its order).
        ``F`` has one row per variable of this basis and no constant term
        (``F(0) = 0``).

        Parameters
        ----------
        F : ndarray, shape (n_vars, len(target))
            Coefficients of the substituted map over ``target``.
        target : Monomials, optional
            The basis of ``F``'s variables ``u`` (default: this basis).
        """
        target = self if target is None else target
        F = np.asarray(F, dtype=float)
        if F.shape != (self.n_vars, len(target)):
            raise InvalidValueError(f"F must have shape ({self.n_vars}, {len(target)})")
        if np.any(F[:, 0] != 0.0):
            raise InvalidValueError("F(0) must be 0 (expand around an equilibrium)")
        MF = np.zeros((len(self), len(target)))
        MF[0, 0] = 1.0
        for i in range(1, len(self)):
            e = self.exponents[i]
            if self.degree[i] > target.order:
                break
            j = int(np.flatnonzero(e)[0])
            prev = e.copy()
            prev[j] -= 1
            MF[i] = target.multiply(MF[self.index[tuple(prev)]], F[j])
        return MF

    def derivative(self, C: NDArray[np.float64], j: int) -> NDArray[np.float64]:
        """Coefficients of ``dC/dv_j`` (same basis; the top degree drops out).

        Parameters
        ----------
        C : ndarray, shape (r, len(self))
            Coefficients.
        j : int
            Variable.
        """
        C = np.atleast_2d(np.asarray(C, dtype=float))
        out = np.zeros_like(C)
        for i in np.flatnonzero(self.exponents[:, j] > 0):
            e = self.exponents[i].copy()
            e[j] -= 1
            out[:, self.index[tuple(e)]] += self.exponents[i, j] * C[:, i]
        return out

    def embed(self, other: Monomials, positions: Sequence[int]) -> NDArray[np.int64]:
        """Where this basis's monomials sit in ``other`` when variable ``i`` of this
        basis is variable ``positions[i]`` of ``other`` (the others set to 0).

        ``C_other[:, idx] = C`` lifts a map; ``C_other[:, idx]`` restricts one
        (to the remaining variables at 0).

        Parameters
        ----------
        other : Monomials
            The larger basis (same order).
        positions : sequence of int
            The positions of this basis's variables among ``other``'s.
        """
        if other.order != self.order:
            raise InvalidValueError("the bases must have the same order")
        e = np.zeros((len(self), other.n_vars), dtype=int)
        e[:, list(positions)] = self.exponents
        return np.array([other.index[tuple(r)] for r in e], dtype=int)

    def monomials(self, v: ArrayLike) -> NDArray[np.float64]:
        """The monomials ``v^alpha`` of this basis at the points ``v``.

        Parameters
        ----------
        v : array_like, shape (n_vars,) or (n_points, n_vars)
            One point or rows of points.

        Returns
        -------
        ndarray, shape (len(self),) or (n_points, len(self))
        """
        v = np.asarray(v, dtype=float)
        pw = v[..., :, None] ** np.arange(self.order + 1)       # (..., n_vars, order + 1)
        return np.prod(pw[..., np.arange(self.n_vars), self.exponents], axis=-1)

    def evaluate(self, C: NDArray[np.float64], v: ArrayLike) -> NDArray[np.float64]:
        """The polynomial map with coefficients ``C`` (rows) at the points ``v``.

        Parameters
        ----------
        C : ndarray, shape (r, len(self))
            Coefficients.
        v : array_like, shape (n_points, n_vars)
            Points.
        """
        return self.monomials(np.atleast_2d(np.asarray(v, dtype=float))) @ np.asarray(
            C, dtype=float).T

    def tail(self, C: NDArray[np.float64], monomials: NDArray[np.float64]) -> float:
        """:func:`series_tail` from the monomials at the point (:meth:`monomials`).

        Parameters
        ----------
        C : ndarray, shape (r, len(self))
            Coefficients.
        monomials : ndarray, shape (len(self),)
            The monomials at the point.
        """
        if self.order < 2:
            return 0.0
        top, lin = self.block[self.order], self.block[1]
        t_top = float(np.abs(C[:, top] @ monomials[top]).max())
        t_lin = float(np.abs(C[:, lin] @ monomials[lin]).max())
        if t_top == 0.0:
            return 0.0
        return t_top / t_lin if t_lin > 0.0 else np.inf


def series_tail(C: NDArray[np.float64], basis: Monomials, v: ArrayLike) -> float:
    """How much the top-degree terms of a truncated series weigh at the point ``v``.

    ``max |C_N v^N| / max |C_1 v|`` (max norms, ``N = basis.order``): small when
    the series has converged at ``v`` to the truncation's accuracy; of order 1 or
    more beyond its radius of convergence. 0 for ``order = 1`` (a linear map
    has no tail to judge by).

    Parameters
    ----------
    C : ndarray, shape (r, len(basis))
    basis : Monomials
    v : array_like, shape (n_vars,)
    """
    return basis.tail(C, basis.monomials(v))


def taylor(exprs: Sequence[Any] | Callable[..., Any], variables: Sequence[Any],
           basis: Monomials) -> NDArray[np.float64]:
    """Taylor coefficients at the origin of sympy expressions, up to ``basis.order``.

    Parameters
    ----------
    exprs : sequence of sympy expressions, or a callable
        The components; a callable is called with the sympy symbols
        ``variables`` and must return a sequence of expressions.
    variables : sequence of sympy symbols
        The variables, in the order of ``basis``.
    basis : Monomials

    Returns
    -------
    ndarray, shape (len(exprs), len(basis))
        Row ``i``: the coefficients of component ``i``.
    """
    sp = optional_import("sympy", extra="nonlinear", feature="Taylor series of nonlinear models")
    variables = list(variables)
    if len(variables) != basis.n_vars:
        raise InvalidValueError(f"{len(variables)} variables for a basis of {basis.n_vars}")
    if callable(exprs):
        exprs = exprs(*variables)
    exprs = [sp.sympify(e) for e in exprs]
    t = sp.Symbol("_t_scale")
    out = np.zeros((len(exprs), len(basis)))
    scale = {v: t * v for v in variables}
    for r, e in enumerate(exprs):
        ser = sp.series(e.subs(scale, simultaneous=True), t, 0, basis.order + 1).removeO()
        poly = sp.Poly(sp.expand(ser), t, *variables)
        for monom, coef in poly.terms():
            d, e_v = monom[0], tuple(monom[1:])
            if d != sum(e_v):
                raise InvalidValueError("unexpected term in the Taylor expansion")
            out[r, basis.index[e_v]] = float(coef)
    return out


@dataclass(frozen=True)
class LFEConditions:
    """Proposition 2's local solvability conditions for ``Phi(F) = A Phi + B h``.

    Attributes
    ----------
    observable : bool
        ``(H_1, F_1)`` is observable (assumption 1 is then solvable with an
        invertible ``T`` for a suitable ``A, B``).
    T_invertible : bool
        The Sylvester solution ``T`` of ``T F_1 - A T = B H_1`` is invertible
        (numerical rank at :data:`setobs.tolerances.RANK_RTOL`).
    nonresonant : bool
        No eigenvalue of ``A`` equals a product of eigenvalues of ``F_1`` of
        total degree 1..order (assumption 2, checked up to the truncation).
    min_divisor : float
        The smallest ``|a_j - prod lambda_i^m_i|`` over those products.
    poincare : bool
        The eigenvalues of ``F_1`` all lie strictly inside the unit disc, or all
        strictly outside (assumption 3).
    eigenvalues_F : ndarray
    eigenvalues_A : ndarray
    """

    observable: bool
    T_invertible: bool
    nonresonant: bool
    min_divisor: float
    poincare: bool
    eigenvalues_F: NDArray[np.complex128]
    eigenvalues_A: NDArray[np.complex128]

    @property
    def satisfied(self) -> bool:
        """All of Proposition 2's assumptions hold."""
        return self.T_invertible and self.nonresonant and self.poincare

    def reason(self) -> str:
        """What fails, in words (empty when all hold)."""
        out = []
        if not self.observable:
            out.append("the linearization (H_1, F_1) is not observable")
        if not self.T_invertible:
            out.append("T of T F_1 - A T = B H_1 is singular")
        if not self.nonresonant:
            out.append(f"resonance: an eigenvalue of A equals a product of eigenvalues of F_1 "
                       f"(smallest divisor {self.min_divisor:.2e})")
        if not self.poincare:
            out.append("eigenvalues of F_1 on the unit circle or on both sides of it (not in "
                       "the Poincare domain; the series may still converge when the divisors "
                       "stay away from 0)")
        return "; ".join(out)


def lfe_conditions(F1: ArrayLike, H1: ArrayLike, A: ArrayLike, B: ArrayLike,
                   order: int) -> LFEConditions:
    """Check Proposition 2's assumptions for the linear parts ``F_1``, ``H_1``.

    Parameters
    ----------
    F1 : array_like, shape (N, N)
        Jacobian of ``F`` at 0.
    H1 : array_like, shape (p, N)
        Jacobian of ``h`` at 0.
    A : array_like, shape (r, r)
    B : array_like, shape (r, p)
    order : int
        Degree up to which non-resonance is checked.
    """
    F1, H1 = np.atleast_2d(np.asarray(F1, float)), np.atleast_2d(np.asarray(H1, float))
    A, B = np.atleast_2d(np.asarray(A, float)), np.atleast_2d(np.asarray(B, float))
    lam, a = np.linalg.eigvals(F1), np.linalg.eigvals(A)
    T = solve_sylvester(-A, F1, B @ H1)
    T_inv = T.shape[0] == T.shape[1] and rank_decision(T).rank == T.shape[0]
    md = min_divisor(a, lam, 1, order)
    scale = max(1.0, float(np.abs(a).max()))
    inside = np.abs(lam) < 1.0
    outside = np.abs(lam) > 1.0
    observable = observability(F1, H1).n_observable == F1.shape[0]
    return LFEConditions(observable, T_inv, md > RESONANCE_RTOL * scale, md,
                         bool(inside.all() or outside.all()), lam, a)


def min_divisor(targets: ArrayLike, lam: ArrayLike, dmin: int, dmax: int) -> float:
    """Smallest ``|a - prod lam_i^m_i|`` over ``a`` in ``targets`` and exponents with
    ``dmin <= sum m_i <= dmax`` (the divisors of the degree-by-degree Sylvester
    equations; 0 at a resonance, Proposition 2's assumption 2).

    Parameters
    ----------
    targets : array_like
        Eigenvalues of the observer matrix.
    lam : array_like
        Eigenvalues of the linearization.
    dmin, dmax : int
        Range of total degrees.
    """
    targets, lam = np.asarray(targets), np.asarray(lam)
    out = np.inf
    for d in range(dmin, dmax + 1):
        for m in itertools.combinations_with_replacement(range(lam.size), d):
            out = min(out, float(np.abs(targets - np.prod(lam[list(m)])).min()))
    return out


@dataclass(frozen=True)
class LFESolution:
    """A truncated power-series solution ``Phi`` of ``Phi(F(v)) = A Phi(v) + B h(v)``.

    Attributes
    ----------
    basis : Monomials
    C : ndarray, shape (r, len(basis))
        Coefficients of ``Phi``.
    conditions : LFEConditions
    """

    basis: Monomials
    C: NDArray[np.float64]
    conditions: LFEConditions

    @property
    def T(self) -> NDArray[np.float64]:
        """The linear part (Jacobian at 0) of ``Phi``."""
        return self.C[:, self.basis.block[1]]

    def __call__(self, v: ArrayLike) -> NDArray[np.float64]:
        """``Phi`` at the points ``v`` (rows); shape (n_points, r)."""
        return self.basis.evaluate(self.C, v)


def solve_lfe(F: NDArray[np.float64], h: NDArray[np.float64], A: ArrayLike, B: ArrayLike,
              basis: Monomials) -> LFESolution:
    """Solve the LFE ``Phi(F(v)) = A Phi(v) + B h(v)`` degree by degree (Section VII).

    Parameters
    ----------
    F : ndarray, shape (N, len(basis))
        Taylor coefficients of the map (``F(0) = 0``), e.g. from :func:`taylor`.
    h : ndarray, shape (p, len(basis))
        Taylor coefficients of the output map (``h(0) = 0``).
    A : array_like, shape (r, r)
        Observer matrix (the assigned eigenvalues).
    B : array_like, shape (r, p)
    basis : Monomials

    Returns
    -------
    LFESolution

    Raises
    ------
    DesignError
        On resonance at some degree (the degree's Sylvester equation is
        singular).
    """
    F, h = np.asarray(F, float), np.asarray(h, float)
    A, B = np.atleast_2d(np.asarray(A, float)), np.atleast_2d(np.asarray(B, float))
    if np.any(h[:, 0] != 0.0):
        raise InvalidValueError("h(0) must be 0 (expand around an equilibrium)")
    MF = basis.substitution(F)
    blk = basis.block
    F1 = F[:, blk[1]]
    H1 = h[:, blk[1]]
    cond = lfe_conditions(F1, H1, A, B, basis.order)
    if not cond.nonresonant:
        raise DesignError("observer linearization: " + cond.reason(), "non-resonance")
    r = A.shape[0]
    C = np.zeros((r, len(basis)))
    Bh = B @ h
    for d in range(1, basis.order + 1):
        b = blk[d]
        # Phi_d (F_1 v) = C_d MF[d, d]; lower degrees through the nonlinear part
        rhs = Bh[:, b] - C[:, :b.start] @ MF[:b.start, b]
        C[:, b] = solve_sylvester(-A, MF[b, b], rhs)
    return LFESolution(basis, C, cond)


def invert(C: NDArray[np.float64], basis: Monomials) -> NDArray[np.float64]:
    """The truncated series of the local inverse of a map with invertible linear part.

    With ``Phi = T v + Phi_{>=2}``, the inverse ``G`` has ``G_1 = T^{-1}`` and
    ``G_d = -T^{-1} [Phi_{>=2} o G_{<d}]_d`` (the degree-``d`` part of
    ``Phi(G(z)) = z``).

    Parameters
    ----------
    C : ndarray, shape (n_vars, len(basis))
        Coefficients of ``Phi`` (``Phi(0) = 0``).
    basis : Monomials

    Returns
    -------
    ndarray, shape (n_vars, len(basis))
        Coefficients of ``G`` with ``Phi(G(z)) = z`` up to ``basis.order``.

    Raises
    ------
    DesignError
        When the linear part is singular.
    """
    C = np.asarray(C, dtype=float)
    blk = basis.block
    T = C[:, blk[1]]
    if T.shape[0] != T.shape[1] or rank_decision(T).rank < T.shape[0]:
        raise DesignError("the map's linear part is singular: no local inverse",
                          "invertible linear part")
    Tinv = np.linalg.inv(T)
    G = np.zeros_like(C)
    G[:, blk[1]] = Tinv
    for d in range(2, basis.order + 1):
        comp = C @ basis.substitution(G)
        G[:, blk[d]] = -Tinv @ comp[:, blk[d]]
    return G
