"""A closed loop that rk4 or lagrange lets drift off its constraints says so and suggests projection
(issue 24; andyc.runtime.status.drift and lost_constraints, DRIFT_BOUND = 1e-3).

The four-bar (models/fourbar.yaml) passes its flat, singular configuration twice a turn. At dt = 0.01 RK4,
which does not correct the drift, leaves the loop (residual 7 at t = 3.88 s) and blows up; the projection
method at the same step keeps it at round-off, so the advice is sound. At dt = 1e-3 RK4 finishes 10 s but
the loop is 1.7 cm open: the summary says so.
"""

import andyc
from andyc.runtime.status import DRIFT_BOUND, largest_residual
from tests.support import MODELS
from tests.support.cli import invoke


def test_rk4_and_lagrange_blow_up_naming_the_drift_and_projection(compiled):
    model = compiled("fourbar")
    for method in ("rk4", "lagrange"):
        run = andyc.simulate(model, 10.0, dt=0.01, method=method)
        assert run.status.startswith("stopped: the solution diverges")
        residual, _ = largest_residual(run.residual_position, run.residual_velocity, run.time)
        assert residual > 1.0
        assert f"the constraints drifted to a residual of {residual:.3g}" in run.status
        assert f"{method} does not correct the drift; use --method projection" in run.status
    fixed = andyc.simulate(model, 10.0, dt=0.01, method="projection")
    assert fixed.finished
    assert largest_residual(fixed.residual_position, fixed.residual_velocity, fixed.time)[0] < 1e-12


def test_a_finished_run_past_the_bound_says_so_and_one_within_does_not(compiled):
    model = compiled("fourbar")
    drifted = andyc.simulate(model, 10.0, dt=1e-3, method="rk4", every=10)
    assert drifted.finished
    residual, _ = largest_residual(drifted.residual_position, drifted.residual_velocity, drifted.time)
    assert residual > DRIFT_BOUND
    assert "use --method projection" in drifted.summary()
    short = andyc.simulate(model, 1.0, dt=1e-3, method="rk4")
    assert largest_residual(short.residual_position, short.residual_velocity, short.time)[0] < DRIFT_BOUND
    assert "drifted" not in short.summary() and "drifted" not in short.status


def test_the_command_line_prints_the_hint(tmp_path, compiled, shipped_build):
    compiled("fourbar")         # (built once for the session)
    result = invoke("sim", MODELS / "fourbar.yaml", "--method", "rk4", "--dt", "0.01", "--t-end", "10",
                    "--out", tmp_path / "blown.h5", "--build-dir", shipped_build)
    assert result.exit_code == 1
    assert "use --method projection" in result.stderr
