"""Display of complex numbers (zeros, poles) in messages and reports: one format."""

from __future__ import annotations

from collections.abc import Iterable

from .tolerances import IMAG_DISPLAY_RTOL


def format_complex(z: complex, digits: int = 6) -> str:
    """``"1.26095"`` for a (numerically) real value, ``"0.3+0.5j"`` otherwise.

    Parameters
    ----------
    z : complex
        The value.
    digits : int
        Significant digits.
    """
    z = complex(z)
    if abs(z.imag) <= IMAG_DISPLAY_RTOL * max(1.0, abs(z)):
        return f"{z.real:.{digits}g}"
    return f"{z.real:.{digits}g}{z.imag:+.{digits}g}j"


def format_complex_list(values: Iterable[complex], digits: int = 6) -> str:
    """Comma-separated :func:`format_complex` of ``values`` (empty string if none).

    Parameters
    ----------
    values : iterable of complex
        The values.
    digits : int
        Significant digits.
    """
    return ", ".join(format_complex(v, digits) for v in values)
