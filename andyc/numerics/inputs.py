"""What drives a run's inputs: compiled input callbacks, status = inputs(t, x, d, p, flow, u, data).

Every integrator takes its inputs as None (held: u stays as set for the flow) or as a pair of such
callbacks (callbacks()), called in turn before each evaluation at a new (t, x):

    the model's    its own input expressions (the module's model_inputs), or `hold` when it has none;
    the run's      what the run drives beyond that: its expressions and tables (a callback andyc
                   generates into the build folder, andyc/codegen/run_inputs.py), a controller
                   (andyc's runtime), or `keep` when nothing.

Both have the type of model.INPUTS_SIGNATURE, so the integrator compiles once for every input source.
`data` carries what they read:

    data = [ U (NF x NU)  |  failure record (RECORD + NX)  |  tables ]

U holds the constant inputs of each flow (the run's values, then the inputs a flow sets itself); a
callback that fails writes the record (failed) and returns nonzero, and the run says why.
"""

import numpy as np

from .compiler import jit
from .model import input_callback
from .status import RECORD, WRONG_SHAPE


@input_callback
def hold(t, x, d, p, flow, u, data):
    """u = the flow's constant inputs, U[flow] (for a model that drives none by an expression)."""
    nu = u.shape[0]
    for i in range(nu):
        u[i] = data[flow * nu + i]
    return 0


@input_callback
def keep(t, x, d, p, flow, u, data):
    """u as the model's callback left it (for a run that drives nothing more)."""
    return 0


def callbacks(model_inputs=None, run_inputs=None) -> tuple:
    """The integrator's pair of input callbacks: the model's (or hold), then the run's (or keep)."""
    return (model_inputs if model_inputs is not None else hold, run_inputs if run_inputs is not None else keep)


@jit
def interpolate(data, start, n, t):
    """Linear interpolation at t in the table data[start:start + n] (times), data[start + n:start + 2n] (values);
    the end values beyond its ends."""
    return np.interp(t, data[start:start + n], data[start + n:start + 2 * n])


@jit
def take(r, u, sets, flow, data, record, t, x):
    """u <- the controller's values r, except the inputs the flow sets itself (sets[flow, i]); a wrong number
    of values is recorded as a failure (the callback's nonzero status)."""
    if len(r) != len(u):
        return failed(data, record, WRONG_SHAPE, t, x, len(r))
    for i in range(len(u)):
        if not sets[flow, i]:
            u[i] = r[i]
    return 0


@jit
def failed(data, record, kind, t, x, count):
    """Record a failure at (t, x) in data[record:] for the run to report; the callback's nonzero status."""
    data[record] = kind
    data[record + 1] = t
    data[record + 2] = count
    for i in range(x.shape[0]):
        data[record + RECORD + i] = x[i]
    return 1
