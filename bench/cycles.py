"""The cycles section of bench/run.py (issue 22, item 7): one Newton step of `andyc cycle` on a walker with the
exact Jacobian (one run carrying its sensitivities along the section's coordinates, as find_cycle does: the RK4
stages and the saltation matrices, the tangent of each chunk of steps in one compiled call) against the same
step with a finite-difference Jacobian (central differences of the compiled map along each of the section's
coordinates: 2 k + 1 plain runs), alternated in one run, at the fixed point, min and max over the repeats."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

import andyc
from andyc.analysis.cycles import PoincareMap, find_cycle, section_basis
from andyc.runtime.sensitivities import load_derivatives

ROOT = Path(__file__).resolve().parents[1]


def _exact_step(Q, B, y):
    image = Q(y, directions=B)          # as find_cycle: DQ B, the run carrying B's columns
    return np.linalg.solve(B.T @ image.jacobian - np.eye(B.shape[1]), -B.T @ (image.y - y))


def _difference_step(Q, B, y, eps=1e-6):
    Qy = Q(y, jacobian=False).y
    J = np.column_stack([(Q(y + eps * b, jacobian=False).y - Q(y - eps * b, jacobian=False).y) / (2 * eps)
                         for b in B.T])
    return np.linalg.solve(B.T @ J - np.eye(B.shape[1]), -B.T @ (Qy - y))


WALKERS = (("compass_gait", "strike2"), ("passive_walker", "strike_outer_foot"))


def cycles_benchmark(tmp: Path, repeats: int = 5) -> None:
    for name, section in WALKERS:
        walker_benchmark(tmp, name, section, repeats)


def walker_benchmark(tmp: Path, name: str, section: str, repeats: int) -> None:
    path = ROOT / "models" / f"{name}.yaml"
    model = andyc.compile_model(path, tmp / "cycles_build")[0]
    andyc.build_derivatives(path, tmp / "cycles_build")
    tic = time.perf_counter()
    cycle = find_cycle(model, section)
    print(f"  {name}, section {section}: andyc cycle {time.perf_counter() - tic:.1f} s, converged "
          f"{cycle.converged} ({cycle.message}), multipliers {np.round(cycle.multipliers, 8)}")
    k = model.jump_names.index(section)
    p = model.parameters(None)
    derivatives = load_derivatives(model)
    Q = PoincareMap(model, derivatives, k, p, 1, 1e-3, 20.0, 1e-14)
    y = cycle.before                # the fixed point, just before the section's jump
    B, _ = section_basis(model, derivatives, int(model.module.JUMP_SOURCE[k]), k, p, y)
    times = {"exact": [], "differences": []}
    steps = {}
    for _ in range(repeats):
        for label, step in (("exact", _exact_step), ("differences", _difference_step)):
            tic = time.perf_counter()
            steps[label] = step(Q, B, y)
            times[label].append(time.perf_counter() - tic)
    for label, runs in (("exact", f"1 run with sensitivities along the section's {B.shape[1]} coordinates"),
                        ("differences", f"{2 * B.shape[1] + 1} plain runs, central differences")):
        t = times[label]
        print(f"  one Newton step, {label} Jacobian ({runs}): min {min(t):.3f} s, max {max(t):.3f} s "
              f"over {repeats}, alternated")
    print(f"  ratio exact / differences (min): {min(times['exact']) / min(times['differences']):.2f}; the two steps "
          f"differ by {np.max(np.abs(steps['exact'] - steps['differences'])):.1e} (at the fixed point, both ~0)")
