"""A fixed-step RK4 loop with event location, over a compiled Model (model.py).

advance() steps along the grid t0 + i dt and returns after a block of steps or after a jump. Each
step is classical RK4 on rhs_mode_into (mode IDEAL, LAGRANGE or BAUMGARTE), followed, with
`project`, by dynamics.project (quaternion norms; with `constrain` and energy_tol, the Braun &
Goldfarb corrections). The options of a run are one Options tuple.

Events: after each step, the guards of the current flow's jumps are compared with their values at
the step's start. A sign change in a jump's direction is located by root finding on the step,
each trial time tau being a step of size tau from the step's start (so the located state is the
method's own solution), to event_tol seconds (relative beyond 1 s). The earliest crossing whose
enabling condition holds wins, ties going to the lower priority number; the jump (resets, impact)
is applied at the near side of the final bracket, and the rest of the step is integrated by the
next call, so the grid stays t0 + i dt. The caller applies the user's jump function and follows
jumps that happen at once (instant).

Inputs: every function here takes `inputs`, a pair of compiled callbacks (inputs.py)
    status = callback(t, x, d, p, flow, u, data)
that write the inputs u at (t, x) (model.INPUTS_SIGNATURE: a first-class function type, so the
integrator compiles once for every input source), and the `data` they read. They are called before
each evaluation at a new (t, x); a nonzero status stops the run with INPUT_FAILED. inputs = data =
None: the inputs are held, u as the caller set it for the flow. Numba then compiles the integrator
without the calls (branches on `is not None` are pruned at compile time), so held inputs do not pay
for carrying functions and an array down the call chain.
"""

import math
from collections import namedtuple

from .compiler import jit
from .active import select_rows
from .dynamics import (enabled_value, guard_value, in_mode, jump, multipliers, project, rhs_free_into, rhs_mode_into,
                       slip_direction)
from .model import borrowed, call
from . import rk4
from .slipping import slip_unit
from .status import (BAUMGARTE, DIVERGED, EITHER, FALLING, GROWTH_LIMIT, INPUT_FAILED, NONFINITE, OK, ON_CONE, ON_ZERO,
                     OPEN_SIDE, REST_SPEED, RISING, SLIP_STOP)

Options = namedtuple("Options", "mode project constrain e0 energy_tol event_tol")
Options.__doc__ = """How a run integrates: mode (IDEAL, LAGRANGE or BAUMGARTE: how constraint forces are found),
project (apply dynamics.project after each step), constrain (its constraint corrections), e0 and energy_tol (its
energy correction to e0; energy_tol < 0: none), event_tol (seconds, relative beyond 1 s)."""

Log = namedtuple("Log", "t x u flow d")
Log.__doc__ = "A run's logged samples: time (N,), state (N, NX), inputs (N, NU), flow (N,) and discrete states (N, ND)."


def options(mode, project, constrain, e0, energy_tol, event_tol) -> Options:
    """Options with the types the compiled integrator takes (one compilation for every run)."""
    return Options(int(mode), bool(project), bool(constrain), float(e0), float(energy_tol), float(event_tol))


@jit
def update_inputs(inputs, t, x, p, d, flow, u, data):
    """u at (t, x) when the inputs are driven (inputs: the pair of callbacks of inputs.callbacks; None: held, u
    stays as the caller set it); a status (INPUT_FAILED: a callback failed, its record in data says why)."""
    if inputs is not None:
        for callback in inputs:
            if call(callback, (t, x, d, p, flow, u, data)) != 0:
                return INPUT_FAILED
    return OK


@jit(inline="always")
def element_powers(model, w, t, x, u, p, d, xdot):
    """xdot[NX:NX + NW] = the elements' powers (stage_powers without rows: all of it where NC = 0)."""
    nx, nv = model.nx, model.nv
    G = w.G
    for i in range(model.nw):           # (the leaf writes the elements' slots only: the others stay 0 in G)
        xdot[nx + i] = G[nv + i]
    call(model.drive_power, (t, x, u, p, d, xdot))      # (reads dv/dt in xdot: after rhs_mode_into)


@jit(inline="always")
def stage_powers(model, w, t, x, u, p, d, flow, xdot, mode):
    """xdot[NX:NX + NW] = the power of each work slot at (t, x) (andyc/symbolic/work.py), right after
    rhs_mode_into in `flow` with `mode`: the elements' from the dynamics leaf (it wrote them after G), each working
    constraint row's -lam (c - A v) from the multipliers the flow's constraint solve left in S's y row and the
    row's A and c in S, and each slipping contact's friction power into the slot `friction` (ROW_FRICTION). So the
    work W is integrated with the motion.

    In the BAUMGARTE mode the rows' forces A^T lam (lam with the soft terms, ANDY eq. 15) also act off the
    constraint manifold, where c != 0: each row's whole power lam A v is counted, a working row's in its
    constraint's slot (lam c more), another's in the slot `baumgarte` (ROW_WORK = -2 - that slot; -1: none)."""
    nx, nv, nq = model.nx, model.nv, model.nq
    if model.nw == 0:
        return
    element_powers(model, w, t, x, u, p, d, xdot)
    S = w.S
    for r in range(w.nactive[0]):          # (the rows rhs_mode_into selected)
        row = w.active[0, r]
        slot = model.row_work[row]
        if slot == -1 or (slot < -1 and mode != BAUMGARTE):
            continue
        c = S[model.s_cv, row]
        av = 0.0
        for j in range(nv):
            av += S[model.s_a + row, j] * x[nq + j]
        lam = S[model.s_y, r]
        if slot >= 0:
            xdot[nx + slot] -= lam * (c - av)
            if mode == BAUMGARTE:
                xdot[nx + slot] += lam * c
        else:
            xdot[nx - 2 - slot] += lam * av
    if w.nactive[2]:                    # a slipping contact's friction: -sigma mu lam_n J_t v (spatial: along u)
        for r in range(w.nactive[0]):
            code, slot = w.active[1, r], model.row_friction[w.active[0, r]]
            if code == 0 or slot < 0:
                continue
            t_row = abs(code) - 1
            js = 0.0
            if w.active[3, r] > 0:
                u1, u2 = slip_unit(model, w, d, r)
                for j in range(nv):
                    js += (u1 * S[model.s_a + t_row, j] + u2 * S[model.s_a + t_row + 1, j]) * x[nq + j]
            else:
                sigma = 1.0 if code < 0 else -1.0           # (code = -sigma (t + 1))
                for j in range(nv):
                    js += sigma * S[model.s_a + t_row, j] * x[nq + j]
            xdot[nx + slot] -= S[model.s_e, w.active[2, r]] * S[model.s_y, r] * js


@jit
def rk4_step(model, w, opts, inputs, data, t, h, x, u, p, d, flow, out, scale, full=True, free=None, slips=True,
             quiet=None):
    """out = the RK4 step of size h from (t, x), then projected; x is unchanged. Returns a status. `full`, `free`:
    as advance's (full None and free True: no rows, no projection; the step compiles without them); slips, quiet:
    (True, None), or (None, True) for a model without jumps (the step then compiles without the slipping
    contacts' solve: dynamics.rhs_mode_into's slips; two flags, as full and free).

    x is the state (NX) followed by the work of each slot (NW, andyc/symbolic/work.py): their rates are the
    powers (stage_powers), so the work is RK4's own quadrature of the power along the step's stages, and the
    augmented system's RK4 step is exactly this one (the motion does not depend on W).

    Stage s evaluates at t + c_s h, x + a_s h k_(s-1), by the tableau of rk4.py. A step whose largest
    entry exceeds GROWTH_LIMIT times `scale` (the largest entry of the states so far, at least 1)
    is DIVERGED: motion that is followed at all never grows by orders of magnitude in one step; a
    diverging solution (a constraint turning singular, a step far past the method's stability
    bound) does, within a few steps. (Against the run's largest entry, not the step start's, so that
    a stiff oscillator whose speed is large where its position is small does not count as growth.)
    """
    k, xt = w.k, w.xt
    nx = x.shape[0]
    for s in range(rk4.STAGES):
        c = rk4.C[s]
        for j in range(nx):
            xt[j] = x[j] if s == 0 else x[j] + rk4.A[s] * h * k[s - 1, j]
        if update_inputs(inputs, t + c * h, xt, p, d, flow, u, data) != OK:
            return INPUT_FAILED
        status = OK
        if full is not None and slips is not None:
            status = rhs_mode_into(model, w, t + c * h, xt, u, p, d, flow, k[s], opts.mode)
        if full is not None and quiet is not None:
            status = rhs_mode_into(model, w, t + c * h, xt, u, p, d, flow, k[s], opts.mode, None)
        if free is not None:
            status = rhs_free_into(model, w, t + c * h, xt, u, p, d, k[s])
        if status != OK:
            return status
        if full is not None:
            stage_powers(model, w, t + c * h, xt, u, p, d, flow, k[s], opts.mode)
        if free is not None and model.nw > 0:
            element_powers(model, w, t + c * h, xt, u, p, d, k[s])
    total = 0.0
    grown = 0.0
    for j in range(nx):
        weighted = rk4.B[0] * k[0, j] + rk4.B[1] * k[1, j] + rk4.B[2] * k[2, j] + rk4.B[3] * k[3, j]
        out[j] = x[j] + h / rk4.DIVISOR * weighted
        total += out[j]
        if j < model.nx:            # (the work may grow without bound: a driven model)
            grown = max(grown, abs(out[j]))
    if not math.isfinite(total):
        return NONFINITE
    if grown > GROWTH_LIMIT * scale:
        return DIVERGED
    if free is not None:
        return OK
    if opts.project:
        if update_inputs(inputs, t + h, out, p, d, flow, u, data) != OK:
            return INPUT_FAILED
        return project(model, w, t + h, out, u, p, d, flow, opts.constrain, opts.e0, opts.energy_tol)
    return OK


@jit
def crosses(direction, g_start, g_end):
    """Whether a guard going from g_start to g_end over a step crosses zero in `direction`."""
    if g_start > 0.0:
        return direction != RISING and g_end <= 0.0
    if g_start < 0.0:
        return direction != FALLING and g_end >= 0.0
    return False            # starting on zero: the instant check (see `instant`) decides


@jit
def illinois_trial(a, ga, b, gb, width):
    """The next trial point in the bracket [a, b] of a root (g(a) = ga and g(b) = gb of opposite signs), and the
    width to compare the next bracket with: the regula falsi point, or the midpoint when that falls outside the
    bracket or the bracket did not halve since `width` (the previous bracket's width; the first: b - a).
    Returns (c, b - a)."""
    c = b - gb * (b - a) / (gb - ga)
    if not (a < c < b) or (b - a) > 0.5 * width:
        c = 0.5 * (a + b)
    return c, b - a


@jit
def illinois_bracket(s, a, ga, b, gb, side, c, gc):
    """The bracket after a trial gc = g(c): c replaces the end on its side of the root (s: the sign of g on the
    near side a), and when the same end moves twice in a row the other end's value is halved (Illinois). side:
    the end that moved last (1: b, -1: a, 0: none yet). Returns (a, ga, b, gb, side)."""
    if s * gc <= 0.0:
        if side == 1:
            ga *= 0.5
        return a, ga, c, gc, 1
    if side == -1:
        gb *= 0.5
    return c, gc, b, gb, -1


@jit
def locate(model, w, opts, inputs, data, jump_index, tol, t, h, x, u, p, d, flow, g_start, g_end, scale):
    """Root of guard `jump_index` on the step (t, x) -> t + h, as a bracket [a, b] no wider than tol.

    Illinois (modified regula falsi) with a bisection whenever the bracket does not halve (illinois_trial,
    illinois_bracket; the adaptive methods use the same two on SciPy's dense output). Returns (a, status)
    with w.xb the state at t + a: the near side of zero, so that a guard reset to move back (a bounce)
    starts the next step on the side from which it can cross again. A guard of forces (a contact's normal
    force, its cone's edge) returns (b, status), the far side: the modes chosen there see the force past its
    bound, so that a slip begun at the cone's edge accelerates along its direction (on the near side, still a
    rounding inside the cone, it would slow down and end at once, its stop and its start in turn without end).
    """
    xb, xc = w.xb, w.xc
    s = 1.0 if g_start > 0.0 else -1.0
    a, ga, b, gb = 0.0, g_start, h, g_end
    xb[:] = x
    side = 0
    width = h
    for _ in range(200):
        if b - a <= tol:
            break
        c, width = illinois_trial(a, ga, b, gb, width)
        w.counts[1] += 1
        status = rk4_step(model, w, opts, inputs, data, t, c, x, u, p, d, flow, xc, scale)
        if status == OK:
            status = update_inputs(inputs, t + c, xc, p, d, flow, u, data)
        if status != OK:
            return c, status
        gc = guard_value(model, w, jump_index, t + c, xc, u, p, d, flow)
        a, ga, b, gb, side = illinois_bracket(s, a, ga, b, gb, side, c, gc)
        if side == -1:
            xb[:] = xc
    if model.jump_multipliers[jump_index]:
        status = rk4_step(model, w, opts, inputs, data, t, b, x, u, p, d, flow, xb, scale)
        return b, status
    return a, OK


@jit(nogil=True)
def advance(model, w, opts, inputs, data, p, d, x, t, flow, i, i_end, t0, dt, every, log, row, full=True,
            events=True, free=None, quiet=None):
    """Integrate from time t (on step i: t0 + i dt <= t < t0 + (i + 1) dt) to the grid point i_end,
    stopping early at a jump or a failure. x, d, w.g0 and the log are updated in place; every
    `every`-th grid point is logged at log[row] (log.u: the inputs there, w.u the latest inputs).
    w.counts[0] += steps taken (a step cut by a jump counts twice), w.counts[1] += trial steps of
    event location, w.counts[2] = the rows logged so far. It runs without the GIL, so that a
    watchdog thread can write those rows should the loop never return (andyc.runtime.interrupts).

    Returns (i, row, status, t, flow, jump): jump is the index of the jump applied at t (w.x_event
    holds the state just before it), or -1.

    full, free: (True, None) (the default), or (None, True) for the free variant, for a model without constraint
    rows, jumps or contacts (NC = NJ = 0) run without projection (not opts.project; opts.mode then changes nothing):
    the same steps, operation for operation, but Numba compiles it without the constrained solves, projection,
    event location and jumps, its branches on `full is not None` pruned at compile time as those on `inputs`. Two
    flags, since Numba prunes `arg is not None` only where arg is None, never on a boolean's value: the full loop's
    `free is not None` branches (the free step) are pruned by its free = None. andyc.runtime.compiled.free_run
    says when a run takes it. events, quiet: (True, None), or (None, True) for a model without jumps (NJ = 0, hence
    no contacts): the guards, their location, the jumps and the slipping contacts' solve pruned likewise
    (andyc.runtime.compiled.variant).
    """
    u, g0, x1, xb, x_event, counts = w.u, w.g0, w.x1, w.xb, w.x_event, w.counts
    direction, priority = model.jump_direction, model.jump_priority
    x, p, d = borrowed(x), borrowed(p), borrowed(d)     # held by the caller: no reference counts below
    if data is not None:
        data = borrowed(data)
    counts[2] = row
    scale = 1.0
    for j in range(model.nx):
        scale = max(scale, abs(x[j]))
    if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
        return i, row, INPUT_FAILED, t, flow, -1
    if full is not None and events is not None:     # (the guards at the start)
        have_rate = False
        for n in range(model.nj):
            if in_mode(model, n, flow, d):
                g0[n] = guard_value(model, w, n, t, x, u, p, d, flow)
                # A guard leaving its surface (a bounce, a rocking block's pivot corner lifted when the other strikes,
                # a hand-written walker's foot after its strike) starts a rounding from zero, either side. A rounding
                # past zero, moving away, would hide its coming back within the step (a block's late, short rocks: the
                # run would pass through the surface unnoticed), and one before it would have locate try the step's
                # start again and again: it starts on the open side, of no known size. (A guard of multipliers has no
                # derived rate: not this.)
                if (direction[n] != EITHER and not model.jump_multipliers[n]
                        and abs(g0[n]) <= ON_ZERO * scale):
                    if not have_rate:
                        have_rate = rhs_mode_into(model, w, t, x, u, p, d, flow, w.xdot, opts.mode) == OK
                    if have_rate and direction[n] * call(model.guard_rate, (n, t, x, u, p, d, w.xdot)) < -REST_SPEED:
                        g0[n] = -direction[n] * OPEN_SIDE
    while i < i_end:
        t_next = t0 + (i + 1) * dt
        h = t_next - t
        if h > 1e-14 * max(1.0, abs(t_next)):
            counts[0] += 1
            if full is not None and events is not None:
                if slip_direction(model, w, t, x, u, p, d, flow, h, opts.mode):  # a spatial slip's direction, held?
                    for n in range(model.nj):
                        if model.jump_contact[n] == SLIP_STOP and in_mode(model, n, flow, d):
                            g0[n] = guard_value(model, w, n, t, x, u, p, d, flow)
            status = OK
            if full is not None and events is not None:
                status = rk4_step(model, w, opts, inputs, data, t, h, x, u, p, d, flow, x1, scale)
            if full is not None and quiet is not None:      # (no jumps, hence no contacts: none slips)
                status = rk4_step(model, w, opts, inputs, data, t, h, x, u, p, d, flow, x1, scale, slips=None,
                                  quiet=True)
            if free is not None:
                status = rk4_step(model, w, opts, inputs, data, t, h, x, u, p, d, flow, x1, scale, None, True)
            if status != OK:
                return i, row, status, t, flow, -1
            if full is not None and events is not None:
                best, best_tau = -1, h
                tol = opts.event_tol * max(1.0, abs(t))
                for n in range(model.nj):
                    if not in_mode(model, n, flow, d):
                        continue
                    if update_inputs(inputs, t_next, x1, p, d, flow, u, data) != OK:
                        return i, row, INPUT_FAILED, t, flow, -1
                    g1 = guard_value(model, w, n, t_next, x1, u, p, d, flow)
                    if model.jump_multipliers[n] and abs(g1) <= ON_CONE * force_scale(w.lam):
                        continue        # (a force a rounding from its bound: no crossing yet; g0 keeps its side)
                    if crosses(direction[n], g0[n], g1):
                        tau, status = locate(model, w, opts, inputs, data, n, tol, t, h, x, u, p, d, flow, g0[n], g1,
                                             scale)
                        if status == OK:
                            status = update_inputs(inputs, t + tau, xb, p, d, flow, u, data)
                        if status != OK:
                            return i, row, status, t, flow, -1
                        earlier = tau < best_tau - tol or (best >= 0 and tau <= best_tau + tol
                                                            and priority[n] < priority[best])
                        if (best < 0 or earlier) and enabled_value(model, w, n, t + tau, xb, u, p, d, flow) >= 0.0:
                            best, best_tau = n, tau
                            x_event[:] = xb
                    g0[n] = g1
                if best >= 0:
                    x[:] = x_event
                    t = t + best_tau
                    if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
                        return i, row, INPUT_FAILED, t, flow, -1
                    status = jump(model, w, best, t, x, u, p, d)
                    target = model.jump_target[best]
                    return i, row, status, t, flow if target < 0 else target, best
            copy(x, x1)
            for j in range(model.nx):
                scale = max(scale, abs(x[j]))
        t = t_next
        i += 1
        if i % every == 0:
            if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
                return i, row, INPUT_FAILED, t, flow, -1
            log.t[row] = t
            copy(log.x[row], x)
            copy(log.u[row], u)
            log.flow[row] = flow
            copy(log.d[row], d)
            row += 1
            counts[2] = row
    return i, row, OK, t, flow, -1


@jit(inline="always")
def copy(dst, src):
    """dst[:] = src, of one length, element by element: Numba's slice assignment carries a shape check whose error
    message (string formatting) compiles for about a second on a fresh install."""
    for j in range(src.shape[0]):
        dst[j] = src[j]


@jit(inline="always")
def force_scale(lam):
    """max(1, |lam|) over the multipliers that have a value (the others are NaN)."""
    scale = 1.0
    for r in range(lam.shape[0]):
        if lam[r] == lam[r]:
            scale = max(scale, abs(lam[r]))
    return scale


@jit(nogil=True)
def instant(model, w, mode, inputs, data, t, x, p, d, flow):
    """The first jump (in priority order) out of `flow` that happens at once at (t, x), or -1.

    A guard already past zero happens at once when it is moving further (falling: g < 0 and
    dg/dt <= 0, or g = 0 and dg/dt < 0; rising mirrored; either: g = 0 and dg/dt != 0) and its
    enabling condition holds. A guard past zero but moving back, such as a bouncing ball's height just
    after the bounce, does not. A contact's impact (JUMP_CONTACT) needs dg/dt < -REST_SPEED: a gap a
    rounding below zero, at rest to a rounding, right after its liftoff, is not closing. A slip's end
    (JUMP_CONTACT = SLIP_STOP) needs its slip speed to reverse faster than REST_SPEED (per second): a slip that
    began at the edge of the friction cone starts with a rate that is a rounding from zero. A guard that reads
    multipliers (a normal force, the cone's edge mu lam_n +- lam_t) within ON_CONE of the largest force of zero is
    on zero: the runtime chose the contacts' modes with a smaller tolerance (runtime.contact_modes.cone_state), and a
    jump at once for a rounding would undo its choice, again and again (a stick and a slip in turn at one instant).
    w.u is left at the inputs at (t, x); -2 when they fail.
    """
    u, xdot = w.u, w.xdot
    x, p, d = borrowed(x), borrowed(p), borrowed(d)
    if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
        return -2
    have_rate = False
    for n in range(model.nj):
        k = model.jump_order[n]
        if not in_mode(model, k, flow, d):
            continue
        direction = model.jump_direction[k]
        g = guard_value(model, w, k, t, x, u, p, d, flow)
        if model.jump_multipliers[k] and abs(g) <= ON_CONE * force_scale(w.lam):
            g = 0.0         # (a force a rounding past its bound: the mode just chosen holds, see ON_CONE)
        if g != 0.0 and (direction == EITHER or (g > 0.0) != (direction == RISING)):
            continue
        if not have_rate:
            status = rhs_mode_into(model, w, t, x, u, p, d, flow, xdot, mode)
            if status != OK:
                return -1
            have_rate = True
        rate = call(model.guard_rate, (k, t, x, u, p, d, xdot))
        if direction == EITHER:
            moving = rate != 0.0
        elif direction == FALLING:
            moving = rate < 0.0 or (g < 0.0 and rate == 0.0)
            if model.jump_contact[k] >= 0:      # a gap a rounding below zero at rest, after its liftoff
                moving = rate < -REST_SPEED
        else:
            moving = rate > 0.0 or (g > 0.0 and rate == 0.0)
        if model.jump_contact[k] == SLIP_STOP:  # a slip just begun at the cone's edge: its rate is a rounding
            moving = rate * direction > REST_SPEED
        if moving and enabled_value(model, w, k, t, x, u, p, d, flow) >= 0.0:
            return k
    return -1


@jit(nogil=True)
def evaluate_energy(model, log, p, out):
    """Energy at the logged samples."""
    for r in range(log.t.shape[0]):
        out[r] = call(model.energy, (log.t[r], log.x[r], log.u[r], p, log.d[r]))


@jit(nogil=True)
def evaluate_frames(model, log, p, out):
    """Frame poses at the logged samples, out (N, frames, 12): each frame's origin, then its rotation matrix
    (own axes -> world) row by row (the leaf frame_poses)."""
    for r in range(log.t.shape[0]):
        call(model.frame_poses, (log.t[r], log.x[r], log.u[r], p, log.d[r], out[r]))


@jit(nogil=True)
def evaluate_rows(model, w, log, p, phi, c, lam, power, mode, full=True, free=None, slips=True, quiet=None):
    """At the logged samples: the residuals phi (N, NH), c (N, NC) and multipliers lam (N, NC), NaN for the rows
    not active in the sample's flow (where NC > 0); the power of each work slot, power (N, NW), from the
    right-hand side in the run's `mode` (a constraint's with its multipliers, soft terms included in the BAUMGARTE
    mode; the drive's with dv/dt), the jumps' 0 (where NW > 0). full, free: as advance's, (None, True) for a run
    of its free variant: the free right-hand side, which is the same there, and Numba compiles neither the
    constraint rows' nor the constrained solves; slips, quiet: as rk4_step's, (None, True) after a run of a model
    without jumps.

    One function for both (rather than one each): every compiled function links and optimizes again everything it
    calls, here the whole constrained right-hand side, which is most of the compiled loop; once is enough."""
    S, nx, xdot = w.S, model.nx, w.k[0]
    for r in range(log.t.shape[0]):
        t, x, u, d, flow = log.t[r], log.x[r], log.u[r], log.d[r], log.flow[r]
        if full is not None and model.nc > 0:
            call(model.constraints_into, (t, x, u, p, d, S))
            phi[r, :] = math.nan
            c[r, :] = math.nan
            for n in range(select_rows(model, w, flow, d)):
                i = w.active[0, n]
                c[r, i] = S[model.s_cv, i]
                if i < model.nh:
                    phi[r, i] = S[model.s_phi, i]
            status = OK
            if slips is not None:
                status = multipliers(model, w, t, x, u, p, d, flow, lam[r])
            if quiet is not None:
                status = multipliers(model, w, t, x, u, p, d, flow, lam[r], None)
            if status != OK:
                lam[r, :] = math.nan
        if model.nw == 0:
            continue
        status = OK
        if full is not None and slips is not None:
            status = rhs_mode_into(model, w, t, x, u, p, d, flow, xdot, mode)
        if full is not None and quiet is not None:
            status = rhs_mode_into(model, w, t, x, u, p, d, flow, xdot, mode, None)
        if free is not None:
            status = rhs_free_into(model, w, t, x, u, p, d, xdot)
        if status != OK:
            power[r, :] = math.nan
            continue
        if full is not None:
            stage_powers(model, w, t, x, u, p, d, flow, xdot, mode)
        if free is not None:
            element_powers(model, w, t, x, u, p, d, xdot)
        for i in range(model.nw):
            power[r, i] = xdot[nx + i]
