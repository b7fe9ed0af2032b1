"""The RK4 step's tangent and the projection's, for runs with sensitivities (andyc.runtime.sensitivities).

The model's <name>_derivatives.py (andyc/codegen/derivatives.py) holds its exact first derivatives over
W = (x, d, p, t), flow_terms, signal_terms and energy_terms, and binds them to these algorithms: each function
here that evaluates the model takes those functions as its first arguments and is inlined (Numba's inline="always")
into the model's own functions, which Numba caches: a function passed to a call that is not inlined is a pointer
to a Python object in the compiled code, and Numba will not cache such code. The tangent T (NW, k)
carries the derivatives of the state along k directions; its last row is the time's.

    rates            f and F = df/dW in a flow
    rk4_tangent      the RK4 step (the integrator's tableau, rk4.py) and its tangent
    project_tangent  the projection method's corrections after a step (Braun & Goldfarb, Part II, eq. 3-6), and
                     their tangent
    step_tangent     both; tangent_steps: the grid steps of a stretch without jumps, in one call

The saddle-point systems [[M, -A^T], [A, 0]] are solved by M's Cholesky factor (dense_solves' factor) and the
Schur complement A M^-1 A^T; the rows must be independent (dependent ones raise).
"""

import math

import numpy as np

from .compiler import jit
from .dense_solves import cholesky_factor
from . import rk4


@jit
def cholesky(M):
    """The lower factor L of M = L L^T in L's lower triangle (dense_solves' factor; raises where M is not positive
    definite: a singular mass matrix or dependent constraint rows)."""
    L = M.copy()
    if not cholesky_factor(L, M.shape[0], 0.0):
        raise ValueError("sensitivities: a singular matrix (dependent constraint rows?)")
    return L


@jit
def solve_columns(L, B):
    """(L L^T)^-1 B for B (n, k) (solve_in_place on a copy)."""
    n = B.shape[0]
    inv = np.empty(n)
    for i in range(n):
        inv[i] = 1.0 / L[i, i]
    X = B.copy()
    solve_in_place(L, inv, X)
    return X


@jit
def saddle_factor(L, A, rows):
    """(Y, W) for the saddle-point system [[M, -A^T], [A, 0]] over the rows `rows` of A, M = L L^T:
    Y = M^-1 A^T (NV, m) and W the Cholesky factor of A M^-1 A^T (raises on dependent rows)."""
    nv, m = L.shape[0], rows.shape[0]
    At = np.zeros((nv, m))
    for r in range(m):
        At[:, r] = A[rows[r]]
    Y = solve_columns(L, At)
    G = np.zeros((m, m))
    for r in range(m):
        for j in range(m):
            s = 0.0
            for i in range(nv):
                s += A[rows[r], i] * Y[i, j]
            G[r, j] = s
    return Y, cholesky(G)


@jit
def saddle_solve(L, Y, W, A, rows, r1, r2):
    """(a, lam) with M a - A^T lam = r1 and A a = r2 over the rows `rows` (columns of r1 (NV, k), r2 (m, k)):
    z = M^-1 r1, lam = (A M^-1 A^T)^-1 (r2 - A z), a = z + M^-1 A^T lam."""
    nv, k = r1.shape
    m = rows.shape[0]
    z = solve_columns(L, r1)
    rhs = r2.copy()
    for r in range(m):
        for c in range(k):
            s = rhs[r, c]
            for i in range(nv):
                s -= A[rows[r], i] * z[i, c]
            rhs[r, c] = s
    lam = solve_columns(W, rhs)
    return z + product(Y, lam), lam


@jit
def times_vector(dX, rows, a):
    """sum_j dX[rows[r], j, :] a[j] (m, NW): a derivative (rows of) dM or dA applied to a."""
    m, nw = rows.shape[0], dX.shape[2]
    out = np.zeros((m, nw))
    for r in range(m):
        row = rows[r]
        for j in range(a.shape[0]):
            aj = a[j]
            if aj != 0.0:
                for w in range(nw):
                    out[r, w] += dX[row, j, w] * aj
    return out


@jit
def transposed_times(dA, rows, lam, nv):
    """sum_r dA[rows[r], :, :] lam[r] (NV, NW): the derivative of A^T lam at fixed lam."""
    nw = dA.shape[2]
    out = np.zeros((nv, nw))
    for r in range(rows.shape[0]):
        row, lr = rows[r], lam[r]
        for i in range(nv):
            for w in range(nw):
                out[i, w] += dA[row, i, w] * lr
    return out


@jit
def product(A, B):
    """A @ B by loops (any of the sizes may be 0)."""
    n, m = A.shape
    k = B.shape[1]
    out = np.zeros((n, k))
    for i in range(n):
        for j in range(m):
            aij = A[i, j]
            if aij != 0.0:
                for c in range(k):
                    out[i, c] += aij * B[j, c]
    return out


@jit
def all_rows(n):
    return np.arange(n)


@jit
def accelerations(M, dM, G, dG, A, dA, kappa, dkappa, rows):
    """(a, da/dW): without rows a = M^-1 G, da = M^-1 (dG - dM a); with the active rows `rows` of A, the
    saddle-point system [[M, -A^T], [A, 0]] [a; lam] = [G; -kappa] and its derivative (as
    andyc.symbolic.linearize), [[M, -A^T], [A, 0]] [da; dlam] = [dG - dM a + dA^T lam; -dkappa - dA a]. The rows
    must be independent (dependent ones raise)."""
    nv, nw, m = M.shape[0], dG.shape[1], rows.shape[0]
    L = cholesky(M)
    Y, W = saddle_factor(L, A, rows)
    r1 = np.zeros((nv, 1))
    r1[:, 0] = G
    r2 = np.zeros((m, 1))
    for r in range(m):
        r2[r, 0] = -kappa[rows[r]]
    a, lam = saddle_solve(L, Y, W, A, rows, r1, r2)
    a, lam = a[:, 0].copy(), lam[:, 0].copy()
    rhs1 = dG - times_vector(dM, all_rows(nv), a) + transposed_times(dA, rows, lam, nv)
    rhs2 = -times_vector(dA, rows, a)
    for r in range(m):
        rhs2[r] -= dkappa[rows[r]]
    return a, saddle_solve(L, Y, W, A, rows, rhs1, rhs2)[0]


@jit
def solve_in_place(L, inv, X):
    """X <- (L L^T)^-1 X (X (n, k)), inv the reciprocals of L's diagonal; rows updated along their columns."""
    n, k = X.shape
    for i in range(n):
        for j in range(i):
            lij = L[i, j]
            for c in range(k):
                X[i, c] -= lij * X[j, c]
        for c in range(k):
            X[i, c] *= inv[i]
    for i in range(n - 1, -1, -1):
        for j in range(i + 1, n):
            lji = L[j, i]
            for c in range(k):
                X[i, c] -= lji * X[j, c]
        for c in range(k):
            X[i, c] *= inv[i]


@jit
def accelerations_along(M, dM, G, dG, A, dA, kappa, dkappa, rows, Ts):
    """(a, da Ts): as `accelerations`, the derivative along the columns of the tangent Ts (NW, k) only: each row of
    the right-hand side [dG - dM a + dA^T lam; -dkappa - dA a] contracted with Ts as it is made, then the
    saddle-point system solved for k columns (by M's Cholesky factor and the Schur complement A M^-1 A^T), in one
    function with few arrays (this runs at every RK4 stage)."""
    nv, m, nw, k = M.shape[0], rows.shape[0], dG.shape[1], Ts.shape[1]
    L = cholesky(M)
    inv = np.empty(nv)
    for i in range(nv):
        inv[i] = 1.0 / L[i, i]
    Y, W = saddle_factor(L, A, rows)    # M^-1 A^T, and the factor of A M^-1 A^T
    winv = np.empty(m)
    for r in range(m):
        winv[r] = 1.0 / W[r, r]
    a = np.empty((nv, 1))               # a = z + Y lam, z = M^-1 G, lam = S^-1 (-kappa - A z)
    for i in range(nv):
        a[i, 0] = G[i]
    solve_in_place(L, inv, a)
    lam = np.empty((m, 1))
    for r in range(m):
        s = -kappa[rows[r]]
        for i in range(nv):
            s -= A[rows[r], i] * a[i, 0]
        lam[r, 0] = s
    solve_in_place(W, winv, lam)
    for i in range(nv):
        for r in range(m):
            a[i, 0] += Y[i, r] * lam[r, 0]
    R = np.zeros((nv + m, k))           # the right-hand side along Ts
    row = np.empty(nw)
    for i in range(nv + m):
        if i < nv:
            for w in range(nw):
                row[w] = dG[i, w]
            for j in range(nv):
                aj = a[j, 0]
                if aj != 0.0:
                    for w in range(nw):
                        row[w] -= dM[i, j, w] * aj
            for r in range(m):
                lr = lam[r, 0]
                for w in range(nw):
                    row[w] += dA[rows[r], i, w] * lr
        else:
            rr = rows[i - nv]
            for w in range(nw):
                row[w] = -dkappa[rr, w]
            for j in range(nv):
                aj = a[j, 0]
                if aj != 0.0:
                    for w in range(nw):
                        row[w] -= dA[rr, j, w] * aj
        for w in range(nw):
            rw = row[w]
            if rw != 0.0:
                for c in range(k):
                    R[i, c] += rw * Ts[w, c]
    Z = R[:nv].copy()                   # da = Z + Y dlam, Z = M^-1 R1, dlam = S^-1 (R2 - A Z)
    solve_in_place(L, inv, Z)
    D = R[nv:].copy()
    for r in range(m):
        for c in range(k):
            s = D[r, c]
            for i in range(nv):
                s -= A[rows[r], i] * Z[i, c]
            D[r, c] = s
    solve_in_place(W, winv, D)
    for i in range(nv):
        for r in range(m):
            yr = Y[i, r]
            for c in range(k):
                Z[i, c] += yr * D[r, c]
    return a[:, 0].copy(), Z


@jit(inline="always")
def rates(flow_terms, signal_terms, t, x, u, p, d, rows, nq):
    """f(t, x) and F = df/dW (nx, NW) in the flow of active rows `rows` (dq/dt = the coordinates' speeds, the
    accelerations, the signals' rates)."""
    M, dM, G, dG, A, dA, kappa, dkappa, _, _, _, _ = flow_terms(t, x, u, p, d)
    a, da = accelerations(M, dM, G, dG, A, dA, kappa, dkappa, rows)
    nx, nv = x.shape[0], M.shape[0]
    f = np.zeros(nx)
    F = np.zeros((nx, dG.shape[1]))
    for i in range(nq):
        f[i] = x[nq + i]
        F[i, nq + i] = 1.0
    f[nq:nq + nv] = a
    F[nq:nq + nv] = da
    if nx > nq + nv:
        s, ds = signal_terms(t, x, u, p, d)
        f[nq + nv:] = s
        F[nq + nv:] = ds
    return f, F


@jit(inline="always")
def rk4_tangent(flow_terms, signal_terms, t, h, x, u, p, d, rows, T, dh, nq):
    """(x', T'): the RK4 step of size h from (t, x) and its tangent, T (NW, k) at the start and dh (k,) the tangent
    of h, stage by stage: dK_i = F(stage i) [dx + a_i (dh K_(i-1) + h dK_(i-1)); dd; dp; dt + c_i dh],
    dx' = dx + dh sum b_i K_i + h sum b_i dK_i, over the tableau of rk4.py (the integrator's step)."""
    nx, ncol, last = x.shape[0], T.shape[1], T.shape[0] - 1    # last: the time's row of T
    Ts = T.copy()                       # the stage's tangent: d, p rows as at the start
    sum_k, sum_dk = np.zeros(nx), np.zeros((nx, ncol))
    k, dk = np.zeros(nx), np.zeros((nx, ncol))
    xs = x.copy()
    for s in range(rk4.STAGES):
        c = rk4.C[s]
        if s > 0:
            a = rk4.A[s]
            for i in range(nx):
                xs[i] = x[i] + a * h * k[i]
                for j in range(ncol):
                    Ts[i, j] = T[i, j] + a * (k[i] * dh[j] + h * dk[i, j])
            for j in range(ncol):
                Ts[last, j] = T[last, j] + c * dh[j]
        M, dM, G, dG, A, dA, kappa, dkappa, _, _, _, _ = flow_terms(t + c * h, xs, u, p, d)
        acc, da = accelerations_along(M, dM, G, dG, A, dA, kappa, dkappa, rows, Ts)
        nv = acc.shape[0]
        for i in range(nq):             # dq/dt = v: F's rows of q pick the speeds' tangent
            k[i] = xs[nq + i]
            dk[i] = Ts[nq + i]
        k[nq:nq + nv] = acc
        dk[nq:nq + nv] = da
        if nx > nq + nv:                # the signals' rates
            sr, dsr = signal_terms(t + c * h, xs, u, p, d)
            k[nq + nv:] = sr
            dk[nq + nv:] = product(dsr, Ts)
        sum_k += rk4.B[s] * k
        sum_dk += rk4.B[s] * dk
    out = T.copy()
    for i in range(nx):
        for j in range(ncol):
            out[i, j] = T[i, j] + sum_k[i] / rk4.DIVISOR * dh[j] + h / rk4.DIVISOR * sum_dk[i, j]
    for j in range(ncol):
        out[last, j] = T[last, j] + dh[j]
    return x + h / rk4.DIVISOR * sum_k, out


@jit
def normalize_tangent(x, T, quats):
    """Each quaternion (x[k:k + 4], k in quats) to unit norm, and its tangent: d(s/|s|) = (ds - n (n . ds))/|s|."""
    ncol = T.shape[1]
    for k in quats:
        norm = math.sqrt(x[k] ** 2 + x[k + 1] ** 2 + x[k + 2] ** 2 + x[k + 3] ** 2)
        for i in range(4):
            x[k + i] /= norm
        for j in range(ncol):
            dot = 0.0
            for i in range(4):
                dot += x[k + i] * T[k + i, j]
            for i in range(4):
                T[k + i, j] = (T[k + i, j] - x[k + i] * dot) / norm


@jit(inline="always")
def project_tangent(flow_terms, signal_terms, energy_terms, t, x, u, p, d, rows, nhr, T, quats, etol, target,
                    dtarget, nq):
    """(x', T'): the projection after a step (andyc_numerics/dynamics.py: project) and its tangent, T (NW, k) the
    tangent of (x, d, p, t) before it; rows: the flow's active rows (holonomic first, nhr of them; none: no
    constraint correction), quats: the quaternions' indices in x (normalized), etol >= 0: the energy correction to
    `target` (its tangent dtarget (k,)). The corrections, as the numerics make them (Braun & Goldfarb Part II), with
    M = M(x) at the step's end, before them:

      position (eq. 3)  q1 = q + delta,  [[M, -A_h^T], [A_h, 0]] [delta; mu] = [0; -phi],   A_h, phi at x
                        (signals move by their rates at the speeds delta, then to unit norm)
      velocity (eq. 4)  v1 = v + eps,    [[M, -A^T], [A, 0]] [eps; nu] = [0; -c],          A, c at x1 = (q1, v)
      energy (eq. 5-6)  v2 = v1 - (E(x2) - target) w / (w^T M w),  [[M, -A^T], [A, 0]] [w; kap] = [M v1; 0]
                        (w = v1 without rows: M^-1 A^T (A M^-1 A^T)^-1 A v1 taken off, i.e. L^-T N L^T v1), when
                        w^T M w = |N L^T v1|^2 > etol.

    Each linear system differentiated, by columns of the tangent: [[M, -A^T], [A, 0]] [da; dlam] =
    [dr1 - dM a + dA^T lam; dr2 - dA a], every derivative taken at its own point (dM at x, dA at x1) and contracted
    with that point's tangent (T at x, T1 at x1)."""
    nx, k = x.shape[0], T.shape[1]
    x, T = x.copy(), T.copy()
    normalize_tangent(x, T, quats)
    nr = rows.shape[0]
    if nr == 0 and etol < 0.0:
        return x, T
    M, dM, _, _, A, dA, _, _, c, dc, phi, dphi = flow_terms(t, x, u, p, d)
    nv = M.shape[0]
    v0, v1 = nq, nq + nv
    T0 = T.copy()
    T1 = T0
    L = cholesky(M)
    everything = all_rows(nv)
    Y, W = np.zeros((nv, 0)), np.zeros((0, 0))
    if nr > 0:
        if nhr > 0:
            h = rows[:nhr].copy()
            Y, W = saddle_factor(L, A, h)
            r2 = np.zeros((nhr, 1))
            for r in range(nhr):
                r2[r, 0] = -phi[h[r]]
            delta, mu = saddle_solve(L, Y, W, A, h, np.zeros((nv, 1)), r2)
            delta, mu = delta[:, 0].copy(), mu[:, 0].copy()
            rhs1 = (transposed_times(dA, h, mu, nv) - times_vector(dM, everything, delta)) @ T0
            rhs2 = -times_vector(dA, h, delta)
            for r in range(nhr):
                rhs2[r] -= dphi[h[r]]
            ddelta = saddle_solve(L, Y, W, A, h, rhs1, rhs2 @ T0)[0]
            if nx > v1:                 # the signals move by their rates at the speeds delta (numerics: move)
                xt = x.copy()
                xt[v0:v1] = delta
                s1, ds1 = signal_terms(t, xt, u, p, d)
                Tt = T0.copy()
                Tt[v0:v1] = ddelta
                xt[v0:v1] = 0.0
                s0, ds0 = signal_terms(t, xt, u, p, d)
                Tz = T0.copy()
                Tz[v0:v1] = 0.0
                x[v1:] += s1 - s0
                T[v1:nx] += ds1 @ Tt - ds0 @ Tz
                normalize_tangent(x, T, quats)
            x[:nq] += delta[:nq]
            T[:nq] += ddelta[:nq]
            _, _, _, _, A, dA, _, _, c, dc, _, _ = flow_terms(t, x, u, p, d)
        T1 = T.copy()
        Y, W = saddle_factor(L, A, rows)
        r2 = np.zeros((nr, 1))
        for r in range(nr):
            r2[r, 0] = -c[rows[r]]
        eps, nu = saddle_solve(L, Y, W, A, rows, np.zeros((nv, 1)), r2)
        eps, nu = eps[:, 0].copy(), nu[:, 0].copy()
        rhs1 = transposed_times(dA, rows, nu, nv) @ T1 - times_vector(dM, everything, eps) @ T0
        rhs2 = -times_vector(dA, rows, eps)
        for r in range(nr):
            rhs2[r] -= dc[rows[r]]
        x[v0:v1] += eps
        T[v0:v1] += saddle_solve(L, Y, W, A, rows, rhs1, rhs2 @ T1)[0]
    if etol >= 0.0:
        vel = x[v0:v1].copy()
        dvel = T[v0:v1].copy()
        if nr > 0:
            r1 = np.zeros((nv, 1))
            r1[:, 0] = M @ vel
            w, kap = saddle_solve(L, Y, W, A, rows, r1, np.zeros((nr, 1)))
            w, kap = w[:, 0].copy(), kap[:, 0].copy()
            rhs1 = (times_vector(dM, everything, vel - w) @ T0 + M @ dvel
                    + transposed_times(dA, rows, kap, nv) @ T1)
            dw = saddle_solve(L, Y, W, A, rows, rhs1, -times_vector(dA, rows, w) @ T1)[0]
        else:
            w, dw = vel, dvel
        Mw = M @ w
        rr = w @ Mw
        if rr > etol:
            E, dE = energy_terms(t, x, u, p, d)
            wdMw = np.zeros(dM.shape[2])    # w^T dM w
            for i in range(nv):
                for j in range(nv):
                    wdMw += w[i] * w[j] * dM[i, j]
            drr = 2.0 * (Mw @ dw) + wdMw @ T0
            g = (E - target) / rr
            dg = (dE @ T - dtarget) / rr - (E - target) / (rr * rr) * drr
            x[v0:v1] -= g * w
            for i in range(nv):
                for j in range(k):
                    T[v0 + i, j] -= g * dw[i, j] + w[i] * dg[j]
    return x, T


@jit(inline="always")
def step_tangent(flow_terms, signal_terms, energy_terms, t, h, x, u, p, d, rows, T, dh, nq, project, prows, nhr,
                 quats, etol, target, dtarget):
    """rk4_tangent, then with `project` project_tangent at t + h over the rows `prows` (see there)."""
    x, T = rk4_tangent(flow_terms, signal_terms, t, h, x, u, p, d, rows, T, dh, nq)
    if project:
        x, T = project_tangent(flow_terms, signal_terms, energy_terms, t + h, x, u, p, d, prows, nhr, T, quats, etol,
                               target, dtarget, nq)
    return x, T


@jit(inline="always")
def tangent_steps(flow_terms, signal_terms, energy_terms, t, x, u, p, d, rows, T, nq, project, prows, nhr, quats,
                  etol, target, dtarget, dt, i, i_end):
    """The grid steps from time t on step i (i dt <= t < (i + 1) dt) to the grid point i_end, and the tangent
    through them, in one call (as the compiled loop steps: andyc_numerics/integrator.py advance): each step ends on
    the grid, so h = t_next - t has the tangent -dt (the time row of T) and the time after it none."""
    last = T.shape[0] - 1               # the time's row of T
    while i < i_end:
        t_next = 0.0 + (i + 1) * dt
        h = t_next - t
        if h > 1e-14 * max(1.0, abs(t_next)):
            dh = -T[last].copy()
            x, T = step_tangent(flow_terms, signal_terms, energy_terms, t, h, x, u, p, d, rows, T, dh, nq, project,
                                prows, nhr, quats, etol, target, dtarget)
        T[last] = 0.0
        t = t_next
        i += 1
    return x, T
