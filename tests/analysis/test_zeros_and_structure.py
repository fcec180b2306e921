"""Invariant zeros, relative degrees, V0 and UIO delay against independent answers."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import block_diag, eigvals

from setobs import examples as ex
from setobs.analysis import invariant_zeros, relative_degrees, system_zeros, uio_conditions
from tests.analysis.helpers import (
    block_system,
    diagonal_rescaling,
    random_similarity,
    siso_with_zeros,
)


def real_sorted(z):
    return np.sort(np.asarray(z).real)


# ----------------------------------------------------------------------- Chang 2006
def test_chang_has_one_zero_at_1_26095():
    sys = ex.chang2006()
    z = invariant_zeros(sys).zeros
    assert z.size == 1
    assert z[0].real == pytest.approx(1.26095, abs=5e-6) and abs(z[0].imag) < 1e-12
    # Independent closed form: Xi G is invertible (relative degree 1), so the zero
    # dynamics are x+ = (I - G (Xi G)^-1 Xi) Phi x on ker Xi; its spectrum is the
    # zero plus l = 2 eigenvalues at 0.
    Pi = np.eye(3) - sys.G @ np.linalg.solve(sys.Xi @ sys.G, sys.Xi)
    ev = eigvals(Pi @ sys.Phi)
    nonzero = ev[np.abs(ev) > 1e-8]
    assert nonzero.size == 1 and nonzero[0].real == pytest.approx(z[0].real, abs=1e-10)
    # The pencil really loses rank there.
    P = np.block([[sys.Phi - z[0].real * np.eye(3), sys.G], [sys.Xi, np.zeros((2, 2))]])
    s = np.linalg.svd(P, compute_uv=False)
    assert s[-1] / s[0] < 1e-12


# ----------------------------------------------------------------------- Example 1
def test_example1_no_zeros_where_plain_eig_invents_some():
    sys = ex.chen_gao_lin_example1()
    res = invariant_zeros(sys)
    assert res.zeros.size == 0 and res.full_normal_rank
    # Pin the failure mode we avoid: a plain generalized eigenvalue call on the
    # Rosenbrock pencil returns large finite "zeros" (near 1.9e6 and 1.4e15 here).
    P = np.block([[sys.Phi, sys.G], [sys.Xi, np.zeros((3, 3))]])
    E = block_diag(np.eye(9), np.zeros((3, 3)))
    ev = eigvals(P, E)
    finite = np.abs(ev[np.isfinite(ev)])
    assert finite.size >= 2 and finite.min() > 1e5 and finite.max() > 1e14


def test_example1_relative_degrees_V0_and_delay():
    sys = ex.chen_gao_lin_example1()
    rd = relative_degrees(sys)
    assert rd.degrees == (2, 4, 3)
    np.testing.assert_allclose(rd.V0, [[2, 0.5, 0.25], [0.35, 1.5, 0.5], [0.4, 0.6, 0.5]],
                               atol=1e-12)
    assert rd.nonsingular and not rd.diagonal and rd.lemma2_no_zeros
    uio = uio_conditions(sys)
    assert uio.delay == 5 == rd.r_max + 1  # Theorem 1 of Chen-Gao-Lin
    assert uio.condition_b and not uio.condition_a


def test_example4_reconstruction_reproduces_printed_V0():
    rd = relative_degrees(ex.chen_gao_lin_example4())
    assert rd.degrees == (2, 4, 3)
    np.testing.assert_array_equal(rd.V0, np.diag([2.0, 1.5, 0.5]))
    assert rd.diagonal and rd.nonsingular
    assert invariant_zeros(ex.chen_gao_lin_example4()).zeros.size == 0
    assert uio_conditions(ex.chen_gao_lin_example4()).delay == 5


@pytest.mark.parametrize(("ts", "V0"), [("20ms", [0.0145, 74.96]), ("1ms", [4.3984e-5, 0.1904])])
def test_example2_sea_both_sampling_times(ts, V0):
    sys = ex.chen_gao_lin_example2(ts)
    rd = relative_degrees(sys)
    assert rd.degrees == (2, 2)
    assert rd.diagonal and rd.nonsingular
    np.testing.assert_allclose(rd.V0, np.diag(V0), rtol=1e-12)
    assert invariant_zeros(sys).zeros.size == 0
    assert uio_conditions(sys).delay == 3


def test_bad_sample_time():
    with pytest.raises(ValueError, match="sample_time must be"):
        ex.chen_gao_lin_example2("5ms")


@pytest.mark.parametrize("zeros", [(0.0, 0.0), (0.2, 0.2), (0.4, 0.4), (0.6, 0.8), (0.3, 0.7),
                                   (-0.5, 0.9), (1.5, 0.2), (1.0, 0.5)])
def test_example5_zeros_equal_the_placed_ones(zeros):
    z = invariant_zeros(ex.chen_gao_lin_example5(zeros)).zeros
    np.testing.assert_allclose(real_sorted(z), np.sort(zeros), atol=1e-7)
    assert np.abs(z.imag).max() < 1e-7


# ----------------------------------------------------------------------- random structure
def test_known_zeros_from_transfer_functions(rng):
    for _ in range(25):
        nz = int(rng.integers(0, 3))
        zs = rng.uniform(-1.5, 1.5, nz)
        ps = rng.uniform(-0.9, 0.9, nz + int(rng.integers(1, 3)))
        sys = siso_with_zeros(zs, ps)
        np.testing.assert_allclose(real_sorted(invariant_zeros(sys).zeros), np.sort(zs),
                                   atol=1e-7)


def test_mimo_block_system_zeros_are_the_union(rng):
    parts = [siso_with_zeros([0.5], [0.1, 0.2, 0.3]), siso_with_zeros([], [0.4, -0.2]),
             siso_with_zeros([-0.7, 1.2], [0.0, 0.25, -0.3, 0.6])]
    sys = block_system(*parts)
    z = invariant_zeros(sys).zeros
    np.testing.assert_allclose(real_sorted(z), [-0.7, 0.5, 1.2], atol=1e-7)
    rd = relative_degrees(sys)
    assert rd.degrees == (2, 2, 2)
    assert not rd.lemma2_no_zeros  # sum r_i = 6 < n = 9: zeros exist (Lemma 2)


def test_verdicts_invariant_under_similarity_and_scaling(rng):
    base = [ex.chang2006(), ex.chen_gao_lin_example1(), ex.chen_gao_lin_example2("1ms"),
            ex.chen_gao_lin_example4(), ex.chen_gao_lin_example5((0.3, 1.2))]
    for sys in base:
        z0 = real_sorted(invariant_zeros(sys).zeros)
        rd0 = relative_degrees(sys)
        tau0 = uio_conditions(sys).delay
        for transform in (random_similarity, diagonal_rescaling):
            for _ in range(3):
                S = transform(sys, rng, decades=3.0)  # six orders of magnitude
                z = invariant_zeros(S).zeros
                assert z.size == z0.size
                np.testing.assert_allclose(real_sorted(z), z0, atol=1e-5)
                rd = relative_degrees(S)
                assert rd.degrees == rd0.degrees
                assert rd.nonsingular == rd0.nonsingular
                if transform is diagonal_rescaling:
                    assert rd.diagonal == rd0.diagonal  # similarity can fill V0? no: invariant
                assert uio_conditions(S).delay == tau0


def test_tall_and_wide_systems(rng):
    siso = siso_with_zeros([0.5, -0.3], [0.1, 0.2, 0.3, 0.4])
    # Duplicate (scaled) output: same zeros.
    tall = system_zeros(siso.Phi, siso.G, np.vstack([siso.Xi, 3.0 * siso.Xi]))
    np.testing.assert_allclose(real_sorted(tall.zeros), [-0.3, 0.5], atol=1e-7)
    # A generic second independent output removes the zeros.
    tall2 = system_zeros(siso.Phi, siso.G, np.vstack([siso.Xi, rng.normal(size=(1, 4))]))
    assert tall2.zeros.size == 0 and tall2.full_normal_rank
    # More disturbances than outputs: not left invertible.
    wide = system_zeros(siso.Phi, np.hstack([siso.G, rng.normal(size=(4, 1))]), siso.Xi)
    assert not wide.full_normal_rank and wide.normal_rank == 5


def test_lemma2_agrees_with_zero_computation_on_random_square_systems(rng):
    agree = 0
    for _ in range(30):
        n, p = int(rng.integers(3, 7)), int(rng.integers(1, 3))
        A = rng.normal(size=(n, n)) * 0.5
        E = rng.normal(size=(n, p))
        C = rng.normal(size=(p, n))
        if rng.random() < 0.5:  # make relative degrees larger: C orthogonal to E
            C = C - (C @ E) @ np.linalg.pinv(E)
        from setobs import LinearSystem

        sys = LinearSystem(A, E, C)
        z = invariant_zeros(sys)
        rd = relative_degrees(sys)
        assert (z.zeros.size == 0 and z.full_normal_rank) == rd.lemma2_no_zeros
        agree += 1
    assert agree == 30


def _slycot_zeros(slycot, A, B, C):
    n, m, p = A.shape[0], B.shape[1], C.shape[0]
    out = slycot.ab08nd(n, m, p, A, B, C, np.zeros((p, m)), equil="S")
    nu, Af, Bf = out[0], out[8], out[9]
    if nu == 0:
        return np.zeros(0)
    z = eigvals(Af[:nu, :nu], Bf[:nu, :nu])
    return z[np.isfinite(z)]


def test_slycot_cross_check(rng):
    """Independent implementation (SLICOT AB08ND) agrees on every example and random systems."""
    slycot = pytest.importorskip("slycot")
    systems = [ex.chang2006(), ex.chen_gao_lin_example1(), ex.chen_gao_lin_example2("20ms"),
               ex.chen_gao_lin_example2("1ms"), ex.chen_gao_lin_example4(),
               ex.chen_gao_lin_example5((0.3, 0.7)), ex.chen_gao_lin_example5((1.5, -0.2))]
    for _ in range(10):
        n, q = int(rng.integers(2, 7)), int(rng.integers(1, 3))
        from setobs import LinearSystem

        systems.append(LinearSystem(rng.normal(size=(n, n)), rng.normal(size=(n, q)),
                                    rng.normal(size=(q, n))))
    for sys in systems:
        ref = _slycot_zeros(slycot, sys.Phi, sys.G, sys.Xi)
        ours = invariant_zeros(sys).zeros
        assert ours.size == ref.size
        if ours.size:  # match as sets (conjugate pairs sort unstably)
            from scipy.optimize import linear_sum_assignment

            cost = np.abs(ours[:, None] - ref[None, :])
            r, c = linear_sum_assignment(cost)
            assert cost[r, c].max() < 1e-6


def test_markov_toeplitz_maps_inputs_to_outputs_by_simulation():
    """``Y[k:k+tau] = M_tau U[k:k+tau]`` from ``x(k) = 0``, checked by simulating the system."""
    from setobs.analysis import markov_toeplitz

    rng = np.random.default_rng(5)
    n, m, l, tau = 4, 2, 3, 5
    A, E, C = rng.normal(size=(n, n)) / 2, rng.normal(size=(n, m)), rng.normal(size=(l, n))
    U = rng.normal(size=(tau + 1, m))
    x, Y = np.zeros(n), []
    for k in range(tau + 1):
        Y.append(C @ x)
        x = A @ x + E @ U[k]
    M = markov_toeplitz(A, E, C, tau)
    assert M.shape == ((tau + 1) * l, (tau + 1) * m)
    np.testing.assert_allclose(M @ U.ravel(), np.concatenate(Y), atol=1e-12)


def test_complex_values_are_displayed_with_their_imaginary_part():
    """One format in every message: a complex zero keeps its imaginary part (the delayed
    UIO's refusal used to print only the real part), a rounding-level one is dropped."""
    from setobs._format import format_complex, format_complex_list

    assert format_complex(1.26095 + 1e-15j) == "1.26095"
    assert format_complex(0.3 - 0.5j) == "0.3-0.5j"
    assert format_complex_list([2.0, 1.5 + 2j], digits=3) == "2, 1.5+2j"
    # A system with a complex pair of invariant zeros outside the unit circle:
    # x+ = A x + g d, y = c x with zeros = roots of c adj(zI - A) g.
    import setobs as so
    from setobs.observers import DelayedUIO

    A = [[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [0.1, 0.2, 0.3]]
    g, c = [[0.0], [0.0], [1.0]], [[2.0, -1.2, 1.0]]  # zeros: z^2 - 1.2 z + 2 = 0
    z = np.roots([1.0, -1.2, 2.0])
    with pytest.raises(so.DesignError) as exc:
        DelayedUIO(so.LinearSystem(A, g, c))
    assert format_complex(z[0]) in str(exc.value) or format_complex(z[1]) in str(exc.value)
