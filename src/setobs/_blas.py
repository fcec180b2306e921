"""Single-threaded BLAS inside the library's numerical kernels.

The LP layer solves many small dense systems (basis duals, pseudo-inverses of
a few unbounded columns, ``n <= a few hundred``). A multi-threaded BLAS makes
those *slower*, badly so when the cores are busy: on a 2-core machine with the
other core loaded, a 400 x 400 ``np.linalg.solve`` took 8.4 ms with OpenBLAS's
default two threads and 2.2 ms with one (``benchmarks/exact_mode.py`` measures
the effect on whole SMFDO steps). So the library's results must not depend in
speed on the user's ``OPENBLAS_NUM_THREADS``: its kernels run under
:func:`single_threaded_blas`.

The BLAS thread count is a *process-wide* setting of the BLAS library
(``threadpoolctl`` sets it), so the limit is reference-counted: the first
kernel to enter saves the current setting and sets one thread, the last one to
leave restores it, whatever the interleaving of threads (a plain
``threadpool_limits`` context per call would let one thread restore the user's
setting while another is still inside, or leave the limit in place for good).
While any setobs kernel runs, BLAS calls of other threads of the process are
single-threaded too; results never depend on it, only speed.

Set the environment variable ``SETOBS_BLAS_LIMIT=0`` to leave the BLAS thread
count alone (read at each call).
"""

from __future__ import annotations

import functools
import os
import sys
import threading
from collections.abc import Callable
from typing import Any, TypeVar

__all__ = ["SMALL_BLAS_DIM", "blas_limit_enabled", "single_threaded_blas",
           "with_single_threaded_blas", "with_single_threaded_blas_unless_small"]

#: Matrices with every dimension below this run single-threaded in OpenBLAS whatever
#: its thread count (its thresholds: ``m n k <= 4 * 65536`` for ``gemm``, ``m n <
#: 9216`` for ``gemv``, ``m n < 10000`` for ``getrf``), so a kernel that handles only
#: such matrices may skip the limit (an SMFDO step on a small window does: the four
#: thread-count calls of the limit were a tenth of its time).
SMALL_BLAS_DIM = 64

F = TypeVar("F", bound=Callable[..., Any])

_lock = threading.Lock()
_depth = 0
_saved: list[tuple[Any, int]] = []
_libs: list[Any] | None = None
_libs_modules = -1  # len(sys.modules) when _libs was read


def blas_limit_enabled() -> bool:
    """Whether the library limits BLAS to one thread in its kernels."""
    return os.environ.get("SETOBS_BLAS_LIMIT", "1").strip().lower() not in ("0", "false", "no",
                                                                              "off")


def blas_libraries() -> list[Any]:
    """The BLAS libraries loaded in this process (numpy's and scipy's OpenBLAS, MKL, ...).

    Read again after any further Python module was imported: an extension may bring
    its own BLAS (python-control's slycot ships one). Libraries built without threads
    (scs ships one) are left out: they have no thread pool to limit.
    """
    global _libs, _libs_modules
    if _libs is None or len(sys.modules) != _libs_modules:
        import scipy.linalg  # noqa: F401  (loads scipy's own BLAS, if it has one)
        from threadpoolctl import ThreadpoolController

        ctl = ThreadpoolController()
        # (a BLAS built without threads, as scs's OpenBLAS, has no pool to limit)
        _libs = [lib for lib in ctl.lib_controllers if lib.user_api == "blas"
                 and getattr(lib, "threading_layer", None) != "disabled"]
        _libs_modules = len(sys.modules)
    return _libs


def set_num_threads(lib: Any, n: int) -> None:
    """Set a BLAS library's thread count from any thread.

    threadpoolctl (>= 3.6) lets only one "controlling" Python thread change a
    pthreads OpenBLAS (others silently do nothing); the reference count above
    already serialises the changes, so the controlling thread is released
    before and after each one.
    """
    clear = getattr(type(lib), "clear_controlling_thread", None)
    if clear is not None:
        clear(force=True)
    lib.set_num_threads(n)
    if clear is not None:
        clear(force=True)


class _SingleThreadedBLAS:
    """Reference-counted ``BLAS threads = 1`` (see the module notes)."""

    __slots__ = ("_active",)

    def __init__(self) -> None:
        self._active = False

    def __enter__(self) -> _SingleThreadedBLAS:
        global _depth
        if not blas_limit_enabled():
            return self
        with _lock:
            if _depth == 0:
                _saved.clear()
                for lib in blas_libraries():
                    n = lib.num_threads
                    if n != 1:
                        _saved.append((lib, n))
                        set_num_threads(lib, 1)
            _depth += 1
            self._active = True
        return self

    def __exit__(self, *exc: object) -> None:
        global _depth
        if not self._active:
            return
        with _lock:
            _depth -= 1
            self._active = False
            if _depth == 0:
                for lib, n in _saved:
                    set_num_threads(lib, n)
                _saved.clear()


def with_single_threaded_blas_unless_small(size: Callable[[Any], int]) -> Callable[[F], F]:
    """Decorator of a method: like :func:`with_single_threaded_blas`, but the limit is
    skipped when ``size(self)``, the largest matrix dimension the method handles, is
    below :data:`SMALL_BLAS_DIM` (OpenBLAS runs such matrices on one thread anyway;
    the limit's thread-count calls cost ~30 us, more than a small query)."""

    def decorate(func: F) -> F:
        @functools.wraps(func)
        def wrapper(self: Any, *args: Any, **kwargs: Any) -> Any:
            if size(self) < SMALL_BLAS_DIM:
                return func(self, *args, **kwargs)
            with _SingleThreadedBLAS():
                return func(self, *args, **kwargs)

        return wrapper  # type: ignore[return-value]

    return decorate


def guard_depth() -> int:
    """How many :func:`single_threaded_blas` regions are open now (0 when none)."""
    return _depth


def single_threaded_blas() -> _SingleThreadedBLAS:
    """Context manager: BLAS runs single-threaded inside (reference-counted, nestable)."""
    return _SingleThreadedBLAS()


def with_single_threaded_blas(func: F) -> F:
    """Decorator running ``func`` under :func:`single_threaded_blas`."""

    @functools.wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        with _SingleThreadedBLAS():
            return func(*args, **kwargs)

    return wrapper  # type: ignore[return-value]
