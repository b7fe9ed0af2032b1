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
    """The `constraints:` section, then the rows of the `contacts:` section's gaps (andyc.spec.contacts; an entry None
    is left out), holonomic ones first (docs/run-file.md; a contact's row is holonomic); multiplier names
    checked."""
    constraints = [_constraint(("constraints", i), c, scope, quantities) for i, c in enumerate(written)]
    constraints += [_constraint(("contacts", i), c, scope, quantities) for i, c in enumerate(contacts) if c]
    # A contact with friction: its stick row, the slip speed = 0 (nonholonomic), active while it sticks; spatial
    # friction (slip: a list of two tangential speeds): one constraint of two rows.
    constraints += [_constraint(("contacts", i), {"name": f"{c['name']}_stick", "slip": c["slip"],
                                                  "multiplier": c.get("friction_multiplier", _friction_names(c))},
                                scope, quantities) for i, c in enumerate(contacts) if c and "slip" in c]
    constraints.sort(key=lambda c: not c.holonomic)
    _check_multipliers(constraints, {"constraints": written, "contacts": contacts}, scope)
    return constraints


def _friction_names(contact: dict):
    """The default names of a contact's friction forces: friction_<contact>, or friction_<contact>_1 and _2 (two
    tangents)."""
    base = f"friction_{contact['name']}"
    return [f"{base}_1", f"{base}_2"] if isinstance(contact["slip"], list) else base


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
    nonlinear = []                                  # the nonholonomic rows not linear in the speeds
    for j, (value, text, path) in enumerate(zip(parsed, texts, paths)):
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
        elif holonomic and key != "gap":          # (a contact's gap: andyc.spec.contacts' rules)
            kinks = sorted({str(f.func).lower() for f in sp.preorder_traversal(value)
                            if isinstance(f, _KINKS) and f.free_symbols & (coordinates | {TIME})})
            if kinks:
                scope.report.error(path, f"in {text!r}: the constraint is not smooth: its derivatives jump where "
                                   f"{' or '.join(kinks)} of a coordinate or of t switches branch, and the row is "
                                   "differentiated twice along the motion", "write a smooth row (square both sides, "
                                   "e.g. x**2 - y**2 for abs(x) - y), or keep one branch and end the flow with a "
                                   "guard where it would switch")
                parsed[j] = None
        if not holonomic:
            if key == "slip":                       # a contact's slip speed: linear in the speeds
                if not free & velocities:
                    scope.report.error(path, f"the slip speed {text!r} uses no speed or velocity",
                                       "a contact's slip is the speed of its contact point along the tangent, "
                                       "linear in the speeds (e.g. slip: block.vx, or x_dot + r*th_dot for a disk)")
                elif any(sp.diff(value, a, b) != 0 for a in free & velocities for b in free & velocities):
                    scope.report.error(path, f"in {text!r}: the slip speed is not linear in the speeds and "
                                       "velocities", "a contact's slip is J(q, t) speeds + b(q, t); speeds and "
                                       "velocities may not be squared, multiplied together or inside functions")
                continue
            kind = _nonholonomic_row(value, text, path, velocities, scope)
            if kind is None:                        # reported: no later check looks at the row again
                parsed[j] = sp.Integer(0)
            elif kind == "nonlinear":
                nonlinear.append(j)
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
        scope.report.error(where + ("friction_multiplier" if key == "slip" else "multiplier",),
                           f"{len(multipliers)} multiplier name(s) for {len(rows)} constraint row(s)",
                           f"give one name per row ({len(rows)})")
    gains = c.get("gains") or {}
    if "stiffness" in gains and not holonomic:
        scope.report.error(where + ("gains", "stiffness"), "a nonholonomic constraint has no stiffness (ANDY eq. "
                           "14: K_s = 0)", "remove 'stiffness'; 'damping' acts on the constraint's velocity residual")
    stiffness = _gain(gains, "stiffness", where, scope) if holonomic else sp.Integer(0)
    damping = _gain(gains, "damping", where, scope)
    return Constraint(c["name"], holonomic, rows, tuple(multipliers), stiffness, damping,
                      found, where, tuple(paths), tuple(nonlinear))


def _nonholonomic_row(value: sp.Expr, text: str, path: tuple, velocities: set, scope: Scope) -> str | None:
    """"linear" or "nonlinear" for a valid nonholonomic row Phi_v(t, q, v) = 0 (Braun & Goldfarb §2, item c),
    after reporting the row if it is none: it must use a speed or a frame velocity, its velocity Jacobian
    A = dPhi_v/dv may not vanish identically (the row would not constrain the speeds: Phi_v = 0 says
    nothing about the motion, or holds of positions only), and a row nonlinear in the speeds must be
    smooth in them (A continuous), since A and the acceleration-level form A dv/dt + kappa = 0 are
    taken along the motion (andyc.symbolic.constraints)."""
    moving = value.free_symbols & velocities
    if not moving:
        scope.report.error(path, f"the constraint {text!r} uses no speed or velocity",
                           "a constraint on positions goes under 'holonomic:'; a nonholonomic one is "
                           "Phi(t, q, speeds) = 0, e.g. J(q, t) speeds + b(q, t) = 0")
        return None
    gradient = [sp.diff(value, s) for s in sorted(moving, key=str)]
    if all(_vanishes(d) for d in gradient):
        scope.report.error(path, f"in {text!r}: the derivative of the constraint with respect to the speeds is "
                           "identically 0, so it does not constrain them",
                           "simplify the row: a constraint on positions goes under 'holonomic:'; a nonholonomic "
                           "one changes with the speeds (its Jacobian dPhi/dv is what the constraint force acts "
                           "along)")
        return None
    if all(sp.diff(d, s) == 0 for d in gradient for s in moving):
        return "linear"
    kinks = sorted({str(f.func).lower() for f in sp.preorder_traversal(value)
                    if isinstance(f, _KINKS) and f.free_symbols & velocities})
    if kinks:
        scope.report.error(path, f"in {text!r}: the constraint is not smooth in the speeds: its derivative "
                           f"jumps where {' or '.join(kinks)} of a speed or velocity switches branch",
                           "write a smooth row (a row nonlinear in the speeds needs its Jacobian dPhi/dv along "
                           "the motion): square both sides, e.g. x_dot**2 - c**2, or keep one branch, e.g. "
                           "x_dot - c")
        return None
    return "nonlinear"


# Functions whose derivative jumps: a row using them of the speeds (nonholonomic), of the coordinates or of t
# (holonomic) has a discontinuous Jacobian, or one with no derivative where it switches (DiracDelta).
_KINKS = (sp.Abs, sp.sign, sp.Min, sp.Max)


def _vanishes(e: sp.Expr) -> bool:
    """e is identically 0: at once, or after simplification (rows are short user expressions; a long one is
    not simplified, and counts as not 0). A value clearly not 0 at a generic point settles it without
    simplifying."""
    if e == 0:
        return True
    point = {s: sp.Float(0.3 + 0.137 * i) for i, s in enumerate(sorted(e.free_symbols, key=str))}
    try:
        value = complex(e.xreplace(point).evalf())
    except (TypeError, ValueError):         # not a number there (a pole, nan): simplify instead
        value = 0.0
    if abs(value) > 1e-9:
        return False
    return sp.count_ops(e) <= 200 and sp.simplify(e) == 0


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
    made.update({n: f"the run-file column '{n}'" for n in ("time", "flow", "energy", "energy_balance")})
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
    A row Phi_v nonlinear in the speeds v acts along A = dPhi_v/dv, so its power is lam A v: it does no
    work when A v vanishes wherever Phi_v does, i.e. when A v / Phi_v is free of the speeds (Euler: a row
    homogeneous of degree k in the speeds and frame velocities has A v = k Phi_v; Appell-Hamel's
    z_dot - k sqrt(x_dot^2 + y_dot^2) does no work, Gauss's isokinetic |v|^2 - c does).
    `written`: the `constraints:` section as written (a row is named as written).
    """
    workers = [f"damper '{x.name}'" for x in elements.dampers] + [f"{x.kind} '{x.name}'" for x in elements.loads] + [
        f"actuator '{x.name}'" for x in elements.actuators]
    # (Rows without coordinates, or without speeds, are reported by _constraint() already.)
    speeds = set(scope.rates.values())
    positions = {q.q for q in scope.coordinates}
    for c in sorted(constraints, key=lambda c: c.where[1]):
        rows = working_rows(c, positions, speeds)
        if not rows:
            continue
        if c.holonomic:
            workers.append(f"constraint '{c.name}' (depends on t)")
            continue
        texts = written[c.where[1]]["nonholonomic"]
        texts = texts if isinstance(texts, list) else [texts]
        i = rows[0]
        why = ("has a force whose power lam dPhi/dv v is not 0 on the motion" if i in c.nonlinear
               else "has a term without speeds")
        workers.append(f"constraint '{c.name}' ({texts[i]!r} {why})")
    workers += [f"frame '{name}' (its link depends on t)" for name in rheonomic_frames(frames)]
    workers += [f"spring '{x.name}' (depends on t)" for x in elements.springs
                if x.length is not None and TIME in x.length.free_symbols]
    workers += [f"potential '{x.name}' (depends on t)" for x in elements.potentials
                if TIME in x.energy.free_symbols]
    if workers:
        scope.report.error(("conserves_energy",), "the model declares energy conserved, but " + ", ".join(workers)
                           + (" does" if len(workers) == 1 else " do") + " work",
                           "remove 'conserves_energy: true', or the elements that do work")


def _works(row: sp.Expr, speeds: set) -> bool:
    """A row nonlinear in the speeds does work: A v / Phi_v depends on the speeds (see check_conservative)."""
    power = sum((sp.diff(row, s) * s for s in row.free_symbols & speeds), sp.Integer(0))
    return bool(sp.simplify(power / row).free_symbols & speeds)


def check_energy_law(data: dict, frames: list, constraints: list, flows: list, initial_flow: int, scope: Scope):
    """Where the model asks for the energy correction (`energy_correction: true` in its simulate: section or an
    expectation), its law E(t) - E(0) - W(t) = 0 (Braun & Goldfarb eq. 5-6, W the work of every element,
    andyc/symbolic/work.py) must make sense: a speed left for the correction to move (fewer constraint rows
    than speeds in the initial flow)."""
    places = [("simulate", "energy_correction")] if (data.get("simulate") or {}).get("energy_correction") else []
    places += [("expect", i, "energy_correction") for i, e in enumerate(data.get("expect") or [])
               if isinstance(e, dict) and e.get("energy_correction")]
    if not places:
        return
    speeds = len(scope.coordinates) + len(scope.speeds)
    active = set(flows[initial_flow].constraints) if flows else {c.name for c in constraints}
    rows = sum(len(c.rows) for c in constraints if c.name in active)
    for path in places:
        if rows >= speeds:
            scope.report.error(path, f"the energy law has no speed to correct: the {rows} constraint rows of the "
                               f"initial flow fix all {speeds} speeds", "remove energy_correction")


def check_work_names(data: dict, jumps: list, scope: Scope):
    """A model with jumps carries the energy they change as the work slot 'jumps' (andyc/symbolic/work.py, the
    run files' work_jumps and power_jumps); any model may carry the slots 'baumgarte' and 'prescribed_motion'
    (the baumgarte method's forces off the manifold, the links that depend on t): no element that does work may
    take those names."""
    reserved = {"baumgarte": "the baumgarte method's constraint forces off the manifold",
                "prescribed_motion": "what drives the links that depend on t"}
    if jumps:
        reserved["jumps"] = "the model's jumps"
    for section in ("forces", "torques", "actuators", "dampers", "springs", "potentials", "constraints"):
        for i, entry in enumerate(data.get(section) or []):
            name = entry.get("name") if isinstance(entry, dict) else None
            if name in reserved:
                scope.report.error((section, i, "name"), f"the name '{name}' is taken by the work of "
                                   f"{reserved[name]} (the run files' work_{name}, power_{name})",
                                   "choose another name")


def working_rows(c: Constraint, positions: set, speeds: set) -> list[int]:
    """The rows of constraint c whose force does work on the motion (their power -lam b is not 0): a holonomic row
    Gamma(t, q) that depends on t (b = dGamma/dt), a nonholonomic row J v + b with a term b without speeds.
    positions: the coordinate symbols; speeds: the speed symbols. (A row whose J alone depends on t does no work:
    its force is normal to every allowed velocity.) A row nonlinear in the speeds works where A v / Phi_v depends
    on the speeds (_works)."""
    if c.holonomic:
        positions = positions | set(c.quantities)
        return [i for i, r in enumerate(c.rows) if TIME in r.free_symbols and r.free_symbols & positions]
    speeds = speeds | {s for s, f in c.quantities.items() if f.kind != "position"}
    return [i for i, r in enumerate(c.rows)
            if r.free_symbols & speeds and (_works(r, speeds) if i in c.nonlinear
                                            else sp.expand(r.subs({s: 0 for s in speeds})) != 0)]


def rheonomic_frames(frames: list) -> list[str]:
    """The frames whose link depends on t: their motion is prescribed, and the power that drives it is not
    derived (andyc/symbolic/work.py), so the energy balance of a model with one is not complete."""
    return [f.name for f in frames if any(TIME in _free(step) for step in f.transforms)]


def driven_frames(frames: list) -> list[str]:
    """The frames moved along t: those whose link depends on t and every frame below them (parents come first)."""
    driven = set(rheonomic_frames(frames))
    for f in frames:
        if f.parent in driven:
            driven.add(f.name)
    return [f.name for f in frames if f.name in driven]


def _free(step) -> set:
    """Free symbols of a link step."""
    if isinstance(step, Translate):
        return step.vector.free_symbols
    if isinstance(step, Rotate):
        return step.angle.free_symbols
    parts = [m for m in (step.velocity, step.angular_velocity) if m is not None]
    return set().union(*(m.free_symbols for m in parts)) if parts else set()
