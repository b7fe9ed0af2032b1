"""The batched engine: a batch of sweep points in one compiled call, not one andyc.simulate each.

A point run alone pays, around its compiled loop, a Python simulate() call: its checks, the run's log of every
step, then the energy, residuals and powers at every logged sample (`_Assembly`), most of it holding the GIL, so
that threads scale poorly and a short run costs more around its loop than in it. Here each point's start is still
set up and checked by simulate's own code (andyc.runtime.simulate.start_run: its parameters, inputs, initial
state on the constraints), then the whole batch runs in one call of andyc_numerics' batch.run_points, without
the GIL, keeping only what the store keeps: the final state and the trajectory's samples. The steps are the
single run's integrator.advance on the same grid, so each point's states equal `andyc sim`'s bit for bit.

It takes the sweeps a single run would answer with nothing but those (batched): a fixed-step method, a model
without jumps (hence without contacts), no metric (a metric reads the whole run), no per-point wall-clock limit,
and no drifting method on constrained rows (rk4 and lagrange: the run's status then depends on the residuals at
every sample, andyc.runtime.status.lost_constraints). Any other sweep, and any point the batch could not take to
its end (a start simulate refuses, a run that stops or blows up), runs alone through worker.record, so that its
outcome and message are the single run's.
"""

from __future__ import annotations

import math
import time

import numpy as np

from andyc.numerics.status import OK
from andyc.runtime.methods import FIXED_STEP
from andyc.runtime.status import DRIFTING_METHODS, FINISHED, FINISHED_CODE


def batched(model, settings) -> bool:
    """Whether the points of a sweep with these Settings run batched (see the module's docstring)."""
    return (settings.method in FIXED_STEP and model.nj == 0 and not settings.metrics and settings.timeout is None
            and settings.basin is None and not (model.nc and settings.method in DRIFTING_METHODS))


def run_batched(out: dict, model, settings, values) -> None:
    """Run the points `values` (one row each) into the rows of `out` (worker.empty_results): those whose start
    simulate accepts in one compiled call, the others, and those that did not finish there, one by one
    (worker.record). KeyboardInterrupt when worker.stop() ended the batch (its results are not kept)."""
    from andyc.analysis.sweeps.worker import STOP_FLAG, point_arguments, record, sample_rows, sample_times
    from andyc.runtime.simulate import start_run

    rows, starts, alone = [], [], []
    for row, point in enumerate(values):
        try:
            starts.append(start_run(model, settings.t_end, compile=False, **point_arguments(model, settings, point)))
            rows.append(row)
        except Exception:           # (refused: the single run says why, as its record)
            alone.append(row)
    steps = int(round(settings.t_end / settings.dt))
    whole = abs(steps * settings.dt - settings.t_end) <= 1e-9 * max(1.0, settings.t_end)
    if not whole or len({tuple(sorted(s.source.drives.items())) for s in starts}) > 1:
        rows, starts, alone = [], [], list(range(len(values)))      # (each run alone says why, or differs)
    if starts:
        grid = np.arange(steps + 1) * settings.dt        # the run's logged times: 0.0 + i dt, as advance sums them
        times = sample_times(settings)
        marks, reached = sample_rows(grid, times)
        status, done, samples, X, F, D, wall, cpu = _run(model, settings, starts, steps, marks.astype(np.int64),
                                                           STOP_FLAG)
        if np.any(status == _compiled(model).NOT_RUN):
            raise KeyboardInterrupt     # the sweep's end, not the points' (as record() takes an interrupted run)
        finished = status == OK
        share_wall, share_cpu = wall / len(starts), cpu / len(starts)
        for j, row in enumerate(rows):
            if not finished[j]:
                alone.append(row)
                continue
            out["outcome"][row], out["message"][row] = FINISHED_CODE, FINISHED
            out["wall"][row], out["cpu"][row] = share_wall, share_cpu
            out["t_final"][row], out["final"][row] = grid[-1], X[j, :model.nx]
            out["final_discrete"][row], out["final_flow"][row] = D[j], F[j]
            out["jump_count"][row] = 0
            if settings.trajectory:
                out["trajectory_time"][row] = np.where(reached, times, math.nan)
                out["trajectory"][row] = np.where(reached[:, None], samples[j], math.nan)
    for row in sorted(alone):
        record(out, row, model, [], settings, values[row])


def _run(model, settings, starts, steps: int, marks: np.ndarray, stop: np.ndarray):
    """One call of batch.run_points over the started points: (status, done, samples, X, F, D, wall s, CPU s)."""
    from andyc.numerics.status import OK
    from andyc.runtime.compiled import projects, variant, work
    from andyc.runtime.fixed_step import MODE
    from andyc.runtime.inputs import inputs_at
    from andyc.runtime.work import JumpWork, law_offset, with_work

    first = starts[0]
    method, projection = settings.method, first.projection      # (resolved alike for every point of the model)
    X = np.stack([with_work(model, s.x) for s in starts])
    P = np.stack([s.p for s in starts])
    D = np.stack([s.d for s in starts]).reshape(len(starts), model.nd)
    F = np.array([s.flow for s in starts], dtype=np.int64)
    U = np.stack([s.source.held(s.flow) for s in starts]).reshape(len(starts), len(model.input_names))
    function = first.source.function_data[0]
    data = None if function is None else np.stack([s.source.function_data[1] for s in starts])
    E0 = np.empty(len(starts))
    for j, s in enumerate(starts):      # the energy correction's offset at the start, as run_fixed_step finds it
        u = inputs_at(model, s.source, 0.0, s.x, s.p, s.d, s.flow)
        E0[j] = law_offset(model, s.flow, JumpWork(model, X[j], u, s.p, s.d, 0.0).add(X[j], u, s.d))
    status, done = np.full(len(starts), OK, np.int64), np.zeros(len(starts), np.int64)
    samples = np.full((len(starts), len(marks), model.nx), math.nan)
    etol = projection.energy_tol if projection.energy_correction else -1.0
    w = work(model)
    tic, cpu = time.perf_counter(), time.thread_time()
    _compiled(model).run_points(
        model.ref, w.ref, int(MODE[method]), bool(projects(model, method, projection)),
        bool(method == "projection" and model.nc > 0), float(etol), float(first.jumps.event_tol), function, data, P, U,
        D, X, F, E0, int(steps), float(settings.dt), marks, stop, status, done, samples,
        *variant(model, method, projection))
    return status, done, samples, X, F, D, time.perf_counter() - tic, time.thread_time() - cpu


def _compiled(model):
    """The build's batch module (andyc_numerics/batch.py), imported on first use: a single run never needs it."""
    import importlib

    return importlib.import_module(f"{model.numerics.__name__}.batch")
