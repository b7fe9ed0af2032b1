"""Closed forms for the constrained reference models (REFERENCE-CASES sections 3, and the four-bar).

Written from the mechanics, not from andyc's derivation, so tests and
benchmarks can hold andyc's runs against them.
"""

from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp


def ball_first_integral(run, r: float, R: float) -> np.ndarray:
    """b' cos^2 a + 2 r / (7 (R - r)) w_rho sin a along a ball_in_bowl run (Braun & Goldfarb Part II, Fig. 2).

    w_rho is the ball's absolute spin about e_rho. Frame c has its x axis along
    e_rho and turns at (-b' sin a, a', b' cos a) in its own axes; the ball turns
    at R(quat) w_body relative to it, so w_rho = -b' sin a + (R(quat) w_body)_x.
    """
    a, db = run.column("alpha"), run.column("beta_dot")
    w = np.column_stack([run.column(k) for k in ("wx", "wy", "wz")])
    qw, qx, qy, qz = (run.column(f"ball_q{k}") for k in "wxyz")
    first_row = np.column_stack([1 - 2 * (qy ** 2 + qz ** 2), 2 * (qx * qy - qw * qz), 2 * (qx * qz + qw * qy)])
    w_rho = -db * np.sin(a) + (first_row * w).sum(axis=1)
    return db * np.cos(a) ** 2 + 2 * r / (7 * (R - r)) * w_rho * np.sin(a)


def fourbar_branch(p: dict, th0: float, w0: float, times) -> tuple:
    """(th, th') of the parallelogram four-bar's crank on its parallelogram branch, at `times`.

    The coupler translates, so th1 = th3 = th and the mechanism is one physical
    pendulum: (I1 + I3 + m2 a^2) th'' = -g a (m1/2 + m2 + m3/2) cos th, with
    uniform rods I1 = m1 a^2/3, I3 = m3 a^2/3 about their pins. Integrated by
    DOP853 at rtol = atol = 1e-13.
    """
    a, m1, m2, m3, g = (p[k] for k in ("a", "m1", "m2", "m3", "g"))
    inertia = (m1 + m3) * a ** 2 / 3 + m2 * a ** 2
    k = g * a * (m1 / 2 + m2 + m3 / 2)
    sol = solve_ivp(lambda t, y: [y[1], -k / inertia * np.cos(y[0])], (0.0, float(times[-1])), [th0, w0],
                    method="DOP853", rtol=1e-13, atol=1e-13, dense_output=True)
    th, w = sol.sol(times)
    return th, w


def fourbar_crank_angle(p: dict, th0: float, w0: float, times) -> np.ndarray:
    """The crank angle th of `fourbar_branch`."""
    return fourbar_branch(p, th0, w0, times)[0]
