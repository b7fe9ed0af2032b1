"""One sweep point: a run of the model against the reference, reduced to the figures both analyses use."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import andyc
from andyc.errors import SimulationError
from andyc.runtime.simulate import FIXED_STEP, SCIPY_METHODS

REFERENCE_TOL = 1e-13
REFERENCE_SAMPLES = 200          # the reference's samples: its amplitude (scale) and its jumps


@dataclass
class Reference:
    """The reference run to T: its final state, amplitude and jump count."""
    t_end: float
    final: np.ndarray
    scale: float                 # max |x| over its samples (at least 1e-300)
    jumps: int
    wall: float


def reference(model, t_end: float, **options) -> Reference:
    run = andyc.simulate(model, t_end, dt=t_end / REFERENCE_SAMPLES, method="DOP853", rtol=REFERENCE_TOL,
                         atol=REFERENCE_TOL, progress=False, **options)
    if not run.finished:
        raise SimulationError(f"the reference run (DOP853, rtol {REFERENCE_TOL:g}) did not finish: {run.status}")
    return Reference(t_end, run.state[-1].copy(), max(float(np.abs(run.state).max()), 1e-300),
                     len(run.events["time"]), run.stats["wall_seconds"])


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
    energy_drift: float          # max |E - E0| / |E0| over the run
    jumps: int
    wall: float                  # seconds (best of the repeats)
    rhs: int                     # right-hand-side evaluations
    blowup_at: float = math.nan  # first time |x| passed `blowup` x the reference's max |x|
    residual_at: float = math.nan  # first time a constraint residual passed `residual_tol`


def run_point(model, ref: Reference, method: str, setting: float, repeats: int = 1, blowup: float = 1e3,
              residual_tol: float = 1e-6, **options) -> Point:
    """Run `method` at `setting` to ref.t_end and compare with the reference."""
    if method in FIXED_STEP:
        kwargs = {"dt": setting}
    elif method in SCIPY_METHODS:
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
        drift = float(np.nanmax(np.abs(run.energy - run.energy[0]), initial=0.0)) / e0
        big = ~(np.abs(np.nan_to_num(run.state, nan=np.inf)) <= blowup * ref.scale).all(axis=1)
        off = np.nanmax(np.abs(np.hstack([run.residual_position, run.residual_velocity])), axis=1,
                        initial=0.0) > residual_tol
    return Point(method, setting, run.finished, run.status, reached, error, growth, float(residual), drift,
                 len(run.events["time"]), min(r.stats["wall_seconds"] for r in runs), run.stats["rhs_evaluations"],
                 _first(run.time, big), _first(run.time, off))


def _first(t, mask) -> float:
    return float(t[np.argmax(mask)]) if mask.any() else math.nan
