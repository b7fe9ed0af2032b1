"""simulate(): one entry point over every integrator.

    rk4                fixed step, compiled loop (andyc.runtime.rk4)
    DOP853 Radau LSODA scipy's adaptive solvers, stepped one step at a time so
                       that a failed run keeps what it computed

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
METHODS = ("rk4",) + tuple(SCIPY_METHODS)


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
             normalize: bool = True) -> Run:
    """Integrate `model` from t = 0 to t_end and return the logged Run.

    dt is the step of rk4 and the output spacing of the adaptive methods;
    every N logs one sample in N steps. frames: None, "all" or a list of names.
    normalize: rk4 renormalizes quaternion signals after each step. (The
    adaptive methods do not; their norm drift stays within the tolerances and
    never reaches the dynamics, whose rotation matrices are exact for any norm.)
    """
    if method not in METHODS:
        raise SimulationError(f"unknown method '{method}'; available: {', '.join(METHODS)}")
    if not (t_end > 0 and dt > 0 and every >= 1):
        raise SimulationError(f"need t_end > 0, dt > 0 and every >= 1, got t_end={t_end}, dt={dt}, every={every}")
    p = model.parameters(parameters)
    u = model.inputs(inputs)
    x = np.array(model.initial_state(p) if x0 is None else x0, dtype=np.float64)
    if x.shape != (model.nx,):
        raise SimulationError(f"initial state has shape {x.shape}, expected ({model.nx},)")
    frame_names = _frame_selection(model, frames)
    bar = Progress(f"{model.name} {method}", t_end, progress)
    start = time.perf_counter()
    try:
        if method == "rk4":
            t_log, x_log, status, stats = _run_rk4(model, x, u, p, t_end, dt, every, bar,
                                                   normalize and bool(model.quaternions))
        else:
            t_log, x_log, status, stats = _run_scipy(model, method, x, u, p, t_end, dt * every, rtol, atol, bar)
    finally:
        bar.close()
    stats["wall_seconds"] = time.perf_counter() - start
    energy = np.empty(t_log.shape[0])
    rk4.evaluate_energy(model.module.energy, t_log, x_log, u, p, energy)
    frames_out = {}
    if frame_names:
        xyz = np.empty((t_log.shape[0], len(model.frame_names), 3))
        rk4.evaluate_frames(model.module.frame_positions, t_log, x_log, u, p, xyz)
        frames_out = {name: xyz[:, model.frame_names.index(name)] for name in frame_names}
    return Run(model=model.name, spec_sha256=model.spec_sha256, method=method, dt=dt, nq=model.nq, nv=model.nv,
               rtol=rtol if method != "rk4" else 0.0, atol=atol if method != "rk4" else 0.0, t_end=t_end,
               parameters=dict(zip(model.parameter_names, map(float, p))),
               inputs=dict(zip(model.input_names, map(float, u))), state_names=list(model.state_names),
               time=t_log, state=x_log, energy=energy, frames=frames_out, status=status, stats=stats)


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


def _run_rk4(model, x, u, p, t_end, dt, every, bar, project):
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
        steps, row, status = rk4.rk4_chunk(model.module.rhs_into, model.module.normalize, project,
                                           0.0, dt, done, n, every, x, u, p,
                                           out_t, out_x, row, ws.M, ws.G, ws.k, ws.x_tmp)
        done += steps
        elapsed = time.perf_counter() - tic
        chunk = int(min(max(chunk * 0.25 / max(elapsed, 1e-6), 1000), 10_000_000))
        bar(done * dt)
    message = "finished"
    if status == rk4.NONFINITE:
        message = (f"stopped: the state became non-finite (NaN or Inf) at t = {done * dt:.9g} s, step {done}; "
                   f"the {row} samples before it are kept")
    elif status == rk4.SINGULAR_MASS:
        message = (f"stopped: the mass matrix is not positive definite at t = {done * dt:.9g} s; "
                   f"the {row} samples before it are kept")
    return out_t[:row], out_x[:row], message, {"steps": done, "rhs_evaluations": 4 * done}


class _NotPositiveDefinite(Exception):
    pass


def _run_scipy(model, method, x0, u, p, t_end, dt_out, rtol, atol, bar):
    ws = Workspace.for_model(model)
    xdot = np.empty(model.nx)
    calls = [0]

    def fun(t, x):
        calls[0] += 1
        if not model.module.rhs_into(t, x, u, p, xdot, ws.M, ws.G):
            raise _NotPositiveDefinite(t)
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
    except _NotPositiveDefinite as exc:
        status = f"stopped: the mass matrix is not positive definite at t = {exc.args[0]:.9g} s"
    if status != "finished":
        status += f"; the {row} samples before it are kept"
    return grid[:row], out_x[:row], status, {"steps": steps, "rhs_evaluations": calls[0]}
