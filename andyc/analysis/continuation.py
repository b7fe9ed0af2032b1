"""Branches of periodic orbits in one parameter (`andyc cycle --continue NAME=A:B`): pseudo-arclength continuation
of the fixed point of a jump's Poincaré map, with its folds and period doublings located and the period-2 branch
followed from each period doubling.

The map is andyc.analysis.cycles' Q(y; p) of jump J (period N): y = (x, d) on J's guard surface, just before J, in
the constraint manifold of J's source flow; its Jacobians DQ = dQ/dy and Q_p = dQ/dp are exact (the rk4
sensitivities and saltation matrices, andyc.runtime.sensitivities). At a point (y, p) of the section,

    B      the section's coordinates (cycles.section_basis: orthonormal, symmetries left out),
    y_p    = -H^+ h_p, the least-norm way y moves with p to stay on the section and the manifold (h(y, p) = 0 the
           constraint rows and the guard, H = dh/dy),
    r      = B^T (Q(y) - y),          M = B^T DQ B  (the multipliers are its eigenvalues),
    r_p    = B^T (DQ y_p + Q_p - y_p), the change of r as p moves (y following the section).

A branch is the curve r(y, p) = 0 in (y, p) space, of dimension one where [M - I | r_p] has full rank m. Its
tangent (t_y, t_p), t_y = B t_z + y_p t_p, spans the null space of [M - I | r_p] (an SVD), has unit Euclidean norm
in (y, p), and keeps its orientation (t . t_previous > 0). One step of length ds from (y0, p0):

    predictor  (y, p) = (y0, p0) + ds (t_y, t_p), put back on the section (cycles._on_section at p);
    corrector  Newton on  r(y, p) = 0,  n(y, p) = t_y . (y - y0) + t_p (p - p0) - ds = 0  (the arclength
               condition: the new point lies on the hyperplane normal to the tangent at distance ds), i.e.

                   [ M - I           r_p             ] [dz]     [ r ]
                   [ t_y^T B   t_y^T y_p + t_p       ] [dp] = - [ n ],   y += B dz + y_p dp, p += dp,

               each iterate put back on the section. The bordered matrix is regular at folds (where M - I is
               singular but r_p is not in its range), so the branch goes round them; it is singular at a branch
               point (r_p in the range of the singular M - I), where the corrector fails.
    step       after 3 corrector steps or fewer ds grows by 1.5 (to --max-step); a corrector that fails (no
               convergence in 6 steps, a run that does not come back, a jump refused) halves ds and retries,
               down to --min-step.

Test functions, evaluated at every point (Kuznetsov, "Elements of Applied Bifurcation Theory", 3rd ed.,
Springer 2004, ch. 10; Seydel, "Practical Bifurcation and Stability Analysis", 3rd ed., Springer 2010, ch. 5
and 7):

    fold            t_p changes sign (the parameter turns back); there det(M - I) = 0 too;
    branch point    det(M - I) changes sign where t_p does not (a multiplier crosses +1 without a fold: a pitchfork
                    or transcritical branch point, e.g. a symmetry of the gait breaking);
    period doubling det(M + I) = prod (mu_i + 1) changes sign: a real multiplier crosses -1 (a complex pair
                    contributes |mu + 1|^2 > 0, so only real crossings change it).

Each change between two points is located on the branch by the Illinois variant of regula falsi on the
arclength s from the earlier point (predictor and corrector at each trial s), until the bracket in p is below
--locate-tol (1e-10), and at a fold (where p hardly moves with s) the bracket in s too: so the point's
parameter is known to that, and its test function vanishes there. When a trial's corrector fails (near a
branch point) the bracket stays as it is and the point is reported as not located, near the better end.

Period doubling: at the located point, the eigenvector v of the multiplier -1 (w = B v in y) is the direction of
the period-2N orbit, which leaves it as a pitchfork of Q^2 (whose multiplier there is +1) with a tangent along
(w, 0). The period-2N branch is started by the same predictor-corrector on Q^2 with the tangent (w/|w|, 0) (the
branch switching of Kuznetsov §10.2.2): the arclength condition w . (y - y*) = ds keeps Newton off the period-N
orbit, itself a fixed point of Q^2. It is then continued along its tangent while p stays in the range. See also
Allgower & Georg, "Introduction to Numerical Continuation Methods", SIAM 2003, ch. 2 (predictor-corrector), 6
(step length) and 8-9 (bifurcation and turning points along a curve).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass, field

import numpy as np

from andyc.analysis.cycles import (CycleError, PoincareMap, _on_section, _section_rows, find_cycle,
                                   section_basis)
from andyc.errors import SimulationError
from andyc.outputs import write_atomic
from andyc.runtime.sensitivities import load_derivatives

GROW, SHRINK = 1.5, 0.5           # step control
FAST = 3                          # a corrector that converges in this many steps or fewer lets ds grow
CORRECTOR_STEPS = 6


@dataclass
class Point:
    """A point of a branch: the parameter, y = (x, d) just before the jump (on the section) and after it, the
    period (time from the section back to it, N times), the multipliers, the tangent (t_y, t_p) and the test
    functions (det(M - I), det(M + I))."""
    parameter: float
    before: np.ndarray
    after: np.ndarray
    period: float
    multipliers: np.ndarray
    tangent: np.ndarray
    tests: tuple
    iterations: int = 0
    vectors: np.ndarray | None = None     # the eigenvectors of M, in y (B V), columns as the multipliers
    step_times: np.ndarray | None = None  # (N,) the times between the jump's N occurrences along the orbit
    visits: np.ndarray | None = None      # (N, len(y)) y just after each of them, the first = after

    @property
    def stable(self) -> bool:
        return bool(len(self.multipliers)) and float(np.max(np.abs(self.multipliers))) < 1.0


@dataclass
class Special:
    """A located point: kind 'fold', 'branch point' or 'period doubling', on the branch of period `period_count`."""
    kind: str
    point: Point
    period_count: int
    bracket: float           # the width in p of the last bracket
    index: int = 0           # it lies between the branch's points index - 1 and index
    located: bool = True     # False: the bracket could not be narrowed to locate_tol (point: its better end)


@dataclass
class Branch:
    period_count: int
    points: list = field(default_factory=list)
    specials: list = field(default_factory=list)
    message: str = ""        # why it stopped
    origin: Special | None = None   # the period doubling it was switched onto from


@dataclass
class Continuation:
    model: str
    section: str
    name: str
    start: float
    end: float
    branches: list
    state_names: list
    discrete_names: list
    parameters: dict         # the others, held
    symmetries: np.ndarray | None = None    # the model's symmetry directions in y (cycles.section_basis)

    def as_dict(self) -> dict:
        """For JSON: each branch's points and located points (y just before and after the jump, multipliers)."""
        names = self.state_names + self.discrete_names

        def point(q: Point) -> dict:
            return {self.name: float(q.parameter), "period": float(q.period), "stable": q.stable,
                    "step_times": [float(t) for t in q.step_times],
                    "visits": [dict(zip(names, map(float, v))) for v in q.visits],
                    "after": dict(zip(names, map(float, q.after))), "before": dict(zip(names, map(float, q.before))),
                    "multipliers": [{"real": float(m.real), "imag": float(m.imag), "abs": float(abs(m))}
                                    for m in q.multipliers]}

        return {"model": self.model, "section": self.section, "parameter": self.name, "from": self.start,
                "to": self.end, "parameters": self.parameters,
                "branches": [{"period_count": b.period_count, "message": b.message,
                              "from": None if b.origin is None else {"kind": b.origin.kind,
                                                                     self.name: float(b.origin.point.parameter)},
                              "points": [point(q) for q in b.points],
                              "located": [{"kind": sp.kind, "bracket": sp.bracket, "located": sp.located,
                                           **point(sp.point)}
                                          for sp in b.specials]} for b in self.branches]}


class Continuer:
    """Pseudo-arclength continuation of jump `section`'s periodic orbits in the parameter `name` (see the module
    docstring). Keyword arguments as find_cycle's (dt, tol, t_max, event_tol), and ds (the first step), ds_min,
    ds_max (in the Euclidean length of (y, p)), max_points (per branch), locate_tol (in p)."""

    def __init__(self, model, section: str, name: str, parameters: dict | None = None, dt: float = 1e-3,
                 tol: float = 1e-11, t_max: float = 20.0, event_tol: float = 1e-14, ds: float = 0.01,
                 ds_min: float = 1e-6, ds_max: float = 0.1, max_points: int = 200, locate_tol: float = 1e-10,
                 progress=None):
        if section not in model.jump_names:
            raise CycleError(f"{model.name}: no jump named '{section}'; jumps: {', '.join(model.jump_names) or 'none'}")
        if name not in model.parameter_names:
            raise CycleError(f"{model.name}: no parameter named '{name}'; parameters: "
                             f"{', '.join(model.parameter_names)}")
        self.model, self.section, self.name = model, section, name
        self.k = model.jump_names.index(section)
        self.source = int(model.module.JUMP_SOURCE[self.k])
        self.index = list(model.parameter_names).index(name)
        self.held = dict(parameters or {})
        self.p0 = np.asarray(model.parameters(self.held), float)
        self.dt, self.tol, self.t_max, self.event_tol = dt, tol, t_max, event_tol
        self.ds, self.ds_min, self.ds_max = ds, ds_min, ds_max
        self.max_points, self.locate_tol = max_points, locate_tol
        self.progress = progress
        self.derivatives = load_derivatives(model)

    # -- the map and its derivatives at (y, p) ------------------------------------------------------------------
    def _p(self, value: float) -> np.ndarray:
        p = self.p0.copy()
        p[self.index] = value
        return p

    def evaluate(self, y, value: float, period: int):
        """r, M, r_p, B, y_p and the image at (y, p = value); None when the run does not come back."""
        p = self._p(value)
        image = PoincareMap(self.model, self.derivatives, self.k, p, period, self.dt, self.t_max, self.event_tol)(y)
        if image.y is None:
            return None
        B, _ = section_basis(self.model, self.derivatives, self.source, self.k, p, y)
        _, H, Hp = _section_rows(self.model, self.derivatives, self.source, self.k, p, y, parameters=True)
        y_p = -np.linalg.lstsq(H, Hp[:, self.index], rcond=None)[0]
        DQ = image.jacobian
        r = B.T @ (image.y - y)
        M = B.T @ DQ @ B
        r_p = B.T @ (DQ @ y_p + image.parameter_jacobian[:, self.index] - y_p)
        return r, M, r_p, B, y_p, image

    def _onto(self, y, value: float) -> np.ndarray:
        return _on_section(self.model, self.derivatives, self.source, self.k, self._p(value), y)

    def _point(self, y, value, ev, previous_tangent, iterations) -> Point:
        """The branch's point at a converged (y, p): multipliers, oriented tangent, test functions."""
        r, M, r_p, B, y_p, image = ev
        m = len(r)
        _, _, vt = np.linalg.svd(np.hstack([M - np.eye(m), r_p[:, None]]))
        t_z, t_p = vt[-1, :m], vt[-1, m]
        tangent = np.concatenate([B @ t_z + y_p * t_p, [t_p]])
        tangent /= np.linalg.norm(tangent)
        if previous_tangent is not None and tangent @ previous_tangent < 0:
            tangent = -tangent
        mu, V = np.linalg.eig(M)
        order = np.lexsort((-mu.imag, -np.abs(mu)))
        tests = (float(np.linalg.det(M - np.eye(m))), float(np.linalg.det(M + np.eye(m))))
        times, states = image.visits
        return Point(value, y.copy(), image.after.copy(), image.time, mu[order], tangent, tests, iterations,
                     B @ V[:, order], np.diff(times), states[:-1])

    # -- one step: predictor and corrector ---------------------------------------------------------------------
    def step(self, start: Point, ds: float, period: int, tangent=None) -> Point | None:
        """The point at arclength ds from `start` along `tangent` (default its own), or None when the corrector
        fails."""
        t = start.tangent if tangent is None else tangent
        t_y, t_p = t[:-1], t[-1]
        value = start.parameter + ds * t_p
        try:
            y = self._onto(start.before + ds * t_y, value)
            for iteration in range(CORRECTOR_STEPS + 1):
                ev = self.evaluate(y, value, period)
                if ev is None:
                    return None
                r, M, r_p, B, y_p, _ = ev
                n = t_y @ (y - start.before) + t_p * (value - start.parameter) - ds
                if np.max(np.abs(r), initial=0.0) <= self.tol and abs(n) <= 1e-9 * max(1.0, abs(ds)):
                    return self._point(y, value, ev, t, iteration)
                if iteration == CORRECTOR_STEPS:
                    return None
                m = len(r)
                J = np.zeros((m + 1, m + 1))
                J[:m, :m], J[:m, m] = M - np.eye(m), r_p
                J[m, :m], J[m, m] = t_y @ B, t_y @ y_p + t_p
                delta = np.linalg.solve(J, -np.concatenate([r, [n]]))
                value = value + delta[m]
                y = self._onto(y + B @ delta[:m] + y_p * delta[m], value)
        except (np.linalg.LinAlgError, SimulationError, CycleError):
            return None
        return None

    # -- a branch -----------------------------------------------------------------------------------------------
    def follow(self, first: Point, period: int, branch: Branch, switch: bool = True) -> list:
        """Continue from `first` along its tangent while p stays in [lo, hi], appending the points and the located
        specials to `branch`. Returns the period doublings found (to switch from, with switch)."""
        branch.points.append(first)
        self._report(first, period)
        current, ds = first, self.ds
        doublings = []
        while len(branch.points) < self.max_points:
            nxt = self.step(current, ds, period)
            if nxt is None:
                ds *= SHRINK
                if ds < self.ds_min:
                    branch.message = (f"stopped at {self.name} = {current.parameter:.12g}: the corrector failed with "
                                      f"the step below --min-step {self.ds_min:g} (the orbit may end here: a gait "
                                      f"that falls, a guard grazed)")
                    return doublings
                continue
            inside = self.lo <= nxt.parameter <= self.hi
            for special in self._specials(current, nxt, ds, period):
                if self.lo <= special.point.parameter <= self.hi:
                    special.index = len(branch.points)      # between points index - 1 and index
                    branch.specials.append(special)
                    self._report(special, period)
                    if switch and special.kind == "period doubling" and special.located:
                        doublings.append(special)
            if not inside:
                branch.message = f"reached the end of the range of {self.name}"
                return doublings
            branch.points.append(nxt)
            self._report(nxt, period)
            current = nxt
            if nxt.iterations <= FAST:
                ds = min(ds * GROW, self.ds_max)
        branch.message = f"stopped after {self.max_points} points (--max-points)"
        return doublings

    # -- specials -----------------------------------------------------------------------------------------------
    def _specials(self, a: Point, b: Point, ds: float, period: int) -> list:
        found = []
        if a.tangent[-1] * b.tangent[-1] < 0:
            found.append(self._locate(a, b, ds, period, "fold", lambda q: q.tangent[-1]))
        elif a.tests[0] * b.tests[0] < 0:
            found.append(self._locate(a, b, ds, period, "branch point", lambda q: q.tests[0]))
        if a.tests[1] * b.tests[1] < 0:
            found.append(self._locate(a, b, ds, period, "period doubling", lambda q: q.tests[1]))
        return sorted(found, key=lambda f: abs(f.point.parameter - a.parameter))

    def _locate(self, a: Point, b: Point, ds: float, period: int, kind: str, test) -> Special | None:
        """The zero of test(point) on the branch between a (arclength s = 0 from a) and b (s = ds): the Illinois
        variant of regula falsi on s, a predictor-corrector step from a at each trial; until the bracket's width
        in p is at most locate_tol, and at a fold (where p hardly moves with s) its width in s too (or in s at
        most 1e-13)."""
        lo, hi = [0.0, test(a), a], [ds, test(b), b]
        kept = 0
        for _ in range(80):
            width = abs(hi[2].parameter - lo[2].parameter)
            arc = abs(hi[0] - lo[0])
            if (width <= self.locate_tol and (kind != "fold" or arc <= self.locate_tol)) or arc <= 1e-13 * max(1.0, ds):
                break
            s = hi[0] - hi[1] * (hi[0] - lo[0]) / (hi[1] - lo[1])
            if not min(lo[0], hi[0]) < s < max(lo[0], hi[0]):
                s = 0.5 * (lo[0] + hi[0])
            q = self.step(a, s, period)
            if q is None:         # (at a branch point the corrector's matrix is singular too)
                break
            f = test(q)
            if f * hi[1] > 0:          # replaces hi; lo kept twice running: halve its value (Illinois)
                hi = [s, f, q]
                kept = kept + 1 if kept > 0 else 1
                if kept > 1:
                    lo[1] /= 2
            else:
                lo = [s, f, q]
                kept = kept - 1 if kept < 0 else -1
                if kept < -1:
                    hi[1] /= 2
        best = min((lo, hi), key=lambda e: abs(test(e[2])))       # (e[1] may be Illinois-halved)
        width = abs(hi[2].parameter - lo[2].parameter)
        return Special(kind, best[2], period, width, located=bool(width <= self.locate_tol))

    # -- the whole run ------------------------------------------------------------------------------------------
    def run(self, start: float, end: float, period: int = 1, branch_switch: bool = True) -> Continuation:
        """Find the orbit of period N at p = start (find_cycle from the model's initial state), then continue it
        towards p = end while p stays between them; from each period doubling, the period-2N branch (one
        generation: its own doublings are located, not followed)."""
        self.lo, self.hi = min(start, end), max(start, end)
        held = {**self.held, self.name: start}
        cycle = find_cycle(self.model, self.section, period, held, dt=self.dt, tol=self.tol, t_max=self.t_max,
                           event_tol=self.event_tol)
        result = Continuation(self.model.name, self.section, self.name, start, end, [],
                              list(self.model.state_names), list(self.model.discrete_names),
                              {k: v for k, v in zip(self.model.parameter_names, map(float, self.p0))
                               if k != self.name})
        main = Branch(period)
        result.branches.append(main)
        result.symmetries = cycle.symmetries
        if not cycle.converged:
            main.message = f"no periodic orbit at {self.name} = {start:g}: {cycle.message}"
            return result
        ev = self.evaluate(cycle.before, start, period)
        if ev is None:
            main.message = f"the orbit at {self.name} = {start:g} does not come back to the section"
            return result
        first = self._point(cycle.before, start, ev, None, 0)
        if first.tangent[-1] * (end - start) < 0:
            first.tangent = -first.tangent
        for special in self.follow(first, period, main, switch=branch_switch):
            child = Branch(2 * special.period_count)
            result.branches.append(child)
            self._switch(special, child)
        return result

    def _switch(self, special: Special, child: Branch) -> None:
        """The period-2N branch from a located period doubling (see the module docstring)."""
        point, period = special.point, 2 * special.period_count
        child.origin = special
        near = int(np.argmin(np.abs(point.multipliers + 1.0)))
        w = np.real(point.vectors[:, near])
        w = w / np.linalg.norm(w)
        base = Point(point.parameter, point.before, point.after, point.period, point.multipliers,
                     np.concatenate([w, [0.0]]), point.tests)
        ds = self.ds
        while ds >= self.ds_min:
            first = self.step(base, ds, period)
            if first is not None and self._not_period(first, special.period_count):
                self.follow(first, period, child, switch=False)
                return
            ds *= SHRINK
        child.message = f"could not start the period-{period} branch at {self.name} = {point.parameter:.12g}"

    def _not_period(self, point: Point, period: int) -> bool:
        """Whether `point` is not a fixed point of Q^period (the period-2N Newton did not fall back on it)."""
        ev = self.evaluate(point.before, point.parameter, period)
        return ev is None or np.max(np.abs(ev[0])) > 1e3 * self.tol

    def _report(self, point: Point, period: int) -> None:
        if self.progress is not None:
            self.progress(point, period)



def rows(result: Continuation) -> tuple[list, list]:
    """(header, rows) of the branch table: one row per point and per located point (kind empty for a point):
    the branch's period count, the kind, the parameter, the period, stable, y just after the jump, then each
    multiplier's real and imaginary parts and modulus."""
    names = result.state_names + result.discrete_names
    m = max((len(q.multipliers) for b in result.branches for q in b.points), default=0)
    header = (["period_count", "kind", result.name, "period", "step_times", "stable"] + names
              + [f"{part}{i + 1}" for i in range(m) for part in ("re", "im", "abs")])
    out = []
    for b in result.branches:
        entries = [("", q) for q in b.points] + [(sp.kind, sp.point) for sp in b.specials]
        for kind, q in sorted(entries, key=lambda e: (e[1].parameter, e[0])):
            mult = list(q.multipliers) + [np.nan] * (m - len(q.multipliers))
            out.append([b.period_count, kind, q.parameter, q.period, ";".join(f"{t:.17g}" for t in q.step_times),
                        int(q.stable), *q.after]
                       + [v for mu in mult for v in (np.real(mu), np.imag(mu), abs(mu))])
    return header, out


def save_csv(result: Continuation, path) -> None:
    """The branch table (rows) as CSV, written whole (andyc.outputs.write_atomic)."""
    header, table = rows(result)
    with write_atomic(path) as tmp, open(tmp, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(header)
        for row in table:
            writer.writerow([v if isinstance(v, str) else f"{v:.17g}" for v in row])


def describe(result: Continuation) -> str:
    """The located points and a summary of each branch, for reading."""
    lines = []
    for b in result.branches:
        pts = b.points
        if pts:
            values = [q.parameter for q in pts]
            stable = sum(q.stable for q in pts)
            lines.append(f"period-{b.period_count} branch: {len(pts)} points, {result.name} from {min(values):.10g} "
                         f"to {max(values):.10g}, {stable} stable; {b.message}")
        else:
            lines.append(f"period-{b.period_count} branch: no points; {b.message}")
        for sp in b.specials:
            lines.append("  " + special_line(result.name, sp))
    return "\n".join(lines)


def special_line(name: str, sp: Special) -> str:
    mu = sp.point.multipliers
    target = -1.0 if sp.kind == "period doubling" else 1.0
    near = mu[int(np.argmin(np.abs(mu - target)))]
    if not sp.located:
        return (f"{sp.kind} near {name} = {sp.point.parameter:.12g}, not located (the bracket stayed {sp.bracket:.1e} "
                f"wide: the corrector failed inside it); multiplier nearest {target:+g} there: {near.real:.9g}")
    return (f"{sp.kind} at {name} = {sp.point.parameter:.15g} (bracket {sp.bracket:.1e}); period "
            f"{sp.point.period:.12g} s; multiplier nearest {target:+g}: {near.real:.15g}"
            + (f" {'+' if near.imag >= 0 else '-'} {abs(near.imag):.3g}i" if near.imag else "")
            + f" (|mu {'-' if target > 0 else '+'} 1| = {abs(near - target):.1e})")


__all__ = ["Branch", "Continuation", "Continuer", "Point", "Special", "describe", "rows", "save_csv", "special_line"]
