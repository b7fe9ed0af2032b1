"""Moreau-Jean time-stepping (`moreau`): contacts resolved in every step by impulses, no event location.

Moreau's theta-scheme as Jean 1999 (The non-smooth contact dynamics method, CMAME 177, 235-257, sec. 4) and
Acary & Brogliato 2008 (Numerical Methods for Nonsmooth Dynamical Systems, Springer, sec. 10.1, the
Moreau-Jean scheme; its equation numbers are not quoted here: the book was not at hand to check them) write it,
at a fixed step h, with theta in [1/2, 1] (TimeStepping.theta, 1/2 by default):

    q_{k+theta} = q_k + theta h v_k
    index set   I = {contact i : g_i(q_k + h v_k / 2) <= 0}           (the gap predicted half a step on, for
                                                                        every theta)
    M (v_{k+1} - v_k) = h G(t_{k+theta}, q_{k+theta}, v_k) + A^T P     (M, G, A at the mid point)
    each contact in I:  0 <= u_n,k+1 + e u_n,k  _|_  P_n >= 0         (Newton's law at velocity level)
                        Coulomb on P_t (planar, or spatial: P_t in the disk): |P_t| <= mu P_n, the slip u_t,k+1 = 0
                        inside the cone, P_t = -mu P_n u_t,k+1 / |u_t,k+1| on its edge
    the model's own (bilateral) rows:  c_{k+1} = A v_{k+1} + b = 0
    q_{k+1} = q_k + h ((1 - theta) v_k + theta v_{k+1})

with G everything but the inertia term (M dv/dt = G), A the rows' Jacobian and u = A v + b their velocity
residuals (a gap's normal speed, a stick row's slip) at the mid point. The index set's test is g_i <= TOUCHING
(1e-12, andyc.runtime.contacts) rather than <= 0: a block sliding on a slope has its gap at a rounding either
side of 0, and one step left out of the set would let it fall for a step (g h^2 into the slope). No contact is
located in time: an impact is an impulse within the step that finds the gap closed, a contact at rest carries
P_n = m g h each step, and the impact times accumulating at a Zeno point need nothing special (the scheme is
O(h) in time across impacts and where the friction's direction turns, second order in smooth motion at
theta = 1/2). The step's contact problem (W = A M^-1 A^T over the rows) is solved by
andyc.runtime.contact_problem (nonlinear Gauss-Seidel, then the active set it finds solved exactly).

Logged per sample: the state, the contact states of the step that ends there as the flow (open, stick, slip +,
slip -: from the impulses and slips of the solution, in andyc.spec.contacts' mixed radix; a contact whose impulse
leaves it lifting off, faster than REST_SPEED, is open: a bounce), and as the multipliers the mean forces P / h
of the steps since the last sample (the impulse of each step is multiplier * dt with every = 1), in the rows and
units the event-driven methods log their multipliers, so that plots and analyses read them alike (NaN: a row in
no step's problem since the last sample). Sample 0 has the ideal multipliers of the initial mode. The `jumps`
work slot takes the work of the contact impulses, P . (A v_{k+1/2} + b) with v_{k+1/2} = (v_k + v_{k+1}) / 2
(the energy an impulse changes in the step), so that E - E0 - W measures the scheme's own energy error.

The bilateral rows, held at velocity level at the mid point, drift; after each step the state is put back on
them (positions, then speeds) by the projection method's Braun & Goldfarb corrections (andyc_numerics'
dynamics.project over the rows of the flow with every contact open: the bilateral ones). Not covered:
nonholonomic or quaternion signals (q moves by v only), hand-written jumps (refused with one line:
check_model). A Python loop calling the compiled leaves: 2e3 to 7e3 steps/s on the 2-core machine (README).
"""

from __future__ import annotations

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import MESSAGES, OK, REST_SPEED, SINGULAR_MASS
from andyc.runtime.contact_problem import BILATERAL, NORMAL, OPEN, PLANAR, SPATIAL, Block, solve
from andyc.runtime.compiled import work
from andyc.runtime.contacts import TOUCHING, friction_coefficients
from andyc.runtime.inputs import inputs_at
from andyc.runtime.status import INTERRUPTED, at, ending, nonfinite
from andyc.runtime.work import with_work

CHUNK = 1000                # steps between looks at interrupts and progress


def check_model(model, theta: float) -> None:
    """SimulationError (one line) unless the moreau method can run `model` with this theta."""
    if not (0.5 <= theta <= 1.0):
        raise SimulationError(f"the moreau method's theta is {theta:g}; use a value in [0.5, 1] (0.5: the "
                              "trapezoidal scheme, second order in smooth motion; 1: backward Euler in the speeds)")
    if not model.contact_names:
        raise SimulationError(f"{model.source}: the moreau method needs contacts (a contacts: section), and this "
                              "model has none; use another --method (rk4, projection, ...)")
    if model.ns:
        raise SimulationError(f"{model.source}: the moreau method moves q by v, and this model has "
                              f"{model.ns} signal(s) (quaternions or nonholonomic); use another --method")
    own = [name for name, (kind, _) in zip(model.jump_names, model.jump_kinds) if not kind]
    if own:
        raise SimulationError(f"{model.source}: jump '{own[0]}' is written by hand, and the moreau method handles "
                              "the contacts' jumps only; use another --method")


class _Stepper:
    """The rows, coefficients and scratch of one run's steps."""

    def __init__(self, model, p, theta: float):
        self.model, self.p, self.theta = model, p, theta
        self.nq, self.nv = model.nq, model.nv
        self.rows = list(model.contact_rows)
        self.stick = list(model.contact_stick_rows) or [-1] * len(self.rows)
        own = set(self.rows) | {r for r in self.stick if r >= 0}
        self.open_flow = model.contact_flow([0] * len(self.rows))
        self.bilateral = [r for r in model.active_rows(self.open_flow) if r not in own]
        self.work = work(model)
        self.e = np.zeros(len(self.rows))
        for k, value in enumerate(model.module.restitutions(p)):
            if model.jump_contact[k] >= 0 and model.jump_kinds[k][0] == "impact":
                self.e[model.jump_contact[k]] = value
        self.mu = friction_coefficients(model, p)
        self.tangents = model.tangents
        self.numerics = model.numerics.api      # (its _dynamics: M and G from one evaluation of the leaf, where the
        #                                         module's mass_matrix and generalized_force would make two)
        self.M = np.zeros((self.nv, self.nv))
        self.G = np.zeros(model.module.SIZES["ng"])
        self.phi, self.c = np.empty(model.nh), np.empty(model.nc)
        self.A, self.kappa = np.empty((model.nc, self.nv)), np.empty(model.nc)
        self.guess = None           # the last step's blocks and states (a warm start)
        self.nu = len(model.input_names)
        self.no_inputs = np.zeros(0)

    def constraints(self, t, x, u, d):
        self.model.module.constraints(t, x, u, self.p, d, self.phi, self.c, self.A, self.kappa)

    def step(self, t, h, x, source, d, flow, stats):
        """x (the state, then the work) from t to t + h, in place; returns (the flow of the contact states, the
        impulses (nc,) over the rows, NaN for those not in the step's problem)."""
        model, nq, nv, theta, p = self.model, self.nq, self.nv, self.theta, self.p
        nx = model.nx
        state = x[:nx]
        v = state[nq:nq + nv].copy()
        mid = state.copy()
        mid[:nq] += theta * h * v[:nq]
        tm = t + theta * h
        u = inputs_at(model, source, tm, mid, p, d, flow) if self.nu else self.no_inputs
        if theta == 0.5:                            # (the predicted point is the mid point)
            self.constraints(tm, mid, u, d)
        else:
            predicted = state.copy()
            predicted[:nq] += 0.5 * h * v[:nq]
            self.constraints(t + 0.5 * h, predicted, u, d)
        touching = [i for i, r in enumerate(self.rows) if self.phi[r] <= TOUCHING]
        self.numerics._dynamics(model.ref, tm, mid, u, p, d, self.M, self.G)
        try:            # (M^-1 from its Cholesky factor: also the test that M is positive definite)
            Linv = np.linalg.inv(np.linalg.cholesky(self.M))
        except np.linalg.LinAlgError:
            raise FloatingPointError(MESSAGES[SINGULAR_MASS]) from None
        Minv = Linv.T @ Linv
        v_free = v + h * (Minv @ self.G[:nv])
        impulses = np.full(model.nc, np.nan)        # (NaN: a row not in the step's problem, as an inactive row's)
        states = [OPEN] * len(self.rows)
        v_new = v_free
        if touching or self.bilateral:
            if theta != 0.5:
                self.constraints(tm, mid, u, d)
            R, blocks = list(self.bilateral), [Block(BILATERAL, (k,)) for k in range(len(self.bilateral))]
            for i in touching:
                if self.tangents[i] == 2:
                    blocks.append(Block(SPATIAL, (len(R), len(R) + 1, len(R) + 2), float(self.mu[i])))
                    R += [self.rows[i], self.stick[i], self.stick[i] + 1]
                elif self.stick[i] >= 0:
                    blocks.append(Block(PLANAR, (len(R), len(R) + 1), float(self.mu[i])))
                    R += [self.rows[i], self.stick[i]]
                else:
                    blocks.append(Block(NORMAL, (len(R),)))
                    R.append(self.rows[i])
            A = self.A[R]
            b = self.c[R] - A @ v
            w0 = A @ v_free + b
            for blk, i in zip(blocks[len(self.bilateral):], touching):
                w0[blk.rows[0]] += self.e[i] * (A[blk.rows[0]] @ v + b[blk.rows[0]])
            X = Minv @ A.T
            key = tuple(R)
            guess = self.guess[1] if self.guess is not None and self.guess[0] == key else None
            sol = solve(A @ X, w0, blocks, guess)
            self.guess = (key, sol)
            stats["contact_sweeps"] += sol.sweeps
            stats["unverified_steps"] += not sol.verified
            v_new = v_free + X @ sol.P
            impulses[R] = sol.P
            after = A @ v_new + b
            for j, i in enumerate(touching):       # (a contact its impulse leaves lifting off is open after the step)
                blk = blocks[len(self.bilateral) + j]
                states[i] = sol.states[len(self.bilateral) + j] if after[blk.rows[0]] <= REST_SPEED else OPEN
            v_half = 0.5 * (v + v_new)
            if model.nj:                            # the `jumps` slot, last: the impulses' work
                x[nx + model.nw - 1] += float(sol.P @ (A @ v_half + b))
        state[:nq] += h * ((1.0 - theta) * v[:nq] + theta * v_new[:nq])
        state[nq:nq + nv] = v_new
        if self.bilateral:          # (held at velocity level, the rows drift: back onto them, positions and speeds)
            u_end = inputs_at(model, source, t + h, state, p, d, flow) if self.nu else self.no_inputs
            if model.numerics.dynamics.project(model.ref, self.work.ref, t + h, x, u_end, p, d, self.open_flow, True,
                                               0.0, -1.0) != OK:
                raise FloatingPointError(MESSAGES[SINGULAR_MASS])
        return model.contact_flow(states), impulses


def run_moreau(model, x, source, p, d, flow, t_end, dt, every, theta, bar, interrupts, run_of):
    """Step from (0, x) to t_end in steps dt, logging every `every`-th. Returns (log, status, stats, forces): the
    integrator's Log arrays (t, x and the work, u, flow, d) and the mean forces (N, nc) of each sample."""
    n_steps = int(round(t_end / dt))
    if abs(n_steps * dt - t_end) > 1e-9 * max(1.0, t_end):
        raise SimulationError(f"t_end = {t_end} is not a whole number of steps dt = {dt}; "
                              f"use t_end = {n_steps * dt:g} or another dt")
    stepper = _Stepper(model, p, theta)
    x = with_work(model, x)
    nu, rows = len(model.input_names), n_steps // every + 2
    out_t, out_x, out_u = np.empty(rows), np.empty((rows, x.shape[0])), np.empty((rows, nu))
    out_f, out_d, forces = np.empty(rows, dtype=np.int64), np.empty((rows, model.nd)), np.full((rows, model.nc), np.nan)
    out_t[0], out_x[0], out_f[0], out_d[0] = 0.0, x, flow, d
    out_u[0] = inputs_at(model, source, 0.0, x[:model.nx], p, d, flow)
    stats = {"steps": 0, "rhs_evaluations": 0, "contact_sweeps": 0, "unverified_steps": 0}
    row, message, t = 1, None, 0.0
    total, seen = np.zeros(model.nc), np.zeros(model.nc, dtype=bool)

    def partial():
        return run_of(_log(out_t, out_x, out_u, out_f, out_d, row), INTERRUPTED, dict(stats), forces[:row].copy())

    interrupts.partial = partial
    for k in range(n_steps):
        if k % CHUNK == 0:
            message = interrupts.reason()
            if message is not None:
                message += at(t)
                break
            bar(t)
        try:
            flow, impulses = stepper.step(t, dt, x, source, d, flow, stats)
        except FloatingPointError as exc:
            message = f"stopped: {exc}" + at(t)
            break
        t = (k + 1) * dt
        stats["steps"] = stats["rhs_evaluations"] = k + 1        # (one evaluation of M and G a step)
        active = ~np.isnan(impulses)
        total[active] += impulses[active]
        seen |= active
        if not np.all(np.isfinite(x)):
            message = nonfinite(t)
            break
        if (k + 1) % every == 0 or k + 1 == n_steps:
            out_t[row], out_x[row], out_f[row], out_d[row] = t, x, flow, d
            if nu:
                out_u[row] = inputs_at(model, source, t, x[:model.nx], p, d, flow)
            forces[row] = np.where(seen, total, np.nan) / (dt * (every if (k + 1) % every == 0 else (k + 1) % every))
            total[:], seen[:] = 0.0, False
            row += 1
    if message is not None and out_t[row - 1] != t:
        out_t[row], out_x[row], out_f[row], out_d[row], out_u[row] = t, x, flow, d, np.nan
        row += 1
    bar(t)
    return _log(out_t, out_x, out_u, out_f, out_d, row), ending(message, row, _NoJumps), stats, forces[:row].copy()


class _NoJumps:
    finished = False            # (status.ending reads it: no stop_after ends a moreau run)


def _log(out_t, out_x, out_u, out_f, out_d, n):
    return tuple(a[:n].copy() for a in (out_t, out_x, out_u, out_f, out_d))
