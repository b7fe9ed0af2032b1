"""Constraints (ANDY §2.3): holonomic rows Gamma(t, q) = 0 and nonholonomic rows J(t, q) v + b = 0.

- The rows, each with its multiplier name and the gains of the baumgarte method (ANDY eq. 15).
- Frame quantities in expressions (`F.x`, `F.vy`, `F.wz`), for constraints and for the hybrid
  automaton's guards, conditions and resets: one symbol per (frame, attribute, in frame) in the model.
- The check of `conserves_energy: true`: nothing in the model does work.
"""

from __future__ import annotations

import sympy as sp

from andyc.spec.elements import Elements
from andyc.spec.expressions import TIME, ExpressionError, parse
from andyc.spec.model import Constraint, FrameQuantity, Rotate, Translate
from andyc.spec.scope import Scope
from andyc.spec.suggest import did_you_mean

# Frame quantities in constraint expressions: F.<attribute> -> (kind, axis).
FRAME_QUANTITIES = {**{a: ("position", i) for i, a in enumerate("xyz")},
                    **{"v" + a: ("velocity", i) for i, a in enumerate("xyz")},
                    **{"w" + a: ("angular_velocity", i) for i, a in enumerate("xyz")}}
QUANTITY_HINT = ("frame quantities: F.x, F.y, F.z (position), F.vx, F.vy, F.vz (velocity), "
                 "F.wx, F.wy, F.wz (angular velocity), for a frame F")


class FrameQuantities:
    """The symbols of the frame quantities the model's expressions use, named once for the whole model."""

    def __init__(self, scope: Scope, bodies: list):
        self.scope = scope                  # with the frames declared
        self.body_frames = {}               # body name -> its frame, to suggest when a body is written as a frame
        for b in bodies:
            self.body_frames.setdefault(b["name"], b["frame"])
        self.names: dict[tuple, str] = {}   # (frame, attribute, in frame) -> its symbol's name

    def symbol(self, owner: str, attribute: str, in_frame: str, found: dict, holonomic: bool = False) -> sp.Symbol:
        """The symbol of `owner.attribute` (a FrameQuantity, recorded in `found`), or ExpressionError."""
        written = f"{owner}.{attribute}"
        known = sorted(self.scope.frames)
        if owner not in self.scope.frames:
            if owner in self.scope.declared:          # a body, a parameter, ... written as a frame
                frame = self.body_frames.get(owner)
                raise ExpressionError(f"'{owner}' is a {self.scope.kind_of(owner)}, not a frame",
                                      (f"use the frame it is on: '{frame}.{attribute}'" if frame else
                                       "frame quantities belong to frames") + "; known frames: " + ", ".join(known))
            raise ExpressionError(f"frame '{owner}' does not exist",
                                  did_you_mean(owner, known) + "known frames: " + ", ".join(known))
        if attribute not in FRAME_QUANTITIES:
            # 'tip.X' means 'tip.x', though the two are too short to be close for difflib.
            guess = attribute.lower() if attribute.lower() in FRAME_QUANTITIES else attribute
            raise ExpressionError(f"'{written}' is not a frame quantity",
                                  did_you_mean(guess, FRAME_QUANTITIES, prefix=f"{owner}.") + QUANTITY_HINT)
        kind, axis = FRAME_QUANTITIES[attribute]
        if holonomic and kind != "position":
            what = "a velocity" if kind == "velocity" else "an angular velocity"
            raise ExpressionError(f"'{written}' is {what}; a holonomic constraint depends on positions only",
                                  "write velocity constraints under 'nonholonomic:'; holonomic rows use "
                                  "F.x, F.y, F.z")
        if kind == "position" and owner == in_frame:
            raise ExpressionError(f"'{written}' is always 0: positions are measured from the origin of the "
                                  f"'in' frame, here '{in_frame}' itself",
                                  "use the position of another frame"
                                  + (f", or remove 'in: {in_frame}' to measure from world"
                                     if in_frame != "world" else ""))
        if kind != "position" and owner == "world":
            raise ExpressionError(f"'{written}' is always 0: the world frame does not move",
                                  "use the velocity of a moving frame")
        sym = sp.Symbol(self._name(owner, attribute, in_frame), real=True)
        found[sym] = FrameQuantity(owner, kind, axis, in_frame)
        return sym

    def _name(self, owner: str, attribute: str, in_frame: str) -> str:
        """The symbol name of a frame quantity, one per (frame, attribute, in frame) in the whole model: names
        may contain '_in_' themselves, so a name already given to another quantity gets a numbered suffix."""
        key = (owner, attribute, in_frame)
        if key not in self.names:
            base = f"fq_{owner}_{attribute}" + ("" if in_frame == "world" else f"_in_{in_frame}")
            taken = set(self.names.values())
            name, n = base, 1
            while name in taken:
                n += 1
                name = f"{base}_{n}"
            self.names[key] = name
        return self.names[key]


def build_constraints(written: list, scope: Scope, quantities: FrameQuantities,
                      contacts: list = ()) -> list[Constraint]:
    """The `constraints:` section, then the rows of the `contacts:` section's gaps (andyc.spec.contacts), holonomic
    ones first (DESIGN.md run layout; a contact's row is holonomic); multiplier names checked."""
    constraints = [_constraint(("constraints", i), c, scope, quantities) for i, c in enumerate(written)]
    constraints += [_constraint(("contacts", i), c, scope, quantities) for i, c in enumerate(contacts)]
    # A contact with friction: its stick row, the slip speed = 0 (nonholonomic), active while it sticks.
    constraints += [_constraint(("contacts", i), {"name": f"{c['name']}_stick", "slip": c["slip"],
                                                  "multiplier": c.get("friction_multiplier", f"friction_{c['name']}")},
                                scope, quantities) for i, c in enumerate(contacts) if "slip" in c]
    constraints.sort(key=lambda c: not c.holonomic)
    _check_multipliers(constraints, {"constraints": written, "contacts": contacts}, scope)
    return constraints


def _constraint(where: tuple, c: dict, scope: Scope, quantities: FrameQuantities) -> Constraint:
    """A constraint, or a contact's gap row (key `gap`: holonomic, one row) or stick row (key `slip`: its slip speed,
    nonholonomic, one row)."""
    holonomic = "holonomic" in c or "gap" in c
    key = "gap" if "gap" in c else "slip" if "slip" in c else "holonomic" if holonomic else "nonholonomic"
    texts = c[key] if isinstance(c[key], list) else [c[key]]
    paths = [where + (key, j) for j in range(len(texts))] if isinstance(c[key], list) else [where + (key,)]
    in_frame = c.get("in", "world")
    in_ok = scope.known_frame(in_frame, where + ("in",))
    found = {}

    def quantity(owner: str, attribute: str) -> sp.Symbol:
        return quantities.symbol(owner, attribute, in_frame, found, holonomic)

    if holonomic:
        names = scope.kinematic
        context = "holonomic constraints use parameters, coordinates, t and " + QUANTITY_HINT.split(", F.vx")[0]
    else:
        names = {**scope.kinematic, **scope.rates}
        context = ("nonholonomic constraints use parameters, coordinates, speeds (<coordinate>_dot and "
                   "declared speeds), t and " + QUANTITY_HINT)

    def row(text, path):
        """The parsed row, or None after reporting a problem in it."""
        if holonomic:
            # A speed is reported as a speed, not as an unknown name: parse once more with the speeds.
            try:
                trial = parse(text, {**names, **scope.rates}, True, quantity)
            except ExpressionError:
                trial = None
            speeds = [n for n, s in scope.rates.items() if trial is not None and s in trial.free_symbols]
            if speeds:
                scope.report.error(path, f"in {text!r}: '{speeds[0]}' is a speed; a holonomic constraint depends "
                                   "on positions only", "write velocity constraints under 'nonholonomic:'; "
                                   "holonomic rows use parameters, coordinates, t and F.x, F.y, F.z")
                return None
        before = len(scope.report.problems)
        value = scope.expr(text, path, names, context, dotted=quantity)
        return value if len(scope.report.problems) == before else None

    parsed = [row(text, path) for text, path in zip(texts, paths)]
    coordinates = {q.q for q in scope.coordinates} | {s for s, f in found.items() if f.kind == "position"}
    velocities = set(scope.rates.values()) | {s for s, f in found.items() if f.kind != "position"}
    for value, text, path in zip(parsed, texts, paths):
        if value is None:                           # reported already
            continue
        free = value.free_symbols
        if holonomic and not free & coordinates:
            if key == "gap":
                scope.report.error(path, f"the gap {text!r} does not depend on the coordinates or any frame "
                                   "position", "a contact's gap is the signed distance, >= 0 apart: write it with "
                                   "coordinates or F.x, F.y, F.z (e.g. gap: foot.y)")
            else:
                scope.report.error(path, f"the constraint {text!r} does not depend on the coordinates or any frame "
                                   "position", "a holonomic constraint is Gamma(t, q) = 0; use coordinates or F.x, "
                                   "F.y, F.z")
        if not holonomic:
            if not free & velocities and key == "slip":
                scope.report.error(path, f"the slip speed {text!r} uses no speed or velocity",
                                   "a contact's slip is the speed of its contact point along the tangent, linear "
                                   "in the speeds (e.g. slip: block.vx, or x_dot + r*th_dot for a disk)")
            elif not free & velocities:
                scope.report.error(path, f"the constraint {text!r} uses no speed or velocity",
                                   "a constraint on positions goes under 'holonomic:'; a nonholonomic one is "
                                   "J(q, t) speeds + b(q, t) = 0")
            elif any(sp.diff(value, a, b) != 0 for a in free & velocities for b in free & velocities):
                scope.report.error(path, f"in {text!r}: the constraint is not linear in the speeds and velocities",
                                   "a nonholonomic constraint is J(q, t) speeds + b(q, t) = 0; speeds and "
                                   "velocities may not be squared, multiplied together or inside functions")
    if "in" in c and in_ok and not found and None not in parsed:
        scope.report.error(where + ("in",), f"'in: {in_frame}' has no effect: the constraint uses no frame "
                           "quantity", f"remove 'in', or write the constraint with frame quantities such as "
                           f"{in_frame}.x (they are then taken in the axes of '" + in_frame + "')")
    rows = tuple(sp.Integer(0) if value is None else value for value in parsed)
    multipliers = c.get("multiplier")
    if multipliers is None:
        multipliers = [f"lambda_{c['name']}"] if len(rows) == 1 else [f"lambda_{c['name']}_{j}"
                                                                      for j in range(len(rows))]
    elif isinstance(multipliers, str):
        multipliers = [multipliers]
    if len(multipliers) != len(rows):
        scope.report.error(where + ("multiplier",), f"{len(multipliers)} multiplier name(s) for {len(rows)} "
                           f"constraint row(s)", f"give one name per row ({len(rows)})")
    gains = c.get("gains") or {}
    if "stiffness" in gains and not holonomic:
        scope.report.error(where + ("gains", "stiffness"), "a nonholonomic constraint has no stiffness (ANDY eq. "
                           "14: K_s = 0)", "remove 'stiffness'; 'damping' acts on the constraint's velocity residual")
    stiffness = _gain(gains, "stiffness", where, scope) if holonomic else sp.Integer(0)
    damping = _gain(gains, "damping", where, scope)
    return Constraint(c["name"], holonomic, rows, tuple(multipliers), stiffness, damping,
                      found, where, tuple(paths))


def _gain(gains: dict, key: str, where, scope: Scope) -> sp.Expr:
    path = where + ("gains", key)
    before = len(scope.report.problems)
    value, number = scope.constant(gains.get(key, 0), path, allow_time=True)
    if len(scope.report.problems) > before:             # a bad expression is reported already
        return value
    if TIME in value.free_symbols:
        scope.report.error(path, f"the {key} gain {gains[key]!r} depends on t",
                           "gains are constants: a number or an expression of parameters")
    elif number < 0:
        shown = f"{number:g}" if value.is_number else f"{gains[key]} = {number:g}"
        scope.report.error(path, f"the {key} gain is negative, got {shown}",
                           "give a gain >= 0 (a negative gain pushes the motion away from the constraint)")
    return value


def _check_multipliers(constraints: list, written: dict, scope: Scope):
    """Multiplier names are unique and taken by nothing else (they name run-file columns). written: the entries
    of each section, by section name."""
    made = {f"{q.name}_dot": f"the rate of coordinate '{q.name}'" for q in scope.coordinates}
    made.update({s.name: f"the {'position' if s.component in 'xyz' else 'quaternion'} signal of frame "
                         f"'{s.frame}'" for s in scope.signals})
    made.update({n: f"the run-file column '{n}'" for n in ("time", "flow", "energy")})
    seen = {}
    for c in sorted(constraints, key=lambda c: c.where):        # in document order, by section
        key = "friction_multiplier" if c.row_where[0][-1] == "slip" else "multiplier"   # a contact's stick row
        given = written[c.where[0]][c.where[1]].get(key)
        for j, name in enumerate(c.multipliers):
            if given is None:         # lambda_<constraint>: point at the name it comes from
                path, what = c.where + ("name",), f"the default multiplier name '{name}' of constraint '{c.name}'"
                fix = (f"name the multiplier: add 'multiplier: <name>' to constraint '{c.name}'" if key == "multiplier"
                       else "name the friction force: add 'friction_multiplier: <name>' to its contact")
            else:
                path = c.where + (key,) + ((j,) if isinstance(given, list) else ())
                what, fix = f"the multiplier name '{name}'", "choose another name"
            if name in seen:
                first = "earlier in this constraint" if seen[name] == c.name else f"in constraint '{seen[name]}'"
                scope.report.error(path, f"{what} is used twice (also {first})",
                                   fix if given is None else "give each constraint row its own multiplier name")
            elif name in scope.declared:
                scope.report.error(path, f"{what} is taken by a {scope.kind_of(name)}", fix)
            elif name in made:
                scope.report.error(path, f"{what} is taken by {made[name]}", fix)
            seen.setdefault(name, c.name)


# -- conserves_energy ----------------------------------------------------------------

def check_conservative(elements: Elements, constraints: list, frames: list, written: list, scope: Scope):
    """conserves_energy: nothing in the model may do work on it.

    A holonomic constraint does work when it depends on t; a nonholonomic row J v + b = 0 when its
    term without speeds, b, is not 0 (J may depend on t: its force is normal to every allowed velocity).
    `written`: the `constraints:` section as written (a row is named as written).
    """
    workers = [f"damper '{x.name}'" for x in elements.dampers] + [f"{x.kind} '{x.name}'" for x in elements.loads]
    # (Rows without coordinates, or without speeds, are reported by _constraint() already.)
    for c in sorted(constraints, key=lambda c: c.where[1]):
        if c.holonomic:
            positions = {q.q for q in scope.coordinates} | set(c.quantities)
            if any(TIME in r.free_symbols and r.free_symbols & positions for r in c.rows):
                workers.append(f"constraint '{c.name}' (depends on t)")
            continue
        speeds = set(scope.rates.values()) | {s for s, f in c.quantities.items() if f.kind != "position"}
        texts = written[c.where[1]]["nonholonomic"]
        texts = texts if isinstance(texts, list) else [texts]
        rest = [text for r, text in zip(c.rows, texts)
                if r.free_symbols & speeds and sp.expand(r.subs({s: 0 for s in speeds})) != 0]
        if rest:
            workers.append(f"constraint '{c.name}' ({rest[0]!r} has a term without speeds)")
    workers += [f"frame '{f.name}' (its link depends on t)" for f in frames
                if any(TIME in _free(step) for step in f.transforms)]
    workers += [f"spring '{x.name}' (depends on t)" for x in elements.springs
                if x.length is not None and TIME in x.length.free_symbols]
    workers += [f"potential '{x.name}' (depends on t)" for x in elements.potentials
                if TIME in x.energy.free_symbols]
    if workers:
        scope.report.error(("conserves_energy",), "the model declares energy conserved, but " + ", ".join(workers)
                           + (" does" if len(workers) == 1 else " do") + " work",
                           "remove 'conserves_energy: true', or the elements that do work")


def _free(step) -> set:
    """Free symbols of a link step."""
    if isinstance(step, Translate):
        return step.vector.free_symbols
    if isinstance(step, Rotate):
        return step.angle.free_symbols
    parts = [m for m in (step.velocity, step.angular_velocity) if m is not None]
    return set().union(*(m.free_symbols for m in parts)) if parts else set()
