"""Command line: a thin layer over the public API.

``setobs demo`` (the main job), ``setobs check FILE`` (which observers exist for
a system), ``setobs study CONFIG`` (a Monte Carlo campaign). Bad input prints one
line on stderr and exits with code 2.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from . import __version__
from .analysis import diagnose
from .exceptions import SetobsError
from .systems import LinearSystem

EXIT_BAD_INPUT = 2
_ALIASES = {"Phi": ("Phi", "A", "A0"), "G": ("G", "E", "E0", "F"), "Xi": ("Xi", "C", "C0"),
            "Gamma": ("Gamma", "B", "B0")}


class CLIError(Exception):
    """Bad input on the command line (one line for stderr)."""


# ---------------------------------------------------------------------------- demo
def demo(out: str | Path = "setobs_demo.png", steps: int = 120, seed: int = 0) -> int:
    """The main job: the set-membership paper's example, SMFDO against the PIO baseline.

    Prints a short table and writes a PNG like Li-Cong-Dong Fig. 1(a) (truth,
    estimate and certified interval band per disturbance component).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .compare import compare
    from .observers import PIO, HigherOrderObserver
    from .plotting import plot_estimate_band
    from .setmembership import SMFDO
    from .studies import Scenario, rng_for_run

    np.set_printoptions(precision=4, suppress=True)
    sc = Scenario(system="chang2006", horizon=steps, increment=1.0, x0_box=1.0)
    sys_ = sc.build_system()
    traj = sc.simulate(rng_for_run(seed, 0))
    kw = {"increment_set": sc.increment_set(2), "initial_state_set": sc.initial_state_set(3)}
    print(f"setobs {__version__} — Li-Cong-Dong example (eq. (25)), |dd_i| <= 1, "
          f"{steps} steps, seed {seed}\n")
    print(repr(diagnose(sys_)).split("\n")[1])
    res = {w: SMFDO(sys_, window=w, **kw).run(traj.Y) for w in (3, 10, None)}
    exact = res[None]
    est = {f"SMFDO delta={w}": r.estimate for w, r in res.items() if w is not None}
    est["SMFDO exact"] = exact.estimate
    est["PIO (designed, Fu-Wang poles)"] = PIO(sys_).run(traj.Y).d_hat
    est["PIO (printed gains, baseline)"] = PIO.chang2006_baseline(sys_).run(traj.Y).d_hat
    est["higher-order observer"] = HigherOrderObserver(sys_).run(traj.Y).d_hat
    table = compare(est, exact)
    print("\nworst-case error over the consistent set (mean over k >= 10) and actual error:\n")
    print(f"{'estimator':<32} {'worst-case':>12} {'/ optimal':>10} {'actual':>12}  violations")
    for s in table.summary(start=10):
        name = s["observer"]
        e = est[name]
        actual = np.nanmean(np.abs(e[10:] - traj.D[10:]).max(axis=1))
        viol = ""
        for w, r in res.items():
            label = "SMFDO exact" if w is None else f"SMFDO delta={w}"
            if name == label:
                viol = str(r.violations(traj.D))
        print(f"{name:<32} {s['mean_error']:>12.4g} {s['mean_ratio']:>10.3g} {actual:>12.4g}"
              f"  {viol}")
    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for i, ax in enumerate(axes):
        plot_estimate_band(res[10], traj.D, component=i, ax=ax, label="SMFDO (delta=10)")
    axes[0].set_title("SMFDO on the Li-Cong-Dong example: truth, estimate, certified interval")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"\nwrote {out}")
    return 0


# ---------------------------------------------------------------------------- check
def _pick(data: dict[str, Any], key: str, required: bool = True):
    for name in _ALIASES[key]:
        if name in data:
            try:
                M = np.asarray(data[name], dtype=float)
            except (TypeError, ValueError):
                raise CLIError(f"matrix {name!r} must be a numeric matrix (a list of rows of "
                               f"numbers), got {str(data[name])[:60]!r}") from None
            if M.ndim > 2:
                raise CLIError(f"matrix {name!r} must be 2-D, got {M.ndim} dimensions")
            return M
    if required:
        raise CLIError(f"missing matrix {key!r} (accepted names: {', '.join(_ALIASES[key])})")
    return None


def load_system(path: str | Path) -> LinearSystem:
    """A :class:`LinearSystem` from ``.json``, ``.yaml``/``.yml``, ``.npz`` or ``.mat``.

    The file holds matrices named ``Phi``, ``G``, ``Xi`` (aliases ``A``/``E``/``C``)
    and optionally ``Gamma`` (alias ``B``).
    """
    p = Path(path)
    if not p.exists():
        raise CLIError(f"no such file: {p}")
    suffix = p.suffix.lower()
    try:
        if suffix == ".json":
            data = json.loads(p.read_text())
        elif suffix in (".yaml", ".yml"):
            import yaml

            data = yaml.safe_load(p.read_text())
        elif suffix == ".npz":
            with np.load(p) as z:
                data = {k: z[k] for k in z.files}
        elif suffix == ".mat":
            from scipy.io import loadmat

            data = {k: v for k, v in loadmat(p).items() if not k.startswith("__")}
        else:
            raise CLIError(f"unsupported file type {suffix!r} (use .json, .yaml, .npz or .mat)")
    except CLIError:
        raise
    except Exception as exc:  # parse errors of any reader
        raise CLIError(f"could not read {p}: {exc}") from None
    if not isinstance(data, dict):
        raise CLIError(f"{p} must contain a mapping of matrices")
    Gamma = _pick(data, "Gamma", required=False)
    return LinearSystem(_pick(data, "Phi"), _pick(data, "G"), _pick(data, "Xi"),
                        Gamma if Gamma is not None and Gamma.size else None)


def _jsonable(v: Any) -> Any:
    if isinstance(v, np.ndarray):
        return _jsonable(v.tolist())
    if isinstance(v, list | tuple):
        return [_jsonable(x) for x in v]
    if isinstance(v, complex):
        return [v.real, v.imag] if v.imag else v.real
    if isinstance(v, np.generic):
        return v.item()
    return v


def check(target: str, fmt: str = "text") -> int:
    """Print the ``diagnose`` report for a system file, an example name, or ``all`` examples."""
    from .studies import EXAMPLE_SYSTEMS

    if target == "all" or (target in EXAMPLE_SYSTEMS and not Path(target).exists()):
        for name in EXAMPLE_SYSTEMS if target == "all" else [target]:
            if target == "all":
                print(f"## {name}\n")
            _print_report(diagnose(EXAMPLE_SYSTEMS[name]()), fmt)
            if target == "all":
                print()
        return 0
    _print_report(diagnose(load_system(target)), fmt)
    return 0


def _print_report(d, fmt: str) -> None:
    if fmt == "markdown":
        print(d.to_markdown())
    elif fmt == "json":
        out = {"zeros": _jsonable([complex(z) for z in d.zeros.zeros]),
               "designs": [{"design": v.design, "exists": v.exists, "condition": v.condition,
                            "reason": v.reason, "numbers": _jsonable(v.numbers)}
                           for v in d.verdicts],
               "notes": d.notes}
        print(json.dumps(out, indent=2))
    else:
        print(repr(d))


# ---------------------------------------------------------------------------- study
def study(config: str, dask: str | None = None, out: str | None = None,
          processes: int | None = None) -> int:
    """Run a campaign from a YAML configuration (see the README)."""
    import yaml

    from .studies import ObserverSpec, Scenario, run_campaign

    p = Path(config)
    if not p.exists():
        raise CLIError(f"no such file: {p}")
    try:
        cfg = yaml.safe_load(p.read_text()) or {}
    except yaml.YAMLError as exc:
        raise CLIError(f"could not parse {p}: {exc}") from None
    if not isinstance(cfg, dict):
        raise CLIError(f"{p} must contain a mapping")
    unknown = set(cfg) - {"scenario", "observers", "runs", "seed", "reference_window", "out"}
    if unknown:
        raise CLIError(f"unknown keys in {p}: {sorted(unknown)}")
    try:
        scenario = Scenario(**(cfg.get("scenario") or {}))
        specs = [ObserverSpec(o["name"], o["kind"], o.get("params") or {})
                 for o in cfg.get("observers") or []]
    except (TypeError, KeyError) as exc:
        raise CLIError(f"bad configuration in {p}: {exc}") from None
    runs, seed = cfg.get("runs", 10), cfg.get("seed", 0)
    for key, val in (("runs", runs), ("seed", seed)):
        if isinstance(val, bool) or not isinstance(val, int):
            raise CLIError(f"{key} must be an integer, got {val!r}")
    ref_window = cfg.get("reference_window", 20)
    if ref_window is not None:
        from .setmembership.smfdo import _check_window

        try:
            _check_window(ref_window)
        except (TypeError, ValueError) as exc:
            raise CLIError(f"reference_window: {exc}") from None
    out_dir = Path(out or cfg.get("out") or p.with_suffix("").name + "_results")
    res = run_campaign(scenario, specs, runs, base_seed=seed, reference_window=ref_window,
                       client=dask, processes=processes, out_dir=out_dir)
    print(res.summary().to_string(float_format=lambda x: f"{x:.4g}"))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .plotting import plot_comparison_bars, plot_error_curves

    fig, axes = plt.subplots(1, 2, figsize=(10, 3.5))
    plot_error_curves(res.table, "err_inf", ax=axes[0])
    plot_comparison_bars(res.table, "worst_inf", ax=axes[1])
    fig.tight_layout()
    fig.savefig(out_dir / "summary.png", dpi=110)
    plt.close(fig)
    print(f"wrote {out_dir / 'results.csv'}, {out_dir / 'metadata.json'}, "
          f"{out_dir / 'summary.png'}")
    return 0


# ---------------------------------------------------------------------------- main
def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``setobs`` command."""
    parser = argparse.ArgumentParser(prog="setobs", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"setobs {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    pd_ = sub.add_parser("demo", help="SMFDO vs PIO on the set-membership paper's example")
    pd_.add_argument("--out", default="setobs_demo.png", help="PNG to write")
    pd_.add_argument("--steps", type=int, default=120)
    pd_.add_argument("--seed", type=int, default=0)
    pc = sub.add_parser("check", help="which observer designs exist for a system")
    pc.add_argument("file", help=".json, .yaml, .npz or .mat with Phi, G, Xi (, Gamma); "
                                 "or an example name (chang2006, cgl1, ...), or 'all'")
    pc.add_argument("--format", choices=["text", "markdown", "json"], default="text")
    ps = sub.add_parser("study", help="run a Monte Carlo campaign from a YAML file")
    ps.add_argument("config")
    ps.add_argument("--dask", metavar="ADDRESS", help="Dask scheduler address")
    ps.add_argument("--out", help="output directory")
    ps.add_argument("--processes", type=int, help="local worker processes")
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_usage(sys.stderr)
        print("setobs: error: a command is required (demo, check or study; see --help)",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        if args.command == "demo":
            return demo(args.out, args.steps, args.seed)
        if args.command == "check":
            return check(args.file, args.format)
        return study(args.config, args.dask, args.out, args.processes)
    except BrokenPipeError:
        # the reader went away (setobs check all | head -1): not an error of ours
        _silence_stdout()
        return 0
    except (CLIError, SetobsError, ValueError, TypeError, OSError) as exc:
        print(f"setobs: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT


def _silence_stdout() -> None:
    """Point stdout at devnull so the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # pragma: no cover - stdout without a descriptor
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
