"""The geometry's LP queries on the compiled simplex: the interval hull's
batch (``FactorPolytope.minimize_many``, ``FixedStructureLP.bounded``), the phase-1
LP of emptiness and containment, and the closed-form hull of sets without
constraints.

Oracles: exact rational LPs (``tests.oracles.exact_lp_min``: every certified bound
must be at or below the exact optimum, and close to it), the exact extremes over the
factor polytope's rational vertices, and points known to lie in or outside the set.
"""

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from setobs import ConstrainedZonotope
from setobs.lp.factor import FactorPolytope
from tests.conftest import assert_hull_tight, random_cz
from tests.oracles import exact_lp_min

seeds = st.integers(0, 2**31 - 1)


def _exact_min(A, b, h, w):
    F = Fraction
    return exact_lp_min([F(float(v)) for v in w], [[F(float(v)) for v in r] for r in A],
                        [F(float(v)) for v in b], [F(-float(v)) for v in h],
                        [F(float(v)) for v in h])


@settings(max_examples=25, deadline=None)
@given(seeds)
def test_batch_bounds_are_certified_and_tight_against_exact_lps(seed):
    """Random bounded factor polytopes, some with a duplicated (redundant) row: every
    bound the batch calls solved is at or below the exact rational optimum and within
    1e-9 (relative) of it; the rows are all solved."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=int(rng.integers(3, 7)), n_c=int(rng.integers(1, 3)))
    A, b = Z.A, Z.b
    if rng.random() < 0.3:  # a redundant row: the artificial stays basic at zero
        A, b = np.vstack([A, 2.0 * A[:1]]), np.concatenate([b, 2.0 * b[:1]])
    fp = FactorPolytope(A, b, Z.h)
    W = rng.normal(size=(4, Z.n_gen))
    bounds, ok = fp.minimize_many(W)
    assert ok.all()
    for w, bound in zip(W, bounds, strict=True):
        exact = _exact_min(A, b, Z.h, w)
        assert Fraction(float(bound)) <= exact
        assert float(exact) - bound <= 1e-9 * (1.0 + abs(float(exact)))


def test_batch_solves_nothing_it_cannot_certify():
    """Inconsistent redundant rows (``xi_1 + xi_2 = 0`` and ``= 1``): nothing solved, so
    the hull goes to the reference path, which certifies the set empty. Unbounded
    factors and sets without rows are declined."""
    fp = FactorPolytope(np.array([[1.0, 1.0], [1.0, 1.0]]), np.array([0.0, 1.0]), np.ones(2))
    _, ok = fp.minimize_many(np.eye(2))
    assert not ok.any()
    Z = ConstrainedZonotope(np.eye(2), np.zeros(2), [[1.0, 1.0], [1.0, 1.0]], [0.0, 1.0])
    assert Z.is_empty()
    fp = FactorPolytope(np.array([[1.0, 1.0]]), np.array([0.5]), np.array([1.0, np.inf]))
    assert not fp.minimize_many(np.eye(2))[1].any()


@settings(max_examples=25, deadline=None)
@given(seeds)
def test_hull_contains_the_exact_extremes(seed):
    """The hull (now the batch) against the exact extremes over the rational vertices."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    assert_hull_tight(Z, Z.interval_hull())


@settings(max_examples=30, deadline=None)
@given(seeds)
def test_compiled_phase1_verdicts_against_exact_feasibility(seed):
    """Random sets moved away from or kept on a known point: the verdict is empty only
    when the exact rational LP is infeasible, and a non-empty verdict carries a
    witness within the tolerance of the normalised rows."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=int(rng.integers(3, 7)), n_c=int(rng.integers(1, 3)))
    shift = rng.uniform(0.0, 3.0)
    b = Z.b + shift * np.abs(Z.A).sum(axis=1)  # beyond the reach of |xi| <= h for large shifts
    fp = FactorPolytope(Z.A, b, Z.h)
    rep = fp.emptiness()
    try:
        _exact_min(Z.A, b, Z.h, np.zeros(Z.n_gen))
        feasible = True
    except ValueError:
        feasible = False
    if rep.empty:
        assert not feasible
    else:
        scale = np.maximum(np.abs(Z.A).max(axis=1), np.abs(b))
        viol = np.abs(Z.A @ rep.witness - b) / scale
        assert (np.abs(rep.witness) <= Z.h).all()
        assert viol.max() <= max(rep.violation_found, 0.0) * 4.0 + 1e-12
        if feasible:
            assert rep.violation_found <= 1e-9


def test_containment_of_known_points():
    """The triangle ``{xi in [-1, 1]^3 : sum xi = 1}`` mapped by ``G``: its vertices
    ``G (1, 1, -1)`` etc. are in, points beyond a facet are out (by hand)."""
    G = np.array([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]])
    Z = ConstrainedZonotope(G, [0.0, 0.0], A=[[1.0, 1.0, 1.0]], b=[1.0])
    for xi in ([1.0, 1.0, -1.0], [1.0, -1.0, 1.0], [-1.0, 1.0, 1.0]):
        assert Z.contains(G @ np.array(xi))
    assert not Z.contains([3.0, 0.0]) and not Z.contains([-2.5, -2.5])


@pytest.mark.parametrize("seed", range(6))
def test_zonotope_hull_closed_form_against_exact_sums(seed):
    """No constraints: ``c +- |G| h`` in exact rational arithmetic lies inside the box,
    within a few ulps of the ends; a row reached by an unbounded factor is infinite."""
    rng = np.random.default_rng(seed)
    n, m = 3, 7
    G = rng.normal(size=(n, m)) * 10.0 ** rng.uniform(-3, 3, size=(n, 1))
    c = rng.normal(size=n) * 100.0
    h = rng.uniform(0.1, 2.0, size=m)
    box = ConstrainedZonotope(G, c, h=h).interval_hull()
    for i in range(n):
        r = sum(abs(Fraction(float(G[i, j]))) * Fraction(float(h[j])) for j in range(m))
        lo, hi = Fraction(float(c[i])) - r, Fraction(float(c[i])) + r
        assert Fraction(box.lo[i]) <= lo and Fraction(box.hi[i]) >= hi
        tol = 1e-13 * float(r) + 4.0 * np.spacing(abs(c[i]) + float(r))  # (a few ulps)
        assert float(lo) - box.lo[i] <= tol and box.hi[i] - float(hi) <= tol
    G2 = np.array([[1.0, 0.0], [0.0, 2.0]])
    box = ConstrainedZonotope(G2, [1.0, 2.0], h=[np.inf, 1.0]).interval_hull()
    assert box.lo[0] == -np.inf and box.hi[0] == np.inf
    assert box.lo[1] <= 0.0 and box.hi[1] >= 4.0 and box.hi[1] - box.lo[1] < 4.0 + 1e-14


def test_large_polytopes_stay_on_highs():
    """Above COMPILED_MAX_ROWS rows the batch solves nothing (the dense simplex lost to
    HiGHS there, 1.07 s against 51 ms on a 320-row hull), and the hull is still tight
    (against scipy's linprog over the same factor set)."""
    from scipy.optimize import linprog

    from setobs.lp.factor import COMPILED_MAX_ROWS

    rng = np.random.default_rng(8)
    m = COMPILED_MAX_ROWS + 6
    Z = random_cz(rng, n=2, n_g=m + 10, n_c=m)
    assert not FactorPolytope(Z.A, Z.b, Z.h).minimize_many(Z.G)[1].any()
    box = Z.interval_hull()
    for i in range(2):
        r = linprog(Z.G[i], A_eq=Z.A, b_eq=Z.b, bounds=[(-h, h) for h in Z.h], method="highs")
        assert r.status == 0
        lo = r.fun + Z.c[i]
        assert box.lo[i] <= lo + 1e-9 and lo - box.lo[i] <= 1e-7 * (1.0 + abs(lo))
