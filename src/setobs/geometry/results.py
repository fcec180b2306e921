"""The answers of the geometry's queries: plain, frozen result types.

They live below :class:`~setobs.geometry.zonotope.ConstrainedZonotope` (this module
imports nothing of the geometry), so that every method of the class is annotated with
the type it returns; the functions that compute them (:mod:`.relations`,
:mod:`.measure`, :mod:`.polytope`) import them from here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..exceptions import InvalidValueError

__all__ = ["ContainmentResult", "DistanceResult", "HRep", "QPResult", "VolumeResult"]


@dataclass(frozen=True)
class ContainmentResult:
    """Three-valued answer of a set relation.

    Attributes
    ----------
    holds : bool or None
        ``True`` (certified up to the tolerance), ``False`` (with a witness) or
        ``None`` (undecided).
    witness : ndarray or None
        With ``holds=False``: a point of the first set outside the second.
    method : str
        How it was decided (``"supports"``, ``"facets"``, ``"matching"``, ...).
    margin : float
        The largest certified excess of a support value over its offset
        (``<= tol`` when ``holds`` is ``True``); ``nan`` where no offsets apply.
    tol : float
        The largest tolerance used.

    Notes
    -----
    ``bool(result)`` is ``holds`` when it is decided and raises
    :class:`ValueError` when it is ``None``, so that ``if Z.is_subset(W):``
    never reads an undecided answer as ``False``.
    """

    holds: bool | None
    witness: NDArray[np.float64] | None = None
    method: str = ""
    margin: float = float("nan")
    tol: float = field(default=0.0)

    def __bool__(self) -> bool:
        if self.holds is None:
            raise InvalidValueError("the relation is undecided (holds=None); read .holds "
                                    "explicitly")
        return self.holds


@dataclass(frozen=True)
class HRep:
    """H-representation ``{x : H x <= k, E x = f}``.

    Attributes
    ----------
    H, k : ndarray
        Inequalities ``H x <= k`` (facets).
    E, f : ndarray
        Equalities ``E x = f`` (the affine hull when the set is flat).
    """

    H: NDArray[np.float64]
    k: NDArray[np.float64]
    E: NDArray[np.float64]
    f: NDArray[np.float64]

    def contains(self, x: ArrayLike, tol: float = 1e-9) -> bool:
        """Whether ``x`` satisfies all inequalities and equalities within ``tol``.

        Parameters
        ----------
        x : array_like, shape (n,)
            The point.
        tol : float
            Allowed violation of each inequality and equality.
        """
        xv = np.asarray(x, dtype=float)
        return bool((self.H @ xv <= self.k + tol).all() and
                    (np.abs(self.E @ xv - self.f) <= tol).all())


@dataclass(frozen=True)
class QPResult:
    """Solution of :func:`minimize_quadratic`.

    Attributes
    ----------
    point : ndarray, shape (n,)
        The minimiser ``z`` (in the set up to the solver's feasibility tolerance).
    value : float
        The objective at ``point``.
    status : str
        Clarabel's status (``"Solved"`` or ``"AlmostSolved"``).
    """

    point: NDArray[np.float64]
    value: float
    status: str


@dataclass(frozen=True)
class DistanceResult:
    """Euclidean distance from a point to a set.

    Attributes
    ----------
    distance : float
        ``||p - z*||`` for the computed nearest point ``z*`` (an upper bound of
        the distance up to the solver's feasibility tolerance).
    lower : float
        Certified lower bound of the distance (``0`` when ``p`` is inside or
        no positive bound could be certified).
    point : ndarray
        The nearest point ``z*``.
    """

    distance: float
    lower: float
    point: NDArray[np.float64]


@dataclass(frozen=True)
class VolumeResult:
    """Volume of a set (Lebesgue measure in its ambient dimension).

    Attributes
    ----------
    value : float
        The volume (exact methods) or its Monte Carlo estimate.
    lower, upper : float
        Confidence interval (equal to ``value`` for exact methods).
    method : str
        ``"interval"`` (1-D), ``"polygon"`` (2-D), ``"qhull"`` (3-D) or
        ``"monte-carlo"``.
    n_samples : int
        Number of Monte Carlo samples (0 for exact methods).
    confidence : float
        Confidence level of ``[lower, upper]`` (1 for exact methods).
    """

    value: float
    lower: float
    upper: float
    method: str
    n_samples: int = 0
    confidence: float = 1.0
