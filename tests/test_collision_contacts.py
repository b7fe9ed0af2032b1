"""Contacts made from geometry (andyc/spec/geometry.py, andyc/spec/urdfcontacts.py), at the Spec and symbolic
level (their simulation: tests/test_go1.py and the contact tests).

- Against Pinocchio: example-robot-data's Go1 on a floating base with its four foot spheres colliding, and a
  small arm of our own with a box, a sphere and a cylinder, both on a tilted ground. At random states, andyc's
  gap rows phi, their rates and the slip rows (c = A v: checked through A too) equal the gap and the contact
  point's velocity computed here from Pinocchio's collision placements (buildGeomFromUrdf,
  updateGeometryPlacements) and frame velocities (getFrameVelocity) with this file's own plane geometry, to
  1e-12. The joint-limit stops' rows are q - lower and upper - q with Pinocchio's limits.
- The rows are read from `andyc.load`: a contact's gap and stick rows are constraint rows of the Spec, which
  the runtime adds to a flow's while the contact is closed.
- A joint-limit URDF: stops for revolute and prismatic joints, none for continuous, mimic or locked joints or
  an unwritten side; `limits: false` gives none.
- A YAML shape with collide: true gives the rows of the hand-written contact.
- Bad input: each problem one located line (tests/support/diagnostics.py).
"""

from __future__ import annotations

import math
import types

import numpy as np
import pytest
import sympy as sp

import andyc
from andyc.errors import SpecError
from andyc.spec.model import Spec
from andyc.symbolic.constraints import FrameQuantities, constraint_terms
from andyc.symbolic.emitter import Emitter
from andyc.symbolic.kinematics import frame_kinematics
from tests.support import ROBOTS_DIR
from tests.support.diagnostics import LINE_FORMAT, assert_at, line_of, one_problem, problems
from tests.support.pinocchio_map import PinocchioMap

pin = pytest.importorskip("pinocchio")

GO1 = ROBOTS_DIR / "go1_description/urdf/go1.urdf"
STATES = 10
TOL = 1e-12
RIM = 8
TILTED = {"normal": [0.1, -0.2, 1.0], "height": 0.05}

ARM = """<?xml version="1.0"?>
<robot name="arm">
  <link name="base"><inertial><mass value="2"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
    </inertial></link>
  <joint name="shoulder" type="revolute">
    <parent link="base"/><child link="upper"/><origin xyz="0 0 0.5" rpy="0.2 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1.5" upper="2.0" effort="10" velocity="3"/>
  </joint>
  <link name="upper">
    <inertial><origin xyz="0.15 0 0"/><mass value="1"/>
      <inertia ixx="0.01" iyy="0.02" izz="0.02" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.15 0.01 -0.02" rpy="0.1 0.2 0.3"/><geometry><box size="0.3 0.1 0.05"/></geometry>
    </collision>
  </link>
  <joint name="elbow" type="revolute">
    <parent link="upper"/><child link="fore"/><origin xyz="0.3 0 0"/><axis xyz="0.6 0.8 0"/>
    <limit lower="-2.5" upper="0.5" effort="10" velocity="3"/>
  </joint>
  <link name="fore">
    <inertial><origin xyz="0.12 0 0"/><mass value="0.7"/>
      <inertia ixx="0.005" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial>
    <collision><origin xyz="0.25 0.01 0"/><geometry><sphere radius="0.05"/></geometry></collision>
    <collision><origin xyz="0.1 0 0.02" rpy="0 1.5707963267948966 0.4"/>
      <geometry><cylinder radius="0.03" length="0.2"/></geometry></collision>
  </link>
</robot>
"""

# The arm with its forearm's sphere alone (one contact: what today's loader takes with spatial friction).
SPHERE_ARM = ARM.replace("""    <collision><origin xyz="0.1 0 0.02" rpy="0 1.5707963267948966 0.4"/>
      <geometry><cylinder radius="0.03" length="0.2"/></geometry></collision>
""", "")

STOPS = """<?xml version="1.0"?>
<robot name="stops">
  <link name="base"/>
  <joint name="hinge" type="revolute">
    <parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
    <limit lower="-0.75" upper="1.25" effort="5" velocity="2"/>
  </joint>
  <link name="a"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
    </inertial></link>
  <joint name="slide" type="prismatic">
    <parent link="a"/><child link="b"/><origin xyz="0.2 0 0"/><axis xyz="1 0 0"/>
    <limit lower="0.05" upper="0.3" effort="5" velocity="2"/>
  </joint>
  <link name="b"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
    </inertial></link>
  <joint name="spin" type="continuous">
    <parent link="b"/><child link="c"/><axis xyz="0 1 0"/><limit effort="5" velocity="2"/>
  </joint>
  <link name="c"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
    </inertial></link>
  <joint name="follow" type="revolute">
    <parent link="c"/><child link="d"/><axis xyz="0 0 1"/><mimic joint="hinge" multiplier="2"/>
    <limit lower="-1" upper="1" effort="5" velocity="2"/>
  </joint>
  <link name="d"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
    </inertial></link>
  <joint name="tilt" type="revolute">
    <parent link="d"/><child link="e"/><axis xyz="1 0 0"/><limit upper="0.4" effort="5" velocity="2"/>
  </joint>
  <link name="e"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/>
    </inertial></link>
</robot>
"""


# -- this file's own plane geometry (the rule docs/model-file.md states) -----------------------------

def plane(ground: dict):
    """(n, h, t1, t2): the unit normal, height and tangents (t1 = x projected on the plane, or y when |n_x| >
    0.9; t2 = n x t1)."""
    n = np.array(ground.get("normal", [0, 0, 1]), dtype=float)
    n /= np.linalg.norm(n)
    e = np.eye(3)[0] if abs(n[0]) <= 0.9 else np.eye(3)[1]
    t1 = e - e.dot(n) * n
    t1 /= np.linalg.norm(t1)
    return n, float(ground.get("height", 0.0)), t1, np.cross(n, t1)


def collision_points(model, geom, gdata, data):
    """contact name -> (world point, radius, its link's frame id) of every collision object, from Pinocchio's
    placements: a sphere's centre, a box's 8 corners, a cylinder's two rims at 8 angles each."""
    per_link = {}
    for o in geom.geometryObjects:
        per_link.setdefault(model.frames[o.parentFrame].name, []).append(o)
    out = {}
    for k, o in enumerate(geom.geometryObjects):
        link = model.frames[o.parentFrame].name
        mine = per_link[link]
        base = link + (f"_{int(o.name.rsplit('_', 1)[1])}" if len(mine) > 1 else "")
        M = gdata.oMg[k]
        g = o.geometry
        kind = type(g).__name__
        if kind == "Sphere":
            out[f"{base}_sphere"] = (M.translation.copy(), g.radius, o.parentFrame)
        elif kind == "Box":
            for sx in (1, -1):
                for sy in (1, -1):
                    for sz in (1, -1):
                        name = "".join("p" if s > 0 else "m" for s in (sx, sy, sz))
                        out[f"{base}_corner_{name}"] = (M.act(np.array([sx, sy, sz]) * g.halfSide), 0.0,
                                                        o.parentFrame)
        elif kind == "Cylinder":
            for end, sign in (("p", 1), ("m", -1)):
                for i in range(RIM):
                    a = 2 * math.pi * i / RIM
                    local = np.array([g.radius * math.cos(a), g.radius * math.sin(a), sign * g.halfLength])
                    out[f"{base}_rim_{end}_{i}"] = (M.act(local), 0.0, o.parentFrame)
    return out


def expected(model, data, points: dict, ground: dict) -> dict:
    """contact -> (gap, gap rate, slip 1, slip 2) from Pinocchio: the contact point p - r n moves at
    v_p + w x (-r n), v_p = v_frame + w x (p - frame origin) (LOCAL_WORLD_ALIGNED: world axes)."""
    n, h, t1, t2 = plane(ground)
    out = {}
    for name, (p, r, frame) in points.items():
        motion = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
        w = motion.angular
        vp = motion.linear + np.cross(w, p - data.oMf[frame].translation)
        vc = vp + np.cross(w, -r * n)
        out[name] = (n.dot(p) - r - h, n.dot(vc), t1.dot(vc), t2.dot(vc))
    return out


# -- andyc's rows ------------------------------------------------------------------------

def rows_spec(path, monkeypatch) -> Spec:
    """andyc.load: every contact's gap and stick rows are constraint rows of the Spec (the runtime switches them)."""
    return andyc.load(path)


class Rows:
    """phi, c and A of a Spec's constraints, evaluated through andyc's kinematics and frame quantities."""

    def __init__(self, spec: Spec):
        emit = Emitter()
        kin = frame_kinematics(spec, emit)
        terms = constraint_terms(spec, FrameQuantities(spec, kin, emit))
        self.spec, self.terms = spec, terms
        self.names = terms.rows
        self.holonomic = [c.name for c in spec.constraints if c.holonomic for _ in c.rows]
        outputs = list(terms.phi) + list(terms.c) + list(terms.A)
        defs = dict(emit.assignments)
        needed, todo = set(), [s for e in outputs for s in e.free_symbols]
        while todo:
            s = todo.pop()
            if s in defs and s not in needed:
                needed.add(s)
                todo.extend(defs[s].free_symbols)
        self.inputs = ([c.q for c in spec.coordinates] + spec.speed_symbols + [s.symbol for s in spec.signals]
                       + [s for s, _ in spec.parameters.values()])
        self.steps = [(s, sp.lambdify(sorted(e.free_symbols, key=str), e, "math"), sorted(e.free_symbols, key=str))
                      for s, e in emit.assignments if s in needed]
        self.out = [(sp.lambdify(sorted(e.free_symbols, key=str), e, "math"), sorted(e.free_symbols, key=str))
                    for e in outputs]

    def module(self):
        """What tests/support/pinocchio_map.PinocchioMap reads of a generated module."""
        s = self.spec
        nq, nv = len(s.coordinates), len(s.speed_symbols)
        return types.SimpleNamespace(COORDINATES=[c.name for c in s.coordinates], SPEEDS=s.speed_names,
                                     SIGNALS=[x.name for x in s.signals], NQ=nq, NV=nv, NX=nq + nv + len(s.signals))

    def __call__(self, x):
        """(phi, c, A) at state x, the parameters at their defaults."""
        values = dict(zip(self.inputs, list(x) + [v for _, v in self.spec.parameters.values()]))
        for s, f, args in self.steps:
            values[s] = f(*(values[a] for a in args))
        out = [float(f(*(values[a] for a in args))) for f, args in self.out]
        nh, nc, nv = self.terms.nh, self.terms.nc, len(self.spec.speed_symbols)
        return np.array(out[:nh]), np.array(out[nh:nh + nc]), np.array(out[nh + nc:]).reshape(nc, nv)


def compare(rows: Rows, model, urdf, base_link, ground: dict, seed: int) -> tuple[dict, float]:
    """(contact -> its rows, the largest difference from Pinocchio over STATES random states)."""
    geom = pin.buildGeomFromUrdf(model, str(urdf), pin.GeometryType.COLLISION)
    data, gdata = model.createData(), geom.createData()
    mapping = PinocchioMap(rows.module(), model, urdf, base_link)
    rng = np.random.default_rng(seed)
    gaps = {name: i for i, name in enumerate(rows.holonomic)}
    slips = {}
    for i, name in enumerate(rows.names):
        if name.endswith("_stick"):
            slips.setdefault(name[:-len("_stick")], []).append(i)
    worst = 0.0
    for _ in range(STATES):
        x = mapping.random_state(rng)
        q, T, _ = mapping.state(x)
        v = T @ x[rows.module().NQ:rows.module().NQ + rows.module().NV]
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        pin.updateGeometryPlacements(model, data, geom, gdata)
        points = collision_points(model, geom, gdata, data)
        want = expected(model, data, points, ground)
        phi, c, A = rows(x)
        speeds = x[rows.module().NQ:rows.module().NQ + rows.module().NV]
        assert np.abs(A @ speeds - c).max() < TOL, "the rows are A v (no term without speeds)"
        for name, (gap, rate, s1, s2) in want.items():
            if name not in gaps:                # a link that does not collide
                continue
            i = gaps[name]
            got = [phi[i], c[i]] + [c[j] for j in slips.get(name, [])]
            worst = max(worst, *(abs(a - b) for a, b in zip(got, (gap, rate, s1, s2))))
    return {"gaps": gaps, "slips": slips, "points": set(points) & set(gaps)}, worst


def write_model(tmp_path, name: str, urdf_text: str | None, options: str, ground: dict) -> tuple:
    urdf = GO1
    if urdf_text is not None:
        urdf = tmp_path / f"{name}.urdf"
        urdf.write_text(urdf_text)
    path = tmp_path / f"{name}.yaml"
    path.write_text(f"name: {name}\nurdf: {{file: {urdf}, {options}}}\nground: {ground}\n")
    return path, urdf


def test_go1_feet_against_pinocchio(tmp_path, monkeypatch):
    """Go1 floating, its four foot spheres (r = 0.02) on a tilted ground with friction, its 12 joints' stops."""
    path, urdf = write_model(tmp_path, "go1", None, 'base: floating, collide: ["*_foot"], friction: 0.7, limits: true',
                             TILTED)
    # (its calves start within their limits: a stop the robot starts beyond is left out, test_joint_limit_stops)
    path.write_text(path.read_text() + "coordinates: {" + ", ".join(f"{leg}_calf_joint: {{initial: -1.5}}"
                                                                   for leg in ("FR", "FL", "RR", "RL")) + "}\n")
    spec = rows_spec(path, monkeypatch)
    rows = Rows(spec)
    model = pin.buildModelFromUrdf(str(urdf), pin.JointModelFreeFlyer())
    found, worst = compare(rows, model, urdf, "base", TILTED, seed=1)
    feet = {f"{leg}_foot_sphere" for leg in ("FR", "FL", "RR", "RL")}
    assert set(found["slips"]) == feet == found["points"] and all(len(v) == 2 for v in found["slips"].values())
    assert worst < TOL, f"gap or contact velocity differs from Pinocchio's by {worst:.2e}"
    # the stops: q - lower, upper - q with Pinocchio's limits, one pair per joint
    stops = {c.name: c.rows[0] for c in spec.constraints if c.name.endswith(("_lower", "_upper"))}
    assert len(stops) == 24
    for jid in range(2, model.njoints):
        name, iq = model.names[jid], model.joints[jid].idx_q
        qs = sp.Symbol(f"q_{name}", real=True)
        assert stops[f"{name}_lower"] - (qs - sp.Rational(repr(float(model.lowerPositionLimit[iq])))) == 0
        assert stops[f"{name}_upper"] - (sp.Rational(repr(float(model.upperPositionLimit[iq]))) - qs) == 0


def test_arm_box_sphere_cylinder_against_pinocchio(tmp_path, monkeypatch):
    """A box (8 corners), a sphere and a cylinder (2 x 8 rim points), rotated and offset in their links, on a
    2-joint arm with a skew axis; the ground tilted and raised."""
    path, urdf = write_model(tmp_path, "arm", ARM, "collide: [upper, fore], friction: 0.5, limits: false", TILTED)
    rows = Rows(rows_spec(path, monkeypatch))
    model = pin.buildModelFromUrdf(str(urdf))
    found, worst = compare(rows, model, urdf, None, TILTED, seed=2)
    assert len(found["points"]) == 8 + 1 + 16
    assert set(found["gaps"]) == found["points"] == set(found["slips"]), "every point a contact, named by the rule"
    assert worst < TOL, f"gap or contact velocity differs from Pinocchio's by {worst:.2e}"


def test_planar_friction_and_ground_tangent(tmp_path, monkeypatch):
    """ground: {tangent: ...} gives one slip per contact, along the tangent projected on the plane."""
    ground = {"normal": [0, 1, 0], "height": -0.3, "tangent": [1, 0.5, 0]}
    path, urdf = write_model(tmp_path, "arm", ARM, "collide: [fore], friction: 0.5, limits: false", ground)
    rows = Rows(rows_spec(path, monkeypatch))
    model = pin.buildModelFromUrdf(str(urdf))
    geom = pin.buildGeomFromUrdf(model, str(urdf), pin.GeometryType.COLLISION)
    data, gdata = model.createData(), geom.createData()
    rng = np.random.default_rng(3)
    for _ in range(3):
        q, v = rng.uniform(-1, 1, 2), rng.normal(size=2)
        pin.forwardKinematics(model, data, q, v)
        pin.updateFramePlacements(model, data)
        pin.updateGeometryPlacements(model, data, geom, gdata)
        points = collision_points(model, geom, gdata, data)
        phi, c, _ = rows(np.concatenate([q, v]))
        n, h = np.array([0.0, 1.0, 0.0]), -0.3
        assert {name for name in points if name in rows.holonomic} == {"fore_0_sphere"} | {
            f"fore_1_rim_{e}_{k}" for e in "pm" for k in range(RIM)}
        for name, (p, r, frame) in points.items():
            if not name.startswith("fore"):
                continue
            motion = pin.getFrameVelocity(model, data, frame, pin.LOCAL_WORLD_ALIGNED)
            vc = motion.linear + np.cross(motion.angular, p - data.oMf[frame].translation - r * n)
            i = rows.holonomic.index(name)
            j = rows.names.index(f"{name}_stick")
            assert abs(phi[i] - (n.dot(p) - r - h)) < TOL and abs(c[j] - vc[0]) < TOL


# -- joint limits ------------------------------------------------------------------------

def test_joint_limit_stops(tmp_path):
    urdf = tmp_path / "stops.urdf"
    urdf.write_text(STOPS)
    (tmp_path / "on.yaml").write_text("urdf: {file: stops.urdf, limits: true}\ncoordinates: {slide: {initial: 0.1}}\n")
    spec = andyc.load(tmp_path / "on.yaml")
    q = {c.name: c.q for c in spec.coordinates}
    rows = {c.name: c.rows[0] for c in spec.constraints}
    assert rows == {"hinge_lower": q["hinge"] + sp.Rational(3, 4), "hinge_upper": sp.Rational(5, 4) - q["hinge"],
                    "slide_lower": q["slide"] - sp.Rational(1, 20), "slide_upper": sp.Rational(3, 10) - q["slide"],
                    "tilt_upper": sp.Rational(2, 5) - q["tilt"]}, "none for continuous, mimic, or a side not written"
    assert [c.name for c in spec.contacts] == list(rows)
    assert all(c.friction is None and c.restitution == 0 for c in spec.contacts)
    assert [c.where[0] for c in spec.constraints] == ["contacts"] * 5
    assert spec.source.line(spec.constraints[0].where) == line_of(STOPS, 'lower="-0.75"')
    unused = next(str(w) for w in spec.warnings if "not used by andyc" in str(w))
    assert "<limit effort>" in unused and "<limit velocity>" in unused and "<joint><limit>" not in unused
    (tmp_path / "off.yaml").write_text("urdf: {file: stops.urdf, limits: false}\n")
    off = andyc.load(tmp_path / "off.yaml")
    assert not off.contacts and not off.constraints
    assert "<joint><limit>" in next(str(w) for w in off.warnings if "not used by andyc" in str(w))
    (tmp_path / "locked.yaml").write_text("urdf: {file: stops.urdf, lock: {slide: 0.1}}\n")
    assert "slide_lower" not in {c.name for c in andyc.load(tmp_path / "locked.yaml").contacts}
    # starting at 0, below its lower limit 0.05, the slide's lower stop is left out (it would start the run inside
    # the limit's wall), with a warning at its <limit> naming the joint and the fix
    (tmp_path / "beyond.yaml").write_text("urdf: {file: stops.urdf}\n")
    beyond = andyc.load(tmp_path / "beyond.yaml")
    assert {c.name for c in beyond.contacts} == set(rows) - {"slide_lower"}
    warning = next(w for w in beyond.warnings if "beyond its lower limit" in w.message)
    assert warning.line == line_of(STOPS, 'lower="0.05"') and warning.message == (
        "joint 'slide' starts at 0, beyond its lower limit 0.05: its stop 'slide_lower' is left out")
    assert warning.hint.startswith("give 'slide' an initial value within its limits to keep the stop")


def test_limits_default_is_stops(tmp_path):
    from andyc.spec import urdf

    urdf_file = tmp_path / "stops.urdf"
    urdf_file.write_text(STOPS)
    (tmp_path / "plain.yaml").write_text("urdf: {file: stops.urdf}\ncoordinates: {slide: {initial: 0.1}}\n")
    names = {c.name for c in andyc.load(tmp_path / "plain.yaml").contacts}
    assert names == ({"hinge_lower", "hinge_upper", "slide_lower", "slide_upper", "tilt_upper"}
                     if urdf.LIMITS_DEFAULT else set())


def test_lower_not_below_upper_is_warned(tmp_path):
    urdf = tmp_path / "stops.urdf"
    urdf.write_text(STOPS.replace('lower="0.05" upper="0.3"', 'lower="0.3" upper="0.3"'))
    (tmp_path / "m.yaml").write_text("urdf: {file: stops.urdf, limits: true}\n")
    spec = andyc.load(tmp_path / "m.yaml")
    assert not {"slide_lower", "slide_upper"} & {c.name for c in spec.contacts}
    warning = next(w for w in spec.warnings if "lower not below upper" in w.message)
    assert warning.line == line_of(urdf.read_text(), 'lower="0.3"') and "slide" in warning.message


# -- YAML shapes ---------------------------------------------------------------------------

BALL = """name: ball
parameters: {m: 1.0, mu: 0.4, e: 0.5}
speeds: {vx: {}, vy: {}, vz: {}, wx: {}, wy: {}, wz: {}}
gravity: [0, 0, -9.81]
ground: {normal: [0, 0, 1], height: 0}
frames:
  - name: ball
    parent: world
    floating: {speeds: [vx, vy, vz, wx, wy, wz], position: [0, 0, 0.1], in: parent}
    shape: {sphere: {radius: 0.1}, collide: true, friction: mu, restitution: e}
bodies:
  - {name: b, frame: ball, mass: m, inertia: [0.004, 0.004, 0.004]}
"""

BALL_BY_HAND = BALL.replace(", collide: true, friction: mu, restitution: e", "") + """contacts:
  - {name: ball_sphere, gap: ball.z - 0.1, slip: [ball.vx - 0.1*ball.wy, ball.vy + 0.1*ball.wx], friction: mu,
     restitution: e}
"""


def test_yaml_shape_gives_the_hand_written_contact(tmp_path):
    (tmp_path / "shape.yaml").write_text(BALL)
    (tmp_path / "hand.yaml").write_text(BALL_BY_HAND)
    made, hand = andyc.load(tmp_path / "shape.yaml"), andyc.load(tmp_path / "hand.yaml")
    assert [(c.name, c.holonomic, c.rows, c.multipliers) for c in made.constraints] == \
        [(c.name, c.holonomic, c.rows, c.multipliers) for c in hand.constraints]
    assert [(c.name, c.friction, c.restitution, c.tangents) for c in made.contacts] == \
        [(c.name, c.friction, c.restitution, c.tangents) for c in hand.contacts]
    assert [f.name for f in made.flows] == [f.name for f in hand.flows]
    assert made.source.line(made.contacts[0].where) == line_of(BALL, "collide: true")


def test_yaml_box_capsule_cylinder_points(tmp_path, monkeypatch):
    """A body's box placed by xyz and rpy, a capsule along x and a cylinder along y on a frame: their points'
    world positions and rows from andyc's kinematics against the shape rule written out here."""
    text = """name: shapes
coordinates: {a: {initial: 0.3}}
ground: {normal: [0, 0, 1], height: 0.1}
frames:
  - name: arm
    parent: world
    revolute: a
    axis: [0.6, 0, 0.8]
    shape:
      - {capsule: {radius: 0.05, length: 0.4, axis: x}, xyz: [0.2, 0, 0.5], collide: true}
      - {cylinder: {radius: 0.1, length: 0.3, axis: y}, xyz: [0, 0.3, 0.4], rpy: [0.3, 0, 0], collide: true}
bodies:
  - {name: slab, frame: arm, mass: 1, shape: {box: {size: [0.2, 0.4, 0.1]}, xyz: [0.1, 0, 0.6],
     rpy: [0.1, "pi/6", 0.2], collide: true}}
"""
    path = tmp_path / "shapes.yaml"
    path.write_text(text)
    spec = rows_spec(path, monkeypatch)
    rows = Rows(spec)
    x = np.array([0.7, 1.3])
    phi, c, _ = rows(x)
    axis = np.array([0.6, 0, 0.8])
    R = _rotation(axis, 0.7)
    w = axis * 1.3

    def check(name, local, r=0.0):
        p = R @ local
        i = rows.holonomic.index(name)
        assert abs(phi[i] - (p[2] - r - 0.1)) < TOL and abs(c[i] - np.cross(w, p)[2]) < TOL, name

    check("arm_0_end_p", np.array([0.4, 0, 0.5]), 0.05)
    check("arm_0_end_m", np.array([0.0, 0, 0.5]), 0.05)
    Rc = _rotation(np.array([1.0, 0, 0]), 0.3)
    for k in range(RIM):
        a = 2 * math.pi * k / RIM
        # axis y: e1 = x, e2 = y x x = -z
        rim = 0.1 * (math.cos(a) * np.array([1.0, 0, 0]) + math.sin(a) * np.array([0, 0, -1.0]))
        for end, sign in (("p", 1), ("m", -1)):
            check(f"arm_1_rim_{end}_{k}", np.array([0, 0.3, 0.4]) + Rc @ (rim + sign * np.array([0, 0.15, 0])))
    Rb = _rotation(np.array([0, 0, 1.0]), 0.2) @ _rotation(np.array([0, 1.0, 0]), math.pi / 6) \
        @ _rotation(np.array([1.0, 0, 0]), 0.1)
    for sx in (1, -1):
        for sy in (1, -1):
            for sz in (1, -1):
                name = "".join("p" if s > 0 else "m" for s in (sx, sy, sz))
                check(f"slab_corner_{name}", np.array([0.1, 0, 0.6]) + Rb @ (np.array([sx, sy, sz]) * [0.1, 0.2, 0.05]))
    assert len(rows.holonomic) == 2 + 16 + 8


def _rotation(axis, angle) -> np.ndarray:
    a = axis / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


# -- bad input: one located line each ----------------------------------------------------

@pytest.mark.parametrize("old, new, needle, path", [
    ("ground: {normal: [0, 0, 1], height: 0}", "ground: {normal: [0, 0, 0], height: 0}", "ground:",
     "ground.normal"),
    ("ground: {normal: [0, 0, 1], height: 0}", "ground: {normal: [0, 0, 1], height: .inf}", "ground:",
     "ground.height"),
    ("ground: {normal: [0, 0, 1], height: 0}", "ground: {normal: [0, 0, 1], tangent: [0, 0, 2]}", "ground:",
     "ground.tangent"),
    ("ground: {normal: [0, 0, 1], height: 0}\n", "", "collide: true", "frames[0].shape.collide"),
    ("sphere: {radius: 0.1}", "sphere: {radius: 2*m}", "collide: true", "frames[0].shape.sphere.radius"),
    ("friction: mu, restitution: e", "friction: -mu, restitution: e", "collide: true", "frames[0].shape.friction"),
    ("restitution: e}", "restitution: 1.5}", "collide: true", "frames[0].shape.restitution"),
    ("collide: true, friction: mu, restitution: e", "collide: false, friction: mu", "collide: false",
     "frames[0].shape.friction"),
])
def test_bad_ground_and_shapes(tmp_path, old, new, needle, path):
    text = BALL.replace(old, new)
    assert text != BALL
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, needle), path)


def test_a_box_with_negative_friction_is_one_problem(tmp_path):
    """Eight corners share the shape's friction: its problem is reported once, at the shape."""
    text = BALL.replace("sphere: {radius: 0.1}", "box: {size: [0.2, 0.2, 0.2]}").replace("friction: mu",
                                                                                         "friction: -1")
    found = problems(tmp_path, text)
    assert len({str(d) for d in found}) == len(found)
    negative = [d for d in found if "negative" in d.message]
    assert len(negative) == 1
    assert_at(negative[0], line_of(text, "collide: true"), "frames[0].shape.friction")


def test_a_generated_name_that_clashes_is_located_at_its_shape(tmp_path):
    text = BALL.replace("bodies:", "  - {name: ball_sphere, parent: ball}\nbodies:")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "collide: true"), "frames[0].shape")
    assert "duplicate name 'ball_sphere'" in d.message


def test_a_colliding_mesh_is_refused(tmp_path):
    (tmp_path / "tri.stl").write_text("solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n"
                                      "vertex 0 1 0\nendloop\nendfacet\nendsolid t\n")
    text = BALL.replace("sphere: {radius: 0.1}", "mesh: {file: tri.stl}")
    d = one_problem(tmp_path, text)
    assert_at(d, line_of(text, "collide: true"), "frames[0].shape.collide")


def urdf_problems(tmp_path, options: str, ground: str = "ground: {}", urdf_text: str = ARM) -> list:
    (tmp_path / "arm.urdf").write_text(urdf_text)
    text = f"name: arm\nurdf:\n  file: arm.urdf\n  limits: false\n{options}\n{ground}\n"
    (tmp_path / "model.yaml").write_text(text)
    with pytest.raises(SpecError) as info:
        andyc.load(tmp_path / "model.yaml")
    for d in info.value.diagnostics:
        assert LINE_FORMAT.match(str(d)) and d.hint and "\n" not in str(d), d
    return text, info.value.diagnostics


@pytest.mark.parametrize("options, ground, needle, path", [
    ("  collide: [uper]", "ground: {}", "collide:", "urdf.collide[0]"),
    ("  collide: ['*_foot']", "ground: {}", "collide:", "urdf.collide[0]"),
    ("  collide: [base]", "ground: {}", "collide:", "urdf.collide[0]"),
    ("  collide: [upper]", "", "collide:", "urdf.collide"),
    ("  friction: 0.5", "ground: {}", "friction:", "urdf.friction"),
    ("  collide: [fore]\n  friction: -0.5", "ground: {}", "friction:", "urdf.friction"),
    ("  collide: [fore]\n  restitution: 2", "ground: {}", "restitution:", "urdf.restitution"),
    ("  collide: [upper]", "ground: {normal: [0, 0, 0]}", "ground:", "ground.normal"),
])
def test_bad_urdf_options(tmp_path, options, ground, needle, path):
    text, found = urdf_problems(tmp_path, options, ground, SPHERE_ARM)
    assert len(found) == 1, found
    assert found[0].file == str(tmp_path / "model.yaml")
    assert_at(found[0], line_of(text, needle), path)


def test_bad_collision_sizes_and_limits_are_located_in_the_urdf(tmp_path):
    bad = ARM.replace('<sphere radius="0.05"/>', '<sphere radius="-0.05"/>')
    text, found = urdf_problems(tmp_path, "  collide: [fore]", urdf_text=bad)
    assert len(found) == 1 and found[0].file == str(tmp_path / "arm.urdf")
    assert found[0].line == line_of(bad, 'radius="-0.05"') and "not positive" in found[0].message
    bad = ARM.replace('lower="-1.5"', 'lower="low"')
    (tmp_path / "arm.urdf").write_text(bad)
    (tmp_path / "m.yaml").write_text("urdf: {file: arm.urdf, limits: true}\n")
    with pytest.raises(SpecError) as info:
        andyc.load(tmp_path / "m.yaml")
    assert [(d.file, d.line, d.path) for d in info.value.diagnostics] == \
        [(str(tmp_path / "arm.urdf"), line_of(bad, 'lower="low"'), "joint[shoulder].limit.lower")]


def test_collision_mesh_is_warned_with_its_link(tmp_path, monkeypatch):
    meshed = ARM.replace('<geometry><sphere radius="0.05"/></geometry>',
                         '<geometry><mesh filename="hand.stl"/></geometry>')
    (tmp_path / "arm.urdf").write_text(meshed)
    (tmp_path / "m.yaml").write_text("urdf: {file: arm.urdf, collide: [fore], limits: false}\nground: {}\n")
    spec = rows_spec(tmp_path / "m.yaml", monkeypatch)
    warning = next(w for w in spec.warnings if "collision mesh" in w.message)
    assert "fore" in warning.message and warning.line == line_of(meshed, "hand.stl")
    assert {c.name for c in spec.constraints if c.holonomic} == {f"fore_1_rim_{e}_{k}" for e in "pm" for k in range(8)}


def test_a_ground_nothing_touches_is_warned(tmp_path):
    text = BALL.replace(", collide: true, friction: mu, restitution: e", "")
    (tmp_path / "m.yaml").write_text(text)
    spec = andyc.load(tmp_path / "m.yaml")
    warning = next(w for w in spec.warnings if "nothing collides" in w.message)
    assert (warning.line, warning.path) == (line_of(text, "ground:"), "ground")


def test_generated_names_that_clash_in_a_urdf_are_located_there(tmp_path):
    """Link 'fore' has two <collision>s (fore_0_..., fore_1_...); a link named 'fore_0' with a sphere makes
    'fore_0_sphere' again."""
    clash = ARM.replace("</robot>", """  <joint name="tip" type="fixed"><parent link="fore"/><child link="fore_0"/></joint>
  <link name="fore_0"><collision><geometry><sphere radius="0.01"/></geometry></collision></link>
</robot>""")
    text, found = urdf_problems(tmp_path, "  collide: [fore, fore_0]\n  friction: 0.5", urdf_text=clash)
    assert len(found) == 1 and found[0].file == str(tmp_path / "arm.urdf")
    assert found[0].line == line_of(clash, '<link name="fore_0">')
    assert "the name 'fore_0_sphere' is also made from link[fore].collision" in found[0].message
