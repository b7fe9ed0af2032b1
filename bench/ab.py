"""A/B of two andyc checkouts on the same models, in one process: what a change to the generated code buys.

Each model is built by each checkout (in a subprocess with that checkout first on PYTHONPATH, into its own
folder), then both builds are loaded into this process (their generated modules and libraries are named by
their build keys, so they do not clash) and timed in alternated rounds: forward dynamics per call (the rhs in a
compiled loop, at a generic state: bench/large.py's generic_state) and, for the planar chain, RK4 steps/s
(andyc.simulate, dt = 1e-3, 20 s). Ratios are before over after, within a round, min .. max: > 1, the change
is faster. The loading and the runtime are this checkout's, so a change to andyc/numerics shows in both.

    python bench/ab.py --before eacd9bf                     chain n = 4, 8, 16, 32; solo12
    python bench/ab.py --before /tmp/old --chain 16 --robot ur5 panda solo12 g1 talos_full --rounds 9

--before: a commit (checked out into a temporary worktree) or a folder holding another checkout.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import andyc
from andyc.independent.robots import robots_dir
from andyc.runtime.compiled import load_compiled

from large import ROBOTS, AndycForward, _spread, compare, generic_state
from large_models import planar_chain_yaml

ROOT = Path(__file__).resolve().parents[1]
BUILD = "import sys; from andyc.cli import run; sys.argv = ['andyc', 'build', sys.argv[1], '--build-dir', sys.argv[2]]; run()"


def build(root: Path, source: Path, folder: Path) -> Path:
    """The generated module of `source`, built by the checkout at `root` into `folder`."""
    proc = subprocess.run([sys.executable, "-c", BUILD, str(source), str(folder)], capture_output=True, text=True,
                          env={**os.environ, "PYTHONPATH": str(root)})
    if proc.returncode != 0:
        raise SystemExit(f"{root}: building {source} failed:\n{proc.stderr[-2000:]}")
    return next(p for p in folder.glob("*/*.py") if p.stem == p.parent.name)


def sources(tmp: Path, chains, robots) -> dict:
    """name -> a model file: the planar chains (bench/large_models.py) and the URDF robots (bench/large.py)."""
    out = {}
    for n in chains:
        out[f"chain{n}"] = tmp / f"chain{n}.yaml"
        out[f"chain{n}"].write_text(planar_chain_yaml(n))
    for name in robots:
        path, base = ROBOTS[name]
        out[name] = tmp / f"{name}.yaml"
        out[name].write_text(f"urdf: {{file: {robots_dir() / path}, base: {base}}}\n")
    return out


def rk4_wall(model, t_end: float = 20.0, dt: float = 1e-3):
    return lambda: andyc.simulate(model, t_end, dt=dt, every=1000, progress=False).stats["wall_seconds"]


def ab(name: str, before, after, rounds: int) -> str:
    """One line: us per rhs call of each build and their ratio; for a chain also the RK4 ratio."""
    state = generic_state(before)
    times = compare({"before": AndycForward(before, state), "after": AndycForward(after, state)}, rounds, 20000)
    ratios = [b / a for b, a in zip(times["before"], times["after"])]
    line = (f"{name:>12}: rhs before {_spread(times['before'])} us, after {_spread(times['after'])} us, "
            f"before/after {_spread(ratios)}")
    if name.startswith("chain"):
        walls = {"before": rk4_wall(before), "after": rk4_wall(after)}
        for f in walls.values():
            f()
        rk4 = []
        for _ in range(rounds):
            b, a = walls["before"](), walls["after"]()
            rk4.append(b / a)
        line += f"; RK4 steps/s after/before {_spread(rk4)}"
    return line


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--before", required=True, help="a commit, or the folder of another checkout")
    parser.add_argument("--chain", type=int, nargs="*", default=[4, 8, 16, 32])
    parser.add_argument("--robot", nargs="*", default=["solo12"], choices=sorted(ROBOTS))
    parser.add_argument("--rounds", type=int, default=7)
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        before = Path(args.before)
        if not before.is_dir():
            before = tmp / "before"
            subprocess.run(["git", "-C", str(ROOT), "worktree", "add", "--detach", "-q", str(before), args.before],
                           check=True)
        try:
            print(f"before: {args.before}; after: {ROOT}; {args.rounds} alternated rounds", flush=True)
            for name, source in sources(tmp, args.chain, args.robot).items():
                tic = time.perf_counter()
                b = load_compiled(build(before.resolve(), source, tmp / "b" / name))
                a = load_compiled(build(ROOT, source, tmp / "a" / name))
                print(ab(name, b, a, args.rounds) + f" (built in {time.perf_counter() - tic:.0f} s)", flush=True)
        finally:
            if before.parent == tmp:
                subprocess.run(["git", "-C", str(ROOT), "worktree", "remove", "--force", str(before)], check=False)


if __name__ == "__main__":
    main()
