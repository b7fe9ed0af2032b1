"""The work the integrators carry after the state, and the energy the jumps change.

Every run integrates, beside the state x (NX), the work W_i of each element that does work on the model
(WORK_SLOTS of the build: forces, torques, dampers, rheonomic constraints, springs and potentials that
depend on t; andyc/symbolic/work.py derives their power P_i), as states of their own with dW_i/dt = P_i.
The fixed-step methods take them through the same RK4 stages as the motion, the adaptive ones through
SciPy's solver as extra components (their error control then counts them too). Projections do not change
them: a correction of the state is not work.

A jump (resets, impact map, a contact's impact, the user's function) does not change W_i; the energy it
changes, E+ - E-, goes to the last slot, `jumps`, so that E(t) - E(0) - W(t), W the sum of the slots, stays
the integration's error across jumps (an impact's loss is then the step of the `jumps` work).
"""

from __future__ import annotations

import numpy as np

def with_work(model, x: np.ndarray) -> np.ndarray:
    """The state x followed by zero work in each slot: what the integrators step."""
    return np.concatenate([np.asarray(x, dtype=np.float64), np.zeros(model.nw)])


class JumpWork:
    """The energy a jump (or a run of jumps at one instant) changes, added to the `jumps` slot: made with the
    augmented state just before it (its inputs u and discrete states d then), `add` after it."""

    def __init__(self, model, x, u, p, d, t):
        self.model, self.p, self.t = model, p, t
        self.before = model.module.energy(t, x[:model.nx], u, p, d.copy())

    def add(self, x, u, d) -> float:
        """Add E+ - E- to the `jumps` slot of x (the augmented state after the jump, in place); returns the energy
        correction's new offset e0 = E+ - W, so that its law E = e0 + W holds right after the jump."""
        model = self.model
        after = model.module.energy(self.t, x[:model.nx], u, self.p, d)
        if model.nj:                   # (a model with jumps has the slot `jumps`, last)
            x[model.nx + model.nw - 1] += after - self.before
        return after - float(np.sum(x[model.nx:]))


def law_offset(model, flow: int, e0: float) -> float:
    """The constant the projection's energy correction subtracts in `flow` (andyc_numerics/dynamics.project): the
    built-in law's e0 (E0, then E+ - W after each jump), or 0 where the flow declares its own law Phi_e = 0
    (andyc.spec.energy_law: taken as written)."""
    laws = model.energy_laws
    return 0.0 if flow < len(laws) and laws[flow] is not None else e0
