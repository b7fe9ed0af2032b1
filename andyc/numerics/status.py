"""Codes shared by the compiled numerics and andyc's runtime, each written once (as SciPy's solve_ivp keeps its
status messages in one table). Plain Python: no Numba, no NumPy."""

# What a compiled function returns.
OK, NONFINITE, SINGULAR_MASS, DEPENDENT, INPUT_FAILED, DIVERGED, PAINLEVE = 0, 1, 2, 3, 4, 5, 6
MESSAGES = {
    NONFINITE: "the state became non-finite (NaN or Inf)",
    SINGULAR_MASS: "the mass matrix is not positive definite",
    DEPENDENT: "the constraint rows are linearly dependent (redundant constraints, or a singular configuration); "
               "the multipliers are not unique, use --method projection",
    INPUT_FAILED: "the inputs failed",
    DIVERGED: "the solution diverges: within one step the state grew past 1000 times its largest value so far "
              "(a step far too large for the dynamics, or a singular mass matrix or constraint)",
    PAINLEVE: "a slipping contact's normal force has no consistent value (Painleve's paradox: with its friction, "
              "pushing would pull the contact open faster, A_n M^-1 (A_n - sigma mu J_t)^T <= 0); rigid contact with "
              "Coulomb friction has no solution here: lower mu, or change the contact's geometry",
}

# How the constraint forces of a flow are found (see dynamics.constraint_force).
IDEAL, LAGRANGE, BAUMGARTE = 0, 1, 2

# The direction in which a guard must cross zero for its jump to happen.
FALLING, EITHER, RISING = -1, 0, 1

# An input callback's failure record in its data (inputs.py): its kind, t, the number of values returned, then x.
RECORD = 3
RAISED, WRONG_SHAPE = 1.0, 2.0

GROWTH_LIMIT = 1e3  # a step that grows the state past this factor of its largest so far: DIVERGED
RANK_TOL = 1e-8     # singular values below RANK_TOL * the largest count as zero (redundant rows, singular poses)
REST_SPEED = 1e-9   # a contact approaching slower than this takes no impact; one this slow after an impact closes
ON_ZERO = 1e-12     # a gap this close to zero (relative to the state's scale beyond 1) is on zero
ON_CONE = 1e-10     # a guard of forces this close to zero (relative to the largest force beyond 1) is on zero, at
#                     an instant (integrator.instant): more than the runtime's choice of modes allows (1e-12)
OPEN_SIDE = float("inf")    # what a gap on zero that is opening starts a step with (integrator.advance,
#                             runtime.adaptive): positive, of no known size, so that the root search bisects until
#                             a trial finds it open (regula falsi from 0+ would try the step's start again and again)
HOLD = 0.5          # a fixed step holds a spatial slip's direction where h times its rate exceeds this (slip_direction)
SLIP_TINY = 1e-13   # m/s: a spatial slip at most this slow has no direction of its own (slipping.slip_unit)
SLIP_STOP = -2      # JUMP_CONTACT of a contact's slip ending (andyc.spec.contacts): not an impact, and at once
#                     (integrator.instant) only when its slip speed reverses faster than a rounding
