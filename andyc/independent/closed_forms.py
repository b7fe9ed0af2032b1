"""Closed forms for the constrained reference models (docs/reference-cases.md §3, and the four-bar).

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


def rolling_disk_lean_rate2(m: float, r: float, g: float, A: float, C: float, spin: float) -> float:
    """lambda^2 of the lean of a disk rolling upright and straight at spin rate `spin` (rad/s; forward speed
    r * spin), mass m, radius r, diametral and axial moments of inertia A and C about its centre.

    Linearized about the steady motion (lean th = 0), the lean and the heading psi obey (Routh, "Advanced
    Rigid Dynamics", 1905, the rolling disc; Neimark & Fufaev, "Dynamics of Nonholonomic Systems", 1972,
    ch. III):

        (A + m r^2) th'' = m g r th - (C + m r^2) spin psi',     A psi'' = C spin th',

    the first the moment about the contact's heading axis (gravity tips the disk, the gyroscopic moment of the
    spinning disk turning at psi' and the rolling constraint's force right it), the second the moment about the
    vertical. From rest in psi' the second integrates to psi' = (C spin / A) th, so th'' = lambda^2 th with

        lambda^2 = (m g r - (C + m r^2) C spin^2 / A) / (A + m r^2):

    lean is unstable (lambda real) while lambda^2 > 0 and oscillates at |lambda| beyond."""
    return (m * g * r - (C + m * r * r) * C * spin * spin / A) / (A + m * r * r)


def rolling_disk_critical_spin(m: float, r: float, g: float, A: float, C: float) -> float:
    """The least spin rate at which upright rolling is stable: lambda^2 = 0 in rolling_disk_lean_rate2,
    spin^2 = A m g r / (C (C + m r^2)); for a thin uniform disk (A = m r^2/4, C = m r^2/2), g / (3 r): a
    forward speed of sqrt(g r / 3)."""
    return float(np.sqrt(A * m * g * r / (C * (C + m * r * r))))
