"""andyc: a compiler for multibody dynamics.

The pipeline has four stages, each handing one object to the next::

    load(path)            -> Spec            (andyc.spec)
    derive(spec)          -> SymbolicModel   (andyc.symbolic)
    generate(model, dir)  -> BuildResult     (andyc.codegen)
    simulate(compiled)    -> Run             (andyc.runtime)

`build` and `compile_model` chain the first three; the CLI is a thin layer
over these functions.
"""

__version__ = "0.1.0"

from andyc.errors import Diagnostic, SpecError  # noqa: E402
from andyc.pipeline import build, compile_model, derive, generate, load  # noqa: E402
from andyc.runtime.simulate import simulate  # noqa: E402

__all__ = [
    "__version__", "Diagnostic", "SpecError",
    "load", "derive", "generate", "build", "compile_model", "simulate",
]
