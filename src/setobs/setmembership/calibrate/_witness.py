"""The witness check of the recommended radii: the noise an exactly consistent trajectory
needs, rebuilt from the record LP's trajectory in extended precision."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ._record_lp import RecordLP

__all__ = ["witness_noise"]


def witness_noise(lp: RecordLP, x: NDArray[np.float64], inc: NDArray[np.float64]
                   ) -> tuple[NDArray[np.float64], dict[str, float]]:
    """Per-channel noise that an exactly consistent trajectory needs, from the LP's
    trajectory ``x`` (centred, scaled): the check of the recommended radii.

    The trajectory is rebuilt in the original units as one of the model, in extended
    precision (``numpy.longdouble``): ``d'`` follows the LP's disturbance by
    increments clipped into their bound (shrunk by two units in the last place, so
    that the rounded sum stays within it), ``x'`` is simulated from the LP's ``x_0``
    with the LP's process noise clipped into its bound (``w' = clip(x_(k+1) - Phi x'_k
    - ..., r_w)``: the noise steers ``x'`` back to the LP's trajectory) and the
    record's inputs. So increments and noise are within their bounds exactly, and
    ``x'`` satisfies the dynamics up to the rounding ``e_k`` of each step, bounded by
    Higham's ``gamma`` on the absolute products (``|e_k| <= E``). The exact trajectory
    from ``x'_0`` with the same ``d'``, ``w'`` differs from ``x'`` by ``sum_(j<k)
    Phi^(k-1-j) e_j``, whose effect on output ``i`` is at most ``S_i E`` with
    ``S_i = sum_(m<N) ||Xi_i Phi^m||_1`` (the powers in double precision, doubled
    for their own rounding). The returned noise is, per channel, the largest
    ``|y - Du u - Xi x'|`` (its own rounding bound added) plus ``S_i E``: radii at or
    above it make the record consistent. It is infinite when the plant is unstable
    enough that ``S_i`` overflows (the trajectory cannot be checked this way).
    """
    L = np.longdouble
    sys = lp.sys
    n, q, l, p = sys.n, sys.q, sys.l, sys.p
    N = lp.N
    Z = x.reshape(N, n + q)
    sig = L(lp.sigma)
    Xh = np.asarray(lp.x_bar, dtype=L) + sig * Z[:, :n].astype(L)
    Dh = np.asarray(lp.d_bar, dtype=L) + sig * Z[:, n:].astype(L)
    Phi, G, Xi = (np.asarray(M, dtype=L) for M in (sys.Phi, sys.G, sys.Xi))
    aPhi, aG = np.abs(Phi), np.abs(G)
    U = None if lp.U is None or not p else np.asarray(lp.U, dtype=L)
    Gam = np.asarray(sys.Gamma, dtype=L)
    aGam = np.abs(Gam)
    rw = None if lp.process_noise is None else np.asarray(lp.process_noise, dtype=L)
    incL = np.asarray(inc, dtype=L)
    u_l = float(np.finfo(L).eps) / 2.0
    g_terms = n + q + p + 3
    g = g_terms * u_l / (1.0 - g_terms * u_l)
    Xs = np.empty((N, n), dtype=L)
    Ms = np.zeros((max(N - 1, 0), n), dtype=L)  # each step's |products| + |result|
    xk, dk = Xh[0].copy(), Dh[0].copy()
    for k in range(N):
        Xs[k] = xk
        if k == N - 1:
            break
        pred = Phi @ xk
        mag = aPhi @ np.abs(xk)
        if q:
            pred = pred + G @ dk
            mag = mag + aG @ np.abs(dk)
        if U is not None:
            pred = pred + Gam @ U[k]
            mag = mag + aGam @ np.abs(U[k])
        if rw is not None:
            room = np.maximum(rw - 2 * np.spacing(np.abs(pred) + rw), L(0))
            w = np.clip(Xh[k + 1] - pred, -room, room)
            pred = pred + w
            mag = mag + np.abs(w)
        Ms[k] = mag + np.abs(pred)
        xk = pred
        if q:
            room = np.maximum(incL - 2 * np.spacing(np.abs(dk) + incL), L(0))
            dk = dk + np.clip(Dh[k + 1] - dk, -room, room)
    E = float(g * Ms.max(initial=L(0)))
    # output residuals and their rounding
    Yr = np.asarray(lp.Y, dtype=L)
    out = Xs @ Xi.T
    omag = np.abs(Xs) @ np.abs(Xi).T + np.abs(Yr)
    if U is not None and np.any(sys.Du != 0):
        Du = np.asarray(sys.Du, dtype=L)
        out = out + U[:N] @ Du.T
        omag = omag + np.abs(U[:N]) @ np.abs(Du).T
    go = (n + p + 2) * u_l / (1.0 - (n + p + 2) * u_l)
    with np.errstate(invalid="ignore"):
        res = np.abs(Yr - out) + go * omag
    res = np.where(np.isfinite(lp.Y), res, L(0)).astype(np.float64)
    need = np.nextafter(res.max(axis=0), np.inf)
    # S_i = sum_m ||Xi_i Phi^m||_1 (doubled): the outputs' sensitivity to the rounding
    S = np.zeros(l)
    if E > 0.0:
        P = np.array(sys.Xi, dtype=np.float64)
        with np.errstate(over="ignore", invalid="ignore"):
            for _ in range(N):
                S += np.abs(P).sum(axis=1)
                if not np.isfinite(S).all():
                    S[:] = np.inf
                    break
                P = P @ sys.Phi
        S *= 2.0
    with np.errstate(invalid="ignore"):
        drift = np.where(S > 0.0, S * E, 0.0)
    need = need + np.nextafter(drift, np.inf)
    return need, {"rounding_bound": E, "drift_bound": float(np.max(drift, initial=0.0))}
