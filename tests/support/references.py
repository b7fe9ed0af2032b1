"""Independent references that several test modules check against: the rocking block's free rocking by quadrature
and Housner's ratio (the derivation: tests/test_rocking_block.py's docstring), and a block sliding on an incline
with spatial Coulomb friction by SciPy's DOP853 on its equations (tests/test_spatial_friction.py)."""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import quad

# -- the rocking block (models/rocking_block.yaml; Housner 1963) ----------------------------------------------

M, B, H, G, TH0 = 1.0, 0.2, 0.6, 9.81, 0.2           # models/rocking_block.yaml's defaults
R = math.hypot(B, H)
ALPHA = math.atan2(B, H)
I_O = 4 * M * R ** 2 / 3
K = 2 * M * G * R / I_O
RATIO = 1 - 1.5 * math.sin(ALPHA) ** 2


def quarter_period(A: float) -> float:
    """T(A)/4, the time from amplitude A to level, by quadrature (tests/test_rocking_block.py's docstring)."""
    if A <= 0.0:
        return 0.0

    def integrand(s):
        return 2 * s / math.sqrt(2 * K * math.sin(ALPHA - A + s * s / 2) * math.sin(s * s / 2))

    return quad(integrand, 0.0, math.sqrt(A), epsabs=0.0, epsrel=1e-13, limit=200)[0]


def amplitude(w: float) -> float:
    """The tilt at which a block leaving level at angular speed w stops: cos(alpha - A) = cos(alpha) + w^2 / k."""
    return ALPHA - math.acos(min(1.0, math.cos(ALPHA) + w * w / K))


def impact_times(n: int) -> np.ndarray:
    """The first n impact times, from the quadrature and the closed-form ratio."""
    w = math.sqrt(K * (math.cos(ALPHA - TH0) - math.cos(ALPHA)))      # at the first impact
    times = [quarter_period(TH0)]
    while len(times) < n:
        w *= RATIO
        times.append(times[-1] + 2 * quarter_period(amplitude(w)))
    return np.array(times)


# -- a block pushed across an incline (models/block_incline_spatial.yaml) -------------------------------------

def sliding_reference(th, mu, v0, t_end):
    """An independent integration (SciPy DOP853) of a point sliding on the incline, in the slope's coordinates
    (s up the slope, w across): s'' = -g sin th - mu g cos th s'/|v|, w'' = -mu g cos th w'/|v|, from rest at the
    origin with speed v0 across. Returns the dense solution and the time it stops (None if it slides to t_end):
    located where |v| = 1e-7, then the rest by d|v|/dt there (|v| falls linearly at the end: its error is
    far below 1e-12 s)."""
    from scipy.integrate import solve_ivp

    def rhs(t, y):
        speed = math.hypot(y[2], y[3])
        friction = mu * G * math.cos(th) / speed
        return [y[2], y[3], -G * math.sin(th) - friction * y[2], -friction * y[3]]

    def slow(t, y):
        return math.hypot(y[2], y[3]) - 1e-7
    slow.terminal = True
    sol = solve_ivp(rhs, (0.0, t_end), [0.0, 0.0, 0.0, v0], method="DOP853", rtol=1e-13, atol=1e-14,
                    dense_output=True, events=slow)
    if not sol.t_events[0].size:
        return sol.sol, None
    speed = sol.y_events[0][0][2:]
    size = np.linalg.norm(speed)
    rate = -G * math.sin(th) * speed[0] / size - mu * G * math.cos(th)
    return sol.sol, sol.t_events[0][0] - size / rate


def slope_coordinates(run, th):
    return (math.cos(th) * run.column("x") + math.sin(th) * run.column("z"), run.column("y"))
