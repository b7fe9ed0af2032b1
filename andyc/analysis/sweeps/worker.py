"""What a worker does: run a batch of points of a sweep on the compiled model, loaded once per process.

A task carries no compiled code: only the build's path and key (Settings) and the batch's values. The
worker imports the generated module from the build folder the first time (Numba loads its functions from
the cache beside it, andyc.runtime.compiled.load_compiled) and keeps it, with the parsed metrics, for every
later batch of the process. A point that fails -- a run refused (an initial state off the constraints), an
exception -- is recorded as failed with its message; it never fails the batch.

Each point is andyc.simulate with the point's parameters, inputs and initial state, the same call a serial
run makes, so its final state is the serial run's bit for bit.
"""

from __future__ import annotations

import math
import os
import threading
import time
from dataclasses import dataclass

import numpy as np

from andyc.errors import SimulationError, printable

ROUNDOFF = 1e-12            # relative: a sample time and a logged time this close are the same instant
MESSAGE_CHARS = 8192        # a status message is kept whole up to this many characters (a variable-length string)


@dataclass(frozen=True)
class Settings:
    """One sweep's runs, as plain data (what a task sends): the build, the swept names and the run options."""
    build: str                  # the generated module's path, as the workers see it
    build_key: str
    names: tuple                # swept names
    kinds: tuple                # ("parameter" | "input" | "state", index) of each
    t_end: float
    dt: float = 1e-3
    method: str = "rk4"
    rtol: float = 1e-8
    atol: float = 1e-10
    fixed: tuple = ()           # (name, value): --set values every point shares
    stop_after: tuple = ()      # (jump, n)
    init: str = "check"
    timeout: float | None = None  # wall-clock seconds a point may take
    metrics: tuple = ()         # (name, text)
    max_events: int = 20        # jump times kept per point
    trajectory: int = 0         # samples of the decimated trajectory kept per point (0: none)
    basin: object = None        # an andyc.analysis.basins.Basin: each point classified step by step (record_point)

    @classmethod
    def of(cls, model, names, t_end: float, **options) -> "Settings":
        """The settings of a sweep of `names` on a CompiledModel (its build as loaded here), with the run
        options of Settings' fields (dt, method, metrics, ...). PointsError for a name it cannot sweep."""
        from andyc.analysis.sweeps.points import check_names, sweepable

        check_names(names, model)
        known = sweepable(model)
        return cls(str(model.path), model.module.BUILD_KEY, tuple(names), tuple(known[n] for n in names), t_end,
                   **options)

    def options(self) -> dict:
        """What the store records of the runs, to refuse resuming with other options."""
        return {"t_end": self.t_end, "dt": self.dt, "method": self.method, "rtol": self.rtol, "atol": self.atol,
                "fixed": [list(f) for f in self.fixed], "stop_after": [list(s) for s in self.stop_after],
                "init": self.init, "timeout": self.timeout, "metrics": [list(m) for m in self.metrics],
                "max_events": self.max_events, "trajectory": self.trajectory,
                **({"basin": self.basin.options()} if self.basin is not None else {})}


_LOADED: dict = {}          # (build path, build key) -> CompiledModel: once per worker process
_METRICS: dict = {}         # (build path, build key, metrics) -> [Metric]


def loaded(settings: Settings):
    """(CompiledModel, [Metric]) of the settings' build and metrics, imported and parsed once per process."""
    key = (settings.build, settings.build_key)
    if key not in _LOADED:
        from andyc.runtime.compiled import load_compiled

        if not os.path.exists(settings.build):
            raise SimulationError(f"{settings.build}: no such file on this worker; a cluster's workers need the "
                                  f"build folder at the same path (a shared file system)")
        model = load_compiled(settings.build)
        if model.module.BUILD_KEY != settings.build_key:
            raise SimulationError(f"{settings.build}: holds another build of {model.name} than the sweep's; "
                                  f"rebuild, then rerun the sweep")
        _LOADED[key] = model
    model = _LOADED[key]
    if key + (settings.metrics,) not in _METRICS:
        _METRICS[key + (settings.metrics,)] = []
        if settings.metrics:        # (the parser, and SymPy under it, imported only for metrics)
            from andyc.analysis.sweeps.metrics import compile_metric

            _METRICS[key + (settings.metrics,)] = [compile_metric(n, t, model) for n, t in settings.metrics]
    return model, _METRICS[key + (settings.metrics,)]


def sample_times(settings: Settings) -> np.ndarray:
    """The times of a point's kept trajectory: --trajectory N evenly spaced from 0 to t_end, as decimals (the
    store's time coordinate, which `ds.sel(time=0.15)` finds)."""
    from andyc.analysis.sweeps.points import decimal_axis

    return decimal_axis(0.0, settings.t_end, settings.trajectory)


def remember(model, settings: Settings) -> None:
    """Run the settings' points on `model`, a CompiledModel loaded in this process already (the inline
    engine: the model the command compiled, not a second import of its build)."""
    _LOADED.setdefault((settings.build, settings.build_key), model)


def run_batch(settings: Settings, indices: np.ndarray, values: np.ndarray) -> dict:
    """Run the points `indices` (their values: one row each) and return their results, stacked (see
    empty_results for the fields); also the process's id (the tests kill workers by it)."""
    from andyc.analysis.sweeps.batch import batched, run_batched

    model, metrics = loaded(settings)
    out = empty_results(model, settings, len(indices))
    out["index"] = np.asarray(indices, dtype=np.int64)
    if settings.basin is not None:
        from andyc.analysis.basins_batched import run_basins

        run_basins(out, model, settings, values)
    elif batched(model, settings):
        run_batched(out, model, settings, values, metrics)
    else:
        for row, point in enumerate(values):
            record(out, row, model, metrics, settings, point)
    out["pid"] = os.getpid()
    return out


def empty_results(model, settings: Settings, n: int) -> dict:
    """The results of n points, not run: NaN, -1 and empty text."""
    full, nan = np.full, math.nan
    return {"outcome": np.zeros(n, np.int8), "message": full(n, "", dtype=object),
            "t_final": full(n, nan), "final": full((n, model.nx), nan), "final_discrete": full((n, model.nd), nan),
            "final_flow": full(n, -1, dtype=np.int16), "jump_count": np.zeros((n, model.nj), np.int32),
            "event_time": full((n, settings.max_events), nan),
            "event_jump": full((n, settings.max_events), -1, dtype=np.int16),
            "metrics": full((n, len(settings.metrics)), nan), "wall": full(n, nan), "cpu": full(n, nan),
            "trajectory": full((n, settings.trajectory, model.nx), nan),
            "trajectory_time": full((n, settings.trajectory), nan),
            "basin": np.zeros(n, np.int8), "basin_period": np.zeros(n, np.int16), "basin_steps": np.zeros(n, np.int32),
            "basin_distance": full(n, nan)}


STOP = threading.Event()    # set: every point running in this process stops (the inline engine's Ctrl-C)
STOP_FLAG = np.zeros(1, np.int64)   # ... as the batched engine's compiled loop reads it (stop(), resume())


def stop() -> None:
    """End every point running in this process at its next look, and start no other (the inline engine's Ctrl-C)."""
    STOP.set()
    STOP_FLAG[0] = 1


def resume() -> None:
    """Let points run again (after stop())."""
    STOP.clear()
    STOP_FLAG[0] = 0


def interrupts(timeout: float | None):
    """The Interrupts of a point's run: its wall-clock limit, and STOP, which ends it as a signal would (its
    status "interrupted: ..."; record() then ends the batch): a point run in a thread gets no signal itself."""
    from andyc.runtime.interrupts import Interrupts

    class Stoppable(Interrupts):
        def reason(self):
            return "interrupted: the sweep was stopped" if STOP.is_set() else super().reason()

    return Stoppable(timeout)


def point_arguments(model, settings: Settings, point) -> dict:
    """simulate()'s arguments of one point: its values over the settings' fixed ones, and the run options."""
    import andyc

    parameters, inputs, states = {}, {}, {}
    for (name, value) in settings.fixed:
        (inputs if name in model.input_names else parameters)[name] = value
    for (kind, i), name, value in zip(settings.kinds, settings.names, point):
        {"parameter": parameters, "input": inputs, "state": states}[kind][name] = float(value)
    return dict(dt=settings.dt, method=settings.method, parameters=parameters, inputs=inputs,
                x0=states or None,      # (the others at the model's: `andyc sim --at`)
                init=andyc.Init(settings.init), events=andyc.Events(stop_after=dict(settings.stop_after) or None))


def simulate_point(model, settings: Settings, point, frames=()):
    """The Run of one point: andyc.simulate with the point's values over the settings' fixed ones."""
    import andyc

    return andyc.simulate(model, settings.t_end, **point_arguments(model, settings, point), rtol=settings.rtol,
                          atol=settings.atol, frames=list(frames), progress=False,
                          interrupts=interrupts(settings.timeout))


def record(out: dict, row: int, model, metrics: list, settings: Settings, point) -> None:
    """Run one point into row `row` of the results; a failure is recorded, never raised."""
    from andyc.runtime.status import FAILED, INTERRUPTED, outcome

    if settings.basin is not None:
        from andyc.analysis.basins import record_point

        return record_point(out, row, model, settings, point)
    frames = tuple(dict.fromkeys(f for m in metrics for f in m.frames))
    start, cpu = time.perf_counter(), time.thread_time()
    try:
        run = simulate_point(model, settings, point, frames)
    except Exception as exc:            # a point's failure is its record, not the sweep's end
        text = str(exc) if isinstance(exc, SimulationError) else f"{type(exc).__name__}: {exc}"
        out["outcome"][row], out["message"][row] = FAILED, printable(text)[:MESSAGE_CHARS]
        out["wall"][row], out["cpu"][row] = time.perf_counter() - start, time.thread_time() - cpu
        return
    if run.status.startswith(INTERRUPTED):     # a signal to this process: the sweep's end, not the point's
        raise KeyboardInterrupt
    out["outcome"][row], out["message"][row] = outcome(run.status), printable(run.status)[:MESSAGE_CHARS]
    out["wall"][row], out["cpu"][row] = time.perf_counter() - start, time.thread_time() - cpu
    if len(run.time):
        out["t_final"][row], out["final"][row] = run.time[-1], run.state[-1]
        out["final_discrete"][row], out["final_flow"][row] = run.discrete[-1], run.flow[-1]
    record_events(out, row, model, settings, run.events["time"], run.events["jump"])
    record_metrics(out, row, metrics, run)
    if settings.trajectory and len(run.time):
        times = sample_times(settings)
        at, reached = sample_rows(run.time, times)
        out["trajectory_time"][row] = np.where(reached, times, math.nan)
        out["trajectory"][row] = np.where(reached[:, None], run.state[at], math.nan)


def record_metrics(out: dict, row: int, metrics: list, run) -> None:
    """The metrics' values on a point's Run into row `row` (NaN where one cannot be evaluated)."""
    if not metrics:
        return              # (the metrics' module, and SymPy under it, not imported)
    from andyc.analysis.sweeps.metrics import evaluate

    for j, metric in enumerate(metrics):
        try:
            out["metrics"][row, j] = evaluate(metric, run)
        except (ValueError, ArithmeticError, TypeError):
            out["metrics"][row, j] = math.nan


def record_events(out: dict, row: int, model, settings: Settings, times, jumps) -> None:
    """A run's jumps (their times and indices, in order) into row `row`: the count of each, the first max_events."""
    out["jump_count"][row] = np.bincount(jumps, minlength=model.nj)[:model.nj] if model.nj else []
    k = min(len(jumps), settings.max_events)
    out["event_time"][row, :k], out["event_jump"][row, :k] = times[:k], jumps[:k]


def sample_rows(logged: np.ndarray, times: np.ndarray) -> tuple:
    """(rows, reached): the row of a run's logged times that each sample time takes, the last at or before it
    within round-off (so a jump is not smeared, and the grid's 0.7000000000000001 is the sample 0.7); and whether
    the run reached each time (NaN is kept past its end)."""
    slack = times + ROUNDOFF * np.maximum(1.0, np.abs(times))
    rows = np.clip(np.searchsorted(logged, slack, side="right") - 1, 0, len(logged) - 1)
    return rows, times <= logged[-1] + ROUNDOFF * max(1.0, abs(logged[-1]))
