"""Linearization of a flow's equations of motion from exact derivatives.

With x = (q, v) and M(q) dv/dt = G(t, q, v, u) (eq. 8), a = M^-1 G:

    d/dt dx = A dx + B du,   A = [[0, I], [da/dq, da/dv]],   B = [[0], [da/du]],
    da/dz = M^-1 (dG/dz - (dM/dz) a)   for z in q, v, u.

The derivatives are exact (no finite differences): the SymbolicModel is a
chain of assignments `s = f(earlier symbols)`, so each intermediate symbol's
value and gradient are carried forward in order (forward-mode automatic
differentiation), every partial df/ds coming from SymPy's `diff` of that one
small expression, evaluated at the point in double precision.

A flow with active constraint rows (c = A v + b, the first of them
holonomic, A_h = dphi/dq; ANDY eq. 10-12; rows nonlinear in v are refused) is linearized at rest on its
constraint manifold, in the null-space form. The acceleration a and the
multipliers lam solve M a = G + A^T lam, A a = -kappa, so their derivatives
solve the same saddle-point matrix:

    [[M, -A^T], [A, 0]] [da; dlam] = [dG/dz - (dM/dz) a + (dA/dz)^T lam;
                                      -(dA/dz) a - dkappa/dz]

(least squares, so redundant rows are allowed). With N_q and N_v orthonormal
bases of null(A_h) and null(A) at the point, dq = N_q z and dv = N_v w, and

    d/dt (z, w) = [[0, N_q^T N_v], [N_v^T da/dq N_q, N_v^T da/dv N_v]] (z, w)
                  + [[0], [N_v^T da/du]] du.

At rest (v = 0, kappa = 0) A a = 0 for every q on the manifold, so A da = 0
and the projection on N_v loses nothing: the eigenvalues are the mechanism's.

A constrained flow that moves is linearized about a steady motion: constant
speeds (dv/dt = 0 at the point), every coordinate that moves cyclic (it
appears in none of the flow's M, G and rows, so its value does not matter:
the wheel's position, its spin angle). The cyclic coordinates leave the state
(the selection E keeps the others), and since c = A(q) v + b changes with q
when v != 0, a change dq = E N_q z of the coordinates takes the speeds off
the manifold unless they change too. The chart of the manifold about the
point is therefore

    dq = E N_q z,   dv = N_v w + P z,   P = -A^+ (dc/dq) E N_q,

(A^+ the pseudo-inverse: the least change of v that keeps c = 0), and with
dq/dt = v and N_v^T P = 0 (the range of A^+ is orthogonal to null(A)):

    dz/dt = (E N_q)^T (N_v w + P z),
    dw/dt = N_v^T (da/dq E N_q z + da/dv (N_v w + P z)) + N_v^T da/du du.

At rest P = 0 and E = I, which is the form above. This is the linearization
about a relative equilibrium in the sense of Routh's steady motions (Routh,
"Advanced Rigid Dynamics", 1905, ch. V; Neimark & Fufaev, "Dynamics of
Nonholonomic Systems", 1972, ch. III, for nonholonomic ones).

An equilibrium (dv/dt = 0 at v = 0) of an unconstrained flow is found by
Newton's method on G(t, q, 0, u) = 0 with this exact Jacobian dG/dq
(scipy.optimize.root, 'hybr').
"""

from __future__ import annotations

from dataclasses import dataclass

import math

import numpy as np
import sympy as sp

from andyc.symbolic.model import SymbolicModel


class LinearizeError(ValueError):
    """A model or a point that this linearization does not handle; the message says why and what to do."""


@dataclass
class Linearization:
    """dx' = A dx + B du about (x, u) at time t, in `flow`; states and inputs named as in the generated module.

    For a constrained flow (null-space form) the state is (z, w) with dq = basis_q z, dv = basis_v w.
    """
    A: np.ndarray
    B: np.ndarray
    x: np.ndarray
    u: np.ndarray
    t: float
    flow: str
    state_names: list
    input_names: list
    basis_q: np.ndarray | None = None      # (nq, nq - holonomic rank), orthonormal
    basis_v: np.ndarray | None = None      # (nv, nv - rank of all rows), orthonormal
    cyclic: tuple = ()                      # coordinates left out of a steady motion's state (see above)
    point_names: tuple = ()                 # the names of x (coordinates and speeds); default state_names

    @property
    def form(self) -> str:
        return "full" if self.basis_q is None else "null-space"

    @property
    def eigenvalues(self) -> np.ndarray:
        """Eigenvalues of A, sorted by real part, then imaginary part."""
        ev = np.linalg.eigvals(self.A)
        return ev[np.lexsort((ev.imag, ev.real))]


class _Point:
    """Values and exact gradients (with respect to `wrt`) of the symbols of a SymbolicModel at one point."""

    def __init__(self, model: SymbolicModel, needed: set, values: dict, wrt: list):
        """needed: the intermediate symbols to evaluate (see _needed)."""
        self.values = {s: sp.Float(v) for s, v in values.items()}
        n = len(wrt)
        self.grads = {s: np.eye(n)[i] for i, s in enumerate(wrt)}
        self.zero = np.zeros(n)
        for sym, expr in model.assignments:
            if sym in needed:
                value, grad = self.evaluate(expr)
                self.values[sym] = sp.Float(value)
                self.grads[sym] = grad

    def evaluate(self, expr) -> tuple[float, np.ndarray]:
        """The value of expr and its gradient, by the chain rule through the symbols it uses."""
        expr = sp.sympify(expr)
        value = float(expr.xreplace(self.values))
        grad = self.zero.copy()
        for s in expr.free_symbols:
            g = self.grads.get(s)
            if g is not None and g.any():
                grad += float(sp.diff(expr, s).xreplace(self.values)) * g
        return value, grad


def _needed(model: SymbolicModel, rows=()) -> set:
    """The intermediate symbols M and G (and the constraint rows' A, kappa, phi, c) depend on, directly
    or through other intermediates."""
    C = model.constraints
    return model.intermediates_of([*model.M, *model.G, *(e for r in rows for e in (*C.A.row(r), C.kappa[r], C.c[r])),
                                   *(C.phi[r] for r in rows if r < C.nh)])


def _check_supported(model: SymbolicModel, flow: int) -> None:
    name = model.spec.name
    if model.signals:
        raise LinearizeError(f"{name}: linearize handles coordinates and speeds; this model also has signals "
                             f"({', '.join(str(s) for s in model.signals)}, from nonholonomic or quaternion links), "
                             "which it does not yet handle")
    if len(model.v) != len(model.q):
        raise LinearizeError(f"{name}: linearize needs one speed per coordinate (dq/dt = v); this model has "
                             f"{len(model.q)} coordinates and {len(model.v)} speeds")
    active = {model.constraints.rows[r] for r in model.hybrid.flow_rows[flow]}
    nonlinear = [c.name for c in model.spec.constraints if c.nonlinear and c.name in active]
    if nonlinear:
        # At rest a row nonlinear in the speeds (|v|^2 = c, a cone z' = k |v_xy|) has no tangent space of
        # allowed speeds, or none at all: the null-space form below needs rows J v + b = 0.
        raise LinearizeError(f"{name}: constraint '{nonlinear[0]}' is not linear in the speeds; linearize handles "
                             f"flows whose velocity rows are J v + b = 0 (the null-space form at rest), so flow "
                             f"'{model.hybrid.flows[flow]}' is not linearized")


def default_point(model: SymbolicModel, parameters: dict | None = None, inputs: dict | None = None,
                  flow: int | None = None):
    """(x, u, p, d): the model's initial state, inputs (with the flow's own), parameters and discrete states
    as numbers, with `parameters` and `inputs` {name: value} overriding the defaults."""
    spec = model.spec
    flow = model.hybrid.initial if flow is None else flow
    for kind, given, known in (("parameter", parameters, spec.parameters), ("input", inputs, spec.inputs)):
        unknown = sorted(set(given or {}) - set(known))
        if unknown:
            raise LinearizeError(f"{spec.name}: no {kind} named {', '.join(unknown)}; "
                                 f"{kind}s: {', '.join(known) or 'none'}")
    p = [float((parameters or {}).get(name, default)) for name, (_, default) in spec.parameters.items()]
    at = {sym: sp.Float(v) for sym, v in zip(model.parameters, p)}
    u = [float((inputs or {}).get(name, default)) for name, (_, default) in spec.inputs.items()]
    for i, expr in model.hybrid.flow_inputs[flow].items():
        u[i] = float(sp.sympify(expr).xreplace(at))
    initial = ([c.initial for c in spec.coordinates] + [c.velocity for c in spec.coordinates]
               + [s.initial for s in spec.speeds] + [s.initial for s in spec.signals])
    x = [float(sp.sympify(e).xreplace(at)) for e in initial]
    d = [float(sp.sympify(v.initial).xreplace(at)) for v in spec.discrete]
    return np.array(x), np.array(u), np.array(p), np.array(d)


def _point_values(model: SymbolicModel, x, u, p, d, t: float) -> dict:
    values = {model.t: t}
    values.update(zip(model.q + model.v + model.signals, x))
    values.update(zip(model.parameters, p))
    values.update(zip(model.inputs, u))
    values.update(zip(model.discrete, d))
    return values


def values_at(model: SymbolicModel, exprs: list, x, u, p, d=(), t: float = 0.0) -> np.ndarray:
    """The values of expressions of the model's symbols (intermediates too) at one point, exactly as the
    linearization evaluates them (x, u, p, d ordered as in linearize)."""
    point = _Point(model, model.intermediates_of(exprs), _point_values(model, x, u, p, d, t), [])
    return np.array([_real(point, e) for e in exprs])


def _real(point: _Point, expr) -> float:
    """expr's value at the point, NaN where it has no real value (a square root of a negative number)."""
    try:
        return point.evaluate(expr)[0]
    except TypeError:           # (SymPy: "Cannot convert complex to float")
        return math.nan


def linearize(model: SymbolicModel, x, u, p, d=(), t: float = 0.0, flow: int | None = None,
              cyclic=None) -> Linearization:
    """A and B of `flow` (default the initial one) about state x and inputs u, at parameters p, discrete states d.

    x, u, p, d are ordered as the generated module's STATES, INPUTS, PARAMETERS and DISCRETE_STATES. A
    constrained flow that moves is linearized about a steady motion, without the cyclic coordinates: those
    named in `cyclic`, or else every coordinate that moves (each must appear in none of the flow's equations;
    cyclic_coordinates).
    """
    flow = model.hybrid.initial if flow is None else flow
    _check_supported(model, flow)
    n, nu = len(model.v), len(model.inputs)
    x, u = np.asarray(x, dtype=float), np.asarray(u, dtype=float)
    wrt = model.q + model.v + model.inputs
    rows = model.hybrid.flow_rows[flow]
    point = _Point(model, _needed(model, rows), _point_values(model, x, u, p, d, t), wrt)
    M = np.empty((n, n))
    dM = np.empty((n, n, len(wrt)))
    for i in range(n):
        for j in range(i, n):
            M[i, j], dM[i, j] = point.evaluate(model.M[i, j])
            M[j, i], dM[j, i] = M[i, j], dM[i, j]
    G, dG = _evaluate(point, list(model.G))
    names, inputs = _state_names(model), list(model.spec.inputs)
    if rows:
        return _constrained(model, point, rows, M, dM, G, dG, x, u, t, flow, cyclic)
    a = np.linalg.solve(M, G)
    da = np.linalg.solve(M, dG - np.einsum("ijk,j->ik", dM, a))     # (n, 2n + nu)
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :] = da[:, :2 * n]
    B = np.zeros((2 * n, nu))
    B[n:, :] = da[:, 2 * n:]
    return Linearization(A, B, x, u, t, model.hybrid.flows[flow], names, inputs)


def _evaluate(point: _Point, exprs: list) -> tuple[np.ndarray, np.ndarray]:
    """Values (len,) and gradients (len, wrt) of expressions at the point."""
    pairs = [point.evaluate(e) for e in exprs]
    return np.array([v for v, _ in pairs]), np.array([g for _, g in pairs]).reshape(len(exprs), -1)


def cyclic_coordinates(model: SymbolicModel, flow: int, x, u, p, d=(), t: float = 0.0) -> list[str]:
    """The coordinates the flow's equations (M, G, its rows' A, kappa, c and phi) do not depend on, so that a
    steady motion may move them: those that appear in none of them, and those that appear but cancel (a
    symmetric disk's spin angle, which the recursive kinematics carry through cos and sin): the equations
    take the same values, to 1e-12 relative, with the coordinate moved by 1 and by 2.5 from the point."""
    C = model.constraints
    rows = model.hybrid.flow_rows[flow]
    exprs = [*model.M, *model.G, *(e for r in rows for e in (*C.A.row(r), C.kappa[r], C.c[r])),
             *(C.phi[r] for r in rows if r < C.nh)]
    defs = dict(model.assignments)
    used = set().union(*(sp.sympify(e).free_symbols for e in exprs),
                       *(defs[s].free_symbols for s in model.intermediates_of(exprs)))
    x = np.asarray(x, dtype=float)
    here = None
    out = []
    for i, (c, q) in enumerate(zip(model.spec.coordinates, model.q)):
        if q in used:
            if here is None:
                here = values_at(model, exprs, x, u, p, d, t)
            tol = 1e-12 * max(1.0, np.max(np.abs(here)))
            moved = (values_at(model, exprs, np.where(np.arange(len(x)) == i, x + shift, x), u, p, d, t)
                     for shift in (1.0, 2.5))
            if any(np.max(np.abs(v - here)) > tol for v in moved):
                continue
        out.append(c.name)
    return out


def _constrained(model: SymbolicModel, point: _Point, rows: list, M, dM, G, dG, x, u, t, flow,
                 cyclic=None) -> Linearization:
    """The null-space form of a constrained flow at rest on its manifold, or about a steady motion (see the
    module docstring)."""
    C, n, name = model.constraints, len(model.v), model.spec.name
    m, k = len(rows), dG.shape[1]
    holonomic = [i for i, r in enumerate(rows) if r < C.nh]
    A_rows, dA = _evaluate(point, [C.A[r, j] for r in rows for j in range(n)])
    A_rows, dA = A_rows.reshape(m, n), dA.reshape(m, n, k)
    kappa, dkappa = _evaluate(point, [C.kappa[r] for r in rows])
    phi = np.array([point.evaluate(C.phi[rows[i]])[0] for i in holonomic])
    c, dc = _evaluate(point, [C.c[r] for r in rows])
    flow_name = model.hybrid.flows[flow]
    worst = max(np.max(np.abs(phi), initial=0.0), np.max(np.abs(c), initial=0.0))
    if worst > 1e-9 * max(1.0, np.max(np.abs(x))):
        j = int(np.argmax(np.abs(np.concatenate([phi, c]))))
        row = rows[holonomic[j] if j < len(phi) else j - len(phi)]
        raise LinearizeError(f"{name}: the point is off flow '{flow_name}''s constraint manifold (largest residual "
                             f"{worst:.3g}, in constraint '{C.rows[row]}'); give coordinates that satisfy the "
                             f"constraints with --at (a sample of a run, for instance)")
    saddle = np.block([[M, -A_rows.T], [A_rows, np.zeros((m, m))]])
    a_lam = np.linalg.lstsq(saddle, np.concatenate([G, -kappa]), rcond=None)[0]
    a, lam = a_lam[:n], a_lam[n:]
    rhs = np.concatenate([dG - np.einsum("ijk,j->ik", dM, a) + np.einsum("rik,r->ik", dA, lam),
                          -np.einsum("rjk,j->rk", dA, a) - dkappa])
    da = np.linalg.lstsq(saddle, rhs, rcond=None)[0][:n]
    kept, left_out = _steady_coordinates(model, flow, point, x, a, G, M, cyclic)
    from scipy.linalg import null_space
    E = np.eye(n)[:, kept]
    Nq = null_space(A_rows[holonomic] @ E) if holonomic else np.eye(len(kept))
    Nv = null_space(A_rows)
    T = E @ Nq                                              # dq = T z
    P = -np.linalg.pinv(A_rows) @ dc[:, :n] @ T            # dv = N_v w + P z stays on the manifold
    nz, nw = Nq.shape[1], Nv.shape[1]
    A = np.zeros((nz + nw, nz + nw))
    A[:nz, :nz] = T.T @ P
    A[:nz, nz:] = T.T @ Nv
    A[nz:, :nz] = Nv.T @ (da[:, :n] @ T + da[:, n:2 * n] @ P)
    A[nz:, nz:] = Nv.T @ da[:, n:2 * n] @ Nv
    B = np.zeros((nz + nw, len(u)))
    B[nz:, :] = Nv.T @ da[:, 2 * n:]
    holonomic_only = nz == nw and np.allclose(T.T @ Nv, np.eye(nz))
    names = [f"z{i + 1}" for i in range(nz)] + [f"z{i + 1}_dot" if holonomic_only else f"w{i + 1}" for i in range(nw)]
    return Linearization(A, B, x, u, t, flow_name, names, list(model.spec.inputs), T, Nv, tuple(left_out),
                         tuple(_state_names(model)))


def _steady_coordinates(model: SymbolicModel, flow: int, point: _Point, x, a, G, M, cyclic) -> tuple[list, list]:
    """(kept, left out): the indices of the coordinates in the linear state, and the names of the cyclic ones
    left out. At rest with no `cyclic` given, every coordinate is kept. Otherwise the point must be a steady
    motion (the module docstring): LinearizeError says which coordinate or speed is not steady."""
    spec, n = model.spec, len(model.v)
    coordinates = [c.name for c in spec.coordinates]
    speeds = np.asarray(x[n:2 * n])
    flow_name = model.hybrid.flows[flow]
    if cyclic is None and not np.any(speeds != 0.0):
        return list(range(n)), []
    free = cyclic_coordinates(model, flow, x, *(np.array([float(point.values[s]) for s in group])
                                                for group in (model.inputs, model.parameters, model.discrete)),
                              float(point.values[model.t]))
    if cyclic is None:
        moving = [coordinates[i] for i in np.flatnonzero(speeds != 0.0) if coordinates[i] not in free]
        cyclic = free
        if moving:
            raise LinearizeError(
                f"{spec.name}: flow '{flow_name}' is constrained and moves, so it is linearized about a steady "
                f"motion, where every coordinate that moves is cyclic (appears in none of the flow's equations); "
                f"{', '.join(f'{c} (speed {speeds[coordinates.index(c)]:.6g})' for c in moving)} "
                f"{'moves but appears' if len(moving) == 1 else 'move but appear'} in them (cyclic here: "
                f"{', '.join(free) or 'none'}); set {', '.join(f'{c}_dot=0' for c in moving)} with --at")
    else:
        unknown = [c for c in cyclic if c not in coordinates]
        if unknown:
            raise LinearizeError(f"{spec.name}: no coordinate named {', '.join(unknown)} (--cyclic); coordinates: "
                                 f"{', '.join(coordinates)}")
        wrong = [c for c in cyclic if c not in free]
        if wrong:
            raise LinearizeError(f"{spec.name}: {', '.join(wrong)} {'is' if len(wrong) == 1 else 'are'} not cyclic "
                                 f"in flow '{flow_name}' (cyclic coordinates appear in none of its equations; "
                                 f"these are: {', '.join(free) or 'none'}); leave {'it' if len(wrong) == 1 else 'them'}"
                                 " out of --cyclic")
        moving = [coordinates[i] for i in np.flatnonzero(speeds != 0.0) if coordinates[i] not in cyclic]
        if moving:
            raise LinearizeError(f"{spec.name}: {', '.join(moving)} moves in a steady motion but is not cyclic; "
                                 f"set {', '.join(f'{c}_dot=0' for c in moving)} with --at, or add it to --cyclic")
    scale = max(1.0, np.max(np.abs(G)), np.max(np.abs(M)) * np.max(np.abs(speeds)) ** 2)
    if np.max(np.abs(a), initial=0.0) > 1e-9 * scale:
        i = int(np.argmax(np.abs(a)))
        speed_names = list(spec.speed_names)
        raise LinearizeError(f"{spec.name}: the point is no steady motion of flow '{flow_name}': d({speed_names[i]})"
                             f"/dt = {a[i]:.6g} there, where every speed must be constant; give another point "
                             "with --at (the upright disk rolling straight, a wheel at constant speed)")
    return [i for i, c in enumerate(coordinates) if c not in cyclic], list(cyclic)


def _state_names(model: SymbolicModel) -> list:
    return [c.name for c in model.spec.coordinates] + list(model.spec.speed_names)


def find_equilibrium(model: SymbolicModel, q_guess, u, p, d=(), t: float = 0.0, flow: int | None = None,
                     tol: float = 1e-12) -> np.ndarray:
    """Coordinates q near q_guess with G(t, q, 0, u) = 0: at rest there, the flow stays at rest (dv/dt = 0).

    Raises LinearizeError when Newton's method does not converge (no equilibrium near the guess)."""
    from scipy.optimize import root

    flow = model.hybrid.initial if flow is None else flow
    _check_supported(model, flow)
    if model.hybrid.flow_rows[flow]:
        raise LinearizeError(f"{model.spec.name}: --find-equilibrium handles flows without constraint rows so far; "
                             f"give a rest point on the constraint manifold with --at instead")
    n = len(model.q)
    needed = _needed(model)

    def residual(q):
        point = _Point(model, needed, _point_values(model, np.concatenate([q, np.zeros(n)]), u, p, d, t), model.q)
        values = [point.evaluate(model.G[i]) for i in range(n)]
        return np.array([v for v, _ in values]), np.array([g for _, g in values])

    sol = root(residual, np.asarray(q_guess, dtype=float), jac=True, method="hybr", tol=tol)
    if not sol.success or np.max(np.abs(sol.fun)) > 1e-9 * max(1.0, np.max(np.abs(residual(q_guess)[0]))):
        raise LinearizeError(f"{model.spec.name}: no equilibrium found near q = {list(np.round(q_guess, 6))} "
                             f"({sol.message.strip()}; largest |G| = {np.max(np.abs(sol.fun)):.2e}); "
                             "start from a closer guess with --at")
    return sol.x
