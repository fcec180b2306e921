"""Benchmark: the LP/QP-based set operations vs the straightforward cvxpy formulation.

For random non-empty constrained zonotopes ``(n, n_gen, n_con)`` in
{(3, 20, 10), (5, 60, 40)} and a polytope ``P`` of ``m = 20`` random
half-spaces, time in the same run:

* ``subset_of_polytope``: ``is_subset_of_polytope(Z, H, k)`` (m certified
  support LPs on one warm HiGHS model) vs one fresh ``cvxpy.Problem`` per row
  (``max H_i (G xi + c)`` over the factor set, Clarabel);
* ``intersect_polytope``: ``intersect_polytope(Z, H, k)`` (up to 2m certified
  LPs: redundancy and the slack bounds) vs the same 2m LPs in cvxpy;
* ``distance``: ``distance(Z, p)`` (a Clarabel QP called directly, plus one
  certified support LP for the lower bound) vs the QP written in cvxpy
  (Clarabel);
* ``convex_hull`` + ``interval_hull``: the hull of two sets, then its 2n LPs,
  vs the 2n LPs of the lambda-formulation of the hull written in cvxpy
  (``z = z1 + z2``, ``z1`` in ``lam Z``, ``z2`` in ``(1 - lam) W``).

The disagreement columns compare the values (supports, distances, bounds):
setobs' LP values are certified outer bounds, so differences are outward and of
the order of Clarabel's accuracy.

With ZonoOpt installed (``pip install setobs[peers]``), the ``peers`` section
compares setobs with it on the same sets (``_peers.py``): Minkowski sum, linear
map, generalized intersection, emptiness of an empty intersection, point
containment and interval hull on random sets (n = 2..6; 10, 20, 40 generators; 0,
5, 10 constraints), interleaved medians and their ratios by dimension; whether
ZonoOpt's hull falls inside setobs' certified box; what the least Python object of a
sum costs (why the three set-building operations are compiled, ``setup.py``); and
constraint elimination on a 3-D polytope with 60 facets (63 generators, 60
constraints): time per eliminated constraint, in 45 x 40 linprog units, and the
support excess over the polytope's.

Run: ``python benchmarks/geometry_ops.py [--repeats N] [--peers-only]``; writes
``benchmarks/results/geometry_ops.json`` (``--peers-only`` keeps the file's cvxpy
rows and measures the peers again).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
from importlib import metadata
from pathlib import Path

import cvxpy as cp
import numpy as np

import setobs
from _common import linprog_unit, make_cz, stamp, timeit
from setobs import ConstrainedZonotope
from setobs.geometry import (
    compiled_set_operations,
    convex_hull,
    distance,
    intersect_polytope,
    is_subset_of_polytope,
)

SIZES = [(3, 20, 10), (5, 60, 40)]
M_ROWS = 20


def fresh(Z: ConstrainedZonotope) -> ConstrainedZonotope:
    return ConstrainedZonotope(Z.G, Z.c, Z.A, Z.b, Z.h)


def cvx_support(Z: ConstrainedZonotope, d: np.ndarray) -> float:
    xi = cp.Variable(Z.n_gen)
    cons = [cp.abs(xi) <= Z.h] + ([Z.A @ xi == Z.b] if Z.n_con else [])
    prob = cp.Problem(cp.Maximize((d @ Z.G) @ xi), cons)
    prob.solve(solver=cp.CLARABEL)
    if prob.status != cp.OPTIMAL:
        raise RuntimeError(prob.status)
    return float(prob.value + d @ Z.c)


def subset_cvxpy(Z, H, k):
    s = np.array([cvx_support(Z, h) for h in H])
    return bool((s <= k).all()), s


def intersect_cvxpy(Z, H, k):
    up = np.array([cvx_support(Z, h) for h in H])
    lo = np.array([-cvx_support(Z, -h) for h in H])
    return up, lo


def distance_cvxpy(Z, p):
    xi = cp.Variable(Z.n_gen)
    cons = [cp.abs(xi) <= Z.h] + ([Z.A @ xi == Z.b] if Z.n_con else [])
    prob = cp.Problem(cp.Minimize(cp.norm(Z.G @ xi + Z.c - p)), cons)
    prob.solve(solver=cp.CLARABEL)
    return float(prob.value)


def hull_cvxpy(Z, W):
    """Interval hull of conv(Z u W) by the lambda formulation, one problem per bound."""
    lo, hi = np.empty(Z.dim), np.empty(Z.dim)
    for i in range(Z.dim):
        for sgn in (1.0, -1.0):
            x1, x2, lam = cp.Variable(Z.n_gen), cp.Variable(W.n_gen), cp.Variable()
            cons = [cp.abs(x1) <= lam * Z.h, cp.abs(x2) <= (1 - lam) * W.h,
                    Z.A @ x1 == lam * Z.b, W.A @ x2 == (1 - lam) * W.b, lam >= 0, lam <= 1]
            z = Z.G @ x1 + lam * Z.c + W.G @ x2 + (1 - lam) * W.c
            prob = cp.Problem(cp.Minimize(sgn * z[i]), cons)
            prob.solve(solver=cp.CLARABEL)
            if sgn > 0:
                lo[i] = prob.value
            else:
                hi[i] = -prob.value
    return lo, hi


def peer_section(repeats: int) -> dict:
    """The ZonoOpt comparison (``_peers.py``), or why it was skipped."""
    try:
        import zonoopt  # noqa: F401  (the optional peer)
    except ImportError:
        return {"skipped": "zonoopt is not installed (pip install setobs[peers])"}
    import _peers

    rows = _peers.operation_rows(np.random.default_rng(34), max(40, 40 * repeats))
    lp_s = linprog_unit()
    elim = _peers.elimination_rows(lp_s, max(40, 40 * repeats))
    ratios = _peers.ratios_by_dimension(rows)
    for op, by_n in ratios.items():
        print(f"  {op:26s} setobs/ZonoOpt by n: "
              + "  ".join(f"{n}: {r:5.2f}" for n, r in by_n.items()))
    for r in elim["rows"]:
        print(f"  eliminate {r['eliminated']:2d}: {1e3 * r['fast_s_per_constraint']:.2f} ms per "
              f"constraint ({r['fast_linprogs_per_constraint']:.2f} linprog), ZonoOpt "
              f"{1e3 * r['zonoopt_s_per_constraint']:.2f} ms; support excess mean "
              f"{r['fast_support_excess_mean']:.4f} (ZonoOpt "
              f"{r['zonoopt_certified_support_excess_mean']:.4f} certified, "
              f"{r['zonoopt_support_excess_mean']:.4f} its own; lp mode "
              f"{r['lp_support_excess_mean']:.4f} at {1e3 * r['lp_s_per_constraint']:.1f} ms)")
    floor = _peers.python_floor(np.random.default_rng(35), max(40, 40 * repeats))
    for shape, r in floor.items():
        print(f"  bare Python sum ({shape}): {1e6 * r['bare_python_s']:.1f} us, ZonoOpt "
              f"{1e6 * r['zonoopt_s']:.1f} us")
    inside = sum(r["zonoopt_hull_inside_certified_box"] for r in rows)
    return {
        "zonoopt": metadata.version("zonoopt"),
        # +, @ and intersect built in C (setup.py) or run in NumPy
        "compiled_set_operations": compiled_set_operations(),
        "ratios_by_dimension": ratios,
        "operations": rows,
        "zonoopt_hulls_inside_certified_box": f"{inside} of {len(rows)}",
        "python_floor_of_a_sum": floor,
        "elimination": elim,
        "targets": {
            # by dimension (the median over the set shapes) and on every single set
            "every_operation_ratio_at_most_1": {
                op: {"worst": max(by_n.values()),
                     "worst_set": max(r[op]["ratio"] for r in rows),
                     "met": max(r[op]["ratio"] for r in rows) <= 1.0}
                for op, by_n in ratios.items()},
            "elimination_at_most_10_linprogs_per_constraint": {
                "worst": max(r["fast_linprogs_per_constraint"] for r in elim["rows"]),
                "met": max(r["fast_linprogs_per_constraint"] for r in elim["rows"]) <= 10.0},
        },
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "geometry_ops.json"))
    ap.add_argument("--peers-only", action="store_true",
                    help="measure only the ZonoOpt comparison (keep the file's other rows)")
    args = ap.parse_args()
    rng = np.random.default_rng(2026)
    peers = peer_section(args.repeats)
    if args.peers_only:
        result = json.loads(Path(args.out).read_text())
        result["peers"] = peers
        result["setobs"] = setobs.__version__
        Path(args.out).write_text(json.dumps({**stamp(), **result}, indent=2) + "\n")
        print(f"wrote {args.out}")
        return
    rows = []
    r_cvx = max(2, args.repeats // 2)
    for n, n_g, n_c in SIZES:
        Z = make_cz(n, n_g, n_c, rng)
        W = make_cz(n, n_g, n_c, rng) + rng.normal(size=n) * 3.0
        H = rng.normal(size=(M_ROWS, n))
        box = Z.interval_hull()
        k = H @ box.center + 0.5 * np.abs(H) @ box.half_width
        p = box.center + 3.0 * box.half_width

        t1, _, res = timeit(lambda Z=Z, H=H, k=k: is_subset_of_polytope(fresh(Z), H, k),
                         repeats=args.repeats)
        t1c, _, (_, s_cvx) = timeit(subset_cvxpy, Z, H, k, repeats=r_cvx)
        s_ours = np.array([fresh(Z).support(h) for h in H])
        t2, _, _ = timeit(lambda Z=Z, H=H, k=k: intersect_polytope(fresh(Z), H, k),
                       repeats=args.repeats)
        t2c, _, _ = timeit(intersect_cvxpy, Z, H, k, repeats=r_cvx)
        t3, _, dres = timeit(lambda Z=Z, p=p: distance(fresh(Z), p), repeats=args.repeats)
        t3c, _, d_cvx = timeit(distance_cvxpy, Z, p, repeats=r_cvx)
        t4, _, hbox = timeit(lambda Z=Z, W=W: convex_hull(fresh(Z), fresh(W)).interval_hull(),
                          repeats=args.repeats)
        t4c, _, (lo_c, hi_c) = timeit(hull_cvxpy, Z, W, repeats=r_cvx)
        row = {
            "n": n, "n_gen": n_g, "n_con": n_c, "m_rows": M_ROWS,
            "subset_of_polytope": {"setobs_s": t1, "cvxpy_s": t1c, "speedup": t1c / t1,
                                   "verdict": res.holds,
                                   "max_outward_support_diff": float((s_ours - s_cvx).max()),
                                   "min_outward_support_diff": float((s_ours - s_cvx).min())},
            "intersect_polytope": {"setobs_s": t2, "cvxpy_s": t2c, "speedup": t2c / t2},
            "distance": {"setobs_s": t3, "cvxpy_s": t3c, "speedup": t3c / t3,
                         "distance_diff": dres.distance - d_cvx,
                         "certified_lower_gap": dres.distance - dres.lower},
            "convex_hull_interval_hull": {
                "setobs_s": t4, "cvxpy_s": t4c, "speedup": t4c / t4,
                "max_outward_diff": float(np.concatenate([lo_c - hbox.lo, hbox.hi - hi_c]).max()),
                "min_outward_diff": float(np.concatenate([lo_c - hbox.lo, hbox.hi - hi_c]).min())},
        }
        rows.append(row)
        print(f"(n, n_gen, n_con) = ({n}, {n_g}, {n_c}):")
        for key in ("subset_of_polytope", "intersect_polytope", "distance",
                    "convex_hull_interval_hull"):
            r = row[key]
            print(f"  {key:27s} setobs {1e3 * r['setobs_s']:8.2f} ms  "
                  f"cvxpy {1e3 * r['cvxpy_s']:8.1f} ms  x{r['speedup']:5.1f}")
    result = {
        "benchmark": "geometry_ops",
        "description": " ".join(__doc__.split("\n\n")[1:3]).replace("\n", " "),
        "setobs": setobs.__version__,
        "highspy": metadata.version("highspy"),
        "clarabel": metadata.version("clarabel"),
        "cvxpy": cp.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "cpus": os.cpu_count(),
        "repeats": args.repeats,
        "results": rows,
        "peers": peers,
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps({**stamp(), **result}, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
