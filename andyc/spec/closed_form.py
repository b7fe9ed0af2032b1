"""closed_form: the exact solution a model may state, every state as an expression of t.

`andyc bench` and `andyc stability` compare runs with it instead of with DOP853. It is the solution
from the initial state: a state inside it would make it an equation, not a solution, and a jump would
break the one formula.
"""

from __future__ import annotations

from andyc.spec.expressions import ExpressionError, parse
from andyc.spec.scope import Scope
from andyc.spec.suggest import did_you_mean


def build_closed_form(given: dict | None, jumps: list, scope: Scope, input_expressions: dict) -> dict:
    """state name -> x_i(t), an expression of t, parameters and held inputs, in STATES order.

    `input_expressions`: the inputs the model drives by an expression (not held, so not allowed)."""
    if given is None:
        return {}
    if jumps:
        scope.report.error(("closed_form",), "a closed form cannot describe jumps (the model has "
                           + ", ".join(f"'{j.name}'" for j in jumps) + ")",
                           "remove closed_form; andyc bench and stability then compare with DOP853 at rtol 1e-13")
        return {}
    states = {**{c.name: c.q for c in scope.coordinates}, **scope.rates, **{s.name: s.symbol for s in scope.signals}}
    # Inputs an expression drives are not held values (their held default 0 is not what the runs see).
    held = {n: s for n, (s, _) in scope.inputs.items() if n not in input_expressions}
    allowed = {**scope.parameter_names, **held}
    context = "a closed form uses t, parameters and held inputs, not those the model drives by an expression"
    kinds = {**{c.name: "coordinate" for c in scope.coordinates}, **{n: "speed" for n in scope.rates},
             **{s.name: "signal" for s in scope.signals}}
    out = {}
    for name, value in given.items():
        where = ("closed_form", name)
        if name not in states:
            kind = scope.kind_of(name)
            scope.report.error(where, f"{kind + ' ' if kind else ''}'{name}' is not a state of the model",
                               did_you_mean(name, states) + "the closed form gives each state: " + ", ".join(states))
            continue
        try:            # states parse too, to be named below as what they are
            expr = parse(value, {**allowed, **states})
        except ExpressionError:
            scope.expr(value, where, allowed, context)       # reports it, listing the names allowed here
            continue
        scope.report.used.update(expr.free_symbols)
        inside = [f"{kinds[n]} '{n}'" for n, s in states.items() if s in expr.free_symbols]
        if inside:
            scope.report.error(where, f"in {value!r}: the closed form of '{name}' uses {' and '.join(inside)}",
                               "a closed form is the solution itself: write x(t) with t, parameters and inputs "
                               "only (for example x0*cos(sqrt(k/m)*t)), no coordinates, speeds or signals")
        out[name] = expr
    missing = [n for n in states if n not in given]
    if missing:
        scope.report.error(("closed_form",), f"the closed form gives no expression for {', '.join(missing)}",
                           "give every state (coordinates, their rates <coordinate>_dot, declared speeds, signals): "
                           + ", ".join(f"{n}: ..." for n in missing))
    return {n: out[n] for n in states if n in out}
