"""The moreau method's driver: Moreau-Jean time-stepping, the build's compiled loop in chunks.

The scheme, its contact problem and its position corrections are andyc_numerics' timestepping.py (Jean 1999;
Acary & Brogliato 2008, sec. 10.1): contacts resolved by impulses in every step of the fixed step `dt`, no event
location, so that a robot's many contacts cost one small complementarity problem a step, whatever they do. As
the fixed-step driver (andyc.runtime.fixed_step) does, it calls the compiled loop in chunks of about a quarter of
a second, so that progress, interrupts and the watchdog are served.

Logged per sample: the state; each contact's mode of the step that ends there in d (its discrete state
`<contact>_mode`: open, stick, slip +, slip -; a bounce is open); and as the multipliers the mean forces P / dt
of the `every` steps since the last sample (the impulse of each step is multiplier * dt with every = 1), in the
rows and units the event-driven methods log their multipliers, so that plots and analyses read them alike (NaN:
a row in no step's problem since the last sample). Sample 0 has the ideal multipliers of the initial modes.

Joint friction (dampers of law coulomb) is a bounded row of each step's problem, on its speed: |P| <= F dt,
sticking inside the bound (andyc_numerics' contact_solver); its work goes to its own slot. Not covered: hand-written jumps (refused with one line: check_model; the event-driven methods run contacts
beside a hand-written automaton), sensitivities (refused by andyc.runtime.sensitivities).
"""

from __future__ import annotations

import time

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import OK
from andyc.runtime.compiled import work
from andyc.runtime.inputs import inputs_at
from andyc.runtime.status import INTERRUPTED, at, ending, failure
from andyc.runtime.work import with_work


def check_model(model, theta: float) -> None:
    """SimulationError (one line) unless the moreau method can run `model` with this theta."""
    if not (0.5 <= theta <= 1.0):
        raise SimulationError(f"the moreau method's theta is {theta:g}; use a value in [0.5, 1] (0.5: the "
                              "trapezoidal scheme, second order in smooth motion; 1: backward Euler in the speeds)")
    if not model.contact_names and not model.friction_names:
        raise SimulationError(f"{model.source}: the moreau method needs contacts (a contacts: section) or joint "
                              "friction (a damper of law coulomb), and this model has neither; use another --method "
                              "(rk4, projection, ...)")
    own = [name for name, (kind, _) in zip(model.jump_names, model.jump_kinds) if not kind]
    if own:
        raise SimulationError(f"{model.source}: jump '{own[0]}' is written by hand, and the moreau method handles "
                              "the contacts' jumps only; use an event-driven --method (rk4, projection, DOP853, ...)")


def run_moreau(model, x, source, p, d, flow, t_end, dt, every, theta, bar, interrupts, run_of):
    """Step from (0, x) to t_end in steps dt, logging every `every`-th. Returns (log, status, stats, forces): the
    integrator's Log arrays (t, x and the work, u, flow, d) and the mean forces (N, nc) of each sample."""
    n_steps = int(round(t_end / dt))
    if abs(n_steps * dt - t_end) > 1e-9 * max(1.0, t_end):
        raise SimulationError(f"t_end = {t_end} is not a whole number of steps dt = {dt}; "
                              f"use t_end = {n_steps * dt:g} or another dt")
    numerics = model.numerics
    stepping = model.stepping
    x = with_work(model, x)
    nu, nx, rows = len(model.input_names), model.nx, n_steps // every + 2
    log = numerics.integrator.Log(np.empty(rows), np.empty((rows, x.shape[0])), np.empty((rows, nu)),
                                  np.empty(rows, dtype=np.int64), np.empty((rows, model.nd)))
    forces = np.full((rows, model.nc), np.nan)
    out_t, out_x, out_u, out_f, out_d = log
    w = work(model)
    s = model.stepping_scratch()
    stepping.coefficients(model.ref, w.ref, s, p)
    s.guess[:] = [m if m > 0 else -1 for m in model.contact_states(d)]     # the initial modes: the warm start
    fn, data = source.function_data
    out_t[0], out_x[0], out_f[0], out_d[0] = 0.0, x, flow, d
    out_u[0] = inputs_at(model, source, 0.0, x[:nx], p, d, flow)
    counts = w.counts
    i, row, chunk, status, t, message = 0, 1, 1000, OK, 0.0, None
    counts[2] = row

    def figures():
        steps, sweeps, unverified, pushed = (int(v) for v in s.stats)
        return {"steps": steps, "rhs_evaluations": steps, "contact_sweeps": sweeps, "unverified_steps": unverified,
                "penetration_corrections": pushed}

    def partial():
        n = int(counts[2])
        return run_of(tuple(a[:n].copy() for a in log), INTERRUPTED, figures(), forces[:n].copy())

    interrupts.partial = partial
    while i < n_steps and status == OK:
        message = interrupts.reason()
        if message is not None:
            message += at(t)
            break
        i_end = min(i + chunk, n_steps)
        tic, i0 = time.perf_counter(), i
        w.u[:] = source.held(flow)
        i, row, status, t = stepping.advance(model.ref, w.ref, s, theta, fn, data, p, d, x, t, flow, i, i_end, 0.0,
                                             dt, every, log, forces, row)
        if i > i0:
            elapsed = time.perf_counter() - tic
            chunk = int(min(max(chunk * 0.25 / max(elapsed, 1e-6) * (i_end - i0) / (i - i0), 1000), 10_000_000))
        bar(t)
    if status != OK:
        message = f"stopped: {failure(model, source, status, t, d, p)}, step {i}"
    if message is not None and out_t[row - 1] != t:
        out_t[row], out_x[row], out_f[row], out_d[row] = t, x, flow, d
        if source.into(model, t, x[:nx], p, d, flow, out_u[row]) != OK:
            out_u[row] = np.nan
        row += 1
    return tuple(a[:row].copy() for a in log), ending(message, row, _NoJumps), figures(), forces[:row].copy()


def refuse_friction(names, method: str, where: str = "", fix: str = "run with --method moreau, or ",
                    error=SimulationError) -> None:
    """`error` (one line, after `where`) when there are joint frictions (`names`), which only the moreau method
    applies, and `method` is another: stick and slip are decided by the time step's contact problem; the
    event-driven methods and the analyses built on them (linearization, cycles, sensitivities) have no such
    decision. fix: what to do first (the message then says how to leave the friction out)."""
    if names and method != "moreau":
        shown = ", ".join(names[:4]) + (" ..." if len(names) > 4 else "")
        raise error(f"{where}joint friction ({shown}: dampers of law coulomb) is applied by the moreau method "
                    f"only, not by {method}; {fix}leave it out (a URDF's: urdf: {{joint_friction: false}}; a "
                    "damper: another law)")


class _NoJumps:
    finished = False            # (status.ending reads it: no stop_after ends a moreau run)
