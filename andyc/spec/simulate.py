"""simulate: how a plain `andyc sim MODEL` runs the model, in the names of andyc sim's options.

The schema checks each value's type and range; here the names the values refer to (frames, jumps) are
checked against the model. The section is runtime data (andyc.spec.meaning leaves it out of the build
key): it is written into the generated module's front file, which `andyc sim` reads without SymPy.
"""

from __future__ import annotations

import math

from andyc.limits import MAX_STEPS
from andyc.spec.scope import Scope

# andyc sim's options that a simulate: section may give, in the order of `andyc sim --help`.
SIMULATE_OPTIONS = ("t_end", "dt", "method", "every", "frames", "init", "init_tol", "energy_correction", "energy_tol",
                    "event_tol", "max_instant_jumps", "zeno_tol", "stop_after", "rtol", "atol")


# andyc sim's defaults, with which a section's t_end or dt makes its run's steps; and the largest count
# (every, max_instant_jumps, a jump's number) the command line accepts too.
DEFAULT_T_END, DEFAULT_DT = 10.0, 1e-3
MAX_COUNT = 10**12


def finite_numbers(value, where: tuple, report) -> bool:
    """Report every number in `value` (a scalar, or lists and mappings of them) that is NaN or infinite (JSON
    Schema's bounds let both through: every comparison with NaN is false, and inf is above any minimum), or a
    whole number past MAX_COUNT; True when there is none."""
    if isinstance(value, bool):
        return True
    if isinstance(value, dict):
        return all([finite_numbers(v, where + (k,), report) for k, v in value.items()])
    if isinstance(value, list):
        return all([finite_numbers(v, where + (k,), report) for k, v in enumerate(value)])
    if isinstance(value, float) and not math.isfinite(value):
        report.error(where, f"{value} is not a finite number", "give a finite number")
        return False
    if isinstance(value, int) and abs(value) > MAX_COUNT:
        report.error(where, f"{value:.3g} is past the limit of {MAX_COUNT:.0e}", "give a smaller whole number")
        return False
    return True


def check_steps(t_end: float, dt: float, where: tuple, report) -> None:
    """A run of more steps than any machine makes is reported at `where` (its t_end or dt)."""
    if t_end / dt > MAX_STEPS:
        report.error(where, f"t_end / dt = {t_end / dt:.3g} steps, past the limit of {MAX_STEPS:.0e}",
                     "shorten t_end or raise dt")


def build_simulate(given: dict | None, scope: Scope, jumps: list) -> dict:
    """The section's options as plain data ({} without one); frames and jumps it names must exist, numbers
    are finite."""
    if not given:
        return {}
    if not finite_numbers(given, ("simulate",), scope.report):
        return {}
    out = {k: given[k] for k in SIMULATE_OPTIONS if k in given}
    if isinstance(out.get("frames"), list):
        for i, name in enumerate(out["frames"]):
            scope.known_frame(name, ("simulate", "frames", i))
    for name in out.get("stop_after") or {}:
        scope.known(name, [j.name for j in jumps], ("simulate", "stop_after", name), "jump")
    if "t_end" in out and "dt" in out and out["t_end"] < out["dt"]:
        scope.report.error(("simulate", "dt"), f"dt = {out['dt']:g} s is longer than t_end = {out['t_end']:g} s",
                           "give a step shorter than the run")
    elif "t_end" in out or "dt" in out:
        check_steps(out.get("t_end", DEFAULT_T_END), out.get("dt", DEFAULT_DT),
                    ("simulate", "t_end" if "t_end" in out else "dt"), scope.report)
    return out
