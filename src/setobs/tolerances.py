"""Default tolerances of :mod:`setobs`, in one place.

Policy
------
* **LP bounds are certified, not tolerance-based.** Interval hulls and support
  values are computed from a dual (Lagrangian) bound that is valid for *any*
  multiplier vector, evaluated with a rigorous floating-point error term
  (see :mod:`setobs.geometry.lp`). They contain the set defined by the stored
  data, whatever the solver's tolerances were.
* **Unbounded factors** (``h_j = inf``) need zero reduced cost on their columns.
  After refinement the residual reduced cost is tiny but rarely exactly zero; the
  bound then covers every point of the set that has a representation with
  ``|xi_j| <= UNBOUNDED_RADIUS`` on the unbounded factors (the term
  ``|r_j| * UNBOUNDED_RADIUS`` is added). If the residual exceeds
  ``UNBOUNDED_REDUCED_COST_TOL`` (relative) the direction is declared unbounded
  (``+inf``), which is always an outer answer.
* **Emptiness and containment use a feasibility tolerance** on constraints
  normalised to unit infinity-norm rows: a set is reported empty only when a
  certified lower bound on the constraint violation exceeds ``FEASIBILITY_TOL``;
  otherwise it is reported non-empty. A ``False`` from :meth:`contains` and a
  ``True`` from :meth:`is_empty` are therefore never caused by solver round-off.
"""

from __future__ import annotations

__all__ = [
    "DATA_RTOL",
    "FEASIBILITY_TOL",
    "FRAGILE_MARGIN_DECADES",
    "PRODUCT_RTOL",
    "RANK_FLOOR",
    "RANK_RTOL",
    "UNBOUNDED_RADIUS",
    "UNBOUNDED_REDUCED_COST_TOL",
    "UNIT_CIRCLE_TOL",
    "ZERO_TOL",
]

#: Absolute tolerance on normalised equality constraints for emptiness/containment.
FEASIBILITY_TOL: float = 1e-9

#: Radius of unbounded factors up to which certified bounds hold (see module docs).
UNBOUNDED_RADIUS: float = 1e8

#: Relative reduced-cost residual on unbounded factors above which a direction is unbounded.
UNBOUNDED_REDUCED_COST_TOL: float = 1e-10

#: Relative threshold below which a row/column is treated as numerically zero in reductions.
ZERO_TOL: float = 1e-12

#: Relative uncertainty of measured data (``y``, ``u``) at rounding level in the SMFDO:
#: the representation error of a double plus a few roundings in the code that
#: produced the data (``2 eps``). The certified bounds hold for all data within it.
DATA_RTOL: float = 2.0 * 2.220446049250313e-16

# ---------------------------------------------------------------------------
# Structural analysis (setobs.analysis)
# ---------------------------------------------------------------------------
# Policy: every rank or zero decision is made on a *balanced* realisation
# (diagonal state scaling from LAPACK's balancing of the system matrix, inputs
# and outputs scaled with it; all of these leave ranks, zeros and relative
# degrees unchanged), and a singular value counts as nonzero when it exceeds
# RANK_RTOL times the norm of the matrix it belongs to. Each decision is
# reported with its margin: how many orders of magnitude the smallest kept and
# the largest dropped singular value sit from the threshold.

#: Relative threshold for numerical rank decisions on balanced data.
RANK_RTOL: float = 1e-9

#: Relative size below which a singular value is zero at the precision of the
#: data (a few hundred ``eps``: what rounding alone leaves of a structural zero).
#: Between ``RANK_FLOOR`` and ``RANK_RTOL`` a rank is *undecidable* at this
#: precision: verdicts that depend on it say so rather than guess.
RANK_FLOOR: float = 1e-14

#: Relative threshold for computed products ``C A^k E`` (relative degrees, UIO
#: delay), measured against their rounding-error scale
#: ``||C|| max(||A^k E||, ||A|| ||A^(k-1) E||)`` (about 4500 eps): such products
#: can legitimately span many decades in non-normal coordinates, so a threshold
#: relative to their own size would cut into the signal.
PRODUCT_RTOL: float = 1e-12

#: A decision whose margin is below this many decades is flagged as fragile.
FRAGILE_MARGIN_DECADES: float = 2.0

#: Invariant zeros with |z| within this of the unit circle are reported as marginal.
UNIT_CIRCLE_TOL: float = 1e-8
