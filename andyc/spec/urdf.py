"""URDF -> the model dictionary the YAML loader consumes (spec v1).

A URDF becomes frames, bodies, coordinates, speeds and dampers, so the rest
of the pipeline (derive, generate, simulate) does not know where a model came
from. yourdfpy reads the robot; lxml's parse of the same bytes gives every
element its line, so a problem is reported as `robot.urdf:LINE: joint[j]:
what; fix`, like the YAML loader's errors.

How URDF maps onto andyc:

    link L                  frame L (its joint's origin, then the joint's motion); a link named
                            like a joint (a common habit) is frame L_link
    root link               frame on world: fixed (the default), or `base: floating`
                            (a floating link: speeds <L>_vx.._wz in L's axes, signals
                            <L>_x/_y/_z and <L>_qw/_qx/_qy/_qz); a root named `world` is world
    revolute, continuous    revolute about `axis` (any direction), coordinate named after the joint
                            (non-identifier characters become '_'; two names made equal are an error)
    prismatic               prismatic along `axis`
    fixed                   translation and rotation only
    floating                floating link (speeds <joint>_vx.._wz, in the child's axes)
    planar                  translation x, y in the plane normal to `axis`, then rotation
                            theta about it: coordinates <joint>_x, <joint>_y, <joint>_theta
                            (plane axes e1 = x projected on the plane, or y if axis is x;
                            e2 = axis x e1: for axis z, the parent's x and y; Pinocchio 4.1
                            ignores the axis and always uses the joint frame's xy-plane)
    mimic                   by substitution: the joint's angle is multiplier * q + offset of
                            the mimicked coordinate; it adds no degree of freedom
    dynamics damping b      a linear damper on the joint's coordinate (on a mimic joint,
                            b * multiplier^2 on the mimicked coordinate: the same power)
    inertial                a body at the link's frame: com = origin xyz, inertia R I R^T
                            with R from origin rpy (about the COM, in the link's axes); an
                            inertia no rigid body has (not positive semi-definite, triangle
                            inequality broken, no mass) is kept as written, as Pinocchio
                            does, and named in a warning
    visual                  kept as a reference in Spec.visuals (link, geometry, file, origin)

Gravity is [0, 0, -g] with a parameter g = 9.81 (URDF has none). Everything
else a URDF may hold (limits, friction, safety controllers, calibration,
collision geometry, transmissions, gazebo tags, materials, unknown tags) is
counted and named in one warning; nothing is dropped silently.

Options (the `urdf:` key of a YAML model): file, base (fixed | floating),
position and quaternion (the root's pose in world; for a floating base, the
initial pose), root (keep the subtree of this link), lock (joint: value, held
at that value, no degree of freedom) and package_paths (folders searched for
`package://` files).
"""

from __future__ import annotations

import difflib
import io
import keyword
import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from andyc.errors import Diagnostic, SpecError, format_path
from andyc.spec.expressions import MODULE_NAMES, RESERVED
from andyc.spec.urdfxml import LIST_SECTIONS, MAP_SECTIONS, ONE_DOF, MergedSourceMap, UrdfSourceMap, XmlReader
from andyc.spec.yamlpos import SourceMap

GRAVITY = 9.81


@dataclass
class UrdfModel:
    """A URDF as the loader's model dictionary, with its source map and what the Spec keeps besides."""
    data: dict                  # spec v1 model dictionary
    source: SourceMap           # document path -> URDF line and element
    warnings: list              # of Diagnostic (unused elements, meshes not found)
    visuals: list               # of dict: link, frame, geometry, filename/size, scale, origin, material
    raw: bytes                  # the URDF's bytes (for the spec hash)
    locked: tuple = ()          # the joints held at given values, by their URDF name
    file: str = ""              # the URDF's path


MAX_URDF_BYTES = 50_000_000       # robots are large, and lxml reads them fast


def identifier(name: str, kind: str) -> str:
    """A URDF name as an andyc name: letters, digits, '_'; starts with a letter; not reserved."""
    out = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not out or not out[0].isalpha():
        out = f"{kind}_{out}"
    if out in RESERVED or keyword.iskeyword(out):
        out += "_"
    return out


def _fmt(x: float):
    """A float as written in the model dictionary: an int when it is one (keeps zeros exact)."""
    return int(x) if float(x).is_integer() and abs(x) < 2**53 else float(x)


def _numbers(text: str):
    """'1 2 3' -> [1.0, 2.0, 3.0], one number -> a float; as written when it is not numbers (for display only)."""
    try:
        values = [float(x) for x in text.split()]
    except ValueError:
        return text
    return values[0] if len(values) == 1 else values


def rpy_matrix(rpy) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll), URDF's fixed-axis roll-pitch-yaw."""
    r, p, y = rpy
    cr, sr, cp, sp_, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp_ * sr - sy * cr, cy * sp_ * cr + sy * sr],
                     [sy * cp, sy * sp_ * sr + cy * cr, sy * sp_ * cr - cy * sr],
                     [-sp_, cp * sr, cp * cr]])


# -- converting ---------------------------------------------------------------

@dataclass
class _Options:
    base: str = "fixed"
    position: list = field(default_factory=lambda: [0, 0, 0])
    quaternion: list = field(default_factory=lambda: [1, 0, 0, 0])
    root: str | None = None
    lock: dict = field(default_factory=dict)
    package_paths: list = field(default_factory=list)


class _Converter:
    """yourdfpy's robot + the XML lines -> the model dictionary and its source entries."""

    def __init__(self, reader: XmlReader, robot, links: dict, joints: dict, parent_joint: dict, root: str,
                 options: _Options, option_error, folder: Path):
        self.r, self.robot, self.links, self.joints = reader, robot, links, joints
        self.parent_joint, self.root, self.options, self.option_error = parent_joint, root, options, option_error
        self.folder = folder
        self.ylinks = {link.name: link for link in robot.links}
        self.entries: dict = {}
        self.data: dict = {"parameters": {"g": GRAVITY}, "coordinates": {}, "gravity": [0, 0, "-g"], "frames": [],
                           "bodies": [], "dampers": []}
        self.names: dict = {}           # andyc name -> (line, label) of the URDF element it comes from
        self.visuals: list = []
        self.missing_meshes: list = []
        self.odd_inertia: list = []     # links whose inertia no rigid body has (kept, as Pinocchio does)

    def line(self, element) -> int:
        return element.sourceline or 1

    def name(self, andyc_name: str, element, label: str) -> str:
        """Claim an andyc name for a URDF element; a second claim is a clash."""
        if andyc_name in self.names:
            line, first = self.names[andyc_name]
            self.r.error(element, label, f"the name '{andyc_name}' is also made from {first} (line {line})",
                         "rename one of them in the URDF (names are turned into identifiers: "
                         "letters, digits and '_')")
        else:
            self.names[andyc_name] = (self.line(element), label)
        return andyc_name

    def entry(self, path, element, label):
        self.entries[path] = (self.line(element) if element is not None else 1, label)

    def convert(self) -> dict:
        o = self.options
        kept = self.subtree(o.root or self.root)
        root = o.root or self.root
        children = {}
        for link in kept:
            if link != root:
                parent = self.joints[self.parent_joint[link]].find("parent").get("link")
                children.setdefault(parent, []).append(link)
        self.frame_of = {}
        order, stack = [], [root]
        while stack:                                    # depth first, in document order
            link = stack.pop()
            order.append(link)
            stack.extend(reversed(children.get(link, [])))
        self.entry(("name",), self.r.root, "robot")
        self.entry(("parameters", "g"), self.r.root, "robot")
        self.entry(("gravity",), self.r.root, "robot")
        name = identifier(self.robot.name or "robot", "robot")
        self.data["name"] = name + "_robot" if name in MODULE_NAMES else name
        self.coordinate_of = self.coordinates(order, root)
        for link in order:
            self.link_frame(link, root)
        for link in order:
            self.body(link, root)
        self.dampers(order, root)
        self.check_moving_mass(order, root, children)
        self.collect_visuals(order)
        return self.data

    def subtree(self, root: str) -> list:
        kids = {}
        for name, j in self.joints.items():
            kids.setdefault(j.find("parent").get("link"), []).append(j.find("child").get("link"))
        out, stack = [], [root]
        while stack:
            link = stack.pop()
            out.append(link)
            stack.extend(kids.get(link, []))
        return out

    # coordinates ------------------------------------------------------------
    def coordinates(self, order, root) -> dict:
        """joint name -> the expression of its 1-DOF motion (a coordinate, a mimic expression, a locked value)."""
        o = self.options
        moving = [self.parent_joint[link] for link in order if link != root]
        for name in o.lock:
            if name not in self.joints:
                close = difflib.get_close_matches(name, list(self.joints), n=1)
                self.option_error(("lock", name), f"joint '{name}' does not exist in the URDF",
                                  (f"did you mean '{close[0]}'? " if close else "") + "lock joints by their URDF name")
            elif name not in moving:
                self.option_error(("lock", name), f"joint '{name}' is not in the kept subtree", "remove it from 'lock'")
            elif self.joints[name].get("type") not in ONE_DOF:
                self.option_error(("lock", name), f"joint '{name}' is {self.joints[name].get('type')}: only revolute, "
                                  "continuous and prismatic joints can be locked", "remove it from 'lock'")
            elif self.joints[name].find("mimic") is not None:
                master = self.joints[name].find("mimic").get("joint")
                self.option_error(("lock", name), f"joint '{name}' mimics joint '{master}'",
                                  f"lock '{master}' instead (its mimic joints follow it)")
        out = {}
        for jname in moving:
            j = self.joints[jname]
            kind, label = j.get("type"), f"joint[{jname}]"
            if kind in ONE_DOF and j.find("mimic") is None:
                if jname in o.lock:
                    value = o.lock[jname]
                    out[jname] = value if isinstance(value, str) else _fmt(value)
                else:
                    coord = self.name(identifier(jname, "joint"), j, label)
                    self.data["coordinates"][coord] = {"initial": 0}
                    self.entry(("coordinates", coord), j, label)
                    out[jname] = coord
            elif kind == "planar":
                base = identifier(jname, "joint")
                for c in ("x", "y", "theta"):
                    coord = self.name(f"{base}_{c}", j, label)
                    self.data["coordinates"][coord] = {"initial": 0}
                    self.entry(("coordinates", coord), j, label)
        self.mimics = {}                                # joint -> (expression, independent joint or None, gain)
        for jname in moving:                            # mimic joints, possibly of mimic joints
            if self.joints[jname].find("mimic") is not None and self.joints[jname].get("type") in ONE_DOF:
                out[jname] = self.mimic(jname, out, [])[0]
        return out

    def mimic(self, jname: str, done: dict, trail: list) -> tuple:
        """(multiplier * q + offset of the joint it follows, the independent joint at the chain's end, the
        product of the multipliers); after a reported problem, ("0", None, 0)."""
        if jname in self.mimics:
            return self.mimics[jname]
        j = self.joints[jname]
        m = j.find("mimic")
        label = f"joint[{jname}].mimic"
        master = m.get("joint")
        broken = ("0", None, 0.0)
        if master == jname:
            self.r.error(m, label, f"joint '{jname}' mimics itself", "name another joint, or remove the mimic")
            return broken
        if jname in trail:
            self.r.error(m, label, "mimic joints form a loop: " + " -> ".join(trail + [jname]),
                         "one of them must be an independent joint")
            return broken
        self.mimics[jname] = broken                     # until resolved (a loop back here stops)
        following = master in self.joints and self.joints[master].find("mimic") is not None \
            and self.joints[master].get("type") in ONE_DOF
        if master not in self.joints:
            close = difflib.get_close_matches(master, list(self.joints), n=1)
            self.r.error(m, label, f"mimicked joint '{master}' does not exist",
                         (f"did you mean '{close[0]}'? " if close else "") + "name a joint of this URDF")
            return broken
        if master not in done and not following:
            self.r.error(m, label, f"mimicked joint '{master}' is "
                         + ("not in the kept subtree" if self.joints[master].get("type") in ONE_DOF
                            else f"a {self.joints[master].get('type')} joint"),
                         "a mimic joint follows a revolute, continuous or prismatic joint of the model")
            return broken
        if following:
            source, independent, gain = self.mimic(master, done, trail + [jname])
        else:
            source, independent, gain = done[master], master, 1.0
        if independent is None:
            return broken
        mult, off = (float(m.get(a, d)) for a, d in (("multiplier", "1"), ("offset", "0")))
        expr = f"({source})" if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*|-?[0-9.eE+-]+", str(source)) else str(source)
        text = expr if mult == 1 else f"{mult!r}*{expr}"
        text = text if off == 0 else f"{text} + {off!r}" if off > 0 else f"{text} - {-off!r}"
        self.mimics[jname] = (text, independent, gain * mult)
        return self.mimics[jname]

    # frames -----------------------------------------------------------------
    def frame_name(self, link: str, root: str) -> str:
        if link == root and link == "world" and self.options.base == "fixed":
            return "world"
        if link not in self.frame_of:
            name = identifier(link, "link")
            if self.names.get(name, (0, ""))[1].startswith("joint["):    # a link named like its joint, as is usual
                name += "_link"
            self.frame_of[link] = self.name(name, self.links[link], f"link[{link}]")
        return self.frame_of[link]

    def link_frame(self, link: str, root: str):
        o = self.options
        frames = self.data["frames"]
        name = self.frame_name(link, root)
        if link == root:
            element, label = self.links[link], f"link[{link}]"
            if name == "world":
                return
            frame = {"name": name, "parent": "world"}
            if o.base == "floating":
                frame["floating"] = self.floating(name, element, label, o.position, o.quaternion)
            else:
                if any(o.position):
                    frame["translation"] = list(o.position)
                if list(o.quaternion) != [1, 0, 0, 0]:
                    frame["rotation"] = {"quaternion": list(o.quaternion)}
            self.entry(("frames", len(frames)), element, label)
            frames.append(frame)
            return
        jname = self.parent_joint[link]
        j = self.joints[jname]
        label = f"joint[{jname}]"
        parent = self.frame_name(j.find("parent").get("link"), root)
        xyz, rpy = self.r.origin(j, label)
        axis = self.r.numbers(j.find("axis"), "xyz", label + ".axis", 3, "1 0 0") or [1.0, 0.0, 0.0]
        kind = j.get("type")
        index = len(frames)
        frame = {"name": name, "parent": parent}
        if any(xyz):
            frame["translation"] = [_fmt(x) for x in xyz]
        if any(rpy):
            frame["rotation"] = {"rpy": [_fmt(x) for x in rpy]}
        self.entry(("frames", index), j, label)
        if j.find("origin") is not None:
            for key in ("translation", "rotation"):
                self.entry(("frames", index, key), j.find("origin"), label + ".origin")
        if j.find("axis") is not None:
            self.entry(("frames", index, "axis"), j.find("axis"), label + ".axis")
        if j.find("mimic") is not None:
            for key in ("revolute", "prismatic"):
                self.entry(("frames", index, key), j.find("mimic"), label + ".mimic")
        if kind in ONE_DOF:
            frame["revolute" if kind != "prismatic" else "prismatic"] = self.coordinate_of[jname]
            frame["axis"] = [_fmt(a) for a in axis]
        elif kind == "floating":
            frame["floating"] = self.floating(identifier(jname, "joint"), j, label, [0, 0, 0], [1, 0, 0, 0])
        elif kind == "planar":
            base = identifier(jname, "joint")
            n = np.array(axis) / np.linalg.norm(axis)
            e1 = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
            e1 = e1 - e1.dot(n) * n
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(n, e1)
            plane = self.name(f"{name}__plane", j, label)
            frame.update({"name": plane, "prismatic": f"{base}_x", "axis": [_fmt(a) for a in e1]})
            frames.append(frame)
            index = len(frames)
            self.entry(("frames", index), j, label)
            frame = {"name": name, "parent": plane,
                     "translation": [_fmt(0.0) if c == 0 else f"{_fmt(c)!r}*{base}_y" for c in e2],
                     "revolute": f"{base}_theta", "axis": [_fmt(a) for a in n]}
        frames.append(frame)

    def floating(self, owner: str, element, label: str, position, quaternion) -> dict:
        speeds = [self.name(f"{owner}_{c}", element, label) for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
        self.data.setdefault("speeds", {}).update({s: {} for s in speeds})
        for s in speeds:
            self.entry(("speeds", s), element, label)
        return {"speeds": speeds, "position": list(position), "quaternion": list(quaternion), "in": "body"}

    # elements ---------------------------------------------------------------
    def inertial(self, link: str) -> tuple[float, np.ndarray]:
        """(mass, 3x3 inertia about the COM in the inertial frame's axes); zeros without <inertial>."""
        inertial, element = self.ylinks[link].inertial, self.links[link].find("inertial")
        if inertial is None or element is None:
            return 0.0, np.zeros((3, 3))
        inertia = np.zeros((3, 3))
        if element.find("inertia") is not None:
            inertia = np.array(inertial.inertia, dtype=float)
            for k, a in enumerate(("ixx", "iyy", "izz")):   # (yourdfpy defaults a missing one to 1, URDF to 0)
                inertia[k, k] = float(element.find("inertia").get(a, "0"))
        return float(inertial.mass or 0.0), inertia

    def body(self, link: str, root: str):
        element = self.links[link].find("inertial")
        mass, inertia = self.inertial(link)
        if mass == 0 and not inertia.any():
            return
        label = f"link[{link}].inertial"
        moments = np.linalg.eigvalsh(inertia)
        scale = max(abs(moments).max(), 1e-300)
        odd = ("inertia without mass" if mass == 0 else
               "not positive semi-definite" if moments.min() < -1e-12 * scale else
               "breaks the triangle inequality" if moments[0] + moments[1] < moments[2] - 1e-9 * scale else None)
        if odd:
            self.odd_inertia.append((self.line(element), f"{link} (line {self.line(element)}: {odd})"))
        xyz, rpy = self.r.origin(element, label)
        if any(rpy):
            R = rpy_matrix(rpy)
            inertia = R @ inertia @ R.T
            inertia = (inertia + inertia.T) / 2
            value = [[_fmt(x) for x in row] for row in inertia]
        else:
            value = [_fmt(inertia[i, j]) for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))]
        bodies = self.data["bodies"]
        body = {"name": self.name(f"{identifier(link, 'link')}_body", element, label),
                "frame": self.frame_name(link, root), "mass": _fmt(mass)}
        if any(xyz):
            body["com"] = [_fmt(x) for x in xyz]
        if np.any(inertia):
            body["inertia"] = value
        path = ("bodies", len(bodies))
        self.entry(path, element, label)
        for key, child in (("mass", "mass"), ("inertia", "inertia"), ("com", "origin")):
            if element.find(child) is not None:
                self.entry(path + (key,), element.find(child), f"{label}.{child}")
        bodies.append(body)

    def dampers(self, order, root):
        for link in order:
            if link == root:
                continue
            jname = self.parent_joint[link]
            j = self.joints[jname]
            dyn = j.find("dynamics")
            if dyn is None or j.get("type") not in ONE_DOF or jname in self.options.lock:
                continue
            b = float(dyn.get("damping", "0") or 0)
            if b == 0:
                continue
            speed, gain = self.coordinate_of[jname], 1.0
            if jname in self.mimics:                    # the power b (m v)^2 on the mimicked coordinate
                _, master, gain = self.mimics[jname]
                speed = self.coordinate_of.get(master)
                if speed not in self.data["coordinates"]:
                    continue                            # follows a locked joint: no motion, no damping
            label = f"joint[{jname}].dynamics"
            path = ("dampers", len(self.data["dampers"]))
            self.entry(path, dyn, label)
            self.data["dampers"].append({"name": self.name(f"{identifier(jname, 'joint')}_damping", dyn, label),
                                         "coefficient": _fmt(b * gain * gain), "speed": speed})

    def check_moving_mass(self, order, root, children):
        """Each degree of freedom must move some mass, or the mass matrix is singular."""
        below = {}          # mass + trace of the inertia of a link and all it carries
        for link in reversed(order):
            mass, inertia = self.inertial(link)
            below[link] = mass + abs(np.trace(inertia)) + sum(below[c] for c in children.get(link, []))
        moved = {}          # DOF owner joint -> mass it moves (mimic joints count for their master)
        for link in order:
            if link == root:
                continue
            jname = self.parent_joint[link]
            owner = self.mimics[jname][1] if jname in self.mimics else jname
            moved[owner] = moved.get(owner, 0.0) + below[link]
        for link in order:
            if link == root:
                if self.options.base == "floating" and below[link] == 0:
                    self.r.error(self.links[link], f"link[{link}]", "the floating base moves no mass: no link "
                                 "of the robot has mass", "give the links <inertial> elements with a mass")
                continue
            jname = self.parent_joint[link]
            j = self.joints[jname]
            if j.get("type") == "fixed" or jname in self.options.lock or jname in self.mimics:
                continue
            if moved.get(jname, 0.0) == 0:
                element = self.links[link].find("inertial")
                element = element if element is not None else self.links[link]
                self.r.error(element, f"link[{link}]", f"zero-mass moving link: joint '{jname}' moves link "
                             f"'{link}' and nothing it carries has mass, so the mass matrix is singular",
                             f"give link '{link}' an <inertial> with <mass value=...> > 0, make joint "
                             f"'{jname}' fixed, or lock it in a YAML model: urdf: {{lock: {{{jname}: 0}}}}")

    def collect_visuals(self, order):
        for link in order:
            for k, element in enumerate(self.links[link].findall("visual")):
                geometry = element.find("geometry")
                shape = next((g for g in geometry if isinstance(g.tag, str)), None) if geometry is not None else None
                if shape is None:
                    continue
                xyz, rpy = self.r.origin(element, f"link[{link}].visual")
                ref = {"link": link, "frame": self.frame_of.get(link, "world"), "geometry": shape.tag,
                       "origin": {"xyz": xyz, "rpy": rpy}, "line": self.line(element)}
                if shape.tag == "mesh":
                    ref["filename"] = self.resolve(shape.get("filename", ""))
                    ref["scale"] = _numbers(shape.get("scale", "1 1 1"))
                else:
                    ref.update({a: _numbers(shape.get(a)) for a in ("radius", "length", "size") if shape.get(a)})
                material = element.find("material")
                if material is not None and material.get("name"):
                    ref["material"] = material.get("name")
                self.visuals.append(ref)

    def resolve(self, filename: str) -> str:
        """package://PKG/REL and relative names -> an existing file (search paths, the URDF's folder and its
        ancestors), or the name as written (reported once in a warning)."""
        if filename.startswith("file://"):
            return filename[len("file://"):]
        candidates = []
        if filename.startswith("package://"):
            pkg, _, rel = filename[len("package://"):].partition("/")
            for d in [Path(p) for p in self.options.package_paths]:
                candidates += [d / pkg / rel, d / rel]
            candidates += [a / pkg / rel for a in [self.folder, *self.folder.parents]] + [self.folder / rel]
        elif not Path(filename).is_absolute():
            candidates = [self.folder / filename]
        else:
            candidates = [Path(filename)]
        for c in candidates:
            if c.is_file():
                return str(c)
        self.missing_meshes.append(filename)
        return filename


def _options(raw) -> _Options:
    o = _Options()
    if isinstance(raw, dict):
        for key in ("base", "position", "quaternion", "root", "lock", "package_paths"):
            if key in raw:
                setattr(o, key, raw[key])
    o.lock = dict(o.lock or {})
    return o


def read(path, options=None, option_error=None, raw: bytes | None = None) -> UrdfModel:
    """A URDF file -> UrdfModel; raises SpecError listing every problem.

    `options`: the `urdf:` mapping of a YAML model (see the module docstring);
    `option_error(path, message, hint)` reports a problem in it (default: at the URDF's line 1).
    """
    import yourdfpy

    path = Path(path)
    file = str(path)
    if raw is None:
        try:
            if path.stat().st_size > MAX_URDF_BYTES:
                raise SpecError([Diagnostic(file, 1, "", f"the URDF has {path.stat().st_size / 1e6:.1f} MB, past "
                                            f"the limit of {MAX_URDF_BYTES / 1e6:g} MB", "check that this is the URDF")])
            raw = path.read_bytes()
        except OSError as exc:
            raise SpecError([Diagnostic(file, 1, "", f"cannot read the URDF ({exc.strerror})", "check the path")])
    reader = XmlReader(file, raw)
    option_problems: list[Diagnostic] = []
    if option_error is None:
        def option_error(where, message, hint=""):
            option_problems.append(Diagnostic(file, 1, format_path(("urdf",) + tuple(where)), message, hint))
    else:
        report = option_error

        def option_error(where, message, hint=""):
            option_problems.append(report(where, message, hint))
    links, joints = reader.check()
    if reader.problems:
        raise SpecError(sorted(reader.problems, key=lambda d: d.line))
    parent_joint, root = reader.tree(links, joints)
    if reader.problems:
        raise SpecError(sorted(reader.problems, key=lambda d: d.line))
    o = _options(options)
    if o.root is not None and o.root not in links:
        close = difflib.get_close_matches(str(o.root), list(links), n=1)
        option_error(("root",), f"link '{o.root}' does not exist in the URDF",
                     (f"did you mean '{close[0]}'? " if close else "") + "name the link whose subtree to keep")
        o.root = None
    if o.base == "floating" and (o.root or root) == "world":
        option_error(("base",), "the root link is 'world', which cannot float",
                     "name the link to float with 'root: <link>' (the subtree of that link is kept)")
        o.base = "fixed"
    try:
        robot = yourdfpy.URDF.load(io.BytesIO(raw), build_scene_graph=False, build_collision_scene_graph=False,
                                   load_meshes=False, load_collision_meshes=False).robot
    except Exception as exc:      # noqa: BLE001 -- whatever yourdfpy raises becomes one located message
        line, element = reader.locate(str(exc))
        raise SpecError([Diagnostic(file, line, element, f"yourdfpy cannot read the URDF: {exc}",
                                    "check this element against the URDF format")])
    converter = _Converter(reader, robot, links, joints, parent_joint, root, o, option_error, path.parent)
    data = converter.convert()
    problems = reader.problems + option_problems
    if problems:
        raise SpecError(sorted(problems, key=lambda d: (d.file, d.line)))
    warnings = [w for w in [reader.unused()] if w is not None]
    if converter.missing_meshes:
        n = len(converter.missing_meshes)
        warnings.append(Diagnostic(file, 1, "robot", f"{n} visual mesh file(s) not found (first: "
                                   f"{converter.missing_meshes[0]!r}); kept as written in Spec.visuals",
                                   "give the folders that hold the packages in 'urdf: {package_paths: [...]}'"))
    if converter.odd_inertia:
        odd = sorted(converter.odd_inertia)
        n = len(odd)
        warnings.append(Diagnostic(file, odd[0][0], "robot", f"{n} link(s) have an inertia no rigid body has, "
                                   "simulated as written (as Pinocchio does): " + ", ".join(t for _, t in odd[:4])
                                   + (f" and {n - 4} more" if n > 4 else ""),
                                   "fix the <inertia> values if the mass matrix turns out singular"))
    if not data["dampers"]:
        del data["dampers"]
    if not data["bodies"]:
        del data["bodies"]
    return UrdfModel(data, UrdfSourceMap(file, converter.entries), warnings, converter.visuals, raw, tuple(o.lock),
                     file)


def merge(data: dict, smap: SourceMap, yaml_path: Path) -> tuple[dict, SourceMap, UrdfModel]:
    """A YAML model with a `urdf:` key -> the merged dictionary: the URDF's frames, bodies, coordinates, ...
    first, then the YAML's own entries (mapping sections: the YAML's entry replaces the URDF's of the same
    name; gravity, name and the other keys: the YAML's)."""
    options = data["urdf"]
    options = {"file": options} if isinstance(options, str) else dict(options)
    target = Path(options["file"])
    if not target.is_absolute():
        target = yaml_path.parent / target
    where = ("urdf",) if isinstance(data["urdf"], str) else ("urdf", "file")
    if not target.is_file():
        raise SpecError([smap.diag(where, f"URDF file '{options['file']}' not found (looked for {target})",
                                   "give a path relative to this model file")])
    options["package_paths"] = [str(p if Path(p).is_absolute() else yaml_path.parent / p)
                                for p in options.get("package_paths", [])]
    model = read(target, options, lambda path, message, hint="": smap.diag(("urdf",) + tuple(path), message, hint))
    merged = dict(model.data)
    counts = {section: len(model.data.get(section, [])) for section in LIST_SECTIONS}
    for key, value in data.items():
        if key == "urdf":
            continue
        if key in LIST_SECTIONS:
            merged[key] = list(model.data.get(key, [])) + list(value or [])
        elif key in MAP_SECTIONS:
            merged[key] = {**model.data.get(key, {}), **(value or {})}
        else:
            merged[key] = value
    return merged, MergedSourceMap(smap, model.source, counts, data), model
