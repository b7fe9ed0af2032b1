"""The contact problem of one time step, or of a multi-contact impact, compiled: the impulses P over m rows.

The same problem and answers as andyc.independent.contact_problem (its pure-Python twin), in flat arrays so that a
compiled time-stepping loop can call it. With W = A M^-1 A^T over the rows and w0 their velocities without the
impulses (plus e u_n on each normal row: Newton's law; Acary & Brogliato 2008, Numerical Methods for Nonsmooth
Dynamical Systems, sec. 10.1):

    w = w0 + W P
    bilateral row:           w_b = 0                           (P_b free)
    frictionless contact:    0 <= w_n  _|_  P_n >= 0
    Coulomb contact:         0 <= w_n  _|_  P_n >= 0,  |P_t| <= mu P_n,
                             w_t = 0 where |P_t| < mu P_n,  P_t = -mu P_n w_t / |w_t| where w_t != 0
                             (planar: one tangent row, P_t a number; spatial: two, P_t in the disk)

Blocks: block k is of kind[k] (BILATERAL, NORMAL, PLANAR, SPATIAL: 1, 1, 2, 3 rows, the normal row first), its
rows first[k] .. first[k] + size - 1. As Jean 1999 (The non-smooth contact dynamics method, CMAME 177, sec. 5)
does, nonlinear Gauss-Seidel over the blocks, each block's local problem solved exactly (open, sticking, sliding
either way; a spatial slide's direction by the secant method, else a scan of the circle and bisection), then a
polish: the states found (open, stick, slip +/-, a spatial slide with its direction) fix an active set whose
linear equations are solved in the least-norm least-squares sense (redundant rows allowed: a box flat on four
corners has 12 rows on 6 speeds; without a slide and of full rank, by Cholesky) and checked against every condition; a checked answer is exact to rounding,
one that fails leaves the Gauss-Seidel answer (verified False). The states passed in are tried first (the warm
start: a resting or sliding contact keeps its state, and the step costs one polish, no sweep). Beyond the
Python twin: where the active set's rows are dependent and the least-norm solution fails a check, the solution
closest to the Gauss-Seidel answer (or to the warm start's impulses) is tried too (_polish).

The polish's least squares: Householder QR with column pivoting (Businger & Golub 1965), the rank where a pivot
falls below RANK_EPS of the first, then the complete orthogonal decomposition (R11 R12 -> T 0 by reflectors from
the right, as LAPACK's xTZRZF) for the least-norm solution: np.linalg.lstsq's answer, written out so that no
call allocates (np.linalg's do, in Numba). The only memory is the caller's `work` (work_shape(m) float64s).
"""

import math

import numpy as np

from .compiler import jit

BILATERAL, NORMAL, PLANAR, SPATIAL = 0, 1, 2, 3     # a block's kind (its size: max(kind, 1) rows)
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3        # a block's state (bilateral blocks: STICK)
SLIDE = 2                                           # a spatial contact's one sliding state
NONE = -1                                           # no guess (in `state`): no warm start
SCAN = 36           # spatial sliding: the slip directions tried around the circle before bisecting
SWEEPS = 500        # Gauss-Seidel sweeps at most (the polish makes the answer exact when it verifies)
SWEEP_TOL = 1e-15   # ... until no impulse changes by more than this, relative to the largest
VECTORS = 12        # work's rows before the reduced system's
RANK_EPS = 1e-12    # least squares: a pivot below this times the first is rounding (a dependent column)
CHOLESKY_EPS = 1e-8     # the polish's Cholesky (no slide): each pivot above this times its diagonal entry, else
PSD_EPS = 1e-10         # ... with diagonal pivoting, where a pivot at most this times the first is rounding
TOL3Z = math.sqrt(np.finfo(np.float64).eps)     # pivoting: a column norm updated past this cancellation is recomputed


@jit
def work_shape(m):
    """The shape of `work` for problems of up to m rows: twelve vectors, the polish's reduced system, then the
    Gram matrix of its pivoted Cholesky (_psd_least_norm)."""
    return 2 * m + VECTORS, m


@jit
def solve(W, w0, kind, first, mu, state, direction, P, work):
    """P (m,) <- the impulses of the problem (the module's docstring); returns (sweeps, verified): the Gauss-Seidel
    sweeps taken (0: the warm start verified), and whether every condition holds to rounding (1e-10 of max(1,
    |w0|) on the velocities, 1e-12 of |P| on the impulses).

    W (m, m), w0 (m,), mu (nb,), direction (nb, 2), P (m,), work (at least work_shape(m)): float64; kind, first,
    state (nb,): int64; all C-contiguous. state and direction in: a guess, tried first (every state >= 0; a sliding
    spatial contact's unit slip direction after the step), or any state NONE: none. P in: with a guess, the
    impulses it came with (the last step's: of a redundant active set's solutions, the one closest to them is
    tried where the least-norm one fails), else anything. Out: the states found (the guess, when it verified),
    the sliding spatial contacts' directions -P_t / |P_t| (the others' (0, 0)), the impulses."""
    m, nb = w0.shape[0], kind.shape[0]
    if m == 0:
        return 0, True
    top = 0.0
    for i in range(m):
        top = max(top, abs(w0[i]))
    tol_v = 1e-10 * max(1.0, top)
    warm = True
    for k in range(nb):
        warm = warm and state[k] >= 0
    if warm and _polish(W, w0, kind, first, mu, state, direction, tol_v, P, work):
        for i in range(m):                      # (the polish's answer: work's first m)
            P[i] = work[0, i]
        return 0, True
    for i in range(m):
        P[i] = 0.0
    sweeps = 0
    while sweeps < SWEEPS:
        sweeps += 1
        change = _sweep(W, w0, kind, first, mu, P)
        top = 1e-300
        for i in range(m):
            top = max(top, abs(P[i]))
        if change <= SWEEP_TOL * top or change != change:     # (NaN: no use sweeping on)
            break
    _states(P, kind, first, mu, state, direction)
    if _polish(W, w0, kind, first, mu, state, direction, tol_v, P, work):
        for i in range(m):
            P[i] = work[0, i]
        return sweeps, True
    return sweeps, False


@jit
def _sweep(W, w0, kind, first, mu, P):
    """One Gauss-Seidel sweep over the blocks, in order, each solved with the others' impulses held; returns the
    largest change of an impulse."""
    m = P.shape[0]
    change = 0.0
    for k in range(kind.shape[0]):
        f, s = first[k], max(kind[k], 1)
        # the block's velocities without its own impulses (summed without them: no cancellation)
        u1 = w0[f] + _dot(W[f], P, 0, f) + _dot(W[f], P, f + s, m)
        u2 = w0[f + 1] + _dot(W[f + 1], P, 0, f) + _dot(W[f + 1], P, f + s, m) if s > 1 else 0.0
        u3 = w0[f + 2] + _dot(W[f + 2], P, 0, f) + _dot(W[f + 2], P, f + s, m) if s > 2 else 0.0
        o1, o2, o3 = P[f], P[f + 1] if s > 1 else 0.0, P[f + 2] if s > 2 else 0.0
        _local(W, f, kind[k], mu[k], u1, u2, u3, P)
        change = max(change, abs(P[f] - o1))
        if s > 1:
            change = max(change, abs(P[f + 1] - o2))
        if s > 2:
            change = max(change, abs(P[f + 2] - o3))
    return change


@jit
def _local(W, f, kind, mu, u1, u2, u3, P):
    """P[f:f + size] <- block f's impulses with the others held (u: its velocities without its own impulses),
    exact: a bilateral row's, a normal row's projected on P_n >= 0; with friction open, sticking, else sliding."""
    a = W[f, f]
    if kind == BILATERAL or kind == NORMAL:
        p = -u1 / a if a > 0.0 else 0.0
        P[f] = max(0.0, p) if kind == NORMAL else p
        return
    spatial = kind == SPATIAL
    P[f] = P[f + 1] = 0.0
    if spatial:
        P[f + 2] = 0.0
    if u1 >= 0.0:                           # open
        return
    ok, x1, x2, x3 = _stick(W, f, spatial, -u1, -u2, -u3)
    if ok and x1 >= 0.0 and math.hypot(x2, x3) <= mu * x1:
        P[f], P[f + 1] = x1, x2
        if spatial:
            P[f + 2] = x3
        return
    if spatial:
        if _slide_spatial(W, f, mu, u1, u2, u3, P):
            return
    else:
        for sigma in (1.0, -1.0):           # sliding forwards (w_t > 0, P_t = -mu P_n) or backwards
            k = a - sigma * mu * W[f, f + 1]
            if k > 0.0:
                pn = -u1 / k
                if sigma * (u2 + (W[f + 1, f] - sigma * mu * W[f + 1, f + 1]) * pn) >= 0.0:
                    P[f], P[f + 1] = pn, -sigma * mu * pn
                    return
    _closest(W, f, spatial, mu, u1, u2, u3, P)


@jit
def _stick(W, f, spatial, b1, b2, b3):
    """(solvable, x) with W_ff x = b, W_ff block f's 3 x 3 (a planar block's 2 x 2, bordered by the identity),
    by its adjugate; not solvable where the determinant is 0 (np.linalg.solve's LinAlgError)."""
    a00, a01, a10, a11 = W[f, f], W[f, f + 1], W[f + 1, f], W[f + 1, f + 1]
    a02 = a12 = a20 = a21 = 0.0
    a22 = 1.0
    if spatial:
        a02, a12, a20, a21, a22 = W[f, f + 2], W[f + 1, f + 2], W[f + 2, f], W[f + 2, f + 1], W[f + 2, f + 2]
    c00, c01, c02 = a11 * a22 - a12 * a21, a12 * a20 - a10 * a22, a10 * a21 - a11 * a20
    det = a00 * c00 + a01 * c01 + a02 * c02
    if det == 0.0:
        return False, 0.0, 0.0, 0.0
    c10, c11, c12 = a02 * a21 - a01 * a22, a00 * a22 - a02 * a20, a01 * a20 - a00 * a21
    c20, c21, c22 = a01 * a12 - a02 * a11, a02 * a10 - a00 * a12, a00 * a11 - a01 * a10
    return (True, (c00 * b1 + c10 * b2 + c20 * b3) / det, (c01 * b1 + c11 * b2 + c21 * b3) / det,
            (c02 * b1 + c12 * b2 + c22 * b3) / det)


@jit
def _closest(W, f, spatial, mu, u1, u2, u3, P):
    """No local solution (W's tangential coupling reverses the slip, Painleve-like): the closest admissible one,
    each row's own impulse scaled into the cone."""
    pn = max(0.0, -u1 / W[f, f])
    t1 = -u2 / W[f + 1, f + 1] if W[f + 1, f + 1] > 0.0 else 0.0
    t2 = 0.0
    if spatial and W[f + 2, f + 2] > 0.0:
        t2 = -u3 / W[f + 2, f + 2]
    size = math.hypot(t1, t2)
    scale = min(1.0, mu * pn / size) if size > 0.0 else 1.0
    P[f], P[f + 1] = pn, t1 * scale
    if spatial:
        P[f + 2] = t2 * scale


@jit
def _at(W, f, mu, u1, u2, u3, angle):
    """A spatial slide along d = (cos, sin)(angle): (admissible, d x s, d . s, P_n, d) with P_n from the normal
    row and s the slip after; not admissible where the normal row's coefficient a - mu b.d is not positive."""
    d1, d2 = math.cos(angle), math.sin(angle)
    den = W[f, f] - mu * (W[f, f + 1] * d1 + W[f, f + 2] * d2)
    if den <= 0.0:
        return False, 0.0, 0.0, 0.0, d1, d2
    pn = -u1 / den
    s1 = u2 + (W[f + 1, f] - mu * (W[f + 1, f + 1] * d1 + W[f + 1, f + 2] * d2)) * pn
    s2 = u3 + (W[f + 2, f] - mu * (W[f + 2, f + 1] * d1 + W[f + 2, f + 2] * d2)) * pn
    return True, d1 * s2 - d2 * s1, d1 * s1 + d2 * s2, pn, d1, d2


@jit
def _slide_spatial(W, f, mu, u1, u2, u3, P):
    """A spatial contact sliding: P = P_n (1, -mu d), d the unit slip after. For each d the normal row gives P_n;
    the slip's turn away from d, d x s, is found zero by the secant method from the slip's direction without
    friction (exact at once for an isotropic, uncoupled tangential inverse inertia: a point mass), or else by
    scanning SCAN directions round the circle, then bisecting the first sign change with d . s > 0 to the last
    bit. Returns whether it found one (P[f:f + 3] then set)."""
    x0 = math.atan2(u3, u2)
    x1 = x0 + 1e-6
    ok0, c0, _, _, _, _ = _at(W, f, mu, u1, u2, u3, x0)
    size = math.hypot(u2, u3)
    for _ in range(20):
        ok1, c1, dot1, pn, d1, d2 = _at(W, f, mu, u1, u2, u3, x1)
        if not (ok0 and ok1):
            break
        if dot1 > 0.0 and abs(c1) <= 1e-15 * size:
            P[f], P[f + 1], P[f + 2] = pn, -mu * pn * d1, -mu * pn * d2
            return True
        if c1 == c0:
            break
        x0, x1, c0 = x1, x1 - c1 * (x1 - x0) / (c1 - c0), c1
    step = 2.0 * math.pi / SCAN
    xl = 0.0
    okl, cl, dl, _, _, _ = _at(W, f, mu, u1, u2, u3, xl)
    for k in range(SCAN):
        xh = 2.0 * math.pi if k + 1 == SCAN else (k + 1) * step
        okh, ch, dh, _, _, _ = _at(W, f, mu, u1, u2, u3, xh)
        if okl and okh and not cl * ch > 0.0 and max(dl, dh) > 0.0:
            x0, x1, c0 = xl, xh, cl
            for _ in range(60):
                xm = 0.5 * (x0 + x1)
                okm, cm, _, _, _, _ = _at(W, f, mu, u1, u2, u3, xm)
                if not okm or xm == x0 or xm == x1:
                    break
                if (cm > 0.0) == (c0 > 0.0):
                    x0, c0 = xm, cm
                else:
                    x1 = xm
            ok, _, dot, pn, d1, d2 = _at(W, f, mu, u1, u2, u3, 0.5 * (x0 + x1))
            if ok and dot >= 0.0:
                P[f], P[f + 1], P[f + 2] = pn, -mu * pn * d1, -mu * pn * d2
                return True
        xl, okl, cl, dl = xh, okh, ch, dh
    return False


@jit
def _states(P, kind, first, mu, state, direction):
    """Each block's state as the impulses P say: open without a normal impulse, sticking inside the cone, else
    sliding against the tangential impulse; a sliding spatial contact's slip direction -P_t / |P_t| ((0, 0)
    without friction, mu = 0: no P_t, and any slip will do)."""
    top = 1e-300
    for i in range(P.shape[0]):
        top = max(top, abs(P[i]))
    for k in range(kind.shape[0]):
        f = first[k]
        direction[k, 0] = direction[k, 1] = 0.0
        if kind[k] == BILATERAL:
            state[k] = STICK
            continue
        pn = P[f]
        t1 = P[f + 1] if kind[k] >= PLANAR else 0.0
        t2 = P[f + 2] if kind[k] == SPATIAL else 0.0
        size = math.hypot(t1, t2)
        if pn <= 1e-12 * top:
            state[k] = OPEN
        elif kind[k] == NORMAL or size < mu[k] * pn * (1.0 - 1e-9):
            state[k] = STICK
        elif kind[k] == SPATIAL:
            state[k] = SLIDE
            if size > 0.0:
                direction[k, 0], direction[k, 1] = -t1 / size, -t2 / size
        else:
            state[k] = SLIP_POS if t1 < 0.0 else SLIP_NEG


@jit
def _polish(W, w0, kind, first, mu, state, direction, tol_v, P, work):
    """work[0, :m] <- the impulses the active set `state` (and the sliding spatial contacts' `direction`) fixes;
    returns whether they satisfy every condition. Its equations' least-norm least-squares solution first (the
    Python twin's); where they are dependent (redundant rows) and that fails, the solution closest to P (the
    Gauss-Seidel answer, or a warm start's last impulses): the least-norm choice can pull a contact or leave the
    cone where the other solutions include valid ones, as the Gauss-Seidel answer shows.

    Column j of the active set is e_r + c1 e_(r+1) + c2 e_(r+2), r = rows[j]: a bilateral or sticking row's own
    impulse (c = 0), or a sliding contact's, its friction riding on its normal impulse (planar: c1 = -+mu;
    spatial: c = -mu d); its equation is w_r = 0. Without a slide the system is W over the rows, symmetric
    positive semidefinite: its least-norm solution by Cholesky first, a fraction of the QR's cost (a robot standing
    on its feet: every step), with diagonal pivoting where plain Cholesky meets a pivot near zero (dependent rows:
    a box resting on four corners, _psd_least_norm); should that answer fail a condition, the QR's as ever."""
    m = w0.shape[0]
    cand, w, b, y, z, vn1, vn2, tau = work[0], work[1], work[2], work[3], work[4], work[5], work[6], work[7]
    c1, c2, rows, perm = work[8], work[9], work[10], work[11]   # (rows, perm: integers, as floats)
    K = work[VECTORS:VECTORS + m]       # the reduced system, K[:n, :n]
    n = np.int64(0)     # (not the literal 0: Numba would compile the calls below once more for it)
    for k in range(kind.shape[0]):
        f, s = first[k], state[k]
        if kind[k] == BILATERAL or (kind[k] != NORMAL and s == STICK):
            for r in range(f, f + max(kind[k], 1)):
                rows[n], c1[n], c2[n] = r, 0.0, 0.0
                n += 1
        elif s != OPEN:
            rows[n], c1[n], c2[n] = f, 0.0, 0.0
            if kind[k] == PLANAR:
                c1[n] = -mu[k] if s == SLIP_POS else mu[k]
            elif kind[k] == SPATIAL:
                c1[n], c2[n] = -mu[k] * direction[k, 0], -mu[k] * direction[k, 1]
            n += 1
    symmetric = True
    for j in range(n):
        symmetric = symmetric and c1[j] == 0.0 and c2[j] == 0.0
    _system(W, w0, rows, c1, c2, n, K, b)
    if symmetric:                           # no slide: K = W over the rows, symmetric: K^+ b by Cholesky first
        for i in range(n):
            y[i] = b[i]
        solved = _cholesky_solve(K, y, n)
        if not solved:                      # (dependent rows, or near it: a box resting on four corners)
            _system(W, w0, rows, c1, c2, n, K, b)
            for i in range(n):
                y[i] = b[i]
            solved = _psd_least_norm(K, y, n, perm, z, vn1, work[VECTORS + m:])
        if solved:
            for i in range(m):
                cand[i] = 0.0
            for j in range(n):
                cand[int(rows[j])] = y[j]
            for i in range(m):
                w[i] = w0[i] + _dot(W[i], cand, 0, m)
            if _holds(kind, first, mu, state, direction, cand, w, rows, n, tol_v):
                return True
        _system(W, w0, rows, c1, c2, n, K, b)          # (the factor, or a part of it, took K's place)
    rank = _factor(K, b, n, vn1, vn2, tau, perm, y, z)
    for closest in (False, True):
        if closest and rank == n:           # (a unique solution: nothing else to try)
            break
        for j in range(n):                  # (P's coefficients: column j is P's only one with a 1 at rows[j])
            vn1[j] = P[int(rows[j])]
        _solution(K, b, y, n, rank, tau, perm, vn1, closest, z)
        for i in range(m):
            cand[i] = 0.0
        for j in range(n):
            r = int(rows[j])
            cand[r] += y[j]
            if c1[j] != 0.0:
                cand[r + 1] += c1[j] * y[j]
            if c2[j] != 0.0:
                cand[r + 2] += c2[j] * y[j]
        for i in range(m):
            w[i] = w0[i] + _dot(W[i], cand, 0, m)
        if _holds(kind, first, mu, state, direction, cand, w, rows, n, tol_v):
            return True
    return False


@jit(inline="always")
def _system(W, w0, rows, c1, c2, n, K, b):
    """K[:n, :n] y = b[:n]: the active set's equations (_polish), K's column j the rows' velocities per unit of
    its column of impulses, b = -w0 at its rows."""
    for i in range(n):
        q = int(rows[i])
        b[i] = -w0[q]
        for j in range(n):
            r = int(rows[j])
            v = W[q, r]
            if c1[j] != 0.0:
                v += c1[j] * W[q, r + 1]
            if c2[j] != 0.0:
                v += c2[j] * W[q, r + 2]
            K[i, j] = v


@jit
def _cholesky_solve(K, y, n):
    """y[:n] <- K^-1 y for K[:n, :n] symmetric positive definite (its lower triangle read), by Cholesky in place
    (K's lower triangle <- L, K = L L^T); False where a pivot is not above CHOLESKY_EPS times its diagonal entry:
    K singular or near it (dependent rows: the least squares of _factor decide), y then undefined."""
    for j in range(n):
        d = K[j, j]
        for k in range(j):
            d -= K[j, k] * K[j, k]
        if not d > CHOLESKY_EPS * K[j, j]:
            return False
        ljj = math.sqrt(d)
        K[j, j] = ljj
        for i in range(j + 1, n):
            s = K[i, j]
            for k in range(j):
                s -= K[i, k] * K[j, k]
            K[i, j] = s / ljj
    for i in range(n):                      # L z = y
        s = y[i]
        for k in range(i):
            s -= K[i, k] * y[k]
        y[i] = s / K[i, i]
    for i in range(n - 1, -1, -1):          # L^T y = z
        s = y[i]
        for k in range(i + 1, n):
            s -= K[k, i] * y[k]
        y[i] = s / K[i, i]
    return True


@jit
def _psd_least_norm(K, y, n, perm, t, u, G):
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
        for i in range(n):                  # L L^T x = t
            s = t[i]
            for k in range(i):
                s -= K[i, k] * t[k]
            t[i] = s / K[i, i]
        for i in range(n - 1, -1, -1):
            s = t[i]
            for k in range(i + 1, n):
                s -= K[k, i] * t[k]
            t[i] = s / K[i, i]
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
        for j in range(r):                  # G = R R^T, then u <- G^-1 G^-1 u
            d = G[j, j]
            for k in range(j):
                d -= G[j, k] * G[j, k]
            if not d > 0.0:
                return False
            G[j, j] = math.sqrt(d)
            for i in range(j + 1, r):
                s = G[i, j]
                for k in range(j):
                    s -= G[i, k] * G[j, k]
                G[i, j] = s / G[j, j]
        for _ in range(2):
            for i in range(r):
                s = u[i]
                for k in range(i):
                    s -= G[i, k] * u[k]
                u[i] = s / G[i, i]
            for i in range(r - 1, -1, -1):
                s = u[i]
                for k in range(i + 1, r):
                    s -= G[k, i] * u[k]
                u[i] = s / G[i, i]
        for i in range(n):                  # t = L u
            s = 0.0
            for k in range(min(i + 1, r)):
                s += K[i, k] * u[k]
            t[i] = s
    for i in range(n):                      # x = Pi^T t
        y[int(perm[i])] = t[i]
    return True


@jit
def _holds(kind, first, mu, state, direction, P, w, rows, n, tol_v):
    """Whether the impulses P and the velocities w after satisfy every condition of the states (to tol_v on the
    velocities, 1e-12 of the largest impulse on the impulses; NaN fails): w = 0 on the active set's n rows, and
    each block's inequalities. (A slip's direction is not checked where mu = 0: the friction is nothing either
    way; where mu > 0 a spatial slide's direction d must be a unit vector: its friction is -mu P_n d.)"""
    top = 1e-300
    for i in range(P.shape[0]):
        top = max(top, abs(P[i]))
    tol_p = 1e-12 * top
    for j in range(n):
        if not abs(w[int(rows[j])]) <= tol_v:            # inconsistent equations (dependent rows, no solution)
            return False
    for k in range(kind.shape[0]):
        f, s = first[k], state[k]
        if kind[k] == BILATERAL:
            continue
        if s == OPEN:
            ok = w[f] >= -tol_v
        elif not P[f] >= -tol_p:
            ok = False
        elif kind[k] == NORMAL:
            ok = True
        elif s == STICK:
            ok = math.hypot(P[f + 1], P[f + 2] if kind[k] == SPATIAL else 0.0) <= mu[k] * P[f] + tol_p
        elif mu[k] == 0.0:
            ok = True
        elif kind[k] == SPATIAL:                    # the slip along d: no turn away from it, not reversed
            d1, d2 = direction[k, 0], direction[k, 1]
            ok = (abs(d1 * w[f + 2] - d2 * w[f + 1]) <= tol_v and d1 * w[f + 1] + d2 * w[f + 2] >= -tol_v
                  and abs(d1 * d1 + d2 * d2 - 1.0) <= 1e-12)
        else:
            ok = (1.0 if s == SLIP_POS else -1.0) * w[f + 1] >= -tol_v
        if not ok:
            return False
    return True


@jit
def _dot(x, y, lo, hi):
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
    tail = _dot(x, x, lo, hi)
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
    s = tau * (x[at] + _dot(v, x, lo, hi))
    x[at] -= s
    for i in range(lo, hi):
        x[i] -= s * v[i]


@jit
def _factor(K, b, n, vn1, vn2, tau, perm, v, s):
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
        pivot = math.sqrt(_dot(v, v, k, n))
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
        b[l] = (b[l] - _dot(K[l], b, l + 1, r)) / K[l, l]
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
def _solution(K, q, y, n, r, tau, perm, ref, closest, z):
    """y[:n] <- Pi Z^T (q[:r], f) of _factor's K Pi = Q [T 0; 0 0] Z, q[:r] = T^-1 (Q^T b)[:r]: a least-squares
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
