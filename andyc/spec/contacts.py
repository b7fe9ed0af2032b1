"""Unilateral contacts (`contacts:`): the flows and jumps of their modes, made from their gaps.

A contact is a gap g(t, q) >= 0 (apart) with a restitution e. It is either open (no force, g > 0) or
closed (the row g = 0 is an active constraint, its multiplier the normal force, >= 0 while it pushes).
The design, and why:

- Modes are flows, one per set of closed contacts (2^n flows; n <= 4, the schema's limit), flow index =
  the bitmask of closed contacts (bit i: contact i in document order), named `open` (none closed) or
  after the closed contacts (`left+right`). A flow's active rows are the model's constraints and its
  closed contacts' gaps, so the compiled right-hand side, projection and multipliers handle a closed
  contact like any constraint, and a model without contacts pays nothing (one flow, as before). Per
  mode flows rather than rows selected at run time: the numerics already select rows per flow
  (FLOW_ROWS), so nothing in the compiled loop changes; 2^n stays small for the few contacts of a
  walker or a hopper.
- Each mode has, for each open contact, an impact jump (`<contact>_impact`, guard: the gap, falling)
  whose target the runtime decides (andyc.runtime.contacts: every contact touching at that instant
  takes its impulse together, from a small complementarity problem, and those left at rest close),
  and for each closed contact a liftoff jump (`<contact>_liftoff`, guard: the normal force, falling)
  to the mode without it. A jump that leaves more than one flow (any with more than one contact, a
  liftoff or slip end with friction) has its name end in its source flow's index (`left_impact_2`).
- The impact jumps carry no compiled impact map (the runtime's solves all touching contacts at once);
  their `restitution` is the contact's e, which the runtime reads from the restitution leaf.

Coulomb friction, planar (a contact with `friction: mu` and `slip:`, the speed of its contact point along its
tangent, linear in the speeds): its stick row (`<contact>_stick`, slip = 0, nonholonomic; its multiplier
`friction_<contact>`, the friction force along +tangent) and four states instead of two: open, stick (gap and
stick rows active), slip forwards and slip backwards (gap row active; its normal force lam_n carries the
friction -sigma mu lam_n along the tangent, sigma = +1 forwards: andyc.numerics.slipping.slip_rows). A flow is
then the contacts' states in mixed radix (2 per contact without friction, 4 with: flow_of, states_of; with no
friction the bitmask as before), at most MAX_MODES flows. Their jumps: stick -> slip forwards where lam_t reaches
-mu lam_n (`<contact>_slip_pos`, guard mu lam_n + lam_t, falling), backwards where it reaches +mu lam_n
(`<contact>_slip_neg`, guard mu lam_n - lam_t, falling); slip -> stick where the slip speed crosses zero
(`<contact>_stop`, guard the slip, falling forwards, rising backwards), whose target the runtime decides (it
sticks if the friction it needs is inside the cone, else slips the other way) and whose coefficient (the
restitution slot, unused: it has no impact map) is mu, which the slipping flow's force reads.

Jumps, flows and rows are ordinary Spec objects: the symbolic stage and code generation treat them as
a hand-written hybrid automaton; only the tables CONTACT_*, JUMP_CONTACT and JUMP_KINDS tell the runtime
which jumps are contacts', and FLOW_SLIP* the numerics which rows slip (andyc.codegen.generate).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.expressions import TIME
from andyc.spec.hybrid import multiplier_symbols, restitution
from andyc.spec.model import FALLING, RISING, DiscreteState, Flow, Jump
from andyc.spec.modes import flow_of, radices, states_of  # noqa: F401 (part of this module's API)
from andyc.spec.scope import Scope

IMPACT, LIFTOFF, SLIP, STOP = "impact", "liftoff", "slip", "stop"
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3      # a contact's state (without friction: 0 open, 1 closed)
SLIDE = 2                                          # spatial friction: 0 open, 1 stick, 2 slip (one state)
STATE_SUFFIX = {STICK: "_stick", SLIP_POS: "_slip_pos", SLIP_NEG: "_slip_neg"}
SPATIAL_SUFFIX = {STICK: "_stick", SLIDE: "_slip"}
MAX_MODES = 64                                     # flows: 4 contacts, at most 2 of them with friction (a walker's
#                                                    feet with friction, its knees' stops without: 4 x 4 x 2 x 2)


@dataclass(frozen=True)
class Contact:
    name: str
    constraint: str             # the name of its gap's constraint row (the contact's own name)
    multiplier: str             # the normal force's name
    restitution: sp.Expr        # e, an expression of parameters
    where: tuple
    friction: sp.Expr | None = None     # mu, an expression of parameters; None: frictionless
    stick: str | None = None    # the name of its stick row (slip speed = 0), with friction
    friction_multiplier: str | None = None  # the friction force's name (the stick row's multiplier; spatial: the first)
    tangents: int = 0           # 0 frictionless, 1 planar, 2 spatial friction (slip: two tangential speeds)
    direction: tuple = ()       # spatial: the names of its two discrete states holding the slip's direction


def mode_name(states: list, contacts: list) -> str:
    """The flow of the contacts' states: `open` (none closed) or the closed contacts (`left+right`), with their
    friction state (`block_stick`, `block_slip_pos`, `block_slip_neg`)."""
    closed = [c.name + ((SPATIAL_SUFFIX if c.tangents == 2 else STATE_SUFFIX)[s] if c.friction is not None else "")
              for c, s in zip(contacts, states) if s]
    return "+".join(closed) if closed else "open"


def build_contacts(written: list, constraints: list, has_hybrid: bool, scope: Scope) -> tuple[list, list, list]:
    """(contacts, flows, jumps) of the `contacts:` section; `constraints` hold their gap and stick rows (built by
    andyc.spec.constraints with the model's own). A model with contacts has no hand-written hybrid section."""
    if not written:
        return [], [], []
    if has_hybrid:
        scope.report.error(("contacts",), "contacts and a hybrid section cannot be combined yet: the contacts' "
                           "modes are the flows", "write the contacts as constraints switched by your jumps "
                           "(guards may use multipliers), or remove 'hybrid'")
    contacts = []
    by_name = {c.name: c for c in constraints}
    for i, c in enumerate(written):
        where = ("contacts", i)
        if c["name"] == "open":
            scope.report.error(where + ("name",), "a contact cannot be named 'open': that names the mode in which no "
                               "contact is closed", "choose another name")
        e = restitution(c.get("restitution", 0), where + ("restitution",), scope)
        row = by_name[c["name"]]
        mu = stick = None
        if "friction" in c and "slip" not in c:
            scope.report.error(where + ("friction",), "a contact with friction needs its slip speed",
                               "add 'slip:', the speed of the contact point along the tangent (e.g. block.vx)")
        elif "slip" in c and "friction" not in c:
            scope.report.error(where + ("slip",), "'slip' without 'friction' has no effect",
                               "add 'friction: mu' (Coulomb's coefficient), or remove 'slip'")
        elif "friction" in c:
            mu, stick = _friction(c["friction"], where + ("friction",), scope), f"{c['name']}_stick"
        tangents = 0 if mu is None else 2 if isinstance(c["slip"], list) else 1
        direction = _slip_direction(c["name"], where, scope) if tangents == 2 else ()
        contacts.append(Contact(c["name"], c["name"], row.multipliers[0], e, where, mu, stick,
                                by_name[stick].multipliers[0] if stick in by_name else None, tangents, direction))
    spatial = [c for c in contacts if c.tangents == 2]
    if spatial and len(contacts) > 1:
        scope.report.error(spatial[0].where + ("slip",), f"contact '{spatial[0].name}' has spatial friction (two "
                           f"tangents) beside {len(contacts) - 1} other contact(s): not supported yet",
                           "give a contact with spatial friction alone, or make its friction planar (slip: one "
                           "speed)")
        return contacts, [], []
    radix = radices([c.tangents for c in contacts])
    n_flows = flow_of([r - 1 for r in radix], radix) + 1
    if n_flows > MAX_MODES:
        scope.report.error(("contacts",), f"{len(contacts)} contacts, {sum(r != 2 for r in radix)} with friction, "
                           f"make {n_flows} modes, more than {MAX_MODES}", "give at most 4 contacts, at most 2 of them "
                           "with friction (each has 4 modes: open, stick, slip forwards, slip backwards)")
        return contacts, [], []
    contact_rows = {c.name for c in contacts} | {c.stick for c in contacts if c.stick}
    bilateral = tuple(c.name for c in constraints if c.name not in contact_rows)
    lams = multiplier_symbols(constraints)
    all_states = [states_of(k, radix) for k in range(n_flows)]
    names = [mode_name(states, contacts) for states in all_states]
    jumps, slips = [], {k: [] for k in range(n_flows)}
    single = len(contacts) == 1

    def add(name, kind, k, target, guard, direction, i, coefficient=sp.Integer(0), quantities=None, used=None,
            text=None):
        suffix = "" if single and (kind != LIFTOFF or radix[i] == 2) and kind != STOP else f"_{k}"
        jumps.append(Jump(f"{name}{suffix}", names[k], names[target], guard, direction, (), "none", coefficient,
                          (), (), len(jumps), dict(quantities or {}), contacts[i].where, text, used or {}, i, kind))
        return jumps[-1].name

    for k, states in enumerate(all_states):
        for i, c in enumerate(contacts):
            s, w = states[i], written[i]
            other = lambda state: flow_of(states[:i] + [state] + states[i + 1:], radix)   # noqa: E731
            row = by_name[c.constraint]
            if s == OPEN:
                add(f"{c.name}_impact", IMPACT, k, k, row.rows[0], FALLING, i, c.restitution, row.quantities,
                    text=_text(w["gap"], {"restitution": w.get("restitution", 0)}))
                continue
            n_sym = lams[c.multiplier][0]
            add(f"{c.name}_liftoff", LIFTOFF, k, other(OPEN), n_sym, FALLING, i, used={n_sym: c.multiplier},
                text=_text(c.multiplier, "none"))
            if c.friction is None:
                continue
            if c.tangents == 2:
                _spatial_jumps(add, c, w, s, k, i, other, by_name[c.stick], lams, n_sym, slips, scope)
                continue
            t_sym = lams[c.friction_multiplier][0]
            used = {n_sym: c.multiplier, t_sym: c.friction_multiplier}
            if s == STICK:
                add(f"{c.name}_slip_pos", SLIP, k, other(SLIP_POS), c.friction * n_sym + t_sym, FALLING, i,
                    used=used, text=_text(f"{w['friction']}*{c.multiplier} + {c.friction_multiplier}", "none"))
                add(f"{c.name}_slip_neg", SLIP, k, other(SLIP_NEG), c.friction * n_sym - t_sym, FALLING, i,
                    used=used, text=_text(f"{w['friction']}*{c.multiplier} - {c.friction_multiplier}", "none"))
            else:
                stick = by_name[c.stick]
                stop = add(f"{c.name}_stop", STOP, k, other(STICK), stick.rows[0],
                           FALLING if s == SLIP_POS else RISING, i, c.friction, stick.quantities,
                           text=_text(w["slip"], "none"))
                slips[k].append((c.constraint, c.stick, 1 if s == SLIP_POS else -1, stop, None))
    flows = []
    for k, states in enumerate(all_states):
        closed = {c.name for c, s in zip(contacts, states) if s} | {c.stick for c, s in zip(contacts, states)
                                                                     if s == STICK and c.stick}
        active = tuple(c.name for c in constraints if c.name in closed or c.name in bilateral)
        flows.append(Flow(names[k], active, {}, ("contacts",), tuple(slips[k])))
    return contacts, flows, jumps


def _spatial_jumps(add, c: Contact, w: dict, s: int, k: int, i: int, other, stick, lams: dict, n_sym, slips: dict,
                   scope: Scope) -> None:
    """The friction jumps of a contact with spatial friction (two tangents t1, t2; friction forces lam_1, lam_2
    along them) in state s of flow k: sticking, it slips where |lam_t| reaches mu lam_n (`<c>_slip`, guard
    mu^2 lam_n^2 - lam_1^2 - lam_2^2, falling; the runtime starts the slip against the sticking force,
    andyc.runtime.contacts); slipping, it stops where the slip s = (s1, s2) reaches zero (`<c>_stop`, guard
    s . d, d the slip's direction at the start of the integration step, kept in the discrete states `direction`
    by the integrator: numerics.dynamics.slip_direction; a linear crossing at the stop, where |s|^2 only touches
    zero), its target decided by the runtime (stick inside the cone, else slip on)."""
    if len(stick.multipliers) != 2:         # one friction name for two tangents: reported (andyc.spec.constraints)
        return
    t1, t2 = (lams[name][0] for name in stick.multipliers)
    used = {n_sym: c.multiplier, t1: stick.multipliers[0], t2: stick.multipliers[1]}
    if s == STICK:
        add(f"{c.name}_slip", SLIP, k, other(SLIDE), c.friction ** 2 * n_sym ** 2 - t1 ** 2 - t2 ** 2, FALLING, i,
            used=used, text=_text(f"({w['friction']})**2*{c.multiplier}**2 - {stick.multipliers[0]}**2 - "
                                  f"{stick.multipliers[1]}**2", "none"))
        return
    d1, d2 = (next(x.symbol for x in scope.discrete if x.name == name) for name in c.direction[:2])
    stop = add(f"{c.name}_stop", STOP, k, other(STICK), stick.rows[0] * d1 + stick.rows[1] * d2, FALLING, i,
               c.friction, stick.quantities,
               text=_text(f"({w['slip'][0]})*{c.direction[0]} + ({w['slip'][1]})*{c.direction[1]}", "none"))
    slips[k].append((c.constraint, c.stick, 0, stop, c.direction[0]))


def _slip_direction(name: str, where: tuple, scope: Scope) -> tuple:
    """The discrete states of a contact with spatial friction that keep its slip's direction (unit, in its
    tangents' coordinates; 0 until it slips): `<contact>_slip_dir_1`, `_2`, and `<contact>_slip_held`, 1 while a
    fixed step holds that direction (andyc.numerics.dynamics.slip_direction)."""
    names = (f"{name}_slip_dir_1", f"{name}_slip_dir_2", f"{name}_slip_held")
    for n in names:
        if n in scope.declared:
            scope.report.error(where + ("name",), f"contact '{name}' with spatial friction needs the name '{n}' "
                               f"(its slip's direction), which is taken", f"rename the {scope.declared[n]} '{n}'")
        scope.discrete.append(DiscreteState(n, sp.Symbol(f"d_{n}", real=True), sp.Integer(0), where + ("slip",)))
    return names


def _friction(value, path, scope: Scope) -> sp.Expr:
    """Coulomb's coefficient: a constant expression of parameters, >= 0 at their defaults."""
    before = len(scope.report.problems)
    mu_expr, mu = scope.constant(value, path, allow_time=True)
    if len(scope.report.problems) > before:
        pass
    elif TIME in mu_expr.free_symbols:
        scope.report.error(path, f"the friction coefficient {value!r} depends on t",
                           "give a constant >= 0: a number or an expression of parameters")
    elif mu < 0:
        shown = f"{mu:g}" if mu_expr.is_number else f"{value} = {mu:g}"
        scope.report.error(path, f"the friction coefficient is {shown}, negative",
                           "give Coulomb's coefficient mu >= 0 (0: frictionless sliding)")
    return mu_expr


def _text(guard, impact) -> dict:
    """A contact's jump as the jump template documents a jump (Jump.text): its guard and impact as written."""
    return {"guard": guard if isinstance(guard, (str, int, float)) else str(guard), "enabled": None, "reset": {},
            "impact": impact if isinstance(impact, str) else {"restitution": str(impact["restitution"])}}
