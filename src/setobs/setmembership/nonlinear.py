"""Guaranteed state (and disturbance) estimation for nonlinear discrete-time systems.

``x+ = f(x, u) + w``, ``y = h(x, u) + v``, with ``w`` in ``W`` and ``v`` in ``V``
(bounded sets) and ``x_0`` in ``X_0``: :class:`NonlinearSetObserver` keeps a
constrained zonotope that contains every state consistent with the model and the
data, as in Rego, Raffo, Scott, Raimondo, "Guaranteed methods based on constrained
zonotopes for set-valued state estimation of nonlinear discrete-time systems",
Automatica 111 (2020) 108614 (below: Rego et al.).

Prediction (Rego et al., Sec. 4, the mean-value extension, their Theorem 2)
----------------------------------------------------------------------------
With ``B = [lo, hi]`` the certified interval hull of ``X_k`` and ``x_c`` its centre,
for every ``x`` in ``X_k`` the mean value theorem, row by row, gives
``f_i(x) = f_i(x_c) + J_i(xi_i) (x - x_c)`` with ``xi_i`` on the segment, so in ``B``.
With ``[J] = M +- R`` the interval Jacobian over ``B`` (:mod:`setobs.interval`) and
``|x - x_c| <= r`` (the box's radius),

.. math::  f(X_k) \\subseteq M X_k \\oplus \\{f(x_c) - M x_c\\} \\oplus [-R r, R r],

and ``X_(k+1)^- = M X_k + (f(x_c) - M x_c) + P + W`` with ``P`` that box, widened by
the enclosure of ``f(x_c)`` and the rounding of ``M x_c``.

``method="taylor"`` (Rego et al., Sec. 5, the first-order Taylor extension):
``f_i(x) = f_i(x_c) + J_i(x_c)(x - x_c) + 1/2 (x - x_c)^T H_i(xi_i) (x - x_c)``, the
Jacobian at the point ``x_c`` (an interval only by rounding) and the remainder
enclosed with the interval Hessian over ``B``: ``sum_j [H_ijj] [0, r_j^2] / 2 +
sum_(j<l) [H_ijl] [-r_j r_l, r_j r_l]``. Tighter when the Jacobian varies much over
``B`` and the box is small; looser on large boxes (the remainder is quadratic in
``r``).

Update (Rego et al., Sec. 4.2, the measurement as a generalized intersection)
----------------------------------------------------------------------------
The same enclosure of ``h`` over the predicted set's hull gives ``h(x) in M_h x +
(h(x_c) - M_h x_c) + P_h``, so every consistent ``x`` satisfies ``M_h x in Y_k :=
(y_k - h(x_c) + M_h x_c) - V - P_h`` and ``X_k = X_k^- cap_(M_h) Y_k`` (Scott et al.
2016, eq. (13)). Unmeasured outputs (NaN) are left out of the step.

Soundness
---------
Every enclosure is outer: the interval evaluator rounds outward; the set operations
carry their own rounding (:attr:`setobs.ConstrainedZonotope.c_err`, ``b_err``); the
interval hulls are certified LP bounds (of the posterior before its reduction: the
prediction maps the reduced set, a superset, but its enclosure of ``f`` holds on the
hull of the unreduced one, which holds the truth); the reductions are outer
(:func:`setobs.geometry.reduction.reduce_order`,
:func:`~setobs.geometry.reduction.eliminate_constraints`). An empty posterior is
reported only when certified (:meth:`setobs.ConstrainedZonotope.is_empty`), as
:class:`setobs.ModelInvalidatedError`.

The default, and the polyhedral relaxation
------------------------------------------
``method="auto"`` (the default) takes both forms and keeps, row by row, the one whose
interval image of ``B`` (``|M_i| r + rad_i``) is narrower: each row holds for every
``x`` in ``B`` whichever form gave it, so the combination is an enclosure too. After the
measurement, when the posterior's certified hull is narrower than the box ``h`` was
linearized over by more than ``RELINEARIZE_GAIN`` (10 %) in some coordinate, ``h`` is
linearized again over that hull (which holds the truth) and the prior is cut by the new
enclosure; the step's box is the meet of both hulls (at most ``RELINEARIZATIONS`` = 2
times a step). On sets of at most ``POLYHEDRAL_MAX_DIM`` dimensions, a map whose linear
remainder is more than ``POLYHEDRAL_SHARE`` of a row's image (a wide box on a curved
map: the first steps from a wide initial set) is enclosed by its polyhedral relaxation
instead.

``intersect_forms=True`` (with ``"auto"``): in the rows where the two linear forms
are of comparable width and differ in slope, the prediction keeps both for the same
state, ``{M_A x + p_A : x in X, (M_A - M_B)_S x + p_A,S - p_B = 0}`` (both hold at the
true state, so their intersection does; :meth:`NonlinearSetObserver._intersected`), at
the cost of a factor and a row per such row; the measurement likewise takes the other
form's strip ``M_B,i x in y_i - offset_B,i - V_i - [-rad_B,i, rad_B,i]`` in such rows.
Off by default: measured (``benchmarks/results/nonlinear_set.json``, "intersected
forms"), it narrows the held-out six tanks' bands by about 1 % and the Rego example's
mean hull radius by 0.2 %, and leaves the oscillator's as it was, for up to twice the
time per step.

``method="polyhedral"``: McCormick's relaxations of the factorable expression tree
(one auxiliary variable per nonlinear node, its interval bounds over ``B`` and the
linear inequalities that hold on ``B``: the four envelopes of a bilinear term, secant
and tangents of a convex or concave univariate function, the mean-value lines of any
other one), lifted into the constrained zonotope and outward rounded
(:mod:`setobs.setmembership._relax`; Rego, Raffo, Terra, Scott 2025 use the same
relaxations). Its lifted sets carry a factor and a row per inequality, several times
the linear forms' cost per step.

Domains
-------
The model holds at the true state, so a function whose argument box reaches outside
its domain (``sqrt`` of a level box reaching below 0) is enclosed over the box's part
inside it (:class:`~setobs.interval.IntervalFunction`'s ``clip_domain``): the natural
enclosure is sound there. The derivatives are not clipped (the mean value theorem needs
the segment in the domain): where no linear form has an enclosure over the box, the
step uses the natural interval enclosure alone -- ``f``'s box as the prediction, and
the measurement waits for later steps -- and reports ``status = "fallback"`` with
``stats["note"]`` naming the form and the expression that failed. A box entirely
outside a function's domain cannot hold a true state: :class:`setobs.DomainError`
says so (the model, its noise bounds or the initial set are wrong). A pole inside the
box (``1 / (4 + x)`` over a box holding ``-4``) has no enclosure in any form; the error
then names it (give a ``state_domain`` or a tighter initial set). ``state_domain`` at a
function's exact domain edge (``x >= -1`` for ``sqrt(x + 1)``) is accepted.

Complexity
----------
Each step's posterior is reduced once (constraints by
:func:`~setobs.geometry.reduction.eliminate_constraints`, generators by
:func:`~setobs.geometry.reduction.reduce_order`) to the current sizes. Then the reduced
set's certified hull is compared with the unreduced one's (the step's bands): while the
reduction widens a coordinate by more than ``reduction_growth`` (default
``REDUCTION_GROWTH`` = 2 %) of its width, the sizes grow by ``GROWTH_FACTOR`` (up to the
caps) and the posterior is reduced again from itself; the sizes never shrink. The
defaults (:meth:`NonlinearSetObserver.default_sizes`) start at ``START_STEPS`` = 8
steps' worth of the model's generators and constraints and cap the constraints so a
posterior stays within the compiled simplex's rows (``COMPILED_MAX_ROWS`` = 64, less a
step's measurement rows), the generators at the model's ratio. At the caps the growth
is measured every ``GROWTH_CHECK_EVERY`` steps, below them every other step
(``GROWTH_CHECK_BELOW_CAPS``). The step's hull LPs stop within
``HULL_REL_GAP`` (1e-3) of each coordinate's band at the previous step (certified
bounds all the same: a band at most twice that wider than the exact hull), and the step
runs with single-threaded BLAS (:mod:`setobs._blas`: its matrices are small, and two
threads made it slower). ``stats`` (per step, and
:attr:`~setobs.setmembership.SetEstimateResult.stats`) holds the sizes, the sizes before
the reduction, the measured growth (NaN where not measured), the re-linearizations and the notes.

Disturbances
------------
``disturbances=(d_1, ..)`` with ``increment_set``: each ``d`` is a state with
``d+ = d + dd`` and ``dd`` in the increment set (the SMFDO's model), so ``f`` and
``h`` may use them; the result's ``lo`` / ``hi`` / ``estimate`` are their bands.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._blas import with_single_threaded_blas
from .._lazy import optional_import
from .._rounding import gamma, round_down, round_up
from .._validation import as_matrix, as_vector
from ..exceptions import (
    ArgumentError,
    DomainError,
    EmptySetError,
    InvalidValueError,
    MagnitudeError,
    ModelInvalidatedError,
    UnboundedSetError,
)
from ..geometry import Box, ConstrainedZonotope
from ..geometry.box import box_center_radius
from ..geometry.reduction import eliminate_constraints, reduce_order
from ..geometry.zonotope import hull_with_status
from ..lp.factor import COMPILED_MAX_ROWS
from ..models.exosystem import NonlinearSystem
from ..models.interval import IntervalFunction
from ..models.nonlinear import NonlinearModel
from ._relax import Relaxation
from ._set_estimates import SetEstimateResult, SetEstimateStep
from ._sets import as_set, noise_set

__all__ = ["METHODS", "NonlinearSetObserver"]

#: The enclosures of ``f`` and ``h`` (module docstring): ``"auto"`` takes, row by row,
#: the narrower of the mean-value and Taylor forms, each cut by the natural interval
#: enclosure.
METHODS = ("auto", "mean-value", "taylor", "polyhedral")

#: The prediction is cut by ``f``'s natural interval enclosure in the coordinates where
#: that box is narrower than the linearization's interval image by more than this
#: fraction (:meth:`NonlinearSetObserver._cut`).
CUT_GAIN = 0.05

#: The measurement is taken again with ``h`` re-linearized over the posterior's hull
#: when that hull is narrower than the box ``h`` was linearized over by more than this
#: fraction in some coordinate (at most :data:`RELINEARIZATIONS` times a step).
RELINEARIZE_GAIN = 0.1

#: ``method="auto"`` takes the polyhedral relaxation (:mod:`._relax`) instead of the
#: linear forms for a map whose linear remainder is more than this share of some row's
#: interval image of the box, on sets of at most :data:`POLYHEDRAL_MAX_DIM` dimensions
#: (its lifted sets cost several times the linear forms' step). Measured on the Rego
#: example: the first steps' mean hull radius 0.142 / 0.095 against 0.147 / 0.099.
POLYHEDRAL_SHARE = 0.25
POLYHEDRAL_MAX_DIM = 4

#: ``method="auto"`` skips the mean-value form where the Taylor form's remainder is at
#: most this share of every row's interval image of the box (the mean-value form's
#: image is then no narrower, up to about that share: it holds the Jacobian's range).
AUTO_TAYLOR_SHARE = 0.01

#: The prediction intersects the two linear forms (:meth:`NonlinearSetObserver._intersected`)
#: in the rows where the wider is at most this many times the narrower's interval image
#: and their slopes differ by more than ``INTERSECT_SLOPE`` of the narrower remainder.
INTERSECT_RATIO = 2.0
INTERSECT_SLOPE = 0.1

#: Largest number of re-linearizations of ``h`` in a step.
RELINEARIZATIONS = 2

#: A reduction is kept when it widens no coordinate of the posterior's hull by more than
#: this fraction of that coordinate's width; otherwise the set keeps more generators and
#: constraints (by :data:`GROWTH_FACTOR`, up to the caps) and is reduced again.
REDUCTION_GROWTH = 0.02

#: Factor by which the sizes grow when a reduction widens the hull too much.
GROWTH_FACTOR = 1.5

#: Steps of the model's constraints the default sizes start from
#: (:meth:`NonlinearSetObserver.default_sizes`).
START_STEPS = 8


#: Candidates whose exact overshoots (two LPs each) decide the constraint eliminations
#: of a set of at most :data:`REFINE_MAX_DIM` dimensions; above it interval propagation
#: alone ranks them (:func:`setobs.geometry.reduction.eliminate_constraints`'s
#: ``refine``). Measured (``benchmarks/nonlinear_set.py``): on the two-state oscillator
#: the exact overshoots took the late unmeasured band from 3.9 to 2.2 times an inner
#: bound for 7 ms a step; on six and thirty tanks they moved the bands by under 1 % and
#: 7 % for 1.3 and 2.7 times the time.
ELIMINATION_REFINE = 8
REFINE_MAX_DIM = 4

#: Eliminations per evaluation of the heuristics (``batch``).
ELIMINATION_BATCH = 64

#: The hulls of a step (the posterior's bands, and the reduced set's for the growth
#: check) stop each LP within this fraction of its coordinate's width at the previous
#: step (the unreduced set's, for the growth check): certified bounds, each band at most
#: twice that wider than its exact hull.
HULL_REL_GAP = 1e-3

#: At the caps the sizes cannot grow: the reduction's growth of the hull (two LPs per
#: coordinate) is then measured every this many steps only (NaN in between).
GROWTH_CHECK_EVERY = 10

#: Below the caps, every this many steps (a size's growth is decided a step later at
#: most; each check costs a hull of the reduced set).
GROWTH_CHECK_BELOW_CAPS = 2


class _Sparse:
    """The nonzero entries of an expression array, compiled once (an ``(m, n)`` Jacobian
    or ``(m, n, n)`` Hessian is mostly zeros on a cascade)."""

    def __init__(self, arr: Any, shape: tuple[int, ...], variables: Sequence[Any]) -> None:
        flat = list(arr)
        self.shape = shape
        self.index = np.array([i for i, e in enumerate(flat) if e != 0], dtype=np.int64)
        self.fn = IntervalFunction([flat[i] for i in self.index], variables)

    def __call__(self, lo: NDArray[np.float64], hi: NDArray[np.float64]
                 ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        out_lo = np.zeros(int(np.prod(self.shape)))
        out_hi = np.zeros_like(out_lo)
        if self.index.size:
            a, b = self.fn(lo, hi)
            out_lo[self.index], out_hi[self.index] = a, b
        return out_lo.reshape(self.shape), out_hi.reshape(self.shape)


class _Map:
    """``g(z, u)`` (``f`` or ``h``) with its enclosures over a box of ``z``."""

    def __init__(self, sp: Any, exprs: list[Any], zs: list[Any], us: list[Any]) -> None:
        self.n, self.m = len(zs), len(exprs)
        variables = [*zs, *us]
        self.value = IntervalFunction(exprs, variables, clip_domain=True)
        J = sp.Matrix(exprs).jacobian(zs)
        self.jac = _Sparse(list(J), (self.m, self.n), variables)
        zset = set(zs)
        # affine in z (the Jacobian depends on u at most): every form is exact
        self.affine = all(not (sp.sympify(e).free_symbols & zset) for e in J)
        # the Hessian from the Jacobian's nonzero entries, each differentiated only by the
        # variables it holds (a cascade's (n, n, n) array has O(n) nonzeros)
        H = [0] * (self.m * self.n * self.n)
        for i in range(self.m):
            for j in range(self.n):
                e = J[i, j]
                if e == 0:
                    continue
                for k, zk in enumerate(zs):
                    if zk in e.free_symbols:
                        H[(i * self.n + j) * self.n + k] = sp.diff(e, zk)
        self.hess = _Sparse(H, (self.m, self.n, self.n), variables)
        self._args = (exprs, zs, us)
        self._relax: Relaxation | None = None

    @property
    def relaxation(self) -> Relaxation:
        """The polyhedral relaxation (:mod:`setobs.setmembership._relax`), compiled on
        first use."""
        if self._relax is None:
            sp = optional_import("sympy", extra="nonlinear", feature="NonlinearSetObserver")
            self._relax = Relaxation(sp, *self._args)
        return self._relax

    def __getstate__(self) -> dict[str, Any]:
        # (the relaxation keeps sympy's Dummy and compiled closures: rebuilt on first use)
        return {**self.__dict__, "_relax": None}

    def enclose(self, lo: NDArray[np.float64], hi: NDArray[np.float64],
                u: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The natural interval enclosure ``[g](B)`` over the box, at the input ``u``, at
        the points where ``g`` is defined (the model holds at the truth:
        :class:`~setobs.interval.IntervalFunction`'s ``clip_domain``)."""
        return self.value(np.concatenate([lo, u]), np.concatenate([hi, u]))

    def linearize(self, lo: NDArray[np.float64], hi: NDArray[np.float64],
                  u: NDArray[np.float64], form: str
                  ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
        """``(M, offset, rad)`` with ``g(z, u) in M z + offset + [-rad, rad]`` for every
        ``z`` in ``[lo, hi]`` by the ``form`` (``"mean-value"`` or ``"taylor"``; module
        docstring; all rounding inside ``rad``). Raises :class:`DomainError` where a
        derivative has no enclosure over the box and :class:`UnboundedSetError` where
        it is not finite."""
        c = 0.5 * lo + 0.5 * hi  # (in the box: the mean value theorem's segment stays in it)
        r = round_up(np.maximum(hi - c, c - lo))
        zc = np.concatenate([c, u])
        gc_lo, gc_hi = self.value(zc, zc)
        if form == "mean-value" or self.affine:  # the Jacobian over the box
            J_lo, J_hi = self.jac(np.concatenate([lo, u]), np.concatenate([hi, u]))
            rem_c, rem_r = np.zeros(self.m), np.zeros(self.m)
        else:  # Taylor: the Jacobian at c, the Hessian over the box
            J_lo, J_hi = self.jac(zc, zc)
            H_lo, H_hi = self.hess(np.concatenate([lo, u]), np.concatenate([hi, u]))
            if not (np.isfinite(H_lo).all() and np.isfinite(H_hi).all()):
                raise UnboundedSetError("the Hessian's enclosure over the box is not finite")
            rem_c, rem_r = _quadratic_remainder(H_lo, H_hi, r)
        if not (np.isfinite(J_lo).all() and np.isfinite(J_hi).all()
                and np.isfinite(gc_lo).all() and np.isfinite(gc_hi).all()):
            raise UnboundedSetError("the enclosure of the model over the current box is not "
                                    "finite (an overflow): bound the initial state set "
                                    "tighter or rescale the model")
        M, R = box_center_radius(J_lo, J_hi)
        g_mid, g_rad = box_center_radius(gc_lo, gc_hi)
        Mc = M @ c
        offset = g_mid - Mc + rem_c
        # |x - c| <= r: (J - M)(x - c) within R r; the rounding of M c, of the offset's
        # sums, and of R r itself (gamma of the dot products' length)
        k = self.n + 3
        rad = R @ r + g_rad + rem_r + gamma(k) * (np.abs(M) @ np.abs(c) + np.abs(g_mid)
                                                  + np.abs(rem_c) + np.abs(offset) + R @ r)
        return M, offset, round_up(rad * (1.0 + gamma(4)))

    def enclosure(self, lo: NDArray[np.float64], hi: NDArray[np.float64],
                  u: NDArray[np.float64], forms: Sequence[str]
                  ) -> tuple[tuple[NDArray[np.float64], NDArray[np.float64],
                                   NDArray[np.float64]] | None, dict[str, str], list[Any]]:
        """The linear enclosure over the box from the ``forms``, row by row the one whose
        interval image of the box (``|M_i| r + rad_i``) is narrowest (each row holds
        for every ``z`` in the box whichever form gave it; ``None`` when none has an
        enclosure there), the forms that failed with why, and every form's own
        enclosure (for their intersection, :func:`_second_form`)."""
        got, failed = [], {}
        lin_forms = [f for f in forms if f != "polyhedral"] or ["mean-value", "taylor"]
        if len(lin_forms) > 1:
            # Taylor first: where its remainder is negligible in every row, the
            # mean-value form cannot be narrower by more (AUTO_TAYLOR_SHARE)
            lin_forms = ["taylor"] + [f for f in lin_forms if f != "taylor"]
        _, r = box_center_radius(lo, hi)
        for form in (("mean-value",) if self.affine else lin_forms):
            try:
                got.append(self.linearize(lo, hi, u, form))
            except (DomainError, UnboundedSetError) as exc:
                failed[form] = str(exc)
                continue
            if form == "taylor" and len(lin_forms) > 1:
                M, _, rad = got[-1]
                with np.errstate(invalid="ignore", divide="ignore"):
                    share = rad / (np.abs(M) @ r + rad)
                if np.nanmax(share, initial=0.0) <= AUTO_TAYLOR_SHARE:
                    break
        if not got:
            return None, failed, got
        if len(got) == 1:
            return got[0], failed, got
        return _take(got, _narrowest(got, r)[0]), failed, got


def _narrowest(got: list[Any], r: NDArray[np.float64]
               ) -> tuple[NDArray[np.int64], NDArray[np.float64]]:
    """Row by row the index of the enclosure of ``got`` whose interval image of the box
    (radius ``r``: ``|M_i| r + rad_i``) is narrowest, and every form's widths."""
    width = np.array([np.abs(M) @ r + rad for M, _, rad in got])
    return np.argmin(width, axis=0), width


def _take(got: list[Any], pick: NDArray[np.int64]) -> tuple[
        NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(M, offset, rad)`` with row ``i`` from the enclosure ``got[pick[i]]``."""
    rows = np.arange(pick.size)
    M = np.array([got[pick[i]][0][i] for i in rows]).reshape(pick.size, -1)
    offset = np.array([got[pick[i]][1][i] for i in rows])
    rad = np.array([got[pick[i]][2][i] for i in rows])
    return M, offset, rad


def _second_form(lin: Any, forms: list[Any], box: Box) -> tuple[
        NDArray[np.int64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """The rows ``S`` where the form not picked row by row (``lin``: the narrower, from
    two ``forms``) is at most :data:`INTERSECT_RATIO` times as wide over the box and
    differs in slope (``|M_A,i - M_B,i| r`` above :data:`INTERSECT_SLOPE` of the smaller
    remainder), and that form's ``(M_B, offset_B, rad_B)`` in every row."""
    M, _, rad = lin
    _, r = box_center_radius(box.lo, box.hi)
    pick, width = _narrowest(forms, r)  # (as in lin: the form not picked is the other)
    other = 1 - pick
    MB, oB, rB = _take(forms, other)
    rows = np.arange(pick.size)
    slope = np.abs(M - MB) @ r
    S = np.flatnonzero((width[other, rows] <= INTERSECT_RATIO * width[pick, rows])
                       & (slope > INTERSECT_SLOPE * np.minimum(rad, rB)))
    return S, MB, oB, rB


def _quadratic_remainder(H_lo: NDArray[np.float64], H_hi: NDArray[np.float64],
                         r: NDArray[np.float64]) -> tuple[NDArray[np.float64],
                                                          NDArray[np.float64]]:
    """Centre and radius of ``1/2 d^T [H_i] d`` over ``|d| <= r``: the diagonal terms
    ``[H_ijj] [0, r_j^2]``, the others ``[H_ijl] [-r_j r_l, r_j r_l]`` (symmetric, so
    the pairs ``j != l`` count twice), all rounded outward by a relative ``gamma``."""
    rr = np.outer(r, r)
    off = ~np.eye(r.size, dtype=bool)
    mag = np.maximum(np.abs(H_lo), np.abs(H_hi))
    off_rad = 0.5 * (mag * rr * off).sum(axis=(1, 2))
    d2 = r * r
    dl = np.einsum("ijj->ij", H_lo)
    dh = np.einsum("ijj->ij", H_hi)
    # [h_lo, h_hi] * [0, r^2]: min(h_lo r^2, 0), max(h_hi r^2, 0)
    diag_lo = 0.5 * (np.minimum(dl, 0.0) * d2).sum(axis=1)
    diag_hi = 0.5 * (np.maximum(dh, 0.0) * d2).sum(axis=1)
    lo, hi = diag_lo - off_rad, diag_hi + off_rad
    c = 0.5 * lo + 0.5 * hi
    g = gamma(2 * r.size * r.size + 4)
    rad = 0.5 * (hi - lo) + g * (np.abs(lo) + np.abs(hi) + mag.reshape(len(lo), -1)
                                 @ rr.ravel())
    return c, round_up(rad)


class NonlinearSetObserver:
    """Guaranteed state estimator for ``x+ = f(x, u) + w``, ``y = h(x, u) + v``.

    Parameters
    ----------
    f : NonlinearModel, NonlinearSystem, or sequence of sympy expressions or strings
        The model (:class:`setobs.models.NonlinearModel`; an exosystem
        :class:`~setobs.models.NonlinearSystem` is converted by
        :meth:`~setobs.models.NonlinearModel.from_exosystem`), and then ``h``,
        ``states``, ``inputs`` and ``disturbances`` are not given; or the state map
        (``n`` components) in the symbols of ``states``, ``inputs`` and
        ``disturbances``.
    h : sequence of sympy expressions or strings
        The output map (``l`` components), when ``f`` is not a model.
    states : sequence of sympy symbols or names
        ``x`` (``n``).
    inputs : sequence of sympy symbols or names
        ``u`` (known inputs; default none).
    process_noise : ConstrainedZonotope, Box, radii or None
        ``W`` (in state space; a scalar is one radius for every state).
    measurement_noise : ConstrainedZonotope, Box, radii or None
        ``V`` (in output space).
    initial_state_set : ConstrainedZonotope or Box
        ``X_0``; bounded.
    method : {"auto", "mean-value", "taylor"}
        The enclosure of ``f`` and ``h`` (module docstring). ``"auto"`` (default): row
        by row the narrower of the two over the current box, and ``h`` re-linearized
        over the posterior's hull while it shrinks.
    disturbances : sequence of sympy symbols or names
        ``d``, with ``d+ = d + dd`` (default none).
    increment_set : ConstrainedZonotope, Box or radii
        The set of ``dd`` (with ``disturbances``).
    initial_disturbance_set : ConstrainedZonotope or Box
        The set of ``d_0`` (with ``disturbances``); bounded.
    state_domain : Box, optional
        Where the states are known to lie (physical limits: levels ``>= 0``); each
        predicted set is cut by it where its hull leaves it, so the enclosures are
        evaluated inside it (``sqrt`` of a level). Sound only if the true states never
        leave it; a prediction entirely outside it is reported as inconsistent.
    max_generators, max_constraints : int, optional
        The caps of the set's complexity (defaults: :meth:`default_sizes`, from ``n``,
        the outputs and the noise sets' generators). The sizes start lower and grow
        while a reduction would widen the posterior's hull by more than
        ``reduction_growth`` (module docstring, "Complexity").
    reduction_growth : float or None
        The fraction of a band's width a reduction may add (default
        :data:`REDUCTION_GROWTH`, 2 %); ``None``: fixed sizes at the caps, no check.
    intersect_forms : bool
        With ``method="auto"``: the prediction intersects the mean-value and Taylor
        forms for the same state (:meth:`_intersected`) in the rows where both are of
        comparable width and slope, instead of keeping the narrower alone, and the
        measurement takes both forms' strips there. Off by default: what it buys and
        costs is in the module docstring ("The default, and the polyhedral
        relaxation").
    dt : float, optional
        Sampling time (the results' time axis).

    Notes
    -----
    Rego, Raffo, Scott, Raimondo (Automatica 2020), the mean-value extension (their
    Sec. 4) and the first-order Taylor extension (their Sec. 5), with the measurement
    update as a generalized intersection (Scott et al. 2016, eq. (13)); the soundness
    argument is in :mod:`setobs.setmembership.nonlinear`.

    Examples
    --------
    >>> import setobs as so
    >>> obs = so.NonlinearSetObserver(["0.9*x + 0.1*sin(x)"], ["x**3 + x"], ["x"],
    ...                               process_noise=0.01, measurement_noise=0.05,
    ...                               initial_state_set=so.Box([-1.0], [1.0]))
    >>> step = obs.step([0.5])
    >>> bool(step.state_lo[0] < 0.45 < step.state_hi[0])
    True
    """

    def __init__(self, f: Any, h: Any = None, states: Sequence[Any] = (),
                 inputs: Sequence[Any] = (), *,
                 process_noise: Any, measurement_noise: Any, initial_state_set: Any,
                 method: str = "auto", disturbances: Sequence[Any] = (),
                 increment_set: Any = None, initial_disturbance_set: Any = None,
                 state_domain: Any = None, max_generators: int | None = None,
                 max_constraints: int | None = None,
                 reduction_growth: float | None = REDUCTION_GROWTH,
                 intersect_forms: bool = False, dt: float | None = None) -> None:
        sp = optional_import("sympy", extra="nonlinear", feature="NonlinearSetObserver")
        if method not in METHODS:
            raise InvalidValueError(f"method must be one of {METHODS}, got {method!r}")
        model = self._model(f, h, states, inputs, disturbances)
        self.model = model
        xs, us, ds = list(model.states), list(model.inputs), list(model.disturbances)
        fx, hx = list(model.f), list(model.h)
        n, q = model.n, model.q
        dt = model.dt if dt is None else dt
        self.method = method
        self.forms = ("mean-value", "taylor") if method == "auto" else (method,)
        zs = xs + ds
        self._f = _Map(sp, fx + list(ds), zs, us)  # (d+ = d: the increment is noise)
        self._h = _Map(sp, hx, zs, us)
        W = noise_set("process_noise", process_noise, n)
        V = noise_set("measurement_noise", measurement_noise, self.l)
        X0 = as_set("initial_state_set", initial_state_set, n)
        if X0 is None or not X0.is_bounded:
            raise InvalidValueError("initial_state_set must be a bounded set (the "
                                    "enclosures need a bounded box of the state)")
        if q:
            if increment_set is None or initial_disturbance_set is None:
                raise ArgumentError("disturbances need increment_set and "
                                    "initial_disturbance_set")
            DD = noise_set("increment_set", increment_set, q)
            D0 = as_set("initial_disturbance_set", initial_disturbance_set, q)
            if D0 is None or not D0.is_bounded:
                raise InvalidValueError("initial_disturbance_set must be a bounded set (the "
                                        f"enclosures need a bounded box), got {D0!r}")
            X0 = X0.cartesian(D0)
            W = _cartesian(W, n, DD, q)
        elif increment_set is not None or initial_disturbance_set is not None:
            raise ArgumentError("increment_set and initial_disturbance_set need disturbances")
        self.W, self.V, self.X0 = W, V, X0
        N = n + q
        self._W_box = hull_with_status(W)[0] if W is not None else Box(np.zeros(N),
                                                                          np.zeros(N))
        self.domain = None
        if state_domain is not None:
            if not isinstance(state_domain, Box) or state_domain.dim != n:
                raise ArgumentError(f"state_domain must be a Box of the {n} states, got "
                                    f"{state_domain!r}")
            inf = np.full(q, np.inf)
            self.domain = (np.concatenate([state_domain.lo, -inf]),
                           np.concatenate([state_domain.hi, inf]))
        g0, c0, g_cap, c_cap = self.default_sizes(
            N, self.l, 0 if W is None else W.n_gen, 0 if V is None else V.n_gen)
        fixed = reduction_growth is None
        if max_generators is not None:
            g_cap = int(max_generators)
        if max_constraints is not None:
            c_cap = int(max_constraints)
        if g_cap < N or c_cap < 0:
            raise InvalidValueError(f"max_generators must be at least {N} and "
                                    f"max_constraints nonnegative, got {g_cap} and {c_cap}")
        if reduction_growth is not None and not (0.0 < float(reduction_growth) < np.inf):
            raise InvalidValueError("reduction_growth must be a positive fraction or None, "
                                    f"got {reduction_growth!r}")
        self.intersect_forms = bool(intersect_forms) and method == "auto"
        self.max_generators, self.max_constraints = g_cap, c_cap
        self.reduction_growth = (None if reduction_growth is None
                                 else float(reduction_growth))
        self._start_sizes = (g_cap, c_cap) if fixed else (min(g0, g_cap), min(c0, c_cap))
        self.dt = dt
        self.reset()

    @staticmethod
    def _model(f: Any, h: Any, states: Sequence[Any], inputs: Sequence[Any],
               disturbances: Sequence[Any]) -> NonlinearModel:
        """The observer's model: ``f`` itself when it is a :class:`NonlinearModel` (an
        exosystem :class:`~setobs.models.NonlinearSystem` converted), else the model of
        ``f, h, states, inputs, disturbances``."""
        if isinstance(f, NonlinearModel | NonlinearSystem):
            if h is not None or len(states) or len(inputs) or len(disturbances):
                raise ArgumentError(
                    "NonlinearSetObserver(model, ...) takes the model's h, states, inputs "
                    "and disturbances from the model: give them to NonlinearModel instead")
            return f if isinstance(f, NonlinearModel) else NonlinearModel.from_exosystem(f)
        if h is None or not len(states):
            raise ArgumentError("NonlinearSetObserver needs a NonlinearModel, or f, h and "
                                "the states")
        return NonlinearModel(f, h, states, inputs, disturbances)

    @staticmethod
    def default_sizes(N: int, l: int, w_gens: int, v_gens: int) -> tuple[int, int, int, int]:
        """The default sizes ``(generators, constraints)`` to start from and their caps.

        A step adds about ``d_g = N + w_gens + v_gens`` generators (the linearization's
        remainder box, ``W``'s and ``V``'s generators) and ``d_c = l`` constraints (one
        per measured output). The constraints are capped so that a posterior (the kept
        ones and a step's ``l``) stays within the compiled simplex's
        :data:`~setobs.lp.factor.COMPILED_MAX_ROWS` rows, where a hull's ``2 N`` LPs run
        on the compiled simplex (above it every LP goes to HiGHS; below, the compiled
        path was measured 2-9 times faster there); they start at :data:`START_STEPS`
        steps' worth. The generators follow the constraints at the model's ratio
        ``d_g / d_c`` (at least ``2 N`` more than the constraints): generators beyond that
        ratio were measured to buy nothing while the constraints are capped.

        Parameters
        ----------
        N : int
            The set's dimension (states and disturbances).
        l : int
            The outputs.
        w_gens, v_gens : int
            The generators of the process and measurement noise sets.

        Returns
        -------
        tuple of int
            ``(g0, c0, g_cap, c_cap)``.
        """
        dg, dc = N + w_gens + v_gens, max(l, 1)
        c_cap = COMPILED_MAX_ROWS - dc if 2 * dc <= COMPILED_MAX_ROWS else 2 * N
        c0 = min(c_cap, max(2, START_STEPS * dc))

        def gens(c: int) -> int:
            return max(c + 2 * N, int(np.ceil(c * dg / dc)))
        return gens(c0), c0, gens(c_cap), c_cap

    # the model's sizes and variables, read from it (one source)
    @property
    def n(self) -> int:
        """Number of states."""
        return self.model.n

    @property
    def q(self) -> int:
        """Number of disturbances."""
        return self.model.q

    @property
    def l(self) -> int:
        """Number of outputs."""
        return self.model.l

    @property
    def p(self) -> int:
        """Number of known inputs."""
        return self.model.p

    @property
    def states(self) -> tuple:
        """The state variables."""
        return tuple(self.model.states)

    @property
    def inputs(self) -> tuple:
        """The input variables."""
        return tuple(self.model.inputs)

    @property
    def disturbances(self) -> tuple:
        """The disturbance variables."""
        return tuple(self.model.disturbances)

    def reset(self) -> None:
        """Back to ``X_0`` at step 0."""
        self.k = 0
        self.prior: ConstrainedZonotope = self.X0
        self.prior_box: Box | None = None  # (a certified box of the prior, from the model)
        self.posterior: ConstrainedZonotope | None = None
        self.sizes = self._start_sizes
        self.restarts = 0
        self.pred_note = ""  # (why the prediction fell back, if it did)
        self._last_width: NDArray[np.float64] | None = None  # (the last step's bands)

    # ------------------------------------------------------------------ one step
    def update(self, y: ArrayLike, u: ArrayLike | None = None) -> SetEstimateStep:
        """Deprecated name of :meth:`step`.

        Parameters
        ----------
        y : array_like, shape (l,)
            The measurement.
        u : array_like, shape (p,), optional
            The input at step ``k``.
        """
        warnings.warn("NonlinearSetObserver.update() is deprecated: use step() (the "
                      "estimators' one protocol: reset, step, run)", DeprecationWarning,
                      stacklevel=2)
        return self.step(y, u)

    @with_single_threaded_blas
    def step(self, y: ArrayLike, u: ArrayLike | None = None) -> SetEstimateStep:
        """Take the measurement ``y_k`` (NaN: not measured) with the input ``u_k``, and
        return step ``k``'s certified bounds; then predict step ``k + 1``.

        Parameters
        ----------
        y : array_like, shape (l,)
            The measurement.
        u : array_like, shape (p,), optional
            The input at step ``k`` (in ``h`` and in ``f``).

        Returns
        -------
        SetEstimateStep
            ``state_lo`` / ``state_hi`` (the states), ``lo`` / ``hi`` / ``estimate`` (the
            disturbances' bands and centres; empty without disturbances); ``stats``: the
            sizes kept, the reduction's growth of the hull, the forms that failed.

        Raises
        ------
        ModelInvalidatedError
            The posterior is certified empty: the data contradict the model, its noise
            bounds or the initial set.
        """
        yv = as_vector("y", y, size=self.l, allow_nan=True)
        if self.p and u is None:
            raise ArgumentError(f"u is required: the model has {self.p} inputs")
        uv = as_vector("u", u, size=self.p) if self.p and u is not None else np.zeros(0)
        try:
            return self._advance(yv, uv)
        except (MagnitudeError, InvalidValueError) as exc:
            # (a set that grows past the double range fails in an operation the user never
            # called -- a linear map, a bound named lo -- : say what happened instead)
            raise UnboundedSetError(
                f"the state set diverged at step {self.k}: its data left the double "
                "range (the model's enclosure over the set grows faster than the data "
                "bound it); bound the initial state set tighter, give a state_domain, or "
                f"measure more (from: {exc})") from exc

    def _invalidated(self, what: str) -> ModelInvalidatedError:
        return ModelInvalidatedError(
            f"{what} at step {self.k} contradicts the model: the set of consistent "
            "states is empty (certified)", self.k,
            hint="what to do: if the sample is an outlier or a fault, it is found; if the "
            "model and the record are right, the noise bounds are too small (a larger "
            "measurement_noise / process_noise)"
            + (", or initial_state_set does not hold the true initial state (every set "
               "derives from it; widen it)" if self.k < 50 else
               ", or initial_state_set missed the true initial state (widen it)"))

    def _hull(self, X: ConstrainedZonotope, what: str, early: bool = False) -> tuple[Box, bool]:
        """``X``'s certified hull; with ``early``, each bound within :data:`HULL_REL_GAP`
        of the previous step's band of its coordinate (exact at the first step)."""
        gap = None
        if early and self._last_width is not None:
            gap = HULL_REL_GAP * self._last_width
        try:
            return hull_with_status(X, gap)
        except EmptySetError:
            raise self._invalidated(what) from None

    def _advance(self, yv, uv) -> SetEstimateStep:
        """:meth:`update` for checked data."""
        X = self.prior
        notes = [self.pred_note] if self.pred_note else []
        fallback = bool(self.pred_note)
        msk = ~np.isnan(yv)
        box = self.prior_box
        if box is None or (msk.any() and not self._h.affine):
            # (h is linearized over the prior's box: its certified hull, the tightest;
            # an affine h is exact over any box, and the model's box is enough)
            hb, fb = self._hull(X, "the prediction")
            fallback |= fb
            box = hb if box is None else _meet(box, hb)
        X, box = self._in_domain(X, box)
        prior = X
        relin = 0
        if msk.any():
            X, note = self._measure(prior, box, yv, uv, msk)
            if note:
                fallback, notes = True, [*notes, note]
        post, fb = self._hull(X, "the measurement", early=True)
        fallback |= fb
        while (msk.any() and not self._h.affine and relin < RELINEARIZATIONS
               and self.method in ("auto", "polyhedral")
               and np.any(post.hi - post.lo < (1.0 - RELINEARIZE_GAIN) * (box.hi - box.lo))):
            # h linearized again over the posterior's hull, which holds the truth: the
            # prior cut by that enclosure holds it too (the enclosure holds at the truth,
            # which lies in the hull), as does the meet of the two hulls
            box = post
            X2, note = self._measure(prior, box, yv, uv, msk)
            relin += 1
            if note:
                break
            post2, fb = self._hull(X2, "the measurement", early=True)
            fallback |= fb
            X, post = X2, _meet(post, post2)
        if self.domain is not None:  # (X lies in the domain: the cut above, or its prior's
            # hull did; the certified hull may pass its edge by the LP's outward rounding)
            post = Box(np.maximum(post.lo, self.domain[0]), np.minimum(post.hi, self.domain[1]))
        if not (np.isfinite(post.lo).all() and np.isfinite(post.hi).all()):
            raise UnboundedSetError(
                f"the state set diverged at step {self.k}: the hull of the posterior is not "
                f"finite ({post!r}); bound the initial state set tighter, or give a "
                "state_domain")
        unreduced = (X.n_gen, X.n_con)
        self.restarts = 0
        X, growth = self._reduce(X, post)
        if self.restarts:
            fallback = True
            notes.append("the constraint elimination stalled at its rounding budget: the "
                         "set restarted from its certified hull")
        self.posterior = X
        w = post.hi - post.lo
        self._last_width = np.where(np.isfinite(w), w, 0.0)
        stats = {"generators": self.sizes[0], "constraints": self.sizes[1],
                 "unreduced_generators": unreduced[0], "unreduced_constraints": unreduced[1],
                 "reduction_growth": growth, "relinearizations": relin,
                 "note": "; ".join(notes)}
        step = self._step(post, "fallback" if fallback else "ok", stats)
        self._predict(X, post, uv)
        self.k += 1
        return step

    def _measure(self, X: ConstrainedZonotope, box: Box, yv, uv, msk
                 ) -> tuple[ConstrainedZonotope, str]:
        """``X`` intersected with the states whose ``h`` (linearized over ``box``, which
        holds the truth) is within the noise of the measured outputs; unchanged, with
        why, when ``h`` has no linear enclosure over the box (the data wait)."""
        poly, enc = self._polyhedral(self._h, box, uv)
        if poly:
            try:
                Xl, P, q, r, _, _ = self._h.relaxation.lift(X, box.lo, box.hi, uv)
            except (DomainError, UnboundedSetError) as exc:
                out, why = self._measure_linear(X, box, yv, uv, msk, enc)
                if self.method != "polyhedral":
                    return out, why
                note = f"h's polyhedral relaxation failed ({exc}); the linear forms carry"
                return out, note + ("; " + why if why else "")
            Xl = Xl.intersect(self._observed(yv, msk, q, r), P[msk])
            return Xl.project(list(range(X.dim))), ""
        return self._measure_linear(X, box, yv, uv, msk, enc)

    def _polyhedral(self, g: _Map, box: Box, uv) -> tuple[bool, Any]:
        """Whether ``g``'s enclosure over the box is the polyhedral relaxation: always with
        ``method="polyhedral"``; with ``"auto"``, on sets of at most
        :data:`POLYHEDRAL_MAX_DIM` dimensions while the linear forms' remainder is more
        than :data:`POLYHEDRAL_SHARE` of some row's interval image of the box (a large box
        on a curved ``g``: the first steps from a wide initial set). With it, the linear
        enclosure ``(lin, failed, forms)`` when the decision computed it (else ``None``), for
        the linear path to reuse."""
        if g.affine or self.method not in ("auto", "polyhedral"):
            return False, None
        if self.method == "polyhedral":
            return True, None
        if self.n + self.q > POLYHEDRAL_MAX_DIM:
            return False, None
        enc = g.enclosure(box.lo, box.hi, uv, self.forms)
        if enc[0] is None:
            return True, enc
        M, _, rad = enc[0]
        _, r = box_center_radius(box.lo, box.hi)
        with np.errstate(invalid="ignore", divide="ignore"):
            share = rad / (np.abs(M) @ r + rad)
        return bool(np.nanmax(share, initial=0.0) > POLYHEDRAL_SHARE), enc

    def _observed(self, yv, msk, offset, rad) -> ConstrainedZonotope:
        """The set ``y - offset - V - [-rad, rad]`` of the measured outputs' ``M x``."""
        ym = yv[msk]
        offset, rad = offset[msk], rad[msk]
        centre = ym - offset
        err = round_up(gamma(2) * (np.abs(ym) + np.abs(offset)))
        wide = round_up(rad + err)  # (and the box's ends rounded outward)
        Y = ConstrainedZonotope.from_box(round_down(centre - wide), round_up(centre + wide))
        if self.V is not None:
            Y = Y + (-np.eye(msk.sum()) @ self.V.project(np.flatnonzero(msk)))
        return Y

    def _measure_linear(self, X: ConstrainedZonotope, box: Box, yv, uv, msk, enc=None
                        ) -> tuple[ConstrainedZonotope, str]:
        """:meth:`_measure` by the linear forms (``enc``: their enclosure over the box,
        when already computed)."""
        lin, failed, forms = enc if enc is not None else self._h.enclosure(
            box.lo, box.hi, uv, self.forms)
        if lin is None:
            self._h.enclose(box.lo, box.hi, uv)  # (raises where h itself is undefined)
            return X, ("h has no linear enclosure over the box (" + "; ".join(
                f"{k}: {v}" for k, v in failed.items()) + "): the measurement waits")
        M, offset, rad = lin
        # M x in y - offset - V - [-rad, rad]
        X = X.intersect(self._observed(yv, msk, offset, rad), M[msk])
        if self.intersect_forms and len(forms) == 2:
            # the other form's strips too, in the rows where it can pay (both hold at the
            # true state; the noise enters each strip whole, so the pair is sound)
            S, MB, oB, rB = _second_form(lin, forms, box)
            two = np.zeros_like(msk)
            two[S] = True
            two &= msk
            if two.any():
                X = X.intersect(self._observed(yv, two, oB, rB), MB[two])
        return X, ""

    def _predict(self, X: ConstrainedZonotope, box: Box, uv) -> None:
        """``X+ = M X + offset + P + W``, cut by ``f``'s natural enclosure over the box,
        and a certified box of it from the model alone (the interval image of ``box``)."""
        poly, poly_note = None, ""
        use, enc = self._polyhedral(self._f, box, uv)
        if use:
            try:
                poly = self._f.relaxation.lift(X, box.lo, box.hi, uv)
            except (DomainError, UnboundedSetError) as exc:
                if self.method == "polyhedral":
                    poly_note = (f"f's polyhedral relaxation failed ({exc}); the linear "
                                 "forms carry")
        if poly is not None:
            lin, failed, forms = None, {}, []
        else:
            lin, failed, forms = enc if enc is not None else self._f.enclosure(
                box.lo, box.hi, uv, self.forms)
        try:
            f_lo, f_hi = self._f.enclose(box.lo, box.hi, uv)
        except DomainError as exc:  # (a pole in the box: the natural form has no bound)
            if lin is None:
                why = ("the model is undefined on the whole box, so no true state lies "
                       "there: the model, its noise bounds or the initial set are wrong"
                       if "everywhere" in str(exc) else "give a state_domain that keeps "
                       "the states off the singularity, or bound the initial state set "
                       "tighter")
                raise DomainError(
                    f"f has no enclosure over the posterior's hull at step {self.k} "
                    f"({box!r}) in any form ({exc}; " + "; ".join(
                        f"{k}: {v}" for k, v in failed.items()) + f"): {why}") from exc
            f_lo, f_hi = np.full(self.n + self.q, -np.inf), np.full(self.n + self.q, np.inf)
            failed["interval"] = str(exc)
        self.pred_note = poly_note
        if poly is not None:
            Xl, P, q, r, L, U = poly
            Xp = (P @ Xl) + ConstrainedZonotope.from_box(round_down(q - r), round_up(q + r))
            lo, hi, img = _image_box(P, q, r, L, U, f_lo, f_hi)
            Xp = self._cut(Xp, img, f_lo, f_hi)
        elif lin is None:  # (f's natural enclosure over the box alone)
            if not (np.isfinite(f_lo).all() and np.isfinite(f_hi).all()):
                raise UnboundedSetError(
                    f"f has no finite enclosure over the posterior's hull at step {self.k}"
                    f" ({box!r}): " + "; ".join(f"{k}: {v}" for k, v in failed.items()))
            self.pred_note = poly_note + ("f has no linear enclosure over the box (" + "; ".join(
                f"{k}: {v}" for k, v in failed.items()) + "): its interval box carries "
                "the prediction")
            Xp = ConstrainedZonotope.from_box(f_lo, f_hi)
            lo, hi = f_lo, f_hi
        else:
            M, offset, rad = lin
            lo, hi, img = _image_box(M, offset, rad, box.lo, box.hi, f_lo, f_hi)
            meet = self._intersected(X, box, lin, forms)
            if meet is None:
                Xp = (M @ X) + ConstrainedZonotope.from_box(round_down(offset - rad),
                                                            round_up(offset + rad))
            else:  # (each form's image box holds f(x) for x in the box: their meet too)
                Xp = meet
                for M2, off2, rad2 in forms:
                    lo2, hi2, _ = _image_box(M2, off2, rad2, box.lo, box.hi, f_lo, f_hi)
                    lo, hi = np.maximum(lo, lo2), np.minimum(hi, hi2)
            Xp = self._cut(Xp, img, f_lo, f_hi)
        if self.W is not None:
            Xp = Xp + self.W
            lo, hi = round_down(lo + self._W_box.lo), round_up(hi + self._W_box.hi)
        self.prior = Xp
        self.prior_box = Box(lo, hi)

    def _intersected(self, X: ConstrainedZonotope, box: Box, lin: Any, forms: list[Any]
                     ) -> ConstrainedZonotope | None:
        """``f(X)``'s enclosure as the intersection of two linear forms (``None`` where
        it cannot pay): ``lin`` (row by row the narrower, ``M x + p_A``) in every row, and
        in the rows ``S`` where the other form is at most :data:`INTERSECT_RATIO` times
        as wide and its slope differs (``|M_A,i - M_B,i| r`` above
        :data:`INTERSECT_SLOPE` of the narrower remainder), also ``M_B,i x + p_B,i``, for
        the *same* ``x``: ``{M x + p_A : x in X, (M_A - M_B)_S x + p_A,S - p_B = 0}``.
        Both forms hold at the true state (in the box), so the truth satisfies the
        coupling; the difference ``D = fl(M_A - M_B)`` carries its rounding as a band
        ``|D| |x|_max u`` (``|x| <= max(|lo|, |hi|)`` on the box) on the rows."""
        if not self.intersect_forms or len(forms) != 2:
            return None
        M, offset, rad = lin
        S, MB, oB, rB = _second_form(lin, forms, box)
        if S.size == 0:
            return None
        D = M - MB
        N = X.dim
        xmax = np.maximum(np.abs(box.lo), np.abs(box.hi))
        delta = round_up((np.abs(D[S]) @ xmax) * (2.0 * gamma(N + 2)))
        PA = ConstrainedZonotope.from_box(round_down(offset - rad), round_up(offset + rad))
        PB = ConstrainedZonotope.from_box(round_down(oB[S] - rB[S]), round_up(oB[S] + rB[S]))
        Xa = X.cartesian(PA).cartesian(PB)
        s = S.size
        R = np.zeros((s, 2 * N + s))
        R[:, :N] = D[S]
        R[np.arange(s), N + S] = 1.0
        R[:, 2 * N:] = -np.eye(s)
        Xa = Xa.intersect(ConstrainedZonotope.from_box(-delta, delta), R)
        out = np.zeros((N, 2 * N + s))
        out[:, :N] = M
        out[:, N:2 * N] = np.eye(N)
        return out @ Xa

    def _in_domain(self, X: ConstrainedZonotope, box: Box) -> tuple[ConstrainedZonotope, Box]:
        """``X`` and its box cut by ``state_domain`` where the box leaves it."""
        if self.domain is None:
            return X, box
        dlo, dhi = self.domain
        sel = np.flatnonzero((box.lo < dlo) | (box.hi > dhi))
        if sel.size == 0:
            return X, box
        lo, hi = np.maximum(box.lo, dlo), np.minimum(box.hi, dhi)
        if (lo > hi).any():
            raise ModelInvalidatedError(
                f"the predicted set at step {self.k} lies outside state_domain (certified): "
                "the model, its noise bounds or the domain are wrong", self.k,
                hint="what to do: check state_domain and the noise bounds")
        # (the box clipped to the domain: finite where the domain is one-sided)
        X = X.intersect(ConstrainedZonotope.from_box(lo[sel], hi[sel]), np.eye(X.dim)[sel])
        return X, Box(lo, hi)

    def _cut(self, Xp: ConstrainedZonotope, lin_rad: NDArray[np.float64],
             f_lo: NDArray[np.float64], f_hi: NDArray[np.float64]) -> ConstrainedZonotope:
        """``Xp`` intersected with the natural interval enclosure ``[f](B)`` in the
        coordinates where that box is narrower than the interval image of ``B`` under the
        enclosure (radius ``lin_rad``, by more than :data:`CUT_GAIN` of it): both enclose
        ``f(X)``, and on a large box with a rational ``f`` the mean-value form alone can
        be several times wider (the dependency effect in the interval Jacobian)."""
        sel = np.flatnonzero(f_hi - f_lo < (1.0 - CUT_GAIN) * 2.0 * lin_rad)
        if sel.size == 0 or not (np.isfinite(f_lo[sel]).all() and np.isfinite(f_hi[sel]).all()):
            return Xp
        R = np.eye(Xp.dim)[sel]
        return Xp.intersect(ConstrainedZonotope.from_box(f_lo[sel], f_hi[sel]), R)

    def _reduce_to(self, X: ConstrainedZonotope, g: int, c: int, box: Box
                   ) -> ConstrainedZonotope:
        """``X`` with at most ``c`` constraints and ``g`` generators (outer). Where the
        elimination stalls short of ``c`` (its rounding budget: each elimination's
        certified error would pass it), the set restarts from ``box``, its certified hull
        (outer too, and the step says so)."""
        if X.n_con > c:
            small = X.dim <= REFINE_MAX_DIM
            X = eliminate_constraints(X, c, method="auto" if small else "fast",
                                      batch=ELIMINATION_BATCH,
                                      refine=ELIMINATION_REFINE if small else 0)
            if X.n_con > c or (X.n_gen > g and g < X.dim + X.n_con):
                self.restarts += 1
                return ConstrainedZonotope.from_box(box.lo, box.hi)
        if X.n_gen > g:
            X = reduce_order(X, g)
        return X

    def _reduce(self, X: ConstrainedZonotope, box: Box) -> tuple[ConstrainedZonotope, float]:
        """``X`` reduced to the current sizes; while that widens a coordinate of the hull
        (``box``, the unreduced set's) by more than ``reduction_growth`` of its width, the
        sizes grow (up to the caps) and ``X`` is reduced again from itself. Returns the
        set and the growth (the largest relative widening of the kept reduction; 0
        without reduction, NaN when not measured)."""
        g, c = self.sizes
        Xr = self._reduce_to(X, g, c, box)
        if Xr is X:
            return X, 0.0
        at_caps = g >= self.max_generators and c >= self.max_constraints
        if self.reduction_growth is None or (at_caps and self.k % GROWTH_CHECK_EVERY) or (
                not at_caps and self.k % GROWTH_CHECK_BELOW_CAPS):
            return Xr, float("nan")
        width = box.hi - box.lo
        floor = 1e-9 * np.maximum(1.0, np.abs(box.lo) + np.abs(box.hi))
        while True:
            try:
                hb, _ = hull_with_status(Xr, HULL_REL_GAP * width)
                growth = float(np.max(((hb.hi - hb.lo) - width) / np.maximum(width, floor)))
            except EmptySetError:  # (a superset of a nonempty set: LP trouble)
                growth = float("inf")
            if growth <= self.reduction_growth or (g >= self.max_generators
                                                   and c >= self.max_constraints):
                break
            g = min(self.max_generators, max(g + 1, int(np.ceil(GROWTH_FACTOR * g))))
            c = min(self.max_constraints, max(c + 1, int(np.ceil(GROWTH_FACTOR * c))))
            g, c = max(g, self.sizes[0]), max(c, self.sizes[1])
            Xr = self._reduce_to(X, g, c, box)
            if Xr is X:
                growth = 0.0
                break
        self.sizes = (g, c)
        return Xr, max(growth, 0.0)

    def _step(self, box: Box, status: str, stats: dict[str, Any]) -> SetEstimateStep:
        n = self.n
        lo, hi = box.lo[n:].copy(), box.hi[n:].copy()
        est = 0.5 * lo + 0.5 * hi
        eb = float(np.max(0.5 * (hi - lo), initial=0.0))
        return SetEstimateStep(self.k, est, lo, hi, eb, status=status,
                               state_lo=box.lo[:n].copy(), state_hi=box.hi[:n].copy(), stats=stats)

    # ------------------------------------------------------------------ a record
    def run(self, Y: ArrayLike, U: ArrayLike | None = None) -> SetEstimateResult:
        """Estimate over a record from ``X_0``: :meth:`reset`, then :meth:`continue_run`.

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measurements (NaN: not measured).
        U : array_like, shape (N, p), optional
            Inputs (``u_k`` with ``y_k``).

        Returns
        -------
        SetEstimateResult
            The record's bands (:meth:`continue_run`).
        """
        self.reset()
        return self.continue_run(Y, U)

    @with_single_threaded_blas  # (its small dense kernels: :mod:`setobs._blas`)
    def continue_run(self, Y: ArrayLike, U: ArrayLike | None = None) -> SetEstimateResult:
        """Estimate over a record continuing from the current step (what :meth:`run` does
        after :meth:`reset`).

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measurements (NaN: not measured).
        U : array_like, shape (N, p), optional
            Inputs (``u_k`` with ``y_k``).

        Returns
        -------
        SetEstimateResult
            ``state_lo`` / ``state_hi`` of shape ``(N, n)``; ``lo`` / ``hi`` /
            ``estimate`` the disturbances' ``(N, q)``; ``status`` per step.

        Raises
        ------
        ModelInvalidatedError
            At the first step whose posterior is certified empty.
        """
        Ym = as_matrix("Y", Y, cols=self.l, allow_nan=True)
        N = Ym.shape[0]
        if self.p:
            if U is None:
                raise ArgumentError(f"U is required: the model has {self.p} inputs")
            Um = as_matrix("U", U, rows=N, cols=self.p)
        else:
            Um = np.zeros((N, 0))
        steps = [self.step(Ym[k], Um[k]) for k in range(N)]
        q = self.q
        lo = np.array([s.lo for s in steps]).reshape(N, q)
        hi = np.array([s.hi for s in steps]).reshape(N, q)
        return SetEstimateResult(
            np.array([s.estimate for s in steps]).reshape(N, q), lo, hi,
            np.array([s.error_bound for s in steps]), steps,
            np.array([s.status for s in steps], dtype="<U9"), None, self.dt,
            tuple(str(d) for d in self.disturbances),
            np.array([s.state_lo for s in steps]), np.array([s.state_hi for s in steps]),
            tuple(str(x) for x in self.states))

    def __repr__(self) -> str:
        return (f"NonlinearSetObserver(n={self.n}, l={self.l}, p={self.p}, q={self.q}, "
                f"method={self.method!r}, k={self.k})")


def _image_box(P: NDArray[np.float64], q: NDArray[np.float64], r: NDArray[np.float64],
               L: NDArray[np.float64], U: NDArray[np.float64], f_lo: NDArray[np.float64],
               f_hi: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                   NDArray[np.float64]]:
    """The certified box of ``P v + q +- r`` over ``v`` in ``[L, U]``, met with the natural
    enclosure ``[f_lo, f_hi]`` where that is finite, and the image's radius without
    rounding terms, ``|P| rad + r`` (what :meth:`NonlinearSetObserver._cut` compares)."""
    c, rl = box_center_radius(L, U)
    mid = P @ c + q
    img = np.abs(P) @ rl + r
    rr = round_up((img + gamma(P.shape[1] + 2) * (np.abs(P) @ (np.abs(c) + rl) + np.abs(q)))
                  * (1.0 + gamma(2)))
    lo, hi = round_down(mid - rr), round_up(mid + rr)
    fin = np.isfinite(f_lo) & np.isfinite(f_hi)
    return np.where(fin, np.maximum(lo, f_lo), lo), np.where(fin, np.minimum(hi, f_hi), hi), img


def _meet(a: Box, b: Box) -> Box:
    """The intersection of two boxes that both hold the truth (the first where they do
    not overlap, which only rounding can cause)."""
    lo, hi = np.maximum(a.lo, b.lo), np.minimum(a.hi, b.hi)
    bad = lo > hi
    return Box(np.where(bad, a.lo, lo), np.where(bad, a.hi, hi))


def _cartesian(W: ConstrainedZonotope | None, n: int, DD: ConstrainedZonotope | None, q: int
               ) -> ConstrainedZonotope | None:
    if W is None and DD is None:
        return None
    W = W if W is not None else ConstrainedZonotope.point(np.zeros(n))
    DD = DD if DD is not None else ConstrainedZonotope.point(np.zeros(q))
    return W.cartesian(DD)
