"""Hybrid zonotopes side by side with ZonoOpt's: each operation's and query's time on the
same sets, and every answer against the enumerated truth.

Sets: unions of ``N`` random constrained zonotopes (``n + 3`` generators, 2 constraints
each) in ``n`` dimensions, built by ``HybridZonotope.from_union`` and by ZonoOpt's
``union_of_many`` (with ``preserve_sharpness=True``, the formulation of the same size as
setobs's; its default, smaller and not sharp, is timed too). Operations: the union itself,
a linear map, a Minkowski sum and a generalised intersection with a constrained zonotope,
a half-space cut. Queries: support values in five directions and the interval hull.
The truth of a union's support is the largest of its operands' certified supports (the
support function of a union is the maximum of its operands'): setobs's answer must
equal it within ``1e-9`` of the set's scale and never lie below it; ZonoOpt's is
reported as it is (``inside`` when it lies below the truth by more than that: the
answer cuts points of the set off). A reachability horizon of a two-mode
piecewise-affine system (``pwa_reachable_sets`` against the same construction written
with ZonoOpt's functions), its final interval hull against the enumeration of every
mode sequence.

Run: ``python benchmarks/hybrid_zonotopes.py [--repeats 20]``; writes
``benchmarks/results/hybrid_zonotopes.json``. Needs ``zonoopt`` (``pip install
setobs[peers]``).
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE))

import setobs as so  # noqa: E402
from _common import stamp  # noqa: E402
from _peers import interleaved, to_zonoopt  # noqa: E402
from setobs.geometry import HybridZonotope, pwa_reachable_sets  # noqa: E402

CZ = so.ConstrainedZonotope
CASES = [(2, 2), (2, 8), (2, 16), (2, 64), (6, 8), (6, 16), (6, 64), (10, 16), (10, 64)]
REL = 1e-9


def operands(n: int, N: int, rng) -> list[CZ]:
    out = []
    for _ in range(N):
        G = rng.normal(size=(n, n + 3))
        A = rng.normal(size=(2, n + 3))
        out.append(CZ(G, 4.0 * rng.normal(size=n), A, A @ rng.uniform(-0.5, 0.5, n + 3)))
    return out


def best_of(f, repeats: int) -> float:
    ts = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t0)
    return min(ts)


def fresh_pair(ops, zops):
    """A new union on each side (no cached LP model on setobs's side)."""
    import zonoopt as zo

    return HybridZonotope.from_union(ops), zo.union_of_many(zops, preserve_sharpness=True)


def union_row(n: int, N: int, rng, repeats: int) -> dict:
    import zonoopt as zo

    ops = operands(n, N, rng)
    zops = [to_zonoopt(Z) for Z in ops]
    U, Uz = fresh_pair(ops, zops)
    W = CZ(0.5 * rng.normal(size=(n, n)), rng.normal(size=n))
    Wz = to_zonoopt(W)
    M = rng.normal(size=(n, n))
    Ms = sp.csc_matrix(M)
    a = rng.normal(size=n)
    beta = float(max(Z.support(a) for Z in ops)) * 0.5
    t_ops = {
        "union": interleaved(lambda: HybridZonotope.from_union(ops),
                             lambda: zo.union_of_many(zops, preserve_sharpness=True), repeats),
        "union_not_sharp_zonoopt": (None, best_of(lambda: zo.union_of_many(zops), repeats)),
        "linear_map": interleaved(lambda: M @ U, lambda: zo.affine_map(Uz, Ms), repeats),
        "minkowski_sum": interleaved(lambda: U + W, lambda: zo.minkowski_sum(Uz, Wz), repeats),
        "intersection": interleaved(lambda: U & W, lambda: zo.intersection(Uz, Wz), repeats),
        "halfspace": interleaved(
            lambda: HybridZonotope.from_union(ops).intersect_halfspace(a, beta),
            lambda: zo.halfspace_intersection(
                zo.union_of_many(zops, preserve_sharpness=True), sp.csc_matrix(a[None, :]),
                np.array([beta])), max(3, repeats // 4)),
    }
    scale = 1.0 + max(float(np.abs(Z.c).max() + np.abs(Z.G).sum()) for Z in ops)
    dirs = rng.normal(size=(5, n))
    truth = [max(Z.support(d) for Z in ops) for d in dirs]
    # the queries, each on a fresh pair of sets (setobs caches the relaxation's LP model)
    reps = max(3, repeats // 4)
    t_sup, t_sup_z, ours, theirs, nodes = [], [], [], [], []
    for d in dirs:
        ta, tb = [], []
        for _ in range(reps):
            U1, U1z = fresh_pair(ops, zops)
            t0 = time.perf_counter()
            r = U1.support_bounds(d)
            ta.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            sz = U1z.support(d)
            tb.append(time.perf_counter() - t0)
        t_sup.append(min(ta))
        t_sup_z.append(min(tb))
        ours.append(r.value)
        theirs.append(float(sz))
        nodes.append(r.nodes)
    ta, tb = [], []
    for _ in range(reps):
        U1, U1z = fresh_pair(ops, zops)
        t0 = time.perf_counter()
        box = U1.interval_hull()
        ta.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        zb = U1z.bounding_box()
        tb.append(time.perf_counter() - t0)
    e = np.eye(n)
    hi = np.array([max(Z.support(e[i]) for Z in ops) for i in range(n)])
    lo = np.array([-max(Z.support(-e[i]) for Z in ops) for i in range(n)])
    zlo, zhi = np.asarray(zb.lower()), np.asarray(zb.upper())
    ours_dev = np.array(ours) - truth
    theirs_dev = np.array(theirs) - truth
    hull_dev = np.concatenate([box.hi - hi, lo - box.lo])
    zhull_dev = np.concatenate([zhi - hi, lo - zlo])
    return {
        "n": n, "N": N, "factors": [U.n_cont, U.n_bin], "constraints": U.n_con,
        "zonoopt_factors": [Uz.nGc, Uz.nGb], "zonoopt_constraints": Uz.nC,
        **{k: {"setobs_s": ta_, "zonoopt_s": tb_,
               "ratio": None if ta_ is None else ta_ / tb_}
           for k, (ta_, tb_) in t_ops.items()},
        "support": {"setobs_s": float(np.median(t_sup)), "zonoopt_s": float(np.median(t_sup_z)),
                    "ratio": float(np.median(t_sup) / np.median(t_sup_z)),
                    "setobs_nodes": nodes},
        "interval_hull": {"setobs_s": min(ta), "zonoopt_s": min(tb), "ratio": min(ta) / min(tb)},
        "scale": scale,
        "setobs_support_deviation": [float(v) for v in ours_dev],
        "setobs_certified_and_equal": bool((ours_dev >= 0).all()
                                           and (np.abs(ours_dev) <= REL * scale).all()),
        "setobs_hull_deviation_max": float(np.abs(hull_dev).max()),
        "setobs_hull_outer": bool((hull_dev >= 0).all()),
        "zonoopt_support_deviation": [float(v) for v in theirs_dev],
        "zonoopt_support_inside": int((theirs_dev < -REL * scale).sum()),
        "zonoopt_hull_inside": int((zhull_dev < -REL * scale).sum()),
        "zonoopt_hull_max_inward": float(max(0.0, -zhull_dev.min())),
    }


def rot(t):
    return np.array([[np.cos(t), -np.sin(t)], [np.sin(t), np.cos(t)]])


def reach_row(K: int, repeats: int) -> dict:
    """Two modes split at x_1 = 0, horizon ``K``: the final set's hull against every
    mode sequence's set, propagated one by one with constrained zonotopes."""
    import zonoopt as zo

    P1, P2 = CZ.from_box([-4.0, -4.0], [0.0, 4.0]), CZ.from_box([0.0, -4.0], [4.0, 4.0])
    modes = [(P1, 0.95 * rot(1.2), np.array([0.4, 0.0])),
             (P2, 0.9 * rot(-0.9), np.array([-0.5, 0.1]))]
    X0 = CZ.from_box([-1.0, -0.5], [1.0, 0.5])

    def zonoopt_reach():
        graphs = [to_zonoopt(P.linear_map(np.vstack([np.eye(2), A]))
                             + np.concatenate([np.zeros(2), f])) for P, A, f in modes]
        Psi = zo.union_of_many(graphs, preserve_sharpness=True)
        R = sp.csc_matrix(np.hstack([np.eye(2), np.zeros((2, 2))]))
        X = to_zonoopt(X0)
        for _ in range(K):
            X = zo.project_onto_dims(zo.intersection(Psi, X, R), [2, 3])
        return X

    t_build = interleaved(lambda: pwa_reachable_sets(modes, X0, K), zonoopt_reach, repeats)
    X = pwa_reachable_sets(modes, X0, K)[-1]
    Xz = zonoopt_reach()
    t0 = time.perf_counter()
    box = X.interval_hull()
    t_hull = time.perf_counter() - t0
    t0 = time.perf_counter()
    try:
        zb = Xz.bounding_box()
        zerr = None
    except ValueError as exc:  # (ZonoOpt's answer when its solver calls the set empty)
        zb, zerr = None, str(exc)
    t_zhull = time.perf_counter() - t0
    seqs = []
    for sig in itertools.product(range(2), repeat=K):
        S = X0
        for m in sig:
            P, A, f = modes[m]
            S = A @ (S & P) + f
            if S.is_empty():
                break
        else:
            seqs.append(S)
    e = np.eye(2)
    hi = np.array([max(S.support(e[i]) for S in seqs) for i in range(2)])
    lo = np.array([-max(S.support(-e[i]) for S in seqs) for i in range(2)])
    dev = np.concatenate([box.hi - hi, lo - box.lo])
    zdev = (np.full(4, np.nan) if zb is None else
            np.concatenate([np.asarray(zb.upper()) - hi, lo - np.asarray(zb.lower())]))
    return {"horizon": K, "mode_sequences_nonempty": len(seqs),
            "factors": [X.n_cont, X.n_bin], "constraints": X.n_con,
            "zonoopt_factors": [Xz.nGc, Xz.nGb], "zonoopt_constraints": Xz.nC,
            "reach": {"setobs_s": t_build[0], "zonoopt_s": t_build[1],
                      "ratio": t_build[0] / t_build[1]},
            "interval_hull": {"setobs_s": t_hull, "zonoopt_s": t_zhull,
                              "ratio": t_hull / t_zhull},
            "setobs_hull_deviation": [float(v) for v in dev],
            "setobs_hull_outer": bool((dev >= 0).all()),
            "zonoopt_hull_deviation": None if zb is None else [float(v) for v in zdev],
            "zonoopt_hull_inside": None if zb is None else int((zdev < -REL * 10).sum()),
            "zonoopt_error": zerr}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--horizons", default="4,8,10")
    ap.add_argument("--out", default=str(HERE / "results" / "hybrid_zonotopes.json"))
    args = ap.parse_args()
    import zonoopt as zo

    rng = np.random.default_rng(0)
    out = {**stamp(), "zonoopt_version": getattr(zo, "__version__", "2.5"),
           "unions": [], "reachability": []}
    # (warm-up: the first LP compiles and loads the solvers)
    HybridZonotope.from_union(operands(2, 2, rng)).interval_hull()
    for n, N in CASES:
        row = union_row(n, N, rng, args.repeats)
        out["unions"].append(row)
        print(f"n={n} N={N}: union {row['union']['ratio']:.2f}x, support "
              f"{row['support']['ratio']:.2f}x, hull {row['interval_hull']['ratio']:.2f}x; "
              f"ours equal {row['setobs_certified_and_equal']}, zonoopt inside "
              f"{row['zonoopt_support_inside']}/5, hull {row['zonoopt_hull_inside']}",
              flush=True)
        Path(args.out).write_text(json.dumps(out, indent=1))
    for K in (int(v) for v in args.horizons.split(",")):
        row = reach_row(K, max(3, args.repeats // 4))
        out["reachability"].append(row)
        print(f"reach K={K}: {row['reach']['ratio']:.2f}x, hull "
              f"{row['interval_hull']['ratio']:.2f}x, ours outer {row['setobs_hull_outer']}, "
              f"zonoopt inside {row['zonoopt_hull_inside']} {row['zonoopt_error'] or ''}",
              flush=True)
        Path(args.out).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
