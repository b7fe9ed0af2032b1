"""The contact problem of one time step (andyc.runtime.timestepping): impulses P over the index set's rows.

With W = A M^-1 A^T over the rows (the model's bilateral rows, each contact's gap row and, with planar friction,
its stick row) and w0 the rows' velocity residuals at the free velocity, plus e_i u_n,k on each normal row
(Newton's law; Acary & Brogliato 2008, Numerical Methods for Nonsmooth Dynamical Systems, sec. 10.1):

    w = w0 + W P
    bilateral row:           w_b = 0                           (P_b free)
    frictionless contact:    0 <= w_n  _|_  P_n >= 0
    planar Coulomb contact:  0 <= w_n  _|_  P_n >= 0,  |P_t| <= mu P_n,
                             w_t = 0 where |P_t| < mu P_n,  P_t = -mu P_n sign(w_t) where w_t != 0

(the friction impulse acts against the slip after the step). With friction it is not an LCP with a symmetric
matrix, and W is only positive semi-definite when the rows are redundant (a block standing on two corners).

Algorithm, and why. The schema's contacts are few (andyc.spec.contacts: at most 16 flows), where
andyc.runtime.contacts enumerates the active sets of an impact; a time-stepping method is for scenes with many
contacts, where enumeration (up to 4^n cases) is not an option. So the step's problem is solved as Jean 1999
does (The non-smooth contact dynamics method, CMAME 177, sec. 5): nonlinear Gauss-Seidel over the contacts
(NSGS, a projected Gauss-Seidel whose local problem, one contact's normal and tangential impulses, is solved
exactly: open, sticking, sliding either way), each sweep O(rows^2). Gauss-Seidel converges only linearly (and
slowly where W is nearly singular), so its answer is then polished: the contact states it found (open, stick,
slip +, slip -) fix an active set, whose linear equations are solved by least squares (redundant rows allowed,
as in andyc.runtime.contacts) and checked against every inequality; a checked solution is exact to rounding,
one that fails the check leaves the Gauss-Seidel answer (counted: Solution.verified False). The last step's
states are tried first (a warm start: a resting or sliding contact keeps its state, and the step then costs one
least-squares solve, no sweep). No Python LCP library is kept well enough to depend on (Siconos' bindings are
not on PyPI for our Pythons; Lemke's pivoting would be a second, exact algorithm the polish already gives).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BILATERAL, NORMAL, PLANAR = 0, 1, 2         # a block's kind: a bilateral row; a contact; a contact with friction
OPEN, STICK, SLIP_POS, SLIP_NEG = 0, 1, 2, 3    # a contact's state (as andyc.runtime.contacts; closed = STICK)
SWEEPS = 500                # Gauss-Seidel sweeps at most (the polish makes the answer exact when it verifies)
SWEEP_TOL = 1e-15           # ... until no impulse changes by more than this, relative to the largest


@dataclass
class Block:
    kind: int
    rows: tuple             # indices into the problem's rows: (b,), (n,) or (n, t)
    mu: float = 0.0


@dataclass
class Solution:
    P: np.ndarray           # the impulses, one per row
    states: list            # per block: OPEN / STICK / SLIP_POS / SLIP_NEG (bilateral blocks: STICK)
    sweeps: int             # Gauss-Seidel sweeps taken (0: the warm start verified)
    verified: bool          # every equation and inequality holds to rounding


def solve(W: np.ndarray, w0: np.ndarray, blocks: list, guess: list | None = None) -> Solution:
    """The impulses P of the step's problem (the module's docstring); guess: the blocks' states to try first."""
    m = w0.shape[0]
    tol_v = 1e-10 * max(1.0, float(np.max(np.abs(w0)))) if m else 0.0
    if guess is not None:
        P = _polish(W, w0, blocks, guess, tol_v)
        if P is not None:
            return Solution(P, list(guess), 0, True)
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
    states = _states(W, w0, P, blocks)
    polished = _polish(W, w0, blocks, states, tol_v)
    if polished is not None:
        return Solution(polished, states, sweeps, True)
    return Solution(P, states, sweeps, False)


def _local(Wl: np.ndarray, w: np.ndarray, b: Block) -> np.ndarray:
    """One block's impulses with the others held (w: its velocities without its own impulse): exact."""
    if b.kind == BILATERAL:
        return np.array([-w[0] / Wl[0, 0]]) if Wl[0, 0] > 0.0 else np.zeros(1)
    if b.kind == NORMAL:
        return np.array([max(0.0, -w[0] / Wl[0, 0])]) if Wl[0, 0] > 0.0 else np.zeros(1)
    if w[0] >= 0.0:                          # open
        return np.zeros(2)
    det = Wl[0, 0] * Wl[1, 1] - Wl[0, 1] * Wl[1, 0]
    if abs(det) > 1e-14 * max(1e-300, Wl[0, 0] * Wl[1, 1]):     # sticking
        Pn = (-w[0] * Wl[1, 1] + w[1] * Wl[0, 1]) / det
        Pt = (-w[1] * Wl[0, 0] + w[0] * Wl[1, 0]) / det
        if Pn >= 0.0 and abs(Pt) <= b.mu * Pn:
            return np.array([Pn, Pt])
    for sigma in (1.0, -1.0):               # sliding forwards (w_t > 0, P_t = -mu P_n) or backwards
        k = Wl[0, 0] - sigma * b.mu * Wl[0, 1]
        if k > 0.0:
            Pn = -w[0] / k
            if sigma * (w[1] + (Wl[1, 0] - sigma * b.mu * Wl[1, 1]) * Pn) >= 0.0:
                return np.array([Pn, -sigma * b.mu * Pn])
    # (no local solution: W's tangential coupling reverses the slip, Painleve-like; the closest admissible one)
    Pn = max(0.0, -w[0] / Wl[0, 0])
    return np.array([Pn, float(np.clip(-w[1] / Wl[1, 1], -b.mu * Pn, b.mu * Pn)) if Wl[1, 1] > 0 else 0.0])


def _states(W, w0, P, blocks) -> list:
    """Each block's state as the impulses P say: open without a normal impulse, sticking inside the cone, else
    sliding against the tangential impulse."""
    scale = max(1e-300, float(np.max(np.abs(P)))) if P.size else 1.0
    out = []
    for b in blocks:
        if b.kind == BILATERAL:
            out.append(STICK)
            continue
        Pn = P[b.rows[0]]
        if Pn <= 1e-12 * scale:
            out.append(OPEN)
        elif b.kind == NORMAL:
            out.append(STICK)
        else:
            Pt = P[b.rows[1]]
            out.append(STICK if abs(Pt) < b.mu * Pn * (1 - 1e-9) else SLIP_POS if Pt < 0 else SLIP_NEG)
    return out


def _polish(W, w0, blocks, states, tol_v) -> np.ndarray | None:
    """The impulses of the active set `states` fixes (least squares), if they satisfy every condition; else None."""
    m = w0.shape[0]
    rows, columns = [], []
    for b, s in zip(blocks, states):
        if s == OPEN:
            continue
        n = b.rows[0]
        rows.append(n)
        column = np.zeros(m)
        column[n] = 1.0
        if b.kind == PLANAR and s == STICK:
            rows.append(b.rows[1])
            tangent = np.zeros(m)
            tangent[b.rows[1]] = 1.0
            columns += [column, tangent]
            continue
        if b.kind == PLANAR:
            column[b.rows[1]] = -b.mu if s == SLIP_POS else b.mu
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
    for b, s in zip(blocks, states):
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
            ok = abs(P[b.rows[1]]) <= b.mu * P[n] + tol_p
        else:
            ok = (1.0 if s == SLIP_POS else -1.0) * w[b.rows[1]] >= -tol_v
        if not ok:
            return None
    return P
