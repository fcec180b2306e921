"""Set geometry: extended constrained zonotopes, certified LP queries, reduction, conversion."""

from ..lp.factor import EmptinessReport, FactorPolytope, LPResult
from .box import Box
from .hybrid import BranchAndBoundResult, HybridEmptiness, HybridZonotope, pwa_reachable_sets
from .measure import (
    DistanceResult,
    QPResult,
    VolumeResult,
    distance,
    minimize_quadratic,
    nearest_point,
    sample,
    volume,
)
from .operations import (
    convex_hull,
    empty_set,
    from_vertices,
    intersect_halfspace,
    intersect_polytope,
    intersect_strip,
    interval_matrix_map,
    pontryagin_difference,
    quad_map,
)
from .polytope import HRep, cz_from_hpolytope, polygon_2d, to_hrep, vertices
from .reduction import eliminate_constraints, reduce_exact, reduce_order, remove_redundancy, rescale
from .relations import ContainmentResult, is_equal, is_subset, is_subset_of_polytope, represents
from .zonotope import ConstrainedZonotope, compiled_set_operations

__all__ = [
    "Box",
    "BranchAndBoundResult",
    "ConstrainedZonotope",
    "ContainmentResult",
    "DistanceResult",
    "EmptinessReport",
    "FactorPolytope",
    "HRep",
    "HybridEmptiness",
    "HybridZonotope",
    "LPResult",
    "QPResult",
    "VolumeResult",
    "compiled_set_operations",
    "convex_hull",
    "cz_from_hpolytope",
    "distance",
    "eliminate_constraints",
    "empty_set",
    "from_vertices",
    "intersect_halfspace",
    "intersect_polytope",
    "intersect_strip",
    "interval_matrix_map",
    "is_equal",
    "is_subset",
    "is_subset_of_polytope",
    "minimize_quadratic",
    "nearest_point",
    "polygon_2d",
    "pontryagin_difference",
    "pwa_reachable_sets",
    "quad_map",
    "reduce_exact",
    "reduce_order",
    "remove_redundancy",
    "represents",
    "rescale",
    "sample",
    "to_hrep",
    "vertices",
    "volume",
]
