"""Frames: each link of the model file lowered to the elementary steps of andyc.spec.model.

A link is an optional fixed `translation` and `rotation` (axis-angle, roll-pitch-yaw or a quaternion),
then at most one joint: `dh` (Rz(theta) Tz(d) Tx(a) Rx(alpha)), `revolute` or `prismatic` about an
`axis`, or a link given by its velocity (ANDY eq. 4): `ball` and `floating` driven by declared speeds,
`nonholonomic` by expressions linear in the speeds. Those create signals, states with their own ODE: a
position <frame>_x/_y/_z and a quaternion <frame>_qw/_qx/_qy/_qz.

Frames come out parents before children, whatever their order in the file.
"""

from __future__ import annotations

import math

import sympy as sp

from andyc.spec.expressions import TIME
from andyc.spec.model import Frame, Nonholonomic, Rotate, Signal, Translate
from andyc.spec.scope import Scope
from andyc.spec.suggest import did_you_mean

AXES = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1),
        "-x": (-1, 0, 0), "-y": (0, -1, 0), "-z": (0, 0, -1)}
JOINTS = ("dh", "revolute", "prismatic", "ball", "floating", "nonholonomic")


def build_frames(raw: list, scope: Scope) -> tuple[list[Frame], list[Signal]]:
    """The frames of the `frames:` section, parents before children, and the signals their links create.

    A cycle or an unknown parent is reported; the frames on it are still built (without their place in
    the tree), so their own problems are reported too."""
    by_name = {}
    for i, f in enumerate(raw):
        by_name.setdefault(f["name"], i)
    known = sorted(by_name) + ["world"]
    ordered, state = [], {}

    def visit(i, trail):
        name = raw[i]["name"]
        if state.get(name) == "done":
            return
        if name in trail:
            cycle = trail[trail.index(name):] + [name]
            scope.report.error(("frames", i, "parent"), "the frame graph has a cycle: " + " -> ".join(cycle),
                               "give one of these frames another parent (frames form a tree rooted at 'world')")
            for n in cycle:
                state[n] = "done"
            return
        parent = raw[i]["parent"]
        if parent != "world":
            if parent not in by_name:
                scope.report.error(("frames", i, "parent"), f"parent frame '{parent}' does not exist",
                                   did_you_mean(parent, known) + "known frames: " + ", ".join(known))
            else:
                visit(by_name[parent], trail + [name])
        if state.get(name) != "done":
            state[name] = "done"
            ordered.append(i)

    for i in range(len(raw)):
        visit(i, [])
    signals: list[Signal] = []
    frames = [_frame(i, raw[i], scope, signals) for i in ordered]
    return frames, signals


def _frame(i: int, f: dict, scope: Scope, signals: list) -> Frame:
    """One frame; the signals of its link are appended to `signals`."""
    where = ("frames", i)
    ctx = "link expressions use parameters, coordinates and t"
    steps = []
    if "translation" in f:
        steps.append(Translate(sp.Matrix([_link_expr(v, where + ("translation", k), scope, ctx)
                                          for k, v in enumerate(f["translation"])])))
    if "rotation" in f:
        steps += _rotation(f["rotation"], where + ("rotation",), scope)
    joints = [k for k in JOINTS if k in f]
    if len(joints) > 1:
        scope.report.error(where, f"a frame has one joint, got {' and '.join(joints)}",
                           "split the link into two frames")
    if "axis" in f and not ({"revolute", "prismatic"} & set(f)):
        scope.report.error(where + ("axis",), "'axis' belongs to a revolute or prismatic joint",
                           "add 'revolute: <coordinate>' or remove 'axis'")
    if "dh" in f:
        d_, theta, a, alpha = (_link_expr(x, where + ("dh", k), scope, ctx) for k, x in enumerate(f["dh"]))
        steps += [Rotate(sp.Matrix([0, 0, 1]), theta), Translate(sp.Matrix([a, 0, d_])),
                  Rotate(sp.Matrix([1, 0, 0]), alpha)]
    for kind in ("revolute", "prismatic"):
        if kind in f:
            axis = _axis(f.get("axis", "z"), where + ("axis",), scope)
            value = _link_expr(f[kind], where + (kind,), scope, ctx)
            steps.append(Rotate(axis, value) if kind == "revolute" else Translate(axis * value))
    # A zero offset or angle (a joint at its origin, written out) is no step: the kinematics stay shorter.
    steps = [s for s in steps if not (isinstance(s, Translate) and s.vector == sp.zeros(3, 1))
             and not (isinstance(s, Rotate) and s.angle == 0)]
    for kind in ("ball", "floating", "nonholonomic"):
        if kind in f and len(joints) == 1:
            steps.append(_nonholonomic_link(f["name"], kind, f[kind], where + (kind,), scope, signals))
    return Frame(f["name"], f["parent"], tuple(steps), where, joint=joints[0] if len(joints) == 1 else "fixed")


def _link_expr(value, path: tuple, scope: Scope, ctx: str) -> sp.Expr:
    """A link's offset or angle: an expression of parameters, coordinates and t, smooth in the coordinates and
    t (the kinematics are differentiated twice along the motion: abs, sign, min or max of them would give
    derivatives that jump, or none, where they switch)."""
    e = scope.expr(value, path, scope.kinematic, ctx)
    moving = {c.q for c in scope.coordinates} | {TIME}
    kinks = sorted({str(f.func).lower() for f in sp.preorder_traversal(e)
                    if isinstance(f, (sp.Abs, sp.sign, sp.Min, sp.Max)) and f.free_symbols & moving})
    if kinks:
        scope.report.error(path, f"in {value!r}: the link is not smooth: its speeds and accelerations jump where "
                           f"{' or '.join(kinks)} of a coordinate or of t switches branch", "write a smooth "
                           "expression (e.g. sqrt(x**2 + eps**2) for abs(x), tanh(x/eps) for sign(x)), or keep one "
                           "branch and end the flow with a guard where it would switch")
        return sp.Integer(0)
    return e


def _rotation(r: dict, where, scope: Scope) -> list:
    ctx = "rotation angles use parameters, coordinates and t"
    if "axis" in r:
        return [Rotate(_axis(r["axis"], where + ("axis",), scope),
                       _link_expr(r["angle"], where + ("angle",), scope, ctx))]
    if "rpy" in r:
        roll, pitch, yaw = (_link_expr(x, where + ("rpy", k), scope, ctx) for k, x in enumerate(r["rpy"]))
        # R = Rz(yaw) Ry(pitch) Rx(roll): applied left to right as z, then y, then x.
        return [Rotate(sp.Matrix([0, 0, 1]), yaw), Rotate(sp.Matrix([0, 1, 0]), pitch),
                Rotate(sp.Matrix([1, 0, 0]), roll)]
    w, x, y, z = (float(e) for e in _quaternion(r["quaternion"], where + ("quaternion",), scope))
    s = math.sqrt(x * x + y * y + z * z)
    angle = 2 * math.atan2(s, w)
    if angle == 0:
        return []
    return [Rotate(sp.Matrix([sp.Float(x / s, 17), sp.Float(y / s, 17), sp.Float(z / s, 17)]), sp.Float(angle, 17))]


def _axis(value, where, scope: Scope) -> sp.Matrix:
    """A unit axis from a name (x, -y, ...) or three numbers; z after a reported problem."""
    vec = AXES[value] if isinstance(value, str) else value
    if not all(math.isfinite(float(x)) for x in vec):
        scope.report.error(where, f"the axis {vec} is not finite", "give a direction such as [0, 0, 1] or z")
        return sp.Matrix([0, 0, 1])
    norm = math.hypot(*(float(x) for x in vec))     # (no overflow: [1e308, 1e308, 0] has a norm)
    if norm < 1e-12:
        scope.report.error(where, "the axis is zero", "give a direction such as [0, 0, 1] or z")
        return sp.Matrix([0, 0, 1])
    # Exact when the norm is rational (z, [0, 0.6, 0.8]) so that zeros stay
    # structural; otherwise 17-digit floats, not a huge exact surd.
    m = sp.Matrix([sp.Rational(repr(float(x))) for x in vec])
    norm = sp.sqrt(sum(x ** 2 for x in m))
    if norm.is_Rational:
        return m / norm
    return sp.Matrix([sp.Float(float(x) / float(norm), 17) for x in m])


def _quaternion(values, where, scope: Scope) -> list:
    """A unit quaternion of constants; an error names the value and its norm.

    After a reported problem it returns the identity, so later checks stay quiet.
    """
    identity = [sp.Integer(1), sp.Integer(0), sp.Integer(0), sp.Integer(0)]
    before = len(scope.report.problems)
    exprs = [scope.expr(v, where + (i,), {}, "initial quaternions are constants", allow_time=False)
             for i, v in enumerate(values)]
    if len(scope.report.problems) > before:     # a bad entry is reported already
        return identity
    nums = [float(e) for e in exprs]
    norm = math.hypot(*nums)                # (no overflow for huge entries)
    if abs(norm - 1.0) > 1e-9:
        unit = ", ".join(f"{c / norm:.12g}" for c in nums) if norm > 0 else "1, 0, 0, 0"
        scope.report.error(where, f"quaternion [{', '.join(f'{c:g}' for c in nums)}] has norm {norm:.12g}, not 1",
                           f"use the unit quaternion [{unit}]")
        return identity
    return exprs


# -- links given by their velocity (ANDY eq. 4) ---------------------------------

def _nonholonomic_link(frame: str, kind: str, link: dict, where, scope: Scope, signals: list) -> Nonholonomic:
    """A ball, floating or general nonholonomic link; its signals are appended to `signals`."""
    if kind == "nonholonomic":
        ctx = ("nonholonomic velocities use parameters, coordinates, speeds, "
               "<coordinate>_dot and t")
        names = {**scope.kinematic, **scope.rates}
        vel = (scope.vector(link["velocity"], where + ("velocity",), names, ctx)
               if "velocity" in link else None)
        ang = (scope.vector(link["angular_velocity"], where + ("angular_velocity",), names, ctx)
               if "angular_velocity" in link else None)
        for key, value in (("velocity", vel), ("angular_velocity", ang)):
            if value is not None:
                _check_linear(value, link[key], where + (key,), scope)
        for key, needs in (("position", "velocity"), ("quaternion", "angular_velocity")):
            if key in link and needs not in link:
                scope.report.error(where + (key,), f"'{key}' goes with '{needs}'",
                                   f"add '{needs}:' or remove '{key}' (a fixed offset is 'translation' or 'rotation')")
    else:
        count = 3 if kind == "ball" else 6
        speeds = _joint_speeds(link["speeds"], count, kind, where + ("speeds",), scope)
        vel = sp.Matrix(speeds[:3]) if kind == "floating" else None
        ang = sp.Matrix(speeds[-3:])
    position = quaternion = None
    if vel is not None:
        init = scope.vector(link.get("position", [0, 0, 0]), where + ("position",), scope.parameter_names,
                            "initial positions use parameters")
        position = tuple(_signal(frame, c, init[i], where + ("position",), signals) for i, c in enumerate("xyz"))
    if ang is not None:
        init = _quaternion(link.get("quaternion", [1, 0, 0, 0]), where + ("quaternion",), scope)
        quaternion = tuple(_signal(frame, f"q{c}", init[i], where + ("quaternion",), signals)
                           for i, c in enumerate("wxyz"))
    return Nonholonomic(vel, ang, link.get("in", "body") == "body", position, quaternion)


def _joint_speeds(names: list, count: int, kind: str, where, scope: Scope) -> list:
    """The symbols of a ball's (3) or floating link's (6) declared speeds; 0 for each one reported."""
    what = "the angular velocity [wx, wy, wz]" if count == 3 else "[vx, vy, vz, wx, wy, wz]"
    if len(names) != count:
        scope.report.error(where, f"a {kind} joint has {count} speeds, got {len(names)}",
                           f"list {count} speeds declared under 'speeds:': {what}")
        return [sp.Integer(0)] * count
    known = {s.name: s.v for s in scope.speeds}
    out = []
    for j, name in enumerate(names):
        if name not in known:
            scope.report.error(where + (j,), f"'{name}' is not a declared speed",
                               did_you_mean(name, known)
                               + "declare it under 'speeds:' (speeds: " + (", ".join(known) or "none") + ")")
            out.append(sp.Integer(0))
        else:
            out.append(known[name])
            scope.report.used.add(known[name])
    for j, name in enumerate(names):
        if name in names[:j]:
            scope.report.error(where + (j,), f"speed '{name}' is listed twice", "list distinct speeds")
    return out


def _check_linear(vec: sp.Matrix, written: list, where, scope: Scope):
    """Velocities must be linear in the speeds: v = J(q, t) speeds + b(q, t)."""
    speeds = list(scope.rates.values())
    for i, e in enumerate(vec):
        if any(sp.diff(e, a, b) != 0 for a in speeds for b in speeds):
            scope.report.error(where + (i,), f"in {written[i]!r}: the velocity is not linear in the speeds",
                               "a velocity is J(q, t) * speeds + b(q, t); speeds may not be squared, "
                               "multiplied together or inside functions")


def _signal(frame: str, component: str, initial, where, signals: list) -> sp.Symbol:
    name = f"{frame}_{component}"
    sym = sp.Symbol(f"s_{name}", real=True)
    signals.append(Signal(name, component, sym, initial, frame, where))
    return sym
