"""The Spec: a validated model, every name resolved, every expression SymPy.

The loader (`andyc.spec.load`) produces it from YAML; later stages read it and
never look at the YAML again. Document paths (`where`) are kept so later
stages can still point at the line a problem comes from.

A frame's link is a sequence of elementary transforms, applied left to
right (each in the frame produced by the previous one):

    Translate(p)          origin moves by p(q, t)
    Rotate(axis, angle)   rotation by angle(q, t) about a fixed unit axis
    Nonholonomic(...)     motion given by velocities (paper eq. 4); last if present

Every holonomic link kind of the spec (fixed translation, axis-angle,
roll-pitch-yaw, quaternion, Denavit-Hartenberg, revolute, prismatic) lowers to
the first two; ball, floating and nonholonomic links lower to the third.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from andyc.numerics.status import EITHER, FALLING, RISING  # noqa: F401  (the one table of guard directions)

ANY = "*"           # a contact's jump goes from and to every flow (andyc.spec.contacts)
from andyc.spec.yamlpos import SourceMap


@dataclass(frozen=True)
class Translate:
    vector: sp.Matrix           # 3x1, expression of q, t, parameters


@dataclass(frozen=True)
class Rotate:
    axis: sp.Matrix             # 3x1 unit vector, constant
    angle: sp.Expr              # expression of q, t, parameters


@dataclass(frozen=True)
class Nonholonomic:
    """A link whose velocity is given, not its position (ANDY paper eq. 4).

    Its position and rotation are signals integrated alongside the dynamics:
    sigma_r' = v and quat' = 1/2 quat (x) [0, w] (w in the link's own axes) or
    1/2 [0, w] (x) quat (w in the reference axes). The reference axes are the
    parent's, turned by any fixed translation/rotation written before the link.
    """
    velocity: sp.Matrix | None          # 3x1, linear in the speeds, or None (no translation)
    angular_velocity: sp.Matrix | None  # 3x1, linear in the speeds, or None (no rotation)
    in_body: bool                       # velocities written in the link's own axes
    position: tuple | None              # 3 signal symbols sigma_r
    quaternion: tuple | None            # 4 signal symbols (w, x, y, z)


@dataclass(frozen=True)
class Signal:
    """A nonholonomic signal: a state with its own first-order ODE (eq. 4)."""
    name: str                   # state name, e.g. ball_qw
    component: str              # x, y, z (position) or qw, qx, qy, qz (quaternion)
    symbol: sp.Symbol
    initial: sp.Expr            # expression of parameters
    frame: str                  # the frame whose link it belongs to
    where: tuple


@dataclass(frozen=True)
class Speed:
    """A quasi-velocity: a speed that is not the rate of any coordinate."""
    name: str
    v: sp.Symbol
    initial: sp.Expr
    where: tuple


@dataclass(frozen=True)
class Coordinate:
    name: str
    q: sp.Symbol                # position symbol
    v: sp.Symbol                # speed symbol (dq/dt)
    initial: sp.Expr            # expression of parameters
    velocity: sp.Expr
    where: tuple


@dataclass(frozen=True)
class Frame:
    name: str
    parent: str
    transforms: tuple           # of Translate / Rotate
    where: tuple
    internal: bool = False      # made by andyc (a COM or point offset), not by the user
    joint: str = "fixed"        # the link's joint as written: fixed, dh, revolute, prismatic, ball, floating, nonholonomic


@dataclass(frozen=True)
class Body:
    name: str
    frame: str                  # frame whose origin is the COM
    mass: sp.Expr
    inertia: sp.Matrix          # 3x3 about the COM, in `frame` axes
    where: tuple


@dataclass(frozen=True)
class Load:
    """A force (acting at the origin of `frame`) or a torque (on `frame`)."""
    name: str
    kind: str                   # "force" | "torque"
    frame: str
    vector: sp.Matrix           # 3x1 in the axes of `in_frame`
    in_frame: str
    where: tuple


@dataclass(frozen=True)
class Damper:
    name: str
    coefficient: sp.Expr
    law: str                    # "linear" | "quadratic" | "coulomb" (dry friction of magnitude coefficient)
    speed: str | None           # coordinate name, or
    frame: str | None           # frame whose velocity is damped
    angular: bool
    where: tuple


@dataclass(frozen=True)
class Actuator:
    """A generalized force on one speed (a coordinate's rate or a declared speed): `force`, clamped to
    [-limit, limit] when `limit` is not None; its virtual power force * speed."""
    name: str
    speed: str                  # coordinate name (its rate) or declared speed name
    force: sp.Expr
    limit: sp.Expr | None
    where: tuple


@dataclass(frozen=True)
class Spring:
    name: str
    stiffness: sp.Expr
    rest_length: sp.Expr
    length: sp.Expr | None      # expression of q, t, or
    between: tuple | None       # two frame names
    where: tuple


@dataclass(frozen=True)
class Potential:
    name: str
    energy: sp.Expr
    where: tuple


@dataclass(frozen=True)
class FrameQuantity:
    """A frame quantity a constraint uses, e.g. `tip.x`: its symbol stands for

        x, y, z     R_F^T (r_A - r_F)   the origin of A from F's origin, in F's axes
        vx, vy, vz  R_F^T v_A           the velocity of A's origin (in world), in F's axes
        wx, wy, wz  R_F^T w_A           the angular velocity of A (in world), in F's axes

    with F the constraint's `in` frame (world by default).
    """
    frame: str                  # A
    kind: str                   # "position" | "velocity" | "angular_velocity"
    axis: int                   # 0, 1, 2
    in_frame: str               # F


@dataclass(frozen=True)
class Constraint:
    """Holonomic rows Gamma(t, q) = 0 or nonholonomic rows Phi_v(t, q, v) = 0 (ANDY eq. 10-15; Braun & Goldfarb
    §2, item c), each nonholonomic row either linear in the speeds, J(t, q) v + b = 0, or not (`nonlinear`)."""
    name: str
    holonomic: bool
    rows: tuple                 # of sp.Expr in q, v, t, parameters and FrameQuantity symbols
    multipliers: tuple          # one name per row
    stiffness: sp.Expr          # K_s (holonomic only), expression of parameters
    damping: sp.Expr            # K_d
    quantities: dict            # symbol -> FrameQuantity, for the symbols the rows use
    where: tuple
    row_where: tuple = ()       # document path of each row
    nonlinear: tuple = ()       # indices of the nonholonomic rows that are not linear in the speeds


@dataclass(frozen=True)
class DiscreteState:
    """A value constant during a flow that jumps may reset (ANDY's sigma, e.g. a foot's contact point)."""
    name: str
    symbol: sp.Symbol
    initial: sp.Expr            # expression of parameters
    where: tuple


@dataclass(frozen=True)
class Flow:
    """A node of the hybrid automaton: the constraints active in it and its own input values."""
    name: str
    constraints: tuple          # names, in the order of Spec.constraints
    inputs: dict                # input name -> expression of parameters
    where: tuple


@dataclass(frozen=True)
class Jump:
    """An edge of the hybrid automaton (ANDY eq. 16): guard, impact map and resets.

    The jump happens where `guard` crosses zero in `direction` (FALLING: from
    positive to zero or below) while every `enabled` expression is >= 0.
    Then, in this order: the resets (simultaneous, from the values before the
    jump), the impact map over the rows of `impact_constraints` with
    restitution e (J v+ = -e J v-; e = 0 is ANDY eq. 19), the user's function
    in <name>_jumps.py.
    """
    name: str
    source: str                 # flow names
    target: str
    guard: sp.Expr
    direction: int              # FALLING, EITHER or RISING
    enabled: tuple              # of sp.Expr, each must be >= 0
    impact: str                 # "none" | "plastic" | "restitution"
    restitution: sp.Expr        # e, expression of parameters (0 when plastic)
    impact_constraints: tuple   # constraint names whose rows take the impact
    resets: tuple               # of (state or discrete-state name, sp.Expr)
    priority: int
    quantities: dict            # symbol -> FrameQuantity used by guard, enabled and resets
    where: tuple
    text: dict = field(default_factory=dict)        # guard, enabled, reset, impact as the model file writes them
    multipliers: dict = field(default_factory=dict)  # multiplier symbol -> its name, used by guard or enabled
    contact: int = -1           # the contact whose jump this is (andyc.spec.contacts), -1 for the user's
    kind: str = ""              # "impact" | "liftoff" | "slip" | "stop" for a contact's jump, "" for the user's
    mode: tuple = ()            # a contact's jump: (its mode's discrete state, the mask of the modes it leaves)


@dataclass
class Spec:
    name: str
    description: str
    file: str
    sha256: str                 # of the source file's bytes
    source: SourceMap
    parameters: dict            # name -> (symbol, default float)
    inputs: dict                # name -> (symbol, default float)
    coordinates: list           # of Coordinate, in declaration order
    speeds: list                # of Speed (quasi-velocities), in declaration order
    signals: list               # of Signal, in frame order; quaternions as 4 consecutive entries
    gravity: sp.Matrix          # 3x1 in world
    frames: list                # of Frame, parents before children
    bodies: list = field(default_factory=list)
    loads: list = field(default_factory=list)
    actuators: list = field(default_factory=list)
    dampers: list = field(default_factory=list)
    springs: list = field(default_factory=list)
    potentials: list = field(default_factory=list)
    constraints: list = field(default_factory=list)  # of Constraint, holonomic ones first
    conserves_energy: bool = False
    discrete: list = field(default_factory=list)       # of DiscreteState
    flows: list = field(default_factory=list)          # of Flow; one "default" flow without a hybrid section
    jumps: list = field(default_factory=list)          # of Jump, in document order
    initial_flow: int = 0
    contacts: list = field(default_factory=list)       # of andyc.spec.contacts.Contact (their jumps end `jumps`)
    warnings: list = field(default_factory=list)   # of Diagnostic
    visuals: list = field(default_factory=list)    # URDF visual geometry, as read (andyc.spec.urdf)
    shapes: list = field(default_factory=list)     # the YAML's shape: keys, for andyc view (andyc.spec.shapes)
    ground: object = None       # the YAML's ground: plane (andyc.spec.geometry.Ground), or None
    locked: tuple = ()          # URDF joints held at given values (urdf: {lock: ...}), by their URDF name
    reduce: bool = False        # merge the bodies fixed to one moving frame before deriving (andyc.symbolic.reduce)
    input_expressions: dict = field(default_factory=dict)  # input name -> the expression text that drives it
    driven_inputs: dict = field(default_factory=dict)  # input name -> that expression, parsed (sp.Expr)
    meaning_sha256: str = ""    # what shapes the equations (andyc.spec.meaning): the build key's part
    files: tuple = ()           # the files the model was read from (the model file; a URDF it names)
    closed_form: dict = field(default_factory=dict)  # state name -> x_i(t) of t, parameters and held inputs
    simulate: dict = field(default_factory=dict)     # andyc sim's options the model gives (andyc.spec.simulate)
    expect: list = field(default_factory=list)       # of Expectation (andyc.spec.expect), for andyc test
    energy_laws: tuple = ()     # per flow: its energy law (andyc.spec.energy_law.EnergyLaw), or None: the built-in

    @property
    def speed_symbols(self) -> list:
        """All speeds v: coordinate rates first, then quasi-velocities."""
        return [c.v for c in self.coordinates] + [s.v for s in self.speeds]

    @property
    def speed_names(self) -> list:
        return [f"{c.name}_dot" for c in self.coordinates] + [s.name for s in self.speeds]

    @property
    def joint_frictions(self) -> list:
        """The dampers of law coulomb: dry friction on one speed, which the moreau method's contact problem
        applies (andyc.numerics.contact_solver's bounded rows); the smooth equations leave them out."""
        return [d for d in self.dampers if d.law == "coulomb"]

    def parameter_values(self) -> dict:
        return {name: value for name, (_, value) in self.parameters.items()}
