"""Where the constrained solves keep their numbers: the rows of one scratch array S (ROWS, WIDTH).

One array rather than one per quantity, because Numba counts references to every array a
compiled function takes or reads from a structure, atomically, at each call; the step of a
walker makes a few hundred such calls. The model's own functions write their constraint terms
into S at these rows (the code generator writes them as numbers), and the algorithms read them
there (Model holds the rows).

    A      NC rows   every constraint row's Jacobian A (NC, NV)
    C      NC rows   the rows in use, whitened: C = A L^-T (linalg.whiten)
    W      WIDTH rows   the Gram matrix C C^T of the rows in use (linalg.solve_gram); in a flow where a
                        contact slips, the rows' force directions D = B L^-T instead (slipping.slip_rows)
    phi    1 row     holonomic residuals (NH)
    cv     1 row     velocity-level residuals c = A v + b (NC)
    kappa  1 row     dc/dt = A dv/dt + kappa (NC)
    y      1 row     right-hand sides of the Gram solves
    dv     1 row     a change of speed (projection, impact)
    r      1 row     the energy correction's direction
    coef   1 row     the least-norm solve's coefficients
    ks kd  1 row each   Baumgarte gains of each row (NC)
    e      1 row     restitution of each jump (NJ), then each joint friction's force

Plain Python: andyc's code generator reads it too.
"""

VECTORS = ("phi", "cv", "kappa", "y", "dv", "r", "coef", "ks", "kd", "e")


def scratch_layout(nv: int, nc: int, ne: int) -> dict:
    """The first row of each block and vector of S, and S's shape ("rows", "width"); ne: the entries of e."""
    width = max(nv, nc, ne, 1)
    rows = {"A": 0, "C": nc, "W": 2 * nc}
    first = 2 * nc + width
    rows.update({name: first + i for i, name in enumerate(VECTORS)})
    rows.update(rows=first + len(VECTORS), width=width)
    return rows


# The leaves that return a number (the others write into their arrays): their C return type, for the
# leaves of either backend (model.py's LEAVES; andyc/codegen/c_leaves.py).
RETURNS = ("energy", "power", "guard", "guard_rate", "enabled", "energy_law")
