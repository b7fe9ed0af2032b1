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
        # Numbers stay numbers (a URDF's constants), computed at PRECISION digits: exact rpy angles would
        # otherwise carry their sines and cosines into every entry, whose evaluation then costs seconds each
        # (g1: 23 s); parameters stay symbolic.
        members = [(_precise(b.mass), _precise(b.inertia), *map(_precise, groups[b.frame][1:])) for b in members]
        mass = sum((b.mass for b in by_root[root]), sp.Integer(0))
        com = sum((m * p for m, _, _, p in members), sp.zeros(3, 1)) / _precise(mass)
        inertia = sp.zeros(3, 3)
        for m, I, R, p in members:
            d = p - com
            inertia += R * I * R.T + m * ((d.T * d)[0, 0] * sp.eye(3) - d * d.T)
        com, inertia = _rounded(com), _rounded(inertia)
        name = "+".join(b.name for b in by_root[root])
        frame = Frame(f"{root}__merged", root, (Translate(com),), by_root[root][0].where, internal=True)
        frames.append(frame)
        bodies.append(Body(name, frame.name, mass, inertia, by_root[root][0].where))
    return replace(spec, frames=frames, bodies=bodies)


PRECISION = 40     # digits of the merged numbers' arithmetic; each is rounded to 17 (a double's) at the end
ZERO = 1e-30       # ... and set to 0 below ZERO times the largest of its matrix: what cancels exactly in exact
                   # arithmetic (R I R^T's products of inertia of a body on a rotated axis) leaves ~1e-40 here


def _precise(value):
    """A number, or each number of a matrix, as a Float of PRECISION digits; symbolic entries as they are."""
    if isinstance(value, sp.MatrixBase):
        return value.applyfunc(_precise)
    return value if value.free_symbols else sp.Float(value.evalf(PRECISION), PRECISION)


def _rounded(matrix):
    """Each number of `matrix` to a double's 17 digits, a numeric entry to 0 below ZERO times the largest (see
    ZERO)."""
    scale = max((abs(e) for e in matrix if not e.free_symbols), default=0)
    return matrix.applyfunc(lambda e: e.evalf(17) if e.free_symbols else
                            sp.Float(0 if abs(e) <= ZERO * scale else e, 17))
