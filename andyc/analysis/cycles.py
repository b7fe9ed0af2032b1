"""Periodic orbits of hybrid models: Newton's method on the Poincaré map of a jump (`andyc cycle`).

The section is a jump J's guard surface g_J = 0 in J's source flow. Q maps a state y = (x, d) on it, just
before J, to the state just before J's N-th next occurrence (N = period): J's map (resets, impact: the
compiled numerics' own) and an rk4 run from there that stops at that occurrence (stop_after). Its exact
Jacobian DQ = dy'/dy comes from J's Jacobian (andyc.runtime.sensitivities.Tangent.jump) and the run's
sensitivities (the RK4 stages and each jump's saltation matrix), so Newton's method converges quadratically,
to round-off. The fixed point is reported just after J (y+ = J(y)), as a step-to-step map is written.

Q is not solved in all of y: a fixed point is isolated only on the section and the constraint manifold, and
modulo the model's symmetries. At the current y the coordinates are an orthonormal basis B of the null space of

    the source flow's constraint rows, dphi/dy (holonomic rows, position level) and dc/dy (every row,
        velocity level), d included (a foot's place), and the guard's gradient g_y (the section),
less the symmetries: directions s of y along which nothing in the model changes (F s = 0 for the flow's
    Jacobian F, g_y s = 0 for every guard, and every reset maps s to s), such as a walker's shift downhill
    together with its foot (hip x and fx): Q(y + s) = Q(y) + s, DQ s = s.

Each Newton step solves (B^T DQ B - I) dz = -B^T (Q(y) - y), moves y by B dz and puts it back on the section and
the manifold by Gauss-Newton on (phi, c, g) = 0 (least-norm steps, normal to them: a change at second order).
Working on the guard surface, which the model defines, rather than on the set of post-jump states (known only
as the jump map's image), keeps the phase fixed, so the fixed point is isolated there. The Floquet multipliers
are the eigenvalues of B^T DQ B at the fixed point: those of the Poincaré map on the section (the trivial ones
of the flow direction and of the symmetries are left out), the same as the post-jump map's, to which J
conjugates it. See Hiskens & Pai, "Trajectory sensitivity analysis of hybrid systems" (IEEE Trans. Circuits
and Systems I 47(2), 2000) and Grizzle, Abba & Plestan, "Asymptotically stable walking for biped robots:
analysis via systems with impulse effects" (IEEE Trans. Automatic Control 46(1), 2001).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import null_space

import andyc
from andyc.runtime.sensitivities import Tangent, load_derivatives
from andyc.runtime.timestepping import refuse_friction


class CycleError(ValueError):
    """A request `find_cycle` does not take (an unknown jump, a period below 1); the message says why."""


@dataclass
class Cycle:
    """The result of find_cycle: converged or not, the last iterate and what Newton saw on the way."""
    model: str
    section: str
    period_count: int
    parameters: dict
    converged: bool
    message: str
    state: np.ndarray                # x just after the section's jump (the fixed point when converged)
    discrete: np.ndarray             # d just after it
    state_names: list
    discrete_names: list
    period: float = float("nan")     # time from the section back to it, N times
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0))
    history: list = field(default_factory=list)  # the residual |B^T (P(y) - y)|_inf at each iterate
    basis: np.ndarray | None = None   # B: the section's coordinates in y = (x, d)
    symmetries: np.ndarray | None = None   # the symmetry directions left out, (len(y), k)
    before: np.ndarray | None = None  # y = (x, d) just before the jump: the iterate on the section

    def as_dict(self) -> dict:
        mult = self.multipliers
        return {"model": self.model, "section": self.section, "period_count": self.period_count,
                "parameters": self.parameters, "converged": self.converged, "message": self.message,
                "state": dict(zip(self.state_names, map(float, self.state))),
                "discrete": dict(zip(self.discrete_names, map(float, self.discrete))),
                "period": float(self.period) if np.isfinite(self.period) else None,   # (JSON has no NaN)
                "multipliers": [{"real": float(m.real), "imag": float(m.imag), "abs": float(abs(m))} for m in mult],
                "residual_history": [float(r) for r in self.history],
                "section_dimension": 0 if self.basis is None else int(self.basis.shape[1]),
                "symmetries": [] if self.symmetries is None else self.symmetries.T.tolist()}


def find_cycle(model, section: str, period: int = 1, parameters: dict | None = None, dt: float = 1e-3,
               tol: float = 1e-11, max_iterations: int = 20, t_max: float = 20.0, event_tol: float = 1e-14,
               x0=None, d0=None, progress=None, start=None) -> Cycle:
    """A periodic orbit of `model` through the jump `section` (see the module docstring), by Newton's method from
    the state just before the first occurrence of the jump in a run from (x0, d0) (default the model's initial
    state, put on its constraint manifold). tol: on the residual |B^T (Q(y) - y)|_inf. t_max: the longest a run
    may take to come back to the section `period` times. progress(iteration, residual): called at each iterate.

    The Cycle says whether it converged and, if not, why (the section never reached, no convergence), with the
    residual of every iterate. start: a first iterate y = (x, d) just before the jump instead (put on the section;
    andyc.analysis.continuation starts a branch of period 2 so)."""
    refuse_friction(model.friction_names, "andyc cycle", f"{model.source}: ", "", CycleError)
    if section not in model.jump_names:
        raise CycleError(f"{model.name}: no jump named '{section}'; jumps: {', '.join(model.jump_names) or 'none'}")
    if period < 1:
        raise CycleError(f"--period must be at least 1, got {period}")
    k = model.jump_names.index(section)
    source = int(model.module.JUMP_SOURCE[k])
    p = model.parameters(parameters)
    params = dict(zip(model.parameter_names, map(float, p)))
    nx, nd = model.nx, model.nd
    result = Cycle(model.name, section, period, params, False, "", np.zeros(nx), np.zeros(nd),
                   list(model.state_names), list(model.discrete_names))
    derivatives = load_derivatives(model)
    first = None if start is not None else andyc.simulate(
        model, t_max, dt, "rk4", parameters=params, x0=x0, d0=d0, progress=False, init=andyc.Init("project"),
        events=andyc.Events(tol=event_tol, stop_after={section: 1}))
    if first is not None and not (first.finished and first.events["jump"].size and first.events["jump"][-1] == k):
        result.message = (f"the run from the initial state did not reach jump '{section}' within t_max = {t_max:g} s "
                          f"({first.status})")
        return result
    y = _before_last_jump(first, nd) if first is not None else _on_section(model, derivatives, source, k, p,
                                                                           np.asarray(start, float))
    Q = PoincareMap(model, derivatives, k, p, period, dt, t_max, event_tol)
    for iteration in range(max_iterations + 1):
        B, sym = section_basis(model, derivatives, source, k, p, y)
        image = Q(y, directions=B)          # DQ B only: the run carries B's columns, not all of z's
        result.state, result.discrete, result.before = image.after[:nx], image.after[nx:], y
        if image.y is None:
            result.message = (f"iteration {iteration}: the run from the iterate did not come back to jump '{section}' "
                              f"{period} time(s) within t_max = {t_max:g} s ({image.status})")
            return result
        Qy = image.y
        reduced = B.T @ image.jacobian
        residual = B.T @ (Qy - y)
        r = float(np.max(np.abs(residual), initial=0.0))
        result.history.append(r)
        result.basis, result.symmetries = B, sym
        result.period = image.time
        result.multipliers = _sorted(np.linalg.eigvals(reduced))
        if progress is not None:
            progress(iteration, r)
        if r <= tol:
            result.converged = True
            result.message = f"converged in {iteration} Newton step(s)"
            return result
        if iteration == max_iterations:
            break
        step = np.linalg.solve(reduced - np.eye(len(residual)), -residual)
        y = _on_section(model, derivatives, source, k, p, y + B @ step)
    result.message = (f"no convergence in {max_iterations} Newton steps: the residual went "
                      f"{', '.join(f'{h:.3g}' for h in result.history)}")
    return result


@dataclass
class Image:
    """Q(y): `y` (None when the run did not come back), its Jacobian DQ (DQ V along directions V; None when not
    asked for), the state `after` J at y (the start of the run), the run's `time` and `status`; with the whole
    DQ, `parameter_jacobian` dQ/dp at fixed y (J's and the run's); `visits`: the times of J's occurrences in the
    run (the last is `time`) and the states (x, d) just after them, the first at t = 0 being `after`."""
    y: np.ndarray | None
    jacobian: np.ndarray | None
    after: np.ndarray
    time: float
    status: str
    parameter_jacobian: np.ndarray | None = None
    visits: tuple | None = None


class PoincareMap:
    """Q of jump k, period N (see the module docstring): Q(y) -> Image, with DQ when jacobian=True (then the
    run carries its sensitivities; without, it is the plain compiled loop); Q(y, directions=V) (len(y), k): the
    Jacobian along V only, DQ V (the run then carries k columns: cheaper)."""

    def __init__(self, model, derivatives, k: int, p, period: int, dt: float, t_max: float, event_tol: float):
        self.model, self.derivatives, self.k, self.p = model, derivatives, k, np.asarray(p, float)
        self.params = dict(zip(model.parameter_names, map(float, p)))
        self.target = int(model.module.JUMP_TARGET[k])
        self.dt, self.t_max = dt, t_max
        self.events = andyc.Events(tol=event_tol, stop_after={model.jump_names[k]: period})

    def __call__(self, y, jacobian: bool = True, directions=None) -> Image:
        model, k, p = self.model, self.k, self.p
        nx, nd = model.nx, model.nd
        held = np.asarray(model.input_defaults, float)
        x, d = y[:nx].copy(), y[nx:].copy()
        DJ = None
        if jacobian:
            DJ = Tangent(model, self.derivatives, p, held).jump(k, 0.0, x, d, np.eye(nx + nd + len(p) + 1))
        _apply_jump(model, k, x, held, p, d)
        after = np.concatenate([x, d])
        want = jacobian
        if jacobian and directions is not None:     # z = (x0, d0, p) along DJ V
            want = np.zeros((nx + nd + len(p), np.shape(directions)[1]))
            want[:nx + nd] = DJ[:nx + nd, :nx + nd] @ directions
        run = andyc.simulate(model, self.t_max, self.dt, "rk4", parameters=self.params, x0=x, d0=d,
                             flow0=self.target, progress=False, sensitivities=want, init=andyc.Init("as-is"),
                             events=self.events)
        if not (run.finished and run.events["jump"].size and run.events["jump"][-1] == k):
            return Image(None, None, after, float(run.time[-1]), run.status)
        ev = run.events
        mine = ev["jump"] == k
        visits = (np.concatenate([[0.0], ev["time"][mine]]),
                  np.vstack([after, np.hstack([ev["state_after"][mine], ev["discrete_after"][mine]])]))
        if not jacobian:
            return Image(_before_last_jump(run, nd), None, after, float(run.events["time"][-1]), run.status,
                         visits=visits)
        if directions is not None:                  # the run carried DJ V: DQ V, and no dQ/dp
            return Image(_before_last_jump(run, nd), run.sensitivities["before_jump"], after,
                         float(run.events["time"][-1]), run.status, visits=visits)
        ny, S = nx + nd, run.sensitivities["before_jump"]    # d(y')/d(x0, d0, p): the run from J(y)
        DQ = S[:, :ny] @ DJ[:ny, :ny]
        DQp = S[:, :ny] @ DJ[:ny, ny:ny + len(p)] + S[:, ny:]
        return Image(_before_last_jump(run, nd), DQ, after, float(run.events["time"][-1]), run.status, DQp, visits)


def _before_last_jump(run, nd: int) -> np.ndarray:
    """(x, d) just before the run's last jump: the discrete states then are those after the jump before it, or,
    if there was none since, those of the last sample before it."""
    ev = run.events
    t = ev["time"][-1]
    row = max(int(np.searchsorted(run.time, t, side="left")) - 1, 0)
    d = run.discrete[row]
    if len(ev["time"]) > 1 and ev["time"][-2] >= run.time[row]:
        d = ev["discrete_after"][-2]
    return np.concatenate([ev["state_before"][-1], d])


def _apply_jump(model, k, x, u, p, d) -> None:
    """Jump k's resets and impact map on x, d in place: the compiled numerics' own (andyc_numerics/dynamics.jump)."""
    from andyc.runtime.compiled import work

    status = model.numerics.dynamics.jump(model.ref, work(model).ref, k, 0.0, x, u, p, d)
    if status != 0:
        raise CycleError(f"{model.name}: jump '{model.jump_names[k]}' failed at the iterate (status {status})")


def _section_rows(model, derivatives, flow: int, k: int, p, y, parameters: bool = False, guard: bool = True):
    """(h, dh/dy): the flow's constraint rows (phi, c) and jump k's guard at y = (x, d); with parameters,
    (h, dh/dy, dh/dp); without guard, the constraint rows only (andyc.analysis.basins' starting states)."""
    nx, ny = model.nx, len(y)
    held = np.asarray(model.input_defaults, float)
    x, d = y[:nx], y[nx:]
    out = derivatives.flow_terms(0.0, x, held, p, d)
    c, dc, phi, dphi = out[8], out[9], out[10], out[11]
    rows = [int(r) for r in model.module.FLOW_ROWS[flow] if r >= 0]
    g, dg = derivatives.guard_terms(k, 0.0, x, held, p, d)
    hol = [r for r in rows if r < model.nh]
    h = np.concatenate([phi[hol], c[rows], [g] if guard else []])
    W = np.vstack([dphi[hol], dc[rows]] + ([dg[None]] if guard else []))
    if parameters:
        return h, W[:, :ny], W[:, ny:ny + len(p)]
    return h, W[:, :ny]


def _on_section(model, derivatives, flow, k, p, y, iterations: int = 8) -> np.ndarray:
    """y moved onto the section and the constraint manifold (phi = c = g = 0) by Gauss-Newton, least-norm steps."""
    for _ in range(iterations):
        h, H = _section_rows(model, derivatives, flow, k, p, y)
        if np.max(np.abs(h)) < 1e-15 * max(1.0, np.max(np.abs(y))):
            break
        y = y - np.linalg.lstsq(H, h, rcond=None)[0]
    return y


def section_basis(model, derivatives, flow: int, k: int, p, y):
    """(B, symmetries) at y = (x, d) on jump k's section in `flow`: see the module docstring."""
    nx, ny = model.nx, len(y)
    held = np.asarray(model.input_defaults, float)
    x, d = y[:nx], y[nx:]
    _, H = _section_rows(model, derivatives, flow, k, p, y)
    N = null_space(H)
    # symmetries: nothing in the flow, the guards or the resets changes along them
    F = Tangent(model, derivatives, p, held).rates(0.0, x, d, flow)[1]
    tests = [F[:, :ny], H]
    for j in range(model.nj):
        tests.append(derivatives.guard_terms(j, 0.0, x, held, p, d)[1][None, :ny])
        idx, _, dr = derivatives.reset_terms(j, 0.0, x, held, p, d)
        if len(idx):
            tests.append(dr[:, :ny] - np.eye(ny)[idx])
    stacked = np.vstack(tests)
    sym = null_space(stacked, rcond=1e-10)
    B = N @ null_space(sym.T @ N) if sym.size else N
    return B, sym


def _sorted(values: np.ndarray) -> np.ndarray:
    """By modulus, largest first, then by imaginary part."""
    return values[np.lexsort((-values.imag, -np.abs(values)))]
