"""Symbolic stage: Spec -> SymbolicModel (recursive kinematics, elements, EOM).

    kinematics.py   the frame tree's recursive kinematics (ANDY eq. 1-3)
    dynamics.py     the elements' terms and M dv/dt = G (ANDY eq. 5-8)
    constraints.py  constraint residuals, Jacobian and velocity-product term (ANDY eq. 10-12)
    hybrid.py       active rows per flow, guards, resets, impacts (ANDY eq. 16-19)
    reduce.py       bodies fixed to one moving frame merged into one
    work.py         the power of every element that does work (the energy balance E - E0 - W)
    emitter.py      the ordered intermediate assignments;  model.py: SymbolicModel and its summary
    formulation.py  the forward dynamics each model gets: dense Cholesky of M, LTDL along its tree, or ABA
    sparse_rows.py  the constrained solve each model gets: dense, or along the tree and the rows' supports
    aba.py          Featherstone's articulated-body algorithm, derived symbolically (dv/dt without M)
    linearize.py    A, B by exact forward-mode derivatives;  eom.py: the equations written out for reading
"""

from __future__ import annotations

import time

from andyc.spec.expressions import TIME
from andyc.spec.model import Spec
from andyc.symbolic.aba import articulated_body
from andyc.symbolic.constraints import FrameQuantities, constraint_terms
from andyc.symbolic.dynamics import assemble, element_terms
from andyc.symbolic.emitter import Emitter
from andyc.symbolic.formulation import choose
from andyc.symbolic.hybrid import hybrid_terms
from andyc.symbolic.kinematics import frame_kinematics
from andyc.symbolic.model import SymbolicModel
from andyc.symbolic.reduce import merge_rigid_bodies
from andyc.symbolic.work import energy_law_terms, work_slots


def derive(spec: Spec) -> SymbolicModel:
    """Derive the equations of motion of `spec`.

    Stages: frame kinematics (eq. 1-3) -> element terms (eq. 5-7) -> sums (eq. 8)
    -> constraint residuals, Jacobian and velocity-product term (eq. 10-12)
    -> the hybrid automaton's guards, resets and impact rows (eq. 16-19)
    -> the forward dynamics' formulation, from the operation counts (formulation.py).
    """
    start = time.perf_counter()
    if spec.reduce:
        spec = merge_rigid_bodies(spec)
    emit = Emitter()
    kin = frame_kinematics(spec, emit)
    terms = element_terms(spec, kin, emit)
    M, G, energy, power = assemble(spec, terms)
    quantities = FrameQuantities(spec, kin, emit)
    constraints = constraint_terms(spec, quantities)
    hybrid = hybrid_terms(spec, quantities, constraints)
    laws = energy_law_terms(spec, quantities)
    work_names, powers, row_work, prescribed = work_slots(spec, terms, constraints)
    rates = {sym: rate for K in kin.values() for sym, rate in K.signal_rates.items()}
    # ABA (aba.py) for the unconstrained rhs, chosen from the operation counts of the whole dv/dt: for a model
    # whose flows have no rows of their own (a contact's rows join only while it is closed).
    contact_rows = {c.constraint for c in spec.contacts} | {c.stick for c in spec.contacts if c.stick}
    bilateral = [c for c in spec.constraints if c.name not in contact_rows]
    aba = articulated_body(spec, terms) if not bilateral else None
    forward = choose(M, aba=aba, G=G, pool=dict(emit.assignments)) if not bilateral else choose(M)
    return SymbolicModel(
        spec=spec, t=TIME,
        q=[c.q for c in spec.coordinates], v=spec.speed_symbols,
        signals=[s.symbol for s in spec.signals], signal_rates=[rates[s.symbol] for s in spec.signals],
        parameters=[s for s, _ in spec.parameters.values()], discrete=[x.symbol for x in spec.discrete],
        inputs=[s for s, _ in spec.inputs.values()],
        assignments=emit.assignments, M=M, G=G, energy=energy, power=power,
        frame_positions={f.name: kin[f.name].r for f in spec.frames if not f.internal},
        frame_rotations={f.name: kin[f.name].R for f in spec.frames if not f.internal},
        elements=terms, powers=powers, work_names=work_names, row_work=row_work,
        constraints=constraints, hybrid=hybrid, energy_laws=laws, prescribed=prescribed, forward=forward, aba=aba, derive_seconds=time.perf_counter() - start)


__all__ = ["derive", "SymbolicModel"]
