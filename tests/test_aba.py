"""Issue 27: the articulated-body algorithm derived symbolically (andyc/symbolic/aba.py), forced on in a build of
its own: its dv/dt (the leaf forward_dynamics, through the runtime's rhs) equals the dense path's M^-1 G from
the same build's M and G to 1e-12 at random states, and Pinocchio's aba (an independent implementation) to
1e-10, on a planar chain, a spatial chain with skew axes and full inertias, the double pendulum, a chain
with every kind of force element, and ur5 (solo12 on a floating base, where the counts choose it: in
tests/test_urdf_pinocchio.py); with links moved by shared speeds (aba_groups.py), a hand-written model with two
groups against the dense path, and panda's mimic fingers against it and Pinocchio's crba/rnea in andyc's speeds;
and the operation counts it is chosen from grow like the tree on a chain while M's assembly does not."""

from __future__ import annotations

import importlib
import sys

import numpy as np
import pytest

from andyc.pipeline import derive, generate, load
from andyc.runtime.compiled import load_compiled
from andyc.symbolic.formulation import ABA, DENSE, choose
from tests.support import MODELS, ROBOTS_DIR, ROOT

sys.path.insert(0, str(ROOT / "bench"))
large_models = importlib.import_module("large_models")

# Every element kind that enters G besides the bodies, on a spatial chain: a force and a torque on frames (in the
# world's and in a frame's axes), linear and quadratic dampers on a speed, a frame and an angular rate, a spring of
# a length and one between frames, a potential, an input.
ELEMENTS_YAML = """
name: aba_elements
parameters: {g: 9.81, beta: 0.3, k: 20.0}
inputs: {T: 0.7}
coordinates:
  q1: {initial: 0.2, velocity: 0.4}
  q2: {initial: -0.5}
  q3: {initial: 0.7, velocity: -0.3}
  s: {initial: 0.1}
gravity: [0, -g, 0]
frames:
  - {name: a, parent: world, revolute: q1, axis: z}
  - {name: a_end, parent: a, translation: [0.5, 0, 0]}
  - {name: b, parent: a_end, revolute: q2, axis: [0, 0.6, 0.8]}
  - {name: b_end, parent: b, translation: [0.4, 0.1, 0]}
  - {name: c, parent: b_end, rotation: {rpy: [0.3, 0.1, -0.2]}, revolute: q3, axis: x}
  - {name: d, parent: c, translation: [0, 0.2, 0], prismatic: s, axis: y}
  - {name: d_tip, parent: d, translation: [0.1, 0, 0.05]}
bodies:
  - {name: A, frame: a, mass: 2.0, com: [0.25, 0, 0], inertia: [0.01, 0.04, 0.04, 0.001, 0, 0]}
  - {name: B, frame: b, mass: 1.5, com: [0.2, 0.05, 0], inertia: [0.02, 0.03, 0.025, 0.002, 0.001, 0.0005]}
  - {name: C, frame: c, mass: 1.0, com: [0, 0.1, 0.02], inertia: [0.01, 0.005, 0.01, 0, 0.0003, 0]}
  - {name: D, frame: d, mass: 0.5, com: [0.05, 0, 0], inertia: [0.001, 0.002, 0.002, 0, 0, 0]}
forces:
  - {name: push, frame: d_tip, vector: [1.0, 0.5 * T, -0.2]}
  - {name: pull, frame: b_end, vector: [0, 0, 0.3], in: c}
torques:
  - {name: drive, frame: a, vector: [0, 0, T]}
  - {name: twist, frame: c, vector: [0.1, 0, 0.2], in: c}
dampers:
  - {name: hinge, coefficient: beta, speed: q2}
  - {name: slide, coefficient: beta, speed: s, law: quadratic}
  - {name: drag, coefficient: beta, frame: d_tip}
  - {name: spin, coefficient: beta, frame: c, angular: true}
springs:
  - {name: slider, stiffness: k, rest_length: 0.1, length: s}
  - {name: band, stiffness: k, rest_length: 0.3, between: [a_end, d_tip]}
potentials:
  - {name: well, energy: 0.5 * q1**2 + 0.1 * sin(q3)}
"""


# Links moved by shared speeds (aba_groups.py): a group {a, b, e} moved by q1 (b by 2 q1 about a skew axis, below a;
# e by -q1 on a second branch) hanging from the link `base`, with the link c (q2) below b; and a group of two speeds
# {f, h} (h by q4 + q5) hanging from `base` too (D 2 x 2: U D^-1 by its LDL^T), with k (q6) below it. A torque on
# b and a damper on q1 enter tau_g.
GROUPS_YAML = """
name: aba_groups
parameters: {g: 9.81, beta: 0.2}
coordinates:
  q0: {initial: 0.1, velocity: 0.3}
  q1: {initial: 0.3, velocity: 0.5}
  q2: {initial: -0.4, velocity: 0.2}
  q4: {initial: 0.2, velocity: -0.1}
  q5: {initial: -0.3, velocity: 0.4}
  q6: {initial: 0.5}
gravity: [0, -g, 0]
frames:
  - {name: base, parent: world, revolute: q0, axis: z}
  - {name: base_end, parent: base, translation: [0.4, 0, 0]}
  - {name: a, parent: base_end, revolute: q1, axis: z}
  - {name: a_end, parent: a, translation: [0.5, 0, 0]}
  - {name: b, parent: a_end, revolute: 2*q1, axis: [0, 0.6, 0.8]}
  - {name: b_end, parent: b, translation: [0.3, 0.1, 0]}
  - {name: c, parent: b_end, rotation: {rpy: [0.3, 0.1, -0.2]}, revolute: q2, axis: x}
  - {name: e, parent: base_end, translation: [0, 0.1, 0.2], revolute: -q1, axis: y}
  - {name: f, parent: base_end, translation: [0.2, 0, 0], revolute: q4, axis: x}
  - {name: f_end, parent: f, translation: [0, 0.4, 0.1]}
  - {name: h, parent: f_end, revolute: q4 + q5, axis: [0.6, 0, 0.8]}
  - {name: h_end, parent: h, translation: [0.3, 0, 0]}
  - {name: k, parent: h_end, prismatic: q6, axis: z}
bodies:
  - {name: Base, frame: base, mass: 3.0, com: [0.2, 0, 0], inertia: [0.02, 0.05, 0.05, 0, 0, 0]}
  - {name: A, frame: a, mass: 2.0, com: [0.25, 0, 0], inertia: [0.01, 0.04, 0.04, 0.001, 0, 0]}
  - {name: B, frame: b, mass: 1.5, com: [0.2, 0.05, 0], inertia: [0.02, 0.03, 0.025, 0.002, 0.001, 0.0005]}
  - {name: C, frame: c, mass: 1.0, com: [0, 0.1, 0.02], inertia: [0.01, 0.005, 0.01, 0, 0.0003, 0]}
  - {name: E, frame: e, mass: 0.7, com: [0.1, 0, 0.05], inertia: [0.003, 0.002, 0.004, 0, 0, 0.0002]}
  - {name: F, frame: f, mass: 1.2, com: [0, 0.2, 0], inertia: [0.01, 0.01, 0.02, 0, 0, 0]}
  - {name: H, frame: h, mass: 0.9, com: [0.15, 0, 0.02], inertia: [0.004, 0.006, 0.005, 0.0005, 0, 0]}
  - {name: K, frame: k, mass: 0.4, com: [0, 0.05, 0], inertia: [0.001, 0.001, 0.001, 0, 0, 0]}
torques:
  - {name: drive, frame: b, vector: [0.2, 0, 0.3], in: b}
dampers:
  - {name: hinge, coefficient: beta, speed: q1}
"""


def _aba_module(path, out_dir):
    """The model at `path` built with the articulated-body algorithm forced on (formulation.choose)."""
    model = derive(load(path))
    assert model.aba is not None, f"{path}: ABA does not apply"
    model.forward = choose(model.M, force=ABA, aba=model.aba, G=model.G, pool=dict(model.assignments))
    result = generate(model, out_dir, force=True)
    module = load_compiled(result.module_path).module
    assert module.FORMULATION == ABA and module.NB == module.NV
    return module


@pytest.fixture(scope="module")
def out(tmp_path_factory):
    return tmp_path_factory.mktemp("aba")


@pytest.fixture(scope="module")
def chain(out):
    path = out / "chain6.yaml"
    path.write_text(large_models.planar_chain_yaml(6))
    return _aba_module(path, out / "build")


def _random_states(module, rng, count=8):
    x0 = module.initial_state()
    nq, nv = module.NQ, module.NV
    for _ in range(count):
        x = x0.copy()
        x[:nq + nv] += rng.uniform(-1, 1, nq + nv)
        yield x


def _dense_equals_aba(module, seed):
    """Largest |ABA - M^-1 G| / max(1, |M^-1 G|) over random states, M and G from the same build."""
    worst = 0.0
    nq, nv = module.NQ, module.NV
    for x in _random_states(module, np.random.default_rng(seed)):
        dense = np.linalg.solve(module.mass_matrix(0.0, x), module.generalized_force(0.0, x))
        aba = module.rhs(0.0, x)[nq:nq + nv]
        worst = max(worst, np.abs(aba - dense).max() / max(1.0, np.abs(dense).max()))
    return worst


@pytest.mark.parametrize("name", ["double_pendulum", "chain3d"])
def test_shipped_models_aba_equals_dense(name, out):
    module = _aba_module(MODELS / f"{name}.yaml", out / "build")
    assert _dense_equals_aba(module, 1) <= 1e-12


def test_planar_chain_aba_equals_dense_and_pinocchio(chain):
    pin = pytest.importorskip("pinocchio")
    assert _dense_equals_aba(chain, 2) <= 1e-12
    pmodel = large_models.planar_chain_pinocchio(6)
    data = pmodel.createData()
    for x in _random_states(chain, np.random.default_rng(3)):
        a = chain.rhs(0.0, x)[6:]
        expected = pin.aba(pmodel, data, x[:6], x[6:], np.zeros(6))
        assert np.abs(a - expected).max() <= 1e-10 * np.abs(expected).max()


def test_every_force_element_enters_as_in_the_dense_path(out):
    """Forces, torques, dampers (linear, quadratic, on a speed, a frame, an angular rate), springs (a length, between
    frames), a potential and an input: tau of ABA is the G of every element other than a body."""
    path = out / "aba_elements.yaml"
    path.write_text(ELEMENTS_YAML)
    module = _aba_module(path, out / "build")
    assert _dense_equals_aba(module, 4) <= 1e-12
    x = module.initial_state()
    u = np.array([2.5])                              # an input other than its default
    dense = np.linalg.solve(module.mass_matrix(0.0, x, u=u), module.generalized_force(0.0, x, u=u))
    assert np.abs(module.rhs(0.0, x, u=u)[module.NQ:module.NQ + module.NV] - dense).max() <= 1e-12 * np.abs(dense).max()


@pytest.mark.parametrize("robot", ["ur5", "panda"])
def test_urdf_robots_aba_equals_dense_and_pinocchio(robot, out):
    """ABA forced on, against the dense path and Pinocchio. panda's second finger mimics the first: a group of two
    links moved by one speed (aba_groups.py), hanging from the hand, which makes ABA panda's choice by the counts.
    Pinocchio keeps a mimic joint as a joint of its own: as in tests/test_urdf_pinocchio.py, its crba and rnea are
    then projected on andyc's speeds (v_pin = T v) and solved there. (solo12 on its floating base gets ABA by the
    counts: tests/test_urdf_pinocchio.py checks it the same way.)"""
    pytest.importorskip("pinocchio")
    from tests.support.pinocchio_map import PINOCCHIO_ROBOTS as ROBOTS, PinocchioMap, relative, root_link

    import pinocchio as pin
    relpath, base = ROBOTS[robot]
    urdf = ROBOTS_DIR / relpath
    source = out / f"{robot}.yaml"
    source.write_text(f"urdf: {{file: {urdf}, base: {base}}}\n")
    if robot == "panda":
        assert derive(load(source)).forward.chosen == ABA
    module = _aba_module(source, out / "build")
    assert _dense_equals_aba(module, 5) <= 1e-12
    pmodel = pin.buildModelFromUrdf(str(urdf), *([pin.JointModelFreeFlyer()] if base == "floating" else []))
    mapping = PinocchioMap(module, pmodel, urdf, root_link(urdf) if base == "floating" else None)
    assert bool(mapping.mimic) == (robot == "panda")
    data, rng = pmodel.createData(), np.random.default_rng(6)
    for _ in range(10):
        x = mapping.random_state(rng)
        _, _, expected = mapping.expected(x, data, mimic_free=not mapping.mimic)
        assert relative(module.rhs(0.0, x)[module.NQ:module.NQ + module.NV], expected) <= 1e-10


def test_links_moved_by_shared_speeds_equal_dense(out):
    """Groups of links moved by shared speeds (aba_groups.py): one speed moving three links on two branches, with a
    link below the group, and two speeds moving two links (D 2 x 2), with a prismatic link below them."""
    from andyc.symbolic import aba_groups
    from andyc.symbolic.aba import _links

    path = out / "aba_groups.yaml"
    path.write_text(GROUPS_YAML)
    links = _links(load(path))
    groups = aba_groups.link_groups(links)
    assert sorted((len(g.members), len(g.speeds), g.parent) for g in groups) == [(2, 2, "base"), (3, 1, "base")]
    module = _aba_module(path, out / "build")
    assert _dense_equals_aba(module, 7) <= 1e-12


def test_groups_that_do_not_hang_from_one_link_keep_m(tmp_path):
    """A speed that moves links on two branches hanging from different links: no group step, no ABA."""
    path = tmp_path / "split.yaml"
    path.write_text(GROUPS_YAML.replace("{name: e, parent: base_end,", "{name: e, parent: world,"))
    model = derive(load(path))
    assert model.aba is None and model.forward.operations[ABA] is None


def test_aba_counts_grow_like_the_chain_and_constrained_models_keep_m(tmp_path):
    """ABA's count of dv/dt grows like n on a planar chain (its passes visit each link a fixed number of times), the
    dense path's (M's assembly and its factorization) faster; a model with constraint rows has no ABA."""
    counts = {}
    for n in (3, 4, 5):
        path = tmp_path / f"chain{n}.yaml"
        path.write_text(large_models.planar_chain_yaml(n))
        counts[n] = derive(load(path)).forward.operations
    step = [counts[n + 1][ABA] - counts[n][ABA] for n in (3, 4)]
    assert step[0] == step[1] > 0                   # the same work for each link added
    dense = [counts[n + 1][DENSE] - counts[n][DENSE] for n in (3, 4)]
    assert dense[1] > dense[0] > 0
    fourbar = derive(load(MODELS / "fourbar.yaml"))
    assert fourbar.aba is None and ABA not in fourbar.forward.operations
    assert "aba n/a (constraint rows" in fourbar.forward.describe()
