"""PIO (Chang 2006), higher-order observer (Fu-Wang) and modular Luenberger observer."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import block_diag, solve_sylvester

from .._validation import as_matrix
from ..analysis import (
    ErrorPoles,
    higher_order_conditions,
    higher_order_error_poles,
    modular_conditions,
    observability,
    pio_conditions,
    pio_error_poles,
)
from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import RESONANCE_RTOL
from ._gains import default_poles, lqe_gain, place_gain
from .base import DesignError, StateSpaceObserver

__all__ = [
    "CHANG2006_PIO_GAINS",
    "FU_WANG_HO_GAINS",
    "GESO",
    "PIO",
    "HigherOrderObserver",
    "ModularObserver",
    "design_higher_order",
    "design_pio",
    "modular_paper_gains",
]

#: PIO gains printed in Fu-Wang, Sec. IV (the "optimal parameters of Chang 2006",
#: the SFODO baseline of Li-Cong-Dong Fig. 1(b)): ``P0'`` (3x2), ``L0'`` (2x2).
CHANG2006_PIO_GAINS = {
    "P": np.array([[31.7392, 19.6384], [1.8918, 1.7307], [29.3767, 19.9849]]),
    "L": np.array([[51.1873, 34.5803], [-21.3249, -10.6399]]),
}

#: Higher-order observer gains printed in Fu-Wang, Sec. IV (lumped ``d in R^3``).
FU_WANG_HO_GAINS = {
    "P0": np.array([[1.1902, 0.0181], [2.1356, 2.0195], [-1.3507, 0.0344]]),
    "L0": np.array([[0.37, 0.0], [0.36, 0.36], [-0.36, 0.0]]),
    "L1": np.array([[0.70, 0.0], [1.20, 1.20], [-0.85, 0.0]]),
}


def _cov(name: str, value: ArrayLike | None, dim: int, default: float | None
         ) -> NDArray[np.float64]:
    """A covariance matrix from a scalar (times I), a vector (diagonal) or a matrix."""
    if value is None:
        if default is None:
            raise DesignError(f"design='lqe' needs {name}", "covariance")
        value = default
    v = np.asarray(value, dtype=float)
    if v.ndim == 0:
        return float(v) * np.eye(dim)
    if v.ndim == 1:
        if v.size != dim:
            raise DesignError(f"{name} must have {dim} entries, got {v.size}", "covariance")
        return np.diag(v)
    return as_matrix(name, v, rows=dim, cols=dim)


def design_pio(sys: LinearSystem, poles: Sequence[complex]) -> dict[str, NDArray[np.float64]]:
    """PIO gains ``P`` (n x l), ``L`` (q x l) placing the error poles (n + q of them).

    The PIO error matrix ``[[Phi - P Xi, G], [-L Xi, I]] = A_aug - [P; L] C_aug``,
    so the gains come from pole placement on the augmented pair (9)-(11).

    Parameters
    ----------
    sys : LinearSystem
        The system.
    poles : sequence of complex
        The ``n + q`` error poles (conjugate pairs complete).
    """
    cond = pio_conditions(sys)
    if not cond.exists:
        raise DesignError(f"PIO: {cond.reason}", cond.condition)
    a = sys.augmented()
    K = place_gain(a.A, a.C, poles)
    return {"P": K[: sys.n], "L": K[sys.n :]}


class PIO(StateSpaceObserver):
    """Proportional-integral observer (Chang 2006, as written in Fu-Wang, Sec. IV).

    ``x_hat(k+1) = Phi x_hat + Gamma u + P (y - Xi x_hat) + G q_hat``,
    ``q_hat(k+1) = q_hat + L (y - Xi x_hat)``; ``d_hat(k) = q_hat(k)``.

    Parameters
    ----------
    sys : LinearSystem
    P, L : array_like, optional
        Gains. Default: designed with :func:`design_pio` at ``poles``.
    poles : sequence, optional
        Error poles (``n + q``); default the Fu-Wang/Chang set
        ``{0.1, 0.2, 0.3 +- 0.5j, 0.4}`` when ``n + q = 5``, otherwise ``n + q``
        distinct real poles evenly spread over ``[0.1, 0.5]``
        (:func:`default_poles`). With unobservable (stable) modes of the
        augmented pair, only the observable part's poles are placed.
    design : {"poles", "lqe"}
        ``"lqe"``: the steady-state Kalman predictor gain of the augmented
        model (:func:`lqe_gain`) from ``process_cov`` (``x``, default 0),
        ``increment_cov`` (``dd``) and ``measurement_cov`` (``y``): scalars
        (times ``I``), vectors (diagonal) or matrices.
    check_stability : bool
        Raise :class:`DesignError` for given gains whose error system is not
        stable (default ``False``: the printed Fu-Wang gains are unstable and are
        still available as a baseline).
    process_cov, increment_cov, measurement_cov : float, array_like, optional
        Covariances for ``design="lqe"``: scalars (times ``I``), vectors (diagonal) or
        matrices.
    information : {"predicted", "filtered"}
        Which measurements ``d_hat(k)`` uses. ``"predicted"`` (the papers'
        form): ``q_hat(k)``, from ``y_0..y_(k-1)``. ``"filtered"``:
        ``q_hat(k+1)``, from ``y_0..y_k``, the information of the SMFDO's
        estimate at ``k``. The model ``d(k+1) = d(k)`` makes ``q_hat(k+1)``
        the observer's estimate of ``d(k)`` as well as of ``d(k+1)`` (for the
        Kalman gain, ``d_hat(k|k) = d_hat(k+1|k)`` exactly: the increment is
        independent of ``y_0..y_k``); the error dynamics are unchanged. The
        state estimate stays ``x_hat(k)`` (from ``y_0..y_(k-1)``).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    """

    name = "PIO"

    def __init__(self, sys: LinearSystem, P: ArrayLike | None = None, L: ArrayLike | None = None,
                 *, poles: Sequence[complex] | None = None, check_stability: bool = False,
                 design: str = "poles", process_cov: ArrayLike | None = None,
                 increment_cov: ArrayLike | None = None,
                 measurement_cov: ArrayLike | None = None,
                 information: str = "predicted",
                 disturbance_inputs: DisturbanceInputs = None) -> None:
        super().__init__(sys, disturbance_inputs=disturbance_inputs)
        if information not in ("predicted", "filtered"):
            raise DesignError(f"information must be 'predicted' or 'filtered', got "
                              f"{information!r}", "information")
        self.information = information
        sys = self.sys
        n, q = sys.n, sys.q
        _check_design(design, poles, P is not None or L is not None)
        if (P is None or L is None) and design == "lqe":
            a = sys.augmented()
            K = lqe_gain(a.A, a.C, block_diag(_cov("process_cov", process_cov, n, 0.0),
                                              _cov("increment_cov", increment_cov, q, None)),
                         _cov("measurement_cov", measurement_cov, sys.l, None))
            P_a, L_a = K[:n], K[n:]
        elif P is None or L is None:
            if poles is None:
                base = [0.1, 0.2, 0.3 + 0.5j, 0.3 - 0.5j, 0.4]
                poles = base if n + q == 5 else default_poles(n + q)
            g = design_pio(sys, poles)
            P_a, L_a = g["P"], g["L"]
        else:
            P_a = as_matrix("P", P, rows=n, cols=sys.l)
            L_a = as_matrix("L", L, rows=q, cols=sys.l)
        self.P, self.L = P_a, L_a
        self.error_poles: ErrorPoles = pio_error_poles(sys, P_a, L_a)
        if check_stability and not self.error_poles.stable:
            raise DesignError(f"PIO error system unstable: {self.error_poles}", "stable gains")
        a = sys.augmented()
        K = np.vstack([P_a, L_a])
        self._init_state_space(a.A - K @ a.C, K, a.Gamma,
                               np.hstack([np.zeros((q, n)), np.eye(q)]),
                               np.hstack([np.eye(n), np.zeros((n, q))]))

    @property
    def gains(self) -> dict:
        return {"P": self.P, "L": self.L}

    @classmethod
    def chang2006_baseline(cls, sys: LinearSystem, information: str = "predicted") -> PIO:
        """The SFODO baseline of Li-Cong-Dong Fig. 1(b): the PIO with the gains printed
        in Fu-Wang (``P0'``, ``L0'``). Its error system is unstable (pole near -1.37).

        Parameters
        ----------
        sys : LinearSystem
            The Chang 2006 example (:func:`setobs.examples.chang2006`).
        information : {"predicted", "filtered"}
            See :class:`PIO`.
        """
        return cls(sys, CHANG2006_PIO_GAINS["P"], CHANG2006_PIO_GAINS["L"],
                   information=information)


def _check_design(design: str, poles, gains_given: bool) -> None:
    if design not in ("poles", "lqe"):
        raise DesignError(f"design must be 'poles' or 'lqe', got {design!r}", "design")
    if design == "lqe" and poles is not None:
        raise DesignError("give poles (design='poles') or covariances (design='lqe'), "
                          "not both", "design")
    if design == "lqe" and gains_given:
        raise DesignError("design='lqe' computes the gains: do not pass them", "design")


def design_higher_order(sys: LinearSystem, poles: Sequence[complex]
                        ) -> dict[str, NDArray[np.float64]]:
    """Gains ``P0, L0, L1`` of the higher-order observer placing its ``n + 2q`` error poles.

    The observer (Fu-Wang (7)-(9) with ``d = G d*``) is a Luenberger observer
    of ``(x, d*, Delta d*)`` with dynamics ``[[Phi, G, 0], [0, I, I], [0, 0, I]]``:
    injection gains ``[P0; Lq; Lv]`` give ``L0 = Lv``, ``L1 = Lq - Lv``
    (since ``d*^+ = d*^ + Delta^ + L1 dy_err + L0 y_err`` in Fu-Wang's form).
    The result is checked against :func:`setobs.analysis.higher_order_error_poles`.

    Parameters
    ----------
    sys : LinearSystem
        The system.
    poles : sequence of complex
        The ``n + 2q`` error poles (conjugate pairs complete).
    """
    cond = higher_order_conditions(sys)
    if not cond.exists:
        raise DesignError(f"higher-order observer: {cond.reason}", cond.condition)
    aug = sys.augmented(order=2)
    return _ho_gains_from_injection(place_gain(aug.A, aug.C, poles), sys.n, sys.q)


def _ho_gains_from_injection(K, n, q):
    P0, Lq, Lv = K[:n], K[n : n + q], K[n + q :]
    return {"P0": P0, "L0": Lv, "L1": Lq - Lv}


class HigherOrderObserver(StateSpaceObserver):
    """Higher-order observer of Fu-Wang, eqs. (7)-(9), with ``d = G d*``.

    ``x_hat+ = Phi x_hat + Gamma u + P0 (y - y_hat) + G d_hat``,
    ``d_hat+ = d_hat + L0 (y - y_hat) + Delta d_hat + L1 (Delta y - Delta y_hat)``.
    Implemented in the equivalent state ``(x_hat, d_hat, v)``; its error poles
    are the roots of eq. (10) (with ``E = G``). Default gains place the poles
    ``{0.1, 0.2, 0.3 +- 0.5j, 0.4, 0.5, 0.45}`` when ``n + 2q = 7`` (the
    example's size), otherwise ``n + 2q`` distinct real poles spread over
    ``[0.1, 0.5]``. ``design="lqe"``: the steady-state Kalman predictor gain of
    the model ``(x, d*, Delta d*)`` with ``process_cov`` on ``x`` (default 0),
    ``increment_cov`` on the second difference of ``d*`` and ``measurement_cov``.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system.
    P0, L0, L1 : array_like, optional
        Gains of Fu-Wang eqs. (7)-(9) (``n x l``, ``q x l``, ``q x l``). Default: designed
        with :func:`design_higher_order` at ``poles``.
    poles : sequence of complex, optional
        The ``n + 2q`` error poles (default above).
    design : {"poles", "lqe"}
        Pole placement, or the steady-state Kalman predictor gain.
    process_cov, increment_cov, measurement_cov : float, array_like, optional
        Covariances for ``design="lqe"``: scalars (times ``I``), vectors (diagonal) or
        matrices.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.

    Notes
    -----
    Fu-Wang's own form lumps the disturbance into ``d in R^n``; with ``l < n``
    that form always has a root at ``z = 1`` (see :mod:`setobs.analysis`), so
    the library parametrises ``d = G d*`` (``q`` disturbances) instead.
    """

    name = "higher-order observer"

    def __init__(self, sys: LinearSystem, P0: ArrayLike | None = None,
                 L0: ArrayLike | None = None, L1: ArrayLike | None = None, *,
                 poles: Sequence[complex] | None = None, design: str = "poles",
                 process_cov: ArrayLike | None = None, increment_cov: ArrayLike | None = None,
                 measurement_cov: ArrayLike | None = None,
                 disturbance_inputs: DisturbanceInputs = None) -> None:
        super().__init__(sys, disturbance_inputs=disturbance_inputs)
        sys = self.sys
        n, q, l = sys.n, sys.q, sys.l
        _check_design(design, poles, P0 is not None or L0 is not None or L1 is not None)
        if (P0 is None or L0 is None or L1 is None) and design == "lqe":
            aug = sys.augmented(order=2)
            K = lqe_gain(aug.A, aug.C, block_diag(_cov("process_cov", process_cov, n, 0.0),
                                          np.zeros((q, q)),
                                          _cov("increment_cov", increment_cov, q, None)),
                         _cov("measurement_cov", measurement_cov, l, None))
            g = _ho_gains_from_injection(K, n, q)
            P0_a, L0_a, L1_a = g["P0"], g["L0"], g["L1"]
        elif P0 is None or L0 is None or L1 is None:
            if poles is None:
                poles = ([0.1, 0.2, 0.3 + 0.5j, 0.3 - 0.5j, 0.4, 0.5, 0.45] if n + 2 * q == 7
                         else default_poles(n + 2 * q))
            g = design_higher_order(sys, poles)
            P0_a, L0_a, L1_a = g["P0"], g["L0"], g["L1"]
        else:
            P0_a = as_matrix("P0", P0, rows=n, cols=l)
            L0_a = as_matrix("L0", L0, rows=q, cols=l)
            L1_a = as_matrix("L1", L1, rows=q, cols=l)
        self.P0, self.L0, self.L1 = P0_a, L0_a, L1_a
        self.error_poles = higher_order_error_poles(sys.Phi, sys.Xi, P0_a, L0_a, L1_a, E=sys.G)
        aug = sys.augmented(order=2)
        K = np.vstack([P0_a, L0_a + L1_a, L0_a])
        self._init_state_space(aug.A - K @ aug.C, K, aug.Gamma,
                               np.hstack([np.zeros((q, n)), np.eye(q), np.zeros((q, q))]),
                               np.hstack([np.eye(n), np.zeros((n, 2 * q))]))

    @property
    def gains(self) -> dict:
        return {"P0": self.P0, "L0": self.L0, "L1": self.L1}


class GESO(PIO):
    """Generalized extended state observer (Li, Yang, Chen and Chen 2012; Chen-Gao-Lin's [27]).

    The GESO is the Luenberger observer of the system augmented with the
    disturbance as an extended state, ``d(k+1) = d(k)``, which is the
    :class:`PIO`'s realisation; it is defined by its gain (the
    eigenvalues of the augmented error dynamics) and does not need
    Chen-Gao-Lin's Assumption 1. Chen-Gao-Lin's Example 5 (Figs. 10-11) places
    all ``n + q`` eigenvalues at one value ``omega``; with a single output the
    gain is then unique (Ackermann's formula). With ``l`` independent outputs a pole
    can be placed at most ``l`` times (pole placement's limit; a :class:`DesignError`
    says so): give ``poles`` instead.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system.
    omega : float
        The common eigenvalue of the ``n + q`` error poles (default 0.3, the paper's
        Fig. 10), in ``[0, 1)``.
    poles : sequence of complex, optional
        All ``n + q`` error poles instead of ``omega``.
    information : {"predicted", "filtered"}
        See :class:`PIO`.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    """

    name = "GESO"

    def __init__(self, sys: LinearSystem, omega: float = 0.3, *,
                 poles: Sequence[complex] | None = None, information: str = "predicted",
                 disturbance_inputs: DisturbanceInputs = None) -> None:
        if poles is None:
            if not 0.0 <= float(omega) < 1.0:
                raise DesignError(f"omega must lie in [0, 1), got {omega}", "poles")
            s = require_system(sys, disturbance_inputs=disturbance_inputs)
            poles = [float(omega)] * (s.n + s.q)
        super().__init__(sys, poles=poles, information=information,
                         disturbance_inputs=disturbance_inputs)


class ModularObserver(StateSpaceObserver):
    """Modular Luenberger observer (modular-observer paper, Sec. VIII, eqs. (45)-(52)).

    Disturbance-free observer ``x0^+ = F x0^ + L0 (y - H x0^)``, disturbance
    observer ``w^+ = S w^ + Lw (y - H x0^ - (H V + Q) w^)`` and state corrector
    ``x^ = x0^ + V w^``, with ``V`` from the Sylvester equation (48)
    ``V S - (F - L0 H) V = P - L0 Q``, for the plant (45)
    ``x+ = F x + P w``, ``y = H x + Q w`` and the exosystem (46) ``w+ = S w``.
    Here ``F = Phi``, ``P = G``, ``H = Xi``; by default ``S = I`` (constant
    disturbance) and ``Q = 0``; ``S`` and ``Q`` give the general form. The
    paper's own gains (49)-(52) come from :func:`modular_paper_gains`.

    Parameters
    ----------
    sys : LinearSystem
    L0 : array_like, optional
        Gain of the disturbance-free observer (default: DARE gain).
    Lw : array_like, optional
        Gain of the disturbance observer (default: places ``eig(S - Lw (H V + Q))``
        at ``w_poles``).
    w_poles : sequence, optional
        Eigenvalues of the disturbance observer (default 0.5 each, spread slightly).
    S : array_like, shape (q, q), optional
        Exosystem matrix of eq. (46) (default ``I``).
    Q : array_like, shape (l, q), optional
        Direct effect of ``w`` on the output, eq. (45) (default 0). The
        measurements passed to :meth:`run` are then ``y = H x + Q w``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.

    Notes
    -----
    The paper's claim (Sec. VIII) that this equals the simultaneous Luenberger
    design with the same eigenvalues is checked in the tests: the combined error
    matrix is block-triangular with blocks ``F - L0 H`` and ``S - Lw (H V + Q)``.
    """

    name = "modular observer"

    def __init__(self, sys: LinearSystem, L0: ArrayLike | None = None, Lw: ArrayLike | None = None,
                 *, w_poles: Sequence[complex] | None = None,
                 S: ArrayLike | None = None, Q: ArrayLike | None = None,
                 disturbance_inputs: DisturbanceInputs = None) -> None:
        super().__init__(sys, disturbance_inputs=disturbance_inputs)
        sys = self.sys
        n, q, l = sys.n, sys.q, sys.l
        general = S is not None or Q is not None
        S_a = np.eye(q) if S is None else as_matrix("S", S, rows=q, cols=q)
        Q_a = np.zeros((l, q)) if Q is None else as_matrix("Q", Q, rows=l, cols=q)
        if not general:
            cond = modular_conditions(sys)
            if not cond.exists:
                raise DesignError(f"modular observer: {cond.reason}", cond.condition)
        elif not observability(sys.Phi, sys.Xi).detectable:
            raise DesignError("modular observer: (F, H) is not detectable: no stabilising L0",
                              "(F, H) detectable")
        F, P, H = sys.Phi, sys.G, sys.Xi
        if L0 is None:
            L0_a = lqe_gain(F, H, np.eye(n), np.eye(l))
        else:
            L0_a = as_matrix("L0", L0, rows=n, cols=l)
        Fc = F - L0_a @ H
        V = _modular_V(Fc, S_a, P - L0_a @ Q_a)
        HVQ = H @ V + Q_a
        if general and not observability(S_a, HVQ).detectable:
            raise DesignError("modular observer: (S, H V + Q) is not detectable: the "
                              "disturbance module has no stabilising gain", "(S, HV+Q) detectable")
        if Lw is None:
            if w_poles is None:
                w_poles = list(0.5 + 0.01 * np.arange(q))
            Lw_a = place_gain(S_a, HVQ, w_poles)
        else:
            Lw_a = as_matrix("Lw", Lw, rows=q, cols=l)
        self.L0, self.Lw, self.V, self.S, self.Q = L0_a, Lw_a, V, S_a, Q_a
        # Combined state (x0^, w^): x0^+ = Fc x0^ + L0 y (+ Gamma u)
        # w^+ = S w^ + Lw (y - H x0^ - (H V + Q) w^)
        Fm = np.block([[Fc, np.zeros((n, q))], [-Lw_a @ H, S_a - Lw_a @ HVQ]])
        K = np.vstack([L0_a, Lw_a])
        B = np.vstack([sys.Gamma, np.zeros((q, sys.p))])
        # The state corrector must also carry the known input: x0^ absorbs Gamma u.
        self._init_state_space(Fm, K, B, np.hstack([np.zeros((q, n)), np.eye(q)]),
                               np.hstack([np.eye(n), V]))

    @property
    def gains(self) -> dict:
        return {"L0": self.L0, "Lw": self.Lw}


def _modular_V(Fc: NDArray[np.float64], S: NDArray[np.float64],
               rhs: NDArray[np.float64]) -> NDArray[np.float64]:
    """``V`` of eq. (48): ``V S - Fc V = rhs``; refused when ``eig(S)`` meets ``eig(Fc)``."""
    ev_f, ev_s = np.linalg.eigvals(Fc), np.linalg.eigvals(S)
    gap = float(np.abs(ev_f[:, None] - ev_s[None, :]).min(initial=np.inf))
    if not gap > RESONANCE_RTOL * max(1.0, float(np.abs(ev_s).max(initial=0.0))):
        raise DesignError(f"eq. (48) has no unique solution: eig(S) and eig(F - L0 H) meet "
                          f"(gap {gap:.1e})", "eig(S) disjoint from eig(F - L0 H)")
    return solve_sylvester(-Fc, S, rhs)


def modular_paper_gains(sys: LinearSystem, A0: ArrayLike, B0: ArrayLike, Aw: ArrayLike,
                        Bw: ArrayLike, *, S: ArrayLike | None = None,
                        Q: ArrayLike | None = None) -> dict[str, NDArray[np.float64]]:
    """The gains of the modular observer by the paper's construction, eqs. (49)-(52).

    With ``F = Phi``, ``P = G``, ``H = Xi`` and the chosen stable ``A0`` (n x n),
    ``B0`` (n x l), ``Aw`` (q x q), ``Bw`` (q x l):

    * (50) ``T0 F - A0 T0 = B0 H``, (49) ``L0 = T0^-1 B0`` (so ``F - L0 H = T0^-1 A0 T0``);
    * (48) ``V S - (F - L0 H) V = P - L0 Q``;
    * (52) ``Tw F - Aw Tw = Bw H`` and ``R S - Aw R = (Bw - Tw L0)(H V + Q)``,
      (51) ``Lw = R^-1 (Bw - Tw L0)`` (so ``S - Lw (H V + Q) = R^-1 Aw R``).

    The observer's eigenvalues are then those of ``diag(A0, Aw)`` (reconstructed
    from the damaged text of Sec. VIII; the two similarity relations above are
    what the construction must give, and the tests check them).

    Parameters
    ----------
    sys : LinearSystem
        The plant (45).
    A0, B0 : array_like
        Dynamics of the disturbance-free observer, shapes (n, n) and (n, l).
    Aw, Bw : array_like
        Dynamics of the disturbance observer, shapes (q, q) and (q, l).
    S : array_like, shape (q, q), optional
        Exosystem (46) (default ``I``).
    Q : array_like, shape (l, q), optional
        Direct effect of ``w`` on ``y`` (default 0).

    Returns
    -------
    dict
        ``L0, Lw, T0, Tw, R, V``.

    Raises
    ------
    DesignError
        If ``T0`` or ``R`` is singular (the chosen ``(A0, B0)`` or ``(Aw, Bw)``
        does not give an invertible transformation), or eq. (48) is resonant.
    """
    sys = require_system(sys)
    n, q, l = sys.n, sys.q, sys.l
    A0_a = as_matrix("A0", A0, rows=n, cols=n)
    B0_a = as_matrix("B0", B0, rows=n, cols=l)
    Aw_a = as_matrix("Aw", Aw, rows=q, cols=q)
    Bw_a = as_matrix("Bw", Bw, rows=q, cols=l)
    S_a = np.eye(q) if S is None else as_matrix("S", S, rows=q, cols=q)
    Q_a = np.zeros((l, q)) if Q is None else as_matrix("Q", Q, rows=l, cols=q)
    F, P, H = sys.Phi, sys.G, sys.Xi
    T0 = solve_sylvester(-A0_a, F, B0_a @ H)                       # eq. (50)
    if np.linalg.cond(T0) > 1.0 / RESONANCE_RTOL:
        raise DesignError("T0 of eq. (50) is singular: choose (A0, B0) controllable with "
                          "eig(A0) disjoint from eig(F)", "T0 invertible")
    L0 = np.linalg.solve(T0, B0_a)                                 # eq. (49)
    V = _modular_V(F - L0 @ H, S_a, P - L0 @ Q_a)                  # eq. (48)
    Tw = solve_sylvester(-Aw_a, F, Bw_a @ H)                       # eq. (52), first
    R = solve_sylvester(-Aw_a, S_a, (Bw_a - Tw @ L0) @ (H @ V + Q_a))   # eq. (52), second
    if np.linalg.cond(R) > 1.0 / RESONANCE_RTOL:
        raise DesignError("R of eq. (52) is singular: choose (Aw, Bw) so that the "
                          "disturbance module is observable through H V + Q", "R invertible")
    Lw = np.linalg.solve(R, Bw_a - Tw @ L0)                        # eq. (51)
    return {"L0": L0, "Lw": Lw, "T0": T0, "Tw": Tw, "R": R, "V": V}
