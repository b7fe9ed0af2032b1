"""Model reduction: bodies rigidly attached to one moving frame become one body.

A frame whose link is made only of constant translations and rotations
(parameters allowed; no coordinate, no time) moves with its nearest moving
ancestor, the root of its rigid group. Every body in a group is re-expressed
in the root's axes and the group is replaced by one body with the combined
mass properties (Featherstone, Rigid Body Dynamics Algorithms, §2.13):

    m = sum m_i
    c = sum m_i p_i / m
    I = sum R_i I_i R_i^T + m_i (|d_i|^2 E - d_i d_i^T),   d_i = p_i - c

where p_i, R_i place body i's COM frame in the root, and I_i is its inertia
about its COM in its own axes. The merged body sits on a new internal frame at
c with the root's axes, so M and G are unchanged and the generated code has
one element per moving frame instead of one per body. A URDF's fixed joints
and locked joints are the usual source of such groups.
"""

from __future__ import annotations

from dataclasses import replace

import sympy as sp

from andyc.spec.model import Body, Frame, Spec, Translate
from andyc.symbolic.kinematics import rigid_groups


def merge_rigid_bodies(spec: Spec) -> Spec:
    """`spec` with each rigid group's bodies merged into one (see the module docstring).

    Groups of one body are left as they are. Frames are kept (loads, springs,
    constraints and logged positions may name them); only the bodies change.
    """
    groups = rigid_groups(spec)
    by_root: dict[str, list[Body]] = {}
    for body in spec.bodies:
        by_root.setdefault(groups[body.frame][0], []).append(body)
    frames, bodies = list(spec.frames), []
    for root, members in by_root.items():
        if len(members) == 1:
            bodies.append(members[0])
            continue
        mass = sum((b.mass for b in members), sp.Integer(0))
        poses = [groups[b.frame][1:] for b in members]
        com = sum((b.mass * p for b, (_, p) in zip(members, poses)), sp.zeros(3, 1)) / mass
        inertia = sp.zeros(3, 3)
        for b, (R, p) in zip(members, poses):
            d = p - com
            inertia += R * b.inertia * R.T + b.mass * ((d.T * d)[0, 0] * sp.eye(3) - d * d.T)
        # Numbers stay numbers (a URDF's constants; exact rpy angles would otherwise carry their
        # sines and cosines into every entry); parameters stay symbolic.
        com, inertia = com.applyfunc(_number), inertia.applyfunc(_number)
        name = "+".join(b.name for b in members)
        frame = Frame(f"{root}__merged", root, (Translate(com),), members[0].where, internal=True)
        frames.append(frame)
        bodies.append(Body(name, frame.name, mass, inertia, members[0].where))
    return replace(spec, frames=frames, bodies=bodies)


def _number(expr):
    return sp.Float(expr.evalf(17)) if not expr.free_symbols else expr
