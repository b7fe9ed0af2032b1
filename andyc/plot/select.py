"""Steering the plots of a run: a time window (`window`), the signals chosen by name or glob
(`select_signals`), and the axes they share (`group_signals`): one axis per kind of quantity (angles,
lengths, angular speeds, speeds, quaternions, discrete states, inputs, multipliers, energy), split further
where the sizes on one axis differ by more than SCALE_RATIO (a disk's spin of 150 rad beside its lean of
0.2 rad: each gets its own axis, so the lean is not flattened).

Functions of the run only: they draw nothing.
"""

from __future__ import annotations

import dataclasses
from fnmatch import fnmatchcase

import numpy as np

from andyc.runtime.run import Run

SCALE_RATIO = 20.0                  # signals share an axis while the largest span is at most this times theirs
QUATERNION = ("_qw", "_qx", "_qy", "_qz")
POSITION = ("_x", "_y", "_z")
KINDS = {           # kind: (axis label, unit)
    "angles": ("angles", "rad"), "lengths": ("lengths", "m"), "angular_speeds": ("angular speeds", "rad/s"),
    "speeds": ("speeds", "m/s"), "coordinates": ("coordinates", "rad | m"),
    "coordinate_speeds": ("speeds", "rad/s | m/s"), "quaternions": ("quaternion", "1"),
    "positions": ("position signals", "m"), "signals": ("other signals", ""), "discrete": ("discrete states", ""),
    "inputs": ("inputs", ""), "multipliers": ("multipliers λ", "N | N m"), "energy": ("energy", "J"),
}
UNIT_KINDS = {"rad": "angles", "m": "lengths", "rad/s": "angular_speeds", "m/s": "speeds", "1": "quaternions"}


def window(run: Run, t0: float | None = None, t1: float | None = None) -> Run:
    """The run's samples with t0 <= t <= t1 (either end open when None) and the events in that span,
    as a new Run (the arrays are slices: shared, not copied). ValueError if no sample is in it."""
    lo = -np.inf if t0 is None else t0
    hi = np.inf if t1 is None else t1
    if lo > hi:
        raise ValueError(f"the window {t0:g}:{t1:g} ends before it starts")
    keep = np.flatnonzero((run.time >= lo) & (run.time <= hi))
    if len(keep) == 0:
        raise ValueError(f"no sample of the run (t = {run.time[0]:g} .. {run.time[-1]:g} s) lies in the window "
                         f"{'' if t0 is None else f'{t0:g}'}:{'' if t1 is None else f'{t1:g}'}")
    s = slice(keep[0], keep[-1] + 1)
    ev = run.events
    k = (ev["time"] >= lo) & (ev["time"] <= hi)
    return dataclasses.replace(
        run, time=run.time[s], state=run.state[s], energy=run.energy[s],
        frames={name: xyz[s] for name, xyz in run.frames.items()},
        frame_rotations={name: q[s] for name, q in run.frame_rotations.items()}, multipliers=run.multipliers[s],
        residual_position=run.residual_position[s], residual_velocity=run.residual_velocity[s], flow=run.flow[s],
        discrete=run.discrete[s], input_values=run.input_values[s], events={key: v[k] for key, v in ev.items()})


def signal_names(run: Run) -> list:
    """Every signal a plot can show, in this order: states, discrete states, inputs, multipliers, energy."""
    return (list(run.state_names) + list(run.discrete_names) + list(run.input_names) + list(run.multiplier_names)
            + ["energy"])


def select_signals(run: Run, patterns) -> list:
    """The signals (`signal_names`) that match any of `patterns` (names or shell globs: `q*`, `*_dot`,
    `lambda_?`; case-sensitive), in the run's order. ValueError naming a pattern that matches nothing,
    with the names there are."""
    names = signal_names(run)
    chosen = set()
    for pattern in patterns:
        hits = [n for n in names if fnmatchcase(n, pattern)]
        if not hits:
            raise ValueError(f"no signal of this run of {run.model} matches '{pattern}'; its signals: "
                             + ", ".join(names))
        chosen.update(hits)
    return [n for n in names if n in chosen]


def signal_values(run: Run, name: str) -> np.ndarray:
    """The samples of one signal (`signal_names`)."""
    if name == "energy":
        return run.energy
    if name in run.input_names:
        return run.input_values[:, run.input_names.index(name)]
    if name in run.multiplier_names:
        return run.multipliers[:, run.multiplier_names.index(name)]
    return run.column(name)


def signal_kind(run: Run, name: str) -> str:
    """The kind of quantity a signal is (a key of KINDS): from the unit the model gives it
    (Run.display['units'], andyc.spec.display), else from where it sits in the run: coordinates,
    their speeds, quaternion and position signals, discrete states, inputs, multipliers, energy."""
    unit = (run.display or {}).get("units", {}).get(name)
    if unit in UNIT_KINDS:
        return UNIT_KINDS[unit]
    if name == "energy":
        return "energy"
    for kind, names in (("discrete", run.discrete_names), ("inputs", run.input_names),
                        ("multipliers", run.multiplier_names)):
        if name in names:
            return kind
    k = run.state_names.index(name)
    if k < run.nq:
        return "coordinates"
    if k < run.nq + run.nv:
        return "coordinate_speeds"
    if name.endswith(QUATERNION):
        return "quaternions"
    return "positions" if name.endswith(POSITION) else "signals"


def group_signals(run: Run, names) -> list:
    """[(kind, [names])]: one group per kind (`signal_kind`), in the order kinds first appear among
    `names`, each split by `split_by_scale`; a kind split in n parts gives n groups of that kind."""
    kinds = {}
    for name in names:
        kinds.setdefault(signal_kind(run, name), []).append(name)
    return [(kind, part) for kind, members in kinds.items() for part in split_by_scale(run, members)]


def split_by_scale(run: Run, names: list) -> list:
    """`names` split into lists that share an axis: taken by decreasing span (max - min over the run,
    NaN ignored), each signal joins the first list where the axis's range (over the list and it) stays
    within SCALE_RATIO times the smallest span on it, so that no line on an axis is flattened more than
    that; else it starts a list. A constant (no span) that fits nowhere goes with the other constants
    (one axis for them all). Each list keeps the run's order."""
    ranges = {}
    for name in names:
        v = signal_values(run, name)
        v = v[np.isfinite(v)]
        ranges[name] = (float(v.min()), float(v.max())) if len(v) else (0.0, 0.0)
    span = {name: hi - lo for name, (lo, hi) in ranges.items()}
    parts, constants = [], []

    def fits(part, name):
        members = part + [name]
        lo = min(ranges[n][0] for n in members)
        hi = max(ranges[n][1] for n in members)
        smallest = min((span[n] for n in members if span[n] > 0), default=0.0)
        return hi - lo <= SCALE_RATIO * smallest

    for name in sorted(names, key=lambda n: -span[n]):
        part = next((p for p in parts if fits(p, name)), None)
        if part is not None:
            part.append(name)
        elif span[name] > 0:
            parts.append([name])
        else:
            constants.append(name)
    order = {name: k for k, name in enumerate(names)}
    return [sorted(part, key=order.get) for part in parts + ([constants] if constants else [])]


def axis_label(kind: str) -> str:
    """The y label of an axis of a kind: 'angles, rad'."""
    label, unit = KINDS[kind]
    return f"{label}, {unit}" if unit else label
