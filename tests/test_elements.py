"""Generalized-force elements (ANDY Table 1, eq. 7) against hand derivations.

Loads: a pendulum of length L about z, angle th from +x, carries an input
torque tau about world z and, at its tip, a force F written in the link frame
(components along the link and across it) and a force P along world x:
    G = tau + L F_across - L sin(th) P - m g L cos(th),  M = m L^2.
Conservative elements: with no gravity and v = 0, G(q) = -dV/dq, where V is the
generated energy function (differenced numerically here).
"""

import textwrap

import numpy as np
import pytest

import andyc
from tests.support import MODELS

PENDULUM = textwrap.dedent("""\
    name: loaded_pendulum
    parameters: {L: 0.7, m: 1.3, g: 9.81}
    inputs: {tau: 0.4, F_along: 2.0, F_across: -1.5, P: 3.0}
    coordinates:
      th: {initial: 0.3}
    gravity: [0, -g, 0]
    frames:
      - {name: link, parent: world, revolute: th}
      - {name: tip, parent: link, translation: [L, 0, 0]}
    bodies:
      - {name: bob, frame: tip, mass: m}
    torques:
      - {name: motor, frame: link, vector: [0, 0, tau]}
    forces:
      - {name: pull, frame: link, point: [L, 0, 0], vector: [F_along, F_across, 0], in: link}
      - {name: push, frame: tip, vector: [P, 0, 0]}
    """)

SPRINGS = textwrap.dedent("""\
    name: sprung_arm
    parameters: {k1: 40.0, k2: 15.0, c: 2.5}
    coordinates:
      a: {initial: 0.2}
      s: {initial: 0.1}
    frames:
      - {name: arm, parent: world, revolute: a, axis: y}
      - {name: slider, parent: arm, translation: [0.3, 0, 0], prismatic: s, axis: x}
      - {name: anchor, parent: world, translation: [0.2, 0.5, -0.4]}
    bodies:
      - {name: carriage, frame: slider, mass: 0.8, inertia: [0.01, 0.02, 0.03]}
      - {name: beam, frame: arm, mass: 2.0, com: [0.15, 0, 0], inertia: [0.001, 0.02, 0.02]}
    springs:
      - {name: cable, stiffness: k1, rest_length: 0.3, between: [slider, anchor]}
      - {name: return_spring, stiffness: k2, rest_length: 0.05, length: "s + 0.1*sin(a)"}
    potentials:
      - {name: cam, energy: "c*(1 - cos(2*a))*s**2"}
    """)


def test_forces_and_torques_give_the_hand_derived_G(tmp_path, build_dir):
    path = tmp_path / "loaded.yaml"
    path.write_text(PENDULUM)
    model = andyc.compile_model(path, build_dir)[0]
    L, m, g = 0.7, 1.3, 9.81
    rng = np.random.default_rng(3)
    for _ in range(10):
        th, w = rng.uniform(-3, 3, 2)
        tau, F_along, F_across, P = rng.normal(size=4)
        u = model.inputs({"tau": tau, "F_along": F_along, "F_across": F_across, "P": P})
        x = np.array([th, w])
        G = model.module.generalized_force(0.0, x, u, model.parameter_defaults)
        M = model.module.mass_matrix(0.0, x, u, model.parameter_defaults)
        assert M[0, 0] == pytest.approx(m * L**2, rel=1e-14)
        expected = tau + L * F_across - L * np.sin(th) * P - m * g * L * np.cos(th)
        assert G[0] == pytest.approx(expected, rel=1e-12, abs=1e-12)
        # power of the loads = G_loads . v (gravity is in the energy, not the power)
        assert model.module.power(0.0, x, u, model.parameter_defaults, model.module.DISCRETE_DEFAULTS) == pytest.approx(
            (expected + m * g * L * np.cos(th)) * w, rel=1e-12, abs=1e-12)


def test_springs_and_potentials_are_minus_the_gradient_of_their_energy(tmp_path, build_dir):
    path = tmp_path / "sprung.yaml"
    path.write_text(SPRINGS)
    model = andyc.compile_model(path, build_dir)[0]
    p, u = model.parameter_defaults, model.input_defaults
    rng = np.random.default_rng(4)
    h = 1e-6
    for _ in range(10):
        q = rng.uniform(-1, 1, 2)
        x = np.concatenate([q, [0.0, 0.0]])
        G = model.module.generalized_force(0.0, x, u, p)
        d = model.module.DISCRETE_DEFAULTS
        grad = np.zeros(2)
        for j in range(2):
            e = np.zeros(4)
            e[j] = h
            grad[j] = (model.module.energy(0.0, x + e, u, p, d) - model.module.energy(0.0, x - e, u, p, d)) / (2 * h)
        assert np.allclose(G, -grad, rtol=1e-7, atol=1e-7)
        assert np.linalg.norm(G) > 1e-3          # the springs do push here


def test_per_element_terms_sum_to_the_grouped_assembly():
    """The assembly adds elements that share a Jacobian before multiplying (a body and
    the damper at its COM, two bars of one rigid body); each element's own M and G
    must still add up to the same equations."""
    import sympy as sp

    sym = andyc.derive(andyc.load(MODELS / "swing_bar.yaml"))
    n = sym.dof
    M = sum((e.M for e in sym.elements if e.M is not None), sp.zeros(n, n))
    G = sum((e.G for e in sym.elements if e.G is not None), sp.zeros(n, 1))
    rng = np.random.default_rng(3)
    values = {s: float(rng.uniform(-1, 1)) for s in sym.q + sym.v + sym.signals + sym.parameters}
    for s, e in sym.assignments:      # in dependency order
        values[s] = float(e.subs(values))
    for a, b in ((M, sym.M), (G, sym.G)):
        diff = np.array((a - b).subs(values), dtype=float)
        scale = np.abs(np.array(b.subs(values), dtype=float)).max()
        assert np.abs(diff).max() < 1e-12 * scale
