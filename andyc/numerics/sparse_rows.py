"""The constrained solves along the tree of M and the rows' sparsity (andyc/symbolic/sparse_rows.py chooses them).

The dense path (linalg.py) whitens with the Cholesky factor of M = L L^T: C = A L^-T, g = L^-1 G, and solves the
Gram system C C^T lam = y over all rows. Here M = L^T D L is factored along its tree instead (linalg.ltdl,
Featherstone 2005), and R = D^1/2 L is the square root: M = R^T R, so that

    C = A R^-1,  g = R^-T G,  dv/dt = R^-1 (g + C^T lam),  C C^T = A M^-1 A^T

hold as in the dense path (R and the dense L^T differ by an orthogonal factor, so C C^T, y = -kappa - C g,
C^T lam in speeds and C's singular values are the same). Row i of C is D^-1/2 L^-T A_i^T, whose nonzeros are
A_i's and their ancestors in the tree: that support is known at build time (ROW_PTR, ROW_COLS: descendants
first, with each speed's position in MASS_ORDER, by which two supports are merged). So whitening a row costs
its support times the depth, a Gram entry the length of two supports, and C C^T has a nonzero only between rows
whose supports meet (the loops that share a link). It is factored as L1 D1 L1^T within its envelope
(FLOW_ENVELOPE[flow, 0, r]: the first row Gram row r reaches; no fill-in outside it), with the dense path's pivot
test. A pivot at most RANK_TOL^2 times the largest diagonal entry (redundant rows, a singular pose) marks its
block (rows that the envelope does not join to the others: FLOW_ENVELOPE[flow, 1, r], its first row): only those blocks take the SVD, over their own rows
and the speeds their supports reach (the dense path's least-norm solve, confined to them).

After tree_factor, M holds L_ki at [k, i] (i an ancestor of k) and D_kk^-1/2 on its diagonal (as linalg.cholesky
keeps 1 / L_jj there).
"""

import math

import numpy as np

from .compiler import jit
from .linalg import ltdl
from .status import RANK_TOL


@jit
def tree_factor(model, M):
    """M[:nv, :nv] <- R's factors (module docstring), in place; False when M is not positive definite."""
    if not ltdl(M, model.mass_parent, model.mass_order, model.nv, 0.0):
        return False
    for k in range(model.nv):
        M[k, k] = math.sqrt(M[k, k])
    return True


@jit
def tree_lower(model, M, b):
    """b[:nv] <- R^-T b = D^-1/2 L^-T b (as linalg.solve_lower for the dense factor)."""
    parent, order = model.mass_parent, model.mass_order
    for kk in range(model.nv):          # L^T y = b: descendants first
        k = order[kk]
        v = b[k]
        i = parent[k]
        while i >= 0:
            b[i] -= M[k, i] * v
            i = parent[i]
        b[k] = v * M[k, k]


@jit
def tree_upper(model, M, b):
    """b[:nv] <- R^-1 b = L^-1 D^-1/2 b (as linalg.solve_upper for the dense factor)."""
    parent, order, n = model.mass_parent, model.mass_order, model.nv
    for k in range(n):
        b[k] *= M[k, k]
    for kk in range(n - 1, -1, -1):     # L x = y: ancestors first
        k = order[kk]
        s = b[k]
        i = parent[k]
        while i >= 0:
            s -= M[k, i] * b[i]
            i = parent[i]
        b[k] = s


@jit
def tree_times(model, M, v, out):
    """out[:nv] <- R v = D^1/2 L v (the energy correction's L^T v of the dense path)."""
    parent = model.mass_parent
    for k in range(model.nv):
        s = v[k]
        i = parent[k]
        while i >= 0:
            s += M[k, i] * v[i]
            i = parent[i]
        out[k] = s / M[k, k]


@jit
def whiten_rows(model, M, S, table, k, m):
    """C = A[rows] R^-1 into S's C block over each row's support only, rows = table[k, :m] (as linalg.whiten)."""
    parent, ptr, cols = model.mass_parent, model.row_ptr, model.row_cols
    a0, c0 = model.s_a, model.s_c
    for r in range(m):
        i = table[k, r]
        row, out = a0 + i, c0 + r
        for e in range(ptr[i], ptr[i + 1]):
            j = cols[0, e]
            S[out, j] = S[row, j]
        for e in range(ptr[i], ptr[i + 1]):    # D^-1/2 L^-T a: descendants first
            j = cols[0, e]
            v = S[out, j]
            a = parent[j]
            while a >= 0:
                S[out, a] -= M[j, a] * v
                a = parent[a]
            S[out, j] = v * M[j, j]


@jit(inline="always")
def row_dot(model, S, table, k, r, q):
    """C_r . C_q over the meeting of the two rows' supports (a merge by position in MASS_ORDER)."""
    ptr, cols, c0 = model.row_ptr, model.row_cols, model.s_c
    i, j = table[k, r], table[k, q]
    a, a1, b, b1 = ptr[i], ptr[i + 1], ptr[j], ptr[j + 1]
    s = 0.0
    while a < a1 and b < b1:
        pa, pb = cols[1, a], cols[1, b]
        if pa == pb:
            s += S[c0 + r, cols[0, a]] * S[c0 + q, cols[0, a]]
            a += 1
            b += 1
        elif pa < pb:
            a += 1
        else:
            b += 1
    return s


@jit
def rows_times(model, S, table, k, m, v, out):
    """out[:m] <- C v over each row's support."""
    ptr, cols, c0 = model.row_ptr, model.row_cols, model.s_c
    for r in range(m):
        i = table[k, r]
        s = 0.0
        for e in range(ptr[i], ptr[i + 1]):
            j = cols[0, e]
            s += S[c0 + r, j] * v[j]
        out[r] = s


@jit
def add_rows_transposed_sparse(model, S, table, k, m, scale, out):
    """out += scale C^T y over each row's support (as linalg.add_rows_transposed)."""
    ptr, cols, c0, y0 = model.row_ptr, model.row_cols, model.s_c, model.s_y
    for r in range(m):
        i = table[k, r]
        s = scale * S[y0, r]
        for e in range(ptr[i], ptr[i + 1]):
            j = cols[0, e]
            out[j] += S[c0 + r, j] * s


@jit
def solve_gram_sparse(model, S, table, k, m, least_norm, envelope):
    """y <- (C C^T)^+ y over the first m rows of C (S's C block, whitened by whiten_rows) and y (S's y row), as
    linalg.solve_gram: returns the rank used, or -1 (a tiny pivot and not least_norm). `envelope` (2, >= m): the
    first row each Gram row reaches, then the first row of its block (FLOW_ENVELOPE[flow]). Module docstring."""
    w0, y0 = model.s_w, model.s_y
    W = S[w0:w0 + m, :m]
    scale = 0.0
    for r in range(m):                  # C C^T within the envelope only
        for q in range(envelope[0, r], r + 1):
            W[r, q] = row_dot(model, S, table, k, r, q)
        scale = max(scale, W[r, r])
    tol = RANK_TOL * RANK_TOL * scale
    singular = 0
    a = 0
    rank = 0
    while a < m:                        # block by block: [a, b) with no envelope reaching back past a
        b = a + 1
        while b < m and envelope[1, b] == a:
            b += 1
        ok = True
        for i in range(a, b):           # L1 D1 L1^T: W[i, j] <- L1_ij (j < i), W[i, i] <- 1 / D1_ii
            fi = envelope[0, i]
            for j in range(fi, i):
                s = W[i, j]
                for t in range(max(fi, envelope[0, j]), j):
                    s -= W[i, t] * W[j, t]      # W[i, t]: L1_it D1_tt until row i is done
                W[i, j] = s
            d = W[i, i]
            for j in range(fi, i):
                lij = W[i, j] * W[j, j]
                d -= lij * W[i, j]
                W[i, j] = lij
            if not d > tol:
                ok = False
                break
            W[i, i] = 1.0 / d
        if ok:
            y = S[y0, a:b]
            for i in range(a, b):       # L1^-1, D1^-1, L1^-T within the block
                s = y[i - a]
                for j in range(envelope[0, i], i):
                    s -= W[i, j] * y[j - a]
                y[i - a] = s
            for i in range(b - a):
                y[i] *= W[a + i, a + i]
            for i in range(b - 1, a - 1, -1):
                v = y[i - a]
                for j in range(envelope[0, i], i):
                    y[j - a] -= W[i, j] * v
            rank += b - a
        else:
            if not least_norm:
                return -1
            singular += 1
            W[a, a] = -1.0              # marks the block for the least-norm solve below
        a = b
    if singular == 0:
        return rank
    return rank + _least_norm_blocks(model, S, table, k, m, envelope, scale)


@jit
def _least_norm_blocks(model, S, table, k, m, envelope, scale):
    """The blocks solve_gram_sparse marked (W[a, a] = -1): y <- U s^-2 U^T y over each, from the SVD of its rows of
    C restricted to the speeds they reach, singular values below RANK_TOL times the largest dropped (the largest
    of the marked blocks' and sqrt of the largest Gram diagonal: with one block, the dense path's). Returns the
    rank."""
    ptr, cols, c0, w0, y0, nv = model.row_ptr, model.row_cols, model.s_c, model.s_w, model.s_y, model.nv
    where = np.full(nv, -1, dtype=np.int64)
    top = math.sqrt(scale)
    parts = []
    a = 0
    while a < m:                        # the blocks again (as solve_gram_sparse)
        b = a + 1
        while b < m and envelope[1, b] == a:
            b += 1
        if S[w0 + a, a] == -1.0:
            n = 0
            for r in range(a, b):
                i = table[k, r]
                for e in range(ptr[i], ptr[i + 1]):
                    j = cols[0, e]
                    if where[j] < 0:
                        where[j] = n
                        n += 1
            block = np.zeros((b - a, n))
            for r in range(a, b):
                i = table[k, r]
                for e in range(ptr[i], ptr[i + 1]):
                    j = cols[0, e]
                    block[r - a, where[j]] = S[c0 + r, j]
            for r in range(a, b):
                i = table[k, r]
                for e in range(ptr[i], ptr[i + 1]):
                    where[cols[0, e]] = -1
            U, sv, _ = np.linalg.svd(block, full_matrices=False)
            top = max(top, sv[0])
            parts.append((a, b, U, sv))
        a = b
    used_total = 0
    for a, b, U, sv in parts:
        y = S[y0, a:b]
        coef = np.zeros(sv.shape[0])
        used = 0
        for j in range(sv.shape[0]):
            if not sv[j] > RANK_TOL * top:
                break
            used += 1
            s = 0.0
            for i in range(b - a):
                s += U[i, j] * y[i]
            coef[j] = s / (sv[j] * sv[j])
        for i in range(b - a):
            s = 0.0
            for j in range(used):
                s += U[i, j] * coef[j]
            y[i] = s
        used_total += used
    return used_total


@jit
def correction_sparse(model, M, S, table, k, m, envelope):
    """S's dv row <- R^-1 C^+ y for the first m rows of C and y in S (as linalg.correction)."""
    solve_gram_sparse(model, S, table, k, m, bool(True), envelope)   # (bool(): see linalg.correction)
    dv = S[model.s_dv, :model.nv]
    for i in range(model.nv):
        dv[i] = 0.0
    add_rows_transposed_sparse(model, S, table, k, m, 1.0, dv)
    tree_upper(model, M, dv)
