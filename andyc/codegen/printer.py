"""One generated function body: needed assignments -> cse -> ordered lines.

Given the outputs of a function (`target = expression`) and the pool of
intermediate assignments of the SymbolicModel, keep only the assignments the
outputs reach, run SymPy's cse over all of them together, and order the cse
replacements and the assignments so that each line uses only earlier ones.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import sympy as sp
from sympy.printing.pycode import PythonCodePrinter


class Unwrapped:
    """A SymPy code printer that rewrites re(...) (SymPy's _handle_UnevaluatedExpr) only in an expression that
    has one: SymPy rebuilds every expression it prints for it, a third of the printing time of a large model,
    and a generated body has none (its symbols are real)."""

    def _handle_UnevaluatedExpr(self, expr):
        return super()._handle_UnevaluatedExpr(expr) if expr.has(sp.re) else expr


class ConstantOverflow(ValueError):
    """A constant of the derived equations that no float holds (the product of a model's large numbers: a
    stiffness of 1e200 on a length of 1e200 * x): the model's units need scaling. The pipeline turns it into
    a problem of the model file."""


def finite_literal(expr) -> str:
    """repr of the float of a SymPy number; ConstantOverflow past 1.8e308."""
    try:
        value = float(expr)
    except OverflowError:
        value = math.inf
    if not math.isfinite(value):
        shown = str(sp.N(expr, 3)).lower()
        raise ConstantOverflow(f"a constant of the derived equations, {shown}, overflows a float (past 1.8e308)")
    return repr(value)


class _Printer(Unwrapped, PythonCodePrinter):
    """Python printer for Numba: math.* calls, floats for rationals."""

    def _print_Rational(self, expr):
        return finite_literal(expr)

    def _print_Integer(self, expr):
        # Numba types integer literals as int64; print larger ones as floats.
        return str(expr.p) if abs(expr.p) < 2**53 else finite_literal(expr)

    def _print_Float(self, expr):
        finite_literal(expr)
        return super()._print_Float(expr)


_PRINTER = _Printer({"fully_qualified_modules": True, "standard": "python3"})


def to_code(expr) -> str:
    if expr is sp.S.Zero:       # what the printer gives, without its ~20 us: most of a large M's entries
        return "0"
    return _PRINTER.doprint(expr)


@dataclass
class FunctionBody:
    inputs: set           # free symbols read (q, v, t, parameters, inputs)
    operations: int       # sympy count_ops of every line
    exprs: list           # [(name or target, expression)]: the lines, then the outputs, for another printer
    n_lines: int          # how many of exprs are local assignments

    # Printed in Python when first read: a build whose leaves are in C never reads them (SymPy's printer took a
    # quarter of a large robot's generation, g1's 10 s).
    @cached_property
    def lines(self) -> list:
        """[(name, code)] local assignments, in order."""
        return [(name, to_code(e)) for name, e in self.exprs[:self.n_lines]]

    @cached_property
    def outputs(self) -> list:
        """[(target, code)]."""
        return [(target, to_code(e)) for target, e in self.exprs[self.n_lines:]]


def function_body(outputs: list[tuple[str, sp.Expr]], pool: dict[sp.Symbol, sp.Expr]) -> FunctionBody:
    """cse and order the computation of `outputs` from the assignment `pool`."""
    # The assignments the outputs reach, kept in pool order (the pool is in
    # dependency order), so the generated code does not depend on set order.
    reached: set = set()
    stack = [s for _, e in outputs for s in _ordered_symbols(sp.sympify(e))]
    while stack:
        s = stack.pop()
        if s in reached or s not in pool:
            continue
        reached.add(s)
        stack.extend(_ordered_symbols(pool[s]))
    needed = [s for s in pool if s in reached]
    exprs = [pool[s] for s in needed] + [sp.sympify(e) for _, e in outputs]
    replacements, reduced = sp.cse(exprs, symbols=sp.numbered_symbols("c", real=True), order="none")
    defs = dict(replacements)
    defs.update(zip(needed, reduced[:len(needed)]))
    out_exprs = reduced[len(needed):]

    # Depth-first post-order from the outputs: each definition lands right
    # before its first use, and unreachable ones are dropped.
    order, state = [], {}
    for root in [s for e in out_exprs for s in _ordered_symbols(e)]:
        stack = [(root, False)]
        while stack:
            sym, done = stack.pop()
            if done:
                order.append(sym)
                continue
            if sym in state or sym not in defs:
                continue
            state[sym] = True
            stack.append((sym, True))
            stack.extend((d, False) for d in reversed(_ordered_symbols(defs[sym])) if d not in state)
    inputs = set()
    for e in [defs[s] for s in order] + out_exprs:
        inputs |= {s for s in e.free_symbols if s not in defs}
    ops = sum(sp.count_ops(defs[s]) for s in order) + sum(sp.count_ops(e) for e in out_exprs if e is not sp.S.Zero)
    exprs = [(str(s), defs[s]) for s in order] + [(t, e) for (t, _), e in zip(outputs, out_exprs)]
    return FunctionBody(inputs, int(ops), exprs, len(order))


def _ordered_symbols(expr) -> list:
    return sorted(expr.free_symbols, key=str)
