"""A declared energy-type law Phi_e(t, q, v) = 0 (Braun & Goldfarb §2 item (d), eq. 5-6; andyc/spec/energy_law.py)
and the work of the baumgarte method's constraint forces (issue 24).

models/central_force.yaml: a particle in the central well V = k (1 + a sin(w t)) |r|^2 / 2. The force is central,
so the angular momentum L = m (x y' - y x') is a first integral whatever the well's time dependence (Goldstein,
Poole & Safko, Classical Mechanics, 3rd ed., §3.2), while the energy is not (dV/dt != 0 at fixed q). Its declared
law m (x y' - y x') - L0 = 0 is checked here from the logged states (numpy, not andyc's leaf), and the motion
against SciPy's DOP853 on x'' = -k (1 + a sin(w t)) x / m, the same for y, written here.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import andyc
from andyc.errors import SimulationError
from andyc.runtime.options import Init, Projection
from tests.support import MODELS
from tests.support.diagnostics import edit, line_of, one_problem

CENTRAL = (MODELS / "central_force.yaml").read_text()
P = {"m": 1.0, "k": 4.0, "a": 0.5, "w": 3.0, "L0": 1.2}


def momentum(run) -> np.ndarray:
    x, y, xd, yd = run.state.T
    return P["m"] * (x * yd - y * xd)


def reference(t_eval) -> np.ndarray:
    """The motion by DOP853 at rtol 1e-12 (states as rows: x, y, x', y')."""
    def rhs(t, s):
        f = -P["k"] * (1 + P["a"] * np.sin(P["w"] * t)) / P["m"]
        return [s[2], s[3], f * s[0], f * s[1]]

    sol = solve_ivp(rhs, (0.0, t_eval[-1]), [1.0, 0.0, 0.0, P["L0"] / P["m"]], method="DOP853", rtol=1e-12,
                    atol=1e-12, t_eval=t_eval)
    assert sol.success
    return sol.y


def test_declared_law_kept_to_round_off(compiled):
    """With the projection method the correction keeps L at round-off (on by default: the model declares a law);
    without it L shows RK4's truncation error; with it the motion is no farther from DOP853's."""
    model = compiled("central_force")
    assert model.energy_laws == ("m*(x*y_dot - y*x_dot) - L0",)
    kept = andyc.simulate(model, 10.0, 0.01, "projection")
    free = andyc.simulate(model, 10.0, 0.01, "projection", projection=Projection(energy_correction=False))
    assert kept.finished and free.finished and kept.energy_correction and not free.energy_correction
    err_kept = np.abs(momentum(kept) - P["L0"]).max() / P["L0"]
    err_free = np.abs(momentum(free) - P["L0"]).max() / P["L0"]
    assert err_kept <= 1e-12                     # measured 3.7e-16
    assert err_free > 1e-10 and err_free > 1000 * err_kept      # measured 1.5e-9: RK4's truncation error
    ref = reference(kept.time)
    dist_kept = np.abs(kept.state.T - ref).max()
    dist_free = np.abs(free.state.T - ref).max()
    assert dist_kept <= dist_free                # measured 6.08e-8 and 6.12e-8 (RK4's phase error)
    # The energy is not the law: it changes by the well's work, which the balance still carries.
    assert np.ptp(kept.energy) > 0.1


def test_per_flow_law_is_the_flows(compiled):
    """models/central_force_hybrid.yaml: a kick at t1 = 3 doubles L. Before it the model's law (L = L0) holds, after
    it the flow's own (L = 2 L0): each to round-off, where the model's law would pull L back to L0 and the built-in
    energy balance would leave it to RK4's drift."""
    model = compiled("central_force_hybrid")
    assert model.energy_laws == ("m*(x*y_dot - y*x_dot) - L0", "m*(x*y_dot - y*x_dot) - 2*L0")
    run = andyc.simulate(model, 6.0, 0.01, "projection")
    free = andyc.simulate(model, 6.0, 0.01, "projection", projection=Projection(energy_correction=False))
    assert run.finished and len(run.events["time"]) == 1
    before, after = run.flow == 0, run.flow == 1
    assert before.sum() > 100 and after.sum() > 100
    L = momentum(run)
    assert np.abs(L[before] - P["L0"]).max() <= 1e-12 * P["L0"]
    assert np.abs(L[after] - 2 * P["L0"]).max() <= 1e-12 * P["L0"]
    drift = np.abs(momentum(free)[free.flow == 1] - 2 * P["L0"]).max()
    assert drift > 1e-10                         # measured 2.1e-9


def test_law_off_at_the_start_is_refused(compiled):
    """A law that does not hold at the initial state is refused with its line, unless --init as-is."""
    model = compiled("central_force")
    x0 = np.array([1.0, 0.0, 0.0, 1.0])          # L = 1.0, the law says 1.2
    with pytest.raises(SimulationError) as info:
        andyc.simulate(model, 0.1, 0.01, "projection", x0=x0)
    line = line_of(CENTRAL, "energy_law:")
    assert str(info.value).startswith(f"central_force.yaml:{line}: energy_law: the energy law")
    assert "is -0.2 at the initial state" in str(info.value) and "--init as-is" in str(info.value)
    run = andyc.simulate(model, 0.1, 0.01, "projection", x0=x0, init=Init("as-is"))
    assert np.abs(momentum(run)[1:] - P["L0"]).max() <= 1e-14     # the first step's correction put it there


# -- errors: FILE:LINE: PATH: what; fix --------------------------------------------------------------------------

LAW = "energy_law: m*(x*y_dot - y*x_dot) - L0"


@pytest.mark.parametrize("law, what, fix", [
    ("energy_law: [m*x_dot, m*y_dot]", "must be one scalar expression Phi_e(t, q, v) = 0, got a list of 2",
     "write one expression"),
    ("energy_law: {value: m*x_dot}", "must be one scalar expression Phi_e(t, q, v) = 0, got a mapping",
     "write one expression"),
    ("energy_law: m*x - L0", "depends on no speed", "write a law of the speeds"),
    ("energy_law: sin(x_dot)**2 + cos(x_dot)**2 - x", "identically 0", "simplify the law"),
    ("energy_law: m*(x*y_dot - y*x_dt) - L0", "unknown name 'x_dt'", "did you mean 'x_dot'"),
])
def test_law_errors(tmp_path, law, what, fix):
    text = edit(CENTRAL, LAW, law)
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "energy_law:"), "energy_law")
    assert what in d.message and fix in d.hint, str(d)


def test_law_on_a_model_without_speeds(tmp_path):
    text = ("name: still\nparameters: {m: 1}\nframes:\n  - {name: f, parent: world, translation: [1, 0, 0]}\n"
            "bodies:\n  - {name: b, frame: f, mass: m}\nenergy_law: m - 1\n")
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (7, "energy_law")
    assert "no speeds" in d.message and "remove energy_law" in d.hint


def test_law_where_the_correction_cannot_apply(tmp_path):
    """A flow whose rows fix every speed (no direction, eq. 6), and a model-level law beside conserves_energy."""
    text = edit(CENTRAL, "simulate:", "constraints:\n  - {name: pin, holonomic: [x - 1, y]}\nsimulate:")
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "energy_law:"), "energy_law")
    assert "cannot be corrected in flow 'default': its 2 constraint rows fix all 2 speeds" in d.message
    assert "remove energy_law there" in d.hint
    text = edit(CENTRAL, "potentials:\n  - {name: well, energy: k*(1 + a*sin(w*t))*(x**2 + y**2)/2}\n",
                "potentials:\n  - {name: well, energy: k*(x**2 + y**2)/2}\nconserves_energy: true\n")
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "energy_law:"), "energy_law")
    assert "two laws" in d.message and "remove one of them" in d.hint


def test_flow_law_error_points_at_the_flow(tmp_path):
    text = (MODELS / "central_force_hybrid.yaml").read_text()
    text = edit(text, "energy_law: m*(x*y_dot - y*x_dot) - 2*L0", "energy_law: 2*L0 - x")
    d = one_problem(tmp_path, text)
    assert (d.line, d.path) == (line_of(text, "2*L0 - x"), "hybrid.flows[1].energy_law")
    assert "depends on no speed" in d.message


# -- the baumgarte method's work (item 3) --------------------------------------------------------------------------

@pytest.mark.parametrize("name, t_end, slot", [("ball_in_bowl", 2.0, "baumgarte"), ("fourbar", 0.15, "baumgarte"),
                                               ("isokinetic", 2.0, "isokinetic")])
def test_baumgarte_work_closes_the_balance(compiled, name, t_end, slot):
    """Started off its constraints (speeds 1 % too large, a coordinate 1 mm off; --init as-is), the baumgarte
    method's soft terms pull the state back, and the constraint forces do work off the manifold (lam A v with
    c != 0). With it in W the balance E - E0 - W is RK4's truncation error: at most 1e-9 J, and 16 times smaller at
    half the step (fourth order); without it the balance would be off by that work (3.3e-3 J, 5.6e-2 J, ...)."""
    model = compiled(name)
    x0 = model.initial_state(model.parameters()).copy()
    x0[model.nq:model.nq + model.nv] *= 1.01
    x0[0] += 1e-3
    runs = [andyc.simulate(model, t_end, dt, "baumgarte", x0=x0, init=Init("as-is")) for dt in (1e-3, 5e-4)]
    coarse, fine = (np.abs(r.energy_balance).max() for r in runs)
    assert all(r.finished for r in runs)
    assert coarse <= 1e-9 and 8 < coarse / fine < 32, (coarse, fine)
    carried = abs(runs[1].work[-1, runs[1].work_names.index(slot)])
    assert carried > 1e3 * coarse                # the part of W these forces do
    # The logged power (the run's own multipliers, soft terms included) integrates to the carried work.
    power = runs[1].power[:, runs[1].work_names.index(slot)]
    t = runs[1].time
    trapezoid = np.sum((power[1:] + power[:-1]) / 2 * np.diff(t))
    assert abs(trapezoid - runs[1].work[-1, runs[1].work_names.index(slot)]) <= 1e-6 * max(1.0, carried)


def test_projection_energy_correction_with_gains(compiled):
    """The same stabilized model with the projection method and energy correction: the balance at round-off (the
    projection applies no soft terms: the `baumgarte` slot stays 0)."""
    run = andyc.simulate(compiled("ball_in_bowl"), 2.0, 1e-3, "projection", projection=Projection(energy_correction=True))
    assert run.finished and run.energy_correction
    assert np.abs(run.work[:, run.work_names.index("baumgarte")]).max() == 0.0
    assert np.abs(run.energy_balance).max() <= 1e-12 * np.abs(run.energy).max()


# -- the work of a link that depends on t (item 3) -----------------------------------------------------------------

SHAKEN = {"m": 1.0, "l": 1.0, "J": 0.05, "g": 9.81, "A": 0.1, "B": 0.05, "w": 5.0, "b": 0.2, "c": 0.1}


def shaken_reference(t_eval) -> np.ndarray:
    """models/shaken_pendulum.yaml by its Lagrange equation in th alone, written here (pivot (A sin(w t),
    B sin(2 w t)), bob at pivot + l (sin th, -cos th)), with the shaker's power P = (m a - m g + b v) . v_pivot
    (Newton on the bob: the rod's force is m a - m g - (-b v), applied at the moving pivot) and the drag's -b |v|^2,
    integrated by DOP853 at rtol 1e-13. Rows: th, th', W_shaker, W_drag."""
    A, B, w, l, m, J, g, b, c = (SHAKEN[k] for k in ("A", "B", "w", "l", "m", "J", "g", "b", "c"))

    def rhs(t, s):
        th, om = s[0], s[1]
        xd, yd = A * w * np.cos(w * t), 2 * w * B * np.cos(2 * w * t)
        xdd, ydd = -A * w * w * np.sin(w * t), -4 * w * w * B * np.sin(2 * w * t)
        thdd = (-m * l * (xdd * np.cos(th) + ydd * np.sin(th)) - m * g * l * np.sin(th)
                - b * l * (xd * np.cos(th) + yd * np.sin(th) + l * om) - c * om) / (m * l * l + J)
        vx, vy = xd + l * np.cos(th) * om, yd + l * np.sin(th) * om
        ax = xdd + l * np.cos(th) * thdd - l * np.sin(th) * om ** 2
        ay = ydd + l * np.sin(th) * thdd + l * np.cos(th) * om ** 2
        return [om, thdd, (m * ax + b * vx) * xd + (m * ay + m * g + b * vy) * yd, -b * (vx * vx + vy * vy)]

    sol = solve_ivp(rhs, (0.0, t_eval[-1]), [0.5, 0.0, 0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-13,
                    t_eval=t_eval)
    assert sol.success
    return sol.y


def test_shaker_work_equals_an_independent_integral(compiled):
    """The pivot's prescribed motion does work (0.71 J over 5 s); andyc carries it as `prescribed_motion` (its power
    a_t . dv/dt + b_t after each solve), equal to the reference's integral to RK4's error, fourth order; the balance
    E - E0 - W closes to the same error, and the energy correction (now allowed: W is complete) holds it at
    round-off."""
    model = compiled("shaken_pendulum")
    assert model.work_names == ("drag", "hinge", "prescribed_motion") and model.untracked_work == ()
    errors = []
    for dt in (1e-3, 5e-4):
        run = andyc.simulate(model, 5.0, dt, "rk4")
        th, _, shaker, drag = shaken_reference(run.time)
        k = run.work_names.index("prescribed_motion")
        assert abs(shaker[-1]) > 0.5
        errors.append(np.abs(run.work[:, k] - shaker).max() / abs(shaker[-1]))
        assert np.abs(run.work[:, run.work_names.index("drag")] - drag).max() < 1e-9 * abs(drag[-1])
        assert np.abs(run.state[:, 0] - th).max() < 1e-9
        assert np.abs(run.energy_balance).max() < 1e-10
    assert errors[0] < 1e-9 and 8 < errors[0] / errors[1] < 32, errors     # measured 2.2e-11, 1.3e-12
    kept = andyc.simulate(model, 5.0, 1e-2, "projection", projection=Projection(energy_correction=True))
    free = andyc.simulate(model, 5.0, 1e-2, "projection")
    assert np.abs(kept.energy_balance).max() <= 1e-12 * np.abs(kept.energy).max()   # measured 3.3e-13 J of 10 J
    assert np.abs(free.energy_balance).max() > 1e-9                                  # measured 1.4e-7 J
