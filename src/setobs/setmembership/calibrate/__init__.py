"""Which noise bound fits my data? One sparse LP over the whole record.

The record ``y_0 .. y_(N-1)`` is consistent with the model

    x[k+1] = Phi x[k] + Gamma u[k] + G d[k] + w[k],    |w[k]| <= r_w   (optional)
    d[k+1] = d[k] + dd[k],                             |dd[k]| <= beta r_dd
    y[k]   = Xi x[k] + Du u[k] + v[k],                 |v[k]|  <= alpha r_v

for given increment and process-noise boxes exactly when some trajectory
``(x_k, d_k)`` satisfies all these (in)equalities: a linear feasibility problem
in ``(x, d)``. The smallest consistent noise scale ``alpha`` (or per-channel
radii) is therefore one linear program over the whole record, sparse and
banded, solved on centred, scaled data by an interior-point method (Clarabel)
with checked answers and a fallback chain. This is the same consistency the exact SMFDO decides
step by step (its set becomes empty exactly when no trajectory exists), which
the tests check by bisection.
"""

from ._noise import (
    MAX_OUTLIER_CANDIDATES,
    PADDING_WARN,
    SAFETY_MARGIN,
    calibrate_noise,
    noise_tradeoff,
)
from ._outcomes import NoiseCalibration, NoiseTradeoff, Outlier

__all__ = ["MAX_OUTLIER_CANDIDATES", "PADDING_WARN", "SAFETY_MARGIN", "NoiseCalibration",
           "NoiseTradeoff", "Outlier", "calibrate_noise", "noise_tradeoff"]
