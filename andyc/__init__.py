"""andyc: a compiler for multibody dynamics.

The pipeline has four stages, each handing one object to the next::

    load(path)            -> Spec            (andyc.spec)
    derive(spec)          -> SymbolicModel   (andyc.symbolic)
    generate(model, dir)  -> BuildResult     (andyc.codegen)
    simulate(compiled)    -> Run             (andyc.runtime)

simulate's options are grouped into small objects: Events, Init, Projection and TimeStepping
(andyc.runtime.options).

`build` and `compile_model` chain the first three; the CLI is a thin layer
over these functions. The names are imported on first use, so that a command
that only checks a model (or prints the version) never imports SciPy or Numba.
"""

__version__ = "0.1.0"

_NAMES = {"Diagnostic": "andyc.errors", "SpecError": "andyc.errors",
          "load": "andyc.spec.load", "derive": "andyc.symbolic", "generate": "andyc.codegen.generate",
          "build": "andyc.pipeline", "compile_model": "andyc.pipeline", "build_derivatives": "andyc.pipeline", "simulate": "andyc.runtime.simulate",
          "Events": "andyc.runtime.options", "Init": "andyc.runtime.options", "Projection": "andyc.runtime.options",
          "TimeStepping": "andyc.runtime.options"}

__all__ = ["__version__", *_NAMES]


def __getattr__(name):
    if name not in _NAMES:
        raise AttributeError(f"module 'andyc' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(_NAMES[name]), name)
    globals()[name] = value
    return value
