"""simulate: how a plain `andyc sim MODEL` runs the model, in the names of andyc sim's options.

The schema checks each value's type and range; here the names the values refer to (frames, jumps) are
checked against the model. The section is runtime data (andyc.spec.meaning leaves it out of the build
key): it is written into the generated module's front file, which `andyc sim` reads without SymPy.
"""

from __future__ import annotations

from andyc.spec.scope import Scope

# andyc sim's options that a simulate: section may give, in the order of `andyc sim --help`.
SIMULATE_OPTIONS = ("t_end", "dt", "method", "every", "frames", "init", "init_tol", "energy_correction", "energy_tol",
                    "event_tol", "max_instant_jumps", "zeno_tol", "stop_after", "rtol", "atol")


def build_simulate(given: dict | None, scope: Scope, jumps: list) -> dict:
    """The section's options as plain data ({} without one); frames and jumps it names must exist."""
    if not given:
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
    return out
