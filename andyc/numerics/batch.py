"""Many runs of one model in one compiled call: the batched engine of sweeps.

run_points integrates each point of a batch (its parameters, held inputs, input data, initial state and
energy offset: one row of each array) over the same grid of fixed steps, by the same integrator.advance a single
run calls, so that each point's states are a single run's bit for bit: the steps do not depend on where the loop
returns, since advance starts each call from the state it left, on the grid t0 + i dt (a single run returns to
Python every quarter of a second). It runs without the GIL, so that threads share the cores, and holds no Python
object per point or step.

A point returns at a jump (its caller, andyc.analysis.sweeps.batch, finishes it in Python as a single run does:
the contact's resolution, the user's function, the event log, then calls again for the points that go on), at its
end, or at a failure (non-finite, diverged, an input callback failed: the caller runs it again alone to say why).
Points are started while stop[0] is 0, and a point checks it every CHUNK steps: a Ctrl-C ends a batch within a
fraction of a second.
"""

from .compiler import jit
from .integrator import Log, Options, advance
from .status import OK

CHUNK = 100_000         # steps between looks at the stop flag
NOT_RUN = -1            # the status of a point not started, or left unfinished, because stop[0] was set
JUMPED = -2             # the status of a point that returned at a jump


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
def run_points(model, w, mode, project, constrain, energy_tol, event_tol, inputs, data, todo, P, U, D, X, F, E0, I, T,
               steps, dt, marks, M, stop, status, jumped, XE, UE, samples, LT, LX, LU, LF, LD, R, every, full=True,
               events=True, free=None, quiet=None):
    """Run each point k of `todo` from step I[k] at time T[k] (0 and 0.0 at its start; I[k] dt <= T[k]) to the grid's
    end, t = steps dt, or to its next jump: parameters P[k], held inputs U[k] (w.u at each call of advance, as the
    single run sets it), input data data[k] (None with inputs None: held inputs), discrete states D[k], flow F[k],
    state X[k] (the state then the work of each slot, andyc.runtime.work) and energy offset E0[k]
    (integrator.Options.e0), with the options of integrator.options (mode, project, constrain, energy_tol,
    event_tol) and advance's variant (full, events, free, quiet). X, D, F, I and T are left where the point stopped. When
    the run reaches grid point i = marks[m] (ascending; m from M[k], left at the next), its state goes to
    samples[k, m]. With every <= steps, each point also logs every `every`-th grid point as a single run does, into
    the point's rows of LT, LX, LU, LF and LD (integrator.Log's fields: time, state and work, inputs, flow, discrete
    states) from row R[k] on (left at the next); with every = steps + 1 nothing is logged (those arrays may then
    hold one row each).

    status[k]: OK when the point reached the end, JUMPED when advance applied a jump (its index in jumped[k], the
    state just before it in XE[k], the inputs there in UE[k]; the caller finishes the jump and runs the point on),
    NOT_RUN when stop[0] was set first, else the status it stopped with (integrator statuses)."""
    nm = marks.shape[0]
    for q in range(todo.shape[0]):
        k = todo[q]
        status[k] = NOT_RUN
        if stop[0] != 0:
            continue
        x, d, p, flow = X[k], D[k], P[k], F[k]
        opts = Options(mode, project, constrain, E0[k], energy_tol, event_tol)
        i, t, st, m, jump, r = I[k], T[k], OK, M[k], -1, R[k]
        log = Log(LT[k], LX[k], LU[k], LF[k], LD[k])
        while True:
            # (advance stops at each mark: a point resumed within a step, after a jump, has passed its marks so far)
            while m < nm and marks[m] == i:
                samples[k, m, :] = x[:samples.shape[2]]
                m += 1
            if i >= steps or st != OK or jump >= 0 or stop[0] != 0:
                break
            i_end = min(steps, i + CHUNK)
            if m < nm:
                i_end = min(i_end, marks[m])
            w.u[:] = U[k]
            i, r, st, t, flow, jump = advance(model, w, opts, inputs, row(data, k), p, d, x, t, flow, i, i_end, 0.0,
                                              dt, every, log, r, full, events, free, quiet)
        F[k], I[k], T[k], M[k], R[k] = flow, i, t, m, r
        if st == OK and jump >= 0:
            st = JUMPED
            jumped[k] = jump
            XE[k, :] = w.x_event
            UE[k, :] = w.u
        status[k] = st if (st != OK or i >= steps) else NOT_RUN
