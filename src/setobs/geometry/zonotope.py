"""Extended constrained zonotopes (Scott et al. 2016; Li-Cong-Dong, Definition 2)."""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._rounding import UNIT_ROUNDOFF, gamma, outward_interval, round_up
from .._validation import as_matrix, as_vector, readonly
from ..exceptions import (
    ArgumentError,
    DimensionError,
    EmptySetError,
    ImmutableError,
    InvalidValueError,
    SolverError,
    SolverWarning,
    UnboundedSetError,
)
from ..lp.factor import EmptinessReport, FactorPolytope, LPResult
from ..tolerances import FEASIBILITY_TOL, MAX_MAGNITUDE, UNBOUNDED_RADIUS
from ._bounds import add_err, cat_err, diff_err, map_err, sum_err
from ._guard import check_set_data
from .box import Box, box_center_radius, trusted_box
from .results import ContainmentResult, DistanceResult, HRep, VolumeResult

try:  # the optional compiled construction of +, @ and intersect (setup.py)
    from . import _setops as compiled_ops
except ImportError:  # not built (no C compiler at install): the NumPy code below runs
    compiled_ops = None

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes
    from matplotlib.patches import Patch


__all__ = ["ConstrainedZonotope", "compiled_set_operations"]


def _blockdiag2(X: NDArray[np.float64], Y: NDArray[np.float64]) -> NDArray[np.float64]:
    """``[[X, 0], [0, Y]]`` (scipy's ``block_diag`` costs ~10x more on small matrices)."""
    out = np.zeros((X.shape[0] + Y.shape[0], X.shape[1] + Y.shape[1]))
    if not out.shape[0]:
        return out
    out[: X.shape[0], : X.shape[1]] = X
    out[X.shape[0] :, X.shape[1] :] = Y
    return out


def _rebuild(G, c, A, b, h, unbounded_radius, cerr, berr) -> ConstrainedZonotope:
    """Unpickling helper of :class:`ConstrainedZonotope`."""
    return ConstrainedZonotope._trusted(G, c, A, b, h, unbounded_radius, cerr, berr,
                                        op="unpickling a set")


class ConstrainedZonotope:
    r"""Extended constrained zonotope ``{G xi + c : A xi = b, |xi_j| <= h_j}``.

    Parameters
    ----------
    G : array_like, shape (n, n_g)
        Generator matrix.
    c : array_like, shape (n,)
        Centre.
    A : array_like, shape (n_c, n_g), optional
        Constraint matrix (default: no constraints).
    b : array_like, shape (n_c,), optional
        Constraint right-hand side (required with ``A``).
    h : array_like, shape (n_g,), optional
        Factor bounds in ``[0, +inf]`` (default: all ones). ``h_j = inf`` makes
        factor ``j`` unbounded, so sets such as ``R^n`` and affine sets are
        representable (Li-Cong-Dong, Definition 2, eq. (19)).
    unbounded_radius : float
        Bound up to which unbounded factors (``h_j = inf``) are certified, in the set's
        normalised units (default :data:`setobs.tolerances.UNBOUNDED_RADIUS`).

    Raises
    ------
    DimensionError
        On inconsistent shapes.
    InvalidValueError
        On NaN, inf in ``G``, ``c``, ``A``, ``b``, or negative/NaN entries of ``h``.
    ArgumentError
        On ``A`` without ``b`` (or the reverse), complex or non-numeric data.

    Notes
    -----
    *Representable sets.* The factor set ``{xi : A xi = b, |xi_j| <= h_j}``
    has the subspace ``{v : A v = 0, v_j = 0 for finite h_j}`` as its recession
    cone, so every extended constrained zonotope is a polytope plus a subspace
    (its lineality space). Half-lines, half-spaces and boxes with a one-sided
    infinite bound are therefore *not* representable.

    *Exactness.* The set operations (``+``, ``@``, products, intersections,
    projection) are the exact formulas of Scott et al. (2016), Sec. 3; only
    their matrix products are rounded, an ``O(eps)`` perturbation of the data.
    The rounding of the centre and of the constraint right-hand side, which
    is what matters when large centres and data cancel (measurements of size
    ``1e8`` whose differences carry the information), is tracked: :attr:`c_err`
    and :attr:`b_err` bound it elementwise, and every LP query (interval hull,
    support function, emptiness, containment) is certified for all centres and
    right-hand sides within those bounds; see :mod:`setobs.lp.factor`. The
    rounding of ``G`` and ``A`` (relative to the factor magnitudes) is not
    tracked.

    Objects are immutable; expensive predicates (interval hull, emptiness) are
    cached on the instance.

    Examples
    --------
    >>> Z = ConstrainedZonotope([[1.0, 0.0, 1.0], [0.0, 1.0, 1.0]], [0.0, 0.0],
    ...                         A=[[1.0, 1.0, 1.0]], b=[1.0])
    >>> box = Z.interval_hull()
    >>> bool(abs(box.hi[0] - 2.0) < 1e-9)
    True
    """

    __slots__ = ("_A", "_G", "_b", "_berr", "_c", "_cache", "_cerr", "_h", "unbounded_radius")
    unbounded_radius: float
    __array_ufunc__ = None  # so that ndarray @ Z calls Z.__rmatmul__

    def __init__(
        self,
        G: ArrayLike,
        c: ArrayLike,
        A: ArrayLike | None = None,
        b: ArrayLike | None = None,
        h: ArrayLike | None = None,
        *,
        unbounded_radius: float = UNBOUNDED_RADIUS,
    ) -> None:
        c_a = as_vector("c", c)
        n = c_a.size
        if np.ndim(G) == 2 and np.shape(G)[0] == n:
            G_a = as_matrix("G", G, rows=n)
        elif np.size(G) == 0:
            G_a = np.zeros((n, 0))
        else:
            G_a = as_matrix("G", G, rows=n)
        n_g = G_a.shape[1]
        if (A is None) != (b is None):
            raise ArgumentError("A and b must be given together (or both omitted)")
        if A is None:
            A_a = np.zeros((0, n_g))
            b_a = np.zeros(0)
        else:
            b_a = as_vector("b", b)
            if np.size(A) == 0 and b_a.size == 0:
                A_a = np.zeros((0, n_g))
            else:
                A_a = as_matrix("A", A, cols=n_g)
                if b_a.size != A_a.shape[0]:
                    raise DimensionError(
                        f"b must have one entry per row of A ({A_a.shape[0]}), got {b_a.size}")
        if h is None:
            h_a = np.ones(n_g)
        else:
            h_a = as_vector("h", h, size=n_g, allow_inf=True)
            if (h_a < 0).any():
                j = int(np.argmax(h_a < 0))
                raise InvalidValueError(f"h must be nonnegative (h[{j}] = {h_a[j]})")
        if not unbounded_radius > 0:
            raise InvalidValueError(f"unbounded_radius must be positive, got {unbounded_radius}")
        for name, val in (("_G", G_a), ("_c", c_a), ("_A", A_a), ("_b", b_a), ("_h", h_a)):
            object.__setattr__(self, name, readonly(val))
        object.__setattr__(self, "unbounded_radius", float(unbounded_radius))
        object.__setattr__(self, "_cerr", None)
        object.__setattr__(self, "_berr", None)
        object.__setattr__(self, "_cache", {})

    @classmethod
    def _owned(cls, G, c, A, b, h, unbounded_radius: float, cerr, berr, op: str
               ) -> ConstrainedZonotope:
        """Build from float64 arrays that are either fresh (made by the caller, no other
        reference) or already read-only arrays of a set: no copies (internal fast path of
        the exact operations). ``cerr``, ``berr``: as in :meth:`_trusted`; ``op``: the
        operation named by the data guard (:func:`check_set_data`)."""
        check_set_data(op, G, c, A, b, h, cerr, berr, compiled_ops)
        self = object.__new__(cls)
        setattr_ = object.__setattr__
        if cerr is not None and not np.count_nonzero(cerr):
            cerr = None
        if berr is not None and not np.count_nonzero(berr):
            berr = None
        for name, val in (("_G", G), ("_c", c), ("_A", A), ("_b", b), ("_h", h),
                          ("_cerr", cerr), ("_berr", berr)):
            if val is not None:
                val.setflags(write=False)
            setattr_(self, name, val)
        setattr_(self, "unbounded_radius", unbounded_radius)
        setattr_(self, "_cache", {})
        return self

    @classmethod
    def _trusted(cls, G, c, A, b, h, unbounded_radius: float = UNBOUNDED_RADIUS, cerr=None,
                 berr=None, op: str | None = "building a set") -> ConstrainedZonotope:
        """Build from arrays already validated (internal fast path).

        ``cerr``, ``berr``: elementwise bounds on the rounding errors of ``c``
        and ``b`` (``None``: exact). ``op``: the operation named by the data guard
        (:func:`check_set_data`); ``None`` skips the guard, for exact power-of-two
        rescalings of a guarded set only (:func:`scaled_by`).
        """
        self = object.__new__(cls)
        for name, val in (("_G", G), ("_c", c), ("_A", A), ("_b", b), ("_h", h)):
            object.__setattr__(self, name, readonly(np.array(val, dtype=np.float64)))
        for name, val in (("_cerr", cerr), ("_berr", berr)):
            arr = None
            if val is not None and np.any(val):
                arr = readonly(np.array(val, dtype=np.float64))
            object.__setattr__(self, name, arr)
        if op is not None:
            check_set_data(op, self._G, self._c, self._A, self._b, self._h, self._cerr,
                           self._berr, compiled_ops)
        object.__setattr__(self, "unbounded_radius", unbounded_radius)
        object.__setattr__(self, "_cache", {})
        return self

    def __setattr__(self, name: str, value: object) -> None:
        raise ImmutableError("ConstrainedZonotope is immutable; operations return new objects")

    def __reduce__(self):
        # Pickling and deepcopy rebuild from the data (the LP cache is dropped).
        return (_rebuild, (self._G, self._c, self._A, self._b, self._h, self.unbounded_radius,
                           self._cerr, self._berr))

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_box(cls, lo: ArrayLike, hi: ArrayLike) -> ConstrainedZonotope:
        """The box ``prod [lo_i, hi_i]``; a coordinate with ``lo=-inf, hi=+inf`` is free.

        Parameters
        ----------
        lo, hi : array_like, shape (n,)
            Lower and upper bounds; a coordinate with ``lo = -inf`` and ``hi = +inf`` is
            free.

        Raises
        ------
        InvalidValueError
            If a coordinate has exactly one infinite bound (not representable:
            see the class notes), or ``lo > hi``.
        """
        box = Box(lo, hi)
        lo_a, hi_a = box.lo, box.hi
        one_sided = np.isinf(lo_a) != np.isinf(hi_a)
        if one_sided.any():
            i = int(np.argmax(one_sided))
            raise InvalidValueError(
                f"coordinate {i} has a one-sided infinite bound [{lo_a[i]}, {hi_a[i]}]; "
                "an extended constrained zonotope is a polytope plus a subspace, so "
                "a coordinate is either bounded on both sides or free (-inf, +inf)"
            )
        c, rad = box_center_radius(lo_a, hi_a)
        n = lo_a.size
        return cls._trusted(np.eye(n), c, np.zeros((0, n)), np.zeros(0), rad)

    @classmethod
    def from_zonotope(cls, G: ArrayLike, c: ArrayLike) -> ConstrainedZonotope:
        """The zonotope ``{G xi + c : ||xi||_inf <= 1}``.

        Parameters
        ----------
        G : array_like, shape (n, n_g)
            Generator matrix.
        c : array_like, shape (n,)
            Centre.
        """
        return cls(G, c)

    @classmethod
    def point(cls, x: ArrayLike) -> ConstrainedZonotope:
        """The singleton ``{x}``.

        Parameters
        ----------
        x : array_like, shape (n,)
            The point.
        """
        xv = as_vector("x", x)
        return cls._trusted(np.zeros((xv.size, 0)), xv, np.zeros((0, 0)), np.zeros(0),
                            np.zeros(0))

    @classmethod
    def full_space(cls, n: int) -> ConstrainedZonotope:
        """The whole space ``R^n`` (``n`` unbounded factors).

        Parameters
        ----------
        n : int
            Dimension.
        """
        if int(n) != n or n < 1:
            raise InvalidValueError(f"n must be a positive integer, got {n!r}")
        n = int(n)
        return cls._trusted(np.eye(n), np.zeros(n), np.zeros((0, n)), np.zeros(0),
                            np.full(n, np.inf))

    @classmethod
    def empty(cls, n: int) -> ConstrainedZonotope:
        """The empty set of ``R^n``; see :func:`setobs.geometry.operations.empty_set`."""
        from .operations import empty_set

        return empty_set(n)

    @classmethod
    def from_vertices(cls, V: ArrayLike) -> ConstrainedZonotope:
        """The convex hull of points (exact); see
        :func:`setobs.geometry.operations.from_vertices`."""
        from .operations import from_vertices

        return from_vertices(V)

    @classmethod
    def affine_set(cls, C: ArrayLike, y: ArrayLike) -> ConstrainedZonotope:
        """The affine set ``{z : C z = y}`` (``R^n`` intersected with ``C z = y``).

        Parameters
        ----------
        C : array_like, shape (m, n)
            Constraint matrix.
        y : array_like, shape (m,)
            Right-hand side: the set is ``{z : C z = y}``.
        """
        C_a = as_matrix("C", C)
        return cls.full_space(C_a.shape[1]).intersect_affine(C_a, y)

    @classmethod
    def from_hpolytope(cls, H: ArrayLike, k: ArrayLike) -> ConstrainedZonotope:
        """The bounded polytope ``{x : H x <= k}`` (Scott et al. 2016, Theorem 1); see
        :func:`setobs.geometry.polytope.cz_from_hpolytope`."""
        from .polytope import cz_from_hpolytope

        return cz_from_hpolytope(H, k)

    # ------------------------------------------------------------------ properties
    @property
    def G(self) -> NDArray[np.float64]:
        """Generator matrix, shape ``(n, n_g)`` (read-only)."""
        return self._G

    @property
    def c(self) -> NDArray[np.float64]:
        """Centre, shape ``(n,)`` (read-only)."""
        return self._c

    @property
    def A(self) -> NDArray[np.float64]:
        """Constraint matrix, shape ``(n_c, n_g)`` (read-only)."""
        return self._A

    @property
    def b(self) -> NDArray[np.float64]:
        """Constraint right-hand side, shape ``(n_c,)`` (read-only)."""
        return self._b

    @property
    def h(self) -> NDArray[np.float64]:
        """Factor bounds, shape ``(n_g,)``, entries in ``[0, inf]`` (read-only)."""
        return self._h

    @property
    def c_err(self) -> NDArray[np.float64]:
        """Bound on the accumulated rounding error of :attr:`c`, shape ``(n,)`` (read-only)."""
        return self._cerr if self._cerr is not None else readonly(np.zeros(self.dim))

    @property
    def b_err(self) -> NDArray[np.float64]:
        """Bound on the accumulated rounding error of :attr:`b`, shape ``(n_c,)`` (read-only)."""
        return self._berr if self._berr is not None else readonly(np.zeros(self.n_con))

    @property
    def dim(self) -> int:
        """Dimension ``n`` of the ambient space."""
        return int(self._c.size)

    @property
    def n_gen(self) -> int:
        """Number of generators (factors) ``n_g``."""
        return int(self._G.shape[1])

    @property
    def n_con(self) -> int:
        """Number of equality constraints ``n_c``."""
        return int(self._A.shape[0])

    @property
    def has_unbounded_factors(self) -> bool:
        """Whether some ``h_j = inf`` (the set may still be bounded)."""
        return bool(np.isinf(self._h).any())

    @property
    def is_bounded(self) -> bool:
        """Whether the set is bounded (certified: decided by the interval hull).

        All factors bounded implies bounded; otherwise the certified interval
        hull decides (an infinite bound means unbounded or not certifiably
        bounded). The empty set is bounded.
        """
        if not self.has_unbounded_factors:
            return True
        try:
            return self.interval_hull().is_bounded
        except EmptySetError:
            return True

    def __repr__(self) -> str:
        unb = int(np.isinf(self._h).sum())
        extra = f", unbounded_factors={unb}" if unb else ""
        return (f"ConstrainedZonotope(dim={self.dim}, n_gen={self.n_gen}, "
                f"n_con={self.n_con}{extra})")

    # ------------------------------------------------------------------ exact operations
    def _check_same_dim(self, other: ConstrainedZonotope, what: str) -> None:
        if other.dim != self.dim:
            raise DimensionError(
                f"{what}: dimensions differ ({self.dim} vs {other.dim})"
            )

    def minkowski_sum(self, other: ConstrainedZonotope | ArrayLike, *,
                      err: ArrayLike | None = None) -> ConstrainedZonotope:
        """Minkowski sum with a set or a vector (Scott et al. 2016, eq. (12)).

        ``err`` (vectors only): elementwise bound on the uncertainty of the
        vector (e.g. the representation error of a measured input); it is
        carried in :attr:`c_err`, so every certified query covers it.

        Parameters
        ----------
        other : ConstrainedZonotope or array_like, shape (n,)
            The set or vector to add.
        err : array_like, shape (n,), optional
            Elementwise bound on the uncertainty of a vector summand (carried in
            :attr:`c_err`).
        """
        if not isinstance(other, ConstrainedZonotope):
            v = as_vector("vector", other, size=self.dim)
            c = self._c + v
            cerr = sum_err(c, self._cerr)
            if err is not None:
                e = as_vector("err", err, size=self.dim)
                if (e < 0).any():
                    raise InvalidValueError("err must be nonnegative")
                cerr = add_err(cerr, e)
            return self._same_factors(self._G, c, cerr, "Minkowski sum with a vector")
        if err is not None:
            raise ArgumentError("err applies to a vector summand only")
        if compiled_ops is not None:
            out = compiled_ops.minkowski_sum(self, other)
            if out is not None:
                return out
        self._check_same_dim(other, "Minkowski sum")
        c = self._c + other._c
        return ConstrainedZonotope._owned(
            np.concatenate((self._G, other._G), axis=1),
            c,
            _blockdiag2(self._A, other._A),
            np.concatenate((self._b, other._b)),
            np.concatenate((self._h, other._h)),
            min(self.unbounded_radius, other.unbounded_radius),
            sum_err(c, add_err(self._cerr, other._cerr)),
            None if self._berr is None and other._berr is None else
            cat_err(self._berr, self.n_con, other._berr, other.n_con),
            "Minkowski sum",
        )

    def __add__(self, other: Any) -> ConstrainedZonotope:
        if isinstance(other, ConstrainedZonotope) or np.ndim(other) == 1:
            return self.minkowski_sum(other)
        return NotImplemented

    __radd__ = __add__

    def __sub__(self, other: Any) -> ConstrainedZonotope:
        if isinstance(other, ConstrainedZonotope):
            raise ArgumentError("Z - W is ambiguous for sets: use Z + (-W) for the Minkowski sum "
                                "with the reflection, or Z.pontryagin_difference(W)")
        if np.ndim(other) == 1:
            return self.minkowski_sum(-as_vector("vector", other, size=self.dim))
        return NotImplemented

    def __neg__(self) -> ConstrainedZonotope:
        """``-Z``: the reflection ``linear_map(-I)`` (exact: only signs change)."""
        return self._same_factors(-self._G, -self._c, self._cerr, "reflection -Z")

    def __and__(self, other: Any) -> ConstrainedZonotope:
        """``Z & W``: :meth:`intersect` (exact)."""
        if isinstance(other, ConstrainedZonotope):
            return self.intersect(other)
        return NotImplemented

    def linear_map(self, M: ArrayLike) -> ConstrainedZonotope:
        """Image under ``x -> M x`` for any ``m x n`` matrix ``M`` (Scott et al. 2016, eq. (11)).

        Parameters
        ----------
        M : array_like, shape (m, n)
            The matrix (any ``m``; the map is exact).
        """
        if compiled_ops is not None:
            out = compiled_ops.linear_map(self, M)
            if out is not None:
                return out
        M_a = as_matrix("M (linear map)", M, cols=self.dim)
        return self._same_factors(M_a @ self._G, M_a @ self._c,
                                  map_err(M_a, self._c, self._cerr), "linear map")

    def _same_factors(self, G: NDArray[np.float64], c: NDArray[np.float64],
                      cerr: NDArray[np.float64] | None, op: str) -> ConstrainedZonotope:
        """A set with the same factor polytope; shares its LP model (and emptiness cache)."""
        out = ConstrainedZonotope._owned(G, c, self._A, self._b, self._h, self.unbounded_radius,
                                         cerr, self._berr, op)
        if "lp" in self._cache:
            out._cache["lp"] = self._cache["lp"]
        return out

    __rmatmul__ = linear_map

    def __matmul__(self, other: Any) -> ConstrainedZonotope:
        return NotImplemented

    def cartesian(self, other: ConstrainedZonotope) -> ConstrainedZonotope:
        """Cartesian product ``self x other``.

        Parameters
        ----------
        other : ConstrainedZonotope
            The second factor.
        """
        if not isinstance(other, ConstrainedZonotope):
            raise ArgumentError(f"cartesian expects a ConstrainedZonotope, got "
                                f"{type(other).__name__}")
        return ConstrainedZonotope._owned(
            _blockdiag2(self._G, other._G),
            np.concatenate([self._c, other._c]),
            _blockdiag2(self._A, other._A),
            np.concatenate([self._b, other._b]),
            np.concatenate([self._h, other._h]),
            min(self.unbounded_radius, other.unbounded_radius),
            cat_err(self._cerr, self.dim, other._cerr, other.dim),
            cat_err(self._berr, self.n_con, other._berr, other.n_con),
            "Cartesian product",
        )

    def intersect_affine(self, C: ArrayLike, y: ArrayLike, *,
                         y_err: ArrayLike | None = None) -> ConstrainedZonotope:
        """Intersection with the affine set ``{z : C z = y}`` (Li-Cong-Dong, eq. (21)).

        ``y_err``: elementwise bound on the uncertainty of ``y`` at rounding
        level (e.g. the representation error of a measurement); it is carried
        in :attr:`b_err`, so every certified query holds for all ``y`` within
        it. (Measurement *noise* is a set: use :meth:`intersect`.)

        Parameters
        ----------
        C : array_like, shape (m, n)
            Constraint matrix.
        y : array_like, shape (m,)
            Right-hand side.
        y_err : array_like, shape (m,), optional
            Elementwise bound on the uncertainty of ``y`` at rounding level (carried in
            :attr:`b_err`).
        """
        C_a = as_matrix("C", C, cols=self.dim)
        y_a = as_vector("y", y, size=C_a.shape[0])
        ye = None
        if y_err is not None:
            ye = as_vector("y_err", y_err, size=C_a.shape[0])
            if (ye < 0).any():
                raise InvalidValueError("y_err must be nonnegative")
        return ConstrainedZonotope._owned(
            self._G, self._c,
            np.vstack([self._A, C_a @ self._G]),
            np.concatenate([self._b, y_a - C_a @ self._c]),
            self._h, self.unbounded_radius, self._cerr,
            cat_err(self._berr, self.n_con, diff_err(y_a, C_a, self._c, self._cerr, ye),
                 C_a.shape[0]),
            "intersection with an affine set",
        )

    def intersect(self, other: ConstrainedZonotope, R: ArrayLike | None = None
                  ) -> ConstrainedZonotope:
        """Generalised intersection ``{z in self : R z in other}`` (Scott et al. 2016, eq. (13)).

        ``R`` defaults to the identity (plain intersection).

        Parameters
        ----------
        other : ConstrainedZonotope
            The set ``W``.
        R : array_like, shape (m, n), optional
            The map of the generalised intersection ``{z in Z : R z in W}`` (default the
            identity).
        """
        if compiled_ops is not None:
            out = compiled_ops.intersect(self, other, R)
            if out is not None:
                return out
        if not isinstance(other, ConstrainedZonotope):
            raise ArgumentError(f"intersect expects a ConstrainedZonotope, got "
                                f"{type(other).__name__}")
        if R is None:
            self._check_same_dim(other, "intersection")
            R_a = np.eye(self.dim)
        else:
            R_a = as_matrix("R (generalised intersection)", R, rows=other.dim, cols=self.dim)
        n_c1, n_c2 = self.n_con, other.n_con
        A = np.zeros((n_c1 + n_c2 + other.dim, self.n_gen + other.n_gen))
        A[:n_c1, : self.n_gen] = self._A
        A[n_c1 : n_c1 + n_c2, self.n_gen :] = other._A
        A[n_c1 + n_c2 :, : self.n_gen] = R_a @ self._G
        A[n_c1 + n_c2 :, self.n_gen :] = -other._G
        b = np.concatenate([self._b, other._b, other._c - R_a @ self._c])
        new_err = diff_err(other._c, R_a, self._c, self._cerr, other._cerr)
        berr = cat_err(cat_err(self._berr, n_c1, other._berr, n_c2), n_c1 + n_c2, new_err,
                       other.dim)
        G = np.zeros((self.dim, self.n_gen + other.n_gen))
        G[:, : self.n_gen] = self._G
        return ConstrainedZonotope._owned(
            G, self._c, A, b,
            np.concatenate([self._h, other._h]), min(self.unbounded_radius, other.unbounded_radius),
            self._cerr, berr, "generalised intersection",
        )

    def project(self, dims: Sequence[int] | NDArray[np.integer]) -> ConstrainedZonotope:
        """Projection onto the coordinates ``dims`` (in that order).

        Parameters
        ----------
        dims : sequence of int
            Coordinates kept, in this order.
        """
        idx = np.asarray(dims, dtype=int).reshape(-1)
        if idx.size == 0 or (idx < 0).any() or (idx >= self.dim).any():
            raise DimensionError(
                f"dims must be indices in [0, {self.dim - 1}], got {list(np.atleast_1d(dims))}"
            )
        return self._same_factors(self._G[idx], self._c[idx],
                                  None if self._cerr is None else self._cerr[idx], "projection")

    # ------------------------------------------------------------------ LP queries
    def _lp(self) -> FactorPolytope:
        fp = self._cache.get("lp")
        if fp is None:
            fp = FactorPolytope(self._A, self._b, self._h, unbounded_radius=self.unbounded_radius,
                                b_err=self._berr)
            self._cache["lp"] = fp
        return fp

    def interval_hull(self) -> Box:
        """Certified interval hull (smallest box containing the set), as a :class:`Box`.

        Computed with ``2n`` LPs that share one HiGHS model (only the objective
        changes). Bounds are certified outer bounds (see
        :mod:`setobs.lp.factor`); unbounded directions give ``+-inf``.

        Raises
        ------
        EmptySetError
            If the set is certified empty.

        Warns
        -----
        SolverWarning
            If an LP failed under every solver setting: the box is then still a
            certified outer bound, but wider (possibly infinite) in that
            coordinate.
        """
        box, fallback = self._interval_hull()
        if fallback:
            warnings.warn("an LP of the interval hull failed under every solver setting; "
                          "the returned box is a wider certified outer bound",
                          SolverWarning, stacklevel=2)
        return box

    def _interval_hull(self, gap: NDArray[np.float64] | None = None) -> tuple[Box, bool]:
        """:meth:`interval_hull` without the warning: ``(box, any_fallback)``; with
        ``gap`` (per coordinate), each bound may stop within its coordinate's gap of the
        exact one (certified outer all the same; not cached)."""
        cached = self._cache.get("hull")
        if cached is not None:
            return cached
        if not self.n_con:
            out = (self._zonotope_hull(), False)
            self._cache["hull"] = out
            return out
        n = self.dim
        low = np.zeros(n)
        upp = np.zeros(n)
        fp = self._lp()
        before = fp.fallbacks
        zero_rows = ~self._G.any(axis=1)
        if self.n_con and zero_rows.any() and fp.emptiness().empty:
            raise EmptySetError("the set is empty (certified by the phase-1 LP)")
        rows = np.flatnonzero(~zero_rows)
        W = np.empty((2 * rows.size, self.n_gen))
        W[0::2] = self._G[rows]
        W[1::2] = -self._G[rows]
        fast, ok = fp.minimize_many(W) if gap is None else fp.minimize_many(W, gap[rows])
        for t, i in enumerate(rows):
            g = self._G[i]
            lw = fast[2 * t] if ok[2 * t] else fp.minimize(g).bound
            up = -fast[2 * t + 1] if ok[2 * t + 1] else -fp.minimize(-g).bound
            if lw > up:
                # Crossing certified bounds prove the exact set empty; within the
                # emptiness tolerance it may not be: decide, then relax outward.
                if fp.emptiness().empty:
                    raise EmptySetError("the set is empty (certified by the phase-1 LP)")
                lw = fp.minimize_relaxed(g).bound
                up = -fp.minimize_relaxed(-g).bound
            low[i], upp[i] = lw, up
        lo, hi = outward_interval(self._c, self._cerr, low, upp, offset=~zero_rows)
        # (trusted: an outer bound of a set with data up to MAX_MAGNITUDE may exceed it)
        out = (trusted_box(lo, hi), fp.fallbacks > before)
        if gap is None:
            self._cache["hull"] = out
        return out

    def _zonotope_hull(self) -> Box:
        """The hull without constraints, in closed form: ``c +- |G| h`` (Scott et al.
        2016, eq. (4)), the radius rounded up (``gamma_(n_g + 1)``, then one ulp) and
        infinite in rows that an unbounded factor reaches."""
        G, h = self._G, self._h
        unb = np.isinf(h)
        absG = np.abs(G)
        Gb, hb = (absG[:, ~unb], h[~unb]) if unb.any() else (absG, h)
        rad = Gb @ hb
        # exact where a row has one term and its bound is a power of two (boxes,
        # points, axis-aligned generators); else rounded up
        one = (Gb != 0.0).sum(axis=1) <= 1
        pow2 = (np.frexp(hb)[0] == 0.5) | (hb == 0.0)
        exact = one & ((Gb == 0.0) | pow2[None, :]).all(axis=1)
        rad = np.where(exact, rad, np.nextafter(rad * (1.0 + gamma(self.n_gen + 1)), np.inf))
        if unb.any():
            rad[absG[:, unb].any(axis=1)] = np.inf
        offset = rad > 0.0
        lo, hi = outward_interval(self._c, self._cerr, -rad, rad, offset=offset)
        return trusted_box(lo, hi)

    def support(self, direction: ArrayLike) -> float:
        """Certified support function ``max_{z in Z} d^T z`` (``+inf`` if unbounded).

        Parameters
        ----------
        direction : array_like, shape (n,)
            The direction ``d``.

        Raises
        ------
        EmptySetError
            If the set is certified empty.

        Warns
        -----
        SolverWarning
            If the LP failed under every solver setting (the value is then a
            wider certified bound, possibly ``inf``).
        """
        d = as_vector("direction", direction, size=self.dim)
        val, fallback = self._support_value(d)
        if fallback:
            warnings.warn("the support LP failed under every solver setting; the value is a "
                          "wider certified bound", SolverWarning, stacklevel=2)
        return val

    def _support(self, d: NDArray[np.float64]) -> float:
        """:meth:`support` for a validated direction, without the warning."""
        return self._support_value(d)[0]

    def _support_value(self, d: NDArray[np.float64]) -> tuple[float, bool]:
        s, out = self._support_lp(d)
        return s, out.status == "fallback"

    def _support_lp(self, d: NDArray[np.float64]) -> tuple[float, LPResult]:
        """The certified support value in direction ``d`` and the LP's result."""
        w = self._G.T @ d
        w_err = 2.0 * gamma(self.dim + 1) * (np.abs(self._G).T @ np.abs(d))
        out = self._lp().minimize(-w, w_err=w_err, w_pair=(self._G, -d))
        if not np.isfinite(out.bound):
            return np.inf, out
        dc = float(d @ self._c)
        err = 2.0 * gamma(self.dim + 1) * float(np.abs(d) @ np.abs(self._c))
        if self._cerr is not None:
            err += float(np.abs(d) @ self._cerr) * (1.0 + gamma(self.dim + 1))
        s = -out.bound + dc
        return round_up(s + err + UNIT_ROUNDOFF * abs(s)), out

    def support_point(self, direction: ArrayLike) -> NDArray[np.float64]:
        """A maximiser of ``d^T z`` over the set (the solver's point; not certified).

        Parameters
        ----------
        direction : array_like, shape (n,)
            The direction ``d``.

        Raises
        ------
        UnboundedSetError
            If the support function is infinite in this direction.
        SolverError
            If no solver setting produced a point.
        """
        d = as_vector("direction", direction, size=self.dim)
        return self._maximiser(self._lp().minimize(-(self._G.T @ d)))[0]

    def _maximiser(self, out: LPResult) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """``(G xi + c, xi)`` for the point ``xi`` of a support LP's result, or the errors
        of :meth:`support_point`."""
        if out.status == "fallback" or (out.point is None and np.isfinite(out.bound)):
            raise SolverError("no LP solver setting produced a maximiser", status=out.status)
        if out.point is None or not np.isfinite(out.bound):
            raise UnboundedSetError("the set is unbounded in this direction")
        return self._G @ out.point + self._c, out.point

    def emptiness(self, tol: float = FEASIBILITY_TOL) -> EmptinessReport:
        """Certified emptiness report with a witness (see :meth:`FactorPolytope.emptiness`).

        When the set is not reported empty, ``witness`` is a point ``G xi + c``
        of the set (``xi`` the phase-1 LP's point, within ``violation_found``
        of the normalised constraints).

        Parameters
        ----------
        tol : float
            Feasibility tolerance of the phase-1 LP (normalised constraint violation).
        """
        rep = self._lp().emptiness(tol)
        if rep.witness is None:
            return rep
        return dataclasses.replace(rep, witness=self._G @ rep.witness + self._c)

    def is_empty(self, tol: float = FEASIBILITY_TOL) -> bool:
        """Whether the set is empty.

        ``True`` is certified: every point violates some constraint, normalised
        to a unit infinity-norm row, by more than ``tol``. Sets that are empty
        only by a margin below ``tol`` are reported non-empty.

        Parameters
        ----------
        tol : float
            Feasibility tolerance of the phase-1 LP (normalised constraint violation).
        """
        return self.emptiness(tol).empty

    def contains(self, x: ArrayLike, tol: float = FEASIBILITY_TOL) -> bool:
        """Whether ``x`` is in the set, up to ``tol``.

        ``False`` is certified: no representation ``x = G xi + c`` with
        ``|xi| <= h`` satisfies the normalised equalities (including
        ``G xi = x - c``) within ``tol``.

        Parameters
        ----------
        x : array_like, shape (n,)
            The point.
        tol : float
            Feasibility tolerance (normalised constraint violation).
        """
        xv = as_vector("x", x, size=self.dim)
        # the factor set of Z cap {x} (rows A xi = b, G xi = x - c), built directly: the
        # rounding of fl(x - c) is at most u |fl(x - c)| (one subtraction), and c's own
        # uncertainty c_err adds to it
        d = xv - self._c
        err = sum_err(d, self._cerr)
        fp = FactorPolytope(np.vstack([self._A, self._G]), np.concatenate([self._b, d]),
                            self._h, unbounded_radius=self.unbounded_radius,
                            b_err=cat_err(self._berr, self.n_con, err, self.dim))
        return not fp.emptiness(tol).empty

    # ------------------------------------------------------------------ more operations
    def intersect_halfspace(self, a: ArrayLike, beta: float) -> ConstrainedZonotope:
        """``{z in Z : a^T z <= beta}`` (exact); see
        :func:`setobs.geometry.operations.intersect_halfspace`."""
        from .operations import intersect_halfspace

        return intersect_halfspace(self, a, beta)

    def intersect_strip(self, C: ArrayLike, y: ArrayLike, radius: ArrayLike
                        ) -> ConstrainedZonotope:
        """``{z in Z : |C z - y| <= radius}`` (exact); see
        :func:`setobs.geometry.operations.intersect_strip`."""
        from .operations import intersect_strip

        return intersect_strip(self, C, y, radius)

    def intersect_polytope(self, H: ArrayLike, k: ArrayLike, E: ArrayLike | None = None,
                           f: ArrayLike | None = None) -> ConstrainedZonotope:
        """``{z in Z : H z <= k, E z = f}`` (exact); see
        :func:`setobs.geometry.operations.intersect_polytope`."""
        from .operations import intersect_polytope

        return intersect_polytope(self, H, k, E, f)

    def convex_hull(self, other: ConstrainedZonotope) -> ConstrainedZonotope:
        """Convex hull with ``other`` (exact); see
        :func:`setobs.geometry.operations.convex_hull`."""
        from .operations import convex_hull

        return convex_hull(self, other)

    def pontryagin_difference(self, other: Any, method: str = "exact") -> ConstrainedZonotope:
        """``{z : z + other subset Z}``; see
        :func:`setobs.geometry.operations.pontryagin_difference`."""
        from .operations import pontryagin_difference

        return pontryagin_difference(self, other, method)

    def interval_matrix_map(self, M_lo: ArrayLike, M_hi: ArrayLike) -> ConstrainedZonotope:
        """Outer bound of ``{M z : M_lo <= M <= M_hi, z in Z}``; see
        :func:`setobs.geometry.operations.interval_matrix_map`."""
        from .operations import interval_matrix_map

        return interval_matrix_map(self, M_lo, M_hi)

    def quad_map(self, Q: ArrayLike) -> ConstrainedZonotope:
        """Outer bound of ``{(z^T Q_i z)_i : z in Z}`` (CORA's ``quadMap``); see
        :func:`setobs.geometry.operations.quad_map`."""
        from .operations import quad_map

        return quad_map(self, Q)

    def is_subset(self, other: ConstrainedZonotope) -> ContainmentResult:
        """Whether ``Z subset other`` (three-valued); see
        :func:`setobs.geometry.relations.is_subset`."""
        from .relations import is_subset

        return is_subset(self, other)

    def is_equal(self, other: ConstrainedZonotope, tol: float = 0.0) -> ContainmentResult:
        """Whether the two sets are equal (three-valued), up to the Hausdorff distance ``tol``
        (infinity norm); see :func:`setobs.geometry.relations.is_equal`."""
        from .relations import is_equal

        return is_equal(self, other, tol)

    def represents(self, kind: str, tol: float | None = None) -> bool:
        """Whether the set is (up to ``tol``) empty, a point, the origin, a box or a zonotope
        (CORA's ``representsa``); see :func:`setobs.geometry.relations.represents`."""
        from .relations import represents

        return represents(self, kind, tol)

    def nearest_point(self, p: ArrayLike) -> NDArray[np.float64]:
        """Euclidean projection of ``p`` onto the set; see
        :func:`setobs.geometry.measure.nearest_point`."""
        from .measure import nearest_point

        return nearest_point(self, p)

    def distance(self, p: ArrayLike) -> DistanceResult:
        """Distance from ``p`` with a certified lower bound; see
        :func:`setobs.geometry.measure.distance`."""
        from .measure import distance

        return distance(self, p)

    def sample(self, n: int, rng: np.random.Generator | int | None = None) -> NDArray[np.float64]:
        """Uniform random points by hit-and-run; see :func:`setobs.geometry.measure.sample`."""
        from .measure import sample

        return sample(self, n, rng)

    def volume(self) -> VolumeResult:
        """Volume (exact up to 3-D, Monte Carlo with a CI above); see
        :func:`setobs.geometry.measure.volume`."""
        from .measure import volume

        return volume(self)

    # ------------------------------------------------------------------ reduction
    def remove_redundancy(self, tol: float | None = None) -> ConstrainedZonotope:
        """Remove zero/duplicate/dependent constraints and unused factors; see
        :func:`setobs.geometry.reduction.remove_redundancy`."""
        from .reduction import remove_redundancy

        return remove_redundancy(self) if tol is None else remove_redundancy(self, tol=tol)

    def rescale(self) -> ConstrainedZonotope:
        """Tighten factor bounds to the certified factor hull; see
        :func:`setobs.geometry.reduction.rescale`."""
        from .reduction import rescale

        return rescale(self)

    def reduce_exact(self) -> ConstrainedZonotope:
        """The same set with redundant factor bounds, constraints and factors removed;
        see :func:`setobs.geometry.reduction.reduce_exact`."""
        from .reduction import reduce_exact

        return reduce_exact(self)

    def eliminate_constraints(self, max_constraints: int, method: str = "auto"
                              ) -> ConstrainedZonotope:
        """Outer constraint elimination (Scott et al. 2016, Sec. 4.2); see
        :func:`setobs.geometry.reduction.eliminate_constraints`."""
        from .reduction import eliminate_constraints

        return eliminate_constraints(self, max_constraints, method)

    def reduce_order(self, max_generators: int) -> ConstrainedZonotope:
        """Outer generator-order reduction; see :func:`setobs.geometry.reduction.reduce_order`."""
        from .reduction import reduce_order

        return reduce_order(self, max_generators)

    # ------------------------------------------------------------------ conversion, plotting
    def vertices(self) -> NDArray[np.float64]:
        """Vertices of a bounded set (verified); see :func:`setobs.geometry.polytope.vertices`."""
        from .polytope import vertices

        return vertices(self)

    def to_hrep(self) -> HRep:
        """H-representation of a bounded set; see :func:`setobs.geometry.polytope.to_hrep`."""
        from .polytope import to_hrep

        return to_hrep(self)

    def plot(self, ax: Axes | None = None, dims: Sequence[int] = (0, 1), **kwargs: Any) -> Patch:
        """Plot the projection onto ``dims``; see :func:`setobs.plotting.plot_set`."""
        from ._draw import plot_set

        return plot_set(self, ax=ax, dims=dims, **kwargs)


def compiled_set_operations() -> bool:
    """Whether ``Z + W``, ``M @ Z`` and :meth:`ConstrainedZonotope.intersect` run compiled.

    The compiled construction (a C extension built at install, ``setup.py``) returns the
    same sets as the NumPy code up to rounding (bit for bit for the sum and the plain
    intersection; the products of the maps and of ``R`` may be summed in another order
    than by the BLAS), with the same error bounds on the centre and the right-hand side,
    which cover either rounding; 5-10x faster on small sets. Both refuse the same inputs
    and never build a set whose data are not finite or exceed ``MAX_MAGNITUDE``
    (:func:`check_set_data`). Where it could not be built (no C compiler), the NumPy
    code runs.

    Returns
    -------
    bool
        True if the extension is loaded.
    """
    return compiled_ops is not None


if compiled_ops is not None:
    # (the extension checks that the slots it writes are exactly the class's: a slot
    # added in Python without a rebuild would be left unset in every set it builds)
    try:
        compiled_ops.bind(ConstrainedZonotope, float(MAX_MAGNITUDE))
    except TypeError as exc:  # pragma: no cover - a stale build
        import warnings

        warnings.warn(f"compiled set operations disabled: {exc}", RuntimeWarning, stacklevel=1)
        compiled_ops = None


# ---------------------------------------------------------------- package-internal access
# The functions below are the package's internal interface to a constrained
# zonotope's unchecked construction and unwarned certified queries (used by the
# reductions, the polytope conversions and the SMFDO). They are not in
# ``__all__`` and carry no stability promise.


def trusted_cz(G: NDArray[np.float64], c: NDArray[np.float64], A: NDArray[np.float64],
               b: NDArray[np.float64], h: NDArray[np.float64],
               unbounded_radius: float = UNBOUNDED_RADIUS, cerr: NDArray[np.float64] | None = None,
               berr: NDArray[np.float64] | None = None, op: str = "building a set"
               ) -> ConstrainedZonotope:
    """Build from arrays the caller has already validated (no shape checks), refusing
    data that are not finite or exceed ``MAX_MAGNITUDE`` (:func:`check_set_data`).

    ``cerr``, ``berr``: elementwise bounds on the rounding errors already in
    ``c`` and ``b`` (``None``: exact); certified queries widen by them. ``op``: the
    operation the error message names.
    """
    return ConstrainedZonotope._trusted(G, c, A, b, h, unbounded_radius, cerr, berr, op=op)


def owned_cz(G: NDArray[np.float64], c: NDArray[np.float64], A: NDArray[np.float64],
             b: NDArray[np.float64], h: NDArray[np.float64],
             unbounded_radius: float = UNBOUNDED_RADIUS, cerr: NDArray[np.float64] | None = None,
             berr: NDArray[np.float64] | None = None, op: str = "building a set"
             ) -> ConstrainedZonotope:
    """:func:`trusted_cz` for fresh float64 arrays the caller hands over (no other
    reference to them remains): not copied, made read-only."""
    return ConstrainedZonotope._owned(G, c, A, b, h, unbounded_radius, cerr, berr, op)


def magnitude(Z: ConstrainedZonotope) -> float:
    """A bound on ``max |z|`` over the set without an LP: ``|c| + |G| h`` on the finite
    factors (``inf`` when a factor is unbounded), at least the largest ``|c|``."""
    fin = np.isfinite(Z.h)
    if not fin.all():
        return float("inf")
    return float((np.abs(Z.c) + np.abs(Z.G) @ Z.h).max(initial=0.0))


def unit_scaled(Z: ConstrainedZonotope, *others: float) -> tuple[ConstrainedZonotope, float]:
    """``(Z / f, f)`` with ``f`` the power of two that brings the set's magnitude
    (:func:`magnitude`, or the largest of ``others`` if larger) into ``[1/2, 1)``.

    Scaling by a power of two is exact in floating point (``G``, ``c`` and the
    rounding bound of ``c`` are divided; the factors, ``A``, ``b`` and ``h`` are
    unchanged), so a query answered on ``Z / f`` and multiplied back by ``f`` is the
    query on ``Z``, and its tolerances become relative to the set's magnitude: the
    same answer, scaled, for a set and its image under ``x -> s x``. ``f = 1`` for a
    set already at that magnitude, an unbounded one, or the origin.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    *others : float
        Further magnitudes to cover (a query point's ``max |p|``).
    """
    m = max([magnitude(Z), *[float(o) for o in others]])
    if not np.isfinite(m) or m <= 0.0:
        return Z, 1.0
    _, e = math.frexp(m)      # m = f' 2^e with f' in [1/2, 1)
    f = math.ldexp(1.0, e)
    Zs = scaled_by(Z, f)
    return (Z, 1.0) if Zs is Z else (Zs, f)


def scaled_by(Z: ConstrainedZonotope, f: float) -> ConstrainedZonotope:
    """``Z / f`` for a power of two ``f`` (exact: see :func:`unit_scaled`).

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    f : float
        A power of two.
    """
    cached = Z._cache.get(("scaled_by", f))
    if cached is not None:   # repeated queries reuse the scaled set and its LP caches
        return cached
    # Factors at unit size too (each finite h_j brought into [1/2, 1) by a power of
    # two, the column of G and A multiplied by it: exact), so that tolerances on the
    # factors (point containment, LP feasibility) are relative as well.
    h = Z.h
    fin = np.isfinite(h) & (h > 0.0)
    e = np.zeros(h.size, dtype=int)
    if fin.any():
        e[fin] = np.frexp(h[fin])[1]
    if f == 1.0 and not e.any():
        return Z
    col = np.ldexp(1.0, e)
    cerr = None if Z._cerr is None else Z._cerr / f
    out = ConstrainedZonotope._trusted(Z.G * (col / f)[None, :], Z.c / f, Z.A * col[None, :],
                                       Z.b, np.where(fin, np.ldexp(h, -e), h),
                                       Z.unbounded_radius, cerr, Z._berr, op=None)
    Z._cache[("scaled_by", f)] = out
    return out


def factor_polytope(Z: ConstrainedZonotope) -> FactorPolytope:
    """The cached LP engine over ``Z``'s factor polytope ``{xi : A xi = b, |xi| <= h}``."""
    return Z._lp()


def hull_with_status(Z: ConstrainedZonotope, gap: ArrayLike | None = None
                     ) -> tuple[Box, bool]:
    """:meth:`ConstrainedZonotope.interval_hull` without the warning: ``(box, any_fallback)``.

    ``gap`` (one nonnegative number per coordinate): each bound the compiled simplex
    finds may stop within its coordinate's gap of the exact one, so a coordinate's
    interval is at most twice its gap wider than the exact hull's; every bound is
    certified either way. The early-stopped hull is not cached."""
    if gap is None:
        return Z._interval_hull()
    g = np.asarray(gap, dtype=np.float64)
    if g.shape != (Z.dim,) or not (np.isfinite(g).all() and (g >= 0.0).all()):
        raise InvalidValueError(f"gap must be {Z.dim} finite nonnegative numbers, got {gap!r}")
    return Z._interval_hull(g)


def support_point_factors(Z: ConstrainedZonotope, d: NDArray[np.float64]
                          ) -> tuple[float, NDArray[np.float64], NDArray[np.float64]]:
    """``(s, G xi + c, xi)`` from one LP in a validated direction ``d``: the certified
    support value ``s`` (as :meth:`ConstrainedZonotope.support`, unwarned) and the LP's
    maximiser ``xi`` of ``d^T (G xi + c)``; the errors of
    :meth:`ConstrainedZonotope.support_point`."""
    s, out = Z._support_lp(d)
    return (s, *Z._maximiser(out))


def support_unwarned(Z: ConstrainedZonotope, d: NDArray[np.float64]) -> float:
    """:meth:`ConstrainedZonotope.support` for a validated direction, without the warning."""
    return Z._support(d)


def absorb_center_error(Z: ConstrainedZonotope, rtol: float) -> ConstrainedZonotope:
    """``Z`` with its centre's rounding bound carried as bounded factors, when it exceeds
    ``rtol`` times the set's magnitude (``max|c|``, or the largest reach
    ``|G| h`` of its bounded factors if that is larger); else ``Z`` itself.

    The certified set ``{c + e + G xi : |e| <= c_err, A xi = b, |xi| <= h}`` is
    ``{c + [G, diag(c_err)] [xi; eta] : A xi = b, |xi| <= h, |eta| <= 1}`` (the
    new factors are unconstrained), so the set is unchanged. A linear map then
    acts on the error as on any generator, ``M diag(c_err)``, instead of
    bounding it by ``|M| c_err``: in a recursion ``Z_(k+1) = A Z_k + ...`` the
    latter grows like ``rho(|A|)^k`` even when ``A`` is stable (on a non-normal
    ``A`` with ``rho(|A|) = 2.4``, 1e-3 of the set's width after 30 steps),
    the former decays with ``A^k``.

    Parameters
    ----------
    Z : ConstrainedZonotope
        The set.
    rtol : float
        Threshold relative to the set's magnitude (0: absorb any error).
    """
    cerr = Z._cerr
    if cerr is None:
        return Z
    # the set's magnitude: its centre, or its bounded generators' reach (a centre at
    # or near zero must not make every step absorb)
    reach = np.abs(Z._G) @ np.where(np.isinf(Z._h), 0.0, Z._h)
    scale = max(float(np.abs(Z._c).max(initial=0.0)), float(reach.max(initial=0.0)))
    if float(cerr.max()) <= rtol * scale:
        return Z
    j = np.flatnonzero(cerr > 0.0)
    E = np.zeros((Z.dim, j.size))
    E[j, np.arange(j.size)] = cerr[j]
    return ConstrainedZonotope._trusted(
        np.hstack([Z._G, E]), Z._c, np.hstack([Z._A, np.zeros((Z.n_con, j.size))]), Z._b,
        np.concatenate([Z._h, np.ones(j.size)]), Z.unbounded_radius, None, Z._berr,
        op="absorbing the centre's rounding bound")
