"""Existence conditions: bounded DO (Li-Cong-Dong, Theorem 1), PIO / higher-order / modular
observers, and error-system poles of given gains (Fu-Wang, eq. (10))."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg import eigvals, null_space

from .._format import format_complex_list
from .._riccati import lqe_gain
from .._validation import as_matrix
from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import RANK_FLOOR, RANK_RTOL, UNIT_CIRCLE_TOL
from ._linalg import (
    RankDecision,
    balance_system,
    min_margin,
    not_inside_unit_circle,
    orth_rows,
    rank_decision,
)
from .observability import ObservabilityReport, observability, observability_matrix

__all__ = [
    "BoundedDOReport",
    "ErrorPoles",
    "ExistenceReport",
    "bounded_do_exists",
    "fu_wang_eq10_matrix",
    "higher_order_conditions",
    "higher_order_error_poles",
    "ibar",
    "modular_conditions",
    "pio_conditions",
    "pio_error_poles",
]


def ibar(blocks: int, l: int) -> NDArray[np.float64]:
    """``Ibar`` of Li-Cong-Dong eq. (16): strictly lower-triangular ones ``(x) I_l``.

    Parameters
    ----------
    blocks : int
        Number of block rows and columns.
    l : int
        Size of each identity block (the number of outputs).
    """
    return np.kron(np.tril(np.ones((blocks, blocks)), -1), np.eye(l))


def verdict_word(holds: bool, decided: bool) -> str:
    """``"yes"``, ``"no"`` or ``"undecidable"``: the word of every existence report.

    Parameters
    ----------
    holds : bool
        The condition's value.
    decided : bool
        Whether it was decided at this precision.
    """
    if not decided:
        return "undecidable"
    return "yes" if holds else "no"


@dataclass(frozen=True)
class BoundedDOReport:
    """Existence of a bounded disturbance observer (Li-Cong-Dong, Theorem 1).

    Attributes
    ----------
    satisfied : bool
        The verdict: a bounded DO exists (Theorem 1, decided in its
        coordinate-free form, Remark 1: ``N_o = n_o + q`` from orthogonal
        staircases), and the decision is not in the grey zone (see
        :attr:`decided`).
    decided : bool
        ``False`` when a singular value the verdict depends on lies between
        ``RANK_FLOOR`` and ``RANK_RTOL`` of its scale: at double precision the
        data cannot tell a structural zero from a small nonzero there (dense
        similarities of condition ``1e8`` put generic systems in that zone), so
        the verdict is *undecidable at this precision* rather than a guess.
    theorem1_explicit : bool
        Theorem 1 evaluated literally: ``rank([O, Ibar O G]) = rank(O) + q``,
        with ``O`` over ``n + q`` blocks (enough by Cayley-Hamilton for the
        augmented system). Explicit powers ``Phi^k`` make it coordinate
        dependent (a similarity of condition 200 flipped it on a system with
        zeros 1.63 and 1.98); it is reported, not used for the verdict.
    rank_O, rank_Oaug : int
        The two ranks of the explicit form.
    n_o, N_o : int
        Remark 1: observable dimensions of ``(Phi, Xi)`` and of the augmented
        pair, from an orthogonal staircase (an independent computation);
        Remark 1 holds iff ``N_o = n_o + q``.
    remark1_satisfied : bool
        ``N_o = n_o + q`` as computed (whether decided or not).
    forms_agree : bool
        Whether the explicit form and Remark 1 agree (they must; a disagreement
        means a rank decision of the explicit form is fragile, flagged in
        :attr:`fragile`).
    corollary1 : bool
        ``n_o < q`` (then no bounded DO exists).
    printed_horizon_satisfied : bool
        Theorem 1 evaluated literally with ``n`` blocks as printed in eq. (16).
        It can fail although a bounded DO exists (e.g. ``x+ = x + d``,
        ``y = x``, where ``Ibar O G = 0`` with one block).
    unrecoverable_directions : ndarray, shape (q, k)
        Orthonormal basis of the disturbance directions ``v`` whose component
        ``v^T d`` is not recoverable (empty when satisfied).
    recoverable_functionals : ndarray, shape (k, q)
        Rows ``w`` such that ``w^T d`` is recoverable with bounded error.
    decisions : list of RankDecision
    q : int
        Number of disturbance channels.
    """

    satisfied: bool
    rank_O: int
    rank_Oaug: int
    q: int
    n_o: int
    N_o: int
    remark1_satisfied: bool
    corollary1: bool
    printed_horizon_satisfied: bool
    unrecoverable_directions: NDArray[np.float64]
    recoverable_functionals: NDArray[np.float64]
    decisions: list[RankDecision] = field(default_factory=list)
    theorem1_explicit: bool = True
    decided: bool = True

    @property
    def verdict(self) -> str:
        """``"yes"``, ``"no"`` or ``"undecidable"`` (at this precision)."""
        return verdict_word(self.satisfied, self.decided)

    @property
    def forms_agree(self) -> bool:
        """The explicit form of Theorem 1 and Remark 1 give the same verdict."""
        return self.theorem1_explicit == self.remark1_satisfied

    @property
    def margin_decades(self) -> float:
        """Smallest margin of the rank decisions (decades)."""
        return min_margin(self.decisions)

    @property
    def fragile(self) -> bool:
        """A decision is close to the threshold, or the two forms disagree."""
        return (not self.forms_agree) or any(d.fragile for d in self.decisions)

    def __repr__(self) -> str:
        return (f"BoundedDOReport({self.verdict}: rank[O, IbarOG]={self.rank_Oaug}, "
                f"rank O={self.rank_O}, q={self.q}; Remark 1 N_o={self.N_o}, n_o={self.n_o}; "
                f"margin={self.margin_decades:.1f} decades)")


def bounded_do_exists(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> BoundedDOReport:
    """Whether a bounded disturbance observer exists (Li-Cong-Dong, Theorem 1, Remark 1, Cor. 1).

    The verdict is decided in the coordinate-free form of Remark 1 (orthogonal
    observability staircases of the balanced pairs, no explicit powers); it is
    ``"undecidable"`` when a rank it depends on is in the grey zone between
    ``RANK_FLOOR`` and ``RANK_RTOL`` (see :attr:`BoundedDOReport.decided`).

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).

    Notes
    -----
    *Theorem 1* (eq. (15)): ``rank([O, Ibar O G]) = rank(O) + q`` with ``O`` and
    ``Ibar`` of eq. (16). The paper's proof (Appendix A) identifies
    ``[O, Ibar O G]`` with the observability matrix of the augmented pair
    (9)-(11); that pair has ``n + q`` states, so ``n + q`` blocks are used here
    (Cayley-Hamilton). The literal ``n``-block version is reported as
    :attr:`BoundedDOReport.printed_horizon_satisfied`: it is not sufficient
    in general.

    *Remark 1*: ``N_o = n_o + q`` with ``N_o``, ``n_o`` the observable
    dimensions of the augmented and the original pair. It is computed here by an
    orthogonal staircase, independently of the explicit matrices of Theorem 1.

    Rank decisions are made on the balanced system with the explicit blocks
    scaled by the a-priori magnitudes ``||Xi|| ||Phi||^k``; their margins are
    reported.

    Examples
    --------
    >>> from setobs.examples import chang2006
    >>> bounded_do_exists(chang2006()).satisfied
    True
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    n, q, l = sys.n, sys.q, sys.l
    Pb, Gb, Xb, _, _, _ = balance_system(sys.Phi, sys.G, sys.Xi)
    decisions: list[RankDecision] = []

    def explicit(blocks: int) -> tuple[RankDecision, RankDecision]:
        O = observability_matrix(Pb, Xb, blocks)
        IOG = ibar(blocks, l) @ O @ Gb
        # floor: the largest block scale stays <= 1e100 (Phi = 0 or nilpotent-small
        # Phi overflowed here; those blocks are zero, any finite scale decides them)
        nP = max(float(np.linalg.norm(Pb, 2)), 1e-100 ** (1.0 / max(blocks - 1, 1)))
        w = np.repeat([nP ** -k for k in range(blocks)], l)[:, None]  # a-priori block scales
        Oaug = np.hstack([O, IOG]) * w
        return rank_decision(O * w, rtol), rank_decision(Oaug, rtol)

    dO, dAug = explicit(n + q)
    explicit_ok = dAug.rank == dO.rank + q
    pO, pAug = explicit(n)
    printed = pAug.rank == pO.rank + q
    # Remark 1 by the orthogonal staircase: the coordinate-free form that decides.
    rep_x = observability(sys.Phi, sys.Xi, rtol=rtol)
    aug = sys.augmented()
    rep_z = observability(aug.A, aug.C, rtol=rtol)
    decisions += rep_x.decisions + rep_z.decisions + [dO, dAug]
    remark1 = rep_z.n_observable == rep_x.n_observable + q
    # Grey zone: a dropped singular value above RANK_FLOOR of its scale could be a
    # small nonzero the data cannot resolve (the threshold is rtol of the scale).
    floor = RANK_FLOOR / rtol
    decided = not any(d.largest_dropped > floor * d.threshold
                      for d in rep_x.decisions + rep_z.decisions)
    # Recoverable functionals: w with [0, w] in row(O_aug) (rows of the staircase basis T_o).
    T_o = rep_z.observable_rows
    if T_o.shape[0]:
        left = null_space(T_o[:, :n].T, rcond=1e-8)  # alpha with alpha T_o[:, :n] = 0
        W = left.T @ T_o[:, n:]
        Wr, Wn, _ = orth_rows(W, 1e-8) if W.size else (np.zeros((0, q)), np.eye(q), None)
    else:
        Wr, Wn = np.zeros((0, q)), np.eye(q)
    return BoundedDOReport(
        satisfied=bool(remark1 and decided), rank_O=dO.rank, rank_Oaug=dAug.rank, q=q,
        n_o=rep_x.n_observable, N_o=rep_z.n_observable, remark1_satisfied=bool(remark1),
        corollary1=rep_x.n_observable < q, printed_horizon_satisfied=bool(printed),
        unrecoverable_directions=Wn.T, recoverable_functionals=Wr, decisions=decisions,
        theorem1_explicit=bool(explicit_ok), decided=bool(decided),
    )


# ----------------------------------------------------------------------------- error poles
@dataclass(frozen=True)
class ErrorPoles:
    """Poles of an observer's error system for given gains.

    Attributes
    ----------
    poles : ndarray of complex
        Eigenvalues of the error-system matrix.
    matrix : ndarray
        The error-system matrix.
    """

    poles: NDArray[np.complex128]
    matrix: NDArray[np.float64]

    @property
    def spectral_radius(self) -> float:
        """``max |pole|``."""
        return float(np.abs(self.poles).max(initial=0.0))

    @property
    def stable(self) -> bool:
        """All poles strictly inside the unit circle (by more than ``UNIT_CIRCLE_TOL``)."""
        return self.spectral_radius < 1.0 - UNIT_CIRCLE_TOL

    def unstable_poles(self) -> NDArray[np.complex128]:
        """Poles with ``|z| >= 1 - UNIT_CIRCLE_TOL`` (on or outside the unit circle)."""
        return not_inside_unit_circle(self.poles)

    def __repr__(self) -> str:
        ps = format_complex_list(self.poles, digits=4)
        return (f"ErrorPoles([{ps}], spectral_radius={self.spectral_radius:.4g}, "
                f"stable={self.stable})")


def pio_error_poles(sys: LinearSystem, P: ArrayLike, L: ArrayLike) -> ErrorPoles:
    """Error poles of the standard PIO (Chang 2006; Fu-Wang, Sec. IV).

    Observer: ``x^+ = Phi x^ + Gamma u + P (y - Xi x^) + G q^``,
    ``q^+ = q^ + L (y - Xi x^)``. With ``e = x - x^``, ``eps = d - q^`` and
    ``d`` constant, ``[e; eps]^+ = [[Phi - P Xi, G], [-L Xi, I]] [e; eps]``.

    Parameters
    ----------
    P : array_like, shape (n, l)
    L : array_like, shape (q, l)
    sys : LinearSystem or control.StateSpace
        The plant.
    """
    sys = require_system(sys)
    P_a = as_matrix("P", P, rows=sys.n, cols=sys.l)
    L_a = as_matrix("L", L, rows=sys.q, cols=sys.l)
    F = np.block([[sys.Phi - P_a @ sys.Xi, sys.G], [-L_a @ sys.Xi, np.eye(sys.q)]])
    return ErrorPoles(np.asarray(eigvals(F), dtype=complex), F)


def higher_order_error_poles(
    A: ArrayLike, C: ArrayLike, P0: ArrayLike, L0: ArrayLike, L1: ArrayLike,
    E: ArrayLike | None = None,
) -> ErrorPoles:
    """Error poles of the Fu-Wang higher-order observer, eqs. (7)-(10).

    Observer (eq. (8) reconstructed from the damaged text):
    ``x^+ = A x^ + B u + P0 (y - y^) + E d^``,
    ``d^+ = d^ + L0 (y - y^) + (d^ - d^_prev) + L1 (dy - dy^)``.
    With ``e = x - x^``, ``q = d - d^`` and ``Delta^2 d = 0``, the state
    ``(e, q, v)`` with ``v[k] = q[k] - q[k-1] + L1 C e[k-1]`` evolves by
    ``[[A - P0 C, E, 0], [-(L0 + L1) C, I, I], [-L0 C, 0, I]]``. Its
    characteristic polynomial is ``det M(z)`` with
    ``M(z) = (z - 1)^2 (zI - (A - P0 C)) + (z L0 + (z - 1) L1) C`` when ``E = I``,
    i.e. the roots of eq. (10) (``Delta = 1 - z^-1``, ``G = 1 + Delta``,
    ``Q = L0 + L1 Delta``, multiplied by ``z^(3n)``).

    Parameters
    ----------
    A, C : the plant ``x+ = A x + d``, ``y = C x`` (Fu-Wang, eqs. (3)-(4)).
    P0 : array_like, shape (n, l)
    L0, L1 : array_like, shape (p, l)
    E : array_like, shape (n, p), optional
        Disturbance direction; default ``I_n`` (the lumped disturbance
        ``d in R^n`` of Fu-Wang, eq. (3)).
    """
    A_a = as_matrix("A", A)
    n = A_a.shape[0]
    C_a = as_matrix("C", C, cols=n)
    l = C_a.shape[0]
    E_a = np.eye(n) if E is None else as_matrix("E", E, rows=n)
    p = E_a.shape[1]
    P0_a = as_matrix("P0", P0, rows=n, cols=l)
    L0_a = as_matrix("L0", L0, rows=p, cols=l)
    L1_a = as_matrix("L1", L1, rows=p, cols=l)
    F = np.block([
        [A_a - P0_a @ C_a, E_a, np.zeros((n, p))],
        [-(L0_a + L1_a) @ C_a, np.eye(p), np.eye(p)],
        [-L0_a @ C_a, np.zeros((p, p)), np.eye(p)],
    ])
    return ErrorPoles(np.asarray(eigvals(F), dtype=complex), F)


def fu_wang_eq10_matrix(z: complex, A, C, P0, L0, L1) -> NDArray[np.complex128]:
    """``M(z) = (z - 1)^2 (zI - (A - P0 C)) + (z L0 + (z - 1) L1) C`` (eq. (10) times ``z^3``).

    Parameters
    ----------
    z : complex
        Where to evaluate.
    A, C : array_like
        The plant's ``A`` (n, n) and ``C`` (l, n).
    P0, L0, L1 : array_like
        The higher-order observer's gains: ``P0`` (n, l) of the state update, ``L0`` and
        ``L1`` (q, l) of the two disturbance-estimate terms. Eq. (10) is stated for
        Fu-Wang's plant ``x+ = A x + d``, so ``q = n`` here.
    """
    A_a, C_a = np.asarray(A, float), np.asarray(C, float)
    Ab = A_a - np.asarray(P0, float) @ C_a
    n = A_a.shape[0]
    return ((z - 1) ** 2 * (z * np.eye(n) - Ab)
            + (z * np.asarray(L0, float) + (z - 1) * np.asarray(L1, float)) @ C_a)


# ----------------------------------------------------------------------------- observer conditions
@dataclass(frozen=True)
class ExistenceReport:
    """Whether an observer design exists, with the numbers it was decided on.

    The return type of the ``*_conditions`` checks and one row of
    :class:`~setobs.analysis.Diagnosis`. ``decided`` is ``False`` when the
    verdict is undecidable at this precision (``exists`` is then ``False`` and
    ``reason`` says why).

    Attributes
    ----------
    exists : bool
        Whether the design exists.
    condition : str
        The deciding condition, in words.
    numbers : dict
        The quantities it was decided on.
    reason : str
        One line: why not (empty when it exists).
    design : str
        The design (a key of the :class:`~setobs.analysis.Diagnosis`).
    source : str
        Paper and result the condition comes from.
    decided : bool
        ``False`` when undecidable at double precision.
    """

    exists: bool
    condition: str
    numbers: dict
    reason: str = ""
    design: str = ""
    source: str = ""
    decided: bool = True

    @property
    def verdict(self) -> str:
        """``"yes"``, ``"no"`` or ``"undecidable"`` (at this precision)."""
        return verdict_word(self.exists, self.decided)


def _pbh_at_one(sys: LinearSystem, rtol: float) -> RankDecision:
    Pb, Gb, Xb, _, _, _ = balance_system(sys.Phi, sys.G, sys.Xi)
    M = np.block([[Pb - np.eye(sys.n), Gb], [Xb, np.zeros((sys.l, sys.q))]])
    return rank_decision(M, rtol)


def pio_conditions(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> ExistenceReport:
    """PIO (Chang 2006): stabilising gains exist iff the augmented pair (9)-(11) is detectable.

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    rep: ObservabilityReport = observability(sys.augmented().A, sys.augmented().C, rtol=rtol)
    bad = rep.unstable_unobservable_modes
    pbh = _pbh_at_one(sys, rtol)
    nums = {"N_o": rep.n_observable, "n_aug": sys.n + sys.q,
            "rank[[Phi-I, G], [Xi, 0]]": pbh.rank,
            "unobservable_modes": np.round(rep.unobservable_modes, 6).tolist(),
            "margin_decades": round(min(rep.margin_decades, pbh.margin_decades), 1)}
    reason = "" if rep.detectable else (
        f"augmented pair not detectable: unobservable mode(s) {np.round(bad, 6).tolist()} "
        "on or outside the unit circle")
    return ExistenceReport(rep.detectable,
                             "augmented pair [[Phi, G], [0, I]], [Xi, 0] detectable", nums, reason)


def higher_order_conditions(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> ExistenceReport:
    """Higher-order observer (Fu-Wang) with ``d = G d*``: the pair with state
    ``(x, d*, Delta d*)``, ``[[Phi, G, 0], [0, I, I], [0, 0, I]]``, ``[Xi, 0, 0]``
    must be detectable (stable roots of eq. (10) for some gains).

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    n, q = sys.n, sys.q
    aug = sys.augmented(order=2)
    rep = observability(aug.A, aug.C, rtol=rtol)
    bad = rep.unstable_unobservable_modes
    nums = {"N_o": rep.n_observable, "n_aug": n + 2 * q,
            "margin_decades": round(rep.margin_decades, 1)}
    reason = "" if rep.detectable else (
        f"pair with states (x, d, Delta d) not detectable: mode(s) {np.round(bad, 6).tolist()}")
    return ExistenceReport(rep.detectable,
                             "pair (x, d, Delta d) with double-integrator disturbance detectable",
                             nums, reason)


def modular_conditions(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> ExistenceReport:
    """Modular Luenberger observer (modular-observer paper, Sec. VIII, eqs. (45)-(52)).

    With ``F = Phi``, ``P = G``, ``H = Xi``, ``Q = 0``, ``S = I_q``: a
    stabilising ``L0`` needs ``(Phi, Xi)`` detectable; ``V`` solves
    ``V S - (F - L0 H) V = P - L0 Q`` (eq. (48)), i.e.
    ``V = (I - Phi + L0 Xi)^-1 G``; the disturbance module ``w^+ = S w^ + L_w(...)``
    needs ``(S, H V + Q) = (I, Xi V)`` detectable, i.e. ``rank(Xi V) = q``.
    ``L0`` is taken from a DARE (any stabilising gain gives the same rank).

    Parameters
    ----------
    sys : LinearSystem or control.StateSpace
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x``.
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).
    """
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    rep = observability(sys.Phi, sys.Xi, rtol=rtol)
    nums: dict = {"n_o": rep.n_observable, "detectable": rep.detectable}
    if not rep.detectable:
        return ExistenceReport(False, "(Phi, Xi) detectable and rank(Xi V) = q", nums,
                                 "(Phi, Xi) is not detectable: no stabilising L0")
    Pb, Gb, Xb, _, _, _ = balance_system(sys.Phi, sys.G, sys.Xi)
    L0 = lqe_gain(Pb, Xb, np.eye(sys.n), np.eye(sys.l))
    V = np.linalg.solve(np.eye(sys.n) - Pb + L0 @ Xb, Gb)
    # Scale of the product, not of its (possibly pure-noise) value.
    d = rank_decision(Xb @ V, rtol, scale=float(np.linalg.norm(Xb, 2) * np.linalg.norm(V, 2)))
    nums.update(rank_XiV=d.rank, q=sys.q, margin_decades=round(d.margin_decades, 1))
    ok = d.rank == sys.q
    reason = "" if ok else (f"rank(Xi V) = {d.rank} < q = {sys.q}: a disturbance direction has "
                            "zero steady-state gain to the outputs (invariant zero at z = 1)")
    return ExistenceReport(ok, "(Phi, Xi) detectable and rank(Xi V) = q", nums, reason)

