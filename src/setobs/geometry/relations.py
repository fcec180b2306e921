"""Relations between sets: containment in a polytope or a constrained zonotope, equality.

The answers are three-valued (:class:`ContainmentResult`): ``True``, ``False``
with a witness point, or ``None`` (undecided). Two sets that share a boundary
(``Z`` and itself) can only be compared up to a tolerance, so containment is
decided up to :data:`~setobs.tolerances.CONTAINMENT_RTOL`:

* ``True`` is certified: every point of ``Z`` satisfies each inequality of the
  container within ``tol_i = CONTAINMENT_RTOL (1 + ||k||_inf)`` (certified
  support values);
* ``False`` comes with a witness: a point the LP solver found in ``Z`` (a
  support point; in ``Z`` up to the solver's feasibility, the same footing as
  :meth:`~setobs.ConstrainedZonotope.contains`), that violates an inequality
  by more than ``tol_i``, and, for a constrained-zonotope container, that the
  container certifiably does not contain;
* ``None`` when neither could be shown (within the tolerance band, or a
  container whose facets could not be computed and whose sufficient
  condition failed).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import as_matrix, as_vector, check_real_scalar
from ..exceptions import (
    ArgumentError,
    DimensionError,
    EmptySetError,
    InvalidValueError,
    NotSupportedError,
    SolverError,
    UnboundedSetError,
)
from ..tolerances import CONTAINMENT_RTOL, FEASIBILITY_TOL
from .results import ContainmentResult
from .zonotope import ConstrainedZonotope, magnitude, scaled_by, support_unwarned, unit_scaled

__all__ = ["ContainmentResult", "is_equal", "is_subset", "is_subset_of_polytope", "represents"]


def _tolerances(k: NDArray[np.float64]) -> NDArray[np.float64]:
    return CONTAINMENT_RTOL * (1.0 + np.abs(k))


def _support_point(Z: ConstrainedZonotope, d: NDArray[np.float64]) -> NDArray[np.float64] | None:
    try:
        return Z.support_point(d)
    except (SolverError, UnboundedSetError):
        return None


def is_subset_of_polytope(Z: ConstrainedZonotope, H: ArrayLike, k: ArrayLike,
                          E: ArrayLike | None = None, f: ArrayLike | None = None
                          ) -> ContainmentResult:
    """Whether ``Z`` lies in the polytope ``{x : H x <= k, E x = f}``: exact by LPs.

    ``Z subset P`` iff ``max_{z in Z} H_i z <= k_i`` for every row (and
    ``E z = f`` on ``Z``: both ``max`` and ``min`` of each ``E_j z`` equal
    ``f_j``): one certified support LP per row (two per equality). See the
    module notes for the three values. The empty set is a subset of anything.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    H : array_like, shape (m, n)
        Inequality normals.
    k : array_like, shape (m,)
        Inequality offsets.
    E : array_like, shape (p, n), optional
        Equality rows.
    f : array_like, shape (p,), optional
        Equality right-hand sides.

    Examples
    --------
    >>> Z = ConstrainedZonotope.from_box([0.0, 0.0], [1.0, 1.0])
    >>> bool(is_subset_of_polytope(Z, [[1.0, 1.0]], [2.0]))
    True
    >>> r = is_subset_of_polytope(Z, [[1.0, 1.0]], [1.5])
    >>> r.holds, (r.witness.round(6) + 0.0).tolist()
    (False, [1.0, 1.0])
    """
    H_a = as_matrix("H", H, cols=Z.dim)
    k_a = as_vector("k", k, size=H_a.shape[0])
    if (E is None) != (f is None):
        raise ArgumentError("E and f must be given together (or both omitted)")
    if E is not None:
        E_a = as_matrix("E", E, cols=Z.dim)
        f_a = as_vector("f", f, size=E_a.shape[0])
        H_a = np.vstack([H_a, E_a, -E_a])
        k_a = np.concatenate([k_a, f_a, -f_a])
    if Z.is_empty():
        return ContainmentResult(True, None, "empty", -np.inf, 0.0)
    tol = _tolerances(k_a)
    margin = -np.inf
    undecided = False
    try:
        for i, row in enumerate(H_a):
            s = support_unwarned(Z, row)
            margin = max(margin, s - k_a[i])
            if s <= k_a[i] + tol[i]:
                continue
            p = _support_point(Z, row)
            if p is not None and row @ p > k_a[i] + tol[i] and Z.contains(p):
                return ContainmentResult(False, p, "supports", s - k_a[i], float(tol.max()))
            undecided = True
    except EmptySetError:
        return ContainmentResult(True, None, "empty", -np.inf, 0.0)
    return ContainmentResult(None if undecided else True, None, "supports", float(margin),
                             float(tol.max(initial=0.0)))


def _hull_witness(Z: ConstrainedZonotope, W: ConstrainedZonotope) -> NDArray[np.float64] | None:
    """A support point of ``Z`` in a coordinate direction that ``W`` certifiably misses."""
    for i in range(Z.dim):
        for s in (1.0, -1.0):
            d = np.zeros(Z.dim)
            d[i] = s
            sw = support_unwarned(W, d)
            if not np.isfinite(sw):
                continue
            p = _support_point(Z, d)
            if p is not None and d @ p > sw + CONTAINMENT_RTOL * (1.0 + abs(sw)) \
                    and not W.contains(p) and Z.contains(p):
                return p
    return None


def is_subset(Z: ConstrainedZonotope, W: ConstrainedZonotope) -> ContainmentResult:
    """Whether ``Z subset W`` for two constrained zonotopes (three-valued).

    1. A coordinate direction in which ``Z`` reaches beyond ``W``'s certified
       support gives ``False`` with a witness that ``W`` certifiably does not
       contain.
    2. A bounded ``W`` is converted to its facets (:func:`~setobs.geometry.to_hrep`,
       verified) and :func:`is_subset_of_polytope`
       decides; a ``False`` witness is checked against ``W`` itself. The
       facets' offsets are certified support values of ``W``, i.e. outer by
       up to :data:`~setobs.tolerances.VERTEX_RTOL` of its size, so a ``True``
       holds up to that tolerance as well.
    3. Otherwise (``W`` unbounded or too large to convert) the sufficient
       condition of Sadraddini and Tedrake (2019, Theorem 1), written for
       factor sets: ``G_Z = G_W Gamma``, ``c_Z - c_W = G_W beta``,
       ``A_W Gamma = Lam A_Z``, ``A_W beta = b_W - Lam b_Z`` and, row by row,
       ``+-(Gamma_r xi + beta_r) <= h_W,r`` on ``Z``'s factor set certified
       by LP duality, is searched with one LP. Found: ``True``; not found:
       ``None``.

    Parameters
    ----------
    Z, W : ConstrainedZonotope
        The sets (same dimension).

    Examples
    --------
    >>> W = ConstrainedZonotope.from_box([-1.0, -1.0], [1.0, 1.0])
    >>> Z = ConstrainedZonotope.from_zonotope([[0.5, 0.5], [0.5, -0.5]], [0.0, 0.0])
    >>> bool(is_subset(Z, W)), bool(is_subset(W, Z))
    (True, False)
    """
    if not isinstance(W, ConstrainedZonotope):
        raise ArgumentError(f"is_subset expects a ConstrainedZonotope, got {type(W).__name__}")
    if W.dim != Z.dim:
        raise DimensionError(f"containment: dimensions differ ({Z.dim} vs {W.dim})")
    # Both sets at the container's magnitude (exact power-of-two scaling), so the
    # tolerances are relative to the sets' size: a 1e-8 set 0.1 % outside its
    # container was "inside" under absolute tolerances.
    mz = magnitude(Z)
    Ws, f = unit_scaled(W, mz if np.isfinite(mz) else 0.0)
    if Ws is not W:
        r = is_subset(scaled_by(Z, f), Ws)
        return ContainmentResult(r.holds, None if r.witness is None else r.witness * f,
                                 r.method, r.margin * f, r.tol * f)
    if Z.is_empty():
        return ContainmentResult(True, None, "empty", -np.inf, 0.0)
    if W.is_empty():
        return ContainmentResult(False, _support_point(Z, np.ones(Z.dim)), "empty container")
    p = _hull_witness(Z, W)
    if p is not None:
        return ContainmentResult(False, p, "hull")
    if W.is_bounded:
        from .polytope import to_hrep

        try:
            hr = to_hrep(W)
        except SolverError:
            hr = None
        if hr is not None:
            res = is_subset_of_polytope(Z, hr.H, hr.k, hr.E if hr.E.size else None,
                                        hr.f if hr.E.size else None)
            if res.holds is False and W.contains(res.witness):
                return ContainmentResult(None, None, "facets", res.margin, res.tol)
            return ContainmentResult(res.holds, res.witness, "facets", res.margin, res.tol)
    ok = _matching_certificate(Z, W)
    return ContainmentResult(True if ok else None, None, "matching")


def _matching_certificate(Z: ConstrainedZonotope, W: ConstrainedZonotope) -> bool:
    """Search the Sadraddini-Tedrake certificate of ``Z subset W`` with one LP (see
    :func:`is_subset`); the returned ``True`` is checked on the residuals."""
    from scipy.optimize import linprog
    from scipy.sparse import csr_matrix, hstack, identity, kron, vstack

    n1, n2 = Z.n_gen, W.n_gen
    c1, c2 = Z.n_con, W.n_con
    if not np.isfinite(Z.h).all():
        return False
    # variables: Gamma (n2 x n1, row-major), beta (n2), Lam (c2 x c1, row-major),
    # for each row r of Gamma and sign s: mu_rs (c1) and the abs-aux t_rs (n1)
    nG, nL = n2 * n1, c2 * c1
    nmu = 2 * n2 * c1
    nt = 2 * n2 * n1
    nv = nG + n2 + nL + nmu + nt
    oG, ob, omu, ot = 0, nG, nG + n2 + nL, nG + n2 + nL + nmu
    eq_rows, eq_rhs = [], []
    # G_W Gamma = G_Z  (n x n1): kron(G_W, I_n1)
    eq_rows.append(hstack([kron(csr_matrix(W.G), identity(n1)),
                           csr_matrix((W.dim * n1, nv - nG))]))
    eq_rhs.append(Z.G.reshape(-1))
    # G_W beta = c_Z - c_W
    eq_rows.append(hstack([csr_matrix((W.dim, nG)), csr_matrix(W.G),
                           csr_matrix((W.dim, nv - nG - n2))]))
    eq_rhs.append(Z.c - W.c)
    if c2:
        # A_W Gamma - Lam A_Z = 0 (c2 x n1)
        blk = hstack([kron(csr_matrix(W.A), identity(n1)), csr_matrix((c2 * n1, n2)),
                      -kron(identity(c2), csr_matrix(Z.A.T)) if c1 else csr_matrix((c2 * n1, 0)),
                      csr_matrix((c2 * n1, nmu + nt))])
        eq_rows.append(blk)
        eq_rhs.append(np.zeros(c2 * n1))
        # A_W beta + Lam b_Z = b_W
        blk = hstack([csr_matrix((c2, nG)), csr_matrix(W.A),
                      kron(identity(c2), csr_matrix(Z.b[None, :])) if c1
                      else csr_matrix((c2, 0)), csr_matrix((c2, nmu + nt))])
        eq_rows.append(blk)
        eq_rhs.append(W.b)
    # row r, sign s: s beta_r + mu^T b_Z + h_Z^T t <= h_W,r, t >= |s Gamma_r - A_Z^T mu|
    ub_rows, ub_rhs = [], []
    fin_w = np.isfinite(W.h)
    for r in range(n2):
        for si, s in enumerate((1.0, -1.0)):
            if not fin_w[r]:
                continue
            q = 2 * r + si
            row = np.zeros(nv)
            row[ob + r] = s
            row[omu + q * c1: omu + (q + 1) * c1] = Z.b
            row[ot + q * n1: ot + (q + 1) * n1] = Z.h
            ub_rows.append(csr_matrix(row[None, :]))
            ub_rhs.append([W.h[r]])
            for sgn in (1.0, -1.0):  # sgn (s Gamma_r - A^T mu) - t <= 0
                M = np.zeros((n1, nv))
                M[:, oG + r * n1: oG + (r + 1) * n1] = sgn * s * np.eye(n1)
                if c1:
                    M[:, omu + q * c1: omu + (q + 1) * c1] = -sgn * Z.A.T
                M[:, ot + q * n1: ot + (q + 1) * n1] = -np.eye(n1)
                ub_rows.append(csr_matrix(M))
                ub_rhs.append(np.zeros(n1))
    A_eq = vstack(eq_rows).tocsr()
    b_eq = np.concatenate(eq_rhs)
    A_ub = vstack(ub_rows).tocsr() if ub_rows else None
    b_ub = np.concatenate(ub_rhs) if ub_rhs else None
    bounds = [(None, None)] * (nv - nt) + [(0, None)] * nt
    res = linprog(np.zeros(nv), A_ub=A_ub, b_ub=b_ub, A_eq=A_eq, b_eq=b_eq, bounds=bounds,
                  method="highs")
    if res.status != 0:
        return False
    x = res.x
    scale = 1.0 + float(np.abs(b_eq).max(initial=0.0))
    ok_eq = np.abs(A_eq @ x - b_eq).max(initial=0.0) <= FEASIBILITY_TOL * scale
    ok_ub = A_ub is None or (A_ub @ x - b_ub).max(initial=0.0) <= FEASIBILITY_TOL * scale
    return bool(ok_eq and ok_ub)


def is_equal(Z: ConstrainedZonotope, W: ConstrainedZonotope, tol: float = 0.0
             ) -> ContainmentResult:
    """Whether ``Z`` and ``W`` are the same set: :func:`is_subset` both ways.

    ``False`` comes with a witness in one set and not the other. With ``tol > 0``
    the sets are compared up to that Hausdorff distance in the infinity norm (CORA's
    ``isequal(S1, S2, tol)``): ``Z subset W + B`` and ``W subset Z + B`` with ``B``
    the box ``[-tol, tol]^n`` (a witness is then farther than ``tol`` from the other
    set).

    Parameters
    ----------
    Z, W : ConstrainedZonotope
        The sets.
    tol : float
        Largest distance (infinity norm, the sets' units) at which they still count as
        equal (default 0: up to :data:`~setobs.tolerances.CONTAINMENT_RTOL` only).

    Examples
    --------
    >>> Z = ConstrainedZonotope.from_box([0.0], [1.0])
    >>> bool(is_equal(Z, Z + np.array([0.0]))), bool(is_equal(Z, Z + np.array([1e-3])))
    (True, False)
    >>> bool(is_equal(Z, Z + np.array([1e-3]), tol=2e-3))
    True
    """
    tol = check_real_scalar("tol", tol, nonnegative=True)
    Zb, Wb = Z, W
    if tol > 0.0:
        if not isinstance(W, ConstrainedZonotope):
            raise ArgumentError(f"is_equal expects a ConstrainedZonotope, got {type(W).__name__}")
        if W.dim != Z.dim:
            raise DimensionError(f"equality: dimensions differ ({Z.dim} vs {W.dim})")
        B = ConstrainedZonotope.from_box(np.full(Z.dim, -tol), np.full(Z.dim, tol))
        Zb, Wb = Z + B, W + B
    a = is_subset(Z, Wb)
    if a.holds is False:
        return ContainmentResult(False, a.witness, a.method, a.margin, a.tol)
    b = is_subset(W, Zb)
    if b.holds is False:
        return ContainmentResult(False, b.witness, b.method, b.margin, b.tol)
    holds = True if (a.holds and b.holds) else None
    return ContainmentResult(holds, None, f"{a.method}/{b.method}",
                             float(np.nanmax([a.margin, b.margin, -np.inf])),
                             max(a.tol, b.tol))


#: Kinds :func:`represents` decides.
REPRESENTABLE_KINDS = ("empty", "point", "origin", "box", "zonotope")


def represents(Z: ConstrainedZonotope, kind: str, tol: float | None = None) -> bool:
    """Whether ``Z`` is (up to ``tol``) a set of a simpler kind (CORA's ``representsa``).

    * ``"empty"``: certified empty (:meth:`~ConstrainedZonotope.is_empty`, with ``tol``
      as the feasibility tolerance when given);
    * ``"point"``: non-empty and its certified interval hull at most ``tol`` wide in
      every coordinate; ``"origin"``: that point within ``tol`` of ``0``;
    * ``"box"``: non-empty, bounded, and every corner of its interval hull within
      ``tol`` of the set (infinity norm): a convex set that contains its hull's
      corners is its hull (``2^n`` containment LPs, ``n <= 12``);
    * ``"zonotope"``: a set without constraints is one; otherwise the constraints are
      first removed exactly where they can be (:func:`~setobs.geometry.reduce_exact`),
      and else the polytope is tested geometrically: a polytope is a zonotope iff
      every 2-face is centrally symmetric (Shephard 1974; in the plane, iff it is
      centrally symmetric), checked on its verified vertices and, in 3-D, on the
      faces of their convex hull (Qhull), up to ``tol``. Lower-dimensional sets are
      tested in their affine hull. Refused above 3 (affine) dimensions when the
      constraints cannot be removed exactly.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    kind : {"empty", "point", "origin", "box", "zonotope"}
        The kind.
    tol : float, optional
        Absolute tolerance in the set's units (default ``CONTAINMENT_RTOL`` times
        ``1 +`` the set's magnitude; for ``"empty"`` the default feasibility tolerance).

    Raises
    ------
    ValueError
        For an unknown ``kind``.
    NotImplementedError
        For ``"box"`` above 12 dimensions and ``"zonotope"`` above 3 affine
        dimensions with constraints that exact reduction cannot remove.

    Examples
    --------
    >>> square = ConstrainedZonotope.from_hpolytope(
    ...     [[1.0, 0.0], [-1.0, 0.0], [0.0, 1.0], [0.0, -1.0]], [1.0, 1.0, 1.0, 1.0])
    >>> represents(square, "box"), represents(square, "point")
    (True, False)
    >>> triangle = ConstrainedZonotope.from_vertices([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    >>> represents(triangle, "zonotope")
    False
    """
    if kind not in REPRESENTABLE_KINDS:
        raise InvalidValueError(f"kind must be one of {REPRESENTABLE_KINDS}, got {kind!r}")
    if tol is not None:
        tol = check_real_scalar("tol", tol, nonnegative=True)
    if kind == "empty":
        return Z.is_empty(FEASIBILITY_TOL if tol is None else max(tol, FEASIBILITY_TOL))
    if Z.is_empty():
        return False
    if kind == "zonotope" and Z.n_con == 0 and np.isfinite(Z.h).all():
        return True
    box = Z.interval_hull()
    if not (np.isfinite(box.lo).all() and np.isfinite(box.hi).all()):
        return False  # unbounded: not a point, a box or a (bounded) zonotope
    mag = float(np.max(np.abs(np.concatenate([box.lo, box.hi])), initial=0.0))
    t = CONTAINMENT_RTOL * (1.0 + mag) if tol is None else tol
    if kind in ("point", "origin"):
        if not (box.width <= t).all():
            return False
        return kind == "point" or bool(np.abs(box.center).max(initial=0.0) <= t)
    if kind == "box":
        return _is_its_hull(Z, box, t)
    return _is_zonotope(Z, t)


def _corners(box) -> NDArray[np.float64]:
    n = box.lo.size
    signs = ((np.arange(2**n)[:, None] >> np.arange(n)[None, :]) & 1).astype(bool)
    return np.where(signs, box.hi[None, :], box.lo[None, :])


def _is_its_hull(Z: ConstrainedZonotope, box, t: float) -> bool:
    if Z.dim > 12:
        raise NotSupportedError("represents(..., 'box') checks the 2^n corners of the hull; "
                                f"n = {Z.dim} is above 12")
    if Z.n_con == 0 and ((Z.G != 0.0).sum(axis=0) <= 1).all():
        return True  # axis-aligned generators: a box
    Zt = Z + ConstrainedZonotope.from_box(np.full(Z.dim, -t), np.full(Z.dim, t)) if t > 0 else Z
    return all(Zt.contains(v) for v in _corners(box))


def _is_zonotope(Z: ConstrainedZonotope, t: float) -> bool:
    from .polytope import vertices
    from .reduction import reduce_exact

    R = reduce_exact(Z)
    if R.n_con == 0:
        return True
    V = vertices(R)
    centred = V - V.mean(axis=0)
    _, sv, Vt = np.linalg.svd(centred, full_matrices=False)
    d = int((sv > max(t, 1e-12 * float(sv.max(initial=0.0)))).sum())
    if d <= 1:
        return True  # a point or a segment
    P = centred @ Vt[:d].T  # coordinates in the affine hull
    if d == 2:
        return _symmetric(P, t)
    if d == 3:
        from scipy.spatial import ConvexHull

        hull = ConvexHull(P)
        scale = 1.0 + float(np.abs(P).max())
        ptol = max(t, 1e-9 * scale)
        planes: list[NDArray[np.float64]] = []
        for eq in hull.equations:  # (unit normal, offset) of each simplex: one per face
            if not any(np.abs(eq - q).max() <= 1e-9 * scale for q in planes):
                planes.append(eq)
        for eq in planes:
            F = P[np.abs(P @ eq[:3] + eq[3]) <= ptol]
            if not _symmetric(F, t):
                return False
        return True
    raise NotSupportedError(
        f"represents(..., 'zonotope') decides polytopes up to 3 (affine) dimensions; this one "
        f"has {d} and constraints that exact reduction cannot remove")


def _symmetric(P: NDArray[np.float64], t: float) -> bool:
    """Whether the point set ``P`` is centrally symmetric about its centroid, up to ``t``
    (every reflected point within ``t`` of a point, infinity norm)."""
    c = P.mean(axis=0)
    Q = 2.0 * c - P
    dist = np.abs(Q[:, None, :] - P[None, :, :]).max(axis=2).min(axis=1)
    return bool((dist <= max(t, 8.0 * np.finfo(float).eps * (1.0 + np.abs(P).max()))).all())
