"""The windowed step's compiled kernels against exact rational arithmetic.

Oracle: ``fractions.Fraction`` (the closed form's data computed exactly from the
system's matrices by the recursion itself, eqs. (20)-(21) of Li-Cong-Dong; the exact
sums of the hull's ends); the margins against their formula.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from setobs import ConstrainedZonotope
from setobs.setmembership import _kernels
from setobs.setmembership._closed_form import WindowModel
from tests.oracles import assert_box_covers, assert_outward_sums, outward_sum_cases


def _fr(M):
    return [[Fraction(float(x)) for x in row] for row in np.atleast_2d(M)]


def _mv(M, v):
    return [sum((a * x for a, x in zip(row, v, strict=True)), Fraction(0)) for row in M]


@pytest.mark.parametrize("seed", range(6))
def test_assembled_data_contain_the_exact_closed_form(seed):
    """``c = c_s`` and ``b = (y_j - C_o c_j)_j`` of ``s`` steps of ``c_j = A c_(j-1) +
    Gamma u_(j-1) + B c_D`` from ``c_0 = c_S`` (Li-Cong-Dong eqs. (20)-(21) on the
    centres), computed exactly: the float data lie within their error bounds, with
    large centres that cancel against the measurements (``|y| ~ 1e6``, ``b ~ 1``)."""
    rng = np.random.default_rng(seed)
    n, q, l, p, s = 3, 1, 2, 1, 1 + seed % 4
    A = rng.normal(size=(n, n)) / 2.0
    B = rng.normal(size=(n, q))
    C = rng.normal(size=(l, n))
    Gam = rng.normal(size=(n, p))
    cD = rng.normal(size=q) * 0.1
    inc = ConstrainedZonotope(np.eye(q), cD)
    model = WindowModel(A, B, C, Gam, increment=inc, G_S=np.eye(n), A_S=np.zeros((0, n)),
                        free_S=np.zeros(n, dtype=bool), s=s, first_posterior=False, P=None,
                        unbounded_radius=1e8)
    c_S = rng.normal(size=n) * 1e6
    U = rng.normal(size=(s, p)) * 10.0
    # measurements near the predictions, so that b cancels to O(1)
    cs, cj = [], c_S.copy()
    for j in range(s):
        cj = A @ cj + Gam @ U[j] + B @ cD
        cs.append(cj)
    Y = np.array([C @ x + rng.normal(size=l) for x in cs])
    c, b, h, c_err, b_err, y_scale = model.assemble(c_S, np.zeros(0), np.ones(n), Y, U)
    assert y_scale == np.abs(Y).max()
    assert np.array_equal(h, np.concatenate([np.ones(n), np.tile(inc.h, s)]))
    # exact recursion
    Af, Bf, Cf, Gf = _fr(A), _fr(B), _fr(C), _fr(Gam)
    x = [Fraction(float(v)) for v in c_S]
    bex = []
    for j in range(s):
        uj = [Fraction(float(v)) for v in U[j]]
        x = [a + g + d for a, g, d in zip(_mv(Af, x), _mv(Gf, uj),
                                          _mv(Bf, [Fraction(float(v)) for v in cD]), strict=True)]
        bex += [Fraction(float(yv)) - cx for yv, cx in zip(Y[j], _mv(Cf, x), strict=True)]
    assert b.size == len(bex)
    for i, v in enumerate(x):
        assert abs(Fraction(float(c[i])) - v) <= Fraction(float(c_err[i]))
    for i, v in enumerate(bex):
        assert abs(Fraction(float(b[i])) - v) <= Fraction(float(b_err[i]))
    # the bounds are not vacuous: far below the magnitudes that cancel
    assert np.all(b_err <= 1e-6 * y_scale)


def test_hull_bounds_contain_the_exact_sums_and_report_crossing():
    c, e, low, upp = outward_sum_cases(8)
    bounds = np.empty(2 * c.size)
    bounds[0::2], bounds[1::2] = low, -upp
    lo, hi, ok = _kernels.hull_bounds(bounds, c, e)
    assert ok
    assert_outward_sums(lo, hi, c, e, low, upp)
    bounds[10], bounds[11] = 1.0, -0.5  # low 1 > upp 0.5
    assert not _kernels.hull_bounds(bounds, c, e)[2]


def test_box_start_covers_the_box_exactly():
    rng = np.random.default_rng(3)
    lo = rng.normal(size=300) * 10.0 ** rng.integers(-10, 10, 300)
    hi = lo + np.abs(rng.normal(size=300)) * 10.0 ** rng.integers(-12, 3, 300)
    hi[:5] = lo[:5]  # points
    lo[5], hi[6], lo[7], hi[7] = -np.inf, np.inf, -np.inf, np.inf
    c, r = _kernels.box_start(lo, hi)
    for i in range(300):
        if i in (5, 6, 7):  # unbounded on a side: free both ways
            assert c[i] == 0.0 and r[i] == np.inf
            continue
        assert_box_covers(c[i:i + 1], r[i:i + 1], lo[i:i + 1], hi[i:i + 1])
        if i < 5:
            assert r[i] == 0.0
        else:  # and not loose: within a few ulps of the half-width
            assert r[i] <= 0.5 * (hi[i] - lo[i]) * (1 + 1e-15) + 4 * np.spacing(abs(c[i]))


def test_reported_margins_centre_and_radius():
    lo_o = np.array([-1.0, -np.inf, 5e8])
    hi_o = np.array([2.0, 3.0, 6e8])
    lo = np.array([-3.0, 0.5, -np.inf])
    hi = np.array([-1.0, 0.5, np.inf])
    m = 1e-9
    ho_lo, ho_hi, lo2, hi2, est, rad, finite = _kernels.reported(lo_o, hi_o, lo, hi, m)
    # margin * max(1, |lo|, |hi|) over the finite ends
    assert ho_lo[0] == -1.0 - 2e-9 and ho_hi[0] == 2.0 + 2e-9
    assert ho_lo[1] == -np.inf and ho_hi[1] == 3.0 + 3e-9
    assert ho_lo[2] == 5e8 - 0.6 and ho_hi[2] == 6e8 + 0.6
    assert lo2[0] == -3.0 - 3e-9 and hi2[0] == -1.0 + 3e-9
    assert lo2[1] == 0.5 - 1e-9 and hi2[1] == 0.5 + 1e-9
    assert lo2[2] == -np.inf and hi2[2] == np.inf
    assert est[0] == pytest.approx(-2.0) and est[1] == 0.5 and np.isnan(est[2])
    assert rad == np.inf and not finite
    _, _, _, _, est, rad, finite = _kernels.reported(lo_o[:1], hi_o[:1], lo[:2], hi[:2], 0.0)
    assert finite and rad == 1.0 and est.tolist() == [-2.0, 0.5]
