"""Exact sensitivities of a run (andyc.runtime.sensitivities): dx(T)/dx0 and dx(T)/dp against central
differences of the same runs (the compiled loop, without sensitivities), issue 22 item 1: the double pendulum
(rk4, no jumps), the ball in a bowl (the projection method: the constraint and energy corrections after every
step, a quaternion, quasi-velocities and nonholonomic rows), the compass gait across three heel strikes (saltation matrices) and the bouncing ball (impacts
with restitution). The run file keeps them; a method they do not follow is refused."""

import numpy as np

import andyc
from andyc.runtime.runfiles import read_h5
from tests.support import MODELS
from tests.support.cli import invoke

EPS = 1e-6      # central differences at EPS and 2 EPS, extrapolated (Richardson): truncation ~ EPS^4, round-off
                # ~ 1e-16 / EPS times the map's growth; both far below 1e-7


def _derivatives(compiled, shipped_build, name):
    model = compiled(name)
    andyc.build_derivatives(MODELS / f"{name}.yaml", shipped_build)
    return model


def _central_differences(model, t_end, x0, d0, p0, events, method="rk4", dt=1e-3, projection=andyc.Projection()):
    """dx(T)/dx0 and dx(T)/dp, and dT/d(x0, p), by central differences of plain runs (extrapolated)."""
    def end(x, p):
        run = andyc.simulate(model, t_end, dt, method, x0=x, d0=d0, parameters=dict(zip(model.parameter_names, p)),
                             events=events, init=andyc.Init("as-is"), projection=projection, progress=False)
        return np.append(run.state[-1], run.time[-1])

    z0 = np.concatenate([x0, p0])
    nx = len(x0)
    out = np.zeros((nx + 1, len(z0)))
    for j in range(len(z0)):
        e = np.zeros(len(z0))
        e[j] = EPS * max(1.0, abs(z0[j]))
        d1, d2 = ((end(*np.split(z0 + s * e, [nx])) - end(*np.split(z0 - s * e, [nx]))) / (2 * s * e[j])
                  for s in (1, 2))
        out[:, j] = (4 * d1 - d2) / 3
    return out[:nx, :nx], out[:nx, nx:], out[nx]


def _relative(a, b):
    return np.max(np.abs(a - b)) / np.max(np.abs(b))


def test_double_pendulum_rk4(compiled, shipped_build):
    model = _derivatives(compiled, shipped_build, "double_pendulum")
    run = andyc.simulate(model, 2.0, 1e-3, "rk4", sensitivities=True, progress=False)
    S = run.sensitivities
    fx, fp, _ = _central_differences(model, 2.0, run.state[0], run.discrete[0], model.parameters(None), andyc.Events())
    assert S["x0"].shape == (4, 4) and S["p"].shape == (4, 5)
    assert _relative(S["x0"], fx) < 1e-7
    assert _relative(S["p"], fp) < 1e-7
    assert np.all(S["time"] == 0.0)           # a run to a fixed t_end


def test_ball_in_bowl_projection(compiled, shipped_build):
    """The projection method (and lagrange, below): after each step the quaternion to unit norm, the position (eq. 3), velocity (eq. 4)
    and energy (eq. 5-6) corrections, each differentiated. The differences start off the constraint manifold
    (x0 perturbed as-is): the first projection takes them back, and its derivative says how."""
    model = _derivatives(compiled, shipped_build, "ball_in_bowl")
    run = andyc.simulate(model, 0.5, 1e-3, "projection", sensitivities=True, progress=False)
    S = run.sensitivities
    fx, fp, _ = _central_differences(model, 0.5, run.state[0], run.discrete[0], model.parameters(None),
                                     andyc.Events(), "projection")
    assert S["x0"].shape == (13, 13)
    assert _relative(S["x0"], fx) < 1e-7
    assert _relative(S["p"], fp) < 1e-7
    # the corrections matter: the rk4 method's derivative (no projection) is far from the projection's
    plain = andyc.simulate(model, 0.5, 1e-3, "rk4", sensitivities=True, progress=False).sensitivities
    assert _relative(plain["x0"], fx) > 1e-3
    # lagrange: rk4 with independent rows, the same tangent (against its own runs' differences)
    run = andyc.simulate(model, 0.3, 1e-3, "lagrange", sensitivities=True, progress=False)
    fx, fp, _ = _central_differences(model, 0.3, run.state[0], run.discrete[0], model.parameters(None),
                                     andyc.Events(), "lagrange")
    assert _relative(run.sensitivities["x0"], fx) < 1e-7
    assert _relative(run.sensitivities["p"], fp) < 1e-7


def test_double_pendulum_projection_energy_correction(compiled, shipped_build):
    """The projection method on the double pendulum: no rows, so after each step only the energy correction
    (eq. 5-6) along w = v, whose scale w^T M w changes with M(q): its derivative carries w^T (dM/dz) w, which the
    ball in a bowl (a sphere: M constant) never tests. It is weighted by the step's energy error, so the step is
    coarse (h = 0.05 s, 2 s). Against the central differences of the same runs (1e-9 apart; with that term's sign
    turned, 5e-6 and 2e-4)."""
    model = _derivatives(compiled, shipped_build, "double_pendulum")
    energy = andyc.Projection(energy_correction=True)       # (the model declares no energy law: asked for)
    run = andyc.simulate(model, 2.0, 0.05, "projection", sensitivities=True, projection=energy, progress=False)
    S = run.sensitivities
    fx, fp, _ = _central_differences(model, 2.0, run.state[0], run.discrete[0], model.parameters(None),
                                     andyc.Events(), "projection", dt=0.05, projection=energy)
    assert _relative(S["x0"], fx) < 1e-7
    assert _relative(S["p"], fp) < 1e-7


def test_compass_gait_through_heel_strikes(compiled, shipped_build):
    """Three heel strikes (strike2, strike1, strike2), the run ending right after the third: the state just
    after it and its time, as a step map sees them. Event location to round-off (tol 1e-15), so that the
    differences of the runs see the root of the discrete map, not the bracket's width."""
    model = _derivatives(compiled, shipped_build, "compass_gait")
    events = andyc.Events(tol=1e-15, stop_after={"strike2": 2})
    run = andyc.simulate(model, 3.0, 1e-3, "rk4", sensitivities=True, events=events, progress=False)
    assert run.status == "finished" and len(run.events["time"]) == 3
    S = run.sensitivities
    fx, fp, ft = _central_differences(model, 3.0, run.state[0], run.discrete[0], model.parameters(None), events)
    assert _relative(S["x0"], fx) < 1e-7
    assert _relative(S["p"], fp) < 1e-7
    time = np.delete(S["time"], np.arange(model.nx, model.nx + model.nd))     # (x0, p) of (x0, d0, p)
    assert np.max(np.abs(time - ft)) < 1e-7 * np.max(np.abs(ft))
    # the saltation matters: the same derivative without the jumps' time shifts would be far off
    assert np.max(np.abs(S["time"])) > 0.1


def test_bouncing_ball_restitution(compiled, shipped_build):
    """Three bounces with e = 0.8: the impact's Jacobian with a restitution, and its derivative in e."""
    model = _derivatives(compiled, shipped_build, "bouncing_ball")
    events = andyc.Events(tol=1e-15)
    run = andyc.simulate(model, 1.9, 1e-3, "rk4", sensitivities=True, events=events, progress=False)
    assert len(run.events["time"]) == 3
    S = run.sensitivities
    fx, fp, _ = _central_differences(model, 1.9, run.state[0], run.discrete[0], model.parameters(None), events)
    assert _relative(S["x0"], fx) < 1e-7
    assert _relative(S["p"], fp) < 1e-7
    assert abs(S["p"][1, model.parameter_names.index("e")]) > 1.0      # e matters, and is differentiated


def test_run_file_and_refusals(compiled, shipped_build, tmp_path):
    """andyc sim --sensitivities writes /sensitivities into the HDF5 run file (the CSV says it does not hold
    them); the baumgarte method is refused with the reason (its soft terms are not differentiated)."""
    _derivatives(compiled, shipped_build, "double_pendulum")
    h5, csv = tmp_path / "dp.h5", tmp_path / "dp.csv"
    result = invoke("sim", MODELS / "double_pendulum.yaml", "--t-end", 0.2, "--sensitivities", "-o", h5, "-o", csv,
                    "--build-dir", shipped_build)
    assert result.exit_code == 0, result.output
    assert "a CSV run file does not hold them" in result.stdout
    run = read_h5(h5)
    model = compiled("double_pendulum")
    again = andyc.simulate(model, 0.2, 1e-3, "rk4", sensitivities=True, progress=False)
    assert np.array_equal(run.sensitivities["x0"], again.sensitivities["x0"])
    assert np.array_equal(run.sensitivities["p"], again.sensitivities["p"])
    refused = invoke("sim", MODELS / "double_pendulum.yaml", "--t-end", 0.2, "--method", "baumgarte",
                     "--sensitivities", "-o", tmp_path / "p.h5", "--build-dir", shipped_build)
    assert refused.exit_code == 2
    assert "method 'baumgarte': sensitivities follow the rk4, lagrange and projection methods only" in refused.output
