"""Basin maps on the batched engine: every start of a batch steps at once, one step (a crossing of J) per call.

A start's classification (andyc.analysis.basins.Walk) reads its steps one by one, each a run of rk4 from the
state just after the last crossing to the next, for at most t_step (`andyc sim --stop-after J=1`). Run alone,
each step is an andyc.simulate call (basins.classify). Here each step of every start not yet classified is
a point of andyc.analysis.sweeps.batch.Batch: started by simulate's own code (start_run, the start as it is),
stepped in compiled calls over all of them without the GIL, its crossing finished by the single run's after_jump,
which ends it (stop_after); its Run, for the fall condition, assembled from its log by simulate's own code. So
each step's end is the single run's bit for bit, and so is each class. A start the batch cannot take (its start
off the constraints, a step simulate refuses, a step that stops: blows up, Zeno) is classified alone
(basins.record_point), so that its record and message are the single run's.
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np

from andyc.runtime.status import FINISHED


def run_basins(out: dict, model, settings, values) -> None:
    """Classify the starts `values` (a row each) into the rows of `out` (worker.empty_results), as record_point
    does one by one. KeyboardInterrupt when worker.stop() ended it (its results are not kept)."""
    from andyc.analysis.basins import Walk, _loaded, record_point, record_walk, start_state
    from andyc.analysis.sweeps.batch import grid_steps, log_group

    basin = settings.basin
    derivatives, fall = _loaded(model, basin)
    held = [kind_index for (_, kind_index) in settings.kinds]
    walks, alone = {}, set()
    for row, point in enumerate(values):
        try:
            walks[row] = Walk(model, basin, start_state(model, derivatives, basin, held, np.asarray(point, float)),
                              fall)
        except Exception:           # (record_point says why)
            alone.add(row)
    steps = grid_steps(basin.t_step, basin.dt)
    if steps is None:
        alone, walks = set(range(len(values))), {}          # (each step alone says why)
    else:
        step = _Step(model, settings, steps, log=fall is not None)
        # (the fall condition reads the step's run: each point logs every grid point)
        group = log_group(model, steps) if fall is not None else max(1, len(values))
    spent = {row: [0.0, 0.0] for row in walks}          # wall, CPU
    while walks:
        rows = list(walks)
        for a in range(0, len(rows), group):
            alone.update(step({row: walks[row] for row in rows[a:a + group]}, spent))
        for row in rows:
            walk = walks[row]
            if row in alone:
                del walks[row]
            elif walk.done:
                record_walk(out, row, settings, walk.out)
                out["wall"][row], out["cpu"][row] = spent[row]
                del walks[row]
    for row in sorted(alone):
        record_point(out, row, model, settings, values[row])


class _Step:
    """One step of many starts in one Batch: what every step shares (simulate's options, the step's Settings)
    made once."""

    def __init__(self, model, settings, steps: int, log: bool):
        from andyc.analysis.basins import step_options

        basin = settings.basin
        self.model, self.basin, self.steps, self.log = model, basin, steps, log
        self.options, self.flow = step_options(model, basin), int(model.module.JUMP_TARGET[basin.section])
        self.settings = dataclasses.replace(settings, t_end=basin.t_step, dt=basin.dt, method="rk4", basin=None,
                                            trajectory=0, metrics=(), stop_after=(), timeout=None)

    def __call__(self, walks: dict, spent: dict) -> list:
        """One step of each of `walks` (row -> Walk), its time shared into `spent`; the rows that must be
        classified alone."""
        from andyc.analysis.sweeps.batch import Batch
        from andyc.runtime.simulate import start_run

        model, basin, nx = self.model, self.basin, self.model.nx
        tic, cpu = time.perf_counter(), time.thread_time()
        rows, starts, alone = [], [], []
        for row, walk in walks.items():
            try:
                starts.append(start_run(model, basin.t_step, compile=False, x0=walk.y[:nx], d0=walk.y[nx:],
                                        flow0=self.flow, **self.options))
                rows.append(row)
            except Exception:           # (refused: the single run says why)
                alone.append(row)
        if starts:
            batch = Batch(model, self.settings, starts, self.steps, log=self.log)
            finished = batch.run()
            for j, row in enumerate(rows):
                # (crossed at t = 0, the single run's last sample is the state before the jump: it runs alone)
                crossed = starts[j].jumps.finished and batch.T[j] > 0
                if not (finished[j] or crossed):
                    alone.append(row)
                    continue
                table = starts[j].jumps.table()
                end = (batch.X[j, :nx].copy(), batch.D[j].copy(), int(batch.F[j]))
                walks[row].take(bool(crossed), FINISHED, float(batch.T[j]), table["jump"], table["time"], end,
                                lambda j=j: batch.run_of(j))
        wall, cpu = (time.perf_counter() - tic) / len(walks), (time.thread_time() - cpu) / len(walks)
        for row in walks:
            spent[row][0] += wall
            spent[row][1] += cpu
        return alone


__all__ = ["run_basins"]
