"""andyc benchmarks: build time per stage, generated-code speed, and SymPy's
KanesMethod on the same chain. Prints figures; run with `make bench`.

Targets (issue 2): derivation at least 5x faster than KanesMethod at 6 bodies,
operation count after cse no larger than KanesMethod's after cse, at least
1e6 RK4 steps/s for a 2-body chain. Issue 3: the swing bar builds (derive +
generate + compile) in under 10 s and runs at least 1e6 RK4 steps/s, 40x
ANDY's 2.4e4 steps/s. Issue 4: for the ball in a bowl, each constrained
method at several steps against a DOP853 reference (rtol 1e-12), with
residuals, energy drift, right-hand-side evaluations and wall time; the
Fig. 2-style comparison is drawn into docs/ball_in_bowl_methods.png. Issue 5:
the passive walker's RK4 steps per second with its jumps (target 5e5; ANDY
ran jump and flow evaluation at 1.7e4), and the bouncing ball's run to its
Zeno point. Issue 6: a 7-DOF arm URDF (panda, fingers locked): build time
(target < 15 s) and forward dynamics per evaluation against pin.aba (target:
within 2x). Issue 7: work-precision diagrams, stability maps (steps, and Baumgarte
gains) and animations of the swing bar, the ball in a bowl, the four-bar and
the walker (bench/accuracy.py), written with the printed figures of every
other section into docs/BENCHMARKS.md and docs/bench/. Every ratio is
measured in this one run.

    python bench/run.py                      all sections (about 10 minutes)
    python bench/run.py --only accuracy      one section: chains, models, swing_bar, constraints, hybrid,
                                             contacts, cycles, urdf, large, accuracy (docs/BENCHMARKS.md then holds
                                             only what ran)
    python bench/large.py --large            issue 27's large sizes (chain n = 32, g1, N-four-bar N = 10)
"""

from __future__ import annotations

import argparse
import multiprocessing
import shutil
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
from numba import njit

import andyc
from andyc.independent.chains import chain_yaml, random_chain
from andyc.independent.closed_forms import ball_first_integral
from andyc.independent.kane import kane_model
from andyc.independent.robots import robots_dir
from andyc.runtime.compiled import work

ROOT = Path(__file__).resolve().parents[1]


def _rhs_loop(model):
    """loop(n, m, w, x, u, p, d, xdot): n right-hand-side evaluations at slowly moving states (so nothing is
    hoisted), the arrays borrowed as the integrator passes them (andyc_numerics/model.py)."""
    rhs_mode_into, borrowed = model.numerics.dynamics.rhs_mode_into, model.numerics.model.borrowed

    @njit(cache=False)
    def loop(n, m, w, x, u, p, d, xdot):
        x, u, p, d, xdot = borrowed(x), borrowed(u), borrowed(p), borrowed(d), borrowed(xdot)
        acc = 0.0
        for i in range(n):
            x[0] += 1e-12
            rhs_mode_into(m, w, 0.0, x, u, p, d, 0, xdot, 0)
            acc += xdot[-1]
        return acc

    return loop


def _rhs_arguments(model):
    """(m, w, x, u, p, d, xdot): the compiled model, a fresh Work, the initial state and defaults, for the
    right-hand side (and the Work, which must outlive them)."""
    p, u = model.parameter_defaults, model.input_defaults
    w = work(model)
    return (model.ref, w.ref, model.initial_state(p).copy(), u, p, model.initial_discrete(p), w.xdot), w


def rhs_microseconds(model, repeats=3, n=200_000) -> float:
    """Best of `repeats`: microseconds per right-hand side (rhs_mode_into, IDEAL) inside a compiled loop."""
    args, _ = _rhs_arguments(model)
    loop = _rhs_loop(model)
    loop(10, *args)
    best = np.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        loop(n, *args)
        best = min(best, time.perf_counter() - tic)
    return 1e6 * best / n


def rk4_steps_per_second(model, t_end=20.0, dt=1e-3, repeats=3) -> float:
    andyc.simulate(model, 10 * dt, dt=dt, progress=False)       # compile the loop outside the timing
    best = min(andyc.simulate(model, t_end, dt=dt, every=1000, progress=False).stats["wall_seconds"]
               for _ in range(repeats))
    return (t_end / dt) / best


STARTED = time.perf_counter()


def section(title):
    print(f"\n== {title} " + "=" * max(0, 70 - len(title)) + f" (at {(time.perf_counter() - STARTED) / 60:.1f} min)")


def _chain(n_bodies: int):
    return random_chain(n_bodies, "3d", "axis", seed=2026)


def kane_chains(max_bodies: int) -> dict:
    """bodies -> (KanesMethod's derivation seconds, its operations after cse), chains of 1 .. max_bodies."""
    out = {}
    for n in range(1, max_bodies + 1):
        kane = kane_model(_chain(n))
        out[n] = (kane.derive_seconds + kane.setup_seconds, kane.ops_after_cse)
    return out


def chain_benchmark(n_bodies: int, tmp: Path, run: bool = False):
    """Derivation time and operation count of a random 3-D chain; with run, Numba-compiled too."""
    path = tmp / f"chain{n_bodies}.yaml"
    path.write_text(chain_yaml(_chain(n_bodies)))
    if run:
        model, result = andyc.compile_model(path, tmp / "build", force=True)
    else:
        model, result = None, andyc.build(path, tmp / "build", force=True)
    return {"bodies": n_bodies, **{k: result.timings.get(k) for k in ("derive", "generate", "compile")},
            "ops": result.operations["dynamics"], "model": model}


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
        fix = andyc.Projection(normalize=normalize)
        andyc.simulate(model, 0.01, dt=1e-3, projection=fix, progress=False)
        best = min(andyc.simulate(model, 30.0, dt=1e-3, every=1000, projection=fix, progress=False)
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
        run = andyc.simulate(model, 10.0, dt=1e-3, frames=frames, every=100,
                             projection=andyc.Projection(normalize=normalize), progress=False)
        drift = np.max(abs(np.linalg.norm(run.state[:, quat], axis=1) - 1))
        err = max(np.max(abs(run.frames[f] - ref.frames[f])) for f in frames)
        label = "renormalize each step" if normalize else "no renormalization  "
        print(f"  {label}: max | |quat| - 1 | = {drift:.2e}, max bar-end error = {err:.2e} m")
    drift = np.max(abs(np.linalg.norm(ref.state[:, quat], axis=1) - 1))
    print(f"  DOP853 (never renormalized):  max | |quat| - 1 | = {drift:.2e}")


def chains_benchmark(tmp: Path, max_bodies: int, kane: dict) -> None:
    """andyc's derivations against `kane` (kane_chains, run in a second process meanwhile)."""
    section("3-D serial chains: andyc against sympy.physics.mechanics.KanesMethod")
    print("derive = kinematics + equations of motion (andyc: recursive, eq. 1-8; Kane: frames, points,")
    print("velocities + KanesMethod.kanes_equations); ops = sympy count_ops of M and G after cse.")
    print("(KanesMethod ran in a second process, one chain after another, while the sections above ran;")
    print("andyc's derivations run here, after them.)")
    header = (f"{'bodies':>6} {'andyc derive s':>14} {'Kane derive s':>13} {'speed-up':>8} "
              f"{'andyc ops':>9} {'Kane ops':>9} {'ops ratio':>9}")
    print(header)
    rows = []
    for n in range(1, max_bodies + 1):
        row = chain_benchmark(n, tmp, run=n == max_bodies)
        row["kane_derive"], row["kane_ops"] = kane[n]
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


BALL_METHODS = {"lagrange": {"method": "lagrange"}, "baumgarte": {"method": "baumgarte"},
                "projection": {"method": "projection", "projection": andyc.Projection(energy_correction=False)},
                "projection+energy": {"method": "projection",
                                      "projection": andyc.Projection(energy_correction=True)}}


def constraints_benchmark(tmp: Path) -> None:
    section("ball in a bowl (Braun & Goldfarb Part II, 3.1): constrained methods, 100 s")
    model, _ = andyc.compile_model(ROOT / "models" / "ball_in_bowl.yaml", tmp / "build")
    p = dict(zip(model.parameter_names, model.parameter_defaults))
    t_end, every = 100.0, 0.1
    ref = andyc.simulate(model, t_end, dt=every, method="DOP853", rtol=1e-12, atol=1e-12, frames=["c"],
                         progress=False)
    print(f"reference: DOP853, rtol = atol = 1e-12, {ref.stats['rhs_evaluations']} rhs evaluations, "
          f"{ref.stats['wall_seconds']:.2f} s; error = max |centre - reference centre| over the samples every {every} s")
    print("residuals: largest |holonomic| and |velocity-level| rows; energy: max |E/E0 - 1|; "
          "first integral: max change (exact: 0);\nrhs evals: 4 per RK4 step (projection adds one M and two "
          "constraint evaluations per step, counted in 'proj')")
    print(f"{'method':>18} {'dt':>6} {'error m':>9} {'holonomic':>9} {'velocity':>9} {'energy':>9} "
          f"{'1st int.':>9} {'rhs evals':>9} {'proj':>6} {'wall s':>7}")
    shown = {}
    for label, options in BALL_METHODS.items():
        andyc.simulate(model, 0.02, dt=0.01, progress=False, **options)       # compile outside the timing
        for dt in (0.05, 0.02, 0.01, 0.005):
            run = andyc.simulate(model, t_end, dt=dt, every=int(round(every / dt)), frames=["c"], progress=False,
                                 **options)
            if dt == 0.01:
                shown[label] = run
            n = run.time.shape[0]
            err = np.max(np.linalg.norm(run.frames["c"] - ref.frames["c"][:n], axis=1))
            eps = ball_first_integral(run, p["r"], p["R"])
            status = "" if run.finished else f"  {run.status}"
            print(f"{label:>18} {dt:>6g} {err:>9.2e} {np.abs(run.residual_position).max():>9.1e} "
                  f"{np.abs(run.residual_velocity).max():>9.1e} {np.abs(run.energy / run.energy[0] - 1).max():>9.1e} "
                  f"{np.abs(eps - eps[0]).max():>9.1e} {run.stats['rhs_evaluations']:>9} {run.stats['projections']:>6} "
                  f"{run.stats['wall_seconds']:>7.3f}{status}", flush=True)
    plot_ball_methods(shown, ref, p, ROOT / "docs" / "ball_in_bowl_methods.png")

    section("parallelogram four-bar through its flat, singular pose: 20 s at dt = 1e-3 s")
    model, _ = andyc.compile_model(ROOT / "models" / "fourbar.yaml", tmp / "build")
    print(f"{'method':>12} {'reached t':>9} {'holonomic':>9} {'velocity':>9} {'energy':>9} {'coupler':>9}  status")
    for label, options in (("lagrange", {"method": "lagrange"}), ("baumgarte", {"method": "baumgarte"}),
                           ("projection", {"method": "projection"}),
                           ("DOP853", {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10})):
        run = andyc.simulate(model, 20.0, dt=1e-3, progress=False, **options)
        coupler = np.abs(run.column("th1") + run.column("th2")).max()     # 0 on the parallelogram branch
        print(f"{label:>12} {run.time[-1]:>9.3f} {np.abs(run.residual_position).max():>9.1e} "
              f"{np.abs(run.residual_velocity).max():>9.1e} {np.abs(run.energy / run.energy[0] - 1).max():>9.1e} "
              f"{coupler:>9.1e}  {run.status}", flush=True)
    print("coupler: largest |th1 + th2|, the coupler's angle (0 on the parallelogram branch, rad)")


def plot_ball_methods(runs: dict, ref, p: dict, path: Path) -> None:
    """Error, no-slip residual, energy error and first-integral error against time, one line per method.

    (cf. Braun & Goldfarb Part II, Fig. 2; the holonomic row rho = R - r holds exactly for
    every method here, since rho is a coordinate and its row is linear.)
    """
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(11, 7), sharex=True)
    panels = [("centre error against DOP853 (rtol 1e-12), m",
               lambda r: np.linalg.norm(r.frames["c"] - ref.frames["c"][:r.time.shape[0]], axis=1)),
              ("nonholonomic residual (no slip)", lambda r: np.abs(r.residual_velocity[:, 1:]).max(axis=1)),
              ("energy error |E/E0 - 1|", lambda r: np.abs(r.energy / r.energy[0] - 1)),
              ("first-integral error", lambda r: np.abs(ball_first_integral(r, p["r"], p["R"])
                                                        - ball_first_integral(r, p["r"], p["R"])[0]))]
    for ax, (title, value) in zip(axes.flat, panels):
        for label, run in runs.items():
            ax.semilogy(run.time, np.maximum(value(run), 1e-17), label=label, lw=1)
        ax.set_title(title, fontsize=10)
        ax.grid(True, which="major", alpha=0.3)
    for ax in axes[1]:
        ax.set_xlabel("t (s)")
    axes[0, 0].legend(fontsize=8)
    fig.suptitle("Ball in a bowl, RK4 at dt = 0.01 s (floor 1e-17 = exact)")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"wrote {path.relative_to(ROOT)}")


ANDY_WALKER_STEPS_PER_SECOND = 1.7e4     # ANDY paper section 3.2: jump + flow evaluation


def hybrid_benchmark(tmp: Path) -> None:
    section("hybrid: passive walker (ANDY section 3.2) and bouncing ball")
    model, result = andyc.compile_model(ROOT / "models" / "passive_walker.yaml", tmp / "hybrid_build", force=True)
    t = result.timings
    print(f"passive walker build: derive {t['derive']:.2f} s, generate {t['generate']:.2f} s, compile "
          f"{t['compile']:.2f} s")
    print(f"right-hand side (flow 1, 3 constraint rows): {rhs_microseconds(model):.3f} us per evaluation")
    print("20 heel strikes (about 12.2 s at dt = 1e-3 s, 60 jumps); steps/s counts every RK4 step, the")
    print("trial steps of event location included; best of 10 (this machine's speed varies between runs):")
    for method in ("rk4", "projection", "lagrange"):
        andyc.simulate(model, 0.5, dt=1e-3, method=method, progress=False)
        runs = [andyc.simulate(model, 30.0, dt=1e-3, method=method, every=1000, progress=False,
                               events=andyc.Events(stop_after={"strike_inner_foot": 10})) for _ in range(10)]
        best = min(runs, key=lambda r: r.stats["wall_seconds"])
        s = best.stats
        steps = s["steps"] + s["event_trial_steps"]
        sps = steps / s["wall_seconds"]
        print(f"  {method:<10} {s['jumps']} jumps, {s['steps']} steps + {s['event_trial_steps']} trial steps in "
              f"{s['wall_seconds'] * 1e3:.1f} ms: {sps:.3g} steps/s = {sps / ANDY_WALKER_STEPS_PER_SECOND:.1f}x "
              f"ANDY's 1.7e4 (target >= 5e5)")
    model, _ = andyc.compile_model(ROOT / "models" / "bouncing_ball.yaml", tmp / "hybrid_build")
    andyc.simulate(model, 0.5, dt=1e-3, progress=False)
    run = andyc.simulate(model, 10.0, dt=1e-3, progress=False)
    t_inf = np.sqrt(2 / 9.81) * (1 + 2 * 0.8 / 0.2)
    print(f"bouncing ball, rk4 dt = 1e-3 s: {run.stats['jumps']} bounces, stopped {t_inf - run.time[-1]:.2e} s "
          f"before t_inf = {t_inf:.9f} s in {run.stats['wall_seconds'] * 1e3:.1f} ms: {run.status[:60]}...")


def _pin_microseconds(model, data, q, v, tau, n=100_000, repeats=3) -> float:
    """Best of `repeats`: microseconds per pin.aba call from Python."""
    import pinocchio as pin
    pin.aba(model, data, q, v, tau)
    best = np.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        for _ in range(n):
            pin.aba(model, data, q, v, tau)
        best = min(best, time.perf_counter() - tic)
    return 1e6 * best / n


def _python_call_microseconds(model, n=100_000, repeats=3) -> float:
    """Best of `repeats`: microseconds per right-hand side called from Python (Numba's dispatch included)."""
    (m, w, x, u, p, d, xdot), _ = _rhs_arguments(model)
    f = model.numerics.dynamics.rhs_mode_into
    best = np.inf
    for _ in range(repeats):
        tic = time.perf_counter()
        for _ in range(n):
            f(m, w, 0.0, x, u, p, d, 0, xdot, 0)
        best = min(best, time.perf_counter() - tic)
    return 1e6 * best / n


def urdf_benchmark(tmp: Path) -> None:
    """Issue 6: a 7-DOF arm from a URDF against Pinocchio's aba."""
    section("7-DOF arm from a URDF (panda, fingers locked): build time, forward dynamics against Pinocchio")
    try:
        import pinocchio as pin
        urdf = robots_dir() / "panda_description/urdf/panda.urdf"
    except ImportError as exc:                  # PackageNotFoundError is an ImportError too
        print(f"skipped: {exc} (both come with pip install -e '.[test]')")
        return
    source = tmp / "panda_arm.yaml"
    source.write_text(f"name: panda_arm\nurdf:\n  file: {urdf}\n  lock: {{panda_finger_joint1: 0.02}}\n")
    model, result = andyc.compile_model(source, tmp / "urdf_build", force=True)    # a fresh folder: no Numba cache
    t = result.timings
    total = t["derive"] + t["generate"] + t["compile"]
    print(f"build: derive {t['derive']:.2f} s, generate {t['generate']:.2f} s, compile {t['compile']:.2f} s "
          f"(total {total:.2f} s, target < 15 s); {result.operations['dynamics']} operations in dynamics")

    full = pin.buildModelFromUrdf(str(urdf))
    fingers = [full.getJointId(f"panda_finger_joint{i}") for i in (1, 2)]
    q_lock = pin.neutral(full)
    for j in fingers:
        q_lock[full.joints[j].idx_q] = 0.02
    arm = pin.buildReducedModel(full, fingers, q_lock)
    data = arm.createData()
    rng = np.random.default_rng(6)
    worst = 0.0
    for _ in range(20):                    # the two compute the same thing (Pinocchio: no joint damping)
        x = rng.uniform(-1, 1, model.nx)
        a = pin.aba(arm, data, x[:7], x[7:], -arm.damping * x[7:])
        worst = max(worst, np.abs(model.module.rhs(0.0, x)[7:] - a).max() / np.abs(a).max())
    print(f"andyc rhs = pin.aba at 20 random states: largest relative difference {worst:.1e}")

    x = rng.uniform(-1, 1, model.nx)
    q, v, tau = x[:7].copy(), x[7:].copy(), np.zeros(7)
    loop = rhs_microseconds(model)
    called = _python_call_microseconds(model)
    pin_us = _pin_microseconds(arm, data, q, v, tau)
    one = pin.Model()                      # the binding's cost: aba on one joint, called the same way
    one.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "j")
    one.appendBodyToJoint(1, pin.Inertia.FromSphere(1.0, 0.1), pin.SE3.Identity())
    overhead = _pin_microseconds(one, one.createData(), np.zeros(1), np.zeros(1), np.zeros(1))
    print("forward dynamics per evaluation (best of 3):")
    print(f"  andyc generated code, inside a compiled loop:  {loop:.3f} us")
    print(f"  andyc generated code, each call from Python:   {called:.3f} us (Numba's dispatch included)")
    print(f"  pin.aba, each call from Python:                {pin_us:.3f} us")
    print(f"  pin.aba on a 1-joint model from Python:        {overhead:.3f} us (the binding's cost, at most)")
    print(f"ratio andyc / Pinocchio (target <= 2): {loop / pin_us:.2f} compiled loop against pin.aba from Python, "
          f"{called / pin_us:.2f} both from Python, {loop / (pin_us - overhead):.2f} compiled loop against "
          "pin.aba less the 1-joint call")


SECTIONS = ("chains", "models", "swing_bar", "constraints", "hybrid", "contacts", "cycles", "urdf", "large", "accuracy")


class Tee:
    """Standard output that is also kept, for docs/BENCHMARKS.md."""

    def __init__(self, stream):
        self.stream, self.parts = stream, []

    def write(self, text):
        self.parts.append(text)
        return self.stream.write(text)

    def flush(self):
        self.stream.flush()

    def text(self) -> str:
        return "".join(self.parts)


def accuracy_benchmark(tmp: Path) -> tuple:
    """Issue 7: work-precision, stability maps and animations of four models, into docs/bench/."""
    from accuracy import ANIMATIONS, CASES, animate, run_case

    section("accuracy against cost: swing bar, ball in a bowl, four-bar, passive walker -> docs/bench/")
    figures = ROOT / "docs" / "bench"
    shutil.rmtree(figures, ignore_errors=True)         # nothing stale from an earlier run
    figures.mkdir(parents=True)
    results = [run_case(case, tmp / "accuracy_build", figures) for case in CASES]
    animations = {}
    for name in ANIMATIONS:
        tic = time.perf_counter()
        animations[name] = animate(name, tmp / "accuracy_build", figures).relative_to(figures.parent)
        print(f"  {name}: animation {animations[name]} ({time.perf_counter() - tic:.0f} s)", flush=True)
    return results, animations


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--max-bodies", type=int, default=6)
    parser.add_argument("--only", choices=SECTIONS, action="append", help="run only this section (repeatable)")
    args = parser.parse_args(argv)
    only = set(args.only or SECTIONS)
    started, accuracy = STARTED, None
    tee = Tee(sys.stdout)
    sys.stdout = tee
    try:
        print(f"andyc {andyc.__version__}, Python {sys.version.split()[0]}")
        # KanesMethod takes minutes on the 6-body chain: it derives in a second process (a second core)
        # while the other sections run, and its table is printed last, once it is done.
        pool = ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn"))
        kane = pool.submit(kane_chains, args.max_bodies) if "chains" in only else None
        with pool, tempfile.TemporaryDirectory() as tmpdir:
            tmp = Path(tmpdir)
            if "models" in only:
                models_benchmark(tmp)
            if "swing_bar" in only:
                swing_bar_benchmark(tmp)
            if "constraints" in only:
                constraints_benchmark(tmp)
            if "hybrid" in only:
                hybrid_benchmark(tmp)
            if "contacts" in only:
                from contacts import contacts_benchmark

                section("contacts (issue 21): resting ball, rocking block, rod on two supports, hopper, friction")
                contacts_benchmark(tmp)
            if "cycles" in only:
                from cycles import cycles_benchmark

                section("cycles (issue 22): one Newton step of andyc cycle on the walkers, exact Jacobian against "
                        "finite differences")
                cycles_benchmark(tmp)
            if "urdf" in only:
                urdf_benchmark(tmp)
            if "large" in only:             # issue 27; its large sizes: python bench/large.py --large
                import large

                large.run(cpp=True)     # with Pinocchio's C++ aba when g++ and Eigen are here (pinocchio_cpp.py)
            accuracy = accuracy_benchmark(tmp) if "accuracy" in only else None
            if kane is not None:
                chains_benchmark(tmp, args.max_bodies, kane.result())
        print(f"\nmake bench: {(time.perf_counter() - started) / 60:.1f} min")
    finally:
        sys.stdout = tee.stream
    if accuracy:
        from accuracy import write_markdown
        write_markdown(*accuracy, tee.text(), time.perf_counter() - started, ROOT / "docs" / "BENCHMARKS.md")
        print("wrote docs/BENCHMARKS.md")


if __name__ == "__main__":
    main()
