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
  to the mode without it. With more than one contact, a jump's name ends in its mode's bitmask.
- The impact jumps carry no compiled impact map (the runtime's solves all touching contacts at once);
  their `restitution` is the contact's e, which the runtime reads from the restitution leaf.

Jumps, flows and rows are ordinary Spec objects: the symbolic stage and code generation treat them as
a hand-written hybrid automaton; only the tables CONTACT_* and JUMP_CONTACT tell the runtime which
jumps are contacts'.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.hybrid import multiplier_symbols, restitution
from andyc.spec.model import FALLING, Flow, Jump
from andyc.spec.scope import Scope

IMPACT, LIFTOFF = "impact", "liftoff"


@dataclass(frozen=True)
class Contact:
    name: str
    constraint: str             # the name of its gap's constraint row (the contact's own name)
    multiplier: str             # the normal force's name
    restitution: sp.Expr        # e, an expression of parameters
    where: tuple


def mode_name(mask: int, names: list) -> str:
    """The flow of the contacts closed in `mask` (bit i: contact i)."""
    closed = [n for i, n in enumerate(names) if mask >> i & 1]
    return "+".join(closed) if closed else "open"


def build_contacts(written: list, constraints: list, has_hybrid: bool, scope: Scope) -> tuple[list, list, list]:
    """(contacts, flows, jumps) of the `contacts:` section; `constraints` hold their gap rows (built by
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
        contacts.append(Contact(c["name"], c["name"], row.multipliers[0], e, where))
    names = [c.name for c in contacts]
    contact_rows = set(names)
    bilateral = tuple(c.name for c in constraints if c.name not in contact_rows)
    lams = multiplier_symbols(constraints)
    flows, jumps = [], []
    n = len(contacts)
    for mask in range(2 ** n):
        closed = {names[i] for i in range(n) if mask >> i & 1}
        active = tuple(c.name for c in constraints if c.name in closed or c.name in bilateral)
        flows.append(Flow(mode_name(mask, names), active, {}, ("contacts",)))
    for mask in range(2 ** n):
        suffix = "" if n == 1 else f"_{mask}"
        for i, c in enumerate(contacts):
            row = by_name[c.constraint]
            if mask >> i & 1:
                symbol, _ = lams[c.multiplier]
                jumps.append(Jump(f"{c.name}_liftoff{suffix}", flows[mask].name, flows[mask & ~(1 << i)].name,
                                  symbol, FALLING, (), "none", sp.Integer(0), (), (), len(jumps), {}, c.where,
                                  _text(c.multiplier, "none"), {symbol: c.multiplier}, i,
                                  LIFTOFF))
            else:
                jumps.append(Jump(f"{c.name}_impact{suffix}", flows[mask].name, flows[mask].name,
                                  row.rows[0], FALLING, (), "none", c.restitution, (), (), len(jumps),
                                  dict(row.quantities), c.where,
                                  _text(written[i]["gap"], {"restitution": written[i].get("restitution", 0)}), {},
                                  i, IMPACT))
    return contacts, flows, jumps


def _text(guard, impact) -> dict:
    """A contact's jump as the jump template documents a jump (Jump.text): its guard and impact as written."""
    return {"guard": guard if isinstance(guard, (str, int, float)) else str(guard), "enabled": None, "reset": {},
            "impact": impact if isinstance(impact, str) else {"restitution": str(impact["restitution"])}}
