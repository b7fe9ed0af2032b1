"""`andyc check` finds an initial state off its constraint manifold, and a guard already past zero, from
the equations, without compiling; `andyc sim` refuses the same state as a model problem (exit 1, no usage
text, the file as given); a model's simulate: section gives andyc sim's options, the command line wins.

The model: a point mass held on a circle of radius L by x^2 + y^2 - L^2 = 0, started at x = 1.1 L, y = 0:
off the circle by (1.1^2 - 1) L^2 = 0.21 at the position level; its velocity (0, v) is tangent there, so
the velocity-level row 2 x x_dot + 2 y y_dot is 0.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from andyc.runtime.runfiles import read_h5
from tests.support.cli import invoke

ROOT = Path(__file__).resolve().parents[1]

RING = """\
name: ring_ci
parameters: {L: 1.0, m: 1.0, g: 9.81}
coordinates:
  x: {initial: 1.1*L}
  y: {initial: 0, velocity: 0.5}
gravity: [0, -g, 0]
frames:
  - {name: slider, parent: world, translation: [x, y, 0]}
bodies:
  - {name: bob, frame: slider, mass: m}
constraints:
  - {name: ring, holonomic: x**2 + y**2 - L**2}
"""

GUARD = RING.replace("name: ring_ci", "name: ring_guard") + """\
hybrid:
  flows:
    - {name: sliding, constraints: [ring]}
  jumps:
    - {name: low, from: sliding, to: sliding, guard: y + 0.5*L, direction: falling}
    - {name: high, from: sliding, to: sliding, guard: y - 0.5*L, direction: falling}
"""


def line_of(text: str, needle: str) -> int:
    return next(n for n, line in enumerate(text.splitlines(), 1) if needle in line)




@pytest.fixture(scope="module")
def place(tmp_path_factory):
    """A folder with the models in a subfolder (so that the file as given has a directory) and a build folder."""
    root = tmp_path_factory.mktemp("initial")
    (root / "sub").mkdir()
    return root


def test_check_finds_the_off_manifold_state_and_the_guard_past_zero_without_compiling(place):
    (place / "sub" / "ring_guard.yaml").write_text(GUARD)
    (place / "sub" / "ring_ok.yaml").write_text(RING.replace("1.1*L", "L").replace("name: ring_ci", "name: ring_ok"))
    result = invoke("check", "sub/ring_guard.yaml", "sub/ring_ok.yaml", "--format", "text", cwd=place)
    assert result.exit_code == 1
    assert "Usage:" not in result.stderr and "Traceback" not in result.stderr
    lines = result.stderr.splitlines()
    ring = line_of(GUARD, "holonomic: x**2")
    assert lines[0] == (
        f"sub/ring_guard.yaml:{ring}: constraints[0].holonomic: the initial state is off the constraint manifold: "
        f"residual 0.21 at the position level (constraint 'ring'), past the bound 1e-06 (init_tol); fix the "
        f"initial values, or give the model `simulate: {{init: project}}` to move the state onto the manifold "
        f"(the smallest change in the mass-matrix metric), or `simulate: {{init: as-is}}` to start from it anyway")
    # The rest of the model is still checked: the jump 'high' starts with its guard y - 0.5 L = -0.5 below
    # zero (falling); 'low' (y + 0.5 L = 0.5) does not.
    high = line_of(GUARD, "name: high")
    assert lines[1].startswith(f"sub/ring_guard.yaml:{high}: hybrid.jumps[1].guard: the guard of jump 'high' is "
                               "already past zero at the start: -0.5, below zero in flow 'sliding'")
    assert not any("'low'" in line for line in lines)
    assert lines[2] == "2 problems found"
    # ... and the other file too: it is valid.
    assert "sub/ring_ok.yaml: model 'ring_ok' is valid" in result.stdout
    assert not (place / "build").exists()           # nothing compiled, nothing written


def test_the_model_may_say_to_project_or_start_as_is(place):
    for mode in ("project", "as-is"):
        (place / "sub" / "ring_mode.yaml").write_text(RING.replace("name: ring_ci", "name: ring_mode")
                                                      + f"simulate: {{init: {mode}}}\n")
        result = invoke("check", "sub/ring_mode.yaml", cwd=place)
        assert result.exit_code == 0, result.stderr
    (place / "sub" / "ring_mode.yaml").write_text(RING.replace("name: ring_ci", "name: ring_mode")
                                                  + "simulate: {init_tol: 0.3}\n")
    assert invoke("check", "sub/ring_mode.yaml", cwd=place).exit_code == 0       # 0.21 is within 0.3


def test_sim_refuses_the_off_manifold_state_as_a_model_problem(place):
    """The compiled module measures the same residual (an independent evaluation: generated code, not SymPy)."""
    (place / "sub" / "ring.yaml").write_text(RING)
    result = invoke("sim", "sub/ring.yaml", "--build-dir", "build", "-o", "out/ring.h5", cwd=place)
    assert result.exit_code == 1
    assert "Usage:" not in result.stderr and "Error:" not in result.stderr
    line = line_of(RING, "holonomic: x**2")
    message = result.stderr.strip().splitlines()[-1]
    assert message.startswith(f"sub/ring.yaml:{line}: constraints[0].holonomic: the initial state is off the "
                              "constraint manifold: largest residual 0.21 at the position level")
    assert not (place / "out" / "ring.h5").exists()


def test_simulate_section_gives_the_options_and_the_command_line_wins(place):
    (place / "sub" / "ring.yaml").write_text(RING + "simulate: {init: project, method: projection, t_end: 0.5, "
                                             "dt: 0.01, every: 5}\n")
    result = invoke("sim", "sub/ring.yaml", "--build-dir", "build", "-o", "out/a.h5", cwd=place)
    assert result.exit_code == 0, result.stderr
    run = read_h5(place / "out" / "a.h5")
    assert run.method == "projection" and run.t_end == 0.5 and run.dt == 0.01
    assert np.allclose(np.diff(run.time), 0.05)                         # every 5 steps of 0.01 s
    x, y = run.column("x"), run.column("y")
    assert np.max(np.abs(x ** 2 + y ** 2 - 1.0)) < 1e-12               # projected onto the circle first
    result = invoke("sim", "sub/ring.yaml", "--build-dir", "build", "-o", "out/b.h5", "--t-end", "0.2",
                   "--method", "rk4", "--every", "1", cwd=place)
    assert result.exit_code == 0, result.stderr
    run = read_h5(place / "out" / "b.h5")
    assert run.method == "rk4" and run.t_end == 0.2 and run.dt == 0.01
    assert np.allclose(np.diff(run.time), 0.01)


def test_simulate_section_names_are_checked(place):
    (place / "sub" / "ring_bad.yaml").write_text(RING.replace("name: ring_ci", "name: ring_bad")
                                                 + "simulate: {frames: [slidr], t_end: 0.01, dt: 0.1}\n")
    result = invoke("check", "sub/ring_bad.yaml", cwd=place)
    assert result.exit_code == 1
    text = result.stderr
    line = line_of(RING, "name: ring_ci") + RING.count("\n")
    assert re.search(rf"^sub/ring_bad.yaml:{line}: simulate.frames\[0\]: frame 'slidr' does not exist; did you "
                     r"mean 'slider'\?", text, re.M), text
    assert f"sub/ring_bad.yaml:{line}: simulate.dt: dt = 0.1 s is longer than t_end = 0.01 s" in text


def test_every_shipped_model_passes_check_with_its_simulate_section():
    """Including biped_rheonomic, whose paper start is off its constraints: it says `init: as-is`."""
    models = sorted(str(p.relative_to(ROOT)) for p in (ROOT / "models").glob("*.yaml"))
    result = invoke("check", *models, cwd=ROOT)
    assert result.exit_code == 0, result.stderr
    assert result.stdout.count(" is valid: ") == len(models)
