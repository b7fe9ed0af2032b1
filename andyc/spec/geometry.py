"""Contacts made from geometry: a ground plane (`ground:`) and the shapes that touch it.

A shape that collides (a YAML `shape:` with `collide: true`, a URDF link's `<collision>` named in
`urdf: {collide: [...]}`) becomes ordinary `contacts:` entries, one per contact point, and the frames
those points are on; the loader then reads them as it reads hand-written ones (andyc.spec.contacts,
andyc.spec.constraints), so the same checks and the same located messages apply, and the rest of the
pipeline never knows where a contact came from.

The ground is the plane n . p = h (n a unit normal in world, h its height along n): a point p with
n . p >= h is above it. Its tangents: t1 = world x projected on the plane and normalized (world y when
|n_x| > 0.9), t2 = n x t1 (for n = z: t1 = x, t2 = y); with `tangent:` given, friction is planar along
that direction (projected on the plane) alone.

Each shape gives contact points fixed in its frame, each a point P with a radius r (0 for a corner):

    sphere      its centre, r = its radius: gap = n . c - r - h, slip_k = t_k . (v_c + w x (-r n))
                (the velocity of the material point touching the plane, w the frame's angular velocity)
    capsule     the centres of its two half-spheres, each a sphere of its radius (exact: a capsule's
                lowest point is always one of its half-spheres' lowest points)
    box         its 8 corners, r = 0: gap = n . p - h, slip_k = t_k . v_p (exact for a box on a plane:
                a face or an edge down is its corners down)
    cylinder    its two rim circles, each sampled at RIM_POINTS = 8 points, r = 0: exact standing on an
                end face (its rim points are its lowest ones) or on an edge at a sampled point; lying
                on its side it rests on a regular octagon's edge and may sink up to r (1 - cos(pi/8)) =
                0.076 r between points, and it rolls as an octagon. Why not the exact lowest rim point
                c +- (L/2) a - r u, u the plane's normal projected on the end face: u is undefined
                standing upright, where the gap n.c +- (L/2)(n.a) - r sqrt(1 - (n.a)^2) has a kink
                (infinite derivative) at the very pose a cylinder rests in; the constraint rows need
                their derivatives along the motion, so smooth rows at body-fixed points are kept.
    mesh        refused (URDF: a warning naming the link; YAML: an error): its vertices would be
                thousands of contacts, and its bounding box's corners would hold it off the ground
                where the mesh does not reach. Not yet.

Frames: a point at the shape's frame origin uses that frame itself (a URDF foot sphere at its link's
origin gives `gap: FR_foot.z - 0.02`); any other point gets a frame fixed to it, translation only (a
point's orientation plays no part), named after the contact: `<contact>_centre` (a sphere's centre)
or `<contact>_point` (a corner, a rim point). Contact names: `<base>_<suffix>`, base the link (URDF:
non-identifier characters become '_') or the YAML frame or body carrying the shape, followed by
`_<k>` (the shape's index on it) when it carries more than one; suffixes `sphere`, `end_p` / `end_m`
(capsule, +-axis), `corner_<sx><sy><sz>` (box; p for +, m for - along the box's x, y, z),
`rim_p_<k>` / `rim_m_<k>` (cylinder, the rim at +-axis, k = 0..7 at angle 2 pi k / 8 from the
shape's x towards its y for a cylinder along z; along another axis a, from the first of x, y
perpendicular enough to a, projected, towards a x that).

Model text never reaches the rows: the gap and slip expressions are written here from numbers formatted
with repr (the shape's sizes and place, the ground's normal and height: numbers, not expressions of
parameters, for this reason and because a contact's geometry shapes the equations) and frame names
andyc made identifiers; the friction and restitution given are expressions of parameters, read by the
safe parser like a hand-written contact's.

No geometry library: a primitive against a plane is the closed form above (a support point per
direction, a few lines), and the rows must be symbolic expressions of frame quantities that andyc
differentiates along the motion, which a distance query at one configuration (coal / hpp-fcl,
python-fcl, trimesh) does not give. A library would serve meshes (a convex hull's vertices:
trimesh is installed with the project), which are not done.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from andyc.errors import Diagnostic
from andyc.spec.expressions import ExpressionError, parse
from andyc.spec.frames import AXES
from andyc.spec.urdflinks import rpy_matrix
from andyc.spec.yamlpos import SourceMap

RIM_POINTS = 8                  # points per rim circle of a cylinder
PRIMITIVES = ("sphere", "box", "cylinder", "capsule")


@dataclass(frozen=True)
class Ground:
    """The plane n . p = h, n unit (world); `tangents` the friction's directions in it (one: planar)."""
    normal: tuple
    height: float
    tangents: tuple


@dataclass(frozen=True)
class Point:
    """A contact point of a shape: its place in the shape's frame and its radius (0: a corner)."""
    suffix: str
    position: tuple
    radius: float


# -- the ground ---------------------------------------------------------------

def ground_plane(raw, error) -> Ground | None:
    """The `ground:` mapping (None: no ground) checked; `error(path, message, hint)` reports a problem (path
    from the document's root). Defaults: normal z, height 0, spatial friction."""
    if raw is None:
        return None
    raw = raw if isinstance(raw, dict) else {}
    ok = True
    normal = _direction(raw.get("normal", "z"))
    if normal is None:
        error(("ground", "normal"), f"the normal {raw.get('normal')} is not a direction (zero or not finite)",
              "give the plane's upward normal, e.g. [0, 0, 1] (normalized for you)")
        ok, normal = False, np.array([0.0, 0.0, 1.0])
    height = raw.get("height", 0)
    if not (isinstance(height, (int, float)) and math.isfinite(height)):
        error(("ground", "height"), f"the height {height} is not a finite number",
              "give the plane's height along its normal in m, e.g. 0")
        ok, height = False, 0.0
    if "tangent" in raw:
        t = _direction(raw["tangent"])
        t = None if t is None else t - t.dot(normal) * normal
        if t is None or not np.linalg.norm(t) > 1e-9:
            error(("ground", "tangent"), f"the tangent {raw['tangent']} is not a direction in the plane (zero, "
                  "not finite or along the normal)", "give the direction of planar friction, e.g. [1, 0, 0], or "
                  "remove 'tangent' for spatial friction")
            return None
        tangents = (tuple(t / np.linalg.norm(t)),)
    else:
        e = np.array([1.0, 0.0, 0.0]) if abs(normal[0]) <= 0.9 else np.array([0.0, 1.0, 0.0])
        t1 = e - e.dot(normal) * normal
        t1 = t1 / np.linalg.norm(t1)
        tangents = (tuple(t1), tuple(np.cross(normal, t1)))
    return Ground(tuple(normal), float(height), tangents) if ok else None


def _direction(value) -> np.ndarray | None:
    """A unit vector from an axis name or three numbers; None when it is none."""
    if isinstance(value, str):
        value = AXES.get(value)
    try:
        vec = np.array([float(v) for v in value])
    except (TypeError, ValueError):
        return None
    norm = np.linalg.norm(vec) if vec.shape == (3,) and np.all(np.isfinite(vec)) else 0.0
    return vec / norm if norm > 1e-12 else None


# -- shapes -> points ---------------------------------------------------------

def _perpendicular(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(e1, e2): orthonormal, perpendicular to the unit vector a, e1 x e2 = a; (x, y) for a = z."""
    e = np.array([1.0, 0.0, 0.0]) if abs(a[0]) <= 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = e - e.dot(a) * a
    e1 = e1 / np.linalg.norm(e1)
    return e1, np.cross(a, e1)


def _unit_circle(k: int, n: int) -> tuple[float, float]:
    """(cos, sin) of 2 pi k / n, exact zeros where they are zero (cos(pi/2) is 6e-17 in floats)."""
    angle = 2 * math.pi * k / n
    c, s = math.cos(angle), math.sin(angle)
    return (0.0 if abs(c) < 1e-15 else c), (0.0 if abs(s) < 1e-15 else s)


def shape_points(kind: str, size=None, radius=None, length=None, axis=(0.0, 0.0, 1.0), xyz=(0.0, 0.0, 0.0),
                 rpy=(0.0, 0.0, 0.0)) -> list[Point]:
    """The contact points of a primitive placed at xyz, rpy in its frame (see the module docstring)."""
    local = []
    a = np.array(axis, dtype=float)
    if kind == "sphere":
        local = [("sphere", np.zeros(3), radius)]
    elif kind == "capsule":
        local = [("end_p", a * length / 2, radius), ("end_m", -a * length / 2, radius)]
    elif kind == "box":
        half = np.array(size, dtype=float) / 2
        for sx in (1, -1):
            for sy in (1, -1):
                for sz in (1, -1):
                    name = "corner_" + "".join("p" if s > 0 else "m" for s in (sx, sy, sz))
                    local.append((name, half * np.array([sx, sy, sz]), 0.0))
    elif kind == "cylinder":
        e1, e2 = _perpendicular(a)
        for end, sign in (("p", 1), ("m", -1)):
            for k in range(RIM_POINTS):
                c, s = _unit_circle(k, RIM_POINTS)
                local.append((f"rim_{end}_{k}", sign * a * length / 2 + radius * (c * e1 + s * e2), 0.0))
    else:
        raise ValueError(f"no contact points for a {kind}")
    R, p0 = rpy_matrix(rpy), np.array(xyz, dtype=float)
    return [Point(name, tuple(float(v) for v in (p0 + (R @ p if any(rpy) else p))), float(r))
            for name, p, r in local]


# -- points -> contacts ---------------------------------------------------------

def combination(terms, constant: float = 0.0) -> str:
    """`c1*a + c2*b + constant` written from numbers (repr: exact) and names; zero terms left out."""
    parts = []
    for c, name in terms:
        if c != 0:
            magnitude = abs(float(c))
            parts.append(("-" if c < 0 else "+", name if magnitude == 1 else f"{magnitude!r}*{name}"))
    if constant != 0:
        parts.append(("-" if constant < 0 else "+", repr(abs(float(constant)))))
    if not parts:
        return "0"
    text = ("-" if parts[0][0] == "-" else "") + parts[0][1]
    return text + "".join(f" {sign} {part}" for sign, part in parts[1:])


def contact_rows(frame: str, radius: float, ground: Ground) -> tuple[str, list[str]]:
    """(gap, slips) of a point of `radius` at the origin of `frame` (world-axes frame quantities): gap =
    n . P - r - h; slip_k = t_k . (v + w x (-r n)) = t_k . v - r w . (n x t_k)."""
    n = np.array(ground.normal)
    gap = combination([(n[i], f"{frame}.{a}") for i, a in enumerate("xyz")], -(radius + ground.height))
    slips = []
    for t in ground.tangents:
        t = np.array(t)
        w = -radius * np.cross(n, t)
        slips.append(combination([(t[i], f"{frame}.v{a}") for i, a in enumerate("xyz")]
                                 + [(w[i], f"{frame}.w{a}") for i, a in enumerate("xyz")]))
    return gap, slips


def contact_entries(owner: str, base: str, points: list, ground: Ground, friction=None,
                    restitution=None) -> tuple[list, list]:
    """(frames, contacts): the `frames:` and `contacts:` entries of a shape's points on frame `owner`.
    `friction`, `restitution`: as written (expressions of parameters), None for none (frictionless, e = 0)."""
    frames, contacts = [], []
    for p in points:
        name = f"{base}_{p.suffix}"
        frame = owner
        if any(p.position):
            frame = f"{name}_{'centre' if p.radius else 'point'}"
            frames.append({"name": frame, "parent": owner, "translation": [_written(x) for x in p.position]})
        gap, slips = contact_rows(frame, p.radius, ground)
        contact = {"name": name, "gap": gap}
        if restitution is not None:
            contact["restitution"] = restitution
        if friction is not None:
            contact["friction"] = friction
            contact["slip"] = slips[0] if len(slips) == 1 else slips
        contacts.append(contact)
    return frames, contacts


def _written(x: float):
    return int(x) if float(x).is_integer() and abs(x) < 2**53 else float(x)


# -- YAML shapes with collide: true ------------------------------------------------

class RedirectedSourceMap(SourceMap):
    """A source map in which the entries andyc made point at the place they were made from: a path whose
    longest prefix is in `table` is sent to that prefix's target (e.g. a generated contact to the shape it
    comes from, its friction to the shape's `friction:`)."""

    def __init__(self, inner, table: dict):
        super().__init__(inner.file, {})
        self.inner, self.table = inner, dict(table)

    def _route(self, path):
        path = tuple(path)
        for n in range(len(path), 0, -1):
            if path[:n] in self.table:
                return self.table[path[:n]]
        return path

    def line(self, path) -> int:
        return self.inner.line(self._route(path))

    def diag(self, path, message: str, hint: str = "") -> Diagnostic:
        return self.inner.diag(self._route(path), message, hint)

    def describe(self, path) -> str:
        return self.inner.describe(self._route(path))


def expand_shapes(data: dict, smap, urdf_collides: bool = False) -> tuple[dict, object, list, list]:
    """(data, smap, problems, warnings): the model document with the contacts and frames of its colliding
    shapes (`shape: {..., collide: true}` on frames and bodies) added after its own, the source map that
    sends them to their shapes, and what is wrong. `urdf_collides`: a URDF's links touch the ground (so a
    ground without colliding shapes is not idle)."""
    problems, warnings = [], []

    def error(path, message, hint):
        problems.append(smap.diag(path, message, hint))

    ground = ground_plane(data.get("ground"), error)
    frames, contacts, table = [], [], {}
    n_frames, n_contacts = len(data.get("frames") or []), len(data.get("contacts") or [])
    colliding = 0
    for section, owner_key in (("frames", "name"), ("bodies", "frame")):
        for i, item in enumerate(data.get(section) or []):
            given = item.get("shape") if isinstance(item, dict) else None
            if given is None:
                continue
            many = isinstance(given, list)
            shapes = given if many else [given]
            for k, raw in enumerate(shapes):
                where = (section, i, "shape") + ((k,) if many else ())
                if not raw.get("collide", False):
                    for key in ("friction", "restitution"):
                        if key in raw:
                            error(where + (key,), f"'{key}' without 'collide: true' has no effect",
                                  "add 'collide: true' (the shape then touches the ground), or remove it")
                    continue
                colliding += 1
                points = _yaml_points(raw, where, error)
                if ground is None:
                    if "ground" not in data:
                        error(where + ("collide",), "a colliding shape needs a ground to touch",
                              "add 'ground: {normal: [0, 0, 1], height: 0}' (the plane it touches)")
                    continue
                if points is None:
                    continue
                base = item["name"] + (f"_{k}" if many and len(shapes) > 1 else "")
                new_frames, new_contacts = contact_entries(item[owner_key], base, points, ground,
                                                           raw.get("friction"), raw.get("restitution"))
                for f in new_frames:
                    table[("frames", n_frames + len(frames))] = where
                    frames.append(f)
                for c in new_contacts:
                    index = n_contacts + len(contacts)
                    table[("contacts", index)] = where
                    for key in ("friction", "restitution"):
                        table[("contacts", index, key)] = where + (key,)
                    table[("contacts", index, "slip")] = where + ("friction",)
                    contacts.append(c)
    if ground is not None and not colliding and not urdf_collides:
        warnings.append(smap.diag(("ground",), "nothing collides with the ground",
                                  "add 'collide: true' to a shape, or name URDF links in 'urdf: {collide: "
                                  "[...]}'; or remove 'ground'"))
    if not frames and not contacts:
        return data, smap, problems, warnings
    out = dict(data)
    out["frames"] = list(data.get("frames") or []) + frames
    if contacts:
        out["contacts"] = list(data.get("contacts") or []) + contacts
    return out, RedirectedSourceMap(smap, table), problems, warnings


def _yaml_points(raw: dict, where: tuple, error) -> list | None:
    """The contact points of a YAML shape; None after reporting why it has none. Sizes and place are
    constants (numbers, pi, functions of them): they are written into the rows as numbers."""
    kinds = [k for k in PRIMITIVES + ("mesh",) if k in raw]
    if len(kinds) != 1:
        return None                         # reported by andyc.spec.shapes
    kind = kinds[0]
    if kind == "mesh":
        error(where + ("collide",), "a mesh does not collide (not yet): its vertices would be too many contacts",
              "give the colliding part as a box, sphere, capsule or cylinder shape (a list may hold both)")
        return None
    spec = raw[kind] or {}
    at = where + (kind,)
    ok = True

    def value(v, path, positive=False):
        nonlocal ok
        try:
            number = float(parse(v, {}, allow_time=False))
        except ExpressionError as exc:
            ok = False
            error(path, f"a colliding shape's sizes and place are constants, got {v!r} ({exc})",
                  "write a number (a contact's geometry is part of its equations, not a runtime parameter); "
                  "for a size that changes, write the contact under 'contacts:' with the parameter")
            return 0.0
        except (TypeError, ValueError):
            ok = False
            return 0.0
        if positive and not number > 0:
            ok = False          # reported by andyc.spec.shapes
        return number

    size = radius = length = None
    if kind == "box":
        size = [value(v, at + ("size", j), True) for j, v in enumerate(spec.get("size", []))]
    else:
        radius = value(spec.get("radius"), at + ("radius",), True)
        if kind != "sphere":
            length = value(spec.get("length"), at + ("length",), kind == "cylinder")
    axis = _direction(spec.get("axis", "z")) if kind in ("cylinder", "capsule") else np.array([0.0, 0.0, 1.0])
    xyz = [value(v, where + ("xyz", j)) for j, v in enumerate(raw.get("xyz", [0, 0, 0]))]
    rpy = [value(v, where + ("rpy", j)) for j, v in enumerate(raw.get("rpy", [0, 0, 0]))]
    if not ok or axis is None:
        return None
    return shape_points(kind, size, radius, length, tuple(axis), xyz, rpy)
