"""No text from a model file can break out into generated code (issue 18).

A model whose every text field holds break-out payloads (quotes, triple quotes, backslashes, line
breaks, comment markers, NUL, surrogates, template syntax) is rendered into every file andyc
generates from a model: the module, the jumps file and the three `andyc eom` formats. Each Python file
must parse to the same tree as the benign model's, text constants aside, and importing it, calling
its jump functions and reading the equations back must not run any payload. Expressions holding such
text are refused by the parser; the test also writes the payloads past it (into the jump texts and
input expressions as the Spec carries them) to show that the emitters alone are safe.
"""

import ast
import dataclasses
import importlib.util
import json
import sys

import pytest

import andyc
from andyc.codegen.buildfiles import write_numerics
from andyc.codegen.generate import render, render_front, render_jumps
from andyc.runtime.run import Run
from andyc.symbolic.eom import equations
from andyc.symbolic.eom import equations_text
from tests.support import yaml_text

MODEL = """\
name: breakout
description: {description}
parameters: {{m: 1.0, g: 9.81, e: 0.5, k: 2.0}}
inputs: {{F: "0.1*sin(t)"}}
coordinates:
  y: {{initial: 1.0}}
  z: {{initial: 0.0}}
discrete: {{n: 0}}
gravity: [0, -g, 0]
frames:
  - {{name: ball, parent: world, prismatic: y, axis: y}}
  - {{name: side, parent: ball, prismatic: z, axis: z}}
bodies:
  - {{name: mass, frame: side, mass: m}}
forces:
  - {{name: push, frame: side, vector: [0, 0, F]}}
springs:
  - {{name: spring, stiffness: k, rest_length: 0, length: z}}
constraints:
  - {{name: ground, holonomic: y}}
hybrid:
  flows:
    - {{name: flight}}
  jumps:
    - name: bounce
      from: flight
      to: flight
      guard: y
      direction: falling
      enabled: "z > -10"
      reset: {{n: n + 1}}
      impact: {{restitution: e, constraints: [ground]}}
"""


def payload(marker) -> str:
    """Text that would run `touch MARKER` if it reached code unescaped anywhere: inside a string or a
    docstring (closing it first), after a comment, or on a line of its own."""
    run = f'__import__("os").system("touch {marker}")'
    return (f'x """; {run}; _ = """ \'\'\'; {run}; _ = \'\'\' \' " \\ \\N{{ \\x \\u12 \\'
            f'\n{run}\n# \r{run}\r\n\t{run} \x00 \ud800 \udc80 \u2028{run}\u2029 \x0c'
            f' {{{{ 7*7 }}}} {{% raw %}} \\"""{run}"""\\')


def generated(spec) -> dict:
    """Every file andyc generates from a model, by name: Python sources and the eom texts."""
    model = andyc.derive(spec)
    eq = equations(model)
    return {"module.py": render_front(spec, "key", "."), "equations.py": render(model, "key")[0],
            "jumps.py": render_jumps(model),
            "eom.py": equations_text(eq, "sympy"), "eom.json": equations_text(eq, "json"),
            "eom.tex": equations_text(eq, "latex", standalone=True)}


def shape(source: str) -> str:
    """The syntax tree of a Python source with every text constant replaced by one placeholder."""
    tree = ast.parse(source)
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            node.value = "TEXT"
    return ast.dump(tree)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """(benign files, hostile files, the hostile spec's payload, the marker path, the folder)."""
    folder = tmp_path_factory.mktemp("breakout")
    marker = folder / "PWNED"
    text = payload(marker)
    benign = folder / "benign.yaml"
    benign.write_text(MODEL.format(description="a benign model"))
    hostile = folder / ('evil"""\'#\\ \nname\r\udc80.yaml')
    hostile.write_text(MODEL.format(description=yaml_text(text)))
    spec = andyc.load(hostile)
    assert spec.description == text                  # the payload arrives intact through YAML
    # Past the expression parser (which refuses such text): the texts the Spec carries into the files.
    jumps = [dataclasses.replace(j, text={**j.text, "guard": text, "enabled": text, "reset": {"n": text},
                                         "impact": {"restitution": text, "constraints": [text]}})
             for j in spec.jumps]
    spec = dataclasses.replace(spec, jumps=jumps, input_expressions={"F": text})
    return generated(andyc.load(benign)), generated(spec), text, marker, folder


@pytest.mark.parametrize("name", ["module.py", "equations.py", "jumps.py", "eom.py"])
def test_generated_python_has_the_benign_shape(files, name):
    benign, hostile, _, marker, _ = files
    assert shape(hostile[name]) == shape(benign[name])
    assert not marker.exists()


def test_importing_the_hostile_module_and_its_jumps_file_runs_no_payload(files):
    _, hostile, text, marker, folder = files
    build = folder / "build" / "breakout"
    build.mkdir(parents=True)
    (build / "breakout.py").write_text(hostile["module.py"], encoding="utf-8")
    (build / "breakout_equations.py").write_text(hostile["equations.py"], encoding="utf-8")
    (build / "breakout_jumps.py").write_text(hostile["jumps.py"], encoding="utf-8")
    write_numerics(folder / "build", "breakout")      # as a build has it: the module imports it from its folder
    spec = importlib.util.spec_from_file_location("andyc_breakout_test", build / "breakout.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)       # Numba compiles lazily: this runs only the module's top level
        assert module.DESCRIPTION == text     # the text is data, read back equal
        assert module.INPUT_EXPRESSIONS == {"F": text}
        assert module.SOURCE.startswith('evil"""')
        jumps = sys.modules[spec.name + "_jumps"]
        assert jumps.JUMPS["bounce"]["guard"] == text and jumps.JUMPS["bounce"]["reset"] == {"n": text}
        for function in module.USER_JUMPS:
            assert function(0.0, None, None, None, None) is None
    finally:
        for name in (spec.name, getattr(module, "MODULE_NAME", None), spec.name + "_jumps"):
            sys.modules.pop(name, None)
    assert not marker.exists()


def test_the_eom_texts_carry_no_payload_line(files):
    _, hostile, text, marker, folder = files
    namespace = {}
    exec(compile(hostile["eom.py"], "eom.py", "exec"), namespace)    # the test reads its own output back
    assert namespace["M"].shape == (2, 2)
    assert not marker.exists()
    # Names are identifiers and nothing else reaches these texts: no line of the payload appears.
    json.loads(hostile["eom.json"])
    for name in ("eom.json", "eom.tex"):
        assert "system(" not in hostile[name] and "__import__" not in hostile[name]


def test_a_run_file_keeps_a_multi_line_status_inside_its_header(tmp_path, files):
    import numpy as np

    _, _, text, _, _ = files
    run = Run(model="breakout", spec_sha256="0", method="rk4", dt=1e-3, nq=1, nv=1, rtol=0.0, atol=0.0, t_end=1.0,
              parameters={}, inputs={}, state_names=["y", "y_dot"], time=np.zeros(2), state=np.zeros((2, 2)),
              energy=np.zeros(2), status="stopped: " + text)
    lines = run.save(tmp_path / "run.csv").read_text(encoding="utf-8").splitlines()
    header = lines[:lines.index(next(line for line in lines if line.startswith("time,")))]
    assert header and all(line.startswith("# ") for line in header)
    from andyc.runtime.runfiles import read_h5
    back = read_h5(run.save(tmp_path / "run.h5"))
    assert back.status.startswith("stopped: x \"\"\"")      # surrogates escaped, everything else as it was


@pytest.mark.parametrize("field, value", [
    ("guard", 'y #"""; __import__("os").system("touch MARKER"); _ = """'),
    ("guard", "y\x00"),
    ("enabled", "z > -10 # evil"),
    ("description", "fine"),        # control: a benign change builds
])
def test_payloads_in_expressions_are_refused_by_the_parser(tmp_path, field, value):
    text = MODEL.format(description="d")
    written = {"guard": "guard: y", "enabled": 'enabled: "z > -10"', "description": "description: d"}[field]
    path = tmp_path / "m.yaml"
    path.write_text(text.replace(written, f"{field}: {yaml_text(value)}", 1))
    if field == "description":
        assert andyc.load(path).description == value
        return
    with pytest.raises(andyc.SpecError) as err:
        andyc.load(path)
    message = str(err.value)
    assert "is not allowed in an expression" in message and f"hybrid.jumps[0].{field}" in message


def test_names_that_would_collide_in_generated_code_stay_apart(tmp_path):
    """Jumps 'x' and 'rate_x' (whose functions, one per jump, were once guard_rate_x both) each keep their own
    branch, by index, in every leaf over the jumps; frame 'a_x_in_b' and frame 'a' measured in 'b_z' would
    both make the frame quantity fq_a_x_in_b_z. Each keeps its own symbol."""
    text = MODEL.format(description="d").replace("    - name: bounce\n", "    - name: x\n").replace(
        "      impact: {restitution: e, constraints: [ground]}\n",
        "      impact: {restitution: e, constraints: [ground]}\n"
        "    - {name: rate_x, from: flight, to: flight, guard: z - 5, direction: rising}\n")
    path = tmp_path / "m.yaml"
    path.write_text(text)
    model = andyc.derive(andyc.load(path))
    source = render(model, "key")[0]
    functions = {node.name: node for node in ast.walk(ast.parse(source)) if isinstance(node, ast.FunctionDef)}
    assert len([n for n in ast.walk(ast.parse(source)) if isinstance(n, ast.FunctionDef)]) == len(functions)
    for leaf in ("guard", "guard_rate", "enabled", "reset"):
        branches = [node for node in functions[leaf].body if isinstance(node, ast.If)]
        assert [ast.unparse(node.test) for node in branches] == ["k == 0", "k == 1"]
    x_guard, rate_x_guard = (ast.unparse(node) for node in functions["guard"].body if isinstance(node, ast.If))
    assert "q_y" in x_guard and "5" not in x_guard          # jump x: guard y
    assert "q_z" in rate_x_guard and "5" in rate_x_guard    # jump rate_x: guard z - 5

    frames = MODEL.format(description="d").replace(
        "  - {name: side, parent: ball, prismatic: z, axis: z}\n",
        "  - {name: side, parent: ball, prismatic: z, axis: z}\n"
        "  - {name: a, parent: side, translation: [1, 0, 0]}\n"
        "  - {name: b_z, parent: world, translation: [0, 0, 2]}\n"
        "  - {name: a_x_in_b, parent: side, translation: [0, 3, 0]}\n").replace(
        "  - {name: ground, holonomic: y}\n",
        "  - {name: ground, holonomic: y}\n"
        "  - {name: one, holonomic: a.x - 1, in: b_z}\n"
        "  - {name: two, holonomic: a_x_in_b.z}\n").replace("hybrid:", "unused:").split("unused:")[0]
    path.write_text(frames)
    spec = andyc.load(path)
    one, two = (c for c in spec.constraints if c.name in ("one", "two"))
    assert one.rows[0].free_symbols.isdisjoint(two.rows[0].free_symbols)


@pytest.mark.parametrize("written, message", [
    ('"bounce\\n"', "is not a valid name"),             # Python's '$' matches before a final newline
    ("print", "cannot name a jump"),
    ("math", "cannot name a jump"),
    ("a" * 201, "a name of 201 characters"),
])
def test_names_that_are_not_safe_identifiers_are_refused(tmp_path, written, message):
    path = tmp_path / "m.yaml"
    path.write_text(MODEL.format(description="d").replace("    - name: bounce\n", f"    - name: {written}\n"))
    with pytest.raises(andyc.SpecError) as err:
        andyc.load(path)
    assert message in str(err.value) and "hybrid.jumps[0].name" in str(err.value)
