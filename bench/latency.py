"""Latency of the command line, as a user meets it: `andyc --version`, `andyc check`, and the first
result of `andyc sim` cold (a fresh build folder and a fresh Numba cache) and warm (the same command
again), for the shipped models and the panda URDF with its fingers locked (issue 19).

Every figure is the wall time of a whole `andyc` process, started as a user starts it
(`python -m andyc.cli`), so imports count. The algorithms every model shares (andyc/numerics) compile
once per installation into andyc's cache (ANDYC_CACHE_DIR): the table first times that, with an
empty cache, then every model cold with it filled, as a user meets a new model. The cold build is
split by stage from what `andyc build` prints in a second fresh folder (load + derive + generate,
then Numba); `andyc sim` then runs in that folder.

    python bench/latency.py                     the table (about 5 minutes on 2 cores)
    python bench/latency.py --root OTHER_TREE   the same for another checkout of andyc (before/after)
    python bench/latency.py --models double_pendulum --repeats 3
    python bench/latency.py --functions passive_walker      where Numba's seconds go, leaf by leaf
    python bench/latency.py --speed-ab OTHER_TREE           same-run A/B of RK4 steps/s against another checkout
    python bench/latency.py --backend-ab                    same-process A/B of RK4 steps/s, C against Numba leaves

Targets on the idle 2-core machine: cold first result <= 10 s (double_pendulum, swing_bar,
ball_in_bowl, passive_walker), <= 30 s (panda); warm sim <= 1 s; --version <= 0.3 s; check <= 1.5 s.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = ["double_pendulum", "swing_bar", "ball_in_bowl", "passive_walker", "panda"]
TARGETS = {"double_pendulum": 10, "swing_bar": 10, "ball_in_bowl": 10, "passive_walker": 10, "panda": 30}
SIM = ["--t-end", "1", "--dt", "1e-3", "--out", "run.csv"]


def _panda(folder: Path) -> Path:
    from andyc.independent.robots import robots_dir

    path = folder / "panda.yaml"
    path.write_text(f"name: panda\nurdf:\n  file: {robots_dir() / 'panda_description/urdf/panda.urdf'}\n"
                    "  lock: {panda_finger_joint1: 0.02}\n")
    return path


def _andyc(root: Path, args, cwd: Path, env: dict) -> tuple[float, str]:
    """Wall seconds of one `andyc ...` process and what it printed (both streams). Python's bytecode cache on,
    as on a user's machine (pip compiles andyc's .pyc at install): PYTHONDONTWRITEBYTECODE, set on some
    machines, would make every command compile andyc's ~50 modules from source."""
    env = {key: value for key, value in env.items() if key != "PYTHONDONTWRITEBYTECODE"}
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "andyc.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, env={**env, "PYTHONPATH": str(root)})
    seconds = time.perf_counter() - start
    if proc.returncode != 0:
        raise SystemExit(f"andyc {' '.join(map(str, args))} failed ({proc.returncode}):\n{proc.stderr}")
    return seconds, proc.stdout + proc.stderr


def _stage(text: str, name: str) -> float:
    found = re.search(rf"{name} ([0-9.]+) s", text)
    return float(found.group(1)) if found else float("nan")


def measure(root: Path, model: str, work: Path, shared: Path) -> dict:
    """One model's row: cold sim, its split (load+derive+generate, Numba in build, then sim), warm sim; andyc's
    shared numerics from `shared` (ANDYC_CACHE_DIR)."""
    path = _panda(work) if model == "panda" else root / "models" / f"{model}.yaml"
    row = {}
    for run in ("cold", "split"):
        folder = work / run
        folder.mkdir()
        env = {**os.environ, "NUMBA_CACHE_DIR": str(folder / "numba-cache"),   # a fresh Numba cache too
               "ANDYC_CACHE_DIR": str(shared)}
        if run == "cold":
            row["cold"], _ = _andyc(root, ["sim", path, *SIM], folder, env)
            row["warm"], _ = _andyc(root, ["sim", path, *SIM], folder, env)
        else:
            wall, text = _andyc(root, ["build", path], folder, env)
            row["build"], row["derive"], row["generate"] = wall, _stage(text, "derive"), _stage(text, "generate")
            row["cc"] = _stage(text, "C compiler") if "C compiler" in text else 0.0     # the leaves in C
            row["numba_build"] = (_stage(text, "compile") if re.search(r"compile [0-9]", text)
                                  else _stage(text, "cache in"))
            row["sim_after_build"], _ = _andyc(root, ["sim", path, *SIM], folder, env)
    return row


def first_use(root: Path, work: Path, shared: Path) -> float:
    """Wall seconds of the first `andyc sim` after installing andyc: an empty cache of the shared numerics
    (filled for every later model) and a fresh build of the double pendulum."""
    work.mkdir()
    env = {**os.environ, "NUMBA_CACHE_DIR": str(work / "numba-cache"), "ANDYC_CACHE_DIR": str(shared)}
    return _andyc(root, ["sim", root / "models" / "double_pendulum.yaml", *SIM], work, env)[0]


PROFILE = """
import json, sys, time
from numba.core import ccallback
import andyc
from andyc.runtime.compiled import compile_integrator, load_compiled

path, out = sys.argv[1], sys.argv[2]
leaves, compile_leaf = {}, ccallback.CFunc.compile


def timed(self):
    start = time.perf_counter()
    compile_leaf(self)
    leaves[self._pyfunc.__module__, self._pyfunc.__name__] = time.perf_counter() - start


ccallback.CFunc.compile = timed
t0 = time.perf_counter()
result = andyc.build(path, out)
t1 = time.perf_counter()
model = load_compiled(result.module_path)         # compiles the leaves (and loads the shared numerics)
t2 = time.perf_counter()
compile_integrator(model)
t3 = time.perf_counter()
own = {name: v for (module, name), v in leaves.items() if module == model.module.EQUATIONS.__name__}
print(json.dumps({"build": t1 - t0, "import": t2 - t1, "integrator": t3 - t2, "leaves": own}))
"""


def profile(root: Path, model: str, shared: Path) -> None:
    """Numba's compile time per leaf (the model's own functions), in one process with a fresh Numba cache
    and andyc's shared numerics already compiled (`shared`, ANDYC_CACHE_DIR), largest first."""
    import json

    with tempfile.TemporaryDirectory(prefix="andyc-profile-") as tmp:
        tmp = Path(tmp)
        path = _panda(tmp) if model == "panda" else root / "models" / f"{model}.yaml"
        env = {**os.environ, "PYTHONPATH": str(root), "NUMBA_CACHE_DIR": str(tmp / "numba-cache"),
               "ANDYC_CACHE_DIR": str(shared)}
        proc = subprocess.run([sys.executable, "-c", PROFILE, str(path), str(tmp / "build")], capture_output=True,
                              text=True, env=env, cwd=tmp)
        if proc.returncode != 0:
            raise SystemExit(proc.stderr)
        r = json.loads(proc.stdout.splitlines()[-1])
    total = sum(r["leaves"].values())
    print(f"{model}: build (load, derive, generate) {r['build']:.1f} s; import {r['import']:.1f} s, of which "
          f"Numba compiling the model's {len(r['leaves'])} leaves {total:.1f} s; the shared integrator "
          f"{r['integrator']:.2f} s (from andyc's cache)")
    for name, seconds in sorted(r["leaves"].items(), key=lambda kv: -kv[1]):
        print(f"  {name:24s} {seconds:6.2f} s  {100 * seconds / total:4.0f}%")


SPEED = """
import json, sys, andyc
model = andyc.compile_model(sys.argv[1], sys.argv[2])[0]
andyc.simulate(model, 0.01, dt=1e-3, progress=False)
best = min(andyc.simulate(model, 100.0, dt=1e-3, every=1000, progress=False).stats["wall_seconds"] for _ in range(3))
print(json.dumps(100.0 / 1e-3 / best))
"""


def speed_ab(root: Path, other: Path, rounds: int = 5) -> None:
    """RK4 steps/s (best of three 100 s runs at 1e-3 s) of the swing bar and the passive walker, this
    checkout (B) against `other` (A), alternated A/B, B/A over `rounds` processes each: the ratio B/A
    of each round, median, min and max (the machine is noisy; only ratios of one run compare)."""
    import statistics

    with tempfile.TemporaryDirectory(prefix="andyc-ab-") as tmp:
        for model in ("swing_bar", "passive_walker"):
            rates = {"A": [], "B": []}
            for k in range(rounds):
                for label in ("AB" if k % 2 == 0 else "BA"):
                    tree = other if label == "A" else root
                    proc = subprocess.run([sys.executable, "-c", SPEED, str(tree / "models" / f"{model}.yaml"),
                                           str(Path(tmp) / label)], capture_output=True, text=True, cwd=tmp,
                                          env={**os.environ, "PYTHONPATH": str(tree)})
                    if proc.returncode != 0:
                        raise SystemExit(proc.stderr)
                    rates[label].append(float(proc.stdout.split()[-1]))
            a, b = rates["A"], rates["B"]
            ratio = [y / x for x, y in zip(a, b)]
            print(f"{model}: A {statistics.median(a):.3g} RK4 steps/s ({min(a):.3g} .. {max(a):.3g}), "
                  f"B {statistics.median(b):.3g} ({min(b):.3g} .. {max(b):.3g}); B/A median "
                  f"{statistics.median(ratio):.2f} ({min(ratio):.2f} .. {max(ratio):.2f})", flush=True)


BACKEND_MODELS = ("swing_bar", "double_pendulum", "passive_walker")


def backend_ab(root: Path, rounds: int = 9, seconds: float = 20.0) -> None:
    """RK4 steps per CPU second of each model of BACKEND_MODELS with the C leaves (andyc/codegen/c_leaves.py)
    against the Numba leaves (ANDYC_BACKEND=numba), both built and run in one process, alternated C/N, N/C over
    `rounds`: the ratio C/N of each round, median, min and max. The thread's CPU time, not the wall's, so that
    other work on the machine counts less (issue 27: the C leaves run no slower, ratio >= 0.99)."""
    import statistics

    sys.path.insert(0, str(root))
    import andyc

    with tempfile.TemporaryDirectory(prefix="andyc-backends-") as tmp:
        for model in BACKEND_MODELS:
            built = {}
            for backend in ("c", "numba"):
                os.environ["ANDYC_BACKEND"] = backend
                built[backend] = andyc.compile_model(root / "models" / f"{model}.yaml", Path(tmp) / backend)[0]
                andyc.simulate(built[backend], 0.01, dt=1e-3, progress=False)
            os.environ.pop("ANDYC_BACKEND")
            rates = {"c": [], "numba": []}
            for k in range(rounds):
                for backend in (("c", "numba") if k % 2 == 0 else ("numba", "c")):
                    start = time.thread_time()
                    andyc.simulate(built[backend], seconds, dt=1e-3, every=1000, progress=False)
                    rates[backend].append(seconds / 1e-3 / (time.thread_time() - start))
            ratio = [c / n for c, n in zip(rates["c"], rates["numba"])]
            print(f"{model}: C {statistics.median(rates['c']):.3g} RK4 steps per CPU s, Numba "
                  f"{statistics.median(rates['numba']):.3g}; C/Numba median {statistics.median(ratio):.3f} "
                  f"({min(ratio):.3f} .. {max(ratio):.3f}), {rounds} rounds", flush=True)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=ROOT, help="the andyc checkout to measure (default: this one)")
    parser.add_argument("--models", default=",".join(MODELS))
    parser.add_argument("--repeats", type=int, default=1, help="cold rows per model (each in fresh folders)")
    parser.add_argument("--functions", metavar="MODEL", help="only the per-function compile profile of MODEL")
    parser.add_argument("--speed-ab", metavar="OTHER_TREE", type=Path,
                        help="only the A/B of simulation speed: OTHER_TREE (A) against --root (B)")
    parser.add_argument("--backend-ab", action="store_true",
                        help="only the same-process A/B of RK4 steps/s, the C leaves against the Numba leaves")
    args = parser.parse_args(argv)
    root = args.root.resolve()
    if args.backend_ab:
        backend_ab(root)
        return 0
    if args.speed_ab:
        speed_ab(root, args.speed_ab.resolve())
        return 0
    with tempfile.TemporaryDirectory(prefix="andyc-latency-") as tmp:
        tmp = Path(tmp)
        shared = tmp / "andyc-cache"
        first = first_use(root, tmp / "first", shared)
        if args.functions:
            profile(root, args.functions, shared)
            return 0
        env = dict(os.environ)
        version = min(_andyc(root, ["--version"], tmp, env)[0] for _ in range(3))
        check = min(_andyc(root, ["check", root / "models" / "passive_walker.yaml"], tmp, env)[0] for _ in range(3))
        print(f"andyc at {root}")
        print(f"andyc --version: {version:.2f} s (target 0.3 s); andyc check passive_walker: {check:.2f} s "
              "(target 1.5 s); best of 3")
        print(f"first andyc sim after installing andyc (the shared numerics compile once, then the double "
              f"pendulum): {first:.1f} s")
        print()
        print(f"{'model':16s} {'cold sim':>9s} {'target':>6s} | {'build':>6s} {'derive':>6s} {'gen':>5s} "
              f"{'cc':>5s} {'numba':>6s} {'then sim':>8s} | {'warm sim':>8s}")
        for model in args.models.split(","):
            for k in range(args.repeats):
                work = tmp / f"{model}-{k}"
                work.mkdir()
                r = measure(root, model, work, shared)
                print(f"{model:16s} {r['cold']:8.1f}s {TARGETS.get(model, 0):5d}s | {r['build']:5.1f}s "
                      f"{r['derive']:5.1f}s {r['generate']:4.1f}s {r['cc']:4.1f}s {r['numba_build']:5.1f}s "
                      f"{r['sim_after_build']:7.1f}s | {r['warm']:7.2f}s", flush=True)
    print()
    print("cold sim: `andyc sim` in a fresh build folder with a fresh NUMBA_CACHE_DIR (build, compile, a 1 s run),")
    print("andyc's shared numerics compiled (the first line above);")
    print("build: `andyc build` in another fresh folder, of which derive, generate, cc (the C compiler on the leaves)")
    print("and numba (compile or cache load; andyc's figures); then sim: `andyc sim` after it; warm sim: the cold")
    print("command again.")
    return 0


if __name__ == "__main__":
    sys.exit(main())
