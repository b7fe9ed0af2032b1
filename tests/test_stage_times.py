"""RK4's stage times (issue 41): a force written as a function of t in the model, not through an input.

m x'' = c t from rest gives x = c t^3 / (6 m) by hand. RK4 integrates a cubic exactly when each stage sees its
own time t + c_s h; a stage evaluated at the step's start time sees the force c t held over the step, an error
of order h in x, so the tight bound below fails. (An input is evaluated by its own call, so the input tests
do not see the dynamics' stage time.)
"""

import numpy as np
import pytest

import andyc

RAMP = """\
name: ramp_cart
parameters: {m: 2.0, c: 0.5}
coordinates:
  x: {initial: 0}
frames:
  - {name: cart, parent: world, prismatic: x, axis: x}
bodies:
  - {name: cart_mass, frame: cart, mass: m}
forces:
  - {name: push, frame: cart, vector: ["c*t", 0, 0]}
"""


@pytest.fixture(scope="module")
def ramp(compiled_text):
    return compiled_text("ramp_cart", RAMP)


def test_rk4_integrates_a_force_ramp_in_t_exactly(ramp):
    run = andyc.simulate(ramp, 3.0, dt=0.1, progress=False)
    assert np.max(np.abs(run.column("x") - 0.5 * run.time**3 / (6 * 2.0))) < 1e-12
