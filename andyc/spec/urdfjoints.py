"""A URDF's joints as andyc's names and coordinates.

- `Draft`: the model dictionary being written from a URDF, the URDF element each of its entries comes
  from (for the source map) and the andyc names claimed so far: two URDF names may become one identifier.
- `link_order`: the links kept (the subtree of the root link), depth first in document order.
- `joint_motions`: what moves each kept joint: a coordinate named after it, the value `lock:` holds it
  at, or, for a mimic joint, multiplier * q + offset of the joint it follows (possibly through other
  mimic joints). A planar joint gets three coordinates, <joint>_x, <joint>_y, <joint>_theta.
"""

from __future__ import annotations

import re
import keyword

from andyc.spec.expressions import RESERVED
from andyc.spec.suggest import did_you_mean
from andyc.spec.urdfxml import ONE_DOF, XmlReader

GRAVITY = 9.81


def identifier(name: str, kind: str) -> str:
    """A URDF name as an andyc name: letters, digits, '_'; starts with a letter; not reserved."""
    out = re.sub(r"[^A-Za-z0-9_]", "_", name)
    if not out or not out[0].isalpha():
        out = f"{kind}_{out}"
    if out in RESERVED or keyword.iskeyword(out):
        out += "_"
    return out


def as_written(x: float):
    """A float as written in the model dictionary: an int when it is one (keeps zeros exact)."""
    return int(x) if float(x).is_integer() and abs(x) < 2**53 else float(x)


class Draft:
    """The model dictionary a URDF becomes, where each entry comes from, and the names it claims."""

    def __init__(self, reader: XmlReader):
        self.reader = reader
        self.data: dict = {"parameters": {"g": GRAVITY}, "coordinates": {}, "gravity": [0, 0, "-g"], "frames": [],
                           "bodies": [], "dampers": []}
        self.entries: dict = {}         # document path -> (URDF line, element label)
        self.names: dict = {}           # andyc name -> (line, label) of the URDF element it comes from

    @staticmethod
    def line(element) -> int:
        return element.sourceline or 1

    def name(self, andyc_name: str, element, label: str) -> str:
        """Claim an andyc name for a URDF element; a second claim is a clash."""
        if andyc_name in self.names:
            line, first = self.names[andyc_name]
            self.reader.error(element, label, f"the name '{andyc_name}' is also made from {first} (line {line})",
                              "rename one of them in the URDF (names are turned into identifiers: "
                              "letters, digits and '_')")
        else:
            self.names[andyc_name] = (self.line(element), label)
        return andyc_name

    def entry(self, path, element, label):
        self.entries[path] = (self.line(element) if element is not None else 1, label)


def link_order(joints: dict, parent_joint: dict, root: str) -> tuple[list, dict]:
    """(the links of root's subtree, depth first in document order; link -> its child links)."""
    kids = {}
    for j in joints.values():
        kids.setdefault(j.find("parent").get("link"), []).append(j.find("child").get("link"))
    kept, stack = [], [root]
    while stack:
        link = stack.pop()
        kept.append(link)
        stack.extend(kids.get(link, []))
    children = {}
    for link in kept:
        if link != root:
            parent = joints[parent_joint[link]].find("parent").get("link")
            children.setdefault(parent, []).append(link)
    order, stack = [], [root]
    while stack:                                    # depth first, in document order
        link = stack.pop()
        order.append(link)
        stack.extend(reversed(children.get(link, [])))
    return order, children


def joint_motions(draft: Draft, joints: dict, moving: list, lock: dict, option_error) -> tuple[dict, dict]:
    """(joint -> the expression of its 1-DOF motion: a coordinate, a mimic expression, a locked value;
    mimic joint -> (expression, independent joint or None, product of the multipliers)).

    `moving`: the kept joints, in link order; their coordinates are added to the draft. A problem with
    `lock` is reported through `option_error(path, message, hint)`."""
    for name in lock:
        if name not in joints:
            option_error(("lock", name), f"joint '{name}' does not exist in the URDF",
                         did_you_mean(name, joints) + "lock joints by their URDF name")
        elif name not in moving:
            option_error(("lock", name), f"joint '{name}' is not in the kept subtree", "remove it from 'lock'")
        elif joints[name].get("type") not in ONE_DOF:
            option_error(("lock", name), f"joint '{name}' is {joints[name].get('type')}: only revolute, "
                         "continuous and prismatic joints can be locked", "remove it from 'lock'")
        elif joints[name].find("mimic") is not None:
            master = joints[name].find("mimic").get("joint")
            option_error(("lock", name), f"joint '{name}' mimics joint '{master}'",
                         f"lock '{master}' instead (its mimic joints follow it)")
    out = {}
    for jname in moving:
        j = joints[jname]
        kind, label = j.get("type"), f"joint[{jname}]"
        if kind in ONE_DOF and j.find("mimic") is None:
            if jname in lock:
                value = lock[jname]
                out[jname] = value if isinstance(value, str) else as_written(value)
            else:
                coord = draft.name(identifier(jname, "joint"), j, label)
                draft.data["coordinates"][coord] = {"initial": 0}
                draft.entry(("coordinates", coord), j, label)
                out[jname] = coord
        elif kind == "planar":
            base = identifier(jname, "joint")
            for c in ("x", "y", "theta"):
                coord = draft.name(f"{base}_{c}", j, label)
                draft.data["coordinates"][coord] = {"initial": 0}
                draft.entry(("coordinates", coord), j, label)
    mimics = _Mimics(draft.reader, joints)
    for jname in moving:                            # mimic joints, possibly of mimic joints
        if joints[jname].find("mimic") is not None and joints[jname].get("type") in ONE_DOF:
            out[jname] = mimics.resolve(jname, out, [])[0]
    return out, mimics.found


class _Mimics:
    """Mimic joints resolved down their chains to an independent joint, each once."""

    def __init__(self, reader: XmlReader, joints: dict):
        self.reader = reader
        self.joints = joints
        self.found: dict = {}           # joint -> (expression, independent joint or None, gain)

    def resolve(self, jname: str, done: dict, trail: list) -> tuple:
        """(multiplier * q + offset of the joint it follows, the independent joint at the chain's end, the
        product of the multipliers); after a reported problem, ("0", None, 0).

        `done`: joint -> its motion, for the joints resolved so far; `trail`: the mimic joints on the way
        here (a loop back is reported)."""
        if jname in self.found:
            return self.found[jname]
        j = self.joints[jname]
        m = j.find("mimic")
        label = f"joint[{jname}].mimic"
        master = m.get("joint")
        broken = ("0", None, 0.0)
        if master == jname:
            self.reader.error(m, label, f"joint '{jname}' mimics itself", "name another joint, or remove the mimic")
            return broken
        if jname in trail:
            self.reader.error(m, label, "mimic joints form a loop: " + " -> ".join(trail + [jname]),
                              "one of them must be an independent joint")
            return broken
        self.found[jname] = broken                      # until resolved (a loop back here stops)
        following = master in self.joints and self.joints[master].find("mimic") is not None \
            and self.joints[master].get("type") in ONE_DOF
        if master not in self.joints:
            self.reader.error(m, label, f"mimicked joint '{master}' does not exist",
                              did_you_mean(master, self.joints) + "name a joint of this URDF")
            return broken
        if master not in done and not following:
            self.reader.error(m, label, f"mimicked joint '{master}' is "
                              + ("not in the kept subtree" if self.joints[master].get("type") in ONE_DOF
                                 else f"a {self.joints[master].get('type')} joint"),
                              "a mimic joint follows a revolute, continuous or prismatic joint of the model")
            return broken
        if following:
            source, independent, gain = self.resolve(master, done, trail + [jname])
        else:
            source, independent, gain = done[master], master, 1.0
        if independent is None:
            return broken
        mult, off = (float(m.get(a, d)) for a, d in (("multiplier", "1"), ("offset", "0")))
        expr = f"({source})" if not re.fullmatch(r"[A-Za-z_][A-Za-z0-9_]*|-?[0-9.eE+-]+", str(source)) else str(source)
        text = expr if mult == 1 else f"{mult!r}*{expr}"
        text = text if off == 0 else f"{text} + {off!r}" if off > 0 else f"{text} - {-off!r}"
        self.found[jname] = (text, independent, gain * mult)
        return self.found[jname]
