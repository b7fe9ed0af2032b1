#!/bin/bash
# The first run on a fresh install, in CPU seconds (user + sys of the whole process, children included:
# they do not depend on the machine's load), as docs/BENCHMARKS.md "First run" reports them:
#   cold    `andyc sim models/double_pendulum.yaml` with every cache empty: a fresh build folder,
#           NUMBA_CACHE_DIR, ANDYC_CACHE_DIR (and XDG_CACHE_HOME), no __pycache__ under andyc/
#   second  then `andyc sim` of another new model (SECOND, default models/pendulum_a01.yaml), caches kept
#   warm    the double pendulum's command again
# Usage: bench/first_run.sh [ROUNDS [SECOND [ROOT]]]   ROOT: the andyc tree to time (default: this one);
# PYTHON: the interpreter (default: python3). It deletes ROOT/andyc's __pycache__ folders.
set -e
ROUNDS=${1:-3}; SECOND=${2:-models/pendulum_a01.yaml}; ROOT=${3:-$(cd "$(dirname "$0")/.." && pwd)}
PYTHON=${PYTHON:-python3}
cd "$ROOT"
cpu() {  # CPU seconds of one `andyc sim` in the folder $D
    /usr/bin/time -f "%U %S" -o "$D/time" env NUMBA_CACHE_DIR="$D/numba" ANDYC_CACHE_DIR="$D/andyc" \
        XDG_CACHE_HOME="$D/xdg" PYTHONPATH="$ROOT" "$PYTHON" -m andyc.cli sim "$1" --build-dir "$D/build" \
        -o "$D/run.h5" > "$D/out" 2> "$D/err" || { cat "$D/err" >&2; exit 1; }
    awk '{printf "%.2f", $1 + $2}' "$D/time"
}
for r in $(seq "$ROUNDS"); do
    D=$(mktemp -d)
    find andyc -name __pycache__ -prune -exec rm -rf {} +
    cold=$(cpu models/double_pendulum.yaml); second=$(cpu "$SECOND"); warm=$(cpu models/double_pendulum.yaml)
    echo "round $r: cold $cold s, second ($(basename "$SECOND" .yaml)) $second s, warm $warm s"
    rm -rf "$D"
done
