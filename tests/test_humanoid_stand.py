"""A humanoid standing on 8 foot-corner contacts (issue 38, item 2): Unitree's G1, models/g1.yaml (legs only, the
waist and arms locked; each foot's four collision spheres at its sole's corners colliding with the ground, mu 0.8;
PD motors holding a standing pose), 5 s of the compiled Moreau-Jean time-stepping at dt 1e-3, and of the
event-driven rk4 (whose 8 sticking contacts give 24 dependent constraint rows: least-norm multipliers).

Independent of andyc: the robot's mass and the height where its soles touch the ground come from Pinocchio (the
URDF's own kinematics and inertias) and the collision spheres from the URDF's XML. Checked at rest (the last
second): the normal forces carry m g to 1e-6 relative; every contact force inside its friction cone, throughout;
no sphere below the ground by more than 1e-4 m; the pelvis' height still; the feet not slipping.

Measured (theta = 1, the figures the bounds below leave room for): sum of the normal forces - m g over the last
second 3e-13 relative; |f_t| / f_n at most 0.47 (the first samples, the PD not yet pushing), 0.0042 at rest;
deepest sphere 9.4e-9 m below the ground; the pelvis settles 0.28 mm below h0 (the PD's sag) and moves 4e-14 m in
the last second; the sphere centres move 0.13 um sideways over the run, 2e-15 m in the last second; no contact
ever leaves the sticking mode. rk4: no event, all sticking, the least-norm forces at 5 s within 6e-5 N of
time-stepping's, the gaps drifting to -5.3e-7 m (no projection: the speed residual 1.1e-7 m/s left by the first
steps stays).

theta = 1 for the main runs, and the default 1/2 once: until the time-stepping's index set kept a closed contact
whatever its free velocity (andyc/numerics/timestepping.py), at 1/2 it dropped each heel whose *free* velocity
rose (the ankle motor spins the light foot in free motion) although the toes' impulses drove it down: the heels
chattered every other step and the robot fell. At theta = 1 the index set is the gap at q_k + h v_k alone.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pytest
import yaml

import andyc
from tests.support import MODELS

pin = pytest.importorskip("pinocchio")

MODEL = MODELS / "g1.yaml"
URDF = MODELS / "g1" / "g1_29dof_rev_1_0.urdf"
FEET = ("left_ankle_roll_link", "right_ankle_roll_link")
T_END, DT = 5.0, 1e-3
REST = 1.0                   # s: the last second is the rest the checks read
STEPPING = andyc.TimeStepping(theta=1.0)


def parameters() -> dict:
    return yaml.safe_load(MODEL.read_text())["parameters"]


def spheres() -> list:
    """(link, centre in the link's frame, radius) of each collision sphere of the feet, from the URDF's XML."""
    robot = ET.parse(URDF).getroot()
    out = []
    for link in robot.findall("link"):
        if link.get("name") not in FEET:
            continue
        for c in link.findall("collision"):
            xyz = np.array([float(v) for v in c.find("origin").get("xyz").split()])
            out.append((link.get("name"), xyz, float(c.find("geometry/sphere").get("radius"))))
    return out


def pinocchio_stance(h0: float):
    """Pinocchio's G1 on a free flyer at the model's pose (pelvis level at height h0, the locked joints at 0):
    (model, data) after forward kinematics."""
    model = pin.buildModelFromUrdf(str(URDF), pin.JointModelFreeFlyer())
    data = model.createData()
    p = parameters()
    q = pin.neutral(model)
    q[2] = h0
    for side in ("left", "right"):
        for joint, name in (("hip_pitch", "q_hip"), ("knee", "q_knee"), ("ankle_pitch", "q_ankle")):
            q[model.joints[model.getJointId(f"{side}_{joint}_joint")].idx_q] = p[name]
    pin.framesForwardKinematics(model, data, q)
    return model, data


@pytest.fixture(scope="module")
def g1(compiled):
    return compiled("g1")


def run(model, method):
    frames = [f"{c}_centre" for c in model.contact_names]
    return andyc.simulate(model, T_END, dt=DT, method=method, frames=frames, stepping=STEPPING)


@pytest.fixture(scope="module")
def stand(g1):
    return run(g1, "moreau")


@pytest.fixture(scope="module")
def stand_rk4(g1):
    return run(g1, "rk4")


@pytest.fixture(scope="module")
def weight(stand):
    """m g: the robot's whole mass (the locked arms and waist too) from Pinocchio, times the run's g. (On a free
    flyer: on a fixed base Pinocchio's total mass leaves out the root link's, the pelvis' 3.8 kg.)"""
    model = pin.buildModelFromUrdf(str(URDF), pin.JointModelFreeFlyer())
    return pin.computeTotalMass(model) * stand.parameters["g"]


def gaps(r) -> np.ndarray:
    """(N, 8) each sphere's lowest point's height above the ground (z = 0); a link's k-th sphere is the contact
    <link>_<k>_sphere."""
    radius = {}
    for foot in FEET:
        for k, (_, _, rad) in enumerate(s for s in spheres() if s[0] == foot):
            radius[f"{foot}_{k}_sphere"] = rad
    return np.stack([r.frames[f"{c}_centre"][:, 2] - radius[c] for c in r.contact_names], axis=1)


def test_the_model_has_the_8_foot_corners():
    """The URDF's four spheres per foot, and nothing else, are the model's contacts (limits: false: no stops)."""
    assert len(spheres()) == 8 and {s[2] for s in spheres()} == {0.005}
    assert sorted(c.name for c in andyc.load(MODEL).contacts) == sorted(
        f"{foot}_{k}_sphere" for foot in FEET for k in range(4))


def test_h0_is_where_the_soles_touch_the_ground():
    """Every sphere touches z = 0 at the pose with the pelvis at h0 (Pinocchio's forward kinematics): the soles
    level, none lifted, none inside."""
    model, data = pinocchio_stance(parameters()["h0"])
    for link, centre, radius in spheres():
        z = data.oMf[model.getFrameId(link)].act(centre)[2] - radius
        assert abs(z) < 1e-12, (link, centre, z)


def test_it_stands_on_its_8_corners(stand, weight):
    r = stand
    assert r.finished, r.status
    rest = r.time >= T_END - REST
    assert rest.sum() == round(REST / DT) + 1
    modes = r.contact_modes
    assert (modes == 1).all()                               # every corner sticks from the first step on
    fn = r.normal_forces
    total = fn[rest].sum(axis=1)
    assert np.abs(total / weight - 1).max() < 1e-6          # measured 3e-13
    assert (fn[1:] > 0).all()


def test_every_contact_force_is_inside_its_friction_cone(stand):
    r = stand
    mu = parameters()["mu"]
    fn = r.normal_forces
    ft = np.hypot(r.friction_forces, r.friction_forces_2)
    assert np.allclose(r.contact_mu, mu)
    assert (ft <= mu * fn * (1 + 1e-12) + 1e-12).all()      # measured: |f_t| / f_n <= 0.47
    rest = r.time >= T_END - REST
    assert (ft[rest] <= 0.01 * fn[rest]).all()              # at rest, 0.0042: the PD's squeeze of the legs


def test_no_corner_sinks_and_the_feet_hold(stand):
    r = stand
    g = gaps(r)
    assert g.min() > -1e-4                                  # the bound; measured -9.4e-9 m
    assert g.min() > -1e-7                                  # (the position corrections keep it at rounding)
    rest = r.time >= T_END - REST
    xy = np.stack([r.frames[f"{c}_centre"][:, :2] for c in r.contact_names], axis=1)     # (N, 8, 2)
    assert np.abs(xy - xy[0]).max() < 1e-6                  # no slip over the run: measured 1.3e-7 m
    assert np.abs(xy[rest] - xy[rest][0]).max() < 1e-10     # at rest: 2e-15 m
    slip = np.hypot(r.slip_speeds, r.slip_speeds_2)[rest]
    assert np.nanmax(slip) < 1e-9


def test_the_base_height_settles_and_stays(stand):
    r = stand
    h0 = parameters()["h0"]
    z = r.column("pelvis_z")
    rest = r.time >= T_END - REST
    assert z[0] == h0
    assert -1e-3 < z[-1] - h0 < 0                           # the PD's sag under the weight: measured -0.28 mm
    assert np.ptp(z[rest]) < 1e-9                           # measured 4e-14 m
    for speed in ("pelvis_vx", "pelvis_vy", "pelvis_vz", "pelvis_wx", "pelvis_wy", "pelvis_wz"):
        assert abs(r.column(speed)[rest]).max() < 1e-8


def test_event_driven_rk4_carries_it_on_least_norm_multipliers(stand_rk4, stand, weight):
    """The event-driven path: 8 sticking contacts, 24 dependent rows (each foot's 12 fix its 6 speeds), solved for
    least-norm multipliers; no contact ever opens or slips, and at rest the forces are time-stepping's."""
    r = stand_rk4
    assert r.finished, r.status
    assert len(r.events["time"]) == 0
    assert (r.contact_modes == 1).all()
    rest = r.time >= T_END - REST
    fn = r.normal_forces
    assert np.abs(fn[rest].sum(axis=1) / weight - 1).max() < 1e-6       # measured 3e-13
    mu = parameters()["mu"]
    assert (np.hypot(r.friction_forces, r.friction_forces_2) <= mu * fn * (1 + 1e-12) + 1e-12).all()
    assert np.abs(fn[-1] - stand.normal_forces[-1]).max() < 1e-3        # measured 6e-5 N (of 30 to 52 N)
    assert gaps(r).min() > -1e-5                                        # rk4's drift: -5.3e-7 m at 5 s


def test_at_the_default_theta_too(g1, stand, weight):
    """theta = 1/2, the default: the index set keeps a closed heel that its free motion would lift (andyc's
    numerics/timestepping.py); the figures of theta = 1."""
    r = andyc.simulate(g1, T_END, dt=DT, method="moreau", frames=[f"{c}_centre" for c in g1.contact_names])
    assert r.finished, r.status
    assert (r.contact_modes == 1).all()
    rest = r.time >= T_END - REST
    fn = r.normal_forces
    assert np.abs(fn[rest].sum(axis=1) / weight - 1).max() < 1e-6       # measured 3e-13
    assert gaps(r).min() > -1e-7                                        # measured -1e-9 m
    assert np.abs(fn[-1] - stand.normal_forces[-1]).max() < 1e-3        # measured 5e-5 N
