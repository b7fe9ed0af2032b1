"""User metrics of a sweep: `--metric NAME=EXPR`, an expression of a run, evaluated on every point's run.

The expression is andyc's arithmetic (andyc.spec.expressions: numbers, names, + - * / **, sin, sqrt, ...,
two-argument min and max), parsed by its safe parser; nothing the user writes is evaluated as code. A name
alone is its value at the end of the run:

    states, discrete states  the final value (x, th1_dot, fx)
    t, energy                the final time, the final energy
    FRAME.x, .y, .z          a frame's world position at the end (the frame is logged for it)
    parameters, inputs       the run's values

and these functions look at the whole run (the logged samples):

    max(E), min(E), mean(E)  E's largest, smallest and mean value over the samples (one argument)
    at(T, E)                 E at time T, interpolated linearly between samples (NaN when the run stops first)
    count(JUMP), count()     how many times JUMP happened; how many jumps in all
    time_of(JUMP, N)         the time of JUMP's N-th occurrence (N = 1, 2, ...; NaN when it did not happen)

A metric may also be one comparison, which gives 1 (true) or 0: `min(foot1.y) < -0.01`. The value is a
float; NaN where it is undefined (a point that failed).
"""

from __future__ import annotations

import ast
import math
import re
from dataclasses import dataclass

import numpy as np

from andyc.analysis.evaluate import numeric
from andyc.errors import MetricError
from andyc.spec.expressions import ExpressionError, parse, syntax_tree

_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
SERIES_FUNCTIONS = ("max", "min", "mean")
RUN_FUNCTIONS = SERIES_FUNCTIONS + ("at", "count", "time_of")
_COMPARE = {ast.Lt: np.less, ast.LtE: np.less_equal, ast.Gt: np.greater, ast.GtE: np.greater_equal}


@dataclass(frozen=True)
class Metric:
    """A parsed metric: `value` (a SymPy expression of the names and of the placeholders `parts` name: each a
    (function, arguments) of the run), or a comparison `left op right` of two such."""
    name: str
    text: str
    value: object
    parts: dict
    compare: tuple = ()         # (numpy comparison, right-hand value) when the metric is a comparison
    frames: tuple = ()          # the frames it reads


def metric_items(items) -> list:
    """('energy_T=energy', ...) -> [(name, text), ...]; MetricError for an item that is not NAME=EXPR or a name
    given twice."""
    out, seen = [], set()
    for item in items:
        name, sep, text = item.partition("=")
        name = name.strip()
        if not sep or not _NAME.fullmatch(name) or not text.strip():
            raise MetricError(f"--metric '{item}': not NAME=EXPRESSION (e.g. peak=max(abs(th1)))")
        if name in seen:
            raise MetricError(f"--metric '{item}': the metric '{name}' is given twice")
        seen.add(name)
        out.append((name, text.strip()))
    return out


def compile_metric(name: str, text: str, model) -> Metric:
    """Parse metric `name` = `text` for a CompiledModel; MetricError says what is wrong."""
    scope = _Scope(model)
    try:
        tree = syntax_tree(text)
        if isinstance(tree, ast.Compare):
            if len(tree.ops) != 1 or type(tree.ops[0]) not in _COMPARE:
                raise MetricError(f"--metric {name}: one comparison with <, <=, > or >= only")
            left, right = scope.value(tree.left), scope.value(tree.comparators[0])
            return Metric(name, text, left, scope.parts, (_COMPARE[type(tree.ops[0])], right), scope.frame_list())
        return Metric(name, text, scope.value(tree), scope.parts, (), scope.frame_list())
    except ExpressionError as exc:
        raise MetricError(f"--metric {name}: {exc}; {exc.hint}") from None
    except SyntaxError as exc:
        raise MetricError(f"--metric {name}: cannot parse {text!r}: {exc.msg}") from None


class _Scope:
    """The names a metric may use, as SymPy symbols, and its run functions replaced by placeholders."""

    def __init__(self, model):
        import sympy as sp

        self.model, self.parts, self.frames = model, {}, []
        names = (list(model.state_names) + list(model.discrete_names) + list(model.parameter_names)
                 + list(model.input_names) + ["energy"])
        self.names = {n: sp.Symbol(n, real=True) for n in names}
        self.symbol = sp.Symbol

    def frame_list(self) -> tuple:
        return tuple(dict.fromkeys(self.frames))

    def dotted(self, owner: str, attribute: str):
        if owner not in self.model.frame_names:
            raise ExpressionError(f"unknown frame '{owner}'", f"frames: {', '.join(self.model.frame_names)}")
        if attribute not in ("x", "y", "z"):
            raise ExpressionError(f"'{owner}.{attribute}' is not a position", f"write {owner}.x, .y or .z")
        self.frames.append(owner)
        return self.symbol(f"{owner}.{attribute}", real=True)

    def value(self, tree):
        """The SymPy expression of a tree, its run functions replaced by placeholder symbols (self.parts)."""
        tree = _Replace(self).visit(ast.Expression(tree)).body
        names = {**self.names, **{s.name: s for s in self.parts}}
        return parse(ast.unparse(tree), names, dotted=self.dotted)

    def part(self, call: ast.Call) -> ast.Name:
        function, args = call.func.id, call.args
        if call.keywords or any(isinstance(a, ast.Starred) for a in args):
            raise ExpressionError(f"{function}(...) takes its arguments by position", "e.g. time_of(strike, 2)")
        if function in SERIES_FUNCTIONS:
            parsed = (self.series(args[0]),)
        elif function == "at":
            if len(args) != 2:
                raise ExpressionError(f"at takes 2 arguments (T, E), got {len(args)}", "write at(1.5, energy)")
            parsed = (float(parse(ast.unparse(args[0]), {}, allow_time=False)), self.series(args[1]))
        elif function == "count":
            if len(args) > 1:
                raise ExpressionError(f"count takes a jump's name or nothing, got {len(args)} arguments",
                                      "write count(strike) or count()")
            parsed = (self.jump(args[0]),) if args else (None,)
        else:
            if len(args) != 2 or not (isinstance(args[1], ast.Constant) and isinstance(args[1].value, int)
                                      and args[1].value >= 1):
                raise ExpressionError("time_of takes a jump's name and a whole number N >= 1",
                                      "write time_of(strike, 3)")
            parsed = (self.jump(args[0]), args[1].value)
        placeholder = self.symbol(f"_run{len(self.parts)}_", real=True)
        self.parts[placeholder] = (function, parsed)
        return ast.Name(placeholder.name, ast.Load())

    def series(self, tree):
        """An expression over the samples: the names as series (a run function inside one is refused)."""
        if any(isinstance(n, ast.Call) and isinstance(n.func, ast.Name) and _is_run_call(n)
               for n in ast.walk(tree)):
            raise ExpressionError("a run function inside another", "write max(E) - min(E), not max(min(E))")
        return parse(ast.unparse(tree), dict(self.names), dotted=self.dotted)

    def jump(self, tree) -> int:
        names = self.model.jump_names
        if not isinstance(tree, ast.Name) or tree.id not in names:
            raise ExpressionError(f"'{ast.unparse(tree)}' is not a jump of {self.model.name}",
                                  f"jumps: {', '.join(names) or 'none'}")
        return names.index(tree.id)


def _is_run_call(node: ast.Call) -> bool:
    """A call of a run function: max, min with one argument (two or more: the arithmetic min and max), mean,
    at, count, time_of."""
    name = node.func.id
    return name in RUN_FUNCTIONS and not (name in ("max", "min") and len(node.args) != 1)


class _Replace(ast.NodeTransformer):
    def __init__(self, scope: _Scope):
        self.scope = scope

    def visit_Call(self, node):
        if isinstance(node.func, ast.Name) and _is_run_call(node):
            return self.scope.part(node)
        return self.generic_visit(node)


# ---- evaluation, on a Run's arrays -------------------------------------------------------------------------

def evaluate(metric: Metric, run) -> float:
    """The metric's value on `run` (an andyc Run that logged the metric's frames)."""
    series = _series(run)
    final = {s: (v[-1] if np.ndim(v) and len(v) else v) for s, v in series.items()}
    for placeholder, (function, args) in metric.parts.items():
        final[placeholder.name] = _run_function(function, args, series, run)
    with np.errstate(all="ignore"):
        value = float(numeric(metric.value, final))
        if metric.compare:
            compare, right = metric.compare
            other = float(numeric(right, final))
            return math.nan if math.isnan(value) or math.isnan(other) else float(compare(value, other))
    return value


def _series(run) -> dict:
    """{name: samples or constant} of everything a metric may name."""
    out = {n: run.state[:, i] for i, n in enumerate(run.state_names)}
    out.update({n: run.discrete[:, i] for i, n in enumerate(run.discrete_names)})
    out.update(run.parameters)
    out.update({n: run.input_values[:, i] for i, n in enumerate(run.input_names)})
    out.update({f"{f}.{a}": xyz[:, k] for f, xyz in run.frames.items() for k, a in enumerate("xyz")})
    out["t"], out["energy"] = run.time, run.energy
    return out


def _run_function(function: str, args: tuple, series: dict, run) -> float:
    events = run.events
    if function == "count":
        return float(len(events["time"]) if args[0] is None else np.count_nonzero(events["jump"] == args[0]))
    if function == "time_of":
        times = events["time"][events["jump"] == args[0]]
        return float(times[args[1] - 1]) if len(times) >= args[1] else math.nan
    with np.errstate(all="ignore"):
        values = np.broadcast_to(numeric(args[-1], series), run.time.shape)
        if function == "at":
            t = args[0]
            if not (run.time[0] <= t <= run.time[-1]) or not len(values):
                return math.nan
            return float(np.interp(t, run.time, values))
        if not len(values):
            return math.nan
        return float({"max": np.max, "min": np.min, "mean": np.mean}[function](values))
