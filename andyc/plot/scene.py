"""What the plots of a run share about its frames and flows: which logged frames are joined by a stick
(`stick_edges`, `world_links`, `animation_edges`, `leaf_frames`), the world plane the frames spread in
(`stick_plane`), the plane of a planar model (`frame_plane`), the fixed view of the animation (`animation_view`: limits, whether the model is
planar, the camera), the colours of the sticks and traces (`leaf_colours`, `branch_colours`), whether
to draw the ground (`has_ground`), and whether a run is hybrid (`is_hybrid`).

Functions of the run only: they draw nothing.
"""

from __future__ import annotations

import numpy as np

from andyc.runtime.run import Run


def is_hybrid(run: Run) -> bool:
    """Whether the run has more than one flow or any jump (and so a flow panel, and the flow in the
    animation's title)."""
    return len(run.flow_names) > 1 or len(run.events["time"]) > 0


# -- which frames connect --------------------------------------------------------------------------

def stick_edges(run: Run) -> list:
    """[(parent, child)] for each logged frame whose parent is logged too (not 'world')."""
    return [(parent, child) for child, parent in run.frame_parents.items()
            if child in run.frames and parent in run.frames]


def world_links(run: Run) -> list:
    """[('world', child)] for each logged frame hung from the world at a fixed, non-zero distance
    from its origin (a link turning about a world pivot, as bar 1 of the swing bar), which
    `stick_edges` leaves out; a floating base (the walker's hip) moves away from the origin."""
    links = []
    for child, parent in run.frame_parents.items():
        if parent == "world" and child in run.frames:
            r = np.linalg.norm(run.frames[child], axis=1)
            if np.nanmax(r) > 1e-9 and np.nanmax(r) - np.nanmin(r) <= 1e-6 * np.nanmax(r):
                links.append(("world", child))
    return links


def animation_edges(run: Run) -> list:
    """The sticks of the animation: `world_links`, then `stick_edges`."""
    return world_links(run) + stick_edges(run)


def leaf_frames(run: Run) -> list:
    """The logged frames that are no logged frame's parent (end effectors, feet): they leave a trace."""
    parents = {parent for parent, _ in stick_edges(run)}
    return [name for name in run.frames if name not in parents]


# -- planes, views and the ground ------------------------------------------------------------------

def stick_plane(run: Run) -> tuple:
    """The two world axes (i, j) along which the frames spread most, in axis order (x-y for a
    planar model in x-y; for a 3-D model the plane in which the frames move most); j is drawn
    upwards."""
    xyz = np.concatenate([run.frames[name] for edge in stick_edges(run) for name in edge])
    spread = np.nanmax(xyz, axis=0) - np.nanmin(xyz, axis=0)
    spread = np.where(np.isfinite(spread), spread, 0.0)
    i, j = sorted(np.argsort(-spread, kind="stable")[:2])
    return int(i), int(j)


def frame_plane(run: Run) -> tuple | None:
    """(i, j), the world axes of the plane every logged frame moves in, when all keep one world
    coordinate at one value over the whole run (a planar model: z for the shipped ones); else None."""
    if not run.frames:
        return None
    xyz = np.concatenate(list(run.frames.values()))
    extent = max(float(np.nanmax(np.nanmax(xyz, axis=0) - np.nanmin(xyz, axis=0))), 1e-3)
    for k in (2, 1, 0):
        if np.nanmax(xyz[:, k]) - np.nanmin(xyz[:, k]) <= 1e-9 * extent:
            return tuple(a for a in range(3) if a != k)
    return None


def has_ground(run: Run, up: int) -> float | None:
    """The height of the ground along world axis `up` (the one drawn upwards), where the run's model
    has a ground there (`Run.display['ground']`, from andyc.spec.display: a constraint or a guard
    holding a frame at a height, against gravity); None where it has none, or the run file does not
    say (it predates andyc's display data), so nothing is shaded that the model does not define."""
    g = (run.display or {}).get("ground")
    if not isinstance(g, dict) or g.get("axis") != up:
        return None
    return float(g.get("height", 0.0))


def animation_view(run: Run) -> dict:
    """The fixed scene: limits around all frames over the whole run and the world origin, with
    one scale along all axes (box aspect = spans), the vertical axis ('y' for a model whose frames
    all lie in the world x-y plane, as the planar models have gravity along -y, else 'z'), the
    camera, and whether to draw the ground ('ground', at 'ground_height' along the vertical axis:
    `has_ground`)."""
    xyz = np.concatenate([np.zeros((1, 3))] + [p for p in run.frames.values()])
    lo, hi = np.nanmin(xyz, axis=0), np.nanmax(xyz, axis=0)
    extent = max(float(np.max(hi - lo)), 1e-3)
    planar = bool(np.nanmax(np.abs(xyz[:, 2])) <= 1e-9 * extent)
    up = 1 if planar else 2
    span = np.maximum(hi - lo, 0.04 * extent) + 0.1 * extent
    centre = (lo + hi) / 2
    limits = [(c - s / 2, c + s / 2) for c, s in zip(centre, span)]
    # planar: look at the x-y plane almost square on (from +z, a little from above and from the
    # right); 3-D: z up, matplotlib's usual oblique view
    camera = dict(vertical_axis="y", elev=12, azim=-10) if planar else dict(vertical_axis="z", elev=20, azim=-60)
    height = has_ground(run, up)
    return {"limits": limits, "span": span, "up": up, "planar": planar, "camera": camera,
            "ground": height is not None, "ground_height": height}


# -- colours ---------------------------------------------------------------------------------------

def leaf_colours(run: Run) -> dict:
    """{leaf frame: colour} (C1, C2, ...): the colour of its trace, and of its branch of sticks."""
    return {leaf: f"C{i + 1}" for i, leaf in enumerate(leaf_frames(run))}


def branch_colours(run: Run, edges: list) -> list:
    """The colour of each stick: with more than one leaf frame (two legs), a stick above exactly
    one leaf takes that leaf's colour (`leaf_colours`), the others C0; with one leaf, all C0."""
    colour = leaf_colours(run)
    if len(colour) < 2:
        return ["C0"] * len(edges)
    children = {}
    for parent, child in edges:
        children.setdefault(parent, []).append(child)

    def under(name, seen=()):
        """The leaves at or below frame `name`."""
        if name in seen:                # frame_parents makes a tree; no loop even if it did not
            return set()
        kids = children.get(name, [])
        return {name} if not kids else set().union(*(under(k, seen + (name,)) for k in kids))

    ends = [under(child) for _, child in edges]
    return [colour.get(next(iter(e)), "C0") if len(e) == 1 else "C0" for e in ends]
