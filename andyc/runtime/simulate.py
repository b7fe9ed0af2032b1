"""simulate(): one entry point over every integrator.

    rk4                fixed step, the compiled loop of the generated module; constraint
                       forces from a pseudo-inverse, no drift correction
    projection         rk4, then the Braun & Goldfarb position and velocity
                       corrections after every step (and energy, when the model
                       declares it conserved)
    lagrange           rk4 with Lagrange multipliers (ANDY eq. 10-12)
    baumgarte          rk4 with multipliers and soft terms (ANDY eq. 15)
    moreau             Moreau-Jean time-stepping for models with contacts: impulses
                       in every step, no event location (andyc.runtime.timestepping)
    DOP853 Radau LSODA scipy's adaptive solvers, stepped one step at a time so
                       that a failed run keeps what it computed

simulate() checks the options, sets up the initial state, the inputs and the event log, and hands them to a
driver; _Assembly turns the driver's log into the Run. The concepts live in their own modules:

    options.py     Events, Init, Projection: the run's options, grouped
    initial.py     the initial state: its consistency with the constraints, its projection, independent rows
    fixed_step.py  the fixed-step driver over the build's compiled loop
    timestepping.py  the moreau method's driver, a Python loop over the compiled leaves
    adaptive.py    the adaptive driver over SciPy's solvers, with event location on the dense output
    events.py      the jumps as they happen (EventLog: loops, Zeno, stop_after), applied from Python
    status.py      the run's status and its messages
    inputs.py      constants, expressions, tables or a controller, evaluated at every stage and logged
    interrupts.py  SIGINT, SIGTERM, the wall-clock limit and the watchdog
    progress.py    the progress line of long runs (on a terminal)

Runs stop, keep their samples and say why when the state becomes non-finite
or grows by orders of magnitude within one step (it diverges), the mass matrix
stops being positive definite or a controller fails; and when SIGINT or SIGTERM
arrives or a wall-clock limit passes (andyc.runtime.interrupts). Long runs
print progress (andyc.runtime.progress).
"""

from __future__ import annotations

import dataclasses
import math
import time
from dataclasses import dataclass

import numpy as np

from andyc.errors import SimulationError
from andyc.limits import MAX_LOG_BYTES, MAX_STEPS
from andyc.numerics.status import IDEAL
from andyc.runtime.adaptive import run_adaptive
from andyc.runtime.compiled import CompiledModel, compile_integrator, free_run, rows_variant, work
from andyc.runtime.contacts import TOUCHING, friction_coefficients, initial_mode, slip_speeds
from andyc.runtime.events import EventLog
from andyc.runtime.fixed_step import MODE, run_fixed_step
from andyc.runtime.initial import consistent_initial_state, initial_state, require_independent_rows
from andyc.runtime.inputs import InputSource, input_source, inputs_at
from andyc.runtime.interrupts import Interrupts
from andyc.runtime.methods import ADAPTIVE, FIXED_STEP, METHODS
from andyc.runtime.options import Events, Init, Projection, TimeStepping
from andyc.runtime.progress import Progress
from andyc.runtime.run import Run, unit_quaternions
from andyc.runtime.status import FINISHED, lost_constraints
from andyc.runtime.timestepping import check_model, refuse_friction, run_moreau


def simulate(model: CompiledModel, t_end: float, dt: float = 1e-3, method: str = "rk4", *,
             parameters: dict | None = None, inputs: dict | None = None, x0=None, d0=None,
             flow0: str | int | None = None, every: int = 1, frames=None, rtol: float = 1e-8, atol: float = 1e-10,
             controller=None, progress: bool | None = None, interrupts: Interrupts | None = None,
             events: Events = Events(), init: Init = Init(), projection: Projection = Projection(),
             sensitivities=False, stepping: TimeStepping = TimeStepping()) -> Run:
    """Integrate `model` from t = 0 to t_end and return the logged Run.

    dt is the step of the fixed-step methods and the output spacing of the adaptive ones; every N logs one
    sample in N steps. frames: None, "all" or a list of names. parameters: {name: value} over the defaults.
    inputs: {name: value}, a value being a number, an expression of t and the states (a string) or a CSV
    table (a path ending in .csv); controller: a Python file defining control(t, x, d, p), which drives
    every input (see andyc.runtime.inputs). rtol, atol: the adaptive methods' tolerances.
    x0, d0 and flow0 (a name or index): the initial state, discrete states and flow (default the model's; x0 and
    d0 either whole arrays or {name: value} over the model's initial values, e.g. x0={"q1": 0.7}; with
    contacts and no d0, each contact's mode in d is that of a run starting there: closed where it touches at
    rest, andyc.runtime.contact_modes.initial_mode).
    progress: print t / t_end to stderr (default: when it is a terminal).
    interrupts: what may stop the run from outside (andyc.runtime.interrupts; default: SIGINT and
    SIGTERM, which then end the run with the status "interrupted: ..." instead of raising).

    events: event location and the stops of hybrid runs (Events: tol, max_instant_jumps, zeno_tol,
    stop_after); init: what a constrained run does with an initial state off the constraint manifold
    (Init: mode, tol); projection: what the fixed-step methods correct after each step (Projection:
    normalize, energy_correction, energy_tol); stepping: the moreau method's scheme (TimeStepping: theta). See
    andyc.runtime.options.

    sensitivities: also compute the exact derivatives of the run's end state, Run.sensitivities: "x0" dx(T)/dx0,
    "d0" dx(T)/dd0, "p" dx(T)/dp (x0 and d0 held), "time" dT/d(x0, d0, p) (nonzero when the run ends
    at a jump, stop_after) and "discrete" dd(T)/d(x0, d0, p), through the same RK4 steps and the saltation matrix of each jump
    (andyc.runtime.sensitivities: the rk4, lagrange and projection methods; needs the build's derivatives,
    andyc.build_derivatives). sensitivities may instead be an array Z (nx + nd + np, k) of directions in
    z = (x0, d0, p): then only the derivatives along them are carried (cheaper when k is small), in
    Run.sensitivities["directions"] = dx(T)/dz Z, and "time", "discrete" and "before_jump" with k columns.
    """
    frame_names = _frame_selection(model, frames)
    ready = start_run(model, t_end, dt, method, parameters=parameters, inputs=inputs, x0=x0, d0=d0, flow0=flow0,
                      every=every, controller=controller, events=events, init=init, projection=projection,
                      stepping=stepping, frames=bool(frame_names))
    projection, p, source, x, d, flow = ready.projection, ready.p, ready.source, ready.x, ready.d, ready.flow
    jumps, initial, free = ready.jumps, ready.initial, ready.free
    tangent = None
    directions = None if isinstance(sensitivities, bool) else np.asarray(sensitivities, float)
    if directions is not None or sensitivities:
        from andyc.runtime.sensitivities import Tangent, check, load_derivatives
        check(model, method, source, controller, projection)
        tangent = Tangent(model, load_derivatives(model), p, source.held(flow), method, projection, directions)
    bar = Progress(f"{model.name} {method}", t_end, enabled=progress)
    interrupts = interrupts or Interrupts()
    start = time.perf_counter()
    run_of = _Assembly(model, method, dt, rtol, atol, t_end, p, source, frame_names, jumps,
                       projection.energy_correction, initial, start, free)
    try:
        with interrupts.watching():
            forces = None
            if method == "moreau":
                log, status, stats, forces = run_moreau(model, x, source, p, d, flow, t_end, dt, every,
                                                        stepping.theta, bar, interrupts, run_of)
            elif method in FIXED_STEP:
                log, status, stats = run_fixed_step(model, method, x, source, p, d, flow, t_end, dt, every, projection,
                                                    bar, jumps, interrupts, run_of, tangent)
            else:
                log, status, stats = run_adaptive(model, method, x, source, p, d, flow, t_end, dt * every, rtol, atol,
                                                  bar, jumps, interrupts, run_of)
            interrupts.stopped = True
    finally:
        bar.close()
    run = run_of(log, status, stats, forces)
    if tangent is not None:
        run.sensitivities = tangent.result()
    return run


@dataclass
class Start:
    """What a run starts from, checked (start_run): the resolved projection options, the parameters, the input
    source, the initial state (x, d, flow; x on the constraints as init asked), the event log, the initial state's
    figures (run stats) and whether the run takes the integrator's free variant."""
    projection: Projection
    p: np.ndarray
    source: InputSource
    x: np.ndarray
    d: np.ndarray
    flow: int
    jumps: EventLog
    initial: dict
    free: bool


def start_run(model: CompiledModel, t_end: float, dt: float = 1e-3, method: str = "rk4", *,
              parameters: dict | None = None, inputs: dict | None = None, x0=None, d0=None, flow0=None,
              every: int = 1, controller=None, events: Events = Events(), init: Init = Init(),
              projection: Projection = Projection(), stepping: TimeStepping = TimeStepping(), frames: bool = False,
              compile: bool = True) -> Start:
    """Check simulate()'s options and set up the start of its run (the arguments are simulate's; frames: whether
    the run logs frames). SimulationError (InitialStateError) where simulate would refuse the run. compile: also
    compile what the run calls (simulate); a caller that compiled it already (the batched sweep engine,
    andyc.analysis.sweeps.batch) passes False."""
    _check_option("events", events, Events)
    _check_option("init", init, Init)
    _check_option("projection", projection, Projection)
    _check_option("stepping", stepping, TimeStepping)
    if method not in METHODS:
        raise SimulationError(f"unknown method '{method}'; available: {', '.join(METHODS)}")
    if method == "moreau":
        check_model(model, stepping.theta)
    refuse_friction(model.friction_names, method, f"{model.source}: ")
    projection = _energy_correction(model, method, projection)
    if not (math.isfinite(t_end) and math.isfinite(dt) and t_end > 0 and dt > 0 and every >= 1):
        raise SimulationError(f"need t_end > 0, dt > 0 and every >= 1, got t_end={t_end}, dt={dt}, every={every}")
    _check_size(model, t_end, dt, every)
    p = model.parameters(parameters)
    _check_coefficients(model, p, parameters)
    source = input_source(model, p, inputs, controller, t_end)
    x, d, flow = initial_state(model, p, x0, d0, flow0)
    jumps = EventLog(model, events)
    free = free_run(model, method, projection)
    if compile:
        compile_integrator(model, method=method, frames=frames, free=free)
        compile_integrator(model, *source.function_data, method=method, free=free)
    u = inputs_at(model, source, 0.0, x, p, d, flow)
    if d0 is None and model.contact_names:      # contacts touching at rest start closed
        initial_mode(model, 0.0, x, u, p, d, flow)
        sunk = _close_sunk(model, x, u, p, d)   # (a contact that starts inside its surface: see _close_sunk)
    initial = consistent_initial_state(model, x, u, p, d, flow, init) if model.nc else {}
    if d0 is None and model.contact_names and sunk:
        initial_mode(model, 0.0, x, u, p, d, flow)
    if method in ("lagrange", "baumgarte") and model.nc:
        require_independent_rows(model, method, x, u, p, d, flow)
    if projection.energy_correction:
        _require_free_speed(model, x, u, p, d, flow)
        _check_declared_law(model, x, u, p, d, flow, init)
    return Start(projection, p, source, x, d, flow, jumps, initial, free)


def assemble(model: CompiledModel, ready: Start, method: str, dt: float, t_end: float, log, frames=(),
             stats: dict | None = None) -> Run:
    """The Run of a fixed-step run that started from `ready` (start_run) and reached t_end having logged `log`
    (integrator.Log's arrays, the state with its work), as simulate() returns it: the points of the batched sweep
    engine (andyc.analysis.sweeps.batch), whose loops ran apart from simulate's driver. frames: names to log."""
    run_of = _Assembly(model, method, dt, 0.0, 0.0, t_end, ready.p, ready.source, _frame_selection(model, list(frames)),
                       ready.jumps, ready.projection.energy_correction, ready.initial, time.perf_counter(), ready.free)
    return run_of(log, FINISHED, stats or {})


def _check_option(name: str, value, kind: type) -> None:
    if not isinstance(value, kind):
        raise TypeError(f"simulate's {name} is an andyc.{kind.__name__}, e.g. {name}=andyc.{kind.__name__}(...); "
                        f"got {value!r}")


def compile_run(model: CompiledModel, method: str | None = "rk4") -> None:
    """Compile, or load from Numba's cache, what a run of `method` with its default options calls on `model`, its
    frames and its input expressions included, as simulate() does before it starts its clock: what `andyc build`
    compiles for the model's own method. A first build then waits for that alone (a model without constraint
    rows, jumps or contacts run by rk4: the integrator's free variant, seconds; the full loop: a minute or more,
    once per installation), not for every method's. method None: what a run of any method may call (`andyc
    build --method all`), so that no later run compiles."""
    if method is not None and method not in METHODS:
        raise SimulationError(f"unknown method '{method}'; available: {', '.join(METHODS)}")
    free = method is not None and free_run(model, method, _energy_correction(model, method, Projection()))
    compile_integrator(model, method=method, free=free)
    source = input_source(model, model.parameter_defaults)
    if source.function_data[0] is not None:
        compile_integrator(model, *source.function_data, method=method, free=free)


def _energy_correction(model: CompiledModel, method: str, projection: Projection) -> Projection:
    """projection with energy_correction decided: by default on for the projection method of a model that
    declares energy conserved. Asked for, it corrects to the energy balance E - E0 - W = 0 (W the work of every
    element, andyc.runtime.work; 0 on a conservative model): refused for another method, and for a model whose
    balance is not known (a frame moved by a link that depends on t)."""
    declared = any(law is not None for law in model.energy_laws)
    if projection.energy_correction is None:
        return dataclasses.replace(projection, energy_correction=(model.conserves_energy or declared)
                                   and method == "projection")
    if projection.energy_correction and method != "projection":
        raise SimulationError(f"energy correction needs the projection method, not {method}; use --method projection")
    builtin = not model.energy_laws or None in model.energy_laws       # a flow keeps the built-in law
    if projection.energy_correction and model.untracked_work and builtin:
        raise SimulationError(f"{model.source}: energy correction: the energy law E - E0 - W = 0 is not known: frame "
                              f"'{model.untracked_work[0]}' moves by a link that depends on t, whose driving work "
                              "andyc does not derive; run without --energy-correction")
    return projection


def _require_free_speed(model: CompiledModel, x, u, p, d, flow) -> None:
    """An energy correction needs a speed the constraints leave free at the start (Braun & Goldfarb eq. 6:
    the direction N L^T v is 0 when the rows fix every speed); FILE:LINE of the first row when they do."""
    rows = model.active_rows(flow)
    if not rows:
        return
    A = np.zeros((model.nc, model.nv))
    model.module.constraints(0.0, x, u, p, d, np.empty(model.nh), np.empty(model.nc), A, np.empty(model.nc))
    rank = np.linalg.matrix_rank(A[rows])
    if rank >= model.nv:
        line, path = model.constraint_where[rows[0]]
        raise SimulationError(f"{model.source}:{line}: {path}: the energy law has no speed to correct: the "
                              f"{len(rows)} constraint rows active at the start fix all {model.nv} speeds (rank "
                              f"{rank}); run without energy correction")


def _check_declared_law(model: CompiledModel, x, u, p, d, flow, init: Init) -> None:
    """The initial flow's declared energy law (andyc.spec.energy_law) at the start: it must hold to init.tol (unless
    init is "as-is": the first step's correction then moves the speeds onto it), and the constraints must leave
    its gradient a direction to correct along (N L^-1 dPhi_e/dv^T != 0, eq. 6); FILE:LINE of the law if not."""
    if flow >= len(model.energy_laws) or model.energy_laws[flow] is None:
        return
    line, path = model.energy_law_where[flow]
    where = f"{model.source}:{line}: {path}"
    value, grad = model.module.energy_law(0.0, x, u, p, d, flow)
    if init.mode != "as-is" and not abs(value) <= init.tol:
        raise SimulationError(f"{where}: the energy law {model.energy_laws[flow]!r} is {value:.6g} at the initial "
                              f"state, not 0 (within {init.tol:g}); correct its constants to the initial state, or "
                              "start with --init as-is to let the first step move the speeds onto it")
    L = np.linalg.cholesky(model.module.mass_matrix(0.0, x, u, p, d))
    r = np.linalg.solve(L, grad)
    rows = model.active_rows(flow)
    if rows:
        A = np.zeros((model.nc, model.nv))
        model.module.constraints(0.0, x, u, p, d, np.empty(model.nh), np.empty(model.nc), A, np.empty(model.nc))
        C = np.linalg.solve(L, A[rows].T).T         # A L^-T
        r = r - np.linalg.pinv(C) @ (C @ r)
    if not np.dot(r, r) > 1e-300:
        raise SimulationError(f"{where}: the energy law has no speed to correct at the start: its gradient dPhi_e/dv "
                              "lies in the span of the active constraint rows; declare a law the constraints leave "
                              "free, or run without energy correction")


@dataclass
class _Assembly:
    """Builds the Run of a log: the samples with the energy, the residuals, the multipliers and the frames at
    each. Called at the end of a run, and by the watchdog on the samples so far (andyc.runtime.interrupts)."""
    model: CompiledModel
    method: str
    dt: float
    rtol: float
    atol: float
    t_end: float
    p: np.ndarray
    source: InputSource
    frame_names: list
    jumps: EventLog
    energy_correction: bool
    initial: dict               # figures of the initial state's consistency (consistent_initial_state)
    start: float                # perf_counter() when the run started
    free: bool                  # the run took the integrator's free variant (free_run): so do its log's powers

    def __call__(self, log, status: str, stats: dict, forces=None) -> Run:
        """forces: the moreau method's mean contact forces (N, nc), its multipliers from the second sample on."""
        model, p, frame_names, fixed = self.model, self.p, self.frame_names, self.method not in ADAPTIVE
        stats = {**stats, "wall_seconds": time.perf_counter() - self.start, "jumps": len(self.jumps.times),
                 **self.initial}
        t_log, x_log, u_log, f_log, d_log = log        # x_log: the state, then the work (andyc.runtime.work)
        n = t_log.shape[0]
        energy = np.empty(n)
        integrator = model.numerics.integrator
        log = integrator.Log(t_log, x_log, u_log, f_log, d_log)
        integrator.evaluate_energy(model.ref, log, p, energy)
        phi, c, lam = np.empty((n, model.nh)), np.empty((n, model.nc)), np.empty((n, model.nc))
        power = np.empty((n, model.nw))
        if model.nc or model.nw:
            integrator.evaluate_rows(model.ref, work(model).ref, log, p, phi, c, lam, power,
                                     MODE.get(self.method, IDEAL), *rows_variant(model, self.free))
        if forces is not None:
            lam[1:] = forces[1:]
        slip, slip_2 = slip_speeds(model, t_log, x_log, u_log, p, d_log) if model.contact_names else (None, None)
        frames_out, rotations = {}, {}
        if frame_names:
            poses = np.empty((n, len(model.frame_names), 12))
            integrator.evaluate_frames(model.ref, log, p, poses)
            at = {name: model.frame_names.index(name) for name in frame_names}
            frames_out = {name: poses[:, k, :3].copy() for name, k in at.items()}
            rotations = {name: unit_quaternions(poses[:, k, 3:].reshape(n, 3, 3)) for name, k in at.items()}
        status = lost_constraints(self.method, status, phi, c, t_log)
        held = u_log[0] if n else self.source.held(model.initial_flow)
        return Run(model=model.name, spec_sha256=model.spec_sha256, method=self.method, dt=self.dt, nq=model.nq,
                   nv=model.nv, rtol=0.0 if fixed else self.rtol, atol=0.0 if fixed else self.atol, t_end=self.t_end,
                   parameters=dict(zip(model.parameter_names, map(float, p))),
                   inputs={n: self.source.drives.get(n, float(v)) for n, v in zip(model.input_names, held)},
                   state_names=list(model.state_names), time=t_log, state=np.ascontiguousarray(x_log[:, :model.nx]),
                   work_names=list(model.work_names), work=np.ascontiguousarray(x_log[:, model.nx:]), power=power,
                   input_names=list(model.input_names),
                   input_values=u_log, energy=energy, frames=frames_out, frame_rotations=rotations, status=status,
                   stats=stats,
                   multiplier_names=list(model.multiplier_names), multipliers=lam, residual_position=phi,
                   residual_velocity=c, energy_correction=bool(self.energy_correction),
                   flow=f_log, flow_names=list(model.flow_names), discrete_names=list(model.discrete_names),
                   discrete=d_log, events=self.jumps.table(), jump_names=list(model.jump_names),
                   frame_parents={name: model.frame_parents[model.frame_names.index(name)] for name in frame_names},
                   display=model.display, contact_names=list(model.contact_names),
                   contact_rows=list(model.contact_rows), contact_stick_rows=list(model.contact_stick_rows),
                   contact_mu=list(friction_coefficients(model, p)) if model.contact_names else [],
                   slip_speeds=slip, slip_speeds_2=slip_2, contact_tangents=model.tangents)


def _close_sunk(model: CompiledModel, x, u, p, d) -> bool:
    """Close (mode 1, into d) every open contact whose gap starts below zero (beyond TOUCHING, a rounding: a foot
    leaving the ground at the start): its impact would never come (its guard
    is past zero), and the body would fall through. Closed, its row is checked like any active row by the initial
    state's check (consistent_initial_state: refused past init.tol, with the contact's line; moved onto the surface
    with init 'project'; kept with 'as-is'), as `andyc check` refuses it. Returns whether any was."""
    phi = np.empty(model.nh)
    model.module.constraints(0.0, x, u, p, d, phi, np.empty(model.nc), np.empty((model.nc, model.nv)),
                             np.empty(model.nc))
    bad = [i for i, r in enumerate(model.contact_rows) if not np.isfinite(phi[r])]
    if bad:
        line, path = model.constraint_where[model.contact_rows[bad[0]]]
        raise SimulationError(f"{model.source}:{line}: {path}: the gap of contact '{model.contact_names[bad[0]]}' is "
                              f"{phi[model.contact_rows[bad[0]]]} at the initial state; write it so that it is real "
                              "and finite there (a square root of a negative number, a division by zero?)")
    states = model.contact_states(d)
    sunk = [i for i, r in enumerate(model.contact_rows) if states[i] == 0 and phi[r] < -TOUCHING]
    for i in sunk:
        states[i] = 1
    model.set_contact_states(d, states)
    return bool(sunk)


def _check_coefficients(model: CompiledModel, p, given: dict | None) -> None:
    """The coefficients the model file checks at its defaults (andyc.spec.hybrid.restitution,
    andyc.spec.contacts.friction_coefficient), checked again at the run's parameters: a restitution in [0, 1] (more
    would add energy at every impact), a friction coefficient >= 0, a joint friction's force >= 0. SimulationError
    naming the contact, jump or friction and the parameters given."""
    if not model.nj and not model.friction_names:
        return
    values = model.module.restitutions(p)
    at = ", ".join(f"{k} = {float(v):g}" for k, v in (given or {}).items()) or "the defaults"
    for i, name in enumerate(model.friction_names):
        if not values[model.nj + i] >= 0.0:
            raise SimulationError(f"joint friction '{name}': its force is {values[model.nj + i]:g} at {at}, negative; "
                                  "give a force (a torque on a rotation) >= 0")
    for k, (kind, i) in enumerate(model.jump_kinds):
        owner = f"contact '{model.contact_names[i]}'" if kind else f"jump '{model.jump_names[k]}'"
        if kind == "stop" and not values[k] >= 0.0:
            raise SimulationError(f"{owner}: its friction coefficient is {values[k]:g} at {at}, negative; give "
                                  "Coulomb's coefficient mu >= 0")
        if (kind == "impact" or (not kind and model.module.IMPACT_NROWS[k] > 0)) and not 0.0 <= values[k] <= 1.0:
            raise SimulationError(f"{owner}: its coefficient of restitution is {values[k]:g} at {at}, outside "
                                  "[0, 1]; give 0 (plastic) to 1 (elastic): more would add energy at every impact")


def _check_size(model: CompiledModel, t_end: float, dt: float, every: int) -> None:
    """Refuse a run whose steps or logged samples no machine could hold, before anything is allocated."""
    steps = t_end / dt
    if steps > MAX_STEPS:
        raise SimulationError(f"t_end / dt = {steps:.3g} steps, past the limit of {MAX_STEPS:.0e}; raise dt or "
                              f"shorten t_end")
    width = 2 + model.nx + model.nw + len(model.input_names) + model.nd
    size = (steps / every + 2) * width * 8
    if size > MAX_LOG_BYTES:
        raise SimulationError(f"the run would log {steps / every:.3g} samples ({size / 1e9:.3g} GB), past the "
                              f"limit of {MAX_LOG_BYTES / 1e9:g} GB; log fewer with a larger --every, or raise dt")


def _frame_selection(model: CompiledModel, frames) -> list:
    if frames is None or frames == []:
        return []
    if frames == "all":
        return list(model.frame_names)
    names = frames.split(",") if isinstance(frames, str) else list(frames)
    unknown = [f for f in names if f not in model.frame_names]
    if unknown:
        raise SimulationError(f"unknown frame(s) {', '.join(unknown)}; frames: {', '.join(model.frame_names)}")
    return names
