"""The initial state checked from the equations, without compiling: what `andyc check` finds before a run.

At the model's initial state (its initial values at the parameter defaults, t = 0, in its initial flow):

- the active constraint rows: holonomic residuals phi(0, q0) and velocity-level residuals
  c = A v0 + b (ANDY eq. 10-11) past `tol` put the state off the constraint manifold, which a run with
  init "check" (the default; the model's simulate: section may say otherwise) refuses;
- the guards of the jumps out of the initial flow whose enabling conditions hold: a guard already past zero
  (falling: g < 0; rising: g > 0) starts the run on the wrong side of its surface (the runtime would take
  the jump at once, or never until the guard comes back);
- a contact's slip speed along its gap's normal (andyc.spec.contacts: a friction direction that is not tangent).

The values are those of the symbolic model, evaluated exactly as its linearization does
(andyc.symbolic.linearize.values_at): the same numbers the compiled module computes, to round-off.
"""

from __future__ import annotations

import numpy as np

from andyc.errors import Diagnostic
from andyc.spec.model import FALLING
from andyc.symbolic.linearize import default_point, values_at
from andyc.symbolic.model import SymbolicModel

# A guard within this of zero is on its surface, not past it (the runtime's instant check decides then).
GUARD_ROUND_OFF = 1e-12
PARALLEL = 1e-9         # a slip row whose angle with its gap row has |cos| within this of 1 is along the normal


def initial_problems(model: SymbolicModel, init: str = "check", tol: float = 1e-6) -> list[Diagnostic]:
    """The problems of the model's initial state, one Diagnostic each (see the module docstring)."""
    spec = model.spec
    flow = model.hybrid.initial
    x, u, p, d = default_point(model)
    out = []
    rows = model.hybrid.flow_rows[flow]
    C = model.constraints
    if rows and init == "check":
        holonomic = [r for r in rows if r < C.nh]
        values = values_at(model, [C.phi[r] for r in holonomic] + [C.c[r] for r in rows], x, u, p, d)
        residuals = list(zip(holonomic, ["position"] * len(holonomic), values[:len(holonomic)])) + list(
            zip(rows, ["velocity"] * len(rows), values[len(holonomic):]))
        where = [w for c in spec.constraints for w in c.row_where]
        reported = set()
        for row, level, value in sorted(residuals, key=lambda r: -abs(r[2])):
            if not abs(value) > tol or row in reported:
                continue
            reported.add(row)
            out.append(spec.source.diag(
                where[row], f"the initial state is off the constraint manifold: residual {value:.3g} at the {level} "
                f"level (constraint '{C.rows[row]}'), past the bound {tol:g} (init_tol)",
                "fix the initial values, or give the model `simulate: {init: project}` to move the state onto "
                "the manifold (the smallest change in the mass-matrix metric), or `simulate: {init: as-is}` to "
                "start from it anyway"))
    jumps = [(j, s) for j, s in zip(model.hybrid.jumps, spec.jumps) if j.direction != 0      # (either: no wrong side)
             and (j.source == flow or (j.source < 0 and s.kind == "impact"))]      # (a contact starts open)
    if jumps:
        values = values_at(model, [e for j, _ in jumps for e in (j.guard, j.enabled)], x, u, p, d)
        for k, (j, s) in enumerate(jumps):
            g, enabled = values[2 * k], values[2 * k + 1]
            if not (np.isreal(g) and np.isfinite(np.real(g))):      # (sqrt of a negative, a division by zero)
                what = f"the gap of contact '{spec.contacts[s.contact].name}'" if s.kind else f"the guard of jump '{j.name}'"
                out.append(spec.source.diag(
                    s.where + (() if s.kind else ("guard",)), f"{what} has no real value at the initial state "
                    f"({g})", "write it so that it is real and finite at the initial values (a square root of a "
                    "negative number, a division by zero?)"))
                continue
            g, enabled = float(np.real(g)), float(np.real(enabled)) if np.isreal(enabled) else -1.0
            past = g < -GUARD_ROUND_OFF if j.direction == FALLING else g > GUARD_ROUND_OFF
            if past and enabled >= 0 and np.isfinite(g) and s.kind == "impact":
                out.append(spec.source.diag(
                    s.where, f"contact '{spec.contacts[s.contact].name}' starts {-g:.3g} inside its surface (its gap "
                    f"is {g:.3g} at the initial state)", "fix the initial values so that the gap starts >= 0, or give "
                    "the model `simulate: {init: project}` to move the state onto the surface (the smallest change "
                    "in the mass-matrix metric)"))
            elif past and enabled >= 0 and np.isfinite(g):
                side = "below" if j.direction == FALLING else "above"
                out.append(spec.source.diag(
                    s.where + ("guard",), f"the guard of jump '{j.name}' is already past zero at the start: "
                    f"{g:.3g}, {side} zero in flow '{model.hybrid.flows[flow]}', where it happens when it "
                    f"{'falls' if j.direction == FALLING else 'rises'} to zero",
                    "fix the initial values so that the guard starts on its far side, or start in another "
                    "flow (hybrid: initial:)"))
    return out + _slip_along_normal(model, x, u, p, d)


def _slip_along_normal(model: SymbolicModel, x, u, p, d) -> list[Diagnostic]:
    """A contact with friction whose slip row is a multiple of its gap's (|cos| within PARALLEL of 1, or no row at
    all) at the initial state: its `slip` is not a tangential speed (sticking would hold the gap twice: dependent
    rows), e.g. `slip: block.vy` for `gap: block.y`. Spatial friction (two slip rows): each, and the second
    parallel to the first (the two would not span the tangent plane)."""
    C, out = model.constraints, []
    nv = C.A.shape[1]
    for c in model.spec.contacts:
        if not c.stick:
            continue
        n, t = C.rows.index(c.constraint), C.rows.index(c.stick)
        rows = [n] + [t + j for j in range(c.tangents)]
        values = values_at(model, [a for r in rows for a in C.A[r, :]], x, u, p, d)
        normal, tangents = values[:nv], [values[nv * (j + 1):nv * (j + 2)] for j in range(c.tangents)]
        for j, tangent in enumerate(tangents):
            path = c.where + ("slip",) + ((j,) if c.tangents == 2 else ())
            which = "" if c.tangents == 1 else ("first ", "second ")[j]
            if _parallel(normal, tangent):
                out.append(model.spec.source.diag(
                    path, f"the {which}slip speed of contact '{c.name}' is along its gap's normal at the initial "
                    f"state (its row is {'zero' if not tangent.any() else 'a multiple of the gap row'}): it is not a "
                    f"tangential speed", "write the speed of the contact point along the tangent, perpendicular to "
                    "the normal: e.g. slip: block.vx for gap: block.y"))
            elif j == 1 and _parallel(tangents[0], tangent):
                out.append(model.spec.source.diag(
                    path, f"the second slip speed of contact '{c.name}' is along its first at the initial state (its "
                    "row is a multiple of the first's): the two do not span the tangent plane", "write the contact "
                    "point's speed along a second tangent, perpendicular to the first and to the normal: e.g. slip: "
                    "[block.vx, block.vy] for gap: block.z"))
    return out


def _parallel(a, b) -> bool:
    """Rows a and b along one line (|cos| within PARALLEL of 1), or either zero."""
    size = np.linalg.norm(a) * np.linalg.norm(b)
    return size == 0 or abs(a @ b) / size > 1.0 - PARALLEL
