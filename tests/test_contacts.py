"""Contacts that come and go (issue 21), against closed forms.

- multipliers in guards: a block lifted off the ground by a force growing in time leaves where its normal
  force, m g - c t, reaches zero;
- the bouncing ball with the ground as a contact: the impact times of the hand-written model, then at rest
  from the accumulation point on;
- a rod falling flat onto two supports: both impacts solved together;
- a spring-leg hopper: touchdown, stance and liftoff where the normal force vanishes, the stance time against
  the closed form of the spring-mass stance;
- the ball's contact beside a hand-written automaton of its own phases;
- the mistakes of a `contacts:` section, one line each.
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

G = 9.81

LIFTED_BLOCK = """\
name: lifted_block
parameters: {m: 2.0, g: 9.81, c: 4.0}
coordinates: {y: {initial: 0}}
gravity: [0, -g, 0]
frames:
  - {name: block, parent: world, prismatic: y, axis: y}
bodies:
  - {name: mass, frame: block, mass: m}
forces:
  - {name: lift, frame: block, vector: [0, c*t, 0]}
constraints:
  - {name: ground, holonomic: y, multiplier: fn}
hybrid:
  flows:
    - {name: rest, constraints: [ground]}
    - {name: held, constraints: [ground]}
    - {name: air}
  jumps:
    - {name: liftoff, from: held, to: air, guard: fn, direction: falling}
    - {name: light, from: rest, to: held, guard: t - 1, direction: rising, enabled: fn < 15}
    - {name: heavy, from: rest, to: held, guard: t - 2, direction: rising, enabled: fn < 12}
"""


def write(tmp_path: Path, text: str, name: str = "model.yaml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


def problems(tmp_path: Path, text: str) -> list:
    """The diagnostics of loading `text` (which must fail)."""
    with pytest.raises(SpecError) as info:
        andyc.load(write(tmp_path, text))
    return info.value.diagnostics


# -- multipliers in guards ------------------------------------------------------------

@pytest.fixture(scope="module")
def lifted_block(compiled, tmp_path_factory):
    return compiled(write(tmp_path_factory.mktemp("lifted"), LIFTED_BLOCK, "lifted_block.yaml"))


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_liftoff_where_the_normal_force_reaches_zero(lifted_block, method):
    m, c = 2.0, 4.0
    t_star = m * G / c                                  # m g - c t = 0
    run = andyc.simulate(lifted_block, 8.0, dt=1e-2, method=method, rtol=1e-12, atol=1e-12, progress=False)
    assert run.finished
    # enabling conditions read the multipliers too: fn = 15.62 at t = 1 (not < 15), 11.62 at t = 2 (< 12)
    assert run.event_names() == ["heavy", "liftoff"]
    assert abs(run.events["time"][0] - 2.0) < 1e-11
    assert abs(run.events["time"][1] - t_star) < 1e-11
    resting = run.flow != 2
    assert np.allclose(run.multipliers[resting, 0], m * G - c * run.time[resting], rtol=0, atol=1e-12)
    assert np.all(run.multipliers[resting, 0] >= 0)      # the ground pushes: the sign of docs/model-file.md
    # then y'' = c (t - t*) / m: a cubic, which RK4 integrates exactly
    flying = run.time > t_star
    exact = c * (run.time[flying] - t_star) ** 3 / (6 * m)
    assert np.max(np.abs(run.column("y")[flying] - exact)) < (1e-10 if method == "rk4" else 1e-8)


def test_a_multiplier_of_a_constraint_not_active_in_the_source_flow(tmp_path):
    text = LIFTED_BLOCK.replace("{name: liftoff, from: held, to: air, guard: fn",
                                "{name: liftoff, from: air, to: held, guard: fn")
    [d] = problems(tmp_path, text)
    assert (d.line, d.path) == (text.splitlines().index(next(line for line in text.splitlines()
                                                              if "guard: fn" in line)) + 1, "hybrid.jumps[0].guard")
    assert d.message == ("multiplier 'fn' of constraint 'ground' has no value in flow 'air', the jump's source: the "
                         "constraint is not active there")
    assert "add 'ground' to its 'constraints'" in d.hint


def test_an_unknown_name_in_a_guard_lists_the_source_flows_multipliers(tmp_path):
    [d] = problems(tmp_path, LIFTED_BLOCK.replace("guard: fn,", "guard: fnn,"))
    assert d.message == "in 'fnn': unknown name 'fnn'"
    assert d.hint.startswith("did you mean 'fn'? names allowed here: c, fn, g, m, pi, t, y, y_dot")


# -- the bouncing ball comes to rest ------------------------------------------------------

H0, E = 1.0, 0.8
T1 = math.sqrt(2 * H0 / G)
T_INF = T1 * (1 + 2 * E / (1 - E))


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_bouncing_ball_comes_to_rest(compiled, method, tmp_path):
    model = compiled("bouncing_ball_contact")
    run = andyc.simulate(model, 10.0, dt=1e-3, method=method, rtol=1e-12, atol=1e-12, progress=False)
    assert run.finished and run.time[-1] == 10.0
    times = run.events["time"]
    expected = T1 + np.concatenate([[0.0], np.cumsum(2 * E ** np.arange(1, 20) * T1)])
    assert np.max(np.abs(times[:20] - expected)) < 1e-9       # as models/bouncing_ball.yaml
    before, after = run.events["state_before"][:-1, 1], run.events["state_after"][:-1, 1]
    assert np.allclose(after, -E * before, rtol=1e-12, atol=0)  # each bounce keeps e of the speed
    # the last impact, within the Zeno tolerance of the accumulation point, is plastic and closes the contact
    after = [run.event_modes(k) for k in range(len(times))]
    assert after[-1] == [1] and all(m == [0] for m in after[:-1])
    assert 0 <= T_INF - times[-1] < 1e-6
    resting = run.time >= T_INF
    assert np.all(run.contact_modes[resting, 0] == 1)
    assert np.max(np.abs(run.column("y")[resting])) < 1e-12
    assert np.max(np.abs(run.multipliers[resting, 0] - G)) < 1e-10       # m g, m = 1
    assert np.all(run.column("y") > -1e-12)
    # the run file says which contact is closed (from the last impact on) and its normal force (0 while open)
    assert run.contact_names == ["ground"] and run.discrete_names == ["ground_mode"]
    assert np.array_equal(run.contact_closed[:, 0] == 1, run.time >= times[-1])
    assert np.all(run.normal_forces[run.contact_closed[:, 0] == 0, 0] == 0.0)
    run.save(tmp_path / "ball.h5")
    run.save(tmp_path / "ball.csv")
    with h5py.File(tmp_path / "ball.h5") as f:
        assert np.array_equal(f["contacts/closed"][()], run.contact_closed)
        assert np.array_equal(f["contacts/normal_force"][()], run.normal_forces)
    back = read_h5(tmp_path / "ball.h5")
    assert back.contact_names == ["ground"] and np.array_equal(back.normal_forces, run.normal_forces)
    header = next(line for line in (tmp_path / "ball.csv").read_text().splitlines() if line.startswith("time,"))
    assert header.endswith("closed_ground,normal_force_ground")


def test_a_ball_starting_on_the_ground_stays_there(compiled):
    model = compiled("bouncing_ball_contact")
    run = andyc.simulate(model, 10.0, dt=1e-3, parameters={"h0": 0.0}, progress=False)
    assert run.finished and len(run.events["time"]) == 0 and np.all(run.contact_modes[:, 0] == 1)
    assert np.max(np.abs(run.column("y"))) == 0.0
    assert np.max(np.abs(run.normal_forces[:, 0] - G)) < 1e-10
    # held above it, it falls
    run = andyc.simulate(model, 1.0, dt=1e-3, parameters={"h0": 1e-6}, progress=False)
    assert run.contact_modes[0, 0] == 0 and run.events["time"][0] == pytest.approx(math.sqrt(2e-6 / G), abs=1e-12)


# -- simultaneous impacts ------------------------------------------------------------------

def rod_impact_speed(h0=0.5):
    return math.sqrt(2 * G * h0)


def one_end_impact(e, L=1.0, m=1.0):
    """(y', th') after the left end alone takes the impact of the rod falling flat at speed v (Newton's law on
    that end only), as a sequential scheme would do first: J = [1, -L/2] at th = 0, M = diag(m, m L^2 / 12)."""
    v = -rod_impact_speed()
    M = np.diag([m, m * L ** 2 / 12])
    J = np.array([[1.0, -L / 2]])
    Minv = np.linalg.inv(M)
    lam = -(1 + e) * (J @ [v, 0.0]) / (J @ Minv @ J.T)
    return np.array([v, 0.0]) + Minv @ J.T @ lam.ravel()


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_rod_falling_flat_strikes_both_supports_together(compiled, e):
    model = compiled("rod_drop")
    run = andyc.simulate(model, 3.0, dt=1e-3, parameters={"e": e}, progress=False)
    assert run.finished
    v = rod_impact_speed()
    assert run.events["time"][0] == pytest.approx(math.sqrt(2 * 0.5 / G), abs=1e-12)
    after = run.events["state_after"][0]                 # y, th, y_dot, th_dot
    assert abs(after[3]) < 1e-12 and np.max(np.abs(run.column("th"))) < 1e-12   # it never turns
    assert after[2] == pytest.approx(e * v, rel=1e-12, abs=1e-12)               # up at e times its speed
    # taken one after the other, the first impact alone would set it spinning
    assert abs(one_end_impact(e)[1]) > 1.0
    # at the end it rests on both supports, each carrying half its weight
    assert list(run.contact_modes[-1]) == [1, 1] and run.flow_names == ["default"]
    assert np.allclose(run.normal_forces[-1], [G / 2, G / 2], rtol=0, atol=1e-10)
    assert abs(run.column("y")[-1]) < 1e-12
    if e == 0.0:
        assert len(run.events["time"]) == 1 and run.event_modes(0) == [1, 1]


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_a_tilted_rod_lands_on_one_end_then_the_other_and_no_support_pulls(compiled, e):
    model = compiled("rod_drop")
    x0 = np.array([0.5 + 0.5 * math.sin(0.2), 0.2, 0.0, 0.0])          # tilted 0.2 rad, the left end lower
    run = andyc.simulate(model, 4.0, dt=1e-3, parameters={"e": e}, x0=x0, progress=False)
    assert run.finished
    assert run.event_names()[:2] == ["left_impact", "right_impact"]
    assert run.event_modes(0) == [1 if e == 0 else 0, 0]     # plastic: the left end stays; else it bounces
    p = model.parameters({"e": e})
    u, d = model.input_defaults, model.initial_discrete(p)
    for t, before, after in zip(run.events["time"], run.events["state_before"], run.events["state_after"]):
        # the impulses, from M (v+ - v-) = A^T Lam, and the normal speeds after, of the supports touched
        M = model.module.mass_matrix(t, before, u, p, d)
        phi, c, A, kappa = np.empty(2), np.empty(2), np.empty((2, 2)), np.empty(2)
        model.module.constraints(t, before, u, p, d, phi, c, A, kappa)
        impulse = np.linalg.lstsq(A.T, M @ (after[2:] - before[2:]), rcond=None)[0]
        assert np.all(impulse >= -1e-12)
        touching = np.abs(phi) < 1e-9
        assert np.all((A @ after[2:])[touching] >= -1e-12)
    # it ends at rest on both, level, each carrying half its weight
    assert list(run.contact_modes[-1]) == [1, 1] and abs(run.column("th")[-1]) < 1e-9
    assert np.allclose(run.normal_forces[-1], [G / 2, G / 2], rtol=0, atol=1e-9)


# -- hopper -----------------------------------------------------------------------------

def stance_time(M=1.0, mf=0.1, k=1000.0, l0=1.0, h=0.5):
    """The spring-mass stance: the foot lands at speed sqrt(2 g h) with the leg at rest length; the body then
    moves as y = y* + A cos(w s) + B sin(w s) about y* = l0 - M g / k, w = sqrt(k / M), until the normal force
    mf g + k (l0 - y) is zero, at y = l0 + mf g / k, on its way up."""
    w = math.sqrt(k / M)
    y_star = l0 - M * G / k
    A, B = l0 - y_star, -math.sqrt(2 * G * h) / w
    R, phi = math.hypot(A, B), math.atan2(B, A)
    D = l0 + mf * G / k - y_star
    return (2 * math.pi - math.acos(D / R) + phi) / w


@pytest.mark.parametrize("method, dt", [("rk4", 1e-4), ("DOP853", 1e-3)])
def test_hopper_stance_time_and_liftoff_on_the_normal_force(compiled, method, dt):
    model = compiled("hopper_contact")
    run = andyc.simulate(model, 1.2, dt=dt, method=method, rtol=1e-13, atol=1e-13, progress=False)
    assert run.finished
    names = run.event_names()
    assert names[:4] == ["ground_impact", "ground_liftoff", "ground_impact", "ground_liftoff"]
    t = run.events["time"]
    assert t[0] == pytest.approx(math.sqrt(2 * 0.5 / G), abs=1e-12)     # touchdown, after a free fall
    assert abs((t[1] - t[0]) - stance_time()) < 1e-9
    assert run.event_modes(0) == [1] and run.event_modes(1) == [0]
    stance = run.contact_modes[:, 0] == 1
    assert np.all(run.normal_forces[stance, 0] > -1e-9)                   # the ground never pulls
    assert np.all(run.column("yf") > -1e-12)


# -- mistakes ------------------------------------------------------------------------------

# The shipped ball without its expectations (which name its jumps: a renamed contact would break them too).
BALL = (Path(__file__).resolve().parents[1] / "models" / "bouncing_ball_contact.yaml").read_text()
BALL = BALL.split("\n# andyc test:")[0] + "\n"
CONTACT_LINE = "  - {name: ground, gap: ball.y, restitution: e, multiplier: normal_force}"


def line_number(text: str, fragment: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if fragment in line)


@pytest.mark.parametrize("entry, path, message, hint", [
    ("{name: ground, gap: h0, restitution: e}", "contacts[0].gap",
     "the gap 'h0' does not depend on the coordinates or any frame position", "a contact's gap is the signed distance"),
    ("{name: ground, gap: ball.y, restitution: 1.5}", "contacts[0].restitution",
     "the coefficient of restitution is 1.5, outside [0, 1]", "give 0 (plastic) to 1 (elastic)"),
    ("{name: ground, gap: ball.y, restitution: -e}", "contacts[0].restitution",
     "the coefficient of restitution is -e = -0.8, outside [0, 1]", "give 0 (plastic) to 1 (elastic)"),
    ("{name: ground, gap: bal.y, restitution: e}", "contacts[0].gap",
     "in 'bal.y': frame 'bal' does not exist", "did you mean 'ball'?"),
    ("{name: ground, gap: yy, restitution: e}", "contacts[0].gap",
     "in 'yy': unknown name 'yy'", "did you mean 'y'?"),
], ids=["no-coordinate", "restitution-above-1", "restitution-negative", "unknown-frame", "unknown-name"])
def test_contact_mistakes(tmp_path, entry, path, message, hint):
    text = BALL.replace(CONTACT_LINE, f"  - {entry}")
    [d] = problems(tmp_path, text)
    assert (d.line, d.path, d.message) == (line_number(text, entry), path, message)
    assert d.hint.startswith(hint)
    assert str(d).startswith(f"{tmp_path / 'model.yaml'}:{d.line}: {path}: {message}; ")


def test_a_contact_whose_mode_state_name_is_taken(tmp_path):
    """A contact's mode is the discrete state <contact>_mode: a name the model uses already is reported."""
    text = BALL.replace("coordinates:", "discrete: {ground_mode: 0}\ncoordinates:")
    found = problems(tmp_path, text)
    d = next(d for d in found if d.path == "contacts[0].name")
    assert d.line == line_number(text, "{name: ground, gap:")
    assert d.message == "contact 'ground' needs the name 'ground_mode' (a discrete state of its own), which is taken"


def test_a_flow_cannot_list_a_contacts_row(tmp_path):
    text = BALL + "hybrid:\n  flows:\n    - {name: flight, constraints: [ground]}\n"
    [d] = problems(tmp_path, text)
    assert (d.line, d.path) == (line_number(text, "constraints: [ground]"), "hybrid.flows[0].constraints[0]")
    assert d.message.startswith("'ground' is a contact's row, which the run closes and opens by itself")


BALL_WITH_PHASES = BALL + """\
hybrid:
  flows:
    - {name: high}
    - {name: low}
  jumps:
    - {name: down, from: high, to: low, guard: y - 0.5, direction: falling}
    - {name: up, from: low, to: high, guard: y - 0.5, direction: rising}
"""


def test_contacts_beside_a_hand_written_automaton(compiled, tmp_path_factory):
    """The ball's contact works in every flow of the user's own automaton (two phases, above and below half the
    drop height): the impacts come at the closed-form times, the phases switch where the closed-form parabolas
    cross y = 0.5 (the first bounce's apex, e^2 h0 = 0.64, is above it; the next, 0.41, is not), and the ball comes
    to rest closed, as without the automaton."""
    model = compiled(write(tmp_path_factory.mktemp("phases"), BALL_WITH_PHASES, "ball_phases.yaml"))
    run = andyc.simulate(model, 6.0, dt=1e-3, progress=False)
    assert run.finished and run.flow_names == ["high", "low"]
    names = run.event_names()
    impacts = run.events["time"][[n == "ground_impact" for n in names]]
    expected = T1 + np.concatenate([[0.0], np.cumsum(2 * E ** np.arange(1, 10) * T1)])
    assert np.max(np.abs(impacts[:10] - expected)) < 1e-9
    assert names[:6] == ["down", "ground_impact", "up", "down", "ground_impact", "ground_impact"]
    v1 = E * math.sqrt(2 * G * H0)                       # up at e times the impact speed
    rise = (v1 - math.sqrt(v1 ** 2 - 2 * G * 0.5)) / G    # y = v1 s - g s^2 / 2 = 0.5, going up, then down
    fall = (v1 + math.sqrt(v1 ** 2 - 2 * G * 0.5)) / G
    crossings = [math.sqrt(2 * (H0 - 0.5) / G), T1 + rise, T1 + fall]
    assert np.max(np.abs(run.events["time"][[0, 2, 3]] - crossings)) < 1e-9
    assert list(run.events["from_flow"][:4]) == [0, 1, 1, 0] and list(run.events["to_flow"][:4]) == [1, 1, 0, 1]
    assert run.flow[-1] == 1 and run.contact_modes[-1, 0] == 1 and abs(run.column("y")[-1]) < 1e-12
