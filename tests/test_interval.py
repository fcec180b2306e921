"""The interval evaluator (setobs.interval) against high-precision evaluation (mpmath at
60 digits, the points converted exactly) and closed-form ranges."""

from __future__ import annotations

import math

import numpy as np
import pytest

sympy = pytest.importorskip("sympy")
mpmath = pytest.importorskip("mpmath")

import setobs as so  # noqa: E402
from setobs.interval import interval_function  # noqa: E402

X, Y = sympy.symbols("x y")

# (expression, domain of x, domain of y): boxes are drawn inside the domains
CASES = [
    ("x**2 - 3*x*y + y**3", (-3, 3), (-2, 2)),
    ("sin(x) * exp(y) + cos(2*x - y)", (-20, 20), (-3, 3)),
    ("sqrt(y) + log(y) - x / (1 + y)", (-5, 5), (0.01, 10)),
    ("tanh(x * y) + atan(x - y) + Abs(x) ** 3", (-4, 4), (-4, 4)),
    ("x ** (S(1)/3) + y ** S(5)/2 - 0.1 * x + x ** y", (0, 8), (-1.5, 1.5)),
    ("sinh(x) - cosh(y) + exp(-x**2) * y**(-2)", (-3, 3), (0.5, 4)),
    ("0.2 * sqrt(2 * 9.81) * sqrt(y) - 0.3 * sqrt(y) / (x**2 + 1)", (-2, 2), (0.0, 3)),
    ("Max(x, y) - Min(x * y, 1) + tan(x / 3)", (-4, 4), (-2, 2)),
    ("pi * x + E ** y + 1/(x**2 + y**2 + S(1)/10)", (-2, 2), (-2, 2)),
    ("y ** 1.5 + x ** 4 - x ** 3", (-2, 2), (0.0, 4)),
]




@pytest.mark.parametrize("expr,dx,dy", CASES)
def test_every_point_of_a_box_is_inside_its_enclosure(expr, dx, dy):
    """Random boxes (some degenerate: single points, where only the rounding is left),
    random points in each: the 60-digit value lies in the enclosure."""
    rng = np.random.default_rng(abs(hash(expr)) % 2**32)
    F = interval_function([sympy.sympify(expr)], [X, Y])
    f = sympy.lambdify((X, Y), sympy.sympify(expr), modules="mpmath")
    with mpmath.workdps(60):
        for trial in range(24):
            a = np.sort(rng.uniform(*dx, 2))
            b = np.sort(rng.uniform(*dy, 2))
            if trial % 4 == 0:  # (a point: the enclosure is the rounding alone)
                a[1], b[1] = a[0], b[0]
            lo, hi = F([a[0], b[0]], [a[1], b[1]])
            pts = [(a[0], b[0]), (a[1], b[1]), (a[0], b[1]), (a[1], b[0])]
            pts += list(zip(rng.uniform(a[0], a[1], 20), rng.uniform(b[0], b[1], 20),
                            strict=True))
            for x, y in pts:
                v = f(mpmath.mpf(x), mpmath.mpf(y))  # (the floats, converted exactly)
                assert mpmath.mpf(lo[0]) <= v <= mpmath.mpf(hi[0]), (expr, x, y, lo, hi, v)


def test_a_point_is_enclosed_within_a_few_units_in_the_last_place():
    """At a point the enclosure is the rounding only: a few ulps wide, around the
    exact value (1/3 at x = 1: the constant's enclosure, one ulp, and the product's
    outward step on either side; and an expression with libm functions)."""
    F = interval_function(["x / 3", "exp(x) * sin(x) + 0.1"], ["x"])
    lo, hi = F([1.0])
    third = mpmath.mpf(1) / 3
    assert lo[0] <= third <= hi[0] and hi[0] - lo[0] <= 3 * math.ulp(1 / 3)
    with mpmath.workdps(60):
        v = mpmath.exp(1) * mpmath.sin(1) + mpmath.mpf(1) / 10
    assert lo[1] <= v <= hi[1] and hi[1] - lo[1] <= 40 * math.ulp(float(v))


@pytest.mark.parametrize("expr,box,rng_exact", [
    ("x**2", (-1.0, 2.0), (0.0, 4.0)),             # even power folds at 0
    ("x**3", (-2.0, 1.0), (-8.0, 1.0)),
    ("sin(x)", (1.0, 2.0), (math.sin(1.0), 1.0)),   # pi/2 inside: the maximum
    ("cos(x)", (3.0, 3.5), (-1.0, math.cos(3.5))),  # pi inside: the minimum
    ("cos(x)", (0.5, 1.0), (math.cos(1.0), math.cos(0.5))),
    ("exp(x)", (-1.0, 1.0), (math.exp(-1.0), math.e)),
    ("Abs(x)", (-3.0, 2.0), (0.0, 3.0)),
    ("1/x", (2.0, 4.0), (0.25, 0.5)),
    ("sqrt(x)", (0.0, 4.0), (0.0, 2.0)),
    ("cosh(x)", (-1.0, 2.0), (1.0, math.cosh(2.0))),
])
def test_a_single_use_expression_gets_its_exact_range(expr, box, rng_exact):
    """Each variable once: the natural extension is the exact range, up to the outward
    rounding (a few ulps; the closed-form range computed independently)."""
    lo, hi = interval_function([expr], ["x"])([box[0]], [box[1]])
    tol = lambda v: 8 * math.ulp(max(abs(v), 1e-300))  # noqa: E731
    assert rng_exact[0] - tol(rng_exact[0]) <= lo[0] <= rng_exact[0]
    assert rng_exact[1] <= hi[0] <= rng_exact[1] + tol(rng_exact[1])


def test_a_box_wider_than_a_period_gives_the_whole_range_of_sin_and_cos():
    lo, hi = interval_function(["sin(x)", "cos(x)"], ["x"])([-1.0], [6.4])
    assert lo.tolist() == [-1.0, -1.0] and hi.tolist() == [1.0, 1.0]


def test_overflow_gives_an_infinite_bound_not_nan():
    lo, hi = interval_function(["exp(x)", "x**400"], ["x"])([0.0], [1000.0])
    assert hi.tolist() == [math.inf, math.inf] and lo[0] <= 1.0 and lo[1] <= 0.0


@pytest.mark.parametrize("expr,box,match", [
    ("sqrt(x)", (-1e-12, 1.0), r"sqrt of x over \[-1e-12, 1.0\], which reaches below 0"),
    ("log(x - 1)", (0.5, 2.0), r"log of x - 1 over .* reaches 0 or below"),
    ("1 / x", (-1.0, 1.0), r"division by x over \[-1.0, 1.0\], which holds 0"),
    ("1 / sqrt(x)", (0.0, 1.0), r"division by sqrt\(x\)"),
    ("x ** 0.5", (-1.0, 1.0), r"power of x over \[-1.0, 1.0\] with exponent in \[0.5, 0.5\]"),
    ("x ** (S(1)/3)", (-1.0, 1.0), r"power of x over .* not real"),
    ("x ** -0.5", (0.0, 1.0), r"power of x over"),
    ("tan(x)", (1.0, 2.0), r"tan of x over .* pole"),
])
def test_a_box_outside_the_domain_is_reported(expr, box, match):
    F = interval_function([expr], ["x"])
    with pytest.raises(so.DomainError, match=match):
        F([box[0]], [box[1]])


def test_bad_input():
    F = interval_function(["x + y"], ["x", "y"])
    with pytest.raises(so.DimensionError, match="the box must have 2 entries, got 3"):
        F([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    with pytest.raises(so.DomainError, match="lower bound above its upper bound"):
        F([1.0, 0.0], [0.0, 1.0])
    with pytest.raises(so.DomainError, match="NaN"):
        F([np.nan, 0.0], [1.0, 1.0])
    with pytest.raises(so.ArgumentError, match="uses z, which is not among the variables"):
        interval_function(["x + z"], ["x", "y"])
    with pytest.raises(so.ArgumentError, match="distinct"):
        interval_function(["x"], ["x", "x"])
    with pytest.raises(so.NotSupportedError, match="interval evaluation of gamma"):
        interval_function(["gamma(x)"], ["x"])
    with pytest.raises(so.NotSupportedError, match="interval evaluation of ImaginaryUnit"):
        interval_function(["x + I"], ["x"])


# ------------------------------------------- integer powers, huge arguments, edges
@pytest.fixture
def dps60():
    """mpmath at 60 digits for one test."""
    with mpmath.workdps(60):
        yield


def _enc(expr: str, lo: float, hi: float) -> tuple[float, float]:
    a, b = interval_function([expr], ["x"])([lo], [hi])
    return float(a[0]), float(b[0])


def _inside(v, lo: float, hi: float) -> bool:
    return mpmath.mpf(lo) <= v <= mpmath.mpf(hi)


@pytest.mark.parametrize("n", [2**53 + 1, 2**53 + 2, 2**60 + 128, 2**64 + 3, 10**20 + 7])
@pytest.mark.parametrize("x", [-1.0, 1.0, -1.0000000000000002, 1.0000000000000002,
                               -0.9999999999999999, 0.5, -2.0])
def test_integer_powers_above_2_53_hold_the_exact_value(n, x, dps60):
    # math.pow rounded 2**53 + 1 to 2**53 (even): x = -1 gave +1
    lo, hi = _enc(f"x**{n}", x, x)
    assert lo <= hi
    v = mpmath.mpf(x) ** n
    assert _inside(v, lo, hi), (lo, hi, v)
    if abs(x) == 1.0:  # exact products stay exact
        assert lo == hi == float(v)


def test_integer_powers_over_boxes_hold_every_point(dps60):
    rng = np.random.default_rng(59)
    for _ in range(200):
        n = int(rng.choice([3, 4, 17, 2**53 + 1, 2**53 + 4, 1001]))
        a, b = np.sort(rng.normal(size=2) * 10.0 ** rng.uniform(-1, 0.1))
        lo, hi = _enc(f"x**{n}", a, b)
        assert lo <= hi
        for t in (a, b, 0.5 * (a + b), 0.0 if a <= 0.0 <= b else a):
            assert _inside(mpmath.mpf(t) ** n, lo, hi)
    lo, hi = _enc(f"x**{2**53 + 1}", -1.0000000000000002, -1.0)
    assert lo <= hi == -1.0


@pytest.mark.parametrize("x", [1e6, 1e9, 1e12, 1e17, 1e18, 1e300, -1e308])
@pytest.mark.parametrize("fn", ["sin", "cos"])
def test_sin_and_cos_of_huge_arguments_are_enclosed_at_once(fn, x, dps60):
    # (the candidate-extremum loop ran about 1e-9 |x| times: no return at 1e18)
    lo, hi = _enc(f"{fn}(x)", x, x)
    v = getattr(mpmath, fn)(mpmath.mpf(x))
    assert _inside(v, lo, hi)
    if abs(x) < 1e8:  # below the threshold a point is enclosed tightly
        assert hi - lo < 1e-6
    lo, hi = _enc(f"{fn}(x)", x, np.nextafter(x, np.inf))
    assert _inside(v, lo, hi)


def test_sin_near_its_extrema_keeps_them():
    for k in (0, 1, 7, 10**6):
        t = (k + 0.5) * math.pi
        lo, hi = _enc("sin(x)", t - 1e-3, t + 1e-3)
        top = (-1.0) ** k
        assert (hi == 1.0) if top > 0 else (lo == -1.0)


@pytest.mark.parametrize("expr", ["x + 10**400", "x*1e400", "tanh(x)*1e308*10", "x - 10**309"])
def test_constants_beyond_the_double_range_raise_a_clear_error(expr):
    with pytest.raises(so.MagnitudeError, match="beyond the double range"):
        interval_function([expr], ["x"])


@pytest.mark.parametrize("expr, box, point", [
    ("sqrt(-x)", (-1.0, 0.0), 0.0), ("sqrt(1 - x**2)", (-1.0, 1.0), 1.0),
    ("sqrt(x - 1)", (1.0, 5.0), 1.0), ("sqrt(x + 1)", (-1.0, 3.0), -1.0),
    ("x**-2", (1e-200, 1e-199), 1e-200), ("log(x)", (1.0, 2.0), 1.0)])
def test_boxes_exactly_at_a_domains_edge_are_accepted(expr, box, point, dps60):
    lo, hi = _enc(expr, *box)
    import sympy as sp

    v = sp.sympify(expr).subs("x", sp.Float(point, 60)).evalf(60)
    assert _inside(mpmath.mpf(str(v)), lo, hi)
    assert lo >= 0.0 or expr.startswith("log")


def test_a_wide_initial_set_does_not_hang_the_nonlinear_observer():
    # shared/data/regressions/nonlinear_wide_initial_set_hang.py: sin and cos of boxes of
    # 1e8 took the extremum loop 1e-1 ... 1e15 rounds
    f = ["0.9*x + 0.2*sin(y)", "0.8*y - 0.1*x**3 + 0.05*cos(x)"]
    obs = so.NonlinearSetObserver(f, ["x + 0.1*y**2"], ["x", "y"], process_noise=1e-3,
                                  measurement_noise=0.01,
                                  initial_state_set=so.Box([-1e8, -1e8], [1e8, 1e8]),
                                  method="taylor")
    for y in ([0.52], [0.49], [0.47]):
        st = obs.step(y)
        assert np.all(st.state_lo <= st.state_hi)


def test_clip_domain_encloses_only_where_the_function_is_defined():
    """``clip_domain``: ``sqrt`` over an argument box reaching below 0 is its range over
    the part inside the domain (exact ends here), ``log`` unbounded below at 0; a box
    entirely outside still raises, and without ``clip_domain`` the partial box raises."""
    F = so.interval.IntervalFunction(["sqrt(x + 1)", "log(x + 2)"], ["x"], clip_domain=True)
    lo, hi = F([-2.5], [3.0])
    assert lo[0] == 0.0 and hi[0] >= 2.0 and hi[0] < 2.0 + 1e-15
    assert lo[1] == -np.inf and hi[1] >= np.log(5.0)
    with pytest.raises(so.DomainError, match="everywhere"):
        F([-4.0], [-3.0])
    with pytest.raises(so.DomainError, match="sqrt of x \\+ 1"):
        so.interval.IntervalFunction(["sqrt(x + 1)"], ["x"])([-1.5], [3.0])
