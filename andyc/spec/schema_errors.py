"""A model's schema, and its errors in the loader's words: `path: what is wrong; how to write it`.

jsonschema reports what failed (a 'oneOf', a 'type', a pattern); the functions here say it as a user reads
it: which field, what was written, what to write instead. A typo in a field name is one problem, not also a
missing field.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import jsonschema

from andyc.errors import Diagnostic
from andyc.spec.suggest import did_you_mean
from andyc.spec.yamlpos import SourceMap

SCHEMA_PATH = Path(__file__).resolve().parents[1] / "schemas" / "andyc-model.schema.json"


def schema() -> dict:
    return json.loads(SCHEMA_PATH.read_text())


@functools.lru_cache(maxsize=1)
def _defs() -> dict:
    """The schema's $defs, read once (to tell which definition an error is in)."""
    return schema()["$defs"]


def schema_problems(data, smap: SourceMap) -> list[Diagnostic]:
    """Every way `data` breaks the schema, located through `smap`, in line order."""
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
            out.append((path + (key,), f"unknown field '{key}'",
                        did_you_mean(key, allowed) + "allowed fields: " + ", ".join(allowed)))
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


# How a JSON type is called in a message: 'expected a mapping, got ...'.
_JSON_TYPE_WORDS = {"object": "a mapping", "array": "a list", "string": "a name or text", "number": "a number",
                    "boolean": "true or false", "integer": "a whole number"}
_TYPE_HINTS = {"object": "write 'key: value' entries, or {} for none",
               "array": "write a list: entries '- item', one a line, or [a, b, ...]",
               "string": "write a name", "number": "write a number such as 1.5",
               "boolean": "write true or false", "integer": "write a whole number"}
# A list of fixed length, by its field: what its entries are.
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
        return f"expected {' or '.join(_JSON_TYPE_WORDS.get(w, w) for w in want)}, got {_describe(inst)}", how
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
