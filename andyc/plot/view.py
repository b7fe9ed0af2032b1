"""`andyc view`: a run as one self-contained HTML file that plays it in 3-D in a browser, offline.

The scene is drawn by MeshCat's viewer (the three.js viewer Drake and Pinocchio use), whose JavaScript
bundle the `meshcat` Python package ships (meshcat/viewer/dist/main.min.js, MIT, three.js inside): it
is inlined into the page, so the page needs no network and no server. The viewer's own animation
machinery (three.js AnimationMixer tracks, `set_animation`) moves the scene; the page adds a bar with
play/pause, a time scrubber, the speed, the time and the active flow, and the jumps as ticks on the
timeline.

- `view_data(run, fps, max_samples)`: what the page shows, as plain data (tests check it): the samples
  kept (`andyc.plot.animate.animation_samples`: real time at `fps`, at most `max_samples`: a long run
  is decimated), each logged frame's positions at them, the sticks (`animation_edges`), the leaf
  frames' paths, the flows and the events, the vertical axis, the ground (only where the model has
  one: `has_ground`) and whether the model is planar (then the camera looks square onto its plane).
- `view_html(run, ...)`, `write_view(run, out, ...)`: the page.

The frames' rotations are not logged (a run logs frame origins), so a stick joins a frame to its
parent and nothing shows a body's spin about its own stick.
"""

from __future__ import annotations

import html
import json
import re
import time
from importlib import resources
from pathlib import Path

import numpy as np

from andyc.outputs import write_atomic
from andyc.plot.animate import animation_samples
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


def view_data(run: Run, fps: int = 30, max_samples: int = MAX_SAMPLES) -> dict:
    """The page's data (see the module's docstring): 'model', 'time' (s, from the run's start),
    'frames' {name: [[x, y, z] per sample]}, 'edges' [[parent, child]], 'paths' {leaf: [[x, y, z]] at
    every sample kept}, 'flow_names', 'flow' (per sample), 'events' [[time, jump]], 'hybrid', 'up'
    (1: y, 2: z), 'planar', 'ground' (height along `up`, or None), 'centre' and 'extent' (m), 'fps'
    (samples kept per second of run time at real speed). ValueError if the run logged no frames."""
    if not run.frames:
        raise ValueError(f"{run.model}: the run logged no frames to view; re-run it with "
                         "`andyc sim MODEL.yaml --frames all --out RUN.h5`")
    samples = animation_samples(run, fps, max_samples)
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
        "edges": [list(e) for e in animation_edges(run)],
        "paths": {name: rounded(run.frames[name][samples]) for name in leaf_frames(run)},
        "flow_names": list(run.flow_names), "flow": [int(f) for f in run.flow[samples]],
        "events": [[float(ev["time"][k] - t[0]), run.jump_names[ev["jump"][k]]] for k in np.flatnonzero(inside)],
        "hybrid": is_hybrid(run), "up": int(view["up"]), "planar": bool(view["planar"]),
        "ground": view["ground_height"], "centre": [float(c) for c in (lo + hi) / 2],
        "extent": float(max(np.max(hi - lo), 1e-3)), "fps": (len(t) - 1) / duration if duration > 0 else 1.0,
    }


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


def write_view(run: Run, out, fps: int = 30, max_samples: int = MAX_SAMPLES) -> dict:
    """Write the page of `run` to `out`; returns {'samples' (kept), 'bytes', 'seconds'}."""
    start = time.perf_counter()
    data = view_data(run, fps, max_samples)
    text = view_html(data)
    with write_atomic(out) as tmp:
        Path(tmp).write_text(text, encoding="utf-8")
    return {"samples": len(data["time"]), "bytes": len(text.encode("utf-8")), "seconds": time.perf_counter() - start}
