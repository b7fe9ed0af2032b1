"""A generated module, imported: the compiled model (immutable) and the arrays its algorithms work in.

As in Pinocchio and MuJoCo, the model holds sizes, names, defaults and the
compiled functions; a Work (andyc_numerics/model.py, in the build) holds the
arrays an algorithm writes into, so nothing is allocated inside the
integration loop. The algorithms are the build's copy of andyc/numerics,
compiled once for every model (CompiledModel.numerics); the model's own
functions are in CompiledModel.ref, the Model those algorithms take.
"""

from __future__ import annotations

import importlib.util
import sys
import traceback
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import IDEAL
from andyc.runtime.methods import ADAPTIVE, FIXED_STEP, TIME_STEPPING

@dataclass(frozen=True)
class CompiledModel:
    module: ModuleType          # the generated <name>.py
    numerics: ModuleType        # the algorithms: its andyc_numerics package (integrator, dynamics, model, ...)
    ref: object                 # the compiled Model they take (module.MODEL)
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
    work_names: tuple = ()      # the work slots carried after the state (andyc.runtime.work): elements, then 'jumps'
    untracked_work: tuple = ()  # frames moved by a link that depends on t (their driving work is not in the work)
    energy_laws: tuple = ()     # per flow: its declared energy law as written (andyc.spec.energy_law), or None
    energy_law_where: tuple = ()  # per flow: (line, document path) of that law, or None
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
    simulate: dict = field(default_factory=dict)  # andyc sim's options the model gives (its simulate: section)
    display: dict = field(default_factory=dict)  # state units, the ground, shapes (andyc.spec.display): for pictures
    contact_names: tuple = ()   # unilateral contacts (andyc.spec.contacts); their modes are in d (contact_states)
    contact_rows: tuple = ()    # the constraint row of each contact's gap
    contact_modes: tuple = ()   # the index in d of each contact's mode: 0 open, 1 closed or sticking, 2 (3) slipping
    jump_contact: tuple = ()    # per jump: the contact whose impact it is (andyc.runtime.contacts resolves it), or
    #                             SLIP_STOP (a slip's end, andyc.numerics.status), or -1
    contact_stick_rows: tuple = ()  # the stick row of each contact with friction (spatial: the first of two), or -1
    contact_tangents: tuple = ()  # per contact: 0 frictionless, 1 planar, 2 spatial friction (stick rows t, t + 1)
    jump_kinds: tuple = ()      # per jump: (kind, contact) of a contact's jump (andyc.spec.contacts), ("", -1) else
    jump_modes: tuple = ()      # per jump: (index in d of its contact's mode, mask of the modes it leaves); (-1, 0)
    friction_names: tuple = ()  # joint frictions (dampers of law coulomb): only the moreau method applies them
    friction_speeds: tuple = ()  # ... the speed each acts on
    friction_slots: tuple = ()  # ... its work slot

    @property
    def stepping(self) -> ModuleType:
        """The build's time-stepping module (andyc_numerics' timestepping.py), imported when first asked for: a run
        of another method does not load it."""
        return importlib.import_module(f"{self.numerics.__name__}.timestepping")

    def stepping_scratch(self):
        """The zeroed arrays of a time-stepping run of this model (the stepping module's new_scratch)."""
        return self.stepping.new_scratch(self.nq, self.nv, self.nx, self.nw, self.nc, self.nd, len(self.contact_names),
                                         self.friction_speeds, self.friction_slots)

    @property
    def tangents(self) -> list:
        """Per contact: 0 frictionless, 1 planar, 2 spatial friction."""
        return list(self.contact_tangents)

    def contact_states(self, d) -> list:
        """Each contact's mode in the discrete states d (andyc.spec.contacts: 0 open, 1 closed or sticking, 2 / 3
        slipping forwards / backwards; spatial friction: 2 slipping)."""
        return [int(d[k]) for k in self.contact_modes]

    def set_contact_states(self, d, states) -> None:
        """Write each contact's mode into d, in place."""
        for k, s in zip(self.contact_modes, states):
            d[k] = float(s)

    def in_mode(self, k: int, flow: int, d) -> bool:
        """Whether jump k leaves `flow` with the contacts' modes in d (as andyc_numerics' dynamics.in_mode)."""
        source = int(self.module.JUMP_SOURCE[k])
        state, mask = self.jump_modes[k] if self.jump_modes else (-1, 0)
        return (source < 0 or source == flow) and (state < 0 or bool((mask >> int(d[state])) & 1))
    @property
    def nw(self) -> int:
        return len(self.work_names)

    @property
    def nd(self) -> int:
        return len(self.discrete_names)

    @property
    def nf(self) -> int:
        return len(self.flow_names)

    @property
    def nj(self) -> int:
        return len(self.jump_names)

    def initial_discrete(self, p: np.ndarray, at: dict | None = None) -> np.ndarray:
        """The discrete states' initial values at the parameters p; `at` {name: value} over them."""
        return _with_overrides(self.discrete_names, self.module.initial_discrete(p), at, "discrete state")

    def flow_inputs(self, u: np.ndarray, p: np.ndarray) -> np.ndarray:
        """(flows, inputs): the run's inputs u, overridden where a flow sets its own."""
        U = np.tile(np.asarray(u, dtype=np.float64), (self.nf, 1))
        self.module.flow_inputs(p, U)
        return U

    def parameters(self, overrides: dict | None = None) -> np.ndarray:
        for name in overrides or ():
            if name not in self.parameter_names and name in self.state_names:
                raise SimulationError(f"'{name}' is a state, not a parameter: set its initial value with --at "
                                      f"{name}=VALUE (andyc.simulate(..., x0={{'{name}': VALUE}}))")
        return _with_overrides(self.parameter_names, self.parameter_defaults, overrides, "parameter")

    def inputs(self, overrides: dict | None = None) -> np.ndarray:
        return _with_overrides(self.input_names, self.input_defaults, overrides, "input")

    def active_rows(self, flow: int, d=None) -> list:
        """The constraint rows active in `flow` with the contacts' modes in d (None: every contact open): indices into
        the nc rows, holonomic ones first, as andyc_numerics' active.select_rows orders them."""
        w = work(self)
        n = self.numerics.active.select_rows(self.ref, w.ref, int(flow),
                                             np.zeros(self.nd) if d is None else np.asarray(d, dtype=np.float64))
        return [int(r) for r in w.active[0, :n]]

    def initial_state(self, p: np.ndarray, at: dict | None = None) -> np.ndarray:
        """The model's initial state at the parameters p; `at` {name: value} over it (the others as the model
        gives them: its initial values are expressions of p)."""
        return _with_overrides(self.state_names, self.module.initial_state(p), at, "state")

    def closed_form_location(self, k: int) -> str:
        """`FILE:LINE: PATH` of state k's closed form, for messages."""
        line, path = self.closed_form_where[k]
        return f"{self.source}:{line}: {path}"


def _with_overrides(names, defaults, overrides, kind) -> np.ndarray:
    """defaults (one per name) with {name: value} over them; SimulationError naming an unknown name."""
    values = np.array(defaults, dtype=np.float64)
    for name, value in (overrides or {}).items():
        if name not in names:
            raise SimulationError(f"unknown {kind} '{name}'; {kind}s of this model: {', '.join(names) or 'none'}")
        values[list(names).index(name)] = float(value)
    return values


def work(model: CompiledModel):
    """A new Work of the model's scratch arrays (andyc_numerics/model.py): `.ref` for the algorithms, and the
    arrays themselves (w.u, w.x_event, w.g0, ...) for Python."""
    return model.numerics.model.Work(model.module.SIZES)


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
    # The leaves compiled (or loaded from Numba's cache) as the module was imported; the module says in one
    # dict what the model is (METADATA: every field below but the first four).
    return CompiledModel(module=module, numerics=module.NUMERICS, ref=module.MODEL, path=path, **module.METADATA)


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
    """How many functions Numba has compiled in this process, rather than loaded from its cache: the model's
    leaves, and the algorithms (shared by every model of the process: see numerics_compilations)."""
    return leaf_compilations(model.module.EQUATIONS) + numerics_compilations(model.numerics)


def leaf_compilations(equations: ModuleType) -> int:
    """How many leaves of a <name>_equations.py module Numba compiled (rather than loaded) when it was imported."""
    return sum(value.cache_hits == 0 for value in vars(equations).values() if _is_cfunc(value))


def numerics_compilations(numerics: ModuleType) -> int:
    """How many functions of a numerics package (a build's andyc_numerics) Numba has compiled in this process."""
    total = 0
    for name in ("model", "stubs", "linalg", "active", "dynamics", "integrator", "inputs", "api", "contact_solver",
                 "timestepping", "batch"):
        for value in vars(getattr(numerics, name, None) or ModuleType(name)).values():
            misses = getattr(getattr(value, "stats", None), "cache_misses", None)
            if misses is not None:
                total += sum(misses.values())
            elif _is_cfunc(value):
                total += value.cache_hits == 0
    return total


def _is_cfunc(value) -> bool:
    return hasattr(value, "cache_hits") and hasattr(value, "address")


def sample_run(model: CompiledModel):
    """(p, u, x, d, flow, w): defaults, the initial state and a new Work, to call the algorithms once."""
    p, u = model.parameter_defaults, model.input_defaults
    return p, u.copy(), model.initial_state(p), model.initial_discrete(p), model.initial_flow, work(model)


def projects(model: CompiledModel, method: str, projection) -> bool:
    """Whether a fixed-step run of `method` projects after each step (integrator.Options.project): the projection
    method's constraint corrections, the energy correction, or the quaternions' norms (projection: a resolved
    andyc.runtime.options.Projection)."""
    constrain = method == "projection" and model.nc > 0
    return constrain or bool(projection.energy_correction) or (projection.normalize and bool(model.quaternions))


def free_model(model: CompiledModel) -> bool:
    """Whether the model has no constraint rows, jumps or contacts: what the integrator's free variant needs."""
    return model.nc == 0 and model.nj == 0 and not model.contact_names


def free_run(model: CompiledModel, method: str, projection) -> bool:
    """Whether a run of `method` takes the integrator's free variant (andyc_numerics' integrator.advance with
    full=None): a fixed-step method, a model without rows, jumps or contacts, no projection. Its steps are the
    full integrator's, operation for operation; Numba compiles it without the constrained solves, projection,
    event location and jumps, which a fresh installation's first run would otherwise wait for."""
    return method in FIXED_STEP and free_model(model) and not projects(model, method, projection)


FREE = (None, None, True)       # advance's trailing arguments (full, events, free) for its free variant
FREE_ROWS = (None, True)        # evaluate_rows' (full, free) after a run of the free variant
QUIET = (True, None, None, True)    # advance's (full, events, free, quiet) for a model without jumps, and
                                    # evaluate_rows' (full, free, slips, quiet) after its run: no events, no slips


def variant(model: CompiledModel, method: str, projection) -> tuple:
    """The trailing arguments (full, events, free, quiet) of the integrator's advance for a run (see its docstring):
    () for the full loop, FREE for the free variant (free_run), QUIET for a model without jumps, whose loop compiles
    without guards, event location, jumps and slips. Each is compiled once per andyc and cached."""
    return FREE if free_run(model, method, projection) else full_variant(model)


def full_variant(model: CompiledModel) -> tuple:
    """The trailing arguments (full, events, free, quiet) of the full loop for `model`: without events (hence
    without contacts, and their slips) where it has no jumps."""
    return QUIET if model.nj == 0 else ()


def rows_variant(model: CompiledModel, free: bool = False) -> tuple:
    """The trailing arguments (full, free, slips, quiet) of the integrator's evaluate_rows after a run of `model`:
    FREE_ROWS after a run of the free variant; without the slipping contacts' solve where it has no jumps (hence
    no contacts), as its loop (full_variant)."""
    return FREE_ROWS if free else QUIET if model.nj == 0 else ()


def compile_integrator(model: CompiledModel, function=None, data=None, method: str | None = None,
                       frames: bool = True, free: bool = False) -> None:
    """Compile what a run calls (or load it from Numba's cache) with the argument types simulate() passes: the
    integrator (a block of no steps, one-sample logs), the hybrid step, the log evaluations, and the
    right-hand side, guards and jumps that the adaptive methods call from Python. With an input function
    (and its data), the integrator's variant that calls it. With a method, only what a run of that method
    calls on this model (no guards without jumps, no constraint code without rows, no frames unless logged):
    each function loaded from the cache costs a warm `andyc sim` up to 40 ms. free (free_run): the integrator's
    free variant instead of the full one, so that a first run of a model without rows, jumps or contacts never
    compiles what it would not call. Without a method, everything (the free variant too where the model takes
    it), as
    `andyc build` does, so that no later run compiles. simulate() calls this before it starts its clock, so a
    run's wall time never includes compilation; once compiled for one model, the algorithms load from the
    cache for every other."""
    numerics, m = model.numerics, model.ref
    integrator = numerics.integrator
    every = method is None
    fixed, adaptive = every or method in FIXED_STEP, every or method in ADAPTIVE
    p, u, x, d, flow, w = sample_run(model)
    x = np.concatenate([x, np.zeros(model.nw)])      # the state and the work (andyc.runtime.work)
    log = integrator.Log(np.zeros(1), x[None, :].copy(), u[None, :].copy(), np.full(1, flow, dtype=np.int64),
                         d[None, :].copy())
    if fixed:
        opts = integrator.options(IDEAL, False, False, 0.0, -1.0, 1e-12)
        if free or (every and free_model(model)):
            integrator.advance(m, w.ref, opts, function, data, p, d.copy(), x.copy(), 0.0, flow, 0, 0, 0.0, 1e-3, 1,
                               log, 1, *FREE)
        if not free:
            integrator.advance(m, w.ref, opts, function, data, p, d.copy(), x.copy(), 0.0, flow, 0, 0, 0.0, 1e-3, 1,
                               log, 1, *full_variant(model))
    if (every or method in TIME_STEPPING) and (model.contact_names or model.friction_names):
        stepping = model.stepping
        s = model.stepping_scratch()
        stepping.coefficients(m, w.ref, s, p)
        stepping.advance(m, w.ref, s, 0.5, function, data, p, d.copy(), x.copy(), 0.0, flow, 0, 0, 0.0, 1e-3, 1,
                         log, np.zeros((1, model.nc)), 1)
    if model.nj or every:
        integrator.instant(m, w.ref, IDEAL, function, data, 0.0, x.copy(), p, d.copy(), flow)
    integrator.update_inputs(function, 0.0, x, p, d, flow, u, data)
    if function is not None:
        return
    integrator.evaluate_energy(m, log, p, np.zeros(1))
    model.flow_inputs(u, p)
    if frames:
        integrator.evaluate_frames(m, log, p, np.zeros((1, len(model.frame_names), 12)))
    rows = (np.zeros((1, model.nh)), np.zeros((1, model.nc)), np.zeros((1, model.nc)), np.zeros((1, model.nw)))
    if (model.nc or model.nw) and not free:
        integrator.evaluate_rows(m, w.ref, log, p, *rows, IDEAL, *rows_variant(model))
    if model.nw and (free or every) and free_model(model):
        integrator.evaluate_rows(m, w.ref, log, p, *rows, IDEAL, *FREE_ROWS)
    if model.nc or every:
        module = model.module
        module.constraints(0.0, x, u, p, d, np.empty(model.nh), np.empty(model.nc),
                           np.empty((model.nc, model.nv)), np.empty(model.nc))
    if model.nc:
        numerics.dynamics.project(m, w.ref, 0.0, x.copy(), u, p, d, flow, True, 0.0, -1.0)
    model.module.energy(0.0, x, u, p, d)             # the energy at the start, and a jump's change (runtime.work)
    if model.nj:
        numerics.dynamics.jump(m, w.ref, 0, 0.0, x.copy(), u, p, d.copy())
    if adaptive:
        numerics.dynamics.rhs_mode_into(m, w.ref, 0.0, x, u, p, d, flow, w.xdot, IDEAL)
        if model.nw:
            xdot = np.zeros(model.nx + model.nw)
            numerics.dynamics.rhs_mode_into(m, w.ref, 0.0, x, u, p, d, flow, xdot, IDEAL)
            integrator.stage_powers(m, w.ref, 0.0, x, u, p, d, flow, xdot, IDEAL)
    if adaptive and (model.nj or every):
        integrator.crosses(0, 1.0, -1.0)
        integrator.illinois_trial(0.0, 1.0, 1.0, -1.0, 1.0)
        integrator.illinois_bracket(1.0, 0.0, 1.0, 1.0, -1.0, 0, 0.5, -0.5)
        for f in (model.module.guard, model.module.enabled):     # (compiled also for a model without jumps)
            getattr(f, "__wrapped__", f)(0, 0.0, x, u, p, d)
