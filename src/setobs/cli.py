"""Command line: a thin layer over the public API.

``setobs demo`` (the main job), ``setobs check FILE`` (which observers exist for
a system), ``setobs estimate RECORD --model FILE`` (certified disturbance bounds
from a measured record), ``setobs study CONFIG`` (a Monte Carlo campaign). Bad
input prints one line on stderr and exits with code 2.
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
from ._lazy import optional_import
from .analysis import diagnose
from .exceptions import SetobsError

EXIT_BAD_INPUT = 2


class CLIError(SetobsError):
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
    # the paper's Algorithm 1 as printed: windows restart from the box (eq. (24))
    res = {w: SMFDO(sys_, window=w, restart="box", **kw).run(traj.Y) for w in (3, 10, None)}
    exact = res[None]
    est = {f"SMFDO window={w}": r.estimate for w, r in res.items() if w is not None}
    est["SMFDO exact"] = exact.estimate
    est["PIO (designed, Fu-Wang poles)"] = PIO(sys_).run(traj.Y).estimate
    est["PIO (printed gains, baseline)"] = PIO.chang2006_baseline(sys_).run(traj.Y).estimate
    est["higher-order observer"] = HigherOrderObserver(sys_).run(traj.Y).estimate
    table = compare(est, exact)
    print("\nworst-case error over the consistent set (mean over k >= 10) and actual error:\n")
    print(f"{'estimator':<32} {'worst-case':>12} {'/ optimal':>10} {'actual':>12}  violations")
    for name, s in table.summary(start=10).iterrows():
        e = est[name]
        actual = np.nanmean(np.abs(e[10:] - traj.D[10:]).max(axis=1))
        viol = ""
        for w, r in res.items():
            label = "SMFDO exact" if w is None else f"SMFDO window={w}"
            if name == label:
                viol = str(r.violations(traj.D))
        print(f"{name:<32} {s['worst_case_error']:>12.4g} {s['ratio']:>10.3g} {actual:>12.4g}"
              f"  {viol}")
    fig, axes = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    for i, ax in enumerate(axes):
        plot_estimate_band(res[10], traj.D, component=i, ax=ax, label="SMFDO (window=10)")
    axes[0].set_title("SMFDO on the Li-Cong-Dong example: truth, estimate, certified interval")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    print(f"\nwrote {out}")
    return 0


# ---------------------------------------------------------------------------- check
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


def check(target: str, fmt: str = "text", dt: float | None = None) -> int:
    """Print the ``diagnose`` report for a system file, an example name, or ``all`` examples.

    ``dt`` is the sampling time for a continuous-time model file without ``Ts``.
    """
    from .studies import EXAMPLE_SYSTEMS

    if target == "all" or (target in EXAMPLE_SYSTEMS and not Path(target).exists()):
        for name in EXAMPLE_SYSTEMS if target == "all" else [target]:
            if target == "all":
                print(f"## {name}\n")
            _print_report(diagnose(EXAMPLE_SYSTEMS[name]()), fmt)
            if target == "all":
                print()
        return 0
    from .io import load_model

    _print_report(diagnose(load_model(target, dt=dt)), fmt)
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


# ---------------------------------------------------------------------------- estimate
def _numbers(name: str, text: str | None) -> list[float] | None:
    if text is None:
        return None
    try:
        vals = [float(v) for v in str(text).replace(";", ",").split(",") if v.strip()]
    except ValueError:
        raise CLIError(f"{name} must be a number or comma-separated numbers, got "
                       f"{text!r}") from None
    if not vals or any(not np.isfinite(v) or v < 0 for v in vals):
        raise CLIError(f"{name} must be finite and nonnegative, got {text!r}")
    return vals


def _per_channel(name: str, vals: list[float], dim: int) -> np.ndarray:
    if len(vals) == 1:
        return np.full(dim, vals[0])
    if len(vals) != dim:
        raise CLIError(f"{name} needs one value" + (f" or {dim} (one per channel)" if dim > 1
                                                    else " (the model has one channel)")
                       + f", got {len(vals)}")
    return np.asarray(vals)


#: Exit code of ``setobs estimate`` when the record contradicts the model.
EXIT_INCONSISTENT = 1
#: A run that skips more than this fraction of its samples says so on stderr.
SKIP_WARN_FRACTION = 0.01



def _units(unit: str | Sequence[str] | None, from_model: dict[str, str],
           sys_: Any) -> dict[str, str]:
    """The plot's units: the model file's ``units:``, then ``--unit`` items
    (``name=unit``; a plain unit: every disturbance)."""
    out = dict(from_model)
    items = [] if unit is None else ([unit] if isinstance(unit, str) else list(unit))
    known = [*sys_.state_names, *sys_.output_names, *sys_.disturbance_names]
    for item in items:
        if "=" in item:
            name, u = (x.strip() for x in item.split("=", 1))
            if name not in known:
                raise CLIError(f"--unit {item!r}: the model has no signal {name!r} (its "
                               f"signals: {', '.join(dict.fromkeys(known))})")
            out[name] = u
        else:
            if not sys_.q:
                raise CLIError(f"--unit {item!r}: the model has no disturbance; name the "
                               "signal, e.g. --unit omega=rad/s")
            out.update(dict.fromkeys(sys_.disturbance_names, item.strip()))
    return out


def estimate(record: str, model: str, *, outputs: str, inputs: str | None = None,
             time_col: str | None = None, dt: float | None = None,
             variable: str | None = None, decimate: int = 1, increment: str | None = None,
             noise: str | None = None, calibrate: bool = False, window: int | None = 10,
             out: str | None = None, plot: bool = True, progress: bool | None = None,
             on_inconsistent: str = "raise", unit: str | Sequence[str] | None = None,
             states: bool = False, process_noise: str | None = None,
             restart: str = "auto", per_channel: bool = False,
             time_limit: float = 120.0, holdout: float = 0.3, max_outliers: int = 0,
             max_skip_fraction: float = 0.01, safety: float | None = None) -> int:
    """Certified disturbance bounds from a measured record (CSV + plot + summary);
    with ``states``, the certified state bounds too (``<state>_lo``/``_hi`` columns).
    A model without disturbances (``disturbance_inputs: []``) is a state estimation:
    the state bounds are written (``--states`` implied) and ``--increment`` does not
    apply.

    The record's time axis comes from its time column, else ``dt``, else the model
    file's ``Ts``; without any of them it is the sample index. With
    ``on_inconsistent="raise"`` (the default) the first sample the model cannot
    explain stops the run: one message on stderr with the step, its time and what
    to do, exit code 1 (:data:`EXIT_INCONSISTENT`).

    ``calibrate`` runs :func:`setobs.calibrate_noise` with the options the run itself
    uses (the increment, the process noise, the noise shape) and its own
    (``per_channel``, ``time_limit``, ``holdout``, ``max_outliers``): the calibrated
    bound is the one that makes the record consistent *for this run's model*. It prints
    the smallest bound of the calibrated part, the validated one and its margin, the
    samples where the bound is attained (with their times) and the outliers removed,
    which the run then ignores; the run uses the recommended radii
    (``NoiseCalibration.radii``: validated plus ``safety``, default
    ``SAFETY_MARGIN`` = 10 %; ``safety=0`` uses ``validated`` itself).

    ``unit`` labels the plot's axes: ``"name=unit"`` items (a state, output or
    disturbance by its name), over the model file's ``units:``; a plain unit applies to
    every disturbance. State bands are drawn around their centre (:func:`plot_state_band`).
    """
    import time as _time

    from .exceptions import ModelInvalidatedError, SkipLimitError
    from .io import load_model, load_record, model_units, round_time
    from .setmembership import SMFDO, calibrate_noise

    rec = load_record(record, outputs=outputs, inputs=inputs, time=time_col, dt=dt,
                      variable=variable, decimate=decimate)
    sys_ = load_model(model, dt=rec.dt)
    if rec.dt is None and sys_.dt is not None:
        # no time column and no --dt: the model's sampling time gives the time axis
        import dataclasses

        rec = dataclasses.replace(rec, t=np.arange(rec.Y.shape[0]) * sys_.dt, dt=sys_.dt)
    times_known = rec.dt is not None
    units = _units(unit, model_units(model, dt=rec.dt), sys_)
    if rec.Y.shape[1] != sys_.l:
        raise CLIError(f"the model has {sys_.l} output(s), the record {rec.Y.shape[1]} "
                       f"(--outputs {outputs})")
    if sys_.p and rec.U is None:
        raise CLIError(f"the model has {sys_.p} input(s): name the input columns with --inputs")
    if rec.U is not None and rec.U.shape[1] != sys_.p:
        raise CLIError(f"the model has {sys_.p} input(s), the record {rec.U.shape[1]} "
                       f"(--inputs {inputs})")
    if sys_.q == 0:
        if increment is not None:
            raise CLIError("the model has no disturbance (disturbance_inputs: []): "
                           "--increment does not apply")
        inc = np.zeros(0)
        states = True
    elif increment is None:
        raise CLIError(f"the model has {sys_.q} disturbance(s): give their increment bound "
                       "per sample with --increment")
    else:
        inc = _per_channel("--increment", _numbers("--increment", increment), sys_.q)
    w = None if process_noise is None else _per_channel(
        "--process-noise", _numbers("--process-noise", process_noise), sys_.n)
    if (per_channel or time_limit != 120.0 or holdout != 0.3 or max_outliers
            or safety is not None) and not calibrate:
        raise CLIError("--per-channel, --time-limit, --holdout, --max-outliers and --safety "
                       "apply to --calibrate only")
    if calibrate and noise is not None:
        shape = _per_channel("--noise (shape for --calibrate)", _numbers("--noise", noise),
                             sys_.l)
    else:
        shape = None
    t0 = _time.perf_counter()
    if calibrate:
        cal = calibrate_noise(sys_, rec.Y, rec.U, increment=inc, shape=shape,
                              per_channel=per_channel, process_noise=w,
                              time_limit=time_limit, holdout=holdout,
                              max_outliers=max_outliers,
                              **({} if safety is None else {"safety": safety}))
        v = cal.radii
        print(cal.describe())
        pairs = ", ".join(f"{n} {r:.6g}" for n, r in zip(sys_.output_names, v, strict=True))
        print(f"calibrated noise: {pairs} (used; LPs over {cal.samples} samples)")
    elif noise is not None:
        v = _per_channel("--noise", _numbers("--noise", noise), sys_.l)
        if not np.any(v):
            v = None  # (--noise 0: exact measurements, asked for explicitly)
    else:
        raise CLIError(
            "no measurement-noise bound given: a measured record needs one. Give --noise "
            "R (one or l radii), --calibrate (the smallest bound that explains the record, "
            "validated on a held-out part), or --noise 0 for measurements taken as exact")
    obs = SMFDO(sys_, window=window, increment_set=inc, measurement_noise=v,
                process_noise=w, on_inconsistent=on_inconsistent, state_bounds=states,
                restart=restart, max_skip_fraction=max_skip_fraction)
    ignore = cal.ignore_mask(rec.Y.shape[0]) if calibrate and cal.outliers else None
    N = rec.Y.shape[0]
    if progress is None:  # automatic: long records on a terminal, when tqdm is installed
        import importlib.util

        show = (N >= 2000 and sys.stderr.isatty()
                and importlib.util.find_spec("tqdm") is not None)
    else:
        show = progress
    import warnings

    from .setmembership import ModelInvalidatedWarning

    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelInvalidatedWarning)
            res = obs.run(rec.Y, rec.U, progress=show, ignore=ignore)
    except ModelInvalidatedError as exc:
        k = exc.step
        when = f" (t = {round_time(float(rec.t[k])):g} s)" if times_known else ""
        if isinstance(exc, SkipLimitError):  # (the message without the API's advice)
            print(f"setobs: stopped at step {k}{when}: "
                  + str(exc).removesuffix(f"; {exc.hint}")
                  + ". What to do: --calibrate, a larger --noise or --increment, or "
                  "--max-skip-fraction if these are outliers.", file=sys.stderr)
            return EXIT_INCONSISTENT
        print(f"setobs: the record is inconsistent with the model at step {k}{when}: no "
              f"trajectory within the bounds explains it. What to do: --calibrate (the "
              f"smallest noise bound that explains the record), a larger --noise or "
              f"--increment, or --on-inconsistent skip (drop such samples) or reset "
              f"(restart there, losing the guarantee at that step).", file=sys.stderr)
        return EXIT_INCONSISTENT
    elapsed = _time.perf_counter() - t0
    out_dir = Path(out or Path(record).with_suffix("").name + "_estimate")
    out_dir.mkdir(parents=True, exist_ok=True)
    df = res.to_pandas(dt=rec.dt, names=sys_.disturbance_names)
    if times_known:
        df.insert(0, "time", np.round(rec.t[: len(df)], 12))
    else:
        df.insert(0, "step", np.arange(len(df)))
    df.to_csv(out_dir / "estimate.csv", index=False)
    statuses = {str(k): int(c) for k, c in zip(*np.unique(res.status, return_counts=True),
                                              strict=True)}
    first = res.first_inconsistent
    skipped = statuses.get("skipped", 0) + statuses.get("reset", 0)
    summary = {"record": str(record), "model": str(model), "steps": int(N),
               "sampling_time": None if rec.dt is None else round_time(rec.dt),
               "window": window, "restart": restart if window is not None else None,
               "increment": inc.tolist(),
               "process_noise": None if w is None else np.asarray(w).tolist(),
               "noise": None if v is None else np.asarray(v).tolist(),
               "calibrated": bool(calibrate),
               "calibration": None if not calibrate else {
                   "minimal": cal.minimal.tolist(), "validated": cal.validated.tolist(),
                   "margin": cal.margin.tolist(), "radii": cal.radii.tolist(),
                   "holdout": cal.holdout, "safety": cal.safety,
                   "active_samples": cal.active_samples.tolist(),
                   "validated_samples": cal.validated_samples.tolist(),
                   "outliers": [int(o.sample) for o in cal.outliers],
                   "scale": cal.scale, "status": cal.status, "per_channel": per_channel},
               "units": units,
               "statuses": statuses,
               "first_inconsistent_step": first,
               "first_inconsistent_time": (None if first is None or not times_known
                                           else round_time(float(rec.t[first]))),
               "seconds": round(elapsed, 3)}
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2) + "\n")
    print(f"steps {N}; statuses: " + ", ".join(f"{k} {c}" for k, c in statuses.items())
          + f"; first inconsistent step: {first if first is not None else 'none'}"
          + (f" (t = {round_time(rec.t[first]):g} s)" if first is not None and times_known
             else "")
          + f"; {elapsed:.2f} s")
    if skipped > SKIP_WARN_FRACTION * N:
        print(f"setobs: warning: {skipped} of {N} samples ({100 * skipped / N:.1f} %) were "
              f"{on_inconsistent + 'ped' if on_inconsistent == 'skip' else 'reset'}: the "
              f"bounds are probably too small for this record (try --calibrate, or a larger "
              f"--noise or --increment)", file=sys.stderr)
    written = [out_dir / "estimate.csv", out_dir / "summary.json"]
    if plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from .plotting import plot_estimate_band, plot_state_band

        n_pan = sys_.q + (2 * sys_.n if states else 0)
        fig, axes = plt.subplots(n_pan, 1, figsize=(8, 2.6 * n_pan), sharex=True,
                                 squeeze=False)
        tt = rec.t if times_known else None
        for i in range(sys_.q):
            plot_estimate_band(res, component=i, ax=axes[i, 0], t=tt,
                               unit=units.get(sys_.disturbance_names[i]))
        for i in range(sys_.n if states else 0):
            plot_state_band(res, component=i, t=tt, unit=units.get(sys_.state_names[i]),
                            axes=(axes[sys_.q + 2 * i, 0], axes[sys_.q + 2 * i + 1, 0]))
        what = "disturbance" if not states else ("state" if not sys_.q else
                                                 "disturbance and state")
        axes[0, 0].set_title(f"certified {what} bounds: {Path(record).name}")
        fig.tight_layout()
        fig.savefig(out_dir / "estimate.png", dpi=110)
        plt.close(fig)
        written.append(out_dir / "estimate.png")
    print("wrote " + ", ".join(str(w) for w in written))
    return 0


# ---------------------------------------------------------------------------- study
def study(config: str, dask: str | None = None, out: str | None = None,
          processes: int | None = None) -> int:
    """Run a campaign from a YAML configuration (see the README)."""
    yaml = optional_import("yaml", extra="yaml", feature="setobs study (YAML configuration)")

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
    sc_cfg = dict(cfg.get("scenario") or {})
    from .studies import EXAMPLE_SYSTEMS

    system = sc_cfg.get("system")
    if isinstance(system, str) and system not in EXAMPLE_SYSTEMS:
        # a model file, relative to the configuration file
        sc_cfg["system"] = str((p.parent / system) if not Path(system).is_absolute() else system)
    try:
        scenario = Scenario(**sc_cfg)
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
        from .setmembership._sets import check_window

        try:
            check_window(ref_window)
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
    plot_error_curves(res.table, "error_inf", ax=axes[0])
    plot_comparison_bars(res.table, "worst_case_error", ax=axes[1])
    fig.tight_layout()
    fig.savefig(out_dir / "summary.png", dpi=110)
    plt.close(fig)
    print(f"wrote {out_dir / 'results.csv'}, {out_dir / 'metadata.json'}, "
          f"{out_dir / 'summary.png'}")
    return 0


class _DefaultsFormatter(argparse.HelpFormatter):
    """Every option's help ends with its default (unless the help already states it);
    an option without one says so."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if ("default" in text or action.default is argparse.SUPPRESS or action.required
                or not action.option_strings):
            return text
        if action.default is None:
            return text + " (default: none)"
        if action.default is False:
            return text + " (default: off)"
        return text + " (default: %(default)s)"


# ---------------------------------------------------------------------------- main
def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``setobs`` command."""
    parser = argparse.ArgumentParser(prog="setobs", description=__doc__.split("\n\n")[0])
    parser.add_argument("--version", action="version", version=f"setobs {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    pd_ = sub.add_parser("demo", formatter_class=_DefaultsFormatter,
                         help="SMFDO vs PIO on the set-membership paper's example")
    pd_.add_argument("--out", default="setobs_demo.png", help="PNG to write")
    pd_.add_argument("--steps", type=int, default=120, help="length of the simulated record")
    pd_.add_argument("--seed", type=int, default=0, help="seed of the simulated disturbance")
    pc = sub.add_parser("check", formatter_class=_DefaultsFormatter,
                         help="which observer designs exist for a system")
    pc.add_argument("file", help=".json, .yaml, .npz or .mat with Phi, G, Xi (, Gamma); "
                                 "or an example name (chang2006, cgl1, ...), or 'all'")
    pc.add_argument("--format", choices=["text", "markdown", "json"], default="text",
                    help="the report's format")
    pc.add_argument("--dt", type=float, default=None,
                    help="sampling time for a continuous-time model file without Ts")
    pe = sub.add_parser("estimate", formatter_class=_DefaultsFormatter,
                         help="certified disturbance bounds from a measured record")
    pe.add_argument("record", help="the record: .csv (header optional), .mat or .npz")
    pe.add_argument("--model", required=True,
                    help="model file (.yaml/.json/.mat/.npz): Phi, G, Xi (, Gamma, Du) or "
                         "A, B, C, D with G or disturbance_inputs; Ts; continuous: true")
    pe.add_argument("--outputs", required=True, help="output columns (names or indices, "
                                                     "comma-separated)")
    pe.add_argument("--inputs", help="input columns (names or indices)")
    pe.add_argument("--time", dest="time_col", help="time column (sets the sampling time)")
    pe.add_argument("--dt", type=float, help="sampling time (without a time column; default "
                                             "the model file's Ts)")
    pe.add_argument("--variable", help="data matrix in a .mat/.npz record")
    pe.add_argument("--decimate", type=int, default=1, help="keep every k-th sample "
                                                           "(continuous models)")
    pe.add_argument("--increment",
                    help="disturbance increment bound per sample (one or q numbers; "
                         "required unless the model has no disturbance)")
    pe.add_argument("--process-noise",
                    help="process-noise radii on the states (one or n numbers)")
    pe.add_argument("--restart", choices=["auto", "polytope", "box"], default="auto",
                    help="what each window restarts from: 'polytope' (keeps the set's "
                         "shape), 'box' (the paper's eq. (24)) or 'auto' (default: the "
                         "polytope where it is tighter, checked every 16 steps)")
    pe.add_argument("--noise", help="measurement-noise radii (one or l numbers; 0: exact "
                                    "measurements); with --calibrate: the shape to scale. "
                                    "Required unless --calibrate (default: none)")
    pe.add_argument("--calibrate", action="store_true",
                    help="use the smallest noise bound that makes the record consistent "
                         "(with this run's --increment, --process-noise and --noise shape)")
    pe.add_argument("--per-channel", action="store_true",
                    help="with --calibrate: per-channel radii instead of one scale of the "
                         "--noise shape (calibrate_noise(per_channel=True))")
    pe.add_argument("--time-limit", type=float, default=120.0,
                    help="with --calibrate: seconds each LP solver may take (default 120)")
    pe.add_argument("--holdout", type=float, default=0.3,
                    help="with --calibrate: fraction of the record (its end) held out to "
                         "validate the bound (default 0.3; 0: none)")
    pe.add_argument("--max-outliers", type=int, default=0,
                    help="with --calibrate: remove up to this many samples that raise the "
                         "bound most (named in the output; the run ignores them)")
    pe.add_argument("--max-skip-fraction", type=float, default=0.01,
                    help="with --on-inconsistent skip: stop (exit 1) once more than this "
                         "fraction of the samples were skipped (default 0.01)")
    pe.add_argument("--window", default="10", help="SMFDO window (the paper's delta), or 'exact'")
    pe.add_argument("--on-inconsistent", choices=["raise", "skip", "reset"], default="raise",
                    help="what to do with a sample the model cannot explain: 'raise' "
                         "(default) stops at the first one with exit code 1, saying the step, "
                         "its time and what to do; 'skip' drops such samples, up to "
                         "--max-skip-fraction of them (then it stops, exit 1; the CSV's "
                         "after_skip column marks the steps after the first skip: their "
                         "guarantee is for the record without those samples); 'reset' "
                         "restarts the filter there (the guarantee is lost at that step)")
    pe.add_argument("--states", action="store_true",
                    help="also write the certified state bounds (<state>_lo, <state>_hi)")
    pe.add_argument("--unit", action="append",
                    help="a signal's unit for the plot's axes, NAME=UNIT (e.g. "
                         "omega=rad/s; repeat for more; over the model file's units:); a "
                         "plain UNIT labels the disturbances (e.g. 'N m')")
    pe.add_argument("--safety", type=float, default=None,
                    help="with --calibrate: relative safety added to the validated bound "
                         "(default 0.1: 10 %%; 0 uses the validated bound itself, whose "
                         "bands collapse where it is attained)")
    pe.add_argument("--out", help="output directory")
    pe.add_argument("--no-plot", action="store_true", help="write no summary plot")
    pe.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                    help="a progress line on stderr (default: on a terminal only)")
    ps = sub.add_parser("study", formatter_class=_DefaultsFormatter,
                         help="run a Monte Carlo campaign from a YAML file")
    ps.add_argument("config", help="the campaign's YAML file")
    ps.add_argument("--dask", metavar="ADDRESS", help="Dask scheduler address")
    ps.add_argument("--out", help="output directory")
    ps.add_argument("--processes", type=int, help="local worker processes")
    args = parser.parse_args(argv)
    if args.command is None:
        parser.print_usage(sys.stderr)
        print("setobs: error: a command is required (demo, check, estimate or study; see "
              "--help)",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    try:
        if args.command == "demo":
            return demo(args.out, args.steps, args.seed)
        if args.command == "check":
            return check(args.file, args.format, args.dt)
        if args.command == "estimate":
            if args.window in ("exact", "none", "None"):
                window = None
            else:
                try:
                    window = int(args.window)
                except ValueError:
                    raise CLIError(f"--window must be an integer or 'exact', got "
                                   f"{args.window!r}") from None
            return estimate(args.record, args.model, outputs=args.outputs, inputs=args.inputs,
                            time_col=args.time_col, dt=args.dt, variable=args.variable,
                            decimate=args.decimate, increment=args.increment,
                            noise=args.noise, calibrate=args.calibrate, window=window,
                            out=args.out, plot=not args.no_plot, progress=args.progress,
                            on_inconsistent=args.on_inconsistent, unit=args.unit,
                            states=args.states, process_noise=args.process_noise,
                            restart=args.restart, per_channel=args.per_channel,
                            time_limit=args.time_limit, holdout=args.holdout,
                            max_outliers=args.max_outliers,
                            max_skip_fraction=args.max_skip_fraction, safety=args.safety)
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
