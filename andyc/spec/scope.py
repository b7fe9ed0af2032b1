"""The names a model declares, and the scope its expressions are read in.

- `Report`: the problems and warnings found so far, each located by its document path, and the symbols
  the expressions used (a parameter no expression uses is warned about).
- `check_names`: every name is unique across the model and not reserved.
- `declare_constants`, `declare_states`: parameters and inputs, then coordinates, speeds and discrete
  states, each given its symbol; each returns the `Scope` the next one reads its expressions in.
- `Scope`: the names declared so far with their symbols. It answers "what may this expression use" with
  tables named for their readers (`kinematic` for links, `forcing` for forces, `rates` for velocities)
  and parses an expression against one of them, reporting what is wrong.

A Scope's names never change: a later stage gets a new Scope (`with_states`, `with_frames`), so the
order in which names become usable is the order of the calls in andyc.spec.load. (The Report it holds
is the one every stage writes to.)
"""

from __future__ import annotations

import keyword
import math

import sympy as sp

from andyc.errors import Diagnostic
from andyc.spec.expressions import MODULE_NAMES, RESERVED, TIME, ExpressionError, parse
from andyc.spec.model import Coordinate, DiscreteState, Speed
from andyc.spec.suggest import did_you_mean
from andyc.spec.yamlpos import SourceMap

ELEMENT_SECTIONS = ("bodies", "forces", "torques", "actuators", "dampers", "springs", "potentials")
# One entry of each section that declares names, as messages call it ("parameter 'L' cannot be used here").
SECTION_SINGULAR = {"parameters": "parameter", "inputs": "input", "coordinates": "coordinate", "speeds": "speed",
                    "frames": "frame",
                    "bodies": "body", "forces": "force", "torques": "torque", "actuators": "actuator",
                    "dampers": "damper",
                    "springs": "spring", "potentials": "potential", "constraints": "constraint",
                    "contacts": "contact",
                    "discrete": "discrete state"}


class Report:
    """Every problem and warning found in one model, located through its source map."""

    def __init__(self, smap: SourceMap):
        self.smap = smap
        self.problems: list[Diagnostic] = []
        self.warnings: list[Diagnostic] = []
        self.used: set[sp.Symbol] = set()      # what the expressions use, for the "is not used" warnings

    def error(self, where, message: str, hint: str = ""):
        self.problems.append(self.smap.diag(where, message, hint))

    def warn(self, where, message: str, hint: str = ""):
        self.warnings.append(self.smap.diag(where, message, hint))


class Scope:
    """The names declared so far, their symbols, and the expressions that may use them."""

    def __init__(self, report: Report, declared: dict, parameters: dict, inputs: dict,
                 coordinates: list = (), speeds: list = (), discrete: list = (), signals: list = (),
                 frames: set = frozenset()):
        self.report = report
        self.declared = declared            # name -> the section that declares it (from check_names)
        self.parameters = parameters        # name -> (symbol, default)
        self.inputs = inputs                # name -> (symbol, held default)
        self.coordinates = coordinates      # of Coordinate
        self.speeds = speeds                # of Speed (quasi-velocities)
        self.discrete = discrete            # of DiscreteState
        self.signals = signals              # of Signal, made by the frames' nonholonomic links
        self.frames = frames                # frame names, 'world' among them
        self.parameter_names = {n: s for n, (s, _) in parameters.items()}
        self.defaults = {s: v for s, v in parameters.values()}
        # A discrete state whose name is taken (reported by check_names) does not shadow the first owner.
        self.discrete_names = {x.name: x.symbol for x in discrete if declared.get(x.name) == "discrete"}
        # Links, spring lengths, potentials and holonomic rows: positions only.
        self.kinematic = {**self.parameter_names, **{c.name: c.q for c in coordinates}, **self.discrete_names}
        # Forces and torques, guards: the inputs too.
        self.forcing = {**self.kinematic, **{n: s for n, (s, _) in inputs.items()}}
        # Velocities (nonholonomic links and rows) may also use every speed: coordinate rates as <name>_dot.
        self.rates = {**{f"{c.name}_dot": c.v for c in coordinates}, **{s.name: s.v for s in speeds}}

    def with_states(self, coordinates: list, speeds: list, discrete: list) -> Scope:
        return Scope(self.report, self.declared, self.parameters, self.inputs, coordinates, speeds, discrete)

    def with_frames(self, frames: set, signals: list) -> Scope:
        return Scope(self.report, self.declared, self.parameters, self.inputs, self.coordinates, self.speeds,
                     self.discrete, signals, frames)

    def kind_of(self, name) -> str | None:
        """What `name` was declared as ('parameter', 'frame', ...), or None."""
        return SECTION_SINGULAR.get(self.declared.get(name))

    # expressions ------------------------------------------------------------
    def expr(self, value, where, names: dict, context: str, allow_time: bool = True, dotted=None) -> sp.Expr:
        """`value` parsed with `names` (one of the tables above), or 0 after reporting why it cannot be.

        `context` says which names this place allows; it is added to the hint when a name is the problem."""
        try:
            result = parse(value, names, allow_time, dotted)
        except ExpressionError as exc:
            message = str(exc)
            if exc.name in self.declared:   # declared, but not usable in this context
                message = f"in {value!r}: {self.kind_of(exc.name)} '{exc.name}' cannot be used here"
            self.report.error(where, message, exc.hint + (f" ({context})" if exc.name else ""))
            return sp.Integer(0)
        self.report.used.update(result.free_symbols)
        return result

    def vector(self, values, where, names: dict, context: str) -> sp.Matrix:
        return sp.Matrix([self.expr(v, where + (i,), names, context) for i, v in enumerate(values)])

    def constant(self, value, where, allow_time: bool = False) -> tuple[sp.Expr, float]:
        """An expression of parameters only, with its value at the defaults (allow_time: t too, for the
        callers that say themselves why t cannot be used)."""
        e = self.expr(value, where, self.parameter_names, "only parameters are allowed here", allow_time=allow_time)
        try:
            return e, float(e.subs(self.defaults))
        except (TypeError, ValueError):
            return e, math.nan

    # references -------------------------------------------------------------
    def known(self, name, known: list, where, kind: str) -> bool:
        """Report `name` (a reference to a {kind}) unless it is in `known`."""
        if name in known:
            return True
        known = list(dict.fromkeys(known))
        self.report.error(where, f"{kind} '{name}' does not exist",
                          did_you_mean(name, known)
                          + (f"{kind}s: {', '.join(known)}" if known else f"the model has no {kind}s"))
        return False

    def known_frame(self, name, where) -> bool:
        """Report `name` (a reference to a frame) unless a frame has it."""
        if name in self.frames:
            return True
        known = sorted(self.frames)
        self.report.error(where, f"frame '{name}' does not exist",
                          did_you_mean(name, known) + "known frames: " + ", ".join(known))
        return False


# -- declarations ---------------------------------------------------------------

def check_names(data: dict, report: Report) -> dict:
    """Every name is unique across the model and not reserved; the model's name is no Python module's.

    Returns name -> the section that declares it (the first, when a name is declared twice)."""
    if keyword.iskeyword(data["name"]) or data["name"] in MODULE_NAMES:
        report.error(("name",), f"'{data['name']}' is the name of a Python "
                     + ("keyword" if keyword.iskeyword(data["name"]) else "module")
                     + f": the generated module {data['name']}.py could not be imported by it, or would hide it",
                     "choose another name")
    seen: dict[str, tuple] = {}
    declared = {}
    entries = [(("parameters", n), n) for n in (data.get("parameters") or {})]
    entries += [(("inputs", n), n) for n in (data.get("inputs") or {})]
    entries += [(("coordinates", n), n) for n in (data.get("coordinates") or {})]
    entries += [(("speeds", n), n) for n in (data.get("speeds") or {})]
    entries += [(("discrete", n), n) for n in (data.get("discrete") or {})]
    for section in ("frames",) + ELEMENT_SECTIONS + ("constraints", "contacts"):
        entries += [((section, i, "name"), x["name"]) for i, x in enumerate(data.get(section) or [])]
    # Names andyc makes: coordinate rates and signal states.
    made = {f"{c}_dot": f"the rate of coordinate '{c}'" for c in (data.get("coordinates") or {})}
    for f in data["frames"]:
        for name, what in signal_names(f).items():
            made[name] = f"the {what} signal of frame '{f['name']}'"
    for where, name in entries:
        if name in made:
            report.error(where, f"the name '{name}' is taken by {made[name]}", "choose another name")
        elif name in RESERVED or keyword.iskeyword(name):
            report.error(where, f"'{name}' is a reserved name", "choose another name (reserved: t, pi, world, "
                         "the function names and Python keywords)")
        elif name in seen:
            first = report.smap.describe(seen[name])
            report.error(where, f"duplicate name '{name}' (first defined at {first})",
                         "rename one (names are unique across parameters, inputs, coordinates, frames and elements)")
        else:
            seen[name] = where
            declared[name] = where[0]
    return declared


def signal_names(frame: dict) -> dict:
    """State names of the signals a frame's link creates -> what they are."""
    out = {}
    link = frame.get("ball") or frame.get("floating") or frame.get("nonholonomic")
    if not isinstance(link, dict):
        return out
    name = frame["name"]
    if "floating" in frame or "velocity" in link:
        out.update({f"{name}_{c}": "position" for c in "xyz"})
    if "ball" in frame or "floating" in frame or "angular_velocity" in link:
        out.update({f"{name}_q{c}": "quaternion" for c in "wxyz"})
    return out


def declare_constants(data: dict, report: Report, declared: dict) -> Scope:
    """Parameters and inputs with their symbols and defaults: the scope the states' initial values use."""
    for section in ("parameters", "inputs"):
        for n, v in (data.get(section) or {}).items():
            if not isinstance(v, str) and not math.isfinite(v):
                report.error((section, n), f"{v} is not a finite number", "give a finite default value")
    parameters = {n: (sp.Symbol(f"p_{n}", real=True), float(v)) for n, v in (data.get("parameters") or {}).items()}
    # An input given as an expression is driven by it in every run that does not set the input itself;
    # its default (held, e.g. for `andyc linearize`) is 0.
    inputs = {n: (sp.Symbol(f"u_{n}", real=True), 0.0 if isinstance(v, str) else float(v))
              for n, v in (data.get("inputs") or {}).items()}
    return Scope(report, declared, parameters, inputs)


def declare_states(data: dict, scope: Scope) -> Scope:
    """Coordinates, speeds and discrete states, with their initial values (expressions of parameters)."""
    coordinates = []
    for name, entry in (data.get("coordinates") or {}).items():
        where = ("coordinates", name)
        q = sp.Symbol(f"q_{name}", real=True)
        v = sp.Symbol(f"v_{name}", real=True)
        init, _ = scope.constant(entry.get("initial", 0), where + ("initial",))
        vel, _ = scope.constant(entry.get("velocity", 0), where + ("velocity",))
        coordinates.append(Coordinate(name, q, v, init, vel, where))
    speeds = [Speed(name, sp.Symbol(f"v_{name}", real=True),
                    scope.constant((entry or {}).get("initial", 0), ("speeds", name, "initial"))[0], ("speeds", name))
              for name, entry in (data.get("speeds") or {}).items()]
    discrete = []
    for name, value in (data.get("discrete") or {}).items():
        initial = scope.constant(value, ("discrete", name), allow_time=True)[0]
        if TIME in initial.free_symbols:        # (the initial values are computed before t exists)
            scope.report.error(("discrete", name), f"the initial value {value!r} of discrete state '{name}' "
                               "depends on t", "give a number or an expression of parameters")
        discrete.append(DiscreteState(name, sp.Symbol(f"d_{name}", real=True), initial, ("discrete", name)))
    return scope.with_states(coordinates, speeds, discrete)


def driven_inputs(data: dict, scope: Scope) -> tuple[dict, dict]:
    """The inputs written as expressions: (name -> the text, name -> the expression parsed)."""
    texts, parsed = {}, {}
    for n, v in (data.get("inputs") or {}).items():
        if isinstance(v, str):
            parsed[n] = scope.expr(v, ("inputs", n), {**scope.kinematic, **scope.rates},
                                   "an input's expression uses t, parameters, coordinates, speeds (<coordinate>_dot) "
                                   "and discrete states")
            texts[n] = v
    return texts, parsed


def warn_unused(scope: Scope):
    """A parameter or discrete state no expression uses is warned about (after a build without problems)."""
    for name, (sym, _) in scope.parameters.items():
        if sym not in scope.report.used:
            scope.report.warn(("parameters", name), f"parameter '{name}' is not used",
                              "remove it or use it in an expression")
    for x in scope.discrete:
        if x.symbol not in scope.report.used and x.where[0] == "discrete":     # (not a contact's own states)
            scope.report.warn(x.where, f"discrete state '{x.name}' is not used",
                              "remove it, or use it in a constraint, guard or reset")
