"""Hybrid models against closed forms and published numbers (docs/reference-cases.md §6-8).

The step maps of the walkers are computed from simulated steps: a run from
a state just after an impact, stopped right after the next one (stop_after).
The rimless wheel's fixed point comes from Newton's method on that map, its
eigenvalue from central differences; the compass gait's, with exact
Jacobians, are andyc cycle's (tests/test_cycles.py).
"""

import math

import numpy as np
import pytest

import andyc

G = 9.81


# -- bouncing ball (§6) -----------------------------------------------------------

H0, E = 1.0, 0.8
T1 = math.sqrt(2 * H0 / G)
T_INF = T1 * (1 + 2 * E / (1 - E))


def impact_times(n):
    """t_1 = sqrt(2 h0 / g), t_(k+1) = t_k + 2 e^k t_1."""
    return T1 + np.concatenate([[0.0], np.cumsum(2 * E ** np.arange(1, n) * T1)])


@pytest.mark.parametrize("method", ["rk4", "projection", "DOP853"])
def test_bouncing_ball_impacts_and_zeno(compiled, method):
    model = compiled("bouncing_ball")
    andyc.simulate(model, 0.5, dt=1e-3, method=method, progress=False)      # compile outside the timing
    run = andyc.simulate(model, 10.0, dt=1e-3, method=method, rtol=1e-12, atol=1e-12, progress=False)
    times = run.events["time"]
    # Free fall is a parabola: RK4 integrates it exactly, so the impact times are exact to the event tolerance.
    assert np.max(np.abs(times[:20] - impact_times(20))) < 1e-9
    assert set(run.event_names()) == {"bounce"}
    assert run.status.startswith("stopped: Zeno behaviour")
    stated = float(run.status.split("accumulate at t = ")[1].split(" s")[0])
    assert abs(stated - T_INF) < 1e-6                      # the accumulation point the message names
    assert 0 < T_INF - run.time[-1] < 1e-6                 # where the run stopped
    # It stops instead of grinding towards t_inf: few steps (counted, not timed: the machine may be loaded).
    assert run.stats["steps"] < 5000
    assert np.all(run.column("y") > -1e-12)                # never through the ground
    # each impact keeps e of the speed
    before, after = run.events["state_before"][:, 1], run.events["state_after"][:, 1]
    assert np.allclose(after, -E * before, rtol=1e-12, atol=0)


# -- rimless wheel (§7) -------------------------------------------------------------

ALPHA, GAMMA = 0.3, 0.04


def wheel_step(model, w, method):
    """Angular speed just after the next impact, from w just after one (the hub alpha behind its foot)."""
    x0 = np.array([-math.sin(ALPHA), math.cos(ALPHA), w * math.cos(ALPHA), w * math.sin(ALPHA)])
    run = andyc.simulate(model, 50.0, dt=1e-3, method=method, x0=x0, d0=np.zeros(1),
                         events=andyc.Events(stop_after={"next_spoke": 1}), progress=False)
    assert run.status == "finished" and len(run.events["time"]) == 1
    x = run.events["state_after"][0]
    fx = run.events["discrete_after"][0][0]
    assert fx == pytest.approx(2 * math.sin(ALPHA), rel=1e-14)
    assert x[0] - fx == pytest.approx(-math.sin(ALPHA), abs=1e-9)     # alpha behind the new foot
    return math.hypot(x[2], x[3])


@pytest.mark.parametrize("method", ["projection", "rk4"])
def test_rimless_wheel_fixed_point_and_eigenvalue(compiled, method):
    model = compiled("rimless_wheel")
    w_star = math.sqrt(4 * G / G * math.sin(ALPHA) * math.sin(GAMMA) / math.tan(2 * ALPHA) ** 2)
    assert w_star == pytest.approx(0.317799, abs=5e-7)          # docs/reference-cases.md §7 (g = l = 1)
    w, h = 0.5, 1e-5
    for _ in range(8):
        f = wheel_step(model, w, method) - w
        slope = (wheel_step(model, w + h, method) - wheel_step(model, w - h, method)) / (2 * h)
        w -= f / (slope - 1)
        if abs(f) < 1e-13:
            break
    assert abs(w - w_star) < 1e-6
    assert abs(slope - math.cos(2 * ALPHA) ** 2) < 1e-6
    assert math.cos(2 * ALPHA) ** 2 == pytest.approx(0.681179, abs=5e-7)


# -- compass gait (§8) --------------------------------------------------------------

STEP_TIME = 0.7343464


# The period-1 fixed point, step time and eigenvalues: tests/test_cycles.py (andyc cycle, exact Jacobians, 1e-8).


def test_compass_gait_walks_from_the_shipped_state(compiled):
    """The model's own initial state is the period-1 gait: every step takes the same time."""
    model = compiled("compass_gait")
    run = andyc.simulate(model, 8.0, dt=1e-3, method="projection", progress=False)
    assert run.finished
    assert len(run.events["time"]) == 10
    assert np.allclose(np.diff(run.events["time"]), STEP_TIME, atol=1e-6)
    assert run.event_names()[:2] == ["strike2", "strike1"]
    assert np.max(np.abs(run.residual_position[~np.isnan(run.residual_position)])) < 1e-10
