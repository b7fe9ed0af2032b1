"""Build time of the IFToMM A02 N-four-bar by stage, in CPU seconds, against the size of the generated code
(issue 27: the build grows no faster than the generated code; N = 40 under 2 min on the 2-core machine).

Each N builds in a fresh process and a fresh folder (bench/large_models.py's nfourbar_yaml): load, derive
(andyc/symbolic), generate (andyc/codegen: cse and printing) in this process's CPU time, then the C compiler
on the leaves in its processes' CPU time (resource's RUSAGE_CHILDREN; compiled in parallel where the leaves
are split, so its wall time can be less). CPU seconds, not wall, since the machine is shared. Then the growth
exponent of each stage against the operation count of the leaves (a least-squares slope of log time on log
operations): 1 is linear in the generated code.

    python bench/build_time.py                 N = 10, 20, 40
    python bench/build_time.py --sizes 10,20   (N = 40 takes a few minutes of CPU)
    python bench/build_time.py --model models/g1.yaml --before /tmp/old --rounds 2
                                               a model file's build, this checkout and another alternated
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STAGES = ("load", "derive", "generate", "cc")

ONE = """
import json, resource, sys, time
from pathlib import Path
sys.path.insert(0, sys.argv[3])
from large_models import nfourbar_yaml
from andyc import pipeline

n, folder = sys.argv[1], Path(sys.argv[2])
if n.isdigit():
    path = folder / f"nfourbar{n}.yaml"
    path.write_text(nfourbar_yaml(int(n)))
else:
    path = Path(n)

def children():
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime

out = {}
t = time.process_time()
spec = pipeline.load(path)
out["load"] = time.process_time() - t
t = time.process_time()
model = pipeline.derive(spec)
out["derive"] = time.process_time() - t
t, c, wall = time.process_time(), children(), time.perf_counter()
result = pipeline.generate(model, folder / "build", force=True)
out["generate"] = time.process_time() - t
out["cc"] = children() - c
out["cc_wall"] = result.timings.get("cc", 0.0)
out["operations"] = sum(result.operations.values())
out["andyc"] = str(Path(pipeline.__file__).parent)
print(json.dumps(out))
"""


def measure(n, root: Path) -> dict:
    """The build of N-four-bar `n` (an int) or of the model file `n` by andyc at `root`, in a fresh process."""
    with tempfile.TemporaryDirectory(prefix="andyc-build-time-") as tmp:
        proc = subprocess.run([sys.executable, "-c", ONE, str(n), tmp, str(root / "bench")], capture_output=True,
                              text=True, env={**os.environ, "PYTHONPATH": str(root)}, cwd=tmp)     # (not this folder)
    if proc.returncode != 0:
        raise SystemExit(proc.stderr)
    out = json.loads(proc.stdout.splitlines()[-1])
    if Path(out["andyc"]) != root / "andyc":
        raise SystemExit(f"measured the andyc at {out['andyc']}, not {root}")
    return out


def slope(xs, ys) -> float:
    """The least-squares slope of log y on log x."""
    lx, ly = [math.log(x) for x in xs], [math.log(max(y, 1e-9)) for y in ys]
    mx, my = sum(lx) / len(lx), sum(ly) / len(ly)
    return sum((a - mx) * (b - my) for a, b in zip(lx, ly)) / sum((a - mx) ** 2 for a in lx)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", default="10,20,40")
    parser.add_argument("--root", type=Path, default=ROOT, help="the andyc checkout to measure (default: this one)")
    parser.add_argument("--model", type=Path, help="a model file to build instead of the N-four-bars")
    parser.add_argument("--before", type=Path, help="with --model: another checkout, built alternately with --root")
    parser.add_argument("--rounds", type=int, default=1)
    args = parser.parse_args(argv)
    if args.model is not None:
        return _model(args)
    rows = {}
    print(f"andyc at {args.root.resolve()}; CPU seconds")
    print(f"{'N':>3} {'operations':>10} {'load':>6} {'derive':>7} {'generate':>8} {'cc':>6} {'cc wall':>7} {'total':>7}")
    for n in map(int, args.sizes.split(",")):
        r = rows[n] = measure(n, args.root.resolve())
        total = sum(r[s] for s in STAGES)
        print(f"{n:>3} {r['operations']:>10} {r['load']:6.1f} {r['derive']:7.1f} {r['generate']:8.1f} {r['cc']:6.1f} "
              f"{r['cc_wall']:7.1f} {total:7.1f}", flush=True)
    if len(rows) > 1:
        ops = [r["operations"] for r in rows.values()]
        print("growth exponent against the operations (1: as the generated code): " + ", ".join(
            f"{s} {slope(ops, [r[s] for r in rows.values()]):.2f}" for s in ("derive", "generate", "cc"))
            + f", total {slope(ops, [sum(r[s] for s in STAGES) for r in rows.values()]):.2f}")
    return 0


def _model(args) -> int:
    """Builds of one model file, by stage, each checkout in turn (--before first) for --rounds."""
    roots = ([("before", args.before.resolve())] if args.before else []) + [("now", args.root.resolve())]
    print(f"{args.model}: CPU seconds by stage (cc: the C compiler's processes), cc wall and the whole build's wall")
    print(f"{'':>7} {'operations':>10} {'load':>6} {'derive':>7} {'generate':>8} {'cc':>6} {'cc wall':>7} "
          f"{'CPU':>6} {'wall':>6}")
    for _ in range(args.rounds):
        for label, root in roots:
            tic = time.perf_counter()
            r = measure(args.model.resolve(), root)
            wall = time.perf_counter() - tic
            print(f"{label:>7} {r['operations']:>10} {r['load']:6.1f} {r['derive']:7.1f} {r['generate']:8.1f} "
                  f"{r['cc']:6.1f} {r['cc_wall']:7.1f} {sum(r[s] for s in STAGES):6.1f} {wall:6.1f}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
