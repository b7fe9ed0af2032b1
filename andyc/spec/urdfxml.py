"""A URDF's XML with a line for every element: well-formedness, the link tree, what andyc leaves unused.

lxml parses the file (yourdfpy drops line numbers), so each problem names its
line and element, `robot.urdf:LINE: joint[j].parent: what; fix`, as the YAML
loader's do. The source maps send a document path of the model dictionary
made from a URDF (andyc.spec.urdf) back to the URDF element it came from.
"""

from __future__ import annotations

import math
import re

from andyc.errors import Diagnostic, SpecError
from andyc.spec.suggest import did_you_mean
from andyc.spec.yamlpos import SourceMap

JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
ONE_DOF = ("revolute", "continuous", "prismatic")
LIST_SECTIONS = ("frames", "bodies", "forces", "torques", "actuators", "dampers", "springs", "potentials", "constraints",
                 "contacts")
MAP_SECTIONS = ("parameters", "inputs", "coordinates", "speeds", "discrete")
# What andyc reads of each element; every other child is counted in the unused-elements warning.
_USED = {"robot": {"link", "joint"}, "link": {"inertial", "visual"}, "inertial": {"origin", "mass", "inertia"},
         "joint": {"parent", "child", "origin", "axis", "mimic", "dynamics"},
         "visual": {"origin", "geometry", "material"}}


class UrdfSourceMap(SourceMap):
    """Document paths of the generated dictionary -> (URDF line, element label)."""

    def __init__(self, file: str, entries: dict):
        super().__init__(file, {path: line for path, (line, _) in entries.items()})
        self.entries = entries

    def _entry(self, path):
        path = tuple(path)
        while path and path not in self.entries:
            path = path[:-1]
        return self.entries.get(path, (1, "robot"))

    def diag(self, path, message: str, hint: str = "") -> Diagnostic:
        line, label = self._entry(path)
        return Diagnostic(self.file, line, label, message, hint)

    def describe(self, path) -> str:
        line, label = self._entry(path)
        return f"{self.file}:{line}, {label}"


class MergedSourceMap(SourceMap):
    """A YAML model with a `urdf:` key: URDF entries first in each list section, the YAML's after.

    Paths into the merged dictionary are sent to the file they came from.
    """

    def __init__(self, yaml_map: SourceMap, urdf_map: UrdfSourceMap, counts: dict, yaml_data: dict):
        super().__init__(yaml_map.file, {})
        self.yaml, self.urdf, self.counts, self.yaml_data = yaml_map, urdf_map, counts, yaml_data

    def _route(self, path):
        path = tuple(path)
        if len(path) >= 2 and path[0] in LIST_SECTIONS and isinstance(path[1], int):
            n = self.counts.get(path[0], 0)
            return (self.urdf, path) if path[1] < n else (self.yaml, (path[0], path[1] - n) + path[2:])
        if len(path) >= 2 and path[0] in MAP_SECTIONS and path[1] not in (self.yaml_data.get(path[0]) or {}):
            return self.urdf, path
        if path[:1] == ("name",) and "name" not in self.yaml_data:
            return self.urdf, path
        return self.yaml, path

    def line(self, path) -> int:
        smap, path = self._route(path)
        return smap.line(path)

    def diag(self, path, message: str, hint: str = "") -> Diagnostic:
        smap, path = self._route(path)
        return smap.diag(path, message, hint)

    def describe(self, path) -> str:
        smap, path = self._route(path)
        return smap.describe(path)


# -- the XML ------------------------------------------------------------------

class XmlReader:
    """The XML with lines, checked before yourdfpy sees it; collects every problem."""

    def __init__(self, file: str, raw: bytes):
        self.file = file
        self.problems: list[Diagnostic] = []
        from lxml import etree
        # A document type can declare entities: an external one reads other files into the robot's names,
        # nested ones expand a few bytes into gigabytes. A URDF needs neither, and yourdfpy's own parse,
        # which comes after this one, would expand them.
        doctype = raw.find(b"<!DOCTYPE")
        if doctype >= 0:
            raise SpecError([Diagnostic(file, raw.count(b"\n", 0, doctype) + 1, "",
                                        "a document type declaration (<!DOCTYPE ...>) in a URDF",
                                        "remove it: andyc reads URDFs without DTDs or entities")])
        try:
            self.root = etree.fromstring(raw, etree.XMLParser(remove_comments=True, resolve_entities=False,
                                                              no_network=True))
        except etree.XMLSyntaxError as exc:
            line = exc.lineno or (exc.position[0] if exc.position else 1)
            raise SpecError([Diagnostic(file, line, "", f"invalid XML: {exc.msg}",
                                        "fix the XML syntax at this line (an unclosed tag or a stray character)")])
        if self.root.getroottree().docinfo.doctype:       # written in another encoding than the check above saw
            raise SpecError([Diagnostic(file, 1, "", "a document type declaration (<!DOCTYPE ...>) in a URDF",
                                        "remove it: andyc reads URDFs without DTDs or entities")])

    def error(self, element, label: str, message: str, hint: str = ""):
        self.problems.append(Diagnostic(self.file, element.sourceline or 1, label, message, hint))

    def numbers(self, element, attribute: str, label: str, count: int, default: str):
        """The `count` numbers of an attribute such as xyz="0 0 1", or None after reporting."""
        text = element.get(attribute, default) if element is not None else default
        try:
            values = [float(x) for x in text.split()]
        except ValueError:
            values = []
        if len(values) != count or not all(math.isfinite(v) for v in values):
            self.error(element, f"{label}.{attribute}", f"expected {count} finite number(s), got {text!r}",
                       f'write {attribute}="' + " ".join(["0"] * count) + '"')
            return None
        return values

    def origin(self, parent, label: str):
        """(xyz, rpy) of the <origin> child of `parent`, zeros when absent."""
        element = parent.find("origin")
        if element is None:
            return [0.0] * 3, [0.0] * 3
        xyz = self.numbers(element, "xyz", label + ".origin", 3, "0 0 0")
        rpy = self.numbers(element, "rpy", label + ".origin", 3, "0 0 0")
        return xyz or [0.0] * 3, rpy or [0.0] * 3

    def check(self) -> tuple[dict, dict]:
        """Names, types, references and numbers; returns (links, joints): name -> element."""
        root = self.root
        if root.tag != "robot":
            raise SpecError([Diagnostic(self.file, root.sourceline or 1, root.tag, f"the root element is "
                                        f"<{root.tag}>, not <robot>", "a URDF file holds one <robot name=...>")])
        if not root.get("name"):
            self.error(root, "robot", "the <robot> has no name", 'add name="..." (it names the model)')
        if root.find("link") is None:
            raise SpecError(self.problems + [Diagnostic(self.file, root.sourceline or 1, "robot", "the robot has "
                                                        "no links", "a URDF robot is <link> and <joint> elements "
                                                        "(is this an unexpanded xacro file?)")])
        links, joints = {}, {}
        for kind, table in (("link", links), ("joint", joints)):
            for element in root.findall(kind):
                name = element.get("name")
                if not name:
                    self.error(element, kind, f"a <{kind}> without a name", f'add name="..." to this <{kind}>')
                elif name in table:
                    self.error(element, f"{kind}[{name}]", f"duplicate {kind} '{name}' (first at line "
                               f"{table[name].sourceline})", f"give each {kind} its own name")
                else:
                    table[name] = element
        for name, j in joints.items():
            label = f"joint[{name}]"
            kind = j.get("type")
            if kind not in JOINT_TYPES:
                self.error(j, label, f"unknown joint type {kind!r}" if kind else "the joint has no type",
                           did_you_mean(kind, JOINT_TYPES) + "URDF joint types: " + ", ".join(JOINT_TYPES))
            for end in ("parent", "child"):
                element = j.find(end)
                link = element.get("link") if element is not None else None
                if not link:
                    self.error(element if element is not None else j, f"{label}.{end}",
                               f"the joint has no <{end} link=...>", f'add <{end} link="LINK"/>')
                elif link not in links:
                    self.error(element, f"{label}.{end}", f"{end} link '{link}' does not exist",
                               did_you_mean(link, links) + f'define <link name="{link}"/> or name an existing link')
            self.origin(j, label)
            if j.find("axis") is not None:
                axis = self.numbers(j.find("axis"), "xyz", label + ".axis", 3, "1 0 0")
                if axis is not None and kind in ONE_DOF + ("planar",) and not any(axis):
                    self.error(j.find("axis"), label + ".axis", "the axis is zero", 'give a direction such as xyz="0 0 1"')
            mimic = j.find("mimic")
            if mimic is not None:
                for attribute, default in (("multiplier", "1"), ("offset", "0")):
                    self.numbers(mimic, attribute, label + ".mimic", 1, default)
                if not mimic.get("joint"):
                    self.error(mimic, label + ".mimic", "<mimic> names no joint", 'add joint="JOINT"')
                if kind in ("planar", "floating"):
                    self.error(mimic, label + ".mimic", f"a {kind} joint cannot mimic another joint",
                               "mimic joints are revolute, continuous or prismatic; remove the <mimic>")
            limit = j.find("limit")
            for attribute in ("lower", "upper", "effort", "velocity"):
                text = limit.get(attribute) if limit is not None else None
                try:
                    float(text) if text is not None else None
                except ValueError:
                    self.error(limit, f"{label}.limit.{attribute}", f"expected a number, got {text!r}",
                               f'write {attribute}="1.57" (rad or m; -1.57 for a lower limit)')
            dynamics = j.find("dynamics")
            if dynamics is not None:
                for attribute in ("damping", "friction"):
                    self.numbers(dynamics, attribute, label + ".dynamics", 1, "0")
        for name, link in links.items():
            for kind in ("visual", "collision"):
                for element in link.findall(kind):
                    self.shape(element, f"link[{name}].{kind}")
            inertial = link.find("inertial")
            if inertial is None:
                continue
            label = f"link[{name}].inertial"
            self.origin(inertial, label)
            mass = inertial.find("mass")
            value = self.numbers(mass, "value", label + ".mass", 1, "0") if mass is not None else [0.0]
            if value is not None and value[0] < 0:
                self.error(mass, label + ".mass", f"negative mass {value[0]:g}", "give a mass >= 0 in kg")
            inertia = inertial.find("inertia")
            if inertia is not None:
                for attribute in ("ixx", "iyy", "izz", "ixy", "ixz", "iyz"):
                    self.numbers(inertia, attribute, label + ".inertia", 1, "0")
        return links, joints

    def shape(self, element, label: str):
        """A <visual> or <collision>: an origin and one box, cylinder, sphere or mesh (yourdfpy needs them)."""
        self.origin(element, label)
        geometry = element.find("geometry")
        shapes = [g for g in geometry if isinstance(g.tag, str)] if geometry is not None else []
        if not shapes or shapes[0].tag not in ("box", "cylinder", "sphere", "mesh"):
            self.error(geometry if geometry is not None else element, label + ".geometry",
                       "expected a box, cylinder, sphere or mesh, got "
                       + (f"<{shapes[0].tag}>" if shapes else "nothing"), "write one of <box size=...>, "
                       "<cylinder radius=... length=...>, <sphere radius=...>, <mesh filename=...>")

    def locate(self, text: str) -> tuple[int, str]:
        """(line, element) of the first attribute holding a value quoted in `text` (an error message)."""
        for value in re.findall(r"'([^']+)'", text):
            for element in self.root.iter():
                if isinstance(element.tag, str) and any(value in v for v in element.attrib.values()):
                    return element.sourceline or 1, element.tag
        return 1, "robot"

    def tree(self, links: dict, joints: dict) -> tuple[dict, str | None]:
        """parent joint of each link, and the root link; reports two parents, cycles and several roots."""
        parent_joint = {}
        for name, j in joints.items():
            child = j.find("child").get("link")
            if child in parent_joint:
                first = parent_joint[child]
                self.error(j.find("child"), f"joint[{name}].child", f"link '{child}' is already the child of joint "
                           f"'{first}' (line {joints[first].sourceline})", "a link has one parent joint; "
                           "URDF links form a tree")
            else:
                parent_joint[child] = name
        reported = set()
        for start in links:
            trail, link = [], start
            while link in parent_joint and link not in trail and link not in reported:
                trail.append(link)
                link = joints[parent_joint[link]].find("parent").get("link")
            if link in trail:
                cycle = trail[trail.index(link):]
                reported |= set(cycle)
                names = [parent_joint[x] for x in reversed(cycle)]
                j = joints[names[0]]
                self.error(j, f"joint[{names[0]}]", "the joints form a cycle: " + " -> ".join(names + names[:1])
                           + f" (links {' -> '.join(reversed(cycle + cycle[:1]))})",
                           "URDF links form a tree: remove one of these joints, or close the loop with a "
                           "constraint in a YAML model")
            reported |= set(trail)
        roots = [name for name in links if name not in parent_joint]
        if len(roots) > 1:
            extra = roots[1]
            self.error(links[extra], f"link[{extra}]", f"the links form {len(roots)} separate trees (roots "
                       + ", ".join(f"'{r}'" for r in roots) + ")", f"connect link '{extra}' with a joint, "
                       "or remove it")
        elif not roots and not reported:
            self.error(self.root, "robot", "the robot has no root link", "one link must be no joint's child")
        return parent_joint, (roots[0] if roots else None)

    def unused(self, limits: bool = False, colliding: frozenset = frozenset(),
               efforts: bool = False, friction: bool = False) -> Diagnostic | None:
        """One warning naming every kind of element andyc does not use, with counts. `limits`: joint limits
        are stops (their lower and upper are used, effort and velocity not); `colliding`: the links whose
        <collision> elements touch the ground; `efforts`: the joints' motors are clamped to their <limit effort>;
        `friction`: one-degree-of-freedom joints' <dynamics friction> is applied."""
        counts, first = {}, None
        joint_types = {j.get("name"): j.get("type") for j in self.root.findall("joint")}

        def note(kind, element):
            nonlocal first
            counts[kind] = counts.get(kind, 0) + 1
            if first is None or (element.sourceline or 0) < first:
                first = element.sourceline or 1

        def walk(element, parent_tag):
            for child in element:
                if not isinstance(child.tag, str):
                    continue
                if parent_tag == "joint" and child.tag == "limit" and (limits or efforts):
                    for attribute in ("lower", "upper") * (not limits) + ("effort",) * (not efforts) + ("velocity",):
                        if child.get(attribute) is not None:
                            note(f"<limit {attribute}>", child)
                    continue
                if parent_tag == "link" and child.tag == "collision" and element.get("name") in colliding:
                    continue
                if parent_tag in _USED and child.tag not in _USED[parent_tag]:
                    note(f"<{child.tag}>" if parent_tag == "robot" else f"<{parent_tag}><{child.tag}>", child)
                    continue
                if child.tag == "mimic" and joint_types.get(element.get("name")) == "fixed":
                    note("<mimic> on fixed joints", child)
                if child.tag == "dynamics":
                    if float(child.get("friction", "0") or 0) != 0 and \
                            (not friction or joint_types.get(element.get("name")) not in ONE_DOF):
                        note("<dynamics friction>" if not friction else
                             f"<dynamics friction> on {joint_types.get(element.get('name'))} joints", child)
                    if float(child.get("damping", "0") or 0) != 0 and \
                            joint_types.get(element.get("name")) not in ONE_DOF:
                        note(f"<dynamics damping> on {joint_types.get(element.get('name'))} joints", child)
                if child.tag in _USED:
                    walk(child, child.tag)

        walk(self.root, "robot")
        if not counts:
            return None
        listed = ", ".join(f"{n} {kind}" for kind, n in sorted(counts.items(), key=lambda kv: -kv[1]))
        return Diagnostic(self.file, first, "robot", f"not used by andyc (no effect on the simulation): {listed}",
                          "andyc simulates the rigid bodies, joints, mimic joints, joint damping, joint limits "
                          "(as stops, unless urdf: {limits: false}) and the collision geometry of the links named "
                          "in urdf: {collide: [...]}; visual geometry is kept in Spec.visuals")
