"""A generated module, imported: the compiled model (immutable) and its workspace.

As in Pinocchio and MuJoCo, the model holds sizes, names, defaults and the
compiled functions; a Workspace holds the arrays an algorithm writes into, so
nothing is allocated inside the integration loop.
"""

from __future__ import annotations

import hashlib
import importlib.util
import sys
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

from andyc.errors import SimulationError


@dataclass(frozen=True)
class CompiledModel:
    module: ModuleType
    path: Path
    name: str
    spec_sha256: str
    nq: int
    nv: int
    ns: int
    nx: int
    state_names: tuple
    quaternions: tuple          # index in x of each quaternion signal's w
    parameter_names: tuple
    parameter_defaults: np.ndarray
    input_names: tuple
    input_defaults: np.ndarray
    frame_names: tuple
    nh: int = 0                 # holonomic constraint rows (the first nh of the nc)
    nc: int = 0                 # velocity-level constraint rows
    multiplier_names: tuple = ()
    constraint_rows: tuple = () # constraint name of each row
    conserves_energy: bool = False
    source: str = ""            # the model file's name
    constraint_where: tuple = ()  # (line, document path) of each row in the model file
    discrete_names: tuple = ()
    flow_names: tuple = ("default",)
    initial_flow: int = 0
    jump_names: tuple = ()
    frame_parents: tuple = ()   # parent of each frame in frame_names

    @property
    def nd(self) -> int:
        return len(self.discrete_names)

    @property
    def nf(self) -> int:
        return len(self.flow_names)

    @property
    def nj(self) -> int:
        return len(self.jump_names)

    def initial_discrete(self, p: np.ndarray) -> np.ndarray:
        return self.module.initial_discrete(p)

    def flow_inputs(self, u: np.ndarray, p: np.ndarray) -> np.ndarray:
        """(flows, inputs): the run's inputs u, overridden where a flow sets its own."""
        U = np.tile(np.asarray(u, dtype=np.float64), (self.nf, 1))
        self.module.flow_inputs(p, U)
        return U

    def parameters(self, overrides: dict | None = None) -> np.ndarray:
        return _with_overrides(self.parameter_names, self.parameter_defaults, overrides, "parameter")

    def inputs(self, overrides: dict | None = None) -> np.ndarray:
        return _with_overrides(self.input_names, self.input_defaults, overrides, "input")

    def row_location(self, row: int) -> str:
        """`FILE:LINE: PATH` of a constraint row, for messages."""
        line, path = self.constraint_where[row]
        return f"{self.source}:{line}: {path}"

    def initial_state(self, p: np.ndarray) -> np.ndarray:
        return self.module.initial_state(p)


def _with_overrides(names, defaults, overrides, kind) -> np.ndarray:
    values = np.array(defaults, dtype=np.float64)
    for name, value in (overrides or {}).items():
        if name not in names:
            raise SimulationError(f"unknown {kind} '{name}'; {kind}s of this model: {', '.join(names) or 'none'}")
        values[list(names).index(name)] = float(value)
    return values


@dataclass
class Workspace:
    """Arrays the integrators write into: M, G, stage derivatives, scratch states, guard values."""
    M: np.ndarray
    G: np.ndarray
    k: np.ndarray        # (4, nx) RK stages
    x_tmp: np.ndarray    # (nx,) stage state
    x_step: np.ndarray   # (nx,) a step's end
    x_near: np.ndarray   # (nx,) event location: the state at the bracket's near end
    x_trial: np.ndarray  # (nx,) event location: a trial state
    x_event: np.ndarray  # (nx,) the state just before a jump
    xdot: np.ndarray     # (nx,)
    g0: np.ndarray       # (nj,) guard values at the current step's start

    @classmethod
    def for_model(cls, model: CompiledModel) -> "Workspace":
        nx = model.nx
        return cls(np.zeros((model.nv, model.nv)), np.zeros(model.nv), np.zeros((4, nx)),
                   *(np.zeros(nx) for _ in range(6)), np.zeros(model.nj))


def load_compiled(path) -> CompiledModel:
    """Import a generated module and compile its functions (or load Numba's cache)."""
    path = Path(path).resolve()
    # A stable, importable name: Numba's cache re-imports the module by it.
    mod_name = f"andyc_build_{path.stem}_{hashlib.sha1(str(path).encode()).hexdigest()[:10]}"
    spec = importlib.util.spec_from_file_location(mod_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[mod_name] = module
    spec.loader.exec_module(module)
    model = CompiledModel(
        module=module, path=path, name=module.NAME, spec_sha256=module.SPEC_SHA256,
        nq=module.NQ, nv=module.NV, ns=module.NS, nx=module.NX, state_names=tuple(module.STATES),
        quaternions=tuple(module.QUATERNIONS),
        parameter_names=tuple(module.PARAMETERS), parameter_defaults=module.PARAMETER_DEFAULTS,
        input_names=tuple(module.INPUTS), input_defaults=module.INPUT_DEFAULTS,
        frame_names=tuple(module.FRAMES), nh=module.NH, nc=module.NC,
        multiplier_names=tuple(module.MULTIPLIERS), constraint_rows=tuple(module.CONSTRAINT_ROWS),
        conserves_energy=bool(module.CONSERVES_ENERGY), source=module.SOURCE,
        constraint_where=tuple(tuple(w) for w in module.CONSTRAINT_WHERE),
        discrete_names=tuple(module.DISCRETE_STATES), flow_names=tuple(module.FLOWS),
        initial_flow=int(module.INITIAL_FLOW), jump_names=tuple(module.JUMPS),
        frame_parents=tuple(module.FRAME_PARENTS))
    # Call each function once so Numba compiles now, not inside a timed run.
    p, u = model.parameter_defaults, model.input_defaults
    x = model.initial_state(p)
    d = model.initial_discrete(p)
    ws = Workspace.for_model(model)
    flow = model.initial_flow
    module.rhs_into(0.0, x, u, p, d, flow, ws.k[0], ws.M, ws.G)
    module.normalize(x.copy())
    module.energy(0.0, x, u, p, d)
    module.power(0.0, x, u, p, d)
    module.frame_positions(0.0, x, u, p, d, np.zeros((len(model.frame_names), 3)))
    return model
