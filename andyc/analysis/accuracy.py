"""A run against the reference solution, reduced to the figures the work-precision sweeps and the stability
scans both use (one point of either).

The reference is the model's closed form where it declares one (closed_form:), else a DOP853 run at
rtol = atol = 1e-13. The closed form is the exact solution, so a run's error against it is the run's own
error, not the difference of two approximations; it is checked against the initial state before use.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

import andyc
from andyc.errors import SimulationError
from andyc.runtime.inputs import input_source
from andyc.runtime.methods import ADAPTIVE
from andyc.runtime.simulate import FIXED_STEP

REFERENCE_TOL = 1e-13
REFERENCE_SAMPLES = 200          # the reference's samples: its amplitude (scale) and its jumps
SOURCES = ("auto", "closed-form", "DOP853")
DOP853_SOURCE = f"DOP853, rtol = atol = {REFERENCE_TOL:g}"
CLOSED_FORM_SOURCE = "closed form"
START_TOL = 1e-9                 # the closed form at t = 0 must match the initial state to this x the amplitude


@dataclass
class ReferenceSolution:
    """The reference to T: its final state, amplitude and jump count, and which reference it is."""
    t_end: float
    final: np.ndarray
    scale: float                 # max |x| over its samples (at least 1e-300)
    jumps: int
    wall: float                  # seconds to run DOP853, or to evaluate the closed form at the samples
    source: str = DOP853_SOURCE  # what it is, for tables and titles: "closed form" or "DOP853, rtol = atol = 1e-13"


def reference_solution(model, t_end: float, source: str | ReferenceSolution = "auto",
                       **options) -> ReferenceSolution:
    """The reference run to t_end for `model` with andyc.simulate's `options` (parameters, inputs, x0, ...).

    source: "auto" -- the model's closed form when it declares one that holds for this run, else DOP853;
    "closed-form" -- the closed form, or SimulationError saying why there is none; "DOP853" -- always DOP853;
    or a ReferenceSolution made already (another model of the same motion, say), used as it is if it ends at
    t_end.
    """
    if isinstance(source, ReferenceSolution):
        if not math.isclose(source.t_end, t_end, rel_tol=1e-12):
            raise SimulationError(f"the reference ends at T = {source.t_end:g} s, the runs at {t_end:g} s")
        return source
    if source not in SOURCES:
        raise SimulationError(f"unknown reference '{source}'; use one of: {', '.join(SOURCES)}")
    if source != "DOP853":
        p, u, why_not = _closed_form_setting(model, t_end, options)
        if why_not is None:
            return _closed_form_reference(model, t_end, p, u, options.get("x0"))
        if source == "closed-form":
            raise SimulationError(f"no closed-form reference: {why_not}; compare with DOP853 instead")
        if model.closed_form is not None:       # say why the declared one is not used
            return _dop853_reference(model, t_end, f"{DOP853_SOURCE} (not the closed form: {why_not})", **options)
    return _dop853_reference(model, t_end, DOP853_SOURCE, **options)


def _dop853_reference(model, t_end: float, label: str, **options) -> ReferenceSolution:
    """The DOP853 reference run; the one long run of a sweep or scan, so it shows its progress on a terminal
    (andyc.runtime.progress)."""
    run = andyc.simulate(model, t_end, dt=t_end / REFERENCE_SAMPLES, method="DOP853", rtol=REFERENCE_TOL,
                         atol=REFERENCE_TOL, **options)
    if not run.finished:
        raise SimulationError(f"the reference run (DOP853, rtol {REFERENCE_TOL:g}) did not finish: {run.status}")
    return ReferenceSolution(t_end, run.state[-1].copy(), max(float(np.abs(run.state).max()), 1e-300),
                             len(run.events["time"]), run.stats["wall_seconds"], label)


def _closed_form_setting(model, t_end: float, options: dict) -> tuple:
    """(p, u, None): the parameters and held inputs of the run `options` describe, as andyc.simulate makes
    them; or (None, None, why the closed form does not describe that run).

    The closed form holds the inputs at their values, so a run whose own inputs are driven (an expression, a
    table, a controller) is not described by it; the model's own input expressions are (the loader keeps
    them out of the closed form, whose solution is then the driven one).
    """
    if model.closed_form is None:
        return None, None, f"{model.name} declares none (add 'closed_form:' to {model.source})"
    if options.get("controller") is not None:
        return None, None, f"the controller {options['controller']} drives the inputs, which the closed form holds"
    p = model.parameters(options.get("parameters"))
    run_inputs = options.get("inputs") or {}
    inputs = input_source(model, p, run_inputs, None, t_end)
    driven = [f"{n} ({inputs.drives[n]})" for n in run_inputs if n in inputs.drives]
    if driven:
        return None, None, f"the run drives {', '.join(driven)}, and the closed form holds the inputs"
    return p, inputs.held(model.initial_flow).copy(), None


def _closed_form_reference(model, t_end: float, p: np.ndarray, u: np.ndarray, x0=None) -> ReferenceSolution:
    """The closed form at the reference's samples t_k = k T / 200: x(T), max |x|, no jumps; wall is the
    time to evaluate it. Checked first at t = 0 against the run's initial state (x0, or the model's)."""
    times = np.linspace(0.0, t_end, REFERENCE_SAMPLES + 1)      # (its last entry is t_end exactly)
    start = time.perf_counter()
    xs = np.array([model.closed_form(float(t), u, p) for t in times])
    wall = time.perf_counter() - start
    bad = ~np.isfinite(xs)
    if bad.any():
        k, i = np.argwhere(bad)[0]
        raise SimulationError(f"{model.closed_form_location(i)}: {model.state_names[i]} is {xs[k, i]} at "
                              f"t = {times[k]:.6g} s; fix the closed form, or the parameters it is evaluated at")
    initial = np.asarray(model.initial_state(p) if x0 is None else x0, dtype=np.float64)
    if initial.shape != (model.nx,):
        raise SimulationError(f"initial state has shape {initial.shape}, expected ({model.nx},)")
    _check_start(model, xs, initial)
    return ReferenceSolution(t_end, xs[-1].copy(), max(float(np.abs(xs).max()), 1e-300), 0, wall, CLOSED_FORM_SOURCE)


def _check_start(model, xs: np.ndarray, initial: np.ndarray) -> None:
    """The closed form must start where the runs start: |x_i(0) - x0_i| <= START_TOL x the state's amplitude
    (max |x_i| over the samples and x0_i), plus round-off of the whole state (1e-15 x max |x|)."""
    amplitude = np.maximum(np.abs(xs).max(axis=0), np.abs(initial))
    bound = START_TOL * amplitude + 1e-15 * float(np.abs(xs).max())
    off = np.abs(xs[0] - initial) > bound
    if off.any():
        i = int(np.argmax(off))
        raise SimulationError(f"{model.closed_form_location(i)}: {model.state_names[i]} is {xs[0, i]:.9g} at "
                              f"t = 0, the initial state {initial[i]:.9g}; fix the closed form or the initial values")


def divides(step: float, t_end: float) -> float:
    """The step nearest `step` that divides t_end."""
    return t_end / max(1, round(t_end / step))


@dataclass
class Point:
    """One run: method and its setting (fixed step h, or rtol = atol for an adaptive method)."""
    method: str
    setting: float
    finished: bool
    status: str
    reached: float               # the time the run reached
    error: float                 # max |x(T) - x_ref(T)| over the state (inf when it did not reach T)
    growth: float                # max |x| over the run / the reference's max |x|
    residual: float              # largest constraint residual over the run (position and velocity rows)
    energy_drift: float          # max |E - E0| / |E0| over the run (NaN: the model does not conserve it)
    jumps: int
    wall: float                  # seconds (best of the repeats)
    rhs: int                     # right-hand-side evaluations
    blowup_at: float = math.nan  # first time |x| passed `blowup` x the reference's max |x|
    residual_at: float = math.nan  # first time a constraint residual passed `residual_tol`


def run_point(model, ref: ReferenceSolution, method: str, setting: float, repeats: int = 1, blowup: float = 1e3,
              residual_tol: float = 1e-6, **options) -> Point:
    """Run `method` at `setting` to ref.t_end and compare with the reference."""
    if method in FIXED_STEP:
        kwargs = {"dt": setting}
    elif method in ADAPTIVE:
        kwargs = {"dt": ref.t_end / REFERENCE_SAMPLES, "rtol": setting, "atol": setting}
    else:
        raise SimulationError(f"unknown method '{method}'")
    runs = [andyc.simulate(model, ref.t_end, method=method, progress=False, **kwargs, **options)
            for _ in range(repeats)]
    run = runs[0]
    with np.errstate(invalid="ignore", over="ignore"):
        reached = float(run.time[-1])
        at_end = run.finished and math.isclose(reached, ref.t_end, rel_tol=1e-12)
        error = float(np.abs(run.state[-1] - ref.final).max()) if at_end else math.inf
        finite = np.isfinite(run.state)
        growth = float(np.abs(run.state[finite]).max(initial=0.0)) / ref.scale
        residual = max(np.nanmax(np.abs(run.residual_position), initial=0.0),
                       np.nanmax(np.abs(run.residual_velocity), initial=0.0))
        e0 = abs(run.energy[0]) or 1.0
        # (a model that does not conserve energy has no drift to speak of: NaN, not its physical change)
        drift = (float(np.nanmax(np.abs(run.energy - run.energy[0]), initial=0.0)) / e0 if model.conserves_energy
                 else math.nan)
        big = ~(np.abs(np.nan_to_num(run.state, nan=np.inf)) <= blowup * ref.scale).all(axis=1)
        off = np.nanmax(np.abs(np.hstack([run.residual_position, run.residual_velocity])), axis=1,
                        initial=0.0) > residual_tol
    return Point(method, setting, run.finished, run.status, reached, error, growth, float(residual), drift,
                 len(run.events["time"]), min(r.stats["wall_seconds"] for r in runs), run.stats["rhs_evaluations"],
                 _first(run.time, big), _first(run.time, off))


def _first(t, mask) -> float:
    return float(t[np.argmax(mask)]) if mask.any() else math.nan
