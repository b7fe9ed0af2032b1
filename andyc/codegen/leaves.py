"""The model's own functions, the leaves of andyc/numerics/model.py, as lines of Python source.

Each leaf's math goes through `function_body` (cse over everything the leaf computes, then ordered
lines); a leaf reads only the states, parameters, inputs and discrete states it uses. The leaves
over the jumps (guard, guard_rate, enabled, reset) have one branch per jump, each with its own cse,
so that a model compiles four functions for its jumps, not four per jump. A model without
constraints, signals, jumps, flow inputs or a closed form generates none of those leaves: the
numerics' stubs stand in.
"""

from __future__ import annotations

import sympy as sp

from andyc.codegen.c_leaves import NoC, c_lines
from andyc.codegen.printer import function_body
from andyc.numerics.layout import scratch_layout
from andyc.symbolic.formulation import ABA
from andyc.symbolic.model import SymbolicModel

STATE = "t, x, u, p, d"
DOCS = {
    "dynamics": "M (NV, NV) and G (NV,) with M dv/dt = G (ANDY eq. 8); then the power of each element that does work "
                "into G[NV:] (andyc/symbolic/work.py).",
    "forward_dynamics": "dv/dt into G[:NV] by the articulated-body algorithm (andyc/symbolic/aba.py), no M; then the "
                        "power of each element that does work into G[NV:], as `dynamics`. M is left as it is.",
    "dynamics_constraints": "`dynamics` and `constraints_into` in one pass that shares their subexpressions.",
    "constraints_into": "phi (NH,), c (NC,: dphi/dt, then the nonholonomic rows), A = dc/dv (NC, NV), kappa "
                        "(NC,) with dc/dt = A dv/dt + kappa (ANDY eq. 11), into the rows of the scratch S "
                        "(andyc_numerics/layout.py).",
    "signal_rates": "Rates of the nonholonomic signals (ANDY eq. 4) into xdot[NQ + NV:].",
    "energy": "Total mechanical energy: kinetic + gravity + springs + potentials.",
    "power": "Power of the non-conservative elements (forces, torques, dampers).",
    "frame_poses": "Pose of each of FRAMES in world into out (len(FRAMES), 12): origin, then rotation row by row.",
    "constraint_gains": "Soft-constraint gains K_s and K_d of each row (ANDY eq. 13-15), for the baumgarte method, "
                        "into S.",
    "restitution": "Coefficient of restitution of each jump's impact (a contact's slip end: its friction mu), then each "
                   "joint friction's force, into S.",
    "guard": "The guard of jump k: it happens where this crosses zero in JUMP_DIRECTION[k]; lam: the multipliers of "
             "its source flow (read when JUMP_MULTIPLIERS[k]).",
    "guard_rate": "d/dt of the guard of jump k, given xdot.",
    "enabled": "Enabling condition of jump k: >= 0 where it may happen; lam as in guard.",
    "reset": "Resets of jump k, into x and d, all from the values before the jump.",
    "flow_inputs": "Input values a flow sets, into U (NF, NU); other entries are left as they are.",
    "energy_law": "The declared energy law Phi_e(t, q, v) of flow k (Braun & Goldfarb eq. 5-6): returns its value and "
                  "writes dPhi_e/dv into grad[:NV]; NaN where the flow keeps the built-in law E - E0 - W (with prescribed "
                  "motion: E - W, the state x followed by the work, and dE/dv = M v + a_t).",
    "drive_power": "The power that drives the links depending on t (andyc/symbolic/work.py), from dv/dt in "
                   "xdot[NQ:NQ + NV], into xdot[NX + its work slot].",
    "closed_form": "x(t), the exact solution the model declares (closed_form:), at held inputs u and parameters p.",
    "model_inputs": "The inputs as the model drives them (INPUT_EXPRESSIONS in the module), as an input callback: "
                    "the flow's held values from data[flow * NU:], then each expression the flow does not override.",
}


def state_names(spec) -> list:
    """The names of x, in order: coordinates, speeds (coordinate rates, then declared), signals."""
    return [c.name for c in spec.coordinates] + spec.speed_names + [s.name for s in spec.signals]


def _unpack(model: SymbolicModel, used: set) -> list[str]:
    states = model.q + model.v + model.signals
    lines = [f"{s} = x[{i}]" for i, s in enumerate(states) if s in used]
    for array, symbols in (("p", model.parameters), ("u", model.inputs), ("d", model.discrete)):
        lines += [f"{s} = {array}[{i}]" for i, s in enumerate(symbols) if s in used]
    nq = len(model.q)
    lines += [f"{s} = xdot[{nq + i}]" for i, s in enumerate(model.hybrid.vdot) if s in used]
    lines += [f"{s} = lam[{i}]" for i, s in enumerate(model.hybrid.multipliers) if s in used]
    return lines


def _code(model, body, returns: str | None, indent: int) -> list[str]:
    pad = " " * indent
    lines = [pad + line for line in _unpack(model, body.inputs)]
    lines += [f"{pad}{target} = {code}" for target, code in body.lines + body.outputs]
    if returns is not None:
        lines.append(f"{pad}return {returns}")
    return lines or [f"{pad}return None"]


def _c(model, body, returns: str | None, indent: int) -> list[str] | None:
    """The body in C (andyc.codegen.c_leaves), or None where it has none."""
    try:
        return c_lines(_unpack(model, body.inputs), body, returns, indent)
    except NoC:
        return None


class Deferred:
    """A leaf's lines of Python, made when first iterated (the template reads them only for the leaves that are
    not in C)."""

    def __init__(self, make):
        self._make, self._lines = make, None

    def __iter__(self):
        if self._lines is None:
            self._lines = list(self._make())
        return iter(self._lines)


class Leaves:
    """The leaves of one model: `functions` ({decorator, name, args, doc, code} each, for the template) and the
    operation count of each (`operations`)."""

    def __init__(self, model: SymbolicModel):
        self.model, self.pool = model, dict(model.assignments)
        self.functions, self.operations = [], {}

    def add(self, name, args, outputs, returns=None):
        body = function_body(outputs, self.pool)
        self._append(name, args, Deferred(lambda: _code(self.model, body, returns, 4)), body.operations,
                     c=_c(self.model, body, returns, 4))

    def add_per_jump(self, name, args, bodies, fallback):
        """A leaf over the jumps: `bodies` holds (outputs, returns) of each jump, in order."""
        made, c, operations = [], [], 0
        for k, (outputs, returns) in enumerate(bodies):
            body = function_body(outputs, self.pool)
            made.append((k, body, returns))
            branch = _c(self.model, body, returns or ("" if fallback == "None" else None), 8)
            c = None if c is None or branch is None else c + [f"    if (k == {k}) {{", *branch, "    }"]
            operations += body.operations
        end = "    return;" if fallback == "None" else f"    return {fallback};"
        code = Deferred(lambda: [line for k, body, returns in made
                                 for line in (f"    if k == {k}:", *_code(self.model, body, returns or "None", 8))]
                        + [f"    return {fallback}"])
        self._append(name, f"k, {args}", code, operations, c=None if c is None else c + [end])

    def _append(self, name, args, code, operations, decorator=None, c=None):
        """c: the body in C, or None where it has none (then the model's leaves are all Numba's)."""
        self.functions.append({"decorator": decorator or f"leaf({name!r})", "name": name, "args": args,
                               "doc": DOCS[name], "code": code, "c": c})
        self.operations[name] = operations

    @property
    def in_c(self) -> bool:
        """Whether every leaf has C (the input callback model_inputs stays Numba's in either backend)."""
        return all(f["c"] is not None for f in self.functions if f["name"] != "model_inputs")


def _flat(array: str, width: int):
    """The target `array[row, column]` of a leaf, which indexes its arrays flat, row-major (as C pointers)."""
    return lambda row, column: f"{array}[{row * width + column}]"


def leaves(model: SymbolicModel) -> Leaves:
    """Every leaf `model` has, with the input callback of the inputs it drives by an expression."""
    out = Leaves(model)
    n, cons, spec = model.dof, model.constraints, model.spec
    mass = [(f"M[{i * n + j}]", model.M[i, j]) for i in range(n) for j in range(i, n)]
    mirror = [(f"M[{j * n + i}]", sp.Symbol(f"M[{i * n + j}]")) for i in range(n) for j in range(i + 1, n)]
    force = [(f"G[{i}]", model.G[i]) for i in range(n)] + [(f"G[{n + i}]", e) for i, e in enumerate(model.powers)]
    at = scratch_layout(n, cons.nc, len(model.hybrid.jumps) + len(spec.joint_frictions))      # the rows of S
    S = _flat("S", at["width"])
    rows = ([(S(at['phi'], i), e) for i, e in enumerate(cons.phi)]
            + [(S(at['cv'], i), e) for i, e in enumerate(cons.c)]
            + [(S(at['A'] + i, j), cons.A[i, j]) for i in range(cons.nc) for j in range(n)]
            + [(S(at['kappa'], i), e) for i, e in enumerate(cons.kappa)])
    out.add("dynamics", f"{STATE}, M, G", mass + force + mirror)
    if model.forward is not None and model.forward.chosen == ABA:
        out.pool.update(model.aba.assignments)
        out.add("forward_dynamics", f"{STATE}, M, G",
                [(f"G[{i}]", e) for i, e in enumerate(model.aba.vdot)] + force[n:])
    out.add("energy", STATE, [("e", model.energy)], returns="e")
    out.add("power", STATE, [("w", model.power)], returns="w")
    frames = list(model.frame_positions)
    out.add("frame_poses", f"{STATE}, out",
            [(f"out[{12 * k + i}]", model.frame_positions[f][i]) for k, f in enumerate(frames) for i in range(3)]
            + [(f"out[{12 * k + 3 + 3 * i + j}]", model.frame_rotations[f][i, j])
               for k, f in enumerate(frames) for i in range(3) for j in range(3)])
    if model.signals:
        nq = len(model.q)
        out.add("signal_rates", f"{STATE}, xdot", [(f"xdot[{nq + n + i}]", r) for i, r in enumerate(model.signal_rates)])
    if cons.nc:
        out.add("dynamics_constraints", f"{STATE}, M, G, S", mass + force + rows + mirror)
        out.add("constraints_into", f"{STATE}, S", rows)
        out.add("constraint_gains", "p, S", [(S(at['ks'], i), e) for i, e in enumerate(cons.stiffness)]
                + [(S(at['kd'], i), e) for i, e in enumerate(cons.damping)])
    _hybrid(out, model, at)
    coefficients = [j.restitution for j in model.hybrid.jumps] + [d.coefficient for d in spec.joint_frictions]
    if coefficients:
        S = _flat("S", at["width"])
        out.add("restitution", "p, S", [(S(at['e'], k), e) for k, e in enumerate(coefficients)])
    _energy_law(out, model)
    if model.prescribed:
        slot, a, b = model.prescribed
        nx = len(model.q) + n + len(model.signals)
        out.add("drive_power", f"{STATE}, xdot",
                [(f"xdot[{nx + slot}]", b + sum((a[i] * model.hybrid.vdot[i] for i in range(n)), sp.Integer(0)))])
    if spec.closed_form:
        out.add("closed_form", "t, u, p, x", [(f"x[{i}]", spec.closed_form[name]) for i, name in enumerate(state_names(spec))])
    _inputs(out, model)
    return out


def _hybrid(out: Leaves, model: SymbolicModel, at: dict) -> None:
    h = model.hybrid
    if any(h.flow_inputs):
        nu = len(model.inputs)
        out.add("flow_inputs", "p, U", [(f"U[{f * nu + i}]", e) for f, inputs in enumerate(h.flow_inputs)
                                         for i, e in inputs.items()])
    if not h.jumps:
        return
    spec, nq = model.spec, len(model.q)
    index = {**{c.name: f"x[{i}]" for i, c in enumerate(spec.coordinates)},
             **{name: f"x[{nq + i}]" for i, name in enumerate(spec.speed_names)},
             **{x.name: f"d[{i}]" for i, x in enumerate(spec.discrete)}}
    out.add_per_jump("guard", f"{STATE}, lam", [([("g", j.guard)], "g") for j in h.jumps], "0.0")
    out.add_per_jump("guard_rate", f"{STATE}, xdot", [([("g", j.guard_rate)], "g") for j in h.jumps], "0.0")
    out.add_per_jump("enabled", f"{STATE}, lam", [([("e", j.enabled)], "e") for j in h.jumps], "1.0")
    out.add_per_jump("reset", STATE, [([(index[s], e) for s, e in j.resets], None) for j in h.jumps], "None")


def _energy_law(out: Leaves, model: SymbolicModel) -> None:
    """energy_law(k, STATE, grad): one branch per flow with a declared law (andyc.spec.energy_law), each with its own
    cse; a model without one uses the stub (NaN: the built-in law, which the numerics evaluate with dE/dv = M v).
    A model with prescribed motion (links that depend on t) has the kinetic term a_t . v too, so dE/dv = M v + a_t:
    its flows with the built-in law return E - W (W the work slots after x) and that gradient."""
    if not any(model.energy_laws) and not model.prescribed:
        return
    code, c, operations = [], [], 0
    n = model.dof
    nx, nw = len(model.q) + n + len(model.signals), len(model.work_names)
    for k, law in enumerate(model.energy_laws or [None] * len(model.hybrid.flows)):
        if law is None and not model.prescribed:
            continue
        if law is None:
            a = model.prescribed[1]
            value, grad = model.energy, [sum(model.M[i, j] * model.v[j] for j in range(n)) + a[i] for i in range(n)]
        else:
            value, grad = law
        body = function_body([("g", value)] + [(f"grad[{i}]", e) for i, e in enumerate(grad)], out.pool)
        code += [f"    if k == {k}:", *_code(model, body, None, 8)]
        if law is None:
            code += ["        for i in range(NW):", "            g -= x[NX + i]"]
        code += ["        return g"]
        branch = _c(model, body, None, 8)
        if c is not None and branch is not None:
            work = [f"        for (int i = 0; i < {nw}; i++) e -= x[{nx} + i];"] if law is None else []
            c += [f"    if (k == {k}) {{", *branch, "        double e = g;", *work, "        return e;", "    }"]
        else:
            c = None
        operations += body.operations
    out._append("energy_law", f"k, {STATE}, grad", code + ["    return math.nan"], operations,
                c=None if c is None else c + ["    return NAN;"])


def _inputs(out: Leaves, model: SymbolicModel) -> None:
    """model_inputs, the input callback (andyc_numerics/model.py) of the inputs the model drives by an expression:
    the flow's held values from data, then each expression, unless the flow sets that input itself."""
    driven = model.spec.driven_inputs
    if not driven:
        return
    names = list(model.spec.inputs)
    code, operations = ["    for i in range(NU):", "        u[i] = data[flow * NU + i]"], 0
    for name, expr in driven.items():
        i = names.index(name)
        body = function_body([(f"u[{i}]", expr)], out.pool)
        code += [f"    if not FLOW_SETS_INPUT[flow, {i}]:", *_code(model, body, None, 8)]
        operations += body.operations
    out._append("model_inputs", "t, x, d, p, flow, u, data", code + ["    return 0"], operations, "input_callback")
