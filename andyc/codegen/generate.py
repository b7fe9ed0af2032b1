"""SymbolicModel -> build/<name>/<name>.py.

The math goes through `function_body` (cse + ordering); the templates only
wrap it. A build is two files: <name>_equations.py, all that Numba compiles,
which depends only on what shapes the equations, and <name>.py, which loads it
and holds the runtime data (defaults, initial values, the description). The
build key hashes what shapes the equations (andyc.spec.meaning), the andyc
version and the sources of the stages that shape the generated code, so that
derivation is skipped exactly when nothing that matters changed, and an edit
of runtime data rewrites <name>.py only, leaving Numba's cache valid.
"""

from __future__ import annotations

import math
import pprint
import time
from pathlib import Path

import jinja2
import sympy as sp

import andyc
from andyc.errors import format_path
from andyc.outputs import check_output, create_once, update_text, write_text
from andyc.codegen.buildfiles import (PACKAGE, BuildResult, build_key, equations_path, jumps_path, module_name,
                                     module_path)
from andyc.codegen.printer import function_body, to_code
from andyc.symbolic.model import SymbolicModel

TEMPLATES = PACKAGE / "templates"


def _unpack(model: SymbolicModel, used: set) -> list[str]:
    states = model.q + model.v + model.signals
    lines = [f"{s} = x[{i}]" for i, s in enumerate(states) if s in used]
    for array, symbols in (("p", model.parameters), ("u", model.inputs), ("d", model.discrete)):
        lines += [f"{s} = {array}[{i}]" for i, s in enumerate(symbols) if s in used]
    nq = len(model.q)
    lines += [f"{s} = xdot[{nq + i}]" for i, s in enumerate(model.hybrid.vdot) if s in used]
    return lines


def _parameter_unpack(parameters: list, exprs: list) -> str:
    """Lines reading from p the parameters (symbols, in order) that `exprs` use (for the initial values)."""
    used = set().union(*(e.free_symbols for e in exprs))
    return "\n".join(f"    {s} = p[{i}]" for i, s in enumerate(parameters) if s in used)


def _function(model, pool, name, args, doc, outputs, returns=None):
    body = function_body(outputs, pool)
    return {"name": name, "args": args, "doc": doc, "unpack": _unpack(model, body.inputs),
            "lines": body.lines, "outputs": body.outputs, "returns": returns, "operations": body.operations}


def _hybrid_functions(model: SymbolicModel, pool: dict) -> list:
    """One guard, guard rate, enabling condition and reset function per jump; restitutions; flow inputs."""
    nq = len(model.q)
    index = {**{c.name: f"x[{i}]" for i, c in enumerate(model.spec.coordinates)},
             **{name: f"x[{nq + i}]" for i, name in enumerate(model.spec.speed_names)},
             **{x.name: f"d[{i}]" for i, x in enumerate(model.spec.discrete)}}
    out = []
    for k, j in enumerate(model.hybrid.jumps):
        arrow = f"jump '{j.name}' ({model.hybrid.flows[j.source]} -> {model.hybrid.flows[j.target]})"
        key = _jump_key(k, j.name)
        out += [
            _function(model, pool, f"guard_{key}", "t, x, u, p, d", f"Guard of {arrow}.",
                      [("g", j.guard)], returns="g"),
            _function(model, pool, f"guard_rate_{key}", "t, x, u, p, d, xdot",
                      f"d/dt of the guard of {arrow}, given xdot.", [("g", j.guard_rate)], returns="g"),
            _function(model, pool, f"enabled_{key}", "t, x, u, p, d",
                      f"Enabling condition of {arrow}: >= 0 where it may happen.", [("e", j.enabled)], returns="e"),
            _function(model, pool, f"reset_{key}", "t, x, u, p, d",
                      f"Resets of {arrow}, all from the values before the jump.",
                      [(index[name], e) for name, e in j.resets], returns="None"),
        ]
    out.append(_function(model, pool, "restitution", "p, e", "Coefficient of restitution of each jump's impact.",
                         [(f"e[{k}]", j.restitution) for k, j in enumerate(model.hybrid.jumps)]))
    inputs = list(model.spec.inputs)
    for name, expr in model.spec.driven_inputs.items():
        out.append(_function(model, pool, _input_function(inputs, name), "t, x, p, d",
                             f"Input {name}, as the model drives it (INPUT_EXPRESSIONS in {model.spec.name}.py).",
                             [("v", expr)], returns="v"))
    out.append(_function(model, pool, "flow_inputs", "p, U",
                         "Input values a flow sets, into U (flows, inputs); other entries are left as they are.",
                         [(f"U[{f}, {i}]", e) for f, inputs in enumerate(model.hybrid.flow_inputs)
                          for i, e in inputs.items()]))
    return out


def _jump_key(k: int, name: str) -> str:
    """The part of jump k's function names after guard_, reset_, ...: its index keeps them apart (jumps 'x'
    and 'rate_x' would both give guard_rate_x), its name keeps them readable."""
    return f"{k}_{name}"


def _closed_form(model: SymbolicModel) -> dict | None:
    """The body of closed_form(t, u, p) -> x, the exact solution the model declares; None without one.

    Its expressions use only t, parameters and inputs, so no intermediate of the pool is needed; cse
    still shares the repeated parts (sqrt(k/m), the sine and cosine of w t).
    """
    spec = model.spec
    if not spec.closed_form:
        return None
    states = _state_names(spec)
    body = function_body([(f"x[{i}]", spec.closed_form[name]) for i, name in enumerate(states)], {})
    return {"unpack": _unpack(model, body.inputs), "lines": body.lines, "outputs": body.outputs}


def _padded(rows: list[list[int]], width: int) -> list:
    """The entries of a (len(rows), width) int64 array, -1 past each row's entries."""
    return [r + [-1] * (width - len(r)) for r in rows]


def _hybrid_context(model: SymbolicModel) -> dict:
    h, nc = model.hybrid, model.constraints.nc
    nh = model.constraints.nh
    return {
        "flows": h.flows, "initial_flow": h.initial,
        "flow_sets_input": [[i in inputs for i in range(len(model.inputs))] for inputs in h.flow_inputs],
        "flow_rows": _padded(h.flow_rows, nc), "flow_nrows": [len(r) for r in h.flow_rows],
        "flow_nhrows": [sum(1 for i in r if i < nh) for r in h.flow_rows],
        "jumps": [{"name": j.name, "key": _jump_key(k, j.name), "source": j.source, "target": j.target, "direction": j.direction,
                   "priority": j.priority, "impact": bool(j.impact_rows),
                   "source_name": h.flows[j.source], "target_name": h.flows[j.target]} for k, j in enumerate(h.jumps)],
        "impact_rows": _padded([j.impact_rows for j in h.jumps], nc),
        "impact_nrows": [len(j.impact_rows) for j in h.jumps],
    }


def render(model: SymbolicModel, key: str) -> tuple[str, dict]:
    """The text of <name>_equations.py (everything Numba compiles: it depends only on what the equations
    depend on) and the operation count of each function."""
    spec = model.spec
    pool = dict(model.assignments)
    n = model.dof
    mass = [(f"M[{i}, {j}]", model.M[i, j]) for i in range(n) for j in range(i, n)]
    mirror = [(f"M[{j}, {i}]", sp.Symbol(f"M[{i}, {j}]")) for i in range(n) for j in range(i + 1, n)]
    frames = list(model.frame_positions)
    cons = model.constraints
    # Into the rows of the scratch S that the constrained solves index directly (no views).
    constraint_outputs = ([(f"S[S_PHI, {i}]", e) for i, e in enumerate(cons.phi)]
                          + [(f"S[S_CV, {i}]", e) for i, e in enumerate(cons.c)]
                          + [(f"S[S_A + {i}, {j}]", cons.A[i, j]) for i in range(cons.nc) for j in range(n)]
                          + [(f"S[S_KAPPA, {i}]", e) for i, e in enumerate(cons.kappa)])
    functions = [
        _function(model, pool, "dynamics", "t, x, u, p, d, M, G",
                  "Fill the mass matrix M (NV, NV) and generalized force G (NV,): M dv/dt = G (eq. 8).",
                  mass + [(f"G[{i}]", model.G[i]) for i in range(n)]),
        _function(model, pool, "energy", "t, x, u, p, d",
                  "Total mechanical energy: kinetic + gravity + springs + potentials.",
                  [("e", model.energy)], returns="e"),
        _function(model, pool, "power", "t, x, u, p, d",
                  "Power of the non-conservative elements (forces, torques, dampers).",
                  [("w", model.power)], returns="w"),
        _function(model, pool, "signal_rates", "t, x, u, p, d, xdot",
                  "Rates of the nonholonomic signals (eq. 4) into xdot[NQ + NV:].",
                  [(f"xdot[{len(model.q) + n + i}]", r) for i, r in enumerate(model.signal_rates)]),
        _function(model, pool, "constraints_into", "t, x, u, p, d, S",
                  "Constraint residuals phi (NH,), velocity residuals c = A v + b (NC,), their Jacobian A "
                  "(NC, NV) and kappa (NC,), with dc/dt = A dv/dt + kappa (ANDY eq. 11), into the scratch S "
                  "(views: terms(S)).",
                  constraint_outputs),
        _function(model, pool, "constraint_gains", "p, ks, kd",
                  "Soft-constraint gains K_s and K_d of each row (ANDY eq. 13-15), for the baumgarte method.",
                  [(f"ks[{i}]", e) for i, e in enumerate(cons.stiffness)]
                  + [(f"kd[{i}]", e) for i, e in enumerate(cons.damping)]),
        _function(model, pool, "frame_positions", "t, x, u, p, d, out",
                  "Origins of FRAMES in world coordinates into out (len(FRAMES), 3).",
                  [(f"out[{k}, {i}]", model.frame_positions[f][i]) for k, f in enumerate(frames) for i in range(3)]),
    ] + _hybrid_functions(model, pool)
    if cons.nc:
        functions.append(_function(
            model, pool, "dynamics_constraints", "t, x, u, p, d, M, G, S",
            "`dynamics` and `constraints_into` in one pass that shares their subexpressions (the flows with rows).",
            mass + [(f"G[{i}]", model.G[i]) for i in range(n)] + constraint_outputs))
    # M is symmetric: copy the upper triangle after it is written.
    for f in functions:
        if f["name"] in ("dynamics", "dynamics_constraints"):
            f["outputs"] += [(t, str(src)) for t, src in mirror]
    nx_before = len(model.q) + n
    quaternions = [nx_before + i for i, s in enumerate(spec.signals) if s.component == "qw"]   # index of each w
    operations = {f["name"]: f["operations"] for f in functions}
    inputs = list(spec.inputs)
    context = {
        "version": andyc.__version__, "build_key": key, "name": spec.name, "module_name": module_name(spec.name, key),
        "coordinates": [c.name for c in spec.coordinates],
        "speeds": spec.speed_names,
        "signals": [s.name for s in spec.signals],
        "quaternions": quaternions,
        "parameters": list(spec.parameters),
        "inputs": inputs,
        "driven_inputs": [{"index": inputs.index(n), "function": _input_function(inputs, n)} for n in spec.driven_inputs],
        "input_functions": {n: _input_function(inputs, n) for n in spec.driven_inputs},
        "frames": frames, "operations": operations,
        "frame_parents": [next(f.parent for f in spec.frames if f.name == name) for name in frames],
        "nh": cons.nh, "nc": cons.nc, "constraint_rows": cons.rows, "multipliers": cons.multipliers,
        "constraint_gains": [(c.name, "holonomic" if c.holonomic else "nonholonomic",
                              _gain_parameter(spec, c.stiffness), _gain_parameter(spec, c.damping))
                             for c in spec.constraints],
        "conserves_energy": spec.conserves_energy,
        "discrete": [x.name for x in spec.discrete],
        "closed_form": _closed_form(model),
        **_hybrid_context(model),
        "functions": functions,
    }
    return _environment().get_template("equations.py.j2").render(**context), operations


def render_front(spec, key: str) -> str:
    """The text of <name>.py: it loads <name>_equations.py (of the build `key`) and holds the model's
    runtime data, which the equations do not depend on (andyc.spec.meaning): the defaults, the initial
    values (as code: they are expressions of the parameters), the description and where each
    constraint row and closed-form state is written in the model file. Needs only the Spec, so that
    a build whose equations are unchanged rewrites it without deriving."""
    parameters = [symbol for symbol, _ in spec.parameters.values()]
    initial = ([c.initial for c in spec.coordinates] + [c.velocity for c in spec.coordinates]
               + [s.initial for s in spec.speeds] + [s.initial for s in spec.signals])
    discrete = [x.initial for x in spec.discrete]
    states = _state_names(spec)
    return _environment().get_template("module.py.j2").render(
        version=andyc.__version__, name=spec.name, build_key=key, module_name=module_name(spec.name, key),
        source=Path(spec.file).name, source_path=str(Path(spec.file).resolve()), spec_sha256=spec.sha256,
        spec_files=[str(Path(f).resolve()) for f in spec.files], meaning_sha256=spec.meaning_sha256,
        description=spec.description or "",
        coordinates=[c.name for c in spec.coordinates], speeds=spec.speed_names,
        signals=[s.name for s in spec.signals], constrained=bool(spec.constraints),
        jumps=[j.name for j in spec.jumps], flows=[f.name for f in spec.flows],
        parameter_defaults=[v for _, v in spec.parameters.values()],
        input_defaults=[v for _, v in spec.inputs.values()], input_expressions=spec.input_expressions,
        constraint_where=[[spec.source.line(w), format_path(w)] for c in spec.constraints for w in c.row_where],
        initial={"unpack": _parameter_unpack(parameters, initial), "state": [to_code(e) for e in initial]},
        initial_discrete={"unpack": _parameter_unpack(parameters, discrete), "values": [to_code(e) for e in discrete]},
        closed_form_where=[[spec.source.line(("closed_form", n)), format_path(("closed_form", n))] for n in states]
        if spec.closed_form else [])


def _state_names(spec) -> list:
    """The names of x, in order: coordinates, speeds (coordinate rates, then declared), signals."""
    return [c.name for c in spec.coordinates] + spec.speed_names + [s.name for s in spec.signals]


def _input_function(inputs: list, name: str) -> str:
    return f"input_{inputs.index(name)}_{name}"


def _gain_parameter(spec, gain) -> str | None:
    """The parameter a Baumgarte gain is, if it is one (then a scan can set it), else None."""
    return next((name for name, (symbol, _) in spec.parameters.items() if gain == symbol), None)


def literal(value, one_line: bool = False) -> str:
    """Python source of plain data (text, finite numbers, booleans, None, and lists, tuples and dicts of
    them), written by repr (pprint's, for long values, unless `one_line`: `| py(true)`, for the constants
    that buildfiles.written_constant reads line by line). The templates write every value through this
    (`| py`), and text from a model file reaches a generated file only this way: as a literal that reads
    back equal, never as code, and never inside a comment or docstring, where a quote, a backslash or a
    line break could end it."""
    _check_plain(value)
    return repr(value) if one_line else pprint.pformat(value, width=110, sort_dicts=False)


def _check_plain(value) -> None:
    if isinstance(value, float) and not math.isfinite(value):
        raise ValueError(f"{value!r} has no literal in generated code")
    if isinstance(value, (list, tuple)):
        for v in value:
            _check_plain(v)
    elif isinstance(value, dict):
        for k, v in value.items():
            _check_plain(k)
            _check_plain(v)
    elif not (value is None or isinstance(value, (str, bool, int, float))):
        raise TypeError(f"{type(value).__name__} is not plain data")


def _environment() -> jinja2.Environment:
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(TEMPLATES), keep_trailing_newline=True,
                             undefined=jinja2.StrictUndefined, autoescape=False)
    env.filters["py"] = literal
    return env


_DIRECTION = {-1: "falling", 0: "either", 1: "rising"}


def render_jumps(model: SymbolicModel) -> str:
    """The user's jump template: what the model file says of each jump (as data), and one documented, empty
    function per jump."""
    spec = model.spec
    jumps = {}
    for j in spec.jumps:
        w = j.written
        jumps[j.name] = {"from": j.source, "to": j.target, "guard": _plain(w["guard"]),
                         "direction": _DIRECTION[j.direction], "enabled": _plain(w.get("enabled")),
                         "reset": _plain(w.get("reset") or {}), "impact": _plain(w.get("impact", "none"))}
    states = _state_names(spec)
    return _environment().get_template("jumps.py.j2").render(
        name=spec.name, version=andyc.__version__, source=Path(spec.file).name, jumps=jumps, states=states,
        discrete=[x.name for x in spec.discrete], parameters=list(spec.parameters), inputs=list(spec.inputs))


def _plain(value):
    """A value of the model file as plain data for `literal` (numbers and text as they are, anything else
    as its text)."""
    if value is None or isinstance(value, (str, bool, int)) or (isinstance(value, float) and math.isfinite(value)):
        return value
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    return str(value)


def write_front(spec, out_dir, key: str) -> bool:
    """Write <name>.py (render_front) unless it holds that text already; True when written."""
    path = module_path(out_dir, spec.name)
    check_output(path, spec.files, "generated module")
    return update_text(path, render_front(spec, key))


def generate(model: SymbolicModel, out_dir="build", force: bool = False) -> BuildResult:
    """Write the build of `model` into out_dir/<name>/: <name>_equations.py, <name>.py, and the jump
    template <name>_jumps.py unless it exists (it is the user's); see pipeline.build for when this is
    skipped. A file that would get the text it has is left as it is (its time stamp, which Numba's cache
    checks, included), unless `force` (then Numba compiles again). Each is written whole (andyc.outputs);
    OutputError, before anything is written, when one would overwrite a model file."""
    start = time.perf_counter()
    spec = model.spec
    path, equations = module_path(out_dir, spec.name), equations_path(out_dir, spec.name)
    jumps = jumps_path(out_dir, spec.name) if spec.jumps else None
    for target, what in ((path, "generated module"), (equations, "generated module"), (jumps, "jumps file")):
        if target is not None:
            check_output(target, spec.files, what)
    key = build_key(spec.meaning_sha256)
    source, operations = render(model, key)
    (write_text if force else update_text)(equations, source)
    write_front(spec, out_dir, key)
    result = BuildResult(spec.name, path, False, key, {"generate": time.perf_counter() - start}, operations)
    if jumps is not None:
        result.jumps_path = jumps
        result.jumps_kept = not create_once(jumps, render_jumps(model))
        if result.jumps_kept:
            text = jumps.read_text(encoding="utf-8", errors="replace")
            result.jumps_missing = [j.name for j in spec.jumps if f"def {j.name}(" not in text]
    return result
