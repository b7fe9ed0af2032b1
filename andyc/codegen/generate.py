"""SymbolicModel -> build/<name>/<name>.py.

The math goes through `function_body` (cse + ordering); the template only
wraps it. The build key hashes the spec, the andyc version and the sources of
the stages that shape the generated code, so a rebuild is skipped exactly
when nothing that matters changed.
"""

from __future__ import annotations

import hashlib
import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path

import jinja2
import sympy as sp

import andyc
from andyc.errors import format_path
from andyc.codegen.printer import function_body, to_code
from andyc.symbolic.model import SymbolicModel

ROOT = Path(__file__).resolve().parents[2]
TEMPLATES = ROOT / "templates"
_GENERATOR_SOURCES = ["andyc/symbolic", "andyc/codegen", "andyc/spec", "templates"]


@dataclass
class BuildResult:
    name: str
    module_path: Path
    skipped: bool
    build_key: str
    timings: dict = field(default_factory=dict)     # seconds per stage
    operations: dict = field(default_factory=dict)  # function -> sympy op count


def generator_fingerprint() -> str:
    h = hashlib.sha256(andyc.__version__.encode())
    for rel in _GENERATOR_SOURCES:
        for path in sorted((ROOT / rel).rglob("*")):
            if path.suffix in (".py", ".j2", ".json") and path.is_file():
                h.update(path.relative_to(ROOT).as_posix().encode())
                h.update(path.read_bytes())
    return h.hexdigest()


def build_key(spec_sha256: str) -> str:
    return hashlib.sha256((spec_sha256 + generator_fingerprint()).encode()).hexdigest()


def module_path(out_dir, name: str) -> Path:
    return Path(out_dir) / name / f"{name}.py"


def existing_build_key(path: Path) -> str | None:
    """The BUILD_KEY line of a generated module, read without importing it."""
    try:
        with open(path) as fh:
            for line in fh:
                if line.startswith("BUILD_KEY = "):
                    return json.loads(line.split("=", 1)[1])
    except OSError:
        return None
    return None


def _unpack(model: SymbolicModel, used: set) -> list[str]:
    states = model.q + model.v + model.signals
    lines = [f"{s} = x[{i}]" for i, s in enumerate(states) if s in used]
    for i, s in enumerate(model.parameters):
        if s in used:
            lines.append(f"{s} = p[{i}]")
    for i, s in enumerate(model.inputs):
        if s in used:
            lines.append(f"{s} = u[{i}]")
    return lines


def _function(model, pool, name, args, doc, outputs, returns=None):
    body = function_body(outputs, pool)
    return {"name": name, "args": args, "doc": doc, "unpack": _unpack(model, body.inputs),
            "lines": body.lines, "outputs": body.outputs, "returns": returns, "operations": body.operations}


def render(model: SymbolicModel, key: str) -> tuple[str, dict]:
    """The module's source text and the operation count of each function."""
    spec = model.spec
    pool = dict(model.assignments)
    n = model.dof
    mass = [(f"M[{i}, {j}]", model.M[i, j]) for i in range(n) for j in range(i, n)]
    mirror = [(f"M[{j}, {i}]", sp.Symbol(f"M[{i}, {j}]")) for i in range(n) for j in range(i + 1, n)]
    frames = list(model.frame_positions)
    cons = model.constraints
    functions = [
        _function(model, pool, "dynamics", "t, x, u, p, M, G",
                  "Fill the mass matrix M (NV, NV) and generalized force G (NV,): M dv/dt = G (eq. 8).",
                  mass + [(f"G[{i}]", model.G[i]) for i in range(n)]),
        _function(model, pool, "energy", "t, x, u, p",
                  "Total mechanical energy: kinetic + gravity + springs + potentials.",
                  [("e", model.energy)], returns="e"),
        _function(model, pool, "power", "t, x, u, p",
                  "Power of the non-conservative elements (forces, torques, dampers).",
                  [("w", model.power)], returns="w"),
        _function(model, pool, "signal_rates", "t, x, u, p, xdot",
                  "Rates of the nonholonomic signals (eq. 4) into xdot[NQ + NV:].",
                  [(f"xdot[{len(model.q) + n + i}]", r) for i, r in enumerate(model.signal_rates)]),
        _function(model, pool, "constraints", "t, x, u, p, phi, c, A, kappa",
                  "Constraint residuals phi (NH,), velocity residuals c = A v + b (NC,), their Jacobian A "
                  "(NC, NV) and kappa (NC,), with dc/dt = A dv/dt + kappa (ANDY eq. 11).",
                  [(f"phi[{i}]", e) for i, e in enumerate(cons.phi)]
                  + [(f"c[{i}]", e) for i, e in enumerate(cons.c)]
                  + [(f"A[{i}, {j}]", cons.A[i, j]) for i in range(cons.nc) for j in range(n)]
                  + [(f"kappa[{i}]", e) for i, e in enumerate(cons.kappa)]),
        _function(model, pool, "constraint_gains", "p, ks, kd",
                  "Soft-constraint gains K_s and K_d of each row (ANDY eq. 13-15), for the baumgarte method.",
                  [(f"ks[{i}]", e) for i, e in enumerate(cons.stiffness)]
                  + [(f"kd[{i}]", e) for i, e in enumerate(cons.damping)]),
        _function(model, pool, "frame_positions", "t, x, u, p, out",
                  "Origins of FRAMES in world coordinates into out (len(FRAMES), 3).",
                  [(f"out[{k}, {i}]", model.frame_positions[f][i]) for k, f in enumerate(frames) for i in range(3)]),
    ]
    # M is symmetric: copy the upper triangle after it is written.
    functions[0]["outputs"] += [(t, str(src)) for t, src in mirror]
    initial = ([c.initial for c in spec.coordinates] + [c.velocity for c in spec.coordinates]
               + [s.initial for s in spec.speeds] + [s.initial for s in spec.signals])
    init_syms = set().union(*(e.free_symbols for e in initial))
    values = [to_code(e) for e in initial]
    # Each quaternion signal: the index of its w component in x.
    nx_before = len(model.q) + n
    quaternions = [nx_before + i for i, s in enumerate(spec.signals) if s.component == "qw"]
    unpack = [f"    {s} = p[{i}]" for i, s in enumerate(model.parameters) if s in init_syms]
    operations = {f["name"]: f["operations"] for f in functions}
    context = {
        "version": andyc.__version__, "source": Path(spec.file).name, "spec_sha256": spec.sha256,
        "build_key": key, "name": spec.name,
        "description": (spec.description or "").strip().replace('"""', "'''"),
        "coordinates": [c.name for c in spec.coordinates],
        "speeds": spec.speed_names,
        "signals": [s.name for s in spec.signals],
        "quaternions": quaternions,
        "parameters": list(spec.parameters),
        "parameter_defaults": repr([v for _, v in spec.parameters.values()]),
        "inputs": list(spec.inputs),
        "input_defaults": repr([v for _, v in spec.inputs.values()]),
        "frames": frames, "operations": operations,
        "nh": cons.nh, "nc": cons.nc, "constraint_rows": cons.rows, "multipliers": cons.multipliers,
        "conserves_energy": spec.conserves_energy,
        "constraint_where": [[spec.source.line(w), format_path(w)] for c in spec.constraints for w in c.row_where],
        "initial": {"unpack": "\n".join(unpack), "state": values},
        "functions": functions,
    }
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(TEMPLATES), keep_trailing_newline=True,
                             undefined=jinja2.StrictUndefined)
    return env.get_template("module.py.j2").render(**context), operations


def generate(model: SymbolicModel, out_dir="build") -> BuildResult:
    """Write the module for `model` into out_dir/<name>/ (always; see pipeline.build for skipping)."""
    start = time.perf_counter()
    key = build_key(model.spec.sha256)
    source, operations = render(model, key)
    path = module_path(out_dir, model.spec.name)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".py.tmp")
    tmp.write_text(source)
    os.replace(tmp, path)
    return BuildResult(model.spec.name, path, False, key,
                       {"generate": time.perf_counter() - start}, operations)
