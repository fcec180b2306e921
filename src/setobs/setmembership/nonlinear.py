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

Where a derivative of ``f`` or ``h`` has no enclosure over the box while the function
has one (``sqrt`` of a level whose box touches 0: the derivative's pole), the step
uses the natural interval enclosure alone: ``f``'s box as the prediction, and the
measurement is left for later steps; such steps report ``status = "fallback"``
(certified, wider).

Limits: the sets are only as tight as the linearization over the current box (a
large ``X_0`` on a strongly nonlinear ``f`` gives wide bands until the data shrink
it); a function outside its domain over the box (``sqrt`` of a level box reaching
below 0) raises :class:`setobs.DomainError` naming it -- bound the state there
(``initial_state_set``) or rewrite the model.

Disturbances
------------
``disturbances=(d_1, ..)`` with ``increment_set``: each ``d`` is a state with
``d+ = d + dd`` and ``dd`` in the increment set (the SMFDO's model), so ``f`` and
``h`` may use them; the result's ``lo`` / ``hi`` / ``estimate`` are their bands.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import optional_import
from .._rounding import gamma, round_down, round_up
from .._validation import as_matrix, as_vector
from ..exceptions import (
    ArgumentError,
    DimensionError,
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
from ..interval import IntervalFunction
from ._setup import as_set, noise_set
from ._steps import SMFDOResult, SMFDOStep

__all__ = ["METHODS", "NonlinearSetObserver"]

#: The enclosures of ``f`` and ``h`` (module docstring).
METHODS = ("mean-value", "taylor")

#: The prediction is cut by ``f``'s natural interval enclosure in the coordinates where
#: that box is narrower than the linearization's interval image by more than this
#: fraction (:meth:`NonlinearSetObserver._cut`).
CUT_GAIN = 0.05


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

    def __init__(self, sp: Any, exprs: list[Any], zs: list[Any], us: list[Any],
                 method: str) -> None:
        self.n, self.m = len(zs), len(exprs)
        variables = [*zs, *us]
        self.value = IntervalFunction(exprs, variables)
        J = sp.Matrix(exprs).jacobian(zs)
        self.jac = _Sparse(list(J), (self.m, self.n), variables)
        self.hess = None
        if method == "taylor":
            H = [sp.hessian(e, zs) for e in exprs]
            self.hess = _Sparse([h for Hi in H for h in Hi], (self.m, self.n, self.n), variables)

    def enclose(self, box: Box, u: NDArray[np.float64]
                ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """The natural interval enclosure ``[g](B)`` over the box, at the input ``u``."""
        return self.value(np.concatenate([box.lo, u]), np.concatenate([box.hi, u]))

    def linearize(self, lo: NDArray[np.float64], hi: NDArray[np.float64],
                  u: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64],
                                                   NDArray[np.float64]]:
        """``(M, offset, rad)`` with ``g(z, u) in M z + offset + [-rad, rad]`` for every
        ``z`` in ``[lo, hi]`` (module docstring; all rounding inside ``rad``)."""
        c = 0.5 * lo + 0.5 * hi  # (in the box: the mean value theorem's segment stays in it)
        r = round_up(np.maximum(hi - c, c - lo))
        zc = np.concatenate([c, u])
        gc_lo, gc_hi = self.value(zc, zc)
        if self.hess is None:  # mean value: the Jacobian over the box
            J_lo, J_hi = self.jac(np.concatenate([lo, u]), np.concatenate([hi, u]))
            rem_c, rem_r = np.zeros(self.m), np.zeros(self.m)
        else:  # Taylor: the Jacobian at c, the Hessian over the box
            J_lo, J_hi = self.jac(zc, zc)
            H_lo, H_hi = self.hess(np.concatenate([lo, u]), np.concatenate([hi, u]))
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


def _symbols(sp: Any, given: Sequence[Any], what: str) -> list[Any]:
    if isinstance(given, str):
        given = [given]
    out = [sp.Symbol(g) if isinstance(g, str) else g for g in given]
    if not all(isinstance(v, sp.Symbol) for v in out):
        raise ArgumentError(f"{what} must be sympy symbols or their names")
    return out


def _exprs(sp: Any, given: Any, names: dict[str, Any], what: str) -> list[Any]:
    if isinstance(given, str) or (not isinstance(given, Sequence | np.ndarray) and \
            not hasattr(given, "tolist")):
        given = [given]
    if hasattr(given, "tolist") and not isinstance(given, list | tuple):
        given = list(np.ravel(np.asarray(given.tolist(), dtype=object)))
    try:
        return [sp.sympify(e, locals=names) for e in given]
    except (sp.SympifyError, TypeError) as exc:
        raise ArgumentError(f"{what}: cannot read {given!r} as sympy expressions ({exc})") \
            from exc


class NonlinearSetObserver:
    """Guaranteed state estimator for ``x+ = f(x, u) + w``, ``y = h(x, u) + v``.

    Parameters
    ----------
    f, h : sequence of sympy expressions or strings
        The state map (``n`` components) and the output map (``l``), in the symbols
        of ``states``, ``inputs`` and ``disturbances``.
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
    method : {"mean-value", "taylor"}
        The enclosure of ``f`` and ``h`` (module docstring).
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
    max_generators : int, optional
        Generators kept after each step (default ``8 (n + q)``).
    max_constraints : int, optional
        Constraints kept after each step (default ``2 (n + q)``).
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
    >>> step = obs.update([0.5])
    >>> bool(step.state_lo[0] < 0.45 < step.state_hi[0])
    True
    """

    def __init__(self, f: Any, h: Any, states: Sequence[Any], inputs: Sequence[Any] = (), *,
                 process_noise: Any, measurement_noise: Any, initial_state_set: Any,
                 method: str = "mean-value", disturbances: Sequence[Any] = (),
                 increment_set: Any = None, initial_disturbance_set: Any = None,
                 state_domain: Any = None, max_generators: int | None = None,
                 max_constraints: int | None = None, dt: float | None = None) -> None:
        sp = optional_import("sympy", extra="nonlinear", feature="NonlinearSetObserver")
        if method not in METHODS:
            raise InvalidValueError(f"method must be one of {METHODS}, got {method!r}")
        xs = _symbols(sp, states, "states")
        us = _symbols(sp, inputs, "inputs")
        ds = _symbols(sp, disturbances, "disturbances")
        if len(set(xs + us + ds)) != len(xs) + len(us) + len(ds):
            raise ArgumentError("the states, inputs and disturbances must be distinct symbols")
        if not xs:
            raise DimensionError("there must be at least one state")
        names = {str(s): s for s in xs + us + ds}
        fx = _exprs(sp, f, names, "f")
        hx = _exprs(sp, h, names, "h")
        n, q = len(xs), len(ds)
        if len(fx) != n:
            raise DimensionError(f"f must have {n} components (one per state), got {len(fx)}")
        allowed = set(xs + us + ds)
        for what, ex in (("f", fx), ("h", hx)):
            extra = set().union(*(e.free_symbols for e in ex)) - allowed
            if extra:
                raise ArgumentError(f"{what} uses {sorted(map(str, extra))}, which are not "
                                    "among the states, inputs or disturbances")
        self.method = method
        self.n, self.q, self.l, self.p = n, q, len(hx), len(us)
        self.states, self.inputs, self.disturbances = tuple(xs), tuple(us), tuple(ds)
        zs = xs + ds
        self._f = _Map(sp, fx + list(ds), zs, us, method)  # (d+ = d: the increment is noise)
        self._h = _Map(sp, hx, zs, us, method)
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
        self.domain = None
        if state_domain is not None:
            if not isinstance(state_domain, Box) or state_domain.dim != n:
                raise ArgumentError(f"state_domain must be a Box of the {n} states, got "
                                    f"{state_domain!r}")
            inf = np.full(q, np.inf)
            self.domain = (np.concatenate([state_domain.lo, -inf]),
                           np.concatenate([state_domain.hi, inf]))
        N = n + q
        self.max_generators = int(max_generators) if max_generators is not None else 8 * N
        self.max_constraints = int(max_constraints) if max_constraints is not None else 2 * N
        if self.max_generators < N or self.max_constraints < 0:
            raise InvalidValueError(f"max_generators must be at least {N} and "
                                    "max_constraints nonnegative, got "
                                    f"{self.max_generators} and {self.max_constraints}")
        self.dt = dt
        self.reset()

    def reset(self) -> None:
        """Back to ``X_0`` at step 0."""
        self.k = 0
        self.prior: ConstrainedZonotope = self.X0
        self.posterior: ConstrainedZonotope | None = None
        self.pred_fallback = False  # (the prior came from f's interval enclosure alone)

    # ------------------------------------------------------------------ one step
    def update(self, y: ArrayLike, u: ArrayLike | None = None) -> SMFDOStep:
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
        SMFDOStep
            ``state_lo`` / ``state_hi`` (the states), ``lo`` / ``hi`` / ``estimate`` (the
            disturbances' bands and centres; empty without disturbances).

        Raises
        ------
        ModelInvalidatedError
            The posterior is certified empty: the data contradict the model and its
            noise bounds.
        """
        yv = as_vector("y", y, size=self.l, allow_nan=True)
        if self.p and u is None:
            raise ArgumentError(f"u is required: the model has {self.p} inputs")
        uv = as_vector("u", u, size=self.p) if self.p else np.zeros(0)
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

    def _advance(self, yv, uv) -> SMFDOStep:
        """:meth:`update` for checked data."""
        X = self.prior
        status = "fallback" if self.pred_fallback else "ok"
        msk = ~np.isnan(yv)
        box, fb = hull_with_status(X)
        status = "fallback" if fb else status
        X, box = self._in_domain(X, box)
        lin = self._linearize(self._h, box, uv) if msk.any() else None
        if lin is None and msk.any():
            status = "fallback"  # (no linear enclosure of h over the box: the data wait)
        if lin is not None:
            M, offset, rad = lin
            M, offset, rad = M[msk], offset[msk], rad[msk]
            # M x in y - offset - V - [-rad, rad]
            ym = yv[msk]
            centre = ym - offset
            err = round_up(gamma(2) * (np.abs(ym) + np.abs(offset)))
            wide = round_up(rad + err)  # (and the box's ends rounded outward)
            Y = ConstrainedZonotope.from_box(round_down(centre - wide), round_up(centre + wide))
            if self.V is not None:
                Y = Y + (-np.eye(msk.sum()) @ self.V.project(np.flatnonzero(msk)))
            X = X.intersect(Y, M)
        # the hull of the posterior before its reduction (tighter); its LPs certify an
        # empty set (EmptySetError) when the data contradict the model
        try:
            box, fb = hull_with_status(X)
        except EmptySetError:
            raise ModelInvalidatedError(
                f"the measurement at step {self.k} contradicts the model: the set of "
                "consistent states is empty (certified)", self.k,
                hint="what to do: if the sample is an outlier or a fault, it is found; "
                "if the model and the record are right, the noise bounds are too small "
                "(a larger measurement_noise / process_noise)") from None
        status = "fallback" if fb else status
        X = self._reduce(X)
        if self.domain is not None:  # (X lies in the domain: the cut above, or its prior's
            # hull did; the certified hull may pass its edge by the LP's outward rounding)
            box = Box(np.maximum(box.lo, self.domain[0]), np.minimum(box.hi, self.domain[1]))
        if not (np.isfinite(box.lo).all() and np.isfinite(box.hi).all()):
            raise UnboundedSetError(
                f"the hull of the posterior at step {self.k} is not finite ({box!r}): bound "
                "the initial state set tighter, or give a state_domain")
        self.posterior = X
        step = self._step(box, status)
        # prediction: X+ = M X + offset + P + W, cut by f's natural enclosure over the box
        lin = self._linearize(self._f, box, uv)
        self.pred_fallback = lin is None
        if lin is None:  # (f's natural enclosure over the box alone)
            Xp = ConstrainedZonotope.from_box(*self._f.enclose(box, uv))
        else:
            M, offset, rad = lin
            Xp = (M @ X) + ConstrainedZonotope.from_box(round_down(offset - rad),
                                                        round_up(offset + rad))
            Xp = self._cut(Xp, M, rad, box, uv)
        if self.W is not None:
            Xp = Xp + self.W
        self.prior = self._reduce(Xp)
        self.k += 1
        return step

    @staticmethod
    def _linearize(g: _Map, box: Box, u: NDArray[np.float64]
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64],
                              NDArray[np.float64]] | None:
        """``g.linearize`` over the box, or ``None`` when a *derivative* leaves its domain
        there while ``g`` itself does not (``sqrt`` at a level box touching 0: its
        derivative has a pole); a domain error of ``g`` itself is raised."""
        try:
            return g.linearize(box.lo, box.hi, u)
        except DomainError:
            g.enclose(box, u)  # (raises)
            return None

    def _in_domain(self, X: ConstrainedZonotope, box: Box) -> tuple[ConstrainedZonotope, Box]:
        """``X`` and its hull cut by ``state_domain`` where the hull leaves it."""
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
        # (the hull clipped to the domain: finite where the domain is one-sided)
        X = X.intersect(ConstrainedZonotope.from_box(lo[sel], hi[sel]), np.eye(X.dim)[sel])
        return X, Box(lo, hi)

    def _cut(self, Xp: ConstrainedZonotope, M: NDArray[np.float64], rad: NDArray[np.float64],
             box: Box, u: NDArray[np.float64]) -> ConstrainedZonotope:
        """``Xp`` intersected with the natural interval enclosure ``[f](B)`` in the
        coordinates where that box is narrower than the interval image of ``B`` under the
        linearization (by more than :data:`CUT_GAIN` of it): both enclose ``f(X)``, and
        on a large box with a rational ``f`` the mean-value form alone can be several
        times wider (the dependency effect in the interval Jacobian)."""
        f_lo, f_hi = self._f.enclose(box, u)
        _, r = box_center_radius(box.lo, box.hi)
        lin_rad = np.abs(M) @ r + rad  # (the linearization's radius over B: the choice only)
        sel = np.flatnonzero(f_hi - f_lo < (1.0 - CUT_GAIN) * 2.0 * lin_rad)
        if sel.size == 0 or not (np.isfinite(f_lo[sel]).all() and np.isfinite(f_hi[sel]).all()):
            return Xp
        R = np.eye(Xp.dim)[sel]
        return Xp.intersect(ConstrainedZonotope.from_box(f_lo[sel], f_hi[sel]), R)

    def _reduce(self, X: ConstrainedZonotope) -> ConstrainedZonotope:
        if X.n_con > self.max_constraints:
            X = eliminate_constraints(X, self.max_constraints)
        if X.n_gen > self.max_generators:
            X = reduce_order(X, self.max_generators)
        return X

    def _step(self, box: Box, status: str) -> SMFDOStep:
        n = self.n
        lo, hi = box.lo[n:].copy(), box.hi[n:].copy()
        est = 0.5 * lo + 0.5 * hi
        eb = float(np.max(0.5 * (hi - lo), initial=0.0))
        return SMFDOStep(self.k, est, lo, hi, eb, status=status,
                         state_lo=box.lo[:n].copy(), state_hi=box.hi[:n].copy())

    # ------------------------------------------------------------------ a record
    def run(self, Y: ArrayLike, U: ArrayLike | None = None) -> SMFDOResult:
        """Estimate over a record from ``X_0`` (the observer is reset first).

        Parameters
        ----------
        Y : array_like, shape (N, l)
            Measurements (NaN: not measured).
        U : array_like, shape (N, p), optional
            Inputs (``u_k`` with ``y_k``).

        Returns
        -------
        SMFDOResult
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
        self.reset()
        steps = [self.update(Ym[k], Um[k]) for k in range(N)]
        q = self.q
        lo = np.array([s.lo for s in steps]).reshape(N, q)
        hi = np.array([s.hi for s in steps]).reshape(N, q)
        return SMFDOResult(
            np.array([s.estimate for s in steps]).reshape(N, q), lo, hi,
            np.array([s.error_bound for s in steps]), steps,
            np.array([s.status for s in steps], dtype="<U9"), None, self.dt,
            tuple(str(d) for d in self.disturbances),
            np.array([s.state_lo for s in steps]), np.array([s.state_hi for s in steps]),
            tuple(str(x) for x in self.states))

    def __repr__(self) -> str:
        return (f"NonlinearSetObserver(n={self.n}, l={self.l}, p={self.p}, q={self.q}, "
                f"method={self.method!r}, k={self.k})")


def _cartesian(W: ConstrainedZonotope | None, n: int, DD: ConstrainedZonotope | None, q: int
               ) -> ConstrainedZonotope | None:
    if W is None and DD is None:
        return None
    W = W if W is not None else ConstrainedZonotope.point(np.zeros(n))
    DD = DD if DD is not None else ConstrainedZonotope.point(np.zeros(q))
    return W.cartesian(DD)
