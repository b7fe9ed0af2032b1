"""Model reduction: bodies fixed to one moving frame merged into one (andyc.symbolic.reduce).

The merged model must have the same M(q) and G(q, v) as the original: compared
at random states, and the merged dynamics must need fewer operations.
"""

import re

import numpy as np
import pytest

from andyc.codegen.generate import generate
from andyc.runtime.compiled import load_compiled
from andyc.spec.load import load
from andyc.symbolic import derive
from andyc.symbolic.kinematics import rigid_groups
from andyc.symbolic.reduce import merge_rigid_bodies
from tests.support import ROBOTS_DIR
from tests.support.cli import invoke

ARM = """
name: rigid_arm
parameters: {g: 9.81}
coordinates:
  q1: {initial: 0.3, velocity: 0.5}
  q2: {initial: -0.6, velocity: 1.2}
gravity: [0, -g*0.6, -g*0.8]
frames:
  - {name: link1, parent: world, revolute: q1, axis: [0, 0.6, 0.8]}
  - {name: tip1, parent: link1, translation: [0.5, 0.1, 0], rotation: {rpy: [0.3, -0.2, 0.7]}}
  - {name: sensor, parent: tip1, translation: [0, 0.05, 0.02], rotation: {rpy: [1.1, 0.4, 0]}}
  - {name: link2, parent: tip1, revolute: q2, axis: y}
  - {name: tool, parent: link2, translation: [0.3, 0, 0.1], rotation: {rpy: [0, 0.5, 0]}}
  - {name: stand, parent: world, translation: [0, 0, -1]}
bodies:
  - {name: arm1, frame: link1, mass: 2.0, com: [0.25, 0.01, 0], inertia: [0.003, 0.04, 0.041, 0.001, 0.0002, 0.0001]}
  - {name: flange, frame: tip1, mass: 0.7, com: [0.02, 0, 0.01], inertia: [0.001, 0.002, 0.0015, 0.0001, 0, 0.0002]}
  - {name: camera, frame: sensor, mass: 0.4, com: [0, 0.03, 0], inertia: [0.0005, 0.0004, 0.0003, 0.00002, 0.00001, 0.00003]}
  - {name: arm2, frame: link2, mass: 1.2, com: [0.15, 0, 0.02], inertia: [0.002, 0.012, 0.011, 0.0003, 0.0001, 0.0002]}
  - {name: gripper, frame: tool, mass: 0.5, com: [0.02, 0, 0], inertia: [0.0004, 0.0005, 0.0006, 0, 0.00002, 0]}
  - {name: base_plate, frame: stand, mass: 5.0}
"""


@pytest.fixture(scope="module")
def arms(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("reduce")
    path = tmp / "rigid_arm.yaml"
    path.write_text(ARM)
    spec = load(path)
    full = generate(derive(spec), tmp / "full")
    merged = generate(derive(merge_rigid_bodies(spec)), tmp / "merged")
    return spec, load_compiled(full.module_path), load_compiled(merged.module_path), full, merged


def test_groups_are_the_moving_frames(arms):
    spec = arms[0]
    roots = {name: root for name, (root, _, _) in rigid_groups(spec).items()}
    assert roots == {"world": "world", "link1": "link1", "tip1": "link1", "sensor": "link1", "link2": "link2",
                     "tool": "link2", "stand": "world", **{f.name: roots[f.name] for f in spec.frames if f.internal}}
    merged = merge_rigid_bodies(spec)
    assert sorted(b.name for b in merged.bodies) == ["arm1+flange+camera", "arm2+gripper", "base_plate"]


def test_merged_model_has_the_same_dynamics_and_fewer_operations(arms):
    _, full, merged, full_result, merged_result = arms
    rng = np.random.default_rng(7)
    for _ in range(20):
        x = rng.uniform(-3, 3, full.nx)
        M1, M2 = full.module.mass_matrix(0.0, x), merged.module.mass_matrix(0.0, x)
        G1, G2 = full.module.generalized_force(0.0, x), merged.module.generalized_force(0.0, x)
        np.testing.assert_allclose(M2, M1, rtol=1e-12, atol=1e-12 * np.abs(M1).max())
        np.testing.assert_allclose(G2, G1, rtol=1e-12, atol=1e-12 * np.abs(G1).max())
    assert merged_result.operations["dynamics"] < full_result.operations["dynamics"]


def test_check_prints_the_operations_before_and_after_for_a_urdf(tmp_path):
    """panda with its fingers locked (panda_finger_joint2 mimics joint1, so both hold): the hand and
    finger bodies merge into the flange's. `andyc check` prints the DOF and operations of the robot as
    written (8 DOF, every body its own) and of the reduced model (7 DOF, merged), fewer after."""
    source = tmp_path / "panda_arm.yaml"
    source.write_text(f"name: panda_arm\nurdf:\n  file: {ROBOTS_DIR / 'panda_description/urdf/panda.urdf'}\n"
                      "  lock: {panda_finger_joint1: 0.02}\n")
    result = invoke("check", str(source))
    assert result.exit_code == 0, result.output
    found = re.search(r"reduced: 8 -> 7 degrees of freedom \(1 joint locked: panda_finger_joint1\); "
                      r"11 bodies merged into (\d+) .*dynamics (\d+) -> (\d+) operations", result.output)
    assert found, result.output
    merged, before, after = map(int, found.groups())
    assert merged < 11 and after < before


SPHERE = """
name: sphere_on_arm
coordinates:
  q: {initial: 0.1}
frames:
  - {name: link, parent: world, revolute: q, axis: z}
  - {name: tip, parent: link, translation: [0.5, 0, 0], rotation: {rpy: [0.3, -0.7, 1.1]}}
bodies:
  - {name: box, frame: link, mass: 1, inertia: [0.1, 0.2, 0.3, 0, 0, 0]}
  - {name: ball, frame: tip, mass: 2, inertia: [0.01, 0.01, 0.01, 0, 0, 0]}
"""


def test_a_merged_bodys_numbers_are_the_parallel_axis_theorems_and_its_zeros_stay_zeros(tmp_path):
    """A ball (isotropic inertia, so R I R^T = I whatever the rotation) fixed 0.5 m along a box's x on a rotated
    frame: the merged body is m = 3 at c = (1/3, 0, 0), with I = diag(0.1, 0.2, 0.3) + 0.01 E plus the parallel
    axis terms m_i (|d_i|^2 E - d_i d_i^T) of d_box = (-1/3, 0, 0) and d_ball = (1/6, 0, 0) (Featherstone 2008,
    2.13), computed by hand: diag(0.11, 0.21 + 1/6, 0.31 + 1/6). Its products of inertia are exactly 0 (not the
    ~1e-40 that the rotation's sines and cosines leave in the arithmetic), so the generated code has no terms
    for them."""
    path = tmp_path / "sphere_on_arm.yaml"
    path.write_text(SPHERE)
    merged = merge_rigid_bodies(load(path))
    body = next(b for b in merged.bodies if b.name == "box+ball")
    frame = next(f for f in merged.frames if f.name == body.frame)
    assert float(body.mass) == 3.0
    assert [float(e) for e in frame.transforms[0].vector] == pytest.approx([1 / 3, 0, 0], abs=1e-16)
    expected = np.diag([0.11, 0.21 + 1 / 6, 0.31 + 1 / 6])
    inertia = np.array(body.inertia.tolist(), dtype=float)
    np.testing.assert_allclose(inertia, expected, rtol=1e-15, atol=0)
    assert all(float(body.inertia[i, j]) == 0.0 for i in range(3) for j in range(3) if i != j)
