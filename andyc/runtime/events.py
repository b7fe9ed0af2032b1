"""The jumps of a run as they happen, and when they must stop it (jump loops, Zeno, stop_after).

EventLog records them; apply_jump applies one from Python (resets and impact in the compiled numerics, then
finish_jump), finish_jump completes one the compiled loop applied (a contact's impact, andyc.runtime.contacts;
the user's function in <name>_jumps.py; the record), follow_instant_jumps the jumps that happen at once
after it. Both drivers use them (andyc.runtime.fixed_step, andyc.runtime.adaptive).
"""

from __future__ import annotations

import traceback
from pathlib import Path

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import OK
from andyc.runtime.contacts import resolve_impact, resolve_liftoff, resolve_stop, start_slip
from andyc.runtime.controller import USER_ERRORS, raised
from andyc.runtime.inputs import InputSource
from andyc.runtime.options import Events
from andyc.runtime.status import ZENO, at, in_jump


class EventLog:
    """The jumps of a run, and the three reasons a run stops at one.

    record() logs a jump and returns why the run must stop, or None:
      - more than max_instant_jumps jumps at one instant (time not advancing
        by more than the event tolerance), a loop such as a -> b -> a;
      - Zeno: the last ZENO_WINDOW intervals between jumps each shrink, and
        the geometric tail they predict, dt_last r / (1 - r) with r the last
        ratio, puts the accumulation point less than zeno_tol ahead;
      - stop_after: the n-th occurrence of a named jump (the run finishes).
    """
    ZENO_WINDOW = 8

    def __init__(self, model, options: Events):
        self.model, self.event_tol = model, options.tol
        self.max_instant, self.zeno_tol = options.max_instant_jumps, options.zeno_tol
        self.stop_after = {}
        for name, count in (options.stop_after or {}).items():
            if name not in model.jump_names:
                raise SimulationError(f"unknown jump '{name}' in stop_after; jumps of {model.name}: "
                                      f"{', '.join(model.jump_names) or 'none'}")
            self.stop_after[model.jump_names.index(name)] = int(count)
        self.times, self.jumps, self.sources, self.targets = [], [], [], []
        self.before, self.after, self.discrete = [], [], []
        self.counts = [0] * model.nj     # occurrences of each jump
        self.instant = 0
        self.finished = False           # stopped by stop_after, not by a failure

    def record(self, t, k, x_before, x_after, d_after, source: int, target: int) -> str | None:
        """Log jump k at t from flow `source` into flow `target`; why the run must stop, or None. A contact's
        impact never stops it as Zeno: its contacts closed instead (finish_jump)."""
        jumps = self.model.jump_names
        same = bool(self.times) and t - self.times[-1] <= self.event_tol * max(1.0, abs(t))
        self.instant = self.instant + 1 if same else 1
        self.times.append(float(t))
        self.jumps.append(int(k))
        self.sources.append(int(source))
        self.targets.append(int(target))
        self.before.append(np.array(x_before))
        self.after.append(np.array(x_after))
        self.discrete.append(np.array(d_after))
        self.counts[k] += 1
        if self.instant > self.max_instant:
            loop = " -> ".join(jumps[j] for j in self.jumps[-min(6, len(self.jumps)):])
            return (f"stopped: {self.instant} jumps at t = {t:.12g} s without time advancing (last: {loop}), past "
                    f"the limit of {self.max_instant}: the guards of these jumps hold again right after each other; "
                    f"check their directions, enabling conditions and resets")
        zeno = self.zeno() if self.model.jump_contact[k] < 0 else None
        if zeno is not None:
            t_inf, ratio = zeno
            return (f"{ZENO}: the times of jump '{jumps[k]}' accumulate at t = {t_inf:.12g} s "
                    f"(intervals shrinking by a factor {ratio:.6g} per jump over the last {self.ZENO_WINDOW}; "
                    f"{len(self.times)} jumps, the last at t = {t:.12g} s, {t_inf - t:.3g} s before the "
                    f"accumulation point)")
        if k in self.stop_after and self.counts[k] >= self.stop_after[k]:
            self.finished = True
            return "finished"
        return None

    def zeno(self, t_next: float | None = None):
        """(accumulation time, ratio) when the last jump intervals shrink towards a point within zeno_tol (with
        a jump at t_next added, when given)."""
        n = self.ZENO_WINDOW
        times = self.times if t_next is None else self.times + [float(t_next)]
        if len(times) < n + 2:
            return None
        dts = np.diff(times[-(n + 2):])
        if not np.all(dts > 0) or not np.all(dts[1:] < dts[:-1]):
            return None
        ratio = dts[-1] / dts[-2]
        t_inf = times[-1] + dts[-1] * ratio / (1.0 - ratio)
        return (t_inf, ratio) if t_inf - times[-1] < self.zeno_tol else None

    def impact_again(self, t: float) -> bool:
        """The last jump was a contact's impact at this same instant (within the event tolerance): a second impact
        at once is the limit of impacts whose times accumulate (two stops coupled through the bodies, each impact
        knocking the other open a rounding's worth: a walker's knee strike and its stance knee), taken as Zeno's."""
        return (bool(self.times) and self.model.jump_contact[self.jumps[-1]] >= 0
                and self.model.jump_kinds[self.jumps[-1]][0] == "impact"
                and t - self.times[-1] <= self.event_tol * max(1.0, abs(t)))

    def table(self) -> dict:
        n, nx, nd = len(self.times), self.model.nx, self.model.nd
        return {"time": np.array(self.times), "jump": np.array(self.jumps, dtype=np.int32),
                "from_flow": np.array(self.sources, dtype=np.int32), "to_flow": np.array(self.targets, dtype=np.int32),
                "state_before": np.array(self.before).reshape(n, nx), "state_after": np.array(self.after).reshape(n, nx),
                "discrete_after": np.array(self.discrete).reshape(n, nd)}


def user_jump(model, k, t, x, u, p, d) -> str | None:
    """Run the user's function of jump k (<name>_jumps.py); a stop message if it fails."""
    try:
        model.module.user_jump(k, t, x, u, p, d)
    except USER_ERRORS as exc:      # the user's code: report it, keep the run's data
        path = Path(model.module.__file__).with_name(f"{model.name}_jumps.py")
        line = next((f.lineno for f in reversed(traceback.extract_tb(exc.__traceback__))
                     if Path(f.filename) == path), None)
        return (f"stopped: {path}{f':{line}' if line else ''}: the function of jump '{model.jump_names[k]}' "
                f"{raised(exc)}" + at(t))
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(d))):
        return (f"stopped: the function of jump '{model.jump_names[k]}' in {model.name}_jumps.py left the state or "
                f"the discrete states non-finite" + at(t))
    return None


def finish_jump(model, k, t, x_before, x, u, p, d, source: int, flow: int,
                jumps: EventLog) -> tuple[int, str | None]:
    """After jump k's resets and impact map (compiled) at t, from flow `source` into `flow` (x, d in place; u the
    inputs just before it): a contact's impact (andyc.runtime.contacts, plastic once the impact times accumulate),
    a liftoff that does not leave, a slip's end or start, the user's function, the record. Returns (the flow it lands in, a stop message or
    None)."""
    kind = model.jump_kinds[k][0] if model.jump_kinds else ""
    if kind == "impact":
        try:
            resolve_impact(model, t, x, u, p, d, flow, jumps.zeno(t) is not None or jumps.impact_again(t),
                           model.jump_contact[k])
        except (FloatingPointError, np.linalg.LinAlgError, SimulationError) as exc:
            return flow, f"stopped: contact impact in jump '{model.jump_names[k]}': {exc}" + at(t)
    elif kind == "stop":        # a slip ends: stick, or slip back
        try:
            resolve_stop(model, t, x, u, p, d, k, flow)
        except (FloatingPointError, np.linalg.LinAlgError) as exc:
            return flow, f"stopped: contact stick in jump '{model.jump_names[k]}': {exc}" + at(t)
    elif kind == "liftoff":
        try:
            resolve_liftoff(model, t, x, u, p, d, k, flow)
        except (FloatingPointError, np.linalg.LinAlgError, SimulationError) as exc:
            return flow, f"stopped: contact liftoff in jump '{model.jump_names[k]}': {exc}" + at(t)
    elif kind == "slip" and model.tangents[model.jump_kinds[k][1]] == 2:
        start_slip(model, t, x, u, p, d, k, flow)   # spatial friction: the slip starts against the sticking force
    message = user_jump(model, k, t, x, u, p, d) or jumps.record(t, k, x_before, x, d, source, flow)
    return flow, message


def apply_jump(model, k, t, x, u, p, d, w, flow: int, jumps: EventLog) -> tuple[int, str | None]:
    """Jump k at t out of `flow` (x, d in place; u the inputs just before it): resets and impact, then
    finish_jump. Returns (the flow it lands in, a stop message or None)."""
    before = x.copy()
    target = int(model.module.JUMP_TARGET[k])
    target = flow if target < 0 else target
    status = model.numerics.dynamics.jump(model.ref, w.ref, k, t, x, u, p, d)
    if status != OK:
        return target, in_jump(model, status, k, t)
    return finish_jump(model, k, t, before, x, u, p, d, flow, target, jumps)


def follow_instant_jumps(model, t, x, source: InputSource, p, d, flow, jumps: EventLog, w, mode):
    """Apply the jumps that happen at once at (t, x), in priority order. Returns (flow, stop message or None)."""
    while model.nj:
        w.u[:] = source.held(flow)
        fn, data = source.function_data
        k = model.numerics.integrator.instant(model.ref, w.ref, mode, fn, data, t, x, p, d, flow)
        if k == -2:
            return flow, f"stopped: {source.failure(model, d, p)}"
        if k < 0:
            break
        flow, stop = apply_jump(model, k, t, x, w.u, p, d, w, flow, jumps)
        if stop is not None:
            return flow, stop
    return flow, None
