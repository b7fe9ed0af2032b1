"""A slipping contact's forces (Pfeiffer & Glocker 1996, ch. 5): in a flow where a contact slips, its normal
force carries Coulomb's friction, so the forces are B^T lam with B != A and the multipliers solve the
non-symmetric system (C D^T) lam = y, C = A L^-T, D = B L^-T (dynamics.slipping_force calls these)."""

import math

import numpy as np

from .compiler import jit
from .model import call
from .status import RANK_TOL, SLIP_TINY


@jit(inline="always")
def slip_unit(model, w, d, r):
    """(u1, u2) the unit slip direction of the contact with spatial friction whose normal row is the r-th active
    row (its stick rows t, t + 1: w.active[1, r] = t + 1; its slip s = (c_t, c_t+1) in S's cv row; in d from
    w.active[3, r] - 1 = k: d_ref = (d[k], d[k + 1]), the direction at the step's start, and d[k + 2],
    1 while the step holds it; both set by slip_direction): sigma s / |s|, sigma = sign(s . d_ref), so that within
    a step the friction keeps its direction through a slip that ends there (as a planar slip's sigma is fixed in
    its flow) and the stop's guard s . d_ref crosses zero; d_ref itself when the step holds it, or when
    |s| <= SLIP_TINY (a slip starting from rest, its direction set by the runtime)."""
    S = w.S
    t = w.active[1, r] - 1
    k = w.active[3, r] - 1
    s1, s2 = S[model.s_cv, t], S[model.s_cv, t + 1]
    n = math.sqrt(s1 * s1 + s2 * s2)
    if n <= SLIP_TINY or d[k + 2] != 0.0:
        return d[k], d[k + 1]
    if s1 * d[k] + s2 * d[k + 1] < 0.0:
        n = -n
    return s1 / n, s2 / n


@jit
def slip_rows(model, w, p, d, L, nr):
    """D = B L^-T into S's W block (its first nr rows; the symmetric solve's Gram matrix, unused where a contact
    slips), the force directions of the active rows, whitened (C = A L^-T in S): B = A but for the normal row of a
    slipping contact, whose force is its normal force plus Coulomb's friction, -sigma mu lam_n along its tangent
    (sigma = +1 slipping forwards, -1 backwards): B_r = A_r - sigma mu J_t, J_t the contact's stick row
    (w.active[1, r] = -sigma (t + 1), t that row; mu the coefficient of jump w.active[2, r], the slip's end, in
    S's e row; active.select_rows). Spatial friction (w.active[3, r] > 0; stick rows t, t + 1): the friction
    -mu lam_n u along the slip's direction u (slip_unit), B_r = A_r - mu (u1 J_t + u2 J_t+1). Only where a contact
    slips (w.nactive[2]): otherwise the symmetric solve."""
    S, nv, w0, c0 = w.S, model.nv, model.s_w, model.s_c
    call(model.restitution, (p, S))
    for r in range(nr):
        code = w.active[1, r]
        if code == 0:
            for i in range(nv):
                S[w0 + r, i] = S[c0 + r, i]
            continue
        row = model.s_a + abs(code) - 1
        u1, u2 = 1.0, 0.0
        if w.active[3, r] > 0:
            u1, u2 = slip_unit(model, w, d, r)
        for i in range(nv):             # J_t L^-T (spatial: (u1 J_t + u2 J_t+1) L^-T), as linalg.whiten
            s = u1 * S[row, i]
            if u2 != 0.0:
                s += u2 * S[row + 1, i]
            for j in range(i):
                s -= L[i, j] * S[w0 + r, j]
            S[w0 + r, i] = s * L[i, i]
        spatial = w.active[3, r] > 0
        scale = S[model.s_e, w.active[2, r]] * (1.0 if code > 0 and not spatial else -1.0)
        for i in range(nv):
            S[w0 + r, i] = S[c0 + r, i] + scale * S[w0 + r, i]


@jit
def solve_slipping(model, w, nr):
    """y <- (C D^T)^+ y over the first nr rows (C D^T = A M^-1 B^T, not symmetric: D from slip_rows in S's W
    block), least squares (one row: a division). False when a slipping contact's own entry A_n M^-1 B_n^T is not
    positive: its normal force would pull it open (Painleve's paradox: no consistent force; Pfeiffer & Glocker
    1996, ch. 5)."""
    S, nv, w0, c0, y0 = w.S, model.nv, model.s_w, model.s_c, model.s_y
    if nr == 1:
        k = 0.0
        for i in range(nv):
            k += S[c0, i] * S[w0, i]
        if k != 0.0:
            S[y0, 0] /= k
        return k > 0.0
    K = np.empty((nr, nr))
    for r in range(nr):
        for j in range(nr):
            s = 0.0
            for i in range(nv):
                s += S[c0 + r, i] * S[w0 + j, i]
            K[r, j] = s
    y = np.empty(nr)
    for r in range(nr):
        y[r] = S[y0, r]
    lam = np.linalg.lstsq(K, y, RANK_TOL)[0]
    for r in range(nr):
        S[y0, r] = lam[r]
    for r in range(nr):
        if w.active[1, r] != 0 and not K[r, r] > 0.0:
            return False
    return True


@jit
def held_direction(h11, h12, h22, z1, z2):
    """The direction an implicit (backward Euler) step of a spatial slip ends in: s1 = z - H s1 / |s1|, with
    z = s0 + h a_free (the slip at the step's end without this contact's friction) and H = h mu lam_n G, G the
    contact's tangential inverse inertia J_t M^-1 J_t^T (2 x 2, symmetric, positive semi-definite): the friction
    -mu lam_n s1 / |s1| taken at the step's end. With sigma = |s1|, s1 = sigma (sigma I + H)^-1 z, so sigma > 0
    solves |(sigma I + H)^-1 z| = 1 (phi(sigma), decreasing; the secular equation of a trust region, solved here
    by Newton's method on 1 / phi - 1, which is nearly linear, within the bracket (0, |z|]: phi(|z|) <= 1).
    Returns (slips, u1, u2): slips False when |H^-1 z| <= 1 (the step's slip ends: the friction needed to stop it
    is inside the cone), else the unit s1 / sigma. An anisotropic G (a box's corner, a foot on a leg) turns
    s1 away from z: unlike normalising z, this keeps a direction that the slip really keeps (z = (beta I + H) d,
    beta > 0, gives d), so that a straight slide stays straight and a slip started at the cone's edge along the
    sticking force's opposite is not turned at once into one that stops."""
    m, r = 0.5 * (h11 + h22), math.hypot(0.5 * (h11 - h22), h12)
    l1, l2 = m + r, max(m - r, 0.0)             # H's eigenvalues, l1 >= l2 >= 0
    q1, q2 = 1.0, 0.0                           # its first eigenvector (any, H isotropic)
    if r > 0.0:
        a1, a2 = h12, l1 - h11                  # (two forms of it: the larger is the accurate one)
        b1, b2 = l1 - h22, h12
        if a1 * a1 + a2 * a2 < b1 * b1 + b2 * b2:
            a1, a2 = b1, b2
        size = math.hypot(a1, a2)
        q1, q2 = a1 / size, a2 / size
    w1, w2 = q1 * z1 + q2 * z2, q1 * z2 - q2 * z1       # z in H's eigenbasis
    if w1 == 0.0 and w2 == 0.0:
        return False, 0.0, 0.0
    if l2 > 0.0 and (w1 / l1) ** 2 + (w2 / l2) ** 2 <= 1.0:
        return False, 0.0, 0.0
    lo, hi = 0.0, math.hypot(z1, z2)
    sigma = hi
    for _ in range(100):
        e1, e2 = w1 / (sigma + l1), w2 / (sigma + l2)
        phi = math.sqrt(e1 * e1 + e2 * e2)
        if phi > 1.0:
            lo = sigma
        else:
            hi = sigma
        slope = (e1 * e1 / (sigma + l1) + e2 * e2 / (sigma + l2)) / phi ** 3    # d(1 / phi) / d sigma
        step = sigma - (1.0 / phi - 1.0) / slope
        if not lo < step < hi:
            step = 0.5 * (lo + hi)
        if abs(step - sigma) <= 4e-16 * sigma or hi - lo <= 4e-16 * hi:
            sigma = step
            break
        sigma = step
    e1, e2 = w1 / (sigma + l1), w2 / (sigma + l2)
    size = math.hypot(e1, e2)
    return True, (q1 * e1 - q2 * e2) / size, (q2 * e1 + q1 * e2) / size
