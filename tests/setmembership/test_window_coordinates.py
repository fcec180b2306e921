"""The windowed SMFDO depends on the state coordinates of its
restart box; the exact mode does not (Li-Cong-Dong Algorithm 1, line 12)."""

import numpy as np
from scipy.stats import ortho_group

import setobs as so
from setobs.studies import Scenario, rng_for_run

SC = Scenario(system="chang2006", horizon=200, increment=1.0, x0_box=1.0)


def _rotated(sys, R):
    return so.LinearSystem(R @ sys.Phi @ R.T, R @ sys.G, sys.Xi @ R.T)


def _run(sys_r, R, window, tr, steps=None):
    Y = tr.Y if steps is None else tr.Y[:steps]
    # (the box restart of eq. (24), whose coordinate dependence is pinned here)
    return so.SMFDO(sys_r, window=window, increment_set=SC.increment_set(2), restart="box",
                    initial_state_set=R @ SC.initial_state_set(3)).run(Y)


def test_exact_mode_does_not_depend_on_the_state_coordinates():
    sys = SC.build_system()
    tr = SC.simulate(rng_for_run(0, 0))
    R = ortho_group.rvs(3, random_state=1)
    a = _run(sys, np.eye(3), None, tr, 60)
    b = _run(_rotated(sys, R), R, None, tr, 60)
    np.testing.assert_allclose(b.lo[5:], a.lo[5:], atol=1e-6)
    np.testing.assert_allclose(b.hi[5:], a.hi[5:], atol=1e-6)


def test_window_three_is_worse_in_rotated_coordinates():
    """Pinned: the model's coordinates give 1.47 on these runs; three random rotations of
    x give more than 1.5 (and every band still contains the truth)."""
    sys = SC.build_system()
    recs = [SC.simulate(rng_for_run(0, r)) for r in range(10)]

    def mean_error(R):
        s2 = _rotated(sys, R)
        errs = []
        for tr in recs:
            res = _run(s2, R, 3, tr)
            assert res.violations(tr.D) == 0
            errs.append(np.abs(res.estimate - tr.D).max(axis=1)[10:].mean())
        return float(np.mean(errs))

    base = mean_error(np.eye(3))
    rotated = [mean_error(ortho_group.rvs(3, random_state=s)) for s in (1, 2, 3)]
    assert base < 1.5
    assert all(e > base + 0.04 for e in rotated)
