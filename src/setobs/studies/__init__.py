"""Studies: scenarios, Monte Carlo campaigns (local processes or Dask), results tables."""

from .campaign import OBSERVER_KINDS, CampaignResult, ObserverSpec, run_campaign, run_one
from .sampling import ErrorOrders, error_orders
from .scenarios import EXAMPLE_SYSTEMS, GENERATORS, Scenario, Trajectory, rng_for_run

__all__ = [
    "EXAMPLE_SYSTEMS",
    "GENERATORS",
    "OBSERVER_KINDS",
    "CampaignResult",
    "ErrorOrders",
    "ObserverSpec",
    "Scenario",
    "Trajectory",
    "error_orders",
    "rng_for_run",
    "run_campaign",
    "run_one",
]
