"""Initial states by name (issue 42): `andyc sim --at NAME=VALUE` and andyc.simulate(x0={name: value}), the other
values as the model file gives them, so a sweep's point can be rerun alone. Expected values from the model files
themselves (read with PyYAML) and their initial-value formulas evaluated by hand."""

import math

import numpy as np
import pytest
import yaml

import andyc
from andyc.errors import SimulationError
from andyc.runtime.initial import initial_state
from andyc.runtime.runfiles import read_h5
from tests.support import MODELS
from tests.support.cli import invoke


def _initial_values(name):
    coordinates = yaml.safe_load((MODELS / f"{name}.yaml").read_text())["coordinates"]
    return {c: spec.get("initial", 0.0) for c, spec in coordinates.items()}


def test_a_run_starts_from_the_named_value_and_the_models_others(compiled):
    model = compiled("double_pendulum")
    given = _initial_values("double_pendulum")
    run = andyc.simulate(model, 0.01, x0={"q1": 0.7}, progress=False)
    assert run.state[0].tolist() == [0.7, given["q2"], 0.0, 0.0]
    spun = andyc.simulate(model, 0.01, x0={"q2_dot": -3.0}, progress=False)
    assert spun.state[0].tolist() == [given["q1"], given["q2"], 0.0, -3.0]


def test_the_others_follow_the_parameters_as_the_model_file_writes_them(compiled):
    """The compass gait's initial values are expressions of phi0, a, b and the speeds: with phi0 = 0.2 and th1
    named, th2 = -phi0 and x = -(a + b) sin(phi0) at the new phi0; the discrete fx by name too."""
    model = compiled("compass_gait")
    params = yaml.safe_load((MODELS / "compass_gait.yaml").read_text())["parameters"]
    p = model.parameters({"phi0": 0.2})
    x, d, _ = initial_state(model, p, {"th1": 0.25}, {"fx": 0.3})
    names = model.state_names
    assert x[names.index("th1")] == 0.25
    assert x[names.index("th2")] == -0.2
    assert math.isclose(x[names.index("x")], -(params["a"] + params["b"]) * math.sin(0.2), rel_tol=1e-15)
    assert math.isclose(x[names.index("th1_dot")], params["w_stance0"], rel_tol=1e-15)
    assert d.tolist() == [0.3]


def test_unknown_names_are_refused_with_the_models_names(compiled):
    model = compiled("double_pendulum")
    with pytest.raises(SimulationError, match=r"unknown state 'q9'; states of this model: q1, q2, q1_dot, q2_dot"):
        andyc.simulate(model, 0.01, x0={"q9": 1.0}, progress=False)
    with pytest.raises(SimulationError, match=r"'q1' is a state, not a parameter: .*--at q1=VALUE"):
        andyc.simulate(model, 0.01, parameters={"q1": 1.0}, progress=False)
    with pytest.raises(SimulationError, match=r"unknown discrete state 'fx'; discrete states of this model: none"):
        andyc.simulate(model, 0.01, d0={"fx": 1.0}, progress=False)


def test_the_command_line_reruns_a_point(tmp_path, shipped_build, compiled):
    compiled("double_pendulum")
    out = tmp_path / "at.h5"
    result = invoke("sim", MODELS / "double_pendulum.yaml", "--at", "q1=0.7", "--at", "q1_dot=0.5", "--set", "m2=2",
                    "--t-end", "0.01", "-o", out, "--build-dir", shipped_build)
    assert result.exit_code == 0, result.output
    run = read_h5(out)
    assert run.state[0].tolist() == [0.7, _initial_values("double_pendulum")["q2"], 0.5, 0.0]
    assert run.parameters["m2"] == 2.0
    wrong = invoke("sim", MODELS / "double_pendulum.yaml", "--set", "q1=0.7", "--t-end", "0.01", "-o",
                   tmp_path / "no.h5", "--build-dir", shipped_build)
    assert wrong.exit_code != 0 and "--at q1=VALUE" in wrong.output and not (tmp_path / "no.h5").exists()
    bad = invoke("sim", MODELS / "double_pendulum.yaml", "--at", "q1=nan", "--t-end", "0.01", "-o", tmp_path / "n.h5",
                 "--build-dir", shipped_build)
    assert bad.exit_code == 2 and "--at" in bad.output
    assert np.isfinite(run.state).all()
