"""The factor polytope (:class:`FactorPolytope`): its data, its HiGHS model and
certificates, and the one entry point of its queries; the jobs behind them are one file
each (:mod:`setobs.lp.factor`)."""

from __future__ import annotations

import functools
import threading
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..._blas import with_single_threaded_blas_unless_small
from ..._lazy import lazy_module
from ..._rounding import gamma
from ...exceptions import DimensionError
from ...tolerances import (
    FEASIBILITY_TOL,
    PRIMAL_RESIDUAL_RTOL,
    RELAXED_EXACT_GAP,
    UNBOUNDED_RADIUS,
)
from .. import highs
from ._compiled import compiled_batch, compiled_retry
from ._interval_rows import free_pivot, within_b_err
from ._ladder import highs_ladder
from ._phase1 import phase1, relaxed_rows
from ._reports import EmptinessReport, LPResult
from ._scaling import equilibration, row_scale

if TYPE_CHECKING:
    from highspy import Highs as HighsModel

__all__ = ["FactorPolytope"]

_INF = np.inf  # HiGHS's kHighsInf

# the one certificate (compiled; loads with the first certified bound)
_certificate = lazy_module("setobs.lp.certificate")


#: The LP queries on sets whose data span double precision's range (entries from 1e-300
#: to 1e150 in one set) overflow in pseudo-inverses and multiplier products; every such
#: result is guarded (a non-finite model never reaches HiGHS, a NaN certificate is
#: -inf, a non-finite reduction declines the compiled path), so the queries answer with
#: a certified, wider bound, without numpy's overflow warnings.
def _quiet_overflow(func):
    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        # (a fresh errstate per call: one instance cannot be entered twice, nor
        # shared by threads)
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            return func(*args, **kwargs)
    return wrapper


def _polytope_size(fp: FactorPolytope) -> int:
    """Largest dimension of a factor polytope's matrices (the phase-1 LP's ``2 n_c``
    extra columns are identities: its products stay below OpenBLAS's thresholds)."""
    return max(fp.n_g, fp.n_c)


_blas_unless_small = with_single_threaded_blas_unless_small(_polytope_size)


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
    the primal simplex at every size (development runs, not in a results file),
    although only the objective changes.
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
        #: the unbounded factors (``h_j = inf``), and whether there is one
        self.unbounded = np.isinf(h)
        self.any_unbounded = bool(np.count_nonzero(self.unbounded))
        self._unb_pinv: NDArray[np.float64] | None = None
        self._csc: tuple | None = None  # (A column by column, for the certificate)
        self._neg_h = -h
        self._pivot: tuple | None = None  # (see pivot)
        self._model: HighsModel | None = None
        self._emptiness: dict[float, EmptinessReport] = {}
        #: the lock of the queries (the HiGHS model is stateful)
        self.lock = threading.RLock()
        self.fallbacks = 0

    def __getstate__(self) -> dict:
        # HiGHS models and locks do not pickle; they are rebuilt on demand.
        state = self.__dict__.copy()
        state["_model"] = None
        del state["lock"]
        return state

    def __setstate__(self, state: dict) -> None:
        self.__dict__.update(state)
        self.lock = threading.RLock()

    # -- model construction ------------------------------------------------
    def col_bounds(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The factors' bounds ``-h``, ``h`` (HiGHS's infinity where unbounded)."""
        up = np.where(self.unbounded, _INF, self.h)
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
        return w + np.where(self.unbounded, 0.0, self.PERTURBATION * max(mag, 1e-300) * u)

    def build(self, row_lo, row_hi, cost, options: dict[str, object] | None = None
               ) -> HighsModel | None:
        """A HiGHS model of ``min cost^T xi, row_lo <= A xi <= row_hi, |xi| <= h`` (``None``
        when HiGHS refuses its data).

        Parameters
        ----------
        row_lo, row_hi : ndarray, shape (n_c,)
            The rows' bounds.
        cost : ndarray, shape (n_g,)
            The objective.
        options : dict, optional
            HiGHS options (:data:`setobs.lp.highs.RETRY_SETTINGS`).
        """
        hs = highs.new_model(options)
        lo, up = self.col_bounds()
        return hs if highs.pass_dense(hs, self.A, lo, up, row_lo, row_hi, cost) else None

    def highs_model(self) -> HighsModel | None:
        """The polytope's reusable HiGHS model (built on first use)."""
        if self._model is None:
            self._model = self.build(self.b, self.b, np.zeros(self.n_g))
        return self._model

    def _pinv(self) -> NDArray[np.float64]:
        pinv = self._unb_pinv
        if pinv is None:
            Au = self.A[:, self.unbounded]
            pinv = np.asarray(np.linalg.pinv(Au.T) if self.n_c else np.zeros((0, Au.shape[1])),
                              dtype=np.float64)
            self._unb_pinv = pinv
        return pinv

    # -- certificates ------------------------------------------------------
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
        return self.certify_with(w, y, w_err, w_pair, exact_residual)[0]

    def tightened(self, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                  w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None,
                  hs: HighsModel | None, y: NDArray[np.float64], bound: float, obj: float,
                  rtol: float) -> float:
        """``bound`` (from multiplier ``y``) certified again while its gap to the
        solver's objective ``obj`` exceeds ``rtol`` (relative to ``1 + |obj|``): from
        the duals of the optimal basis of ``hs`` (refined in extended precision;
        skipped when ``hs`` is ``None``), then, above :data:`RELAXED_EXACT_GAP`, with
        every reduced cost correctly rounded (the forward error bound of
        ``w - A^T y`` grows with ``|y|``, and duals of 1e4 once opened a gap of 2e-6
        by that term alone).

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        w_err : ndarray or None
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v) or None
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        hs : highspy.Highs or None
            The model whose optimal basis gives refined duals.
        y : ndarray, shape (n_c,)
            The multiplier ``bound`` comes from.
        bound : float
            Its certified bound.
        obj : float
            The solver's objective value.
        rtol : float
            The gap (relative to ``1 + |obj|``) below which ``bound`` is kept.
        """
        gap_tol = 1.0 + abs(obj)
        if not np.isfinite(bound) or obj - bound <= rtol * gap_tol:
            return bound
        if hs is not None:
            bound, y = self.basis_bound(w, w_err, w_pair, hs, y, bound)
        if obj - bound > RELAXED_EXACT_GAP * gap_tol:
            bound = max(bound, self.certify(w, y, w_err, w_pair, exact_residual=True))
        return bound

    def basis_bound(self, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                    w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None,
                    hs: HighsModel, y: NDArray[np.float64], bound: float
                    ) -> tuple[float, NDArray[np.float64]]:
        """``(bound, y)``, or the certified bound of the duals of the optimal basis of
        ``hs`` (refined in extended precision) with those duals, when it is higher.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        w_err : ndarray or None
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v) or None
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        hs : highspy.Highs
            A model of this polytope at an optimal basis.
        y : ndarray, shape (n_c,)
            The multiplier ``bound`` comes from.
        bound : float
            Its certified bound.
        """
        y_ref = highs.basis_duals(hs, self.A, w)
        if y_ref is not None:
            b_ref = self.certify(w, y_ref, w_err, w_pair)
            if b_ref > bound:
                return b_ref, y_ref
        return bound, y

    def certify_with(self, w: NDArray[np.float64], y: NDArray[np.float64],
                     w_err: NDArray[np.float64] | None = None,
                     w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None = None,
                     exact_residual: bool = False) -> tuple[float, NDArray[np.float64]]:
        """:meth:`certify`'s bound, and the multiplier as the certificate used it.

        Parameters
        ----------
        w : ndarray, shape (n_g,)
            Objective over the factors.
        y : ndarray, shape (n_c,)
            Multiplier of the equality constraints.
        w_err : ndarray, optional
            Elementwise bound on the rounding error in ``w``.
        w_pair : (M, v), optional
            ``w`` was computed as ``M^T v`` (see :mod:`setobs.lp.certificate`).
        exact_residual : bool
            Reduced costs correctly rounded (see :mod:`setobs.lp.certificate`).
        """
        if self._csc is None:
            self._csc = _certificate.csc_of(np.ascontiguousarray(self.A, dtype=np.float64))
        bound, y, _ = _certificate.certified_lower_bound(
            w, self.A, self.b, self._neg_h, self.h, y, w_err=w_err,
            unbounded_radius=self.unbounded_radius,
            unbounded_pinv=self._pinv() if self.any_unbounded else None, w_pair=w_pair,
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

    # -- queries -----------------------------------------------------------
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
        with self.lock:
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
        return highs_ladder(self, w, w_err, w_pair)

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
        return compiled_batch(self, W, gaps)

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
        return within_b_err(self, w, w_err, w_pair, scale)

    def pivot(self) -> tuple:
        """The unbounded factors pivoted out of the rows, once per polytope
        (:func:`setobs.lp.factor._interval_rows.free_pivot`)."""
        if self._pivot is None:
            self._pivot = free_pivot(self)
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
                reach = np.abs(self.A[:, ~self.unbounded]) @ self.h[~self.unbounded]
                tol = row_allowance + PRIMAL_RESIDUAL_RTOL * (1.0 + reach) + 8.0 * gamma(
                    self.n_g + 2) * (absAx + np.abs(self.b))
            if (resid > tol).any():
                return False
        over = np.abs(x) - self.h
        slack = PRIMAL_RESIDUAL_RTOL * (1.0 + np.where(self.unbounded, 0.0, self.h))
        return not (over > slack).any()

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
        return compiled_retry(self, w, w_err, w_pair)

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
        return relaxed_rows(self, w, w_err, w_pair)

    def row_scale(self) -> NDArray[np.float64]:
        """Power-of-two row scales of the phase-1 LP (:func:`._scaling.row_scale`)."""
        return row_scale(self.A, self.b, self.b_err)

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
        with self.lock:
            if tol in self._emptiness:
                return self._emptiness[tol]
            rep = phase1(self, tol)
            self._emptiness[tol] = rep
            return rep
