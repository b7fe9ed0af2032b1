"""The inputs a run drives beyond the model's own (command-line expressions and tables) as a generated
input callback, andyc_numerics/inputs.py's `run_inputs`.

`andyc sim --input F="-10*th"` is an expression like the model's own: it goes through the whitelist
parser (andyc.spec.expressions) and the code printer, into a module written beside the build
(run_inputs/r_<key>.py), never through exec. The key hashes what defines the module (each drive as
written, where its table lies in the run's data, the model's build key, andyc's version), so a run
with the same drives finds the module without SymPy and Numba loads it from its cache.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path

import andyc
from andyc.codegen.buildfiles import PACKAGE, numerics_package


def run_inputs_key(build_key: str, expressions: dict, tables: dict, held: list) -> str:
    """The key of the run-inputs module for these drives: expressions {input: text}, tables {input: (start, n)}
    (in the run's data), held [inputs the model drives that the run holds constant instead]."""
    what = json.dumps([build_key, andyc.__version__, numerics_package(), sorted(expressions.items()),
                       sorted((k, list(v)) for k, v in tables.items()), sorted(held)])
    return hashlib.sha256(what.encode()).hexdigest()[:16]


def run_inputs_path(folder, key: str) -> Path:
    """Where the run-inputs module of `key` lives in a build folder."""
    return Path(folder) / "run_inputs" / f"r_{key}.py"


def write_run_inputs(path, model: dict, expressions: dict, tables: dict, held: list) -> None:
    """Write the run-inputs module at `path`. model: the built model's names ("states", "parameters",
    "discrete", "inputs"), its FLOW_SETS_INPUT rows ("flow_sets_input") and its "name". ExpressionError (with the
    input's name in `name`... of the parse) for an expression that is not allowed."""
    import jinja2
    import sympy as sp

    from andyc.codegen.generate import literal
    from andyc.codegen.printer import function_body
    from andyc.outputs import write_text
    from andyc.spec.expressions import TIME, parse

    symbols, code = {}, {}
    for array, names in (("x", model["states"]), ("p", model["parameters"]), ("d", model["discrete"])):
        for i, name in enumerate(names):
            symbols[name] = sp.Symbol(name, real=True)
            code[symbols[name]] = sp.Symbol(f"{array}[{i}]", real=True)      # no user text reaches the code
    code[TIME] = sp.Symbol("t", real=True)
    inputs = list(model["inputs"])
    drives = []
    for name, text in expressions.items():
        expr = parse(text, symbols, allow_time=True).xreplace(code)
        body = function_body([(f"u[{inputs.index(name)}]", expr)], {})
        drives.append({"index": inputs.index(name), "lines": body.lines, "outputs": body.outputs})
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(PACKAGE / "templates"), keep_trailing_newline=True,
                             undefined=jinja2.StrictUndefined, autoescape=False)
    env.filters["py"] = literal
    text = env.get_template("run_inputs.py.j2").render(
        version=andyc.__version__, name=model["name"], numerics=numerics_package(), nu=len(inputs),
        nf=len(model["flow_sets_input"]),
        flow_sets_input=model["flow_sets_input"], held=[inputs.index(n) for n in held], drives=drives,
        tables=[{"index": inputs.index(n), "start": start, "n": n_rows} for n, (start, n_rows) in tables.items()])
    write_text(path, text)
