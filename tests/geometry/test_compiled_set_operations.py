"""The compiled construction of ``Z + W``, ``M @ Z`` and ``Z.intersect(W, R)``.

Oracles:

* the operations' formulas, Scott et al. (2016) eqs. (11)-(13), written out here with
  ``np.block`` (generators, constraints, right-hand side, factor bounds);
* exact rational arithmetic (``fractions``) for the centre and the new right-hand
  side: the carried rounding bounds must cover the distance from the computed values to
  the exact ones plus the bounds carried in;
* the NumPy code of the same operations (the fallback, run with the extension switched
  off): the sum and the plain intersection must agree to the bit (same operations, no
  fused multiply-add), the maps to rounding;
* sampled points of both sets (exact factor vertices), which the sum must contain;
* reference counts and traced allocations for leaks.
"""

from __future__ import annotations

import os
import pickle
import sys
import tracemalloc
from fractions import Fraction

import numpy as np
import pytest

import setobs.geometry.zonotope as zonotope_module
from setobs import ConstrainedZonotope
from setobs.exceptions import DimensionError, InvalidValueError
from setobs.geometry import compiled_set_operations
from tests.conftest import random_cz, sample_points


def numpy_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """Switch the compiled construction off (the NumPy code runs)."""
    monkeypatch.setattr(zonotope_module, "compiled_ops", None)


def with_errors(Z: ConstrainedZonotope, rng: np.random.Generator, offset: float
                ) -> ConstrainedZonotope:
    """``Z`` moved by a large vector with an uncertainty (``c_err``) and cut by a measured
    hyperplane with one (``b_err``): sets whose rounding bounds are not zero."""
    v = rng.normal(size=Z.dim) * offset
    Zv = Z.minkowski_sum(v, err=np.full(Z.dim, 1e-9))
    C = rng.normal(size=(1, Z.dim))
    y = C @ (sample_points(Zv, rng, 1)[0])
    return Zv.intersect_affine(C, y, y_err=[1e-10])


def same_set(P: ConstrainedZonotope, Q: ConstrainedZonotope, *, exact: bool) -> None:
    pairs = [(P.G, Q.G), (P.c, Q.c), (P.A, Q.A), (P.b, Q.b), (P.h, Q.h),
             (P.c_err, Q.c_err), (P.b_err, Q.b_err)]
    for x, y in pairs:
        assert x.shape == y.shape
        if exact:
            np.testing.assert_array_equal(x, y)
        else:
            np.testing.assert_allclose(x, y, rtol=1e-13, atol=1e-13 * (1 + np.abs(y).max(
                initial=0.0)))
    assert P.unbounded_radius == Q.unbounded_radius


def fr(x) -> list:
    return [Fraction(float(v)) for v in np.ravel(x)]


def exact_matvec(M: np.ndarray, x: np.ndarray) -> list[Fraction]:
    return [sum((Fraction(float(m)) * Fraction(float(v)) for m, v in zip(row, x, strict=True)),
                Fraction(0)) for row in M]


def test_the_extension_is_built():
    """The build (setup.py) compiles it wherever there is a C compiler, as on CI; a
    machine without one sets SETOBS_ALLOW_PURE_PYTHON=1 to run the suite on NumPy."""
    if os.environ.get("SETOBS_ALLOW_PURE_PYTHON") == "1":
        pytest.skip("SETOBS_ALLOW_PURE_PYTHON=1")
    assert compiled_set_operations()


@pytest.mark.parametrize("seed", range(12))
def test_sum_formula_rounding_and_numpy(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=3, n_g=int(rng.integers(1, 6)))
    W = random_cz(rng, n=3, n_g=int(rng.integers(1, 6)))
    if seed % 2:
        Z = with_errors(Z, rng, 1e7)
    if seed % 3:
        W = with_errors(W, rng, 3e6)
    S = Z + W
    # eq. (12): [G_Z G_W], c_Z + c_W, blockdiag(A_Z, A_W), [b_Z; b_W], [h_Z; h_W]
    np.testing.assert_array_equal(S.G, np.hstack([Z.G, W.G]))
    np.testing.assert_array_equal(S.A, np.block([
        [Z.A, np.zeros((Z.n_con, W.n_gen))], [np.zeros((W.n_con, Z.n_gen)), W.A]]))
    np.testing.assert_array_equal(S.b, np.concatenate([Z.b, W.b]))
    np.testing.assert_array_equal(S.h, np.concatenate([Z.h, W.h]))
    np.testing.assert_array_equal(S.b_err, np.concatenate([Z.b_err, W.b_err]))
    exact = [a + b for a, b in zip(fr(Z.c), fr(W.c), strict=True)]
    for i in range(3):
        needed = (abs(Fraction(float(S.c[i])) - exact[i]) + Fraction(float(Z.c_err[i]))
                  + Fraction(float(W.c_err[i])))
        assert Fraction(float(S.c_err[i])) >= needed
    assert not (S.G.flags.writeable or S.c.flags.writeable or S.A.flags.writeable
                or S.c_err.flags.writeable)
    numpy_path(monkeypatch)
    same_set(S, Z + W, exact=True)
    same_set(Z.minkowski_sum(W), Z + W, exact=True)


@pytest.mark.parametrize("seed", range(12))
def test_map_formula_rounding_and_numpy(seed, monkeypatch):
    rng = np.random.default_rng(100 + seed)
    Z = random_cz(rng, n=3, n_g=4)
    if seed % 2:
        Z = with_errors(Z, rng, 1e8)
    M = rng.normal(size=(int(rng.integers(1, 5)), 3))
    if seed % 3 == 1:
        M = np.asfortranarray(M)
    elif seed % 3 == 2:
        M = np.repeat(np.repeat(M, 2, axis=0), 2, axis=1)[::2, ::2]  # strided view
    P = M @ Z
    np.testing.assert_allclose(P.G, np.asarray(M) @ Z.G, rtol=1e-14, atol=1e-14)
    assert P.A is Z.A and P.b is Z.b and P.h is Z.h  # eq. (11): the factors are kept
    exact = exact_matvec(np.asarray(M), Z.c)
    carried = np.abs(M) @ Z.c_err
    for i in range(M.shape[0]):
        needed = abs(Fraction(float(P.c[i])) - exact[i]) + Fraction(float(carried[i]))
        assert Fraction(float(P.c_err[i])) >= needed * (1 - 1e-12)
    assert P.c_err.min() > 0 or not np.count_nonzero(Z.c)
    numpy_path(monkeypatch)
    same_set(P, M @ Z, exact=False)


@pytest.mark.parametrize("seed", range(12))
def test_intersection_formula_rounding_and_numpy(seed, monkeypatch):
    rng = np.random.default_rng(200 + seed)
    Z = random_cz(rng, n=3, n_g=4)
    m = 3 if seed % 2 else 2
    W = random_cz(rng, n=m, n_g=int(rng.integers(1, 5)))
    if seed % 3:
        Z = with_errors(Z, rng, 1e6)
    if seed % 4 == 1:
        W = with_errors(W, rng, 2e6)
    R = None if (m == 3 and seed % 4 == 3) else rng.normal(size=(m, 3))
    Rm = np.eye(3) if R is None else R
    P = Z.intersect(W, R)
    # eq. (13): [G_Z 0], c_Z, [[A_Z 0], [0 A_W], [R G_Z, -G_W]], [b_Z; b_W; c_W - R c_Z]
    np.testing.assert_array_equal(P.G, np.hstack([Z.G, np.zeros((3, W.n_gen))]))
    assert P.c is Z.c
    want_A = np.block([[Z.A, np.zeros((Z.n_con, W.n_gen))],
                       [np.zeros((W.n_con, Z.n_gen)), W.A],
                       [Rm @ Z.G, -W.G]])
    np.testing.assert_allclose(P.A, want_A, rtol=1e-14, atol=1e-14)
    np.testing.assert_array_equal(P.b[: Z.n_con + W.n_con], np.concatenate([Z.b, W.b]))
    exact = [cw - rc for cw, rc in zip(fr(W.c), exact_matvec(Rm, Z.c), strict=True)]
    carried = np.abs(Rm) @ Z.c_err + W.c_err
    k = Z.n_con + W.n_con
    for i in range(m):
        needed = abs(Fraction(float(P.b[k + i])) - exact[i]) + Fraction(float(carried[i]))
        assert Fraction(float(P.b_err[k + i])) >= needed * (1 - 1e-12)
    np.testing.assert_array_equal(P.b_err[:k], np.concatenate([Z.b_err, W.b_err]))
    numpy_path(monkeypatch)
    same_set(P, Z.intersect(W, R), exact=R is None)


def test_sum_contains_the_sums_of_points(rng):
    Z, W = random_cz(rng, n=2, n_g=4, n_c=1), random_cz(rng, n=2, n_g=3, n_c=1)
    S = Z + W
    for z, w in zip(sample_points(Z, rng, 6), sample_points(W, rng, 6), strict=True):
        assert S.contains(z + w)


def test_unbounded_factors_and_radius_carried():
    Z = ConstrainedZonotope([[1.0, 0.0]], [0.0], h=[1.0, np.inf], unbounded_radius=1e6)
    W = ConstrainedZonotope([[2.0]], [1.0], unbounded_radius=1e4)
    S = Z + W
    np.testing.assert_array_equal(S.h, [1.0, np.inf, 1.0])
    assert S.unbounded_radius == 1e4 and (W + Z).unbounded_radius == 1e4
    assert Z.intersect(W).unbounded_radius == 1e4


def test_inputs_the_compiled_path_leaves_to_numpy():
    """Lists, integers, wrong shapes, non-finite entries, other byte orders: the NumPy
    code runs and gives its results or its errors."""
    Z = ConstrainedZonotope([[1.0, 0.0], [0.0, 2.0]], [1.0, -1.0])
    W = ConstrainedZonotope([[1.0]], [3.0])
    np.testing.assert_array_equal(([[1, 1], [0, 1]] @ Z).G, [[1.0, 2.0], [0.0, 2.0]])
    np.testing.assert_array_equal((np.array([[2, 0], [0, 1]]) @ Z).c, [2.0, -1.0])
    big_endian = np.array([[0.0, 1.0], [1.0, 0.0]], dtype=">f8")
    np.testing.assert_array_equal((big_endian @ Z).c, [-1.0, 1.0])
    with pytest.raises(InvalidValueError):
        np.array([[np.nan, 0.0], [0.0, 1.0]]) @ Z
    with pytest.raises(DimensionError):
        np.ones((2, 3)) @ Z
    with pytest.raises(DimensionError):
        Z + W
    with pytest.raises(DimensionError):
        Z.intersect(W)
    with pytest.raises(DimensionError):
        Z.intersect(W, np.ones((2, 2)))
    with pytest.raises(TypeError):
        Z.intersect(np.ones(2))
    P = Z.intersect(W, [[1, 1]])
    np.testing.assert_array_equal(P.A, [[1.0, 2.0, -1.0]])
    np.testing.assert_array_equal(P.b, [3.0])


def test_results_pickle_and_share_the_lp_model():
    Z = ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.5, 0.0],
                            A=[[1.0, 1.0, 1.0]], b=[1.0])
    assert not Z.is_empty()
    P = np.array([[2.0, 0.0], [0.0, 3.0]]) @ Z
    assert zonotope_module.factor_polytope(P) is zonotope_module.factor_polytope(Z)
    Q = pickle.loads(pickle.dumps(Z + P))
    box = Q.interval_hull()
    want = (Z + P).interval_hull()
    np.testing.assert_array_equal(box.lo, want.lo)
    np.testing.assert_array_equal(box.hi, want.hi)


def test_no_reference_or_memory_leak(rng):
    Z = with_errors(random_cz(rng, n=3, n_g=4, n_c=1), rng, 1e6)
    W = with_errors(random_cz(rng, n=3, n_g=3, n_c=1), rng, 1e6)
    E = random_cz(rng, n=3, n_g=2, n_c=1)  # exact: no rounding bounds
    M, R = rng.normal(size=(3, 3)), rng.normal(size=(3, 3))
    shared = [Z.G, Z.c, Z.A, Z.b, Z.h, Z.c_err, Z.b_err, W.G, W.c, W.c_err, E.A, E.b, E.h,
              E.c, M, R]
    before = [sys.getrefcount(x) for x in shared]

    def run(k):
        for _ in range(k):
            for X, Y in ((Z, W), (E, E), (E, Z)):
                X + Y
                M @ X
                X.intersect(Y, R)
                X.intersect(Y)

    run(10)
    tracemalloc.start()
    run(200)
    first, _ = tracemalloc.get_traced_memory()
    run(2000)
    second, _ = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert [sys.getrefcount(x) for x in shared] == before
    assert second - first < 20_000  # 2000 rounds of ~10 kB of arrays each, none kept


@pytest.mark.skipif(not compiled_set_operations(), reason="no compiled extension")
def test_a_slot_the_extension_does_not_write_is_refused():
    """The extension writes the class's slots by offset: a class with one more slot (or a
    ``__dict__``, or a slot missing) is refused at binding, and the binding in force
    is unchanged (sets built by the extension keep every slot set)."""
    from setobs.geometry import _setops

    names = ConstrainedZonotope.__slots__
    extra = type("WithExtra", (), {"__slots__": (*names, "_extra")})
    missing = type("Missing", (), {"__slots__": tuple(n for n in names if n != "_cache")})
    with_dict = type("WithDict", (), {"__slots__": (*names, "__dict__")})
    with pytest.raises(TypeError, match="slot _extra"):
        _setops.bind(extra, 1e150)
    with pytest.raises(AttributeError):
        _setops.bind(missing, 1e150)
    with pytest.raises(TypeError, match="__dict__"):
        _setops.bind(with_dict, 1e150)
    # the real class still binds, and a compiled sum sets every slot
    _setops.bind(ConstrainedZonotope, 1e150)
    Z = ConstrainedZonotope([[1.0, 0.5], [0.0, 1.0]], [0.0, 1.0], A=[[1.0, 1.0]], b=[0.5])
    S = Z + Z
    for name in names:
        getattr(S, name)  # (AttributeError if the extension left a slot unset)
    np.testing.assert_array_equal(S.c, [0.0, 2.0])
