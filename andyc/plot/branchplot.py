"""A branch of periodic orbits (`andyc cycle --continue`): the bifurcation diagram (a fixed-point coordinate and
the step time against the parameter, solid where the orbit is stable, dashed where not), the multipliers' moduli
against the parameter, and the multipliers in the complex plane with the unit circle; folds, branch points and
period doublings marked."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from andyc.outputs import write_atomic

COLOURS = ["#1d3557", "#e76f51", "#2a9d8f", "#8d5fd3"]
MARKS = {"period doubling": ("D", "#e63946"), "fold": ("s", "#f4a261"), "branch point": ("^", "#6a4c93")}


def coordinate(result) -> int:
    """The index in y (after the jump) that varies most along the first branch, among the coordinates no symmetry
    moves (a walker's downhill position is arbitrary)."""
    points = result.branches[0].points
    after = np.array([q.after for q in points])
    spread = after.max(axis=0) - after.min(axis=0) if len(points) else np.zeros(len(result.state_names))
    if result.symmetries is not None and result.symmetries.size:
        spread[np.any(np.abs(result.symmetries) > 1e-9, axis=1)] = -1.0
    return int(np.argmax(spread))


def plot_branches(result, out, index: int | None = None) -> None:
    """Write to `out` (PNG) the four panels of the module docstring for result's branches (a Continuation);
    index: the coordinate of y (after the jump) to draw (default: coordinate(result))."""
    names = result.state_names + result.discrete_names
    index = coordinate(result) if index is None else index
    fig = Figure(figsize=(10, 7.5))
    FigureCanvasAgg(fig)
    (diagram, times), (moduli, plane) = fig.subplots(2, 2)
    for i, branch in enumerate(result.branches):
        if not branch.points:
            continue
        colour = COLOURS[i % len(COLOURS)]
        p = np.array([q.parameter for q in branch.points])
        label = f"period {branch.period_count}"
        sequence = list(branch.points)          # the located points in their places: stability changes there
        for sp in sorted(branch.specials, key=lambda sp: -sp.index):
            sequence.insert(sp.index, sp)
        if branch.origin is not None:           # a period-2N branch starts at its doubling: that orbit twice
            o = branch.origin
            twice = replace(o.point, visits=np.vstack([o.point.visits, o.point.visits]),
                            step_times=np.tile(o.point.step_times, 2))
            sequence.insert(0, replace(o, point=twice))
        for j in range(branch.period_count):    # each of the N visits of the section: the tines of a doubling
            for ax, value in ((diagram, lambda q: q.visits[j][index]), (times, lambda q: q.step_times[j])):
                _stability_line(ax, sequence, value, colour, label)
        mods = np.array([np.abs(q.multipliers) for q in branch.points])
        moduli.plot(p, mods, ".-", ms=3, lw=0.8, color=colour)
        mult = np.concatenate([q.multipliers for q in branch.points])
        plane.plot(mult.real, mult.imag, ".", ms=3, color=colour, label=label)
        for sp in branch.specials:
            marker, c = MARKS.get(sp.kind, ("o", "k"))
            for ax, values in ((diagram, sp.point.visits[:, index]), (times, sp.point.step_times)):
                ax.plot([sp.point.parameter] * len(values), values, marker, color=c, ms=7, label=f"{sp.kind}")
            moduli.axvline(sp.point.parameter, color=c, lw=0.8, ls="--")
            plane.plot(sp.point.multipliers.real, sp.point.multipliers.imag, marker, color=c, ms=6)
    t = np.linspace(0, 2 * np.pi, 361)
    plane.plot(np.cos(t), np.sin(t), color="0.6", lw=0.8)
    plane.set_aspect("equal", adjustable="datalim")
    plane.set_xlabel("Re μ")
    plane.set_ylabel("Im μ")
    plane.set_title("multipliers (unit circle grey)", fontsize=9)
    moduli.axhline(1.0, color="0.6", lw=0.8)
    moduli.set_yscale("log")
    moduli.set_xlabel(result.name)
    moduli.set_ylabel("|μ|")
    diagram.set_ylabel(f"{names[index]} just after '{result.section}'")
    times.set_ylabel(f"time between '{result.section}'s, s")
    for ax in (diagram, times):
        ax.set_xlabel(result.name)
        handles, labels = ax.get_legend_handles_labels()
        unique = dict(zip(labels, handles))
        ax.legend(unique.values(), unique.keys(), fontsize=7)
    fig.suptitle(f"{result.model}: periodic orbits through '{result.section}' along {result.name} "
                 f"(solid: stable, dashed: unstable)", fontsize=10)
    fig.tight_layout()
    with write_atomic(out) as tmp:
        fig.savefig(tmp, dpi=110)


def _stability_line(ax, sequence, value, colour, label) -> None:
    """value(q) against the parameter along `sequence` (points, and located points where stability changes),
    solid where the orbit is stable and dashed where not; a segment takes the style of its end that is a point."""
    def stable(entry):
        return None if not hasattr(entry, "stable") else entry.stable

    def at(entry):
        q = entry if hasattr(entry, "stable") else entry.point
        return q.parameter, value(q)

    for first, second in zip(sequence, sequence[1:]):
        s = stable(first) if stable(first) is not None else stable(second)
        (p0, v0), (p1, v1) = at(first), at(second)
        ax.plot([p0, p1], [v0, v1], "-" if s else "--", color=colour, lw=1.2, label=label)
    points = [at(e) for e in sequence if hasattr(e, "stable")]
    ax.plot([p for p, _ in points], [v for _, v in points], ".", color=colour, ms=3)
