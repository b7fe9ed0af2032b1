"""Malformed models give one clear line per problem: `FILE:LINE: PATH: what; fix`.

Each case writes a small model into tmp_path and checks the file, the line
(computed from the text written here, never from what andyc prints), the
document path, and that the text says what is wrong and what to do.
"""

from __future__ import annotations

import re

import andyc
from tests.support import MODELS
from tests.support.cli import andyc_cli
from tests.support.diagnostics import LINE_FORMAT, assert_at, edit, line_of, one_problem, problems

SHIPPED_ALL = sorted(MODELS.glob("*.yaml"))
CHAIN3D = (MODELS / "chain3d.yaml").read_text()

# A small valid model; the cases below break one thing at a time.
BASE = """\
name: arm
parameters:
  L1: 1.0
  m1: 2.0
coordinates:
  q1: {initial: 0.1}
frames:
  - {name: a, parent: world, revolute: q1}
  - name: b
    parent: a
    translation: [L1, 0, 0]
bodies:
  - name: bob
    frame: b
    mass: m1
"""

def test_base_model_is_valid(tmp_path):
    file = tmp_path / "model.yaml"
    file.write_text(BASE)
    model = andyc.derive(andyc.load(file))
    assert model.dof == 1


# -- YAML syntax ----------------------------------------------------------------

def test_yaml_missing_colon_points_at_the_key_line(tmp_path):
    text = edit(BASE, "    parent: a\n", "    parent a\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "parent a"), "")
    assert "invalid YAML" in d.message and "no ':'" in d.message and "parent a" in d.message
    assert "key: value" in d.hint


def test_yaml_bad_indentation(tmp_path):
    text = edit(BASE, "  m1: 2.0\n", " m1: 2.0\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, " m1: 2.0"), "")
    assert "invalid YAML" in d.message and "indentation" in d.message
    assert "same number of spaces" in d.hint


def test_yaml_over_indented_key(tmp_path):
    text = edit(BASE, "    parent: a\n", "      parent: a\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "      parent: a"), "")
    assert "unexpected ':'" in d.message
    assert "indentation" in d.hint


def test_yaml_unclosed_bracket_points_at_the_bracket(tmp_path):
    text = edit(BASE, "translation: [L1, 0, 0]", "translation: [L1, 0, 0")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "translation: [L1, 0, 0"), "")
    column = text.splitlines()[d.line - 1].index("[") + 1
    assert f"the '[' at column {column} is not closed" in d.message
    assert "']'" in d.hint


def test_yaml_unclosed_quote_points_at_the_quote(tmp_path):
    text = edit(BASE, "translation: [L1, 0, 0]", "translation: ['L1, 0, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "'L1, 0, 0]"), "")
    assert "is not closed" in d.message and "close it with \"'\"" in d.hint


def test_yaml_second_document(tmp_path):
    text = BASE + "---\nname: other\n"
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "---"), "")
    assert "second document" in d.message


def test_yaml_tab_indentation(tmp_path):
    text = edit(BASE, "    parent: a\n", "\tparent: a\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "\tparent"), "")
    assert "tab" in d.message and "spaces" in d.hint


def test_duplicate_yaml_key_names_both_lines(tmp_path):
    text = edit(BASE, "  m1: 2.0\n", "  m1: 2.0\n  m1: 3.0\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "m1: 3.0"), "parameters.m1")
    assert f"duplicate key 'm1' (first at line {line_of(text, 'm1: 2.0')})" in d.message
    assert "remove or rename" in d.hint


# -- schema ---------------------------------------------------------------------

def test_missing_required_field_points_at_the_body(tmp_path):
    text = edit(BASE, "    mass: m1\n", "")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: bob"), "bodies[0]")
    assert d.message == "missing required field 'mass'"
    assert "add 'mass:'" in d.hint


def test_missing_top_level_field(tmp_path):
    text = edit(BASE, "name: arm\n", "")
    d = one_problem(tmp_path, text)
    assert_at(d, 1, "")
    assert d.message == "missing required field 'name'"
    assert "top level" in d.hint


def test_wrong_type_mass_is_a_list(tmp_path):
    text = edit(BASE, "mass: m1", "mass: [1, 2]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "mass: [1, 2]"), "bodies[0].mass")
    assert d.message == "expected a number or an expression, got a list [1, 2]"
    assert "write a number" in d.hint


def test_wrong_type_parameter_is_text(tmp_path):
    text = edit(BASE, "L1: 1.0", "L1: one")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "L1: one"), "parameters.L1")
    assert "expected a number" in d.message and "'one'" in d.message
    assert "write a number" in d.hint


def test_unknown_field_typo_is_one_problem_with_did_you_mean(tmp_path):
    text = edit(BASE, "    mass: m1\n", "    masss: m1\n")
    d = one_problem(tmp_path, text)            # not also "missing required field 'mass'"
    assert_at(d, line_of(text, "masss"), "bodies[0].masss")
    assert d.message == "unknown field 'masss'"
    assert d.hint.startswith("did you mean 'mass'?") and "allowed fields: com, frame, inertia, mass, name" in d.hint


def test_unknown_top_level_section(tmp_path):
    text = edit(BASE, "bodies:", "bodys:")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "bodys:"), "bodys")
    assert "did you mean 'bodies'?" in d.hint


def test_wrong_number_of_dh_entries(tmp_path):
    text = edit(CHAIN3D, "dh: [0.05, q4, 0.3, pi/2]", "dh: [0.05, q4, 0.3]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "dh: [0.05"), "frames[3].dh")
    assert d.message == "expected 4 items, got 3"
    assert "[d, theta, a, alpha]" in d.hint


def test_rotation_given_two_ways(tmp_path):
    text = edit(BASE, "    translation: [L1, 0, 0]\n",
                "    translation: [L1, 0, 0]\n    rotation: {rpy: [0, 0, 1], axis: z, angle: 1}\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "rotation:"), "frames[1].rotation")
    assert "conflicting fields" in d.message and "'rpy'" in d.message and "'axis'" in d.message
    assert "not valid under any" not in d.message
    assert "{quaternion: [w, x, y, z]}" in d.hint


def test_rotation_missing_half_of_axis_angle(tmp_path):
    text = edit(BASE, "    translation: [L1, 0, 0]\n", "    translation: [L1, 0, 0]\n    rotation: {angle: 1}\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "rotation:"), "frames[1].rotation")
    assert d.message == "missing field 'axis' (it goes with 'angle')"


def test_damper_without_speed_or_frame(tmp_path):
    text = BASE + "dampers:\n  - {name: drag, coefficient: 0.1}\n"
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "name: drag"), "dampers[0]")
    assert d.message == "a damper needs 'speed' or 'frame'"
    assert "speed: <coordinate>" in d.hint


def test_axis_of_wrong_shape(tmp_path):
    text = edit(BASE, "revolute: q1}", "revolute: q1, axis: [1, 0]}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "axis: [1, 0]"), "frames[0].axis")
    assert d.message == "a list [1, 0] is not a valid axis"
    assert "x, y, z" in d.hint and "three numbers" in d.hint


def test_inertia_matrix_row_too_short_names_the_row(tmp_path):
    text = edit(BASE, "    mass: m1\n", "    mass: m1\n    inertia:\n      - [1, 0, 0]\n      - [0, 1]\n      - [0, 0, 1]\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- [0, 1]"), "bodies[0].inertia[1]")
    assert d.message == "expected 3 items, got 2"
    assert "row" in d.hint


# -- expressions ----------------------------------------------------------------

def test_unknown_name_in_expression_lists_the_known_names(tmp_path):
    text = edit(CHAIN3D, "dh: [0.05, q4, 0.3, pi/2]", "dh: [0.05, q5, 0.3, pi/2]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "dh: [0.05, q5"), "frames[3].dh[1]")
    assert "unknown name 'q5'" in d.message
    assert "names allowed here: g, m1, m2, m3, m4, pi, q1, q2, q3, q4, t" in d.hint


def test_unknown_name_suggests_the_close_one(tmp_path):
    text = edit(CHAIN3D, "revolute: q3, axis", "revolute: qq3, axis")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "revolute: qq3"), "frames[2].revolute")   # 2nd line of a flow mapping
    assert "unknown name 'qq3'" in d.message and "did you mean 'q3'?" in d.hint


def test_coordinate_where_only_parameters_are_allowed(tmp_path):
    text = edit(BASE, "mass: m1", "mass: 2*q1")
    d = one_problem(tmp_path, text)            # and no second "mass must be positive"
    assert_at(d, line_of(text, "mass: 2*q1"), "bodies[0].mass")
    assert "coordinate 'q1' cannot be used here" in d.message
    assert "only parameters" in d.hint and "L1, m1" in d.hint


def test_unparsable_expression(tmp_path):
    text = edit(BASE, "translation: [L1, 0, 0]", "translation: ['L1 *', 0, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "L1 *"), "frames[1].translation[0]")
    assert "cannot parse 'L1 *'" in d.message and "at the end" in d.message
    assert "brackets and operators" in d.hint


def test_caret_is_not_a_power(tmp_path):
    text = edit(BASE, "translation: [L1, 0, 0]", "translation: [0, 'L1^2', 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "L1^2"), "frames[1].translation[1]")
    assert "'^' is not a power" in d.message
    assert "'**'" in d.hint


def test_unknown_function(tmp_path):
    text = edit(BASE, "translation: [L1, 0, 0]", "translation: ['sinn(L1)', 0, 0]")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "sinn"), "frames[1].translation[0]")
    assert "unknown function 'sinn'" in d.message and "did you mean 'sin'?" in d.hint


# -- meaning --------------------------------------------------------------------

def test_cycle_in_the_frame_graph(tmp_path):
    text = edit(BASE, "{name: a, parent: world,", "{name: a, parent: b,")
    d = one_problem(tmp_path, text)            # and no "frame 'b' does not exist" for the body
    assert_at(d, line_of(text, "name: a, parent: b"), "frames[0].parent")
    assert "cycle: a -> b -> a" in d.message
    assert "another parent" in d.hint


def test_frame_that_is_its_own_parent(tmp_path):
    text = edit(BASE, "{name: a, parent: world,", "{name: a, parent: a,")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "parent: a,"), "frames[0].parent")
    assert "cycle: a -> a" in d.message


def test_duplicate_frame_name_says_where_the_first_is(tmp_path):
    text = edit(BASE, "  - name: b\n", "  - name: a\n")
    text = edit(text, "    frame: b\n", "    frame: a\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: a"), "frames[1].name")
    assert f"duplicate name 'a' (first defined at line {line_of(text, '{name: a')}, frames[0].name)" in d.message
    assert "rename" in d.hint


def test_frame_named_like_a_coordinate(tmp_path):
    text = edit(BASE, "  - name: b\n", "  - name: q1\n")
    text = edit(text, "    frame: b\n", "    frame: q1\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "- name: q1"), "frames[1].name")
    assert f"duplicate name 'q1' (first defined at line {line_of(text, 'q1: {initial')}, coordinates.q1)" in d.message


def test_missing_parent_frame_suggests_the_close_name(tmp_path):
    text = edit(CHAIN3D, "{name: tool, parent: wrist,", "{name: tool, parent: wirst,")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "parent: wirst"), "frames[4].parent")
    assert d.message == "parent frame 'wirst' does not exist"
    assert d.hint.startswith("did you mean 'wrist'?") and "known frames:" in d.hint


def test_body_on_a_missing_frame(tmp_path):
    text = edit(BASE, "    frame: b\n", "    frame: bb\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "frame: bb"), "bodies[0].frame")
    assert "frame 'bb' does not exist" in d.message and "did you mean 'b'?" in d.hint


def test_negative_mass(tmp_path):
    text = edit(BASE, "mass: m1", "mass: -1.5")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "mass: -1.5"), "bodies[0].mass")
    assert d.message == "mass must be positive, got -1.5"
    assert "positive mass" in d.hint


def test_negative_mass_through_a_parameter_names_it(tmp_path):
    text = edit(BASE, "m1: 2.0", "m1: -2.0")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "mass: m1"), "bodies[0].mass")
    assert d.message == "mass must be positive, got m1 = -2"


def test_non_symmetric_inertia_matrix(tmp_path):
    text = edit(BASE, "    mass: m1\n",
                "    mass: m1\n    inertia: [[0.2, 0.01, 0], [0, 0.3, 0], [0, 0, 0.4]]\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "inertia:"), "bodies[0].inertia")
    assert d.message == "inertia is not symmetric: I[0][1] = 0.01 but I[1][0] = 0"
    assert "off-diagonal pairs equal" in d.hint


def test_inertia_breaking_the_triangle_inequality(tmp_path):
    text = edit(BASE, "    mass: m1\n", "    mass: m1\n    inertia: [0.1, 0.1, 0.5]\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "inertia:"), "bodies[0].inertia")
    assert "principal moments 0.1, 0.1, 0.5 break the triangle inequality" in d.message
    assert "at most the sum of the other two" in d.hint


def test_inertia_not_positive_semidefinite(tmp_path):
    text = edit(BASE, "    mass: m1\n", "    mass: m1\n    inertia: [-0.1, 0.1, 0.1]\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "inertia:"), "bodies[0].inertia")
    assert "not positive semi-definite" in d.message


def test_non_unit_quaternion_names_the_norm(tmp_path):
    text = edit(BASE, "    translation: [L1, 0, 0]\n",
                "    translation: [L1, 0, 0]\n    rotation:\n      quaternion: [1, 0, 0, 1]\n")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "quaternion:"), "frames[1].rotation.quaternion")
    assert "has norm 1.41421356237, not 1" in d.message
    assert "unit quaternion [0.707106781187, 0, 0, 0.707106781187]" in d.hint


def test_non_finite_parameter(tmp_path):
    text = edit(BASE, "L1: 1.0", "L1: .nan")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "L1: .nan"), "parameters.L1")
    assert "not a finite number" in d.message


def test_coordinate_that_moves_no_mass(tmp_path):
    text = edit(BASE, "  q1: {initial: 0.1}\n", "  q1: {initial: 0.1}\n  q2: {}\n")
    file = tmp_path / "idle.yaml"
    file.write_text(text)
    andyc.load(file)                           # the loader accepts it; the symbolic stage does not
    d = one_problem(tmp_path, text, derive=True)
    assert_at(d, line_of(text, "q2: {}"), "coordinates.q2")
    assert "coordinate 'q2' moves no mass or inertia" in d.message
    assert "use it in a link" in d.hint


# -- several problems at once ---------------------------------------------------

def test_several_schema_problems_reported_together_in_line_order(tmp_path):
    text = edit(BASE, "  m1: 2.0\n", "  m1: 2.0\n  m1: 3.0\n")      # duplicate key
    text = edit(text, "    parent: a\n", "    parent: [a]\n")          # wrong type
    text = edit(text, "    mass: m1\n", "    masss: m1\n")             # typo
    found = problems(tmp_path, text)
    assert [(d.line, d.path) for d in found] == [
        (line_of(text, "m1: 3.0"), "parameters.m1"),
        (line_of(text, "parent: [a]"), "frames[1].parent"),
        (line_of(text, "masss"), "bodies[0].masss"),
    ]


def test_several_meaning_problems_reported_together_in_line_order(tmp_path):
    text = edit(BASE, "    parent: a\n", "    parent: aa\n")
    text = edit(text, "translation: [L1, 0, 0]", "translation: [L2, 0, 0]")
    text = edit(text, "mass: m1", "mass: -1")
    text += "springs:\n  - {name: s, stiffness: 10, between: [a, a]}\n"
    found = problems(tmp_path, text)
    assert [(d.line, d.path) for d in found] == [
        (line_of(text, "parent: aa"), "frames[1].parent"),
        (line_of(text, "[L2, 0, 0]"), "frames[1].translation[0]"),
        (line_of(text, "mass: -1"), "bodies[0].mass"),
        (line_of(text, "between: [a, a]"), "springs[0].between"),
    ]


# -- the command line -----------------------------------------------------------

def test_cli_check_bad_model_prints_only_diagnostics(tmp_path):
    text = edit(BASE, "    parent: a\n", "    parent: aa\n")
    text = edit(text, "mass: m1", "mass: -1")
    (tmp_path / "bad.yaml").write_text(text)
    result = andyc_cli("check", "bad.yaml", cwd=tmp_path)
    assert result.returncode == 1
    assert result.stdout == ""
    assert "Traceback" not in result.stderr
    lines = result.stderr.splitlines()
    if lines and re.fullmatch(r"\d+ problems? found", lines[-1]):   # a count line is allowed at the end
        assert lines.pop() == f"{len(lines)} problem{'s' if len(lines) != 1 else ''} found"
    assert lines == [
        f"bad.yaml:{line_of(text, 'parent: aa')}: frames[1].parent: parent frame 'aa' does not exist; "
        "did you mean 'a'? known frames: a, b, world",
        f"bad.yaml:{line_of(text, 'mass: -1')}: bodies[0].mass: mass must be positive, got -1; "
        "give a positive mass in kg",
    ]
    for line in lines:
        assert LINE_FORMAT.match(line)


def test_cli_check_bad_yaml_prints_one_line(tmp_path):
    text = edit(BASE, "    parent: a\n", "    parent a\n")
    (tmp_path / "bad.yaml").write_text(text)
    result = andyc_cli("check", "bad.yaml", cwd=tmp_path)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    lines = [x for x in result.stderr.splitlines() if not re.fullmatch(r"\d+ problems? found", x)]
    assert len(lines) == 1 and lines[0].startswith(f"bad.yaml:{line_of(text, 'parent a')}: <document>: invalid YAML")


def test_cli_check_models_prints_a_summary(tmp_path):
    # (the models written in YAML whole: a robot's from its URDF, Go1's and G1's, derives its unreduced model too for
    # the summary, a minute of CPU: tests/test_urdf_errors.py checks a URDF's summary)
    SHIPPED = [m for m in SHIPPED_ALL if "\nurdf:" not in m.read_text()]
    result = andyc_cli("check", *SHIPPED, cwd=tmp_path)
    assert result.returncode == 0, result.stderr
    assert "Traceback" not in result.stderr
    lines = result.stdout.strip().splitlines()
    summaries = [line for line in lines if not line.startswith(" ")]
    assert len(summaries) == len(SHIPPED)          # one paragraph per model: its summary line, then indented ones
    details = [line for line in lines if line.startswith(" ") and not line.startswith("  reduced: ")]   # (a URDF's)
    forward = [d for d in details if d.startswith("  forward dynamics: ")]
    constrained = [d for d in details if d.startswith("  constrained solve: ")]    # (andyc/symbolic/sparse_rows.py)
    assert len(forward) == len(SHIPPED) and len(forward) + len(constrained) == len(details)
    # (the rows of the model's constraints, or of its contacts: both take the constrained solve while active)
    assert len(constrained) == sum("constraint row" in s or " contact" in s for s in summaries)
    for model, summary in zip(SHIPPED, summaries):
        assert summary.startswith(f"{model}: model '{model.stem}' is valid")
        for word in ("state", "bod", "frame"):
            assert word in summary
        assert ("of freedom" in summary) != ("constraint row" in summary)   # constrained models count rows
    chain = summaries[[m.name for m in SHIPPED].index("chain3d.yaml")]
    assert "4 degrees of freedom (q1, q2, q3, q4), 8 states, 4 bodies, 5 frames besides world" in chain


def test_cli_check_missing_file(tmp_path):
    result = andyc_cli("check", "nowhere.yaml", cwd=tmp_path)
    assert result.returncode == 1
    assert "Traceback" not in result.stderr
    lines = [x for x in result.stderr.splitlines() if not re.fullmatch(r"\d+ problems? found", x)]
    assert lines == ["nowhere.yaml:1: <document>: cannot read the file (No such file or directory); check the path"]


def test_cli_check_good_and_bad_together(tmp_path):
    (tmp_path / "bad.yaml").write_text(edit(BASE, "mass: m1", "mass: -1"))
    result = andyc_cli("check", MODELS / "pendulum_a01.yaml", "bad.yaml", cwd=tmp_path)
    assert result.returncode == 1
    assert "pendulum_a01" in result.stdout and "is valid" in result.stdout
    assert "bad.yaml:" in result.stderr and "mass must be positive" in result.stderr
