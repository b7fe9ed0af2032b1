"""Exact first derivatives of a model's expressions, as more assignments (symbolic forward mode).

The SymbolicModel is a chain of assignments s = f(earlier symbols). For variables w (here the state
x = (q, v, sigma), the discrete states d, the parameters p and the time t: W = (x, d, p, t)), each intermediate
symbol's gradient is carried forward in order, entry by entry:

    ds/dw_j = sum_a (df/da) da/dw_j        over the symbols a that f reads,

each df/da from SymPy's `diff` of that one small expression, and each nonzero entry becomes a new
assignment of its own (a symbol `_dd<n>`), so nothing large is ever differentiated and the code
generator's cse shares the work (andyc/codegen/derivatives.py). This is what andyc.symbolic.linearize
does numerically at one point, written out as expressions instead, so that a run can evaluate it at
every RK4 stage (andyc.runtime.sensitivities).
"""

from __future__ import annotations

import sympy as sp

from andyc.symbolic.model import SymbolicModel


class ForwardGradients:
    """Gradients with respect to `wrt` (symbols) of the expressions of `model`, as extra assignments.

    assignments: [(symbol, expression)] in dependency order (after the model's own); gradient(expr) gives
    {index in wrt: expression} of the nonzero entries of d expr / d wrt."""

    def __init__(self, model: SymbolicModel, exprs: list, wrt: list):
        self.wrt = list(wrt)
        self.grads = {s: {i: sp.Integer(1)} for i, s in enumerate(self.wrt)}
        self.assignments = []
        needed = model.intermediates_of(exprs)
        for sym, expr in model.assignments:
            if sym not in needed:
                continue
            entries = {}
            for i, e in self.gradient(expr).items():
                if e.is_Symbol or e.is_Number:
                    entries[i] = e              # a copy or a constant: no assignment of its own
                else:
                    d = sp.Symbol(f"_dd{len(self.assignments)}", real=True)
                    self.assignments.append((d, e))
                    entries[i] = d
            self.grads[sym] = entries

    def gradient(self, expr) -> dict:
        """{index in wrt: d expr / d wrt[index]}, the nonzero entries, by the chain rule through the symbols
        expr reads."""
        expr = sp.sympify(expr)
        out: dict = {}
        for s in sorted(expr.free_symbols, key=str):
            g = self.grads.get(s)
            if not g:
                continue
            partial = sp.diff(expr, s)
            if partial == 0:
                continue
            for i, gi in g.items():
                out[i] = out.get(i, sp.Integer(0)) + partial * gi
        return {i: e for i, e in out.items() if e != 0}


def variables(model: SymbolicModel) -> list:
    """W = (q, v, sigma, d, p, t): the symbols the derivatives are taken with respect to, in the order of the
    generated module's STATES (coordinates, speeds, signals), DISCRETE_STATES, PARAMETERS, then t."""
    return [*model.q, *model.v, *model.signals, *model.discrete, *model.parameters, model.t]
