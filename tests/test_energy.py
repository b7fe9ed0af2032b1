"""Energy: conserved without dampers, and lost exactly as the dampers' power with them.

The damper power is computed here independently of andyc's symbolic stage:
-b v_j^2 for a damper on a coordinate's speed, -b |v_f|^2 and -b |v_f|^3 for
linear and quadratic dampers on a frame's velocity v_f = (dr_f/dq) dq/dt, with
dr_f/dq from central differences of the frame's position.
"""

import numpy as np
import pytest
import yaml
from scipy.integrate import simpson

import andyc
from tests.support import MODELS


def relative_drift(run):
    e = run.energy
    return np.max(abs(e - e[0])) / abs(e[0])


def test_double_pendulum_energy_1e8_over_100s(compiled):
    run = andyc.simulate(compiled("double_pendulum"), 100.0, dt=1e-3, every=10)
    assert run.finished
    assert relative_drift(run) < 1e-8


def test_chain3d_energy_error_is_rk4_truncation(compiled):
    """The 3-D chain's light, fast distal link makes RK4 at 1e-3 s drift about 1e-7
    over 100 s. That is truncation error: over 2 s (before the chaotic motion lets
    runs at different steps part ways) halving the step cuts it about 2^4-fold,
    and at 2.5e-4 s the 100 s drift is below 1e-8."""
    model = compiled("chain3d")
    coarse = relative_drift(andyc.simulate(model, 2.0, dt=1e-3, every=10))
    fine = relative_drift(andyc.simulate(model, 2.0, dt=5e-4, every=20))
    assert 10 < coarse / fine < 25
    run = andyc.simulate(model, 100.0, dt=2.5e-4, every=40)
    assert relative_drift(run) < 1e-8


DAMPERS = [
    {"name": "joint_friction", "coefficient": 0.3, "speed": "q2"},
    {"name": "air_drag", "coefficient": 0.5, "law": "quadratic", "frame": "tool"},
    {"name": "viscous_elbow", "coefficient": 0.8, "frame": "elbow"},
]


@pytest.fixture(scope="module")
def damped(tmp_path_factory, build_dir):
    data = yaml.safe_load((MODELS / "chain3d.yaml").read_text())
    data["name"] = "chain3d_damped"
    data["dampers"] = DAMPERS
    path = tmp_path_factory.mktemp("models") / "chain3d_damped.yaml"
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    model = andyc.compile_model(path, build_dir)[0]
    run = andyc.simulate(model, 10.0, dt=1e-3, every=1, frames=["tool", "elbow"])
    return model, run


def frame_velocity(model, name, x, h=1e-6):
    k = model.frame_names.index(name)
    p, u = model.parameter_defaults, model.input_defaults
    nq = model.nq
    out = np.zeros((len(model.frame_names), 3))
    J = np.zeros((3, nq))
    for j in range(nq):
        for sign in (1, -1):
            xs = x.copy()
            xs[j] += sign * h
            model.module.frame_positions(0.0, xs, u, p, model.initial_discrete(p), out)
            J[:, j] += sign * out[k] / (2 * h)
    return J @ x[nq:]


def damper_power(model, x):
    qdot = x[model.nq:]
    v_tool = frame_velocity(model, "tool", x)
    v_elbow = frame_velocity(model, "elbow", x)
    return (-0.3 * qdot[1] ** 2 - 0.5 * np.linalg.norm(v_tool) ** 3 - 0.8 * v_elbow @ v_elbow)


def test_damped_chain_loses_the_integrated_damper_power(damped):
    model, run = damped
    assert run.finished
    power = np.array([damper_power(model, x) for x in run.state])
    dissipated = simpson(power, x=run.time)
    change = run.energy[-1] - run.energy[0]
    assert dissipated < -0.1 * abs(run.energy[0])      # the dampers do take out energy
    assert abs(change - dissipated) < 1e-6 * abs(dissipated)


def test_generated_power_matches_independent_power(damped):
    model, run = damped
    p, u = model.parameter_defaults, model.input_defaults
    for x in run.state[::1000]:
        assert model.module.power(0.0, x, u, p, model.initial_discrete(p)) == pytest.approx(damper_power(model, x), rel=1e-7)
