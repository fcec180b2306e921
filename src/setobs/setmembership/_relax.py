"""Polyhedral relaxations of factorable functions, lifted into a constrained zonotope.

For ``g(z, u)`` (sympy expressions) and a box ``B`` of ``z`` that holds the truth, each
nonlinear node of ``g``'s expression tree (a product of two non-constant factors, a
power, a function) gets an auxiliary variable ``a_j`` with its interval bounds over
``B`` and linear inequalities that hold for every ``z`` in ``B`` (McCormick, "Computability
of global solutions to factorable nonconvex programs", Math. Programming 10 (1976): the
four envelopes of a bilinear term; a convex univariate function lies below its secant
and above its tangents, a concave one the other way; any other one within its
derivative's interval enclosure of a line, the mean-value form). The lifted set
``{(z, a) : z in X, a in [L, U], P (z, a) <= beta}`` holds ``(z, a(z))`` for every ``z``
in ``X`` and ``B``, and ``g`` is an affine form of the lifted variables, so its image is
a linear map of a constrained zonotope (Rego, Raffo, Terra, Scott 2025 apply the same
relaxations to guaranteed state estimation; this is their construction with one
auxiliary per node and outward rounding).

Rounding: every affine form ``p^T v + q`` carries a radius ``r`` that bounds its value's
distance to the node's (its own rounding included: ``gamma`` of the terms' magnitudes
over the lifted box), and every inequality's right-hand side is rounded up by the same
bound on its computed coefficients, so each holds in exact arithmetic for the
computed rows.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .._rounding import gamma, round_down, round_up
from ..exceptions import DomainError, UnboundedSetError
from ..geometry import ConstrainedZonotope
from ..models.interval import IntervalFunction

#: Convexity of the univariate functions the relaxation knows on their whole domain
#: (others, and powers whose convexity changes over the box, get the mean-value lines).
_CONVEX = {"exp": 1, "log": -1, "cosh": 1}

_Form = tuple[NDArray[np.float64], float, float]


class Relaxation:
    """The lifted polyhedral relaxation of expressions ``exprs`` in ``zs`` (and inputs
    ``us``), compiled once: the nonlinear nodes in topological order, each with the
    interval enclosure of its subexpression and of the univariate function's value and
    derivative."""

    def __init__(self, sp: Any, exprs: Sequence[Any], zs: Sequence[Any],
                 us: Sequence[Any]) -> None:
        self.zs, self.us = list(zs), list(us)
        self.N = len(self.zs)
        self.variables = [*self.zs, *self.us]
        self._sp = sp
        self.nodes: list[tuple[Any, ...]] = []  # (kind, expr, children..)
        self._index: dict[Any, int] = {}
        self._uni: dict[Any, tuple[IntervalFunction, IntervalFunction, int, float]] = {}
        self._t = sp.Dummy("t")
        self.outputs = [self._node(sp.sympify(e)) for e in exprs]
        self.n_aux = sum(1 for nd in self.nodes if nd[0] in ("mul", "uni"))
        aux = iter(range(self.N, self.N + self.n_aux))
        self.aux_of = {j: next(aux) for j, nd in enumerate(self.nodes) if nd[0] in ("mul", "uni")}
        self.bounds = [IntervalFunction([nd[1]], self.variables, clip_domain=True)
                       if nd[0] in ("mul", "uni") else None for nd in self.nodes]

    # ------------------------------------------------------------------ compiling
    def _node(self, e: Any) -> int:
        sp = self._sp
        if e in self._index:
            return self._index[e]
        zset = set(self.zs)
        if not (e.free_symbols & zset):
            nd: tuple[Any, ...] = ("const", e, IntervalFunction([e], self.variables))
        elif e.is_Symbol:
            nd = ("var", self.zs.index(e))
        elif e.is_Add:
            nd = ("add", e, *[self._node(a) for a in e.args])
        elif e.is_Mul:
            const = [a for a in e.args if not (a.free_symbols & zset)]
            var = [a for a in e.args if a.free_symbols & zset]
            coef = sp.Mul(*const)
            acc = self._node(var[0])
            prod = var[0]
            for a in var[1:]:  # (a chain of bilinear terms)
                prod = prod * a
                nd_m = ("mul", prod, acc, self._node(a))
                self.nodes.append(nd_m)
                acc = len(self.nodes) - 1
                self._index[prod] = acc
            if coef == 1:
                self._index[e] = acc
                return acc
            nd = ("scale", e, IntervalFunction([coef], self.variables), acc)
        elif e.is_Pow or (e.is_Function and len(e.args) == 1):
            arg = e.args[0]
            if e.is_Pow and (e.args[1].free_symbols & zset):
                raise DomainError(f"no polyhedral relaxation of {e} (a variable exponent)")
            child = self._node(arg)
            phi = e.subs(arg, self._t) if not e.is_Pow else self._t ** e.args[1]
            key = phi
            if key not in self._uni:
                conv, dom = 0, -np.inf
                if e.is_Pow:
                    ex = e.args[1]
                    if ex.is_Integer and int(ex) >= 2 and int(ex) % 2 == 0:
                        conv = 1
                    elif ex == sp.Rational(1, 2):
                        conv, dom = -1, 0.0
                else:
                    conv = _CONVEX.get(type(e).__name__, 0)
                # (clip_domain is not used: a secant over a box cut to the domain by
                # clipping values would not be one; the argument's box is cut to the
                # domain's edge instead, ``dom``, where the relaxation knows it)
                self._uni[key] = (IntervalFunction([phi], [self._t]),
                                  IntervalFunction([sp.diff(phi, self._t)], [self._t]),
                                  conv, dom)
            nd = ("uni", e, child, key)
        else:
            raise DomainError(f"no polyhedral relaxation of {e}")
        self.nodes.append(nd)
        self._index[e] = len(self.nodes) - 1
        return len(self.nodes) - 1

    # ------------------------------------------------------------------ one box
    def lift(self, X: ConstrainedZonotope, lo: NDArray[np.float64], hi: NDArray[np.float64],
             u: NDArray[np.float64]
             ) -> tuple[ConstrainedZonotope, NDArray[np.float64], NDArray[np.float64],
                        NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """The lifted set over the box ``[lo, hi]`` (which holds ``X``'s truth), the
        outputs' affine forms ``(P, q, r)`` and the lifted box ``(L, U)``: every output
        ``g_i(z, u)`` of a ``z`` in ``X`` and the box is ``P_i v + q_i`` within ``r_i`` for
        some ``v`` of the lifted set whose first ``N`` coordinates are ``z``. Raises
        :class:`DomainError` or :class:`UnboundedSetError` where a node has no finite
        relaxation over the box."""
        box_lo, box_hi = np.concatenate([lo, u]), np.concatenate([hi, u])
        V = self.N + self.n_aux
        L, U = np.empty(V), np.empty(V)
        L[:self.N], U[:self.N] = lo, hi
        nb: dict[int, tuple[float, float]] = {}
        for j, f in enumerate(self.bounds):
            if f is not None:
                a, b = f(box_lo, box_hi)
                if not (np.isfinite(a[0]) and np.isfinite(b[0])):
                    raise UnboundedSetError(f"the node {self.nodes[j][1]} has no finite "
                                            "bound over the box")
                nb[j] = (float(a[0]), float(b[0]))
                L[self.aux_of[j]], U[self.aux_of[j]] = nb[j]
        vabs = np.maximum(np.abs(L), np.abs(U))
        forms: list[_Form] = []
        rows: list[tuple[NDArray[np.float64], float]] = []

        def mag(fm: _Form) -> float:
            return float(np.abs(fm[0]) @ vabs) + abs(fm[1]) + fm[2]

        def bounds_of(j: int) -> tuple[float, float]:
            if j in nb:
                return nb[j]
            p, q, r = forms[j]
            c = p @ (0.5 * L + 0.5 * U) + q
            rad = np.abs(p) @ (0.5 * (U - L)) + r + gamma(V + 2) * mag(forms[j])
            return float(round_down(c - rad)), float(round_up(c + rad))

        def row(terms: Sequence[tuple[float, _Form]], const: float) -> None:
            """``sum coef * form <= const`` holds at the truth: its computed row."""
            p = np.zeros(V)
            q = 0.0
            err = abs(const)
            for cf, fm in terms:
                p += cf * fm[0]
                q += cf * fm[1]
                err += abs(cf) * mag(fm)
            slack = sum(abs(cf) * fm[2] for cf, fm in terms)
            beta = const - q + slack + gamma(2 * len(terms) + 4) * err
            rows.append((p, float(round_up(round_up(beta)))))

        unit = np.eye(V)
        for j, nd in enumerate(self.nodes):
            kind = nd[0]
            if kind == "const":
                c_lo, c_hi = nd[2](box_lo, box_hi)
                m = 0.5 * float(c_lo[0]) + 0.5 * float(c_hi[0])
                forms.append((np.zeros(V), m,
                              float(round_up(max(c_hi[0] - m, m - c_lo[0])))))
            elif kind == "var":
                forms.append((unit[nd[1]].copy(), 0.0, 0.0))
            elif kind == "add":
                ch = [forms[c] for c in nd[2:]]
                p = np.sum([fm[0] for fm in ch], axis=0)
                q = float(sum(fm[1] for fm in ch))
                r = sum(fm[2] for fm in ch) + gamma(len(ch) + 1) * sum(mag(fm) for fm in ch)
                forms.append((p, q, float(round_up(r))))
            elif kind == "scale":
                c_lo, c_hi = nd[2](box_lo, box_hi)
                cm = 0.5 * float(c_lo[0]) + 0.5 * float(c_hi[0])
                cr = float(round_up(max(c_hi[0] - cm, cm - c_lo[0])))
                p, q, r = forms[nd[3]]
                rr = abs(cm) * r + cr * mag(forms[nd[3]]) + gamma(3) * abs(cm) * mag(
                    forms[nd[3]])
                forms.append((cm * p, cm * q, float(round_up(rr))))
            elif kind == "mul":
                a, b = forms[nd[2]], forms[nd[3]]
                (aL, aU), (bL, bU) = bounds_of(nd[2]), bounds_of(nd[3])
                z = (unit[self.aux_of[j]], 0.0, 0.0)
                # McCormick's envelopes of z = a b over [aL, aU] x [bL, bU]
                row([(aL, b), (bL, a), (-1.0, z)], _prod_up(aL, bL))
                row([(aU, b), (bU, a), (-1.0, z)], _prod_up(aU, bU))
                row([(1.0, z), (-aU, b), (-bL, a)], -_prod_dn(aU, bL))
                row([(1.0, z), (-aL, b), (-bU, a)], -_prod_dn(aL, bU))
                forms.append(z)
            else:  # univariate
                phi, dphi, conv, dom = self._uni[nd[3]]
                t = forms[nd[2]]
                tL, tU = bounds_of(nd[2])
                if tU < dom:
                    raise DomainError(f"{nd[1]} is undefined on the whole box")
                tL = max(tL, dom)  # (the truth's argument is in the domain)
                z = (unit[self.aux_of[j]], 0.0, 0.0)
                self._univariate(row, z, t, tL, tU, phi, dphi, conv, nd[1])
                forms.append(z)
        P = np.array([forms[o][0] for o in self.outputs],
                     dtype=np.float64).reshape(len(self.outputs), V)
        q_out = np.array([forms[o][1] for o in self.outputs], dtype=np.float64)
        r_out = np.array([forms[o][2] for o in self.outputs], dtype=np.float64)
        aux_lo, aux_hi = L[self.N:], U[self.N:]
        Xl = X.cartesian(ConstrainedZonotope.from_box(aux_lo, aux_hi)) if self.n_aux else X
        if rows:
            R = np.array([p for p, _ in rows])
            beta = np.array([b for _, b in rows])
            c, rad = 0.5 * L + 0.5 * U, 0.5 * (U - L)
            mid = R @ c
            spread = np.abs(R) @ rad + gamma(V + 2) * (np.abs(R) @ vabs)
            low, upp = round_down(mid - spread), round_up(mid + spread)
            keep = upp > beta  # (a row the box satisfies everywhere adds nothing)
            if keep.any():
                low = np.minimum(low[keep], beta[keep])
                Xl = Xl.intersect(ConstrainedZonotope.from_box(low, beta[keep]), R[keep])
        return Xl, P, q_out, r_out, L, U

    @staticmethod
    def _univariate(row, z: _Form, t: _Form, tL: float, tU: float, phi: IntervalFunction,
                    dphi: IntervalFunction, conv: int, what: Any) -> None:
        """The rows of ``z = phi(t)`` for ``t`` in ``[tL, tU]``: secant and tangents of a
        convex (``conv = 1``) or concave (``-1``) ``phi``, else the mean-value lines."""
        def val(x: float) -> tuple[float, float]:
            a, b = phi(np.array([x]), np.array([x]))
            if not (np.isfinite(a[0]) and np.isfinite(b[0])):
                raise UnboundedSetError(f"{what} is not finite at {x}")
            return float(a[0]), float(b[0])

        def der(x0: float, x1: float) -> tuple[float, float]:
            try:
                a, b = dphi(np.array([x0]), np.array([x1]))
            except DomainError:
                return -np.inf, np.inf
            return float(a[0]), float(b[0])

        span = max(abs(tL), abs(tU))
        if conv == 0:
            m = 0.5 * tL + 0.5 * tU
            dL, dU = der(tL, tU)
            if not (np.isfinite(dL) and np.isfinite(dU)):
                raise DomainError(f"no polyhedral relaxation of {what} over [{tL}, {tU}] "
                                  "(its derivative has no finite enclosure)")
            d = 0.5 * dL + 0.5 * dU
            R = float(round_up(max(dU - d, d - dL) * float(round_up(max(tU - m, m - tL)))))
            fl, fh = val(m)
            e = gamma(3) * (abs(d) * (span + abs(m)))
            row([(1.0, z), (-d, t)], float(round_up(fh - d * m + R + e)))
            row([(-1.0, z), (d, t)], float(round_up(-fl + d * m + R + e)))
            return
        s_ = conv  # (1: z below the secant, above tangents; -1: the mirror)
        fL, fU = val(tL), val(tU)
        # secant: s z - s k t <= s alpha at both ends (s phi - s k t is convex)
        if tU > tL:
            k = ((fU[0] + fU[1]) - (fL[0] + fL[1])) / (2.0 * (tU - tL))
        else:
            k = 0.0
        ends = [(fL, tL), (fU, tU)]
        if s_ > 0:
            alpha = max(f[1] - k * x for f, x in ends)
        else:
            alpha = min(f[0] - k * x for f, x in ends)
        e = gamma(3) * (abs(k) * span + max(abs(fL[0]), abs(fL[1]), abs(fU[0]), abs(fU[1])))
        row([(s_, z), (-s_ * k, t)], float(round_up(s_ * alpha + e)))
        # tangents at the ends and the middle: s (phi(x0) + d (t - x0)) <= s z
        for x0 in (tL, 0.5 * tL + 0.5 * tU, tU):
            dL, dU = der(x0, x0)
            if not (np.isfinite(dL) and np.isfinite(dU)):
                continue
            d = 0.5 * dL + 0.5 * dU
            f0 = val(x0)
            wid = float(round_up(max(dU - d, d - dL) * max(abs(tL - x0), abs(tU - x0))))
            base = f0[0] if s_ > 0 else f0[1]
            e = gamma(3) * (abs(d) * (span + abs(x0)) + abs(base))
            # s d t - s z <= s (d x0 - base) + wid
            row([(s_ * d, t), (-float(s_), z)], float(round_up(s_ * (d * x0 - base) + wid + e)))


def _prod_up(a: float, b: float) -> float:
    p = a * b
    return float(round_up(p + gamma(1) * abs(p))) if p != 0.0 else 0.0


def _prod_dn(a: float, b: float) -> float:
    p = a * b
    return float(round_down(p - gamma(1) * abs(p))) if p != 0.0 else 0.0
