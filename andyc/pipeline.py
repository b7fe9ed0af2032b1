"""The stages, chained: load -> derive -> generate -> compile.

`build` skips derive and generate when the module on disk carries the same
build key (same spec bytes, same andyc); `compile_model` imports the module
and lets Numba compile (or load its cache).
"""

from __future__ import annotations

import time

import numpy as np
from andyc.codegen.generate import BuildResult, build_key, existing_build_key, jumps_path, module_path
from andyc.codegen.generate import generate as _generate
from andyc.spec.load import load as _load
from andyc.symbolic import derive as _derive

load = _load
derive = _derive
generate = _generate


def build(path, out_dir="build", force: bool = False) -> BuildResult:
    """Load, derive and generate `path` into out_dir/<name>/, unless up to date."""
    t0 = time.perf_counter()
    spec = load(path)
    t_load = time.perf_counter() - t0
    key = build_key(spec.sha256)
    target = module_path(out_dir, spec.name)
    jumps = jumps_path(out_dir, spec.name) if spec.jumps else None
    if not force and existing_build_key(target) == key and (jumps is None or jumps.exists()):
        return BuildResult(spec.name, target, True, key, {"load": t_load}, jumps_path=jumps, jumps_kept=True)
    model = derive(spec)
    result = generate(model, out_dir)
    result.timings = {"load": t_load, "derive": model.derive_seconds, **result.timings}
    return result


def compile_model(path, out_dir="build", force: bool = False):
    """Build (if needed), import a model and compile all that a run needs (its functions and its
    integrator, or load them from Numba's cache); returns (CompiledModel, BuildResult), with the
    number of functions Numba compiled (not loaded) in result.compiled."""
    from andyc.runtime.compiled import compilations, compile_integrator, load_compiled

    result = build(path, out_dir, force)
    t0 = time.perf_counter()
    compiled = load_compiled(result.module_path)
    compile_integrator(compiled)
    if compiled.input_expressions:          # the integrator's variant that calls the model's input callback
        data = np.zeros(compiled.nf * len(compiled.input_names) + 3 + compiled.nx)
        compile_integrator(compiled, compiled.module.model_inputs, data)
    result.timings["compile"] = time.perf_counter() - t0
    result.compiled = compilations(compiled)
    return compiled, result

