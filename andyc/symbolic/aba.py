"""Featherstone's articulated-body algorithm (ABA), derived symbolically: dv/dt without M.

Featherstone, "Rigid Body Dynamics Algorithms" (2008), ch. 7, Table 7.1, in each link's own axes,
spatial vectors (angular; linear), a link being a moving frame with the frames fixed to it (the root of
a rigid group, kinematics.rigid_groups) and its bodies merged into one spatial inertia I_i about its
origin (RBDA eq. 2.63; bodies have their COM at their frame's origin):

    I_i = [[Ic + m c~ c~^T, m c~], [m c~^T, m 1]]

Link i hangs from link lambda(i) (or the world) by X_i = [[E, 0], [-E r~, E]], E the rotation from
lambda(i)'s axes to i's, r i's origin in lambda(i)'s axes. Its relative spatial velocity in its own axes is
v_J = S_i v_i + sigma_i: S_i (6 x n_i) the columns of its own speeds v_i (angular: the link's Jw_own; linear:
R^T Jv of its relative motion, R its rotation), sigma_i an explicit time part. Then

    pass 1 (out)  v_i = X_i v_lambda + v_J
                  c_i = v_i x v_J + d/dt v_J |_(dv/dt = 0)      (own axes: Jw_own' v, R^T ac_rel - w_own x R^T v_rel)
                  I^A_i = I_i,  p^A_i = v_i x* I_i v_i
    pass 2 (in)   U_i = I^A_i S_i,  D_i = S_i^T U_i,  u_i = tau_i - S_i^T p^A_i
                  I^a = I^A_i - U_i D_i^-1 U_i^T,  p^a = p^A_i + I^a c_i + U_i D_i^-1 u_i
                  I^A_lambda += X_i^T I^a X_i,  p^A_lambda += X_i^T p^a
    pass 3 (out)  a' = X_i a_lambda + c_i,  dv_i/dt = D_i^-1 (u_i - U_i^T a'),  a_i = a' + S_i dv_i/dt

with the world's a_0 = (0, -g) (gravity as an acceleration of the ground, RBDA §5.3). tau is the
generalized force of every element other than a body (forces, torques, dampers, springs, potentials: their
G of dynamics.py, the same terms the dense path adds), so dv/dt = M^-1 G exactly. X_i^T I^a X_i is formed
in blocks (rotate by E, then shift by r: A + r~ B'^T - B' r~ - r~ C' r~, B' + r~ C', C'), every
intermediate an emitted symbol (no expression grows along the tree), symmetric ones by their upper
triangle; D_i^-1 by its LDL^T factors written out (n_i = 1: one division; a floating base: 6 x 6). Where a
column of S_i is a unit vector e_k (a joint about or along one of the link's own axes), I^a's row and column k
are zero exactly (I^a S_i = U_i - U_i D_i^-1 D_i = 0), so they are written as zeros, not computed to rounding.

Applies to an unconstrained tree of links (revolute, prismatic, any holonomic link of its coordinates, a
floating link's six quasi-velocities, a link moved along t) where every speed moves a link. Links whose S_i
share speeds (a URDF mimic joint: a finger moved by the other's speed, a gripper's links by one coordinate)
form a group that takes one step over all of its links (aba_groups.py), provided the group hangs from one
link through its own links; `articulated_body` returns None otherwise. Links that share no speed with another
take the step above, so a model without groups gets the same derivation as before groups existed.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.model import Nonholonomic, Spec
from andyc.spec.expressions import TIME
from andyc.symbolic.emitter import Emitter
from andyc.symbolic.kinematics import _is_fixed, cross, link_motion, nonholonomic_motion, rigid_groups, skew


@dataclass
class ArticulatedBody:
    """dv/dt (n expressions over `assignments`, in dependency order after the model's own) and the links."""
    assignments: list
    vdot: list
    links: int


@dataclass
class _Link:
    name: str
    parent: str         # the link it hangs from, or "world"
    E: sp.Matrix        # parent axes -> own axes
    r: sp.Matrix        # own origin in the parent's axes
    S: sp.Matrix        # 6 x n_i
    speeds: list        # indices of its own speeds
    vJ: sp.Matrix       # relative spatial velocity, own axes
    cJ: sp.Matrix       # d/dt vJ at dv/dt = 0
    inertia: sp.Matrix  # 6 x 6 about its origin, own axes


def _vec(a, b) -> sp.Matrix:
    return sp.Matrix.vstack(sp.Matrix(a), sp.Matrix(b))


def _spatial_inertia(m, c: sp.Matrix, Ic: sp.Matrix) -> sp.Matrix:
    cx = skew(c)
    return sp.Matrix(sp.BlockMatrix([[Ic + m * cx * cx.T, m * cx], [m * cx.T, m * sp.eye(3)]]))


def _links(spec: Spec) -> list | None:
    """The links (moving frames, parents first) with their joints and inertias, or None when a speed moves no
    link (a speed that moves several makes them a group: aba_groups.py)."""
    q = [c.q for c in spec.coordinates]
    v = spec.speed_symbols
    n = len(v)
    groups = rigid_groups(spec)
    moving = set(q) | {TIME}
    links, owner = [], {}
    for k, frame in enumerate(spec.frames):
        if groups[frame.name][0] != frame.name:
            continue
        steps = list(frame.transforms)
        if steps and isinstance(steps[-1], Nonholonomic):
            last = steps.pop()
            if not _is_fixed(steps, moving):
                return None
            ref = link_motion(steps, q, v)
            # The same symbols as frame_kinematics' (its labels): they are in the model's pool.
            motion, _ = nonholonomic_motion(last, q, v, Emitter(), f"f{k}_{frame.name}_")
            R_ref, p_ref = ref.R, ref.p
        else:
            motion = link_motion(steps, q, v)
            R_ref, p_ref = sp.eye(3), sp.zeros(3, 1)
        root, R0, p0 = groups[frame.parent]
        Rm = motion.R
        E = (R0 * R_ref * Rm).T
        r = p0 + R0 * (p_ref + R_ref * motion.p)
        v_lin = Rm.T * motion.v
        S = sp.Matrix.vstack(motion.Jw_own, Rm.T * motion.Jv)
        own = [j for j in range(n) if any(e != 0 for e in S[:, j])]
        for j in own:
            owner.setdefault(j, frame.name)
        cJ = _vec(motion.al_own, Rm.T * motion.ac - cross(motion.w_own, v_lin))
        links.append(_Link(frame.name, root, E, r, S[:, own], own, _vec(motion.w_own, v_lin), cJ, sp.zeros(6, 6)))
    if len(owner) != n:
        return None
    index = {link.name: link for link in links}
    for b in spec.bodies:
        root, R, p = groups[b.frame]
        if root != "world":
            index[root].inertia += _spatial_inertia(b.mass, p, R * b.inertia * R.T)
    return links


class _Writer:
    """Emits ABA's intermediates, named aba<i>_<what>..., zero entries kept as zeros."""

    def __init__(self):
        self.emit = Emitter()

    def vec(self, label, vec):
        return self.emit.matrix(label, sp.Matrix(vec))

    def mat(self, label, mat):
        return sp.Matrix(mat.rows, mat.cols, lambda i, j: self.emit.scalar(f"{label}{i}_{j}", mat[i, j]))

    def sym(self, label, mat):
        """A symmetric matrix by its upper triangle."""
        out = sp.zeros(mat.rows, mat.cols)
        for i in range(mat.rows):
            for j in range(i, mat.cols):
                out[i, j] = out[j, i] = self.emit.scalar(f"{label}{i}_{j}", mat[i, j])
        return out

    def solve(self, label, D, B):
        """D^-1 B for a symmetric positive definite D (n x n), by D = L diag(d) L^T written out."""
        n = D.rows
        L, d, inv = sp.eye(n), [None] * n, [None] * n
        for j in range(n):
            for i in range(j, n):
                s = D[i, j] - sum((L[i, k] * L[j, k] * d[k] for k in range(j)), sp.Integer(0))
                if i == j:
                    d[j] = self.emit.scalar(f"{label}d{j}", s)
                    inv[j] = self.emit.scalar(f"{label}id{j}", 1 / d[j])
                else:
                    L[i, j] = self.emit.scalar(f"{label}L{i}_{j}", s * inv[j])
        out = sp.zeros(n, B.cols)
        for c in range(B.cols):
            y = [None] * n
            for i in range(n):
                y[i] = self.emit.scalar(f"{label}y{i}_{c}", B[i, c] - sum((L[i, k] * y[k] for k in range(i)),
                                                                           sp.Integer(0)))
            x = [None] * n
            for i in reversed(range(n)):
                x[i] = self.emit.scalar(f"{label}x{i}_{c}", y[i] * inv[i]
                                        - sum((L[k, i] * x[k] for k in range(i + 1, n)), sp.Integer(0)))
            for i in range(n):
                out[i, c] = x[i]
        return out


def _unit_rows(S: sp.Matrix) -> list:
    """The rows k where a column of S is the unit vector e_k (a joint about or along one of its own axes)."""
    out = []
    for j in range(S.cols):
        nonzero = [k for k in range(S.rows) if S[k, j] != 0]
        if len(nonzero) == 1 and S[nonzero[0], j] == 1:
            out.append(nonzero[0])
    return out


def _cross_motion(a, b):
    w, v, w2, v2 = a[:3, 0], a[3:, 0], b[:3, 0], b[3:, 0]
    return _vec(cross(w, w2), cross(w, v2) + cross(v, w2))


def _cross_force(a, f):
    w, v, n, f3 = a[:3, 0], a[3:, 0], f[:3, 0], f[3:, 0]
    return _vec(cross(w, n) + cross(v, f3), cross(w, f3))


def _motion(link, m):
    """X_i m: a motion vector of the parent's axes in the link's."""
    w, v = m[:3, 0], m[3:, 0]
    return _vec(link.E * w, link.E * (v - cross(link.r, w)))


def _force_to_parent(link, f):
    """X_i^T f: a force of the link's axes (about its origin) in the parent's."""
    n = link.E.T * f[:3, 0]
    f3 = link.E.T * f[3:, 0]
    return _vec(n + cross(link.r, f3), f3)


def _inertia_to_parent(link, Ia, out, label):
    """X_i^T I^a X_i by blocks: rotate (E^T . E), then shift by r (module docstring)."""
    E, rx = link.E, skew(link.r)
    A, B, C = Ia[:3, :3], Ia[:3, 3:], Ia[3:, 3:]
    A1 = out.sym(f"{label}A", E.T * out.mat(f"{label}AE", A * E))
    B1 = out.mat(f"{label}B", E.T * out.mat(f"{label}BE", B * E))
    C1 = out.sym(f"{label}C", E.T * out.mat(f"{label}CE", C * E))
    rC = out.mat(f"{label}rC", rx * C1)
    Bp = B1 + rC
    Ap = A1 + rx * B1.T - B1 * rx - rC * rx
    return sp.Matrix(sp.BlockMatrix([[Ap, Bp], [Bp.T, C1]]))


def articulated_body(spec: Spec, terms) -> ArticulatedBody | None:
    """ABA's dv/dt for `spec` (its element terms `terms`, bodies first, as dynamics.element_terms gives them),
    or None when it does not apply (module docstring). A contact's rows do not count: its flows are solved with M
    only while it is closed (andyc_numerics' dynamics.rhs_mode_into)."""
    contact_rows = {c.constraint for c in spec.contacts} | {c.stick for c in spec.contacts if c.stick}
    if any(c.name not in contact_rows for c in spec.constraints):
        return None
    links = _links(spec)
    if links is None:
        return None
    from andyc.symbolic import aba_groups       # (it imports this module's spatial operations)
    groups = aba_groups.link_groups(links)
    if groups is None:
        return None
    group_of = {i: g for g in groups for i in g.members}
    n = len(spec.speed_symbols)
    tau = sp.zeros(n, 1)
    for e in terms[len(spec.bodies):]:
        if e.G is not None:
            tau += e.G
    out = _Writer()
    zero = sp.zeros(6, 1)
    vel, bias, IA, pA = {"world": zero}, {}, {}, {}
    for i, link in enumerate(links):
        label = f"aba{i}_"
        vi = out.vec(f"{label}v", _motion(link, vel[link.parent]) + link.vJ)
        vel[link.name] = vi
        bias[link.name] = out.vec(f"{label}c", _cross_motion(vi, link.vJ) + link.cJ)
        IA[link.name] = link.inertia
        pA[link.name] = _cross_force(vi, link.inertia * vi)
    U, D, u, acc, vdot = {}, {}, {}, {"world": _vec(sp.zeros(3, 1), -spec.gravity)}, [None] * n
    for i in reversed(range(len(links))):
        link, label = links[i], f"aba{i}_"
        if i in group_of:                           # a group's step, at its first link (aba_groups.py)
            if i == group_of[i].members[0]:
                aba_groups.articulate(group_of[i], links, IA, pA, bias, tau, out)
            continue
        Ik = out.sym(f"{label}IA", IA[link.name])
        pk = out.vec(f"{label}pA", pA[link.name])
        c = bias[link.name]
        if link.speeds:
            U[i] = out.mat(f"{label}U", Ik * link.S)
            D[i] = link.S.T * U[i]
            u[i] = out.vec(f"{label}u", sp.Matrix([tau[j] for j in link.speeds]) - link.S.T * pk)
            if len(link.speeds) == 1:
                D[i] = out.emit.scalar(f"{label}Dinv", 1 / D[i][0, 0])     # (kept as D^-1)
        if link.parent == "world":
            continue
        if link.speeds:
            # W = U D^-1: I^a = I^A - W U^T, p^a = p^A + I^a c + W u
            W = (U[i] * D[i] if len(link.speeds) == 1 else out.solve(f"{label}W", D[i], U[i].T).T)
            W = out.mat(f"{label}W", W)
            Ia = Ik - W * U[i].T
            for k in _unit_rows(link.S):        # I^a S = U - U D^-1 D = 0: exactly, not by rounding
                Ia[k, :], Ia[:, k] = sp.zeros(1, 6), sp.zeros(6, 1)
            Ia = out.sym(f"{label}Ia", Ia)
            pa = Ia * c + pk + W * u[i]
        else:
            Ia, pa = Ik, pk + Ik * c
        IA[link.parent] = IA[link.parent] + _inertia_to_parent(link, Ia, out, f"{label}X")
        pA[link.parent] = pA[link.parent] + _force_to_parent(link, pa)
    for i, link in enumerate(links):
        label = f"aba{i}_"
        if i in group_of:
            if i == group_of[i].members[0]:
                aba_groups.accelerate(group_of[i], links, bias, acc, vdot, out)
            continue
        a1 = out.vec(f"{label}a1", _motion(link, acc[link.parent]) + bias[link.name])
        if link.speeds:
            rhs = out.vec(f"{label}r", u[i] - U[i].T * a1)
            dv = rhs * D[i] if len(link.speeds) == 1 else out.solve(f"{label}dv", D[i], rhs)
            dv = out.vec(f"{label}dv", dv)
            for j, e in zip(link.speeds, dv):
                vdot[j] = e
            acc[link.name] = out.vec(f"{label}a", a1 + link.S * dv)
        else:
            acc[link.name] = a1
    return ArticulatedBody(out.emit.assignments, vdot, len(links))
