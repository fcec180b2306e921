"""One correctness battery, run against every LP backend of :mod:`setobs.lp`.

The pattern of scipy.optimize's ``linprog`` tests: the same LPs and the same
checks for each solver path. The backends are the factor polytope's HiGHS path
(:class:`~setobs.lp.factor.FactorPolytope`, the compiled retries switched off),
the compiled warm-started simplex (:class:`~setobs.lp.fastlp.FixedStructureLP`)
and the grown box LP of exact mode (:class:`~setobs.lp.boxlp.BoxLP`). The oracle
is the exact rational optimum of the stored data (``tests.oracles.exact_lp_min``):
every reported bound must be at or below it and, where the backend reports
success, within ``1e-9`` (relative) of it.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from setobs.lp import boxlp, fastlp
from setobs.lp.boxlp import BoxLP
from setobs.lp.factor import FactorPolytope
from setobs.lp.fastlp import FixedStructureLP
from tests.conftest import disable_compiled_lps
from tests.oracles import exact_lp_min


def _instances(with_free: bool, n_inst: int = 30):
    """Factor-polytope LPs ``min W^T xi, A xi = b, |xi| <= h``: scales over four
    decades, degenerate (duplicated columns, zero-width factors), redundant rows."""
    rng = np.random.default_rng(7 if with_free else 8)
    out = []
    for t in range(n_inst):
        m = int(rng.integers(1, 4))
        n = m + int(rng.integers(2, 5))
        A = rng.normal(size=(m, n)) * 10.0 ** rng.uniform(-2, 2, size=(1, n))
        if t % 5 == 1:
            A[:, -1] = A[:, 0]  # (dual degenerate)
        if t % 7 == 2 and m > 1:
            A[-1] = A[0] * 2.0 ** int(rng.integers(-3, 4))  # (a redundant row, exact)
        h = rng.uniform(0.1, 2.0, n)
        if t % 6 == 3:
            h[1] = 0.0
        free = np.zeros(n, dtype=bool)
        if with_free:
            free[0] = True
            h[0] = np.inf
        xi = np.where(free, rng.normal(size=n), rng.uniform(-0.9, 0.9, n) * np.where(free, 0, h))
        b = A @ xi
        W = rng.normal(size=(3, n))
        if with_free:
            W[:, 0] = 0.0  # (bounded objectives: w_U in range(A_U^T) trivially)
        out.append((A, b, h, W, free))
    return out


def _exact(A, b, h, w):
    F = Fraction
    lo = [None if np.isinf(v) else -F(float(v)) for v in h]
    hi = [None if np.isinf(v) else F(float(v)) for v in h]
    try:
        return exact_lp_min([F(float(v)) for v in w], [[F(float(v)) for v in r] for r in A],
                            [F(float(v)) for v in b], lo, hi)
    except ValueError:  # (b rounded: the stored data can be infeasible)
        return "infeasible"


def _highs(A, b, h, W, free):
    fp = FactorPolytope(A, b, h)
    outs = [fp.minimize(w) for w in W]
    return np.array([o.bound for o in outs]), np.array([o.status == "optimal" for o in outs])


def _compiled(A, b, h, W, free):
    S = FixedStructureLP(A, W, free)
    assert S.usable, S.reason
    return S.minimize_all(b, h)


def _box_lp(A, b, h):
    """A BoxLP of ``A xi = b``, ``|xi| <= h``, and its columns."""
    lp = BoxLP()
    cols = lp.add_cols(-h, h)
    r, c = np.nonzero(A)
    lp.add_rows(r, c, A[r, c], b, np.zeros(b.size))
    return lp, cols


def _box(A, b, h, W, free):
    lp, cols = _box_lp(A, b, h)
    out = lp.minimize_all(cols, W)
    if out is None:
        return np.full(W.shape[0], -np.inf), np.zeros(W.shape[0], dtype=bool)
    return out, np.ones(W.shape[0], dtype=bool)


BACKENDS = {"highs": _highs, "compiled": _compiled, "compiled_each": _compiled,
            "boxlp": _box, "boxlp_each": _box}


# (the box LP bounds every variable, its certificate's premise: no free factors;
# "_each": without the objective chain, each LP from its own warm start)
@pytest.mark.parametrize(("backend", "with_free"), [
    ("highs", False), ("highs", True), ("compiled", False), ("compiled", True),
    ("compiled_each", True), ("boxlp", False), ("boxlp_each", False)])
def test_every_backend_is_below_the_exact_optimum_and_tight(backend, with_free, monkeypatch):
    if backend == "highs":
        disable_compiled_lps(monkeypatch)
    if backend == "compiled_each":
        monkeypatch.setattr(fastlp, "PRIMAL_CHAIN", False)
        monkeypatch.setattr(fastlp, "CHAIN_ORDER", False)
    if backend == "boxlp":
        monkeypatch.setattr(boxlp, "CHAIN_MIN_OBJECTIVES", 1)
    if backend == "boxlp_each":
        monkeypatch.setattr(boxlp, "CHAIN", False)
    solved = checked = 0
    for A, b, h, W, free in _instances(with_free):
        exact = [_exact(A, b, h, w) for w in W]
        if any(e == "infeasible" for e in exact):
            continue
        bounds, ok = BACKENDS[backend](A, b, h, W, free)
        for i, e in enumerate(exact):
            checked += 1
            assert not np.isnan(bounds[i])
            if e is None:  # (unbounded below)
                assert bounds[i] == -np.inf or not ok[i]
                continue
            assert bounds[i] == -np.inf or Fraction(bounds[i]) <= e
            if ok[i]:
                solved += 1
                assert float(e) - bounds[i] <= 1e-9 * (1.0 + abs(float(e)))
    assert checked >= 60
    assert solved >= 0.9 * checked  # (a backend that declines everything fails here)


@pytest.mark.parametrize("chain", [True, False])
def test_the_box_lp_grows_and_undoes_blocks_like_a_fresh_one(chain, monkeypatch):
    """Blocks added after a solve reach the warm models (the grown LP's optimum is the
    exact one of the grown LP), and ``undo`` restores the previous LP (its exact optima);
    with the objective chain (one model) and with one model per objective."""
    monkeypatch.setattr(boxlp, "CHAIN", chain)
    monkeypatch.setattr(boxlp, "CHAIN_MIN_OBJECTIVES", 1)
    A, b, h, W, _ = _instances(False)[4]
    lp, cols = _box_lp(A, b, h)
    assert lp.minimize_all(cols, W) is not None  # (warm models exist from here on)
    lp.begin()
    # a new block: x' = xi_0 + xi_1 + s, |s| <= 0.05, objectives on x'
    extra = lp.add_cols(np.array([-10.0, -0.05]), np.array([10.0, 0.05]))
    row = lp.n_row
    lp.add_rows(np.full(4, row), np.array([extra[0], cols[0], cols[1], extra[1]]),
                np.array([1.0, -1.0, -1.0, -1.0]), np.zeros(1), np.zeros(1))
    grown = lp.minimize_all(extra[:1], np.array([[1.0], [-1.0]]))
    w_sum = np.zeros(h.size)
    w_sum[:2] = 1.0
    s_max = Fraction(0.05)
    lo_exact = _exact(A, b, h, w_sum) - s_max
    hi_exact = -_exact(A, b, h, -w_sum) + s_max
    assert Fraction(grown[0]) <= lo_exact and Fraction(-grown[1]) >= hi_exact
    assert float(lo_exact) - grown[0] <= 1e-9 * (1 + abs(float(lo_exact)))
    assert -grown[1] - float(hi_exact) <= 1e-9 * (1 + abs(float(hi_exact)))
    lp.undo()
    again = lp.minimize_all(cols, W)
    for i, w in enumerate(W):
        e = _exact(A, b, h, w)
        assert Fraction(again[i]) <= e and float(e) - again[i] <= 1e-9 * (1 + abs(float(e)))


def test_a_failed_warm_solve_restarts_a_fresh_model_from_the_warm_basis(monkeypatch):
    """When HiGHS's warm primal and then its dual simplex both stop undecided (on the
    30-tank cascade's whole-history LP at k = 186 they did, and a cold model then ran for
    minutes), the next attempt is a fresh model started from the basis the warm solve
    began with: one more solve, not a cold one, and the bound is still the exact optimum."""
    from setobs.lp import highs

    monkeypatch.setattr(boxlp, "CHAIN_MIN_OBJECTIVES", 1)
    A, b, h, W, _ = _instances(False)[4]
    lp, cols = _box_lp(A, b, h)
    assert lp.minimize_all(cols, W) is not None  # (the model is warm from here on)
    calls = []
    real = highs.solve

    def failing(hs, *, primal=False, iteration_limit=None):
        calls.append((primal, hs.getBasis().valid))
        if len(calls) <= 2:  # (the warm primal, then the dual from where it stopped)
            return "undecided"
        return real(hs, primal=primal, iteration_limit=iteration_limit)

    monkeypatch.setattr(highs, "solve", failing)
    again = lp.minimize_all(cols, W)
    assert again is not None
    # the third solve: a fresh model by the primal simplex, from a valid basis; then the
    # chain goes on on that model (one solve per objective)
    assert calls[2] == (True, True)
    assert len(calls) == 2 + W.shape[0]
    for i, w in enumerate(W):
        e = _exact(A, b, h, w)
        assert Fraction(again[i]) <= e and float(e) - again[i] <= 1e-9 * (1 + abs(float(e)))
