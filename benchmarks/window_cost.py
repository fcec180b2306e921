"""Benchmark: where a window step's cost goes, and what it is in the steady state.

Two measurements on plants of ``benchmarks/state_estimation.py`` (its records):

* ``chains``: the window LPs of the last ``SETS`` steps of a run (window 10, box
  restart: one data set of ``2 n`` hull LPs per step) solved three ways from the same
  start: by setobs's compiled simplex from the warm-start state the run had (the
  objective chain, ``setobs.lp.fastlp``; to the optimum, and with the window's early
  stop, ``WINDOW_REL_GAP``), and by HiGHS (no presolve) as a chain on one
  model, the first LP cold and each next one from the previous LP's optimal basis by
  the primal simplex, or by the dual simplex. Simplex iterations per data set (HiGHS's
  ``simplex_iteration_count``; ours: primal and dual pivots and bound flips), and our
  early-stopped chain's time per set and per iteration.
* ``steady``: time per step of window 10 (``restart="auto"`` and ``"box"``) over the
  steps after the first ones (``PLANTS``: the start-up, the first restarts and the first
  probe left out), timed step by step with ``SMFDO.update``, in units of one 45 x 40
  ``scipy.optimize.linprog`` timed around each run (the faster), with the simplex
  iterations per step and the step's time per iteration (everything in the step
  included: an upper bound on one iteration's cost).

Plants: a random 6-state plant, the 30-tank cascade with 21 levels measured (sparse
``A``), a random 30-state plant with 21 outputs (dense ``A``).

Writes ``benchmarks/results/window_cost.json``. Run: ``python benchmarks/window_cost.py``.
"""

from __future__ import annotations

import copy
import json
import platform
import sys
import time
from pathlib import Path

import highspy
import numpy as np
import scipy.sparse as sp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

import setobs as so  # noqa: E402
from _common import linprog_unit, stamp  # noqa: E402
from setobs.lp import fastlp  # noqa: E402
from setobs.setmembership import _closed_form  # noqa: E402
from state_estimation import noise_model, random_system, record, tanks_outputs  # noqa: E402

SETS = 5
#: plant: (system, steps of the steady run, steps left out at its start, steps run
#: before the last SETS data sets are taken for the chains)
PLANTS = {"random_6": (lambda: random_system(6, 4, 3), 120, 40, 120),
          "tanks_30_21": (lambda: tanks_outputs(30, 21), 120, 40, 40),
          "random_30_21": (lambda: random_system(30, 21, 5), 30, 12, 20)}


def setup(name: str, steps: int):
    A, B, C, rw, rv = PLANTS[name][0]()
    n = A.shape[0]
    X, Y, U = record(A, B, C, rw, rv, steps, 0)
    X0 = so.Box(-2.0 * np.ones(n), 2.0 * np.ones(n))
    nkw, _ = noise_model(rw, n)
    kw = dict(measurement_noise=rv, state_bounds=True, initial_state_set=X0, **nkw)
    return so.LinearSystem(A, np.zeros((n, 0)), C, B), kw, X, Y, U


def highs_chain(lp, hB, bred, dual: bool) -> list[int]:
    """HiGHS's iterations for each LP of one data set, as a chain on one model."""
    A = lp.Ared
    m, n = A.shape
    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    h.setOptionValue("presolve", "off")
    model = highspy.HighsLp()
    model.num_col_, model.num_row_ = n, m
    model.col_cost_ = np.zeros(n)
    model.col_lower_, model.col_upper_ = -hB, hB
    model.row_lower_ = model.row_upper_ = bred
    csc = sp.csc_matrix(A)
    model.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    model.a_matrix_.start_, model.a_matrix_.index_ = csc.indptr, csc.indices
    model.a_matrix_.value_ = csc.data
    h.passModel(model)
    its = []
    for t, i in enumerate(lp.order):
        h.changeColsCost(n, np.arange(n, dtype=np.int32), lp.Wred[i])
        if t:
            h.setOptionValue("simplex_strategy", 1 if dual else 4)
        h.run()
        if h.getModelStatus() != highspy.HighsModelStatus.kOptimal:
            raise RuntimeError(f"HiGHS: {h.modelStatusToString(h.getModelStatus())}")
        its.append(int(h.getInfo().simplex_iteration_count))
    return its


def chains(name: str) -> dict:
    sys_, kw, _, Y, U = setup(name, PLANTS[name][3])
    calls = []
    orig = fastlp.FixedStructureLP.minimize_all_unchecked

    def record_call(self, b, h, st, b_scale=0.0, b_err=None, rel_gap=0.0):
        calls.append((self, b.copy(), h.copy(), copy.deepcopy(st), b_scale,
                      None if b_err is None else b_err.copy()))
        return orig(self, b, h, st, b_scale, b_err, rel_gap)

    # the states a measurement row reads alone (a row of C with one nonzero)
    C = np.asarray(sys_.Xi)
    single = np.count_nonzero(C, axis=1) == 1
    measured = np.zeros(C.shape[1], bool)
    measured[np.argmax(C[single] != 0, axis=1)] = True
    fastlp.FixedStructureLP.minimize_all_unchecked = record_call
    try:
        so.SMFDO(sys_, window=10, restart="box", **kw).run(Y, U)
    finally:
        fastlp.FixedStructureLP.minimize_all_unchecked = orig
    big = max(c[0].mr for c in calls)
    sets = [c for c in calls if c[0].mr == big][-SETS:]
    out = []
    for lp, b, h, st, b_scale, b_err in sets:
        st2, st3 = copy.deepcopy(st), copy.deepcopy(st)
        orig(lp, b, h, st2, b_scale, b_err)
        ours = int(st2.iters.sum() - st.iters.sum())
        t0 = time.perf_counter()
        orig(lp, b, h, st3, b_scale, b_err, _closed_form.WINDOW_REL_GAP)
        dt = time.perf_counter() - t0
        ours_early = int(st3.iters.sum() - st.iters.sum())
        hB, bred, ok = lp.reduced_data(b, h, b_scale)
        assert ok
        primal, dual = highs_chain(lp, hB, bred, False), highs_chain(lp, hB, bred, True)
        # where the early-stopped chain's pivots go: the first LP (the dual simplex from
        # its last basis) and each later LP's primal pivots (est[i, 1]: this set's), by
        # whether the LP bounds a measured state or an unmeasured one
        piv = st3.est[lp.order[1:], 1]
        meas = measured[lp.order[1:] // 2] if lp.n_lp == 2 * measured.size else None
        split = {} if meas is None else {
            "primal_pivots_measured_states": float(piv[meas].sum()),
            "lps_measured_states": int(meas.sum()),
            "primal_pivots_unmeasured_states": float(piv[~meas].sum()),
            "lps_unmeasured_states": int((~meas).sum())}
        out.append({"ours": ours, "ours_early_stop": ours_early,
                    "ours_early_stop_ms": 1e3 * dt,
                    "us_per_iteration": 1e6 * dt / max(ours_early, 1),
                    "first_lp_dual_iterations": int(st3.iters[1] - st.iters[1]),
                    **split,
                    "highs_primal_chain": sum(primal),
                    "highs_dual_chain": sum(dual), "highs_first_lp_cold": primal[0]})
    mean = {k: float(np.mean([o[k] for o in out])) for k in out[0]}
    print(f"{name}: LP {big} x {sets[0][0].Ared.shape[1]}, {sets[0][0].n_lp} LPs per set; "
          f"iterations per set {mean}", flush=True)
    return {"plant": name, "lp_rows": int(big), "lp_cols": int(sets[0][0].Ared.shape[1]),
            "lps_per_set": int(sets[0][0].n_lp), "sets": out, "mean": mean}


def steady(name: str, restart: str) -> dict:
    _, steps, warm, _ = PLANTS[name]
    sys_, kw, X, Y, U = setup(name, steps)
    obs = so.SMFDO(sys_, window=10, restart=restart, **kw)
    unit0 = linprog_unit()
    times, its = [], []
    inside = True
    for k in range(steps):
        it0 = sum(obs.simplex_iterations)
        t0 = time.perf_counter()
        est = obs.step(Y[k], None if U is None else U[k])
        dt = time.perf_counter() - t0
        if k >= warm:
            times.append(dt)
            its.append(sum(obs.simplex_iterations) - it0)
        inside &= bool(np.all((X[k] >= est.state_lo) & (X[k] <= est.state_hi)))
    unit = min(unit0, linprog_unit())
    row = {"plant": name, "restart": restart, "steps": f"{warm}-{steps - 1}",
           "ms_per_step": 1e3 * float(np.mean(times)),
           "per_linprog": float(np.mean(times)) / unit, "linprog_ms": 1e3 * unit,
           "iterations_per_step": float(np.mean(its)),
           "us_per_iteration": 1e6 * float(np.sum(times)) / max(float(np.sum(its)), 1.0),
           "truth_inside": inside,
           "stats": dict(obs.stats)}
    print(f"{name} {restart}: {row['ms_per_step']:.2f} ms/step ({row['per_linprog']:.2f} LP), "
          f"{row['iterations_per_step']:.0f} iterations, inside {inside}", flush=True)
    return row


def main() -> None:
    out = {"chains": [chains(p) for p in PLANTS],
           "steady": [steady(p, r) for p in PLANTS for r in ("auto", "box")],
           "machine": platform.platform(), "python": platform.python_version()}
    path = HERE / "results" / "window_cost.json"
    path.write_text(json.dumps({**stamp(), **out}, indent=1))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
