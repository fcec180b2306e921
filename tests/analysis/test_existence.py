"""Theorem 1 (both forms), observability, observer conditions, error poles, diagnose."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad_vec
from scipy.linalg import expm

import setobs as so
from setobs import DimensionError, LinearSystem
from setobs import examples as ex
from setobs.analysis import (
    augmented_observability,
    bounded_do_exists,
    diagnose,
    fu_wang_eq10_matrix,
    higher_order_error_poles,
    ibar,
    modular_conditions,
    observability,
    observability_decomposition,
    observability_matrix,
    pio_conditions,
    pio_error_poles,
)
from setobs.exceptions import InvalidValueError
from tests.analysis.helpers import (
    block_system,
    diagonal_rescaling,
    random_similarity,
    siso_with_zeros,
    with_unobservable_disturbance,
)
from tests.printed import has_number

# Published gains (Fu-Wang, Sec. IV).
P0_HO = [[1.1902, 0.0181], [2.1356, 2.0195], [-1.3507, 0.0344]]
L0_HO = [[0.37, 0.0], [0.36, 0.36], [-0.36, 0.0]]
L1_HO = [[0.70, 0.0], [1.20, 1.20], [-0.85, 0.0]]
P_PIO = [[31.7392, 19.6384], [1.8918, 1.7307], [29.3767, 19.9849]]
L_PIO = [[51.1873, 34.5803], [-21.3249, -10.6399]]


# ------------------------------------------------------------------------ LinearSystem
@pytest.mark.parametrize(
    ("args", "error", "match"),
    [
        (dict(Phi=np.ones((2, 3)), G=np.ones((2, 1)), Xi=np.ones((1, 3))), DimensionError,
         "Phi must be square"),
        (dict(Phi=np.eye(2), G=np.ones((3, 1)), Xi=np.ones((1, 2))), DimensionError,
         "G must have 2 rows, got 3"),
        (dict(Phi=np.eye(2), G=np.ones((2, 1)), Xi=np.ones((1, 3))), DimensionError,
         "Xi must have 2 columns"),
        (dict(Phi=[[1, np.nan], [0, 1]], G=np.ones((2, 1)), Xi=np.ones((1, 2))),
         InvalidValueError, "Phi contains NaN"),
        (dict(Phi=np.eye(2), G=np.ones((2, 1)), Xi=[[1, np.inf]]), InvalidValueError,
         "Xi contains inf"),
        (dict(Phi=np.eye(2), G=np.ones((2, 1)), Xi=np.ones((1, 2)), Gamma=np.ones((3, 1))),
         DimensionError, "Gamma must have 2 rows"),
    ],
)
def test_linear_system_rejects(args, error, match):
    with pytest.raises(error, match=match):
        LinearSystem(**args)


def test_linear_system_names_and_immutability():
    s = LinearSystem(np.eye(2), [[1.0], [0.0]], [[1.0, 0.0]], disturbance_names=["load"])
    assert s.disturbance_names == ("load",) and (s.n, s.q, s.l, s.p) == (2, 1, 1, 0)
    with pytest.raises(DimensionError, match="disturbance_names must have 1 entries"):
        LinearSystem(np.eye(2), [[1.0], [0.0]], [[1.0, 0.0]], disturbance_names=["a", "b"])
    with pytest.raises(AttributeError):
        s.Phi = np.eye(2)
    with pytest.raises(ValueError, match="read-only"):
        s.Phi[0, 0] = 3.0


def test_zoh_discretisation_against_quadrature(rng):
    H = rng.normal(size=(3, 3))
    D, F, C = rng.normal(size=(3, 1)), rng.normal(size=(3, 2)), rng.normal(size=(2, 3))
    T = 0.1
    s = LinearSystem.from_continuous(H, D, F, C, T)
    integral, _ = quad_vec(lambda t: expm(H * t), 0.0, T, epsabs=1e-13)
    np.testing.assert_allclose(s.Phi, expm(H * T), atol=1e-13)
    np.testing.assert_allclose(s.Gamma, integral @ D, atol=1e-11)
    np.testing.assert_allclose(s.G, integral @ F, atol=1e-11)
    # Closed form for invertible H: int = H^-1 (e^{HT} - I).
    np.testing.assert_allclose(s.G, np.linalg.solve(H, expm(H * T) - np.eye(3)) @ F, atol=1e-11)
    assert s.dt == T
    with pytest.raises(InvalidValueError, match="T must be positive"):
        LinearSystem.from_continuous(H, D, F, C, 0.0)


def test_from_python_control():
    control = pytest.importorskip("control")
    s0 = ex.chang2006()
    ss = control.ss(s0.Phi, np.hstack([s0.G, np.ones((3, 1))]), s0.Xi, np.zeros((2, 3)), 0.1)
    s = LinearSystem.from_statespace(ss, disturbance_inputs=[0, 1])
    np.testing.assert_array_equal(s.G, s0.G)
    np.testing.assert_array_equal(s.Gamma, np.ones((3, 1)))
    assert s.dt == 0.1


def test_augmented_system_eq_11():
    s = ex.chang2006()
    a = s.augmented()
    np.testing.assert_array_equal(a.A[:3, :3], s.Phi)
    np.testing.assert_array_equal(a.A[:3, 3:], s.G)
    np.testing.assert_array_equal(a.A[3:, 3:], np.eye(2))
    np.testing.assert_array_equal(a.A[3:, :3], 0)
    np.testing.assert_array_equal(a.E, np.vstack([np.zeros((3, 2)), np.eye(2)]))
    np.testing.assert_array_equal(a.C, np.hstack([s.Xi, np.zeros((2, 2))]))


# ------------------------------------------------------------------------ observability
def test_eq16_matrix_is_the_augmented_observability_matrix(rng):
    """[O, Ibar O G] with N blocks equals the N-block observability matrix of (9)-(11)."""
    s = LinearSystem(rng.normal(size=(4, 4)), rng.normal(size=(4, 2)), rng.normal(size=(2, 4)))
    for N in (1, 4, 6):
        O = observability_matrix(s.Phi, s.Xi, N)
        lhs = np.hstack([O, ibar(N, 2) @ O @ s.G])
        a = s.augmented()
        np.testing.assert_allclose(lhs, observability_matrix(a.A, a.C, N), atol=1e-12)


def test_observability_of_structured_systems(rng):
    sys, _ = with_unobservable_disturbance(rng)
    rep = observability(sys.Phi, sys.Xi)
    assert rep.n_observable == 3 and not rep.observable
    # The unobservable subspace is exactly span(e4, e5).
    np.testing.assert_allclose(np.abs(rep.unobservable_rows[:, :3]), 0, atol=1e-10)
    np.testing.assert_allclose(np.sort(np.abs(rep.unobservable_modes)),
                               np.sort(np.abs(np.linalg.eigvals(sys.Phi[3:, 3:]))), atol=1e-10)
    assert rep.detectable == bool(np.all(np.abs(np.linalg.eigvals(sys.Phi[3:, 3:])) < 1))


def test_observability_decomposition_structure():
    dec = observability_decomposition(ex.chang2006())
    T = dec.T
    np.testing.assert_allclose(T @ T.T, np.eye(5), atol=1e-12)
    assert dec.N_o == 5 and dec.report.index == 3
    # A non-trivial case: the unobservable-disturbance system.
    sys, _ = with_unobservable_disturbance(np.random.default_rng(1))
    dec = observability_decomposition(sys)
    At = dec.T @ sys.augmented().A @ dec.T.T
    np.testing.assert_allclose(At[: dec.N_o, dec.N_o :], 0, atol=1e-10)  # eq. (14) structure
    Ct = sys.augmented().C @ dec.T.T
    np.testing.assert_allclose(Ct[:, dec.N_o :], 0, atol=1e-10)
    np.testing.assert_allclose(dec.C_o, Ct[:, : dec.N_o])


# ------------------------------------------------------------------------ Theorem 1
def test_chang_theorem1_holds_and_augmented_pair_is_observable():
    s = ex.chang2006()
    r = bounded_do_exists(s)
    assert r.satisfied and r.remark1_satisfied and r.forms_agree and not r.fragile
    assert (r.rank_O, r.rank_Oaug, r.n_o, r.N_o) == (3, 5, 3, 5)
    assert augmented_observability(s).observable
    assert r.unrecoverable_directions.shape == (2, 0)


def test_scalar_integrator_printed_horizon_finding():
    """x+ = x + d, y = x: d[k-1] = y[k] - y[k-1], so a bounded DO exists; the n-block
    form of eq. (16) says it does not (Ibar O G = 0 with one block)."""
    s = LinearSystem([[1.0]], [[1.0]], [[1.0]])
    r = bounded_do_exists(s)
    assert r.satisfied and r.remark1_satisfied
    assert not r.printed_horizon_satisfied
    # Any observable SISO system: [O, IbarOG] with n blocks has n rows < n + 1 = required rank.
    r5 = bounded_do_exists(ex.chen_gao_lin_example5((0.3, 0.7)))
    assert r5.satisfied and not r5.printed_horizon_satisfied
    assert "n blocks" in " ".join(diagnose(ex.chen_gao_lin_example5((0.3, 0.7))).notes)


def test_unobservable_disturbance_is_named(rng):
    for _ in range(5):
        sys, direction = with_unobservable_disturbance(rng)
        r = bounded_do_exists(sys)
        assert not r.satisfied and not r.remark1_satisfied
        assert not r.corollary1  # n_o = 3 >= q = 2: fails for another reason
        U = r.unrecoverable_directions
        assert U.shape == (2, 1)
        assert abs(abs(U[:, 0] @ direction) - 1.0) < 1e-8
        assert "not recoverable" in diagnose(sys)["SMFDO"].reason


def test_corollary1(rng):
    # n_o = 1 < q = 2: one output, observable part of dimension 1.
    A = np.diag([0.5, 0.3, 0.2])
    sys = LinearSystem(A, rng.normal(size=(3, 2)), [[1.0, 0.0, 0.0]])
    r = bounded_do_exists(sys)
    assert r.corollary1 and not r.satisfied
    assert "Corollary 1" in diagnose(sys)["SMFDO"].reason


def test_generic_augmented_observable_systems_satisfy_theorem1(rng):
    for _ in range(10):
        n, q = int(rng.integers(2, 6)), int(rng.integers(1, 3))
        l = q + int(rng.integers(0, 2))
        sys = LinearSystem(rng.normal(size=(n, n)) * 0.5, rng.normal(size=(n, q)),
                           rng.normal(size=(l, n)))
        r = bounded_do_exists(sys)
        assert augmented_observability(sys).observable
        assert r.satisfied and r.forms_agree


def test_theorem1_forms_agree_on_random_structures(rng):
    """Two independent computations (explicit ranks vs orthogonal staircase) agree."""
    for _ in range(40):
        n = int(rng.integers(2, 7))
        q = int(rng.integers(1, 3))
        l = int(rng.integers(1, 3))
        A = rng.normal(size=(n, n)) * 0.5
        G = rng.normal(size=(n, q))
        C = rng.normal(size=(l, n))
        if rng.random() < 0.4:  # make part of the state unobservable
            k = int(rng.integers(1, n))
            A[:k, k:] = 0.0
            C[:, k:] = 0.0
            if rng.random() < 0.5:
                G[:k, -1] = 0.0
        r = bounded_do_exists(LinearSystem(A, G, C))
        assert r.forms_agree


def test_verdicts_invariant_under_transforms(rng):
    systems = [ex.chang2006(), with_unobservable_disturbance(rng)[0],
               ex.chen_gao_lin_example1(), ex.chen_gao_lin_example5((1.0, 0.5))]
    for s in systems:
        base = {v.design: v.exists for v in diagnose(s).verdicts}
        for tr in (random_similarity, diagonal_rescaling):
            for _ in range(2):
                S = tr(s, rng, decades=3.0)
                assert {v.design: v.exists for v in diagnose(S).verdicts} == base
                assert bounded_do_exists(S).satisfied == bounded_do_exists(s).satisfied


# ------------------------------------------------------------------------ error poles
def test_published_pio_gains_are_unstable():
    poles = pio_error_poles(ex.chang2006(), P_PIO, L_PIO)
    assert not poles.stable
    real_unstable = [p.real for p in poles.unstable_poles() if abs(p.imag) < 1e-9]
    assert len(real_unstable) == 1 and real_unstable[0] == pytest.approx(-1.37, abs=0.01)


def test_published_higher_order_gains_have_a_double_root_at_one():
    s = ex.chang2006()
    ep = higher_order_error_poles(s.Phi, s.Xi, P0_HO, L0_HO, L1_HO)
    near_one = ep.poles[np.abs(ep.poles - 1.0) < 1e-4]
    assert near_one.size == 2
    # Independent check: every pole is a root of eq. (10) (times z^3n).
    for z in ep.poles:
        M = fu_wang_eq10_matrix(z, s.Phi, s.Xi, P0_HO, L0_HO, L1_HO)
        sv = np.linalg.svd(M, compute_uv=False)
        assert sv[-1] <= 1e-6 * max(sv[0], 1.0)
    # 3n poles, as the degree of det M(z).
    assert ep.poles.size == 9


def test_lumped_higher_order_form_always_has_a_root_at_one(rng):
    """With E = I_n and l < n, M(1) = L0 C has rank <= l < n: z = 1 is always a root."""
    s = ex.chang2006()
    for _ in range(5):
        ep = higher_order_error_poles(s.Phi, s.Xi, rng.normal(size=(3, 2)),
                                      rng.normal(size=(3, 2)), rng.normal(size=(3, 2)))
        assert np.min(np.abs(ep.poles - 1.0)) < 1e-6


def test_pio_poles_match_placement():
    from scipy.signal import place_poles

    s = ex.chang2006()
    a = s.augmented()
    want = np.array([0.1, 0.2, 0.3 + 0.5j, 0.3 - 0.5j, 0.4])
    K = place_poles(a.A.T, a.C.T, want).gain_matrix.T
    poles = pio_error_poles(s, K[:3], K[3:])
    np.testing.assert_allclose(np.sort_complex(poles.poles), np.sort_complex(want), atol=1e-8)
    assert poles.stable


def test_pio_and_modular_conditions_agree(rng):
    for _ in range(20):
        n, q, l = int(rng.integers(2, 5)), 1, int(rng.integers(1, 3))
        A = rng.normal(size=(n, n)) * 0.4
        sys = LinearSystem(A, rng.normal(size=(n, q)), rng.normal(size=(l, n)))
        assert pio_conditions(sys).exists == modular_conditions(sys).exists
    zero_at_one = ex.chen_gao_lin_example5((1.0, 0.5))
    assert not pio_conditions(zero_at_one).exists
    assert not modular_conditions(zero_at_one).exists
    assert "z = 1" in modular_conditions(zero_at_one).reason


# ------------------------------------------------------------------------ diagnose
def test_diagnose_chang():
    d = diagnose(ex.chang2006())
    assert d["SMFDO"].exists and d["PIO"].exists
    for name in ("MB-ESO", "variant MB-ESO", "delayed UIO"):
        assert not d[name].exists
        assert has_number(d[name].reason, 1.26095)
    text = repr(d)
    assert "SMFDO" in text and "NO" in text
    md = d.to_markdown()
    rows = [ln for ln in md.splitlines() if ln.startswith("| ") and "design" not in ln]
    assert len(rows) == 7 and "| design | exists |" in md


def test_diagnose_examples_and_zero_on_the_unit_circle():
    d1 = diagnose(ex.chen_gao_lin_example1())
    assert d1["variant MB-ESO"].exists and not d1["MB-ESO"].exists
    assert "not diagonal" in d1["MB-ESO"].reason
    assert d1["delayed UIO"].numbers["delay tau"] == 5
    d4 = diagnose(ex.chen_gao_lin_example4())
    assert d4["MB-ESO"].exists
    for ts in ("20ms", "1ms"):
        assert diagnose(ex.chen_gao_lin_example2(ts))["MB-ESO"].exists
    d5 = diagnose(ex.chen_gao_lin_example5((1.0, 0.5)))
    assert not d5["SMFDO"].exists and not d5["delayed UIO"].exists
    assert not d5["PIO"].exists
    with pytest.raises(KeyError, match="no design"):
        d5["Kalman"]


# ---------------------------------------------------- hardening: ill-conditioned coordinates
def _dense_similarity(rng, n, cond):
    U, _ = np.linalg.qr(rng.normal(size=(n, n)))
    V, _ = np.linalg.qr(rng.normal(size=(n, n)))
    return U @ np.diag(np.logspace(0, np.log10(cond), n)) @ V


def test_existence_verdict_does_not_depend_on_coordinates():
    """Two SISO channels with zeros 1.6259 and 1.97735: a bounded DO exists (the zeros
    are not at 1; each channel is observable). The explicit Theorem-1 ranks flipped to NO
    under well-conditioned similarities; the verdict is now yes, or undecidable when the
    coordinates are so ill-conditioned that the data cannot tell — never a wrong NO.
    And a structurally failing system is never called yes."""
    yes_sys = block_system(siso_with_zeros([1.6259], [0.5, -0.3]),
                           siso_with_zeros([1.97735], [0.2, 0.7]))
    assert bounded_do_exists(yes_sys).verdict == "yes"
    no_sys, _ = with_unobservable_disturbance(np.random.default_rng(0))
    assert bounded_do_exists(no_sys).verdict == "no"
    for t in range(40):
        rng = np.random.default_rng(t)
        for cond, allowed in ((200.0, {"yes"}), (1e3, {"yes"}), (1e8, {"yes", "undecidable"})):
            S = yes_sys.transformed(_dense_similarity(rng, 4, cond))
            assert bounded_do_exists(S).verdict in allowed, (t, cond)
            Sn = no_sys.transformed(_dense_similarity(rng, no_sys.n, cond))
            assert bounded_do_exists(Sn).verdict in {"no", "undecidable"}, (t, cond)
        # outputs and disturbances scaled over 2 x 3 and 2 x 8 decades (+ a cond-10 basis)
        assert bounded_do_exists(random_similarity(yes_sys, rng, decades=3.0)).verdict == "yes"
        assert bounded_do_exists(random_similarity(yes_sys, rng, decades=8.0)).verdict in {
            "yes", "undecidable"}


def test_undecidable_is_reported_by_diagnose_and_the_smfdo():
    from setobs.setmembership import ExistenceError

    yes_sys = block_system(siso_with_zeros([1.6259], [0.5, -0.3]),
                           siso_with_zeros([1.97735], [0.2, 0.7]))
    S = yes_sys.transformed(_dense_similarity(np.random.default_rng(0), 4, 1e8))
    r = bounded_do_exists(S)
    assert r.verdict == "undecidable" and not r.decided and not r.satisfied
    v = diagnose(S)["SMFDO"]
    assert v.verdict == "undecidable" and "undecidable at this precision" in v.reason
    assert "undecidable" in repr(diagnose(S))
    with pytest.raises(ExistenceError, match="undecidable at this precision"):
        so.SMFDO(S)
    # a well-conditioned similarity of the same system: the SMFDO runs
    so.SMFDO(yes_sys.transformed(_dense_similarity(np.random.default_rng(0), 4, 200.0)))
