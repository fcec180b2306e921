"""Compare printed output with a stored copy without depending on platform digits.

Numbers printed from floating-point results move in their last digit with the BLAS
build and the CPU (a value on a rounding boundary prints as 6.5 on one machine and
6.6 on another). :func:`same_printout` compares text as text and numbers as
numbers: equal within ``rtol`` or within one unit of the last digit the expected
text shows; integers (no decimal point, no exponent) must be equal.
"""

from __future__ import annotations

import re

_NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


def _unit(token: str) -> float | None:
    """One unit of the last printed digit, or ``None`` for an integer."""
    mant, _, exp = token.lower().partition("e")
    if "." not in mant and not exp:
        return None
    decimals = len(mant.split(".")[1]) if "." in mant else 0
    return 10.0 ** (int(exp or 0) - decimals)


def number_mismatch(actual: str, expected: str, rtol: float = 1e-6) -> str | None:
    """Why two lines differ, or ``None`` when they agree (see the module notes)."""
    a_txt, e_txt = _NUMBER.split(actual), _NUMBER.split(expected)
    if a_txt != e_txt:
        return f"text differs: {actual!r} != {expected!r}"
    for a, e in zip(_NUMBER.findall(actual), _NUMBER.findall(expected), strict=True):
        unit = _unit(e)
        if unit is None and _unit(a) is None:
            if int(a) != int(e):
                return f"integer {a} != {e} in {expected!r}"
            continue
        tol = max(rtol * abs(float(e)), 1.0000001 * (unit if unit is not None else 0.0))
        if abs(float(a) - float(e)) > tol:
            return f"number {a} != {e} (tolerance {tol:g}) in {expected!r}"
    return None


def same_printout(actual: str, expected: str, rtol: float = 1e-6) -> list[str]:
    """Line-by-line differences between two printouts (empty when they agree)."""
    a, e = actual.strip().splitlines(), expected.strip().splitlines()
    if len(a) != len(e):
        return [f"{len(a)} lines printed, {len(e)} expected"]
    return [m for x, y in zip(a, e, strict=True) if (m := number_mismatch(x, y, rtol))]


def line_in(actual_line: str, text: str, rtol: float = 1e-6) -> bool:
    """Whether some line of ``text`` agrees with ``actual_line``."""
    return any(number_mismatch(actual_line, t, rtol) is None for t in text.splitlines())


def has_number(text: str, value: float, rtol: float = 1e-4, after: str = "") -> bool:
    """Whether ``text`` prints ``value`` (within ``rtol``), right after ``after`` if given."""
    pattern = re.escape(after) + r"\s*(" + _NUMBER.pattern + ")" if after else _NUMBER.pattern
    for m in re.finditer(pattern, text):
        tok = m.group(1) if after else m.group(0)
        if abs(float(tok) - value) <= rtol * abs(value):
            return True
    return False
