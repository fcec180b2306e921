"""Interval evaluation of sympy expressions with outward rounding (needs sympy).

:func:`interval_function` compiles expressions (and, on request, their Jacobian)
into an evaluator over boxes: ``F(lo, hi)`` returns ``(flo, fhi)`` with
``f(x)`` in ``[flo, fhi]`` for every real ``x`` in the box ``[lo, hi]`` -- the
natural interval extension (Moore, Kearfott, Cloud, *Introduction to Interval
Analysis*, SIAM 2009, Sec. 5.1), with every floating-point operation rounded
outward. It is the enclosure the guaranteed nonlinear estimators build on (the
mean-value and first-order Taylor extensions of Rego, Raffo, Scott, Raimondo,
Automatica 2020, need ``f`` at a point and its derivatives over a box).

Rounding
--------
Python floats round to nearest, so the exact result of ``+``, ``-``, ``*``,
``/`` and ``sqrt`` (correctly rounded by IEEE 754) lies within one unit in the
last place of the computed one: one step of :func:`math.nextafter` outward
encloses it. Sums and products are widened only on the side their exact error
lies (Knuth's TwoSum, Dekker's TwoProduct), and not at all when exact, so that a
box exactly at a domain's edge stays there (``sqrt(-x)`` over ``[-1, 0]``,
``sqrt(1 - x**2)`` over ``[-1, 1]``). Integer powers of any size are products by
binary exponentiation (``O(log n)``), never ``pow`` (which rounds an exponent
above ``2**53``). ``sin`` and ``cos`` take constant time: a box that may hold a
maximum and a minimum (any box wider than about ``1e-9 |x|``, so every box
beyond ``|x| ~ 6e9``) is ``[-1, 1]``. A constant beyond the double range raises
:class:`setobs.exceptions.MagnitudeError`. The elementary functions of the C
library (``exp``, ``log``, ``sin``, ``cos``, ``tanh``, ``atan``, ``pow`` ...) are
not correctly rounded; the
GNU C library documents errors of at most 1-2 units in the last place for them
on x86-64, and the evaluator widens their results by :data:`LIBM_ULPS` units (4)
outward. Constants (``Rational``, ``pi``, ``E``, floats) become intervals that
contain the exact real value. A result that overflows becomes ``+-inf`` (still an
enclosure).

Domain errors
-------------
An operation whose argument box leaves its domain (``sqrt`` or ``log`` of a box
reaching below 0, a division by a box that holds 0, a non-integer power of a box
reaching below 0 -- sympy's principal branch is complex there --, ``tan`` over a
pole) raises :class:`setobs.exceptions.DomainError` naming the sub-expression and
the box; nothing is propagated as NaN.

Supported: sums, products, integer and real powers, ``sqrt``, ``exp``, ``log``,
``sin``, ``cos``, ``tan``, ``sinh``, ``cosh``, ``tanh``, ``atan``, ``Abs``,
``Min``, ``Max``; anything else raises :class:`setobs.exceptions.NotSupportedError`.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable, Sequence
from fractions import Fraction
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import optional_import
from ..exceptions import (
    ArgumentError,
    DimensionError,
    DomainError,
    MagnitudeError,
    NotSupportedError,
)

__all__ = ["IntervalFunction", "interval_function"]

#: Units in the last place by which results of the C library's elementary functions
#: are widened outward (glibc documents at most 1-2 for the functions used here).
LIBM_ULPS = 4

#: The functions the evaluator encloses (besides sums, products and powers).
KNOWN_FUNCTIONS = ("sqrt", "exp", "log", "sin", "cos", "tan", "sinh", "cosh", "tanh", "atan",
                   "Abs", "Min", "Max")

_INF = math.inf
_Ival = tuple[float, float]
_Node = Callable[[Sequence[_Ival]], _Ival]


def _dn(v: float, k: int = 1) -> float:
    """``v`` moved ``k`` floats toward ``-inf`` (``-inf`` stays)."""
    if v != v:  # (NaN: an operation outside the evaluator's cases)
        return -_INF
    for _ in range(k):
        v = math.nextafter(v, -_INF)
    return v


def _up(v: float, k: int = 1) -> float:
    """``v`` moved ``k`` floats toward ``+inf``."""
    if v != v:
        return _INF
    for _ in range(k):
        v = math.nextafter(v, _INF)
    return v


# ---------------------------------------------------------------------- arithmetic
# (Dekker's splitting constant and the range in which TwoProduct is exact)
_SPLIT = 134217729.0  # 2**27 + 1
_BIG = 2.0 ** 995
_TINY = 2.0 ** -969


def _round_pair(p: float, e: float | None) -> _Ival:
    """The tightest float bounds of ``p + e`` (``e`` the exact error of ``p``, ``None``
    when unknown: one float outward each way)."""
    if e is None:
        return _dn(p), _up(p)
    if e == 0.0:
        return p, p
    return (p, _up(p)) if e > 0.0 else (_dn(p), p)


def _two_sum(a: float, b: float) -> _Ival:
    """Bounds of the exact ``a + b`` (Knuth's TwoSum: no widening when it is exact)."""
    s = a + b
    if not math.isfinite(s):
        return _dn(s), _up(s)
    bv = s - a
    av = s - bv
    return _round_pair(s, (a - av) + (b - bv))


def _split(a: float) -> tuple[float, float]:
    t = _SPLIT * a
    hi = t - (t - a)
    return hi, a - hi


def _two_prod(a: float, b: float) -> _Ival:
    """Bounds of the exact ``a * b`` (Dekker's TwoProduct where it is exact, i.e. away
    from overflow and underflow; one float outward each way elsewhere)."""
    if a == 0.0 or b == 0.0:  # (0 * inf is 0 for a bound: the other factor is finite)
        return 0.0, 0.0
    p = a * b
    if not (abs(a) < _BIG and abs(b) < _BIG and _TINY < abs(p) < _BIG):
        lo, hi = _dn(p), _up(p)
        if p == 0.0 or abs(p) < _TINY:  # (underflow: the sign is still known)
            lo, hi = (0.0, hi) if (a > 0) == (b > 0) else (lo, 0.0)
        return lo, hi
    ah, al = _split(a)
    bh, bl = _split(b)
    return _round_pair(p, ((ah * bh - p) + ah * bl + al * bh) + al * bl)


def _exact_or_enclosed(q: Fraction) -> _Ival:
    """The tightest float interval holding the rational ``q``."""
    try:
        f = float(q)
    except OverflowError:
        mag = math.log10(abs(q.numerator)) - math.log10(q.denominator)
        raise MagnitudeError(
            f"a constant of about {'-' if q < 0 else ''}1e{mag:.0f} is beyond the double "
            "range (|c| > 1.8e308): the interval evaluator works in double precision; "
            "rescale the model") from None
    if Fraction(f) == q:
        return f, f
    return (_dn(f), f) if Fraction(f) > q else (f, _up(f))


def _add(a: _Ival, b: _Ival) -> _Ival:
    return _two_sum(a[0], b[0])[0], _two_sum(a[1], b[1])[1]


def _mul(a: _Ival, b: _Ival) -> _Ival:
    if a[0] == a[1] == 0.0 or b[0] == b[1] == 0.0:
        return 0.0, 0.0
    p = (_two_prod(a[0], b[0]), _two_prod(a[0], b[1]), _two_prod(a[1], b[0]),
         _two_prod(a[1], b[1]))
    return min(v[0] for v in p), max(v[1] for v in p)


def _recip(a: _Ival, where: str) -> _Ival:
    if a[0] <= 0.0 <= a[1]:
        raise DomainError(f"division by {where} over [{a[0]!r}, {a[1]!r}], which holds 0")
    return _dn(1.0 / a[1]), _up(1.0 / a[0])


def _pow_nonneg(x: float, n: int) -> _Ival:
    """Bounds of ``x ** n`` for a float ``x >= 0`` and an integer ``n >= 0`` of any size:
    binary exponentiation with every product's bounds directed (exact products stay
    exact, so ``1 ** n = 1``, ``2 ** 10 = 1024`` exactly), ``O(log n)`` products."""
    lo = hi = 1.0
    blo = bhi = x
    while True:
        if n & 1:
            lo, hi = _two_prod(lo, blo)[0], _two_prod(hi, bhi)[1]
        n >>= 1
        if not n:
            break
        blo, bhi = _two_prod(blo, blo)[0], _two_prod(bhi, bhi)[1]
    return max(lo, 0.0), hi


def _ipow(a: _Ival, n: int) -> _Ival:
    """``a ** n`` for an integer ``n >= 0`` of any size (exact range: odd powers are
    increasing, even ones fold at 0), by :func:`_pow_nonneg` (no ``math.pow``, which
    rounds an exponent above ``2**53`` to a double and may change its parity)."""
    if n == 0:
        return 1.0, 1.0
    if n == 1:
        return a
    lo, hi = a

    def at(x: float) -> _Ival:  # bounds of x ** n for a float x of either sign
        if x >= 0.0:
            return _pow_nonneg(x, n)
        pl, ph = _pow_nonneg(-x, n)
        return (-ph, -pl) if n % 2 else (pl, ph)

    if n % 2 or lo >= 0.0:
        return at(lo)[0], at(hi)[1]
    if hi <= 0.0:
        return at(hi)[0], at(lo)[1]
    return 0.0, max(at(lo)[1], at(hi)[1])


def _clamp_nonneg(v: _Ival) -> _Ival:
    return max(v[0], 0.0), v[1]


def _monotone(fn: Callable[[float], float], a: _Ival, *, increasing: bool = True,
              lo_cap: float = -_INF, hi_cap: float = _INF) -> _Ival:
    def ev(x: float) -> float:
        try:
            return fn(x)
        except OverflowError:
            return _INF if (x > 0) == increasing else -_INF

    x0, x1 = (a[0], a[1]) if increasing else (a[1], a[0])
    lo, hi = _dn(ev(x0), LIBM_ULPS), _up(ev(x1), LIBM_ULPS)
    return max(lo, lo_cap), min(hi, hi_cap)


def _exp(a: _Ival) -> _Ival:
    return _monotone(math.exp, a, lo_cap=0.0)


def _log(a: _Ival, where: str, clip: bool = False) -> _Ival:
    if a[0] <= 0.0:
        if not clip or a[1] <= 0.0:
            raise DomainError(f"log of {where} over [{a[0]!r}, {a[1]!r}], which reaches 0 "
                              "or below" + (" everywhere" if a[1] <= 0.0 else ""))
        return -_INF, _monotone(math.log, (a[1], a[1]))[1]
    return _monotone(math.log, a)


def _sqrt(a: _Ival, where: str, clip: bool = False) -> _Ival:
    if a[0] < 0.0:
        if not clip or a[1] < 0.0:
            raise DomainError(f"sqrt of {where} over [{a[0]!r}, {a[1]!r}], which reaches "
                              "below 0" + (" everywhere" if a[1] < 0.0 else ""))
        a = (0.0, a[1])  # (the model holds at the truth: its argument is >= 0 there)

    def root(x: float, up: bool) -> float:
        # (sqrt is correctly rounded: widened by one float unless r * r == x exactly)
        r = math.sqrt(x)
        if _two_prod(r, r) == (x, x):
            return r
        return _up(r) if up else max(_dn(r), 0.0)
    return root(a[0], False), root(a[1], True)


def _rpow(b: _Ival, r: _Ival, where: str, clip: bool = False) -> _Ival:
    """``x ** r`` for a real, non-integer exponent (sympy's principal branch: real only
    for ``x >= 0``, and ``x > 0`` when ``r`` may be 0 or negative). For ``x > 0`` it is
    monotone in ``x`` and in ``r`` separately, so its range over the box is at a
    corner. ``clip``: a base reaching below 0 is cut to ``x >= 0`` when ``r > 0``."""
    if clip and b[0] < 0.0 <= b[1] and r[0] > 0.0:
        b = (0.0, b[1])
    if b[0] < 0.0 or (b[0] == 0.0 and r[0] <= 0.0):
        raise DomainError(f"power of {where} over [{b[0]!r}, {b[1]!r}] with exponent in "
                          f"[{r[0]!r}, {r[1]!r}]: not real (or not finite) over the box")

    def pw(x: float, e: float) -> float:
        try:
            return math.pow(x, e)
        except OverflowError:
            return _INF

    vals = [pw(x, e) for x in b for e in r]
    return max(_dn(min(vals), LIBM_ULPS), 0.0), _up(max(vals), LIBM_ULPS)


# pi enclosed: math.pi is the double nearest to pi, below it
_PI = (math.pi, _up(math.pi))


def _trig(a: _Ival, fn: Callable[[float], float], phase: float) -> _Ival:
    """``sin`` (``phase = 0``) or ``cos`` (``phase = pi / 2``, ``cos x = sin(x + pi/2)``)
    over ``a``: the endpoints' values, and ``+-1`` wherever an extremum may lie in the
    box (decided with a margin, so the answer only widens)."""
    lo, hi = a
    if not (math.isfinite(lo) and math.isfinite(hi)) or hi - lo >= 2.0 * _PI[0]:
        return -1.0, 1.0
    # extrema of sin(t) at t = pi/2 + j pi, t = x + phase: count them with a margin
    # (far above the rounding of t: beyond |x| ~ 6e9 the margin alone spans two
    # extrema, and the answer is [-1, 1] at once; the work is constant in |x|)
    m = 1e-9 * (1.0 + max(abs(lo), abs(hi)))
    t0 = (lo + phase - m) / math.pi - 0.5
    t1 = (hi + phase + m) / math.pi - 0.5
    j0, j1 = math.ceil(t0), math.floor(t1)
    if j1 - j0 >= 1:  # (two consecutive extrema: a maximum and a minimum)
        return -1.0, 1.0
    vals = [fn(lo), fn(hi)]
    out_lo, out_hi = _dn(min(vals), LIBM_ULPS), _up(max(vals), LIBM_ULPS)
    if j1 == j0:  # one extremum may lie in the box
        if j0 % 2 == 0:
            out_hi = 1.0
        else:
            out_lo = -1.0
    return max(out_lo, -1.0), min(out_hi, 1.0)


def _tan(a: _Ival, where: str) -> _Ival:
    lo, hi = a
    m = 1e-9 * (1.0 + max(abs(lo), abs(hi)))
    if not (math.isfinite(lo) and math.isfinite(hi)) or \
            math.floor((hi + m) / math.pi - 0.5) >= math.ceil((lo - m) / math.pi - 0.5):
        raise DomainError(f"tan of {where} over [{lo!r}, {hi!r}], which may hold a pole")
    return _monotone(math.tan, a)


def _cosh(a: _Ival) -> _Ival:
    lo, hi = a
    if lo >= 0.0:
        return _monotone(math.cosh, a, lo_cap=1.0)
    if hi <= 0.0:
        return _monotone(math.cosh, a, increasing=False, lo_cap=1.0)
    top = max(_monotone(math.cosh, (0.0, -lo))[1], _monotone(math.cosh, (0.0, hi))[1])
    return 1.0, top


def _abs(a: _Ival) -> _Ival:
    lo, hi = a
    if lo >= 0.0:
        return a
    if hi <= 0.0:
        return -hi, -lo
    return 0.0, max(-lo, hi)


# ---------------------------------------------------------------------- compiling
def _compile(e: Any, index: dict[Any, int], sp: Any, clip: bool = False) -> _Node:
    """A closure evaluating ``e`` over the boxes of its symbols (``clip``: the arguments
    of ``sqrt``, ``log`` and real powers cut to their domain, :class:`IntervalFunction`)."""
    where = str(e)
    if e.is_Symbol:
        if e not in index:
            raise ArgumentError(f"the expression uses {e}, which is not among the variables")
        i = index[e]
        return lambda X: X[i]
    if e.is_Rational:
        v = _exact_or_enclosed(Fraction(int(e.p), int(e.q)))
        return lambda X: v
    if e.is_Float:
        f = float(e)
        if not math.isfinite(f):
            raise MagnitudeError(
                f"the constant {sp.Float(e, 4)} is beyond the double range (|c| > 1.8e308): "
                "the interval evaluator works in double precision; rescale the model")
        r = sp.Rational(e)
        if Fraction(f) == Fraction(int(r.p), int(r.q)):
            v = (f, f)
        else:
            v = (_dn(f), _up(f))
        return lambda X: v
    if e == sp.pi:
        return lambda X: _PI
    if e == sp.E:
        v = (_dn(math.e), _up(math.e))
        return lambda X: v
    if e.is_Number:
        raise NotSupportedError(f"the number {e} has no real interval enclosure here")
    args = [_compile(a, index, sp, clip) for a in e.args]
    if e.is_Add or e.is_Mul:
        # (a quotient is a product with a negative power: 1 / x^n, its domain checked)
        op = _add if e.is_Add else _mul

        def fold(X: Sequence[_Ival]) -> _Ival:
            acc = args[0](X)
            for a in args[1:]:
                acc = op(acc, a(X))
            return acc
        return fold
    if e.is_Pow:
        base, ex = args[0], e.args[1]
        bwhere = str(e.args[0])
        if ex.is_Integer:
            n = int(ex)
            if n >= 0:
                return lambda X: _ipow(base(X), n)
            # (1 / x) ** |n|: a base whose power underflows (x**-2 over [1e-200,
            # 1e-199]) is no division by a box holding 0
            return lambda X: _ipow(_recip(base(X), bwhere), -n)
        if ex == sp.Rational(1, 2):
            return lambda X: _sqrt(base(X), bwhere, clip)
        if ex == sp.Rational(-1, 2):
            return lambda X: _recip(_sqrt(base(X), bwhere, clip), f"sqrt({bwhere})")
        expo = args[1]

        def real_pow(X: Sequence[_Ival]) -> _Ival:
            return _rpow(base(X), expo(X), bwhere, clip)
        return real_pow
    fname = type(e).__name__
    one = {"exp": _exp, "sin": lambda a: _trig(a, math.sin, 0.0),
           "cos": lambda a: _trig(a, math.cos, math.pi / 2),
           "sinh": lambda a: _monotone(math.sinh, a), "cosh": _cosh,
           "tanh": lambda a: _monotone(math.tanh, a, lo_cap=-1.0, hi_cap=1.0),
           "atan": lambda a: _monotone(math.atan, a, lo_cap=-_PI[1] / 2, hi_cap=_PI[1] / 2),
           "Abs": _abs}
    if fname in one and len(args) == 1:
        f1, a0 = one[fname], args[0]
        return lambda X: f1(a0(X))
    if fname == "log" and len(args) == 1:
        a0, aw = args[0], str(e.args[0])
        return lambda X: _log(a0(X), aw, clip)
    if fname == "tan":
        a0, aw = args[0], str(e.args[0])
        return lambda X: _tan(a0(X), aw)
    if fname in ("Min", "Max"):
        pick = min if fname == "Min" else max

        def minmax(X: Sequence[_Ival]) -> _Ival:
            vs = [a(X) for a in args]
            return pick(v[0] for v in vs), pick(v[1] for v in vs)
        return minmax
    if isinstance(type(e), sp.core.function.UndefinedFunction):
        close = difflib.get_close_matches(fname, KNOWN_FUNCTIONS, n=1)
        raise NotSupportedError(f"{fname} (in {where}) is not a known function"
                                + (f": did you mean {close[0]}?" if close else "")
                                + f" (the evaluator knows {', '.join(KNOWN_FUNCTIONS)})")
    raise NotSupportedError(f"interval evaluation of {fname} ({where}) is not supported")


class IntervalFunction:
    """Compiled interval enclosure of ``m`` expressions in ``n`` variables.

    Call it with a box, ``F(lo, hi)``, for ``(flo, fhi)`` (arrays of shape ``(m,)``):
    ``flo <= f(x) <= fhi`` for every ``x`` with ``lo <= x <= hi``.

    Parameters
    ----------
    exprs : sequence of sympy expressions or strings
    variables : sequence of sympy symbols or names
    clip_domain : bool
        Enclose ``f`` only at the points of the box where it is defined: the argument
        box of ``sqrt``, ``log`` or a real power that reaches below its domain is cut to
        the domain (``sqrt`` over ``[-1e-3, 4]`` is ``[0, 2]``) instead of raising
        :class:`~setobs.exceptions.DomainError` (still raised when the whole argument
        box lies outside). Sound wherever ``f`` is known to be defined at the point of
        interest -- a model evaluated at its true state -- not for derivatives, whose
        mean-value argument needs the whole segment in the domain.

    Attributes
    ----------
    exprs : tuple
        The expressions.
    variables : tuple
        Their variables, in the order of the box's entries.
    clip_domain : bool
        As given.
    """

    def __init__(self, exprs: Sequence[Any], variables: Sequence[Any],
                 clip_domain: bool = False) -> None:
        sp = optional_import("sympy", extra="nonlinear", feature="interval evaluation")
        self.clip_domain = bool(clip_domain)
        self.variables = tuple(sp.Symbol(v) if isinstance(v, str) else v for v in variables)
        if len(set(self.variables)) != len(self.variables):
            raise ArgumentError("the variables must be distinct")
        self.exprs = tuple(sp.sympify(e) for e in exprs)
        index = {v: i for i, v in enumerate(self.variables)}
        self._nodes = [_compile(e, index, sp, self.clip_domain) for e in self.exprs]

    @property
    def shape(self) -> tuple[int, int]:
        """``(m, n)``: expressions and variables."""
        return len(self.exprs), len(self.variables)

    def __call__(self, lo: ArrayLike, hi: ArrayLike | None = None
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The enclosure over the box ``[lo, hi]`` (``hi`` omitted: the point ``lo``)."""
        lo = np.asarray(lo, dtype=np.float64).ravel()
        hi = lo if hi is None else np.asarray(hi, dtype=np.float64).ravel()
        n = len(self.variables)
        if lo.shape != (n,) or hi.shape != (n,):
            raise DimensionError(f"the box must have {n} entries, got {lo.size} and {hi.size}")
        if np.isnan(lo).any() or np.isnan(hi).any() or (lo > hi).any():
            raise DomainError(f"the box [{lo.tolist()}, {hi.tolist()}] has NaN bounds or a "
                              "lower bound above its upper bound: pass lo <= hi")
        X = list(zip(lo.tolist(), hi.tolist(), strict=True))
        out = [node(X) for node in self._nodes]
        return (np.array([o[0] for o in out], dtype=np.float64),
                np.array([o[1] for o in out], dtype=np.float64))

    def __reduce__(self):
        # (the compiled closures do not pickle: rebuilt from the expressions)
        return (type(self), (self.exprs, self.variables, self.clip_domain))

    def __repr__(self) -> str:
        m, n = self.shape
        return f"IntervalFunction({m} expressions in {n} variables)"


def interval_function(exprs: Any, variables: Sequence[Any]) -> IntervalFunction:
    """Compile sympy expressions (or strings) into an outward-rounded interval enclosure.

    Parameters
    ----------
    exprs : sympy expression, str, or sequence of them
        The functions ``f_1 .. f_m``.
    variables : sequence of sympy symbols or names
        The variables, in the order of the box's entries.

    Returns
    -------
    IntervalFunction
        ``F(lo, hi) -> (flo, fhi)``.

    Raises
    ------
    NotSupportedError
        A function the evaluator has no enclosure for.
    DomainError
        (when called) A box that leaves a function's domain.

    Notes
    -----
    The natural interval extension with outward rounding (module docstring): sound for
    every real point of the box; tight (up to rounding) when every variable occurs
    once in an expression, wider otherwise (the dependency effect).

    Examples
    --------
    >>> import setobs as so
    >>> F = so.interval.interval_function(["x**2 - x"], ["x"])
    >>> lo, hi = F([0.0], [1.0])
    >>> bool(lo[0] <= -0.25 and hi[0] >= 0.0)
    True
    """
    if isinstance(exprs, str) or not isinstance(exprs, Sequence):
        exprs = [exprs]
    return IntervalFunction(list(exprs), list(variables))
