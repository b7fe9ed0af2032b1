"""Which contacts are closed, sticking or slipping at an instant: a run's start, and after an impact or a stop.

Each contact's mode is a discrete state (andyc.spec.contacts: 0 open, 1 closed or sticking, 2 / 3 slipping
forwards / backwards; spatial friction: 2 slipping). initial_mode picks the modes a run starts in: the contacts
touching at rest, less those that would pull, each with friction sticking if it does not slip and the friction
it needs is inside the cone, else slipping (settle does the same after an impact, from the contacts it leaves
closed). Should a contact so dropped then close again at once (its gap's acceleration negative in that mode: two
stops coupled through the bodies, a walker's two knees, where dropping the most negative is the wrong one), the
modes are enumerated instead, the fewest dropped first, for the first in which the closed contacts push and the
dropped ones open (_complementary): the acceleration-level complementarity problem of Pfeiffer & Glocker (1996,
ch. 6). That enumeration is for a few contacts (at most MAX_ENUMERATED at rest); beyond, the first answer stands.
"""

from __future__ import annotations

from itertools import combinations

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import MESSAGES, PAINLEVE, REST_SPEED, SLIP_TINY

TOUCHING = 1e-12        # a contact whose gap is at most this at the start, at rest, starts closed
STICK, SLIP_POS, SLIP_NEG = 1, 2, 3     # a contact's modes beside open (0), as andyc.spec.contacts
SLIP = 2                                # spatial friction: its one slipping mode
MAX_ENUMERATED = 8      # contacts at rest whose drop sets _settle enumerates (2^n trials) when the first fails
LEAVE_TOL = 1e-6        # a contact just lifted off whose gap accelerates closed by more than this (relative) falls back
PULL_TOL = 1e-12        # a closed contact's normal force below minus this (of the largest, beyond 1) pulls


def friction_coefficients(model, p) -> np.ndarray:
    """mu of each contact (NaN without friction): the coefficient of its slip's end jumps (andyc.spec.contacts)."""
    mu = np.full(len(model.contact_names), np.nan)
    if any(r >= 0 for r in model.contact_stick_rows):
        values = model.module.restitutions(p)
        for k, (kind, i) in enumerate(model.jump_kinds):
            if kind == "stop":
                mu[i] = values[k]
    return mu


def terms(model, t, x, u, p, d):
    """(M, phi, c, A) at (t, x): the mass matrix and every constraint row's residuals and Jacobian."""
    M = model.module.mass_matrix(t, x, u, p, d)
    phi, c, A = np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, model.nv))
    model.module.constraints(t, x, u, p, d, phi, c, A, np.empty(model.nc))
    return M, phi, c, A


def with_states(model, d, states) -> np.ndarray:
    """A copy of d with the contacts' modes `states` (a list of every contact's, or {contact: mode})."""
    out = np.array(d, dtype=np.float64)
    items = states.items() if isinstance(states, dict) else enumerate(states)
    for i, s in items:
        out[model.contact_modes[i]] = float(s)
    return out


def slip_state(slip: float) -> int:
    """A closing contact with friction: sticking at (almost) no slip, else slipping its way."""
    return STICK if abs(slip) <= REST_SPEED else SLIP_POS if slip > 0 else SLIP_NEG


def cone_state(lam_t: float, lam_n: float, mu: float) -> int:
    """Where a contact that would stick goes: it sticks if the friction it needs is inside the cone; past its
    edge it slips the way the other forces push it (lam_t > mu lam_n: backwards)."""
    tol = 1e-12 * max(1.0, abs(lam_n))
    return SLIP_NEG if lam_t > mu * lam_n + tol else SLIP_POS if lam_t < -mu * lam_n - tol else STICK


def direction_index(model, i: int) -> int:
    """The index in d of contact i's slip direction (spatial friction: two discrete states, then `held`)."""
    return model.discrete_names.index(f"{model.contact_names[i]}_slip_dir_1")


def set_direction(model, d, i: int, direction) -> int:
    """Contact i (spatial friction) slips along `direction` (made unit) from here: into its discrete states
    (numerics.slipping.slip_unit reads them while the slip is slower than SLIP_TINY). Returns SLIP."""
    k = direction_index(model, i)
    d[k:k + 2] = np.asarray(direction, dtype=float) / np.hypot(*direction)
    d[k + 2] = 0.0          # (not held: the integrator decides at its next step)
    return SLIP


def stuck(model, d, i: int) -> int:
    """Contact i (spatial friction) sticks: no step holds its slip's direction (its discrete state to 0); STICK."""
    d[direction_index(model, i) + 2] = 0.0
    return STICK


def spatial_cone_state(model, d, i: int, lam, mu: float) -> int:
    """Where contact i (spatial friction) that would stick goes: it sticks if the friction it needs is inside the
    cone, |lam_t| <= mu lam_n; past its edge it slips against that friction, along -lam_t / |lam_t|."""
    t1 = model.contact_stick_rows[i]
    lam_t, lam_n = lam[t1:t1 + 2], lam[model.contact_rows[i]]
    if np.hypot(*lam_t) <= mu * lam_n + 1e-12 * max(1.0, abs(lam_n)):
        return stuck(model, d, i)
    return set_direction(model, d, i, -lam_t)


def initial_mode(model, t, x, u, p, d, flow: int) -> None:
    """The contacts' modes a run starts in, into d (module docstring): those touching (|gap| <= TOUCHING) at rest
    (|normal speed| <= REST_SPEED), less those whose normal force is negative, the most negative first, one at a
    time (dropping one changes the others' forces); each with friction slipping its way if its slip speed exceeds
    REST_SPEED, else sticking if the friction it needs is inside the cone (else slipping, cone_state)."""
    _, phi, c, _ = terms(model, t, x, u, p, d)
    rows, stick = model.contact_rows, list(model.contact_stick_rows)
    states = [int(abs(phi[r]) <= TOUCHING and abs(c[r]) <= REST_SPEED) for r in rows]
    for i, s in enumerate(states):
        if s and model.tangents[i] == 2:
            slip = c[stick[i]:stick[i] + 2]
            states[i] = STICK if np.hypot(*slip) <= REST_SPEED else set_direction(model, d, i, slip)
        elif s and stick[i] >= 0:
            states[i] = slip_state(c[stick[i]])
    settle(model, t, x, u, p, d, flow, states)


def settle(model, t, x, u, p, d, flow: int, states: list) -> None:
    """Into d: the contacts closed in `states` (at rest) less those that would pull (initial_mode's rule)."""
    at_rest = [i for i, s in enumerate(states) if s]
    mode = _drop_pulling(model, t, x, u, p, d, flow, list(states))
    if _complementary(model, t, x, u, p, d, flow, mode, [i for i in at_rest if not mode[i]]) \
            or len(at_rest) > MAX_ENUMERATED:
        model.set_contact_states(d, mode)
        return
    for n in range(1, len(at_rest) + 1):
        for dropped in combinations(at_rest, n):
            trial = [0 if i in dropped else s for i, s in enumerate(states)]
            if _complementary(model, t, x, u, p, d, flow, trial, dropped, pushing=True):
                model.set_contact_states(d, _drop_pulling(model, t, x, u, p, d, flow, trial))
                return
    model.set_contact_states(d, mode)


def leaves(model, t, x, u, p, d, flow: int, i: int) -> bool:
    """Whether contact i, open in d at its liftoff (its normal force through zero), leaves: its gap does not
    accelerate closed in the modes of d. (Where its friction held a force as its normal force fell, the open
    contact can fall back: the modes of that instant are then chosen again, as initial_mode chooses.) The
    liftoff is located to the event tolerance, where the normal force is a rounding from zero either way, and so
    is the open gap's acceleration: LEAVE_TOL of the largest term is taken for zero."""
    return _complementary(model, t, x, u, p, d, flow, list(model.contact_states(d)), [i], rel=LEAVE_TOL)


def _drop_pulling(model, t, x, u, p, d, flow: int, states: list) -> list:
    """The contacts' modes less those whose normal force is negative, the most negative first, one at a time;
    each sticking one then sticking or slipping by its cone (initial_mode)."""
    rows, tangents = model.contact_rows, model.tangents
    stick = list(model.contact_stick_rows)
    mu = friction_coefficients(model, p)
    while any(states):
        lam = model.module.multipliers(t, x, u, p, with_states(model, d, states), flow)
        force, worst = min((lam[r], i) for i, r in enumerate(rows) if states[i])
        # (a force a rounding below zero is zero: two balls leaving together at no force stay closed, to part
        # where their force falls through zero, not to strike again and again a gap a rounding from zero)
        if force < -PULL_TOL * max(1.0, max(abs(lam[r]) for i, r in enumerate(rows) if states[i])):
            if states[worst] > STICK:
                _painleve(model, t, x, u, p, d, worst, states[worst], mu[worst])
            states[worst] = 0
            continue
        cone = [(spatial_cone_state(model, d, i, lam, mu[i]) if tangents[i] == 2 else
                 cone_state(lam[stick[i]], lam[rows[i]], mu[i])) if s == STICK and stick[i] >= 0 else s
                for i, s in enumerate(states)]
        if cone == states:
            break
        states = cone
    return states


def _complementary(model, t, x, u, p, d, flow: int, states: list, dropped, pushing: bool = False,
                   rel: float = 1e-10) -> bool:
    """In the modes `states`, no dropped contact's gap accelerates closed (A_i dv/dt + kappa_i >= -tol) and, with
    `pushing`, every closed contact pushes (its normal force >= -tol); tol is `rel` of the largest term."""
    trial = with_states(model, d, states)
    nq, nv = model.nq, model.nv
    phi, c, A, kappa = np.empty(model.nh), np.empty(model.nc), np.empty((model.nc, nv)), np.empty(model.nc)
    model.module.constraints(t, x, u, p, trial, phi, c, A, kappa)
    try:
        vdot = model.module.rhs(t, x, u, p, trial, flow)[nq:nq + nv]
        lam = model.module.multipliers(t, x, u, p, trial, flow)
    except FloatingPointError:
        return False
    rows = model.contact_rows
    accel = [A[rows[i]] @ vdot + kappa[rows[i]] for i in dropped]
    scale = rel * max([1.0, float(np.max(np.abs(vdot)))] + [abs(a) for a in accel])
    if any(a < -scale for a in accel):
        return False
    return not pushing or all(lam[r] >= -1e-10 * max(1.0, float(np.max(np.abs(lam)))) for i, r in enumerate(rows)
                              if states[i])


def _painleve(model, t, x, u, p, d, i: int, state: int, mu: float) -> None:
    """SimulationError if contact i, slipping (state), has A_n M^-1 (A_n - sigma mu J_t)^T <= 0: its negative
    normal force is then no reason to open it (open, it would close faster: Painleve's paradox, no consistent
    mode; numerics.slipping.solve_slipping refuses the same during a run)."""
    M, _, c, A = terms(model, t, x, u, p, d)
    normal, tangent = A[model.contact_rows[i]], A[model.contact_stick_rows[i]]
    sigma = 1.0 if state == SLIP_POS else -1.0
    if model.tangents[i] == 2:          # along the slip's direction (as numerics.slipping.slip_unit)
        t1, k = model.contact_stick_rows[i], direction_index(model, i)
        slip = c[t1:t1 + 2]
        direction = slip / np.hypot(*slip) if np.hypot(*slip) > SLIP_TINY else d[k:k + 2]
        tangent, sigma = direction @ A[t1:t1 + 2], 1.0
    if not normal @ np.linalg.solve(M, normal - sigma * mu * tangent) > 0.0:
        when = "at the start" if t == 0.0 else f"coming to rest at t = {t:.12g} s"
        raise SimulationError(f"contact '{model.contact_names[i]}' {when}: {MESSAGES[PAINLEVE]}")
