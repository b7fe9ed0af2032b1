"""SymbolicModel -> build/<name>/<name>.py.

The math goes through `function_body` (cse + ordering); the template only
wraps it. The build key hashes the spec, the andyc version and the sources of
the stages that shape the generated code, so a rebuild is skipped exactly
when nothing that matters changed.
"""

from __future__ import annotations

import ast
import hashlib
import math
import pprint
import time
from dataclasses import dataclass, field
from pathlib import Path

import jinja2
import sympy as sp

import andyc
from andyc.errors import format_path
from andyc.outputs import check_output, create_once, write_text
from andyc.codegen.printer import function_body, to_code
from andyc.symbolic.model import SymbolicModel

PACKAGE = Path(__file__).resolve().parents[1]
TEMPLATES = PACKAGE / "templates"
_GENERATOR_SOURCES = ["symbolic", "codegen", "spec", "templates", "schemas"]


@dataclass
class BuildResult:
    name: str
    module_path: Path
    skipped: bool
    build_key: str
    timings: dict = field(default_factory=dict)     # seconds per stage
    operations: dict = field(default_factory=dict)  # function -> sympy op count
    jumps_path: Path | None = None                  # the user's <name>_jumps.py, when the model has jumps
    jumps_kept: bool = False                        # it existed and was left as it was
    jumps_missing: list = field(default_factory=list)  # jumps without a function in a kept file
    compiled: int = 0                               # functions Numba compiled (not loaded from its cache)


def generator_fingerprint() -> str:
    h = hashlib.sha256(andyc.__version__.encode())
    for rel in _GENERATOR_SOURCES:
        for path in sorted((PACKAGE / rel).rglob("*")):
            if path.suffix in (".py", ".j2", ".json") and path.is_file():
                h.update(path.relative_to(PACKAGE).as_posix().encode())
                h.update(path.read_bytes())
    return h.hexdigest()


def build_key(spec_sha256: str) -> str:
    return hashlib.sha256((spec_sha256 + generator_fingerprint()).encode()).hexdigest()


def module_path(out_dir, name: str) -> Path:
    return Path(out_dir) / name / f"{name}.py"


def module_name(name: str, key: str) -> str:
    """The name a generated module takes in sys.modules, one per build (see MODULE_NAME in the template)."""
    return f"andyc_{name}_{key[:16]}"


def existing_build_key(path: Path) -> str | None:
    """The BUILD_KEY line of a generated module, read without importing it."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if line.startswith("BUILD_KEY = "):
                    key = ast.literal_eval(line.split("=", 1)[1].strip())
                    return key if isinstance(key, str) else None
    except (OSError, ValueError, SyntaxError):
        return None
    return None


def _unpack(model: SymbolicModel, used: set) -> list[str]:
    states = model.q + model.v + model.signals
    lines = [f"{s} = x[{i}]" for i, s in enumerate(states) if s in used]
    for array, symbols in (("p", model.parameters), ("u", model.inputs), ("d", model.discrete)):
        lines += [f"{s} = {array}[{i}]" for i, s in enumerate(symbols) if s in used]
    nq = len(model.q)
    lines += [f"{s} = xdot[{nq + i}]" for i, s in enumerate(model.hybrid.vdot) if s in used]
    return lines


def _parameter_unpack(model: SymbolicModel, exprs: list) -> str:
    """Lines reading from p the parameters `exprs` use (for the initial-value functions)."""
    used = set().union(*(e.free_symbols for e in exprs))
    return "\n".join(f"    {s} = p[{i}]" for i, s in enumerate(model.parameters) if s in used)


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
        k = inputs.index(name)
        out.append(_function(model, pool, f"input_{k}_{name}", "t, x, p, d",
                             f"Input {name}, as the model drives it: INPUT_EXPRESSIONS[{name!r}].", [("v", expr)],
                             returns="v"))
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
    states = [c.name for c in spec.coordinates] + spec.speed_names + [s.name for s in spec.signals]
    body = function_body([(f"x[{i}]", spec.closed_form[name]) for i, name in enumerate(states)], {})
    return {"unpack": _unpack(model, body.inputs), "lines": body.lines, "outputs": body.outputs,
            "where": [[spec.source.line(("closed_form", name)), format_path(("closed_form", name))]
                      for name in states]}


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
    """The module's source text and the operation count of each function."""
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
    initial = ([c.initial for c in spec.coordinates] + [c.velocity for c in spec.coordinates]
               + [s.initial for s in spec.speeds] + [s.initial for s in spec.signals])
    values = [to_code(e) for e in initial]
    # Each quaternion signal: the index of its w component in x.
    nx_before = len(model.q) + n
    quaternions = [nx_before + i for i, s in enumerate(spec.signals) if s.component == "qw"]
    discrete = [x.initial for x in spec.discrete]
    operations = {f["name"]: f["operations"] for f in functions}
    context = {
        "version": andyc.__version__, "source": Path(spec.file).name, "spec_sha256": spec.sha256,
        "build_key": key, "name": spec.name, "module_name": module_name(spec.name, key),
        "description": spec.description or "",
        "coordinates": [c.name for c in spec.coordinates],
        "speeds": spec.speed_names,
        "signals": [s.name for s in spec.signals],
        "quaternions": quaternions,
        "parameters": list(spec.parameters),
        "parameter_defaults": [v for _, v in spec.parameters.values()],
        "inputs": list(spec.inputs),
        "input_defaults": [v for _, v in spec.inputs.values()],
        "input_expressions": spec.input_expressions,
        "driven_inputs": [{"index": list(spec.inputs).index(n), "function": f"input_{list(spec.inputs).index(n)}_{n}"}
                          for n in spec.driven_inputs],
        "frames": frames, "operations": operations,
        "frame_parents": [next(f.parent for f in spec.frames if f.name == name) for name in frames],
        "nh": cons.nh, "nc": cons.nc, "constraint_rows": cons.rows, "multipliers": cons.multipliers,
        "constraint_gains": [(c.name, "holonomic" if c.holonomic else "nonholonomic",
                              _gain_parameter(spec, c.stiffness), _gain_parameter(spec, c.damping))
                             for c in spec.constraints],
        "conserves_energy": spec.conserves_energy,
        "constraint_where": [[spec.source.line(w), format_path(w)] for c in spec.constraints for w in c.row_where],
        "initial": {"unpack": _parameter_unpack(model, initial), "state": values},
        "initial_discrete": {"unpack": _parameter_unpack(model, discrete), "values": [to_code(e) for e in discrete]},
        "discrete": [x.name for x in spec.discrete],
        "closed_form": _closed_form(model),
        **_hybrid_context(model),
        "functions": functions,
    }
    return _environment().get_template("module.py.j2").render(**context), operations


def _gain_parameter(spec, gain) -> str | None:
    """The parameter a Baumgarte gain is, if it is one (then a scan can set it), else None."""
    return next((name for name, (symbol, _) in spec.parameters.items() if gain == symbol), None)


def literal(value) -> str:
    """Python source of plain data (text, finite numbers, booleans, None, and lists, tuples and dicts of
    them), written by repr (pprint's, for long values). The templates write every value through this (`| py`), and text from a model
    file reaches a generated file only this way: as a literal that reads back equal, never as code, and
    never inside a comment or docstring, where a quote, a backslash or a line break could end it."""
    _check_plain(value)
    return pprint.pformat(value, width=110, sort_dicts=False)


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
    states = ([c.name for c in spec.coordinates] + spec.speed_names + [s.name for s in spec.signals])
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


def jumps_path(out_dir, name: str) -> Path:
    return Path(out_dir) / name / f"{name}_jumps.py"


def generate(model: SymbolicModel, out_dir="build") -> BuildResult:
    """Write the module for `model` into out_dir/<name>/ (always; see pipeline.build for skipping),
    and the jump template <name>_jumps.py unless it exists (it is the user's). Both are written whole
    (andyc.outputs); OutputError, before anything is written, when either would overwrite a model file."""
    start = time.perf_counter()
    spec = model.spec
    path = module_path(out_dir, spec.name)
    jumps = jumps_path(out_dir, spec.name) if spec.jumps else None
    for target in (path, jumps):
        if target is not None:
            check_output(target, spec.files, "generated module" if target == path else "jumps file")
    key = build_key(spec.sha256)
    source, operations = render(model, key)
    write_text(path, source)
    result = BuildResult(spec.name, path, False, key, {"generate": time.perf_counter() - start}, operations)
    if jumps is not None:
        result.jumps_path = jumps
        result.jumps_kept = not create_once(jumps, render_jumps(model))
        if result.jumps_kept:
            text = jumps.read_text(encoding="utf-8", errors="replace")
            result.jumps_missing = [j.name for j in spec.jumps if f"def {j.name}(" not in text]
    return result
