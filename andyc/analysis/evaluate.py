"""The value of an expression of a run, on numbers: the one evaluator of expectations' `final:` and sweeps'
`--metric`.

The expression is a SymPy expression built by andyc's safe parser (andyc.spec.expressions), so its tree holds
only numbers, symbols, + * ** and the parser's functions. It is walked with NumPy's functions, on floats or on
arrays of samples alike: nothing is compiled or run as code, and a value that is not real (sqrt of a negative
number, log of zero) is NaN or an infinity, as in the generated code, rather than a complex number.
"""

from __future__ import annotations

import numpy as np


def numeric(expr, values: dict):
    """The value of a SymPy expression (built by andyc's parser) at `values` {symbol name: float or array},
    walking its tree with NumPy's functions; nothing is compiled or run as code."""
    import sympy as sp

    if expr.is_Number or isinstance(expr, sp.NumberSymbol):
        return float(expr)
    if expr.is_Symbol:
        return values[expr.name]
    args = [numeric(a, values) for a in expr.args]
    if expr.is_Add:
        return sum(args[1:], args[0])
    if expr.is_Mul:
        out = args[0]
        for a in args[1:]:
            out = out * a
        return out
    if expr.is_Pow:
        return np.power(np.asarray(args[0], dtype=float), args[1])
    function = _NUMPY.get(type(expr).__name__)
    if function is None:
        raise ValueError(f"cannot evaluate {type(expr).__name__} on numbers")
    return function(*args)


def _reduce(f):
    def apply(*args):
        out = args[0]
        for a in args[1:]:
            out = f(out, a)
        return out
    return apply


_NUMPY = {"sin": np.sin, "cos": np.cos, "tan": np.tan, "asin": np.arcsin, "acos": np.arccos, "atan": np.arctan,
          "atan2": np.arctan2, "sinh": np.sinh, "cosh": np.cosh, "tanh": np.tanh, "exp": np.exp, "log": np.log,
          "Abs": np.abs, "sign": np.sign, "Min": _reduce(np.fmin), "Max": _reduce(np.fmax)}
