"""The map of a sweep (`andyc plot STORE`): a value over a grid's two swept names as a heat map, over one as a
line; over Monte Carlo samples or CSV points, a scatter. The outcome (finished, stopped, blew up, Zeno,
failed) is drawn in one colour per outcome, with a legend. On a metric's map, a point whose run did not
finish is left out of the colour scale (its value is that of a cut run) and marked by a cross in its
outcome's colour, named in a legend."""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import BoundaryNorm, ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Patch

from andyc.outputs import write_atomic

OUTCOME_COLOURS = {0: "#ffffff", 1: "#2a9d8f", 2: "#e9c46a", 3: "#e76f51", 4: "#8d5fd3", 5: "#6c757d"}
NOT_RUN, FINISHED = 0, 1        # andyc.runtime.status.OUTCOMES' codes


def plot_sweep(grid: bool, axes: list, values: np.ndarray, name: str, expression: str, out, title: str = "",
               outcomes: dict | None = None, colours: dict | None = None, runs: tuple | None = None) -> None:
    """Write the map of `values` to `out` (PNG). axes: [(swept name, its values)] -- a grid's axes (values of
    shape (len(x),) or (len(x), len(y))) or the points' values of each name (values of shape (n,));
    outcomes: {code: name} when the values are codes (the outcomes, or classes such as walks / falls), drawn
    in `colours` {code: colour} (default OUTCOME_COLOURS); runs: (each point's outcome code, {code: name}),
    to mark the points of a metric whose run did not finish."""
    with write_atomic(out) as tmp:
        sweep_figure(grid, axes, values, name, expression, title, outcomes, colours, runs).savefig(tmp, dpi=110)


def sweep_figure(grid, axes, values, name, expression="", title="", outcomes=None, colours=None,
                 runs=None) -> Figure:
    palette = colours or OUTCOME_COLOURS
    fig = Figure(figsize=(7, 5.2))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    label = f"{name} = {expression}" if expression else name
    values = np.asarray(values, dtype=float)
    cut = None
    if runs is not None and not outcomes:
        code = np.asarray(runs[0])
        cut = (code != FINISHED) & (code != NOT_RUN)
        values = np.where(cut, np.nan, values)
    if outcomes:
        codes = sorted(outcomes)
        cmap = ListedColormap([palette.get(c, "#000000") for c in codes])
        norm = BoundaryNorm(np.arange(len(codes) + 1) - 0.5, len(codes))
        colour = dict(cmap=cmap, norm=norm)
    else:
        colour = dict(cmap="viridis")
    if len(axes) == 2 and grid:
        (xn, x), (yn, y) = axes
        mesh = ax.pcolormesh(x, y, values.T, shading="nearest", **colour)
        ax.set_xlabel(xn)
        ax.set_ylabel(yn)
    elif len(axes) == 2:
        (xn, x), (yn, y) = axes
        mesh = ax.scatter(x, y, c=values, s=12, **colour)
        ax.set_xlabel(xn)
        ax.set_ylabel(yn)
    else:
        (xn, x), = axes
        order = np.argsort(x)
        if outcomes:
            mesh = ax.scatter(x, values, c=values, s=14, **colour)
        else:
            ax.plot(x[order], values[order], "-o" if grid else "o", ms=3)
            mesh = None
        ax.set_xlabel(xn)
        ax.set_ylabel(label)
    if cut is not None and cut.any():
        _mark_cut(ax, grid, axes, values, code, cut, runs[1])
    if outcomes:
        present = [c for c in sorted(outcomes) if np.any(values == c)]
        ax.legend(handles=[Patch(color=palette.get(c, "#000000"), label=outcomes[c]) for c in present],
                  loc="best", fontsize=8, framealpha=0.8)
    elif mesh is not None:
        fig.colorbar(mesh, ax=ax, label=label)
    ax.set_title(title)
    fig.tight_layout()
    return fig


def _mark_cut(ax, grid, axes, values, code, cut, names: dict) -> None:
    """A cross in its outcome's colour at each point whose run did not finish, one legend entry an outcome."""
    if len(axes) == 2 and grid:
        (_, x), (_, y) = axes
        xs, ys = np.meshgrid(x, y, indexing="ij")
    elif len(axes) == 2:
        (_, xs), (_, ys) = axes
    else:
        (_, xs), = axes
        ys = np.where(np.isfinite(values), values, np.nanmin(values) if np.isfinite(values).any() else 0.0)
    for c in sorted(set(code[cut].tolist())):
        here = cut & (code == c)
        ax.scatter(np.asarray(xs)[here], np.asarray(ys)[here], marker="x", s=28, color=OUTCOME_COLOURS.get(c, "k"),
                   label=names.get(c, str(c)), zorder=3)
    ax.legend(loc="best", fontsize=8, framealpha=0.8)
