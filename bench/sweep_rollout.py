"""Many runs of one model (issue 42): andyc's batched sweep engine against one andyc.simulate per point and against
MuJoCo's batched `mujoco.rollout`, on the same planar chain of n uniform rods (bench/large_models.py: the same
masses, inertias and gravity, no contacts; n = 2 is a double pendulum of rods), the same RK4 at dt = 1e-3, from
the same N initial states (a Latin hypercube over the joint angles, +-0.5 rad about 0.3, at rest).

First the answers: every point's state after 0.2 s by the batched engine, by a loop of andyc.simulate and by
MuJoCo (their RK4s take the same steps of the same equations; MuJoCo gives each rod an inertia of 1e-9 about its
long axis where andyc's is 0, which a planar motion never turns: they agree to 1e-13; the two andyc paths to the
bit). Then, in `--rounds` rounds with the variants alternated, the wall time of the whole batch of T seconds each:

    batched 1 thread    andyc.analysis.sweeps.run_sweep(engine="inline", workers=1): the points in compiled calls
                        of andyc_numerics/batch.run_points (andyc.analysis.sweeps.batch), final states into a Zarr
                        store
    batched 2 threads   the same on two threads (the compiled calls run without the GIL)
    batched 2 threads,  the same with a metric, peak = max(abs(q1)): each point then logs every step and its Run
      a metric          is assembled (energy at every step) for the metric to read, as a single run's is
    per point 1 thread  the same sweep with each point one andyc.simulate (what sweeps did before the batched
                        engine)
    python loop         a plain loop of andyc.simulate over the points, in this process: what a user writes
    mujoco 1 thread     mujoco.rollout.rollout over the batch on one thread (C, no Python per step or point),
                        keeping every step's state as rollout does
    mujoco 2 threads    the same on two threads (one MjData each)

and the steps per second each reaches (N T / dt over the wall time), beside one run's: the compiled loop of a
single andyc.simulate of the first point (its own wall time, best of the rounds), times the cores, the ceiling
issue 42 measures the batched engine against (target: 0.8 of it).

    python bench/sweep_rollout.py [--links 6] [--points 200] [--t-end 5] [--rounds 3] [--skip "mujoco 1 thread,..."]
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import andyc  # noqa: E402
from andyc.analysis.sweeps import batch  # noqa: E402
from andyc.analysis.sweeps import points as P  # noqa: E402
from andyc.analysis.sweeps.run import run_sweep  # noqa: E402
from andyc.analysis.sweeps.worker import Settings  # noqa: E402
from large_models import planar_chain_mjcf, planar_chain_yaml  # noqa: E402

DT = 1e-3
PEAK = ("peak", "max(abs(q1))")


def andyc_finals(model, points, t_end: float, store: Path, threads: int = 1, per_point: bool = False,
                 metrics=()) -> tuple[np.ndarray, float]:
    """(final states (N, nx), wall seconds) of an inline sweep of the points on `threads` threads; per_point: each
    point one andyc.simulate (the batched engine turned off); metrics: (name, expression) pairs."""
    import xarray as xr

    settings = Settings.of(model, points.names, t_end, dt=DT, metrics=tuple(metrics))
    saved = batch.batched
    if per_point:
        batch.batched = lambda model, settings: False
    try:
        start = time.perf_counter()
        run_sweep(model, points, settings, store, engine="inline", workers=threads, progress=False)
        wall = time.perf_counter() - start
    finally:
        batch.batched = saved
    return xr.open_zarr(store).final.values, wall


def mujoco_finals(mj, datas, starts: np.ndarray, t_end: float) -> tuple[np.ndarray, float]:
    """(final (qpos, qvel) per point (N, 2 n), wall seconds) of mujoco.rollout from the full physics states."""
    import mujoco
    from mujoco import rollout

    nstep = int(round(t_end / DT))
    start = time.perf_counter()
    state, _ = rollout.rollout(mj, datas, starts, nstep=nstep)
    wall = time.perf_counter() - start
    size = mujoco.mj_stateSize(mj, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    assert state.shape[-1] == size
    n = mj.nq
    return state[:, -1, 1:1 + 2 * n], wall      # (the full physics state: time, qpos, qvel, ...)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--links", type=int, default=6)
    parser.add_argument("--points", type=int, default=200)
    parser.add_argument("--t-end", type=float, default=5.0)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--skip", default="", help="variants left out, comma-separated (e.g. 'mujoco 1 thread')")
    args = parser.parse_args()
    import mujoco

    n = args.links
    scratch = Path(tempfile.mkdtemp(prefix="andyc-rollout-"))
    source = ROOT / "build" / "rollout" / "models" / f"chain{n}.yaml"     # (one path: its build is reused)
    source.parent.mkdir(parents=True, exist_ok=True)
    source.write_text(planar_chain_yaml(n))
    model = andyc.compile_model(source, ROOT / "build" / "rollout")[0]
    mj = mujoco.MjModel.from_xml_string(planar_chain_mjcf(n))
    names = [f"q{i}" for i in range(1, n + 1)]
    points = P.samples(args.points, [f"{q}=uniform(-0.2, 0.8)" for q in names], seed=1, sampler="lhs")
    data = mujoco.MjData(mj)
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    starts = np.empty((points.n, mujoco.mj_stateSize(mj, spec)))
    for k, q in enumerate(points.values):
        mujoco.mj_resetData(mj, data)
        data.qpos[:] = q
        mujoco.mj_getState(mj, data, starts[k], spec)
    one, two = [mujoco.MjData(mj)], [mujoco.MjData(mj) for _ in range(2)]

    import xarray as xr

    a, _ = andyc_finals(model, points, 0.2, scratch / "check.zarr", threads=2)
    alone, _ = andyc_finals(model, points, 0.2, scratch / "alone.zarr", threads=1, per_point=True)
    measured, _ = andyc_finals(model, points, 0.2, scratch / "metric.zarr", threads=2, metrics=[PEAK])
    looped, _, peaks = python_loop(model, points, 0.2)
    b, _ = mujoco_finals(mj, one, starts, 0.2)
    gap = np.abs(a[:, :2 * n] - b).max()      # (andyc's states: q1 .. qn, then their rates)
    assert np.array_equal(a, alone) and np.array_equal(a, looped), "the batched engine differs from single runs"
    assert np.array_equal(measured, a) and np.array_equal(xr.open_zarr(scratch / "metric.zarr").peak.values, peaks), \
        "the batched engine's metric differs from the single runs'"
    print(f"planar chain of {n} rods, {points.n} initial states (Latin hypercube), RK4 at dt = {DT:g}: after 0.2 s "
          f"the batched engine equals single runs to the bit, and andyc and MuJoCo agree to {gap:.1e} (largest "
          f"difference of any angle or speed)")
    variants = {
        "batched 1 thread": lambda r: andyc_finals(model, points, args.t_end, scratch / f"b1_{r}.zarr", 1)[1],
        "mujoco 1 thread": lambda r: mujoco_finals(mj, one, starts, args.t_end)[1],
        "batched 2 threads": lambda r: andyc_finals(model, points, args.t_end, scratch / f"b2_{r}.zarr", 2)[1],
        "batched 2 thr, metric": lambda r: andyc_finals(model, points, args.t_end, scratch / f"m2_{r}.zarr", 2,
                                                        metrics=[PEAK])[1],
        "mujoco 2 threads": lambda r: mujoco_finals(mj, two, starts, args.t_end)[1],
        "per point 1 thread": lambda r: andyc_finals(model, points, args.t_end, scratch / f"p1_{r}.zarr", 1,
                                                     per_point=True)[1],
        "python loop": lambda r: python_loop(model, points, args.t_end)[1],
    }
    skipped = {name.strip() for name in args.skip.split(",") if name.strip()}
    if skipped - set(variants):
        parser.error(f"--skip: no variant {sorted(skipped - set(variants))}; variants: {', '.join(variants)}")
    variants = {name: run for name, run in variants.items() if name not in skipped}
    walls = {name: [] for name in variants}
    single = []
    for r in range(args.rounds):
        for name, run in variants.items():
            walls[name].append(run(r))
        single.append(one_run(model, points, args.t_end))
    steps = points.n * args.t_end / DT
    cores = os.cpu_count() or 1
    best = 1 / min(single)          # one run's steps per second, at best
    print(f"{points.n} runs of {args.t_end:g} s ({steps:.0f} steps), {args.rounds} rounds alternated; one run's "
          f"compiled loop {best / 1e6:.2f} M steps/s at best, x {cores} cores = {cores * best / 1e6:.2f} M:")
    for name, w in walls.items():
        print(f"  {name:>21}: {min(w):.2f} .. {max(w):.2f} s, {steps / min(w) / 1e6:.2f} M steps/s at best "
              f"({steps / min(w) / (cores * best):.2f} of cores x one run)")
    for a, b in (("batched 1 thread", "mujoco 1 thread"), ("batched 2 threads", "mujoco 2 threads"),
                 ("batched 1 thread", "per point 1 thread")):
        if a in walls and b in walls:
            ratio = [x / y for x, y in zip(walls[a], walls[b])]
            print(f"  {a} / {b}, per round: {min(ratio):.3f} .. {max(ratio):.3f} (time ratio; above 1: {a} slower)")


def python_loop(model, points, t_end: float) -> tuple[np.ndarray, float, np.ndarray]:
    """(final states, wall seconds, each run's max |q1|) of a loop of andyc.simulate over the points (x0 by name, as
    `andyc sim --at`)."""
    finals, peaks = [], []
    start = time.perf_counter()
    for v in points.values:
        run = andyc.simulate(model, t_end, dt=DT, x0=dict(zip(points.names, map(float, v))), progress=False)
        finals.append(run.state[-1])
        peaks.append(np.max(np.abs(run.state[:, 0])))
    return np.array(finals), time.perf_counter() - start, np.array(peaks)


def one_run(model, points, t_end: float) -> float:
    """Seconds per step of one run's compiled loop (its own wall time, Run.stats), from the first point."""
    run = andyc.simulate(model, t_end, dt=DT, x0=dict(zip(points.names, map(float, points.values[0]))),
                         progress=False)
    return run.stats["wall_seconds"] / run.stats["steps"]


if __name__ == "__main__":
    main()
