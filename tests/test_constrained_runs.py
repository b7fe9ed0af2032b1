"""Constrained integration (docs/reference-cases.md §3 and 4; issue 4).

- Ball in a bowl, 100 s at 1e-2 s: the projection method holds the holonomic
  and nonholonomic rows at round-off, its energy correction holds the energy,
  and the first integral b' cos^2 a + 2r/(7(R - r)) w_rho sin a stays put; the
  normal-force multiplier equals its closed form.
- Rheonomic biped from the paper's inconsistent start: residuals at round-off
  after a few steps, for the rest of 100 s.
- Parallelogram four-bar through its flat (singular) configuration: projection
  stays on the parallelogram branch and follows the closed-form 1-DOF motion;
  lagrange does not survive it.
- The same closure written twice: projection gives the same trajectory, and
  lagrange refuses with a message naming the redundant row.
"""

import numpy as np
import pytest
import yaml

import andyc
from andyc.errors import SimulationError
from andyc.independent.closed_forms import ball_first_integral, fourbar_crank_angle
from andyc.runtime.runfiles import read_h5
from tests.support import MODELS


def largest(a):
    return float(np.abs(a).max()) if a.size else 0.0


def parameter(model, name):
    return model.parameter_defaults[model.parameter_names.index(name)]


# -- ball in a bowl -----------------------------------------------------------

def first_integral(model, run):
    return ball_first_integral(run, parameter(model, "r"), parameter(model, "R"))


@pytest.fixture(scope="module")
def ball_runs(compiled):
    model = compiled("ball_in_bowl")
    return model, {
        "projection": andyc.simulate(model, 100.0, dt=1e-2, method="projection",
                                     projection=andyc.Projection(energy_correction=False)),
        "projection+energy": andyc.simulate(model, 100.0, dt=1e-2, method="projection"),
        "lagrange": andyc.simulate(model, 100.0, dt=1e-2, method="lagrange"),
        "baumgarte": andyc.simulate(model, 100.0, dt=1e-2, method="baumgarte"),
    }


def test_ball_projection_holds_both_constraint_kinds(ball_runs):
    _, runs = ball_runs
    for key in ("projection", "projection+energy"):
        run = runs[key]
        assert run.finished and run.time[-1] == pytest.approx(100.0)
        assert (run.residual_position.shape[1], run.residual_velocity.shape[1]) == (1, 3)
        assert largest(run.residual_position) < 1e-10, key
        assert largest(run.residual_velocity) < 1e-10, key     # d/dt on_bowl and both no-slip rows


def test_ball_energy_correction_holds_the_energy(ball_runs):
    _, runs = ball_runs
    corrected, plain = runs["projection+energy"], runs["projection"]
    assert corrected.energy_correction and not plain.energy_correction
    drift = np.abs(corrected.energy / corrected.energy[0] - 1).max()
    assert drift < 1e-10
    assert drift < 1e-3 * np.abs(plain.energy / plain.energy[0] - 1).max()


def test_ball_first_integral_is_kept(ball_runs):
    model, runs = ball_runs
    for key in ("projection", "projection+energy"):
        eps = first_integral(model, runs[key])
        assert np.abs(eps - eps[0]).max() < 1e-6, key


def test_ball_without_projection_drifts_where_projection_does_not(ball_runs):
    """lagrange and baumgarte, same step: both finish, with residuals far above projection's."""
    _, runs = ball_runs
    for key in ("lagrange", "baumgarte"):
        assert runs[key].finished
        assert largest(runs[key].residual_velocity) > 1e3 * largest(runs["projection"].residual_velocity)


def test_ball_normal_force_multiplier(ball_runs):
    """Radial equation on rho = R - r: lam = -m rho (a'^2 + cos^2 a b'^2) - m g sin a (e_rho . g = g sin a)."""
    model, runs = ball_runs
    run = runs["projection+energy"]
    m, g = parameter(model, "m"), parameter(model, "g")
    rho, a = run.column("rho"), run.column("alpha")
    da, db = run.column("alpha_dot"), run.column("beta_dot")
    expected = -m * rho * (da ** 2 + np.cos(a) ** 2 * db ** 2) - m * g * np.sin(a)
    assert run.multiplier_names == ["normal_force", "friction_beta", "friction_alpha"]
    np.testing.assert_allclose(run.multipliers[:, 0], expected, rtol=1e-9)


def test_ball_runs_are_logged_side_by_side(ball_runs, tmp_path):
    """Residuals and multipliers land in the HDF5 layout of docs/run-file.md, one file per method."""
    model, runs = ball_runs
    for key, run in runs.items():
        back = read_h5(run.save(tmp_path / f"ball_{key}.h5"))
        assert back.multiplier_names == run.multiplier_names
        np.testing.assert_array_equal(back.residual_velocity, run.residual_velocity)
        np.testing.assert_array_equal(back.multipliers, run.multipliers)
        assert back.method == run.method and back.energy_correction == run.energy_correction
    header = (runs["lagrange"].save(tmp_path / "ball.csv")).read_text().splitlines()
    columns = next(line for line in header if line.startswith("time,")).split(",")
    assert {"normal_force", "phi_normal_force", "c_friction_alpha"} <= set(columns)


# -- rheonomic biped ----------------------------------------------------------

def test_biped_recovers_from_an_inconsistent_start(compiled):
    model = compiled("biped_rheonomic")
    run = andyc.simulate(model, 100.0, dt=1e-2, method="projection", init=andyc.Init("as-is"))
    assert run.finished
    assert run.stats["initial_position_residual"] > 1e-3            # the paper's q(0) is off by millimetres
    residual = np.maximum(np.abs(run.residual_position).max(axis=1), np.abs(run.residual_velocity).max(axis=1))
    assert residual[run.time >= 1.0].max() < 1e-10
    settled = run.time[np.nonzero(residual > 1e-10)[0][-1] + 1]
    assert settled <= 0.05                                           # a few steps, not a transient


def test_biped_inconsistent_start_is_refused_without_init(compiled):
    model = compiled("biped_rheonomic")
    with pytest.raises(SimulationError) as err:
        andyc.simulate(model, 1.0, dt=1e-2, method="projection")
    message = str(err.value)
    assert message.startswith("biped_rheonomic.yaml:")
    assert "constraints[4].holonomic" in message and "'torso_pitch'" in message
    assert "--init project" in message and "0.00374" in message


def test_biped_projected_start_is_consistent_from_the_first_sample(compiled):
    model = compiled("biped_rheonomic")
    run = andyc.simulate(model, 2.0, dt=1e-2, method="projection", init=andyc.Init("project"))
    assert run.stats["initial_projection"] > 1e-3
    assert max(largest(run.residual_position), largest(run.residual_velocity)) < 1e-12


# -- four-bar through its singular configuration -----------------------------

def fourbar_closed_form(model, times):
    x0 = model.initial_state(model.parameter_defaults)
    return fourbar_crank_angle(dict(zip(model.parameter_names, model.parameter_defaults)), x0[0], x0[3], times)


@pytest.fixture(scope="module")
def fourbar_run(compiled):
    return andyc.simulate(compiled("fourbar"), 20.0, dt=1e-3, method="projection")


def test_fourbar_projection_through_the_flat_configuration(compiled, fourbar_run):
    run = fourbar_run
    th1 = run.column("th1")
    assert run.finished
    assert np.count_nonzero(np.diff(np.floor(th1 / np.pi))) >= 30   # th1 crosses 0 or pi (flat) 30+ times
    assert largest(run.residual_position) < 1e-9 and largest(run.residual_velocity) < 1e-9
    assert np.abs(run.energy / run.energy[0] - 1).max() < 1e-6
    assert np.abs(th1 + run.column("th2")).max() < 1e-9             # coupler stays level: parallelogram branch
    np.testing.assert_allclose(th1, fourbar_closed_form(compiled("fourbar"), run.time), atol=1e-9)


def test_fourbar_lagrange_fails_at_the_singularity(compiled):
    """Reported, not hidden: without projection the closure drifts and the run leaves the branch or blows up."""
    run = andyc.simulate(compiled("fourbar"), 20.0, dt=1e-3, method="lagrange")
    left_branch = np.abs(run.column("th1") + run.column("th2")).max() > 0.1
    assert not run.finished or left_branch
    if not run.finished:
        assert run.status.startswith("stopped: ") and "samples before it are kept" in run.status


@pytest.fixture(scope="module")
def redundant_fourbar(tmp_path_factory):
    spec = yaml.safe_load((MODELS / "fourbar.yaml").read_text())
    spec["name"] = "fourbar_redundant"
    again = dict(spec["constraints"][0], name="closure_again", multiplier=["fx2", "fy2"])
    spec["constraints"].append(again)
    path = tmp_path_factory.mktemp("models") / "fourbar_redundant.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def test_redundant_closure_gives_the_same_trajectory(compiled, fourbar_run, redundant_fourbar):
    model = compiled(redundant_fourbar)
    assert model.nc == 4
    run = andyc.simulate(model, 20.0, dt=1e-3, method="projection")
    assert run.finished
    # Identical but for rounding where the pseudo-inverse is ill-conditioned: measured 0 at all
    # but 4 of 20001 samples, 8.3e-12 (1.3e-12 relative) next to the flat pose at t = 3.305 s.
    np.testing.assert_allclose(run.state, fourbar_run.state, rtol=1e-11, atol=1e-12)
    # The force splits evenly between the two copies (least-norm multipliers).
    np.testing.assert_allclose(run.multipliers[:, :2] + run.multipliers[:, 2:], fourbar_run.multipliers, atol=1e-6)
    np.testing.assert_allclose(run.multipliers[:, :2], run.multipliers[:, 2:], atol=1e-6)


def test_redundant_closure_is_refused_by_lagrange(compiled, redundant_fourbar):
    for method in ("lagrange", "baumgarte"):
        with pytest.raises(SimulationError) as err:
            andyc.simulate(compiled(redundant_fourbar), 1.0, dt=1e-3, method=method)
        message = str(err.value)
        assert message.startswith("fourbar_redundant.yaml:") and "constraints[1].holonomic[0]" in message
        assert "'closure_again'" in message and "'closure'" in message and "--method projection" in message
