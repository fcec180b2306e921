"""The record's LP: the consistency of a whole record with the model as one sparse LP over
the trajectory (centred and scaled), solved by the conic chain of :mod:`setobs.lp.conic`
with checked answers and one round of iterative refinement."""

from __future__ import annotations

from typing import Literal, NamedTuple, overload

import numpy as np
import scipy.sparse as sp
from numpy.typing import NDArray

from ...exceptions import InvalidValueError, SolverError
from ...lp import conic
from ...models.linear import LinearSystem
from ...tolerances import CALIBRATION_CHECK_TOL

__all__ = ["LPSolution", "RecordLP", "worse"]


class RecordLP:
    """The LP data of one record, centred and scaled; re-solved for several increments.

    Centring: the trajectory is written as ``x_k = x_bar + x~_k``, ``d_k = d_bar + d~_k``
    with ``(x_bar, d_bar)`` the least-squares equilibrium at the record's mean input
    and output, an exact substitution (the dynamics' right-hand side takes the
    constant ``(Phi - I) x_bar + G d_bar``). Scaling: every datum (outputs, inputs,
    increment and process-noise radii) is divided by ``sigma``, the largest centred
    output, which divides the whole solution by it (the LP is homogeneous in data and
    variables). On the heat-exchanger record of the regression suite (outputs near
    100, noise near 2) this turns variables of size 100 into variables of size 1.
    """

    def __init__(self, sys: LinearSystem, Y: NDArray, U: NDArray | None,
                 process_noise: NDArray | None) -> None:
        self.sys = sys
        n, q, l = sys.n, sys.q, sys.l
        N = Y.shape[0]
        self.N = N
        self.Y, self.U, self.process_noise = Y, U, process_noise
        nx = (n + q) * N
        self.nx = nx
        # ---- outputs: residual r_k = y_k - Du u_k - Xi x_k for measured entries
        feed = U is not None and sys.p and np.any(sys.Du != 0)
        Yc = Y - (U[:N] @ sys.Du.T if feed and U is not None else 0.0)
        mask = np.isfinite(Yc)
        kk, ii = np.nonzero(mask)
        self.kk, self.ii = kk, ii
        yout = Yc[kk, ii]
        self.samples = int(mask.any(axis=1).sum())
        bu = (U[:N - 1] @ sys.Gamma.T if (U is not None and N > 1)
              else np.zeros((max(N - 1, 0), n)))
        # ---- centring: the least-squares equilibrium at the mean input and output
        ybar = np.array([yout[ii == i].mean() if np.any(ii == i) else 0.0 for i in range(l)])
        ubar = bu.mean(axis=0) if N > 1 else np.zeros(n)
        K = np.block([[sys.Phi - np.eye(n), sys.G], [sys.Xi, np.zeros((l, q))]])
        z = np.linalg.lstsq(K, np.concatenate([-ubar, ybar]), rcond=None)[0]
        if not np.isfinite(z).all():  # pragma: no cover - lstsq of finite data is finite
            z = np.zeros(n + q)
        self.x_bar, self.d_bar = z[:n], z[n:]
        yout = yout - (sys.Xi @ self.x_bar)[ii]
        bu = bu + ((sys.Phi - np.eye(n)) @ self.x_bar + sys.G @ self.d_bar)
        # ---- scaling: the largest centred output (1 for a record the equilibrium explains)
        spread = float(np.max(np.abs(yout))) if yout.size else 0.0
        self.sigma = spread if spread > 0.0 and np.isfinite(spread) else 1.0
        if not np.isfinite(self.sigma) or not np.isfinite(bu).all():
            raise InvalidValueError("the record's outputs or inputs are too large to calibrate "
                                 "in double precision")
        self.yout = yout / self.sigma
        self.bu = bu.reshape(-1) / self.sigma
        self.w = None if process_noise is None else process_noise / self.sigma
        # x_k at columns k*(n+q) .. +n, d_k at +n .. +n+q
        if N > 1:
            # ---- dynamics: x_{k+1} - Phi x_k - G d_k = Gamma u_k (+ w_k)
            base = sp.kron(sp.eye(N - 1), sp.hstack([sp.csr_matrix(-sys.Phi),
                                                      sp.csr_matrix(-sys.G)]), format="csr")
            left = sp.hstack([base, sp.csr_matrix((n * (N - 1), n + q))], format="csr")
            shift = sp.kron(sp.eye(N - 1), sp.hstack([sp.eye(n), sp.csr_matrix((n, q))]))
            right = sp.hstack([sp.csr_matrix((n * (N - 1), n + q)), shift], format="csr")
            self.Mdyn = (left + right).tocsr()
            # ---- increments: d_{k+1} - d_k
            dsel = sp.kron(sp.eye(N - 1), sp.hstack([sp.csr_matrix((q, n)), sp.eye(q)]))
            self.Minc = (sp.hstack([sp.csr_matrix((q * (N - 1), n + q)), dsel])
                         - sp.hstack([dsel, sp.csr_matrix((q * (N - 1), n + q))])).tocsr()
        else:
            self.Mdyn = sp.csr_matrix((0, nx))
            self.Minc = sp.csr_matrix((0, nx))
        cols, data, rr = [], [], []
        for j in range(n):
            cols.append(kk * (n + q) + j)
            data.append(sys.Xi[ii, j])
            rr.append(np.arange(kk.size))
        self.Mout = sp.csr_matrix((np.concatenate(data), (np.concatenate(rr),
                                   np.concatenate(cols))), shape=(kk.size, nx))

    # ------------------------------------------------------------------ the LP
    def _conic(self, inc: NDArray, weights: NDArray, per_channel: bool,
               fixed: NDArray | None = None, lower: NDArray | None = None):
        """The LP as ``min c^T z, A z + s = b, s in {0}^m_eq x R_+^m``: variables the
        centred, scaled trajectory, then the noise variables ``a`` (scalar mode:
        ``|r_ki| <= a w_i / max w``) or ``s_i`` (per channel: ``|r_ki| <= s_i``).

        ``fixed`` (one entry per measured row, NaN where the row's bound is the
        variable one): rows whose bound is a given number (scaled units), as the
        first part of a record with its calibrated bound; ``lower``: lower bounds of
        the noise variables (``a`` or ``s``, scaled)."""
        l, m = self.sys.l, self.yout.size
        nv = l if per_channel else 1
        wn = weights / np.max(weights)
        free = np.ones(m, dtype=bool) if fixed is None else np.isnan(fixed)
        if per_channel:
            S = sp.csr_matrix((np.ones(int(free.sum())), (np.flatnonzero(free),
                                                          self.ii[free])), shape=(m, l))
        else:
            S = sp.csr_matrix(np.where(free, wn[self.ii], 0.0).reshape(-1, 1))
        ybound = np.zeros(m) if fixed is None else np.where(free, 0.0, fixed)
        Z = sp.csr_matrix
        eq_A, eq_b, in_A, in_b = [], [], [], []
        N = self.N
        if N > 1:
            Mdyn, nd = self.Mdyn, self.Mdyn.shape[0]
            if self.w is None or not np.any(self.w):
                eq_A.append(sp.hstack([Mdyn, Z((nd, nv))]))
                eq_b.append(self.bu)
            else:
                rw = np.tile(self.w, N - 1)
                in_A += [sp.hstack([Mdyn, Z((nd, nv))]), sp.hstack([-Mdyn, Z((nd, nv))])]
                in_b += [self.bu + rw, rw - self.bu]
            ni = self.Minc.shape[0]
            r = np.tile(inc / self.sigma, N - 1)
            in_A += [sp.hstack([self.Minc, Z((ni, nv))]), sp.hstack([-self.Minc, Z((ni, nv))])]
            in_b += [r, r]
        in_A += [sp.hstack([self.Mout, -S]), sp.hstack([-self.Mout, -S]),
                 sp.hstack([Z((nv, self.nx)), -sp.eye(nv)])]
        in_b += [self.yout + ybound, ybound - self.yout,
                 np.zeros(nv) if lower is None else -np.asarray(lower, dtype=float)]
        m_eq = sum(a.shape[0] for a in eq_A)
        A = sp.vstack(eq_A + in_A, format="csc")
        b = np.concatenate(eq_b + in_b)
        c = np.zeros(self.nx + nv)
        c[self.nx:] = 1.0 / wn if per_channel else 1.0
        return A, b, c, m_eq

    def solve(self, inc: NDArray, weights: NDArray, per_channel: bool,
              time_limit: float = 120.0, fixed: NDArray | None = None,
              lower: NDArray | None = None) -> LPSolution:
        """The smallest consistent noise: ``alpha`` (``|r_ki| <= alpha weights_i``) or,
        per channel, ``s`` minimising ``sum_i s_i / weights_i`` (``|r_ki| <= s_i``).

        The solver chain ends in an answer or a :class:`SolverError`, never a crash:
        Clarabel (interior point) at tight tolerances, then Clarabel with robust
        settings, then HiGHS's interior point through scipy. Each answer is checked
        on the centred, scaled LP (every row within ``CALIBRATION_CHECK_TOL``, the
        noise variables at least the largest residual of the returned trajectory)
        before it is accepted. HiGHS's dual simplex, which this function used
        before, segfaulted or stopped with "Not Set" on real records (the
        heat-exchanger LP of the regression suite) and took 10-15 s on the
        20 000-sample motor record, where Clarabel takes about 1 s (development
        runs, not in a results file).

        The answer is then refined (:meth:`_refine`): the solvers' tolerances are
        relative to the data, and the data are the signal (the record's spread), so
        a first answer is accurate to ``1e-10`` of the *signal*; on a long record of
        a marginally stable plant that left the optimum 4e-4 (relative) short
        (``calibration_recommended_inconsistent.py``).
        """
        A, b, c, m_eq = self._conic(inc, weights, per_channel, fixed, lower)
        free = None if fixed is None else np.isnan(fixed)
        first = self._chain(A, b, c, m_eq, weights, per_channel, time_limit, self.yout,
                            free=free)
        return self._refine(first, A, b, c, m_eq, weights, per_channel, time_limit, free)

    @overload
    def _chain(self, A, b: NDArray, c: NDArray, m_eq: int, weights: NDArray,
               per_channel: bool, time_limit: float, yout: NDArray,
               raise_on_failure: Literal[True] = ..., free: NDArray | None = None
               ) -> LPSolution: ...

    @overload
    def _chain(self, A, b: NDArray, c: NDArray, m_eq: int, weights: NDArray,
               per_channel: bool, time_limit: float, yout: NDArray,
               raise_on_failure: bool = ..., free: NDArray | None = None
               ) -> LPSolution | None: ...

    def _chain(self, A, b: NDArray, c: NDArray, m_eq: int, weights: NDArray,
               per_channel: bool, time_limit: float, yout: NDArray,
               raise_on_failure: bool = True, free: NDArray | None = None
               ) -> LPSolution | None:
        """Solve ``min c^T z, A z + s = b`` by the solver chain; the checked answer
        (see :meth:`solve`), or ``None`` / a :class:`SolverError` if none is."""
        tried = []
        for name, attempt in conic.SOLVER_CHAIN:
            try:
                z, lower, status = attempt(A, b, c, m_eq, time_limit)
            except Exception as exc:
                tried.append(f"{name}: {type(exc).__name__}: {exc}")
                continue
            if z is None:
                tried.append(f"{name}: {status}")
                continue
            ok, why, v = self._accept(z, A, b, m_eq, weights, per_channel, yout, free)
            if ok:
                return LPSolution(z[:self.nx], v, lower, status, name, tuple(tried))
            tried.append(f"{name}: {status}, rejected: {why}")
        if not raise_on_failure:
            return None
        raise SolverError("the calibration LP failed under every solver (" + "; ".join(tried)
                          + "); check the record for non-finite or extreme values, or "
                          "shorten it", "; ".join(tried))

    def _refine(self, sol: LPSolution, A, b: NDArray, c: NDArray, m_eq: int,
                weights: NDArray, per_channel: bool, time_limit: float,
                free: NDArray | None = None) -> LPSolution:
        """One round of iterative refinement (Gleixner, Steffy and Wolter, "Iterative
        refinement for linear programming", INFORMS J. Comput. 28(3), 2016): the LP is
        re-solved for the correction ``delta`` of the trajectory ``x~`` found,
        ``A delta + s = b - A x~`` (the noise variables are not shifted), scaled by the
        largest entry of that right-hand side. Its data are now the residuals (the
        noise level), not the signal, so the solver's relative tolerances act on the
        residuals: on the 20 000-sample marginally stable record the optimum moves from
        4e-4 (relative) short to within 1e-9 of the states-eliminated LP in extended
        precision. The refined answer replaces the first only if the chain answers."""
        nx = self.nx
        shift = b - A[:, :nx] @ sol.x
        s2 = float(np.max(np.abs(shift), initial=0.0))
        if not (np.isfinite(s2) and s2 > 0.0):
            return sol
        yres = (self.yout - self.Mout @ sol.x) / s2
        fine = self._chain(A, shift / s2, c, m_eq, weights, per_channel, time_limit, yres,
                           raise_on_failure=False, free=free)
        if fine is None:
            return LPSolution(sol.x, sol.v, sol.lower, sol.status, sol.solver,
                               (*sol.failed, "refinement: no solver answered"))
        x = sol.x + s2 * fine.x
        v = s2 * fine.v
        return LPSolution(x, v, s2 * fine.lower, worse(sol.status, fine.status),
                           sol.solver if fine.solver == sol.solver
                           else f"{sol.solver}, refined by {fine.solver}",
                           sol.failed + fine.failed, True)

    def _accept(self, z: NDArray, A, b: NDArray, m_eq: int, weights: NDArray,
                per_channel: bool, yout: NDArray, free: NDArray | None = None
                ) -> tuple[bool, str, NDArray]:
        """Check a solver's point on the scaled LP; return the noise variables it proves
        (``yout``: the scaled outputs the trajectory variables are measured against;
        ``free``: the rows whose bound is the noise variable, default all)."""
        if not np.isfinite(z).all():
            return False, "non-finite solution", z
        res = A @ z - b
        scale = 1.0 + np.max(np.abs(z[:self.nx]), initial=0.0)
        viol = max(np.max(np.abs(res[:m_eq]), initial=0.0),
                   np.max(res[m_eq:], initial=0.0))
        if viol > CALIBRATION_CHECK_TOL * scale:
            return False, f"constraint violation {viol:.3g}", z
        # the noise the returned trajectory needs (outward: at least the solver's value)
        r = np.abs(yout - self.Mout @ z[:self.nx])
        ii = self.ii
        if free is not None:
            r, ii = r[free], ii[free]
        wn = weights / np.max(weights)
        if per_channel:
            need = np.array([np.max(r[ii == i], initial=0.0) for i in range(self.sys.l)])
            v = np.maximum(z[self.nx:], need)
        else:
            v = np.array([max(float(z[self.nx]), float(np.max(r / wn[ii], initial=0.0)))])
        return True, "", np.maximum(v, 0.0)


def worse(a: str, b: str) -> str:
    """The less accurate of two solver statuses."""
    return a if a != "optimal" else b


class LPSolution(NamedTuple):
    x: NDArray[np.float64]       # the centred, scaled trajectory
    v: NDArray[np.float64]       # the noise variables (scaled), proved by the trajectory
    lower: float                 # the solver's dual objective (scaled; NaN if unknown)
    status: str                  # "optimal" or "almost optimal"
    solver: str
    failed: tuple[str, ...]      # earlier attempts of the chain and why they were passed over
    refined: bool = False        # whether the refinement round answered
