"""The contact problem of one time step, in Python: the twin of andyc.numerics.contact_solver (which the runtime
runs, compiled), kept as an independent implementation for its tests and benchmarks (tests/test_contact_solver.py,
bench/contact_solver.py): impulses P over the index set's rows.

With W = A M^-1 A^T over the rows (the model's bilateral rows, each contact's gap row and, with planar friction,
its stick row) and w0 the rows' velocity residuals at the free velocity, plus e_i u_n,k on each normal row
(Newton's law; Acary & Brogliato 2008, Numerical Methods for Nonsmooth Dynamical Systems, sec. 10.1):

    w = w0 + W P
    bilateral row:           w_b = 0                           (P_b free)
    frictionless contact:    0 <= w_n  _|_  P_n >= 0
    Coulomb contact:         0 <= w_n  _|_  P_n >= 0,  |P_t| <= mu P_n,
                             w_t = 0 where |P_t| < mu P_n,  P_t = -mu P_n w_t / |w_t| where w_t != 0
                             (planar: one tangent row, P_t a number; spatial: two, P_t in the disk)

(the friction impulse acts against the slip after the step). With friction it is not an LCP with a symmetric
matrix, and W is only positive semi-definite when the rows are redundant (a block standing on two corners).

Algorithm, and why. The schema's contacts are few (andyc.spec.contacts: at most 16 flows), where
andyc.runtime.contacts enumerates the active sets of an impact; a time-stepping method is for scenes with many
contacts, where enumeration (up to 4^n cases) is not an option. So the step's problem is solved as Jean 1999
does (The non-smooth contact dynamics method, CMAME 177, sec. 5): nonlinear Gauss-Seidel over the contacts
(NSGS, a projected Gauss-Seidel whose local problem, one contact's normal and tangential impulses, is solved
exactly: open, sticking, sliding either way; a spatial slide's direction by the secant method, else bisection),
each sweep O(rows^2). Gauss-Seidel converges only linearly (and slowly where W is nearly singular), so its
answer is then polished: the contact states it found (open, stick, slip +, slip -; a spatial slide with its
direction) fix an active set, whose linear equations are solved by least squares (redundant rows allowed, as in
andyc.runtime.contacts) and checked against every inequality; a checked solution is exact to rounding, one that
fails the check leaves the Gauss-Seidel answer (counted: Solution.verified False). The last step's solution is
tried first (a warm start: a resting or sliding contact keeps its state, and the step then costs one
least-squares solve, no sweep). No Python LCP library is kept well enough to depend on (PyPI's lemkelcp is a
0.1 of 2016; Siconos is not on PyPI), and Lemke's pivoting would not take Coulomb's disk.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

BILATERAL, NORMAL, PLANAR, SPATIAL = 0, 1, 2, 3     # a block's kind: a bilateral row; a contact; with friction
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3    # a contact's state (as andyc.runtime.contacts; closed = STICK)
SLIDE = 2                                       # spatial friction's one sliding state (andyc.spec.contacts)
SCAN = 36                   # spatial sliding: the slip directions tried around the circle before bisecting
SWEEPS = 500                # Gauss-Seidel sweeps at most (the polish makes the answer exact when it verifies)
SWEEP_TOL = 1e-15           # ... until no impulse changes by more than this, relative to the largest


@dataclass
class Block:
    kind: int
    rows: tuple             # indices into the problem's rows: (b,), (n,), (n, t) or (n, t1, t2)
    mu: float = 0.0


@dataclass
class Solution:
    P: np.ndarray           # the impulses, one per row
    states: list            # per block: OPEN / STICK / SLIP_POS / SLIP_NEG / SLIDE (bilateral blocks: STICK)
    sweeps: int             # Gauss-Seidel sweeps taken (0: the warm start verified)
    verified: bool          # every equation and inequality holds to rounding
    directions: list = None  # per block: a sliding spatial contact's unit slip direction after the step, else None


def solve(W: np.ndarray, w0: np.ndarray, blocks: list, guess: Solution | None = None) -> Solution:
    """The impulses P of the step's problem (the module's docstring); guess: a solution whose states (and slip
    directions) to try first."""
    m = w0.shape[0]
    tol_v = 1e-10 * max(1.0, float(np.max(np.abs(w0)))) if m else 0.0
    if guess is not None:
        directions = guess.directions or [None] * len(blocks)
        P = _polish(W, w0, blocks, guess.states, directions, tol_v)
        if P is not None:
            return Solution(P, list(guess.states), 0, True, list(directions))
    P = np.zeros(m)
    sweeps = 0
    for sweeps in range(1, SWEEPS + 1):
        change = 0.0
        for b in blocks:
            r = list(b.rows)
            old = P[r].copy()
            local = w0[r] + W[r] @ P - W[np.ix_(r, r)] @ old      # the block's velocities without its own impulse
            P[r] = _local(W[np.ix_(r, r)], local, b)
            change = max(change, float(np.max(np.abs(P[r] - old))))
        if change <= SWEEP_TOL * max(1e-300, float(np.max(np.abs(P)))):
            break
    states, directions = _states(P, blocks)
    polished = _polish(W, w0, blocks, states, directions, tol_v)
    if polished is not None:
        return Solution(polished, states, sweeps, True, directions)
    return Solution(P, states, sweeps, False, directions)


def _local(Wl: np.ndarray, w: np.ndarray, b: Block) -> np.ndarray:
    """One block's impulses with the others held (w: its velocities without its own impulse): exact."""
    if b.kind == BILATERAL:
        return np.array([-w[0] / Wl[0, 0]]) if Wl[0, 0] > 0.0 else np.zeros(1)
    if b.kind == NORMAL:
        return np.array([max(0.0, -w[0] / Wl[0, 0])]) if Wl[0, 0] > 0.0 else np.zeros(1)
    if w[0] >= 0.0:                          # open
        return np.zeros(len(b.rows))
    try:                                    # sticking
        P = np.linalg.solve(Wl, -w)
        if P[0] >= 0.0 and math.hypot(*P[1:]) <= b.mu * P[0]:
            return P
    except np.linalg.LinAlgError:
        pass
    if b.kind == SPATIAL:
        return _slide_spatial(Wl, w, b.mu)
    for sigma in (1.0, -1.0):               # sliding forwards (w_t > 0, P_t = -mu P_n) or backwards
        k = Wl[0, 0] - sigma * b.mu * Wl[0, 1]
        if k > 0.0:
            Pn = -w[0] / k
            if sigma * (w[1] + (Wl[1, 0] - sigma * b.mu * Wl[1, 1]) * Pn) >= 0.0:
                return np.array([Pn, -sigma * b.mu * Pn])
    return _closest(Wl, w, b.mu)


def _closest(Wl, w, mu) -> np.ndarray:
    """No local solution (W's tangential coupling reverses the slip, Painleve-like): the closest admissible one."""
    Pn = max(0.0, -w[0] / Wl[0, 0])
    Pt = np.array([-w[k] / Wl[k, k] if Wl[k, k] > 0 else 0.0 for k in range(1, len(w))])
    size = math.hypot(*Pt)
    return np.array([Pn, *(Pt * min(1.0, mu * Pn / size) if size > 0 else Pt)])


def _slide_spatial(Wl, w, mu) -> np.ndarray:
    """A spatial contact sliding: P = P_n (1, -mu d) with d = (cos a, sin a) the unit slip after, s = |s| d. For
    each d the normal row gives P_n; the slip's turn away from d, d x s, is found zero by the secant method from
    the slip's direction without friction, or else by scanning SCAN directions round the circle, then bisecting
    the first sign change with d . s > 0 to the last bit."""
    a, bn, c, T = Wl[0, 0], Wl[0, 1:], Wl[1:, 0], Wl[1:, 1:]

    def at(angle):
        d = np.array([math.cos(angle), math.sin(angle)])
        den = a - mu * (bn @ d)
        if den <= 0.0:
            return None
        Pn = -w[0] / den
        slip = w[1:] + (c - mu * (T @ d)) * Pn
        return d[0] * slip[1] - d[1] * slip[0], d @ slip, Pn, d

    # (first the secant method from the slip's direction without friction, exact at once where the tangential
    # inverse inertia is isotropic and uncoupled, as for a point mass)
    x0 = math.atan2(w[2], w[1])
    x1, f0 = x0 + 1e-6, at(x0)
    for _ in range(20):
        f1 = at(x1)
        if f0 is None or f1 is None:
            break
        if f1[1] > 0.0 and abs(f1[0]) <= 1e-15 * math.hypot(*w[1:]):
            _, _, Pn, d = f1
            return np.array([Pn, *(-mu * Pn * d)])
        if f1[0] == f0[0]:
            break
        x0, x1, f0 = x1, x1 - f1[0] * (x1 - x0) / (f1[0] - f0[0]), f1
    angles = np.linspace(0.0, 2 * math.pi, SCAN + 1)
    values = [at(x) for x in angles]
    for k in range(SCAN):
        lo, hi = values[k], values[k + 1]
        if lo is None or hi is None or lo[0] * hi[0] > 0.0 or max(lo[1], hi[1]) <= 0.0:
            continue
        x0, x1, f0 = angles[k], angles[k + 1], lo[0]
        for _ in range(60):
            xm = 0.5 * (x0 + x1)
            mid = at(xm)
            if mid is None or xm in (x0, x1):
                break
            if (mid[0] > 0.0) == (f0 > 0.0):
                x0, f0 = xm, mid[0]
            else:
                x1 = xm
        found = at(0.5 * (x0 + x1))
        if found is not None and found[1] >= 0.0:
            _, _, Pn, d = found
            return np.array([Pn, *(-mu * Pn * d)])
    return _closest(Wl, w, mu)


def _states(P, blocks) -> tuple:
    """Each block's state as the impulses P say: open without a normal impulse, sticking inside the cone, else
    sliding against the tangential impulse; and each sliding spatial contact's slip direction, -P_t / |P_t|."""
    scale = max(1e-300, float(np.max(np.abs(P)))) if P.size else 1.0
    out, directions = [], [None] * len(blocks)
    for k, b in enumerate(blocks):
        if b.kind == BILATERAL:
            out.append(STICK)
            continue
        Pn = P[b.rows[0]]
        Pt = P[list(b.rows[1:])]
        if Pn <= 1e-12 * scale:
            out.append(OPEN)
        elif b.kind == NORMAL or math.hypot(*Pt) < b.mu * Pn * (1 - 1e-9):
            out.append(STICK)
        elif b.kind == SPATIAL:
            out.append(SLIDE)
            directions[k] = -Pt / math.hypot(*Pt)
        else:
            out.append(SLIP_POS if Pt[0] < 0 else SLIP_NEG)
    return out, directions


def _polish(W, w0, blocks, states, directions, tol_v) -> np.ndarray | None:
    """The impulses of the active set `states` (and the sliding spatial contacts' `directions`) fixes (least
    squares), if they satisfy every condition; else None."""
    m = w0.shape[0]
    rows, columns = [], []
    for b, s, d in zip(blocks, states, directions):
        if s == OPEN:
            continue
        if b.kind != NORMAL and s == STICK:         # (a bilateral row, or a sticking contact: every row)
            for r in b.rows:
                rows.append(r)
                columns.append(np.eye(1, m, r)[0])
            continue
        n = b.rows[0]
        rows.append(n)
        column = np.eye(1, m, n)[0]
        if b.kind == PLANAR:
            column[b.rows[1]] = -b.mu if s == SLIP_POS else b.mu
        elif b.kind == SPATIAL:
            column[list(b.rows[1:])] = -b.mu * d
        columns.append(column)
    if rows:
        B = np.array(columns).T
        y = np.linalg.lstsq(W[rows] @ B, -w0[rows], rcond=None)[0]
        P = B @ y
    else:
        P = np.zeros(m)
    w = w0 + W @ P
    tol_p = 1e-12 * max(1e-300, float(np.max(np.abs(P)))) if m else 0.0
    if rows and np.max(np.abs(w[rows])) > tol_v:         # inconsistent equations (dependent rows, no solution)
        return None
    for b, s, d in zip(blocks, states, directions):
        if b.kind == BILATERAL:
            continue
        n = b.rows[0]
        if s == OPEN:
            ok = w[n] >= -tol_v
        elif P[n] < -tol_p:
            ok = False
        elif b.kind == NORMAL:
            ok = True
        elif s == STICK:
            ok = math.hypot(*P[list(b.rows[1:])]) <= b.mu * P[n] + tol_p
        elif b.kind == SPATIAL:
            slip = w[list(b.rows[1:])]          # along d: no turn away from it, not reversed
            ok = abs(d[0] * slip[1] - d[1] * slip[0]) <= tol_v and d @ slip >= -tol_v
        else:
            ok = (1.0 if s == SLIP_POS else -1.0) * w[b.rows[1]] >= -tol_v
        if not ok:
            return None
    return P
