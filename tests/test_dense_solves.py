"""The contact polish's dense solves (andyc.numerics.dense_solves) against NumPy's: their answers are checked by
the polish, which falls back to QR where they fail, so a wrong fast path would only show as lost speed there."""

import numpy as np
import pytest

from andyc.numerics.dense_solves import cholesky_solve, psd_least_norm


@pytest.mark.parametrize("n", [1, 3, 7])
def test_cholesky_solve_is_numpys_solve(n):
    rng = np.random.default_rng(n)
    B = rng.standard_normal((n, n))
    K, y = B @ B.T + n * np.eye(n), rng.standard_normal(n)
    x = y.copy()
    assert cholesky_solve(K.copy(), x, n)
    np.testing.assert_allclose(x, np.linalg.solve(K, y), rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("n, rank", [(4, 4), (6, 3), (12, 6)])
def test_psd_least_norm_is_the_pseudo_inverse(n, rank):
    """K = B B^T of rank r (a box's 12 corner rows on its 6 speeds: rank 6): x = K^+ y, the least-norm least
    squares solution, as np.linalg.pinv gives it."""
    rng = np.random.default_rng(n + rank)
    B = rng.standard_normal((n, rank))
    K, y = B @ B.T, rng.standard_normal(n)
    x = y.copy()
    scratch = [np.zeros(n) for _ in range(3)]
    assert psd_least_norm(K.copy(), x, n, *scratch, np.zeros((n, n)))
    np.testing.assert_allclose(x, np.linalg.pinv(K) @ y, rtol=1e-9, atol=1e-9)
