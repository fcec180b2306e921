"""Command-line interface (a thin layer over the public API).

``python -m setobs demo`` runs a short geometry demo (the main job until the
SMFDO lands): the paper's initial disturbance range ``R^q`` becomes bounded
once it is intersected with measurements, and the certified interval hull and
worst-case-optimal centre are printed.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import numpy as np

from . import __version__, examples
from .analysis import diagnose
from .geometry import ConstrainedZonotope

EXAMPLES = {
    "chang2006": examples.chang2006,
    "cgl1": examples.chen_gao_lin_example1,
    "cgl2-20ms": lambda: examples.chen_gao_lin_example2("20ms"),
    "cgl2-1ms": lambda: examples.chen_gao_lin_example2("1ms"),
    "cgl4": examples.chen_gao_lin_example4,
    "cgl5": examples.chen_gao_lin_example5,
}


def demo() -> int:
    """Print a short demonstration of the constrained-zonotope core."""
    np.set_printoptions(precision=4, suppress=True)
    print(f"setobs {__version__} — constrained-zonotope demo\n")
    # State x in a box, disturbance d completely unknown (R^1): the paper's start.
    X0 = ConstrainedZonotope.from_box([-1.0, -1.0], [1.0, 1.0])
    D0 = ConstrainedZonotope.full_space(1)
    Z = X0.cartesian(D0)
    print("Z = [[x0]] x R^q:", Z)
    print("  interval hull:", Z.interval_hull())
    # One step x+ = Phi x + G d, then a measurement y = C x+.
    Phi = np.array([[1.0, 0.1], [0.0, 1.0]])
    G = np.array([[0.0], [0.1]])
    M = np.block([[Phi, G], [np.zeros((1, 2)), np.eye(1)]])
    dd = ConstrainedZonotope.from_box([0, 0, -0.01], [0, 0, 0.01])
    Z1 = M @ Z + dd
    y = np.array([0.3])
    Z1 = Z1.intersect_affine([[0.0, 1.0, 0.0]], y)
    print("\nafter one step and y = C x+ =", y, ":", Z1)
    box = Z1.interval_hull()
    print("  certified interval hull:", box)
    print("  disturbance interval  :", f"[{box.lo[2]:.4f}, {box.hi[2]:.4f}]")
    print("  worst-case-optimal estimate (centre):", f"{box.center[2]:.4f}")
    print("  is_bounded:", Z1.is_bounded, "| empty:", Z1.is_empty())
    red = Z1.rescale().remove_redundancy()
    print("\nrescaled + redundancy removed:", red)
    print("  unbounded factors made bounded:", not red.has_unbounded_factors)
    V = Z1.project([0, 2]).vertices()
    print("  vertices of the (x1, d) projection:\n", V)
    _smfdo_demo()
    return 0


def _smfdo_demo() -> None:
    """SMFDO on the Li-Cong-Dong example (eq. (25)) with a random-walk disturbance."""
    from .setmembership import SMFDO

    sys = examples.chang2006()
    rng = np.random.default_rng(0)
    x, d = np.array([0.0, 1.0, 0.0]), np.zeros(2)
    Y, D = [], []
    for _ in range(100):
        Y.append(sys.Xi @ x)
        D.append(d.copy())
        x = sys.Phi @ x + sys.G @ d
        d = d + rng.uniform(-1, 1, 2)
    print("\nSMFDO on the paper example (eq. (25)), |dd_i| <= 1, 100 steps:")
    for window in (3, 10, None):
        res = SMFDO(sys, window=window).run(np.array(Y))
        err = np.abs(res.estimate[10:] - np.array(D)[10:]).max(axis=1)
        name = "exact" if window is None else f"delta={window}"
        print(f"  {name:>9}: violations {res.violations(np.array(D))}, "
              f"mean worst-case radius {res.radius[10:].mean():.3f}, "
              f"mean actual error {err.mean():.3f}")


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``setobs`` command."""
    parser = argparse.ArgumentParser(prog="setobs", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"setobs {__version__}")
    sub = parser.add_subparsers(dest="command")
    sub.add_parser("demo", help="run a short constrained-zonotope demo")
    pd = sub.add_parser("diagnose", help="which observer designs exist for an example system")
    pd.add_argument("system", choices=[*EXAMPLES, "all"])
    pd.add_argument("--markdown", action="store_true", help="print a Markdown table")
    args = parser.parse_args(argv)
    if args.command == "demo":
        return demo()
    if args.command == "diagnose":
        names = list(EXAMPLES) if args.system == "all" else [args.system]
        for name in names:
            d = diagnose(EXAMPLES[name]())
            print(f"## {name}\n")
            print(d.to_markdown() if args.markdown else repr(d))
            print()
        return 0
    parser.print_help()
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
