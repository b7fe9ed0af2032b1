"""Safe expression parsing: text -> SymPy, through a whitelist.

The text is parsed by Python's `ast` (which only parses, never runs) and the
tree is walked node by node: numbers, declared names, `t`, `pi`, the
arithmetic operators and the functions in FUNCTIONS; where the caller allows
it, dotted names such as `tip.x` (frame quantities, resolved by the caller). Anything else is an
error that says what is allowed. Nothing the user writes is evaluated.
"""

from __future__ import annotations

import ast
import difflib

import sympy as sp

FUNCTIONS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan,
    "asin": sp.asin, "acos": sp.acos, "atan": sp.atan, "atan2": sp.atan2,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh,
    "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt,
    "abs": sp.Abs, "sign": sp.sign, "min": sp.Min, "max": sp.Max,
}
CONSTANTS = {"pi": sp.pi}
TIME = sp.Symbol("t", real=True)
RESERVED = set(FUNCTIONS) | set(CONSTANTS) | {"t", "world"}

_BINOPS = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
    ast.Pow: lambda a, b: a ** b,
}


class ExpressionError(ValueError):
    """An expression that is not allowed; `hint` says what to do.

    `name` is set when the problem is a name not allowed in this context.
    """

    def __init__(self, message: str, hint: str, name: str | None = None):
        super().__init__(message)
        self.hint = hint
        self.name = name


def number(value) -> sp.Expr:
    """A YAML number as an exact SymPy number (0.5 -> 1/2, so cos(pi/2) = 0)."""
    if isinstance(value, bool):
        raise ExpressionError(f"expected a number, got {value!r}", "write a number or an expression in quotes")
    if isinstance(value, int):
        return sp.Integer(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise ExpressionError(f"{value!r} is not a finite number", "write a finite number")
    return sp.Rational(repr(float(value)))


def parse(text, names: dict[str, sp.Symbol], allow_time: bool = True, dotted=None) -> sp.Expr:
    """Parse a number or an expression string into SymPy.

    `names` maps every name the expression may use to its symbol.
    `dotted(owner, attribute)` resolves `owner.attribute` (or raises
    ExpressionError); without it, dotted names are not allowed.
    Raises ExpressionError with a hint naming the allowed names.
    """
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return number(text)
    if not isinstance(text, str):
        raise ExpressionError(f"expected a number or an expression string, got {type(text).__name__}",
                              "write a number, or an expression in quotes such as \"L/2\"")
    source = text.strip()
    if not source:
        raise ExpressionError("empty expression", "write a number or an expression")
    if "^" in source:
        raise ExpressionError(f"cannot parse {text!r}: '^' is not a power", "write powers as '**', e.g. x**2")
    try:
        tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        # offset is 1-based; 0 or past the end means Python ran out of text.
        where = (f"at character {exc.offset} ({source[exc.offset - 1]!r})" if 0 < (exc.offset or 0) <= len(source)
                 else "at the end (something is missing)")
        raise ExpressionError(f"cannot parse {text!r}: {exc.msg} {where}",
                              "check the brackets and operators (allowed: + - * / ** and the functions "
                              + ", ".join(sorted(FUNCTIONS)) + ")")
    return _Builder(text, names, allow_time, dotted).visit(tree.body)


class _Builder:
    def __init__(self, text, names, allow_time, dotted):
        self.text = text
        self.names = names
        self.allow_time = allow_time
        self.dotted = dotted

    def fail(self, what: str, hint: str, name: str | None = None):
        raise ExpressionError(f"in {self.text!r}: {what}", hint, name)

    def visit(self, node) -> sp.Expr:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
                return number(node.value)
            self.fail(f"{node.value!r} is not a number", "only numbers, names and arithmetic are allowed")
        if isinstance(node, ast.Name):
            return self.name(node.id)
        if isinstance(node, ast.BinOp) and type(node.op) in _BINOPS:
            return _BINOPS[type(node.op)](self.visit(node.left), self.visit(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            value = self.visit(node.operand)
            return -value if isinstance(node.op, ast.USub) else value
        if isinstance(node, ast.Call):
            return self.call(node)
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and self.dotted is not None:
            try:
                return self.dotted(node.value.id, node.attr)
            except ExpressionError as exc:
                self.fail(str(exc), exc.hint, exc.name)
        self.fail(f"'{ast.unparse(node)}' is not allowed",
                  "use numbers, declared names, t, pi, + - * / ** and functions " + ", ".join(sorted(FUNCTIONS)))

    def name(self, ident: str) -> sp.Expr:
        if ident in self.names:
            return self.names[ident]
        if ident in CONSTANTS:
            return CONSTANTS[ident]
        if ident == "t" and self.allow_time:
            return TIME
        known = sorted(set(self.names) | set(CONSTANTS) | ({"t"} if self.allow_time else set()))
        close = difflib.get_close_matches(ident, known, n=1)
        hint = (f"did you mean '{close[0]}'? " if close else "") + "names allowed here: " + ", ".join(known)
        if ident in FUNCTIONS:
            self.fail(f"function '{ident}' used as a value", f"call it, e.g. {ident}(x)")
        self.fail(f"unknown name '{ident}'", hint, ident)

    def call(self, node: ast.Call) -> sp.Expr:
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            called = ast.unparse(node.func)
            close = difflib.get_close_matches(called, list(FUNCTIONS), n=1)
            self.fail(f"unknown function '{called}'",
                      (f"did you mean '{close[0]}'? " if close else "")
                      + "allowed functions: " + ", ".join(sorted(FUNCTIONS)))
        if node.keywords:
            self.fail("keyword arguments are not allowed", "pass arguments by position")
        args = [self.visit(a) for a in node.args]
        want = 2 if node.func.id == "atan2" else (None if node.func.id in ("min", "max") else 1)
        if (want is not None and len(args) != want) or (want is None and len(args) < 2):
            self.fail(f"{node.func.id} takes {want or 'two or more'} argument(s), got {len(args)}",
                      f"write {node.func.id}({', '.join(['x', 'y'][:want or 2])})")
        return FUNCTIONS[node.func.id](*args)


_COMPARE = {ast.Gt: 1, ast.GtE: 1, ast.Lt: -1, ast.LtE: -1}     # a > b: a - b >= 0; a < b: b - a >= 0


def parse_condition(text, names: dict[str, sp.Symbol], allow_time: bool = True, dotted=None) -> list[sp.Expr]:
    """Parse a comparison such as `foot.x > fx` (or a chain `0 < x < L`) into expressions s >= 0.

    Each returned s holds where its comparison does (a > b gives a - b; a < b
    gives b - a). Strict and non-strict comparisons are not told apart: the
    condition is checked at a located event, where equality has no meaning.
    """
    if not isinstance(text, str) or not text.strip():
        raise ExpressionError(f"expected a comparison, got {text!r}", 'write a comparison such as "x > 0"')
    equality = ("a condition is an inequality, checked where the guard crosses 0: write <, <=, > or >=; "
                "to jump where a = b, make 'a - b' the guard")
    try:
        tree = ast.parse(text.strip(), mode="eval").body
    except SyntaxError as exc:
        alone = text
        for op in ("==", "!=", "<=", ">="):
            alone = alone.replace(op, "")
        if isinstance(exc, IndentationError) or "=" not in alone:      # no lone '=' written for '=='
            raise ExpressionError(f"cannot parse {text!r}: {exc.msg}", 'write a comparison such as "x > 0"')
        raise ExpressionError(f"in {text!r}: '=' is not a comparison", equality)
    if isinstance(tree, ast.Compare) and any(isinstance(op, (ast.Eq, ast.NotEq)) for op in tree.ops):
        op = next("==" if isinstance(op, ast.Eq) else "!="
                  for op in tree.ops if isinstance(op, (ast.Eq, ast.NotEq)))
        raise ExpressionError(f"in {text!r}: '{op}' cannot be a condition", equality)
    if not isinstance(tree, ast.Compare) or not all(type(op) in _COMPARE for op in tree.ops):
        raise ExpressionError(f"{text!r} is not a comparison", "write a comparison with <, <=, > or >=, such as "
                              '"foot.x > fx"; give several as a list (all must hold)')
    builder = _Builder(text, names, allow_time, dotted)
    sides = [builder.visit(tree.left)] + [builder.visit(c) for c in tree.comparators]
    out = []
    for op, a, b in zip(tree.ops, sides, sides[1:]):
        out.append(a - b if _COMPARE[type(op)] > 0 else b - a)
    return out
