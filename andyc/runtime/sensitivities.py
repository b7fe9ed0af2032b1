"""Exact sensitivities of a fixed-step run (rk4, lagrange, projection): dx(T)/dx0 and dx(T)/dp, through its jumps.

The run's trajectory is the compiled loop's own (andyc.runtime.fixed_step); beside it this module carries the tangent T = d(x, d, p, t)/dz, z = (x0, d0, p), through the same discrete
map, with the exact first derivatives of the model's functions and the RK4 tangent step, compiled beside them
(<name>_derivatives.py, andyc.codegen.derivatives); the jumps' Jacobians are assembled here, in NumPy.
dx(T)/dp is at fixed x0 and d0. The active constraint rows must be independent (a saddle-point system solves
for the accelerations' derivatives).

Steps. The RK4 step x' = x + h/6 (K1 + 2 K2 + 2 K3 + K4), K_i = f(t + c_i h, x + c_i h K_(i-1)), differentiated
stage by stage (the variational equations integrated by the same stages; forward mode of the step):

    dK_i = F(stage i) [dx + c_i (dh K_(i-1) + h dK_(i-1)); dd; dp; dt + c_i dh],
    dx' = dx + dh (K1 + 2 K2 + 2 K3 + K4)/6 + h/6 (dK1 + 2 dK2 + 2 dK3 + dK4),

F = df/d(x, d, p, t) from M dv/dt = G (+ A^T lam in a constrained flow: the saddle-point system
[[M, -A^T], [A, 0]] differentiated as in andyc.symbolic.linearize). On a whole grid step dh = dt = 0; the
step that follows a jump starts at the jump's time t_e and ends on the grid, so it has dt = dt_e, dh = -dt_e.

Jumps: the saltation matrix of the discrete map. The loop locates the guard's zero on the step as the
step length tau with g(t + tau, Phi(x, tau)) = 0, Phi the RK4 step (andyc_numerics/integrator.py: locate).
With Phi_tau its derivative in tau (the extra tangent column dh = 1 above) and the implicit function theorem,

    dtau = -(g_w dPhi) / (g_x Phi_tau + g_t),                 w = (x, d, p), dPhi the step's tangent at fixed tau,
    dw_e = dPhi + Phi_tau dtau,  dt_e = dt + dtau,
    dw+ = I_w (R_w dw_e + R_t dt_e) + I_t dt_e,                 R the resets, I the impact map (after them)

and the remainder of the step (length t_(i+1) - t_e) is differentiated as above. As h -> 0 (Phi_tau -> f-,
the remainder's dh-column -> f+) this is the classical saltation matrix

    Xi = D_w + (f+ - D_w f- - D_t) g_w / (g_w f- + g_t),      D = I o R, the whole jump map,

(M. A. Aizerman & F. R. Gantmacher, "On the stability of periodic motions", J. Appl. Math. Mech. 22, 1958;
P. C. Mueller, "Calculation of Lyapunov exponents for dynamic systems with discontinuities", Chaos, Solitons &
Fractals 5, 1995; I. A. Hiskens & M. A. Pai, "Trajectory sensitivity analysis of hybrid systems", IEEE Trans.
Circuits and Systems I 47(2), 2000).

The impact I: v+ solves [[M, -J^T], [J, 0]] [v+; L] = [M v; J v - (1 + e) c] (c = J v + b the impact rows'
velocity residual; ANDY eq. 19), differentiated the same way.

Accuracy. This is the exact derivative of the discrete map with tau the exact root of g(Phi(x, tau)); the loop
stops its root finding at a bracket of width event_tol (andyc.Events.tol, 1e-12 s), so the map it computes
differs from that one by about |f| event_tol in x, and its finite differences carry that error divided by
their step; the derivative itself is exact to round-off. When the run ends at a jump (stop_after), the end
time is the jump's: dT/dz (Run.sensitivities["time"]) is dt_e, and dx(T)/dz the state just after it.

The projection method (and quaternions under rk4): each step is the RK4 step followed by the correction map
x -> P(x) of andyc_numerics/dynamics.py project (Braun & Goldfarb, "Simulation of constrained mechanical systems"
Part II: quaternions to unit norm; the position correction, eq. 3; the velocity correction, eq. 4; with
energy_correction the energy correction, eq. 5-6, to E = E0, E0 the energy at the start or just after the latest
jump), so the step's tangent is P'(x) times the RK4 tangent, and the event steps' too (the located state is a
projected step). P' is differentiated in the generated project_tangent (its docstring has the formulas): each
correction solves a saddle-point system [[M, -A^T], [A, 0]], whose derivative is the same system with the
derivatives of M, A and the right-hand side (at the point where each is evaluated) on the right. The lagrange
method is rk4's with independent rows, so its tangent is the rk4 one.

Speed: the tangent of a stretch of steps without a jump is taken in one compiled call (tangent_steps) after the
loop's call that made them, from the stretch's first state (the states are recomputed there: equal to the loop's
to round-off); with directions Z (simulate(sensitivities=Z)), only the k columns T Z are carried, and every
stage's saddle-point system is solved for those k columns.

Not handled (refused with a message by `check`): the baumgarte method (its soft terms are not differentiated),
the adaptive methods, inputs driven by expressions, tables or controllers, guards that read multipliers,
contacts, the energy correction of a model whose elements do work (the balance E - E0 - W: W is not
differentiated), and jumps that happen at once after another (their saltation is degenerate). The user's
functions in <name>_jumps.py are taken to change nothing (they are not differentiated).
"""

from __future__ import annotations

import importlib.util
import sys

import numpy as np

from andyc.errors import SimulationError



def load_derivatives(model):
    """The build's <name>_derivatives.py (andyc.pipeline.build_derivatives), imported; SimulationError when it is
    missing or of another build."""
    path = model.path.with_name(f"{model.name}_derivatives.py")
    key = getattr(model.module, "BUILD_KEY", None)
    if not path.exists():
        raise SimulationError(f"{model.name}: sensitivities need the model's derivatives, {path.name}, beside its "
                              f"build; write them with andyc.build_derivatives(MODEL_FILE, BUILD_DIR) (andyc sim "
                              f"--sensitivities does)")
    name = f"{model.module.__name__}_derivatives"
    module = sys.modules.get(name)
    if module is None or getattr(module, "__file__", None) != str(path):
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        sys.modules[name] = module
    if module.BUILD_KEY != key:
        raise SimulationError(f"{model.name}: {path} is of another build of the model; write it again with "
                              f"andyc.build_derivatives(MODEL_FILE, BUILD_DIR)")
    return module


def check(model, method: str, source, controller, projection=None) -> None:
    """Refuse, with the reason, a run whose sensitivities this module does not compute (see the docstring)."""
    why = None
    m = model.module
    # the slots that can do work in these methods ('baumgarte' holds the soft terms' work: 0 but in that method)
    work = [w for w in getattr(model, "work_names", ()) if w not in ("jumps", "baumgarte")]
    if method not in ("rk4", "lagrange", "projection"):
        what = {"baumgarte": "baumgarte terms are", "moreau": "moreau method's impulses are"}.get(method,
                                                                                                 "adaptive methods are")
        why = (f"method '{method}': sensitivities follow the rk4, lagrange and projection methods only (the "
               f"{what} not differentiated); use --method rk4")
    elif controller is not None or source.drives or model.input_expressions:
        why = "inputs driven by expressions, tables or a controller are not differentiated; hold the inputs"
    elif model.input_names and np.any(np.asarray(m.FLOW_SETS_INPUT)):
        why = "a flow sets inputs (of the parameters), which are not differentiated"
    elif model.contact_names:
        why = "contacts (their impacts are solved as a complementarity problem) are not differentiated"
    elif model.nj and np.any(np.asarray(m.JUMP_MULTIPLIERS)):
        why = "a guard or condition reads multipliers, whose derivatives are not derived"
    elif projection is not None and projection.energy_correction and work:
        why = (f"the energy correction to the balance E - E0 - W: the work of {', '.join(work)} is not "
               f"differentiated (a model that conserves energy is); run without --energy-correction")
    if why is not None:
        raise SimulationError(f"{model.name}: cannot compute sensitivities: {why}")


class Tangent:
    """The tangent T = d(x, d, p, t)/dz of a run, z = (x0, d0, p), carried step by step (see the module docstring).

    method and projection (an andyc.Projection with energy_correction resolved) say which corrections follow each
    RK4 step, as in andyc.runtime.fixed_step (the projection method: the constraint rows and, with
    energy_correction, the energy; quaternions to unit norm with projection.normalize)."""

    def __init__(self, model, derivatives, p, u, method: str = "rk4", projection=None, directions=None):
        self.model, self.D, self.p, self.u = model, derivatives, np.asarray(p, float), np.asarray(u, float)
        nx, nd, npar = model.nx, model.nd, len(p)
        self.nx, self.nd, self.nw = nx, nd, nx + nd + npar + 1
        self.directions = None if directions is None else np.asarray(directions, float)
        if self.directions is None:
            self.ncol = nx + nd + npar
            T = np.zeros((self.nw, self.ncol))
            T[:-1, :] = np.eye(self.ncol)
        else:                       # the derivatives along these directions of z only (columns)
            if self.directions.ndim != 2 or self.directions.shape[0] != nx + nd + npar:
                raise SimulationError(f"{model.name}: sensitivities' directions must be an array of shape "
                                      f"({nx + nd + npar}, k) over z = (x0, d0, p); got {self.directions.shape}")
            self.ncol = self.directions.shape[1]
            T = np.zeros((self.nw, self.ncol))
            T[:-1, :] = self.directions
        self.T = T
        m = model.module
        self.flow_rows = [np.array([r for r in m.FLOW_ROWS[f] if r >= 0], dtype=np.int64) for f in range(model.nf)]
        self.impact_rows = [[int(r) for r in m.IMPACT_ROWS[k] if r >= 0] for k in range(model.nj)]
        self.jumps = 0
        self.before_jump = None     # d(x, d)/dz just before the latest jump (after its time shift, before its map)
        constrain = method == "projection" and model.nc > 0
        self.etol = -1.0
        normalize = bool(model.quaternions)
        if projection is not None:
            normalize = normalize and projection.normalize
            if projection.energy_correction:
                self.etol = float(projection.energy_tol)
        self.quats = np.array(model.quaternions if normalize else [], dtype=np.int64)
        self.project = constrain or self.etol >= 0 or normalize
        nh = [int(n) for n in m.FLOW_NHROWS] if hasattr(m, "FLOW_NHROWS") else [0] * model.nf
        self.project_rows = [rows if constrain else rows[:0] for rows in self.flow_rows]
        self.project_nhrows = [nh[f] if constrain else 0 for f in range(model.nf)]
        self.target, self.dtarget = 0.0, np.zeros(self.ncol)     # the energy correction's E0 and its tangent
        self.target_set = False

    # -- the flow -------------------------------------------------------------------------------------------
    def rates(self, t, x, d, flow):
        """f(t, x) and F = df/dW (nx, NW) in `flow` (the build's compiled `rates`)."""
        return self.D.rates(t, x, self.u, self.p, d, self.flow_rows[flow], self.model.nq)

    @staticmethod
    def _saddle(M, A):
        """[[M, -A^T], [A, 0]]."""
        n, m = M.shape[0], A.shape[0]
        out = np.zeros((n + m, n + m))
        out[:n, :n] = M
        out[:n, n:] = -A.T
        out[n:, :n] = A
        return out

    def step(self, t, h, x, d, flow, T, dh):
        """The step of size h from (t, x), with the method's corrections, and its tangent: T (NW, k) at the start,
        dh (k,) the tangent of h. Returns (x', T')."""
        dtarget = self.dtarget if T.shape[1] == self.ncol else np.append(self.dtarget, 0.0)
        return self.D.step_tangent(t, h, x, self.u, self.p, d, self.flow_rows[flow], T, dh, self.model.nq,
                                   self.project, self.project_rows[flow], self.project_nhrows[flow], self.quats,
                                   self.etol, self.target, dtarget)

    def _energy_target(self, t, x, d):
        """The energy correction's law E = E0 (a model that conserves energy: E0 the energy at the start or just
        after the latest jump, as andyc.runtime.work.JumpWork makes it), with its tangent."""
        if self.etol >= 0 and not self.target_set:
            E, dE = self.D.energy_terms(t, np.asarray(x, float)[:self.nx], self.u, self.p, d)
            self.target, self.dtarget = float(E), dE @ self.T
            self.target_set = True

    # -- the driver's calls ---------------------------------------------------------------------------------
    def advance(self, t0, x0, d0, flow0, i0, t, i, dt, k, x_event):
        """After one call of the compiled loop from (t0, x0, d0) in flow0, on step i0: it reached t on step i (the
        grid point i dt when no jump, k < 0), or jump k >= 0 at t within step i, x_event the state just before
        it. The whole steps are taken again here with their tangent in one compiled call (tangent_steps; the
        states are the loop's to round-off), then the jump's part step and saltation (see the module docstring)."""
        x0 = np.asarray(x0, float)[:self.nx]
        self._energy_target(t0, x0, d0)
        rows, prows, nhr = self.flow_rows[flow0], self.project_rows[flow0], self.project_nhrows[flow0]
        D, nq = self.D, self.model.nq
        xs, T = D.tangent_steps(t0, x0, self.u, self.p, d0, rows, self.T, nq, self.project, prows, nhr, self.quats,
                                self.etol, self.target, self.dtarget, dt, i0, i)
        if k < 0:
            self.T = T
            return
        self.jumps += 1
        ts = t0 if i == i0 else 0.0 + i * dt        # the start of the step the jump cuts
        tau = t - ts
        Te = np.hstack([T, np.zeros((self.nw, 1))])
        xe, Te = self.step(ts, tau, xs, d0, flow0, Te, np.concatenate([np.zeros(self.ncol), [1.0]]))
        x_event = np.asarray(x_event, float)[:self.nx]
        g, dg = self.D.guard_terms(k, t, x_event, self.u, self.p, d0)
        rate = dg @ Te[:, -1]
        if rate == 0.0:
            raise SimulationError(f"{self.model.name}: jump '{self.model.jump_names[k]}' at t = {t:.12g}: the guard "
                                  f"touches zero without crossing it (dg/dt = 0), where the jump time has no "
                                  f"derivative")
        dtau = -(dg @ Te[:, :-1]) / rate
        T = Te[:, :-1] + np.outer(Te[:, -1], dtau)
        self.before_jump = T[:-1 - len(self.p)].copy()     # d(x, d)/dz just before it
        self.T = self.jump(k, t, x_event, d0, T)
        self.target_set = False                           # E0 is the energy just after it

    def jump(self, k, t, x, d, T):
        """The tangent through jump k's resets, then its impact, at (t, x, d) just before it."""
        nx = self.nx
        w = np.concatenate([x, d])
        idx, r, dr = self.D.reset_terms(k, t, x, self.u, self.p, d)
        if len(idx):
            R = np.eye(self.nw)
            R[idx] = dr
            T = R @ T
            w[idx] = r
        x, d = w[:nx], w[nx:]
        rows = self.impact_rows[k]
        if rows:
            T = self._impact(k, t, x, d, rows) @ T
        return T

    def _impact(self, k, t, x, d, rows):
        """The Jacobian (NW, NW) of jump k's impact map at (t, x, d) (see the module docstring)."""
        nq, nv = self.model.nq, self.model.nv
        M, dM, _, _, A, dA, _, _, c, dc, _, _ = self.D.flow_terms(t, x, self.u, self.p, d)
        J, dJ, c, dc = A[rows], dA[rows], c[rows], dc[rows]
        e, de = self.D.restitution_terms(k, t, x, self.u, self.p, d)
        v = x[nq:nq + nv]
        saddle = self._saddle(M, J)
        sol = _solve(saddle, np.concatenate([M @ v, J @ v - (1.0 + e) * c]))
        vp, lam = sol[:nv], sol[nv:]
        dv = np.zeros((nv, self.nw))
        dv[:, nq:nq + nv] = np.eye(nv)
        rhs = np.concatenate([(v - vp) @ dM + np.tensordot(lam, dJ, (0, 0)) + M @ dv,
                              (v - vp) @ dJ + J @ dv - (1.0 + e) * dc - np.outer(c, de)])
        out = np.eye(self.nw)
        out[nq:nq + nv] = _solve(saddle, rhs)[:nv]
        return out

    def result(self) -> dict:
        """The derivatives at the run's end (see _result; with directions, along them)."""
        if self.directions is not None:
            nx, nd, T = self.nx, self.nd, self.T
            out = {"directions": T[:nx].copy(), "time": T[-1].copy(), "discrete": T[nx:nx + nd].copy()}
            if self.before_jump is not None:
                out["before_jump"] = self.before_jump
            return out
        return self._result()

    def _result(self) -> dict:
        """At the run's end: dx/dx0 (nx, nx), dx/dd0 (nx, nd), dx/dp (nx, np); the time's dt/dz (nx + nd + np,)
        and the discrete states' dd/dz (nd, nx + nd + np), z = (x0, d0, p); after a jump, "before_jump":
        d(x, d)/dz of the state just before the latest one (nx + nd, nx + nd + np). With directions Z (nx + nd +
        np, k): "directions" dx/dz Z (nx, k), and "time", "discrete", "before_jump" along them (k columns)."""
        nx, nd, T = self.nx, self.nd, self.T
        out = {"x0": T[:nx, :nx].copy(), "d0": T[:nx, nx:nx + nd].copy(), "p": T[:nx, nx + nd:].copy(),
               "time": T[-1].copy(), "discrete": T[nx:nx + nd].copy()}
        if self.before_jump is not None:
            out["before_jump"] = self.before_jump
        return out


def _solve(a, b):
    """a^-1 b, least squares when a is singular (redundant rows)."""
    try:
        return np.linalg.solve(a, b)
    except np.linalg.LinAlgError:
        return np.linalg.lstsq(a, b, rcond=None)[0]
