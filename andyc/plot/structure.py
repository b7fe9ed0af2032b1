"""A model's structure as plain data, for `andyc graph` (andyc.plot.graph draws it) and for tests.

- `frame_tree(spec)`: ANDY's frame hierarchy (its Fig. 5): a node per frame of the model file (and
  `world`), an edge per link from its parent, labelled with the link's kind (fixed, dh, revolute,
  prismatic, ball, floating, nonholonomic; a fixed link whose translation or rotation depends on
  coordinates or t is 'moving') and its motion; the bodies and elements attached where they sit
  (an element on a COM or point offset, a frame andyc makes, sits on the user's frame it hangs from).
- `automaton(spec)`: the hybrid automaton (ANDY Fig. 8, eq. 16-19): a node per flow with its
  active constraints, an edge per jump with its guard, direction, conditions, resets and impact as
  the model file writes them.

Functions of the Spec only: nothing is derived or drawn.
"""

from __future__ import annotations

import sympy as sp

from andyc.spec.expressions import TIME
from andyc.spec.model import EITHER, FALLING, RISING, Nonholonomic, Rotate, Translate

DIRECTIONS = {FALLING: "falling", RISING: "rising", EITHER: "either"}


def frame_tree(spec) -> dict:
    """{'nodes': [{'name', 'parent', 'attached': [text]}], 'edges': [{'parent', 'child', 'kind',
    'label'}]}: 'world' first, then the frames of the model in the Spec's order (parents before
    children); internal frames (COM and point offsets) are left out and what sits on them is
    attached to their nearest user frame above. 'attached' holds 'body NAME', 'force NAME',
    'torque NAME', 'damper NAME', 'spring NAME' (on both frames of a spring between frames) and
    'constraint NAME' (on each frame a constraint's rows use)."""
    frames = [f for f in spec.frames if not f.internal]
    parent_of = {f.name: f.parent for f in spec.frames}
    internal = {f.name for f in spec.frames if f.internal}

    def owner(name):
        """The user frame an element on `name` sits on."""
        while name in internal:
            name = parent_of[name]
        return name

    attached = {"world": []} | {f.name: [] for f in frames}

    def attach(frame, text):
        if frame is not None and owner(frame) in attached and text not in attached[owner(frame)]:
            attached[owner(frame)].append(text)

    for b in spec.bodies:
        attach(b.frame, f"body {b.name}")
    for load in spec.loads:
        attach(load.frame, f"{load.kind} {load.name}")
    for d in spec.dampers:
        attach(d.frame, f"damper {d.name}")
    for s in spec.springs:
        for frame in s.between or ():
            attach(frame, f"spring {s.name}")
    for c in spec.constraints:
        for quantity in c.quantities.values():
            attach(quantity.frame, f"constraint {c.name}")
    coordinates = {c.q for c in spec.coordinates}
    names = _names(spec)
    nodes = [{"name": "world", "parent": None, "attached": attached["world"]}]
    nodes += [{"name": f.name, "parent": f.parent, "attached": attached[f.name]} for f in frames]
    edges = [{"parent": owner(f.parent), "child": f.name, **_link(f, coordinates, names)} for f in frames]
    return {"nodes": nodes, "edges": edges, "contacts": [c.name for c in spec.contacts]}


def _names(spec) -> dict:
    """{symbol: the symbol named as the model file names it} (andyc's symbols carry prefixes: q_qi1)."""
    named = {c.q: c.name for c in spec.coordinates} | {s.symbol: s.name for s in spec.signals}
    named |= {symbol: name for name, (symbol, _) in spec.parameters.items()}
    named |= {symbol: name for name, (symbol, _) in spec.inputs.items()}
    return {symbol: sp.Symbol(name) for symbol, name in named.items()}


def _link(frame, coordinates: set, names: dict) -> dict:
    """{'kind', 'label'} of a frame's link: its joint and what moves it."""
    steps = frame.transforms

    def _text(expr):
        return _plain(sp.sympify(expr).xreplace(names))

    def _vector(v):
        return "[" + ", ".join(_text(x) for x in v) + "]"

    def _along(v):
        """A prismatic joint's motion: the one non-zero component of axis * value, or the vector."""
        nonzero = [x for x in v if x != 0]
        return _text(nonzero[0]) if len(nonzero) == 1 else _vector(v)

    kind = frame.joint
    step = _last(steps, {"revolute": Rotate, "prismatic": Translate}.get(kind, ()))
    if kind in ("revolute", "prismatic") and step is None:      # a URDF joint locked at zero (urdf: {lock})
        return {"kind": "fixed", "label": f"{kind}, locked"}
    if kind == "revolute":
        return {"kind": kind, "label": f"revolute {_text(step.angle)}"}
    if kind == "prismatic":
        return {"kind": kind, "label": f"prismatic {_along(step.vector)}"}
    if kind == "dh":
        theta = next((s.angle for s in steps if isinstance(s, Rotate) and list(s.axis) == [0, 0, 1]), 0)
        return {"kind": kind, "label": f"DH θ = {_text(theta)}"}
    if kind in ("ball", "floating", "nonholonomic"):
        link = _last(steps, Nonholonomic)
        parts = [kind]
        if link is not None and link.quaternion:
            base = str(names.get(link.quaternion[0], link.quaternion[0]))[:-3]
            parts.append(f"(quaternion {base}_qw..qz)")
        return {"kind": kind, "label": " ".join(parts)}
    moving = [s for s in steps if _symbols(s) & (coordinates | {TIME})]
    if not moving:
        return {"kind": "fixed", "label": "fixed"}
    text = ", ".join(f"translation {_vector(s.vector)}" if isinstance(s, Translate) else f"rotation {_text(s.angle)}"
                     for s in moving)
    return {"kind": "moving", "label": text}


def _last(steps, kind):
    return next((s for s in reversed(steps) if isinstance(s, kind)), None)


def _symbols(step) -> set:
    value = step.vector if isinstance(step, Translate) else step.angle
    return set(getattr(value, "free_symbols", ()))


def _plain(expr) -> str:
    return str(expr).replace("**", "^")


def automaton(spec) -> dict:
    """{'nodes': [{'name', 'constraints', 'initial'}], 'edges': [{'name', 'source', 'target', 'guard',
    'direction', 'enabled', 'reset', 'impact'}], 'contacts': [name]}: the flows in the model's order, the jumps in
    the order of the model file (texts as the model file writes them, Jump.text), and the contacts, which open and
    close within every flow (their own jumps are not edges: andyc.spec.contacts)."""
    nodes = [{"name": f.name, "constraints": list(f.constraints), "initial": k == spec.initial_flow}
             for k, f in enumerate(spec.flows)]
    edges = []
    for j in spec.jumps:
        if j.kind:
            continue
        text = j.text or {}
        edges.append({"name": j.name, "source": j.source, "target": j.target,
                      "guard": str(text.get("guard", _plain(j.guard))), "direction": DIRECTIONS[j.direction],
                      "enabled": _listed(text.get("enabled")), "reset": text.get("reset") or {},
                      "impact": _impact(text.get("impact", j.impact))})
    return {"nodes": nodes, "edges": edges, "contacts": [c.name for c in spec.contacts]}


def _listed(value) -> list:
    if value is None:
        return []
    return [str(v) for v in value] if isinstance(value, list) else [str(value)]


def _impact(value) -> str:
    """'none', 'plastic' or 'restitution e' (with the constraints named, if any)."""
    if isinstance(value, dict):
        text = f"restitution {value.get('restitution', 0)}"
        return text + (f" on {', '.join(map(str, value['constraints']))}" if value.get("constraints") else "")
    return str(value or "none")
