"""andyc cycle (andyc.analysis.cycles): Newton's method on a jump's Poincaré map with exact Jacobians, issue 22
items 2, 3 and 4. The rimless wheel against its closed forms (docs/reference-cases.md §7) to 1e-12; the compass gait
against §8 and against central differences of its one-step map (the legs swapped, as the step-to-step map of
§8 is written): the two-step orbit's multipliers are the squares of that map's eigenvalues. The passive walker
with knees (item 4): its stride's fixed point and the rate at which runs from a perturbed one approach it."""

import json
import math

import numpy as np
import pytest
from scipy.integrate import quad

import andyc
from andyc.analysis.cycles import find_cycle
from tests.support import MODELS
from tests.support.gaits import gait_step
from tests.support.cli import invoke

ALPHA, GAMMA = 0.3, 0.04                                  # the shipped wheel's, g = l = 1


def wheel_closed_form():
    """(omega*, multiplier, step time). Between impacts the hub is an inverted pendulum about the foot, at angle
    theta from the slope's normal: omega^2 = omega+^2 + 2 (cos(gamma - alpha) - cos(theta + gamma)) (energy,
    theta from -alpha to alpha); the plastic impact keeps omega- = cos(2 alpha) omega-: omega+ = c omega-, with
    omega-^2 = omega+^2 + 4 sin(alpha) sin(gamma). Fixed point: omega*^2 (1 - c^2) = 4 c^2 sin alpha sin gamma,
    i.e. omega*^2 = 4 sin(alpha) sin(gamma) cot^2(2 alpha); the map omega+ -> omega+' = sqrt(c^2 (omega+^2 + 4 ..))
    has the derivative c^2 at the fixed point. The step time is the quadrature of dtheta / omega."""
    c = math.cos(2 * ALPHA)
    w = math.sqrt(4 * math.sin(ALPHA) * math.sin(GAMMA)) / math.tan(2 * ALPHA)
    time = quad(lambda th: 1 / math.sqrt(w * w + 2 * (math.cos(GAMMA - ALPHA) - math.cos(th + GAMMA))),
                -ALPHA, ALPHA, epsabs=1e-13, epsrel=1e-13)[0]
    return w, c * c, time


def test_rimless_wheel_cycle_command(shipped_build, tmp_path):
    w, multiplier, step = wheel_closed_form()
    assert (w, multiplier) == (pytest.approx(0.317799, abs=5e-7), pytest.approx(0.681179, abs=5e-7))   # §7
    out = tmp_path / "wheel.json"
    result = invoke("cycle", MODELS / "rimless_wheel.yaml", "--section", "next_spoke", "-o", out,
                    "--build-dir", shipped_build)
    assert result.exit_code == 0, result.output
    assert "Floquet multipliers (1 on the section; flow direction and 1 symmetry left out)" in result.stdout
    found = json.loads(out.read_text())
    assert found["converged"] and found["residual_history"][-1] <= 1e-11
    history = found["residual_history"]
    assert history[-2] < 1e-6 and history[-1] < 1e3 * history[-2] ** 2      # quadratic at the end
    s, fx = found["state"], found["discrete"]["fx"]
    assert abs(math.hypot(s["x_dot"], s["y_dot"]) - w) < 1e-12
    assert abs(s["x"] - fx + math.sin(ALPHA)) < 1e-12 and abs(s["y"] - math.cos(ALPHA)) < 1e-12  # alpha behind
    (m,) = found["multipliers"]
    assert abs(m["real"] - multiplier) < 1e-12 and m["imag"] == 0.0
    assert abs(found["period"] - step) < 1e-9                # RK4 at dt = 1e-3 and the quadrature
    assert found["symmetries"] and found["section_dimension"] == 1


def test_cycle_failures_say_why(shipped_build, tmp_path):
    """A section never reached, and Newton stopped before it converges: exit 1, with the residual history."""
    model = MODELS / "rimless_wheel.yaml"
    never = invoke("cycle", model, "--section", "next_spoke", "--t-max", 0.5, "-o", tmp_path / "a.json",
                   "--build-dir", shipped_build)
    assert never.exit_code == 1
    assert "did not reach jump 'next_spoke' within t_max = 0.5 s" in never.stdout
    failed = json.loads((tmp_path / "a.json").read_text())       # strict JSON: no NaN for the unknown period
    assert failed["converged"] is False and failed["period"] is None and failed["residual_history"] == []
    short = invoke("cycle", model, "--section", "next_spoke", "--dt", 2e-3, "--max-iterations", 1,
                   "-o", tmp_path / "b.json", "--build-dir", shipped_build)
    assert short.exit_code == 1
    history = json.loads((tmp_path / "b.json").read_text())["residual_history"]
    assert len(history) == 2 and history[1] < history[0]
    assert f"no convergence in 1 Newton steps: the residual went {history[0]:.3g}, {history[1]:.3g}" in short.stdout
    # (the residuals themselves, 0.0455 and 0.00544, are andyc's own earlier output: a regression pin, not asserted)
    usage = invoke("cycle", model, "--section", "nope", "-o", tmp_path / "c.json", "--build-dir", shipped_build)
    assert usage.exit_code == 2 and "no jump 'nope'; jumps: next_spoke" in usage.output
    unknown = invoke("cycle", model, "--section", "next_spoke", "--at", "slope=0.1", "-o", tmp_path / "d.json",
                     "--build-dir", shipped_build)
    assert unknown.exit_code == 2 and "no parameter named slope; parameters: m, g, l, alpha, gamma, w0" in unknown.output


# -- compass gait (§8) --------------------------------------------------------------

PHI, W_STANCE, W_SWING, STEP_TIME = 0.2710286805, 1.0923835899, 0.3773739489, 0.7343464
EIGENVALUES = np.array([-0.19973 + 0.54448j, -0.19973 - 0.54448j, 0.13157])


def test_compass_gait_cycle(compiled, shipped_build):
    model = compiled("compass_gait")
    andyc.build_derivatives(MODELS / "compass_gait.yaml", shipped_build)
    cycle = find_cycle(model, "strike2")
    assert cycle.converged, cycle.message
    x, fx = cycle.state, cycle.discrete[0]
    names = dict(zip(cycle.state_names, x))
    # just after strike2 leg 2 stands at fx, phi ahead of the hip's normal; leg 1 phi behind
    got = np.array([names["th2"], -names["th1"], -names["th2_dot"], -names["th1_dot"]])
    assert np.max(np.abs(got - [PHI, PHI, W_STANCE, W_SWING])) < 1e-8                       # §8, to 1e-8
    th2 = names["th2"]
    assert abs(names["x"] - fx + math.sin(th2)) < 1e-12 and abs(names["y"] - math.cos(th2)) < 1e-12
    # strike2 comes back after two steps (strike1 between): the step time is half the period
    assert abs(cycle.period / 2 - STEP_TIME) < 5e-8                                          # §8 gives 7 digits
    # the two-step map's multipliers are the squares of the step-to-step map's eigenvalues (§8: 5 digits)
    mult = np.sort_complex(cycle.multipliers)
    assert len(mult) == 3 and cycle.basis.shape[1] == 3
    assert np.max(np.abs(mult - np.sort_complex(EIGENVALUES ** 2))) < 2e-5
    # ... and, to 5e-8, those of central differences of the one-step map with the legs swapped, at the fixed point
    # (differences of step 1e-6 of maps through located events: their roundings, divided by the step, are of 1e-8;
    # measured 1.4e-8 on an AVX-512 machine, below 1e-8 on earlier ones: libmvec's vector sines round by machine)
    z = got[[0, 2, 3]]
    assert np.max(np.abs(gait_step(model, z) - z)) < 1e-10
    J = np.empty((3, 3))
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1e-6
        J[:, k] = (gait_step(model, z + e) - gait_step(model, z - e)) / 2e-6
    step_eigenvalues = np.linalg.eigvals(J)
    assert np.max(np.abs(np.sort_complex(step_eigenvalues ** 2) - mult)) < 5e-8
    assert np.max(np.abs(np.sort_complex(step_eigenvalues) - np.sort_complex(EIGENVALUES))) < 1e-5


def test_rimless_wheel_period_two(compiled, shipped_build):
    """--period 2: the same orbit, the section passed twice: the period doubles, the multiplier squares."""
    model = compiled("rimless_wheel")
    andyc.build_derivatives(MODELS / "rimless_wheel.yaml", shipped_build)
    w, multiplier, step = wheel_closed_form()
    cycle = find_cycle(model, "next_spoke", period=2)
    assert cycle.converged, cycle.message
    assert abs(math.hypot(cycle.state[2], cycle.state[3]) - w) < 1e-12
    assert abs(cycle.multipliers[0] - multiplier ** 2) < 1e-12
    assert abs(cycle.period - 2 * step) < 2e-9


# -- passive walker with knees (item 4) ----------------------------------------------

def test_passive_walker_cycle_and_convergence_rate(compiled, shipped_build):
    """The walker's stride (section: the outer heel strike, six jumps per period): Newton converges, the fixed
    point comes back after one stride of the plain compiled loop, and 50 steps (25 strides) from a perturbed fixed
    point approach it at the rate of the dominant multiplier: the ratio of successive distances at the section
    (between successive strides, below) tends to |lambda_max| (real here: the step-to-step map's flip -0.959, squared), once the second multiplier's
    share, (|lambda_2| / |lambda_max|)^n, has died out."""
    model = compiled("passive_walker")
    andyc.build_derivatives(MODELS / "passive_walker.yaml", shipped_build)
    cycle = find_cycle(model, "strike_outer_foot")
    assert cycle.converged, cycle.message
    mult = cycle.multipliers
    lead = abs(mult[0])
    assert mult[0].imag == 0.0 and 0.5 < lead < 1.0 and abs(mult[1]) < 0.5 * lead      # stable, one slow mode
    fx = model.discrete_names.index("fx")

    def strides(x0, d0, n):
        """(x, d) just after each of the first n outer heel strikes from (x0, d0) just after one, relative to the
        stance foot (qx - fx; fx itself left out: the walker's shift downhill is a symmetry)."""
        run = andyc.simulate(model, 2.0 * n, 1e-3, "rk4", x0=x0, d0=d0, flow0="IOpenOFix", init=andyc.Init("as-is"),
                             events=andyc.Events(tol=1e-14, stop_after={"strike_outer_foot": n}), progress=False)
        assert run.finished
        at = np.flatnonzero(np.array(run.event_names()) == "strike_outer_foot")
        assert len(at) == n
        x, d = run.events["state_after"][at].copy(), run.events["discrete_after"][at]
        x[:, 0] -= d[:, fx]
        return np.hstack([x, np.delete(d, fx, axis=1)])

    def relative(x, d):
        z = np.concatenate([x, np.delete(d, fx)])
        z[0] -= d[fx]
        return z

    star = relative(cycle.state, cycle.discrete)
    assert np.max(np.abs(strides(cycle.state, cycle.discrete, 1)[0] - star)) < 1e-8     # a fixed point (3e-9)
    x0 = cycle.state.copy()
    names = list(model.state_names)
    x0[names.index("qi1_dot")] += 1e-4        # the free swing leg: the start stays on the stance constraints
    x0[names.index("qi2_dot")] -= 2e-4
    z = strides(x0, cycle.discrete, 25)
    distance = np.linalg.norm(z - star, axis=1)
    assert distance[-1] < 0.5 * distance[0]
    # the rate, from the distances between successive strides: the orbit the runs approach sits ~3e-9 off the
    # reported point (the rk4 method's drift off the constraints over a stride, which Newton's section
    # coordinates do not see), which would bend distances to it by that much; successive steps cancel it
    step = np.linalg.norm(np.diff(z, axis=0), axis=1)
    ratio = step[1:] / step[:-1]
    assert np.max(np.abs(ratio[10:] / lead - 1.0)) < 1e-3
