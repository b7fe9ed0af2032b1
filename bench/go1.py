"""Go1 side by side with MuJoCo, in one process (issue 38 item 4): steps/s of andyc's time-stepping (moreau) and
event-driven (rk4, projection) methods against mj_step on the same robot, standing and trotting, at dt = 1e-3 and
2e-3 (MuJoCo's default), in interleaved rounds; beside the speed, each engine's penetration, Coulomb violation
and base-height drift; and how the time-stepping's step grows with contacts (N boxes on the ground).

The robots: andyc's models/go1.yaml (example-robot-data's URDF on a floating base, the four foot spheres colliding
with the ground, mu 0.8, exact Coulomb disks; the 12 joints' limits as stops, 24 more contacts, never touched here;
the PD as the model's input expressions, compiled; `trot = 1` trots) and MuJoCo's Go1 of bench/mujoco_go1.py
(MJCF from Pinocchio's model of the same URDF: the same masses to the bit, the four foot spheres on a plane, mu 0.8,
MuJoCo's defaults otherwise: soft contacts, solref 0.02 1; the same PD, clamp and trot). MuJoCo's elliptic cone
is andyc's friction law (the disk |f_t| <= mu f_n); its default, pyramidal, is shown beside it.

What is timed, each from the same settled state in every round (1 s of standing, or of trotting, by the engine
itself), each variant once per round, rounds interleaved (the machine is shared: min .. max over the rounds, and
the ratios within a round):

    andyc moreau      the build's compiled stepping loop itself (timestepping.advance, as andyc.runtime.timestepping
                      run_moreau calls it) over 1 s, logging once at the end: no Python, no logging, no compilation
    andyc rk4 / projection   andyc.simulate from the settled state (x0, d0), one sample at the end; its
                      stats['wall_seconds'] (the compiled loop in chunks, no compilation); the contacts closed,
                      their liftoff and slip guards watched, impacts located (none while standing)
    MuJoCo c_pd       position actuators (the same PD computed in C), mj_step(m, d, nstep): no Python in the loop;
                      andyc's PD is its input expressions compiled, so this is the fair comparison
    MuJoCo python_pd  motor actuators, the PD in Python before each mj_step (bench/mujoco_go1.py's own loop)
    trot              andyc moreau with trot = 1 (its references compiled); MuJoCo position actuators with ctrl set
                      to the trot's reference from Python before each mj_step (c_ref), and the PD in Python
                      (python_pd)

    python bench/go1.py                         everything (a few minutes once Go1 is built; its first build takes
                                                about 6 minutes on a loaded 2-core machine)
    python bench/go1.py --only speed --rounds 9
    python bench/go1.py --only accuracy|speed|friction|scaling
"""

from __future__ import annotations

import argparse
import gc
import math
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import andyc
from andyc.runtime.compiled import compile_integrator, work
from andyc.runtime.contact_modes import initial_mode
from andyc.runtime.initial import initial_state
from andyc.runtime.inputs import input_source, inputs_at
from andyc.runtime.work import with_work

sys.path.insert(0, str(Path(__file__).resolve().parent))
import mujoco_go1 as mj  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
FEET = ("FL_foot", "FR_foot", "RL_foot", "RR_foot")
MU = 0.8
CONES = ("elliptic", "pyramidal")


# ------------------------------------------------------------------------------------------- andyc's loop

class Moreau:
    """andyc's compiled Moreau-Jean loop on a CompiledModel, called as run_moreau calls it (scratch, warm start,
    the inputs' callbacks), without its chunks, progress or logging: steps(n) times n steps in one call of the
    build's timestepping.advance (logging every 10^12-th step: never). snapshot() / restore() put back the state,
    the contacts' modes and the solver's warm start, so that every round starts alike."""

    def __init__(self, model, dt: float, parameters: dict | None = None, theta: float = 0.5):
        self.model, self.dt, self.theta = model, dt, theta
        p = model.parameters(parameters)
        self.source = input_source(model, p, None, None, 1.0)
        x, d, flow = initial_state(model, p)
        compile_integrator(model, method="moreau", frames=False)
        compile_integrator(model, *self.source.function_data, method="moreau")
        u = inputs_at(model, self.source, 0.0, x, p, d, flow)
        initial_mode(model, 0.0, x, u, p, d, flow)
        self.p, self.flow, self.x, self.d = p, flow, with_work(model, x), d
        self.w = work(model)
        stepping = model.stepping
        self.s = model.stepping_scratch()
        stepping.coefficients(model.ref, self.w.ref, self.s, p)
        self.s.guess[:] = [m if m > 0 else -1 for m in model.contact_states(d)]
        self.w.u[:] = self.source.held(flow)
        self.i = 0
        rows, nu = 2, len(model.input_names)
        self.log = model.numerics.integrator.Log(np.empty(rows), np.empty((rows, self.x.shape[0])),
                                                 np.empty((rows, nu)), np.empty(rows, dtype=np.int64),
                                                 np.empty((rows, model.nd)))
        self.forces = np.zeros((rows, model.nc))

    def steps(self, n: int) -> float:
        """n steps from where the run is; the wall seconds of the compiled call."""
        fn, data = self.source.function_data
        t = self.i * self.dt
        advance = self.model.stepping.advance
        tic = time.perf_counter()
        i, _, status, _ = advance(self.model.ref, self.w.ref, self.s, self.theta, fn, data, self.p, self.d, self.x, t,
                                  self.flow, self.i, self.i + n, 0.0, self.dt, 10 ** 12, self.log, self.forces, 0)
        wall = time.perf_counter() - tic
        if status != 0 or i != self.i + n:
            raise RuntimeError(f"moreau stopped at step {i} with status {status}")
        self.i = i
        return wall

    def snapshot(self):
        return self.x.copy(), self.d.copy(), self.s.guess.copy(), self.s.guess_dir.copy(), self.i

    def restore(self, snap) -> None:
        x, d, guess, direction, i = snap
        self.x[:], self.d[:], self.s.guess[:], self.s.guess_dir[:], self.i = x, d, guess, direction, i

    @property
    def stats(self):
        steps, sweeps, unverified, pushed = (int(v) for v in self.s.stats)
        return {"steps": steps, "sweeps": sweeps, "unverified": unverified, "corrections": pushed}


def go1_model(build: Path):
    """andyc's Go1 (models/go1.yaml), built into `build` (or loaded from it)."""
    model, _ = andyc.compile_model(ROOT / "models" / "go1.yaml", build, integrator=False)
    return model


def _steps(seconds: float, dt: float) -> int:
    return int(round(seconds / dt))


# ----------------------------------------------------------------------------------------------- accuracy

def andyc_figures(model, method: str, dt: float, seconds: float, trot: bool) -> dict:
    """One andyc run from rest in the standing pose, sampled every step (feet and base frames): the figures
    bench/mujoco_go1.py's Record.stats gives for MuJoCo (standing: over t >= 1 s; trotting: the whole run)."""
    run = andyc.simulate(model, seconds, dt=dt, method=method, progress=False, frames=["base", *FEET],
                         parameters={"trot": 1.0 if trot else 0.0})
    if not run.finished:
        return {"status": run.status}
    after = 0.0 if trot else 1.0
    k = run.time >= after - 1e-12
    z = run.frames["base"][k, 2]
    feet = np.stack([run.frames[f] for f in FEET], axis=1)[k]            # (N, 4, 3)
    names = list(run.contact_names)
    cols = [names.index(f"{f}_sphere") for f in FEET]
    fn = run.normal_forces[k][:, cols]
    ft = np.hypot(run.friction_forces[k][:, cols], run.friction_forces_2[k][:, cols])
    ratio = np.where(fn > 0, ft / np.where(fn > 0, MU * fn, 1.0), 0.0)
    late = run.time >= seconds - 5.0 - 1e-12
    mass = 13.100529                                                     # kg (docs/go1.md: the same in both)
    x = run.frames["base"][:, 0]
    return {"status": "finished", "height_mean": float(z.mean()), "height_drift": float(z[-1] - z[0]),
            "drift_last5": float(run.frames["base"][late, 2][-1] - run.frames["base"][late, 2][0]),
            "penetration_max": float(max(0.0, (mj.FOOT_RADIUS - feet[:, :, 2]).max())),
            "cone_ratio_max": float(ratio.max()), "cone_violation": max(0.0, float(ratio.max()) - 1.0),
            "feet_xy_moved": float(np.linalg.norm(feet[:, :, :2] - feet[0, :, :2], axis=2).max()),
            "normal_sum_end": float(fn[-1].sum()), "mg": mass * mj.GRAVITY, "base_z_min": float(z.min()),
            "speed_x": float((x[-1] - x[k][0]) / (run.time[-1] - run.time[k][0])),
            "steps": run.stats.get("steps"), "jumps": run.stats.get("jumps", 0)}


def accuracy(model, dts=(1e-3, 2e-3), seconds: float = 10.0, event_driven=("rk4", "projection")) -> None:
    print(f"\naccuracy: Go1 released at rest in the standing pose, {seconds:g} s (standing: figures over t >= 1 s; "
          "trotting: the whole run); andyc's contacts are rigid (gap >= 0 exactly, Coulomb's disk), MuJoCo's soft "
          "(solref 0.02 1)")
    head = (f"  {'engine':28s} {'dt':>6s} {'trunk z':>9s} {'drift z(10)-z(1)':>17s} {'drift [5,10]':>13s} "
            f"{'max pen.':>10s} {'max |ft|/(mu fn)':>17s} {'beyond 1':>9s} {'feet moved':>11s} {'sum fn / m g':>13s}")
    print("  standing")
    print(head)
    for dt in dts:
        rows = [(f"andyc moreau", andyc_figures(model, "moreau", dt, seconds, False))]
        for method in event_driven:
            rows.append((f"andyc {method}", andyc_figures(model, method, dt, seconds, False)))
        for cone in CONES:
            rows.append((f"MuJoCo {cone}", _mujoco_stand(dt, cone, seconds)))
        for label, s in rows:
            if s.get("status", "finished") != "finished":
                print(f"  {label:28s} {dt:6g}  {s['status']}")
                continue
            print(f"  {label:28s} {dt:6g} {s['height_mean']:9.5f} {s['height_drift']:+17.1e} {s['drift_last5']:+13.1e} "
                  f"{1e3 * s['penetration_max']:7.3f} mm {s['cone_ratio_max']:17.6f} {s['cone_violation']:9.1e} "
                  f"{1e3 * s['feet_xy_moved']:8.3f} mm {s['normal_sum_end'] / s['mg']:13.9f}")
    print("  trotting (trot = 1; MuJoCo: the same reference and PD)")
    print(f"  {'engine':28s} {'dt':>6s} {'speed':>10s} {'min trunk z':>12s} {'max pen.':>10s} {'max |ft|/(mu fn)':>17s} "
          f"{'beyond 1':>9s}")
    for dt in dts:
        rows = [("andyc moreau", andyc_figures(model, "moreau", dt, seconds, True))]
        for method in event_driven:
            rows.append((f"andyc {method}", andyc_figures(model, method, dt, seconds, True)))
        for cone in CONES:
            rows.append((f"MuJoCo {cone}", mj.trot(dt, cone, MU, seconds)))
        for label, s in rows:
            if s.get("status", "finished") != "finished":
                print(f"  {label:28s} {dt:6g}  {_short(s['status'])}")
                continue
            print(f"  {label:28s} {dt:6g} {s['speed_x']:6.3f} m/s {s['base_z_min']:10.4f} m {1e3 * s['penetration_max']:7.3f} mm "
                  f"{s['cone_ratio_max']:17.6f} {s['cone_violation']:9.1e}")
    pose(model)


def _short(status: str, size: int = 400) -> str:
    return status if len(status) <= size else status[:size] + " ..."


def _mujoco_stand(dt: float, cone: str, seconds: float) -> dict:
    s = mj.stand(dt, cone, MU, seconds)
    late = s.pop("last5")
    return {**s, "drift_last5": late["height_drift"]}


def pose(model, dt: float = 1e-3, seconds: float = 10.0) -> None:
    """Both engines' standing pose at t = 10 s, and why they differ."""
    run = andyc.simulate(model, seconds, dt=dt, method="moreau", every=_steps(seconds, dt), progress=False)
    x, names = run.state[-1], model.state_names
    joints = np.array([x[names.index(n)] for n in mj.JOINTS])
    base = np.array([x[names.index(f"base_{c}")] for c in ("x", "y", "z")])
    print(f"\n  the pose at t = {seconds:g} s (dt {dt:g}), andyc moreau against MuJoCo (position actuators), by "
          "MuJoCo's contact stiffness:")
    print(f"    andyc: trunk at ({base[0]:+.5f}, {base[1]:+.5f}, {base[2]:.5f}) m; hips {_hips(joints)} rad")
    import mujoco
    for cone in CONES:
        for solref in (None, (0.005, 1), (0.002, 1)):
            m = mj.model(dt, cone, MU, actuators="position", solref=solref)
            d = mj.standing_data(m)
            mujoco.mj_step(m, d, nstep=_steps(seconds, dt))
            other = np.abs(np.delete(d.qpos[7:] - joints, [0, 3, 6, 9])).max()
            print(f"    MuJoCo {cone:9s} solref {solref[0] if solref else 0.02:<5g}: trunk z {d.qpos[2]:.5f} m "
                  f"({1e3 * (d.qpos[2] - base[2]):+.2f} mm), x {1e3 * (d.qpos[0] - base[0]):+.2f} mm; hips "
                  f"{_hips(d.qpos[7:])} rad (hip torques {_hips(d.actuator_force, '{:+.2f}')} N m); thighs and calves "
                  f"within {other:.4f} rad of andyc's")


def _hips(q, fmt="{:+.4f}") -> str:
    return " ".join(fmt.format(v) for v in np.asarray(q)[[0, 3, 6, 9]])


# -------------------------------------------------------------------------------------------------- speed

class Variant:
    """A timed variant: run(seconds) -> steps/s from its settled state (restored each round)."""

    def __init__(self, label, run):
        self.label, self.run, self.rates = label, run, []


def _andyc_moreau(model, dt, trot: bool, settle: float) -> Variant:
    h = Moreau(model, dt, {"trot": 1.0 if trot else 0.0})
    h.steps(_steps(settle, dt))
    snap = h.snapshot()

    def run(seconds):
        h.restore(snap)
        n = _steps(seconds, dt)
        return n / h.steps(n)
    v = Variant(f"andyc moreau{' trot' if trot else ''}", run)
    v.runner = h
    return v


def _andyc_event(model, method: str, dt: float, settle: float) -> Variant:
    first = andyc.simulate(model, settle, dt=dt, method=method, every=_steps(settle, dt), progress=False)
    if not first.finished:
        raise RuntimeError(first.status)
    x0, d0 = first.state[-1].copy(), first.discrete[-1].copy()

    def run(seconds):
        r = andyc.simulate(model, seconds, dt=dt, method=method, x0=x0, d0=d0, every=_steps(seconds, dt),
                           progress=False)
        if not r.finished:
            raise RuntimeError(r.status)
        return r.stats["steps"] / r.stats["wall_seconds"]
    return Variant(f"andyc {method}", run)


def _mujoco(dt, cone, kind: str, settle: float, **options) -> Variant:
    """MuJoCo variants from bench/mujoco_go1.py: c_pd (position actuators, nstep), python_pd (motor actuators, PD in
    Python), trot_c_ref (position actuators, the trot's reference set from Python), trot_python_pd."""
    import mujoco
    position = kind in ("c_pd", "trot_c_ref")
    m = mj.model(dt, cone, MU, actuators="position", **options) if position else mj.model(dt, cone, MU, **options)
    pd = None if position else mj.PD(mj.KP, mj.KD)
    gait = mj.Trot()
    trotting = kind.startswith("trot")
    controller = mj.Controller(pd, gait.reference if trotting else mj.STAND)
    d = mj.standing_data(m)
    mj.run(m, d, controller, settle) if settle > 0 else None
    start = (d.qpos.copy(), d.qvel.copy(), d.ctrl.copy(), d.qacc_warmstart.copy(), d.time)

    def run(seconds):
        dd = mujoco.MjData(m)
        dd.qpos[:], dd.qvel[:], dd.ctrl[:], dd.qacc_warmstart[:], dd.time = start
        mujoco.mj_forward(m, dd)
        return mj.steps_per_second(m, dd, None if kind == "c_pd" else controller, seconds)
    return Variant(f"MuJoCo {cone} {kind}", run)


def speed(model, dts=(1e-3, 2e-3), rounds: int = 7, seconds: float = 1.0, settle: float = 1.0,
          event_driven=("rk4", "projection")) -> dict:
    """Steps/s of every variant (module docstring), rounds interleaved; prints min .. max and the ratios of andyc's
    time-stepping over MuJoCo's c_pd within each round. Returns {dt: {label: [steps/s per round]}}."""
    out = {}
    print(f"\nspeed: steps/s over {seconds:g} s simulated from a settled state ({settle:g} s), {rounds} interleaved "
          "rounds, min .. max (ratios within a round)")
    for dt in dts:
        variants = [_andyc_moreau(model, dt, False, settle), _andyc_moreau(model, dt, True, settle)]
        for method in event_driven:
            try:
                variants.append(_andyc_event(model, method, dt, settle))
            except Exception as exc:                                     # noqa: BLE001 - said plainly
                print(f"  dt {dt:g}: andyc {method} does not run: {exc}")
        for cone in CONES:
            variants += [_mujoco(dt, cone, "c_pd", settle), _mujoco(dt, cone, "python_pd", settle)]
        variants += [_mujoco(dt, "elliptic", "trot_c_ref", settle), _mujoco(dt, "elliptic", "trot_python_pd", settle)]
        for v in variants:                                               # (one warm round each)
            v.run(0.1)
        gc.collect()
        for _ in range(rounds):
            for v in variants:
                v.rates.append(v.run(seconds))
        out[dt] = {v.label: v.rates for v in variants}
        print(f"  dt = {dt:g}:")
        for v in variants:
            r = v.rates
            extra = ""
            if hasattr(v, "runner"):
                st = v.runner.stats
                extra = (f"   (over all its steps: {st['sweeps'] / max(st['steps'], 1):.2f} Gauss-Seidel sweeps a step, "
                         f"{st['corrections'] / max(st['steps'], 1):.2f} position corrections a step, "
                         f"{st['unverified']} unverified)")
            print(f"    {v.label:34s} {min(r):>9,.0f} .. {max(r):>9,.0f} steps/s  ({1e6 / max(r):6.2f} .. "
                  f"{1e6 / min(r):6.2f} us/step){extra}")
        ratio = lambda a, b: [x / y for x, y in zip(out[dt][a], out[dt][b])]   # noqa: E731
        for a in ("andyc moreau", "andyc moreau trot"):
            for b in ("MuJoCo elliptic c_pd", "MuJoCo pyramidal c_pd", "MuJoCo elliptic python_pd"):
                if "trot" in a:
                    b = b.replace("c_pd", "trot_c_ref").replace("python_pd", "trot_python_pd")
                    if "pyramidal" in b:
                        continue
                r = ratio(a, b)
                print(f"    {a} / {b}: {min(r):.2f} .. {max(r):.2f}")
    return out


def friction(build: Path, tmp: Path, dt: float = 1e-3, rounds: int = 7, seconds: float = 1.0,
             settle: float = 1.0) -> None:
    """Go1 standing with its URDF's joint friction (0.2 N m on 12 joints): andyc's moreau (models/go1.yaml with
    joint_friction: true: a bounded row a joint) against MuJoCo with the same frictionloss, position actuators;
    steps/s in interleaved rounds, the ratio within each, and what each does to the stance."""
    text = (ROOT / "models" / "go1.yaml").read_text().replace("name: go1\n", "name: go1_joint_friction\n")
    text = text.replace("file: go1/go1.urdf", f"file: {ROOT / 'models' / 'go1' / 'go1.urdf'}")
    source = tmp / "go1_joint_friction.yaml"
    source.write_text(text.replace("joint_friction: false", "joint_friction: true"))
    model, _ = andyc.compile_model(source, build, integrator=False)
    variants = [_andyc_moreau(model, dt, False, settle)]
    variants += [_mujoco(dt, cone, "c_pd", settle, frictionloss=True) for cone in CONES]
    for v in variants:
        v.run(0.1)
    gc.collect()
    for _ in range(rounds):
        for v in variants:
            v.rates.append(v.run(seconds))
    print(f"\njoint friction: Go1 standing with 0.2 N m of dry friction on each joint, dt = {dt:g}, {rounds} "
          f"interleaved rounds of {seconds:g} s from {settle:g} s of settling")
    for v in variants:
        extra = ""
        if hasattr(v, "runner"):
            st = v.runner.stats
            extra = (f"   ({st['sweeps'] / max(st['steps'], 1):.2f} Gauss-Seidel sweeps a step, "
                     f"{st['unverified']} unverified steps)")
        print(f"    {v.label:34s} {min(v.rates):>9,.0f} .. {max(v.rates):>9,.0f} steps/s{extra}")
    for b in variants[1:]:
        r = [x / y for x, y in zip(variants[0].rates, b.rates)]
        print(f"    andyc moreau / {b.label}: {min(r):.2f} .. {max(r):.2f}")
    run = andyc.simulate(model, 3.0, dt=dt, method="moreau", progress=False)
    late = run.time >= 1.0
    z = run.column("base_z")[late]
    speeds = np.array([run.column(n)[late] for n in run.state_names if n.endswith("_joint_dot")])
    print(f"    andyc: base z {z.mean():.5f} m, moving {z.max() - z.min():.1e} m over [1, 3] s; joints below "
          f"{np.abs(speeds).max():.1e} rad/s")


# ------------------------------------------------------------------------------------------ contacts' scale

def boxes_yaml(n: int, mu: float = MU, size=(0.2, 0.2, 0.1), mass: float = 1.0, spacing: float = 0.5) -> str:
    """n boxes (each on its own floating joint, 6 speeds) resting on the ground on their four bottom corners, in
    rows of four, `spacing` apart: 4 n contacts touching (each box's eight corners are contacts: 8 n in all)."""
    lx, ly, lz = size
    inertia = [mass * (ly ** 2 + lz ** 2) / 12, mass * (lx ** 2 + lz ** 2) / 12, mass * (lx ** 2 + ly ** 2) / 12]
    speeds = ", ".join(f"{v}{k}: {{}}" for k in range(n) for v in ("vx", "vy", "vz", "wx", "wy", "wz"))
    lines = [f"name: boxes{n}", f"description: {n} boxes resting on the ground on their four bottom corners each.",
             f"parameters: {{mu: {mu!r}}}", f"speeds: {{{speeds}}}", "gravity: [0, 0, -9.81]",
             "ground: {normal: [0, 0, 1], height: 0}", "frames:"]
    for k in range(n):
        x, y = spacing * (k % 4), spacing * (k // 4)
        lines.append(f"  - name: box{k}\n    parent: world\n    floating: {{speeds: [vx{k}, vy{k}, vz{k}, wx{k}, wy{k}, "
                     f"wz{k}], position: [{x!r}, {y!r}, {lz / 2!r}]}}\n    shape: {{box: {{size: [{lx!r}, {ly!r}, "
                     f"{lz!r}]}}, collide: true, friction: mu}}")
    lines.append("bodies:")
    for k in range(n):
        lines.append(f"  - {{name: b{k}, frame: box{k}, mass: {mass!r}, inertia: [{inertia[0]!r}, {inertia[1]!r}, "
                     f"{inertia[2]!r}]}}")
    return "\n".join(lines) + "\n"


def boxes_mjcf(n: int, dt: float, cone: str, mu: float = MU, size=(0.2, 0.2, 0.1), mass: float = 1.0,
               spacing: float = 0.5) -> str:
    """The same scene in MuJoCo: n free boxes (freejoint, the same mass and inertia) on a plane; boxes collide with
    the floor only (contype 1 conaffinity 0 against the floor's 0 1), condim 3, MuJoCo's defaults otherwise."""
    lx, ly, lz = size
    inertia = [mass * (ly ** 2 + lz ** 2) / 12, mass * (lx ** 2 + lz ** 2) / 12, mass * (lx ** 2 + ly ** 2) / 12]
    bodies = "\n".join(
        f'    <body name="box{k}" pos="{spacing * (k % 4)!r} {spacing * (k // 4)!r} {lz / 2!r}"><freejoint/>'
        f'<inertial pos="0 0 0" mass="{mass!r}" diaginertia="{inertia[0]!r} {inertia[1]!r} {inertia[2]!r}"/>'
        f'<geom type="box" size="{lx / 2!r} {ly / 2!r} {lz / 2!r}" condim="3" friction="{mu!r} 0.005 0.0001" '
        f'contype="1" conaffinity="0"/></body>' for k in range(n))
    return f"""<mujoco model="boxes{n}">
  <compiler inertiafromgeom="false"/>
  <option timestep="{dt!r}" gravity="0 0 {-mj.GRAVITY!r}" cone="{cone}"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" condim="3" friction="{mu!r} 0.005 0.0001" contype="0" conaffinity="1"/>
{bodies}
  </worldbody>
</mujoco>
"""


def scaling(build: Path, tmp: Path, counts=(1, 2, 4, 8), dt: float = 1e-3, rounds: int = 7,
            seconds: float = 1.0) -> None:
    """Steps/s of andyc's time-stepping against mj_step (nstep) on n boxes resting on the ground (4 n contacts),
    rounds interleaved, from the state after 0.5 s of rest; each engine's largest penetration and the number of
    contacts MuJoCo finds."""
    import mujoco
    print(f"\ncontacts' scale: n boxes resting on the ground, 4 n contacts touching, dt = {dt:g}, {rounds} "
          f"interleaved rounds of {seconds:g} s, min .. max (andyc: each box's 8 corners are contacts, its 4 top ones "
          "never in a step's problem; MuJoCo: box-plane contacts, 4 a box)")
    for n in counts:
        path = tmp / f"boxes{n}.yaml"
        path.write_text(boxes_yaml(n))
        tic = time.perf_counter()
        model, result = andyc.compile_model(path, build, integrator=False)
        built = time.perf_counter() - tic
        h = Moreau(model, dt)
        h.steps(_steps(0.5, dt))
        snap = h.snapshot()
        z = [model.state_names.index(f"box{k}_z") for k in range(n)]
        sink = 0.05 - min(h.x[i] for i in z)
        variants = {}

        def andyc_run(s):
            h.restore(snap)
            k = _steps(s, dt)
            return k / h.steps(k)
        variants["andyc moreau"] = andyc_run
        found = {}
        for cone in CONES:
            m = mujoco.MjModel.from_xml_string(boxes_mjcf(n, dt, cone))
            d = mujoco.MjData(m)
            mujoco.mj_step(m, d, nstep=_steps(0.5, dt))
            found[cone] = (d.ncon, 0.05 - min(d.qpos[7 * k + 2] for k in range(n)))
            start = (d.qpos.copy(), d.qvel.copy(), d.qacc_warmstart.copy(), d.time)

            def mujoco_run(s, m=m, start=start):
                dd = mujoco.MjData(m)
                dd.qpos[:], dd.qvel[:], dd.qacc_warmstart[:], dd.time = start
                mujoco.mj_forward(m, dd)
                return mj.steps_per_second(m, dd, None, s)
            variants[f"MuJoCo {cone}"] = mujoco_run
        rates = {k: [] for k in variants}
        for f in variants.values():
            f(0.05)
        for _ in range(rounds):
            for k, f in variants.items():
                rates[k].append(f(seconds))
        cells = ", ".join(f"{k} {min(r):,.0f} .. {max(r):,.0f}" for k, r in rates.items())
        ratio = [a / b for a, b in zip(rates["andyc moreau"], rates["MuJoCo elliptic"])]
        st = h.stats
        print(f"  {n} box{'es' if n > 1 else ''}, {4 * n} contacts ({6 * n} speeds; andyc build {built:.0f} s): {cells} "
              f"steps/s; andyc / MuJoCo elliptic {min(ratio):.2f} .. {max(ratio):.2f}; andyc sinks "
              f"{sink:.1e} m, MuJoCo {found['elliptic'][1] * 1e3:.3f} mm (elliptic, {found['elliptic'][0]} contacts), "
              f"{found['pyramidal'][1] * 1e3:.3f} mm (pyramidal, {found['pyramidal'][0]}); andyc "
              f"{st['sweeps'] / st['steps']:.2f} sweeps a step, {st['unverified']} unverified")


# ---------------------------------------------------------------------------------------------------- main

def machine() -> str:
    load = os.getloadavg() if hasattr(os, "getloadavg") else ("?",) * 3
    import mujoco
    return (f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average "
            f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; MuJoCo {mujoco.__version__}, Python "
            f"{platform.python_version()}, andyc {andyc.__version__}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only", choices=("accuracy", "speed", "friction", "scaling"), action="append")
    ap.add_argument("--rounds", type=int, default=7)
    ap.add_argument("--seconds", type=float, default=1.0, help="simulated seconds per timed round")
    ap.add_argument("--build-dir", default=None, help="where andyc builds Go1 and the boxes (default: a temporary "
                    "folder; pass one to keep the builds between runs)")
    ap.add_argument("--boxes", type=int, nargs="*", default=[1, 2, 4, 8])
    a = ap.parse_args(argv)
    only = set(a.only or ("accuracy", "speed", "friction", "scaling"))
    print("machine:", machine())
    with tempfile.TemporaryDirectory() as tmp:
        build = Path(a.build_dir) if a.build_dir else Path(tmp) / "build"
        tic = time.perf_counter()
        model = go1_model(build)
        print(f"andyc's Go1: {model.nv} speeds, {len(model.contact_names)} contacts (4 feet, 24 joint stops), "
              f"{model.nc} rows; built or loaded in {time.perf_counter() - tic:.0f} s")
        gc.collect()
        gc.freeze()                     # (the builds' objects: no collection walks them while timing)
        if "accuracy" in only:
            accuracy(model)
        if "speed" in only:
            speed(model, rounds=a.rounds, seconds=a.seconds)
        if "friction" in only:
            friction(build, Path(tmp), rounds=a.rounds, seconds=a.seconds)
        if "scaling" in only:
            scaling(build, Path(tmp), tuple(a.boxes), rounds=a.rounds, seconds=a.seconds)


if __name__ == "__main__":
    main()
