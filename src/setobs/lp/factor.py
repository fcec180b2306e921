"""The factor polytope's LP: certified linear optimisation over a constrained zonotope's factors.

Every LP query on a constrained zonotope reduces to optimising a linear
function over its *factor polytope*

.. math::  F = \\{\\xi \\in \\mathbb{R}^{n_g} : A\\xi = b,\\ |\\xi_j| \\le h_j\\},
           \\qquad h_j \\in [0, +\\infty].

This module solves those LPs with HiGHS (one model per polytope, built once and
re-solved with a new objective, warm-started from the previous basis; set up in
:mod:`setobs.lp.highs`) or the compiled simplex (:mod:`setobs.lp.fastlp`) and
turns the solver's answer into a **certified** bound.

Certification
-------------
Every bound is the certificate of :mod:`setobs.lp.certificate` (weak duality
with its rounding analysis) for the solver's multiplier, over ``lo = -h``,
``hi = h``: the solver's dual only decides how *tight* the bound is, never
whether it is valid, and the bound holds for the *stored* data regardless of
solver tolerances (primal feasibility of the solver's point is never relied
upon). Unbounded factors (``h_j = inf``) are covered for ``|xi_j| <=
unbounded_radius`` once their reduced costs are negligible, else the bound is
``-inf``; a right-hand side known only to ``+- b_err`` (rounding of the
operations that formed it, representation error of measured data) is covered too.

Infeasibility reported by the solver is never trusted either: emptiness is
decided by a phase-1 LP whose dual gives a certified lower bound on the
smallest constraint violation (see :meth:`FactorPolytope.emptiness`).

A solver's bad day never aborts a query: an undecided HiGHS status is retried
with other settings (a fresh unscaled model, default tolerances with the
primal simplex, the interior-point method with crossover, a restart with the
objective perturbed -- certified for the true one), with the compiled simplex of
:mod:`setobs.lp.fastlp`, and with the rows as the intervals
``[b - b_err, b + b_err]`` the certificate covers (exact for the certified set
when decided; unbounded factors are pivoted out first, so that rows of an
unknown initial state of size 1e9 do not reach HiGHS); if every attempt fails,
the best certified
bound of any multiplier seen (at worst ``y = 0``, i.e. ``-sum h_j |w_j|`` or
``-inf``) is returned with status ``"fallback"``: wider, still outer.
"""

from __future__ import annotations

import math
import threading
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._blas import with_single_threaded_blas_unless_small
from .._lazy import lazy_module
from .._rounding import gamma, round_down, two_prod
from ..exceptions import DimensionError, EmptySetError
from ..tolerances import (
    FASTLP_GAP_RTOL,
    FEASIBILITY_TOL,
    LP_REFINE_GAP,
    MAX_MAGNITUDE,
    PRIMAL_RESIDUAL_RTOL,
    RELAXED_EXACT_GAP,
    UNBOUNDED_RADIUS,
)
from . import highs

if TYPE_CHECKING:
    from highspy import Highs as HighsModel

__all__ = ["EmptinessReport", "FactorPolytope", "LPResult"]

_INF = math.inf  # HiGHS's kHighsInf

# the compiled simplex (numba): compiles or loads on the first compiled query
_simplex = lazy_module("setobs.lp._simplex")
# the one certificate (compiled; loads with the first certified bound)
_certificate = lazy_module("setobs.lp.certificate")


@dataclass(frozen=True)
class LPResult:
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
        ``"optimal"``, ``"unbounded"``, or ``"fallback"`` (every solver attempt
        failed; ``bound`` is the best certified bound of the multipliers seen,
        possibly ``-inf``).
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
    witness : ndarray or None
        When not ``empty``: the solver's best point (LazySets'
        ``isempty(X, witness=true)``), clipped to the factor box, whose
        normalised violation is ``violation_found``. A factor vector from
        :meth:`FactorPolytope.emptiness`, a point of the set from
        :meth:`~setobs.ConstrainedZonotope.emptiness`. ``None`` when the set is
        empty or no LP solved.
    """

    empty: bool
    violation_lower_bound: float
    violation_found: float
    tol: float = field(default=FEASIBILITY_TOL)
    witness: NDArray[np.float64] | None = None


def _exact_residual(b: NDArray[np.float64], M: NDArray[np.float64],
                    x: NDArray[np.float64]) -> NDArray[np.float64]:
    """Correctly rounded ``b - M^T x``, entry by entry (Dekker's TwoProduct and
    :func:`math.fsum`); NaN where the exact sum is beyond double precision."""
    prods = two_prod(M, x)
    out = np.empty(b.size)
    for j in range(b.size):
        terms = [b[j]]
        for block in prods:
            terms.extend((-block[:, j]).tolist())
        try:
            out[j] = math.fsum(terms)
        except (ValueError, OverflowError):
            out[j] = np.nan
    return out


#: The LP queries on sets whose data span double precision's range (entries from 1e-300
#: to 1e150 in one set) overflow in pseudo-inverses and multiplier products; every such
#: result is guarded (a non-finite model never reaches HiGHS, a NaN certificate is
#: -inf, a non-finite reduction declines the compiled path), so the queries answer with
#: a certified, wider bound, without numpy's overflow warnings.
def _quiet_overflow(func):
    import functools

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        # (a fresh errstate per call: one instance cannot be entered twice, nor
        # shared by threads)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return func(*args, **kwargs)
    return wrapper


#: Largest number of constraint rows for which the factor polytope's queries use the
#: compiled dense simplex (the hull batch, the phase-1 LP). Above it HiGHS's sparse
#: simplex wins: on the convex hull of two random sets with 100 rows the hull took 20
#: ms compiled against 7 ms, with 320 rows 1.07 s against 51 ms (emptiness: 8 vs 3
#: ms, 217 vs 19 ms); below 64 rows the compiled path was 2-9x faster.
COMPILED_MAX_ROWS: int = 64


def _polytope_size(fp: FactorPolytope) -> int:
    """Largest dimension of a factor polytope's matrices (the phase-1 LP's ``2 n_c``
    extra columns are identities: its products stay below OpenBLAS's thresholds)."""
    return max(fp.n_g, fp.n_c)


_blas_unless_small = with_single_threaded_blas_unless_small(_polytope_size)


def equilibration(A: NDArray[np.float64], b: NDArray[np.float64],
                  b_err: NDArray[np.float64] | None = None) -> NDArray[np.float64] | None:
    """Power-of-two row scales ``s`` that bring each row of ``A`` to an infinity norm in
    ``[1/2, 1)`` (``A / s``, ``b / s`` are exact; ``b`` does not set the scale: its size
    is the solution's, e.g. states of ``1e8`` carried by unbounded factors, and rows
    scaled down by it fell back), or ``None`` when the rows'
    sizes are within a factor of ``2^10`` of each other and of ``2^+-20`` of unit size:
    HiGHS's own scaling and the compiled simplex's equilibration of the working copy
    handle those (and a thin set of the soundness campaign, rows of 190 to 8000, came
    out 2e-5 looser re-scaled: ``window_open_gap_set.npz``). A row whose ``b`` or
    ``b_err`` would exceed ``MAX_MAGNITUDE`` once scaled keeps its scale (no overflow).

    Parameters
    ----------
    A : ndarray, shape (m, n)
        Constraint matrix.
    b : ndarray, shape (m,)
        Right-hand side.
    b_err : ndarray, shape (m,), optional
        Bound on the rounding error of ``b``.
    """
    r = np.abs(A).max(axis=1, initial=0.0)
    r = r[r > 0.0]
    if r.size == 0:
        return None
    top, low = float(r.max()), float(r.min())
    if top <= 2.0 ** 20 and low >= 2.0 ** -20 and top <= 1024.0 * low:
        return None
    r = np.abs(A).max(axis=1, initial=0.0)
    e = np.frexp(np.where(r > 0.0, r, 1.0))[1]
    s = np.where(r > 0.0, np.ldexp(1.0, e), 1.0)
    big = np.abs(b) if b_err is None else np.maximum(np.abs(b), b_err)
    return np.where(big > MAX_MAGNITUDE * np.minimum(s, 1.0), 1.0, s)


class FactorPolytope:
    """The polytope ``{xi : A xi = b, |xi_j| <= h_j}`` with one reusable HiGHS model.

    Parameters
    ----------
    A : ndarray, shape (n_c, n_g)
    b : ndarray, shape (n_c,)
    h : ndarray, shape (n_g,), entries in ``[0, inf]``
    unbounded_radius : float
        Radius on unbounded factors used in certification.
    b_err : ndarray, shape (n_c,), optional
        Bound on the uncertainty of ``b`` (see :mod:`setobs.lp.certificate`);
        every bound and emptiness verdict then holds for all ``b`` within it.

    Attributes
    ----------
    fallbacks : int
        Number of queries on which every solver attempt failed and the best
        certified bound of the multipliers seen was returned (status
        ``"fallback"``).

    Notes
    -----
    HiGHS runs with presolve off (with presolve on it returned no status on
    some LPs with many infinite bounds). The model is re-solved warm with a new
    objective per direction. The dual simplex is used: on the benchmark's dense
    interval-hull LPs (``benchmarks/interval_hull.py``) it measured faster than
    the primal simplex at every size (e.g. 374 ms vs 558 ms for the 20 LPs of
    ``(n, n_gen, n_con) = (10, 200, 150)``), although only the objective changes.
    If a solve ends without a decided status, it is retried (see the module
    notes) before a ``"fallback"`` answer is returned. Queries on one instance
    are serialised by a lock (the HiGHS model is stateful), so a set shared by
    threads stays correct.
    """

    def __init__(
        self,
        A: NDArray[np.float64],
        b: NDArray[np.float64],
        h: NDArray[np.float64],
        unbounded_radius: float = UNBOUNDED_RADIUS,
        b_err: NDArray[np.float64] | None = None,
    ) -> None:
        if A.ndim != 2 or b.shape != (A.shape[0],) or h.shape != (A.shape[1],) or (
                b_err is not None and np.shape(b_err) != b.shape):
            raise DimensionError(
                f"FactorPolytope needs the shapes A (m, n), b (m,), h (n,), b_err (m,): got A "
                f"{A.shape}, b {b.shape}, h {h.shape}, b_err "
                f"{None if b_err is None else np.shape(b_err)}")
        # (count_nonzero: ~0.3 us against ~1.4 for np.any, on every set's first query)
        b_err = None if b_err is None or not np.count_nonzero(b_err) else b_err
        if A.shape[0]:
            # Rows equilibrated by powers of two (exact: the same polytope, the same
            # rounding bounds): every LP below, compiled or HiGHS, sees rows of unit
            # size. Rows of [A, b] scaled by 2^+-30 had made 2 of 250 hull LPs fall
            # back to wide bounds and left others up to 1.5 (relative) loose, unwarned.
            s = equilibration(A, b, b_err)
            if s is not None:
                A, b = A / s[:, None], b / s
                if b_err is not None:
                    b_err = b_err / s
        self.A = A
        self.b = b
        self.h = h
        self.unbounded_radius = unbounded_radius
        self.b_err = b_err
        self.n_c, self.n_g = A.shape
        self._unb = np.isinf(h)
        self._any_unb = bool(np.count_nonzero(self._unb))
        self._unb_pinv: NDArray[np.float64] | None = None
        self._csc: tuple | None = None  # (A column by column, for the certificate)
        self._neg_h = -h
        self._pivot: tuple | None = None  # (see _free_pivot)
        self._model: HighsModel | None = None
        self._emptiness: dict[float, EmptinessReport] = {}
        self._lock = threading.RLock()
        self.fallbacks = 0

    def __getstate__(self) -> dict:
        # HiGHS models and locks do not pickle; they are rebuilt on demand.
        state = self.__dict__.copy()
        state["_model"] = None
        del state["_lock"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self._lock = threading.RLock()

    # -- model construction ------------------------------------------------
    def _col_bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        up = np.where(self._unb, _INF, self.h)
        return -up, up

    #: Settings of the retries after an undecided status (see the module notes).
    #: Relative size of the objective perturbation of the last HiGHS retry (a
    #: perturbed restart: ties of a degenerate LP broken, the bound certified for
    #: the true objective from the basis found).
    PERTURBATION: float = 1e-7

    def perturbed_objective(self, w: NDArray[np.float64]) -> NDArray[np.float64]:
        """``w`` plus a fixed pseudo-random perturbation of relative size
        :attr:`PERTURBATION` on the bounded factors (a perturbation on an unbounded
        one could make the LP unbounded).

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        """
        u = np.random.default_rng(12345).uniform(-1.0, 1.0, self.n_g)
        mag = float(np.abs(w).max(initial=0.0))
        return w + np.where(self._unb, 0.0, self.PERTURBATION * max(mag, 1e-300) * u)

    def _build(self, row_lo, row_hi, cost, options: dict[str, object] | None = None
               ) -> HighsModel | None:
        """A HiGHS model of ``min cost^T xi, row_lo <= A xi <= row_hi, |xi| <= h``."""
        hs = highs.new_model(options)
        lo, up = self._col_bounds()
        return hs if highs.pass_dense(hs, self.A, lo, up, row_lo, row_hi, cost) else None

    def highs_model(self) -> HighsModel | None:
        if self._model is None:
            self._model = self._build(self.b, self.b, np.zeros(self.n_g))
        return self._model

    def _pinv(self) -> NDArray[np.float64]:
        pinv = self._unb_pinv
        if pinv is None:
            Au = self.A[:, self._unb]
            pinv = np.asarray(np.linalg.pinv(Au.T) if self.n_c else np.zeros((0, Au.shape[1])),
                              dtype=np.float64)
            self._unb_pinv = pinv
        return pinv

    # -- queries -----------------------------------------------------------
    def certify(
        self,
        w: NDArray[np.float64],
        y: NDArray[np.float64],
        w_err: NDArray[np.float64] | None = None,
        w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
        exact_residual: bool = False,
    ) -> float:
        """Certified lower bound of ``min w^T xi`` from multiplier ``y``.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        y : ndarray, shape (n_c,)
            Multiplier of the equality constraints (any vector gives a valid bound).
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        exact_residual : bool
            Reduced costs correctly rounded (see :mod:`setobs.lp.certificate`).
        """
        return self._certify(w, y, w_err, w_pair, exact_residual)[0]

    def _tightened(self, w, w_err, w_pair, hs, y, bound: float, obj: float,
                   rtol: float) -> float:
        """``bound`` (from multiplier ``y``) certified again while its gap to the
        solver's objective ``obj`` exceeds ``rtol`` (relative to ``1 + |obj|``): from
        the duals of the optimal basis of ``hs`` (refined in extended precision;
        skipped when ``hs`` is ``None``), then, above :data:`RELAXED_EXACT_GAP`, with
        every reduced cost correctly rounded (the forward error bound of
        ``w - A^T y`` grows with ``|y|``, and duals of 1e4 once opened a gap of 2e-6
        by that term alone)."""
        gap_tol = 1.0 + abs(obj)
        if not np.isfinite(bound) or obj - bound <= rtol * gap_tol:
            return bound
        if hs is not None:
            bound, y = self._basis_bound(w, w_err, w_pair, hs, y, bound)
        if obj - bound > RELAXED_EXACT_GAP * gap_tol:
            bound = max(bound, self.certify(w, y, w_err, w_pair, exact_residual=True))
        return bound

    def _basis_bound(self, w, w_err, w_pair, hs, y, bound: float):
        """``(bound, y)``, or the certified bound of the duals of the optimal basis of
        ``hs`` (refined in extended precision) with those duals, when it is higher."""
        y_ref = highs.basis_duals(hs, self.A, w)
        if y_ref is not None:
            b_ref = self.certify(w, y_ref, w_err, w_pair)
            if b_ref > bound:
                return b_ref, y_ref
        return bound, y

    def _certify(self, w, y, w_err=None, w_pair=None, exact_residual=False
                 ) -> tuple[float, NDArray[np.float64]]:
        if self._csc is None:
            self._csc = _certificate.csc_of(np.ascontiguousarray(self.A, dtype=np.float64))
        bound, y, _ = _certificate.certified_lower_bound(
            w, self.A, self.b, self._neg_h, self.h, y, w_err=w_err,
            unbounded_radius=self.unbounded_radius,
            unbounded_pinv=self._pinv() if self._any_unb else None, w_pair=w_pair,
            exact_residual=exact_residual, b_err=self.b_err, csc=self._csc)
        return bound, y

    @staticmethod
    def objective_scale(w: NDArray[np.float64]) -> float:
        """A power of two close to ``max |w|`` (dividing by it is exact).

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        """
        m = float(np.abs(w).max(initial=0.0))
        if m == 0.0 or not np.isfinite(m):
            return 1.0
        return float(np.ldexp(1.0, np.frexp(m)[1]))

    def solve_objective(self, hs: HighsModel, w: NDArray[np.float64], scale: float):
        """Run HiGHS on objective ``w / scale``; return the outcome
        (:func:`setobs.lp.highs.status`).

        Parameters
        ----------
        hs : highspy.Highs
            A model of this polytope (:meth:`highs_model`).
        w : ndarray, shape (n_g,)
            Objective over the factors.
        scale : float
            Power of two the objective is divided by (:meth:`objective_scale`).
        """
        hs.changeColsCost(self.n_g, np.arange(self.n_g, dtype=np.int32), w / scale)
        hs.run()
        return highs.status(hs)

    @_blas_unless_small
    def minimize(
        self,
        w: NDArray[np.float64],
        w_err: NDArray[np.float64] | None = None,
        w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    ) -> LPResult:
        """Certified ``min w^T xi`` over the polytope.

        Parameters
        ----------
        w : ndarray
            Objective.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).

        Returns
        -------
        LPResult
            Status ``"optimal"``, ``"unbounded"`` or ``"fallback"`` (every
            solver attempt failed: the best certified bound of the multipliers
            seen, possibly ``-inf``; counted in :attr:`fallbacks`).

        Raises
        ------
        EmptySetError
            If the polytope is certified empty (see :meth:`emptiness`).
        DimensionError
            ``w`` (or ``w_err``) not of length ``n_g``.
        """
        w = np.asarray(w, dtype=np.float64)
        if w.shape != (self.n_g,) or (w_err is not None and np.shape(w_err) != (self.n_g,)):
            raise DimensionError(f"w and w_err must have shape ({self.n_g},) (the polytope's "
                                 f"factors), got {w.shape} and "
                                 f"{None if w_err is None else np.shape(w_err)}")
        with self._lock:
            return self.minimize_under_lock(w, w_err, w_pair)

    @_quiet_overflow
    def minimize_under_lock(self, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                            w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None
                            ) -> LPResult:
        """:meth:`minimize` for a caller that holds the polytope's lock.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        """
        if self.n_c == 0:
            # No constraints: the minimum over the box is analytic and exact.
            bound = self.certify(w, np.zeros(0), w_err, w_pair)
            if not np.isfinite(bound):
                return LPResult(-np.inf, -np.inf, None, "unbounded")
            point = -np.sign(w) * np.where(self._unb, 0.0, self.h)
            return LPResult(bound, float(w @ point), point, "optimal")
        # HiGHS sees the objective divided by a power of two (exact), so that its
        # tolerances act on a unit-size problem; certification uses the true w.
        scale = self.objective_scale(w)
        best = -np.inf  # best certified bound of any multiplier (fallback answer)
        infeasible_claims = 0
        open_gap: LPResult | None = None  # the best "optimal" whose gap stayed open
        attempts = [None, *highs.RETRY_SETTINGS, "perturbed"]
        for i, options in enumerate(attempts):
            perturbed = options == "perturbed"
            hs = self.highs_model() if i == 0 else self._build(
                self.b, self.b, np.zeros(self.n_g),
                None if perturbed or isinstance(options, str) else options)
            if hs is None:
                continue
            st = self.solve_objective(hs, self.perturbed_objective(w) if perturbed else w, scale)
            if perturbed and st == "unbounded":
                continue  # (says nothing about the true objective)
            if st == "optimal":
                sol = hs.getSolution()
                y = np.asarray(sol.row_dual, dtype=np.float64) * scale
                x = np.asarray(sol.col_value, dtype=np.float64)
                bound = self.certify(w, y, w_err, w_pair)
                if not self.point_is_feasible(x):
                    # "Optimal" at an infeasible point: its objective, and the
                    # multiplier certified near it, may undercut the minimum.
                    # Certified all the same. Exact only if the objective plus the
                    # first-order cost of the rows' residual, |y|^T |A x - b|, still
                    # meets the certified bound (HiGHS's 1.3e-6 relative residual on
                    # a state-bound LP, with its gap at 1e-7); else the next attempt.
                    out = self._nearly_feasible(w, w_err, w_pair, hs, y, x, bound)
                    if out is not None:
                        return out
                    best = max(best, bound)
                    continue
                obj = float(w @ x)
                bound = self._tightened(w, w_err, w_pair, hs, y, bound, obj, LP_REFINE_GAP)
                if np.isinf(bound):
                    return LPResult(-np.inf, obj, x, "unbounded")
                if obj - bound > RELAXED_EXACT_GAP * (1.0 + abs(obj)):
                    # Certified, but not tight (duals inaccurate on a nearly degenerate
                    # set, 1e-3 of its width once): the next settings may close it.
                    if open_gap is None or bound > open_gap.bound:
                        open_gap = LPResult(bound, obj, x, "fallback")
                    continue
                return LPResult(bound, obj, x, "optimal")
            if st == "unbounded":
                return LPResult(-np.inf, -np.inf, None, "unbounded")
            if st == "infeasible":
                rep = self.emptiness()
                if rep.empty:
                    raise EmptySetError(
                        "the set is empty (certified: every point violates a normalised "
                        f"constraint by at least {rep.violation_lower_bound:.3g})"
                    )
                # "Infeasible" without a certificate: a hard LP, not a verdict. The
                # other settings decide it; the relaxed LP is the last resort.
                infeasible_claims += 1
                continue
            # Undecided: keep whatever multiplier the solver left (certified, it
            # is a valid bound however poor), then retry with other settings.
            y = np.asarray(hs.getSolution().row_dual, dtype=np.float64)
            if y.size == self.n_c and np.isfinite(y).all():
                best = max(best, self.certify(w, y * scale, w_err, w_pair))
        out = self.try_compiled(w, w_err, w_pair)
        if out is not None:
            return out
        # The rows are known to within b_err (the rounding of the operations that
        # formed b, the data's representation): at magnitudes where b_err exceeds
        # the solver's tolerance (states of 1e9, outputs of 1e10) the float rows
        # may be inconsistent while the certified set is not ("infeasible"), or too
        # ill-scaled for any setting (no status). Its LP has the rows as intervals
        # [b - b_err, b + b_err]; the certificate already holds for every such b,
        # so a minimiser there with the gap closed is exact.
        out = self.minimize_within_b_err(w, w_err, w_pair, scale)
        if out is not None:
            return out
        if open_gap is not None:
            self.fallbacks += 1
            return LPResult(max(open_gap.bound, best), open_gap.objective, open_gap.point,
                            "fallback")
        if infeasible_claims:
            # Not certified empty, but no setting found a feasible optimum: the LP
            # with rows relaxed by the smallest violation found is a valid outer
            # bound, wider than the exact one (so a fallback, counted).
            rel = self.minimize_relaxed(w, w_err, w_pair)
            if rel.status == "optimal":
                # Exact after all when the relaxed minimiser satisfies the exact rows
                # (then its objective bounds the minimum from above) and closes the
                # gap: a degenerate LP that HiGHS mislabelled, decided.
                if (rel.point is not None and self.point_is_feasible(rel.point)
                        and rel.objective - rel.bound
                        <= RELAXED_EXACT_GAP * (1.0 + abs(rel.objective))):
                    return rel
                self.fallbacks += 1
                return LPResult(max(rel.bound, best), rel.objective, rel.point, "fallback")
            if rel.status == "unbounded":
                return rel
            best = max(best, rel.bound)
        best = max(best, self.certify(w, np.zeros(self.n_c), w_err, w_pair))
        self.fallbacks += 1
        return LPResult(best, np.nan, None, "fallback")

    @_quiet_overflow
    def minimize_many(self, W: NDArray[np.float64], gaps: NDArray[np.float64] | None = None
                      ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Certified lower bounds of ``min W[i]^T xi`` for all ``i`` by the compiled
        simplex (:meth:`FixedStructureLP.bounded <setobs.lp.fastlp.FixedStructureLP.bounded>`:
        one dual simplex warm from the previous objective's basis, each multiplier
        certified like the HiGHS path's). For polytopes with every bound finite and
        1 to :data:`COMPILED_MAX_ROWS` rows; elsewhere nothing is solved.

        Parameters
        ----------
        W : ndarray, shape (n_lp, n_g)
            Objectives (exact: no rounding error to carry).
        gaps : ndarray, shape (n_lp // 2,), optional
            For objectives in pairs ``(w, -w)``: each LP may stop within ``gaps[t]`` of
            its pair's minimum (certified all the same;
            :meth:`~setobs.lp.fastlp.FixedStructureLP.minimize_all`).

        Returns
        -------
        bounds : ndarray, shape (n_lp,)
            Certified lower bounds where ``ok``.
        ok : ndarray of bool, shape (n_lp,)
            Solved with the certified bound within the fast path's gap of the simplex
            objective; the others go to :meth:`minimize` (which also decides
            emptiness).
        """
        n_lp = W.shape[0]
        if self.n_c == 0 or self.n_c > COMPILED_MAX_ROWS or self._any_unb or not n_lp:
            return np.full(n_lp, -np.inf), np.zeros(n_lp, dtype=bool)
        from .fastlp import FixedStructureLP

        with self._lock:
            lp = FixedStructureLP.bounded(self.A, W)
            if self.b_err is None:
                return lp.minimize_all(self.b, np.concatenate([self.h, np.zeros(self.n_c)]),
                                       gaps=gaps)
            bounds, ok, ys, objs = lp.minimize_all(
                self.b, np.concatenate([self.h, np.zeros(self.n_c)]), b_err=self.b_err,
                return_duals=True, gaps=gaps)
            # The exact rows' multiplier pays |y|^T b_err for the rows' uncertainty; where
            # that is more than the fast path's gap, the interval-row LP of minimize may
            # be tighter (a thin set of the soundness campaign: 2e-5 of a 0.33 width).
            if ok.any():  # (the multipliers of unsolved LPs are the buffer's leftovers)
                cost = np.abs(ys[ok, :self.n_c]) @ self.b_err
                ok[ok] = cost <= FASTLP_GAP_RTOL * (1.0 + np.abs(objs[ok]))
            return bounds, ok

    def _nearly_feasible(self, w, w_err, w_pair, hs, y, x, bound) -> LPResult | None:
        """An "optimal" answer at a point slightly off the rows, accepted as exact when
        ``w^T x + |y|^T max(|A x - b| - b_err, 0)`` (the objective corrected by the
        sensitivity of the optimum to the residual) is within :data:`RELAXED_EXACT_GAP`
        of the certified bound (duals of the basis tried too), the point in its
        box; else ``None``. A gross residual (3e-3 once) does not pass."""
        if not np.isfinite(x).all():
            return None
        over = np.abs(x) - self.h
        if (over > PRIMAL_RESIDUAL_RTOL * (1.0 + np.where(self._unb, 0.0, self.h))).any():
            return None
        resid = np.abs(self.A @ x - self.b)
        if self.b_err is not None:
            resid = np.maximum(resid - self.b_err, 0.0)
        bound, yb = self._basis_bound(w, w_err, w_pair, hs, y, bound)
        obj = float(w @ x) + float(np.abs(yb) @ resid)
        if not np.isfinite(bound) or obj - bound > RELAXED_EXACT_GAP * (1.0 + abs(obj)):
            return None
        return LPResult(bound, obj, x, "optimal")

    def minimize_within_b_err(self, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                              w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None,
                              scale: float) -> LPResult | None:
        """``min w^T xi`` over ``|A xi - b| <= b_err``, ``|xi| <= h`` (the set the
        certificate covers), or ``None`` unless it is decided with the gap closed.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        scale : float
            Power of two the objective is divided by (:meth:`objective_scale`).
        """
        be = self.b_err
        if be is None or not np.any(be):
            return None
        if self._any_unb and self.A[:, self._unb].any():
            out = self._within_b_err_reduced(w, w_err, w_pair)
            if out is not None:
                return out
        for options in (None, *highs.RETRY_SETTINGS):
            hs = self._build(self.b - be, self.b + be, np.zeros(self.n_g), options)
            if hs is None or self.solve_objective(hs, w, scale) != "optimal":
                continue
            sol = hs.getSolution()
            out = self._decided_within_b_err(
                w, w_err, w_pair, np.asarray(sol.row_dual, dtype=np.float64) * scale,
                np.asarray(sol.col_value, dtype=np.float64), hs)
            if out is not None:
                return out
        return None

    def _decided_within_b_err(self, w, w_err, w_pair, y, x, hs=None) -> LPResult | None:
        """The answer of the interval-row LP from a multiplier ``y`` and a point ``x``:
        ``x`` in the certified set and the gap closed (with the duals of the basis
        of ``hs`` refined where the solver's are not accurate enough), or ``None``."""
        if not self.point_is_feasible(x, row_allowance=self.b_err):
            return None
        bound = self.certify(w, y, w_err, w_pair)
        obj = float(w @ x)
        bound = self._tightened(w, w_err, w_pair, hs, y, bound, obj, RELAXED_EXACT_GAP)
        if not np.isfinite(bound) or obj - bound > RELAXED_EXACT_GAP * (1.0 + abs(obj)):
            return None
        return LPResult(bound, obj, x, "optimal")

    def _within_b_err_reduced(self, w, w_err, w_pair) -> LPResult | None:
        """:meth:`minimize_within_b_err` with the unbounded factors pivoted out.

        The LP is ``min w^T xi`` over ``A_u xi_u + A_b xi_b = b + e``,
        ``|e| <= b_err``, ``|xi_b| <= h`` (``u``: unbounded factors). With
        ``A_u = U S V^T`` (numerical rank ``r``), ``N`` an orthonormal basis of its
        left null space and ``A_u^T M = w_u``, it is the same LP as
        ``min (w_b - A_b^T M)^T xi_b + M^T e`` subject to
        ``N^T A_b xi_b - N^T e = N^T b`` (``xi_u`` is then fixed by the rest), up
        to the constant ``M^T b``. A record whose states are of size 1e9 (an
        unknown initial state, ``X0 = R^n``) gives rows of that size, consistent
        only to their ``b_err`` (1e-16 relative), on which HiGHS says
        "infeasible" under every setting; pivoted out, the rows are of the size of
        the increments and the solve is routine. Only the LP is solved this way:
        its multiplier ``y = M + N y_N`` (the reduced cost of ``e``) is certified
        on the stored data by :meth:`certify`, and its point is checked against
        the certified set.
        """
        unb = self._unb
        be = self.b_err
        if be is None:  # exact rows: minimize_within_b_err's other paths decide
            return None
        Au, Ab = self.A[:, unb], self.A[:, ~unb]
        Ur, Sr, Vr, N, xi0, r0, A2, b2, pos = self._free_pivot()
        wu = w[unb]
        with np.errstate(over="ignore", invalid="ignore"):
            M = Ur @ ((Vr.T @ wu) / Sr)
        if not np.isfinite(M).all():  # (singular values beyond double precision)
            return None
        # w_u outside the row space of A_u: unbounded below (the other paths decide)
        if np.abs(Au.T @ M - wu).max(initial=0.0) > 1e3 * np.finfo(np.float64).eps * float(
                (np.abs(wu) + np.abs(Au).T @ np.abs(M)).max(initial=0.0)):
            return None
        hb = self.h[~unb]
        w2 = np.concatenate([w[~unb] - Ab.T @ M, M[pos] * be[pos]])
        ones = np.ones(int(pos.sum()))
        scale = self.objective_scale(w2)
        hs = highs.new_model()
        if not highs.pass_dense(hs, A2, np.concatenate([-hb, -ones]), np.concatenate([hb, ones]),
                                b2, b2, w2 / scale):
            return None
        if highs.solve(hs) != "optimal":
            return None
        sol = hs.getSolution()
        y = M + N @ (np.asarray(sol.row_dual, dtype=np.float64) * scale)
        col = np.asarray(sol.col_value, dtype=np.float64)
        x = np.empty(self.n_g)
        x[~unb] = col[:hb.size]
        e = np.zeros(self.n_c)
        e[pos] = col[hb.size:] * be[pos]
        x[unb] = xi0 + Vr @ ((Ur.T @ (r0 + e - Ab @ x[~unb])) / Sr)
        return self._decided_within_b_err(w, w_err, w_pair, y, x)

    def _free_pivot(self):
        """The objective-independent parts of :meth:`_within_b_err_reduced`, computed
        once per polytope: ``A_u = U_r S_r V_r^T`` (numerical rank ``r``), the left
        null space ``N``, the centre ``xi_0`` and its residual ``r_0``, the reduced
        rows ``[N^T A_b, -N^T diag(b_err)]`` and right-hand side ``N^T r_0``, and the
        rows with ``b_err > 0``."""
        if self._pivot is None:
            unb, be = self._unb, self.b_err
            Au, Ab = self.A[:, unb], self.A[:, ~unb]
            U, S, Vt = np.linalg.svd(Au)
            eps = np.finfo(np.float64).eps
            r = int(np.count_nonzero(S > S[0] * max(Au.shape) * eps)) if S[0] > 0 else 0
            Ur, Vr, Sr, N = U[:, :r], Vt[:r].T, S[:r], U[:, r:]
            # Centred at the least-squares point xi_0 of A_u xi_u = b (refined, residual
            # correctly rounded): N^T A_u is zero only to rounding, and times xi_u ~ 1e11
            # that would shift the reduced rows by 1e-4; times xi_u - xi_0 it does not.
            xi0 = Vr @ ((Ur.T @ self.b) / Sr)
            for _ in range(2):
                r0 = _exact_residual(self.b, Au.T, xi0)
                xi0 = xi0 + Vr @ ((Ur.T @ r0) / Sr)
            r0 = _exact_residual(self.b, Au.T, xi0)
            pos = be > 0.0  # e_i = b_err_i t_i, |t_i| <= 1 (columns of the data's size)
            A2 = np.hstack([N.T @ Ab, -N.T[:, pos] * be[pos]])
            self._pivot = (Ur, Sr, Vr, N, xi0, r0, A2, N.T @ r0, pos)
        return self._pivot

    def point_is_feasible(self, x: NDArray[np.float64],
                          row_allowance: NDArray[np.float64] | None = None) -> bool:
        """Whether a solver's point satisfies ``A x = b`` and ``|x| <= h`` to
        ``PRIMAL_RESIDUAL_RTOL`` (row by row, relative to ``1 + |b_i| + |A_i| |x|``).

        Parameters
        ----------
        x : ndarray, shape (n_g,)
            The point.
        row_allowance : ndarray, shape (n_c,), optional
            Rows as intervals: ``|A x - b| <= row_allowance`` (``b_err``), to
            ``PRIMAL_RESIDUAL_RTOL`` relative to ``1 + |A_i| h`` over the bounded
            factors, plus the rounding of the evaluation.
        """
        if x.shape != (self.n_g,) or not np.isfinite(x).all():
            return False
        if self.n_c:
            resid = np.abs(self.A @ x - self.b)
            absAx = np.abs(self.A) @ np.abs(x)
            if row_allowance is None:
                tol = PRIMAL_RESIDUAL_RTOL * (1.0 + np.abs(self.b) + absAx)
            else:
                # Rows as intervals: the tolerance relative to the rows' bounded part
                # (the unbounded factors of an unknown initial state make |b| ~ 1e10,
                # and 1e-6 of that would hide anything), plus the rounding of
                # representing and evaluating A x - b.
                reach = np.abs(self.A[:, ~self._unb]) @ self.h[~self._unb]
                tol = row_allowance + PRIMAL_RESIDUAL_RTOL * (1.0 + reach) + 8.0 * gamma(
                    self.n_g + 2) * (absAx + np.abs(self.b))
            if (resid > tol).any():
                return False
        over = np.abs(x) - self.h
        return not (over > PRIMAL_RESIDUAL_RTOL * (1.0 + np.where(self._unb, 0.0, self.h))).any()

    def try_compiled(self, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                     w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None
                     ) -> LPResult | None:
        """Last retry: the compiled simplex of :mod:`setobs.lp.fastlp`, certified here.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        """
        from .fastlp import FixedStructureLP

        lp = FixedStructureLP(self.A, w[None, :], self._unb, self.unbounded_radius)
        if not lp.usable:
            return None
        bounds, ok, ys, objs = lp.minimize_all(self.b, self.h, b_err=self.b_err,
                                               return_duals=True)
        if not ok[0] or not np.isfinite(bounds[0]):
            return None
        bound = self.certify(w, ys[0], w_err, w_pair)
        if not np.isfinite(bound):
            return None
        return LPResult(bound, float(objs[0]), None, "optimal")

    def _compiled_relaxed(self, w, delta, w_err, w_pair) -> LPResult | None:
        """The relaxed LP by the compiled simplex: slack factors ``|s| <= delta`` turn
        ``|A xi - b| <= delta`` into ``A xi + s = b``, a fixed-structure LP."""
        from .fastlp import FixedStructureLP

        A2 = np.hstack([self.A, np.eye(self.n_c)])
        h2 = np.concatenate([self.h, delta])
        w2 = np.concatenate([w, np.zeros(self.n_c)])
        lp = FixedStructureLP(A2, w2[None, :], np.isinf(h2), self.unbounded_radius)
        if not lp.usable:
            return None
        bounds, ok, ys, objs = lp.minimize_all(self.b, h2, b_err=self.b_err,
                                               return_duals=True)
        if not ok[0] or not np.isfinite(bounds[0]):
            return None
        werr2 = None if w_err is None else np.concatenate([w_err, np.zeros(self.n_c)])
        pair2 = None if w_pair is None else (
            np.hstack([w_pair[0], np.zeros((w_pair[0].shape[0], self.n_c))]), w_pair[1])
        bound, _ = _certificate.lagrangian_lower_bound(w2, A2, self.b, h2, ys[0], w_err=werr2,
                                          unbounded_radius=self.unbounded_radius, w_pair=pair2,
                                          b_err=self.b_err)
        if not np.isfinite(bound):
            return None
        return LPResult(bound, float(objs[0]), None, "optimal")

    @_blas_unless_small
    @_quiet_overflow
    def minimize_relaxed(
        self,
        w: NDArray[np.float64],
        w_err: NDArray[np.float64] | None = None,
        w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    ) -> LPResult:
        """Certified ``min w^T xi`` with the rows relaxed to ``|A xi - b| <= delta``.

        Used when the set is not certified empty but the exact LP is infeasible
        or its certified bounds cross: the relaxed feasible set contains every
        point that satisfies the normalised constraints within the emptiness
        tolerance, so its certified bound is an outer bound in the sense of
        :meth:`emptiness` (and a valid bound for the exact set). If the relaxed
        LP does not solve either, the ``"fallback"`` answer of :meth:`minimize`
        is returned.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        """
        with self._lock:
            rep = self.emptiness()
            found = rep.violation_found if np.isfinite(rep.violation_found) else 1.0
            delta = self._row_scale() * max(2.0 * found, 2.0 * rep.tol)
            scale = self.objective_scale(w)
            y: NDArray[np.float64] | None = None
            x: NDArray[np.float64] | None = None
            for options in (None, *highs.RETRY_SETTINGS):
                hs = self._build(self.b - delta, self.b + delta, w / scale, options)
                if hs is None:
                    continue
                hs.run()
                st = highs.status(hs)
                if st == "unbounded":
                    return LPResult(-np.inf, -np.inf, None, "unbounded")
                if st == "optimal":
                    y = np.asarray(hs.getSolution().row_dual, dtype=np.float64) * scale
                    x = np.asarray(hs.getSolution().col_value, dtype=np.float64)
                    break
            if y is None:
                out = self._compiled_relaxed(w, delta, w_err, w_pair)
                if out is not None:
                    return out
                self.fallbacks += 1
                y, x = np.zeros(self.n_c), None
            bound, y = self._certify(w, y, w_err, w_pair)
            obj = float(w @ x) if x is not None else np.nan
            status = "optimal" if x is not None else "fallback"
            if np.isinf(bound):
                return LPResult(-np.inf, obj, x, "unbounded" if x is not None else status)
            # Relaxed rows |A xi - b| <= delta add -sum |y_i| delta_i to the bound.
            relax = float(np.abs(y) @ delta) * (1.0 + 2.0 * gamma(self.n_c + 1))
            return LPResult(round_down(bound - relax), obj, x, status)

    def _row_scale(self) -> NDArray[np.float64]:
        """Power-of-two row scales (so that scaling is exact in floating point); 1 for a
        row whose ``b_err`` would exceed ``MAX_MAGNITUDE`` once scaled (see
        :func:`equilibration`)."""
        s = np.maximum(np.abs(self.A).max(axis=1, initial=0.0), np.abs(self.b))
        m, e = np.frexp(np.where(s > 0.0, s, 1.0))
        s = np.ldexp(1.0, np.where(m == 0.5, e - 1, e))
        if self.b_err is not None:
            s = np.where(self.b_err > MAX_MAGNITUDE * np.minimum(s, 1.0), 1.0, s)
        return s

    @_blas_unless_small
    @_quiet_overflow
    def emptiness(self, tol: float = FEASIBILITY_TOL) -> EmptinessReport:
        """Certified emptiness test with a phase-1 LP.

        Solves ``min sum(s+ + s-)`` subject to ``D(A xi - b) + s+ - s- = 0``,
        ``|xi| <= h``, ``s+-  >= 0``, with ``D`` scaling each row to unit
        infinity norm. For any multiplier ``y``, ``L(y) / ||y||_1`` (with
        ``L`` the Lagrangian bound of the zero objective, covering ``b_err``)
        is a certified lower bound on the smallest infinity-norm violation of
        the normalised rows.

        Parameters
        ----------
        tol : float
            The set is reported empty only if that lower bound exceeds ``tol``.

        Notes
        -----
        If the phase-1 LP does not solve under any setting, the set is reported
        non-empty (``violation_lower_bound = 0``, ``violation_found = nan``):
        the conservative answer.
        """
        with self._lock:
            if tol in self._emptiness:
                return self._emptiness[tol]
            rep = self._phase1(tol)
            self._emptiness[tol] = rep
            return rep

    def _phase1_highs(self, As: NDArray[np.float64], bs: NDArray[np.float64]
                      ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """``(y, xi)`` of the phase-1 LP by HiGHS (with retries), or ``None``."""
        n_c, n_g = self.n_c, self.n_g
        lo, up = self._col_bounds()
        big = np.hstack([As, np.eye(n_c), -np.eye(n_c)])
        lo_c = np.concatenate([lo, np.zeros(2 * n_c)])
        up_c = np.concatenate([up, np.full(2 * n_c, _INF)])
        cost = np.concatenate([np.zeros(n_g), np.ones(2 * n_c)])
        for options in (None, *highs.RETRY_SETTINGS):
            hs = highs.new_model(options)
            if not highs.pass_dense(hs, big, lo_c, up_c, bs, bs, cost):
                continue
            hs.run()
            if highs.status(hs) == "optimal":
                sol = hs.getSolution()
                return (np.asarray(sol.row_dual, dtype=np.float64),
                        np.asarray(sol.col_value, dtype=np.float64)[:n_g])
        return None

    def _phase1(self, tol: float) -> EmptinessReport:
        if self.n_c == 0:
            return EmptinessReport(False, 0.0, 0.0, tol, np.zeros(self.n_g))
        if not self._any_unb and self.n_c <= COMPILED_MAX_ROWS:
            # every bound finite: the compiled phase 1, scaled and certified in one call
            code, lower_inf, found, xc = _simplex.emptiness(
                self.A, self.b, self.h, np.zeros(self.n_c) if self.b_err is None else self.b_err,
                self.unbounded_radius, 50 * (self.n_c + self.n_g))
            if code == _simplex.OPTIMAL:
                empty = bool(lower_inf > tol)
                # undecided (no certificate above tol, no point within it): HiGHS decides
                if empty or found <= tol:
                    return EmptinessReport(empty, float(lower_inf), float(found), tol,
                                           None if empty else xc)
        scale = self._row_scale()
        As = self.A / scale[:, None]
        bs = self.b / scale
        solved = self._phase1_highs(As, bs)
        if solved is None:
            self.fallbacks += 1
            return EmptinessReport(False, 0.0, np.nan, tol)
        return self._phase1_report(As, bs, scale, *solved, tol)

    def _phase1_report(self, As, bs, scale, y, x, tol: float) -> EmptinessReport:
        """The certified verdict of a phase-1 solution ``(y, x)`` (scaled rows)."""
        n_c, n_g = self.n_c, self.n_g
        # Certified bound with the scaled data (exact: power-of-two scales); the
        # objective is zero in xi, so L(y) <= ||y||_1 * min ||As xi - bs||_inf.
        lower, y = _certificate.lagrangian_lower_bound(
            np.zeros(n_g), As, bs, self.h, y, unbounded_radius=self.unbounded_radius,
            unbounded_pinv=np.linalg.pinv(As[:, self._unb].T) if self._any_unb else None,
            b_err=None if self.b_err is None else self.b_err / scale,
        )
        norm1 = float(np.abs(y).sum()) * (1.0 + 2.0 * gamma(n_c + 1))
        if norm1 > 0.0 and np.isfinite(lower) and lower > 0.0:
            lower_inf = round_down(lower / norm1)
        else:
            lower_inf = 0.0  # no positive certificate
        xc = np.clip(x, -self.h, self.h)
        found = float(np.abs(As @ xc - bs).max())
        empty = bool(lower_inf > tol)
        return EmptinessReport(empty, lower_inf, found, tol, None if empty else xc)
