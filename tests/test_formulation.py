"""Issue 27: the forward dynamics along the tree of M (andyc/symbolic/formulation.py, the LTDL kernels of
andyc/numerics/linalg.py) against the dense path: the same accelerations to 1e-12 on random matrices of a
tree's pattern and on every shipped model, with the tree's factorization forced on; and what it is
chosen from (the tree read off M's pattern, the operation counts)."""

import numpy as np
import pytest

from andyc.numerics.linalg import cholesky, ltdl, ltdl_solve, solve_lower, solve_upper
from andyc.symbolic.formulation import ABA, DENSE, LTDL, dense_operations, ltdl_operations, tree_of
from tests.support import MODELS

SHIPPED = sorted(p.stem for p in MODELS.glob("*.yaml"))


def tree_matrix(parent, rng):
    """A random symmetric positive definite M = L^T D L with L unit lower along `parent` (Featherstone 2005,
    eq. 8): M's pattern is exactly the tree's (ancestor-descendant pairs)."""
    n = len(parent)
    L = np.eye(n)
    for k in range(n):
        j = parent[k]
        while j >= 0:
            L[k, j] = rng.uniform(-1, 1)
            j = parent[j]
    return L.T @ np.diag(rng.uniform(0.5, 2.0, n)) @ L


def pattern(M):
    return [{j for j in range(len(M)) if j != i and M[i, j] != 0} for i in range(len(M))]


def dense_solve(M, b):
    """The dense path of numerics/dynamics.rhs_mode_into: cholesky, solve_lower, solve_upper."""
    L, x = M.copy(), b.copy()
    assert cholesky(L, len(b), 0.0)
    solve_lower(L, x, len(b))
    solve_upper(L, x, len(b))
    return x


def tree_solve(M, b, parent, order):
    F, x = M.copy(), b.copy()
    assert ltdl(F, np.array(parent, dtype=np.int64), np.array(order, dtype=np.int64), len(b), 0.0)
    ltdl_solve(F, np.array(parent, dtype=np.int64), np.array(order, dtype=np.int64), x, len(b))
    return x


# A quadruped's pattern as andyc numbers it: three joints per leg first (hip, knee, foot), then the
# floating base's six speeds last, each coupled to everything; and a humanoid-like tree numbered parents
# first, with a branch point inside a limb.
QUADRUPED = [-1, 0, 1, -1, 3, 4, -1, 6, 7, -1, 9, 10] + [-1] * 6
HUMANOID = [-1, 0, 1, 2, 3, 2, 5, 6, 2, 8, 9, 0, 11, 12, 0, 14, 15]


def _quadruped_tree():
    """QUADRUPED's real parents: each hip hangs from the last base speed (index 17), the base speeds chain."""
    parent = QUADRUPED[:]
    for hip in (0, 3, 6, 9):
        parent[hip] = 17
    for k in range(13, 18):
        parent[k] = k - 1
    return parent


@pytest.mark.parametrize("parent", [_quadruped_tree(), HUMANOID, list(range(-1, 7)), [-1] * 5],
                         ids=["quadruped, base last", "humanoid", "chain", "diagonal"])
def test_the_tree_is_read_off_the_pattern_and_solves_as_the_dense_path(parent):
    rng = np.random.default_rng(len(parent))
    M = tree_matrix(parent, rng)
    found = tree_of(pattern(M))
    assert found is not None
    tree, order = found
    for _ in range(5):
        b = rng.normal(size=len(parent))
        a = tree_solve(M, b, tree, order)
        assert np.abs(a - dense_solve(M, b)).max() <= 1e-12 * np.abs(a).max()
        assert np.abs(M @ a - b).max() <= 1e-12 * np.abs(b).max() * np.abs(M).max() * len(b)


def test_a_pattern_without_a_tree_is_refused():
    """Speed 2 couples to 0 and 1, which do not couple (each has two other partners): no order of
    elimination along one tree keeps 2's couplings on its chain of ancestors, so the dense path is used.
    A loop 0-1-2-3-0 on the other hand factors along the chain 0-1-2-3 (its zeros fill in, exactly)."""
    assert tree_of([{2, 3, 4}, {2, 5, 6}, {0, 1}, {0}, {0}, {1}, {1}]) is None
    loop = [{1, 3}, {0, 2}, {1, 3}, {0, 2}]
    assert tree_of(loop) == ([-1, 0, 1, 2], [3, 2, 1, 0])
    rng = np.random.default_rng(4)
    M = tree_matrix([-1, 0, 1, 2], rng)
    M[0, 2] = M[2, 0] = M[1, 3] = M[3, 1] = 0.0                 # the loop's pattern, still definite
    M += 4 * np.eye(4)
    b = rng.normal(size=4)
    assert np.abs(tree_solve(M, b, *tree_of(pattern(M))) - np.linalg.solve(M, b)).max() < 1e-12


def test_a_factor_that_is_not_positive_definite_is_refused():
    M = np.array([[1.0, 2.0], [2.0, 1.0]])
    assert not ltdl(M.copy(), np.array([-1, 0]), np.array([1, 0]), 2, 0.0)


def test_operation_counts():
    """Counted from the kernels' loops: a diagonal M costs one division and one multiplication per speed;
    on a full chain the tree's count grows like the dense one (n^3 / 3), on the quadruped far slower."""
    assert ltdl_operations([-1] * 7) == 14
    chain = list(range(-1, 31))
    assert 0.5 < ltdl_operations(chain) / dense_operations(32) < 1.0
    assert ltdl_operations(_quadruped_tree()) < 0.5 * dense_operations(18)
    assert dense_operations(1) == 1 + 1 + 2        # a division and a square root; a multiplication per solve


@pytest.fixture(scope="module", params=SHIPPED)
def shipped(request, compiled):
    return compiled(request.param)


def test_shipped_models_tree_formulation_equals_dense(shipped):
    """Every shipped model: M (and G) from the generated code; dv/dt = M^-1 G by the tree's LTDL (forced, also
    where the counts chose dense) equals the dense path's to 1e-12; so does the model's rhs without rows."""
    module = shipped.module
    if len(module.MASS_ORDER) == 0:
        pytest.skip(f"{module.NAME}: M has no tree pattern (the dense path only)")
    assert module.FORMULATION in (DENSE, LTDL, ABA) and (module.NT > 0) == (module.FORMULATION == LTDL)
    rng = np.random.default_rng(27)
    x0 = module.initial_state()
    nq, nv = module.NQ, module.NV
    for _ in range(5):
        x = x0 + 0.3 * rng.normal(size=x0.shape)
        x[nq + nv:] = x0[nq + nv:]                      # signals (quaternions) as they start
        M, G = module.mass_matrix(0.0, x), module.generalized_force(0.0, x)
        dense = dense_solve(M, G)
        tree = tree_solve(M, G, module.MASS_PARENT, module.MASS_ORDER)
        assert np.abs(tree - dense).max() <= 1e-12 * max(1.0, np.abs(dense).max()), module.NAME
        if module.NC == 0 and module.NF == 1:
            rhs = module.rhs(0.0, x)[nq:nq + nv]
            assert np.abs(rhs - dense).max() <= 1e-12 * max(1.0, np.abs(dense).max()), module.NAME
