"""Studies: scenarios, Monte Carlo campaigns (local processes or Dask), results tables."""

from .baselines import PoleSweep, cluster_poles, kalman_baseline, pio_pole_sweep
from .campaign import (
    FILTERED_KINDS,
    OBSERVER_KINDS,
    CampaignResult,
    Improvement,
    ObserverSpec,
    run_campaign,
    run_one,
)
from .sampling import ErrorOrders, error_orders
from .scenarios import (
    EXAMPLE_SYSTEMS,
    GENERATORS,
    Scenario,
    Trajectory,
    band_limited_noise,
    rng_for_run,
)

__all__ = [
    "EXAMPLE_SYSTEMS",
    "FILTERED_KINDS",
    "GENERATORS",
    "OBSERVER_KINDS",
    "CampaignResult",
    "ErrorOrders",
    "Improvement",
    "ObserverSpec",
    "PoleSweep",
    "Scenario",
    "Trajectory",
    "band_limited_noise",
    "cluster_poles",
    "error_orders",
    "kalman_baseline",
    "pio_pole_sweep",
    "rng_for_run",
    "run_campaign",
    "run_one",
]
