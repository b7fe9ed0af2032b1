"""Basins of attraction of a periodic orbit (`andyc cycle --basin`): which starting states reach it.

The orbit is andyc.analysis.cycles' fixed point of the Poincaré map Q of a jump J (the section), with its
visits y*_1..y*_N just after J (N = the period). A point of the grid is a starting state y0 = (x0, d0): the
orbit's first visit y*_1 with the grid's components set (states only), then put back on the constraint
manifold of J's target flow by Gauss-Newton on its rows (phi, c) = 0, moving only the other components
(least-norm steps in them), so that the grid's values are the run's own. From y0 the point runs step by step,
as `andyc sim --stop-after J=1` does (rk4, each step from the state just after the previous crossing of J,
for at most `t_step` seconds), for at most K steps, and is classified:

    cycle        some y_n (just after J's n-th crossing) is within tol of a visit y*_i, in the largest
                 component of the difference, once the model's symmetries s are taken out
                 (|(I - S S^T)(y_n - y*_i)|_inf <= tol, S the orthonormal symmetry directions of
                 cycles.section_basis: a walker's place down the slope does not matter)
    falls        the fall condition (a comparison of the step's run, as a sweep's metric: `min(y) < 0.5`)
                 holds after a step, or a step does not reach J: no crossing within t_step, or the run
                 ended early (blew up, Zeno, stopped, failed)
    other orbit  after K steps, y_K repeats with a period m <= max_period (|P(y_K - y_{K-m})|_inf <= tol,
                 the smallest such m) and lies more than 100 tol from the cycle's visits (so that a point
                 still converging onto the cycle, slowly, is not taken for another orbit)
    other        none of these within K steps, or a start that could not run (its grid values held, the
                 constraints cannot be met; a run that raised): its outcome is then "failed", with the message

A point stops as soon as it is classified. The classes, their codes and the period m of an other orbit are
what the sweep store records (`basin`, `basin_period`, with `basin_steps` the steps run and
`basin_distance` the distance of the last y_n from the cycle). The runs are the sweep engine's
(andyc.analysis.sweeps): each worker steps its batch's starts together (andyc.analysis.basins_batched), each
step of every start in one compiled call, and classifies each start with Walk as classify does with single
runs, to the same bit. See Schwab & Wisse, "Basin of attraction
of the simplest walking model" (ASME DETC 2001), for such maps of a walker.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass

import numpy as np

CLASSES = {0: "not run", 1: "cycle", 2: "other orbit", 3: "falls", 4: "other"}
CYCLE, OTHER_ORBIT, FALLS, OTHER = 1, 2, 3, 4
OTHER_ORBIT_MARGIN = 100.0        # an other orbit lies more than this many tol from the cycle


@dataclass(frozen=True)
class Basin:
    """A basin's classification, as plain data a sweep task carries (andyc.analysis.sweeps.worker.Settings)."""
    section: int                # J's index
    steps: int                  # K: steps at most
    orbit: tuple                # the cycle's visits y*_i = (x, d) just after J, a tuple per visit
    symmetries: tuple           # the symmetry directions in y, a tuple per direction (orthonormal)
    tol: float
    t_step: float               # the longest one step may take, s
    dt: float
    event_tol: float
    fall: str = ""              # the fall condition (a comparison of the step's run), or "" for none
    max_period: int = 8
    parameters: tuple = ()      # (name, value) of the cycle's parameters

    def options(self) -> dict:
        return asdict(self)


class BasinError(ValueError):
    """A basin request that cannot run (a fall condition that is not a comparison); the message says why."""


def make_basin(model, cycle, steps: int, tol: float, t_step: float, dt: float, event_tol: float, fall: str = "",
               max_period: int = 8) -> Basin:
    """The Basin of a converged andyc.analysis.cycles.Cycle: its visits just after the section (Q run once
    more from the fixed point, no Jacobian) and its symmetries."""
    from andyc.analysis.cycles import PoincareMap
    from andyc.runtime.sensitivities import load_derivatives

    k = model.jump_names.index(cycle.section)
    p = model.parameters(cycle.parameters)
    if fall:
        fall_metric(model, fall)                    # refused here, before any worker runs
    image = PoincareMap(model, load_derivatives(model), k, p, cycle.period_count, dt, t_step * cycle.period_count,
                        event_tol)(cycle.before, jacobian=False)
    if image.y is None:
        raise BasinError(f"the cycle's fixed point did not come back to '{cycle.section}' ({image.status})")
    visits = image.visits[1][:cycle.period_count]
    sym = np.zeros((0, len(cycle.before))) if cycle.symmetries is None else cycle.symmetries.T
    return Basin(k, steps, tuple(map(tuple, visits.tolist())), tuple(map(tuple, sym.tolist())), tol, t_step, dt,
                 event_tol, fall, max_period, tuple(cycle.parameters.items()))


def fall_metric(model, text: str):
    """The parsed fall condition (andyc.analysis.sweeps.metrics); BasinError unless it is one comparison."""
    from andyc.analysis.sweeps.metrics import MetricError, compile_metric

    try:
        metric = compile_metric("fall", text, model)
    except MetricError as exc:
        raise BasinError(str(exc).replace("--metric fall", f"--fall '{text}'")) from None
    if not metric.compare:
        raise BasinError(f"--fall '{text}': not a comparison; write a condition of a step's run, e.g. min(y) < 0.5")
    return metric


_CACHE: dict = {}           # (build path, build key, fall) -> (derivatives, fall metric): once per process


def _loaded(model, basin: Basin):
    from andyc.runtime.sensitivities import load_derivatives

    key = (str(model.path), model.module.BUILD_KEY, basin.fall)
    if key not in _CACHE:
        _CACHE[key] = (load_derivatives(model), fall_metric(model, basin.fall) if basin.fall else None)
    return _CACHE[key]


def start_state(model, derivatives, basin: Basin, held: list, values, iterations: int = 20) -> np.ndarray:
    """y0: the orbit's first visit with the components `held` (indices in y) set to `values`, put on the
    constraint manifold of J's target flow by moving the other components only (Gauss-Newton, least-norm
    steps). SimulationError when it cannot get there."""
    from andyc.analysis.cycles import _section_rows
    from andyc.errors import SimulationError

    y = np.array(basin.orbit[0], dtype=float)
    y[held] = values
    flow = int(model.module.JUMP_TARGET[basin.section])
    p = model.parameters(dict(basin.parameters))
    free = np.setdiff1d(np.arange(len(y)), held)
    for _ in range(iterations):
        h, H = _section_rows(model, derivatives, flow, basin.section, p, y, guard=False)
        if not len(h) or np.max(np.abs(h)) <= 1e-13 * max(1.0, np.max(np.abs(y))):
            return y
        y[free] -= np.linalg.lstsq(H[:, free], h, rcond=None)[0]
    raise SimulationError(f"cannot put the start on the constraint manifold with {', '.join(_names(model, held))} "
                          f"held (residual {np.max(np.abs(h)):.2g}); sweep other components")


def _names(model, indices) -> list:
    names = list(model.state_names) + list(model.discrete_names)
    return [names[i] for i in indices]


class Walk:
    """One start's classification as its steps come in (take): the steps of a single run each (classify) or of
    the batched engine (andyc.analysis.basins_batched), read alike. `out` is the record: class, period, steps,
    distance, the crossing times, the last step's status and end (x, d, flow), the total time, the jump counts."""

    def __init__(self, model, basin: Basin, y: np.ndarray, fall):
        self.model, self.basin, self.fall = model, basin, fall
        self.orbit = np.asarray(basin.orbit, dtype=float)
        S = np.asarray(basin.symmetries, dtype=float).reshape(-1, self.orbit.shape[1]).T
        self.project = np.eye(self.orbit.shape[1]) - S @ S.T
        self.y, self.history, self.done = y, [y], False
        self.out = {"class": OTHER, "period": 0, "steps": 0, "distance": math.nan, "times": [], "t": 0.0,
                    "jump_count": np.zeros(model.nj, np.int32), "status": "", "end": None, "message": ""}

    def distance(self, a, b) -> float:
        return float(np.max(np.abs(self.project @ (a - b))))

    def take(self, crossed: bool, status: str, t: float, jumps, times, end, run) -> bool:
        """The next step ended at its time t (from 0), with status, its jumps and their times, its last state
        end = (x, d, flow) (None when it logged nothing), crossed: right after J's crossing (stop_after); run():
        its Run, for the fall condition. Whether the point is classified now (done)."""
        basin, out = self.basin, self.out
        out["steps"] += 1
        n = out["steps"]
        out["status"], out["end"] = status, end
        jumps = np.asarray(jumps, dtype=np.int64)
        out["jump_count"] += np.bincount(jumps, minlength=self.model.nj)[:self.model.nj].astype(np.int32)
        out["times"].extend((out["t"] + np.asarray(times)[jumps == basin.section]).tolist())
        out["t"] += t
        if self.fall is not None and _holds(self.fall, run()):
            return self._classified(FALLS, 0, f"step {n}: the fall condition holds ({basin.fall})")
        if not crossed:
            return self._classified(FALLS, 0, f"step {n}: no crossing of '{self.model.jump_names[basin.section]}' "
                                              f"within {basin.t_step:g} s ({status})")
        self.y = np.concatenate([end[0], end[1]])
        self.history.append(self.y)
        out["distance"] = min(self.distance(self.y, o) for o in self.orbit)
        if out["distance"] <= basin.tol:
            return self._classified(CYCLE, len(self.orbit), f"step {n}: within {basin.tol:g} of the cycle")
        if n >= basin.steps:
            self._conclude()
        return self.done

    def _classified(self, kind: int, period: int, message: str) -> bool:
        self.out["class"], self.out["period"], self.out["message"], self.done = kind, period, message, True
        return True

    def _conclude(self) -> None:
        """After K steps: an other orbit, or other."""
        basin, out, history = self.basin, self.out, self.history
        for m in range(1, basin.max_period + 1):
            if m < len(history) and self.distance(history[-1], history[-1 - m]) <= basin.tol:
                if out["distance"] > OTHER_ORBIT_MARGIN * basin.tol:
                    self._classified(OTHER_ORBIT, m, f"after {basin.steps} steps: an orbit of period {m}, "
                                                     f"{out['distance']:.3g} from the cycle")
                    return
                break
        self._classified(OTHER, 0, f"after {basin.steps} steps: {out['distance']:.3g} from the cycle, no orbit of "
                                   f"period <= {basin.max_period}")


def step_options(model, basin: Basin) -> dict:
    """simulate()'s options of every step (but the start): rk4 from the state as it is, to J's first crossing."""
    import andyc

    return dict(dt=basin.dt, method="rk4", parameters=dict(basin.parameters), init=andyc.Init("as-is"),
                events=andyc.Events(tol=basin.event_tol, stop_after={model.jump_names[basin.section]: 1}))


def classify(model, basin: Basin, held: list, values) -> dict:
    """The point's class (see the module docstring) and its record (Walk.out), each step a single run; "run":
    the last step's Run."""
    import andyc
    from andyc.analysis.sweeps.worker import interrupts
    from andyc.runtime.status import INTERRUPTED

    derivatives, fall = _loaded(model, basin)
    walk = Walk(model, basin, start_state(model, derivatives, basin, held, values), fall)
    flow, nx = int(model.module.JUMP_TARGET[basin.section]), model.nx
    while not walk.done:
        run = andyc.simulate(model, basin.t_step, x0=walk.y[:nx], d0=walk.y[nx:], flow0=flow, progress=False,
                             interrupts=interrupts(None), **step_options(model, basin))
        if run.status.startswith(INTERRUPTED):     # the sweep's end, not the point's (record())
            raise KeyboardInterrupt
        jumps = run.events["jump"]
        crossed = bool(run.finished and len(jumps) and jumps[-1] == basin.section)
        end = (run.state[-1], run.discrete[-1], int(run.flow[-1])) if len(run.time) else None
        walk.take(crossed, run.status, float(run.time[-1]) if len(run.time) else 0.0, jumps, run.events["time"],
                  end, lambda: run)
    return {**walk.out, "run": run}


def _holds(metric, run) -> bool:
    from andyc.analysis.sweeps.metrics import evaluate

    try:
        return evaluate(metric, run) == 1.0
    except (ValueError, ArithmeticError, TypeError):
        return False


def record_point(out: dict, row: int, model, settings, point) -> None:
    """A sweep worker's record of one basin point (andyc.analysis.sweeps.worker.record): its class into the
    basin fields, the last step's run into the others; a failure is recorded, never raised."""
    from andyc.analysis.sweeps.worker import MESSAGE_CHARS
    from andyc.errors import SimulationError, printable
    from andyc.runtime.status import FAILED

    basin = settings.basin
    held = [kind_index for (_, kind_index) in settings.kinds]
    start, cpu = time.perf_counter(), time.thread_time()
    try:
        found = classify(model, basin, held, np.asarray(point, dtype=float))
    except Exception as exc:            # a point's failure is its record, not the sweep's end
        text = str(exc) if isinstance(exc, SimulationError) else f"{type(exc).__name__}: {exc}"
        out["outcome"][row], out["message"][row] = FAILED, printable(text)[:MESSAGE_CHARS]
        out["wall"][row], out["cpu"][row] = time.perf_counter() - start, time.thread_time() - cpu
        out["basin"][row] = OTHER           # (not 0, "not run": it ran, and could not be classified)
        return
    record_walk(out, row, settings, found)
    out["wall"][row], out["cpu"][row] = time.perf_counter() - start, time.thread_time() - cpu


def record_walk(out: dict, row: int, settings, found: dict) -> None:
    """A classified point's record (Walk.out) into row `row` of a sweep's results (worker.empty_results), but its
    times."""
    from andyc.analysis.sweeps.worker import MESSAGE_CHARS
    from andyc.errors import printable
    from andyc.runtime.status import outcome

    out["outcome"][row] = outcome(found["status"])
    out["message"][row] = printable(found["message"])[:MESSAGE_CHARS]
    out["basin"][row], out["basin_period"][row] = found["class"], found["period"]
    out["basin_steps"][row], out["basin_distance"][row] = found["steps"], found["distance"]
    out["t_final"][row] = found["t"]
    if found["end"] is not None:
        out["final"][row], out["final_discrete"][row], out["final_flow"][row] = found["end"]
    out["jump_count"][row] = found["jump_count"]
    times = found["times"][:settings.max_events]
    out["event_time"][row, :len(times)], out["event_jump"][row, :len(times)] = times, settings.basin.section


__all__ = ["Basin", "BasinError", "CLASSES", "Walk", "make_basin", "classify", "start_state", "step_options",
           "record_point", "record_walk"]
