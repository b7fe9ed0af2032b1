"""An ordered list of intermediate assignments `symbol = expression`.

The symbolic stage never expands a chain into one big expression: every
nonzero entry of a frame's rotation, position, velocity, Jacobian and bias
acceleration gets its own symbol, defined from its parent's symbols. Code
generation later keeps only the assignments an output needs and runs cse
over them.
"""

from __future__ import annotations

import sympy as sp


class Emitter:
    def __init__(self):
        self.assignments: list[tuple[sp.Symbol, sp.Expr]] = []

    def scalar(self, label: str, expr) -> sp.Expr:
        """Name `expr` unless it is already cheap (a number, a symbol, or minus one)."""
        expr = sp.sympify(expr)
        if expr.is_Atom or (expr.is_Mul and len(expr.args) == 2 and expr.args[0] == -1 and expr.args[1].is_Atom):
            return expr
        sym = sp.Symbol(label, real=True)
        self.assignments.append((sym, expr))
        return sym

    def define(self, sym: sp.Symbol, expr) -> sp.Symbol:
        """Give `expr` a name chosen by the caller (a frame quantity used in a constraint)."""
        self.assignments.append((sym, sp.sympify(expr)))
        return sym

    def matrix(self, label: str, mat: sp.Matrix) -> sp.Matrix:
        """Name each entry of `mat` (scalar), row by row: <label><i> of a column, <label><i><j> of a matrix of
        at most 3 x 3, else <label><i>_<j>. Only the nonzero entries are visited (a Jacobian's columns are
        mostly zero, and a model's frames times its speeds would make the derivation quadratic)."""
        rows, cols = mat.shape
        if cols == 1:
            return sp.Matrix([self.scalar(f"{label}{i}", mat[i]) for i in range(rows)])
        short = cols <= 3 and rows <= 3
        named = {(i, j): self.scalar(f"{label}{i}{j}" if short else f"{label}{i}_{j}", e)
                 for (i, j), e in sorted(mat.todok().items())}
        return sp.Matrix.from_dok(rows, cols, named)
