"""Same behaviour, two checkouts: does a change keep every shipped model's numbers? (issue 20's check)

For each checkout (this one and OTHER_TREE, e.g. a `git worktree` of an earlier commit), in a process of
its own with that checkout's andyc on PYTHONPATH, every model both ship is built from that checkout's own
file (a later one may add sections the earlier cannot read) into a fresh folder and

- run for 1 s with rk4, projection and DOP853 (dt 1e-3; `init` as-is where the model asks for it): the
  logged states, energies and multipliers;
- its generated functions evaluated at the same 20 random states (seeded; quaternions normalised): energy,
  mass matrix, generalized force, rhs, frame positions, power, the constraint terms and every guard.

Then the two are compared, array by array: the largest difference, and how many agree to the bit.

    python bench/compare_trees.py OTHER_TREE [--models double_pendulum,fourbar]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
METHODS = ("rk4", "projection", "DOP853")

# Run in each checkout (its andyc first on sys.path): results as one .npz of named arrays.
WORKER = r'''
import sys, numpy as np
root, out, models_dir, names = sys.argv[1], sys.argv[2], sys.argv[3], sys.argv[4].split(",")
sys.path.insert(0, root)
import andyc
results = {}
for name in names:
    model, _ = andyc.compile_model(f"{models_dir}/{name}.yaml", out + "/build")
    as_is = getattr(andyc, "Init", None)
    kw = {"init": as_is(mode="as-is") if as_is else "as-is"} if name in ("fourbar", "biped_rheonomic") else {}
    for method in ("rk4", "projection", "DOP853"):
        run = andyc.simulate(model, 1.0, dt=1e-3, method=method, **kw)
        for field, a in (("x", run.state), ("e", run.energy), ("lam", run.multipliers)):
            results[f"run/{name}/{method}/{field}"] = np.nan_to_num(np.asarray(a, float), nan=123.0)
    m = model.module
    p, u, d = m.PARAMETER_DEFAULTS, m.INPUT_DEFAULTS, m.DISCRETE_DEFAULTS
    rng = np.random.default_rng(1)
    for k in range(20):
        x = m.initial_state() + 0.3 * rng.standard_normal(m.NX)
        for q in m.QUATERNIONS:
            x[q:q + 4] /= np.linalg.norm(x[q:q + 4])
        frames = np.zeros((len(m.FRAMES), 3))      # into an array: older modules return nothing
        m.frame_positions(0.3, x, u, p, d, frames)
        values = {"energy": m.energy(0.3, x, u, p, d), "M": m.mass_matrix(0.3, x, u, p, d),
                  "G": m.generalized_force(0.3, x, u, p, d), "rhs": m.rhs(0.3, x, u, p, d),
                  "frames": frames, "power": m.power(0.3, x, u, p, d)}
        if m.NC:
            terms = [np.empty(m.NH), np.empty(m.NC), np.empty((m.NC, m.NV)), np.empty(m.NC)]
            m.constraints(0.3, x, u, p, d, *terms)
            values.update(zip(("phi", "c", "A", "kappa"), terms))
        for j in range(m.NJ):
            values[f"guard{j}"] = m.guard(j, 0.3, x, u, p, d)
        for key, v in values.items():
            results[f"fn/{name}/{key}/{k}"] = np.asarray(v, float)
np.savez(out + "/results.npz", **results)
'''


def results_of(tree: Path, models: list, folder: Path) -> dict:
    folder.mkdir(parents=True)
    env = {**os.environ, "PYTHONPATH": str(tree), "NUMBA_CACHE_DIR": str(folder / "numba-cache")}
    proc = subprocess.run([sys.executable, "-c", WORKER, str(tree), str(folder), str(tree / "models"),
                           ",".join(models)], env=env, capture_output=True, text=True)
    if proc.returncode != 0:
        raise SystemExit(f"{tree}: the runs failed:\n{proc.stderr[-3000:]}")
    with np.load(folder / "results.npz") as data:
        return {key: data[key] for key in data.files}


def compare(a: dict, b: dict, prefix: str) -> tuple:
    """(arrays compared, arrays equal to the bit, largest difference relative to max(1, |a|))."""
    keys = sorted(k for k in a if k.startswith(prefix))
    missing = [k for k in keys if k not in b or a[k].shape != b[k].shape]
    if missing:
        raise SystemExit(f"not in both, or of other shapes: {', '.join(missing[:5])}")
    diffs = [float(np.abs(a[k] - b[k]).max() / max(1.0, float(np.abs(a[k]).max()))) if a[k].size else 0.0
             for k in keys]
    return len(keys), sum(d == 0.0 for d in diffs), max(diffs, default=0.0)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("other", type=Path, help="the other checkout (its andyc/ and models)")
    parser.add_argument("--models", default=None, help="comma-separated (default: every shipped model the other "
                                                       "checkout has too)")
    args = parser.parse_args(argv)
    mine = {p.stem for p in (ROOT / "models").glob("*.yaml")}
    theirs = {p.stem for p in (args.other / "models").glob("*.yaml")}
    models = args.models.split(",") if args.models else sorted(mine & theirs)
    with tempfile.TemporaryDirectory() as tmp:
        a = results_of(args.other.resolve(), models, Path(tmp) / "other")
        b = results_of(ROOT, models, Path(tmp) / "this")
    print(json.dumps({"models": models}))
    for prefix, what in (("run/", "1 s runs (states, energies, multipliers)"), ("fn/", "generated functions "
                                                                                      "at 20 random states")):
        n, equal, worst = compare(a, b, prefix)
        print(f"{what}: {n} arrays, {equal} equal to the bit, largest relative difference {worst:.3g}")


if __name__ == "__main__":
    main()
