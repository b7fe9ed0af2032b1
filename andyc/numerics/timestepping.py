"""Moreau-Jean time-stepping, compiled: contacts resolved by impulses in every step, no event location.

Moreau's theta-scheme as Jean 1999 (The non-smooth contact dynamics method, CMAME 177, 235-257, sec. 4) and
Acary & Brogliato 2008 (Numerical Methods for Nonsmooth Dynamical Systems, sec. 10.1) write it, at a fixed step h,
theta in [1/2, 1]:

    q_{k+theta} = q_k + theta h v_k                                    (signals: sigma + theta h dsigma/dt)
    index set   I = {contact i : g_i(q_{k+theta}) + (1 - theta) h u_i <= TOUCHING}   (the gap predicted at the
                                                          step's end, u_i = A_i v_free + b_i at the free velocity
                                                          v_free = v_k + h M^-1 G: gravity's pull included; for
                                                          a contact closed in the last step min(u_i, 0), and KEEP)
    M (v_{k+1} - v_k) = h G(t_{k+theta}, q_{k+theta}, v_k) + A^T P     (M, G, A at the mid point)
    each contact in I:  0 <= u_n,k+1 + e min(u_n,k, 0)  _|_  P_n >= 0  (Newton's law at velocity level)
                        Coulomb on P_t: |P_t| <= mu P_n, the slip u_t,k+1 = 0 inside the cone,
                        P_t = -mu P_n u_t,k+1 / |u_t,k+1| on its edge (planar, or spatial: the disk)
    the flow's own (bilateral) rows:  A v_{k+1} + b = 0
    q_{k+1} = q_k + h ((1 - theta) v_k + theta v_{k+1})               (signals at the mid point's rates, with
                                                                       v_{k+theta}; quaternions renormalized)

with G everything but the inertia term (M dv/dt = G), A the rows' Jacobian and u = A v + b their velocity
residuals. A closed contact whose free velocity lifts it stays in the problem, which opens it (P_n = 0, u_n > 0)
if the others let it rise: its free velocity is its own motion without any contact's impulse, and where several
contacts hold one body it can rise while the body, held by the others, presses it down (a robot's heel, which its
ankle motor spins up in free motion, while the toes' impulses turn the foot heel down: left out, it would sink for
a step and land, every other step). Newton's law restores e of an approaching speed only (min(u_n,k, 0)): a contact that enters the index
set already separating (a corner lifted, a ball rising out of its push-out) must not be allowed to sink at e times
that speed. The step's contact problem, W = A M^-1 A^T over the rows, is contact_solver.solve's (nonlinear
Gauss-Seidel, then the active set it finds solved exactly); each contact's state in the last step is its warm
start. Then two position corrections, since the scheme holds its rows at velocity level only: the bilateral rows
are put back on their manifold (dynamics.project over the flow's own rows: positions, then speeds), and each
contact closed after the step whose gap ended further than PENETRATION from zero, or in the step's problem,
below -PENETRATION and not rising out of it within a step (a bounce does by itself: pushing it out would add
the energy of its dip), is put back on the surface, by the least
change of the positions in the metric of M at the step's mid point (the position correction of Braun & Goldfarb
over those gaps and the flow's holonomic rows; no speed changes: the normal speeds are the scheme's). Why: a
closing contact enters the index set in the step at whose end it would first sink (its predicted gap, to first
order), so that it stops on the surface or up to h |u_n| above it, and is pulled onto it; and one that stays closed keeps u_n = 0 at the mid point's Jacobian only, so its gap drifts by O(h^2) a step
while the body turns on it (a rocking block's pivot, a robot's rolling foot). A contact in the index set whose
normal speed after the step exceeds REST_SPEED is open (a bounce, left alone: it rises out by itself); the others
keep the solver's state (stick, slip either way): the modes go into d at each step, so the log shows them.

The work slots: the elements' at the step's forces, h times their power at (t_{k+theta}, q_{k+theta}, v_k) (first
order, the scheme's own evaluation); the contact and bilateral impulses' in the `jumps` slot, P . (A v_{k+1/2} + b)
with v_{k+1/2} = (v_k + v_{k+1}) / 2: exactly the energy the impulses change (with friction, what it takes away),
so that E - E0 - W measures the scheme's own energy error.
"""

from collections import namedtuple

import math

import numpy as np

from .active import select_rows
from .compiler import jit
from .contact_solver import BILATERAL, BOUNDED, NORMAL, OPEN, PLANAR, SPATIAL, STICK, size, solve, work_shape
from .dynamics import correct_rows, move, normalize, project
from .integrator import update_inputs
from .linalg import add_rows_transposed, cholesky, solve_gram, solve_lower, solve_upper
from .sparse_rows import tree_factor, tree_upper
from .model import borrowed, call
from .status import DIVERGED, GROWTH_LIMIT, INPUT_FAILED, NONFINITE, OK, REST_SPEED, SINGULAR_MASS

TOUCHING = 1e-12        # m: a contact whose predicted gap is at most this is in the step's index set
KEEP = 1e-6             # m: ... or at most this, when it was closed in the last step: the mid point's linear update
#                         lifts a pivot by O((h w)^2) (a corner a block rocks about: 1e-8 m at 0.3 rad/s); out of the
#                         set for that, it would fall for a step and land again
PENETRATION = 1e-9      # m: a closed contact's gap further than this from zero after a step is put back on it
COMPLIANCE = 1e-6       # a joint friction's row: W's diagonal entry times 1 + this (_soften)

Scratch = namedtuple("Scratch", "W w0 X rows owner kind first mu state direction P work v a col xm x0 xdot "
                                "d_open e cmu total seen guess guess_dir landed speed stats tree span cut runs av "
                                "fspeed fslot fbound fguess fwork")
Scratch.__doc__ = """The arrays of a time-stepping run (new_scratch). The step's problem over at most nc rows: W (nc * nc),
w0, P (nc,), X (nc * nv) its rows whitened, C = A R^-1 (M = R^T R: _factor), row by row, span (nc, 2) the first
and one past the last speed where each row of C may be nonzero; rows (nc,) its constraint rows; per block: owner (its contact, -1 bilateral),
kind, first, mu, state, direction (2 each) as contact_solver takes them; work the solver's. v, a, col (nv,),
xm, x0, xdot (nx + nw,) buffers; d_open (nd,) d with every contact open; e, cmu (contacts,) each contact's
restitution and mu; total (nc,) each row's impulse since the last sample, seen (nc,) 1 where it took part; guess
(contacts,) each contact's block state in the last step (-1: not in it), guess_dir (contacts, 2); landed
(contacts,) 1 where a contact open at the step's start is closed at its end; speed (contacts,) each contact's
normal speed after the step (those of its problem); stats (4,):
steps, Gauss-Seidel sweeps, steps whose answer did not verify, push-outs; tree (1,) 1 where M is factored along
its tree (coefficients); cut (nc + 1,) the first block of each independent part of the step's problem, runs (nc, 2)
the speeds each part reaches (_parts); av (nc,) A v_k over the problem's rows. Per joint friction (frictions,): the
speed it acts on, its work slot, its force (coefficients), its state in the last step (the warm start), its work in
the step. (nc here counts the problem's rows at most: the constraint rows and the joint frictions.)"""


def new_scratch(nq, nv, nx, nw, nc, nd, contacts, friction_speeds=(), friction_slots=()) -> Scratch:
    """The zeroed arrays of a run's steps (Scratch); the joint frictions' speeds and work slots."""
    nf = len(friction_speeds)
    m = max(nc + nf, 1)
    z, i = np.zeros, np.int64
    return Scratch(z(m * m), z(m), z(nv * m), z(m, i), z(m, i), z(m, i), z(m, i), z(m), z(m, i), z(2 * m), z(m),
                   z(work_shape(m)), z(nv), z(nv), z(nv), z(nx + nw), z(nx + nw), z(nx + nw), z(nd), z(contacts),
                   z(contacts), z(m), z(m), np.full(contacts, -1, i), z((contacts, 2)), z(contacts, i), z(contacts), z(4, i),
                   z(1, i), z((m, 2), i), z(m + 1, i), z((m, 2), i), z(m), np.array(friction_speeds, dtype=i),
                   np.array(friction_slots, dtype=i), z(nf), np.full(nf, STICK, i), z(nf))


@jit
def coefficients(model, w, s, p):
    """Each contact's restitution (its impact jump's coefficient) and mu (its stop's; 0 without friction), and each
    joint friction's force (the leaf's entry nj + i), into s."""
    call(model.restitution, (p, w.S))
    for i in range(s.fbound.shape[0]):
        s.fbound[i] = w.S[model.s_e, model.nj + i]
    for k in range(model.nj):
        i = model.jump_contact[k]
        if i >= 0:
            s.e[i] = w.S[model.s_e, k]
    for i in range(model.contact_rows.shape[0]):
        s.cmu[i] = w.S[model.s_e, model.contact_mu[i]] if model.contact_mu[i] >= 0 else 0.0
    s.tree[0] = 1 if _tree_pays(model) else 0


@jit
def _tree_pays(model):
    """Whether the step factors M along its tree (M = L^T D L, linalg.ltdl: no fill-in) rather than densely: where
    the model has a tree (MASS_PARENT) whose factor has at most 3/4 of the dense one's entries below the diagonal
    (the sum of the speeds' depths against n (n - 1) / 2): a floating base's legs, bodies side by side; a chain,
    whose M is full, keeps the dense Cholesky (unrolled up to linalg.UNROLLED speeds)."""
    n = model.nv
    if model.mass_order.shape[0] != n or n < 2:
        return False
    entries = 0
    for k in range(n):
        i = model.mass_parent[k]
        while i >= 0:
            entries += 1
            i = model.mass_parent[i]
    return 4 * entries <= 3 * (n * (n - 1) // 2)


@jit
def _factor(model, M, tree):
    """M <- a square root R of M = R^T R, in place: along the tree (sparse_rows.tree_factor: R = D^1/2 L) or dense
    (linalg.cholesky: R = L^T); False when M is not positive definite."""
    if tree:
        return tree_factor(model, M)
    return cholesky(M, model.nv, 0.0)


@jit
def _lower(model, M, b, tree):
    """b[:nv] <- R^-T b, M factored by _factor. Returns the first and one past the last entry of the result that
    may be nonzero. Along the tree, a speed whose entry is still zero adds nothing to its ancestors and is skipped
    (a foot's row reaches its leg and the base, not the other legs)."""
    n = model.nv
    if not tree:
        solve_lower(M, b, n)
        lo = 0
        while lo < n and b[lo] == 0.0:
            lo += 1
        return lo, n
    parent, order = model.mass_parent, model.mass_order
    lo, hi = n, 0
    for kk in range(n):                 # L^T y = b: descendants first (sparse_rows.tree_lower)
        k = order[kk]
        v = b[k]
        if v == 0.0:
            continue
        i = parent[k]
        while i >= 0:
            b[i] -= M[k, i] * v
            i = parent[i]
        b[k] = v * M[k, k]
        lo, hi = min(lo, k), max(hi, k + 1)
    return lo, max(hi, lo)


@jit
def _upper(model, M, b, tree):
    """b[:nv] <- R^-1 b, M factored by _factor."""
    if tree:
        tree_upper(model, M, b)
    else:
        solve_upper(M, b, model.nv)


@jit(inline="always")
def _block(s, m, nb, kind, owner, mu, guess, gx, gy):
    """Append a block of `kind` (its rows already in s.rows from m) as block nb; returns the next free row."""
    s.kind[nb] = kind
    s.first[nb] = m
    s.owner[nb] = owner
    s.mu[nb] = mu
    s.state[nb] = guess
    s.direction[2 * nb] = gx
    s.direction[2 * nb + 1] = gy
    return m + size(kind)


@jit
def step(model, w, s, theta, inputs, data, t, h, x, u, p, d, flow):
    """x (the state, then the work) from t to t + h, in place, the contacts' modes of the step into d, and each
    row's impulse into s.total (s.seen 1 where it took part). Returns a status (module docstring)."""
    nq, nv, nx, nc = model.nq, model.nv, model.nx, model.contact_rows.shape[0]
    S, M, G = w.S, w.M, w.G
    v, a, xm, xdot = s.v, s.a, s.xm, s.xdot
    for j in range(nv):
        v[j] = x[nq + j]
    for j in range(x.shape[0]):
        xm[j] = x[j]
    for j in range(nq):
        xm[j] += theta * h * v[j]
    tm = t + theta * h
    if model.ns > 0:                                    # (the signals' rates at the step's start)
        call(model.signal_rates, (t, x, u, p, d, xdot))
        for j in range(nq + nv, nx):
            xm[j] += theta * h * xdot[j]
    if update_inputs(inputs, tm, xm, p, d, flow, u, data) != OK:
        return INPUT_FAILED
    call(model.constraints_into, (tm, xm, u, p, d, S))
    call(model.dynamics, (tm, xm, u, p, d, M, G))
    tree = s.tree[0] == 1
    if not _factor(model, M, tree):
        return SINGULAR_MASS
    for j in range(nv):                                 # a = v_free = v + h M^-1 G
        a[j] = G[j]
    _lower(model, M, a, tree)
    _upper(model, M, a, tree)
    for j in range(nv):
        a[j] = v[j] + h * a[j]
    for j in range(model.nw):                           # the elements' work at the step's forces (first order)
        x[nx + j] += h * G[nv + j]
    # The step's problem: the flow's own rows, then each touching contact's block (normal row first).
    m, nb = 0, 0
    for r in range(model.flow_nrows[flow]):
        s.rows[m] = model.flow_rows[flow, r]
        m = _block(s, m, nb, BILATERAL, -1, 0.0, 1, 0.0, 0.0)
        nb += 1
    for i in range(nc):
        n = model.contact_rows[i]
        closed = d[model.contact_mode[i]] != 0.0
        near = KEEP if closed else TOUCHING             # (hysteresis: see KEEP)
        u_free = S[model.s_cv, n]                       # (the normal speed at the free velocity: A v_free + b)
        for j in range(nv):
            u_free += S[model.s_a + n, j] * (a[j] - v[j])
        if closed and u_free > 0.0:                     # (a closed contact's free rise is not counted: see the
            u_free = 0.0                                #  module docstring)
        if S[model.s_phi, n] + (1.0 - theta) * h * u_free > near:       # the gap predicted at the step's end
            s.guess[i] = -1
            continue
        t1, kind = model.contact_stick[i], NORMAL
        if t1 >= 0:
            kind = SPATIAL if model.contact_tangents[i] == 2 else PLANAR
        s.rows[m] = n
        if t1 >= 0:
            s.rows[m + 1] = t1
            if kind == SPATIAL:
                s.rows[m + 2] = t1 + 1
        guess = s.guess[i] if s.guess[i] >= 0 else 1
        if kind == SPATIAL and guess == 2 and s.guess_dir[i, 0] == 0.0 and s.guess_dir[i, 1] == 0.0:
            guess = 1                                   # (a slide with no direction yet: try sticking first)
        m = _block(s, m, nb, kind, i, s.cmu[i], guess, s.guess_dir[i, 0], s.guess_dir[i, 1])
        nb += 1
    for i in range(s.fspeed.shape[0]):                  # each joint friction: |P| <= F h on its speed (row -1 - j)
        if s.fbound[i] > 0.0:
            s.rows[m] = -1 - s.fspeed[i]
            m = _block(s, m, nb, BOUNDED, -2 - i, s.fbound[i] * h, s.fguess[i], 0.0, 0.0)
            nb += 1
    if m > 0:
        # (int(): m and nb start as the literal 0, and Numba would compile a second _impulses for Literal[int](0))
        impulse_work = _impulses(model, w, s, int(m), int(nb), v, a, tree)
        if model.nj > 0:
            x[nx + model.nw - 1] += impulse_work
        for i in range(s.fspeed.shape[0]):
            x[nx + s.fslot[i]] += s.fwork[i]
            s.fwork[i] = 0.0
    # q_{k+1}, the signals, v_{k+1} (in a)
    for j in range(nq):
        x[j] += h * ((1.0 - theta) * v[j] + theta * a[j])
    if model.ns > 0:
        for j in range(nv):
            xm[nq + j] = (1.0 - theta) * v[j] + theta * a[j]
        call(model.signal_rates, (tm, xm, u, p, d, xdot))
        for j in range(nq + nv, nx):
            x[j] += h * xdot[j]
        normalize(model, x)
    for j in range(nv):
        x[nq + j] = a[j]
    _modes(model, s, nb, d)
    return _corrections(model, w, s, t + h, h, x, u, p, d, flow, tree)


@jit
def _impulses(model, w, s, m, nb, v, vel, tree):
    """Solve the step's problem over s.rows' first m rows (nb blocks); vel: the free velocity in, v_{k+1} out;
    v: v_k. Each row's impulse into s.total (and s.seen), its normal speed after into s.w0, the blocks' states into
    s.state (and s.direction); returns the impulses' work P . (A v_{k+1/2} + b), but the joint frictions' (their
    rows -1 - j: the speed j), which goes to s.fwork. W = A M^-1 A^T = C C^T with
    C = A R^-1 (one triangular solve a row, the tree's skipping the speeds a row does not reach), each entry over
    the speeds where both rows may be nonzero, the lower triangle mirrored; solved part by part where the blocks
    fall into parts that share no speed (_parts: boxes side by side), each part's W alone."""
    S, M, nv = w.S, w.M, model.nv
    C = s.X[:m * nv].reshape((m, nv))
    w0, span = s.w0[:m], s.span
    for r in range(m):                                  # C = A R^-1, row by row; w0 = A v_free + b (b = c - A v_k)
        row = s.rows[r]
        Cr = C[r]
        if row < 0:                                     # (a joint friction's: its speed -1 - row)
            for j in range(nv):
                Cr[j] = 0.0
            Cr[-1 - row] = 1.0
            s.av[r] = v[-1 - row]
            w0[r] = vel[-1 - row]
            span[r, 0], span[r, 1] = _lower(model, M, Cr, tree)
            continue
        av, af = 0.0, 0.0
        for j in range(nv):
            a = S[model.s_a + row, j]
            Cr[j] = a
            av += a * v[j]
            af += a * vel[j]
        w0[r] = af + S[model.s_cv, row] - av
        s.av[r] = av
        span[r, 0], span[r, 1] = _lower(model, M, Cr, tree)
    for k in range(nb):                                 # Newton's law: u_n,k+1 + e min(u_n,k, 0) >= 0
        if s.owner[k] >= 0:
            w0[s.first[k]] += s.e[s.owner[k]] * min(S[model.s_cv, s.rows[s.first[k]]], 0.0)
    parts = _parts(s, nb, nv)
    if parts == 1:
        W = s.W[:m * m].reshape((m, m))
        _gram(C, span, W, 0, m)
        _soften(s, W, 0, nb, 0)
        sweeps, verified = solve(W, w0, s.kind[:nb], s.first[:nb], s.mu[:nb], s.state[:nb],
                                 s.direction[:2 * nb].reshape((nb, 2)), s.P[:m], s.work)
    else:
        sweeps, verified = _solve_parts(s, C, span, w0, parts)
    s.stats[1] += sweeps
    if not verified:
        s.stats[2] += 1
    col = s.col                                         # v_{k+1} = v_free + R^-1 C^T P
    for j in range(nv):
        col[j] = 0.0
    for r in range(m):
        P = s.P[r]
        if P != 0.0:
            Cr = C[r]
            for j in range(span[r, 0], span[r, 1]):
                col[j] += Cr[j] * P
    _upper(model, M, col, tree)
    for j in range(nv):
        vel[j] += col[j]
    work = 0.0
    for r in range(m):                                  # A v_{k+1} + b, and P . (A v_{k+1/2} + b), b = c - A v_k
        row = s.rows[r]
        if row < 0:                                     # (a joint friction: its speed's own)
            w0[r] = vel[-1 - row]
            continue
        after = 0.0
        for j in range(nv):
            after += S[model.s_a + row, j] * vel[j]
        b = S[model.s_cv, row] - s.av[r]
        w0[r] = after + b
        work += s.P[r] * (0.5 * (s.av[r] + after) + b)
        s.total[row] += s.P[r]
        s.seen[row] = 1.0
    for k in range(nb):
        if s.owner[k] <= -2:
            r = s.first[k]
            s.fwork[-2 - s.owner[k]] += s.P[r] * 0.5 * (s.av[r] + w0[r])
    return work


@jit(inline="always")
def _gram(C, span, W, r0, n):
    """W[:n, :n] <- C C^T over C's rows r0 .. r0 + n - 1, each entry over the speeds where both rows may be nonzero
    (span), symmetric."""
    for r in range(n):
        Cr, lo_r, hi_r = C[r0 + r], span[r0 + r, 0], span[r0 + r, 1]
        for q in range(r + 1):
            lo, hi = max(lo_r, span[r0 + q, 0]), min(hi_r, span[r0 + q, 1])
            Cq = C[r0 + q]
            total = 0.0
            for j in range(lo, hi):
                total += Cr[j] * Cq[j]
            W[r, q] = total
            W[q, r] = total


@jit(inline="always")
def _soften(s, W, k0, k1, r0):
    """Each joint friction's diagonal entry of W (blocks k0 .. k1 - 1, whose rows start at r0) times 1 + COMPLIANCE:
    a stuck joint creeps at COMPLIANCE times the speed its load would give it in a step (MuJoCo regularizes its
    frictionloss rows alike). Why: a robot standing with its joints stuck has more rows than speeds, and some
    nearly dependent (a hip's friction beside a foot's tangent rows: W's singular values down to 1e-15 of the
    largest), whose least-squares answers leave 1e-9 inconsistent and share the load by rounding; softened, the
    step's problem is regular and its answer the one that asks the joints' friction the least."""
    for k in range(k0, k1):
        if s.kind[k] == BOUNDED:
            f = s.first[k] - r0
            W[f, f] *= 1.0 + COMPLIANCE


@jit
def _solve_parts(s, C, span, w0, parts):
    """The step's problem part by part (_parts), each part's W alone; returns (sweeps, verified) over them all."""
    used, sweeps, verified = 0, 0, True
    for c in range(parts):
        k0, k1 = s.cut[c], s.cut[c + 1]
        r0, r1 = s.first[k0], s.first[k1 - 1] + size(s.kind[k1 - 1])
        n = r1 - r0
        W = s.W[used:used + n * n].reshape((n, n))
        used += n * n
        _gram(C, span, W, r0, n)
        _soften(s, W, k0, k1, r0)
        for k in range(k0, k1):
            s.first[k] -= r0
        part_sweeps, part_verified = solve(W, w0[r0:r1], s.kind[k0:k1], s.first[k0:k1], s.mu[k0:k1], s.state[k0:k1],
                                           s.direction[2 * k0:2 * k1].reshape((k1 - k0, 2)), s.P[r0:r1], s.work)
        for k in range(k0, k1):
            s.first[k] += r0
        sweeps += part_sweeps
        verified = verified and part_verified
    return sweeps, verified


@jit(inline="always")
def _parts(s, nb, nv):
    """The blocks' independent parts: runs of consecutive blocks whose rows (of C) reach speed intervals that meet
    no other run's, so that W is zero between runs (bodies side by side; a robot's feet all meet at its base: one
    part). s.cut[c] the first block of run c, s.cut[parts] = nb; returns the number of parts, 1 where runs would
    interleave (a block meeting an earlier run but the last: kept as one problem)."""
    parts = 0
    for k in range(nb):
        lo, hi = nv, 0
        for r in range(s.first[k], s.first[k] + size(s.kind[k])):
            if s.span[r, 0] < s.span[r, 1]:
                lo, hi = min(lo, s.span[r, 0]), max(hi, s.span[r, 1])
        for c in range(parts - 1):
            if lo < s.runs[c, 1] and hi > s.runs[c, 0]:
                s.cut[0], s.cut[1] = 0, nb
                return 1
        if parts > 0 and (lo >= hi or (lo < s.runs[parts - 1, 1] and hi > s.runs[parts - 1, 0])):
            s.runs[parts - 1, 0] = min(s.runs[parts - 1, 0], lo)       # (joins the last run; an empty row too)
            s.runs[parts - 1, 1] = max(s.runs[parts - 1, 1], hi)
            continue
        s.cut[parts] = k
        s.runs[parts, 0], s.runs[parts, 1] = lo, hi
        parts += 1
    s.cut[parts] = nb
    return parts


@jit(inline="always")
def _modes(model, s, nb, d):
    """Each contact's mode of the step into d (and its warm start): open out of the index set or leaving it (its
    normal speed after the step above REST_SPEED: a bounce), else the solver's state."""
    for i in range(model.contact_rows.shape[0]):
        s.landed[i] = 1 if d[model.contact_mode[i]] == 0.0 else 0
        if s.guess[i] < 0:
            d[model.contact_mode[i]] = 0.0
            s.landed[i] = 0
    for k in range(nb):
        i = s.owner[k]
        if i <= -2:                                     # (a joint friction's: its warm start)
            s.fguess[-2 - i] = s.state[k]
        if i < 0:
            continue
        state = s.state[k]
        s.guess[i] = state
        s.guess_dir[i, 0] = s.direction[2 * k]
        s.guess_dir[i, 1] = s.direction[2 * k + 1]
        s.speed[i] = s.w0[s.first[k]]
        if s.w0[s.first[k]] > REST_SPEED:
            state = OPEN
            s.landed[i] = 0
        d[model.contact_mode[i]] = float(state)


@jit
def _corrections(model, w, s, t, h_step, x, u, p, d, flow, tree):
    """After the step: the flow's own rows back on their manifold (positions and speeds: dynamics.project with every
    contact open), then the gap of each closed contact further than PENETRATION from zero, and of each other one
    of the step's problem below -PENETRATION that its speed does not lift out within a step (h_step), put back on
    zero (positions only, the least change in the metric of M at the step's mid point, whose factor w.M holds: one
    linearized step, with the flow's holonomic rows held; tree: how the step factored M, _factor). Returns a
    status."""
    nc = model.contact_rows.shape[0]
    d_open = s.d_open
    for k in range(d.shape[0]):
        d_open[k] = d[k]
    for i in range(nc):
        d_open[model.contact_mode[i]] = 0.0
    if model.flow_nrows[flow] > 0:
        status = project(model, w, t, x, u, p, d_open, flow, bool(True), 0.0, -1.0)   # (bool(): linalg.correction)
        if status != OK:
            return status
        tree = False                                    # (w.M: project's dense factor at the step's end)
    if nc == 0:
        return OK
    S = w.S
    call(model.constraints_into, (t, x, u, p, d, S))
    off = False
    for i in range(nc):
        gap = S[model.s_phi, model.contact_rows[i]]
        closed = d[model.contact_mode[i]] != 0.0
        rising = s.guess[i] >= 0 and s.speed[i] * h_step > -gap         # (it leaves the surface by itself)
        if (closed and abs(gap) > PENETRATION) or (s.guess[i] >= 0 and gap < -PENETRATION and not rising):
            d_open[model.contact_mode[i]] = 1.0
            off = True
    if not off:
        return OK
    s.stats[3] += 1
    select_rows(model, w, flow, d_open)
    if tree:
        _correct_tree(model, w, w.nactive[1])
    else:
        correct_rows(model, w, w.nactive[1], model.s_phi, w.M)
    move(model, t, x, u, p, d, S[model.s_dv, :model.nv])
    return OK


@jit
def _correct_tree(model, w, nr):
    """S's dv row <- the least M-norm change with A dv = -phi over the first nr active rows, M factored along its
    tree (_factor): dynamics.correct_rows' dense path with the tree's R (C = A R^-1, dv = R^-1 C^+ (-phi))."""
    S, M, nv, c0 = w.S, w.M, model.nv, model.s_c
    for r in range(nr):
        row = w.active[0, r]
        for j in range(nv):
            S[c0 + r, j] = S[model.s_a + row, j]
        _lower(model, M, S[c0 + r], bool(True))     # (bool(): one compiled _lower for this and step's, linalg.correction)
        S[model.s_y, r] = -S[model.s_phi, row]
    solve_gram(model, S, nr, bool(True))        # (bool(): see linalg.correction)
    dv = S[model.s_dv, :nv]
    for j in range(nv):
        dv[j] = 0.0
    add_rows_transposed(model, S, nr, 1.0, dv)
    tree_upper(model, M, dv)


@jit(nogil=True)
def advance(model, w, s, theta, inputs, data, p, d, x, t, flow, i, i_end, t0, dt, every, log, forces, row):
    """Step from time t (on the grid point i: t = t0 + i dt) to the grid point i_end, or to a failure. x, d, the
    log and `forces` (N, NC: each row's mean force, its impulses over the `every` steps since the last sample
    divided by their time, NaN where it took no part) are updated in place; every `every`-th grid point is logged at log[row]; w.counts[0] += steps taken,
    w.counts[2] = the rows logged so far (for the watchdog: andyc.runtime.interrupts). Returns (i, row, status, t)."""
    u, counts = w.u, w.counts
    x, p, d = borrowed(x), borrowed(p), borrowed(d)
    if data is not None:
        data = borrowed(data)
    counts[2] = row
    scale = 1.0
    for j in range(model.nx):
        scale = max(scale, abs(x[j]))
    while i < i_end:
        status = step(model, w, s, theta, inputs, data, t, dt, x, u, p, d, flow)
        if status != OK:
            return i, row, status, t
        total, grown = 0.0, 0.0
        for j in range(model.nx):
            total += x[j]
            grown = max(grown, abs(x[j]))
        if not math.isfinite(total):
            return i, row, NONFINITE, t
        if grown > GROWTH_LIMIT * scale:
            return i, row, DIVERGED, t
        scale = max(scale, grown)
        i += 1
        t = t0 + i * dt
        counts[0] += 1
        s.stats[0] += 1
        if i % every == 0:
            if update_inputs(inputs, t, x, p, d, flow, u, data) != OK:
                return i, row, INPUT_FAILED, t
            log.t[row] = t
            log.x[row] = x
            log.u[row] = u
            log.flow[row] = flow
            log.d[row] = d
            for r in range(model.nc):           # (a sample every `every` steps: their mean force)
                forces[row, r] = s.total[r] / (dt * every) if s.seen[r] > 0.0 else np.nan
                s.total[r] = 0.0
                s.seen[r] = 0.0
            row += 1
            counts[2] = row
    return i, row, OK, t
