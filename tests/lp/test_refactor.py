"""The compiled simplex's refactorisation (by blocks: singleton columns, then a dense
nucleus) against numpy's inverse of the whole basis."""

from __future__ import annotations

import numpy as np
import pytest

from setobs.lp import _simplex


def _basis(rng, m, singletons, density=0.3):
    """A random ``m x m`` basis (as ``A`` and ``basis``) with ``singletons`` columns that
    have one nonzero each (in distinct random rows), the rest random sparse columns, in
    shuffled positions and with extra nonbasic columns in ``A``."""
    rows = rng.permutation(m)[:singletons]
    cols = []
    for r in rows:
        c = np.zeros(m)
        c[r] = rng.choice([-1.0, 1.0]) * rng.uniform(0.2, 5.0)
        cols.append(c)
    while len(cols) < m:
        c = rng.normal(size=m) * (rng.random(m) < max(density, 2.5 / m))
        if np.count_nonzero(c) >= 2:
            cols.append(c)
    B = np.column_stack(cols)[:, rng.permutation(m)]
    extra = rng.normal(size=(m, 5))
    A = np.hstack([extra[:, :2], B, extra[:, 2:]])
    perm = rng.permutation(A.shape[1])
    A = A[:, perm]
    where = np.argsort(perm)  # column j of the old A is column where[j] of the new
    basis = where[2 + np.arange(m)].astype(np.int64)
    return np.ascontiguousarray(A), basis


@pytest.mark.parametrize("m,singletons", [(1, 1), (2, 0), (6, 0), (6, 6), (12, 7),
                                          (40, 25), (80, 60), (80, 79)])
def test_the_block_inverse_is_the_inverse(m, singletons):
    rng = np.random.default_rng(m + 100 * singletons)
    checked = 0
    for _ in range(200):  # (five well-conditioned bases: random sparse ones can be singular)
        if checked == 5:
            break
        A, basis = _basis(rng, m, singletons)
        B = A[:, basis]
        if np.linalg.cond(B) > 1e8:
            continue
        checked += 1
        BinvT = np.full((m, m), np.nan)
        ok = _simplex.refactor(_simplex.sparse_pattern(A)[1], basis, BinvT)
        assert ok
        ref = np.linalg.inv(B)
        assert np.abs(BinvT.T - ref).max() <= 1e-10 * np.abs(ref).max()
        assert np.abs(BinvT.T @ B - np.eye(m)).max() <= 1e-9
    assert checked == 5


def test_singular_bases_are_refused():
    rng = np.random.default_rng(3)
    A, basis = _basis(rng, 10, 6)
    while np.linalg.cond(A[:, basis]) > 1e6:  # (a well-conditioned start)
        A, basis = _basis(rng, 10, 6)
    cols = _simplex.sparse_pattern(A)[1]
    out = np.empty((10, 10))
    # two singleton columns in the same row (parallel columns)
    e = np.zeros((10, 2))
    e[4, 0], e[4, 1] = 1.0, -3.0
    A2 = np.hstack([A, e])
    b2 = basis.copy()
    b2[:2] = [A.shape[1], A.shape[1] + 1]
    assert not _simplex.refactor(_simplex.sparse_pattern(A2)[1], b2, out)
    # a zero column
    A3 = np.hstack([A, np.zeros((10, 1))])
    b3 = basis.copy()
    b3[5] = A.shape[1]
    assert not _simplex.refactor(_simplex.sparse_pattern(A3)[1], b3, out)
    # a singular nucleus: one non-singleton column repeated
    B = A[:, basis]
    dense = [k for k in range(10) if np.count_nonzero(B[:, k]) > 1]
    b4 = basis.copy()
    b4[dense[1]] = basis[dense[0]]
    assert not _simplex.refactor(cols, b4, out)
    # the nonsingular original is accepted
    assert _simplex.refactor(cols, basis, out)
