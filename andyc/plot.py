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
"""

from __future__ import annotations

from functools import partial

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
from matplotlib import cm, colors  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from andyc.runtime.run import Run  # noqa: E402

QUATERNION = ("_qw", "_qx", "_qy", "_qz")
POSITION = ("_x", "_y", "_z")


def plot_run(run: Run, out) -> None:
    """Write the figure of `run` to `out` (PNG)."""
    figure_for(run).savefig(out, dpi=110)


def plot_sticks(run: Run, out, count: int = 10) -> None:
    """Write the stick figure of `run` to `out` (PNG); see `sticks_figure`."""
    sticks_figure(run, count=count).savefig(out, dpi=110)


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
    up = xyz[..., j]                # ground: a frame rests on 0 (a stance foot) and none goes far below it
    ground = bool(np.any(np.abs(up) <= 1e-3 * extent) and lo[1] >= -0.05 * extent)
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
