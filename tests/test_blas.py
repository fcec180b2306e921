"""The library's kernels run with single-threaded BLAS, and give the user's setting back."""

from __future__ import annotations

import threading

import numpy as np
import pytest
from threadpoolctl import threadpool_info

import setobs as so
from setobs import _blas
from setobs.lp.factor import FactorPolytope


def blas_threads() -> list[int]:
    return [lib.num_threads for lib in _blas.blas_libraries()]


def test_numpy_and_scipy_blas_are_controlled():
    ours = {lib.filepath for lib in _blas.blas_libraries()}
    loaded = {info["filepath"] for info in threadpool_info() if info["user_api"] == "blas"
              and ("numpy" in info["filepath"] or "scipy" in info["filepath"])}
    assert loaded <= ours


@pytest.fixture
def two_threads():
    libs = _blas.blas_libraries()
    if not libs:
        pytest.skip("no BLAS library with a thread pool is loaded")
    saved = [lib.num_threads for lib in libs]
    # (threadpoolctl's own threadpool_limits is ignored from a thread that is not
    # its "controlling thread", which another test's threads may have become)
    for lib in libs:
        _blas.set_num_threads(lib, 2)
    assert blas_threads() == [2] * len(libs)
    yield
    for lib, n in zip(libs, saved, strict=True):
        _blas.set_num_threads(lib, n)


def spy_minimize(monkeypatch, seen):
    orig = FactorPolytope.minimize_under_lock

    def spy(self, *args):
        seen.append(blas_threads())
        return orig(self, *args)

    monkeypatch.setattr(FactorPolytope, "minimize_under_lock", spy)


def test_lp_queries_run_single_threaded_and_restore(monkeypatch, two_threads):
    """A set with more factors than ``SMALL_BLAS_DIM``: its support LP (HiGHS path) and
    its hull (the compiled batch) run with one BLAS thread; the setting comes back."""
    from setobs.lp.fastlp import FixedStructureLP

    seen: list[list[int]] = []
    spy_minimize(monkeypatch, seen)
    orig = FixedStructureLP.minimize_all_unchecked

    def spy_batch(self, *args, **kwargs):
        seen.append(blas_threads())
        return orig(self, *args, **kwargs)

    monkeypatch.setattr(FixedStructureLP, "minimize_all_unchecked", spy_batch)
    rng = np.random.default_rng(0)
    n_g = _blas.SMALL_BLAS_DIM + 6
    A = rng.normal(size=(1, n_g))
    Z = so.ConstrainedZonotope(rng.normal(size=(2, n_g)), [0.0, 0.0], A,
                               A @ rng.uniform(-0.5, 0.5, n_g))
    Z.interval_hull()
    Z.support([1.0, 1.0])
    assert len(seen) >= 2 and all(all(n == 1 for n in s) for s in seen)
    assert all(n == 2 for n in blas_threads())


def test_small_queries_skip_the_limit(monkeypatch, two_threads):
    """Below ``SMALL_BLAS_DIM`` (OpenBLAS runs such matrices on one thread anyway) the
    thread count is left alone: the limit's calls would cost more than the query."""
    seen: list[list[int]] = []
    spy_minimize(monkeypatch, seen)
    Z = so.ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0],
                               A=[[1.0, 1.0, 1.0]], b=[0.5])
    Z.support([1.0, 0.0])
    assert seen and all(all(n == 2 for n in s) for s in seen)


def test_nested_and_threaded_use_restores_the_setting(monkeypatch, two_threads):
    seen: list[list[int]] = []
    spy_minimize(monkeypatch, seen)
    sys = so.examples.chang2006()
    Y = np.array([[0.0, 1.0]] * 12)
    errors: list[BaseException] = []
    barrier = threading.Barrier(3)

    def work():
        try:
            barrier.wait()
            for _ in range(2):
                so.SMFDO(sys, window=3, fast=False).run(Y)
        except BaseException as exc:
            errors.append(exc)

    threads = [threading.Thread(target=work) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    assert seen and all(all(n == 1 for n in s) for s in seen)
    assert _blas.guard_depth() == 0
    assert all(n == 2 for n in blas_threads())


def test_the_limit_can_be_switched_off(monkeypatch, two_threads):
    monkeypatch.setenv("SETOBS_BLAS_LIMIT", "0")
    assert not _blas.blas_limit_enabled()
    with _blas.single_threaded_blas():
        assert all(n == 2 for n in blas_threads())
    monkeypatch.setenv("SETOBS_BLAS_LIMIT", "1")
    with _blas.single_threaded_blas():
        with _blas.single_threaded_blas():
            assert all(n == 1 for n in blas_threads())
        assert all(n == 1 for n in blas_threads())
    assert all(n == 2 for n in blas_threads())


def test_libraries_are_read_again_after_an_import(monkeypatch):
    """A BLAS brought by a later import (python-control's slycot ships its own) is
    controlled too: the list is read again once ``sys.modules`` has grown."""
    import sys
    import types

    first = _blas.blas_libraries()
    assert _blas.blas_libraries() is first  # cached while nothing is imported
    monkeypatch.setitem(sys.modules, "setobs_test_fake_extension", types.ModuleType("x"))
    again = _blas.blas_libraries()
    assert again is not first
    assert {lib.filepath for lib in again} >= {lib.filepath for lib in first}
    assert all(lib.threading_layer != "disabled" for lib in again
               if hasattr(lib, "threading_layer"))
