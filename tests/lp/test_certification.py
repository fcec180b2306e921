"""The certificate itself: valid for any multiplier, and solver failures are never silent."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from setobs import ConstrainedZonotope
from setobs.exceptions import SolverWarning
from setobs.geometry.zonotope import factor_polytope
from setobs.lp.certificate import lagrangian_lower_bound
from setobs.lp.factor import FactorPolytope
from tests.conftest import (
    assert_hull_tight,
    cripple_highs,
    disable_compiled_lps,
    exact_extremes,
    random_cz,
)
from tests.oracles import assert_outward_sums, outward_sum_cases

seeds = st.integers(0, 2**32 - 1)


@given(seeds)
def test_bound_is_valid_for_arbitrary_multipliers(seed):
    """Weak duality: a garbage multiplier gives a loose but valid bound."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    d = rng.normal(size=2)
    true_min = exact_extremes(Z, d)[0] - Fraction(float(d @ Z.c))  # min (G^T d)^T xi, exact
    w = Z.G.T @ d
    werr = 4 * np.finfo(float).eps * (np.abs(Z.G).T @ np.abs(d))
    for y in (rng.normal(size=2) * 10.0 ** rng.uniform(-3, 3), np.zeros(2)):
        bound, _ = lagrangian_lower_bound(w, Z.A, Z.b, Z.h, y, w_err=werr,
                                          w_pair=(Z.G, d))
        assert Fraction(bound) <= true_min


@given(seeds)
def test_exactly_rounded_reduced_costs_give_a_valid_and_tighter_bound(seed):
    """``exact_residual=True`` against the Lagrangian ``L(y) = y^T b - sum_j h_j |r_j|``
    evaluated in rationals, for multipliers of size up to 1e6 on 40 rows near an
    optimal basis (reduced costs zero on 40 columns, where the forward error bound
    ``gamma(82) |A|^T |y|`` of the float residual dominates):
    the bound stays below ``L(y)`` (so below the minimum, by weak duality), and it
    loses at most a tenth of what the forward-error bound loses."""
    rng = np.random.default_rng(seed)
    n_c, n_g = 40, 70
    A = rng.normal(size=(n_c, n_g))
    b = A @ rng.uniform(-0.5, 0.5, n_g)
    h = rng.uniform(0.5, 2.0, n_g)
    y = rng.normal(size=n_c) * 10.0 ** rng.uniform(3, 6)
    # near an optimal basis: reduced costs zero (to rounding) on n_c columns
    w = A.T @ y + np.where(np.arange(n_g) < n_c, 0.0, rng.normal(size=n_g))
    Fr = Fraction
    exact = sum(Fr(float(yi)) * Fr(float(bi)) for yi, bi in zip(y, b, strict=True)) - sum(
        Fr(float(h[j])) * abs(Fr(float(w[j])) - sum(Fr(float(A[i, j])) * Fr(float(y[i]))
                                                    for i in range(n_c)))
        for j in range(n_g))
    fast, _ = lagrangian_lower_bound(w, A, b, h, y)
    tight, _ = lagrangian_lower_bound(w, A, b, h, y, exact_residual=True)
    assert Fraction(tight) <= exact and Fraction(fast) <= exact
    assert exact - Fraction(tight) <= (exact - Fraction(fast)) / 10


@given(seeds)
def test_sloppy_solver_duals_still_give_outer_bounds(seed):
    """Perturb the solver's optimal duals (as a sloppy solver would): still outer."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    fp = FactorPolytope(Z.A, Z.b, Z.h)
    for i in range(2):
        out = fp.minimize(Z.G[i])
        hs = fp.highs_model()
        y = np.asarray(hs.getSolution().row_dual) * fp.objective_scale(Z.G[i])
        e = np.zeros(2)
        e[i] = 1.0
        exact_min = exact_extremes(Z, e)[0] - Fraction(float(Z.c[i]))
        for eps in (1e-9, 1e-6, 1e-3):
            noisy = y + eps * rng.normal(size=y.size)
            bound = fp.certify(Z.G[i], noisy)
            assert Fraction(bound) <= exact_min
            assert bound >= out.bound - 20 * eps * (np.abs(Z.A).sum() + np.abs(Z.b).sum()
                                                    + Z.h.sum()) - 1e-9


def test_unbounded_factor_bound_covers_points_within_radius():
    # x = xi_1 (free), constraint xi_1 - 3 xi_2 = 0.1, |xi_2| <= 1 -> x in [-2.9, 3.1].
    Z = ConstrainedZonotope([[1.0, 0.0]], [0.0], [[1.0, -3.0]], [0.1], [np.inf, 1.0])
    box = Z.interval_hull()
    assert box.lo[0] <= -2.9 and box.hi[0] >= 3.1
    assert box.hi[0] - 3.1 < 1e-12 and -2.9 - box.lo[0] < 1e-12


def test_solver_failure_is_retried_with_the_compiled_simplex(monkeypatch):
    """HiGHS fails under every setting: the compiled simplex gives the tight answer."""
    cripple_highs(monkeypatch)
    Z = ConstrainedZonotope(np.eye(3), np.zeros(3), [[1.0, 1.0, 1.0]], [0.5])
    box = Z.interval_hull()  # no warning: a retry solved it
    # exact hull of {xi in [-1, 1]^3 : sum xi = 0.5}: each xi_i in [-1, 1]
    np.testing.assert_allclose(box.lo, -1.0, atol=1e-12)
    np.testing.assert_allclose(box.hi, 1.0, atol=1e-12)
    assert (box.lo <= -1.0).all() and (box.hi >= 1.0).all()


@given(seeds)
def test_total_solver_failure_gives_a_wider_certified_box_and_a_warning(seed):
    """Every attempt fails: the answer is still outer (exact oracle), flagged by a warning."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=5, n_c=2)
    with pytest.MonkeyPatch.context() as mp:
        cripple_highs(mp)
        disable_compiled_lps(mp)
        with pytest.warns(SolverWarning, match="failed under every solver setting"):
            box = Z.interval_hull()
        assert factor_polytope(Z).fallbacks > 0
    for i in range(2):
        e = np.zeros(2)
        e[i] = 1.0
        lo, hi = exact_extremes(Z, e)
        assert Fraction(box.lo[i]) <= lo and Fraction(box.hi[i]) >= hi


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_an_lp_no_setting_decides_is_decided_by_the_perturbed_restart(seed, monkeypatch):
    """HiGHS stalls on the objective itself under every setting (a degenerate tie it
    cannot break), the compiled simplex is unavailable: the restart with the
    objective perturbed finds a basis, and the bound certified for the true
    objective from it is exact (rational oracle), not a fallback."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=2, n_g=6, n_c=2)
    made: list[np.ndarray] = []
    real_perturbed, real_solve = FactorPolytope.perturbed_objective, FactorPolytope.solve_objective

    def perturbed(self, w):
        made.append(out := real_perturbed(self, w))
        return out

    def stalling(self, hs, w, scale):
        if any(w is m for m in made):
            assert np.any(w != made[-1] * 0.0)  # (a perturbed objective reaches HiGHS)
            return real_solve(self, hs, w, scale)
        return "undecided"

    monkeypatch.setattr(FactorPolytope, "perturbed_objective", perturbed)
    monkeypatch.setattr(FactorPolytope, "solve_objective", stalling)
    disable_compiled_lps(monkeypatch)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error", SolverWarning)
        box = Z.interval_hull()
    assert made and factor_polytope(Z).fallbacks == 0
    assert_hull_tight(Z, box)


def test_highs_infeasible_claim_is_checked(monkeypatch):
    """If HiGHS claims infeasibility on a feasible set, we must not report it empty."""
    Z = ConstrainedZonotope(np.eye(2), np.zeros(2), [[1.0, 1.0]], [0.5])
    fp = factor_polytope(Z)
    real_solve = FactorPolytope.solve_objective

    def lying_solve(self, hs, w, scale):
        real_solve(self, hs, w, scale)
        return "infeasible"

    monkeypatch.setattr(FactorPolytope, "solve_objective", lying_solve)
    out = fp.minimize(np.array([1.0, 0.0]))
    # Relaxed-and-certified: still a valid bound for min xi_1 = -0.5.
    assert out.bound <= -0.5 and out.bound > -0.5 - 1e-6


@given(seeds)
def test_certificates_with_unbounded_factors_against_exact_rational_lps(seed):
    """h = inf: the double-double refinement and the radius term, checked exactly.

    Unbounded factors pinned by the constraints (A_U of full column rank), so the
    exact minimum is finite; it is computed in rational arithmetic (tests/oracles.py).
    The certificate of any multiplier (HiGHS's duals, perturbed ones, arbitrary ones)
    must be <= it, and the solver-based bound within 1e-9 of it.
    """
    from tests.oracles import exact_lp_min

    rng = np.random.default_rng(seed)
    f = int(rng.integers(1, 3))
    nb = int(rng.integers(2, 6))
    m = f + int(rng.integers(1, 3))
    A = rng.normal(size=(m, f + nb)) * 10.0 ** rng.uniform(-3, 3, size=(1, f + nb))
    h = np.concatenate([np.full(f, np.inf), rng.uniform(0.2, 2.0, nb)])
    xi0 = np.concatenate([rng.normal(size=f) * 10.0 ** rng.uniform(-2, 4),
                          rng.uniform(-0.8, 0.8, nb) * h[f:]])
    b = A @ xi0
    w = rng.normal(size=f + nb)
    Af = [[Fraction(float(v)) for v in row] for row in A]
    bf = [Fraction(float(v)) for v in b]
    lo = [None] * f + [-Fraction(float(v)) for v in h[f:]]
    hi = [None] * f + [Fraction(float(v)) for v in h[f:]]
    try:
        exact = exact_lp_min([Fraction(float(v)) for v in w], Af, bf, lo, hi)
    except ValueError:  # b rounded: the stored data can be infeasible; nothing to check
        return
    if exact is None:  # unbounded below: certificates must say -inf
        assert FactorPolytope(A, b, h).minimize(w).bound == -np.inf
        return
    out = FactorPolytope(A, b, h).minimize(w)
    assert Fraction(out.bound) <= exact
    assert float(exact) - out.bound <= 1e-9 * (1.0 + abs(float(exact)))
    hs = FactorPolytope(A, b, h)
    hs.minimize(w)
    y = np.asarray(hs.highs_model().getSolution().row_dual)
    for yy in (y, y + 1e-3 * rng.normal(size=m), rng.normal(size=m)):
        for exact_residual in (False, True):
            bound, _ = lagrangian_lower_bound(w, A, b, h, yy.copy(),
                                              exact_residual=exact_residual)
            assert bound == -np.inf or Fraction(bound) <= exact


def test_outward_interval_contains_the_exact_sums():
    """``[c + low, c + upp]`` widened by ``c_err``: checked in exact rational arithmetic."""
    from setobs._rounding import outward_interval

    c, e, low, upp = outward_sum_cases(8)
    lo, hi = outward_interval(c, e, low, upp)
    assert_outward_sums(lo, hi, c, e, low, upp)
    # coordinates without an offset keep the (rounded) centre
    lo2, hi2 = outward_interval(c, e, low, upp, offset=np.zeros(200, bool))
    assert np.all(lo2[e == 0] == c[e == 0]) and np.all(hi2[e == 0] == c[e == 0])
    assert np.all(lo2[e > 0] < c[e > 0]) and np.all(hi2[e > 0] > c[e > 0])


def test_an_optimal_answer_with_an_open_gap_is_not_taken_as_exact():
    """A set of the randomized soundness campaign (seed 72, window 20, k = 235: states
    of 1e4 pinned to 1e-7 by 20 steps of three outputs, a thin factor polytope of 61
    factors and 60 rows). For one direction HiGHS answered "optimal" with a
    certified bound 2.7e-4 below its own objective (0.1 % of the width), and that
    was reported as exact; for another every setting failed and the interval-row LP
    left a gap of 1.3e-6 that its basis duals close. Oracle: scipy's HiGHS (dual
    simplex, tolerances 1e-10) on the rows as inequality pairs ``|A xi - b| <= b_err``."""
    from pathlib import Path

    from scipy.optimize import linprog

    from setobs.geometry.zonotope import hull_with_status, trusted_cz

    z = np.load(Path(__file__).resolve().parents[1] / "data" / "regressions"
                / "window_open_gap_set.npz")
    A, b, h, be, G = z["A"], z["b"], z["h"], z["b_err"], z["G"]
    Z = trusted_cz(G, z["c"], A, b, h, 1e8, z["c_err"], be)
    box, fell_back = hull_with_status(Z)
    assert not fell_back
    for i in range(G.shape[0]):
        ext = []
        for sgn in (1.0, -1.0):
            r = linprog(sgn * G[i], A_ub=np.vstack([A, -A]), b_ub=np.r_[b + be, be - b],
                        bounds=list(zip(-h, h, strict=True)), method="highs-ds",
                        options={"primal_feasibility_tolerance": 1e-10,
                                 "dual_feasibility_tolerance": 1e-10})
            assert r.status == 0
            ext.append(z["c"][i] + sgn * r.fun)
        tol = 1e-9 * (1.0 + abs(ext[0]))
        assert box.lo[i] <= ext[0] + tol and box.hi[i] >= ext[1] - tol
        if i == 5:  # the disturbance coordinate of the open gap (width 0.33)
            assert ext[0] - box.lo[i] < 1e-6 and box.hi[i] - ext[1] < 1e-6


@pytest.mark.parametrize("seed", range(6))
def test_an_early_stopped_hull_is_outer_and_within_twice_its_gap(seed):
    """``hull_with_status(Z, gap)``: each bound may stop within its coordinate's gap of
    the exact one; against the rational LP oracle every bound is outer, and each
    interval at most twice its gap wider (a gap of a tenth of the width, so the simplex
    stops early); a wrong gap is refused."""
    from setobs.exceptions import InvalidValueError
    from setobs.geometry.zonotope import hull_with_status

    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=3, n_g=7, n_c=2)
    exact = [exact_extremes(Z, np.eye(3)[i]) for i in range(3)]
    width = np.array([float(hi - lo) for lo, hi in exact])
    box, _ = hull_with_status(Z, 0.1 * width)
    for i, (lo, hi) in enumerate(exact):
        assert Fraction(box.lo[i]) <= lo and Fraction(box.hi[i]) >= hi
        assert (box.hi[i] - box.lo[i]) - width[i] <= 0.2 * width[i] * (1 + 1e-9) + 1e-12
    with pytest.raises(InvalidValueError, match="gap must be 3 finite nonnegative"):
        hull_with_status(Z, [0.1, -1.0, 0.1])
