"""The result protocol shared by every time-series result of the package.

:class:`~setobs.setmembership.SetEstimateResult`, :class:`~setobs.observers.ObserverResult`,
:class:`~setobs.compare.ComparisonTable` and
:class:`~setobs.studies.CampaignResult` all offer

* ``.estimate`` — the disturbance estimate, shape ``(N, q)`` (the SMFDO's and
  the point observers' alike);
* ``.to_pandas()`` — a ``pandas.DataFrame`` indexed by time ``k dt`` (named
  ``"time"``) when the sampling time is known, else by the step ``k``;
* ``.plot(ax=None)`` — draws on ``ax`` (default: the current axes) and returns it;
* ``.summary()`` — a ``pandas.DataFrame`` with one row per estimator (index
  ``"observer"``) and the metric columns below;
* tuple unpacking, like python-control's ``TimeResponseData``:
  ``t, estimate = observer.run(Y)`` and ``t, estimate, lo, hi = smfdo.run(Y)``.

Metric names mean one thing everywhere (tables, summaries, campaign rows):

``error_inf``, ``error_2``
    Actual error ``||d_hat_k - d_k||`` against the true disturbance (infinity
    and Euclidean norm); needs the truth.
``worst_case_error``
    ``max_{d in D_k} ||d_hat_k - d||_inf`` over the set ``D_k`` of disturbances
    consistent with the data (exact over its interval hull,
    :func:`setobs.compare.worst_case_error`).
``optimal``
    The smallest possible ``worst_case_error``: that of the interval-hull
    centre, i.e. the exact SMFDO's ``error_bound``.
``error_bound``
    An SMFDO's certified bound on its own error, ``max_i (hi_i - lo_i) / 2``
    (``>= optimal``; equal in exact mode).
``ratio``
    ``worst_case_error / optimal`` (``>= 1``).
``outside``
    The estimate lies outside the consistent set's interval hull.
``truth_inside``
    The true disturbance lies in the SMFDO's certified interval (a soundness
    check in simulation).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["METRICS", "time_axis", "time_index"]

#: The metric vocabulary (see the module docstring).
METRICS = ("error_inf", "error_2", "worst_case_error", "optimal", "error_bound", "ratio",
           "outside", "truth_inside")


def time_axis(N: int, dt: float | None) -> NDArray[np.float64]:
    """Times ``k dt`` for ``k = 0..N-1``, or the steps ``k`` when ``dt`` is unknown.

    Parameters
    ----------
    N : int
        Number of samples.
    dt : float or None
        Sampling time.

    Returns
    -------
    ndarray, shape (N,)
        The time axis.
    """
    k = np.arange(N, dtype=float)
    return k * dt if dt else k


def time_index(N: int, dt: float | None) -> Any:
    """The ``pandas`` index of a result table: ``"time"`` (``k dt``) or ``"k"``.

    Parameters
    ----------
    N : int
        Number of samples.
    dt : float or None
        Sampling time.

    Returns
    -------
    pandas.Index
        A float index named ``"time"``, or a ``RangeIndex`` named ``"k"``.
    """
    import pandas as pd

    return pd.Index(np.arange(N) * dt, name="time") if dt else pd.RangeIndex(N, name="k")


def error_summary(name: str, estimate: NDArray[np.float64], truth: Any | None,
                  start: int, extra: dict[str, Any]) -> Any:
    """One summary row (a DataFrame indexed by ``observer``) with actual errors if ``truth``."""
    import pandas as pd

    row = {"steps": int(max(estimate.shape[0] - start, 0)), **extra}
    if truth is not None:
        D = np.asarray(truth, dtype=float)
        if D.shape != estimate.shape:
            from .exceptions import DimensionError

            raise DimensionError(f"truth must have shape {estimate.shape}, got {D.shape}")
        err = estimate[start:] - D[start:]
        ok = np.all(np.isfinite(err), axis=1)
        e_inf = np.abs(err[ok]).max(axis=1) if ok.any() else np.full(1, np.nan)
        e_2 = np.linalg.norm(err[ok], axis=1) if ok.any() else np.full(1, np.nan)
        row.update({"error_inf": float(e_inf.mean()), "max_error_inf": float(e_inf.max()),
                    "error_2": float(e_2.mean())})
    return pd.DataFrame([row], index=pd.Index([name], name="observer"))
