"""A sweep's result store: one Zarr store (format 2) that xarray opens as a labelled dataset.

    ds = xarray.open_zarr("walk.zarr")

Dimensions: a grid's swept names (its coordinates, the grid's values), or `point` for samples and CSV rows
(the swept names are then coordinates along it); `state`, `discrete`, `jump` (their names), `event` (the
first jumps of a run) and `time` (the times of the kept trajectories, a coordinate: plots are over time).
Variables, per point:

    outcome          0 not run, 1 finished, 2 stopped, 3 blew up, 4 Zeno, 5 failed (flag_meanings names them)
    message          the run's status, or why it failed (a variable-length string, whole)
    t_final          the time the run reached
    final            the final state (state), final_discrete (discrete), final_flow (the flow's index)
    jump_count       how many times each jump happened (jump)
    event_time       the times of the first jumps (event; NaN past the last), event_jump their jump's index
    wall, cpu        seconds the point took on its worker: wall-clock time, and the CPU time of its thread
    <metric>         each --metric, by its name
    trajectory       the state at the `time` coordinate's N evenly spaced times, with --trajectory N;
                     trajectory_time: those the run reached (NaN past its end)
    basin            a basin's class of each point (andyc.analysis.basins: 1 cycle, 2 other orbit, 3 falls,
                     4 other), with basin_period, basin_steps and basin_distance; the run variables are
                     then those of the point's last step (t_final: the time of all its steps)

Variables and coordinates carry CF's `long_name` and, where andyc knows them (times), `units`; the time
coordinate `standard_name` and `axis`. Attributes name the model, its build key and andyc's version, the sweep's points (their SHA-256, the kind,
the seed) and the run options; a store made by another model, build or version, or for other points or
options, is refused. The store is made whole (in a temporary folder, then renamed); results are written as
each batch of points completes (Zarr writes each chunk file atomically), `outcome` last, so that a point
counts as done only once all its results are in.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import andyc
from andyc.analysis.sweeps.points import Points
from andyc.analysis.sweeps.worker import MESSAGE_CHARS, Settings, empty_results, sample_times
from andyc.outputs import OutputError, check_folder, new_folder_atomic
from andyc.runtime.status import OUTCOMES

CHUNK_VALUES = 1 << 18          # at most this many values in a chunk (2 MB of floats)
CHUNK_POINTS = 4096             # at most this many points in a chunk
# Names of the store's own variables and dimensions, which a metric or a swept name must not take.
RESERVED = ("outcome", "message", "t_final", "final", "final_discrete", "final_flow", "jump_count", "event_time",
            "event_jump", "wall", "cpu", "trajectory", "trajectory_time", "point", "state", "discrete", "jump", "event",
            "time", "basin", "basin_period", "basin_steps", "basin_distance")
# CF attributes of the store's own variables: (long_name, units); units only where andyc knows them (a
# model's states and parameters carry none)
DESCRIPTIONS = {
    "outcome": ("outcome of the run", None), "message": ("status of the run, or why it failed", None),
    "t_final": ("time the run reached", "s"), "final": ("final state", None),
    "final_discrete": ("final discrete state", None), "final_flow": ("index of the final flow", None),
    "jump_count": ("number of occurrences of each jump", "1"), "event_time": ("time of the first jumps", "s"),
    "event_jump": ("index of the jump at event_time", None), "wall": ("wall-clock time the point took", "s"),
    "cpu": ("CPU time of the point's thread", "s"), "trajectory": ("state at the sampled times", None),
    "trajectory_time": ("sampled time reached by the run (NaN past its end)", "s"),
    "basin": ("class of the orbit", None), "basin_period": ("period of the cycle, in steps", "1"),
    "basin_steps": ("steps taken", "1"), "basin_distance": ("distance to the cycle at the last step", None)}
KINDS = {"parameter": "parameter", "input": "held input", "state": "initial value of the state"}


class StoreError(ValueError):
    """A store that cannot be used: another model's, another sweep's, or not a sweep store."""


def check_names(points: Points, settings: Settings) -> None:
    """StoreError when a swept name or a metric takes the name of one of the store's variables, or a metric
    a swept name."""
    for name in points.names + tuple(m for m, _ in settings.metrics):
        if name in RESERVED:
            raise StoreError(f"'{name}' is the name of the store's own variable; rename the metric (or sweep "
                             f"another name)")
    clash = set(points.names) & {m for m, _ in settings.metrics}
    if clash:
        raise StoreError(f"the metric '{clash.pop()}' has the name of a swept name; rename the metric")


def attributes(model, points: Points, settings: Settings) -> dict:
    return {"Conventions": "CF-1.10", "andyc_version": andyc.__version__, "model": model.name, "build_key": settings.build_key,
            "spec_sha256": model.spec_sha256, "source": model.source, "kind": points.kind,
            "swept": list(points.names), "points_sha256": points.digest(),
            "seed": -1 if points.seed is None else int(points.seed), "sampler": points.sampler or "",
            "options": json.dumps(settings.options()),
            "outcomes": json.dumps(OUTCOMES)}


def open_store(path, model, points: Points, settings: Settings, inputs=()) -> np.ndarray:
    """Create the store at path, or check the one there; returns the done mask of the points (flat)."""
    import zarr

    path = Path(path)
    if not path.exists():
        check_folder(path.parent, inputs)
        with new_folder_atomic(path) as tmp:
            write_layout(tmp, layout(model, points, settings), _encoding(model, points, settings))
        return np.zeros(points.n, dtype=bool)
    if not path.is_dir():
        raise OutputError(f"{path}: is a file, not a result store; give a new name ending in .zarr")
    try:
        group = zarr.open_group(str(path), mode="r")
        found = dict(group.attrs)
    except Exception:
        raise StoreError(f"{path}: not a sweep's result store; give a new name (-o), or delete it") from None
    check_attributes(path, found, attributes(model, points, settings))
    return np.asarray(group["outcome"][...]).reshape(-1) != 0


def check_attributes(path, found: dict, want: dict) -> None:
    """StoreError naming what differs between a store's attributes and this sweep's."""
    if "build_key" not in found or "andyc_version" not in found:
        raise StoreError(f"{path}: not a sweep's result store; give a new name (-o), or delete it")
    if (found["model"], found["build_key"], found["andyc_version"]) != (want["model"], want["build_key"],
                                                                       want["andyc_version"]):
        raise StoreError(f"{path}: made by another model or version (model {found['model']}, build "
                         f"{found['build_key'][:12]}, andyc {found['andyc_version']}; this sweep: model "
                         f"{want['model']}, build {want['build_key'][:12]}, andyc {want['andyc_version']}); write to "
                         f"another store (-o), or delete it to start again")
    for key, what in (("points_sha256", "other points"), ("options", "other run options or metrics")):
        if found.get(key) != want[key]:
            raise StoreError(f"{path}: holds a sweep of {model_name(found)} with {what}; resuming needs the same "
                             f"command: write to another store (-o), or delete it to start again")


def model_name(attrs: dict) -> str:
    return str(attrs.get("model", "?"))


def write_batch(path, points: Points, settings: Settings, results: dict) -> None:
    """Write a completed batch's results (worker.run_batch) into the store, `outcome` last."""
    import zarr

    group = zarr.open_group(str(path), mode="r+")
    index = points.index(results["index"])
    for name, values in _variables(settings, results).items():
        _set(group[name], index, values)
    _set(group["outcome"], index, results["outcome"])


def _variables(settings: Settings, results: dict) -> dict:
    out = {k: results[k] for k in ("message", "t_final", "final", "final_flow", "wall", "cpu")}
    if results["final_discrete"].shape[1]:
        out["final_discrete"] = results["final_discrete"]
    if results["jump_count"].shape[1]:         # (a model without jumps has no jump to count or time)
        out.update({k: results[k] for k in ("jump_count", "event_time", "event_jump")})
    for j, (name, _) in enumerate(settings.metrics):
        out[name] = results["metrics"][:, j]
    if settings.trajectory:
        out["trajectory"], out["trajectory_time"] = results["trajectory"], results["trajectory_time"]
    if settings.basin is not None:
        out.update({k: results[k] for k in ("basin", "basin_period", "basin_steps", "basin_distance")})
    return out


def _set(array, index: tuple, values: np.ndarray) -> None:
    """array[index[0][i], index[1][i], ..., :, :] = values[i] for every point i (a coordinate selection, with
    the array's trailing dimensions spelled out)."""
    values = np.asarray(values)
    extra = array.shape[len(index):]
    n = len(index[0])
    spread = [np.broadcast_to(np.reshape(i, (n,) + (1,) * len(extra)), (n,) + extra).ravel() for i in index]
    rest = [np.broadcast_to(g, (n,) + extra).ravel() for g in np.meshgrid(*map(np.arange, extra), indexing="ij")]
    array.set_coordinate_selection(tuple(spread + rest), values.reshape(-1).astype(array.dtype, copy=False))


def _point_dims(points: Points) -> tuple:
    return points.names if points.kind == "grid" else ("point",)


@dataclass
class Layout:
    """The store before any point ran, as an xarray Dataset would hold it: `variables` (name -> (dims, values,
    attrs)), the names among them that are `coordinates`, and the global `attrs`."""
    variables: dict
    coordinates: tuple
    attrs: dict


def layout(model, points: Points, settings: Settings) -> Layout:
    """The store's variables, every point not run (its arrays filled with NaN, -1 or 0), and its coordinates."""
    dims = _point_dims(points)
    empty = empty_results(model, settings, 1)
    extra = {"final": ("state",), "final_discrete": ("discrete",), "jump_count": ("jump",), "event_time": ("event",),
             "event_jump": ("event",), "trajectory": ("time", "state"), "trajectory_time": ("time",)}
    described = {n: {"long_name": ln, **({"units": u} if u else {})} for n, (ln, u) in DESCRIPTIONS.items()}
    metrics = {n: {"expression": text, "long_name": f"metric {n} = {text}"} for n, text in settings.metrics}
    variables = {}
    for name, one in _variables(settings, empty).items():
        shape = points.shape + one.shape[1:]
        variables[name] = (dims + extra.get(name, ()), np.broadcast_to(one.reshape(one.shape[1:]), shape).copy(),
                           dict(described.get(name, metrics.get(name, {}))))
    variables["message"][2]["max_characters"] = MESSAGE_CHARS
    variables["outcome"] = (dims, np.zeros(points.shape, np.int8), {
        "flag_values": list(OUTCOMES), "flag_meanings": " ".join(o.replace(" ", "_") for o in OUTCOMES.values()),
        **described["outcome"]})
    if settings.basin is not None:
        from andyc.analysis.basins import CLASSES

        variables["basin"][2].update({"flag_values": list(CLASSES), "flag_meanings": " ".join(
            c.replace(" ", "_") for c in CLASSES.values()), **described["basin"]})
    coords = {k: ((k,), np.array(v), {}) for k, v in (("state", model.state_names), ("jump", model.jump_names),
                                                     ("discrete", model.discrete_names)) if len(v)}
    if settings.trajectory:         # the sampled times as the dimension's coordinate: plots over time
        coords["time"] = (("time",), sample_times(settings),
                          {"standard_name": "time", "long_name": "time", "units": "s", "axis": "T"})
    long_names = {name: {"long_name": f"{KINDS[kind]} {name}"} for name, (kind, _) in zip(points.names, settings.kinds)}
    if points.kind == "grid":
        coords.update({n: ((n,), np.asarray(axis), long_names[n]) for n, axis in zip(points.names, points.axes)})
    else:
        coords["point"] = (("point",), np.arange(points.n), {})
        coords.update({n: (("point",), points.values[:, k].copy(), long_names[n]) for k, n in enumerate(points.names)})
    return Layout({**variables, **coords}, tuple(coords), attributes(model, points, settings))


def write_layout(path, layout: Layout, encoding: dict) -> None:
    """Write `layout` into a new Zarr store (format 2) as xarray's Dataset.to_zarr(zarr_format=2, consolidated=True)
    writes the same Dataset: each array's dimensions in its `_ARRAY_DIMENSIONS` attribute, a data variable's
    non-dimension coordinates named in its `coordinates` attribute (CF), NaN the fill value of floats, text of
    variable length as vlen-utf8 and names as fixed-width unicode, the metadata consolidated; encoding: each
    variable's chunks. Not through xarray: its import, and its checks of every array for a dask array (which
    import dask.array), take over a second before a first result can be stored; tests/test_sweep.py checks that
    the two write the same store."""
    import zarr

    group = zarr.open_group(str(path), mode="w", zarr_format=2, attributes=layout.attrs)
    auxiliary = [n for n in layout.coordinates if layout.variables[n][0] != (n,)]
    for name, (dims, values, attrs) in layout.variables.items():
        attrs = dict(attrs)
        named = sorted(c for c in auxiliary if name not in layout.coordinates and name not in dims
                       and set(layout.variables[c][0]) <= set(dims))
        if named:
            attrs["coordinates"] = " ".join(named)
        attrs["_ARRAY_DIMENSIONS"] = list(dims)
        text = values.dtype == object
        array = group.create_array(name, shape=values.shape, dtype=str if text else values.dtype,
                                   chunks=encoding.get(name, {}).get("chunks", "auto"),
                                   fill_value=math.nan if values.dtype.kind == "f" else None, attributes=attrs)
        array[...] = values
    zarr.consolidate_metadata(str(path), zarr_format=2)


def _encoding(model, points: Points, settings: Settings) -> dict:
    """Chunks: whole along the trailing dimensions; along the points, at most CHUNK_POINTS points and
    CHUNK_VALUES values a chunk (the first grid axes split first)."""
    empty = empty_results(model, settings, 1)
    out = {}
    for name, one in {**_variables(settings, empty), "outcome": empty["outcome"]}.items():
        trailing = one.shape[1:]
        budget = max(1, min(CHUNK_POINTS, CHUNK_VALUES // max(1, math.prod(trailing))))
        chunks = []
        for size in reversed(points.shape):     # the last grid axes whole as far as the budget goes
            take = max(1, min(size, budget))
            chunks.insert(0, take)
            budget = max(1, budget // take)
        out[name] = {"chunks": tuple(chunks) + tuple(max(1, s) for s in trailing)}
    return out
