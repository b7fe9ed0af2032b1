"""The right-hand side of a flow, its multipliers, the projection after a step and the impact map.

Every function takes the compiled Model `model` and its Work `w` (model.py), then t, x (state),
u (inputs), p (parameters) and d (discrete states). The state is x = (q, v, sigma): NQ coordinates,
NV speeds, NS nonholonomic signals; M dv/dt = G + A^T lam, with A the active constraint rows of
the flow. The constraint terms live in the scratch S (layout.py).
"""

import math

import numpy as np

from .compiler import jit
from .linalg import (add_rows_transposed, cholesky, correction, ltdl, ltdl_solve, solve_gram, solve_lower, solve_upper,
                     whiten)
from .active import select_rows
from .model import call
from .slipping import held_direction, slip_rows, solve_slipping
from .sparse_rows import (add_rows_transposed_sparse, correction_sparse, rows_times, solve_gram_sparse, tree_factor,
                          tree_lower, tree_times, tree_upper, whiten_rows)
from .status import BAUMGARTE, DEPENDENT, HOLD, IDEAL, OK, PAINLEVE, SINGULAR_MASS, SLIP_TINY


@jit
def rhs_mode_into(model, w, t, x, u, p, d, flow, xdot, mode, slips=True):
    """xdot = f(t, x) in `flow`: dq/dt = v[:NQ], dv/dt, dsigma/dt (in w's M, G and S). Returns a status (OK = 0).

    dv/dt = a + M^-1 A^T lam with a = M^-1 G and A the rows active in the flow with the contacts' modes in d
    (active.select_rows, into w); `mode` says how lam is found (see constraint_force, slipping_force). slips:
    True, or None for a model without jumps (NJ = 0, hence no contacts: no row of it ever slips), which then
    compiles without the slipping contacts' solve (Numba prunes the branch, as advance's on `events`).
    """
    M, G, S = w.M, w.G, w.S
    if select_rows(model, w, flow, d) > 0:
        status = whitened_equations(model, t, x, u, p, d, M, G, S)
        if status == OK:
            if slips is not None and w.nactive[2]:
                status = slipping_force(model, w, p, d, mode, M, G, S)
            else:
                status = constraint_force(model, w, p, d, mode, M, G, S)
            upper(model, M, G)
    else:
        status = free_acceleration(model, t, x, u, p, d, M, G)
    if status != OK:
        return status
    return state_rates(model, t, x, u, p, d, G, xdot)


@jit
def rhs_free_into(model, w, t, x, u, p, d, xdot):
    """rhs_mode_into of a model without constraint rows (NC = 0: no flow selects any, whatever its mode and d), with
    the same operations in the same order; so an integrator of such a model compiles without the constrained
    solves (integrator.advance's `free`)."""
    M, G = w.M, w.G
    status = free_acceleration(model, t, x, u, p, d, M, G)
    if status != OK:
        return status
    return state_rates(model, t, x, u, p, d, G, xdot)


@jit(inline="always")
def free_acceleration(model, t, x, u, p, d, M, G):
    """G[:NV] <- a = M^-1 G at (t, x), no constraint force; a status."""
    nv = model.nv
    if model.nb > 0:                    # a by the articulated-body algorithm (Featherstone 2008), no M
        call(model.forward_dynamics, (t, x, u, p, d, M, G))
        status = OK
        for i in range(nv):             # (a singular articulated inertia divides by zero)
            if not math.isfinite(G[i]):
                status = SINGULAR_MASS
    elif model.nt > 0:                  # a = M^-1 G along the tree of M (LTDL, Featherstone 2005)
        call(model.dynamics, (t, x, u, p, d, M, G))
        status = OK if ltdl(M, model.mass_parent, model.mass_order, nv, 0.0) else SINGULAR_MASS
        if status == OK:
            ltdl_solve(M, model.mass_parent, model.mass_order, G, nv)
    else:
        call(model.dynamics, (t, x, u, p, d, M, G))
        status = OK if cholesky(M, nv, 0.0) else SINGULAR_MASS
        if status == OK:                # a = M^-1 G (ANDY eq. 8)
            solve_lower(M, G, nv)
            solve_upper(M, G, nv)
    return status


@jit(inline="always")
def state_rates(model, t, x, u, p, d, G, xdot):
    """xdot = (v[:NQ], a = G[:NV], the signals' rates); OK."""
    nq, nv = model.nq, model.nv
    for i in range(nq):
        xdot[i] = x[nq + i]
    for i in range(nv):
        xdot[nq + i] = G[i]
    if model.ns > 0:
        call(model.signal_rates, (t, x, u, p, d, xdot))
    return OK


@jit(inline="always")
def sparse(model):
    """Whether the model's constrained flows are solved along the tree of M and the rows' sparsity (sparse_rows.py,
    chosen by andyc/symbolic/sparse_rows.py) rather than densely (linalg.py)."""
    return model.row_ptr.shape[0] > 0


@jit(inline="always")
def factor(model, M):
    """M <- a square root R of M = R^T R (the dense path's R = L^T of cholesky, or sparse_rows.tree_factor's);
    False when M is not positive definite."""
    if sparse(model):
        return tree_factor(model, M)
    return cholesky(M, model.nv, 0.0)


@jit(inline="always")
def lower(model, M, b):
    """b <- R^-T b, M factored by `factor`."""
    if sparse(model):
        tree_lower(model, M, b)
    else:
        solve_lower(M, b, model.nv)


@jit(inline="always")
def upper(model, M, b):
    """b <- R^-1 b, M factored by `factor`."""
    if sparse(model):
        tree_upper(model, M, b)
    else:
        solve_upper(M, b, model.nv)


@jit(inline="always")
def whiten_flow(model, w, M, m):
    """C = A R^-1 over the first m active rows (w.active, active.select_rows), into S's C block."""
    if sparse(model):
        whiten_rows(model, M, w.S, w.active, 0, m)
    else:
        whiten(model, M, w.S, w.active, int(0), m)      # (int(): the impact's k is an int64, not the literal 0)


@jit(inline="always")
def solve_flow_gram(model, w, m, least_norm):
    """y <- (C C^T)^+ y over the first m active rows (linalg.solve_gram; sparse_rows.solve_gram_sparse)."""
    least_norm = bool(least_norm)       # (a literal True would compile a copy of its own: linalg.correction)
    if sparse(model):
        return solve_gram_sparse(model, w.S, w.active, int(0), m, least_norm, w.envelope)
    return solve_gram(model, w.S, m, least_norm)


@jit(inline="always")
def add_flow_rows(model, w, m, scale, out):
    """out += scale C^T y over the first m active rows."""
    if sparse(model):
        add_rows_transposed_sparse(model, w.S, w.active, 0, m, scale, out)
    else:
        add_rows_transposed(model, w.S, m, scale, out)


@jit(inline="always")
def whitened_equations(model, t, x, u, p, d, M, G, S):
    """M <- R (M = R^T R, see factor), G <- g = R^-T G and every row's terms into S, from one evaluation
    that shares their subexpressions (dynamics_constraints); returns a status."""
    call(model.dynamics_constraints, (t, x, u, p, d, M, G, S))
    if not factor(model, M):
        return SINGULAR_MASS
    lower(model, M, G)
    return OK


@jit(inline="always")
def constraint_system(model, w, L, g):
    """C = A L^-T and y = -kappa - C g (= -kappa - A M^-1 G for g = L^-1 G) over the active rows, into S;
    returns their number."""
    S, nr, nv, rows = w.S, w.nactive[0], model.nv, w.active
    c0, y0, kappa = model.s_c, model.s_y, model.s_kappa
    whiten_flow(model, w, L, nr)
    if sparse(model):
        rows_times(model, S, rows, 0, nr, g, S[y0])
        for r in range(nr):
            S[y0, r] = -S[kappa, rows[0, r]] - S[y0, r]
        return nr
    for r in range(nr):
        s = -S[kappa, rows[0, r]]
        for i in range(nv):
            s -= S[c0 + r, i] * g[i]
        S[y0, r] = s
    return nr


@jit(inline="always")
def constraint_force(model, w, p, d, mode, L, g, S):
    """g <- g + C^T lam over the active rows (w), in whitened speeds: with M = L L^T and g = L^-1 G on entry,
    dv/dt = L^-T g on return. Needs A, kappa (and for BAUMGARTE phi, c) in S; returns a status.

    With C = A L^-T and y = -kappa - C g (= -kappa - A a, a = M^-1 G), so that C C^T = A M^-1 A^T:
      IDEAL      lam = (C C^T)^+ y, the least-norm force of any rank (C^T lam = C^+ y)
      LAGRANGE   lam = (C C^T)^-1 y                           (ANDY eq. 12)
      BAUMGARTE  LAGRANGE's lam - (K_s phi + K_d c)           (ANDY eq. 15)
    """
    nr = constraint_system(model, w, L, g)
    if solve_flow_gram(model, w, nr, mode == IDEAL) < 0:
        return DEPENDENT
    if mode == BAUMGARTE:
        baumgarte(model, w, p, nr)
    add_flow_rows(model, w, nr, 1.0, g)
    return OK


@jit(inline="always")
def slipping_force(model, w, p, d, mode, L, g, S):
    """constraint_force where a contact slips (w.nactive[2]): its normal force carries Coulomb's friction, so the
    forces are B^T lam with B != A (slip_rows: D = B L^-T), lam = (C D^T)^+ y and g <- g + D^T lam (Pfeiffer &
    Glocker 1996, ch. 5); BAUMGARTE's terms as there."""
    nr = constraint_system(model, w, L, g)
    slip_rows(model, w, p, d, L, nr)
    if not solve_slipping(model, w, nr):
        return PAINLEVE
    if mode == BAUMGARTE:
        baumgarte(model, w, p, nr)
    for i in range(model.nv):       # g += D^T lam: a slipping contact's normal force carries its friction
        s = 0.0
        for r in range(nr):
            s += S[model.s_w + r, i] * S[model.s_y, r]
        g[i] += s
    return OK


@jit(inline="always")
def baumgarte(model, w, p, nr):
    """lam <- lam - (K_s phi + K_d c) over the active rows, lam in S's y row (ANDY eq. 15)."""
    S = w.S
    call(model.constraint_gains, (p, S))
    y0, ks, kd = model.s_y, model.s_ks, model.s_kd
    for r in range(nr):
        i = w.active[0, r]
        S[y0, r] -= S[kd, i] * S[model.s_cv, i]
        if i < model.nh:
            S[y0, r] -= S[ks, i] * S[model.s_phi, i]


@jit
def slip_direction(model, w, t, x, u, p, d, flow, h, mode):
    """At a step's start in `flow`: each contact with spatial friction slipping there gets its slip's direction,
    s / |s|, into its discrete states (FLOW_SLIP_DIR: d[k], d[k + 1]), unless |s| <= SLIP_TINY (then they keep
    the direction the runtime set: a slip from rest). Returns whether the flow has such a contact (the caller then
    re-evaluates the stop's guard, s . d).

    With a fixed step h > 0 it may hold a direction over the step instead (d[k + 2] = 1, slip_unit): the
    direction relaxes towards the slip at the rate mu lam_n |J_t M^-1 J_t^T| / |s| (the friction's pull on a
    sideways slip, over the slip), which near |s| = 0 is far beyond an explicit step's stability bound. Where h
    times that rate exceeds HOLD, the step holds the direction in which an implicit (backward Euler) step of the
    slip ends, which is stable: slipping.held_direction, from s + h a_free, a_free the slip's acceleration less
    the friction's (a_free = a + mu lam_n G d_ref, G = J_t M^-1 J_t^T, d_ref the direction held in the evaluation).
    A slip whose implicit step ends (the friction that stops it inside the cone) holds d_ref to the stop's event,
    as a planar slip keeps its sign to its stop. A slip whose acceleration
    keeps its direction (a ball's; a box sliding straight; a slip started at the cone's edge, a = 0) keeps d_ref to
    rounding, whatever G's anisotropy; one that turns (a block across a slope) is followed to first order over the
    few steps before it stops, or after it starts."""
    found = False
    S, nq, nv = w.S, model.nq, model.nv
    for r in range(select_rows(model, w, flow, d)):
        k = w.active[3, r] - 1
        if k < 0:
            continue
        found = True
        call(model.constraints_into, (t, x, u, p, d, S))
        row = w.active[1, r] - 1
        s1, s2 = S[model.s_cv, row], S[model.s_cv, row + 1]
        n = math.sqrt(s1 * s1 + s2 * s2)
        if n > SLIP_TINY:
            d[k] = s1 / n
            d[k + 1] = s2 / n
        d[k + 2] = 0.0
        if h <= 0.0:
            continue
        d[k + 2] = 1.0                  # (evaluated holding it, as the step would)
        if rhs_mode_into(model, w, t, x, u, p, d, flow, w.xdot, mode) != OK:
            continue
        z1, z2 = S[model.s_dv, :nv], S[model.s_r, :nv]      # J_t L^-T, whitened with M's factor L (linalg.whiten)
        for i in range(nv):
            v1, v2 = S[model.s_a + row, i], S[model.s_a + row + 1, i]
            for m in range(i):
                v1 -= w.M[i, m] * z1[m]
                v2 -= w.M[i, m] * z2[m]
            z1[i] = v1 * w.M[i, i]
            z2[i] = v2 * w.M[i, i]
        g11, g12, g22 = 0.0, 0.0, 0.0
        a1, a2 = S[model.s_kappa, row], S[model.s_kappa, row + 1]      # the slip's acceleration, A dv/dt + kappa
        for i in range(nv):
            g11 += z1[i] * z1[i]
            g12 += z1[i] * z2[i]
            g22 += z2[i] * z2[i]
            a1 += S[model.s_a + row, i] * w.xdot[nq + i]
            a2 += S[model.s_a + row + 1, i] * w.xdot[nq + i]
        pull = S[model.s_e, w.active[2, r]] * S[model.s_y, r]       # mu lam_n
        if h * abs(pull) * (g11 + g22) <= HOLD * n:
            d[k + 2] = 0.0
            continue
        if pull <= 0.0:
            continue
        hp = h * pull
        f1 = s1 + h * a1 + hp * (g11 * d[k] + g12 * d[k + 1])      # s + h a_free
        f2 = s2 + h * a2 + hp * (g12 * d[k] + g22 * d[k + 1])
        slips, u1, u2 = held_direction(hp * g11, hp * g12, hp * g22, f1, f2)
        if slips:
            d[k] = u1
            d[k + 1] = u2
    return found


@jit
def multipliers(model, w, t, x, u, p, d, flow, lam, slips=True):
    """Multipliers lam (NC,) of the ideal constraint force A^T lam in `flow` (ANDY eq. 10, 12); NaN for rows
    not active. lam = (C C^T)^+ y (see constraint_force), the least-norm split when rows are redundant.
    Returns a status. slips: as rhs_mode_into's."""
    M, G, S = w.M, w.G, w.S
    select_rows(model, w, flow, d)
    status = whitened_equations(model, t, x, u, p, d, M, G, S)
    if status != OK:
        return status
    nr = constraint_system(model, w, M, G)
    if slips is not None and w.nactive[2]:
        slip_rows(model, w, p, d, M, nr)
        solve_slipping(model, w, nr)
    else:
        solve_flow_gram(model, w, nr, True)
    for r in range(model.nc):
        lam[r] = np.nan
    for r in range(nr):
        lam[w.active[0, r]] = S[model.s_y, r]
    return OK


@jit(inline="always")
def guard_value(model, w, k, t, x, u, p, d, flow):
    """The guard of jump k at (t, x) in `flow`. A guard that reads multipliers (JUMP_MULTIPLIERS[k]: a normal force
    reaching zero) gets them in w.lam, the ideal multipliers of the flow with the contacts' modes in d at (t, x)
    (see `multipliers`; this uses w's M, G and S); the others pay one table look-up."""
    if k < model.nj and model.jump_multipliers[k]:     # (a model without jumps is called with k = 0: a stub)
        multipliers(model, w, t, x, u, p, d, flow, w.lam)
    return call(model.guard, (k, t, x, u, p, d, w.lam))


@jit(inline="always")
def enabled_value(model, w, k, t, x, u, p, d, flow):
    """The enabling condition of jump k at (t, x) (>= 0: it may happen), with the multipliers as in guard_value."""
    if k < model.nj and model.jump_multipliers[k]:
        multipliers(model, w, t, x, u, p, d, flow, w.lam)
    return call(model.enabled, (k, t, x, u, p, d, w.lam))


@jit(inline="always")
def in_mode(model, k, flow, d):
    """Whether jump k leaves `flow` with the contacts' modes in d: its source is the flow (or every flow: -1, a
    contact's jump), and a contact's jump only in the modes it leaves (JUMP_MODE_STATE, JUMP_MODE_MASK)."""
    source = model.jump_source[k]
    if source >= 0 and source != flow:
        return False
    state = model.jump_mode_state[k]
    return state < 0 or (model.jump_mode_mask[k] >> int(d[state])) & 1 == 1


@jit
def normalize(model, x):
    """Put each quaternion signal back on the unit sphere (after an integration step)."""
    for k in model.quaternions:
        n = math.sqrt(x[k] ** 2 + x[k + 1] ** 2 + x[k + 2] ** 2 + x[k + 3] ** 2)
        x[k] /= n
        x[k + 1] /= n
        x[k + 2] /= n
        x[k + 3] /= n


@jit
def move(model, t, x, u, p, d, dq):
    """x <- x (+) dq: a small change of position dq, given in speed space (NV,).

    q += dq[:NQ]; signals move by their rates at speeds dq (eq. 4, to first order).
    """
    nq, nv = model.nq, model.nv
    if model.ns > 0:
        xt = x.copy()
        r1 = np.zeros(model.nx)
        r0 = np.zeros(model.nx)
        for i in range(nv):
            xt[nq + i] = dq[i]
        call(model.signal_rates, (t, xt, u, p, d, r1))
        for i in range(nv):
            xt[nq + i] = 0.0
        call(model.signal_rates, (t, xt, u, p, d, r0))
        for i in range(model.ns):
            x[nq + nv + i] += r1[nq + nv + i] - r0[nq + nv + i]
        normalize(model, x)
    for i in range(nq):
        x[i] += dq[i]


@jit(inline="always")
def correct_rows(model, w, nr, residual, L):
    """S's dv row <- the least M-norm change with A dv = -r over the first nr active rows, r the values of S's
    `residual` row (phi or cv) at those rows; L from `factor`."""
    S, rows, y0 = w.S, w.active, model.s_y
    whiten_flow(model, w, L, nr)
    for r in range(nr):
        S[y0, r] = -S[residual, rows[0, r]]
    if sparse(model):
        correction_sparse(model, L, S, rows, int(0), nr, w.envelope)     # (int(): as the impact's k, one copy)
    else:
        correction(model, L, S, nr)


@jit
def project(model, w, t, x, u, p, d, flow, constrain, e0, energy_tol):
    """After a step: quaternions to unit norm, then the Braun & Goldfarb corrections (Part II).

    With constrain (C = A L^-T over the flow's active rows at the step's end, M = L L^T):
      position (eq. 3)  x <- x (+) L^-T C_q^+ (-phi)
      velocity (eq. 4)  v <- v + L^-T C^+ (-c), at the corrected position
    With energy_tol >= 0, energy (eq. 5-6): with r = N L^T v, N = I - C^+ C the projector onto the
    constraints' null space, v <- v - L^-T r (E - e0 - W) / |r|^2 when |r|^2 (2T on the constraint
    manifold) exceeds energy_tol; W = the sum of x[NX:NX + NW], the work carried with the state (0 for a
    model on which nothing does work: the law E = e0). A flow with a declared law Phi_e (the leaf
    energy_law) takes r = N L^-1 dPhi_e/dv^T and the residual Phi_e - e0 instead: one Newton step on the law
    within the constraints (exact for a law linear in v). One pass, no iteration. Returns a status.
    """
    normalize(model, x)
    if not constrain and energy_tol < 0.0:
        return OK
    nq, nv = model.nq, model.nv
    M, G, S = w.M, w.G, w.S
    call(model.dynamics, (t, x, u, p, d, M, G))
    if not factor(model, M):
        return SINGULAR_MASS
    nr = select_rows(model, w, flow, d)
    constrain = constrain and nr > 0
    dv = S[model.s_dv, :nv]
    if constrain:
        nhr = w.nactive[1]
        if nhr > 0:
            call(model.constraints_into, (t, x, u, p, d, S))
            correct_rows(model, w, nhr, model.s_phi, M)
            move(model, t, x, u, p, d, dv)
        call(model.constraints_into, (t, x, u, p, d, S))
        correct_rows(model, w, nr, model.s_cv, M)
        for i in range(nv):
            x[nq + i] += dv[i]
    if energy_tol >= 0.0:
        r = S[model.s_r, :nv]
        # A declared law Phi_e of the flow (andyc.spec.energy_law): r = L^-1 dPhi_e/dv^T, its residual Phi_e - e0
        # (the run passes e0 = 0 there). Else the built-in E - e0 - W, whose gradient M v gives r = L^T v.
        law = call(model.energy_law, (flow, t, x, u, p, d, S[model.s_r]))
        if law == law:
            lower(model, M, r)
        elif sparse(model):
            tree_times(model, M, x[nq:nq + nv], r)
        else:
            for i in range(nv):            # r = L^T v (the factor's diagonal holds 1 / L_ii)
                s = x[nq + i] / M[i, i]
                for k in range(i + 1, nv):
                    s += M[k, i] * x[nq + k]
                r[i] = s
        if constrain:
            c0, y0 = model.s_c, model.s_y
            if sparse(model):          # y <- C r, for r <- r - C^+ C r
                rows_times(model, S, w.active, 0, nr, r, S[y0])
            else:
                for j in range(nr):
                    s = 0.0
                    for i in range(nv):
                        s += S[c0 + j, i] * r[i]
                    S[y0, j] = s
            solve_flow_gram(model, w, nr, True)
            add_flow_rows(model, w, nr, -1.0, r)
        rr = 0.0
        for i in range(nv):
            rr += r[i] * r[i]
        if rr > energy_tol:
            if law == law:
                residual = law - e0
            else:                      # the balance E = E0 + W (Braun & Goldfarb's energy law, W the work slots)
                residual = call(model.energy, (t, x, u, p, d)) - e0
                for i in range(model.nw):
                    residual -= x[model.nx + i]
            scale = -residual / rr
            for i in range(nv):
                r[i] *= scale
            upper(model, M, r)
            for i in range(nv):
                x[nq + i] += r[i]
    return OK


@jit
def impact(model, w, t, x, u, p, d, k):
    """The impact map of jump k over its impact rows J, restitution e (ANDY eq. 19 at e = 0).

    v+ = v- + M^-1 J^T Lambda with J v+ = -e J v-:  v+ = v- - (1 + e) L^-T C^+ c-,
    C = J L^-T, c- the rows' velocity residual before. Returns a status.
    """
    nq, nv = model.nq, model.nv
    M, G, S = w.M, w.G, w.S
    call(model.dynamics, (t, x, u, p, d, M, G))
    if not cholesky(M, nv, 0.0):
        return SINGULAR_MASS
    nr = model.impact_nrows[k]
    call(model.constraints_into, (t, x, u, p, d, S))
    call(model.restitution, (p, S))
    e = S[model.s_e, k]
    whiten(model, M, S, model.impact_rows, k, nr)
    for r in range(nr):
        S[model.s_y, r] = -(1.0 + e) * S[model.s_cv, model.impact_rows[k, r]]
    correction(model, M, S, nr)
    for i in range(nv):
        x[nq + i] += S[model.s_dv, i]
    return OK


@jit
def jump(model, w, k, t, x, u, p, d):
    """Apply jump k at (t, x), x and d in place: its resets, then its impact map. Returns a status.
    (The user's function in <name>_jumps.py comes after, from Python.)"""
    call(model.reset, (k, t, x, u, p, d))
    if model.impact_nrows[k] > 0:
        return impact(model, w, t, x, u, p, d, k)
    return OK
