"""A run's controller: `u = control(t, x, d, p)` from a Python file, checked by one call at the initial state,
compiled with Numba where it can be (else called as Python, with a warning), and wrapped as the run's input
callback (andyc_numerics/inputs.py's signature); a failure named by the file and line of the user's code.
andyc.runtime.inputs puts it among a run's input sources."""

from __future__ import annotations

import importlib.util
import inspect
import re
import sys
import traceback
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from andyc.errors import SimulationError
from andyc.numerics.status import RAISED, WRONG_SHAPE

# What the user's code may raise and the run reports: its exceptions, and sys.exit(), which must not end
# andyc (a KeyboardInterrupt still does).
USER_ERRORS = (Exception, SystemExit)


class InputWarning(UserWarning):
    """A controller runs as Python because Numba cannot compile it."""


@dataclass
class Controller:
    path: Path
    function: object        # the user's control, as Python
    compiled: object        # Numba's compilation of it, or None when it runs as Python
    returns_scalar: bool


def raised(exc: BaseException) -> str:
    """What the user's code raised, in words: `ValueError: text`, or that it called sys.exit()."""
    if isinstance(exc, SystemExit):
        return f"called sys.exit({'' if exc.code is None else repr(exc.code)})"
    return f"raised {type(exc).__name__}: {exc}"


def where(path: Path, line: int | None) -> str:
    return f"{path}:{line}" if line else str(path)


def expected(model) -> str:
    n = len(model.input_names)
    return (f"{model.name} has {n} input{'' if n == 1 else 's'} ({', '.join(model.input_names)}): return "
            + ("one number" if n == 1 else f"a sequence of {n} numbers in this order"))


def user_line(exc: BaseException, path: Path) -> int | None:
    """The deepest line of `path` in the exception's traceback."""
    return next((f.lineno for f in reversed(traceback.extract_tb(exc.__traceback__))
                 if Path(f.filename).resolve() == path), None)


def return_line(function, t, x, d, p) -> int | None:
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


def controller_failure(c: Controller, model, kind, t: float, count: int, x, d, p) -> str:
    """Why a controller's callback failed (its record: kind, t, count, x), naming the controller's file and line:
    the wrong number of values, or what it raises when called again as Python there."""
    if kind == WRONG_SHAPE:
        line = return_line(c.function, t, x, d, p)
        return f"{where(c.path, line)}: control returned {count} values at t = {t:.9g} s; {expected(model)}"
    try:
        c.function(t, x, d.copy(), p.copy())
    except USER_ERRORS as exc:        # the user's code: report it, keep the run's data
        return f"{where(c.path, user_line(exc, c.path))}: control {raised(exc)} at t = {t:.9g} s"
    return (f"{c.path}: control raised an exception in compiled code at t = {t:.9g} s (Numba keeps no message), "
            f"but not when called again as Python there; check indexing past the end of an array, which "
            f"Numba does not catch")


def load_controller(path: Path, model, p) -> Controller:
    """Import `control(t, x, d, p)` from the file, call it once as Python at the initial state (to name the
    file and line of any problem before the run), and compile it with Numba when it can be."""
    path = path.resolve()
    if not path.exists():
        raise SimulationError(f"{path}: no such file (--controller)")
    if not path.is_file():
        raise SimulationError(f"{path}: is a {'folder' if path.is_dir() else 'special file'}, not a Python file "
                              f"(--controller); give a regular file")
    mod_name = f"andyc_controller_{abs(hash(str(path))):x}"
    spec = importlib.util.spec_from_file_location(mod_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[mod_name] = module
    try:
        spec.loader.exec_module(module)
    except USER_ERRORS as exc:
        line = (exc.lineno or 1) if isinstance(exc, SyntaxError) else user_line(exc, path)
        raise SimulationError(f"{where(path, line)}: importing the controller {raised(exc)}") from None
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
        raise SimulationError(f"{where(path, user_line(exc, path))}: control {raised(exc)} at t = 0 (the "
                              f"initial state)") from None
    scalar = isinstance(out, (int, float, np.floating, np.integer)) and not isinstance(out, bool)
    shape = np.shape(out) if not scalar else ()
    if not scalar and (len(shape) != 1 or shape[0] != len(model.input_names)):
        what = (f"an array of shape {shape}" if isinstance(out, np.ndarray) else
                f"a {type(out).__name__} of {len(out)} values" if hasattr(out, "__len__") else repr(out)[:60])
        raise SimulationError(f"{where(path, return_line(python, 0.0, x0, d0, p))}: control returned {what} at "
                              f"t = 0; {expected(model)}")
    if scalar and len(model.input_names) != 1:
        raise SimulationError(f"{where(path, return_line(python, 0.0, x0, d0, p))}: control returned one number "
                              f"at t = 0; {expected(model)}")
    compiled = numba_compile(control, python, path)
    return Controller(path, python, compiled, scalar)


def numba_compile(control, python, path: Path):
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
        warnings.warn(f"{where(path, int(found.group(1)) if found else None)}: Numba cannot compile control "
                      f"({first}); running it as Python, which costs some microseconds per call",
                      InputWarning, stacklevel=2)
        return None
    return jitted


def controller_callback(model, ctrl: Controller, record: int):
    """The run's input callback of a controller: it calls control(t, x, d, p) and writes every input the flow
    does not set; a controller that raises or returns the wrong number of values records why (see
    InputSource.failure). Compiled for each run, from closures over the controller (nothing executed as text)."""
    from numba import cfunc, njit, objmode

    failed, take = model.numerics.inputs.failed, model.numerics.inputs.take
    sets = np.ascontiguousarray(model.module.FLOW_SETS_INPUT)
    nx = model.nx       # the integrators' x carries the work after the state (andyc.runtime.work): not the user's
    if ctrl.compiled is None:
        python = ctrl.function

        def guarded(t, x, d, p):
            # An exception must not leave the object-mode block: raised inside a C callback, it would stay set
            # behind the compiled integrator's back. The run calls control again as Python there to say what
            # it raised and where.
            try:
                return np.ascontiguousarray(np.atleast_1d(python(t, x, d, p)), dtype=np.float64), True
            except BaseException:
                return np.zeros(0), False

        @njit
        def call_python(t, x, d, p):
            with objmode(r="float64[::1]", ok="boolean"):
                r, ok = guarded(t, x, d, p)
            return r, ok

        def inputs(t, x_work, d, p, flow, u, data):
            x = x_work[:nx]
            r, ok = call_python(t, x, d, p)
            if not ok:
                return failed(data, record, RAISED, t, x, 0)
            return take(r, u, sets, flow, data, record, t, x)
    elif ctrl.returns_scalar:
        control = ctrl.compiled

        def inputs(t, x_work, d, p, flow, u, data):
            x = x_work[:nx]
            try:
                r = control(t, x, d, p)
            except Exception:
                return failed(data, record, RAISED, t, x, 0)
            if not sets[flow, 0]:
                u[0] = r
            return 0
    else:
        control = ctrl.compiled

        def inputs(t, x_work, d, p, flow, u, data):
            x = x_work[:nx]
            try:
                r = control(t, x, d, p)
            except Exception:
                return failed(data, record, RAISED, t, x, 0)
            return take(r, u, sets, flow, data, record, t, x)

    try:
        return cfunc(model.numerics.model.INPUTS_SIGNATURE, error_model="numpy")(inputs)
    except Exception as exc:
        raise SimulationError(f"{ctrl.path}: cannot compile the inputs with Numba: {str(exc).splitlines()[0]}") from None
