"""Cholesky, triangular solves and the Gram solves of the constrained dynamics (Braun & Goldfarb, Part II);
the tree's sparse LTDL factorization of M (Featherstone 2005; andyc/symbolic/formulation.py).

The Gram solves work in the scratch S of layout.py, at the rows the compiled Model (`model`) gives.
Sizes are arguments, the same compiled code serving every model. For the sizes of most models
(n up to UNROLLED) each kernel branches once to a copy compiled with n as a constant, which LLVM
unrolls: at n = 6 that makes the passive walker's step about a fifth faster than loops of run-time
length. Each public kernel is that branch table over its private body (`_name`, inlined).
"""

import math

import numpy as np

from .compiler import jit
from .status import RANK_TOL

UNROLLED = 8    # sizes with a copy of their own


@jit(inline="always")
def _cholesky(M, n, tol):
    scale = 0.0
    for j in range(n):
        scale = max(scale, M[j, j])
    for j in range(n):
        s = M[j, j]
        for k in range(j):
            s -= M[j, k] * M[k, j]              # L1_jk (L1_jk D_kk)
        if not s > tol * scale:
            return False
        r = 1.0 / s
        M[j, j] = r
        for i in range(j + 1, n):
            s = M[i, j]
            for k in range(j):
                s -= M[i, k] * M[k, j]
            M[j, i] = s                         # L1_ij D_jj
            M[i, j] = s * r                     # L1_ij
    for j in range(n):
        r = math.sqrt(M[j, j])                  # D_jj^-1/2 = 1 / L_jj
        M[j, j] = r
        for i in range(j + 1, n):
            M[i, j] = M[j, i] * r               # L_ij = L1_ij D_jj^1/2
    return True


@jit
def cholesky(M, n, tol):
    """M[:n, :n] <- its lower Cholesky factor L (M = L L^T), in place, but with 1 / L_jj on the diagonal.
    The strict upper triangle is left as scratch (L_ij L_jj, i > j, at [j, i]).

    Factored as M = L1 D L1^T first (unit lower L1), whose column-to-column chain has one division
    per column and no square root; L = L1 D^1/2 then takes n independent square roots, off that
    chain. Storing the reciprocals takes the divisions out of the solves' chains too (solve_lower,
    solve_upper and whiten multiply by them). Returns False when a pivot D_jj is not above tol * the
    largest diagonal entry (tol = 0: M is not positive definite).
    """
    if n == 1: return _cholesky(M, 1, tol)      # noqa: E701  (a table: one compiled copy per size)
    if n == 2: return _cholesky(M, 2, tol)      # noqa: E701
    if n == 3: return _cholesky(M, 3, tol)      # noqa: E701
    if n == 4: return _cholesky(M, 4, tol)      # noqa: E701
    if n == 5: return _cholesky(M, 5, tol)      # noqa: E701
    if n == 6: return _cholesky(M, 6, tol)      # noqa: E701
    if n == 7: return _cholesky(M, 7, tol)      # noqa: E701
    if n == 8: return _cholesky(M, 8, tol)      # noqa: E701
    return _cholesky(M, n, tol)


@jit
def ltdl(M, parent, order, n, tol):
    """M[:n, :n] <- its LTDL factors along the tree `parent` (M = L^T D L; Featherstone 2005, Table 1), in place:
    L_ki at [k, i] for i an ancestor of k (unit diagonal, not stored), 1 / D_kk on the diagonal. `order`
    lists every speed before its parent. M's entries outside the tree's pattern (neither an ancestor nor a
    descendant) are neither read nor written: they are zero, and stay so in the factors (no fill-in).
    Returns False when a pivot D_kk is not above tol * the largest diagonal entry."""
    scale = 0.0
    for j in range(n):
        scale = max(scale, M[j, j])
    for kk in range(n):
        k = order[kk]
        d = M[k, k]                     # final: every descendant of k has been eliminated
        if not d > tol * scale:
            return False
        r = 1.0 / d
        M[k, k] = r
        i = parent[k]
        while i >= 0:
            a = M[k, i] * r
            j = i
            while j >= 0:               # j = i, then i's ancestors: M_ij -= L_ki M_kj
                M[i, j] -= a * M[k, j]
                j = parent[j]
            M[k, i] = a
            i = parent[i]
    return True


@jit
def ltdl_solve(M, parent, order, b, n):
    """b[:n] <- M^-1 b = L^-1 D^-1 L^-T b, M factored by ltdl (Featherstone 2005, eq. 10-12)."""
    for kk in range(n):                 # L^T y = b: descendants first
        k = order[kk]
        i = parent[k]
        while i >= 0:
            b[i] -= M[k, i] * b[k]
            i = parent[i]
    for k in range(n):
        b[k] *= M[k, k]
    for kk in range(n - 1, -1, -1):     # L x = y: ancestors first
        k = order[kk]
        i = parent[k]
        while i >= 0:
            b[k] -= M[k, i] * b[i]
            i = parent[i]


@jit(inline="always")
def _solve_lower(L, b, n):
    for i in range(n):
        s = b[i]
        for k in range(i):
            s -= L[i, k] * b[k]
        b[i] = s * L[i, i]


@jit
def solve_lower(L, b, n):
    """b[:n] <- L^-1 b, L from cholesky."""
    if n == 1: return _solve_lower(L, b, 1)     # noqa: E701
    if n == 2: return _solve_lower(L, b, 2)     # noqa: E701
    if n == 3: return _solve_lower(L, b, 3)     # noqa: E701
    if n == 4: return _solve_lower(L, b, 4)     # noqa: E701
    if n == 5: return _solve_lower(L, b, 5)     # noqa: E701
    if n == 6: return _solve_lower(L, b, 6)     # noqa: E701
    if n == 7: return _solve_lower(L, b, 7)     # noqa: E701
    if n == 8: return _solve_lower(L, b, 8)     # noqa: E701
    return _solve_lower(L, b, n)


@jit(inline="always")
def _solve_upper(L, b, n):
    for i in range(n - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, n):
            s -= L[k, i] * b[k]
        b[i] = s * L[i, i]


@jit
def solve_upper(L, b, n):
    """b[:n] <- L^-T b, L from cholesky."""
    if n == 1: return _solve_upper(L, b, 1)     # noqa: E701
    if n == 2: return _solve_upper(L, b, 2)     # noqa: E701
    if n == 3: return _solve_upper(L, b, 3)     # noqa: E701
    if n == 4: return _solve_upper(L, b, 4)     # noqa: E701
    if n == 5: return _solve_upper(L, b, 5)     # noqa: E701
    if n == 6: return _solve_upper(L, b, 6)     # noqa: E701
    if n == 7: return _solve_upper(L, b, 7)     # noqa: E701
    if n == 8: return _solve_upper(L, b, 8)     # noqa: E701
    return _solve_upper(L, b, n)


@jit(inline="always")
def _whiten(L, S, a0, c0, table, k, m, nv):
    for r in range(m):
        row = a0 + table[k, r]
        for i in range(nv):
            s = S[row, i]
            for j in range(i):
                s -= L[i, j] * S[c0 + r, j]
            S[c0 + r, i] = s * L[i, i]


@jit
def whiten(model, L, S, table, k, m):
    """C = A[rows] L^-T into S's C block, rows = table[k, :m] (a flow's or an impact's rows), A from S's A
    block; then C C^T = A M^-1 A^T (Braun & Goldfarb, Part II: C = A R^-1 with R = L^T)."""
    nv, a0, c0 = model.nv, model.s_a, model.s_c
    if nv == 1: return _whiten(L, S, a0, c0, table, k, m, 1)     # noqa: E701
    if nv == 2: return _whiten(L, S, a0, c0, table, k, m, 2)     # noqa: E701
    if nv == 3: return _whiten(L, S, a0, c0, table, k, m, 3)     # noqa: E701
    if nv == 4: return _whiten(L, S, a0, c0, table, k, m, 4)     # noqa: E701
    if nv == 5: return _whiten(L, S, a0, c0, table, k, m, 5)     # noqa: E701
    if nv == 6: return _whiten(L, S, a0, c0, table, k, m, 6)     # noqa: E701
    if nv == 7: return _whiten(L, S, a0, c0, table, k, m, 7)     # noqa: E701
    if nv == 8: return _whiten(L, S, a0, c0, table, k, m, 8)     # noqa: E701
    return _whiten(L, S, a0, c0, table, k, m, nv)


@jit(inline="always")
def _gram(S, c0, w0, m, nv):
    for r in range(m):
        for j in range(r + 1):
            s = 0.0
            for i in range(nv):
                s += S[c0 + r, i] * S[c0 + j, i]
            S[w0 + r, j] = s
            S[w0 + j, r] = s


@jit
def gram(model, S, m):
    """S's W block <- C C^T over the first m rows of its C block."""
    nv, c0, w0 = model.nv, model.s_c, model.s_w
    if nv == 1: return _gram(S, c0, w0, m, 1)       # noqa: E701
    if nv == 2: return _gram(S, c0, w0, m, 2)       # noqa: E701
    if nv == 3: return _gram(S, c0, w0, m, 3)       # noqa: E701
    if nv == 4: return _gram(S, c0, w0, m, 4)       # noqa: E701
    if nv == 5: return _gram(S, c0, w0, m, 5)       # noqa: E701
    if nv == 6: return _gram(S, c0, w0, m, 6)       # noqa: E701
    if nv == 7: return _gram(S, c0, w0, m, 7)       # noqa: E701
    if nv == 8: return _gram(S, c0, w0, m, 8)       # noqa: E701
    return _gram(S, c0, w0, m, nv)


@jit
def solve_gram(model, S, m, least_norm):
    """y <- (C C^T)^+ y for the first m rows of C (S's C block) and y (S's y row); returns the rank used, or -1.

    Independent rows: by the Cholesky factor of the Gram matrix C C^T (in S's W block). Otherwise (a
    pivot below RANK_TOL^2 times the largest: redundant rows, a singular pose) -1, or with least_norm
    the SVD C = U s V^T with the singular values below RANK_TOL times the largest dropped:
    y <- U s^-2 U^T y, so that C^T y = C^+ y_before, the least-norm solution.
    """
    gram(model, S, m)
    w0 = model.s_w
    # W: the block's whole rows, of which the kernels read [:m, :m]: a C-contiguous array as M is elsewhere, so that
    # Numba compiles one cholesky and one pair of solves for both (S[w0:w0 + m, :m] would be another layout, 'A')
    W, y = S[w0:w0 + m], S[model.s_y, :m]
    if cholesky(W, m, RANK_TOL * RANK_TOL):
        solve_lower(W, y, m)
        solve_upper(W, y, m)
        return m
    if not least_norm:
        return -1
    c0 = model.s_c
    U, sv, Vt = np.linalg.svd(S[c0:c0 + m, :model.nv], full_matrices=False)
    coef = S[model.s_coef, :m]
    rank = 0
    for j in range(sv.shape[0]):
        if not sv[j] > RANK_TOL * sv[0]:
            break
        rank += 1
        s = 0.0
        for i in range(m):
            s += U[i, j] * y[i]
        coef[j] = s / (sv[j] * sv[j])
    for i in range(m):
        s = 0.0
        for j in range(rank):
            s += U[i, j] * coef[j]
        y[i] = s
    return rank


@jit(inline="always")
def _add_rows_transposed(S, c0, y0, m, nv, scale, out):
    for i in range(nv):
        s = 0.0
        for r in range(m):
            s += S[c0 + r, i] * S[y0, r]
        out[i] += scale * s


@jit
def add_rows_transposed(model, S, m, scale, out):
    """out += scale C^T y, for the first m rows of C and y in S."""
    nv, c0, y0 = model.nv, model.s_c, model.s_y
    if nv == 1: return _add_rows_transposed(S, c0, y0, m, 1, scale, out)     # noqa: E701
    if nv == 2: return _add_rows_transposed(S, c0, y0, m, 2, scale, out)     # noqa: E701
    if nv == 3: return _add_rows_transposed(S, c0, y0, m, 3, scale, out)     # noqa: E701
    if nv == 4: return _add_rows_transposed(S, c0, y0, m, 4, scale, out)     # noqa: E701
    if nv == 5: return _add_rows_transposed(S, c0, y0, m, 5, scale, out)     # noqa: E701
    if nv == 6: return _add_rows_transposed(S, c0, y0, m, 6, scale, out)     # noqa: E701
    if nv == 7: return _add_rows_transposed(S, c0, y0, m, 7, scale, out)     # noqa: E701
    if nv == 8: return _add_rows_transposed(S, c0, y0, m, 8, scale, out)     # noqa: E701
    return _add_rows_transposed(S, c0, y0, m, nv, scale, out)


@jit
def correction(model, L, S, m):
    """S's dv row <- L^-T C^+ y for the first m rows of C and y in S (M = L L^T): the least M-norm change of
    speed with A dv = y (C = A L^-T), as the projections and the impact map use it."""
    solve_gram(model, S, m, bool(True))     # (bool(): not the literal True, a copy of its own; one solve_gram serves all)
    dv = S[model.s_dv, :model.nv]
    for i in range(model.nv):
        dv[i] = 0.0
    add_rows_transposed(model, S, m, 1.0, dv)
    solve_upper(L, dv, model.nv)
