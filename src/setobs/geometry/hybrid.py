"""Hybrid zonotopes (Bird, Pangborn, Jain, Hinrichs 2023) with certified queries.

A hybrid zonotope is the set

.. math::  \\{G_c \\xi_c + G_b \\xi_b + c : A_c \\xi_c + A_b \\xi_b = b,\\
           |\\xi_{c,j}| \\le h_j,\\ \\xi_b \\in \\{-1, 1\\}^{n_b}\\}

(Bird et al. 2023, Definition 3, with the extended constrained zonotope's factor bounds
``h``, ``h_j = inf`` allowed, Li-Cong-Dong Definition 2): a union of up to ``2^n_b``
constrained zonotopes, one per assignment of the binary factors (its *leaves*), written
with a size that grows linearly where a list of polytopes grows exponentially.

Representation
--------------
A :class:`HybridZonotope` is its *convex relaxation* (the binary factors relaxed to
``[-1, 1]``), an extended constrained zonotope, and which of its factors are binary. It
stores the relaxation in two parts: the *zonotope part* (``G``, ``c``, ``c_err``, ``h``: a
:class:`~setobs.ConstrainedZonotope` without rows) and the *rows* ``A xi = b`` (``b_err``)
with ``A`` sparse, as coordinate triplets; the dense relaxation
(:attr:`HybridZonotope.relaxation`) and the compressed-column ``A`` that HiGHS takes are
built once, when a query asks. The set operations are the relaxation's exact operations
(Scott et al. 2016, Sec. 3; Bird et al. 2023, Propositions 1-3: linear map, Minkowski
sum, generalised intersection and Cartesian product act on the factors as for a
constrained zonotope): the zonotope parts combine by the constrained zonotope's own
operations (the generalised intersection's new rows ``[R G, -G_W]``, ``c_W - R c`` come
out of the zonotope parts' intersection), the rows stack block-diagonally, the binary
flags follow their factors, and the rounding bounds of centres and right-hand sides
(``c_err``, ``b_err``) are carried as for constrained zonotopes. The union, the Minkowski
sum and the generalised intersection have a compiled construction (``_setops.c``) of the
same arrays; the NumPy code here is its reference and its fallback.

Certified queries (branch and bound)
------------------------------------
A node of the search fixes some binary factors to ``+-1`` and relaxes the rest: it is a
constrained zonotope (the fixed columns moved into the centre and the right-hand side,
with their rounding bounded), which contains every leaf below it. Every bound is a
certified answer of the constrained-zonotope core (:mod:`setobs.lp.factor`):

* *support function* ``max d^T z``: best-first (or depth-first) search; a node is closed
  when its relaxation is certified empty (pruned), when it is a leaf, or when its LP's
  maximiser has every free binary at ``+-1`` within :data:`~setobs.tolerances.BINARY_TOL`
  (the relaxation's value is then attained by a leaf, up to the solver's accuracy); a node
  whose certified bound does not exceed the largest certified bound of the closed nodes
  cannot raise the answer and is pruned. The answer is the largest certified bound over
  the closed nodes and, when a node or time limit stops the search, over the open ones
  too: **an outer bound whenever the search stops**, with the gap to the best value
  attained at a leaf (:class:`BranchAndBoundResult`).
* *emptiness*: depth-first; the set is empty only when every node on the frontier is
  certified empty (a phase-1 LP's certified violation above the tolerance), non-empty
  when a leaf is not (its phase-1 point is the witness), undecided when a limit stops
  the search.
* *point containment*: the emptiness of ``H cap {x}``.
* *interval hull*: ``2 n`` support searches.

The bound of a node is valid for every leaf below it because a leaf's factor set is
the node's factor set with more factors fixed, a subset; so the largest node bound over
a frontier that covers every leaf bounds the set's support function. Nothing in a bound
depends on the branching order or on the solver's tolerances.

Unions (a disjunctive formulation)
----------------------------------
:meth:`HybridZonotope.from_union` writes ``Z_1 cup ... cup Z_N`` with a selector
``lam_i = (1 + beta_i) / 2`` per operand (``beta_i`` binary, ``sum beta_i = 2 - N``: one
selected) and copies of each operand's factors scaled by its selector (Balas 1979,
"Disjunctive programming"; the sharp unions of Glunt, Robbins, Siefert, Silvestre and
Pangborn 2025): for a continuous factor ``|xi_j| <= h_j`` the copy ``xt_j`` with two
slacks ``s1, s2 in [-1, 1]``,

.. math::  \\tfrac{h_j}{2}\\beta_i - \\tilde\\xi_j - h_j s_1 = \\tfrac{h_j}{2},\\qquad
           \\tfrac{h_j}{2}\\beta_i + \\tilde\\xi_j - h_j s_2 = \\tfrac{h_j}{2},

which say ``|xt_j| <= h_j lam_i`` (their sum is ``beta_i - s1 - s2 = 1``: at ``beta_i = -1``
both slacks are ``-1`` and ``xt_j = 0``; at ``beta_i = 1``, ``xt_j = -h_j s1`` is free in
``[-h_j, h_j]``); for an operand's binary factor ``b_j`` the copy ``bt_j`` (binary) with
``bt_j - beta_i + s = -1``, ``s in [-1, 1]`` (that is, ``(1 + bt_j)/2 <= lam_i``); the
operand's rows ``A_c xt + A_b bt - ((A_b 1 + b)/2) beta_i = (b - A_b 1)/2`` and its point
``G_c xt + G_b bt + ((c - G_b 1)/2) beta_i + (c + G_b 1)/2``. With ``lam_i = 1`` these
are the operand itself (``bt = b``); with ``lam_i = 0`` every copy is zero and the rows
read ``0 = 0``. For constrained-zonotope operands the relaxation is the convex hull of the
union (the formulation is sharp), so the search's bounds are as tight as they can be at
the root. The operands' rounding bounds are carried, not turned into factors: the
selected operand's centre error is at most the largest of the operands' ``c_err``
(elementwise; one selector is 1, the others 0), which the union's ``c_err`` takes on, and
operand ``i``'s rows, scaled by ``lam_i in [0, 1]``, keep its ``b_err``; with the rounding
of the sums ``G_b 1``, ``A_b 1`` and of the union's centre bounded, the union contains the
operands' certified sets, and exceeds their union by at most those rounding bounds (the
rounding of generator and constraint entries is not tracked, as in
:class:`~setobs.ConstrainedZonotope`). An operand with an unbounded factor is
refused: a copy of an unbounded factor cannot be forced to zero.
"""

from __future__ import annotations

import dataclasses
import heapq
import time
import warnings
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._lazy import lazy_module
from .._rounding import UNIT_ROUNDOFF, gamma, round_down, round_up
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
from ..lp import highs
from ..lp.factor import FactorPolytope
from ..lp.factor._scaling import row_scale
from ..lp.fastlp import FixedStructureLP
from ..tolerances import (
    BINARY_TOL,
    FEASIBILITY_TOL,
    RELAXED_EXACT_GAP,
    UNBOUNDED_RADIUS,
    ZERO_TOL,
)
from ._bounds import cat_err, map_err
from ._guard import check_set_data
from .box import Box, box_center_radius
from .operations import empty_set
from .operations import from_vertices as cz_from_vertices
from .reduction import reduce_exact_among
from .reduction import remove_redundancy as cz_remove_redundancy
from .zonotope import (
    ConstrainedZonotope,
    compiled_ops,
    factor_polytope,
    owned_cz,
    support_point_factors,
    support_unwarned,
    trusted_cz,
)

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

sparse = lazy_module("scipy.sparse")
_certificate = lazy_module("setobs.lp.certificate")
_simplex = lazy_module("setobs.lp._simplex")

__all__ = ["NODE_COMPILED_MAX_ROWS", "NODE_LIMIT", "BranchAndBoundResult", "HybridEmptiness",
           "HybridZonotope", "pwa_reachable_sets"]

#: Default number of nodes (LPs) a branch-and-bound query may evaluate before it stops
#: with its certified outer answer and status ``"node_limit"``.
NODE_LIMIT = 20000

#: Most constraint rows for which the branch and bound solves its nodes by the compiled
#: dual simplex (one warm state per search); above, one HiGHS model per search. (Development
#: runs, interval hulls of the benchmark's unions: the compiled nodes 1.8x faster at 57
#: rows, even at 113, HiGHS's 2.3x faster at 177 and 9x at 449.)
NODE_COMPILED_MAX_ROWS = 128


@dataclasses.dataclass(frozen=True)
class BranchAndBoundResult:
    """A certified support value of a hybrid zonotope from a branch and bound.

    Attributes
    ----------
    value : float
        Certified upper bound of ``max d^T z`` over the set (``+inf`` if unbounded or not
        certifiably bounded), whatever ``status`` is.
    attained : float
        The largest ``d^T z`` at an LP maximiser of a closed leaf (a point of the set up to
        the solver's accuracy; not certified); ``-inf`` if none was found.
    gap : float
        ``value - attained`` (``inf`` when nothing was attained).
    status : str
        ``"optimal"`` (every node closed or pruned: ``value`` is the support function
        up to the LPs' certification gaps), ``"node_limit"`` or ``"time_limit"`` (stopped
        early: ``value`` is still an outer bound, looser by up to ``gap``).
    nodes : int
        Nodes evaluated (one LP each).
    open_nodes : int
        Nodes left open when the search stopped.
    binaries : ndarray or None
        The binary factors (``+-1``) of the leaf that attained ``attained``.
    """

    value: float
    attained: float
    gap: float
    status: str
    nodes: int
    open_nodes: int
    binaries: NDArray[np.float64] | None = None


@dataclasses.dataclass(frozen=True)
class HybridEmptiness:
    """Outcome of a hybrid zonotope's emptiness test.

    Attributes
    ----------
    empty : bool
        ``True`` only when certified: every node of a frontier covering all leaves is
        certified empty (:meth:`~setobs.geometry.FactorPolytope.emptiness`).
    status : str
        ``"empty"``, ``"nonempty"`` (a leaf not certified empty: ``witness``) or
        ``"undecided"`` (a node or time limit stopped the search; ``empty`` is ``False``
        but not certified).
    witness : ndarray or None
        A point of a non-empty leaf (its phase-1 point, within ``tol`` of the normalised
        constraints).
    binaries : ndarray or None
        That leaf's binary factors (``+-1``).
    nodes : int
        Nodes evaluated.
    tol : float
        The feasibility tolerance used.
    """

    empty: bool
    status: str
    witness: NDArray[np.float64] | None
    binaries: NDArray[np.float64] | None
    nodes: int
    tol: float = FEASIBILITY_TOL


def _rebuild(Z: ConstrainedZonotope, binary: NDArray[np.bool_]) -> HybridZonotope:
    """Unpickling helper of :class:`HybridZonotope`."""
    return HybridZonotope.from_relaxation(Z, binary)


def _zonotope_part(G, c, cerr, h, unbounded_radius: float, op: str) -> ConstrainedZonotope:
    """The constrained zonotope without rows that holds a hybrid zonotope's ``G``, ``c``,
    ``c_err`` and ``h`` (its exact operations are the hybrid's on those arrays)."""
    return owned_cz(G, c, np.zeros((0, G.shape[1])), np.zeros(0), h, unbounded_radius,
                    None if cerr is None else _err(cerr), None, op=op)


class _Rows:
    """A hybrid zonotope's constraint rows ``A xi = b`` (``b_err`` their rounding bound),
    ``A`` stored sparse as coordinate triplets (``m x nf``, no zero entries, no repeated
    position), its dense and compressed-column forms built once, when a query asks.

    The set operations only place blocks (a Minkowski sum's or Cartesian product's
    block-diagonal ``A``, an intersection's new rows, a union's copies), so they cost the
    size of the data, not ``m x nf``; sets that share rows (a linear map, a projection)
    share this object and its cached forms."""

    __slots__ = ("_csc", "_dense", "b", "berr", "i", "j", "m", "nf", "v")

    def __init__(self, i, j, v, m: int, nf: int, b, berr, dense=None) -> None:
        self.i, self.j, self.v, self.m, self.nf = i, j, v, m, nf
        self.b = readonly(b)
        self.berr = None if berr is None else readonly(berr)
        self._dense, self._csc = dense, None

    @staticmethod
    def from_dense(A, b, berr) -> _Rows:
        """The rows of a dense ``A`` (kept as the dense form)."""
        i, j = np.nonzero(A)
        return _Rows(i, j, A[i, j], A.shape[0], A.shape[1], b, berr, A)

    @property
    def b_err(self) -> NDArray[np.float64]:
        return self.berr if self.berr is not None else np.zeros(self.m)

    def dense(self) -> NDArray[np.float64]:
        """``A`` as a dense read-only array."""
        if self._dense is None:
            flat = np.bincount(self.i * self.nf + self.j, weights=self.v,
                               minlength=self.m * self.nf)
            self._dense = readonly(flat.reshape(self.m, self.nf))
        return self._dense

    def csc(self):
        """``A`` as a SciPy compressed-column array (sorted indices)."""
        if self._csc is None:
            self._csc = sparse.csc_array((self.v, (self.i, self.j)), shape=(self.m, self.nf))
            self._csc.sort_indices()
        return self._csc

    def block_diag(self, other: _Rows) -> _Rows:
        """``[[A, 0], [0, A_other]]`` with the right-hand sides stacked."""
        return _Rows(np.concatenate([self.i, other.i + self.m]),
                     np.concatenate([self.j, other.j + self.nf]),
                     np.concatenate([self.v, other.v]), self.m + other.m,
                     self.nf + other.nf, np.concatenate([self.b, other.b]),
                     cat_err(self.berr, self.m, other.berr, other.m))

    def stacked(self, A, b, berr) -> _Rows:
        """These rows with the dense rows ``A x = b`` (``b_err`` ``berr``) below."""
        i, j = np.nonzero(A)
        return _Rows(np.concatenate([self.i, i + self.m]), np.concatenate([self.j, j]),
                     np.concatenate([self.v, A[i, j]]), self.m + A.shape[0], self.nf,
                     np.concatenate([self.b, b]),
                     cat_err(self.berr, self.m, berr, A.shape[0]))


class HybridZonotope:
    r"""Hybrid zonotope ``{Gc xc + Gb xb + c : Ac xc + Ab xb = b, |xc| <= h, xb in {-1,1}^nb}``.

    Parameters
    ----------
    Gc : array_like, shape (n, n_c)
        Generators of the continuous factors.
    Gb : array_like, shape (n, n_b)
        Generators of the binary factors.
    c : array_like, shape (n,)
        Centre.
    Ac : array_like, shape (n_con, n_c), optional
        Constraint matrix of the continuous factors (default: no constraints).
    Ab : array_like, shape (n_con, n_b), optional
        Constraint matrix of the binary factors.
    b : array_like, shape (n_con,), optional
        Constraint right-hand side (required with ``Ac`` or ``Ab``).
    h : array_like, shape (n_c,), optional
        Bounds of the continuous factors in ``[0, +inf]`` (default: all ones).
    unbounded_radius : float
        As for :class:`~setobs.ConstrainedZonotope`.

    Raises
    ------
    DimensionError
        On inconsistent shapes.
    InvalidValueError
        On NaN or inf in the data, negative or NaN entries of ``h``.
    ArgumentError
        On constraint matrices without ``b`` (or the reverse).

    Notes
    -----
    Bird, Pangborn, Jain and Hinrichs (2023), "Hybrid zonotopes: a new set representation
    for reachability analysis of mixed logical dynamical systems", Automatica 154,
    Definition 3. The module docstring (:mod:`setobs.geometry.hybrid`) has the
    representation, the certified branch and bound and the union's construction.
    Objects are immutable.

    Examples
    --------
    Two unit squares, centred at ``-2`` and ``+2`` on the first axis:

    >>> import numpy as np
    >>> H = HybridZonotope(np.eye(2), [[2.0], [0.0]], [0.0, 0.0])
    >>> H.contains([0.0, 0.0]), H.contains([2.5, 0.5])
    (False, True)
    >>> bool(abs(H.support([1.0, 0.0]) - 3.0) < 1e-9)
    True
    """

    __slots__ = ("_P", "_R", "_binary", "_cache")
    _P: ConstrainedZonotope
    _R: _Rows
    _binary: NDArray[np.bool_]
    _cache: dict
    __array_ufunc__ = None  # so that ndarray @ H calls H.__rmatmul__

    def __init__(self, Gc: ArrayLike, Gb: ArrayLike, c: ArrayLike, Ac: ArrayLike | None = None,
                 Ab: ArrayLike | None = None, b: ArrayLike | None = None,
                 h: ArrayLike | None = None, *,
                 unbounded_radius: float = UNBOUNDED_RADIUS) -> None:
        c_a = as_vector("c", c)
        n = c_a.size
        Gc_a = np.zeros((n, 0)) if np.size(Gc) == 0 else as_matrix("Gc", Gc, rows=n)
        Gb_a = np.zeros((n, 0)) if np.size(Gb) == 0 else as_matrix("Gb", Gb, rows=n)
        ng, nb = Gc_a.shape[1], Gb_a.shape[1]
        if (Ac is None and Ab is None) != (b is None):
            raise ArgumentError("Ac/Ab and b must be given together (or all omitted)")
        if b is None:
            A = np.zeros((0, ng + nb))
            b_a = np.zeros(0)
        else:
            b_a = as_vector("b", b) if np.size(b) else np.zeros(0)
            m = b_a.size
            Ac_a = (np.zeros((m, ng)) if Ac is None or np.size(Ac) == 0
                    else as_matrix("Ac", Ac, rows=m, cols=ng))
            Ab_a = (np.zeros((m, nb)) if Ab is None or np.size(Ab) == 0
                    else as_matrix("Ab", Ab, rows=m, cols=nb))
            if Ac_a.shape != (m, ng) or Ab_a.shape != (m, nb):
                raise DimensionError(f"Ac must be {m} x {ng} and Ab {m} x {nb} (b has {m} "
                                     f"entries), got {Ac_a.shape} and {Ab_a.shape}")
            A = np.hstack([Ac_a, Ab_a])
        h_a = np.ones(ng) if h is None else as_vector("h", h, size=ng, allow_inf=True)
        if (h_a < 0).any():
            j = int(np.argmax(h_a < 0))
            raise InvalidValueError(f"h must be nonnegative (h[{j}] = {h_a[j]})")
        Z = ConstrainedZonotope(np.hstack([Gc_a, Gb_a]), c_a, A, b_a,
                                np.concatenate([h_a, np.ones(nb)]),
                                unbounded_radius=unbounded_radius)
        self._set(Z, np.concatenate([np.zeros(ng, bool), np.ones(nb, bool)]))

    def _set(self, Z: ConstrainedZonotope, binary: NDArray[np.bool_]) -> None:
        self._put(_zonotope_part(Z.G, Z.c, Z.c_err, Z.h, Z.unbounded_radius, "a hybrid zonotope"),
                  _Rows.from_dense(Z.A, Z.b, _err(Z.b_err)),
                  readonly(np.array(binary, dtype=bool)))
        self._cache["Z"] = Z

    def _put(self, P: ConstrainedZonotope, R: _Rows, binary: NDArray[np.bool_]) -> None:
        object.__setattr__(self, "_P", P)
        object.__setattr__(self, "_R", R)
        object.__setattr__(self, "_binary", binary)
        object.__setattr__(self, "_cache", {})

    @staticmethod
    def _make(P: ConstrainedZonotope, R: _Rows, binary: NDArray[np.bool_]) -> HybridZonotope:
        """The hybrid zonotope of a zonotope part ``P``, rows ``R`` and binary flags (a
        read-only array), the caller's data taken as they are."""
        self = object.__new__(HybridZonotope)
        self._put(P, R, binary)
        return self

    @property
    def _Z(self) -> ConstrainedZonotope:
        """The convex relaxation as a dense constrained zonotope (built once, when asked)."""
        Z = self._cache.get("Z")
        if Z is None:
            P, R = self._P, self._R
            Z = owned_cz(P.G, P.c, R.dense(), R.b, P.h, P.unbounded_radius,
                         _err(P.c_err), R.berr, op="the relaxation of a hybrid zonotope")
            self._cache["Z"] = Z
        return Z

    @classmethod
    def from_relaxation(cls, Z: ConstrainedZonotope, binary: ArrayLike) -> HybridZonotope:
        """The hybrid zonotope whose convex relaxation is ``Z`` with the factors flagged
        in ``binary`` restricted to ``{-1, 1}``.

        Parameters
        ----------
        Z : ConstrainedZonotope
            The relaxation (a binary factor's bound ``h_j`` must be 1).
        binary : array_like of bool, shape (Z.n_gen,)
            Which factors are binary.
        """
        if not isinstance(Z, ConstrainedZonotope):
            raise ArgumentError(f"from_relaxation expects a ConstrainedZonotope, got "
                                f"{type(Z).__name__}")
        mask = np.asarray(binary, dtype=bool).reshape(-1)
        if mask.size != Z.n_gen:
            raise DimensionError(f"binary must have one flag per factor ({Z.n_gen}), got "
                                 f"{mask.size}")
        if (Z.h[mask] != 1.0).any():
            raise InvalidValueError("a binary factor's bound h_j must be 1 (it takes -1 or 1)")
        self = object.__new__(cls)
        self._set(Z, mask)
        return self

    @classmethod
    def from_constrained_zonotope(cls, Z: ConstrainedZonotope) -> HybridZonotope:
        """``Z`` as a hybrid zonotope without binary factors.

        Parameters
        ----------
        Z : ConstrainedZonotope
            The set.
        """
        return cls.from_relaxation(Z, np.zeros(Z.n_gen, bool))

    @classmethod
    def from_union(cls, sets: Sequence[ConstrainedZonotope | HybridZonotope]
                   ) -> HybridZonotope:
        """The union of constrained or hybrid zonotopes, exactly (the disjunctive
        formulation of the module docstring: sharp for constrained zonotopes).

        Parameters
        ----------
        sets : sequence of ConstrainedZonotope or HybridZonotope
            The operands (at least one, of one dimension, every factor bounded).

        Raises
        ------
        ArgumentError
            On an empty sequence, an operand of another type, or an operand with an
            unbounded factor.
        DimensionError
            On operands of different dimensions.
        """
        ops = list(sets)
        if len(ops) > 1 and compiled_ops is not None:
            out = compiled_ops.hybrid_union(ops)
            if out is not None:  # (else the checks below, then the NumPy construction)
                return out
        if not ops:
            raise ArgumentError("from_union needs at least one set")
        for i, S in enumerate(ops):
            if not isinstance(S, HybridZonotope | ConstrainedZonotope):
                raise ArgumentError(f"from_union expects hybrid or constrained zonotopes, "
                                    f"got {type(S).__name__} (operand {i})")
        n = ops[0].dim
        for i, S in enumerate(ops):
            if S.dim != n:
                raise DimensionError(f"union: operand {i} has dimension {S.dim}, operand 0 {n}")
            if np.isinf(S._P.h if isinstance(S, HybridZonotope) else S.h).any():
                raise ArgumentError(f"union: operand {i} has an unbounded factor (h = inf), "
                                    f"which the disjunctive construction cannot switch off")
        if len(ops) == 1:
            return _as_hybrid(ops[0], "from_union")
        return _union(ops)

    @classmethod
    def from_vertices(cls, polytopes: Sequence[ArrayLike]) -> HybridZonotope:
        """The union of polytopes given by their vertices (one array of shape ``(m_i, n)``
        per polytope; :func:`~setobs.geometry.from_vertices` for each).

        Parameters
        ----------
        polytopes : sequence of array_like
            The polytopes' points, one row per point.
        """
        return cls.from_union([cz_from_vertices(V) for V in polytopes])

    def __setattr__(self, name: str, value: object) -> None:
        raise ImmutableError("HybridZonotope is immutable; operations return new objects")

    def __reduce__(self):
        return (_rebuild, (self._Z, np.array(self._binary)))

    # ------------------------------------------------------------------ data
    @property
    def relaxation(self) -> ConstrainedZonotope:
        """The convex relaxation (binary factors in ``[-1, 1]``): a constrained zonotope
        that contains the set (its convex hull, for unions of constrained zonotopes)."""
        return self._Z

    @property
    def binary(self) -> NDArray[np.bool_]:
        """Which of the relaxation's factors are binary, shape ``(n_cont + n_bin,)``."""
        return self._binary

    @property
    def Gc(self) -> NDArray[np.float64]:
        """Continuous generators, shape ``(n, n_cont)``."""
        return readonly(self._P.G[:, ~self._binary])

    @property
    def Gb(self) -> NDArray[np.float64]:
        """Binary generators, shape ``(n, n_bin)``."""
        return readonly(self._P.G[:, self._binary])

    @property
    def Ac(self) -> NDArray[np.float64]:
        """Constraint matrix of the continuous factors, shape ``(n_con, n_cont)``."""
        return readonly(self._R.dense()[:, ~self._binary])

    @property
    def Ab(self) -> NDArray[np.float64]:
        """Constraint matrix of the binary factors, shape ``(n_con, n_bin)``."""
        return readonly(self._R.dense()[:, self._binary])

    @property
    def c(self) -> NDArray[np.float64]:
        """Centre, shape ``(n,)``."""
        return self._P.c

    @property
    def b(self) -> NDArray[np.float64]:
        """Constraint right-hand side, shape ``(n_con,)``."""
        return self._R.b

    @property
    def h(self) -> NDArray[np.float64]:
        """Bounds of the continuous factors, shape ``(n_cont,)``."""
        return readonly(self._P.h[~self._binary])

    @property
    def dim(self) -> int:
        """Dimension ``n`` of the ambient space."""
        return self._P.dim

    @property
    def n_cont(self) -> int:
        """Number of continuous factors."""
        return int(self._binary.size - self._binary.sum())

    @property
    def n_bin(self) -> int:
        """Number of binary factors."""
        return int(self._binary.sum())

    @property
    def n_con(self) -> int:
        """Number of equality constraints."""
        return self._R.m

    def __repr__(self) -> str:
        return (f"HybridZonotope(dim={self.dim}, n_cont={self.n_cont}, n_bin={self.n_bin}, "
                f"n_con={self.n_con})")

    # ------------------------------------------------------------------ exact operations
    def linear_map(self, M: ArrayLike) -> HybridZonotope:
        """Image under ``x -> M x`` (Bird et al. 2023, Proposition 1).

        Parameters
        ----------
        M : array_like, shape (m, n)
            The matrix.
        """
        return HybridZonotope._make(self._P.linear_map(M), self._R, self._binary)

    __rmatmul__ = linear_map

    def __matmul__(self, other: Any) -> HybridZonotope:
        return NotImplemented

    def minkowski_sum(self, other: HybridZonotope | ConstrainedZonotope | ArrayLike
                      ) -> HybridZonotope:
        """Minkowski sum with a hybrid or constrained zonotope or a vector (Bird et al.
        2023, Proposition 2).

        Parameters
        ----------
        other : HybridZonotope, ConstrainedZonotope or array_like, shape (n,)
            The summand.
        """
        if isinstance(other, HybridZonotope | ConstrainedZonotope):
            if compiled_ops is not None:
                out = compiled_ops.hybrid_combine(0, self, other, None)
                if out is not None:
                    return out
            o = _as_hybrid(other, "minkowski_sum")
            return HybridZonotope._make(self._P + o._P, self._R.block_diag(o._R),
                                        self._joined(o))
        return HybridZonotope._make(self._P + as_vector("vector", other, size=self.dim),
                                    self._R, self._binary)

    def _joined(self, o: HybridZonotope) -> NDArray[np.bool_]:
        """The binary flags of the factors of ``self`` then ``o``."""
        return readonly(np.concatenate([self._binary, o._binary]))

    def __add__(self, other: Any) -> HybridZonotope:
        if compiled_ops is not None:  # (minkowski_sum's compiled path, called directly; it
            out = compiled_ops.hybrid_combine(0, self, other, None)  # refuses other types)
            if out is not None:
                return out
        if isinstance(other, HybridZonotope | ConstrainedZonotope):
            return self.minkowski_sum(other)
        if np.ndim(other) == 1:
            return self.minkowski_sum(other)
        return NotImplemented

    __radd__ = __add__

    def intersect(self, other: HybridZonotope | ConstrainedZonotope,
                  R: ArrayLike | None = None) -> HybridZonotope:
        """Generalised intersection ``{z in self : R z in other}`` (Bird et al. 2023,
        Proposition 3; ``R`` defaults to the identity).

        Parameters
        ----------
        other : HybridZonotope or ConstrainedZonotope
            The set ``W``.
        R : array_like, shape (m, n), optional
            The map (default the identity).
        """
        if compiled_ops is not None:
            out = compiled_ops.hybrid_combine(1, self, other, R)
            if out is not None:
                return out
        o = _as_hybrid(other, "intersect")
        J = self._P.intersect(o._P, R)  # (without rows of their own: only the new rows)
        P = _zonotope_part(J.G, J.c, J.c_err, J.h, J.unbounded_radius,
                           "generalised intersection")
        return HybridZonotope._make(P, self._R.block_diag(o._R).stacked(J.A, J.b,
                                                                         _err(J.b_err)),
                                    self._joined(o))

    def __and__(self, other: Any) -> HybridZonotope:
        """``H & W``: :meth:`intersect` (exact)."""
        if isinstance(other, HybridZonotope | ConstrainedZonotope):
            return self.intersect(other)
        return NotImplemented

    __rand__ = __and__

    def cartesian(self, other: HybridZonotope | ConstrainedZonotope) -> HybridZonotope:
        """Cartesian product ``self x other``.

        Parameters
        ----------
        other : HybridZonotope or ConstrainedZonotope
            The second factor.
        """
        o = _as_hybrid(other, "cartesian")
        return HybridZonotope._make(self._P.cartesian(o._P), self._R.block_diag(o._R),
                                    self._joined(o))

    def union(self, *others: HybridZonotope | ConstrainedZonotope) -> HybridZonotope:
        """``self cup others`` (:meth:`from_union`).

        Parameters
        ----------
        *others : HybridZonotope or ConstrainedZonotope
            The other operands.
        """
        return HybridZonotope.from_union([self, *others])

    def __or__(self, other: Any) -> HybridZonotope:
        """``H | W``: :meth:`union` (exact)."""
        if isinstance(other, HybridZonotope | ConstrainedZonotope):
            return self.union(other)
        return NotImplemented

    __ror__ = __or__

    def project(self, dims: Sequence[int] | NDArray[np.integer]) -> HybridZonotope:
        """Projection onto the coordinates ``dims`` (in that order).

        Parameters
        ----------
        dims : sequence of int
            Coordinates kept, in this order.
        """
        return HybridZonotope._make(self._P.project(dims), self._R, self._binary)

    def intersect_halfspace(self, a: ArrayLike, beta: float) -> HybridZonotope:
        """``{z in H : a^T z <= beta}`` (exact).

        As :func:`~setobs.geometry.intersect_halfspace`: the generalised intersection with
        the interval ``[low, beta]`` under ``a^T``, ``low`` a certified lower bound of
        ``a^T z`` on the set, so that the lower end cuts nothing. Here ``low`` is the
        relaxation's zonotope bound ``a^T c - sum_j |a^T G_j| h_j`` (its rounding outward;
        no LP: any valid lower bound gives the same set), and an LP on the relaxation only
        where that bound is infinite (an unbounded factor). The set is returned unchanged
        when the same kind of bound shows it inside the half-space, and the empty set when
        it shows it outside; otherwise the cut adds one factor and one row even where it
        cuts nothing (a tighter test would cost two LPs per cut).

        Parameters
        ----------
        a : array_like, shape (n,)
            Normal.
        beta : float
            Offset.

        Raises
        ------
        UnboundedSetError
            If ``a^T z`` is not bounded below on the relaxation.
        """
        av = as_vector("a", a, size=self.dim)
        if not np.isfinite(beta):
            raise InvalidValueError(f"beta must be finite, got {beta}")
        low, high = _zonotope_range(self._P, av)
        try:
            if not np.isfinite(low):
                low = -support_unwarned(self._Z, -av)
            if not np.isfinite(high) and low <= beta:
                high = support_unwarned(self._Z, av)
        except EmptySetError:
            return self
        if not np.isfinite(low):
            raise UnboundedSetError("a^T z is not bounded below on the set's relaxation: the "
                                    "cut is not representable with bounded slack")
        if high <= beta:
            return self
        if low > beta:
            return HybridZonotope.from_constrained_zonotope(empty_set(self.dim))
        # (the interval [low, beta]: its lower end cuts nothing, a^T z >= low on the set;
        # built as from_box builds it, the bounds being valid already)
        mid, rad = box_center_radius(np.array([low]), np.array([beta]))
        interval = owned_cz(np.ones((1, 1)), mid, np.zeros((0, 1)), np.zeros(0), rad,
                            op="a half-space cut")
        return self.intersect(interval, av[None, :])

    def intersect_polytope(self, H: ArrayLike, k: ArrayLike) -> HybridZonotope:
        """``{z in self : H z <= k}``, one half-space at a time (exact).

        Parameters
        ----------
        H : array_like, shape (m, n)
            Normals, one per row.
        k : array_like, shape (m,)
            Offsets.
        """
        H_a = as_matrix("H", H, cols=self.dim)
        k_a = as_vector("k", k, size=H_a.shape[0])
        out = self
        for row, val in zip(H_a, k_a, strict=True):
            out = out.intersect_halfspace(row, float(val))
        return out

    def remove_redundancy(self, tol: float = ZERO_TOL) -> HybridZonotope:
        """The same set with fewer factors and constraints (nothing approximated).

        Each step is decided by certified LP bounds on the convex relaxation; where a
        bound does not decide, the factor or row stays.

        1. **Fixed binary factors.** For each binary factor in a constraint, certified
           bounds ``[l_j, u_j]`` of it over the relaxation's factor polytope (two LPs).
           ``u_j < 1`` says no point of the relaxation, so none of the set, has
           ``xb_j = 1``: every leaf has ``xb_j = -1``, and the factor is fixed there
           (moved into the centre and the right-hand side, the rounding bounded, as at a
           node of the branch and bound); ``l_j > -1`` likewise. Repeated while a factor
           is fixed (the relaxation shrinks). A set whose relaxation is certified empty,
           or with a factor that can be neither, is empty.
        2. **Implied bounds of continuous factors**, eliminated with a constraint row
           (:func:`~setobs.geometry.reduce_exact`, steps 1-2, on the continuous factors
           only): a bound the relaxation's constraints imply is implied in every leaf
           (a leaf's factor set is the relaxation's with the binaries fixed), and the
           substitution of an eliminated factor is exact for every assignment of the
           binaries. Binary factors are never eliminated. A continuous factor whose
           certified range is a point (to :data:`~setobs.tolerances.PINNED_FACTOR_RTOL`
           of its bound: a fixed binary's copies in a union) is replaced by that point,
           the range's half-width carried outward in ``c_err`` and ``b_err``.
        3. **Unused parts**: factors with zero columns in both ``G`` and ``A`` (binary
           ones too: their value changes nothing), ``h_j = 0``, zero rows.
        4. **Dependent rows** of ``[A | b]`` (:func:`~setobs.geometry.remove_redundancy`,
           relative rank tolerance ``tol``; a row that is a combination of the others
           holds for every assignment of the binaries).

        Parameters
        ----------
        tol : float
            Relative rank tolerance of step 4.

        Returns
        -------
        HybridZonotope
            The same set (up to the rounding of the eliminated matrices, as in every set
            operation; step 4 as :func:`~setobs.geometry.remove_redundancy`), or
            :func:`~setobs.geometry.empty_set` when it is certified empty.

        Notes
        -----
        Cost: two LPs per binary factor in a constraint per round of step 1, two per
        bounded continuous factor in a constraint in step 2. Bird et al. (2023) remove
        redundancy from the structure of a union or of a reachability step; this
        removal needs no structure, only the relaxation's LPs, so it also finds the
        binary factors that a cut or an intersection has fixed (for a reachable set, the
        modes no trajectory can take).
        """
        H = self
        while True:
            Z, binary = H._Z, H._binary
            cand = np.flatnonzero(binary & Z.A.any(axis=0)) if Z.n_con else np.zeros(0, int)
            if not cand.size:
                break
            try:
                fp = factor_polytope(Z)
                cols, vals = [], []
                for j in cand:
                    e = np.zeros(Z.n_gen)
                    e[j] = 1.0
                    lo, hi = fp.minimize(e).bound, -fp.minimize(-e).bound
                    if hi < 1.0 and lo > -1.0:
                        raise EmptySetError("no assignment of a binary factor is feasible")
                    if hi < 1.0 or lo > -1.0:
                        cols.append(j)
                        vals.append(-1.0 if hi < 1.0 else 1.0)
            except EmptySetError:
                return HybridZonotope.from_constrained_zonotope(empty_set(self.dim))
            if not cols:
                break
            c_a = np.array(cols, dtype=np.int64)
            node, _, _ = H._node(c_a, np.array(vals))
            H = HybridZonotope.from_relaxation(node, np.delete(binary, c_a))
        try:
            Z, pos = reduce_exact_among(H._Z, ~H._binary, pin=True)
        except EmptySetError:
            return HybridZonotope.from_constrained_zonotope(empty_set(self.dim))
        binary = H._binary[pos]
        R = cz_remove_redundancy(Z, tol)
        if R.n_gen == Z.n_gen:  # (the factors are all used after step 3: only rows go)
            Z = R
        return HybridZonotope.from_relaxation(Z, binary)

    # ------------------------------------------------------------------ nodes
    def _node(self, cols: NDArray[np.int64], vals: NDArray[np.float64]
              ) -> tuple[ConstrainedZonotope, NDArray[np.int64], NDArray[np.int64]]:
        """The node that fixes the relaxation's factors ``cols`` to ``vals`` (``+-1``), as
        a constrained zonotope, and the free binary factors' positions in it and in the
        relaxation (the same factors, in the same order)."""
        Z = self._Z
        free = self._free_mask(cols)
        free_root = np.flatnonzero(free)
        if cols.size == 0:
            return Z, free_root, free_root
        keep = np.ones(Z.n_gen, bool)
        keep[cols] = False
        c, cerr, b, berr = _fixed(Z, Z.A, Z.b, _err(Z.b_err), cols, vals)
        node = trusted_cz(Z.G[:, keep], c, Z.A[:, keep], b, Z.h[keep], Z.unbounded_radius,
                          cerr, berr, op="fixing binary factors")
        return node, np.flatnonzero(free[keep]), free_root

    def _free_mask(self, cols: NDArray[np.int64]) -> NDArray[np.bool_]:
        """The binary factors (relaxation order) that a node fixing ``cols`` leaves free."""
        free = self._binary.copy()
        free[cols] = False
        return free

    def _leaf_values(self, cols, vals, free_root, xi_free) -> NDArray[np.float64]:
        """The binary factors (relaxation order) of the leaf that fixes ``cols`` to
        ``vals`` and the free ones to the signs of ``xi_free``."""
        out = np.zeros(self._P.n_gen)
        out[cols] = vals
        out[free_root] = np.where(xi_free >= 0.0, 1.0, -1.0)
        return out[self._binary]

    # ------------------------------------------------------------------ certified queries
    def support_bounds(self, direction: ArrayLike, *, node_limit: int = NODE_LIMIT,
                       time_limit: float | None = None, search: str = "best"
                       ) -> BranchAndBoundResult:
        """Certified support value ``max d^T z`` by branch and bound, with its status.

        Parameters
        ----------
        direction : array_like, shape (n,)
            The direction ``d``.
        node_limit : int
            Nodes (LPs) after which the search stops with an outer answer.
        time_limit : float, optional
            Seconds after which the search stops with an outer answer.
        search : {"best", "depth"}
            Best-first (the open node with the largest bound next) or depth-first.

        Raises
        ------
        EmptySetError
            If the set is certified empty.
        """
        d = as_vector("direction", direction, size=self.dim)
        if search not in ("best", "depth"):
            raise ArgumentError(f"search must be 'best' or 'depth', got {search!r}")
        _check_limits(node_limit, time_limit)
        return _maximize(self, d, int(node_limit), time_limit, search)

    def support(self, direction: ArrayLike) -> float:
        """Certified support function ``max_{z in H} d^T z`` (``+inf`` if unbounded);
        :meth:`support_bounds` for the status and the limits.

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
            If the search stopped at its node limit (the value is then a looser outer
            bound).
        """
        out = self.support_bounds(direction)
        if out.status != "optimal":
            warnings.warn(f"the branch and bound stopped ({out.status}); the support value "
                          f"is an outer bound within {out.gap:.3g} of a leaf's value",
                          SolverWarning, stacklevel=2)
        return out.value

    def interval_hull(self, *, node_limit: int = NODE_LIMIT,
                      time_limit: float | None = None) -> Box:
        """Certified interval hull (``2 n`` support searches).

        Parameters
        ----------
        node_limit : int
            Nodes per search after which it stops with an outer answer.
        time_limit : float, optional
            Seconds per search after which it stops with an outer answer.

        Raises
        ------
        EmptySetError
            If the set is certified empty.

        Warns
        -----
        SolverWarning
            If a search stopped early (the box is then a looser outer bound).
        """
        n = self.dim
        lo, hi = np.empty(n), np.empty(n)
        early = []
        for i in range(n):
            e = np.zeros(n)
            e[i] = 1.0
            up = self.support_bounds(e, node_limit=node_limit, time_limit=time_limit)
            dn = self.support_bounds(-e, node_limit=node_limit, time_limit=time_limit)
            hi[i], lo[i] = up.value, -dn.value
            early += [r.gap for r in (up, dn) if r.status != "optimal"]
        if early:
            warnings.warn(f"{len(early)} of {2 * n} searches of the interval hull stopped "
                          f"early; the box is an outer bound (largest gap {max(early):.3g})",
                          SolverWarning, stacklevel=2)
        return Box(lo, hi)

    def emptiness(self, tol: float = FEASIBILITY_TOL, *, node_limit: int = NODE_LIMIT,
                  time_limit: float | None = None) -> HybridEmptiness:
        """Certified emptiness by a depth-first branch and bound (:class:`HybridEmptiness`).

        Parameters
        ----------
        tol : float
            Feasibility tolerance of the phase-1 LPs (normalised constraint violation).
        node_limit : int
            Nodes after which the search stops, undecided.
        time_limit : float, optional
            Seconds after which the search stops, undecided.
        """
        _check_limits(node_limit, time_limit)
        if not (np.isfinite(tol) and tol >= 0.0):
            raise InvalidValueError(f"tol must be a finite nonnegative number, got {tol!r}")
        return _emptiness(self, float(tol), int(node_limit), time_limit)

    def is_empty(self, tol: float = FEASIBILITY_TOL) -> bool:
        """Whether the set is empty (``True`` certified, as for a constrained zonotope).

        Parameters
        ----------
        tol : float
            Feasibility tolerance (normalised constraint violation).

        Warns
        -----
        SolverWarning
            If the search stopped undecided (``False`` is then not certified).
        """
        rep = self.emptiness(tol)
        if rep.status == "undecided":
            warnings.warn("the emptiness search stopped at its node limit, undecided; "
                          "reported non-empty (not certified)", SolverWarning, stacklevel=2)
        return rep.empty

    def contains(self, x: ArrayLike, tol: float = FEASIBILITY_TOL) -> bool:
        """Whether ``x`` is in the set up to ``tol`` (``False`` certified: every leaf
        certified not to contain it).

        Parameters
        ----------
        x : array_like, shape (n,)
            The point.
        tol : float
            Feasibility tolerance (normalised constraint violation).

        Warns
        -----
        SolverWarning
            If the search stopped undecided (``True`` is then not certified).
        """
        xv = as_vector("x", x, size=self.dim)
        rep = self.intersect(ConstrainedZonotope.point(xv)).emptiness(tol)
        if rep.status == "undecided":
            warnings.warn("the containment search stopped at its node limit, undecided; "
                          "reported contained (not certified)", SolverWarning, stacklevel=2)
        return not rep.empty

    def to_constrained_zonotopes(self, tol: float = FEASIBILITY_TOL
                                 ) -> list[ConstrainedZonotope]:
        """The leaves not certified empty, each a constrained zonotope (depth-first, a
        subtree dropped when its relaxation is certified empty; at most ``2^n_bin``).

        Parameters
        ----------
        tol : float
            Feasibility tolerance of the emptiness tests.
        """
        out = []
        stack = [(np.zeros(0, np.int64), np.zeros(0))]
        while stack:
            cols, vals = stack.pop()
            Zn, _, free_root = self._node(cols, vals)
            if Zn.n_con and factor_polytope(Zn).emptiness(tol).empty:
                continue
            if free_root.size == 0:
                out.append(Zn)
                continue
            j = free_root[0]
            for v in (1.0, -1.0):
                stack.append((np.append(cols, j), np.append(vals, v)))
        return out

    def plot(self, ax: Axes | None = None, dims: Sequence[int] = (0, 1), **kwargs: Any
             ) -> list:
        """Plot the projection of every non-empty leaf onto ``dims``
        (:meth:`ConstrainedZonotope.plot`); returns the patches.

        Parameters
        ----------
        ax : matplotlib.axes.Axes, optional
            The axes (default: the current ones).
        dims : sequence of int
            The two coordinates.
        **kwargs
            Passed to each leaf's plot.
        """
        return [Z.plot(ax=ax, dims=dims, **kwargs) for Z in self.to_constrained_zonotopes()]


# ---------------------------------------------------------------------- helpers
def _zonotope_range(Z: ConstrainedZonotope, a: NDArray[np.float64]) -> tuple[float, float]:
    """Certified ``[low, high]`` containing ``a^T z`` on ``Z`` from its zonotope alone
    (``a^T c -+ sum_j |a^T G_j| h_j``, the constraints ignored, every rounding and
    ``c_err`` outward; infinite where an unbounded factor meets ``a``)."""
    n, ng = Z.dim, Z.n_gen
    w = np.abs(Z.G.T @ a)
    with np.errstate(invalid="ignore"):  # (0 * inf: a factor that a does not see)
        terms = np.where(w > 0.0, w * Z.h, 0.0)
    rad = float(terms.sum())
    mid = float(a @ Z.c)
    absa = np.abs(a)
    hfin = np.where(np.isfinite(Z.h), Z.h, 0.0)
    err = gamma(n + 1) * (float(absa @ np.abs(Z.c)) + float((np.abs(Z.G).T @ absa) @ hfin)) \
        + gamma(ng + 1) * rad + float(absa @ Z.c_err) * (1.0 + gamma(n + 1))
    err *= 1.0 + gamma(4)
    if not np.isfinite(rad):
        return -np.inf, np.inf
    return round_down(mid - rad - err), round_up(mid + rad + err)


def _check_limits(node_limit: Any, time_limit: Any) -> None:
    if not (isinstance(node_limit, int | np.integer) and node_limit >= 1):
        raise InvalidValueError(f"node_limit must be a positive integer, got {node_limit!r}")
    if time_limit is not None and not (np.isfinite(time_limit) and time_limit > 0):
        raise InvalidValueError(f"time_limit must be a positive number of seconds or None, "
                                f"got {time_limit!r}")


def _err(e: NDArray[np.float64]) -> NDArray[np.float64] | None:
    return e if np.count_nonzero(e) else None


def _fixed(P: ConstrainedZonotope, A, b, berr, cols: NDArray[np.int64],
           vals: NDArray[np.float64]):
    """``(c, c_err, b, b_err)`` of the set with generators ``P.G``, centre ``P.c`` and rows
    ``A xi = b`` (``A`` dense or SciPy sparse, ``b_err`` ``berr``) with its factors
    ``cols`` fixed to ``vals`` (their columns moved into the centre and the right-hand
    side, the rounding bounded; an error ``None`` is exact): the data of a node of the
    branch and bound."""
    n = P.dim
    Mc = np.hstack([np.eye(n), P.G[:, cols]])
    vc = np.concatenate([P.c, vals])
    cerr = map_err(Mc, vc, cat_err(_err(P.c_err), n, None, cols.size))
    if not b.size:
        return Mc @ vc, cerr, b, None
    Acols = A[:, cols]
    # b - A_cols vals: per row a sum of cols.size + 1 terms (map_err's bound for
    # [I, -A_cols] [b; vals], the identity's one term per row)
    k = cols.size + 1
    bn = b - Acols @ vals
    e = abs(Acols) @ (gamma(k + 1) * np.abs(vals)) + gamma(k + 1) * np.abs(b)
    if berr is not None:
        e += berr
    e *= 1.0 + gamma(k + 2)
    return Mc @ vc, cerr, bn, _err(e)


def _as_hybrid(S: Any, what: str) -> HybridZonotope:
    if isinstance(S, HybridZonotope):
        return S
    if isinstance(S, ConstrainedZonotope):
        return HybridZonotope.from_constrained_zonotope(S)
    raise ArgumentError(f"{what} expects hybrid or constrained zonotopes, got {type(S).__name__}")


def _union(ops: list[HybridZonotope | ConstrainedZonotope]) -> HybridZonotope:
    """The disjunctive construction of the module docstring for two or more operands,
    written for all operands at once (their factors and rows concatenated; operand ``i``'s
    factors ``j`` get the copies ``s1, s2`` (continuous) or ``bt, t`` (binary), its rows
    follow one another: its own rows, one row per continuous factor, one per binary one;
    the last row is ``sum beta_i = 2 - N``)."""
    ops = [_as_hybrid(S, "from_union") for S in ops]
    N = len(ops)
    n = ops[0].dim
    Ps, Rs = [H._P for H in ops], [H._R for H in ops]
    f = np.array([P.n_gen for P in Ps], dtype=np.int64)
    m = np.array([R.m for R in Rs], dtype=np.int64)
    BN = np.concatenate([H._binary for H in ops])
    cont = ~BN
    opid = np.repeat(np.arange(N), f)  # each operand factor's operand
    start = np.concatenate([[0], np.cumsum(f)[:-1]])  # its first factor among them all
    F = N + 2 * start  # its first factor in the union (after the N selectors)
    R0 = np.concatenate([[0], np.cumsum(m + f)[:-1]])  # its first row in the union
    n_fac, n_row = N + 2 * int(f.sum()), 1 + int((m + f).sum())
    nc = np.bincount(opid, weights=cont, minlength=N).astype(np.int64)
    nb = f - nc
    cc, cb = np.cumsum(cont), np.cumsum(BN)
    rank = np.where(BN, cb - 1 - np.concatenate([[0], cb])[start][opid],
                    cc - 1 - np.concatenate([[0], cc])[start][opid])
    pos = np.where(BN, nc[opid] + rank, rank)  # among its operand's (continuous first)
    col1 = F[opid] + pos + np.where(BN, nc[opid], 0)  # s1 or bt
    col2 = col1 + np.where(BN, nb[opid], nc[opid])  # s2 or t
    # the copies' columns: -h_j G_j (continuous, xt = h ((beta_i - 1)/2 - s1)) or G_j
    scale = np.where(BN, 1.0, -np.concatenate([P.h for P in Ps]))
    Gs = np.hstack([P.G for P in Ps]) * scale
    S = np.zeros((n, N))  # per operand: G_B 1 - P 1 (P = G_C diag(h_C))
    has = f > 0
    if has.any():
        S[:, has] = np.add.reduceat(Gs, start[has], axis=1)
    Cm = np.column_stack([P.c for P in Ps])
    G = np.zeros((n, n_fac))
    G[:, col1] = Gs
    G[:, :N] = 0.5 * (Cm - S)  # the point: ... + ((c - G_B 1 + P 1)/2) beta_i
    # c = sum_i (c_i + G_B 1 - P 1)/2, one sum of N + sum f_i terms
    c = 0.5 * (Cm.sum(axis=1) + Gs.sum(axis=1))
    k = N + int(f.sum())
    cerr = gamma(k + 1) * (0.5 * (np.abs(Cm).sum(axis=1) + np.abs(Gs).sum(axis=1))) \
        * (1.0 + gamma(k + 2))
    # The operands' rounding bounds: the selected operand's centre error is at most the
    # largest of theirs (one selector is 1), and operand i's rows carry b_err_i scaled by
    # lam_i in [0, 1], so at most b_err_i.
    cerr_ops = np.max([P.c_err for P in Ps], axis=0)
    if cerr_ops.any():
        cerr = (cerr + cerr_ops) * (1.0 + gamma(3))
    # the operands' rows: their scaled entries, then
    #   ((Q 1 - A_B 1 - b)/2) beta_i = (b - A_B 1 + Q 1)/2   (Q = A_C diag(h_C))
    nnz = np.array([R.v.size for R in Rs], dtype=np.int64)
    eop = np.repeat(np.arange(N), nnz)
    jg = np.concatenate([R.j for R in Rs]) + start[eop]
    ri = np.concatenate([R.i for R in Rs]) + R0[eop]
    rv = np.concatenate([R.v for R in Rs]) * scale[jg]
    rowop = np.repeat(np.arange(N), m)
    orow = R0[rowop] + (np.arange(int(m.sum())) - np.concatenate([[0], np.cumsum(m)[:-1]])[rowop])
    rowsum = np.bincount(ri, weights=rv, minlength=n_row)[orow]
    absrow = np.bincount(ri, weights=np.abs(rv), minlength=n_row)[orow]
    b_all = np.concatenate([R.b for R in Rs])
    b = np.full(n_row, -1.0)  # (the rows |xt_j| <= h_j lam_i and (1 + bt_j)/2 <= lam_i)
    b[-1] = 2.0 - N  # sum beta_i = 2 - N
    b[orow] = 0.5 * (b_all - rowsum)
    kr = 1 + f[rowop]  # (terms per row: b_i and the operand's entries)
    berr = np.zeros(n_row)
    berr[orow] = gamma(kr + 1) * (0.5 * (np.abs(b_all) + absrow)) * (1.0 + gamma(kr + 2))
    for i, R in enumerate(Rs):
        if R.berr is not None:
            berr[R0[i]:R0[i] + R.m] += R.berr * (1.0 + gamma(3))
    # the copies' rows: s1 + s2 - beta_i = -1 (continuous), bt - beta_i + t = -1 (binary)
    crow = R0[opid] + m[opid] + pos
    ones = np.ones(col1.size)
    i_all = np.concatenate([ri, orow, crow, crow, crow, np.full(N, n_row - 1)])
    j_all = np.concatenate([col1[jg], rowop, col1, col2, opid, np.arange(N)])
    v_all = np.concatenate([rv, -0.5 * (rowsum + b_all), ones, ones, -ones, np.ones(N)])
    keep = v_all != 0.0
    if not keep.all():
        i_all, j_all, v_all = i_all[keep], j_all[keep], v_all[keep]
    h = np.ones(n_fac)
    binary = np.zeros(n_fac, bool)
    binary[:N] = True  # the selectors beta_i
    binary[col1[BN]] = True  # the copies of the binary factors
    rows = _Rows(i_all, j_all, v_all, n_row, n_fac, b, _err(berr))
    check_set_data("union", G, c, v_all, b, h, cerr, rows.berr, compiled_ops)
    Pu = _zonotope_part(G, c, cerr, h, min(Pi.unbounded_radius for Pi in Ps), "union")
    return HybridZonotope._make(Pu, rows, readonly(binary))


def _integral(xi: NDArray[np.float64]) -> bool:
    return bool((np.abs(np.abs(xi) - 1.0) <= BINARY_TOL).all())


def _branch_factor(xi_free, free_root) -> tuple[int, float]:
    """The free binary factor to branch on, the most fractional in the LP's point (the
    first free one without a point), and the value its point is nearer to (``+1`` without
    a point)."""
    if xi_free is None or xi_free.size == 0:
        return int(free_root[0]), 1.0
    t = int(np.argmin(np.abs(xi_free)))
    return int(free_root[t]), 1.0 if xi_free[t] >= 0.0 else -1.0


class _NodeLP:
    """The support LPs of a search's nodes in direction ``d``, on one warm model.

    A node that fixes the binary factors ``cols`` to ``vals`` is the relaxation's factor
    set with those factors' bounds set to zero and their columns moved into the centre
    and the right-hand side (``c + G_cols vals``, ``b - A_cols vals``, the rounding
    bounded by :func:`~setobs.geometry._bounds.map_err`, as :meth:`HybridZonotope._node`
    does): the constraint matrix and the objective stay the same at every node, only
    ``b`` and the bounds change. So one model serves the whole search: the compiled dual
    simplex of :class:`~setobs.lp.fastlp.FixedStructureLP` (up to
    :data:`NODE_COMPILED_MAX_ROWS` rows; a basis that was optimal stays dual feasible for
    any ``b`` and bounds, so a node costs a few pivots from the last one), or above that
    one HiGHS model whose column and row bounds change, started from the parent's basis.

    Each bound is certified like the core's (the one certificate over the node's data,
    with the rounding of ``G^T d`` and of the node's ``b`` covered); a node the model
    does not decide (not optimal, a loose certificate) returns ``None``, and the search
    evaluates it on its own constrained zonotope through the core's retry ladder. A node
    the compiled model finds infeasible is certified empty by the compiled phase-1 test
    of :meth:`~setobs.lp.factor.FactorPolytope.emptiness` (the same verdict at the same
    tolerance); one it leaves open goes to the HiGHS model (built then), and only then to
    the ladder."""

    def __init__(self, H: HybridZonotope, d: NDArray[np.float64], tol: float) -> None:
        # (Z: the zonotope part, G, c, c_err and h; rows: A xi = b, dense or sparse)
        Z, R = H._P, H._R
        self.Z, self.rows, self.tol = Z, R, tol
        n, m = Z.dim, R.m
        self.bins = np.flatnonzero(H._binary)
        self.w = np.ascontiguousarray(-(Z.G.T @ d))
        self.w_err = 2.0 * gamma(n + 1) * (np.abs(Z.G).T @ np.abs(d))
        self.d, self.absd = d, np.abs(d)
        self.compiled = m <= NODE_COMPILED_MAX_ROWS
        if self.compiled:
            self.A = np.ascontiguousarray(R.dense())
            # (the structure of the rows, built once per set; each search's objective on it)
            base = H._cache.get("nodes")
            if base is None:
                base = H._cache["nodes"] = FixedStructureLP.bounded(self.A, self.w[None, :])
                self.lp = base
            else:
                self.lp = base.with_objectives(self.w[None, :])
            self.state = self.lp.new_state()
            self.ok = self.lp.usable
            self.hext = np.concatenate([Z.h, np.zeros(m)])
            self.hs = None  # (HiGHS's model, built at the first node the simplex leaves open)
        else:
            self.ok = self._build_highs()

    def _build_highs(self) -> bool:
        """The HiGHS model of the nodes (the relaxation's data; bounds change per node)."""
        Z, R = self.Z, self.rows
        self.As = R.csc()
        self.hs = highs.new_model()
        self.scale = FactorPolytope.objective_scale(self.w)
        self.csc = (self.As.indptr.astype(np.int64), self.As.indices.astype(np.int64),
                    self.As.data)
        return highs.pass_csc(self.hs, R.m, self.w / self.scale, -Z.h, Z.h, R.b, R.b,
                              self.As.indptr, self.As.indices, self.As.data)

    def _data(self, cols, vals):
        """The node's ``c``, ``c_err``, ``b``, ``b_err`` and bounds ``h``."""
        Z, R = self.Z, self.rows
        if cols.size == 0:
            return Z.c, Z.c_err, R.b, R.b_err, Z.h
        c, cerr, b, berr = _fixed(Z, self.A if self.compiled else self.As, R.b, R.berr,
                                  cols, vals)
        h = Z.h.copy()
        h[cols] = 0.0
        return (c, np.zeros(Z.dim) if cerr is None else cerr, b,
                np.zeros(R.m) if berr is None else berr, h)

    def node_centre(self, cols, vals) -> NDArray[np.float64]:
        """The node's centre ``c + G_cols vals``."""
        return self.Z.c + self.Z.G[:, cols] @ vals if cols.size else self.Z.c

    def _value(self, bound: float, h, c, cerr) -> float:
        """The certified support value from a certified ``min w^T xi`` over the node (``w``
        exact): the rounding of ``w`` (``w_err^T h``) and of ``d^T c`` added outward."""
        n = self.Z.dim
        werr = float(self.w_err @ h) * (1.0 + gamma(h.size + 1))
        dc = float(self.d @ c)
        err = 2.0 * gamma(n + 1) * float(self.absd @ np.abs(c)) + \
            float(self.absd @ cerr) * (1.0 + gamma(n + 1))
        s1 = -bound + werr
        sv = s1 + dc  # (two roundings, each at most u times its result)
        return round_up(sv + err + 2.0 * UNIT_ROUNDOFF * (abs(s1) + abs(sv)))

    def solve(self, cols: NDArray[np.int64], vals: NDArray[np.float64], basis: Any):
        """``(value, xi, x, basis)``: the node's certified support value, its LP point
        (relaxation order, the fixed factors at zero), that point in the set's space and
        the basis for its children; ``"empty"`` when certified
        empty; ``None`` when not decided here."""
        c, cerr, b, berr, h = self._data(cols, vals)
        if not self.compiled:
            return self._solve_highs(c, cerr, b, berr, h, basis)
        got = self._solve_compiled(c, cerr, b, berr, h)
        if got is not None:
            return got
        # (a node the compiled simplex leaves open, typically a thin one that it calls
        # infeasible and the phase-1 test finds feasible: HiGHS's model, from its last basis)
        if self.hs is None and not self._build_highs():
            return None
        return self._solve_highs(c, cerr, b, berr, h, None)

    def _solve_compiled(self, c, cerr, b, berr, h):
        bounds, ok = self._minimize(b, h, berr)
        if not ok[0]:
            verdict = self._unsolved(b, berr, h)
            return "empty" if verdict is not None and verdict[0] else None
        xi = self._point(b)
        return self._value(float(bounds[0]), h, c, cerr), xi, self.Z.G @ xi + c, None

    def _minimize(self, b, h, berr):
        """The warm state's certified ``min w^T xi`` over the node (the unchecked entry of
        :class:`~setobs.lp.fastlp.FixedStructureLP`: the node's data are float arrays of the
        structure's shapes with no unbounded factor, by construction)."""
        return self.lp.minimize_all_unchecked(np.ascontiguousarray(b), self._hext(h),
                                              self.state, b_err=berr)

    def _hext(self, h):
        self.hext[:h.size] = h
        return self.hext

    def _basic(self, b):
        """The compiled state's final basic solution in the working copy ``R A S`` (``x_N``
        at its bounds, then ``x_B = B^-1 (R b - N x_N)``), the working bounds and the
        basis: ``(x, h / S, basis)``."""
        lp, st = self.lp, self.state
        hB = self.hext / lp.S_B
        xw = np.where(st.upper[0], hB, -hB)
        basis = st.bases[0]
        xw[basis] = 0.0
        xw[basis] = st.binv[0].T @ (lp.R * b - lp.Ared @ xw)
        return xw, hB, basis

    def _point(self, b) -> NDArray[np.float64]:
        """The point of the compiled state's final basis (the fixed factors at zero)."""
        return (self.lp.S_B * self._basic(b)[0])[:self.Z.n_gen]

    def _rows(self, b, h):
        """The node's rows (fixed columns zero) scaled as the phase-1 test scales them:
        by the smallest power of two at least ``max(max_j |A_ij|, |b_i|)``."""
        A = self._live(h)
        return A, row_scale(A, b, None)

    def _live(self, h):
        """The constraint matrix with the node's fixed columns (``h_j = 0``) zero."""
        return np.where(h > 0.0, self.A, 0.0) if (h == 0.0).any() else self.A

    def _farkas(self, b, berr, h) -> bool:
        """Whether the basis at which the dual simplex stopped infeasible certifies the node
        empty at ``tol``, in the phase-1 test's sense: for the primal-infeasible basic
        variables, the rows ``y`` of the basis inverse (only candidates, the best two by
        their uncertified bound) are certified on the scaled rows by the Lagrangian bound
        of the zero objective (:func:`setobs.lp.certificate.lagrangian_lower_bound`,
        ``b_err`` covered), and the node is empty when that bound over ``||y||_1``
        exceeds ``tol``, the smallest infinity-norm violation of its scaled rows being at
        least that. (It decides about 60 % of the infeasible nodes of the two-mode
        reachable set at horizon 12, each saving a phase-1 LP of about a millisecond:
        the hull 10 % faster, development runs.)"""
        lp, st = self.lp, self.state
        xw, hB, basis = self._basic(b)
        xB, hb = xw[basis], hB[basis]
        rows = np.flatnonzero(np.maximum(xB - hb, -hb - xB) > 0.0)
        if not rows.size:
            return False
        A, scale = self._rows(b, h)
        m = A.shape[0]
        As, bs, be = A / scale[:, None], b / scale, berr / scale
        # the candidates (rows of the basis inverse on the original rows, scaled, signed so
        # that y^T b is positive), ranked by their uncertified Lagrangian bound per ||y||_1
        Y = (lp.R[:, None] * st.binv[0][:, rows]) * scale[:, None]
        Y *= np.where(bs @ Y >= 0.0, 1.0, -1.0)
        est = (bs @ Y - h @ np.abs(As.T @ Y) - be @ np.abs(Y)) / np.abs(Y).sum(axis=0)
        for t in np.argsort(-est)[:2]:
            if not est[t] > self.tol:
                break
            lower, y2 = _certificate.lagrangian_lower_bound(
                np.zeros(A.shape[1]), As, bs, h, Y[:, t],
                unbounded_radius=self.Z.unbounded_radius, b_err=be)
            norm1 = float(np.abs(y2).sum()) * (1.0 + 2.0 * gamma(m + 1))
            if norm1 > 0.0 and np.isfinite(lower) and round_down(lower / norm1) > self.tol:
                return True
        return False

    def _phase1(self, b, berr, h):
        """The compiled phase-1 test of :meth:`~setobs.lp.factor.FactorPolytope.emptiness`
        on the node (its fixed columns zero, as in the node's own constrained zonotope):
        ``(True, None)`` certified empty at ``tol``, ``(False, xi)`` a point within it,
        ``None`` undecided."""
        A = self._live(h)
        m, n = A.shape
        code, lower_inf, found, xi = _simplex.emptiness(
            np.ascontiguousarray(A), b, h, berr, self.Z.unbounded_radius, 50 * (m + n))
        if code != _simplex.OPTIMAL:
            return None
        if lower_inf > self.tol:
            return True, None
        return (False, xi) if found <= self.tol else None

    def feasibility(self, cols: NDArray[np.int64], vals: NDArray[np.float64]):
        """A node's emptiness at ``tol``, as the node's constrained zonotope's
        :meth:`~setobs.lp.factor.FactorPolytope.emptiness` decides it: ``(True, None)``
        certified empty, ``(False, xi)`` with a point within ``tol`` of its rows (the warm
        dual simplex's basic point when that is within ``tol``, else the phase-1 test's),
        ``None`` undecided (compiled engine only)."""
        _, _, b, berr, h = self._data(cols, vals)
        _, ok = self._minimize(b, h, berr)
        if ok[0]:
            xi = np.clip(self._point(b), -h, h)
            A, scale = self._rows(b, h)
            if float((np.abs(A @ xi - b) / scale).max(initial=0.0)) <= self.tol:
                return False, xi
        return self._unsolved(b, berr, h)

    def _unsolved(self, b, berr, h):
        """The emptiness verdict of a node the warm simplex did not solve (as
        :meth:`_phase1`'s): the Farkas certificate of its last basis where it stopped
        infeasible, else the phase-1 test."""
        if self.state.codes[0] == _simplex.INFEASIBLE and self._farkas(b, berr, h):
            return True, None
        return self._phase1(b, berr, h)

    def _solve_highs(self, c, cerr, b, berr, h, basis):
        hs = self.hs
        bins = self.bins
        hs.changeColsBounds(bins.size, bins.astype(np.int32), -h[bins], h[bins])
        m = self.rows.m
        hs.changeRowsBounds(m, np.arange(m, dtype=np.int32), b, b)
        if basis is not None and not highs.set_basis(hs, basis):
            return None
        if highs.solve(hs) != "optimal":
            return None
        obj = float(hs.getInfo().objective_function_value) * self.scale
        y = np.asarray(hs.getSolution().row_dual, dtype=np.float64) * self.scale
        bound = self._certify(b, berr, h, y)
        tol = RELAXED_EXACT_GAP * (1.0 + abs(obj))
        if not (np.isfinite(bound) and obj - bound <= tol):
            y2 = highs.basis_duals(hs, self.As, self.w)
            if y2 is not None:
                bound = max(bound, self._certify(b, berr, h, y2))
            if not (np.isfinite(bound) and obj - bound <= tol):
                return None
        xi = np.asarray(hs.getSolution().col_value, dtype=np.float64)
        return self._value(bound, h, c, cerr), xi, self.Z.G @ xi + c, hs.getBasis()

    def _certify(self, b, berr, h, y) -> float:
        return _certificate.certified_lower_bound(self.w, self.As, b, -h, h, y, b_err=berr,
                                                  csc=self.csc)[0]


def _evaluate(H: HybridZonotope, cols, vals, d):
    """A node's certified support value, its LP maximiser (``None`` if none), the free
    binary factors (relaxation order and node order); ``None`` if certified empty."""
    Zn, free, free_root = H._node(cols, vals)
    try:
        s, x, xi = support_point_factors(Zn, d)
    except EmptySetError:
        return None
    except UnboundedSetError:
        return np.inf, None, None, free_root, free
    except SolverError:
        try:
            s = support_unwarned(Zn, d)
        except EmptySetError:
            return None
        return s, None, None, free_root, free
    return s, x, xi, free_root, free


def _maximize(H: HybridZonotope, d, node_limit: int, time_limit, search: str
              ) -> BranchAndBoundResult:
    t0 = time.perf_counter()
    best = -np.inf  # the largest certified bound of a closed node
    attained, leaf = -np.inf, None
    nodes = 0
    open_: list = []  # (-bound, count, cols, vals, xi_free, free_root, basis): heap/stack
    count = 0

    lp = (_NodeLP(H, d, FEASIBILITY_TOL) if H.n_con and not H._P.has_unbounded_factors
          else None)

    def visit(cols, vals, basis) -> None:
        nonlocal best, attained, leaf, nodes, count
        nodes += 1
        got = lp.solve(cols, vals, basis) if lp is not None and lp.ok else None
        if isinstance(got, str):  # (certified empty)
            return
        if got is not None:
            s, xi, x, basis = got
            free_root = np.flatnonzero(H._free_mask(cols))
            xi_free = xi[free_root]
        else:
            ev = _evaluate(H, cols, vals, d)
            if ev is None:
                return
            s, x, xi, free_root, free = ev
            xi_free = None if xi is None else xi[free]
            basis = None
        if free_root.size == 0 or (xi_free is not None and _integral(xi_free)):
            best = max(best, s)
            if x is not None and float(d @ x) > attained:
                attained = float(d @ x)
                leaf = H._leaf_values(cols, vals, free_root,
                                      xi_free if xi_free is not None else np.zeros(0))
            return
        if s <= best:
            return
        count += 1
        item = (-s, count, cols, vals, xi_free, free_root, basis)
        if search == "best":
            heapq.heappush(open_, item)
        else:
            open_.append(item)

    visit(np.zeros(0, np.int64), np.zeros(0), None)
    status = "optimal"
    while open_:
        item = heapq.heappop(open_) if search == "best" else open_.pop()
        neg, _, cols, vals, xi_free, free_root, basis = item
        if -neg <= best:
            if search == "best":
                open_.clear()
                break
            continue
        if nodes >= node_limit or (time_limit is not None
                                   and time.perf_counter() - t0 > time_limit):
            open_.append(item)  # (still open; the order no longer matters)
            status = "node_limit" if nodes >= node_limit else "time_limit"
            break
        j, near = _branch_factor(xi_free, free_root)
        for v in (-near, near):  # (depth-first: the nearer child is on top)
            visit(np.append(cols, j), np.append(vals, v), basis)
    left = [-item[0] for item in open_ if -item[0] > best]
    value = max([best, *left])
    if value == -np.inf:
        raise EmptySetError("the hybrid zonotope is empty (every node certified empty)")
    gap = value - attained if np.isfinite(attained) else np.inf
    return BranchAndBoundResult(value=float(value), attained=float(attained), gap=float(gap),
                                status=status, nodes=nodes, open_nodes=len(left),
                                binaries=leaf)


def _emptiness(H: HybridZonotope, tol: float, node_limit: int, time_limit
               ) -> HybridEmptiness:
    t0 = time.perf_counter()
    Z = H._P  # (G and c)
    lp = None
    if H.n_con and not Z.has_unbounded_factors and H.n_con <= NODE_COMPILED_MAX_ROWS:
        lp = _NodeLP(H, np.zeros(Z.dim), tol)
        if not lp.ok:
            lp = None

    def verdict(cols, vals):
        """``(empty, x, xi_free, free_root)``: the node certified empty, or a point of it
        within ``tol`` and its free binaries' values there (``None`` without a point)."""
        got = lp.feasibility(cols, vals) if lp is not None else None
        if got is not None:
            free_root = np.flatnonzero(H._free_mask(cols))
            empty, xi = got
            if empty:
                return True, None, None, free_root
            return False, Z.G @ xi + lp.node_centre(cols, vals), xi[free_root], free_root
        Zn, free, free_root = H._node(cols, vals)
        if Zn.n_con == 0:
            xi = np.zeros(Zn.n_gen)
            xi[free] = 1.0
            return False, Zn.G @ xi + Zn.c, xi[free], free_root
        rep = factor_polytope(Zn).emptiness(tol)
        if rep.empty:
            return True, None, None, free_root
        xi = rep.witness
        if xi is None:
            return False, None, None, free_root
        return False, Zn.G @ xi + Zn.c, xi[free], free_root

    stack = [(np.zeros(0, np.int64), np.zeros(0))]
    nodes = 0
    while stack:
        if nodes >= node_limit or (time_limit is not None
                                   and time.perf_counter() - t0 > time_limit):
            return HybridEmptiness(False, "undecided", None, None, nodes, tol)
        cols, vals = stack.pop()
        nodes += 1
        empty, x, xi_free, free_root = verdict(cols, vals)
        if empty:
            continue
        if free_root.size == 0:
            return HybridEmptiness(False, "nonempty", x,
                                   H._leaf_values(cols, vals, free_root, np.zeros(0)),
                                   nodes, tol)
        if xi_free is not None and _integral(xi_free):
            # the point is a leaf's: try that leaf directly
            signs = np.where(xi_free >= 0.0, 1.0, -1.0)
            nodes += 1
            lcols, lvals = np.concatenate([cols, free_root]), np.concatenate([vals, signs])
            lempty, lx, _, _ = verdict(lcols, lvals)
            if not lempty:
                return HybridEmptiness(False, "nonempty", lx,
                                       H._leaf_values(cols, vals, free_root, signs), nodes, tol)
        j, near = _branch_factor(xi_free, free_root)
        for v in (-near, near):  # the nearer child on top
            stack.append((np.append(cols, j), np.append(vals, v)))
    return HybridEmptiness(True, "empty", None, None, nodes, tol)


# ---------------------------------------------------------------------- use
def pwa_reachable_sets(modes: Sequence[tuple[ConstrainedZonotope, ArrayLike, ArrayLike]],
                       initial_set: ConstrainedZonotope | HybridZonotope, steps: int, *,
                       disturbance: ConstrainedZonotope | None = None
                       ) -> list[HybridZonotope]:
    """The exact reachable sets of a piecewise-affine system, each one hybrid zonotope.

    The system is ``x+ = A_i x + f_i (+ w)`` for ``x`` in the region ``P_i`` of mode
    ``i`` (``w`` in ``disturbance`` if given). The graph of the map,
    ``Psi = union_i {(x, A_i x + f_i) : x in P_i}``, is one hybrid zonotope
    (:meth:`HybridZonotope.from_union`), and each step is
    ``X_(k+1) = [0 I] (Psi cap_([I 0]) X_k) (+ W)`` (Bird et al. 2023, Sec. 5: the
    state-update set), so a step adds ``Psi``'s factors once: the size grows linearly
    with the horizon, where the list of one set per mode sequence grows as ``N^k``.

    Parameters
    ----------
    modes : sequence of (ConstrainedZonotope, array_like, array_like)
        Per mode its region ``P_i`` (bounded), ``A_i`` of shape ``(n, n)`` and ``f_i`` of
        shape ``(n,)``.
    initial_set : ConstrainedZonotope or HybridZonotope
        ``X_0``.
    steps : int
        The horizon ``K`` (``>= 0``).
    disturbance : ConstrainedZonotope, optional
        The set of ``w``.

    Returns
    -------
    list of HybridZonotope
        ``[X_0, X_1, ..., X_K]``.

    Notes
    -----
    The regions are closed: a state on a boundary shared by two regions has both modes'
    successors (the union's semantics), a superset of any single-valued choice there.
    Points outside every region have no successor.
    """
    X = _as_hybrid(initial_set, "pwa_reachable_sets")
    n = X.dim
    if not modes:
        raise ArgumentError("pwa_reachable_sets needs at least one mode")
    if not (isinstance(steps, int | np.integer) and steps >= 0):
        raise InvalidValueError(f"steps must be a nonnegative integer, got {steps!r}")
    graphs = []
    for i, mode in enumerate(modes):
        if len(mode) != 3:
            raise ArgumentError(f"mode {i} must be (region, A, f), got {len(mode)} items")
        P, Ai, fi = mode
        if not isinstance(P, ConstrainedZonotope):
            raise ArgumentError(f"mode {i}: the region must be a ConstrainedZonotope, got "
                                f"{type(P).__name__}")
        if P.dim != n:
            raise DimensionError(f"mode {i}: the region has dimension {P.dim}, the state {n}")
        A_a = as_matrix(f"A of mode {i}", Ai, rows=n, cols=n)
        f_a = as_vector(f"f of mode {i}", fi, size=n)
        graphs.append(P.linear_map(np.vstack([np.eye(n), A_a]))
                      + np.concatenate([np.zeros(n), f_a]))
    if disturbance is not None and not isinstance(disturbance, ConstrainedZonotope):
        raise ArgumentError("disturbance must be a ConstrainedZonotope")
    Psi = HybridZonotope.from_union(graphs)
    R = np.hstack([np.eye(n), np.zeros((n, n))])
    out = [X]
    for _ in range(int(steps)):
        X = Psi.intersect(X, R).project(np.arange(n, 2 * n))
        if disturbance is not None:
            X = X + disturbance
        out.append(X)
    return out


if compiled_ops is not None:  # (the compiled union, sum and intersection build these classes)
    try:
        compiled_ops.bind_hybrid(HybridZonotope, _Rows)
    except TypeError as exc:  # pragma: no cover - a stale build
        warnings.warn(f"compiled hybrid set operations disabled: {exc}", RuntimeWarning,
                      stacklevel=1)
        compiled_ops = None
