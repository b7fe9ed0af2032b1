"""The generated module's functions for Python callers: plain arguments, new arrays, the model's defaults.

    import <name> as model          # its folder on sys.path; andyc need not be installed
    from scipy.integrate import solve_ivp
    solve_ivp(model.rhs, (0, 10), model.initial_state(), args=(model.INPUT_DEFAULTS, model.PARAMETER_DEFAULTS))

Each is a thin wrapper over a compiled function of this package and the module's Model. The inputs a
model drives by an expression (its INPUT_EXPRESSIONS) are evaluated at (t, x) by every function that
takes a flow; the others are taken from u. One Functions object reuses one Work: it is not meant to be
called from several threads at once.
"""

import numpy as np

from .compiler import jit
from .dynamics import enabled_value, guard_value, multipliers, rhs_mode_into
from .inputs import callbacks
from .integrator import crosses, update_inputs  # noqa: F401  (crosses: for the module's users)
from .model import Work, call
from .status import IDEAL, MESSAGES, OK


@jit
def _dynamics(model, t, x, u, p, d, M, G):
    call(model.dynamics, (t, x, u, p, d, M, G))


@jit
def _energy(model, t, x, u, p, d):
    return call(model.energy, (t, x, u, p, d))


@jit
def _power(model, t, x, u, p, d):
    return call(model.power, (t, x, u, p, d))


@jit
def _frame_poses(model, t, x, u, p, d, out):
    call(model.frame_poses, (t, x, u, p, d, out))


@jit
def _constraints(model, t, x, u, p, d, S, phi, c, A, kappa):
    call(model.constraints_into, (t, x, u, p, d, S))
    for i in range(model.nc):
        if i < model.nh:
            phi[i] = S[model.s_phi, i]
        c[i] = S[model.s_cv, i]
        kappa[i] = S[model.s_kappa, i]
        for j in range(model.nv):
            A[i, j] = S[model.s_a + i, j]


@jit
def _signal_rates(model, t, x, u, p, d, xdot):
    call(model.signal_rates, (t, x, u, p, d, xdot))


@jit
def _guard(model, w, k, t, x, u, p, d, flow):
    return guard_value(model, w, k, t, x, u, p, d, flow)


@jit
def _enabled(model, w, k, t, x, u, p, d, flow):
    return enabled_value(model, w, k, t, x, u, p, d, flow)


@jit
def _jump_source(model, k):
    return model.jump_source[k], model.jump_mode_state[k], model.jump_mode_mask[k]


@jit
def _restitutions(model, p, S, out):
    call(model.restitution, (p, S))
    for k in range(out.shape[0]):
        out[k] = S[model.s_e, k]


@jit
def _flow_inputs(model, p, U):
    call(model.flow_inputs, (p, U))


@jit
def _closed_form(model, t, u, p, x):
    call(model.closed_form, (t, u, p, x))


@jit
def _energy_law(model, k, t, x, u, p, d, grad):
    return call(model.energy_law, (k, t, x, u, p, d, grad))


def _vector(x) -> np.ndarray:
    return np.ascontiguousarray(x, dtype=np.float64)


class Functions:
    """The Python functions of a generated module over its compiled `model` (see the module docstring).

    sizes: the model's sizes (model.SIZES, lower case); model_inputs: the model's input callback, or None
    when it drives no input; parameters, inputs, discrete, flow: the defaults of p, u, d and the flow.
    """

    def __init__(self, model, sizes: dict, model_inputs, parameters, inputs, discrete, flow):
        self.model, self.sizes, self.model_inputs = model, sizes, model_inputs
        self.defaults = (inputs, parameters, discrete, flow)
        self.work = Work(sizes)

    def _args(self, u, p, d, flow):
        du, dp, dd, dflow = self.defaults
        return (dp if p is None else _vector(p), _vector(du if u is None else u),
                dd if d is None else _vector(d), dflow if flow is None else int(flow))

    def driven(self, t, x, u=None, p=None, d=None, flow=None):
        """u with the inputs the model drives by an expression set at (t, x), a new array."""
        p, u, d, flow = self._args(u, p, d, flow)
        u = u.copy()
        if self.model_inputs is not None:
            data = np.tile(u, self.sizes["nf"])        # the callback reads the flow's held values from here
            update_inputs(callbacks(self.model_inputs), float(t), _vector(x), p, d, flow, u, data)
        return u

    def mass_matrix(self, t, x, u=None, p=None, d=None):
        """M(q), (NV, NV)."""
        p, u, d, _ = self._args(u, p, d, None)
        nv = self.sizes["nv"]
        M, G = np.zeros((nv, nv)), np.zeros(self.sizes["ng"])     # (the leaf writes the elements' powers after G)
        _dynamics(self.model, float(t), _vector(x), u, p, d, M, G)
        return M

    def generalized_force(self, t, x, u=None, p=None, d=None, flow=None):
        """G(t, q, v), (NV,): everything but the inertia term, M dv/dt = G."""
        u = self.driven(t, x, u, p, d, flow)
        p, u, d, _ = self._args(u, p, d, flow)
        nv = self.sizes["nv"]
        M, G = np.zeros((nv, nv)), np.zeros(self.sizes["ng"])     # (the leaf writes the elements' powers after G)
        _dynamics(self.model, float(t), _vector(x), u, p, d, M, G)
        return G[:nv].copy()

    def energy_law(self, t, x, u=None, p=None, d=None, flow=None):
        """(Phi_e, dPhi_e/dv (NV,)) of the energy law `flow` declares (energy_law:), or (NaN, zeros) where the
        flow keeps the built-in law E - E0 - W."""
        x = _vector(x)
        u = self.driven(t, x, u, p, d, flow)
        p, u, d, flow = self._args(u, p, d, flow)
        grad = np.zeros(self.sizes["nv"])
        return _energy_law(self.model, flow, float(t), x, u, p, d, grad), grad

    def rhs(self, t, x, u=None, p=None, d=None, flow=None):
        """dx/dt in `flow`, for scipy.integrate.solve_ivp, with the ideal constraint forces of the flow's rows."""
        x = _vector(x)
        u = self.driven(t, x, u, p, d, flow)
        p, u, d, flow = self._args(u, p, d, flow)
        xdot = np.empty(self.sizes["nx"])
        status = rhs_mode_into(self.model, self.work.ref, float(t), x, u, p, d, flow, xdot, IDEAL)
        if status != OK:
            raise FloatingPointError(f"{MESSAGES[status]} at t = {t}")
        return xdot

    def multipliers(self, t, x, u=None, p=None, d=None, flow=None):
        """The multipliers (NC,) of the ideal constraint force A^T lam in `flow`; NaN for rows not active."""
        x = _vector(x)
        u = self.driven(t, x, u, p, d, flow)
        p, u, d, flow = self._args(u, p, d, flow)
        lam = np.empty(self.sizes["nc"])
        if multipliers(self.model, self.work.ref, float(t), x, u, p, d, flow, lam) != OK:
            raise FloatingPointError(f"the mass matrix is not positive definite at t = {t}")
        return lam

    def energy(self, t, x, u=None, p=None, d=None):
        """Total mechanical energy: kinetic + gravity + springs + potentials."""
        p, u, d, _ = self._args(u, p, d, None)
        return _energy(self.model, float(t), _vector(x), u, p, d)

    def power(self, t, x, u=None, p=None, d=None):
        """Power of the non-conservative elements (forces, torques, dampers)."""
        p, u, d, _ = self._args(u, p, d, None)
        return _power(self.model, float(t), _vector(x), u, p, d)

    def frame_poses(self, t, x, u=None, p=None, d=None):
        """The pose of each of FRAMES in world, (len(FRAMES), 12): its origin, then its rotation matrix (own
        axes -> world) row by row."""
        p, u, d, _ = self._args(u, p, d, None)
        out = np.zeros((self.sizes["frames"], 12))
        _frame_poses(self.model, float(t), _vector(x), u, p, d, out)
        return out

    def frame_positions(self, t, x, u=None, p=None, d=None, out=None):
        """Origins of FRAMES in world coordinates, (len(FRAMES), 3) (into `out` when given)."""
        poses = self.frame_poses(t, x, u, p, d)
        out = np.zeros((len(poses), 3)) if out is None else out
        out[:] = poses[:, :3]
        return out

    def frame_rotations(self, t, x, u=None, p=None, d=None):
        """Rotation matrix of each of FRAMES, own axes -> world, (len(FRAMES), 3, 3)."""
        return self.frame_poses(t, x, u, p, d)[:, 3:].reshape(-1, 3, 3)

    def constraints(self, t, x, u, p, d, phi, c, A, kappa):
        """Constraint residuals phi (NH,), velocity residuals c = A v + b (NC,), their Jacobian A (NC, NV) and
        kappa (NC,), with dc/dt = A dv/dt + kappa (ANDY eq. 11), into the arrays given."""
        _constraints(self.model, float(t), _vector(x), _vector(u), _vector(p), _vector(d), self.work.S, phi, c, A,
                     kappa)

    def signal_rates(self, t, x, u, p, d, xdot):
        """Rates of the nonholonomic signals (ANDY eq. 4) into xdot[NQ + NV:]."""
        _signal_rates(self.model, float(t), _vector(x), _vector(u), _vector(p), _vector(d), xdot)

    def guard(self, k, t, x, u=None, p=None, d=None, flow=None):
        """The guard of jump k: it happens where this crosses zero in JUMP_DIRECTION[k] (with the multipliers of
        `flow` and d at (t, x), when it reads them; default its source flow, the initial flow for a contact's jump,
        which leaves every flow, and the default d with the contact in the first mode the jump leaves)."""
        p, u, d, flow = self._jump_args(k, u, p, d, flow)
        return _guard(self.model, self.work.ref, int(k), float(t), _vector(x), u, p, d, flow)

    def enabled(self, k, t, x, u=None, p=None, d=None, flow=None):
        """>= 0 where jump k may happen (its enabling conditions)."""
        p, u, d, flow = self._jump_args(k, u, p, d, flow)
        return _enabled(self.model, self.work.ref, int(k), float(t), _vector(x), u, p, d, flow)

    def _jump_args(self, k, u, p, d, flow):
        """The arguments of jump k's guard: as given, else its source flow (the default for a contact's jump, which
        leaves every flow), and for a contact's jump the default d with its contact in the first mode it leaves."""
        source, state, mask = (int(v) for v in _jump_source(self.model, int(k)))
        given = d is not None
        p, u, d, flow = self._args(u, p, d, flow if flow is not None else source if source >= 0 else None)
        if not given and state >= 0:
            d = d.copy()
            d[state] = float((mask & -mask).bit_length() - 1)
        return p, u, d, flow

    def restitutions(self, p=None):
        """The coefficient of restitution of each jump's impact (NJ,), then each joint friction's force, at
        parameters p."""
        p, _, _, _ = self._args(None, p, None, None)
        out = np.zeros(self.sizes["ne"])
        _restitutions(self.model, p, self.work.S, out)
        return out

    def flow_inputs(self, p, U):
        """Input values a flow sets, into U (flows, inputs); other entries are left as they are."""
        _flow_inputs(self.model, _vector(p), U)

    def closed_form(self, t, u=None, p=None):
        """x(t), the exact solution the model declares (closed_form:), at held inputs u and parameters p."""
        p, u, _, _ = self._args(u, p, None, None)
        x = np.empty(self.sizes["nx"])
        _closed_form(self.model, float(t), u, p, x)
        return x
