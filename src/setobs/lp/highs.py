"""HiGHS, set up once: every HiGHS model of the package is made, filled and read here.

The LP problems (:mod:`setobs.lp.factor`, the whole-history LP of exact mode,
the hit-and-run chords of :mod:`setobs.geometry.measure`) ask this module for a
model (:func:`new_model`), pass their data (:func:`pass_dense`, :func:`pass_csc`)
and read a solve's outcome as a plain word (:func:`status`); nothing else in the
package names a HiGHS option or status. HiGHS only *proposes* multipliers: every
bound reported is certified by :mod:`setobs.lp.certificate`.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._lazy import lazy_module

__all__ = ["RETRY_SETTINGS", "basis", "basis_duals", "highspy", "new_model", "option",
           "pass_csc", "pass_dense", "set_basis", "simplex_limit", "solve", "status",
           "status_name"]

# HiGHS loads on the first LP, not on ``import setobs``.
highspy = lazy_module("highspy")

INF = float("inf")  # (HiGHS's kHighsInf)


#: The other settings a failed solve is retried with, in order: a fresh unscaled
#: model; the primal simplex with HiGHS's default tolerances; the interior-point
#: method with crossover.
RETRY_SETTINGS: tuple[dict[str, object], ...] = (
    {"simplex_strategy": 1, "simplex_scale_strategy": 0},
    {"simplex_strategy": 4, "primal_feasibility_tolerance": 1e-7,
     "dual_feasibility_tolerance": 1e-7},
    {"solver": "ipm", "run_crossover": "on"},
)


def new_model(settings: dict[str, object] | None = None, *, scaled: bool = True):
    """A HiGHS model with the package's settings: silent, no presolve, tolerances
    1e-10, the dual simplex (measured faster here), HiGHS's own scaling unless
    ``scaled`` is false, then ``settings``.

    Parameters
    ----------
    settings : dict, optional
        HiGHS options to set on top (e.g. one of :data:`RETRY_SETTINGS`).
    scaled : bool
        Whether HiGHS scales the LP itself (its default); off for an LP whose columns
        the caller has already scaled (:data:`setobs.lp.boxlp.HIGHS_SCALING`).

    Returns
    -------
    highspy.Highs
        An empty model.
    """
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
    # it agrees with the compiled fast path to 1e-8 (tests/lp/test_fastlp.py).
    hs.setOptionValue("primal_feasibility_tolerance", 1e-10)
    hs.setOptionValue("dual_feasibility_tolerance", 1e-10)
    hs.setOptionValue("simplex_strategy", 1)
    if not scaled:
        hs.setOptionValue("simplex_scale_strategy", 0)
    for key, val in (settings or {}).items():
        hs.setOptionValue(key, val)
    return hs


def solve(hs, *, primal: bool = False, iteration_limit: int | None = None) -> str:
    """Run ``hs`` (the dual simplex, or the primal from its current basis) and return
    :func:`status`.

    Parameters
    ----------
    hs : highspy.Highs
        A model with its data.
    primal : bool
        The primal simplex (a warm start whose basis stays primal feasible but for
        new rows: its phase 1 is short) instead of the dual.
    iteration_limit : int, optional
        Simplex iterations allowed.

    Returns
    -------
    str
        The outcome.
    """
    hs.setOptionValue("simplex_strategy", 4 if primal else 1)
    if iteration_limit is not None:
        hs.setOptionValue("simplex_iteration_limit", int(iteration_limit))
    hs.run()
    return status(hs)


def set_basis(hs, basis) -> bool:
    """Start the next solve of ``hs`` from ``basis`` (a ``highspy.HighsBasis`` of a model
    of the same size, from ``getBasis()``, which copies); ``False`` if HiGHS refuses it.

    Parameters
    ----------
    hs : highspy.Highs
        A model with its data.
    basis : highspy.HighsBasis
        The basis.

    Returns
    -------
    bool
        Whether the basis was taken.
    """
    return bool(basis.valid) and hs.setBasis(basis) == highspy.HighsStatus.kOk


def simplex_limit(n_rows: int, n_cols: int) -> int:
    """Simplex iteration limit of a HiGHS solve: generous for a healthy LP of this size.

    Parameters
    ----------
    n_rows, n_cols : int
        The LP's size.

    Returns
    -------
    int
        The limit.
    """
    return 50 * (n_rows + n_cols) + 10_000


def option(hs, name: str) -> int:
    """An integer HiGHS option (``getOptionValue`` returns ``(status, value)`` in
    recent highspy releases and the value alone in older ones).

    Parameters
    ----------
    hs : highspy.Highs
        The model.
    name : str
        The option.

    Returns
    -------
    int
        Its value.
    """
    v = hs.getOptionValue(name)
    return int(v[1] if isinstance(v, tuple) else v)


def status(hs) -> str:
    """The outcome of the last solve of ``hs``, as one word.

    Parameters
    ----------
    hs : highspy.Highs
        A model that has been run.

    Returns
    -------
    str
        ``"optimal"``, ``"unbounded"``, ``"infeasible"`` (including HiGHS's
        "unbounded or infeasible"), or ``"undecided"`` (an iteration or time limit,
        a numerical failure, anything else).
    """
    st = hs.getModelStatus()
    S = highspy.HighsModelStatus
    if st == S.kOptimal:
        return "optimal"
    if st == S.kUnbounded:
        return "unbounded"
    if st in (S.kInfeasible, S.kUnboundedOrInfeasible):
        return "infeasible"
    return "undecided"


def basis(hs) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
    """Which columns and which rows (slacks) are basic in the last solve's basis.

    Parameters
    ----------
    hs : highspy.Highs
        A model that has been run.

    Returns
    -------
    basic_col, basic_row : ndarray of bool
        The basic columns and rows.
    """
    b = hs.getBasis()
    basic = highspy.HighsBasisStatus.kBasic
    return (np.array([st == basic for st in b.col_status], dtype=bool),
            np.array([st == basic for st in b.row_status], dtype=bool))


def basis_duals(hs, A, w: NDArray[np.float64]) -> NDArray[np.float64] | None:
    """Row duals recomputed from the last solve's basis, refined in extended precision.

    Solves ``A[N, B]^T y_N = w_B`` (``B`` the basic columns, ``N`` the nonbasic rows;
    ``y = 0`` on rows whose slack is basic), then up to three rounds of iterative
    refinement with the residual in extended precision (long double where the platform
    has it): the duals of the basis to working precision, also on ill-conditioned
    bases. Only a candidate multiplier: a bound from it is certified like any other.

    Parameters
    ----------
    hs : highspy.Highs
        A model that has been run, of the LP ``A x = b`` in ``A``'s columns.
    A : ndarray or scipy.sparse array, shape (m, n)
        The constraint matrix (sparse: the basis is factorized by a sparse LU).
    w : ndarray, shape (n,)
        The objective.

    Returns
    -------
    ndarray or None
        ``y`` of shape ``(m,)``, or ``None`` when the basis does not fit ``A``, is not
        square or is singular.
    """
    basic_col, basic_row = basis(hs)
    m, n = A.shape
    if basic_col.size != n or basic_row.size != m:
        return None
    bc = np.flatnonzero(basic_col)
    nbr = np.flatnonzero(~basic_row)
    if bc.size != nbr.size:
        return None
    wb = np.asarray(w, dtype=np.float64)[bc]
    if hasattr(A, "tocsc"):
        import scipy.sparse.linalg as spla

        M = A.tocsr()[nbr][:, bc].T.tocsc()
        try:
            solve = spla.splu(M).solve
        except RuntimeError:  # (singular)
            return None
        Ml = M.astype(np.longdouble)
    else:
        M = A[np.ix_(nbr, bc)].T

        def solve(r):
            return np.linalg.solve(M, r)
        Ml = M.astype(np.longdouble)
    try:
        yn = solve(wb)
        wl = wb.astype(np.longdouble)
        for _ in range(3):
            r = np.asarray(wl - Ml @ yn.astype(np.longdouble), dtype=np.float64)
            if not r.any():
                break
            yn = yn + solve(r)
    except np.linalg.LinAlgError:
        return None
    if not np.isfinite(yn).all():
        return None
    y = np.zeros(m)
    y[nbr] = yn
    return y


def status_name(hs) -> str:
    """HiGHS's own name of the last solve's status (for messages).

    Parameters
    ----------
    hs : highspy.Highs
        A model that has been run.

    Returns
    -------
    str
        The name.
    """
    return hs.modelStatusToString(hs.getModelStatus())


def _limits(hs, n_rows: int, n_cols: int) -> None:
    # Deterministic iteration limits (a degenerate LP once cycled for minutes):
    # a solve that hits them is undecided, and the retries / fallback take over.
    hs.setOptionValue("simplex_iteration_limit",
                      min(simplex_limit(n_rows, n_cols), option(hs, "simplex_iteration_limit")))
    hs.setOptionValue("ipm_iteration_limit", min(1000, option(hs, "ipm_iteration_limit")))


def pass_csc(hs, n_rows: int, cost, col_lo, col_hi, row_lo, row_hi, start, index, value) -> bool:
    """Pass ``min cost^T x, row_lo <= A x <= row_hi, col_lo <= x <= col_hi`` with ``A``
    given column by column; ``False`` if the data hold a NaN or an infinite cost, or
    HiGHS rejects the model.

    Parameters
    ----------
    hs : highspy.Highs
        A model from :func:`new_model`.
    n_rows : int
        Rows of ``A``.
    cost, col_lo, col_hi : ndarray, shape (n,)
        Objective and column bounds.
    row_lo, row_hi : ndarray, shape (n_rows,)
        Row bounds.
    start, index, value : ndarray
        ``A`` in compressed sparse column form.

    Returns
    -------
    bool
        Whether the model was taken.
    """
    # Never NaN (or an infinite cost) into HiGHS: it looped for minutes on such a
    # model, past its own time limit (a NaN objective from a pseudo-inverse of
    # data of extreme dynamic range). The model is refused: the caller's retries
    # and certified fallback take over.
    if not (np.isfinite(value).all() and np.isfinite(cost).all()) or any(
            np.isnan(v).any() for v in (col_lo, col_hi, row_lo, row_hi)):
        return False
    n_cols = int(np.size(cost))
    lp = highspy.HighsLp()
    lp.num_col_ = n_cols
    lp.num_row_ = n_rows
    lp.col_cost_ = np.ascontiguousarray(cost, dtype=np.float64)
    lp.col_lower_ = np.ascontiguousarray(col_lo, dtype=np.float64)
    lp.col_upper_ = np.ascontiguousarray(col_hi, dtype=np.float64)
    lp.row_lower_ = np.ascontiguousarray(row_lo, dtype=np.float64)
    lp.row_upper_ = np.ascontiguousarray(row_hi, dtype=np.float64)
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_ = np.ascontiguousarray(start, dtype=np.int32)
    lp.a_matrix_.index_ = np.ascontiguousarray(index, dtype=np.int32)
    lp.a_matrix_.value_ = np.ascontiguousarray(value, dtype=np.float64)
    lp.a_matrix_.num_col_ = n_cols
    lp.a_matrix_.num_row_ = n_rows
    _limits(hs, n_rows, n_cols)
    return hs.passModel(lp) != highspy.HighsStatus.kError


def pass_dense(hs, A: NDArray[np.float64], col_lo, col_hi, row_lo, row_hi, cost) -> bool:
    """:func:`pass_csc` for a dense ``A`` (its zeros left out).

    Parameters
    ----------
    hs : highspy.Highs
        A model from :func:`new_model`.
    A : ndarray, shape (m, n)
        Constraint matrix.
    col_lo, col_hi : ndarray, shape (n,)
        Column bounds.
    row_lo, row_hi : ndarray, shape (m,)
        Row bounds.
    cost : ndarray, shape (n,)
        Objective.

    Returns
    -------
    bool
        Whether the model was taken.
    """
    if not np.isfinite(A).all():
        return False
    n_r, n_col = A.shape
    mask = A != 0.0
    start = np.zeros(n_col + 1, dtype=np.int32)
    np.cumsum(mask.sum(axis=0), out=start[1:])
    rows, cols = np.nonzero(mask.T)  # column-major order
    return pass_csc(hs, n_r, cost, col_lo, col_hi, row_lo, row_hi, start, cols,
                    np.ascontiguousarray(A.T[rows, cols]))
