"""simulate(): one entry point over every integrator.

    rk4                fixed step, the compiled loop of the generated module; constraint
                       forces from a pseudo-inverse, no drift correction
    projection         rk4, then the Braun & Goldfarb position and velocity
                       corrections after every step (and energy, when the model
                       declares it conserved)
    lagrange           rk4 with Lagrange multipliers (ANDY eq. 10-12)
    baumgarte          rk4 with multipliers and soft terms (ANDY eq. 15)
    DOP853 Radau LSODA scipy's adaptive solvers, stepped one step at a time so
                       that a failed run keeps what it computed

Before a constrained run, the initial state's distance from the constraint
manifold is measured; past `init_tol` the run is refused unless `init` says
to project the state onto the manifold ("project") or to start anyway ("as-is").

Inputs are constants, expressions, tables or a controller (andyc.runtime.inputs);
they are evaluated at every stage and logged with the states.

Runs stop, keep their samples and say why when the state becomes non-finite
or grows by orders of magnitude within one step (it diverges), the mass matrix
stops being positive definite or a controller fails; and when SIGINT or SIGTERM
arrives or a wall-clock limit passes (andyc.runtime.interrupts). Long runs
print progress.
"""

from __future__ import annotations

import math
import sys
import time
import traceback
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import BAUMGARTE, DIVERGED, IDEAL, INPUT_FAILED, LAGRANGE, MESSAGES, OK
from andyc.runtime.compiled import CompiledModel, compile_integrator, work
from andyc.runtime.events import EventLog
from andyc.runtime.inputs import USER_ERRORS, InputSource, input_source, raised
from andyc.runtime.interrupts import Interrupts
from andyc.runtime.methods import FIXED_STEP, MAX_LOG_BYTES, MAX_STEPS, METHODS
from andyc.runtime.run import Run

def scipy_method(name: str):
    """The solve_ivp solver class of an adaptive method (SciPy is imported only by a run that uses one)."""
    from scipy import integrate

    return getattr(integrate, name)
INIT = ("check", "project", "as-is")
_MODE = {"rk4": IDEAL, "projection": IDEAL, "lagrange": LAGRANGE, "baumgarte": BAUMGARTE}


class Progress:
    """Prints `t / t_end` to stderr at most once a second, after the first second."""

    def __init__(self, label: str, t_end: float, enabled: bool | None = None):
        self.label, self.t_end = label, t_end
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.start = self.last = time.perf_counter()
        self.shown = False

    def __call__(self, t: float) -> None:
        now = time.perf_counter()
        if not self.enabled or now - self.start < 1.0 or now - self.last < 1.0:
            return
        self.last = now
        self.shown = True
        end = "\r" if sys.stderr.isatty() else "\n"
        print(f"{self.label}: t = {t:.6g} / {self.t_end:g} s ({100 * t / self.t_end:.0f}%), "
              f"{now - self.start:.0f} s elapsed", end=end, file=sys.stderr, flush=True)

    def close(self) -> None:
        if self.shown and sys.stderr.isatty():
            print(file=sys.stderr)


def simulate(model: CompiledModel, t_end: float, dt: float = 1e-3, method: str = "rk4",
             parameters: dict | None = None, inputs: dict | None = None, x0=None, every: int = 1,
             frames=None, rtol: float = 1e-8, atol: float = 1e-10, progress: bool | None = None,
             normalize: bool = True, energy_correction: bool | None = None, energy_tol: float = 1e-6,
             init: str = "check", init_tol: float = 1e-6, d0=None, flow0: str | int | None = None,
             event_tol: float = 1e-12, max_instant_jumps: int = 100, zeno_tol: float = 1e-6,
             stop_after: dict | None = None, controller=None, interrupts: Interrupts | None = None) -> Run:
    """Integrate `model` from t = 0 to t_end and return the logged Run.

    dt is the step of rk4 and the output spacing of the adaptive methods;
    every N logs one sample in N steps. frames: None, "all" or a list of names.
    inputs: {name: value}, a value being a number, an expression of t and the
    states (a string) or a CSV table (a path ending in .csv); controller: a
    Python file defining control(t, x, d, p), which drives every input (see
    andyc.runtime.inputs).
    normalize: rk4 renormalizes quaternion signals after each step. (The
    adaptive methods do not; their norm drift stays within the tolerances and
    never reaches the dynamics, whose rotation matrices are exact for any norm.)
    energy_correction: the projection method's energy correction (Braun &
    Goldfarb eq. 5-6, applied when 2T > energy_tol); default on when the
    model declares energy conserved. init, init_tol: see the module docstring.

    Hybrid models: x0, d0 and flow0 (a name or index) give the initial state,
    discrete states and flow (default the model's). Guard crossings are located
    to event_tol seconds relative; the run stops, keeping its samples, after
    max_instant_jumps jumps at one instant or when the jump times accumulate
    (Zeno: intervals shrinking geometrically, the accumulation point less than
    zeno_tol seconds ahead). stop_after {jump name: n} ends the run (status
    "finished") right after the n-th occurrence of that jump, with the state
    just after it as the last sample.

    interrupts: what may stop the run from outside (andyc.runtime.interrupts; default: SIGINT and
    SIGTERM, which then end the run with the status "interrupted: ..." instead of raising).
    """
    if method not in METHODS:
        raise SimulationError(f"unknown method '{method}'; available: {', '.join(METHODS)}")
    if init not in INIT:
        raise SimulationError(f"unknown init '{init}'; use one of: {', '.join(INIT)}")
    if energy_correction is None:
        energy_correction = model.conserves_energy and method == "projection"
    elif energy_correction and not (model.conserves_energy and method == "projection"):
        raise SimulationError("energy correction needs the projection method and a model that declares "
                              "'conserves_energy: true'" + ("" if model.conserves_energy else
                                                            f" ({model.name} does not)"))
    if not (math.isfinite(t_end) and math.isfinite(dt) and t_end > 0 and dt > 0 and every >= 1):
        raise SimulationError(f"need t_end > 0, dt > 0 and every >= 1, got t_end={t_end}, dt={dt}, every={every}")
    _check_size(model, t_end, dt, every)
    p = model.parameters(parameters)
    source = input_source(model, p, inputs, controller, t_end)
    x = np.array(model.initial_state(p) if x0 is None else x0, dtype=np.float64)
    if x.shape != (model.nx,):
        raise SimulationError(f"initial state has shape {x.shape}, expected ({model.nx},)")
    d = np.array(model.initial_discrete(p) if d0 is None else d0, dtype=np.float64)
    if d.shape != (model.nd,):
        raise SimulationError(f"initial discrete states have shape {d.shape}, expected ({model.nd},)")
    flow = _flow_index(model, flow0)
    events = EventLog(model, event_tol, max_instant_jumps, zeno_tol, stop_after)
    frame_names = _frame_selection(model, frames)
    compile_integrator(model)
    compile_integrator(model, *source.function_data)
    u = inputs_at(model, source, 0.0, x, p, d, flow)
    initial = consistent_initial_state(model, x, u, p, d, flow, init, init_tol) if model.nc else {}
    if method in ("lagrange", "baumgarte") and model.nc:
        _require_independent_rows(model, method, x, u, p, d, flow)
    bar = Progress(f"{model.name} {method}", t_end, progress)
    interrupts = interrupts or Interrupts()
    start = time.perf_counter()
    run_of = _Assembly(model, method, dt, rtol, atol, t_end, p, source, frame_names, events, energy_correction,
                       initial, start)
    try:
        with interrupts.watching():
            if method in FIXED_STEP:
                log, status, stats = _run_rk4(model, method, x, source, p, d, flow, t_end, dt, every, bar, events,
                                              energy_correction, energy_tol, normalize, interrupts, run_of)
            else:
                log, status, stats = _run_scipy(model, method, x, source, p, d, flow, t_end, dt * every, rtol, atol,
                                                bar, events, interrupts, run_of)
            interrupts.stopped = True
    finally:
        bar.close()
    return run_of(log, status, stats)


@dataclass
class _Assembly:
    """Builds the Run of a log: the samples with the energy, the residuals, the multipliers and the frames at
    each. Called at the end of a run, and by the watchdog on the samples so far (andyc.runtime.interrupts)."""
    model: CompiledModel
    method: str
    dt: float
    rtol: float
    atol: float
    t_end: float
    p: np.ndarray
    source: InputSource
    frame_names: list
    events: EventLog
    energy_correction: bool
    initial: dict               # figures of the initial state's consistency (consistent_initial_state)
    start: float                # perf_counter() when the run started

    def __call__(self, log, status: str, stats: dict) -> Run:
        model, p, frame_names, fixed = self.model, self.p, self.frame_names, self.method in FIXED_STEP
        stats = {**stats, "wall_seconds": time.perf_counter() - self.start, "jumps": len(self.events.times),
                 **self.initial}
        t_log, x_log, u_log, f_log, d_log = log
        n = t_log.shape[0]
        energy = np.empty(n)
        integrator = model.numerics.integrator
        log = integrator.Log(t_log, x_log, u_log, f_log, d_log)
        integrator.evaluate_energy(model.ref, log, p, energy)
        phi, c, lam = np.empty((n, model.nh)), np.empty((n, model.nc)), np.empty((n, model.nc))
        if model.nc:
            integrator.evaluate_constraints(model.ref, work(model).ref, log, p, phi, c, lam)
        frames_out = {}
        if frame_names:
            xyz = np.empty((n, len(model.frame_names), 3))
            integrator.evaluate_frames(model.ref, log, p, xyz)
            frames_out = {name: xyz[:, model.frame_names.index(name)] for name in frame_names}
        held = u_log[0] if n else self.source.held(model.initial_flow)
        return Run(model=model.name, spec_sha256=model.spec_sha256, method=self.method, dt=self.dt, nq=model.nq,
                   nv=model.nv, rtol=0.0 if fixed else self.rtol, atol=0.0 if fixed else self.atol, t_end=self.t_end,
                   parameters=dict(zip(model.parameter_names, map(float, p))),
                   inputs={n: self.source.drives.get(n, float(v)) for n, v in zip(model.input_names, held)},
                   state_names=list(model.state_names), time=t_log, state=x_log, input_names=list(model.input_names),
                   input_values=u_log, energy=energy, frames=frames_out, status=status, stats=stats,
                   multiplier_names=list(model.multiplier_names), multipliers=lam, residual_position=phi,
                   residual_velocity=c, energy_correction=bool(self.energy_correction),
                   flow=f_log, flow_names=list(model.flow_names), discrete_names=list(model.discrete_names),
                   discrete=d_log, events=self.events.table(), jump_names=list(model.jump_names),
                   frame_parents={name: model.frame_parents[model.frame_names.index(name)] for name in frame_names})


def _check_size(model: CompiledModel, t_end: float, dt: float, every: int) -> None:
    """Refuse a run whose steps or logged samples no machine could hold, before anything is allocated."""
    steps = t_end / dt
    if steps > MAX_STEPS:
        raise SimulationError(f"t_end / dt = {steps:.3g} steps, past the limit of {MAX_STEPS:.0e}; raise dt or "
                              f"shorten t_end")
    width = 2 + model.nx + len(model.input_names) + model.nd
    size = (steps / every + 2) * width * 8
    if size > MAX_LOG_BYTES:
        raise SimulationError(f"the run would log {steps / every:.3g} samples ({size / 1e9:.3g} GB), past the "
                              f"limit of {MAX_LOG_BYTES / 1e9:g} GB; log fewer with a larger --every, or raise dt")


def _flow_index(model: CompiledModel, flow) -> int:
    if flow is None:
        return model.initial_flow
    if isinstance(flow, str):
        if flow not in model.flow_names:
            raise SimulationError(f"unknown flow '{flow}'; flows of {model.name}: {', '.join(model.flow_names)}")
        return model.flow_names.index(flow)
    if not 0 <= int(flow) < model.nf:
        raise SimulationError(f"flow index {flow} out of range; {model.name} has {model.nf} flows")
    return int(flow)


def inputs_at(model: CompiledModel, source: InputSource, t: float, x, p, d, flow: int) -> np.ndarray:
    """The inputs at (t, x) in `flow` (a new array); SimulationError naming the controller's line if it fails."""
    u = np.empty(len(model.input_names))
    x = np.ascontiguousarray(x, dtype=np.float64)
    if source.into(model, t, x, p, d, flow, u) != OK:
        raise SimulationError(source.failure(model, d, p))
    return u


def constraint_residuals(model: CompiledModel, t: float, x, u, p, d=None, flow=None):
    """(phi, c) of the flow's active rows: holonomic residuals and velocity-level residuals at (t, x)."""
    d = model.initial_discrete(p) if d is None else d
    flow = model.initial_flow if flow is None else flow
    phi, c = np.empty(model.nh), np.empty(model.nc)
    model.module.constraints(t, x, u, p, d, phi, c, np.empty((model.nc, model.nv)), np.empty(model.nc))
    rows = _active_rows(model, flow)
    return phi[[r for r in rows if r < model.nh]], c[rows]


def _active_rows(model: CompiledModel, flow: int) -> list:
    return [int(r) for r in model.module.FLOW_ROWS[flow, :model.module.FLOW_NROWS[flow]]]


def _require_independent_rows(model: CompiledModel, method: str, x, u, p, d, flow) -> None:
    """Multipliers (ANDY eq. 12) need independent rows; name the first row that is not."""
    A = np.zeros((model.nc, model.nv))
    model.module.constraints(0.0, x, u, p, d, np.empty(model.nh), np.empty(model.nc), A, np.empty(model.nc))
    rows = _active_rows(model, flow)
    A = A[rows]
    tol = 1e-8 * max(np.linalg.norm(A, 2) if A.size else 0.0, 1e-300)
    for k in range(len(rows)):
        if np.linalg.matrix_rank(A[:k + 1], tol=tol) <= k:
            row = rows[k]
            earlier = sorted({model.constraint_rows[r] for r in rows[:k]})
            raise SimulationError(
                f"{model.row_location(row)}: row {row} of the constraints (in '{model.constraint_rows[row]}') is a "
                f"combination of earlier rows (in {', '.join(repr(e) for e in earlier)}) at the initial state: the "
                f"constraints are redundant or the pose is singular, so the {method} method's multipliers are not "
                f"unique; remove the redundant constraint, or use --method projection, which allows them")


def consistent_initial_state(model: CompiledModel, x, u, p, d, flow, init: str, init_tol: float) -> dict:
    """Measure (and with init="project", remove) the initial state's constraint residuals.

    Projection repeats the Braun & Goldfarb position and velocity corrections
    (the smallest change in the mass-matrix metric) until the residuals are
    at round-off. x is changed in place; returns the figures for run stats.
    """
    phi, c = constraint_residuals(model, 0.0, x, u, p, d, flow)
    out = {"initial_position_residual": float(np.max(np.abs(phi), initial=0.0)),
           "initial_velocity_residual": float(np.max(np.abs(c), initial=0.0))}
    worst = max(out.values())
    if init == "as-is" or worst <= (init_tol if init == "check" else 0.0):
        return out
    if init == "check":
        rows = _active_rows(model, flow)
        values = np.concatenate([np.abs(phi), np.abs(c)])
        k = int(np.argmax(values))
        row = rows[k] if k < phi.shape[0] else rows[k - phi.shape[0]]
        level = "position" if k < phi.shape[0] else "velocity"
        raise SimulationError(
            f"{model.row_location(row)}: the initial state is off the constraint manifold: largest residual "
            f"{values[k]:.3g} at the {level} level (constraint '{model.constraint_rows[row]}'; all rows: position "
            f"{out['initial_position_residual']:.3g}, velocity {out['initial_velocity_residual']:.3g}), past the bound "
            f"{init_tol:g}; fix the initial values, or use --init project to move the state onto the manifold "
            f"(the smallest change in the mass-matrix metric), or --init as-is to start from it anyway")
    w = work(model)
    for _ in range(50):
        if model.numerics.dynamics.project(model.ref, w.ref, 0.0, x, u, p, d, flow, True, 0.0, -1.0) != OK:
            raise SimulationError("cannot project the initial state: the mass matrix is not positive definite there")
        phi, c = constraint_residuals(model, 0.0, x, u, p, d, flow)
        if max(np.max(np.abs(phi), initial=0.0), np.max(np.abs(c), initial=0.0)) <= 1e-13 * max(1.0, np.abs(x).max()):
            out["initial_projection"] = float(worst)
            return out
    raise SimulationError(f"cannot project the initial state onto the constraint manifold (residuals still "
                          f"{np.max(np.abs(phi), initial=0.0):.3g}, {np.max(np.abs(c), initial=0.0):.3g} after 50 "
                          f"corrections); the constraints may have no solution near it: check the initial values")


def user_jump(model: CompiledModel, k, t, x, u, p, d) -> str | None:
    """Run the user's function of jump k (<name>_jumps.py); a stop message if it fails."""
    try:
        model.module.user_jump(k, t, x, u, p, d)
    except USER_ERRORS as exc:      # the user's code: report it, keep the run's data
        path = Path(model.module.__file__).with_name(f"{model.name}_jumps.py")
        line = next((f.lineno for f in reversed(traceback.extract_tb(exc.__traceback__))
                     if Path(f.filename) == path), None)
        return (f"stopped: {path}{f':{line}' if line else ''}: the function of jump '{model.jump_names[k]}' "
                f"{raised(exc)} at t = {t:.9g} s")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(d))):
        return (f"stopped: the function of jump '{model.jump_names[k]}' in {model.name}_jumps.py left the state or "
                f"the discrete states non-finite at t = {t:.9g} s")
    return None


def apply_jump(model: CompiledModel, k, t, x, u, p, d, w) -> str | None:
    """Jump k at t (x, d in place; u the inputs just before it): resets and impact, then the user's function."""
    status = model.numerics.dynamics.jump(model.ref, w.ref, k, t, x, u, p, d)
    if status != OK:
        return f"stopped: {MESSAGES[status]} in jump '{model.jump_names[k]}' at t = {t:.9g} s"
    return user_jump(model, k, t, x, u, p, d)


def follow_instant_jumps(model: CompiledModel, t, x, source: InputSource, p, d, flow, events: EventLog,
                         w, mode):
    """Apply the jumps that happen at once at (t, x), in priority order. Returns (flow, stop message or None)."""
    while model.nj:
        w.u[:] = source.held(flow)
        fn, data = source.function_data
        k = model.numerics.integrator.instant(model.ref, w.ref, mode, fn, data, t, x, p, d, flow)
        if k == -2:
            return flow, f"stopped: {source.failure(model, d, p)}"
        if k < 0:
            break
        before = x.copy()
        stop = apply_jump(model, k, t, x, w.u, p, d, w)
        flow = int(model.module.JUMP_TARGET[k])
        stop = stop or events.record(t, k, before, x, d)
        if stop is not None:
            return flow, stop
    return flow, None


def _frame_selection(model: CompiledModel, frames) -> list:
    if frames is None or frames == []:
        return []
    if frames == "all":
        return list(model.frame_names)
    names = frames.split(",") if isinstance(frames, str) else list(frames)
    unknown = [f for f in names if f not in model.frame_names]
    if unknown:
        raise SimulationError(f"unknown frame(s) {', '.join(unknown)}; frames: {', '.join(model.frame_names)}")
    return names


def _run_rk4(model, method, x, source, p, d, flow, t_end, dt, every, bar, events, energy_correction, energy_tol,
             normalize, interrupts: Interrupts, run_of):
    n_steps = int(round(t_end / dt))
    if abs(n_steps * dt - t_end) > 1e-9 * max(1.0, t_end):
        raise SimulationError(f"t_end = {t_end} is not a whole number of steps dt = {dt}; "
                              f"use t_end = {n_steps * dt:g} or another dt")
    module, integrator = model.module, model.numerics.integrator
    mode = _MODE[method]
    constrain = method == "projection" and model.nc > 0
    etol = energy_tol if energy_correction else -1.0
    do_project = constrain or etol >= 0 or (normalize and bool(model.quaternions))
    rows = n_steps // every + 2             # the grid, and a last sample where a run stops between grid points
    nu = len(model.input_names)
    log = integrator.Log(np.empty(rows), np.empty((rows, model.nx)), np.empty((rows, nu)),
                         np.empty(rows, dtype=np.int64), np.empty((rows, model.nd)))
    out_t, out_x, out_u, out_f, out_d = log
    w = work(model)
    fn, data = source.function_data
    out_t[0], out_x[0], out_u[0], out_f[0], out_d[0] = 0.0, x, inputs_at(model, source, 0.0, x, p, d, flow), flow, d
    i, row, chunk, status, t = 0, 1, 1000, OK, 0.0
    counts = w.counts                               # steps, event trial steps, rows logged (see advance)
    counts[2] = row

    def partial():
        """The Run of the rows logged so far, for the watchdog: advance keeps counts[2] up to date."""
        n = int(counts[2])
        return run_of(tuple(a[:n].copy() for a in log), "interrupted", _rk4_stats(counts, constrain))

    interrupts.partial = partial
    e0 = module.energy(0.0, x, out_u[0], p, d)
    flow, message = follow_instant_jumps(model, t, x, source, p, d, flow, events, w, mode)
    while i < n_steps and status == OK and message is None:
        message = interrupts.reason()
        if message is not None:
            message += f" at t = {t:.9g} s"
            break
        i_end = min(i + chunk, n_steps)
        tic = time.perf_counter()
        i0 = i
        w.u[:] = source.held(flow)
        opts = integrator.options(mode, do_project, constrain, e0, etol, events.event_tol)
        i, row, status, t, flow, k = integrator.advance(model.ref, w.ref, opts, fn, data, p, d, x, t, flow, i, i_end,
                                                        0.0, dt, every, log, row)
        if k >= 0:
            if status != OK:
                message = f"stopped: {MESSAGES[status]} in jump '{model.jump_names[k]}' at t = {t:.9g} s"
                break
            message = user_jump(model, k, t, x, w.u, p, d) or events.record(t, k, w.x_event, x, d)
            if message is None:
                flow, message = follow_instant_jumps(model, t, x, source, p, d, flow, events, w, mode)
            if message is None and source.into(model, t, x, p, d, flow, w.u) != OK:
                status = INPUT_FAILED
            e0 = module.energy(t, x, w.u, p, d)
        elif i > i0:
            elapsed = time.perf_counter() - tic
            chunk = int(min(max(chunk * 0.25 / max(elapsed, 1e-6) * (i_end - i0) / (i - i0), 1000), 10_000_000))
        bar(t)
    if status != OK:
        why = source.failure(model, d, p) if status == INPUT_FAILED else f"{MESSAGES[status]} at t = {t:.9g} s"
        if status == DIVERGED:
            why += diverging_constraints(model, t, x, w.u, p, d, flow)
        message = f"stopped: {why}, step {i}; the {row} samples before it are kept"
    elif message is not None and out_t[row - 1] != t:
        out_t[row], out_x[row], out_f[row], out_d[row] = t, x, flow, d
        if source.into(model, t, x, p, d, flow, out_u[row]) != OK:
            out_u[row] = np.nan
        row += 1
    if message is not None and not events.finished and status == OK:
        message += f"; the {row} samples before it are kept"
    status_text = "finished" if message is None or events.finished else message
    return tuple(a[:row] for a in log), status_text, _rk4_stats(counts, constrain)


def _rk4_stats(counts, constrain: bool) -> dict:
    steps, trials = int(counts[0]), int(counts[1])
    return {"steps": steps, "event_trial_steps": trials, "rhs_evaluations": 4 * (steps + trials),
            "projections": steps + trials if constrain else 0}


def diverging_constraints(model: CompiledModel, t, x, u, p, d, flow) -> str:
    """Why a state may have diverged from (t, x), the last sound state, as a clause for the message: the
    flow's constraint rows nearly dependent there (a singular pose, where the constraint forces that keep
    the rows grow without bound), or nothing."""
    rows = _active_rows(model, flow)
    if not rows:
        return ""
    A = np.zeros((model.nc, model.nv))
    model.module.constraints(t, x, u, p, d, np.empty(model.nh), np.empty(model.nc), A, np.empty(model.nc))
    M = model.module.mass_matrix(t, x, u, p, d)
    try:
        W = A[rows] @ np.linalg.solve(M, A[rows].T)
        sv = np.linalg.svd(W, compute_uv=False)
    except np.linalg.LinAlgError:
        return "; the mass matrix is singular there"
    if not np.all(np.isfinite(sv)) or sv[-1] < 1e-6 * sv[0]:
        names = ", ".join(dict.fromkeys(model.constraint_rows[r] for r in rows))
        return (f"; the constraint rows ({names}) are nearly dependent there (A M^-1 A^T has condition number "
                f"{sv[0] / max(sv[-1], 1e-300):.3g}): the mechanism reaches a singular pose, where its "
                f"constraint forces grow without bound")
    return ""


class _Stopped(Exception):
    pass


def _run_scipy(model, method, x, source, p, d, flow, t_end, dt_out, rtol, atol, bar, events, interrupts, run_of):
    """scipy's solver stepped one step at a time; after each step the guards are checked, a crossing
    is located on the step's dense output (Illinois, to the event tolerance) and the solver restarts
    after the jump."""
    module, rhs_mode_into = model.module, model.numerics.dynamics.rhs_mode_into
    w = work(model)
    xdot = np.empty(model.nx)
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
        status = rhs_mode_into(model.ref, w.ref, t, y, inputs(t, y), p, d, current[0], xdot, IDEAL)
        if status != OK:
            raise _Stopped(t, status)
        return xdot.copy()

    n_out = int(math.floor(t_end / dt_out + 1e-9)) + 1
    # (3 * 0.1 is 0.30000000000000004: a grid point a rounding past t_end is t_end, or the last sample is lost)
    grid = np.minimum(np.arange(n_out) * dt_out, t_end)
    if grid[-1] < t_end - 1e-12 * t_end:
        grid = np.append(grid, t_end)
    out_t, out_x, out_f, out_d = [0.0], [x.copy()], [flow], [d.copy()]
    out_u = [inputs(0.0, x).copy()]
    row, steps, t = 1, 0, 0.0

    def partial():
        n = min(map(len, (out_t, out_x, out_u, out_f, out_d)))
        return run_of(_scipy_log(model, out_t[:n], out_x[:n], out_u[:n], out_f[:n], out_d[:n]), "interrupted",
                      {"steps": steps, "rhs_evaluations": calls[0]})

    interrupts.partial = partial
    try:
        flow, message = follow_instant_jumps(model, t, x, source, p, d, flow, events, w, IDEAL)
        while message is None and t < t_end:
            current[0] = flow
            solver = scipy_method(method)(fun, t, x, t_end, rtol=rtol, atol=atol)
            watched = [m for m in range(model.nj) if module.JUMP_SOURCE[m] == flow]
            g0 = {m: module.guard(m, t, x, inputs(t, x), p, d) for m in watched}
            while solver.status == "running":
                message = interrupts.reason()
                if message is not None:
                    message += f" at t = {solver.t:.9g} s"
                    break
                t_old = solver.t
                text = solver.step()
                steps += 1
                if solver.status == "failed":
                    message = f"stopped: {method} failed at t = {solver.t:.9g} s: {text}"
                    break
                if not np.all(np.isfinite(solver.y)):
                    message = f"stopped: the state became non-finite (NaN or Inf) at t = {solver.t:.9g} s"
                    break
                dense = solver.dense_output()
                hit = _first_crossing(model, dense, watched, g0, t_old, solver.t, inputs, p, d, events.event_tol)
                t_stop = solver.t if hit is None else hit[1]
                while row < grid.shape[0] and grid[row] <= t_stop:
                    out_t.append(grid[row]), out_x.append(dense(grid[row])), out_f.append(flow)
                    out_d.append(d.copy()), out_u.append(inputs(grid[row], out_x[-1]).copy())
                    row += 1
                bar(t_stop)
                if hit is None:
                    t, x = solver.t, solver.y.copy()
                    continue
                k, t, x_before = hit
                x = x_before.copy()
                message = apply_jump(model, k, t, x, inputs(t, x_before), p, d, w)
                flow = int(module.JUMP_TARGET[k])
                message = message or events.record(t, k, x_before, x, d)
                if message is None:
                    flow, message = follow_instant_jumps(model, t, x, source, p, d, flow, events, w, IDEAL)
                break
            else:
                t, x = solver.t, solver.y.copy()
    except _Stopped as exc:
        why = (source.failure(model, d, p) if exc.args[1] == INPUT_FAILED
               else f"{MESSAGES[exc.args[1]]} at t = {exc.args[0]:.9g} s")
        message = f"stopped: {why}"
    if message is not None and out_t[-1] != t:
        out_t.append(t), out_x.append(x.copy()), out_f.append(flow), out_d.append(d.copy())
        u = np.empty(len(model.input_names))
        ok = source.into(model, t, x, p, d, flow, u) == OK
        out_u.append(u if ok else np.full_like(u, np.nan))
    if message is not None and not events.finished:
        message += f"; the {len(out_t)} samples before it are kept"
    status = "finished" if message is None or events.finished else message
    return (_scipy_log(model, out_t, out_x, out_u, out_f, out_d), status,
            {"steps": steps, "rhs_evaluations": calls[0]})


def _scipy_log(model, out_t, out_x, out_u, out_f, out_d):
    n = len(out_t)
    return (np.array(out_t), np.array(out_x).reshape(n, model.nx), np.array(out_u).reshape(n, len(model.input_names)),
            np.array(out_f, dtype=np.int64), np.array(out_d).reshape(n, model.nd))


def _first_crossing(model, dense, watched, g0, t0, t1, inputs, p, d, event_tol):
    """(jump, time, state) of the earliest enabled guard crossing on [t0, t1] along `dense`, or None.

    inputs(t, x) gives the inputs there; g0 (jump -> guard value at t0) is updated to the values at t1.
    """
    module = model.module
    best = None
    x1 = dense(t1)
    tol = event_tol * max(1.0, abs(t0))

    def guard(m, s, y):
        return module.guard(m, s, y, inputs(s, y), p, d)

    for m in watched:
        g1 = guard(m, t1, x1)
        if module.crosses(module.JUMP_DIRECTION[m], g0[m], g1):
            tau, x_near = _illinois(lambda s: guard(m, s, dense(s)), dense, t0, t1, g0[m], g1, tol)
            earlier = best is None or tau < best[1] - tol or (
                tau <= best[1] + tol and module.JUMP_PRIORITY[m] < module.JUMP_PRIORITY[best[0]])
            if earlier and module.enabled(m, tau, x_near, inputs(tau, x_near), p, d) >= 0.0:
                best = (m, tau, x_near)
        g0[m] = g1
    return best


def _illinois(g, dense, a, b, ga, gb, tol):
    """The near end of a bracket of g's root on [a, b] no wider than tol, and the state there
    (as the generated module's `locate`)."""
    s = 1.0 if ga > 0 else -1.0
    side, width = 0, b - a
    for _ in range(200):
        if b - a <= tol:
            break
        c = b - gb * (b - a) / (gb - ga)
        if not (a < c < b) or (b - a) > 0.5 * width:
            c = 0.5 * (a + b)
        width = b - a
        gc = g(c)
        if s * gc <= 0.0:
            b, gb = c, gc
            ga = ga * 0.5 if side == 1 else ga
            side = 1
        else:
            a, ga = c, gc
            gb = gb * 0.5 if side == -1 else gb
            side = -1
    return a, dense(a)
