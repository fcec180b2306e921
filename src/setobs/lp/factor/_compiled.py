"""The factor polytope's LPs by the compiled simplex (:mod:`setobs.lp.fastlp`): the batch of
a hull, the last retry of a single LP, and the relaxed LP."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from ..._lazy import lazy_module
from ...tolerances import FASTLP_GAP_RTOL
from ._reports import LPResult

if TYPE_CHECKING:
    from .polytope import FactorPolytope

# the one certificate (compiled; loads with the first certified bound)
_certificate = lazy_module("setobs.lp.certificate")

__all__ = ["COMPILED_MAX_ROWS", "compiled_batch", "compiled_relaxed", "compiled_retry"]

#: Largest number of constraint rows for which the factor polytope's queries use the
#: compiled dense simplex (the hull batch, the phase-1 LP). Above it HiGHS's sparse
#: simplex wins (development runs, not in a results file: on the convex hull of two
#: random sets with 100 rows the hull took 20 ms compiled against 7 ms, with 320 rows
#: 1.07 s against 51 ms; below 64 rows the compiled path was 2-9x faster).
COMPILED_MAX_ROWS: int = 64


def compiled_batch(fp: FactorPolytope, W: NDArray[np.float64],
                   gaps: NDArray[np.float64] | None = None
                  ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Certified lower bounds of ``min W[i]^T xi`` for all ``i`` by the compiled
    simplex (:meth:`FixedStructureLP.bounded <setobs.lp.fastlp.FixedStructureLP.bounded>`:
    one dual simplex warm from the previous objective's basis, each multiplier
    certified like the HiGHS path's). For polytopes with every bound finite and
    1 to :data:`COMPILED_MAX_ROWS` rows; elsewhere nothing is solved.
    (Parameters as for the method of :class:`FactorPolytope` it serves.)
    """
    n_lp = W.shape[0]
    if fp.n_c == 0 or fp.n_c > COMPILED_MAX_ROWS or fp.any_unbounded or not n_lp:
        return np.full(n_lp, -np.inf), np.zeros(n_lp, dtype=bool)
    from ..fastlp import FixedStructureLP

    with fp.lock:
        lp = FixedStructureLP.bounded(fp.A, W)
        if fp.b_err is None:
            return lp.minimize_all(fp.b, np.concatenate([fp.h, np.zeros(fp.n_c)]),
                                   gaps=gaps)
        bounds, ok, ys, objs = lp.minimize_all(
            fp.b, np.concatenate([fp.h, np.zeros(fp.n_c)]), b_err=fp.b_err,
            return_duals=True, gaps=gaps)
        # The exact rows' multiplier pays |y|^T b_err for the rows' uncertainty; where
        # that is more than the fast path's gap, the interval-row LP of minimize may
        # be tighter (a thin set of the soundness campaign: 2e-5 of a 0.33 width).
        if ok.any():  # (the multipliers of unsolved LPs are the buffer's leftovers)
            cost = np.abs(ys[ok, :fp.n_c]) @ fp.b_err
            ok[ok] = cost <= FASTLP_GAP_RTOL * (1.0 + np.abs(objs[ok]))
        return bounds, ok


def compiled_retry(fp: FactorPolytope, w: NDArray[np.float64], w_err: NDArray[np.float64] | None,
                   w_pair: tuple[NDArray[np.float64], NDArray[np.float64]] | None
                  ) -> LPResult | None:
    """Last retry: the compiled simplex of :mod:`setobs.lp.fastlp`, certified here.
    (Parameters as for the method of :class:`FactorPolytope` it serves.)
    """
    from ..fastlp import FixedStructureLP

    lp = FixedStructureLP(fp.A, w[None, :], fp.unbounded, fp.unbounded_radius)
    if not lp.usable:
        return None
    bounds, ok, ys, objs = lp.minimize_all(fp.b, fp.h, b_err=fp.b_err,
                                           return_duals=True)
    if not ok[0] or not np.isfinite(bounds[0]):
        return None
    bound = fp.certify(w, ys[0], w_err, w_pair)
    if not np.isfinite(bound):
        return None
    return LPResult(bound, float(objs[0]), None, "optimal")


def compiled_relaxed(fp: FactorPolytope, w, delta, w_err, w_pair) -> LPResult | None:
    """The relaxed LP by the compiled simplex: slack factors ``|s| <= delta`` turn
    ``|A xi - b| <= delta`` into ``A xi + s = b``, a fixed-structure LP."""
    from ..fastlp import FixedStructureLP

    A2 = np.hstack([fp.A, np.eye(fp.n_c)])
    h2 = np.concatenate([fp.h, delta])
    w2 = np.concatenate([w, np.zeros(fp.n_c)])
    lp = FixedStructureLP(A2, w2[None, :], np.isinf(h2), fp.unbounded_radius)
    if not lp.usable:
        return None
    bounds, ok, ys, objs = lp.minimize_all(fp.b, h2, b_err=fp.b_err,
                                           return_duals=True)
    if not ok[0] or not np.isfinite(bounds[0]):
        return None
    werr2 = None if w_err is None else np.concatenate([w_err, np.zeros(fp.n_c)])
    pair2 = None if w_pair is None else (
        np.hstack([w_pair[0], np.zeros((w_pair[0].shape[0], fp.n_c))]), w_pair[1])
    bound, _ = _certificate.lagrangian_lower_bound(w2, A2, fp.b, h2, ys[0], w_err=werr2,
                                      unbounded_radius=fp.unbounded_radius, w_pair=pair2,
                                      b_err=fp.b_err)
    if not np.isfinite(bound):
        return None
    return LPResult(bound, float(objs[0]), None, "optimal")
