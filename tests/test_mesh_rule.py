"""Which mesh files a model may name (andyc.spec.meshfiles): by the path a name resolves to, inside the
model's folder (YAML) or the URDF's package roots, regular files, at most MAX_MESH_BYTES. A model from
anyone cannot get another file's bytes into a run file or a page through a symbolic link, a chain of
links, `package://` traversal or a path outside its folder."""

import os

import h5py
import pytest

import andyc
from andyc.runtime.runfiles import read_h5
from andyc.spec.display import display
from andyc.spec.meshfiles import MAX_MESH_BYTES
from tests.support.cli import invoke
from tests.support.diagnostics import line_of, one_problem
from tests.support.meshes import binary_stl, with_shape as _with

SECRET = b"root:x:0:0:the secret a link must not leak\n" * 4
STL = binary_stl([((0, 0, 0), (0.1, 0, 0), (0, 0.1, 0))])

ROBOT = """<?xml version="1.0"?>
<robot name="leaky">
  <link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>
  <link name="arm">
    <inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <visual><geometry><mesh filename="MESH"/></geometry></visual>
  </link>
  <joint name="shoulder" type="continuous"><parent link="base"/><child link="arm"/><axis xyz="0 1 0"/></joint>
</robot>
"""


@pytest.fixture
def outside(tmp_path):
    """A folder beside the model's, holding a secret (not a mesh) and a real mesh."""
    folder = tmp_path / "outside"
    folder.mkdir()
    (folder / "secret.txt").write_bytes(SECRET)
    (folder / "secret.stl").write_bytes(STL)
    return folder


def _robot(folder, mesh: str):
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "r.urdf").write_text(ROBOT.replace("MESH", mesh))
    return folder / "r.urdf"


def _meshes(spec) -> list:
    return [s for s in display(spec)["shapes"] if s["kind"] == "mesh"]


def _refusal(spec) -> str:
    lines = [w.message for w in spec.warnings if "refused" in w.message]
    assert len(lines) == 1, [w.message for w in spec.warnings]
    return lines[0]


def test_a_mesh_link_to_another_file_is_refused_and_nothing_of_it_reaches_the_run_file(tmp_path, outside):
    """`ln -s SECRET evil.stl`, the URDF naming evil.stl: a warning names the resolved file; `andyc sim
    --frames all` writes a run file with no mesh, and no byte of the secret is in it."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "evil.stl").symlink_to(outside / "secret.txt")
    urdf = _robot(pkg, "evil.stl")
    spec = andyc.load(urdf)
    assert _meshes(spec) == []
    assert "resolves to" in _refusal(spec) and str((outside / "secret.txt").resolve()) in _refusal(spec)
    checked = invoke("check", urdf)
    assert checked.exit_code == 0 and "1 visual mesh file(s) refused" in checked.output, checked.output
    result = invoke("sim", urdf, "--t-end", "0.01", "--dt", "1e-3", "--frames", "all", "-o", tmp_path / "run.h5",
                    "--build-dir", tmp_path / "build")
    assert result.exit_code == 0, result.output
    with h5py.File(tmp_path / "run.h5") as f:
        assert "meshes" not in f
    assert SECRET[:20] not in (tmp_path / "run.h5").read_bytes()


def test_a_chain_of_links_is_followed_to_its_end(tmp_path, outside):
    """b.obj -> a.dae -> the secret: both names have a mesh suffix, the file they resolve to has none and
    lies outside."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "a.dae").symlink_to(outside / "secret.txt")
    (pkg / "b.obj").symlink_to(pkg / "a.dae")
    spec = andyc.load(_robot(pkg, "b.obj"))
    assert _meshes(spec) == [] and "outside" in _refusal(spec)


def test_a_link_to_a_real_mesh_outside_is_refused_too(tmp_path, outside):
    """The rule is where the bytes live, not what they look like: a real STL outside the package."""
    pkg = tmp_path / "pkg"
    pkg.mkdir()
    (pkg / "fine.stl").symlink_to(outside / "secret.stl")
    spec = andyc.load(_robot(pkg, "fine.stl"))
    assert _meshes(spec) == [] and "outside the folders" in _refusal(spec)


def test_package_traversal_is_refused(tmp_path, outside):
    """package://pkg/../../outside/secret.stl climbs out of the package it names."""
    urdf = _robot(tmp_path / "ws" / "pkg", "package://pkg/../../outside/secret.stl")
    spec = andyc.load(urdf)
    assert _meshes(spec) == [] and "outside" in _refusal(spec)


def test_an_absolute_name_outside_the_package_is_refused(tmp_path, outside):
    spec = andyc.load(_robot(tmp_path / "pkg", f"file://{outside / 'secret.stl'}"))
    assert _meshes(spec) == [] and "outside" in _refusal(spec)


def test_meshes_inside_the_package_pass_links_included(tmp_path):
    """A link inside the package to a mesh inside it, `package://` and a relative name into a sibling folder
    of a ROS package (package.xml marks its root): all drawn, each by its resolved path."""
    pkg = tmp_path / "robot_description"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "package.xml").write_text("<package/>")
    (pkg / "meshes" / "arm.stl").write_bytes(STL)
    (pkg / "meshes" / "alias.stl").symlink_to("arm.stl")
    real = str((pkg / "meshes" / "arm.stl").resolve())
    for name in ("../meshes/alias.stl", "package://robot_description/meshes/arm.stl", "../meshes/arm.stl"):
        spec = andyc.load(_robot(pkg / "urdf", name))
        (mesh,) = _meshes(spec)
        assert mesh["file"] == real and mesh["format"] == "stl"


def test_a_folder_of_package_paths_is_a_root(tmp_path, outside):
    """A folder the user names in `urdf: {package_paths}` is trusted: its meshes are drawn."""
    _robot(tmp_path / "m", "package://outside/secret.stl")
    (tmp_path / "m" / "model.yaml").write_text(f"urdf: {{file: r.urdf, package_paths: ['{tmp_path}']}}\n")
    (mesh,) = _meshes(andyc.load(tmp_path / "m" / "model.yaml"))
    assert mesh["file"] == str((outside / "secret.stl").resolve())


@pytest.mark.parametrize("name, words", [
    ("../outside/secret.stl", "outside the folders"),
    ("evil.stl", "outside the folders"),
    ("pipe.stl", "not a regular file"),
    ("huge.stl", f"past andyc's limit of {MAX_MESH_BYTES // 2**20} MB"),
    ("looped.stl", "does not exist"),
])
def test_a_yaml_mesh_that_breaks_the_rule_is_one_located_error(tmp_path, outside, name, words):
    """A YAML `shape: {mesh: ...}` must resolve inside the model file's folder to a regular mesh file within
    the size limit; the sparse 'huge' file is refused from its size, before any byte is read, and the pipe
    without waiting on it."""
    model = tmp_path / "m"
    model.mkdir()
    (model / "evil.stl").symlink_to(outside / "secret.txt")
    os.mkfifo(model / "pipe.stl")
    with open(model / "huge.stl", "wb") as f:
        f.truncate(MAX_MESH_BYTES + 1)
    (model / "looped.stl").symlink_to(model / "looped.stl")
    text = _with("{mesh: {file: " + name + "}}")
    d = one_problem(model, text)
    assert d.line == line_of(text, "shape: {mesh") and d.path == "frames[0].shape.mesh.file"
    assert words in d.message, d.message


def test_a_run_file_read_back_never_reads_the_disk(tmp_path, outside):
    """A run file names its meshes' files as text anyone could write: read back, only the bytes it holds
    are drawn, whatever file it names (here a real mesh outside any root)."""
    (tmp_path / "wedge.stl").write_bytes(STL)
    (tmp_path / "model.yaml").write_text(_with("{mesh: {file: wedge.stl}}"))
    model, _ = andyc.compile_model(tmp_path / "model.yaml", tmp_path / "build")
    andyc.simulate(model, 0.01, dt=1e-3, frames="all").save(tmp_path / "run.h5")
    back = read_h5(tmp_path / "run.h5")
    assert back.mesh_bytes(back.display["shapes"][0]["file"]) == STL
    assert back.mesh_bytes(str(outside / "secret.stl")) is None
