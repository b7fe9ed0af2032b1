"""A run's files: HDF5 and CSV written and read back, and a run file checked before use (their layout:
docs/run-file.md)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from andyc.errors import printable
from andyc.outputs import write_atomic
from andyc.runtime.run import Run

RUN_SUFFIXES = (".h5", ".hdf5", ".csv")
MAX_ATTRIBUTE = 32_000      # characters of an HDF5 attribute at most (its object header holds 64 kB in all)



def save_run(run: Run, path) -> Path:
    """Write the run to path (.h5 or .csv; a CSV of a hybrid model also writes its events beside it,
    see events_csv_path), each file under a temporary name renamed into place (andyc.outputs), so an
    interrupted write never leaves a truncated run file. ValueError for another suffix."""
    path = Path(path)
    kind = path.suffix.lower()
    if kind not in RUN_SUFFIXES:
        raise ValueError(f"unknown run file type '{path.suffix}'; use .h5 or .csv")
    with write_atomic(path) as tmp:
        (write_h5 if kind in (".h5", ".hdf5") else write_csv)(run, tmp)
    if kind == ".csv" and run.jump_names:
        with write_atomic(events_csv_path(path)) as tmp:
            write_events_csv(run, tmp)
    return path


def write_h5(run: Run, path: Path) -> None:
    import h5py

    with h5py.File(path, "w") as f:
        for key, value in run.attributes().items():
            if key == "display" and len(value) > MAX_ATTRIBUTE:     # a robot's many shapes: as a dataset
                f["display"] = value
            else:
                f.attrs[key] = value
        f["time"] = run.time
        f["state"] = run.state
        f["state"].attrs["names"] = run.state_names
        f["flow"] = run.flow.astype(np.int32)
        f["flow"].attrs["names"] = run.flow_names
        f["discrete"] = run.discrete
        f["discrete"].attrs["names"] = run.discrete_names
        f["inputs"] = run.input_values
        f["inputs"].attrs["names"] = run.input_names
        f["multipliers"] = run.multipliers
        f["multipliers"].attrs["names"] = run.multiplier_names
        f["residual/position"] = run.residual_position
        f["residual/velocity"] = run.residual_velocity
        f["energy"] = run.energy
        f["work"] = run.work
        f["work"].attrs["names"] = run.work_names
        f["power"] = run.power
        f["energy_balance"] = run.energy_balance
        for name, xyz in run.frames.items():
            f[f"frames/{name}"] = xyz
        for name, wxyz in run.frame_rotations.items():
            f[f"frame_rotations/{name}"] = wxyz
        # The shapes' mesh files go in whole (compressed), so that andyc view needs only the run file.
        files = dict.fromkeys(s["file"] for s in run.display.get("shapes", []) if s["kind"] == "mesh")
        for k, file in enumerate(files):
            data = run.mesh_bytes(file)
            if data is not None:
                f.create_dataset(f"meshes/{k}", data=np.frombuffer(data, dtype=np.uint8), compression="gzip")
                f[f"meshes/{k}"].attrs["file"] = file
        if run.contact_names:
            f["contacts/closed"] = run.contact_closed
            f["contacts/normal_force"] = run.normal_forces
            f["contacts"].attrs["names"] = run.contact_names
            if run.frictional:      # modes 0 open, 1 closed / stick, 2 / 3 slipping forwards / backwards
                f["contacts/mode"] = run.contact_modes
                f["contacts/friction_force"] = run.friction_forces
                f["contacts/slip_speed"] = run.slip_speeds
                if 2 in run.contact_tangents:       # spatial friction: the second tangent's
                    f["contacts/friction_force_2"] = run.friction_forces_2
                    f["contacts/slip_speed_2"] = run.slip_speeds_2
        ev = run.events
        table = np.zeros(len(ev["time"]), dtype=[("time", "f8"), ("jump", h5py.string_dtype()),
                                                 ("from_flow", "i4"), ("to_flow", "i4")])
        table["time"], table["from_flow"], table["to_flow"] = ev["time"], ev["from_flow"], ev["to_flow"]
        table["jump"] = run.event_names()
        f.create_dataset("events", data=table, maxshape=(None,))
        for key in ("state_before", "state_after", "discrete_after"):
            f[f"event_states/{key}"] = ev[key]
        if run.sensitivities is not None:       # dx(T)/dx0, dx(T)/dd0, dx(T)/dp, dT/dz, dd(T)/dz
            for key, value in run.sensitivities.items():
                f[f"sensitivities/{key}"] = value


def read_h5(path) -> Run:
    import h5py

    with h5py.File(path, "r") as f:
        a = dict(f.attrs)
        frames = {name: f["frames"][name][()] for name in f["frames"]} if "frames" in f else {}
        rotations = ({name: f["frame_rotations"][name][()] for name in f["frame_rotations"]}
                     if "frame_rotations" in f else {})          # run files before andyc logged rotations: none
        contacts = json.loads(a.get("contacts", '{"names": [], "rows": []}'))
        jump_names = json.loads(a.get("jump_names", "[]"))
        table = f["events"][()]
        events = {"time": table["time"], "jump": np.array([jump_names.index(j.decode() if isinstance(j, bytes) else j)
                                                           for j in table["jump"]], dtype=np.int32),
                  "from_flow": table["from_flow"], "to_flow": table["to_flow"]}
        meshes = {str(d.attrs["file"]): d[()].tobytes() for d in f["meshes"].values()} if "meshes" in f else {}
        display = a.get("display") or (f["display"].asstr()[()] if "display" in f else "{}")
        if "event_states" in f:
            events.update({key: f["event_states"][key][()] for key in f["event_states"]})
        return Run(model=a["model"], spec_sha256=a["spec_sha256"], method=a["method"], dt=float(a["dt"]),
                   nq=int(a["nq"]), nv=int(a["nv"]),
                   rtol=float(a["rtol"]), atol=float(a["atol"]), t_end=float(a["t_end"]),
                   parameters=json.loads(a["parameters"]), inputs=json.loads(a.get("inputs", "{}")),
                   state_names=[str(s) for s in f["state"].attrs["names"]], time=f["time"][()],
                   state=f["state"][()], energy=f["energy"][()], frames=frames, frame_rotations=rotations,
                   status=str(a["status"]),
                   stats=json.loads(a.get("stats", "{}")), andyc_version=str(a["andyc_version"]),
                   multiplier_names=[str(s) for s in f["multipliers"].attrs["names"]],
                   multipliers=f["multipliers"][()], residual_position=f["residual/position"][()],
                   residual_velocity=f["residual/velocity"][()],
                   energy_correction=bool(a.get("energy_correction", False)),
                   flow=f["flow"][()].astype(np.int64), flow_names=json.loads(a.get("flow_names", '["default"]')),
                   discrete_names=[str(s) for s in f["discrete"].attrs["names"]] if "discrete" in f else [],
                   discrete=f["discrete"][()] if "discrete" in f else None, events=events, jump_names=jump_names,
                   input_names=[str(s) for s in f["inputs"].attrs["names"]] if "inputs" in f else [],
                   input_values=f["inputs"][()] if "inputs" in f else None,
                   frame_parents=json.loads(a.get("frame_parents", "{}")), display=json.loads(display),
                   contact_names=contacts["names"], contact_rows=contacts["rows"], meshes=meshes, meshes_on_disk=False,
                   work_names=[str(s) for s in f["work"].attrs["names"]] if "work" in f else [],
                   work=f["work"][()] if "work" in f else None, power=f["power"][()] if "power" in f else None,
                   contact_stick_rows=contacts.get("stick_rows", []),
                   contact_mu=[math.nan if m is None else m for m in contacts.get("mu", [])],
                   slip_speeds=f["contacts/slip_speed"][()] if "contacts/slip_speed" in f else None,
                   contact_tangents=contacts.get("tangents", []),
                   slip_speeds_2=f["contacts/slip_speed_2"][()] if "contacts/slip_speed_2" in f else None,
                   sensitivities={k: f["sensitivities"][k][()] for k in f["sensitivities"]}
                   if "sensitivities" in f else None)


def write_csv(run: Run, path: Path) -> None:
    """The time series as columns, the attributes as `# key: value` lines first (one line each: see
    Run.attributes)."""
    header = [f"# {k}: {v}" for k, v in run.attributes().items()]
    columns = (["time"] + list(run.state_names) + list(run.discrete_names) + list(run.input_names) + ["flow", "energy"]
               + list(run.multiplier_names)
               + [f"phi_{m}" for m in run.multiplier_names[:run.residual_position.shape[1]]]
               + [f"c_{m}" for m in run.multiplier_names])
    data = [run.time[:, None], run.state, run.discrete, run.input_values, run.flow[:, None], run.energy[:, None],
            run.multipliers, run.residual_position, run.residual_velocity]
    if run.work_names:
        columns += ([f"power_{w}" for w in run.work_names] + [f"work_{w}" for w in run.work_names]
                    + ["energy_balance"])
        data += [run.power, run.work, run.energy_balance[:, None]]
    if run.contact_names:
        columns += [f"closed_{c}" for c in run.contact_names] + [f"normal_force_{c}" for c in run.contact_names]
        data += [run.contact_closed, run.normal_forces]
        friction = run.frictional
        if friction:
            names = [run.contact_names[i] for i in friction]
            columns += ([f"mode_{c}" for c in names] + [f"friction_force_{c}" for c in names]
                        + [f"slip_speed_{c}" for c in names])
            data += [run.contact_modes[:, friction], run.friction_forces[:, friction], run.slip_speeds[:, friction]]
            spatial = [i for i in friction if run.contact_tangents[i] == 2]
            if spatial:
                columns += ([f"friction_force_2_{run.contact_names[i]}" for i in spatial]
                            + [f"slip_speed_2_{run.contact_names[i]}" for i in spatial])
                data += [run.friction_forces_2[:, spatial], run.slip_speeds_2[:, spatial]]
    for name, xyz in run.frames.items():
        columns += [f"{name}.x", f"{name}.y", f"{name}.z"]
        data.append(xyz)
    for name, wxyz in run.frame_rotations.items():
        columns += [f"{name}.qw", f"{name}.qx", f"{name}.qy", f"{name}.qz"]
        data.append(wxyz)
    with open(path, "w", encoding="utf-8", errors="backslashreplace") as fh:
        fh.write("\n".join(header) + "\n")
        np.savetxt(fh, np.hstack(data), delimiter=",", header=",".join(columns), comments="", fmt="%.17g")


def events_csv_path(path) -> Path:
    """The events table beside a CSV run file: run.csv -> run.events.csv."""
    path = Path(path)
    return path.with_name(path.stem + ".events.csv")


def write_events_csv(run: Run, path: Path) -> None:
    """One line per jump: time, jump, from, to, then the state and discrete states just after it."""
    ev = run.events
    with open(path, "w", encoding="utf-8") as fh:
        fh.write(",".join(["time", "jump", "from_flow", "to_flow"] + [f"{n}+" for n in run.state_names]
                          + [f"{n}+" for n in run.discrete_names]) + "\n")
        for r in range(len(ev["time"])):
            values = [repr(float(ev["time"][r])), run.jump_names[ev["jump"][r]],
                      run.flow_names[ev["from_flow"][r]], run.flow_names[ev["to_flow"][r]]]
            values += [repr(float(v)) for v in ev["state_after"][r]] + [repr(float(v)) for v in ev["discrete_after"][r]]
            fh.write(",".join(values) + "\n")


class RunFileError(ValueError):
    """A file that is not a run file of andyc sim's, or one damaged since: one line that says what."""


def read_run_file(path) -> Run:
    """read_h5 of a file a user names (andyc plot, andyc view, an expectation's reference): RunFileError, one
    line, for a file that is not HDF5, lacks a dataset or an attribute, or whose arrays disagree (a truncated
    or edited file), rather than whichever exception the plot would meet first."""
    import os
    import stat

    try:
        regular = stat.S_ISREG(os.stat(path).st_mode)
    except OSError as exc:
        raise RunFileError(f"{path}: cannot read it ({exc.strerror})") from None
    if not regular:                         # a pipe would be waited on without end, a device read without end
        raise RunFileError(f"{path}: this is a {'folder' if os.path.isdir(path) else 'special file'}, not a run "
                           f"file; give the .h5 file andyc sim wrote")
    try:
        run = read_h5(path)
    except Exception as exc:                # h5py's, json's, numpy's errors vary with the damage
        raise RunFileError(f"{path}: not a run file that andyc sim wrote ({printable(str(exc)) or type(exc).__name__})"
                           ) from None
    problem = run_problem(run)
    if problem:
        raise RunFileError(f"{path}: a damaged run file ({problem}); write it again with andyc sim")
    run.status = printable(run.status)
    return run


def run_problem(run: Run) -> str:
    """What is inconsistent in a Run read back, or '': each array's shape against the time's and the names',
    finite increasing times, the names printable text (they reach titles, the terminal and pages)."""
    def names(value) -> bool:
        return isinstance(value, list) and all(isinstance(v, str) and v.isprintable() for v in value)

    n = run.time.shape[0] if isinstance(run.time, np.ndarray) and run.time.ndim == 1 else -1
    if n < 0 or run.time.dtype.kind not in "fiu":
        return "time is not a list of numbers"
    if not np.all(np.isfinite(run.time)) or np.any(np.diff(run.time) < 0):
        return "its times are not finite and increasing"
    for what, value in (("model", [run.model]), ("state names", run.state_names), ("flow names", run.flow_names),
                        ("jump names", run.jump_names), ("discrete names", run.discrete_names),
                        ("input names", run.input_names), ("multiplier names", run.multiplier_names),
                        ("work names", run.work_names), ("contact names", run.contact_names),
                        ("frames", list(run.frames)), ("frame parents", list(run.frame_parents.values())
                                                       if isinstance(run.frame_parents, dict) else None)):
        if not names(value):
            return f"its {what} are not a list of printable names"
    if not run.flow_names:
        return "it names no flow"
    for what, value in (("parameters", run.parameters), ("inputs", run.inputs), ("display", run.display),
                        ("stats", run.stats)):
        if not isinstance(value, dict):
            return f"its {what} are not a mapping"
    columns = {"state": (run.state, len(run.state_names)), "discrete": (run.discrete, len(run.discrete_names)),
               "inputs": (run.input_values, len(run.input_names)),
               "multipliers": (run.multipliers, len(run.multiplier_names)),
               "residual/velocity": (run.residual_velocity, len(run.multiplier_names)),
               "residual/position": (run.residual_position, None), "work": (run.work, len(run.work_names)),
               "power": (run.power, len(run.work_names)), "slip speeds": (run.slip_speeds, len(run.contact_names)),
               "slip speeds 2": (run.slip_speeds_2, len(run.contact_names)),
               **{f"frames/{k}": (v, 3) for k, v in run.frames.items()},
               **{f"frame_rotations/{k}": (v, 4) for k, v in run.frame_rotations.items()}}
    for what, (value, width) in columns.items():
        if not isinstance(value, np.ndarray) or value.ndim != 2 or value.dtype.kind not in "fiu" \
                or value.shape[0] != n or (width is not None and value.shape[1] != width):
            return (f"{what} has the shape {getattr(value, 'shape', '?')}, not ({n}, "
                    f"{'*' if width is None else width}) for {n} samples")
    for what, value in (("energy", run.energy), ("flow", run.flow)):
        if not isinstance(value, np.ndarray) or value.shape != (n,) or value.dtype.kind not in "fiu":
            return f"{what} has the shape {getattr(value, 'shape', '?')}, not ({n},)"
    if n and (run.flow.min() < 0 or run.flow.max() >= max(len(run.flow_names), 1) and not run.contact_names):
        return "its flow indices are outside its flows"
    if not (0 <= run.nq and 0 <= run.nv and run.nq + run.nv <= len(run.state_names)):
        return f"nq = {run.nq} and nv = {run.nv} do not fit its {len(run.state_names)} states"
    if len(run.residual_position[0] if n else []) > len(run.multiplier_names):
        return "residual/position has more rows than multipliers"
    if any(not isinstance(r, int) or not -1 <= r < len(run.multiplier_names)
           for r in list(run.contact_rows) + list(run.contact_stick_rows)):
        return "its contacts name rows outside its multipliers"
    if not (len(run.contact_rows) == len(run.contact_stick_rows) == len(run.contact_mu)
            == len(run.contact_tangents) == len(run.contact_names)):
        return "its contacts' lists disagree in length"
    events = run.events
    k = len(events["time"])
    if any(len(events[key]) != k for key in ("jump", "from_flow", "to_flow", "state_before", "state_after")):
        return "its events' columns disagree in length"
    return ""
