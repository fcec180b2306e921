"""Deferred imports: heavy engines load on first use, optional packages fail clearly.

``import setobs`` loads numpy, scipy.linalg and the package's own modules only.
The compiled simplex (numba), HiGHS (highspy), Qhull/linprog, pycddlib, cvxpy,
pandas, tqdm, PyYAML and matplotlib are imported where they are used, through
:func:`lazy_module` (a module proxy that imports on first attribute access) or
:func:`optional_import` (an import that names the extra to install when the
package is missing).
"""

from __future__ import annotations

import importlib
import threading
import types
from typing import Any

from .exceptions import MissingDependencyError

__all__ = ["lazy_module", "optional_import", "progress_bar"]

_LOCK = threading.Lock()


class _LazyModule(types.ModuleType):
    """Stands in for a module until an attribute is first read."""

    def __init__(self, name: str) -> None:
        super().__init__(name)
        self.__dict__["_lazy_target"] = None

    def _load(self) -> types.ModuleType:
        mod = self.__dict__["_lazy_target"]
        if mod is None:
            with _LOCK:  # a module's first import is not re-entrant across threads
                mod = importlib.import_module(self.__name__)
            self.__dict__["_lazy_target"] = mod
        return mod

    def __getattr__(self, attr: str) -> Any:
        # Read once, then kept on the proxy: a miss through __getattr__ costs ~2.5 us,
        # several per SMFDO step. (So a later rebinding in the real module is not
        # seen: patch the proxy's attribute instead.)
        value = getattr(self._load(), attr)
        self.__dict__[attr] = value
        return value

    def __dir__(self) -> list[str]:
        return dir(self._load())


def lazy_module(name: str) -> types.ModuleType:
    """Return a proxy for module ``name`` that imports it on first attribute access.

    Parameters
    ----------
    name : str
        Absolute module name, e.g. ``"highspy"`` or ``"setobs.lp._simplex"``.

    Returns
    -------
    types.ModuleType
        The proxy; attribute access behaves as on the module itself.
    """
    return _LazyModule(name)


def optional_import(name: str, *, extra: str, feature: str) -> types.ModuleType:
    """Import an optional package, or raise an ImportError that says how to get it.

    Parameters
    ----------
    name : str
        Module to import (``"pandas"``, ``"tqdm.auto"``, ``"yaml"``, ...).
    extra : str
        The ``setobs`` extra that installs it (``pip install "setobs[extra]"``).
    feature : str
        What needs it, for the message (``"SMFDOResult.to_pandas"``).

    Returns
    -------
    types.ModuleType
        The imported module.

    Raises
    ------
    ImportError
        If the package is not installed.
    """
    try:
        return importlib.import_module(name)
    except ImportError as exc:
        top = name.split(".")[0]
        dist = _DISTRIBUTIONS.get(top, top)
        raise MissingDependencyError(
            f"{feature} needs the optional package {top!r}, which is not installed: "
            f'pip install "setobs[{extra}]" (or pip install {dist})'
        ) from exc


#: Import names whose distribution on the package index has another name.
_DISTRIBUTIONS = {"yaml": "pyyaml"}


class _NoBar:
    """The do-nothing progress bar used when progress is off."""

    n = 0

    def update(self, k: int = 1) -> None:
        self.n += k

    def close(self) -> None:
        pass


def progress_bar(enabled: bool, *, total: int, desc: str, **kwargs: Any) -> Any:
    """A tqdm bar on stderr when ``enabled`` (tqdm is the ``progress`` extra), else a no-op.

    Parameters
    ----------
    enabled : bool
        Whether to show a bar; when False, tqdm is not imported.
    total : int
        Number of units.
    desc : str
        Label shown before the bar.
    **kwargs
        Passed to ``tqdm.auto.tqdm``.

    Returns
    -------
    object
        An object with ``update(k)``, ``close()`` and ``n``.
    """
    if not enabled:
        return _NoBar()
    tqdm = optional_import("tqdm.auto", extra="progress", feature="progress=True").tqdm
    return tqdm(total=total, desc=desc, **kwargs)
