"""Shapes (andyc.spec.shapes): a YAML `shape:` on frames and bodies and a URDF's <visual> elements become one
list of plain shapes, in the module's DISPLAY and the run files' display record (HDF5 with the mesh files'
bytes), so that andyc view needs only the run file. Bad values: one FILE:LINE: PATH line each."""

import math
import re

import numpy as np
import pytest
import yaml

import andyc
from andyc.runtime.runfiles import read_h5
from andyc.spec.display import display
from andyc.spec.meaning import meaning_sha256
from tests.support import MODELS, ROBOTS_DIR
from tests.support.meshes import binary_stl, with_shape as _with
from tests.support.diagnostics import assert_at, line_of, load_text, one_problem

def test_double_pendulum_shapes_are_its_yaml_at_the_defaults(compiled):
    """The shipped double pendulum: the links' boxes and the masses' spheres, as the file says (read with
    pyyaml), sizes and offsets evaluated at the defaults L1 = 1, L2 = 0.8 by hand."""
    doc = yaml.safe_load((MODELS / "double_pendulum.yaml").read_text())
    shapes = compiled("double_pendulum").display["shapes"]
    assert [(s["frame"], s["kind"]) for s in shapes] == (
        [(f["name"], next(iter(f["shape"]))) for f in doc["frames"] if "shape" in f]
        + [(b["frame"], "sphere") for b in doc["bodies"]])
    upper, lower, mass1, mass2 = shapes
    assert upper["size"] == [0.04, 1.0, 0.02] and upper["xyz"] == [0.0, -0.5, 0.0]
    assert lower["size"] == [0.04, 0.8, 0.02] and lower["xyz"] == [0.0, -0.4, 0.0]
    assert mass1["radius"] == 0.08 and mass2["radius"] == 0.064
    assert mass1["rgba"] == pytest.approx([0xD6 / 255, 0x27 / 255, 0x28 / 255, 1.0])    # tab:red, #d62728
    assert all(s["rpy"] == [0.0, 0.0, 0.0] for s in shapes)


def test_every_kind_with_its_pose_colour_and_a_mesh_beside_the_model(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "wedge.stl").write_bytes(binary_stl([((0, 0, 0), (1, 0, 0), (0, 1, 0))]))
    spec = load_text(tmp_path, _with(
        "[{box: {size: [0.05, L, 0.05]}, xyz: [0, -L/2, 0], rpy: [0, 0, pi/2], colour: [0, 0.5, 1]},"
        " {cylinder: {radius: 0.02, length: L, axis: -y}, colour: '#ff8000'},"
        " {capsule: {radius: 0.01, length: 2*L, axis: [1, 1, 0]}},"
        " {mesh: {file: parts/wedge.stl, scale: 0.001}, xyz: [1, 2, 3], colour: [0.1, 0.2, 0.3, 0.5]}]"))
    box, cylinder, capsule, mesh, sphere = display(spec)["shapes"]
    assert box == {"frame": "arm", "kind": "box", "size": [0.05, 0.7, 0.05], "xyz": [0.0, -0.35, 0.0],
                   "rpy": [0.0, 0.0, pytest.approx(math.pi / 2)], "rgba": [0.0, 0.5, 1.0, 1.0]}
    assert (cylinder["radius"], cylinder["length"], cylinder["axis"]) == (0.02, 0.7, [0.0, -1.0, 0.0])
    assert cylinder["rgba"] == [1.0, 128 / 255, 0.0, 1.0]
    assert capsule["length"] == 1.4 and capsule["axis"] == pytest.approx([2 ** -0.5, 2 ** -0.5, 0.0])
    assert mesh["file"] == str((tmp_path / "parts" / "wedge.stl").resolve()) and mesh["format"] == "stl"
    assert mesh["scale"] == [0.001] * 3 and mesh["xyz"] == [1.0, 2.0, 3.0] and mesh["rgba"] == [0.1, 0.2, 0.3, 0.5]
    assert sphere == {"frame": "tip", "kind": "sphere", "radius": pytest.approx(0.07), "xyz": [0.0, 0.0, 0.0],
                      "rpy": [0.0, 0.0, 0.0], "rgba": [1.0, 0.0, 0.0, 1.0]}


def test_a_shape_does_not_change_what_the_model_means():
    """Shapes are pictures: the build key (andyc.spec.meaning) is the same with and without them, so adding
    one rewrites the module's front file and compiles nothing."""
    bare = yaml.safe_load(_with("{sphere: {radius: 1}}"))
    del bare["frames"][0]["shape"], bare["bodies"][0]["shape"]
    shaped = yaml.safe_load(_with("{sphere: {radius: 1}}"))
    assert meaning_sha256(bare) == meaning_sha256(shaped)


@pytest.mark.parametrize("shape, path, words", [
    ("{sphere: {radius: -0.1}}", "frames[0].shape.sphere.radius", "is not > 0"),
    ("{box: {size: [1, 0, 1]}}", "frames[0].shape.box.size[1]", "is not > 0"),
    ("{mesh: {file: nowhere.stl}}", "frames[0].shape.mesh.file", "does not exist"),
    ("{mesh: {file: model.yaml}}", "frames[0].shape.mesh.file", "is not STL, OBJ or DAE"),
    ("{sphere: {radius: 1}, colour: nocolour}", "frames[0].shape.colour", "is not a colour name"),
    ("{sphere: {radius: 1}, colour: [1.5, 0, 0]}", "frames[0].shape.colour", "outside 0..1"),
    ("{sphere: {radius: 1}, box: {size: [1, 1, 1]}}", "frames[0].shape", "got box and sphere"),
    ("{colour: red}", "frames[0].shape", "got none"),
    ("{sphere: {radius: q}}", "frames[0].shape.sphere.radius", "cannot be used here"),
    ("{cylinder: {radius: 1, length: 1, axis: [0, 0, 0]}}", "frames[0].shape.cylinder.axis", "not a direction"),
    ("{sphere: {radius: 1, height: 2}}", "frames[0].shape.sphere", "'height' was unexpected"),
    ("[{sphere: {radius: 1}}, {sphere: {radius: 0}}]", "frames[0].shape[1].sphere.radius", "is not > 0"),
])
def test_a_bad_shape_is_one_line_at_its_place(tmp_path, shape, path, words):
    text = _with(shape)
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "shape: " + shape), path)
    assert words in d.message


def test_the_run_file_carries_the_shapes_and_the_mesh_bytes(tmp_path):
    """A run's HDF5 file holds the display record's shapes and each mesh file's bytes: once the mesh file is
    gone, the run read back still has them (andyc view needs only the run file)."""
    stl = binary_stl([((0, 0, 0), (0.1, 0, 0), (0, 0.1, 0)), ((0, 0, 0), (0, 0, 0.1), (0.1, 0, 0))])
    (tmp_path / "wedge.stl").write_bytes(stl)
    (tmp_path / "model.yaml").write_text(_with("{mesh: {file: wedge.stl}}"))
    model, _ = andyc.compile_model(tmp_path / "model.yaml", tmp_path / "build")
    run = andyc.simulate(model, 0.05, dt=1e-3, every=10, frames="all")
    run.save(tmp_path / "run.h5")
    (tmp_path / "wedge.stl").unlink()
    back = read_h5(tmp_path / "run.h5")
    assert back.display["shapes"] == model.display["shapes"]
    file = back.display["shapes"][0]["file"]
    assert back.mesh_bytes(file) == stl
    assert np.array_equal(back.frame_rotations["arm"], run.frame_rotations["arm"])


URDF = """<?xml version="1.0"?>
<robot name="shaped_arm">
  <material name="blue"><color rgba="0 0 0.8 1"/></material>
  <link name="base">
    <visual><geometry><box size="0.2 0.2 0.1"/></geometry><material name="blue"/></visual>
  </link>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual>
      <origin xyz="0 0 0.25" rpy="0.1 0.2 0.3"/>
      <geometry><cylinder radius="0.03" length="0.5"/></geometry>
      <material name="own"><color rgba="1 0.5 0 0.9"/></material>
    </visual>
    <visual><origin xyz="0 0 0.5"/><geometry><sphere radius="0.05"/></geometry></visual>
    <visual><geometry><mesh filename="package://shaped/meshes/wedge.stl" scale="2 2 2"/></geometry></visual>
    <visual><geometry><mesh filename="meshes/wedge.stl"/></geometry></visual>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="arm"/><origin xyz="0 0 0.1"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="3"/>
  </joint>
</robot>
"""


def test_urdf_visuals_become_the_same_shapes(tmp_path):
    """Primitives with their origin and material colour (its own, or the robot's material of its name), and
    meshes through package:// and a relative path, resolved as the importer resolves them."""
    folder = tmp_path / "shaped"
    (folder / "meshes").mkdir(parents=True)
    (folder / "meshes" / "wedge.stl").write_bytes(binary_stl([((0, 0, 0), (1, 0, 0), (0, 1, 0))]))
    (folder / "arm.urdf").write_text(URDF)
    spec = andyc.load(folder / "arm.urdf")
    box, cylinder, sphere, packaged, relative = display(spec)["shapes"]
    arm = cylinder["frame"]
    assert box["kind"] == "box" and box["size"] == [0.2, 0.2, 0.1] and box["rgba"] == [0.0, 0.0, 0.8, 1.0]
    assert cylinder == {"frame": arm, "kind": "cylinder", "radius": 0.03, "length": 0.5, "axis": [0.0, 0.0, 1.0],
                        "xyz": [0.0, 0.0, 0.25], "rpy": [0.1, 0.2, 0.3], "rgba": [1.0, 0.5, 0.0, 0.9]}
    assert sphere["radius"] == 0.05 and sphere["xyz"] == [0.0, 0.0, 0.5] and sphere["rgba"] is not None
    wedge = str((folder / "meshes" / "wedge.stl").resolve())
    assert (packaged["file"], packaged["scale"], packaged["rgba"]) == (wedge, [2.0, 2.0, 2.0], None)
    assert relative["file"] == wedge and relative["format"] == "stl"
    assert {s["frame"] for s in (cylinder, sphere, packaged, relative)} == {arm}
    assert arm in {f.name for f in spec.frames}


def test_the_panda_visuals_are_its_meshes_on_its_link_frames():
    """The panda of example-robot-data, fingers locked as the tests use it: one DAE mesh per link that has a
    <visual>, each on that link's frame, with the files of its package."""
    urdf = ROBOTS_DIR / "panda_description/urdf/panda.urdf"
    spec = andyc.load(urdf)
    shapes = display(spec)["shapes"]
    links = re.findall(r'<link name="(\w+)">(.*?)</link>', urdf.read_text(), flags=re.S)
    assert sorted(s["frame"] for s in shapes) == sorted(name for name, body in links if "<visual>" in body)
    assert all(s["kind"] == "mesh" and s["format"] == "dae" and s["file"].startswith(str(ROBOTS_DIR)) for s in shapes)
    finger = [s for s in shapes if s["frame"] == "panda_rightfinger"][0]
    assert finger["rpy"] == [0.0, 0.0, pytest.approx(math.pi)]


def test_a_robot_with_many_shapes_keeps_them_in_its_run_file(tmp_path):
    """More shapes than an HDF5 attribute holds (its object header takes 64 kB in all): the display record
    goes into a dataset, and reads back equal."""
    from tests.support.runs import plain_run

    run = plain_run()
    shape = {"frame": "world", "kind": "sphere", "radius": 0.1, "xyz": [0.0, 0.0, 0.0], "rpy": [0.0, 0.0, 0.0],
             "rgba": [0.5, 0.5, 0.5, 1.0]}
    run.display = {"units": {}, "ground": None, "shapes": [dict(shape, radius=0.001 * (k + 1)) for k in range(1000)]}
    assert read_h5(run.save(tmp_path / "run.h5")).display == run.display
