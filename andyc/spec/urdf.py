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
    dynamics friction f     dry friction: a damper <joint>_friction of law coulomb on the coordinate (a
                            mimic joint's: f * |multiplier| on the mimicked one), which the moreau
                            method applies; urdf: {joint_friction: false} leaves it out
    inertial                a body at the link's frame: com = origin xyz, inertia R I R^T
                            with R from origin rpy (about the COM, in the link's axes); an
                            inertia no rigid body has (not positive semi-definite, triangle
                            inequality broken, no mass) is kept as written, as Pinocchio
                            does, and named in a warning
    visual                  kept as a reference in Spec.visuals (link, geometry, file, origin)
    limit lower, upper      stops: contacts <joint>_lower, <joint>_upper (urdf: {limits: false}: none)
    collision               contacts on the model's ground, for the links named in urdf: {collide: [...]}
                            (andyc.spec.urdfcontacts, andyc.spec.geometry)

Gravity is [0, 0, -g] with a parameter g = 9.81 (URDF has none). Everything
else a URDF may hold (effort and velocity limits, safety controllers,
calibration, other collision geometry, transmissions, gazebo tags, materials,
unknown tags) is counted and named in one warning; nothing is dropped silently.

The work is split by what is read: andyc.spec.urdfxml checks the XML and keeps its lines,
andyc.spec.urdfjoints turns the joints into coordinates (lock, mimic), andyc.spec.urdflinks the
links into frames, bodies and dampers. This module reads the file, applies the options and merges
the result with a YAML model's own keys.

Options (the `urdf:` key of a YAML model): file, base (fixed | floating),
position and quaternion (the root's pose in world; for a floating base, the
initial pose), root (keep the subtree of this link), lock (joint: value, held
at that value, no degree of freedom), package_paths (folders searched for
`package://` files), collide (links or fnmatch patterns whose <collision> shapes
touch the YAML's `ground:`) with friction and restitution (their contacts'),
limits (joint limits as stops; default true) and joint_friction (<dynamics friction> applied; default true).
"""

from __future__ import annotations

import io
from dataclasses import dataclass, field
from pathlib import Path

from andyc.errors import Diagnostic, SpecError, format_path
from andyc.spec import geometry
from andyc.spec.expressions import MODULE_NAMES
from andyc.spec.suggest import did_you_mean
from andyc.spec.urdfjoints import Draft, identifier, joint_motions, link_order
from andyc.spec.urdfcontacts import ContactWriter
from andyc.spec.urdflinks import LinkWriter
from andyc.spec.urdfxml import LIST_SECTIONS, MAP_SECTIONS, MergedSourceMap, UrdfSourceMap, XmlReader
from andyc.spec.yamlpos import SourceMap

__all__ = ["UrdfModel", "MAX_URDF_BYTES", "identifier", "read", "merge"]


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
    option_paths: dict = field(default_factory=dict)   # generated entry's path -> its `urdf:` option's path
    collides: bool = False      # some link's collision geometry touches the ground
    stops: dict = field(default_factory=dict)   # joint-limit stop -> (joint, coordinate, side, bound)


MAX_URDF_BYTES = 50_000_000       # robots are large, and lxml reads them fast
LIMITS_DEFAULT = True              # `urdf: {limits: ...}` when not given: joint limits are stops


@dataclass(frozen=True)
class _Options:
    """The `urdf:` key's options (see the module docstring), checked against the robot."""
    base: str                   # fixed | floating
    position: list
    quaternion: list
    root: str | None            # the link whose subtree is kept; None: the robot's root
    lock: dict                  # joint -> the value it is held at
    package_paths: list
    collide: list = ()          # link names or fnmatch patterns whose <collision> shapes touch the ground
    friction: object = None     # their contacts' friction coefficient (an expression), None: frictionless
    restitution: object = None  # their contacts' restitution (an expression), None: 0
    limits: bool = True         # joint limits as stops (andyc.spec.urdfcontacts)
    actuators: bool = False     # a motor (input tau_<joint>, actuator <joint>_motor) on every moving joint
    joint_friction: bool = True  # <dynamics friction> as a damper of law coulomb (andyc.spec.urdflinks)


def _options(raw, links: dict, tree_root: str | None, option_error) -> _Options:
    """The options given (defaults for the others). A root link that does not exist is reported and
    ignored; a floating 'world' is reported, and stays fixed."""
    given = ({k: raw[k] for k in ("base", "position", "quaternion", "root", "lock", "package_paths", "collide",
                                  "friction", "restitution", "limits", "actuators", "joint_friction") if k in raw}
             if isinstance(raw, dict) else {})
    root = given.get("root")
    if root is not None and root not in links:
        option_error(("root",), f"link '{root}' does not exist in the URDF",
                     did_you_mean(root, links) + "name the link whose subtree to keep")
        root = None
    base = given.get("base", "fixed")
    if base == "floating" and (root or tree_root) == "world":
        option_error(("base",), "the root link is 'world', which cannot float",
                     "name the link to float with 'root: <link>' (the subtree of that link is kept)")
        base = "fixed"
    return _Options(base, given.get("position", [0, 0, 0]), given.get("quaternion", [1, 0, 0, 0]), root,
                    dict(given.get("lock") or {}), given.get("package_paths", []), list(given.get("collide", [])),
                    given.get("friction"), given.get("restitution"), bool(given.get("limits", LIMITS_DEFAULT)),
                    bool(given.get("actuators", False)), bool(given.get("joint_friction", True)))


def _convert(reader: XmlReader, robot, links: dict, joints: dict, parent_joint: dict, tree_root: str,
             options: _Options, option_error, folder: Path, ground) -> tuple[Draft, LinkWriter, ContactWriter]:
    """yourdfpy's robot + the XML lines -> the model dictionary (in the draft), in this order: the
    coordinates of the joints, then each link's frame, body and damper, then the checks and visuals, then
    the contacts (collision shapes on `ground`, joint limits). Names are claimed in this order, so a clash
    names the element that came first."""
    draft = Draft(reader)
    root = options.root or tree_root
    order, children = link_order(joints, parent_joint, root)
    for path in (("name",), ("parameters", "g"), ("gravity",)):
        draft.entry(path, reader.root, "robot")
    name = identifier(robot.name or "robot", "robot")
    draft.data["name"] = name + "_robot" if name in MODULE_NAMES else name
    coordinate_of, mimics = joint_motions(draft, joints, [parent_joint[link] for link in order if link != root],
                                          options.lock, option_error)
    writer = LinkWriter(draft, robot, links, joints, parent_joint, options, folder, coordinate_of, mimics)
    for link in order:
        writer.link_frame(link, root)
    for link in order:
        writer.body(link, root)
    writer.dampers(order, root)
    writer.check_moving_mass(order, root, children)
    writer.collect_visuals(order)
    contacts = ContactWriter(writer, option_error)
    contacts.collisions(order, root, ground)
    contacts.limits(order, root)
    if options.actuators:
        writer.actuators(order, root)
    return draft, writer, contacts


def read(path, options=None, option_error=None, raw: bytes | None = None, ground=None) -> UrdfModel:
    """A URDF file -> UrdfModel; raises SpecError listing every problem.

    `options`: the `urdf:` mapping of a YAML model (see the module docstring);
    `option_error(path, message, hint)` reports a problem in it (default: at the URDF's line 1);
    `ground`: the YAML model's ground (andyc.spec.geometry.Ground), which `collide` links touch.
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
    o = _options(options, links, root, option_error)
    try:
        robot = yourdfpy.URDF.load(io.BytesIO(raw), build_scene_graph=False, build_collision_scene_graph=False,
                                   load_meshes=False, load_collision_meshes=False).robot
    except Exception as exc:      # noqa: BLE001 -- whatever yourdfpy raises becomes one located message
        line, element = reader.locate(str(exc))
        raise SpecError([Diagnostic(file, line, element, f"yourdfpy cannot read the URDF: {exc}",
                                    "check this element against the URDF format")])
    draft, writer, contacts = _convert(reader, robot, links, joints, parent_joint, root, o, option_error,
                                       path.parent, ground)
    data = draft.data
    problems = reader.problems + option_problems
    if problems:
        raise SpecError(sorted(problems, key=lambda d: (d.file, d.line)))
    warnings = [w for w in [reader.unused(contacts.stops, set(contacts.colliding), o.actuators, o.joint_friction)]
                if w is not None]
    if contacts.mesh_links:
        n = len(contacts.mesh_links)
        line, _ = contacts.mesh_links[0]
        names = ", ".join(dict.fromkeys(link for _, link in contacts.mesh_links))
        warnings.append(Diagnostic(file, line, "robot", f"{n} collision mesh(es) give no contact (not yet): "
                                   f"links {names}", "give those links primitive <collision> shapes (box, "
                                   "sphere, cylinder), or touch the ground with others"))
    if contacts.odd_limits:
        line, _ = contacts.odd_limits[0]
        warnings.append(Diagnostic(file, line, "robot", f"{len(contacts.odd_limits)} joint limit(s) with lower "
                                   "not below upper give no stops: " + ", ".join(t for _, t in contacts.odd_limits),
                                   "lock such a joint in a YAML model (urdf: {lock: {JOINT: value}}), or fix "
                                   "its <limit>"))
    if writer.missing_meshes:
        n = len(writer.missing_meshes)
        warnings.append(Diagnostic(file, 1, "robot", f"{n} visual mesh file(s) not found (first: "
                                   f"{writer.missing_meshes[0]!r}); kept as written in Spec.visuals",
                                   "give the folders that hold the packages in 'urdf: {package_paths: [...]}'"))
    if writer.refused_meshes:
        n = len(writer.refused_meshes)
        line, why = writer.refused_meshes[0]
        warnings.append(Diagnostic(file, line, "robot", f"{n} visual mesh file(s) refused, not drawn (first: {why})",
                                   "a mesh must resolve to a regular .stl, .obj or .dae file inside its package or "
                                   "the URDF's package (docs/model-file.md: Model files from anyone)"))
    unreadable = [v for v in writer.visuals if v["geometry"] == "mesh" and not v["format"]
                  and Path(v["filename"]).suffix.lower() not in (".stl", ".obj", ".dae")]
    if unreadable:
        warnings.append(Diagnostic(file, unreadable[0]["line"], "robot", f"{len(unreadable)} visual mesh file(s) "
                                   f"andyc view cannot draw (first: {unreadable[0]['filename']!r}); not drawn",
                                   "convert them to STL, OBJ or DAE (e.g. with meshlab or trimesh)"))
    if writer.odd_inertia:
        odd = sorted(writer.odd_inertia)
        n = len(odd)
        warnings.append(Diagnostic(file, odd[0][0], "robot", f"{n} link(s) have an inertia no rigid body has, "
                                   "simulated as written (as Pinocchio does): " + ", ".join(t for _, t in odd[:4])
                                   + (f" and {n - 4} more" if n > 4 else ""),
                                   "fix the <inertia> values if the mass matrix turns out singular"))
    if not data["dampers"]:
        del data["dampers"]
    if not data["bodies"]:
        del data["bodies"]
    return UrdfModel(data, UrdfSourceMap(file, draft.entries), warnings, writer.visuals, raw, tuple(o.lock),
                     file, contacts.option_paths, bool(contacts.colliding), contacts.stop_bounds)


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
    problems = []
    ground = geometry.ground_plane(data.get("ground"), lambda path, message, hint: problems.append(
        smap.diag(path, message, hint)))
    if problems:
        raise SpecError(problems)
    model = read(target, options, lambda path, message, hint="": smap.diag(("urdf",) + tuple(path), message, hint),
                 ground=ground)
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
    merged_map = MergedSourceMap(smap, model.source, counts, data)
    if model.option_paths:      # a generated contact's friction and restitution: the urdf: option's line
        merged_map = geometry.RedirectedSourceMap(merged_map, {path: ("urdf",) + option for path, option
                                                               in model.option_paths.items()})
    return merged, merged_map, model
