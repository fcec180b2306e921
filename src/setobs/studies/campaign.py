"""Monte Carlo campaigns: seeds x observers, local processes by default, Dask on request."""

from __future__ import annotations

import inspect
import json
import os
import platform
import time
from collections.abc import Sequence
from dataclasses import asdict, dataclass, field
from importlib import metadata as _md
from pathlib import Path
from typing import Any

import numpy as np

from .._lazy import progress_bar
from ..exceptions import ArgumentError, InvalidValueError
from .scenarios import Scenario, rng_for_run

__all__ = ["FILTERED_KINDS", "OBSERVER_KINDS", "SMFDO_PARAMS", "CampaignResult", "Improvement",
           "ObserverSpec", "run_campaign", "run_one"]

#: Observer kinds a campaign can run (built inside the worker from plain data).
OBSERVER_KINDS = ("smfdo", "pio", "pio_printed", "kalman", "higher_order", "modular", "mbeso",
                  "variant_mbeso", "delayed_uio")

#: Point-observer kinds that can use ``y_k`` for the estimate at ``k``: a campaign runs
#: them with ``information="filtered"`` (the SMFDO's information) unless a spec says
#: otherwise. The others use ``y_0..y_(k-1)`` and the table says so.
FILTERED_KINDS = ("pio", "pio_printed", "kalman")


#: SMFDO keywords an ObserverSpec may set (the scenario gives the initial state
#: set; ``increment_set`` defaults to the scenario's increment box).
SMFDO_PARAMS = ("window", "increment_set", "fast", "margin", "data_rtol", "on_inconsistent",
                "reset", "reset_inflation", "measurement_noise", "process_noise", "restart",
                "restart_depth")


def _point_ctor(kind: str):
    from .. import observers as obs

    return {"pio": obs.PIO, "higher_order": obs.HigherOrderObserver,
            "modular": obs.ModularObserver, "mbeso": obs.MBESO,
            "variant_mbeso": obs.VariantMBESO, "delayed_uio": obs.DelayedUIO}[kind]


def _accepted_params(kind: str) -> tuple[str, ...]:
    if kind == "smfdo":
        return SMFDO_PARAMS
    if kind == "pio_printed":
        return ("information",)
    if kind == "kalman":
        from .baselines import kalman_baseline

        sig = inspect.signature(kalman_baseline)
    else:
        sig = inspect.signature(_point_ctor(kind).__init__)
    return tuple(p for p in sig.parameters if p not in ("self", "sys", "scenario"))


@dataclass(frozen=True)
class ObserverSpec:
    """An observer in a campaign: a display ``name``, a ``kind`` and its parameters.

    ``kind="smfdo"`` takes the SMFDO keywords in :data:`SMFDO_PARAMS`
    (``window``: int, or ``None`` for exact mode; ``increment_set``: a radius or
    per-channel radii, default the scenario's); point observers take their
    constructor keywords (e.g. ``omega`` for the MB-ESO). ``kind="kalman"`` is
    the steady-state Kalman filter of :func:`setobs.studies.kalman_baseline`
    (parameters ``information``, ``measurement_cov``). Every parameter is
    honoured or refused: an unknown name raises at construction.

    *Information.* The SMFDO's estimate at ``k`` uses ``y_0..y_k``; the papers'
    point observers use ``y_0..y_(k-1)``. Kinds in :data:`FILTERED_KINDS` are
    run with ``information="filtered"`` (equal information) unless ``params``
    sets it; the table's ``information`` column states what each row used.

    Attributes
    ----------
    name : str
        Display name (distinct within a campaign).
    kind : str
        A key of :data:`OBSERVER_KINDS`.
    params : dict
        Keywords of the observer (see above).
    """

    name: str
    kind: str
    params: dict[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise InvalidValueError(f"an observer needs a non-empty name, got {self.name!r}")
        if self.kind not in OBSERVER_KINDS:
            raise InvalidValueError(f"unknown observer kind {self.kind!r}; choose from "
                                 f"{list(OBSERVER_KINDS)}")
        if not isinstance(self.params, dict):
            raise ArgumentError(f"params of observer {self.name!r} must be a mapping, got "
                                f"{type(self.params).__name__}")
        accepted = _accepted_params(self.kind)
        unknown = sorted(set(self.params) - set(accepted))
        if unknown:
            raise InvalidValueError(
                f"observer {self.name!r} ({self.kind}): unknown parameter(s) {unknown}; "
                f"accepted: {list(accepted) or 'none'}")
        if self.kind == "smfdo" and "window" in self.params:
            from ..setmembership._sets import check_window

            try:
                check_window(self.params["window"])
            except (TypeError, ValueError) as exc:
                raise InvalidValueError(f"observer {self.name!r}: {exc}") from None


def _point_observer(spec: ObserverSpec, sys, scenario: Scenario | None = None):
    from .. import observers as obs

    params = dict(spec.params)
    if spec.kind in FILTERED_KINDS:
        params.setdefault("information", "filtered")
    if spec.kind == "pio_printed":
        return obs.PIO.chang2006_baseline(sys, **params)
    if spec.kind == "kalman":
        from .baselines import kalman_baseline

        if scenario is None:
            raise InvalidValueError("the Kalman baseline needs the scenario (its covariances)")
        return kalman_baseline(scenario, sys, **params)
    return _point_ctor(spec.kind)(sys, **params)


def _smfdo_for(spec_params: dict[str, Any], scenario: Scenario, sys, on_inconsistent: str):
    """The SMFDO of a spec (scenario defaults for the sets)."""
    from ..setmembership import SMFDO

    kw = {"increment_set": scenario.increment_set(sys.q),
          "initial_state_set": scenario.initial_state_set(sys.n)}
    if "reset" not in spec_params:
        kw["on_inconsistent"] = on_inconsistent
    kw.update(spec_params)
    if np.ndim(kw["increment_set"]) == 0 and not hasattr(kw["increment_set"], "dim"):
        kw["increment_set"] = np.full(sys.q, float(kw["increment_set"]))
    return SMFDO(sys, **kw)


def run_one(scenario: Scenario, specs: Sequence[ObserverSpec], run: int, base_seed: int = 0,
            reference_window: int | None = 20) -> list[dict[str, Any]]:
    """One run: simulate, run every observer, score against the consistent set.

    The consistent set comes from an SMFDO with ``reference_window``
    (``None``: exact mode, the true consistent set; a window gives an outer
    approximation, so worst-case scores are upper bounds).

    Returns tidy rows ``(run, observer, k, error_inf, error_2, worst_case_error,
    optimal, error_bound, truth_inside, information)`` (the metric names of
    :mod:`setobs.results`; ``information`` is the measurements the estimate at
    ``k`` used, see :class:`ObserverSpec`):
    actual errors, worst-case infinity-norm error over the consistent set, the
    optimal worst-case error (the reference's ``error_bound``), the observer's own
    ``error_bound`` (SMFDO only) and whether the truth lies in that interval
    (SMFDO only).

    Parameters
    ----------
    scenario : Scenario
        The simulated plant, disturbance and noise.
    specs : sequence of ObserverSpec
        The observers to run.
    run : int
        Run index (selects the random stream, :func:`rng_for_run`).
    base_seed : int
        The campaign's seed.
    reference_window : int or None
        Window of the reference SMFDO that gives the consistent set (``None``: exact).
    """
    from ..compare import worst_case_error

    sys = scenario.build_system()
    traj = scenario.simulate(rng_for_run(base_seed, run))
    # Gaussian noise is unbounded: the reference resets where it is inconsistent.
    reset = "reset" if scenario.noise_std > 0 else "raise"
    ref_params = {"window": reference_window}
    ref = _smfdo_for(ref_params, scenario, sys, reset).run(traj.Y, traj.U)
    rows: list[dict[str, Any]] = []
    for spec in specs:
        if spec.kind == "smfdo":
            params = {"window": 10, **spec.params}
            # The same deterministic computation as the reference: reuse it.
            res = ref if params == ref_params else _smfdo_for(params, scenario, sys,
                                                              reset).run(traj.Y, traj.U)
            est, bound = res.estimate, res.error_bound
            inside = np.all((traj.D >= res.lo) & (traj.D <= res.hi), axis=1)
            info = "y_0..y_k"
        else:
            pres = _point_observer(spec, sys, scenario).run(traj.Y, traj.U)
            est, info = pres.estimate, pres.information
            bound = np.full(scenario.horizon, np.nan)
            inside = np.full(scenario.horizon, np.nan)
        err = est - traj.D
        worst = worst_case_error(est, ref.lo, ref.hi)
        with np.errstate(invalid="ignore"):
            e_inf = np.abs(err).max(axis=1)
            e_2 = np.linalg.norm(err, axis=1)
        for k in range(scenario.horizon):
            rows.append({"run": int(run), "observer": spec.name, "k": k,
                         "error_inf": float(e_inf[k]), "error_2": float(e_2[k]),
                         "worst_case_error": float(worst[k]), "optimal": float(ref.error_bound[k]),
                         "error_bound": float(bound[k]), "truth_inside": float(inside[k]),
                         "information": info})
    return rows


@dataclass(frozen=True)
class Improvement:
    """Relative improvement ``1 - mean_A / mean_B`` with a bootstrap interval over runs.

    Attributes
    ----------
    value : float
        The point estimate.
    lo, hi : float
        The percentile bootstrap interval.
    runs : int
        Runs resampled.
    confidence : float
        Level of the interval.
    """

    value: float
    lo: float
    hi: float
    runs: int
    confidence: float

    def __str__(self) -> str:
        return (f"{self.value:.1%} [{self.lo:.1%}, {self.hi:.1%}] "
                f"({self.confidence:.0%} CI over {self.runs} runs)")


@dataclass
class CampaignResult:
    """A campaign's tidy table and its metadata (the protocol of :mod:`setobs.results`).

    Attributes
    ----------
    table : pandas.DataFrame
        One row per run, observer and step: ``run, observer, k, error_inf,
        error_2, worst_case_error, optimal, error_bound, truth_inside,
        information``.
    metadata : dict
        The request, versions, machine and timing (also in ``metadata.json``).
    """

    table: Any
    metadata: dict[str, Any]

    def to_pandas(self) -> Any:
        """The tidy table (a copy).

        Returns
        -------
        pandas.DataFrame
            :attr:`table`.
        """
        return self.table.copy()

    def summary(self, start: int = 10) -> Any:
        """Mean of each metric per observer (index ``observer``) over steps ``k >= start``.

        Parameters
        ----------
        start : int
            First step counted (skip the transient).

        Returns
        -------
        pandas.DataFrame
            Columns ``error_inf, error_2, worst_case_error, optimal, error_bound,
            truth_inside``, and ``information`` (the measurements each observer's
            estimate at ``k`` used) when the table has it.
        """
        t = self.table[self.table["k"] >= start]
        cols = ["error_inf", "error_2", "worst_case_error", "optimal", "error_bound",
                "truth_inside"]
        out = t.groupby("observer", sort=False)[cols].mean()
        if "information" in t.columns:
            out["information"] = t.groupby("observer", sort=False)["information"].first()
        return out

    def improvement(self, better: str, baseline: str, *, start: int = 10,
                    metric: str = "error_inf", confidence: float = 0.95, n_boot: int = 4000,
                    rng: np.random.Generator | int | None = 0) -> Improvement:
        """``1 - mean(better) / mean(baseline)`` of ``metric``, with a bootstrap interval.

        The per-run means over ``k >= start`` are resampled by run (paired: both
        observers ran on the same records), ``n_boot`` times; the interval is
        the percentile interval at ``confidence``.

        Parameters
        ----------
        better, baseline : str
            Observer names.
        start : int
            First step counted.
        metric : str
            A metric column of :attr:`table`.
        confidence : float
            Level of the interval, in ``(0, 1)``.
        n_boot : int
            Bootstrap resamples.
        rng : numpy.random.Generator, int or None
            Random source of the resampling.

        Returns
        -------
        Improvement
        """
        t = self.table[self.table["k"] >= start]
        names = set(t["observer"])
        for nm in (better, baseline):
            if nm not in names:
                raise InvalidValueError(f"no observer named {nm!r} in the campaign")
        if not 0 < confidence < 1:
            raise InvalidValueError(f"confidence must be in (0, 1), got {confidence}")
        per = t.groupby(["observer", "run"])[metric].mean()
        a = per.loc[better].to_numpy()
        b = per.loc[baseline].to_numpy()
        gen = np.random.default_rng(rng)
        idx = gen.integers(0, a.size, size=(int(n_boot), a.size))
        boot = 1.0 - a[idx].mean(axis=1) / b[idx].mean(axis=1)
        alpha = 1.0 - confidence
        lo, hi = np.quantile(boot, [alpha / 2, 1 - alpha / 2])
        return Improvement(float(1.0 - a.mean() / b.mean()), float(lo), float(hi),
                           int(a.size), float(confidence))

    def plot(self, ax: Any = None, metric: str = "error_inf", logy: bool = True) -> Any:
        """Mean of ``metric`` over runs, per step and observer
        (:func:`setobs.plotting.plot_error_curves`).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default: the current axes).
        metric : str
            A metric column of :attr:`table`.
        logy : bool
            Logarithmic axis.

        Returns
        -------
        matplotlib Axes
            The axes drawn on.
        """
        from ..plotting import plot_error_curves

        return plot_error_curves(self.table, metric, ax=ax, logy=logy)


def _check_resume(out: Path, request: dict[str, Any]) -> None:
    """Refuse to mix runs of different campaigns in one ``out_dir``."""
    req_file = out / "request.json"
    if req_file.exists():
        stored = json.loads(req_file.read_text())
        if stored != request:
            diff = sorted(k for k in request if stored.get(k) != request.get(k))
            raise InvalidValueError(
                f"{out} holds runs of a different campaign (different {', '.join(diff)}); "
                "use another out_dir, or delete it to start over")
    elif any(out.glob("run_*.csv")):
        raise InvalidValueError(f"{out} holds runs without a record of their campaign "
                             "(request.json); use another out_dir")
    else:
        req_file.write_text(json.dumps(request, indent=2) + "\n")


def _versions() -> dict[str, str]:
    out = {}
    for pkg in ("setobs", "numpy", "scipy", "highspy", "pandas", "dask", "distributed"):
        try:
            out[pkg] = _md.version(pkg)
        except _md.PackageNotFoundError:
            pass
    return out


def _connect(client):
    from distributed import Client

    return client if isinstance(client, Client) else Client(client)


def run_campaign(
    scenario: Scenario,
    specs: Sequence[ObserverSpec],
    runs: int,
    *,
    base_seed: int = 0,
    reference_window: int | None = 20,
    client: Any = None,
    processes: int | None = None,
    out_dir: str | os.PathLike[str] | None = None,
    progress: bool = True,
) -> CampaignResult:
    r"""Run ``runs`` seeded runs of ``scenario`` for every observer in ``specs``.

    Parameters
    ----------
    client : distributed.Client or str, optional
        Run on Dask: a ``Client`` or a scheduler address. Default: local
        processes (``concurrent.futures``), or in-process when ``processes=1``.
    processes : int, optional
        Local worker processes (default: ``os.cpu_count()``).
    out_dir : path, optional
        Resumable output: each run is written to ``run_XXXXX.csv`` and skipped
        when the file exists; ``results.csv`` and ``metadata.json`` are written
        at the end. ``request.json`` records the scenario, observers, seed and
        reference window: resuming into a directory of a different request is
        refused (runs are never mixed).
    progress : bool
        Show a tqdm progress bar.
    scenario : Scenario
        The simulated plant, disturbance and noise.
    specs : sequence of ObserverSpec
        The observers to run (distinct names).
    runs : int
        Number of runs.
    base_seed : int
        The campaign's seed; run ``r`` draws from :func:`rng_for_run`\ ``(base_seed, r)``,
        the same on every back end.
    reference_window : int or None
        Window of the reference SMFDO that gives the consistent set (``None``: exact mode,
        the true consistent set; a window gives an outer approximation, so worst-case scores
        are upper bounds).

    Returns
    -------
    CampaignResult
        ``table``: pandas DataFrame sorted by ``(run, observer order, k)``.
    """
    import pandas as pd

    if (isinstance(runs, bool) or not isinstance(runs, int | np.integer | float)
            or int(runs) != runs or runs < 1):
        raise InvalidValueError(f"runs must be a positive integer, got {runs!r}")
    runs = int(runs)
    specs = list(specs)
    if not specs:
        raise InvalidValueError("at least one observer is needed")
    names = [s.name for s in specs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise InvalidValueError(f"observer names must be distinct (their rows are keyed by "
                             f"name); repeated: {dup}")
    # Build every observer once on the scenario's system: bad parameters fail here,
    # before any run is dispatched.
    sys0 = scenario.build_system()
    for spec in specs:
        if spec.kind == "smfdo":
            _smfdo_for({"window": 10, **spec.params}, scenario, sys0, "raise")
        else:
            _point_observer(spec, sys0, scenario)
    out = Path(out_dir) if out_dir is not None else None
    request = {"scenario": scenario.to_dict(), "observers": [asdict(s) for s in specs],
               "base_seed": int(base_seed), "reference_window": reference_window}
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        _check_resume(out, json.loads(json.dumps(request, default=str)))
    frames: dict[int, Any] = {}
    todo = []
    for r in range(runs):
        f = out / f"run_{r:05d}.csv" if out is not None else None
        if f is not None and f.exists():
            frames[r] = pd.read_csv(f)
        else:
            todo.append(r)
    t0 = time.perf_counter()
    bar = progress_bar(bool(progress and todo), total=len(todo), desc="runs")

    def store(r: int, rows: list[dict[str, Any]]) -> None:
        df = pd.DataFrame(rows)
        if out is not None:
            df.to_csv(out / f"run_{r:05d}.csv", index=False)
        frames[r] = df
        bar.update(1)

    args = (scenario, specs)
    try:
        if client is not None:
            c = _connect(client)
            futs = {c.submit(run_one, *args, r, base_seed, reference_window, pure=False): r
                    for r in todo}
            from distributed import as_completed as das_completed

            for fut in das_completed(list(futs)):
                store(futs[fut], fut.result())
        elif processes == 1 or len(todo) <= 1:
            for r in todo:
                store(r, run_one(*args, r, base_seed, reference_window))
        else:
            from concurrent.futures import ProcessPoolExecutor, as_completed

            with ProcessPoolExecutor(max_workers=processes) as ex:
                futs2 = {ex.submit(run_one, *args, r, base_seed, reference_window): r
                         for r in todo}
                for fut in as_completed(futs2):
                    store(futs2[fut], fut.result())
    finally:
        bar.close()
    order = {s.name: i for i, s in enumerate(specs)}
    table = pd.concat([frames[r] for r in sorted(frames)], ignore_index=True)
    table = table.assign(_o=table["observer"].map(order)).sort_values(
        ["run", "_o", "k"], kind="stable").drop(columns="_o").reset_index(drop=True)
    meta = {
        "scenario": scenario.to_dict(), "observers": [asdict(s) for s in specs],
        "runs": int(runs), "base_seed": int(base_seed),
        "seeding": "numpy.random.SeedSequence(base_seed, spawn_key=(run,))",
        "reference_window": reference_window,
        "backend": "dask" if client is not None else ("serial" if processes == 1
                                                      else "processes"),
        "versions": _versions(), "python": platform.python_version(),
        "elapsed_s": time.perf_counter() - t0,
    }
    if out is not None:
        table.to_csv(out / "results.csv", index=False)
        (out / "metadata.json").write_text(json.dumps(meta, indent=2, default=str) + "\n")
    return CampaignResult(table, meta)
