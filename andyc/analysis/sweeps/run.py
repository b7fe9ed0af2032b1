"""Running a sweep on Dask (dask.distributed): batches of points as tasks, each result written to the store
as its batch completes.

The points not yet in the store are cut into batches of consecutive points (enough per task that the
scheduler's few milliseconds per task do not dominate tiny runs, few enough that every worker gets several
tasks to balance); each batch is one task, worker.run_batch, which sends back the batch's results. The
client writes them into the store in the order they complete, so a worker that dies loses only the batch
it was running, which the scheduler runs again on another worker; and rerunning the same sweep computes
only the points the store lacks. By default the cluster is a LocalCluster of processes, one per core, made
for the sweep and closed after it; `scheduler` names an existing one (its workers need andyc and the build
folder at the same path).
"""

from __future__ import annotations

import logging
import math
import os
from dataclasses import dataclass, field

import numpy as np

from andyc.analysis.sweeps import store
from andyc.analysis.sweeps.points import Points, check_names
from andyc.analysis.sweeps.worker import Settings, run_batch
from andyc.runtime.progress import Progress
from andyc.runtime.status import OUTCOMES

CONNECT_TIMEOUT = 5.0       # seconds to reach a scheduler before giving up
MAX_BATCH = 256
TASKS_PER_WORKER = 8


class SweepError(RuntimeError):
    """A sweep that cannot run: the scheduler unreachable, a batch that failed as a whole."""


@dataclass
class Summary:
    """What a sweep did: the points computed now and in the store already, and how many ended how."""
    store: str
    points: int
    computed: int
    already: int
    outcomes: dict = field(default_factory=dict)        # outcome name -> count, over the whole store
    workers: int = 0
    batches: int = 0
    pids: set = field(default_factory=set)              # the worker processes that ran batches

    def text(self) -> str:
        counts = ", ".join(f"{k} {v}" for k, v in self.outcomes.items() if v)
        if not self.computed:
            return f"{self.store}: {self.points} points, all in the store already (nothing to compute): {counts}"
        return (f"{self.store}: {self.points} points ({self.computed} computed now in {self.batches} batches on "
                f"{self.workers} workers, {self.already} already in the store): {counts}")


def batch_size(todo: int, workers: int, batch: int | None = None) -> int:
    """Points per task: `batch`, or about TASKS_PER_WORKER tasks per worker, at most MAX_BATCH points."""
    if batch is not None:
        return batch
    return max(1, min(MAX_BATCH, math.ceil(todo / (max(1, workers) * TASKS_PER_WORKER))))


def run_sweep(model, points: Points, settings: Settings, store_path, *, client=None, scheduler: str | None = None,
              workers: int | None = None, batch: int | None = None, progress: bool | None = None,
              inputs=()) -> Summary:
    """Run every point of `points` not yet in the store at store_path; returns the Summary.

    client: a dask.distributed Client to use (kept open); else scheduler: the address of one to connect to;
    else a LocalCluster of `workers` processes (default: one per core), closed at the end."""
    from andyc.analysis.sweeps.metrics import compile_metric

    check_names(points.names, model)
    store.check_names(points, settings)
    for name, text in settings.metrics:         # refused here, before any cluster starts
        compile_metric(name, text, model)
    done = store.open_store(store_path, model, points, settings, inputs)
    todo = np.flatnonzero(~done)
    summary = Summary(str(store_path), points.n, 0, int(done.sum()))
    if len(todo):
        with _cluster(client, scheduler, workers) as connected:
            summary.workers = len(connected.scheduler_info(n_workers=-1)["workers"]) or workers or 1
            _run(connected, model, points, settings, store_path, todo, batch_size(len(todo), summary.workers, batch),
                 progress, summary)
    outcome = _outcomes(store_path)
    summary.outcomes = {name: int(np.count_nonzero(outcome == code)) for code, name in OUTCOMES.items() if code}
    return summary


def _run(client, model, points, settings, store_path, todo, size, progress, summary) -> None:
    from dask.distributed import as_completed

    batches = [todo[i:i + size] for i in range(0, len(todo), size)]
    futures = [client.submit(run_batch, settings, b, points.values[b], pure=False) for b in batches]
    summary.batches = len(batches)
    with Progress(f"{model.name} sweep", len(todo), unit="points", enabled=progress) as bar:
        try:
            for future in as_completed(futures, loop=client.loop):
                try:
                    results = future.result()
                except Exception as exc:        # a batch failed as a whole (the build missing on a worker, ...)
                    raise SweepError(f"a batch of points failed on a worker: {_reason(exc)}; the points done "
                                     f"are in {store_path}, rerun to compute the rest") from None
                store.write_batch(store_path, points, settings, results)
                summary.computed += len(results["index"])
                summary.pids.add(results["pid"])
                bar(summary.computed)
        finally:
            for future in futures:
                future.cancel()


def _reason(exc: BaseException) -> str:
    return str(exc) if str(exc) else type(exc).__name__


def _outcomes(store_path) -> np.ndarray:
    import zarr

    return np.asarray(zarr.open_group(str(store_path), mode="r")["outcome"][...])


class _cluster:
    """The client to run on: the one given; one connected to `scheduler`; or a new LocalCluster's."""

    def __init__(self, client, scheduler, workers):
        self.client, self.scheduler, self.workers = client, scheduler, workers
        self.made = []

    def __enter__(self):
        if self.client is not None:
            return self.client
        from dask.distributed import Client, LocalCluster

        if self.scheduler is not None:
            try:
                client = Client(self.scheduler, timeout=CONNECT_TIMEOUT, set_as_default=False)
            except (OSError, TimeoutError, ValueError) as exc:
                raise SweepError(f"cannot reach the Dask scheduler at {self.scheduler} within {CONNECT_TIMEOUT:g} s "
                                 f"({_reason(exc)}); check the address (tcp://HOST:8786) and that `dask scheduler` "
                                 f"runs there") from None
            self.made.append(client)
            return client
        logger = logging.getLogger("distributed")     # its INFO lines, as workers start and stop: quiet
        self.made.append(_Level(logger, logger.level))
        logger.setLevel(logging.ERROR)
        cluster = LocalCluster(n_workers=self.workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                               dashboard_address=":0", silence_logs=logging.ERROR)
        self.made.insert(0, cluster)
        client = Client(cluster, set_as_default=False)
        self.made.insert(0, client)
        return client

    def __exit__(self, *exc):
        for thing in self.made:         # the client, the cluster, then the logger's level as it was
            thing.close()


@dataclass
class _Level:
    logger: logging.Logger
    level: int

    def close(self) -> None:
        self.logger.setLevel(self.level)
