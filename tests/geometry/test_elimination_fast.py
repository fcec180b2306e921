"""Constraint elimination without LPs: interval propagation and the
heuristics of every factor from one factorisation.

Oracles: the polytope's vertices from scipy's ``HalfspaceIntersection`` (the set is
given as ``H x <= 1``, its vertices computed apart from setobs), scipy's ``linprog``
over the factor set (written in the test), the eq. (A.8) QP solved per factor by
its own KKT system (``hausdorff_heuristic``) and by cvxpy, and closed forms.
"""

import numpy as np
import pytest
from scipy.optimize import linprog
from scipy.spatial import HalfspaceIntersection

from setobs import ConstrainedZonotope
from setobs.geometry import cz_from_hpolytope, eliminate_constraints
from setobs.geometry.reduction import (
    hausdorff_heuristic,
    hausdorff_heuristics,
    propagated_factor_ranges,
    relaxed_overshoots,
)

from ..conftest import random_cz


def sphere_polytope(m: int, seed: int = 0):
    """``{x in R^3 : H x <= 1}`` with ``m`` random unit normals (every row a facet:
    each plane touches the unit sphere, which lies inside) and its vertices."""
    rng = np.random.default_rng(seed)
    H = rng.normal(size=(m, 3))
    H /= np.linalg.norm(H, axis=1)[:, None]
    hs = HalfspaceIntersection(np.hstack([H, -np.ones((m, 1))]), np.zeros(3))
    return H, hs.intersections


def lp_range(A, b, h, j, drop_own=False):
    """``min`` and ``max`` of ``xi_j`` over ``{A xi = b, |xi| <= h}`` by scipy's linprog
    (with ``xi_j``'s own bound dropped if asked)."""
    bounds = [(-hk, hk) for hk in h]
    if drop_own:
        bounds[j] = (None, None)
    e = np.zeros(len(h))
    e[j] = 1.0
    lo = linprog(e, A_eq=A, b_eq=b, bounds=bounds, method="highs")
    hi = linprog(-e, A_eq=A, b_eq=b, bounds=bounds, method="highs")
    assert lo.status == 0 and hi.status == 0
    return lo.fun, -hi.fun


@pytest.mark.parametrize("target", [59, 45, 30, 10, 0])
def test_fast_elimination_contains_the_polytope(target):
    """The 60-facet polytope of the issue (63 generators, 60 constraints): after
    eliminating down to ``target`` constraints without an LP, every vertex is still in
    the set and every support value is at least the vertices' maximum."""
    H, V = sphere_polytope(60)
    Z = cz_from_hpolytope(H, np.ones(60))
    assert (Z.n_gen, Z.n_con) == (63, 60)
    R = eliminate_constraints(Z, target, method="fast")
    assert R.n_con <= target
    assert all(R.contains(v) for v in V)
    D = np.random.default_rng(1).normal(size=(40, 3))
    for d in D:
        assert R.support(d) >= float((V @ d).max()) - 1e-9 * (1.0 + np.abs(d).sum())
    assert np.isfinite(R.interval_hull().hi).all()


def test_fast_elimination_is_the_default_for_large_sets_and_close_to_the_lp_mode():
    """``auto`` takes the fast mode on the 63 x 60 set (it agrees with ``method="fast"``),
    and one eliminated constraint costs little width: the support excess over the
    polytope's (from its vertices) is below 0.05 of the unit sphere's radius in every
    direction, as is the LP mode's."""
    H, V = sphere_polytope(60)
    Z = cz_from_hpolytope(H, np.ones(60))
    R_auto = eliminate_constraints(Z, 59)
    R_fast = eliminate_constraints(Z, 59, method="fast")
    assert np.array_equal(R_auto.G, R_fast.G) and np.array_equal(R_auto.A, R_fast.A)
    R_lp = eliminate_constraints(Z, 59, method="lp")
    D = np.random.default_rng(2).normal(size=(30, 3))
    D /= np.linalg.norm(D, axis=1)[:, None]
    exact = (V @ D.T).max(axis=0)
    for R in (R_fast, R_lp):
        excess = np.array([R.support(d) for d in D]) - exact
        assert excess.min() >= -1e-9 and excess.max() < 0.05


def test_fast_elimination_of_a_redundant_bound_is_exact():
    """The square with the redundant slack ``|x1 + x2| <= 3``: the propagated range of
    the slack is [-2, 2], inside its bound, so the fast mode drops that bound and the
    result is the square (vertices by hand)."""
    Z = ConstrainedZonotope([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]], [0.0, 0.0],
                            A=[[1.0, 1.0, 1.0]], b=[0.0], h=[1.0, 1.0, 3.0])
    R = eliminate_constraints(Z, 0, method="fast")
    assert R.n_con == 0
    got = {tuple(np.round(v, 9) + 0.0) for v in R.vertices()}
    assert got == {(-1.0, -1.0), (-1.0, 1.0), (1.0, -1.0), (1.0, 1.0)}


def test_fast_elimination_with_unbounded_factors_stays_bounded():
    """A bounded set with unbounded factors in its rows (a line, ``x1 = x2``, cut by the
    box [-1, 1] x [-2, 2]): the unbounded factor goes exactly first, and the result
    contains the segment's end points and is bounded."""
    line = ConstrainedZonotope.affine_set([[1.0, -1.0]], [0.0])
    box = ConstrainedZonotope.from_box([-1.0, -2.0], [1.0, 2.0])
    Z = line.intersect(box)
    assert np.isinf(Z.h).any()
    R = eliminate_constraints(Z, 0, method="fast")
    assert R.n_con == 0 and np.isfinite(R.h).all()
    assert R.contains([1.0, 1.0]) and R.contains([-1.0, -1.0])
    hull = R.interval_hull()
    assert np.isfinite(hull.lo).all() and np.isfinite(hull.hi).all()


@pytest.mark.parametrize("seed", range(5))
def test_propagated_ranges_contain_the_lp_ranges(seed):
    """Interval propagation gives outer bounds ``E_j`` of each factor (against
    linprog over the factor set); where it calls a bound redundant (``R_j`` strictly
    inside ``(-h_j, h_j)``), the LP with that bound dropped stays inside it."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=8, n_c=3)
    lo, hi, R_lo, R_hi = propagated_factor_ranges(Z.A, Z.b, Z.h)
    for j in range(Z.n_gen):
        a, b = lp_range(Z.A, Z.b, Z.h, j)
        assert lo[j] <= a + 1e-9 and hi[j] >= b - 1e-9
        assert lo[j] >= -Z.h[j] and hi[j] <= Z.h[j]
        if -Z.h[j] < R_lo[j] and R_hi[j] < Z.h[j]:
            a, b = lp_range(Z.A, Z.b, Z.h, j, drop_own=True)
            assert -Z.h[j] - 1e-9 <= a and b <= Z.h[j] + 1e-9


def test_propagation_closed_form():
    """``xi_1 + xi_2 = 1.5`` with ``|xi| <= 1``: each factor is in [0.5, 1] (by hand)."""
    lo, hi, _, _ = propagated_factor_ranges([[1.0, 1.0]], [1.5], [1.0, 1.0])
    assert np.allclose(lo, [0.5, 0.5]) and np.allclose(hi, [1.0, 1.0])


@pytest.mark.parametrize("seed", range(4))
def test_all_heuristics_at_once_equal_the_qp_of_each_factor(seed):
    """:func:`hausdorff_heuristics` (one Schur complement) against eq. (A.8)'s KKT system
    solved for each factor on its own."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=3, n_g=9, n_c=4)
    r = rng.uniform(0.1, 2.0, size=Z.n_gen)
    r[2] = np.inf
    got = hausdorff_heuristics(Z, r)
    assert got[2] == np.inf
    for j in range(Z.n_gen):
        if j != 2:
            assert got[j] == pytest.approx(hausdorff_heuristic(Z, j, r[j]), rel=1e-8)


def test_bad_method_is_refused():
    Z = ConstrainedZonotope([[1.0, 1.0]], [0.0], A=[[1.0, 1.0]], b=[0.5])
    with pytest.raises(ValueError, match="method"):
        eliminate_constraints(Z, 0, method="interval")


@pytest.mark.parametrize("seed", range(4))
def test_compiled_overshoots_equal_the_lp_with_the_bound_dropped(seed):
    """The LP mode's overshoots on the compiled simplex (the relaxed set bounded by the
    one-sweep range, one warm state across candidates) against scipy's linprog over
    the factor set with ``xi_j``'s bound dropped (written in the test)."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=7, n_c=3)
    cand = np.arange(Z.n_gen)
    r = relaxed_overshoots(Z, cand)
    for j in cand:
        lo, hi = lp_range(Z.A, Z.b, Z.h, j, drop_own=True)
        expected = max(0.0, max(-lo, hi) / Z.h[j] - 1.0)
        assert r[j] == pytest.approx(expected, abs=1e-8)


def test_lp_mode_is_tighter_than_the_fast_mode_on_the_polytope():
    """Ten eliminations on the 60-facet polytope: with exact overshoots the support
    excess over the polytope's (Qhull vertices) stays below 0.005 on average, below
    the fast mode's, and both contain the polytope."""
    H, V = sphere_polytope(60)
    Z = cz_from_hpolytope(H, np.ones(60))
    D = np.random.default_rng(4).normal(size=(30, 3))
    D /= np.linalg.norm(D, axis=1)[:, None]
    exact = (V @ D.T).max(axis=0)
    ex = {}
    for method in ("lp", "fast"):
        R = eliminate_constraints(Z, 50, method=method)
        ex[method] = np.array([R.support(d) for d in D]) - exact
        assert ex[method].min() >= -1e-9
    assert ex["lp"].mean() < 0.005 and ex["lp"].mean() < ex["fast"].mean()


def _row_ranges_vectorised(A, b, lo, hi, b_err=None):
    """The one-sweep ranges in numpy, one ``(n_c, n_g)`` array per term (the form the
    compiled kernel replaced), written apart from it."""
    from setobs._rounding import UNIT_ROUNDOFF, gamma

    absA = np.abs(A)
    fin = np.isfinite(lo) & np.isfinite(hi)
    with np.errstate(invalid="ignore"):
        m = np.where(fin, 0.5 * (lo + hi), 0.0)
        r = np.where(fin, 0.5 * (hi - lo), 0.0)
    nz = A != 0.0
    S, Rr = A @ m, absA @ r
    n_inf = nz @ (~fin).astype(np.float64)
    err = 2.0 * gamma(A.shape[1] + 8) * (np.abs(b) + absA @ (np.abs(m) + r))
    if b_err is not None:
        err = err + b_err
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        centre = (b[:, None] - S[:, None] + A * m[None, :]) / A
        rad = (np.maximum(Rr[:, None] - absA * r[None, :], 0.0) + err[:, None]) / absA
        rad *= 1.0 + 4.0 * UNIT_ROUNDOFF
        rad = np.where(n_inf[:, None] - (nz & ~fin[None, :]) > 0.5, np.inf, rad)
        low = np.where(nz, centre - rad, -np.inf).max(axis=0, initial=-np.inf)
        upp = np.where(nz, centre + rad, np.inf).min(axis=0, initial=np.inf)
    return low, upp


@pytest.mark.parametrize("seed", range(3))
def test_the_compiled_propagation_equals_the_vectorised_formula(seed):
    """The compiled sweep against the vectorised numpy formula (written above) on random
    sparse rows with unbounded factors and an uncertain ``b``: equal up to the order of
    the rows' sums (1e-12 relative); and the propagated bounds hold the LP ranges."""
    from setobs._rounding import UNIT_ROUNDOFF, gamma
    from setobs.geometry._propagation import row_ranges

    rng = np.random.default_rng(seed)
    for _ in range(60):
        m, g = int(rng.integers(1, 7)), int(rng.integers(2, 12))
        A = rng.normal(size=(m, g)) * (rng.random((m, g)) < 0.6)
        h = rng.uniform(0.2, 2.0, g)
        h[rng.random(g) < 0.15] = np.inf
        b = A @ (rng.uniform(-0.5, 0.5, g) * np.minimum(h, 1.0))
        be = rng.uniform(0.0, 1e-3, m) if rng.random() < 0.5 else None
        got = row_ranges(A, b, -h, h, np.zeros(0) if be is None else be,
                         2.0 * gamma(g + 8), 1.0 + 4.0 * UNIT_ROUNDOFF)
        want = _row_ranges_vectorised(A, b, -h, h, be)
        for x, y in zip(got, want, strict=True):
            assert np.allclose(x, y, rtol=1e-12, atol=1e-14, equal_nan=True)
        if np.isfinite(h).all() and be is None:
            lo, hi, _, _ = propagated_factor_ranges(A, b, h)
            for j in range(g):
                a, c = lp_range(A, b, h, j)
                assert lo[j] <= a + 1e-9 and hi[j] >= c - 1e-9
