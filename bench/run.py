"""andyc benchmarks: build time per stage, generated-code speed, and SymPy's
KanesMethod on the same chain. Prints figures; run with `make bench`.

Targets (issue 2): derivation at least 5x faster than KanesMethod at 6 bodies,
operation count after cse no larger than KanesMethod's after cse, at least
1e6 RK4 steps/s for a 2-body chain. Every ratio is measured in this one run.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from numba import njit

import andyc
from andyc.reference.chains import chain_yaml, kane_model, random_chain

ROOT = Path(__file__).resolve().parents[1]


@njit(cache=False)
def _rhs_loop(rhs_into, n, x, u, p, xdot, M, G):
    """n right-hand-side evaluations at slowly moving states (so nothing is hoisted)."""
    acc = 0.0
    for i in range(n):
        x[0] += 1e-12
        rhs_into(0.0, x, u, p, xdot, M, G)
        acc += xdot[-1]
    return acc


def rhs_microseconds(model, repeats=3, n=200_000) -> float:
    """Best of `repeats`: microseconds per rhs_into call inside a compiled loop."""
    p, u = model.parameter_defaults, model.input_defaults
    x = model.initial_state(p).copy()
    xdot = np.zeros(model.nx)
    M, G = np.zeros((model.nv, model.nv)), np.zeros(model.nv)
    _rhs_loop(model.module.rhs_into, 10, x, u, p, xdot, M, G)
    best = np.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        _rhs_loop(model.module.rhs_into, n, x, u, p, xdot, M, G)
        best = min(best, time.perf_counter() - tic)
    return 1e6 * best / n


def rk4_steps_per_second(model, t_end=20.0, dt=1e-3, repeats=3) -> float:
    andyc.simulate(model, 10 * dt, dt=dt, progress=False)       # compile the loop outside the timing
    best = min(andyc.simulate(model, t_end, dt=dt, every=1000, progress=False).stats["wall_seconds"]
               for _ in range(repeats))
    return (t_end / dt) / best


def section(title):
    print(f"\n== {title} " + "=" * max(0, 70 - len(title)))


def chain_benchmark(n_bodies: int, tmp: Path, with_kane: bool = True):
    chain = random_chain(n_bodies, "3d", "axis", seed=2026)
    path = tmp / f"chain{n_bodies}.yaml"
    path.write_text(chain_yaml(chain))
    model, result = andyc.compile_model(path, tmp / "build", force=True)
    row = {"bodies": n_bodies, **{k: result.timings[k] for k in ("derive", "generate", "compile")},
           "ops": result.operations["dynamics"], "model": model}
    if with_kane:
        kane = kane_model(chain)
        row["kane_derive"] = kane.derive_seconds + kane.setup_seconds
        row["kane_ops"] = kane.ops_after_cse
    return row


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-bodies", type=int, default=6)
    args = parser.parse_args(argv)
    print(f"andyc {andyc.__version__}, Python {sys.version.split()[0]}")
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)

        section("3-D serial chains: andyc against sympy.physics.mechanics.KanesMethod")
        print("derive = kinematics + equations of motion (andyc: recursive, eq. 1-8; Kane: frames, points,")
        print("velocities + KanesMethod.kanes_equations); ops = sympy count_ops of M and G after cse.")
        header = (f"{'bodies':>6} {'andyc derive s':>14} {'Kane derive s':>13} {'speed-up':>8} "
                  f"{'andyc ops':>9} {'Kane ops':>9} {'ops ratio':>9}")
        print(header)
        rows = []
        for n in range(1, args.max_bodies + 1):
            row = chain_benchmark(n, tmp)
            rows.append(row)
            print(f"{n:>6} {row['derive']:>14.3f} {row['kane_derive']:>13.3f} "
                  f"{row['kane_derive'] / row['derive']:>7.1f}x {row['ops']:>9} {row['kane_ops']:>9} "
                  f"{row['ops'] / row['kane_ops']:>9.2f}", flush=True)

        big = rows[-1]
        section(f"{big['bodies']}-body 3-D chain: build and run")
        print(f"build: derive {big['derive']:.2f} s, generate {big['generate']:.2f} s, "
              f"compile {big['compile']:.2f} s (total {big['derive'] + big['generate'] + big['compile']:.2f} s)")
        us = rhs_microseconds(big["model"])
        sps = rk4_steps_per_second(big["model"])
        print(f"right-hand side: {us:.3f} us per evaluation inside a compiled loop")
        print(f"RK4: {sps:.3g} steps/s ({1e6 / sps / 4:.3f} us per rhs evaluation including the RK4 update)")
        print(f"KanesMethod derivation {big['kane_derive']:.2f} s vs andyc {big['derive']:.2f} s: "
              f"{big['kane_derive'] / big['derive']:.1f}x faster (target >= 5x)")
        print(f"operations after cse: andyc {big['ops']} vs KanesMethod {big['kane_ops']} "
              f"(ratio {big['ops'] / big['kane_ops']:.2f}, target <= 1)")

        section("shipped models: RK4 steps per second (dt = 1e-3 s)")
        for name in ("pendulum_a01", "double_pendulum", "chain3d"):
            model, _ = andyc.compile_model(ROOT / "models" / f"{name}.yaml", tmp / "build")
            sps = rk4_steps_per_second(model)
            note = "  (2-body chain; target >= 1e6)" if name == "double_pendulum" else ""
            print(f"{name:>16}: {sps:.3g} steps/s, {rhs_microseconds(model):.3f} us per rhs{note}")


if __name__ == "__main__":
    main()
