# -- the integrator ---------------------------------------------------------------
# (andyc/templates/integrator.py, included verbatim: a fixed-step RK4 loop with
# event location over this module's functions, compiled and cached with them.)
#
# advance() steps along the grid t0 + i dt and returns after a block of steps or
# after a jump. Each step is classical RK4 on rhs_mode_into (mode IDEAL, LAGRANGE
# or BAUMGARTE), followed, with do_project, by `project` (quaternion norms; with
# constrain and energy_tol, the Braun & Goldfarb corrections).
#
# Events: after each step, the guards of the current flow's jumps are compared
# with their values at the step's start. A sign change in a jump's direction is
# located by root finding on the step, each trial time tau being a step of size
# tau from the step's start (so the located state is the method's own solution),
# to event_tol seconds (relative beyond 1 s). The earliest crossing whose
# enabling condition holds wins, ties going to the lower priority number; the
# jump (resets, impact) is applied at the near side of the final bracket, and
# the rest of the step is integrated by the next call, so the grid stays
# t0 + i dt. The caller applies the user's jump function and follows jumps
# that happen at once (instant).
#
# Inputs: every function here takes `inputs`, a compiled function
#     status = inputs(t, x, d, p, flow, u, data)
# that writes the inputs u at (t, x) (INPUTS_SIGNATURE: a first-class function
# type, so the integrator compiles once for every input source), and the
# `data` it reads; andyc's runtime compiles it from expressions, tables and
# controllers. It is called before each evaluation at a new (t, x); a nonzero
# status stops the run with INPUT_FAILED. inputs = data = None: the inputs are
# held, u as the caller set it for the flow. Numba then compiles the integrator
# without the calls (branches on `is not None` are pruned at compile time), so
# held inputs do not pay for carrying a function and an array down the call
# chain, about a tenth of a constrained step in reference counting.


@njit(cache=True, error_model="numpy")
def update_inputs(inputs, t, x, p, d, flow, u, data):
    """u at (t, x) when the inputs are driven (held: u stays as the caller set it); a status (INPUT_FAILED:
    `inputs` failed, its record in data says why)."""
    if inputs is not None:
        if inputs(t, x, d, p, flow, u, data) != 0:
            return INPUT_FAILED
    return OK


@njit(cache=True, error_model="numpy")
def rk4_step(mode, do_project, constrain, e0, energy_tol, t, h, x, inputs, u, data, p, d, flow, out, M, G, S, k, xt,
             scale):
    """out = the RK4 step of size h from (t, x), then projected; x is unchanged. Returns a status.

    Stage s evaluates at t + c_s h, x + c_s h k_(s-1), c = (0, 1/2, 1/2, 1). A step whose largest
    entry exceeds GROWTH_LIMIT times `scale` (the largest entry of the states so far, at least 1)
    is DIVERGED: motion that is followed at all never grows by orders of magnitude in one step; a
    diverging solution (a constraint turning singular, a step far past the method's stability
    bound) does, within a few steps. (Against the run's largest entry, not the step start's, so that
    a stiff oscillator whose speed is large where its position is small does not count as growth.)
    """
    nx = x.shape[0]
    for s in range(4):
        c = 0.0 if s == 0 else (1.0 if s == 3 else 0.5)
        for j in range(nx):
            xt[j] = x[j] if s == 0 else x[j] + c * h * k[s - 1, j]
        if inputs is not None:
            if inputs(t + c * h, xt, d, p, flow, u, data) != 0:
                return INPUT_FAILED
        status = rhs_mode_into(t + c * h, xt, u, p, d, flow, k[s], M, G, S, mode)
        if status != OK:
            return status
    total = 0.0
    grown = 0.0
    for j in range(nx):
        out[j] = x[j] + h / 6.0 * (k[0, j] + 2.0 * k[1, j] + 2.0 * k[2, j] + k[3, j])
        total += out[j]
        grown = max(grown, abs(out[j]))
    if not math.isfinite(total):
        return NONFINITE
    if grown > GROWTH_LIMIT * scale:
        return DIVERGED
    if do_project:
        if update_inputs(inputs, t + h, out, p, d, flow, u, data) != OK:
            return INPUT_FAILED
        return project(t + h, out, u, p, d, flow, constrain, e0, energy_tol, M, G, S)
    return OK


@njit(cache=True, error_model="numpy")
def crosses(direction, g_start, g_end):
    """Whether a guard going from g_start to g_end over a step crosses zero in `direction`."""
    if g_start > 0.0:
        return direction != RISING and g_end <= 0.0
    if g_start < 0.0:
        return direction != FALLING and g_end >= 0.0
    return False            # starting on zero: the instant check (see `instant`) decides


@njit(cache=True, error_model="numpy")
def locate(m, mode, do_project, constrain, e0, energy_tol, tol, t, h, x, inputs, u, data, p, d, flow,
           g_start, g_end, xb, xc, M, G, S, k, xt, counts, scale):
    """Root of guard m on the step (t, x) -> t + h, as a bracket [a, b] no wider than tol.

    Illinois (modified regula falsi) with a bisection whenever the bracket
    does not halve. Returns (a, status) with xb the state at t + a: the near
    side of zero, so that a guard reset to move back (a bounce) starts the
    next step on the side from which it can cross again.
    """
    s = 1.0 if g_start > 0.0 else -1.0
    a, ga, b, gb = 0.0, g_start, h, g_end
    xb[:] = x
    side = 0
    width = h
    for _ in range(200):
        if b - a <= tol:
            break
        c = b - gb * (b - a) / (gb - ga)
        if not (a < c < b) or (b - a) > 0.5 * width:
            c = 0.5 * (a + b)
        width = b - a
        counts[1] += 1
        status = rk4_step(mode, do_project, constrain, e0, energy_tol, t, c, x, inputs, u, data, p, d, flow, xc,
                          M, G, S, k, xt, scale)
        if status == OK:
            status = update_inputs(inputs, t + c, xc, p, d, flow, u, data)
        if status != OK:
            return c, status
        gc = guard(m, t + c, xc, u, p, d)
        if s * gc <= 0.0:
            b, gb = c, gc
            if side == 1:
                ga *= 0.5
            side = 1
        else:
            a, ga = c, gc
            xb[:] = xc
            if side == -1:
                gb *= 0.5
            side = -1
    return a, OK


@njit(cache=True, error_model="numpy", nogil=True)
def advance(mode, do_project, constrain, e0, energy_tol, event_tol, t0, dt, i, i_end, every, t, flow, x, inputs,
            u, data, p, d, out_t, out_x, out_u, out_flow, out_d, row, g0, x_event, M, G, S, k, xt, x1, xb, xc, counts):
    """Integrate from time t (on step i: t0 + i dt <= t < t0 + (i + 1) dt) to the grid point i_end,
    stopping early at a jump or a failure. x, d, g0 and the logs are updated in place; every
    `every`-th grid point is logged at out_*[row] (out_u: the inputs there). counts[0] += steps
    taken (a step cut by a jump counts twice), counts[1] += trial steps of event location,
    counts[2] = the rows logged so far. It runs without the GIL, so that a watchdog thread can
    write those rows should the loop never return (see andyc.runtime.interrupts).

    Returns (i, row, status, t, flow, jump): jump is the index of the jump applied at t (x_event
    holds the state just before it), or -1.
    """
    counts[2] = row
    scale = 1.0
    for j in range(x.shape[0]):
        scale = max(scale, abs(x[j]))
    if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
        return i, row, INPUT_FAILED, t, flow, -1
    for m in range(NJ):
        if JUMP_SOURCE[m] == flow:
            g0[m] = guard(m, t, x, u, p, d)
    while i < i_end:
        t_next = t0 + (i + 1) * dt
        h = t_next - t
        if h > 1e-14 * max(1.0, abs(t_next)):
            counts[0] += 1
            status = rk4_step(mode, do_project, constrain, e0, energy_tol, t, h, x, inputs, u, data, p, d, flow,
                              x1, M, G, S, k, xt, scale)
            if status != OK:
                return i, row, status, t, flow, -1
            best, best_tau = -1, h
            tol = event_tol * max(1.0, abs(t))
            for m in range(NJ):
                if JUMP_SOURCE[m] != flow:
                    continue
                if update_inputs(inputs, t_next, x1, p, d, flow, u, data) != OK:
                    return i, row, INPUT_FAILED, t, flow, -1
                g1 = guard(m, t_next, x1, u, p, d)
                if crosses(JUMP_DIRECTION[m], g0[m], g1):
                    tau, status = locate(m, mode, do_project, constrain, e0, energy_tol, tol, t, h, x, inputs,
                                         u, data, p, d, flow, g0[m], g1, xb, xc, M, G, S, k, xt, counts, scale)
                    if status == OK:
                        status = update_inputs(inputs, t + tau, xb, p, d, flow, u, data)
                    if status != OK:
                        return i, row, status, t, flow, -1
                    earlier = tau < best_tau - tol or (best >= 0 and tau <= best_tau + tol
                                                        and JUMP_PRIORITY[m] < JUMP_PRIORITY[best])
                    if (best < 0 or earlier) and enabled(m, t + tau, xb, u, p, d) >= 0.0:
                        best, best_tau = m, tau
                        x_event[:] = xb
                g0[m] = g1
            if best >= 0:
                x[:] = x_event
                t = t + best_tau
                if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
                    return i, row, INPUT_FAILED, t, flow, -1
                status = jump(best, t, x, u, p, d, M, G, S)
                return i, row, status, t, JUMP_TARGET[best], best
            x[:] = x1
            for j in range(x.shape[0]):
                scale = max(scale, abs(x[j]))
        t = t_next
        i += 1
        if i % every == 0:
            if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
                return i, row, INPUT_FAILED, t, flow, -1
            out_t[row] = t
            out_x[row] = x
            out_u[row] = u
            out_flow[row] = flow
            out_d[row] = d
            row += 1
            counts[2] = row
    return i, row, OK, t, flow, -1


@njit(cache=True, error_model="numpy", nogil=True)
def instant(mode, t, x, inputs, u, data, p, d, flow, xdot, M, G, S):
    """The first jump (in priority order) out of `flow` that happens at once at (t, x), or -1.

    A guard already past zero happens at once when it is moving further
    (falling: g < 0 and dg/dt <= 0, or g = 0 and dg/dt < 0; rising mirrored;
    either: g = 0 and dg/dt != 0) and its enabling condition holds. A guard
    past zero but moving back, such as a bouncing ball's height just after
    the bounce, does not. u is left at the inputs at (t, x); -2 when they fail.
    """
    if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
        return -2
    have_rate = False
    for n in range(NJ):
        m = JUMP_ORDER[n]
        if JUMP_SOURCE[m] != flow:
            continue
        g = guard(m, t, x, u, p, d)
        if g != 0.0 and (JUMP_DIRECTION[m] == EITHER or (g > 0.0) != (JUMP_DIRECTION[m] == RISING)):
            continue
        if not have_rate:
            status = rhs_mode_into(t, x, u, p, d, flow, xdot, M, G, S, mode)
            if status != OK:
                return -1
            have_rate = True
        rate = guard_rate(m, t, x, u, p, d, xdot)
        if JUMP_DIRECTION[m] == EITHER:
            moving = rate != 0.0
        elif JUMP_DIRECTION[m] == FALLING:
            moving = rate < 0.0 or (g < 0.0 and rate == 0.0)
        else:
            moving = rate > 0.0 or (g > 0.0 and rate == 0.0)
        if moving and enabled(m, t, x, u, p, d) >= 0.0:
            return m
    return -1


@njit(cache=True, error_model="numpy")
def evaluate_energy(t, X, U, p, D, out):
    """Energy at the logged samples (time t, state X, inputs U, discrete states D)."""
    for r in range(t.shape[0]):
        out[r] = energy(t[r], X[r], U[r], p, D[r])


@njit(cache=True, error_model="numpy")
def evaluate_frames(t, X, U, p, D, out):
    for r in range(t.shape[0]):
        frame_positions(t[r], X[r], U[r], p, D[r], out[r])


@njit(cache=True, error_model="numpy")
def evaluate_constraints(t, X, U, p, D, F, phi, c, lam, M, G, S):
    """Residuals phi (N, NH), c (N, NC) and multipliers lam (N, NC) at the logged samples;
    NaN for the rows not active in the sample's flow F[r]."""
    for r in range(t.shape[0]):
        u = U[r]
        constraints_into(t[r], X[r], u, p, D[r], S)
        phi_all, c_all, A, kappa = terms(S)
        phi[r, :] = np.nan
        c[r, :] = np.nan
        for n in range(FLOW_NROWS[F[r]]):
            i = FLOW_ROWS[F[r], n]
            c[r, i] = c_all[i]
            if i < NH:
                phi[r, i] = phi_all[i]
        if multipliers(t[r], X[r], u, p, D[r], F[r], lam[r], M, G, S) != OK:
            lam[r, :] = np.nan
