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
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.expressions import TIME
from andyc.spec.model import Rotate, Spec, Translate
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


def rotation_matrix(axis: sp.Matrix, angle) -> sp.Matrix:
    """Rodrigues: R = I + sin(a) [k]x + (1 - cos(a)) [k]x^2 for a unit axis k."""
    k = skew(axis)
    return sp.eye(3) + sp.sin(angle) * k + (1 - sp.cos(angle)) * (k * k)


def skew(a: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])


def cross(a: sp.Matrix, b: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _rate(expr, q, v):
    """Total time derivative of expr(q, v, t) with dv/dt = 0."""
    return sum((sp.diff(expr, qi) * vi for qi, vi in zip(q, v)), sp.diff(expr, TIME))


def link_motion(transforms, q, v):
    """Relative motion of a link in its parent's axes.

    Returns R_rel, p_rel, Jw_rel, Jv_rel (3 x n), w_rel, v_rel, al_rel, ac_rel.
    """
    n = len(q)
    R = sp.eye(3)
    p = sp.zeros(3, 1)
    Jw = sp.zeros(3, n)
    w_t = sp.zeros(3, 1)            # explicit-time part of w_rel
    for step in transforms:
        if isinstance(step, Translate):
            p = p + R * step.vector
        else:
            axis = R * step.axis
            for j, qj in enumerate(q):
                Jw[:, j] += axis * sp.diff(step.angle, qj)
            w_t += axis * sp.diff(step.angle, TIME)
            R = R * rotation_matrix(step.axis, step.angle)
    Jv = p.jacobian(q) if n else sp.zeros(3, 0)
    vvec = sp.Matrix(v)
    w_rel = Jw * vvec + w_t
    v_rel = Jv * vvec + sp.diff(p, TIME)
    al_rel = w_rel.applyfunc(lambda e: _rate(e, q, v))
    ac_rel = v_rel.applyfunc(lambda e: _rate(e, q, v))
    return R, p, Jw, Jv, w_rel, v_rel, al_rel, ac_rel


def frame_kinematics(spec: Spec, emit: Emitter) -> dict[str, FrameKinematics]:
    """World kinematics of every frame, parents first, as emitted symbols."""
    q = [c.q for c in spec.coordinates]
    v = [c.v for c in spec.coordinates]
    n = len(q)
    zero = sp.zeros(3, 1)
    out = {"world": FrameKinematics(-1, sp.eye(3), zero, zero, zero, sp.zeros(3, n), sp.zeros(3, n), zero, zero)}
    for k, frame in enumerate(spec.frames):
        P = out[frame.parent]
        R_rel, p_rel, Jw_rel, Jv_rel, w_rel, v_rel, al_rel, ac_rel = link_motion(frame.transforms, q, v)
        d = emit.matrix(f"f{k}d", P.R * p_rel)
        Rw_rel = P.R * w_rel
        Rv_rel = P.R * v_rel
        R = emit.matrix(f"f{k}R", P.R * R_rel)
        r = emit.matrix(f"f{k}r", P.r + d)
        w = emit.matrix(f"f{k}w", P.w + Rw_rel)
        vel = emit.matrix(f"f{k}v", P.v + cross(P.w, d) + Rv_rel)
        Jw = emit.matrix(f"f{k}Jw", P.Jw + P.R * Jw_rel)
        Jv_cols = [P.Jv[:, j] + cross(P.Jw[:, j], d) + P.R * Jv_rel[:, j] for j in range(n)]
        Jv = emit.matrix(f"f{k}Jv", sp.Matrix.hstack(*Jv_cols) if n else sp.zeros(3, 0))
        al = emit.matrix(f"f{k}al", P.al + P.R * al_rel + cross(P.w, Rw_rel))
        ac = emit.matrix(f"f{k}ac", P.ac + cross(P.al, d) + cross(P.w, cross(P.w, d))
                         + 2 * cross(P.w, Rv_rel) + P.R * ac_rel)
        out[frame.name] = FrameKinematics(k, R, r, w, vel, Jw, Jv, al, ac)
    return out
