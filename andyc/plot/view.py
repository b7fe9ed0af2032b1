"""`andyc view`: a run as one self-contained HTML file that plays it in 3-D in a browser, offline.

The scene is drawn by MeshCat's viewer (the three.js viewer Drake and Pinocchio use), whose JavaScript
bundle the `meshcat` Python package ships (meshcat/viewer/dist/main.min.js, MIT, three.js inside): it
is inlined into the page, so the page needs no network and no server. The viewer's own animation
machinery (three.js AnimationMixer tracks, `set_animation`) moves the scene; the page adds a bar with
play/pause, a time scrubber, the speed, the time and the active flow, and the jumps as ticks on the
timeline.

- `view_data(run, fps, max_samples, follow, trails)`: what the page shows, as plain data (tests check
  it): the samples kept (`andyc.plot.animate.animation_samples`: real time at `fps`, at most
  `max_samples`: a long run is decimated), each logged frame's position at them and, for the frames
  that carry shapes, its rotation; the shapes of the model
  (andyc.spec.shapes, from the run file's display record) with their mesh files' bytes in base64;
  the sticks (`animation_edges`) of the frames without a shape; the frames that leave a trail (the
  leaf frames unless `trails` names them); the frame the camera follows; the flows and the events,
  the vertical axis, the ground (only where the model has one: `has_ground`) and whether the model
  is planar (then the camera looks square onto its plane).
- `view_html(run, ...)`, `write_view(run, out, ...)`: the page.

A shape is a three.js object (box, sphere, cylinder, a capsule as a cylinder and two spheres: the
bundle's three.js r132 has no capsule; a mesh as MeshCat's `_meshfile_geometry`, or `_meshfile_object`
to keep a DAE's or OBJ's own colours) under a node per frame that the animation tracks move by the
frame's logged position and rotation; its pose in the frame (xyz, rpy) is that node's child's fixed
transform.
"""

from __future__ import annotations

import base64
import hashlib
import html
import json
import re
import time
from importlib import resources
from pathlib import Path

import numpy as np

from andyc.outputs import write_atomic
from andyc.plot.animate import animation_samples
from andyc.plot.meshes import FACE_BUDGET, simplified
from andyc.plot.scene import animation_edges, animation_view, is_hybrid, leaf_frames
from andyc.runtime.run import Run

MAX_SAMPLES = 3000          # samples kept at most: a 12 s run at 30 fps keeps 361; a long run is decimated
DIGITS = 5                  # significant digits of the positions written into the page


def meshcat_bundle() -> str:
    """The text of MeshCat's viewer bundle (three.js inside), from the installed `meshcat` package;
    ImportError with the fix when it is not installed."""
    try:
        import meshcat
    except ImportError:
        raise ImportError("andyc view needs the meshcat package (its three.js viewer is inlined into the page); "
                          "install it with `pip install 'andyc[view]'` (or `pip install meshcat`)") from None
    path = Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"
    if not path.exists():
        raise ImportError(f"the meshcat package has no viewer bundle at {path}; reinstall it (pip install meshcat)")
    return path.read_text(encoding="utf-8")


def view_data(run: Run, fps: int = 30, max_samples: int = MAX_SAMPLES, follow: str | None = None,
              trails=None, face_budget: int | None = FACE_BUDGET) -> dict:
    """The page's data (see the module's docstring): 'model', 'time' (s, from the run's start),
    'frames' {name: [[x, y, z] per sample]}, 'rotations' {name: [[x, y, z, w] per sample]} (three.js's
    order) for the frames with shapes, 'shapes' [shape with 'mesh': index into
    'meshes' [{'format', 'base64', 'faces'}]] (each simplified to at most `face_budget` faces; None: full
    resolution), 'edges' [[parent, child]] (the sticks of the frames without a
    shape), 'trails' [frame], 'follow' (a frame or None), 'flow_names', 'flow' (per sample), 'events'
    [[time, jump]], 'hybrid', 'up' (1: y, 2: z), 'planar', 'ground' (height along `up`, or None), 'planes'
    (`ground_planes`: the contacts' ground planes or slopes, drawn),
    'centre' and 'extent' (m), 'fps' (samples kept per second of run time at real speed), 'missing'
    [what is not drawn, and why]. ValueError if the run logged no frames, or `follow` or `trails` names a
    frame it did not log."""
    if not run.frames:
        raise ValueError(f"{run.model}: the run logged no frames to view; re-run it with "
                         "`andyc sim MODEL.yaml --frames all --out RUN.h5`")
    trails = leaf_frames(run) if trails is None else list(trails)
    for name in ([follow] if follow else []) + trails:
        if name not in run.frames:
            raise ValueError(f"{run.model}: the run logged no frame '{name}'; logged: {', '.join(run.frames)}")
    samples = animation_samples(run, fps, max_samples)
    shapes, meshes, missing = _shapes(run, face_budget)
    shaped = {s["frame"] for s in shapes}
    turning = sorted(shaped - {"world"})
    for name in turning:
        if name not in run.frame_rotations:
            raise ValueError(f"{run.model}: the run file has no rotation of frame '{name}' (written before "
                             "andyc logged rotations); re-run it with `andyc sim MODEL.yaml --frames all`")
    view = animation_view(run)
    t = run.time[samples]
    xyz = np.concatenate([np.zeros((1, 3))] + [p[samples] for p in run.frames.values()])
    lo, hi = np.nanmin(xyz, axis=0), np.nanmax(xyz, axis=0)
    rounded = lambda a: [[float(f"{v:.{DIGITS}g}") for v in row] for row in a]  # noqa: E731
    ev = run.events
    inside = (ev["time"] >= run.time[0]) & (ev["time"] <= run.time[-1])
    duration = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    return {
        "model": run.model, "time": [float(f"{v - t[0]:.9g}") for v in t],
        "frames": {name: rounded(p[samples]) for name, p in run.frames.items()},
        "rotations": {name: rounded(run.frame_rotations[name][samples][:, [1, 2, 3, 0]]) for name in turning},
        "shapes": shapes, "meshes": meshes, "missing": missing,
        "edges": [list(e) for e in animation_edges(run) if e[1] not in shaped],
        "trails": trails, "follow": follow,
        "flow_names": list(run.flow_names), "flow": [int(f) for f in run.flow[samples]],
        "events": [[float(ev["time"][k] - t[0]), run.jump_names[ev["jump"][k]]] for k in np.flatnonzero(inside)],
        "hybrid": is_hybrid(run), "up": int(view["up"]), "planar": bool(view["planar"]),
        "ground": view["ground_height"], "centre": [float(c) for c in (lo + hi) / 2],
        "extent": float(max(np.max(hi - lo), 1e-3)), "fps": (len(t) - 1) / duration if duration > 0 else 1.0,
        "planes": ground_planes(run), "forces": contact_forces(run, samples),
    }


def contact_forces(run: Run, samples) -> dict:
    """{'contacts': [{'name', 'foot' [[x, y, z] per sample], 'normal' [[fx, fy, fz]], 'friction' [[...]]}],
    'scale' (m per N)}: for each contact whose gap is a plane (display's 'contacts') on a logged frame, its
    normal force along the plane's normal and its friction along its tangents (Run.normal_forces,
    friction_forces, friction_forces_2: 0 while open), in world, at the samples kept; the arrows' foot is the
    frame's origin projected on the plane (the contact point of a point or a sphere). The scale makes the
    largest force of the run 0.3 of the scene's size."""
    planes = {c["name"]: c for c in plane_contacts(run)}
    out = []
    if run.contact_names:
        normal, f1, f2 = run.normal_forces[samples], run.friction_forces[samples], run.friction_forces_2[samples]
    for i, name in enumerate(run.contact_names):
        c = planes.get(name)
        if c is None or c["frame"] not in run.frames:
            continue
        n = np.array(c["normal"], float)
        p = run.frames[c["frame"]][samples]
        foot = p - (p @ n + c["offset"])[:, None] * n
        tangents = [np.array(t, float) for t in c.get("tangents", [])]
        friction = np.zeros_like(p)
        for t, f in zip(tangents, (f1[:, i], f2[:, i])):
            friction += f[:, None] * t
        out.append({"name": name, "foot": foot, "normal": normal[:, i][:, None] * n, "friction": friction})
    largest = max([float(np.nanmax(np.linalg.norm(c[k], axis=1), initial=0.0)) for c in out
                   for k in ("normal", "friction")] + [0.0])
    xyz = np.concatenate([np.zeros((1, 3))] + [q[samples] for q in run.frames.values()])
    extent = max(float(np.max(np.nanmax(xyz, axis=0) - np.nanmin(xyz, axis=0))), 1e-3)
    rounded = lambda a: [[float(f"{v:.{DIGITS}g}") for v in row] for row in np.nan_to_num(a)]  # noqa: E731
    return {"contacts": [{"name": c["name"], **{k: rounded(c[k]) for k in ("foot", "normal", "friction")}}
                         for c in out],
            "scale": 0.3 * extent / largest if largest > 0 else 0.0}


def plane_contacts(run: Run) -> list:
    """The run file's display record's 'contacts' (andyc.spec.display.contact_planes), each read back as
    {'name', 'frame', 'normal' (unit), 'offset', 'tangents'} of finite numbers; an entry that is not so (a run
    file written by hand, or damaged) is left out: the page then draws no ground or arrow for it."""
    raw = (run.display or {}).get("contacts", [])
    out = []
    for c in raw if isinstance(raw, list) else []:
        try:
            n = np.array(c["normal"], float)
            offset = float(c["offset"])
            tangents = [np.array(t, float) for t in c.get("tangents", [])][:2]
            name, frame = c["name"], c["frame"]
        except (TypeError, ValueError, KeyError, AttributeError):
            continue
        if not (isinstance(name, str) and isinstance(frame, str) and n.shape == (3,) and np.all(np.isfinite(n))
                and np.isfinite(offset) and abs(np.linalg.norm(n) - 1) < 1e-6
                and all(t.shape == (3,) and np.all(np.isfinite(t)) for t in tangents)):
            continue
        out.append({"name": name, "frame": frame, "normal": n, "offset": offset, "tangents": tangents})
    return out


def ground_planes(run: Run) -> list:
    """[{'normal', 'offset'}]: the model's `ground:` plane when it has one (the run file's display record's
    'plane'); else the distinct planes normal . p + offset = 0 of the run's contacts (its 'contacts':
    andyc.spec.display.contact_planes; none in a run file older than it), to 6 digits: a quadruped's four
    feet on one ground are one plane. (A sphere's contact plane is its centre's, the ground lifted by its
    radius: the ground itself, where the model says it, is the one to draw.)"""
    plane = (run.display or {}).get("plane")
    try:
        normal, offset = np.array(plane["normal"], float), float(plane["offset"])
        if normal.shape == (3,) and np.all(np.isfinite(normal)) and np.isfinite(offset) and \
                abs(np.linalg.norm(normal) - 1) < 1e-6:
            return [{"normal": [float(x) for x in normal], "offset": offset}]
    except (TypeError, ValueError, KeyError, IndexError):
        pass            # none, or damaged: the contacts' planes
    planes = {}
    for c in plane_contacts(run):
        key = tuple(round(float(x), 6) + 0.0 for x in c["normal"]) + (round(float(c["offset"]), 6) + 0.0,)
        planes.setdefault(key, {"normal": list(key[:3]), "offset": key[3]})
    return list(planes.values())


def _shapes(run: Run, face_budget: int | None = FACE_BUDGET) -> tuple[list, list, list]:
    """(shapes, meshes, missing): the run's shapes on the frames it logged (and 'world'), each mesh as an
    index into `meshes` [{'format', 'base64'}] (its file's bytes, from the run file or the file), and
    what is not drawn and why."""
    # A mesh is stored once per distinct content (its format and bytes), not per file nor per shape: a robot's
    # left and right legs, or two copies of one file, share one entry in the page.
    shapes, meshes, index, missing, by_content = [], [], {}, [], {}
    for shape in run.display.get("shapes", []):
        if shape["frame"] != "world" and shape["frame"] not in run.frames:
            missing.append(f"a {shape['kind']} on frame '{shape['frame']}', which the run did not log")
            continue
        shape = dict(shape)
        if shape["kind"] == "mesh":
            file = shape.pop("file")
            if file not in index:
                data = run.mesh_bytes(file)
                if data is None:
                    missing.append(f"the mesh {file} (in neither the run file nor on disk)")
                    continue
                key = (shape["format"], hashlib.sha256(data).hexdigest())
                if key not in by_content:
                    by_content[key] = len(meshes)
                    data, fmt, faces = simplified(data, shape["format"], face_budget)
                    meshes.append({"format": fmt, "base64": base64.b64encode(data).decode("ascii"),
                                   "faces": faces})
                index[file] = by_content[key]
            shape["mesh"] = index[file]
        shapes.append(shape)
    return shapes, meshes, missing


def view_html(data: dict) -> str:
    """The page of `data` (`view_data`): MeshCat's bundle, the data as JSON and the page's script,
    put into andyc/templates/view.html in one pass (no inserted text is searched again)."""
    page = resources.files("andyc").joinpath("templates/view.html").read_text(encoding="utf-8")
    # Inside <script>, no '</' may end the element early. The data's text (names are identifiers today) has
    # every '<' as the JSON escape \u003c all the same, so that no '</script' nor '<!--' can ever form in it;
    # the title is escaped too.
    script = lambda text: text.replace("</", "<\\/")  # noqa: E731
    data_json = json.dumps(data, separators=(",", ":"), allow_nan=False).replace("<", "\\u003c")
    parts = {"TITLE": html.escape(f"{data['model']}: andyc view"), "MESHCAT": script(meshcat_bundle()),
             "DATA": data_json}
    return re.sub(r"\{\{(TITLE|MESHCAT|DATA)\}\}", lambda m: parts[m.group(1)], page)


def write_view(run: Run, out, fps: int = 30, max_samples: int = MAX_SAMPLES, follow: str | None = None,
               trails=None, face_budget: int | None = FACE_BUDGET) -> dict:
    """Write the page of `run` to `out`; returns {'samples' (kept), 'shapes', 'bytes', 'seconds', 'missing'}."""
    start = time.perf_counter()
    data = view_data(run, fps, max_samples, follow, trails, face_budget)
    text = view_html(data)
    with write_atomic(out) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return {"samples": len(data["time"]), "shapes": len(data["shapes"]), "bytes": len(text.encode("utf-8")),
            "seconds": time.perf_counter() - start, "missing": data["missing"]}
