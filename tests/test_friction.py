"""Coulomb friction at contacts (issue 21, planar), against closed forms.

- a block on an incline (models/block_incline.yaml): it sticks when mu > tan th, else slides down at
  g (sin th - mu cos th); on flat ground, pushed at v0, it stops at v0 / (mu g) and stays; pushed up the slope
  it stops at v0 / (g (sin th + mu cos th)), then sticks or slides back by the same rule;
- a ball thrown sliding and spinning (models/ball_rolling.yaml): it rolls from t* on;
- a ball striking the ground obliquely: Newton's impact law on the normal impulse, Coulomb's bound on the
  tangential one, against the closed-form impact map;
- run files and the mistakes of a friction contact.

Every closed form is elementary rigid-body mechanics (e.g. Meriam & Kraige, Engineering Mechanics: Dynamics,
§3/5 friction, §6/4 rolling with slipping; the impact map: Brach, Mechanical Impact Dynamics, 1991, ch. 3,
Newton's restitution with Coulomb's bound |P_t| <= mu P_n).
"""

from __future__ import annotations

import math
from pathlib import Path

import h5py
import numpy as np
import pytest

import andyc
from andyc.errors import SimulationError, SpecError
from andyc.runtime.runfiles import read_h5

G = 9.81
TH = 0.5                                    # the incline's angle (tan th = 0.546)
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3


def along_slope(run, th=TH) -> np.ndarray:
    """The block's position along the slope (up positive): t . p, t = (cos th, sin th)."""
    return math.cos(th) * run.column("x") + math.sin(th) * run.column("y")


def gap(run, th=TH) -> np.ndarray:
    return math.cos(th) * run.column("y") - math.sin(th) * run.column("x")


@pytest.fixture(scope="module")
def block(compiled):
    return compiled("block_incline")


@pytest.fixture(scope="module")
def ball(compiled):
    return compiled("ball_rolling")


# -- a block on an incline ------------------------------------------------------------------

def test_block_sticks_when_mu_exceeds_tan_theta(block):
    """mu = 0.7 > tan 0.5 = 0.546: static equilibrium, lam_t = m g sin th (up the slope), lam_n = m g cos th."""
    run = andyc.simulate(block, 5.0, dt=1e-2, parameters={"mu": 0.7}, progress=False)
    assert run.finished and len(run.events["time"]) == 0
    assert np.all(run.contact_modes[:, 0] == STICK)
    assert np.max(np.hypot(run.column("x"), run.column("y"))) <= 1e-12          # moves <= 1e-12 m in 5 s
    assert np.max(np.abs(run.friction_forces[:, 0] - G * math.sin(TH))) < 1e-10
    assert np.max(np.abs(run.normal_forces[:, 0] - G * math.cos(TH))) < 1e-10
    assert np.max(np.abs(run.slip_speeds[:, 0])) <= 1e-12


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_block_slides_when_tan_theta_exceeds_mu(block, method):
    """mu = 0.3 < tan th: it slides down from rest, s(t) = -1/2 g (sin th - mu cos th) t^2 along the slope, the
    friction force +mu m g cos th (up the slope: it slips backwards), on the slope throughout."""
    mu = 0.3
    run = andyc.simulate(block, 1.0, dt=1e-2, method=method, rtol=1e-12, atol=1e-12, parameters={"mu": mu},
                         progress=False)
    assert run.finished and len(run.events["time"]) == 0
    assert np.all(run.contact_modes[:, 0] == SLIP_NEG)
    exact = -0.5 * G * (math.sin(TH) - mu * math.cos(TH)) * run.time ** 2
    assert np.max(np.abs(along_slope(run) - exact)) < 1e-10
    assert abs(along_slope(run)[-1] - exact[-1]) < 1e-10 and run.time[-1] == 1.0
    assert np.max(np.abs(gap(run))) < 1e-12
    assert np.max(np.abs(run.friction_forces[:, 0] - mu * G * math.cos(TH))) < 1e-10
    assert np.max(np.abs(run.slip_speeds[:, 0] + G * (math.sin(TH) - mu * math.cos(TH)) * run.time)) < 1e-10


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_block_pushed_on_flat_ground_stops_at_v0_over_mu_g(block, method):
    """th = 0, v0 = 1, mu = 0.3: x = v0 t - mu g t^2 / 2 until t1 = v0 / (mu g) (the slip's end, located like a
    guard), then at rest at x1 = v0^2 / (2 mu g), sticking with no friction force."""
    mu, v0 = 0.3, 1.0
    run = andyc.simulate(block, 2.0, dt=1e-2, method=method, rtol=1e-12, atol=1e-12,
                         parameters={"mu": mu, "th": 0.0, "v0": v0}, progress=False)
    assert run.finished and run.event_names() == ["slope_stop"]
    t1 = v0 / (mu * G)
    assert abs(run.events["time"][0] - t1) < 1e-10
    assert run.event_modes(0) == [STICK]
    x = run.column("x")
    sliding, resting = run.time < t1, run.time > t1
    assert np.max(np.abs(x[sliding] - (v0 * run.time[sliding] - mu * G * run.time[sliding] ** 2 / 2))) < 1e-10
    assert np.max(np.abs(x[resting] - v0 ** 2 / (2 * mu * G))) < 1e-10
    assert np.max(np.abs(run.column("x_dot")[resting])) == 0.0
    assert np.allclose(run.friction_forces[sliding, 0], -mu * G, rtol=0, atol=1e-12)
    assert np.max(np.abs(run.friction_forces[resting, 0])) < 1e-12


@pytest.mark.parametrize("mu", [0.3, 0.7])
def test_block_pushed_up_the_slope_stops_then_sticks_or_slides_back(block, mu):
    """v0 = 2 up the slope: it decelerates at g (sin th + mu cos th) and stops at t1 = v0 / that; then with
    mu > tan th it sticks, with mu < tan th it slides back at g (sin th - mu cos th)."""
    v0 = 2.0
    run = andyc.simulate(block, 1.5, dt=1e-3, parameters={"mu": mu, "v0": v0}, progress=False)
    assert run.finished
    up = G * (math.sin(TH) + mu * math.cos(TH))
    t1 = v0 / up
    s1 = v0 ** 2 / (2 * up)
    assert abs(run.events["time"][0] - t1) < 1e-10
    s, after = along_slope(run), run.time > t1
    if mu > math.tan(TH):
        assert run.event_names() == ["slope_stop"] and np.all(run.contact_modes[after, 0] == STICK)
        assert np.max(np.abs(s[after] - s1)) < 1e-10
        assert np.max(np.abs(run.friction_forces[after, 0] - G * math.sin(TH))) < 1e-10
    else:       # the stick is refused: the friction it would need, m g sin th, is outside the cone
        assert run.event_names() == ["slope_stop"] and run.event_modes(0) == [SLIP_NEG]
        down = G * (math.sin(TH) - mu * math.cos(TH))
        assert np.max(np.abs(s[after] - (s1 - down * (run.time[after] - t1) ** 2 / 2))) < 1e-9


# -- a ball sliding, then rolling ---------------------------------------------------------------

def rolling_time(v0, w0, mu=0.2, r=0.1):
    """t* = |v0 + r w0| / (mu g (1 + m r^2 / I)), I = 2/5 m r^2: the slip s = v + r w changes at
    -sign(s) mu g (1 + m r^2 / I) (friction -sign(s) mu m g at the contact point: dv/dt = -sign(s) mu g,
    dw/dt = -sign(s) mu m g r / I)."""
    return abs(v0 + r * w0) / (mu * G * (1 + 2.5))


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_ball_thrown_sliding_rolls_from_t_star(ball, method):
    """v0 = 2, no spin: t* = 2 v0 / (7 mu g), then rolling at v = 5 v0 / 7 (issue 21, item 3)."""
    v0, mu = 2.0, 0.2
    run = andyc.simulate(ball, 1.0, dt=1e-3, method=method, rtol=1e-12, atol=1e-12, progress=False)
    assert run.finished and run.event_names() == ["ground_stop"]
    t_star = 2 * v0 / (7 * mu * G)
    assert t_star == pytest.approx(rolling_time(v0, 0.0), rel=1e-15)
    assert abs(run.events["time"][0] - t_star) < 1e-10
    rolling = run.time > t_star
    assert np.max(np.abs(run.column("x_dot")[rolling] - 5 * v0 / 7)) < 1e-12
    assert np.max(np.abs(run.slip_speeds[rolling, 0])) < 1e-12
    assert np.all(run.contact_modes[rolling, 0] == STICK) and np.all(run.contact_modes[~rolling, 0] == SLIP_POS)
    assert np.max(np.abs(run.friction_forces[rolling, 0])) < 1e-12      # rolling on the flat needs no friction


@pytest.mark.parametrize("w0", [10.0, -40.0], ids=["backspin", "topspin"])
def test_a_spinning_ball_rolls_from_its_t_star(ball, w0):
    """v0 = 2 with spin w0 (counter-clockwise): slip v0 + r w0 = 3 (forwards) or -2 (backwards, friction pushing it
    on); t* = |v0 + r w0| / (mu g (1 + m r^2 / I)), then v = r (-w): rolling."""
    run = andyc.simulate(ball, 1.0, dt=1e-3, parameters={"w0": w0}, progress=False)
    assert run.finished and len(run.events["time"]) == 1
    t_star = rolling_time(2.0, w0)
    assert abs(run.events["time"][0] - t_star) < 1e-9
    slip = 2.0 + 0.1 * w0
    assert run.contact_modes[0, 0] == (SLIP_POS if slip > 0 else SLIP_NEG)
    v_end = 2.0 - math.copysign(0.2 * G, slip) * t_star
    assert abs(run.column("x_dot")[-1] - v_end) < 1e-12
    assert abs(run.column("x_dot")[-1] + 0.1 * run.column("th_dot")[-1]) < 1e-12


# -- friction at impact ---------------------------------------------------------------------------

def impact_map(vx, vy, w, e, mu=0.2, m=1.0, r=0.1):
    """(vx+, vy+, w+, P_n, P_t, sticking) of a ball (I = 2/5 m r^2) striking the ground at (vx, vy < 0, w): Newton,
    P_n = -(1 + e) m vy; the tangential impulse that stops the slip s = vx + r w, P* = -s / (1/m + r^2/I), if
    |P*| <= mu P_n, else Coulomb's P_t = -sign(s) mu P_n (Brach 1991, ch. 3)."""
    inertia = 0.4 * m * r ** 2
    pn = -(1 + e) * m * vy
    p_stick = -(vx + r * w) / (1 / m + r ** 2 / inertia)
    sticking = abs(p_stick) <= mu * pn
    pt = p_stick if sticking else -math.copysign(mu * pn, vx + r * w)
    return vx + pt / m, vy + pn / m, w + r * pt / inertia, pn, pt, sticking


@pytest.mark.parametrize("w0, e", [(0.0, 0.0), (0.0, 0.5), (30.0, 0.0), (30.0, 0.5), (-60.0, 0.0), (-60.0, 0.8)])
def test_oblique_impact_bounds_the_tangential_impulse_by_mu_p_n(ball, w0, e):
    """Dropped from 0.2 m with v0 = 1 and spin w0: at the impact the normal speed reverses to -e of its value, and
    the slip stops if Coulomb's cone allows (a sticking impact), else the tangential impulse is mu P_n, opposing
    the slip, which keeps its sign; closed contact (e = 0) then sticks or slips on its way."""
    run = andyc.simulate(ball, 0.25, dt=1e-3, parameters={"h0": 0.2, "e": e, "w0": w0, "v0": 1.0}, progress=False)
    assert run.finished and run.event_names()[0] == "ground_impact"
    before, after = run.events["state_before"][0], run.events["state_after"][0]    # x, y, th, x', y', th'
    assert before[4] == pytest.approx(-math.sqrt(2 * G * 0.2), rel=1e-12)
    vx, vy, w, pn, pt, sticking = impact_map(before[3], before[4], before[5], e)
    assert np.allclose(after[3:], [vx, vy, w], rtol=0, atol=1e-12)
    assert abs(pt) <= 0.2 * pn * (1 + 1e-12)                          # inside the cone
    assert abs(after[3] - before[3]) <= 0.2 * pn + 1e-12                 # the impulse on the ball, m (vx+ - vx-)
    slip = after[3] + 0.1 * after[5]
    [mode] = run.event_modes(0)
    if e > 0:
        assert mode == OPEN
    else:
        assert mode == (STICK if sticking else SLIP_POS if slip > 0 else SLIP_NEG)
    assert sticking == (abs(slip) < 1e-12)
    assert sticking == (w0 == 0.0)            # no spin: stick; large spin: the cone is too narrow


# -- run files and plots ---------------------------------------------------------------------------

def test_friction_goes_into_the_run_files(block, tmp_path):
    run = andyc.simulate(block, 1.0, dt=1e-2, parameters={"mu": 0.3, "th": 0.0, "v0": 1.0}, progress=False)
    run.save(tmp_path / "block.h5")
    run.save(tmp_path / "block.csv")
    with h5py.File(tmp_path / "block.h5") as f:
        assert np.array_equal(f["contacts/mode"][()], run.contact_modes)
        assert np.array_equal(f["contacts/friction_force"][()], run.friction_forces)
        assert np.array_equal(f["contacts/slip_speed"][()], run.slip_speeds)
    back = read_h5(tmp_path / "block.h5")
    assert np.array_equal(back.friction_forces, run.friction_forces) and back.contact_mu == [0.3]
    assert np.array_equal(back.contact_modes, run.contact_modes)
    lines = (tmp_path / "block.csv").read_text().splitlines()
    header = next(line for line in lines if line.startswith("time,")).split(",")
    assert header[-3:] == ["mode_slope", "friction_force_slope", "slip_speed_slope"]
    first = [float(v) for v in lines[lines.index(",".join(header)) + 1].split(",")]
    assert first[-3:] == [SLIP_POS, -0.3 * G, 1.0]


# -- mistakes --------------------------------------------------------------------------------------

# The shipped block without its expectations (which name its jumps, and the mistakes change them).
BLOCK = (Path(__file__).resolve().parents[1] / "models" / "block_incline.yaml").read_text()
BLOCK = BLOCK.split("\n# andyc test:")[0] + "\n"


def problems(tmp_path: Path, text: str) -> list:
    path = tmp_path / "model.yaml"
    path.write_text(text)
    with pytest.raises(SpecError) as info:
        andyc.load(path)
    return info.value.diagnostics


def line_number(text: str, fragment: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if fragment in line)


@pytest.mark.parametrize("old, new, path, message, hint", [
    ("friction: mu", "friction: -mu", "contacts[0].friction", "the friction coefficient is -mu = -0.3, negative",
     "give Coulomb's coefficient mu >= 0"),
    ("friction: mu", "friction: mu*t", "contacts[0].friction", "the friction coefficient 'mu*t' depends on t",
     "give a constant >= 0"),
    ("    slip: cos(th)*block.vx + sin(th)*block.vy\n", "", "contacts[0].friction",
     "a contact with friction needs its slip speed", "add 'slip:'"),
    ("    friction: mu\n", "", "contacts[0].slip", "'slip' without 'friction' has no effect", "add 'friction: mu'"),
    ("slip: cos(th)*block.vx + sin(th)*block.vy", "slip: block.x", "contacts[0].slip",
     "the slip speed 'block.x' uses no speed or velocity", "a contact's slip is the speed of its contact point"),
], ids=["negative-mu", "mu-of-t", "friction-without-slip", "slip-without-friction", "slip-not-a-speed"])
def test_friction_mistakes(tmp_path, old, new, path, message, hint):
    text = BLOCK.replace(old, new)
    [d] = problems(tmp_path, text)
    key = path.split(".")[-1]
    assert (d.line, d.path, d.message) == (line_number(text, f"    {key}:"), path, message)
    assert d.hint.startswith(hint)
    assert str(d).startswith(f"{tmp_path / 'model.yaml'}:{d.line}: {path}: {message}; ")


def test_contacts_with_friction_are_not_limited_in_number(tmp_path):
    """Each contact is a discrete state and a few jumps of its own, not a factor in a count of modes: three
    contacts with planar friction and one without load (they were 4 x 4 x 4 x 2 = 128 enumerated flows before),
    with one flow, a mode state per contact and its jumps: impact, liftoff, slip either way and stop with
    friction; impact and liftoff without."""
    entry = BLOCK[BLOCK.index("  - name: slope"):]
    frictionless = "  - {name: slope4, gap: block.y + 1, multiplier: nf4}\n"
    text = BLOCK + entry.replace("name: slope", "name: slope2").replace("normal_force", "nf2") + \
        entry.replace("name: slope", "name: slope3").replace("normal_force", "nf3") + frictionless
    path = tmp_path / "model.yaml"
    path.write_text(text)
    spec = andyc.load(path)
    assert [f.name for f in spec.flows] == ["default"]
    assert [x.name for x in spec.discrete] == ["slope_mode", "slope2_mode", "slope3_mode", "slope4_mode"]
    kinds = [j.name for j in spec.jumps]
    for c in ("slope", "slope2", "slope3"):
        assert [k for k in kinds if k.startswith(c + "_")] == [f"{c}_{k}" for k in
                                                               ("impact", "liftoff", "slip_pos", "slip_neg", "stop")]
    assert [k for k in kinds if k.startswith("slope4_")] == ["slope4_impact", "slope4_liftoff"]


# -- a slipping contact whose friction changes its normal force ------------------------------------------

ROD_SLIDE = """\
name: rod_slide
parameters: {m: 1.0, L: 1.0, g: 9.81, mu: 0.4, phi0: 1.0, v0: 1.0}
coordinates:
  x: {initial: 0, velocity: v0}
  y: {initial: L/2*sin(phi0)}
  phi: {initial: phi0}
gravity: [0, -g, 0]
frames:
  - {name: cx, parent: world, prismatic: x, axis: x}
  - {name: centre, parent: cx, prismatic: y, axis: y}
  - {name: rod, parent: centre, revolute: phi}
  - {name: foot, parent: rod, translation: [-L/2, 0, 0]}
bodies:
  - {name: bar, frame: rod, mass: m, inertia: [0, m*L**2/12, m*L**2/12]}
contacts:
  - {name: floor, gap: foot.y, slip: foot.vx, friction: mu, multiplier: normal}
"""


def rod_slide_reference(state, sigma, t0, t1, mu=0.4, m=1.0, L=1.0):
    """An independent integration (SciPy) of a rod whose lower end slides on the floor: centre (x, y = L/2 sin phi),
    friction F = -sigma mu N at the end. Newton-Euler: m x'' = F, m y'' = N - m g, I phi'' = -(L/2) cos phi N +
    (L/2) sin phi F (I = m L^2 / 12), with y'' = (L/2)(cos phi phi'' - sin phi phi'^2), solved for N and phi''
    (the friction's moment changes N: a slipping contact's force is not along its gap's gradient). Returns the
    dense solution of (x, x', phi, phi'), N(state), and the time the end's slip, x' + (L/2) sin phi phi', reaches 0
    (None if not before t1)."""
    from scipy.integrate import solve_ivp

    inertia = m * L ** 2 / 12

    def solve(s):
        _, _, phi, w = s
        K = np.array([[m * L / 2 * math.cos(phi), -1.0],
                      [inertia, L / 2 * (math.cos(phi) + sigma * mu * math.sin(phi))]])
        return np.linalg.solve(K, [m * L / 2 * math.sin(phi) * w ** 2 - m * G, 0.0])     # phi'', N

    def rhs(t, s):
        a, n = solve(s)
        return [s[1], -sigma * mu * n / m, s[3], a]

    def slip(t, s):
        return s[1] + L / 2 * math.sin(s[2]) * s[3]
    slip.terminal, slip.direction = True, -sigma       # towards zero from its side (it starts at 0 backwards)
    sol = solve_ivp(rhs, (t0, t1), state, method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True, events=slip)
    return sol.sol, (lambda s: solve(s)[1]), (sol.t_events[0][0] if len(sol.t_events[0]) else None)


@pytest.fixture(scope="module")
def rod_slide(compiled, tmp_path_factory):
    path = tmp_path_factory.mktemp("rod_slide") / "rod_slide.yaml"
    path.write_text(ROD_SLIDE)
    return compiled(path)


def test_a_slipping_rod_end_against_an_independent_integration(rod_slide):
    """A rod leaning at 1 rad, its lower end pushed along the floor at 1 m/s (mu = 0.4): it slides forwards, the
    friction's moment lowering its normal force (4.05 N against 5.23 N frictionless at the start); the slip ends,
    the stick is refused (the cone too narrow) and it slides backwards, then sticks. Each phase, and each slip's
    end, against rod_slide_reference."""
    run = andyc.simulate(rod_slide, 0.2, dt=1e-3, method="DOP853", rtol=1e-13, atol=1e-13, progress=False)
    assert run.finished and run.event_names() == ["floor_stop", "floor_stop"]
    assert [run.event_modes(k) for k in range(2)] == [[SLIP_NEG], [STICK]]
    t = np.concatenate([[0.0], run.events["time"]])
    starts = [np.array([0.0, 1.0, 1.0, 0.0])] + [run.events["state_after"][k][[0, 3, 2, 5]] for k in range(2)]
    for phase, sigma in enumerate([1.0, -1.0]):
        sol, normal, t_stop = rod_slide_reference(starts[phase], sigma, t[phase], 1.0)
        assert abs(t_stop - t[phase + 1]) < 1e-9
        inside = (run.time > t[phase]) & (run.time < t[phase + 1])
        ref = sol(run.time[inside])
        assert np.max(np.abs(run.column("x")[inside] - ref[0])) < 1e-9
        assert np.max(np.abs(run.column("phi")[inside] - ref[2])) < 1e-9
        n_ref = np.array([normal(ref[:, k]) for k in range(ref.shape[1])])
        assert np.max(np.abs(run.normal_forces[inside, 0] - n_ref)) < 1e-8
        assert np.allclose(run.friction_forces[inside, 0], -sigma * 0.4 * n_ref, rtol=0, atol=1e-8)
    frictionless = rod_slide_reference(starts[0], 1.0, 0.0, 0.01, mu=0.0)[1](starts[0])
    assert run.normal_forces[0, 0] == pytest.approx(4.0514, abs=1e-4) and frictionless == pytest.approx(5.2298, abs=1e-4)
    stuck = run.time > t[2]
    assert np.max(np.abs(run.slip_speeds[stuck, 0])) < 1e-12
    assert np.all(np.abs(run.friction_forces[stuck, 0]) <= 0.4 * run.normal_forces[stuck, 0])


def test_a_slip_along_the_normal_is_reported_by_check(tmp_path):
    """`andyc check`: a slip row parallel to the gap's (here the block's speed across the slope) is not a friction
    direction, at the initial state; the shipped block's is tangent and passes."""
    from tests.support.cli import invoke

    good = tmp_path / "good.yaml"
    good.write_text(BLOCK)
    bad = tmp_path / "bad.yaml"
    text = BLOCK.replace("slip: cos(th)*block.vx + sin(th)*block.vy", "slip: 2*cos(th)*block.vy - 2*sin(th)*block.vx")
    bad.write_text(text)
    result = invoke("check", str(good))
    assert result.exit_code == 0, result.output
    result = invoke("check", str(bad))
    assert result.exit_code == 1
    line = line_number(text, "    slip:")
    assert (f"{bad}:{line}: contacts[0].slip: the slip speed of contact 'slope' is along its gap's normal at the "
            "initial state (its row is a multiple of the gap row): it is not a tangential speed; write the speed of "
            "the contact point along the tangent") in result.output


# -- two contacts with friction ----------------------------------------------------------------------

ROD_SKID = ROD_SLIDE.replace("name: rod_slide", "name: rod_skid").replace(
    "parameters: {m: 1.0, L: 1.0, g: 9.81, mu: 0.4, phi0: 1.0, v0: 1.0}",
    "parameters: {m: 1.0, L: 1.0, g: 9.81, mu: 0.4, h0: 0.0, e: 0.0, v0: 1.0}").replace(
    "y: {initial: L/2*sin(phi0)}\n  phi: {initial: phi0}", "y: {initial: h0}\n  phi: {initial: 0}").replace(
    "  - {name: foot, parent: rod, translation: [-L/2, 0, 0]}\n",
    "  - {name: left_end, parent: rod, translation: [-L/2, 0, 0]}\n"
    "  - {name: right_end, parent: rod, translation: [L/2, 0, 0]}\n").replace(
    "  - {name: floor, gap: foot.y, slip: foot.vx, friction: mu, multiplier: normal}\n",
    "  - {name: left, gap: left_end.y, slip: left_end.vx, friction: mu, restitution: e}\n"
    "  - {name: right, gap: right_end.y, slip: right_end.vx, friction: mu, restitution: e}\n")


@pytest.fixture(scope="module")
def rod_skid(compiled, tmp_path_factory):
    path = tmp_path_factory.mktemp("rod_skid") / "rod_skid.yaml"
    path.write_text(ROD_SKID)
    return compiled(path)


def test_a_rod_skidding_on_two_supports_stops_on_both_at_once(rod_skid):
    """A rod lying on the floor on its two ends, pushed at v0 = 1 (mu = 0.4): both ends slip forwards,
    the rod decelerates at mu g and both slips end together at v0 / (mu g), where both ends stick (the second
    with the first, not left slipping at zero speed), at x = v0^2 / (2 mu g), each end carrying m g / 2 and no
    friction."""
    assert rod_skid.flow_names == ("default",) and rod_skid.contact_names == ("left", "right")
    run = andyc.simulate(rod_skid, 1.0, dt=1e-3, progress=False)
    assert run.finished and run.contact_modes[0].tolist() == [SLIP_POS, SLIP_POS]
    assert len(run.events["time"]) == 1 and abs(run.events["time"][0] - 1 / (0.4 * G)) < 1e-10
    assert run.event_modes(0) == [STICK, STICK]
    resting = run.time > 1 / (0.4 * G)
    assert np.all(run.contact_modes[resting] == STICK)
    assert np.max(np.abs(run.column("x")[resting] - 1 / (2 * 0.4 * G))) < 1e-12
    assert np.max(np.abs(run.friction_forces[resting])) < 1e-12
    assert np.allclose(run.normal_forces[resting], G / 2, rtol=0, atol=1e-10)
    assert np.max(np.abs(run.column("phi"))) < 1e-12


@pytest.mark.parametrize("vx", [1.0, 5.0])
def test_a_rod_falling_flat_while_moving_takes_both_impacts_with_friction(rod_skid, vx):
    """Falling flat from 0.5 m at horizontal speed vx onto both ends (e = 0): the normal impulses m v / 2 each
    (v = sqrt(2 g h0)); stopping the slide needs m vx in all, inside the cones iff vx <= mu v: then it sticks,
    else each end takes mu m v / 2 and it slides on at vx - mu v, level and slipping forwards."""
    run = andyc.simulate(rod_skid, 0.4, dt=1e-3, parameters={"h0": 0.5, "v0": vx}, progress=False)
    assert run.finished and run.event_names()[0] == "left_impact"
    v = math.sqrt(2 * G * 0.5)
    after = run.events["state_after"][0]                 # x, y, phi, x', y', phi'
    assert after[3] == pytest.approx(max(0.0, vx - 0.4 * v), abs=1e-12)
    assert abs(after[4]) < 1e-12 and abs(after[5]) < 1e-12
    mode = STICK if vx <= 0.4 * v else SLIP_POS
    assert run.event_modes(0) == [mode, mode]


@pytest.mark.parametrize("v0", [-1.0, 1.0])
def test_painleves_paradox_is_refused(rod_slide, v0):
    """The rod at 0.6 rad with mu = 3, its end slipping backwards (v0 = -1): A_n M^-1 (A_n + mu J_t)^T =
    1 + 3 cos phi (cos phi - mu sin phi) = -1.15 < 0, so no normal force is consistent (Painleve's paradox): the
    run refuses to start rather than open the contact and let the end sink. Slipping forwards (+1) it is
    consistent (1 + 3 cos phi (cos phi + mu sin phi) > 0) and the run goes on."""
    model, phi = rod_slide, 0.6
    k = 1 + 3 * math.cos(phi) * (math.cos(phi) + math.copysign(3.0, v0) * math.sin(phi))
    assert (k < 0) == (v0 < 0)
    parameters = {"mu": 3.0, "phi0": phi, "v0": v0}
    if v0 < 0:
        with pytest.raises(SimulationError, match="contact 'floor' at the start: a slipping contact's normal "
                           "force has no consistent value .Painleve's paradox"):
            andyc.simulate(model, 0.1, dt=1e-3, parameters=parameters, progress=False)
        # started slipping by hand (its mode in d0), the compiled right-hand side refuses it: the run stops at once
        d0 = model.initial_discrete(model.parameters(parameters))
        d0[model.discrete_names.index("floor_mode")] = SLIP_NEG
        run = andyc.simulate(model, 0.1, dt=1e-3, parameters=parameters, d0=d0, progress=False)
        assert run.status.startswith("stopped: a slipping contact's normal force has no consistent value")
        assert run.status.endswith("at t = 0 s, step 0; the 1 samples before it are kept")
    else:
        run = andyc.simulate(model, 0.1, dt=1e-3, parameters=parameters, progress=False)
        assert run.finished and run.contact_modes[0, 0] == SLIP_POS and run.normal_forces[0, 0] > 0
