"""The adaptive driver (DOP853, Radau, LSODA, RK45, BDF): SciPy's solvers, stepped one step at a time so that
a failed run keeps what it computed.

After each step the guards of the flow's jumps are compared with their values at the step's start; a
crossing is located on the step's dense output by the same Illinois arithmetic as the compiled `locate`
(illinois_trial and illinois_bracket in the build's andyc_numerics/integrator.py, called from Python), to
Events.tol; the earliest enabled crossing wins, ties going to the lower priority number. The jump is applied
at the near side of the bracket and the solver restarts after it (made_jump: no stale derivative).
The output is the grid i dt, read from the dense output.
"""

from __future__ import annotations

import math

import numpy as np

from andyc.numerics.status import IDEAL, INPUT_FAILED, OK, SLIP_STOP
from andyc.runtime.compiled import work
from andyc.runtime.contacts import open_side
from andyc.runtime.events import apply_jump, follow_instant_jumps
from andyc.runtime.status import INTERRUPTED, at, ending, failure, nonfinite, solver_failed
from andyc.runtime.work import JumpWork, with_work


def scipy_method(name: str):
    """The solve_ivp solver class of an adaptive method (SciPy is imported only by a run that uses one)."""
    from scipy import integrate

    return getattr(integrate, name)


class _Stopped(Exception):
    """A right-hand side or input evaluation inside the solver failed: args (t, status)."""


STALLED_STEPS = 1000        # steps in a row that leave t where it was: the solver is stuck


def run_adaptive(model, method, x, source, p, d, flow, t_end, dt_out, rtol, atol, bar, jumps, interrupts, run_of):
    """Integrate from (0, x) to t_end with SciPy's `method`, logging the grid i dt_out. Returns (log, status,
    stats)."""
    module, rhs_mode_into = model.module, model.numerics.dynamics.rhs_mode_into
    stage_powers = model.numerics.integrator.stage_powers
    slip_direction = model.numerics.dynamics.slip_direction
    w = work(model)
    nx = model.nx
    x = with_work(model, x)         # the state, then the work of each slot: extra components of the solver's y
    xdot = np.empty(x.shape[0])
    calls = [0]
    current = [flow]

    def inputs(t, y):
        """w.u at (t, y) in the current flow."""
        y = np.ascontiguousarray(y)      # the input function's type takes C-contiguous arrays only
        if source.into(model, t, y, p, d, current[0], w.u) != OK:
            raise _Stopped(t, INPUT_FAILED)
        return w.u

    def fun(t, y):
        calls[0] += 1
        y = np.ascontiguousarray(y)      # (Radau's Jacobian passes columns of a matrix)
        u = inputs(t, y)
        status = rhs_mode_into(model.ref, w.ref, t, y, u, p, d, current[0], xdot, IDEAL)
        if status != OK:
            raise _Stopped(t, status)
        stage_powers(model.ref, w.ref, t, y, u, p, d, current[0], xdot, IDEAL)
        return xdot.copy()

    n_out = int(math.floor(t_end / dt_out + 1e-9)) + 1
    # (3 * 0.1 is 0.30000000000000004: a grid point a rounding past t_end is t_end, or the last sample is lost)
    grid = np.minimum(np.arange(n_out) * dt_out, t_end)
    if grid[-1] < t_end - 1e-12 * t_end:
        grid = np.append(grid, t_end)
    out_t, out_x, out_f, out_d = [0.0], [x.copy()], [flow], [d.copy()]
    out_u = [inputs(0.0, x).copy()]
    row, steps, t, still = 1, 0, 0.0, 0

    def partial():
        n = min(map(len, (out_t, out_x, out_u, out_f, out_d)))
        return run_of(_log(model, out_t[:n], out_x[:n], out_u[:n], out_f[:n], out_d[:n]), INTERRUPTED,
                      {"steps": steps, "rhs_evaluations": calls[0]})

    interrupts.partial = partial
    try:
        balance = JumpWork(model, x, out_u[0], p, d, t)
        flow, message = follow_instant_jumps(model, t, x[:nx], source, p, d, flow, jumps, w, IDEAL)
        balance.add(x, inputs(t, x), d)
        while message is None and t < t_end:
            current[0] = flow
            with np.errstate(all="ignore"):     # (its first step's estimate, from a right-hand side past a float)
                solver = scipy_method(method)(fun, t, x, t_end, rtol=rtol, atol=atol)
            watched = [m for m in range(model.nj) if model.in_mode(m, flow, d)]
            g0 = {m: module.guard(m, t, x, inputs(t, x), p, d, flow) for m in watched}
            open_side(model, t, x[:nx], inputs(t, x), p, d, g0)     # a gap leaving an impact: on its open side
            while solver.status == "running":
                message = interrupts.reason()
                if message is not None:
                    message += at(solver.t)
                    break
                t_old = solver.t
                try:
                    with np.errstate(all="ignore"):     # (a state that overflows is reported below, as such)
                        text = solver.step()
                except (ValueError, ArithmeticError, np.linalg.LinAlgError) as exc:
                    # Radau's and BDF's Newton on a state past a float: "array must not contain infs or NaNs"
                    message = solver_failed(method, solver.t, f"{type(exc).__name__}: {exc} (the solution "
                                            "diverges, or the equations are not finite there)")
                    break
                steps += 1
                if solver.status == "failed":
                    message = solver_failed(method, solver.t, text)
                    break
                still = still + 1 if solver.t <= t_old else 0
                if still >= STALLED_STEPS:      # (LSODA at a discontinuity: steps of zero length, without end)
                    message = solver_failed(method, solver.t, f"{STALLED_STEPS} steps in a row made no progress "
                                            "(the equations are stiff or discontinuous there: try Radau, or a "
                                            "fixed-step method)")
                    break
                if not np.all(np.isfinite(solver.y)):
                    message = nonfinite(solver.t)
                    break
                dense = solver.dense_output()
                hit = first_crossing(model, dense, watched, g0, t_old, solver.t, inputs, p, d, flow, jumps.event_tol)
                t_stop = solver.t if hit is None else hit[1]
                while row < grid.shape[0] and grid[row] <= t_stop:
                    out_t.append(grid[row]), out_x.append(dense(grid[row])), out_f.append(flow)
                    out_d.append(d.copy()), out_u.append(inputs(grid[row], out_x[-1]).copy())
                    row += 1
                bar(t_stop)
                if hit is None:
                    t, x = solver.t, solver.y.copy()
                    if slip_direction(model.ref, w.ref, t, x, inputs(t, x), p, d, flow, 0.0, IDEAL):    # a spatial slip
                        g0.update({m: module.guard(m, t, x, inputs(t, x), p, d, flow) for m in watched
                                   if module.JUMP_CONTACT[m] == SLIP_STOP})
                    continue
                k, t, x_before = hit
                x = x_before.copy()
                u_before = inputs(t, x_before).copy()
                balance = JumpWork(model, x_before, u_before, p, d, t)
                flow, message = apply_jump(model, k, t, x[:nx], u_before, p, d, w, flow, jumps)
                if message is None:
                    flow, message = follow_instant_jumps(model, t, x[:nx], source, p, d, flow, jumps, w, IDEAL)
                current[0] = flow
                balance.add(x, inputs(t, x), d)
                break
            else:
                t, x = solver.t, solver.y.copy()
    except _Stopped as exc:
        message = f"stopped: {failure(model, source, exc.args[1], exc.args[0], d, p)}"
    if message is not None and out_t[-1] != t:
        out_t.append(t), out_x.append(x.copy()), out_f.append(flow), out_d.append(d.copy())
        u = np.empty(len(model.input_names))
        ok = source.into(model, t, x[:nx], p, d, flow, u) == OK
        out_u.append(u if ok else np.full_like(u, np.nan))
    return (_log(model, out_t, out_x, out_u, out_f, out_d), ending(message, len(out_t), jumps),
            {"steps": steps, "rhs_evaluations": calls[0]})


def _log(model, out_t, out_x, out_u, out_f, out_d):
    """The integrator's Log arrays (t, x, u, flow, d) of the samples collected as lists."""
    n = len(out_t)
    return (np.array(out_t), np.array(out_x).reshape(n, model.nx + model.nw), np.array(out_u).reshape(n, len(model.input_names)),
            np.array(out_f, dtype=np.int64), np.array(out_d).reshape(n, model.nd))


def first_crossing(model, dense, watched, g0, t0, t1, inputs, p, d, flow, event_tol):
    """(jump, time, state) of the earliest enabled guard crossing on [t0, t1] along `dense` in `flow`, or None.

    inputs(t, x) gives the inputs there; g0 (jump -> guard value at t0) is updated to the values at t1.
    """
    module = model.module
    best = None
    x1 = dense(t1)
    tol = event_tol * max(1.0, abs(t0))

    def guard(m, s, y):
        return module.guard(m, s, y, inputs(s, y), p, d, flow)

    for m in watched:
        g1 = guard(m, t1, x1)
        if module.crosses(module.JUMP_DIRECTION[m], g0[m], g1):
            tau = illinois(model, lambda s: guard(m, s, dense(s)), t0, t1, g0[m], g1, tol)
            x_near = dense(tau)
            earlier = best is None or tau < best[1] - tol or (
                tau <= best[1] + tol and module.JUMP_PRIORITY[m] < module.JUMP_PRIORITY[best[0]])
            if earlier and module.enabled(m, tau, x_near, inputs(tau, x_near), p, d, flow) >= 0.0:
                best = (m, tau, x_near)
        g0[m] = g1
    return best


def illinois(model, g, a, b, ga, gb, tol):
    """The near end of a bracket of g's root on [a, b] (ga = g(a), gb = g(b) of opposite signs) no wider than
    tol: the compiled `locate`'s iteration, its arithmetic in the build's integrator."""
    integrator = model.numerics.integrator
    s = 1.0 if ga > 0 else -1.0
    side, width = 0, b - a
    for _ in range(200):
        if b - a <= tol:
            break
        c, width = integrator.illinois_trial(a, ga, b, gb, width)
        a, ga, b, gb, side = integrator.illinois_bracket(s, a, ga, b, gb, side, c, g(c))
    return a
