"""The hybrid runtime on small models with closed-form answers: per-flow inputs, time guards,
instant jumps, the jump counter, the user's jump file (kept across rebuilds, called at each jump)."""

import re

import numpy as np
import pytest

import andyc
from tests.support.cli import invoke

# A mass pushed by an input force u along x; at t = t_off the push stops (the flow
# 'coast' sets u = 0), and when x passes x_wall the mass is put back to 0 with a
# user-editable jump (the file's function adds a count to the discrete state n).
PUSH = """\
name: push
parameters: {m: 2.0, F: 3.0, t_off: 1.0, x_wall: 5.0}
inputs: {u: 0.0}
discrete: {n: 0}
coordinates:
  x: {}
frames:
  - {name: cart, parent: world, prismatic: x, axis: x}
bodies:
  - {name: mass, frame: cart, mass: m}
forces:
  - {name: push, frame: cart, vector: [u, 0, 0]}
hybrid:
  flows:
    - {name: pushed, inputs: {u: F}}
    - {name: coast}
  jumps:
    - {name: stop_pushing, from: pushed, to: coast, guard: t - t_off, direction: rising}
    - name: wrap
      from: coast
      to: coast
      guard: x - x_wall
      direction: rising
      reset: {x: 0, n: n + 1}
"""


@pytest.fixture(scope="module")
def push(tmp_path_factory):
    folder = tmp_path_factory.mktemp("push")
    path = folder / "push.yaml"
    path.write_text(PUSH)
    model, result = andyc.compile_model(path, folder / "build")
    return model, result, path, folder / "build"


def test_flow_inputs_and_time_guard_follow_the_closed_form(push):
    model = push[0]
    run = andyc.simulate(model, 4.0, dt=1e-3, progress=False)
    m, F, t_off, wall = 2.0, 3.0, 1.0, 5.0
    a = F / m
    assert run.event_names()[0] == "stop_pushing"
    assert run.events["time"][0] == pytest.approx(t_off, abs=1e-12)
    # constant acceleration, then constant speed a t_off, wrapping at the wall
    t = run.time
    x = np.where(t <= t_off, 0.5 * a * t**2, 0.5 * a * t_off**2 + a * t_off * (t - t_off))
    t_wall = t_off + (wall - 0.5 * a * t_off**2) / (a * t_off)
    assert run.events["time"][1] == pytest.approx(t_wall, abs=1e-11)
    x = np.where(t > t_wall, x - wall, x)
    assert np.max(np.abs(run.column("x") - x)) < 1e-10
    assert list(run.flow_names[f] for f in run.flow[[0, -1]]) == ["pushed", "coast"]
    assert run.column("n")[-1] == 1 and run.column("n")[0] == 0


def test_user_jump_file_is_kept_called_and_reported(push, tmp_path):
    model, result, path, build = push
    jumps_file = result.jumps_path
    assert jumps_file.name == "push_jumps.py" and not result.jumps_kept
    text = jumps_file.read_text()
    assert "def wrap(t, x, u, p, d):" in text and "def stop_pushing(t, x, u, p, d):" in text
    # The user edits it: after each wrap, also set the speed to 1.
    jumps_file.write_text(text.replace("def wrap(t, x, u, p, d):", "def wrap(t, x, u, p, d):\n    x[1] = 1.0", 1))
    reloaded, again = andyc.compile_model(path, build, force=True)
    assert again.jumps_kept and jumps_file.read_text().count("x[1] = 1.0") == 1     # not overwritten
    run = andyc.simulate(reloaded, 4.0, dt=1e-3, progress=False)
    k = run.event_names().index("wrap")
    assert run.events["state_after"][k][1] == 1.0
    assert run.events["discrete_after"][k][0] == 1.0          # the YAML's reset ran too
    # the CLI says it kept the file
    out = invoke("build", str(path), "--build-dir", str(build), "--force")
    assert out.exit_code == 0 and "push_jumps.py: kept" in out.output


def test_a_failing_user_jump_stops_the_run_with_its_file_and_line(tmp_path):
    path = tmp_path / "push.yaml"
    path.write_text(PUSH)
    build = tmp_path / "build"
    model, result = andyc.compile_model(path, build)
    text = result.jumps_path.read_text()
    result.jumps_path.write_text(text.replace("def wrap(t, x, u, p, d):", "def wrap(t, x, u, p, d):\n    raise ValueError('bad wall')", 1))
    model, _ = andyc.compile_model(path, build, force=True)
    run = andyc.simulate(model, 4.0, dt=1e-3, progress=False)
    line = result.jumps_path.read_text().splitlines().index("    raise ValueError('bad wall')") + 1
    assert run.status.startswith(f"stopped: {result.jumps_path}:{line}: the function of jump 'wrap' raised ValueError: bad wall")
    assert run.time[-1] == pytest.approx(1.0 + (5.0 - 0.75) / 1.5, abs=1e-9)     # stopped at the wall ...
    assert run.time.shape[0] > 3800 and run.event_names() == ["stop_pushing"]    # ... keeping what it logged


def test_a_jump_loop_at_one_instant_trips_the_counter(tmp_path):
    """Two flows whose jumps send the state back at once: a -> b -> a ... at t = 0.5."""
    text = PUSH.split("hybrid:")[0] + """\
hybrid:
  flows:
    - {name: a}
    - {name: b}
  jumps:
    - {name: ab, from: a, to: b, guard: t - 0.5, direction: rising}
    - {name: ba, from: b, to: a, guard: t - 0.5, direction: rising}
"""
    path = tmp_path / "loop.yaml"
    path.write_text(text.replace("name: push", "name: loop"))
    model, _ = andyc.compile_model(path, tmp_path / "build")
    run = andyc.simulate(model, 1.0, dt=1e-3, events=andyc.Events(max_instant_jumps=20), progress=False)
    assert re.match(r"stopped: 21 jumps at t = 0\.(5|49999\d*) s without time advancing", run.status)
    assert "ab -> ba" in run.status or "ba -> ab" in run.status
    assert len(run.events["time"]) == 21 and np.all(run.events["time"] == run.events["time"][0])


def test_a_flow_that_sets_an_input_wins_over_the_run_driving_it(push):
    """In 'pushed' the flow sets u = F; in 'coast' the run's expression u = t/2 drives it:
    x = a t^2 / 2 up to t_off, then x'' = t / (2 m)."""
    model = push[0]
    run = andyc.simulate(model, 3.0, dt=1e-3, inputs={"u": "t/2"}, progress=False)
    m, F, t_off = 2.0, 3.0, 1.0
    t, u = run.time, run.input_values[:, 0]
    pushed = run.flow == run.flow_names.index("pushed")
    assert np.all(u[pushed] == F) and np.allclose(u[~pushed], t[~pushed] / 2, rtol=0, atol=1e-15)
    a = F / m
    after = 0.5 * a * t_off**2 + a * t_off * (t - t_off) + ((t**3 - t_off**3) / 3 - t_off**2 * (t - t_off)) / (4 * m)
    x = np.where(t <= t_off, 0.5 * a * t**2, after)
    assert np.max(np.abs(run.column("x") - x)) < 1e-10
