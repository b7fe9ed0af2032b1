"""SymbolicModel: the equations of motion as ordered SymPy assignments."""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from andyc.errors import plural
from andyc.spec.model import Spec
from andyc.symbolic.constraints import ConstraintTerms
from andyc.symbolic.aba import ArticulatedBody
from andyc.symbolic.formulation import ForwardDynamics
from andyc.symbolic.hybrid import HybridTerms


@dataclass
class SymbolicModel:
    """Equations of motion M(q, sigma) dv/dt = G(q, v, sigma, t) and friends.

    Every expression is written in the symbols q, v, sigma, t, parameters p, inputs u, discrete states d
    and the intermediate symbols of `assignments` (in dependency order).
    """
    spec: Spec
    t: sp.Symbol
    q: list
    v: list                   # coordinate rates, then quasi-velocities
    signals: list             # signal symbols sigma, in spec.signals order
    signal_rates: list        # d sigma / dt, same order (eq. 4)
    parameters: list          # symbols, in the order of spec.parameters
    inputs: list              # symbols, in the order of spec.inputs
    discrete: list            # symbols of the discrete states, in the order of spec.discrete
    assignments: list         # [(symbol, expression)], each uses only earlier ones
    M: sp.Matrix              # n x n, symmetric
    G: sp.Matrix              # n x 1
    energy: sp.Expr           # kinetic + potential
    power: sp.Expr            # power of the non-conservative elements
    frame_positions: dict     # frame name -> 3x1, world (user frames only)
    frame_rotations: dict     # frame name -> 3x3, own axes -> world (the same frames)
    elements: list            # ElementTerms, per element
    work_names: list          # the work slots the integrator carries (work.py): elements, constraints, 'jumps'
    powers: list              # the power of each element slot (the first of work_names), written after G
    row_work: list            # per velocity-level row: the slot of its constraint's power, or -1
    constraints: ConstraintTerms  # phi, c = A v + b, kappa (eq. 10-12); empty without constraints
    hybrid: HybridTerms       # flows, jumps (one flow, no jumps without a hybrid section)
    prescribed: tuple = ()    # (slot, a, b): the power a . dv/dt + b driving the links that depend on t (work.py)
    energy_laws: list = field(default_factory=list)  # per flow: (Phi_e, dPhi_e/dv) of its declared law, or None
    forward: ForwardDynamics | None = None  # how dv/dt = M^-1 G is solved (formulation.py); None: dense
    aba: ArticulatedBody | None = None      # dv/dt by the articulated-body algorithm (aba.py), where it applies
    derive_seconds: float = 0.0

    @property
    def dof(self) -> int:
        return len(self.v)

    def summary(self, file, spec: Spec | None = None) -> str:
        """One line, what the model is (`andyc check` prints it): its degrees of freedom (or speeds less
        constraint rows), flows and jumps, states, bodies, frames, parameters, inputs, force elements and the
        intermediate expressions derived. `spec`: the Spec as loaded, when the derivation reduced it (a URDF's
        bodies merged): its bodies are counted as written. Default self.spec."""
        spec = self.spec if spec is None else spec
        speeds = ", ".join([c.name for c in spec.coordinates] + [s.name for s in spec.speeds])
        contact_rows = {c.constraint for c in spec.contacts} | {c.stick for c in spec.contacts if c.stick}
        own = [c for c in spec.constraints if c.name not in contact_rows]
        nc, nh = sum(len(c.rows) for c in own), sum(len(c.rows) for c in own if c.holonomic)
        freedom = (f"{plural(self.dof, 'degree')} of freedom ({speeds})" if not own else
                   f"{self.dof} speeds ({speeds}) less {plural(nc, 'constraint row')} ({nh} holonomic) "
                   f"in {plural(len(own), 'constraint')}")
        signals = f" incl. {len(self.signals)} nonholonomic signals" if self.signals else ""
        if spec.jumps:
            def rows(flow) -> int:
                return sum(len(c.rows) for c in spec.constraints if c.name in flow.constraints)
            flows = ", ".join(f"{f.name} ({plural(rows(f), 'row')})" for f in spec.flows)
            kind = "hybrid" if len(spec.jumps) > sum(1 for j in spec.jumps if j.kind) else "one flow"
            shown = ", ".join(c.name for c in spec.contacts[:6]) + (f" and {len(spec.contacts) - 6} more"
                                                                   if len(spec.contacts) > 6 else "")
            contacts = f"; {plural(len(spec.contacts), 'contact')} ({shown})" if spec.contacts else ""
            freedom += (f"{contacts}; {kind}: {plural(len(spec.flows), 'flow')} ({flows}), "
                        f"{plural(len(spec.jumps), 'jump')}, {plural(len(spec.discrete), 'discrete state')}")
        n_elements = (len(spec.loads) + len(spec.actuators) + len(spec.dampers) + len(spec.springs)
                      + len(spec.potentials))
        n_frames = len([f for f in spec.frames if not f.internal])
        return (f"{file}: model '{spec.name}' is valid: {freedom}, "
                f"{plural(len(self.q) + self.dof + len(self.signals), 'state')}{signals}, "
                f"{plural(len(spec.bodies), 'body', 'bodies')}, {plural(n_frames, 'frame')} besides world, "
                f"{plural(len(spec.parameters), 'parameter')}, {plural(len(spec.inputs), 'input')}, "
                f"{plural(n_elements, 'force element')}; {len(self.assignments)} intermediate expressions.")

    def intermediates_of(self, exprs) -> set:
        """The intermediate symbols (of `assignments`) the expressions depend on, directly or through others."""
        defs = dict(self.assignments)
        todo = [s for e in exprs for s in sp.sympify(e).free_symbols]
        needed = set()
        while todo:
            s = todo.pop()
            if s in defs and s not in needed:
                needed.add(s)
                todo.extend(defs[s].free_symbols)
        return needed
