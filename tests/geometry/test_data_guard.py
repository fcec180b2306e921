"""No set with non-finite data, or data above ``MAX_MAGNITUDE``, is ever built
(reproducer ``tests/data/regressions/compiled_map_overflow_nan_set.py``).

Oracles: the data of every set an operation returns, checked here entry by entry with
NumPy (finite, at most ``1e150`` in magnitude; ``h`` nonnegative or ``+inf``), and the
reproducer's sets written out by hand (the matrix entries and the products that overflow).
Every operation runs on both paths: the compiled construction and the NumPy code (the
extension switched off).
"""

from __future__ import annotations

import pickle
import time
import warnings

import numpy as np
import pytest

import setobs.geometry.zonotope as zonotope_module
from setobs import ConstrainedZonotope as CZ
from setobs.exceptions import (
    DimensionError,
    EmptySetError,
    InvalidValueError,
    MagnitudeError,
    SetobsError,
    SolverWarning,
    UnboundedSetError,
)
from setobs.geometry import compiled_set_operations
from setobs.geometry.operations import intersect_halfspace, quad_map
from setobs.geometry.zonotope import trusted_cz
from setobs.tolerances import MAX_MAGNITUDE

PATHS = ["compiled", "numpy"]


def use_path(path: str, monkeypatch: pytest.MonkeyPatch) -> None:
    if path == "numpy":
        monkeypatch.setattr(zonotope_module, "compiled_ops", None)
    elif not compiled_set_operations():  # pragma: no cover - a build without a compiler
        pytest.skip("the compiled extension is not built here")


def assert_data_sane(Z: CZ) -> None:
    """Every entry of G, c, A, b, c_err, b_err finite and at most 1e150; h in [0, 1e150]
    or +inf (checked here, not by the library's guard)."""
    for name in ("G", "c", "A", "b", "c_err", "b_err"):
        a = np.asarray(getattr(Z, name))
        assert np.isfinite(a).all(), (name, a)
        assert (np.abs(a) <= 1e150).all(), (name, np.abs(a).max())
    h = Z.h
    assert not np.isnan(h).any()
    assert (h >= 0).all()
    assert ((h <= 1e150) | (h == np.inf)).all()


# ------------------------------------------------------------------ the reproducer
@pytest.mark.parametrize("path", PATHS)
def test_matrix_above_the_limit_is_refused_on_both_paths(path, monkeypatch):
    """Variant (a): a map by a matrix with entries of 1e300. The C path took it and built
    a set with NaN in G and c whose containment test said True for a point outside."""
    use_path(path, monkeypatch)
    Z = CZ([[1e10, 1.0], [1e10, 1.0]], [1e10, 1e10], A=[[1.0, 1.0]], b=[0.5])
    M = np.array([[1e300, -1e300], [0.0, 1.0]])
    with pytest.raises(InvalidValueError, match=r"M \(linear map\) has an entry of 1e\+300"):
        M @ Z
    with pytest.raises(InvalidValueError, match=r"R \(generalised intersection\) has an entry"):
        Z.intersect(CZ.full_space(2), M)
    assert MAX_MAGNITUDE == 1e150


@pytest.mark.parametrize("path", PATHS)
def test_product_that_overflows_is_refused_naming_the_operation(path, monkeypatch):
    """Variant (b): three maps within the limit whose products reach 1e300 and then
    overflow; the result had NaN in G, `contains([1, 0])` said True (the set's x1 is 0)
    and `interval_hull` ran for minutes. Now the first map beyond 1e150 raises."""
    use_path(path, monkeypatch)
    Z = CZ([[1e150, 1.0], [1e150, 1.0]], [1.0, 1.0], A=[[1.0, 1.0]], b=[0.5])
    M1 = np.diag([1e150, 1e150])
    with pytest.raises(MagnitudeError, match=r"linear map: the result's G would hold an "
                                             r"entry of 1e\+300 \(first at index \(0, 0\)\)"):
        M1 @ Z
    # what stays within the limit is built and answers at once (G [[1e150, 1]], c 1)
    t = time.perf_counter()
    V = np.array([[1.0, -1.0], [0.0, 1.0]]) @ Z
    assert_data_sane(V)
    assert not V.contains([1.0, 0.0])  # x1 = 1e150 (xi_1 - xi_1) + (1 - 1) = 0 exactly
    box = V.interval_hull()
    assert time.perf_counter() - t < 30.0  # (not a benchmark: the old failure was minutes)
    assert box.lo[0] <= 0.0 <= box.hi[0]


def test_internal_constructions_and_unpickling_are_guarded():
    """The package-internal builder and unpickling refuse NaN, inf and huge data too."""
    G, c = np.eye(2), np.zeros(2)
    A, b, h = np.zeros((0, 2)), np.zeros(0), np.ones(2)
    with pytest.raises(MagnitudeError, match="building a set: the result's c would hold NaN"):
        trusted_cz(G, np.array([np.nan, 0.0]), A, b, h)
    with pytest.raises(MagnitudeError, match="the result's c_err would hold an entry of inf"):
        trusted_cz(G, c, A, b, h, cerr=np.array([np.inf, 0.0]))
    with pytest.raises(MagnitudeError, match="the result's h would hold NaN"):
        trusted_cz(G, c, A, b, np.array([1.0, np.nan]))
    assert_data_sane(trusted_cz(G, c, A, b, np.array([1.0, np.inf])))  # +inf: unbounded
    Z = CZ(np.eye(2), [1.0, 2.0])
    data = pickle.dumps(Z)
    assert pickle.loads(data).contains([1.5, 2.5])
    bad = data.replace(np.array([1.0, 2.0]).tobytes(), np.array([1.0, np.inf]).tobytes())
    assert bad != data
    with pytest.raises(MagnitudeError, match="unpickling a set"):
        pickle.loads(bad)


# ------------------------------------------------------------------ the fuzz test
def _magnitudes(rng, shape, top: float):
    """Entries of random sign and log-uniform magnitude in [1e-300, 10^top] (some 0)."""
    a = np.sign(rng.normal(size=shape)) * 10.0 ** rng.uniform(-300, top, size=shape)
    a[rng.random(shape) < 0.15] = 0.0
    return a


def _random_set(rng) -> CZ:
    n, ng = int(rng.integers(1, 4)), int(rng.integers(1, 5))
    nc = int(rng.integers(0, ng + 1))
    G, c = _magnitudes(rng, (n, ng), 150), _magnitudes(rng, n, 150)
    A, b = _magnitudes(rng, (nc, ng), 150), _magnitudes(rng, nc, 150)
    h = np.abs(_magnitudes(rng, ng, 150))
    h[rng.random(ng) < 0.2] = np.inf
    return CZ(G, c, A if nc else None, b if nc else None, h)


def _random_op(rng, Z: CZ, other: CZ):
    kind = int(rng.integers(0, 11))
    n = Z.dim
    if kind == 0:
        return Z + other if other.dim == n else Z + Z
    if kind == 1:
        return _magnitudes(rng, (int(rng.integers(1, 4)), n), 300) @ Z
    if kind == 2:
        return Z.intersect(other, _magnitudes(rng, (other.dim, n), 300))
    if kind == 3:
        return Z.intersect(Z)
    if kind == 4:
        return Z.intersect_affine(_magnitudes(rng, (1, n), 300), _magnitudes(rng, 1, 300))
    if kind == 5:
        return Z.cartesian(other)
    if kind == 6:
        return -Z
    if kind == 7:
        return Z + _magnitudes(rng, n, 300)
    if kind == 8:
        return Z.project([int(rng.integers(0, n))])
    if kind == 9:
        return intersect_halfspace(Z, _magnitudes(rng, n, 300), float(_magnitudes(rng, 1, 300)[0]))
    return quad_map(Z, [_magnitudes(rng, (n, n), 300)])


@pytest.mark.parametrize("path", PATHS)
def test_fuzz_no_non_finite_set_is_ever_built(path, monkeypatch):
    """Random chains of operations on sets with data up to 1e150 and operands up to 1e300:
    each operation raises a SetobsError (a refused operand, or a result beyond the limit)
    or returns a set whose data are finite and within it. No other exception, no
    RuntimeWarning (overflow) from the library (an error under pytest's settings)."""
    use_path(path, monkeypatch)
    rng = np.random.default_rng(46)
    built = refused_operand = refused_result = hulls = 0
    for _ in range(400):
        Z, other = _random_set(rng), _random_set(rng)
        assert_data_sane(Z)
        for _step in range(4):
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("error", RuntimeWarning)
                    out = _random_op(rng, Z, other)
            except MagnitudeError:
                refused_result += 1
                continue
            except (DimensionError, InvalidValueError, UnboundedSetError, EmptySetError):
                # (an operand above the magnitude limit; quad_map takes bounded factors only)
                refused_operand += 1
                continue
            except SetobsError as exc:  # pragma: no cover - reported by the assert
                raise AssertionError(f"unexpected {type(exc).__name__}: {exc}") from exc
            assert_data_sane(out)
            built += 1
            Z = out
            if built % 8 == 0:  # queries on such sets answer (an outer box, never NaN)
                try:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", SolverWarning)
                        box = Z.interval_hull()
                except EmptySetError:
                    continue
                assert not (np.isnan(box.lo).any() or np.isnan(box.hi).any())
                assert (box.lo <= box.hi).all()
                hulls += 1
    assert built > 300 and refused_operand > 100 and refused_result > 30 and hulls > 30, (
        built, refused_operand, refused_result, hulls)
