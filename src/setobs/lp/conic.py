"""The conic LP chain: ``min c^T z`` subject to ``A z + s = b``, ``s in {0}^m_eq x R_+^m``,
by Clarabel (interior point) at tight tolerances, Clarabel with robust settings, then
HiGHS's interior point through scipy (the noise calibration's record LP,
:mod:`setobs.setmembership.calibrate`).

Each attempt returns ``(z or None, dual bound, status)``; the caller checks every answer
before it accepts it (a solver's point is never trusted), so the chain ends in a checked
answer or in the caller's error naming every attempt.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

__all__ = ["CLARABEL_ROBUST", "CLARABEL_TIGHT", "SOLVER_CHAIN", "clarabel_attempt",
           "highs_ipm_attempt"]

#: Clarabel's settings of the first attempt: tight tolerances, the default iterations
#: (the answer is checked and refined by the caller).
CLARABEL_TIGHT = {"max_iter": 300, "tol_gap_abs": 1e-10, "tol_gap_rel": 1e-10,
                  "tol_feas": 1e-10}
#: Clarabel's settings of the second attempt, after the first failed: more iterations,
#: more regularization and refinement, looser tolerances ("almost solved" accepted).
CLARABEL_ROBUST = {"max_iter": 1000, "static_regularization_constant": 1e-7,
                   "iterative_refinement_max_iter": 50, "tol_gap_abs": 1e-8,
                   "tol_gap_rel": 1e-8, "tol_feas": 1e-8}

#: One attempt of the chain: ``(A, b, c, m_eq, time_limit) -> (z or None, bound, status)``.
Attempt = Callable[[sp.spmatrix, NDArray[np.float64], NDArray[np.float64], int, float],
                   tuple[NDArray[np.float64] | None, float, str]]


def clarabel_attempt(robust: bool) -> Attempt:
    """Clarabel with :data:`CLARABEL_TIGHT` or (``robust``) :data:`CLARABEL_ROBUST`.

    Parameters
    ----------
    robust : bool
        The second attempt's settings (and "almost solved" accepted).
    """
    def attempt(A, b, c, m_eq, time_limit):
        import clarabel

        st = clarabel.DefaultSettings()
        st.verbose = False
        st.time_limit = float(time_limit)
        for key, value in (CLARABEL_ROBUST if robust else CLARABEL_TIGHT).items():
            setattr(st, key, value)
        P = sp.csc_matrix((A.shape[1], A.shape[1]))
        cones = [clarabel.ZeroConeT(m_eq), clarabel.NonnegativeConeT(A.shape[0] - m_eq)]
        if m_eq == 0:
            cones = cones[1:]
        sol = clarabel.DefaultSolver(P, c, A.tocsc(), b, cones, st).solve()
        S = clarabel.SolverStatus
        good = (S.Solved, S.AlmostSolved) if robust else (S.Solved,)
        name = str(sol.status).rsplit(".", 1)[-1]
        if sol.status not in good:
            return None, np.nan, name
        status = "optimal" if sol.status == S.Solved else "almost optimal"
        return np.asarray(sol.x, dtype=float), float(sol.obj_val_dual), status
    return attempt


def highs_ipm_attempt(A, b, c, m_eq: int, time_limit: float
                      ) -> tuple[NDArray[np.float64] | None, float, str]:
    """HiGHS's interior point through :func:`scipy.optimize.linprog` (presolve off).

    Parameters
    ----------
    A : sparse matrix, shape (m_eq + m, n)
        The rows, the equalities first.
    b : ndarray, shape (m_eq + m,)
        Their right-hand side.
    c : ndarray, shape (n,)
        The objective.
    m_eq : int
        The number of equality rows.
    time_limit : float
        Seconds.
    """
    from scipy.optimize import linprog

    r = linprog(c, A_ub=A[m_eq:], b_ub=b[m_eq:], A_eq=A[:m_eq] if m_eq else None,
                b_eq=b[:m_eq] if m_eq else None, bounds=(None, None), method="highs-ipm",
                options={"time_limit": float(time_limit), "presolve": False})
    if r.status != 0 or r.x is None:
        return None, np.nan, f"HiGHS status {r.status} ({r.message})"
    lower = getattr(r, "fun", np.nan)
    return np.asarray(r.x, dtype=float), float(lower), "optimal"


#: The chain, in order: ``(name, attempt)``. The caller checks each answer before it
#: accepts it; the tests insert failing solvers here.
SOLVER_CHAIN: tuple[tuple[str, Attempt], ...] = (
    ("clarabel", clarabel_attempt(False)),
    ("clarabel (robust settings)", clarabel_attempt(True)),
    ("HiGHS interior point (scipy)", highs_ipm_attempt),
)
