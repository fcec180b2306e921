"""LP layer: certified linear optimisation over a factor polytope.

Every LP query on a constrained zonotope reduces to optimising a linear
function over its *factor polytope*

.. math::  F = \\{\\xi \\in \\mathbb{R}^{n_g} : A\\xi = b,\\ |\\xi_j| \\le h_j\\},
           \\qquad h_j \\in [0, +\\infty].

This module solves those LPs with HiGHS (one model per polytope, built once and
re-solved with a new objective, warm-started from the previous basis) and turns
the solver's answer into a **certified** bound.

Certification
-------------
For any multiplier vector ``y`` (weak Lagrangian duality)

.. math::  \\min_{\\xi\\in F} w^\\top\\xi \\;\\ge\\; L(y) = y^\\top b - \\sum_j h_j |r_j|,
           \\qquad r = w - A^\\top y,

whatever the accuracy of ``y``: the solver's dual only decides how *tight* the
bound is, never whether it is valid. ``L(y)`` is evaluated in floating point
with a rigorous forward error term (Higham's ``gamma_k = k u / (1 - k u)``
bounds for dot products, doubled for the rounding of the error term itself),
and the result is rounded one ulp further down. So the bound holds for the
*stored* data regardless of solver tolerances; primal feasibility of the solver's
point is never relied upon.

An unbounded factor (``h_j = inf``) contributes ``-inf`` unless ``r_j = 0``.
The solver's ``y`` is refined by a least-squares correction on the unbounded
columns, after which ``|r_j|`` is at round-off level but rarely exactly zero.
The bound then holds for every point of ``F`` with ``|xi_j| <= radius`` on the
unbounded factors (the term ``radius * (|r_j| + err_j)`` is added); when the
relative residual stays above ``UNBOUNDED_REDUCED_COST_TOL`` the objective is
declared unbounded below (``-inf``), which is always an outer answer.

Infeasibility reported by the solver is never trusted either: emptiness is
decided by a phase-1 LP whose dual gives a certified lower bound on the
smallest constraint violation (see :meth:`FactorPolytope.emptiness`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import highspy
import numpy as np
from numpy.typing import NDArray

from ..exceptions import EmptySetError, SolverError
from ..tolerances import FEASIBILITY_TOL, UNBOUNDED_RADIUS, UNBOUNDED_REDUCED_COST_TOL

__all__ = ["EmptinessReport", "FactorPolytope", "LPOutcome", "lagrangian_lower_bound"]

_U = np.finfo(np.float64).eps / 2.0
_TINY = np.finfo(np.float64).tiny
_INF = highspy.kHighsInf
#: Relative certification gap above which duals are recomputed from the basis.
_REFINE_GAP = 1e-9
_DECIDED = (
    highspy.HighsModelStatus.kOptimal,
    highspy.HighsModelStatus.kUnbounded,
    highspy.HighsModelStatus.kInfeasible,
    highspy.HighsModelStatus.kUnboundedOrInfeasible,
)


def _gamma(k: int) -> float:
    """Higham's bound ``k u / (1 - k u)`` on the relative error of a length-k dot product."""
    return k * _U / (1.0 - k * _U)


def _down(x: float) -> float:
    return float(np.nextafter(x, -np.inf))


@dataclass(frozen=True)
class LPOutcome:
    """Result of one certified minimisation ``min w^T xi`` over a factor polytope.

    Attributes
    ----------
    bound : float
        Certified lower bound of the minimum (``-inf`` if unbounded below).
    objective : float
        The solver's objective value at its (approximate) minimiser
        (``-inf`` if unbounded). ``objective - bound`` is the certification gap.
    point : ndarray or None
        The solver's minimiser (``None`` if unbounded or no LP was needed and no
        point is meaningful).
    status : str
        ``"optimal"`` or ``"unbounded"``.
    """

    bound: float
    objective: float
    point: NDArray[np.float64] | None
    status: str

    @property
    def gap(self) -> float:
        """Certification gap ``objective - bound`` (>= 0 up to round-off)."""
        if np.isinf(self.bound):
            return 0.0 if np.isinf(self.objective) else np.inf
        return self.objective - self.bound


@dataclass(frozen=True)
class EmptinessReport:
    """Outcome of an emptiness test.

    Attributes
    ----------
    empty : bool
        ``True`` only if no point satisfies every normalised equality within
        ``tol`` (certified by ``violation_lower_bound > tol``).
    violation_lower_bound : float
        Certified lower bound on ``min_xi max_i |(A xi - b)_i| / s_i`` over the
        box, with ``s_i`` the row scale (infinity norm of ``[A_i, b_i]``).
    violation_found : float
        Violation of the best point the solver found (an upper bound on the
        minimum, up to the solver's accuracy).
    tol : float
        Tolerance used.
    """

    empty: bool
    violation_lower_bound: float
    violation_found: float
    tol: float = field(default=FEASIBILITY_TOL)


def _split(a: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Dekker's split of doubles into 26-bit halves (``a = hi + lo`` exactly)."""
    t = 134217729.0 * a  # 2**27 + 1
    hi = t - (t - a)
    return hi, a - hi


def _two_prod(M: NDArray[np.float64], v: NDArray[np.float64]):
    """Exact products ``M * v[:, None] = p + e`` (Dekker's TwoProduct)."""
    p = M * v[:, None]
    mh, ml = _split(M)
    vh, vl = _split(np.broadcast_to(v[:, None], M.shape))
    return p, ((mh * vh - p) + mh * vl + ml * vh) + ml * vl


def _exact_residual(
    w: NDArray[np.float64],
    A: NDArray[np.float64],
    ys: list[NDArray[np.float64]],
    w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> NDArray[np.float64]:
    """Correctly rounded ``w - A^T (y_1 + y_2 + ...)``, column by column.

    With ``w_pair = (M, v)`` the objective is taken as the exact ``M^T v``
    instead of ``w``.

    Products are split exactly (Dekker's TwoProduct) and summed with
    :func:`math.fsum`, so each entry has relative error at most ``u``
    (barring underflow, covered by an absolute guard in the caller).
    """
    neg = []
    for y in ys:
        neg.extend(_two_prod(A, y))
    pos = list(_two_prod(*w_pair)) if w_pair is not None else []
    out = np.empty(w.size)
    for j in range(w.size):
        terms = [] if w_pair is not None else [w[j]]
        for block in pos:
            terms.extend(block[:, j].tolist())
        for block in neg:
            terms.extend((-block[:, j]).tolist())
        out[j] = math.fsum(terms)
    return out


def lagrangian_lower_bound(
    w: NDArray[np.float64],
    A: NDArray[np.float64],
    b: NDArray[np.float64],
    h: NDArray[np.float64],
    y: NDArray[np.float64],
    *,
    w_err: NDArray[np.float64] | None = None,
    radius: float = UNBOUNDED_RADIUS,
    unbounded_pinv: NDArray[np.float64] | None = None,
    w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
) -> tuple[float, NDArray[np.float64]]:
    """Certified lower bound of ``min {w^T xi : A xi = b, |xi| <= h}`` from any multiplier ``y``.

    Parameters
    ----------
    w : ndarray, shape (n_g,)
        Objective.
    A, b, h :
        The factor polytope.
    y : ndarray, shape (n_c,)
        Any multiplier vector (typically the solver's row duals).
    w_err : ndarray, optional
        Elementwise bound on the error of ``w`` itself (when ``w`` was computed
        in floating point, e.g. ``G^T d``).
    radius : float
        Radius on unbounded factors (see module notes).
    unbounded_pinv : ndarray, optional
        ``pinv(A[:, unbounded].T)``, used to refine ``y``; computed if omitted.
    w_pair : (M, v), optional
        When ``w`` was computed as ``M^T v``, the exact objective on unbounded
        columns is taken from ``(M[:, unbounded], v)`` (no rounding of ``w``
        enters the radius term).

    Returns
    -------
    bound : float
        Certified lower bound (``-inf`` if the unbounded columns' reduced costs
        cannot be made negligible).
    y : ndarray
        The (refined) multiplier used (``y1 + y2`` rounded).

    Notes
    -----
    With unbounded factors the multiplier is kept in double-double form
    ``y1 + y2``: ``y1`` is refined in floating point, then the residual reduced
    costs on the unbounded columns are evaluated exactly (correctly rounded)
    and corrected by ``y2``. This brings them to ``O(eps^2)`` relative size, so
    that the radius term is negligible.
    """
    n_c, n_g = A.shape
    unb = np.isinf(h)
    y1 = np.array(y, dtype=np.float64)
    y2 = np.zeros(n_c)
    ru = np.zeros(0)
    if unb.any() and n_c:
        if unbounded_pinv is None:
            unbounded_pinv = np.linalg.pinv(A[:, unb].T)
        Au, wu = A[:, unb], w[unb]
        pair = (w_pair[0][:, unb], w_pair[1]) if w_pair is not None else None
        for _ in range(2):
            y1 = y1 + unbounded_pinv @ (wu - Au.T @ y1)
        ru = _exact_residual(wu, Au, [y1, y2], pair)
        for _ in range(2):
            if not ru.any():
                break
            y2 = y2 + unbounded_pinv @ ru
            ru = _exact_residual(wu, Au, [y1, y2], pair)
    elif unb.any():
        ru = w[unb] if w_pair is None else _exact_residual(
            w[unb], np.zeros((0, int(unb.sum()))), [], (w_pair[0][:, unb], w_pair[1]))
    abs_y = np.abs(y1) + np.abs(y2)
    scale_r = np.abs(w) + (np.abs(A).T @ abs_y if n_c else 0.0)
    r = w - A.T @ y1 - A.T @ y2 if n_c else w.copy()
    err_r = 2.0 * _gamma(2 * n_c + 2) * scale_r
    if w_err is not None:
        err_r = err_r + w_err * (1.0 + 4.0 * _U)
    bound_r = np.abs(r) + err_r
    t2 = 0.0
    if unb.any():
        # Correctly rounded residual: |true| <= |ru| / (1 - u), plus an underflow guard.
        ru_bound = np.abs(ru) / (1.0 - _U) + 2.0 * (2 * n_c + 1) * _TINY
        if w_err is not None and w_pair is None:
            ru_bound = ru_bound + w_err[unb] * (1.0 + 4.0 * _U)
        rel = (ru_bound - 2.0 * (2 * n_c + 1) * _TINY) / np.maximum(scale_r[unb], _TINY)
        if (rel > UNBOUNDED_REDUCED_COST_TOL).any():
            return -np.inf, y1
        t2 += radius * float(ru_bound.sum()) * (1.0 + _gamma(ru_bound.size + 1))
    fin = ~unb
    t2 += float(h[fin] @ bound_r[fin])
    t1 = float(y1 @ b + y2 @ b) if n_c else 0.0
    err = 2.0 * (
        _gamma(2 * n_c + 2) * (float(abs_y @ np.abs(b)) if n_c else 0.0)
        + _gamma(n_g + 3) * t2
        + _U * (abs(t1) + t2)
    )
    return _down(t1 - t2 - err), y1 + y2


def _status_name(h: highspy.Highs) -> str:
    return h.modelStatusToString(h.getModelStatus())


class FactorPolytope:
    """The polytope ``{xi : A xi = b, |xi_j| <= h_j}`` with one reusable HiGHS model.

    Parameters
    ----------
    A : ndarray, shape (n_c, n_g)
    b : ndarray, shape (n_c,)
    h : ndarray, shape (n_g,), entries in ``[0, inf]``
    radius : float
        Radius on unbounded factors used in certification.

    Notes
    -----
    HiGHS runs with presolve off (with presolve on it returned no status on
    some LPs with many infinite bounds). The model is re-solved warm with a new
    objective per direction. The dual simplex is used: on the benchmark's dense
    interval-hull LPs (``benchmarks/interval_hull.py``) it measured faster than
    the primal simplex at every size (e.g. 374 ms vs 558 ms for the 20 LPs of
    ``(n, n_gen, n_con) = (10, 200, 150)``), although only the objective changes.
    If a solve ends without a decided status, a fresh model with the dual
    simplex is tried once before :class:`~setobs.SolverError` is raised.
    """

    def __init__(
        self,
        A: NDArray[np.float64],
        b: NDArray[np.float64],
        h: NDArray[np.float64],
        radius: float = UNBOUNDED_RADIUS,
    ) -> None:
        self.A = A
        self.b = b
        self.h = h
        self.radius = radius
        self.n_c, self.n_g = A.shape
        self._unb = np.isinf(h)
        self._unb_pinv: NDArray[np.float64] | None = None
        self._model: highspy.Highs | None = None
        self._phase1: highspy.Highs | None = None
        self._emptiness: dict[float, EmptinessReport] = {}

    # -- model construction ------------------------------------------------
    @staticmethod
    def _new_highs() -> highspy.Highs:
        hs = highspy.Highs()
        hs.setOptionValue("output_flag", False)
        hs.setOptionValue("presolve", "off")
        hs.setOptionValue("threads", 1)
        # Tighter than HiGHS's 1e-7 defaults: with them the certified bound sat up
        # to ~1e-6 (relative) below the optimum on SMFDO sets with constrained
        # increment sets (the solver's point was infeasible by ~1e-7); with 1e-10
        # it agrees with the compiled fast path to 1e-8 (tests/geometry/test_fastlp.py).
        hs.setOptionValue("primal_feasibility_tolerance", 1e-10)
        hs.setOptionValue("dual_feasibility_tolerance", 1e-10)
        return hs

    @staticmethod
    def _pass(hs: highspy.Highs, A: NDArray[np.float64], lo_c, up_c, lo_r, up_r, cost) -> None:
        lp = highspy.HighsLp()
        n_r, n_col = A.shape
        lp.num_col_ = n_col
        lp.num_row_ = n_r
        lp.col_cost_ = np.ascontiguousarray(cost, dtype=np.float64)
        lp.col_lower_ = np.ascontiguousarray(lo_c, dtype=np.float64)
        lp.col_upper_ = np.ascontiguousarray(up_c, dtype=np.float64)
        lp.row_lower_ = np.ascontiguousarray(lo_r, dtype=np.float64)
        lp.row_upper_ = np.ascontiguousarray(up_r, dtype=np.float64)
        mask = A != 0.0
        counts = mask.sum(axis=0)
        start = np.zeros(n_col + 1, dtype=np.int32)
        np.cumsum(counts, out=start[1:])
        rows, cols = np.nonzero(mask.T)  # column-major order
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = start
        lp.a_matrix_.index_ = cols.astype(np.int32)
        lp.a_matrix_.value_ = np.ascontiguousarray(A.T[rows, cols])
        lp.a_matrix_.num_col_ = n_col
        lp.a_matrix_.num_row_ = n_r
        status = hs.passModel(lp)
        if status == highspy.HighsStatus.kError:
            raise SolverError("HiGHS rejected the LP model", status=str(status))

    def _col_bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        up = np.where(self._unb, _INF, self.h)
        return -up, up

    def _build(self, row_lo, row_hi, cost, *, unscaled: bool = False) -> highspy.Highs:
        """A HiGHS model of ``min cost^T xi, row_lo <= A xi <= row_hi, |xi| <= h``."""
        hs = self._new_highs()
        hs.setOptionValue("simplex_strategy", 1)  # dual simplex (measured faster)
        if unscaled:
            hs.setOptionValue("simplex_scale_strategy", 0)
        lo, up = self._col_bounds()
        self._pass(hs, self.A, lo, up, row_lo, row_hi, cost)
        return hs

    def _get_model(self) -> highspy.Highs:
        if self._model is None:
            self._model = self._build(self.b, self.b, np.zeros(self.n_g))
        return self._model

    def _pinv(self) -> NDArray[np.float64]:
        if self._unb_pinv is None:
            Au = self.A[:, self._unb]
            self._unb_pinv = np.linalg.pinv(Au.T) if self.n_c else np.zeros((0, Au.shape[1]))
        return self._unb_pinv

    # -- queries -----------------------------------------------------------
    def certify(
        self,
        w: NDArray[np.float64],
        y: NDArray[np.float64],
        w_err: NDArray[np.float64] | None = None,
        w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    ) -> float:
        """Certified lower bound of ``min w^T xi`` from multiplier ``y``."""
        return self._certify(w, y, w_err, w_pair)[0]

    def _certify(self, w, y, w_err=None, w_pair=None) -> tuple[float, NDArray[np.float64]]:
        return lagrangian_lower_bound(
            w, self.A, self.b, self.h, y, w_err=w_err, radius=self.radius,
            unbounded_pinv=self._pinv() if self._unb.any() else None, w_pair=w_pair,
        )

    @staticmethod
    def _pow2_scale(w: NDArray[np.float64]) -> float:
        """A power of two close to ``max |w|`` (dividing by it is exact)."""
        m = float(np.abs(w).max(initial=0.0))
        if m == 0.0 or not np.isfinite(m):
            return 1.0
        return float(np.ldexp(1.0, np.frexp(m)[1]))

    def _solve(self, hs: highspy.Highs, w: NDArray[np.float64], scale: float):
        hs.changeColsCost(self.n_g, np.arange(self.n_g, dtype=np.int32), w / scale)
        hs.run()
        return hs.getModelStatus()

    def minimize(
        self,
        w: NDArray[np.float64],
        w_err: NDArray[np.float64] | None = None,
        w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    ) -> LPOutcome:
        """Certified ``min w^T xi`` over the polytope.

        Parameters
        ----------
        w : ndarray
            Objective.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :func:`lagrangian_lower_bound`).

        Raises
        ------
        EmptySetError
            If the polytope is certified empty (see :meth:`emptiness`).
        SolverError
            If HiGHS ends in any status other than optimal/unbounded/infeasible
            twice (a fresh model with the dual simplex is tried once).
        """
        w = np.asarray(w, dtype=np.float64)
        if self.n_c == 0:
            # No constraints: the minimum over the box is analytic and exact.
            bound = self.certify(w, np.zeros(0), w_err, w_pair)
            if not np.isfinite(bound):
                return LPOutcome(-np.inf, -np.inf, None, "unbounded")
            point = -np.sign(w) * np.where(self._unb, 0.0, self.h)
            return LPOutcome(bound, float(w @ point), point, "optimal")
        # HiGHS sees the objective divided by a power of two (exact), so that its
        # tolerances act on a unit-size problem; certification uses the true w.
        scale = self._pow2_scale(w)
        hs = self._get_model()
        st = self._solve(hs, w, scale)
        if st not in _DECIDED:
            hs = self._build(self.b, self.b, np.zeros(self.n_g), unscaled=True)
            st = self._solve(hs, w, scale)
        if st == highspy.HighsModelStatus.kOptimal:
            sol = hs.getSolution()
            y = np.asarray(sol.row_dual, dtype=np.float64) * scale
            x = np.asarray(sol.col_value, dtype=np.float64)
            bound = self.certify(w, y, w_err, w_pair)
            obj = float(w @ x)
            if np.isfinite(bound) and obj - bound > _REFINE_GAP * (1.0 + abs(obj)):
                y_ref = self._basis_duals(hs, w)
                if y_ref is not None:
                    bound = max(bound, self.certify(w, y_ref, w_err, w_pair))
            if np.isinf(bound):
                return LPOutcome(-np.inf, obj, x, "unbounded")
            return LPOutcome(bound, obj, x, "optimal")
        if st == highspy.HighsModelStatus.kUnbounded:
            return LPOutcome(-np.inf, -np.inf, None, "unbounded")
        if st in (highspy.HighsModelStatus.kInfeasible,
                  highspy.HighsModelStatus.kUnboundedOrInfeasible):
            rep = self.emptiness()
            if rep.empty:
                raise EmptySetError(
                    "the set is empty (certified: every point violates a normalised "
                    f"constraint by at least {rep.violation_lower_bound:.3g})"
                )
            return self.minimize_relaxed(w, w_err, w_pair)
        raise SolverError(
            f"HiGHS did not solve the LP (status: {_status_name(hs)})", status=_status_name(hs)
        )

    def _basis_duals(self, hs: highspy.Highs, w: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """Duals recomputed from HiGHS's optimal basis, with one refinement step.

        Solves ``A[N, B]^T y_N = w_B`` (``B`` basic columns, ``N`` nonbasic rows;
        ``y = 0`` on rows whose slack is basic). Only a candidate multiplier:
        the bound is certified by :meth:`certify` like any other.
        """
        basis = hs.getBasis()
        basic = highspy.HighsBasisStatus.kBasic
        bc = np.flatnonzero([st == basic for st in basis.col_status])
        nbr = np.flatnonzero([st != basic for st in basis.row_status])
        if bc.size != nbr.size:
            return None
        M = self.A[np.ix_(nbr, bc)].T
        try:
            yn = np.linalg.solve(M, w[bc])
            yn += np.linalg.solve(M, w[bc] - M @ yn)
        except np.linalg.LinAlgError:
            return None
        y = np.zeros(self.n_c)
        y[nbr] = yn
        return y

    def minimize_relaxed(
        self,
        w: NDArray[np.float64],
        w_err: NDArray[np.float64] | None = None,
        w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    ) -> LPOutcome:
        """Certified ``min w^T xi`` with the rows relaxed to ``|A xi - b| <= delta``.

        Used when the set is not certified empty but the exact LP is infeasible
        or its certified bounds cross: the relaxed feasible set contains every
        point that satisfies the normalised constraints within the emptiness
        tolerance, so its certified bound is an outer bound in the sense of
        :meth:`emptiness` (and a valid bound for the exact set).
        """
        rep = self.emptiness()
        delta = self._row_scale() * max(2.0 * rep.violation_found, 2.0 * rep.tol)
        scale = self._pow2_scale(w)
        hs = self._build(self.b - delta, self.b + delta, w / scale)
        hs.run()
        st = hs.getModelStatus()
        if st == highspy.HighsModelStatus.kUnbounded:
            return LPOutcome(-np.inf, -np.inf, None, "unbounded")
        if st != highspy.HighsModelStatus.kOptimal:
            raise SolverError(
                "HiGHS reported infeasibility that could not be certified, and the relaxed "
                f"LP did not solve (status: {_status_name(hs)})",
                status=_status_name(hs),
            )
        sol = hs.getSolution()
        y = np.asarray(sol.row_dual, dtype=np.float64) * scale
        x = np.asarray(sol.col_value, dtype=np.float64)
        bound, y = self._certify(w, y, w_err, w_pair)
        if np.isinf(bound):
            return LPOutcome(-np.inf, float(w @ x), x, "unbounded")
        # Relaxed rows |A xi - b| <= delta add -sum |y_i| delta_i to the bound.
        relax = float(np.abs(y) @ delta) * (1.0 + 2.0 * _gamma(self.n_c + 1))
        return LPOutcome(_down(bound - relax), float(w @ x), x, "optimal")

    def _row_scale(self) -> NDArray[np.float64]:
        """Power-of-two row scales (so that scaling is exact in floating point)."""
        s = np.maximum(np.abs(self.A).max(axis=1, initial=0.0), np.abs(self.b))
        m, e = np.frexp(np.where(s > 0.0, s, 1.0))
        return np.ldexp(1.0, np.where(m == 0.5, e - 1, e))

    def emptiness(self, tol: float = FEASIBILITY_TOL) -> EmptinessReport:
        """Certified emptiness test with a phase-1 LP.

        Solves ``min sum(s+ + s-)`` subject to ``D(A xi - b) + s+ - s- = 0``,
        ``|xi| <= h``, ``s+-  >= 0``, with ``D`` scaling each row to unit
        infinity norm. For any multiplier ``y``, ``L(y) / ||y||_1`` (with
        ``L`` the Lagrangian bound of the zero objective) is a certified lower
        bound on the smallest infinity-norm violation of the normalised rows.

        Parameters
        ----------
        tol : float
            The set is reported empty only if that lower bound exceeds ``tol``.
        """
        if tol in self._emptiness:
            return self._emptiness[tol]
        if self.n_c == 0:
            rep = EmptinessReport(False, 0.0, 0.0, tol)
            self._emptiness[tol] = rep
            return rep
        scale = self._row_scale()
        As = self.A / scale[:, None]
        bs = self.b / scale
        n_c, n_g = self.n_c, self.n_g
        hs = self._new_highs()
        hs.setOptionValue("simplex_strategy", 1)  # dual simplex
        lo, up = self._col_bounds()
        big = np.hstack([As, np.eye(n_c), -np.eye(n_c)])
        lo_c = np.concatenate([lo, np.zeros(2 * n_c)])
        up_c = np.concatenate([up, np.full(2 * n_c, _INF)])
        cost = np.concatenate([np.zeros(n_g), np.ones(2 * n_c)])
        self._pass(hs, big, lo_c, up_c, bs, bs, cost)
        hs.run()
        if hs.getModelStatus() != highspy.HighsModelStatus.kOptimal:
            raise SolverError(
                f"phase-1 LP did not solve (status: {_status_name(hs)})",
                status=_status_name(hs),
            )
        sol = hs.getSolution()
        y = np.asarray(sol.row_dual, dtype=np.float64)
        x = np.asarray(sol.col_value, dtype=np.float64)[:n_g]
        # Certified bound with the scaled data (exact: power-of-two scales); the
        # objective is zero in xi, so L(y) <= ||y||_1 * min ||As xi - bs||_inf.
        lower, y = lagrangian_lower_bound(
            np.zeros(n_g), As, bs, self.h, y, radius=self.radius,
            unbounded_pinv=np.linalg.pinv(As[:, self._unb].T) if self._unb.any() else None,
        )
        norm1 = float(np.abs(y).sum()) * (1.0 + 2.0 * _gamma(n_c + 1))
        if norm1 > 0.0 and np.isfinite(lower) and lower > 0.0:
            lower_inf = _down(lower / norm1)
        else:
            lower_inf = 0.0  # no positive certificate
        xc = np.clip(x, -self.h, self.h)
        found = float(np.abs(As @ xc - bs).max())
        rep = EmptinessReport(bool(lower_inf > tol), lower_inf, found, tol)
        self._emptiness[tol] = rep
        return rep
