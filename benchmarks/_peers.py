"""ZonoOpt as a peer of the geometry: the same sets, the same operations,
interleaved medians, the ratios by dimension, and what each answer is worth.

ZonoOpt (``pip install setobs[peers]``) is a C++ library with Python bindings; its
interval hulls and support values come from an ADMM solver without a certificate.
Here its boxes are compared with setobs' certified ones: a ZonoOpt box that lies
*inside* setobs' certified box by more than the latter's certification slack (1e-9
relative) cuts off points of the set.
"""

from __future__ import annotations

import copy
import statistics
import time

import numpy as np
import scipy.sparse as sp

from setobs import ConstrainedZonotope
from setobs.geometry import eliminate_constraints

#: (n_gen, n_con) of the random sets at each dimension n = 2..6.
SHAPES = [(10, 0), (20, 5), (40, 10)]
DIMS = [2, 3, 4, 5, 6]


def to_zonoopt(Z: ConstrainedZonotope):
    import zonoopt as zo

    return zo.ConZono(sp.csc_matrix(Z.G), Z.c, sp.csc_matrix(Z.A), Z.b)


def from_zonoopt(Rz) -> ConstrainedZonotope:
    """A ZonoOpt constrained zonotope (``[-1, 1]`` form) as a setobs set, to read it with
    certified LPs."""
    if Rz.is_0_1_form():
        Rz = Rz.copy()
        Rz.convert_form()
    G = Rz.G.toarray() if sp.issparse(Rz.G) else np.asarray(Rz.G)
    A = Rz.A.toarray() if sp.issparse(Rz.A) else np.asarray(Rz.A)
    if not A.size:
        return ConstrainedZonotope(G, np.asarray(Rz.c))
    return ConstrainedZonotope(G, np.asarray(Rz.c), A, np.asarray(Rz.b))


def _copies(Z: ConstrainedZonotope, k: int):
    """``k`` copies of ``Z`` without its cached LP model and results (``copy.copy``
    rebuilds the set from its arrays), made before the timing, as an iterator: each
    timed query runs on a set that has answered nothing yet, and pays nothing else."""
    return iter([copy.copy(Z) for _ in range(k)])


def interleaved(fa, fb, repeats: int) -> tuple[float, float]:
    """Medians of ``fa`` and ``fb`` timed alternately (after one warm-up each)."""
    fa()
    fb()
    ta, tb = [], []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fa()
        ta.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        fb()
        tb.append(time.perf_counter() - t0)
    return statistics.median(ta), statistics.median(tb)


def random_set(n, n_g, n_c, rng) -> ConstrainedZonotope:
    G = rng.normal(size=(n, n_g))
    A = rng.normal(size=(n_c, n_g))
    return ConstrainedZonotope(G, rng.normal(size=n), A, A @ rng.uniform(-0.5, 0.5, n_g))


def _time_ops(Z, W, M, R, E, p, repeats: int) -> dict:
    """The medians of each operation on one set, setobs then ZonoOpt."""
    import zonoopt as zo

    Zz, Wz, Ez = to_zonoopt(Z), to_zonoopt(W), to_zonoopt(E)
    Ms, Rs = sp.csc_matrix(M), sp.csc_matrix(R)
    lp_reps = max(5, repeats // 10)
    E_it, Zc_it, Zh_it = (_copies(E, lp_reps + 1), _copies(Z, lp_reps + 1),
                          _copies(Z, lp_reps + 1))
    return {
        "minkowski_sum": interleaved(lambda: Z + W, lambda: zo.minkowski_sum(Zz, Wz), repeats),
        "linear_map": interleaved(lambda: M @ Z, lambda: zo.affine_map(Zz, Ms), repeats),
        "generalized_intersection": interleaved(
            lambda: Z.intersect(W, R), lambda: zo.intersection(Zz, Wz, Rs), repeats),
        "emptiness_of_empty": interleaved(lambda: next(E_it).is_empty(),
                                          lambda: Ez.is_empty(), lp_reps),
        "point_containment": interleaved(lambda: next(Zc_it).contains(p),
                                         lambda: Zz.contains_point(p), lp_reps),
        "interval_hull": interleaved(lambda: next(Zh_it).interval_hull(),
                                     lambda: Zz.bounding_box(), lp_reps),
    }


def operation_rows(rng: np.random.Generator, repeats: int) -> list[dict]:
    """Per dimension and set shape: setobs' and ZonoOpt's medians of each operation."""
    rows = []
    for n in DIMS:
        for n_g, n_c in SHAPES:
            Z, W = random_set(n, n_g, n_c, rng), random_set(n, n_g, n_c, rng)
            M, R = rng.normal(size=(n, n)), rng.normal(size=(n, n))
            E = Z.intersect(W + 100.0 * np.ones(n))  # empty
            p = Z.interval_hull().center
            t = _time_ops(Z, W, M, R, E, p, repeats)
            Zz, Ez = to_zonoopt(Z), to_zonoopt(E)
            box = Z.interval_hull()
            zb = Zz.bounding_box()
            zlo, zhi = np.asarray(zb.lower()), np.asarray(zb.upper())
            slack = 1e-9 * (1.0 + np.abs(box.lo) + np.abs(box.hi))
            inside = bool(((zlo > box.lo + slack) | (zhi < box.hi - slack)).any())
            assert E.is_empty() and Ez.is_empty() and Z.contains(p)
            rows.append({"n": n, "n_gen": n_g, "n_con": n_c,
                         **{k: {"setobs_s": a, "zonoopt_s": b, "ratio": a / b}
                            for k, (a, b) in t.items()},
                         "zonoopt_hull_inside_certified_box": inside,
                         "zonoopt_hull_max_inward": float(np.max(np.concatenate(
                             [zlo - box.lo, box.hi - zhi])))})
    return rows


class _Bare:
    """A plain slotted object: the least a Python set type costs to create."""

    __slots__ = ("G", "c", "h")


def python_floor(rng: np.random.Generator, repeats: int) -> dict:
    """What a Minkowski sum costs in Python at the least, whatever the library: a slotted
    object holding the concatenated generators, the summed centre and the concatenated
    bounds (no constraints, no rounding bookkeeping, no checks), against ZonoOpt's sum,
    per number of generators (n = 4)."""
    out = {}
    for n_g, n_c in SHAPES:
        Z, W = random_set(4, n_g, n_c, rng), random_set(4, n_g, n_c, rng)
        a, b = interleaved(_bare_sum(Z, W), _zonoopt_sum(Z, W), repeats)
        out[f"{n_g}x{n_c}"] = {"bare_python_s": a, "zonoopt_s": b, "ratio": a / b}
    return out


def _bare_sum(Z: ConstrainedZonotope, W: ConstrainedZonotope):
    G1, G2, c1, c2, h1, h2 = Z.G, W.G, Z.c, W.c, Z.h, W.h

    def bare():
        o = _Bare()
        o.G = np.concatenate((G1, G2), axis=1)
        o.c = c1 + c2
        o.h = np.concatenate((h1, h2))
        return o

    return bare


def _zonoopt_sum(Z: ConstrainedZonotope, W: ConstrainedZonotope):
    import zonoopt as zo

    Zz, Wz = to_zonoopt(Z), to_zonoopt(W)
    return lambda: zo.minkowski_sum(Zz, Wz)


def ratios_by_dimension(rows: list[dict]) -> dict:
    """Median ratio (setobs / ZonoOpt) of each operation over the shapes, per dimension."""
    ops = [k for k in rows[0] if isinstance(rows[0][k], dict)]
    out: dict = {}
    for op in ops:
        out[op] = {str(n): statistics.median(r[op]["ratio"] for r in rows if r["n"] == n)
                   for n in sorted({r["n"] for r in rows})}
    return out


def sphere_polytope(m: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """``{x in R^3 : H x <= 1}``, ``m`` random unit normals (every row a facet)."""
    from scipy.spatial import HalfspaceIntersection

    rng = np.random.default_rng(seed)
    H = rng.normal(size=(m, 3))
    H /= np.linalg.norm(H, axis=1)[:, None]
    V = HalfspaceIntersection(np.hstack([H, -np.ones((m, 1))]), np.zeros(3)).intersections
    return H, V


def elimination_rows(linprog_s: float, repeats: int) -> dict:
    """The 3-D 60-facet polytope (63 generators, 60 constraints): time per eliminated
    constraint and support excess over the polytope's (from its Qhull vertices) in 50
    unit directions, for 1, 10 and 30 eliminated constraints."""
    H, V = sphere_polytope(60)
    Z = ConstrainedZonotope.from_hpolytope(H, np.ones(60))
    Zz = to_zonoopt(Z)
    D = np.random.default_rng(7).normal(size=(50, 3))
    D /= np.linalg.norm(D, axis=1)[:, None]
    exact = (V @ D.T).max(axis=0)
    out: dict = {"set": {"n": 3, "n_gen": Z.n_gen, "n_con": Z.n_con},
                 "linprog_45x40_s": linprog_s, "rows": []}
    for k in (1, 10, 30):
        def ours(k=k):
            return eliminate_constraints(Z, Z.n_con - k, method="fast")

        def theirs(k=k):
            R = Zz
            for _ in range(k):
                R = R.constraint_reduction()
            return R

        ta, tb = interleaved(ours, theirs, max(3, repeats // 20))
        R, Rz = ours(), theirs()
        ex_ours = np.array([R.support(d) for d in D]) - exact
        ex_z = np.array([Rz.support(d) for d in D]) - exact
        row = {"eliminated": k,
               "fast_s_per_constraint": ta / k, "zonoopt_s_per_constraint": tb / k,
               "fast_linprogs_per_constraint": ta / k / linprog_s,
               "ratio": ta / tb,
               "fast_support_excess_mean": float(ex_ours.mean()),
               "fast_support_excess_max": float(ex_ours.max()),
               "fast_support_excess_min": float(ex_ours.min()),
               "zonoopt_support_excess_mean": float(ex_z.mean()),
               "zonoopt_support_excess_max": float(ex_z.max()),
               "zonoopt_support_excess_min": float(ex_z.min())}
        t0 = time.perf_counter()
        R_lp = eliminate_constraints(Z, Z.n_con - k, method="lp")
        row["lp_s_per_constraint"] = (time.perf_counter() - t0) / k
        row["lp_linprogs_per_constraint"] = row["lp_s_per_constraint"] / linprog_s
        ex_lp = np.array([R_lp.support(d) for d in D]) - exact
        row["lp_support_excess_mean"] = float(ex_lp.mean())
        row["lp_support_excess_max"] = float(ex_lp.max())
        # ZonoOpt's own support values come from its ADMM solver: the same set's
        # certified supports (setobs' LP) say how far the set really reaches
        ex_zc = np.array([from_zonoopt(Rz).support(d) for d in D]) - exact
        row["zonoopt_certified_support_excess_mean"] = float(ex_zc.mean())
        row["zonoopt_certified_support_excess_min"] = float(ex_zc.min())
        out["rows"].append(row)
    return out
