"""SymbolicModel: the equations of motion as ordered SymPy assignments."""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from andyc.spec.model import Spec
from andyc.symbolic.constraints import ConstraintTerms
from andyc.symbolic.hybrid import HybridTerms


@dataclass
class SymbolicModel:
    """Equations of motion M(q, sigma) dv/dt = G(q, v, sigma, t) and friends.

    Every expression is written in the symbols q, v, sigma, t, parameters p, inputs u, discrete states d
    and the intermediate symbols of `assignments` (in dependency order).
    """
    spec: Spec
    t: sp.Symbol
    q: list
    v: list                   # coordinate rates, then quasi-velocities
    signals: list             # signal symbols sigma, in spec.signals order
    signal_rates: list        # d sigma / dt, same order (eq. 4)
    parameters: list          # symbols, in the order of spec.parameters
    inputs: list              # symbols, in the order of spec.inputs
    discrete: list            # symbols of the discrete states, in the order of spec.discrete
    assignments: list         # [(symbol, expression)], each uses only earlier ones
    M: sp.Matrix              # n x n, symmetric
    G: sp.Matrix              # n x 1
    energy: sp.Expr           # kinetic + potential
    power: sp.Expr            # power of the non-conservative elements
    frame_positions: dict     # frame name -> 3x1, world (user frames only)
    elements: list            # ElementTerms, per element
    constraints: ConstraintTerms  # phi, c = A v + b, kappa (eq. 10-12); empty without constraints
    hybrid: HybridTerms       # flows, jumps (one flow, no jumps without a hybrid section)
    derive_seconds: float = 0.0

    @property
    def dof(self) -> int:
        return len(self.v)

    def intermediates_of(self, exprs) -> set:
        """The intermediate symbols (of `assignments`) the expressions depend on, directly or through others."""
        defs = dict(self.assignments)
        todo = [s for e in exprs for s in sp.sympify(e).free_symbols]
        needed = set()
        while todo:
            s = todo.pop()
            if s in defs and s not in needed:
                needed.add(s)
                todo.extend(defs[s].free_symbols)
        return needed
