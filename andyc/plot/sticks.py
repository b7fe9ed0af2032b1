"""Stick figures of a run: `sticks_figure(run)` draws the logged frames (each joined to its logged
parent) at snapshot times over the run (`snapshot_indices`), as Fig. 9 of the ANDY paper shows the
passive walker going down the slope; `plot_sticks(run, out)` saves it.
"""

from __future__ import annotations

import matplotlib
import numpy as np
from matplotlib import cm, colors
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from andyc.outputs import write_atomic
from andyc.plot.scene import has_ground, stick_edges, stick_plane
from andyc.runtime.run import Run


def plot_sticks(run: Run, out, count: int = 10) -> None:
    """Write the stick figure of `run` to `out` (PNG); see `sticks_figure`."""
    with write_atomic(out) as tmp:
        sticks_figure(run, count=count).savefig(tmp, dpi=110)


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
    earlier snapshots lighter, a dot on every frame, the ground drawn and shaded below where the
    model has one along the vertical axis (`has_ground`). Each
    stick line has gid 'parent>child@sample'. On an Agg canvas of its own (no pyplot)."""
    edges = stick_edges(run)
    if not edges:
        raise ValueError("no stick figure: no logged frame has its parent frame logged too "
                         "(simulate with frames='all')")
    i, j = stick_plane(run)
    names = list(dict.fromkeys(name for edge in edges for name in edge))
    xyz = np.stack([run.frames[name] for name in names])          # (frames, N, 3)
    lo, hi = np.nanmin(xyz[..., [i, j]], axis=(0, 1)), np.nanmax(xyz[..., [i, j]], axis=(0, 1))
    extent = max(float(np.max(hi - lo)), 1e-3)
    ground = has_ground(run, j)
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
    if ground is not None:
        ax.axhline(ground, color="saddlebrown", lw=1.2, gid="ground", zorder=1)
        ax.axhspan(lo[1] - 10 * extent, ground, color="saddlebrown", alpha=0.12, lw=0, zorder=0)
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
    FigureCanvasAgg(fig)
    return fig
