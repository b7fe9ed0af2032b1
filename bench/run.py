"""andyc benchmarks: build time per stage, generated-code speed, and SymPy's
KanesMethod on the same chain. Prints figures; run with `make bench`.

Targets (issue 2): derivation at least 5x faster than KanesMethod at 6 bodies,
operation count after cse no larger than KanesMethod's after cse, at least
1e6 RK4 steps/s for a 2-body chain. Issue 3: the swing bar builds (derive +
generate + compile) in under 10 s and runs at least 1e6 RK4 steps/s, 40x
ANDY's 2.4e4 steps/s. Every ratio is measured in this one run.

    python bench/run.py                      all sections (about 6 minutes)
    python bench/run.py --only swing_bar     one section: chains, models, swing_bar
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


ANDY_SWING_BAR_STEPS_PER_SECOND = 2.4e4     # ANDY paper section 3.1 (i7-7700, single thread)


def swing_bar_benchmark(tmp: Path) -> None:
    section("swing bar (ANDY section 3.1): build, speed, quaternion normalization")
    # A folder of its own, so that Numba's cache from another section cannot hide the compile time.
    model, result = andyc.compile_model(ROOT / "models" / "swing_bar.yaml", tmp / "swing_bar_build", force=True)
    t = result.timings
    total = t["derive"] + t["generate"] + t["compile"]
    print(f"build: derive {t['derive']:.2f} s, generate {t['generate']:.2f} s, compile {t['compile']:.2f} s "
          f"(total {total:.2f} s, target < 10 s); {result.operations['dynamics']} operations in dynamics")
    for normalize in (True, False):
        andyc.simulate(model, 0.01, dt=1e-3, normalize=normalize, progress=False)
        best = min(andyc.simulate(model, 30.0, dt=1e-3, every=1000, normalize=normalize, progress=False)
                   .stats["wall_seconds"] for _ in range(5))
        sps = 30.0 / 1e-3 / best
        label = "with" if normalize else "without"
        print(f"RK4, dt = 1e-3 s, 30 s, {label} quaternion renormalization: {sps:.3g} steps/s = "
              f"{sps / ANDY_SWING_BAR_STEPS_PER_SECOND:.0f}x ANDY's 2.4e4 steps/s (target >= 1e6, 40x)")
    print(f"right-hand side: {rhs_microseconds(model):.3f} us per evaluation")

    # What renormalizing after each step buys: the norm, and the error against a
    # tight DOP853 reference at the same instants (bar-end positions).
    frames = ["bar2", "bar3"]
    ref = andyc.simulate(model, 10.0, dt=1e-3, method="DOP853", rtol=1e-13, atol=1e-13, frames=frames,
                         every=100, progress=False)
    quat = [model.state_names.index(f"ball_q{c}") for c in "wxyz"]
    print("quaternion strategy over 10 s at dt = 1e-3 s (reference: DOP853, rtol = atol = 1e-13):")
    for normalize in (True, False):
        run = andyc.simulate(model, 10.0, dt=1e-3, frames=frames, every=100, normalize=normalize, progress=False)
        drift = np.max(abs(np.linalg.norm(run.state[:, quat], axis=1) - 1))
        err = max(np.max(abs(run.frames[f] - ref.frames[f])) for f in frames)
        label = "renormalize each step" if normalize else "no renormalization  "
        print(f"  {label}: max | |quat| - 1 | = {drift:.2e}, max bar-end error = {err:.2e} m")
    drift = np.max(abs(np.linalg.norm(ref.state[:, quat], axis=1) - 1))
    print(f"  DOP853 (never renormalized):  max | |quat| - 1 | = {drift:.2e}")


def chains_benchmark(tmp: Path, max_bodies: int) -> None:
    section("3-D serial chains: andyc against sympy.physics.mechanics.KanesMethod")
    print("derive = kinematics + equations of motion (andyc: recursive, eq. 1-8; Kane: frames, points,")
    print("velocities + KanesMethod.kanes_equations); ops = sympy count_ops of M and G after cse.")
    header = (f"{'bodies':>6} {'andyc derive s':>14} {'Kane derive s':>13} {'speed-up':>8} "
              f"{'andyc ops':>9} {'Kane ops':>9} {'ops ratio':>9}")
    print(header)
    rows = []
    for n in range(1, max_bodies + 1):
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


def models_benchmark(tmp: Path) -> None:
    section("shipped models: RK4 steps per second (dt = 1e-3 s)")
    for name in ("pendulum_a01", "double_pendulum", "chain3d", "swing_bar", "free_body"):
        model, _ = andyc.compile_model(ROOT / "models" / f"{name}.yaml", tmp / "build")
        sps = rk4_steps_per_second(model)
        note = "  (2-body chain; target >= 1e6)" if name == "double_pendulum" else ""
        print(f"{name:>16}: {sps:.3g} steps/s, {rhs_microseconds(model):.3f} us per rhs{note}")


SECTIONS = ("chains", "models", "swing_bar")


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-bodies", type=int, default=6)
    parser.add_argument("--only", choices=SECTIONS, action="append", help="run only this section (repeatable)")
    args = parser.parse_args(argv)
    only = set(args.only or SECTIONS)
    print(f"andyc {andyc.__version__}, Python {sys.version.split()[0]}")
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        if "chains" in only:
            chains_benchmark(tmp, args.max_bodies)
        if "models" in only:
            models_benchmark(tmp)
        if "swing_bar" in only:
            swing_bar_benchmark(tmp)


if __name__ == "__main__":
    main()
