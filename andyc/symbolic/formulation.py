"""Which forward dynamics a model gets: the dense factorization of M, or the tree's sparse one.

Forward dynamics solves M dv/dt = G (ANDY eq. 8). The dense path factors all of M (Cholesky,
n^3 / 6 multiply-adds). In a kinematic tree, M_ij = 0 unless speed i's joint is an ancestor or a
descendant of speed j's: Featherstone's LTDL factorization M = L^T D L ("Efficient factorization of
the joint-space inertia matrix for branched kinematic trees", IJRR 24(6), 2005, Table 1 and eq. 8-12)
then keeps that sparsity exactly (no fill-in) and costs sum_k d_k^2 for depths d_k, which on a
branched tree (a quadruped's or a humanoid's limbs on a floating base) is far below n^3 / 6; on an
unbranched chain the two are the same work.

The tree is read off M's symbolic zero pattern, so it needs no numbering convention (andyc puts a
floating base's six speeds last): a speed whose closed neighbourhood {j : M_ij != 0} contains
another's is its ancestor (in a tree, N[d] is a subset of N[a] for a an ancestor of d). Speeds sorted
by decreasing neighbourhood, ties by index, give an order with ancestors first; the parent lambda(i)
is the latest of i's neighbours before it. The factorization is exact (no fill-in) when every
neighbour of i before it lies on i's chain i, lambda(i), lambda(lambda(i)), ... (then eliminating
a speed only updates entries between its own ancestors); otherwise the dense path is used.

The third, Featherstone's articulated-body algorithm (andyc/symbolic/aba.py), gives dv/dt without M: its
cost grows like the number of links, M's symbolic assembly like n^2 .. n^3 on a chain. It applies to an
unconstrained tree of links, those moved by shared speeds (mimic joints) taken as one group each
(aba.py, aba_groups.py); flows with constraint rows, and every other use of M (projection, impacts, energy,
linearization), keep M.

The operation counts are those of the numerical kernels (andyc/numerics/linalg.py: cholesky with
solve_lower and solve_upper, ltdl with ltdl_solve), a multiplication, an addition, a division or a
square root counting one: the same for every state, from M's pattern alone; with the symbolic
assembly of M and G added (the operations of the intermediates they reach, before cse) when ABA is among the
alternatives, whose own count is that of its intermediates the same way: all three then count the whole
of dv/dt.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import sympy as sp

DENSE, LTDL, ABA = "dense", "ltdl", "aba"
FORMULATIONS = (DENSE, LTDL, ABA)
LTDL_GAIN = 0.6     # the tree factorization is chosen when it needs at most this fraction of the dense
                    # operations: the dense kernels run with sizes as constants up to n = 8 (unrolled) and
                    # stream through rows, the tree's reads its parents from a table. Measured (bench/large.py,
                    # kernels): on chains (0.69 .. 0.96 of the operations) the tree's is 1.0 .. 2x slower,
                    # on a quadruped's tree (0.44) and a humanoid's (0.22) 0.3 .. 0.6x the time.
ABA_GAIN = 0.75    # ABA is chosen when its count is at most this fraction of the chosen factorization's: where
                   # the counts are about even (the double pendulum, the swing bar) the model keeps M's path
ABA_SAVING = 100   # ... and saves at least this many operations: below, a few nanoseconds per call, not worth
                   # results that differ in the last bits (a 1-DOF pendulum: 27 against 9)


@dataclass
class ForwardDynamics:
    """The chosen formulation, the tree (parent of each speed, -1 for a root; `order`: every speed before
    its parent) when M has one, and the operation count of each alternative (None: not applicable)."""
    chosen: str
    parent: list = field(default_factory=list)
    order: list = field(default_factory=list)
    operations: dict = field(default_factory=dict)

    def describe(self, rows: bool = False) -> str:
        """One line for `andyc check`; `rows`: the model has constraint rows (their flows stay dense)."""
        why = {LTDL: "n/a (M has no tree pattern)", ABA: "n/a (not a tree of links, or links sharing speeds not hanging from one link)"}
        ops = ", ".join(f"{name} {why[name] if n is None else n}" for name, n in self.operations.items())
        what = {LTDL: "sparse LTDL along the tree of M (Featherstone 2005)",
                ABA: "articulated-body algorithm (Featherstone 2008, Table 7.1), no M",
                DENSE: "dense Cholesky of M"}[self.chosen]
        depth = f"; tree depth {max(_depths(self.parent)) + 1}" if self.parent else ""
        note = "; flows with constraint rows: see the constrained solve" if rows else ""
        if ABA in self.operations:
            kind = "operations of dv/dt"
        else:
            kind, ops = "factor + solve operations", ops + f", {ABA} n/a (constraint rows: M is needed)"
        return f"forward dynamics: {what}{depth}; {kind}: {ops}{note}"


def _depths(parent: list) -> list:
    out = []
    for i in range(len(parent)):
        d, j = 0, parent[i]
        while j >= 0:
            d, j = d + 1, parent[j]
        out.append(d)
    return out


def ancestors(parent: list, i: int) -> list:
    """i's ancestors, nearest first."""
    out, j = [], parent[i]
    while j >= 0:
        out.append(j)
        j = parent[j]
    return out


def tree_of(pattern: list[set]) -> tuple[list, list] | None:
    """(parent, order) of the tree of a symmetric pattern (pattern[i]: the j != i with M_ij != 0), or None
    when eliminating along any tree read from it would fill in (module docstring)."""
    n = len(pattern)
    rank = sorted(range(n), key=lambda i: (-len(pattern[i]), i))        # ancestors first
    position = {i: k for k, i in enumerate(rank)}
    parent = [-1] * n
    for i in range(n):
        before = [j for j in pattern[i] if position[j] < position[i]]
        if before:
            parent[i] = max(before, key=position.get)
    for i in range(n):
        chain = set(ancestors(parent, i))
        if any(position[j] < position[i] and j not in chain for j in pattern[i]):
            return None
    return parent, rank[::-1]


def dense_operations(n: int) -> int:
    """Operations of cholesky(M, n) + solve_lower + solve_upper (linalg.py)."""
    factor = sum(2 * j + 1 + (n - 1 - j) * (2 * j + 1) for j in range(n)) + n + n * (n - 1) // 2
    return factor + 2 * n * n


def ltdl_operations(parent: list) -> int:
    """Operations of ltdl + ltdl_solve (linalg.py) along the tree `parent`."""
    depth = _depths(parent)
    factor = sum(1 + sum(1 + 2 * (depth[i] + 1) for i in ancestors(parent, k)) for k in range(len(parent)))
    return factor + 4 * sum(depth) + len(parent)


def pattern_of(M: sp.Matrix) -> list[set]:
    n = M.rows
    return [{j for j in range(n) if j != i and (M[i, j] != 0 or M[j, i] != 0)} for i in range(n)]


def _operations(expr) -> int:
    """Arithmetic operations of expr as written: an n-ary sum or product n - 1, a power or a function one (a
    product by -1, a negation, counts one). Close to sp.count_ops, without its cost (it is called on every
    intermediate M reaches)."""
    total = 0
    for node in sp.preorder_traversal(expr):
        if node.is_Add or node.is_Mul:
            total += len(node.args) - 1
        elif node.is_Pow or node.is_Function:
            total += 1
    return total


def reached_operations(exprs, pool: dict) -> int:
    """Operations (_operations) of `exprs` and of the intermediates of `pool` they reach (before cse)."""
    seen, stack, total = set(), [], 0
    for e in exprs:
        e = sp.sympify(e)
        total += _operations(e)
        stack.extend(e.free_symbols)
    while stack:
        s = stack.pop()
        if s in seen or s not in pool:
            continue
        seen.add(s)
        total += _operations(pool[s])
        stack.extend(pool[s].free_symbols)
    return int(total)


def choose(M: sp.Matrix, force: str | None = None, aba=None, G: sp.Matrix | None = None,
           pool: dict | None = None) -> ForwardDynamics:
    """The forward dynamics of M dv/dt = G: the tree's LTDL when M has a tree pattern and it needs at most
    LTDL_GAIN of the dense operations, else dense; `force` (DENSE, LTDL or ABA) overrides the counts (LTDL
    still needs the pattern, ABA its derivation: ValueError without). `aba` (aba.ArticulatedBody or None),
    G and `pool` (the model's intermediates) count the whole dv/dt (module docstring), ABA's too where it
    applies (`aba` not None), and ABA is chosen when its count is at most ABA_GAIN of the other's and it
    saves at least ABA_SAVING operations."""
    n = M.rows
    tree = tree_of(pattern_of(M))
    ops = {DENSE: dense_operations(n), LTDL: None if tree is None else ltdl_operations(tree[0])}
    if force == LTDL and tree is None:
        raise ValueError("M has no tree pattern: the LTDL factorization would fill in")
    if force == ABA and aba is None:
        raise ValueError("the articulated-body algorithm does not apply to this model")
    if force is not None:
        chosen = force
    else:
        chosen = LTDL if tree is not None and ops[LTDL] <= LTDL_GAIN * ops[DENSE] else DENSE
    if pool is not None:
        assembly = reached_operations(list(M.upper_triangular()) + list(G), pool)
        ops = {k: None if x is None else x + assembly for k, x in ops.items()}
        ops[ABA] = None
        if aba is not None:
            ops[ABA] = reached_operations(aba.vdot, {**pool, **dict(aba.assignments)})
            if force is None and ops[ABA] <= ABA_GAIN * ops[chosen] and ops[chosen] - ops[ABA] >= ABA_SAVING:
                chosen = ABA
    parent, order = tree if tree is not None and chosen == LTDL else ([], [])
    return ForwardDynamics(chosen, parent, order, ops)
