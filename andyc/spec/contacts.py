"""Unilateral contacts (`contacts:`): their states, and the jumps that change them, made from their gaps.

A contact is a gap g(t, q) >= 0 (apart) with a restitution e and, with friction, its slip speed(s). It is open
(no force, g > 0) or closed (the row g = 0 active, its multiplier the normal force, >= 0 while it pushes); with
friction, closed sticking (its stick rows, slip = 0, active too) or slipping. The design, and why:

- Each contact's state is a discrete state `<contact>_mode` (0 open, 1 closed / sticking, 2 slipping forwards
  or, with spatial friction, slipping, 3 slipping backwards): the run decides it, at the start and at every
  contact event, and the compiled numerics read it. The rows active at an instant are the flow's own and those
  of the closed contacts (andyc_numerics' active.select_rows), so n contacts cost n states and about 4 n jumps,
  not 2^n (4^n with friction) enumerated flows: a legged robot on 4, 8 or 32 contacts, and contacts beside a
  hand-written `hybrid:` automaton (its flows are the user's modes; the contacts switch within every flow).
- The jumps of contact c, each enabled only in the states it leaves (Jump.mode: the mode state and a mask of
  the states, read by the integrator before the guard), from and to every flow (source and target ANY):
    `c_impact`    open:      the gap crosses zero, falling; the runtime resolves the impulses of every
                             contact touching then (andyc.runtime.contacts) and sets their states;
    `c_liftoff`   closed:    the normal force crosses zero, falling; resets the mode to 0;
    `c_slip_pos`, `c_slip_neg`  sticking, planar friction: the friction reaches -mu lam_n (+mu lam_n): guard
                             mu lam_n + lam_t (mu lam_n - lam_t), falling; resets the mode to 2 (3);
    `c_slip`      sticking, spatial friction: |lam_t| reaches mu lam_n (guard mu^2 lam_n^2 - lam_1^2 - lam_2^2,
                             falling; resets the mode to 2, the runtime starts the slip against lam_t);
    `c_stop`      slipping:  the slip speed crosses zero; planar: guard (5 - 2 mode) slip, falling (slip
                             forwards, mode 2: the slip; backwards, mode 3: minus it); spatial: s . d, d the
                             slip's direction at the step's start (discrete states `c_slip_dir_1`, `_2`; set by
                             the integrator: andyc_numerics' dynamics.slip_direction). The runtime decides
                             whether it sticks or slips on. Its coefficient (the restitution slot, unused: it
                             has no impact map) is mu, which the slipping force reads.
- A slipping contact's normal row carries the friction: -sigma mu lam_n along its tangent (planar, sigma = +1
  forwards), or -mu lam_n u along the slip's direction u (spatial): andyc_numerics' slipping.slip_rows.

Jumps and rows are ordinary Spec objects: the symbolic stage and code generation treat them as a hand-written
automaton's; the tables CONTACT_* and JUMP_MODE tell the numerics and the runtime which are contacts'.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.hybrid import multiplier_symbols, restitution
from andyc.spec.model import ANY, FALLING, DiscreteState, Jump
from andyc.spec.expressions import TIME
from andyc.spec.scope import Scope

IMPACT, LIFTOFF, SLIP, STOP = "impact", "liftoff", "slip", "stop"
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3      # a contact's mode (without friction: 0 open, 1 closed)
SLIDE = 2                                          # spatial friction: 0 open, 1 stick, 2 slip
CLOSED = (1 << STICK) | (1 << SLIP_POS) | (1 << SLIP_NEG)      # masks of modes (bit s: mode s)
MAX_CONTACTS = 1024                                # a scene's contact candidates (the schema's limit)


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
    mode: str = ""              # the name of its discrete state holding its mode
    direction: tuple = ()       # spatial: the names of its discrete states holding the slip's direction, and held
    stop: str | None = None     # with friction: the name of its `stop` jump, whose coefficient is mu


def build_contacts(written: list, constraints: list, scope: Scope) -> tuple[list, list]:
    """(contacts, jumps) of the `contacts:` section; `constraints` hold their gap and stick rows (built by
    andyc.spec.constraints with the model's own). Each contact's mode state (and, with spatial friction, its slip
    direction's) is declared in scope.discrete."""
    contacts, jumps = [], []
    by_name = {c.name: c for c in constraints}
    lams = multiplier_symbols(constraints)
    for i, c in enumerate(written):
        if c is None:                       # (a stop left out: stops_inside)
            continue
        where = ("contacts", i)
        e = restitution(c.get("restitution", 0), where + ("restitution",), scope)
        mu = stick = None
        if "friction" in c and "slip" not in c:
            scope.report.error(where + ("friction",), "a contact with friction needs its slip speed",
                               "add 'slip:', the speed of the contact point along the tangent (e.g. block.vx)")
        elif "slip" in c and "friction" not in c:
            scope.report.error(where + ("slip",), "'slip' without 'friction' has no effect",
                               "add 'friction: mu' (Coulomb's coefficient), or remove 'slip'")
        elif "friction" in c:
            mu, stick = friction_coefficient(c["friction"], where + ("friction",), scope), f"{c['name']}_stick"
        tangents = 0 if mu is None else 2 if isinstance(c["slip"], list) else 1
        mode = _state(c["name"], "mode", where, scope)
        direction = tuple(_state(c["name"], s, where, scope) for s in ("slip_dir_1", "slip_dir_2", "slip_held")) \
            if tangents == 2 else ()
        stick_row = by_name.get(stick) if stick else None
        contact = Contact(c["name"], c["name"], by_name[c["name"]].multipliers[0], e, where, mu, stick,
                          stick_row.multipliers[0] if stick_row else None, tangents, mode, direction,
                          f"{c['name']}_stop" if mu is not None else None)
        contacts.append(contact)
        jumps += _jumps(contact, c, by_name, lams, scope, len(contacts) - 1)
    return contacts, jumps


def stops_inside(written: list, robot, scope: Scope) -> list:
    """The `contacts:` entries with a URDF's joint-limit stops that its joints start beyond (their coordinate's
    initial value at the parameters' defaults past the limit: a robot's zero pose, panda's fourth joint) replaced by
    None, each named in a warning: such a stop would start the run inside the limit's wall."""
    stops = getattr(robot, "stops", None) or {}
    if not stops:
        return list(written)
    initial = {c.name: c.initial for c in scope.coordinates}
    values = {symbol: value for symbol, value in scope.parameters.values()}
    out = []
    for i, c in enumerate(written):
        joint, q, side, bound = stops.get(c["name"], (None, None, None, None))
        start = float(initial[q].subs(values)) if joint is not None and q in initial else None
        if start is not None and (start < bound if side == "lower" else start > bound):
            scope.report.warn(("contacts", i), f"joint '{joint}' starts at {start:g}, beyond its {side} limit "
                              f"{bound:g}: its stop '{c['name']}' is left out", f"give '{q}' an initial value within "
                              "its limits to keep the stop (coordinates: {" + q + ": {initial: ...}}), or urdf: "
                              "{limits: false}")
            out.append(None)
        else:
            out.append(c)
    return out


def _jumps(c: Contact, w: dict, by_name: dict, lams: dict, scope: Scope, i: int) -> list:
    """The jumps of contact c (the i-th), as the module's docstring lists them."""
    symbols = {x.name: x.symbol for x in scope.discrete}
    mode = symbols[c.mode]
    out = []

    def add(kind, states, guard, coefficient=sp.Integer(0), quantities=None, used=None, text=None, to=None):
        resets = ((c.mode, sp.Integer(to)),) if to is not None else ()
        out.append(Jump(f"{c.name}_{kind}" if kind in (IMPACT, LIFTOFF, SLIP, STOP) else f"{c.name}_slip_{kind}",
                        ANY, ANY, guard, FALLING, (), "none", coefficient, (), resets, 0, dict(quantities or {}),
                        c.where, text, used or {}, i, kind if kind in (IMPACT, LIFTOFF, STOP) else SLIP,
                        (c.mode, states)))

    row = by_name[c.constraint]
    add(IMPACT, 1 << OPEN, row.rows[0], c.restitution, row.quantities,
        text=_text(w["gap"], {"restitution": w.get("restitution", 0)}))
    n_sym = lams[c.multiplier][0]
    add(LIFTOFF, CLOSED, n_sym, used={n_sym: c.multiplier}, text=_text(c.multiplier, "none"), to=OPEN)
    if c.friction is None or c.stick not in by_name:
        return out
    stick = by_name[c.stick]
    if c.tangents == 2:
        if len(stick.multipliers) != 2:     # one friction name for two tangents: reported (andyc.spec.constraints)
            return out
        t1, t2 = (lams[name][0] for name in stick.multipliers)
        d1, d2 = symbols[c.direction[0]], symbols[c.direction[1]]
        add(SLIP, 1 << STICK, c.friction ** 2 * n_sym ** 2 - t1 ** 2 - t2 ** 2,
            used={n_sym: c.multiplier, t1: stick.multipliers[0], t2: stick.multipliers[1]},
            text=_text(f"({w['friction']})**2*{c.multiplier}**2 - {stick.multipliers[0]}**2 - "
                       f"{stick.multipliers[1]}**2", "none"), to=SLIDE)
        add(STOP, 1 << SLIDE, stick.rows[0] * d1 + stick.rows[1] * d2, c.friction, stick.quantities,
            text=_text(f"({w['slip'][0]})*{c.direction[0]} + ({w['slip'][1]})*{c.direction[1]}", "none"))
        return out
    t_sym = lams[c.friction_multiplier][0]
    used = {n_sym: c.multiplier, t_sym: c.friction_multiplier}
    add("pos", 1 << STICK, c.friction * n_sym + t_sym, used=used,
        text=_text(f"{w['friction']}*{c.multiplier} + {c.friction_multiplier}", "none"), to=SLIP_POS)
    add("neg", 1 << STICK, c.friction * n_sym - t_sym, used=used,
        text=_text(f"{w['friction']}*{c.multiplier} - {c.friction_multiplier}", "none"), to=SLIP_NEG)
    add(STOP, (1 << SLIP_POS) | (1 << SLIP_NEG), (5 - 2 * mode) * stick.rows[0], c.friction, stick.quantities,
        text=_text(f"(5 - 2*{c.mode})*({w['slip']})", "none"))
    return out


def _state(contact: str, what: str, where: tuple, scope: Scope) -> str:
    """Declare contact's discrete state `<contact>_<what>` (initial 0): its mode or its slip's direction."""
    name = f"{contact}_{what}"
    if name in scope.declared:
        scope.report.error(where + ("name",), f"contact '{contact}' needs the name '{name}' (a discrete state of "
                           f"its own), which is taken", f"rename the {scope.declared[name]} '{name}'")
    scope.discrete.append(DiscreteState(name, sp.Symbol(f"d_{name}", real=True), sp.Integer(0), where + ("name",)))
    return name


def friction_coefficient(value, path, scope: Scope) -> sp.Expr:
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
