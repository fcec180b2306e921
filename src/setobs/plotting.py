"""Plots of sets, estimates with their interval bands, error curves and comparisons.

matplotlib is imported lazily; every function takes ``ax=None`` (current axes)
and returns what it drew.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .exceptions import InvalidValueError
from .geometry._draw import plot_set
from .results import time_axis

__all__ = ["plot_comparison_bars", "plot_error_curves", "plot_estimate_band", "plot_set",
           "plot_state_band"]


def _ax(ax):
    import matplotlib.pyplot as plt

    return plt.gca() if ax is None else ax


def plot_estimate_band(result: Any, truth: ArrayLike | None = None, component: int = 0,
                       ax: Any = None, label: str = "SMFDO", t: ArrayLike | None = None,
                       unit: str | None = None, steady_ylim: bool = True) -> Any:
    """Estimate, its certified interval ``[lo, hi]`` and the truth (like Li-Cong-Dong Fig. 1(a)).

    A result without an interval (a point observer's) draws the estimate and the truth.

    Parameters
    ----------
    result : SMFDOResult or ObserverResult
    truth : array_like, shape (N, q), optional
    component : int
        Disturbance component to draw.
    t : array_like, shape (N,), optional
        Time axis; default ``k dt`` when the result knows the sampling time
        (``result.dt``), else the step ``k``. The y label is the disturbance's
        name (``result.names``).
    ax : matplotlib.axes.Axes, optional
        Axes to draw on (default: a new figure).
    label : str
        Legend prefix of the estimate and its interval.
    unit : str, optional
        Unit of the disturbance, appended to the y label (``"tau_L [N m]"``).
    steady_ylim : bool
        Set the y range from the band after its start-up (1st-99th percentiles of
        the finite bounds, estimate and truth, plus a margin) when the start-up
        transient would otherwise squash a steady band into a line (default True).
    """
    ax = _ax(ax)
    N = result.estimate.shape[0]
    dt = getattr(result, "dt", None)
    if t is not None:
        k = np.asarray(t, dtype=float)[:N]
    else:
        k = time_axis(N, dt)
    names = getattr(result, "names", ()) or ()
    if hasattr(result, "lo"):
        lo, hi = result.lo[:, component], result.hi[:, component]
        ok = np.isfinite(lo) & np.isfinite(hi)
        ax.fill_between(k[ok], lo[ok], hi[ok], alpha=0.3, label=f"{label} interval")
    ax.plot(k, result.estimate[:, component], lw=1.2, label=f"{label} estimate")
    if truth is not None:
        ax.plot(k, np.asarray(truth)[:, component], "k--", lw=1.0, label="truth")
    ax.set_xlabel("time [s]" if t is not None or dt else "k")
    name = names[component] if len(names) > component else f"d[{component}]"
    ax.set_ylabel(f"{name} [{unit}]" if unit else name)
    ax.legend(loc="best", fontsize=7)
    if steady_ylim:
        series = [result.estimate[:, component]]
        if hasattr(result, "lo"):
            series += [result.lo[:, component], result.hi[:, component]]
        if truth is not None:
            series.append(np.asarray(truth, dtype=float)[:, component])
        lim = _steady_range(series)
        if lim is not None:
            ax.set_ylim(*lim)
    return ax


def plot_state_band(result: Any, component: int = 0, axes: Any = None, *,
                    truth: ArrayLike | None = None, truth_error: ArrayLike | None = None,
                    t: ArrayLike | None = None, unit: str | None = None,
                    truth_label: str = "truth") -> Any:
    """A certified state band a person can read: the band's centre with the band on
    top, and below it the band around its centre (``lo - centre``, ``hi - centre``,
    i.e. minus and plus the half-width) with the truth's deviation from the centre.

    A state such as a motor angle spans thousands of radians while its band is a
    fraction of one: drawn on the state's own axis the band is a line. The lower
    panel shows what the guarantee says (how wide, and whether a reference lies
    inside).

    Parameters
    ----------
    result : SMFDOResult
        A result with state bounds (``state_bounds=True``).
    component : int
        State component to draw.
    axes : pair of matplotlib Axes, optional
        Where to draw (default: a new figure with two panels sharing the time axis).
    truth : array_like, shape (N,) or (N, n), optional
        A reference for the state (the true state in a simulation, an independent
        measurement on a record); with shape ``(N, n)`` its column ``component``.
    truth_error : array_like, shape (N,), optional
        The reference's own error bound, drawn in the lower panel as a grey region
        around the reference's deviation.
    t : array_like, shape (N,), optional
        Time axis (default ``k dt`` from the result's sampling time, else ``k``).
    unit : str, optional
        The state's unit, in both y labels (``"omega [rad/s]"``).
    truth_label : str
        Legend label of the reference.

    Returns
    -------
    tuple of matplotlib Axes
        The two panels.
    """
    import matplotlib.pyplot as plt

    from .exceptions import DimensionError

    lo_all, hi_all = getattr(result, "state_lo", None), getattr(result, "state_hi", None)
    if lo_all is None or hi_all is None:
        raise InvalidValueError("no state bounds in this result: run the SMFDO with "
                             "state_bounds=True")
    n = lo_all.shape[1]
    if not 0 <= component < n:
        raise DimensionError(f"component must be in 0..{n - 1}, got {component}")
    if axes is None:
        _, axes = plt.subplots(2, 1, sharex=True, figsize=(8, 4.5))
    ax_top, ax_dev = axes
    N = lo_all.shape[0]
    k = (np.asarray(t, dtype=float)[:N] if t is not None
         else time_axis(N, getattr(result, "dt", None)))
    lo, hi = lo_all[:, component], hi_all[:, component]
    ok = np.isfinite(lo) & np.isfinite(hi)
    mid = np.full(N, np.nan)
    mid[ok] = 0.5 * (lo[ok] + hi[ok])
    names = tuple(getattr(result, "state_names", ()) or ())
    name = names[component] if len(names) > component else f"x{component}"
    lab = f"{name} [{unit}]" if unit else name
    ref = None
    if truth is not None:
        ref = np.asarray(truth, dtype=float)
        ref = ref[:, component] if ref.ndim == 2 else ref.reshape(-1)
        ref = ref[:N]
    ax_top.fill_between(k[ok], lo[ok], hi[ok], alpha=0.3, label="certified band")
    ax_top.plot(k, mid, lw=1.0, label="band centre")
    if ref is not None:
        ax_top.plot(k[: ref.size], ref, "k--", lw=0.8, label=truth_label)
    ax_top.set_ylabel(lab)
    ax_top.legend(loc="best", fontsize=7)
    half = np.where(ok, 0.5 * (hi - lo), np.nan)
    ax_dev.fill_between(k[ok], -half[ok], half[ok], alpha=0.3,
                        label="band - centre (+- half-width)")
    ax_dev.axhline(0.0, lw=0.6, color="0.4")
    if ref is not None:
        dev = ref - mid[: ref.size]
        if truth_error is not None:
            err = np.asarray(truth_error, dtype=float).reshape(-1)[: ref.size]
            fin = np.isfinite(dev) & np.isfinite(err)
            ax_dev.fill_between(k[: ref.size][fin], (dev - err)[fin], (dev + err)[fin],
                                color="0.5", alpha=0.25, lw=0,
                                label=f"{truth_label} +- its error bound")
        ax_dev.plot(k[: ref.size], dev, "k.", ms=1.5, label=f"{truth_label} - centre")
    ax_dev.set_ylabel(f"{name} - centre" + (f" [{unit}]" if unit else ""))
    ax_dev.set_xlabel("time [s]" if t is not None or getattr(result, "dt", None) else "k")
    ax_dev.legend(loc="best", fontsize=7)
    lim = _steady_range([half, -half])
    if lim is not None:
        ax_dev.set_ylim(*lim)
    return ax_top, ax_dev


def _steady_range(series: list[ArrayLike], startup: float = 0.05,
                 squash: float = 3.0) -> tuple[float, float] | None:
    """A y range that shows the steady part of time series, or ``None`` if the full
    range already does.

    The range spans the 1st to 99th percentiles of the finite values after the first
    ``startup`` fraction of the samples, widened by 10 % on each side; it is returned
    only when the full range of the finite values is more than ``squash`` times it
    (a start-up transient that would squash the steady band into a line).

    Parameters
    ----------
    series : list of array_like, each shape (N,)
        The curves drawn (estimate, bounds, truth).
    startup : float
        Fraction of the samples treated as start-up.
    squash : float
        How much wider the full range must be before the steady range is used.
    """
    arrs = [np.asarray(x, dtype=float).reshape(-1) for x in series]
    full = np.concatenate([a[np.isfinite(a)] for a in arrs]) if arrs else np.zeros(0)
    tails = [a[int(startup * a.size):] for a in arrs]
    steady = np.concatenate([t[np.isfinite(t)] for t in tails])
    if full.size == 0 or steady.size == 0:
        return None
    lo, hi = np.percentile(steady, [1.0, 99.0])
    width = hi - lo
    if not width > 0:
        width = max(abs(lo), 1.0) * 1e-3
    if full.max() - full.min() <= squash * width:
        return None
    return float(lo - 0.1 * width), float(hi + 0.1 * width)


def plot_error_curves(table: Any, metric: str = "error_inf", ax: Any = None, *,
                      logy: bool = True) -> Any:
    """Mean of ``metric`` over runs, per step and observer (like Li-Cong-Dong Fig. 1(b)).

    Parameters
    ----------
    table : pandas.DataFrame
        A campaign table (:attr:`CampaignResult.table`).
    metric : str
        A metric column (see :mod:`setobs.results`).
    ax : matplotlib Axes, optional
        Where to draw (default the current axes).
    logy : bool
        Logarithmic axis.
    """
    ax = _ax(ax)
    mean = table.groupby(["observer", "k"], sort=False)[metric].mean().unstack(0)
    for name in mean.columns:
        ax.plot(mean.index, mean[name], label=name)
    if logy:
        ax.set_yscale("log")
    ax.set_xlabel("k")
    ax.set_ylabel(f"mean {metric}")
    ax.legend(loc="best", fontsize=7)
    return ax


def plot_comparison_bars(table: Any, metric: str = "error_inf", start: int = 10,
                         ax: Any = None) -> Any:
    """Mean ``metric`` per observer over steps ``k >= start``, as bars.

    Parameters
    ----------
    table : pandas.DataFrame
        A campaign table.
    metric : str
        A metric column.
    start : int
        First step counted.
    ax : matplotlib Axes, optional
        Where to draw (default the current axes).
    """
    ax = _ax(ax)
    t = table[table["k"] >= start]
    mean = t.groupby("observer", sort=False)[metric].mean()
    ax.bar(range(len(mean)), mean.to_numpy())
    ax.set_xticks(range(len(mean)), list(mean.index), rotation=20, fontsize=7)
    ax.set_yscale("log")
    ax.set_ylabel(f"mean {metric} (k >= {start})")
    return ax
