"""The README's comparison table: point observers against the SMFDO optimum.

Li-Cong-Dong example, |dd_i| <= 1, 100 steps, seed 0 (the README snippet).
Writes ``benchmarks/results/observer_comparison.md``.

Run: ``python benchmarks/observer_comparison.py``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import setobs as so
from _common import stamp


def main() -> None:
    sys = so.examples.chang2006()
    dd = np.random.default_rng(0).uniform(-1, 1, size=(99, 2))  # the README's data
    D = np.vstack([np.zeros(2), np.cumsum(dd, axis=0)])
    Y, _ = sys.simulate(D, x0=[0.0, 1.0, 0.0])
    ref = so.SMFDO(sys, window=None).run(Y)
    est = {"PIO": so.observers.PIO(sys).run(Y).estimate,
           "PIO (printed gains)": so.observers.PIO.chang2006_baseline(sys).run(Y).estimate,
           "higher-order": so.observers.HigherOrderObserver(sys).run(Y).estimate}
    md = so.compare.compare(est, ref).to_markdown(start=10)
    print(md)
    out = Path(__file__).parent / "results" / "observer_comparison.md"
    st = stamp()
    out.write_text(f"<!-- commit {st['commit']}, {st['date']} -->\n" + md + "\n")
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
