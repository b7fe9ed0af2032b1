"""The stages, chained: load -> derive -> generate -> compile; and reduction_report, which chains load, derive
and the code generator's operation counts to say what reduction saved on a URDF robot.

`build` skips derive and generate when the build folder holds equations of the
same build key (what shapes the equations, and the same andyc), and then only
rewrites the runtime data in <name>.py if it changed; `compile_model` imports
the module and lets Numba compile (or load its cache).
"""

from __future__ import annotations

import hashlib
import re
import sys
import time
from pathlib import Path

from andyc.codegen.buildfiles import (BuildResult, build_key, equations_path, jumps_path, library_present, module_name,
                                     module_path, numerics_package, numerics_path, recorded_back,
                                     written_constant)
from andyc.errors import Diagnostic, SpecError, plural
from andyc.outputs import OutputError
from andyc.spec.yamlpos import MAX_YAML_BYTES

# A YAML model's top-level `name:` line, to find its build before reading the model (see unchanged).
_NAME_LINE = re.compile(rb"^name:[ \t]*([A-Za-z_][A-Za-z0-9_]*)[ \t]*(?:#.*)?$", re.MULTILINE)


def unchanged(path, out_dir="build") -> BuildResult | None:
    """The build of the YAML model `path` in out_dir/<name>/ when it was made from these very bytes (the
    model file, and the URDF it names) by this andyc, else None: found from the files' bytes and the
    build's written constants, without reading the model (so without importing SymPy), which makes a
    warm `andyc sim` fast. The name comes from the file's `name:` line; a name read wrongly only misses
    this shortcut (the build found must name this file and hash its bytes)."""
    path = Path(path)
    try:
        if path.suffix.lower() not in (".yaml", ".yml") or path.stat().st_size > MAX_YAML_BYTES:
            return None
        found = _NAME_LINE.search(path.read_bytes())
        if found is None:
            return None
        name = found.group(1).decode()
        front = module_path(out_dir, name)
        files, key = written_constant(front, "SPEC_FILES"), written_constant(front, "BUILD_KEY")
        source = written_constant(front, "SOURCE_PATH")
        if (not isinstance(source, str) or recorded_back(source, front.parent) != path.resolve()
                or not isinstance(files, list) or not isinstance(key, str)
                or written_constant(equations_path(out_dir, name), "BUILD_KEY") != key
                or build_key(str(written_constant(front, "MEANING_SHA256"))) != key):
            return None
        digest = hashlib.sha256(b"".join(recorded_back(f, front.parent).read_bytes() for f in files)).hexdigest()
    except (OSError, TypeError):
        return None
    jumps = jumps_path(out_dir, name) if written_constant(front, "JUMPS_FILE") else None
    if digest != written_constant(front, "SPEC_SHA256") or (jumps is not None and not jumps.exists()):
        return None
    if not (numerics_path(out_dir, name) / "__init__.py").exists() or not library_present(out_dir, name):
        return None
    return BuildResult(name, front, True, key, jumps_path=jumps, jumps_kept=jumps is not None)


def load(path, unlock: bool = False):
    from andyc.spec.load import load as _load
    return _load(path, unlock)


def derive(spec):
    from andyc.symbolic import derive as _derive
    return _derive(spec)


def reduction_report(file, spec, model) -> str:
    """One line, what reduction saved on a URDF robot (`andyc check` prints it): the robot as written (every
    joint free, every body its own: `file` loaded again unlocked, derived without reduction) against `model`,
    derived from `spec` with the locked joints held and the bodies fixed to one moving frame merged
    (andyc.symbolic.reduce); degrees of freedom, bodies and the operations of the generated functions."""
    from dataclasses import replace

    from andyc.codegen.leaves import leaves

    free = load(file, unlock=True) if spec.locked else spec
    full_model = derive(replace(free, reduce=False))
    full, reduced = leaves(full_model).operations, leaves(model).operations
    dof = (f"{full_model.dof} -> {model.dof} degrees of freedom ({plural(len(spec.locked), 'joint')} locked: "
           f"{', '.join(spec.locked)})" if spec.locked else f"{model.dof} degrees of freedom")
    bodies = plural(len(spec.bodies), "body", "bodies")
    merged = (f"{bodies} merged into {len(model.spec.bodies)} (one per moving frame)"
              if len(model.spec.bodies) < len(spec.bodies) else f"{bodies}, none fixed to another's frame")
    return (f"  reduced: {dof}; {merged}; dynamics {full['dynamics']} -> {reduced['dynamics']} operations, "
            f"all functions {sum(full.values())} -> {sum(reduced.values())}")


def generate(model, out_dir="build", force: bool = False) -> BuildResult:
    from andyc.codegen.generate import generate as _generate
    return _generate(model, out_dir, force)


def build(path, out_dir="build", force: bool = False) -> BuildResult:
    """Load, derive and generate `path` into out_dir/<name>/, unless its equations are up to date
    (then only <name>.py's runtime data is rewritten, if it changed: result.skipped).

    OutputError when out_dir/<name>/ holds the build of another model file of the same name (unless
    `force`): two models never overwrite each other's build silently."""
    t0 = time.perf_counter()
    result = None if force else unchanged(path, out_dir)
    if result is not None:
        result.timings = {"load": time.perf_counter() - t0}
        return result
    spec = load(path)
    t_load = time.perf_counter() - t0
    key = build_key(spec.meaning_sha256)
    target = module_path(out_dir, spec.name)
    other = written_constant(target, "SOURCE_PATH")
    other = recorded_back(other, target.parent) if isinstance(other, str) else None
    if not force and other is not None and other != Path(spec.file).resolve():
        raise OutputError(f"{target.parent}: holds the build of '{spec.name}' from {other}, and {spec.file} has "
                          f"the same name; give one of them another `name:`, build it into another folder "
                          f"(--build-dir DIR), or pass --force to replace that build")
    jumps = jumps_path(out_dir, spec.name) if spec.jumps else None
    if not force and written_constant(equations_path(out_dir, spec.name), "BUILD_KEY") == key and (
            jumps is None or jumps.exists()) and library_present(out_dir, spec.name):
        from andyc.codegen.generate import write_front

        write_front(spec, out_dir, key)
        return BuildResult(spec.name, target, True, key, {"load": t_load}, jumps_path=jumps, jumps_kept=True)
    model = derive(spec)
    from andyc.codegen.printer import ConstantOverflow

    try:
        result = generate(model, out_dir, force)
    except ConstantOverflow as exc:     # products of the model's numbers: a problem of the model, not a bug
        raise SpecError([Diagnostic(spec.file, 1, "", str(exc), "scale the model's units so that its products of "
                                    "masses, lengths, stiffnesses and gains stay below 1e308")]) from None
    result.timings = {"load": t_load, "derive": model.derive_seconds, **result.timings}
    return result


def compile_model(path, out_dir="build", force: bool = False, integrator: bool = True, method: str | None = None):
    """Build (if needed), import a model and compile all that a run needs (its functions and its
    integrator, or load them from Numba's cache); returns (CompiledModel, BuildResult), with the
    number of functions Numba compiled (not loaded) in result.compiled. integrator=False leaves the
    integrator to simulate(), which compiles (or loads) only what its run calls: what one `andyc sim`
    does, where loading the rest from the cache would be most of a warm run's time. method: None, what
    a run of any method calls; a method's name, what a run of that one calls (andyc.runtime.simulate.compile_run);
    "model", the model's own method (its simulate: section's, else rk4), as `andyc build` does."""
    from andyc.runtime.compiled import compilations, load_compiled
    from andyc.runtime.simulate import compile_run

    result = build(path, out_dir, force)
    t0 = time.perf_counter()
    before = _compiled_so_far(result)
    compiled = load_compiled(result.module_path)
    if integrator:
        compile_run(compiled, compiled.simulate.get("method", "rk4") if method == "model" else method)
    result.timings["compile"] = time.perf_counter() - t0
    result.compiled = compilations(compiled) - before
    return compiled, result



def build_derivatives(path, out_dir="build") -> Path:
    """Build `path` (if needed) and write its exact first derivatives, out_dir/<name>/<name>_derivatives.py
    (andyc.codegen.derivatives), unless that file is of this build already; returns its path. What a run with
    sensitivities needs (andyc.simulate(..., sensitivities=True)); it derives the model (SymPy) when written."""
    from andyc.codegen.derivatives import derivatives_path, write_derivatives

    result = build(path, out_dir)
    target = derivatives_path(out_dir, result.name)
    if written_constant(target, "BUILD_KEY") != result.build_key:
        write_derivatives(derive(load(path)), out_dir, result.build_key)
    return target


def _compiled_so_far(result: BuildResult) -> int:
    """What Numba has compiled in this process of the build's modules, where they are imported already (its
    equations, by their name; the algorithms, which every build of this andyc shares)."""
    from andyc.runtime.compiled import leaf_compilations, numerics_compilations

    numerics = sys.modules.get(numerics_package())
    equations = sys.modules.get(module_name(result.name, result.build_key))
    return ((numerics_compilations(numerics) if numerics is not None else 0)
            + (leaf_compilations(equations) if equations is not None else 0))
