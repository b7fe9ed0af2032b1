"""Moreau's midpoint time (issue 41): a force c t on a block resting on frictionless flat ground.

The theta-method evaluates the forces at t_k + theta h: v_(k+1) = v_k + h c (t_k + theta h) / m. Summed by hand
from rest, v_k = (c / m) (t_k^2 / 2 + (theta - 1/2) h t_k): at theta = 1/2 the exact c t^2 / (2 m), at theta = 1
half a step's force more. Forces evaluated at t_k instead would give (c / m) (t_k^2 - h t_k) / 2, off by
c h t / (2 m) (5e-3 m/s at t = 1 here), far past the bound.
"""

import numpy as np
import pytest

import andyc

BLOCK = """\
name: pushed_block
parameters: {m: 2.0, c: 3.0, g: 9.81}
inputs:
  F: "c*t"
coordinates:
  x: {initial: 0}
  y: {initial: 0}
gravity: [0, -g, 0]
frames:
  - {name: slide, parent: world, prismatic: x, axis: x}
  - {name: block, parent: slide, prismatic: y, axis: y}
bodies:
  - {name: mass, frame: block, mass: m}
forces:
  - {name: push, frame: block, vector: [F, 0, 0]}
contacts:
  - name: ground
    gap: block.y
"""
M, C, H = 2.0, 3.0, 1e-3


@pytest.fixture(scope="module")
def block(compiled_text):
    return compiled_text("pushed_block", BLOCK)


@pytest.mark.parametrize("theta", [0.5, 1.0])
def test_the_step_evaluates_the_force_at_its_theta_time(block, theta):
    run = andyc.simulate(block, 1.0, dt=H, method="moreau", stepping=andyc.TimeStepping(theta=theta))
    t = run.time
    expected = C / M * (t ** 2 / 2 + (theta - 0.5) * H * t)
    assert np.max(np.abs(run.column("x_dot") - expected)) < 1e-9
    assert np.max(np.abs(run.column("y"))) < 1e-9          # it stays on the ground
