"""The constraint rows, their Jacobian A and velocity-product term kappa
(andyc.symbolic.constraints), checked numerically along the motion.

At a random state x with speeds v, move along x(s) = x + s xdot with
xdot = (v[:NQ], 0, dsigma/dt) (coordinates at their rates, speeds held, signals
at their rates) and t(s) = t + s. Then, with central differences:

    c     = d/ds phi(t(s), x(s))       (holonomic rows)
    kappa = d/ds c(t(s), x(s))         (dv/dt = 0)
    A     = dc/dv                      (c is affine in v)

The models cover frame positions and velocities in world and in a moving
frame (`in: c`), angular velocities, a ball joint (quaternion signals),
time-dependent (rheonomic) rows, and rows nonlinear in the speeds (there A is
checked by central differences in each speed instead).
"""

import numpy as np
import pytest
import yaml

from tests.support import MODELS

EPS = 1e-5


def evaluate(model, t, x, p):
    u = model.input_defaults
    phi, c, A, kappa = np.empty(model.nh), np.empty(model.nc), np.zeros((model.nc, model.nv)), np.empty(model.nc)
    model.module.constraints(t, x, u, p, model.initial_discrete(p), phi, c, A, kappa)
    return phi, c, A, kappa


def path_rate(model, t, x, p):
    """dx/ds with the speeds held: coordinates move at v[:NQ], signals at their rates."""
    xdot = np.zeros(model.nx)
    model.module.signal_rates(t, x, model.input_defaults, p, model.initial_discrete(p), xdot)
    xdot[:model.nq] = x[model.nq:model.nq + model.nq]
    xdot[model.nq:model.nq + model.nv] = 0.0
    return xdot


def random_state(model, rng):
    x = model.initial_state(model.parameter_defaults).copy()
    x[:model.nq] += rng.uniform(-0.5, 0.5, model.nq)
    x[model.nq:model.nq + model.nv] = rng.uniform(-2, 2, model.nv)
    for k in model.quaternions:
        quat = rng.normal(size=4)
        x[k:k + 4] = quat / np.linalg.norm(quat)
    return x


@pytest.fixture(scope="module")
def swing_bar_constrained(tmp_path_factory):
    """The swing bar with rows through its ball joint: positions and velocities in the moving frame bar1."""
    spec = yaml.safe_load((MODELS / "swing_bar.yaml").read_text())
    spec["name"] = "swing_bar_constrained"
    spec["constraints"] = [
        {"name": "bar3_height", "holonomic": "bar3.z + 0.1*bar3.x*bar2.y - 0.2*sin(t)", "in": "bar1"},
        {"name": "bar3_drift", "nonholonomic": ["bar3.vx + bar2.wy*bar3.y", "bar2.vz - qh_dot*bar3.x"],
         "in": "bar1"},
    ]
    path = tmp_path_factory.mktemp("models") / "swing_bar_constrained.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


@pytest.mark.parametrize("name", ["ball_in_bowl", "fourbar", "biped_rheonomic", "swing_bar_constrained"])
def test_jacobian_and_kappa_agree_with_finite_differences(compiled, name, request):
    model = compiled(request.getfixturevalue(name) if name == "swing_bar_constrained" else name)
    p = model.parameter_defaults
    rng = np.random.default_rng(7)
    for _ in range(5):
        t = rng.uniform(0, 3)
        x = random_state(model, rng)
        phi, c, A, kappa = evaluate(model, t, x, p)
        xdot = path_rate(model, t, x, p)
        ahead, behind = evaluate(model, t + EPS, x + EPS * xdot, p), evaluate(model, t - EPS, x - EPS * xdot, p)
        dphi = (ahead[0] - behind[0]) / (2 * EPS)
        dc = (ahead[1] - behind[1]) / (2 * EPS)
        scale = 1 + np.abs(c).max() + np.abs(kappa).max()
        np.testing.assert_allclose(c[:model.nh], dphi, atol=1e-7 * scale, err_msg="c != d phi/dt")
        np.testing.assert_allclose(kappa, dc, atol=1e-7 * scale, err_msg="kappa != dc/dt at dv/dt = 0")
        # c is affine in the speeds, with slope A.
        for j in range(model.nv):
            y = x.copy()
            y[model.nq + j] += 1.0
            np.testing.assert_allclose(evaluate(model, t, y, p)[1] - c, A[:, j], atol=1e-12 * scale)


@pytest.fixture(scope="module")
def swing_bar_nonlinear(tmp_path_factory):
    """The swing bar with rows nonlinear in the speeds (issue 24): frame velocities of moving frames in a
    moving frame's axes, squared and multiplied together, with coordinates, frame positions and t; so kappa
    carries every term (dPhi/dq q', dPhi/dt, and the frame quantities' rates)."""
    spec = yaml.safe_load((MODELS / "swing_bar.yaml").read_text())
    spec["name"] = "swing_bar_nonlinear"
    spec["constraints"] = [
        {"name": "bar3_spin", "in": "bar1",
         "nonholonomic": ["bar3.vx**2 + bar2.wy*bar3.vy*bar3.x - qh_dot**2*sin(t) + wz*sqrt(1 + bar3.vz**2)",
                          "bar3.wz*qh_dot - cos(qh)*bar2.vx**2 + 0.3*t*wx**3"]},
    ]
    path = tmp_path_factory.mktemp("models") / "swing_bar_nonlinear.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def test_nonlinear_rows_jacobian_and_kappa_agree_with_finite_differences(compiled, swing_bar_nonlinear):
    """As above, with c not affine in v: A = dc/dv by central differences in each speed."""
    model = compiled(swing_bar_nonlinear)
    p = model.parameter_defaults
    rng = np.random.default_rng(24)
    for _ in range(5):
        t = rng.uniform(0, 3)
        x = random_state(model, rng)
        _, c, A, kappa = evaluate(model, t, x, p)
        xdot = path_rate(model, t, x, p)
        ahead, behind = evaluate(model, t + EPS, x + EPS * xdot, p), evaluate(model, t - EPS, x - EPS * xdot, p)
        dc = (ahead[1] - behind[1]) / (2 * EPS)
        scale = 1 + np.abs(c).max() + np.abs(kappa).max() + np.abs(A).max()
        np.testing.assert_allclose(kappa, dc, atol=1e-7 * scale, err_msg="kappa != dc/dt at dv/dt = 0")
        for j in range(model.nv):
            step = np.zeros(model.nx)
            step[model.nq + j] = EPS
            fd = (evaluate(model, t, x + step, p)[1] - evaluate(model, t, x - step, p)[1]) / (2 * EPS)
            np.testing.assert_allclose(A[:, j], fd, atol=1e-7 * scale, err_msg=f"A[:, {j}] != dc/dv")
        assert np.abs(kappa).min() > 1e-3                  # the test has something to check


def test_rheonomic_rows_carry_their_time_derivatives(compiled):
    """biped knee row: th2 - th1 + pi/10 (1 - cos(w t)); c and kappa hold the explicit d/dt terms."""
    model = compiled("biped_rheonomic")
    p = model.parameter_defaults
    w = p[model.parameter_names.index("w")]
    x = model.initial_state(p).copy()
    x[model.nq:] = 0.0                    # at rest: only the explicit time terms are left
    t = 0.3
    phi, c, A, kappa = evaluate(model, t, x, p)
    row = model.constraint_rows.index("knee1")
    assert phi[row] == pytest.approx(x[4] - x[3] + np.pi / 10 * (1 - np.cos(w * t)), abs=1e-15)
    assert c[row] == pytest.approx(np.pi / 10 * w * np.sin(w * t), rel=1e-13)
    assert kappa[row] == pytest.approx(np.pi / 10 * w ** 2 * np.cos(w * t), rel=1e-13)
    np.testing.assert_array_equal(A[row], np.eye(model.nv)[4] - np.eye(model.nv)[3])


def test_fourbar_closure_matches_its_geometry(compiled):
    """phi = coupler end - rocker end, written out by hand."""
    model = compiled("fourbar")
    p = model.parameter_defaults
    a, d = (p[model.parameter_names.index(k)] for k in ("a", "d"))
    x = np.array([0.3, -0.2, 0.5, 1.0, 2.0, 3.0])
    th1, th2, th3 = x[:3]
    coupler_end = a * np.array([np.cos(th1), np.sin(th1)]) + d * np.array([np.cos(th1 + th2), np.sin(th1 + th2)])
    rocker_end = np.array([d, 0.0]) + a * np.array([np.cos(th3), np.sin(th3)])
    np.testing.assert_allclose(evaluate(model, 0.0, x, p)[0], coupler_end - rocker_end, atol=1e-15)
