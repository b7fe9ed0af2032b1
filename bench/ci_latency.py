"""Wall time of a warm `andyc test models/`: every shipped model's expectations (expect:), as a CI job
meets them once the builds and Numba's cache are in place (make bench prints it).

The first `andyc test` builds whatever is missing in the build folder (untimed, reported); then the
command is timed `--repeats` times, a whole process each (`python -m andyc.cli`, imports included).

    python bench/ci_latency.py                 build/bench-test, 3 timed runs
    python bench/ci_latency.py --repeats 5 --build-dir build/tests
"""

from __future__ import annotations

import argparse
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def timed(build_dir: str) -> tuple[float, subprocess.CompletedProcess]:
    start = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "andyc.cli", "test", "models", "--build-dir", build_dir],
                          cwd=ROOT, capture_output=True, text=True)
    return time.perf_counter() - start, proc


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--build-dir", default="build/bench-test")
    args = parser.parse_args(argv)
    first, proc = timed(args.build_dir)
    if proc.returncode != 0:
        print(proc.stdout + proc.stderr, file=sys.stderr)
        return 1
    times = [timed(args.build_dir)[0] for _ in range(args.repeats)]
    last = proc.stdout.strip().splitlines()[-1]
    print(f"andyc test models/ ({last}): first {first:.2f} s (builds what is missing); warm "
          f"median {statistics.median(times):.2f} s, min {min(times):.2f} s over {args.repeats} runs")
    return 0


if __name__ == "__main__":
    sys.exit(main())
