"""The numerics every generated module shares: constrained dynamics, projection, impacts and the
integrator with its event location (Braun & Goldfarb; ANDY eq. 8-19).

This package is static source. `andyc build` copies it verbatim into each build folder as
`andyc_numerics/`, and the generated module imports it from there, so that a build stands alone.
It never imports andyc. What depends on the model is only the model's own functions (the leaves:
M and G, the constraint rows, the energy, the guards, ...), compiled per model in
<name>_equations.py and handed to these algorithms through a compiled `Model` (model.py), as
MuJoCo's and Pinocchio's algorithms take a model and its data. So Numba compiles these
algorithms once per andyc version, for every model, and keeps them in a cache keyed by their
content (compiler.py), wherever the copy sits.

    status.py      statuses and their messages, how constraint forces are found, guard directions
    compiler.py    the `jit` and `cfunc` decorators and the content-keyed cache
    layout.py      the rows of the scratch array of the constrained solves
    model.py       Model (the compiled model: sizes, tables, the leaves' signatures) and Work (its arrays)
    stubs.py       leaves that do nothing, for the parts a model has none of
    linalg.py      Cholesky, triangular and Gram solves, unrolled for small sizes
    sparse_rows.py the Gram solves along the tree of M and the rows' supports (banded factor, SVD per block)
    active.py      the rows active at an instant: the flow's own and the closed contacts' (modes in d)
    dynamics.py    the right-hand side of a flow, the multipliers, projection and the impact map
    slipping.py    a slipping contact's forces: friction in the normal row, the non-symmetric solve
    contact_solver.py  the contact problem of a time step or an impact: impulses by Gauss-Seidel, then an
                   exact polish of the active set found
    dense_solves.py    the polish's dense solves: Cholesky, pivoted Cholesky, pivoted QR least squares
    timestepping.py    Moreau-Jean's time-stepping: one step's impulses from the contact problem
    integrator.py  RK4 with event location, the hybrid step, evaluations over a run's log
    batch.py       many runs of one model in one compiled call (the sweeps' batched engine)
    inputs.py      input callbacks: the model's and the run's, held values, tables
    api.py         the generated module's Python functions (rhs, mass_matrix, energy, ...)

Importing the package itself imports nothing heavy; andyc's runtime reads status.py from its own
copy (andyc.numerics.status) without Numba.
"""
