"""The expectations of a model (its expect: section, andyc.spec.expect), run and measured: `andyc test`.

Each expectation is one short run, with the run options it gives over the model's simulate: section over
simulate()'s defaults (the same as andyc sim's). Every expectation yields one Outcome for the run itself
(it must finish), then one per check:

    energy_drift     max_k |E_k - E_0|                                     <= bound (J)
    energy_balance   max_k |E_k - E_0 - W_k|, W the work the run integrated with the motion (every element
                     that does work, and the energy jumps changed: andyc.runtime.work; Run.energy_balance)
                                                                           <= bound (J)
    residual         max over samples and active rows of |phi|, |c| (ANDY eq. 10-11)  <= bound
    jumps            the count of each jump                                == given
    jump_times       each jump's times t_j, in order, |t_j - given_j| <= tol, and as many
    states           max_i |x_i(t) - target_i| <= tol; x(t) linear between samples (exact on a sample); the
                     target: given values, the closed form x(t) (the model's closed_form), or a stored run
                     file's states at t (linear between its samples)
    final            min <= f(final state) <= max, f parsed by andyc.spec.expressions, evaluated
                     on numbers by andyc.analysis.evaluate (as sweeps' --metric), never as code
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from andyc.analysis.evaluate import numeric
from andyc.errors import SimulationError, printable
from andyc.spec.expect import Check, Expectation


@dataclass
class Outcome:
    """One expectation's run or one of its checks: where it is written, whether it holds, and the figures."""
    file: str                   # the model file, as the user named it
    line: int
    path: str                   # expect[i] (the run) or expect[i].<check>
    kind: str                   # "run" or the check's kind
    ok: bool
    measured: str
    expected: str
    seconds: float = 0.0        # the run's wall time (on the run's outcome)

    def __str__(self) -> str:
        return printable(f"{self.file}:{self.line}: {self.path}: measured {self.measured}, expected {self.expected}")

    def as_dict(self) -> dict:
        return {"file": self.file, "line": self.line, "path": self.path, "kind": self.kind, "ok": self.ok,
                "measured": self.measured, "expected": self.expected, "message": str(self)}


def run_expectations(spec, model, file=None) -> list[Outcome]:
    """Run each expectation of `spec` (a Spec) on `model` (its CompiledModel); one Outcome per run and check.

    `file`: the model file as the user named it, for the outcomes' locations (default spec.file)."""
    file = spec.file if file is None else str(file)
    out = []
    for e in spec.expect:
        out += _expectation(spec, model, file, e)
    return out


def _options(spec, e: Expectation) -> dict:
    """The run's options: the expectation's over the model's simulate: section (its run options)."""
    from andyc.spec.expect import RUN_OPTIONS

    return {**{k: v for k, v in spec.simulate.items() if k in RUN_OPTIONS}, **e.run}


def _expectation(spec, model, file: str, e: Expectation) -> list[Outcome]:
    import andyc

    o = _options(spec, e)
    line = spec.source.line(e.where)
    where = f"expect[{e.index}]"
    start = time.perf_counter()
    try:
        run = andyc.simulate(
            model, o["t_end"], dt=o.get("dt", 1e-3), method=o.get("method", "rk4"), parameters=e.parameters,
            inputs=e.inputs, rtol=o.get("rtol", 1e-8), atol=o.get("atol", 1e-10), progress=False,
            init=andyc.Init(mode=o.get("init", "check"), tol=o.get("init_tol", 1e-6)),
            projection=andyc.Projection(energy_correction=o.get("energy_correction")),
            events=andyc.Events(tol=o.get("event_tol", 1e-12), max_instant_jumps=o.get("max_instant_jumps", 100),
                                zeno_tol=o.get("zeno_tol", 1e-6)))
    except SimulationError as exc:
        return [Outcome(file, line, where, "run", False, f"a run refused ({exc})", f"a run to t = {o['t_end']:g} s")]
    seconds = time.perf_counter() - start
    out = [Outcome(file, line, where, "run", run.finished,
                   f"{run.status} at t = {run.time[-1]:.6g} s" if not run.finished else f"finished at t = "
                   f"{run.time[-1]:.6g} s", f"finished at t = {o['t_end']:g} s", seconds)]
    for check in sorted(e.checks, key=lambda c: spec.source.line(c.where)):      # in the file's order
        ok, measured, expected = MEASURES[check.kind](check, run, model, spec)
        out.append(Outcome(file, spec.source.line(check.where), _path(check.where), check.kind, bool(ok), measured,
                           expected))
    return out


def _path(where: tuple) -> str:
    from andyc.errors import format_path

    return format_path(where)


def _bounded(value: float, bound: float, what: str, unit: str = "") -> tuple:
    return (value <= bound, f"{what} {value:.3g}{unit}", f"<= {bound:g}{unit}")


def _energy_drift(check: Check, run, model, spec) -> tuple:
    drift = float(np.max(np.abs(run.energy - run.energy[0]))) if run.energy.size else 0.0
    return _bounded(drift, check.data["bound"], "largest |E(t) - E(0)|", " J")


def _energy_balance(check: Check, run, model, spec) -> tuple:
    gap = float(np.max(np.abs(run.energy_balance))) if run.energy.size else 0.0
    return _bounded(gap, check.data["bound"], "largest |E(t) - E(0) - W(t)|", " J")


def _residual(check: Check, run, model, spec) -> tuple:
    largest = max(float(np.nanmax(np.abs(a), initial=0.0)) if a.size else 0.0
                  for a in (run.residual_position, run.residual_velocity))
    return _bounded(largest, check.data["bound"], "largest constraint residual")


def _counts(run) -> dict:
    counts = dict.fromkeys(run.jump_names, 0)
    for name in run.event_names():
        counts[name] += 1
    return counts


def _jumps(check: Check, run, model, spec) -> tuple:
    counts = _counts(run)
    wanted = check.data["counts"]
    got = {n: counts.get(n, 0) for n in wanted}
    return (got == wanted, ", ".join(f"{n} {c}" for n, c in got.items()) + " jumps",
            ", ".join(f"{n} {c}" for n, c in wanted.items()))


def _jump_times(check: Check, run, model, spec) -> tuple:
    names, times = run.event_names(), run.events["time"]
    tol, wrong = check.data["tol"], []
    for name, wanted in check.data["times"].items():
        got = [float(t) for n, t in zip(names, times) if n == name]
        if len(got) != len(wanted):
            wrong.append(f"{name} {len(got)} times ({_times(got)})")
            continue
        worst = max((abs(a - b) for a, b in zip(got, wanted)), default=0.0)
        if worst > tol:
            k = int(np.argmax([abs(a - b) for a, b in zip(got, wanted)]))
            wrong.append(f"{name} #{k + 1} at t = {got[k]:.9g} s, off by {worst:.3g} s")
    expected = "; ".join(f"{n} {len(w)} times ({_times(w)}) each within {tol:g} s"
                         for n, w in check.data["times"].items())
    return (not wrong, "; ".join(wrong) if wrong else "all within tol", expected)


def _times(ts) -> str:
    shown = ", ".join(f"{t:.6g}" for t in ts[:6])
    return shown + (", ..." if len(ts) > 6 else "")


def _at(run_time, states, t: float) -> np.ndarray:
    return np.array([np.interp(t, run_time, states[:, i]) for i in range(states.shape[1])])


def _states(check: Check, run, model, spec) -> tuple:
    t, tol = check.data["t"], check.data["tol"]
    if t > run.time[-1] + 1e-12 * max(1.0, t):
        return False, f"no sample at t = {t:g} s (the run ended at {run.time[-1]:.6g} s)", f"states at t = {t:g} s"
    names = list(run.state_names) + list(run.discrete_names)
    here = dict(zip(names, np.concatenate([_at(run.time, run.state, t), _at(run.time, run.discrete, t)])))
    if "values" in check.data:
        target, what = check.data["values"], "the values given"
    elif check.data.get("closed_form"):
        p, u = model.parameters(run.parameters), run.input_values[0]
        target, what = dict(zip(run.state_names, model.closed_form(float(t), u, p))), "the closed form"
    else:
        from andyc.runtime.runfiles import RunFileError, read_run_file

        try:
            reference = read_run_file(check.data["reference"])
        except RunFileError as exc:         # (not an HDF5 file, not andyc's layout, or damaged)
            return False, f"the run file cannot be read: {exc}", "a run file written by andyc sim (.h5)"
        if not len(reference.time) or t > reference.time[-1]:
            end = f"ends at {reference.time[-1]:.6g} s" if len(reference.time) else "holds no samples"
            return False, f"the reference run {end}", f"a reference sample at t = {t:g} s"
        missing = [n for n in run.state_names if n not in reference.state_names]
        if missing:
            return False, f"the reference run has no states {', '.join(missing)}", "a run of this model"
        ref = _at(reference.time, reference.state, t)
        target = {n: ref[reference.state_names.index(n)] for n in run.state_names}
        what = f"the run file {Path(check.data['reference']).name}"
    errors = {n: abs(here[n] - v) for n, v in target.items()}
    worst = max(errors, key=errors.get)
    return (errors[worst] <= tol, f"largest error {errors[worst]:.3g} at t = {t:g} s ({worst} = {here[worst]:.9g}, "
            f"target {target[worst]:.9g})", f"<= {tol:g} from {what}")


def _final(check: Check, run, model, spec) -> tuple:
    values = {}
    for name, symbol in check.data["symbols"].items():
        values[symbol.name] = run.parameters[name] if name in run.parameters else float(run.column(name)[-1])
    if check.data["time"]:
        from andyc.spec.expressions import TIME

        values[TIME.name] = float(run.time[-1])
    with np.errstate(all="ignore"):
        value = float(numeric(check.data["expr"], values))
    low, high = check.data["min"], check.data["max"]
    ok = math.isfinite(value) and (low is None or value >= low) and (high is None or value <= high)
    bounds = " and ".join(x for x in (f">= {low:.12g}" if low is not None else "",
                                       f"<= {high:.12g}" if high is not None else "") if x)
    shown = f"{value:.9g}" if math.isfinite(value) else f"{value} (not a real number)"
    return ok, f"{check.data['value']} = {shown} at t = {run.time[-1]:.6g} s", bounds


MEASURES = {"energy_drift": _energy_drift, "energy_balance": _energy_balance, "residual": _residual,
            "jumps": _jumps, "jump_times": _jump_times, "states": _states, "final": _final}
