"""A run's initial state: x, d and the flow it starts in, and their consistency with the constraints.

Before a constrained run, the initial state's distance from the constraint manifold is measured; past
Init.tol the run is refused unless Init.mode says to project the state onto the manifold ("project") or to
start anyway ("as-is") (andyc.runtime.options.Init). The multiplier methods (lagrange, baumgarte) also need
the active rows to be independent there; the first row that is not is named.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from andyc.errors import InitialStateError, SimulationError
from andyc.numerics.status import MESSAGES, OK
from andyc.runtime.compiled import CompiledModel, work
from andyc.runtime.options import Init


def initial_state(model: CompiledModel, p, x0=None, d0=None, flow0=None) -> tuple:
    """(x, d, flow): the given initial state, discrete states and flow (a name or index), or the model's. x0 and d0
    are arrays of every value, or mappings {name: value} over the model's own initial values (`andyc sim --at`)."""
    x = np.array(model.initial_state(p, x0) if x0 is None or isinstance(x0, Mapping) else x0, dtype=np.float64)
    if x.shape != (model.nx,):
        raise SimulationError(f"initial state has shape {x.shape}, expected ({model.nx},)")
    d = np.array(model.initial_discrete(p, d0) if d0 is None or isinstance(d0, Mapping) else d0, dtype=np.float64)
    if d.shape != (model.nd,):
        raise SimulationError(f"initial discrete states have shape {d.shape}, expected ({model.nd},)")
    return x, d, _flow_index(model, flow0)


def _flow_index(model: CompiledModel, flow) -> int:
    if flow is None:
        return model.initial_flow
    if isinstance(flow, str):
        if flow not in model.flow_names:
            raise SimulationError(f"unknown flow '{flow}'; flows of {model.name}: {', '.join(model.flow_names)}")
        return model.flow_names.index(flow)
    if not 0 <= int(flow) < model.nf:
        raise SimulationError(f"flow index {flow} out of range; {model.name} has {model.nf} flows")
    return int(flow)


def constraint_residuals(model: CompiledModel, t: float, x, u, p, d=None, flow=None):
    """(phi, c) of the flow's active rows: holonomic residuals and velocity-level residuals at (t, x)."""
    d = model.initial_discrete(p) if d is None else d
    flow = model.initial_flow if flow is None else flow
    phi, c = np.empty(model.nh), np.empty(model.nc)
    model.module.constraints(t, x, u, p, d, phi, c, np.empty((model.nc, model.nv)), np.empty(model.nc))
    rows = model.active_rows(flow, d)
    return phi[[r for r in rows if r < model.nh]], c[rows]


def consistent_initial_state(model: CompiledModel, x, u, p, d, flow, init: Init) -> dict:
    """Measure (and with init.mode "project", remove) the initial state's constraint residuals.

    Projection repeats the Braun & Goldfarb position and velocity corrections
    (the smallest change in the mass-matrix metric) until the residuals are
    at round-off. x is changed in place; returns the figures for run stats.
    """
    phi, c = constraint_residuals(model, 0.0, x, u, p, d, flow)
    out = {"initial_position_residual": float(np.max(np.abs(phi), initial=0.0)),
           "initial_velocity_residual": float(np.max(np.abs(c), initial=0.0))}
    worst = max(out.values())
    if init.mode == "as-is" or worst <= (init.tol if init.mode == "check" else 0.0):
        return out
    if init.mode == "check":
        rows = model.active_rows(flow, d)
        values = np.concatenate([np.abs(phi), np.abs(c)])
        k = int(np.argmax(values))
        row = rows[k] if k < phi.shape[0] else rows[k - phi.shape[0]]
        level = "position" if k < phi.shape[0] else "velocity"
        line, path = model.constraint_where[row]
        raise InitialStateError(
            model.source, line, path, f"the initial state is off the constraint manifold: largest residual "
            f"{values[k]:.3g} at the {level} level (constraint '{model.constraint_rows[row]}'; all rows: position "
            f"{out['initial_position_residual']:.3g}, velocity {out['initial_velocity_residual']:.3g}), past the bound "
            f"{init.tol:g}; fix the initial values, or use --init project to move the state onto the manifold "
            f"(the smallest change in the mass-matrix metric), or --init as-is to start from it anyway")
    w = work(model)
    for _ in range(50):
        status = model.numerics.dynamics.project(model.ref, w.ref, 0.0, x, u, p, d, flow, True, 0.0, -1.0)
        if status != OK:
            raise SimulationError(f"cannot project the initial state: {MESSAGES[status]} there")
        phi, c = constraint_residuals(model, 0.0, x, u, p, d, flow)
        if max(np.max(np.abs(phi), initial=0.0), np.max(np.abs(c), initial=0.0)) <= 1e-13 * max(1.0, np.abs(x).max()):
            out["initial_projection"] = float(worst)
            return out
    raise SimulationError(f"cannot project the initial state onto the constraint manifold (residuals still "
                          f"{np.max(np.abs(phi), initial=0.0):.3g}, {np.max(np.abs(c), initial=0.0):.3g} after 50 "
                          f"corrections); the constraints may have no solution near it: check the initial values")


def require_independent_rows(model: CompiledModel, method: str, x, u, p, d, flow) -> None:
    """Multipliers (ANDY eq. 12) need independent rows; name the first row that is not."""
    A = np.zeros((model.nc, model.nv))
    model.module.constraints(0.0, x, u, p, d, np.empty(model.nh), np.empty(model.nc), A, np.empty(model.nc))
    rows = model.active_rows(flow, d)
    A = A[rows]
    tol = 1e-8 * max(np.linalg.norm(A, 2) if A.size else 0.0, 1e-300)
    for k in range(len(rows)):
        if np.linalg.matrix_rank(A[:k + 1], tol=tol) <= k:
            row = rows[k]
            earlier = sorted({model.constraint_rows[r] for r in rows[:k]})
            line, path = model.constraint_where[row]
            raise InitialStateError(
                model.source, line, path, f"row {row} of the constraints (in '{model.constraint_rows[row]}') is a "
                f"combination of earlier rows (in {', '.join(repr(e) for e in earlier)}) at the initial state: the "
                f"constraints are redundant or the pose is singular, so the {method} method's multipliers are not "
                f"unique; remove the redundant constraint, or use --method projection, which allows them")
