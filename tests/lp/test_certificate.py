"""The one certificate: below the exact minimum for any multiplier, tight for optimal ones,
and compiled bit for bit as written.

Oracles: exact rational LPs (``tests.oracles.exact_lp_min``) over the stored data
(and over corners of the ``b_err`` / ``w_err`` boxes the bound claims to cover);
scipy's HiGHS for optimal multipliers; the certificate's own text run by the
Python interpreter (``NUMBA_DISABLE_JIT=1``) for the compiled twin.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import linprog

from setobs.lp.certificate import certified_lower_bound, lower_bound
from tests.lp.certificate_cases import run_all
from tests.oracles import exact_lp_min

ROOT = Path(__file__).resolve().parents[2]


def test_the_compiled_certificate_is_its_text_bit_for_bit():
    """Every bound, slack and refined multiplier of 160 cases (unbounded columns,
    ``b_err``, ``w_err``, exact objectives, exact reduced costs) agrees to the last
    bit between the compiled kernel and its source interpreted by Python."""
    script = ("import json, sys, numba; from tests.lp.certificate_cases import run_all; "
              "json.dump([bool(numba.config.DISABLE_JIT), run_all()], sys.stdout)")
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    out = subprocess.run([sys.executable, "-c", script], cwd=ROOT, env=env, check=True,
                         capture_output=True, text=True, timeout=600)
    jit_disabled, rows = json.loads(out.stdout)
    assert jit_disabled  # (the other side really is the text, interpreted)
    assert hasattr(lower_bound, "py_func")  # (and this side the compiled kernel)
    interpreted = [(r[0], r[1], r[2]) for r in rows]
    compiled = [(r[0], r[1], r[2]) for r in run_all()]
    assert len(compiled) == 160
    mismatches = [i for i, (a, b) in enumerate(zip(compiled, interpreted, strict=True))
                  if a != b]
    assert mismatches == []
    # (the battery is not vacuous: most bounds are finite, some are -inf)
    finite = sum(float.fromhex(r[0]) > -np.inf for r in compiled)
    assert 100 <= finite < 160


def test_the_dense_and_the_column_forms_of_a_give_the_same_bound():
    """With ``A`` dense as well (the simplex's and the factor polytope's LPs) the reduced
    costs are summed row by row: the same terms in the same order as the column loop,
    so every bound, slack and multiplier is the same value."""
    from tests.lp.certificate_cases import cases

    compared = 0
    for args in cases():
        if args[-1].size == 0:
            continue
        dense = list(args)
        dense[7] = args[7].copy()
        column = list(args)
        column[7] = args[7].copy()
        column[-1] = np.zeros((0, 0))
        bd, sd = lower_bound(*dense)
        bc, sc = lower_bound(*column)
        assert bd == bc and sd == sc
        np.testing.assert_array_equal(dense[7], column[7])
        compared += 1
    assert compared == 80


def _random_lp(rng, one_sided: bool):
    m = int(rng.integers(1, 4))
    n = m + int(rng.integers(1, 5))
    A = rng.normal(size=(m, n)) * 10.0 ** rng.uniform(-2, 2, size=(1, n))
    lo = -rng.uniform(0.1, 2.0, n)
    hi = rng.uniform(0.1, 2.0, n)
    shift = rng.uniform(-1.0, 1.0, n)  # (asymmetric boxes, some not containing 0)
    lo, hi = lo + shift, hi + shift
    if one_sided:
        hi[0] = np.inf  # (one infinite side: the certificate must handle it soundly)
    x = lo + rng.uniform(0.2, 0.8, n) * (np.minimum(hi, lo + 4.0) - lo)
    b = A @ x
    w = rng.normal(size=n)
    return A, b, lo, hi, w


def _exact_min(A, b, lo, hi, w):
    F = Fraction
    try:
        return exact_lp_min([F(float(v)) for v in w], [[F(float(v)) for v in r] for r in A],
                            [F(float(v)) for v in b],
                            [None if np.isinf(v) else F(float(v)) for v in lo],
                            [None if np.isinf(v) else F(float(v)) for v in hi])
    except ValueError:  # (b rounded: the stored LP may be infeasible)
        return None


def _duals(A, b, lo, hi, w):
    res = linprog(w, A_eq=A, b_eq=b, bounds=list(zip(lo, hi, strict=True)), method="highs",
                  options={"primal_feasibility_tolerance": 1e-10,
                           "dual_feasibility_tolerance": 1e-10})
    return res.eqlin.marginals if res.status == 0 else None


@pytest.mark.parametrize("seed", range(40))
def test_the_bound_is_below_the_exact_minimum_and_tight_for_optimal_duals(seed):
    rng = np.random.default_rng(seed)
    A, b, lo, hi, w = _random_lp(rng, one_sided=seed % 4 == 3)
    exact = _exact_min(A, b, lo, hi, w)
    if exact is None:
        return
    y_opt = _duals(A, b, lo, hi, w)
    assert y_opt is not None
    one_sided = np.isinf(hi).any()
    for exact_residual in (False, True):
        bound, _, _ = certified_lower_bound(w, A, b, lo, hi, y_opt,
                                            exact_residual=exact_residual)
        if one_sided and bound == -np.inf:
            # (a column bounded on one side whose reduced cost is zero to rounding:
            # its sign cannot be certified, and -inf is the outer answer)
            continue
        assert Fraction(bound) <= exact
        assert float(exact) - bound <= 1e-9 * (1.0 + abs(float(exact)))
        for scale in (1e-8, 1e-3, 1.0, 30.0):
            y = y_opt + scale * rng.normal(size=y_opt.size)
            bound, _, _ = certified_lower_bound(w, A, b, lo, hi, y,
                                                exact_residual=exact_residual)
            assert bound == -np.inf or Fraction(bound) <= exact


@pytest.mark.parametrize("seed", range(12))
def test_the_bound_covers_every_right_hand_side_and_objective_in_their_error_boxes(seed):
    """``b_err`` and ``w_err`` are claims: the bound must lie below the exact minimum
    of every LP with ``b`` and ``w`` at corners of those boxes (errors far above
    rounding, so a missing term would show)."""
    rng = np.random.default_rng(100 + seed)
    A, b, lo, hi, w = _random_lp(rng, one_sided=False)
    b_err = 1e-3 * (1.0 + np.abs(b))
    w_err = 1e-3 * (1.0 + np.abs(w))
    y = _duals(A, b, lo, hi, w)
    if y is None:
        return
    bound, _, _ = certified_lower_bound(w, A, b, lo, hi, y, b_err=b_err, w_err=w_err)
    assert np.isfinite(bound)
    checked = 0
    for _ in range(12):
        sb = rng.choice([-1.0, 1.0], size=b.size)
        sw = rng.choice([-1.0, 1.0], size=w.size)
        exact = _exact_min(A, b + sb * b_err, lo, hi, w + sw * w_err)
        if exact is not None:
            checked += 1
            assert Fraction(bound) <= exact
    assert checked > 0


def test_a_column_bounded_on_one_side_is_certified_at_its_bound():
    """``x_0 >= 0`` only, with a positive reduced cost at the optimum: a finite bound
    equal to the exact minimum (to 1e-12); with the objective's sign flipped the
    column has no certified sign and the bound is ``-inf`` (the LP is unbounded)."""
    A = np.array([[1.0, 1.0, 0.5]])
    b = np.array([0.7])
    lo = np.array([0.0, -1.0, -1.0])
    hi = np.array([np.inf, 1.0, 1.0])
    w = np.array([2.0, 1.0, -0.25])
    exact = _exact_min(A, b, lo, hi, w)
    bound, _, _ = certified_lower_bound(w, A, b, lo, hi, _duals(A, b, lo, hi, w))
    assert np.isfinite(bound) and Fraction(bound) <= exact
    assert float(exact) - bound <= 1e-12
    bound, _, _ = certified_lower_bound(-w, A, b, lo, hi, np.array([0.3]))
    assert bound == -np.inf


def test_an_exact_objective_product_is_used_exactly():
    """``w = M^T v`` given as a pair: the bound is for the exact objective (checked
    against the rational LP with ``M^T v`` in Fractions), with a free column whose
    reduced cost the refinement brings to zero."""
    A = np.array([[1.0, 1.0, 0.0], [0.0, 1.0, 1.0]])
    lo = np.array([-np.inf, -1.0, -1.0])
    hi = np.array([np.inf, 1.0, 1.0])
    b = np.array([0.3, 0.2])
    M = np.array([[0.1, 0.3, 0.7], [0.2, -0.6, 0.4]])
    v = np.array([1.0, 0.5])
    w = M.T @ v
    F = Fraction
    w_exact = [sum(F(float(M[i, j])) * F(float(v[i])) for i in range(2)) for j in range(3)]
    exact = exact_lp_min(w_exact, [[F(float(a)) for a in r] for r in A],
                         [F(float(a)) for a in b], [None, F(-1), F(-1)], [None, F(1), F(1)])
    y = _duals(A, b, lo, hi, w)
    for exact_residual in (False, True):
        bound, _, _ = certified_lower_bound(w, A, b, lo, hi, y, w_pair=(M, v),
                                            exact_residual=exact_residual)
        assert np.isfinite(bound) and Fraction(bound) <= exact
        assert float(exact) - bound <= 1e-9


def test_data_beyond_double_precision_certify_nothing_and_never_nan():
    A = np.array([[1e200, 1e-200], [1.0, 1e300]])
    b = np.array([1e300, 1e300])
    lo, hi = np.full(2, -1e300), np.full(2, 1e300)
    w = np.array([1e300, -1e300])
    for y in (np.array([1e200, -1e200]), np.array([np.inf, 0.0]), np.array([1.0, 1.0])):
        bound, _, slack = certified_lower_bound(w, A, b, lo, hi, y)
        assert not np.isnan(bound) and not np.isnan(slack)
        assert bound <= -1e300 or bound == -np.inf


# ---------------------------------------------------------- shapes of the entry points
def test_mismatched_shapes_are_refused_by_name():
    # shared/data/regressions/certificate_shapes.py: a short lo / hi was read past its
    # end by the compiled certificate, and a long b gave a "certified" 6.0 for an LP
    # whose optimum is 1
    import setobs as so
    from setobs.lp import FactorPolytope, FixedStructureLP
    from setobs.lp.certificate import lagrangian_lower_bound

    A, b, w = np.array([[1.0, 1.0, 1.0]]), np.array([1.0]), np.ones(3)
    lo, hi, y = -np.ones(3), np.ones(3), np.ones(1)
    bound = certified_lower_bound(w, A, b, lo, hi, y)[0]
    assert bound <= 1.0 and bound > 1.0 - 1e-12  # (the optimum is 1)
    bad = [dict(lo=-np.ones(2)), dict(hi=np.ones(2)), dict(w=np.ones(2)),
           dict(b=np.array([1.0, 5.0]), y=np.ones(2)), dict(y=np.ones(2)),
           dict(b_err=np.zeros(2)), dict(w_err=np.zeros(4))]
    for kw in bad:
        args = dict(w=w, A=A, b=b, lo=lo, hi=hi, y=y) | kw
        name = next(iter(kw))
        with pytest.raises(so.DimensionError, match=f"^{name} must have shape"):
            certified_lower_bound(args.pop("w"), args.pop("A"), args.pop("b"),
                                  args.pop("lo"), args.pop("hi"), args.pop("y"), **args)
    for kw, match in ((dict(b=np.array([np.nan])), "b holds NaN"),
                      (dict(w=np.array([np.inf, 1, 1])), "w must be finite"),
                      (dict(lo=np.array([2.0, -1, -1])), "lo <= hi")):
        args = dict(w=w, A=A, b=b, lo=lo, hi=hi, y=y) | kw
        with pytest.raises(so.InvalidValueError, match=match):
            certified_lower_bound(**args)
    with pytest.raises(so.DimensionError, match=r"^h must have shape"):
        lagrangian_lower_bound(w, A, b, np.ones(2), y)
    with pytest.raises(so.DimensionError, match="FactorPolytope needs the shapes"):
        FactorPolytope(A, b, np.ones(2))
    P = FactorPolytope(A, b, np.ones(3))
    with pytest.raises(so.DimensionError, match="w and w_err must have shape"):
        P.minimize(np.ones(2))
    with pytest.raises(so.DimensionError, match="FixedStructureLP needs the shapes"):
        FixedStructureLP(A, np.ones((2, 2)), np.zeros(3, dtype=bool))
    F = FixedStructureLP(A, np.vstack([w, -w]), np.zeros(3, dtype=bool))
    with pytest.raises(so.DimensionError, match=r"^b must have shape"):
        F.minimize_all(np.ones(2), np.ones(3))
    with pytest.raises(so.InvalidValueError, match="b holds NaN"):
        F.minimize_all(np.array([np.nan]), np.ones(3))
    bounds, ok = F.minimize_all(b, np.ones(3))
    assert ok.all() and bounds[0] <= 1.0 and bounds[0] > 1.0 - 1e-12
