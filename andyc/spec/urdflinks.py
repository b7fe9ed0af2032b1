"""A URDF's links as andyc frames, bodies and dampers, and their visual geometry.

Each kept link becomes a frame on its parent's: its joint's origin (translation, roll-pitch-yaw), then
the joint's motion from andyc.spec.urdfjoints. A planar joint needs two frames: <link>__plane moves
along the plane's first axis, the link's frame along its second and about the normal. The root link
is fixed in world, or floats (six speeds in its own axes, a position and a quaternion signal).

A link's <inertial> becomes a body at the COM (its inertia turned into the link's axes); a joint's
<dynamics damping> a linear damper on its coordinate. Each degree of freedom must move some mass.
Visual geometry is kept as references (mesh files looked up in the package paths).
"""

from __future__ import annotations

import math
import os
from pathlib import Path

import numpy as np

from andyc.spec.meshfiles import MeshRefused, checked_mesh, package_root
from andyc.spec.urdfjoints import Draft, as_written, identifier
from andyc.spec.urdfxml import ONE_DOF


def rpy_matrix(rpy) -> np.ndarray:
    """R = Rz(yaw) Ry(pitch) Rx(roll), URDF's fixed-axis roll-pitch-yaw."""
    r, p, y = rpy
    cr, sr, cp, sp_, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    return np.array([[cy * cp, cy * sp_ * sr - sy * cr, cy * sp_ * cr + sy * sr],
                     [sy * cp, sy * sp_ * sr + cy * cr, sy * sp_ * cr - cy * sr],
                     [-sp_, cp * sr, cp * cr]])


def _numbers(text: str):
    """'1 2 3' -> [1.0, 2.0, 3.0], one number -> a float; as written when it is not numbers (for display only)."""
    try:
        values = [float(x) for x in text.split()]
    except ValueError:
        return text
    return values[0] if len(values) == 1 else values


class LinkWriter:
    """Writes the kept links into the draft; collects what read() reports besides (visuals, missing
    meshes, inertias no rigid body has)."""

    def __init__(self, draft: Draft, robot, links: dict, joints: dict, parent_joint: dict, options,
                 folder: Path, coordinate_of: dict, mimics: dict):
        self.draft = draft
        self.reader = draft.reader
        self.links, self.joints = links, joints         # name -> XML element
        self.parent_joint = parent_joint                # link -> the joint whose child it is
        self.ylinks = {link.name: link for link in robot.links}     # name -> yourdfpy's link
        self.options = options
        self.folder = folder            # the URDF's, where relative mesh names start
        self.coordinate_of = coordinate_of      # joint -> its motion (andyc.spec.urdfjoints.joint_motions)
        self.mimics = mimics                    # mimic joint -> (expression, independent joint, gain)
        self.frame_of: dict = {}        # link -> its frame's name, claimed when first asked for
        self.visuals: list = []
        self.missing_meshes: list = []
        self.refused_meshes: list = []  # (line, why) of meshes that break andyc.spec.meshfiles' rule
        self.odd_inertia: list = []     # links whose inertia no rigid body has (kept, as Pinocchio does)

    # frames -----------------------------------------------------------------
    def frame_name(self, link: str, root: str) -> str:
        """The name of a link's frame (claimed on first use, so a clash names the element seen first)."""
        if link == root and link == "world" and self.options.base == "fixed":
            return "world"
        if link not in self.frame_of:
            name = identifier(link, "link")
            if self.draft.names.get(name, (0, ""))[1].startswith("joint["):   # named like its joint, as is usual
                name += "_link"
            self.frame_of[link] = self.draft.name(name, self.links[link], f"link[{link}]")
        return self.frame_of[link]

    def link_frame(self, link: str, root: str):
        """The frame of a link: the root's pose in world, or its joint's origin then the joint's motion (two
        frames for a planar joint)."""
        o = self.options
        frames = self.draft.data["frames"]
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
            self.draft.entry(("frames", len(frames)), element, label)
            frames.append(frame)
            return
        jname = self.parent_joint[link]
        j = self.joints[jname]
        label = f"joint[{jname}]"
        parent = self.frame_name(j.find("parent").get("link"), root)
        xyz, rpy = self.reader.origin(j, label)
        axis = self.reader.numbers(j.find("axis"), "xyz", label + ".axis", 3, "1 0 0") or [1.0, 0.0, 0.0]
        kind = j.get("type")
        index = len(frames)
        frame = {"name": name, "parent": parent}
        if any(xyz):
            frame["translation"] = [as_written(x) for x in xyz]
        if any(rpy):
            frame["rotation"] = {"rpy": [as_written(x) for x in rpy]}
        self.draft.entry(("frames", index), j, label)
        if j.find("origin") is not None:
            for key in ("translation", "rotation"):
                self.draft.entry(("frames", index, key), j.find("origin"), label + ".origin")
        if j.find("axis") is not None:
            self.draft.entry(("frames", index, "axis"), j.find("axis"), label + ".axis")
        if j.find("mimic") is not None:
            for key in ("revolute", "prismatic"):
                self.draft.entry(("frames", index, key), j.find("mimic"), label + ".mimic")
        if kind in ONE_DOF:
            frame["revolute" if kind != "prismatic" else "prismatic"] = self.coordinate_of[jname]
            frame["axis"] = [as_written(a) for a in axis]
        elif kind == "floating":
            frame["floating"] = self.floating(identifier(jname, "joint"), j, label, [0, 0, 0], [1, 0, 0, 0])
        elif kind == "planar":
            base = identifier(jname, "joint")
            n = np.array(axis) / np.linalg.norm(axis)
            e1 = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
            e1 = e1 - e1.dot(n) * n
            e1 /= np.linalg.norm(e1)
            e2 = np.cross(n, e1)
            plane = self.draft.name(f"{name}__plane", j, label)
            frame.update({"name": plane, "prismatic": f"{base}_x", "axis": [as_written(a) for a in e1]})
            frames.append(frame)
            index = len(frames)
            self.draft.entry(("frames", index), j, label)
            frame = {"name": name, "parent": plane,
                     "translation": [as_written(0.0) if c == 0 else f"{as_written(c)!r}*{base}_y" for c in e2],
                     "revolute": f"{base}_theta", "axis": [as_written(a) for a in n]}
        frames.append(frame)

    def floating(self, owner: str, element, label: str, position, quaternion) -> dict:
        """A floating link's entry, with its six speeds <owner>_vx .. <owner>_wz declared."""
        speeds = [self.draft.name(f"{owner}_{c}", element, label) for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
        self.draft.data.setdefault("speeds", {}).update({s: {} for s in speeds})
        for s in speeds:
            self.draft.entry(("speeds", s), element, label)
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
        """A body at the link's COM, unless it has neither mass nor inertia."""
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
            self.odd_inertia.append((self.draft.line(element), f"{link} (line {self.draft.line(element)}: {odd})"))
        xyz, rpy = self.reader.origin(element, label)
        if any(rpy):
            R = rpy_matrix(rpy)
            inertia = R @ inertia @ R.T
            inertia = (inertia + inertia.T) / 2
            value = [[as_written(x) for x in row] for row in inertia]
        else:
            value = [as_written(inertia[i, j]) for i, j in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))]
        bodies = self.draft.data["bodies"]
        body = {"name": self.draft.name(f"{identifier(link, 'link')}_body", element, label),
                "frame": self.frame_name(link, root), "mass": as_written(mass)}
        if any(xyz):
            body["com"] = [as_written(x) for x in xyz]
        if np.any(inertia):
            body["inertia"] = value
        path = ("bodies", len(bodies))
        self.draft.entry(path, element, label)
        for key, child in (("mass", "mass"), ("inertia", "inertia"), ("com", "origin")):
            if element.find(child) is not None:
                self.draft.entry(path + (key,), element.find(child), f"{label}.{child}")
        bodies.append(body)

    def dampers(self, order, root):
        """A linear damper on the coordinate of each joint with <dynamics damping> (not fixed, not locked), and
        with urdf: {joint_friction: true} a coulomb one with its <dynamics friction>."""
        for link in order:
            if link == root:
                continue
            jname = self.parent_joint[link]
            j = self.joints[jname]
            dyn = j.find("dynamics")
            if dyn is None or j.get("type") not in ONE_DOF or jname in self.options.lock:
                continue
            b = float(dyn.get("damping", "0") or 0)
            f = float(dyn.get("friction", "0") or 0) if self.options.joint_friction else 0.0
            if b == 0 and f == 0:
                continue
            speed, gain = self.coordinate_of[jname], 1.0
            if jname in self.mimics:                    # the power b (m v)^2 on the mimicked coordinate
                _, master, gain = self.mimics[jname]
                speed = self.coordinate_of.get(master)
                if speed not in self.draft.data["coordinates"]:
                    continue                            # follows a locked joint: no motion, no damping
            label = f"joint[{jname}].dynamics"
            for kind, entry in (("damping", {"coefficient": as_written(b * gain * gain)} if b else None),
                                ("friction", {"coefficient": as_written(f * abs(gain)), "law": "coulomb"} if f else None)):
                if entry is None:       # (friction f |v_joint| = f |gain| |v|: the same power on the mimicked one)
                    continue
                path = ("dampers", len(self.draft.data["dampers"]))
                self.draft.entry(path, dyn, label)
                name = self.draft.name(f"{identifier(jname, 'joint')}_{kind}", dyn, label)
                self.draft.data["dampers"].append({"name": name, **entry, "speed": speed})

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
                    self.reader.error(self.links[link], f"link[{link}]", "the floating base moves no mass: no link "
                                 "of the robot has mass", "give the links <inertial> elements with a mass")
                continue
            jname = self.parent_joint[link]
            j = self.joints[jname]
            if j.get("type") == "fixed" or jname in self.options.lock or jname in self.mimics:
                continue
            if moved.get(jname, 0.0) == 0:
                element = self.links[link].find("inertial")
                element = element if element is not None else self.links[link]
                self.reader.error(element, f"link[{link}]", f"zero-mass moving link: joint '{jname}' moves link "
                             f"'{link}' and nothing it carries has mass, so the mass matrix is singular",
                             f"give link '{link}' an <inertial> with <mass value=...> > 0, make joint "
                             f"'{jname}' fixed, or lock it in a YAML model: urdf: {{lock: {{{jname}: 0}}}}")

    def actuators(self, order, root):
        """A motor on every moving joint (urdf: {actuators: true}): an input tau_<joint> (default 0) and an actuator
        <joint>_motor on the joint's coordinate, clamped to its <limit effort> when it gives one (> 0)."""
        data = self.draft.data
        for link in order:
            if link == root:
                continue
            jname = self.parent_joint[link]
            j = self.joints[jname]
            if (j.get("type") not in ("revolute", "continuous", "prismatic") or jname in self.options.lock
                    or jname in self.mimics):
                continue
            q = self.coordinate_of[jname]
            label = f"joint[{jname}]"
            tau = self.draft.name(f"tau_{q}", j, label)
            data.setdefault("inputs", {})[tau] = 0.0
            self.draft.entry(("inputs", tau), j, label)
            motor = {"name": self.draft.name(f"{q}_motor", j, label), "coordinate": q, "force": tau}
            limit = j.find("limit")
            effort = _numbers(limit.get("effort", "")) if limit is not None else None
            if isinstance(effort, float) and math.isfinite(effort) and effort > 0:
                motor["limit"] = effort
            self.draft.entry(("actuators", len(data.setdefault("actuators", []))), j, label)
            data["actuators"].append(motor)

    def collect_visuals(self, order):
        for link in order:
            for k, element in enumerate(self.links[link].findall("visual")):
                geometry = element.find("geometry")
                shape = next((g for g in geometry if isinstance(g.tag, str)), None) if geometry is not None else None
                if shape is None:
                    continue
                xyz, rpy = self.reader.origin(element, f"link[{link}].visual")
                ref = {"link": link, "frame": self.frame_of.get(link, "world"), "geometry": shape.tag,
                       "origin": {"xyz": xyz, "rpy": rpy}, "line": self.draft.line(element)}
                if shape.tag == "mesh":
                    ref["filename"], ref["format"] = self.resolve(shape.get("filename", ""), ref["line"])
                    ref["scale"] = _numbers(shape.get("scale", "1 1 1"))
                else:
                    ref.update({a: _numbers(shape.get(a)) for a in ("radius", "length", "size") if shape.get(a)})
                material = element.find("material")
                if material is not None and material.get("name"):
                    ref["material"] = material.get("name")
                rgba = self.material_rgba(material)
                if rgba is not None:
                    ref["rgba"] = rgba
                self.visuals.append(ref)

    def material_rgba(self, material):
        """[r, g, b, a] of a visual's <material>: its own <color rgba>, else that of the robot's top-level
        <material> of its name (as URDF defines them); None without one, or one that is not 4 numbers in 0..1."""
        if material is None:
            return None
        color = material.find("color")
        if color is None and material.get("name"):
            named = [m for m in self.reader.root.findall("material") if m.get("name") == material.get("name")]
            color = named[0].find("color") if named else None
        rgba = _numbers(color.get("rgba", "")) if color is not None else None
        if isinstance(rgba, list) and len(rgba) == 4 and all(0.0 <= c <= 1.0 for c in rgba):
            return rgba
        return None

    def resolve(self, filename: str, line: int) -> tuple[str, str]:
        """(file, format) of a visual's mesh: package://PKG/REL and relative names looked up in the search
        paths, the URDF's folder and its ancestors; the first that exists must keep andyc.spec.meshfiles'
        rule inside its own root (format ''; the name as written, kept in missing_meshes or refused_meshes
        for one warning, when none does)."""
        name = filename[len("file://"):] if filename.startswith("file://") else filename
        own = [package_root(self.folder)] + [Path(p) for p in self.options.package_paths]
        candidates = []         # (path, the folder it must resolve inside)
        if name.startswith("package://"):
            pkg, _, rel = name[len("package://"):].partition("/")
            for d in [Path(p) for p in self.options.package_paths]:
                candidates += [(d / pkg / rel, [d / pkg]), (d / rel, [d])]
            candidates += [(a / pkg / rel, [a / pkg]) for a in [self.folder, *self.folder.parents]]
            candidates += [(self.folder / rel, own)]
        else:
            candidates = [(self.folder / name, own)]      # an absolute name replaces the folder
        for path, roots in candidates:
            if not os.path.lexists(path):
                continue
            try:
                resolved, fmt = checked_mesh(path, roots)
            except MeshRefused as why:
                self.refused_meshes.append((line, f"{filename!r} {why}"))
                return filename, ""
            return str(resolved), fmt
        self.missing_meshes.append(filename)
        return filename, ""
