"""A run's status and its messages.

A run ends "finished" (at t_end, or by Events.stop_after), "stopped: why" (a failure, a jump loop, Zeno, the
wall-clock limit) or "interrupted: why" (a signal), and a stopped run says how many samples it kept. The
reasons a compiled function fails come from the one table of status messages,
andyc.numerics.status.MESSAGES, shared with the compiled numerics; the jumps' stops are in EventLog
(andyc.runtime.events), the interruptions' in andyc.runtime.interrupts.
"""

from __future__ import annotations

import numpy as np

from andyc.numerics.status import DIVERGED, INPUT_FAILED, MESSAGES, NONFINITE

FINISHED = "finished"
INTERRUPTED = "interrupted"     # a partial run's status, built by the watchdog (andyc.runtime.interrupts)
ZENO = "stopped: Zeno behaviour"  # how the status of a run that EventLog stopped at a Zeno point begins

# What a run's status says, in short (a sweep records one per point: andyc.analysis.sweeps): its code and
# name. 0 is a point not run yet; "failed" a run that could not start or raised (the message says why).
OUTCOMES = {0: "not run", 1: "finished", 2: "stopped", 3: "blew up", 4: "Zeno", 5: "failed"}
NOT_RUN, FINISHED_CODE, STOPPED, BLEW_UP, ZENO_CODE, FAILED = range(6)


def at(t: float) -> str:
    """" at t = ... s": where a run stopped."""
    return f" at t = {t:.9g} s"


def outcome(status: str) -> int:
    """The OUTCOMES code of a run's status: finished; blew up (its state became non-finite, or diverged);
    Zeno; any other stop (or interruption): stopped."""
    if status == FINISHED:
        return FINISHED_CODE
    if status.startswith(ZENO):
        return ZENO_CODE
    if MESSAGES[NONFINITE] in status or MESSAGES[DIVERGED] in status:
        return BLEW_UP
    return STOPPED


def failure(model, source, status: int, t: float, d, p) -> str:
    """Why a step failed with `status` at t: the record of a failed input, or the status's message."""
    return source.failure(model, d, p) if status == INPUT_FAILED else MESSAGES[status] + at(t)


def in_jump(model, status: int, k: int, t: float) -> str:
    """The stop of a jump whose resets or impact failed with `status`."""
    return f"stopped: {MESSAGES[status]} in jump '{model.jump_names[k]}'" + at(t)


def nonfinite(t: float) -> str:
    """The stop of a run whose state became NaN or Inf at t."""
    return f"stopped: {MESSAGES[NONFINITE]}" + at(t)


def solver_failed(method: str, t: float, text: str) -> str:
    """The stop of a SciPy solver that failed at t, with its own message."""
    return f"stopped: {method} failed" + at(t) + f": {text}"


def ending(message: str | None, samples: int, jumps) -> str:
    """The status of a run that ended with `message` (None: it reached t_end) having logged `samples`:
    "finished", also when stop_after ended it (jumps.finished); otherwise the message and the samples kept."""
    if message is None or jumps.finished:
        return FINISHED
    return f"{message}; the {samples} samples before it are kept"


# The methods that do not correct a constraint's drift, and the residual past which a run with them has lost its
# constraints (a closed loop whose position or velocity residual passes it is no longer the mechanism).
DRIFTING_METHODS = ("rk4", "lagrange")
DRIFT_BOUND = 1e-3


def drift(method: str, residual: float, t: float) -> str:
    """The clause that says a run of a DRIFTING_METHODS method lost its constraints (largest residual `residual`,
    reached at t) and what to do about it; "" when it did not."""
    if method not in DRIFTING_METHODS or not residual > DRIFT_BOUND:
        return ""
    return (f"the constraints drifted to a residual of {residual:.3g}{at(t)} (past {DRIFT_BOUND:g}): {method} does "
            f"not correct the drift; use --method projection, which keeps them at round-off")


def lost_constraints(method: str, status: str, phi, c, time) -> str:
    """A stopped run's status with the drift clause (see `drift`) when the samples it kept had lost their
    constraints, or when they are non-finite or the run blew up (a closed loop blowing up)."""
    if not status.startswith("stopped") or method not in DRIFTING_METHODS or not (phi.size or c.size) or not len(time):
        return status
    residual, t = largest_residual(phi, c, time)
    blew = MESSAGES[NONFINITE] in status or MESSAGES[DIVERGED] in status
    if blew and not residual > DRIFT_BOUND:
        return status + (f"; {method} does not correct the constraints' drift (largest residual {residual:.3g}); "
                         "try --method projection")
    clause = drift(method, residual, t)
    return f"{status}; {clause}" if clause else status


def largest_residual(phi, c, time) -> tuple[float, float]:
    """(the largest |residual| over the samples and rows, position and velocity level, NaN rows skipped, inf
    for a non-finite one; the time of the sample where it is)."""
    both = np.abs(np.hstack([phi, c]))
    both = np.where(np.isnan(both), 0.0, both)
    row = np.max(both, axis=1) if both.shape[1] else np.zeros(len(time))
    k = int(np.argmax(row))
    return float(row[k]), float(time[k])


def diverging_constraints(model, t, x, u, p, d, flow) -> str:
    """Why a state may have diverged from (t, x), the last sound state, as a clause for the message: the
    flow's constraint rows nearly dependent there (a singular pose, where the constraint forces that keep
    the rows grow without bound), or nothing."""
    rows = model.active_rows(flow, d)
    if not rows:
        return ""
    A = np.zeros((model.nc, model.nv))
    model.module.constraints(t, x, u, p, d, np.empty(model.nh), np.empty(model.nc), A, np.empty(model.nc))
    M = model.module.mass_matrix(t, x, u, p, d)
    try:
        W = A[rows] @ np.linalg.solve(M, A[rows].T)
        sv = np.linalg.svd(W, compute_uv=False)
    except np.linalg.LinAlgError:
        return "; the mass matrix is singular there"
    if not np.all(np.isfinite(sv)) or sv[-1] < 1e-6 * sv[0]:
        names = ", ".join(dict.fromkeys(model.constraint_rows[r] for r in rows))
        return (f"; the constraint rows ({names}) are nearly dependent there (A M^-1 A^T has condition number "
                f"{sv[0] / max(sv[-1], 1e-300):.3g}): the mechanism reaches a singular pose, where its "
                f"constraint forces grow without bound")
    return ""
