"""Deprecated attribute names kept as aliases of their new names."""

from __future__ import annotations

import warnings
from typing import Any


def renamed(old: str, new: str, why: str = "") -> Any:
    """A read-only property ``old`` that warns and returns ``self.<new>``.

    Parameters
    ----------
    old : str
        The deprecated name (for the message).
    new : str
        The attribute it now reads.
    why : str
        Optional reason appended to the message.
    """

    def getter(self: Any) -> Any:
        warnings.warn(f"{type(self).__name__}.{old} is deprecated; use .{new}"
                      + (f" ({why})" if why else ""), DeprecationWarning, stacklevel=2)
        return getattr(self, new)

    getter.__name__ = old
    getter.__doc__ = f"Deprecated name of :attr:`{new}`."
    return property(getter)
