"""A user-declared energy-type law Phi_e(t, q, v) = 0 (Braun & Goldfarb Part II §2, item (d); eq. 5-6).

`energy_law: <expression>` at the model's top level, or on a flow of the hybrid section, names an invariant of
the motion that the projection method's energy correction keeps instead of the built-in law E - E0 - W = 0
(E - E0 on a conservative model): after each step, v <- v - M^-1 N dPhi_e/dv^T Phi_e / |N L^-1 dPhi_e/dv^T|^2
(eq. 6, one Newton step along the law's velocity gradient, within the constraints' null space N). A flow's own
law wins over the model's; a flow with neither keeps the built-in law. The expression uses what guards use:
parameters, inputs, coordinates, speeds (<coordinate>_dot, declared speeds), discrete states, t and frame
quantities (world axes), and is taken as written: its constants say what value the invariant keeps (a discrete
state reset by a jump may carry a value from one flow to the next).

Refused with their line: a law that is not one scalar expression, a law on a model without speeds, a law that
depends on no speed or whose velocity gradient vanishes identically (there is no direction to correct along), a
law in a flow whose constraint rows fix every speed, and a model-level law beside `conserves_energy: true`
(two laws for one correction).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.constraints import QUANTITY_HINT, FrameQuantities, _vanishes
from andyc.spec.scope import Scope

KEY = "energy_law"
EXAMPLE = "energy_law: m*(x*y_dot - y*x_dot) - L0"
CONTEXT = ("an energy law uses parameters, inputs, coordinates, speeds (<coordinate>_dot and declared speeds), "
           "discrete states, t and " + QUANTITY_HINT + " (world axes)")


@dataclass(frozen=True)
class EnergyLaw:
    """Phi_e(t, q, v) = 0: the expression, the frame quantities it uses (symbol -> FrameQuantity), where it is
    written and its text."""
    expr: sp.Expr
    quantities: dict
    where: tuple
    text: str


def build_energy_laws(data: dict, flows: list, constraints: list, scope: Scope,
                      quantities: FrameQuantities) -> tuple:
    """The law of each flow (its own `energy_law`, else the model's, else None: the built-in law), in the order of
    `flows`; every problem reported with its line."""
    model_law = _law(data, (KEY,), scope, quantities) if KEY in data else None
    if model_law is not None and data.get("conserves_energy"):
        scope.report.error((KEY,), "the model declares two laws for the energy correction: conserves_energy: true "
                           "(E - E0 = 0) and this energy law", "remove one of them: an energy law replaces the "
                           "built-in one")
    written = ((data.get("hybrid") or {}).get("flows")) or []
    laws = []
    for i, flow in enumerate(flows):
        entry = written[i] if i < len(written) and flow.where == ("hybrid", "flows", i) else {}
        own = _law(entry, flow.where + (KEY,), scope, quantities) if KEY in entry else None
        law = own or model_law
        if law is not None:
            _check_free_speed(law, flow, constraints, scope)
        laws.append(law)
    return tuple(laws)


def _law(owner: dict, where: tuple, scope: Scope, quantities: FrameQuantities) -> EnergyLaw | None:
    """The law written at `where`, or None after reporting why it is none."""
    value = owner[KEY]
    if isinstance(value, (list, dict)) or isinstance(value, bool) or value is None:
        what = (f"a list of {len(value)}" if isinstance(value, list) else "a mapping" if isinstance(value, dict)
                else repr(value))
        scope.report.error(where, f"the energy law must be one scalar expression Phi_e(t, q, v) = 0, got {what}",
                           f"write one expression, e.g. '{EXAMPLE}'")
        return None
    if not scope.rates:
        scope.report.error(where, "the model has no speeds, and an energy law is corrected along its speeds",
                           "remove energy_law, or give the model coordinates")
        return None
    found = {}

    def quantity(owner_name, attribute):
        return quantities.symbol(owner_name, attribute, "world", found)

    before = len(scope.report.problems)
    expr = scope.expr(value, where, {**scope.forcing, **scope.rates}, CONTEXT, dotted=quantity)
    if len(scope.report.problems) > before:
        return None
    velocities = set(scope.rates.values()) | {s for s, f in found.items() if f.kind != "position"}
    moving = expr.free_symbols & velocities
    if not moving:
        scope.report.error(where, f"the energy law {value!r} depends on no speed, so the energy correction has no "
                           "direction to move the speeds along (its gradient dPhi_e/dv is 0)",
                           "write a law of the speeds, e.g. '" + EXAMPLE + "'; a law of positions only is a "
                           "holonomic constraint")
        return None
    if all(_vanishes(sp.diff(expr, s)) for s in moving):
        scope.report.error(where, f"in {value!r}: the derivative of the energy law with respect to the speeds is "
                           "identically 0, so the energy correction cannot move it",
                           "simplify the law: the correction moves the speeds along dPhi_e/dv")
        return None
    return EnergyLaw(expr, found, where, str(value))


def _check_free_speed(law: EnergyLaw, flow, constraints: list, scope: Scope) -> None:
    """Refuse a law in a flow whose constraint rows fix every speed (eq. 6: the direction N L^-1 dPhi_e/dv^T is 0)."""
    rows = sum(len(c.rows) for c in constraints if c.name in flow.constraints)
    speeds = len(scope.rates)
    if rows >= speeds:
        scope.report.error(law.where, f"the energy law cannot be corrected in flow '{flow.name}': its {rows} "
                           f"constraint rows fix all {speeds} speeds", "remove energy_law there, or a constraint "
                           "row of that flow")
