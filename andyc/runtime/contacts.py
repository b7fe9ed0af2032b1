"""Contact impacts: which contacts take an impulse together, and which are left closed (andyc.spec.contacts).

A contact's impact jump (its gap crossing zero, falling) carries no compiled impact map; the drivers call
resolve_impact right after it, before the user's jump function and the record. Every contact touching at
that instant takes part: the closed ones (the flow's bitmask) and the open ones whose gap would close within
SIMULTANEOUS seconds at their normal speed (a rod falling flat onto two supports strikes both at once).
Their impulses solve the impact as a linear complementarity problem (Pfeiffer & Glocker, Multibody Dynamics
with Unilateral Contacts, 1996, ch. 7; Newton's law per contact):

    c+ = c- + W Lam,   W = J M^-1 J^T,   v+ = v- + M^-1 J^T Lam
    Lam_i >= 0,   c+_i + e_i c-_i >= 0,   Lam_i (c+_i + e_i c-_i) = 0      (each touching contact i)
    c+_r = 0                                                             (the flow's other rows: bilateral)

with c the rows' velocity residuals (the normal speeds of the gaps), J their rows of A. No contact pulls
and none is processed before another, so no sequence is invented. It is solved by enumerating the active
sets, smallest first (at most 2^4 for the schema's 4 contacts), each a least-squares solve of W over its
rows (redundant rows allowed); W is positive semi-definite, and the first set that satisfies every
inequality is taken.

An open contact approaching slower than REST_SPEED (andyc.numerics.status) takes no impact (nor does the
integrator's `instant` fire its jump): right after a liftoff its gap is a rounding from zero, at rest.
Modes after the impact: a touching contact whose normal speed after is at most REST_SPEED closes (e = 0, or a
rebound too slow to matter); the others are open. When the jump times accumulate (Zeno: the EventLog's
test, the same that stops a hand-written bouncing ball), the impact is solved plastic (e = 0 for every
contact), so the contacts close and the run goes on from the accumulation point: the ball comes to rest.

initial_mode picks the mode a run starts in: the contacts touching at rest, less those that would pull.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from andyc.numerics.status import REST_SPEED

SIMULTANEOUS = 1e-9     # s: an open contact takes part when its gap closes within this time at its speed
TOUCHING = 1e-12        # a contact whose gap is at most this at the start, at rest, starts closed


def resolve_impact(model, t, x, u, p, d, flow: int, plastic: bool) -> int:
    """Apply the impulses of the contacts touching at (t, x) to x's speeds, in place; the new flow (the bitmask
    of the contacts closed after). plastic: e = 0 for every contact (the impact times accumulate)."""
    module, nq, nv = model.module, model.nq, model.nv
    M = module.mass_matrix(t, x, u, p, d)
    phi, c, A, kappa = np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, nv)), np.empty(model.nc)
    module.constraints(t, x, u, p, d, phi, c, A, kappa)
    e = np.zeros(len(model.contact_names))
    if not plastic:
        for k, restitution in enumerate(module.restitutions(p)):
            if model.jump_contact[k] >= 0:
                e[model.jump_contact[k]] = restitution
    rows = list(model.contact_rows)
    contact_row = set(rows)
    bilateral = [r for r in model.active_rows(flow) if r not in contact_row]
    touching = [i for i, r in enumerate(rows)
                if flow >> i & 1 or (c[r] < -REST_SPEED and phi[r] <= SIMULTANEOUS * -c[r])]
    scale = max(1.0, float(np.max(np.abs(c[rows + bilateral])))) if rows + bilateral else 1.0
    tol = 1e-10 * scale
    Minv = np.linalg.inv(M)
    best = None
    for size in range(len(touching) + 1):
        for active in combinations(touching, size):
            R = bilateral + [rows[i] for i in active]
            J = A[R]
            target = np.concatenate([np.zeros(len(bilateral)), [-e[i] * c[rows[i]] for i in active]])
            lam = np.linalg.lstsq(J @ Minv @ J.T, target - c[R], rcond=None)[0] if R else np.zeros(0)
            dv = Minv @ J.T @ lam if R else np.zeros(nv)
            after = c + A @ dv
            ok = all(lam[len(bilateral) + n] >= -tol for n in range(size))
            ok = ok and all(after[rows[i]] >= -e[i] * c[rows[i]] - tol for i in touching if i not in active)
            if ok:
                best = (dv, after)
                break
        if best is not None:
            break
    if best is None:                # (W is positive semi-definite: a solution exists; this is a safeguard)
        raise FloatingPointError(f"no consistent contact impulses at t = {t}")
    dv, after = best
    x[nq:nq + nv] += dv
    mask = 0
    for i in touching:
        if after[rows[i]] <= REST_SPEED:
            mask |= 1 << i
    return mask


def initial_mode(model, t, x, u, p, d) -> int:
    """The flow a run starts in (the bitmask of the closed contacts): the contacts touching (|gap| <= TOUCHING)
    at rest (|normal speed| <= REST_SPEED), less those whose normal force in that mode is negative, the most
    negative first, one at a time (dropping one changes the others' forces)."""
    phi, c = np.empty(model.nh), np.empty(model.nc)
    model.module.constraints(t, x, u, p, d, phi, c, np.empty((model.nc, model.nv)), np.empty(model.nc))
    rows = model.contact_rows
    mask = sum(1 << i for i, r in enumerate(rows) if abs(phi[r]) <= TOUCHING and abs(c[r]) <= REST_SPEED)
    while mask:
        lam = model.module.multipliers(t, x, u, p, d, mask)
        force, worst = min((lam[r], i) for i, r in enumerate(rows) if mask >> i & 1)
        if force >= 0.0:
            break
        mask &= ~(1 << worst)
    return mask
