"""An LQR controller that balances the cart-pole (cart_pole.yaml) at the upright.

Designed from andyc's linearization about the upright at rest (the A and B that
`andyc linearize models/cart_pole.yaml --at th=0` prints), with SciPy's Riccati
solver:

    A^T P + P A - P B R^-1 B^T P + Q = 0,    K = R^-1 B^T P,    F = -K x

Run it:  andyc sim models/cart_pole.yaml --controller models/cart_pole_lqr.py --t-end 5
x is the state (x, th, x_dot, th_dot); d and p are the discrete states and parameters.
"""

from pathlib import Path

import numpy as np
from scipy.linalg import solve_continuous_are

import andyc
from andyc.symbolic.linearize import default_point, linearize

MODEL = andyc.derive(andyc.load(Path(__file__).with_name("cart_pole.yaml")))
x_up, u_up, p_default, d_default = default_point(MODEL)
x_up[:] = 0.0                                   # upright, at rest
LINEAR = linearize(MODEL, x_up, u_up, p_default, d_default)
Q = np.diag([10.0, 100.0, 1.0, 1.0])            # weights on x, th, x_dot, th_dot
R = np.array([[0.01]])                          # weight on F
P = solve_continuous_are(LINEAR.A, LINEAR.B, Q, R)
K = np.linalg.solve(R, LINEAR.B.T @ P)[0]       # (4,): F = -K x


def control(t, x, d, p):
    return -np.dot(K, x)
