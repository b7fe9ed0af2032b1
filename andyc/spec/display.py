"""What the pictures of a run need to know about its model, as plain data (`display(spec)`): it goes into
the generated module (DISPLAY, in METADATA) and from there into every run file, so that `andyc plot` and
`andyc view` need nothing but the run.

- 'units': {state name: unit} for the states whose unit the model says: a coordinate that turns a
  revolute, DH or rotation step only is an angle ('rad'), one that moves translations only a length
  ('m'); its rate 'rad/s' or 'm/s'; a ball's, floating or nonholonomic link's speeds 'rad/s' (angular
  velocity) or 'm/s' (velocity); position signals 'm', quaternion signals '1'. A coordinate used both
  ways, or by no link (a constraint's only), is left out: its unit is not known.
- 'ground': {'axis': k, 'height': h} when a constraint row or a jump guard holds a frame at world axis k
  = h (a foot on the ground: `foot.y`, `ball.y - r`; or the coordinate that is that frame's height, as a
  bouncing ball's `y`), with gravity pulling along -k; else None. The plots shade the ground only then.
- 'contacts': [{'name', 'frame', 'normal', 'offset', 'tangents'}] for each contact whose gap is a plane: linear,
  with numbers (at the parameters' defaults) for coefficients, in the world position of one frame's origin:
  gap = normal . p + offset (normal a unit vector). The plane normal . p + offset = 0 is where that origin
  touches (a sphere's centre: the ground lifted by its radius); 'tangents' the friction's directions, from its
  slip speeds' velocity terms (none without friction). `andyc view` draws the ground and the force arrows
  from them. A gap between two frames (Newton's cradle) or of a joint (a URDF limit) is not a plane: left out.
- 'plane': the YAML's `ground:` plane {'normal' (unit), 'offset'}: normal . p + offset = 0, or None. The
  ground itself, which the contacts' planes above lift by a sphere's radius: `andyc view` draws this one
  when the model has it.
- 'shapes': what `andyc view` draws on the frames: the YAML's `shape:` keys, then the URDF's visuals
  (andyc.spec.shapes), sizes in numbers, mesh files by their absolute path.
"""

from __future__ import annotations

import sympy as sp

from andyc.spec.model import Nonholonomic, Rotate, Translate
from andyc.spec.shapes import urdf_shapes


def display(spec) -> dict:
    """{'units': {state: unit}, 'ground': {'axis', 'height'} | None, 'shapes': [shape]}; see the module's
    docstring."""
    plane = None
    if spec.ground is not None:
        plane = {"normal": [float(x) for x in spec.ground.normal], "offset": -float(spec.ground.height)}
    return {"units": units(spec), "ground": ground(spec), "contacts": contact_planes(spec), "plane": plane,
            "shapes": spec.shapes + urdf_shapes(spec.visuals)}


def units(spec) -> dict:
    """{state name: 'rad' | 'm' | 'rad/s' | 'm/s' | '1'} for the states whose unit the links say."""
    turns, moves = set(), set()
    angular, linear = set(), set()
    for f in spec.frames:
        for step in f.transforms:
            if isinstance(step, Rotate):
                turns |= step.angle.free_symbols
            elif isinstance(step, Translate):
                moves |= step.vector.free_symbols
            elif isinstance(step, Nonholonomic):
                if step.angular_velocity is not None:
                    angular |= step.angular_velocity.free_symbols
                if step.velocity is not None:
                    linear |= step.velocity.free_symbols
    out = {}
    for c in spec.coordinates:
        if (c.q in turns) != (c.q in moves):
            unit = "rad" if c.q in turns else "m"
            out[c.name], out[f"{c.name}_dot"] = unit, unit + "/s"
    for s in spec.speeds:
        if (s.v in angular) != (s.v in linear):
            out[s.name] = "rad/s" if s.v in angular else "m/s"
    for s in spec.signals:
        out[s.name] = "m" if s.component in ("x", "y", "z") else "1"
    return out


def ground(spec) -> dict | None:
    """The ground a constraint row or a jump guard defines (see the module's docstring), or None."""
    values = {symbol: value for symbol, value in spec.parameters.values()}
    try:
        gravity = [float(g.subs(values)) for g in spec.gravity]
    except (TypeError, ValueError):
        return None
    heights = _translated_heights(spec)
    expressions = [(row, c.quantities) for c in spec.constraints if c.holonomic for row in c.rows]
    expressions += [(j.guard, j.quantities) for j in spec.jumps]
    for expr, quantities in expressions:
        candidates = [(sym, q.axis) for sym, q in quantities.items()
                      if q.kind == "position" and q.in_frame == "world"]
        candidates += [(height, axis) for height, axis in heights]
        for term, axis in candidates:
            if gravity[axis] >= 0 or abs(gravity[axis]) < 0.5 * max(abs(g) for g in gravity):
                continue        # the ground's normal points against gravity, near enough
            rest = sp.expand(expr - term)
            if rest.free_symbols <= set(values):
                try:
                    return {"axis": axis, "height": float(-rest.subs(values))}
                except (TypeError, ValueError):
                    continue
    return None


def _translated_heights(spec) -> list:
    """[(expression, axis)]: each world coordinate of the frames reached from world by translations only
    (a bouncing ball's y), as the expression that gives it."""
    position = {"world": sp.zeros(3, 1)}
    for f in spec.frames:
        if f.parent in position and all(isinstance(s, Translate) for s in f.transforms):
            position[f.name] = position[f.parent] + sum((s.vector for s in f.transforms), sp.zeros(3, 1))
    out = []
    for name, r in position.items():
        for axis in range(3):
            if name != "world" and r[axis].free_symbols & {c.q for c in spec.coordinates}:
                out.append((r[axis], axis))
    return out


def contact_planes(spec) -> list:
    """The contacts whose gap is a plane (see the module's docstring)."""
    values = {symbol: value for symbol, value in spec.parameters.values()}
    rows = {c.name: c for c in spec.constraints}
    out = []
    for contact in spec.contacts:
        gap = rows.get(contact.constraint)
        found = _linear(gap.rows[0], gap.quantities, "position", values) if gap is not None else None
        if found is None:
            continue
        frame, a, b = found
        norm = sum(x * x for x in a) ** 0.5
        if not norm > 0:
            continue
        tangents = []
        stick = rows.get(contact.stick) if contact.stick else None
        for row in (stick.rows if stick is not None else ()):
            slip = _linear(row, stick.quantities, "velocity", values, frame)
            if slip is not None and sum(x * x for x in slip[1]) > 0:
                t = slip[1]
                tangents.append([x / sum(y * y for y in t) ** 0.5 for x in t])
        out.append({"name": contact.name, "frame": frame, "normal": [x / norm for x in a], "offset": b / norm,
                    "tangents": tangents})
    return out


def _linear(expr, quantities: dict, kind: str, values: dict, frame: str | None = None):
    """(frame, [a_x, a_y, a_z], b) when `expr` at the parameters' defaults is a . r + b, r the world `kind`
    (position, velocity) of one frame's origin (`frame` if given) and a, b numbers; other frame quantities of
    that frame (a slip's angular-velocity terms, a sphere's rolling) count as 0; else None."""
    ours = {sym: q for sym, q in quantities.items() if q.kind == kind and q.in_frame == "world"}
    frames = {q.frame for q in ours.values()}
    if len(frames) != 1 or (frame is not None and frames != {frame}):
        return None
    (name,) = frames
    others = {sym: 0 for sym, q in quantities.items() if sym not in ours and q.frame == name}
    e = sp.expand(sp.sympify(expr).subs(values).subs(others))
    a = [0.0, 0.0, 0.0]
    rest = e
    for sym, q in ours.items():
        coefficient = sp.diff(e, sym)
        if coefficient.free_symbols:
            return None
        a[q.axis] += float(coefficient)
        rest -= coefficient * sym
    rest = sp.simplify(rest)
    if rest.free_symbols:
        return None
    return name, a, float(rest)
