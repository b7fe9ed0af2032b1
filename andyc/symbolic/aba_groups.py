"""The articulated-body algorithm's step over a group of links moved by shared speeds (a multi-link joint).

A URDF mimic joint (andyc/spec/urdf.py: by substitution, no coordinate of its own) moves its link by the
speed of the joint it mimics: panda's second finger moves by the first finger's speed, and each of talos_full's
grippers is seven links moved by one gripper coordinate. Links whose own columns S_i (aba.py) share any speed,
transitively, form a group g with speeds v_g (n_g of them); its links must hang from one parent link P (or
the world) through links of the group only (else `link_groups` returns None and the model keeps M). Being
the transitive closure, no link outside g moves by v_g. The group is then one joint of n_g speeds between P
and a tree of rigid links, and aba.py's per-link step becomes, in each link's own axes:

    pass 1 (out)  for b in g, pb its parent inside g (S_pb = 0, C_pb = 0 when b hangs from P), X_bP = X_b X_pb,P:
                  S_b = X_b S_pb + S_b_own            (6 x n_g: b's own columns placed at their speeds)
                  C_b = X_b C_pb + c_b                (c_b = v_b x v_J,b + d/dt v_J,b: aba.py's per-link bias)
                  so that a_b = X_bP a_P + S_b dv_g/dt + C_b
    pass 2 (in)   (the children of g's links outside g first, into I^A_b, p^A_b as aba.py does)
                  U = sum_b X_bP^T I^A_b S_b   (6 x n_g),   D = sum_b S_b^T I^A_b S_b   (n_g x n_g)
                  I_G = sum_b X_bP^T I^A_b X_bP,   p_G = sum_b X_bP^T (p^A_b + I^A_b C_b)
                  u = tau_g - sum_b S_b^T (p^A_b + I^A_b C_b)
                  I^A_P += I_G - U D^-1 U^T,   p^A_P += p_G + U D^-1 u
    pass 3 (out)  dv_g/dt = D^-1 (u - U^T a_P)
                  a_b = X_b a_pb + c_b + S_b_own dv_g/dt      (= X_bP a_P + S_b dv_g/dt + C_b)

Derivation: each link b obeys f_b = I^A_b a_b + p^A_b (RBDA §7.1, the articulated inertias of its children
outside g folded in as Table 7.1 does); summed over the group in P's axes, the force P exerts on it is
f = sum_b X_bP^T f_b = I_G a_P + U dv_g/dt + p_G, and the group's generalized equation (the power of v_g, S_b
being b's velocity per unit v_g) sum_b S_b^T f_b = tau_g gives D dv_g/dt = u - U^T a_P. Eliminating dv_g/dt,
f = (I_G - U D^-1 U^T) a_P + p_G + U D^-1 u: the group's articulated inertia and bias force seen from P. With one
link (I_G = X^T I^A X, U = X^T U_i, D = D_i, p_G = X^T (p^A + I^A c)) these are Table 7.1's I^a and p^a moved to
P; that per-link path (aba.py) is kept for single links, so models without groups get the same code as before.

The sums are formed along the group's tree, never through X_bP: I_G from composite inertias (each link's I^A_b
plus its group children's, moved to its parent by aba._inertia_to_parent, as the composite-rigid-body algorithm
of RBDA ch. 6 accumulates them), the columns of U and p_G as forces moved up link by link (aba._force_to_parent),
and pass 3's a_b link by link. Every intermediate is an emitted symbol (aba._Writer, zeros kept as zeros), named
aba<i>_g... for link i, aba<m>_G... for the group (m its first link).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

from andyc.symbolic.aba import _force_to_parent, _inertia_to_parent, _motion


@dataclass
class Group:
    members: list       # link indices, parents first
    speeds: list        # v_g: the speeds they share, ascending
    parent: str         # P: the link (or "world") the group hangs from
    own: dict = field(default_factory=dict)     # link index -> S_b_own (6 x n_g)
    U: sp.Matrix = None
    D: sp.Matrix = None  # D^-1 (1 x 1) when n_g = 1, else D
    u: sp.Matrix = None


def link_groups(links) -> list | None:
    """The groups of links that share speeds (two or more links; single links keep aba.py's step), or None when a
    group does not hang from one parent through its own links (module docstring)."""
    root = list(range(len(links)))

    def find(i):
        while root[i] != i:
            root[i] = root[root[i]]
            i = root[i]
        return i

    first = {}
    for i, link in enumerate(links):
        for j in link.speeds:
            if j in first:
                root[find(i)] = find(first[j])
            else:
                first[j] = i
    members = {}
    for i, link in enumerate(links):
        if link.speeds:
            members.setdefault(find(i), []).append(i)
    groups = []
    for idx in members.values():
        if len(idx) == 1:
            continue
        names = {links[i].name for i in idx}
        outside = {links[i].parent for i in idx if links[i].parent not in names}
        if len(outside) != 1:
            return None
        speeds = sorted({j for i in idx for j in links[i].speeds})
        col = {j: k for k, j in enumerate(speeds)}
        own = {}
        for i in idx:
            S = sp.zeros(6, len(speeds))
            for k, j in enumerate(links[i].speeds):
                S[:, col[j]] = links[i].S[:, k]
            own[i] = S
        groups.append(Group(sorted(idx), speeds, outside.pop(), own))
    return groups


def articulate(group: Group, links, IA, pA, bias, tau, out) -> None:
    """Pass 2 for the group: its U, D, u (kept on `group` for pass 3), and its articulated inertia and bias force
    added to those of its parent P (IA, pA: by link name; unless P is the world)."""
    ng, inside = len(group.speeds), {links[i].name: i for i in group.members}
    S, C = {}, {}
    for i in group.members:                         # parents first: S_b, C_b
        link, label = links[i], f"aba{i}_g"
        pb = inside.get(link.parent)
        if pb is None:
            S[i], C[i] = group.own[i], bias[link.name]
        else:
            moved = sp.Matrix.hstack(*[_motion(link, S[pb][:, k]) for k in range(ng)])
            S[i] = out.mat(f"{label}S", moved + group.own[i])
            C[i] = out.vec(f"{label}C", _motion(link, C[pb]) + bias[link.name])
    D, u = sp.zeros(ng, ng), sp.Matrix([tau[j] for j in group.speeds])
    J, F, W = {}, {}, {}                            # composite inertia, force and U of each link's part of the group
    P = group.parent
    J[P], F[P], W[P] = sp.zeros(6, 6), sp.zeros(6, 1), sp.zeros(6, ng)
    for i in reversed(group.members):
        link, label = links[i], f"aba{i}_g"
        Ik = out.sym(f"{label}IA", IA[link.name])
        pk = out.vec(f"{label}pA", pA[link.name])
        Wb = out.mat(f"{label}W", Ik * S[i])
        fb = out.vec(f"{label}f", pk + Ik * C[i])
        D += S[i].T * Wb
        u -= S[i].T * fb
        if i in J:                                  # its group children's, already in its axes
            Jb = out.sym(f"{label}J", Ik + J[i])
            Fb, Wc = out.vec(f"{label}F", fb + F[i]), out.mat(f"{label}Uc", Wb + W[i])
        else:
            Jb, Fb, Wc = Ik, fb, Wb
        up = inside.get(link.parent, P)
        if up not in J:
            J[up], F[up], W[up] = sp.zeros(6, 6), sp.zeros(6, 1), sp.zeros(6, ng)
        J[up] = J[up] + _inertia_to_parent(link, Jb, out, f"{label}X")
        F[up] = F[up] + _force_to_parent(link, Fb)
        W[up] = W[up] + sp.Matrix.hstack(*[_force_to_parent(link, Wc[:, k]) for k in range(ng)])
    label = f"aba{group.members[0]}_G"
    group.U = out.mat(f"{label}U", W[P])
    D = out.sym(f"{label}D", D)
    group.u = out.vec(f"{label}u", u)
    if ng == 1:
        group.D = sp.Matrix([[out.emit.scalar(f"{label}Dinv", 1 / D[0, 0])]])
        Wd = group.U * group.D[0, 0]
    else:
        group.D = D
        Wd = out.solve(f"{label}W", D, group.U.T).T
    if P == "world":
        return
    Wd = out.mat(f"{label}W", Wd)                   # U D^-1
    IA[P] = IA[P] + out.sym(f"{label}Ia", J[P] - Wd * group.U.T)
    pA[P] = pA[P] + F[P] + Wd * group.u


def accelerate(group: Group, links, bias, acc, vdot, out) -> None:
    """Pass 3 for the group: dv_g/dt into vdot, each link's acceleration into acc (by name)."""
    label = f"aba{group.members[0]}_G"
    rhs = out.vec(f"{label}r", group.u - group.U.T * acc[group.parent])
    dv = rhs * group.D[0, 0] if len(group.speeds) == 1 else out.solve(f"{label}dv", group.D, rhs)
    dv = out.vec(f"{label}dv", dv)
    for j, e in zip(group.speeds, dv):
        vdot[j] = e
    for i in group.members:
        link = links[i]
        acc[link.name] = out.vec(f"aba{i}_ga", _motion(link, acc[link.parent]) + bias[link.name]
                                 + group.own[i] * dv)
