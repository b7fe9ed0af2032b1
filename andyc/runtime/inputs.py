"""What drives a run's inputs: constants, expressions of t and the state, tables, a controller.

The integrator calls one compiled function before every evaluation at a new
(t, x) (the generated module's INPUTS_SIGNATURE):

    status = inputs(t, x, d, p, flow, u, data)

It is a Numba C callback; its type is its signature, not the function, so the
integrator compiles once for every input source and its cache holds. `data`
carries what the function reads:

    data = [ U (NF x NU)  |  failure record (3 + NX)  |  tables ]

U holds the constant inputs of each flow (the run's values, then the inputs a
flow sets itself). The model's own input expressions are compiled into the
generated module (input_<k>_<name>, and the callback model_inputs, used as it is
when the run drives no input itself); the run's own drives are added here.
When no input is driven, the function is None and the
integrator holds u = U[flow] (see the module's integrator). Driven inputs are
written over U's values, except where the current flow sets them: the model's
flow wins over the run.

  NAME=2.5             a constant
  NAME="-10*th"        an expression of t, the states (q, <q>_dot, signals),
                       the parameters and the discrete states, parsed through
                       the whitelist of andyc.spec.expressions and printed as code
  NAME=push.csv        a table: a time column `t` (or `time`) and a column NAME
                       (or a single value column), interpolated linearly
  controller FILE.py   `u = control(t, x, d, p)` for all inputs: a number (one
                       input) or a sequence of NU numbers, compiled with Numba,
                       or, when Numba cannot, called as Python (slower; a warning)

A controller that raises or returns the wrong number of values stops the run:
the callback records (t, x) and the failure, and the run calls the controller
again as Python there to name the file and line.
"""

from __future__ import annotations

import csv
import importlib.util
import inspect
import math
import re
import sys
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from andyc.errors import SimulationError

RAISED, WRONG_SHAPE = 1.0, 2.0          # failure kinds in the record
# What the user's code may raise and the run reports: its exceptions, and sys.exit(), which must not end
# andyc (a KeyboardInterrupt still does).
USER_ERRORS = (Exception, SystemExit)
_RECORD = 3                             # kind, t, number of values returned; then x


class InputWarning(UserWarning):
    """A controller runs as Python because Numba cannot compile it."""


@dataclass
class Table:
    path: Path
    column: str
    time: np.ndarray
    values: np.ndarray


@dataclass
class Controller:
    path: Path
    function: object        # the user's control, as Python
    compiled: object        # Numba's compilation of it, or None when it runs as Python
    returns_scalar: bool


@dataclass
class InputSource:
    """A run's inputs: the compiled function (None: held), its data, and what drives each input."""
    function: object
    data: np.ndarray
    nx: int
    flows: int
    record: int                                     # offset of the failure record in data (= flows x inputs)
    drives: dict = field(default_factory=dict)      # input name -> what drives it (text for the run's metadata)
    controller: Controller | None = None

    @property
    def function_data(self):
        """The integrator's (inputs, data) arguments: (None, None) when the inputs are held."""
        return (self.function, self.data) if self.function is not None else (None, None)

    def held(self, flow: int) -> np.ndarray:
        """The inputs the run holds in `flow` (its constants, the flow's own values over them)."""
        nu = self.record // self.flows
        return self.data[flow * nu:(flow + 1) * nu]

    def into(self, model, t, x, p, d, flow: int, u) -> int:
        """u = the inputs of the CompiledModel `model` at (t, x) in `flow`; a status (OK or INPUT_FAILED)."""
        u[:] = self.held(flow)
        inputs, data = self.function_data
        return model.numerics.integrator.update_inputs(inputs, t, np.ascontiguousarray(x), p, d, flow, u, data)

    def failure(self, model, d, p) -> str:
        """Why the function failed (from its record), naming the controller's file and line."""
        r = self.record
        kind, t, count = self.data[r], float(self.data[r + 1]), int(self.data[r + 2])
        x = self.data[r + _RECORD:r + _RECORD + self.nx].copy()
        c = self.controller
        if c is None:
            return f"the inputs failed at t = {t:.9g} s"
        if kind == WRONG_SHAPE:
            line = _return_line(c.function, t, x, d, p)
            return (f"{_where(c.path, line)}: control returned {count} values at t = {t:.9g} s; "
                    f"{_expected(model)}")
        try:
            c.function(t, x, d.copy(), p.copy())
        except USER_ERRORS as exc:        # the user's code: report it, keep the run's data
            return f"{_where(c.path, _user_line(exc, c.path))}: control {raised(exc)} at t = {t:.9g} s"
        return (f"{c.path}: control raised an exception in compiled code at t = {t:.9g} s (Numba keeps no message), "
                f"but not when called again as Python there; check indexing past the end of an array, which "
                f"Numba does not catch")


def raised(exc: BaseException) -> str:
    """What the user's code raised, in words: `ValueError: text`, or that it called sys.exit()."""
    if isinstance(exc, SystemExit):
        return f"called sys.exit({'' if exc.code is None else repr(exc.code)})"
    return f"raised {type(exc).__name__}: {exc}"


def _where(path: Path, line: int | None) -> str:
    return f"{path}:{line}" if line else str(path)


def _expected(model) -> str:
    n = len(model.input_names)
    return (f"{model.name} has {n} input{'' if n == 1 else 's'} ({', '.join(model.input_names)}): return "
            + ("one number" if n == 1 else f"a sequence of {n} numbers in this order"))


def _user_line(exc: BaseException, path: Path) -> int | None:
    """The deepest line of `path` in the exception's traceback."""
    return next((f.lineno for f in reversed(traceback.extract_tb(exc.__traceback__))
                 if Path(f.filename).resolve() == path), None)


def _return_line(function, t, x, d, p) -> int | None:
    """The line of the return statement `function` ends on at (t, x): found by profiling one call."""
    code = getattr(function, "__code__", None)
    seen = []

    def profile(frame, event, arg):
        if event == "return" and frame.f_code is code:
            seen.append(frame.f_lineno)

    old = sys.getprofile()
    sys.setprofile(profile)
    try:
        function(t, x, d.copy(), p.copy())
    except USER_ERRORS:
        pass
    finally:
        sys.setprofile(old)
    return seen[-1] if seen else None


# -- compiled helpers, referenced by the generated callback ---------------------------------------

def _helpers():
    from numba import njit

    @njit(cache=True, error_model="numpy")
    def interpolate(data, start, n, t):
        """Linear interpolation in the table at data[start:start + n] (times), data[start + n:start + 2n] (values)."""
        if t <= data[start]:
            return data[start + n]
        if t >= data[start + n - 1]:
            return data[start + 2 * n - 1]
        lo, hi = 0, n - 1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if data[start + mid] <= t:
                lo = mid
            else:
                hi = mid
        a = (t - data[start + lo]) / (data[start + hi] - data[start + lo])
        return data[start + n + lo] + a * (data[start + n + hi] - data[start + n + lo])

    @njit(cache=True, error_model="numpy")
    def failed(data, r, kind, t, x, count):
        """Record a failure at (t, x) for the run to report; the callback's nonzero status."""
        data[r] = kind
        data[r + 1] = t
        data[r + 2] = count
        for i in range(x.shape[0]):
            data[r + 3 + i] = x[i]
        return 1

    return interpolate, failed


# -- building a source -----------------------------------------------------------------------------

def input_source(model, p, values: dict | None = None, controller=None, t_end: float | None = None) -> InputSource:
    """The input source of a run of `model` at parameters p.

    values: input name -> a number, an expression string, or a CSV path (str or Path) ending in .csv.
    controller: path of a Python file defining control(t, x, d, p), which drives every input.
    t_end: the run's end, which a table must reach.
    """
    values = dict(values or {})
    names = list(model.input_names)
    for name in values:
        if name not in names:
            raise SimulationError(f"unknown input '{name}'; inputs of {model.name}: {', '.join(names) or 'none'}")
    # The model's own expressions, unless the run drives the input otherwise: compiled into the module.
    own = {} if controller is not None else {n: text for n, text in model.input_expressions if n not in values}
    numbers = {n: v for n, v in values.items() if _is_number(v)}
    u0 = model.inputs({n: float(v) for n, v in numbers.items()})
    U = model.flow_inputs(u0, p)
    drives = {n: f"expression {text}" for n, text in own.items()}
    expressions, tables = {}, {}
    for name, value in values.items():
        if name in numbers:
            continue
        text = str(value)
        if text.lower().endswith(".csv"):
            tables[name] = read_table(Path(text), name, t_end)
            drives[name] = f"table {text}"
        else:
            expressions[name] = _expression_code(model, name, text)
            drives[name] = f"expression {text}"
    ctrl = None
    if controller is not None:
        if not names:
            raise SimulationError(f"{controller}: {model.name} has no inputs for a controller to drive")
        taken = sorted(values)
        if taken:
            raise SimulationError(f"{controller}: the controller drives every input of {model.name}, but "
                                  f"{', '.join(taken)} also given with --input/--set; drop one of the two")
        ctrl = load_controller(Path(controller), model, p)
        drives.update({n: f"controller {controller}" for n in names})
    nu, nx = len(names), model.nx
    record = model.nf * nu
    data = [U.ravel(), np.zeros(_RECORD + nx)]
    offsets = {}
    start = record + _RECORD + nx
    for name, table in tables.items():
        offsets[name] = (start, table.time.shape[0])
        data += [table.time, table.values]
        start += 2 * table.time.shape[0]
    data = np.ascontiguousarray(np.concatenate(data))
    if not drives:
        return InputSource(None, data, nx, model.nf, record)
    if own and not (expressions or tables or ctrl):
        function = model.module.MODEL_INPUTS                # the module's own callback
    else:
        function = _compile(model, expressions, offsets, ctrl, record, list(own))
    return InputSource(function, data, nx, model.nf, record, drives, ctrl)


def _is_number(value) -> bool:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return True
    try:
        float(str(value))
        return True
    except ValueError:
        return False


def _expression_code(model, name: str, text: str) -> str:
    """An input's expression as code over t, x[i], p[j], d[k] (parsed through the whitelist)."""
    import sympy as sp              # here: a run that drives no input by a command-line expression needs no SymPy

    from andyc.codegen.printer import to_code
    from andyc.spec.expressions import TIME, ExpressionError, parse

    symbols = {}
    code = {}
    for kind, names in (("x", model.state_names), ("p", model.parameter_names), ("d", model.discrete_names)):
        for i, n in enumerate(names):
            symbols[n] = sp.Symbol(n, real=True)
            code[symbols[n]] = sp.Symbol(f"{kind}[{i}]", real=True)
    try:
        expr = parse(text, symbols, allow_time=True)
    except ExpressionError as exc:
        raise SimulationError(f"input {name}: {exc}; {exc.hint}") from None
    return to_code(expr.xreplace({**code, TIME: sp.Symbol("t", real=True)}))


def read_table(path: Path, name: str, t_end: float | None) -> Table:
    """A CSV table of an input: a header row, a time column `t` or `time`, one row per time, in increasing time.

    Stops at the first problem with FILE:LINE: a missing or non-numeric value (a gap), a time that does
    not increase, or a table that does not cover the run (0 .. t_end).
    """
    if not path.is_file():
        raise SimulationError(f"{path}: no such file (the table of input {name})")
    try:
        with open(path, newline="", encoding="utf-8") as fh:
            rows = [(n, row) for n, row in enumerate(csv.reader(fh), start=1)
                    if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    except UnicodeDecodeError as exc:
        line = path.read_bytes()[:exc.start].count(b"\n") + 1
        raise SimulationError(f"{path}:{line}: not UTF-8 text (the table of input {name}); write it as a CSV "
                              f"text file") from None
    except (csv.Error, OSError) as exc:
        raise SimulationError(f"{path}:1: cannot read the table of input {name}: {exc}") from None
    if not rows:
        raise SimulationError(f"{path}:1: empty; write a header row (t,{name}) and one row per time")
    line, header = rows[0]
    header = [h.strip() for h in header]
    time_col = next((i for i, h in enumerate(header) if h in ("t", "time")), None)
    if time_col is None:
        raise SimulationError(f"{path}:{line}: no time column in the header {','.join(header)}; name one 't' or 'time'")
    others = [h for i, h in enumerate(header) if i != time_col]
    if name in header:
        col = header.index(name)
    elif len(others) == 1:
        col = header.index(others[0])
    else:
        raise SimulationError(f"{path}:{line}: no column '{name}' among {', '.join(others) or 'none'}; name the "
                              f"column after the input, or keep a single value column")
    times, values = [], []
    for n, row in rows[1:]:
        cells = []
        for i, what in ((time_col, "time"), (col, f"column '{header[col]}'")):
            cell = row[i].strip() if i < len(row) else ""
            try:
                value = float(cell)
            except ValueError:
                value = math.nan
            if not math.isfinite(value):
                problem = "is empty" if not cell else f"is {cell!r}, not a finite number"
                raise SimulationError(f"{path}:{n}: {what} {problem}: a gap in the table; fill it in (the input "
                                      f"is interpolated linearly between rows) or delete the row")
            cells.append(value)
        if times and cells[0] <= times[-1]:
            raise SimulationError(f"{path}:{n}: time {cells[0]:g} does not increase (the row before has "
                                  f"{times[-1]:g}); sort the rows by time, one row per time")
        times.append(cells[0])
        values.append(cells[1])
    last = rows[-1][0]
    if len(times) < 2:
        raise SimulationError(f"{path}:{last}: {len(times)} data row(s); a table needs two or more (for a "
                              f"constant, give --input {name}=VALUE)")
    if times[0] > 0.0 or (t_end is not None and times[-1] < t_end):
        needed = f"0 .. {t_end:g} s" if t_end is not None else "from t = 0"
        at = rows[1][0] if times[0] > 0.0 else last
        raise SimulationError(f"{path}:{at}: the table covers t = {times[0]:g} .. {times[-1]:g} s but the run "
                              f"needs {needed}; add rows, or shorten the run")
    return Table(path, header[col], np.array(times), np.array(values))


def load_controller(path: Path, model, p) -> Controller:
    """Import `control(t, x, d, p)` from the file, call it once as Python at the initial state (to name the
    file and line of any problem before the run), and compile it with Numba when it can be."""
    path = path.resolve()
    if not path.is_file():
        raise SimulationError(f"{path}: no such file (--controller)")
    mod_name = f"andyc_controller_{abs(hash(str(path))):x}"
    spec = importlib.util.spec_from_file_location(mod_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[mod_name] = module
    try:
        spec.loader.exec_module(module)
    except USER_ERRORS as exc:
        line = (exc.lineno or 1) if isinstance(exc, SyntaxError) else _user_line(exc, path)
        raise SimulationError(f"{_where(path, line)}: importing the controller {raised(exc)}") from None
    control = getattr(module, "control", None)
    if not callable(control):
        raise SimulationError(f"{path}:1: defines no function control(t, x, d, p); the run calls it for the inputs "
                              f"({', '.join(model.input_names)})")
    python = getattr(control, "py_func", control)          # the user may have decorated it with @njit
    line = python.__code__.co_firstlineno
    try:
        inspect.signature(python).bind(0.0, None, None, None)
    except TypeError:
        raise SimulationError(f"{path}:{line}: control{inspect.signature(python)} must take four arguments "
                              f"(t, x, d, p): time, state, discrete states, parameters") from None
    x0 = model.initial_state(p)
    d0 = model.initial_discrete(p)
    try:
        out = python(0.0, x0.copy(), d0.copy(), p.copy())
    except USER_ERRORS as exc:
        raise SimulationError(f"{_where(path, _user_line(exc, path))}: control {raised(exc)} at t = 0 (the "
                              f"initial state)") from None
    scalar = isinstance(out, (int, float, np.floating, np.integer)) and not isinstance(out, bool)
    shape = np.shape(out) if not scalar else ()
    if not scalar and (len(shape) != 1 or shape[0] != len(model.input_names)):
        what = (f"an array of shape {shape}" if isinstance(out, np.ndarray) else
                f"a {type(out).__name__} of {len(out)} values" if hasattr(out, "__len__") else repr(out)[:60])
        raise SimulationError(f"{_where(path, _return_line(python, 0.0, x0, d0, p))}: control returned {what} at "
                              f"t = 0; {_expected(model)}")
    if scalar and len(model.input_names) != 1:
        raise SimulationError(f"{_where(path, _return_line(python, 0.0, x0, d0, p))}: control returned one number "
                              f"at t = 0; {_expected(model)}")
    compiled = _numba_compile(control, python, path)
    return Controller(path, python, compiled, scalar)


def _numba_compile(control, python, path: Path):
    """control compiled by Numba for (float64, float64[::1] x 3), or None with a warning naming why."""
    from numba import njit, types

    array = types.float64[::1]
    jitted = control if hasattr(control, "py_func") else njit(cache=False)(python)
    try:
        jitted.compile((types.float64, array, array, array))
    except Exception as exc:        # NumbaError, and the errors Numba raises for bytecode it does not support
        text = str(exc)
        found = re.search(rf'File "[^"]*{re.escape(path.name)}", line (\d+)', text)
        first = next((ln.strip() for ln in text.splitlines() if ln.strip() and not ln.startswith("Failed in")),
                     type(exc).__name__)
        warnings.warn(f"{_where(path, int(found.group(1)) if found else None)}: Numba cannot compile control "
                      f"({first}); running it as Python, which costs some microseconds per call",
                      InputWarning, stacklevel=2)
        return None
    return jitted


def _compile(model, expressions: dict, tables: dict, ctrl: Controller | None, record: int, own: list):
    """Write, then compile, the callback: the held values, then each driven input unless the flow sets it
    (`own`: the inputs the module's own expressions drive, by name)."""
    from numba import cfunc, njit, objmode

    interpolate, failed = _helpers()
    nu = len(model.input_names)
    lines = ["def inputs(t, x, d, p, flow, u, data):"]
    if own:         # the module's callback: the held values, then the model's own expressions ...
        lines += ["    model_inputs(t, x, d, p, flow, u, data)"]
        for name, _ in model.input_expressions:     # ... but the run's constant, where it holds one of those
            if name not in own:
                i = model.input_names.index(name)
                lines += [f"    u[{i}] = data[flow * {nu} + {i}]"]
    else:
        lines += [f"    for i in range({nu}):", f"        u[i] = data[flow * {nu} + i]"]
    index = {n: i for i, n in enumerate(model.input_names)}
    for name, code in expressions.items():
        lines += [f"    if not SETS[flow, {index[name]}]:", f"        u[{index[name]}] = {code}"]
    for name, (start, n) in tables.items():
        lines += [f"    if not SETS[flow, {index[name]}]:", f"        u[{index[name]}] = interpolate(data, {start}, {n}, t)"]
    namespace = {"math": math, "np": np, "SETS": np.ascontiguousarray(model.module.FLOW_SETS_INPUT),
                 "interpolate": interpolate, "failed": failed, "model_inputs": model.module.MODEL_INPUTS}
    if ctrl is not None:
        if ctrl.compiled is None:
            python = ctrl.function

            def guarded(t, x, d, p):
                # An exception must not leave the object-mode block: raised inside a C callback, it would
                # stay set behind the compiled integrator's back. The run calls control again as Python
                # there to say what it raised and where.
                try:
                    return np.ascontiguousarray(np.atleast_1d(python(t, x, d, p)), dtype=np.float64), True
                except BaseException:
                    return np.zeros(0), False

            @njit
            def call_python(t, x, d, p):
                with objmode(r="float64[::1]", ok="boolean"):
                    r, ok = guarded(t, x, d, p)
                return r, ok
            namespace["control"] = call_python
            scalar = False
            lines += ["    r, ok = control(t, x, d, p)",
                      "    if not ok:",
                      f"        return failed(data, {record}, {RAISED}, t, x, 0)"]
        else:
            namespace["control"] = ctrl.compiled
            scalar = ctrl.returns_scalar
            lines += ["    try:",
                      "        r = control(t, x, d, p)",
                      "    except Exception:",
                      f"        return failed(data, {record}, {RAISED}, t, x, 0)"]
        if scalar:
            lines += ["    if not SETS[flow, 0]:", "        u[0] = r"]
        else:
            lines += [f"    if len(r) != {nu}:",
                      f"        return failed(data, {record}, {WRONG_SHAPE}, t, x, len(r))",
                      f"    for i in range({nu}):",
                      "        if not SETS[flow, i]:",
                      "            u[i] = r[i]"]
    lines.append("    return 0")
    # Generated code, as the module is: the user's expressions arrive as trees checked by the whitelist
    # parser and printed by SymPy; no user text is executed here.
    exec(compile("\n".join(lines) + "\n", f"<andyc inputs of {model.name}>", "exec"), namespace)
    try:
        return cfunc(model.numerics.model.INPUTS_SIGNATURE, error_model="numpy")(namespace["inputs"])
    except Exception as exc:
        where = ctrl.path if ctrl is not None else model.name
        raise SimulationError(f"{where}: cannot compile the inputs with Numba: {str(exc).splitlines()[0]}") from None
