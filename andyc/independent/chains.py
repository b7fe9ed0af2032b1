"""Random serial chains, written as andyc YAML (and derived independently with Kane's method: kane.py).

A chain of n links hangs from the world; link i carries coordinate q_i, frame
L_i and one rigid body B_i. Every link is a homogeneous transform from its
parent's frame, applied left to right exactly as the andyc spec defines it:

    T_i = Trans(t_i) * Rot(R_i) * Joint_i(q_i)

    Trans(t)              translation t, in the parent's axes
    Rot(R)                a fixed rotation: rpy [r, p, y] -> R = Rz(y) Ry(p) Rx(r),
                          axis-angle (k, a) -> Rodrigues, quaternion (w, x, y, z)
    revolute about k      Rot(k, q)      (k unit, in the axes after Trans and Rot)
    prismatic along k     Trans(q k)
    DH row [d, th, a, al] Rz(th) Tz(d) Tx(a) Rx(al)   (standard DH), with the
                          coordinate added to th (revolute) or to d (prismatic)

Body B_i has mass m_i, centre of mass c_i (in L_i axes, from the L_i origin, or
from an optional fixed "tool" frame T_i hung on L_i) and inertia I_i about the
COM in the same axes; gravity g * e_g (e_g a unit vector in world axes) acts at
every COM.

`random_chain` draws a chain from a seed and `chain_yaml` writes it as an andyc
model; andyc.independent.kane derives the same system with sympy.physics.mechanics
(no andyc.symbolic or andyc.codegen code is used there).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Rotation", "Link", "Chain", "random_chain", "chain_yaml", "rotation_matrix", "unit_axis"]

NAMED_AXES = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0),
              "-x": (-1.0, 0.0, 0.0), "-y": (0.0, -1.0, 0.0), "-z": (0.0, 0.0, -1.0)}
KINDS = ("planar", "3d")
JOINT_FORMS = ("axis", "dh")
G_DEFAULT = 9.81


# -- description of a chain -------------------------------------------------------

@dataclass(frozen=True)
class Rotation:
    """A fixed rotation, child axes -> parent axes.

    kind "rpy": values (roll, pitch, yaw), R = Rz(yaw) Ry(pitch) Rx(roll);
    kind "axis": values (axis, angle), axis a name ("x", "-z", ...) or 3 numbers;
    kind "quaternion": values (w, x, y, z), a unit quaternion.
    """
    kind: str
    values: tuple

    def matrix(self) -> np.ndarray:
        return rotation_matrix(self)


@dataclass(frozen=True)
class Link:
    """One link of the chain: a joint frame L_i and the body B_i it carries.

    translation, rotation: the fixed part of the link (None when absent).
    joint: "revolute" or "prismatic"; the joint variable is `coordinate`.
    axis: joint axis for the axis form (name or 3 numbers, not normalized); None for DH.
    dh: (d, theta, a, alpha) constants for the DH form: the coordinate is added to
        theta (revolute) or d (prismatic); alpha may be the string "pi/2" or "-pi/2".
    tool: None, or (translation, Rotation | None) of a fixed child frame T_i of L_i
        that carries the body instead of L_i.
    mass, com, inertia: body mass, COM offset and 3x3 inertia about the COM (frame axes).
    inertia_form: how the YAML writes the inertia, "6" ([xx, yy, zz, xy, xz, yz]) or "3x3".
    initial, velocity: q_i(0) and dq_i/dt(0).
    """
    index: int
    joint: str
    translation: tuple | None
    rotation: Rotation | None
    axis: str | tuple | None
    dh: tuple | None
    tool: tuple | None
    mass: float
    com: tuple
    inertia: tuple
    inertia_form: str
    initial: float
    velocity: float

    @property
    def coordinate(self) -> str:
        return f"q{self.index}"

    @property
    def frame(self) -> str:
        return f"L{self.index}"

    @property
    def body_frame(self) -> str:
        return f"T{self.index}" if self.tool is not None else self.frame

    @property
    def mass_parameter(self) -> str:
        return f"m{self.index}"


@dataclass(frozen=True)
class Chain:
    """A serial chain: links[0] hangs from the world, links[i] from links[i-1].

    gravity: a unit vector in world axes; the acceleration is g * gravity with
    g a model parameter (default 9.81). Parameters are g, m1..mn.
    """
    name: str
    kind: str
    joints: str
    seed: int
    links: tuple
    gravity: tuple
    g: float = G_DEFAULT

    @property
    def n(self) -> int:
        return len(self.links)

    @property
    def coordinates(self) -> tuple:
        return tuple(link.coordinate for link in self.links)

    @property
    def parameters(self) -> dict:
        """Parameter name -> default value, in the order the YAML declares them."""
        return {"g": self.g, **{link.mass_parameter: link.mass for link in self.links}}


# -- numeric rotations -------------------------------------------------------------

def unit_axis(axis) -> np.ndarray:
    """A named axis or 3 numbers, normalized to unit length."""
    vec = np.array(NAMED_AXES[axis] if isinstance(axis, str) else axis, dtype=float)
    return vec / np.linalg.norm(vec)


def _rx(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0], [0, c, -s], [0, s, c]], dtype=float)


def _ry(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]], dtype=float)


def _rz(a):
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], dtype=float)


def rotation_matrix(rot: Rotation) -> np.ndarray:
    """The 3x3 matrix R of a Rotation: parent components = R @ child components."""
    if rot.kind == "rpy":
        roll, pitch, yaw = rot.values
        return _rz(yaw) @ _ry(pitch) @ _rx(roll)
    if rot.kind == "axis":
        axis, angle = rot.values
        k = unit_axis(axis)
        K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
        return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K
    if rot.kind == "quaternion":
        w, x, y, z = rot.values
        return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])
    raise ValueError(f"unknown rotation kind {rot.kind!r}")


# -- random generation -------------------------------------------------------------

def _random_rotation_matrix(rng) -> np.ndarray:
    w, x, y, z = _random_quaternion(rng)
    return rotation_matrix(Rotation("quaternion", (w, x, y, z)))


def _random_quaternion(rng) -> tuple:
    quat = rng.normal(size=4)
    quat /= np.linalg.norm(quat)
    if quat[0] < 0:
        quat = -quat
    return tuple(float(c) for c in quat)


def _random_inertia(rng, mass: float) -> tuple:
    """R diag(Ixx, Iyy, Izz) R^T from second moments s_k = int x_k^2 dm >= 0.

    Ixx = s_y + s_z etc., so each principal moment is at most the sum of the
    other two (strictly, as every s_k > 0): a physically valid rigid body.
    """
    s = mass * rng.uniform(0.002, 0.05, size=3)
    principal = np.array([s[1] + s[2], s[0] + s[2], s[0] + s[1]])
    R = _random_rotation_matrix(rng)
    inertia = R @ np.diag(principal) @ R.T
    inertia = (inertia + inertia.T) / 2          # exactly symmetric in floating point
    return tuple(tuple(float(x) for x in row) for row in inertia)


def _u(rng, lo, hi, size=None):
    out = rng.uniform(lo, hi, size=size)
    return float(out) if size is None else tuple(float(x) for x in out)


def _random_axis_3d(rng):
    if rng.random() < 0.4:
        return str(rng.choice(list(NAMED_AXES)))
    vec = rng.normal(size=3)
    vec *= rng.uniform(0.5, 2.0) / np.linalg.norm(vec)   # not unit: andyc normalizes
    return tuple(float(x) for x in vec)


def _random_rotation_3d(rng) -> Rotation:
    r = rng.random()
    if r < 0.6:
        return Rotation("rpy", _u(rng, -math.pi, math.pi, 3))
    if r < 0.8:
        return Rotation("axis", (_random_axis_3d(rng), _u(rng, -math.pi, math.pi)))
    return Rotation("quaternion", _random_quaternion(rng))


def random_chain(n_bodies: int, kind: str = "3d", joints: str = "axis", seed: int = 0) -> Chain:
    """A reproducible random serial chain of `n_bodies` links and bodies.

    kind "planar": revolute joints about +-z, prismatic joints along in-plane axes,
        translations and COMs in the xy plane, rotations about z, gravity in the
        plane (inertia tensors are full all the same: the motion stays planar).
    kind "3d": named and skew joint axes, rpy / axis-angle / quaternion rotations,
        3-D translations and COMs, gravity in a random direction, and (for n >= 2)
        at least one prismatic and one revolute joint.
    joints "axis": `revolute`/`prismatic` with `axis`; "dh": each joint a DH row
        [d, theta, a, alpha] with the coordinate in theta (revolute) or d
        (prismatic). Planar DH chains are all revolute with d = alpha = 0.
    Each body: mass in [0.5, 3], random COM offset, full inertia (see _random_inertia);
    some bodies sit on a fixed tool frame hung on their joint frame.
    """
    if kind not in KINDS:
        raise ValueError(f"kind must be one of {KINDS}, got {kind!r}")
    if joints not in JOINT_FORMS:
        raise ValueError(f"joints must be one of {JOINT_FORMS}, got {joints!r}")
    if n_bodies < 1:
        raise ValueError("a chain has at least one body")
    rng = np.random.default_rng([int(seed), int(n_bodies), KINDS.index(kind), JOINT_FORMS.index(joints)])
    planar = kind == "planar"

    prismatic = rng.random(n_bodies) < 0.3
    if planar and joints == "dh":
        prismatic[:] = False
    elif not planar and n_bodies >= 2:
        if not prismatic.any():
            prismatic[rng.integers(n_bodies)] = True
        if prismatic.all():
            prismatic[0] = False

    links = []
    for i in range(n_bodies):
        joint = "prismatic" if prismatic[i] else "revolute"
        translation = rotation = axis = dh = tool = None
        if joints == "axis":
            if rng.random() < 0.85:
                translation = (*_u(rng, -0.6, 0.6, 2), 0.0) if planar else _u(rng, -0.5, 0.5, 3)
            if planar:
                if rng.random() < 0.4:
                    angle = _u(rng, -math.pi, math.pi)
                    rotation = (Rotation("rpy", (0.0, 0.0, angle)) if rng.random() < 0.5
                                else Rotation("axis", ("z", angle)))
                if joint == "revolute":
                    axis = ["z", "-z", (0.0, 0.0, 1.0), (0.0, 0.0, 2.5)][rng.integers(4)]
                else:
                    a = _u(rng, -math.pi, math.pi)
                    scale = _u(rng, 0.5, 2.0)
                    axis = (scale * math.cos(a), scale * math.sin(a), 0.0)
            else:
                if rng.random() < 0.6:
                    rotation = _random_rotation_3d(rng)
                axis = _random_axis_3d(rng)
        else:
            a = _u(rng, -0.5, 0.5)
            if planar:
                d, alpha = 0.0, 0.0
            else:
                d = _u(rng, -0.3, 0.3)
                alpha = ["pi/2", "-pi/2", 0.0, _u(rng, -math.pi, math.pi)][rng.integers(4)]
            theta = 0.0 if rng.random() < 0.3 else _u(rng, -math.pi, math.pi)
            if joint == "prismatic":
                d = 0.0 if rng.random() < 0.3 else _u(rng, -0.2, 0.2)
            dh = (d, theta, a, alpha)
        if rng.random() < (0.2 if planar else 0.3):
            if planar:
                tool = ((*_u(rng, -0.3, 0.3, 2), 0.0), Rotation("rpy", (0.0, 0.0, _u(rng, -math.pi, math.pi))))
            else:
                tool = (_u(rng, -0.3, 0.3, 3), Rotation("rpy", _u(rng, -math.pi, math.pi, 3)))
        mass = _u(rng, 0.5, 3.0)
        com = (*_u(rng, -0.3, 0.3, 2), 0.0) if planar else _u(rng, -0.3, 0.3, 3)
        links.append(Link(index=i + 1, joint=joint, translation=translation, rotation=rotation, axis=axis,
                          dh=dh, tool=tool, mass=mass, com=com, inertia=_random_inertia(rng, mass),
                          inertia_form=["6", "3x3"][rng.integers(2)],
                          initial=_u(rng, -1.0, 1.0), velocity=_u(rng, -1.0, 1.0)))
    if planar:
        a = _u(rng, -math.pi, math.pi)
        gravity = (math.cos(a), math.sin(a), 0.0)
    else:
        vec = rng.normal(size=3)
        gravity = tuple(float(x) for x in vec / np.linalg.norm(vec))
    return Chain(name=f"chain_{kind}_{joints}_n{n_bodies}_s{seed}", kind=kind, joints=joints, seed=seed,
                 links=tuple(links), gravity=gravity)


# -- YAML ----------------------------------------------------------------------------

def _num(x) -> str:
    """A float in full precision (repr) that YAML reads as a number (always with a '.')."""
    if isinstance(x, str):
        return f'"{x}"'
    s = repr(float(x))
    if "e" in s and "." not in s.split("e")[0]:
        mantissa, exponent = s.split("e")
        s = f"{mantissa}.0e{exponent}"
    return s


def _vec(values) -> str:
    return "[" + ", ".join(_num(v) for v in values) + "]"


def _plus(name: str, offset) -> str:
    """The expression name + offset as a quoted string (just the name when offset is 0)."""
    if offset == 0:
        return name
    return f'"{name} - {_num(-offset)}"' if offset < 0 else f'"{name} + {_num(offset)}"'


def _axis(axis) -> str:
    return f'"{axis}"' if isinstance(axis, str) else _vec(axis)


def _rotation(rot: Rotation) -> str:
    if rot.kind == "rpy":
        return "{rpy: " + _vec(rot.values) + "}"
    if rot.kind == "axis":
        return "{axis: " + _axis(rot.values[0]) + ", angle: " + _num(rot.values[1]) + "}"
    return "{quaternion: " + _vec(rot.values) + "}"


def _inertia(link: Link) -> str:
    I = link.inertia
    if link.inertia_form == "3x3":
        return "[" + ", ".join(_vec(row) for row in I) + "]"
    return _vec([I[0][0], I[1][1], I[2][2], I[0][1], I[0][2], I[1][2]])


def chain_yaml(chain: Chain) -> str:
    """The chain as an andyc model (YAML text). Frames L_i (and T_i), bodies B_i."""
    out = [f"# Generated by andyc.independent.chains.random_chain({chain.n}, {chain.kind!r}, "
           f"{chain.joints!r}, seed={chain.seed}).",
           f"name: {chain.name}",
           f"description: Random {chain.kind} serial chain, {chain.n} bodies, {chain.joints} joints.",
           "parameters:"]
    out += [f"  {name}: {_num(value)}" for name, value in chain.parameters.items()]
    out.append("coordinates:")
    out += [f"  {link.coordinate}: {{initial: {_num(link.initial)}, velocity: {_num(link.velocity)}}}"
            for link in chain.links]
    out.append("gravity: [" + ", ".join(f'"{_num(c)}*g"' if c != 0 else "0" for c in chain.gravity) + "]")
    out.append("frames:")
    parent = "world"
    for link in chain.links:
        parts = [f"name: {link.frame}", f"parent: {parent}"]
        if link.translation is not None:
            parts.append("translation: " + _vec(link.translation))
        if link.rotation is not None:
            parts.append("rotation: " + _rotation(link.rotation))
        if link.dh is not None:
            d, theta, a, alpha = link.dh
            if link.joint == "revolute":
                d_s, theta_s = _num(d), _plus(link.coordinate, theta)
            else:
                d_s, theta_s = _plus(link.coordinate, d), _num(theta)
            parts.append(f"dh: [{d_s}, {theta_s}, {_num(a)}, {_num(alpha)}]")
        else:
            parts.append(f"{link.joint}: {link.coordinate}")
            parts.append("axis: " + _axis(link.axis))
        out.append("  - {" + ", ".join(parts) + "}")
        if link.tool is not None:
            translation, rot = link.tool
            tool = [f"name: {link.body_frame}", f"parent: {link.frame}", "translation: " + _vec(translation)]
            if rot is not None:
                tool.append("rotation: " + _rotation(rot))
            out.append("  - {" + ", ".join(tool) + "}")
        parent = link.frame
    out.append("bodies:")
    for link in chain.links:
        out.append(f"  - {{name: B{link.index}, frame: {link.body_frame}, mass: {link.mass_parameter}, "
                   f"com: {_vec(link.com)}, inertia: {_inertia(link)}}}")
    return "\n".join(out) + "\n"
