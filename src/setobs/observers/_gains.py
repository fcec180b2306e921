"""Observer gains: pole placement that works on every detectable pair, and the LQE gain.

Used by all Luenberger-type observers. Placement works on the observable part
of the pair only (orthogonal observability decomposition), so a detectable but
unobservable pair (which the existence checks approve) gets a gain, and its
unobservable modes are checked to be stable. Poles repeated more often than
the output rank, e.g. a dead-beat target with one output, are placed with
Ackermann's formula on the observable part (single output) or spread apart.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import block_diag

from .._riccati import lqe_gain
from ..analysis import observability, observability_matrix
from .base import DesignError

__all__ = ["default_poles", "lqe_gain", "place_gain"]

# Serialises the warning-filter swap around scipy's place_poles (_place_observable).
_PLACE_LOCK = threading.Lock()

#: Relative size of the spread used for repeated poles that the output rank
#: cannot place exactly (several outputs).
POLE_SPREAD = 1e-2


def default_poles(count: int, lo: float = 0.1, hi: float = 0.5) -> list[complex]:
    """``count`` distinct real poles spread evenly over ``[lo, hi]`` (closed under
    conjugation, placeable with a single output)."""
    if count <= 0:
        return []
    if count == 1:
        return [0.5 * (lo + hi)]
    return list(np.linspace(lo, hi, count))


def _ackermann(A: NDArray[np.float64], c: NDArray[np.float64], poles: NDArray) -> NDArray:
    """Single-output gain ``L`` with ``char(A - L c) = prod (z - p)``: Ackermann's formula
    on the dual, ``L = p(A) O^-1 e_n`` with ``O = [c; c A; ...]``."""
    n = A.shape[0]
    coeffs = np.real(np.poly(poles))
    O = observability_matrix(A, c, n)
    pA = np.zeros_like(A)
    for a in coeffs:
        pA = pA @ A + a * np.eye(n)
    e = np.zeros(n)
    e[-1] = 1.0
    return (pA @ np.linalg.solve(O, e)).reshape(n, 1)


def _place_observable(A, C, poles, check):
    """Gain for an observable pair whose ``C`` has full row rank."""
    n, rank_c = A.shape[0], C.shape[0]
    if n == 0:
        return np.zeros((0, rank_c))
    mult = max(int(np.sum(np.abs(poles - p) < 1e-12)) for p in poles)
    if mult > rank_c and rank_c == 1:
        return _ackermann(A, C, poles)
    if mult > rank_c:
        if check == "poles":
            raise DesignError(f"poles repeated {mult} times cannot be placed with "
                              f"{rank_c} independent outputs", "poles")
        poles = poles + POLE_SPREAD * max(1.0, float(np.abs(poles).max())) * np.arange(n)
    # YT's robustness iteration may stop early; accuracy is checked by the caller.
    # ``catch_warnings`` swaps process-global filters: the lock keeps two threads
    # (Dask's threaded workers) from restoring each other's filters mid-call, which
    # let the warning through in a threaded campaign.
    with _PLACE_LOCK, warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        from scipy.signal import place_poles  # scipy.signal is slow to import

        return place_poles(A.T, C.T, poles, method="YT").gain_matrix.T


def place_gain(A: ArrayLike, C: ArrayLike, poles: Sequence[complex],
               check: str = "poles") -> NDArray[np.float64]:
    """Observer gain ``L`` with ``eig(A - L C)`` at ``poles`` on the observable part.

    Parameters
    ----------
    A, C : array_like
        The pair ``(A, C)``; it must be detectable.
    poles : sequence of complex
        ``n`` target eigenvalues, closed under conjugation. When the pair has
        ``n_u`` unobservable modes, the first ``n - n_u`` poles are placed and the
        unobservable modes (which no gain moves) must be inside the unit circle.
    check : {"poles", "radius"}
        ``"poles"``: the characteristic polynomial of the observable part must
        match the target's (1e-6 relative on its coefficients; insensitive to the
        ill-conditioning of repeated roots); ``"radius"``: only stability and a
        spectral radius at most ``max|poles|`` plus the spread used for repeated
        poles are required.

    Raises
    ------
    DesignError
        On a bad pole list, an undetectable pair, or an inaccurate placement.
    """
    A = np.asarray(A, dtype=float)
    C = np.asarray(C, dtype=float)
    try:
        p = np.asarray(poles, dtype=complex).reshape(-1)
    except (TypeError, ValueError):
        raise DesignError(f"poles must be a sequence of numbers, got {poles!r}",
                          "poles") from None
    n = A.shape[0]
    if not np.isfinite(p).all():
        raise DesignError(f"poles must be finite, got {p.tolist()}", "poles")
    if p.size != n:
        raise DesignError(f"need {n} poles, got {p.size}", "pole count")
    if not np.allclose(np.sort_complex(p), np.sort_complex(p.conj()), atol=1e-12):
        raise DesignError(f"poles must be closed under conjugation, got {p.tolist()}", "poles")
    # the library's observability staircase and rank policy (as in the existence checks)
    rep = observability(A, C)
    if not rep.detectable:
        raise DesignError("the pair is not detectable: unobservable mode(s) "
                          f"{np.round(rep.unstable_unobservable_modes, 6).tolist()}",
                          "detectable")
    V_o, n_o = rep.observable_rows.T, rep.n_observable
    if n_o < n:  # keep a conjugate-closed subset of the requested poles
        p = _conjugate_closed_prefix(p, n_o)
    A11, C1 = V_o.T @ A @ V_o, C @ V_o
    # independent output combinations only (redundant outputs trouble place_poles)
    U, sv, Vt = np.linalg.svd(C1, full_matrices=False)
    r = int((sv > 1e-12 * max(1.0, float(sv.max(initial=0.0)))).sum())
    C1r = sv[:r, None] * Vt[:r]
    with np.errstate(all="ignore"):
        if r == n_o and n_o:
            # every observable coordinate is measured: L1 C1 = A11 - M, M real with
            # eigenvalues p (block-diagonal real form), so L1 = (A11 - M) C1r^-1 U^T
            L1 = (A11 - _real_block(p)) @ np.linalg.inv(C1r) @ U[:, :r].T
        else:
            L1 = np.real_if_close(_place_observable(A11, C1r, p, check)) @ U[:, :r].T
    L = np.real(V_o @ L1)
    got = np.linalg.eigvals(A11 - L1 @ C1) if n_o else np.zeros(0)
    rho_all = float(np.abs(np.linalg.eigvals(A - L @ C)).max(initial=0.0))
    if check == "radius":
        allow = float(np.abs(p).max(initial=0.0)) + POLE_SPREAD * n + 1e-6
        if rho_all >= 1.0 or float(np.abs(got).max(initial=0.0)) > allow:
            raise DesignError(f"pole placement failed (spectral radius {rho_all:.3g})", "poles")
        return L
    want = np.real(np.poly(p))
    have = np.real(np.poly(A11 - L1 @ C1)) if n_o else np.ones(1)
    scale = max(1.0, float(np.abs(want).max()))
    if np.abs(have - want).max() > 1e-6 * scale or rho_all >= 1.0:
        raise DesignError(f"pole placement inaccurate: got {np.round(got, 6)}", "poles")
    return L


def _conjugate_groups(p: NDArray) -> list[NDArray]:
    """The poles ``p`` in order as groups: a real pole, or a conjugate pair."""
    groups: list[NDArray] = []
    used = np.zeros(p.size, bool)
    for i, z in enumerate(p):
        if used[i]:
            continue
        used[i] = True
        if abs(z.imag) < 1e-12:
            groups.append(np.array([z.real], dtype=complex))
            continue
        j = next(j for j in range(p.size) if not used[j] and abs(p[j] - z.conjugate()) < 1e-12)
        used[j] = True
        groups.append(np.array([z, p[j]]))
    return groups


def _real_block(p: NDArray) -> NDArray[np.float64]:
    """A real block-diagonal matrix with eigenvalues ``p`` (conjugate-closed)."""
    blocks = [np.array([[g[0].real]]) if g.size == 1 else
              np.array([[g[0].real, g[0].imag], [-g[0].imag, g[0].real]])
              for g in _conjugate_groups(p)]
    return block_diag(*blocks) if blocks else np.zeros((0, 0))


def _conjugate_closed_prefix(p: NDArray, m: int) -> NDArray:
    """``m`` of the poles ``p``, in order, keeping conjugate pairs together (real
    poles 0.5 fill up when only pairs would overshoot)."""
    out: list[complex] = []
    for g in _conjugate_groups(p):
        if len(out) + g.size <= m:
            out += list(g)
    out += [0.5] * (m - len(out))
    return np.asarray(out, dtype=complex)
