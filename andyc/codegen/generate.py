"""SymbolicModel -> build/<name>/.

The math goes through the leaves (andyc.codegen.leaves: cse + ordering); the
templates only wrap it. A build is three parts: <name>_equations.py, the
model's leaves, all that Numba compiles of the model, which depends only on
what shapes the equations; <name>.py, which loads it and holds the runtime
data (defaults, initial values, the description); and andyc_numerics/, a copy
of andyc/numerics, the algorithms every model shares. The build key hashes
what shapes the equations (andyc.spec.meaning), the andyc version and the
sources of the stages that shape the generated code, so that derivation is
skipped exactly when nothing that matters changed, and an edit of runtime data
rewrites <name>.py only, leaving Numba's cache valid.
"""

from __future__ import annotations

import math
import pprint
import time
import warnings
from pathlib import Path

import jinja2

import andyc
from andyc.errors import format_path
from andyc.outputs import check_output, create_once, update_text, write_text
from andyc.codegen.buildfiles import (PACKAGE, BuildResult, build_key, equations_path, jumps_path, module_name,
                                     module_path, numerics_package, recorded_path, write_numerics)
from andyc.codegen import c_leaves
from andyc.codegen.leaves import leaves, state_names
from andyc.codegen.printer import to_code
from andyc.numerics.compiler import library_file
from andyc.spec.display import display
from andyc.symbolic.formulation import ABA, LTDL, choose, pattern_of, tree_of
from andyc.symbolic.model import SymbolicModel
from andyc.symbolic import sparse_rows

TEMPLATES = PACKAGE / "templates"


def _parameter_unpack(parameters: list, exprs: list) -> str:
    """Lines reading from p the parameters (symbols, in order) that `exprs` use (for the initial values)."""
    used = set().union(*(e.free_symbols for e in exprs))
    return "\n".join(f"    {s} = p[{i}]" for i, s in enumerate(parameters) if s in used)


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
        "jumps": [{"name": j.name, "source": j.source, "target": j.target, "direction": j.direction,
                   "priority": j.priority} for j in h.jumps],
        "impact_rows": _padded([j.impact_rows for j in h.jumps], nc),
        "impact_nrows": [len(j.impact_rows) for j in h.jumps],
        "jump_multipliers": [j.uses_multipliers for j in h.jumps],
        "jump_contact": [j.contact for j in h.jumps],
        "jump_mode_state": [j.mode_state for j in h.jumps], "jump_mode_mask": [j.mode_mask for j in h.jumps],
        "jump_kinds": [[j.kind, j.contact] for j in model.spec.jumps],
        **_contact_tables(model),
        **_friction_tables(model),
    }


def _friction_tables(model: SymbolicModel) -> dict:
    """Per joint friction (a coulomb damper): its name, the speed it acts on and its work slot; its force is the
    restitution leaf's entry NJ + i."""
    spec = model.spec
    damped = [c.name for c in spec.coordinates] + [s.name for s in spec.speeds]
    frictions = spec.joint_frictions
    return {"frictions": [d.name for d in frictions], "friction_speeds": [damped.index(d.speed) for d in frictions],
            "friction_slots": [model.work_names.index(d.name) for d in frictions]}


def _contact_tables(model: SymbolicModel) -> dict:
    """Per contact (andyc.spec.contacts): its name, gap row, stick row (spatial friction: the first of two; -1
    without friction), number of tangents, the index in d of its mode, the index of the jump whose coefficient is
    its mu (its `stop`; -1 without friction) and the index in d of its slip's direction (spatial; -1 else): what
    andyc_numerics' active.select_rows needs to add a closed contact's rows to the flow's; and per row, the work
    slot of its sliding friction's power (ROW_FRICTION: the `friction` slot on a gap row with friction, else -1)."""
    rows, contacts = model.constraints.rows, model.spec.contacts
    jump_index = {j.name: k for k, j in enumerate(model.spec.jumps)}
    discrete = [x.name for x in model.spec.discrete]
    friction = model.work_names.index("friction") if "friction" in model.work_names else -1
    row_friction = [-1] * model.constraints.nc
    for c in contacts:
        if c.friction is not None:
            row_friction[rows.index(c.constraint)] = friction
    return {"contacts": [c.name for c in contacts], "row_friction": row_friction,
            "contact_rows": [rows.index(c.constraint) for c in contacts],
            "contact_stick": [rows.index(c.stick) if c.stick else -1 for c in contacts],
            "contact_tangents": [c.tangents for c in contacts],
            "contact_mode": [discrete.index(c.mode) for c in contacts],
            "contact_mu": [jump_index[c.stop] if c.stop in jump_index else -1 for c in contacts],
            "contact_dir": [discrete.index(c.direction[0]) if c.direction else -1 for c in contacts]}


def _forward_context(model: SymbolicModel) -> dict:
    """The tree of M (when it has one) and the formulation the runtime uses (andyc.symbolic.formulation)."""
    fwd = model.forward or choose(model.M)
    tree = (fwd.parent, fwd.order) if fwd.chosen == LTDL else tree_of(pattern_of(model.M))
    parent, order = tree if tree is not None else ([], [])
    return {"formulation": fwd.chosen, "forward_operations": fwd.operations, "mass_parent": parent,
            "mass_order": order, "nt": len(order) if fwd.chosen == LTDL else 0,
            "nb": model.dof if fwd.chosen == ABA else 0}


def _constrained_context(model: SymbolicModel) -> dict:
    """The constrained solve the runtime uses and, where the sparse one applies, its tables
    (andyc.symbolic.sparse_rows; the runtime may still be asked for either, andyc_numerics/model.new_model)."""
    solve = constrained_solve(model)
    nf, nc = len(model.hybrid.flow_rows), model.constraints.nc
    applies = solve.operations.get(sparse_rows.SPARSE) is not None
    return {"constrained_solve": solve.chosen, "constrained_operations": solve.operations,
            "row_ptr": solve.row_ptr if applies else [], "row_cols": solve.row_cols if applies else [[], []],
            "flow_envelope": solve.envelopes if applies else [[[0] * nc, [0] * nc] for _ in range(nf)]}


def constrained_solve(model: SymbolicModel, force: str | None = None) -> sparse_rows.ConstrainedSolve:
    """andyc.symbolic.sparse_rows.choose for a derived model (M's and A's patterns, the tree of M, its flows)."""
    A, n = model.constraints.A, model.M.rows
    M_pattern = pattern_of(model.M)
    A_pattern = [{j for j in range(n) if A[i, j] != 0} for i in range(model.constraints.nc)]
    # (A contact's rows join the flow's at run time, in any combination: the sparse solve's envelopes are per flow.)
    slips = bool(model.spec.contacts)
    return sparse_rows.choose(M_pattern, A_pattern, tree_of(M_pattern), model.hybrid.flow_rows, slips, force)


def render(model: SymbolicModel, key: str, c: bool = False) -> tuple[str, dict, str | None]:
    """The text of <name>_equations.py (the model's leaves, everything of it that Numba compiles: it depends
    only on what the equations depend on), the operation count of each leaf, and with `c` (a C compiler
    at hand) the text of <name>_leaves.c, when every leaf has C (andyc.codegen.c_leaves), else None; then
    <name>_equations.py loads the leaves from the library of it."""
    spec = model.spec
    cons = model.constraints
    found = leaves(model)
    c_source = (c_leaves.render(spec.name, found.functions, c_leaves.parts_for(found.functions))
                if c and found.in_c else None)
    nx_before = len(model.q) + model.dof
    context = {
        "version": andyc.__version__, "build_key": key, "name": spec.name, "module_name": module_name(spec.name, key),
        "numerics": numerics_package(),
        "coordinates": [c.name for c in spec.coordinates],
        "speeds": spec.speed_names,
        "signals": [s.name for s in spec.signals],
        "quaternions": [nx_before + i for i, s in enumerate(spec.signals) if s.component == "qw"],  # each w
        "parameters": list(spec.parameters),
        "inputs": list(spec.inputs),
        "frames": list(model.frame_positions), "operations": found.operations,
        "frame_parents": [next(f.parent for f in spec.frames if f.name == name) for name in model.frame_positions],
        "nh": cons.nh, "nc": cons.nc, "constraint_rows": cons.rows, "multipliers": cons.multipliers,
        "constraint_gains": [(c.name, "holonomic" if c.holonomic else "nonholonomic",
                              _gain_parameter(spec, c.stiffness), _gain_parameter(spec, c.damping))
                             for c in spec.constraints],
        "conserves_energy": spec.conserves_energy,
        "work_slots": model.work_names, "row_work": model.row_work,
        "untracked_work": [],       # (every element's work is derived: a frame moved along t, prescribed_motion)
        "energy_laws": [law.text if law else None for law in _laws(spec)],
        "discrete": [x.name for x in spec.discrete],
        "has_closed_form": bool(spec.closed_form),
        **_hybrid_context(model),
        **_forward_context(model),
        **_constrained_context(model),
        "leaves": found.functions,
        "c_leaves": c_leaves.library_stem(spec.name, key) if c_source else None,
        "c_names": [f["name"] for f in found.functions if f["c"] is not None] if c_source else [],
    }
    return _environment().get_template("equations.py.j2").render(**context), found.operations, c_source


def render_front(spec, key: str, folder) -> str:
    """The text of <name>.py: it loads <name>_equations.py (of the build `key`) and holds the model's
    runtime data, which the equations do not depend on (andyc.spec.meaning): the defaults, the initial
    values (as code: they are expressions of the parameters), the description and where each
    constraint row and closed-form state is written in the model file. Needs only the Spec, so that
    a build whose equations are unchanged rewrites it without deriving."""
    parameters = [symbol for symbol, _ in spec.parameters.values()]
    initial = ([c.initial for c in spec.coordinates] + [c.velocity for c in spec.coordinates]
               + [s.initial for s in spec.speeds] + [s.initial for s in spec.signals])
    discrete = [x.initial for x in spec.discrete]
    states = state_names(spec)
    return _environment().get_template("module.py.j2").render(
        version=andyc.__version__, name=spec.name, build_key=key, module_name=module_name(spec.name, key),
        numerics=numerics_package(), source=Path(spec.file).name, source_path=recorded_path(spec.file, folder),
        spec_sha256=spec.sha256, spec_files=[recorded_path(f, folder) for f in spec.files], meaning_sha256=spec.meaning_sha256,
        description=spec.description or "",
        coordinates=[c.name for c in spec.coordinates], speeds=spec.speed_names,
        signals=[s.name for s in spec.signals], constrained=bool(spec.constraints),
        jumps=[j.name for j in spec.jumps], flows=[f.name for f in spec.flows],
        parameter_defaults=[v for _, v in spec.parameters.values()],
        input_defaults=[v for _, v in spec.inputs.values()], input_expressions=spec.input_expressions,
        constraint_where=[[spec.source.line(w), format_path(w)] for c in spec.constraints for w in c.row_where],
        initial={"unpack": _parameter_unpack(parameters, initial), "state": [to_code(e) for e in initial]},
        initial_discrete={"unpack": _parameter_unpack(parameters, discrete), "values": [to_code(e) for e in discrete]},
        display=display(spec),
        closed_form_where=[[spec.source.line(("closed_form", n)), format_path(("closed_form", n))] for n in states]
        if spec.closed_form else [], simulate=spec.simulate,
        energy_law_where=[[spec.source.line(law.where), format_path(law.where)] if law else None
                          for law in _laws(spec)])


def _laws(spec) -> list:
    """The energy law of each flow (andyc.spec.energy_law), None where the built-in law holds."""
    return list(spec.energy_laws) or [None] * len(spec.flows)


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
        jumps[j.name] = {"from": j.source, "to": j.target, "guard": j.text["guard"],
                         "direction": _DIRECTION[j.direction], "enabled": j.text["enabled"],
                         "reset": j.text["reset"], "impact": j.text["impact"]}
    states = state_names(spec)
    return _environment().get_template("jumps.py.j2").render(
        name=spec.name, version=andyc.__version__, source=Path(spec.file).name, jumps=jumps, states=states,
        discrete=[x.name for x in spec.discrete], parameters=list(spec.parameters), inputs=list(spec.inputs))



def write_front(spec, out_dir, key: str) -> bool:
    """Write <name>.py (render_front) unless it holds that text already, and the build's copy of the numerics;
    True when <name>.py was written."""
    path = module_path(out_dir, spec.name)
    check_output(path, spec.files, "generated module")
    write_numerics(out_dir, spec.name)
    return update_text(path, render_front(spec, key, path.parent))


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
    cc = c_leaves.compiler()
    source, operations, c_source = render(model, key, c=cc is not None)
    timings = {"generate": time.perf_counter() - start}
    if c_source is not None:
        start = time.perf_counter()
        c_path = equations.with_name(f"{spec.name}_leaves.c")
        library = equations.with_name(library_file(c_leaves.library_stem(spec.name, key)))
        if (write_text if force else update_text)(c_path, c_source) or force or not library.exists():
            try:
                c_leaves.compile_library(c_path, equations.parent, c_leaves.library_stem(spec.name, key), cc)
            except c_leaves.NoC as exc:     # the compiler refused it: the Numba leaves, and say why
                warnings.warn(f"{spec.name}: the C leaves did not compile, Numba compiles them instead ({exc})",
                              stacklevel=2)
                source, operations, _ = render(model, key, c=False)
        timings["cc"] = time.perf_counter() - start
    (write_text if force else update_text)(equations, source)
    write_front(spec, out_dir, key)
    result = BuildResult(spec.name, path, False, key, timings, operations)
    if jumps is not None:
        result.jumps_path = jumps
        result.jumps_kept = not create_once(jumps, render_jumps(model))
        if result.jumps_kept:
            text = jumps.read_text(encoding="utf-8", errors="replace")
            result.jumps_missing = [j.name for j in spec.jumps if f"def {j.name}(" not in text]
    return result
