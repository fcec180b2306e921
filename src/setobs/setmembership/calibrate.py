"""Which noise bound fits my data? One sparse LP over the whole record.

The record ``y_0 .. y_(N-1)`` is consistent with the model

    x[k+1] = Phi x[k] + Gamma u[k] + G d[k] + w[k],    |w[k]| <= r_w   (optional)
    d[k+1] = d[k] + dd[k],                             |dd[k]| <= beta r_dd
    y[k]   = Xi x[k] + Du u[k] + v[k],                 |v[k]|  <= alpha r_v

for given increment and process-noise boxes exactly when some trajectory
``(x_k, d_k)`` satisfies all these (in)equalities: a linear feasibility problem
in ``(x, d)``. The smallest consistent noise scale ``alpha`` (or per-channel
radii) is therefore one linear program over the whole record, sparse and
banded, solved by HiGHS. This is the same consistency the exact SMFDO decides
step by step (its set becomes empty exactly when no trajectory exists), which
the tests check by bisection.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple

import numpy as np
import scipy.sparse as sp
from numpy.typing import ArrayLike, NDArray

from .._validation import as_matrix, as_vector
from ..exceptions import DimensionError, SolverError
from ..geometry import Box
from ..systems import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import CALIBRATION_ATOL, CALIBRATION_RTOL

__all__ = ["NoiseCalibration", "NoiseTradeoff", "calibrate_noise", "noise_tradeoff"]


@dataclass(frozen=True)
class NoiseCalibration:
    """Result of :func:`calibrate_noise`.

    Attributes
    ----------
    radii : ndarray, shape (l,)
        Recommended per-channel measurement-noise radii: the LP optimum moved
        outward by ``CALIBRATION_RTOL`` (relative) and ``CALIBRATION_ATOL``
        (absolute, the solver's feasibility tolerance), so that the record is
        consistent with them.
    minimal : ndarray, shape (l,)
        The LP optimum itself (the smallest consistent radii, to solver accuracy).
    scale : float or None
        ``alpha``: the smallest consistent multiple of ``shape`` (``None`` in
        per-channel mode).
    increment : ndarray, shape (q,)
        The increment radii used.
    worst_step : ndarray, shape (l,)
        For each channel, a step where the optimal trajectory's residual
        ``|y - Xi x - Du u|`` reaches the bound (where the data are tightest).
    samples : int
        Measured samples used (rows with at least one finite entry).
    status : str
        HiGHS's model status.
    info : dict
        Solver details (``objective``: the LP's optimal value).
    """

    radii: NDArray[np.float64]
    minimal: NDArray[np.float64]
    scale: float | None
    increment: NDArray[np.float64]
    worst_step: NDArray[np.int64]
    samples: int
    status: str
    info: dict[str, Any] = field(default_factory=dict)

    def __repr__(self) -> str:
        s = "" if self.scale is None else f", scale={self.scale:.6g}"
        return (f"NoiseCalibration(radii={np.array2string(self.radii, precision=6)}{s}, "
                f"samples={self.samples})")


@dataclass(frozen=True)
class NoiseTradeoff:
    """Result of :func:`noise_tradeoff`: for each increment scale ``beta`` (radii
    ``beta * increment``), the smallest consistent noise scale ``alpha`` (radii
    ``alpha * shape``).

    Parameters
    ----------
    beta : ndarray, shape (m,)
        Increment scales.
    alpha : ndarray, shape (m,)
        Smallest consistent noise scale for each ``beta``.
    increment : ndarray, shape (q,)
        The increment shape.
    shape : ndarray, shape (l,)
        The noise shape.
    output_names : tuple of str
        Output names (for labels).
    """

    beta: NDArray[np.float64]
    alpha: NDArray[np.float64]
    increment: NDArray[np.float64]
    shape: NDArray[np.float64]
    output_names: tuple[str, ...] = ()

    def plot(self, ax: Any = None) -> Any:
        """The trade-off curve: noise scale against increment scale (matplotlib).

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw (default the current axes).
        """
        import matplotlib.pyplot as plt

        if ax is None:
            ax = plt.gca()
        ax.plot(self.beta, self.alpha, "o-")
        ax.set_xlabel("increment bound scale beta (|dd| <= beta r_dd)")
        ax.set_ylabel("smallest consistent noise scale alpha")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_title("which bounds fit the record: consistent above the curve")
        ax.grid(True, which="both", alpha=0.3)
        return ax


def _radii(name: str, value: Any, dim: int) -> NDArray[np.float64]:
    """Per-channel radii from a scalar, a vector or a symmetric Box."""
    if isinstance(value, Box):
        if not (np.allclose(value.lo, -value.hi) and np.isfinite(value.hi).all()):
            raise DimensionError(f"{name}: calibration takes boxes centred at 0; got "
                                 f"[{value.lo}, {value.hi}]")
        value = value.hi
    if value is None or isinstance(value, str | bytes) or callable(value) or hasattr(value, "G"):
        raise TypeError(f"{name} must be per-channel radii (a number or a vector) or a "
                        f"symmetric Box, got {type(value).__name__}")
    r = np.asarray(value, dtype=float)
    if r.ndim == 0:
        r = np.full(dim, float(r))
    r = as_vector(name, r, size=dim)
    if (r < 0).any() or not np.isfinite(r).all():
        raise DimensionError(f"{name} radii must be finite and nonnegative, got {r}")
    return r


class _RecordLP:
    """The LP data of one record; re-solved for several increment scales."""

    def __init__(self, sys: LinearSystem, Y: NDArray, U: NDArray | None,
                 process_noise: NDArray | None) -> None:
        self.sys = sys
        n, q = sys.n, sys.q
        N = Y.shape[0]
        self.N = N
        nx = (n + q) * N
        self.nx = nx
        # x_k at columns k*(n+q) .. +n, d_k at +n .. +n+q
        # ---- dynamics: x_{k+1} - Phi x_k - G d_k = Gamma u_k (+ w_k)
        if N > 1:
            base = sp.kron(sp.eye(N - 1), sp.hstack([sp.csr_matrix(-sys.Phi),
                                                      sp.csr_matrix(-sys.G)]), format="csr")
            left = sp.hstack([base, sp.csr_matrix((n * (N - 1), n + q))], format="csr")
            shift = sp.kron(sp.eye(N - 1), sp.hstack([sp.eye(n), sp.csr_matrix((n, q))]))
            right = sp.hstack([sp.csr_matrix((n * (N - 1), n + q)), shift], format="csr")
            self.Mdyn = (left + right).tocsr()
            self.bu = (U[:N - 1] @ sys.Gamma.T).reshape(-1) if U is not None else np.zeros(
                n * (N - 1))
            # ---- increments: d_{k+1} - d_k
            dsel = sp.kron(sp.eye(N - 1), sp.hstack([sp.csr_matrix((q, n)), sp.eye(q)]))
            Minc = (sp.hstack([sp.csr_matrix((q * (N - 1), n + q)), dsel])
                    - sp.hstack([dsel, sp.csr_matrix((q * (N - 1), n + q))])).tocsr()
            self.Minc = Minc
        else:
            self.Minc = sp.csr_matrix((0, nx))
        self.w = process_noise
        # ---- outputs: residual r_k = y_k - Du u_k - Xi x_k for measured entries
        Yc = Y - (U[:N] @ sys.Du.T if (U is not None and sys.p) else 0.0)
        mask = np.isfinite(Yc)
        kk, ii = np.nonzero(mask)
        self.kk, self.ii = kk, ii
        cols, data, rr = [], [], []
        for j in range(n):
            cols.append(kk * (n + q) + j)
            data.append(sys.Xi[ii, j])
            rr.append(np.arange(kk.size))
        self.Mout = sp.csr_matrix((np.concatenate(data), (np.concatenate(rr),
                                   np.concatenate(cols))), shape=(kk.size, nx))
        self.yout = Yc[kk, ii]
        self.samples = int(mask.any(axis=1).sum())

    def solve(self, inc: NDArray, weights: NDArray, per_channel: bool) -> _LPSolution:
        """Minimise ``alpha`` (``|r_ki| <= alpha weights_i``) or, per channel,
        ``sum_i s_i / weights_i`` (``|r_ki| <= s_i``).

        Columns: the trajectory ``z`` (``nx``), the increments ``dd`` as bounded
        columns (``|dd| <= inc``: bounds cost the dual simplex nothing, rows
        would), then the noise variables; rows: dynamics (ranged with process
        noise), ``d_(k+1) - d_k - dd_k = 0``, and two output rows per measured
        entry. HiGHS's dual simplex with Dantzig pricing: on the 20 000-sample
        motor record 5.8 s against 10.3 s for scipy.linprog with increment rows and
        pricing (``benchmarks/calibration.py``).
        """
        import highspy

        sys, N = self.sys, self.N
        l = sys.l
        nv = 1 if not per_channel else l
        m = self.yout.size
        n_dd = self.Minc.shape[0]
        inf = highspy.kHighsInf
        if per_channel:
            S = sp.csr_matrix((np.ones(m), (np.arange(m), self.ii)), shape=(m, l))
        else:
            S = sp.csr_matrix(weights[self.ii].reshape(-1, 1))
        Zo = sp.csr_matrix((m, n_dd))
        blocks = [sp.hstack([self.Mout, Zo, S]), sp.hstack([self.Mout, Zo, -S])]
        lo = [self.yout, np.full(m, -inf)]
        hi = [np.full(m, inf), self.yout]
        if N > 1:
            blocks.append(sp.hstack([self.Minc, -sp.eye(n_dd), sp.csr_matrix((n_dd, nv))]))
            lo.append(np.zeros(n_dd))
            hi.append(np.zeros(n_dd))
            Mdyn, bu = self.Mdyn, self.bu
            blocks.append(sp.hstack([Mdyn, sp.csr_matrix((Mdyn.shape[0], n_dd + nv))]))
            rw = 0.0 if self.w is None else np.tile(self.w, N - 1)
            lo.append(bu - rw)
            hi.append(bu + rw)
        A = sp.vstack(blocks).tocsc()
        ncol = self.nx + n_dd + nv
        c = np.zeros(ncol)
        c[self.nx + n_dd:] = 1.0 if not per_channel else 1.0 / np.maximum(weights, 1e-300)
        col_lo = np.full(ncol, -inf)
        col_hi = np.full(ncol, inf)
        r = np.tile(inc, N - 1) if N > 1 else np.zeros(0)
        col_lo[self.nx:self.nx + n_dd], col_hi[self.nx:self.nx + n_dd] = -r, r
        col_lo[self.nx + n_dd:] = 0.0
        lp = highspy.HighsLp()
        lp.num_col_, lp.num_row_ = ncol, A.shape[0]
        lp.col_cost_, lp.col_lower_, lp.col_upper_ = c, col_lo, col_hi
        lp.row_lower_, lp.row_upper_ = np.concatenate(lo), np.concatenate(hi)
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_, lp.a_matrix_.index_, lp.a_matrix_.value_ = (A.indptr, A.indices,
                                                                          A.data)
        h = highspy.Highs()
        h.setOptionValue("output_flag", False)
        h.setOptionValue("solver", "simplex")
        h.setOptionValue("simplex_dual_edge_weight_strategy", 0)  # Dantzig pricing
        h.passModel(lp)
        h.run()
        status = h.getModelStatus()
        message = h.modelStatusToString(status)
        if status != highspy.HighsModelStatus.kOptimal:
            raise SolverError(f"the calibration LP failed: {message}", message)
        x = np.asarray(h.getSolution().col_value)
        return _LPSolution(np.concatenate([x[:self.nx], x[self.nx + n_dd:]]),
                           float(h.getInfo().objective_function_value), message)


class _LPSolution(NamedTuple):
    x: NDArray[np.float64]   # trajectory, then the noise variables
    fun: float
    message: str


def _setup(sys, Y, U, increment, shape, process_noise, disturbance_inputs):
    """Validated inputs of both entry points: the system, the record's LP, the
    increment radii and the noise shape."""
    sys, Ya, Ua = _prepare(sys, Y, U, disturbance_inputs)
    inc = _radii("increment", increment, sys.q)
    w = None if process_noise is None else _radii("process_noise", process_noise, sys.n)
    r_v = np.ones(sys.l) if shape is None else _radii("shape", shape, sys.l)
    if (r_v <= 0).any():
        raise DimensionError(f"shape radii must be positive, got {r_v}")
    return sys, _RecordLP(sys, Ya, Ua, w), inc, r_v


def _prepare(sys, Y, U, disturbance_inputs):
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    Ya = as_matrix("Y", Y, cols=sys.l, allow_nan=True)
    Ua = None
    if sys.p:
        if U is None:
            raise DimensionError(f"U is required: the system has {sys.p} input(s)")
        Ua = as_matrix("U", U, cols=sys.p)
        if Ua.shape[0] < Ya.shape[0] - 1 or (np.any(sys.Du != 0) and Ua.shape[0] < Ya.shape[0]):
            raise DimensionError(f"U must have N = {Ya.shape[0]} rows (N - 1 without a "
                                 f"feedthrough), got {Ua.shape[0]}")
    if not np.isfinite(Ya).any():
        raise DimensionError("Y has no measured (finite) entry")
    return sys, Ya, Ua


def calibrate_noise(sys: LinearSystem, Y: ArrayLike, U: ArrayLike | None = None, *,
                    increment: Any, shape: Any = None, per_channel: bool = False,
                    process_noise: Any = None,
                    disturbance_inputs: DisturbanceInputs = None) -> NoiseCalibration:
    """The smallest measurement-noise bound that makes a record consistent.

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

    Returns
    -------
    NoiseCalibration
        ``radii`` (recommended, outward), ``minimal`` (the LP optimum),
        ``scale``, ``worst_step``.

    Raises
    ------
    SolverError
        If HiGHS does not report an optimum (never a silent answer).

    Notes
    -----
    Consistency is the exact SMFDO's (Li-Cong-Dong, Algorithm 1 with
    ``delta`` = the whole record, eqs. (20)-(21) with noise): the posterior set
    is empty exactly when no trajectory ``(x_k, d_k)`` explains the data within
    the sets, which is the LP's feasibility. A windowed SMFDO forgets old data
    and may accept a smaller bound.

    Examples
    --------
    >>> import numpy as np, setobs as so
    >>> sys = so.LinearSystem([[1.0]], [[1.0]], [[1.0]])
    >>> Y = np.array([[0.0], [1.0], [0.0], [1.0]])     # alternating: |dd| <= 0 fits with noise 1/2
    >>> round(float(calibrate_noise(sys, Y, increment=0.0).minimal[0]), 6)
    0.5
    """
    sys, lp, inc, r_v = _setup(sys, Y, U, increment, shape, process_noise, disturbance_inputs)
    res = lp.solve(inc, r_v, per_channel)
    if per_channel:
        minimal = np.maximum(res.x[lp.nx:], 0.0)
        scale = None
    else:
        scale = max(float(res.x[lp.nx]), 0.0)
        minimal = scale * r_v
    pad = CALIBRATION_RTOL * minimal + CALIBRATION_ATOL
    resid = np.abs(lp.yout - lp.Mout @ res.x[:lp.nx])
    worst = np.zeros(sys.l, dtype=np.int64)
    for i in range(sys.l):
        sel = lp.ii == i
        if sel.any():
            worst[i] = int(lp.kk[sel][np.argmax(resid[sel])])
    return NoiseCalibration(minimal + pad, minimal, scale, inc, worst, lp.samples,
                            str(res.message), {"objective": float(res.fun)})


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
        raise DimensionError(f"betas must be finite and nonnegative, got {b}")
    alpha = np.array([max(float(lp.solve(beta * inc, r_v, False).x[lp.nx]), 0.0) for beta in b])
    return NoiseTradeoff(b, alpha, inc, r_v, tuple(sys.output_names))
