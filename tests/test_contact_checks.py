"""Independent checks of the contact machinery (issue 38, item 3): each against a closed form or an independent
computation written here, by the event-driven methods (rk4, DOP853: events located to 1e-12 s) and by Moreau-Jean
time-stepping (`method="moreau"`: impacts and the turns of friction's direction at O(h), h = 1e-3 s), each with
its own tolerance.

1. A box dropped flat onto the ground (8 corner contacts, spatial friction): its four bottom corners strike at once
   at t = sqrt(2 h0 / g), it lands level and never turns; then it rests with m g / 4 on each bottom corner. Four
   corners hold the box's three free motions out of the plane (z, roll, pitch) with four rows: the split is not
   determined by the mechanics. What andyc guarantees: the ideal multipliers are the least-norm solution,
   lam = (A M^-1 A^T)^+ y (andyc_numerics' dynamics.constraint_force, IDEAL), and a least-norm solution of a
   problem symmetric under the box's two mirror planes is itself symmetric (it is unique, and the mirror image of
   a solution is a solution of the same norm): m g / 4 each.
2. The box pushed at v0 on flat ground (mu): all four corners slide, the friction mu m g in all, so it stops at
   t = v0 / (mu g) after v0^2 / (2 mu g), then sticks. While it slides the friction's moment about the centre
   (mu m g at the height c below it) loads the front corners: by moments, each front corner carries
   m g (1 + mu c / a) / 4 and each back one m g (1 - mu c / a) / 4 (a the half-length).
3. The box at rest on an incline of angle th (gravity turned by th): it sticks when mu > tan th and stays, and
   slides at a = g (sin th - mu cos th) when mu < tan th; at the boundary, mu = tan th +- 1e-3. Sticking well
   inside the cone, the forces are the least-norm solution of the box's equilibrium (six equations, twelve force
   components), computed here by numpy's lstsq.
4. A ball (a point mass of radius r, frictionless) sliding at v0 off a table's edge: it slides on the top to the
   edge, pivots about the edge (the table's gap is the distance from the edge, past it) at
   v^2 = v0^2 + 2 g r (1 - cos phi) with the normal force m (g cos phi - v^2 / r) = m (3 g cos phi - 2 g - v0^2/r),
   and leaves it where that force vanishes, cos phi* = (2 + v0^2 / (g r)) / 3 (the particle leaving a sphere:
   e.g. Meriam & Kraige, Dynamics, sample problem on a particle sliding off a hemisphere), after the quadrature
   t = int_0^phi* r dphi / v(phi); then a parabola to the floor, landing at the closed-form time and place.
5. Newton's cradle with 3 and 5 balls (models/newtons_cradle.yaml: equal balls on strings, frictionless,
   restitution e). andyc takes the impulses of every contact touching at an impact together, as the
   complementarity problem of Newton's law on each (andyc.runtime.contacts, Pfeiffer & Glocker 1996):
       Lam >= 0,  c+ + e c- >= 0,  Lam^T (c+ + e c-) = 0,  c+ = c- + W Lam,  W = J M^-1 J^T.
   For n touching equal balls, ball 1 arriving at w0, its one solution (W is positive definite) has every contact
   pushing, c+_12 = e w0 and c+_k = 0 for the others: momentum n w = w0 (1 + ...) gives balls 2..n together at
   (1 + e) w0 / n and ball 1 at (1 - (n - 1) e) w0 / n; each Lam_k = m L (n - k)(1 + e) w0 / n > 0. For e = 1 that
   keeps the energy too, (n - 2)^2 + 4 (n - 1) = n^2, but it is not the "one ball out" of a real cradle: that is
   the limit of impacts taken one after another. Balls separated by tiny gaps d do take them one after another,
   d / (L w0) apart, each an exchange of velocities between equal balls (e = 1): ball n leaves at w0.
6. The rimless wheel (models/rimless_wheel_contact.yaml: eight spoke tips as contacts) rolling down a slope:
   McGeer's (1990) closed form of its period-one gait (the post-strike angular velocity, the step period by
   quadrature) and its step map; and the hand-written wheel of models/rimless_wheel.yaml (a point hub, its foot a
   distance constraint and a hand-written plastic jump), run at the same alpha and gamma, as the independent
   reference (equal to O(k^2) for the contact wheel's radius of gyration k).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import ellipk

import andyc

G = 9.81
H = 1e-3        # every run's step (rk4's, moreau's); DOP853's first step
TIGHT = {"rtol": 1e-12, "atol": 1e-12}


def write(directory: Path, name: str, text: str) -> Path:
    path = directory / f"{name}.yaml"
    path.write_text(text)
    return path


# == 1-3. a box on the ground ==========================================================================================

A, B, C, MASS = 0.2, 0.15, 0.1, 2.0         # half-length (x), half-width (y), half-height (z), mass

BOX = f"""\
name: box_on_ground
parameters:
  m: {MASS}
  g: 9.81
  mu: 0.5       # friction at the corners
  e: 0.0        # restitution at the corners
  th: 0.0       # incline: gravity turned by th about y (the ground z = 0 is the slope, x down it)
  h0: 0.0       # drop height of the bottom face, m
  v0: 0.0       # initial speed along x, m/s
speeds:
  vx: {{initial: v0}}
  vy: {{initial: 0}}
  vz: {{initial: 0}}
  wx: {{initial: 0}}
  wy: {{initial: 0}}
  wz: {{initial: 0}}
ground: {{}}
gravity: [g*sin(th), 0, -g*cos(th)]
frames:
  - name: box
    parent: world
    floating: {{speeds: [vx, vy, vz, wx, wy, wz], position: [0, 0, {C} + h0], in: parent}}
    shape: {{box: {{size: [{2 * A}, {2 * B}, {2 * C}]}}, collide: true, friction: mu, restitution: e}}
bodies:
  - {{name: block, frame: box, mass: m,
     inertia: [m*({2 * B}**2 + {2 * C}**2)/12, m*({2 * A}**2 + {2 * C}**2)/12, m*({2 * A}**2 + {2 * B}**2)/12]}}
"""
# the corners (geometry.py: box_corner_<x><y><z>, p for +, m for -); the bottom four, front (+x) first
BOTTOM = ["box_corner_ppm", "box_corner_pmm", "box_corner_mpm", "box_corner_mmm"]
TOP = ["box_corner_ppp", "box_corner_pmp", "box_corner_mpp", "box_corner_mmp"]
CORNER_XY = np.array([[A, B], [A, -B], [-A, B], [-A, -B]])
OPEN, STICK, SLIP = 0, 1, 2


@pytest.fixture(scope="module")
def box(compiled, tmp_path_factory):
    return compiled(write(tmp_path_factory.mktemp("box"), "box_on_ground", BOX))


def bottom(run, values):
    """The bottom corners' columns of a (N, contacts) array."""
    return values[:, [run.contact_names.index(c) for c in BOTTOM]]


def lowest_corner(run):
    """The lowest height of any corner at any sample (frames='all')."""
    return min(np.min(run.frames[f"{c}_point"][:, 2]) for c in BOTTOM + TOP)


def moreau_friction(model, run):
    """(N, 4, 2) the bottom corners' tangential forces of a moreau run: the steps' mean impulses P_t / h, logged as
    the stick rows' multipliers."""
    rows = [model.contact_stick_rows[run.contact_names.index(c)] for c in BOTTOM]
    return np.stack([np.nan_to_num(run.multipliers[:, [r, r + 1]]) for r in rows], axis=1)


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
@pytest.mark.parametrize("e", [0.0, 0.5])
def test_box_dropped_flat_lands_on_four_corners_at_once(box, method, e):
    """Dropped flat from h0 = 0.2 m: the first impact at sqrt(2 h0 / g) (1e-12 s; measured 1.5e-14), taken by the
    four bottom corners together; the box leaves it level at e times its speed (e = 0: at rest; 1e-12), with no
    spin; the top corners stay open. With e = 0.5 every bounce is the same, until the impacts accumulate and it
    rests. It never turns (1e-11 rad/s; measured 5e-12) and no corner goes below the ground; it ends at rest on its
    four bottom corners, each carrying m g / 4 (the least-norm split: module docstring, item 1; 1e-10 N)."""
    run = andyc.simulate(box, 2.0, dt=H, method=method, parameters={"h0": 0.2, "e": e}, frames="all", **TIGHT)
    assert run.finished
    v = math.sqrt(2 * G * 0.2)
    assert abs(run.events["time"][0] - math.sqrt(2 * 0.2 / G)) < 1e-12
    before, after = run.events["state_before"][0], run.events["state_after"][0]    # vx vy vz wx wy wz, x y z, q
    assert before[2] == pytest.approx(-v, rel=1e-12)
    assert abs(after[2] - e * v) < 1e-12 and np.max(np.abs(after[[0, 1, 3, 4, 5]])) < 1e-12
    modes = dict(zip(run.contact_names, run.event_modes(0)))
    assert all(modes[c] == (STICK if e == 0 else OPEN) for c in BOTTOM) and all(modes[c] == OPEN for c in TOP)
    if e > 0:   # every bounce on all four at once: the impacts accumulate (Zeno) and it comes to rest
        assert np.allclose(run.events["state_after"][:-1, 2], -e * run.events["state_before"][:-1, 2],
                           rtol=1e-12, atol=1e-12)
    assert np.max(np.abs(run.state[:, 3:6])) < 1e-11                       # no spin (measured 5e-12)
    assert np.max(np.abs(run.state[:, 10:13])) < 1e-11                     # the quaternion stays (1, 0, 0, 0)
    assert lowest_corner(run) > -1e-12
    rest = run.time > 1.5
    assert np.all(bottom(run, run.contact_modes)[rest] == STICK)
    assert np.max(np.abs(bottom(run, run.normal_forces)[rest] - MASS * G / 4)) < 1e-10
    assert np.max(np.abs(bottom(run, run.friction_forces)[rest])) < 1e-10
    assert abs(run.column("box_z")[-1] - C) < 1e-12


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_box_dropped_flat_moreau(box, e):
    """Time-stepping: the impact step gives the four bottom corners equal impulses (1e-12 of them) summing to the
    box's change of momentum; Newton's law holds in that step on every corner, vz+ = -e vz- (1e-12); no spin
    (1e-13); it rests with m g / 4 on each corner (the mean force, 1e-10). A landing corner sinks by at most a
    step's travel, h |v| (the index set is decided on the gap predicted at the step's end; the corners are put back
    on the ground once closed): measured 0 for e = 0, 2.6e-5 m for e = 0.5, against h v = 2e-3 m."""
    model = box
    run = andyc.simulate(model, 2.0, dt=H, method="moreau", parameters={"h0": 0.2, "e": e}, frames="all")
    assert run.finished and run.stats["unverified_steps"] == 0
    impulses = bottom(run, np.nan_to_num(run.multipliers[:, list(model.contact_rows)])) * H
    k = np.nonzero(impulses.sum(axis=1) > 0.1)[0][0]            # the step ending at sample k
    assert np.max(np.abs(impulses[k] - impulses[k].mean())) < 1e-12 * impulses[k].mean()
    vz = run.column("vz")
    assert abs(impulses[k].sum() - MASS * (vz[k] - vz[k - 1]) - MASS * G * H) < 1e-12   # (gravity over the step)
    assert abs(vz[k] + e * vz[k - 1]) < 1e-12
    assert np.max(np.abs(run.state[:, 3:6])) < 1e-13
    assert lowest_corner(run) > -H * math.sqrt(2 * G * 0.2)
    rest = run.time > 1.5
    assert np.all(bottom(run, run.contact_modes)[rest] == STICK)
    assert np.max(np.abs(bottom(run, run.normal_forces)[rest] - MASS * G / 4)) < 1e-10


# -- 2. sliding to rest --------------------------------------------------------------------------------------------

MU, V0 = 0.5, 1.0
T_STOP = V0 / (MU * G)
X_STOP = V0 ** 2 / (2 * MU * G)


def test_box_slides_to_rest_at_v0_over_mu_g(box):
    """DOP853: pushed at v0 = 1 m/s (mu = 0.5) it slides straight, x = v0 t - mu g t^2 / 2, the front corners
    carrying m g (1 + mu c / a) / 4 and the back ones m g (1 - mu c / a) / 4, each with the friction mu lam_n
    against the slide; all four stop together at v0 / (mu g) (one stop event: the others, slipping at no speed
    then, stop with it) after v0^2 / (2 mu g), and stick: m g / 4 each, no friction, no motion."""
    run = andyc.simulate(box, 1.0, dt=H, method="DOP853", parameters={"v0": V0, "mu": MU}, frames="all", **TIGHT)
    assert run.finished
    assert len(run.events["time"]) == 1 and run.event_names()[0].endswith("_stop")
    assert abs(run.events["time"][0] - T_STOP) < 1e-12
    assert run.event_modes(0) == [STICK if c in BOTTOM else OPEN for c in run.contact_names]
    t, x = run.time, run.column("box_x")
    sliding, resting = t < T_STOP, t > T_STOP
    assert np.max(np.abs(x[sliding] - (V0 * t[sliding] - MU * G * t[sliding] ** 2 / 2))) < 1e-12
    assert np.max(np.abs(x[resting] - X_STOP)) < 1e-12
    assert np.max(np.abs(run.state[resting, :6])) < 1e-12
    # straight, level, no yaw, to the integrator's tolerance (1e-12 a step): the slip's direction grows more sensitive
    # to a rounding's yaw as the slip slows (as 1 / |s|): measured 1.7e-11 rad/s at t = 0.18 s, 20 ms before the
    # stop, with Numba 0.68 and NumPy 2.4 (below 1e-12 with the versions before)
    assert np.max(np.abs(run.state[:, [1, 2, 3, 4, 5]])) < 1e-10
    normal, friction = bottom(run, run.normal_forces), bottom(run, run.friction_forces)
    front, back = MASS * G * (1 + MU * C / A) / 4, MASS * G * (1 - MU * C / A) / 4
    assert np.max(np.abs(normal[sliding] - [front, front, back, back])) < 1e-10
    assert np.max(np.abs(friction[sliding] + MU * normal[sliding])) < 1e-10
    assert np.all(bottom(run, run.contact_modes)[sliding] == SLIP)
    assert np.all(bottom(run, run.contact_modes)[resting] == STICK)
    assert np.max(np.abs(normal[resting] - MASS * G / 4)) < 1e-10
    assert np.max(np.abs(friction[resting])) < 1e-10
    assert lowest_corner(run) > -1e-12


def test_box_slides_to_rest_rk4(box):
    """rk4 at h = 1e-3: near the stop the slip is slower than the fixed step can follow, and each step holds the
    direction in which an implicit step of the slip ends (numerics.slipping.held_direction): the box's corners,
    whose tangential inverse inertia J_t M^-1 J_t^T is not isotropic (their two tangents coupled through the box's
    turning), keep the slide's direction, as a ball's contact does. So the one stop event comes at v0 / (mu g) to
    the event tolerance (measured 7.0e-13 s early), the box rests at X_STOP (4.7e-16 m), and it sticks on all four
    corners with m g / 4 each; sliding straight, it does not yaw (2.7e-15 rad/s; was 1.2e-3 with the held
    direction s + h a_free, normalised, which the anisotropy turned)."""
    run = andyc.simulate(box, 1.0, dt=H, parameters={"v0": V0, "mu": MU})
    assert run.finished
    stops = run.events["time"]
    assert len(stops) == 1 and run.event_names()[0].endswith("_stop")
    assert abs(stops[0] - T_STOP) < 2e-12
    assert abs(run.column("box_x")[-1] - X_STOP) < 1e-12
    resting = run.time > stops[-1]
    assert np.max(np.abs(run.state[resting, :6])) < 1e-12
    assert np.all(bottom(run, run.contact_modes)[-1] == STICK)
    assert np.max(np.abs(bottom(run, run.normal_forces)[-1] - MASS * G / 4)) < 1e-10
    assert np.max(np.abs(run.column("wz"))) < 1e-12


def test_box_slides_to_rest_moreau(box):
    """Time-stepping: the friction impulse mu P_n per step takes mu g h off the speed each step, so the box stops in
    the step that holds v0 / (mu g) (the step's speed reaches 0 there and sticks: Coulomb's law at velocity level)
    and its position, a trapezoidal sum of the speeds, is X_STOP to h v0 / 2 at most (measured 2.7e-7 m); then it
    rests. While it slides, the corners' mean forces are the closed-form front and back ones (1e-10); at rest,
    the four corners' split is left as the steps' solver finds it (the problem is redundant, not the least-norm
    one: a warm start from the slide): what holds is the sum m g and no moment (1e-10), each corner pushing and
    inside its cone, and the friction forces cancelling (1e-10)."""
    model = box
    run = andyc.simulate(model, 1.0, dt=H, method="moreau", parameters={"v0": V0, "mu": MU})
    assert run.finished and run.stats["unverified_steps"] == 0
    t, vx = run.time, run.column("vx")
    first = np.nonzero(np.abs(vx) < 1e-12)[0][0]
    assert t[first - 1] < T_STOP <= t[first]
    assert abs(run.column("box_x")[-1] - X_STOP) < H * V0 / 2
    assert np.max(np.abs(run.state[first:, :6])) < 1e-12
    normal, friction = bottom(run, run.normal_forces), moreau_friction(model, run)
    sliding = (t > 0) & (t < t[first - 1])
    front, back = MASS * G * (1 + MU * C / A) / 4, MASS * G * (1 - MU * C / A) / 4
    assert np.max(np.abs(normal[sliding] - [front, front, back, back])) < 1e-10
    assert np.max(np.abs(friction[sliding, :, 0] + MU * normal[sliding])) < 1e-10
    rest = t > T_STOP + 10 * H
    assert np.max(np.abs(normal[rest].sum(axis=1) - MASS * G)) < 1e-10
    assert np.max(np.abs(normal[rest] @ CORNER_XY)) < 1e-10                     # no moment about x or y
    assert np.all(normal[rest] > 0)
    assert np.all(np.linalg.norm(friction[rest], axis=2) <= MU * normal[rest] + 1e-10)
    assert np.max(np.abs(friction[rest].sum(axis=1))) < 1e-10
    # Run.friction_forces reports those mean impulses, in every closed mode (some corners rest "slipping" at the
    # edge of their cone, at no speed)
    reported = np.stack([bottom(run, run.friction_forces), bottom(run, run.friction_forces_2)], axis=2)
    assert np.array_equal(reported[1:], friction[1:])


# -- 3. on an incline ----------------------------------------------------------------------------------------------

TH = 0.3        # tan th = 0.3093


def least_norm_forces(th):
    """(4, 3) the bottom corners' forces (x, y, z) holding the box at rest on the incline: the least-norm solution
    of its equilibrium, sum f = m g (-sin th, 0, cos th) and sum r x f = 0 (r = (+-a, +-b, -c) from the centre)."""
    rows = []
    for k in range(3):                          # forces
        rows.append([1.0 if j % 3 == k else 0.0 for j in range(12)])
    for k in range(3):                          # moments: (r x f)_k
        row = np.zeros(12)
        for i, (x, y) in enumerate(CORNER_XY):
            r = np.array([x, y, -C])
            for j in range(3):
                unit = np.zeros(3)
                unit[j] = 1.0
                row[3 * i + j] = np.cross(r, unit)[k]
        rows.append(row)
    rhs = np.array([-MASS * G * math.sin(th), 0.0, MASS * G * math.cos(th), 0.0, 0.0, 0.0])
    return np.linalg.lstsq(np.array(rows), rhs, rcond=None)[0].reshape(4, 3)


def box_forces(run):
    """(N, 4, 3) the bottom corners' forces of a run: friction along x and y, normal along z."""
    return np.stack([bottom(run, run.friction_forces), bottom(run, run.friction_forces_2),
                     bottom(run, run.normal_forces)], axis=2)


def incline_checks(run, mu, tol_still, tol_slide, tol_level=1e-12):
    """The box at rest on the incline from t = 0: it stays (mu > tan th) or slides down at g (sin th - mu cos th)
    (tol_slide), straight and level (tol_level: its height and sideways position; its turning 10 tol_slide)."""
    a = G * (math.sin(TH) - mu * math.cos(TH))
    x = run.column("box_x")
    if a < 0:
        assert np.max(np.abs(run.state[:, 6:9] - run.state[0, 6:9])) < tol_still
    else:
        assert np.max(np.abs(x - a * run.time ** 2 / 2)) < tol_slide
        assert np.all(bottom(run, run.contact_modes)[1:] == SLIP)
    assert np.max(np.abs(run.column("box_y"))) < max(tol_slide, tol_level)
    assert np.max(np.abs(run.column("box_z") - C)) < tol_level
    assert np.max(np.abs(run.state[:, 3:6])) < 10 * tol_slide         # no turning (DOP853: 7e-11 rad/s)


@pytest.mark.parametrize("dmu", [0.2, -0.2, 1e-3, -1e-3], ids=["sticks", "slides", "sticks-at-boundary",
                                                                 "slides-at-boundary"])
def test_box_on_incline(box, dmu):
    """DOP853, mu = tan th + dmu: for mu > tan th the box does not move (1e-12 m in 1 s); the forces hold it (their
    sum is -m g, 1e-10) and every corner's is inside its cone. Well inside (dmu = 0.2) they are the least-norm
    solution (1e-10: equal friction m g sin th / 4, the normal forces split by the friction's moment). At the
    boundary (dmu = 1e-3) the least-norm split would ask the back corners for more than their cone: they slip at
    rest at its edge, the front ones stick. For mu < tan th it slides at a = g (sin th - mu cos th), to 1e-10 m
    over 1 s (measured 2e-11 m at dmu = -1e-3, where a = 9.4e-3 m/s^2)."""
    mu = math.tan(TH) + dmu
    run = andyc.simulate(box, 1.0, dt=H, method="DOP853", parameters={"th": TH, "mu": mu}, frames="all", **TIGHT)
    assert run.finished and len(run.events["time"]) == 0
    incline_checks(run, mu, 1e-12, 1e-10)
    forces = box_forces(run)
    assert np.all(np.hypot(forces[..., 0], forces[..., 1]) <= mu * forces[..., 2] * (1 + 1e-12) + 1e-12)
    assert lowest_corner(run) > -1e-12
    if dmu > 0:
        weight = MASS * G * np.array([-math.sin(TH), 0.0, math.cos(TH)])
        assert np.max(np.abs(forces.sum(axis=1) - weight)) < 1e-10
        if dmu == 0.2:
            assert np.all(bottom(run, run.contact_modes) == STICK)
            assert np.max(np.abs(forces - least_norm_forces(TH))) < 1e-10
        else:
            assert np.all(bottom(run, run.contact_modes) == [STICK, STICK, SLIP, SLIP])
            assert np.allclose(np.hypot(forces[:, 2:, 0], forces[:, 2:, 1]), mu * forces[:, 2:, 2], rtol=1e-12)
    else:
        # sliding: each corner's friction mu lam_n straight up the slope
        assert np.max(np.abs(forces[1:, :, 0] + mu * forces[1:, :, 2])) < 1e-10


@pytest.mark.parametrize("dmu", [0.2, -0.2, 1e-3, pytest.param(-1e-3, marks=pytest.mark.xfail(
    strict=True, reason="rk4, sliding from rest at the cone's edge (a = 9.4e-3 m/s^2): while the slip is slower "
                        "than the step can follow, each corner's implicit step, taken with its own tangential "
                        "inverse inertia and not the four corners' coupled one, lets a rounding's yaw grow (1e-5 "
                        "rad/s by 10 ms), then the upper corners stop and slip again several times a step "
                        "(issue 38 report)"))],
    ids=["sticks", "slides", "sticks-at-boundary", "slides-at-boundary"])
def test_box_on_incline_rk4(box, dmu):
    """rk4 at h = 1e-3: the same closed forms (sticking: not a move, 1e-12 m; sliding: 1e-10 m)."""
    mu = math.tan(TH) + dmu
    run = andyc.simulate(box, 1.0, dt=H, parameters={"th": TH, "mu": mu})
    assert run.finished
    incline_checks(run, mu, 1e-12, 1e-10)


@pytest.mark.parametrize("dmu", [0.2, -0.2, 1e-3, -1e-3],
                         ids=["sticks", "slides", "sticks-at-boundary", "slides-at-boundary"])
def test_box_on_incline_moreau(box, dmu):
    """Time-stepping (0.2 s): sticking, it does not move (1e-12 m) and the forces sum to -m g (1e-10); sliding,
    theta = 1/2 is exact for a constant acceleration (dmu = -0.2: 1e-12 m over 0.2 s, measured 1.4e-16), straight
    and level. At the boundary (a = 9.4e-3 m/s^2) the slide from rest starts within a step (its speed off by
    4.6e-8 m/s: 9.2e-9 m at 0.2 s), within a h t of the closed form, and 4 of its 200 steps' contact problems
    are left unverified (Gauss-Seidel's answer kept), in which the box sinks 1.4e-11 m, moves 2.5e-11 m sideways
    (1e-10 asked) and turns at 1.4e-7 rad/s; well inside the cone every step is verified. Held at the boundary
    (mu = tan th + 1e-3) the upper corners carry less: an even split of the friction leaves their cones, so the
    polish splits it by mu P_n (contact_solver._weighted), and every step is verified (was: never, and the box crept
    down at 6.4e-8 m/s)."""
    model = box
    mu = math.tan(TH) + dmu
    run = andyc.simulate(model, 0.2, dt=H, method="moreau", parameters={"th": TH, "mu": mu})
    assert run.finished
    a = G * (math.sin(TH) - mu * math.cos(TH))
    boundary = abs(dmu) < 0.1
    incline_checks(run, mu, 1e-12, a * H * 0.2 if boundary and a > 0 else 1e-12, 1e-10 if boundary else 1e-12)
    assert run.stats["unverified_steps"] == (4 if dmu == -1e-3 else 0)
    if dmu > 0:
        weight = MASS * G * np.array([-math.sin(TH), 0.0])
        friction, normal = moreau_friction(model, run)[1:], bottom(run, run.normal_forces)[1:]
        assert np.max(np.abs(friction.sum(axis=1) - weight)) < 1e-10
        assert np.max(np.abs(normal.sum(axis=1) - MASS * G * math.cos(TH))) < 1e-10
        assert np.all(np.hypot(friction[..., 0], friction[..., 1]) <= mu * normal * (1 + 1e-12))  # every cone


# == 4. a ball sliding off a ledge ====================================================================================

R, HT, V_EDGE, X0 = 0.1, 0.5, 0.5, -0.2       # ball radius, table height, speed, start (0.2 m before the edge)

LEDGE = f"""\
name: ledge
parameters: {{m: 1.0, g: 9.81, r: {R}, h: {HT}, v0: {V_EDGE}, x0: {X0}}}
discrete: {{past: 0}}       # 1 once the centre is past the edge
coordinates:
  x: {{initial: x0, velocity: v0}}
  z: {{initial: h + r}}
gravity: [0, 0, -g]
frames:
  - {{name: slide, parent: world, prismatic: x, axis: x}}
  - {{name: ball, parent: slide, prismatic: z, axis: z}}
bodies:
  - {{name: mass, frame: ball, mass: m}}
contacts:
  # the distance from the centre to the table's top face (x <= 0 at height h), less r: to the face before the
  # edge, to the edge past it (the side face below never comes within r: the centre is 1.14 r out when it
  # passes the top's height)
  - {{name: table, gap: sqrt(past*ball.x**2 + (ball.z - h)**2) - r, multiplier: table_force}}
  - {{name: floor, gap: ball.z - r, multiplier: floor_force}}
hybrid:
  flows: [{{name: before}}, {{name: beyond}}]
  jumps:
    - {{name: edge, from: before, to: beyond, guard: x, direction: rising, reset: {{past: 1}}}}
"""
# the same table for time-stepping, which takes no hand-written jump: the ball starts at the edge at v0
EDGE = LEDGE.replace("name: ledge", "name: ledge_edge").replace("past*ball.x", "ball.x").replace(
    "initial: x0, velocity", "initial: 0, velocity").split("hybrid:")[0]


def ledge_reference(v0=V_EDGE, r=R, h=HT):
    """(pivot time, leaving angle, landing time after leaving, landing x, leaving velocity (vx, vz)): the closed
    form of the module docstring, item 4; the pivot's time by quadrature (its integrand is smooth)."""
    c = (2 + v0 ** 2 / (G * r)) / 3
    phi = math.acos(c)
    pivot = quad(lambda f: r / math.sqrt(v0 ** 2 + 2 * G * r * (1 - math.cos(f))), 0.0, phi, epsabs=0.0,
                 epsrel=1e-13)[0]
    speed = math.sqrt(G * r * c)                        # v^2 = g r cos(phi*) where the force vanishes
    x1, z1, vx, vz = r * math.sin(phi), h + r * c, speed * c, -speed * math.sin(phi)
    fall = (vz + math.sqrt(vz ** 2 + 2 * G * (z1 - r))) / G
    return pivot, phi, fall, x1 + vx * fall, (vx, vz)


@pytest.fixture(scope="module")
def ledge(compiled, tmp_path_factory):
    return compiled(write(tmp_path_factory.mktemp("ledge"), "ledge", LEDGE))


@pytest.fixture(scope="module")
def edge(compiled, tmp_path_factory):
    return compiled(write(tmp_path_factory.mktemp("edge"), "ledge_edge", EDGE))


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_ball_slides_off_a_ledge(ledge, method):
    """v0 = 0.5 m/s, r = 0.1 m (v0^2 < g r: it pivots), from 0.2 m before the edge: at the edge at 0.4 s (the
    hand-written jump that turns the table's gap from the top face to the edge), the table's force
    m (3 g cos phi - 2 g - v0^2 / r) along the pivot (1e-8 N), leaving at phi* = acos((2 + v0^2 / (g r)) / 3) =
    0.7203 rad after the quadrature's time, the floor struck at the parabola's time and place (rk4 at h = 1e-3:
    times to 1e-11 s, place 6e-11 m; DOP853: 5e-14; 1e-10 s and 1e-9 m asked), plastic, then sliding on at the
    leaving vx."""
    run = andyc.simulate(ledge, 1.0, dt=H, method=method, **TIGHT)
    pivot, phi, fall, x_land, (vx, vz) = ledge_reference()
    t_edge = -X0 / V_EDGE
    assert run.finished and run.event_names() == ["edge", "table_liftoff", "floor_impact"]
    expected = [t_edge, t_edge + pivot, t_edge + pivot + fall]
    assert np.max(np.abs(run.events["time"] - expected)) < 1e-10
    before = run.events["state_before"]                                     # x, z, x', z'
    assert abs(before[1, 0] - R * math.sin(phi)) < 1e-10 and abs(before[1, 1] - HT - R * math.cos(phi)) < 1e-10
    assert abs(before[2, 0] - x_land) < 1e-9
    assert abs(before[2, 2] - vx) < 1e-9 and abs(before[2, 3] - (vz - G * fall)) < 1e-9
    t, x, z = run.time, run.column("x"), run.column("z")
    top = t < t_edge
    assert np.all(run.contact_modes[top] == [STICK, OPEN]) and np.max(np.abs(z[top] - HT - R)) < 1e-12
    assert np.max(np.abs(run.normal_forces[top, 0] - G)) < 1e-10
    pivoting = (t > t_edge) & (t < t_edge + pivot)
    angle = np.arctan2(x[pivoting], z[pivoting] - HT)
    assert np.max(np.abs(np.hypot(x[pivoting], z[pivoting] - HT) - R)) < 1e-11        # (rk4's drift: 3.7e-12)
    force = 3 * G * np.cos(angle) - 2 * G - V_EDGE ** 2 / R
    assert np.max(np.abs(run.normal_forces[pivoting, 0] - force)) < 1e-8
    landed = t > expected[2]
    assert np.all(run.contact_modes[landed] == [OPEN, STICK])
    assert np.max(np.abs(run.column("x_dot")[landed] - vx)) < 1e-9 and np.max(np.abs(z[landed] - R)) < 1e-12
    assert np.min(z - R) > -1e-12


def test_ball_slides_off_the_edge_moreau(edge):
    """Time-stepping from the edge (at v0): the table's contact holds the ball on its circle about the edge (1e-12)
    and is open for good from the step that holds the closed-form leaving time, within 3 h (before that, where the
    force is small, it opens and closes again from step to step: the free motion along the tangent leaves the
    circle by O(h^2) and an impulse brings it back); the floor is struck within a step of the parabola's time
    and the ball slides on at the leaving vx to O(h) (measured 1.2e-3 m/s at h = 1e-3, 1.6e-4 at 1e-4), having
    landed within 3e-4 m of the closed-form place (measured 2.6e-4). No penetration of the floor."""
    run = andyc.simulate(edge, 0.6, dt=H, method="moreau")
    pivot, phi, fall, x_land, (vx, vz) = ledge_reference()
    assert run.finished
    t, x, z = run.time, run.column("x"), run.column("z")
    closed = np.nonzero(run.contact_modes[:, 0] == STICK)[0]
    assert abs(t[closed[-1]] - pivot) < 3 * H
    on = t <= t[closed[-1]]
    assert np.max(np.abs(np.hypot(x[on], z[on] - HT)[run.contact_modes[on, 0] == STICK] - R)) < 1e-12
    landed = np.nonzero(run.contact_modes[:, 1] == STICK)[0][0]
    assert abs(t[landed] - (pivot + fall)) <= H
    assert abs(x[landed] - x_land - vx * (t[landed] - pivot - fall)) < 3e-4
    assert abs(run.column("x_dot")[-1] - vx) < 2e-3
    assert np.min(z - R) > -1e-12


# == 5. Newton's cradle ================================================================================================

L_STRING, TH0 = 0.3, 0.4
W0 = 2 * math.sqrt(G / L_STRING) * math.sin(TH0 / 2)                  # at the bottom, from energy
T_STRIKE = math.sqrt(L_STRING / G) * ellipk(math.sin(TH0 / 2) ** 2)   # a quarter period at amplitude TH0
CRADLE3 = (Path(__file__).resolve().parents[1] / "models" / "newtons_cradle.yaml").read_text().split("\n# andyc")[0]
for _k in (4, 5):       # the shipped five-ball cradle less balls 4 and 5
    CRADLE3 = "\n".join(line for line in CRADLE3.splitlines()
                        if not any(s in line for s in (f"q{_k}", f"pivot{_k}", f"string{_k}", f"ball{_k}",
                                                       f"mass{_k}")))
CRADLE3 = CRADLE3.replace("name: newtons_cradle", "name: newtons_cradle3") + "\n"


@pytest.fixture(scope="module")
def cradles(compiled, tmp_path_factory):
    return {3: compiled(write(tmp_path_factory.mktemp("cradle3"), "newtons_cradle3", CRADLE3)),
            5: compiled("newtons_cradle")}


def simultaneous_law(n, e):
    """The angular velocities after ball 1 strikes n touching balls at w0: (1 - (n - 1) e) w0 / n, then (1 + e) w0 / n
    for the others (module docstring, item 5)."""
    return W0 * np.array([(1 - (n - 1) * e) / n] + [(1 + e) / n] * (n - 1))


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
@pytest.mark.parametrize("e", [1.0, 0.5])
@pytest.mark.parametrize("n", [3, 5])
def test_touching_cradle_takes_the_simultaneous_law(cradles, n, e, method):
    """Touching balls: one impact, at the quarter period sqrt(L/g) K(sin^2(th0/2)) (1e-11 s), that every contact
    takes part in, ball 1 arriving at w0; after it the velocities of the simultaneous law (rk4: 1e-12 of w0;
    DOP853, whose impact state is 1e-11 off: 1e-10), the sum of the speeds (the momentum: the strings are vertical,
    the impulses horizontal) kept to 1e-13, and for e = 1 the kinetic energy too (1e-13 relative). Ball 1 leaves
    its contact, the others move on together."""
    model = cradles[n]
    run = andyc.simulate(model, 0.4, dt=H, method=method, parameters={"e": e},
                         events=andyc.Events(stop_after={"c12_impact": 1}), **TIGHT)
    assert run.status == "finished" and run.event_names() == ["c12_impact"]
    assert abs(run.events["time"][0] - T_STRIKE) < 1e-11
    before, after = run.events["state_before"][0][n:], run.events["state_after"][0][n:]
    assert abs(before[0] - W0) < 1e-10 and np.max(np.abs(before[1:])) == 0.0
    tol = 1e-12 if method == "rk4" else 1e-10
    assert np.max(np.abs(after - simultaneous_law(n, e))) < tol * W0
    assert abs(after.sum() - before.sum()) < 1e-13 * W0
    if e == 1.0:
        assert abs(np.sum(after ** 2) / np.sum(before ** 2) - 1) < 1e-13
    else:   # the energy lost: the closed form's
        law = simultaneous_law(n, e)
        assert abs(np.sum(after ** 2) - np.sum(law ** 2)) < 10 * tol * W0 ** 2
    # ball 1 leaves (c+ = e w0 L); the others' contacts are left at zero force, closed or opened by a rounding
    assert run.event_modes(0)[0] == OPEN


def test_touching_cradle_runs_on(cradles):
    """DOP853 with five balls (e = 1) runs on past the impact for a swing (0.6 s): balls 2..5 move together at no
    contact force, each keeping its own energy after the impact, (2/5)^2 E0; ball 1 (3/5)^2 E0 (1e-10 relative)."""
    model = cradles[5]
    run = andyc.simulate(model, 0.6, dt=H, method="DOP853", **TIGHT)
    assert run.finished and run.event_names()[0] == "c12_impact"
    assert run.event_names().count("c12_impact") == 1
    e0 = 1 - math.cos(TH0)
    after = run.time > T_STRIKE
    for k, share in zip(range(1, 6), [9 / 25] + [4 / 25] * 4):
        q, w = run.column(f"q{k}")[after], run.column(f"q{k}_dot")[after]
        energy = (L_STRING * w ** 2 / (2 * G) + 1 - np.cos(q)) / e0
        assert np.max(np.abs(energy - share)) < 1e-10


def test_touching_cradle_runs_on_rk4(cradles):
    """rk4 with three touching balls (e = 1) runs on past the impact for a swing (0.6 s): balls 2 and 3 leave it
    together at no force between them, so their contact stays closed (a force a rounding from zero is zero), the two
    swinging as one, with no other event. (Before: the contact opened, its gap a rounding, 7e-18 m, crossed zero
    again and again, each crossing an impact with no impulse, until 101 jumps at one instant stopped the run.)"""
    run = andyc.simulate(cradles[3], 0.6, dt=H)
    assert run.finished and run.event_names() == ["c12_impact"]
    after = run.time > run.events["time"][0]
    assert np.all(run.contact_modes[after, 1] == 1)
    assert np.max(np.abs(run.column("q2")[after] - run.column("q3")[after])) < 1e-12
    assert np.max(np.abs(run.normal_forces[after, 1])) < 1e-12


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
@pytest.mark.parametrize("n", [3, 5])
def test_cradle_with_gaps_sends_one_ball_out(cradles, n, method):
    """Gaps of d = 1e-5 m (e = 1): n - 1 impacts, each between two balls alone, d / (L w0) = 1.467e-5 s apart (the
    first that long after the quarter period: ball 1 crosses the gap), each an exchange of velocities: ball n
    leaves at w0, the others are left at rest. The closed form neglects the strings: each impact comes d / L past
    the bottom, where the line of the centres is tilted by O((d/L)^2), so each exchange is exact to (d/L)^2 w0
    (measured 0.56 of it; 2 asked); and gravity over the chain, (n - 1) d / (L w0), which turns the balls, up to
    (n - 1) d / L from the bottom, by g/L (n - 1)^2 d^2 / (L^2 w0) at most, 1.1e-7 of w0 for n = 5 (measured
    2e-8), the tolerance of the velocities after the chain; the impact times to 1e-10 s."""
    model = cradles[n]
    d = 1e-5
    run = andyc.simulate(model, 0.4, dt=H, method=method, parameters={"d": d}, **TIGHT)
    assert run.finished
    assert run.event_names() == [f"c{k}{k + 1}_impact" for k in range(1, n)]
    gap_time = d / (L_STRING * W0)
    assert np.max(np.abs(run.events["time"] - T_STRIKE - gap_time * np.arange(1, n))) < 1e-10
    for k in range(n - 1):         # impact k: balls k + 1 and k + 2 exchange their velocities, the others keep theirs
        before, after = run.events["state_before"][k][n:], run.events["state_after"][k][n:]
        swapped = before.copy()
        swapped[[k, k + 1]] = before[[k + 1, k]]
        assert np.max(np.abs(after - swapped)) < 2 * (d / L_STRING) ** 2 * W0
        assert all(m == OPEN for m in run.event_modes(k))
    bound = G / L_STRING * (n - 1) ** 2 * d ** 2 / (L_STRING ** 2 * W0)
    last = run.events["state_after"][-1][n:]
    assert np.max(np.abs(last - W0 * np.eye(n)[-1])) < bound


@pytest.mark.parametrize("n", [3, 5])
def test_cradle_moreau(cradles, n):
    """Time-stepping, e = 1. Touching: every contact is in the impact step's problem (their gaps predicted at the
    step's end are <= 0: 0 for the resting ones), and Newton's law on all together is the simultaneous law: the
    step's velocities are the law's to O(h) (the impact is taken up to a step before the bottom: measured 5e-7 of
    w0; 1e-5 asked), the kinetic energy kept to 1e-6 relative. With gaps of 1e-5 m (less than a step's travel,
    w0 L h = 6.8e-4 m) the impacts still come one a step: each step's index set has only the contact whose gap the
    free motion closes, so one ball goes out, at w0 to O(h) (measured 6.3e-3 of w0 with five balls, 7.6e-3 with
    three; 1e-2 asked), the others left nearly at rest (7e-4 of w0 at most; 2e-3 asked)."""
    model = cradles[n]
    run = andyc.simulate(model, 0.3, dt=H, method="moreau")
    w = run.state[:, n:2 * n]
    k = np.nonzero(np.abs(w[:, 1]) > 0)[0][0]           # the impact step ends at sample k
    assert run.time[k - 1] < T_STRIKE <= run.time[k] + H
    assert np.max(np.abs(w[k] - simultaneous_law(n, 1.0))) < 1e-5 * W0
    assert abs(np.sum(w[k] ** 2) / np.sum(w[k - 1] ** 2) - 1) < 1e-6
    run = andyc.simulate(model, 0.3, dt=H, method="moreau", parameters={"d": 1e-5})
    end = run.state[-1, n:2 * n]
    assert abs(end[-1] - W0) < 1e-2 * W0 and np.max(np.abs(end[:-1])) < 2e-3 * W0


# == 6. the rimless wheel =============================================================================================

ALPHA, GAMMA, K_GYR = math.pi / 8, 0.1, 1e-3      # models/rimless_wheel_contact.yaml's defaults (g = l = m = 1)


def mcgeer(k=K_GYR, alpha=ALPHA, gamma=GAMMA):
    """(eta, c): a strike keeps w+ = eta w- (the angular momentum about the new tip: before it, k^2 w + l^2 w cos 2
    alpha, the hub's velocity l w at 2 alpha from the new spoke's normal; after it, (k^2 + l^2) w+), and a step
    adds c to w^2 (from energy: (l^2 + k^2) w^2 / 2 + g l cos(th + gamma), th from alpha to -alpha)."""
    eta = (k ** 2 + math.cos(2 * alpha)) / (k ** 2 + 1)
    return eta, 4 * math.sin(alpha) * math.sin(gamma) / (1 + k ** 2)


def gait(k=K_GYR):
    """McGeer's period-one gait: w* (just after a strike) from w*^2 = eta^2 (w*^2 + c), its step period."""
    eta, c = mcgeer(k)
    w = math.sqrt(eta ** 2 * c / (1 - eta ** 2))
    return w, step_time(w, k)


def step_time(w, k=K_GYR):
    """The time from a strike (leaving at w) to the next: int_{-alpha}^{alpha} dth / w(th), w(th)^2 = w^2 +
    2 (cos(alpha - gamma) - cos(th + gamma)) / (1 + k^2) (scipy quad; its integrand is smooth)."""
    return quad(lambda th: 1 / math.sqrt(w ** 2 + 2 * (math.cos(ALPHA - GAMMA) - math.cos(th + GAMMA)) / (1 + k ** 2)),
                -ALPHA, ALPHA, epsabs=0.0, epsrel=1e-13)[0]


@pytest.fixture(scope="module")
def wheel(compiled):
    return compiled("rimless_wheel_contact")


def strikes(run):
    """(times, angular speeds just after) of the wheel's spoke strikes."""
    return run.events["time"], -run.events["state_after"][:, 5]


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
@pytest.mark.parametrize("k", [K_GYR, 0.5])
def test_rimless_wheel_walks_mcgeers_gait(wheel, k, method):
    """From McGeer's gait (w* = 0.3909 rad/s for k = 1e-3, 0.4162 for k = 0.5; g = l = 1, 2 alpha = pi/4, gamma =
    0.1): in 20 s eight strikes (k = 0.5: nine), spokes 1, 2, ... in turn, each the plastic impact of the new
    tip alone (the trailing one lifts with no impulse, and no liftoff event is needed), the new tip closing
    sticking: w after each within 1e-9 of w* (measured 4.9e-10 at k = 1e-3, whose tiny inertia costs accuracy;
    2.3e-12 at 0.5), each step the quadrature's period (1e-8 s; measured 6.5e-9 at k = 1e-3, 2.9e-11 at 0.5), one
    tip closed at a time and sticking, no tip below the slope by more than the drift of the stance tip's row over 20 s (no projection:
    measured 2e-10 m; 1e-9 asked)."""
    w_star, period = gait(k)
    run = andyc.simulate(wheel, 20.0, dt=H, method=method, parameters={"k": k, "w0": w_star}, **TIGHT)
    assert run.finished
    n = int(20.0 // period)
    assert run.event_names() == [f"spoke{j % 8}_impact" for j in range(1, n + 1)]
    times, w = strikes(run)
    assert np.max(np.abs(times - period * np.arange(1, n + 1))) < 1e-8 * n
    assert np.max(np.abs(np.diff(np.concatenate([[0.0], times])) - period)) < 1e-8
    assert np.max(np.abs(w - w_star)) < 1e-9
    for j in range(n):
        assert run.event_modes(j) == [STICK if i == (j + 1) % 8 else OPEN for i in range(8)]
    closed = run.contact_modes > 0
    assert np.all(closed.sum(axis=1) == 1) and np.all(run.contact_modes[closed] == STICK)
    # the tips' heights: y - l cos(th + k pi/4), y the hub's
    tips = run.column("y")[:, None] - np.cos(run.column("th")[:, None] + np.pi / 4 * np.arange(8))
    assert np.min(tips) > -1e-9


@pytest.mark.parametrize("method", ["rk4", "DOP853"])
def test_rimless_wheel_against_the_hand_written_wheel(wheel, compiled, method):
    """Started off the gait (w0 = 0.6), the contact wheel follows McGeer's step map w+ = eta sqrt(w^2 + c) (1e-9
    rad/s; measured 3.1e-10) and the quadrature's step times (2e-8 s; measured 8.3e-9) towards its gait; and models/rimless_wheel.yaml, the point-hub wheel written with a
    hand-written foot and plastic jump (alpha = pi/8, gamma = 0.1 set), as the independent reference: the same
    strikes to O(k^2) = 1e-6 of the contact wheel's radius of gyration (measured 1.8e-7 rad/s in w, 9.5e-6 s in
    the seventh strike's time, the period's O(k^2) difference accumulating; 1e-6 rad/s and 2e-6 s per step asked)."""
    run = andyc.simulate(wheel, 16.0, dt=H, method=method, parameters={"w0": 0.6}, **TIGHT)
    ref = andyc.simulate(compiled("rimless_wheel"), 16.0, dt=H, method=method,
                         parameters={"w0": 0.6, "alpha": ALPHA, "gamma": GAMMA}, **TIGHT)
    assert run.finished and ref.finished
    times, w = strikes(run)
    eta, c = mcgeer()
    expected_w, expected_t, speed, t = [], [], 0.6, 0.0
    for _ in range(len(times)):
        t += step_time(speed)
        speed = eta * math.sqrt(speed ** 2 + c)
        expected_t.append(t)
        expected_w.append(speed)
    assert len(times) == 7
    assert np.max(np.abs(w - expected_w)) < 1e-9 and np.max(np.abs(times - expected_t)) < 2e-8
    off = np.abs(w - gait()[0])
    assert np.all(off[1:] < off[:-1])                      # converging to the gait
    ref_w = np.hypot(ref.events["state_after"][:, 2], ref.events["state_after"][:, 3])     # l w, l = 1
    assert len(ref.events["time"]) == len(times)
    assert np.max(np.abs(w - ref_w)) < 1e-6
    assert np.max(np.abs(times - ref.events["time"]) / np.arange(1, 8)) < 2e-6


def test_rimless_wheel_moreau(wheel):
    """Time-stepping from the gait (20 s): a strike is a step whose speed falls by a factor of about eta (rather than
    the smooth change of the stance); the strikes come within 3 h of the quadrature's period apart, and w after
    each is w* to O(h) (measured 1.2e-4 rad/s at h = 1e-3; 1e-3 asked). Sticking is held at velocity level (the
    tip's speed at the step's mid-point configuration), so the stance tip creeps along the slope by O(h) over a
    stance (measured 9.5e-4 m at h = 1e-3, 4.7e-4 at 5e-4; 2e-3 asked), and a landing tip enters the slope by at
    most a step's travel at its approach speed, 2 l sin(alpha) w, before its strike's step (measured 8.7e-6 m)."""
    w_star, period = gait()
    run = andyc.simulate(wheel, 20.0, dt=H, method="moreau")
    assert run.finished
    w = -run.column("th_dot")
    jumps = np.nonzero(w[1:] < 0.85 * w[:-1])[0] + 1       # the sample ending a strike's step
    assert len(jumps) == int(20.0 // period)
    assert np.max(np.abs(np.diff(run.time[jumps]) - period)) < 3 * H
    assert np.max(np.abs(w[jumps] - w_star)) < 1e-3
    x, th = run.column("x"), run.column("th")
    angles = th[:, None] + np.pi / 4 * np.arange(8)
    tip_x, tip_y = x[:, None] + np.sin(angles), run.column("y")[:, None] - np.cos(angles)
    for j in range(1, len(jumps)):                          # each stance between two strikes: one tip
        stance = slice(jumps[j - 1], jumps[j])
        tip = j % 8
        assert np.all(run.contact_modes[stance, tip] == STICK)
        assert np.ptp(tip_x[stance, tip]) < 2e-3
    assert np.min(tip_y) > -H * 2 * math.sin(ALPHA) * 0.5
