"""Worst-case-optimal point estimates of a bounded set, for the infinity and Euclidean norms."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._deprecation import renamed
from .._lazy import optional_import
from ..exceptions import SolverError, UnboundedSetError
from ..geometry import ConstrainedZonotope

__all__ = ["PointEstimate", "chebyshev_center", "interval_center"]


@dataclass(frozen=True)
class PointEstimate:
    """A point estimate and its worst-case error over the set.

    Attributes
    ----------
    point : ndarray
        The estimate ``d^``.
    worst_case_error : float
        ``max_{d in S} ||d^ - d||`` in the stated norm (``inf`` if unbounded):
        for the Chebyshev centre, the radius of the minimum enclosing ball.
    norm : str
        ``"inf"`` or ``"2"``.
    """

    point: NDArray[np.float64]
    worst_case_error: float
    norm: str

    radius = renamed("radius", "worst_case_error")


def interval_center(Z: ConstrainedZonotope) -> PointEstimate:
    """Centre of the interval hull: the worst-case-optimal estimate for the infinity norm.

    ``max_{d in S} ||c - d||_inf = max_i max(c_i - lo_i, hi_i - c_i)`` is
    minimised coordinate by coordinate at ``c = (lo + hi)/2``, with value
    ``max_i (hi_i - lo_i)/2``. (It is *not* optimal for the Euclidean norm in
    general: see :func:`chebyshev_center`.) Unbounded coordinates give NaN and
    ``worst_case_error = inf``.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    """
    box = Z.interval_hull()
    r = box.half_width
    return PointEstimate(box.center, float(r.max(initial=0.0)), "inf")


def chebyshev_center(Z: ConstrainedZonotope) -> PointEstimate:
    """Euclidean worst-case-optimal estimate: centre of the minimum enclosing ball.

    ``min_c max_{d in S} ||c - d||_2``. The maximum of a convex function over a
    polytope is attained at a vertex, so with the vertices ``v_i`` of ``S``
    (pycddlib) this is the second-order cone program
    ``min r s.t. ||v_i - c||_2 <= r`` (cvxpy, Clarabel). Exact for the small
    dimensions of a disturbance; vertex enumeration is exponential in general.

    This is the estimate Li-Cong-Dong's Definition 3 / Theorem 3 call optimal
    (they use the Euclidean norm), while Algorithm 1 line 15 returns the
    interval-hull centre, which is optimal for the infinity norm. Example: the
    triangle ``(0,0), (2,0), (1,2)`` has interval-hull centre ``(1, 1)`` with
    Euclidean radius ``sqrt(2) ~ 1.414``, but Chebyshev centre ``(1, 0.75)``
    with radius ``1.25``.

    Parameters
    ----------
    Z : ConstrainedZonotope
        A bounded set.

    Raises
    ------
    UnboundedSetError
        If the set is unbounded.
    """
    cp = optional_import("cvxpy", extra="qp", feature="chebyshev_center")

    if not Z.is_bounded:
        raise UnboundedSetError("the Chebyshev centre of an unbounded set does not exist")
    V = Z.vertices()
    if V.shape[0] == 1:
        return PointEstimate(V[0].copy(), 0.0, "2")
    c = cp.Variable(Z.dim)
    r = cp.Variable()
    prob = cp.Problem(cp.Minimize(r), [cp.norm(V[i] - c, 2) <= r for i in range(V.shape[0])])
    prob.solve(solver=cp.CLARABEL)
    if prob.status not in (cp.OPTIMAL, cp.OPTIMAL_INACCURATE) or c.value is None:
        raise SolverError(f"minimum enclosing ball SOCP failed (status {prob.status})",
                          status=str(prob.status))
    point = np.asarray(c.value, dtype=float)
    radius = float(np.linalg.norm(V - point, axis=1).max())  # exact worst case at this point
    return PointEstimate(point, radius, "2")
