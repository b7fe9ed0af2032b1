"""A corpus of malformed and hostile inputs (issue 18): every one ends in a message, never in a traceback.

Each case writes its files into a fresh folder and runs one andyc command in-process (click's
CliRunner, so the corpus costs no interpreter start-ups). What must hold for every case:

- the exit code is 1 (an invalid model, a run that stopped) or 2 (a usage error), and no exception
  but SystemExit escapes the command;
- no "Traceback" in the output;
- for an input that is a file (a model, a URDF, a table, a controller), the message says `FILE:LINE`;
- no payload ran (the marker file a payload would create does not exist), and the files a case names
  as inputs are unchanged.

The commands that need a compiled model use one shipped model built once per session (cart_pole, which
has an input); most option checks come before any work.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import pytest

from tests.support import MODELS, yaml_text
from tests.support.cli import invoke

MARKER = "PWNED"
RUN = f'__import__("os").system("touch {MARKER}")'


@dataclass
class Case:
    id: str
    args: list                              # {d}: the case's folder, {b}: the shared build folder, {m}: models/
    files: dict = field(default_factory=dict)   # name -> text or bytes
    codes: tuple = (1, 2)
    where: str | None = None                # a file whose name must appear as NAME:LINE in the message
    unchanged: tuple = ()                   # files that must be byte-for-byte as before
    says: str = ""                          # a fragment the message must contain
    forbid: tuple = ("Traceback", "internal error", "\x1b")   # never in the output (ESC: terminal escapes)


FIFO = object()          # a file value: a named pipe (reading it would wait forever)


def _empty_h5() -> bytes:
    import io

    import h5py
    buffer = io.BytesIO()
    with h5py.File(buffer, "w"):
        pass
    return buffer.getvalue()


EMPTY_H5 = _empty_h5()

# -- models to break ----------------------------------------------------------------------------------

BALL = """\
name: ball
description: A point mass on a prismatic joint, bouncing.
parameters: {m: 1.0, g: 9.81, e: 0.8}
coordinates:
  y: {initial: 1.0}
gravity: [0, -g, 0]
frames:
  - {name: body, parent: world, prismatic: y, axis: y}
bodies:
  - {name: mass, frame: body, mass: m}
constraints:
  - {name: ground, holonomic: y}
hybrid:
  flows:
    - {name: flight}
  jumps:
    - name: bounce
      from: flight
      to: flight
      guard: y
      direction: falling
      impact: {restitution: e, constraints: [ground]}
"""


def ball(old: str, new: str) -> dict:
    """The ball model with one piece of text replaced (the piece must be there)."""
    assert old in BALL, old
    return {"m.yaml": BALL.replace(old, new, 1)}


def model_case(id, old, new, says="", codes=(1,)):
    return Case(id, ["check", "{d}/m.yaml"], ball(old, new), codes, "m.yaml", ("m.yaml",), says)


def alias_bomb(levels=9, width=9) -> str:
    lines = [f"a0: &a0 [{', '.join(['lol'] * width)}]"]
    lines += [f"a{i}: &a{i} [{', '.join([f'*a{i - 1}'] * width)}]" for i in range(1, levels)]
    return "\n".join(lines) + "\n" + BALL


# -- 1. YAML syntax ---------------------------------------------------------------------------------

YAML_CASES = [
    model_case("tab-indent", "  - {name: mass", "\t- {name: mass"),
    model_case("unclosed-bracket", "[0, -g, 0]", "[0, -g, 0"),
    model_case("unclosed-brace", "{name: mass, frame: body, mass: m}", "{name: mass, frame: body, mass: m"),
    model_case("unclosed-quote", "name: ball", 'name: "ball'),
    model_case("bad-indent", "  flows:", "   flows:"),
    model_case("duplicate-key", "name: ball\n", "name: ball\nname: ball2\n"),
    model_case("second-document", "name: ball\n", "name: ball\n---\nname: other\n"),
    model_case("missing-colon", "gravity: [0, -g, 0]", "gravity [0, -g, 0]\nframes2: 1"),
    model_case("colon-in-value", "description: A point mass", "description: A: point: mass"),
    Case("empty-file", ["check", "{d}/m.yaml"], {"m.yaml": ""}, (1,), "m.yaml"),
    Case("only-comment", ["check", "{d}/m.yaml"], {"m.yaml": "# nothing\n"}, (1,), "m.yaml"),
    Case("scalar-document", ["check", "{d}/m.yaml"], {"m.yaml": "42\n"}, (1,), "m.yaml"),
    Case("list-document", ["check", "{d}/m.yaml"], {"m.yaml": "- a\n- b\n"}, (1,), "m.yaml"),
    Case("null-document", ["check", "{d}/m.yaml"], {"m.yaml": "~\n"}, (1,), "m.yaml"),
    Case("binary-garbage", ["check", "{d}/m.yaml"], {"m.yaml": bytes(range(256)) * 4}, (1,), "m.yaml"),
    Case("not-utf8", ["check", "{d}/m.yaml"], {"m.yaml": BALL.encode().replace(b"bouncing", b"bo\xffuncing")},
         (1,), "m.yaml"),
    Case("nul-byte", ["check", "{d}/m.yaml"], {"m.yaml": BALL.replace("bouncing", "bo\x00uncing")}, (1,), "m.yaml"),
    Case("bom-then-garbage", ["check", "{d}/m.yaml"], {"m.yaml": "\ufeff[[[\n"}, (1,), "m.yaml"),
    model_case("surrogate-in-name", "name: ball", 'name: "ba\\ud800ll"'),
    Case("deep-nesting", ["check", "{d}/m.yaml"], {"m.yaml": BALL + "x: " + "[" * 5000 + "]" * 5000 + "\n"},
         (1,), "m.yaml", says="nested too deeply"),
    Case("alias-bomb", ["check", "{d}/m.yaml"], {"m.yaml": alias_bomb()}, (1,), "m.yaml", says="aliases"),
    Case("alias-bomb-wide", ["check", "{d}/m.yaml"], {"m.yaml": alias_bomb(6, 40)}, (1,), "m.yaml"),
    Case("recursive-alias", ["check", "{d}/m.yaml"], {"m.yaml": "x: &a [*a]\n" + BALL}, (1,), "m.yaml"),
    Case("recursive-alias-map", ["check", "{d}/m.yaml"], {"m.yaml": "x: &a {k: *a}\n" + BALL}, (1,), "m.yaml"),
    Case("undefined-alias", ["check", "{d}/m.yaml"], {"m.yaml": BALL.replace("mass: m}", "mass: *nope}")},
         (1,), "m.yaml"),
    model_case("python-tag-apply", "mass: m}", f'mass: !!python/object/apply:os.system ["touch {MARKER}"]}}'),
    model_case("python-tag-name", "mass: m}", "mass: !!python/name:os.system }"),
    model_case("python-tag-module", "mass: m}", "mass: !!python/module:os }"),
    model_case("custom-tag", "mass: m}", "mass: !shout m}"),
    model_case("binary-tag", "mass: m}", "mass: !!binary aGVsbG8=}"),
    model_case("unhashable-key", "name: ball\n", "name: ball\n[a, b]: 1\n"),
    model_case("number-key", "name: ball\n", "name: ball\n1: one\n"),
    model_case("escape-sequence-in-key", "name: ball\n", 'name: ball\n"\\e]0;pwned\\a\\e[2J": 1\n'),
    model_case("escape-sequence-in-parent", "parent: world, prismatic", 'parent: "\\e]0;pwned\\a", prismatic'),
    Case("mappings-nested-3000-deep", ["check", "{d}/m.yaml"],
         {"m.yaml": BALL + "x: " + "{a: " * 3000 + "1" + "}" * 3000 + "\n"}, (1,), "m.yaml"),
    model_case("alias-of-mapping-as-key", "name: ball\n", "name: ball\njunk: &k {a: 1}\n? *k\n: 2\n"),
    Case("huge-file", ["check", "{d}/m.yaml"], {"m.yaml": BALL + "#" + "x" * 3_000_000 + "\n"}, (1,), "m.yaml",
         says="past the limit"),
    Case("model-is-a-folder", ["check", "{d}/dir.yaml"], {"dir.yaml/keep": ""}, (1, 2)),
    Case("missing-model", ["check", "{d}/absent.yaml"], {}, (1, 2)),
]

# -- 2. Schema and meaning --------------------------------------------------------------------------

SCHEMA_CASES = [
    model_case("missing-name", "name: ball\n", ""),
    model_case("name-with-space", "name: ball", "name: my ball"),
    model_case("name-leading-digit", "name: ball", "name: 2ball"),
    model_case("name-unicode", "name: ball", "name: bäll"),
    model_case("name-trailing-newline", "name: ball", 'name: "ball\\n"'),
    model_case("name-10000-chars", "name: ball", "name: " + "b" * 10000),
    model_case("name-underscore-import", "name: ball", "name: __import__"),
    model_case("frame-name-keyword", "{name: body,", "{name: class,"),
    model_case("frame-name-None", "{name: body,", "{name: None,"),
    model_case("frame-name-world", "{name: body,", "{name: world,"),
    model_case("parameter-named-t", "parameters: {m: 1.0,", "parameters: {t: 1.0, m: 1.0,"),
    model_case("parameter-named-pi", "parameters: {m: 1.0,", "parameters: {pi: 1.0, m: 1.0,"),
    model_case("parameter-named-sin", "parameters: {m: 1.0,", "parameters: {sin: 1.0, m: 1.0,"),
    model_case("jump-named-print", "- name: bounce", "- name: print", "cannot name a jump"),
    model_case("jump-named-len", "- name: bounce", "- name: len", "cannot name a jump"),
    model_case("jump-named-math", "- name: bounce", "- name: math", "cannot name a jump"),
    model_case("jump-named-JUMPS", "- name: bounce", "- name: JUMPS", "cannot name a jump"),
    model_case("jump-named-exec", "- name: bounce", "- name: exec", "cannot name a jump"),
    model_case("duplicate-across-sections", "parameters: {m: 1.0,", "parameters: {body: 1.0, m: 1.0,"),
    model_case("name-taken-by-rate", "parameters: {m: 1.0,", "parameters: {y_dot: 1.0, m: 1.0,"),
    model_case("unknown-top-key", "name: ball\n", "name: ball\nbodys: []\n"),
    model_case("unknown-frame-key", "{name: body, parent: world,", "{name: body, parnt: world, parent: world,"),
    model_case("mass-as-list", "mass: m}", "mass: [1, 2]}"),
    model_case("mass-as-mapping", "mass: m}", "mass: {value: 1}}"),
    model_case("mass-negative", "mass: m}", "mass: -2}"),
    model_case("mass-zero", "mass: m}", "mass: 0}"),
    model_case("mass-nan", "mass: m}", "mass: .nan}"),
    model_case("mass-inf", "mass: m}", "mass: .inf}"),
    model_case("mass-bool", "mass: m}", "mass: true}"),
    model_case("mass-null", "mass: m}", "mass: null}"),
    model_case("parameter-nan", "m: 1.0,", "m: .nan,"),
    model_case("parameter-inf", "m: 1.0,", "m: -.inf,"),
    model_case("parameter-1e400", "m: 1.0,", "m: 1e400,"),
    model_case("parameter-string", "m: 1.0,", "m: heavy,"),
    model_case("initial-1e400", "y: {initial: 1.0}", "y: {initial: 1e400}"),
    model_case("frames-as-mapping", "frames:\n  - {name: body, parent: world, prismatic: y, axis: y}",
               "frames: {body: {parent: world}}"),
    model_case("coordinates-as-list", "coordinates:\n  y: {initial: 1.0}", "coordinates: [y]"),
    model_case("frame-cycle", "{name: body, parent: world, prismatic: y, axis: y}",
               "{name: body, parent: other, prismatic: y, axis: y}\n  - {name: other, parent: body}"),
    model_case("frame-self-parent", "parent: world, prismatic", "parent: body, prismatic"),
    model_case("missing-parent", "parent: world, prismatic", "parent: wrld, prismatic", "did you mean"),
    model_case("body-on-missing-frame", "frame: body, mass", "frame: nobody, mass"),
    model_case("constraint-missing-frame", "holonomic: y}", "holonomic: hand.y}"),
    model_case("flow-missing-constraint", "- {name: flight}", "- {name: flight, constraints: [roof]}"),
    model_case("jump-missing-flow", "from: flight", "from: flying"),
    model_case("jump-bad-direction", "direction: falling", "direction: down"),
    model_case("reset-unknown-name", "direction: falling", "direction: falling\n      reset: {z: 0}"),
    model_case("restitution-string", "restitution: e,", "restitution: bouncy,"),
    model_case("impact-unknown-kind", "impact: {restitution: e, constraints: [ground]}", "impact: elastic"),
    model_case("hybrid-empty", "hybrid:\n", "hybrid: {}\nunused:\n"),
    model_case("flows-empty", "  flows:\n    - {name: flight}\n", "  flows: []\n"),
    model_case("gravity-two-entries", "gravity: [0, -g, 0]", "gravity: [0, -g]"),
    model_case("axis-zero", "axis: y}", "axis: [0, 0, 0]}"),
    model_case("axis-unknown", "axis: y}", "axis: up}"),
    model_case("inertia-wrong-length", "mass: m}", "mass: m, inertia: [1, 2]}"),
    model_case("quaternion-not-unit", "prismatic: y, axis: y}",
               "prismatic: y, axis: y, rotation: {quaternion: [1, 1, 1, 1]}}"),
    model_case("closed-form-unknown-state", "hybrid:\n", "closed_form: {q: t}\nhybrid:\n"),
    model_case("conserves-energy-string", "name: ball\n", "name: ball\nconserves_energy: maybe\n"),
    model_case("axis-nan", "axis: y}", "axis: [.nan, 0, 1]}"),
    model_case("quaternion-nan", "prismatic: y, axis: y}",
               "prismatic: y, axis: y, rotation: {quaternion: [.nan, 0, 0, 0]}}"),
    model_case("initial-uses-time", "y: {initial: 1.0}", "y: {initial: 1 + t}"),
    model_case("velocity-uses-time", "y: {initial: 1.0}", "y: {initial: 1.0, velocity: t}"),
    model_case("mass-uses-time", "mass: m}", "mass: m + t}"),
    *[model_case(f"model-name-{name}", "name: ball", f"name: {name}", "choose another name")
      for name in ("class", "None", "math", "numpy", "numba", "sys", "andyc", "os", "signal", "random")],
    model_case("guard-constant", "guard: y", "guard: m"),
    model_case("guard-comparison", "guard: y", "guard: y > 0"),
]

# -- 3. Expressions ---------------------------------------------------------------------------------

def expr_case(id, text, says="", where="mass: m}", template="mass: {}}}"):
    return model_case(f"expr-{id}", where, template.format(yaml_text(text)), says)


EXPRESSION_CASES = [
    expr_case("import", f"{RUN}", "not allowed"),
    expr_case("class-walk", "().__class__.__bases__[0].__subclasses__()", "not allowed"),
    expr_case("lambda", "(lambda: 1)()", "not allowed"),
    expr_case("comprehension", "[x for x in ()]", "not allowed"),
    expr_case("comment-breakout", f'm #"""; {RUN}; _ = """', "'#'"),
    expr_case("comment-plain", "m # heavy", "'#'"),
    expr_case("single-quotes", "'m'", "not allowed"),
    expr_case("double-quotes", '"m"', "not allowed"),
    expr_case("triple-quotes", '"""m"""', "not allowed"),
    expr_case("backslash", "m \\ 2", "not allowed"),
    expr_case("backslash-newline", "m +\\\n 1", "not allowed"),
    expr_case("nul", "m\x00", "not allowed"),
    expr_case("surrogate", "m\ud800", "not allowed"),
    expr_case("fstring", 'f"{m}"', "not allowed"),
    expr_case("walrus", "(z := 1)", "not allowed"),
    expr_case("attribute-on-number", "(1).real", "not allowed"),
    expr_case("subscript", "m[0]", "not allowed"),
    expr_case("keyword-argument", "sin(x=m)", "keyword"),
    expr_case("starred-argument", "max(*m)", "not allowed"),
    expr_case("caret-power", "m^2", "'^'"),
    expr_case("unknown-function", "sinus(m)", "unknown function"),
    expr_case("eval-call", "eval('1')", "not allowed"),
    expr_case("wrong-arity", "atan2(m)", "takes 2"),
    expr_case("function-as-value", "sin", "used as a value"),
    expr_case("tower-of-powers", "2**2**2**2**2**2", "past the limit"),
    expr_case("huge-exponent", "m**100000", "past the limit"),
    expr_case("float-overflow", "1e308*10", "overflows"),
    expr_case("exp-overflow", "exp(1000)*m", "overflows"),
    expr_case("int-overflow", "1" + "0" * 400, "too large"),
    expr_case("power-overflow", "10**99*10**99*10**99*10**99", "overflows"),
    expr_case("division-by-zero", "m/0", "division by zero"),
    expr_case("division-by-zero-symbolic", "m/(g-g)", "division by zero"),
    expr_case("sqrt-negative", "sqrt(-1)*m", "not a real number"),
    expr_case("log-zero", "log(0)+m", "not a real number"),
    expr_case("negative-fractional-power", "(-8)**(1/3)", "not a real number"),
    expr_case("5000-terms", "+".join(["m"] * 5000), "too long"),
    expr_case("3000-unary-minus", "-" * 3000 + "m", "too long"),
    expr_case("500-parentheses", "(" * 500 + "m" + ")" * 500, "nested too deeply"),
    expr_case("200-nested-sin", "sin(" * 200 + "m" + ")" * 200, "too large"),
    expr_case("long-text", "m +" + " " * 5000 + "1", "too long"),
    expr_case("comparison-as-value", "m > 1", "not allowed"),
    expr_case("empty", "", "empty"),
    expr_case("whitespace", "   ", "empty"),
    expr_case("boolean-and", "m and 1", "not allowed"),
    expr_case("if-else", "1 if m else 2", "not allowed"),
    expr_case("string-concat", "'a' 'b'", "not allowed"),
    expr_case("modulo", "m % 2", "'%'"),
    expr_case("floor-division", "m // 2", "not allowed"),
    expr_case("bitwise", "m | 2", "'|'"),
    expr_case("complex-literal", "1j*m", "not a number"),
    expr_case("ellipsis", "...", "not a number"),
    expr_case("semicolon", "m; m", "';'"),
    expr_case("guard-payload", f'y #"""; {RUN}', "'#'", "guard: y", "guard: {}"),
    expr_case("enabled-equals", "y = 1", "'='", "direction: falling", "direction: falling\n      enabled: {}"),
    expr_case("enabled-value", "y", "not a comparison", "direction: falling", "direction: falling\n      enabled: {}"),
    expr_case("enabled-double-equals", "y == 1", "cannot be a condition", "direction: falling",
              "direction: falling\n      enabled: {}"),
    expr_case("enabled-payload", f"y > 0 # {RUN}", "'#'", "direction: falling", "direction: falling\n      enabled: {}"),
    expr_case("reset-payload", f'0 #"""{RUN}', "'#'", "direction: falling", "direction: falling\n      reset: {{y: {}}}"),
    expr_case("restitution-payload", f"e # {RUN}", "'#'", "restitution: e,", "restitution: {},"),
    expr_case("initial-payload", f"1 # {RUN}", "'#'", "y: {initial: 1.0}", "y: {{initial: {}}}"),
    expr_case("constraint-payload", f"y # {RUN}", "'#'", "holonomic: y}", "holonomic: {}}}"),
    expr_case("gravity-payload", f"g # {RUN}", "'#'", "gravity: [0, -g, 0]", "gravity: [0, {}, 0]"),
]

# -- 4. Text that ends up in generated files -----------------------------------------------------------

PAYLOAD = f'x """; {RUN}; _ = """ \'\'\'; {RUN} \\ \\N{{ \n{RUN}\n# \r{RUN}\x00 \ud800'

TEXT_CASES = [
    # Free text is data: these models are valid (exit 0), and nothing they hold runs when built.
    Case("description-payload-check", ["check", "{d}/m.yaml"],
         ball("description: A point mass on a prismatic joint, bouncing.", f"description: {yaml_text(PAYLOAD)}"),
         (0,), unchanged=("m.yaml",)),
    Case("file-name-payload-check", ["check", '{d}/evil"""\'#\\ name.yaml'], {'evil"""\'#\\ name.yaml': BALL},
         (0,)),
    Case("description-and-file-name-build", ["build", '{d}/evil"""\'# name.yaml', "--build-dir", "{d}/build"],
         {'evil"""\'# name.yaml': BALL.replace("description: A point mass on a prismatic joint, bouncing.",
                                               f"description: {yaml_text(PAYLOAD)}")}, (0,)),
]

# -- 5. URDF ----------------------------------------------------------------------------------------

LINK = '<link name="{0}"><inertial><mass value="{1}"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/>' \
       '</inertial></link>'
JOINT = '<joint name="{0}" type="{3}"><parent link="{1}"/><child link="{2}"/><axis xyz="0 0 1"/></joint>'


def robot(*parts, name="r") -> str:
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n' + "\n".join(parts) + "\n</robot>\n"


GOOD_ROBOT = robot(LINK.format("base", 1), LINK.format("arm", 1), JOINT.format("j", "base", "arm", "continuous"))


def urdf_case(id, text, says="", codes=(1,)):
    return Case(f"urdf-{id}", ["check", "{d}/r.urdf"], {"r.urdf": text}, codes, "r.urdf", ("r.urdf",), says)


URDF_CASES = [
    urdf_case("malformed-xml", GOOD_ROBOT.replace("</robot>", "</robt>")),
    urdf_case("unclosed-tag", GOOD_ROBOT.replace("</robot>\n", "")),
    urdf_case("entity-bomb", '<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY a "aaaaaaaaaa">'
              + "".join(f'<!ENTITY a{i} "{("&a" + str(i - 1) + ";") * 10 if i else "&a;" * 10}">' for i in range(8))
              + ']>\n<robot name="&a7;"></robot>\n', "DOCTYPE"),
    urdf_case("external-entity", '<?xml version="1.0"?>\n<!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n'
              '<robot name="r"><link name="&x;"/></robot>\n', "DOCTYPE"),
    urdf_case("missing-mesh", robot(LINK.format("base", 1).replace(
        "</link>", '<visual><geometry><mesh filename="package://nowhere/m.stl"/></geometry></visual></link>'),
        LINK.format("arm", 1), JOINT.format("j", "base", "arm", "continuous")).replace("continuous", "cylindrical")),
    urdf_case("joint-without-parent", GOOD_ROBOT.replace('<parent link="base"/>', "")),
    urdf_case("joint-unknown-parent", GOOD_ROBOT.replace('<parent link="base"/>', '<parent link="bse"/>')),
    urdf_case("cycle", robot(LINK.format("a", 1), LINK.format("b", 1), JOINT.format("j1", "a", "b", "continuous"),
                             JOINT.format("j2", "b", "a", "continuous"))),
    urdf_case("negative-mass", GOOD_ROBOT.replace('<mass value="1"/>', '<mass value="-1"/>', 1)),
    urdf_case("nan-inertia", GOOD_ROBOT.replace('ixx="1"', 'ixx="nan"', 1)),
    urdf_case("unknown-joint-type", GOOD_ROBOT.replace('type="continuous"', 'type="spherical"')),
    urdf_case("empty-robot", robot()),
    urdf_case("not-a-robot", '<?xml version="1.0"?>\n<house name="h"/>\n'),
    urdf_case("garbage", "\x00\x01 not xml at all"),
    urdf_case("mimic-itself", GOOD_ROBOT.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/><mimic joint="j"/>'),
              "mimics itself"),
    urdf_case("duplicate-link", robot(LINK.format("a", 1), LINK.format("a", 1))),
    urdf_case("bad-origin", GOOD_ROBOT.replace('<axis xyz="0 0 1"/>', '<origin xyz="1 2"/><axis xyz="0 0 1"/>')),
    urdf_case("zero-axis", GOOD_ROBOT.replace('<axis xyz="0 0 1"/>', '<axis xyz="0 0 0"/>')),
    Case("urdf-key-missing-file", ["check", "{d}/m.yaml"], {"m.yaml": "name: r\nurdf: absent.urdf\n"}, (1,),
         "m.yaml"),
    Case("urdf-key-folder", ["check", "{d}/m.yaml"], {"m.yaml": "name: r\nurdf: sub\n", "sub/keep": ""}, (1,),
         "m.yaml"),
    Case("urdf-key-bad-lock", ["check", "{d}/m.yaml"],
         {"m.yaml": "name: r\nurdf: {file: r.urdf, lock: {nope: 0}}\n", "r.urdf": GOOD_ROBOT}, (1,), "m.yaml"),
]

# -- 6. Command-line values and output paths -------------------------------------------------------------

CART = ["{m}/cart_pole.yaml", "--build-dir", "{b}"]


def sim_option(id, *option, says=""):
    return Case(f"sim{id}", ["sim", *CART, "--t-end", "0.01", *option, "--out", "{d}/r.h5"], {}, (2,), says=says)


OPTION_CASES = [
    *[sim_option(f"-{name}-{value}", f"--{name}", value)
      for name in ("t-end", "dt", "rtol", "atol", "event-tol", "init-tol", "energy-tol", "zeno-tol", "timeout")
      for value in ("nan", "inf", "-1")],
    sim_option("-dt-0", "--dt", "0"),
    sim_option("-dt-tiny", "--dt", "1e-300", says="steps"),
    sim_option("-t-end-huge", "--t-end", "1e300", says="steps"),
    sim_option("-every-0", "--every", "0"),
    sim_option("-every-negative", "--every", "-1"),
    sim_option("-every-float", "--every", "2.5"),
    sim_option("-huge-log", "--dt", "1e-5", "--t-end", "1e5", says="GB"),
    sim_option("-max-instant-jumps-0", "--max-instant-jumps", "0"),
    sim_option("-rtol-1", "--rtol", "1"),
    sim_option("-set-nan", "--set", "m=nan"),
    sim_option("-set-inf", "--set", "m=inf"),
    sim_option("-set-malformed", "--set", "m"),
    sim_option("-set-unknown", "--set", "nope=1"),
    sim_option("-input-malformed", "--input", "F"),
    sim_option("-input-unknown", "--input", "G=1"),
    sim_option("-input-twice", "--input", "F=1", "--input", "F=2"),
    sim_option("-input-payload", "--input", f"F=0 # {RUN}", says="'#'"),
    sim_option("-input-tower", "--input", "F=2**2**2**2**2**2", says="past the limit"),
    sim_option("-input-5000-terms", "--input", "F=" + "+".join(["x"] * 5000), says="too long"),
    sim_option("-method-unknown", "--method", "euler"),
    sim_option("-init-unknown", "--init", "maybe"),
    sim_option("-frames-unknown", "--frames", "hand"),
    sim_option("-stop-after-zero", "--stop-after", "bounce=0"),
    sim_option("-stop-after-negative", "--stop-after", "bounce=-1"),
    sim_option("-stop-after-unknown", "--stop-after", "fly=1", says="unknown jump 'fly'"),
    Case("sim-out-unknown-type", ["sim", *CART, "--out", "{d}/r.txt"], {}, (2,)),
    Case("sim-out-is-folder", ["sim", *CART, "--out", "{d}/dir.h5"], {"dir.h5/keep": ""}, (2,), says="folder"),
    Case("sim-out-under-file", ["sim", *CART, "--out", "{d}/file/r.h5"], {"file": "x"}, (2,), says="not a folder"),
    Case("sim-out-is-model", ["sim", "{d}/m.csv", "--out", "{d}/m.csv", "--build-dir", "{d}/build"],
         {"m.csv": (MODELS / "double_pendulum.yaml").read_text()}, (2,), unchanged=("m.csv",), says="overwrite"),
    Case("sim-out-is-table", ["sim", *CART, "--input", "F={d}/push.csv", "--out", "{d}/push.csv"],
         {"push.csv": "t,F\n0,0\n10,1\n"}, (2,), unchanged=("push.csv",), says="overwrite"),
    Case("sim-out-is-controller", ["sim", *CART, "--controller", "{d}/c.csv", "--out", "{d}/c.csv"],
         {"c.csv": "def control(t, x, d, p):\n    return 0.0\n"}, (2,), unchanged=("c.csv",), says="overwrite"),
    Case("build-over-model", ["build", "{d}/build/ball/ball.py", "--build-dir", "{d}/build"], {"build/ball/ball.py": BALL},
         (2,), unchanged=("build/ball/ball.py",), says="overwrite"),
    Case("build-dir-is-file", ["build", "{d}/m.yaml", "--build-dir", "{d}/m.yaml"], {"m.yaml": BALL}, (2,),
         unchanged=("m.yaml",)),
    Case("eom-over-model", ["eom", "{d}/m.yaml", "-o", "{d}/m.yaml"], {"m.yaml": BALL}, (2,), unchanged=("m.yaml",),
         says="overwrite"),
    Case("eom-out-is-folder", ["eom", "{d}/m.yaml", "-o", "{d}/dir"], {"m.yaml": BALL, "dir/keep": ""}, (2,)),
    Case("eom-out-under-file", ["eom", "{d}/m.yaml", "-o", "{d}/m.yaml/eq.tex"], {"m.yaml": BALL}, (2,),
         unchanged=("m.yaml",)),
    Case("linearize-out-is-file", ["linearize", "{d}/m.yaml", "-o", "{d}/m.yaml"], {"m.yaml": BALL}, (2,),
         unchanged=("m.yaml",)),
    Case("linearize-at-nan", ["linearize", "{m}/cart_pole.yaml", "--at", "th=nan"], {}, (2,)),
    Case("linearize-at-inf", ["linearize", "{m}/cart_pole.yaml", "--at", "th=inf"], {}, (2,)),
    Case("linearize-at-unknown", ["linearize", "{m}/cart_pole.yaml", "--at", "phi=1"], {}, (1,)),
    Case("linearize-time-nan", ["linearize", "{m}/cart_pole.yaml", "--time", "nan"], {}, (2,)),
    Case("linearize-flow-unknown", ["linearize", "{m}/cart_pole.yaml", "--flow", "nope"], {}, (1,)),
    Case("bench-repeats-0", ["bench", "{m}/cart_pole.yaml", "--repeats", "0", "-o", "{d}"], {}, (2,)),
    Case("bench-t-end-nan", ["bench", "{m}/cart_pole.yaml", "--t-end", "nan", "-o", "{d}"], {}, (2,)),
    Case("bench-steps-negative", ["bench", *CART[:1], "--build-dir", "{b}", "--steps", "-1e-3", "-o", "{d}"], {},
         (2,)),
    Case("bench-steps-geom-huge", ["bench", *CART[:1], "--build-dir", "{b}", "--steps", "geom:1e-3:1e-2:10000000",
                                   "-o", "{d}"], {}, (2,)),
    Case("bench-tols-nan", ["bench", *CART[:1], "--build-dir", "{b}", "--tols", "nan", "-o", "{d}"], {}, (2,)),
    Case("bench-out-is-file", ["bench", *CART[:1], "--build-dir", "{b}", "-o", "{d}/f"], {"f": "x"}, (2,)),
    Case("stability-tol-0", ["stability", "{m}/cart_pole.yaml", "--tol", "0", "-o", "{d}"], {}, (2,)),
    Case("stability-blowup-nan", ["stability", "{m}/cart_pole.yaml", "--blowup", "nan", "-o", "{d}"], {}, (2,)),
    Case("stability-horizon-negative", ["stability", "{m}/cart_pole.yaml", "--horizon", "-1", "-o", "{d}"], {},
         (2,)),
    Case("stability-residual-inf", ["stability", "{m}/cart_pole.yaml", "--residual-tol", "inf", "-o", "{d}"], {},
         (2,)),
    Case("plot-fps-0", ["plot", "{d}/r.h5", "--animate", "--fps", "0"], {"r.h5": b"x"}, (2,)),
    Case("plot-not-h5", ["plot", "{d}/r.csv"], {"r.csv": "t\n0\n"}, (2,)),
    Case("plot-garbage-h5", ["plot", "{d}/r.h5"], {"r.h5": b"\x89HDF garbage"}, (2,), unchanged=("r.h5",)),
    Case("plot-over-run", ["plot", "{d}/r.h5", "-o", "{d}/r.h5"], {"r.h5": b"\x89HDF garbage"}, (2,),
         unchanged=("r.h5",), says="overwrite"),
    Case("check-a-fifo", ["check", "{d}/m.yaml"], {"m.yaml": FIFO}, (1,), "m.yaml", says="special file"),
    Case("check-dev-zero", ["check", "/dev/zero"], {}, (1,), "/dev/zero:1", says="special file"),
    sim_option("-input-nan", "--input", "F=nan"),
    sim_option("-input-inf", "--input", "F=-inf"),
    Case("sim-out-read-only", ["sim", *CART, "--t-end", "0.01", "--out", "{ro}/r.h5"], {}, (2,),
         says="cannot write"),
    Case("linearize-set-nan", ["linearize", "{m}/cart_pole.yaml", "--set", "g=nan"], {}, (2,)),
    Case("linearize-input-nan", ["linearize", "{m}/cart_pole.yaml", "--input", "F=nan"], {}, (2,)),
    Case("linearize-equilibrium-g-nan", ["linearize", "{m}/cart_pole.yaml", "--find-equilibrium", "--set", "g=nan"],
         {}, (2,)),
    Case("linearize-at-no-name", ["linearize", "{m}/cart_pole.yaml", "--at", "=1"], {}, (1,)),
    Case("bench-steps-0", ["bench", *CART[:1], "--build-dir", "{b}", "--steps", "0", "-o", "{d}"], {}, (2,)),
    Case("stability-steps-empty", ["stability", *CART[:1], "--build-dir", "{b}", "--steps", "", "-o", "{d}"], {},
         (2,)),
    Case("plot-out-is-folder", ["plot", "{run}", "-o", "{d}/dir"], {"dir/keep": ""}, (2,), says="folder"),
    Case("plot-out-under-file", ["plot", "{run}", "-o", "{d}/f/p.png"], {"f": "x"}, (2,), says="not a folder"),
    Case("plot-empty-h5", ["plot", "{d}/e.h5"], {"e.h5": EMPTY_H5}, (2,), unchanged=("e.h5",)),
    Case("check-no-file", ["check"], {}, (2,)),
    Case("unknown-command", ["simulate", "m.yaml"], {}, (2,)),
]

# -- 7. Input tables and controllers ---------------------------------------------------------------------

def table_case(id, text, says=""):
    content = text.encode("latin-1") if isinstance(text, str) and "\xff" in text else text
    return Case(f"table-{id}", ["sim", *CART, "--t-end", "0.01", "--input", "F={d}/push.csv", "--out", "{d}/r.h5"],
                {"push.csv": content}, (2,), "push.csv", ("push.csv",), says)


def controller_case(id, text, says="", codes=(1, 2), where="c.py"):
    return Case(f"controller-{id}", ["sim", *CART, "--t-end", "0.01", "--controller", "{d}/c.py", "--out",
                                     "{d}/r.h5"], {"c.py": text}, codes, where, ("c.py",), says)


INPUT_CASES = [
    table_case("no-time-column", "a,F\n0,1\n1,2\n", "no time column"),
    table_case("no-value-column", "t,a,b\n0,1,2\n1,2,3\n", "no column"),
    table_case("non-numeric", "t,F\n0,1\n0.005,heavy\n1,2\n", "not a finite number"),
    table_case("empty-cell", "t,F\n0,1\n0.005,\n1,2\n", "empty"),
    table_case("nan-cell", "t,F\n0,1\n0.005,nan\n1,2\n", "not a finite number"),
    table_case("decreasing-time", "t,F\n0,1\n0.5,2\n0.2,3\n1,2\n", "does not increase"),
    table_case("single-row", "t,F\n0,1\n", "two or more"),
    table_case("short", "t,F\n0,1\n0.001,2\n", "covers"),
    table_case("garbage", "\xff\xfe\x00\x01", ""),
    table_case("empty", "", "empty"),
    Case("table-missing", ["sim", *CART, "--input", "F={d}/nope.csv", "--out", "{d}/r.h5"], {}, (2,),
         says="no such file"),
    controller_case("syntax-error", "def control(t, x, d, p)\n    return 0.0\n", where="c.py:1"),
    controller_case("raises-at-import", "raise RuntimeError('no')\n", "RuntimeError"),
    controller_case("exits-at-import", "import sys\nsys.exit(0)\n", "sys.exit"),
    controller_case("exits-at-import-nonzero", "import sys\nsys.exit('bye')\n", "sys.exit"),
    controller_case("no-control", "def contrl(t, x, d, p):\n    return 0.0\n", "defines no function", where=None),
    controller_case("control-not-callable", "control = 5\n", "defines no function"),
    controller_case("nul-byte", "def control(t, x, d, p):\n    return 0.0\x00\n", "importing the controller"),
    controller_case("wrong-arity", "def control(t, x):\n    return 0.0\n", "four arguments"),
    controller_case("wrong-shape", "def control(t, x, d, p):\n    return [1.0, 2.0]\n", "returned"),
    controller_case("returns-text", "def control(t, x, d, p):\n    return 'push'\n", "returned"),
    controller_case("raises-at-start", "def control(t, x, d, p):\n    raise ValueError('no')\n", "ValueError"),
    controller_case("exits-at-start", "import sys\ndef control(t, x, d, p):\n    sys.exit(1)\n", "sys.exit"),
    controller_case("raises-later-python",
                    "import os\ndef control(t, x, d, p):\n    if t > 0.005:\n        raise ValueError('late')\n"
                    "    os.getpid()\n    return 0.0\n", "ValueError: late", (1,)),
    controller_case("exits-later-python",
                    "import sys\ndef control(t, x, d, p):\n    if t > 0.005:\n        import sys; sys.exit(3)\n"
                    "    return 0.0\n", "sys.exit(3)", (1,)),
    controller_case("raises-later-compiled",
                    "def control(t, x, d, p):\n    if t > 0.005:\n        raise ValueError('late')\n    return 0.0\n",
                    "ValueError", (1,)),
    controller_case("binary", "\x00\x01\x02 not python", "importing the controller"),
    Case("controller-missing", ["sim", *CART, "--controller", "{d}/nope.py", "--out", "{d}/r.h5"], {}, (2,),
         says="no such file"),
    Case("controller-and-input", ["sim", *CART, "--controller", "{d}/c.py", "--input", "F=1", "--out", "{d}/r.h5"],
         {"c.py": "def control(t, x, d, p):\n    return 0.0\n"}, (2,), says="drop one"),
    Case("jumps-file-broken", ["sim", "{d}/m.yaml", "--t-end", "0.01", "--build-dir", "{d}/build"],
         {"m.yaml": BALL, "build/ball/ball_jumps.py": "def bounce(t, x, u, p, d)\n    pass\n"}, (1, 2),
         "ball_jumps.py"),
]

CASES = YAML_CASES + SCHEMA_CASES + EXPRESSION_CASES + TEXT_CASES + URDF_CASES + OPTION_CASES + INPUT_CASES


def test_the_corpus_is_large_and_its_ids_unique():
    ids = [c.id for c in CASES]
    assert len(ids) == len(set(ids))
    assert len([c for c in CASES if c.codes != (0,)]) >= 150


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.id)
def test_hostile_input_gets_a_message_not_a_traceback(case, tmp_path, build_dir, compiled, monkeypatch):
    if any("{b}" in a for a in case.args):
        compiled("cart_pole")                                   # the shared model, built once per session
    for name, content in case.files.items():
        path = tmp_path / name
        path.parent.mkdir(parents=True, exist_ok=True)
        if name.endswith("/keep"):
            continue
        if content is FIFO:
            os.mkfifo(path)
            continue
        path.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8", "surrogatepass"))
    before = {name: (tmp_path / name).read_bytes() for name in case.unchanged}
    monkeypatch.chdir(tmp_path)                             # payloads would touch MARKER here
    args = [str(a).replace("{d}", str(tmp_path)).replace("{b}", str(build_dir)).replace("{m}", str(MODELS))
            .replace("{ro}", str(read_only(tmp_path))).replace("{run}", str(run_file(tmp_path))) for a in case.args]
    result = invoke(*args)
    text = result.output                                    # stdout and stderr, as a terminal shows them
    assert result.exception is None or isinstance(result.exception, SystemExit), repr(result.exception)
    assert result.exit_code in case.codes, text
    assert not [f for f in case.forbid if f in text], text
    if case.where:
        assert re.search(re.escape(case.where) + (r"" if ":" in case.where else r":\d+"), text), text
    assert case.says in text, text
    assert not (tmp_path / MARKER).exists()
    for name, content in before.items():
        assert (tmp_path / name).read_bytes() == content, f"{name} changed"
    if case.id == "description-and-file-name-build":
        _import_built(tmp_path / "build" / "ball")
        assert not (tmp_path / MARKER).exists()


def read_only(tmp_path: Path) -> Path:
    """A folder nothing can be written in: /sys for root (whom permissions do not stop), else one made so."""
    if os.geteuid() == 0:
        return Path("/sys")
    folder = tmp_path / "ro"
    folder.mkdir(exist_ok=True)
    folder.chmod(0o500)
    return folder


def run_file(tmp_path: Path) -> Path:
    """A small run file of a made-up model, to plot."""
    import numpy as np

    from andyc.runtime.run import Run
    path = tmp_path / "run.h5"
    if not path.exists():
        Run(model="m", spec_sha256="0", method="rk4", dt=1e-3, nq=1, nv=1, rtol=0.0, atol=0.0, t_end=1.0,
            parameters={}, inputs={}, state_names=["y", "y_dot"], time=np.linspace(0, 1, 11), state=np.ones((11, 2)),
            energy=np.zeros(11)).save(path)
    return path


def _import_built(folder: Path) -> None:
    """Import a module andyc built (its top level and its jumps file run; nothing is compiled)."""
    import importlib.util
    import sys

    spec = importlib.util.spec_from_file_location("andyc_corpus_ball", folder / "ball.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    try:
        spec.loader.exec_module(module)
        assert module.DESCRIPTION.startswith('x """')
    finally:
        for name in (spec.name, getattr(module, "MODULE_NAME", ""), spec.name + "_jumps"):
            sys.modules.pop(name, None)
