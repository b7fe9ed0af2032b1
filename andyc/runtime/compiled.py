"""A generated module, imported: the compiled model (immutable) and its workspace.

As in Pinocchio and MuJoCo, the model holds sizes, names, defaults and the
compiled functions; a Workspace holds the arrays an algorithm writes into, so
nothing is allocated inside the integration loop.
"""

from __future__ import annotations

import importlib.util
import inspect
import sys
import traceback
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np
from numba import types

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
    constraint_gains: tuple = ()  # (constraint, "holonomic" | "nonholonomic", stiffness parameter, damping parameter)
    conserves_energy: bool = False
    source: str = ""            # the model file's name
    constraint_where: tuple = ()  # (line, document path) of each row in the model file
    discrete_names: tuple = ()
    flow_names: tuple = ("default",)
    initial_flow: int = 0
    jump_names: tuple = ()
    frame_parents: tuple = ()   # parent of each frame in frame_names
    input_expressions: tuple = ()  # (input, expression text) the model drives by default
    closed_form: object = None  # the module's closed_form(t, u, p) -> x, the exact solution it declares, or None
    closed_form_where: tuple = ()  # (line, document path) of each state's closed form in the model file

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

    def closed_form_location(self, k: int) -> str:
        """`FILE:LINE: PATH` of state k's closed form, for messages."""
        line, path = self.closed_form_where[k]
        return f"{self.source}:{line}: {path}"


def _with_overrides(names, defaults, overrides, kind) -> np.ndarray:
    values = np.array(defaults, dtype=np.float64)
    for name, value in (overrides or {}).items():
        if name not in names:
            raise SimulationError(f"unknown {kind} '{name}'; {kind}s of this model: {', '.join(names) or 'none'}")
        values[list(names).index(name)] = float(value)
    return values


@dataclass
class Workspace:
    """Arrays the integrators write into: M, G, the solver scratch, stage derivatives, scratch states, guard values."""
    M: np.ndarray
    G: np.ndarray
    S: np.ndarray        # (S_ROWS, S_WIDTH) scratch of the constrained solve, projection and impacts (the module's S_*)
    k: np.ndarray        # (4, nx) RK stages
    x_tmp: np.ndarray    # (nx,) stage state
    x_step: np.ndarray   # (nx,) a step's end
    x_near: np.ndarray   # (nx,) event location: the state at the bracket's near end
    x_trial: np.ndarray  # (nx,) event location: a trial state
    x_event: np.ndarray  # (nx,) the state just before a jump
    xdot: np.ndarray     # (nx,)
    g0: np.ndarray       # (nj,) guard values at the current step's start
    u: np.ndarray        # (nu,) the inputs at the latest (t, x)

    @classmethod
    def for_model(cls, model: CompiledModel) -> "Workspace":
        nx = model.nx
        return cls(np.zeros((model.nv, model.nv)), np.zeros(model.nv), np.zeros((model.module.S_ROWS, model.module.S_WIDTH)), np.zeros((4, nx)),
                   *(np.zeros(nx) for _ in range(6)), np.zeros(model.nj), np.zeros(len(model.input_names)))


def load_compiled(path) -> CompiledModel:
    """Import a generated module <name>.py (which imports its <name>_equations.py) and compile its
    functions (or load Numba's cache)."""
    path = Path(path).resolve()
    mod_name = f"andyc_loading_{path.stem}"
    spec = importlib.util.spec_from_file_location(mod_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[mod_name] = module
    try:
        spec.loader.exec_module(module)         # this imports the user's <name>_jumps.py too
    except (Exception, SystemExit) as exc:
        raise SimulationError(_import_failure(path, exc)) from None
    finally:
        sys.modules.pop(mod_name, None)     # (it registers its equations under the name their cache knows)
    model = CompiledModel(
        module=module, path=path, name=module.NAME, spec_sha256=module.SPEC_SHA256,
        nq=module.NQ, nv=module.NV, ns=module.NS, nx=module.NX, state_names=tuple(module.STATES),
        quaternions=tuple(module.QUATERNIONS),
        parameter_names=tuple(module.PARAMETERS), parameter_defaults=module.PARAMETER_DEFAULTS,
        input_names=tuple(module.INPUTS), input_defaults=module.INPUT_DEFAULTS,
        frame_names=tuple(module.FRAMES), nh=module.NH, nc=module.NC,
        multiplier_names=tuple(module.MULTIPLIERS), constraint_rows=tuple(module.CONSTRAINT_ROWS),
        constraint_gains=tuple(tuple(g) for g in module.CONSTRAINT_GAINS),
        conserves_energy=bool(module.CONSERVES_ENERGY), source=module.SOURCE,
        constraint_where=tuple(tuple(w) for w in module.CONSTRAINT_WHERE),
        discrete_names=tuple(module.DISCRETE_STATES), flow_names=tuple(module.FLOWS),
        initial_flow=int(module.INITIAL_FLOW), jump_names=tuple(module.JUMPS),
        frame_parents=tuple(module.FRAME_PARENTS), input_expressions=tuple(module.INPUT_EXPRESSIONS.items()),
        closed_form=module.closed_form if module.HAS_CLOSED_FORM else None,
        closed_form_where=tuple(tuple(w) for w in module.CLOSED_FORM_WHERE))
    # Call each function once so Numba compiles now, not inside a timed run.
    p, u, x, d, ws, flow = _sample_arguments(model)
    module.rhs_into(0.0, x, u, p, d, flow, ws.k[0], ws.M, ws.G, ws.S)
    module.normalize(x.copy())
    module.energy(0.0, x, u, p, d)
    module.power(0.0, x, u, p, d)
    module.frame_positions(0.0, x, u, p, d, np.zeros((len(model.frame_names), 3)))
    if model.closed_form is not None:
        model.closed_form(0.0, u, p)
    return model


def _import_failure(path: Path, exc: BaseException) -> str:
    """Why importing the generated module at path failed: most likely in the user's jumps file beside it."""
    jumps = path.with_name(f"{path.stem}_jumps.py")
    what = "called sys.exit()" if isinstance(exc, SystemExit) else f"raised {type(exc).__name__}: {exc}"
    if isinstance(exc, SyntaxError) and exc.filename and Path(exc.filename) == jumps:
        return f"{jumps}:{exc.lineno}: {exc.msg}; fix it, or delete the file to get a fresh template"
    line = next((f.lineno for f in reversed(traceback.extract_tb(exc.__traceback__)) if Path(f.filename) == jumps),
                None)
    if line is not None:
        return f"{jumps}:{line}: importing it {what}; fix it, or delete the file to get a fresh template"
    return f"{path}: importing the generated module {what}; rebuild it with `andyc build --force`"


def compilations(model: CompiledModel) -> int:
    """How many functions of the module Numba has compiled in this process, rather than loaded from its
    cache (the misses of its cache)."""
    total = 0
    for value in vars(model.module).values():
        misses = getattr(getattr(value, "stats", None), "cache_misses", None)
        if misses is not None:
            total += sum(misses.values())
    return total


def _sample_arguments(model: CompiledModel):
    """Defaults and the initial state, to call the module's functions once (so Numba compiles them)."""
    p, u = model.parameter_defaults, model.input_defaults
    return p, u, model.initial_state(p), model.initial_discrete(p), Workspace.for_model(model), model.initial_flow


def integrator_compiled(model: CompiledModel, driven: bool = False) -> bool:
    """Whether the module's integrator is compiled (or plain Python: Numba absent), for held inputs
    or (driven) for an input function."""
    advance = model.module.advance
    signatures = getattr(advance, "signatures", None)
    if signatures is None:
        return True
    k = list(inspect.signature(advance.py_func).parameters).index("inputs")
    return any((sig[k] != types.none) == driven for sig in signatures)


def compile_integrator(model: CompiledModel, function=None, data=None) -> None:
    """Compile the module's integrator and log evaluations (or load them from Numba's cache) once,
    with the argument types simulate() passes: a block of no steps and one-sample logs. With an
    input function (and its data), the integrator's second compilation, which calls it. simulate()
    calls this before it starts its clock, so a run's wall time never includes compilation."""
    module = model.module
    driven = function is not None
    if integrator_compiled(model, driven):
        return
    p, u, x, d, ws, flow = _sample_arguments(model)
    t_log, x_log, f_log, d_log = np.zeros(1), x[None, :].copy(), np.full(1, flow, dtype=np.int64), d[None, :].copy()
    u_log = u[None, :].copy()
    module.advance(0, False, False, 0.0, -1.0, 1e-12, 0.0, 1e-3, 0, 0, 1, 0.0, flow, x.copy(), function, ws.u, data,
                   p, d.copy(), t_log.copy(), x_log.copy(), u_log.copy(), f_log.copy(), d_log.copy(), 1, ws.g0,
                   ws.x_event, ws.M, ws.G, ws.S, ws.k, ws.x_tmp, ws.x_step, ws.x_near, ws.x_trial,
                   np.zeros(3, dtype=np.int64))
    module.instant(0, 0.0, x.copy(), function, ws.u, data, p, d.copy(), flow, ws.xdot, ws.M, ws.G, ws.S)
    module.update_inputs(function, 0.0, x, p, d, flow, ws.u, data)
    if driven:
        return
    module.evaluate_energy(t_log, x_log, u_log, p, d_log, np.zeros(1))
    model.flow_inputs(u, p)                             # what simulate() calls before it integrates
    if model.nc:
        module.constraints(0.0, x, u, p, d, np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, model.nv)),
                           np.empty(model.nc))
    if model.nc:
        module.evaluate_constraints(t_log, x_log, u_log, p, d_log, f_log, np.zeros((1, model.nh)),
                                    np.zeros((1, model.nc)), np.zeros((1, model.nc)), ws.M, ws.G, ws.S)
