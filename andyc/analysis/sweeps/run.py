"""Running a sweep: in this process on threads (the inline engine, the default without a scheduler), or on
Dask (dask.distributed), batches of points as tasks; each batch's results written to the store as it
completes.

Inline, each thread runs batches of points (worker.run_batch, as a Dask worker does); andyc's compiled loop
runs without the GIL, so the threads share the cores, and no process starts. The rest of this docstring is
the cluster's way.

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
import shutil
from dataclasses import dataclass, field

import numpy as np

from andyc.analysis.sweeps import store
from andyc.analysis.sweeps.points import Points, check_names
from andyc.analysis.sweeps.worker import Settings, run_batch
from andyc.errors import plural
from andyc.runtime.progress import Progress
from andyc.runtime.status import OUTCOMES

CONNECT_TIMEOUT = 5.0       # seconds to reach a scheduler (and for it to answer) before giving up
WORKER_WAIT = 60.0          # seconds to wait for a scheduler's first worker before giving up
MAX_BATCH = 256
TASKS_PER_WORKER = 8
ENGINES = ("auto", "inline", "cluster")
BATCH_SECONDS = 1.0         # inline, a batch of about this long (of one thread's time)
WRITE_SECONDS = 1.0         # inline, the store written at most this often (and at once for the first results)


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
    lost: int = 0                                       # workers of the start gone by the end (died, killed)
    engine: str = "inline"                              # where the points ran: inline (threads) or cluster

    def text(self) -> str:
        counts = ", ".join(f"{k} {v}" for k, v in self.outcomes.items() if v)
        if not self.computed:
            return f"{self.store}: {self.points} points, all in the store already (nothing to compute): {counts}"
        lost = f", {self.lost} of them lost during the sweep" if self.lost else ""
        where = (f"in this process on {plural(self.workers, 'thread')}" if self.engine == "inline" else
                 f"on {plural(self.workers, 'worker')}{lost}")
        return (f"{self.store}: {self.points} points ({self.computed} computed now in {self.batches} batches "
                f"{where}, {self.already} already in the store): {counts}")


def batch_size(todo: int, workers: int, batch: int | None = None) -> int:
    """Points per task: `batch`, or about TASKS_PER_WORKER tasks per worker, at most MAX_BATCH points."""
    if batch is not None:
        return batch
    return max(1, min(MAX_BATCH, math.ceil(todo / (max(1, workers) * TASKS_PER_WORKER))))


def run_sweep(model, points: Points, settings: Settings, store_path, *, client=None, scheduler: str | None = None,
              workers: int | None = None, batch: int | None = None, progress: bool | None = None,
              inputs=(), engine: str = "auto") -> Summary:
    """Run every point of `points` not yet in the store at store_path; returns the Summary.

    Where the points run (`engine`): "inline", in this process on `workers` threads (default: one per core),
    no cluster; "cluster", on Dask: the `client` given (kept open), else one connected to `scheduler`, else
    a LocalCluster of `workers` processes (default: one per core), closed at the end; "auto" (the default):
    on the client or scheduler if one is given, else inline."""
    check_names(points.names, model)
    store.check_names(points, settings)
    if settings.metrics:                        # refused here, before any cluster starts
        from andyc.analysis.sweeps.metrics import compile_metric

        for name, text in settings.metrics:
            compile_metric(name, text, model)
    if client is None and scheduler is not None:
        probe_scheduler(scheduler)          # before the store is made: a bad address leaves no folder behind
    created = not os.path.exists(store_path)
    done = store.open_store(store_path, model, points, settings, inputs)
    todo = np.flatnonzero(~done)
    summary = Summary(str(store_path), points.n, 0, int(done.sum()))
    if engine not in ENGINES:
        raise ValueError(f"engine {engine!r}: one of {', '.join(ENGINES)}")
    if client is not None or scheduler is not None:
        engine = "cluster"
    if engine != "cluster" and len(todo):
        _run_inline(model, points, settings, store_path, todo, progress, summary, batch=batch,
                    threads=workers or os.cpu_count() or 1)
    elif len(todo):
        summary.engine = "cluster"
        try:
            with _cluster(client, scheduler, workers) as connected, _sigint_deferred() as interrupted:
                present = set(connected.scheduler_info(n_workers=-1)["workers"])
                summary.workers = len(present) or workers or 1
                _run(connected, model, points, settings, store_path, todo,
                     batch_size(len(todo), summary.workers, batch), progress, summary, interrupted)
                summary.lost = len(present - set(connected.scheduler_info(n_workers=-1)["workers"]))
        except SweepError:
            if created and not summary.computed:        # the store this call made holds nothing: no trace left
                shutil.rmtree(store_path, ignore_errors=True)
            raise
        summary.workers = len(summary.pids) or summary.workers      # the processes that ran (with a replaced one)
    outcome = _outcomes(store_path)
    summary.outcomes = {name: int(np.count_nonzero(outcome == code)) for code, name in OUTCOMES.items() if code}
    return summary


def _run(client, model, points, settings, store_path, todo, size, progress, summary, interrupted) -> None:
    import time

    batches = [todo[i:i + size] for i in range(0, len(todo), size)]
    futures = [client.submit(run_batch, settings, b, points.values[b], pure=False) for b in batches]
    summary.batches = len(batches)
    pending = list(futures)
    with Progress(f"{model.name} sweep", len(todo), unit="points", enabled=progress) as bar:
        try:
            while pending:
                # Polled, not waited on (as_completed): a Ctrl-C is then taken here, between results, never
                # inside distributed's blocking calls, whose own KeyboardInterrupt path logs a traceback.
                interrupted.check()
                done = [future for future in pending if future.done()]
                if not done:
                    time.sleep(0.02)
                    continue
                pending = [future for future in pending if all(future is not d for d in done)]
                for future in done:
                    try:
                        results = future.result()
                    except Exception as exc:        # a batch failed as a whole (the build missing on a worker, ...)
                        raise SweepError(f"a batch of points failed on a worker: {_reason(exc)}; the points "
                                         f"done are in {store_path}, rerun to compute the rest") from None
                    store.write_batch(store_path, points, settings, results)
                    summary.computed += len(results["index"])
                    summary.pids.add(results["pid"])
                    bar(summary.computed)
        finally:
            for future in futures:
                future.cancel()


def _run_inline(model, points, settings, store_path, todo, progress, summary, threads: int = 1,
                batch=None) -> None:
    """Run the points `todo` in this process on `threads` threads (andyc's compiled loop runs without the
    GIL, so threads share the cores), in batches of about BATCH_SECONDS, their results written to the store by
    this thread: the first at once, then those ended since at most every WRITE_SECONDS (a write costs this
    thread tens of milliseconds, taken from the cores the points run on). A Ctrl-C (or any error) sets
    worker.STOP, which ends the running points at their next look (within a fraction of a second); their
    batches are not written, the batches that ended are."""
    import time
    from concurrent.futures import FIRST_COMPLETED, ThreadPoolExecutor, wait

    from andyc.analysis.sweeps import worker

    worker.remember(model, settings)    # the model compiled here is the one the points run on
    size, submitted, seconds = batch or 1, 0, 0.0
    pending, ended, written = {}, [], -math.inf
    summary.workers = threads

    def write() -> None:
        nonlocal written
        if ended:
            results = {key: np.concatenate([r[key] for r in ended]) for key in ended[0] if key != "pid"}
            store.write_batch(store_path, points, settings, results)
            summary.computed += len(results["index"])
            ended.clear()
        written = time.perf_counter()

    with Progress(f"{model.name} sweep", len(todo), unit="points", enabled=progress) as bar, \
            ThreadPoolExecutor(threads, thread_name_prefix="andyc-sweep") as pool:
        try:
            while submitted < len(todo) or pending:
                while submitted < len(todo) and len(pending) < 2 * threads:     # a few ahead, not all
                    indices = todo[submitted:submitted + size]
                    pending[pool.submit(worker.run_batch, settings, indices, points.values[indices])] = indices
                    submitted += len(indices)
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in finished:
                    del pending[future]
                    ended.append(future.result())
                    summary.batches += 1
                    seconds += float(np.nansum(ended[-1]["wall"]))
                if time.perf_counter() - written >= WRITE_SECONDS or not (pending or submitted < len(todo)):
                    write()
                bar(summary.computed + sum(len(r["index"]) for r in ended))
                if not batch:   # batches of about BATCH_SECONDS: a Ctrl-C loses little;
                    # and, as OpenMP's guided schedule, at most a share of what is left: the threads end together
                    done = summary.computed + sum(len(r["index"]) for r in ended)
                    left = math.ceil((len(todo) - submitted) / (2 * threads))
                    size = max(1, int(min(MAX_BATCH, left, BATCH_SECONDS * done / max(seconds, 1e-9))))
        except BaseException:
            worker.stop()               # the points running now end at their next look; the rest never start
            for future in pending:
                future.cancel()
            write()                     # (the batches that ended are whole: kept)
            raise
        finally:
            pool.shutdown(wait=True)
            worker.resume()


def probe_scheduler(address: str, timeout: float = CONNECT_TIMEOUT) -> dict:
    """Ask the Dask scheduler at `address` who it is, every wait bounded by `timeout` (dask's own connect waits
    for the peer's handshake without end: a plain HTTP server on the port hangs it); its identity, or
    SweepError saying what is at the address."""
    import asyncio

    from distributed.comm import connect

    async def identity():
        comm = await asyncio.wait_for(connect(address, timeout=timeout), 2 * timeout)   # (its own message first)
        try:
            await asyncio.wait_for(comm.write({"op": "identity", "reply": True}), timeout)
            return await asyncio.wait_for(comm.read(), timeout)
        finally:
            comm.abort()

    hint = "check the address (tcp://HOST:8786) and that `dask scheduler` runs there"
    try:
        asyncio.get_running_loop()
        return {}                   # (called from a running event loop: Client's own connect, unprobed)
    except RuntimeError:
        pass
    _first_bytes(address, timeout, hint)
    try:
        reply = asyncio.run(identity())
    except (asyncio.TimeoutError, TimeoutError):
        raise SweepError(f"the Dask scheduler at {address} did not answer within {timeout:g} s (something else "
                         f"listens there, or nothing does); {hint}") from None
    except (OSError, ValueError, TypeError, KeyError) as exc:
        raise SweepError(f"cannot reach the Dask scheduler at {address} within {timeout:g} s ({_reason(exc)}); "
                         f"{hint}") from None
    except Exception as exc:         # a peer that is not Dask: its bytes are no Dask message
        raise SweepError(f"what answers at {address} is not a Dask scheduler ({type(exc).__name__}); {hint}") from None
    if not isinstance(reply, dict) or reply.get("type") != "Scheduler":
        raise SweepError(f"what answers at {address} is not a Dask scheduler (it says it is "
                         f"{reply.get('type') if isinstance(reply, dict) else type(reply).__name__!r}); {hint}")
    return reply


def _first_bytes(address: str, timeout: float, hint: str) -> None:
    """For a tcp:// address: SweepError unless what listens there begins as a Dask peer does, with a handshake
    of a few frames (its first 8 bytes, the frame count). Dask's reader would otherwise allocate what any
    service's first bytes announce (an SSH banner read as a frame count: exabytes)."""
    import socket

    if not address.startswith("tcp://"):
        return
    from distributed.comm.addressing import parse_host_port

    try:
        host, port = parse_host_port(address[len("tcp://"):])
        with socket.create_connection((host, port), timeout=timeout) as sock:
            sock.settimeout(timeout)
            head = b""
            while len(head) < 8:
                more = sock.recv(8 - len(head))
                if not more:
                    raise ConnectionError("the connection was closed")
                head += more
    except (TimeoutError, socket.timeout):
        raise SweepError(f"the Dask scheduler at {address} did not answer within {timeout:g} s (something else "
                         f"listens there); {hint}") from None
    except (OSError, ValueError) as exc:
        raise SweepError(f"cannot reach the Dask scheduler at {address} ({_reason(exc)}); {hint}") from None
    if not 0 < int.from_bytes(head, "little") < 1000:
        raise SweepError(f"what answers at {address} is not a Dask scheduler (it begins {head!r}); {hint}")


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
            if not client.scheduler_info(n_workers=-1)["workers"]:
                try:
                    client.wait_for_workers(1, timeout=WORKER_WAIT)
                except (TimeoutError, OSError) as exc:
                    client.close()
                    self.made.remove(client)
                    raise SweepError(f"the Dask scheduler at {self.scheduler} has no worker after {WORKER_WAIT:g} s "
                                     f"of waiting ({_reason(exc)}); start one there: `dask worker {self.scheduler}` "
                                     f"(andyc installed, the build folder at the same path)") from None
            return client
        logger = logging.getLogger("distributed")     # its INFO lines, as workers start and stop: quiet
        self.made.append(_Level(logger, logger.level))
        logger.setLevel(logging.ERROR)
        self.made.append(_WorkersWithoutSigint())    # Ctrl-C reaches andyc, which closes the workers
        try:
            with _sigint_held():        # (a Ctrl-C while the cluster starts comes once it is whole: closed then)
                cluster = LocalCluster(n_workers=self.workers or os.cpu_count() or 1, threads_per_worker=1,
                                       processes=True, dashboard_address=":0", silence_logs=logging.ERROR)
                self.made.insert(0, cluster)
                client = Client(cluster, set_as_default=False)
                self.made.insert(0, client)
        except BaseException:           # (nothing left running)
            self.__exit__()
            raise
        return client

    def __exit__(self, *exc):
        # Closing: a comm the other side closed first (CommClosedError) is logged with its traceback by
        # distributed, tornado or asyncio; the sweep's results are written by then, so that is no news.
        quiet = [_Level(logging.getLogger(n), logging.getLogger(n).level) for n in ("distributed", "tornado",
                                                                                     "asyncio")]
        for level in quiet:
            level.logger.setLevel(logging.CRITICAL)
        try:
            with _sigint_held():        # a second Ctrl-C waits for the workers to be closed, not cut it short
                for thing in self.made:     # the client, the cluster, ...
                    if not isinstance(thing, _Level):
                        try:
                            thing.close()
                        except Exception:   # (a worker gone already: closing it is done)
                            pass
        finally:
            for level in quiet + [t for t in self.made if isinstance(t, _Level)]:   # ... the loggers as they were
                level.close()
            self.made = []


class _sigint_held:
    """SIGINT blocked in the main thread for the block, then unblocked: one that came meanwhile is delivered
    then, as KeyboardInterrupt. Elsewhere than the main thread, or without signal masks, nothing."""

    def __enter__(self):
        import signal
        import threading

        self.before = None
        if hasattr(signal, "pthread_sigmask") and threading.current_thread() is threading.main_thread():
            self.before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
        return self

    def __exit__(self, *exc):
        import signal

        if self.before is not None:
            signal.pthread_sigmask(signal.SIG_SETMASK, self.before)


class _sigint_deferred:
    """While open, a SIGINT in the main thread sets a flag instead of raising: check() raises the
    KeyboardInterrupt where the caller chooses, and leaving the block raises it if one came meanwhile.
    Elsewhere than the main thread, nothing."""

    def __enter__(self):
        import signal
        import threading

        self.came, self.before = False, None
        if threading.current_thread() is threading.main_thread():
            self.before = signal.signal(signal.SIGINT, self._note)
        return self

    def _note(self, signum, frame) -> None:
        self.came = True

    def check(self) -> None:
        if self.came:
            raise KeyboardInterrupt

    def __exit__(self, kind, *exc):
        import signal

        if self.before is not None:
            signal.signal(signal.SIGINT, self.before)
        if self.came and kind is None:
            raise KeyboardInterrupt


class _WorkersWithoutSigint:
    """While it is open, the processes multiprocessing spawns (a LocalCluster's workers, also those its nannies
    start again) start with SIGINT blocked, a mask they keep across exec: the terminal's Ctrl-C, sent to the
    whole process group, reaches andyc only, which closes the cluster, instead of printing each worker's
    KeyboardInterrupt traceback. (Blocked in the spawning thread around the spawn only; andyc's own threads are
    left as they are.)"""

    def __init__(self):
        import multiprocessing.util as util
        import signal

        self.util, self.original = util, util.spawnv_passfds
        if not hasattr(signal, "pthread_sigmask"):
            return

        def spawn(path, args, passfds, _original=self.original):
            before = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT})
            try:
                return _original(path, args, passfds)
            finally:
                signal.pthread_sigmask(signal.SIG_SETMASK, before)

        util.spawnv_passfds = spawn

    def close(self) -> None:
        self.util.spawnv_passfds = self.original


@dataclass
class _Level:
    logger: logging.Logger
    level: int

    def close(self) -> None:
        self.logger.setLevel(self.level)
