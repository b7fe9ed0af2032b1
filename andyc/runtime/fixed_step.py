"""The fixed-step driver (rk4, projection, lagrange, baumgarte): the compiled loop in chunks.

The build's integrator (andyc_numerics/integrator.py: advance) steps along the grid i dt, locates guard
crossings on the step and applies the jump's resets and impact; it returns after a chunk of steps, sized
to about a quarter of a second so that progress, interrupts and the watchdog are served, or right after a
jump. Python then runs the user's jump function, records the jump (EventLog: loops, Zeno, stop_after) and
follows the jumps that happen at once, and the loop goes on from there: the grid stays regular.
"""

from __future__ import annotations

import time

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import BAUMGARTE, DIVERGED, IDEAL, INPUT_FAILED, LAGRANGE, OK
from andyc.runtime.compiled import projects, variant, work
from andyc.runtime.events import finish_jump, follow_instant_jumps
from andyc.runtime.inputs import inputs_at
from andyc.runtime.options import Projection
from andyc.runtime.status import INTERRUPTED, at, diverging_constraints, ending, failure, in_jump
from andyc.runtime.work import JumpWork, law_offset, with_work

MODE = {"rk4": IDEAL, "projection": IDEAL, "lagrange": LAGRANGE, "baumgarte": BAUMGARTE}


def run_fixed_step(model, method, x, source, p, d, flow, t_end, dt, every, projection: Projection, bar, jumps,
                   interrupts, run_of, tangent=None):
    """Integrate from (0, x) to t_end in steps dt, logging every `every`-th; x and d change in place.
    projection.energy_correction is resolved (a bool). Returns (log, status, stats).
    tangent: an andyc.runtime.sensitivities.Tangent, carried through every step (after each call of the loop, over
    the steps that call took, in one compiled call) and every jump."""
    n_steps = int(round(t_end / dt))
    if abs(n_steps * dt - t_end) > 1e-9 * max(1.0, t_end):
        raise SimulationError(f"t_end = {t_end} is not a whole number of steps dt = {dt}; "
                              f"use t_end = {n_steps * dt:g} or another dt")
    integrator = model.numerics.integrator
    mode = MODE[method]
    constrain = method == "projection" and model.nc > 0
    etol = projection.energy_tol if projection.energy_correction else -1.0
    do_project = projects(model, method, projection)
    trailing = variant(model, method, projection)      # (the integrator's variant for this run: advance)
    rows = n_steps // every + 2             # the grid, and a last sample where a run stops between grid points
    nu = len(model.input_names)
    nx = model.nx
    x = with_work(model, x)                        # the state, then the work of each slot (andyc.runtime.work)
    state = x[:nx]                                 # (a view: the jumps change it in place)
    log = integrator.Log(np.empty(rows), np.empty((rows, x.shape[0])), np.empty((rows, nu)),
                         np.empty(rows, dtype=np.int64), np.empty((rows, model.nd)))
    out_t, out_x, out_u, out_f, out_d = log
    w = work(model)
    fn, data = source.function_data
    out_t[0], out_x[0], out_u[0], out_f[0], out_d[0] = 0.0, x, inputs_at(model, source, 0.0, state, p, d, flow), flow, d
    i, row, chunk, status, t = 0, 1, 1000, OK, 0.0
    counts = w.counts                               # steps, event trial steps, rows logged (see advance)
    counts[2] = row

    def partial():
        """The Run of the rows logged so far, for the watchdog: advance keeps counts[2] up to date."""
        n = int(counts[2])
        return run_of(tuple(a[:n].copy() for a in log), INTERRUPTED, stats(counts, constrain))

    interrupts.partial = partial
    flow, message, e0 = start_flow(model, x, out_u[0], source, p, d, flow, jumps, w, mode)
    _no_instant_jump(tangent, jumps, 0)
    while i < n_steps and status == OK and message is None:
        message = interrupts.reason()
        if message is not None:
            message += at(t)
            break
        i_end = min(i + chunk, n_steps)
        tic = time.perf_counter()
        i0, t0, x0, d0, flow0 = i, t, state.copy(), d.copy(), flow
        d_before = d0
        w.u[:] = source.held(flow)
        opts = integrator.options(mode, do_project, constrain, e0, etol, jumps.event_tol)
        i, row, status, t, flow, k = integrator.advance(model.ref, w.ref, opts, fn, data, p, d, x, t, flow, i, i_end,
                                                        0.0, dt, every, log, row, *trailing)
        if tangent is not None and status == OK:
            tangent.advance(t0, x0, d0, flow0, i0, t, i, dt, k, w.x_event[:nx])
        if k >= 0:
            if status != OK:
                message = in_jump(model, status, k, t)
                break
            n_jumps = len(jumps.times)
            flow, message, status, e0 = after_jump(model, k, t, x, source, p, d, d_before, flow0, flow, jumps, w, mode)
            _no_instant_jump(tangent, jumps, n_jumps + 1)
        elif i > i0:
            elapsed = time.perf_counter() - tic
            target = interrupts.budget(0.25)       # (a quarter of a second, or what is left of --timeout)
            chunk = int(min(max(chunk * target / max(elapsed, 1e-6) * (i_end - i0) / (i - i0), 1000), 10_000_000))
        bar(t)
    if status != OK:
        why = failure(model, source, status, t, d, p)
        if status == DIVERGED:
            why += diverging_constraints(model, t, state, w.u, p, d, flow)
        message = f"stopped: {why}, step {i}"
    elif message is not None and out_t[row - 1] != t:
        out_t[row], out_x[row], out_f[row], out_d[row] = t, x, flow, d
        if source.into(model, t, state, p, d, flow, out_u[row]) != OK:
            out_u[row] = np.nan
        row += 1
    return tuple(a[:row] for a in log), ending(message, row, jumps), stats(counts, constrain)


def start_flow(model, x, u, source, p, d, flow, jumps, w, mode) -> tuple:
    """Before a fixed-step run's first step (x the augmented state, u the inputs at the start; x, d in place): the
    jumps that happen at once there, and the energy correction's offset then. Returns (flow, stop message or None,
    e0)."""
    balance = JumpWork(model, x, u, p, d, 0.0)
    state = x[:model.nx]
    flow, message = follow_instant_jumps(model, 0.0, state, source, p, d, flow, jumps, w, mode)
    return flow, message, law_offset(model, flow, balance.add(x, inputs_at(model, source, 0.0, state, p, d, flow), d))


def after_jump(model, k, t, x, source, p, d, d_before, flow0, flow, jumps, w, mode) -> tuple:
    """After advance applied jump k at t, from flow0 into `flow` (x the augmented state, d in place; w.x_event the
    state just before it, w.u the inputs there, d_before the discrete states before it): the contact's resolution
    and the user's function (finish_jump), the jumps that follow at once, the inputs in the new flow (into w.u),
    the jump's energy into the `jumps` slot. Returns (flow, stop message or None, status, e0 of the energy
    correction after it)."""
    balance = JumpWork(model, w.x_event, w.u, p, d_before, t)
    state = x[:model.nx]
    flow, message = finish_jump(model, k, t, w.x_event[:model.nx], state, w.u, p, d, flow0, flow, jumps)
    if message is None:
        flow, message = follow_instant_jumps(model, t, state, source, p, d, flow, jumps, w, mode)
    status = OK
    if message is None and source.into(model, t, state, p, d, flow, w.u) != OK:
        status = INPUT_FAILED
    return flow, message, status, law_offset(model, flow, balance.add(x, w.u, d))


def _no_instant_jump(tangent, jumps, expected: int) -> None:
    """Refuse sensitivities through a jump that happens at once after another (or at the start)."""
    if tangent is not None and len(jumps.times) > expected:
        raise SimulationError(f"{tangent.model.name}: cannot compute sensitivities through jump "
                              f"'{tangent.model.jump_names[jumps.jumps[-1]]}' at t = {jumps.times[-1]:.12g}: it "
                              f"happens at once (after another jump, or at the start), where the saltation "
                              f"matrix is degenerate")


def stats(counts, constrain: bool) -> dict:
    """The run's figures from the integrator's counts (steps, event trial steps)."""
    steps, trials = int(counts[0]), int(counts[1])
    return {"steps": steps, "event_trial_steps": trials, "rhs_evaluations": 4 * (steps + trials),
            "projections": steps + trials if constrain else 0}
