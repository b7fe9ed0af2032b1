"""YAML model (or URDF) -> Spec: read, check against the JSON Schema, check meaning.

A `.urdf` file, or a YAML model with a `urdf:` key, is first turned into the
same model dictionary by andyc.spec.urdf.

Every problem is collected with its line and document path; the loader raises
one SpecError carrying all of them, so `andyc check` can print them at once.
"""

from __future__ import annotations

import builtins
import difflib
import functools
import hashlib
import json
import keyword
import math
from pathlib import Path

import jsonschema
import numpy as np
import sympy as sp

from andyc.errors import Diagnostic, SpecError, format_path
from andyc.spec import urdf
from andyc.spec.meaning import meaning_sha256
from andyc.spec.expressions import MODULE_NAMES, RESERVED, TIME, ExpressionError, parse, parse_condition
from andyc.spec.model import (EITHER, FALLING, RISING, Body, Constraint, Coordinate, Damper, DiscreteState, Flow,
                              Frame, FrameQuantity, Jump, Load, Nonholonomic, Potential, Rotate, Signal, Spec, Speed,
                              Spring, Translate)
from andyc.spec.yamlpos import MAX_YAML_BYTES, SourceMap, load_yaml

SCHEMA_PATH = Path(__file__).resolve().parents[1] / "schemas" / "andyc-model.schema.json"
AXES = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1),
        "-x": (-1, 0, 0), "-y": (0, -1, 0), "-z": (0, 0, -1)}
MAX_URDF_BYTES = urdf.MAX_URDF_BYTES
ELEMENT_SECTIONS = ("bodies", "forces", "torques", "dampers", "springs", "potentials")
JOINTS = ("dh", "revolute", "prismatic", "ball", "floating", "nonholonomic")
_KIND = {"parameters": "parameter", "inputs": "input", "coordinates": "coordinate", "speeds": "speed",
         "frames": "frame",
         "bodies": "body", "forces": "force", "torques": "torque", "dampers": "damper",
         "springs": "spring", "potentials": "potential", "constraints": "constraint",
         "discrete": "discrete state"}
# Frame quantities in constraint expressions: F.<attribute> -> (kind, axis).
FRAME_QUANTITIES = {**{a: ("position", i) for i, a in enumerate("xyz")},
                    **{"v" + a: ("velocity", i) for i, a in enumerate("xyz")},
                    **{"w" + a: ("angular_velocity", i) for i, a in enumerate("xyz")}}
# A jump's function in <model>_jumps.py is named after it: not a builtin, nor a name that file uses.
JUMP_FILE_NAMES = frozenset(dir(builtins)) | {"math", "np", "JUMPS"}
QUANTITY_HINT = ("frame quantities: F.x, F.y, F.z (position), F.vx, F.vy, F.vz (velocity), "
                 "F.wx, F.wy, F.wz (angular velocity), for a frame F")


def schema() -> dict:
    return json.loads(SCHEMA_PATH.read_text())


@functools.lru_cache(maxsize=1)
def _defs() -> dict:
    """The schema's $defs, read once (to tell which definition an error is in)."""
    return schema()["$defs"]


def load(path, unlock: bool = False) -> Spec:
    """Load and validate a model file. Raises SpecError listing every problem.

    `unlock`: ignore the `lock:` of a YAML model's `urdf:` key (the robot with every joint free, for
    `andyc check` to count what locking saved)."""
    path = Path(path)
    file = str(path)
    try:
        if path.exists() and not path.is_file():         # a folder, a pipe (reading it would wait), a device
            raise SpecError([Diagnostic(file, 1, "", "this is a " + ("folder" if path.is_dir() else "special file")
                                        + ", not a model file", "give the path of a YAML model or a URDF")])
        size = path.stat().st_size
        limit = MAX_URDF_BYTES if path.suffix.lower() == ".urdf" else MAX_YAML_BYTES
        if size > limit:
            raise SpecError([Diagnostic(file, 1, "", f"the file has {size / 1e6:.1f} MB, past the limit of "
                                        f"{limit / 1e6:g} MB for a {'URDF' if limit == MAX_URDF_BYTES else 'model'} "
                                        "file", "check that this is the model file")])
        raw = path.read_bytes()
    except OSError as exc:
        raise SpecError([Diagnostic(file, 1, "", f"cannot read the file ({exc.strerror})",
                                    "check the path")])
    if path.suffix.lower() == ".urdf":              # a URDF: its own reader, the same builder
        robot = urdf.read(path, raw=raw)
        return _with_urdf(_Builder(robot.data, robot.source, hashlib.sha256(raw).hexdigest(),
                                   len(robot.data.get("bodies", []))).build(), robot, robot.data)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise SpecError([Diagnostic(file, 1, "", "the file is not UTF-8 text", "save it as UTF-8")])
    data, smap, duplicates = load_yaml(text, file)
    if not isinstance(data, dict):
        raise SpecError([Diagnostic(file, 1, "", "the document is not a mapping",
                                    "a model starts with keys such as 'name:', 'coordinates:', 'frames:'")])
    problems = _schema_problems(data, smap) + duplicates
    if problems:
        raise SpecError(sorted(problems, key=lambda d: d.line))
    if "urdf" in data:                              # start from a URDF, then the YAML's own keys
        if unlock and isinstance(data["urdf"], dict):
            data = {**data, "urdf": {k: v for k, v in data["urdf"].items() if k != "lock"}}
        data, smap, robot = urdf.merge(data, smap, path)
        problems = _schema_problems(data, smap)
        if problems:
            raise SpecError(sorted(problems, key=lambda d: (d.file, d.line)))
        return _with_urdf(_Builder(data, smap, hashlib.sha256(raw + robot.raw).hexdigest(),
                                   len(robot.data.get("bodies", []))).build(), robot, data)
    spec = _Builder(data, smap, hashlib.sha256(raw).hexdigest()).build()
    spec.files = (spec.file,)
    spec.meaning_sha256 = meaning_sha256(data)
    return spec


def _with_urdf(spec: Spec, robot, data: dict) -> Spec:
    """The URDF's visual references and warnings (unused elements) on the Spec; its fixed and locked
    joints' bodies are merged before deriving (reduce). `data`: the document the Spec was built from
    (the URDF's, merged with the YAML's keys)."""
    # The URDF's bytes count whole: what the reader takes from them is more than the document shows.
    spec.meaning_sha256 = meaning_sha256({**data, "reduce": True, "urdf_sha256": hashlib.sha256(robot.raw).hexdigest()})
    spec.visuals = robot.visuals
    spec.locked = robot.locked
    spec.files = tuple(dict.fromkeys((spec.file, robot.file)))
    spec.reduce = True
    spec.warnings = robot.warnings + spec.warnings
    return spec


def _signal_names(frame: dict) -> dict:
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


# -- schema -------------------------------------------------------------------

def _schema_problems(data, smap: SourceMap) -> list[Diagnostic]:
    validator = jsonschema.Draft202012Validator(schema())
    found = []                                  # (path, message, hint)
    for error in validator.iter_errors(data):
        found += _explain_all(error)
    # A typo such as 'masss' is one problem, not also a missing 'mass'.
    typos = {(path[:-1], hint.split("'")[1]) for path, message, hint in found
             if message.startswith("unknown field") and hint.startswith("did you mean")}
    found = [(path, message, hint) for path, message, hint in found
             if not (message.startswith("missing required field") and (path, message.split("'")[1]) in typos)]
    out = [smap.diag(path, message, hint) for path, message, hint in found]
    return sorted(out, key=lambda d: d.line)


def _explain_all(error) -> list[tuple]:
    """One schema error -> [(path, message, hint)], usually one entry."""
    path = tuple(error.absolute_path)
    if error.validator in ("oneOf", "anyOf"):
        return _explain_one_of(error, path)
    if error.validator == "additionalProperties" and isinstance(error.instance, dict):
        allowed = sorted(error.schema.get("properties", {}))
        out = []
        for key in (k for k in error.instance if k not in allowed):
            close = difflib.get_close_matches(str(key), allowed, n=1)
            out.append((path + (key,), f"unknown field '{key}'",
                        (f"did you mean '{close[0]}'? " if close else "") + "allowed fields: " + ", ".join(allowed)))
        return out
    if "propertyNames" in error.schema_path:      # a bad key: point at the key itself
        path += (error.instance,)
    return [(path, *_explain(error, path))]


# What each 'oneOf'/'anyOf' of the schema accepts, by $defs name: (what it is, how to write it).
_ALTERNATIVES = {
    "rotation": ("a rotation", "write one of {axis: z, angle: 0.5}, {rpy: [roll, pitch, yaw]} "
                               "or {quaternion: [w, x, y, z]}"),
    "damper": ("a damper", "give either 'speed: <coordinate>' or 'frame: <frame>'"),
    "nonholonomic": ("a nonholonomic link", "give 'velocity: [vx, vy, vz]', 'angular_velocity: [wx, wy, wz]' "
                                            "or both, as expressions of the speeds"),
    "spring": ("a spring", "give either 'length: <expression>' or 'between: [frameA, frameB]'"),
    "constraint": ("a constraint", "give either 'holonomic: <expressions>' or 'nonholonomic: <expressions>'"),
    "constraint_rows": ("constraint expression", 'write one expression such as "x - L", or a non-empty list of them'),
    "impact": ("impact", "write plastic, none, or {restitution: e} (optionally with 'constraints: [names]')"),
    "condition": ("condition", 'write a comparison such as "foot.x > fx", or a list of them (all must hold)'),
    "axis": ("axis", "write x, y, z, -x, -y, -z or three numbers such as [0, 0.6, 0.8]"),
    "inertia": ("inertia", "write [Ixx, Iyy, Izz], [Ixx, Iyy, Izz, Ixy, Ixz, Iyz] "
                           "or a 3x3 matrix [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]]"),
}


def _explain_one_of(error, path) -> list[tuple]:
    """jsonschema says only 'not valid under any of the given schemas'; say which and why."""
    kind = next((name for name, s in _defs().items() if s == error.schema), None)
    what, how = _ALTERNATIVES.get(kind, ("value", "see andyc's model schema, andyc/schemas/andyc-model.schema.json"))
    branches = error.schema[error.validator]
    inst = error.instance
    if all("required" in b for b in branches):
        # Alternatives told apart by which fields are present (a non-mapping is a 'type' error).
        if not isinstance(inst, dict):
            return []
        options = [b["required"] for b in branches]
        present = [k for k in inst if any(k in o for o in options)]
        if any(set(o) <= set(present) for o in options):
            return [(path, f"conflicting fields {', '.join(map(repr, present))}: {what} is given one way only", how)]
        for option in options:
            given = [k for k in option if k in present]
            if given:
                missing = [k for k in option if k not in present]
                return [(path, f"missing field '{missing[0]}' (it goes with '{given[0]}')", how)]
        wanted = (" or " if len(options) == 2 else ", or ").join(" and ".join(map(repr, o)) for o in options)
        return [(path, f"{what} needs {wanted}", how)]
    # Alternatives told apart by shape (axis, inertia): if exactly one alternative has the
    # right shape and fails only inside, report its errors; otherwise say what is accepted.
    by_branch = {}
    for sub in error.context:
        by_branch.setdefault(sub.relative_schema_path[0], []).append(sub)
    fitting = [errs for errs in by_branch.values()
               if all(e.relative_path and e.validator not in ("type", "enum", "const") for e in errs)]
    if len(fitting) == 1:
        return [(tuple(e.absolute_path), *_explain(e, tuple(e.absolute_path))) for e in fitting[0]]
    return [(path, f"{_describe(inst)} is not a valid {what}", how)]


_KINDS = {"object": "a mapping", "array": "a list", "string": "a name or text", "number": "a number",
          "boolean": "true or false", "integer": "a whole number"}
_TYPE_HINTS = {"object": "write 'key: value' entries, or {} for none", "array": "write a list such as [0, 0, 1]",
               "string": "write a name", "number": "write a number such as 1.5",
               "boolean": "write true or false", "integer": "write a whole number"}
_ITEMS = {"dh": "[d, theta, a, alpha]", "quaternion": "[w, x, y, z]", "rpy": "[roll, pitch, yaw]",
          "between": "[frameA, frameB]", "inertia": "one row of the matrix, such as [Ixx, Ixy, Ixz]"}


def _describe(inst) -> str:
    if inst is None:
        return "an empty value"
    if isinstance(inst, bool):
        return str(inst).lower()
    if isinstance(inst, dict):
        return "a mapping"
    if isinstance(inst, list):
        text = repr(inst)
        return "a list " + (text if len(text) <= 60 else text[:57] + "...")
    if isinstance(inst, str):
        return f"the text {inst!r}"
    return f"the number {inst!r}"


def _explain(error, path) -> tuple[str, str]:
    v, inst, sch = error.validator, error.instance, error.schema
    field = next((p for p in reversed(path) if isinstance(p, str)), "")
    if v == "required":
        name = error.message.split("'")[1]
        return f"missing required field '{name}'", f"add '{name}:' " + ("here" if path else "at the top level")
    if v == "type":
        want = [error.validator_value] if isinstance(error.validator_value, str) else error.validator_value
        if set(want) == {"number", "string"}:
            return f"expected a number or an expression, got {_describe(inst)}", \
                'write a number, or an expression such as "L/2"'
        how = next((how for kind, (_, how) in _ALTERNATIVES.items() if _defs()[kind] == sch),
                   _TYPE_HINTS.get(want[0], "see andyc's model schema, andyc/schemas/andyc-model.schema.json"))
        if len(path) == 2 and path[0] in ("coordinates", "speeds") and want == ["object"]:
            value = inst if isinstance(inst, (int, float, str)) and not isinstance(inst, bool) else 0
            how = f"write {{initial: {value}}}" + (", with 'velocity:' for the initial rate"
                                                   if path[0] == "coordinates" else "")
        return f"expected {' or '.join(_KINDS.get(w, w) for w in want)}, got {_describe(inst)}", how
    if v in ("minItems", "maxItems"):
        lo, hi = sch.get("minItems"), sch.get("maxItems")
        if lo == hi:
            example = _ITEMS.get(field, "[x, y, z]" if lo == 3 else "")
            return f"expected {lo} items, got {len(inst)}", f"write {lo} entries" + (f": {example}" if example else "")
        if v == "minItems":
            return f"expected at least {lo} item{'s' if lo != 1 else ''}, got {len(inst)}", "add the missing entries"
        return f"expected at most {hi} items, got {len(inst)}", "remove the extra entries"
    if v == "maxLength":
        return f"a name of {len(inst)} characters", f"use at most {error.validator_value} characters"
    if v == "pattern":
        return f"{_describe(inst)} is not a valid name", "names start with a letter and use letters, digits and '_'"
    if v in ("enum", "const"):
        allowed = error.validator_value if v == "enum" else [error.validator_value]
        return f"{_describe(inst)} is not allowed here", "use one of: " + ", ".join(map(str, allowed))
    if v == "minProperties":
        return "must not be empty", "declare at least one entry"
    return error.message, "see andyc's model schema, andyc/schemas/andyc-model.schema.json"


# -- meaning ------------------------------------------------------------------

class _Builder:
    """Semantic checks and lowering to the Spec; collects every problem."""

    def __init__(self, data: dict, smap: SourceMap, sha: str, urdf_bodies: int = 0):
        self.data = data
        self.smap = smap
        self.sha = sha
        # The first urdf_bodies bodies come from a URDF, whose reader checked (and warned about) their mass and
        # inertia: like Pinocchio, andyc simulates them as written (massless inertia, broken triangle inequality).
        self.urdf_bodies = urdf_bodies
        self.problems: list[Diagnostic] = []
        self.warnings: list[Diagnostic] = []
        self.used: set[sp.Symbol] = set()
        self.quantity_names: dict[tuple, str] = {}     # (frame, attribute, in frame) -> its symbol's name

    def error(self, where, message, hint=""):
        self.problems.append(self.smap.diag(where, message, hint))

    # expression contexts --------------------------------------------------
    def expr(self, value, where, names: dict, context: str, allow_time: bool = True, dotted=None):
        try:
            result = parse(value, names, allow_time, dotted)
        except ExpressionError as exc:
            message = str(exc)
            if exc.name in self.declared:   # declared, but not usable in this context
                message = f"in {value!r}: {_KIND[self.declared[exc.name]]} '{exc.name}' cannot be used here"
            self.error(where, message, exc.hint + (f" ({context})" if exc.name else ""))
            return sp.Integer(0)
        self.used |= result.free_symbols
        return result

    def vector(self, values, where, names, context):
        return sp.Matrix([self.expr(v, where + (i,), names, context) for i, v in enumerate(values)])

    def constant(self, value, where, allow_time: bool = False):
        """An expression of parameters only, with its value at the defaults (allow_time: t too, for the
        callers that say themselves why t cannot be used)."""
        e = self.expr(value, where, self.param_names, "only parameters are allowed here", allow_time=allow_time)
        try:
            return e, float(e.subs(self.defaults))
        except (TypeError, ValueError):
            return e, math.nan

    # the build ------------------------------------------------------------
    def build(self) -> Spec:
        d = self.data
        self.check_names()
        for section in ("parameters", "inputs"):
            for n, v in (d.get(section) or {}).items():
                if not isinstance(v, str) and not math.isfinite(v):
                    self.error((section, n), f"{v} is not a finite number", "give a finite default value")
        self.parameters = {n: (sp.Symbol(f"p_{n}", real=True), float(v))
                           for n, v in (d.get("parameters") or {}).items()}
        # An input given as an expression is driven by it in every run that does not set the input itself;
        # its default (held, e.g. for `andyc linearize`) is 0.
        self.inputs = {n: (sp.Symbol(f"u_{n}", real=True), 0.0 if isinstance(v, str) else float(v))
                       for n, v in (d.get("inputs") or {}).items()}
        self.param_names = {n: s for n, (s, _) in self.parameters.items()}
        self.defaults = {s: v for s, v in self.parameters.values()}
        coords = []
        for name, entry in (d.get("coordinates") or {}).items():
            where = ("coordinates", name)
            q = sp.Symbol(f"q_{name}", real=True)
            v = sp.Symbol(f"v_{name}", real=True)
            init, _ = self.constant(entry.get("initial", 0), where + ("initial",))
            vel, _ = self.constant(entry.get("velocity", 0), where + ("velocity",))
            coords.append(Coordinate(name, q, v, init, vel, where))
        self.coords = coords
        self.speeds = [Speed(name, sp.Symbol(f"v_{name}", real=True),
                             self.constant((entry or {}).get("initial", 0), ("speeds", name, "initial"))[0],
                             ("speeds", name))
                       for name, entry in (d.get("speeds") or {}).items()]
        self.discrete = []
        for name, value in (d.get("discrete") or {}).items():
            initial = self.constant(value, ("discrete", name), allow_time=True)[0]
            if TIME in initial.free_symbols:        # (the initial values are computed before t exists)
                self.error(("discrete", name), f"the initial value {value!r} of discrete state '{name}' depends on t",
                           "give a number or an expression of parameters")
            self.discrete.append(DiscreteState(name, sp.Symbol(f"d_{name}", real=True), initial,
                                               ("discrete", name)))
        # A discrete state whose name is taken (reported by check_names) does not shadow the first owner.
        self.discrete_names = {x.name: x.symbol for x in self.discrete if self.declared.get(x.name) == "discrete"}
        self.kin_names = {**self.param_names, **{c.name: c.q for c in coords}, **self.discrete_names}
        self.load_names = {**self.kin_names, **{n: s for n, (s, _) in self.inputs.items()}}
        # Nonholonomic velocities may also use every speed: coordinate rates as <name>_dot.
        self.rate_names = {**{f"{c.name}_dot": c.v for c in coords}, **{s.name: s.v for s in self.speeds}}
        self.signals: list[Signal] = []
        self.input_expressions, self.driven_inputs = {}, {}
        for n, v in (d.get("inputs") or {}).items():
            if isinstance(v, str):
                self.driven_inputs[n] = self.expr(
                    v, ("inputs", n), {**self.kin_names, **self.rate_names},
                    "an input's expression uses t, parameters, coordinates, speeds (<coordinate>_dot) and "
                    "discrete states")
                self.input_expressions[n] = v

        frames = self.frames()
        self.frame_names = {"world"} | {f["name"] for f in d["frames"]}
        extra_frames: list[Frame] = []
        bodies = [self.body(i, b, extra_frames) for i, b in enumerate(d.get("bodies") or [])]
        loads = [self.load_(kind, i, f, extra_frames)
                 for kind, section in (("force", "forces"), ("torque", "torques"))
                 for i, f in enumerate(d.get(section) or [])]
        dampers = [self.damper(i, x, extra_frames) for i, x in enumerate(d.get("dampers") or [])]
        springs = [self.spring(i, x) for i, x in enumerate(d.get("springs") or [])]
        potentials = [Potential(x["name"], self.expr(x["energy"], ("potentials", i, "energy"),
                                                     self.kin_names, "potentials use parameters, coordinates and t"),
                                ("potentials", i)) for i, x in enumerate(d.get("potentials") or [])]
        constraints = [self.constraint(i, x) for i, x in enumerate(d.get("constraints") or [])]
        constraints.sort(key=lambda c: not c.holonomic)     # holonomic rows first (DESIGN.md run layout)
        self.check_multipliers(constraints)
        flows, jumps, initial_flow = self.hybrid(constraints)
        closed_form = self.closed_form(jumps)
        conserves = bool(d.get("conserves_energy", False))
        if conserves:
            self.check_conservative(loads, dampers, springs, potentials, constraints, frames)
        gravity = (self.vector(d["gravity"], ("gravity",), self.param_names, "only parameters are allowed here")
                   if "gravity" in d else sp.zeros(3, 1))
        if self.problems:
            raise SpecError(sorted(self.problems, key=lambda p: p.line))
        for name, (sym, _) in self.parameters.items():
            if sym not in self.used:
                self.warnings.append(self.smap.diag(("parameters", name), f"parameter '{name}' is not used",
                                                    "remove it or use it in an expression"))
        for x in self.discrete:
            if x.symbol not in self.used:
                self.warnings.append(self.smap.diag(x.where, f"discrete state '{x.name}' is not used",
                                                    "remove it, or use it in a constraint, guard or reset"))
        return Spec(name=d["name"], description=d.get("description", ""), file=self.smap.file,
                    sha256=self.sha, source=self.smap, parameters=self.parameters, inputs=self.inputs,
                    coordinates=coords, speeds=self.speeds, signals=self.signals, gravity=gravity, frames=frames + extra_frames, bodies=bodies,
                    loads=loads, dampers=dampers, springs=springs, potentials=potentials,
                    constraints=constraints, conserves_energy=conserves, discrete=self.discrete, flows=flows,
                    jumps=jumps, initial_flow=initial_flow, warnings=self.warnings,
                    input_expressions=self.input_expressions, driven_inputs=self.driven_inputs,
                    closed_form=closed_form)

    def check_names(self):
        """Every name is unique across the model and not reserved; the model's name is no Python module's."""
        d = self.data
        if keyword.iskeyword(d["name"]) or d["name"] in MODULE_NAMES:
            self.error(("name",), f"'{d['name']}' is the name of a Python "
                       + ("keyword" if keyword.iskeyword(d["name"]) else "module")
                       + f": the generated module {d['name']}.py could not be imported by it, or would hide it",
                       "choose another name")
        seen: dict[str, tuple] = {}
        self.declared = {}          # name -> its section, for messages
        entries = [(("parameters", n), n) for n in (d.get("parameters") or {})]
        entries += [(("inputs", n), n) for n in (d.get("inputs") or {})]
        entries += [(("coordinates", n), n) for n in (d.get("coordinates") or {})]
        entries += [(("speeds", n), n) for n in (d.get("speeds") or {})]
        entries += [(("discrete", n), n) for n in (d.get("discrete") or {})]
        for section in ("frames",) + ELEMENT_SECTIONS + ("constraints",):
            entries += [((section, i, "name"), x["name"]) for i, x in enumerate(d.get(section) or [])]
        # Names andyc makes: coordinate rates and signal states.
        made = {f"{c}_dot": f"the rate of coordinate '{c}'" for c in (d.get("coordinates") or {})}
        for f in d["frames"]:
            for name, what in _signal_names(f).items():
                made[name] = f"the {what} signal of frame '{f['name']}'"
        for where, name in entries:
            if name in made:
                self.error(where, f"the name '{name}' is taken by {made[name]}", "choose another name")
            elif name in RESERVED or keyword.iskeyword(name):
                self.error(where, f"'{name}' is a reserved name", "choose another name (reserved: t, pi, world, "
                           "the function names and Python keywords)")
            elif name in seen:
                first = self.smap.describe(seen[name])
                self.error(where, f"duplicate name '{name}' (first defined at {first})",
                           "rename one (names are unique across parameters, inputs, coordinates, frames and elements)")
            else:
                seen[name] = where
                self.declared[name] = where[0]

    def frames(self) -> list[Frame]:
        raw = self.data["frames"]
        by_name = {}
        for i, f in enumerate(raw):
            by_name.setdefault(f["name"], i)
        known = sorted(by_name) + ["world"]
        ordered, state = [], {}

        def visit(i, trail):
            name = raw[i]["name"]
            if state.get(name) == "done":
                return
            if name in trail:
                cycle = trail[trail.index(name):] + [name]
                self.error(("frames", i, "parent"), "the frame graph has a cycle: " + " -> ".join(cycle),
                           "give one of these frames another parent (frames form a tree rooted at 'world')")
                for n in cycle:
                    state[n] = "done"
                return
            parent = raw[i]["parent"]
            if parent != "world":
                if parent not in by_name:
                    close = difflib.get_close_matches(parent, known, n=1)
                    self.error(("frames", i, "parent"), f"parent frame '{parent}' does not exist",
                               (f"did you mean '{close[0]}'? " if close else "") + "known frames: " + ", ".join(known))
                else:
                    visit(by_name[parent], trail + [name])
            if state.get(name) != "done":
                state[name] = "done"
                ordered.append(i)

        for i in range(len(raw)):
            visit(i, [])
        return [self.frame(i, raw[i]) for i in ordered]

    def frame(self, i, f) -> Frame:
        where = ("frames", i)
        ctx = "link expressions use parameters, coordinates and t"
        steps = []
        if "translation" in f:
            steps.append(Translate(self.vector(f["translation"], where + ("translation",), self.kin_names, ctx)))
        if "rotation" in f:
            steps += self.rotation(f["rotation"], where + ("rotation",))
        joints = [k for k in JOINTS if k in f]
        if len(joints) > 1:
            self.error(where, f"a frame has one joint, got {' and '.join(joints)}",
                       "split the link into two frames")
        if "axis" in f and not ({"revolute", "prismatic"} & set(f)):
            self.error(where + ("axis",), "'axis' belongs to a revolute or prismatic joint",
                       "add 'revolute: <coordinate>' or remove 'axis'")
        if "dh" in f:
            d_, theta, a, alpha = (self.expr(x, where + ("dh", k), self.kin_names, ctx) for k, x in enumerate(f["dh"]))
            steps += [Rotate(sp.Matrix([0, 0, 1]), theta), Translate(sp.Matrix([a, 0, d_])),
                      Rotate(sp.Matrix([1, 0, 0]), alpha)]
        for kind in ("revolute", "prismatic"):
            if kind in f:
                axis = self.axis(f.get("axis", "z"), where + ("axis",))
                value = self.expr(f[kind], where + (kind,), self.kin_names, ctx)
                steps.append(Rotate(axis, value) if kind == "revolute" else Translate(axis * value))
        steps = [s for s in steps if not (isinstance(s, Translate) and s.vector == sp.zeros(3, 1))
                 and not (isinstance(s, Rotate) and s.angle == 0)]
        for kind in ("ball", "floating", "nonholonomic"):
            if kind in f and len(joints) == 1:
                steps.append(self.nonholonomic(f["name"], kind, f[kind], where + (kind,)))
        return Frame(f["name"], f["parent"], tuple(steps), where)

    def nonholonomic(self, frame: str, kind: str, link: dict, where) -> Nonholonomic:
        """A ball, floating or general nonholonomic link, and its signals (paper eq. 4)."""
        if kind == "nonholonomic":
            ctx = ("nonholonomic velocities use parameters, coordinates, speeds, "
                   "<coordinate>_dot and t")
            names = {**self.kin_names, **self.rate_names}
            vel = (self.vector(link["velocity"], where + ("velocity",), names, ctx)
                   if "velocity" in link else None)
            ang = (self.vector(link["angular_velocity"], where + ("angular_velocity",), names, ctx)
                   if "angular_velocity" in link else None)
            for key, value in (("velocity", vel), ("angular_velocity", ang)):
                if value is not None:
                    self.check_linear(value, link[key], where + (key,))
            for key, needs in (("position", "velocity"), ("quaternion", "angular_velocity")):
                if key in link and needs not in link:
                    self.error(where + (key,), f"'{key}' goes with '{needs}'",
                               f"add '{needs}:' or remove '{key}' (a fixed offset is 'translation' or 'rotation')")
        else:
            count = 3 if kind == "ball" else 6
            speeds = self.joint_speeds(link["speeds"], count, kind, where + ("speeds",))
            vel = sp.Matrix(speeds[:3]) if kind == "floating" else None
            ang = sp.Matrix(speeds[-3:])
        position = quaternion = None
        if vel is not None:
            init = self.vector(link.get("position", [0, 0, 0]), where + ("position",), self.param_names,
                               "initial positions use parameters")
            position = tuple(self.signal(frame, c, init[i], where + ("position",)) for i, c in enumerate("xyz"))
        if ang is not None:
            init = self.quaternion(link.get("quaternion", [1, 0, 0, 0]), where + ("quaternion",))
            quaternion = tuple(self.signal(frame, f"q{c}", init[i], where + ("quaternion",))
                               for i, c in enumerate("wxyz"))
        return Nonholonomic(vel, ang, link.get("in", "body") == "body", position, quaternion)

    def joint_speeds(self, names: list, count: int, kind: str, where) -> list:
        what = "the angular velocity [wx, wy, wz]" if count == 3 else "[vx, vy, vz, wx, wy, wz]"
        if len(names) != count:
            self.error(where, f"a {kind} joint has {count} speeds, got {len(names)}",
                       f"list {count} speeds declared under 'speeds:': {what}")
            return [sp.Integer(0)] * count
        known = {s.name: s.v for s in self.speeds}
        out = []
        for j, name in enumerate(names):
            if name not in known:
                close = difflib.get_close_matches(name, list(known), n=1)
                self.error(where + (j,), f"'{name}' is not a declared speed",
                           (f"did you mean '{close[0]}'? " if close else "")
                           + "declare it under 'speeds:' (speeds: " + (", ".join(known) or "none") + ")")
                out.append(sp.Integer(0))
            else:
                out.append(known[name])
                self.used.add(known[name])
        for j, name in enumerate(names):
            if name in names[:j]:
                self.error(where + (j,), f"speed '{name}' is listed twice", "list distinct speeds")
        return out

    def check_linear(self, vec: sp.Matrix, written: list, where):
        """Velocities must be linear in the speeds: v = J(q, t) speeds + b(q, t)."""
        speeds = list(self.rate_names.values())
        for i, e in enumerate(vec):
            if any(sp.diff(e, a, b) != 0 for a in speeds for b in speeds):
                self.error(where + (i,), f"in {written[i]!r}: the velocity is not linear in the speeds",
                           "a velocity is J(q, t) * speeds + b(q, t); speeds may not be squared, "
                           "multiplied together or inside functions")

    def quaternion(self, values, where) -> list:
        """A unit quaternion of constants; an error names the value and its norm.

        After a reported problem it returns the identity, so later checks stay quiet.
        """
        identity = [sp.Integer(1), sp.Integer(0), sp.Integer(0), sp.Integer(0)]
        before = len(self.problems)
        exprs = [self.expr(v, where + (i,), {}, "initial quaternions are constants", allow_time=False)
                 for i, v in enumerate(values)]
        if len(self.problems) > before:     # a bad entry is reported already
            return identity
        nums = [float(e) for e in exprs]
        norm = math.sqrt(sum(c * c for c in nums))
        if abs(norm - 1.0) > 1e-9:
            unit = ", ".join(f"{c / norm:.12g}" for c in nums) if norm > 0 else "1, 0, 0, 0"
            self.error(where, f"quaternion [{', '.join(f'{c:g}' for c in nums)}] has norm {norm:.12g}, not 1",
                       f"use the unit quaternion [{unit}]")
            return identity
        return exprs

    def signal(self, frame, component, initial, where) -> sp.Symbol:
        name = f"{frame}_{component}"
        sym = sp.Symbol(f"s_{name}", real=True)
        self.signals.append(Signal(name, component, sym, initial, frame, where))
        return sym

    def axis(self, value, where) -> sp.Matrix:
        vec = AXES[value] if isinstance(value, str) else value
        if not all(math.isfinite(float(x)) for x in vec):
            self.error(where, f"the axis {vec} is not finite", "give a direction such as [0, 0, 1] or z")
            return sp.Matrix([0, 0, 1])
        norm = math.sqrt(sum(float(x) ** 2 for x in vec))
        if norm < 1e-12:
            self.error(where, "the axis is zero", "give a direction such as [0, 0, 1] or z")
            return sp.Matrix([0, 0, 1])
        # Exact when the norm is rational (z, [0, 0.6, 0.8]) so that zeros stay
        # structural; otherwise 17-digit floats, not a huge exact surd.
        m = sp.Matrix([sp.Rational(repr(float(x))) for x in vec])
        norm = sp.sqrt(sum(x ** 2 for x in m))
        if norm.is_Rational:
            return m / norm
        return sp.Matrix([sp.Float(float(x) / float(norm), 17) for x in m])

    def rotation(self, r, where) -> list:
        ctx = "rotation angles use parameters, coordinates and t"
        if "axis" in r:
            return [Rotate(self.axis(r["axis"], where + ("axis",)), self.expr(r["angle"], where + ("angle",), self.kin_names, ctx))]
        if "rpy" in r:
            roll, pitch, yaw = (self.expr(x, where + ("rpy", k), self.kin_names, ctx) for k, x in enumerate(r["rpy"]))
            # R = Rz(yaw) Ry(pitch) Rx(roll): applied left to right as z, then y, then x.
            return [Rotate(sp.Matrix([0, 0, 1]), yaw), Rotate(sp.Matrix([0, 1, 0]), pitch), Rotate(sp.Matrix([1, 0, 0]), roll)]
        w, x, y, z = (float(e) for e in self.quaternion(r["quaternion"], where + ("quaternion",)))
        s = math.sqrt(x * x + y * y + z * z)
        angle = 2 * math.atan2(s, w)
        if angle == 0:
            return []
        return [Rotate(sp.Matrix([sp.Float(x / s, 17), sp.Float(y / s, 17), sp.Float(z / s, 17)]), sp.Float(angle, 17))]

    def frame_ref(self, name, where, extra=()) -> bool:
        if name in self.frame_names:
            return True
        known = sorted(self.frame_names)
        close = difflib.get_close_matches(name, known, n=1)
        self.error(where, f"frame '{name}' does not exist",
                   (f"did you mean '{close[0]}'? " if close else "") + "known frames: " + ", ".join(known))
        return False

    def offset_frame(self, owner: str, frame: str, offset, where, extra: list) -> str:
        """A fixed child of `frame` at `offset` (frame axes); returns its name.

        Elements at the same point (a body's COM and a damper on it) share one
        frame, so its kinematics are computed once.
        """
        vec = self.vector(offset, where, self.param_names, "offsets use parameters only")
        if vec == sp.zeros(3, 1):
            return frame
        for f in extra:
            if f.parent == frame and f.transforms == (Translate(vec),):
                return f.name
        name = f"{owner}__{where[-1]}"
        extra.append(Frame(name, frame, (Translate(vec),), where, internal=True))
        return name

    def body(self, i, b, extra) -> Body:
        where = ("bodies", i)
        before = len(self.problems)
        mass, m = self.constant(b["mass"], where + ("mass",))
        if len(self.problems) == before and not m > 0 and i >= self.urdf_bodies:   # (a bad expression: reported)
            value = f"{m:g}" if mass.is_number else f"{b['mass']} = {m:g}"
            self.error(where + ("mass",), f"mass must be positive, got {value}", "give a positive mass in kg")
        inertia = self.inertia(b.get("inertia", [0, 0, 0]), where + ("inertia",))
        frame = b["frame"]
        if self.frame_ref(frame, where + ("frame",)) and "com" in b:
            frame = self.offset_frame(b["name"], frame, b["com"], where + ("com",), extra)
        return Body(b["name"], frame, mass, inertia, where)

    def inertia(self, value, where) -> sp.Matrix:
        before = len(self.problems)
        if len(value) == 3 and all(isinstance(r, list) for r in value):
            rows = [[self.constant(x, where + (i, j))[0] for j, x in enumerate(row)] for i, row in enumerate(value)]
            mat = sp.Matrix(rows)
        elif len(value) == 3:
            mat = sp.diag(*[self.constant(x, where + (i,))[0] for i, x in enumerate(value)])
        else:
            xx, yy, zz, xy, xz, yz = (self.constant(x, where + (i,))[0] for i, x in enumerate(value))
            mat = sp.Matrix([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        if len(self.problems) > before or where[1] < self.urdf_bodies:     # reported already, or a URDF's
            return mat
        try:
            num = np.array(mat.subs(self.defaults), dtype=float)
        except (TypeError, ValueError):
            return mat
        if not np.allclose(num, num.T, rtol=1e-12, atol=1e-12 * max(1.0, abs(num).max())):
            i, j = np.unravel_index(np.argmax(abs(num - num.T)), num.shape)
            self.error(where, f"inertia is not symmetric: I[{i}][{j}] = {num[i, j]:g} but I[{j}][{i}] = {num[j, i]:g}",
                       "make the off-diagonal pairs equal (an inertia tensor is symmetric)")
            return mat
        eig = np.linalg.eigvalsh(num)
        scale = max(1.0, abs(eig).max())
        if eig.min() < -1e-12 * scale:
            self.error(where, f"inertia is not positive semi-definite (principal moments {', '.join(f'{e:g}' for e in eig)})",
                       "check signs: the diagonal is positive and products of inertia are -sum(m x y)")
        elif any(eig[a] + eig[b] < eig[c] - 1e-9 * scale for a, b, c in ((0, 1, 2), (0, 2, 1), (1, 2, 0))):
            self.error(where, f"principal moments {', '.join(f'{e:g}' for e in eig)} break the triangle inequality",
                       "no rigid body has these moments (each must be at most the sum of the other two)")
        return mat

    def load_(self, kind, i, f, extra) -> Load:
        section = "forces" if kind == "force" else "torques"
        where = (section, i)
        frame = f["frame"]
        in_frame = f.get("in", "world")
        ok = self.frame_ref(frame, where + ("frame",))
        self.frame_ref(in_frame, where + ("in",))
        if ok and "point" in f:
            if kind == "torque":
                self.error(where + ("point",), "a torque has no point of action", "remove 'point'")
            else:
                frame = self.offset_frame(f["name"], frame, f["point"], where + ("point",), extra)
        vec = self.vector(f["vector"], where + ("vector",), self.load_names,
                          "forces use parameters, inputs, coordinates and t")
        return Load(f["name"], kind, frame, vec, in_frame, where)

    def damper(self, i, x, extra) -> Damper:
        where = ("dampers", i)
        coef, _ = self.constant(x["coefficient"], where + ("coefficient",))
        speed = x.get("speed")
        damped = [c.name for c in self.coords] + [s.name for s in self.speeds]
        if speed is not None and speed not in damped:
            close = difflib.get_close_matches(speed, damped, n=1)
            self.error(where + ("speed",), f"'{speed}' is not a coordinate or a speed",
                       (f"did you mean '{close[0]}'? " if close else "") + "coordinates and speeds: "
                       + ", ".join(damped))
        frame = x.get("frame")
        if frame is not None and self.frame_ref(frame, where + ("frame",)) and "point" in x:
            if x.get("angular"):
                self.error(where + ("point",), "an angular damper has no point", "remove 'point'")
            else:
                frame = self.offset_frame(x["name"], frame, x["point"], where + ("point",), extra)
        for key in ("angular", "point"):
            if key in x and "frame" not in x:
                self.error(where + (key,), f"'{key}' goes with 'frame'", "remove it, or damp a frame")
        return Damper(x["name"], coef, x.get("law", "linear"), speed, frame, bool(x.get("angular", False)), where)

    def spring(self, i, x) -> Spring:
        where = ("springs", i)
        k, _ = self.constant(x["stiffness"], where + ("stiffness",))
        rest, _ = self.constant(x.get("rest_length", 0), where + ("rest_length",))
        length = between = None
        if "length" in x:
            length = self.expr(x["length"], where + ("length",), self.kin_names,
                               "spring lengths use parameters, coordinates and t")
        else:
            between = tuple(x["between"])
            for j, name in enumerate(between):
                self.frame_ref(name, where + ("between", j))
            if between[0] == between[1]:
                self.error(where + ("between",), "a spring needs two different frames", "name two frames")
        return Spring(x["name"], k, rest, length, between, where)

    # constraints ------------------------------------------------------------
    def constraint(self, i, c) -> Constraint:
        where = ("constraints", i)
        holonomic = "holonomic" in c
        key = "holonomic" if holonomic else "nonholonomic"
        texts = c[key] if isinstance(c[key], list) else [c[key]]
        paths = [where + (key, j) for j in range(len(texts))] if isinstance(c[key], list) else [where + (key,)]
        in_frame = c.get("in", "world")
        in_ok = self.frame_ref(in_frame, where + ("in",))
        quantities = {}

        def quantity(owner: str, attribute: str) -> sp.Symbol:
            return self.frame_quantity(owner, attribute, in_frame, quantities, holonomic)

        if holonomic:
            names = self.kin_names
            context = "holonomic constraints use parameters, coordinates, t and " + QUANTITY_HINT.split(", F.vx")[0]
        else:
            names = {**self.kin_names, **self.rate_names}
            context = ("nonholonomic constraints use parameters, coordinates, speeds (<coordinate>_dot and "
                       "declared speeds), t and " + QUANTITY_HINT)

        def row(text, path):
            """The parsed row, or None after reporting a problem in it."""
            if holonomic:
                # A speed is reported as a speed, not as an unknown name: parse once more with the speeds.
                try:
                    trial = parse(text, {**names, **self.rate_names}, True, quantity)
                except ExpressionError:
                    trial = None
                speeds = [n for n, s in self.rate_names.items() if trial is not None and s in trial.free_symbols]
                if speeds:
                    self.error(path, f"in {text!r}: '{speeds[0]}' is a speed; a holonomic constraint depends on "
                               "positions only", "write velocity constraints under 'nonholonomic:'; holonomic "
                               "rows use parameters, coordinates, t and F.x, F.y, F.z")
                    return None
            before = len(self.problems)
            value = self.expr(text, path, names, context, dotted=quantity)
            return value if len(self.problems) == before else None

        parsed = [row(text, path) for text, path in zip(texts, paths)]
        coordinates = {q.q for q in self.coords} | {s for s, f in quantities.items() if f.kind == "position"}
        velocities = set(self.rate_names.values()) | {s for s, f in quantities.items() if f.kind != "position"}
        for value, text, path in zip(parsed, texts, paths):
            if value is None:                           # reported already
                continue
            free = value.free_symbols
            if holonomic and not free & coordinates:
                self.error(path, f"the constraint {text!r} does not depend on the coordinates or any frame position",
                           "a holonomic constraint is Gamma(t, q) = 0; use coordinates or F.x, F.y, F.z")
            if not holonomic:
                if not free & velocities:
                    self.error(path, f"the constraint {text!r} uses no speed or velocity",
                               "a constraint on positions goes under 'holonomic:'; a nonholonomic one is "
                               "J(q, t) speeds + b(q, t) = 0")
                elif any(sp.diff(value, a, b) != 0 for a in free & velocities for b in free & velocities):
                    self.error(path, f"in {text!r}: the constraint is not linear in the speeds and velocities",
                               "a nonholonomic constraint is J(q, t) speeds + b(q, t) = 0; speeds and velocities "
                               "may not be squared, multiplied together or inside functions")
        if "in" in c and in_ok and not quantities and None not in parsed:
            self.error(where + ("in",), f"'in: {in_frame}' has no effect: the constraint uses no frame quantity",
                       f"remove 'in', or write the constraint with frame quantities such as {in_frame}.x "
                       "(they are then taken in the axes of '" + in_frame + "')")
        rows = tuple(sp.Integer(0) if value is None else value for value in parsed)
        multipliers = c.get("multiplier")
        if multipliers is None:
            multipliers = [f"lambda_{c['name']}"] if len(rows) == 1 else [f"lambda_{c['name']}_{j}"
                                                                          for j in range(len(rows))]
        elif isinstance(multipliers, str):
            multipliers = [multipliers]
        if len(multipliers) != len(rows):
            self.error(where + ("multiplier",), f"{len(multipliers)} multiplier name(s) for {len(rows)} "
                       f"constraint row(s)", f"give one name per row ({len(rows)})")
        gains = c.get("gains") or {}
        if "stiffness" in gains and not holonomic:
            self.error(where + ("gains", "stiffness"), "a nonholonomic constraint has no stiffness (ANDY eq. 14: "
                       "K_s = 0)", "remove 'stiffness'; 'damping' acts on the constraint's velocity residual")
        stiffness = self.gain(gains, "stiffness", where) if holonomic else sp.Integer(0)
        damping = self.gain(gains, "damping", where)
        return Constraint(c["name"], holonomic, rows, tuple(multipliers), stiffness, damping,
                          quantities, where, tuple(paths))

    def frame_quantity(self, owner: str, attribute: str, in_frame: str, quantities: dict,
                       holonomic: bool = False) -> sp.Symbol:
        """The symbol of `owner.attribute` (a FrameQuantity, recorded in `quantities`), or ExpressionError."""
        written = f"{owner}.{attribute}"
        known = sorted(self.frame_names)
        if owner not in self.frame_names:
            if owner in self.declared:          # a body, a parameter, ... written as a frame
                frame = next((b["frame"] for b in self.data.get("bodies") or [] if b["name"] == owner), None)
                raise ExpressionError(f"'{owner}' is a {_KIND[self.declared[owner]]}, not a frame",
                                      (f"use the frame it is on: '{frame}.{attribute}'" if frame else
                                       "frame quantities belong to frames") + "; known frames: " + ", ".join(known))
            close = difflib.get_close_matches(owner, known, n=1)
            raise ExpressionError(f"frame '{owner}' does not exist",
                                  (f"did you mean '{close[0]}'? " if close else "")
                                  + "known frames: " + ", ".join(known))
        if attribute not in FRAME_QUANTITIES:
            close = ([attribute.lower()] if attribute.lower() in FRAME_QUANTITIES
                     else difflib.get_close_matches(attribute, list(FRAME_QUANTITIES), n=1))
            raise ExpressionError(f"'{written}' is not a frame quantity",
                                  (f"did you mean '{owner}.{close[0]}'? " if close else "") + QUANTITY_HINT)
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
        sym = sp.Symbol(self.quantity_name(owner, attribute, in_frame), real=True)
        quantities[sym] = FrameQuantity(owner, kind, axis, in_frame)
        return sym

    def quantity_name(self, owner: str, attribute: str, in_frame: str) -> str:
        """The symbol name of a frame quantity, one per (frame, attribute, in frame) in the whole model: names
        may contain '_in_' themselves, so a name already given to another quantity gets a numbered suffix."""
        key = (owner, attribute, in_frame)
        if key not in self.quantity_names:
            base = f"fq_{owner}_{attribute}" + ("" if in_frame == "world" else f"_in_{in_frame}")
            taken = set(self.quantity_names.values())
            name, n = base, 1
            while name in taken:
                n += 1
                name = f"{base}_{n}"
            self.quantity_names[key] = name
        return self.quantity_names[key]

    # hybrid automaton -----------------------------------------------------
    def hybrid(self, constraints) -> tuple[list, list, int]:
        """Flows, jumps and the initial flow's index; without a hybrid section, one flow with every constraint."""
        h = self.data.get("hybrid")
        names = [c.name for c in constraints]
        if h is None:
            return [Flow("default", tuple(names), {}, ())], [], 0
        flows, impacted = [], set()
        for i, f in enumerate(h["flows"]):
            where = ("hybrid", "flows", i)
            first = next((g.where for g in flows if g.name == f["name"]), None)
            if first is not None:
                self.error(where + ("name",), f"duplicate flow name '{f['name']}' (first defined at line "
                           f"{self.smap.line(first + ('name',))}, {format_path(first + ('name',))})",
                           "give each flow its own name")
            active = f.get("constraints", [])
            for j, name in enumerate(active):
                self.known(name, names, where + ("constraints", j), "constraint")
                if name in active[:j]:
                    self.error(where + ("constraints", j), f"constraint '{name}' is listed twice", "list it once")
            inputs = {}
            for name, value in (f.get("inputs") or {}).items():
                if self.known(name, list(self.inputs), where + ("inputs", name), "input"):
                    inputs[name] = self.constant(value, where + ("inputs", name), allow_time=True)[0]
                    if TIME in inputs[name].free_symbols:
                        self.error(where + ("inputs", name), f"the value {value!r} of input '{name}' in flow "
                                   f"'{f['name']}' depends on t", "a flow sets its inputs to constants: a number "
                                   "or an expression of parameters")
            flows.append(Flow(f["name"], tuple(n for n in names if n in active), inputs, where))
        flow_names = [f.name for f in flows]
        initial = h.get("initial", flow_names[0])
        initial_index = flow_names.index(initial) if self.known(initial, flow_names, ("hybrid", "initial"),
                                                                "flow") else 0
        jumps = []
        for i, j in enumerate(h.get("jumps") or []):
            jump = self.jump(i, j, flows, names)
            if jump is not None:
                jumps.append(jump)
                impacted |= set(jump.impact_constraints)
        used = {n for f in flows for n in f.constraints} | impacted
        for c in constraints:
            if c.name not in used:
                self.warnings.append(self.smap.diag(c.where, f"constraint '{c.name}' is active in no flow and "
                                                    "takes no impact", "list it in a flow's 'constraints', or remove it"))
        return flows, jumps, initial_index

    # closed form -----------------------------------------------------------
    def closed_form(self, jumps) -> dict:
        """closed_form: state name -> x_i(t), an expression of t, parameters and held inputs, in STATES order.

        It is the exact solution from the initial state, which andyc bench and stability compare runs with; a
        state inside it would make it an equation, not a solution, and a jump would break the one formula.
        """
        given = self.data.get("closed_form")
        if given is None:
            return {}
        if jumps:
            self.error(("closed_form",), "a closed form cannot describe jumps (the model has "
                       + ", ".join(f"'{j.name}'" for j in jumps) + ")",
                       "remove closed_form; andyc bench and stability then compare with DOP853 at rtol 1e-13")
            return {}
        states = {**{c.name: c.q for c in self.coords}, **self.rate_names, **{s.name: s.symbol for s in self.signals}}
        # Inputs an expression drives are not held values (their held default 0 is not what the runs see).
        held = {n: s for n, (s, _) in self.inputs.items() if n not in self.input_expressions}
        allowed = {**self.param_names, **held}
        context = "a closed form uses t, parameters and held inputs, not those the model drives by an expression"
        kinds = {**{c.name: "coordinate" for c in self.coords}, **{n: "speed" for n in self.rate_names},
                 **{s.name: "signal" for s in self.signals}}
        out = {}
        for name, value in given.items():
            where = ("closed_form", name)
            if name not in states:
                kind = _KIND.get(self.declared.get(name))
                close = difflib.get_close_matches(str(name), list(states), n=1)
                self.error(where, f"{kind + ' ' if kind else ''}'{name}' is not a state of the model",
                           (f"did you mean '{close[0]}'? " if close else "") + "the closed form gives each state: "
                           + ", ".join(states))
                continue
            try:            # states parse too, to be named below as what they are
                expr = parse(value, {**allowed, **states})
            except ExpressionError:
                self.expr(value, where, allowed, context)       # reports it, listing the names allowed here
                continue
            self.used |= expr.free_symbols
            inside = [f"{kinds[n]} '{n}'" for n, s in states.items() if s in expr.free_symbols]
            if inside:
                self.error(where, f"in {value!r}: the closed form of '{name}' uses {' and '.join(inside)}",
                           "a closed form is the solution itself: write x(t) with t, parameters and inputs only "
                           "(for example x0*cos(sqrt(k/m)*t)), no coordinates, speeds or signals")
            out[name] = expr
        missing = [n for n in states if n not in given]
        if missing:
            self.error(("closed_form",), f"the closed form gives no expression for {', '.join(missing)}",
                       "give every state (coordinates, their rates <coordinate>_dot, declared speeds, signals): "
                       + ", ".join(f"{n}: ..." for n in missing))
        return {n: out[n] for n in states if n in out}

    def known(self, name, known: list, where, kind: str) -> bool:
        """Report `name` (a reference to a {kind}) unless it is in `known`."""
        if name in known:
            return True
        known = list(dict.fromkeys(known))
        close = difflib.get_close_matches(str(name), known, n=1)
        self.error(where, f"{kind} '{name}' does not exist",
                   (f"did you mean '{close[0]}'? " if close else "")
                   + (f"{kind}s: {', '.join(known)}" if known else f"the model has no {kind}s"))
        return False

    def jump(self, i, j, flows, constraint_names) -> Jump | None:
        where = ("hybrid", "jumps", i)
        flow_names = [f.name for f in flows]
        ok = self.known(j["from"], flow_names, where + ("from",), "flow")
        ok = self.known(j["to"], flow_names, where + ("to",), "flow") and ok
        if j["name"] in JUMP_FILE_NAMES:
            self.error(where + ("name",), f"'{j['name']}' cannot name a jump: the jump's function in the jumps file "
                       f"(<model>_jumps.py) would hide Python's '{j['name']}'", "choose another name")
        earlier = [k for k, x in enumerate(self.data["hybrid"]["jumps"][:i]) if x["name"] == j["name"]]
        if earlier:
            first = ("hybrid", "jumps", earlier[0], "name")
            self.error(where + ("name",), f"duplicate jump name '{j['name']}' (first defined at line "
                       f"{self.smap.line(first)}, {format_path(first)})", "give each jump its own name")
        quantities = {}

        def quantity(owner, attribute):
            return self.frame_quantity(owner, attribute, "world", quantities)

        states = {**{c.name: c.q for c in self.coords}, **self.rate_names}
        discrete = self.discrete_names
        names = {**self.load_names, **self.rate_names, **discrete}
        context = ("guards, conditions and resets use parameters, inputs, coordinates, speeds (<coordinate>_dot "
                   "and declared speeds), discrete states, t and " + QUANTITY_HINT)
        before = len(self.problems)
        written = j["guard"] if isinstance(j["guard"], str) else ""
        op = next((op for op in (">=", "<=", "==", ">", "<") if op in written), None)
        if op is not None:              # a guard is a signed expression, not a condition
            a, b = (side.strip() for side in written.split(op, 1))
            b = f"({b})" if any(c in b for c in "+-") else b
            turn = {">": "rising", "<": "falling"}.get(op[0], "either")
            self.error(where + ("guard",), f"the guard {written!r} is a comparison",
                       f"a guard is a signed expression that crosses 0 where the jump happens: write "
                       f"'guard: {a} - {b}' with 'direction: {turn}'; conditions that must also hold go "
                       "under 'enabled:'")
        guard = (sp.Integer(0) if op is not None
                 else self.expr(j["guard"], where + ("guard",), names, context, dotted=quantity))
        moving = set(states.values()) | set(quantities) | {TIME}
        if len(self.problems) == before and not guard.free_symbols & moving:
            self.error(where + ("guard",), f"the guard {j['guard']!r} does not change during a flow",
                       "a guard is a signed expression of the coordinates, speeds, frame quantities or t "
                       "that crosses 0 where the jump happens")
        enabled = []
        texts = j.get("enabled", [])
        for k, text in enumerate(texts if isinstance(texts, list) else [texts]):
            path = where + ("enabled",) + ((k,) if isinstance(texts, list) else ())
            try:
                found = parse_condition(text, names, True, quantity)
            except ExpressionError as exc:
                message = str(exc)
                if exc.name in self.declared:   # a frame, body, ... written as a value
                    message = f"in {text!r}: {_KIND[self.declared[exc.name]]} '{exc.name}' cannot be used here"
                self.error(path, message, exc.hint + (f" ({context})" if exc.name else ""))
                continue
            self.used |= set().union(*(e.free_symbols for e in found))
            enabled += found
        resets = []
        for name, value in (j.get("reset") or {}).items():
            path = where + ("reset", name)
            if name in states or name in discrete:
                resets.append((name, self.expr(value, path, names, context, dotted=quantity)))
            else:
                close = difflib.get_close_matches(str(name), list(states) + list(discrete), n=1)
                kind = _KIND.get(self.declared.get(name))
                why = {"parameter": "parameters keep their value for the whole run",
                       "input": "inputs are set by the run or by a flow's 'inputs'"}.get(
                    kind, "it is not a coordinate, speed or discrete state")
                fix = {"parameter": "for a value that changes at jumps, declare a discrete state under "
                                    "'discrete:' and reset that; ",
                       "input": f"set it in flow '{j['to']}' with 'inputs: {{{name}: <value>}}'; "}.get(kind, "")
                self.error(path, f"cannot reset {kind + ' ' if kind else ''}'{name}': {why}",
                           (f"did you mean '{close[0]}'? " if close else "") + fix + "resets assign coordinates, "
                           "speeds (<coordinate>_dot and declared speeds) and discrete states: "
                           + ", ".join(list(states) + list(discrete)))
        impact, restitution, impact_constraints = self.impact(j, where, flows, constraint_names)
        if not ok:
            return None
        direction = {"falling": FALLING, "rising": RISING, "either": EITHER}[j["direction"]]
        return Jump(j["name"], j["from"], j["to"], guard, direction, tuple(enabled), impact, restitution,
                    impact_constraints, tuple(resets), int(j.get("priority", i)), quantities, where, dict(j))

    def impact(self, j, where, flows, constraint_names):
        """(kind, restitution e, constraint names) of a jump's impact map."""
        spec = j.get("impact", "none")
        target = next((f for f in flows if f.name == j["to"]), None)
        if spec == "none":
            return "none", sp.Integer(0), ()
        if spec == "plastic":
            restitution, named = sp.Integer(0), None
        else:
            path = where + ("impact", "restitution")
            before = len(self.problems)
            restitution, e = self.constant(spec["restitution"], path, allow_time=True)
            if len(self.problems) > before:         # a bad expression is reported already
                pass
            elif TIME in restitution.free_symbols:
                self.error(path, f"the coefficient of restitution {spec['restitution']!r} depends on t",
                           "give a constant from 0 (plastic) to 1 (elastic): a number or an expression of parameters")
            elif not 0 <= e <= 1:
                shown = f"{e:g}" if restitution.is_number else f"{spec['restitution']} = {e:g}"
                self.error(path, f"the coefficient of restitution is {shown}, outside [0, 1]",
                           "give 0 (plastic) to 1 (elastic); more than 1 would add energy at every impact")
            named = spec.get("constraints")
            for k, name in enumerate(named or []):
                if self.known(name, constraint_names, where + ("impact", "constraints", k), "constraint") \
                        and name in named[:k]:
                    self.error(where + ("impact", "constraints", k), f"constraint '{name}' is listed twice",
                               "list it once")
        chosen = named if named is not None else (target.constraints if target else ())
        if target is not None and not chosen:
            self.error(where + ("impact",), f"the impact has no constraint rows to act on: the target flow "
                       f"'{target.name}' has no constraints",
                       "name the constraints that take the impact: impact: {restitution: e, constraints: [names]}, "
                       "or write the velocity change as a reset")
        return ("plastic" if spec == "plastic" else "restitution"), restitution, \
            tuple(n for n in constraint_names if n in chosen)

    def gain(self, gains: dict, key: str, where) -> sp.Expr:
        path = where + ("gains", key)
        before = len(self.problems)
        value, number = self.constant(gains.get(key, 0), path, allow_time=True)
        if len(self.problems) > before:             # a bad expression is reported already
            return value
        if TIME in value.free_symbols:
            self.error(path, f"the {key} gain {gains[key]!r} depends on t",
                       "gains are constants: a number or an expression of parameters")
        elif number < 0:
            shown = f"{number:g}" if value.is_number else f"{gains[key]} = {number:g}"
            self.error(path, f"the {key} gain is negative, got {shown}",
                       "give a gain >= 0 (a negative gain pushes the motion away from the constraint)")
        return value

    def check_multipliers(self, constraints):
        """Multiplier names are unique and taken by nothing else (they name run-file columns)."""
        made = {f"{q.name}_dot": f"the rate of coordinate '{q.name}'" for q in self.coords}
        made.update({s.name: f"the {'position' if s.component in 'xyz' else 'quaternion'} signal of frame "
                             f"'{s.frame}'" for s in self.signals})
        made.update({n: f"the run-file column '{n}'" for n in ("time", "flow", "energy")})
        seen = {}
        for c in sorted(constraints, key=lambda c: c.where[1]):        # in document order
            written = self.data["constraints"][c.where[1]].get("multiplier")
            for j, name in enumerate(c.multipliers):
                if written is None:         # lambda_<constraint>: point at the name it comes from
                    path, what = c.where + ("name",), f"the default multiplier name '{name}' of constraint '{c.name}'"
                    fix = f"name the multiplier: add 'multiplier: <name>' to constraint '{c.name}'"
                else:
                    path = c.where + ("multiplier",) + ((j,) if isinstance(written, list) else ())
                    what, fix = f"the multiplier name '{name}'", "choose another name"
                if name in seen:
                    first = "earlier in this constraint" if seen[name] == c.name else f"in constraint '{seen[name]}'"
                    self.error(path, f"{what} is used twice (also {first})",
                               fix if written is None else "give each constraint row its own multiplier name")
                elif name in self.declared:
                    self.error(path, f"{what} is taken by a {_KIND[self.declared[name]]}", fix)
                elif name in made:
                    self.error(path, f"{what} is taken by {made[name]}", fix)
                seen.setdefault(name, c.name)

    def check_conservative(self, loads, dampers, springs, potentials, constraints, frames):
        """conserves_energy: nothing in the model may do work on it.

        A holonomic constraint does work when it depends on t; a nonholonomic row J v + b = 0 when its
        term without speeds, b, is not 0 (J may depend on t: its force is normal to every allowed velocity).
        """
        workers = [f"damper '{x.name}'" for x in dampers] + [f"{x.kind} '{x.name}'" for x in loads]
        # (Rows without coordinates, or without speeds, are reported by constraint() already.)
        for c in sorted(constraints, key=lambda c: c.where[1]):
            if c.holonomic:
                positions = {q.q for q in self.coords} | set(c.quantities)
                if any(TIME in r.free_symbols and r.free_symbols & positions for r in c.rows):
                    workers.append(f"constraint '{c.name}' (depends on t)")
                continue
            speeds = set(self.rate_names.values()) | {s for s, f in c.quantities.items() if f.kind != "position"}
            texts = self.data["constraints"][c.where[1]]["nonholonomic"]
            texts = texts if isinstance(texts, list) else [texts]
            rest = [text for r, text in zip(c.rows, texts)
                    if r.free_symbols & speeds and sp.expand(r.subs({s: 0 for s in speeds})) != 0]
            if rest:
                workers.append(f"constraint '{c.name}' ({rest[0]!r} has a term without speeds)")
        workers += [f"frame '{f.name}' (its link depends on t)" for f in frames
                    if any(TIME in _free(step) for step in f.transforms)]
        workers += [f"spring '{x.name}' (depends on t)" for x in springs
                    if x.length is not None and TIME in x.length.free_symbols]
        workers += [f"potential '{x.name}' (depends on t)" for x in potentials if TIME in x.energy.free_symbols]
        if workers:
            self.error(("conserves_energy",), "the model declares energy conserved, but " + ", ".join(workers)
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
