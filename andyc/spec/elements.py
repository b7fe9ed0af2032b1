"""Elements: bodies with their inertia, forces and torques, actuators, dampers, springs and potentials.

A body's COM or a force's point of action away from its frame's origin becomes a fixed child frame,
internal to andyc (`<element>__com`, `<element>__point`); elements at the same point share it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import sympy as sp

from andyc.spec.model import Actuator, Body, Damper, Frame, Load, Potential, Spring, Translate
from andyc.spec.scope import Scope
from andyc.spec.suggest import did_you_mean


@dataclass(frozen=True)
class Elements:
    bodies: list                # of Body
    loads: list                 # of Load: the forces, then the torques
    actuators: list             # of Actuator
    dampers: list               # of Damper
    springs: list               # of Spring
    potentials: list            # of Potential
    offset_frames: list         # of Frame (internal): the COMs and points of action off a frame's origin


def build_elements(data: dict, scope: Scope, urdf_bodies: int = 0) -> Elements:
    """Every element section, in this order.

    The first `urdf_bodies` bodies come from a URDF, whose reader checked (and warned about) their mass and
    inertia: like Pinocchio, andyc simulates them as written (massless inertia, broken triangle inequality).
    """
    offset_frames: list[Frame] = []
    bodies = [_body(i, b, scope, offset_frames, urdf_bodies) for i, b in enumerate(data.get("bodies") or [])]
    loads = [_force_or_torque(kind, i, f, scope, offset_frames)
             for kind, section in (("force", "forces"), ("torque", "torques"))
             for i, f in enumerate(data.get(section) or [])]
    actuators = [_actuator(i, x, scope) for i, x in enumerate(data.get("actuators") or [])]
    dampers = [_damper(i, x, scope, offset_frames) for i, x in enumerate(data.get("dampers") or [])]
    springs = [_spring(i, x, scope) for i, x in enumerate(data.get("springs") or [])]
    potentials = [Potential(x["name"], scope.expr(x["energy"], ("potentials", i, "energy"), scope.kinematic,
                                                  "potentials use parameters, coordinates and t"),
                            ("potentials", i)) for i, x in enumerate(data.get("potentials") or [])]
    for p in potentials:
        _no_step(p.energy, p.where + ("energy",), "potential energy", scope)
    for s in springs:
        if s.length is not None:
            _no_step(s.length, s.where + ("length",), "spring length", scope)
    return Elements(bodies, loads, actuators, dampers, springs, potentials, offset_frames)


def _no_step(value, path: tuple, what: str, scope: Scope) -> None:
    """Report a potential energy or a spring length that steps with a coordinate (sign() of it): its force,
    the derivative by the coordinates, is an impulse at the step (DiracDelta), which no code computes."""
    if not value.has(sp.sign):
        return
    coordinates = {c.q: c.name for c in scope.coordinates}
    stepping = sorted(name for q, name in coordinates.items() if value.diff(q).has(sp.DiracDelta))
    if stepping:
        scope.report.error(path, f"the {what} steps where sign() of {', '.join(stepping)} changes: its force "
                           "(the derivative by the coordinates) is infinite there", "write a continuous "
                           f"{what} (abs(x) for sign(x)*x; a smooth step such as tanh(x/eps) for sign(x))")


def _offset_frame(owner: str, frame: str, offset, where, scope: Scope, offset_frames: list) -> str:
    """A fixed child of `frame` at `offset` (frame axes), added to `offset_frames`; returns its name.

    Elements at the same point (a body's COM and a damper on it) share one
    frame, so its kinematics are computed once.
    """
    vec = scope.vector(offset, where, scope.parameter_names, "offsets use parameters only")
    if vec == sp.zeros(3, 1):
        return frame
    for f in offset_frames:
        if f.parent == frame and f.transforms == (Translate(vec),):
            return f.name
    name = f"{owner}__{where[-1]}"
    offset_frames.append(Frame(name, frame, (Translate(vec),), where, internal=True))
    return name


# -- bodies -----------------------------------------------------------------------

def _body(i: int, b: dict, scope: Scope, offset_frames: list, urdf_bodies: int) -> Body:
    where = ("bodies", i)
    before = len(scope.report.problems)
    mass, m = scope.constant(b["mass"], where + ("mass",))
    if len(scope.report.problems) == before and not m > 0 and i >= urdf_bodies:   # (a bad expression: reported)
        value = f"{m:g}" if mass.is_number else f"{b['mass']} = {m:g}"
        scope.report.error(where + ("mass",), f"mass must be positive, got {value}", "give a positive mass in kg")
    inertia = _inertia(b.get("inertia", [0, 0, 0]), where + ("inertia",), scope, urdf_bodies)
    frame = b["frame"]
    if scope.known_frame(frame, where + ("frame",)) and "com" in b:
        frame = _offset_frame(b["name"], frame, b["com"], where + ("com",), scope, offset_frames)
    return Body(b["name"], frame, mass, inertia, where)


def _inertia(value, where, scope: Scope, urdf_bodies: int) -> sp.Matrix:
    """The 3x3 inertia about the COM from any of its three forms; a symmetric, positive semi-definite
    matrix whose principal moments obey the triangle inequality (checked at the parameters' defaults)."""
    before = len(scope.report.problems)
    if len(value) == 3 and all(isinstance(r, list) for r in value):
        rows = [[scope.constant(x, where + (i, j))[0] for j, x in enumerate(row)] for i, row in enumerate(value)]
        mat = sp.Matrix(rows)
    elif len(value) == 3:
        mat = sp.diag(*[scope.constant(x, where + (i,))[0] for i, x in enumerate(value)])
    else:
        xx, yy, zz, xy, xz, yz = (scope.constant(x, where + (i,))[0] for i, x in enumerate(value))
        mat = sp.Matrix([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    if len(scope.report.problems) > before or where[1] < urdf_bodies:     # reported already, or a URDF's
        return mat
    try:
        num = np.array(mat.subs(scope.defaults), dtype=float)
    except (TypeError, ValueError):
        return mat
    if not np.allclose(num, num.T, rtol=1e-12, atol=1e-12 * max(1.0, abs(num).max())):
        i, j = np.unravel_index(np.argmax(abs(num - num.T)), num.shape)
        scope.report.error(where, f"inertia is not symmetric: I[{i}][{j}] = {num[i, j]:g} but "
                           f"I[{j}][{i}] = {num[j, i]:g}",
                           "make the off-diagonal pairs equal (an inertia tensor is symmetric)")
        return mat
    eig = np.linalg.eigvalsh(num)
    scale = max(1.0, abs(eig).max())
    if eig.min() < -1e-12 * scale:
        scope.report.error(where, "inertia is not positive semi-definite (principal moments "
                           f"{', '.join(f'{e:g}' for e in eig)})",
                           "check signs: the diagonal is positive and products of inertia are -sum(m x y)")
    elif any(eig[a] + eig[b] < eig[c] - 1e-9 * scale for a, b, c in ((0, 1, 2), (0, 2, 1), (1, 2, 0))):
        scope.report.error(where, f"principal moments {', '.join(f'{e:g}' for e in eig)} break the triangle "
                           "inequality",
                           "no rigid body has these moments (each must be at most the sum of the other two)")
    return mat


# -- forces, torques, dampers, springs ---------------------------------------------

def _force_or_torque(kind: str, i: int, f: dict, scope: Scope, offset_frames: list) -> Load:
    section = "forces" if kind == "force" else "torques"
    where = (section, i)
    frame = f["frame"]
    in_frame = f.get("in", "world")
    ok = scope.known_frame(frame, where + ("frame",))
    scope.known_frame(in_frame, where + ("in",))
    if ok and "point" in f:
        if kind == "torque":
            scope.report.error(where + ("point",), "a torque has no point of action", "remove 'point'")
        else:
            frame = _offset_frame(f["name"], frame, f["point"], where + ("point",), scope, offset_frames)
    vec = scope.vector(f["vector"], where + ("vector",), scope.forcing,
                       "forces use parameters, inputs, coordinates and t")
    return Load(f["name"], kind, frame, vec, in_frame, where)


def _actuator(i: int, x: dict, scope: Scope) -> Actuator:
    where = ("actuators", i)
    driven = [c.name for c in scope.coordinates] + [s.name for s in scope.speeds]
    if x["coordinate"] not in driven:
        scope.report.error(where + ("coordinate",), f"'{x['coordinate']}' is not a coordinate or a speed",
                           did_you_mean(x["coordinate"], driven) + "coordinates and speeds: " + ", ".join(driven))
    force = scope.expr(x["force"], where + ("force",), {**scope.forcing, **scope.rates},
                       "an actuator's force uses parameters, inputs, coordinates, speeds (<coordinate>_dot), "
                       "discrete states and t")
    limit = None
    if "limit" in x:
        before = len(scope.report.problems)
        limit, value = scope.constant(x["limit"], where + ("limit",))
        if len(scope.report.problems) == before and not value > 0:
            scope.report.error(where + ("limit",), f"the limit {x['limit']!r} = {value:g} is not > 0",
                               "give the largest |force| the actuator can exert (a motor's effort limit), > 0")
    return Actuator(x["name"], x["coordinate"], force, limit, where)


def _damper(i: int, x: dict, scope: Scope, offset_frames: list) -> Damper:
    where = ("dampers", i)
    coef, value = scope.constant(x["coefficient"], where + ("coefficient",))
    speed = x.get("speed")
    damped = [c.name for c in scope.coordinates] + [s.name for s in scope.speeds]
    if speed is not None and speed not in damped:
        scope.report.error(where + ("speed",), f"'{speed}' is not a coordinate or a speed",
                           did_you_mean(speed, damped) + "coordinates and speeds: " + ", ".join(damped))
    frame = x.get("frame")
    if frame is not None and scope.known_frame(frame, where + ("frame",)) and "point" in x:
        if x.get("angular"):
            scope.report.error(where + ("point",), "an angular damper has no point", "remove 'point'")
        else:
            frame = _offset_frame(x["name"], frame, x["point"], where + ("point",), scope, offset_frames)
    for key in ("angular", "point"):
        if key in x and "frame" not in x:
            scope.report.error(where + (key,), f"'{key}' goes with 'frame'", "remove it, or damp a frame")
    if x.get("law") == "coulomb":
        if frame is not None:
            scope.report.error(where + ("frame",), "a coulomb damper acts on one speed, not on a frame",
                               "give 'speed: <coordinate or speed>' (a joint's dry friction) instead of 'frame'")
        elif value < 0:
            scope.report.error(where + ("coefficient",), f"the friction force is {value:g}, negative",
                               "give a force (a torque on a rotation) >= 0: a number or an expression of parameters")
    return Damper(x["name"], coef, x.get("law", "linear"), speed, frame, bool(x.get("angular", False)), where)


def _spring(i: int, x: dict, scope: Scope) -> Spring:
    where = ("springs", i)
    k, _ = scope.constant(x["stiffness"], where + ("stiffness",))
    rest, _ = scope.constant(x.get("rest_length", 0), where + ("rest_length",))
    length = between = None
    if "length" in x:
        length = scope.expr(x["length"], where + ("length",), scope.kinematic,
                            "spring lengths use parameters, coordinates and t")
    else:
        between = tuple(x["between"])
        for j, name in enumerate(between):
            scope.known_frame(name, where + ("between", j))
        if between[0] == between[1]:
            scope.report.error(where + ("between",), "a spring needs two different frames", "name two frames")
    return Spring(x["name"], k, rest, length, between, where)
