"""Hit-and-run's chords on one warm HiGHS model per chain.

Oracle: the chord ``{t : x + t u in Z}`` as two LPs written in the test and solved by
scipy's ``linprog`` (a fresh model each), for many directions in a row on one chain.
"""

import numpy as np
import pytest
from scipy.optimize import linprog

from setobs.geometry import sample
from setobs.geometry.measure import LPChords
from tests.conftest import random_cz


def linprog_chord(Z, x, u):
    n_g = Z.n_gen
    A_eq = np.vstack([np.hstack([u[:, None], -Z.G]), np.hstack([np.zeros((Z.n_con, 1)), Z.A])])
    b_eq = np.concatenate([Z.c - x, Z.b])
    bounds = [(None, None)] + [(-h, h) for h in Z.h]
    e = np.zeros(1 + n_g)
    e[0] = 1.0
    lo = linprog(e, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
    hi = linprog(-e, A_eq=A_eq, b_eq=b_eq, bounds=bounds, method="highs")
    assert lo.status == 0 and hi.status == 0
    return lo.x[0], hi.x[0]


@pytest.mark.parametrize("seed", range(3))
def test_warm_chords_equal_fresh_linprog_chords(seed):
    """Thirty chords in a row on one model (the direction and the point change each
    time): each equals scipy's, to 1e-7 of the set's size."""
    rng = np.random.default_rng(seed)
    Z = random_cz(rng, n=4, n_g=8, n_c=2)
    oracle = LPChords(Z)
    x = sample(Z, 1, rng=seed, burn_in=20)[0]
    size = float(Z.interval_hull().width.max())
    for _ in range(30):
        u = rng.normal(size=4)
        u /= np.linalg.norm(u)
        lo, hi = oracle.chord(x, u)
        lo_r, hi_r = linprog_chord(Z, x, u)
        assert abs(lo - lo_r) <= 1e-7 * size and abs(hi - hi_r) <= 1e-7 * size
        assert lo <= 1e-9 * size and hi >= -1e-9 * size  # (x is in the set)
        x = x + rng.uniform(lo, hi) * u * (1.0 - 1e-9)
