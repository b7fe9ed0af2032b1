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
    bounded row (dry friction of a joint: a bound F h, F the friction force or torque, h the step):
                             |P_f| <= F h,  w_f = 0 where |P_f| < F h,  P_f = -F h sign(w_f) where w_f != 0
                             (Coulomb's law with a normal impulse held fixed: MuJoCo's frictionloss)

Blocks: block k is of kind[k] (BILATERAL, NORMAL, PLANAR, SPATIAL, BOUNDED: 1, 1, 2, 3, 1 rows, the normal row
first; size(kind)), its rows first[k] .. first[k] + size - 1; a bounded block's bound F h is its mu[k]. As Jean 1999 (The non-smooth contact dynamics method, CMAME 177, sec. 5)
does, nonlinear Gauss-Seidel over the blocks, each block's local problem solved exactly (open, sticking, sliding
either way; a spatial slide's direction by the secant method, else a scan of the circle and bisection), then a
polish: the states found (open, stick, slip +/-, a spatial slide with its direction) fix an active set whose
linear equations are solved in the least-norm least-squares sense (redundant rows allowed: a box flat on four
corners has 12 rows on 6 speeds; andyc.numerics.dense_solves) and checked against every condition; a checked
answer is exact to rounding, one that fails leaves the Gauss-Seidel answer (verified False). The states passed in are tried first (the warm
start: a resting or sliding contact keeps its state, and the step costs one polish, no sweep). Beyond the
Python twin: where the active set's rows are dependent and the least-norm solution fails a check, the solution
whose friction is split over the sticking contacts by mu P_n (_weighted: a box held on a slope near its cone's
edge), then the one closest to the Gauss-Seidel answer (or to the warm start's impulses) are tried (_polish).

No call allocates: the only memory is the caller's `work` (work_shape(m) float64s).
"""

import math

import numpy as np

from .compiler import jit
from .dense_solves import cholesky_solve, dot, psd_least_norm, qr_factor, qr_solution

BILATERAL, NORMAL, PLANAR, SPATIAL, BOUNDED = 0, 1, 2, 3, 4    # a block's kind (its rows: size(kind))
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3        # a block's state (bilateral blocks: STICK; a bounded block
#                                                     slipping forwards, w_f > 0: SLIP_POS, P_f = -bound)
SLIDE = 2                                           # a spatial contact's one sliding state
NONE = -1                                           # no guess (in `state`): no warm start
FAILED, VERIFIED, ADJUSTED = 0, 1, 2                 # what a polish found (_polish)
SCAN = 36           # spatial sliding: the slip directions tried around the circle before bisecting
SWEEPS = 500        # Gauss-Seidel sweeps at most (the polish makes the answer exact when it verifies)
SWEEP_TOL = 1e-15   # ... until no impulse changes by more than this, relative to the largest
VECTORS = 14        # work's rows before the reduced system's


@jit(inline="always")
def size(kind):
    """The rows of a block of this kind."""
    return 1 if kind == BOUNDED else max(kind, 1)


@jit
def work_shape(m):
    """The shape of `work` for problems of up to m rows: VECTORS vectors, the polish's reduced system, then the
    Gram matrix of its pivoted Cholesky (psd_least_norm)."""
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
    if warm and _settle(W, w0, kind, first, mu, state, direction, tol_v, P, work):
        for i in range(m):                      # (the polish's answer: work's first m)
            P[i] = work[0, i]
        return 0, True
    if warm and _unclamp(kind, state) and _settle(W, w0, kind, first, mu, state, direction, tol_v, P, work):
        for i in range(m):                      # (the warm start with its bounded rows sticking again, clamped
            P[i] = work[0, i]                   #  afresh: a joint held at its friction's bound that lets go)
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
    if _settle(W, w0, kind, first, mu, state, direction, tol_v, P, work):
        for i in range(m):
            P[i] = work[0, i]
        return sweeps, True
    return sweeps, False


@jit
def _settle(W, w0, kind, first, mu, state, direction, tol_v, P, work):
    """_polish, and where its answer fails with a sticking bounded row beyond its bound, that row held at the
    bound (a slip state, whose zero slip also satisfies its conditions), or with a held row whose slip reverses,
    that row sticking, and polished again (_adjust), until it verifies or no such row is left. Why: where the rows are dependent (a robot standing on its feet with its joints stuck:
    more rows than speeds) the least-norm impulses share the load evenly and can ask a joint's friction for more
    than it has; the other solutions, with that friction at its bound, hold."""
    for _ in range(2 * kind.shape[0] + 1):
        found = _polish(W, w0, kind, first, mu, state, direction, tol_v, P, work)
        if found != ADJUSTED:
            return found == VERIFIED
    return False


@jit
def _unclamp(kind, state):
    """Every bounded row sticking (state); whether any was not."""
    changed = False
    for k in range(kind.shape[0]):
        if kind[k] == BOUNDED and state[k] != STICK:
            state[k] = STICK
            changed = True
    return changed


@jit
def _adjust(kind, first, mu, state, P, w, tol_v):
    """The bounded rows' states that the impulses P and velocities w of a failed polish contradict, changed
    (_settle): a sticking row asked for more than its bound is held at it, a row held at its bound whose slip
    reverses sticks; whether any changed."""
    changed = False
    for k in range(kind.shape[0]):
        if kind[k] != BOUNDED:
            continue
        f = first[k]
        if state[k] == STICK and abs(P[f]) > mu[k] * (1.0 + 1e-9):
            state[k] = SLIP_POS if P[f] < 0.0 else SLIP_NEG
            changed = True
        elif (state[k] == SLIP_POS and w[f] < -tol_v) or (state[k] == SLIP_NEG and w[f] > tol_v):
            state[k] = STICK
            changed = True
    return changed


@jit
def _sweep(W, w0, kind, first, mu, P):
    """One Gauss-Seidel sweep over the blocks, in order, each solved with the others' impulses held; returns the
    largest change of an impulse."""
    m = P.shape[0]
    change = 0.0
    for k in range(kind.shape[0]):
        f, s = first[k], size(kind[k])
        # the block's velocities without its own impulses (summed without them: no cancellation)
        u1 = w0[f] + dot(W[f], P, 0, f) + dot(W[f], P, f + s, m)
        u2 = w0[f + 1] + dot(W[f + 1], P, 0, f) + dot(W[f + 1], P, f + s, m) if s > 1 else 0.0
        u3 = w0[f + 2] + dot(W[f + 2], P, 0, f) + dot(W[f + 2], P, f + s, m) if s > 2 else 0.0
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
    if kind == BOUNDED:                     # stuck, else held at the bound against the slip
        p = -u1 / a if a > 0.0 else (-mu if u1 > 0.0 else mu)
        P[f] = min(max(p, -mu), mu)
        return
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
        if kind[k] == BOUNDED:
            state[k] = STICK if abs(P[f]) < mu[k] * (1.0 - 1e-9) else (SLIP_POS if P[f] < 0.0 else SLIP_NEG)
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
    returns VERIFIED where they satisfy every condition, else FAILED, or ADJUSTED where its answer contradicts a
    bounded row's state, which is then changed (_adjust; _settle polishes again). Its equations' least-norm
    least-squares solution first (the
    Python twin's); where they are dependent (redundant rows) and that fails, the solution closest to P (the
    Gauss-Seidel answer, or a warm start's last impulses): the least-norm choice can pull a contact or leave the
    cone where the other solutions include valid ones, as the Gauss-Seidel answer shows.

    Column j of the active set is e_r + c1 e_(r+1) + c2 e_(r+2), r = rows[j]: a bilateral or sticking row's own
    impulse (c = 0), or a sliding contact's, its friction riding on its normal impulse (planar: c1 = -+mu;
    spatial: c = -mu d); its equation is w_r = 0. A sticking bounded row is a column of its own; a slipping one's
    impulse is its bound (`fixed`), known, so its effect W fixed moves to the right-hand side. Without a slide the system is W over the rows, symmetric
    positive semidefinite: its least-norm solution by Cholesky first, a fraction of the QR's cost (a robot standing
    on its feet: every step), with diagonal pivoting where plain Cholesky meets a pivot near zero (dependent rows:
    a box resting on four corners, psd_least_norm); should that answer fail a condition, the QR's as ever."""
    m = w0.shape[0]
    cand, w, b, y, z, vn1, vn2, tau = work[0], work[1], work[2], work[3], work[4], work[5], work[6], work[7]
    c1, c2, rows, perm = work[8], work[9], work[10], work[11]   # (rows, perm: integers, as floats)
    fixed, wf = work[12], work[13]      # the slipping bounded rows' impulses (at the bound), w0 + W fixed
    K = work[VECTORS:VECTORS + m]       # the reduced system, K[:n, :n]
    n = np.int64(0)     # (not the literal 0: Numba would compile the calls below once more for it)
    held = False
    for i in range(m):
        fixed[i] = 0.0
    for k in range(kind.shape[0]):
        f, s = first[k], state[k]
        if kind[k] == BOUNDED and (s == SLIP_POS or s == SLIP_NEG):
            fixed[f] = -mu[k] if s == SLIP_POS else mu[k]
            held = True
        elif kind[k] == BILATERAL or kind[k] == BOUNDED or (kind[k] != NORMAL and s == STICK):
            for r in range(f, f + size(kind[k])):
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
    for i in range(m):
        wf[i] = w0[i] + dot(W[i], fixed, 0, m) if held else w0[i]
    _system(W, wf, rows, c1, c2, n, K, b)
    if symmetric:                           # no slide: K = W over the rows, symmetric: K^+ b by Cholesky first
        for i in range(n):
            y[i] = b[i]
        unique = cholesky_solve(K, y, n)
        solved = unique
        if not solved:                      # (dependent rows, or near it: a box resting on four corners)
            _system(W, wf, rows, c1, c2, n, K, b)
            for i in range(n):
                y[i] = b[i]
            solved = psd_least_norm(K, y, n, perm, z, vn1, work[VECTORS + m:])
        if solved:
            for i in range(m):
                cand[i] = fixed[i]
            for j in range(n):
                cand[int(rows[j])] = y[j]
            for i in range(m):
                w[i] = w0[i] + dot(W[i], cand, 0, m)
            if _holds(kind, first, mu, state, direction, cand, w, rows, n, tol_v):
                return VERIFIED
            if not unique and _weighted(W, w0, wf, fixed, kind, first, mu, state, direction, tol_v, rows, c1, c2, n,
                                        cand, w, y, z, vn1, vn2, tau, perm, K, b, work[VECTORS + m:]):
                return VERIFIED
            if _adjust(kind, first, mu, state, cand, w, tol_v):
                return ADJUSTED
        _system(W, wf, rows, c1, c2, n, K, b)          # (the factor, or a part of it, took K's place)
    rank = qr_factor(K, b, n, vn1, vn2, tau, perm, y, z)
    for closest in (False, True):
        if closest and rank == n:           # (a unique solution: nothing else to try)
            break
        for j in range(n):                  # (P's coefficients: column j is P's only one with a 1 at rows[j])
            vn1[j] = P[int(rows[j])]
        qr_solution(K, b, y, n, rank, tau, perm, vn1, closest, z)
        for i in range(m):
            cand[i] = fixed[i]
        for j in range(n):
            r = int(rows[j])
            cand[r] += y[j]
            if c1[j] != 0.0:
                cand[r + 1] += c1[j] * y[j]
            if c2[j] != 0.0:
                cand[r + 2] += c2[j] * y[j]
        for i in range(m):
            w[i] = w0[i] + dot(W[i], cand, 0, m)
        if _holds(kind, first, mu, state, direction, cand, w, rows, n, tol_v):
            return VERIFIED
        if not closest and _adjust(kind, first, mu, state, cand, w, tol_v):
            return ADJUSTED
    return FAILED


@jit
def _weighted(W, w0, wf, fixed, kind, first, mu, state, direction, tol_v, rows, c1, c2, n, cand, w, y, t, u, weight,
              d2, perm, K, b, G):
    """Whether the active set's solution of least weighted norm sum_j x_j^2 / d2_j satisfies every condition; it is
    then in `cand` (and w). A sticking contact's friction rows are weighted by mu P_n (P_n of `cand`, the
    least-norm solution, which failed), every other row by the mean of those:
    x = D z with z the least-norm solution of K D z = b, D = D2^1/2 (by QR; the same as D2 K (K D2 K)^+ b) for K
    symmetric (no slide). Of a redundant set's solutions (a box on four corners) the least-norm one splits a
    friction evenly over the contacts that share its direction; this one splits it in proportion to what their
    cones allow, so where the load is uneven (the box held on a slope near its cone's edge: the upper corners
    carry less) it stays inside every cone whenever their total cone holds the total friction.
    wf: w0 + W fixed, fixed: the slipping bounded rows' impulses (_polish). t, u, weight (m,), d2 (n,), perm:
    scratch; K, G: (m, m) each (K holds the system on return)."""
    m = w0.shape[0]
    _system(W, wf, rows, c1, c2, n, K, b)
    total, count = 0.0, 0
    for i in range(m):
        weight[i] = -1.0
    for k in range(kind.shape[0]):
        f = first[k]
        if (kind[k] == PLANAR or kind[k] == SPATIAL) and state[k] == STICK:
            pn = max(cand[f], 0.0)
            weight[f + 1] = mu[k] * pn
            if kind[k] == SPATIAL:
                weight[f + 2] = mu[k] * pn
            total += mu[k] * pn
            count += 1
    if count == 0 or not total > 0.0:
        return False
    mean = total / count
    for j in range(n):
        r = int(rows[j])
        d2[j] = weight[r] if weight[r] >= 0.0 else mean
    for j in range(n):                      # x = D z, z the least-norm solution of (K D) z = b, D = D2^1/2: by QR,
        d2[j] = math.sqrt(d2[j])            # not through K D2 K (its condition number squared)
        for i in range(n):
            K[i, j] *= d2[j]
    rank = qr_factor(K, b, n, t, u, G[0], perm, y, weight)
    qr_solution(K, b, y, n, rank, G[0], perm, t, bool(False), weight)     # (bool(): one qr_solution, as _settle's)
    _system(W, wf, rows, c1, c2, n, K, b)
    for i in range(m):
        cand[i] = fixed[i]
    for j in range(n):
        cand[int(rows[j])] = d2[j] * y[j]
    for i in range(m):
        w[i] = w0[i] + dot(W[i], cand, 0, m)
    return _holds(kind, first, mu, state, direction, cand, w, rows, n, tol_v)


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
        if kind[k] == BOUNDED:                      # held at the bound against the slip, or inside it and stuck
            if s == SLIP_POS:
                ok = w[f] >= -tol_v
            elif s == SLIP_NEG:
                ok = w[f] <= tol_v
            else:
                ok = abs(P[f]) <= mu[k] + tol_p
        elif s == OPEN:
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

