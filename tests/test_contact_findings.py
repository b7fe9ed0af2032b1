"""Issue 38's findings about contacts, each a test: a mode the runtime chooses at the cone's edge holds (no stick
and slip in turn at one instant), the friction's work is in the energy balance, a contact that starts inside its
surface is refused by `check` and `sim` alike (or moved onto it with --init project), coefficients given at run
time are checked as the model file's are, `andyc cycle` refuses contacts before any build, and a gap with no real
value at the start is a located error."""

from __future__ import annotations

import math

import numpy as np
import pytest

import andyc
from andyc.errors import SimulationError
from tests.support import MODELS
from tests.support.cli import invoke

G = 9.81
STICK, SLIP_NEG = 1, 3


@pytest.fixture(scope="module")
def block(compiled):
    return compiled("block_incline")


@pytest.mark.parametrize("f", [1 - 1e-13, 1 + 1e-13])
def test_a_stick_chosen_at_the_cone_edge_holds(block, f):
    """A block at rest on a 0.5 rad incline with mu = tan(0.5) (1 -+ 1e-13): the friction it needs is on the cone's
    edge to a rounding. The run starts sticking (its choice of modes allows 1e-12 of the normal force) and stays:
    before, the slip jump fired at once for the rounding (mu lam_n - lam_t = -1e-15), undoing the choice; at a
    slip's end the same pair looped 101 times at one instant (a hopper's foot). Pushed up the slope, the block
    stops once and sticks, with no slip at that instant."""
    th = 0.5
    run = andyc.simulate(block, 0.2, dt=1e-3, parameters={"th": th, "mu": math.tan(th) * f}, progress=False)
    assert run.finished and run.event_names() == [] and np.all(run.contact_modes[:, 0] == STICK)
    assert np.max(np.abs(run.column("x"))) < 1e-12
    run = andyc.simulate(block, 1.0, dt=1e-3, parameters={"th": th, "mu": math.tan(th) * f, "v0": 1.0},
                         progress=False)
    stop = 1.0 / (G * (math.sin(th) + math.tan(th) * math.cos(th)))     # v0 / (g (sin th + mu cos th))
    assert run.finished and run.event_names() == ["slope_stop"] and abs(run.events["time"][0] - stop) < 1e-9
    assert run.event_modes(0) == [STICK] and np.all(run.contact_modes[run.time > stop, 0] == STICK)


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_the_friction_work_closes_the_energy_balance(block, method):
    """The block sliding down a 0.5 rad incline (mu = 0.3 < tan 0.5): the friction -mu m g cos th does the work
    -mu m g cos th |s| over the distance s slid (closed form), which the run integrates in its `friction` slot, so
    that E - E0 - W stays at the integration's error. (Before, the balance missed it: 0.44 J on a slipping hopper.)"""
    th, mu = 0.5, 0.3
    run = andyc.simulate(block, 1.0, dt=1e-3, method=method, rtol=1e-12, atol=1e-12,
                         parameters={"th": th, "mu": mu}, progress=False)
    s = math.cos(th) * run.column("x") + math.sin(th) * run.column("y")
    assert np.max(np.abs(s + 0.5 * G * (math.sin(th) - mu * math.cos(th)) * run.time ** 2)) < 1e-9
    friction = run.work[:, run.work_names.index("friction")]
    assert np.max(np.abs(friction + mu * G * math.cos(th) * np.abs(s))) < 1e-9
    assert friction[-1] < -1.0                                   # (what the balance missed: 1.5 J here)
    assert np.max(np.abs(run.energy_balance)) < 1e-9


SUNK = """\
name: sunk_ball
parameters: {m: 1.0, g: 9.81, h0: -1.0}
coordinates: {y: {initial: h0}}
gravity: [0, -g, 0]
frames: [{name: ball, parent: world, prismatic: y, axis: y}]
bodies: [{name: mass, frame: ball, mass: m}]
contacts:
  - {name: ground, gap: GAP, restitution: 0}
"""


@pytest.mark.parametrize("h0", ["-1.0", "-0.05"])
def test_a_contact_that_starts_inside_its_surface_is_refused_by_check_and_sim(tmp_path, h0):
    """The ball starts 1 m (5 cm) below the ground: before, `check` refused it and `sim` ran 'finished' with the ball
    falling through (its impact guard past zero never crosses). Both refuse it now, at the contact's line; with
    --init project the run starts on the ground (the contact closed) and rests there."""
    path = tmp_path / "sunk.yaml"
    path.write_text(SUNK.replace("GAP", "ball.y").replace("h0: -1.0", f"h0: {h0}"))
    line = SUNK.splitlines().index("  - {name: ground, gap: GAP, restitution: 0}") + 1
    checked = invoke("check", path)
    assert checked.exit_code == 1 and f"{path}:{line}: contacts[0]: contact 'ground' starts" in checked.stderr
    build = tmp_path / "build"
    run = invoke("sim", path, "--t-end", 0.5, "--build-dir", build, "-o", tmp_path / "run.h5")
    assert run.exit_code == 1 and f"{path.name}:{line}: contacts[0].gap: the initial state is off" in run.stderr
    assert not (tmp_path / "run.h5").exists()
    model, _ = andyc.compile_model(path, build)
    run = andyc.simulate(model, 0.5, dt=1e-3, init=andyc.Init("project"), progress=False)
    assert run.finished and np.max(np.abs(run.column("y"))) < 1e-12 and np.all(run.contact_modes[:, 0] == 1)


def test_a_gap_with_no_real_value_at_the_start_is_located(tmp_path):
    """sqrt(ball.y - 5) at y = 1: `check` named no problem before (an internal error), `sim` ran with the contact
    never acting (its gap NaN). Both name the contact's line now."""
    path = tmp_path / "complex.yaml"
    path.write_text(SUNK.replace("GAP", "sqrt(ball.y - 5)").replace("h0: -1.0", "h0: 1.0"))
    line = SUNK.splitlines().index("  - {name: ground, gap: GAP, restitution: 0}") + 1
    checked = invoke("check", path)
    assert checked.exit_code == 1 and f"{path}:{line}: contacts[0]: the gap of contact 'ground' has no real value" \
        in checked.stderr
    run = invoke("sim", path, "--t-end", 0.1, "--build-dir", tmp_path / "build", "-o", tmp_path / "run.h5")
    assert run.exit_code == 2 and f"{path.name}:{line}: contacts[0].gap: the gap of contact 'ground' is nan" \
        in run.stderr


def test_coefficients_given_at_run_time_are_checked(compiled, shipped_build, tmp_path):
    """`--set e=1.5` (the ball gained energy at each impact) and `--set mu=-1` ran and exited 0, although the model
    file refuses those values: refused now, by the API and the command line, naming the contact and the values."""
    ball = compiled("bouncing_ball_contact")
    with pytest.raises(SimulationError, match=r"contact 'ground': its coefficient of restitution is 1\.5 at e = 1\.5, "
                                              r"outside \[0, 1\]"):
        andyc.simulate(ball, 1.0, parameters={"e": 1.5}, progress=False)
    result = invoke("sim", MODELS / "block_incline.yaml", "--set", "mu=-1", "--t-end", 0.1, "--build-dir",
                    shipped_build, "-o", tmp_path / "run.h5")
    assert result.exit_code == 2 and "contact 'slope': its friction coefficient is -1 at mu = -1, negative" \
        in result.stderr
    assert not (tmp_path / "run.h5").exists()


def test_cycle_refuses_contacts_before_any_build(tmp_path):
    """`andyc cycle` on a hopper with a contact ended in an internal error (NameError in the generated derivatives)
    after 19 s; it refuses now, at the contacts' line, before building anything."""
    build = tmp_path / "build"
    result = invoke("cycle", MODELS / "hopper_contact.yaml", "--section", "ground_impact", "--build-dir", build)
    line = (MODELS / "hopper_contact.yaml").read_text().splitlines().index("contacts:") + 1
    assert result.exit_code == 2
    assert f"hopper_contact.yaml:{line}: contacts: andyc cycle follows a gait through hand-written jumps" \
        in result.stderr
    assert not build.exists()
