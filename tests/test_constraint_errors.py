"""Mistakes in `constraints:` and `conserves_energy:` give one clear line each.

Same style as tests/test_check_errors.py: each case writes a small model into
tmp_path and checks the line (computed from the text written here), the
document path, and that the message says what is wrong and the hint what to do.
"""

from __future__ import annotations

import re

import pytest

import andyc
from tests.support import MODELS
from tests.support.cli import check
from tests.support.diagnostics import assert_at, check_all_at_once, edit, line_of, load_text, one_problem, problems

BALL_IN_BOWL = MODELS / "ball_in_bowl.yaml"

# A bead on three prismatic joints held on a circle (holonomic, written with frame
# positions) and skating (nonholonomic, with a frame velocity in frame slide's axes).
BEAD = """\
name: bead
parameters:
  L: 1.0
  m: 1.0
  g: 9.81
  k: 10.0
  b: 2.0
coordinates:
  x: {initial: 1.0}
  y: {}
  z: {}
gravity: [0, -g, 0]
conserves_energy: true
frames:
  - {name: slide, parent: world, prismatic: x, axis: x}
  - {name: lift, parent: slide, prismatic: y, axis: y}
  - {name: tip, parent: lift, prismatic: z}
bodies:
  - {name: bob, frame: tip, mass: m}
constraints:
  - name: rod
    holonomic: tip.x**2 + tip.y**2 - L**2
    multiplier: tension
    gains: {stiffness: k, damping: b}
  - name: skate
    nonholonomic: [tip.vz - x*y_dot]
    in: slide
    gains:
      damping: b
"""

ROD = "tip.x**2 + tip.y**2 - L**2"           # the holonomic row, constraints[0].holonomic
SKATE = "[tip.vz - x*y_dot]"                  # the nonholonomic rows, constraints[1].nonholonomic
NAMES_IN_HOLONOMIC_ROWS = "names allowed here: L, b, g, k, m, pi, t, x, y, z"
KNOWN_FRAMES = "known frames: lift, slide, tip, world"
WORKS = "remove 'conserves_energy: true', or the elements that do work"


def with_rod(row: str) -> str:
    return edit(BEAD, ROD, row)


def with_skate(rows: str) -> str:
    return edit(BEAD, SKATE, rows)


def test_the_base_model_is_valid(tmp_path):
    file = tmp_path / "model.yaml"
    file.write_text(BEAD)
    spec = andyc.load(file)
    andyc.derive(spec)
    assert [(c.name, c.holonomic, c.multipliers) for c in spec.constraints] == [
        ("rod", True, ("tension",)), ("skate", False, ("lambda_skate",))]
    assert spec.conserves_energy


# -- 1. holonomic or nonholonomic --------------------------------------------------

@pytest.mark.parametrize("old, new, message", [
    (f"    holonomic: {ROD}\n", f"    holonomic: {ROD}\n    nonholonomic: x_dot\n",
     "conflicting fields 'holonomic', 'nonholonomic': a constraint is given one way only"),
    (f"    holonomic: {ROD}\n", "", "a constraint needs 'holonomic' or 'nonholonomic'"),
], ids=["both", "neither"])
def test_constraint_is_holonomic_or_nonholonomic(tmp_path, old, new, message):
    text = edit(BEAD, old, new)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: rod"), "constraints[0]")
    assert d.message == message
    assert d.hint == "give either 'holonomic: <expressions>' or 'nonholonomic: <expressions>'"


def test_typo_in_a_constraint_field_suggests_the_field(tmp_path):
    text = edit(BEAD, "    holonomic: tip", "    holonomc: tip")
    # (The schema's oneOf also says "a constraint needs 'holonomic' or 'nonholonomic'" on the line above.)
    typo = [d for d in problems(tmp_path, text) if d.path == "constraints[0].holonomc"]
    assert len(typo) == 1
    assert_at(typo[0], line_of(text, "holonomc:"), "constraints[0].holonomc")
    assert typo[0].message == "unknown field 'holonomc'"
    assert typo[0].hint.startswith("did you mean 'holonomic'? allowed fields: gains, holonomic, in, multiplier")


def test_typo_in_a_gain_suggests_the_gain(tmp_path):
    text = edit(BEAD, "{stiffness: k, damping: b}", "{stifness: k, damping: b}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "stifness"), "constraints[0].gains.stifness")
    assert d.message == "unknown field 'stifness'"
    assert d.hint == "did you mean 'stiffness'? allowed fields: damping, stiffness"


@pytest.mark.parametrize("rows, shown", [("[]", "a list []"), ("true", "true")])
def test_rows_that_are_no_expression(tmp_path, rows, shown):
    text = with_rod(rows)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"holonomic: {rows}"), "constraints[0].holonomic")
    assert d.message == f"{shown} is not a valid constraint expression"
    assert "one expression" in d.hint and "list" in d.hint


# -- 2. names and frame quantities in the rows ---------------------------------------

def test_unknown_name_in_a_holonomic_row_suggests_a_parameter(tmp_path):
    text = with_rod("tip.x**2 + tip.y**2 - LL**2")
    d = one_problem(tmp_path, text)           # and not also "does not depend on the coordinates"
    assert_at(d, line_of(text, "LL**2"), "constraints[0].holonomic")
    assert d.message == "in 'tip.x**2 + tip.y**2 - LL**2': unknown name 'LL'"
    assert d.hint.startswith(f"did you mean 'L'? {NAMES_IN_HOLONOMIC_ROWS} (holonomic constraints use")
    assert "F.x, F.y, F.z" in d.hint and "F.vx" not in d.hint


@pytest.mark.parametrize("row, name, what", [
    ("tip.vx + tip.y - L", "tip.vx", "a velocity"),
    ("tip.wz + tip.y - L", "tip.wz", "an angular velocity"),
    ("x_dot + tip.y - L", "x_dot", "a speed"),
], ids=["velocity", "angular-velocity", "speed"])
def test_velocity_in_a_holonomic_row(tmp_path, row, name, what):
    text = with_rod(row)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, row), "constraints[0].holonomic")
    assert d.message == f"in {row!r}: '{name}' is {what}; a holonomic constraint depends on positions only"
    assert "under 'nonholonomic:'" in d.hint and "F.x, F.y, F.z" in d.hint


def test_declared_speed_in_a_holonomic_row_is_called_a_speed(tmp_path):
    text = edit(BEAD, "  z: {}\n", "  z: {}\nspeeds:\n  spin: {}\n")
    text = edit(text, ROD, "tip.x - spin")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "tip.x - spin"), "constraints[0].holonomic")
    assert "'spin' is a speed" in d.message
    assert "under 'nonholonomic:'" in d.hint


def test_unknown_frame_in_a_frame_quantity_suggests_the_frame(tmp_path):
    text = with_rod("tipp.x**2 + tip.y**2 - L**2")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "tipp.x"), "constraints[0].holonomic")
    assert d.message == "in 'tipp.x**2 + tip.y**2 - L**2': frame 'tipp' does not exist"
    assert d.hint == f"did you mean 'tip'? {KNOWN_FRAMES}"


def test_body_used_as_a_frame_names_its_frame(tmp_path):
    text = with_rod("bob.x - L")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "bob.x - L"), "constraints[0].holonomic")
    assert d.message == "in 'bob.x - L': 'bob' is a body, not a frame"
    assert d.hint.startswith("use the frame it is on: 'tip.x'") and KNOWN_FRAMES in d.hint


@pytest.mark.parametrize("quantity, suggestion", [("tip.q", None), ("tip.X", "tip.x"), ("tip.vxx", "tip.vx")])
def test_unknown_attribute_of_a_frame(tmp_path, quantity, suggestion):
    text = with_skate(f"[{quantity} - x*y_dot]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, quantity), "constraints[1].nonholonomic[0]")
    assert d.message == f"in '{quantity} - x*y_dot': '{quantity}' is not a frame quantity"
    assert d.hint.startswith(f"did you mean '{suggestion}'? " if suggestion else "frame quantities: F.x")
    assert "F.vx, F.vy, F.vz (velocity)" in d.hint


@pytest.mark.parametrize("rows, quantity, why", [
    ("[world.vx + y_dot]", "world.vx", "the world frame does not move"),
    ("[slide.x*y_dot + z_dot]", "slide.x", "positions are measured from the origin of the 'in' frame, here 'slide'"),
], ids=["world-velocity", "in-frame-position"])
def test_frame_quantity_that_is_always_zero(tmp_path, rows, quantity, why):
    text = with_skate(rows)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, rows), "constraints[1].nonholonomic[0]")
    assert f"'{quantity}' is always 0: {why}" in d.message
    assert "another frame" in d.hint or "moving frame" in d.hint


def test_in_names_a_missing_frame(tmp_path):
    text = edit(BEAD, "    in: slide\n", "    in: slidee\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "in: slidee"), "constraints[1].in")
    assert d.message == "frame 'slidee' does not exist"
    assert d.hint == f"did you mean 'slide'? {KNOWN_FRAMES}"


def test_in_without_frame_quantities_has_no_effect(tmp_path):
    text = with_skate("[z_dot - x*y_dot]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "in: slide"), "constraints[1].in")
    assert d.message == "'in: slide' has no effect: the constraint uses no frame quantity"
    assert d.hint.startswith("remove 'in'")


# -- 3. what each kind of row may be ---------------------------------------------------

@pytest.mark.parametrize("row", ["tip.vz - sqrt(tip.vx**2 + y_dot**2)", "tip.vz**2 - x*y_dot**2",
                                 "tip.vz*tip.vx - z*y_dot**2"],
                         ids=["cone", "squared-speeds", "product-of-velocities"])
def test_nonholonomic_row_nonlinear_in_the_speeds_is_a_row(tmp_path, row):
    """Braun & Goldfarb's Phi_v(t, q, v) = 0 (issue 24); each is homogeneous in the speeds, so its force does no
    work and conserves_energy stands (Euler: dPhi/dv v = k Phi)."""
    spec = load_text(tmp_path, with_skate(f"[z_dot - y_dot, {row}]"))
    (skate,) = [c for c in spec.constraints if c.name == "skate"]
    assert skate.nonlinear == (1,) and spec.conserves_energy and spec.warnings == []


@pytest.mark.parametrize("row, why", [
    ("tip.vz - x*y_dot**2 - y_dot", "has a force whose power lam dPhi/dv v is not 0 on the motion"),
    ("tip.vy**2 + tip.vz**2 - L**2", "has a force whose power lam dPhi/dv v is not 0 on the motion"),
], ids=["mixed-degrees", "isokinetic"])
def test_conserves_energy_with_a_nonlinear_row_that_does_work(tmp_path, row, why):
    text = with_skate(f"[{row}]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "conserves_energy: true"), "conserves_energy")
    assert d.message == f"the model declares energy conserved, but constraint 'skate' ({row!r} {why}) does work"


@pytest.mark.parametrize("row", ["sin(tip.vz)**2 + cos(tip.vz)**2 - x", "tip.vz*(sin(x)**2 + cos(x)**2 - 1)"],
                         ids=["nonlinear", "linear"])
def test_nonholonomic_row_whose_speed_jacobian_vanishes(tmp_path, row):
    """Speeds written, but dPhi/dv = 0 identically: no constraint on the speeds (and no force direction)."""
    text = with_skate(f"[{row}]")
    d = one_problem(tmp_path, text)           # and no conserves_energy complaint about the same row
    assert_at(d, line_of(text, row), "constraints[1].nonholonomic[0]")
    assert d.message == (f"in {row!r}: the derivative of the constraint with respect to the speeds is identically 0, "
                         "so it does not constrain them")
    assert d.hint.startswith("simplify the row: a constraint on positions goes under 'holonomic:'")


@pytest.mark.parametrize("row, kink", [("abs(tip.vz) - y_dot", "abs"), ("tip.vz - max(y_dot, 0)", "max"),
                                       ("sign(tip.vz)*y_dot - x", "sign")])
def test_nonholonomic_row_not_smooth_in_the_speeds(tmp_path, row, kink):
    text = with_skate(f"['{row}']")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, row), "constraints[1].nonholonomic[0]")
    assert d.message == (f"in {row!r}: the constraint is not smooth in the speeds: its derivative jumps where "
                         f"{kink} of a speed or velocity switches branch")
    assert d.hint.startswith("write a smooth row")


HOPPER = """name: hop
parameters: {m: 1, g: 9.81, k: 0.5}
coordinates:
  x: {velocity: 2}
  y: {initial: 1, velocity: 1}
gravity: [0, -g, 0]
frames:
  - {name: sx, parent: world, prismatic: x, axis: x}
  - {name: p, parent: sx, prismatic: y, axis: y}
bodies:
  - {name: bead, frame: p, mass: m}
constraints:
  - {name: ground, holonomic: y}
  - {name: steer, nonholonomic: x_dot**2 + y_dot**2 - 5}
"""


def test_an_impact_on_a_nonlinear_row_is_refused(tmp_path):
    text = HOPPER + """hybrid:
  flows: [{name: air, constraints: [steer]}, {name: down, constraints: [ground, steer]}]
  jumps:
    - {name: land, from: air, to: down, guard: y, direction: falling, impact: plastic}
"""
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "impact: plastic"), "hybrid.jumps[0].impact")
    assert d.message == ("the impact of jump 'land' acts on constraint 'steer', whose rows are not all linear in "
                         "the speeds")
    assert "impact: {restitution: e, constraints: [...]}" in d.hint
    named = edit(text, "impact: plastic", "impact: {restitution: 0, constraints: [ground]}")
    assert load_text(tmp_path, named, "named.yaml").jumps[0].impact_constraints == ("ground",)


def test_contacts_with_a_nonlinear_row_are_refused(tmp_path):
    text = edit(HOPPER, "  - {name: ground, holonomic: y}\n", "") + "contacts:\n  - {name: ground, gap: y}\n"
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "x_dot**2 + y_dot**2 - 5"), "constraints[0].nonholonomic")
    assert d.message == ("constraint 'steer' is not linear in the speeds, and the model has contacts, whose impacts "
                         "keep the model's constraints through their rows J v + b = 0")


def test_nonholonomic_row_with_no_speed(tmp_path):
    text = with_skate("[z_dot - y_dot, tip.x - x]")
    d = one_problem(tmp_path, text)           # and not also a conserves_energy complaint
    assert_at(d, line_of(text, "tip.x - x"), "constraints[1].nonholonomic[1]")
    assert d.message == "the constraint 'tip.x - x' uses no speed or velocity"
    assert "under 'holonomic:'" in d.hint


@pytest.mark.parametrize("row", ["L", "2*pi - L", "t - L"])
def test_holonomic_row_of_only_time_and_parameters(tmp_path, row):
    text = with_rod(row)
    d = one_problem(tmp_path, text)           # 't - L' is not also reported as doing work
    assert_at(d, line_of(text, f"holonomic: {row}"), "constraints[0].holonomic")
    assert d.message == f"the constraint {row!r} does not depend on the coordinates or any frame position"
    assert "Gamma(t, q) = 0" in d.hint and "F.x, F.y, F.z" in d.hint


# -- 4. multipliers ------------------------------------------------------------------

@pytest.mark.parametrize("old, new, path, message, hint", [
    ("    multiplier: tension\n", "    multiplier: [tension, pull]\n", "constraints[0].multiplier",
     "2 multiplier name(s) for 1 constraint row(s)", "give one name per row (1)"),
    ("    in: slide\n", "    in: slide\n    multiplier: friction\n", "constraints[1].multiplier",
     "1 multiplier name(s) for 2 constraint row(s)", "give one name per row (2)"),
], ids=["two-for-one", "one-for-two"])
def test_wrong_number_of_multiplier_names(tmp_path, old, new, path, message, hint):
    text = edit(with_skate("[tip.vz - x*y_dot, tip.vy]"), old, new)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, new.splitlines()[-1]), path)
    assert (d.message, d.hint) == (message, hint)


def test_multiplier_name_used_by_two_constraints(tmp_path):
    text = edit(BEAD, "    in: slide\n", "    in: slide\n    multiplier: tension\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "multiplier: tension", occurrence=2), "constraints[1].multiplier")
    assert d.message == "the multiplier name 'tension' is used twice (also in constraint 'rod')"
    assert d.hint == "give each constraint row its own multiplier name"


def test_multiplier_name_listed_twice_in_one_constraint(tmp_path):
    text = edit(with_skate("[tip.vz - x*y_dot, tip.vy]"), "    in: slide\n", "    in: slide\n    multiplier: [f, f]\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "multiplier: [f, f]"), "constraints[1].multiplier[1]")
    assert d.message == "the multiplier name 'f' is used twice (also earlier in this constraint)"


def test_multiplier_name_taken_by_a_default_name_points_at_that_constraint(tmp_path):
    text = edit(BEAD, "multiplier: tension", "multiplier: lambda_skate")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: skate"), "constraints[1].name")
    assert d.message == ("the default multiplier name 'lambda_skate' of constraint 'skate' is used twice "
                         "(also in constraint 'rod')")
    assert d.hint == "name the multiplier: add 'multiplier: <name>' to constraint 'skate'"


@pytest.mark.parametrize("name, owner", [
    ("L", "a parameter"), ("x", "a coordinate"), ("tip", "a frame"), ("bob", "a body"), ("skate", "a constraint"),
    ("x_dot", "the rate of coordinate 'x'"), ("energy", "the run-file column 'energy'"),
])
def test_multiplier_name_taken_by_another_name(tmp_path, name, owner):
    text = edit(BEAD, "multiplier: tension", f"multiplier: {name}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"multiplier: {name}"), "constraints[0].multiplier")
    assert d.message == f"the multiplier name '{name}' is taken by {owner}"
    assert d.hint == "choose another name"


# -- 5. gains ----------------------------------------------------------------------

@pytest.mark.parametrize("old, new, needle, path, shown", [
    ("{stiffness: k, damping: b}", "{stiffness: -k, damping: b}", "stiffness: -k",
     "constraints[0].gains.stiffness", "the stiffness gain is negative, got -k = -10"),
    ("      damping: b\n", "      damping: -0.5\n", "damping: -0.5",
     "constraints[1].gains.damping", "the damping gain is negative, got -0.5"),
], ids=["holonomic-stiffness", "nonholonomic-damping"])
def test_negative_gain(tmp_path, old, new, needle, path, shown):
    text = edit(BEAD, old, new)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, needle), path)
    assert d.message == shown
    assert d.hint.startswith("give a gain >= 0")


@pytest.mark.parametrize("gain, message", [
    ("t*k", "the stiffness gain 't*k' depends on t"),
    ("x*k", "in 'x*k': coordinate 'x' cannot be used here"),
], ids=["time", "coordinate"])
def test_gain_that_is_not_a_constant(tmp_path, gain, message):
    text = edit(BEAD, "{stiffness: k, damping: b}", f"{{stiffness: '{gain}', damping: b}}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, gain), "constraints[0].gains.stiffness")
    assert d.message == message
    assert "parameters" in d.hint


def test_stiffness_on_a_nonholonomic_constraint(tmp_path):
    text = edit(BEAD, "      damping: b\n", "      damping: b\n      stiffness: -k\n")
    d = one_problem(tmp_path, text)           # only that: its (negative) value is not checked as well
    assert_at(d, line_of(text, "stiffness: -k"), "constraints[1].gains.stiffness")
    assert d.message.startswith("a nonholonomic constraint has no stiffness")
    assert d.hint.startswith("remove 'stiffness'")


# -- 6. constraint names -------------------------------------------------------------

@pytest.mark.parametrize("constraint, name, first", [
    ("rod", "tip", "frames[2].name"), ("rod", "bob", "bodies[0].name"), ("skate", "rod", "constraints[0].name"),
], ids=["frame", "body", "constraint"])
def test_constraint_name_already_taken(tmp_path, constraint, name, first):
    text = edit(BEAD, f"  - name: {constraint}\n", f"  - name: {name}\n")
    d = one_problem(tmp_path, text)
    again = 2 if first.startswith("constraints") else 1
    assert_at(d, line_of(text, f"- name: {name}", occurrence=again), f"constraints[{again - 1}].name")
    assert d.message == f"duplicate name '{name}' (first defined at line {line_of(text, f'name: {name}')}, {first})"
    assert d.hint.startswith("rename one")


# -- 7. conserves_energy ---------------------------------------------------------------

@pytest.mark.parametrize("old, new, worker", [
    ("constraints:\n", "dampers:\n  - {name: drag, speed: x, coefficient: b}\nconstraints:\n", "damper 'drag'"),
    ("constraints:\n", "forces:\n  - {name: push, frame: tip, vector: [1, 0, 0]}\nconstraints:\n", "force 'push'"),
    (ROD, "tip.x**2 + tip.y**2 - (L + 0.1*t)**2", "constraint 'rod' (depends on t)"),
    (SKATE, "[tip.vz - x*y_dot - 0.5]", "constraint 'skate' ('tip.vz - x*y_dot - 0.5' has a term without speeds)"),
    ("constraints:\n", "potentials:\n  - {name: well, energy: 'k*x**2*cos(t)'}\nconstraints:\n",
     "potential 'well' (depends on t)"),
    ("  - {name: tip, parent: lift, prismatic: z}\n",
     "  - {name: tip, parent: lift, prismatic: z, rotation: {axis: z, angle: t}}\n",
     "frame 'tip' (its link depends on t)"),
], ids=["damper", "force", "rheonomic-holonomic", "nonholonomic-with-b", "time-potential", "driven-frame"])
def test_conserves_energy_with_an_element_that_does_work(tmp_path, old, new, worker):
    text = edit(BEAD, old, new)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "conserves_energy: true"), "conserves_energy")
    assert d.message == f"the model declares energy conserved, but {worker} does work"
    assert d.hint == WORKS


def test_conserves_energy_lists_every_element_that_does_work(tmp_path):
    text = edit(BEAD, "constraints:\n", "dampers:\n  - {name: drag, speed: x, coefficient: b}\n"
                "forces:\n  - {name: push, frame: tip, vector: [1, 0, 0]}\nconstraints:\n")
    d = one_problem(tmp_path, text)
    assert d.message == "the model declares energy conserved, but damper 'drag', force 'push' do work"


def test_conserves_energy_accepts_a_time_dependent_coefficient_of_the_speeds(tmp_path):
    spec = load_text(tmp_path, with_skate("[tip.vz - t*y_dot]"))      # J(t) v = 0: its force does no work
    assert spec.conserves_energy and spec.warnings == []


def test_elements_that_do_work_are_fine_without_conserves_energy(tmp_path):
    text = edit(with_rod("tip.x**2 + tip.y**2 - (L + 0.1*t)**2"), "conserves_energy: true\n", "")
    text = edit(text, "constraints:\n", "dampers:\n  - {name: drag, speed: x, coefficient: b}\nconstraints:\n")
    file = tmp_path / "model.yaml"
    file.write_text(text)
    spec = andyc.load(file)
    assert not spec.conserves_energy and [x.name for x in spec.dampers] == ["drag"]


# -- 8. the command line (click's CliRunner, in process) --------------------------------

def test_cli_check_one_bad_constraint_prints_one_line(tmp_path, monkeypatch):
    text = with_rod("tipp.x**2 + tip.y**2 - L**2")
    (tmp_path / "bad.yaml").write_text(text)
    monkeypatch.chdir(tmp_path)
    result = check("bad.yaml")
    assert result.exit_code == 1
    assert result.stdout == ""
    assert result.stderr.splitlines() == [
        f"bad.yaml:{line_of(text, 'tipp.x')}: constraints[0].holonomic: "
        f"in 'tipp.x**2 + tip.y**2 - L**2': frame 'tipp' does not exist; did you mean 'tip'? {KNOWN_FRAMES}",
        "1 problem found"]


def test_cli_check_reports_every_constraint_problem_at_once(tmp_path, monkeypatch):
    text = edit(with_skate("[abs(tip.vz) - tip.vx]"), "{stiffness: k, damping: b}", "{stiffness: -k, damping: b}")
    text = edit(text, "constraints:\n", "dampers:\n  - {name: drag, speed: x, coefficient: b}\nconstraints:\n")
    found = check_all_at_once(tmp_path, monkeypatch, text, 3)
    assert [(m["file"], int(m["line"]), m["path"]) for m in found] == [
        ("bad.yaml", line_of(text, "conserves_energy: true"), "conserves_energy"),
        ("bad.yaml", line_of(text, "stiffness: -k"), "constraints[0].gains.stiffness"),
        ("bad.yaml", line_of(text, "abs(tip.vz)"), "constraints[1].nonholonomic[0]")]
    assert "damper 'drag'" in found[0]["what"] and "not smooth" in found[2]["what"]


def test_cli_check_ball_in_bowl_is_valid():
    result = check(BALL_IN_BOWL)
    assert result.exit_code == 0, result.stderr
    assert result.stderr == ""
    assert re.match(rf"{re.escape(str(BALL_IN_BOWL))}: model 'ball_in_bowl' is valid: 6 speeds "
                    r"\(rho, alpha, beta, wx, wy, wz\) less 3 constraint rows \(1 holonomic\) in 2 constraints",
                    result.stdout)
