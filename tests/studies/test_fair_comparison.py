"""Fair comparisons: equal information, Kalman and tuned PIO baselines.

The Kalman baseline is checked against a textbook time-varying Kalman filter
written here; the pinned finding (the ">40 % better" claim holds against the
printed-pole PIO, not against a Kalman filter or a tuned PIO on equal
information) is asserted on 40 runs with bootstrap intervals.
"""

import numpy as np
import pytest

import setobs as so
from setobs.exceptions import DesignError, InvalidValueError
from setobs.studies import (
    ObserverSpec,
    Scenario,
    cluster_poles,
    kalman_baseline,
    pio_pole_sweep,
    rng_for_run,
    run_campaign,
)

SC = Scenario(system="chang2006", horizon=200, increment=1.0, x0_box=1.0)


def test_filtered_estimate_is_the_next_predicted_one():
    sys = SC.build_system()
    tr = SC.simulate(rng_for_run(3, 0))
    pred = so.observers.PIO(sys).run(tr.Y)
    filt = so.observers.PIO(sys, information="filtered").run(tr.Y)
    assert np.array_equal(filt.estimate[:-1], pred.estimate[1:])
    assert pred.information == "y_0..y_(k-1)" and filt.information == "y_0..y_k"
    with pytest.raises(DesignError, match="information must be"):
        so.observers.PIO(sys, information="smoothed")


def test_kalman_baseline_equals_a_textbook_kalman_filter():
    """Time-varying Kalman filter of the augmented model, from a large prior: after it has
    converged, d_hat(k|k) equals the steady-state baseline's estimate."""
    sys = SC.build_system()
    a = sys.augmented()
    A, C = a.A, a.C
    n, q = sys.n, sys.q
    Q = np.zeros((n + q, n + q))
    Q[n:, n:] = np.eye(q) / 3.0
    R = 1e-6 * np.eye(sys.l)
    tr = SC.simulate(rng_for_run(4, 0))
    z = np.zeros(n + q)             # z(k|k-1)
    P = 1e4 * np.eye(n + q)
    d_filt = []
    for y in tr.Y:
        S = C @ P @ C.T + R
        K = P @ C.T @ np.linalg.inv(S)
        zf = z + K @ (y - C @ z)    # z(k|k)
        Pf = (np.eye(n + q) - K @ C) @ P
        d_filt.append(zf[n:])
        z = A @ zf
        P = A @ Pf @ A.T + Q
    d_filt = np.array(d_filt)
    est = kalman_baseline(SC, sys).run(tr.Y).estimate
    np.testing.assert_allclose(est[100:], d_filt[100:], atol=1e-6)


def test_pole_clusters_and_bad_input():
    assert np.allclose(cluster_poles(0.5, 5), [0.45, 0.475, 0.5, 0.525, 0.55])
    with pytest.raises(InvalidValueError, match="radius must lie"):
        cluster_poles(0.99, 3)
    with pytest.raises(InvalidValueError, match="runs must be"):
        pio_pole_sweep(SC, [0.5], runs=1)
    with pytest.raises(InvalidValueError, match="measurement_cov"):
        kalman_baseline(SC, measurement_cov=0.0)


def test_campaign_states_the_information_and_runs_the_kalman_baseline():
    specs = [ObserverSpec("SMFDO", "smfdo", {"window": 3}), ObserverSpec("PIO", "pio"),
             ObserverSpec("PIO (paper)", "pio", {"information": "predicted"}),
             ObserverSpec("printed", "pio_printed"), ObserverSpec("KF", "kalman"),
             ObserverSpec("HO", "higher_order")]
    camp = run_campaign(Scenario(system="chang2006", horizon=30), specs, 2, processes=1,
                        progress=False)
    info = camp.summary()["information"].to_dict()
    assert info == {"SMFDO": "y_0..y_k", "PIO": "y_0..y_k", "PIO (paper)": "y_0..y_(k-1)",
                    "printed": "y_0..y_k", "KF": "y_0..y_k", "HO": "y_0..y_(k-1)"}
    # the improvement is the ratio of the per-run means, computed here by hand
    t = camp.table[camp.table["k"] >= 10]
    m = t.groupby("observer")["error_inf"].mean()
    imp = camp.improvement("SMFDO", "KF")
    assert imp.value == pytest.approx(1 - m["SMFDO"] / m["KF"])
    assert imp.lo <= imp.value <= imp.hi
    with pytest.raises(InvalidValueError, match="no observer named"):
        camp.improvement("SMFDO", "nobody")


def test_the_forty_percent_claim_holds_only_against_the_printed_pole_pio():
    """Li-Cong-Dong Fig. 1(b): "SMFDO improves the accuracy by over 40 %". Pinned finding
    (40 runs x 200 steps, 95 % bootstrap intervals), for the paper's Algorithm 1 (the
    window restarts from a box, eq. (24)): against the PIO at the printed poles it holds
    (59 %); on equal information against the steady-state Kalman filter it does not
    (31 %, interval below 40 %), nor against a PIO tuned on separate runs (38 %); with
    window 3 the SMFDO is no better than the Kalman filter. With the polytope restart
    window 3 is better than the Kalman filter (13 %,
    interval above 5 %): the box restart is what made window 3 weak."""
    sweep = pio_pole_sweep(SC, [0.3, 0.4, 0.5, 0.6, 0.7], runs=12, base_seed=1)
    assert 0.4 <= sweep.best_radius <= 0.6
    specs = [ObserverSpec("SMFDO d=3", "smfdo", {"window": 3, "restart": "box"}),
             ObserverSpec("SMFDO d=10", "smfdo", {"window": 10, "restart": "box"}),
             ObserverSpec("SMFDO d=3 polytope", "smfdo", {"window": 3, "restart": "polytope"}),
             ObserverSpec("PIO (paper)", "pio", {"information": "predicted"}),
             ObserverSpec("PIO (tuned)", "pio",
                          {"poles": list(cluster_poles(sweep.best_radius, 5))}),
             ObserverSpec("Kalman filter", "kalman")]
    camp = run_campaign(SC, specs, 40, processes=1, progress=False)
    vs_paper = camp.improvement("SMFDO d=10", "PIO (paper)")
    vs_kalman = camp.improvement("SMFDO d=10", "Kalman filter")
    vs_tuned = camp.improvement("SMFDO d=10", "PIO (tuned)")
    small_vs_kalman = camp.improvement("SMFDO d=3", "Kalman filter")
    poly_vs_kalman = camp.improvement("SMFDO d=3 polytope", "Kalman filter")
    assert vs_paper.lo > 0.40
    assert vs_kalman.hi < 0.40 and vs_kalman.lo > 0.2
    assert vs_tuned.value < 0.40 and vs_tuned.lo > 0.3
    assert small_vs_kalman.lo < 0.05 < 0.40
    assert poly_vs_kalman.lo > 0.05
