"""The compass gait's basin map on the batched engine (issue 42), run by `make bench`: prints the figures.

The map of `andyc cycle --basin` (docs/howto/walker-cycle.md): the step-to-step model
(models/compass_gait_step.yaml), its period-one cycle through the heel strike, and a grid of the legs' speeds just
after it (th1_dot -1.8..-0.6, th2_dot -1.4..1.0 rad/s), each start run step by step (rk4, dt 1e-3, at most 3 s a
step and 50 steps, fall: the hip below 0.5 m, tolerance 1e-6) until it is classified. Three variants of the same
map, in this process:

- batched: the sweep's inline engine on 2 threads, each batch's starts stepped together
  (andyc.analysis.basins_batched);
- per point: the same sweep with each start classified alone (each step one andyc.simulate: basins.record_point);
- python loop: basins.classify over the starts, one after the other, on one thread.

The classes, steps, distances and final states are compared first (equal to the bit across the variants), then
the variants alternated in each round; wall and CPU seconds (this process), min .. max over the rounds. MuJoCo
has no model of this walker's heel strike (a reset of the state at a guard), so no rollout stands beside it.

    python bench/basin.py [--side 32] [--rounds 3] [--skip "python loop,..."]
"""

from __future__ import annotations

import argparse
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
from andyc.analysis import basins, basins_batched  # noqa: E402
from andyc.analysis.cycles import find_cycle  # noqa: E402
from andyc.analysis.sweeps import points as P  # noqa: E402
from andyc.analysis.sweeps.run import run_sweep  # noqa: E402
from andyc.analysis.sweeps.worker import Settings  # noqa: E402

BUILD = ROOT / "build" / "bench"
MODEL = ROOT / "models" / "compass_gait_step.yaml"
FIELDS = ("basin", "basin_steps", "basin_period", "basin_distance", "final", "t_final")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--side", type=int, default=32, help="starts along each axis (default 32: 1024 starts)")
    parser.add_argument("--rounds", type=int, default=3, help="rounds, variants alternated (default 3)")
    parser.add_argument("--skip", default="", help="variants left out, comma-separated (e.g. 'python loop')")
    args = parser.parse_args()
    model, _ = andyc.compile_model(MODEL, BUILD)
    andyc.build_derivatives(MODEL, BUILD)
    cycle = find_cycle(model, "strike")
    basin = basins.make_basin(model, cycle, steps=50, tol=1e-6, t_step=3.0, dt=1e-3, event_tol=1e-14,
                              fall="min(y) < 0.5")
    grid = P.grid([f"th1_dot=-1.8:-0.6:{args.side}", f"th2_dot=-1.4:1.0:{args.side}"])
    settings = Settings.of(model, grid.names, basin.t_step * basin.steps, dt=basin.dt, method="rk4",
                           fixed=tuple((k, float(v)) for k, v in basin.parameters), basin=basin)
    held = [i for (_, i) in settings.kinds]
    scratch = Path(tempfile.mkdtemp(prefix="andyc-basin-bench-"))

    def sweep(batched: bool, tag: str) -> tuple:
        import xarray as xr

        store, saved = scratch / f"basin_{tag}.zarr", basins_batched.run_basins
        shutil.rmtree(store, ignore_errors=True)
        if not batched:         # (each start alone, as record() runs it)
            def one_by_one(out, model, settings, values):
                for row, point in enumerate(values):
                    basins.record_point(out, row, model, settings, point)
            basins_batched.run_basins = one_by_one
        try:
            wall, cpu = time.perf_counter(), time.process_time()
            run_sweep(model, grid, settings, store, engine="inline", workers=2, progress=False)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        finally:
            basins_batched.run_basins = saved
        ds = xr.open_zarr(store)
        return wall, cpu, {f: ds[f].values.reshape(grid.n, -1) for f in FIELDS}

    def loop() -> tuple:
        found = {f: [] for f in FIELDS}
        wall, cpu = time.perf_counter(), time.process_time()
        for point in grid.values:
            walk = basins.classify(model, basin, held, np.asarray(point, float))
            for field, value in (("basin", walk["class"]), ("basin_steps", walk["steps"]),
                                 ("basin_period", walk["period"]), ("basin_distance", walk["distance"]),
                                 ("final", walk["end"][0]), ("t_final", walk["t"])):
                found[field].append(np.atleast_1d(value))
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        return wall, cpu, {f: np.array(v) for f, v in found.items()}

    variants = {"batched, 2 threads": lambda: sweep(True, "b"), "per point, 2 threads": lambda: sweep(False, "p"),
                "python loop": loop}
    skipped = {name.strip() for name in args.skip.split(",") if name.strip()}
    if skipped - set(variants) or "batched, 2 threads" in skipped or len(skipped) > 1:
        parser.error(f"--skip: one of {', '.join(list(variants)[1:])}")
    variants = {name: run for name, run in variants.items() if name not in skipped}
    try:
        tiny = P.grid(["th1_dot=-1.2:-1.0:2", "th2_dot=-0.4:-0.2:2"])      # (what the runs compile, loaded first)
        run_sweep(model, tiny, settings, scratch / "warm.zarr", engine="inline", workers=2, progress=False)
        answers = {name: run() for name, run in variants.items()}
        reference = answers[list(variants)[-1]][2]
        same = all(np.array_equal(a[2][f].astype(float), reference[f].astype(float), equal_nan=True)
                   for a in answers.values() for f in FIELDS)
        times = {name: [answers[name][:2]] for name in variants}
        for _ in range(args.rounds - 1):
            for name, run in variants.items():
                times[name].append(run()[:2])
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    classes = reference["basin"].ravel().astype(int)
    counts = ", ".join(f"{n} {int(np.count_nonzero(classes == c))}" for c, n in basins.CLASSES.items() if c)
    print(f"compass gait basin map, {grid.n} starts ({args.side} x {args.side}; {counts}; "
          f"{int(reference['basin_steps'].sum())} steps in all), {args.rounds} rounds alternated, {os.cpu_count()} "
          f"cores; classes, steps, distances and final states {'equal to the bit' if same else 'DIFFER'} "
          f"across variants:")
    for name, pairs in times.items():
        walls, cpus = [w for w, _ in pairs], [c for _, c in pairs]
        print(f"  {name:>20}: wall {min(walls):.2f} .. {max(walls):.2f} s, CPU {min(cpus):.2f} .. {max(cpus):.2f} s "
              f"({grid.n / min(walls):.0f} starts/s at best)")
    for name in list(variants)[1:]:
        ratio = [a[0] / b[0] for a, b in zip(times[name], times["batched, 2 threads"])]
        print(f"  {name} / batched, per round: {min(ratio):.2f} .. {max(ratio):.2f}")
    if not same:
        raise SystemExit("the variants' maps differ: the figures above compare different answers")


if __name__ == "__main__":
    main()
