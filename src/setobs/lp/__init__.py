"""LP problems and the one certificate, below the geometry.

Every bound setobs reports is the minimum of a linear function over a polytope,
certified by weak duality with a rounding analysis. This package holds:

* :mod:`setobs.lp.certificate` -- **the** certificate, written once (a lower bound
  of ``min {w^T x : A x = b, lo <= x <= hi}`` from any multiplier), compiled by
  numba and tested bit for bit against its own text interpreted;
* :mod:`setobs.lp.highs` -- every HiGHS model's set-up, data and status;
* :mod:`setobs.lp.factor` -- the factor polytope's LP (:class:`FactorPolytope`:
  support values, emptiness, retries and the certified fallback);
* :mod:`setobs.lp.fastlp` -- the fixed-structure warm-started LP
  (:class:`FixedStructureLP`) of the compiled simplex (:mod:`setobs.lp._simplex`);
* :mod:`setobs.lp.boxlp` -- the box-bounded LP grown block by block (the
  whole-history LP of exact mode), solved per objective from its last basis.

It imports nothing above it (the package's base modules only): :mod:`setobs.geometry`
and :mod:`setobs.setmembership` call it.
"""

from .factor import EmptinessReport, FactorPolytope, LPResult
from .fastlp import FixedStructureLP, LPState

__all__ = ["EmptinessReport", "FactorPolytope", "FixedStructureLP", "LPResult", "LPState"]
