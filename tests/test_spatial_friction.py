"""Spatial Coulomb friction (issue 21: a contact with two tangents, `slip: [s1, s2]`), against closed forms and an
independent integration.

- a ball thrown sliding obliquely with spin onto the ground (models/ball_sliding_spatial.yaml): it slides, then
  rolls from t* on. Closed form (Routh, Dynamics of a System of Rigid Bodies, Advanced Part, 1905, §§ 222-224; any
  text on the billiard ball): with the contact point at rho = -r e_z, the slip u = v + w x rho; sliding, the
  friction F = -mu m g u/|u| gives dv/dt = F/m and dw/dt = rho x F / I, so
  du/dt = F/m + (rho x F / I) x rho = -mu g (1 + m r^2 / I) u/|u| = -(7/2) mu g u/|u| (I = 2/5 m r^2; F is in
  the plane, so (rho x F) x rho = r^2 F): u keeps its direction and shrinks linearly to zero at
  t* = 2 |u0| / (7 mu g); then v = v0 - mu g t* u0/|u0| = v0 - (2/7) u0, and it rolls on at that velocity;
- its impact with the ground while spinning: Newton's P_n = (1 + e) m |vz|, the tangential impulse that stops
  the slip, P* = -u / (1/m + r^2/I), if |P*| <= mu P_n, else -mu P_n u/|u| (Brach, Mechanical Impact Dynamics,
  1991, ch. 3, in the plane of u: for a ball the slip keeps its direction through the impact);
- a block pushed across an incline (models/block_incline_spatial.yaml): its path curves down the slope,
  a = g sin th e_down - mu g cos th v/|v|, against SciPy's DOP853 on those equations; it stops and sticks when
  mu > tan th, and at rest it sticks (moves <= 1e-12 m in 5 s);
- run files, and the mistakes of a spatial friction contact.
"""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np
import pytest

import andyc
from andyc.errors import SpecError
from andyc.runtime.runfiles import read_h5
from tests.support.references import sliding_reference, slope_coordinates

G, MU, R = 9.81, 0.2, 0.1
OPEN, STICK, SLIP = 0, 1, 2
MODELS = Path(__file__).resolve().parents[1] / "models"


@pytest.fixture(scope="module")
def ball(compiled):
    return compiled("ball_sliding_spatial")


@pytest.fixture(scope="module")
def block(compiled):
    return compiled("block_incline_spatial")


# -- a ball sliding obliquely with spin, then rolling -------------------------------------------------

def initial_slip(v0, w0):
    """u0 = v0 + w0 x (-r e_z), its x and y components: (vx - r wy, vy + r wx)."""
    return np.array([v0[0] - R * w0[1], v0[1] + R * w0[0]])


@pytest.mark.parametrize("spin, method", [
    ((0.0, 0.0, 0.0), "rk4"), ((10.0, 0.0, 0.0), "rk4"), ((0.0, 0.0, 0.0), "DOP853"), ((10.0, 0.0, 0.0), "DOP853"),
    ((10.0, -15.0, 5.0), "DOP853")], ids=["no-spin-rk4", "side-spin-rk4", "no-spin", "side-spin", "spin-all-axes"])
def test_ball_thrown_obliquely_with_spin_rolls_from_t_star(ball, spin, method):
    """v0 = (2, 1) with spin w0: the slip keeps its direction u0/|u0| while it slides (the path curves when u0 is
    not along v0), the ball rolls from t* = 2 |u0| / (7 mu g) on at v = v0 - (2/7) u0 (the module docstring)."""
    v0 = np.array([2.0, 1.0])
    parameters = {"wx0": spin[0], "wy0": spin[1], "wz0": spin[2]}
    run = andyc.simulate(ball, 1.0, dt=1e-3, method=method, rtol=1e-12, atol=1e-12, parameters=parameters,
                         progress=False)
    u0 = initial_slip(v0, spin)
    t_star = 2 * np.linalg.norm(u0) / (7 * MU * G)
    assert run.finished and run.event_names() == ["ground_stop"]
    assert abs(run.events["time"][0] - t_star) < 1e-10
    rolling, sliding = run.time > t_star, run.time < t_star
    v = np.stack([run.column("x_dot"), run.column("y_dot")], axis=1)
    assert np.max(np.abs(v[rolling] - (v0 - 2 / 7 * u0))) < 1e-12
    assert np.all(run.contact_modes[rolling, 0] == STICK) and np.all(run.contact_modes[sliding, 0] == SLIP)
    slip = np.stack([run.slip_speeds[:, 0], run.slip_speeds_2[:, 0]], axis=1)
    assert np.max(np.abs(slip[rolling])) < 1e-12
    # sliding: the slip along u0, shrinking at 7/2 mu g; the friction -mu m g along it
    expected = u0 * (1 - run.time[sliding] / t_star)[:, None]
    # (rk4 at dt = 1e-3 follows the spinning ball's slip to its truncation error, 1e-9 m/s; it ends where it must)
    assert np.max(np.abs(slip[sliding] - expected)) < (1e-8 if method == "rk4" else 1e-10)
    friction = np.stack([run.friction_forces[:, 0], run.friction_forces_2[:, 0]], axis=1)
    # (rk4: over the last steps of the slip, which hold a predicted direction, 1e-7 N)
    assert np.max(np.abs(friction[sliding] + MU * G * u0 / np.linalg.norm(u0))) < (1e-7 if method == "rk4" else 1e-10)
    assert np.max(np.abs(friction[rolling])) < 1e-12           # rolling on the flat needs no friction
    assert np.max(np.abs(run.normal_forces[:, 0] - G)) < 1e-10
    if spin[0]:                                                 # the path curves: v turns from v0 to v0 - 2/7 u0
        cross = v0[0] * v[-1, 1] - v0[1] * v[-1, 0]
        assert abs(cross) > 0.1


def impact_map(v, w, e, m=1.0):
    """(v+, w+, P_n, P_t, sticking) of the ball striking the ground at v = (vx, vy, vz < 0), spin w (world axes):
    P_n = -(1 + e) m vz; the tangential impulse that stops the slip u, P* = -u / (1/m + r^2/I), if
    |P*| <= mu P_n, else -mu P_n u/|u|; then v+ = v + P/m, w+ = w + rho x P / I."""
    inertia = 0.4 * m * R ** 2
    pn = -(1 + e) * m * v[2]
    u = initial_slip(v, w)
    p_stick = -u / (1 / m + R ** 2 / inertia)
    sticking = np.linalg.norm(p_stick) <= MU * pn
    pt = p_stick if sticking else -MU * pn * u / np.linalg.norm(u)
    impulse = np.array([pt[0], pt[1], pn])
    rho = np.array([0.0, 0.0, -R])
    return v + impulse / m, w + np.cross(rho, impulse) / inertia, pn, pt, sticking


@pytest.mark.parametrize("spin, e", [((0.0, 0.0, 0.0), 0.0), ((0.0, 0.0, 0.0), 0.5), ((30.0, -20.0, 3.0), 0.0),
                                     ((30.0, -20.0, 3.0), 0.6)])
def test_an_oblique_impact_with_spin_keeps_the_impulse_in_the_disk(ball, spin, e):
    """Dropped from 0.2 m at v0 = (1, 0.5) with spin: Newton on the normal impulse, and the tangential one inside
    the disk |P_t| <= mu P_n (sticking without spin; sliding against the slip with it), against impact_map."""
    parameters = {"h0": 0.2, "e": e, "vx0": 1.0, "vy0": 0.5, "wx0": spin[0], "wy0": spin[1], "wz0": spin[2]}
    run = andyc.simulate(ball, 0.25, dt=1e-3, parameters=parameters, progress=False)
    assert run.finished and run.event_names()[0] == "ground_impact"
    before, after = run.events["state_before"][0], run.events["state_after"][0]   # x y z, x' y' z', wx wy wz, q
    assert before[5] == pytest.approx(-math.sqrt(2 * G * 0.2), rel=1e-12)
    world = _world_spin(before)
    v, w, pn, pt, sticking = impact_map(before[3:6], world, e)
    assert np.allclose(after[3:6], v, rtol=0, atol=1e-12)
    assert np.allclose(_world_spin(after), w, rtol=0, atol=1e-10)
    assert np.linalg.norm(pt) <= MU * pn * (1 + 1e-12)
    assert sticking == (not any(spin))
    assert run.event_modes(0) == [OPEN if e > 0 else STICK if sticking else SLIP]


def _world_spin(state):
    """The ball's angular velocity in world axes, R(q) w_body, from a state (x y z, x' y' z', w_body, q)."""
    qw, qx, qy, qz = state[9:13]
    rot = np.array([[1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)],
                    [2 * (qx * qy + qw * qz), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qw * qx)],
                    [2 * (qx * qz - qw * qy), 2 * (qy * qz + qw * qx), 1 - 2 * (qx * qx + qy * qy)]])
    return rot @ state[6:9]


# -- a block pushed across an incline ---------------------------------------------------------------------

@pytest.mark.parametrize("th, mu", [(0.3, 0.5), (0.5, 0.3)], ids=["stops", "slides-on"])
def test_block_pushed_across_the_slope_curves_down_it(block, th, mu):
    """Pushed across at 1 m/s: its path curves down the slope; with mu > tan th (0.309) it stops at the
    reference's time and sticks there; with mu < tan th it slides on. Against sliding_reference, to 1e-9."""
    run = andyc.simulate(block, 1.0, dt=1e-3, method="DOP853", rtol=1e-12, atol=1e-12,
                         parameters={"th": th, "mu": mu}, progress=False)
    sol, t_stop = sliding_reference(th, mu, 1.0, 1.0)
    assert run.finished
    s, w = slope_coordinates(run, th)
    if t_stop is None:
        assert run.event_names() == [] and np.all(run.contact_modes[:, 0] == SLIP)
        sliding = run.time >= 0
    else:
        assert run.event_names() == ["slope_stop"] and abs(run.events["time"][0] - t_stop) < 1e-9
        sliding, resting = run.time < t_stop, run.time > t_stop
        assert np.all(run.contact_modes[resting, 0] == STICK)
        end = sol(t_stop)
        assert np.max(np.abs(s[resting] - end[0])) < 1e-9 and np.max(np.abs(w[resting] - end[1])) < 1e-9
        assert np.max(np.abs(s[resting] - s[-1])) <= 1e-12 and np.max(np.abs(w[resting] - w[-1])) <= 1e-12
        # sticking: the friction holds it against gravity along the slope, m g sin th up it, nothing across
        assert np.max(np.abs(run.friction_forces[resting, 0] - G * math.sin(th))) < 1e-10
        assert np.max(np.abs(run.friction_forces_2[resting, 0])) < 1e-10
    ref = sol(run.time[sliding])
    assert np.max(np.abs(s[sliding] - ref[0])) < 1e-9 and np.max(np.abs(w[sliding] - ref[1])) < 1e-9
    assert s[sliding][-1] < -1e-3                                      # down the slope: the path curves
    # sliding: the friction mu lam_n against the slip, lam_n = m g cos th
    friction = np.stack([run.friction_forces[sliding, 0], run.friction_forces_2[sliding, 0]], axis=1)
    slip = np.stack([run.slip_speeds[sliding, 0], run.slip_speeds_2[sliding, 0]], axis=1)
    assert np.allclose(run.normal_forces[sliding, 0], G * math.cos(th), rtol=0, atol=1e-10)
    assert np.allclose(np.linalg.norm(friction, axis=1), mu * G * math.cos(th), rtol=0, atol=1e-10)
    moving = np.linalg.norm(slip, axis=1) > 1e-6
    assert np.allclose(friction[moving] * np.linalg.norm(slip[moving], axis=1)[:, None],
                       -mu * G * math.cos(th) * slip[moving], rtol=0, atol=1e-9)


def test_block_at_rest_sticks_when_tan_theta_is_below_mu(block):
    """mu = 0.5 > tan 0.3: it does not move in 5 s (<= 1e-12 m), the friction m g sin th up the slope."""
    run = andyc.simulate(block, 5.0, dt=1e-2, parameters={"v0": 0.0}, progress=False)
    assert run.finished and len(run.events["time"]) == 0 and np.all(run.contact_modes[:, 0] == STICK)
    assert np.max(np.linalg.norm(run.state[:, :3], axis=1)) <= 1e-12
    assert np.max(np.abs(run.friction_forces[:, 0] - G * math.sin(0.3))) < 1e-10
    assert np.max(np.abs(run.friction_forces_2[:, 0])) < 1e-12


def test_block_at_rest_slides_down_when_tan_theta_exceeds_mu(block):
    """mu = 0.3 < tan 0.5 from rest: the slip starts from rest against the sticking force (down the slope) and it
    slides straight down, s = -g (sin th - mu cos th) t^2 / 2."""
    th, mu = 0.5, 0.3
    run = andyc.simulate(block, 1.0, dt=1e-2, parameters={"v0": 0.0, "th": th, "mu": mu}, progress=False)
    assert run.finished and len(run.events["time"]) == 0 and np.all(run.contact_modes[:, 0] == SLIP)
    s, w = slope_coordinates(run, th)
    assert np.max(np.abs(s + G * (math.sin(th) - mu * math.cos(th)) * run.time ** 2 / 2)) < 1e-10
    assert np.max(np.abs(w)) < 1e-12
    assert run.column("slope_slip_dir_1")[0] == -1.0


# -- run files -----------------------------------------------------------------------------------------

def test_both_friction_forces_and_slips_go_into_the_run_files(block, tmp_path):
    run = andyc.simulate(block, 0.5, dt=1e-2, progress=False)
    run.save(tmp_path / "block.h5")
    run.save(tmp_path / "block.csv")
    with h5py.File(tmp_path / "block.h5") as f:
        assert np.array_equal(f["contacts/mode"][()], run.contact_modes)
        assert np.array_equal(f["contacts/friction_force_2"][()], run.friction_forces_2)
        assert np.array_equal(f["contacts/slip_speed_2"][()], run.slip_speeds_2)
    back = read_h5(tmp_path / "block.h5")
    assert back.contact_tangents == [2] and np.array_equal(back.friction_forces_2, run.friction_forces_2)
    assert np.array_equal(back.contact_modes, run.contact_modes)
    lines = (tmp_path / "block.csv").read_text().splitlines()
    header = next(line for line in lines if line.startswith("time,")).split(",")
    assert header[-5:] == ["mode_slope", "friction_force_slope", "slip_speed_slope", "friction_force_2_slope",
                           "slip_speed_2_slope"]
    first = [float(v) for v in lines[lines.index(",".join(header)) + 1].split(",")]
    assert first[-5] == SLIP and first[-3:] == [0.0, pytest.approx(-0.5 * G * math.cos(0.3), abs=1e-12), 1.0]


def test_every_dataset_attribute_and_column_of_a_run_file_is_in_the_run_file_reference(block, tmp_path):
    """docs/run-file.md lists what the files hold: each HDF5 dataset (a frame's as <frame>), each root attribute,
    and each CSV column as one of its patterns with the model's own names for <state>, <contact>, ... (a run with
    a contact, spatial friction and every frame logged)."""
    import re

    from tests.support import ROOT

    page = (ROOT / "docs" / "run-file.md").read_text(encoding="utf-8")
    run = andyc.simulate(block, 0.1, dt=1e-2, frames="all", progress=False)
    run.save(tmp_path / "block.h5")
    run.save(tmp_path / "block.csv")
    paths = []
    with h5py.File(tmp_path / "block.h5") as f:
        f.visititems(lambda name, item: paths.append(name) if isinstance(item, h5py.Dataset) else None)
        attributes = list(f.attrs)
    assert {"contacts/slip_speed_2", "event_states/state_after"} <= set(paths) and run.frames
    general = {f"frames/{n}": "frames/<frame>" for n in run.frames}
    general.update({f"frame_rotations/{n}": "frame_rotations/<frame>" for n in run.frame_rotations})
    missing = [p for p in (general.get(p, p) for p in paths) if f"`/{p}`" not in page]
    root = page.split("## HDF5 attributes")[1].split("## CSV")[0]
    missing += [a for a in attributes if f"`{a}`" not in root]
    assert not missing, missing
    names = {"state": run.state_names, "discrete": run.discrete_names, "input": run.input_names,
             "multiplier": run.multiplier_names, "element": run.work_names, "contact": run.contact_names,
             "frame": list(run.frames)}
    patterns = [re.sub(r"<([a-z]+)>", lambda m: "(" + "|".join(map(re.escape, names[m.group(1)])) + ")",
                       re.escape(column)) for row in page.split("## CSV")[1].splitlines() if row.startswith("| `")
                for column in re.findall(r"`([^`]+)`", row.split(" | ")[0])]
    header = next(line for line in (tmp_path / "block.csv").read_text().splitlines() if line.startswith("time,"))
    undocumented = [c for c in header.split(",") if not any(re.fullmatch(p, c) for p in patterns)]
    assert len(header.split(",")) > 20 and not undocumented, undocumented


# -- mistakes ------------------------------------------------------------------------------------------

# The shipped block without its expectations (which name its jumps, and the mistakes change them).
BLOCK = (MODELS / "block_incline_spatial.yaml").read_text().split("\n# andyc test:")[0] + "\n"


def problems(tmp_path: Path, text: str) -> list:
    path = tmp_path / "model.yaml"
    path.write_text(text)
    with pytest.raises(SpecError) as info:
        andyc.load(path)
    return info.value.diagnostics


def line_number(text: str, fragment: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if fragment in line)


def test_a_negative_mu_is_refused(tmp_path):
    text = BLOCK.replace("friction: mu", "friction: -mu")
    [d] = problems(tmp_path, text)
    assert (d.line, d.path) == (line_number(text, "friction: -mu"), "contacts[0].friction")
    assert d.message == "the friction coefficient is -mu = -0.5, negative" and d.hint.startswith("give Coulomb's")


def test_a_spatial_contact_beside_another_moves_as_alone(block, compiled, tmp_path):
    """A contact with spatial friction beside another (a wall the block never reaches): the block pushed across
    the slope moves as the block alone does, to rounding, and the wall stays open."""
    path = tmp_path / "block_and_wall.yaml"
    path.write_text(BLOCK.replace("name: block_incline_spatial", "name: block_and_wall")
                    + "  - {name: wall, gap: block.x + 10, multiplier: wall_force}\n")
    both = compiled(path)
    parameters = {"th": 0.3, "mu": 0.5}
    alone = andyc.simulate(block, 1.0, dt=1e-3, parameters=parameters, progress=False)
    run = andyc.simulate(both, 1.0, dt=1e-3, parameters=parameters, progress=False)
    assert run.finished and run.event_names() == alone.event_names() == ["slope_stop"]
    assert np.max(np.abs(run.state - alone.state)) < 1e-14 and np.all(run.contact_modes[:, 1] == OPEN)


def test_one_friction_name_for_two_tangents_is_refused(tmp_path):
    text = BLOCK.replace("    multiplier: normal_force\n", "    multiplier: normal_force\n    friction_multiplier: f\n")
    [d] = problems(tmp_path, text)
    assert (d.line, d.path) == (line_number(text, "friction_multiplier: f"), "contacts[0].friction_multiplier")
    assert d.message == "1 multiplier name(s) for 2 constraint row(s)" and d.hint == "give one name per row (2)"


@pytest.mark.parametrize("second, message", [
    ("2*cos(th)*block.vx + 2*sin(th)*block.vz", "the second slip speed of contact 'slope' is along its first at the "
     "initial state (its row is a multiple of the first's): the two do not span the tangent plane; write the contact "
     "point's speed along a second tangent"),
    ("cos(th)*block.vz - sin(th)*block.vx", "the second slip speed of contact 'slope' is along its gap's normal at "
     "the initial state (its row is a multiple of the gap row): it is not a tangential speed; write the speed of "
     "the contact point along the tangent")], ids=["parallel-to-the-first", "along-the-normal"])
def test_a_bad_second_tangent_is_reported_by_check(tmp_path, second, message):
    """`andyc check`: the second slip speed must be a second tangent, at the initial state."""
    from tests.support.cli import invoke

    text = BLOCK.replace("slip: [cos(th)*block.vx + sin(th)*block.vz, block.vy]",
                         f"slip: [cos(th)*block.vx + sin(th)*block.vz, {second}]")
    bad = tmp_path / "bad.yaml"
    bad.write_text(text)
    result = invoke("check", str(bad))
    assert result.exit_code == 1
    assert f"{bad}:{line_number(text, '    slip: [')}: contacts[0].slip[1]: {message}" in result.output
    result = invoke("check", str(MODELS / "block_incline_spatial.yaml"))
    assert result.exit_code == 0, result.output


# -- sticking, then slipping where the friction reaches the cone -------------------------------------------

PUCK = """\
name: puck_pushed
parameters: {m: 1.0, g: 9.81, mu: 0.4, c: 8.0, b: 0.6}
coordinates:
  x: {initial: 0}
  y: {initial: 0}
  z: {initial: 0}
gravity: [0, 0, -g]
frames:
  - {name: slide_x, parent: world, prismatic: x, axis: x}
  - {name: slide_y, parent: slide_x, prismatic: y, axis: y}
  - {name: puck, parent: slide_y, prismatic: z, axis: z}
bodies:
  - {name: mass, frame: puck, mass: m}
forces:
  - {name: push, frame: puck, vector: [c*t*cos(b), c*t*sin(b), 0]}
contacts:
  - {name: floor, gap: puck.z, slip: [puck.vx, puck.vy], friction: mu}
"""


@pytest.fixture(scope="module")
def puck(compiled, tmp_path_factory):
    path = tmp_path_factory.mktemp("puck") / "puck_pushed.yaml"
    path.write_text(PUCK)
    return compiled(path)


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_a_puck_pushed_harder_and_harder_sticks_then_slips_along_the_push(puck, method):
    """A force c t along (cos b, sin b) on a puck at rest on the floor: it sticks (friction -c t) until |lam_t|
    reaches mu m g at t1 = mu m g / c (the jump floor_slip, guard mu^2 lam_n^2 - |lam_t|^2), then slips along the
    push, its slip starting against the sticking force: m s'' = c t - mu m g, s = c (t - t1)^3 / (6 m)."""
    b, c = 0.6, 8.0
    run = andyc.simulate(puck, 1.0, dt=1e-3, method=method, rtol=1e-12, atol=1e-12, progress=False)
    t1 = 0.4 * G / c
    assert run.finished and run.event_names() == ["floor_slip"] and abs(run.events["time"][0] - t1) < 1e-10
    before, after = run.time < t1, run.time > t1
    assert np.all(run.contact_modes[before, 0] == STICK) and np.all(run.contact_modes[after, 0] == SLIP)
    assert np.max(np.abs(run.state[before, :3])) < 1e-12
    push = np.array([math.cos(b), math.sin(b)])
    expected = c * (run.time[after] - t1) ** 3 / 6
    xy = np.stack([run.column("x"), run.column("y")], axis=1)[after]
    # (DOP853 starts the slip with steps its error control sizes by atol = 1e-12 on speeds of that order: 3e-10 m)
    assert np.max(np.abs(xy - expected[:, None] * push)) < (1e-10 if method == "rk4" else 1e-9)
    friction = np.stack([run.friction_forces[:, 0], run.friction_forces_2[:, 0]], axis=1)
    assert np.max(np.abs(friction[before] + c * run.time[before, None] * push)) < 1e-10
    assert np.allclose(np.linalg.norm(friction[after], axis=1), 0.4 * G, rtol=0, atol=1e-10)
    # along -push: at the slip's first samples the slip is slow (1e-6 m/s) and its direction within 5e-5 rad of the
    # push (rk4 holds the direction predicted at each step's end while the slip is too slow for its step:
    # numerics.dynamics.slip_direction; DOP853 follows it with the steps its error control sizes over every
    # integrated quantity, the friction's work among them: measured 3.4e-5 rad), an error that the friction itself
    # damps as the slip grows: 1e-10 at 1 s
    assert np.max(np.abs(friction[after] + 0.4 * G * push)) < 2e-4
    assert np.max(np.abs(friction[-1] + 0.4 * G * push)) < 1e-10


def test_the_held_slip_direction_solves_the_implicit_step():
    """numerics.slipping.held_direction, the direction a fixed step holds a slow spatial slip in: an implicit step
    s1 = z - H s1 / |s1| (H = h mu lam_n J_t M^-1 J_t^T). Against SciPy's root finder on that equation, for random
    anisotropic H (condition numbers to 1e6): the same direction (1e-9), and no slip (False) exactly where
    |H^-1 z| <= 1, where the equation has no root with |s1| > 0. A z of the form (beta I + H) d, beta > 0, a slip
    whose acceleration keeps its direction d, gives d back; an isotropic H gives z / |z|."""
    from scipy.optimize import root

    from andyc.numerics.slipping import held_direction
    rng = np.random.default_rng(38)
    slips = 0
    for _ in range(200):
        Q = np.linalg.qr(rng.normal(size=(2, 2)))[0]
        H = Q @ np.diag([1.0, 10.0 ** rng.uniform(-6, 0)]) @ Q.T * 10.0 ** rng.uniform(-3, 3)
        z = rng.normal(size=2) * np.linalg.norm(H) * 10.0 ** rng.uniform(-1, 1)
        ok, u1, u2 = held_direction(H[0, 0], H[0, 1], H[1, 1], *z)
        inside = np.linalg.norm(np.linalg.solve(H, z))
        if abs(inside - 1.0) < 1e-6:
            continue
        assert ok == (inside > 1.0)
        if ok:
            slips += 1
            s1 = root(lambda s: s + H @ s / np.linalg.norm(s) - z, z, method="lm", tol=1e-15).x
            assert np.linalg.norm(s1 + H @ s1 / np.linalg.norm(s1) - z) < 1e-10 * np.linalg.norm(z)
            assert np.linalg.norm([u1, u2] - s1 / np.linalg.norm(s1)) < 1e-9
        d = rng.normal(size=2)
        d /= np.linalg.norm(d)
        beta = np.linalg.norm(H) * 10.0 ** rng.uniform(-6, 2)
        ok, u1, u2 = held_direction(H[0, 0], H[0, 1], H[1, 1], *((beta * np.eye(2) + H) @ d))
        assert ok and np.linalg.norm([u1 - d[0], u2 - d[1]]) < 1e-9
    assert slips > 50
    ok, u1, u2 = held_direction(2.0, 0.0, 2.0, 3.0, -4.0)
    assert ok and abs(u1 - 0.6) < 1e-15 and abs(u2 + 0.8) < 1e-15
