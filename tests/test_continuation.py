"""andyc cycle --continue (andyc.analysis.continuation): pseudo-arclength continuation of periodic orbits, issue 22
item 5. The rimless wheel's branch over the slope against its closed forms (docs/reference-cases.md §7); the compass
gait's first period doubling over the slope (its step-to-step map, models/compass_gait_step.yaml): a multiplier
-1 there, checked against central differences of compass_gait.yaml's one-step map (another formulation, no
continuation), and direct simulations on either side that settle onto period 1 and onto the period-2 branch
found by branch switching."""

import csv
import json
import math

import numpy as np
import pytest

import andyc
from andyc.analysis.continuation import Continuer
from andyc.analysis.cycles import find_cycle
from tests.support import MODELS
from tests.support.cli import invoke
from tests.support.gaits import gait_step

PD_MARGIN = 0.002          # the simulations' slopes past and before the period doubling, rad
ALPHA = 0.3               # the shipped wheel's half-angle between spokes


def wheel_speed(gamma):
    """omega*(gamma) of docs/reference-cases.md §7 (g = l = 1): omega*^2 = 4 sin(alpha) sin(gamma) cot^2(2 alpha)."""
    return math.sqrt(4 * math.sin(ALPHA) * math.sin(gamma)) / math.tan(2 * ALPHA)


def test_rimless_wheel_branch_is_the_closed_form(shipped_build, tmp_path):
    """Continued over the slope, every point is the closed-form orbit; the command writes JSON, CSV and a plot."""
    out = tmp_path / "wheel.json"
    result = invoke("cycle", MODELS / "rimless_wheel.yaml", "--section", "next_spoke", "--continue",
                    "gamma=0.04:0.1", "--step", 0.02, "-o", out, "--build-dir", shipped_build)
    assert result.exit_code == 0, result.output
    found = json.loads(out.read_text())
    (branch,) = found["branches"]                        # no period doubling: one branch
    assert branch["located"] == [] and branch["message"] == "reached the end of the range of gamma"
    points = branch["points"]
    gammas = [q["gamma"] for q in points]
    assert len(points) >= 4 and gammas[0] == 0.04 and max(gammas) > 0.075 and np.all(np.diff(gammas) > 0)
    c2 = math.cos(2 * ALPHA) ** 2
    for q in points:
        s = q["after"]
        assert abs(math.hypot(s["x_dot"], s["y_dot"]) - wheel_speed(q["gamma"])) < 1e-10
        (m,) = q["multipliers"]
        assert abs(m["real"] - c2) < 1e-10 and m["imag"] == 0.0 and q["stable"]
    with open(out.with_suffix(".csv"), newline="") as f:
        table = list(csv.DictReader(f))
    assert len(table) == len(points)
    assert [float(r["gamma"]) for r in table] == pytest.approx(gammas, abs=0, rel=1e-15)
    assert out.with_suffix(".png").stat().st_size > 10_000
    assert "period-1 branch: " in result.stdout and "wrote " + str(out.with_suffix(".png")) in result.stdout


KICKED_BALL = """\
name: kicked_ball
description: A ball thrown up from the floor; each landing sends it up at mu + v^2 (a fold of its orbits at mu = 1/4).
parameters: {g: 1.0, mu: 0.1}
coordinates:
  h: {initial: 0.5}
gravity: [0, -g, 0]
frames:
  - {name: ball, parent: world, translation: [0, h, 0]}
bodies:
  - {name: mass, frame: ball, mass: 1.0}
hybrid:
  flows:
    - {name: air}
  jumps:
    - {name: land, from: air, to: air, guard: h, direction: falling, reset: {h_dot: mu + h_dot**2}}
"""


def test_fold_of_a_kicked_ball(compiled, build_dir, tmp_path_factory):
    """A ball that lands at speed u leaves at mu + u^2 and lands again at that speed (g = 1): its orbits are the
    roots of u^2 - u + mu = 0, u = (1 -+ sqrt(1 - 4 mu))/2, with the period 2u and the multiplier of the map
    v- -> -(mu + v-^2), 2u. The two meet at the fold mu = 1/4, u = 1/2 (multiplier 1). Continued from mu = 0.1
    towards 0.3, the branch turns there and comes back on the other root; rk4 is exact on a parabola."""
    path = tmp_path_factory.mktemp("fold") / "kicked_ball.yaml"
    path.write_text(KICKED_BALL)
    model = compiled(path)
    andyc.build_derivatives(path, build_dir)
    result = Continuer(model, "land", "mu", ds=0.05).run(0.1, 0.3)
    (branch,) = result.branches
    (fold,) = branch.specials
    assert fold.kind == "fold" and abs(fold.point.parameter - 0.25) < 1e-10
    assert abs(fold.point.period - 1.0) < 1e-8 and abs(fold.point.multipliers[0] - 1.0) < 1e-8
    roots = {"upper": 0, "lower": 0}
    for q in branch.points:
        u = q.period / 2
        assert abs(u * u - u + q.parameter) < 1e-11 and abs(q.multipliers[0] - 2 * u) < 1e-10
        assert q.stable == (u < 0.5)
        roots["upper" if u > 0.5 else "lower"] += 1
    assert roots["upper"] >= 2 and roots["lower"] >= 2          # both sides of the fold
    assert branch.points[-1].parameter < fold.point.parameter - 0.05    # and back


def test_continuation_usage_errors(shipped_build, tmp_path):
    model = MODELS / "rimless_wheel.yaml"
    for args, message in ((["--continue", "gamma=0.04"], "write NAME=A:B"),
                          (["--continue", "gamma=0.04:0.04"], "A and B must be finite and differ"),
                          (["--continue", "slope=0.04:0.1"], "no parameter named slope"),
                          (["--continue", "gamma=0.04:0.1", "--at", "gamma=0.05"], "gamma is continued")):
        result = invoke("cycle", model, "--section", "next_spoke", *args, "-o", tmp_path / "x.json",
                        "--build-dir", shipped_build)
        assert result.exit_code == 2 and message in result.output, result.output


@pytest.fixture(scope="module")
def doubling(compiled, shipped_build):
    """The compass gait continued over the slope from 4.1 to 4.7 degrees, switching onto period 2."""
    andyc.build_derivatives(MODELS / "compass_gait_step.yaml", shipped_build)
    model = compiled("compass_gait_step")
    return model, Continuer(model, "strike", "slope", ds=0.02).run(0.072, 0.081)


def test_compass_gait_period_doubling(doubling, compiled):
    """(a) the first period doubling: located to 1e-10 in the slope, a multiplier -1 there to 1e-8; the
    eigenvalue of central differences of compass_gait.yaml's one-step map (legs swapped) is -1 there too."""
    model, result = doubling
    main, child = result.branches
    (pd,) = main.specials
    assert pd.kind == "period doubling" and pd.bracket <= 1e-10
    slope = pd.point.parameter
    assert 0.0745 < slope < 0.0785                      # (found: 0.07663563158 rad = 4.3909 deg)
    mu = pd.point.multipliers
    assert np.min(np.abs(mu + 1)) < 1e-8
    before = [q for q in main.points if q.parameter < slope]
    after = [q for q in main.points if q.parameter > slope]
    assert before and after and all(q.stable for q in before) and not any(q.stable for q in after)
    # independently: the other model (two flows), its one-step map by central differences at the fixed point
    other = compiled("compass_gait")
    names = dict(zip(result.state_names, pd.point.after))
    z = np.array([names["th1"], -names["th1_dot"], -names["th2_dot"]])
    step = lambda z: gait_step(other, z, {"slope": slope})      # noqa: E731
    assert np.max(np.abs(step(z) - z)) < 1e-9
    J = np.empty((3, 3))
    for k in range(3):
        e = np.zeros(3)
        e[k] = 1e-6
        J[:, k] = (step(z + e) - step(z - e)) / 2e-6
    eig = np.linalg.eigvals(J)
    assert np.min(np.abs(eig + 1)) < 1e-6               # d(mu)/d(slope) ~ 60: the slope to ~2e-8


def strike_times(model, slope, steps, start=None):
    """The times between heel strikes of a plain rk4 run of `steps` strikes from the model's initial state or from
    `start`, a state (x, d) just after a strike."""
    x0, d0 = (None, None) if start is None else (start[:model.nx], start[model.nx:])
    run = andyc.simulate(model, 0.8 * steps, dt=1e-3, method="rk4", parameters={"slope": slope}, x0=x0, d0=d0,
                         events=andyc.Events(tol=1e-15), progress=False)
    assert run.finished and run.events["jump"].size > 0.9 * steps
    return np.diff(run.events["time"])


def test_compass_gait_settles_onto_the_branches(doubling):
    """(b) direct simulations: just before the doubling the gait settles onto period 1 (the continued branch's step
    time), just past it onto period 2 (from the period-1 gait, unstable there): alternating step times, distinct,
    repeating, the period-2 branch's."""
    model, result = doubling
    main, child = result.branches
    slope = main.specials[0].point.parameter
    assert child.period_count == 2 and child.points and child.message == "reached the end of the range of slope"
    q1 = max((q for q in main.points if q.parameter < slope - PD_MARGIN), key=lambda q: q.parameter)
    times = strike_times(model, q1.parameter, 400)
    assert np.max(np.abs(times[-20:] - q1.period)) < 1e-8
    q2 = min((q for q in child.points if q.parameter > slope + PD_MARGIN), key=lambda q: q.parameter)
    assert np.all(np.abs(q2.step_times - q2.period / 2) > 5e-3)       # two distinct steps
    # from the period-1 gait just past the doubling (unstable there), at the period-2 point's slope
    unstable = min((q for q in main.points if q.parameter > slope), key=lambda q: q.parameter)
    times = strike_times(model, q2.parameter, 200, unstable.after)
    tail = times[-20:]
    assert np.max(np.abs(tail[2:] - tail[:-2])) < 1e-9                  # repeats every two steps
    assert np.min(np.abs(tail[1:] - tail[:-1])) > 5e-3                  # and alternates
    assert np.sort(tail[-2:]) == pytest.approx(np.sort(q2.step_times), abs=1e-8)


# ---- the simplest walking model: the published period doubling -------------------------------------------------

SIMPLEST = MODELS / "simplest_walker_step.yaml"
BETAS = (1e-6, 2e-6)            # foot / hip mass: the paper's beta = 0 by Richardson's extrapolation, 2 f(b) - f(2b)
# Garcia's simulation code for the paper ("All code by Mariano Garcia ... used to produce results for the paper";
# its header comment: "initial conditions gam=0.009 long step to 1e-10"): theta, theta' just after a heel strike
GARCIA_LONG_GAIT = (0.20031090049483, -0.19983247291764)
PUBLISHED_PD = 0.015            # the abstract: the period-one gait "is stable when 0 < gamma < 0.015 rad"


def extrapolated(values):
    """f(0) from f(beta) and f(2 beta) (the map depends smoothly on beta): 2 f(b) - f(2b), error O(b^2)."""
    a, b = (np.asarray(v) for v in values)
    return 2 * a - b


def garcia_stride(z, gamma):
    """An independent stride function of the simplest walker (beta = 0), Garcia et al.'s equations of motion and
    heel-strike rule:
    theta'' = sin(theta - gamma), phi'' = sin(theta - gamma) + sin(phi) (theta'^2 - cos(theta - gamma)); heel strike
    at phi = 2 theta past mid-stance (scuffing ignored): theta+ = -theta, theta'+ = cos(2 theta) theta',
    phi'+ = cos(2 theta) (1 - cos 2 theta) theta'. SciPy's DOP853 at 1e-13. (theta, theta') just after a strike ->
    the same after the next, and the step's time."""
    from scipy.integrate import solve_ivp

    th, thd = z
    y0 = [th, 2 * th, thd, (1 - math.cos(2 * th)) * thd]

    def rates(t, y):
        s = math.sin(y[0] - gamma)
        return [y[2], y[3], s, s + math.sin(y[1]) * (y[2] ** 2 - math.cos(y[0] - gamma))]

    def mid(t, y):
        return y[0]

    def strike(t, y):
        return y[1] - 2 * y[0]
    mid.terminal = strike.terminal = True
    mid.direction = -1
    first = solve_ivp(rates, (0, 10), y0, method="DOP853", rtol=1e-13, atol=1e-13, events=mid)
    second = solve_ivp(rates, (first.t[-1], first.t[-1] + 10), first.y[:, -1], method="DOP853", rtol=1e-13,
                       atol=1e-13, events=strike)
    th, _, thd, _ = second.y_events[0][0]
    return np.array([-th, math.cos(2 * th) * thd]), second.t_events[0][0]


def garcia_fixed_point(gamma, z=GARCIA_LONG_GAIT, h=1e-6):
    """Newton on garcia_stride with central differences: (z*, its eigenvalues, the step time)."""
    z = np.array(z, float)
    for _ in range(30):
        J = np.column_stack([(garcia_stride(z + h * e, gamma)[0] - garcia_stride(z - h * e, gamma)[0]) / (2 * h)
                             for e in np.eye(2)])
        r = garcia_stride(z, gamma)[0] - z
        if np.max(np.abs(r)) < 1e-13:
            break
        z = z - np.linalg.solve(J - np.eye(2), r)
    return z, np.linalg.eigvals(J), garcia_stride(z, gamma)[1]


@pytest.fixture(scope="module")
def simplest(compiled, shipped_build):
    andyc.build_derivatives(SIMPLEST, shipped_build)
    return compiled(SIMPLEST)


def test_simplest_walker_long_gait_is_garcias(simplest):
    """The fixed point at gamma = 0.009 (the paper's example slope), extrapolated to beta = 0, against the initial
    conditions in Garcia's simulation code for Garcia, Chatterjee, Ruina & Coleman, "The simplest walking model:
    stability, complexity, and scaling", J. Biomech. Eng. 120(2):281-288 (1998), given there "to 1e-10"; the step
    time and the multipliers against garcia_stride (SciPy, the paper's equations, central differences). (The
    eigenvalues in the code's comment, -0.19121 +/- 0.55633i, are not compared: the paper's equations integrated
    here give -0.190100 +/- 0.557599i, as andyc does, and agree with the fixed point to 1e-10.)"""
    found = []
    for beta in BETAS:
        cycle = find_cycle(simplest, "strike", parameters={"beta": beta}, tol=1e-9, t_max=10)
        assert cycle.converged, cycle.message
        s = dict(zip(cycle.state_names, cycle.state))
        mu = cycle.multipliers
        assert abs(mu[2]) < 1e-6         # the swing leg's speed, which the strike takes away as beta -> 0
        found.append((s["th1"], s["th1_dot"], cycle.period, mu[0], mu[1]))
    th, thd, period, mu1, mu2 = extrapolated(found)
    assert abs(th - GARCIA_LONG_GAIT[0]) < 1e-9 and abs(thd - GARCIA_LONG_GAIT[1]) < 1e-9
    z, eig, step = garcia_fixed_point(0.009)
    assert np.max(np.abs(z - [th, thd])) < 1e-9 and abs(period - step) < 1e-8
    assert np.max(np.abs(np.sort_complex(eig) - np.sort_complex([mu1, mu2]))) < 1e-6


def test_simplest_walker_period_doubling_is_the_published_one(simplest):
    """The period-one (long) gait continued over the slope from 0.009 loses stability by a period doubling at
    gamma = 0.01508844 (extrapolated to beta = 0), the published value: Garcia, Chatterjee, Ruina & Coleman, J.
    Biomech. Eng. 120(2):281-288 (1998), abstract: "The model exhibits two period-one gait cycles, one of which is
    stable when 0 < gamma < 0.015 rad" (two digits). Independently, garcia_stride's eigenvalue at that slope is -1."""
    located = []
    for beta in BETAS:
        result = Continuer(simplest, "strike", "slope", {"beta": beta}, tol=1e-9, t_max=10, ds=0.01).run(
            0.009, 0.02, branch_switch=False)
        pd = [sp for sp in result.branches[0].specials if sp.kind == "period doubling"]
        assert pd and pd[0].located and pd[0].bracket <= 1e-10
        assert np.min(np.abs(pd[0].point.multipliers + 1)) < 1e-7
        located.append(pd[0].point.parameter)
    gamma = float(extrapolated(located))
    assert round(gamma, 3) == PUBLISHED_PD                   # (found: 0.0150884379)
    z = np.array(GARCIA_LONG_GAIT)
    for g in np.linspace(0.009, gamma, 7)[1:]:               # Newton from the last slope's fixed point
        z, eig, _ = garcia_fixed_point(g, z)
    assert np.min(np.abs(eig + 1)) < 1e-6                    # d(mu)/d(gamma) ~ 100: gamma to ~1e-8
