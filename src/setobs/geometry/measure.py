"""Metric questions about a constrained zonotope: nearest point, distance, samples, volume.

* :func:`minimize_quadratic` — a convex QP over the set, solved by Clarabel
  (the ``qp`` extra) in the factor variables.
* :func:`nearest_point` and :func:`distance` — the Euclidean projection of a
  point; the distance comes with a *certified lower bound* from the separating
  hyperplane through the projection (a certified support value), so a user
  can tell how far the solver's answer can be trusted.
* :func:`sample` — uniform random points by hit-and-run (Smith 1984) in the
  set's affine hull, chords from the facets (dimension <= 3) or from two LPs.
* :func:`volume` — exact in dimension 1-3 (vertex enumeration, then the
  polygon area or Qhull's volume of the verified vertices); above, a Monte
  Carlo estimate over the certified interval hull with a Clopper-Pearson
  confidence interval.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import optional_import
from .._rounding import gamma, round_down
from .._validation import as_matrix, as_vector, check_real_scalar
from ..exceptions import (
    EmptySetError,
    InvalidValueError,
    SolverError,
    UnboundedSetError,
)
from ..lp import highs
from .results import DistanceResult, QPResult, VolumeResult
from .zonotope import (
    ConstrainedZonotope,
    hull_with_status,
    support_unwarned,
    unit_scaled,
)

__all__ = ["DistanceResult", "QPResult", "VolumeResult", "distance", "minimize_quadratic",
           "nearest_point", "sample", "volume"]


def _clarabel():
    return optional_import("clarabel", extra="qp", feature="QPs over a set (nearest_point)")


def minimize_quadratic(Z: ConstrainedZonotope, P: ArrayLike, q: ArrayLike) -> QPResult:
    """``min 1/2 z^T P z + q^T z`` over ``z in Z`` (``P`` symmetric positive semidefinite).

    Solved by Clarabel in the factors: with ``z = G xi + c``, the objective is
    ``1/2 xi^T (G^T P G) xi + (G^T (P c + q))^T xi`` + const, subject to
    ``A xi = b`` and ``|xi| <= h`` (finite entries).

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    P : array_like, shape (n, n)
        Symmetric positive semidefinite matrix.
    q : array_like, shape (n,)
        Linear term.

    Raises
    ------
    EmptySetError
        If the set is certified empty.
    SolverError
        If Clarabel reports neither ``Solved`` nor ``AlmostSolved`` (an
        unbounded objective, or a failure).

    Examples
    --------
    >>> Z = ConstrainedZonotope.from_box([1.0, 1.0], [2.0, 3.0])
    >>> r = minimize_quadratic(Z, np.eye(2), np.zeros(2))
    >>> (r.point.round(6) + 0.0).tolist()
    [1.0, 1.0]
    """
    from scipy import sparse

    n = Z.dim
    P_a = as_matrix("P", P, rows=n, cols=n)
    if not np.allclose(P_a, P_a.T, rtol=1e-12, atol=1e-14 * max(1.0, float(np.abs(P_a).max()))):
        raise InvalidValueError("P must be symmetric")
    q_a = as_vector("q", q, size=n)
    if Z.is_empty():
        raise EmptySetError("the set is empty")
    G, c = Z.G, Z.c
    if Z.n_gen == 0:  # a point: nothing to solve
        return QPResult(c.copy(), float(0.5 * c @ P_a @ c + q_a @ c), "Solved")
    cl = _clarabel()
    Pq = G.T @ P_a @ G
    Pq = (Pq + Pq.T) / 2.0
    lin = G.T @ (P_a @ c + q_a)
    fin = np.flatnonzero(np.isfinite(Z.h))
    ng = Z.n_gen
    rows = [Z.A, np.eye(ng)[fin], -np.eye(ng)[fin]]
    rhs = np.concatenate([Z.b, Z.h[fin], Z.h[fin]])
    Acon = sparse.csc_matrix(np.vstack(rows))
    cones = ([cl.ZeroConeT(Z.n_con)] if Z.n_con else []) + \
        ([cl.NonnegativeConeT(2 * fin.size)] if fin.size else [])
    settings = cl.DefaultSettings()
    settings.verbose = False
    solver = cl.DefaultSolver(sparse.triu(sparse.csc_matrix(Pq)).tocsc(), lin, Acon, rhs,
                              cones, settings)
    sol = solver.solve()
    status = str(sol.status)
    if status not in ("Solved", "AlmostSolved"):
        raise SolverError(f"Clarabel did not solve the QP over the set (status {status})",
                          status=status)
    xi = np.asarray(sol.x, dtype=np.float64)
    xi = np.clip(xi, -Z.h, Z.h)
    z = G @ xi + c
    return QPResult(z, float(0.5 * z @ P_a @ z + q_a @ z), status)


def nearest_point(Z: ConstrainedZonotope, p: ArrayLike) -> NDArray[np.float64]:
    """The point of ``Z`` nearest to ``p`` in the Euclidean norm (a QP, Clarabel).

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    p : array_like, shape (n,)
        The point.
    """
    pv = as_vector("p", p, size=Z.dim)
    Zs, f = unit_scaled(Z, float(np.abs(pv).max(initial=0.0)))
    if Zs is not Z:  # at unit magnitude (exact power-of-two scaling), scaled back
        return nearest_point(Zs, pv / f) * f
    return minimize_quadratic(Z, np.eye(Z.dim), -pv).point


def distance(Z: ConstrainedZonotope, p: ArrayLike) -> DistanceResult:
    """Euclidean distance from ``p`` to ``Z``, with a certified lower bound.

    The nearest point ``z*`` comes from :func:`nearest_point`. With
    ``u = (p - z*)/||p - z*||``, every point of ``Z`` satisfies
    ``u^T z <= sigma_Z(u)`` (certified support value), so the distance is at
    least ``u^T p - sigma_Z(u)`` (rounded down): the lower bound.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    p : array_like, shape (n,)
        The point.

    Examples
    --------
    >>> Z = ConstrainedZonotope.from_box([0.0, 0.0], [1.0, 1.0])
    >>> r = distance(Z, [4.0, 5.0])
    >>> round(r.distance, 6), bool(abs(r.lower - 5.0) < 1e-6)
    (5.0, True)
    """
    pv = as_vector("p", p, size=Z.dim)
    Zs, f = unit_scaled(Z, float(np.abs(pv).max(initial=0.0)))
    if Zs is not Z:  # at unit magnitude (exact power-of-two scaling), scaled back
        r = distance(Zs, pv / f)
        return DistanceResult(r.distance * f, r.lower * f, r.point * f)
    z = nearest_point(Z, pv)
    d = float(np.linalg.norm(pv - z))
    lower = 0.0
    if d > 0.0:
        u = (pv - z) / d
        s = support_unwarned(Z, u)
        up = float(u @ pv)
        err = gamma(Z.dim + 1) * float(np.abs(u) @ np.abs(pv))
        lower = max(0.0, float(round_down(up - s - err)))
    return DistanceResult(d, lower, z)


# ----------------------------------------------------------------------------- sampling
def _direction_basis(Z: ConstrainedZonotope) -> NDArray[np.float64]:
    """Orthonormal basis of the direction space ``G null([A; E_0])`` of the affine hull."""
    from scipy.linalg import null_space

    keep = Z.h > 0
    G, A = Z.G[:, keep], Z.A[:, keep]
    N = null_space(A) if A.shape[0] else np.eye(G.shape[1])
    M = G @ N
    if M.size == 0:
        return np.zeros((Z.dim, 0))
    U, s, _ = np.linalg.svd(M, full_matrices=False)
    r = int((s > 1e-12 * max(1.0, float(s.max(initial=0.0)))).sum())
    return U[:, :r]


class _FacetChords:
    """Chords from the verified facets ``H x <= k`` (small dimensions)."""

    def __init__(self, Z: ConstrainedZonotope) -> None:
        from .polytope import to_hrep

        hr = to_hrep(Z)
        self.H, self.k = hr.H, hr.k
        self.E = hr.E

    def chord(self, x: NDArray[np.float64], u: NDArray[np.float64]) -> tuple[float, float]:
        Hu = self.H @ u
        slack = self.k - self.H @ x
        with np.errstate(divide="ignore", invalid="ignore"):
            t = slack / Hu
        hi = float(np.min(t[Hu > 0], initial=np.inf))
        lo = float(np.max(t[Hu < 0], initial=-np.inf))
        return lo, hi


class LPChords:
    """Chords from two LPs on ``{t : x + t u in Z}``, all on one HiGHS model per chain.

    Columns ``(t, xi)`` (``t`` free, ``|xi| <= h``), rows ``u t - G xi = c - x`` and
    ``A xi = b``: between chords only the ``t`` column (``u``), the first rows' bounds
    (``c - x``) and the sign of ``t``'s cost change, so each LP starts from the last
    basis (warm) instead of a new model (0.6 ms per LP before).
    """

    def __init__(self, Z: ConstrainedZonotope) -> None:
        self.Z = Z
        n, n_g, n_c = Z.dim, Z.n_gen, Z.n_con
        M = np.zeros((n + n_c, 1 + n_g))
        M[:n, 0] = 1.0  # (the structure of u; its values are set per chord)
        M[:n, 1:] = -Z.G
        M[n:, 1:] = Z.A
        inf = np.inf
        up = np.concatenate([[inf], Z.h])  # (h = inf: free, as HiGHS's infinity)
        self.hs = highs.new_model()
        rows = np.concatenate([Z.c, Z.b])
        ok = highs.pass_dense(self.hs, M, -up, up, rows, rows,
                              np.concatenate([[1.0], np.zeros(n_g)]))
        if not ok:
            raise SolverError("hit-and-run: HiGHS rejected the chord model")
        self.n = n
        self.idx = np.arange(n, dtype=np.int32)

    def _solve(self, sign: float) -> float:
        hs = self.hs
        hs.changeColCost(0, sign)
        if highs.solve(hs) != "optimal":
            raise SolverError("a chord LP of hit-and-run failed", status=highs.status_name(hs))
        return float(hs.getSolution().col_value[0])

    def chord(self, x: NDArray[np.float64], u: NDArray[np.float64]) -> tuple[float, float]:
        hs = self.hs
        for i in range(self.n):
            hs.changeCoeff(i, 0, float(u[i]))
        r = self.Z.c - x
        hs.changeRowsBounds(self.n, self.idx, r, r)
        return self._solve(1.0), self._solve(-1.0)


def sample(Z: ConstrainedZonotope, n: int, rng: np.random.Generator | int | None = None, *,
           burn_in: int = 200, thin: int | None = None, method: str = "auto"
           ) -> NDArray[np.float64]:
    """Approximately uniform random points of a bounded set, by hit-and-run.

    Hit-and-run (Smith 1984): from the current point, a uniformly random
    direction in the set's affine hull (directions ``G null(A)``), and a
    uniform point on the chord through it. The chain's stationary law is
    uniform on the set; ``burn_in`` steps are discarded and every ``thin``-th
    point is kept. The start is the mean of support points in ``+-`` each
    direction of the affine hull (a relative-interior point). Chords shrink by
    a relative ``1e-9`` so that points stay inside.

    Parameters
    ----------
    Z : ConstrainedZonotope
        A bounded, nonempty set.
    n : int
        Number of points.
    rng : numpy.random.Generator, int or None
        Random source.
    burn_in : int
        Steps discarded at the start.
    thin : int, optional
        Steps per returned point (default ``5 d``, ``d`` the dimension of the
        affine hull). Consecutive hit-and-run points are correlated; long thin
        sets need more steps (a 4-D box with side ratio 6 needed 20 per point
        for a Kolmogorov-Smirnov test of its marginals to pass).
    method : {"auto", "facets", "lp"}
        Chord computation: from the verified facets (fast; ``"auto"`` uses it
        in dimension <= 3) or from two LPs per step.

    Returns
    -------
    ndarray, shape (n, dim)

    Raises
    ------
    UnboundedSetError
        If the set is unbounded.
    SolverError
        If the set is flatter than its representation says (zero-length
        chords in the directions of ``G null(A)``: use
        :meth:`~ConstrainedZonotope.reduce_exact` first).
    """
    if int(n) != n or n < 0:
        raise InvalidValueError(f"n must be a nonnegative integer, got {n!r}")
    if method not in ("auto", "facets", "lp"):
        raise InvalidValueError(f"method must be 'auto', 'facets' or 'lp', got {method!r}")
    Zs, f = unit_scaled(Z)
    if Zs is not Z:  # at unit magnitude (exact power-of-two scaling), scaled back
        return sample(Zs, n, rng, burn_in=burn_in, thin=thin, method=method) * f
    gen = np.random.default_rng(rng)
    box, _ = hull_with_status(Z)
    if not box.is_bounded:
        raise UnboundedSetError("sampling needs a bounded set")
    B = _direction_basis(Z)
    if B.shape[1] == 0:
        return np.tile(Z.c if Z.n_gen == 0 else box.center, (int(n), 1))
    pts = [Z.support_point(s * B[:, j]) for j in range(B.shape[1]) for s in (1.0, -1.0)]
    x = np.mean(pts, axis=0)
    if thin is None:
        thin = 5 * B.shape[1]
    if int(thin) != thin or thin < 1:
        raise InvalidValueError(f"thin must be a positive integer, got {thin!r}")
    thin = int(thin)
    use_facets = method == "facets" or (method == "auto" and Z.dim <= 3)
    oracle = _FacetChords(Z) if use_facets else LPChords(Z)
    scale = max(1.0, float(np.abs(np.concatenate([box.lo, box.hi])).max()))
    out = np.empty((int(n), Z.dim))
    total = burn_in + int(n) * thin
    zero = 0
    kept = 0
    for step in range(total):
        u = B @ gen.standard_normal(B.shape[1])
        u /= np.linalg.norm(u)
        lo, hi = oracle.chord(x, u)
        length = hi - lo
        if not length > 1e-12 * scale:
            zero += 1
            if zero > 20:
                raise SolverError("hit-and-run: zero-length chords; the set is flatter than "
                                  "G null(A) (reduce_exact() first)")
        else:
            shrink = 1e-9 * length
            x = x + gen.uniform(lo + shrink, hi - shrink) * u
        if step >= burn_in and (step - burn_in) % thin == thin - 1:
            out[kept] = x
            kept += 1
    return out


# ----------------------------------------------------------------------------- volume
def volume(Z: ConstrainedZonotope, *, n_samples: int = 20_000, confidence: float = 0.95,
           rng: np.random.Generator | int | None = None) -> VolumeResult:
    """Volume of a bounded set: exact in dimension 1-3, Monte Carlo with a CI above.

    In dimension 1 it is the certified hull's length; in 2 the shoelace area
    of :func:`~setobs.geometry.polygon_2d`; in 3 Qhull's volume of the
    verified vertices (0 for a flat set). Above, ``n_samples`` uniform points
    of the certified interval hull are tested with
    :meth:`~ConstrainedZonotope.contains`; the fraction inside, times the
    box's volume, estimates the volume, with a Clopper-Pearson interval at
    ``confidence`` (exact for the binomial count).

    Parameters
    ----------
    Z : ConstrainedZonotope
        A bounded set.
    n_samples : int
        Monte Carlo sample size (dimension > 3).
    confidence : float
        Confidence level of the Monte Carlo interval, in ``(0, 1)``.
    rng : numpy.random.Generator, int or None
        Random source (Monte Carlo).

    Examples
    --------
    >>> T = ConstrainedZonotope.from_zonotope([[1.0, 1.0], [0.0, 1.0]], [0.0, 0.0])
    >>> round(volume(T).value, 9)
    4.0
    """
    check_real_scalar("confidence", confidence, positive=True)
    if not confidence < 1:
        raise InvalidValueError(f"confidence must be in (0, 1), got {confidence}")
    Zs, f = unit_scaled(Z)
    if Zs is not Z:  # at unit magnitude (exact power-of-two scaling), scaled back
        r = volume(Zs, n_samples=n_samples, confidence=confidence, rng=rng)
        fn = f ** Z.dim
        return dataclasses.replace(r, value=r.value * fn, lower=r.lower * fn, upper=r.upper * fn)
    if Z.is_empty():
        return VolumeResult(0.0, 0.0, 0.0, "empty")
    box, _ = hull_with_status(Z)
    if not box.is_bounded:
        raise UnboundedSetError("the volume of an unbounded set is infinite")
    n = Z.dim
    if n == 1:
        v = float(box.hi[0] - box.lo[0])
        return VolumeResult(v, v, v, "interval")
    if n == 2:
        from .polytope import polygon_2d

        P = polygon_2d(Z)
        if P.shape[0] < 3:
            return VolumeResult(0.0, 0.0, 0.0, "polygon")
        x, y = P[:, 0], P[:, 1]
        v = 0.5 * abs(float(x @ np.roll(y, -1) - y @ np.roll(x, -1)))
        return VolumeResult(v, v, v, "polygon")
    if n == 3:
        from scipy.spatial import ConvexHull, QhullError

        V = Z.vertices()
        try:
            v = float(ConvexHull(V).volume)
        except (QhullError, ValueError):
            v = 0.0  # flat: fewer than 4 affinely independent vertices
        return VolumeResult(v, v, v, "qhull")
    if int(n_samples) != n_samples or n_samples < 1:
        raise InvalidValueError(f"n_samples must be a positive integer, got {n_samples!r}")
    from scipy.stats import beta

    gen = np.random.default_rng(rng)
    width = box.hi - box.lo
    vbox = float(np.prod(width))
    if vbox == 0.0:
        return VolumeResult(0.0, 0.0, 0.0, "monte-carlo", 0, confidence)
    X = box.lo + gen.random((int(n_samples), n)) * width
    k = sum(bool(Z.contains(x)) for x in X)
    N = int(n_samples)
    alpha = 1.0 - confidence
    lo = 0.0 if k == 0 else float(beta.ppf(alpha / 2, k, N - k + 1))
    hi = 1.0 if k == N else float(beta.ppf(1 - alpha / 2, k + 1, N - k))
    return VolumeResult(vbox * k / N, vbox * lo, vbox * hi, "monte-carlo", N, confidence)
