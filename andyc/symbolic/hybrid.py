"""The hybrid automaton's terms (ANDY eq. 16-19): active rows per flow, guards, resets, impacts.

For each jump, with the guard g(t, q, v, d) (frame quantities allowed):

    dg/dt = rate(g) + jac(g) dv/dt        (dv/dt given: the flow's acceleration)

which the runtime uses to tell, at an instant, whether a guard already past
zero is moving further (the jump happens) or back (it does not). A guard may
read the multipliers of its source flow (a contact's normal force); their rate
is not derived (it would need d(dv/dt)/dt) and counts as 0, so such a guard
already past zero happens at once, and one exactly at zero does not. Resets are
kept as (target name, expression); the impact map acts on the velocity-level
rows of the jump's impact constraints (see the generated `impact`).
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.numerics.status import SLIP_STOP
from andyc.spec.model import ANY, Spec
from andyc.symbolic.constraints import ConstraintTerms, FrameQuantities


@dataclass
class JumpTerms:
    name: str
    source: int                 # flow index
    target: int
    direction: int              # FALLING -1, EITHER 0, RISING 1
    priority: int
    guard: sp.Expr
    guard_rate: sp.Expr         # in terms of the symbols HybridTerms.vdot
    enabled: sp.Expr            # >= 0 where the jump may happen (1 without conditions)
    resets: list                # [(target name, expression)], simultaneous
    impact_rows: list           # velocity-level constraint rows that take the impact
    restitution: sp.Expr        # e, of parameters
    uses_multipliers: bool = False  # guard or enabled read the source flow's multipliers (HybridTerms.multipliers)
    contact: int = -1           # the contact whose impact this is (the runtime resolves it), SLIP_STOP, or -1
    mode_state: int = -1        # a contact's jump: the index in d of its contact's mode, -1 for the user's jumps
    mode_mask: int = 0          # ... and the modes it leaves (bit s: mode s): it is considered only in them


@dataclass
class HybridTerms:
    flows: list                 # flow names
    initial: int
    flow_rows: list             # per flow: the active velocity-level constraint rows
    flow_inputs: list           # per flow: {input index: expression of parameters}
    jumps: list                 # of JumpTerms, in document order
    vdot: list                  # symbols standing for dv/dt in guard rates
    multipliers: list           # symbols standing for the multiplier of each row in guards (lam in the leaves)


def hybrid_terms(spec: Spec, quantities: FrameQuantities, constraints: ConstraintTerms) -> HybridTerms:
    flow_index = {f.name: i for i, f in enumerate(spec.flows)} | {ANY: -1}     # -1: every flow (a contact's jump)
    discrete = [x.name for x in spec.discrete]
    inputs = list(spec.inputs)
    vdot = [sp.Symbol(f"vdot_{i}", real=True) for i in range(quantities.n)]
    jumps = []
    for j in spec.jumps:
        for sym, fq in j.quantities.items():
            quantities.define(sym, fq)
        rate = quantities.rate(j.guard) + sum((a * b for a, b in zip(quantities.jac(j.guard), vdot)), sp.Integer(0))
        enabled = sp.Min(*j.enabled) if len(j.enabled) > 1 else (j.enabled[0] if j.enabled else sp.Integer(1))
        jumps.append(JumpTerms(
            j.name, flow_index[j.source], flow_index[j.target], j.direction, j.priority, j.guard, rate, enabled,
            list(j.resets), [r for r, name in enumerate(constraints.rows) if name in j.impact_constraints],
            j.restitution, bool(j.multipliers),
            j.contact if j.kind == "impact" else SLIP_STOP if j.kind == "stop" else -1,
            discrete.index(j.mode[0]) if j.mode else -1, j.mode[1] if j.mode else 0))
    return HybridTerms(
        flows=[f.name for f in spec.flows], initial=spec.initial_flow,
        flow_rows=[[r for r, name in enumerate(constraints.rows) if name in f.constraints] for f in spec.flows],
        flow_inputs=[{inputs.index(k): e for k, e in f.inputs.items()} for f in spec.flows],
        jumps=jumps, vdot=vdot, multipliers=[sp.Symbol(f"lam_{name}", real=True) for name in constraints.multipliers])
