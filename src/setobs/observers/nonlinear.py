"""The nonlinear modular state and disturbance observer (modular-observer paper, Secs. IV-VII)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import as_matrix, as_vector, check_real_scalar
from ..analysis.modular import ModularDesign, design_modular
from ..exceptions import ArgumentError, InvalidValueError
from ..tolerances import TRUST_TOL
from .base import ObserverResult, PointObserver

__all__ = ["NonlinearModularObserver", "NonlinearObserverResult"]

COORDINATES = ("linearizing", "original")


@dataclass(frozen=True)
class NonlinearObserverResult(ObserverResult):
    """:class:`ObserverResult` with the disturbance-free estimate, the estimates'
    consistency with the model and the data, and the steps not to trust.

    Attributes
    ----------
    estimate : ndarray, shape (N, q)
        The disturbance estimates ``w^``.
    x_hat : ndarray, shape (N, n)
        The corrected state estimates ``x^ = Xi(x~, w^)`` (eq. (26)).
    delay : int
        0 (causal estimates).
    gains : dict
        ``A0``, ``B0``, ``Aw``, ``Bw``.
    dt : float or None
        The system's sampling time.
    names : tuple of str
        The disturbance names.
    observer : str
        The observer's name.
    information : str
        ``"y_0..y_(k-1)"``: ``w^`` at ``k`` uses the measurements before ``k``.
    x_tilde : ndarray, shape (N, n)
        The disturbance-free observer's estimate ``x~`` (eq. (24)).
    consistency : ndarray, shape (N,)
        An estimate of each step's error from the model and the data alone, in the
        units of ``(x, w)`` (:meth:`NonlinearModularObserver.consistency`: the
        Gauss-Newton correction that makes the model's output predictions from
        ``(x^_k, w^_k)`` match the next measurements); ``inf`` for the last steps,
        which too few outputs follow to check.
    untrusted : ndarray of bool, shape (N,)
        Steps whose consistency exceeds the observer's ``trust_tol``, whose estimate
        came from a Newton solve that did not converge (original coordinates), and
        step 0 (the initial guess).
    """

    x_tilde: NDArray[np.float64] | None = None
    consistency: NDArray[np.float64] | None = None
    untrusted: NDArray[np.bool_] | None = None


class NonlinearModularObserver(PointObserver):
    """Nonlinear modular observer (modular-observer paper, eqs. (24)-(26), (30)-(36)).

    An identity observer ``x~`` for the disturbance-free part, a disturbance
    observer ``w^`` and a corrector ``x^ = Xi(x~, w^)``, designed by
    :func:`setobs.analysis.modular.design_modular` (power series of Section VII) so that
    in ``z0 = Phi0(x~)``, ``zw = Psi(x~, w^)`` the observer is linear with the
    eigenvalues of ``A0`` and ``Aw``.

    Two realisations of the same observer:

    * ``coordinates="linearizing"`` (default): ``z0+ = A0 z0 + B0 y``,
      ``zw+ = Aw zw + Bw y`` (eqs. (30), (34)), exactly; the estimates are read
      out by the series inverse (:meth:`ModularDesign.readout`). The initial
      ``z`` comes from :meth:`ModularDesign.extend_to_z`.
    * ``coordinates="original"``: eq. (32) for ``x~`` and the algebraic equation
      (36) for ``w^`` solved by Newton, then ``x^ = Xi(x~, w^)`` (26). Here the
      observer property (27) holds exactly for the truncated series, but ``Psi``
      and ``Xi`` must be evaluated at the estimates, which is hopeless where the
      estimates lie beyond the series' radius of convergence in ``w`` (the
      paper's Figure 3, ``w = 1``, is on that boundary; see notebook 06).

    Parameters
    ----------
    system : NonlinearSystem or ModularDesign
        The plant, or a finished design (then ``A0`` ... ``order`` must be omitted).
    A0, B0, Aw, Bw, order
        The design's parameters (:func:`~setobs.analysis.modular.design_modular`).
    x0 : array_like, shape (n,), optional
        Initial ``x~`` (default 0).
    w0 : array_like, shape (q,), optional
        Initial ``w^`` (default 0).
    coordinates : {"linearizing", "original"}
    trust_tol : float
        Consistency (see :class:`NonlinearObserverResult`: an error estimate, in the
        units of ``x`` and ``w``) above which a step is flagged untrusted (default
        :data:`~setobs.tolerances.TRUST_TOL`). With measurement noise, set it above
        the noise's effect (the consistency of the noise alone is ``J^+`` applied to
        it, see :meth:`consistency`).

    Notes
    -----
    ``step(y_k)`` returns ``w^_k``, computed from ``y_0, ..., y_(k-1)`` like the
    library's other point observers; :meth:`state_estimate` is ``x^_k``. The
    trust measure (:meth:`consistency`) looks ahead over the record, so :meth:`run`
    gives it.

    Examples
    --------
    Figure 3 of the paper: ``x(0) = 2``, ``w = 1``, the observer from
    ``x~(0) = 1``, ``w^(0) = 0``:

    >>> from setobs.examples import modular_example
    >>> sys = modular_example()
    >>> X, W, Y = sys.simulate([2.0], [1.0], 60)
    >>> obs = NonlinearModularObserver(sys, 0.4, 1.0, 0.6, 1.0, order=12, x0=[1.0])
    >>> res = obs.run(Y)
    >>> bool(abs(res.estimate[-1, 0] - 1.0) < 1e-3), bool(abs(res.x_hat[-1, 0] - X[-1, 0]) < 1e-3)
    (True, True)
    """

    name = "nonlinear modular observer"

    def __init__(self, system: Any, A0: ArrayLike | None = None, B0: ArrayLike | None = None,
                 Aw: ArrayLike | None = None, Bw: ArrayLike | None = None, *,
                 order: int | None = None, x0: ArrayLike | None = None,
                 w0: ArrayLike | None = None, coordinates: str = "linearizing",
                 trust_tol: float = TRUST_TOL) -> None:
        if isinstance(system, ModularDesign):
            if any(a is not None for a in (A0, B0, Aw, Bw, order)):
                raise ArgumentError("pass either a ModularDesign or the design's parameters")
            design = system
        else:
            if A0 is None or Aw is None:
                raise ArgumentError("A0 and Aw (or their eigenvalues) are required")
            design = design_modular(system, A0, B0, Aw, Bw,
                                    order=7 if order is None else int(order))
        if coordinates not in COORDINATES:
            raise InvalidValueError(f"coordinates must be one of {COORDINATES}, got "
                                    f"{coordinates!r}")
        self.trust_tol = check_real_scalar("trust_tol", trust_tol, positive=True)
        self.design = design
        self.sys = design.system
        self.delay = 0
        self.coordinates = coordinates
        n, q = self.sys.n, self.sys.q
        self.x0 = np.zeros(n) if x0 is None else as_vector("x0", x0, size=n)
        self.w0 = np.zeros(q) if w0 is None else as_vector("w0", w0, size=q)
        self._R = design.readout()
        self.reset()

    @property
    def gains(self) -> dict[str, Any]:
        """The design's linear dynamics ``A0, B0, Aw, Bw``, keyed by the paper's symbols."""
        d = self.design
        return {"A0": d.A0, "B0": d.B0, "Aw": d.Aw, "Bw": d.Bw}

    def reset(self) -> None:
        """Restart from ``x~(0) = x0``, ``w^(0) = w0``."""
        d = self.design
        self.x_tilde, self.w_hat = self.x0.copy(), self.w0.copy()
        self.x_hat = d.Xi_at(self.x_tilde, self.w_hat)
        self.trusted = True  # (the Newton solves of the original coordinates converged)
        if self.coordinates == "linearizing":
            self.z = d.extend_to_z(self.x_tilde, self.w_hat)

    def _read(self) -> None:
        n, q = self.sys.n, self.sys.q
        basis = self.design.basis_v
        mon = basis.monomials(self.z)
        out = self._R @ mon
        self.x_tilde, self.w_hat, self.x_hat = out[:n], out[n:n + q], out[n + q:]

    def step(self, y: ArrayLike, u: ArrayLike | None = None) -> NDArray[np.float64]:
        """Process ``y_k``; return ``w^_k`` (from ``y_0, ..., y_(k-1)``).

        Parameters
        ----------
        y : array_like, shape (l,)
        u : None
            The nonlinear system has no known inputs.
        """
        if u is not None and np.size(u):
            raise ArgumentError("the nonlinear modular observer takes no inputs")
        yv = as_vector("y", y, size=self.sys.l)
        d, sys = self.design, self.sys
        w_out = self.w_hat.copy()
        self._xk, self._xtk = self.x_hat.copy(), self.x_tilde.copy()
        if self.coordinates == "linearizing":
            n = sys.n
            self.z = np.concatenate([d.A0 @ self.z[:n] + d.B0 @ yv,
                                     d.Aw @ self.z[n:] + d.Bw @ yv])
            self._read()
        else:
            xt, wh = self.x_tilde, self.w_hat
            yhat = sys.h_num(self.x_hat, wh)
            xn, ok1 = d.phi0_at(xt, yv)                       # eq. (32)
            zt, ok2 = d.phi0_at(xt, yhat, guess=xn)
            sw = sys.s_num(wh)
            target = d.Psi_at(zt, sw) + d.Bw @ (yv - yhat)    # eq. (36)
            wn, ok3 = d.Psi_solve_w(xn, target, sw)
            mon = d.basis_v.monomials(np.concatenate([xn, wn]))
            self.x_tilde, self.w_hat = xn, wn
            self.x_hat = d.Xi @ mon                           # eq. (26)
            self.trusted = bool(ok1 and ok2 and ok3)
        return w_out

    def consistency(self, Y: ArrayLike, x_hat: ArrayLike, w_hat: ArrayLike
                    ) -> NDArray[np.float64]:
        """How far each estimate ``(x^_k, w^_k)`` is from explaining the data: an
        estimate of its error, from the model alone (no truth, no series).

        From ``(x^_k, w^_k)`` the model (``f``, ``s``, ``h``, exactly) predicts the next
        ``H`` outputs (``H = 2 (n + q)``, fewer at the end of the record), to compare
        with the measured ``y_k, ..., y_(k+H-1)``. The true states and disturbance
        predict them exactly (noise-free), and an estimate off by ``e`` deviates by
        about ``J_k e``, with ``J_k`` the Jacobian of the predicted outputs in
        ``(x_k, w_k)`` at the estimate (finite differences along the prediction). The
        least-squares (Gauss-Newton) correction ``J_k^+ (y - y_pred)`` is therefore the
        error itself to first order; its largest entry is returned, in the units of
        ``(x, w)`` (absolute: an estimate that diverges must not hide behind its own
        size). With measurement noise it adds ``J_k^+ noise``. Solving through ``J_k``
        matters: with a small sampling time (a pendulum at ``dt = 0.05``) a
        disturbance error moves the next outputs by only ``dt^2`` of itself, which raw
        output residuals would miss. The last steps of a record, with too few outputs
        after them to determine ``(x, w)``, get ``inf`` (cannot be checked).

        Parameters
        ----------
        Y : array_like, shape (N, l)
            The record.
        x_hat : array_like, shape (N, n)
        w_hat : array_like, shape (N, q)
            The estimates (``result.x_hat``, ``result.estimate``).

        Returns
        -------
        ndarray, shape (N,)
        """
        sys = self.sys
        Ya = as_matrix("Y", Y, cols=sys.l)
        Xh = as_matrix("x_hat", x_hat, rows=Ya.shape[0], cols=sys.n, allow_nan=True,
                       allow_inf=True)
        Wh = as_matrix("w_hat", w_hat, rows=Ya.shape[0], cols=sys.q, allow_nan=True,
                       allow_inf=True)
        N, H = Ya.shape[0], 2 * (sys.n + sys.q)
        nv = sys.n + sys.q
        out = np.empty(N)
        with np.errstate(all="ignore"):
            for k in range(N):
                h = min(H, N - k)
                v0 = np.concatenate([Xh[k], Wh[k]])
                pred = self._predict(v0, h)
                dy = (Ya[k:k + h] - pred).ravel()
                # the outputs' first-order sensitivity to (x_k, w_k) along the prediction
                J = np.empty((pred.size, nv))
                for c in range(nv):
                    dv = 1e-6 * (1.0 + abs(v0[c]))
                    vc = v0.copy()
                    vc[c] += dv
                    J[:, c] = (self._predict(vc, h) - pred).ravel() / dv
                if not (np.isfinite(J).all() and np.isfinite(dy).all()) or J.shape[0] < nv:
                    out[k] = np.inf  # (too few outputs after k to determine (x, w))
                    continue
                U, sv, Vt = np.linalg.svd(J, full_matrices=False)
                if sv.min() <= 1e-9 * max(sv.max(), 1e-300):
                    out[k] = np.inf
                    continue
                # the Gauss-Newton correction J^+ dy: the error itself to first order
                e = Vt.T @ ((U.T @ dy) / sv)
                out[k] = float(np.abs(e).max())
        return out

    def _predict(self, v: NDArray[np.float64], h: int) -> NDArray[np.float64]:
        """The model's outputs ``y_k .. y_(k+h-1)`` from ``(x_k, w_k) = v``."""
        sys = self.sys
        x, w = v[: sys.n], v[sys.n:]
        out = np.empty((h, sys.l))
        for j in range(h):
            out[j] = sys.h_num(x, w)
            x, w = sys.f_num(x, w), sys.s_num(w)
        return out

    def state_estimate(self) -> NDArray[np.float64]:
        """``x^_k`` (the corrected state estimate)."""
        return self._xk

    def run(self, Y: ArrayLike, U: ArrayLike | None = None) -> NonlinearObserverResult:
        """Run over a record from a fresh start: :meth:`reset`, then :meth:`continue_run`.

        Parameters
        ----------
        Y : array_like, shape (N, l)
        U : None
            No known inputs.

        Returns
        -------
        NonlinearObserverResult
            As :meth:`continue_run`.
        """
        self.reset()
        return self._continue(Y, U)

    def continue_run(self, Y: ArrayLike, U: ArrayLike | None = None
                     ) -> NonlinearObserverResult:
        """Run over a record from the current step (what :meth:`run` does after
        :meth:`reset`); the record's first estimate counts as untrusted.

        Parameters
        ----------
        Y : array_like, shape (N, l)
        U : None
            No known inputs.

        Returns
        -------
        NonlinearObserverResult
            ``estimate`` (``w^``), ``x_hat``, ``x_tilde`` and the ``untrusted`` steps
            (a ``RuntimeWarning`` says how many).
        """
        return self._continue(Y, U)

    def _continue(self, Y: ArrayLike, U: ArrayLike | None) -> NonlinearObserverResult:
        """:meth:`continue_run`'s work (its warning points at the caller of ``run`` or
        ``continue_run``)."""
        if U is not None and np.size(U):
            raise ArgumentError("the nonlinear modular observer takes no inputs")
        Ya = as_matrix("Y", Y, cols=self.sys.l)
        N = Ya.shape[0]
        D = np.empty((N, self.sys.q))
        X = np.empty((N, self.sys.n))
        Xt = np.empty((N, self.sys.n))
        newton_ok = np.ones(N, dtype=bool)
        for k in range(N):
            newton_ok[k] = self.trusted
            D[k] = self.step(Ya[k])
            X[k], Xt[k] = self._xk, self._xtk
        cons = self.consistency(Ya, X, D)
        bad = ~newton_ok | ~(cons <= self.trust_tol)
        bad[0] = True  # (the initial guess: no measurement behind it)
        # Warn when trust is never reached, or lost after it was (the transient before
        # the observer converges, and the last steps that too few outputs follow to
        # check, are flagged in result.untrusted but expected)
        end = N
        while end > 0 and np.isinf(cons[end - 1]) and newton_ok[end - 1]:
            end -= 1
        ok = ~bad[:end]
        later = bad[int(np.argmax(ok)):end] if ok.any() else bad[:end]
        if N > 1 and (not ok.any() or later.any()):
            what = ("no estimate of the run" if not ok.any() else
                    f"{int(later.sum())} estimates after the transient (from step "
                    f"{int(np.argmax(ok))})")
            warnings.warn(f"{what} consistent with the model and the data to trust_tol = "
                          f"{self.trust_tol:g} (result.consistency: an error estimate; "
                          "result.untrusted), or from an unconverged Newton solve; a higher "
                          "order, a design closer to the operating point, or the linearizing "
                          "coordinates may help", RuntimeWarning, stacklevel=3)
        return NonlinearObserverResult(D, X, 0, self.gains, dt=self.sys.dt,
                                       names=tuple(self.sys.disturbance_names),
                                       observer=self.name, x_tilde=Xt, consistency=cons,
                                       untrusted=bad)

    def __repr__(self) -> str:
        return (f"NonlinearModularObserver(order={self.design.order}, "
                f"coordinates={self.coordinates!r})")
