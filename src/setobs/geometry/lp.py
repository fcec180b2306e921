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
The bound then holds for every point of ``F`` with ``|xi_j| <= unbounded_radius`` on the
unbounded factors (the term ``unbounded_radius * (|r_j| + err_j)`` is added); when the
relative residual stays above ``UNBOUNDED_REDUCED_COST_TOL`` the objective is
declared unbounded below (``-inf``), which is always an outer answer.

Whether the residual counts as negligible is decided relative to the size of
the whole reduced-cost computation (``max_j |w_j| + |A_j|^T |y|``), not to the
unbounded column itself: a column of rounding-level entries (``1e-16`` where
a model has a structural zero) is then as well determined as any other.

A right-hand side known only to within ``|b - b_stored| <= b_err`` (rounding
of the operations that formed it, representation error of measured data) is
covered by the term ``sum_i |y_i| b_err_i``: the bound then holds for every
such ``b``.

Infeasibility reported by the solver is never trusted either: emptiness is
decided by a phase-1 LP whose dual gives a certified lower bound on the
smallest constraint violation (see :meth:`FactorPolytope.emptiness`).

A solver's bad day never aborts a query: an undecided HiGHS status is retried
with other settings (a fresh unscaled model, default tolerances with the
primal simplex, the interior-point method with crossover, a restart with the
objective perturbed -- certified for the true one), with the compiled simplex of
:mod:`setobs.geometry.fastlp`, and with the rows as the intervals
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

import numpy as np
from numpy.typing import NDArray

from .._blas import with_single_threaded_blas_unless_small
from .._lazy import lazy_module
from .._rounding import UNIT_ROUNDOFF, exact_dot, gamma, round_down, two_prod
from ..exceptions import EmptySetError
from ..tolerances import (
    FASTLP_GAP_RTOL,
    FEASIBILITY_TOL,
    LP_REFINE_GAP,
    MAX_MAGNITUDE,
    PRIMAL_RESIDUAL_RTOL,
    RELAXED_EXACT_GAP,
    UNBOUNDED_RADIUS,
    UNBOUNDED_REDUCED_COST_TOL,
)

__all__ = ["EmptinessReport", "FactorPolytope", "LPResult", "lagrangian_lower_bound"]

_TINY = np.finfo(np.float64).tiny
_INF = math.inf  # HiGHS's kHighsInf

# HiGHS loads on the first LP, not on ``import setobs``.
highspy = lazy_module("highspy")
# the compiled simplex (numba): compiles or loads on the first compiled query
_simplex = lazy_module("setobs.geometry._simplex")


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
        neg.extend(two_prod(A, y))
    pos = list(two_prod(*w_pair)) if w_pair is not None else []
    out = np.empty(w.size)
    for j in range(w.size):
        terms = [] if w_pair is not None else [w[j]]
        for block in pos:
            terms.extend(block[:, j].tolist())
        for block in neg:
            terms.extend((-block[:, j]).tolist())
        try:
            out[j] = math.fsum(terms)
        except (ValueError, OverflowError):  # (inf - inf: beyond double precision)
            out[j] = np.nan  # (the callers then certify nothing: -inf)
    return out


@np.errstate(over="ignore", invalid="ignore")  # (an overflow gives -inf or NaN: see the end)
def lagrangian_lower_bound(
    w: NDArray[np.float64],
    A: NDArray[np.float64],
    b: NDArray[np.float64],
    h: NDArray[np.float64],
    y: NDArray[np.float64],
    *,
    w_err: NDArray[np.float64] | None = None,
    unbounded_radius: float = UNBOUNDED_RADIUS,
    unbounded_pinv: NDArray[np.float64] | None = None,
    w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
    b_err: NDArray[np.float64] | None = None,
    exact_residual: bool = False,
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
    unbounded_radius : float
        Radius on unbounded factors (see module notes).
    unbounded_pinv : ndarray, optional
        ``pinv(A[:, unbounded].T)``, used to refine ``y``; computed if omitted.
    w_pair : (M, v), optional
        When ``w`` was computed as ``M^T v``, the exact objective on unbounded
        columns is taken from ``(M[:, unbounded], v)`` (no rounding of ``w``
        enters the radius term).
    b_err : ndarray, optional
        Elementwise bound on the uncertainty of ``b``: the bound then holds for
        every right-hand side within ``b +- b_err``.
    exact_residual : bool
        Evaluate every reduced cost ``r = w - A^T y`` correctly rounded (exact
        products, :func:`math.fsum`; ``O(n_c n_g)`` Python work) instead of with
        the forward error bound ``gamma(2 n_c + 2) (|w| + |A|^T |y|)``. With
        duals of size 1e4 the latter alone opened a gap of 2e-6 on an optimal
        basis (``y^T b`` and ``sum h |r|`` both 2e4, cancelling to 0.87).

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
    that the radius term is negligible. ``y^T b`` is evaluated exactly and
    rounded once, so that a large right-hand side (measurements of size
    ``1e8`` whose differences carry the information) costs no accuracy.
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
        with np.errstate(over="ignore", invalid="ignore"):
            for _ in range(2):
                y1 = y1 + unbounded_pinv @ (wu - Au.T @ y1)
        if not np.isfinite(y1).all():
            # (a pseudo-inverse beyond double precision: data of extreme dynamic
            # range) no refinement, no bound: -inf is certified
            return -np.inf, np.array(y, dtype=np.float64)
        ru = _exact_residual(wu, Au, [y1, y2], pair)
        for _ in range(2):
            if not ru.any():
                break
            with np.errstate(over="ignore", invalid="ignore"):
                y2 = y2 + unbounded_pinv @ ru
            if not np.isfinite(y2).all():
                return -np.inf, y1
            ru = _exact_residual(wu, Au, [y1, y2], pair)
    elif unb.any():
        ru = w[unb] if w_pair is None else _exact_residual(
            w[unb], np.zeros((0, int(unb.sum()))), [], (w_pair[0][:, unb], w_pair[1]))
    abs_y = np.abs(y1) + np.abs(y2)
    scale_r = np.abs(w) + (np.abs(A).T @ abs_y if n_c else 0.0)
    if exact_residual and n_c:
        # correctly rounded: |true - r| <= u |r| / (1 - u), plus an underflow guard
        r = _exact_residual(w, A, [y1, y2], w_pair)
        err_r = 2.0 * UNIT_ROUNDOFF * np.abs(r) + 2.0 * (2 * n_c + 1) * _TINY
        if w_err is not None and w_pair is None:
            err_r = err_r + w_err * (1.0 + 4.0 * UNIT_ROUNDOFF)
    else:
        r = w - A.T @ y1 - A.T @ y2 if n_c else w.copy()
        err_r = 2.0 * gamma(2 * n_c + 2) * scale_r
        if w_err is not None:
            err_r = err_r + w_err * (1.0 + 4.0 * UNIT_ROUNDOFF)
    bound_r = np.abs(r) + err_r
    t2 = 0.0
    if unb.any():
        # Correctly rounded residual: |true| <= |ru| / (1 - u), plus an underflow guard.
        ru_bound = np.abs(ru) / (1.0 - UNIT_ROUNDOFF) + 2.0 * (2 * n_c + 1) * _TINY
        if w_err is not None and w_pair is None:
            ru_bound = ru_bound + w_err[unb] * (1.0 + 4.0 * UNIT_ROUNDOFF)
        # Negligible relative to the whole reduced-cost computation (norm-wise),
        # not to the unbounded column alone.
        scale_all = max(float(scale_r.max(initial=0.0)), _TINY)
        rel = (ru_bound - 2.0 * (2 * n_c + 1) * _TINY) / scale_all
        if (rel > UNBOUNDED_REDUCED_COST_TOL).any():
            return -np.inf, y1
        t2 += unbounded_radius * float(ru_bound.sum()) * (1.0 + gamma(ru_bound.size + 1))
    fin = ~unb
    t2 += float(h[fin] @ bound_r[fin])
    # t1 = y^T b correctly rounded (|error| <= u |t1|, plus an underflow guard)
    try:
        t1 = exact_dot([y1, y2], b) if n_c else 0.0
    except (ValueError, OverflowError):  # (inf - inf: products beyond double precision)
        return -np.inf, y1 + y2
    tb = 0.0
    if b_err is not None and n_c:
        tb = float(abs_y @ b_err) * (1.0 + gamma(n_c + 2))
    err = UNIT_ROUNDOFF * abs(t1) + 2.0 * (
        gamma(n_g + 3) * t2
        + UNIT_ROUNDOFF * (abs(t1) + t2 + tb)
        + 4.0 * (2 * n_c + 1) * _TINY
    )
    bound = round_down(t1 - t2 - tb - err)
    if np.isnan(bound):  # (inf - inf of data beyond double precision: nothing certified)
        bound = -np.inf
    return bound, y1 + y2


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


def _simplex_limit(n_rows: int, n_cols: int) -> int:
    """Simplex iteration limit of a HiGHS solve: generous for a healthy LP of this size."""
    return 50 * (n_rows + n_cols) + 10_000


def _option(hs: highspy.Highs, name: str) -> int:
    """An integer HiGHS option (``getOptionValue`` returns ``(status, value)`` in
    recent highspy releases and the value alone in older ones)."""
    v = hs.getOptionValue(name)
    return int(v[1] if isinstance(v, tuple) else v)


def _status_name(h: highspy.Highs) -> str:
    return h.modelStatusToString(h.getModelStatus())


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
        Bound on the uncertainty of ``b`` (see :func:`lagrangian_lower_bound`);
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
        self._pivot: tuple | None = None  # (see _free_pivot)
        self._model: highspy.Highs | None = None
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
    @staticmethod
    def new_highs() -> highspy.Highs:
        # highspy's Python class (1.8+) registers its logging callback in __init__,
        # and HiGHS prints its banner on stdout right there, before any option can
        # be set; the compiled class underneath prints nothing and is all we use.
        hs = getattr(highspy, "_Highs", highspy.Highs)()
        hs.setOptionValue("output_flag", False)
        hs.setOptionValue("presolve", "off")
        # No "threads" option: HiGHS keeps one task scheduler per calling thread, sized
        # by the first solve in that thread, and every later model whose "threads"
        # differs fails in run() with an error status ("Not Set"). With threads = 1
        # here, any earlier HiGHS solve at the default size in the same thread (the
        # old calibration LP, a user's own model, cvxpy's HiGHS) turned every SMFDO LP
        # into a retry chain ending in "fallback", and records that contradicted
        # the model were never invalidated. The default (0)
        # accepts any scheduler; the LPs here run the serial dual simplex anyway.
        # Tighter than HiGHS's 1e-7 defaults: with them the certified bound sat up
        # to ~1e-6 (relative) below the optimum on SMFDO sets with constrained
        # increment sets (the solver's point was infeasible by ~1e-7); with 1e-10
        # it agrees with the compiled fast path to 1e-8 (tests/geometry/test_fastlp.py).
        hs.setOptionValue("primal_feasibility_tolerance", 1e-10)
        hs.setOptionValue("dual_feasibility_tolerance", 1e-10)
        return hs

    @staticmethod
    def pass_model(hs: highspy.Highs, A: NDArray[np.float64], lo_c, up_c, lo_r, up_r, cost) -> bool:
        """Pass ``min cost^T x, lo_r <= A x <= up_r, lo_c <= x <= up_c`` (dense ``A``) to the
        HiGHS model ``hs``, with the library's iteration limits; ``False`` if HiGHS
        rejects the model.

        Parameters
        ----------
        hs : highspy.Highs
            A model from :meth:`new_highs`.
        A : ndarray, shape (m, n)
            Constraint matrix.
        lo_c, up_c : ndarray, shape (n,)
            Column bounds.
        lo_r, up_r : ndarray, shape (m,)
            Row bounds.
        cost : ndarray, shape (n,)
            Objective.
        """
        # Never NaN (or an infinite cost) into HiGHS: it looped for minutes on such a
        # model, past its own time limit (a NaN objective from a pseudo-inverse of
        # data of extreme dynamic range). The model is refused: the caller's retries
        # and certified fallback take over.
        if not (np.isfinite(A).all() and np.isfinite(cost).all()) or any(
                np.isnan(v).any() for v in (lo_c, up_c, lo_r, up_r)):
            return False
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
        # Deterministic iteration limits (a degenerate LP once cycled for minutes):
        # a solve that hits them is undecided, and the retries / fallback take over.
        hs.setOptionValue("simplex_iteration_limit",
                          min(_simplex_limit(n_r, n_col), _option(hs, "simplex_iteration_limit")))
        hs.setOptionValue("ipm_iteration_limit", min(1000, _option(hs, "ipm_iteration_limit")))
        return hs.passModel(lp) != highspy.HighsStatus.kError

    def _col_bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        up = np.where(self._unb, _INF, self.h)
        return -up, up

    #: Settings of the retries after an undecided status (see the module notes).
    _RETRIES: tuple[dict[str, object], ...] = (
        {"simplex_strategy": 1, "simplex_scale_strategy": 0},
        {"simplex_strategy": 4, "primal_feasibility_tolerance": 1e-7,
         "dual_feasibility_tolerance": 1e-7},
        {"solver": "ipm", "run_crossover": "on"},
    )
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
               ) -> highspy.Highs | None:
        """A HiGHS model of ``min cost^T xi, row_lo <= A xi <= row_hi, |xi| <= h``."""
        hs = self.new_highs()
        hs.setOptionValue("simplex_strategy", 1)  # dual simplex (measured faster)
        for key, val in (options or {}).items():
            hs.setOptionValue(key, val)
        lo, up = self._col_bounds()
        return hs if self.pass_model(hs, self.A, lo, up, row_lo, row_hi, cost) else None

    def highs_model(self) -> highspy.Highs | None:
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
            ``w`` was computed as ``M^T v`` (see :func:`lagrangian_lower_bound`).
        exact_residual : bool
            Reduced costs correctly rounded (see :func:`lagrangian_lower_bound`).
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
        y_ref = self._basis_duals(hs, w)
        if y_ref is not None:
            b_ref = self.certify(w, y_ref, w_err, w_pair)
            if b_ref > bound:
                return b_ref, y_ref
        return bound, y

    def _certify(self, w, y, w_err=None, w_pair=None, exact_residual=False
                 ) -> tuple[float, NDArray[np.float64]]:
        return lagrangian_lower_bound(
            w, self.A, self.b, self.h, y, w_err=w_err, unbounded_radius=self.unbounded_radius,
            unbounded_pinv=self._pinv() if self._any_unb else None, w_pair=w_pair,
            exact_residual=exact_residual,
            b_err=self.b_err,
        )

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

    def solve_objective(self, hs: highspy.Highs, w: NDArray[np.float64], scale: float):
        """Run HiGHS on objective ``w / scale``; return its model status.

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
        return hs.getModelStatus()

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
            ``w`` was computed as ``M^T v`` (see :func:`lagrangian_lower_bound`).

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
        """
        w = np.asarray(w, dtype=np.float64)
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
            ``w`` was computed as ``M^T v`` (see :func:`lagrangian_lower_bound`).
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
        attempts = [None, *self._RETRIES, "perturbed"]
        for i, options in enumerate(attempts):
            perturbed = options == "perturbed"
            hs = self.highs_model() if i == 0 else self._build(
                self.b, self.b, np.zeros(self.n_g), None if perturbed else options)
            if hs is None:
                continue
            st = self.solve_objective(hs, self.perturbed_objective(w) if perturbed else w, scale)
            if perturbed and st == highspy.HighsModelStatus.kUnbounded:
                continue  # (says nothing about the true objective)
            if st == highspy.HighsModelStatus.kOptimal:
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
            if st == highspy.HighsModelStatus.kUnbounded:
                return LPResult(-np.inf, -np.inf, None, "unbounded")
            if st in (highspy.HighsModelStatus.kInfeasible,
                      highspy.HighsModelStatus.kUnboundedOrInfeasible):
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
    def minimize_many(self, W: NDArray[np.float64]
                      ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """Certified lower bounds of ``min W[i]^T xi`` for all ``i`` by the compiled
        simplex (:meth:`FixedStructureLP.bounded <setobs.geometry.fastlp.FixedStructureLP.bounded>`:
        one dual simplex warm from the previous objective's basis, each multiplier
        certified like the HiGHS path's). For polytopes with every bound finite and
        1 to :data:`COMPILED_MAX_ROWS` rows; elsewhere nothing is solved.

        Parameters
        ----------
        W : ndarray, shape (n_lp, n_g)
            Objectives (exact: no rounding error to carry).

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
                return lp.minimize_all(self.b, np.concatenate([self.h, np.zeros(self.n_c)]))
            bounds, ok, ys, objs = lp.minimize_all(
                self.b, np.concatenate([self.h, np.zeros(self.n_c)]), b_err=self.b_err,
                return_duals=True)
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
            ``w`` was computed as ``M^T v`` (see :func:`lagrangian_lower_bound`).
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
        for options in (None, *self._RETRIES):
            hs = self._build(self.b - be, self.b + be, np.zeros(self.n_g), options)
            if hs is None or self.solve_objective(hs, w, scale) != \
                    highspy.HighsModelStatus.kOptimal:
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
        hs = self.new_highs()
        hs.setOptionValue("simplex_strategy", 1)
        if not self.pass_model(hs, A2, np.concatenate([-hb, -ones]), np.concatenate([hb, ones]),
                          b2, b2, w2 / scale):
            return None
        hs.run()
        if hs.getModelStatus() != highspy.HighsModelStatus.kOptimal:
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
                r0 = _exact_residual(self.b, Au.T, [xi0])
                xi0 = xi0 + Vr @ ((Ur.T @ r0) / Sr)
            r0 = _exact_residual(self.b, Au.T, [xi0])
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
        """Last retry: the compiled simplex of :mod:`setobs.geometry.fastlp`, certified here.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :func:`lagrangian_lower_bound`).
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
        bound, _ = lagrangian_lower_bound(w2, A2, self.b, h2, ys[0], w_err=werr2,
                                          unbounded_radius=self.unbounded_radius, w_pair=pair2,
                                          b_err=self.b_err)
        if not np.isfinite(bound):
            return None
        return LPResult(bound, float(objs[0]), None, "optimal")

    def _basis_duals(self, hs: highspy.Highs, w: NDArray[np.float64]) -> NDArray[np.float64] | None:
        """Duals recomputed from HiGHS's optimal basis, refined in extended precision.

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
            # Iterative refinement with residuals in extended precision (long
            # double where the platform has it): the duals of the basis to
            # working precision, also on ill-conditioned bases.
            Ml, wl = M.astype(np.longdouble), w[bc].astype(np.longdouble)
            for _ in range(3):
                r = np.asarray(wl - Ml @ yn.astype(np.longdouble), dtype=np.float64)
                if not r.any():
                    break
                yn = yn + np.linalg.solve(M, r)
        except np.linalg.LinAlgError:
            return None
        y = np.zeros(self.n_c)
        y[nbr] = yn
        return y

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
            ``w`` was computed as ``M^T v`` (see :func:`lagrangian_lower_bound`).
        """
        with self._lock:
            rep = self.emptiness()
            found = rep.violation_found if np.isfinite(rep.violation_found) else 1.0
            delta = self._row_scale() * max(2.0 * found, 2.0 * rep.tol)
            scale = self.objective_scale(w)
            y = None
            for options in (None, *self._RETRIES):
                hs = self._build(self.b - delta, self.b + delta, w / scale, options)
                if hs is None:
                    continue
                hs.run()
                st = hs.getModelStatus()
                if st == highspy.HighsModelStatus.kUnbounded:
                    return LPResult(-np.inf, -np.inf, None, "unbounded")
                if st == highspy.HighsModelStatus.kOptimal:
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
        for options in ({"simplex_strategy": 1}, *self._RETRIES):
            hs = self.new_highs()
            for key, val in options.items():
                hs.setOptionValue(key, val)
            if not self.pass_model(hs, big, lo_c, up_c, bs, bs, cost):
                continue
            hs.run()
            if hs.getModelStatus() == highspy.HighsModelStatus.kOptimal:
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
        lower, y = lagrangian_lower_bound(
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
