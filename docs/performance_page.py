"""The performance page, generated from ``benchmarks/results/`` when the docs are built.

Every figure on the page is read from a results file; nothing is typed by hand. Each
results file carries the commit and the date of the run (``commit``, ``date``: written
by ``benchmarks/_common.stamp``, or, for files older than the stamp, the commit that
recorded the file, as its ``stamp`` entry says). ``render(results_dir)`` returns the
page as Markdown; ``docs/conf.py`` writes it to ``docs/performance.md``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

STAMP_KEYS = ("commit", "date", "stamp")
MAX_ROWS = 25        # longer tables are cut, with the count of rows left in the file
MAX_LIST = 8         # longer lists of numbers are summarised
MAX_TEXT = 240       # longer strings are cut

# One line per benchmark: its script and what it measures (no figures: those are below).
ABOUT: dict[str, tuple[str, str]] = {
    "calibration": ("calibration", "The noise calibration on the HSM150 motor record: the "
                    "validated bound and its cost, and the noise-against-increment trade-off."),
    "chain_ab": ("chain_ab", "The objective chain against one warm start per bound, on the "
                 "window's LPs and exact mode's whole-history LP."),
    "early_stop": ("early_stop", "The window's early-stopped bounds: how much wider than the "
                   "bounds solved to the optimum, over random plants."),
    "exact_floor": ("exact_floor", "What holds exact mode's step cost on 30-state plants: "
                    "HiGHS's fixed cost per solve and per iteration, the work outside the "
                    "solver, and the LP bases' structure (what a sparse LU would factor)."),
    "exact_long": ("exact_long", "Exact mode with noise on the 30-tank cascade over a long "
                   "record: the whole-history LP's cost per step, checked against an "
                   "independent LP."),
    "exact_long_basis_restart": ("exact_long", "The same run before the restart from the "
                                 "warm solve's first basis and with HiGHS's own scaling "
                                 "(stopped where it stalled)."),
    "exact_long_tight_bounds": ("exact_long", "The same run with tight implied state bounds "
                                "(degenerate LPs), kept as the reason for the widened ones."),
    "exact_mode": ("exact_mode", "Exact mode without noise (the H-representation): cost per "
                   "step against k, and the exact-mode Fig. 1(b) campaign."),
    "exact_noise": ("exact_noise", "Exact mode with noise (the whole-history LP) on three "
                    "plants, against one LP of the same step solved from scratch."),
    "exact_bounded": ("exact_bounded", "Exact mode with noise over a bounded history (the "
                      "outer and inner cut LPs) on three 30-state plants: cost per step, the "
                      "history kept, and the bounds against an independent whole-history LP."),
    "exact_truncation": ("exact_truncation", "A study: the whole-history LP cut at s = k - L "
                         "with outer and inner restart sets."),
    "geometry_ops": ("geometry_ops", "The set operations and queries against cvxpy and "
                     "ZonoOpt on the same random sets (time and answers)."),
    "hybrid_zonotopes": ("hybrid_zonotopes", "Hybrid zonotopes against ZonoOpt's: time of "
                         "each operation and query on unions of 2-64 sets in 2-10 dimensions and "
                         "a piecewise-affine reachability horizon, and every answer against the "
                         "enumerated truth."),
    "import_time": ("import_time", "The time of `import setobs` and of the first use of each "
                    "heavy engine."),
    "interval_hull": ("interval_hull", "The certified interval hull against cvxpy."),
    "nonlinear_observer": ("nonlinear_observer", "The nonlinear modular observer's design and "
                           "step costs by order."),
    "nonlinear_set": ("nonlinear_set", "NonlinearSetObserver at its defaults: time per step "
                      "(in linprog units), band widths against inner bounds of the exact set "
                      "on plants the defaults were not tuned on, and the Rego example."),
    "notebook_03_full": ("notebook_full", "Notebook 03 at the paper's size (5000 runs x 200 "
                         "steps): time per cell."),
    "observer_comparison": ("observer_comparison", "Point observers against the worst-case "
                            "optimal bound on the paper example."),
    "smfdo": ("smfdo", "The SMFDO's time per update by window and restart, in linprog units."),
    "smfdo_campaign": ("smfdo_campaign", "The SMFDO's fast path against the reference path, "
                       "the hull against HiGHS and cvxpy, and the Fig. 1(b) campaign."),
    "window_worst": ("window_worst", "A study: what holds window 10's worst state band "
                     "against exact mode on two 30-tank cascades (a fast and a slow one), "
                     "by restart variant."),
    "smfdo_noise": ("smfdo_noise", "The SMFDO on the measured motor record with noise bounds."),
    "state_estimation": ("state_estimation", "Guaranteed state estimation: band widths against "
                         "the whole-history LP and cost per step, by plant, window and "
                         "restart."),
    "state_estimation_r30": ("state_estimation", "The same on a random 30-state plant with 21 "
                             "outputs and a dense `A` (`--r30`): windows 3, 5 and 10 and exact "
                             "mode against the whole-history LP."),
    "verdict_campaign": ("verdict_campaign", "Statuses and verdicts at calibrated noise bounds "
                         "against an independent whole-history LP, on random systems."),
    "window_cost": ("window_cost", "Where the window's cost goes: the objective chain against "
                    "HiGHS's on the same LPs (iterations, our time per iteration), and the "
                    "steady-state cost, on a random 6-state plant, the 30-tank cascade and a "
                    "random 30-state plant."),
}

INTRO = """# Performance

Every figure on this page is read from a results file in `benchmarks/results/` when the
documentation is built; each section names its file, the script that writes it
(`python benchmarks/<script>.py`) and the commit and date of the run. Times are in
milliseconds or in *linprog units*: one 45 x 40 `scipy.optimize.linprog` (HiGHS) timed in
the same run, so that runs on different machines compare. On the 2-core machines these
ran on, the unit itself moves by tens of percent within minutes: compare units within one
file, not milliseconds across files. A `targets` entry states what a benchmark was asked
to reach and whether it did.
"""


def _num(x: float) -> str:
    if isinstance(x, bool):
        return "yes" if x else "no"
    if isinstance(x, int):
        return f"{x:,}".replace(",", " ") if abs(x) >= 10_000 else str(x)
    if not math.isfinite(x):
        return str(x)
    if x == 0:
        return "0"
    if 1e-3 <= abs(x) < 1e5:
        return f"{x:.4g}"
    return f"{x:.3e}"


def _scalar(x: object) -> bool:
    return x is None or isinstance(x, bool | int | float | str)


def _cell(x: object) -> str:
    if x is None:
        return ""
    if isinstance(x, bool | int | float):
        return _num(x)
    if isinstance(x, str):
        text = x if len(x) <= MAX_TEXT else x[:MAX_TEXT] + " ..."
        return text.replace("|", "\\|").replace("\n", " ")
    if isinstance(x, list) and all(isinstance(v, bool | int | float) for v in x):
        shown = ", ".join(_num(v) for v in x[:MAX_LIST])
        return f"[{shown}{', ...' if len(x) > MAX_LIST else ''}]"
    text = json.dumps(x)
    return _cell(text)


def _table(rows: list[dict], cols: list[str] | None = None) -> list[str]:
    cols = cols or list(dict.fromkeys(k for r in rows for k in r))
    out = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    for r in rows[:MAX_ROWS]:
        out.append("| " + " | ".join(_cell(r.get(c)) for c in cols) + " |")
    if len(rows) > MAX_ROWS:
        out.append(f"\n({len(rows) - MAX_ROWS} more rows in the file)")
    return out


def _flatten(d: dict, prefix: str = "") -> dict:
    """Nested dictionaries as one row: ``{"a": {"b": 1}}`` is ``{"a.b": 1}``."""
    out: dict = {}
    for k, v in d.items():
        if isinstance(v, dict) and v:
            out.update(_flatten(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def _flat(d: dict) -> bool:
    return all(_scalar(v) or (isinstance(v, list) and all(_scalar(x) for x in v))
               for v in d.values())


def _value(name: str, x: object, depth: int) -> list[str]:
    """Markdown for one entry of a results file."""
    head = "#" * min(depth, 6)
    if isinstance(x, list) and x and all(isinstance(r, dict) for r in x):
        rows = [_flatten(r) for r in x]
        return [f"{head} {name}", "", *_table(rows), ""]
    if isinstance(x, dict):
        if x and all(isinstance(v, dict) and _flat(v) for v in x.values()):
            rows = [{"": k, **v} for k, v in x.items()]
            return [f"{head} {name}", "", *_table(rows), ""]
        if x and all(isinstance(v, dict) for v in x.values()):
            rows = [{"": k, **_flatten(v)} for k, v in x.items()]
            if len({c for r in rows for c in r}) <= 14:
                return [f"{head} {name}", "", *_table(rows), ""]
        if _flat(x):
            rows = [{"entry": k, "value": v} for k, v in x.items()]
            return [f"{head} {name}", "", *_table(rows), ""]
        out = [f"{head} {name}", ""]
        flat = {k: v for k, v in x.items() if _scalar(v)}
        if flat:
            out += [*_table([{"entry": k, "value": v} for k, v in flat.items()]), ""]
        for k, v in x.items():
            if k not in flat:
                out += _value(k, v, depth + 1)
        return out
    if isinstance(x, list) and len(x) > MAX_LIST:
        return [f"- {name}: {len(x)} values in the file", ""]
    return [f"- {name}: {_cell(x)}"]


def section(path: Path) -> list[str]:
    """The page's section for one results file."""
    stem = path.stem
    script, about = ABOUT.get(stem, (stem, ""))
    if path.suffix == ".md":
        text = path.read_text()
        first, _, body = text.partition("\n")
        stamp = first.removeprefix("<!--").removesuffix("-->").strip()
        return [f"## {stem}", "", f"`benchmarks/results/{path.name}`, written by "
                f"`python benchmarks/{script}.py`; {stamp}.", "", about, "", body.strip(), ""]
    data = json.loads(path.read_text())
    commit, date = data.get("commit"), data.get("date")
    stamp = (f"commit `{commit[:10]}`, {date}" if commit else "no commit recorded")
    if "stamp" in data:
        stamp += f" ({data['stamp']})"
    out = [f"## {stem}", "", f"`benchmarks/results/{path.name}`, written by "
           f"`python benchmarks/{script}.py`; {stamp}.", "", about, ""]
    scalars = {k: v for k, v in data.items() if k not in STAMP_KEYS and _scalar(v)}
    if scalars:
        out += [*_table([{"entry": k, "value": v} for k, v in scalars.items()]), ""]
    for k, v in data.items():
        if k in STAMP_KEYS or k in scalars:
            continue
        out += _value(k, v, 3)
    return out


def render(results: Path) -> str:
    """The whole page: the introduction and one section per results file."""
    lines = [INTRO]
    for path in sorted([*results.glob("*.json"), *results.glob("*.md")]):
        lines += section(path)
    return "\n".join(lines) + "\n"
