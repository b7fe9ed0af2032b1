"""Linearization (andyc.symbolic.linearize, `andyc linearize`): A and B from exact derivatives.

Checked against closed forms (the double pendulum's small-oscillation
frequencies, the cart-pole's A and B derived by hand below), against central
differences of the generated right-hand side at states away from equilibrium,
and through the command line.
"""

import numpy as np
import pytest

import andyc
from andyc.symbolic.linearize import LinearizeError, default_point, find_equilibrium, linearize
from tests.support import MODELS
from tests.support.cli import invoke


def derived(name):
    return andyc.derive(andyc.load(MODELS / f"{name}.yaml"))


def test_double_pendulum_frequencies_equal_the_closed_form():
    """Point masses m1, m2 on links L1, L2 hanging at rest: with M0 = [[(m1+m2) L1^2, m2 L1 L2], [m2 L1 L2,
    m2 L2^2]] and K = diag((m1+m2) g L1, m2 g L2) (absolute angles), det(K - w^2 M0) = 0 is the quadratic
    (ac - b^2) w^4 - (k1 c + k2 a) w^2 + k1 k2 = 0. The eigenvalues of A are +-i w (relative angles give
    the same frequencies)."""
    model = derived("double_pendulum")
    x, u, p, d = default_point(model)
    L1, L2, m1, m2, g = p
    lin = linearize(model, np.zeros(4), u, p, d)
    a, b, c = (m1 + m2) * L1**2, m2 * L1 * L2, m2 * L2**2
    k1, k2 = (m1 + m2) * g * L1, m2 * g * L2
    qa, qb, qc = a * c - b * b, -(k1 * c + k2 * a), k1 * k2
    w2 = (-qb + np.array([-1.0, 1.0]) * np.sqrt(qb * qb - 4 * qa * qc)) / (2 * qa)
    expected = np.sort(np.concatenate([np.sqrt(w2), -np.sqrt(w2)]))
    ev = lin.eigenvalues
    assert np.abs(ev.real).max() < 1e-12
    np.testing.assert_allclose(np.sort(ev.imag), expected, rtol=1e-10, atol=0)


def test_cart_pole_A_and_B_equal_the_hand_derivation():
    """models/cart_pole.yaml, th from the upright, pole COM at (x - l sin th, l cos th), rod inertia J_c = m l^2/3:
    M = [[mc + m, -m l cos th], [-m l cos th, J]], J = 4/3 m l^2; V = m g l cos th; the force F acts on x.
    At th = 0: [x'', th''] = M0^-1 [F, m g l th], M0^-1 = [[J, m l], [m l, mc + m]] / det, det = (mc + m) J - m^2 l^2."""
    model = derived("cart_pole")
    x, u, p, d = default_point(model)
    mc, m, l, g = p
    lin = linearize(model, np.zeros(4), [0.0], p, d)
    J = 4 / 3 * m * l * l
    det = (mc + m) * J - (m * l) ** 2
    A = np.zeros((4, 4))
    A[0, 2] = A[1, 3] = 1.0
    A[2, 1] = m * l * m * g * l / det
    A[3, 1] = (mc + m) * m * g * l / det
    B = np.array([[0.0], [0.0], [J / det], [m * l / det]])
    np.testing.assert_allclose(lin.A, A, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(lin.B, B, rtol=1e-13, atol=1e-13)
    assert lin.state_names == ["x", "th", "x_dot", "th_dot"] and lin.input_names == ["F"]


@pytest.mark.parametrize("name", ["cart_pole", "chain3d"])
def test_away_from_equilibrium_A_and_B_equal_central_differences_of_the_generated_rhs(name, compiled):
    """At random states with nonzero speeds (where dM/dq a and the velocity terms count), A and B equal
    central differences of the generated module's rhs to the differences' own accuracy."""
    model = derived(name)
    module = compiled(name).module
    _, u, p, d = default_point(model)
    n = len(model.q)
    rng = np.random.default_rng(3)
    for _ in range(3):
        x = np.concatenate([rng.uniform(-1.5, 1.5, n), rng.uniform(-2, 2, n)])
        u = rng.uniform(-1, 1, len(u))
        lin = linearize(model, x, u, p, d, t=0.0)
        h = 1e-6
        fd_A = np.column_stack([(module.rhs(0.0, x + h * e, u, p, d) - module.rhs(0.0, x - h * e, u, p, d)) / (2 * h)
                                for e in np.eye(2 * n)])
        np.testing.assert_allclose(lin.A, fd_A, rtol=1e-6, atol=1e-6 * np.abs(fd_A).max())
        if len(u):
            fd_B = np.column_stack([(module.rhs(0.0, x, u + h * e, p, d) - module.rhs(0.0, x, u - h * e, p, d))
                                    / (2 * h) for e in np.eye(len(u))])
            np.testing.assert_allclose(lin.B, fd_B, rtol=1e-6, atol=1e-8)


def test_find_equilibrium_reaches_the_rest_points():
    """The double pendulum from a guess off rest returns to hanging (0, 0); the cart-pole's pole from near the
    bottom finds th = pi, where the linearization has two pairs of imaginary eigenvalues and no unstable one."""
    model = derived("double_pendulum")
    _, u, p, d = default_point(model)
    np.testing.assert_allclose(find_equilibrium(model, [0.4, -0.3], u, p, d), [0.0, 0.0], atol=1e-12)
    model = derived("cart_pole")
    _, u, p, d = default_point(model)
    q = find_equilibrium(model, [0.2, 2.9], u, p, d)
    assert abs(q[1] - np.pi) < 1e-12
    lin = linearize(model, np.concatenate([q, [0.0, 0.0]]), u, p, d)
    assert np.all(lin.eigenvalues.real < 1e-9)


def test_cli_prints_and_writes_the_linearization(tmp_path):
    result = invoke("linearize", str(MODELS / "cart_pole.yaml"), "--at", "th=0",
                    "--set", "mc=2", "--input", "F=1.5", "-o", str(tmp_path))
    assert result.exit_code == 0, result.output
    assert "1 eigenvalue with positive real part (unstable)" in result.output
    saved = np.load(tmp_path / "cart_pole_linearization.npz")
    assert list(saved["u"]) == [1.5]
    m, l, g, mc = 0.1, 0.5, 9.81, 2.0
    J = 4 / 3 * m * l * l
    assert saved["A"][3, 1] == pytest.approx((mc + m) * m * g * l / ((mc + m) * J - (m * l) ** 2), rel=1e-13)
    assert list(saved["state_names"]) == ["x", "th", "x_dot", "th_dot"]
    np.testing.assert_array_equal(np.loadtxt(tmp_path / "cart_pole_B.csv", delimiter=",", skiprows=1), saved["B"][:, 0])


@pytest.mark.parametrize("args, message", [
    (["passive_walker", "--flow", "IFixOOpen"], "flow 'IFixOOpen' is constrained and moves, so it is linearized "
                                                "about a steady motion, where every coordinate that moves is cyclic"),
    (["fourbar", "--at", "th1_dot=0", "--at", "th2_dot=0", "--at", "th3_dot=0", "--at", "th2=1"],
     "the point is off flow 'default''s constraint manifold (largest residual"),
    (["cart_pole", "--at", "phi=0"], "no coordinate or speed named 'phi' (--at); states: x, th, x_dot, th_dot"),
    (["cart_pole", "--flow", "walk"], "no flow named 'walk'; flows: default"),
    (["cart_pole", "--set", "mass=3"], "no parameter named mass; parameters: mc, m, l, g"),
    (["cart_pole", "--input", "G=1"], "no input named G (--input); inputs: F"),
    (["swing_bar"], "also has signals"),
])
def test_cli_errors_say_what_and_how(args, message):
    result = invoke("linearize", str(MODELS / f"{args[0]}.yaml"), *args[1:])
    assert result.exit_code == 1
    assert message in result.output, result.output
    assert "Traceback" not in result.output


def test_no_equilibrium_is_an_error():
    """A cart pushed by a constant force never rests."""
    model = derived("cart_pole")
    _, u, p, d = default_point(model, inputs={"F": 1.0})
    with pytest.raises(LinearizeError, match="no equilibrium found near"):
        find_equilibrium(model, [0.0, 0.1], u, p, d)


def test_cli_a_malformed_at_names_the_option():
    result = invoke("linearize", str(MODELS / "cart_pole.yaml"), "--at", "th")
    assert result.exit_code == 2
    assert "'th' is not NAME=NUMBER" in result.output and "--at" in result.output


# The double pendulum again, its lower mass a free point (x, y) held at L2 from the elbow by a
# holonomic constraint: 3 coordinates, 1 row, the same two modes.
CARTESIAN = """\
name: double_pendulum_cartesian
parameters: {L1: 1.0, L2: 0.8, m1: 1.0, m2: 0.5, g: 9.81}
coordinates:
  q1: {}
  x: {}
  y: {initial: -L1 - L2}
gravity: [0, -g, 0]
frames:
  - {name: upper, parent: world, revolute: q1}
  - {name: elbow, parent: upper, translation: [0, -L1, 0]}
  - {name: slide_x, parent: world, prismatic: x, axis: x}
  - {name: point, parent: slide_x, prismatic: y, axis: y}
bodies:
  - {name: mass1, frame: elbow, mass: m1}
  - {name: mass2, frame: point, mass: m2}
constraints:
  - name: rod
    holonomic: (point.x - elbow.x)**2 + (point.y - elbow.y)**2 - L2**2
"""


def test_a_constrained_flow_in_null_space_form_has_the_mechanisms_frequencies(tmp_path):
    """At the hanging rest point the null-space form of the constrained model has the double
    pendulum's closed-form frequencies, with orthonormal bases of the row's null space."""
    (tmp_path / "dp.yaml").write_text(CARTESIAN)
    model = andyc.derive(andyc.load(tmp_path / "dp.yaml"))
    x, u, p, d = default_point(model)
    lin = linearize(model, x, u, p, d)
    free = linearize(derived("double_pendulum"), np.zeros(4), [], p, d)
    assert lin.form == "null-space" and lin.basis_q.shape == (3, 2) and lin.basis_v.shape == (3, 2)
    np.testing.assert_allclose(lin.basis_q.T @ lin.basis_q, np.eye(2), atol=1e-14)
    np.testing.assert_allclose(np.sort(lin.eigenvalues.imag), np.sort(free.eigenvalues.imag), rtol=1e-10, atol=0)
    assert np.abs(lin.eigenvalues.real).max() < 1e-10
    assert lin.state_names == ["z1", "z2", "z1_dot", "z2_dot"]


def test_the_fourbar_at_rest_swings_at_its_closed_form_frequency():
    """Parallelogram four-bar hanging at rest (cranks down, coupler level): the coupler translates, so
    T = (I1 + I3 + m2 a^2) th'^2 / 2 with I = m a^2 / 3 and V = -(m1/2 + m3/2 + m2) g a cos th:
    w^2 = g (m1/2 + m3/2 + m2) / (a (m1/3 + m3/3 + m2)). Two closure rows leave one degree of freedom."""
    model = derived("fourbar")
    x, u, p, d = default_point(model)
    x[3:] = 0.0
    lin = linearize(model, x, u, p, d)
    a, dd, m1, m2, m3, g = p[:6]
    w = np.sqrt(g * (m1 / 2 + m3 / 2 + m2) / (a * (m1 / 3 + m3 / 3 + m2)))
    assert lin.A.shape == (2, 2)
    np.testing.assert_allclose(np.sort(lin.eigenvalues.imag), [-w, w], rtol=1e-10)


def test_cli_prints_the_null_space_bases_of_a_constrained_flow(tmp_path):
    args = ["linearize", str(MODELS / "fourbar.yaml"), "-o", str(tmp_path)] + [
        item for name in ("th1_dot", "th2_dot", "th3_dot") for item in ("--at", f"{name}=0")]
    result = invoke(*args)
    assert result.exit_code == 0, result.output
    assert "null-space form, dq = N_q z, dv = N_v w" in result.output
    saved = np.load(tmp_path / "fourbar_linearization.npz")
    assert str(saved["form"]) == "null-space" and saved["N_q"].shape == (3, 1)


SLOPED_LINE = """\
name: puck_on_a_line
parameters: {m: 2.0}
inputs:
  F: 0
coordinates:
  x: {}
  y: {}
frames:
  - {name: slide_x, parent: world, prismatic: x, axis: x}
  - {name: puck, parent: slide_x, prismatic: y, axis: y}
bodies:
  - {name: puck_mass, frame: puck, mass: m}
forces:
  - {name: push, frame: puck, vector: [F, 0, 0]}
constraints:
  - {name: on_line, holonomic: x - y}
"""


def test_a_constrained_flows_B_is_the_force_projected_on_the_line(tmp_path):
    """A puck of mass m held on the line x = y, pushed along x by F: along the line's unit direction b (the
    null-space basis, b = +-(1, 1)/sqrt 2) the speed w = b . v obeys m w' = b . (F, 0), by hand; so
    B = [0, b_x / m] and A has only the kinematic 1."""
    (tmp_path / "puck.yaml").write_text(SLOPED_LINE)
    model = andyc.derive(andyc.load(tmp_path / "puck.yaml"))
    x, u, p, d = default_point(model)
    lin = linearize(model, x, u, p, d)
    b = lin.basis_v[:, 0]
    assert lin.form == "null-space" and abs(abs(b[0]) - 1 / np.sqrt(2)) < 1e-14 and abs(b[0] - b[1]) < 1e-14
    np.testing.assert_allclose(lin.B[:, 0], [0.0, b[0] / 2.0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(lin.A, [[0.0, 1.0], [0.0, 0.0]], atol=1e-14)
