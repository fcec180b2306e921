"""Default tolerances of :mod:`setobs`, in one place.

Policy
------
* **LP bounds are certified, not tolerance-based.** Interval hulls and support
  values are computed from a dual (Lagrangian) bound that is valid for *any*
  multiplier vector, evaluated with a rigorous floating-point error term
  (see :mod:`setobs.lp.factor`). They contain the set defined by the stored
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
    "ALLOWANCE_RTOL",
    "BINARY_TOL",
    "CALIBRATION_ACTIVE_RTOL",
    "CALIBRATION_ATOL",
    "CALIBRATION_CHECK_TOL",
    "CALIBRATION_RTOL",
    "CENTER_ERROR_ABSORB_RTOL",
    "CONTAINMENT_RTOL",
    "DATA_RTOL",
    "ELIMINATION_ERR_RTOL",
    "ELIMINATION_PIVOT_TOL",
    "EQUILIBRATION_FLOOR",
    "EQUILIBRIUM_ATOL",
    "EXACT_RTOL",
    "FASTLP_BOUNDED_CLEAR",
    "FASTLP_CONSISTENCY_RTOL",
    "FASTLP_GAP_RTOL",
    "FASTLP_PRIMAL_RTOL",
    "FASTLP_RANK_GREY",
    "FASTLP_UNBOUNDED_CLEAR",
    "FEASIBILITY_TOL",
    "FRAGILE_MARGIN_DECADES",
    "HISTORY_GAP_RTOL",
    "HREP_ACTIVE_RTOL",
    "HREP_CLIP_RTOL",
    "HREP_CONVERT_RTOL",
    "HREP_FLAT_RTOL",
    "HREP_SNAP_TOL",
    "HREP_VERIFY_RTOL",
    "ILL_CONDITIONED_RTOL",
    "IMAG_DISPLAY_RTOL",
    "KALMAN_MEASUREMENT_FLOOR",
    "LP_REFINE_GAP",
    "MAX_MAGNITUDE",
    "MISSING_WARN_FRACTION",
    "NEAR_RESONANCE_RTOL",
    "NEWTON_RTOL",
    "PINNED_FACTOR_RTOL",
    "PONTRYAGIN_MATCH_RTOL",
    "PRIMAL_RESIDUAL_RTOL",
    "PRODUCT_RTOL",
    "RANK_FLOOR",
    "RANK_RTOL",
    "REDUNDANT_BOUND_MARGIN",
    "RELAXED_EXACT_GAP",
    "RESIDUAL_GROWTH_FACTOR",
    "RESONANCE_RTOL",
    "TRUST_TOL",
    "UNBOUNDED_RADIUS",
    "UNBOUNDED_REDUCED_COST_TOL",
    "UNIT_CIRCLE_TOL",
    "VERTEX_RTOL",
    "ZERO_TOL",
]

#: Absolute tolerance on normalised equality constraints for emptiness/containment.
#: Largest magnitude of a finite entry in any matrix, vector or record the package
#: accepts: products and sums of a few such numbers still fit in double precision
#: (1e308); larger entries are refused with a message that names the matrix.
MAX_MAGNITUDE: float = 1e150
FEASIBILITY_TOL: float = 1e-9

#: Distance from +-1 within which a relaxed binary factor of a hybrid zonotope counts as
#: integral in a node's LP point (the branch and bound then closes the node with its
#: certified bound, which a leaf attains up to the solver's accuracy; soundness does not
#: depend on it).
BINARY_TOL: float = 1e-9

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

#: Invariant zeros with ``|z|`` within this of the unit circle are reported as marginal.
UNIT_CIRCLE_TOL: float = 1e-8

#: Zeros and poles whose imaginary part is below this fraction of ``max(1, |z|)``
#: are displayed as real (messages and reports only; no decision uses it).
IMAG_DISPLAY_RTOL: float = 1e-10

# ---- the compiled fast path (setobs.lp.fastlp)
#: Relative least-squares residual of ``w_U`` on ``range(A_U^T)`` above which a
#: direction is unbounded below, and below which it is bounded; in between the
#: direction is left to the reference path.
FASTLP_UNBOUNDED_CLEAR: float = 1e-6
FASTLP_BOUNDED_CLEAR: float = 1e-12
#: Accepted gap between the certified bound and the simplex objective.
FASTLP_GAP_RTOL: float = 1e-9
#: The compiled simplex accepts an optimal basis only when its basic solution
#: satisfies the reduced equations to this, relative to ``1 + |b_i| + |A_i| |x|``
#: row by row (an inaccurate basis inverse otherwise passes a loose bound as optimal).
FASTLP_PRIMAL_RTOL: float = 1e-9
#: Relative size of the singular values that make a structure unusable (rank
#: decisions between these and 1 would have to be made; the reference path
#: does not make them, so the fast path does not either).
FASTLP_RANK_GREY: float = 1e-6
#: Relative residual of the data on the left null space of ``A`` (redundant rows)
#: above which the reduced LP is not trusted (the reference path decides emptiness).
FASTLP_CONSISTENCY_RTOL: float = 1e-11
#: Norms below this fraction of the largest are rounding level: equilibration
#: leaves them at the scale of the largest instead of blowing them up (a column
#: of 1e-17 entries left by a rotated basis must not become a unit column, whose
#: factor would then have a range of 1e-17 and an objective weight of 1e17).
EQUILIBRATION_FLOOR: float = 1e-10

# ---- exact mode with noise (setobs.setmembership._history)
#: Largest accepted certification gap (certified bound against the solver's optimum)
#: of one whole-history LP, relative to ``1 + |optimum|``; above it the solve is
#: retried (dual simplex, fresh model, ranged rows) and then the step goes to the
#: set recursion (still certified, only slower).
HISTORY_GAP_RTOL: float = 1e-8

# ---- what a step's "ok" promises (setobs.setmembership)
#: A window step (or exact mode's H-representation step) whose rounding allowances (the
#: LP certificate's ``|y|^T b_err`` on both ends of a band and ``2 c_err``) exceed this
#: fraction of a band's reported width is reported ``"inexact"``, not ``"ok"``: the band
#: is certified, but part of its width is the allowance's, not the set's.
ALLOWANCE_RTOL: float = 1e-2
#: Exact mode reports ``"ok"`` only for bounds certified within this fraction of each
#: band's width of the whole-history set (a certified gap above it, after the multiplier
#: is refined from the solver's basis: ``"inexact"``, the gap in ``step.gap``).
EXACT_RTOL: float = 1e-6

# ---- the HiGHS reference LPs (setobs.lp.factor)
#: Relative certification gap above which duals are recomputed from the basis.
LP_REFINE_GAP: float = 1e-9
#: A solver's "optimal" point is accepted only when every row satisfies
#: ``|A_i x - b_i| <= PRIMAL_RESIDUAL_RTOL (1 + |b_i| + |A_i| |x|)`` (and the factor
#: bounds to the same tolerance): a guard against gross errors, above the solvers'
#: own feasibility tolerances (1e-10 to 1e-7). HiGHS once returned "optimal" with a
#: relative residual of 3e-3 on an exact-mode set, and a multiplier certified near
#: that point's objective, 0.01 below the true minimum.
PRIMAL_RESIDUAL_RTOL: float = 1e-6
#: The LP with rows relaxed (the last resort after an uncertified "infeasible") counts
#: as exact when its minimiser satisfies the exact rows and its objective is within
#: this of its certified bound, relative to ``1 + |objective|``.
RELAXED_EXACT_GAP: float = 1e-6

# ---- vertex enumeration (setobs.geometry.polytope)
#: Relative tolerance of the vertex enumeration: a facet of the found hull is
#: confirmed when the certified support in its normal exceeds its offset by at
#: most this times the set's size; flat directions have certified width below it.
VERTEX_RTOL: float = 1e-9

# ---- exact mode's H-representation recursion (setobs.setmembership._hrep)
#: Singular values of a point cloud below this fraction of the largest are flat
#: directions of the approximate geometry (they only choose normals: the
#: offsets in flat directions are certified like every other).
HREP_FLAT_RTOL: float = 1e-10
#: Two unit normals closer than this (infinity norm) are the same normal: the
#: previous step's is reused bit for bit, so that the LP structure stays fixed.
HREP_SNAP_TOL: float = 1e-10
#: Relative tolerance below which a point lies on a measurement hyperplane when
#: the approximate geometry is clipped.
HREP_CLIP_RTOL: float = 1e-12
#: A vertex of the approximate geometry lies on a facet ``H_i z <= g_i`` of the
#: certified set when its slack is below this fraction of the set's extent:
#: vertices with the same facets are one vertex (near-duplicates from clipping).
HREP_ACTIVE_RTOL: float = 1e-6
#: Exact mode's H-representation is carried to the next step only when every vertex
#: of ``{z : H z <= g}`` lies within this (relative to the set's extent) of the
#: carried vertex set: otherwise the normals miss a facet (the vertex set drifted
#: from the polytope on thin sets at a calibrated noise bound, and the carried set
#: grew outer by up to 5 % of the width while steps said ok), and the step's exact
#: set is carried as a constrained zonotope instead.
HREP_VERIFY_RTOL: float = 1e-6
#: Facet tolerance (relative to the set's size) of exact mode's conversion of a
#: posterior to an H-representation. With ``VERTEX_RTOL`` (1e-9) the converted
#: polytope may exceed the set by slivers of that size, and on thin sets at a
#: calibrated noise bound later measurement slabs amplified them to 2e-4 of the
#: interval width. A conversion that cannot confirm its facets this tightly falls
#: back to ``VERTEX_RTOL`` (carrying the set instead cost 1e-6 of exactness over
#: long records through the set recursion's rounding allowances).
HREP_CONVERT_RTOL: float = 1e-12
#: The set recursion (exact mode's reference path) carries the rounding bound of a
#: posterior's centre as bounded factors once it exceeds this fraction of the
#: set's magnitude: mapped as a bound, ``|A| c_err``, it grows like
#: ``rho(|A|)^k`` (1e-3 of the width after 30 steps of a non-normal ``A``);
#: mapped as generators it follows ``A^k``.
CENTER_ERROR_ABSORB_RTOL: float = 1e-13
#: :meth:`SMFDO.run <setobs.SMFDO.run>` warns (``MissingDataWarning``) when more than
#: this fraction of a record's output samples (entries of ``Y``) are missing (NaN): its
#: bands are then mostly predictions. A record with no measured sample is refused.
MISSING_WARN_FRACTION: float = 0.5

# ---- exact reduction (setobs.geometry.reduction)
#: Relative margin by which a factor's certified interval must lie inside its
#: bound for :func:`reduce_exact` to call the bound redundant.
REDUNDANT_BOUND_MARGIN: float = 1e-9
#: Budget of the certified rounding of ``c`` and ``b`` that :func:`reduce_exact`
#: may add, relative to the size of the set's data (it stops eliminating there).
ELIMINATION_ERR_RTOL: float = 1e-12
#: Smallest pivot, relative to the largest entry of its row, that
#: :func:`reduce_exact` eliminates with (partial pivoting).
ELIMINATION_PIVOT_TOL: float = 1e-3
#: Half-width of a factor's certified range, relative to its bound, below which
#: :meth:`HybridZonotope.remove_redundancy <setobs.HybridZonotope.remove_redundancy>`
#: replaces the factor by the range's centre, the half-width carried in ``c_err`` and
#: ``b_err`` (outward, so the set still contains the original).
PINNED_FACTOR_RTOL: float = 1e-11

# ---- studies (setobs.studies.baselines)
#: Measurement covariance of the Kalman baseline on noise-free scenarios, relative
#: to the squared increment radius (a Kalman gain needs a positive definite one).
KALMAN_MEASUREMENT_FLOOR: float = 1e-6

# ---- further set operations (setobs.geometry.operations, .relations, .measure)
#: Largest equality residual, relative to the data, that the generator matching
#: of the inner Pontryagin difference accepts (after least-squares refinement).
PONTRYAGIN_MATCH_RTOL: float = 1e-10
#: Set containment and equality are decided up to this distance, relative to
#: ``1 + ||k||_inf`` of the inequality tested (``Z subset P`` holds when every
#: certified support value is within it of its offset).
CONTAINMENT_RTOL: float = 1e-9

# ---- noise calibration (setobs.setmembership.calibrate)
#: Relative margin added to the LP optimum in the recommended bound (outward).
CALIBRATION_RTOL: float = 1e-6
#: Margin added to the recommended bound, relative to the record's spread (the
#: largest deviation of an output from the record's equilibrium): the accuracy of
#: the interior-point solve on the centred, scaled LP (tolerances 1e-10), by which
#: its optimum may undercut the true minimum. A noise-free record gets this, not 0.
CALIBRATION_ATOL: float = 1e-9
#: A solver's answer to the calibration LP is accepted when no row of the centred,
#: scaled LP is violated by more than this times ``1 + max |variable|``.
CALIBRATION_CHECK_TOL: float = 1e-7
#: Relative distance of a residual below the bound within which its sample counts as
#: active (``NoiseCalibration.active_samples``): the refined LP's accuracy is about
#: 1e-9, so a sample within 1e-6 of the bound is where the bound is attained.
CALIBRATION_ACTIVE_RTOL: float = 1e-6

# ---- nonlinear modular observer (setobs.nonlinear, setobs.analysis.modular)
#: Largest ``|f(0, 0)|``, ``|s(0)|``, ``|h(0, 0)|`` accepted as an equilibrium at
#: the origin (the power series expand there).
EQUILIBRIUM_ATOL: float = 1e-12
#: Newton's method (eqs. (32), (36)) stops when its step falls below this,
#: relative to the iterate's size (at least 1).
NEWTON_RTOL: float = 1e-12
#: An observer eigenvalue within this (relative to the largest eigenvalue's
#: modulus, at least 1) of a product of the linearization's eigenvalues is
#: resonant (Proposition 2, assumption 2).
RESONANCE_RTOL: float = 1e-9
#: A smallest divisor below this (relative like :data:`RESONANCE_RTOL`) is near
#: resonance: the series' coefficients grow like its inverse, and the modular design
#: warns (:class:`~setobs.exceptions.DesignWarning`).
NEAR_RESONANCE_RTOL: float = 1e-2
#: A linear part (``T0`` of (31), ``d Psi / d w`` of (35)) whose smallest singular
#: value is below this fraction of its largest is nearly singular: the modular design
#: warns (the inverse maps amplify by the inverse ratio).
ILL_CONDITIONED_RTOL: float = 1e-6
#: A residual of (31), (28) or (35) at the full order above this multiple of its
#: smallest over the lower orders grows with the order (``ModularDesign.diagnostics``).
RESIDUAL_GROWTH_FACTOR: float = 10.0
#: The nonlinear modular observer flags a step whose error estimate (the Gauss-Newton
#: correction of the model's output predictions to the data,
#: ``NonlinearModularObserver.consistency``; absolute, in the units of ``x`` and
#: ``w``) exceeds this. On runs with known truth the estimate was within a factor 2
#: of the true error (three systems, ``tests/observers/test_nonlinear_trust.py``).
TRUST_TOL: float = 1e-3
