"""Exact mode at a cost that follows the set: an H-representation recursion.

The exact posterior of Algorithm 1 without a window (Li-Cong-Dong, eqs.
(20)-(21) run from ``Z_0^-``, Theorem 3) is a polytope in the observable
coordinates ``z_o`` whose *complexity* stays small (on the paper's example a
3-dimensional parallelotope inside the measured hyperplane at every step),
while its constrained-zonotope representation gains ``q`` generators and ``l``
constraints per step. Once the posterior is bounded the recursion therefore
carries the set as

.. math::  P_k = \\{z : H_k z \\le g_k\\} \\cap [lo_k, hi_k],

and computes one step at a time:

1. **Normals** ``H_k`` from an *approximate* float geometry of the exact set:
   the vertices of ``P_(k-1)`` are mapped by ``A_o`` and shifted by
   ``Gamma_o u``, summed with the vertices of the increment (and process-noise)
   sets mapped by ``B_o`` (``E_o``) -- eq. (20) on vertex sets -- then clipped by
   the measurement (hyperplanes ``C_o z = y``, or the half-spaces of
   ``y - V``: eq. (21)); the convex hull (Qhull) in the affine hull of the
   points gives the vertices of ``P_k`` and its facet normals, and the flat
   directions (the measured rows) give two-sided normals. A normal within
   :data:`~setobs.tolerances.HREP_SNAP_TOL` of one of the previous step is
   replaced by it bit for bit, so that the LP structure below stays fixed.
   After step 2 the vertices are tidied against the certified facets
   (:func:`tidy_vertices`): points with the same active facets are one vertex,
   and points on fewer facets than a vertex needs are dropped, so that float
   near-duplicates from clipping do not accumulate from step to step.
2. **Offsets** ``g_k`` and the box, *certified*: one prior/posterior step of
   eqs. (20)-(21) from the constrained zonotope of ``P_(k-1)`` (Scott et al.
   2016, Theorem 1, :func:`setobs.geometry.polytope.hpolytope_in_box`) is a
   :class:`~setobs.setmembership._closed_form.WindowModel` with ``s = 1`` whose
   objectives are the coordinates, ``P`` and the normals ``H_k``; its LPs go
   through the compiled warm-started simplex with the same certificate as
   every interval hull of the library.

Soundness never depends on step 1: whatever the normals are, ``g_k`` bounds
``H_k z`` over the exact one-step image of ``P_(k-1)``, so ``P_k`` contains
the true state whenever ``P_(k-1)`` does. Exactness does: when ``H_k``
holds the facet normals of the exact set, ``P_k`` is the exact set (up to the
certificate's outward rounding), which the tests check against an independent
whole-history LP. The cost per step follows the number of vertices and
facets of the set, not ``k``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..geometry.polytope import hpolytope_in_box
from ..geometry.zonotope import ConstrainedZonotope, trusted_cz
from ..tolerances import (
    HREP_ACTIVE_RTOL,
    HREP_CLIP_RTOL,
    HREP_FLAT_RTOL,
    HREP_SNAP_TOL,
    HREP_VERIFY_RTOL,
)

__all__ = ["HState", "clip", "hull_points", "snap_normals", "step_geometry", "tidy_vertices"]

_EPS = np.finfo(float).eps
#: Most points a clip of the approximate geometry may produce before the step goes
#: to the reference path (every inside-outside pair of points gives one).
MAX_CLIP_POINTS = 1024


@dataclass(frozen=True, eq=False)
class HState:
    """A posterior ``{z in [lo, hi] : H z <= g}`` (certified) and its approximate vertices.

    Attributes
    ----------
    H : ndarray, shape (m, N)
        Unit normals: facets, then the flat directions with both signs.
    g : ndarray, shape (m,)
        Certified offsets.
    lo, hi : ndarray, shape (N,)
        Certified box.
    V : ndarray, shape (n_v, N)
        Float vertices of the exact set (chooses the next normals only).
    """

    H: NDArray[np.float64]
    g: NDArray[np.float64]
    lo: NDArray[np.float64]
    hi: NDArray[np.float64]
    V: NDArray[np.float64]

    def start(self) -> tuple[NDArray[np.float64], ...]:
        """``(c, b, h, b_err)`` of the set as ``c + [I 0] xi``, ``[H I] xi = b``, ``|xi| <= h``."""
        c, dx, dsig, b, berr = hpolytope_in_box(self.H, self.g, self.lo, self.hi)
        return c, b, np.concatenate([dx, dsig / 2.0]), berr

    def to_cz(self) -> ConstrainedZonotope:
        """The set as a constrained zonotope (equal to ``{z in [lo, hi] : H z <= g}``)."""
        N = self.H.shape[1]
        m = self.H.shape[0]
        c, b, h, berr = self.start()
        G = np.hstack([np.eye(N), np.zeros((N, m))])
        return trusted_cz(G, c, structure_A(self.H), b, h, berr=berr)


def structure_A(H: NDArray[np.float64]) -> NDArray[np.float64]:
    """Constraint matrix ``[H I]`` of :meth:`HState.to_cz` (depends on the normals only)."""
    return np.hstack([H, np.eye(H.shape[0])])


def _frame(P: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                           NDArray[np.float64]]:
    """Centroid, orthonormal basis of the affine hull (columns), basis of its complement."""
    p0 = P.mean(axis=0)
    X = P - p0
    N = P.shape[1]
    if P.shape[0] < 2:
        return p0, np.zeros((N, 0)), np.eye(N)
    if X.shape[0] < N:  # (zero rows: Vt stays square, the complement included)
        X = np.vstack([X, np.zeros((N - X.shape[0], N))])
    _, s, Vt = np.linalg.svd(X, full_matrices=False)
    floor = 64.0 * _EPS * float(np.abs(P).max(initial=0.0)) * np.sqrt(P.shape[0])
    thr = max(HREP_FLAT_RTOL * float(s[0]) if s.size else 0.0, floor)
    r = int((s > thr).sum())
    return p0, Vt[:r].T, Vt[r:].T


def _dedupe(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """Rows of ``R`` with near-duplicates removed (the triangulated pieces of one
    facet): rows equal on the ``HREP_SNAP_TOL`` grid are one normal."""
    if R.shape[0] < 2:
        return R
    _, idx = np.unique(np.round(R / HREP_SNAP_TOL), axis=0, return_index=True)
    return R[np.sort(idx)]


def hull_points(P: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                NDArray[np.float64]] | None:
    """Vertices, unit facet normals (in the affine hull) and flat directions of ``conv(P)``.

    Returns ``(V, F, Q)``: the points of ``P`` that are vertices, the facet
    normals (rows, orthogonal to the flat directions), and an orthonormal basis
    (columns) of the directions in which the points are flat; ``None`` if
    Qhull fails.

    Parameters
    ----------
    P : ndarray, shape (n_p, N)
        Points.
    """
    p0, B, Q = _frame(P)
    r = B.shape[1]
    N = P.shape[1]
    if r == 0:
        return P[:1].copy(), np.zeros((0, N)), Q
    t = (P - p0) @ B
    if r == 1:
        i, j = int(np.argmin(t[:, 0])), int(np.argmax(t[:, 0]))
        return P[[i, j]], np.vstack([-B[:, 0], B[:, 0]]), Q
    from scipy.spatial import ConvexHull, QhullError

    try:
        hull = ConvexHull(t)
    except QhullError:
        try:
            hull = ConvexHull(t, qhull_options="QJ")
        except QhullError:
            return None
    F = hull.equations[:, :r] @ B.T
    F /= np.linalg.norm(F, axis=1)[:, None]
    return P[hull.vertices], _dedupe(F), Q


def clip(P: NDArray[np.float64], a: NDArray[np.float64], b: float,
         equality: bool) -> NDArray[np.float64]:
    """Points whose hull is ``conv(P) ∩ {a z = b}`` (or ``{a z <= b}``).

    The points on the kept side, and the intersections of every segment between
    a point strictly inside and one strictly outside with the hyperplane: the
    convex hull of those is the clipped hull.

    Parameters
    ----------
    P : ndarray, shape (n_p, N)
        Points.
    a : ndarray, shape (N,)
        Normal.
    b : float
        Offset.
    equality : bool
        Clip to the hyperplane (else to the half-space).
    """
    s = P @ a - b
    tol = HREP_CLIP_RTOL * (abs(b) + float(np.abs(a).sum()) * float(np.abs(P).max(initial=0.0)))
    out = s > tol
    inside = (np.abs(s) <= tol) if equality else ~out
    neg = s < -tol if equality else s <= 0.0
    parts = [P[inside]]
    if out.any() and neg.any():
        Pn, Pp, sn, sp = P[neg], P[out], s[neg], s[out]
        t = sn[:, None] / (sn[:, None] - sp[None, :])
        X = Pn[:, None, :] + t[..., None] * (Pp[None, :, :] - Pn[:, None, :])
        parts.append(X.reshape(-1, P.shape[1]))
    return np.vstack(parts)


def snap_normals(H_new: NDArray[np.float64], H_prev: NDArray[np.float64] | None
                 ) -> NDArray[np.float64]:
    """``H_new`` with every row that matches a row of ``H_prev`` (within
    ``HREP_SNAP_TOL``) replaced by it; ``H_prev`` itself when all rows match one to one.

    Parameters
    ----------
    H_new : ndarray, shape (m, N)
        New unit normals.
    H_prev : ndarray or None
        The previous step's normals.
    """
    if H_prev is None or H_prev.shape[0] == 0 or H_new.shape[0] == 0:
        return H_new
    D = np.abs(H_new[:, None, :] - H_prev[None, :, :]).max(axis=2)
    j = D.argmin(axis=1)
    hit = D[np.arange(H_new.shape[0]), j] <= HREP_SNAP_TOL
    if hit.all() and H_new.shape[0] == H_prev.shape[0] and np.unique(j).size == j.size:
        return H_prev
    out = H_new.copy()
    out[hit] = H_prev[j[hit]]
    return out


def vertices_match(V: NDArray[np.float64], H: NDArray[np.float64],
                   g: NDArray[np.float64]) -> bool:
    """Whether the carried vertices ``V`` span ``{z : H z <= g}``: every vertex of the
    polytope (pycddlib's float enumeration) lies within ``HREP_VERIFY_RTOL`` times the
    extent of ``V`` of a point of ``V``. ``False`` also when the enumeration fails.

    Parameters
    ----------
    V : ndarray, shape (n_v, N)
        The carried (tidied) vertices.
    H : ndarray, shape (m, N)
        Normals, flat directions included with both signs.
    g : ndarray, shape (m,)
        Certified offsets.
    """
    import cdd

    if V.shape[0] == 0 or H.shape[0] == 0:
        return False
    ext = float(np.abs(V - V.mean(axis=0)).max())
    mag = max(ext, float(np.abs(V).max()) * 1e-12, np.finfo(float).tiny)
    c = V.mean(axis=0)
    try:
        mat = cdd.matrix_from_array(np.hstack([(g - H @ c)[:, None], -H]).tolist(),
                                    rep_type=cdd.RepType.INEQUALITY)
        gen = np.array(cdd.copy_generators(cdd.polyhedron_from_matrix(mat)).array,
                       dtype=float)
    except Exception:
        return False
    if gen.size == 0 or np.any(gen[:, 0] != 1.0):
        return False   # empty, or rays/lines: the polytope is not the bounded set carried
    W = gen[:, 1:] + c
    d = np.sqrt(((W[:, None, :] - V[None, :, :]) ** 2).sum(axis=2)).min(axis=1)
    return bool(d.max() <= HREP_VERIFY_RTOL * mag)


def tidy_vertices(V: NDArray[np.float64], H: NDArray[np.float64],
                  g: NDArray[np.float64]) -> NDArray[np.float64]:
    """The approximate vertices ``V`` of ``{z : H z <= g}`` identified by their facets.

    A point's active set is ``{i : g_i - H_i z <= HREP_ACTIVE_RTOL * extent}``.
    Points with the same active set are one vertex (their mean); active sets
    of rank below ``N`` (relative tolerance ``HREP_ACTIVE_RTOL``: points on an
    edge or inside a facet, which clipping produces) are dropped, unless no
    active set has full rank (then ``V`` is only merged). Clipping makes a
    true vertex many times over (every segment through it), and in floats the
    copies differ by rounding: left alone they multiply from step to step (on
    the paper example, tens of "vertices" of an 8-vertex set by k = 10 000).
    This only chooses the points of the next
    step's geometry; the offsets stay certified.

    Parameters
    ----------
    V : ndarray, shape (n_v, N)
        Approximate vertices (from :func:`step_geometry`).
    H : ndarray, shape (m, N)
        Normals, flat directions included with both signs.
    g : ndarray, shape (m,)
        Certified offsets.
    """
    N = V.shape[1]
    if V.shape[0] < 2 or H.shape[0] == 0:
        return V
    ext = float(np.abs(V - V.mean(axis=0)).max())
    act = (g[None, :] - V @ H.T) <= HREP_ACTIVE_RTOL * max(ext, np.finfo(float).tiny)
    keys, inv, cnt = np.unique(act, axis=0, return_inverse=True, return_counts=True)
    inv = inv.ravel()
    # rank with the same relative tolerance: a redundant normal through an edge
    # is, up to the geometry's rounding, a combination of the edge's facets
    def full_rank(k: NDArray[np.bool_]) -> bool:
        if k.sum() < N:
            return False
        sv = np.linalg.svd(H[k], compute_uv=False)
        return bool(sv[N - 1] > HREP_ACTIVE_RTOL * sv[0])

    full = np.array([full_rank(k) for k in keys])
    out = np.zeros((keys.shape[0], N))
    np.add.at(out, inv, V)
    out /= cnt[:, None]
    return out[full] if full.any() else out


def step_geometry(V: NDArray[np.float64], A_o: NDArray[np.float64], shift: NDArray[np.float64],
                  images: list[NDArray[np.float64]],
                  clips: list[tuple[NDArray[np.float64], float, bool]],
                  flat_candidates: NDArray[np.float64] | None
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
    """Approximate vertices and normals of one exact prior/posterior step (eqs. (20)-(21)).

    Returns ``(V_new, H_new)`` (facet normals, then the flat directions with
    both signs) or ``None`` when the points vanish (the measurement looks
    inconsistent) or Qhull fails: the caller then takes the reference path.

    Parameters
    ----------
    V : ndarray, shape (n_v, N)
        Vertices of the previous posterior.
    A_o : ndarray, shape (N, N)
        State matrix.
    shift : ndarray, shape (N,)
        ``Gamma_o u``.
    images : list of ndarray
        Vertices of the per-step uncertainty sets mapped into the state
        (``B_o`` times the increment set's, ``E_o`` times the process noise's).
    clips : list of (a, b, equality)
        The measurement's hyperplanes or half-spaces, in order.
    flat_candidates : ndarray or None
        Unit rows to use as the flat directions when they span them exactly
        (the measured rows of ``C_o``), so that these normals are the same at
        every step.
    """
    N = V.shape[1]

    def pruned(P: NDArray[np.float64]) -> NDArray[np.float64] | None:
        out = hull_points(P)
        return None if out is None else out[0]

    P = V @ A_o.T + shift
    for W in images:
        P = (P[:, None, :] + W[None, :, :]).reshape(-1, N)
        if P.shape[0] > 256:
            kept = pruned(P)
            if kept is None:
                return None
            P = kept
    for i, (a, b, eq) in enumerate(clips):
        P = clip(P, a, b, eq)
        if P.shape[0] == 0 or P.shape[0] > MAX_CLIP_POINTS:
            # (too many: every inside-outside pair gives a point, and the hull of
            # thousands of points in 7 dimensions took Qhull 15 s and 7e5 facets)
            return None
        if i < len(clips) - 1 and P.shape[0] > 8 * N:
            kept = pruned(P)
            if kept is None:
                return None
            P = kept
    out = hull_points(P)
    if out is None:
        return None
    Vn, F, Q = out
    f = Q.shape[1]
    flats = Q.T
    if f and flat_candidates is not None and flat_candidates.shape[0] == f:
        # the candidates span the flat directions: use them (stable normals)
        res = flat_candidates - (flat_candidates @ Q) @ Q.T
        if np.abs(res).max() <= 1e3 * HREP_FLAT_RTOL and \
                np.linalg.matrix_rank(flat_candidates @ Q) == f:
            flats = flat_candidates
    H = np.vstack([F, flats, -flats]) if f else F
    return Vn, H
