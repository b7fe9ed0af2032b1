"""YAML model -> Spec: read, check against the JSON Schema, check meaning.

Every problem is collected with its line and document path; the loader raises
one SpecError carrying all of them, so `andyc check` can print them at once.
"""

from __future__ import annotations

import difflib
import hashlib
import json
import keyword
import math
from pathlib import Path

import jsonschema
import numpy as np
import sympy as sp

from andyc.errors import Diagnostic, SpecError
from andyc.spec.expressions import RESERVED, ExpressionError, parse
from andyc.spec.model import (Body, Coordinate, Damper, Frame, Load, Potential,
                              Rotate, Spec, Spring, Translate)
from andyc.spec.yamlpos import SourceMap, load_yaml

SCHEMA_PATH = Path(__file__).resolve().parents[2] / "schemas" / "andyc-model.schema.json"
AXES = {"x": (1, 0, 0), "y": (0, 1, 0), "z": (0, 0, 1),
        "-x": (-1, 0, 0), "-y": (0, -1, 0), "-z": (0, 0, -1)}
ELEMENT_SECTIONS = ("bodies", "forces", "torques", "dampers", "springs", "potentials")


def schema() -> dict:
    return json.loads(SCHEMA_PATH.read_text())


def load(path) -> Spec:
    """Load and validate a model file. Raises SpecError listing every problem."""
    path = Path(path)
    file = str(path)
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise SpecError([Diagnostic(file, 1, "", f"cannot read the file ({exc.strerror})",
                                    "check the path")])
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise SpecError([Diagnostic(file, 1, "", "the file is not UTF-8 text", "save it as UTF-8")])
    data, smap = load_yaml(text, file)
    if not isinstance(data, dict):
        raise SpecError([Diagnostic(file, 1, "", "the document is not a mapping",
                                    "a model starts with keys such as 'name:', 'coordinates:', 'frames:'")])
    problems = _schema_problems(data, smap)
    if problems:
        raise SpecError(problems)
    return _Builder(data, smap, hashlib.sha256(raw).hexdigest()).build()


# -- schema -------------------------------------------------------------------

def _schema_problems(data, smap: SourceMap) -> list[Diagnostic]:
    validator = jsonschema.Draft202012Validator(schema())
    out = []
    for error in sorted(validator.iter_errors(data), key=lambda e: list(map(str, e.absolute_path))):
        if error.context:
            error = jsonschema.exceptions.best_match(error.context)
        message, hint = _explain(error)
        out.append(smap.diag(tuple(error.absolute_path), message, hint))
    return out


def _explain(error) -> tuple[str, str]:
    v, inst = error.validator, error.instance
    names = {"object": "a mapping", "array": "a list", "string": "a string", "number": "a number",
             "boolean": "true or false", "integer": "an integer"}
    if v == "required":
        field = error.message.split("'")[1]
        return f"missing required field '{field}'", f"add '{field}:' here"
    if v == "additionalProperties":
        allowed = sorted(error.schema.get("properties", {}))
        extra = [k for k in inst if k not in allowed] if isinstance(inst, dict) else []
        key = extra[0] if extra else "?"
        close = difflib.get_close_matches(key, allowed, n=1)
        return (f"unknown field '{key}'",
                (f"did you mean '{close[0]}'? " if close else "") + "allowed fields: " + ", ".join(allowed))
    if v == "type":
        want = error.validator_value
        want = [want] if isinstance(want, str) else want
        got = type(inst).__name__ if not isinstance(inst, (dict, list)) else ("a mapping" if isinstance(inst, dict) else "a list")
        return f"expected {' or '.join(names.get(w, w) for w in want)}, got {got} {inst!r}"[:200], \
            "change the value to the expected kind"
    if v in ("minItems", "maxItems"):
        return f"expected {error.validator_value} {'or more' if v == 'minItems' else 'or fewer'} items, got {len(inst)}", \
            "give the right number of entries"
    if v == "pattern":
        return f"'{inst}' is not a valid name", "names start with a letter and use letters, digits and '_'"
    if v in ("enum", "const"):
        allowed = error.validator_value if v == "enum" else [error.validator_value]
        return f"{inst!r} is not allowed", "use one of: " + ", ".join(map(str, allowed))
    if v == "minProperties":
        return "must not be empty", "declare at least one entry"
    if v == "not" or v == "oneOf":
        return "conflicting or missing fields", _ONE_OF_HINTS.get(error.absolute_path and str(error.absolute_path[0]), "see the schema for the allowed combinations")
    return error.message, "see schemas/andyc-model.schema.json"


_ONE_OF_HINTS = {
    "frames": "a rotation is one of {axis, angle}, {rpy} or {quaternion}",
    "dampers": "a damper acts on either 'speed: <coordinate>' or 'frame: <frame>', not both",
    "springs": "a spring has either 'length: <expression>' or 'between: [frameA, frameB]', not both",
}


# -- meaning ------------------------------------------------------------------

class _Builder:
    """Semantic checks and lowering to the Spec; collects every problem."""

    def __init__(self, data: dict, smap: SourceMap, sha: str):
        self.data = data
        self.smap = smap
        self.sha = sha
        self.problems: list[Diagnostic] = []
        self.warnings: list[Diagnostic] = []
        self.used: set[sp.Symbol] = set()

    def error(self, where, message, hint=""):
        self.problems.append(self.smap.diag(where, message, hint))

    # expression contexts --------------------------------------------------
    def expr(self, value, where, names: dict, context: str):
        try:
            result = parse(value, names)
        except ExpressionError as exc:
            self.error(where, str(exc), exc.hint + (f" ({context})" if "unknown name" in str(exc) else ""))
            return sp.Integer(0)
        self.used |= result.free_symbols
        return result

    def vector(self, values, where, names, context, n=3):
        return sp.Matrix([self.expr(v, where + (i,), names, context) for i, v in enumerate(values)])

    def constant(self, value, where):
        """An expression of parameters only, with its value at the defaults."""
        e = self.expr(value, where, self.param_names, "only parameters are allowed here")
        try:
            return e, float(e.subs(self.defaults))
        except (TypeError, ValueError):
            return e, math.nan

    # the build ------------------------------------------------------------
    def build(self) -> Spec:
        d = self.data
        self.check_names()
        self.parameters = {n: (sp.Symbol(f"p_{n}", real=True), float(v))
                           for n, v in (d.get("parameters") or {}).items()}
        self.inputs = {n: (sp.Symbol(f"u_{n}", real=True), float(v))
                       for n, v in (d.get("inputs") or {}).items()}
        self.param_names = {n: s for n, (s, _) in self.parameters.items()}
        self.defaults = {s: v for s, v in self.parameters.values()}
        coords = []
        for name, entry in d["coordinates"].items():
            entry = entry or {}
            where = ("coordinates", name)
            q = sp.Symbol(f"q_{name}", real=True)
            v = sp.Symbol(f"v_{name}", real=True)
            init, _ = self.constant(entry.get("initial", 0), where + ("initial",))
            vel, _ = self.constant(entry.get("velocity", 0), where + ("velocity",))
            coords.append(Coordinate(name, q, v, init, vel, where))
        self.coords = coords
        self.kin_names = {**self.param_names, **{c.name: c.q for c in coords}}
        self.load_names = {**self.kin_names, **{n: s for n, (s, _) in self.inputs.items()}}

        frames = self.frames()
        self.frame_names = {"world"} | {f.name for f in frames}
        extra_frames: list[Frame] = []
        bodies = [self.body(i, b, extra_frames) for i, b in enumerate(d.get("bodies") or [])]
        loads = [self.load_(kind, i, f, extra_frames)
                 for kind, section in (("force", "forces"), ("torque", "torques"))
                 for i, f in enumerate(d.get(section) or [])]
        dampers = [self.damper(i, x) for i, x in enumerate(d.get("dampers") or [])]
        springs = [self.spring(i, x) for i, x in enumerate(d.get("springs") or [])]
        potentials = [Potential(x["name"], self.expr(x["energy"], ("potentials", i, "energy"),
                                                     self.kin_names, "potentials use parameters, coordinates and t"),
                                ("potentials", i)) for i, x in enumerate(d.get("potentials") or [])]
        gravity = (self.vector(d["gravity"], ("gravity",), self.param_names, "only parameters are allowed here")
                   if "gravity" in d else sp.zeros(3, 1))
        if self.problems:
            raise SpecError(self.problems)
        for name, (sym, _) in self.parameters.items():
            if sym not in self.used:
                self.warnings.append(self.smap.diag(("parameters", name), f"parameter '{name}' is not used",
                                                    "remove it or use it in an expression"))
        return Spec(name=d["name"], description=d.get("description", ""), file=self.smap.file,
                    sha256=self.sha, source=self.smap, parameters=self.parameters, inputs=self.inputs,
                    coordinates=coords, gravity=gravity, frames=frames + extra_frames, bodies=bodies,
                    loads=loads, dampers=dampers, springs=springs, potentials=potentials,
                    warnings=self.warnings)

    def check_names(self):
        """Every name is unique across the model and not reserved."""
        d = self.data
        seen: dict[str, tuple] = {}
        entries = [(("parameters", n), n) for n in (d.get("parameters") or {})]
        entries += [(("inputs", n), n) for n in (d.get("inputs") or {})]
        entries += [(("coordinates", n), n) for n in d["coordinates"]]
        for section in ("frames",) + ELEMENT_SECTIONS:
            entries += [((section, i, "name"), x["name"]) for i, x in enumerate(d.get(section) or [])]
        for where, name in entries:
            if name in RESERVED or keyword.iskeyword(name):
                self.error(where, f"'{name}' is a reserved name", "choose another name (reserved: t, pi, world, "
                           "the function names and Python keywords)")
            elif name in seen:
                self.error(where, f"duplicate name '{name}' (first defined at line {self.smap.line(seen[name])})",
                           "names must be unique across parameters, inputs, coordinates, frames and elements; rename one")
            else:
                seen[name] = where

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
                           "frames form a tree rooted at 'world'; give one of these frames another parent")
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
        joints = [k for k in ("dh", "revolute", "prismatic") if k in f]
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
        return Frame(f["name"], f["parent"], tuple(steps), where)

    def axis(self, value, where) -> sp.Matrix:
        vec = AXES[value] if isinstance(value, str) else value
        norm = math.sqrt(sum(float(x) ** 2 for x in vec))
        if norm < 1e-12:
            self.error(where, "the axis is zero", "give a direction such as [0, 0, 1] or z")
            return sp.Matrix([0, 0, 1])
        m = sp.Matrix([sp.Rational(repr(float(x))) for x in vec])
        return m / sp.sqrt(sum(x ** 2 for x in m))

    def rotation(self, r, where) -> list:
        ctx = "rotation angles use parameters, coordinates and t"
        if "axis" in r:
            return [Rotate(self.axis(r["axis"], where + ("axis",)), self.expr(r["angle"], where + ("angle",), self.kin_names, ctx))]
        if "rpy" in r:
            roll, pitch, yaw = (self.expr(x, where + ("rpy", k), self.kin_names, ctx) for k, x in enumerate(r["rpy"]))
            # R = Rz(yaw) Ry(pitch) Rx(roll): applied left to right as z, then y, then x.
            return [Rotate(sp.Matrix([0, 0, 1]), yaw), Rotate(sp.Matrix([0, 1, 0]), pitch), Rotate(sp.Matrix([1, 0, 0]), roll)]
        w, x, y, z = (float(c) for c in r["quaternion"])
        norm = math.sqrt(w * w + x * x + y * y + z * z)
        if abs(norm - 1.0) > 1e-9:
            unit = ", ".join(f"{c / norm:.12g}" for c in (w, x, y, z)) if norm > 0 else "1, 0, 0, 0"
            self.error(where + ("quaternion",), f"quaternion [{w}, {x}, {y}, {z}] has norm {norm:.12g}, not 1",
                       f"use the unit quaternion [{unit}]")
            return []
        angle = 2 * math.atan2(math.sqrt(x * x + y * y + z * z), w)
        if angle == 0:
            return []
        s = math.sqrt(x * x + y * y + z * z)
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
        """A fixed child of `frame` at `offset` (frame axes); returns its name."""
        vec = self.vector(offset, where, self.param_names, "offsets use parameters only")
        if vec == sp.zeros(3, 1):
            return frame
        name = f"{owner}__{where[-1]}"
        extra.append(Frame(name, frame, (Translate(vec),), where, internal=True))
        return name

    def body(self, i, b, extra) -> Body:
        where = ("bodies", i)
        mass, m = self.constant(b["mass"], where + ("mass",))
        if not m > 0:
            self.error(where + ("mass",), f"mass must be positive, got {m:g}", "give a positive mass in kg")
        inertia = self.inertia(b.get("inertia", [0, 0, 0]), where + ("inertia",))
        frame = b["frame"]
        if self.frame_ref(frame, where + ("frame",)) and "com" in b:
            frame = self.offset_frame(b["name"], frame, b["com"], where + ("com",), extra)
        return Body(b["name"], frame, mass, inertia, where)

    def inertia(self, value, where) -> sp.Matrix:
        if len(value) == 3 and all(isinstance(r, list) for r in value):
            rows = [[self.constant(x, where + (i, j))[0] for j, x in enumerate(row)] for i, row in enumerate(value)]
            mat = sp.Matrix(rows)
        elif len(value) == 3:
            mat = sp.diag(*[self.constant(x, where + (i,))[0] for i, x in enumerate(value)])
        else:
            xx, yy, zz, xy, xz, yz = (self.constant(x, where + (i,))[0] for i, x in enumerate(value))
            mat = sp.Matrix([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        try:
            num = np.array(mat.subs(self.defaults), dtype=float)
        except (TypeError, ValueError):
            return mat
        if not np.allclose(num, num.T, rtol=1e-12, atol=1e-12 * max(1.0, abs(num).max())):
            i, j = np.unravel_index(np.argmax(abs(num - num.T)), num.shape)
            self.error(where, f"inertia is not symmetric: I[{i}][{j}] = {num[i, j]:g} but I[{j}][{i}] = {num[j, i]:g}",
                       "an inertia tensor is symmetric; make the off-diagonal pairs equal")
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

    def damper(self, i, x) -> Damper:
        where = ("dampers", i)
        coef, _ = self.constant(x["coefficient"], where + ("coefficient",))
        speed = x.get("speed")
        if speed is not None and speed not in {c.name for c in self.coords}:
            close = difflib.get_close_matches(speed, [c.name for c in self.coords], n=1)
            self.error(where + ("speed",), f"'{speed}' is not a coordinate",
                       (f"did you mean '{close[0]}'? " if close else "") + "coordinates: "
                       + ", ".join(c.name for c in self.coords))
        if "frame" in x:
            self.frame_ref(x["frame"], where + ("frame",))
        if "angular" in x and "frame" not in x:
            self.error(where + ("angular",), "'angular' goes with 'frame'", "remove it, or damp a frame")
        return Damper(x["name"], coef, x.get("law", "linear"), speed, x.get("frame"), bool(x.get("angular", False)), where)

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
