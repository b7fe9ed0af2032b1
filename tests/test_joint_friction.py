"""Joint dry friction (a damper of law coulomb; a URDF's <dynamics friction>), applied by the moreau method as a
bounded row of each step's contact problem (andyc.numerics.contact_solver, BOUNDED), against closed forms: a
wheel spun down at the constant rate F / I, a pendulum whose swings end where friction holds it (the turning
angles from the energy balance, solved by scipy's brentq), the work of friction in the energy balance, the
bounded problem itself against scipy's bound-constrained minimization, and the refusals."""

import math

import numpy as np
import pytest
from scipy.optimize import brentq, minimize

import andyc
from andyc.errors import SimulationError, SpecError
from andyc.numerics import contact_solver as cs
from tests.support import MODELS
from tests.support.cli import invoke

WHEEL = """\
name: wheel_friction
description: A disc spinning about a vertical axis, slowed by its bearing's dry friction F.
parameters: {I: 0.5, F: 0.2, w0: 3.0}
coordinates:
  theta: {initial: 0, velocity: w0}
gravity: [0, 0, -9.81]
frames:
  - {name: disc, parent: world, revolute: theta, axis: z}
bodies:
  - {name: d, frame: disc, mass: 1, inertia: [I, I, I]}
dampers:
  - {name: bearing, speed: theta, coefficient: F, law: coulomb}
"""

PENDULUM = """\
name: pendulum_friction
description: A point mass on a massless rod (angle phi from hanging down), its pivot's dry friction F.
parameters: {m: 1.0, L: 1.0, g: 9.81, F: 2.943, phi0: 1.0}
coordinates:
  phi: {initial: phi0}
gravity: [0, -g, 0]
frames:
  - {name: rod, parent: world, revolute: phi, axis: z}
  - {name: bob, parent: rod, translation: [0, -L, 0]}
bodies:
  - {name: mass, frame: bob, mass: m}
dampers:
  - {name: pivot, speed: phi, coefficient: F, law: coulomb}
"""
H = 1e-3


@pytest.fixture(scope="module")
def wheel(compiled_text):
    return compiled_text("wheel_friction", WHEEL)


@pytest.fixture(scope="module")
def pendulum(compiled_text):
    return compiled_text("pendulum_friction", PENDULUM)


def test_wheel_spins_down_at_f_over_i_and_stays(wheel):
    """w(t) = w0 - F t / I until t* = I w0 / F = 7.5 s, then 0 for good: the scheme is exact in the speed (a
    constant torque), and theta(t) = w0 t - F t^2 / (2 I) to the trapezoid's error of the stopping step,
    F h^2 / (2 I). The friction's work slot holds -(F (theta)) = E - E0 to rounding."""
    I, F, w0 = 0.5, 0.2, 3.0
    run = andyc.simulate(wheel, 10.0, dt=H, method="moreau")
    assert run.finished
    t, w, th = run.time, run.column("theta_dot"), run.column("theta")
    stop = I * w0 / F
    sliding = t < stop - H
    assert np.max(np.abs(w[sliding] - (w0 - F * t[sliding] / I))) <= 1e-12
    assert np.max(np.abs(w[t > stop + H])) <= 1e-20         # (the stuck row's creep, COMPLIANCE: 4e-22 at once)
    assert np.max(np.abs(th[sliding] - (w0 * t[sliding] - F * t[sliding] ** 2 / (2 * I)))) <= 1e-9
    assert abs(th[-1] - I * w0 ** 2 / (2 * F)) <= F * H ** 2 / (2 * I) + 1e-12
    work = run.work[:, run.work_names.index("bearing")]
    assert np.max(np.abs(work + F * th)) <= 1e-10
    energy = 0.5 * I * w ** 2
    assert np.max(np.abs(energy - energy[0] - work)) <= 1e-10


def _turning_angles(m, L, g, F, phi0):
    """The angles where the pendulum's swings end, from rest at phi0, by the energy balance of each swing,
    m g L (cos a - cos b) = F |a - b| (b the next turning angle), until friction holds it: m g L |sin b| <= F."""
    angles, k = [phi0], m * g * L
    while k * abs(math.sin(angles[-1])) > F:
        a = angles[-1]
        s = -math.copysign(1.0, a)                   # it swings toward the other side
        f = lambda b: k * (math.cos(b) - math.cos(a)) - F * abs(a - b)      # noqa: E731
        angles.append(brentq(f, a + s * 1e-9, -a))  # (its energy ends before the mirror angle)
    return angles


def test_pendulum_swings_end_where_the_energy_balance_says_and_friction_holds_it(pendulum):
    """Released at 1 rad with F = 0.3 m g L: each swing ends where m g L (cos a - cos b) = F |a - b| (brentq), and
    it stops for good at the first such angle where m g L |sin b| <= F; at dt = 1e-4 every turning angle within
    1e-3 rad, then at rest (speed below 1e-8 rad/s: the stuck row's creep); E - E0 - W (W the friction's work, 4.16 J) within 1e-7 J, the
    scheme's own error in gravity's work (second order: 4e-8 J at this step)."""
    angles = _turning_angles(1.0, 1.0, 9.81, 2.943, 1.0)
    assert len(angles) >= 3                         # (at least two swings before it sticks)
    run = andyc.simulate(pendulum, 6.0, dt=1e-4, method="moreau")
    phi, w = run.column("phi"), run.column("phi_dot")
    moving = np.abs(w) > 1e-6
    stops = [phi[0]] + [phi[i + 1] for i in range(len(w) - 1)
                        if moving[i] and (w[i] * w[i + 1] < 0.0 or not moving[i + 1])]
    assert len(stops) == len(angles)
    assert np.max(np.abs(np.array(stops) - angles)) <= 1e-3
    assert np.max(np.abs(w[-1000:])) <= 1e-8 and abs(phi[-1] - angles[-1]) <= 1e-3
    energy = run.energy
    work = run.work[:, run.work_names.index("pivot")]
    assert work[-1] < -4.0 and np.max(np.abs(energy - energy[0] - work)) <= 1e-7


def test_pendulum_held_where_gravity_stays_below_the_friction(pendulum):
    """At 0.29 rad, m g L sin(phi0) = 2.80 N m < F = 2.943 N m: it stays, but for the stuck row's creep of
    COMPLIANCE (1e-6) times the speed gravity gives it in a step (2.8e-3 rad/s): below 3e-9 rad/s, 3e-9 rad in 1 s."""
    run = andyc.simulate(pendulum, 1.0, dt=H, method="moreau", parameters={"phi0": 0.29})
    assert np.max(np.abs(run.column("phi_dot"))) <= 3e-9 and np.max(np.abs(run.column("phi") - 0.29)) <= 3e-9
    run = andyc.simulate(pendulum, 1.0, dt=H, method="moreau", parameters={"phi0": 0.31})
    assert run.column("phi")[-1] < 0.31 - 1e-3     # (m g L sin 0.31 = 2.99 > F: it slides)


@pytest.mark.parametrize("seed", range(6))
def test_bounded_rows_solve_the_box_constrained_problem(seed):
    """Bounded rows alone: P minimizes 1/2 P.W P + w0.P over |P_i| <= b_i (the step problem's conditions are this
    problem's KKT conditions); scipy's L-BFGS-B finds the same minimizer, and the answer is verified."""
    rng = np.random.default_rng(seed)
    for _ in range(20):
        m = int(rng.integers(1, 8))
        A = rng.normal(size=(m, m + 2))
        W, w0, b = A @ A.T, rng.normal(size=m) * 3, rng.uniform(0.0, 2.0, size=m)
        P, state = np.zeros(m), np.full(m, cs.NONE, np.int64)
        _, verified = cs.solve(W, w0, np.full(m, cs.BOUNDED, np.int64), np.arange(m, dtype=np.int64), b, state,
                               np.zeros((m, 2)), P, np.zeros(cs.work_shape(m)))
        best = minimize(lambda x: 0.5 * x @ W @ x + w0 @ x, np.zeros(m), jac=lambda x: W @ x + w0,
                        bounds=list(zip(-b, b)), method="L-BFGS-B", options={"ftol": 1e-15, "gtol": 1e-12})
        assert verified and np.max(np.abs(best.x - P)) <= 1e-5


def test_one_gauss_seidel_sweep_clips_a_bounded_row_exactly():
    """A bounded row alone is solved exactly by its local problem (Gauss-Seidel's step): P = -w0 / W clipped to
    [-b, b]: W = 2, w0 = -3 gives 1.5 within a bound 2 and 1 at a bound 1 (-1 for w0 = 3)."""
    W = np.array([[2.0]])
    for w0, bound, expected in ((-3.0, 2.0, 1.5), (-3.0, 1.0, 1.0), (3.0, 1.0, -1.0)):
        P = np.zeros(1)
        cs._sweep(W, np.array([w0]), np.array([cs.BOUNDED]), np.array([0]), np.array([bound]), P)
        assert P[0] == expected


def test_a_bounded_row_beside_a_contact_meets_both_laws():
    """A unit point mass in the plane pressed onto the ground (normal speed -1) while sliding at 2, its tangent
    speed also held by a bounded row (friction F h = 0.3, as a wheel's bearing would): Coulomb (mu = 0.5) and the
    bound both act against the slip, P_t = -0.5, P_f = -0.3, slip after 2 - 0.8 = 1.2; at slip 0.5 both stick
    the slip out only together: P_t + P_f = -0.5 with the contact's share inside its cone."""
    W = np.array([[1.0, 0, 0], [0, 1.0, 1.0], [0, 1.0, 1.0]])       # rows: normal, tangent, the bounded row's
    kind, first, mu = np.array([cs.PLANAR, cs.BOUNDED]), np.array([0, 2]), np.array([0.5, 0.3])
    for slip, total in ((2.0, -0.8), (0.5, -0.5)):
        P = np.zeros(3)
        _, verified = cs.solve(W, np.array([-1.0, slip, slip]), kind, first, mu, np.full(2, cs.NONE),
                               np.zeros((2, 2)), P, np.zeros(cs.work_shape(3)))
        w = np.array([-1.0, slip, slip]) + W @ P
        assert verified and abs(P[0] - 1.0) <= 1e-12 and abs(w[0]) <= 1e-12
        assert abs(P[1] + P[2] - total) <= 1e-12 and abs(P[1]) <= 0.5 + 1e-12 and abs(P[2]) <= 0.3 + 1e-12
        assert abs(w[1] - (slip + total)) <= 1e-12


def test_event_driven_methods_refuse_joint_friction(wheel):
    with pytest.raises(SimulationError, match=r"joint friction \(bearing: dampers of law coulomb\) is applied by "
                                              r"the moreau method only, not by rk4; run with --method moreau"):
        andyc.simulate(wheel, 1.0, dt=H, method="rk4")
    with pytest.raises(SimulationError, match=r"joint friction 'bearing': its force is -1 at F = -1, negative"):
        andyc.simulate(wheel, 1.0, dt=H, method="moreau", parameters={"F": -1.0})


def test_a_coulomb_damper_on_a_frame_or_negative_is_refused_with_its_line(tmp_path):
    text = WHEEL.replace("speed: theta, coefficient: F", "frame: disc, coefficient: F")
    (tmp_path / "a.yaml").write_text(text)
    with pytest.raises(SpecError) as e:
        andyc.load(tmp_path / "a.yaml")
    d = e.value.diagnostics[0]
    assert (d.line, d.path) == (12, "dampers[0].frame") and "acts on one speed" in d.message
    (tmp_path / "b.yaml").write_text(WHEEL.replace("F: 0.2", "F: -0.2"))
    with pytest.raises(SpecError) as e:
        andyc.load(tmp_path / "b.yaml")
    d = e.value.diagnostics[0]
    assert d.path == "dampers[0].coefficient" and d.message == "the friction force is -0.2, negative"


URDF = """<robot name="arm">
  <link name="base"/>
  <link name="upper">
    <inertial><origin xyz="0 0 -0.5"/><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0"
      iyz="0"/></inertial>
  </link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="5" velocity="2"/>
    <dynamics damping="0" friction="FRICTION"/>
  </joint>
</robot>
"""


def test_urdf_joint_friction_holds_the_arm_where_gravity_stays_below_it(tmp_path, build_dir):
    """A URDF arm (1 kg at 0.5 m below a revolute joint about x) at 0.3 rad: gravity's torque 9.81 * 0.5 *
    sin 0.3 = 1.45 N m. Its <dynamics friction> of 2 N m holds it (moreau: not a speed above 0); 1 N m does
    not; urdf: {joint_friction: false} leaves it out (a swing; rk4 runs it)."""
    for friction, moves in ((2.0, False), (1.0, True)):
        (tmp_path / "arm.urdf").write_text(URDF.replace("FRICTION", str(friction)))
        source = tmp_path / f"arm_{int(friction)}.yaml"
        source.write_text(f"name: arm_{int(friction)}\nurdf: {{file: arm.urdf, limits: false}}\n"
                          "coordinates:\n  shoulder: {initial: 0.3}\n")
        model = andyc.compile_model(source, build_dir)[0]
        assert model.friction_names == ("shoulder_friction",)
        run = andyc.simulate(model, 0.5, dt=H, method="moreau")
        assert (np.max(np.abs(run.column("shoulder_dot"))) > 0.1) == moves
    source = tmp_path / "arm_free.yaml"
    source.write_text("name: arm_free\nurdf: {file: arm.urdf, limits: false, joint_friction: false}\n"
                      "coordinates:\n  shoulder: {initial: 0.3}\n")
    result = invoke("sim", source, "--method", "rk4", "--t-end", 0.5, "--build-dir", build_dir, "-o",
                    tmp_path / "free.h5")
    assert result.exit_code == 0, result.output


def test_linearize_refuses_joint_friction_naming_the_fix(tmp_path):
    """A linearization has no stick-slip decision: andyc linearize refuses, exit 1, one line."""
    (tmp_path / "wheel.yaml").write_text(WHEEL)
    result = invoke("linearize", tmp_path / "wheel.yaml", cwd=tmp_path)
    assert result.exit_code == 1
    assert result.stderr.strip() == (f"{tmp_path / 'wheel.yaml'}: joint friction (bearing: dampers of law coulomb) "
                                     "is applied by the moreau method only, not by andyc linearize; leave it out (a "
                                     "URDF's: urdf: {joint_friction: false}; a damper: another law)")


def test_go1_stands_with_its_urdf_joint_friction(build_dir, tmp_path_factory):
    """models/go1.yaml with its URDF's joint friction (0.2 N m on each of 12 joints; the shipped model leaves it out):
    4 feet and 12 stuck joints are 24 rows on 18 speeds, some nearly dependent, and every step's problem is solved
    and verified from the warm start (no Gauss-Seidel sweep); after 1 s the joints creep below 1e-7 rad/s, the base
    stays within 1e-7 m, and the feet carry m g (13.100529 kg, Pinocchio's mass of the URDF) to 1e-9."""
    text = (MODELS / "go1.yaml").read_text().replace("name: go1\n", "name: go1_joint_friction\n")
    text = text.replace("file: go1/go1.urdf", f"file: {MODELS / 'go1' / 'go1.urdf'}")
    text = text.replace("joint_friction: false", "joint_friction: true")
    source = tmp_path_factory.mktemp("go1") / "go1_joint_friction.yaml"
    source.write_text(text)
    model = andyc.compile_model(source, build_dir)[0]
    assert len(model.friction_names) == 12
    run = andyc.simulate(model, 2.0, dt=H, method="moreau")
    assert run.finished and run.stats["unverified_steps"] == 0 and run.stats["contact_sweeps"] == 0
    late = run.time >= 1.0
    speeds = np.array([run.column(n) for n in run.state_names if n.endswith("_joint_dot")])
    assert speeds.shape[0] == 12 and np.max(np.abs(speeds[:, late])) <= 1e-7
    z = run.column("base_z")[late]
    assert z.max() - z.min() <= 1e-7
    normal = np.nan_to_num(run.multipliers[-1][run.contact_rows]).sum()
    assert abs(normal / (13.100529 * 9.81) - 1.0) <= 1e-9
