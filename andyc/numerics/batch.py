"""Many runs of one model in one compiled call: the batched engine of sweeps.

run_points integrates each point of a batch (its parameters, held inputs, input data, initial state and
energy offset: one row of each array) from t = 0 over the same grid of fixed steps, by the same
integrator.advance a single run calls, so that each point's states are a single run's bit for bit (the steps do
not depend on where the loop returns: advance starts each call from the state it left, on the grid t0 + i dt).
It runs without the GIL, so that threads share the cores, and holds no Python object per point or step.

A point that meets a jump, or that stops (non-finite, diverged, an input callback failed), ends there with its
status; its caller runs it again alone to say why (andyc.analysis.sweeps.batch). Points are started while
stop[0] is 0, and a point checks it every CHUNK steps: a Ctrl-C ends a batch within a fraction of a second.
"""

import numpy as np

from .compiler import jit
from .integrator import Log, Options, advance
from .status import OK

CHUNK = 100_000         # steps between looks at the stop flag
NOT_RUN = -1            # the status of a point not started, or left unfinished, because stop[0] was set
JUMPED = -2             # the status of a point that met a jump (the batched engine follows none)


def row(data, k):
    """data[k], or None for data None: typed apart (an overload), so that advance is compiled for None, as a single
    run with held inputs calls it (Numba does not prune a branch on `data is None` where data is an array)."""
    return None if data is None else data[k]


try:
    from numba import types
    from numba.extending import overload

    @overload(row)
    def _row(data, k):
        if isinstance(data, types.NoneType):
            return lambda data, k: None
        return lambda data, k: data[k]
except ImportError:         # (without Numba, plain Python: row as it is)
    pass


@jit(nogil=True)
def run_points(model, w, mode, project, constrain, energy_tol, event_tol, inputs, data, P, U, D, X, F, E0, steps, dt,
               marks, stop, status, done, samples, full=True, events=True, free=None):
    """Run point k (k = 0, 1, ...) of the batch: parameters P[k], held inputs U[k] (w.u at each call of advance,
    as the single run sets it), input data data[k] (None with inputs None: held inputs), discrete states D[k],
    flow F[k], state X[k] (the state then the work of each slot, andyc.runtime.work; changed in place into the
    final one) and energy offset E0[k] (integrator.Options.e0), over `steps` steps of dt from t = 0, with the
    options of integrator.options (mode, project, constrain, energy_tol, event_tol) and advance's variant (full,
    events, free). After step marks[m] (ascending; 0: the start), the state goes to samples[k, m].

    status[k]: OK when the point reached t = steps dt, else the status it stopped with (integrator statuses),
    JUMPED (a jump was met at the time reached) or NOT_RUN; done[k]: the steps it took (its grid index)."""
    nm = marks.shape[0]
    log = Log(np.zeros(1), np.zeros((1, X.shape[1])), np.zeros((1, U.shape[1])), np.zeros(1, np.int64),
              np.zeros((1, D.shape[1])))
    never = steps + 1           # advance logs no row: a grid index past the last is never a multiple of it
    for k in range(X.shape[0]):
        status[k], done[k] = NOT_RUN, 0
        if stop[0] != 0:
            continue
        x, d, p, flow = X[k], D[k], P[k], F[k]
        opts = Options(mode, project, constrain, E0[k], energy_tol, event_tol)
        i, t, st, m = 0, 0.0, OK, 0
        while m < nm and marks[m] == 0:
            samples[k, m, :] = x[:samples.shape[2]]
            m += 1
        while i < steps and st == OK and stop[0] == 0:
            i_end = min(steps, i + CHUNK)
            if m < nm:
                i_end = min(i_end, marks[m])
            w.u[:] = U[k]
            i, _, st, t, flow, jump = advance(model, w, opts, inputs, row(data, k), p, d, x, t, flow, i, i_end, 0.0,
                                              dt, never, log, 0, full, events, free)
            if st == OK and jump >= 0:
                st = JUMPED
            while st == OK and m < nm and marks[m] == i:
                samples[k, m, :] = x[:samples.shape[2]]
                m += 1
        F[k], done[k] = flow, i
        status[k] = st if (st != OK or i == steps) else NOT_RUN
