"""Contact impacts: which contacts take an impulse together, and which are left closed (andyc.spec.contacts).

A contact's impact jump (its gap crossing zero, falling) carries no compiled impact map; the drivers call
resolve_impact right after it, before the user's jump function and the record. Every contact touching at
that instant takes part: the closed ones (the flow's bitmask) and the open ones whose gap would close within
SIMULTANEOUS seconds at their normal speed (a rod falling flat onto two supports strikes both at once), or
whose gap is at most TOUCHING (the contact whose guard fired: a slow approach, a rocking block's corner late in
its decay, is located with its gap a rounding above zero, more than SIMULTANEOUS times its speed).
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
rebound too slow to matter), less those whose normal force would then pull, chosen as initial_mode chooses
(_settle); the others are open. When the jump times accumulate (Zeno: the EventLog's test, the same that stops a
hand-written bouncing ball; or a second contact impact at the same instant, EventLog.impact_again: two stops
coupled through the bodies, each impact knocking the other open by a rounding, as a walker's knee strike and its
stance knee), the impact is solved plastic (e = 0 for every
contact), and the touching contacts are then set at rest (_at_rest), so the run goes on from the accumulation
point: the ball comes to rest, and so does a rocking block on both its corners.

With friction (andyc.spec.contacts: planar Coulomb, a stick row J_t, the slip speed s = J_t v), each touching
contact with friction takes part in one of four ways: no impulse, a sticking impulse (its stick row too:
s+ = 0, |Lam_t| <= mu Lam_n), or a sliding one forwards or backwards (the impulse along B = A_n - sigma mu J_t,
s+ sigma >= 0): Newton's law in the normal direction, Coulomb's on the tangential impulse (Glocker & Pfeiffer's
Newton-Coulomb impact, planar; the cases are enumerated as the active sets are, sticking before sliding). The
contact then closes sticking if its slip speed after is at most REST_SPEED, else slipping its way.

Spatial friction (two tangents, slip s = (s1, s2), andyc.spec.contacts): the tangential impulse lies in the disk
|P_t| <= mu P_n. The cases: no impulse; a sticking impulse (both stick rows: s+ = 0) if it is inside the disk;
else sliding, P_t = -mu P_n u along the slip's direction before the impact, u = s-/|s-| (without a slip before,
against the sticking impulse), with s+ . u >= 0 (the slip is not reversed). For a ball, whose tangential inverse
inertia at the contact is isotropic, the slip keeps its direction through the impact and this is Coulomb's law
integrated over it (Brach 1991, ch. 3, in the plane of u); for other bodies the slip's direction turns during a
sliding impact, which this law (the direction frozen at its start) does not follow. The contact then closes
sticking if |s+| <= REST_SPEED, else slipping along s+.

resolve_stop decides where a slip ends (its slip speed crossing zero): the contact sticks if the friction force
it needs there is inside the cone, |lam_t| <= mu lam_n; otherwise it slips the other way (lam_t > mu lam_n: the
other forces push it backwards). The other contacts whose slip is zero then too stop with it, each deciding by
its own cone; the rest keep their states (this is not the full complementarity problem of the accelerations).
A contact with spatial friction sticks if |lam_t| <= mu lam_n, else slips on against lam_t (its direction into
the discrete states that keep it); a stick that reaches the cone's edge (its `_slip` jump) starts its slip the same
way (start_slip).

initial_mode picks the mode a run starts in: the contacts touching at rest, less those that would pull, each
with friction sticking if it does not slip and the friction it needs is inside the cone, else slipping.
"""

from __future__ import annotations

import math
from itertools import combinations, product

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import MESSAGES, ON_ZERO, OPEN_SIDE, PAINLEVE, REST_SPEED, SLIP_TINY

SIMULTANEOUS = 1e-9     # s: an open contact takes part when its gap closes within this time at its speed
TOUCHING = 1e-12        # a contact whose gap is at most this at the start, at rest, starts closed
STICK, SLIP_POS, SLIP_NEG = 1, 2, 3     # a contact's states beside open (0), as andyc.spec.contacts
SLIP = 2                                # spatial friction: its one slipping state


def friction_coefficients(model, p) -> np.ndarray:
    """mu of each contact (NaN without friction): the coefficient of its slip's end jumps (andyc.spec.contacts)."""
    mu = np.full(len(model.contact_names), np.nan)
    if any(r >= 0 for r in model.contact_stick_rows):
        values = model.module.restitutions(p)
        for k, (kind, i) in enumerate(model.jump_kinds):
            if kind == "stop":
                mu[i] = values[k]
    return mu


def _terms(model, t, x, u, p, d):
    M = model.module.mass_matrix(t, x, u, p, d)
    phi, c, A = np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, model.nv))
    model.module.constraints(t, x, u, p, d, phi, c, A, np.empty(model.nc))
    return M, phi, c, A


def resolve_impact(model, t, x, u, p, d, flow: int, plastic: bool, fired: int = -1) -> int:
    """Apply the impulses of the contacts touching at (t, x) to x's speeds, in place; the new flow (the states of
    the contacts after). plastic: e = 0 for every contact (the impact times accumulate). fired: the contact whose
    impact jump this is; on zero (|gap| <= TOUCHING) it takes part whatever its speed, even one a rounding above
    zero (a gap left opening at 4e-9 m/s by the impact before and accelerated closed: its root is located at the
    step's start), so that the plastic impact of accumulated impacts sets it at rest too."""
    nq, nv = model.nq, model.nv
    M, phi, c, A = _terms(model, t, x, u, p, d)
    e = np.zeros(len(model.contact_names))
    if not plastic:
        for k, restitution in enumerate(model.module.restitutions(p)):
            if model.jump_contact[k] >= 0:
                e[model.jump_contact[k]] = restitution
    mu = friction_coefficients(model, p)
    stick = list(model.contact_stick_rows) or [-1] * len(model.contact_names)
    spatial = [n == 2 for n in model.tangents]
    states = model.contact_states(flow)
    rows = list(model.contact_rows)
    contact_row = set(rows) | {r for r in stick if r >= 0}
    bilateral = [r for r in model.active_rows(flow) if r not in contact_row]
    touching = [i for i, r in enumerate(rows)
                if states[i] or (c[r] < -REST_SPEED and phi[r] <= max(SIMULTANEOUS * -c[r], TOUCHING))
                or (i == fired and abs(phi[r]) <= TOUCHING)]
    used = rows + bilateral + [r for r in stick if r >= 0] + [r + 1 for i, r in enumerate(stick) if spatial[i]]
    scale = max(1.0, float(np.max(np.abs(c[used])))) if used else 1.0
    tol = 1e-10 * scale
    Minv = np.linalg.inv(M)
    # Impulses are checked against the impulse that changes a touching contact's speed by tol (tol / W_ii, W =
    # A M^-1 A^T), not against tol itself: so the choice does not depend on the units of mass (a walker with every
    # mass scaled by 0.1 moves as before, and takes the same impacts).
    reach = [float(A[rows[i]] @ Minv @ A[rows[i]]) for i in touching]
    ptol = tol / max(reach) if reach and max(reach) > 0.0 else tol
    # each touching contact: 0 no impulse, 1 active (sticking, with friction), 2 / 3 sliding forwards / backwards
    # (spatial friction: 0 none, 1 sticking, 2 sliding against the slip before, _slide_direction)
    choices = [range(3) if spatial[i] else range(4) if stick[i] >= 0 else range(2) for i in touching]
    slide = {i: _slide_direction(model, i, c, A, Minv, bilateral, e[i])
             for i in touching if spatial[i]}
    cases = sorted(product(*choices), key=lambda case: (sum(o > 0 for o in case), sum(o > 1 for o in case), case))
    best = None
    for case in cases:
        R, B, target = list(bilateral), [A[r] for r in bilateral], [0.0] * len(bilateral)
        for i, o in zip(touching, case):
            r = rows[i]
            if o == 0:
                continue
            R.append(r)
            target.append(-e[i] * c[r])
            if o == 1:
                B.append(A[r])
                if stick[i] >= 0:
                    R.append(stick[i])
                    B.append(A[stick[i]])
                    target.append(0.0)
                if spatial[i]:
                    R.append(stick[i] + 1)
                    B.append(A[stick[i] + 1])
                    target.append(0.0)
            elif spatial[i]:
                B.append(A[r] - mu[i] * (slide[i] @ A[stick[i]:stick[i] + 2]))
            else:
                B.append(A[r] - (1.0 if o == SLIP_POS else -1.0) * mu[i] * A[stick[i]])
        if R:
            B = np.array(B)
            lam = np.linalg.lstsq(A[R] @ Minv @ B.T, np.array(target) - c[R], rcond=None)[0]
            dv = Minv @ B.T @ lam
        else:
            lam, dv = np.zeros(0), np.zeros(nv)
        after = c + A @ dv
        impulse = dict(zip(R, lam))
        ok = True
        for i, o in zip(touching, case):
            r = rows[i]
            if o == 0:
                ok = after[r] >= -e[i] * c[r] - tol
            elif impulse[r] < -ptol:
                ok = False
            elif o == 1 and spatial[i]:
                ok = math.hypot(impulse[stick[i]], impulse[stick[i] + 1]) <= mu[i] * impulse[r] + ptol
            elif o == 1 and stick[i] >= 0:
                ok = abs(impulse[stick[i]]) <= mu[i] * impulse[r] + ptol
            elif spatial[i]:
                ok = slide[i] @ after[stick[i]:stick[i] + 2] >= -tol
            elif o == SLIP_POS:
                ok = after[stick[i]] >= -tol
            elif o == SLIP_NEG:
                ok = after[stick[i]] <= tol
            if not ok:
                break
        if ok:
            best = (dv, after)
            break
    if best is None:                # (W is positive semi-definite: a solution exists; this is a safeguard)
        raise FloatingPointError(f"no consistent contact impulses at t = {t}")
    dv, after = best
    x[nq:nq + nv] += dv
    if plastic:
        return _at_rest(model, t, x, u, p, d, [rows[i] for i in touching] + bilateral
                        + [stick[i] for i in touching if stick[i] >= 0 and abs(after[stick[i]]) <= REST_SPEED])
    states = [0] * len(rows)
    for i in touching:
        if after[rows[i]] > REST_SPEED:
            continue
        if spatial[i]:
            slip = after[stick[i]:stick[i] + 2]
            states[i] = _stuck(model, d, i) if np.hypot(*slip) <= REST_SPEED else _set_direction(model, d, i, slip)
        else:
            states[i] = 1 if stick[i] < 0 else _slip_state(after[stick[i]])
    return _settle(model, t, x, u, p, d, states)


def _at_rest(model, t, x, u, p, d, R: list) -> int:
    """The impact times accumulate (Zeno): at their accumulation point the touching contacts are at rest, as the
    ball that stops bouncing or the rocking block whose corners strike ever faster and ever slower (Housner's
    rocking loses a fixed share of its speed at each impact, so its half-cycles shrink geometrically). The
    plastic impact alone leaves the corner that did not strike lifting (no impulse can stop a block rocking
    about one corner without pulling at the other), at a speed that the impacts that remain would take away,
    so the rows R (the touching contacts' gaps, the stick rows of those not slipping, the flow's other rows) are
    set at rest by the least M-norm change of x's speeds, in place (a change of the size of the speed that is
    left), and the run goes on in the mode of a run starting there (initial_mode: no contact pulls)."""
    nq, nv = model.nq, model.nv
    M, _, c, A = _terms(model, t, x, u, p, d)
    Minv, J = np.linalg.inv(M), A[R]
    x[nq:nq + nv] -= Minv @ J.T @ np.linalg.lstsq(J @ Minv @ J.T, c[R], rcond=None)[0]
    return initial_mode(model, t, x, u, p, d)


def _slide_direction(model, i: int, c, A, Minv, bilateral: list, e: float) -> np.ndarray:
    """The unit direction along which contact i (spatial friction) slides at an impact: its slip before, s-/|s-|;
    without one (|s-| <= REST_SPEED), against the tangential impulse that would stop it, -P_t/|P_t| (the sticking
    impulse, outside the cone). (1, 0) if neither has a direction."""
    t1 = model.contact_stick_rows[i]
    slip = c[t1:t1 + 2]
    if np.hypot(*slip) > REST_SPEED:
        return slip / np.hypot(*slip)
    R = list(bilateral) + [model.contact_rows[i], t1, t1 + 1]
    target = np.array([0.0] * len(bilateral) + [-e * c[model.contact_rows[i]], 0.0, 0.0])
    lam = np.linalg.lstsq(A[R] @ Minv @ A[R].T, target - c[R], rcond=None)[0]
    size = np.hypot(lam[-2], lam[-1])
    return -lam[-2:] / size if size > 0.0 else np.array([1.0, 0.0])


def _direction_index(model, i: int) -> int:
    """The index in d of contact i's slip direction (spatial friction: two discrete states)."""
    return model.discrete_names.index(f"{model.contact_names[i]}_slip_dir_1")


def _set_direction(model, d, i: int, direction) -> int:
    """Contact i (spatial friction) slips along `direction` (made unit) from here: into its discrete states
    (numerics.slipping.slip_unit reads them while the slip is slower than SLIP_TINY). Returns SLIP."""
    k = _direction_index(model, i)
    d[k:k + 2] = np.asarray(direction, dtype=float) / np.hypot(*direction)
    d[k + 2] = 0.0          # (not held: the integrator decides at its next step)
    return SLIP


def _stuck(model, d, i: int) -> int:
    """Contact i (spatial friction) sticks: no step holds its slip's direction (its discrete state to 0); STICK."""
    d[_direction_index(model, i) + 2] = 0.0
    return STICK


def _spatial_cone_state(model, d, i: int, lam, mu: float) -> int:
    """Where contact i (spatial friction) that would stick goes: it sticks if the friction it needs is inside the
    cone, |lam_t| <= mu lam_n; past its edge it slips against that friction, along -lam_t / |lam_t|."""
    t1 = model.contact_stick_rows[i]
    lam_t, lam_n = lam[t1:t1 + 2], lam[model.contact_rows[i]]
    if np.hypot(*lam_t) <= mu * lam_n + 1e-12 * max(1.0, abs(lam_n)):
        return _stuck(model, d, i)
    return _set_direction(model, d, i, -lam_t)


def start_slip(model, t, x, u, p, d, k: int) -> None:
    """After jump k, a contact with spatial friction that stuck reaching the edge of its cone (`<contact>_slip`):
    its slip starts against the friction force it had, along -lam_t / |lam_t| (into d: _set_direction)."""
    i = model.jump_kinds[k][1]
    lam = model.module.multipliers(t, x, u, p, d, int(model.module.JUMP_SOURCE[k]))
    t1 = model.contact_stick_rows[i]
    if np.hypot(*lam[t1:t1 + 2]) > 0.0:
        _set_direction(model, d, i, -lam[t1:t1 + 2])


def _slip_state(slip: float) -> int:
    """A closing contact with friction: sticking at (almost) no slip, else slipping its way."""
    return STICK if abs(slip) <= REST_SPEED else SLIP_POS if slip > 0 else SLIP_NEG


def _cone_state(lam_t: float, lam_n: float, mu: float) -> int:
    """Where a contact that would stick goes: it sticks if the friction it needs is inside the cone; past its
    edge it slips the way the other forces push it (lam_t > mu lam_n: backwards)."""
    tol = 1e-12 * max(1.0, abs(lam_n))
    return SLIP_NEG if lam_t > mu * lam_n + tol else SLIP_POS if lam_t < -mu * lam_n - tol else STICK


def resolve_stop(model, t, x, u, p, d, k: int, flow: int) -> int:
    """After jump k, a contact's slip ending (its slip speed crossing zero) into `flow`, where it sticks: with it
    every other contact slipping at a slip speed of at most REST_SPEED then (two ends of one rod on the floor stop
    together), their slip speeds (and every active row's velocity residual, a rounding at the located event) set
    to zero by the least M-norm change of x's speeds, in place. Returns the flow it lands in: each of them
    sticking, or slipping the other way (_cone_state)."""
    nq, nv = model.nq, model.nv
    M, _, c, A = _terms(model, t, x, u, p, d)
    states, stick, tangents = model.contact_states(flow), model.contact_stick_rows, model.tangents
    stopping = [model.jump_kinds[k][1]] + [i for i, s in enumerate(states) if s > STICK and tangents[i] == 1
                                           and abs(c[stick[i]]) <= REST_SPEED]
    for i in stopping:
        states[i] = STICK
    flow = model.contact_flow(states)
    R = model.active_rows(flow)
    Minv = np.linalg.inv(M)
    J = A[R]
    x[nq:nq + nv] -= Minv @ J.T @ np.linalg.lstsq(J @ Minv @ J.T, c[R], rcond=None)[0]
    lam = model.module.multipliers(t, x, u, p, d, flow)
    mu = friction_coefficients(model, p)
    for i in stopping:
        states[i] = (_spatial_cone_state(model, d, i, lam, mu[i]) if tangents[i] == 2
                     else _cone_state(lam[stick[i]], lam[model.contact_rows[i]], mu[i]))
    return model.contact_flow(states)


def initial_mode(model, t, x, u, p, d) -> int:
    """The flow a run starts in: the contacts touching (|gap| <= TOUCHING) at rest (|normal speed| <= REST_SPEED),
    less those whose normal force in that mode is negative, the most negative first, one at a time (dropping one
    changes the others' forces); each with friction slipping its way if its slip speed exceeds REST_SPEED, else
    sticking if the friction it needs is inside the cone (else slipping, _cone_state). Should a contact so dropped
    then close again at once (its gap's acceleration negative in that mode: two stops coupled through the bodies,
    a walker's two knees, where dropping the most negative is the wrong one), the modes are enumerated instead, the
    fewest dropped first, for the first in which the closed contacts push and the dropped ones open
    (_complementary): the acceleration-level complementarity problem of Pfeiffer & Glocker (1996, ch. 6)."""
    _, phi, c, _ = _terms(model, t, x, u, p, d)
    rows = model.contact_rows
    stick = list(model.contact_stick_rows) or [-1] * len(rows)
    states = [int(abs(phi[r]) <= TOUCHING and abs(c[r]) <= REST_SPEED) for r in rows]
    tangents = model.tangents
    for i, s in enumerate(states):
        if s and tangents[i] == 2:
            slip = c[stick[i]:stick[i] + 2]
            states[i] = STICK if np.hypot(*slip) <= REST_SPEED else _set_direction(model, d, i, slip)
        elif s and stick[i] >= 0:
            states[i] = _slip_state(c[stick[i]])
    return _settle(model, t, x, u, p, d, states)


def _settle(model, t, x, u, p, d, states: list) -> int:
    """The flow of the contacts closed in `states` (at rest) less those that would pull (initial_mode's rule)."""
    at_rest = [i for i, s in enumerate(states) if s]
    mode = _drop_pulling(model, t, x, u, p, d, list(states))
    if _complementary(model, t, x, u, p, d, mode, [i for i in at_rest if not mode[i]]):
        return model.contact_flow(mode)
    for n in range(1, len(at_rest) + 1):
        for dropped in combinations(at_rest, n):
            trial = [0 if i in dropped else s for i, s in enumerate(states)]
            if _complementary(model, t, x, u, p, d, trial, dropped, pushing=True):
                return model.contact_flow(_drop_pulling(model, t, x, u, p, d, trial))
    return model.contact_flow(mode)


def _drop_pulling(model, t, x, u, p, d, states: list) -> list:
    """The contacts' states less those whose normal force is negative, the most negative first, one at a time;
    each sticking one then sticking or slipping by its cone (initial_mode)."""
    rows, tangents = model.contact_rows, model.tangents
    stick = list(model.contact_stick_rows) or [-1] * len(rows)
    mu = friction_coefficients(model, p)
    while any(states):
        flow = model.contact_flow(states)
        lam = model.module.multipliers(t, x, u, p, d, flow)
        force, worst = min((lam[r], i) for i, r in enumerate(rows) if states[i])
        if force < 0.0:
            if states[worst] > STICK:
                _painleve(model, t, x, u, p, d, worst, states[worst], mu[worst])
            states[worst] = 0
            continue
        cone = [(_spatial_cone_state(model, d, i, lam, mu[i]) if tangents[i] == 2 else
                 _cone_state(lam[stick[i]], lam[rows[i]], mu[i])) if s == STICK and stick[i] >= 0 else s
                for i, s in enumerate(states)]
        if cone == states:
            break
        states = cone
    return states


def _complementary(model, t, x, u, p, d, states: list, dropped, pushing: bool = False) -> bool:
    """In the mode of `states`, no dropped contact's gap accelerates closed (A_i dv/dt + kappa_i >= -tol) and, with
    `pushing`, every closed contact pushes (its normal force >= -tol); tol is 1e-10 of the largest term."""
    flow = model.contact_flow(states)
    nq, nv = model.nq, model.nv
    phi, c, A, kappa = np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, nv)), np.empty(model.nc)
    model.module.constraints(t, x, u, p, d, phi, c, A, kappa)
    try:
        vdot = model.module.rhs(t, x, u, p, d, flow)[nq:nq + nv]
        lam = model.module.multipliers(t, x, u, p, d, flow)
    except FloatingPointError:
        return False
    rows = model.contact_rows
    accel = [A[rows[i]] @ vdot + kappa[rows[i]] for i in dropped]
    scale = 1e-10 * max([1.0, float(np.max(np.abs(vdot)))] + [abs(a) for a in accel])
    if any(a < -scale for a in accel):
        return False
    return not pushing or all(lam[r] >= -1e-10 * max(1.0, float(np.max(np.abs(lam)))) for i, r in enumerate(rows)
                              if states[i])


def _painleve(model, t, x, u, p, d, i: int, state: int, mu: float) -> None:
    """SimulationError if contact i, slipping (state), has A_n M^-1 (A_n - sigma mu J_t)^T <= 0: its negative
    normal force is then no reason to open it (open, it would close faster: Painleve's paradox, no consistent
    mode; numerics.slipping.solve_slipping refuses the same during a run)."""
    M, _, c, A = _terms(model, t, x, u, p, d)
    normal, tangent = A[model.contact_rows[i]], A[model.contact_stick_rows[i]]
    sigma = 1.0 if state == SLIP_POS else -1.0
    if model.tangents[i] == 2:          # along the slip's direction (as numerics.slipping.slip_unit)
        t1, k = model.contact_stick_rows[i], _direction_index(model, i)
        slip = c[t1:t1 + 2]
        direction = slip / np.hypot(*slip) if np.hypot(*slip) > SLIP_TINY else d[k:k + 2]
        tangent, sigma = direction @ A[t1:t1 + 2], 1.0
    if not normal @ np.linalg.solve(M, normal - sigma * mu * tangent) > 0.0:
        when = "at the start" if t == 0.0 else f"coming to rest at t = {t:.12g} s"
        raise SimulationError(f"contact '{model.contact_names[i]}' {when}: {MESSAGES[PAINLEVE]}")


def open_side(model, t, x, u, p, d, g0: dict) -> None:
    """The adaptive methods' start of a segment (as the compiled integrator.advance's): each contact impact guard in
    g0 (jump -> value) whose gap is on zero (|gap| <= ON_ZERO, relative beyond 1) and opening (normal speed above
    REST_SPEED: it left an impact) starts at OPEN_SIDE, so that its coming down within the step is located."""
    opening = [m for m in g0 if model.jump_contact and model.jump_contact[m] >= 0
               and abs(g0[m]) <= ON_ZERO * max(1.0, float(np.max(np.abs(x))))]
    if opening:
        _, _, c, _ = _terms(model, t, x, u, p, d)
        for m in opening:
            if c[model.contact_rows[model.jump_contact[m]]] > REST_SPEED:
                g0[m] = OPEN_SIDE


def slip_speeds(model, t, x, u, p, d) -> tuple[np.ndarray, np.ndarray]:
    """(N, contacts) each contact's slip speed (its stick row's velocity residual J_t v + b) at the logged samples
    t (N,), x, u, d (N, ...), NaN for the contacts without friction; and (N, contacts) the slip along the second
    tangent of a contact with spatial friction (NaN for the others)."""
    out, second = np.full((2, len(t), len(model.contact_names)), np.nan)
    rows = [(i, r) for i, r in enumerate(model.contact_stick_rows) if r >= 0]
    spatial = [(i, r + 1) for i, r in rows if model.tangents[i] == 2]
    if rows:
        phi, c, A, kappa = np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, model.nv)), np.empty(model.nc)
        for n in range(len(t)):
            model.module.constraints(t[n], x[n], u[n], p, d[n], phi, c, A, kappa)
            for i, r in rows:
                out[n, i] = c[r]
            for i, r in spatial:
                second[n, i] = c[r]
    return out, second
