"""andyc's M(q) and G(q, v) against an independent KanesMethod derivation.

Random serial chains (andyc.independent.chains) are written as andyc YAML,
compiled into pytest's tmp_path, and compared at random states with
sympy.physics.mechanics.KanesMethod (M du/dt = forcing, u = dq/dt), which is
andyc's convention M dv/dt = G. Two closed-form systems pin the reference
itself (and andyc) to the textbook signs.
"""

from __future__ import annotations

import ast
import math
from pathlib import Path

import numpy as np
import pytest

import andyc
from andyc.independent import chains, kane
from andyc.independent.chains import Chain, Link, chain_yaml, random_chain
from andyc.independent.kane import kane_model

RTOL = 1e-10
TINY = 1e-300
N_STATES = 20

# (n_bodies, kind, joints, seed): every n from 1 to 6, every kind x joint form,
# within about a minute and a half on 2 cores. KanesMethod takes minutes on a
# 6-body 3-D chain with skew axes, so n = 6 is one planar and one 3-D DH chain.
CASES = [
    (1, "planar", "axis", 0),
    (1, "3d", "dh", 0),
    (2, "planar", "dh", 0),
    (2, "3d", "axis", 0),
    (3, "3d", "axis", 1),
    (3, "planar", "dh", 1),
    (4, "planar", "axis", 0),
    (5, "3d", "axis", 0),
    (6, "planar", "axis", 0),
    (6, "3d", "dh", 0),
]


def _compile(chain: Chain, tmp_path: Path):
    path = tmp_path / f"{chain.name}.yaml"
    path.write_text(chain_yaml(chain))
    model, _ = andyc.compile_model(path, tmp_path / "build", force=True)
    return model


def _andyc_MG(model, q, v):
    x = np.concatenate([q, v]).astype(float)
    u, p = model.input_defaults, model.parameter_defaults
    return (np.array(model.module.mass_matrix(0.0, x, u, p)),
            np.array(model.module.generalized_force(0.0, x, u, p)))


def _rel(a, b) -> float:
    return float(np.linalg.norm(a - b) / max(np.linalg.norm(b), TINY))


def _states(n, seed):
    rng = np.random.default_rng(seed)
    return [(rng.uniform(-math.pi, math.pi, n), rng.uniform(-2.0, 2.0, n)) for _ in range(N_STATES)]


@pytest.mark.parametrize("n, kind, joints, seed", CASES, ids=[f"{k}-{j}-n{n}-s{s}" for n, k, j, s in CASES])
def test_matches_kane(n, kind, joints, seed, tmp_path):
    chain = random_chain(n, kind, joints, seed)
    reference = kane_model(chain)
    model = _compile(chain, tmp_path)
    assert model.nq == model.nv == n
    assert list(model.parameter_names) == list(chain.parameters)
    np.testing.assert_array_equal(model.parameter_defaults, reference.param_values)

    worst_M = worst_G = 0.0
    for q, v in _states(n, seed + 1000 * n):
        M_ref, G_ref = reference.M(q, v), reference.forcing(q, v)
        M, G = _andyc_MG(model, q, v)
        # Guard against vacuous agreement (zeros vs zeros) and convention slips.
        assert np.linalg.norm(G_ref) > 1e-3, "the reference forcing vanished: gravity or speeds lost"
        assert np.linalg.norm(G) > 1e-3, "andyc's G vanished with gravity and nonzero speeds"
        np.testing.assert_allclose(M_ref, M_ref.T, rtol=0, atol=1e-12 * np.linalg.norm(M_ref))
        assert np.linalg.eigvalsh(M_ref).min() > 0
        worst_M = max(worst_M, _rel(M, M_ref))
        worst_G = max(worst_G, _rel(G, G_ref))
    print(f"{chain.name}: max rel err M {worst_M:.2e}, G {worst_G:.2e}; "
          f"Kane derive {reference.derive_seconds:.2f} s")
    assert worst_M <= RTOL, f"M differs from KanesMethod: relative error {worst_M:.3e}"
    assert worst_G <= RTOL, f"G differs from KanesMethod: relative error {worst_G:.3e}"

    # G holds gravity plus terms quadratic in the speeds: G(q, 2v) - G(q, 0) = 4 (G(q, v) - G(q, 0)).
    q, v = _states(n, seed)[0]
    G0, G1, G2 = (_andyc_MG(model, q, s * v)[1] for s in (0.0, 1.0, 2.0))
    np.testing.assert_allclose(G2 - G0, 4 * (G1 - G0), rtol=1e-9, atol=1e-9 * np.linalg.norm(G1))


# -- closed forms: the reference and andyc against the textbook ----------------------------

def _point_mass_link(index, translation, com, mass):
    return Link(index=index, joint="revolute", translation=translation, rotation=None, axis="z", dh=None,
                tool=None, mass=mass, com=com, inertia=((0.0, 0.0, 0.0),) * 3, inertia_form="6",
                initial=0.0, velocity=0.0)


def test_double_pendulum_closed_form(tmp_path):
    """Point masses m1, m2 on massless links L1, L2; angles from the downward vertical.

    M = [[(m1 + m2) L1^2 + m2 L2^2 + 2 m2 L1 L2 c2, m2 L2^2 + m2 L1 L2 c2], [., m2 L2^2]],
    G = [h (2 v1 v2 + v2^2) - (m1 + m2) g L1 s1 - m2 g L2 s12, -h v1^2 - m2 g L2 s12],
    h = m2 L1 L2 sin(q2).
    """
    L1, L2, m1, m2, g = 0.7, 0.45, 1.3, 0.8, 9.81
    links = (_point_mass_link(1, None, (0.0, -L1, 0.0), m1),
             _point_mass_link(2, (0.0, -L1, 0.0), (0.0, -L2, 0.0), m2))
    chain = Chain(name="closed_double_pendulum", kind="planar", joints="axis", seed=0, links=links,
                  gravity=(0.0, -1.0, 0.0), g=g)
    reference = kane_model(chain)
    model = _compile(chain, tmp_path)
    for q, v in _states(2, 7)[:5]:
        c2, h = math.cos(q[1]), m2 * L1 * L2 * math.sin(q[1])
        s1, s12 = math.sin(q[0]), math.sin(q[0] + q[1])
        M_exact = np.array([[(m1 + m2) * L1**2 + m2 * L2**2 + 2 * m2 * L1 * L2 * c2, m2 * L2**2 + m2 * L1 * L2 * c2],
                            [m2 * L2**2 + m2 * L1 * L2 * c2, m2 * L2**2]])
        G_exact = np.array([h * (2 * v[0] * v[1] + v[1]**2) - (m1 + m2) * g * L1 * s1 - m2 * g * L2 * s12,
                            -h * v[0]**2 - m2 * g * L2 * s12])
        M, G = _andyc_MG(model, q, v)
        for name, value, exact in (("Kane M", reference.M(q, v), M_exact), ("Kane G", reference.forcing(q, v), G_exact),
                                   ("andyc M", M, M_exact), ("andyc G", G, G_exact)):
            assert _rel(value, exact) <= 1e-12, f"{name} = {value}, closed form {exact}"


def test_pendulum_closed_form(tmp_path):
    """A rigid pendulum about a non-unit z axis, COM at (a, b, 0), inertia Izz about the COM.

    M = m (a^2 + b^2) + Izz; with gravity -g y the COM height is y = a sin q + b cos q,
    so G = -dV/dq = -m g (a cos q - b sin q).
    """
    a, b, m, Izz, g = 0.3, -0.5, 2.0, 0.04, 9.81
    link = Link(index=1, joint="revolute", translation=None, rotation=None, axis=(0.0, 0.0, 3.0), dh=None, tool=None,
                mass=m, com=(a, b, 0.0), inertia=((0.05, 0.0, 0.0), (0.0, 0.03, 0.0), (0.0, 0.0, Izz)),
                inertia_form="3x3", initial=0.0, velocity=0.0)
    chain = Chain(name="closed_pendulum", kind="planar", joints="axis", seed=0, links=(link,),
                  gravity=(0.0, -1.0, 0.0), g=g)
    reference = kane_model(chain)
    model = _compile(chain, tmp_path)
    for q, v in _states(1, 3)[:5]:
        M_exact = np.array([[m * (a * a + b * b) + Izz]])
        G_exact = np.array([-m * g * (a * math.cos(q[0]) - b * math.sin(q[0]))])   # -dV/dq, V = m g (a sin q + b cos q)
        M, G = _andyc_MG(model, q, v)
        for name, value, exact in (("Kane M", reference.M(q, v), M_exact), ("Kane G", reference.forcing(q, v), G_exact),
                                   ("andyc M", M, M_exact), ("andyc G", G, G_exact)):
            assert _rel(value, exact) <= 1e-12, f"{name} = {value}, closed form {exact}"


# -- the generator ---------------------------------------------------------------------------

def test_random_chain_is_reproducible_and_valid():
    for kind in ("planar", "3d"):
        for joints in ("axis", "dh"):
            a, b = random_chain(4, kind, joints, 5), random_chain(4, kind, joints, 5)
            assert chain_yaml(a) == chain_yaml(b)
            assert chain_yaml(a) != chain_yaml(random_chain(4, kind, joints, 6))
            for link in a.links:
                eig = np.linalg.eigvalsh(np.array(link.inertia))
                assert eig.min() > 0 and all(eig[i] + eig[j] > eig[k] for i, j, k in ((0, 1, 2), (0, 2, 1), (1, 2, 0)))
                if kind == "planar":
                    assert link.com[2] == 0.0 and (link.translation is None or link.translation[2] == 0.0)
            if kind == "3d":
                assert {link.joint for link in a.links} == {"revolute", "prismatic"}


def test_generated_yaml_loads(tmp_path):
    for kind in ("planar", "3d"):
        for joints in ("axis", "dh"):
            chain = random_chain(6, kind, joints, 11)
            path = tmp_path / f"{chain.name}.yaml"
            path.write_text(chain_yaml(chain))
            spec = andyc.load(path)
            assert [c.name for c in spec.coordinates] == list(chain.coordinates)
            assert not spec.warnings


def test_reference_is_independent_of_andyc_stages():
    for module in (chains, kane):
        tree = ast.parse(Path(module.__file__).read_text())
        imported = {alias.name for node in ast.walk(tree) if isinstance(node, ast.Import) for alias in node.names}
        imported |= {node.module or "" for node in ast.walk(tree) if isinstance(node, ast.ImportFrom)}
        assert not any(name.startswith("andyc") and not name.startswith("andyc.independent")
                       for name in imported), (module.__name__, imported)
