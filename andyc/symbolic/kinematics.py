"""Recursive kinematics of the frame tree (ANDY paper, eq. 1-3).

For each frame k, in world coordinates, with speeds v (dq/dt for ordinary
coordinates):

    R_k   rotation frame k -> world          r_k   origin position
    w_k   angular velocity                   v_k   origin velocity
    Jw_k  3 x n, w_k = Jw_k v + (explicit-time part)
    Jv_k  3 x n, v_k = Jv_k v + (explicit-time part)
    al_k  angular acceleration at dv/dt = 0 (Jw_k' v + ...)
    ac_k  origin acceleration at dv/dt = 0 (Jv_k' v + ...)

A link gives, in its parent's axes, R_rel, p_rel and the relative velocities
w_rel, v_rel and their Jacobians; from a parent P, with d = R_P p_rel:

    R_k  = R_P R_rel                      r_k  = r_P + d
    w_k  = w_P + R_P w_rel                v_k  = v_P + w_P x d + R_P v_rel
    Jw_k = Jw_P + R_P Jw_rel                                          (eq. 3)
    Jv_k = Jv_P + Jw_P x d + R_P Jv_rel   (column by column)          (eq. 2)
    al_k = al_P + R_P al_rel + w_P x (R_P w_rel)                      (eq. 1)
    ac_k = ac_P + al_P x d + w_P x (w_P x d) + 2 w_P x (R_P v_rel) + R_P ac_rel

The relative terms are derivatives of the link's own small expressions, so
nothing large is ever differentiated.

Bodies use the angular quantities in their own axes (as Pinocchio's local
frame): wb_k = R_k^T w_k, Jwb_k, alb_k. With R_rel the link rotation and
w_own = R_rel^T w_rel (the link's angular velocity in its own axes, formed
step by step so that a joint's axis stays a constant), al_own = d/dt w_own:

    Jwb_k = R_rel^T Jwb_P + Jw_own      wb_k = R_rel^T wb_P + w_own
    alb_k = R_rel^T alb_P + al_own + (R_rel^T wb_P) x w_own

A ball joint's speeds then enter its body's Jacobian as the identity.

Speeds v are the coordinate rates dq/dt first, then quasi-velocities. A
nonholonomic link (paper eq. 4) has no position expression to differentiate:
its relative velocities are given, linear in v, and its rotation Q and
position are signals. With w_g, v_g as written (rates at dv/dt = 0: w_g', v_g'):

    in the reference axes   w_rel = w_g     v_rel = v_g     al_rel = w_g'   ac_rel = v_g'
    in the link's own axes  w_rel = Q w_g   v_rel = Q v_g   al_rel = Q w_g'
                            ac_rel = Q (w_g x v_g + v_g')   (since Q' = Q [w_g]x)

and the signals follow sigma_r' = v_rel and quat' = 1/2 quat (x) [0, w_g]
(own axes) or 1/2 [0, w_g] (x) quat (reference axes). Q is written so that it
is a rotation for any nonzero quat, so a drift of |quat| never reaches the
dynamics (the runtime also renormalizes after each step).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from andyc.spec.expressions import TIME
from andyc.spec.model import Nonholonomic, Rotate, Spec, Translate
from andyc.symbolic.emitter import Emitter


@dataclass
class FrameKinematics:
    index: int
    R: sp.Matrix
    r: sp.Matrix
    w: sp.Matrix
    v: sp.Matrix
    Jw: sp.Matrix
    Jv: sp.Matrix
    al: sp.Matrix
    ac: sp.Matrix
    wb: sp.Matrix               # angular velocity, own axes
    Jwb: sp.Matrix              # 3 x n, own axes
    alb: sp.Matrix              # angular acceleration at dv/dt = 0, own axes
    signal_rates: dict = field(default_factory=dict)   # signal symbol -> its rate (eq. 4)


def rotation_matrix(axis: sp.Matrix, angle) -> sp.Matrix:
    """Rodrigues: R = I + sin(a) [k]x + (1 - cos(a)) [k]x^2 for a unit axis k."""
    k = skew(axis)
    return sp.eye(3) + sp.sin(angle) * k + (1 - sp.cos(angle)) * (k * k)


def skew(a: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def quaternion_matrix(w, x, y, z, two_over_norm2) -> sp.Matrix:
    """Rotation matrix of the quaternion (w, x, y, z), exact for any norm: s = 2 / |quat|^2."""
    s = two_over_norm2
    return sp.Matrix([[1 - s * (y * y + z * z), s * (x * y - w * z), s * (x * z + w * y)],
                      [s * (x * y + w * z), 1 - s * (x * x + z * z), s * (y * z - w * x)],
                      [s * (x * z - w * y), s * (y * z + w * x), 1 - s * (x * x + y * y)]])


def _rate(expr, q, v):
    """Total time derivative of expr(q, v, t) with dv/dt = 0 (dq/dt is the first len(q) speeds). Only the
    coordinates expr holds are differentiated by (the others give zero terms): a frame's few, not the model's."""
    held = expr.free_symbols
    return sum((sp.diff(expr, qi) * vi for qi, vi in zip(q, v) if qi in held), sp.diff(expr, TIME))


def _by_coordinates(expr, q) -> list:
    """d expr / dq_j for each coordinate, zero (without differentiating) for those expr does not hold."""
    held = expr.free_symbols
    return [sp.diff(expr, qj) if qj in held else sp.S.Zero for qj in q]


@dataclass
class LinkMotion:
    """A link's motion relative to its parent: in the parent's axes, and angular in its own."""
    R: sp.Matrix        # rotation, own axes -> parent axes
    p: sp.Matrix        # origin position
    Jw: sp.Matrix       # 3 x n
    Jv: sp.Matrix       # 3 x n
    w: sp.Matrix
    v: sp.Matrix
    al: sp.Matrix       # dw/dt at dv/dt = 0
    ac: sp.Matrix       # dv/dt at dv/dt = 0
    Jw_own: sp.Matrix   # R^T Jw
    w_own: sp.Matrix    # R^T w
    al_own: sp.Matrix   # R^T al = d/dt (R^T w)


def link_pose(transforms) -> tuple[sp.Matrix, sp.Matrix]:
    """R and p of a link of Translate and Rotate steps, as link_motion finds them, without its motion (a fixed
    link's: its Jacobians would be 3 x n zeros, work per speed of the model for each fixed frame)."""
    R, p = sp.eye(3), sp.zeros(3, 1)
    for step in transforms:
        if isinstance(step, Translate):
            p = p + R * step.vector
        else:
            R = R * rotation_matrix(step.axis, step.angle)
    return R, p


def link_motion(transforms, q, v) -> LinkMotion:
    """Relative motion of a holonomic link (its Translate and Rotate steps)."""
    n = len(v)
    R = sp.eye(3)
    p = sp.zeros(3, 1)
    Jw = sp.zeros(3, n)
    w_t = sp.zeros(3, 1)            # explicit-time part of w
    Jw_own = sp.zeros(3, n)         # the same, in the axes reached so far
    w_t_own = sp.zeros(3, 1)
    for step in transforms:
        if isinstance(step, Translate):
            p = p + R * step.vector
            continue
        rate = sp.Matrix([_by_coordinates(step.angle, q) + [0] * (n - len(q))])
        axis = R * step.axis
        Jw += axis * rate
        w_t += axis * sp.diff(step.angle, TIME)
        turn = rotation_matrix(step.axis, step.angle)
        # A rotation leaves its own axis fixed, so this axis enters as a constant.
        Jw_own = turn.T * Jw_own + step.axis * rate
        w_t_own = turn.T * w_t_own + step.axis * sp.diff(step.angle, TIME)
        R = R * turn
    columns = [_by_coordinates(e, q) for e in p]
    Jv = sp.Matrix.from_dok(3, n, {(i, j): e for i, row in enumerate(columns) for j, e in enumerate(row) if e != 0})
    vvec = sp.Matrix(v)
    w_rel = Jw * vvec + w_t
    v_rel = Jv * vvec + sp.diff(p, TIME)
    w_own = Jw_own * vvec + w_t_own

    def rate(vec):
        return vec.applyfunc(lambda e: _rate(e, q, v))

    return LinkMotion(R, p, Jw, Jv, w_rel, v_rel, rate(w_rel), rate(v_rel), Jw_own, w_own, rate(w_own))


def nonholonomic_motion(step: Nonholonomic, q, v, emit: Emitter, label: str):
    """Relative motion of a nonholonomic link (eq. 4) and the rates of its signals."""
    zero = sp.zeros(3, 1)
    Q = sp.eye(3)
    if step.quaternion:
        w, x, y, z = step.quaternion
        s = emit.scalar(f"{label}n", 2 / (w * w + x * x + y * y + z * z))
        Q = emit.matrix(f"{label}Q", quaternion_matrix(w, x, y, z, s))
    p = sp.Matrix(step.position) if step.position else zero
    w_g = step.angular_velocity if step.angular_velocity is not None else zero
    v_g = step.velocity if step.velocity is not None else zero
    Jw_g, Jv_g = w_g.jacobian(v), v_g.jacobian(v)
    al_g = w_g.applyfunc(lambda e: _rate(e, q, v))
    ac_g = v_g.applyfunc(lambda e: _rate(e, q, v))
    if step.in_body:
        motion = LinkMotion(Q, p, Q * Jw_g, Q * Jv_g, Q * w_g, Q * v_g, Q * al_g, Q * (cross(w_g, v_g) + ac_g),
                            Jw_g, w_g, al_g)
    else:
        motion = LinkMotion(Q, p, Jw_g, Jv_g, w_g, v_g, al_g, ac_g, Q.T * Jw_g, Q.T * w_g, Q.T * al_g)
    rates = {}
    if step.position:
        rates.update(zip(step.position, motion.v))
    if step.quaternion:
        qw, qv = step.quaternion[0], sp.Matrix(step.quaternion[1:])
        # Hamilton product: quat (x) [0, w] = (-qv.w, qw w + qv x w); [0, w] (x) quat = (-w.qv, qw w + w x qv).
        turn = cross(qv, w_g) if step.in_body else cross(w_g, qv)
        vec = (qw * w_g + turn) / 2
        rates.update(zip(step.quaternion, [-qv.dot(w_g) / 2, *vec]))
    return motion, rates


def _is_fixed(steps, moving: set) -> bool:
    """A link of constant translations and rotations (parameters allowed)."""
    return all(isinstance(s, Translate) and not (s.vector.free_symbols & moving)
               or isinstance(s, Rotate) and not (s.angle.free_symbols & moving) for s in steps)


def rigid_groups(spec: Spec) -> dict[str, tuple[str, sp.Matrix, sp.Matrix]]:
    """frame -> (root, R, p): the nearest moving ancestor (or world) it is fixed to, and its pose there.

    A frame is fixed to its parent when its link is only constant translations and
    rotations (parameters allowed; no coordinate, no time); a moving frame is its own root.
    """
    moving = {c.q for c in spec.coordinates} | {TIME}
    out = {"world": ("world", sp.eye(3), sp.zeros(3, 1))}
    for frame in spec.frames:
        steps = list(frame.transforms)
        if _is_fixed(steps, moving):
            R, p = link_pose(steps)
            root, R0, p0 = out[frame.parent]
            out[frame.name] = (root, R0 * R, p0 + R0 * p)
        else:
            out[frame.name] = (frame.name, sp.eye(3), sp.zeros(3, 1))
    return out


def _fixed(R, p, n) -> LinkMotion:
    zero, Z = sp.zeros(3, 1), sp.zeros(3, n)
    return LinkMotion(R, p, Z, Z, zero, zero, zero, zero, Z, zero, zero)


def _attach(P: FrameKinematics, motion: LinkMotion, emit: Emitter, label: str, index: int) -> FrameKinematics:
    """World kinematics of a frame from its parent's and its link's relative motion (eq. 1-3)."""
    m = motion
    R_rel, p_rel, Jw_rel, Jv_rel, w_rel, v_rel, al_rel, ac_rel = m.R, m.p, m.Jw, m.Jv, m.w, m.v, m.al, m.ac
    n = P.Jw.shape[1]
    d = emit.matrix(f"{label}d", P.R * p_rel)
    Rw_rel = P.R * w_rel
    Rv_rel = P.R * v_rel
    R = emit.matrix(f"{label}R", P.R * R_rel)
    r = emit.matrix(f"{label}r", P.r + d)
    w = emit.matrix(f"{label}w", P.w + Rw_rel)
    vel = emit.matrix(f"{label}v", P.v + cross(P.w, d) + Rv_rel)
    Jw = emit.matrix(f"{label}Jw", P.Jw + P.R * Jw_rel)
    # Column by column, of the columns where Jw_P or Jv_rel has an entry (the others are Jv_P's: no work per
    # speed of the model, which would make the derivation quadratic in its size).
    Jv_sum = P.Jv.todok()
    for j in sorted({j for _, j in P.Jw.todok()} | {j for _, j in Jv_rel.todok()}):
        column = P.Jv[:, j] + cross(P.Jw[:, j], d) + P.R * Jv_rel[:, j]
        Jv_sum.update({(i, j): column[i] for i in range(3)})
    Jv = emit.matrix(f"{label}Jv", sp.Matrix.from_dok(3, n, Jv_sum))
    al = emit.matrix(f"{label}al", P.al + P.R * al_rel + cross(P.w, Rw_rel))
    ac = emit.matrix(f"{label}ac", P.ac + cross(P.al, d) + cross(P.w, cross(P.w, d))
                     + 2 * cross(P.w, Rv_rel) + P.R * ac_rel)
    RT = R_rel.T
    wb_P = RT * P.wb
    wb = emit.matrix(f"{label}wb", wb_P + m.w_own)
    Jwb = emit.matrix(f"{label}Jwb", RT * P.Jwb + m.Jw_own)
    alb = emit.matrix(f"{label}alb", RT * P.alb + m.al_own + cross(wb_P, m.w_own))
    return FrameKinematics(index, R, r, w, vel, Jw, Jv, al, ac, wb, Jwb, alb)


def frame_kinematics(spec: Spec, emit: Emitter) -> dict[str, FrameKinematics]:
    """World kinematics of every frame, parents first, as emitted symbols."""
    q = [c.q for c in spec.coordinates]
    v = spec.speed_symbols
    n = len(v)
    zero = sp.zeros(3, 1)
    out = {"world": FrameKinematics(-1, sp.eye(3), zero, zero, zero, sp.zeros(3, n), sp.zeros(3, n), zero, zero,
                                    zero, sp.zeros(3, n), zero)}
    moving = set(q) | {TIME}
    rigid = rigid_groups(spec)
    for k, frame in enumerate(spec.frames):
        # Intermediates are named by the frame (f<k>_<name>_R00, ...): its index keeps two frames apart
        # whatever their names (frames 'a' and 'a_ref' would share a_ref_R00), its name makes them readable.
        label = f"f{k}_{frame.name}_"
        P = out[frame.parent]
        steps = list(frame.transforms)
        rates = {}
        if _is_fixed(steps, moving):
            # Place a fixed frame from the nearest moving ancestor, so the frames
            # between (a bar's end, when only its COM carries a body) need no
            # Jacobians of their own.
            root, R, p = rigid[frame.name]
            P = out[root]
            motion = _fixed(R, p, n)
        elif steps and isinstance(steps[-1], Nonholonomic):
            nonholonomic = steps.pop()
            if steps:   # fixed offsets first: the link's reference frame
                P = _attach(P, link_motion(steps, q, v), emit, f"{label}ref_", k)
            motion, rates = nonholonomic_motion(nonholonomic, q, v, emit, label)
        else:
            motion = link_motion(steps, q, v)
        out[frame.name] = _attach(P, motion, emit, label, k)
        out[frame.name].signal_rates = rates
    return out
