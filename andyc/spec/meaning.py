"""What a model means, as a key: the parts of a model document that shape its equations.

A build is reused while this key is unchanged (andyc.pipeline.build). The key
is a hash of the document as data, so comments, key order, quoting and
whitespace do not count. Runtime data does not count either: parameter
defaults, numeric input defaults, how the model is run (simulate:, expect:), initial values (coordinates, speeds,
discrete states, the signals of ball, floating and nonholonomic links) and
the description, and the shapes a picture draws (`shape:` on frames and bodies). Those are written into the generated module's front file,
which is rewritten without touching the compiled equations (see
codegen.generate). Anything not listed here counts: a key is only left out
when it is certain that no equation depends on it.
"""

from __future__ import annotations

import hashlib
import json

# Keys of a frame's link whose values are initial values of its signals.
_LINK_INITIAL = {"ball": ("quaternion",), "floating": ("position", "quaternion"),
                 "nonholonomic": ("position", "quaternion")}


def meaning(data: dict) -> dict:
    """`data` (a validated model document) without its runtime data: defaults and initial values go,
    their names stay (they are the model's symbols), and so does the description.

    The order of parameters, inputs, coordinates, speeds and discrete states is their index in the
    generated arrays (p, u, x, d), so those mappings become lists of names, in order: the canonical
    JSON sorts the keys of a mapping, never the items of a list."""
    out = {k: v for k, v in data.items() if k not in ("description", "simulate", "expect")}
    if isinstance(data.get("parameters"), dict):
        out["parameters"] = list(data["parameters"])
    if isinstance(data.get("inputs"), dict):       # a number is a default; a text an expression that drives it
        out["inputs"] = [[n, v if isinstance(v, str) else None] for n, v in data["inputs"].items()]
    if isinstance(data.get("discrete"), dict):
        out["discrete"] = list(data["discrete"])
    for key, initial in (("coordinates", ("initial", "velocity")), ("speeds", ("initial",))):
        if isinstance(data.get(key), dict):
            out[key] = [[n, _without(v, initial)] for n, v in data[key].items()]
    if isinstance(data.get("frames"), list):
        out["frames"] = [_frame(f) for f in data["frames"]]
    if isinstance(data.get("bodies"), list):         # a body's shape: a picture (andyc.spec.shapes)
        out["bodies"] = [_without(b, ("shape",)) for b in data["bodies"]]
    return out


def meaning_sha256(data: dict) -> str:
    """sha256 of `meaning(data)`, written as canonical JSON (sorted keys; values the YAML reader gave)."""
    text = json.dumps(meaning(data), sort_keys=True, separators=(",", ":"), ensure_ascii=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()


def _without(value, keys):
    return {k: v for k, v in value.items() if k not in keys} if isinstance(value, dict) else value


def _frame(frame):
    if not isinstance(frame, dict):
        return frame
    return {k: (_without(v, _LINK_INITIAL[k]) if k in _LINK_INITIAL else v) for k, v in frame.items() if k != "shape"}
