"""The moreau method (andyc.runtime.timestepping): Moreau-Jean time-stepping against closed forms, and its
contact problem (andyc.numerics.contact_solver, and its Python twin andyc.independent.contact_problem) against the complementarity conditions themselves."""

import math

import numpy as np
import pytest

import andyc
from andyc.errors import SimulationError
from andyc.independent.contact_problem import (BILATERAL, NORMAL, OPEN, PLANAR, SLIDE, SLIP_NEG, SLIP_POS, SPATIAL, STICK,
                                           Block, solve)
from tests.support import MODELS
from tests.support.references import RATIO, impact_times, sliding_reference, slope_coordinates
from tests.support.cli import invoke

G = 9.81
H = 1e-3


@pytest.fixture(scope="module")
def ball_run(compiled):
    return andyc.simulate(compiled("bouncing_ball_contact"), 10.0, dt=H, method="moreau")


def test_ball_impact_times_within_two_steps(ball_run):
    """The impact times t1 = sqrt(2 h0 / g), t_(k+1) = t_k + 2 e^k t1: the step that takes an impact is the first
    whose predicted mid-point gap y_k + h v_k / 2 is <= 0, so it starts within a step of the touch, and each
    flight of the discrete ball (exact parabolas between impacts at theta = 1/2, launched up to a step late)
    shifts the later ones by a fraction of a step: the first three within 2 h."""
    run, e = ball_run, 0.8
    force = np.nan_to_num(run.multipliers[:, 0])
    starts = np.nonzero((force[1:] > 0) & (force[:-1] == 0))[0]        # the step from sample i to i + 1
    t1 = math.sqrt(2 * 1.0 / G)
    exact = [t1, t1 + 2 * e * t1, t1 + 2 * e * t1 + 2 * e ** 2 * t1]
    assert np.all(np.abs(run.time[starts[:3]] - exact) <= 2 * H)


def test_ball_rests_after_the_zeno_point(ball_run):
    """Past t_inf = t1 (1 + 2e / (1 - e)) = 4.0637 s the ball rests to t = 10 s: speed 0 to 1e-12, mean normal
    force P / h = m g to 1e-10, closed. From t_inf + 0.2 s: in the index set the rebound is v_(k+1) = -e v_k
    (Newton's law, step by step) from speeds of order g h, so 1e-12 comes log(1e-12 / (g h)) / log(e) = 103 steps
    later. Its height stays within h^2 g of 0 (it rests on the ground: its gap put back on zero when it closes)."""
    run = ball_run
    late = run.time >= 4.0637 + 0.2
    assert run.finished and run.time[-1] == pytest.approx(10.0)
    assert np.max(np.abs(run.column("y_dot")[late])) <= 1e-12
    assert np.max(np.abs(run.multipliers[late, 0] - 1.0 * G)) <= 1e-10
    assert np.max(np.abs(run.column("y")[late])) <= H ** 2 * G
    assert set(run.contact_modes[late, 0]) == {1}
    # (the impulses' work is in the `jumps` slot: E - E0 - W is the scheme's own error, exact parabolas here, but
    # for the step in which it closes: the contact enters the problem where the gap predicted at the step's end
    # reaches zero, so the ball stops up to a step's travel of its last, slowest approach (g h^2 / 2) above the
    # ground, and is set on it, which changes its potential energy by at most m g (g h^2 / 2))
    assert np.max(np.abs(run.energy_balance)) <= 1.0 * G * G * H ** 2 / 2
    assert np.max(np.abs(run.energy_balance[run.time < 4.0])) <= 1e-9


@pytest.mark.parametrize("mu", [0.7, 0.3])
def test_block_sticks_or_slides(compiled, mu):
    """tan th = 0.546 for th = 0.5: mu = 0.7 sticks (moves <= 1e-12 m over 5 s, friction m g sin th); mu = 0.3
    slides down at a = g (sin th - mu cos th), x = -a t^2 / 2 along the slope (the trapezoidal theta = 1/2 is
    exact for a constant acceleration: 1e-10 m)."""
    th = 0.5
    run = andyc.simulate(compiled("block_incline"), 5.0, dt=H, method="moreau", parameters={"th": th, "mu": mu})
    x, y, t = run.column("x"), run.column("y"), run.time
    along, normal = math.cos(th) * x + math.sin(th) * y, math.cos(th) * y - math.sin(th) * x
    assert np.max(np.abs(normal)) <= 1e-12
    assert np.allclose(run.multipliers[1:, 0], G * math.cos(th), rtol=0, atol=1e-10)
    if mu > math.tan(th):
        assert np.max(np.abs(along)) <= 1e-12
        assert np.allclose(run.multipliers[1:, 1], G * math.sin(th), rtol=0, atol=1e-10)
        assert set(run.contact_modes[1:, 0]) == {STICK}
    else:
        a = G * (math.sin(th) - mu * math.cos(th))
        assert np.max(np.abs(along + 0.5 * a * t ** 2)) <= 1e-10
        assert set(run.contact_modes[1:, 0]) == {SLIP_NEG}     # slipping down: backwards


def test_ball_thrown_sliding_rolls_at_five_sevenths(compiled):
    """The ball thrown sliding at v0 = 2 m/s without spin (mu = 0.2): its slip falls at (7/2) mu g and it rolls from
    t* = 2 v0 / (7 mu g) at 5 v0 / 7 (the friction impulses have no moment about the contact point, so its angular
    momentum about it, m r v + I w, is kept through the step that stops the slip too): the speed to 1e-12, the
    first rolling sample within a step of t*."""
    v0, mu = 2.0, 0.2
    run = andyc.simulate(compiled("ball_rolling"), 1.0, dt=H, method="moreau")
    rolling = run.contact_modes[:, 0] == STICK
    first = np.nonzero(rolling)[0][0]
    assert np.all(rolling[first:]) and 0.0 <= run.time[first] - 2 * v0 / (7 * mu * G) <= H
    assert np.max(np.abs(run.column("x_dot")[first:] - 5 * v0 / 7)) <= 1e-12
    assert np.max(np.abs(run.column("x_dot")[first:] + 0.1 * run.column("th_dot")[first:])) <= 1e-12


def test_theta_one_is_backward_euler_in_the_speeds(compiled):
    """theta = 1: x_(k+1) = x_k + h v_(k+1), so under a constant acceleration -a the slope position is
    -a (t^2 + h t) / 2 exactly (the sum of h^2 a (1 + ... + n)); 1e-10 m over 2 s."""
    th, mu = 0.5, 0.3
    run = andyc.simulate(compiled("block_incline"), 2.0, dt=H, method="moreau", parameters={"th": th, "mu": mu},
                         stepping=andyc.TimeStepping(theta=1.0))
    along = math.cos(th) * run.column("x") + math.sin(th) * run.column("y")
    a, t = G * (math.sin(th) - mu * math.cos(th)), run.time
    assert np.max(np.abs(along + 0.5 * a * (t ** 2 + H * t))) <= 1e-10


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_rod_lands_on_both_supports_without_turning(compiled, e):
    """The rod falls flat onto two supports: both take the same impulses in every step, to 1e-12 of the largest,
    and it never turns (tilt and its rate 1e-12). In the impact step Newton's law holds exactly, u_(k+1) = -e u_k:
    it leaves level at e times its speed (1e-12); with e = 0 it rests with m g / 2 on each (mean force, 1e-10)."""
    run = andyc.simulate(compiled("rod_drop"), 1.0, dt=H, method="moreau", parameters={"e": e})
    left, right = (np.nan_to_num(run.multipliers[:, k]) * H for k in range(2))
    assert np.max(left) > 1.0                           # the impact: about (1 + e) m sqrt(2 g h0) / 2 each
    assert np.max(np.abs(left - right)) <= 1e-12 * np.max(left)
    assert np.max(np.abs(run.column("th"))) <= 1e-12 and np.max(np.abs(run.column("th_dot"))) <= 1e-12
    k = np.nonzero(left > 0)[0][0]                      # the impact step ends at sample k
    vy = run.column("y_dot")
    assert abs(vy[k] + e * vy[k - 1]) <= 1e-12
    if e == 0.0:
        assert abs(vy[-1]) <= 1e-12
        assert np.allclose(run.multipliers[-1], G / 2, rtol=0, atol=1e-10)


def test_every_logs_the_mean_force_of_its_steps(compiled):
    """Logging one sample in 10 keeps the same steps: the states at the common samples are the every-step run's,
    and each sample's force is the mean of its 10 steps' (so sum(force) 10 h is the same total impulse)."""
    model = compiled("rod_drop")
    one = andyc.simulate(model, 1.0, dt=H, method="moreau")
    ten = andyc.simulate(model, 1.0, dt=H, method="moreau", every=10)
    assert np.array_equal(ten.state, one.state[::10])
    impulses = np.nan_to_num(one.multipliers[1:]).reshape(-1, 10, 2).sum(axis=1) * H
    assert np.allclose(np.nan_to_num(ten.multipliers[1:]) * 10 * H, impulses, rtol=0, atol=1e-14)


def test_rocking_block_against_housner(compiled):
    """The rocking block (tests/test_rocking_block.py: the quadrature of its free rocking, Housner's ratio): its
    first impact (th crossing level) comes in the step that holds the exact time, its second within a step of it
    (the first impulse acts at its step's mid point, up to h |w| off level: the rocking after it is O(h) off), and
    the angular velocity one step either side of the first impact step has Housner's ratio 1 - (3/2) sin^2 alpha to
    10 h (O(h): gravity turns the block over the three steps; measured 3.7 h at h = 1e-3, 0.3 h at 1e-4). The pivot
    stays on the ground all along (its position corrected where it drifts: 1e-15 m)."""
    run = andyc.simulate(compiled("rocking_block"), 1.2, dt=H, method="moreau",
                         frames=["left_corner", "right_corner"])
    th, w, t = run.column("th"), run.column("th_dot"), run.time
    level = np.nonzero(th[1:] * th[:-1] < 0)[0]
    exact = impact_times(2)
    assert t[level[0]] <= exact[0] <= t[level[0] + 1]
    assert t[level[1]] - H <= exact[1] <= t[level[1] + 1] + H
    assert min(run.frames["left_corner"][:, 1].min(), run.frames["right_corner"][:, 1].min()) > -1e-15
    k = level[0]
    assert abs(w[k + 2] / w[k - 1] - RATIO) <= 10 * H
    assert run.stats["unverified_steps"] == 0


@pytest.mark.parametrize("th, mu", [(0.3, 0.5), (0.5, 0.3)], ids=["stops", "slides-on"])
def test_spatial_friction_block_against_the_reference(compiled, th, mu):
    """The block pushed across the incline at 1 m/s (spatial friction; tests/test_spatial_friction.py's independent
    SciPy integration): the path converges at first order (the friction's direction is the slip's after each step,
    an O(h) lag): off the reference by at most 1e-3 m at h = 1e-3 and half that, to 10 %, at h / 2. With
    mu > tan th it sticks within 2 h of the reference's stop (its path O(h) off) and stays, moving <= 1e-12 m,
    held by the friction m g sin th up the slope (mean force, 1e-10)."""
    sol, t_stop = sliding_reference(th, mu, 1.0, 1.0)
    errors = []
    for h in (H, H / 2):
        run = andyc.simulate(compiled("block_incline_spatial"), 1.0, dt=h, method="moreau",
                             parameters={"th": th, "mu": mu})
        s, w = slope_coordinates(run, th)
        ref = sol(np.minimum(run.time, t_stop or 1.0))
        errors.append(max(np.max(np.abs(s - ref[0])), np.max(np.abs(w - ref[1]))))
        assert run.stats["unverified_steps"] == 0
    assert errors[0] <= 1e-3 and 0.45 <= errors[1] / errors[0] <= 0.55
    modes = run.contact_modes[1:, 0]
    if t_stop is None:
        assert set(modes) == {SLIDE}
        return
    stuck = 1 + np.nonzero(modes == STICK)[0]
    assert abs(run.time[stuck[0]] - t_stop) <= 2 * H / 2
    assert np.all(np.diff(stuck) == 1) and stuck[-1] == len(run.time) - 1      # and it stays
    rest = run.state[stuck[0]:, :3]
    assert np.max(np.abs(rest - rest[-1])) <= 1e-12
    friction = run.multipliers[stuck[0] + 1:, 1:3]   # friction_slope_1 (up the slope), _2 (across); after the
    #                                                  step that stops it (its impulse stops the slip left)
    assert np.allclose(friction, [G * math.sin(th), 0.0], rtol=0, atol=1e-10)


def test_four_redundant_supports(compiled, tmp_path_factory):
    """A rod dropped tilted (0.05 rad) onto four supports (its ends and at +-L/6: four contacts, the schema's most
    without friction, on 2 speeds: W = A M^-1 A^T of rank 2): every step's problem is solved and verified, no
    support ever pulls, and it comes to rest (speeds 1e-12) on the supports its landing left touching, their
    mean forces summing to m g (1e-10) with no moment about the centre (1e-10)."""
    text = (MODELS / "rod_drop.yaml").read_text().split("\n# andyc test:")[0] + "\n"
    text = text.replace("name: rod_drop", "name: rod_four").replace("th: {initial: 0}", "th: {initial: 0.05}")
    text = text.replace("  - {name: right_end, parent: rod, translation: [L/2, 0, 0]}\n",
                        "  - {name: right_end, parent: rod, translation: [L/2, 0, 0]}\n"
                        "  - {name: left_in, parent: rod, translation: [-L/6, 0, 0]}\n"
                        "  - {name: right_in, parent: rod, translation: [L/6, 0, 0]}\n")
    text += ("  - {name: left_inner, gap: left_in.y, restitution: e}\n"
             "  - {name: right_inner, gap: right_in.y, restitution: e}\n")
    path = tmp_path_factory.mktemp("moreau") / "rod_four.yaml"
    path.write_text(text)
    run = andyc.simulate(compiled(path), 2.0, dt=H, method="moreau")
    assert run.finished and run.stats["unverified_steps"] == 0
    forces = run.multipliers[1:]
    assert np.nanmin(forces) >= 0.0
    assert np.max(np.abs(run.state[-1, 2:])) <= 1e-12
    end = np.nan_to_num(run.multipliers[-1])
    th = run.column("th")[-1]
    arms = math.cos(th) * np.array([-0.5, 0.5, -1 / 6, 1 / 6])        # left, right, left_inner, right_inner
    assert abs(end.sum() - G) <= 1e-10 and abs(end @ arms) <= 1e-10


PENDULUM_WALL = """\
name: pendulum_wall
description: A pendulum in Cartesian coordinates (a bilateral rod) striking a wall (a contact).
parameters: {m: 1.0, g: 9.81, L: 1.0, a: 0.5, e: 0.5}
coordinates:
  x: {initial: L}
  y: {initial: 0}
gravity: [0, -g, 0]
frames:
  - {name: sx, parent: world, prismatic: x, axis: x}
  - {name: bob, parent: sx, prismatic: y, axis: y}
bodies:
  - {name: mass, frame: bob, mass: m}
constraints:
  - {name: rod, holonomic: (bob.x**2 + bob.y**2 - L**2)/(2*L), multiplier: tension}
contacts:
  - {name: wall, gap: bob.x + a, restitution: e, multiplier: wall_force}
"""


def test_bilateral_rows_hold_and_the_impact_keeps_to_them(compiled, tmp_path_factory):
    """A pendulum in Cartesian coordinates (its rod a bilateral row) released level strikes a wall at x = -L/2:
    the rod holds to 1e-9 over 3 s (the rows, held at velocity level, are projected back after each step: without
    that it drifts to 8e-3), and the impact, solved with the rod's row, reverses the wall-normal speed and keeps the
    bob on the circle, so its speed drops by e = 0.5, to O(h): gravity changes it by at most g h / |v| = 2.4e-3
    relative within the step."""
    path = tmp_path_factory.mktemp("moreau") / "pendulum_wall.yaml"
    path.write_text(PENDULUM_WALL)
    run = andyc.simulate(compiled(path), 3.0, dt=H, method="moreau")
    x, y, vx, vy = (run.column(n) for n in ("x", "y", "x_dot", "y_dot"))
    assert run.finished and np.max(np.abs(np.hypot(x, y) - 1.0)) <= 1e-9
    k = np.nonzero(np.nan_to_num(run.multipliers[:, 1]) > 0)[0][0]
    before, after = np.hypot(vx[k - 1], vy[k - 1]), np.hypot(vx[k], vy[k])
    assert abs(after / before - 0.5) <= G * H / before


def test_usage_errors(compiled, tmp_path):
    with pytest.raises(SimulationError, match="needs contacts"):
        andyc.simulate(compiled("pendulum_a01"), 0.1, method="moreau")
    with pytest.raises(SimulationError, match=r"theta is 0\.3; use a value in \[0\.5, 1\]"):
        andyc.simulate(compiled("bouncing_ball_contact"), 0.1, method="moreau", stepping=andyc.TimeStepping(0.3))
    text = (MODELS / "bouncing_ball_contact.yaml").read_text().split("\n# andyc test:")[0]
    (tmp_path / "ball_phases.yaml").write_text(text.replace("name: bouncing_ball_contact", "name: ball_phases") + """
hybrid:
  flows: [{name: high}, {name: low}]
  jumps: [{name: down, from: high, to: low, guard: y - 0.5, direction: falling}]
""")
    with pytest.raises(SimulationError, match="jump 'down' is written by hand, and the moreau method handles the "
                       "contacts' jumps only"):
        andyc.simulate(compiled(tmp_path / "ball_phases.yaml"), 0.1, method="moreau")


def test_a_spinning_ball_on_quaternions_rolls_at_five_sevenths(compiled):
    """The spatial ball (a floating body: a quaternion signal, three angular speeds), thrown at v0 = (2, 1) with
    side spin 10 rad/s (models/ball_sliding_spatial.yaml, mu = 0.2): its signals move by their rates at the step's
    mid point, so time-stepping takes it as it takes any model. It slides, then rolls from t* = 2 |u0| / (7 mu g)
    on at v0 - (2/7) u0 (Routh; tests/test_spatial_friction.py has it event-driven): the final speed to 2 g mu h
    (the step that ends the slip lands within one step of friction), sticking at the end, |q| = 1 to rounding."""
    ball = compiled("ball_sliding_spatial")
    run = andyc.simulate(ball, 1.0, dt=H, method="moreau", parameters={"wx0": 10.0})
    v0, mu, r = np.array([2.0, 1.0]), 0.2, 0.1
    u0 = np.array([v0[0], v0[1] + r * 10.0])
    v = np.array([run.column("x_dot")[-1], run.column("y_dot")[-1]])
    assert run.finished and np.max(np.abs(v - (v0 - 2 / 7 * u0))) <= 2 * G * mu * H
    t_star = 2 * np.linalg.norm(u0) / (7 * mu * G)
    rolling = np.nonzero(run.contact_modes[:, 0] == STICK)[0]
    assert abs(run.time[rolling[0]] - t_star) <= 2 * H and np.all(run.contact_modes[rolling[0]:, 0] == STICK)
    q = np.stack([run.column(f"ball_q{c}") for c in "wxyz"], axis=1)
    assert np.max(np.abs(np.linalg.norm(q, axis=1) - 1.0)) <= 1e-14
    assert np.max(np.abs(run.column("z") - r)) <= 1e-12            # on the ground all along (its centre at r)


@pytest.mark.parametrize("args, message", [
    (("pendulum_a01.yaml", "--method", "moreau"), "the moreau method needs contacts"),
    (("bouncing_ball_contact.yaml", "--method", "moreau", "--theta", "1.5"), "theta is 1.5; use a value in [0.5, 1]"),
    (("bouncing_ball_contact.yaml", "--theta", "0.7"), "--theta is the moreau method's, not rk4's"),
])
def test_cli_usage_errors_exit_2(shipped_build, tmp_path, args, message):
    result = invoke("sim", MODELS / args[0], *args[1:], "--t-end", 0.1, "--build-dir", shipped_build,
                    "-o", tmp_path / "run.h5")
    assert result.exit_code == 2, result.output
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and message in lines[0]
    assert not (tmp_path / "run.h5").exists()


def test_cli_run_file_and_plot(shipped_build, tmp_path):
    """`andyc sim --method moreau` writes the run file the plots read: its flows (contact modes) and mean forces as
    the in-process run's, and `andyc plot` draws it."""
    from andyc.runtime.runfiles import read_h5

    h5, png = tmp_path / "rod.h5", tmp_path / "rod.png"
    result = invoke("sim", MODELS / "rod_drop.yaml", "--t-end", 0.5, "--method", "moreau", "--theta", 0.75,
                    "--build-dir", shipped_build, "-o", h5)
    assert result.exit_code == 0, result.output
    assert "moreau" in result.stdout and "500 steps" in result.stdout
    run = read_h5(h5)
    model = andyc.compile_model(MODELS / "rod_drop.yaml", shipped_build)[0]
    again = andyc.simulate(model, 0.5, dt=H, method="moreau", stepping=andyc.TimeStepping(0.75))
    assert run.method == "moreau" and np.array_equal(run.flow, again.flow)
    assert np.array_equal(run.multipliers, again.multipliers, equal_nan=True)
    assert invoke("plot", h5, "-o", png).exit_code == 0 and png.stat().st_size > 10_000


def _check(W, w0, blocks, P, tol=1e-9):
    """The step problem's conditions at P (andyc.independent.contact_problem's docstring), to tol."""
    w = w0 + W @ P
    for b in blocks:
        n = b.rows[0]
        if b.kind == BILATERAL:
            assert abs(w[n]) <= tol
            continue
        assert P[n] >= -tol and w[n] >= -tol and abs(P[n] * w[n]) <= tol
        if b.kind in (PLANAR, SPATIAL):
            t = list(b.rows[1:])
            Pt, slip = P[t], w[t]
            assert np.linalg.norm(Pt) <= b.mu * P[n] + tol
            if np.linalg.norm(Pt) < b.mu * P[n] - 1e-6:
                assert np.linalg.norm(slip) <= tol       # inside the cone: no slip
            elif np.linalg.norm(slip) > tol:             # on its edge, against the slip
                assert np.allclose(Pt, -b.mu * P[n] * slip / np.linalg.norm(slip), rtol=0, atol=tol)


@pytest.mark.parametrize("seed", range(20))
def test_contact_problem_solves_its_conditions(seed):
    """Random step problems (W = A M^-1 A^T of random A and M; 6 contacts, frictionless, planar and spatial, and
    a bilateral row): the Gauss-Seidel answer, polished, satisfies Newton's and Coulomb's conditions; and started
    from the states it found (the warm start) it gives the same impulses without a sweep."""
    rng = np.random.default_rng(seed)
    nv = 14
    blocks, m = [Block(BILATERAL, (0,))], 1
    for i in range(6):
        kind = (NORMAL, PLANAR, SPATIAL)[i % 3]
        blocks.append(Block(kind, tuple(range(m, m + kind)), float(rng.uniform(0.1, 1.0))))
        m += kind
    A = rng.normal(size=(m, nv))
    B = rng.normal(size=(nv, nv))
    W = A @ np.linalg.inv(B @ B.T + nv * np.eye(nv)) @ A.T
    w0 = rng.normal(size=m)
    sol = solve(W, w0, blocks)
    assert sol.verified and sol.sweeps > 0
    _check(W, w0, blocks, sol.P)
    again = solve(W, w0, blocks, sol)
    assert again.sweeps == 0 and np.allclose(again.P, sol.P, rtol=0, atol=1e-12)


def test_contact_problem_local_cases():
    """One contact with friction on a unit point mass (W = I): approaching at 1 with slip 0.2, mu = 0.5 sticks
    (P = (1, -0.2)); with slip 2 it slides (P_n = 1, P_t = -0.5, slip after 1.5); leaving, it stays open."""
    blocks = [Block(PLANAR, (0, 1), 0.5)]
    stick = solve(np.eye(2), np.array([-1.0, 0.2]), blocks)
    assert stick.states == [STICK] and np.allclose(stick.P, [1.0, -0.2], rtol=0, atol=1e-15)
    slide = solve(np.eye(2), np.array([-1.0, 2.0]), blocks)
    assert slide.states == [SLIP_POS] and np.allclose(slide.P, [1.0, -0.5], rtol=0, atol=1e-15)
    leave = solve(np.eye(2), np.array([1.0, 2.0]), blocks)
    assert leave.states == [OPEN] and not leave.P.any()
