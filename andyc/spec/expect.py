"""expect: short runs `andyc test` makes of the model, and what must hold for each.

Each entry is one run (t_end, and any of andyc sim's run options, parameters and inputs; what it does not
give comes from the model's simulate: section, then andyc sim's defaults). The run must finish; each
check the entry gives must also hold (andyc.analysis.expectations measures them):

    energy_drift: E     |E(t) - E(0)| <= E at every sample (J)
    energy_balance: E   |E(t) - E(0) - W(t)| <= E, W the work of the non-conservative elements (the
                        integral of their power, trapezoidal over the samples)
    residual: R         every active constraint residual, position and velocity level, <= R
    jumps: {j: n}       jump j happens n times
    jump_times:         jump j happens at these times, each within tol
    states:             the states at time t within tol of values, of the closed form, or of a run file
    final:              an expression of the final state within [min, max]

The schema checks the types and ranges; here the names are checked against the model, and the
expressions parsed by the safe parser (andyc.spec.expressions), never evaluated as code.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from andyc.spec.expressions import TIME
from andyc.spec.scope import Scope
from andyc.spec.simulate import DEFAULT_DT, check_steps, finite_numbers

# The run options an expectation may give (the rest of simulate:'s are about logging and stopping).
RUN_OPTIONS = ("t_end", "dt", "method", "init", "init_tol", "rtol", "atol", "energy_correction", "event_tol",
               "max_instant_jumps", "zeno_tol")
CHECKS = ("energy_drift", "energy_balance", "residual", "jumps", "jump_times", "states", "final")


@dataclass(frozen=True)
class Check:
    """One thing that must hold of a run: `kind` (one of CHECKS, 'states' one entry of it) and its data."""
    kind: str
    where: tuple
    data: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Expectation:
    """One short run and its checks."""
    index: int
    where: tuple
    run: dict                   # option -> value (RUN_OPTIONS), as written
    parameters: dict            # name -> value
    inputs: dict                # name -> a number or an expression's text (as simulate() takes them)
    checks: tuple               # of Check


def build_expect(given: list | None, scope: Scope, constraints: list, jumps: list, closed_form: dict,
                 simulate: dict | None = None) -> list:
    """The expectations, their names checked and expressions parsed, every number finite; [] without an
    expect: section. `simulate`: the model's simulate: section (a run's dt when the entry gives none)."""
    out = []
    for i, entry in enumerate(given or []):
        if not finite_numbers(entry, ("expect", i), scope.report):
            continue
        check_steps(entry["t_end"], entry.get("dt", (simulate or {}).get("dt", DEFAULT_DT)),
                    ("expect", i, "t_end"), scope.report)
        out.append(_expectation(i, entry, scope, constraints, jumps, closed_form))
    return out


def _expectation(i: int, entry: dict, scope: Scope, constraints: list, jumps: list,
                 closed_form: dict) -> Expectation:
    where = ("expect", i)
    report = scope.report
    parameters = {}
    for name, value in (entry.get("parameters") or {}).items():
        if scope.known(name, list(scope.parameters), where + ("parameters", name), "parameter"):
            parameters[name] = float(value)
    inputs = {}
    for name, value in (entry.get("inputs") or {}).items():
        path = where + ("inputs", name)
        if scope.known(name, list(scope.inputs), path, "input"):
            if isinstance(value, str):      # parsed here to be reported here; the run parses it again
                scope.expr(value, path, {**scope.kinematic, **scope.rates},
                           "an input's expression uses t, parameters, coordinates, speeds (<coordinate>_dot) "
                           "and discrete states")
            inputs[name] = value
    checks = []
    jump_names = [j.name for j in jumps]
    for kind in ("energy_drift", "energy_balance", "residual"):
        if kind in entry:
            checks.append(Check(kind, where + (kind,), {"bound": float(entry[kind])}))
    if "residual" in entry and not constraints:
        report.error(where + ("residual",), "the model has no constraints, so no residuals",
                     "remove residual:, or check energy_drift: or states: instead")
    if "jumps" in entry:
        counts = {n: c for n, c in entry["jumps"].items()
                  if scope.known(n, jump_names, where + ("jumps", n), "jump")}
        checks.append(Check("jumps", where + ("jumps",), {"counts": counts}))
    if "jump_times" in entry:
        times = {n: [float(t) for t in ts] for n, ts in entry["jump_times"]["times"].items()
                 if scope.known(n, jump_names, where + ("jump_times", "times", n), "jump")}
        checks.append(Check("jump_times", where + ("jump_times",),
                            {"times": times, "tol": float(entry["jump_times"]["tol"])}))
    states = {**{c.name: c.q for c in scope.coordinates}, **scope.rates, **{s.name: s.symbol for s in scope.signals},
              **scope.discrete_names}
    for k, at in enumerate(entry.get("states") or []):
        path = where + ("states", k)
        if at["t"] > entry["t_end"]:
            report.error(path + ("t",), f"t = {at['t']:g} s is past the run's end, t_end = {entry['t_end']:g} s",
                         "give a time within the run")
        data = {"t": float(at["t"]), "tol": float(at["tol"])}
        if "values" in at:
            data["values"] = {n: float(v) for n, v in at["values"].items()
                              if scope.known(n, list(states), path + ("values", n), "state")}
        elif "closed_form" in at:
            data["closed_form"] = True
            if not closed_form:
                report.error(path + ("closed_form",), "the model declares no closed_form",
                             "add a closed_form: section, or compare with values: or a reference: run file")
        else:
            file = Path(report.smap.file).parent / at["reference"]
            data["reference"] = str(file)
            if not file.is_file():
                report.error(path + ("reference",), f"the run file {at['reference']!r} does not exist (looked for "
                             f"{file})", "give a run file (.h5 or .csv) written by andyc sim, relative to the model file")
        checks.append(Check("states", path, data))
    names = {**states, **scope.parameter_names}
    for k, bound in enumerate(entry.get("final") or []):
        path = where + ("final", k)
        expr = scope.expr(bound["value"], path + ("value",), names,
                          "an expression of the final state uses t, states, discrete states and parameters")
        if "min" in bound and "max" in bound and bound["min"] > bound["max"]:
            report.error(path, f"min = {bound['min']:g} is above max = {bound['max']:g}", "give min <= max")
        used = {n: s for n, s in names.items() if s in expr.free_symbols}
        checks.append(Check("final", path, {"value": bound["value"], "expr": expr, "symbols": used,
                                            "time": TIME in expr.free_symbols,
                                            "min": bound.get("min"), "max": bound.get("max")}))
    run = {k: entry[k] for k in RUN_OPTIONS if k in entry}
    return Expectation(i, where, run, parameters, inputs, tuple(checks))
