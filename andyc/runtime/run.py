"""A finished (or stopped) run, and its HDF5 and CSV files (DESIGN.md layout)."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import andyc


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
    frames: dict = field(default_factory=dict)      # name -> (N, 3)
    status: str = "finished"         # "finished" or "stopped: why"
    stats: dict = field(default_factory=dict)       # steps, rhs_evaluations, wall_seconds
    multiplier_names: list = field(default_factory=list)
    multipliers: np.ndarray | None = None            # (N, nc)
    residual_position: np.ndarray | None = None      # (N, nh)
    residual_velocity: np.ndarray | None = None      # (N, nc)
    energy_correction: bool = False
    andyc_version: str = andyc.__version__

    def __post_init__(self):
        n = self.time.shape[0]
        nc = len(self.multiplier_names)
        if self.multipliers is None:
            self.multipliers = np.zeros((n, nc))
        if self.residual_velocity is None:
            self.residual_velocity = np.zeros((n, nc))
        if self.residual_position is None:
            self.residual_position = np.zeros((n, 0))

    @property
    def signal_names(self) -> list:
        return self.state_names[self.nq + self.nv:]

    @property
    def finished(self) -> bool:
        return self.status == "finished"

    def column(self, name: str) -> np.ndarray:
        return self.state[:, self.state_names.index(name)]

    def attributes(self) -> dict:
        return {"model": self.model, "spec_sha256": self.spec_sha256, "andyc_version": self.andyc_version,
                "method": self.method, "dt": self.dt, "nq": self.nq, "nv": self.nv, "rtol": self.rtol, "atol": self.atol,
                "parameters": json.dumps(self.parameters), "inputs": json.dumps(self.inputs),
                "t_end": self.t_end, "status": self.status, "stats": json.dumps(self.stats),
                "energy_correction": self.energy_correction}

    def save(self, path) -> Path:
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        if path.suffix.lower() in (".h5", ".hdf5"):
            write_h5(self, path)
        elif path.suffix.lower() == ".csv":
            write_csv(self, path)
        else:
            raise ValueError(f"unknown run file type '{path.suffix}'; use .h5 or .csv")
        return path


def write_h5(run: Run, path: Path) -> None:
    import h5py

    n = run.time.shape[0]
    with h5py.File(path, "w") as f:
        for key, value in run.attributes().items():
            f.attrs[key] = value
        f["time"] = run.time
        f["state"] = run.state
        f["state"].attrs["names"] = run.state_names
        f["flow"] = np.zeros(n, dtype=np.int32)
        f["multipliers"] = run.multipliers
        f["multipliers"].attrs["names"] = run.multiplier_names
        f["residual/position"] = run.residual_position
        f["residual/velocity"] = run.residual_velocity
        f["energy"] = run.energy
        for name, xyz in run.frames.items():
            f[f"frames/{name}"] = xyz
        events = np.zeros(0, dtype=[("time", "f8"), ("jump", h5py.string_dtype()),
                                    ("from_flow", "i4"), ("to_flow", "i4")])
        f.create_dataset("events", data=events, maxshape=(None,))


def read_h5(path) -> Run:
    import h5py

    with h5py.File(path, "r") as f:
        a = dict(f.attrs)
        frames = {name: f["frames"][name][()] for name in f["frames"]} if "frames" in f else {}
        return Run(model=a["model"], spec_sha256=a["spec_sha256"], method=a["method"], dt=float(a["dt"]),
                   nq=int(a["nq"]), nv=int(a["nv"]),
                   rtol=float(a["rtol"]), atol=float(a["atol"]), t_end=float(a["t_end"]),
                   parameters=json.loads(a["parameters"]), inputs=json.loads(a.get("inputs", "{}")),
                   state_names=[str(s) for s in f["state"].attrs["names"]], time=f["time"][()],
                   state=f["state"][()], energy=f["energy"][()], frames=frames, status=str(a["status"]),
                   stats=json.loads(a.get("stats", "{}")), andyc_version=str(a["andyc_version"]),
                   multiplier_names=[str(s) for s in f["multipliers"].attrs["names"]],
                   multipliers=f["multipliers"][()], residual_position=f["residual/position"][()],
                   residual_velocity=f["residual/velocity"][()],
                   energy_correction=bool(a.get("energy_correction", False)))


def write_csv(run: Run, path: Path) -> None:
    header = [f"# {k}: {v}" for k, v in run.attributes().items()]
    columns = (["time"] + list(run.state_names) + ["flow", "energy"] + list(run.multiplier_names)
               + [f"phi_{m}" for m in run.multiplier_names[:run.residual_position.shape[1]]]
               + [f"c_{m}" for m in run.multiplier_names])
    data = [run.time[:, None], run.state, np.zeros((run.time.shape[0], 1)), run.energy[:, None],
            run.multipliers, run.residual_position, run.residual_velocity]
    for name, xyz in run.frames.items():
        columns += [f"{name}.x", f"{name}.y", f"{name}.z"]
        data.append(xyz)
    with open(path, "w") as fh:
        fh.write("\n".join(header) + "\n")
        np.savetxt(fh, np.hstack(data), delimiter=",", header=",".join(columns), comments="", fmt="%.17g")
