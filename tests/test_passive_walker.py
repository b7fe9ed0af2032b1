"""The passive walker with knees (ANDY §3.2; docs/reference-cases.md §2), models/passive_walker.yaml.

It walks from the reference's initial state, its heel-strike states converge
to the reference's gait, and every knee strike and heel strike loses the
kinetic energy of the plastic impact map (ANDY eq. 19, Carnot's theorem).
"""

import math

import numpy as np
import pytest

import andyc

L1, L2 = 0.5, 0.5
SQRT_G = math.sqrt(9.81)
# the active constraint rows of each flow (docs/reference-cases.md §2), columns in the model's order
ROWS = ["iKnee", "oKnee", "iFootX", "iFootY", "oFootX", "oFootY"]
ACTIVE = {"IFixOOpen": {"iKnee", "iFootX", "iFootY"},
          "IFixOLock": {"oKnee", "iKnee", "iFootX", "iFootY"},
          "IBendOLock": {"oKnee", "iFootX", "iFootY"},
          "IOpenOFix": {"oKnee", "oFootX", "oFootY"},
          "ILockOFix": {"iKnee", "oKnee", "oFootX", "oFootY"},
          "ILockOBend": {"iKnee", "oFootX", "oFootY"}}
STRIKES = ("strike_outer_foot", "strike_inner_foot")
CYCLE = ["lock_outer_knee", "bend_inner_knee", "strike_outer_foot",
         "lock_inner_knee", "bend_outer_knee", "strike_inner_foot"]


@pytest.fixture(scope="module")
def walker(compiled):
    model = compiled("passive_walker")
    andyc.simulate(model, 0.2, dt=1e-3, method="projection", progress=False)    # compile outside the runs
    return model


@pytest.fixture(scope="module")
def twenty_steps(walker):
    """From the shipped state (flow 1 just after an inner heel strike) to the 20th heel strike."""
    return andyc.simulate(walker, 20.0, dt=1e-3, method="projection", frames="all",
                          events=andyc.Events(stop_after={"strike_inner_foot": 10}), progress=False)


def strike_states(run):
    """Post-strike states relative to the stance foot (qx - fx), legs renamed so that the
    leg that just struck comes first: (qx - fx, qy, stance thigh, stance shank, swing
    thigh, swing shank) and their speeds, one row per heel strike."""
    names = run.event_names()
    rows = []
    for k, name in enumerate(names):
        if name not in STRIKES:
            continue
        x = run.events["state_after"][k].copy()
        x[0] -= run.events["discrete_after"][k][0]
        if name == "strike_outer_foot":
            x = x[[0, 1, 4, 5, 2, 3, 6, 7, 10, 11, 8, 9]]
        rows.append(x)
    return np.array(rows)


def test_walks_twenty_steps_without_falling(twenty_steps, walker):
    run = twenty_steps
    assert run.finished
    names = run.event_names()
    assert names == CYCLE * 10                          # the six jumps in the order of the automaton
    fx_strike = run.events["discrete_after"][[k for k, n in enumerate(names) if n in STRIKES], 0]
    assert len(fx_strike) == 20
    assert np.all(np.diff(np.r_[0.0, fx_strike]) > 0.25)     # every step lands 0.27 m ahead of the last
    assert run.column("qy").min() > 0.85                 # the hip stays up (0.9085 at a heel strike)

    # constraint residuals: the active rows (NaN marks the others) held to round-off
    flows = [walker.flow_names[f] for f in run.flow]
    expected_nan = np.array([[r not in ACTIVE[f] for r in ROWS] for f in flows])
    assert np.array_equal(np.isnan(run.residual_position), expected_nan)
    assert np.nanmax(np.abs(run.residual_position)) < 1e-12
    assert np.nanmax(np.abs(run.residual_velocity)) < 1e-12


def test_swing_foot_stays_above_the_slope_from_midstance_to_the_strike(twenty_steps):
    """The swing foot is above the slope from the moment it passes the stance foot until it
    strikes (the stance knee's bend lets it come down ahead). Before that it is not: the
    plastic heel strike fixes only the new stance foot and leaves the trailing foot with a
    downward speed (0.054 m/s in the cycle; the reference's own initial state has 0.058 m/s),
    and its knee locks straight while it is still behind the stance foot, so it goes through
    the slope by up to 2.04 cm until it passes the stance foot (the first 0.13 s of each
    step). The reference model has no guard there either; we bound that dip."""
    run = twenty_steps
    inner_stance = np.isin(run.flow, [0, 1, 2])
    ifoot, ofoot = run.frames["ifoot"], run.frames["ofoot"]
    swing = np.where(inner_stance[:, None], ofoot, ifoot)
    stance = np.where(inner_stance[:, None], ifoot, ofoot)
    fx = run.column("fx")
    assert np.max(np.abs(stance[:, :2] - np.c_[fx, np.zeros_like(fx)])) < 1e-12     # locked where it landed
    ahead = swing[:, 0] >= fx
    assert np.min(swing[ahead, 1]) > -1e-6
    assert np.min(swing[~ahead, 1]) < 0.0                       # the dip behind the stance foot exists (see pin)


@pytest.mark.pin
def test_pin_the_trailing_foots_dip(twenty_steps):
    """Regression pin, not a validation: the depth of the trailing foot's dip through the slope (above) is andyc's
    own earlier output, -0.0204 m, which no published source gives; a change beyond the band needs a reason."""
    run = twenty_steps
    inner_stance = np.isin(run.flow, [0, 1, 2])
    swing = np.where(inner_stance[:, None], run.frames["ofoot"], run.frames["ifoot"])
    behind = swing[:, 0] < run.column("fx")
    assert -0.025 < np.min(swing[behind, 1]) < -0.015


def test_heel_strike_states_converge_to_a_period_one_gait(walker):
    """The gait is period 1 (one step with the legs' roles swapped repeats; every step the
    same), but approached slowly through a flip: the step-to-step map's dominant eigenvalue
    is about -0.959, so for the first twenty steps the strikes alternate and look like
    period 2 (inner strikes leave qx - fx = -0.4163, outer ones -0.4179). Measured
    (dt 1e-3 and 5e-4 agree to 3e-8): the largest difference between successive swapped
    strike states is 0.023 at strike 6, 0.0149 at strike 20, 5.8e-4 at 101, 9.0e-6 at
    201, 1.5e-6 at 244; between every second strike 5e-4 at strike 20. The cycle's strike
    state is close to the reference's initial state (which is rounded to four digits):
    angles (0.43021, 0.43021, 0.56016, -0.24315) against (0.4309, 0.4309, 0.5608, -0.2439),
    within 8e-4 rad; speeds in sqrt(g) units (-0.1377, -0.0087, 0.6000) against (-0.1391,
    -0.0139, 0.6033), within 5.2e-3. Step time 0.6105 s, step length 0.272 m."""
    run = andyc.simulate(walker, 150.0, dt=1e-3, method="projection", progress=False)
    assert run.finished
    S = strike_states(run)
    assert len(S) >= 240
    d1 = np.max(np.abs(np.diff(S, axis=0)), axis=1)      # successive strikes, legs swapped
    assert d1[:20].max() > 0.01                           # far from the cycle at first
    assert d1[-1] < 3e-6                                  # period 1 at the end
    rate = (d1[200] / d1[100]) ** (1 / 100)
    assert 0.95 < rate < 0.965                            # slow geometric convergence
    dev = S[100:110, 0] - S[-1, 0]
    assert np.all(np.sign(dev[1:]) == -np.sign(dev[:-1]))   # ... through a flip (negative eigenvalue)
    # the cycle against the reference's initial state
    z = S[-1]
    assert np.max(np.abs(z[2:6] - [0.4309, 0.4309, 0.5608, -0.2439])) < 1e-3
    assert np.max(np.abs(z[8:12] / SQRT_G - [-0.1391, -0.1391, -0.0139, 0.6033])) < 6e-3
    strikes = run.events["time"][np.isin(run.event_names(), STRIKES)]
    assert np.ptp(np.diff(strikes[-20:])) < 1e-5 and np.diff(strikes[-2:])[0] == pytest.approx(0.6105, abs=5e-4)


def constraint_jacobian(q, rows):
    """d(rows)/dq, written out from the foot formula of docs/reference-cases.md §2."""
    qx, qy, qi1, qi2, qo1, qo2 = q
    J = {"iKnee": [0, 0, 1, -1, 0, 0], "oKnee": [0, 0, 0, 0, 1, -1],
         "iFootX": [1, 0, L1 * math.cos(qi1), L2 * math.cos(qi2), 0, 0],
         "iFootY": [0, 1, L1 * math.sin(qi1), L2 * math.sin(qi2), 0, 0],
         "oFootX": [1, 0, 0, 0, L1 * math.cos(qo1), L2 * math.cos(qo2)],
         "oFootY": [0, 1, 0, 0, L1 * math.sin(qo1), L2 * math.sin(qo2)]}
    return np.array([J[r] for r in rows], dtype=float)


def test_impacts_lose_the_energy_of_the_plastic_impact_map(twenty_steps, walker):
    """v+ = (I - M^-1 J^T (J M^-1 J^T)^-1 J) v- over the target flow's rows (ANDY eq. 19), and
    the energy lost is Carnot's 1/2 (v- - v+)^T M (v- - v+); the knee bends lose nothing."""
    run = twenty_steps
    p = walker.parameters(None)
    U = walker.flow_inputs(walker.inputs(None), p)
    ev = run.events
    worst = 0.0
    for k, name in enumerate(run.event_names()):
        t, to, d = ev["time"][k], ev["to_flow"][k], ev["discrete_after"][k]
        xb, xa = ev["state_before"][k], ev["state_after"][k]
        lost = walker.module.energy(t, xb, U[to], p, d) - walker.module.energy(t, xa, U[to], p, d)
        if name.startswith("bend"):
            assert np.array_equal(xa, xb)
            assert abs(lost) < 1e-12
            continue
        M = walker.module.mass_matrix(t, xb, U[to], p, d)
        J = constraint_jacobian(xb[:6], sorted(ACTIVE[walker.flow_names[to]], key=ROWS.index))
        vm = xb[6:]
        MiJt = np.linalg.solve(M, J.T)
        vp = vm - MiJt @ np.linalg.solve(J @ MiJt, J @ vm)
        assert np.max(np.abs(xa[6:] - vp)) < 1e-10 * np.max(np.abs(vm))
        # the reset q2 := q1 moves a shank by what the event location leaves (1e-10 rad):
        # its potential energy change is taken out, not left in the tolerance
        assert np.max(np.abs(xa[:6] - xb[:6])) < 1e-9
        at_rest = np.r_[xb[:6], np.zeros(6)], np.r_[xa[:6], np.zeros(6)]
        moved = walker.module.energy(t, at_rest[0], U[to], p, d) - walker.module.energy(t, at_rest[1], U[to], p, d)
        carnot = 0.5 * (vm - vp) @ M @ (vm - vp)
        assert carnot > 3.0                     # measured: 3.4-3.5 J at a knee strike, 74-76 J at a heel strike
        worst = max(worst, abs(lost - moved - carnot) / carnot)
    assert worst < 1e-10                       # measured: 2.3e-12 (round-off of energies of ~1e3 J)
