"""What drives a run's inputs: constants, expressions of t and the state, tables, a controller.

The integrator calls a pair of compiled input callbacks before every evaluation at a new (t, x)
(andyc_numerics/inputs.py): the model's own expressions (the module's model_inputs), then what
the run drives beyond them. Their type is their signature, not the function, so the integrator
compiles once for every input source and its cache holds. `data` carries what they read:

    data = [ U (NF x NU)  |  failure record (3 + NX)  |  tables ]

U holds the constant inputs of each flow (the run's values, then the inputs a flow sets itself).
When no input is driven, the integrator gets None and holds u = U[flow]. Driven inputs are written
over U's values, except where the current flow sets them: the model's flow wins over the run.

  NAME=2.5             a constant
  NAME="-10*th"        an expression of t, the states (q, <q>_dot, signals), the parameters and
                       the discrete states: parsed through the whitelist of andyc.spec.expressions
                       and generated into the build folder like the model's own expressions
                       (andyc.codegen.run_inputs), never executed as text
  NAME=push.csv        a table: a time column `t` (or `time`) and a column NAME (or a single value
                       column), interpolated linearly
  controller FILE.py   `u = control(t, x, d, p)` for all inputs (andyc.runtime.controller): a number or a sequence
                       of NU numbers, compiled with Numba, or, when Numba cannot, called as Python
                       (slower; a warning)

A controller that raises or returns the wrong number of values stops the run: the callback
records (t, x) and the failure, and the run calls the controller again as Python there to name
the file and line.
"""

from __future__ import annotations

import csv
import importlib.util
import math
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from andyc.errors import SimulationError

from andyc.numerics.status import INPUT_FAILED, MESSAGES, OK, RECORD
from andyc.runtime.controller import Controller, controller_callback, controller_failure, load_controller

@dataclass
class Table:
    path: Path
    column: str
    time: np.ndarray
    values: np.ndarray


@dataclass
class InputSource:
    """A run's inputs: the pair of compiled callbacks (None: held), their data, and what drives each input."""
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
        x = self.data[r + RECORD:r + RECORD + self.nx].copy()
        if self.controller is None:
            return f"{MESSAGES[INPUT_FAILED]} at t = {t:.9g} s"
        return controller_failure(self.controller, model, kind, t, count, x, d, p)


def inputs_at(model, source: InputSource, t: float, x, p, d, flow: int) -> np.ndarray:
    """The inputs at (t, x) in `flow` (a new array); SimulationError naming the controller's line if it fails."""
    u = np.empty(len(model.input_names))
    x = np.ascontiguousarray(x, dtype=np.float64)
    if source.into(model, t, x, p, d, flow, u) != OK:
        raise SimulationError(source.failure(model, d, p))
    return u


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
            expressions[name] = text
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
    data = [U.ravel(), np.zeros(RECORD + nx)]
    offsets = {}
    start = record + RECORD + nx
    for name, table in tables.items():
        offsets[name] = (start, table.time.shape[0])
        data += [table.time, table.values]
        start += 2 * table.time.shape[0]
    data = np.ascontiguousarray(np.concatenate(data))
    if not drives:
        return InputSource(None, data, nx, model.nf, record)
    callbacks = model.numerics.inputs.callbacks
    if ctrl is not None:                                    # it drives every input: the model's expressions do not
        function = callbacks(None, controller_callback(model, ctrl, record))
    else:
        held = [n for n, _ in model.input_expressions if n in numbers]
        run = _run_inputs(model, expressions, offsets, held) if (expressions or offsets or held) else None
        function = callbacks(model.module.MODEL_INPUTS, run)
    return InputSource(function, data, nx, model.nf, record, drives, ctrl)


def _is_number(value) -> bool:
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        return True
    try:
        float(str(value))
        return True
    except ValueError:
        return False


def _run_inputs(model, expressions: dict, tables: dict, held: list):
    """The run's input callback for its expressions (as written), tables ({input: (start, n)} in data) and the
    inputs it holds over the model's expressions: from the build folder's run_inputs/ when a run with these
    drives made it, else generated there (andyc.codegen.run_inputs), then imported (Numba loads its cache)."""
    from andyc.codegen.run_inputs import run_inputs_key, run_inputs_path

    key = run_inputs_key(model.module.BUILD_KEY, expressions, tables, held)
    path = run_inputs_path(model.path.parent, key)
    if not path.exists():
        from andyc.codegen.run_inputs import write_run_inputs
        from andyc.spec.expressions import ExpressionError

        names = {"states": model.state_names, "parameters": model.parameter_names, "discrete": model.discrete_names,
                 "inputs": model.input_names, "name": model.name,
                 "flow_sets_input": np.asarray(model.module.FLOW_SETS_INPUT).tolist()}
        for name, text in expressions.items():           # each alone first, to name the input that is wrong
            try:
                write_run_inputs(path, names, {name: text}, {}, [])
            except ExpressionError as exc:
                raise SimulationError(f"input {name}: {exc}; {exc.hint}") from None
        write_run_inputs(path, names, expressions, tables, held)
    module_name = f"andyc_run_inputs_{key}"
    module = sys.modules.get(module_name)
    if module is None:
        spec = importlib.util.spec_from_file_location(module_name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[module_name] = module
        spec.loader.exec_module(module)
    return module.run_inputs


MAX_TABLE_BYTES = 256 * 2**20       # an input's table is read whole, into Python lists: bounded


def read_table(path: Path, name: str, t_end: float | None) -> Table:
    """A CSV table of an input: a header row, a time column `t` or `time`, one row per time, in increasing time.

    Stops at the first problem with FILE:LINE: a missing or non-numeric value (a gap), a time that does
    not increase, or a table that does not cover the run (0 .. t_end).
    """
    if not path.exists():
        raise SimulationError(f"{path}: no such file (the table of input {name})")
    if not path.is_file():                  # a pipe would be waited on, a device read without end
        raise SimulationError(f"{path}: is a {'folder' if path.is_dir() else 'special file'}, not a CSV table (the "
                              f"table of input {name}); give a regular file")
    if path.stat().st_size > MAX_TABLE_BYTES:
        raise SimulationError(f"{path}: {path.stat().st_size / 2**20:.0f} MB, past andyc's limit of "
                              f"{MAX_TABLE_BYTES // 2**20} MB for the table of input {name}; give a shorter table")
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


