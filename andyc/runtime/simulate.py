"""simulate(): one entry point over every integrator.

    rk4                fixed step, compiled loop (andyc.runtime.rk4); constraint
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

Runs stop, keep their samples and say why when the state becomes non-finite
or the mass matrix stops being positive definite. Long runs print progress.
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np
from scipy import integrate

from andyc.errors import SimulationError
from andyc.runtime import rk4
from andyc.runtime.compiled import CompiledModel, Workspace
from andyc.runtime.run import Run

SCIPY_METHODS = {"DOP853": integrate.DOP853, "Radau": integrate.Radau, "LSODA": integrate.LSODA,
                 "RK45": integrate.RK45, "BDF": integrate.BDF}
FIXED_STEP = ("rk4", "projection", "lagrange", "baumgarte")
METHODS = FIXED_STEP + tuple(SCIPY_METHODS)
INIT = ("check", "project", "as-is")
_RHS = {"rk4": "rhs_into", "projection": "rhs_into", "lagrange": "rhs_lagrange_into",
        "baumgarte": "rhs_baumgarte_into"}


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
             init: str = "check", init_tol: float = 1e-6) -> Run:
    """Integrate `model` from t = 0 to t_end and return the logged Run.

    dt is the step of rk4 and the output spacing of the adaptive methods;
    every N logs one sample in N steps. frames: None, "all" or a list of names.
    normalize: rk4 renormalizes quaternion signals after each step. (The
    adaptive methods do not; their norm drift stays within the tolerances and
    never reaches the dynamics, whose rotation matrices are exact for any norm.)
    energy_correction: the projection method's energy correction (Braun &
    Goldfarb eq. 5-6, applied when 2T > energy_tol); default on when the
    model declares energy conserved. init, init_tol: see the module docstring.
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
    if not (t_end > 0 and dt > 0 and every >= 1):
        raise SimulationError(f"need t_end > 0, dt > 0 and every >= 1, got t_end={t_end}, dt={dt}, every={every}")
    p = model.parameters(parameters)
    u = model.inputs(inputs)
    x = np.array(model.initial_state(p) if x0 is None else x0, dtype=np.float64)
    if x.shape != (model.nx,):
        raise SimulationError(f"initial state has shape {x.shape}, expected ({model.nx},)")
    frame_names = _frame_selection(model, frames)
    initial = consistent_initial_state(model, x, u, p, init, init_tol) if model.nc else {}
    if method in ("lagrange", "baumgarte") and model.nc:
        _require_independent_rows(model, method, x, u, p)
    bar = Progress(f"{model.name} {method}", t_end, progress)
    start = time.perf_counter()
    try:
        if method in FIXED_STEP:
            rhs = getattr(model.module, _RHS[method] if model.nc else "rhs_into")
            constrain = method == "projection" and model.nc > 0
            etol = energy_tol if energy_correction else -1.0
            e0 = model.module.energy(0.0, x, u, p)
            project = constrain or etol >= 0 or (normalize and bool(model.quaternions))
            t_log, x_log, status, stats = _run_rk4(model, rhs, x, u, p, t_end, dt, every, bar,
                                                   (project, constrain, e0, etol))
        else:
            t_log, x_log, status, stats = _run_scipy(model, method, x, u, p, t_end, dt * every, rtol, atol, bar)
    finally:
        bar.close()
    stats["wall_seconds"] = time.perf_counter() - start
    stats.update(initial)
    energy = np.empty(t_log.shape[0])
    rk4.evaluate_energy(model.module.energy, t_log, x_log, u, p, energy)
    n = t_log.shape[0]
    phi, c, lam = np.empty((n, model.nh)), np.empty((n, model.nc)), np.empty((n, model.nc))
    if model.nc:
        rk4.evaluate_constraints(model.module.constraints, model.module.multipliers, t_log, x_log, u, p,
                                 phi, c, lam, np.empty((model.nv, model.nv)), np.empty(model.nv))
    frames_out = {}
    if frame_names:
        xyz = np.empty((t_log.shape[0], len(model.frame_names), 3))
        rk4.evaluate_frames(model.module.frame_positions, t_log, x_log, u, p, xyz)
        frames_out = {name: xyz[:, model.frame_names.index(name)] for name in frame_names}
    return Run(model=model.name, spec_sha256=model.spec_sha256, method=method, dt=dt, nq=model.nq, nv=model.nv,
               rtol=rtol if method != "rk4" else 0.0, atol=atol if method != "rk4" else 0.0, t_end=t_end,
               parameters=dict(zip(model.parameter_names, map(float, p))),
               inputs=dict(zip(model.input_names, map(float, u))), state_names=list(model.state_names),
               time=t_log, state=x_log, energy=energy, frames=frames_out, status=status, stats=stats,
               multiplier_names=list(model.multiplier_names), multipliers=lam, residual_position=phi,
               residual_velocity=c, energy_correction=bool(energy_correction))


def constraint_residuals(model: CompiledModel, t: float, x, u, p):
    """(phi, c): holonomic residuals (NH,) and velocity-level residuals (NC,) at (t, x)."""
    phi, c = np.empty(model.nh), np.empty(model.nc)
    model.module.constraints(t, x, u, p, phi, c, np.empty((model.nc, model.nv)), np.empty(model.nc))
    return phi, c


def _require_independent_rows(model: CompiledModel, method: str, x, u, p) -> None:
    """Multipliers (ANDY eq. 12) need independent rows; name the first row that is not."""
    A = np.zeros((model.nc, model.nv))
    model.module.constraints(0.0, x, u, p, np.empty(model.nh), np.empty(model.nc), A, np.empty(model.nc))
    tol = 1e-8 * max(np.linalg.norm(A, 2), 1e-300)
    for k in range(model.nc):
        if np.linalg.matrix_rank(A[:k + 1], tol=tol) <= k:
            earlier = sorted(set(model.constraint_rows[:k]))
            raise SimulationError(
                f"{model.row_location(k)}: row {k} of the constraints (in '{model.constraint_rows[k]}') is a "
                f"combination of earlier rows (in {', '.join(repr(e) for e in earlier)}) at the initial state: the "
                f"constraints are redundant or the pose is singular, so the {method} method's multipliers are not "
                f"unique; remove the redundant constraint, or use --method projection, which allows them")


def consistent_initial_state(model: CompiledModel, x, u, p, init: str, init_tol: float) -> dict:
    """Measure (and with init="project", remove) the initial state's constraint residuals.

    Projection repeats the Braun & Goldfarb position and velocity corrections
    (the smallest change in the mass-matrix metric) until the residuals are
    at round-off. x is changed in place; returns the figures for run stats.
    """
    phi, c = constraint_residuals(model, 0.0, x, u, p)
    out = {"initial_position_residual": float(np.max(np.abs(phi), initial=0.0)),
           "initial_velocity_residual": float(np.max(np.abs(c), initial=0.0))}
    worst = max(out.values())
    if init == "as-is" or worst <= (init_tol if init == "check" else 0.0):
        return out
    if init == "check":
        rows = np.concatenate([np.abs(phi), np.abs(c)])
        k = int(np.argmax(rows))
        row = k if k < model.nh else k - model.nh
        level = "position" if k < model.nh else "velocity"
        raise SimulationError(
            f"{model.row_location(row)}: the initial state is off the constraint manifold: largest residual "
            f"{rows[k]:.3g} at the {level} level (constraint '{model.constraint_rows[row]}'; all rows: position "
            f"{out['initial_position_residual']:.3g}, velocity {out['initial_velocity_residual']:.3g}), past the bound "
            f"{init_tol:g}; fix the initial values, or use --init project to move the state onto the manifold "
            f"(the smallest change in the mass-matrix metric), or --init as-is to start from it anyway")
    M, G = np.empty((model.nv, model.nv)), np.empty(model.nv)
    for _ in range(50):
        if model.module.project(0.0, x, u, p, True, 0.0, -1.0, M, G) != rk4.OK:
            raise SimulationError("cannot project the initial state: the mass matrix is not positive definite there")
        phi, c = constraint_residuals(model, 0.0, x, u, p)
        if max(np.max(np.abs(phi), initial=0.0), np.max(np.abs(c), initial=0.0)) <= 1e-13 * max(1.0, np.abs(x).max()):
            out["initial_projection"] = float(worst)
            return out
    raise SimulationError(f"cannot project the initial state onto the constraint manifold (residuals still "
                          f"{np.max(np.abs(phi), initial=0.0):.3g}, {np.max(np.abs(c), initial=0.0):.3g} after 50 "
                          f"corrections); the constraints may have no solution near it: check the initial values")


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


_STOPPED = {rk4.NONFINITE: "the state became non-finite (NaN or Inf)",
            rk4.SINGULAR_MASS: "the mass matrix is not positive definite",
            rk4.DEPENDENT: "the constraint rows are linearly dependent (redundant constraints, or a singular "
                           "configuration); the multipliers are not unique, use --method projection"}


def _run_rk4(model, rhs, x, u, p, t_end, dt, every, bar, projection):
    n_steps = int(round(t_end / dt))
    if abs(n_steps * dt - t_end) > 1e-9 * max(1.0, t_end):
        raise SimulationError(f"t_end = {t_end} is not a whole number of steps dt = {dt}; "
                              f"use t_end = {n_steps * dt:g} or another dt")
    rows = n_steps // every + 1
    out_t = np.empty(rows)
    out_x = np.empty((rows, model.nx))
    out_t[0], out_x[0] = 0.0, x
    ws = Workspace.for_model(model)
    done, row, chunk, status = 0, 1, 1000, rk4.OK
    while done < n_steps and status == rk4.OK:
        n = min(chunk, n_steps - done)
        tic = time.perf_counter()
        steps, row, status = rk4.rk4_chunk(rhs, model.module.project, *projection, 0.0, dt, done, n, every,
                                           x, u, p, out_t, out_x, row, ws.M, ws.G, ws.k, ws.x_tmp)
        done += steps
        elapsed = time.perf_counter() - tic
        chunk = int(min(max(chunk * 0.25 / max(elapsed, 1e-6), 1000), 10_000_000))
        bar(done * dt)
    message = "finished"
    if status != rk4.OK:
        message = (f"stopped: {_STOPPED[status]} at t = {done * dt:.9g} s, step {done}; "
                   f"the {row} samples before it are kept")
    projections = done if projection[1] else 0
    return out_t[:row], out_x[:row], message, {"steps": done, "rhs_evaluations": 4 * done, "projections": projections}


class _Stopped(Exception):
    pass


def _run_scipy(model, method, x0, u, p, t_end, dt_out, rtol, atol, bar):
    ws = Workspace.for_model(model)
    xdot = np.empty(model.nx)
    calls = [0]

    def fun(t, x):
        calls[0] += 1
        status = model.module.rhs_into(t, x, u, p, xdot, ws.M, ws.G)
        if status != rk4.OK:
            raise _Stopped(t, status)
        return xdot.copy()

    n_out = int(math.floor(t_end / dt_out + 1e-9)) + 1
    grid = np.arange(n_out) * dt_out
    if grid[-1] < t_end - 1e-12 * t_end:
        grid = np.append(grid, t_end)
    out_x = np.empty((grid.shape[0], model.nx))
    out_x[0] = x0
    row = 1
    solver = SCIPY_METHODS[method](fun, 0.0, x0, t_end, rtol=rtol, atol=atol)
    status = "finished"
    steps = 0
    try:
        while solver.status == "running":
            message = solver.step()
            steps += 1
            if solver.status == "failed":
                status = f"stopped: {method} failed at t = {solver.t:.9g} s: {message}"
                break
            if not np.all(np.isfinite(solver.y)):
                status = f"stopped: the state became non-finite (NaN or Inf) at t = {solver.t:.9g} s"
                break
            if row < grid.shape[0] and grid[row] <= solver.t:
                dense = solver.dense_output()
                while row < grid.shape[0] and grid[row] <= solver.t:
                    out_x[row] = dense(grid[row])
                    row += 1
            bar(solver.t)
    except _Stopped as exc:
        status = f"stopped: {_STOPPED[exc.args[1]]} at t = {exc.args[0]:.9g} s"
    if status != "finished":
        status += f"; the {row} samples before it are kept"
    return grid[:row], out_x[:row], status, {"steps": steps, "rhs_evaluations": calls[0]}
