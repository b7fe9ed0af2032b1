"""The swing bar of the ANDY paper (docs/reference-cases.md §1): a ball joint on a
quaternion signal, driven by three body-frame angular-velocity speeds.

Checks that do not depend on the paper's figures:
- the quaternion stays on the unit sphere;
- the power balance E(t) - E(0) = W(t) from the work the run logs, with the
  drive's work against T (qh - qh0) and the dampers' against the COM
  velocities computed here from the logged bar-end positions;
- the same mechanism with three revolute joints in place of the ball joint
  follows the same bar-end trajectories.
"""

import numpy as np
import pytest
from scipy.integrate import cumulative_simpson
from scipy.interpolate import CubicSpline

import andyc
from tests.support import MODELS

FRAMES = ["bar1", "ball", "bar2", "bar3"]


@pytest.fixture(scope="module")
def run30(compiled):
    run = andyc.simulate(compiled("swing_bar"), 30.0, dt=1e-3, frames=FRAMES)
    assert run.finished
    return run


def quaternion(run):
    return np.column_stack([run.column(f"ball_q{c}") for c in "wxyz"])


def test_state_layout_names_every_signal(compiled):
    model = compiled("swing_bar")
    assert model.state_names == ("qh", "qh_dot", "wx", "wy", "wz", "ball_qw", "ball_qx", "ball_qy", "ball_qz")
    assert (model.nq, model.nv, model.ns, model.nx) == (1, 4, 4, 9)
    x0 = model.initial_state(model.parameter_defaults)
    np.testing.assert_allclose(x0, [0, -5, 0, 0, 0, np.sqrt(0.5), 0, np.sqrt(0.5), 0], atol=1e-15)


def test_quaternion_norm_within_1e9_over_30s(run30, compiled):
    norm = np.linalg.norm(quaternion(run30), axis=1)
    assert np.max(abs(norm - 1)) < 1e-9
    # Without the projection after each step the drift is RK4's own; it is
    # also inside the bound at this step (measured 1.3e-11), and the
    # projection leaves the trajectory within RK4's truncation error.
    bare = andyc.simulate(compiled("swing_bar"), 30.0, dt=1e-3, projection=andyc.Projection(normalize=False),
                          every=100)
    drift = np.max(abs(np.linalg.norm(quaternion(bare), axis=1) - 1))
    assert 1e-14 < drift < 1e-9
    assert np.max(abs(bare.state[:, :5] - run30.state[::100, :5])) < 1e-5


def test_power_balance_from_the_logged_work_1e9_over_30s(compiled):
    """E(t) - E(0) = W(t), W the work andyc integrates with the motion (RK4 on the power of the drive and the
    three dampers, the same stages as the state). The residual is RK4's truncation error: at dt = 5e-4 it is
    below 1e-9 J over 30 s, and halving the step divides it by about 2^4.

    Independent of andyc's power: the drive's torque T about z has power T dqh/dt, so its work is exactly
    T (qh(t) - qh(0)) (RK4 takes the same weighted sum of the stages for both, hence round-off); the
    dampers' work is checked against the COM velocities rebuilt from the logged frame positions (spline
    derivative, then Simpson), to the spline's accuracy."""
    model = compiled("swing_bar")
    runs = {dt: andyc.simulate(model, 30.0, dt=dt, frames=FRAMES) for dt in (1e-3, 5e-4)}
    assert all(r.finished for r in runs.values())
    run = runs[5e-4]
    assert run.work_names == ["drive", "drag1", "drag2", "drag3"]
    gap = {dt: np.max(abs(r.energy - r.energy[0] - r.work.sum(axis=1))) for dt, r in runs.items()}
    assert gap[5e-4] < 1e-9
    assert 10 < gap[1e-3] / gap[5e-4] < 25                # fourth order
    np.testing.assert_allclose(run.energy_balance, run.energy - run.energy[0] - run.work.sum(axis=1), atol=0)
    drive = run.work[:, 0]
    assert np.max(abs(drive - run.parameters["T"] * (run.column("qh") - run.column("qh")[0]))) < 1e-11
    t = run.time[::10]
    pos = {f: run.frames[f][::10] for f in FRAMES}
    coms = [pos["bar1"] / 2, (pos["ball"] + pos["bar2"]) / 2, (pos["bar2"] + pos["bar3"]) / 2]
    for k, com in enumerate(coms):      # each rod's COM is the midpoint of its two ends
        power = -run.parameters["b"] * np.sum(CubicSpline(t, com).derivative()(t) ** 2, axis=1)
        work = cumulative_simpson(power, x=t, initial=0.0)
        assert np.max(abs(work[5:-5] - run.work[::10, 1 + k][5:-5])) < 1e-6      # spline ends are one-sided
    np.testing.assert_allclose(run.power[:, 0], run.parameters["T"] * run.column("qh_dot"), rtol=1e-13, atol=1e-13)
    assert run.energy[-1] < 0.05 * run.energy[0]   # it is really damped


def test_motion_settles_to_steady_rotation(run30):
    """The paper's Fig. 6: the bar turns steadily and the bar ends' heights settle."""
    late = run30.time > 25
    rate = run30.column("qh_dot")[late]
    assert 1.0 < rate.mean() and rate.std() < 0.5 * rate.mean()
    early = run30.time < 5
    for f in ("bar2", "bar3"):
        z = run30.frames[f][:, 2]
        assert z[late].std() < 0.3 * z[early].std()


REVOLUTE_BALL = """\
  - {name: j1, parent: bar1, revolute: ea, axis: y}
  - {name: j2, parent: j1, revolute: eb, axis: x}
  - {name: ball, parent: j2, revolute: ec, axis: z}
"""


def test_three_revolute_joints_give_the_same_trajectory(tmp_path, build_dir, compiled):
    """The ball joint written as R = Ry(ea) Rx(eb) Rz(ec), from ea = pi/2 (the initial
    quaternion is a quarter turn about y), away from the YXZ gimbal lock at eb = pi/2."""
    text = (MODELS / "swing_bar.yaml").read_text()
    lines = [line for line in text.splitlines(keepends=True) if not line.lstrip().startswith("- {name: ball,")]
    text = "".join(lines)
    text = text.replace("name: swing_bar", "name: swing_bar_euler")
    text = text.replace("speeds: {wx: {}, wy: {}, wz: {}}", "")
    text = text.replace("  qh: {velocity: -5}", "  qh: {velocity: -5}\n  ea: {initial: pi/2}\n  eb: {}\n  ec: {}")
    text = text.replace("  - {name: bar2,", REVOLUTE_BALL + "  - {name: bar2,")
    path = tmp_path / "swing_bar_euler.yaml"
    path.write_text(text)
    euler, _ = andyc.compile_model(path, build_dir)
    assert euler.nx == 8 and euler.ns == 0
    ball = andyc.simulate(compiled("swing_bar"), 2.0, dt=1e-3, frames=["bar2", "bar3"])
    other = andyc.simulate(euler, 2.0, dt=1e-3, frames=["bar2", "bar3"])
    assert ball.finished and other.finished
    assert np.max(abs(other.column("eb"))) < 1.4        # the start is away from gimbal lock, and stays away
    for f in ("bar2", "bar3"):
        assert np.max(abs(ball.frames[f] - other.frames[f])) < 1e-6
    np.testing.assert_allclose(ball.column("qh"), other.column("qh"), atol=1e-8)
    np.testing.assert_allclose(ball.energy, other.energy, atol=1e-8)
