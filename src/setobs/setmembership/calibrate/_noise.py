"""The calibration's entry points: :func:`calibrate_noise` (the smallest consistent bound,
validated on a held-out part, outliers, the recommended radii, the witness check) and
:func:`noise_tradeoff`, with their argument checks."""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._validation import as_inputs, as_matrix, as_vector, check_real_scalar
from ...exceptions import ArgumentError, DimensionError, InvalidValueError, SolverWarning
from ...geometry import Box
from ...models.linear import DisturbanceInputs, LinearSystem, require_system
from ...tolerances import CALIBRATION_ACTIVE_RTOL, CALIBRATION_ATOL, CALIBRATION_RTOL
from ._outcomes import NoiseCalibration, NoiseTradeoff, Outlier
from ._record_lp import LPSolution, RecordLP, worse
from ._witness import witness_noise

__all__ = ["MAX_OUTLIER_CANDIDATES", "PADDING_WARN", "SAFETY_MARGIN", "calibrate_noise",
           "noise_tradeoff"]


def _radii(name: str, value: Any, dim: int) -> NDArray[np.float64]:
    """Per-channel radii from a scalar, a vector or a symmetric Box."""
    if isinstance(value, Box):
        if not (np.allclose(value.lo, -value.hi) and np.isfinite(value.hi).all()):
            raise InvalidValueError(f"{name}: calibration takes boxes centred at 0; got "
                                 f"[{value.lo}, {value.hi}]")
        value = value.hi
    if value is None or isinstance(value, str | bytes) or callable(value) or hasattr(value, "G"):
        raise ArgumentError(f"{name} must be per-channel radii (a number or a vector) or a "
                            f"symmetric Box, got {type(value).__name__}")
    r = np.asarray(value, dtype=float)
    if r.ndim == 0:
        r = np.full(dim, float(r))
    r = as_vector(name, r, size=dim)
    if (r < 0).any() or not np.isfinite(r).all():
        raise InvalidValueError(f"{name} radii must be finite and nonnegative, got {r}")
    return r


def _setup(sys, Y, U, increment, shape, process_noise, disturbance_inputs):
    """Validated inputs of both entry points: the system, the record's LP, the
    increment radii and the noise shape."""
    sys, Ya, Ua = _prepare(sys, Y, U, disturbance_inputs)
    inc = _radii("increment", increment, sys.q)
    w = None if process_noise is None else _radii("process_noise", process_noise, sys.n)
    return sys, RecordLP(sys, Ya, Ua, w), inc, _shape(shape, sys.l)


def _prepare(sys, Y, U, disturbance_inputs):
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    Ya = as_matrix("Y", Y, cols=sys.l, allow_nan=True)
    Ua = as_inputs(sys.p, U)
    if Ua is not None:
        if Ua.shape[0] < Ya.shape[0] - 1 or (np.any(sys.Du != 0) and Ua.shape[0] < Ya.shape[0]):
            raise DimensionError(f"U must have N = {Ya.shape[0]} rows (N - 1 without a "
                                 f"feedthrough), got {Ua.shape[0]}")
    if not np.isfinite(Ya).any():
        raise InvalidValueError("Y has no measured (finite) entry")
    return sys, Ya, Ua


#: Relative safety the recommended radii of a validated calibration add to
#: ``validated``: a bound that is attained exactly collapses a band there (see
#: :func:`calibrate_noise`'s notes; on the motor record, 10 % leaves a narrowest
#: velocity band of 0.4-0.8 rad/s where the smallest bound leaves 0.02-0.05).
SAFETY_MARGIN = 0.1


def calibrate_noise(sys: LinearSystem, Y: ArrayLike, U: ArrayLike | None = None, *,
                    increment: Any, shape: Any = None, per_channel: bool = False,
                    process_noise: Any = None,
                    disturbance_inputs: DisturbanceInputs = None,
                    time_limit: float = 120.0, holdout: float = 0.3,
                    max_outliers: int = 0,
                    safety: float = SAFETY_MARGIN) -> NoiseCalibration:
    """The smallest measurement-noise bound that makes a record consistent, calibrated on
    the first part of the record and validated on the rest.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The model (a ``StateSpace`` with ``disturbance_inputs``).
    Y : array_like, shape (N, l)
        The record; NaN entries are not measured.
    U : array_like, shape (N, p), optional
        Inputs (required when the system has inputs; ``U[k]`` acts between
        ``y_k`` and ``y_(k+1)``, as in :meth:`SMFDO.run`).
    increment : float, array_like or Box
        Increment radii ``r_dd`` (``|d_(k+1) - d_k| <= r_dd``), as for the SMFDO.
    shape : float, array_like or Box, optional
        Noise shape ``r_v``: the result is the smallest ``alpha`` with
        ``|v_k| <= alpha r_v`` (default ``r_v = 1`` on every channel).
    per_channel : bool
        Instead of a scaling, per-channel radii ``s`` minimising
        ``sum_i s_i / r_v,i`` (one point of the Pareto set: the channels trade
        off against each other through the shared trajectory).
    process_noise : float, array_like or Box, optional
        Process-noise radii ``|w_k| <= r_w`` (state space, identity matrix).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances; the others are control inputs.
    time_limit : float
        Seconds each solver of the chain may take (a hard limit; default 120).
    holdout : float
        Fraction of the record (its last samples) held out to validate the bound
        (default 0.3; 0: calibrate on the whole record, no validation).
    max_outliers : int
        Up to this many samples removed, one at a time, each the one whose removal
        lowers the first part's smallest bound most (re-solving for each candidate among
        the samples where the bound is attained); named in ``outliers`` (default 0).
    safety : float
        Relative safety the recommended ``radii`` add to ``validated`` (default
        ``SAFETY_MARGIN`` = 0.1, see the notes; 0: the radii are ``validated``, and a
        band may collapse where it is attained). Ignored with ``holdout=0``.

    Returns
    -------
    NoiseCalibration
        ``minimal`` (the first part's smallest bound), ``validated`` (the smallest
        bound, at least ``minimal``, with which the whole record is consistent when the
        first part keeps ``minimal``), ``margin`` (``validated / minimal - 1``),
        ``radii`` (``validated (1 + safety)``, padded and checked on the whole
        record: the bound to use), ``active_samples``,
        ``outliers``, ``scale``, ``worst_step``;
        :meth:`NoiseCalibration.describe` says it in words.

    Raises
    ------
    SolverError
        If no solver of the chain returns a checked optimum (never a silent answer).

    Warns
    -----
    SolverWarning
        When the answer comes from a solve at reduced accuracy (``status`` is
        ``"almost optimal"``): the bound is still consistent, perhaps not the smallest.

    Notes
    -----
    *Validation.* "Calibrated on 70 % of the record, the bound needed a margin of
    ``m`` to explain the other 30 %": ``minimal`` is the smallest bound of the first
    ``1 - holdout`` of the record; ``validated`` the smallest bound for the rest, the
    first part keeping ``minimal`` (the same LP on the whole record, the first part's
    rows at ``minimal``, the rest's at a variable bound of at least ``minimal``). The
    default ``holdout = 0.3`` is there so that a band does not collapse: at the
    smallest bound of a record the bound is attained somewhere (an active sample), and
    there the consistent set is pinned to a point and its band to a width near zero
    (the motor record at its minimum of 2.68 counts: velocity bands of 0.02 rad/s that
    miss an independent velocity). ``validated`` is itself the smallest bound of a
    problem, so some sample attains it and its band collapses there too (the motor
    record: 2.68 counts, the whole record's minimum, set by glitches in its last
    third). The recommended ``radii`` are therefore ``validated (1 + safety)``,
    by default 10 % above it, so that no sample sits exactly at the bound (the motor record: 2.94
    counts, narrowest velocity band 0.83 rad/s against 0.02 at the minimum, every band
    consistent with a central-difference velocity and its own error bound). Applying
    the measured margin once more instead ("what the last 30 % needed, allowed again
    for data not yet seen") gave 14 times the minimum on a 25-sample record: the margin
    is reported, not compounded. With ``holdout=0`` the radii are the whole record's
    minimum, padded only for the solver's accuracy.

    Consistency is the exact SMFDO's (Li-Cong-Dong, Algorithm 1 with
    ``delta`` = the whole record, eqs. (20)-(21) with noise): the posterior set
    is empty exactly when no trajectory ``(x_k, d_k)`` explains the data within
    the sets, which is the LP's feasibility. A windowed SMFDO forgets old data
    and may accept a smaller bound.

    The LP is solved on centred, scaled data (see ``RecordLP``) by a solver chain
    that ends in a checked answer or a :class:`SolverError` (Clarabel, then
    Clarabel with robust settings, then HiGHS's interior point); ``info`` names
    the solver, the dual lower bound and the attempts passed over.

    The recommended ``radii`` are ``target (1 + CALIBRATION_RTOL) +
    CALIBRATION_ATOL * spread`` (``target``: ``validated (1 + safety)``, or ``minimal``
    with ``holdout=0``), then checked, with ``spread`` the largest deviation of a
    measured output from the record's equilibrium (``info["data_scale"]``): a
    record that the model explains exactly (no noise at all) gets radii of about
    ``1e-9 spread``, not 0 -- the solver's accuracy, not a noise level.

    Examples
    --------
    >>> import numpy as np, setobs as so
    >>> sys = so.LinearSystem([[1.0]], [[1.0]], [[1.0]])
    >>> Y = np.array([[0.0], [1.0], [0.0], [1.0]])     # alternating: |dd| <= 0 fits with noise 1/2
    >>> round(float(calibrate_noise(sys, Y, increment=0.0).minimal[0]), 6)
    0.5
    """
    sys, Ya, Ua = _prepare(sys, Y, U, disturbance_inputs)
    inc = _radii("increment", increment, sys.q)
    w = None if process_noise is None else _radii("process_noise", process_noise, sys.n)
    r_v = _shape(shape, sys.l)
    limit = _time_limit(time_limit)
    N = Ya.shape[0]
    split = _split(Ya, holdout)
    k_out = _max_outliers(max_outliers)
    safety = check_real_scalar("safety", safety, nonnegative=True)
    wmax = float(np.max(r_v))
    ignore = np.zeros(N, dtype=bool)

    def fit(ignored):
        """The first part's LP (without the ignored samples): (lp, solution, bound)."""
        Yf = Ya if split is None else Ya[:split]
        Yf = np.where(ignored[:Yf.shape[0], None], np.nan, Yf)
        if not np.isfinite(Yf).any():
            raise InvalidValueError("no measured sample is left in the calibrated part")
        Uf = Ua if (Ua is None or split is None) else Ua[:split]
        lp = RecordLP(sys, Yf, Uf, w)
        sol = lp.solve(inc, r_v, per_channel, limit)
        return lp, sol, radii_of(lp, sol)

    def radii_of(lp, sol):
        """The radii of the LP's noise variable (per channel, or a scale of the shape)."""
        return sol.v * lp.sigma if per_channel else float(sol.v[0]) * lp.sigma / wmax * r_v

    def objective(bound):
        return float(np.sum(bound / r_v))

    lp_f, res_f, minimal = fit(ignore)
    outliers: list[Outlier] = []
    for _ in range(k_out):  # greedy: the active sample whose removal lowers the bound most
        best = None
        for k in _active(lp_f, res_f, minimal)[:MAX_OUTLIER_CANDIDATES]:
            trial = ignore.copy()
            trial[k] = True
            try:
                cand = fit(trial)
            except InvalidValueError:  # (no measured sample left in the calibrated part)
                continue
            if best is None or objective(cand[2]) < objective(best[1][2]):
                best = (k, cand)
        if best is None or objective(best[1][2]) >= objective(minimal) * (1.0 - 1e-9):
            break
        k, cand = best
        outliers.append(Outlier(int(k), minimal, cand[2]))
        ignore[k] = True
        lp_f, res_f, minimal = cand
    scale = None if per_channel else float(minimal[0] / r_v[0])
    active = _active(lp_f, res_f, minimal)
    # the whole record with the first part's bound: the smallest bound of the rest
    val_active = np.zeros(0, dtype=np.int64)
    if split is None:
        lp, res, validated = lp_f, res_f, minimal
    else:
        Yw = np.where(ignore[:, None], np.nan, Ya)
        lp = RecordLP(sys, Yw, Ua, w)
        fixed = np.where(lp.kk < split, minimal[lp.ii] / lp.sigma, np.nan)
        lower = (minimal / lp.sigma if per_channel or scale is None
                 else np.array([scale * wmax / lp.sigma]))
        res = lp.solve(inc, r_v, per_channel, limit, fixed=fixed, lower=lower)
        validated = np.maximum(minimal, radii_of(lp, res))
        # within the LP's accuracy of minimal: no margin (the radii are checked below)
        validated = np.where(validated <= minimal * (1.0 + CALIBRATION_ACTIVE_RTOL), minimal,
                             validated)
        if np.any(validated > minimal):
            held = _active(lp, res, validated)
            val_active = held[held >= split]
    # the bound to use: validated with a safety, so that no sample sits exactly at it
    target = validated if split is None else validated * (1.0 + safety)
    standard = target + (CALIBRATION_RTOL * target + CALIBRATION_ATOL * lp.sigma)
    # the check: the noise an exactly consistent trajectory needs (see witness_noise)
    need, wit = witness_noise(lp, res.x, inc)
    status = worse(res_f.status, res.status)
    if np.isfinite(need).all():
        # per channel, or (a scale) the same multiple of the shape on every channel
        cand = need if per_channel else np.nextafter(
            float(np.max(need / r_v)) * (1.0 + 4.0 * np.finfo(float).eps) * r_v, np.inf)
        radii = standard if np.all(cand <= standard) else np.maximum(standard, cand)
        padding = float(np.max(radii / np.where(standard > 0, standard, 1.0) - 1.0))
    else:
        radii, padding = standard, float("nan")
        status = "unverified"
    resid = np.abs(lp_f.yout - lp_f.Mout @ res_f.x)
    worst = np.zeros(sys.l, dtype=np.int64)
    for i in range(sys.l):
        sel = lp_f.ii == i
        if sel.any():
            worst[i] = int(lp_f.kk[sel][np.argmax(resid[sel])])
    lower_b = res_f.lower * lp_f.sigma / (1.0 if per_channel else wmax)
    info = {"objective": objective(minimal) if per_channel else scale,
            "lower_bound": float(lower_b), "solver": res_f.solver,
            "failed_attempts": res_f.failed + (() if res is res_f else res.failed),
            "data_scale": lp.sigma, "refined": res_f.refined and res.refined,
            "verified_noise": need, "padding": padding, **wit}
    if status == "unverified":
        warnings.warn("calibrate_noise: the recommended radii could not be checked against "
                      "an exactly consistent trajectory (the plant is too unstable over "
                      f"{lp.N} samples for the check: drift bound {wit['drift_bound']:.3g}); "
                      "they are the LP optimum padded by CALIBRATION_RTOL and "
                      "CALIBRATION_ATOL, unverified: check them with the SMFDO, or calibrate "
                      "a shorter record", SolverWarning, stacklevel=2)
    elif padding > PADDING_WARN:
        warnings.warn(f"calibrate_noise: the recommended radii are {padding:.3g} (relative) "
                      "above the LP optimum's usual padding: the exactly consistent "
                      "trajectory that checks them needs that much more (a long record of "
                      "an unstable or marginally stable plant); they are consistent, the "
                      "optimum may be less accurate", SolverWarning, stacklevel=2)
    elif status != "optimal":
        warnings.warn(f"calibrate_noise: {res_f.solver} returned an inaccurate optimum "
                      f"({status}); the recommended radii are checked against an "
                      "exactly consistent trajectory and make the record consistent, but "
                      "may not be the smallest", SolverWarning, stacklevel=2)
    return NoiseCalibration(
        radii, minimal, scale, inc, worst, lp.samples, status, info, validated=validated,
        active_samples=active, outliers=tuple(outliers),
        validated_samples=val_active,
        holdout=0.0 if split is None else float(holdout), split=split, record_length=N,
        dt=sys.dt, output_names=tuple(sys.output_names),
        safety=0.0 if split is None else float(safety))


#: Candidates :func:`calibrate_noise` tries per outlier round (the active samples with
#: the largest residuals; each costs one LP).
MAX_OUTLIER_CANDIDATES = 8


def _active(lp: RecordLP, sol: LPSolution, bound: NDArray[np.float64]) -> NDArray[np.int64]:
    """The samples at which the LP's trajectory attains the bound (its active rows),
    the largest residuals (relative to the bound) first."""
    r = np.abs(lp.yout - lp.Mout @ sol.x) * lp.sigma
    b = bound[lp.ii]
    tol = CALIBRATION_ACTIVE_RTOL * b + CALIBRATION_ATOL * lp.sigma
    hit = (r >= b - tol) & (b > 0)
    if not hit.any():
        return np.zeros(0, dtype=np.int64)
    rel = r[hit] / b[hit]
    ks = lp.kk[hit][np.argsort(-rel, kind="stable")]
    _, first = np.unique(ks, return_index=True)
    return ks[np.sort(first)].astype(np.int64)


def _split(Y: NDArray[np.float64], holdout: float) -> int | None:
    """The first held-out row for ``holdout`` (a fraction in ``[0, 1)``), or ``None``."""
    h = check_real_scalar("holdout", holdout, nonnegative=True)
    if h >= 1.0:
        raise InvalidValueError(f"holdout must be a fraction in [0, 1), got {holdout!r}")
    if h == 0.0:
        return None
    N = Y.shape[0]
    split = max(1, min(int(np.ceil((1.0 - h) * N)), N - 1))  # (both parts nonempty)
    meas = np.asarray(np.isfinite(Y).any(axis=1))
    if N < 2 or not meas[:split].any() or not meas[split:].any():
        raise InvalidValueError(
            f"holdout={holdout!r} leaves no measured sample in one of the parts of a "
            f"{N}-sample record (calibrated: rows 0-{split - 1}); use a longer record or "
            "holdout=0 (no validation)")
    return split


def _max_outliers(value: Any) -> int:
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or value < 0:
        raise InvalidValueError(f"max_outliers must be a nonnegative integer, got {value!r}")
    return int(value)


def _shape(shape: Any, l: int) -> NDArray[np.float64]:
    r_v = np.ones(l) if shape is None else _radii("shape", shape, l)
    if (r_v <= 0).any():
        raise InvalidValueError(f"shape radii must be positive, got {r_v}")
    return r_v


#: Padding of the recommended radii beyond the usual (relative) above which
#: :func:`calibrate_noise` warns.
PADDING_WARN = 1e-3


def _time_limit(value: float) -> float:
    t = float(value)
    if not (t > 0.0):
        raise InvalidValueError(f"time_limit must be positive (seconds), got {value!r}")
    return t


def noise_tradeoff(sys: LinearSystem, Y: ArrayLike, U: ArrayLike | None = None, *,
                   increment: Any, betas: ArrayLike | None = None, shape: Any = None,
                   process_noise: Any = None,
                   disturbance_inputs: DisturbanceInputs = None) -> NoiseTradeoff:
    """The trade-off between the increment bound and the noise bound for a record.

    For each ``beta`` in ``betas`` (default 13 points, log-spaced over
    ``[1e-3, 1e3]``), the smallest noise scale ``alpha`` with which the record
    is consistent when ``|dd| <= beta * increment`` (one LP each, see
    :func:`calibrate_noise`). Pairs above the curve are consistent, pairs
    below are not; ``alpha`` never increases with ``beta``.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The model.
    Y : array_like, shape (N, l)
        Measurements (NaN: missing).
    U : array_like, shape (N, p), optional
        Inputs (required when the system has inputs).
    increment : array_like or Box or ConstrainedZonotope
        Shape of the increment bound ``|dd| <= beta * increment``.
    betas : array_like, optional
        Increment scales (default 13 points log-spaced over ``[1e-3, 1e3]``).
    shape : array_like, optional
        Shape of the noise bound (per-channel radii; default ones).
    process_noise : array_like or Box or ConstrainedZonotope, optional
        Bound of the process noise ``w`` (as in :class:`SMFDO`).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances; the others are control inputs.
    """
    sys, lp, inc, r_v = _setup(sys, Y, U, increment, shape, process_noise, disturbance_inputs)
    b = np.logspace(-3, 3, 13) if betas is None else np.asarray(betas, dtype=float).reshape(-1)
    if b.size == 0 or (b < 0).any() or not np.isfinite(b).all():
        raise InvalidValueError(f"betas must be finite and nonnegative, got {b}")
    wmax = float(np.max(r_v))
    order = np.argsort(b, kind="stable")
    alpha = np.empty(b.size)
    alpha[order] = [float(lp.solve(beta * inc, r_v, False).v[0]) * lp.sigma / wmax
                    for beta in b[order]]
    # A trajectory consistent at one increment scale is consistent at every larger one,
    # so the running minimum over increasing beta is still a proved consistent noise
    # level; it removes the solver-accuracy wiggle where the true curve is flat at 0.
    alpha[order] = np.minimum.accumulate(alpha[order])
    return NoiseTradeoff(b, alpha, inc, r_v, tuple(sys.output_names))
