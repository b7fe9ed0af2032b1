"""Fixed-step classical Runge-Kutta (RK4), the whole loop compiled by Numba.

    k1 = f(t, x)               k2 = f(t + h/2, x + h/2 k1)
    k3 = f(t + h/2, x + h/2 k2) k4 = f(t + h, x + h k3)
    x <- x + h/6 (k1 + 2 k2 + 2 k3 + k4)

`rk4_chunk` advances a block of steps and returns to Python, which reports
progress between blocks; the model's `rhs_into` is passed in as a compiled
function, so each model gets its own specialised loop. With `do_project`, the
model's `project` runs after every step: it puts quaternion signals back on
the unit sphere (its cost and effect are measured in bench/run.py) and, with
`constrain` and `energy_tol`, applies the Braun & Goldfarb position,
velocity and energy corrections (the `projection` method).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

OK, NONFINITE, SINGULAR_MASS, DEPENDENT = 0, 1, 2, 3     # as in the generated module


@njit(cache=False)
def rk4_chunk(rhs_into, project, do_project, constrain, e0, energy_tol, t0, dt, step0, n_steps, every,
              x, u, p, out_t, out_x, row, M, G, k, xt):
    """Advance x (in place) from step index step0 by up to n_steps steps.

    Time is t0 + i dt (no accumulated round-off). Every `every`-th step is
    stored in out_t[row], out_x[row], row incremented.
    Returns (steps done, next row, status).
    """
    nx = x.shape[0]
    h = dt
    for s in range(n_steps):
        i = step0 + s
        t = t0 + i * h
        status = rhs_into(t, x, u, p, k[0], M, G)
        if status != OK:
            return s, row, status
        for j in range(nx):
            xt[j] = x[j] + 0.5 * h * k[0, j]
        status = rhs_into(t + 0.5 * h, xt, u, p, k[1], M, G)
        if status != OK:
            return s, row, status
        for j in range(nx):
            xt[j] = x[j] + 0.5 * h * k[1, j]
        status = rhs_into(t + 0.5 * h, xt, u, p, k[2], M, G)
        if status != OK:
            return s, row, status
        for j in range(nx):
            xt[j] = x[j] + h * k[2, j]
        status = rhs_into(t + h, xt, u, p, k[3], M, G)
        if status != OK:
            return s, row, status
        total = 0.0
        for j in range(nx):
            x[j] += h / 6.0 * (k[0, j] + 2.0 * k[1, j] + 2.0 * k[2, j] + k[3, j])
            total += x[j]
        if not math.isfinite(total):
            return s + 1, row, NONFINITE
        if do_project:
            status = project(t + h, x, u, p, constrain, e0, energy_tol, M, G)
            if status != OK:
                return s + 1, row, status
        if (i + 1) % every == 0:
            out_t[row] = t0 + (i + 1) * h
            for j in range(nx):
                out_x[row, j] = x[j]
            row += 1
    return n_steps, row, OK


@njit(cache=False)
def evaluate_energy(energy, t, X, u, p, out):
    for r in range(t.shape[0]):
        out[r] = energy(t[r], X[r], u, p)


@njit(cache=False)
def evaluate_frames(frame_positions, t, X, u, p, out):
    for r in range(t.shape[0]):
        frame_positions(t[r], X[r], u, p, out[r])


@njit(cache=False)
def evaluate_constraints(constraints, multipliers, t, X, u, p, phi, c, lam, M, G):
    """Residuals phi (N, NH), c (N, NC) and multipliers lam (N, NC) at the logged samples."""
    nc = c.shape[1]
    A = np.empty((nc, M.shape[0]))
    kappa = np.empty(nc)
    for r in range(t.shape[0]):
        constraints(t[r], X[r], u, p, phi[r], c[r], A, kappa)
        if multipliers(t[r], X[r], u, p, lam[r], M, G) != OK:
            lam[r, :] = np.nan
