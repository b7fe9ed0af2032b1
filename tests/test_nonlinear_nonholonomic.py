"""Nonholonomic rows nonlinear in the speeds (issue 24; Braun & Goldfarb Part II §2.2.3), each run checked
against an independent integration of equations of motion derived by hand, here, with the multiplier.

- Appell-Hamel (Appell 1911; Neimark & Fufaev, Dynamics of Nonholonomic Systems, 1972, ch. I §6): a particle
  of mass m, m v' = m g + lam A, under the row Phi = w_z - k sqrt(w_x^2 + w_y^2) = 0 on its velocity w in the
  axes of a fixed frame (the cone's axis z; A = dPhi/dw = (-k u, 1), u = (w_x, w_y) / s the unit horizontal
  velocity, s = |(w_x, w_y)|). With h = (g_x, g_y) and g_z gravity in those axes, dPhi/dt = 0 along the motion
  is s' = h.u - lam k / m, w_z' = g_z + lam / m = k s', so

      lam = m (k h.u - g_z) / (1 + k^2),   (w_x, w_y)' = h - (lam k / m) u,   w_z' = g_z + lam / m.

  With the cone upright (h = 0) lam = m g / (1 + k^2) and the motion is the closed form in
  models/appell_hamel.yaml; tilted (the row written with frame velocities `in` a rotated frame) it curves.
- Gauss's isokinetic constraint |v|^2 - c = 0 in the well V = (kx x^2 + ky y^2)/2: m v' = -grad V + 2 lam v
  and v.v' = 0 give 2 lam = v.grad V / |v|^2, i.e. m v' = -grad V + (v.grad V / |v|^2) v (Evans & Morriss,
  Statistical Mechanics of Nonequilibrium Liquids, 2008, §5.2).

The references are SciPy's DOP853 at rtol = atol = 1e-13 (their own error, against rtol 1e-12: below 1e-11
over the 10 s here). andyc runs the projection method (RK4, then Braun & Goldfarb eq. 3-4) at dt = 1e-3.
"""

import numpy as np
import pytest
import yaml
from scipy.integrate import solve_ivp

import andyc
from andyc.symbolic.linearize import LinearizeError, linearize
from tests.support import MODELS

T_END, DT = 10.0, 1e-3
STATES = ["x", "y", "z", "x_dot", "y_dot", "z_dot"]


def parameter(model, name, given=None):
    return (given or {}).get(name, model.parameter_defaults[model.parameter_names.index(name)])


def states(run, names):
    return np.stack([run.column(n) for n in names], axis=1)


def rotation_x(angle):
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


# -- Appell-Hamel --------------------------------------------------------------------------------------

def appell_hamel_rate(t, y, m, k, gravity):
    """(r, w)' in the cone's axes (the module docstring's equations); gravity in those axes."""
    w = y[3:]
    s = np.hypot(w[0], w[1])
    u = w[:2] / s
    h, gz = gravity[:2], gravity[2]
    lam = m * (k * (h @ u) - gz) / (1 + k * k)
    return np.concatenate([w, h - lam * k / m * u, [gz + lam / m]])


def appell_hamel_reference(model, given, tilt):
    """The reference trajectory (world axes) at the run's sample times, and the multiplier along it."""
    m, k, g = (parameter(model, n, given) for n in ("m", "k", "g"))
    R = rotation_x(tilt)                                    # the cone's axes in world
    x0 = model.initial_state(model.parameters(given))
    y0 = np.concatenate([R.T @ x0[:3], R.T @ x0[3:6]])
    gravity = R.T @ np.array([0.0, 0.0, -g])
    sol = solve_ivp(appell_hamel_rate, (0.0, T_END), y0, method="DOP853", rtol=1e-13, atol=1e-13,
                    dense_output=True, args=(m, k, gravity))
    assert sol.success

    def at(t):
        y = sol.sol(t).T
        w = y[:, 3:]
        u = w[:, :2] / np.hypot(w[:, 0], w[:, 1])[:, None]
        lam = m * (k * (u @ gravity[:2]) - gravity[2]) / (1 + k * k)
        return np.concatenate([y[:, :3] @ R.T, w @ R.T], axis=1), lam

    return at


@pytest.fixture(scope="module")
def tilted(tmp_path_factory):
    """The Appell-Hamel model with its cone tilted by 0.6 rad about x: the row in a rotated frame's axes,
    the initial velocity on the tilted cone (horizontal part (6, 0) in the cone's axes)."""
    spec = yaml.safe_load((MODELS / "appell_hamel.yaml").read_text())
    spec["name"] = "appell_hamel_tilted"
    spec["parameters"].update({"tilt": 0.6, "u0": 6, "w0": 0})
    spec["coordinates"] = {"x": {"velocity": "u0"},
                           "y": {"velocity": "cos(tilt)*w0 - sin(tilt)*k*sqrt(u0**2 + w0**2)"},
                           "z": {"velocity": "sin(tilt)*w0 + cos(tilt)*k*sqrt(u0**2 + w0**2)"}}
    spec["frames"].insert(0, {"name": "axis", "parent": "world", "rotation": {"axis": "x", "angle": "tilt"}})
    spec["constraints"][0]["in"] = "axis"
    for key in ("closed_form", "expect", "simulate"):
        del spec[key]
    path = tmp_path_factory.mktemp("models") / "appell_hamel_tilted.yaml"
    path.write_text(yaml.safe_dump(spec, sort_keys=False))
    return path


def test_appell_hamel_matches_the_closed_form_and_an_independent_integration(compiled):
    """Upright cone: lam = m g / (1 + k^2) and the closed form of the model file; states within 1e-10 of
    both over 10 s (x ~ 250 m), the row at round-off, the energy kept (the row does no work)."""
    model = compiled("appell_hamel")
    run = andyc.simulate(model, T_END, dt=DT, method="projection")
    assert run.finished and run.energy_correction
    got = states(run, STATES)
    reference, lam = appell_hamel_reference(model, {}, 0.0)(run.time)
    u, p = model.input_defaults, model.parameter_defaults
    closed = np.array([model.closed_form(float(t), u, p) for t in run.time])
    assert list(run.state_names) == STATES
    assert np.abs(got - reference).max() < 1e-10
    assert np.abs(got - closed).max() < 1e-10
    assert np.abs(run.residual_velocity).max() < 1e-12
    m, g, k = (parameter(model, n) for n in ("m", "g", "k"))
    np.testing.assert_allclose(run.multipliers[:, 0], m * g / (1 + k * k), rtol=1e-12)
    np.testing.assert_allclose(lam, m * g / (1 + k * k), rtol=1e-14)
    assert np.abs(run.energy - run.energy[0]).max() < 1e-9 * np.abs(run.energy).max()


def test_appell_hamel_on_a_tilted_cone_matches_an_independent_integration(compiled, tilted):
    """The row through frame velocities in a rotated frame (`in: axis`): a curving path, within 1e-10 of the
    reference over 10 s; the row at round-off; the multiplier lam = m (k h.u - g_z) / (1 + k^2)."""
    model = compiled(tilted)
    run = andyc.simulate(model, T_END, dt=DT, method="projection")
    assert run.finished
    reference, lam = appell_hamel_reference(model, {}, parameter(model, "tilt"))(run.time)
    got = states(run, STATES)
    assert np.abs(got - reference).max() < 1e-10
    assert np.ptp(np.arctan2(got[:, 3], got[:, 4])) > 0.5       # the horizontal velocity turns: not a line
    assert np.abs(run.residual_velocity).max() < 1e-12
    np.testing.assert_allclose(run.multipliers[:, 0], lam, rtol=1e-11)


def test_the_nonlinear_row_its_jacobian_and_kappa(compiled, tilted):
    """At random states: c is the row written out by hand, A = dc/dv (central differences in v: c is not
    affine in v here) and kappa = dc/dt at dv/dt = 0 (here 0: the row depends on the speeds only)."""
    model = compiled(tilted)
    p = model.parameter_defaults
    k, R = parameter(model, "k"), rotation_x(parameter(model, "tilt"))
    d, u = model.initial_discrete(p), model.input_defaults
    rng = np.random.default_rng(24)

    def terms(x):
        phi, c, A, kappa = np.empty(0), np.empty(1), np.zeros((1, 3)), np.empty(1)
        model.module.constraints(0.4, x, u, p, d, phi, c, A, kappa)
        return c[0], A[0], kappa[0]

    for _ in range(5):
        x = rng.uniform(-3, 3, 6)
        c, A, kappa = terms(x)
        w = R.T @ x[3:]
        assert c == pytest.approx(w[2] - k * np.hypot(w[0], w[1]), abs=1e-14)
        eps = 1e-6
        fd = [(terms(x + eps * e)[0] - terms(x - eps * e)[0]) / (2 * eps) for e in np.eye(6)[3:]]
        np.testing.assert_allclose(A, fd, atol=1e-8)
        assert kappa == 0.0


def test_a_model_with_a_nonlinear_row_is_not_linearized(compiled, tilted):
    model = compiled(tilted)
    x, u, p = model.initial_state(model.parameter_defaults), model.input_defaults, model.parameter_defaults
    with pytest.raises(LinearizeError, match="constraint 'cone' is not linear in the speeds"):
        linearize(andyc.derive(andyc.load(tilted)), x, u, p)


# -- Gauss's isokinetic constraint ---------------------------------------------------------------------

def isokinetic_reference(model):
    m, kx, ky = (parameter(model, n) for n in ("m", "kx", "ky"))

    def rate(t, s):
        v = s[2:]
        grad = np.array([kx * s[0], ky * s[1]])
        return np.concatenate([v, (-grad + (v @ grad) / (v @ v) * v) / m])

    sol = solve_ivp(rate, (0.0, T_END), model.initial_state(model.parameter_defaults), method="DOP853",
                    rtol=1e-13, atol=1e-13, dense_output=True)
    assert sol.success
    return lambda t: sol.sol(t).T


@pytest.fixture(scope="module")
def isokinetic(compiled):
    model = compiled("isokinetic")
    return model, isokinetic_reference(model)


def test_isokinetic_speed_stays_put_and_the_path_matches(isokinetic):
    model, reference = isokinetic
    run = andyc.simulate(model, T_END, dt=DT, method="projection")
    assert run.finished and not run.energy_correction
    got = states(run, ["x", "y", "x_dot", "y_dot"])
    assert np.abs(got - reference(run.time)).max() < 1e-10
    speed = np.hypot(got[:, 2], got[:, 3])
    assert np.abs(speed - parameter(model, "v0")).max() < 1e-14
    assert np.ptp(run.energy) > 0.1          # the constraint does work: the energy is not conserved


def test_isokinetic_lagrange_and_baumgarte_follow_the_acceleration_level_row(isokinetic):
    """From a start off the row (the speed 1e-3 too high: Phi_0 = (1.001^2 - 1) v0^2), lagrange enforces the
    acceleration-level row A v' + kappa = 0, so Phi stays Phi_0. baumgarte adds the generalized force
    -A^T kd Phi (ANDY eq. 15), so Phi' = -W kd Phi with W = A M^-1 A^T = 4 |v|^2 / m = 4 (Phi + c) / m,
    c = v0^2: with a = 4 kd / m, 1/Phi grows as (1/Phi_0 + 1/c) exp(a c t) - 1/c. Both to RK4's error:
    the truncation error of the motion moves Phi by ~4e-12 over 2 s under lagrange, and holds it ~1e-10 off
    0 against the baumgarte term (the tolerances)."""
    model, _ = isokinetic
    p = model.parameter_defaults
    x0 = model.initial_state(p).copy()
    x0[2:] *= 1.001
    m, v0, kd = (parameter(model, n) for n in ("m", "v0", "kd"))
    c = v0 ** 2
    phi0 = (1.001 ** 2 - 1) * c
    as_is = andyc.Init("as-is")
    lagrange = andyc.simulate(model, 2.0, dt=DT, method="lagrange", x0=x0, init=as_is)
    baumgarte = andyc.simulate(model, 2.0, dt=DT, method="baumgarte", x0=x0, init=as_is)
    np.testing.assert_allclose(lagrange.residual_velocity[:, 0], phi0, rtol=1e-8)
    a = 4 * kd / m
    expected = 1 / ((1 / phi0 + 1 / c) * np.exp(a * c * baumgarte.time) - 1 / c)
    np.testing.assert_allclose(baumgarte.residual_velocity[:, 0], expected, rtol=1e-8, atol=3e-10)
    assert expected[-1] < 1e-12 and np.abs(baumgarte.residual_velocity[-1, 0]) < 1e-10    # from 2e-3


def test_isokinetic_lagrange_from_the_row_matches_too(isokinetic):
    """Started on the row, lagrange's acceleration-level form follows the same motion (RK4 at 1e-3)."""
    model, reference = isokinetic
    run = andyc.simulate(model, T_END, dt=DT, method="lagrange")
    got = states(run, ["x", "y", "x_dot", "y_dot"])
    assert np.abs(got - reference(run.time)).max() < 1e-10
