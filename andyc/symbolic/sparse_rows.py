"""Which constrained solve a model gets: the dense one, or one along the tree of M and the rows' sparsity.

A flow with constraint rows A solves (ANDY eq. 10-12; Braun & Goldfarb, Part II, for the projection)

    C = A R^-1,  C C^T lam = y,  dv/dt = R^-1 (R^-T G + C^T lam)      M = R^T R.

The dense path (andyc/numerics/linalg.py) takes R from the Cholesky factor of M and works on full rows: whitening
costs m n^2, the Gram matrix m^2 n, its factor m^3 / 6 (m rows, n speeds). With R = D^1/2 L from M's tree
factorization M = L^T D L (formulation.py, Featherstone 2005), row i of C has nonzeros only on A_i's speeds and
their ancestors (its support, known here from A's symbolic pattern), two rows of C meet only where their supports
do, and C C^T has the pattern of that meeting: in a closed loop's rows, only the loops that share a link. Its
factor stays within its envelope (the first row each Gram row reaches, rows in the flow's order), and rows the
envelope does not join form blocks, each factored alone; a rank-deficient block alone takes the SVD
(andyc/numerics/sparse_rows.py). For the IFToMM A02 N-four-bar the supports have three speeds and the Gram
matrix is banded: the solve grows like N, not N^3.

The operation counts are those of the kernels, a multiplication, an addition, a division or a square root
counting one, for the flow with the most rows: per evaluation of the right-hand side, the factor of M, the
whitening of the rows, y, the Gram matrix, its factor and the solves. The sparse solve is chosen when it needs at
most SPARSE_GAIN of the dense one's operations. It needs the tree of M (formulation.tree_of), rows that each reach
a speed, and no contact that slips (whose forces take slipping.slip_rows' dense solve).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from andyc.symbolic.formulation import ancestors

DENSE, SPARSE = "dense", "sparse"
SPARSE_GAIN = 0.3   # the dense kernels run with sizes as constants up to n = 8 (unrolled), the sparse ones read
                    # index tables. Measured on the N-four-bar (bench/large.py, projection steps, alternated):
                    # N = 3 (0.35 of the operations) 0.98 .. 1.29 the dense step's time, N = 5 (0.18) 0.64 .. 0.70,
                    # N = 10 (0.057) 0.30, N = 20 (0.016) 0.06 .. 0.16; the shipped models (0.7 .. 1) stay dense.


@dataclass
class ConstrainedSolve:
    """The chosen solve and, when the sparse one applies, its tables (andyc/numerics/sparse_rows.py): row_ptr (NC + 1)
    and row_cols (2, nnz: each row's support, descendants first, and each speed's position in MASS_ORDER), and
    per flow the Gram envelope (2, NC: the first row each row reaches, the first row of its block; 0 past the
    flow's rows); `operations`: of each alternative (None: not applicable)."""
    chosen: str
    row_ptr: list = field(default_factory=list)
    row_cols: list = field(default_factory=lambda: [[], []])
    envelopes: list = field(default_factory=list)
    operations: dict = field(default_factory=dict)

    def describe(self) -> str:
        """One line for `andyc check`."""
        ops = ", ".join(f"{name} {'n/a' if n is None else n}" for name, n in self.operations.items())
        what = ("sparse: along the tree of M and the rows' supports, banded Gram factor, SVD only in a singular block"
                if self.chosen == SPARSE else "dense Cholesky of M and of the Gram matrix, SVD when singular")
        return f"constrained solve: {what}; operations per evaluation: {ops}"


def supports(rows: list[set], parent: list, order: list) -> list[list[int]]:
    """Each row's support in C = A R^-1: its speeds and their ancestors, in `order` (descendants first)."""
    position = {k: i for i, k in enumerate(order)}
    out = []
    for cols in rows:
        closed = set(cols)
        for j in cols:
            closed.update(ancestors(parent, j))
        out.append(sorted(closed, key=position.get))
    return out


def envelope(rows: list[int], support: list[list[int]]) -> tuple[list, list]:
    """(first, block) of the Gram matrix of the active `rows` in their order: the first row each row's supports
    meets, and the first row of its block (a run of rows no later row's envelope reaches back past)."""
    sets = [set(support[i]) for i in rows]
    first = [next(q for q in range(r + 1) if sets[q] & sets[r] or q == r) for r in range(len(rows))]
    block, start = [0] * len(rows), 0
    for r in range(len(rows)):
        if r > 0 and min(first[r:]) >= r:
            start = r
        block[r] = start
    return first, block


def dense_operations(n: int, m: int) -> int:
    """Operations of the dense solve (linalg.py): cholesky(M) and its two solves, whiten, y, gram, cholesky of the
    Gram matrix and its two solves, C^T lam."""
    chol = lambda k: sum(2 * j + 1 + (k - 1 - j) * (2 * j + 1) for j in range(k)) + k + k * (k - 1) // 2  # noqa: E731
    return chol(n) + 2 * n * n + m * n * n + 2 * m * n + m * (m + 1) * n + chol(m) + 2 * m * m + 2 * m * n


def sparse_operations(parent: list, support: list[list[int]], rows: list[int]) -> int:
    """Operations of the sparse solve (sparse_rows.py) over the active `rows`."""
    n = len(parent)
    depth = [len(ancestors(parent, k)) for k in range(n)]
    tree = sum(1 + sum(1 + 2 * (depth[i] + 1) for i in ancestors(parent, k)) for k in range(n)) + n   # ltdl + sqrt
    tree += 2 * (2 * sum(depth) + n)                                                                # two solves
    whiten = sum(sum(2 * depth[j] + 1 for j in support[i]) for i in rows)
    first, _ = envelope(rows, support)
    sets = [set(support[i]) for i in rows]
    gram = sum(2 * len(sets[r] & sets[q]) + len(sets[r]) + len(sets[q])
               for r in range(len(rows)) for q in range(first[r], r + 1))
    factor = sum(2 * (j - max(first[r], first[j])) + 3 for r in range(len(rows)) for j in range(first[r], r)) + len(rows)
    solves = 4 * sum(r - first[r] for r in range(len(rows))) + len(rows)
    products = 4 * sum(len(support[i]) for i in rows)                                             # y, C^T lam
    return tree + whiten + gram + factor + solves + products


def choose(M_pattern: list[set], A_pattern: list[set], tree, flow_rows: list[list[int]], slips: bool,
           force: str | None = None) -> ConstrainedSolve:
    """The constrained solve of a model: M's symmetric pattern (formulation.pattern_of), A's (the speeds of each
    row), the tree of M (formulation.tree_of: (parent, order) or None), each flow's active rows, whether a contact
    slips in some flow; `force` (DENSE or SPARSE) overrides the counts (SPARSE still needs what it needs:
    ValueError without)."""
    n, rows = len(M_pattern), max(flow_rows, key=len, default=[])
    ops = {DENSE: dense_operations(n, len(rows)), SPARSE: None}
    why = ("M has no tree pattern" if tree is None else "a contact slips" if slips
           else "no constraint rows" if not rows else "a row reaches no speed" if any(not a for a in A_pattern)
           else None)
    if why is not None:
        if force == SPARSE:
            raise ValueError(f"the sparse constrained solve does not apply: {why}")
        return ConstrainedSolve(DENSE, operations=ops)
    parent, order = tree
    support = supports(A_pattern, parent, order)
    ops[SPARSE] = sparse_operations(parent, support, rows)
    chosen = force or (SPARSE if ops[SPARSE] <= SPARSE_GAIN * ops[DENSE] else DENSE)
    position = {k: i for i, k in enumerate(order)}
    ptr, cols, where = [0], [], []
    for s in support:
        cols += s
        where += [position[k] for k in s]
        ptr.append(len(cols))
    nc = len(A_pattern)
    envelopes = []
    for active in flow_rows:
        first, block = envelope(active, support)
        pad = [0] * (nc - len(active))
        envelopes.append([first + pad, block + pad])
    return ConstrainedSolve(chosen, ptr, [cols, where], envelopes, ops)
