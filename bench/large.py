"""Issue 27: large models. Forward dynamics per call on the planar chain (andyc's compiled function in a
compiled loop, `pin.aba` and MuJoCo's `mj_forward` from Python), RK4 steps/s against MuJoCo's RK4 C loop
(`mj_step` with nstep), the URDF robots (ur5, panda, solo12; g1 and talos_full with --large), and the IFToMM
A02 N-four-bar (us per projection step, build time by stage, B0 against the reduced exact motion;
bench/large_models.py); and the factor + solve kernels alone, dense against the tree's LTDL, which the
choice of formulation rests on. Each chain row says which formulation the build chose (dense, ltdl or aba:
andyc/symbolic/formulation.py); a robot's line times M, G + dense, M, G + LTDL and, when chosen, the
articulated-body algorithm's leaf, in the same rounds.

On a loaded machine absolute times move: every figure comes from `--rounds` alternated rounds (andyc, then
each peer, then andyc again ...), printed as min .. max, and ratios are taken within a round.

    python bench/large.py                       chain n = 2, 4, 8, 16; ur5, panda, solo12; N-four-bar N = 1, 2, 5
    python bench/large.py --large               also n = 24, 32, g1, talos_full and N = 10 (minutes of compile)
    python bench/large.py --chain 2 8 --fourbar 1 --robot solo12
    python bench/large.py --cpp                 also the robots against Pinocchio's C++ aba (bench/pinocchio_cpp.py)
    python bench/run.py --only large            as a section of `make bench`
"""

from __future__ import annotations

import argparse
import dataclasses
import tempfile
import time
from pathlib import Path

import numpy as np
from numba import njit

import andyc
from andyc.independent.robots import robots_dir
from andyc.numerics.linalg import cholesky, ltdl, ltdl_solve, solve_lower, solve_upper
from andyc.symbolic.formulation import dense_operations, ltdl_operations, tree_of

from large_models import (nfourbar_yaml, planar_chain_mjcf, planar_chain_pinocchio, planar_chain_yaml,
                          reduced_b0)
from run import _rhs_arguments, _rhs_loop, section

CHAINS, CHAINS_LARGE = (2, 4, 8, 16), (24, 32)
FOURBARS, FOURBARS_LARGE = (1, 2, 5), (10,)
ROBOTS = {    # name: (URDF inside example-robot-data, base)
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "fixed"),
    "panda": ("panda_description/urdf/panda.urdf", "fixed"),
    "solo12": ("solo_description/robots/solo12.urdf", "floating"),
    "g1": ("g1_description/urdf/g1_29dof_rev_1_0.urdf", "floating"),
    "talos_full": ("talos_data/robots/talos_full_v2.urdf", "floating"),
}
B0_TIMES = (0.5, 1.0, 12.5, 20.0)


def _spread(values) -> str:
    return f"{min(values):.3g} .. {max(values):.3g}"


def _per_call(f, n) -> float:
    """Microseconds per call of f() over n calls."""
    tic = time.perf_counter()
    for _ in range(n):
        f()
    return 1e6 * (time.perf_counter() - tic) / n


def generic_state(model, seed: int = 0) -> np.ndarray:
    """The model's initial state with its coordinates and speeds drawn from [-1, 1] (a floating base's pose, its
    signals, stays): a pose a robot moves through rather than zero, where sin and cos return at once."""
    x = model.initial_state(model.parameter_defaults).copy()
    n = model.nq + model.nv
    x[:n] = np.random.default_rng(seed).uniform(-1.0, 1.0, n)
    return x


def pin_generic(pmodel, seed: int = 0):
    """(q, v) for Pinocchio alike: a random configuration within [-1, 1] (a free flyer's quaternion a random unit
    one) and speeds from [-1, 1]."""
    import pinocchio as pin
    pin.seed(seed)
    q = pin.randomConfiguration(pmodel, -np.ones(pmodel.nq), np.ones(pmodel.nq))
    return q, np.random.default_rng(seed).uniform(-1.0, 1.0, pmodel.nv)


class AndycForward:
    """andyc's right-hand side in a compiled loop (bench/run.py's _rhs_loop) at `state` (default: the initial
    state): us per evaluation."""

    def __init__(self, model, state=None):
        self.args, self.work = _rhs_arguments(model)
        if state is not None:
            self.args[2][:] = state
        self.loop = _rhs_loop(model)
        self.loop(10, *self.args)

    def __call__(self, n) -> float:
        tic = time.perf_counter()
        self.loop(n, *self.args)
        return 1e6 * (time.perf_counter() - tic) / n


def pin_forward(pmodel, q, v):
    """pin.aba from Python at (q, v), zero torque: us per call."""
    import pinocchio as pin
    data, tau = pmodel.createData(), np.zeros(pmodel.nv)
    return lambda n: _per_call(lambda: pin.aba(pmodel, data, q, v, tau), n)


def mujoco_model(mjcf: str):
    try:
        import mujoco
    except ImportError:
        return None
    return mujoco.MjModel.from_xml_string(mjcf)


def mujoco_forward(m, q, v):
    """mj_forward from Python at (q, v): us per call."""
    import mujoco
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = q, v
    return lambda n: _per_call(lambda: mujoco.mj_forward(m, d), n)


def compare(timers: dict, rounds: int, n: int) -> dict:
    """name -> [us per call, one per round], the timers alternated within each round."""
    out = {name: [] for name in timers}
    for name, f in timers.items():          # warm up
        f(max(1, n // 10))
    for _ in range(rounds):
        for name, f in timers.items():
            out[name].append(f(n))
    return out


def _ratios(times: dict, a: str, b: str) -> list:
    return [x / y for x, y in zip(times[a], times[b])]


def chain_section(tmp: Path, sizes, rounds: int) -> None:
    section("planar chain: forward dynamics per call, and RK4 steps/s against MuJoCo (issue 27)")
    print("us per call, min .. max over alternated rounds; ratios within a round. andyc: rhs in a compiled loop;")
    print("pin.aba and mj_forward called from Python (their binding's cost included).")
    print(f"{'n':>3} {'build s':>8} {'andyc us':>14} {'pin.aba us':>14} {'mj_forward us':>14} "
          f"{'andyc/pin':>12} {'andyc/mj_fwd':>12} {'RK4 andyc/MuJoCo':>17}")
    for n in sizes:
        path = tmp / f"chain{n}.yaml"
        path.write_text(planar_chain_yaml(n))
        tic = time.perf_counter()
        model, result = andyc.compile_model(path, tmp / "build", force=True)
        build = time.perf_counter() - tic
        x = model.initial_state(model.parameter_defaults)
        q, v = x[:n].copy(), x[n:].copy()
        timers = {"andyc": AndycForward(model)}
        try:
            timers["pin"] = pin_forward(planar_chain_pinocchio(n), q, v)
        except ImportError:
            pass
        mj = mujoco_model(planar_chain_mjcf(n))
        if mj is not None:
            timers["mujoco"] = mujoco_forward(mj, q, v)
        agree = same_accelerations(model, x, planar_chain_pinocchio(n), mj)
        times = compare(timers, rounds, 20000)
        cells = [_spread(times[k]) if k in times else "-" for k in ("andyc", "pin", "mujoco")]
        ratios = [_spread(_ratios(times, "andyc", k)) if k in times else "-" for k in ("pin", "mujoco")]
        rk4 = _spread(rk4_ratios(model, mj, rounds)) if mj is not None else "-"
        print(f"{n:>3} {build:>8.1f} {cells[0]:>14} {cells[1]:>14} {cells[2]:>14} {ratios[0]:>12} {ratios[1]:>12} "
              f"{rk4:>17}  {agree}; {model.module.FORMULATION}", flush=True)
    print("RK4 andyc/MuJoCo: andyc's RK4 steps/s (andyc.simulate, dt = 1e-3, 5 s, logging every 1000 steps) over "
          "MuJoCo's (mj_step with nstep = 5000, integrator RK4), per round; > 1: andyc faster.")


def same_accelerations(model, x, pmodel, mj) -> str:
    """The largest relative difference of pin.aba's and mj_forward's accelerations from andyc's at x."""
    n = model.nv
    a = model.module.rhs(0.0, x)[n:]
    out = []
    try:
        import pinocchio as pin
        out.append("pin %.0e" % (abs(pin.aba(pmodel, pmodel.createData(), x[:n], x[n:], np.zeros(n)) - a).max()
                                 / abs(a).max()))
    except ImportError:
        pass
    if mj is not None:
        import mujoco
        d = mujoco.MjData(mj)
        d.qpos[:], d.qvel[:] = x[:n], x[n:]
        mujoco.mj_forward(mj, d)
        out.append("mujoco %.0e" % (abs(d.qacc - a).max() / abs(a).max()))
    return "same qdd: " + ", ".join(out)


def rk4_ratios(model, mj, rounds: int, t_end: float = 5.0, dt: float = 1e-3) -> list:
    """Per round: andyc's RK4 steps/s over MuJoCo's, both integrating the chain for t_end."""
    import mujoco
    d = mujoco.MjData(mj)
    steps = int(round(t_end / dt))
    andyc.simulate(model, 10 * dt, dt=dt, progress=False)
    out = []
    for _ in range(rounds):
        wall = andyc.simulate(model, t_end, dt=dt, every=1000, progress=False).stats["wall_seconds"]
        mujoco.mj_resetData(mj, d)
        d.qpos[:] = 0.3
        tic = time.perf_counter()
        mujoco.mj_step(mj, d, nstep=steps)
        out.append((time.perf_counter() - tic) / wall)
    return out


def formulation_loops(model, state=None) -> dict:
    """name -> timer (us per evaluation) of M dv/dt = G solved both ways in the same build: the generated M and G
    (the leaf `dynamics`) then the dense Cholesky, or the tree's LTDL (when M has a tree), or the articulated-body
    algorithm's leaf `forward_dynamics` (when the build chose it: no M): the formulation's gain alone, A/B in one
    process. At `state` (default: the initial state)."""
    numerics = model.numerics
    call, borrowed, linalg = numerics.model.call, numerics.model.borrowed, numerics.linalg
    cholesky_, lower, upper = linalg.cholesky, linalg.solve_lower, linalg.solve_upper
    ltdl_, ltdl_solve_ = linalg.ltdl, linalg.ltdl_solve
    parent, order = model.module.MASS_PARENT, model.module.MASS_ORDER

    @njit(cache=False)
    def dense(n, m, w, x, u, p, d):
        x, u, p, d, M, G = borrowed(x), borrowed(u), borrowed(p), borrowed(d), w.M, w.G
        acc = 0.0
        for _ in range(n):
            x[0] += 1e-12
            call(m.dynamics, (0.0, x, u, p, d, M, G))
            cholesky_(M, m.nv, 0.0)
            lower(M, G, m.nv)
            upper(M, G, m.nv)
            acc += G[0]
        return acc

    @njit(cache=False)
    def tree(n, m, w, x, u, p, d, parent, order):
        x, u, p, d, M, G = borrowed(x), borrowed(u), borrowed(p), borrowed(d), w.M, w.G
        acc = 0.0
        for _ in range(n):
            x[0] += 1e-12
            call(m.dynamics, (0.0, x, u, p, d, M, G))
            ltdl_(M, parent, order, m.nv, 0.0)
            ltdl_solve_(M, parent, order, G, m.nv)
            acc += G[0]
        return acc

    @njit(cache=False)
    def aba(n, m, w, x, u, p, d):
        x, u, p, d, M, G = borrowed(x), borrowed(u), borrowed(p), borrowed(d), w.M, w.G
        acc = 0.0
        for _ in range(n):
            x[0] += 1e-12
            call(m.forward_dynamics, (0.0, x, u, p, d, M, G))
            acc += G[0]
        return acc

    (m, w, x, u, p, d, _), keep = _rhs_arguments(model)
    if state is not None:
        x[:] = state

    def timed(f, *extra):
        def run(n):
            tic = time.perf_counter()
            f(n, m, w, x, u, p, d, *extra)
            return 1e6 * (time.perf_counter() - tic) / n
        run.keep = keep
        return run

    out = {"dense": timed(dense)}
    if len(order):
        out["ltdl"] = timed(tree, parent, order)
    if getattr(model.module, "NB", 0):
        out["aba"] = timed(aba)
    return out


def build_robot(tmp: Path, urdf: Path, base: str):
    """(andyc model, compile result, build seconds, Pinocchio model) of one URDF with a fixed or free-flyer base."""
    import pinocchio as pin
    source = tmp / f"{urdf.stem}.yaml"
    source.write_text(f"urdf: {{file: {urdf}, base: {base}}}\n")
    tic = time.perf_counter()
    model, result = andyc.compile_model(source, tmp / "build", force=True)
    build = time.perf_counter() - tic
    pmodel = (pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer()) if base == "floating"
              else pin.buildModelFromUrdf(str(urdf)))
    return model, result, build, pmodel


def robot_section(tmp: Path, names, rounds: int, cpp: bool = False) -> None:
    """URDF robots: andyc against pin.aba (both from the same URDF, with the same fixed or free-flyer base); with
    cpp, also against Pinocchio's C++ aba (bench/pinocchio_cpp.py) in the same rounds."""
    section("URDF robots: forward dynamics per call against pin.aba (issue 27)")
    try:
        import pinocchio  # noqa: F401 (the section compares with it)
        root = robots_dir()
    except ImportError as exc:
        print(f"skipped: {exc}")
        return
    exe = None
    if cpp:
        import pinocchio_cpp
        exe, why = pinocchio_cpp.build()
        if exe is None:
            print(f"Pinocchio C++ aba: skipped, {why}")
    for name in names:
        path, base = ROBOTS[name]
        urdf = root / path
        if not urdf.exists():
            print(f"{name}: skipped, no {urdf}")
            continue
        model, result, build, pmodel = build_robot(tmp, urdf, base)
        state = generic_state(model)
        timers = {"andyc": AndycForward(model, state), "pin": pin_forward(pmodel, *pin_generic(pmodel)),
                  **formulation_loops(model, state)}
        peer = pinocchio_cpp.CppAba(exe, urdf, base) if exe else None
        try:
            times = compare({**timers, **(pinocchio_cpp.timers(peer) if peer else {})}, rounds, 20000)
        finally:
            if peer:
                peer.close()
        t = result.timings
        print(f"{name} ({base} base): nv {pmodel.nv}, build {build:.1f} s (derive {t.get('derive', 0):.1f}, generate "
              f"{t.get('generate', 0):.1f}, compile {t.get('compile', 0):.1f}); formulation {model.module.FORMULATION}"
              f" {model.module.FORWARD_OPERATIONS}", flush=True)
        print(f"  andyc rhs {_spread(times['andyc'])} us, pin.aba {_spread(times['pin'])} us, andyc/pin.aba "
              f"{_spread(_ratios(times, 'andyc', 'pin'))}; M, G + dense {_spread(times['dense'])} us"
              + (f", M, G + ltdl {_spread(times['ltdl'])} us, ltdl/dense {_spread(_ratios(times, 'ltdl', 'dense'))}"
                 if "ltdl" in times else "")
              + (f", ABA {_spread(times['aba'])} us, ABA/pin.aba {_spread(_ratios(times, 'aba', 'pin'))}, ABA/dense "
                 f"{_spread(_ratios(times, 'aba', 'dense'))}" if "aba" in times else ""), flush=True)
        if peer:
            print("  " + pinocchio_cpp.summary(times, pmodel, peer), flush=True)


def _solves(model) -> dict:
    """name -> the model with that constrained solve (andyc_numerics/model.new_model), the chosen one first: the
    dense and the sparse solve A/B in one process, from one build."""
    chosen = model.module.EQUATIONS.CONSTRAINED_SOLVE
    names = [chosen] + [k for k in ("dense", "sparse") if k != chosen and (k == "dense" or len(model.module.EQUATIONS.ROW_PTR))]
    return {k: dataclasses.replace(model, ref=model.numerics.model.new_model(model.module.EQUATIONS,
                                                                              model.numerics.stubs, k))
            for k in names}


def fourbar_section(tmp: Path, sizes, rounds: int, t_end: float = 20.0, dt: float = 1e-3) -> None:
    section("IFToMM A02 N-four-bar: projection step, build by stage, B0 against the reduced motion (issue 27)")
    print(f"projection method (RK4 + Braun & Goldfarb projection, energy correction), dt = {dt:g} s, {t_end:g} s; "
          f"us per step min .. max over {rounds} rounds, the constrained solves (andyc/symbolic/sparse_rows.py) "
          f"alternated within each round; B0 error: max over t = {B0_TIMES} of |B0 - exact|")
    for n in sizes:
        path = tmp / f"nfourbar{n}.yaml"
        path.write_text(nfourbar_yaml(n))
        tic, cpu = time.perf_counter(), time.process_time()
        model, result = andyc.compile_model(path, tmp / "build", force=True)
        total, cpu = time.perf_counter() - tic, time.process_time() - cpu
        t = result.timings
        exact = reduced_b0(n, B0_TIMES)
        variants = _solves(model)
        walls, worst = {k: [] for k in variants}, {k: 0.0 for k in variants}
        for variant in variants.values():
            andyc.simulate(variant, 10 * dt, dt=dt, method="projection", progress=False)
        for _ in range(rounds):
            for k, variant in variants.items():
                run = andyc.simulate(variant, t_end, dt=dt, method="projection", every=500, frames=["tip0"],
                                     progress=False)
                walls[k].append(1e6 * run.stats["wall_seconds"] / (t_end / dt))
                for j, tk in enumerate(B0_TIMES):
                    i = int(np.argmin(abs(run.time - tk)))
                    worst[k] = max(worst[k], float(np.max(abs(run.frames["tip0"][i, :2] - exact[j]))))
        ops = model.module.EQUATIONS.CONSTRAINED_OPERATIONS
        print(f"N = {n:>2}: {2 * n + 1} speeds, {2 * n} rows, {result.operations['dynamics']} operations; build "
              f"{total:.1f} s, CPU {cpu:.1f} s (derive {t.get('derive', 0):.1f}, generate {t.get('generate', 0):.1f}, "
              f"cc {t.get('cc', 0):.1f}, compile {t.get('compile', 0):.1f}); solve operations {ops}", flush=True)
        for k in variants:
            ratio = f", {k}/dense {_spread(_ratios(walls, k, 'dense'))}" if k != "dense" else ""
            print(f"    {k:>6}{' (chosen)' if k == next(iter(variants)) else '':9}: {_spread(walls[k])} us per step"
                  f"{ratio}; B0 error {worst[k]:.1e} m", flush=True)


@njit(cache=False)
def _dense_loop(M0, b0, M, b, n, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(n):              # (element by element: a slice assignment slows the kernels after it)
            for j in range(n):
                M[i, j] = M0[i, j]
            b[i] = b0[i]
        cholesky(M, n, 0.0)
        solve_lower(M, b, n)
        solve_upper(M, b, n)
        acc += b[0]
    return acc


@njit(cache=False)
def _tree_loop(M0, b0, M, b, parent, order, n, reps):
    acc = 0.0
    for _ in range(reps):
        for i in range(n):              # (element by element: a slice assignment slows the kernels after it)
            for j in range(n):
                M[i, j] = M0[i, j]
            b[i] = b0[i]
        ltdl(M, parent, order, n, 0.0)
        ltdl_solve(M, parent, order, b, n)
        acc += b[0]
    return acc


def _limbs(base: int, limbs) -> list:
    """Parents of a floating base's `base` speeds (a chain) with limbs of the given lengths on its last."""
    parent = list(range(-1, base - 1))
    for length in limbs:
        start = len(parent)
        parent += [base - 1] + list(range(start, start + length - 1))
    return parent


KERNEL_TREES = {**{f"chain {n}": list(range(-1, n - 1)) for n in (2, 3, 4, 8, 16, 32)},
                "quadruped 6 + 4 x 3": _limbs(6, [3, 3, 3, 3]), "humanoid 6 + 3 + 2 x 6 + 2 x 7": _limbs(6, [3, 6, 6, 7, 7])}


def kernel_section(rounds: int) -> None:
    """What formulation.LTDL_GAIN rests on: factor + solve of M dv/dt = G alone, dense against the tree's, on
    random matrices of each tree's pattern (the copy of M into the scratch included in both)."""
    section("factor + solve alone: dense Cholesky against the tree's LTDL (andyc/symbolic/formulation.py)")
    rng = np.random.default_rng(0)
    for name, parent in KERNEL_TREES.items():
        n = len(parent)
        L = np.eye(n)
        for k in range(n):
            j = parent[k]
            while j >= 0:
                L[k, j] = rng.uniform(-1, 1)
                j = parent[j]
        M0, b0 = L.T @ np.diag(rng.uniform(0.5, 2.0, n)) @ L, rng.normal(size=n)
        tree, order = (np.array(a, dtype=np.int64) for a in tree_of([set(np.flatnonzero(M0[i])) - {i}
                                                                     for i in range(n)]))
        M, b = M0.copy(), b0.copy()
        reps = 200_000 if n < 10 else 20_000
        timers = {"dense": lambda r: _dense_loop(M0, b0, M, b, n, r),
                  "ltdl": lambda r: _tree_loop(M0, b0, M, b, tree, order, n, r)}
        times = compare({k: (lambda f: lambda r: _per_call(lambda: f(reps), 1) / reps)(f) for k, f in timers.items()},
                        rounds, 1)
        ops = ltdl_operations(list(tree)) / dense_operations(n)
        print(f"{name:>32}: operations ltdl/dense {ops:.2f}; time ltdl/dense {_spread(_ratios(times, 'ltdl', 'dense'))}"
              f" (dense {_spread(times['dense'])} us)", flush=True)


def main(argv=None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--large", action="store_true", help="also the large sizes (minutes of Numba compile)")
    parser.add_argument("--chain", type=int, nargs="*", help="chain sizes (default 2 4 8 16)")
    parser.add_argument("--fourbar", type=int, nargs="*", help="N-four-bar sizes (default 1 2 5)")
    parser.add_argument("--robot", choices=tuple(ROBOTS), nargs="*", help="URDF robots (default solo12)")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--no-kernels", action="store_true", help="skip the factor + solve comparison")
    parser.add_argument("--cpp", action="store_true", help="also the robots against Pinocchio's C++ aba "
                        "(bench/pinocchio_cpp.py: compiles bench/pinocchio_aba.cpp once)")
    args = parser.parse_args(argv)
    large = args.large
    chains = args.chain if args.chain is not None else CHAINS + (CHAINS_LARGE if large else ())
    fourbars = args.fourbar if args.fourbar is not None else FOURBARS + (FOURBARS_LARGE if large else ())
    robots = (args.robot if args.robot is not None else ("ur5", "panda", "solo12", "g1", "talos_full") if large
              else ("ur5", "panda", "solo12"))
    run(chains, robots, fourbars, args.rounds, not args.no_kernels, args.cpp)


def run(chains=CHAINS, robots=("ur5", "panda", "solo12"), fourbars=FOURBARS, rounds: int = 5,
        kernels: bool = True, cpp: bool = False) -> None:
    if kernels:
        kernel_section(rounds)
    with tempfile.TemporaryDirectory() as tmpdir:
        tmp = Path(tmpdir)
        if chains:
            chain_section(tmp, chains, rounds)
        if robots:
            robot_section(tmp, robots, rounds, cpp)
        if fourbars:
            fourbar_section(tmp, fourbars, rounds)


if __name__ == "__main__":
    main()
