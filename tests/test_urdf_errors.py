"""URDF import: every problem is one line `FILE:LINE: ELEMENT: what; fix` at the element's line, the
elements andyc does not use are named in one warning, and the CLI takes a URDF or a YAML model built on
one (`urdf:` with overrides)."""

from __future__ import annotations

from functools import partial
from pathlib import Path

import h5py
import pytest

import andyc
from andyc.errors import SpecError
from andyc.spec.urdf import LIMITS_DEFAULT
from tests.support import ROBOTS_DIR
from tests.support import diagnostics
from tests.support.cli import andyc_cli, check
from tests.support.diagnostics import LINE_FORMAT, edit, line_of

INERTIAL = '<inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>'

ARM = f"""<?xml version="1.0"?>
<robot name="arm">
  <link name="base"/>
  <link name="upper">
    {INERTIAL}
  </link>
  <link name="lower">
    <inertial>
      <origin xyz="0.2 0 0" rpy="0 0 0.3"/>
      <mass value="0.5"/>
      <inertia ixx="0.001" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/>
    </inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/>
    <child link="upper"/>
    <axis xyz="0 0 1"/>
  </joint>
  <joint name="elbow" type="continuous">
    <parent link="upper"/>
    <child link="lower"/>
    <origin xyz="0.4 0 0"/>
    <axis xyz="0 1 0"/>
  </joint>
</robot>
"""


# A URDF's problems, checked as any model's: one FILE:LINE: PATH: what; fix line each.
one_problem = partial(diagnostics.one_problem, name="robot.urdf")


def test_the_base_urdf_is_valid(tmp_path):
    (tmp_path / "arm.urdf").write_text(ARM)
    spec = andyc.load(tmp_path / "arm.urdf")
    assert [c.name for c in spec.coordinates] == ["shoulder", "elbow"]
    assert [f.name for f in spec.frames if not f.internal] == ["base", "upper", "lower"]
    assert spec.warnings == []              # nothing unused in it


# -- the four errors of the issue ---------------------------------------------------

def test_missing_parent_link(tmp_path):
    text = edit(ARM, '<parent link="base"/>', '<parent link="bse"/>')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, '<parent link="bse"/>'), "joint[shoulder].parent")
    assert d.message == "parent link 'bse' does not exist"
    assert "did you mean 'base'?" in d.hint


def test_joint_cycle(tmp_path):
    text = edit(ARM, "</robot>", """  <joint name="back" type="revolute">
    <parent link="lower"/>
    <child link="base"/>
  </joint>
</robot>""")
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, '<joint name="shoulder"'), "joint[shoulder]")
    assert d.message == ("the joints form a cycle: shoulder -> elbow -> back -> shoulder "
                         "(links base -> upper -> lower -> base)")
    assert "tree" in d.hint


def test_link_with_two_parent_joints(tmp_path):
    """A closed chain: the second joint into a link is the one reported."""
    text = edit(ARM, "</robot>", """  <joint name="shortcut" type="revolute">
    <parent link="base"/>
    <child link="lower"/>
  </joint>
</robot>""")
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, '<child link="lower"/>', 2), "joint[shortcut].child")
    elbow = line_of(text, '<joint name="elbow"')
    assert d.message == f"link 'lower' is already the child of joint 'elbow' (line {elbow})"


def test_zero_mass_moving_link(tmp_path):
    text = edit(ARM, '<mass value="0.5"/>', '<mass value="0"/>')
    text = edit(text, 'ixx="0.001" iyy="0.01" izz="0.01"', 'ixx="0" iyy="0" izz="0"')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "<inertial>", 2), "link[lower]")
    assert d.message == ("zero-mass moving link: joint 'elbow' moves link 'lower' and nothing it carries has "
                         "mass, so the mass matrix is singular")
    assert "lock" in d.hint


def test_zero_mass_link_that_carries_mass_is_fine(tmp_path):
    """A massless link between two joints (a universal joint's cross) moves the mass after it: no error."""
    text = edit(ARM, f"""<link name="upper">
    {INERTIAL}
  </link>""", '<link name="upper"/>')
    (tmp_path / "arm.urdf").write_text(text)
    assert len(andyc.load(tmp_path / "arm.urdf").coordinates) == 2


def test_unknown_joint_type(tmp_path):
    text = edit(ARM, 'type="continuous"', 'type="ball"')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, 'type="ball"'), "joint[elbow]")
    assert d.message == "unknown joint type 'ball'"
    assert "revolute, continuous, prismatic, fixed, floating, planar" in d.hint


def test_all_problems_at_once_through_the_cli(tmp_path, monkeypatch):
    text = edit(ARM, '<parent link="base"/>', '<parent link="bse"/>')
    text = edit(text, 'type="continuous"', 'type="revolut"')
    (tmp_path / "bad.urdf").write_text(text)
    monkeypatch.chdir(tmp_path)
    result = check("bad.urdf")
    assert result.exit_code == 1 and result.stdout == ""
    *lines, last = result.stderr.splitlines()
    assert last == "2 problems found" and "Traceback" not in result.stderr
    assert [LINE_FORMAT.match(x)["line"] for x in lines] == [str(line_of(text, "bse")),
                                                            str(line_of(text, "revolut\""))]
    assert "did you mean 'revolute'?" in lines[1]


# -- other problems -------------------------------------------------------------------

def test_xml_syntax_error(tmp_path):
    text = edit(ARM, "    <child link=\"upper\"/>\n", "    <child link=\"upper\">\n")
    d = one_problem(tmp_path, text)
    assert d.message.startswith("invalid XML:") and d.line >= line_of(text, '<child link="upper">')


def test_names_that_become_the_same_identifier(tmp_path):
    text = edit(ARM, 'name="elbow"', 'name="shoulder-"')
    text = edit(text, 'name="shoulder"', 'name="shoulder_"')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, 'name="shoulder-"'), "joint[shoulder-]")
    first = line_of(text, '<joint name="shoulder_"')
    assert d.message == f"the name 'shoulder_' is also made from joint[shoulder_] (line {first})"


def test_link_named_like_its_joint_gets_a_link_frame(tmp_path):
    text = ARM.replace('"upper"', '"shoulder"')
    (tmp_path / "arm.urdf").write_text(text)
    spec = andyc.load(tmp_path / "arm.urdf")
    assert [c.name for c in spec.coordinates] == ["shoulder", "elbow"]
    assert "shoulder_link" in [f.name for f in spec.frames]


def test_mimic_of_a_missing_joint(tmp_path):
    text = edit(ARM, '<axis xyz="0 1 0"/>', '<axis xyz="0 1 0"/>\n    <mimic joint="shoulderr" multiplier="2"/>')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "<mimic"), "joint[elbow].mimic")
    assert d.message == "mimicked joint 'shoulderr' does not exist" and "did you mean 'shoulder'?" in d.hint


def test_bad_number(tmp_path):
    text = edit(ARM, '<origin xyz="0.4 0 0"/>', '<origin xyz="0.4 0"/>')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, '<origin xyz="0.4 0"/>'), "joint[elbow].origin.xyz")
    assert d.message == "expected 3 finite number(s), got '0.4 0'"


def test_unknown_visual_geometry(tmp_path):
    text = edit(ARM, f"""    {INERTIAL}
  </link>""", f"""    {INERTIAL}
    <visual><geometry><capsule radius="0.1" length="0.3"/></geometry></visual>
  </link>""")
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "<capsule"), "link[upper].visual.geometry")
    assert d.message == "expected a box, cylinder, sphere or mesh, got <capsule>"


def test_what_yourdfpy_refuses_is_located_by_its_value(tmp_path):
    """A bad number in an element andyc does not read (a safety controller) is still reported at its line."""
    text = edit(ARM, '<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/>\n    <safety_controller k_velocity="lots"/>')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, 'k_velocity="lots"'), "safety_controller")
    assert d.message == "yourdfpy cannot read the URDF: could not convert string to float: 'lots'"


def test_a_limit_that_is_not_a_number_is_located_at_its_attribute(tmp_path):
    """andyc reads a limit's lower and upper (joint-limit stops), and checks all four of its numbers first."""
    text = edit(ARM, '<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/>\n    <limit effort="lots" velocity="1"/>')
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, 'effort="lots"'), "joint[shoulder].limit.effort")
    assert d.message == "expected a number, got 'lots'"


# -- what andyc does not use, and what it keeps -----------------------------------------

def test_unused_elements_are_listed_once_in_one_warning(tmp_path):
    text = edit(ARM, '<axis xyz="0 0 1"/>', '<axis xyz="0 0 1"/>\n    <limit lower="-1" upper="1" effort="5" '
                'velocity="2"/>\n    <dynamics damping="0.1" friction="0.3"/>\n    <safety_controller k_velocity="1"/>')
    text = edit(text, '<axis xyz="0 1 0"/>', '<axis xyz="0 1 0"/>\n    <limit effort="5" velocity="2"/>')
    text = edit(text, f"""    {INERTIAL}
  </link>""", f"""    {INERTIAL}
    <collision><geometry><box size="0.1 0.1 0.4"/></geometry></collision>
    <visual><geometry><mesh filename="package://arm_description/meshes/upper.stl"/></geometry></visual>
  </link>""")
    text = edit(text, "</robot>", """  <transmission name="t"><type>SimpleTransmission</type></transmission>
  <gazebo reference="upper"><mu1>0.5</mu1></gazebo>
  <gazebo><plugin name="p"/></gazebo>
  <material name="grey"><color rgba="0.5 0.5 0.5 1"/></material>
</robot>""")
    (tmp_path / "arm.urdf").write_text(text)
    spec = andyc.load(tmp_path / "arm.urdf")
    unused = [w for w in spec.warnings if "not used by andyc" in w.message]
    assert len(unused) == 1
    w = unused[0]
    assert w.file == str(tmp_path / "arm.urdf") and w.line == line_of(text, "<collision>")     # the first
    # limits are stops by default (LIMITS_DEFAULT): their lower and upper used, effort and velocity not
    limits = ("2 <limit effort>", "2 <limit velocity>") if LIMITS_DEFAULT else ("2 <joint><limit>",)
    for kind in limits + ("1 <joint><safety_controller>",
                          "1 <link><collision>", "1 <transmission>", "2 <gazebo>", "1 <material>"):
        assert w.message.count(kind) == 1, (kind, w.message)
    assert "visual" not in w.message.split(":", 1)[1].split(";")[0]       # visuals are kept, not unused
    # The damping and the friction are used: a linear and a coulomb damper on the joint's coordinate.
    assert "friction" not in w.message
    assert [(d.name, d.speed, float(d.coefficient), d.law) for d in spec.dampers] == [
        ("shoulder_damping", "shoulder", 0.1, "linear"), ("shoulder_friction", "shoulder", 0.3, "coulomb")]
    # The visual mesh is kept as a reference; its package is not found, which a second warning says.
    assert spec.visuals == [{"link": "upper", "frame": "upper", "geometry": "mesh", "line": line_of(text, "<visual>"),
                             "origin": {"xyz": [0.0] * 3, "rpy": [0.0] * 3},
                             "filename": "package://arm_description/meshes/upper.stl", "format": "", "scale": [1.0] * 3}]
    assert any("1 visual mesh file(s) not found" in w.message for w in spec.warnings)
    # andyc check prints each warning on one line
    result = check(tmp_path / "arm.urdf")
    assert result.exit_code == 0
    assert result.stderr.count("not used by andyc") == 1 and result.stderr.count("(warning)") == 2


def test_package_paths_resolve_meshes(tmp_path):
    """package://PKG/... is found relative to the URDF's folder (PKG/... or the folder itself) or a search path."""
    mesh = tmp_path / "arm_description" / "meshes" / "upper.stl"
    mesh.parent.mkdir(parents=True)
    mesh.write_text("solid x\nendsolid x\n")
    text = edit(ARM, f"""    {INERTIAL}
  </link>""", f"""    {INERTIAL}
    <visual><origin xyz="0 0 0.1" rpy="0 0.5 0"/>
      <geometry><mesh filename="package://arm_description/meshes/upper.stl" scale="2 2 2"/></geometry></visual>
  </link>""")
    urdf = tmp_path / "arm_description" / "urdf" / "arm.urdf"
    urdf.parent.mkdir()
    urdf.write_text(text)
    spec = andyc.load(urdf)
    assert spec.visuals[0]["filename"] == str(mesh) and spec.visuals[0]["scale"] == [2.0] * 3
    assert spec.visuals[0]["origin"] == {"xyz": [0, 0, 0.1], "rpy": [0, 0.5, 0]}
    assert not any("not found" in w.message for w in spec.warnings)


def test_inertia_no_rigid_body_has_is_kept_with_a_warning(tmp_path):
    """Real URDFs carry such inertias (allegro hand, anymal, tiago); Pinocchio simulates them, so does andyc."""
    text = edit(ARM, 'ixx="0.001" iyy="0.01" izz="0.01"', 'ixx="0.001" iyy="0.001" izz="0.01"')
    (tmp_path / "arm.urdf").write_text(text)
    spec = andyc.load(tmp_path / "arm.urdf")
    (w,) = spec.warnings
    assert w.line == line_of(text, "<inertial>", 2)
    assert "lower (line" in w.message and "breaks the triangle inequality" in w.message


# -- a YAML model on a URDF --------------------------------------------------------------

def yaml_on(tmp_path, urdf_text: str, yaml_text: str) -> Path:
    (tmp_path / "arm.urdf").write_text(urdf_text)
    (tmp_path / "model.yaml").write_text(yaml_text)
    return tmp_path / "model.yaml"


def test_yaml_option_problems_point_into_the_yaml(tmp_path):
    text = "name: arm2\nurdf:\n  file: arm.urdf\n  lock: {elbw: 0.3}\n  root: uper\n"
    source = yaml_on(tmp_path, ARM, text)
    with pytest.raises(SpecError) as info:
        andyc.load(source)
    found = [(d.file, d.line, d.path) for d in info.value.diagnostics]
    assert found == [(str(source), 4, "urdf.lock.elbw"), (str(source), 5, "urdf.root")]
    assert "did you mean 'elbow'?" in info.value.diagnostics[0].hint


def test_yaml_problem_about_a_urdf_name_names_both_files(tmp_path):
    text = ("urdf: arm.urdf\nbodies:\n  - {name: lower_body, frame: lower, mass: 1}\n"
            "  - {name: extra, frame: lowr, mass: 1}\n")
    source = yaml_on(tmp_path, ARM, text)
    with pytest.raises(SpecError) as info:
        andyc.load(source)
    first, second = info.value.diagnostics
    assert (first.file, first.line, first.path) == (str(source), 3, "bodies[0].name")
    assert f"{tmp_path / 'arm.urdf'}:{line_of(ARM, '<inertial>', 2)}, link[lower].inertial" in first.message
    assert (second.file, second.line, second.path) == (str(source), 4, "bodies[1].frame")


def test_missing_urdf_file(tmp_path):
    source = yaml_on(tmp_path, ARM, "urdf: {file: nope.urdf}\n")
    with pytest.raises(SpecError) as info:
        andyc.load(source)
    (d,) = info.value.diagnostics
    assert (d.line, d.path) == (1, "urdf.file") and "not found" in d.message


# -- the command line --------------------------------------------------------------------

def test_cli_check_a_urdf_from_a_package():
    urdf = ROBOTS_DIR / "ur_description/urdf/ur5_robot.urdf"
    result = check(urdf)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.startswith(f"{urdf}: model 'ur5' is valid: 6 degrees of freedom (shoulder_pan_joint, "
                                    "shoulder_lift_joint, elbow_joint, wrist_1_joint, wrist_2_joint, wrist_3_joint)")
    assert ("8 <gazebo>, 8 <link><collision>, 6 <limit effort>, 6 <limit velocity>, 6 <transmission>"
            in result.stderr)                   # (the limits' lower and upper are stops)


def test_cli_check_yaml_with_urdf_and_overrides(tmp_path):
    """Gravity, a locked joint, an extra frame and body, a constraint on a URDF frame, a hybrid graph whose
    guard uses a URDF frame, and a floating base (ur5's root link is 'world', so the subtree of base_link is
    kept and floats)."""
    urdf = ROBOTS_DIR / "ur_description/urdf/ur5_robot.urdf"
    (tmp_path / "ur5_payload.yaml").write_text(f"""name: ur5_payload
urdf:
  file: {urdf}
  base: floating
  root: base_link
  position: [0, 0, 1]
  lock: {{wrist_3_joint: 0.4}}
parameters: {{g: 3.0}}
coordinates: {{elbow_joint: {{initial: 0.5}}}}
gravity: [0, "-g", 0]
frames:
  - {{name: payload_frame, parent: wrist_3_link, translation: [0, 0.1, 0]}}
bodies:
  - {{name: payload, frame: payload_frame, mass: 2.0, inertia: [0.01, 0.01, 0.01]}}
constraints:
  - {{name: base_pinned, holonomic: [base_link.x, base_link.y, base_link.z - 1]}}
discrete: {{touches: 0}}
hybrid:
  flows: [{{name: pinned, constraints: [base_pinned]}}, {{name: loose}}]
  jumps:
    - {{name: release, from: pinned, to: loose, guard: t - 1, direction: rising}}
    - {{name: touch, from: loose, to: pinned, guard: tool0.z - 0.2, direction: falling, reset: {{touches: touches + 1}}}}
""")
    result = check(tmp_path / "ur5_payload.yaml")
    assert result.exit_code == 0, result.stderr
    assert ("model 'ur5_payload' is valid: 11 speeds (shoulder_pan_joint, shoulder_lift_joint, elbow_joint, "
            "wrist_1_joint, wrist_2_joint, base_link_vx, base_link_vy, base_link_vz, base_link_wx, base_link_wy, "
            "base_link_wz) less 3 constraint rows") in result.stdout
    # (its 5 free joints' limits are 10 stops, beside the hand-written automaton: 20 jumps and 10 modes of theirs)
    assert ("less 3 constraint rows (3 holonomic) in 1 constraint; 10 contacts (shoulder_pan_joint_lower, "
            "shoulder_pan_joint_upper,") in result.stdout
    assert "hybrid: 2 flows (pinned (3 rows), loose (0 rows)), 22 jumps, 11 discrete states" in result.stdout
    spec = andyc.load(tmp_path / "ur5_payload.yaml")
    assert float(spec.gravity[1].subs({spec.parameters["g"][0]: spec.parameters["g"][1]})) == -3.0
    assert [float(c.initial) for c in spec.coordinates if c.name == "elbow_joint"] == [0.5]
    assert [float(s.initial) for s in spec.signals if s.name.startswith("base_link_")] == [0, 0, 1, 1, 0, 0, 0]


def test_cli_build_and_sim_a_urdf(tmp_path):
    """`andyc sim robot.urdf`: builds, runs and logs the URDF's frames; energy is kept (no damping here)."""
    urdf = ROBOTS_DIR / "double_pendulum_description/urdf/double_pendulum.urdf"
    run = tmp_path / "run.h5"
    proc = andyc_cli("sim", urdf, "--t-end", 0.5, "--dt", 1e-3, "--frames", "link2", "--out", run,
                     "--build-dir", tmp_path / "build", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert "500 steps" in proc.stdout and "not used by andyc" not in proc.stdout
    with h5py.File(run) as f:
        energy = f["energy"][:]
        assert list(f["frames"]) == ["link2"] and f.attrs["model"] == "robot_2dof_planar"
    assert abs(energy[-1] - energy[0]) < 1e-6 * max(1.0, abs(energy[0]))
