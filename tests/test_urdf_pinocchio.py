"""URDF robots against Pinocchio (docs/reference-cases.md §9).

For URDFs that ship inside the PyPI package example-robot-data (real robots
nobody here wrote), andyc's M(q), bias force and forward dynamics must equal
Pinocchio's crba, rnea(q, v, 0) and aba at 20 random states, to 1e-10
relative (largest entry difference over the largest entry of Pinocchio's).
A small hand-written URDF adds what those robots lack: a planar joint, a
floating joint inside the tree, skew and negative axes, rotated inertial
frames, a mimic joint with multiplier and offset. A YAML model built on a URDF
(gravity, a locked joint, an extra body) is compared with Pinocchio's reduced
model carrying the same changes.

andyc's generated module: M dv/dt = G(t, q, v) at zero inputs, so the bias is
-G; `rhs` gives dv/dt. Pinocchio ignores joint damping in rnea and aba, so the
expected bias adds D v and aba gets tau = -D v, with D = diag(model.damping)
as Pinocchio parsed it from <dynamics damping>.

Set ANDYC_URDF_SLOW=1 to add bolt (a biped on a floating base, about 13 s)
and baxter (17 DOF, mimic, prismatic, rotated inertials; about 50 s to build
and compile).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest

import andyc
from tests.support import ROBOTS_DIR
from tests.support.pinocchio_map import PINOCCHIO_ROBOTS, PinocchioMap, relative, root_link

pin = pytest.importorskip("pinocchio")

ROBOTS = dict(PINOCCHIO_ROBOTS)
if os.environ.get("ANDYC_URDF_SLOW"):
    ROBOTS["bolt"] = ("bolt_description/robots/bolt.urdf", "floating")       # biped; feet with inertia, no mass
    ROBOTS["baxter"] = ("baxter_description/urdf/baxter.urdf", "fixed")
STATES, TOL = 20, 1e-10

# Every URDF joint kind andyc reads, in one robot (no example-robot-data robot has a planar joint).
FEATURES_URDF = """<?xml version="1.0"?>
<robot name="features">
  <link name="base">
    <inertial><mass value="3"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial>
  </link>
  <link name="arm">
    <inertial>
      <origin xyz="0.05 -0.02 0.2" rpy="0.3 -0.2 0.5"/>
      <mass value="1.2"/>
      <inertia ixx="0.02" iyy="0.03" izz="0.015" ixy="0.001" ixz="-0.002" iyz="0.0005"/>
    </inertial>
  </link>
  <joint name="skew" type="revolute">
    <parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0.3" rpy="0.1 0.2 -0.3"/>
    <axis xyz="0 0.6 -0.8"/>
    <limit lower="-2" upper="2" effort="10" velocity="3"/>
    <dynamics damping="0.1" friction="0.2"/>
  </joint>
  <link name="forearm">
    <inertial>
      <origin xyz="0.1 0 0" rpy="0 1.2 0"/>
      <mass value="0.7"/>
      <inertia ixx="0.004" iyy="0.01" izz="0.009" ixy="0" ixz="0.0003" iyz="0"/>
    </inertial>
  </link>
  <joint name="follower" type="revolute">
    <parent link="arm"/><child link="forearm"/>
    <origin xyz="0 0 0.4"/>
    <axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="10" velocity="3"/>
    <mimic joint="skew" multiplier="-1.5" offset="0.2"/>
    <dynamics damping="0.05"/>
  </joint>
  <link name="tip"><inertial><origin xyz="0 0.02 0"/><mass value="0.2"/>
    <inertia ixx="1e-4" iyy="2e-4" izz="1.5e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="tip_mount" type="fixed">
    <parent link="forearm"/><child link="tip"/><origin xyz="0.2 0 0" rpy="0 0 0.7"/>
  </joint>
  <link name="slider"><inertial><mass value="0.5"/>
    <inertia ixx="0.001" iyy="0.002" izz="0.002" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="slide" type="prismatic">
    <parent link="base"/><child link="slider"/><origin xyz="0.3 0 0"/><axis xyz="-1 0 0"/>
    <limit lower="-1" upper="1" effort="10" velocity="3"/>
    <dynamics damping="0.2"/>
  </joint>
  <link name="puck">
    <inertial>
      <origin xyz="0.01 0.02 -0.01" rpy="0.4 0 0.1"/>
      <mass value="0.8"/>
      <inertia ixx="0.003" iyy="0.004" izz="0.006" ixy="0.0002" ixz="0" iyz="0.0001"/>
    </inertial>
  </link>
  <joint name="table" type="planar">
    <parent link="base"/><child link="puck"/><origin xyz="0 0.5 0.1" rpy="0 0 0.25"/><axis xyz="0 0 1"/>
  </joint>
  <link name="drone">
    <inertial><origin xyz="0 0 0.05" rpy="0.2 0.1 0"/><mass value="1.5"/>
      <inertia ixx="0.02" iyy="0.025" izz="0.04" ixy="0.001" ixz="0" iyz="0"/></inertial>
  </link>
  <joint name="hover" type="floating">
    <parent link="puck"/><child link="drone"/><origin xyz="0 0 0.2" rpy="0 0.3 0"/>
  </joint>
  <link name="rotor"><inertial><origin xyz="0 0 0.01"/><mass value="0.1"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="2e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="spin" type="continuous">
    <parent link="drone"/><child link="rotor"/><origin xyz="0.1 0 0.05"/><axis xyz="0.48 0.6 0.64"/>
    <dynamics damping="0.01"/>
  </joint>
  <transmission name="t1"><type>SimpleTransmission</type></transmission>
  <gazebo reference="arm"><material>Gazebo/Blue</material></gazebo>
</robot>
"""


def build(source: Path, out_dir: Path):
    """andyc build, then import and Numba compile; returns (module, seconds)."""
    model, result = andyc.compile_model(source, out_dir)
    t = result.timings
    return model.module, {"build": t["load"] + t.get("derive", 0.0) + t.get("generate", 0.0), "numba": t["compile"]}


def compare(module, model, urdf: Path, base_link, seed: int) -> dict:
    """Largest relative errors of M, bias and dv/dt over STATES random states."""
    mapping = PinocchioMap(module, model, urdf, base_link)
    data = model.createData()
    rng = np.random.default_rng(seed)
    errors = {"M": 0.0, "bias": 0.0, "aba": 0.0}
    for _ in range(STATES):
        x = mapping.random_state(rng)
        M, b, a = mapping.expected(x, data, mimic_free=not mapping.mimic)
        errors["M"] = max(errors["M"], relative(module.mass_matrix(0.0, x), M))
        errors["bias"] = max(errors["bias"], relative(-module.generalized_force(0.0, x), b))
        errors["aba"] = max(errors["aba"], relative(module.rhs(0.0, x)[module.NQ:module.NQ + module.NV], a))
    return errors


@pytest.fixture(scope="module")
def out_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("urdf_build")


@pytest.fixture(scope="module", params=list(ROBOTS))
def robot(request, out_dir):
    """(name, errors, timings, module) for one robot, built once for this module."""
    name = request.param
    relpath, base = ROBOTS[name]
    urdf = ROBOTS_DIR / relpath
    source = urdf
    if base == "floating":
        source = out_dir / f"{name}.yaml"
        source.write_text(f"urdf: {{file: {urdf}, base: floating}}\n")
    module, times = build(source, out_dir)
    if base == "floating":
        model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    else:
        model = pin.buildModelFromUrdf(str(urdf))
    errors = compare(module, model, urdf, root_link(urdf) if base == "floating" else None, seed=len(name))
    print(f"\n[urdf] {name}: nv {module.NV}, build {times['build']:.1f} s + numba {times['numba']:.1f} s; "
          f"max relative error M {errors['M']:.1e}, bias {errors['bias']:.1e}, aba {errors['aba']:.1e}")
    return name, errors, times, module


def test_mass_matrix_equals_crba(robot):
    name, errors, _, _ = robot
    assert errors["M"] < TOL, f"{name}: M(q) differs from Pinocchio's crba by {errors['M']:.2e} (relative)"


def test_bias_equals_rnea_at_zero_acceleration(robot):
    name, errors, _, _ = robot
    assert errors["bias"] < TOL, f"{name}: bias differs from Pinocchio's rnea(q, v, 0) by {errors['bias']:.2e}"


def test_forward_dynamics_equals_aba(robot):
    name, errors, _, _ = robot
    assert errors["aba"] < TOL, f"{name}: dv/dt differs from Pinocchio's aba by {errors['aba']:.2e}"


def test_tree_formulation_equals_dense(robot):
    """Issue 27: every robot's M has the tree pattern, and dv/dt = M^-1 G by its LTDL (forced on, also where the
    operation counts chose dense) equals the dense Cholesky path's to 1e-12; the rhs (the chosen one) too.
    M and G come from the same generated code either way. The floating-base robots get LTDL or the
    articulated-body algorithm (tests/test_aba.py) by the counts, not the dense path."""
    name, _, _, module = robot
    linalg = module.NUMERICS.linalg
    assert len(module.MASS_ORDER) == module.NV, f"{name}: M has no tree pattern"
    if ROBOTS[name][1] == "floating":
        assert module.FORMULATION in ("ltdl", "aba") and (module.NT == module.NV) == (module.FORMULATION == "ltdl")
    if name == "solo12":        # (so the floating base's ABA is checked here against the dense path and pin.aba)
        assert module.FORMULATION == "aba" and module.NB == module.NV
    rng = np.random.default_rng(27)
    n, nq = module.NV, module.NQ
    for _ in range(5):
        x = module.initial_state()
        x[:nq + n] += rng.uniform(-1, 1, nq + n)
        M, G = module.mass_matrix(0.0, x), module.generalized_force(0.0, x)
        dense, L = G.copy(), M.copy()
        assert linalg.cholesky(L, n, 0.0)
        linalg.solve_lower(L, dense, n)
        linalg.solve_upper(L, dense, n)
        tree, F = G.copy(), M.copy()
        assert linalg.ltdl(F, module.MASS_PARENT, module.MASS_ORDER, n, 0.0)
        linalg.ltdl_solve(F, module.MASS_PARENT, module.MASS_ORDER, tree, n)
        scale = np.abs(dense).max()
        assert np.abs(tree - dense).max() <= 1e-12 * scale, name
        assert np.abs(module.rhs(0.0, x)[nq:nq + n] - dense).max() <= 1e-12 * scale, name


def test_the_comparison_can_fail(robot, out_dir):
    """The comparison is not vacuous: Pinocchio's model with every moving body 10 % heavier fails it."""
    name, _, _, module = robot
    relpath, base = ROBOTS[name]
    urdf = ROBOTS_DIR / relpath
    model = pin.buildModelFromUrdf(str(urdf), *([pin.JointModelFreeFlyer()] if base == "floating" else []))
    for k in range(1, model.njoints):           # (inertias[0] is the universe: fixed links, no motion)
        model.inertias[k].mass *= 1.1
    errors = compare(module, model, urdf, root_link(urdf) if base == "floating" else None, seed=1)
    assert errors["M"] > 1e-4 and errors["bias"] > 1e-4


def test_state_layout(robot):
    """Fixed base: the speeds are the joint rates, no signals. Floating base: the joint angles, their rates,
    then the base's six body-frame speeds; its position and quaternion (w first) are the 7 signals."""
    name, _, _, module = robot
    if ROBOTS[name][1] == "fixed":
        assert list(module.SPEEDS) == [f"{c}_dot" for c in module.COORDINATES] and module.NS == 0
    else:
        assert module.NV == module.NQ + 6 and module.NQ == {"solo12": 12, "bolt": 6}[name]
        assert list(module.SPEEDS[-6:]) == [f"base_link_{c}" for c in ("vx", "vy", "vz", "wx", "wy", "wz")]
        assert list(module.SIGNALS) == [f"base_link_{c}" for c in ("x", "y", "z", "qw", "qx", "qy", "qz")]


# -- joint kinds no example robot has -----------------------------------------

@pytest.fixture(scope="module")
def features(out_dir):
    urdf = out_dir / "features.urdf"
    urdf.write_text(FEATURES_URDF)
    without_mimic = out_dir / "features_free.urdf"
    text = FEATURES_URDF.replace('<mimic joint="skew" multiplier="-1.5" offset="0.2"/>', "")
    without_mimic.write_text(text.replace('name="features"', 'name="features_free"'))
    return {path: build(path, out_dir)[0] for path in (urdf, without_mimic)}


def test_every_joint_kind_against_pinocchio(features):
    """Planar (T depends on the angle), a floating joint inside the tree, skew and negative axes, rotated
    inertial frames, continuous, prismatic, fixed, damping; with a mimic joint (multiplier -1.5, offset 0.2):
    M and bias against crba and rnea, dv/dt against their solve; without it, dv/dt against aba."""
    for urdf, module in features.items():
        model = pin.buildModelFromUrdf(str(urdf))
        errors = compare(module, model, urdf, None, seed=3)
        print(f"\n[urdf] {urdf.stem}: nv {module.NV}; max relative error M {errors['M']:.1e}, "
              f"bias {errors['bias']:.1e}, dv/dt {errors['aba']:.1e}")
        assert max(errors.values()) < TOL, (urdf.stem, errors)
    mimic = next(m for u, m in features.items() if u.stem == "features")
    assert "follower" not in mimic.COORDINATES and "skew" in mimic.COORDINATES       # no DOF of its own
    assert [c for c in mimic.COORDINATES if c.startswith("table_")] == ["table_x", "table_y", "table_theta"]
    assert [s for s in mimic.SPEEDS if s.startswith("hover_")] == [f"hover_{c}" for c in
                                                                   ("vx", "vy", "vz", "wx", "wy", "wz")]


def test_mimic_reduction_is_pinocchios_mimic_model(features):
    """Pinocchio's own mimic joints (mimic=True: crba and rnea, no aba) give the same M and bias (no damping)."""
    urdf, module = next((u, m) for u, m in features.items() if u.stem == "features")
    full = pin.buildModelFromUrdf(str(urdf))
    reduced = pin.buildModelFromUrdf(str(urdf), mimic=True)
    mapping = PinocchioMap(module, full, urdf, None)
    data, rdata = full.createData(), reduced.createData()
    rng = np.random.default_rng(5)
    for _ in range(5):
        x = mapping.random_state(rng)
        q, T, c = mapping.state(x)
        v = T @ x[module.NQ:module.NQ + module.NV]
        # The reduced model's q and v are the full ones without the mimic joint's entries.
        keep_q = [i for i in range(full.nq) if i != full.joints[full.getJointId("follower")].idx_q]
        keep_v = [i for i in range(full.nv) if i != full.joints[full.getJointId("follower")].idx_v]
        M_r = pin.crba(reduced, rdata, q[keep_q])
        M_r = np.triu(M_r) + np.triu(M_r, 1).T
        T_r = T[keep_v]
        M_full = pin.crba(full, data, q)
        M_full = np.triu(M_full) + np.triu(M_full, 1).T
        assert relative(T_r.T @ M_r @ T_r, T.T @ M_full @ T) < TOL     # Pinocchio agrees with the reduction
        assert relative(module.mass_matrix(0.0, x), T_r.T @ M_r @ T_r) < TOL
        rnea = pin.rnea(reduced, rdata, q[keep_q], v[keep_v], c[keep_v])
        damping = T.T @ np.diag(full.damping) @ v
        assert relative(-module.generalized_force(0.0, x) - damping, T_r.T @ rnea) < TOL


# -- a YAML model that starts from a URDF ---------------------------------------

def test_yaml_overrides_against_pinocchios_reduced_model(out_dir):
    """ur5 with wrist_3 locked at 0.4, wrist_2 at -a (a parameter), gravity g = 3 along -y and a 2 kg payload
    0.1 m along wrist_3_link's y: Pinocchio's buildReducedModel with the same gravity and appended body."""
    urdf = ROBOTS_DIR / ROBOTS["ur5"][0]
    source = out_dir / "ur5_payload.yaml"
    source.write_text(f"""name: ur5_payload
urdf:
  file: {urdf}
  lock: {{wrist_3_joint: 0.4, wrist_2_joint: "-a"}}
parameters: {{g: 3.0, a: 0.2}}
gravity: [0, "-g", 0]
frames:
  - {{name: payload_frame, parent: wrist_3_link, translation: [0, 0.1, 0]}}
bodies:
  - {{name: payload, frame: payload_frame, mass: 2.0, inertia: [0.01, 0.02, 0.03]}}
""")
    module, _ = build(source, out_dir)
    full = pin.buildModelFromUrdf(str(urdf))
    wrist3 = full.getJointId("wrist_3_joint")
    # wrist_3_link is wrist_3_joint's child body: append the payload to that joint, at the link frame.
    link = full.frames[full.getFrameId("wrist_3_link")]
    placement = link.placement * pin.SE3(np.eye(3), np.array([0, 0.1, 0]))
    full.appendBodyToJoint(wrist3, pin.Inertia(2.0, np.zeros(3), np.diag([0.01, 0.02, 0.03])), placement)
    q_ref = pin.neutral(full)
    q_ref[full.joints[wrist3].idx_q] = 0.4
    q_ref[full.joints[full.getJointId("wrist_2_joint")].idx_q] = -0.2
    model = pin.buildReducedModel(full, [wrist3, full.getJointId("wrist_2_joint")], q_ref)
    model.gravity.linear = np.array([0, -3.0, 0])
    assert list(module.COORDINATES) == [model.names[j] for j in range(1, model.njoints)]
    errors = compare(module, model, urdf, None, seed=7)
    print(f"\n[urdf] ur5 + YAML overrides: max relative error M {errors['M']:.1e}, bias {errors['bias']:.1e}, "
          f"aba {errors['aba']:.1e}")
    assert max(errors.values()) < TOL, errors
    # The comparison sees the payload: without it Pinocchio's M is far from andyc's.
    bare = pin.buildReducedModel(pin.buildModelFromUrdf(str(urdf)), [wrist3, full.getJointId("wrist_2_joint")], q_ref)
    bare.gravity.linear = np.array([0, -3.0, 0])
    assert compare(module, bare, urdf, None, seed=7)["M"] > 1e-3
