"""Closed-form references declared in a model (`closed_form:`): the generated closed_form(t, u, p)
against an integrator, the reference andyc bench and andyc stability choose, RK4's error measured
against the exact solution, and the loader's and the reference's messages."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import andyc
from andyc.analysis.stability import scan
from andyc.analysis.accuracy import divides, reference_solution, run_point
from andyc.analysis.workprecision import sweep
from andyc.errors import SimulationError
from tests.support import MODELS, diagnostics
from tests.support.diagnostics import line_of

OMEGA, X0 = 100.0, 0.01     # models/stiff_spring.yaml: sqrt(k/m), the initial displacement
T = 1.3                     # 20.7 periods: the phase at T is no multiple of pi/2

# The mass on its spring (models/stiff_spring.yaml without its closed form).
SPRING_BODY = """\
parameters: {m: 1.0, k: 1.0e4, x0: 0.01}
coordinates:
  x: {initial: x0}
frames:
  - {name: slider, parent: world, prismatic: x, axis: x}
bodies:
  - {name: mass, frame: slider, mass: m}
springs:
  - {name: spring, stiffness: k, rest_length: 0, length: x}
"""

# A spring whose closed form starts at twice its initial displacement; F is a held input (F/k: the
# static offset a constant push adds).
WRONG_START = "name: wrong_start\ninputs: {F: 0.0}\n" + SPRING_BODY + """\
forces:
  - {name: push, frame: slider, vector: [F, 0, 0]}
closed_form:
  x: 2*x0*cos(sqrt(k/m)*t) + F/k
  x_dot: -2*x0*sqrt(k/m)*sin(sqrt(k/m)*t)
"""


@pytest.fixture(scope="module")
def spring(compiled):
    return compiled("stiff_spring")


@pytest.fixture(scope="module")
def wrong_start(tmp_path_factory):
    folder = tmp_path_factory.mktemp("wrong_start")
    (folder / "wrong_start.yaml").write_text(WRONG_START)
    return andyc.compile_model(folder / "wrong_start.yaml", folder / "build")[0]


def oscillation(omega: float, t: float) -> np.ndarray:
    """(x, x_dot) of x'' = -omega^2 x from (X0, 0)."""
    return np.array([X0 * math.cos(omega * t), -X0 * omega * math.sin(omega * t)])


# -- the generated function and the reference -------------------------------------------------------

def test_the_generated_closed_form_matches_a_dop853_run(spring):
    """Two independent computations of x(T): the generated closed form and DOP853 at 1e-13 integrating the
    generated equations of motion; both equal the oscillation the test computes itself."""
    text = (MODELS / "stiff_spring.yaml").read_text()
    assert spring.closed_form_where == ((line_of(text, "  x: x0*cos"), "closed_form.x"),
                                        (line_of(text, "  x_dot: "), "closed_form.x_dot"))
    exact = spring.closed_form(T, spring.inputs(), spring.parameters())
    run = andyc.simulate(spring, T, dt=T / 100, method="DOP853", rtol=1e-13, atol=1e-13, progress=False)
    assert run.finished and run.time[-1] == pytest.approx(T, rel=1e-14)
    assert np.abs(exact - run.state[-1]).max() < 1e-10
    assert np.abs(exact - oscillation(OMEGA, T)).max() < 1e-14


def test_the_reference_is_the_closed_form_by_default_and_follows_the_parameters(spring):
    auto, dop = reference_solution(spring, T), reference_solution(spring, T, source="DOP853")
    assert auto.source == "closed form" and dop.source == "DOP853, rtol = atol = 1e-13"
    assert auto.jumps == dop.jumps == 0
    assert np.abs(auto.final - dop.final).max() < 1e-10
    assert auto.scale == pytest.approx(dop.scale, rel=1e-8)         # the same 201 samples
    assert auto.wall < dop.wall                                   # 201 evaluations against an integration
    # k = 2.5e3: w = 50 rad/s, for both references
    slow = reference_solution(spring, T, source="closed-form", parameters={"k": 2.5e3})
    slow_dop = reference_solution(spring, T, source="DOP853", parameters={"k": 2.5e3})
    assert np.abs(slow.final - oscillation(50.0, T)).max() < 1e-14
    assert np.abs(slow.final - slow_dop.final).max() < 1e-10
    assert np.abs(slow.final - auto.final).max() > 0.1
    # A model without one: "auto" falls back to DOP853, "closed-form" says there is none.
    bare = dataclasses.replace(spring, closed_form=None)
    assert reference_solution(bare, 0.1).source == "DOP853, rtol = atol = 1e-13"
    with pytest.raises(SimulationError, match="no closed-form reference: stiff_spring declares none"):
        reference_solution(bare, 0.1, source="closed-form")
    with pytest.raises(SimulationError, match="unknown reference 'exact'"):
        reference_solution(spring, 0.1, source="exact")


def test_sweep_and_scan_pass_the_reference_choice_on(spring):
    assert sweep(spring, ["rk4"], 0.1, steps=[1e-3], repeats=1)[0].source == "closed form"
    assert sweep(spring, ["rk4"], 0.1, steps=[1e-3], repeats=1, reference="DOP853")[0].source.startswith("DOP853")
    assert scan(spring, ["rk4"], [1e-3], horizon=0.1, reference="DOP853")[0].source.startswith("DOP853")
    made = reference_solution(spring, 0.1, source="DOP853")             # a reference made already is used as it is
    assert sweep(spring, ["rk4"], 0.1, steps=[1e-3], repeats=1, reference=made)[0] is made
    with pytest.raises(SimulationError, match="the reference ends at T = 0.1 s, the runs at 0.2 s"):
        sweep(spring, ["rk4"], 0.2, steps=[1e-3], repeats=1, reference=made)


def test_rk4_error_against_the_closed_form_is_its_phase_lag(spring):
    """RK4 on the oscillator: R(iy) = e^(iy) - i y^5/120 + O(y^6) (tests/test_analysis.py), a phase lag
    d = w^5 h^4 T / 120 at T, and |R(iy)| = 1 - y^6/144 + ..., an amplitude loss a = w^6 h^5 T / 144. The
    speed -X0 w (1 - a) sin(w T - d) is then off by X0 w |d cos(w T) + a sin(w T)|; the lag alone (the
    formula of tests/test_analysis.py) is 98% of it here. Against the exact solution nothing else enters:
    the rest is O(y^2) = 1e-4 of it."""
    ref = reference_solution(spring, T)
    h = divides(1e-4, T)
    lag, loss = OMEGA**5 * h**4 * T / 120, OMEGA**6 * h**5 * T / 144
    predicted = X0 * OMEGA * abs(lag * math.cos(OMEGA * T) + loss * math.sin(OMEGA * T))
    assert run_point(spring, ref, "rk4", h).error == pytest.approx(predicted, rel=1e-3)


# -- messages ----------------------------------------------------------------------------------------

def test_a_closed_form_off_the_initial_state_is_refused_with_its_line(wrong_start):
    line = line_of(WRONG_START, "  x: 2*x0")
    with pytest.raises(SimulationError) as info:
        reference_solution(wrong_start, T)
    assert str(info.value) == (f"wrong_start.yaml:{line}: closed_form.x: x is 0.02 at t = 0, the initial state "
                               "0.01; fix the closed form or the initial values")
    # From the start it describes, it is the solution: with F = 3 N held, about x = F/k.
    start = {"x0": [2 * X0 + 3e-4, 0.0], "inputs": {"F": 3.0}}
    exact = reference_solution(wrong_start, T, source="closed-form", **start)
    assert np.abs(exact.final - reference_solution(wrong_start, T, source="DOP853", **start).final).max() < 1e-10
    # A run that drives F is not what it describes.
    with pytest.raises(SimulationError, match=r"no closed-form reference: the run drives F \(expression 0\*t\)"):
        reference_solution(wrong_start, T, source="closed-form", inputs={"F": "0*t"})


SPRING = "name: spring\n" + SPRING_BODY + "closed_form:\n"
X = "  x: x0*cos(sqrt(k/m)*t)\n"
X_DOT = "  x_dot: -x0*sqrt(k/m)*sin(sqrt(k/m)*t)\n"


def problems(tmp_path, text: str) -> list[str]:
    """The loader's diagnostics for `text`, as `andyc check` prints them (FILE:LINE: PATH: what; fix), FILE left out."""
    return [str(d).removeprefix(f"{d.file}:") for d in diagnostics.problems(tmp_path, text)]


def test_the_spring_with_its_closed_form_loads(tmp_path):
    (tmp_path / "model.yaml").write_text(SPRING + X + X_DOT)
    spec = andyc.load(tmp_path / "model.yaml")
    assert list(spec.closed_form) == ["x", "x_dot"] and not spec.warnings


def test_a_missing_state_is_named(tmp_path):
    text = SPRING + X
    assert problems(tmp_path, text) == [
        f"{line_of(text, 'closed_form:')}: closed_form: the closed form gives no expression for x_dot; give every "
        "state (coordinates, their rates <coordinate>_dot, declared speeds, signals): x_dot: ..."]


def test_an_unknown_state_suggests_the_close_one(tmp_path):
    text = SPRING + X + "  x_dt: 0\n  k: 1\n"
    found = problems(tmp_path, text)
    assert f"{line_of(text, 'x_dt:')}: closed_form.x_dt: 'x_dt' is not a state of the model; did you mean " \
           "'x_dot'? the closed form gives each state: x, x_dot" in found
    assert f"{line_of(text, '  k: 1')}: closed_form.k: parameter 'k' is not a state of the model; the closed " \
           "form gives each state: x, x_dot" in found
    assert any("no expression for x_dot" in p for p in found) and len(found) == 3


def test_a_state_inside_the_closed_form_is_refused(tmp_path):
    text = SPRING + X + "  x_dot: -sqrt(k/m)*x*tan(sqrt(k/m)*t)\n"
    (problem,) = problems(tmp_path, text)
    assert problem.startswith(f"{line_of(text, 'x_dot:')}: closed_form.x_dot: in '-sqrt(k/m)*x*tan(sqrt(k/m)*t)': "
                              "the closed form of 'x_dot' uses coordinate 'x'; a closed form is the solution itself: "
                              "write x(t) with t, parameters and inputs only")


def test_a_hybrid_model_with_jumps_has_no_closed_form(tmp_path):
    text = (MODELS / "bouncing_ball.yaml").read_text() + "closed_form: {y: h0 - g*t**2/2, y_dot: -g*t}\n"
    (problem,) = problems(tmp_path, text)
    assert problem == (f"{line_of(text, 'closed_form:')}: closed_form: a closed form cannot describe jumps (the "
                       "model has 'bounce'); remove closed_form; andyc bench and stability then compare with DOP853 "
                       "at rtol 1e-13")
