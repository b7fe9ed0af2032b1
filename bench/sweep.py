"""Sweeps on Dask (issue 25), run by `make bench`: prints the figures, draws docs/compass_gait_sweep.png.

1. The compass gait's 20 x 20 grid, slope x the stance leg's initial speed (w_stance0), 8 s each: a point
   walks when it makes at least 8 heel strikes (count() >= 8) and its hip never sinks below half the leg's
   length (min(y) > 0.5 m); else it falls (the hip swings down through the slope: the model has no
   ground for it). The map goes to docs/compass_gait_sweep.png.
2. Speed-up of 2 workers against 1 on that grid: two LocalClusters, both started and warmed (the model
   loaded on every worker) first, then the grid run on each in turn (A, B, A, B, ...), into a new store
   each time; the speed-up is the ratio of the best times, with the range of the ratios of each pair. Both
   in this one run, on the same machine (its other load shows in the spread).
3. Per-point overhead: a double-pendulum run of about 1 ms (t_end chosen so that andyc.simulate takes 1 ms
   here), 1000 points on the one-worker cluster: (the sweep's wall time - the points' own wall times on the
   worker) / 1000, target <= 5 ms; beside it, a loop of andyc.simulate over the same points here.

4. The command end to end, as the issue measured it: `andyc sweep` of the double pendulum, 200 points of 5 s,
   with --engine inline (this process, no cluster), auto, and cluster on 1 and 2 workers; each command's
   wall time and CPU time (its process and every child: the cluster's workers), the engines alternated in
   each round; the final states of the stores compared first (equal to the bit).
5. The first result: how many seconds after `andyc sweep` is launched (1000 points of the double pendulum, inline)
   its store holds a point.
6. The compass gait's map batched: 32 x 32 points of section 1's grid, 8 s each by projection (the model's own
   method), with section 1's three metrics, in this process on 2 threads by the batched engine, against the same
   sweep with each point one andyc.simulate (the batched engine turned off), and against a Python loop of
   andyc.simulate with the metrics evaluated on each run; the metrics and final states compared first (equal to
   the bit), then the variants alternated in each round.

    python bench/sweep.py [--rounds 3]
"""

from __future__ import annotations

import argparse
import math
import logging
import os
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import andyc  # noqa: E402
from andyc.analysis.sweeps import points as P  # noqa: E402
from andyc.analysis.sweeps.run import run_sweep  # noqa: E402
from andyc.analysis.sweeps.worker import Settings, simulate_point  # noqa: E402

BUILD = ROOT / "build" / "bench"
WALKS = "min(min(y) - 0.5, count() - 7.5) > 0"


def _warm(settings):
    """On a worker: load the model (and parse the metrics) now, outside the timed sweeps."""
    from andyc.analysis.sweeps.worker import loaded

    loaded(settings)
    return os.getpid()


def cluster(n: int):
    from dask.distributed import Client, LocalCluster

    made = LocalCluster(n_workers=n, threads_per_worker=1, processes=True, dashboard_address=":0",
                        silence_logs=logging.ERROR)
    return made, Client(made, set_as_default=False)


def timed_sweep(model, points, settings, client, scratch, cpu: list | None = None) -> tuple:
    """(the sweep's wall time, the sum of its points' wall times on the workers), into a new store; the
    mean CPU time of a point appended to `cpu`."""
    import xarray as xr

    store = Path(tempfile.mkdtemp(dir=scratch)) / "s.zarr"
    start = time.perf_counter()
    summary = run_sweep(model, points, settings, store, client=client, progress=False)
    wall = time.perf_counter() - start
    assert summary.computed == points.n, summary.text()
    ds = xr.open_zarr(store)
    points_wall = float(ds.wall.sum())
    if cpu is not None:
        cpu.append(float(ds.cpu.mean()))
    shutil.rmtree(store.parent)
    return wall, points_wall


def compass_map(model, points, settings, store) -> dict:
    import xarray as xr

    from andyc.plot.sweepmap import plot_sweep

    ds = xr.open_zarr(store)
    walks = ((ds.walks.values == 1) & (ds.outcome.values == 1)).astype(int)
    out = ROOT / "docs" / "compass_gait_sweep.png"
    plot_sweep(True, [(n, a) for n, a in zip(points.names, points.axes)], walks, "walks", WALKS, out,
               title=f"compass gait: walks or falls within {settings.t_end:g} s", outcomes={0: "falls", 1: "walks"},
               colours={0: "#e76f51", 1: "#2a9d8f"})
    return {"walks": int(walks.sum()), "falls": int(walks.size - walks.sum()), "out": out,
            "outcomes": {int(k): int(np.count_nonzero(ds.outcome.values == k)) for k in np.unique(ds.outcome.values)}}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=3, help="A/B rounds of the speed-up (default 3)")
    args = parser.parse_args()
    logging.getLogger("distributed").setLevel(logging.ERROR)     # (its INFO lines as workers start and stop)
    gait, _ = andyc.compile_model(ROOT / "models" / "compass_gait.yaml", BUILD)
    pendulum, _ = andyc.compile_model(ROOT / "models" / "double_pendulum.yaml", BUILD)
    grid = P.grid(["slope=0:0.1:20", "w_stance0=-1.8:-0.6:20"])
    gait_settings = Settings.of(gait, grid.names, 8.0, metrics=(("walks", WALKS), ("steps", "count()"),
                                                                 ("hip_low", "min(y)")))
    print(f"andyc sweep benchmarks ({os.cpu_count()} cores; the machine may be shared: the spread shows it)")
    scratch = Path(tempfile.mkdtemp(prefix="andyc-sweep-bench-"))
    clusters = {n: cluster(n) for n in (1, 2)}
    try:
        for _, client in clusters.values():
            client.run(_warm, gait_settings)

        # 1. the map
        store = scratch / "compass.zarr"
        start = time.perf_counter()
        run_sweep(gait, grid, gait_settings, store, client=clusters[2][1], progress=False)
        first = time.perf_counter() - start
        found = compass_map(gait, grid, gait_settings, store)
        print(f"compass gait 20 x 20 (slope 0..0.1 rad x w_stance0 -1.8..-0.6 rad/s, 8 s each): "
              f"{found['walks']} walk, {found['falls']} fall; outcomes {found['outcomes']} (1 = finished); "
              f"{first:.1f} s on 2 workers; map: {found['out'].relative_to(ROOT)}")

        # 2. speed-up, A/B alternated; beside it, how many points ran at once (the points' own wall times
        # over the sweep's: 2 when both workers are busy all along, whatever share of the cores they get)
        walls, busy, cpu = {1: [], 2: []}, {1: [], 2: []}, {1: [], 2: []}
        for _ in range(args.rounds):
            for n in (1, 2):
                wall, points_wall = timed_sweep(gait, grid, gait_settings, clusters[n][1], scratch, cpu[n])
                walls[n].append(wall)
                busy[n].append(points_wall / wall)
        ratios = [a / b for a, b in zip(walls[1], walls[2])]
        print(f"speed-up, 2 workers vs 1 on the 400-point grid ({args.rounds} A/B rounds): "
              f"{min(walls[1]) / min(walls[2]):.2f} (best times {min(walls[1]):.2f} s / {min(walls[2]):.2f} s); "
              f"per round {min(ratios):.2f} .. {max(ratios):.2f}; target >= 1.7. Points running at once: "
              f"{min(busy[2]):.2f} .. {max(busy[2]):.2f} on 2 workers, {min(busy[1]):.2f} .. {max(busy[1]):.2f} on 1; "
              f"CPU time a point {min(cpu[2]) * 1e3:.1f} .. {max(cpu[2]) * 1e3:.1f} ms on 2 workers, "
              f"{min(cpu[1]) * 1e3:.1f} .. {max(cpu[1]) * 1e3:.1f} ms on 1")

        # 3. per-point overhead of a 1 ms run, over 1000 points on one worker: the sweep's wall time per point
        # less the time each point took on the worker (andyc.simulate and its metrics, measured there), in
        # the same sweep; beside it, a loop of the same runs in this process
        t_end = 0.5
        for _ in range(3):      # t_end for a 1 ms andyc.simulate, measured here
            probe = [time.perf_counter(), andyc.simulate(pendulum, t_end, progress=False), time.perf_counter()]
            t_end = max(1, round(t_end * 1e-3 / max(probe[2] - probe[0], 1e-5) / 1e-3)) * 1e-3   # whole steps
        many = P.grid(["q1=0.1:1.1:1000"])
        settings = Settings.of(pendulum, many.names, t_end)
        clusters[1][1].run(_warm, settings)
        start = time.perf_counter()
        for point in many.values:
            simulate_point(pendulum, settings, point)
        loop = (time.perf_counter() - start) / many.n
        runs = [timed_sweep(pendulum, many, settings, clusters[1][1], scratch) for _ in range(3)]
        overhead = [(wall - points_wall) / many.n for wall, points_wall in runs]
        print(f"overhead per point, 1000 runs of about 1 ms (double pendulum, t_end {t_end:.3g} s; a loop of "
              f"andyc.simulate here: {loop * 1e3:.2f} ms a run): sweep on 1 worker "
              f"{min(w for w, _ in runs) / many.n * 1e3:.2f} ms a point, of which the runs "
              f"{min(p for _, p in runs) / many.n * 1e3:.2f} ms; overhead {min(overhead) * 1e3:.2f} .. "
              f"{max(overhead) * 1e3:.2f} ms a point over 3 sweeps (target <= 5 ms)")
        engines(scratch, args.rounds)
        first_result(scratch, args.rounds)
        gait_map(gait, scratch, args.rounds)
    finally:
        logging.getLogger("distributed").setLevel(logging.ERROR)     # (starting a cluster resets it)
        for made, client in clusters.values():
            client.close()
            made.close()
        shutil.rmtree(scratch, ignore_errors=True)


def engines(scratch: Path, rounds: int) -> None:
    """Section 4: the command line's engines, A/B alternated; wall and CPU seconds of each command."""
    import resource
    import subprocess

    import xarray as xr

    variants = {"inline": ["--engine", "inline"], "auto": ["--engine", "auto"],
                "cluster, 1 worker": ["--engine", "cluster", "--workers", "1"],
                "cluster, 2 workers": ["--engine", "cluster", "--workers", "2"]}
    walls, cpus, finals = {k: [] for k in variants}, {k: [] for k in variants}, {}
    for _ in range(rounds):
        for name, extra in variants.items():
            store = scratch / f"engine_{len(walls[name])}_{name.replace(' ', '_').replace(',', '')}.zarr"
            before = resource.getrusage(resource.RUSAGE_CHILDREN)
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "andyc.cli", "sweep", str(ROOT / "models" / "double_pendulum.yaml"),
                            "--grid", "m1=0.5:2:200", "--t-end", "5", "--build-dir", str(BUILD), "-o", str(store),
                            *extra], check=True, capture_output=True)
            walls[name].append(time.perf_counter() - start)
            after = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpus[name].append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
            finals.setdefault(name, xr.open_zarr(store).final.values)
    reference = finals["inline"]
    agree = all(np.array_equal(f, reference) for f in finals.values())
    print(f"andyc sweep, double pendulum, 200 points of 5 s, the whole command ({rounds} rounds, engines alternated; "
          f"final states {'equal to the bit' if agree else 'DIFFER'} across engines):")
    for name in variants:
        print(f"  {name:>20}: wall {min(walls[name]):.2f} .. {max(walls[name]):.2f} s, "
              f"CPU {min(cpus[name]):.2f} .. {max(cpus[name]):.2f} s")
    if not agree:
        raise SystemExit("andyc sweep's engines: the final states differ; the figures above compare different answers")


def gait_map(gait, scratch: Path, rounds: int) -> None:
    """Section 6 (see the module's docstring)."""
    import xarray as xr

    from andyc.analysis.sweeps import batch
    from andyc.analysis.sweeps.metrics import compile_metric, evaluate
    from andyc.errors import SimulationError

    grid = P.grid(["slope=0:0.1:32", "w_stance0=-1.8:-0.6:32"])
    metrics = (("walks", WALKS), ("steps", "count()"), ("hip_low", "min(y)"))
    settings = Settings.of(gait, grid.names, 8.0, method="projection", metrics=metrics)
    parsed = [compile_metric(n, text, gait) for n, text in metrics]

    def inline(batched: bool, tag: str) -> tuple:
        store, saved = scratch / f"gait_{tag}.zarr", batch.batched
        shutil.rmtree(store, ignore_errors=True)
        if not batched:
            batch.batched = lambda model, settings: False
        try:
            start = time.perf_counter()
            run_sweep(gait, grid, settings, store, engine="inline", workers=2, progress=False)
            wall = time.perf_counter() - start
        finally:
            batch.batched = saved
        ds = xr.open_zarr(store)
        return wall, np.stack([ds[n].values.ravel() for n, _ in metrics], axis=1), ds.final.values.reshape(grid.n, -1)

    def loop() -> tuple:
        values, finals = [], []
        start = time.perf_counter()
        for point in grid.values:
            try:
                run = simulate_point(gait, settings, point)
            except SimulationError:             # (a start refused: the store's point has NaN)
                values.append([math.nan] * len(parsed))
                finals.append(np.full(gait.nx, math.nan))
                continue
            values.append([evaluate(m, run) for m in parsed])
            finals.append(run.state[-1])
        return time.perf_counter() - start, np.array(values), np.array(finals)

    variants = {"batched, 2 threads": lambda: inline(True, "b"), "per point, 2 threads": lambda: inline(False, "p"),
                "python loop": loop}
    answers = {name: run() for name, run in variants.items()}
    same = all(np.array_equal(a[1], answers["python loop"][1], equal_nan=True)
               and np.array_equal(a[2], answers["python loop"][2]) for a in answers.values())
    walls = {name: [answers[name][0]] for name in variants}
    for _ in range(rounds - 1):
        for name, run in variants.items():
            walls[name].append(run()[0])
    walking = int(np.nansum(answers["python loop"][1][:, 0]))
    print(f"compass gait map, {grid.n} points of 8 s (projection, 3 metrics; {walking} walk), {rounds} rounds "
          f"alternated; metrics and final states {'equal to the bit' if same else 'DIFFER'} across variants:")
    for name, w in walls.items():
        print(f"  {name:>20}: {min(w):.2f} .. {max(w):.2f} s ({grid.n / min(w):.0f} points/s at best)")
    ratio = [a / b for a, b in zip(walls["batched, 2 threads"], walls["per point, 2 threads"])]
    print(f"  batched / per point, per round: {min(ratio):.3f} .. {max(ratio):.3f}")
    if not same:
        raise SystemExit("compass gait map: the variants' metrics or final states differ; the figures above compare "
                         "different answers")


def first_result(scratch: Path, rounds: int) -> None:
    """Section 5: how soon a local sweep stores its first point: `andyc sweep` of 1000 points of the double
    pendulum (5 s each), launched as a user does, the store read from here every 10 ms until a point's outcome is
    in it; the seconds from the launch (Python's start, the model's load from its build, the store's making)."""
    import subprocess

    import zarr

    times, totals = [], []
    for r in range(rounds):
        store = scratch / f"first_{r}.zarr"
        start = time.perf_counter()
        command = subprocess.Popen([sys.executable, "-m", "andyc.cli", "sweep",
                                    str(ROOT / "models" / "double_pendulum.yaml"), "--grid", "q1=0.1:1.5:1000",
                                    "--t-end", "5", "--build-dir", str(BUILD), "-o", str(store)],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        first = None
        while command.poll() is None or first is None:
            try:
                if first is None and np.any(zarr.open_group(str(store), mode="r")["outcome"][:] != 0):
                    first = time.perf_counter() - start
            except Exception:           # (not made yet, or being written)
                pass
            if command.poll() is not None and first is None:
                first = math.nan if command.returncode else time.perf_counter() - start
            time.sleep(0.01)
        totals.append(time.perf_counter() - start)
        times.append(first)
    print(f"first result of a local sweep (andyc sweep, double pendulum, 1000 points of 5 s, {rounds} runs): stored "
          f"{min(times):.2f} .. {max(times):.2f} s after the launch (target <= 2 s); the whole command "
          f"{min(totals):.2f} .. {max(totals):.2f} s")


if __name__ == "__main__":          # (Dask starts its worker processes by spawning: they import this file)
    main()
