"""The classical Runge-Kutta method's Butcher tableau, the one every RK4 step of andyc takes (the integrator's,
integrator.rk4_step, and its tangent's, tangents.rk4_tangent), as MuJoCo writes its RK4 from one tableau.

    c = (0, 1/2, 1/2, 1)          stage s evaluates at t + c_s h, at the state x + a_s h k_(s-1)
    a = (-, 1/2, 1/2, 1)          (the tableau's only entries below the diagonal: a_(s, s-1))
    b = (1, 2, 2, 1) / 6          x' = x + h/6 (k_0 + 2 k_1 + 2 k_2 + k_3)

The weights are kept as the integers over their common divisor, so that x' is computed as h/6 times the
weighted sum: the steps are the same to the bit as written out by hand.
"""

STAGES = 4
C = (0.0, 0.5, 0.5, 1.0)
A = (0.0, 0.5, 0.5, 1.0)        # a_(s, s-1); A[0] unused (the first stage is at x)
B = (1.0, 2.0, 2.0, 1.0)        # b_s times DIVISOR
DIVISOR = 6.0
