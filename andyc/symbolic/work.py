"""The power of every element that does work on the model: the terms of the energy balance.

With E the total energy (kinetic + gravity + springs + potentials) and W_i the work of element i,

    dE/dt = sum_i P_i,      E(t) - E(0) - W(t) = 0,      W = sum_i W_i,  W_i(t) = int_0^t P_i dt

along the motion (Braun & Goldfarb's energy-type law, Part I eq. (d), with the work as its time-dependent
part). The elements that do work, each with its power P_i:

    force F at frame f (vector in e's axes)     v_f . R_e F
    torque T on frame f                         w_f . R_e T
    damper on chi                               -b chi . chi     (-b |chi| chi . chi, quadratic)
    potential V(q, t)                           dV/dt at fixed q (explicit t only)
    spring of length x(q, t)                    k (x - x0) dx/dt at fixed q (explicit t only)
    constraint with rows c = A v + b            lam . (A v - c) = -lam . b on the manifold c = 0

The constraint's power: its force A^T lam (M dv/dt = G + A^T lam) has power v . A^T lam = lam . (c - b); a
holonomic row Gamma(t, q) has b = dGamma/dt at fixed q, a nonholonomic row J v + b its term without
speeds. Only the rows whose b is not 0 are elements (andyc.spec.constraints.working_rows): the others do no
work on any allowed motion. The numerics compute it from the multipliers of the step's own constraint solve
and the rows' A and c (the table ROW_WORK of the build), as -lam . (c - A v), so that a run whose c
drifts from 0 still gets the b of its actual state; the elements' powers are written by the dynamics leaf
after G (G[NV + i]), sharing its subexpressions.

In the baumgarte method the rows' forces (with the soft terms of ANDY eq. 15) also act off the manifold,
where c != 0: there each row's whole power lam A v is counted, in its constraint's slot or in `baumgarte`.

A frame whose link depends on t moves along t: each body below it has the velocity J v + V_t, V_t = dr/dt at
fixed q (its motion at zero speeds). What drives that motion does the work `prescribed_motion`, the power of the
reaction along it (Kane's method with t as one more coordinate):

    P = sum_bodies [m (a - g) . V_t + (I alb + wb x I wb) . Wb_t] - sum_forces,torques,dampers f . V_t
        + sum_springs between frames  k (x - x0) dx/dt at zero speeds

with a = Jv dv/dt + ac: P = a_t . dv/dt + b_t, which the numerics evaluate after each solve (the leaf
drive_power). So dE/dt = sum of the powers, with the forces' own powers f . (J v + V_t).

A slipping contact's friction, -sigma mu lam_n along its tangent J_t (spatial: -mu lam_n along the slip's direction
u), has power -sigma mu lam_n J_t v (-mu lam_n (u_1 J_1 + u_2 J_2) v): the numerics add it to the slot `friction`
from the multipliers of the step's solve (ROW_FRICTION: the slot of each contact's gap row).

Not here: the energy a jump changes (the integrator adds E+ - E- to the work `jumps`).
"""

from __future__ import annotations

import sympy as sp

from andyc.spec.constraints import driven_frames, working_rows
from andyc.spec.expressions import TIME
from andyc.spec.model import Spec

JUMPS = "jumps"     # the work slot of the energy the jumps change (resets, impacts): E+ - E- at each
FRICTION = "friction"   # the work slot of the slipping contacts' Coulomb friction (andyc.spec.contacts)
PRESCRIBED = "prescribed_motion"  # the work slot of the links that depend on t (the power that drives them)
BAUMGARTE = "baumgarte"  # the work slot of the baumgarte method's constraint forces off the manifold


def work_slots(spec: Spec, terms: list, constraints) -> tuple[list, list, list, tuple]:
    """The work slots of the model: (names, powers, row_slot). names: every element that does work, in the
    model's order (forces and torques, dampers, springs and potentials that depend on t: `terms`, the
    ElementTerms), then each constraint with a working row, then 'baumgarte' when a constraint has gains (the
    baumgarte method's forces off the manifold), then each joint friction (a coulomb damper), then 'friction' when a contact has friction (the power of its
    sliding force, which the numerics compute: integrator.stage_powers), then 'jumps' when the model has jumps. powers: the
    power of each element slot (the first len(powers) names), which the dynamics leaf writes after G. row_slot:
    for each velocity-level row of `constraints`, the slot its power -lam (c - A v) goes to, or -1 (the
    numerics compute it from the step's multipliers, A and c), or -2 - the slot `baumgarte` (a row that does
    no work on the manifold, in a model with gains: its power lam A v in the baumgarte method). prescribed: () or
    (slot, a, b) of the slot 'prescribed_motion', whose power a . dv/dt + b (the leaf drive_power) drives the links
    that depend on t."""
    elements = [(e.name, e.power) for e in terms if e.power != 0]
    names, powers = [n for n, _ in elements], [e for _, e in elements]
    row_slot = [-1] * constraints.nc
    positions = {c.q for c in spec.coordinates}
    driven = set(driven_frames(spec.frames))
    for c in spec.constraints:
        working = working_rows(c, positions, set(spec.speed_symbols))
        # A row of the frame quantities of a frame moved along t depends on t through them (b != 0).
        moving = {s for s, f in c.quantities.items() if {f.frame, f.in_frame} & driven}
        working = sorted(set(working) | {i for i, r in enumerate(c.rows) if r.free_symbols & moving})
        if not working:
            continue
        # A constraint's velocity-level rows, in order (holonomic constraints' rows come first in the model's).
        rows = [i for i, name in enumerate(constraints.rows) if name == c.name]
        for k in working:
            row_slot[rows[k]] = len(names)
        names.append(c.name)
    prescribed = ()
    drives = [e.drive for e in terms if e.drive]
    if drives:
        n = len(spec.speed_symbols)
        prescribed = (len(names), sum((a for a, _ in drives), sp.zeros(n, 1)), sum(b for _, b in drives))
        names.append(PRESCRIBED)
    if -1 in row_slot and any(c.stiffness != 0 or c.damping != 0 for c in spec.constraints):
        # The baumgarte method's soft terms act off the manifold, where every row's force does work lam A v: the
        # rows whose constraint does none on it count theirs in the slot `baumgarte` (-2 - slot: the numerics
        # add it in that method only, integrator.stage_powers).
        row_slot = [-2 - len(names) if slot < 0 else slot for slot in row_slot]
        names.append(BAUMGARTE)
    names += [d.name for d in spec.joint_frictions]     # (their work: the moreau method's, timestepping.step)
    if any(c.friction is not None for c in spec.contacts):
        names.append(FRICTION)
    if spec.jumps:
        names.append(JUMPS)
    return names, powers, row_slot, prescribed


def energy_law_terms(spec: Spec, quantities) -> list:
    """Per flow, (Phi_e, dPhi_e/dv) of its declared energy law (andyc.spec.energy_law), or None where the built-in
    law E - E0 - W holds: the energy correction of the projection method moves the speeds along the gradient
    (Braun & Goldfarb eq. 6). Frame quantities enter through their Jacobians (quantities.jac), as in rows."""
    out = []
    for law in spec.energy_laws or [None] * len(spec.flows):
        if law is None:
            out.append(None)
            continue
        for sym, fq in law.quantities.items():
            quantities.define(sym, fq)
        out.append((law.expr, quantities.jac(law.expr)))
    return out


def time_power(energy: sp.Expr) -> sp.Expr:
    """d energy / dt at fixed q: the power an element's explicit time dependence gives (a potential V(q, t), a
    spring whose length depends on t). Where the energy switches in t (sign, abs, min, max of t), SymPy's
    derivative holds DiracDelta terms: they are 0 at every instant but the switch, whose jump of energy no
    integrator can carry as a power, so they are dropped (the balance residual then shows that jump)."""
    return sp.diff(energy, TIME).replace(sp.DiracDelta, lambda *args: sp.Integer(0))
