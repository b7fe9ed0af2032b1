"""`andyc eom` (andyc.symbolic.eom): the equations of motion written out for reading.

Checked against the double pendulum's M and G derived by hand (also after a round trip through the
printed LaTeX), by adding the elements' own M and G up to the whole, and by reading each output format
back (sympy file, JSON) and comparing with the symbolic model evaluated through its intermediates.

Double pendulum (models/double_pendulum.yaml): point masses m1 at the end of link L1 and m2 at the end
of link L2, q1 from the downward vertical, q2 relative to link 1, gravity -g y. With
x1 = L1 sin q1, y1 = -L1 cos q1, x2 = x1 + L2 sin(q1 + q2), y2 = y1 - L2 cos(q1 + q2):
    T = m1 L1^2 q1'^2 / 2 + m2 (L1^2 q1'^2 + L2^2 (q1' + q2')^2 + 2 L1 L2 cos q2 q1' (q1' + q2')) / 2
    V = -(m1 + m2) g L1 cos q1 - m2 g L2 cos(q1 + q2)
Lagrange's equations d/dt dT/dq' - dT/dq + dV/dq = 0 give M q'' = G with
    M = [[(m1 + m2) L1^2 + m2 L2^2 + 2 m2 L1 L2 cos q2, m2 L2^2 + m2 L1 L2 cos q2],
         [m2 L2^2 + m2 L1 L2 cos q2,                   m2 L2^2]]
    G = [m2 L1 L2 sin q2 (2 q1' q2' + q2'^2) - (m1 + m2) g L1 sin q1 - m2 g L2 sin(q1 + q2),
         -m2 L1 L2 sin q2 q1'^2 - m2 g L2 sin(q1 + q2)]
"""

import functools
import json
import re
import runpy
import shutil
import subprocess
import textwrap

import numpy as np
import pytest
import sympy as sp
from sympy.core.function import AppliedUndef
from sympy.parsing.latex import parse_latex

import andyc
from andyc.symbolic.eom import equations
from tests.support import MODELS
from tests.support.cli import invoke

L1, L2, m1, m2, g, q1, q2, q1_dot, q2_dot = sp.symbols("L1 L2 m1 m2 g q1 q2 q1_dot q2_dot", real=True)
M12 = m2 * L2**2 + m2 * L1 * L2 * sp.cos(q2)
HAND_M = sp.Matrix([[(m1 + m2) * L1**2 + m2 * L2**2 + 2 * m2 * L1 * L2 * sp.cos(q2), M12],
                    [M12, m2 * L2**2]])
HAND_G = sp.Matrix([m2 * L1 * L2 * sp.sin(q2) * (2 * q1_dot * q2_dot + q2_dot**2) - (m1 + m2) * g * L1 * sp.sin(q1)
                    - m2 * g * L2 * sp.sin(q1 + q2),
                    -m2 * L1 * L2 * sp.sin(q2) * q1_dot**2 - m2 * g * L2 * sp.sin(q1 + q2)])

# Every element kind the ANDY paper's Table 1 lists, on a 3-D arm with a slider: bodies with inertia,
# two springs (between frames; on a length expression), a potential, linear dampers on a speed and on a
# frame's velocity, a quadratic one on an angular velocity, a force given by an input and a torque.
ELEMENTS = textwrap.dedent("""\
    name: all_elements
    parameters: {k1: 40.0, k2: 15.0, c: 2.5, b: 0.3, g: 9.81}
    inputs: {F: 1.5}
    coordinates:
      a: {initial: 0.2}
      s: {initial: 0.1}
    gravity: [0, 0, -g]
    frames:
      - {name: arm, parent: world, revolute: a, axis: y}
      - {name: slider, parent: arm, translation: [0.3, 0, 0], prismatic: s, axis: x}
      - {name: anchor, parent: world, translation: [0.2, 0.5, -0.4]}
    bodies:
      - {name: carriage, frame: slider, mass: 0.8, inertia: [0.01, 0.02, 0.03]}
      - {name: beam, frame: arm, mass: 2.0, com: [0.15, 0, 0], inertia: [0.001, 0.02, 0.02]}
    springs:
      - {name: cable, stiffness: k1, rest_length: 0.3, between: [slider, anchor]}
      - {name: return_spring, stiffness: k2, rest_length: 0.05, length: "s + 0.1*sin(a)"}
    potentials:
      - {name: cam, energy: "c*(1 - cos(2*a))*s**2"}
    dampers:
      - {name: rail_friction, speed: s, coefficient: b}
      - {name: carriage_drag, frame: slider, coefficient: b}
      - {name: spin_drag, frame: arm, angular: true, law: quadratic, coefficient: b}
    forces:
      - {name: push, frame: slider, vector: [F, 0, 0], in: slider}
    torques:
      - {name: motor, frame: arm, vector: [0, 2*F, 0]}
    """)


def derived(path):
    return andyc.derive(andyc.load(path))


@functools.lru_cache(maxsize=None)
def written_out(name):
    """(model, equations(model)) of models/<name>.yaml, once per session."""
    model = derived(MODELS / f"{name}.yaml")
    return model, equations(model)


def eom(*args):
    return invoke("eom", *args)


def display_names(model) -> dict:
    """model symbol -> the symbol andyc eom writes: the names of the model file, speeds as <coordinate>_dot."""
    spec = model.spec
    out = {c.q: sp.Symbol(c.name, real=True) for c in spec.coordinates}
    out.update({v: sp.Symbol(name, real=True) for v, name in zip(model.v, spec.speed_names)})
    out.update({s.symbol: sp.Symbol(s.name, real=True) for s in spec.signals})
    for section in (spec.parameters, spec.inputs):
        out.update({sym: sp.Symbol(name, real=True) for name, (sym, _) in section.items()})
    out.update({x.symbol: sp.Symbol(x.name, real=True) for x in spec.discrete})
    return out


def random_point(model, rng) -> dict:
    """Values of q, v, signals (unit quaternions), parameters (defaults, randomly scaled), inputs and t."""
    spec = model.spec
    values = {model.t: rng.uniform(0, 2)}
    values.update({s: rng.uniform(-2, 2) for s in model.q + model.v + model.inputs + model.discrete})
    defaults = spec.parameter_values().values()
    values.update({s: value * rng.uniform(0.5, 1.5) for s, value in zip(model.parameters, defaults)})
    quaternion = [s for s in spec.signals if s.component in ("qw", "qx", "qy", "qz")]
    for i in range(0, len(quaternion), 4):
        unit = rng.normal(size=4)
        values.update({s.symbol: x for s, x in zip(quaternion[i:i + 4], unit / np.linalg.norm(unit))})
    values.update({s.symbol: rng.uniform(-1, 1) for s in spec.signals if s.symbol not in values})
    return {s: sp.Float(x) for s, x in values.items()}


def model_values(model, point: dict) -> dict:
    """The point extended by the model's intermediate symbols, walked in order (no eom code involved)."""
    values = dict(point)
    for sym, expr in model.assignments:
        values[sym] = expr.xreplace(values)
    return values


def numeric(mat, values) -> np.ndarray:
    return np.array(sp.Matrix(mat).xreplace(values).evalf(), dtype=float)


def compiled(mat, symbols):
    """mat as a function of the values of `symbols` (lambdify; xreplace is slow on large entries)."""
    f = sp.lambdify(symbols, sp.Matrix(mat).tolist(), "math")
    return lambda values: np.array(f(*[float(values[s]) for s in symbols]), dtype=float)


def test_latex_of_the_double_pendulum_parses_back_to_the_hand_derived_mass_matrix():
    """Each entry of the printed M, read back by sympy's LaTeX parser (antlr backend; it reads no matrices,
    so the matrix is split at & and \\\\), equals the hand-derived M symbolically."""
    result = eom(MODELS / "double_pendulum.yaml")
    assert result.exit_code == 0, result.output
    found = re.search(r"^M = \\left\[\\begin\{matrix\}(.*)\\end\{matrix\}\\right\]$", result.stdout, re.M)
    assert found, result.stdout
    rows = [row.split("&") for row in found.group(1).split(r"\\")]
    assert [len(r) for r in rows] == [2, 2]
    back = {sp.Symbol(sp.latex(s)): s for s in (L1, L2, m1, m2, g, q1, q2)}      # L_{1} -> L1 ...

    def read(entry):
        """The parser reads `m_{2} \\left(x\\right)` as a function m_{2}(x): make it a product again."""
        expr = parse_latex(entry.strip(), backend="antlr")
        expr = expr.replace(lambda e: isinstance(e, AppliedUndef) and sp.Symbol(e.func.__name__) in back,
                            lambda e: sp.Symbol(e.func.__name__) * e.args[0])
        return expr.xreplace(back)

    parsed = sp.Matrix([[read(entry) for entry in row] for row in rows])
    assert parsed.free_symbols <= {L1, L2, m1, m2, q2}
    assert sp.simplify(parsed - HAND_M) == sp.zeros(2, 2)


def test_simplified_M_and_G_of_the_double_pendulum_equal_lagranges_equations():
    _, eq = written_out("double_pendulum")
    assert sp.simplify(eq.M - HAND_M) == sp.zeros(2, 2)
    assert sp.simplify(eq.G - HAND_G) == sp.zeros(2, 1)
    assert eq.speeds == [q1_dot, q2_dot] and eq.rows == [] and eq.A.shape == (0, 2)


@pytest.mark.parametrize("name", ["double_pendulum", "cart_pole"])
def test_element_contributions_add_up_to_M_and_G_symbolically(name):
    _, eq = written_out(name)
    n = len(eq.speeds)
    M_sum = sum((M for M, _ in eq.elements.values() if M is not None), sp.zeros(n, n))
    G_sum = sum((G for _, G in eq.elements.values() if G is not None), sp.zeros(n, 1))
    assert sp.simplify(M_sum - eq.M) == sp.zeros(n, n)
    assert sp.simplify(G_sum - eq.G) == sp.zeros(n, 1)


def test_element_contributions_add_up_numerically_and_equal_the_model(tmp_path):
    """A model with every element kind: at 10 random points the elements' M and G add up to the printed
    M and G, and these equal the symbolic model's M and G (evaluated through its intermediates), to
    1e-12 of their size."""
    path = tmp_path / "all_elements.yaml"
    path.write_text(ELEMENTS)
    model = derived(path)
    eq = equations(model)
    assert set(eq.elements) == {e.name for e in model.elements}
    names = display_names(model)
    symbols = list(names.values()) + [model.t]
    M, G = compiled(eq.M, symbols), compiled(eq.G, symbols)
    parts = [compiled(x, symbols) for pair in eq.elements.values() for x in pair if x is not None]
    kinds = [x.shape[1] for pair in eq.elements.values() for x in pair if x is not None]   # n: an M, 1: a G
    rng = np.random.default_rng(8)
    for _ in range(10):
        point = random_point(model, rng)
        shown = {names[s]: x for s, x in point.items() if s in names} | {model.t: point[model.t]}
        M_sum = sum(f(shown) for f, cols in zip(parts, kinds) if cols > 1)
        G_sum = sum(f(shown) for f, cols in zip(parts, kinds) if cols == 1)
        values = model_values(model, point)
        for got, want in ((M_sum, M(shown)), (G_sum, G(shown)),
                          (M(shown), numeric(model.M, values)), (G(shown), numeric(model.G, values))):
            np.testing.assert_allclose(got, want, rtol=0, atol=1e-12 * np.abs(want).max())


@pytest.mark.parametrize("name", ["double_pendulum", "fourbar"])
def test_sympy_format_loads_back_equal_to_the_model(name, tmp_path):
    """The file is plain Python: run it, and M, G, phi, A, kappa are the equations printed, exactly, and equal
    the model's (evaluated through its intermediates) at random points; the double pendulum's also
    symbolically."""
    out = tmp_path / "eom.py"
    result = eom(MODELS / f"{name}.yaml", "--format", "sympy", "-o", out)
    assert result.exit_code == 0, result.output
    ns = runpy.run_path(str(out))
    model, eq = written_out(name)
    cons = model.constraints
    quantities = (("M", model.M), ("G", model.G), ("phi", cons.phi), ("A", cons.A), ("kappa", cons.kappa))
    for key, _ in quantities:
        assert isinstance(ns[key], sp.Matrix) and ns[key] == getattr(eq, key), key
    assert set(ns["elements"]) == {e.name for e in model.elements} and ns["rows"] == eq.rows
    for key, (M_e, G_e) in eq.elements.items():
        assert ns["elements"][key] == (M_e, G_e)
    names = display_names(model)
    rng = np.random.default_rng(2)
    for _ in range(3):
        point = random_point(model, rng)
        values = model_values(model, point)
        shown = {names[s]: x for s, x in point.items() if s in names} | {model.t: point[model.t]}
        for key, mat in quantities:
            if mat.rows == 0:       # no constraints: the model's are 0 x 0
                assert ns[key].rows == 0
                continue
            want = numeric(mat, values)
            np.testing.assert_allclose(numeric(ns[key], shown), want, rtol=0, atol=1e-13 * max(1.0, np.abs(want).max()))
    if name == "double_pendulum":
        written = {}        # the model's intermediates, written out in display names
        for sym, expr in model.assignments:
            written[sym] = expr.xreplace(names).xreplace(written)
        for key, mat in quantities[:2]:
            assert sp.simplify(ns[key] - mat.xreplace(written).xreplace(names)) == sp.zeros(*mat.shape), key


def test_json_format_has_the_names_and_quantities():
    """cart_pole: names as the model file and `andyc linearize` give them; each entry's str parses back."""
    model, eq = written_out("cart_pole")
    result = eom(MODELS / "cart_pole.yaml", "--format", "json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    spec = model.spec
    assert data["model"] == spec.name and data["flow"] == model.hybrid.flows[model.hybrid.initial]
    assert data["states"] == [c.name for c in spec.coordinates] + list(spec.speed_names)
    assert data["parameters"] == list(spec.parameters) and data["inputs"] == list(spec.inputs)
    assert set(data["elements"]) == {e.name for e in model.elements}
    assert data["elements"]["push"]["M"] is None        # a force adds no mass
    local = {name: sp.Symbol(name, real=True) for name in data["symbols"]}
    for key in ("M", "G"):
        q = data[key]
        assert q["shape"] == list(getattr(eq, key).shape) and q["latex"].startswith(r"\left[\begin{matrix}")
        assert sp.Matrix([[sp.sympify(s, locals=local) for s in row] for row in q["str"]]) == getattr(eq, key)
    assert data["A"]["shape"] == [0, 2] and data["constraint_rows"] == []


def test_element_option_prints_only_that_element():
    model, _ = written_out("double_pendulum")
    result = eom(MODELS / "double_pendulum.yaml", "--element", "mass2", "--format", "json")
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    assert list(data["elements"]) == ["mass2"] and data["M"] is None and data["G"] is None
    local = {name: sp.Symbol(name, real=True) for name in data["symbols"]}
    M2 = sp.Matrix([[sp.sympify(s, locals=local) for s in row] for row in data["elements"]["mass2"]["M"]["str"]])
    mass2 = next(e for e in model.elements if e.name == "mass2")
    written = {}
    for sym, expr in model.assignments:
        written[sym] = expr.xreplace(display_names(model)).xreplace(written)
    assert sp.simplify(M2 - mass2.M.xreplace(written).xreplace(display_names(model))) == sp.zeros(2, 2)
    latex = eom(MODELS / "double_pendulum.yaml", "--element", "mass2").stdout
    assert r"M_{\text{mass2}} = " in latex and r"G_{\text{mass2}} = " in latex
    assert "mass1" not in latex and "\nM = " not in latex


def test_unknown_element_or_flow_is_an_error_naming_the_file_and_the_choices():
    path = MODELS / "double_pendulum.yaml"
    model = derived(path)
    result = eom(path, "--element", "mass3")
    assert result.exit_code == 1 and result.stdout == ""
    elements = ", ".join(e.name for e in model.elements)
    assert result.stderr.startswith(f"{path}: ") and f"no element named 'mass3'; elements: {elements}" in result.stderr
    result = eom(path, "--flow", "walk")
    assert result.exit_code == 1 and result.stderr.startswith(f"{path}: ")
    assert "no flow named 'walk'; flows: default" in result.stderr
    assert "Traceback" not in result.output


def test_an_invalid_model_is_reported_as_andyc_check_does(tmp_path):
    """A model error goes through the same FILE:LINE: path: what; fix diagnostics as `andyc check`."""
    path = tmp_path / "broken.yaml"
    path.write_text((MODELS / "double_pendulum.yaml").read_text().replace("parent: elbow", "parent: elbo"))
    result = eom(path)
    assert result.exit_code == 1 and result.stdout == ""
    check = invoke("check", path)
    assert check.exit_code == 1 and result.stderr == check.stderr
    assert result.stderr.startswith(f"{path}:") and "elbo" in result.stderr
    result = eom(MODELS / "cart_pole.yaml", "--format", "json", "--standalone")
    assert result.exit_code == 2 and "--standalone" in result.stderr


@pytest.mark.parametrize("name, flow", [("fourbar", None), ("passive_walker", "IFixOLock")])
def test_constraint_jacobian_of_the_flows_rows_equals_the_model(name, flow):
    """The printed phi, A and kappa of the flow's active rows (passive walker: both knees locked, 4 of its 6
    constraints' rows) equal the model's rows at a random point."""
    model = derived(MODELS / f"{name}.yaml")
    k = model.hybrid.initial if flow is None else model.hybrid.flows.index(flow)
    args = [MODELS / f"{name}.yaml", "--format", "json"] + (["--flow", flow] if flow else [])
    result = eom(*args)
    assert result.exit_code == 0, result.output
    data = json.loads(result.stdout)
    rows = [r for r, con in enumerate(model.constraints.rows) if con in model.spec.flows[k].constraints]
    assert rows and (flow is None or len(rows) < model.constraints.nc)
    assert data["constraint_rows"] == [f"{model.constraints.rows[r]} ({model.constraints.multipliers[r]})"
                                       for r in rows]
    local = {n: sp.Symbol(n, real=True) for n in data["symbols"]}
    names = display_names(model)
    point = random_point(model, np.random.default_rng(5))
    shown = {names[s]: x for s, x in point.items() if s in names} | {model.t: point[model.t]}
    values = model_values(model, point)
    cons = model.constraints
    holonomic = [r for r in rows if r < cons.nh]
    for key, want in (("A", cons.A.extract(rows, list(range(model.dof)))),
                      ("kappa", sp.Matrix([cons.kappa[r] for r in rows])),
                      ("phi", sp.Matrix([cons.phi[r] for r in holonomic]))):
        got = sp.Matrix([[sp.sympify(s, locals=local) for s in row] for row in data[key]["str"]])
        assert got.shape == want.shape
        want = numeric(want, values)
        scale = max(1.0, np.abs(want).max(initial=0.0))
        np.testing.assert_allclose(numeric(got, shown), want, rtol=0, atol=1e-12 * scale)
        assert data[key]["latex"].startswith(r"\left[\begin{matrix}")


def test_latex_standalone_is_a_document_and_reports_the_file_written(tmp_path):
    out = tmp_path / "eom.tex"
    result = eom(MODELS / "cart_pole.yaml", "--standalone", "-o", out)
    assert result.exit_code == 0, result.output
    assert f"wrote {out}" in result.stdout
    text = out.read_text()
    assert text.startswith("\\documentclass") and text.rstrip().endswith("\\end{document}")
    assert text.count(r"\begin{equation}") == text.count(r"\end{equation}") > 3
    assert "% symbols: " in text and "F" in text.split("% symbols: ")[1].splitlines()[0]


@pytest.mark.skipif(shutil.which("pdflatex") is None, reason="needs pdflatex")
def test_latex_compiles_standalone_and_as_a_fragment(tmp_path):
    """The four-bar (constraint rows, elements) as a document, and the cart-pole as a fragment brought in
    with \\input into a document of one's own."""
    (tmp_path / "main.tex").write_text("\\documentclass{article}\n\\usepackage{amsmath}\n\\begin{document}\n"
                                       "\\input{cart_pole}\n\\end{document}\n")
    for name, args, document in (("fourbar", ["--standalone"], "fourbar.tex"), ("cart_pole", [], "main.tex")):
        assert eom(MODELS / f"{name}.yaml", *args, "-o", tmp_path / f"{name}.tex").exit_code == 0
        run = subprocess.run(["pdflatex", "-interaction=nonstopmode", "-halt-on-error", document], cwd=tmp_path,
                             capture_output=True, text=True, timeout=120)
        assert run.returncode == 0, run.stdout[-2000:]
        assert (tmp_path / document).with_suffix(".pdf").stat().st_size > 0


def test_a_decimal_the_file_wrote_prints_as_a_decimal_and_the_derivations_fractions_stay(tmp_path):
    """An inertia of 1.0e-7 in the file is kept exact (1/10000000) but printed 1.0 · 10^-7 in LaTeX; the
    derivation's own 1/2 stays a fraction; the sympy format, which reads back exactly, keeps the rational."""
    from andyc.symbolic.eom import decimals

    x = sp.Symbol("x")
    shown = decimals(sp.Matrix([x / 2, x + sp.Rational(1, 10**7), -sp.Rational(3, 10) * x, sp.Rational(1, 12)]))
    assert list(shown) == [x / 2, x + sp.Float(1e-7), -sp.Float(0.3) * x, sp.Rational(1, 12)]
    assert isinstance(shown[0].args[0], sp.Rational) and shown[3] == sp.Rational(1, 12)
    (tmp_path / "m.yaml").write_text(textwrap.dedent("""\
        name: tiny_inertia
        parameters: {L: 0.25, m: 1.0, g: 9.81}
        coordinates: {theta: {initial: 0.1}}
        gravity: [0, -g, 0]
        frames:
          - {name: link, parent: world, revolute: theta, axis: z}
          - {name: tip, parent: link, translation: [L, 0, 0]}
        bodies:
          - {name: bob, frame: tip, mass: m, inertia: [1.0e-7, 1.0e-7, 1.0e-7]}
        """))
    latex = invoke("eom", tmp_path / "m.yaml")
    assert latex.exit_code == 0, latex.output
    assert r"M = \left[\begin{matrix}L^{2} m + 1.0 \cdot 10^{-7}\end{matrix}\right]" in latex.output
    assert "10000000" not in latex.output
    exact = invoke("eom", tmp_path / "m.yaml", "--format", "sympy")
    assert exact.exit_code == 0 and "Rational(1, 10000000)" in exact.output
