"""Microseconds per solve of the step's contact problem: the compiled andyc.numerics.contact_solver against its
Python twin andyc.independent.contact_problem, for n = 4, 8, 16, 32 spatial contacts (3 n rows), mu = 0.5 .. 0.8.

Two systems. random: W = A M^-1 A^T of a random A (3n x nv, nv = 3n + 6: W positive definite) and a random SPD
M, every contact approaching (w0_n = -1) with a random slip (normal, deviation 0.5): most slide, some stick,
a few open. boxes: n / 4 boxes flat on four corners each (12 rows on 6 speeds a box: W of rank 6 n / 4, the
redundant contacts of flat feet), their speeds coupled (M: the boxes' own inertias plus a random SPD part),
one step h of gravity from small random speeds: most stick. Cold: no guess (Gauss-Seidel sweeps, then the
polish); warm: the states (and directions, impulses) of the cold solve given back (the polish alone, as in a
step that keeps its contacts' states). The compiled solver is timed from Python (each call through Numba's
dispatcher) and in a compiled loop (what a compiled time-stepping loop pays). Alternated rounds (each variant
in turn), min and max of the rounds' means over them.

    python bench/contact_solver.py              (rounds 5)
    python bench/contact_solver.py --rounds 9 --contacts 4,32 --systems random
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from andyc.numerics import contact_solver as cs  # noqa: E402
from andyc.independent import contact_problem as cp  # noqa: E402


def random_system(n: int, seed: int = 0):
    """(W, w0, mu) of n spatial contacts on a random system (the module's docstring)."""
    rng = np.random.default_rng(seed)
    m, nv = 3 * n, 3 * n + 6
    A = rng.normal(size=(m, nv))
    B = rng.normal(size=(nv, nv))
    W = A @ np.linalg.solve(B @ B.T + nv * np.eye(nv), A.T)
    w0 = rng.normal(scale=0.5, size=m)
    w0[::3] = -1.0
    return W, w0, 0.5


def boxes(n: int, seed: int = 0):
    """(W, w0, mu) of n // 4 coupled boxes on four corners each (the module's docstring)."""
    rng = np.random.default_rng(seed)
    k, mass, (a, b, c), g, h = n // 4, 2.0, (0.3, 0.2, 0.1), 9.81, 1e-3
    inertia = mass / 3 * np.array([b * b + c * c, a * a + c * c, a * a + b * b])
    B = rng.normal(scale=0.1, size=(6 * k, 6 * k))
    M = np.kron(np.eye(k), np.diag([mass, mass, mass, *inertia])) + B @ B.T
    A = np.zeros((3 * n, 6 * k))
    for box in range(k):
        for corner, (x, y) in enumerate(((a, b), (-a, b), (-a, -b), (a, -b))):
            r = np.array([x, y, -c])
            for t, e in enumerate(np.eye(3)[[2, 0, 1]]):        # (normal z, tangents x, y: e . (v + omega x r))
                A[12 * box + 3 * corner + t, 6 * box:6 * box + 6] = np.concatenate([e, np.cross(r, e)])
    v = rng.normal(scale=1e-4, size=6 * k) + h * np.tile([0, 0, -g, 0, 0, 0], k)
    return A @ np.linalg.solve(M, A.T), A @ v, 0.8


SYSTEMS = {"random": random_system, "boxes": boxes}


def problem(system: str, n: int):
    """(W, w0, kind, first, mu, blocks) of n spatial contacts on `system`."""
    W, w0, mu = SYSTEMS[system](n)
    kind = np.full(n, cs.SPATIAL, np.int64)
    first = np.arange(0, 3 * n, 3, dtype=np.int64)
    blocks = [cp.Block(cp.SPATIAL, (3 * k, 3 * k + 1, 3 * k + 2), mu) for k in range(n)]
    return np.ascontiguousarray(0.5 * (W + W.T)), w0, kind, first, np.full(n, mu), blocks


@numba.njit
def _loop(count, warm, W, w0, kind, first, mu, state, direction, P, work, state0, direction0, P0):
    """`count` solves from compiled code, each from the given guess (warm) or none."""
    sweeps = 0
    for _ in range(count):
        for k in range(state.shape[0]):
            state[k] = state0[k] if warm else cs.NONE
            direction[k, 0], direction[k, 1] = direction0[k, 0], direction0[k, 1]
        for i in range(P.shape[0]):
            P[i] = P0[i]
        sweeps += cs.solve(W, w0, kind, first, mu, state, direction, P, work)[0]
    return sweeps


def variants(system: str, n: int):
    """(name -> a function of a count that makes that many solves; a description of the problem)."""
    W, w0, kind, first, mu, blocks = problem(system, n)
    m, nb = len(w0), len(kind)
    state, direction, P = np.full(nb, cs.NONE, np.int64), np.zeros((nb, 2)), np.zeros(m)
    work = np.empty(cs.work_shape(m))
    sweeps, verified = cs.solve(W, w0, kind, first, mu, state, direction, P, work)
    guess = cp.solve(W, w0, blocks)
    assert verified and list(state) == guess.states
    state0, direction0, P0 = state.copy(), direction.copy(), P.copy()
    open_, stick, slide = np.bincount(state0, minlength=3)[:3]
    info = (f"{system}, {n} contacts ({m} rows, rank {np.linalg.matrix_rank(W)}): {sweeps} sweeps cold; {stick} "
            f"stick, {slide} slide, {open_} open; the Python twin {'' if guess.verified else 'un'}verified")

    def python(warm):
        def run(count):
            for _ in range(count):
                cp.solve(W, w0, blocks, guess if warm else None)
        return run

    def from_python(warm):
        def run(count):
            for _ in range(count):
                state[:] = state0 if warm else cs.NONE
                direction[:] = direction0
                P[:] = P0
                cs.solve(W, w0, kind, first, mu, state, direction, P, work)
        return run

    def in_loop(warm):
        def run(count):
            _loop(count, warm, W, w0, kind, first, mu, state, direction, P, work, state0, direction0, P0)
        return run

    out = {}
    for warm in (False, True):
        label = "warm" if warm else "cold"
        out[f"python {label}"] = python(warm)
        out[f"compiled {label} (from Python)"] = from_python(warm)
        out[f"compiled {label} (compiled loop)"] = in_loop(warm)
    for run in out.values():
        run(1)                                  # (compiles, once)
    return out, info


def per_call(run, budget: float = 0.2) -> float:
    """Microseconds per call of run(count), count grown until one timing takes `budget` seconds."""
    count = 1
    while True:
        t = time.perf_counter()
        run(count)
        elapsed = time.perf_counter() - t
        if elapsed >= budget or count >= 1 << 20:
            return elapsed / count * 1e6
        count *= max(2, int(budget / max(elapsed, 1e-6) * 1.2))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--contacts", default="4,8,16,32")
    parser.add_argument("--systems", default="random,boxes")
    args = parser.parse_args()
    for system, n in ((s, int(x)) for s in args.systems.split(",") for x in args.contacts.split(",")):
        runs, info = variants(system, n)
        times = {name: [] for name in runs}
        for _ in range(args.rounds):
            for name, run in runs.items():
                times[name].append(per_call(run))
        print(info)
        for name, values in times.items():
            print(f"  {name:34s} {min(values):10.1f} .. {max(values):10.1f} us")
        for label in ("cold", "warm"):
            ratio = min(times[f"python {label}"]) / min(times[f"compiled {label} (compiled loop)"])
            print(f"  {label}: compiled loop {ratio:.0f}x faster than Python (min / min)")


if __name__ == "__main__":
    main()
