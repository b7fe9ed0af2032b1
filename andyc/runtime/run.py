"""A finished (or stopped) run: its arrays, names and summary (its files: runfiles.py; docs/run-file.md)."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import andyc
from andyc.errors import plural, printable
from andyc.numerics.status import SLIP_TINY
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
        """Write the run to path (.h5 or .csv): andyc.runtime.runfiles.save_run."""
        from andyc.runtime.runfiles import save_run

        return save_run(self, path)


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
