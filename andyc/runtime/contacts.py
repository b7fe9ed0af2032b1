"""Contact impacts and slip ends: which contacts take an impulse together, and the modes they are left in.

Each contact's mode is a discrete state (andyc.spec.contacts: 0 open, 1 closed or sticking, 2 / 3 slipping
forwards / backwards; spatial friction: 2 slipping), read through CompiledModel.contact_states(d). A contact's
impact jump (its gap crossing zero, falling) carries no compiled impact map; the drivers call resolve_impact
right after it, before the user's jump function and the record. Every contact touching at that instant takes
part: the closed ones and the open ones whose gap would close within SIMULTANEOUS seconds at their normal speed
(a rod falling flat onto two supports strikes both at once), or whose gap is at most TOUCHING (the contact whose
guard fired: a slow approach, a rocking block's corner late in its decay, is located with its gap a rounding
above zero, more than SIMULTANEOUS times its speed). Their impulses solve the impact as a complementarity
problem (Pfeiffer & Glocker, Multibody Dynamics with Unilateral Contacts, 1996, ch. 7; Newton's law per
contact):

    c+ = c- + W Lam,   W = J M^-1 J^T,   v+ = v- + M^-1 J^T Lam
    Lam_i >= 0,   c+_i + e_i c-_i >= 0,   Lam_i (c+_i + e_i c-_i) = 0      (each touching contact i)
    c+_r = 0                                                             (the flow's own rows: bilateral)

with c the rows' velocity residuals (the normal speeds of the gaps), J their rows of A. No contact pulls
and none is processed before another, so no sequence is invented. With few touching contacts (at most
MAX_CASES cases) it is solved by enumerating the active sets, smallest first, each a least-squares solve of W
over its rows (redundant rows allowed; W is positive semi-definite), the first that satisfies every
inequality taken; with more (a robot's feet, a box's corners), by the time-stepping method's solver
(andyc_numerics' contact_solver: Gauss-Seidel over the contacts, then the active set it finds solved exactly),
whose problem this is with the step's free velocity replaced by the speeds before the impact.

An open contact approaching slower than REST_SPEED (andyc.numerics.status) takes no impact (nor does the
integrator's `instant` fire its jump): right after a liftoff its gap is a rounding from zero, at rest.
Modes after the impact: a touching contact whose normal speed after is at most REST_SPEED closes (e = 0, or a
rebound too slow to matter), less those whose normal force would then pull, chosen as initial_mode chooses
(andyc.runtime.contact_modes); the others are open. When the jump times accumulate (Zeno: the EventLog's test;
or a second contact impact at the same instant, EventLog.impact_again: two stops coupled through the bodies,
each impact knocking the other open by a rounding, as a walker's knee strike and its stance knee), the impact is
solved plastic (e = 0 for every contact), and the touching contacts are then set at rest (_at_rest), so the run
goes on from the accumulation point: the ball comes to rest, and so does a rocking block on both its corners.

With friction (planar Coulomb, a stick row J_t, the slip speed s = J_t v), each touching contact with friction
takes part in one of four ways: no impulse, a sticking impulse (its stick row too: s+ = 0, |Lam_t| <= mu Lam_n),
or a sliding one forwards or backwards (the impulse along B = A_n - sigma mu J_t, s+ sigma >= 0): Newton's law in
the normal direction, Coulomb's on the tangential impulse (Glocker & Pfeiffer's Newton-Coulomb impact, planar;
the cases are enumerated as the active sets are, sticking before sliding). The contact then closes sticking if
its slip speed after is at most REST_SPEED, else slipping its way.

Spatial friction (two tangents, slip s = (s1, s2)): the tangential impulse lies in the disk |P_t| <= mu P_n. The
cases: no impulse; a sticking impulse (both stick rows: s+ = 0) if it is inside the disk; else sliding,
P_t = -mu P_n u along the slip's direction before the impact, u = s-/|s-| (without a slip before, against the
sticking impulse), with s+ . u >= 0 (the slip is not reversed). For a ball, whose tangential inverse inertia at
the contact is isotropic, the slip keeps its direction through the impact and this is Coulomb's law integrated
over it (Brach 1991, ch. 3, in the plane of u); for other bodies the slip's direction turns during a sliding
impact, which this law (the direction frozen at its start) does not follow. (The solver used for many contacts
takes the slip's direction after the impulse instead: the time-stepping method's law.) The contact then closes
sticking if |s+| <= REST_SPEED, else slipping along s+.

resolve_stop decides where a slip ends (its slip speed crossing zero): the contact sticks if the friction force
it needs there is inside the cone, |lam_t| <= mu lam_n; otherwise it slips the other way (lam_t > mu lam_n: the
other forces push it backwards). The other contacts whose slip is zero then too stop with it, each deciding by
its own cone; the rest keep their modes. A contact with spatial friction sticks if |lam_t| <= mu lam_n, else
slips on against lam_t (its direction into the discrete states that keep it); a stick that reaches the cone's edge
(its `_slip` jump) starts its slip the same way (start_slip).
"""

from __future__ import annotations

import importlib
import math
from itertools import product

import numpy as np

from andyc.runtime.contact_modes import (SLIP_NEG, SLIP_POS, STICK, TOUCHING, cone_state, friction_coefficients,
                                         initial_mode, leaves, set_direction, settle, slip_state, spatial_cone_state,
                                         stuck, terms, with_states)
from andyc.numerics.status import ON_ZERO, OPEN_SIDE, REST_SPEED

__all__ = ["resolve_impact", "resolve_liftoff", "resolve_stop", "start_slip", "initial_mode", "friction_coefficients", "open_side",
           "slip_speeds", "TOUCHING"]

SIMULTANEOUS = 1e-9     # s: an open contact takes part when its gap closes within this time at its speed
MAX_CASES = 256         # an impact's active sets enumerated at most; beyond, the time-stepping method's solver


def resolve_impact(model, t, x, u, p, d, flow: int, plastic: bool, fired: int = -1) -> None:
    """Apply the impulses of the contacts touching at (t, x) to x's speeds and set the contacts' modes after in d,
    both in place. plastic: e = 0 for every contact (the impact times accumulate). fired: the contact whose impact
    jump this is; on zero (|gap| <= TOUCHING) it takes part whatever its speed, even one a rounding above zero (a
    gap left opening at 4e-9 m/s by the impact before and accelerated closed: its root is located at the step's
    start), so that the plastic impact of accumulated impacts sets it at rest too."""
    nq, nv = model.nq, model.nv
    M, phi, c, A = terms(model, t, x, u, p, d)
    e = np.zeros(len(model.contact_names))
    if not plastic:
        for k, restitution in enumerate(model.module.restitutions(p)):
            if model.jump_contact[k] >= 0:
                e[model.jump_contact[k]] = restitution
    mu = friction_coefficients(model, p)
    stick = list(model.contact_stick_rows)
    spatial = [n == 2 for n in model.tangents]
    states = model.contact_states(d)
    rows = list(model.contact_rows)
    bilateral = model.active_rows(flow)
    touching = [i for i, r in enumerate(rows)
                if states[i] or (c[r] < -REST_SPEED and phi[r] <= max(SIMULTANEOUS * -c[r], TOUCHING))
                or (i == fired and abs(phi[r]) <= TOUCHING)]
    used = rows + bilateral + [r for r in stick if r >= 0] + [r + 1 for i, r in enumerate(stick) if spatial[i]]
    scale = max(1.0, float(np.max(np.abs(c[used])))) if used else 1.0
    tol = 1e-10 * scale
    Minv = np.linalg.inv(M)
    choices = [range(3) if spatial[i] else range(4) if stick[i] >= 0 else range(2) for i in touching]
    if math.prod(len(ch) for ch in choices) > MAX_CASES:
        dv, after = _impulses_many(model, touching, rows, stick, spatial, bilateral, mu, e, c, A, Minv)
    else:
        found = _impulses_enumerated(model, touching, choices, rows, stick, spatial, bilateral, mu, e, c, A, Minv,
                                     tol)
        # (a spatial slide is enumerated along one direction, _slide_direction; where the impulse turns it, no
        # case holds, and the solver that finds the slide's direction takes the impact)
        dv, after = found or _impulses_many(model, touching, rows, stick, spatial, bilateral, mu, e, c, A, Minv)
    x[nq:nq + nv] += dv
    if plastic:
        _at_rest(model, t, x, u, p, d, flow, [rows[i] for i in touching] + bilateral
                 + [stick[i] for i in touching if stick[i] >= 0 and abs(after[stick[i]]) <= REST_SPEED])
        return
    states = [0] * len(rows)
    for i in touching:
        if after[rows[i]] > REST_SPEED:
            continue
        if spatial[i]:
            slip = after[stick[i]:stick[i] + 2]
            states[i] = stuck(model, d, i) if np.hypot(*slip) <= REST_SPEED else set_direction(model, d, i, slip)
        else:
            states[i] = 1 if stick[i] < 0 else slip_state(after[stick[i]])
    settle(model, t, x, u, p, d, flow, states)


def _impulses_enumerated(model, touching, choices, rows, stick, spatial, bilateral, mu, e, c, A, Minv, tol):
    """(dv, the rows' speeds after) of the impact, its active sets enumerated, fewest impulses first (module
    docstring); None where no case holds."""
    # Impulses are checked against the impulse that changes a touching contact's speed by tol (tol / W_ii, W =
    # A M^-1 A^T), not against tol itself: so the choice does not depend on the units of mass (a walker with every
    # mass scaled by 0.1 moves as before, and takes the same impacts).
    reach = [float(A[rows[i]] @ Minv @ A[rows[i]]) for i in touching]
    ptol = tol / max(reach) if reach and max(reach) > 0.0 else tol
    # each touching contact: 0 no impulse, 1 active (sticking, with friction), 2 / 3 sliding forwards / backwards
    # (spatial friction: 0 none, 1 sticking, 2 sliding against the slip before, _slide_direction)
    slide = {i: _slide_direction(model, i, c, A, Minv, bilateral, e[i]) for i in touching if spatial[i]}
    cases = sorted(product(*choices), key=lambda case: (sum(o > 0 for o in case), sum(o > 1 for o in case), case))
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
            lam, dv = np.zeros(0), np.zeros(A.shape[1])
        after = c + A @ dv
        impulse = dict(zip(R, lam))
        if all(_holds(i, o, rows[i], stick[i], spatial[i], mu[i], e[i], c, after, impulse, slide, tol, ptol)
               for i, o in zip(touching, case)):
            return dv, after
    return None


def _holds(i, o, r, t_row, spatial, mu, e, c, after, impulse, slide, tol, ptol) -> bool:
    """Whether touching contact i's case o keeps its conditions after the impulses (module docstring)."""
    if o == 0:
        return after[r] >= -e * c[r] - tol
    if impulse[r] < -ptol:
        return False
    if o == 1 and spatial:
        return math.hypot(impulse[t_row], impulse[t_row + 1]) <= mu * impulse[r] + ptol
    if o == 1 and t_row >= 0:
        return abs(impulse[t_row]) <= mu * impulse[r] + ptol
    if spatial:
        return slide[i] @ after[t_row:t_row + 2] >= -tol
    if o == SLIP_POS:
        return after[t_row] >= -tol
    if o == SLIP_NEG:
        return after[t_row] <= tol
    return True


def _impulses_many(model, touching, rows, stick, spatial, bilateral, mu, e, c, A, Minv):
    """(dv, the rows' speeds after) of an impact with more touching contacts than enumeration serves: the
    time-stepping method's contact problem (andyc_numerics' contact_solver) with w0 the speeds before, (1 + e) c- on
    each normal row (Newton's law c+ + e c- >= 0), c- on the tangent and bilateral rows."""
    solver = importlib.import_module(f"{model.numerics.__name__}.contact_solver")
    R, kinds, first, mus, w0 = list(bilateral), [solver.BILATERAL] * len(bilateral), list(range(len(bilateral))), \
        [0.0] * len(bilateral), [c[r] for r in bilateral]
    for i in touching:
        first.append(len(R))
        w0.append((1.0 + e[i]) * c[rows[i]])
        R.append(rows[i])
        mus.append(float(mu[i]) if stick[i] >= 0 else 0.0)
        if spatial[i]:
            kinds.append(solver.SPATIAL)
            R += [stick[i], stick[i] + 1]
            w0 += [c[stick[i]], c[stick[i] + 1]]
        elif stick[i] >= 0:
            kinds.append(solver.PLANAR)
            R.append(stick[i])
            w0.append(c[stick[i]])
        else:
            kinds.append(solver.NORMAL)
    X = Minv @ A[R].T
    nb, m = len(kinds), len(R)
    P = np.zeros(m)
    solver.solve(np.ascontiguousarray(A[R] @ X), np.array(w0), np.array(kinds, dtype=np.int64),
                 np.array(first, dtype=np.int64), np.array(mus), np.full(nb, solver.NONE, dtype=np.int64),
                 np.zeros((nb, 2)), P, np.zeros(solver.work_shape(m)))
    dv = X @ P
    return dv, c + A @ dv


def _at_rest(model, t, x, u, p, d, flow, R: list) -> None:
    """The impact times accumulate (Zeno): at their accumulation point the touching contacts are at rest, as the
    ball that stops bouncing or the rocking block whose corners strike ever faster and ever slower (Housner's
    rocking loses a fixed share of its speed at each impact, so its half-cycles shrink geometrically). The
    plastic impact alone leaves the corner that did not strike lifting (no impulse can stop a block rocking
    about one corner without pulling at the other), at a speed that the impacts that remain would take away,
    so the rows R (the touching contacts' gaps, the stick rows of those not slipping, the flow's own rows) are
    set at rest by the least M-norm change of x's speeds, in place (a change of the size of the speed that is
    left), and the run goes on in the modes of a run starting there (initial_mode: no contact pulls)."""
    nq, nv = model.nq, model.nv
    M, _, c, A = terms(model, t, x, u, p, d)
    Minv, J = np.linalg.inv(M), A[R]
    x[nq:nq + nv] -= Minv @ J.T @ np.linalg.lstsq(J @ Minv @ J.T, c[R], rcond=None)[0]
    initial_mode(model, t, x, u, p, d, flow)


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


def start_slip(model, t, x, u, p, d, k: int, flow: int) -> None:
    """After jump k, a contact with spatial friction that stuck reaching the edge of its cone (`<contact>_slip`,
    which set its mode to slipping): its slip starts against the friction force it had while sticking, along
    -lam_t / |lam_t| (into d: set_direction)."""
    i = model.jump_kinds[k][1]
    sticking = with_states(model, d, {i: STICK})
    lam = model.module.multipliers(t, x, u, p, sticking, flow)
    t1 = model.contact_stick_rows[i]
    if np.hypot(*lam[t1:t1 + 2]) > 0.0:
        set_direction(model, d, i, -lam[t1:t1 + 2])


def resolve_liftoff(model, t, x, u, p, d, k: int, flow: int) -> None:
    """After jump k, a contact's liftoff (its normal force through zero; the reset left it open): where its gap
    would then accelerate closed at once, it has not left, and the modes of the contacts touching at rest are
    chosen again as a run's start chooses them (initial_mode: the closed ones push, the open ones leave). A gap on
    zero at zero speed falling would otherwise go unseen by the impact guard (it starts on zero: no crossing)."""
    if not leaves(model, t, x, u, p, d, flow, model.jump_kinds[k][1]):
        initial_mode(model, t, x, u, p, d, flow)


def resolve_stop(model, t, x, u, p, d, k: int, flow: int) -> None:
    """After jump k, a contact's slip ending (its slip speed crossing zero): it sticks, and with it every other
    contact slipping at a slip speed of at most REST_SPEED then (two ends of one rod on the floor stop together),
    their slip speeds (and every active row's velocity residual, a rounding at the located event) set to zero by
    the least M-norm change of x's speeds, in place. Then each of them sticks, or slips the other way
    (cone_state): their modes into d."""
    nq, nv = model.nq, model.nv
    M, _, c, A = terms(model, t, x, u, p, d)
    states, stick, tangents = model.contact_states(d), model.contact_stick_rows, model.tangents
    stopping = [model.jump_kinds[k][1]] + [i for i, s in enumerate(states) if s > STICK
                                           and np.linalg.norm(c[stick[i]:stick[i] + tangents[i]]) <= REST_SPEED]
    for i in stopping:
        states[i] = STICK
    model.set_contact_states(d, states)
    R = model.active_rows(flow, d)
    Minv = np.linalg.inv(M)
    J = A[R]
    x[nq:nq + nv] -= Minv @ J.T @ np.linalg.lstsq(J @ Minv @ J.T, c[R], rcond=None)[0]
    lam = model.module.multipliers(t, x, u, p, d, flow)
    mu = friction_coefficients(model, p)
    for i in stopping:
        states[i] = (spatial_cone_state(model, d, i, lam, mu[i]) if tangents[i] == 2
                     else cone_state(lam[stick[i]], lam[model.contact_rows[i]], mu[i]))
    model.set_contact_states(d, states)


def open_side(model, t, x, u, p, d, g0: dict) -> None:
    """The adaptive methods' start of a segment (as the compiled integrator.advance's): each contact impact guard in
    g0 (jump -> value) whose gap is on zero (|gap| <= ON_ZERO, relative beyond 1) and opening (normal speed above
    REST_SPEED: it left an impact) starts at OPEN_SIDE, so that its coming down within the step is located."""
    opening = [m for m in g0 if model.jump_contact and model.jump_contact[m] >= 0
               and abs(g0[m]) <= ON_ZERO * max(1.0, float(np.max(np.abs(x))))]
    if opening:
        _, _, c, _ = terms(model, t, x, u, p, d)
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

