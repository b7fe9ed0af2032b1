"""The compass gait's one-step map by plain simulation of models/compass_gait.yaml (docs/reference-cases.md §8), which
tests/test_cycles.py and tests/test_continuation.py difference independently of andyc cycle."""

import math

import numpy as np

import andyc


def gait_state(z):
    """The state just after a heel strike of leg 1 at the origin, from z = (half inter-leg angle, stance speed,
    swing speed), walking downhill (+x)."""
    phi, w_st, w_sw = z
    return np.array([-math.sin(phi), math.cos(phi), phi, -phi,
                     math.cos(phi) * w_st, math.sin(phi) * w_st, -w_st, -w_sw])


def gait_step(model, z, parameters=None):
    """z after the next heel strike (leg 2's; the roles swap), by the same rk4 as the cycle."""
    run = andyc.simulate(model, 5.0, dt=1e-3, method="rk4", x0=gait_state(z), d0=np.zeros(1), flow0="stance1",
                         parameters=parameters,
                         events=andyc.Events(tol=1e-15, stop_after={"strike2": 1}), init=andyc.Init("as-is"),
                         progress=False)
    x = run.events["state_after"][0]
    return np.array([x[3], -x[7], -x[6]])
