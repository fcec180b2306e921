"""Benchmark: the nonlinear modular observer's cost.

* **Design time against order and dimension.** ``design_modular`` on the paper's
  example (``n + q = 2``) at orders 3-19, a Henon-like map with an unknown input
  (``n + q = 3``) at orders 3-9 and a pendulum with an unknown torque (``n + q = 3``)
  at orders 3-9; with the number of monomials in ``(x, w)``, the size the time
  follows (``MAX_SERIES_TERMS`` refuses above 250 by default).
* **Time per step in both realisations.** ``step()`` in the linearizing coordinates
  (a linear update and the readout series) and in the original ones (Newton on eqs.
  (32), (36)), median over a Figure-3 run at orders 5, 9, 13; and the trust measure
  (``consistency``, once per run) per step.

Run: ``python benchmarks/nonlinear_observer.py``; writes
``benchmarks/results/nonlinear_observer.json``.
"""

from __future__ import annotations

import json
import math
import platform
import statistics
import time
import warnings
from pathlib import Path

import sympy as sp

import setobs
from _common import stamp
from setobs.analysis.modular import design_modular
from setobs.examples import modular_example
from setobs.nonlinear import NonlinearSystem
from setobs.observers import NonlinearModularObserver


def systems():
    x1, x2, w = sp.symbols("x1 x2 w")
    henon = NonlinearSystem([x2 - 0.3 * x1**2 + w, 0.4 * x1], [x1], [x1, x2], [w])
    dt = 0.05
    th, om, tau = sp.symbols("theta omega tau")
    pend = NonlinearSystem([th + dt * om, om + dt * (-9.81 * sp.sin(th) - om + tau)], [th],
                           [th, om], [tau], dt=dt)
    return {
        "paper example (n + q = 2)": (modular_example(), (0.4, 1.0, 0.6, 1.0),
                                      (3, 7, 11, 15, 19)),
        "Henon-like map (n + q = 3)": (henon, ([0.3, 0.35], None, [0.5], None), (3, 5, 7, 9)),
        "pendulum (n + q = 3)": (pend, ([0.7, 0.75], None, [0.8], None), (3, 5, 7, 9)),
    }


def design_times() -> list[dict]:
    rows = []
    for name, (sys, (A0, B0, Aw, Bw), orders) in systems().items():
        for order in orders:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                t0 = time.perf_counter()
                design_modular(sys, A0, B0, Aw, Bw, order=order)
                dt = time.perf_counter() - t0
            terms = math.comb(sys.n + sys.q + order, order)
            rows.append({"system": name, "order": order, "monomials": terms, "design_s": dt})
            print(f"  {name:28s} order {order:2d} ({terms:3d} terms): {dt:6.2f} s")
    return rows


def step_times() -> list[dict]:
    ex = modular_example()
    _X, _W, Y = ex.simulate([2.0], [1.0], 60)
    rows = []
    for order in (5, 9, 13):
        d = design_modular(ex, 0.4, 1.0, 0.6, 1.0, order=order)
        row = {"order": order}
        for coords in ("linearizing", "original"):
            obs = NonlinearModularObserver(d, x0=[1.0], coordinates=coords)
            obs.reset()
            ts = []
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                for y in Y:
                    t0 = time.perf_counter()
                    obs.step(y)
                    ts.append(time.perf_counter() - t0)
            row[f"{coords}_step_s"] = statistics.median(ts[1:])
        obs = NonlinearModularObserver(d, x0=[1.0])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            res = obs.run(Y)
        t0 = time.perf_counter()
        obs.consistency(Y, res.x_hat, res.estimate)
        row["consistency_per_step_s"] = (time.perf_counter() - t0) / len(Y)
        rows.append(row)
        print(f"  order {order:2d}: step {1e6 * row['linearizing_step_s']:7.0f} us (linearizing), "
              f"{1e6 * row['original_step_s']:7.0f} us (original); trust measure "
              f"{1e6 * row['consistency_per_step_s']:6.0f} us per step")
    return rows


def main() -> None:
    print("design time:")
    design = design_times()
    print("time per step (paper example, Figure 3 run):")
    steps = step_times()
    out = {
        "benchmark": "nonlinear_observer",
        "description": " ".join(__doc__.split("\n\n")[1:3]).replace("\n", " "),
        "setobs": setobs.__version__,
        "python": platform.python_version(),
        "machine": platform.machine(),
        "design": design,
        "steps": steps,
    }
    path = Path(__file__).parent / "results" / "nonlinear_observer.json"
    path.write_text(json.dumps({**stamp(), **out}, indent=2) + "\n")
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
