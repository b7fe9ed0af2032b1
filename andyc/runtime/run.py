"""A finished (or stopped) run, and its HDF5 and CSV files (docs/design.md, the run layout)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import andyc
from andyc.errors import plural, printable
from andyc.numerics.status import SLIP_TINY
from andyc.outputs import write_atomic
from andyc.runtime.status import drift, largest_residual
from andyc.spec.meshfiles import read_mesh
from andyc.spec.modes import radices


@dataclass
class Run:
    model: str
    spec_sha256: str
    method: str
    dt: float
    nq: int                          # state = (q [nq], v [nv], signals [rest])
    nv: int
    rtol: float
    atol: float
    t_end: float
    parameters: dict
    inputs: dict
    state_names: list
    time: np.ndarray                 # (N,)
    state: np.ndarray                # (N, nx)
    energy: np.ndarray               # (N,)
    frames: dict = field(default_factory=dict)      # name -> (N, 3) its origin in world
    frame_rotations: dict = field(default_factory=dict)  # name -> (N, 4) unit quaternion w, x, y, z: own axes -> world
    status: str = "finished"         # "finished" or "stopped: why"
    stats: dict = field(default_factory=dict)       # steps, rhs_evaluations, wall_seconds
    multiplier_names: list = field(default_factory=list)
    multipliers: np.ndarray | None = None            # (N, nc)
    residual_position: np.ndarray | None = None      # (N, nh)
    residual_velocity: np.ndarray | None = None      # (N, nc)
    energy_correction: bool = False
    flow: np.ndarray | None = None                   # (N,) index of the active flow
    flow_names: list = field(default_factory=lambda: ["default"])
    discrete_names: list = field(default_factory=list)
    discrete: np.ndarray | None = None               # (N, nd) discrete states
    events: dict = field(default_factory=dict)       # EVENT_COLUMNS -> arrays, one entry per jump
    jump_names: list = field(default_factory=list)
    frame_parents: dict = field(default_factory=dict)  # logged frame -> its parent frame (stick figures)
    input_names: list = field(default_factory=list)
    input_values: np.ndarray | None = None           # (N, nu) the inputs at each sample
    contact_names: list = field(default_factory=list)  # unilateral contacts; flow = their states (contact_modes)
    contact_rows: list = field(default_factory=list)   # the multiplier (row) of each contact's normal force
    contact_stick_rows: list = field(default_factory=list)  # the multiplier (row) of its friction force, or -1
    contact_mu: list = field(default_factory=list)     # its friction coefficient (NaN without friction)
    slip_speeds: np.ndarray | None = None              # (N, contacts) each contact's slip speed (NaN without friction)
    contact_tangents: list = field(default_factory=list)  # per contact: 0 frictionless, 1 planar, 2 spatial friction
    slip_speeds_2: np.ndarray | None = None            # (N, contacts) the slip along a spatial contact's second tangent
    andyc_version: str = andyc.__version__
    display: dict = field(default_factory=dict)      # state units, the ground, shapes: for pictures (andyc.spec.display)
    work_names: list = field(default_factory=list)   # the elements that do work, then 'jumps' (andyc.runtime.work)
    work: np.ndarray | None = None                   # (N, nw) the work of each, integrated with the motion
    power: np.ndarray | None = None                  # (N, nw) the power of each at the samples ('jumps': 0)
    sensitivities: dict | None = None   # simulate(sensitivities=True): "x0" dx(T)/dx0 (nx, nx), "d0" dx(T)/dd0,
                                        # "p" dx(T)/dp (nx, np), "time" dT/dz, "discrete" dd(T)/dz, z = (x0, d0, p)
                                        # (andyc.runtime.sensitivities)
    meshes: dict = field(default_factory=dict)       # mesh file (as display's shapes name it) -> its bytes, as read

    meshes_on_disk: bool = True     # a run made here reads its shapes' meshes from disk; one read back does not

    def mesh_bytes(self, file: str) -> bytes | None:
        """The bytes of a shape's mesh file: as the run file holds them; for a run made in this process, read
        from the file the spec accepted (andyc.spec.meshfiles). None when neither has it. A run file read
        back never reads the disk: its file names are text anyone could have written."""
        if file not in self.meshes:
            data = read_mesh(file) if self.meshes_on_disk else None
            if data is None:
                return None
            self.meshes[file] = data
        return self.meshes[file]

    def __post_init__(self):
        n = self.time.shape[0]
        nc = len(self.multiplier_names)
        if self.flow is None:
            self.flow = np.zeros(n, dtype=np.int64)
        if self.discrete is None:
            self.discrete = np.zeros((n, len(self.discrete_names)))
        if self.input_values is None:
            self.input_values = np.zeros((n, len(self.input_names)))
        nx = self.state.shape[1]
        empty = {"time": np.zeros(0), "jump": np.zeros(0, np.int32), "from_flow": np.zeros(0, np.int32),
                 "to_flow": np.zeros(0, np.int32), "state_before": np.zeros((0, nx)),
                 "state_after": np.zeros((0, nx)), "discrete_after": np.zeros((0, len(self.discrete_names)))}
        self.events = {**empty, **self.events}
        if self.multipliers is None:
            self.multipliers = np.zeros((n, nc))
        if self.residual_velocity is None:
            self.residual_velocity = np.zeros((n, nc))
        if self.residual_position is None:
            self.residual_position = np.zeros((n, 0))
        if self.work is None:
            self.work = np.zeros((n, len(self.work_names)))
        if self.power is None:
            self.power = np.zeros((n, len(self.work_names)))
        k = len(self.contact_names)
        self.contact_stick_rows = list(self.contact_stick_rows) or [-1] * k
        self.contact_mu = list(self.contact_mu) or [math.nan] * k
        if self.slip_speeds is None:
            self.slip_speeds = np.full((n, k), np.nan)
        self.contact_tangents = list(self.contact_tangents) or [int(r >= 0) for r in self.contact_stick_rows]
        if self.slip_speeds_2 is None:
            self.slip_speeds_2 = np.full((n, k), np.nan)

    @property
    def energy_balance(self) -> np.ndarray:
        """(N,) E(t) - E(0) - W(t), W the work of every element and the energy the jumps changed: 0 but for the
        integration's error (Braun & Goldfarb's energy law, andyc/symbolic/work.py)."""
        total = self.work.sum(axis=1) if self.work.size else np.zeros(len(self.time))
        return self.energy - self.energy[:1] - total

    @property
    def signal_names(self) -> list:
        return self.state_names[self.nq + self.nv:]

    @property
    def finished(self) -> bool:
        return self.status == "finished"

    def column(self, name: str) -> np.ndarray:
        if name in self.discrete_names:
            return self.discrete[:, self.discrete_names.index(name)]
        return self.state[:, self.state_names.index(name)]

    @property
    def contact_modes(self) -> np.ndarray:
        """(N, contacts) each contact's mode: 0 open, 1 closed (sticking, with friction), 2 slipping forwards
        (slip speed > 0), 3 backwards (spatial friction: 2 slipping): its discrete state `<contact>_mode`
        (andyc.spec.contacts). (Older run files coded them in the flow index: read from it there.)"""
        names = [f"{c}_mode" for c in self.contact_names]
        if all(n in self.discrete_names for n in names):
            columns = [self.discrete_names.index(n) for n in names]
            return self.discrete[:, columns].astype(np.int8).reshape(len(self.time), len(names))
        radix = radices(self.contact_tangents)
        place = np.cumprod([1] + radix[:-1]).astype(np.int64)
        return ((self.flow[:, None] // place[None, :]) % np.array(radix, dtype=np.int64)).astype(np.int8).reshape(
            len(self.time), len(self.contact_names))

    def event_modes(self, k: int) -> list:
        """Each contact's mode right after the run's k-th event (its discrete states then)."""
        names = [f"{c}_mode" for c in self.contact_names]
        return [int(self.events["discrete_after"][k, self.discrete_names.index(n)]) for n in names]

    @property
    def contact_closed(self) -> np.ndarray:
        """(N, contacts) 1 where a contact is closed (sticking or slipping)."""
        return (self.contact_modes > 0).astype(np.int8)

    @property
    def normal_forces(self) -> np.ndarray:
        """(N, contacts) each contact's normal force (its multiplier, >= 0 while it pushes), 0 where it is open."""
        lam = self.multipliers[:, list(self.contact_rows)] if self.contact_rows else np.zeros((len(self.time), 0))
        return np.where(self.contact_closed == 1, lam, 0.0)

    @property
    def friction_forces(self) -> np.ndarray:
        """(N, contacts) each contact's friction force along +tangent (the direction of positive slip): its stick
        row's multiplier while it sticks, -mu lam_n slipping forwards, +mu lam_n backwards; 0 open or frictionless.
        A moreau run's, after sample 0: the steps' mean tangential impulse P_t / dt, in every closed mode."""
        return self._friction(0)

    @property
    def friction_forces_2(self) -> np.ndarray:
        """(N, contacts) the friction force of a contact with spatial friction along its second tangent (0 for the
        others): its second stick row's multiplier while it sticks, -mu lam_n u_2 slipping (friction_forces: the
        first tangent, -mu lam_n u_1), u the slip's unit direction."""
        return self._friction(1)

    def _friction(self, j: int) -> np.ndarray:
        """Each contact's friction force along its tangent j (0, or 1 for the second of spatial friction)."""
        modes, normal = self.contact_modes, self.normal_forces
        out = np.zeros(modes.shape)
        for i, row in enumerate(self.contact_stick_rows):
            if self.contact_tangents[i] == 2:
                slip = np.stack([self.slip_speeds[:, i], self.slip_speeds_2[:, i]], axis=1)
                size = np.hypot(slip[:, 0], slip[:, 1])
                known = f"{self.contact_names[i]}_slip_dir_1"
                if known in self.discrete_names:        # a slip from rest, or a step that held it: the run's
                    k = self.discrete_names.index(known)
                    # (as numerics.slipping.slip_unit: the run's direction where |s| <= SLIP_TINY or held, else
                    # s / |s| turned towards it)
                    ref = self.discrete[:, k:k + 2]
                    own = (size > SLIP_TINY) & (self.discrete[:, k + 2] == 0)
                    sigma = np.where(np.sum(slip * ref, axis=1) < 0.0, -1.0, 1.0)
                    direction = np.where(own[:, None], slip * (sigma / np.where(size > 0, size, 1.0))[:, None], ref)
                else:
                    direction = slip / np.where(size > 0, size, 1.0)[:, None]
                out[:, i] = np.where(modes[:, i] == 1, self.multipliers[:, row + j], 0.0)
                out[:, i] += np.where(modes[:, i] == 2, -self.contact_mu[i] * normal[:, i] * direction[:, j], 0.0)
                continue
            if row < 0 or j:
                continue
            mu = self.contact_mu[i]
            out[:, i] = np.where(modes[:, i] == 1, self.multipliers[:, row], 0.0)
            out[:, i] += np.where(modes[:, i] == 2, -mu * normal[:, i], 0.0) + np.where(modes[:, i] == 3,
                                                                                         mu * normal[:, i], 0.0)
        if self.method == "moreau":
            # after sample 0 (the initial modes' ideal multipliers), the steps' mean tangential impulses P_t / dt,
            # logged in the stick rows whatever the contact's mode (a slip at rest, a slide: the step's own force)
            for i, row in enumerate(self.contact_stick_rows):
                if row >= 0 and j < self.contact_tangents[i]:
                    out[1:, i] = np.where(modes[1:, i] > 0, np.nan_to_num(self.multipliers[1:, row + j]), 0.0)
        return out

    @property
    def frictional(self) -> list:
        """The indices of the contacts with friction."""
        return [i for i, r in enumerate(self.contact_stick_rows) if r >= 0]

    def event_names(self) -> list:
        """Name of the jump of each event."""
        return [self.jump_names[k] for k in self.events["jump"]]

    def summary(self) -> str:
        """One paragraph, what the run did (`andyc sim` prints it, then the files it wrote): method, time span,
        steps, right-hand-side evaluations, wall time and the energy at both ends; with constraints the
        largest residuals (and how far the initial state was projected), with jumps how many of each and the
        flow the run ended in."""
        s = self.stats
        constraints = ""
        if self.multiplier_names:
            constraints = (f"; largest constraint residuals: position {_largest(self.residual_position):.3g}, "
                           f"velocity {_largest(self.residual_velocity):.3g}")
            if "initial_projection" in s:
                constraints += f" (initial state projected from {s['initial_projection']:.3g})"
            if self.finished:
                clause = drift(self.method, *largest_residual(self.residual_position, self.residual_velocity,
                                                              self.time))
                constraints += f"; {clause}" if clause else ""
        if self.jump_names:
            counts = {}
            for name in self.event_names():
                counts[name] = counts.get(name, 0) + 1
            constraints += (f"; {plural(len(self.events['time']), 'jump')}"
                            + (f" ({', '.join(f'{k} {v}' for k, v in counts.items())})" if counts else "")
                            + f", ending in flow {self.flow_names[self.flow[-1]]}")
        return (f"{self.model}: {self.method}, t = 0 .. {self.time[-1]:.6g} s, {s['steps']} steps, "
                f"{s['rhs_evaluations']} rhs evaluations, {s['wall_seconds']:.3f} s wall; {self._energy_summary()}"
                f"{constraints}")

    def _energy_summary(self) -> str:
        """The energy at both ends; with elements that do work, their work and the balance's largest residual."""
        e = f"energy {self.energy[0]:.10g} -> {self.energy[-1]:.10g} J"
        if not self.work_names:
            return f"{e} (change {self.energy[-1] - self.energy[0]:.3g} J)"
        return (f"{e}, work {self.work[-1].sum():.6g} J; energy balance residual "
                f"{_largest(self.energy_balance):.3g} J (largest |E - E0 - W|)")

    def attributes(self) -> dict:
        """The run's metadata as HDF5 attributes; text on one line, control characters and lone surrogates
        escaped (a status can quote a user's exception or a file name, and HDF5 takes neither NUL nor them)."""
        return {k: printable(v) if isinstance(v, str) else v for k, v in self._attributes().items()}

    def _attributes(self) -> dict:
        return {"model": self.model, "spec_sha256": self.spec_sha256, "andyc_version": self.andyc_version,
                "method": self.method, "dt": self.dt, "nq": self.nq, "nv": self.nv, "rtol": self.rtol, "atol": self.atol,
                "parameters": json.dumps(self.parameters), "inputs": json.dumps(self.inputs),
                "t_end": self.t_end, "status": self.status, "stats": json.dumps(self.stats),
                "energy_correction": self.energy_correction, "flow_names": json.dumps(self.flow_names),
                "jump_names": json.dumps(self.jump_names), "frame_parents": json.dumps(self.frame_parents),
                "display": json.dumps(self.display),
                **({"contacts": json.dumps({"names": self.contact_names, "rows": self.contact_rows,
                                            "stick_rows": self.contact_stick_rows,
                                            "tangents": self.contact_tangents,
                                            "mu": [None if math.isnan(m) else m for m in self.contact_mu]})}
                   if self.contact_names else {})}

    def save(self, path) -> Path:
        """Write the run to path (.h5 or .csv; a CSV of a hybrid model also writes its events beside it,
        see events_csv_path), each file under a temporary name renamed into place (andyc.outputs), so an
        interrupted write never leaves a truncated run file. ValueError for another suffix."""
        path = Path(path)
        kind = path.suffix.lower()
        if kind not in RUN_SUFFIXES:
            raise ValueError(f"unknown run file type '{path.suffix}'; use .h5 or .csv")
        with write_atomic(path) as tmp:
            (write_h5 if kind in (".h5", ".hdf5") else write_csv)(self, tmp)
        if kind == ".csv" and self.jump_names:
            with write_atomic(events_csv_path(path)) as tmp:
                write_events_csv(self, tmp)
        return path


RUN_SUFFIXES = (".h5", ".hdf5", ".csv")
MAX_ATTRIBUTE = 32_000      # characters of an HDF5 attribute at most (its object header holds 64 kB in all)


def unit_quaternions(R: np.ndarray) -> np.ndarray:
    """(N, 4) unit quaternions w, x, y, z of the rotation matrices R (N, 3, 3), each taken with the sign nearer
    the one before it, so a logged rotation is continuous in time (q and -q are the same rotation; an
    animation interpolating between samples, or a plot, wants no jump between them). SciPy's conversion
    (Shepperd's method, exact to rounding at every angle)."""
    from scipy.spatial.transform import Rotation

    if not len(R):
        return np.zeros((0, 4))
    xyzw = Rotation.from_matrix(R).as_quat()
    q = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    flips = np.cumprod(np.where(np.einsum("ij,ij->i", q[1:], q[:-1]) < 0.0, -1.0, 1.0))
    q[1:] *= flips[:, None]
    if q[0, 0] < 0.0:         # the first sample with w >= 0, so a run's first rotation has one spelling
        q *= -1.0
    return q


def _largest(a: np.ndarray) -> float:
    """The largest |entry|, skipping NaN (the rows a sample's flow does not use)."""
    return float(np.nanmax(np.abs(a), initial=0.0)) if a.size else 0.0


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
