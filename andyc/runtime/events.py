"""The jumps of a run as they happen, and when they must stop it (jump loops, Zeno, stop_after)."""

from __future__ import annotations

import numpy as np

from andyc.errors import SimulationError


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

    def __init__(self, model, event_tol: float, max_instant: int, zeno_tol: float,
                 stop_after: dict | None):
        self.model, self.event_tol, self.max_instant, self.zeno_tol = model, event_tol, max_instant, zeno_tol
        self.stop_after = {}
        for name, count in (stop_after or {}).items():
            if name not in model.jump_names:
                raise SimulationError(f"unknown jump '{name}' in stop_after; jumps of {model.name}: "
                                      f"{', '.join(model.jump_names) or 'none'}")
            self.stop_after[model.jump_names.index(name)] = int(count)
        self.times, self.jumps, self.sources, self.targets = [], [], [], []
        self.before, self.after, self.discrete = [], [], []
        self.counts = [0] * model.nj     # occurrences of each jump
        self.instant = 0
        self.finished = False           # stopped by stop_after, not by a failure

    def record(self, t, k, x_before, x_after, d_after) -> str | None:
        jumps = self.model.jump_names
        same = bool(self.times) and t - self.times[-1] <= self.event_tol * max(1.0, abs(t))
        self.instant = self.instant + 1 if same else 1
        self.times.append(float(t))
        self.jumps.append(int(k))
        self.sources.append(int(self.model.module.JUMP_SOURCE[k]))
        self.targets.append(int(self.model.module.JUMP_TARGET[k]))
        self.before.append(np.array(x_before))
        self.after.append(np.array(x_after))
        self.discrete.append(np.array(d_after))
        self.counts[k] += 1
        if self.instant > self.max_instant:
            loop = " -> ".join(jumps[j] for j in self.jumps[-min(6, len(self.jumps)):])
            return (f"stopped: {self.instant} jumps at t = {t:.12g} s without time advancing (last: {loop}), past "
                    f"the limit of {self.max_instant}: the guards of these jumps hold again right after each other; "
                    f"check their directions, enabling conditions and resets")
        zeno = self.zeno()
        if zeno is not None:
            t_inf, ratio = zeno
            return (f"stopped: Zeno behaviour: the times of jump '{jumps[k]}' accumulate at t = {t_inf:.12g} s "
                    f"(intervals shrinking by a factor {ratio:.6g} per jump over the last {self.ZENO_WINDOW}; "
                    f"{len(self.times)} jumps, the last at t = {t:.12g} s, {t_inf - t:.3g} s before the "
                    f"accumulation point)")
        if k in self.stop_after and self.counts[k] >= self.stop_after[k]:
            self.finished = True
            return "finished"
        return None

    def zeno(self):
        """(accumulation time, ratio) when the last jump intervals shrink towards a point within zeno_tol."""
        n = self.ZENO_WINDOW
        if len(self.times) < n + 2:
            return None
        dts = np.diff(self.times[-(n + 2):])
        if not np.all(dts > 0) or not np.all(dts[1:] < dts[:-1]):
            return None
        ratio = dts[-1] / dts[-2]
        t_inf = self.times[-1] + dts[-1] * ratio / (1.0 - ratio)
        return (t_inf, ratio) if t_inf - self.times[-1] < self.zeno_tol else None

    def table(self) -> dict:
        n, nx, nd = len(self.times), self.model.nx, self.model.nd
        return {"time": np.array(self.times), "jump": np.array(self.jumps, dtype=np.int32),
                "from_flow": np.array(self.sources, dtype=np.int32), "to_flow": np.array(self.targets, dtype=np.int32),
                "state_before": np.array(self.before).reshape(n, nx), "state_after": np.array(self.after).reshape(n, nx),
                "discrete_after": np.array(self.discrete).reshape(n, nd)}
