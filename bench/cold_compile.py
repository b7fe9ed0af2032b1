"""Where a first run's compile time goes: `andyc sim` of one model in this process, with Numba's compile events
recorded, then the CPU seconds of compile_model and simulate and the compilations that took longest (each
function's own, callees compiled first included; d0: called from Python, d1: a callee of one).

Run it with every cache empty to see a fresh install's first run (docs/BENCHMARKS.md, "First run"):

    find andyc -name __pycache__ -prune -exec rm -rf {} +
    ANDYC_CACHE_DIR=$(mktemp -d) NUMBA_CACHE_DIR=$(mktemp -d) python bench/cold_compile.py MODEL.yaml BUILD_DIR \\
        [METHOD]
"""

import collections
import sys
import time

from numba.core import event


def main(model_file: str, build_dir: str, method: str = "rk4") -> None:
    with event.install_recorder("numba:compile") as recorder:
        import andyc

        t0 = time.process_time()
        model = andyc.compile_model(model_file, build_dir, integrator=False)[0]     # as `andyc sim` does
        t1 = time.process_time()
        andyc.simulate(model, t_end=0.05, method=method, progress=False)
        t2 = time.process_time()
    print(f"compile_model {t1 - t0:.1f} s, simulate {t2 - t1:.1f} s of CPU")
    starts, took, depth = collections.defaultdict(list), collections.Counter(), 0
    for stamp, e in recorder.buffer:
        key = str(e.data.get("dispatcher")) if e.data else "?"
        if e.is_start:
            starts[key].append((stamp, depth))
            depth += 1
        else:
            depth -= 1
            began, level = starts[key].pop()
            if level <= 1:
                took[(level, key)] += stamp - began
    for (level, key), seconds in took.most_common(15):
        print(f"{seconds:7.1f} s  d{level}  {key[:100]}")


if __name__ == "__main__":
    main(*sys.argv[1:])
