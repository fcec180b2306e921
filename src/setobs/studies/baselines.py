"""Fair baselines for the SMFDO: the Kalman filter, a PIO tuned over its poles, and CIs.

Li-Cong-Dong (Fig. 1(b)) compare the SMFDO with a PIO at printed gains that turn
out unstable; a comparison a reader can trust needs baselines that work, on the
same information (``y_0..y_k`` for the estimate at ``k``, as the SMFDO), with
the spread over runs stated:

* :func:`kalman_baseline` — the steady-state Kalman filter of the augmented
  model ``(x, d)``, from the scenario's increment and measurement covariances;
* :func:`pio_pole_sweep` — the PIO's mean error against the radius of its
  (real, clustered) error poles, with t-confidence intervals over runs, and the
  best radius on *training* runs (so that the evaluation runs do not tune it);
* :meth:`~setobs.studies.CampaignResult.improvement` — ``1 - mean_A / mean_B``
  with a bootstrap interval over runs.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..exceptions import InvalidValueError
from ..tolerances import KALMAN_MEASUREMENT_FLOOR
from .scenarios import Scenario, rng_for_run

__all__ = ["PoleSweep", "cluster_poles", "kalman_baseline", "pio_pole_sweep"]


def kalman_baseline(scenario: Scenario, sys: Any = None, *, information: str = "filtered",
                    measurement_cov: float | None = None) -> Any:
    """The steady-state Kalman filter of the scenario's plant, as a :class:`~setobs.observers.PIO`.

    The augmented model ``(x, d)`` with ``d(k+1) = d(k) + dd(k)`` gets the
    covariance of the scenario's increments: ``r^2 / 3`` per channel for the
    uniform ``random_walk`` increments of radius ``r`` (also used for the other
    generators, as a design choice); the measurement covariance is
    ``noise_std^2``, or, for noise-free scenarios,
    ``KALMAN_MEASUREMENT_FLOOR * r^2`` (a Kalman gain needs a positive
    definite one; the filter's error barely changes below it, see notebook 03).
    ``design="lqe"`` of :class:`~setobs.observers.PIO` computes the predictor
    gain; ``information="filtered"`` reads ``d_hat(k|k) = d_hat(k+1|k)``.

    Parameters
    ----------
    scenario : Scenario
        The plant and disturbance.
    sys : LinearSystem, optional
        The scenario's system (built if not given).
    information : {"filtered", "predicted"}
        See :class:`~setobs.observers.PIO`.
    measurement_cov : float, optional
        Overrides the measurement covariance (scalar, times ``I``).

    Returns
    -------
    setobs.observers.PIO
        Named ``"Kalman filter"``.
    """
    from ..observers import PIO

    sys = scenario.build_system() if sys is None else sys
    r = float(scenario.increment)
    if measurement_cov is None:
        measurement_cov = (scenario.noise_std ** 2 if scenario.noise_std > 0
                           else KALMAN_MEASUREMENT_FLOOR * r * r)
    if not measurement_cov > 0:
        raise InvalidValueError(f"measurement_cov must be positive, got {measurement_cov}")
    obs = PIO(sys, design="lqe", increment_cov=r * r / 3.0, measurement_cov=measurement_cov,
              information=information)
    obs.name = "Kalman filter"
    return obs


def cluster_poles(radius: float, count: int, spread: float = 0.05) -> NDArray[np.float64]:
    """``count`` distinct real poles evenly spread over ``[radius - spread, radius + spread]``.

    Parameters
    ----------
    radius : float
        Centre of the cluster, in ``(spread, 1 - spread)``.
    count : int
        Number of poles.
    spread : float
        Half-width of the cluster.
    """
    if not spread < radius < 1.0 - spread:
        raise InvalidValueError(f"radius must lie in ({spread}, {1.0 - spread}), got {radius}")
    if count == 1:
        return np.array([float(radius)])
    return np.linspace(radius - spread, radius + spread, int(count))


@dataclass(frozen=True)
class PoleSweep:
    """Mean error of the PIO against the radius of its error poles.

    Attributes
    ----------
    table : pandas.DataFrame
        One row per radius: ``radius, mean, ci_low, ci_high, runs`` (the mean over
        runs of the per-run mean ``error_inf`` over ``k >= start``, with a
        two-sided t-interval at ``confidence``).
    per_run : ndarray, shape (n_radii, runs)
        The per-run means.
    best_radius : float
        The radius with the smallest mean.
    spread : float
        Half-width of the pole cluster.
    information : str
        ``"filtered"`` or ``"predicted"``.
    confidence : float
        Confidence level of the intervals.
    """

    table: Any
    per_run: NDArray[np.float64]
    best_radius: float
    spread: float
    information: str
    confidence: float

    def observer(self, sys: Any, radius: float | None = None) -> Any:
        """The PIO at ``radius`` (default :attr:`best_radius`), named ``"PIO (tuned)"``.

        Parameters
        ----------
        sys : LinearSystem
            The plant.
        radius : float, optional
            Pole radius.
        """
        from ..observers import PIO

        r = self.best_radius if radius is None else radius
        obs = PIO(sys, poles=cluster_poles(r, sys.n + sys.q, self.spread),
                  information=self.information)
        obs.name = "PIO (tuned)"
        return obs


def pio_pole_sweep(scenario: Scenario, radii: Sequence[float], runs: int = 20, *,
                   base_seed: int = 1, start: int = 10, spread: float = 0.05,
                   information: str = "filtered", confidence: float = 0.95) -> PoleSweep:
    """The PIO's mean error over runs against the radius of its error poles.

    For each radius the PIO's ``n + q`` error poles are placed at
    :func:`cluster_poles` (real, distinct, within ``spread``); every PIO runs on
    the same ``runs`` simulated records (streams ``rng_for_run(base_seed, run)``:
    choose a ``base_seed`` different from the evaluation campaign's, so the
    tuning does not see the evaluation data).

    Parameters
    ----------
    scenario : Scenario
        Plant, disturbance and noise.
    radii : sequence of float
        Pole radii in ``(spread, 1 - spread)``.
    runs : int
        Records per radius (at least 2, for the intervals).
    base_seed : int
        Seed of the records.
    start : int
        First step counted.
    spread : float
        Half-width of each pole cluster.
    information : {"filtered", "predicted"}
        See :class:`~setobs.observers.PIO`.
    confidence : float
        Level of the t-intervals.

    Returns
    -------
    PoleSweep
    """
    import pandas as pd
    from scipy import stats

    from ..observers import PIO

    if int(runs) != runs or runs < 2:
        raise InvalidValueError(f"runs must be an integer >= 2, got {runs!r}")
    if not 0 < confidence < 1:
        raise InvalidValueError(f"confidence must be in (0, 1), got {confidence}")
    radii = [float(r) for r in radii]
    if not radii:
        raise InvalidValueError("radii must not be empty")
    sys = scenario.build_system()
    observers = [PIO(sys, poles=cluster_poles(r, sys.n + sys.q, spread), information=information)
                 for r in radii]
    per_run = np.empty((len(radii), int(runs)))
    for j in range(int(runs)):
        tr = scenario.simulate(rng_for_run(base_seed, j))
        for i, obs in enumerate(observers):
            err = np.abs(obs.run(tr.Y, tr.U).estimate - tr.D).max(axis=1)
            per_run[i, j] = float(np.mean(err[start:]))
    mean = per_run.mean(axis=1)
    half = stats.t.ppf(0.5 + confidence / 2, runs - 1) * per_run.std(axis=1, ddof=1) \
        / np.sqrt(runs)
    table = pd.DataFrame({"radius": radii, "mean": mean, "ci_low": mean - half,
                          "ci_high": mean + half, "runs": int(runs)})
    return PoleSweep(table, per_run, radii[int(np.argmin(mean))], float(spread), information,
                     float(confidence))
