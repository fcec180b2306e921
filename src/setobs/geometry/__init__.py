"""Set geometry: extended constrained zonotopes, certified LP queries, reduction, conversion."""

from .box import Box
from .lp import EmptinessReport, FactorPolytope, LPResult
from .polytope import HRep, cz_from_hpolytope, polygon_2d, to_hrep, vertices
from .reduction import reduce_exact, reduce_order, remove_redundancy, rescale
from .zonotope import ConstrainedZonotope

__all__ = [
    "Box",
    "ConstrainedZonotope",
    "EmptinessReport",
    "FactorPolytope",
    "HRep",
    "LPResult",
    "cz_from_hpolytope",
    "polygon_2d",
    "reduce_exact",
    "reduce_order",
    "remove_redundancy",
    "rescale",
    "to_hrep",
    "vertices",
]
