"""The dense solves of the contact problem's polish (andyc.numerics.contact_solver): the active set's reduced
system K x = b, n rows, in the caller's memory (no call allocates: np.linalg's do, in Numba).

- cholesky_solve: K symmetric positive definite and well conditioned (no slide, independent rows: a robot standing
  on its feet, every step), K^-1 b by Cholesky.
- psd_least_norm: K symmetric positive semidefinite (dependent rows: a box resting on four corners), the
  least-norm solution K^+ b by Cholesky with diagonal pivoting (as LAPACK's xPSTRF; Higham 2009, Cholesky
  factorization, WIREs Comp. Stat. 1, sec. 3).
- qr_factor, qr_solution: any K (a slide makes it unsymmetric), the least-norm least-squares solution by
  Householder QR with column pivoting (Businger & Golub 1965), the rank where a pivot falls below RANK_EPS of
  the first, then the complete orthogonal decomposition (R11 R12 -> T 0 by reflectors from the right, as
  LAPACK's xTZRZF): np.linalg.lstsq's answer, written out.
"""

import math

import numpy as np

from .compiler import jit

RANK_EPS = 1e-12    # least squares: a pivot below this times the first is rounding (a dependent column)
CHOLESKY_EPS = 1e-8     # Cholesky: each pivot above this times its diagonal entry, else the caller tries another
PSD_EPS = 1e-10         # ... with diagonal pivoting, where a pivot at most this times the first is rounding
TOL3Z = math.sqrt(np.finfo(np.float64).eps)     # pivoting: a column norm updated past this cancellation is recomputed


@jit
def cholesky_solve(K, y, n):
    """y[:n] <- K^-1 y for K[:n, :n] symmetric positive definite (its lower triangle read), by Cholesky in place
    (K's lower triangle <- L, K = L L^T); False where a pivot is not above CHOLESKY_EPS times its diagonal entry:
    K singular or near it (dependent rows: the least squares of qr_factor decide), y then undefined."""
    if not cholesky_factor(K, n, CHOLESKY_EPS):
        return False
    _llt_solve(K, y, n)
    return True


@jit(inline="always")
def cholesky_factor(K, n, eps):
    """K[:n, :n]'s lower triangle <- L, K = L L^T (its lower triangle read); False where a pivot is not above eps
    times its diagonal entry."""
    for j in range(n):
        d = K[j, j]
        for k in range(j):
            d -= K[j, k] * K[j, k]
        if not d > eps * K[j, j]:
            return False
        ljj = math.sqrt(d)
        K[j, j] = ljj
        for i in range(j + 1, n):
            s = K[i, j]
            for k in range(j):
                s -= K[i, k] * K[j, k]
            K[i, j] = s / ljj
    return True


@jit(inline="always")
def _llt_solve(L, y, n):
    """y[:n] <- (L L^T)^-1 y, L lower triangular in L[:n, :n]."""
    for i in range(n):                      # L z = y
        s = y[i]
        for k in range(i):
            s -= L[i, k] * y[k]
        y[i] = s / L[i, i]
    for i in range(n - 1, -1, -1):          # L^T y = z
        s = y[i]
        for k in range(i + 1, n):
            s -= L[k, i] * y[k]
        y[i] = s / L[i, i]


@jit
def psd_least_norm(K, y, n, perm, t, u, G):
    """y[:n] <- K^+ y, the least-norm least-squares solution of K x = y, for K[:n, :n] symmetric positive
    semidefinite (both triangles read, and overwritten), by Cholesky with diagonal pivoting (LAPACK's xPSTRF):
    Pi K Pi^T = L L^T with L (n, r) lower trapezoidal, r the pivots above PSD_EPS times the first (the rest is
    rounding: dependent rows); then x = Pi^T L (L^T L)^-2 L^T Pi y, K^+ for that factor (full rank: L^-T L^-1 at
    once). perm, t, u (n,) and G (at least r x r): scratch. False where no pivot is positive, or L^T L is not
    positive definite (the caller's QR decides then); the answer is the caller's to check."""
    for i in range(n):
        perm[i] = i
    r, first = n, 0.0
    for j in range(n):
        p = j
        for i in range(j + 1, n):
            if K[i, i] > K[p, p]:
                p = i
        if j == 0:
            first = K[p, p]
            if not first > 0.0:
                return False
        if not K[p, p] > PSD_EPS * first:
            r = j
            break
        if p != j:                          # rows and columns j and p swapped (the factor's columns with them)
            for i in range(n):
                K[j, i], K[p, i] = K[p, i], K[j, i]
            for i in range(n):
                K[i, j], K[i, p] = K[i, p], K[i, j]
            perm[j], perm[p] = perm[p], perm[j]
        ljj = math.sqrt(K[j, j])
        K[j, j] = ljj
        for i in range(j + 1, n):
            K[i, j] /= ljj
        for i in range(j + 1, n):           # the Schur complement, both triangles
            lij = K[i, j]
            for k in range(j + 1, i + 1):
                K[i, k] -= lij * K[k, j]
                K[k, i] = K[i, k]
    for i in range(n):                      # t = Pi y
        t[i] = y[int(perm[i])]
    if r == n:
        _llt_solve(K, t, n)                 # L L^T x = t
    else:
        for a in range(r):                  # u = L^T t, G = L^T L (its lower triangle)
            s = 0.0
            for i in range(a, n):
                s += K[i, a] * t[i]
            u[a] = s
            for c in range(a + 1):
                s = 0.0
                for i in range(a, n):
                    s += K[i, a] * K[i, c]
                G[a, c] = s
        if not cholesky_factor(G, r, 0.0):        # G = R R^T, then u <- G^-1 G^-1 u
            return False
        _llt_solve(G, u, r)
        _llt_solve(G, u, r)
        for i in range(n):                  # t = L u
            s = 0.0
            for k in range(min(i + 1, r)):
                s += K[i, k] * u[k]
            t[i] = s
    for i in range(n):                      # x = Pi^T t
        y[int(perm[i])] = t[i]
    return True


@jit
def dot(x, y, lo, hi):
    """The sum of x[i] y[i] over lo .. hi - 1, in four interleaved sums: four chains of dependent additions rather
    than one, a few times faster (Numba keeps the order of floating-point additions, so it cannot do this)."""
    s0 = s1 = s2 = s3 = 0.0
    i = lo
    while i + 4 <= hi:
        s0 += x[i] * y[i]
        s1 += x[i + 1] * y[i + 1]
        s2 += x[i + 2] * y[i + 2]
        s3 += x[i + 3] * y[i + 3]
        i += 4
    while i < hi:
        s0 += x[i] * y[i]
        i += 1
    return (s0 + s1) + (s2 + s3)


@jit
def _reflector(x, lo, hi, at):
    """The Householder reflector H = I - tau v v^T with H x = (beta, 0, ..) over the entries `at`, lo .. hi - 1 of
    the row x (LAPACK's xLARFG): v's tail is left in x[lo:hi] (its head is 1), beta in x[at]; returns tau."""
    alpha = x[at]
    tail = dot(x, x, lo, hi)
    if tail == 0.0:
        return 0.0
    beta = -math.copysign(math.sqrt(alpha * alpha + tail), alpha)
    scale = 1.0 / (alpha - beta)
    for i in range(lo, hi):
        x[i] *= scale
    x[at] = beta
    return (beta - alpha) / beta


@jit
def _reflect(v, x, lo, hi, at, tau):
    """x <- H x for the reflector _reflector left in v (its head at `at`, tail lo .. hi - 1)."""
    s = tau * (x[at] + dot(v, x, lo, hi))
    x[at] -= s
    for i in range(lo, hi):
        x[i] -= s * v[i]


@jit
def qr_factor(K, b, n, vn1, vn2, tau, perm, v, s):
    """The complete orthogonal decomposition K Pi = Q [T 0; 0 0] Z of K[:n, :n], in place; b[:r] <- T^-1 (Q^T
    b)[:r]; returns the rank r. Householder QR with column pivoting, stopped where the largest column left is
    below RANK_EPS |R_00| (the rest of R is rounding: dependent columns); then [R11 R12] = [T 0] Z by r
    reflectors from the right, each on coordinates l and r .. n - 1 (bottom row first, as LAPACK's xLATRZ),
    their tails left in K[l, r:n], their tau in tau[l]. v, s: scratch."""
    for j in range(n):
        perm[j] = j
        vn1[j] = 0.0
    for i in range(n):
        for j in range(n):
            vn1[j] += K[i, j] * K[i, j]
    for j in range(n):
        vn1[j] = vn2[j] = math.sqrt(vn1[j])
    r, top = n, 0.0
    for k in range(n):
        p = k
        for j in range(k + 1, n):
            if vn1[j] > vn1[p]:
                p = j
        if p != k:
            for i in range(n):
                K[i, k], K[i, p] = K[i, p], K[i, k]
            perm[k], perm[p] = perm[p], perm[k]
            vn1[k], vn1[p], vn2[k], vn2[p] = vn1[p], vn1[k], vn2[p], vn2[k]
        for i in range(k, n):               # (column k, contiguous; its norm afresh: the updated one lost digits)
            v[i] = K[i, k]
        pivot = math.sqrt(dot(v, v, k, n))
        top = pivot if k == 0 else top
        if not pivot > RANK_EPS * top:
            r = k
            break
        t = _reflector(v, k + 1, n, k)
        K[k, k] = v[k]
        if t != 0.0:                        # the later columns j: K[k:, j] -= t v (v . K[k:, j]), row by row
            _update(K, v, s, k, n, t)
            _reflect(v, b, k + 1, n, k, t)
        for j in range(k + 1, n):           # the columns' norms below row k, updated (LAPACK's xLAQP2)
            if vn1[j] != 0.0:
                q = abs(K[k, j]) / vn1[j]
                q = max(0.0, (1.0 - q) * (1.0 + q))
                if q * (vn1[j] / vn2[j]) ** 2 <= TOL3Z:
                    q = 0.0
                    for i in range(k + 1, n):
                        q += K[i, j] * K[i, j]
                    vn1[j] = vn2[j] = math.sqrt(q)
                else:
                    vn1[j] *= math.sqrt(q)
    for l in range(r - 1, -1, -1):          # [R11 R12] -> [T 0] (no reflector where the rank is full)
        if r == n:
            break
        t = tau[l] = _reflector(K[l], r, n, l)
        if t != 0.0:
            for p in range(l):
                _reflect(K[l], K[p], r, n, l, t)
    for l in range(r - 1, -1, -1):          # T^-1 (Q^T b)[:r]
        b[l] = (b[l] - dot(K[l], b, l + 1, r)) / K[l, l]
    return r


@jit
def _update(K, v, s, k, n, t):
    """K[k:n, k + 1:n] <- H K[k:n, k + 1:n], H = I - t v v^T (v[k] = 1, its tail in v[k + 1:n]): s = t v^T K, then
    K -= v s, both row by row over views indexed from 0, which LLVM vectorizes (indices it cannot prove
    non-negative carry Numba's wraparound test, which keeps it from that: 3x slower)."""
    sk, Kk = s[k + 1:n], K[k, k + 1:n]
    for j in range(n - k - 1):
        sk[j] = Kk[j]
    for i in range(k + 1, n):
        Ki, vi = K[i, k + 1:n], v[i]
        for j in range(n - k - 1):
            sk[j] += vi * Ki[j]
    for j in range(n - k - 1):
        sk[j] *= t
        Kk[j] -= sk[j]
    for i in range(k + 1, n):
        Ki, vi = K[i, k + 1:n], v[i]
        for j in range(n - k - 1):
            Ki[j] -= vi * sk[j]


@jit
def qr_solution(K, q, y, n, r, tau, perm, ref, closest, z):
    """y[:n] <- Pi Z^T (q[:r], f) of qr_factor's K Pi = Q [T 0; 0 0] Z, q[:r] = T^-1 (Q^T b)[:r]: a least-squares
    solution of K y = b: the least-norm one (f = 0), or with `closest`, the one closest to ref (f = (Z Pi^T ref)[r:],
    its part along K's null space). z: scratch."""
    for j in range(n):
        z[j] = ref[int(perm[j])] if closest else 0.0
    if closest and r < n:
        for l in range(r - 1, -1, -1):      # Z z = H_0 .. H_r-1 z
            _reflect(K[l], z, r, n, l, tau[l])
    for j in range(r):
        z[j] = q[j]
    if r < n:
        for l in range(r):                  # Z^T z = H_r-1 .. H_0 z
            _reflect(K[l], z, r, n, l, tau[l])
    for j in range(n):
        y[int(perm[j])] = z[j]
