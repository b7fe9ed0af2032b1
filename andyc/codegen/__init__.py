"""Code generation: SymbolicModel -> a standalone Python/Numba module in build/<name>/.

It reads only the SymbolicModel (never the model file): the template renders what depends on the model,
and the model-independent numerics (andyc/numerics) are copied beside it verbatim.

    generate.py    the build folder: the module, its equations, the jump template, the numerics copy
    leaves.py      the model's own functions (M and G, constraint rows, energy, guards, ...) as source
    printer.py     one generated function body: the assignments it needs, common subexpressions, order
    buildfiles.py  a build's paths and keys, read without SymPy or Jinja (what andyc.pipeline checks)
    run_inputs.py  a run's command-line input expressions, through the same printer, as a generated file
"""
