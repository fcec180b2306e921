"""One report: which observer designs exist for a system, and why not."""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .._format import format_complex, format_complex_list
from ..exceptions import NotFoundError
from ..models.linear import DisturbanceInputs, LinearSystem, require_system
from ..tolerances import RANK_RTOL
from .existence import (
    BoundedDOReport,
    ExistenceReport,
    bounded_do_exists,
    higher_order_conditions,
    modular_conditions,
    pio_conditions,
)
from .structure import RelativeDegreeResult, UIOReport, relative_degrees, uio_conditions
from .zeros import ZerosResult

__all__ = ["Diagnosis", "diagnose"]


@dataclass(frozen=True)
class Diagnosis:
    """Which observer designs exist for a system (see :func:`diagnose`).

    Attributes
    ----------
    verdicts : list of ExistenceReport
    bounded_do : BoundedDOReport
    zeros : ZerosResult
    relative_degrees : RelativeDegreeResult
    uio : UIOReport
        (``None`` for a nonlinear system whose linearization is not a
        :class:`LinearSystem`, these four)
    system : LinearSystem or NonlinearSystem
        The diagnosed system.
    notes : list of str
        Remarks that apply to several designs (e.g. undecidable rank decisions).
    """

    system: Any
    verdicts: list[ExistenceReport]
    bounded_do: BoundedDOReport | None
    zeros: ZerosResult | None
    relative_degrees: RelativeDegreeResult | None
    uio: UIOReport | None
    notes: list[str] = field(default_factory=list)

    def __getitem__(self, design: str) -> ExistenceReport:
        for v in self.verdicts:
            if v.design == design:
                return v
        raise NotFoundError(f"no design {design!r}; designs: {[v.design for v in self.verdicts]}")

    @property
    def existing(self) -> list[str]:
        """Names of the designs that exist."""
        return [v.design for v in self.verdicts if v.exists]

    def _header(self) -> str:
        s = self.system
        if self.zeros is None:
            return (f"nonlinear system: n={s.n} states, q={s.q} disturbances, l={s.l} outputs "
                    "(linear designs: see the linearization)")
        zs = format_complex_list(self.zeros.zeros) or "none"
        head = (f"system: n={s.n} states, q={s.q} disturbances, l={s.l} outputs; "
                f"finite invariant zeros: {zs}")
        return head + ("\n  " + self._signals() if self._signals() else "")

    def _signals(self) -> str:
        """The system's signal names, when the user gave any (empty for default names)."""
        s = self.system
        groups = [("disturbances", s.disturbance_names, "d"), ("outputs", s.output_names, "y"),
                  ("inputs", getattr(s, "input_names", ()), "u"), ("states", s.state_names, "x")]
        custom = [(label, names) for label, names, prefix in groups
                  if names != tuple(f"{prefix}{i}" for i in range(len(names)))]
        if not custom:
            return ""
        parts = [f"{label} ({', '.join(names)})" for label, names in custom]
        dt = f"; sampling time {s.dt:g} s" if s.dt is not None else ""
        return "signals: " + "; ".join(parts) + dt

    def __repr__(self) -> str:
        width = max(len(v.design) for v in self.verdicts)
        lines = ["Diagnosis", "  " + self._header()]
        for v in self.verdicts:
            mark = f"{'NO' if v.verdict == 'no' else v.verdict:<3}"
            lines.append(f"  {v.design:<{width}}  {mark}  {v.condition}")
            if not v.exists:
                lines.append(f"  {'':<{width}}       -> {v.reason}")
            nums = "; ".join(f"{k}={_fmt(val)}" for k, val in v.numbers.items()
                             if not isinstance(val, list | tuple) or len(val) <= 3)
            lines.append(f"  {'':<{width}}       [{nums}]")
        lines += [f"  note: {n}" for n in self.notes]
        return "\n".join(lines)

    def to_markdown(self) -> str:
        """A Markdown table of the verdicts, with the deciding numbers."""
        head, *signals = self._header().split("\n")
        out = [f"**{head}**", *[f"\n{line.strip()}" for line in signals], "",
               "| design | exists | deciding condition | numbers | why not |",
               "|---|---|---|---|---|"]
        for v in self.verdicts:
            nums = "; ".join(f"{k}={_fmt(val)}" for k, val in v.numbers.items())
            out.append(f"| {v.design} | {v.verdict} | {v.condition} | "
                       f"{nums} | {v.reason or '—'} |")
        if self.notes:
            out += ["", *[f"- {n}" for n in self.notes]]
        return "\n".join(out)


def _fmt(v) -> str:
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, np.ndarray):
        return np.array2string(v, precision=4, separator=", ")
    return str(v)


def _diagnose_nonlinear(sys: Any, rtol: float) -> Diagnosis:
    from ..models.linear import LinearSystem as _LS
    from .modular import nonlinear_modular_conditions

    row = nonlinear_modular_conditions(sys)
    extra = [f"nonlinear modular observer: {row.reason.removeprefix('note: ')}"
             ] if row.exists and row.reason else []
    lin = sys.linearization()
    if np.all(lin["Q"] == 0) and np.array_equal(lin["S"], np.eye(sys.q)):
        d = diagnose(_LS(lin["F"], lin["P"], lin["H"], dt=sys.dt), rtol=rtol)
        notes = [*d.notes, *extra, "rows other than the nonlinear modular observer are for the "
                 "linearization at the equilibrium (local statements)"]
        return replace(d, system=sys, verdicts=[*d.verdicts, row], notes=notes)
    why = ("the linearization has a disturbance feedthrough Q != 0" if np.any(lin["Q"] != 0)
           else "the exosystem is not a constant disturbance (S != I)")
    return Diagnosis(sys, [row], None, None, None, None,
                     [*extra, f"linear designs not checked: {why}, which LinearSystem does not "
                      "represent"])


def diagnose(sys: LinearSystem, *, disturbance_inputs: DisturbanceInputs = None,
    rtol: float = RANK_RTOL) -> Diagnosis:
    """For each observer design in the library, whether it exists for ``sys`` and why not.

    Designs and their deciding conditions:

    * **SMFDO** (Li-Cong-Dong, Algorithm 1): Theorem 1 (bounded DO exists).
    * **MB-ESO** (Chen-Gao-Lin, eq. (16)): ``q = l``, no invariant zeros
      (Assumption 1; Lemma 2), and ``V0`` diagonal (Theorem 2).
    * **variant MB-ESO** (eqs. (18)-(22)): ``q = l`` and no invariant zeros.
    * **delayed UIO**: condition (b) (strong detectability: full normal rank,
      every invariant zero strictly inside the unit circle); delay from (25)-(26).
    * **PIO** (Chang 2006): augmented pair detectable.
    * **higher-order observer** (Fu-Wang): pair with a double-integrator
      disturbance model detectable.
    * **modular observer** (Sec. VIII): ``(Phi, Xi)`` detectable, ``rank(Xi V) = q``.
    * **nonlinear modular observer** (modular-observer paper, Prop. 2-3), for a
      :class:`~setobs.nonlinear.NonlinearSystem`: the linearization observable
      (disturbance-free and extended); the Poincare-domain assumption is
      reported, not decided on (it fails for every constant disturbance, the
      paper's example included). The linear rows are then those of the
      linearization, when it is a :class:`LinearSystem` (``Q = 0``, ``S = I``).

    Parameters
    ----------
    sys : LinearSystem, control.StateSpace or NonlinearSystem
        The system ``x+ = Phi x + Gamma u + G d``, ``y = Xi x`` (or
        ``x+ = f(x, w)``, ``w+ = s(w)``, ``y = h(x, w)``).
    disturbance_inputs : sequence of int or str, optional
        When ``sys`` is a ``control.StateSpace``: the columns of its ``B`` (indices or input
        names) that are disturbances.
    rtol : float
        Relative threshold of the rank decisions (:data:`setobs.tolerances.RANK_RTOL`).

    Examples
    --------
    >>> from setobs.examples import chang2006
    >>> d = diagnose(chang2006())
    >>> d.existing
    ['SMFDO', 'PIO', 'higher-order observer', 'modular observer']
    """
    from ..models.exosystem import NonlinearSystem

    if isinstance(sys, NonlinearSystem):
        return _diagnose_nonlinear(sys, rtol)
    sys = require_system(sys, disturbance_inputs=disturbance_inputs)
    bdo = bounded_do_exists(sys, rtol=rtol)
    rd = relative_degrees(sys, rtol=rtol)
    uio = uio_conditions(sys, rtol=rtol)
    z = uio.zeros
    verdicts: list[ExistenceReport] = []
    notes: list[str] = []

    # SMFDO -----------------------------------------------------------------
    nums = {"rank[O, IbarOG]": bdo.rank_Oaug, "rank O": bdo.rank_O, "q": bdo.q,
            "N_o": bdo.N_o, "n_o": bdo.n_o, "margin_decades": round(bdo.margin_decades, 1)}
    if bdo.satisfied:
        reason = ""
    elif not bdo.decided:
        reason = ("undecidable at this precision: a singular value of the observability "
                  "staircase lies between RANK_FLOOR and RANK_RTOL of its scale (a structural "
                  "zero cannot be told from a small nonzero; an ill-conditioned state basis "
                  "does this)")
    elif bdo.corollary1:
        reason = f"Corollary 1: n_o = {bdo.n_o} < q = {bdo.q}"
    else:
        k = bdo.unrecoverable_directions.shape[1]
        dirs = np.round(bdo.unrecoverable_directions.T, 4).tolist()
        reason = (f"rank[O, IbarOG] = {bdo.rank_Oaug} < rank O + q = {bdo.rank_O + bdo.q}: "
                  f"{k} disturbance direction(s) not recoverable: {dirs}")
    verdicts.append(ExistenceReport(bdo.satisfied, "Theorem 1: rank[O, IbarOG] = rank O + q",
                                    nums, reason, design="SMFDO", source="Li-Cong-Dong Thm 1",
                                    decided=bdo.decided))
    if not bdo.forms_agree:
        notes.append("Theorem 1's explicit ranks disagree with its coordinate-free form "
                     "(Remark 1, which decides): an explicit rank decision is fragile "
                     f"(margin {bdo.margin_decades:.1f} decades)")
    if bdo.satisfied and not bdo.printed_horizon_satisfied:
        notes.append("Theorem 1 with only n blocks (as printed in eq. (16)) fails here; "
                     "n + q blocks are needed for the augmented system")

    # Zero-based designs ------------------------------------------------------
    square = sys.q == sys.l
    no_zeros = z.full_normal_rank and z.zeros.size == 0
    zs = [format_complex(v) for v in z.zeros]
    zero_nums = {"finite zeros": zs, "normal rank": z.normal_rank, "n+q": sys.n + sys.q,
                 "degrees": rd.degrees, "V0 nonsingular": rd.nonsingular,
                 "V0 diagonal": rd.diagonal, "margin_decades": round(z.margin_decades, 1)}
    if not square:
        why = f"needs as many disturbances as outputs (q = {sys.q}, l = {sys.l})"
    elif not z.full_normal_rank:
        why = f"pencil normal rank {z.normal_rank} < n + q = {sys.n + sys.q}"
    elif z.zeros.size:
        why = f"invariant zero(s) at {', '.join(zs)} (Assumption 1 violated)"
    else:
        why = ""
    verdicts.append(ExistenceReport(
        square and no_zeros, "q = l and no invariant zeros (Assumption 1)", zero_nums, why,
        design="variant MB-ESO", source="Chen-Gao-Lin Thm 3"))
    mb_ok = square and no_zeros and rd.diagonal
    mb_why = why or ("" if rd.diagonal
                     else "V0 is not diagonal (Theorem 2); use the variant MB-ESO")
    verdicts.append(ExistenceReport(mb_ok, "q = l, no invariant zeros, V0 diagonal", zero_nums,
                                    mb_why, design="MB-ESO", source="Chen-Gao-Lin Thm 2"))
    if square and no_zeros != rd.lemma2_no_zeros:
        notes.append("Lemma 2 (V0 nonsingular, sum r_i = n) disagrees with the zero computation")

    # Delayed UIO -------------------------------------------------------------
    uio_nums = {"unstable zeros": [format_complex(v) for v in uio.unstable_zeros],
                "normal rank": z.normal_rank, "n+rank G": sys.n + uio.rank_G,
                "delay tau": uio.delay, "rank(Xi G)": uio.rank_XiG, "rank G": uio.rank_G}
    if uio.delayed_uio_exists:
        uio_why = ""
    elif z.normal_rank < sys.n + uio.rank_G:
        uio_why = f"not left invertible (normal rank {z.normal_rank} < n + rank G)"
    elif uio.unstable_zeros.size:
        uio_why = (f"invariant zero(s) on/outside the unit circle: "
                   f"{format_complex_list(uio.unstable_zeros)}")
    else:
        uio_why = "no finite delay satisfies eq. (25)"
    verdicts.append(ExistenceReport(uio.delayed_uio_exists, "condition (b): strongly detectable",
                                    uio_nums, uio_why, design="delayed UIO",
                                    source="Chen-Gao-Lin Sec. III-A"))

    # Augmented-model observers -------------------------------------------------
    for name, cond, src in (("PIO", pio_conditions(sys, rtol=rtol), "Chang 2006"),
                            ("higher-order observer", higher_order_conditions(sys, rtol=rtol),
                             "Fu-Wang"),
                            ("modular observer", modular_conditions(sys, rtol=rtol),
                             "modular observer Sec. VIII")):
        verdicts.append(replace(cond, design=name, source=src))
    order = ["SMFDO", "MB-ESO", "variant MB-ESO", "delayed UIO", "PIO",
             "higher-order observer", "modular observer"]
    verdicts.sort(key=lambda v: order.index(v.design))
    return Diagnosis(sys, verdicts, bdo, z, rd, uio, notes)
