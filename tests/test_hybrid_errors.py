"""Mistakes in `hybrid:` (flows, jumps, guards, conditions, resets, impacts) and
`discrete:` give one clear line each.

Same style as tests/test_check_errors.py: each case writes a small model into
tmp_path and checks the line (computed from the text written here), the
document path, and that the message says what is wrong and the hint what to do.
"""

from __future__ import annotations

import pytest

import andyc
from andyc.errors import SimulationError
from tests.support import MODELS
from tests.support.cli import check
from tests.support.diagnostics import (LINE_FORMAT, assert_at, check_all_at_once, edit, line_of, load_text, one_problem,
                                       problems)

HYBRID_MODELS = ["bouncing_ball", "rimless_wheel", "compass_gait"]

# A point foot on two prismatic joints: it flies (pushed by an input the flight flow sets), lands
# (plastic impact, the foot pinned where it landed: a discrete state), and lifts off at t = L
# (an impact of restitution e on the ground constraint alone).
HOPPER = """\
name: hopper
parameters:
  m: 1.0
  g: 9.81
  e: 0.5
  L: 1.0
inputs:
  push: 0.0
discrete:
  fx: 0
coordinates:
  x: {initial: 0.5}
  y: {initial: 1.0}
gravity: [0, -g, 0]
frames:
  - {name: slide, parent: world, prismatic: x, axis: x}
  - {name: foot, parent: slide, prismatic: y, axis: y}
bodies:
  - {name: mass, frame: foot, mass: m}
forces:
  - {name: drive, frame: foot, vector: [push, 0, 0]}
constraints:
  - {name: ground, holonomic: foot.y}
  - {name: pin, holonomic: x - fx}
hybrid:
  initial: flight
  flows:
    - name: flight
      inputs: {push: 1.0}
    - name: stance
      constraints: [ground, pin]
  jumps:
    - name: land
      from: flight
      to: stance
      guard: foot.y
      direction: falling
      enabled: foot.x > fx
      reset: {fx: foot.x}
      impact: plastic
    - name: lift
      from: stance
      to: flight
      guard: t - L
      direction: rising
      impact: {restitution: e, constraints: [ground]}
"""

GUARD = "guard: foot.y"                                 # hybrid.jumps[0].guard
ENABLED = "enabled: foot.x > fx"                        # hybrid.jumps[0].enabled
RESET = "reset: {fx: foot.x}"                           # hybrid.jumps[0].reset
IMPACT = "impact: {restitution: e, constraints: [ground]}"   # hybrid.jumps[1].impact
NAMES_IN_JUMPS = "names allowed here: L, e, fx, g, m, pi, push, t, x, x_dot, y, y_dot"
JUMP_CONTEXT = "(guards, conditions and resets use parameters, inputs, coordinates, speeds"
RESETTABLE = ("resets assign coordinates, speeds (<coordinate>_dot and declared speeds) and discrete states: "
              "x, y, x_dot, y_dot, fx")
KNOWN_FRAMES = "known frames: foot, slide, world"
NOT_A_GUARD = ("a guard is a signed expression of the coordinates, speeds, frame quantities or t that crosses 0 "
               "where the jump happens")


def test_the_base_model_is_valid(tmp_path):
    spec = load_text(tmp_path, HOPPER)
    assert spec.warnings == []
    assert [(f.name, f.constraints) for f in spec.flows] == [("flight", ()), ("stance", ("ground", "pin"))]
    assert [(j.name, j.source, j.target, j.impact, j.impact_constraints) for j in spec.jumps] == [
        ("land", "flight", "stance", "plastic", ("ground", "pin")),
        ("lift", "stance", "flight", "restitution", ("ground",))]
    assert [x.name for x in spec.discrete] == ["fx"] and spec.initial_flow == 0
    andyc.derive(spec)


@pytest.mark.parametrize("name", HYBRID_MODELS)
def test_the_shipped_hybrid_models_load_without_warnings(name):
    spec = andyc.load(MODELS / f"{name}.yaml")
    assert spec.jumps and spec.warnings == []


# -- 1. the cases of the issue: names that do not exist ---------------------------------

def test_unknown_name_in_a_guard_suggests_the_name(tmp_path):
    text = edit(HOPPER, GUARD, "guard: foot.y - fxx")
    d = one_problem(tmp_path, text)           # and not also "the guard does not change during a flow"
    assert_at(d, line_of(text, "guard: foot.y - fxx"), "hybrid.jumps[0].guard")
    assert d.message == "in 'foot.y - fxx': unknown name 'fxx'"
    assert d.hint.startswith(f"did you mean 'fx'? {NAMES_IN_JUMPS} {JUMP_CONTEXT}")
    assert "discrete states, t and frame quantities: F.x, F.y, F.z (position)" in d.hint


@pytest.mark.parametrize("field, old, new, path", [
    ("to", "      to: stance\n", "      to: stanse\n", "hybrid.jumps[0].to"),
    ("from", "      from: flight\n", "      from: flite\n", "hybrid.jumps[0].from"),
], ids=["to", "from"])
def test_jump_to_or_from_a_missing_flow(tmp_path, field, old, new, path):
    text = edit(HOPPER, old, new)
    d = one_problem(tmp_path, text)           # and the impact into a missing flow is not reported too
    missing = new.split(": ")[1].strip()
    assert_at(d, line_of(text, new.strip()), path)
    assert d.message == f"flow '{missing}' does not exist"
    assert d.hint == f"did you mean '{'stance' if field == 'to' else 'flight'}'? flows: flight, stance"


def test_flow_names_a_missing_constraint(tmp_path):
    text = edit(HOPPER, "constraints: [ground, pin]", "constraints: [ground, pinn]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "constraints: [ground, pinn]"), "hybrid.flows[1].constraints[1]")
    assert d.message == "constraint 'pinn' does not exist"
    assert d.hint == "did you mean 'pin'? constraints: ground, pin"


def test_reset_of_a_name_that_does_not_exist(tmp_path):
    text = edit(HOPPER, RESET, "reset: {fxx: foot.x}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "reset: {fxx"), "hybrid.jumps[0].reset.fxx")
    assert d.message == "cannot reset 'fxx': it is not a coordinate, speed or discrete state"
    assert d.hint == f"did you mean 'fx'? {RESETTABLE}"


# -- 2. flows and jumps ---------------------------------------------------------------

def test_duplicate_flow_name_points_at_the_first(tmp_path):
    text = edit(HOPPER, "    - name: stance\n", "    - name: flight\n    - name: stance\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: flight", occurrence=2), "hybrid.flows[1].name")
    assert d.message == (f"duplicate flow name 'flight' (first defined at line {line_of(text, '- name: flight')}, "
                         "hybrid.flows[0].name)")
    assert d.hint == "give each flow its own name"


def test_duplicate_flow_name_lists_each_flow_once(tmp_path):
    # Renaming 'stance' to 'flight' also leaves the jumps' 'stance' dangling: flows are listed once.
    text = edit(HOPPER, "    - name: stance\n", "    - name: flight\n")
    found = problems(tmp_path, text)
    assert [(d.line, d.path) for d in found] == [
        (line_of(text, "- name: flight", occurrence=2), "hybrid.flows[1].name"),
        (line_of(text, "to: stance"), "hybrid.jumps[0].to"),
        (line_of(text, "from: stance"), "hybrid.jumps[1].from")]
    assert [d.message for d in found[1:]] == ["flow 'stance' does not exist"] * 2
    assert [d.hint for d in found[1:]] == ["flows: flight"] * 2


def test_duplicate_jump_name_points_at_the_first(tmp_path):
    text = edit(HOPPER, "    - name: lift\n", "    - name: land\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: land", occurrence=2), "hybrid.jumps[1].name")
    assert d.message == (f"duplicate jump name 'land' (first defined at line {line_of(text, '- name: land')}, "
                         "hybrid.jumps[0].name)")
    assert d.hint == "give each jump its own name"


def test_unknown_initial_flow(tmp_path):
    text = edit(HOPPER, "initial: flight", "initial: flihgt")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "initial: flihgt"), "hybrid.initial")
    assert d.message == "flow 'flihgt' does not exist"
    assert d.hint == "did you mean 'flight'? flows: flight, stance"


@pytest.mark.parametrize("direction", ["down", "falling_edge"])
def test_direction_that_is_not_falling_rising_or_either(tmp_path, direction):
    text = edit(HOPPER, "direction: falling", f"direction: {direction}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"direction: {direction}"), "hybrid.jumps[0].direction")
    assert d.message == f"the text '{direction}' is not allowed here"
    assert d.hint == "use one of: falling, rising, either"


@pytest.mark.parametrize("field, line", [
    ("guard", "      guard: t - L\n"), ("direction", "      direction: rising\n"), ("to", "      to: flight\n"),
])
def test_jump_without_a_required_field(tmp_path, field, line):
    text = edit(HOPPER, line, "")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: lift"), "hybrid.jumps[1]")
    assert d.message == f"missing required field '{field}'"
    assert d.hint == f"add '{field}:' here"


@pytest.mark.parametrize("old, new, path, fields", [
    ("      guard: foot.y\n", "      gaurd: foot.y\n", "hybrid.jumps[0].gaurd",
     "direction, enabled, from, guard, impact, name, priority, reset, to"),
    ("      constraints: [ground, pin]\n", "      constraint: [ground, pin]\n", "hybrid.flows[1].constraint",
     "constraints, energy_law, inputs, name"),
    ("  initial: flight\n", "  intial: flight\n", "hybrid.intial", "flows, initial, jumps"),
    ("  jumps:\n", "  jump:\n", "hybrid.jump", "flows, initial, jumps"),
], ids=["jump-gaurd", "flow-constraint", "hybrid-intial", "hybrid-jump"])
def test_typo_in_a_hybrid_field_suggests_the_field(tmp_path, old, new, path, fields):
    text = edit(HOPPER, old, new)
    d = one_problem(tmp_path, text)           # a typo of 'guard' is not also a missing 'guard'
    typo = path.rsplit(".", 1)[1]
    meant = old.split(":")[0].strip()
    assert_at(d, line_of(text, f"{typo}:"), path)
    assert d.message == f"unknown field '{typo}'"
    assert d.hint == f"did you mean '{meant}'? allowed fields: {fields}"


def test_flow_lists_a_constraint_twice(tmp_path):
    text = edit(HOPPER, "constraints: [ground, pin]", "constraints: [ground, pin, ground]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "constraints: [ground, pin, ground]"), "hybrid.flows[1].constraints[2]")
    assert (d.message, d.hint) == ("constraint 'ground' is listed twice", "list it once")


def test_unknown_input_in_a_flow(tmp_path):
    text = edit(HOPPER, "inputs: {push: 1.0}", "inputs: {puhs: 1.0}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "inputs: {puhs"), "hybrid.flows[0].inputs.puhs")
    assert d.message == "input 'puhs' does not exist"
    assert d.hint == "did you mean 'push'? inputs: push"


@pytest.mark.parametrize("value, message", [
    ("x", "in 'x': coordinate 'x' cannot be used here"),
    ("t", "the value 't' of input 'push' in flow 'flight' depends on t"),     # (it broke the build)
], ids=["coordinate", "time"])
def test_flow_input_that_is_not_a_constant(tmp_path, value, message):
    text = edit(HOPPER, "inputs: {push: 1.0}", f"inputs: {{push: {value}}}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "inputs: {push"), "hybrid.flows[0].inputs.push")
    assert d.message == message
    assert "parameters" in d.hint


# -- 3. guards ----------------------------------------------------------------------

@pytest.mark.parametrize("guard", ["L - 1", "fx - L", "push", "2*pi"],
                         ids=["parameters", "discrete-state", "input", "number"])
def test_guard_that_does_not_change_during_a_flow(tmp_path, guard):
    text = edit(HOPPER, "guard: t - L", f"guard: {guard}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"guard: {guard}"), "hybrid.jumps[1].guard")
    assert d.message == f"the guard {guard!r} does not change during a flow"
    assert d.hint == NOT_A_GUARD


@pytest.mark.parametrize("guard, fix", [
    ("t > L", "'guard: t - L' with 'direction: rising'"),
    ("foot.y < fx + L", "'guard: foot.y - (fx + L)' with 'direction: falling'"),
    ("t == L", "'guard: t - L' with 'direction: either'"),
], ids=["greater", "less", "equal"])
def test_guard_written_as_a_comparison(tmp_path, guard, fix):
    text = edit(HOPPER, "guard: t - L", f"guard: {guard}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"guard: {guard}"), "hybrid.jumps[1].guard")
    assert d.message == f"the guard {guard!r} is a comparison"
    assert fix in d.hint and "under 'enabled:'" in d.hint


@pytest.mark.parametrize("guard, message, hint", [
    ("fot.y", "in 'fot.y': frame 'fot' does not exist", f"did you mean 'foot'? {KNOWN_FRAMES}"),
    ("mass.y", "in 'mass.y': 'mass' is a body, not a frame", f"use the frame it is on: 'foot.y'; {KNOWN_FRAMES}"),
    ("foot.yy", "in 'foot.yy': 'foot.yy' is not a frame quantity", "did you mean 'foot.y'? frame quantities: F.x"),
], ids=["missing-frame", "body", "attribute"])
def test_frame_quantity_of_a_missing_frame_in_a_guard(tmp_path, guard, message, hint):
    text = edit(HOPPER, GUARD, f"guard: {guard}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"guard: {guard}"), "hybrid.jumps[0].guard")
    assert d.message == message
    assert d.hint.startswith(hint)


@pytest.mark.parametrize("old, new, path, text_", [
    (GUARD, "guard: foot", "hybrid.jumps[0].guard", "foot"),
    (ENABLED, "enabled: foot > fx", "hybrid.jumps[0].enabled", "foot > fx"),
], ids=["guard", "enabled"])
def test_frame_name_used_as_a_value(tmp_path, old, new, path, text_):
    text = edit(HOPPER, old, new)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, new), path)
    assert d.message == f"in {text_!r}: frame 'foot' cannot be used here"
    assert d.hint.startswith(NAMES_IN_JUMPS) and "F.x, F.y, F.z" in d.hint


# -- 4. enabling conditions -------------------------------------------------------------

@pytest.mark.parametrize("condition", ["foot.x - fx", "foot.x > fx and y > 0"], ids=["expression", "and"])
def test_enabled_that_is_not_a_comparison(tmp_path, condition):
    text = edit(HOPPER, ENABLED, f"enabled: {condition}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"enabled: {condition}"), "hybrid.jumps[0].enabled")
    assert d.message == f"{condition!r} is not a comparison"
    assert d.hint == ('write a comparison with <, <=, > or >=, such as "foot.x > fx"; '
                      "give several as a list (all must hold)")


@pytest.mark.parametrize("condition, op", [("foot.x == fx", "=="), ("foot.x = fx", "="), ("foot.x != fx", "!=")],
                         ids=["double-equals", "equals", "not-equal"])
def test_enabled_that_is_an_equality(tmp_path, condition, op):
    text = edit(HOPPER, ENABLED, f"enabled: {condition}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"enabled: {condition}"), "hybrid.jumps[0].enabled")
    assert d.message == f"in {condition!r}: '{op}' " + ("is not a comparison" if op == "=" else
                                                         "cannot be a condition")
    assert "write <, <=, > or >=" in d.hint and "make 'a - b' the guard" in d.hint


def test_enabled_with_an_unknown_name_suggests_the_name(tmp_path):
    text = edit(HOPPER, ENABLED, "enabled: foot.x > fxx")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "enabled: foot.x > fxx"), "hybrid.jumps[0].enabled")
    assert d.message == "in 'foot.x > fxx': unknown name 'fxx'"
    assert d.hint.startswith(f"did you mean 'fx'? {NAMES_IN_JUMPS} {JUMP_CONTEXT}")


def test_enabled_list_points_at_the_bad_entry(tmp_path):
    text = edit(HOPPER, ENABLED, "enabled:\n        - foot.x > fx\n        - y < gg")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- y < gg"), "hybrid.jumps[0].enabled[1]")
    assert d.message == "in 'y < gg': unknown name 'gg'"
    assert d.hint.startswith(f"did you mean 'g'? {NAMES_IN_JUMPS}")


@pytest.mark.parametrize("value, shown", [("3", "the number 3"), ("[]", "a list []"), ("true", "true")])
def test_enabled_that_is_not_text(tmp_path, value, shown):
    text = edit(HOPPER, ENABLED, f"enabled: {value}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"enabled: {value}"), "hybrid.jumps[0].enabled")
    assert d.message == f"{shown} is not a valid condition"
    assert d.hint == 'write a comparison such as "foot.x > fx", or a list of them (all must hold)'


def test_enabled_that_does_not_parse(tmp_path):
    text = edit(HOPPER, ENABLED, "enabled: foot.x > > fx")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "enabled: foot.x > > fx"), "hybrid.jumps[0].enabled")
    assert d.message.startswith("cannot parse 'foot.x > > fx'")
    assert d.hint == 'write a comparison such as "x > 0"'


# -- 5. resets ----------------------------------------------------------------------

def test_reset_of_a_parameter_is_not_allowed(tmp_path):
    text = edit(HOPPER, RESET, "reset: {fx: foot.x, L: 2}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "reset: {fx: foot.x, L: 2}"), "hybrid.jumps[0].reset.L")
    assert d.message == "cannot reset parameter 'L': parameters keep their value for the whole run"
    assert d.hint == ("for a value that changes at jumps, declare a discrete state under 'discrete:' and reset that; "
                      + RESETTABLE)


def test_reset_of_an_input_points_at_the_flow(tmp_path):
    text = edit(HOPPER, RESET, "reset: {fx: foot.x, push: 0}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "push: 0}"), "hybrid.jumps[0].reset.push")
    assert d.message == "cannot reset input 'push': inputs are set by the run or by a flow's 'inputs'"
    assert d.hint == f"set it in flow 'stance' with 'inputs: {{push: <value>}}'; {RESETTABLE}"


@pytest.mark.parametrize("value, message, hint", [
    ("foot.xx", "in 'foot.xx': 'foot.xx' is not a frame quantity", "did you mean 'foot.x'?"),
    ("xx + 1", "in 'xx + 1': unknown name 'xx'", f"did you mean 'x'? {NAMES_IN_JUMPS}"),
], ids=["frame-quantity", "name"])
def test_bad_value_of_a_reset(tmp_path, value, message, hint):
    text = edit(HOPPER, RESET, f"reset: {{fx: {value}}}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"reset: {{fx: {value}"), "hybrid.jumps[0].reset.fx")
    assert d.message == message
    assert d.hint.startswith(hint)


# -- 6. impacts ---------------------------------------------------------------------

@pytest.mark.parametrize("old, new, shown", [
    ("restitution: e,", "restitution: 1.5,", "1.5"),
    ("restitution: e,", "restitution: -0.2,", "-0.2"),
    ("  e: 0.5\n", "  e: 1.5\n", "e = 1.5"),
], ids=["above-one", "negative", "parameter"])
def test_restitution_outside_zero_one(tmp_path, old, new, shown):
    text = edit(HOPPER, old, new)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "impact: {restitution"), "hybrid.jumps[1].impact.restitution")
    assert d.message == f"the coefficient of restitution is {shown}, outside [0, 1]"
    assert d.hint == "give 0 (plastic) to 1 (elastic); more than 1 would add energy at every impact"


@pytest.mark.parametrize("value, message", [
    ("0.5*t", "the coefficient of restitution '0.5*t' depends on t"),      # (it said "is nan")
    ("x", "in 'x': coordinate 'x' cannot be used here"),
    ("ee", "in 'ee': unknown name 'ee'"),
], ids=["time", "coordinate", "unknown"])
def test_restitution_that_is_not_a_constant(tmp_path, value, message):
    text = edit(HOPPER, "restitution: e,", f"restitution: {value},")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "impact: {restitution"), "hybrid.jumps[1].impact.restitution")
    assert d.message == message
    assert "parameters" in d.hint


@pytest.mark.parametrize("impact", ["plastic", "{restitution: e}"])
def test_impact_into_a_flow_without_constraints(tmp_path, impact):
    text = edit(HOPPER, IMPACT, f"impact: {impact}")
    d = one_problem(tmp_path, text)
    last = text.count(f"impact: {impact}")                # 'impact: plastic' is also jump 0's
    assert_at(d, line_of(text, f"impact: {impact}", occurrence=last), "hybrid.jumps[1].impact")
    assert d.message == ("the impact has no constraint rows to act on: the target flow 'flight' has no "
                         "constraints")
    assert d.hint.startswith("name the constraints that take the impact: impact: {restitution: e, constraints: "
                             "[names]}")


def test_impact_names_a_missing_constraint(tmp_path):
    text = edit(HOPPER, IMPACT, "impact: {restitution: e, constraints: [grund]}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "constraints: [grund]"), "hybrid.jumps[1].impact.constraints[0]")
    assert d.message == "constraint 'grund' does not exist"
    assert d.hint == "did you mean 'ground'? constraints: ground, pin"


def test_impact_lists_a_constraint_twice(tmp_path):
    text = edit(HOPPER, IMPACT, "impact: {restitution: e, constraints: [ground, ground]}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "[ground, ground]"), "hybrid.jumps[1].impact.constraints[1]")
    assert (d.message, d.hint) == ("constraint 'ground' is listed twice", "list it once")


@pytest.mark.parametrize("impact, shown", [
    ("elastic", "the text 'elastic'"),
    ("{restitution: e, constraint: [ground]}", "a mapping"),       # (the typo itself is not named)
    ("{constraints: [ground]}", "a mapping"),
], ids=["word", "field-typo", "no-restitution"])
def test_impact_that_is_not_an_impact(tmp_path, impact, shown):
    text = edit(HOPPER, IMPACT, f"impact: {impact}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"impact: {impact}"), "hybrid.jumps[1].impact")
    assert d.message == f"{shown} is not a valid impact"
    assert d.hint == "write plastic, none, or {restitution: e} (optionally with 'constraints: [names]')"


# -- 7. discrete states ----------------------------------------------------------------

@pytest.mark.parametrize("name, first", [("x", "coordinates.x"), ("m", "parameters.m"), ("push", "inputs.push")])
def test_discrete_state_name_clashes(tmp_path, name, first):
    text = edit(HOPPER, "  fx: 0\n", f"  fx: 0\n  {name}: 0\n")
    d = one_problem(tmp_path, text)           # and the first owner keeps the name: no follow-on errors
    assert_at(d, line_of(text, "  fx: 0") + 1, f"discrete.{name}")
    first_line = line_of(text, {"x": "  x: {", "m": "  m: 1.0", "push": "  push: 0.0"}[name])
    assert d.message == f"duplicate name '{name}' (first defined at line {first_line}, {first})"
    assert d.hint.startswith("rename one")


def test_discrete_state_named_like_a_coordinate_rate(tmp_path):
    text = edit(HOPPER, "  fx: 0\n", "  fx: 0\n  x_dot: 0\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "x_dot: 0"), "discrete.x_dot")
    assert (d.message, d.hint) == ("the name 'x_dot' is taken by the rate of coordinate 'x'", "choose another name")


def test_frame_named_like_a_discrete_state(tmp_path):
    text = edit(HOPPER, "  fx: 0\n", "  fx: 0\n  slide: 0\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "{name: slide"), "frames[0].name")
    assert d.message == f"duplicate name 'slide' (first defined at line {line_of(text, 'slide: 0')}, discrete.slide)"


@pytest.mark.parametrize("value, message", [
    ("t", "the initial value 't' of discrete state 'fx' depends on t"),      # (it broke the build)
    ("y", "in 'y': coordinate 'y' cannot be used here"),
    ("LL", "in 'LL': unknown name 'LL'"),
], ids=["time", "coordinate", "unknown"])
def test_discrete_initial_value_that_is_not_a_constant(tmp_path, value, message):
    text = edit(HOPPER, "  fx: 0\n", f"  fx: {value}\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"  fx: {value}"), "discrete.fx")
    assert d.message == message
    assert "parameters" in d.hint


# -- 8. warnings ------------------------------------------------------------------

def warning_of(spec):
    assert len(spec.warnings) == 1, spec.warnings
    w = spec.warnings[0]
    match = LINE_FORMAT.match(str(w))
    assert match and (int(match["line"]), match["path"]) == (w.line, w.path)
    return w


def test_constraint_active_in_no_flow_and_taking_no_impact_warns(tmp_path):
    text = edit(HOPPER, "constraints: [ground, pin]", "constraints: [ground]")
    w = warning_of(load_text(tmp_path, text))
    assert_at(w, line_of(text, "{name: pin"), "constraints[1]")
    assert w.message == "constraint 'pin' is active in no flow and takes no impact"
    assert w.hint == "list it in a flow's 'constraints', or remove it"


def test_constraint_that_only_takes_an_impact_does_not_warn(tmp_path):
    text = edit(HOPPER, "constraints: [ground, pin]", "constraints: [pin]")
    assert load_text(tmp_path, text).warnings == []            # 'ground' takes the impact of 'lift'


def test_unused_discrete_state_warns(tmp_path):
    text = edit(HOPPER, "  fx: 0\n", "  fx: 0\n  steps: 0\n")
    w = warning_of(load_text(tmp_path, text))
    assert_at(w, line_of(text, "steps: 0"), "discrete.steps")
    assert w.message == "discrete state 'steps' is not used"
    assert w.hint == "remove it, or use it in a constraint, guard or reset"


def test_discrete_state_used_only_in_a_reset_counts_as_used(tmp_path):
    text = edit(HOPPER, "  fx: 0\n", "  fx: 0\n  steps: 0\n")
    text = edit(text, RESET, "reset: {fx: foot.x, steps: steps + 1}")
    assert load_text(tmp_path, text).warnings == []


# -- 9. the command line (click's CliRunner, in process) --------------------------------

def test_cli_check_one_bad_jump_prints_one_line(tmp_path, monkeypatch):
    text = edit(HOPPER, "      to: stance\n", "      to: stanse\n")
    (tmp_path / "bad.yaml").write_text(text)
    monkeypatch.chdir(tmp_path)
    result = check("bad.yaml")
    assert result.exit_code == 1
    assert result.stdout == ""
    assert result.stderr.splitlines() == [
        f"bad.yaml:{line_of(text, 'to: stanse')}: hybrid.jumps[0].to: flow 'stanse' does not exist; "
        "did you mean 'stance'? flows: flight, stance",
        "1 problem found"]


def test_cli_check_reports_every_hybrid_problem_at_once(tmp_path, monkeypatch):
    text = edit(HOPPER, GUARD, "guard: fot.y")
    text = edit(text, RESET, "reset: {L: 2}")
    text = edit(text, "restitution: e,", "restitution: 1.5,")
    text = edit(text, "constraints: [ground, pin]", "constraints: [ground, pinn]")
    found = check_all_at_once(tmp_path, monkeypatch, text, 4)
    assert [(m["file"], int(m["line"]), m["path"]) for m in found] == [
        ("bad.yaml", line_of(text, "[ground, pinn]"), "hybrid.flows[1].constraints[1]"),
        ("bad.yaml", line_of(text, "guard: fot.y"), "hybrid.jumps[0].guard"),
        ("bad.yaml", line_of(text, "reset: {L: 2}"), "hybrid.jumps[0].reset.L"),
        ("bad.yaml", line_of(text, "restitution: 1.5"), "hybrid.jumps[1].impact.restitution")]
    assert "frame 'fot' does not exist" in found[1]["what"] and "parameter 'L'" in found[2]["what"]


def test_cli_check_prints_hybrid_warnings_and_passes(tmp_path, monkeypatch):
    text = edit(HOPPER, "  fx: 0\n", "  fx: 0\n  steps: 0\n")
    (tmp_path / "warn.yaml").write_text(text)
    monkeypatch.chdir(tmp_path)
    result = check("warn.yaml")
    assert result.exit_code == 0, result.stderr
    assert "model 'hopper' is valid" in result.stdout
    assert result.stderr.splitlines() == [
        f"warn.yaml:{line_of(text, 'steps: 0')}: discrete.steps: discrete state 'steps' is not used; "
        "remove it, or use it in a constraint, guard or reset (warning)"]


@pytest.mark.parametrize("name", HYBRID_MODELS)
def test_cli_check_shipped_hybrid_models_are_valid(name):
    result = check(MODELS / f"{name}.yaml")
    assert result.exit_code == 0, result.stderr
    assert result.stderr == ""
    assert f"model '{name}' is valid" in result.stdout


# -- 10. run-time mistakes (one build of bouncing_ball) ---------------------------------

def test_simulate_stop_after_an_unknown_jump_names_the_jumps(compiled):
    model = compiled("bouncing_ball")
    with pytest.raises(SimulationError) as info:
        andyc.simulate(model, 0.1, dt=1e-3, events=andyc.Events(stop_after={"nope": 1}), progress=False)
    message = str(info.value)
    assert "unknown jump 'nope'" in message and "stop_after" in message
    assert message.endswith("jumps of bouncing_ball: bounce")


def test_simulate_from_an_unknown_flow_names_the_flows(compiled):
    model = compiled("bouncing_ball")
    with pytest.raises(SimulationError) as info:
        andyc.simulate(model, 0.1, dt=1e-3, flow0="nope", progress=False)
    message = str(info.value)
    assert "unknown flow 'nope'" in message
    assert message.endswith("flows of bouncing_ball: flight")
