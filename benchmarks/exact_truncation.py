"""Study: can exact mode bound its history? How the whole-history LP's bounds depend on
the history older than ``L`` steps, on the 30-tank cascade with 21 outputs.

Exact mode solves the whole-history LP, which grows by a block per step
(``exact_long.py``). Cut at ``s = k - L``, the LP over steps ``s .. k`` with the state
``x_s`` restricted to a set ``S`` gives

* an *outer* bound of the exact set's support when ``S`` contains the exact set ``X_s``
  (here ``S`` = its interval hull, the bounds exact mode computed at step ``s``: what a
  window's box restart carries), and
* an *inner* bound when every point of ``S`` has a history consistent with the data up
  to ``s`` (here ``S`` = the convex hull of the states ``x_s`` of the optimal histories
  of the whole-history LPs of steps ``s .. k - 1``: ``60 L`` points, each a state of a
  history that satisfies every constraint; an algorithm would take them from its own
  inner LPs, which are feasible histories by induction).

If the two agree to a tolerance, the cut LP's outer bound is the exact support to that
tolerance, certified: the exact value lies between them. Per ``L``: the outer bound's
excess over the exact one and the inner bound's deficit, as fractions of the exact width
(largest and mean over the 60 bounds), and HiGHS's simplex iterations for the cut LP's
60 bounds as a chain on one model (the first cold; HiGHS's scaling off, as in
``setobs.lp.boxlp``). The exact bounds: the whole-history LP from ``x_0`` in the initial
box, one fresh model per bound where the chain's warm start fails.

Writes ``benchmarks/results/exact_truncation.json``. Run:
``python benchmarks/exact_truncation.py [--k 120] [--lengths 5,10,20,30,40,60]
[--inner 10,20,30]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import highspy
import numpy as np
import scipy.sparse as sp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _common import stamp  # noqa: E402
from state_estimation import record, tanks_outputs  # noqa: E402

TOL = 1e-10


def history_lp(A, B, C, rw, rv, U, Y, s, k, lo_s, hi_s):
    """The LP over steps ``s .. k`` (every state a variable, ``x_s`` in ``[lo_s, hi_s]``):
    ``(M, rhs, lo, hi, first)``, ``first`` the column of ``x_k``'s first entry."""
    n, l = A.shape[0], C.shape[0]
    T = k - s
    nx, nw, nv = (T + 1) * n, T * n, (T + 1) * l
    As, Cs = sp.coo_array(A), sp.coo_array(C)
    R, Cc, V, rhs = [], [], [], []
    r = 0
    for j in range(T):  # x_(j+1) - A x_j - w_j = B u_j
        R += [r + np.arange(n), r + np.arange(n), r + As.row]
        Cc += [(j + 1) * n + np.arange(n), nx + j * n + np.arange(n), j * n + As.col]
        V += [np.ones(n), -np.ones(n), -As.data]
        rhs.append(B @ U[s + j])
        r += n
    for j in range(T + 1):  # C x_j + v_j = y_j
        R += [r + Cs.row, r + np.arange(l)]
        Cc += [j * n + Cs.col, nx + nw + j * l + np.arange(l)]
        V += [Cs.data, np.ones(l)]
        rhs.append(Y[s + j])
        r += l
    M = sp.csc_array((np.concatenate(V), (np.concatenate(R), np.concatenate(Cc))),
                     shape=(r, nx + nw + nv))
    lo = np.r_[np.full(nx, -np.inf), np.full(nw, -rw), np.full(nv, -rv)]
    hi = -lo
    lo[:n], hi[:n] = lo_s, hi_s
    return M, np.concatenate(rhs), lo, hi, T * n


def model(M, rhs, lo, hi):
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("presolve", "off")
    h.setOptionValue("simplex_scale_strategy", 0)
    h.setOptionValue("primal_feasibility_tolerance", TOL)
    h.setOptionValue("dual_feasibility_tolerance", TOL)
    lp = highspy.HighsLp()
    lp.num_col_, lp.num_row_ = M.shape[1], M.shape[0]
    lp.col_cost_, lp.col_lower_, lp.col_upper_ = np.zeros(M.shape[1]), lo, hi
    lp.row_lower_ = lp.row_upper_ = rhs
    lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_ = M.indptr, M.indices, M.data
    lp.a_matrix_.num_col_, lp.a_matrix_.num_row_ = M.shape[1], M.shape[0]
    h.passModel(lp)
    return h


def bounds(M, rhs, lo, hi, first, n):
    """``(lo_k, hi_k, iterations, histories)``: the 60 bounds as a chain (min x_1 .. min
    x_n, max x_n .. max x_1), a fresh model cold where a warm solve is not optimal within
    10 s; ``histories[(i, sign)]`` the optimal point."""
    h = model(M, rhs, lo, hi)
    lo_k, hi_k, its, sols = np.empty(n), np.empty(n), 0, {}
    order = [(i, 1.0) for i in range(n)] + [(i, -1.0) for i in reversed(range(n))]
    prev = None
    for i, sg in order:
        if prev is not None:
            h.changeColCost(prev, 0.0)
        h.changeColCost(first + i, sg)
        prev = first + i
        h.setOptionValue("time_limit", h.getRunTime() + 10.0)
        h.run()
        its += h.getInfo().simplex_iteration_count
        if h.getModelStatus() != highspy.HighsModelStatus.kOptimal:
            h = model(M, rhs, lo, hi)
            h.changeColCost(first + i, sg)
            h.run()
            its += h.getInfo().simplex_iteration_count
            if h.getModelStatus() != highspy.HighsModelStatus.kOptimal:
                raise RuntimeError(h.modelStatusToString(h.getModelStatus()))
        v = sg * h.getInfo().objective_function_value
        (lo_k if sg > 0 else hi_k)[i] = v
        sols[(i, sg)] = np.asarray(h.getSolution().col_value)
    return lo_k, hi_k, its, sols


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--k", type=int, default=120)
    ap.add_argument("--lengths", default="5,10,20,30,40,60")
    ap.add_argument("--inner", default="10,20,30")
    ap.add_argument("--out", default=str(HERE / "results" / "exact_truncation.json"))
    args = ap.parse_args()
    k = args.k
    lengths = [int(v) for v in args.lengths.split(",")]
    inner = {int(v) for v in args.inner.split(",") if v}
    A, B, C, rw, rv = tanks_outputs(30, 21)
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, k + 1, 0)
    box = (-2.0 * np.ones(n), 2.0 * np.ones(n))
    cache: dict[int, tuple] = {}

    def exact(t):
        if t not in cache:
            M, rhs, lo, hi, first = history_lp(A, B, C, rw, rv, U, Y, 0, t, *box)
            t0 = time.perf_counter()
            lo_t, hi_t, its, sols = bounds(M, rhs, lo, hi, first, n)
            xs = [p[:(t + 1) * n].reshape(t + 1, n) for p in sols.values()]
            cache[t] = (lo_t, hi_t, its, xs)
            print(f"  exact k={t}: {its} iterations, {time.perf_counter() - t0:.1f} s",
                  file=sys.stderr, flush=True)
        return cache[t]

    lo, hi, its_k, _ = exact(k)
    width = hi - lo
    assert np.all((X[k] >= lo - 1e-9) & (X[k] <= hi + 1e-9))
    rows = []
    for L in lengths:
        s = k - L
        lo_s, hi_s = exact(s)[:2]
        M, rhs, lo_c, hi_c, first = history_lp(A, B, C, rw, rv, U, Y, s, k, lo_s, hi_s)
        lo_o, hi_o, its_o, _ = bounds(M, rhs, lo_c, hi_c, first, n)
        excess = np.maximum(lo - lo_o, hi_o - hi) / width
        row = {"L": L, "lp_size": list(M.shape), "outer_iterations": its_o,
               "outer_excess_max": float(excess.max()), "outer_excess_mean": float(excess.mean()),
               "outer_narrower": bool(np.any(excess < -1e-9))}
        if L in inner:
            P = np.array([x[s] for t in range(s, k) for x in exact(t)[3]]).T
            npt = P.shape[1]
            # x_s = P lam, sum lam = 1, lam >= 0; x_s free
            top = sp.hstack([sp.eye_array(n), sp.csc_array((n, M.shape[1] - n))])
            Mi = sp.csc_array(sp.block_array([[M, None], [top, -sp.csc_array(P)],
                                              [None, sp.csc_array(np.ones((1, npt)))]]))
            rhs_i = np.r_[rhs, np.zeros(n), 1.0]
            lo_i = np.r_[lo_c, np.zeros(npt)]
            hi_i = np.r_[hi_c, np.full(npt, np.inf)]
            lo_i[:n], hi_i[:n] = -np.inf, np.inf
            lo_n, hi_n, its_i, _ = bounds(Mi, rhs_i, lo_i, hi_i, first, n)
            deficit = np.maximum(lo_n - lo, hi - hi_n) / width
            gap = np.maximum(lo_n - lo_o, hi_o - hi_n) / width
            row.update({"inner_points": npt, "inner_iterations": its_i,
                        "inner_deficit_max": float(deficit.max()),
                        "certified_gap_max": float(gap.max()),
                        "certified_gap_mean": float(gap.mean())})
        rows.append(row)
        print(json.dumps(row), file=sys.stderr, flush=True)
    out = {"system": "tanks_30_21", "k": k, "exact_lp_size": list(
        history_lp(A, B, C, rw, rv, U, Y, 0, k, *box)[0].shape),
        "exact_iterations_cold_chain": its_k, "mean_exact_width": float(width.mean()),
        "rows": rows}
    Path(args.out).write_text(json.dumps({**stamp(), **out}, indent=1))
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
