"""Malformed nonholonomic links (ball, floating, nonholonomic) and speeds give one clear line each.

Same style as tests/test_check_errors.py: each case writes a small model into
tmp_path and checks the line (computed from the text written here), the
document path, and that the message says what is wrong and the hint what to do.
"""

from __future__ import annotations

import re

import pytest
import sympy as sp

import andyc
from andyc.spec.expressions import TIME
from tests.support import MODELS
from tests.support.cli import andyc_cli
from tests.support.diagnostics import LINE_FORMAT, assert_at, edit, line_of, load_text, one_problem, problems

SWING_BAR = MODELS / "swing_bar.yaml"

# A revolute arm carrying a ball joint with a bob below it (1 coordinate, 3 speeds).
BALL = """\
name: swing
parameters:
  L: 1.0
  m: 2.0
coordinates:
  q1: {initial: 0.1}
speeds:
  wx: {initial: 0.5}
  wy: {}
  wz: {}
frames:
  - {name: arm, parent: world, revolute: q1}
  - name: ball
    parent: arm
    ball:
      speeds: [wx, wy, wz]
      quaternion: [1, 0, 0, 0]
  - name: tip
    parent: ball
    translation: [0, 0, -L]
bodies:
  - name: bob
    frame: tip
    mass: m
    inertia: [0.1, 0.1, 0.1]
"""

# A sled moved by a general nonholonomic link, with a pole on it (1 coordinate, 2 speeds).
SLED = """\
name: sled
parameters:
  m: 2.0
  c: 0.5
coordinates:
  th: {initial: 0.1}
speeds:
  v: {initial: 1.0}
  w: {}
frames:
  - name: cart
    parent: world
    nonholonomic:
      velocity: [v, 0, 0]
      angular_velocity: [0, 0, 'c*w + th_dot']
      position: [0, 0, 0]
      quaternion: [1, 0, 0, 0]
      in: body
  - {name: pole, parent: cart, revolute: th, axis: x}
  - {name: top, parent: pole, translation: [0, 0, 1]}
bodies:
  - name: hull
    frame: cart
    mass: m
    inertia: [0.1, 0.1, 0.2]
  - {name: bob, frame: top, mass: m}
"""

# The ball joint as a floating joint: six speeds, a position and a quaternion.
FLOATING = edit(edit(BALL, "  wz: {}\n", "  wz: {}\n  vx: {}\n  vy: {}\n  vz: {}\n"),
                "    ball:\n      speeds: [wx, wy, wz]\n",
                "    floating:\n      speeds: [vx, vy, vz, wx, wy, wz]\n      position: [0, 0, 0]\n")

NAMES_IN_SLED_LINK = "names allowed here: c, m, pi, t, th, th_dot, v, w"


@pytest.mark.parametrize("text, speeds, signals, dof", [
    (BALL, ["wx", "wy", "wz"], ["ball_qw", "ball_qx", "ball_qy", "ball_qz"], 1 + 3),
    (SLED, ["v", "w"], ["cart_x", "cart_y", "cart_z", "cart_qw", "cart_qx", "cart_qy", "cart_qz"], 1 + 2),
    (FLOATING, ["wx", "wy", "wz", "vx", "vy", "vz"],
     ["ball_x", "ball_y", "ball_z", "ball_qw", "ball_qx", "ball_qy", "ball_qz"], 1 + 6),
], ids=["ball", "sled", "floating"])
def test_the_base_models_are_valid(tmp_path, text, speeds, signals, dof):
    """The declared speeds in the joint's order; the signals: the joint's (or link's) position where it has
    one, then its quaternion; one degree of freedom per coordinate and per speed."""
    spec = load_text(tmp_path, text)
    assert spec.warnings == []
    assert [x.name for x in spec.speeds] == speeds and [x.name for x in spec.signals] == signals
    assert andyc.derive(spec).dof == dof


# -- 1. initial quaternions -------------------------------------------------------

def test_ball_quaternion_not_unit_names_the_value_and_its_norm(tmp_path):
    text = edit(BALL, "quaternion: [1, 0, 0, 0]", "quaternion: [1, 0, 0, 1]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "quaternion: [1, 0, 0, 1]"), "frames[1].ball.quaternion")
    assert d.message == "quaternion [1, 0, 0, 1] has norm 1.41421356237, not 1"
    assert d.hint == "use the unit quaternion [0.707106781187, 0, 0, 0.707106781187]"


def test_nonholonomic_quaternion_not_unit(tmp_path):
    text = edit(SLED, "quaternion: [1, 0, 0, 0]", "quaternion: [0, 3, 4, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "quaternion: [0, 3, 4, 0]"), "frames[0].nonholonomic.quaternion")
    assert "quaternion [0, 3, 4, 0] has norm 5, not 1" in d.message
    assert "unit quaternion [0, 0.6, 0.8, 0]" in d.hint


def test_zero_quaternion_suggests_the_identity(tmp_path):
    text = edit(BALL, "quaternion: [1, 0, 0, 0]", "quaternion: [0, 0, 0, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "quaternion: [0, 0, 0, 0]"), "frames[1].ball.quaternion")
    assert "has norm 0, not 1" in d.message
    assert "unit quaternion [1, 0, 0, 0]" in d.hint


def test_coordinate_in_initial_quaternion_is_one_problem(tmp_path):
    text = edit(BALL, "quaternion: [1, 0, 0, 0]", "quaternion: ['cos(q1)', 0, 0, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "cos(q1)"), "frames[1].ball.quaternion[0]")
    assert "coordinate 'q1' cannot be used here" in d.message
    assert "constants" in d.hint


def test_time_in_initial_quaternion_is_an_error(tmp_path):
    text = edit(BALL, "quaternion: [1, 0, 0, 0]", "quaternion: ['cos(t)', 'sin(t)', 0, 0]")
    first, second = problems(tmp_path, text)     # one per entry that uses t
    assert_at(first, line_of(text, "cos(t)"), "frames[1].ball.quaternion[0]")
    assert second.path == "frames[1].ball.quaternion[1]"
    assert "'t'" in first.message and "constant" in first.hint


def test_time_in_rotation_quaternion_is_an_error(tmp_path):
    text = edit(BALL, "  - name: tip\n",
                "  - {name: side, parent: arm, rotation: {quaternion: ['cos(t)', 0, 'sin(t)', 0]}}\n  - name: tip\n")
    first, second = problems(tmp_path, text)
    assert_at(first, line_of(text, "cos(t)"), "frames[2].rotation.quaternion[0]")
    assert second.path == "frames[2].rotation.quaternion[2]"
    assert "'t'" in first.message


# -- 2. number of joint speeds ----------------------------------------------------

@pytest.mark.parametrize("speeds, count", [("[wx, wy]", 2), ("[wx, wy, wz, wx]", 4)])
def test_ball_joint_with_wrong_number_of_speeds(tmp_path, speeds, count):
    text = edit(BALL, "speeds: [wx, wy, wz]", f"speeds: {speeds}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"speeds: {speeds}"), "frames[1].ball.speeds")
    assert d.message == f"a ball joint has 3 speeds, got {count}"
    assert "list 3 speeds" in d.hint and "'speeds:'" in d.hint and "[wx, wy, wz]" in d.hint


def test_floating_joint_with_three_speeds(tmp_path):
    text = edit(FLOATING, "speeds: [vx, vy, vz, wx, wy, wz]", "speeds: [wx, wy, wz]")
    text = edit(text, "  vx: {}\n  vy: {}\n  vz: {}\n", "")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "speeds: [wx, wy, wz]"), "frames[1].floating.speeds")
    assert d.message == "a floating joint has 6 speeds, got 3"
    assert "list 6 speeds" in d.hint and "[vx, vy, vz, wx, wy, wz]" in d.hint


def test_ball_speeds_not_a_list(tmp_path):
    text = edit(BALL, "speeds: [wx, wy, wz]", "speeds: wx")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "speeds: wx"), "frames[1].ball.speeds")
    assert "expected a list" in d.message and "'wx'" in d.message
    assert "list" in d.hint


def test_ball_speed_listed_twice_names_it(tmp_path):
    text = edit(BALL, "speeds: [wx, wy, wz]", "speeds: [wx, wx, wz]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "speeds: [wx, wx, wz]"), "frames[1].ball.speeds[1]")
    assert "'wx'" in d.message and "twice" in d.message
    assert "distinct" in d.hint


# -- 3. unknown names in nonholonomic velocities ----------------------------------

def test_nonholonomic_angular_velocity_unknown_name_lists_allowed_names(tmp_path):
    text = edit(SLED, "'c*w + th_dot'", "'c*omega + th_dot'")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "c*omega"), "frames[0].nonholonomic.angular_velocity[2]")
    assert "unknown name 'omega'" in d.message and "c*omega + th_dot" in d.message
    assert NAMES_IN_SLED_LINK in d.hint                     # speeds v, w and the rate th_dot
    assert "<coordinate>_dot" in d.hint and "speeds" in d.hint
    assert "did you mean" not in d.hint


def test_nonholonomic_rate_typo_suggests_the_dot_name(tmp_path):
    text = edit(SLED, "'c*w + th_dot'", "'c*w + thdot'")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "thdot"), "frames[0].nonholonomic.angular_velocity[2]")
    assert "unknown name 'thdot'" in d.message
    assert d.hint.startswith("did you mean 'th_dot'?") and NAMES_IN_SLED_LINK in d.hint


def test_input_in_nonholonomic_velocity_is_not_allowed(tmp_path):
    text = edit(SLED, "coordinates:\n", "inputs:\n  push: 0\ncoordinates:\n")
    text = edit(text, "velocity: [v, 0, 0]", "velocity: [v, push, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "velocity: [v, push, 0]"), "frames[0].nonholonomic.velocity[1]")
    assert "input 'push' cannot be used here" in d.message
    assert NAMES_IN_SLED_LINK in d.hint


# -- 4. joint speeds that are not declared ----------------------------------------

def test_ball_speed_not_declared(tmp_path):
    text = edit(BALL, "speeds: [wx, wy, wz]", "speeds: [wx, wy, omega]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "speeds: [wx, wy, omega]"), "frames[1].ball.speeds[2]")
    assert d.message == "'omega' is not a declared speed"
    assert "declare it under 'speeds:'" in d.hint and "wx, wy, wz" in d.hint
    assert "did you mean" not in d.hint


def test_ball_speed_typo_gets_did_you_mean(tmp_path):
    text = edit(BALL, "speeds: [wx, wy, wz]", "speeds: [wx, wy, wzz]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "speeds: [wx, wy, wzz]"), "frames[1].ball.speeds[2]")
    assert d.message == "'wzz' is not a declared speed"
    assert d.hint.startswith("did you mean 'wz'?") and "'speeds:'" in d.hint


def test_ball_joint_without_a_speeds_section(tmp_path):
    text = edit(BALL, "speeds:\n  wx: {initial: 0.5}\n  wy: {}\n  wz: {}\n", "")
    found = problems(tmp_path, text)
    assert [(d.line, d.path) for d in found] == [
        (line_of(text, "speeds: [wx, wy, wz]"), f"frames[1].ball.speeds[{i}]") for i in range(3)]
    assert all("is not a declared speed" in d.message and "speeds: none" in d.hint for d in found)


# -- 5. velocities must be linear in the speeds -----------------------------------

NONLINEAR = ["v**2", "sin(v)", "v*w", "th_dot*v"]


@pytest.mark.parametrize("velocity", NONLINEAR)
def test_nonholonomic_velocity_not_linear_in_the_speeds(tmp_path, velocity):
    text = edit(SLED, "velocity: [v, 0, 0]", f"velocity: ['{velocity}', 0, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, f"velocity: ['{velocity}'"), "frames[0].nonholonomic.velocity[0]")
    assert "is not linear in the speeds" in d.message
    assert "J(q, t) * speeds + b(q, t)" in d.hint and "squared" in d.hint and "inside functions" in d.hint


@pytest.mark.parametrize("velocity", NONLINEAR)
def test_not_linear_message_quotes_the_expression_as_written(tmp_path, velocity):
    text = edit(SLED, "velocity: [v, 0, 0]", f"velocity: ['{velocity}', 0, 0]")
    d = one_problem(tmp_path, text)
    assert f"'{velocity}'" in d.message
    assert "v_" not in d.message


def test_velocity_linear_in_speeds_with_coordinate_coefficients_is_accepted(tmp_path):
    text = edit(SLED, "velocity: [v, 0, 0]", "velocity: ['v*cos(th) + th_dot', 'v*sin(th)', 't*w']")
    file = tmp_path / "model.yaml"
    file.write_text(text)
    spec = andyc.load(file)
    link = next(f for f in spec.frames if f.name == "cart").transforms[-1]
    th, (v, w) = spec.coordinates[0], (s.v for s in spec.speeds)
    expected = sp.Matrix([v * sp.cos(th.q) + th.v, v * sp.sin(th.q), TIME * w])
    assert sp.simplify(link.velocity - expected) == sp.zeros(3, 1)       # read as written, coefficients and all
    # and the cart's position signals move with it (the body axes are the world's at the initial quaternion)
    model = andyc.derive(spec)
    at_start = dict(zip(model.signals[3:], (1, 0, 0, 0)))
    rates = [expanded(model, r).subs(at_start) for r in model.signal_rates[:3]]
    assert [sp.simplify(r - e) for r, e in zip(rates, expected)] == [0, 0, 0]


# -- 6. names andyc makes ---------------------------------------------------------

def test_parameter_named_like_a_quaternion_signal(tmp_path):
    text = edit(BALL, "  m: 2.0\n", "  m: 2.0\n  ball_qw: 1.0\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "ball_qw: 1.0"), "parameters.ball_qw")
    assert d.message == "the name 'ball_qw' is taken by the quaternion signal of frame 'ball'"
    assert "another name" in d.hint


def test_speed_named_like_a_coordinate_rate(tmp_path):
    text = edit(BALL, "  wz: {}\n", "  wz: {}\n  q1_dot: {}\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "q1_dot: {}"), "speeds.q1_dot")
    assert d.message == "the name 'q1_dot' is taken by the rate of coordinate 'q1'"
    assert "another name" in d.hint


def test_coordinate_named_like_a_position_signal(tmp_path):
    text = edit(SLED, "  th: {initial: 0.1}\n", "  th: {initial: 0.1}\n  cart_x: {}\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "cart_x: {}"), "coordinates.cart_x")
    assert d.message == "the name 'cart_x' is taken by the position signal of frame 'cart'"
    assert "another name" in d.hint


# -- 7. position / quaternion without their velocity -------------------------------

def test_nonholonomic_position_without_velocity(tmp_path):
    text = edit(SLED, "      velocity: [v, 0, 0]\n", "")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "position: [0, 0, 0]"), "frames[0].nonholonomic.position")
    assert d.message == "'position' goes with 'velocity'"
    assert "add 'velocity:'" in d.hint and "remove 'position'" in d.hint


def test_nonholonomic_quaternion_without_angular_velocity(tmp_path):
    text = edit(SLED, "      angular_velocity: [0, 0, 'c*w + th_dot']\n", "")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "quaternion: [1, 0, 0, 0]"), "frames[0].nonholonomic.quaternion")
    assert d.message == "'quaternion' goes with 'angular_velocity'"
    assert "add 'angular_velocity:'" in d.hint


def test_nonholonomic_without_any_velocity(tmp_path):
    text = edit(SLED, "      velocity: [v, 0, 0]\n      angular_velocity: [0, 0, 'c*w + th_dot']\n", "")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "nonholonomic:"), "frames[0].nonholonomic")
    assert "not valid under any" not in d.message
    assert "'velocity'" in d.message and "'angular_velocity'" in d.message
    assert "velocity:" in d.hint


def test_ball_joint_has_no_position(tmp_path):
    text = edit(BALL, "      quaternion: [1, 0, 0, 0]\n", "      quaternion: [1, 0, 0, 0]\n      position: [0, 0, 1]\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "position: [0, 0, 1]"), "frames[1].ball.position")
    assert d.message == "unknown field 'position'"
    assert "allowed fields: in, quaternion, speeds" in d.hint


# -- 8. a speed that moves no mass -------------------------------------------------

def test_unused_speed_points_at_the_speed(tmp_path):
    text = edit(BALL, "  wz: {}\n", "  wz: {}\n  spare: {}\n")
    file = tmp_path / "idle.yaml"
    file.write_text(text)
    andyc.load(file)                           # the loader accepts it; the symbolic stage does not
    d = one_problem(tmp_path, text, derive=True)
    assert_at(d, line_of(text, "spare: {}"), "speeds.spare")
    assert "speed 'spare' moves no mass or inertia" in d.message
    assert "use it in a link" in d.hint and "remove it" in d.hint


def test_speed_used_only_by_a_damper_still_moves_no_mass(tmp_path):
    text = edit(BALL, "  wz: {}\n", "  wz: {}\n  spare: {}\n")
    text += "dampers:\n  - {name: drag, speed: spare, coefficient: 0.1}\n"
    d = one_problem(tmp_path, text, derive=True)
    assert_at(d, line_of(text, "spare: {}"), "speeds.spare")
    assert "moves no mass" in d.message


def test_cli_check_unused_speed(tmp_path):
    text = edit(BALL, "  wz: {}\n", "  wz: {}\n  spare: {}\n")
    (tmp_path / "idle.yaml").write_text(text)
    result = andyc_cli("check", "idle.yaml", cwd=tmp_path)
    assert result.returncode == 1 and result.stdout == "" and "Traceback" not in result.stderr
    lines = [x for x in result.stderr.splitlines() if not re.fullmatch(r"\d+ problems? found", x)]
    assert len(lines) == 1 and lines[0].startswith(f"idle.yaml:{line_of(text, 'spare: {}')}: speeds.spare: ")


# -- 9. velocities are written in body or parent axes -----------------------------

QUATERNION_LINE = "      quaternion: [1, 0, 0, 0]\n"


@pytest.mark.parametrize("base, old, new, path", [
    (BALL, QUATERNION_LINE, QUATERNION_LINE + "      in: world\n", "frames[1].ball.in"),
    (FLOATING, QUATERNION_LINE, QUATERNION_LINE + "      in: world\n", "frames[1].floating.in"),
    (SLED, "      in: body\n", "      in: world\n", "frames[0].nonholonomic.in"),
], ids=["ball", "floating", "nonholonomic"])
def test_in_world_is_not_allowed(tmp_path, base, old, new, path):
    text = edit(base, old, new)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "in: world"), path)
    assert d.message == "the text 'world' is not allowed here"
    assert d.hint == "use one of: body, parent"


def test_in_parent_is_accepted(tmp_path):
    """in: parent: the angular velocity is written in the parent's axes, so quat' = 1/2 [0, w] (x) quat (ANDY eq. 4)
    rather than 1/2 quat (x) [0, w]; the two differ once the quaternion has turned."""
    body, parent = tmp_path / "body.yaml", tmp_path / "parent.yaml"
    body.write_text(SLED)
    parent.write_text(edit(SLED, "in: body", "in: parent"))
    assert andyc.load(parent).frames[0].transforms[-1].in_body is False
    rates = []
    for file in (body, parent):
        model = andyc.derive(andyc.load(file))
        turned = dict(zip(model.signals[3:], (sp.cos(sp.Rational(1, 3)), 0, sp.sin(sp.Rational(1, 3)), 0)))  # about y
        rates.append([sp.simplify(expanded(model, r).subs(turned)) for r in model.signal_rates[3:]])
    assert rates[0] != rates[1]


def expanded(model, expr):
    """expr with the symbolic model's intermediate symbols replaced by what they stand for, recursively."""
    definitions = dict(model.assignments)
    while expr.free_symbols & definitions.keys():
        expr = expr.xreplace(definitions)
    return expr


# -- 10. the command line ---------------------------------------------------------

def test_cli_check_bad_ball_joint_prints_one_line(tmp_path):
    text = edit(BALL, "quaternion: [1, 0, 0, 0]", "quaternion: [1, 0, 0, 1]")
    (tmp_path / "bad.yaml").write_text(text)
    result = andyc_cli("check", "bad.yaml", cwd=tmp_path)
    assert result.returncode == 1
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    lines = result.stderr.splitlines()
    if lines and re.fullmatch(r"\d+ problems? found", lines[-1]):
        assert lines.pop() == "1 problem found"
    assert lines == [
        f"bad.yaml:{line_of(text, 'quaternion: [1, 0, 0, 1]')}: frames[1].ball.quaternion: "
        "quaternion [1, 0, 0, 1] has norm 1.41421356237, not 1; "
        "use the unit quaternion [0.707106781187, 0, 0, 0.707106781187]"]
    assert LINE_FORMAT.match(lines[0])


def test_cli_check_swing_bar_is_valid(tmp_path):
    result = andyc_cli("check", str(SWING_BAR), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    assert result.stdout.startswith(f"{SWING_BAR}: model 'swing_bar' is valid")
    assert "4 degrees of freedom" in result.stdout


def test_cli_check_swing_bar_summary_counts_speeds_and_signals(tmp_path):
    result = andyc_cli("check", str(SWING_BAR), cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "9 states" in result.stdout
    assert "wx" in result.stdout and "wz" in result.stdout

