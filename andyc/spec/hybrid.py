"""The hybrid automaton (ANDY §2.4, eq. 16-19): flows and the jumps between them.

A flow names the constraints active in it and may set inputs to constants. A jump goes from one flow to
another where its guard crosses 0 in its direction, while its enabling conditions hold; it then applies
its resets (simultaneously, from the values before the jump) and its impact map (plastic, or a
restitution e, on the target flow's constraints or the ones named). A model without `hybrid:` is one
flow with every constraint active.
"""

from __future__ import annotations

import builtins
import math
import re

import sympy as sp

from andyc.errors import format_path
from andyc.spec.constraints import QUANTITY_HINT, FrameQuantities
from andyc.spec.expressions import TIME, ExpressionError, parse_condition
from andyc.spec.model import EITHER, FALLING, RISING, Flow, Jump
from andyc.spec.scope import Scope
from andyc.spec.suggest import did_you_mean

# A jump's function in <model>_jumps.py is named after it: not a builtin, nor a name that file uses.
JUMP_FILE_NAMES = frozenset(dir(builtins)) | {"math", "np", "JUMPS"}


def build_hybrid(h: dict | None, constraints: list, scope: Scope, quantities: FrameQuantities,
                 contact_rows: frozenset = frozenset()) -> tuple[list, list, int]:
    """Flows, jumps and the initial flow's index; without a hybrid section, one flow with every constraint but
    the contacts' rows (`contact_rows`: the runtime switches them in every flow, andyc.spec.contacts).

    A constraint active in no flow and taking no impact is warned about."""
    names = [c.name for c in constraints if c.name not in contact_rows]
    if h is None:
        return [Flow("default", tuple(names), {}, ())], [], 0
    flows, impacted = [], set()
    for i, f in enumerate(h["flows"]):
        where = ("hybrid", "flows", i)
        first = next((g.where for g in flows if g.name == f["name"]), None)
        if first is not None:
            scope.report.error(where + ("name",), f"duplicate flow name '{f['name']}' (first defined at line "
                               f"{scope.report.smap.line(first + ('name',))}, {format_path(first + ('name',))})",
                               "give each flow its own name")
        active = f.get("constraints", [])
        for j, name in enumerate(active):
            if name in contact_rows:
                scope.report.error(where + ("constraints", j), f"'{name}' is a contact's row, which the run closes "
                                   "and opens by itself in every flow", "remove it from the flow's 'constraints'")
                continue
            scope.known(name, names, where + ("constraints", j), "constraint")
            if name in active[:j]:
                scope.report.error(where + ("constraints", j), f"constraint '{name}' is listed twice",
                                   "list it once")
        inputs = {}
        for name, value in (f.get("inputs") or {}).items():
            if scope.known(name, list(scope.inputs), where + ("inputs", name), "input"):
                inputs[name] = scope.constant(value, where + ("inputs", name), allow_time=True)[0]
                if TIME in inputs[name].free_symbols:
                    scope.report.error(where + ("inputs", name), f"the value {value!r} of input '{name}' in flow "
                                       f"'{f['name']}' depends on t", "a flow sets its inputs to constants: a "
                                       "number or an expression of parameters")
        flows.append(Flow(f["name"], tuple(n for n in names if n in active), inputs, where))
    flow_names = [f.name for f in flows]
    initial = h.get("initial", flow_names[0])
    initial_index = flow_names.index(initial) if scope.known(initial, flow_names, ("hybrid", "initial"),
                                                             "flow") else 0
    jumps = []
    written = h.get("jumps") or []
    for i, j in enumerate(written):
        jump = _jump(i, j, written, flows, constraints, scope, quantities, contact_rows)
        if jump is not None:
            jumps.append(jump)
            impacted |= set(jump.impact_constraints)
    used = {n for f in flows for n in f.constraints} | impacted
    for c in constraints:
        if c.name not in used and c.name not in contact_rows:
            scope.report.warn(c.where, f"constraint '{c.name}' is active in no flow and takes no impact",
                              "list it in a flow's 'constraints', or remove it")
    return flows, jumps, initial_index


def check_nonlinear_impacts(constraints: list, jumps: list, contacts: list, scope: Scope) -> None:
    """Impacts need velocity rows linear in the speeds: the impact map solves J v+ = -e J v- in one step
    (ANDY eq. 19), and a contact's impact keeps the model's own rows at c+ = c- + J dv = 0 (andyc.runtime.
    contacts); for a row Phi_v nonlinear in v neither is the impact it describes. Such rows are refused
    there, for now."""
    nonlinear = {c.name: c for c in constraints if c.nonlinear}
    if not nonlinear:
        return
    for jump in jumps:
        hit = [n for n in jump.impact_constraints if n in nonlinear]
        if hit and not jump.kind:
            scope.report.error(jump.where + ("impact",), f"the impact of jump '{jump.name}' acts on constraint "
                               f"'{hit[0]}', whose rows are not all linear in the speeds",
                               "an impact map solves J v+ = -e J v- over rows J v + b = 0: name the constraints "
                               "that take it, without that one (impact: {restitution: e, constraints: [...]}), "
                               "or set the speeds after the jump with a reset")
    if contacts:
        first = next(iter(nonlinear.values()))
        scope.report.error(first.row_where[first.nonlinear[0]], f"constraint '{first.name}' is not linear in the "
                           "speeds, and the model has contacts, whose impacts keep the model's constraints through "
                           "their rows J v + b = 0", "write the constraint linear in the speeds in a model with "
                           "contacts, or model the contacts as jumps of a hybrid section")


def _jump(i: int, j: dict, written: list, flows: list, constraints: list, scope: Scope,
          quantities: FrameQuantities, contact_rows: frozenset = frozenset()) -> Jump | None:
    """One jump, or None when its source or target flow does not exist (reported)."""
    where = ("hybrid", "jumps", i)
    constraint_names = [c.name for c in constraints]
    flow_names = [f.name for f in flows]
    ok = scope.known(j["from"], flow_names, where + ("from",), "flow")
    ok = scope.known(j["to"], flow_names, where + ("to",), "flow") and ok
    if j["name"] in JUMP_FILE_NAMES:
        scope.report.error(where + ("name",), f"'{j['name']}' cannot name a jump: the jump's function in the "
                           f"jumps file (<model>_jumps.py) would hide Python's '{j['name']}'", "choose another name")
    earlier = [k for k, x in enumerate(written[:i]) if x["name"] == j["name"]]
    if earlier:
        first = ("hybrid", "jumps", earlier[0], "name")
        scope.report.error(where + ("name",), f"duplicate jump name '{j['name']}' (first defined at line "
                           f"{scope.report.smap.line(first)}, {format_path(first)})", "give each jump its own name")
    found = {}

    def quantity(owner, attribute):
        return quantities.symbol(owner, attribute, "world", found)

    states = {**{c.name: c.q for c in scope.coordinates}, **scope.rates}
    discrete = scope.discrete_names
    names = {**scope.forcing, **scope.rates, **discrete}
    context = ("guards, conditions and resets use parameters, inputs, coordinates, speeds (<coordinate>_dot "
               "and declared speeds), discrete states, t and " + QUANTITY_HINT + "; guards and conditions also the "
               "multipliers of the source flow's constraints")
    # The multipliers of the source flow's rows; others only where written (reported then by _used_multipliers).
    lams = multiplier_symbols(constraints)
    source = next((f.constraints for f in flows if f.name == j["from"]), ()) + tuple(contact_rows)
    texts = j.get("enabled", [])
    written_names = set(re.findall(r"[A-Za-z_]\w*", " ".join(map(str, [j["guard"]] + (texts if isinstance(texts, list)
                                                                                       else [texts])))))
    guard_names = {**names, **{name: symbol for name, (symbol, c) in lams.items()
                               if c in source or name in written_names}}
    guard = _guard(j, where, guard_names, context, states, found, quantity, scope, set(guard_names) - set(names))
    enabled = []
    for k, text in enumerate(texts if isinstance(texts, list) else [texts]):
        path = where + ("enabled",) + ((k,) if isinstance(texts, list) else ())
        try:
            conditions = parse_condition(text, guard_names, True, quantity)
        except ExpressionError as exc:
            message = str(exc)
            if exc.name in scope.declared:   # a frame, body, ... written as a value
                message = f"in {text!r}: {scope.kind_of(exc.name)} '{exc.name}' cannot be used here"
            scope.report.error(path, message, exc.hint + (f" ({context})" if exc.name else ""))
            continue
        scope.report.used.update(*(e.free_symbols for e in conditions))
        enabled += conditions
    resets = []
    for name, value in (j.get("reset") or {}).items():
        path = where + ("reset", name)
        if name in states or name in discrete:
            resets.append((name, scope.expr(value, path, names, context, dotted=quantity)))
        else:
            kind = scope.kind_of(name)
            why = {"parameter": "parameters keep their value for the whole run",
                   "input": "inputs are set by the run or by a flow's 'inputs'"}.get(
                kind, "it is not a coordinate, speed or discrete state")
            fix = {"parameter": "for a value that changes at jumps, declare a discrete state under "
                                "'discrete:' and reset that; ",
                   "input": f"set it in flow '{j['to']}' with 'inputs: {{{name}: <value>}}'; "}.get(kind, "")
            scope.report.error(path, f"cannot reset {kind + ' ' if kind else ''}'{name}': {why}",
                               did_you_mean(name, list(states) + list(discrete)) + fix + "resets assign "
                               "coordinates, speeds (<coordinate>_dot and declared speeds) and discrete states: "
                               + ", ".join(list(states) + list(discrete)))
    impact, restitution, impact_constraints = _impact(j, where, flows, constraint_names, scope)
    if not ok:
        return None
    used = _used_multipliers(j, where, [guard, *enabled], lams, flows, scope, contact_rows)
    direction = {"falling": FALLING, "rising": RISING, "either": EITHER}[j["direction"]]
    return Jump(j["name"], j["from"], j["to"], guard, direction, tuple(enabled), impact, restitution,
                impact_constraints, tuple(resets), int(j.get("priority", i)), found, where, _texts(j), used)


def _texts(j: dict) -> dict:
    """What the entry writes of the jump, as plain data (numbers and text as written, anything else as its
    text), for the jump template's documentation: guard, enabled, reset, impact."""
    return {"guard": _plain(j["guard"]), "enabled": _plain(j.get("enabled")), "reset": _plain(j.get("reset") or {}),
            "impact": _plain(j.get("impact", "none"))}


def _plain(value):
    if value is None or isinstance(value, (str, bool, int)) or (isinstance(value, float) and math.isfinite(value)):
        return value
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    return str(value)


def multiplier_symbols(constraints: list) -> dict:
    """{multiplier name: (symbol, constraint name)} of every constraint row. A multiplier is the force along its
    row's gradient: M dv/dt = G + A^T lam (ANDY eq. 10), so the multiplier of a row written as a gap (>= 0
    apart, e.g. `foot.y`) is >= 0 while the constraint pushes."""
    return {name: (sp.Symbol(f"lam_{name}", real=True), c.name) for c in constraints for name in c.multipliers}


def _used_multipliers(j: dict, where, exprs: list, lams: dict, flows: list, scope: Scope,
                      contact_rows: frozenset = frozenset()) -> dict:
    """{symbol: name} of the multipliers a jump's guard and conditions use; each must be of a constraint active
    in the jump's source flow (elsewhere it has no value), or a contact's (NaN while it is open: a guard or a
    condition that reads it is then false)."""
    source = next((f for f in flows if f.name == j["from"]), None)
    free = set().union(*(e.free_symbols for e in exprs))
    used = {}
    for name, (symbol, constraint) in lams.items():
        if symbol not in free:
            continue
        used[symbol] = name
        if source is not None and constraint not in source.constraints and constraint not in contact_rows:
            key = "guard" if symbol in exprs[0].free_symbols else "enabled"
            scope.report.error(where + (key,), f"multiplier '{name}' of constraint '{constraint}' has no value in "
                               f"flow '{source.name}', the jump's source: the constraint is not active there",
                               f"use the multipliers of the constraints of flow '{source.name}' "
                               f"({', '.join(source.constraints) or 'none'}), or add '{constraint}' to its "
                               "'constraints'")
    return used


def _guard(j: dict, where, names: dict, context: str, states: dict, found: dict, quantity,
           scope: Scope, multipliers: set = frozenset()) -> sp.Expr:
    """A jump's guard: a signed expression that changes during a flow (0 after a reported problem).

    The frame quantities it uses are recorded in `found` (through `quantity`)."""
    before = len(scope.report.problems)
    written = j["guard"] if isinstance(j["guard"], str) else ""
    op = next((op for op in (">=", "<=", "==", ">", "<") if op in written), None)
    if op is not None:              # a guard is a signed expression, not a condition
        a, b = (side.strip() for side in written.split(op, 1))
        b = f"({b})" if any(c in b for c in "+-") else b
        turn = {">": "rising", "<": "falling"}.get(op[0], "either")
        scope.report.error(where + ("guard",), f"the guard {written!r} is a comparison",
                           f"a guard is a signed expression that crosses 0 where the jump happens: write "
                           f"'guard: {a} - {b}' with 'direction: {turn}'; conditions that must also hold go "
                           "under 'enabled:'")
    guard = (sp.Integer(0) if op is not None
             else scope.expr(j["guard"], where + ("guard",), names, context, dotted=quantity))
    moving = set(states.values()) | set(found) | {TIME} | {names[n] for n in multipliers}
    if len(scope.report.problems) == before and not guard.free_symbols & moving:
        scope.report.error(where + ("guard",), f"the guard {j['guard']!r} does not change during a flow",
                           "a guard is a signed expression of the coordinates, speeds, frame quantities or t "
                           "that crosses 0 where the jump happens")
    return guard


def restitution(value, path, scope: Scope) -> sp.Expr:
    """A coefficient of restitution: a constant expression of parameters in [0, 1] at their defaults."""
    before = len(scope.report.problems)
    e_expr, e = scope.constant(value, path, allow_time=True)
    if len(scope.report.problems) > before:         # a bad expression is reported already
        pass
    elif TIME in e_expr.free_symbols:
        scope.report.error(path, f"the coefficient of restitution {value!r} depends on t",
                           "give a constant from 0 (plastic) to 1 (elastic): a number or an expression of "
                           "parameters")
    elif not 0 <= e <= 1:
        shown = f"{e:g}" if e_expr.is_number else f"{value} = {e:g}"
        scope.report.error(path, f"the coefficient of restitution is {shown}, outside [0, 1]",
                           "give 0 (plastic) to 1 (elastic); more than 1 would add energy at every impact")
    return e_expr


def _impact(j: dict, where, flows: list, constraint_names: list, scope: Scope) -> tuple[str, sp.Expr, tuple]:
    """(kind, restitution e, constraint names) of a jump's impact map."""
    spec = j.get("impact", "none")
    target = next((f for f in flows if f.name == j["to"]), None)
    if spec == "none":
        return "none", sp.Integer(0), ()
    if spec == "plastic":
        e, named = sp.Integer(0), None
    else:
        e = restitution(spec["restitution"], where + ("impact", "restitution"), scope)
        named = spec.get("constraints")
        for k, name in enumerate(named or []):
            if scope.known(name, constraint_names, where + ("impact", "constraints", k), "constraint") \
                    and name in named[:k]:
                scope.report.error(where + ("impact", "constraints", k), f"constraint '{name}' is listed twice",
                                   "list it once")
    chosen = named if named is not None else (target.constraints if target else ())
    if target is not None and not chosen:
        scope.report.error(where + ("impact",), f"the impact has no constraint rows to act on: the target flow "
                           f"'{target.name}' has no constraints",
                           "name the constraints that take the impact: impact: {restitution: e, constraints: "
                           "[names]}, or write the velocity change as a reset")
    return ("plastic" if spec == "plastic" else "restitution"), e, \
        tuple(n for n in constraint_names if n in chosen)
