"""Safe expression parsing: text -> SymPy, through a whitelist.

The text is parsed by Python's `ast` (which only parses, never runs) and the
tree is walked node by node: numbers, declared names, `t`, `pi`, the
arithmetic operators and the functions in FUNCTIONS; where the caller allows
it, dotted names such as `tip.x` (frame quantities, resolved by the caller). Anything else is an
error that says what is allowed. Nothing the user writes is evaluated.

Model files may come from anyone (a pull request in another project's CI), so
the text is bounded before any work is done on it:

- only the characters of arithmetic are allowed (CHARACTERS): no quotes, `#`,
  backslashes or control characters, so a comment cannot hide text from the
  parser and nothing written can end a string in a generated file;
- at most MAX_CHARACTERS characters, MAX_OPERATORS operators (Python's own
  parser overflows its stack a little beyond), MAX_NODES operands and
  operations, and MAX_DEPTH levels of nesting (a chain a + b + c is one level);
- a power's exponent, when it is a number, at most MAX_EXPONENT in size, so a
  tower such as 2**2**2**2**2**2 is refused before SymPy computes it;
- every constant part (no names in it) must be a finite real number in floating
  point, so exp(1000), 1/0, sqrt(-1) or 10**400 are refused here, not met as
  an overflow in the generated code.
"""

from __future__ import annotations

import ast
import math
import string
import sys

import sympy as sp

from andyc.spec.suggest import did_you_mean

FUNCTIONS = {
    "sin": sp.sin, "cos": sp.cos, "tan": sp.tan,
    "asin": sp.asin, "acos": sp.acos, "atan": sp.atan, "atan2": sp.atan2,
    "sinh": sp.sinh, "cosh": sp.cosh, "tanh": sp.tanh,
    "exp": sp.exp, "log": sp.log, "sqrt": sp.sqrt,
    "abs": sp.Abs, "sign": sp.sign, "min": sp.Min, "max": sp.Max,
}
# The same functions on floats, to check the constant parts of an expression.
_FLOAT_FUNCTIONS = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "asin": math.asin, "acos": math.acos, "atan": math.atan,
    "atan2": math.atan2, "sinh": math.sinh, "cosh": math.cosh, "tanh": math.tanh, "exp": math.exp,
    "log": math.log, "sqrt": math.sqrt, "abs": abs, "sign": lambda a: float((a > 0) - (a < 0)),
    "min": min, "max": max,
}
CONSTANTS = {"pi": sp.pi}
TIME = sp.Symbol("t", real=True)
RESERVED = set(FUNCTIONS) | set(CONSTANTS) | {"t", "world"}
# A model's generated module is <name>.py: no module of Python's, nor one the module imports.
MODULE_NAMES = frozenset(sys.stdlib_module_names) | {"numpy", "numba", "scipy", "llvmlite", "andyc"}

CHARACTERS = frozenset(string.ascii_letters + string.digits + "_.+-*/(),<>=! \t\r\n")
MAX_CHARACTERS = 4000
MAX_OPERATORS = 2000
MAX_NODES = 4000
MAX_DEPTH = 64
MAX_EXPONENT = 100

_SUM, _PRODUCT = (ast.Add, ast.Sub), (ast.Mult, ast.Div)
_ALLOWED = ("use numbers, declared names, t, pi, + - * / ** and the functions " + ", ".join(sorted(FUNCTIONS)))


class ExpressionError(ValueError):
    """An expression that is not allowed; `hint` says what to do.

    `name` is set when the problem is a name not allowed in this context.
    """

    def __init__(self, message: str, hint: str, name: str | None = None):
        super().__init__(message)
        self.hint = hint
        self.name = name


def shown(text: str, limit: int = 60) -> str:
    """`text` quoted for a message: repr (control characters and surrogates escaped), cut to about limit."""
    return repr(text) if len(text) <= limit else repr(text[:limit]) + f"... ({len(text)} characters)"


def _cut(code: str, limit: int = 40) -> str:
    """Code of a checked tree (only CHARACTERS in it, so nothing to escape), cut for a message."""
    return code if len(code) <= limit else code[:limit] + "..."


def number(value) -> sp.Expr:
    """A YAML number as an exact SymPy number (0.5 -> 1/2, so cos(pi/2) = 0)."""
    if isinstance(value, bool):
        raise ExpressionError(f"expected a number, got {value!r}", "write a number or an expression in quotes")
    if isinstance(value, int):
        try:
            float(value)
        except OverflowError:
            raise ExpressionError(f"the number {shown(str(value))} is too large for a float (past 1.8e308)",
                                  "write a number of a size a float holds") from None
        return sp.Integer(value)
    if value != value or value in (float("inf"), float("-inf")):
        raise ExpressionError(f"{value!r} is not a finite number", "write a finite number")
    return sp.Rational(repr(float(value)))


def syntax_tree(text) -> ast.expr:
    """The checked syntax tree of an expression or comparison, for a caller that reads its structure before
    handing parts of it back to parse() (andyc.analysis.sweeps.metrics); ExpressionError past the bounds."""
    return _tree(text)


def _tree(text) -> ast.expr:
    """The checked syntax tree of an expression or comparison (see the module docstring for the bounds)."""
    if not isinstance(text, str):
        raise ExpressionError(f"expected a number or an expression string, got {type(text).__name__}",
                              "write a number, or an expression in quotes such as \"L/2\"")
    source = text.strip()
    if not source:
        raise ExpressionError("empty expression", "write a number or an expression")
    if "^" in source:
        raise ExpressionError(f"cannot parse {shown(text)}: '^' is not a power", "write powers as '**', e.g. x**2")
    bad = next((i for i, ch in enumerate(source) if ch not in CHARACTERS), None)
    if bad is not None:
        raise ExpressionError(f"in {shown(text)}: the character {source[bad]!r} (at {bad + 1}) is not allowed in an "
                              f"expression", _ALLOWED + " (no quotes, comments or backslashes)")
    operators = sum(source.count(ch) for ch in "+-*/(,<>")
    if len(source) > MAX_CHARACTERS or operators > MAX_OPERATORS:
        raise ExpressionError(f"{shown(text)} is too long ({len(source)} characters, {operators} operators; the "
                              f"limits are {MAX_CHARACTERS} and {MAX_OPERATORS})", "write a shorter expression")
    # A YAML block scalar may break a long expression over lines: line breaks are spaces here.
    source = source.replace("\r", " ").replace("\n", " ")
    try:
        tree = ast.parse(source, mode="eval").body
    except SyntaxError as exc:
        if "nested" in (exc.msg or ""):
            raise ExpressionError(f"{shown(text)} is nested too deeply", f"nest at most {MAX_DEPTH} levels") from None
        raise
    except (RecursionError, MemoryError):
        raise ExpressionError(f"{shown(text)} is nested too deeply", f"nest at most {MAX_DEPTH} levels") from None
    nodes, depth = _size(tree)
    if nodes > MAX_NODES or depth > MAX_DEPTH:
        raise ExpressionError(f"{shown(text)} is too large ({nodes} parts nested {depth} deep; the limits are "
                              f"{MAX_NODES} parts and {MAX_DEPTH} levels)", "write a shorter expression")
    return tree


def _size(tree) -> tuple[int, int]:
    """(operands and operations, nesting depth) of a tree, without recursion; a chain of + and - (or * and /)
    is one level."""
    nodes, deepest = 0, 0
    stack = [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        nodes += 1
        deepest = max(deepest, depth)
        for child in ast.iter_child_nodes(node):
            if not isinstance(child, ast.expr):         # operators and contexts
                continue
            same_chain = (isinstance(node, ast.BinOp) and child is node.left and isinstance(child, ast.BinOp)
                          and _family(child.op) is not None and _family(child.op) == _family(node.op))
            stack.append((child, depth if same_chain else depth + 1))
    return nodes, deepest


def _family(op):
    return _SUM if isinstance(op, _SUM) else _PRODUCT if isinstance(op, _PRODUCT) else None


def parse(text, names: dict[str, sp.Symbol], allow_time: bool = True, dotted=None) -> sp.Expr:
    """Parse a number or an expression string into SymPy.

    `names` maps every name the expression may use to its symbol.
    `dotted(owner, attribute)` resolves `owner.attribute` (or raises
    ExpressionError); without it, dotted names are not allowed.
    Raises ExpressionError with a hint naming the allowed names.
    """
    if isinstance(text, (int, float)) and not isinstance(text, bool):
        return number(text)
    try:
        tree = _tree(text)
    except SyntaxError as exc:
        source = text.strip()
        # offset is 1-based; 0 or past the end means Python ran out of text.
        where = (f"at character {exc.offset} ({source[exc.offset - 1]!r})" if 0 < (exc.offset or 0) <= len(source)
                 else "at the end (something is missing)")
        raise ExpressionError(f"cannot parse {shown(text)}: {exc.msg} {where}",
                              "check the brackets and operators (allowed: + - * / ** and the functions "
                              + ", ".join(sorted(FUNCTIONS)) + ")") from None
    value = _SympyBuilder(text, names, allow_time, dotted).expression(tree)
    for n in value.atoms(sp.Number):        # SymPy folds constant factors: x*1e308*10 is 1e309*x
        if n.is_finite and not _fits(n):
            big = str(sp.N(n, 3)).lower()
            raise ExpressionError(f"in {shown(text)}: the constant {big} that its numbers make together overflows a "
                                  f"float (past 1.8e308)", "write numbers of a size a float holds")
    return value


def _fits(n: sp.Number) -> bool:
    """n as a float is finite."""
    try:
        return math.isfinite(float(n))
    except OverflowError:
        return False


class _SympyBuilder:
    """Builds the SymPy expression of a checked syntax tree, node by node; beside each value, its float when
    it is a constant (else None)."""

    def __init__(self, text, names, allow_time, dotted):
        self.text = text
        self.names = names
        self.allow_time = allow_time
        self.dotted = dotted

    def fail(self, what: str, hint: str, name: str | None = None):
        raise ExpressionError(f"in {shown(self.text)}: {what}", hint, name)

    def expression(self, tree) -> sp.Expr:
        value = self.visit(tree)[0]
        if value.has(sp.zoo, sp.oo, sp.nan):
            self.fail("the expression is infinite or undefined (a division by zero?)", "write a finite expression")
        return value

    def visit(self, node) -> tuple[sp.Expr, float | None]:
        if isinstance(node, ast.Constant):
            if isinstance(node.value, (int, float)) and not isinstance(node.value, bool):
                value = number(node.value)
                return value, float(value)
            self.fail(f"{node.value!r} is not a number", "only numbers, names and arithmetic are allowed")
        if isinstance(node, ast.Name):
            value = self.name(node.id)
            return value, math.pi if value is sp.pi else None
        if isinstance(node, ast.BinOp) and _family(node.op) is not None:
            return self.chain(node)
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Pow):
            return self.power(node)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            value, constant = self.visit(node.operand)
            if isinstance(node.op, ast.UAdd):
                return value, constant
            return -value, None if constant is None else -constant
        if isinstance(node, ast.Call):
            return self.call(node)
        if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and self.dotted is not None:
            try:
                return self.dotted(node.value.id, node.attr), None
            except ExpressionError as exc:
                self.fail(str(exc), exc.hint, exc.name)
        self.fail(f"'{ast.unparse(node)}' is not allowed", _ALLOWED)

    def chain(self, node) -> tuple[sp.Expr, float | None]:
        """a + b - c (or a * b / c): one SymPy Add (Mul) of all terms, built without recursing down the chain."""
        whole, family = node, _family(node.op)
        steps = []
        while isinstance(node, ast.BinOp) and _family(node.op) == family:
            steps.append((node.op, node.right))
            node = node.left
        first, constant = self.visit(node)
        terms = [first]
        for op, right in reversed(steps):
            value, c = self.visit(right)
            if isinstance(op, ast.Div) and c == 0.0:
                self.fail(f"division by zero in '{ast.unparse(right)}'", "divide by a nonzero value")
            terms.append(value if isinstance(op, (ast.Add, ast.Mult)) else -value if isinstance(op, ast.Sub)
                         else 1 / value)
            if constant is not None and c is not None:
                constant = (constant + c if isinstance(op, ast.Add) else constant - c if isinstance(op, ast.Sub)
                            else constant * c if isinstance(op, ast.Mult) else constant / c)
                self.finite(constant, whole)
            else:
                constant = None
        return (sp.Add(*terms) if family is _SUM else sp.Mul(*terms)), constant

    def power(self, node) -> tuple[sp.Expr, float | None]:
        exponent, e = self.visit(node.right)
        if e is not None and abs(e) > MAX_EXPONENT:
            self.fail(f"the exponent of '{_cut(ast.unparse(node))}' is {e:.6g}, past the limit of "
                      f"{MAX_EXPONENT}", f"use exponents up to {MAX_EXPONENT} in size")
        base, b = self.visit(node.left)
        constant = None
        if b is not None and e is not None:
            if b == 0.0 and e < 0:
                self.fail(f"division by zero in '{ast.unparse(node)}'", "raise zero to a positive power only")
            try:
                constant = b ** e
            except OverflowError:
                self.overflow(node)
            if isinstance(constant, complex):
                self.fail(f"'{ast.unparse(node)}' is not a real number", "raise negative numbers to whole powers")
            self.finite(constant, node)
        return base ** exponent, constant

    def finite(self, value: float, node) -> None:
        if not math.isfinite(value):
            self.overflow(node)

    def overflow(self, node):
        self.fail(f"'{_cut(ast.unparse(node))}' overflows a float (past 1.8e308)",
                  "write numbers of a size a float holds")

    def name(self, ident: str) -> sp.Expr:
        if ident in self.names:
            return self.names[ident]
        if ident in CONSTANTS:
            return CONSTANTS[ident]
        if ident == "t" and self.allow_time:
            return TIME
        known = sorted(set(self.names) | set(CONSTANTS) | ({"t"} if self.allow_time else set()))
        hint = did_you_mean(ident, known) + "names allowed here: " + ", ".join(known)
        if ident in FUNCTIONS:
            self.fail(f"function '{ident}' used as a value", f"call it, e.g. {ident}(x)")
        self.fail(f"unknown name '{ident}'", hint, ident)

    def call(self, node: ast.Call) -> tuple[sp.Expr, float | None]:
        if not isinstance(node.func, ast.Name) or node.func.id not in FUNCTIONS:
            called = ast.unparse(node.func)
            self.fail(f"unknown function '{called}'",
                      did_you_mean(called, FUNCTIONS) + "allowed functions: " + ", ".join(sorted(FUNCTIONS)))
        if node.keywords:
            self.fail("keyword arguments are not allowed", "pass arguments by position")
        name = node.func.id
        if any(isinstance(a, ast.Starred) for a in node.args):
            self.fail("'*' arguments are not allowed", "pass arguments by position")
        args = [self.visit(a) for a in node.args]
        want = 2 if name == "atan2" else (None if name in ("min", "max") else 1)
        if (want is not None and len(args) != want) or (want is None and len(args) < 2):
            self.fail(f"{name} takes {want or 'two or more'} argument(s), got {len(args)}",
                      f"write {name}({', '.join(['x', 'y'][:want or 2])})")
        constant = None
        if all(c is not None for _, c in args):
            try:
                constant = float(_FLOAT_FUNCTIONS[name](*(c for _, c in args)))
            except OverflowError:
                self.overflow(node)
            except (ValueError, ZeroDivisionError):
                self.fail(f"'{_cut(ast.unparse(node))}' is not a real number (outside the domain of "
                          f"{name})", f"give {name} an argument in its domain")
            self.finite(constant, node)
        return FUNCTIONS[name](*(v for v, _ in args)), constant


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
        tree = _tree(text)
    except SyntaxError as exc:
        alone = text
        for op in ("==", "!=", "<=", ">="):
            alone = alone.replace(op, "")
        if isinstance(exc, IndentationError) or "=" not in alone:      # no lone '=' written for '=='
            raise ExpressionError(f"cannot parse {shown(text)}: {exc.msg}", 'write a comparison such as "x > 0"') \
                from None
        raise ExpressionError(f"in {shown(text)}: '=' is not a comparison", equality) from None
    if isinstance(tree, ast.Compare) and any(isinstance(op, (ast.Eq, ast.NotEq)) for op in tree.ops):
        op = next("==" if isinstance(op, ast.Eq) else "!="
                  for op in tree.ops if isinstance(op, (ast.Eq, ast.NotEq)))
        raise ExpressionError(f"in {shown(text)}: '{op}' cannot be a condition", equality)
    if not isinstance(tree, ast.Compare) or not all(type(op) in _COMPARE for op in tree.ops):
        raise ExpressionError(f"{shown(text)} is not a comparison", "write a comparison with <, <=, > or >=, such as "
                              '"foot.x > fx"; give several as a list (all must hold)')
    builder = _SympyBuilder(text, names, allow_time, dotted)
    sides = [builder.expression(side) for side in [tree.left] + tree.comparators]
    out = []
    for op, a, b in zip(tree.ops, sides, sides[1:]):
        out.append(a - b if _COMPARE[type(op)] > 0 else b - a)
    return out
