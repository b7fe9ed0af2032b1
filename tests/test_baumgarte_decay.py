"""Baumgarte's stabilisation (issue 41): a holonomic row started off its constraint returns to it as the damped
oscillator phi'' + K_d phi' + K_s phi = 0 (ANDY eq. 15), where the row's effective mass A M^-1 A^T is 1.

A unit mass moves in the plane (coordinates x, y); the row is phi = x. Started at x = x0 at rest (init as-is),
the closed form with K_s = 4, K_d = 2 (omega_0 = 2, zeta = 1/2, omega_d = sqrt 3) is
x(t) = x0 e^-t (cos(sqrt3 t) + sin(sqrt3 t) / sqrt3); y moves on at its own speed. Without the position term the
row would only stop drifting (x stays at x0); without the damping it would oscillate undamped.
"""

import math

import numpy as np
import pytest

import andyc

PLANE = """\
name: baumgarte_plane
parameters: {m: 1.0, k_s: 4.0, k_d: 2.0, x0: 0.1}
coordinates:
  x: {initial: x0}
  y: {initial: 0, velocity: 0.3}
frames:
  - {name: slide_x, parent: world, prismatic: x, axis: x}
  - {name: puck, parent: slide_x, prismatic: y, axis: y}
bodies:
  - {name: puck_mass, frame: puck, mass: m}
constraints:
  - {name: on_line, holonomic: x, gains: {stiffness: k_s, damping: k_d}}
"""


@pytest.fixture(scope="module")
def plane(compiled_text):
    return compiled_text("baumgarte_plane", PLANE)


def test_an_offset_row_decays_as_the_damped_oscillator_of_its_gains(plane):
    run = andyc.simulate(plane, 3.0, dt=1e-3, method="baumgarte", init=andyc.Init("as-is"), progress=False)
    t, w = run.time, math.sqrt(3.0)
    expected = 0.1 * np.exp(-t) * (np.cos(w * t) + np.sin(w * t) / w)
    assert run.finished
    assert np.max(np.abs(run.column("x") - expected)) < 1e-9
    assert np.max(np.abs(run.column("y") - 0.3 * t)) < 1e-12            # the free direction is untouched
