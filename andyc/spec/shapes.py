"""Shapes: what `andyc view` draws on a frame, from a YAML `shape:` on a frame or a body, or a URDF
`<visual>`, as plain data (the same dict for both):

    {'frame': F, 'kind': 'box' | 'sphere' | 'cylinder' | 'capsule' | 'mesh',
     'size': [x, y, z] (box), 'radius', 'length', 'axis': [x, y, z] (cylinder, capsule: a unit vector),
     'file': absolute path, 'format': 'stl' | 'obj' | 'dae', 'scale': [x, y, z] (mesh),
     'xyz': [x, y, z], 'rpy': [roll, pitch, yaw] (its pose in F: R = Rz(yaw) Ry(pitch) Rx(roll)),
     'rgba': [r, g, b, a] or None (a mesh's own colours)}

A capsule's length is that of its cylinder, between the centres of its two half-spheres (as URDF's and
MuJoCo's). Sizes are expressions of parameters, taken at the defaults: a picture, not an equation, so no
shape changes what a model means (andyc.spec.meaning leaves `shape` out of the build key). A shape with
`collide: true` is also made into contacts (andyc.spec.geometry), which are in the document the key is
made of, so those count. A body's shape
sits on the body's frame. The shapes travel in DISPLAY (andyc.spec.display) into the module and run files.
"""

from __future__ import annotations

import math
import re
from pathlib import Path

from andyc.spec.frames import AXES
from andyc.spec.meshfiles import MESH_FORMATS, MeshRefused, checked_mesh
from andyc.spec.scope import Scope

KINDS = ("box", "sphere", "cylinder", "capsule", "mesh")


def build_shapes(data: dict, scope: Scope, model_file) -> list:
    """The shapes of the `shape:` keys of `frames:` and `bodies:` (see the module's docstring); each
    problem reported with its place."""
    folder = Path(model_file).resolve().parent
    out = []
    for section, frame_key in (("frames", "name"), ("bodies", "frame")):
        for i, item in enumerate(data.get(section) or []):
            if not isinstance(item, dict) or "shape" not in item:
                continue
            given = item["shape"]
            many = isinstance(given, list)
            for k, raw in enumerate(given if many else [given]):
                where = (section, i, "shape") + ((k,) if many else ())
                shape = _shape(raw, item[frame_key], where, scope, folder)
                if shape is not None:
                    out.append(shape)
    return out


def _shape(raw: dict, frame: str, where, scope: Scope, folder: Path) -> dict | None:
    kinds = [k for k in KINDS if k in raw]
    if len(kinds) != 1:
        scope.report.error(where, f"a shape is one of {', '.join(KINDS)}, got "
                           + (" and ".join(kinds) if kinds else "none"),
                           "write e.g. shape: {box: {size: [0.1, 0.2, 0.3]}} (several shapes: a list)")
        return None
    kind = kinds[0]
    spec = raw[kind]
    at = where + (kind,)
    shape = {"frame": frame, "kind": kind}
    if kind == "box":
        shape["size"] = [_positive(v, at + ("size", j), scope) for j, v in enumerate(spec["size"])]
    elif kind == "sphere":
        shape["radius"] = _positive(spec["radius"], at + ("radius",), scope)
    elif kind in ("cylinder", "capsule"):
        shape["radius"] = _positive(spec["radius"], at + ("radius",), scope)
        shape["length"] = _positive(spec["length"], at + ("length",), scope, zero=kind == "capsule")
        shape["axis"] = _unit_axis(spec.get("axis", "z"), at + ("axis",), scope)
    else:
        shape.update(mesh_file(spec["file"], at + ("file",), scope, folder))
        scale = spec.get("scale", 1.0)
        scale = [scale] * 3 if not isinstance(scale, list) else scale
        if not all(math.isfinite(s) and s > 0 for s in scale):
            scope.report.error(at + ("scale",), f"the scale {spec.get('scale')} is not positive",
                               "give one factor > 0 or three (x, y, z), e.g. 0.001 for a file in millimetres")
        shape["scale"] = [float(s) for s in scale]
    shape["xyz"] = [_number(v, where + ("xyz", j), scope) for j, v in enumerate(raw.get("xyz", [0, 0, 0]))]
    shape["rpy"] = [_number(v, where + ("rpy", j), scope) for j, v in enumerate(raw.get("rpy", [0, 0, 0]))]
    shape["rgba"] = (colour(raw["colour"], where + ("colour",), scope) if "colour" in raw
                     else None if kind == "mesh" else DEFAULT_RGBA)
    return shape


DEFAULT_RGBA = [0.6, 0.62, 0.66, 1.0]      # a primitive's colour unless it says one: a light steel grey


def mesh_file(name: str, where, scope: Scope, folder: Path) -> dict:
    """{'file': its resolved path, 'format'} of a mesh file named relative to the model file's folder, which
    it must resolve inside (andyc.spec.meshfiles: the rule); reported otherwise."""
    if MESH_FORMATS.get(Path(name).suffix.lower()) is None:
        scope.report.error(where, f"mesh file '{name}' is not STL, OBJ or DAE (by its suffix)",
                           "give a .stl, .obj or .dae file (convert others, e.g. with meshlab or trimesh)")
        return {"file": str(folder / name), "format": ""}
    try:
        path, fmt = checked_mesh(folder / name, [folder])
    except MeshRefused as why:
        scope.report.error(where, f"mesh file '{name}' {why}",
                           "give a regular mesh file inside the model file's folder (a link may point only "
                           "inside it too)")
        return {"file": str(folder / name), "format": ""}
    return {"file": str(path), "format": fmt}


_HEX = re.compile(r"#(?:[0-9a-fA-F]{6}|[0-9a-fA-F]{8})")


def colour(value, where, scope: Scope) -> list:
    """[r, g, b, a] in 0..1 from a colour name or 3 or 4 numbers; reported when it is neither."""
    if isinstance(value, str) and _HEX.fullmatch(value):     # '#rrggbb' or '#rrggbbaa': no library needed
        digits = value[1:]
        return [int(digits[i:i + 2], 16) / 255 for i in range(0, len(digits), 2)] + ([1.0] if len(digits) == 6 else [])
    if isinstance(value, str):
        from matplotlib.colors import to_rgba      # its CSS4 and tab: names; imported only for a name

        try:
            return [float(c) for c in to_rgba(value)]
        except ValueError:
            scope.report.error(where, f"'{value}' is not a colour name",
                               "give a CSS colour name (red, steelblue, ...), tab:blue, a '#rrggbb' or [r, g, b, a] "
                               "in 0..1")
            return list(DEFAULT_RGBA)
    rgba = [float(c) for c in value] + ([1.0] if len(value) == 3 else [])
    if not all(0.0 <= c <= 1.0 for c in rgba):
        scope.report.error(where, f"the colour {value} has a component outside 0..1",
                           "give [r, g, b] or [r, g, b, a] each in 0..1")
        return list(DEFAULT_RGBA)
    return rgba


def _number(value, where, scope: Scope) -> float | None:
    """The value of an expression of parameters at their defaults; None once a problem is reported."""
    before = len(scope.report.problems)
    _, number = scope.constant(value, where)
    if len(scope.report.problems) > before:
        return None
    if not math.isfinite(number):
        scope.report.error(where, f"{value!r} is not a finite number at the parameters' defaults",
                           "a shape's sizes and pose are expressions of parameters")
        return None
    return number


def _positive(value, where, scope: Scope, zero: bool = False) -> float | None:
    number = _number(value, where, scope)
    if number is None:
        return None
    if number < 0 or (number == 0 and not zero):
        scope.report.error(where, f"{value!r} = {number:g} is not {'>= 0' if zero else '> 0'}",
                           "a shape's sizes are lengths in metres")
        return None
    return number


def _unit_axis(value, where, scope: Scope) -> list:
    vec = [float(v) for v in (AXES[value] if isinstance(value, str) else value)]
    norm = math.hypot(*vec)                 # (no overflow for huge entries)
    if not (math.isfinite(norm) and norm > 1e-12):
        scope.report.error(where, f"the axis {value} is not a direction", "give x, y, z, -x, ... or three numbers")
        return [0.0, 0.0, 1.0]
    return [v / norm for v in vec]


def urdf_shapes(visuals: list) -> list:
    """The shapes of a URDF's `<visual>` elements (Spec.visuals, as andyc.spec.urdflinks collects them: the
    mesh files resolved as the importer resolves them, the origin, the material's colour): the same dicts as
    a YAML `shape:`. URDF cylinders and capsules lie along z."""
    out = []
    for v in visuals:
        shape = {"frame": v["frame"], "kind": v["geometry"]}
        if v["geometry"] == "box":
            shape["size"] = v.get("size")
            if not (isinstance(shape["size"], list) and len(shape["size"]) == 3):
                continue            # the URDF reader reports a box without three sizes
        elif v["geometry"] in ("sphere", "cylinder", "capsule"):
            if not isinstance(v.get("radius"), float) or (v["geometry"] != "sphere"
                                                          and not isinstance(v.get("length"), float)):
                continue            # the URDF reader reports a shape without its sizes
            shape["radius"] = v["radius"]
            if v["geometry"] != "sphere":
                shape.update(length=v["length"], axis=[0.0, 0.0, 1.0])
        elif v["geometry"] == "mesh":
            if not v.get("format"):
                continue            # refused by the importer (andyc.spec.meshfiles), which said why in a warning
            shape.update(file=v["filename"], format=v["format"], scale=list(v["scale"]))
        else:
            continue
        shape["xyz"], shape["rpy"] = list(v["origin"]["xyz"]), list(v["origin"]["rpy"])
        shape["rgba"] = v.get("rgba") or (None if v["geometry"] == "mesh" else list(DEFAULT_RGBA))
        out.append(shape)
    return out
