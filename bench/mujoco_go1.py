"""Unitree Go1 in MuJoCo: the peer andyc's Go1 (standing, trotting on four frictional feet) is compared with.

The robot is example-robot-data's go1_description/urdf/go1.urdf, the file andyc's model reads.

How the MuJoCo model is made (`mjcf`, `model`): written as MJCF by script from Pinocchio's model of the same
URDF (`pin.buildModelFromUrdf(URDF, pin.JointModelFreeFlyer())`). Pinocchio fuses every fixed link (the rotors,
the IMU, the cameras, the feet) into the body of its moving parent, so the MuJoCo tree has 13 bodies: the trunk
(fused with `base`, the hip rotors, IMU and sensors) on a freejoint, and per leg hip (+ thigh rotor), thigh (+ calf
rotor), calf (+ foot). Each body gets its joint placement, its hinge axis, the URDF `<dynamics damping>`
(0.01 N m s, which andyc's URDF import also keeps as a damper; `damping=False` drops it) and an `<inertial>` with
Pinocchio's mass, COM and full inertia about the COM (`fullinertia`), so MuJoCo derives nothing from geoms.
The URDF's `<dynamics friction>` (dry joint friction, which andyc ignores) and its joint limits (which andyc
ignores too) are left out; `limits=True` adds the limits as MuJoCo joint ranges. MuJoCo's own URDF import is
not used for the model (it cannot read the .dae meshes), only as a second opinion on the masses (`verify`).

Geometry: only contact geometry. A sphere r = 0.02 at each foot frame (`FL_foot` ...; condim 3, friction mu)
and a plane at z = 0 (condim 3, friction mu); the feet have contype 1 conaffinity 0 and the floor contype 0
conaffinity 1, so the only collisions are foot-floor. Everything else is MuJoCo's defaults: Euler integrator
(implicit in joint damping only), solref 0.02 1, solimp 0.9 0.95 0.001, impratio 1, no margin; gravity 9.81.
`actuators="motor"` gives 12 torque motors (ctrl = tau, clamped to the URDF efforts by ctrlrange), driven by a
PD computed in Python each step; `actuators="position"` gives the same PD (kp, kd, the same force clamp) as
MuJoCo position actuators (ctrl = q_ref), computed in C: the same motion without Python in the loop.

Coordinates: qpos = [x y z, qw qx qy qz, 12 joints], qvel = [v (world axes), omega (trunk axes), 12 joint
rates]. The joints come in Pinocchio's order (JOINTS: FL, FR, RL, RR; hip, thigh, calf), so qpos[7:] is
Pinocchio's q[7:] (Pinocchio's quaternion is x y z w; its base linear speed is in the base's axes).

    python bench/mujoco_go1.py                   everything, at dt 1e-3 and 2e-3, both cones
    python bench/mujoco_go1.py --rounds 7 --seconds 2

Use from another module (bench/ on sys.path; the functions build MuJoCo and Pinocchio models on call):

    import mujoco, mujoco_go1 as go1
    m = go1.model(dt=1e-3, cone="pyramidal", mu=0.8)        # MjModel; actuators="position" for the PD in C
    d = go1.standing_data(m)                                # at rest: STAND, trunk level at BASE_HEIGHT
    pd = go1.PD(go1.KP, go1.KD)                             # pd(q, qdot, q_ref) = clip(kp (q_ref - q) - kd qdot)
    stand = go1.Controller(pd, go1.STAND)                   # controller(m, d) sets d.ctrl before mj_step
    trot = go1.Controller(pd, go1.Trot().reference)         # q_ref(t) of the open-loop trot
    rec = go1.run(m, d, trot, 10.0)                         # steps, sampling; rec.stats(after=1.0) -> dict
    go1.stand(dt, cone, mu), go1.trot(dt, cone, mu)          # the runs above, their stats
    go1.steps_per_second(m, d, controller, seconds)         # controller None: mj_step(nstep) in C
    go1.timings(dt, cone, mu, seconds, rounds)              # the variants, rounds interleaved
    go1.verify(m), go1.base_height(q_joints)                # against Pinocchio
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

GRAVITY = 9.81
FOOT_RADIUS = 0.02
LEGS = ("FL", "FR", "RL", "RR")                  # Pinocchio's order of the URDF's joints
PARTS = ("hip", "thigh", "calf")
JOINTS = tuple(f"{leg}_{part}_joint" for leg in LEGS for part in PARTS)
FEET = tuple(f"{leg}_foot" for leg in LEGS)
EFFORT = np.array([23.7, 23.7, 35.55] * 4)       # N m, the URDF's <limit effort>

# The standing pose: every leg hip 0, thigh 0.9, calf -1.8, so each foot is right below its thigh joint
# (x_foot = -0.213 (sin 0.9 + sin(0.9 - 1.8)) = 0). BASE_HEIGHT: the trunk's height (level, identity orientation)
# at which the four foot spheres touch z = 0, from Pinocchio's forward kinematics (base_height()):
# 0.02 + 0.426 cos 0.9.
STAND_LEG = (0.0, 0.9, -1.8)
STAND = np.array(STAND_LEG * 4)
BASE_HEIGHT = 0.28480584648330304

# PD gains, the same for the 12 joints.
KP, KD = 100.0, 2.0


def urdf_path() -> Path:
    try:
        from andyc.independent.robots import robots_dir
        return robots_dir() / "go1_description/urdf/go1.urdf"
    except Exception:                                      # noqa: BLE001 - the venv's copy
        import pinocchio  # noqa: F401
        import sys
        return (Path(sys.prefix) / "lib" / f"python{sys.version_info.major}.{sys.version_info.minor}"
                / "site-packages/cmeel.prefix/share/example-robot-data/robots/go1_description/urdf/go1.urdf")


URDF = urdf_path()


def pinocchio_model():
    """Pinocchio's model of the URDF on a free-flyer root (fixed links fused into their moving parent)."""
    import pinocchio as pin
    return pin.buildModelFromUrdf(str(URDF), pin.JointModelFreeFlyer())


# ----------------------------------------------------------------------------------------------- the model

def _f(x) -> str:
    return " ".join(repr(float(v)) for v in np.ravel(x))


def _quat_wxyz(R) -> np.ndarray:
    import pinocchio as pin
    q = pin.Quaternion(np.asarray(R))
    return np.array([q.w, q.x, q.y, q.z])


def _axis(joint) -> np.ndarray:
    name = joint.shortname()
    if name in ("JointModelRX", "JointModelRY", "JointModelRZ"):
        return np.eye(3)["XYZ".index(name[-1])]
    if name == "JointModelRevoluteUnaligned":
        return np.asarray(joint.axis)
    raise ValueError(f"joint type {name} is not converted")


def mjcf(dt: float = 1e-3, cone: str = "pyramidal", mu: float = 0.8, actuators: str = "motor",
         kp: float = KP, kd: float = KD, damping: bool = True, limits: bool = False, solref=None,
         frictionloss: bool = False) -> str:
    """The MJCF text of Go1 (see the module's docstring). solref (timeconst, dampratio): the contacts' solref
    (on the feet and the floor) instead of MuJoCo's default 0.02 1, e.g. (0.005, 1) for stiffer contacts."""
    if cone not in ("pyramidal", "elliptic"):
        raise ValueError("cone: pyramidal or elliptic")
    pm = pinocchio_model()
    children = {j: [] for j in range(pm.njoints)}
    for j in range(1, pm.njoints):
        children[pm.parents[j]].append(j)
    feet = {f.parentJoint: f for f in pm.frames if f.name in FEET}
    friction = f"{mu!r} 0.005 0.0001"
    if solref is not None:
        friction += f'" solref="{float(solref[0])!r} {float(solref[1])!r}'

    def body(j: int, indent: str) -> str:
        name, jm, X, inertia = pm.names[j], pm.joints[j], pm.jointPlacements[j], pm.inertias[j]
        out = [f'{indent}<body name="{name.removesuffix("_joint") if j > 1 else "trunk"}" '
               f'pos="{_f(X.translation)}" quat="{_f(_quat_wxyz(X.rotation))}">']
        out.append(f'{indent}  <inertial pos="{_f(inertia.lever)}" mass="{float(inertia.mass)!r}" '
                   f'fullinertia="{_f(inertia.inertia[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]])}"/>')
        if j == 1:
            out.append(f'{indent}  <freejoint name="{name}"/>')
        else:
            extra = ""
            if damping:
                extra += f' damping="{float(pm.damping[jm.idx_v])!r}"'
            if frictionloss:            # (the URDF's <dynamics friction>: MuJoCo's dry joint friction)
                extra += f' frictionloss="{float(pm.friction[jm.idx_v])!r}"'
            if limits:
                extra += (f' limited="true" range="{float(pm.lowerPositionLimit[jm.idx_q])!r} '
                          f'{float(pm.upperPositionLimit[jm.idx_q])!r}"')
            out.append(f'{indent}  <joint name="{name}" type="hinge" axis="{_f(_axis(jm))}"{extra}/>')
        if j in feet:
            f = feet[j]
            p = f.placement.translation
            out.append(f'{indent}  <geom name="{f.name}" type="sphere" size="{FOOT_RADIUS!r}" pos="{_f(p)}" '
                       f'condim="3" friction="{friction}" contype="1" conaffinity="0"/>')
            out.append(f'{indent}  <site name="{f.name}" pos="{_f(p)}"/>')
        for c in children[j]:
            out.append(body(c, indent + "  "))
        out.append(f"{indent}</body>")
        return "\n".join(out)

    if actuators == "motor":
        acts = "\n".join(f'    <motor name="{n}" joint="{n}" ctrllimited="true" ctrlrange="{-float(e)!r} {float(e)!r}"/>'
                         for n, e in zip(JOINTS, EFFORT))
    elif actuators == "position":
        acts = "\n".join(f'    <position name="{n}" joint="{n}" kp="{kp!r}" kv="{kd!r}" forcelimited="true" '
                         f'forcerange="{-float(e)!r} {float(e)!r}"/>' for n, e in zip(JOINTS, EFFORT))
    else:
        raise ValueError("actuators: motor or position")
    if [pm.names[j] for j in range(2, pm.njoints)] != list(JOINTS):
        raise ValueError("the URDF's joints are not Go1's")
    return f"""<mujoco model="go1">
  <compiler angle="radian" inertiafromgeom="false"/>
  <option timestep="{dt!r}" gravity="0 0 {-GRAVITY!r}" cone="{cone}"/>
  <worldbody>
    <geom name="floor" type="plane" size="0 0 1" condim="3" friction="{friction}" contype="0" conaffinity="1"/>
{body(1, "    ")}
  </worldbody>
  <actuator>
{acts}
  </actuator>
</mujoco>
"""


def model(dt: float = 1e-3, cone: str = "pyramidal", mu: float = 0.8, **options):
    """mujoco.MjModel of Go1 on a freejoint, the four foot spheres and a floor (see the module's docstring).
    options: actuators ("motor" | "position"), kp, kd (position actuators), damping, limits, solref, frictionloss."""
    import mujoco
    return mujoco.MjModel.from_xml_string(mjcf(dt, cone, mu, **options))


# ----------------------------------------------------------------------------------- verification of masses

def _full_inertia(m, b) -> np.ndarray:
    """Body b's inertia about its COM in the body's axes (MuJoCo keeps principal moments and their frame)."""
    import mujoco
    R = np.zeros(9)
    mujoco.mju_quat2Mat(R, m.body_iquat[b])
    R = R.reshape(3, 3)
    return R @ np.diag(m.body_inertia[b]) @ R.T


def verify(m) -> dict:
    """The largest differences between MuJoCo's model m and Pinocchio's (same URDF): per body mass, COM,
    inertia about the COM (relative to the largest entry), total mass; joint-space mass matrix and gravity
    forces at random joint angles with the base at identity orientation (where Pinocchio's and MuJoCo's
    free-flyer velocities coincide); the foot positions; and the total mass from MuJoCo's own URDF parser."""
    import mujoco
    import pinocchio as pin
    pm = pinocchio_model()
    pdata = pm.createData()
    out = {"bodies": m.nbody - 1, "mass": 0.0, "com": 0.0, "inertia": 0.0}
    for j in range(1, pm.njoints):
        name = "trunk" if j == 1 else pm.names[j].removesuffix("_joint")
        b = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)
        I = pm.inertias[j]
        out["mass"] = max(out["mass"], abs(m.body_mass[b] - I.mass))
        out["com"] = max(out["com"], float(np.abs(m.body_ipos[b] - I.lever).max()))
        out["inertia"] = max(out["inertia"], float(np.abs(_full_inertia(m, b) - I.inertia).max()
                                                   / np.abs(I.inertia).max()))
    out["total_pinocchio"] = float(pin.computeTotalMass(pm))
    out["total_mujoco"] = float(m.body_subtreemass[0])
    d = mujoco.MjData(m)
    rng = np.random.default_rng(1)
    worst_M = worst_g = worst_feet = 0.0
    for _ in range(5):
        qj = STAND + rng.uniform(-0.5, 0.5, 12)
        xyz = rng.uniform(-1, 1, 3)
        q = np.concatenate([xyz, [0, 0, 0, 1], qj])                # Pinocchio: quaternion x y z w
        d.qpos[:] = np.concatenate([xyz, [1, 0, 0, 0], qj])
        d.qvel[:] = 0
        mujoco.mj_forward(m, d)
        M = np.zeros((m.nv, m.nv))
        if hasattr(d, "qM"):
            mujoco.mj_fullM(m, M, d.qM)                               # MuJoCo 3
        else:
            mujoco.mj_fullM(m, d, M)                                  # MuJoCo 4
        Mp = pin.crba(pm, pdata, q)
        Mp = np.triu(Mp) + np.triu(Mp, 1).T
        worst_M = max(worst_M, float(np.abs(M - Mp).max() / np.abs(Mp).max()))
        g = pin.computeGeneralizedGravity(pm, pdata, q)
        worst_g = max(worst_g, float(np.abs(d.qfrc_bias - g).max() / np.abs(g).max()))
        pin.framesForwardKinematics(pm, pdata, q)
        for foot in FEET:
            s = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, foot)
            worst_feet = max(worst_feet, float(np.abs(d.site_xpos[s]
                                                      - pdata.oMf[pm.getFrameId(foot)].translation).max()))
    out.update(mass_matrix=worst_M, gravity=worst_g, feet=worst_feet)
    out["total_mujoco_urdf"] = mujoco_urdf_mass()
    return out


def mujoco_urdf_mass() -> float:
    """Total mass as MuJoCo's URDF parser reads the same file (meshes stripped: MuJoCo cannot read .dae; the
    1e-6 kg `base` link's inertia, all nine entries 1e-6, is singular and refused by MuJoCo: its products are
    zeroed here, which moves nothing at the printed precision)."""
    import re
    import mujoco
    text = URDF.read_text()
    text = re.sub(r"<visual>.*?</visual>", "", text, flags=re.S)
    text = re.sub(r"<collision>.*?</collision>", "", text, flags=re.S)
    text = text.replace('ixy="1e-6" ixz="1e-6" iyy="1e-6" iyz="1e-6"', 'ixy="0" ixz="0" iyy="1e-6" iyz="0"', 1)
    text = text.replace('<robot name="go1">', '<robot name="go1"><mujoco><compiler discardvisual="true" '
                        'fusestatic="false" balanceinertia="false"/></mujoco>', 1)
    m = mujoco.MjModel.from_xml_string(text)
    return float(m.body_subtreemass[0])


# ------------------------------------------------------------------------------------------ pose and control

def base_height(q_joints=STAND) -> float:
    """Height of the trunk (level, identity orientation) at which the lowest foot sphere touches z = 0, by
    Pinocchio's forward kinematics; also checks that all four feet are at one height."""
    import pinocchio as pin
    pm = pinocchio_model()
    pdata = pm.createData()
    q = np.concatenate([[0, 0, 0, 0, 0, 0, 1], q_joints])
    pin.framesForwardKinematics(pm, pdata, q)
    z = np.array([pdata.oMf[pm.getFrameId(f)].translation[2] for f in FEET])
    if np.ptp(z) > 1e-12:
        raise ValueError(f"feet at different heights: {z}")
    return FOOT_RADIUS - float(z.min())


def standing_data(m, height: float = BASE_HEIGHT, q_joints=STAND):
    """MjData at rest: trunk level at `height`, joints at q_joints (the feet just touching at BASE_HEIGHT)."""
    import mujoco
    d = mujoco.MjData(m)
    d.qpos[:] = np.concatenate([[0, 0, height, 1, 0, 0, 0], q_joints])
    if m.actuator_biastype[0] == mujoco.mjtBias.mjBIAS_AFFINE:        # position actuators: ctrl = q_ref
        d.ctrl[:] = q_joints
    mujoco.mj_forward(m, d)
    return d


@dataclass
class PD:
    """tau = clip(kp (q_ref - q) - kd qdot, -EFFORT, EFFORT), the same gains for all 12 joints."""
    kp: float = KP
    kd: float = KD
    limit: np.ndarray = field(default_factory=lambda: EFFORT.copy())

    def __call__(self, q, qdot, q_ref, out=None):
        tau = np.minimum(np.maximum(self.kp * (q_ref - q) - self.kd * qdot, -self.limit), self.limit)
        if out is None:
            return tau
        out[:] = tau
        return out


@dataclass
class Trot:
    """An open-loop trot: the diagonal pairs (FL, RR) and (FR, RL) half a period apart. With phase
    p = 2 pi f t + (0 for FR and RL, pi for FL and RR), every leg's reference is

        hip   = 0
        thigh = thigh0 + a_thigh * cos(p)                 (decreasing: the foot swings forward)
        calf  = calf0  - a_calf * max(0, sin(p))          (folded: the foot lifts while sin(p) > 0)

    so a foot lifts and swings forward for sin(p) > 0 and pushes back on the ground for sin(p) < 0."""
    f: float = 2.5              # Hz
    a_thigh: float = 0.2       # rad
    a_calf: float = 0.4        # rad
    thigh0: float = STAND_LEG[1]
    calf0: float = STAND_LEG[2]

    def reference(self, t: float, out=None) -> np.ndarray:
        """q_ref(t) (12 angles in JOINTS' order), written into `out` when given."""
        w = 2 * math.pi * self.f * t
        s, c = math.sin(w), math.cos(w)
        a = self.a_thigh * c
        lift_0, lift_pi = self.a_calf * max(0.0, s), self.a_calf * max(0.0, -s)    # sin(p + pi) = -sin(p)
        out = np.empty(12) if out is None else out
        out[0] = out[3] = out[6] = out[9] = 0.0
        out[1], out[2] = self.thigh0 - a, self.calf0 - lift_pi      # FL: phase pi (cos(p + pi) = -cos(p))
        out[4], out[5] = self.thigh0 + a, self.calf0 - lift_0       # FR: phase 0
        out[7], out[8] = self.thigh0 + a, self.calf0 - lift_0       # RL: phase 0
        out[10], out[11] = self.thigh0 - a, self.calf0 - lift_pi    # RR: phase pi
        return out


class Controller:
    """Sets d.ctrl before each mj_step: the PD torques (motor actuators) toward reference(t), or the
    reference itself (position actuators). reference: a constant 12-vector, or a function (t, out) that
    writes q_ref(t) into out (as Trot.reference)."""

    def __init__(self, pd: PD | None, reference=STAND):
        self.pd = pd
        self.reference = reference
        self.ref = np.zeros(12)
        if callable(reference):
            reference(0.0, self.ref)
        else:
            self.ref[:] = reference

    def __call__(self, m, d) -> None:
        if callable(self.reference):
            self.reference(d.time, self.ref)
        if self.pd is None:
            d.ctrl[:] = self.ref
        else:
            self.pd(d.qpos[7:], d.qvel[6:], self.ref, out=d.ctrl)


# ------------------------------------------------------------------------------------------ measured runs

def _rpy(quat) -> tuple:
    """Roll, pitch, yaw (Z-Y-X Euler angles) of a w x y z quaternion; pitch > 0 tilts the nose down."""
    w, x, y, z = quat
    roll = math.atan2(2 * (w * x + y * z), 1 - 2 * (x * x + y * y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (w * y - z * x))))
    yaw = math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    return roll, pitch, yaw


@dataclass
class Record:
    """Samples of one run, one row per step (after the step): time, base position, roll pitch yaw, per foot
    the penetration r - z_center, in-contact flag, tangential speed of the contact point; per step the sum
    of normal forces and the largest |f_t| / (mu f_n) over the contacts."""
    t: np.ndarray
    base: np.ndarray
    rp: np.ndarray
    penetration: np.ndarray
    contact: np.ndarray
    slip_speed: np.ndarray
    normal_sum: np.ndarray
    cone_ratio: np.ndarray
    feet_xy: np.ndarray
    mass: float
    mu: float
    dt: float

    def stats(self, after: float = 1.0) -> dict:
        """Figures over t >= after (drift, penetration, slip, forces)."""
        k = self.t >= after - 1e-12
        z = self.base[k, 2]
        slip_dist = (self.slip_speed[k] * self.contact[k]).sum(axis=0) * self.dt
        fx = self.feet_xy[k]
        return {
            "height_mean": float(z.mean()), "height_drift": float(z[-1] - z[0]), "height_range": float(np.ptp(z)),
            "penetration_max": float(self.penetration[k].max()),
            "penetration_mean": float(self.penetration[k][self.contact[k]].mean()) if self.contact[k].any() else 0.0,
            "slip_speed_max": float((self.slip_speed[k] * self.contact[k]).max()),
            "slip_distance_max": float(slip_dist.max()),
            "feet_xy_moved": float(np.linalg.norm(fx - fx[0], axis=2).max()),
            "normal_sum_end": float(self.normal_sum[-1]), "mg": self.mass * GRAVITY,
            "normal_sum_mean": float(self.normal_sum[k].mean()),
            "cone_ratio_max": float(self.cone_ratio[k].max()),
            "cone_violation": max(0.0, float(self.cone_ratio[k].max()) - 1.0),
            "roll_range": (float(self.rp[k, 0].min()), float(self.rp[k, 0].max())),
            "pitch_range": (float(self.rp[k, 1].min()), float(self.rp[k, 1].max())),
            "yaw_end": float(self.rp[-1, 2]),
            "base_z_min": float(z.min()),
            "speed_x": float((self.base[k][-1, 0] - self.base[k][0, 0]) / (self.t[k][-1] - self.t[k][0])),
            "drift_y": float(self.base[k][-1, 1] - self.base[k][0, 1]),
        }


def run(m, d, controller, seconds: float) -> Record:
    """Steps d for `seconds` with controller(m, d) before each mj_step, sampling after each step."""
    import mujoco
    n = int(round(seconds / m.opt.timestep))
    foot_geoms = [mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f) for f in FEET]
    floor = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "floor")
    mu = float(m.geom_friction[floor, 0])
    t = np.zeros(n)
    base = np.zeros((n, 3))
    rp = np.zeros((n, 3))
    pen = np.zeros((n, 4))
    contact = np.zeros((n, 4), bool)
    slip = np.zeros((n, 4))
    nsum = np.zeros(n)
    cone = np.zeros(n)
    feet_xy = np.zeros((n, 4, 2))
    jacp = np.zeros((3, m.nv))
    f6 = np.zeros(6)
    for i in range(n):
        if controller is not None:
            controller(m, d)
        mujoco.mj_step(m, d)
        t[i] = d.time
        base[i] = d.qpos[:3]
        rp[i] = _rpy(d.qpos[3:7])
        for k, g in enumerate(foot_geoms):
            c = d.geom_xpos[g]
            pen[i, k] = FOOT_RADIUS - c[2]
            feet_xy[i, k] = c[:2]
        for c_i in range(d.ncon):
            con = d.contact[c_i]
            g = con.geom1 if con.geom1 != floor else con.geom2
            k = foot_geoms.index(g)
            contact[i, k] = True
            point = d.geom_xpos[g] - np.array([0, 0, FOOT_RADIUS])     # the sphere's lowest point
            mujoco.mj_jac(m, d, jacp, None, point, m.geom_bodyid[g])
            v = jacp @ d.qvel
            slip[i, k] = math.hypot(v[0], v[1])
            mujoco.mj_contactForce(m, d, c_i, f6)
            nsum[i] += f6[0]
            if f6[0] > 0:
                cone[i] = max(cone[i], math.hypot(f6[1], f6[2]) / (mu * f6[0]))
    return Record(t, base, rp, pen, contact, slip, nsum, cone, feet_xy, float(m.body_subtreemass[0]), mu,
                  float(m.opt.timestep))


def stand(dt: float = 1e-3, cone: str = "pyramidal", mu: float = 0.8, seconds: float = 10.0,
          kp: float = KP, kd: float = KD, **options) -> dict:
    """Go1 released at rest in the standing pose, held by the Python PD for `seconds`: Record.stats(1.0),
    and under 'last5' the stats of the last 5 s. options: model()'s."""
    m = model(dt, cone, mu, **options)
    d = standing_data(m)
    rec = run(m, d, Controller(PD(kp, kd), STAND), seconds)
    return {**rec.stats(1.0), "last5": rec.stats(seconds - 5.0)}


def trot(dt: float = 1e-3, cone: str = "pyramidal", mu: float = 0.8, seconds: float = 10.0,
         gait: Trot | None = None, kp: float = KP, kd: float = KD, settle: float = 0.0, **options) -> dict:
    """Go1 released at rest in the standing pose, held `settle` s by the PD toward STAND, then trotting
    (gait.reference(t - settle)) for `seconds`: Record.stats over the trot (speed_x its mean forward speed).
    options: model()'s."""
    gait = gait or Trot()
    m = model(dt, cone, mu, **options)
    d = standing_data(m)
    pd = PD(kp, kd)
    if settle > 0:
        run(m, d, Controller(pd, STAND), settle)
    rec = run(m, d, Controller(pd, lambda t, out: gait.reference(t - settle, out)), seconds)
    return rec.stats(settle)


# ----------------------------------------------------------------------------------------------- timing

def steps_per_second(m, d, controller, seconds: float) -> float:
    """mj_step calls per wall second over `seconds` of simulated time from d's state (d is advanced).
    controller None: one C call mj_step(m, d, nstep) with d.ctrl as it is (no Python in the loop);
    otherwise a Python loop calling controller(m, d) then mj_step(m, d)."""
    import mujoco
    n = int(round(seconds / m.opt.timestep))
    if controller is None:
        tic = time.perf_counter()
        mujoco.mj_step(m, d, nstep=n)
        return n / (time.perf_counter() - tic)
    step = mujoco.mj_step
    tic = time.perf_counter()
    for _ in range(n):
        controller(m, d)
        step(m, d)
    return n / (time.perf_counter() - tic)


def _settled(m, controller, seconds: float = 1.0):
    """The state after `seconds` standing (qpos, qvel, ctrl, qacc_warmstart, time), each timed run's start."""
    d = standing_data(m)
    run(m, d, controller, seconds)
    return d.qpos.copy(), d.qvel.copy(), d.ctrl.copy(), d.qacc_warmstart.copy(), d.time


def _restore(m, state):
    import mujoco
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:], d.ctrl[:], d.qacc_warmstart[:], d.time = state
    mujoco.mj_forward(m, d)
    return d


def timings(dt: float = 1e-3, cone: str = "pyramidal", mu: float = 0.8, seconds: float = 2.0,
            rounds: int = 5, kp: float = KP, kd: float = KD, gait: Trot | None = None) -> dict:
    """Steps per second of Go1 standing, from the same settled state, rounds interleaved (each round runs
    every variant once). Variants:
      python_pd     motor actuators, PD in Python before each mj_step (a Python loop)
      python_const  motor actuators, the same Python loop calling mj_step with ctrl left constant
                    (the settled PD torques): Python's per-call cost without the controller's
      c_const       the same constant ctrl, mj_step(nstep=N): no Python in the loop
      c_pd          position actuators (the same PD, clamp, gains) with ctrl = STAND, mj_step(nstep=N)
      python_trot   motor actuators, Trot() reference (t counted from the round's start) and PD in Python
                    (a different motion: feet lifting and landing, 2 to 4 contacts)
    Returns {variant: [steps/s per round]} and 'held' {variant: base height at the end of the round}."""
    mm = model(dt, cone, mu)
    mp = model(dt, cone, mu, actuators="position", kp=kp, kd=kd)
    pd = Controller(PD(kp, kd), STAND)
    start_m = _settled(mm, pd)
    start_p = _settled(mp, None)
    keep = lambda m, d: None   # noqa: E731 - ctrl as it is
    gait = gait or Trot()
    t0 = float(start_m[4])
    trotting = Controller(PD(kp, kd), lambda t, out: gait.reference(t - t0, out))
    variants = {"python_pd": (mm, start_m, pd), "python_const": (mm, start_m, keep),
                "c_const": (mm, start_m, None), "c_pd": (mp, start_p, None), "python_trot": (mm, start_m, trotting)}
    out = {k: [] for k in variants}
    held = {k: [] for k in variants}
    for _ in range(rounds):
        for k, (m, start, ctrl) in variants.items():
            d = _restore(m, start)
            out[k].append(steps_per_second(m, d, ctrl, seconds))
            held[k].append(float(d.qpos[2]))
    out["held"] = held
    return out


def _machine() -> str:
    load = os.getloadavg() if hasattr(os, "getloadavg") else ("?",) * 3
    import mujoco
    return (f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average "
            f"{load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; MuJoCo {mujoco.__version__}, Python {platform.python_version()}")


# ------------------------------------------------------------------------------------------------- main

def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rounds", type=int, default=9)
    ap.add_argument("--seconds", type=float, default=1.0, help="simulated seconds per timed round")
    ap.add_argument("--mu", type=float, default=0.8)
    ap.add_argument("--skip-timing", action="store_true")
    a = ap.parse_args(argv)
    print("machine:", _machine())
    print(f"URDF: {URDF}")

    v = verify(model())
    print(f"\nmasses (MuJoCo model against Pinocchio, same URDF): {v['bodies']} bodies; max |dm| {v['mass']:.1e} kg,"
          f" |dcom| {v['com']:.1e} m, |dI|/|I| {v['inertia']:.1e}; total {v['total_mujoco']:.6f} kg (Pinocchio "
          f"{v['total_pinocchio']:.6f}, MuJoCo's URDF parser {v['total_mujoco_urdf']:.6f}); mass matrix rel "
          f"{v['mass_matrix']:.1e}, gravity rel {v['gravity']:.1e}, feet {v['feet']:.1e} m")

    h = base_height(STAND)
    print(f"\nstanding pose (FL FR RL RR x hip thigh calf): {STAND_LEG} per leg; base height {h:.12f} m "
          f"(BASE_HEIGHT {BASE_HEIGHT!r}, 0.02 + 0.426 cos 0.9 = {0.02 + 0.426 * math.cos(0.9):.12f})")
    print(f"PD: kp {KP} N m/rad, kd {KD} N m s/rad, |tau| <= {EFFORT[:3]} (hip, thigh, calf)")

    print(f"\nstanding 10 s, Python PD, mu {a.mu} (figures over t in [1, 10] s):")
    for dt in (1e-3, 2e-3):
        for cone in ("pyramidal", "elliptic"):
            s = stand(dt, cone, a.mu)
            late = s.pop("last5")
            print(f"  dt {dt:g} {cone:9s}: height {s['height_mean']:.5f} m, drift {s['height_drift']:+.1e} m "
                  f"(range {s['height_range']:.1e}), penetration max {1e3 * s['penetration_max']:.3f} mm, "
                  f"slip speed max {s['slip_speed_max']:.1e} m/s, slip distance max {s['slip_distance_max']:.1e} m, "
                  f"feet moved {s['feet_xy_moved']:.1e} m, normal sum {s['normal_sum_end']:.4f} N vs m g "
                  f"{s['mg']:.4f} N, |f_t|/(mu f_n) max {s['cone_ratio_max']:.6f}; over [5, 10] s: drift "
                  f"{late['height_drift']:+.1e} m, slip distance {late['slip_distance_max']:.1e} m")

    g = Trot()
    print(f"\ntrot from t = 0 (released at rest in the standing pose), f {g.f} Hz, a_thigh {g.a_thigh}, a_calf {g.a_calf}, 10 s:")
    for dt in (1e-3, 2e-3):
        for cone in ("pyramidal", "elliptic"):
            s = trot(dt, cone, a.mu)
            print(f"  dt {dt:g} {cone:9s}: speed {s['speed_x']:.3f} m/s, lateral drift {s['drift_y']:+.3f} m, yaw at "
                  f"the end {s['yaw_end']:+.3f}, "
                  f"roll [{s['roll_range'][0]:+.3f}, {s['roll_range'][1]:+.3f}], pitch [{s['pitch_range'][0]:+.3f}, "
                  f"{s['pitch_range'][1]:+.3f}] rad, base z min {s['base_z_min']:.3f} m, penetration max "
                  f"{1e3 * s['penetration_max']:.2f} mm, |f_t|/(mu f_n) max {s['cone_ratio_max']:.6f} (beyond 1: "
                  f"{s['cone_violation']:.1e})")

    if a.skip_timing:
        return
    print(f"\nsteps/s from a settled stance ({a.rounds} interleaved rounds of {a.seconds} s simulated, min .. max):")
    for dt in (1e-3, 2e-3):
        for cone in ("pyramidal", "elliptic"):
            r = timings(dt, cone, a.mu, a.seconds, a.rounds)
            cells = ", ".join(f"{k} {min(r[k]):,.0f} .. {max(r[k]):,.0f}" for k in
                              ("python_pd", "python_const", "c_const", "c_pd", "python_trot"))
            held = ", ".join(f"{k} {min(r['held'][k]):.3f}" for k in r["held"])
            us = lambda k: 1e6 / max(r[k])   # noqa: E731 - the best round: the least disturbed by other load
            print(f"  dt {dt:g} {cone:9s}: {cells}")
            print(f"      best round, us/step: python_pd {us('python_pd'):.1f}, c_pd {us('c_pd'):.1f} (Python's share "
                  f"{us('python_pd') - us('c_pd'):.1f}), python_const {us('python_const'):.1f}, c_const "
                  f"{us('c_const'):.1f}, python_trot {us('python_trot'):.1f}; simulated s per wall s: python_pd "
                  f"{dt * max(r['python_pd']):.0f}, c_pd {dt * max(r['c_pd']):.0f}, python_trot "
                  f"{dt * max(r['python_trot']):.0f}")
            print(f"      base z at the end of a round: {held}")


if __name__ == "__main__":
    main()
