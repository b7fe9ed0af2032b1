"""A URDF's contacts: its links' `<collision>` shapes against the ground, and its joints' limits as stops.

- `urdf: {collide: [FR_foot, "*_foot"], friction: mu, restitution: e}`: the collision shapes of the links
  named (URDF names or fnmatch patterns, of the kept subtree) touch the model's `ground:`, each shape its
  contact points (andyc.spec.geometry: a sphere its centre, a box its corners, a cylinder its rims sampled;
  a mesh gives none, with a warning naming the link). `friction` and `restitution` (expressions of
  parameters) are every such contact's; without `friction` they are frictionless. A pattern takes the
  moving links it matches that have collision geometry; a link named exactly must exist, be kept, move
  and have some.
- `urdf: {limits: true}` (the default): each revolute or prismatic joint's `<limit lower upper>` become two
  frictionless, plastic contacts on its coordinate q: `<joint>_lower` (gap q - lower) and `<joint>_upper`
  (gap upper - q). None for continuous joints, mimic joints (they follow another joint's coordinate), locked
  joints, a side not written (URDF's default 0 would hold the joint), an infinite side, or a joint whose
  lower is not below its upper (named in a warning).

The entries go into the draft like the links' frames, each pointing at its URDF element (`<collision>`,
`<limit>`); the friction and restitution of collision contacts point at the YAML option (option_paths).
"""

from __future__ import annotations

import fnmatch
import math

from andyc.spec import geometry
from andyc.spec.suggest import did_you_mean
from andyc.spec.urdfjoints import identifier

STOP_TYPES = ("revolute", "prismatic")


class ContactWriter:
    """Writes a URDF's contacts into the draft of its LinkWriter (andyc.spec.urdflinks)."""

    def __init__(self, writer, option_error):
        self.writer, self.draft, self.reader = writer, writer.draft, writer.reader
        self.options = writer.options
        self.option_error = option_error
        self.option_paths: dict = {}        # document path of a generated entry -> path in the urdf: options
        self.mesh_links: list = []          # (line, link) of collision meshes of colliding links: no contact
        self.odd_limits: list = []          # (line, text) of limits with lower >= upper: no stop
        self.colliding: list = []           # the links whose collision geometry gives contacts
        self.stops = False                  # limits were read (any joint's)
        self.stop_bounds: dict = {}         # stop contact -> (joint, coordinate, side, bound): andyc.spec.load drops
        #                                     a stop its joint starts beyond (a robot's zero pose past a limit)

    # collision geometry -------------------------------------------------------------
    def moving(self, order: list, root: str) -> dict:
        """link -> whether it moves: some joint between it and world is not fixed or locked, or the base
        floats."""
        moves = {}
        for link in order:
            if link == root:
                moves[link] = self.options.base == "floating"
                continue
            j = self.writer.joints[self.writer.parent_joint[link]]
            parent = j.find("parent").get("link")
            moves[link] = moves[parent] or (j.get("type") != "fixed" and j.get("name") not in self.options.lock)
        return moves

    def select(self, order: list, root: str) -> list:
        """The links `collide` names, in link order; each name or pattern that selects none reported."""
        o = self.options
        links = self.writer.links
        moves = self.moving(order, root)
        kept = set(order)
        eligible = [link for link in order if moves[link] and links[link].find("collision") is not None]
        chosen = set()
        for k, pattern in enumerate(o.collide):
            where = ("collide", k)
            if not any(c in pattern for c in "*?["):
                if pattern not in links:
                    self.option_error(where, f"link '{pattern}' does not exist in the URDF",
                                      did_you_mean(pattern, links) + "name links by their URDF name, or give a "
                                      "pattern such as '*_foot'")
                elif pattern not in kept:
                    self.option_error(where, f"link '{pattern}' is not in the kept subtree",
                                      "remove it from 'collide'")
                elif links[pattern].find("collision") is None:
                    self.option_error(where, f"link '{pattern}' has no <collision> element",
                                      "give it collision geometry in the URDF, or remove it from 'collide'")
                elif not moves[pattern]:
                    self.option_error(where, f"link '{pattern}' does not move (it is fixed to world), so it "
                                      "cannot touch the ground or leave it", "remove it from 'collide' (or "
                                      "float the robot: 'base: floating')")
                else:
                    chosen.add(pattern)
                continue
            found = [link for link in eligible if fnmatch.fnmatchcase(link, pattern)]
            if not found:
                names = ", ".join(eligible[:12]) + (f" and {len(eligible) - 12} more" if len(eligible) > 12 else "")
                self.option_error(where, f"no moving link with a <collision> element matches '{pattern}'",
                                  f"moving links with collision geometry: {names}" if eligible else
                                  "no moving link of the robot has collision geometry")
            chosen.update(found)
        return [link for link in order if link in chosen]

    def collisions(self, order: list, root: str, ground) -> None:
        """The contacts of the selected links' collision shapes on `ground`."""
        o = self.options
        if not o.collide:
            for key in ("friction", "restitution"):
                if getattr(o, key) is not None:
                    self.option_error((key,), f"'{key}' without 'collide' has no effect",
                                      "name the links that touch the ground in 'collide: [...]', or remove it")
            return
        selected = self.select(order, root)
        if ground is None:
            self.option_error(("collide",), "colliding links need a ground to touch",
                              "add 'ground: {normal: [0, 0, 1], height: 0}' to the model (the plane they touch)")
            return
        self.colliding = selected
        for link in selected:
            elements = self.writer.links[link].findall("collision")
            for k, element in enumerate(elements):
                points = self.points(link, element)
                if points is None:
                    continue
                frame = self.writer.frame_name(link, root)
                base = frame + (f"_{k}" if len(elements) > 1 else "")
                frames, contacts = geometry.contact_entries(frame, base, points, ground, o.friction, o.restitution)
                self.add(frames, contacts, element, f"link[{link}].collision")

    def points(self, link: str, element) -> list | None:
        """The contact points of one <collision> (in the link's frame); None for a mesh (noted for the
        warning) or after reporting bad sizes."""
        label = f"link[{link}].collision"
        shape = next(g for g in element.find("geometry") if isinstance(g.tag, str))   # checked by the reader
        if shape.tag == "mesh":
            self.mesh_links.append((self.draft.line(element), link))
            return None
        at = f"{label}.geometry.{shape.tag}"
        values = {}
        for attribute, count in {"sphere": (("radius", 1),), "box": (("size", 3),),
                                 "cylinder": (("radius", 1), ("length", 1))}[shape.tag]:
            numbers = self.reader.numbers(shape, attribute, at, count, "")
            if numbers is None:
                return None
            if not all(x > 0 for x in numbers):
                self.reader.error(shape, f"{at}.{attribute}", f"the {attribute} {shape.get(attribute)!r} is not "
                                  "positive", "give sizes > 0 in m")
                return None
            values[attribute] = numbers if count == 3 else numbers[0]
        xyz, rpy = self.reader.origin(element, label)
        return geometry.shape_points(shape.tag, values.get("size"), values.get("radius"), values.get("length"),
                                     (0.0, 0.0, 1.0), xyz, rpy)

    def add(self, frames: list, contacts: list, element, label: str) -> None:
        """Append generated frames and contacts to the draft, their names claimed and their places kept."""
        data = self.draft.data
        for f in frames:
            self.draft.name(f["name"], element, label)
            self.draft.entry(("frames", len(data["frames"])), element, label)
            data["frames"].append(f)
        out = data.setdefault("contacts", [])
        for c in contacts:
            self.draft.name(c["name"], element, label)
            path = ("contacts", len(out))
            self.draft.entry(path, element, label)
            for key in ("friction", "restitution"):
                if key in c and element.tag == "collision":
                    self.option_paths[path + (key,)] = (key,)
            out.append(c)

    # joint limits ---------------------------------------------------------------
    def limits(self, order: list, root: str) -> None:
        """Two stops per revolute or prismatic joint with limits (see the module docstring)."""
        if not self.options.limits:
            return
        self.stops = True
        for link in order:
            if link == root:
                continue
            jname = self.writer.parent_joint[link]
            j = self.writer.joints[jname]
            limit = j.find("limit")
            if (j.get("type") not in STOP_TYPES or limit is None or j.find("mimic") is not None
                    or jname in self.options.lock):
                continue
            label = f"joint[{jname}].limit"
            bounds = {}
            for side in ("lower", "upper"):
                text = limit.get(side)
                if text is None:
                    continue
                value = float(text)                 # a number: checked by the reader
                if math.isfinite(value):
                    bounds[side] = value
            if len(bounds) == 2 and not bounds["lower"] < bounds["upper"]:
                self.odd_limits.append((self.draft.line(limit), f"{jname} (lower {bounds['lower']:g}, upper "
                                        f"{bounds['upper']:g})"))
                continue
            q = self.writer.coordinate_of[jname]
            base = identifier(jname, "joint")
            contacts = []
            if "lower" in bounds:
                contacts.append({"name": f"{base}_lower", "gap": geometry.combination([(1, q)], -bounds["lower"])})
            if "upper" in bounds:
                contacts.append({"name": f"{base}_upper", "gap": f"{bounds['upper']!r} - {q}"})
            for c, side in zip(contacts, [k for k in ("lower", "upper") if k in bounds]):
                self.stop_bounds[c["name"]] = (jname, q, side, bounds[side])
            self.add([], contacts, limit, label)
