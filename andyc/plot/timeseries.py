"""The figure of a run against time: `figure_for(run)` builds it, `plot_run(run, out)` saves it.

Panels, each only when it applies, each an axes whose gid names it: the world trajectories of the
logged frames in 3-D ('trajectories', as Fig. 6 of the ANDY paper shows the ends of the swing bar)
and their x, y, z against time ('frame_x', 'frame_y', 'frame_z'; a world axis along which no frame
moves is left out), coordinates ('coordinates'), speeds ('speeds'), quaternion signals
('quaternions'), position signals ('position_signals'), other signals ('other_signals'), inputs
that change ('inputs'), multipliers and constraint residuals ('multipliers', 'residuals'), energy
and its relative change ('energy', 'energy_change'). A hybrid run (more than one flow, or any jump)
also gets, at the top of the time series, the active flow against time with the jumps marked
('flow'), and its discrete states against time ('discrete', as Fig. 10 of the paper).
"""

from __future__ import annotations

from functools import partial

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from andyc.outputs import write_atomic
from andyc.plot.scene import frame_plane, is_hybrid
from andyc.plot.select import axis_label, group_signals, signal_values
from andyc.runtime.run import Run

QUATERNION = ("_qw", "_qx", "_qy", "_qz")
POSITION = ("_x", "_y", "_z")


def plot_run(run: Run, out, signals=None) -> None:
    """Write the figure of `run` to `out` (PNG): `figure_for(run, signals)`."""
    with write_atomic(out) as tmp:
        figure_for(run, signals).savefig(tmp, dpi=110)


def figure_for(run: Run, signals=None) -> Figure:
    """Frame trajectories on the left (in 3-D; in their plane for a planar model), energy below them,
    time series on the right; without frames, one column of time series. With `signals` (names of
    andyc.plot.select.signal_names), only those, one axis per group (`group_signals`; gid
    'signals:KIND', 'signals:KIND#2' for a second scale), below the flow panel of a hybrid run. On an
    Agg canvas of its own (no pyplot)."""
    if signals is not None:
        return _signals_figure(run, list(signals))
    series = _series_panels(run)
    energy = [("energy", _energy), ("energy_change", _energy_change)]
    if run.frames:
        fig = Figure(figsize=(16, max(10, 1.8 * len(series))), layout="constrained")
        grid = fig.add_gridspec(1, 2, width_ratios=[1, 1.1])
        left = grid[0].subgridspec(3, 1, height_ratios=[5, 1.5, 1.5])
        plane = frame_plane(run)
        if plane:
            _plane_trajectories(fig.add_subplot(left[0], gid="trajectories"), run, plane)
        else:
            _trajectories(fig.add_subplot(left[0], projection="3d", gid="trajectories"), run)
        right = grid[1].subgridspec(len(series), 1, height_ratios=[_height(gid, run) for gid, _ in series])
        axes = _time_axes(fig, right, series, run)
        _time_axes(fig, [left[1], left[2]], energy, run, sharex=axes[0])
    else:
        panels = series + energy
        ratios = [3 * _height(gid, run) for gid, _ in series] + [2, 2]
        fig = Figure(figsize=(10, 0.75 * sum(ratios) + 1), layout="constrained")
        _time_axes(fig, fig.add_gridspec(len(panels), 1, height_ratios=ratios), panels, run)
    fig.suptitle(f"{run.model}: {run.method}, dt = {run.dt:g} s, {run.status}")
    FigureCanvasAgg(fig)
    return fig


def _series_panels(run: Run) -> list:
    """[(gid, draw)]: the panels of the right-hand (or only) column, top to bottom."""
    panels = []
    if is_hybrid(run):
        panels.append(("flow", _flows))
    if run.discrete_names:
        panels.append(("discrete", _discrete))
    panels += [(f"frame_{'xyz'[k]}", partial(_frame_axis, k=k)) for k in range(3) if _moves(run.frames, k)]
    if run.nq:          # a free body has speeds and signals only
        panels += _grouped("coordinates", run, run.state_names[:run.nq], "coordinates q, rad | m")
    panels += _grouped("speeds", run, run.state_names[run.nq:run.nq + run.nv], "speeds v, rad/s | m/s")
    quaternions, positions, others = _signal_groups(run.signal_names)
    if quaternions:
        panels.append(("quaternions", partial(_quaternions, bases=quaternions)))
    for gid, names, ylabel in (("position_signals", positions, "position signals, m"),
                               ("other_signals", others, "other signals")):
        if names:
            panels.append((gid, partial(_states, cols=[run.state_names.index(n) for n in names], ylabel=ylabel)))
    if run.input_names and len(run.time) and np.ptp(run.input_values, axis=0).max() > 0:
        panels.append(("inputs", _inputs))      # inputs that change (driven, or set by flows)
    if run.contact_names:
        panels.append(("contacts", _contacts))
    if run.multiplier_names:
        panels += [("multipliers", _multipliers), ("residuals", _residuals)]
    return panels


def _grouped(gid: str, run: Run, names: list, ylabel: str) -> list:
    """[(gid, draw)]: the panel of `names` (gid, `ylabel`), or, where they fall into several groups
    (`group_signals`: angles apart from lengths, a spin apart from a lean), a panel per group, gid
    'GID:KIND' ('GID:KIND#2' for a kind's second scale; 'GID#2' where the run does not say the kind)."""
    groups = group_signals(run, names)
    if len(groups) == 1:
        return [(gid, partial(_named, names=names, ylabel=ylabel))]
    generic = ("coordinates", "coordinate_speeds")
    return [(gid + ("" if kind in generic else f":{kind}") + (f"#{n}" if n > 1 else ""),
             partial(_named, names=members, ylabel=ylabel if kind in generic else axis_label(kind)))
            for kind, members, n in _numbered(groups)]


def _numbered(groups: list) -> list:
    """[(kind, members, n)]: n counts the groups of one kind (1, 2, ...)."""
    seen = {}
    out = []
    for kind, members in groups:
        seen[kind] = seen.get(kind, 0) + 1
        out.append((kind, members, seen[kind]))
    return out


def _signals_figure(run: Run, names: list) -> Figure:
    """The figure of chosen signals: a hybrid run's flow panel, then one axis per group."""
    panels = [("flow", _flows)] if is_hybrid(run) else []
    for kind, members, n in _numbered(group_signals(run, names)):
        draw = partial(_named, names=members, ylabel=axis_label(kind), steps=kind == "discrete")
        panels.append((f"signals:{kind}" + (f"#{n}" if n > 1 else ""), draw))
    ratios = [3 * _height(gid, run) for gid, _ in panels]
    fig = Figure(figsize=(10, 0.75 * sum(ratios) + 1.5), layout="constrained")
    _time_axes(fig, fig.add_gridspec(len(panels), 1, height_ratios=ratios), panels, run)
    span = f"t = {run.time[0]:g} .. {run.time[-1]:g} s"
    shown = ", ".join(names) if len(names) <= 6 else f"{len(names)} signals"
    fig.suptitle(f"{run.model}: {shown} ({span}; {run.method}, dt = {run.dt:g} s)")
    FigureCanvasAgg(fig)
    return fig


def _height(gid: str, run: Run) -> float:
    """Relative height of a time-series panel: the flow panel (unless there are many flows) and the
    discrete panel are shorter."""
    if gid == "flow":
        return min(0.5 + 0.1 * len(run.flow_names), 1.0)
    return 0.7 if gid == "discrete" else 1.0


def _time_axes(fig, specs, panels, run, sharex=None) -> list:
    """One axes per (gid, draw) panel down `specs`, sharing the time axis; only the bottom one labels it."""
    axes = []
    for spec, (gid, draw) in zip(specs, panels):
        ax = fig.add_subplot(spec, sharex=sharex or (axes[0] if axes else None), gid=gid)
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


def _plane_trajectories(ax, run: Run, plane: tuple) -> None:
    """A planar model's frame paths in their plane (world axes i, j), start and end marked, equal axes."""
    i, j = plane
    for c, (name, xyz) in enumerate(_frame_paths(run.frames)):
        ax.plot(xyz[:, i], xyz[:, j], color=f"C{c}", lw=0.8, label=name)
        ax.scatter(xyz[0, i], xyz[0, j], color=f"C{c}", marker="o", s=30)
        ax.scatter(xyz[-1, i], xyz[-1, j], color=f"C{c}", marker="s", s=30)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel(f"world {'xyz'[i]}, m")
    ax.set_ylabel(f"world {'xyz'[j]}, m")
    ax.grid(alpha=0.3)
    ax.set_title(f"frame trajectories in the world {'xyz'[i]}-{'xyz'[j]} plane (● start, ■ end)")
    ax.legend(loc="upper left", fontsize="small")


def _frame_axis(ax, run: Run, k: int) -> None:
    for i, (name, xyz) in enumerate(_frame_paths(run.frames)):
        ax.plot(run.time, xyz[:, k], color=f"C{i}", lw=1, label=name)
    ax.set_ylabel(f"frame {'xyz'[k]}, m")
    _legend(ax)


def _lines(ax, run: Run, values, names, ylabel: str) -> None:
    """One line per column of values (samples x names) against time, labelled by name."""
    for j, name in enumerate(names):
        ax.plot(run.time, values[:, j], lw=1, label=name)
    ax.set_ylabel(ylabel)
    _legend(ax)


def _named(ax, run: Run, names: list, ylabel: str, steps: bool = False) -> None:
    """One line per signal (andyc.plot.select.signal_values) against time; steps for discrete states."""
    for name in names:
        ax.plot(run.time, signal_values(run, name), lw=1, label=name, drawstyle="steps-post" if steps else "default")
    ax.set_ylabel(ylabel)
    _legend(ax)


def _states(ax, run: Run, cols, ylabel: str) -> None:
    cols = list(cols)
    _lines(ax, run, run.state[:, cols], [run.state_names[j] for j in cols], ylabel)


def _inputs(ax, run: Run) -> None:
    _lines(ax, run, run.input_values, run.input_names, "inputs u")


def _quaternions(ax, run: Run, bases: list) -> None:
    """Components w, x, y, z in fixed colours; one line style per quaternion."""
    for b, style in zip(bases, ["-", "--", ":", "-."] * len(bases)):
        for c, s in enumerate(QUATERNION):
            ax.plot(run.time, run.column(b + s), color=f"C{c}", ls=style, lw=1, label=b + s)
    ax.set_ylabel("quaternion (w, x, y, z), 1")
    _legend(ax)


def _contacts(ax, run: Run) -> None:
    """Each contact's normal force (0 while open), and the spans where it is closed shaded in its colour; with
    friction its friction force along +tangent too, dashed in the same colour (spatial friction: along the second
    tangent dotted)."""
    closed, force, friction = run.contact_closed, run.normal_forces, run.friction_forces
    for i, name in enumerate(run.contact_names):
        ax.plot(run.time, force[:, i], color=f"C{i}", lw=1, label=f"normal force {name}")
        if i in run.frictional:
            ax.plot(run.time, friction[:, i], color=f"C{i}", lw=1, ls="--", label=f"friction force {name}")
        if run.contact_tangents[i] == 2:
            ax.plot(run.time, run.friction_forces_2[:, i], color=f"C{i}", lw=1, ls=":",
                    label=f"friction force {name}, 2nd tangent")
        ax.fill_between(run.time, 0, 1, where=closed[:, i] == 1, step="post", color=f"C{i}", alpha=0.12,
                        transform=ax.get_xaxis_transform(), lw=0)
    ax.set_ylabel("contacts: normal" + (" and friction" if run.frictional else "") + " force, N")
    _legend(ax)


def _multipliers(ax, run: Run) -> None:
    _lines(ax, run, run.multipliers, run.multiplier_names, "multipliers λ, N | N m")


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
    """E; with elements that do work (dampers, friction, inputs, jumps), also E(0) + W, which E follows."""
    ax.plot(run.time, run.energy, color="k", lw=1, label="E")
    if run.work_names:
        ax.plot(run.time, run.energy[0] + run.work.sum(axis=1), color="tab:blue", lw=1, ls="--", label="E(0) + W")
        _legend(ax)
    ax.set_ylabel("energy E, J")
    ax.ticklabel_format(axis="y", useOffset=False)


def _energy_change(ax, run: Run) -> None:
    """The energy balance E - E(0) - W in J where elements do work (the residual the run's summary reports:
    0 but for the integration's error), else the relative change of a conserved E."""
    if run.work_names:
        ax.plot(run.time, run.energy_balance, color="tab:red", lw=0.8, label="E - E(0) - W")
        ax.set_ylabel("balance E - E(0) - W, J")
        return
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
