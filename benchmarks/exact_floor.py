"""What holds exact mode's step cost on a 30-state plant: HiGHS's fixed cost per solve, its
cost per simplex iteration, and the work outside the solver, measured in the steady state
of the bounded history (``setobs.setmembership._bounded``), with the floor each part sets
in linprog units against the target of 30 per step.

Per step of the steady state (after ``--warm`` steps): the HiGHS solves (``highs.solve``:
``run()`` and its status), their iterations and seconds, the solves that made no
iteration (a start already optimal for the next objective: their time is HiGHS's fixed
cost), and a least-squares fit ``seconds = a + b * iterations`` over the step's solves
(its intercept ``a`` is ill-determined where no solve is without iterations, as on the
dense plant: the direct measurement below is the better figure there). At the end, on
each HiGHS model the last step solved on (the outer and the inner cut LP): its
size, the time of ``run()`` again from its optimal basis (no iteration: the fixed cost
measured directly, the best of five), and the structure of its optimal basis after
triangularisation (column and row singletons removed until none is left), the part a
sparse LU would factor (its nonzeros) where the compiled simplex's dense explicit
inverse of the whole basis (``m x m``, one per LP of a chain) does not fit; and what a
sparse LU of that basis costs (``_sparselu.py``, a probe not used by setobs): its
factorisation's time and fill against SuperLU's, and the solve ``B^-1 a_q`` of a simplex
iteration for random nonbasic columns (hyper-sparse, timed as one compiled batch, and with
a dense right-hand side, one call at a time from Python), with the results' density and
the residuals against the basis itself.

Run: ``python benchmarks/exact_floor.py [--plants fast,dense] [--warm 40,8] [--steps 10,3]``
(the dense plant's steps cost ~100x the cascade's: fewer of them);
writes ``benchmarks/results/exact_floor.json``.
"""

from __future__ import annotations

import argparse
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
from _common import count_solves, linprog_unit, stamp  # noqa: E402
from _sparselu import (  # noqa: E402
    ftran_columns,
    lu_factor,
    lu_solve,
    lu_solve_sparse,
    lu_solve_transposed,
    triangular_order,
)
from exact_bounded import plant  # noqa: E402
from setobs.lp import highs  # noqa: E402
from setobs.setmembership import _bounded  # noqa: E402


def model_facts(hs) -> dict:
    """A solved HiGHS model's size, its fixed cost per ``run()`` (measured: again from its
    optimal basis, no iteration), its optimal basis's nucleus and the LU probe on it."""
    import highspy

    lp = hs.getLp()
    m, n = lp.num_row_, lp.num_col_
    M = sp.csc_matrix((np.asarray(lp.a_matrix_.value_), np.asarray(lp.a_matrix_.index_),
                       np.asarray(lp.a_matrix_.start_)), shape=(m, n))
    runs = []
    for _ in range(5):
        t0 = time.perf_counter()
        st = highs.solve(hs, primal=True)
        runs.append((time.perf_counter() - t0, int(hs.getInfo().simplex_iteration_count), st))
    zero = [t for t, it, st in runs if it == 0 and st == "optimal"]
    bas = hs.getBasis()
    basic = int(highspy.HighsBasisStatus.kBasic)
    bc = np.flatnonzero(np.array([int(s) for s in bas.col_status]) == basic)
    br = np.flatnonzero(np.array([int(s) for s in bas.row_status]) == basic)
    full = sp.hstack([M, sp.eye(m, format="csc")]).tocsc()  # (a slack column per row)
    cols = np.concatenate([bc, n + br]).astype(np.int64)
    B = full[:, cols].tocsc()
    facts = {"rows": m, "cols": n, "nonzeros": int(M.nnz),
             "rerun_ms_no_iteration": 1e3 * min(zero) if zero else None,
             "basis_nonzeros": int(B.nnz), "dense_inverse_MB": 8.0 * m * m / 1e6}
    if cols.size == m:
        # the nucleus: what is left after the column and row singletons (the probe's
        # triangular order; -1 marks its columns, the rest pivot on their own rows)
        q, prefer, size = triangular_order(m, full.indptr.astype(np.int64),
                                           full.indices.astype(np.int64), cols)
        rows = np.setdiff1d(np.arange(m), prefer[prefer >= 0])
        facts.update(nucleus_size=int(size),
                     nucleus_nonzeros=int(B[rows][:, q[prefer < 0]].nnz),
                     sparse_lu_probe=lu_probe(full, cols, B))
    return facts


def lu_probe(full: sp.csc_matrix, cols: np.ndarray, B: sp.csc_matrix,
             threshold: float = 0.1, columns: int = 200) -> dict:
    """What a sparse LU of this basis costs (``_sparselu``: triangularisation, then
    Gilbert-Peierls with threshold ``threshold``): the factorisation's time (best of five)
    and fill against SuperLU's (``scipy.sparse.linalg.splu``, COLAMD), and the solve
    ``B^-1 a_q`` for ``columns`` random nonbasic columns by the hyper-sparse solve (in one
    compiled batch) and with a dense right-hand side, with the results' density and the
    largest residual ``|B x - a_q|`` against the matrix itself."""
    import scipy.sparse.linalg as spla

    m = full.shape[0]
    ip, ix, dx = full.indptr.astype(np.int64), full.indices.astype(np.int64), full.data
    times = []
    for _ in range(5):
        t0 = time.perf_counter()
        ok, *f = lu_factor(m, ip, ix, dx, cols, threshold)
        times.append(time.perf_counter() - t0)
    if not ok:
        return {"singular": True}
    t0 = time.perf_counter()
    slu = spla.splu(B)
    t_slu = time.perf_counter() - t0
    rng = np.random.default_rng(0)
    qs = rng.choice(np.setdiff1d(np.arange(full.shape[1]), cols), columns).astype(np.int64)
    ftran_columns(*f[:7], ip, ix, dx, qs[:2])  # (compiled before it is timed)
    t0 = time.perf_counter()
    total = ftran_columns(*f[:7], ip, ix, dx, qs)
    t_sparse = (time.perf_counter() - t0) / columns
    worst = 0.0
    x = np.zeros(m)
    xi, ps, mark = np.empty(m, np.int64), np.empty(m, np.int64), np.zeros(m, np.int64)
    out = np.empty(m)
    t_dense = []
    for t, c in enumerate(qs[:20]):
        a = full[:, [c]].toarray().ravel()
        top = lu_solve_sparse(*f[:7], ix[ip[c]:ip[c + 1]], dx[ip[c]:ip[c + 1]], x, xi, ps,
                              mark, 2 * t + 1, np.arange(m))
        z = np.zeros(m)
        z[xi[top:]] = x[xi[top:]]
        x[xi[top:]] = 0.0
        out[f[7]] = z  # (B^-1 a = Q z)
        worst = max(worst, float(np.abs(B @ out - a).max()))
        t0 = time.perf_counter()
        lu_solve(*f, a, out)
        t_dense.append(time.perf_counter() - t0)
        worst = max(worst, float(np.abs(B @ out - a).max()))
        lu_solve_transposed(*f, a, out)
        worst = max(worst, float(np.abs(B.T @ out - a).max()))
    return {"threshold": threshold, "factor_ms": 1e3 * min(times),
            "factor_nonzeros": int(f[0][-1] + f[3][-1]),
            "superlu_ms": 1e3 * t_slu, "superlu_nonzeros": int(slu.L.nnz + slu.U.nnz),
            "sparse_solve_us": 1e6 * t_sparse, "result_density": total / columns / m,
            "dense_solve_us": 1e6 * float(np.median(t_dense)),
            "largest_residual": worst}


def run(name: str, warm: int, steps: int) -> dict:
    N = warm + steps
    A, B, C, rw, rv, R0, _, Y, U = plant(name, N)
    n = A.shape[0]
    X0 = so.Box(-R0 * np.ones(n), R0 * np.ones(n))
    obs = so.SMFDO(so.LinearSystem(A, np.zeros((n, 0)), C, B), window=None,
                   measurement_noise=rv, state_bounds=True, initial_state_set=X0,
                   process_noise=rw)
    for k in range(warm):
        obs.step(Y[k], U[k])
    solves: list[tuple[int, float]] = []
    plain = count_solves(solves)
    counted = highs.solve
    last: list = []  # (the models of the step's solves)

    def seen(hs, **kw):
        last.append(hs)
        return counted(hs, **kw)

    highs.solve = seen
    unit = linprog_unit()
    rows = []
    try:
        for k in range(warm, N):
            solves.clear()
            last.clear()
            t0 = time.perf_counter()
            est = obs.step(Y[k], U[k])
            dt = time.perf_counter() - t0
            s = np.array(solves, dtype=float).reshape(-1, 2)
            it, sec = s[:, 0], s[:, 1]
            zero = it == 0
            a, b = np.linalg.lstsq(np.column_stack([np.ones_like(it), it]), sec, rcond=None)[0]
            rows.append({"k": k, "ms": 1e3 * dt, "status": est.status,
                         "history": obs.history_length, "solves": int(it.size),
                         "iterations": int(it.sum()), "solve_ms": 1e3 * float(sec.sum()),
                         "no_iteration_solves": int(zero.sum()),
                         "no_iteration_ms": 1e3 * float(sec[zero].sum()),
                         "fit_ms_per_solve": 1e3 * float(a),
                         "fit_us_per_iteration": 1e6 * float(b)})
            print(f"{name} k={k} {1e3 * dt:.0f} ms solves {it.size} it {int(it.sum())} "
                  f"L {obs.history_length} {est.status}", file=sys.stderr, flush=True)
            unit = min(unit, linprog_unit())
    finally:
        highs.solve = plain
    # the models the last step solved on (the outer and the inner cut LP, or the whole
    # history's), in the order of their first solve in it
    # (one flat row per model, for the performance page's table)
    models = []
    for i, hs in enumerate(dict.fromkeys(last)):
        facts = model_facts(hs)
        probe = facts.pop("sparse_lu_probe", {})
        models.append({"plant": name, "model": i,
                       "solves_in_last_step": sum(1 for h in last if h is hs), **facts,
                       **{f"lu_{key}": val for key, val in probe.items()}})

    def mean(key):
        return float(np.mean([r[key] for r in rows]))

    ms, solve_ms = mean("ms"), mean("solve_ms")
    per_solve, per_it = mean("fit_ms_per_solve"), mean("fit_us_per_iteration")
    u = 1e3 * unit
    return {"plant": name, "warm_steps": warm, "steps": steps, "linprog_ms": u,
            "mean_ms": ms, "mean_per_linprog": ms / u,
            "mean_solves": mean("solves"), "mean_iterations": mean("iterations"),
            "mean_no_iteration_solves": mean("no_iteration_solves"),
            "floor_per_linprog": {
                "fixed_cost_of_solves": mean("solves") * per_solve / u,
                "iterations": mean("iterations") * per_it / 1e3 / u,
                "outside_the_solver": (ms - solve_ms) / u},
            "fit_ms_per_solve": per_solve, "fit_us_per_iteration": per_it,
            "models": models, "per_step": rows}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--plants", default="fast,dense")
    ap.add_argument("--warm", default="40,8", help="steps before the measured ones, per plant")
    ap.add_argument("--steps", default="10,3", help="measured steps, per plant")
    ap.add_argument("--out", default=str(HERE / "results" / "exact_floor.json"))
    args = ap.parse_args()
    _bounded.BOUNDED = True
    out = {**stamp(), "target_mean_per_linprog": 30.0, "plants": []}
    warms = [int(v) for v in args.warm.split(",")]
    counts = [int(v) for v in args.steps.split(",")]
    out["bases"] = []
    for name, warm, steps in zip(args.plants.split(","), warms, counts, strict=True):
        row = run(name, warm, steps)
        out["bases"] += row.pop("models")
        out["plants"].append(row)
        Path(args.out).write_text(json.dumps(out, indent=1))
    print(json.dumps([{k: v for k, v in p.items() if k != "per_step"} for p in out["plants"]]
                     + out["bases"], indent=1))


if __name__ == "__main__":
    main()
