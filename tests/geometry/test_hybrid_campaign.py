"""A randomized soundness campaign for hybrid zonotopes: run with ``pytest -m slow``.

Random chains of operations (union, linear map, Minkowski sum, generalised intersection,
Cartesian product and projection, half-space cut, redundancy removal) on random
constrained and hybrid zonotopes, with points sampled from the operands carried through
each operation by the operation's own definition (the image, the sum, the pair; a cut
keeps the points it keeps). At the end every carried point must be in the set
(``contains``), below every certified support value (finished or stopped at a node
limit) and inside the certified interval hull: the set operations lose no point and the
queries' bounds are outer.
"""

from __future__ import annotations

import numpy as np
import pytest

import setobs as so
from setobs.geometry import HybridZonotope

CZ = so.ConstrainedZonotope


def operand(rng, n):
    """A random hybrid zonotope (a union of 2-3 constrained zonotopes) and its points."""
    ops = []
    for _ in range(int(rng.integers(2, 4))):
        ng = int(rng.integers(n, n + 3))
        G = rng.normal(size=(n, ng)) * 10.0 ** rng.uniform(-1, 1)
        A = rng.normal(size=(1, ng))
        ops.append(CZ(G, 3.0 * rng.normal(size=n), A, A @ rng.uniform(-0.5, 0.5, ng)))
    pts = np.vstack([Z.sample(4, rng=rng) for Z in ops])
    return HybridZonotope.from_union(ops), pts


def chain(rng):
    n = int(rng.integers(1, 4))
    H, P = operand(rng, n)
    for _ in range(int(rng.integers(2, 5))):
        op = rng.choice(["union", "map", "sum", "intersect", "product", "cut", "reduce"])
        if op == "union":
            H2, P2 = operand(rng, H.dim)
            H, P = H | H2, np.vstack([P, P2])
        elif op == "map":
            M = rng.normal(size=(int(rng.integers(1, 4)), H.dim))
            H, P = M @ H, P @ M.T
        elif op == "sum":
            H2, P2 = operand(rng, H.dim)
            H, P = H + H2, P + P2[rng.integers(len(P2), size=len(P))]
        elif op == "intersect":
            # with a box around half of the points: the points inside it are kept
            lo, hi = P.min(axis=0), P.max(axis=0)
            mid = 0.5 * (lo + hi)
            B = CZ.from_box(lo - 0.1, mid + 0.1)
            keep = np.all(P <= mid + 0.1 - 1e-9, axis=1)
            if keep.sum() < 2:
                continue
            H, P = H & B, P[keep]
        elif op == "product":
            H2, P2 = operand(rng, 1)
            H = H.cartesian(H2)
            P = np.hstack([P, P2[rng.integers(len(P2), size=len(P))]])
            H, P = H.project(np.arange(H.dim)[::-1]), P[:, ::-1]
        elif op == "reduce":
            H = H.remove_redundancy()
        else:
            a = rng.normal(size=H.dim)
            beta = float(np.median(P @ a))
            keep = P @ a <= beta - 1e-9
            if keep.sum() < 2:
                continue
            H, P = H.intersect_halfspace(a, beta), P[keep]
    return H, P


@pytest.mark.slow
@pytest.mark.parametrize("seed", range(40))
def test_random_chains_keep_their_points_and_bound_them(seed):
    rng = np.random.default_rng(seed)
    H, P = chain(rng)
    scale = 1.0 + np.abs(P).max()
    for x in P:
        assert H.contains(x, tol=1e-7), seed
    for _ in range(3):
        d = rng.normal(size=H.dim)
        top = float((P @ d).max())
        full = H.support_bounds(d)
        assert full.value >= top - 1e-9 * scale
        early = H.support_bounds(d, node_limit=2, search="depth")
        assert early.value >= full.value - 1e-9 * scale
    box = H.interval_hull()
    assert np.all(P >= box.lo - 1e-9 * scale) and np.all(P <= box.hi + 1e-9 * scale)
