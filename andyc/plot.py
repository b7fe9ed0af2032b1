"""Plots of runs (matplotlib, no screen needed).

`figure_for(run)` builds the Figure, `plot_run(run, out)` saves it. Panels,
each only when it applies: the world trajectories of the logged frames in 3-D
and their x, y, z against time (as Fig. 6 of the ANDY paper shows the ends of
the swing bar; a world axis along which no frame moves is left out),
coordinates, speeds, quaternion signals, position signals, other signals,
energy and its relative change. A hybrid run (more than one flow, or any jump)
also gets, at the top of the time series, the active flow against time with the
jumps marked, and its discrete states against time (as Fig. 10 of the paper).

`sticks_figure(run)` draws the logged frames as stick figures (each frame
joined to its logged parent) at snapshot times over the run, as Fig. 9 of the
paper shows the passive walker going down the slope; `plot_sticks(run, out)`
saves it.

`animate_run(run, out)` writes a 3-D stick animation of the logged frames
(GIF, or MP4 with ffmpeg): `animation_samples` picks the samples,
`stick_segments` gives the sticks' ends at them, `animation_figure` draws.
"""

from __future__ import annotations

from functools import partial
from pathlib import Path

import matplotlib
import matplotlib.ticker

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib import animation, cm, colors  # noqa: E402
from matplotlib.backend_bases import FigureCanvasBase  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from andyc.runtime.run import Run  # noqa: E402
from andyc.outputs import write_atomic  # noqa: E402

QUATERNION = ("_qw", "_qx", "_qy", "_qz")
POSITION = ("_x", "_y", "_z")


def plot_run(run: Run, out) -> None:
    """Write the figure of `run` to `out` (PNG)."""
    with write_atomic(out) as tmp:
        figure_for(run).savefig(tmp, dpi=110)


def plot_sticks(run: Run, out, count: int = 10) -> None:
    """Write the stick figure of `run` to `out` (PNG); see `sticks_figure`."""
    with write_atomic(out) as tmp:
        sticks_figure(run, count=count).savefig(tmp, dpi=110)


def figure_for(run: Run) -> Figure:
    """3-D frame trajectories on the left (energy below them), time series on the right;
    without frames, one column of time series."""
    series = _series_panels(run)
    energy = [_energy, _energy_change]
    if run.frames:
        fig = Figure(figsize=(16, max(10, 1.8 * len(series))), layout="constrained")
        grid = fig.add_gridspec(1, 2, width_ratios=[1, 1.1])
        left = grid[0].subgridspec(3, 1, height_ratios=[5, 1.5, 1.5])
        _trajectories(fig.add_subplot(left[0], projection="3d"), run)
        right = grid[1].subgridspec(len(series), 1, height_ratios=[_height(p, run) for p in series])
        axes = _time_axes(fig, right, series, run)
        _time_axes(fig, [left[1], left[2]], energy, run, sharex=axes[0])
    else:
        panels = series + energy
        ratios = [3 * _height(p, run) for p in series] + [2, 2]
        fig = Figure(figsize=(10, 0.75 * sum(ratios) + 1), layout="constrained")
        _time_axes(fig, fig.add_gridspec(len(panels), 1, height_ratios=ratios), panels, run)
    fig.suptitle(f"{run.model}: {run.method}, dt = {run.dt:g} s, {run.status}")
    return fig


def _series_panels(run: Run) -> list:
    """The drawing functions of the right-hand (or only) column, top to bottom."""
    panels = []
    if is_hybrid(run):
        panels.append(_flows)
    if run.discrete_names:
        panels.append(_discrete)
    panels += [partial(_frame_axis, k=k) for k in range(3) if _moves(run.frames, k)]
    if run.nq:          # a free body has speeds and signals only
        panels.append(partial(_states, cols=range(run.nq), ylabel="coordinates q, rad | m"))
    panels.append(partial(_states, cols=range(run.nq, run.nq + run.nv), ylabel="speeds v, rad/s | m/s"))
    quaternions, positions, others = _signal_groups(run.signal_names)
    if quaternions:
        panels.append(partial(_quaternions, bases=quaternions))
    for names, ylabel in ((positions, "position signals, m"), (others, "other signals")):
        if names:
            panels.append(partial(_states, cols=[run.state_names.index(n) for n in names], ylabel=ylabel))
    if run.input_names and len(run.time) and np.ptp(run.input_values, axis=0).max() > 0:
        panels.append(_inputs)      # inputs that change (driven, or set by flows)
    if run.multiplier_names:
        panels += [_multipliers, _residuals]
    return panels


def is_hybrid(run: Run) -> bool:
    """Whether the run has more than one flow or any jump (and so a flow panel)."""
    return len(run.flow_names) > 1 or len(run.events["time"]) > 0


def _height(panel, run: Run) -> float:
    """Relative height of a time-series panel: the flow panel (unless there are many flows) and the
    discrete panel are shorter."""
    if panel is _flows:
        return min(0.5 + 0.1 * len(run.flow_names), 1.0)
    return 0.7 if panel is _discrete else 1.0


def _time_axes(fig, specs, panels, run, sharex=None) -> list:
    """One axes per panel down `specs`, sharing the time axis; only the bottom one labels it."""
    axes = []
    for spec, draw in zip(specs, panels):
        ax = fig.add_subplot(spec, sharex=sharex or (axes[0] if axes else None))
        draw(ax, run)
        ax.grid(alpha=0.3)
        ax.tick_params(labelbottom=False)
        axes.append(ax)
    axes[-1].tick_params(labelbottom=True)
    axes[-1].set_xlabel("time, s")
    return axes


def _legend(ax) -> None:
    ax.legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), fontsize="small", frameon=False)


def _moves(frames: dict, k: int) -> bool:
    """Whether any frame moves along world axis k."""
    if not frames:
        return False
    xyz = np.concatenate(list(frames.values()))
    scale = max(np.nanmax(np.abs(xyz)), 1.0)
    return any(np.nanmax(p[:, k]) - np.nanmin(p[:, k]) > 1e-9 * scale for p in frames.values())


def _signal_groups(names: list) -> tuple:
    """(quaternion base names, position signal names, the other signal names)."""
    bases = [n[:-3] for n in names if n.endswith("_qw") and all(n[:-3] + s in names for s in QUATERNION)]
    in_quaternion = {b + s for b in bases for s in QUATERNION}
    positions = [n for n in names if n.endswith(POSITION) and n not in in_quaternion]
    others = [n for n in names if n not in in_quaternion and n not in positions]
    return bases, positions, others


def _frame_paths(frames: dict) -> list:
    """[(label, xyz)]: frames whose paths coincide (e.g. a joint frame at a link's end) share one
    line labelled 'a = b', so that no line hides another."""
    paths = []
    for name, xyz in frames.items():
        same = next((p for p in paths if np.allclose(p[1], xyz, rtol=1e-9, atol=1e-12, equal_nan=True)), None)
        if same:
            same[0].append(name)
        else:
            paths.append(([name], xyz))
    return [(" = ".join(names), xyz) for names, xyz in paths]


def _trajectories(ax, run: Run) -> None:
    """Each frame's path in world coordinates, start (●) and end (■) marked, on equal axes."""
    for i, (name, xyz) in enumerate(_frame_paths(run.frames)):
        ax.plot(*xyz.T, color=f"C{i}", lw=0.8, label=name)
        ax.scatter(*xyz[0], color=f"C{i}", marker="o", s=30)
        ax.scatter(*xyz[-1], color=f"C{i}", marker="s", s=30)
    points = np.concatenate(list(run.frames.values()))
    lo, hi = np.nanmin(points, axis=0), np.nanmax(points, axis=0)
    centre, half = (lo + hi) / 2, max(np.max(hi - lo) / 2, 1e-3) * 1.05
    for setter, c, label in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), centre, "xyz"):
        setter(c - half, c + half)
        getattr(ax, f"set_{label}label")(f"{label}, m", labelpad=10)
    ax.set_box_aspect((1, 1, 1), zoom=0.92)
    ax.set_title("frame trajectories in world (● start, ■ end)")
    ax.legend(loc="upper left", fontsize="small")


def _frame_axis(ax, run: Run, k: int) -> None:
    for i, (name, xyz) in enumerate(_frame_paths(run.frames)):
        ax.plot(run.time, xyz[:, k], color=f"C{i}", lw=1, label=name)
    ax.set_ylabel(f"frame {'xyz'[k]}, m")
    _legend(ax)


def _states(ax, run: Run, cols, ylabel: str) -> None:
    for j in cols:
        ax.plot(run.time, run.state[:, j], lw=1, label=run.state_names[j])
    ax.set_ylabel(ylabel)
    _legend(ax)


def _inputs(ax, run: Run) -> None:
    for j, name in enumerate(run.input_names):
        ax.plot(run.time, run.input_values[:, j], lw=1, label=name)
    ax.set_ylabel("inputs u")
    _legend(ax)


def _quaternions(ax, run: Run, bases: list) -> None:
    """Components w, x, y, z in fixed colours; one line style per quaternion."""
    for b, style in zip(bases, ["-", "--", ":", "-."] * len(bases)):
        for c, s in enumerate(QUATERNION):
            ax.plot(run.time, run.column(b + s), color=f"C{c}", ls=style, lw=1, label=b + s)
    ax.set_ylabel("quaternion (w, x, y, z), 1")
    _legend(ax)


def _multipliers(ax, run: Run) -> None:
    for j, name in enumerate(run.multiplier_names):
        ax.plot(run.time, run.multipliers[:, j], lw=1, label=name)
    ax.set_ylabel("multipliers λ, N | N m")
    _legend(ax)


def _residuals(ax, run: Run) -> None:
    """|phi| (solid) and |c| (dashed) per row, on a log scale floored at 1e-17 (exact zeros)."""
    names = run.multiplier_names
    for j in range(run.residual_position.shape[1]):
        ax.semilogy(run.time, np.maximum(np.abs(run.residual_position[:, j]), 1e-17), color=f"C{j}", lw=1,
                    label=f"φ {names[j]}")
    for j in range(run.residual_velocity.shape[1]):
        ax.semilogy(run.time, np.maximum(np.abs(run.residual_velocity[:, j]), 1e-17), color=f"C{j}", lw=1,
                    ls="--", label=f"c {names[j]}")
    ax.set_ylabel("constraint residuals")
    _legend(ax)


def _energy(ax, run: Run) -> None:
    ax.plot(run.time, run.energy, color="k", lw=1)
    ax.set_ylabel("energy E, J")
    ax.ticklabel_format(axis="y", useOffset=False)


def _energy_change(ax, run: Run) -> None:
    e = run.energy
    ax.plot(run.time, (e - e[0]) / max(abs(e[0]), np.abs(e).max(), 1e-300), color="tab:red", lw=0.8)
    ax.set_ylabel("(E - E(0)) / max|E|, 1")


def _flows(ax, run: Run) -> None:
    """The active flow as a step line, flow names as tick labels; the jumps as dashed vertical
    lines, one colour (and legend entry) per jump."""
    ax.step(run.time, run.flow, where="post", color="k", lw=1.2, label="active flow")
    n = len(run.flow_names)
    ax.set_yticks(range(n), labels=run.flow_names)
    ax.set_ylim(-0.5, n - 0.5)
    ev = run.events
    for j, name in enumerate(run.jump_names):
        times = ev["time"][ev["jump"] == j]
        if len(times):
            ax.vlines(times, 0, 1, transform=ax.get_xaxis_transform(), colors=f"C{j % 10}", lw=0.9, ls="--",
                      label=f"{name} ({len(times)})", gid=f"jump:{name}")
    ax.set_ylabel("flow")
    _legend(ax)


def _discrete(ax, run: Run) -> None:
    for j, name in enumerate(run.discrete_names):
        ax.step(run.time, run.discrete[:, j], where="post", lw=1, label=name)
    ax.set_ylabel("discrete states")
    _legend(ax)


# -- stick figures -----------------------------------------------------------------------------

def stick_edges(run: Run) -> list:
    """[(parent, child)] for each logged frame whose parent is logged too (not 'world')."""
    return [(parent, child) for child, parent in run.frame_parents.items()
            if child in run.frames and parent in run.frames]


def stick_plane(run: Run) -> tuple:
    """The two world axes (i, j) along which the frames spread most, in axis order (x-y for a
    planar model in x-y; for a 3-D model the plane in which the frames move most); j is drawn
    upwards."""
    xyz = np.concatenate([run.frames[name] for edge in stick_edges(run) for name in edge])
    spread = np.nanmax(xyz, axis=0) - np.nanmin(xyz, axis=0)
    spread = np.where(np.isfinite(spread), spread, 0.0)
    i, j = sorted(np.argsort(-spread, kind="stable")[:2])
    return int(i), int(j)


def has_ground(up: np.ndarray, extent: float) -> bool:
    """Whether to draw the ground (vertical coordinate 0): some frame rests on it (a stance foot)
    and none goes far below it (a foot may scuff through it a little); `up` holds the vertical
    coordinates of the frames, `extent` the size of the figure."""
    return bool(np.any(np.abs(up) <= 1e-3 * extent) and np.nanmin(up) >= -0.05 * extent)


def snapshot_indices(run: Run, count: int = 10) -> np.ndarray:
    """Sample indices of the snapshots: `count` spread evenly over the run (first and last
    included) and, when there are no more jumps than that, the last sample before each jump."""
    n = len(run.time)
    even = np.round(np.linspace(0, n - 1, max(min(count, n), 1))).astype(int)
    times = run.events["time"]
    at_jumps = np.searchsorted(run.time, times, side="right") - 1 if 0 < len(times) <= count else []
    return np.unique(np.clip(np.concatenate([even, at_jumps]), 0, n - 1).astype(int))


def sticks_figure(run: Run, count: int = 10) -> Figure:
    """Stick figures of the logged frames at snapshot times (see `snapshot_indices`), in the world
    plane of `stick_plane` with equal aspect: each frame joined to its logged parent by a line,
    earlier snapshots lighter, a dot on every frame, the ground (vertical coordinate 0) drawn when
    some frame touches it and none goes far below it (a foot may scuff through it a little). Each
    stick line has gid 'parent>child@sample'."""
    edges = stick_edges(run)
    if not edges:
        raise ValueError("no stick figure: no logged frame has its parent frame logged too "
                         "(simulate with frames='all')")
    i, j = stick_plane(run)
    names = list(dict.fromkeys(name for edge in edges for name in edge))
    xyz = np.stack([run.frames[name] for name in names])          # (frames, N, 3)
    lo, hi = np.nanmin(xyz[..., [i, j]], axis=(0, 1)), np.nanmax(xyz[..., [i, j]], axis=(0, 1))
    extent = max(float(np.max(hi - lo)), 1e-3)
    ground = has_ground(xyz[..., j], extent)
    span = hi - lo + 0.1 * extent                                  # the axes limits below
    width = 12.0                    # the axes get about width - 2 inches (labels, colour bar), height + 1.4
    height = float(np.clip((width - 2.0) * span[1] / span[0] + 1.4, 3.5, 11.0))
    if height == 11.0:              # a tall model: narrower figure instead
        width = float(np.clip((height - 1.4) * span[0] / span[1] + 2.0, 5.0, width))
    fig = Figure(figsize=(width, height), layout="constrained")
    ax = fig.add_subplot()

    snaps = snapshot_indices(run, count)
    t0, t1 = run.time[0], run.time[-1]
    cmap = matplotlib.colormaps["Blues"]
    shade = lambda k: cmap(0.3 + 0.7 * (run.time[k] - t0) / (t1 - t0 if t1 > t0 else 1.0))  # noqa: E731
    jumps = set(np.searchsorted(run.time, run.events["time"], side="right") - 1)
    for k in snaps:
        colour = shade(k)
        style = "--" if k in jumps else "-"
        for parent, child in edges:
            a, b = run.frames[parent][k], run.frames[child][k]
            ax.plot([a[i], b[i]], [a[j], b[j]], color=colour, lw=1.6, ls=style, solid_capstyle="round",
                    gid=f"{parent}>{child}@{k}")
        ax.scatter(xyz[:, k, i], xyz[:, k, j], color=colour, s=10, zorder=3)

    pad = 0.05 * extent
    if ground:
        ax.axhline(0.0, color="saddlebrown", lw=1.2, gid="ground", zorder=1)
        ax.axhspan(lo[1] - 10 * extent, 0.0, color="saddlebrown", alpha=0.12, lw=0, zorder=0)
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_autoscale_on(True)       # no new artists follow: the limits stay, and may widen ...
    ax.set_aspect("equal", adjustable="datalim")                  # ... to fill the axes
    ax.set_xlabel(f"world {'xyz'[i]}, m")
    ax.set_ylabel(f"world {'xyz'[j]}, m")
    ax.grid(alpha=0.3)
    sm = cm.ScalarMappable(cmap=colors.ListedColormap(cmap(np.linspace(0.3, 1, 256))),
                                      norm=colors.Normalize(t0, t1))
    fig.colorbar(sm, ax=ax, label="time, s", fraction=0.03, pad=0.01)
    at = " (dashed: just before a jump)" if jumps & set(snaps) else ""
    fig.suptitle(f"{run.model}: stick figures at {len(snaps)} times{at}, {run.method}, dt = {run.dt:g} s")
    return fig


# -- animation ---------------------------------------------------------------------------------

TRACE_SECONDS = 0.5                 # the trail behind each leaf frame
SCENE_INCHES = {"planar": (8.0, 5.0), "3-D": (6.4, 5.2)}     # the largest size of the drawing (100 px an inch)


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


def animation_samples(run: Run, fps: int = 30, max_frames: int = 300) -> np.ndarray:
    """Indices of the samples shown, one per animation frame: the samples nearest to times evenly
    spread from the first sample to the last; as many as play the run in real time at `fps`
    (duration * fps + 1), but at most `max_frames` (then it plays faster) and at most all samples."""
    t = run.time
    n = len(t)
    if n == 0:
        return np.zeros(0, dtype=int)
    count = int(min(n, max(max_frames, 1), round((t[-1] - t[0]) * fps) + 1))
    if count >= n:
        return np.arange(n)
    want = np.linspace(t[0], t[-1], count)
    k = np.clip(np.searchsorted(t, want), 1, n - 1)
    k -= want - t[k - 1] < t[k] - want             # the nearer of the two neighbours
    return np.unique(k)


def stick_segments(run: Run, samples) -> tuple:
    """(edges, segments): the sticks (`animation_edges`) and their ends at the given samples,
    segments[f, e] = [parent xyz, child xyz] of edge e at samples[f], shape (frames, edges, 2, 3);
    'world' is the origin."""
    edges = animation_edges(run)
    samples = np.asarray(samples, dtype=int)
    at = lambda name: np.zeros((len(samples), 3)) if name == "world" else run.frames[name][samples]  # noqa: E731
    segments = np.zeros((len(samples), len(edges), 2, 3))
    for e, (parent, child) in enumerate(edges):
        segments[:, e, 0], segments[:, e, 1] = at(parent), at(child)
    return edges, segments


def animation_view(run: Run) -> dict:
    """The fixed scene: limits around all frames over the whole run and the world origin, with
    one scale along all axes (box aspect = spans), the vertical axis ('y' for a model whose frames
    all lie in the world x-y plane, as the planar models have gravity along -y, else 'z'), the
    camera, and whether to draw the ground (vertical coordinate 0)."""
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
    return {"limits": limits, "span": span, "up": up, "planar": planar, "camera": camera,
            "ground": has_ground(xyz[1:, up], extent)}


class GifWriter(animation.PillowWriter):
    """matplotlib's PillowWriter, writing all frames with one palette of 256 colours (median cut of
    a few frames over the run, no dithering): what does not move keeps its colour, so Pillow
    stores each frame as the small rectangle that changed (the GIF is several times smaller),
    and it takes a fraction of the time of a median cut per frame."""

    def finish(self):
        from PIL import Image

        frames = self._frames
        if frames:
            some = frames[::max(1, len(frames) // 8)]
            w, h = frames[0].size
            montage = Image.new("RGB", (w, h * len(some)))
            for i, im in enumerate(some):
                montage.paste(im.convert("RGB"), (0, h * i))
            palette = montage.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
            self._frames = [im.convert("RGB").quantize(palette=palette, dither=Image.Dither.NONE) for im in frames]
        super().finish()


def animation_writer(out, fps: int = 30) -> tuple:
    """(writer, frames per second it plays at) for `out`: `GifWriter` for .gif, whose
    frames last whole hundredths of a second (at least 2: browsers slow shorter ones down), so
    30 fps plays at 33.3; FFMpegWriter (H.264) for .mp4 if ffmpeg is installed. ValueError
    otherwise."""
    suffix = Path(out).suffix.lower()
    if suffix == ".gif":
        hundredths = max(2, round(100 / fps))
        # Pillow keeps int(int(1000 / fps) / 10) hundredths: 1000 / fps = 10 * hundredths + 5 is safe from round-off
        return GifWriter(fps=1000 / (10 * hundredths + 5)), 100 / hundredths
    if suffix == ".mp4":
        if not animation.FFMpegWriter.isAvailable():
            raise ValueError(f"{out}: writing .mp4 needs ffmpeg, which is not installed (not on PATH); "
                             f"install ffmpeg, or write a GIF instead: -o {Path(out).with_suffix('.gif')}")
        return animation.FFMpegWriter(fps=fps, codec="h264", extra_args=["-pix_fmt", "yuv420p"]), fps
    raise ValueError(f"{out}: an animation is written as .gif or .mp4, not '{suffix or 'no suffix'}'")


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


def animation_figure(run: Run, samples, dpi: int = 100) -> tuple:
    """(fig, update): the 3-D scene of `run` and update(f), which draws animation frame f
    (samples[f]): sticks (coloured by `branch_colours`), joints, the trace of the last
    TRACE_SECONDS of each leaf frame, in 3-D the shadows of the sticks on the floor, and the title
    with the time (and the flow of a hybrid run). The axes, the world origin and the ground do not
    move: they are drawn once, at `dpi` (the dpi to save at), into a background image."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    samples = np.asarray(samples, dtype=int)
    edges, segments = stick_segments(run, samples)
    view = animation_view(run)
    joints = np.stack([run.frames[name][samples] for name in run.frames], axis=1)  # (frames, names, 3)

    fig = Figure(figsize=(12, 10), dpi=dpi)  # generous: `_fit_figure` scales the scene to SCENE_INCHES and crops
    ax = fig.add_axes((0.25, 0.25, 0.5, 0.5), projection="3d")
    ax.view_init(**view["camera"])
    ax.set_box_aspect(view["span"])
    for setter, lim in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), view["limits"]):
        setter(*lim)
    for axis, label in zip((ax.xaxis, ax.yaxis, ax.zaxis), "xyz"):
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
        axis.set_label_text(f"{label}, m")
    ax.zaxis.labelpad = 9
    if view["planar"]:
        ax.set_zticks([])
        ax.set_zlabel("")
    ax.tick_params(labelsize="small")
    hybrid = is_hybrid(run)
    digits = len(f"{run.time[-1]:.2f}")     # the title's width stays put

    def heading(k):
        text = f"{run.model}   t = {run.time[k]:{digits}.2f} s"
        return text + f"   flow {run.flow_names[run.flow[k]]}" if hybrid else text

    widest = max((heading(k) for k in samples[np.unique(run.flow[samples], return_index=True)[1]]), key=len)
    title = fig.text(0.5, 1.0, widest, ha="left", va="center", family="monospace")    # placed by `_fit_figure`
    _fit_figure(fig, ax, title, SCENE_INCHES["planar" if view["planar"] else "3-D"])

    still = [ax.plot([0], [0], [0], "s", color="k", ms=5, gid="world")[0]]
    if view["ground"] and view["planar"]:   # the line where the ground meets the plane of motion
        line = np.zeros((2, 3))
        line[:, 1 - view["up"]] = view["limits"][1 - view["up"]]
        still += ax.plot(*line.T, color="saddlebrown", lw=1.5, gid="ground")
    # the background: the 3-D axes take most of the time of drawing a frame, and do not change
    title.set_visible(False)
    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    fig.figimage(np.asarray(canvas.buffer_rgba()).copy(), zorder=-1, gid="background")
    ax.set_axis_off()
    ax.patch.set_visible(False)
    for artist in still:
        artist.set_visible(False)
    title.set_visible(True)

    traces = {name: ax.plot([], [], [], color=colour, lw=1.5, alpha=0.6, gid=f"trace:{name}")[0]
              for name, colour in leaf_colours(run).items()}
    floor = 0.0 if view["ground"] else view["limits"][2][0]     # 3-D: shadows on the floor show the depth
    shadows = [] if view["planar"] else [ax.plot([], [], [], color="0.6", lw=2, alpha=0.5, gid=f"shadow:{p}>{c}")[0]
                                         for p, c in edges]
    sticks = [ax.plot([], [], [], color=colour, lw=2.5, solid_capstyle="round", gid=f"{parent}>{child}")[0]
              for (parent, child), colour in zip(edges, branch_colours(run, edges))]
    dots = ax.plot([], [], [], "o", color="k", ms=3.5, gid="joints")[0]
    FigureCanvasBase(fig)           # whose draw does nothing: FuncAnimation's draw_idle after each frame
                                    # would otherwise draw it once more than saving it does

    def update(f):
        k = samples[f]
        for line, seg in zip(sticks, segments[f]):
            line.set_data_3d(*seg.T)
        for line, seg in zip(shadows, segments[f]):
            line.set_data_3d(seg[:, 0], seg[:, 1], [floor, floor])
        dots.set_data_3d(*joints[f].T)
        first = np.searchsorted(run.time, run.time[k] - TRACE_SECONDS)
        for name, line in traces.items():
            line.set_data_3d(*run.frames[name][first:k + 1].T)
        title.set_text(heading(k))
        return []

    return fig, update


def _ink(fig) -> tuple:
    """(x0, y0, x1, y1): the box, in inches from the bottom left, of what `fig` draws."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    ink = np.any(np.asarray(canvas.buffer_rgba())[..., :3] < 250, axis=2)      # rows from the top
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    h = fig.get_size_inches()[1]
    return cols[0] / fig.dpi, h - (rows[-1] + 1) / fig.dpi, (cols[-1] + 1) / fig.dpi, h - rows[0] / fig.dpi


def _fit_figure(fig, ax, title, size, margin: float = 0.1) -> None:
    """Scale the figure so that what `ax` draws is about `size` (width, height) inches at most
    (matplotlib draws a 3-D box small in its axes), then crop the figure to that, plus `margin`
    inches around it and a line above it for `title` (left-aligned, holding its widest text, which
    is centred: the text does not shift as it changes), keeping the axes' size (so the drawing
    keeps its scale)."""
    title.set_visible(False)
    x0, y0, x1, y1 = _ink(fig)
    fig.set_size_inches(fig.get_size_inches() * min(size[0] / (x1 - x0), size[1] / (y1 - y0)))
    x0, y0, x1, y1 = _ink(fig)      # the box scales with the axes (not zoom: the lines are clipped to the axes)
    title.set_visible(True)
    top = 2.2 * title.get_fontsize() / 72                                      # inches
    text_width = title.get_window_extent(fig.canvas.get_renderer()).width / fig.dpi
    w, h = fig.get_size_inches()
    new_w, new_h = max(x1 - x0, text_width) + 2 * margin, y1 - y0 + 2 * margin + top
    new_w, new_h = (2 * np.ceil(v * fig.dpi / 2) / fig.dpi for v in (new_w, new_h))   # even pixels (H.264 needs them)
    left = x0 - margin - (new_w - 2 * margin - (x1 - x0)) / 2                  # the drawing centred
    pos = ax.get_position()
    fig.set_size_inches(new_w, new_h)
    ax.set_position([(pos.x0 * w - left) / new_w, (pos.y0 * h - y0 + margin) / new_h,
                     pos.width * w / new_w, pos.height * h / new_h])
    title.set_position(((new_w - text_width) / 2 / new_w, 1 - top / 2 / new_h))    # the widest title centred


def animate_run(run: Run, out, fps: int = 30, max_frames: int = 300, dpi: int = 100, progress=None) -> dict:
    """Write a 3-D stick animation of the logged frames of `run` to `out` (.gif, or .mp4 with
    ffmpeg): `animation_samples` picks the samples, `animation_figure` draws them at `dpi`.
    progress(done, total) is called before each frame and once at the end. Returns {'frames',
    'fps' (as played), 'seconds' (playing time), 'speed' (run time per playing time),
    'render_seconds'}. ValueError if no frames were logged or `out` cannot be written (see
    `animation_writer`)."""
    import time

    if not run.frames:
        raise ValueError(f"{run.model}: the run logged no frames to animate; re-run it with "
                         "`andyc sim MODEL.yaml --frames all --out RUN.h5`")
    writer, fps = animation_writer(out, fps)
    start = time.perf_counter()
    samples = animation_samples(run, fps, max_frames)
    fig, update = animation_figure(run, samples, dpi)
    anim = animation.FuncAnimation(fig, update, frames=len(samples), blit=False, repeat=False,
                                   cache_frame_data=False)
    with write_atomic(out) as tmp:
        anim.save(tmp, writer=writer, dpi=dpi, progress_callback=progress)  # before each frame: frames done so far
    if progress:
        progress(len(samples), len(samples))
    seconds = len(samples) / fps
    played = run.time[samples[-1]] - run.time[samples[0]] if len(samples) else 0.0
    return {"frames": len(samples), "fps": fps, "seconds": seconds, "speed": played * fps / max(len(samples) - 1, 1),
            "render_seconds": time.perf_counter() - start}
