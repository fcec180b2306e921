"""What the factor polytope's queries answer: a certified minimum (:class:`LPResult`) and
an emptiness verdict (:class:`EmptinessReport`)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from ...tolerances import FEASIBILITY_TOL

__all__ = ["EmptinessReport", "LPResult"]


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
