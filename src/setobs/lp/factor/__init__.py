"""The factor polytope's LP: certified linear optimisation over a constrained zonotope's factors.

Every LP query on a constrained zonotope reduces to optimising a linear
function over its *factor polytope*

.. math::  F = \\{\\xi \\in \\mathbb{R}^{n_g} : A\\xi = b,\\ |\\xi_j| \\le h_j\\},
           \\qquad h_j \\in [0, +\\infty].

This module solves those LPs with HiGHS (one model per polytope, built once and
re-solved with a new objective, warm-started from the previous basis; set up in
:mod:`setobs.lp.highs`) or the compiled simplex (:mod:`setobs.lp.fastlp`) and
turns the solver's answer into a **certified** bound.

Certification
-------------
Every bound is the certificate of :mod:`setobs.lp.certificate` (weak duality
with its rounding analysis) for the solver's multiplier, over ``lo = -h``,
``hi = h``: the solver's dual only decides how *tight* the bound is, never
whether it is valid, and the bound holds for the *stored* data regardless of
solver tolerances (primal feasibility of the solver's point is never relied
upon). Unbounded factors (``h_j = inf``) are covered for ``|xi_j| <=
unbounded_radius`` once their reduced costs are negligible, else the bound is
``-inf``; a right-hand side known only to ``+- b_err`` (rounding of the
operations that formed it, representation error of measured data) is covered too.

Infeasibility reported by the solver is never trusted either: emptiness is
decided by a phase-1 LP whose dual gives a certified lower bound on the
smallest constraint violation (see :meth:`FactorPolytope.emptiness`).

A solver's bad day never aborts a query: an undecided HiGHS status is retried
with other settings (a fresh unscaled model, default tolerances with the
primal simplex, the interior-point method with crossover, a restart with the
objective perturbed -- certified for the true one), with the compiled simplex of
:mod:`setobs.lp.fastlp`, and with the rows as the intervals
``[b - b_err, b + b_err]`` the certificate covers (exact for the certified set
when decided; unbounded factors are pivoted out first, so that rows of an
unknown initial state of size 1e9 do not reach HiGHS); if every attempt fails,
the best certified
bound of any multiplier seen (at worst ``y = 0``, i.e. ``-sum h_j |w_j|`` or
``-inf``) is returned with status ``"fallback"``: wider, still outer.

Layout
------
One file per job behind the one entry point, :class:`FactorPolytope`
(:mod:`.polytope`: the data, the HiGHS model, the certificates): the HiGHS retry ladder
(:mod:`._ladder`), the compiled simplex's batch and retries (:mod:`._compiled`), the rows
as intervals of ``b_err`` (:mod:`._interval_rows`), the phase-1 emptiness test and the
relaxed rows (:mod:`._phase1`), the exact row scales (:mod:`._scaling`), and the answers
(:mod:`._reports`).
"""

from ._compiled import COMPILED_MAX_ROWS
from ._reports import EmptinessReport, LPResult
from ._scaling import equilibration
from .polytope import FactorPolytope

__all__ = ["COMPILED_MAX_ROWS", "EmptinessReport", "FactorPolytope", "LPResult", "equilibration"]
