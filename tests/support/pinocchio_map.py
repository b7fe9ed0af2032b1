"""andyc's state against Pinocchio's (q, v) for a URDF robot, and the robots the Pinocchio tests compare
(tests/test_urdf_pinocchio.py, tests/test_aba.py)."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from andyc.spec.urdf import identifier

# name: (URDF inside example-robot-data, base)
PINOCCHIO_ROBOTS = {
    "ur5": ("ur_description/urdf/ur5_robot.urdf", "fixed"),                   # 6 revolute, origins with rpy
    "kinova": ("kinova_description/robots/kinova.urdf", "fixed"),             # continuous joints (Pinocchio: cos, sin)
    "panda": ("panda_description/urdf/panda.urdf", "fixed"),                  # prismatic fingers, a mimic, damping
    "finger_edu": ("finger_edu_description/robots/finger_edu.urdf", "fixed"),
    "double_pendulum": ("double_pendulum_description/urdf/double_pendulum_continuous.urdf", "fixed"),
    "solo12": ("solo_description/robots/solo12.urdf", "floating"),           # quadruped on a floating base
}


def root_link(urdf: Path) -> str:
    robot = ET.parse(urdf).getroot()
    children = {j.find("child").get("link") for j in robot.findall("joint")}
    return next(link.get("name") for link in robot.findall("link") if link.get("name") not in children)


class PinocchioMap:
    """andyc's state x -> Pinocchio's (q, v), with v_pin = T(x) v_andyc and c = dT/dt v_andyc.

    The conventions, read from andyc/spec/urdf.py and andyc/symbolic/kinematics.py (not guessed):

    - andyc: x = (coordinates, speeds, signals). Coordinates are named after the joints; the speeds are the
      coordinate rates, then each floating link's [vx, vy, vz, wx, wy, wz] (named <base link>_vx.. for a
      floating base, <joint>_vx.. for a floating joint): the velocity of the link's origin and its angular
      velocity, both in the link's own axes (`in: body`: v_rel = Q v). Signals <link>_x, _y, _z are the
      origin's position in the joint frame, <link>_qw, _qx, _qy, _qz the rotation (w first).
    - Pinocchio free flyer: q = [x, y, z, qx, qy, qz, qw], v = [linear, angular] in the local frame, i.e.
      andyc's six speeds one for one and its signals with the quaternion's w moved last.
    - revolute, prismatic: q and v one for one; continuous (Pinocchio's RUB joints, nq = 2): q = [cos, sin].
    - mimic: Pinocchio (without mimic=True) keeps the joint: q = m q_master + o, v = m v_master.
    - planar: Pinocchio uses the plane normal to the joint frame's z (it ignores the URDF axis) with
      q = [x, y, cos th, sin th] and v = [Rz(th)^T (dx/dt, dy/dt), dth/dt]; andyc's coordinates are x, y
      (in the joint frame) and th, so T depends on th and c = dT/dt v is not zero.
    """

    def __init__(self, module, model, urdf: Path, base_link: str | None):
        self.module, self.model = module, model
        self.nq, self.nv = module.NQ, module.NV
        coords, speeds, signals = list(module.COORDINATES), list(module.SPEEDS), list(module.SIGNALS)
        robot = ET.parse(urdf).getroot()
        self.mimic = {j.get("name"): (j.find("mimic").get("joint"), float(j.find("mimic").get("multiplier", 1)),
                                      float(j.find("mimic").get("offset", 0)))
                      for j in robot.findall("joint") if j.find("mimic") is not None}
        child = {j.get("name"): j.find("child").get("link") for j in robot.findall("joint")}
        signal = {name: self.nq + self.nv + k for k, name in enumerate(signals)}
        self.joints = []
        for jid in range(1, model.njoints):
            jm, name = model.joints[jid], model.names[jid]
            if (jm.nq, jm.nv) == (7, 6):            # free flyer: the floating base or a floating joint
                owner, link = (base_link, base_link) if name == "root_joint" else (name, child[name])
                v = [speeds.index(f"{identifier(owner, 'joint')}_{c}") for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
                s = [signal[f"{identifier(link, 'link')}_{c}"] for c in ("x", "y", "z", "qx", "qy", "qz", "qw")]
                self.joints.append(("free", jm.idx_q, jm.idx_v, v, s))
            elif (jm.nq, jm.nv) == (4, 3):
                q = [coords.index(f"{identifier(name, 'joint')}_{c}") for c in ("x", "y", "theta")]
                self.joints.append(("planar", jm.idx_q, jm.idx_v, q, None))
            else:
                master, m, o = self.mimic.get(name, (name, 1.0, 0.0))
                self.joints.append(("rev" if jm.nq == 1 else "rub", jm.idx_q, jm.idx_v,
                                    coords.index(identifier(master, "joint")), (m, o)))

    def state(self, x):
        """(q_pin, T, c) at andyc's state x."""
        q = np.zeros(self.model.nq)
        T = np.zeros((self.model.nv, self.nv))
        c = np.zeros(self.model.nv)
        va = x[self.nq:self.nq + self.nv]
        for kind, iq, iv, a, b in self.joints:
            if kind == "free":
                q[iq:iq + 7] = x[b]
                T[iv + np.arange(6), a] = 1
            elif kind == "planar":
                px, py, th = x[a]
                cs, sn = np.cos(th), np.sin(th)
                q[iq:iq + 4] = px, py, cs, sn
                T[iv:iv + 2, a[0]] = cs, -sn
                T[iv:iv + 2, a[1]] = sn, cs
                T[iv + 2, a[2]] = 1
                dx, dy, dth = va[a]
                c[iv:iv + 2] = dth * (-sn * dx + cs * dy), dth * (-cs * dx - sn * dy)
            else:
                m, o = b
                angle = m * x[a] + o
                q[iq:iq + (1 if kind == "rev" else 2)] = angle if kind == "rev" else (np.cos(angle), np.sin(angle))
                T[iv, a] = m
        return q, T, c

    def random_state(self, rng):
        x = np.zeros(self.module.NX)
        x[:self.nq] = rng.uniform(-np.pi, np.pi, self.nq)
        x[self.nq:self.nq + self.nv] = rng.normal(scale=2.0, size=self.nv)
        for kind, _, _, _, s in self.joints:
            if kind == "free":
                x[s[:3]] = rng.normal(size=3)
                quat = rng.normal(size=4)
                x[s[3:]] = quat / np.linalg.norm(quat)
        return x

    def expected(self, x, data, mimic_free: bool):
        """Pinocchio's (M, bias, dv/dt) in andyc's speeds; dv/dt from aba unless the robot has mimic joints."""
        import pinocchio as pin

        q, T, c = self.state(x)
        v = T @ x[self.nq:self.nq + self.nv]
        D = np.diag(self.model.damping)
        M = pin.crba(self.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        M_a = T.T @ M @ T
        b_a = T.T @ (pin.rnea(self.model, data, q, v, c) + D @ v)     # M (T a + c) + b = tau, projected by T^T
        if mimic_free:
            a_pin = pin.aba(self.model, data, q, v, -D @ v)
            a_a = np.linalg.lstsq(T, a_pin - c, rcond=None)[0]
        else:       # Pinocchio's aba has no mimic joints (RuntimeError): solve its crba/rnea in andyc's speeds
            a_a = np.linalg.solve(M_a, -b_a)
        return M_a, b_a, a_a


def relative(a, b) -> float:
    return float(np.abs(a - b).max() / np.abs(b).max())
