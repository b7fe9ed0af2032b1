"""The batched engine: a batch of sweep points in compiled calls, not one andyc.simulate each.

A point run alone pays, around its compiled loop, a Python simulate() call: its checks, the run's log of every
step, then the energy, residuals and powers at every logged sample (`_Assembly`), most of it holding the GIL, so
that threads scale poorly and a short run costs more around its loop than in it. Here each point's start is still
set up and checked by simulate's own code (andyc.runtime.simulate.start_run: its parameters, inputs, initial
state on the constraints), then the batch runs in calls of andyc_numerics' batch.run_points, without the GIL,
keeping only what the store keeps: the final state, the jumps and the trajectory's samples; with metrics, which
read the whole run, each point also logs every step, and its Run is assembled from that log by simulate's own
code (andyc.runtime.simulate.assemble: energy, frames, residuals at every sample), its points then run in groups
whose logs fit LOG_BYTES. A call returns a
point at its jumps, which Python finishes as a single run does (andyc.runtime.fixed_step.after_jump: a contact's
resolution, the user's function, the event log), and the next call takes the points that go on. The steps are
the single run's integrator.advance on the same grid, so each point's states equal `andyc sim`'s bit for bit.

It takes the sweeps whose points a single run would answer with nothing but those (batched): a fixed-step method
and no per-point wall-clock limit. (A drifting method on constraint rows, rk4 or lagrange, is batched too: a single
run's status reads the residuals of every sample only when it stopped, andyc.runtime.status.lost_constraints, and a
point that stops runs alone. A basin map's starts run on Batches too, a step at a time:
andyc.analysis.basins_batched.) Any other sweep, and any point the batch could not take to the end of its time (a
start simulate refuses, a run that stops, blows up or ends at a jump: Zeno, stop_after, the user's function),
runs alone through worker.record, so that its outcome and message are the single run's.
"""

from __future__ import annotations

import math
import threading
import time

import numpy as np

from andyc.numerics.status import OK
from andyc.runtime.fixed_step import MODE
from andyc.runtime.methods import FIXED_STEP
from andyc.runtime.status import FINISHED, FINISHED_CODE


def batched(model, settings) -> bool:
    """Whether the points of a sweep with these Settings run batched (see the module's docstring)."""
    return settings.method in FIXED_STEP and settings.timeout is None and settings.basin is None


LOG_BYTES = 64e6            # the logs a batch with metrics holds at once (their points run in groups of this)


def grid_steps(t_end: float, dt: float) -> int | None:
    """The fixed steps dt to t_end, None where t_end is not a whole number of them (a single run refuses it:
    andyc.runtime.fixed_step, whose message the caller's single runs then give)."""
    steps = int(round(t_end / dt))
    return steps if abs(steps * dt - t_end) <= 1e-9 * max(1.0, t_end) else None


def log_group(model, steps: int) -> int:
    """How many points that log every one of `steps` steps (a Batch with log) fit LOG_BYTES."""
    width = 2 + model.nx + model.nw + len(model.input_names) + model.nd
    return max(1, int(LOG_BYTES // (8 * width * (steps + 1))))


def run_batched(out: dict, model, settings, values, metrics=()) -> None:
    """Run the points `values` (one row each) into the rows of `out` (worker.empty_results): those whose start
    simulate accepts in compiled calls (Batch), the others, and those that did not reach the end there, one by one
    (worker.record); metrics: the settings' parsed metrics (worker.loaded), evaluated on each point's Run.
    KeyboardInterrupt when worker.stop() ended the batch (its results are not kept)."""
    from andyc.analysis.sweeps.worker import point_arguments, record
    from andyc.runtime.simulate import start_run

    rows, starts, alone = [], [], []
    for row, point in enumerate(values):
        try:
            starts.append(start_run(model, settings.t_end, compile=False, **point_arguments(model, settings, point)))
            rows.append(row)
        except Exception:           # (refused: the single run says why, as its record)
            alone.append(row)
    steps = grid_steps(settings.t_end, settings.dt)
    if steps is None or len({tuple(sorted(s.source.drives.items())) for s in starts}) > 1:
        rows, starts, alone = [], [], list(range(len(values)))      # (each run alone says why, or differs)
    # (a metric reads the whole run: each point logs every step, as a single run does)
    group = log_group(model, steps) if metrics and starts else max(1, len(starts))
    for a in range(0, len(starts), group):
        batch = Batch(model, settings, starts[a:a + group], steps, log=bool(metrics))
        tic, cpu = time.perf_counter(), time.thread_time()
        finished = batch.run()
        for j, row in enumerate(rows[a:a + group]):
            if finished[j]:
                batch.record(out, row, j, metrics)
            else:
                alone.append(row)
        share_wall = (time.perf_counter() - tic) / len(finished)
        share_cpu = (time.thread_time() - cpu) / len(finished)
        for j, row in enumerate(rows[a:a + group]):
            if finished[j]:
                out["wall"][row], out["cpu"][row] = share_wall, share_cpu
    for row in sorted(alone):
        record(out, row, model, list(metrics), settings, values[row])


class Batch:
    """The started points of a batch (andyc.runtime.simulate.Start each) as the arrays of batch.run_points, run
    to their ends: compiled between jumps, each jump finished in Python (fixed_step.after_jump), as run_fixed_step
    finishes it in a single run."""

    def __init__(self, model, settings, starts: list, steps: int, log: bool = False):
        from andyc.analysis.sweeps.worker import sample_rows, sample_times
        from andyc.runtime.compiled import projects, work
        from andyc.runtime.work import with_work

        n, first = len(starts), starts[0]
        self.model, self.settings, self.starts, self.steps = model, settings, starts, steps
        self.projection = first.projection          # (resolved alike for every point of the model)
        self.grid = np.arange(steps + 1) * settings.dt      # the run's logged times: 0.0 + i dt, as advance sums them
        self.times = sample_times(settings)
        marks, self.reached = sample_rows(self.grid, self.times)
        self.marks = marks.astype(np.int64)
        self.X = np.stack([with_work(model, s.x) for s in starts])
        self.P = np.stack([s.p for s in starts])
        self.D = np.stack([s.d for s in starts]).reshape(n, model.nd)
        self.F = np.array([s.flow for s in starts], dtype=np.int64)
        self.U = np.zeros((n, len(model.input_names)))
        self.function = first.source.function_data[0]
        self.data = None if self.function is None else np.stack([s.source.function_data[1] for s in starts])
        self.E0, self.T = np.zeros(n), np.zeros(n)
        self.I, self.M = np.zeros(n, np.int64), np.zeros(n, np.int64)
        self.status, self.jumped = np.zeros(n, np.int64), np.full(n, -1, np.int64)
        self.XE, self.UE = np.zeros_like(self.X), np.zeros_like(self.U)
        self.samples = np.full((n, len(self.marks), model.nx), math.nan)
        rows = steps + 1 if log else 1          # (log: every grid point, as a single run with every = 1 logs)
        self.every = 1 if log else steps + 1    # (steps + 1: no grid point is logged)
        self.log = (np.zeros((n, rows)), np.zeros((n, rows, self.X.shape[1])),
                    np.zeros((n, rows, len(model.input_names))), np.zeros((n, rows), np.int64),
                    np.zeros((n, rows, model.nd)))
        self.R = np.ones(n, np.int64)
        self.w = work(model)
        self.ref = thread_model(model)
        method = settings.method
        self.mode = MODE[method]
        self.options = (int(self.mode), bool(projects(model, method, self.projection)),
                        bool(method == "projection" and model.nc > 0),
                        float(self.projection.energy_tol if self.projection.energy_correction else -1.0),
                        float(first.jumps.event_tol))

    def run(self) -> np.ndarray:
        """Run every point to its end; whether each finished there (the others stopped: a failure, a stop
        message, a jump's failure). KeyboardInterrupt when stop() ended it."""
        from andyc.analysis.sweeps.worker import STOP_FLAG
        from andyc.runtime.compiled import variant
        from andyc.runtime.fixed_step import start_flow
        from andyc.runtime.inputs import inputs_at

        model = self.model
        finished = np.zeros(len(self.starts), bool)
        todo = []
        LT, LX, LU, LF, LD = self.log
        for j, s in enumerate(self.starts):         # the jumps at once at the start, the energy offset
            u = inputs_at(model, s.source, 0.0, s.x, s.p, s.d, s.flow)
            LT[j, 0], LX[j, 0], LU[j, 0], LF[j, 0], LD[j, 0] = 0.0, self.X[j], u, self.F[j], self.D[j]
            flow, message, self.E0[j] = start_flow(model, self.X[j], u, s.source, self.P[j], self.D[j], s.flow,
                                                   s.jumps, self.w, self.mode)
            self.F[j] = flow
            if message is None:
                todo.append(j)
        trailing = variant(model, self.settings.method, self.projection)
        run_points = _compiled(model).run_points
        while todo:
            todo = np.array(todo, dtype=np.int64)
            before_d, before_flow = self.D[todo].copy(), self.F[todo].copy()
            for j in todo:
                self.U[j] = self.starts[j].source.held(self.F[j])
            run_points(self.ref, self.w.ref, *self.options, self.function, self.data, todo, self.P, self.U, self.D,
                       self.X, self.F, self.E0, self.I, self.T, int(self.steps), float(self.settings.dt), self.marks,
                       self.M, STOP_FLAG, self.status, self.jumped, self.XE, self.UE, self.samples, *self.log, self.R,
                       self.every, *trailing)
            if np.any(self.status[todo] == _compiled(model).NOT_RUN):
                raise KeyboardInterrupt     # the sweep's end, not the points' (as record() takes an interrupted run)
            finished[todo] = self.status[todo] == OK
            todo = [j for j, d, flow in zip(todo, before_d, before_flow)
                    if self.status[j] == _compiled(model).JUMPED and self._finish_jump(j, d, flow)]
        return finished

    def _finish_jump(self, j: int, d_before, flow0: int) -> bool:
        """Finish point j's jump (as after_jump does in a single run); whether it goes on (not stopped)."""
        from andyc.runtime.fixed_step import after_jump

        s, w = self.starts[j], self.w
        w.x_event[:], w.u[:] = self.XE[j], self.UE[j]
        flow, message, status, self.E0[j] = after_jump(self.model, int(self.jumped[j]), float(self.T[j]), self.X[j],
                                                       s.source, self.P[j], self.D[j], d_before, int(flow0),
                                                       int(self.F[j]), s.jumps, w, self.mode)
        self.F[j] = flow
        return message is None and status == OK

    def record(self, out: dict, row: int, j: int, metrics=()) -> None:
        """Point j's results (it finished) into row `row` of out, as worker.record keeps a single run's; metrics
        (the Batch logged every step) evaluated on its Run."""
        from andyc.analysis.sweeps.worker import record_events, record_metrics

        model = self.model
        out["outcome"][row], out["message"][row] = FINISHED_CODE, FINISHED
        out["t_final"][row], out["final"][row] = self.T[j], self.X[j, :model.nx]
        out["final_discrete"][row], out["final_flow"][row] = self.D[j], self.F[j]
        jumps = self.starts[j].jumps.table()
        record_events(out, row, model, self.settings, jumps["time"], jumps["jump"])
        if self.settings.trajectory:
            out["trajectory_time"][row] = np.where(self.reached, self.times, math.nan)
            out["trajectory"][row] = np.where(self.reached[:, None], self.samples[j], math.nan)
        if metrics:
            record_metrics(out, row, metrics, self.run_of(j, tuple(f for m in metrics for f in m.frames)))

    def run_of(self, j: int, frames=()):
        """Point j's Run (it finished, also where stop_after ended it; the Batch logged every step), as
        andyc.simulate returns it: a run that stop_after ended between grid points logs its end too
        (run_fixed_step)."""
        from andyc.runtime.simulate import assemble

        n = int(self.R[j])
        log = tuple(a[j, :n] for a in self.log)
        s, t = self.starts[j], float(self.T[j])
        if s.jumps.finished and log[0][-1] != t:
            u = np.empty(len(self.model.input_names))
            x = self.X[j]
            if s.source.into(self.model, t, x[:self.model.nx], self.P[j], self.D[j], int(self.F[j]), u) != OK:
                u[:] = math.nan
            log = tuple(np.concatenate([a, [b]]) for a, b in zip(log, (t, x, u, self.F[j], self.D[j])))
        return assemble(self.model, self.starts[j], self.settings.method, self.settings.dt, self.settings.t_end, log,
                        dict.fromkeys(frames))


_THREAD = threading.local()


def thread_model(model):
    """The compiled Model of `model` (its ref) for this thread: a Model of its own, with the same leaves and tables.
    Each read of a Model's array field in compiled code counts a reference, atomically: threads sharing one Model
    wait on each other's counts (measured on 2 cores, 6-link chain, 2 threads against 1: 0.95-1.83x shared,
    1.41-1.88x each its own)."""
    refs = _THREAD.__dict__.setdefault("refs", {})
    key = (str(model.path), model.module.BUILD_KEY)
    if key not in refs:
        refs[key] = model.numerics.model.new_model(model.module.EQUATIONS, model.module._stubs)
    return refs[key]


def _compiled(model):
    """The build's batch module (andyc_numerics/batch.py), imported on first use: a single run never needs it."""
    import importlib

    return importlib.import_module(f"{model.numerics.__name__}.batch")
