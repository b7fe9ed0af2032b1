"""Unitree's Go1 on its four frictional feet (issue 38, item 1): models/go1.yaml, example-robot-data's URDF on a
floating base, its four foot spheres colliding with the ground (mu = 0.8), joint limits as stops, a PD motor on
each joint; time-stepping (Moreau-Jean, dt = 1e-3), and event-driven (projection) for standing and trotting.

- It stands 10 s on four feet: no foot below the ground by more than 1e-4 m, the base height drifting less than
  1 mm over the last 9 s, the normal forces summing to m g (m from the URDF's own masses, read here from its XML)
  to 1e-6, every foot's friction force inside its cone, the feet sticking. Event-driven, the feet stay on the
  ground to 1e-9 m.
- With trot = 1 (an open-loop trot: diagonal pairs swinging their thighs and lifting their feet in turn) it moves
  forward without falling and with no foot below the ground by more than 1e-4 m; event-driven, for 10 s, its
  feet on the ground to 1e-9 m.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest

import andyc
from tests.support import MODELS

G, MU, RADIUS = 9.81, 0.8, 0.02
FEET = ("FR", "FL", "RR", "RL")


def urdf_mass() -> float:
    """The robot's mass: the sum of the URDF's <mass value> (every link's, as written)."""
    root = ET.parse(MODELS / "go1" / "go1.urdf").getroot()
    return sum(float(m.get("value")) for m in root.iter("mass"))


@pytest.fixture(scope="module")
def go1(compiled):
    return compiled("go1")


@pytest.fixture(scope="module")
def standing(go1):
    return andyc.simulate(go1, 10.0, dt=1e-3, method="moreau", every=10, frames=[f"{f}_foot" for f in FEET],
                          progress=False)


def foot_bottoms(run) -> np.ndarray:
    """(N, 4) the height of each foot sphere's lowest point above the ground (from its centre, the frame logged)."""
    return np.stack([run.frames[f"{f}_foot"][:, 2] for f in FEET], axis=1) - RADIUS


def test_go1_stands_ten_seconds_on_four_feet(go1, standing):
    run = standing
    feet = [run.contact_names.index(f"{f}_foot_sphere") for f in FEET]
    assert run.finished and run.stats["unverified_steps"] == 0
    assert np.all(run.contact_modes[:, feet] == 1)                  # every foot closed and sticking, all along
    assert foot_bottoms(run).min() > -1e-4                           # (measured: 1e-16 m)
    z, late = run.column("base_z"), run.time >= 1.0
    assert abs(z[-1] - z[late][0]) < 1e-3 and np.ptp(z[late]) < 1e-3     # (measured: 0.3 and 0.5 mm)
    total = run.normal_forces[-1, feet].sum()
    assert abs(total / (urdf_mass() * G) - 1.0) < 1e-6               # (measured: 5e-12)
    normal = run.normal_forces[1:, feet]
    tangential = np.hypot(run.friction_forces[1:, feet], run.friction_forces_2[1:, feet])
    assert np.all(normal > 0) and np.all(tangential <= MU * normal * (1 + 1e-9))
    # the feet stick: the step holds their slip at zero at its mid point, so at its end the slip is O(h) times the
    # robot's motion while it settles (measured 5e-5 m/s at first, 4e-7 after 1 s), and nothing once it stands
    slips = np.hypot(run.slip_speeds[:, feet], run.slip_speeds_2[:, feet])
    assert np.nanmax(slips[1:]) < 1e-4 and np.nanmax(slips[run.time > 5.0]) < 1e-10


@pytest.fixture(scope="module")
def trotting(go1):
    return andyc.simulate(go1, 5.0, dt=1e-3, method="moreau", every=10, parameters={"trot": 1.0},
                          frames=[f"{f}_foot" for f in FEET], progress=False)


def test_go1_trots_forward(trotting):
    run = trotting
    x, z = run.column("base_x"), run.column("base_z")
    assert run.finished and x[-1] - x[0] > 1.0                     # (measured: 2.0 m in 5 s, 0.4 m/s)
    assert z.min() > 0.2                                            # it does not fall (standing: 0.276 m)
    assert foot_bottoms(run).min() > -1e-4
    feet = [run.contact_names.index(f"{f}_foot_sphere") for f in FEET]
    modes = run.contact_modes[:, feet]
    assert np.any(modes == 0, axis=0).all() and np.any(modes > 0, axis=0).all()   # each foot lifts and lands


def test_go1_stands_ten_seconds_event_driven(go1):
    """Event-driven (projection: RK4 with the closed feet's rows as constraints, projected back to them after
    each step): the feet held on the ground to 1e-9 m, and the standing figures of time-stepping."""
    run = andyc.simulate(go1, 10.0, dt=1e-3, method="projection", every=10, frames=[f"{f}_foot" for f in FEET],
                         progress=False)
    feet = [run.contact_names.index(f"{f}_foot_sphere") for f in FEET]
    assert run.finished and np.all(run.contact_modes[:, feet] > 0)
    assert np.abs(foot_bottoms(run)).max() < 1e-9                    # on the ground, neither below nor above
    z, late = run.column("base_z"), run.time >= 1.0
    assert abs(z[-1] - z[late][0]) < 1e-3 and np.ptp(z[late]) < 1e-3
    assert abs(run.normal_forces[-1, feet].sum() / (urdf_mass() * G) - 1.0) < 1e-6
    normal = run.normal_forces[1:, feet]
    tangential = np.hypot(run.friction_forces[1:, feet], run.friction_forces_2[1:, feet])
    assert np.all(normal > 0) and np.all(tangential <= MU * normal * (1 + 1e-9))


@pytest.fixture(scope="module")
def trotting_event_driven(go1):
    return andyc.simulate(go1, 10.0, dt=1e-3, method="projection", every=1, parameters={"trot": 1.0},
                          frames=[f"{f}_foot" for f in FEET], progress=False)


def test_go1_trots_event_driven_as_it_does_time_stepping(trotting_event_driven, trotting):
    """Event-driven, the feet's landings are impacts (the touching feet's impulses solved together, a spatial
    slide's direction found by the contact solver) and their liftoffs and slips events: it trots the whole 10 s
    (its feet sticking and slipping in turn some hundred times; a slip begun at the cone's edge once ended and
    began again without end at one instant, at 6.4 s), and as far as time-stepping's in the first 5 s (both are
    first order in the step where the feet land)."""
    run = trotting_event_driven
    x, z = run.column("base_x"), run.column("base_z")
    assert run.finished and run.time[-1] == 10.0 and z.min() > 0.2
    assert x[-1] - x[0] > 3.0                                       # (measured: 4.0 m in 10 s)
    five = np.searchsorted(run.time, 5.0 - 1e-9)
    ahead = trotting.column("base_x")[-1] - trotting.column("base_x")[0]
    assert abs((x[five] - x[0]) - ahead) < 0.05 * ahead
    names = run.event_names()
    assert sum(n.endswith("_slip") for n in names) > 10 and sum(n.endswith("_stop") for n in names) > 10


def test_go1_trots_event_driven_with_its_feet_on_the_ground(trotting_event_driven):
    """No foot below the ground by more than 1e-9 m: landings located, and a liftoff at zero speed whose foot would
    fall back at once (its friction held a force as its normal force fell) is no liftoff (resolve_liftoff)."""
    assert foot_bottoms(trotting_event_driven).min() > -1e-9
