"""The work and power of every element, logged by every run (issue 24; andyc/symbolic/work.py,
andyc/runtime/work.py), against an independent integration.

The driven, damped slider-crank (models/slider_crank.yaml) has one degree of freedom once its loop is
closed. Here its equations are derived again, independently of andyc, by Lagrange's equations in the crank
angle th alone (SymPy), with the slider and rod positions as closed-form functions of th:

    psi = -asin(r sin th / l),  s = r cos th + l cos psi          (the loop, solved)
    L = T_kin(th, th') - V(th),  d/dt dL/dth' - dL/dth = T - c s' ds/dth
    W_drive' = T th',  W_friction' = -c s'^2

and integrated with SciPy's DOP853 at rtol = atol = 1e-13 together with both works. andyc's run (projection
at dt = 5e-4, RK4 on the constrained equations in three coordinates, the work carried through the same RK4
stages) must give each element's work at every logged sample to 1e-9 of its final size (about 230 J each
way over 4 s). What is exact here: nothing but the reference, whose error is ~1e-12; andyc's error is RK4's
truncation error, O(dt^4): measured 2.5e-10 relative at dt = 5e-4, 3.7e-9 at 1e-3 (the test checks the
ratio, about 2^4).
"""

import numpy as np
import pytest
import sympy as sp
from scipy.integrate import solve_ivp

import andyc
from andyc.runtime.runfiles import read_h5
from tests.support import MODELS
from tests.support.diagnostics import line_of, problems


def reference(p: dict, t_eval):
    """(th, th', W_drive, W_friction) at t_eval, by Lagrange's equations in th (see the module docstring)."""
    th, w = sp.symbols("th w")
    r, l, m1, m2, ms, g, T, c = (p[k] for k in ("r", "l", "m1", "m2", "ms", "g", "T", "c"))
    psi = -sp.asin(r * sp.sin(th) / l)
    A = sp.Matrix([r * sp.cos(th), r * sp.sin(th)])            # crank end
    s = A[0] + l * sp.cos(psi)                                  # slider
    rod_com = A + l / 2 * sp.Matrix([sp.cos(psi), sp.sin(psi)])
    crank_com = A / 2
    d = sp.diff
    v_rod = rod_com.diff(th) * w
    kinetic = (m1 * r ** 2 / 3 * w ** 2 / 2                        # crank about its pin: m r^2 / 3
               + m2 * v_rod.dot(v_rod) / 2 + m2 * l ** 2 / 12 * (d(psi, th) * w) ** 2 / 2
               + ms * (d(s, th) * w) ** 2 / 2)
    potential = g * (m1 * crank_com[1] + m2 * rod_com[1])
    mass = sp.diff(kinetic, w, 2)                               # T_kin = mass(th) w^2 / 2
    force = T - c * d(s, th) ** 2 * w                           # generalized force of drive and friction
    # d/dt (mass w) - d/dth (mass w^2 / 2 - V) = force  =>  mass w' = force - mass'(th) w^2 / 2 - V'(th)
    accel = (force - d(mass, th) * w ** 2 / 2 - d(potential, th)) / mass
    f = sp.lambdify((th, w), [accel, T * w, -c * (d(s, th) * w) ** 2], "math")

    def rhs(t, y):
        a, p_drive, p_friction = f(y[0], y[1])
        return [y[1], a, p_drive, p_friction]

    sol = solve_ivp(rhs, (0.0, t_eval[-1]), [p["th0"], p["w0"], 0.0, 0.0], method="DOP853", rtol=1e-13,
                    atol=1e-13, t_eval=t_eval)
    assert sol.success
    return sol.y


@pytest.fixture(scope="module")
def crank_runs(compiled):
    model = compiled("slider_crank")
    return {dt: andyc.simulate(model, 4.0, dt=dt, method="projection") for dt in (5e-4, 1e-3)}


def test_slider_crank_logged_work_equals_an_independent_integral(crank_runs):
    run = crank_runs[5e-4]
    assert run.finished and run.work_names == ["drive", "friction"]
    th, w, w_drive, w_friction = reference(run.parameters, run.time)
    assert np.max(abs(run.column("th") - th)) < 1e-7           # the same motion (measured 8e-9)
    assert abs(th[-1] - th[0]) > 4 * np.pi                      # the crank turns over (two turns and more)
    for k, ref in enumerate((w_drive, w_friction)):
        size = abs(ref[-1])
        assert size > 10.0                                      # joules, not round-off
        assert np.max(abs(run.work[:, k] - ref)) < 1e-9 * size
    # The error is RK4's: fourth order in dt.
    coarse = crank_runs[1e-3]
    _, _, d2, f2 = reference(coarse.parameters, coarse.time)
    e_fine = np.max(abs(run.work[:, 1] - w_friction))
    e_coarse = np.max(abs(coarse.work[:, 1] - f2))
    assert 8 < e_coarse / e_fine < 32
    # The logged power at the samples is T th' and -c s'^2 there.
    p = run.parameters
    np.testing.assert_allclose(run.power[:, 0], p["T"] * run.column("th_dot"), rtol=1e-14, atol=1e-12)
    np.testing.assert_allclose(run.power[:, 1], -p["c"] * run.column("s_dot") ** 2, rtol=1e-14, atol=1e-12)


def test_run_files_carry_power_work_and_balance(crank_runs, tmp_path):
    run = crank_runs[5e-4]
    back = read_h5(run.save(tmp_path / "crank.h5"))
    assert back.work_names == run.work_names
    np.testing.assert_array_equal(back.work, run.work)
    np.testing.assert_array_equal(back.power, run.power)
    np.testing.assert_array_equal(back.energy_balance, run.energy_balance)
    run.save(tmp_path / "crank.csv")
    lines = (tmp_path / "crank.csv").read_text().splitlines()
    header = next(line for line in lines if not line.startswith("#")).split(",")
    for name in ("power_drive", "power_friction", "work_drive", "work_friction", "energy_balance"):
        assert name in header
    table = np.loadtxt(tmp_path / "crank.csv", delimiter=",", comments="#", skiprows=lines.index(",".join(header)) + 1)
    np.testing.assert_allclose(table[:, header.index("work_friction")], run.work[:, 1], rtol=1e-15)
    assert "energy balance residual" in run.summary() and "(change" not in run.summary()


def test_energy_correction_to_the_balance_law_holds_it_at_round_off(crank_runs, compiled):
    """Braun & Goldfarb eq. 5-6 with the law E(t) - E(0) - W(t) = 0: the projection method's energy correction
    moves the speeds (in the constraints' null space, M-metric) onto it after every step. Without it the
    residual is RK4's truncation error (the runs above: ~1e-8 J at dt = 5e-4, 16 times that at 1e-3); with
    it, round-off of energies ~10 J, while the motion still follows the reference to RK4's accuracy."""
    model = compiled("slider_crank")
    plain = crank_runs[1e-3]
    fixed = andyc.simulate(model, 4.0, dt=1e-3, method="projection",
                           projection=andyc.Projection(energy_correction=True))
    assert fixed.finished and fixed.energy_correction and not plain.energy_correction
    assert np.max(abs(plain.energy_balance)) > 1e-8
    assert np.max(abs(fixed.energy_balance)) < 1e-12
    assert np.max(abs(fixed.residual_position)) < 1e-12
    th, _, w_drive, w_friction = reference(fixed.parameters, fixed.time)
    assert np.max(abs(fixed.column("th") - th)) < 1e-6
    assert np.max(abs(fixed.work[:, 1] - w_friction)) < 1e-8 * abs(w_friction[-1])


def test_an_energy_law_that_makes_no_sense_is_refused_with_its_place(tmp_path, compiled):
    # Every speed fixed by a constraint: the correction has no direction (eq. 6's N L^T v is 0).
    text = FIXED.replace("SIM", "simulate: {method: projection, energy_correction: true}")
    (d,) = problems(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "energy_correction"), "simulate.energy_correction")
    assert "the energy law has no speed to correct: the 1 constraint rows of the initial flow fix all 1 speeds" in str(d)
    # A frame whose link depends on t is no longer refused: its driving work is derived (prescribed_motion;
    # tests/test_energy_law.py checks it against an independent integration).
    text = DRIVEN_FRAME + "expect:\n  - {t_end: 1, energy_correction: true, energy_balance: 1}\n"
    (tmp_path / "driven.yaml").write_text(text)
    assert andyc.load(tmp_path / "driven.yaml").expect
    # At run time, on the rank of the rows at the start: the rheonomic biped's 9 rows fix its 9 speeds.
    biped = compiled("biped_rheonomic")
    with pytest.raises(andyc.errors.SimulationError) as info:
        andyc.simulate(biped, 0.01, dt=1e-3, method="projection", init=andyc.Init(mode="project"),
                       projection=andyc.Projection(energy_correction=True))
    line, path = biped.constraint_where[0]
    assert str(info.value).startswith(f"biped_rheonomic.yaml:{line}: {path}: the energy law has no speed to correct")
    with pytest.raises(andyc.errors.SimulationError, match="needs the projection method, not rk4"):
        andyc.simulate(compiled("slider_crank"), 0.01, projection=andyc.Projection(energy_correction=True))


FIXED = """\
name: fixed
parameters: {m: 1}
coordinates: {x: {}}
frames: [{name: cart, parent: world, prismatic: x, axis: x}]
bodies: [{name: b, frame: cart, mass: m}]
constraints: [{name: drive, holonomic: x - 0.1*t}]
SIM
"""

DRIVEN_FRAME = """\
name: driven_frame
parameters: {m: 1, g: 9.81}
coordinates: {q: {initial: 0.1}}
gravity: [0, -g, 0]
frames:
  - {name: cart, parent: world, translation: [0.1*sin(t), 0, 0]}
  - {name: arm, parent: cart, revolute: q}
  - {name: tip, parent: arm, translation: [0, -1, 0]}
bodies: [{name: b, frame: tip, mass: m}]
"""


def test_the_jumps_work_slot_name_is_reserved(tmp_path):
    """A model with jumps logs the energy they change as the work 'jumps' (work_jumps, power_jumps)."""
    text = (MODELS / "bouncing_ball.yaml").read_text().replace(
        "constraints:\n", "dampers: [{name: jumps, coefficient: 0.1, speed: y}]\nconstraints:\n")
    (d,) = problems(tmp_path, text, name="bouncing_ball.yaml")
    assert (d.line, d.path) == (line_of(text, "name: jumps"), "dampers[0].name")
    assert "the name 'jumps' is taken by the work of the model's jumps" in str(d)
