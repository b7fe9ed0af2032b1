"""The map of a basin of attraction (`andyc cycle --basin`): each grid point's class (andyc.analysis.basins) in
one colour per class over the two swept starting components, the cycle's visits marked."""

from __future__ import annotations

import numpy as np

from andyc.outputs import write_atomic
from andyc.plot.sweepmap import sweep_figure

CLASS_COLOURS = {0: "#ffffff", 1: "#2a9d8f", 2: "#457b9d", 3: "#e76f51", 4: "#adb5bd"}


def plot_basin(axes: list, classes: np.ndarray, periods: np.ndarray, names: dict, marks, out, title: str) -> None:
    """Write the basin map to `out` (PNG). axes: [(name, values)] of the grid's two components; classes: the
    codes over the grid; periods: the other orbits' periods (named in the legend); names: {code: class};
    marks: the cycle's visits, a (name_1 value, name_2 value) each."""
    with write_atomic(out) as tmp:
        basin_figure(axes, classes, periods, names, marks, title).savefig(tmp, dpi=110)


def basin_figure(axes, classes, periods, names, marks, title=""):
    """The Figure of plot_basin."""
    labels = dict(names)
    found = sorted({int(p) for p in np.asarray(periods)[np.asarray(classes) == 2]})
    if found:
        labels[2] = f"orbit of period {', '.join(map(str, found))}"
    fig = sweep_figure(True, axes, classes, "class", title=title, outcomes={c: labels[c] for c in names},   # (every code: the colours go by position)
                       colours=CLASS_COLOURS)
    ax = fig.axes[0]
    marks = np.atleast_2d(np.asarray(marks, dtype=float))
    ax.plot(marks[:, 0], marks[:, 1], "k*", ms=12, mec="w", label="cycle (fixed point)")
    handles, _ = ax.get_legend_handles_labels()
    legend = ax.get_legend()
    ax.legend(handles=list(legend.legend_handles) + handles, loc="best", fontsize=8, framealpha=0.8)
    return fig
