"""`andyc cycle`: a periodic orbit through a jump, its period and Floquet multipliers (andyc.analysis.cycles)."""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import click

from andyc.cli.common import Refused, build_dir_option, compiled
from andyc.cli.values import COUNT, POSITIVE, Number, parse_sets
from andyc.errors import SimulationError
from andyc.outputs import check_folder, check_output, write_text


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--section", required=True, metavar="JUMP", help="The jump whose guard surface is the Poincaré section.")
@click.option("--period", default=1, show_default=True, type=COUNT,
              help="The orbit's period: the jump's occurrences from the section back to it.")
@click.option("--at", "at", multiple=True, metavar="NAME=VALUE", help="A parameter's value (others: the defaults).")
@click.option("--dt", default=1e-3, show_default=True, type=POSITIVE, help="The rk4 step, s.")
@click.option("--tol", default=1e-11, show_default=True, type=POSITIVE,
              help="Converged when the residual |Q(y) - y| on the section is at most this.")
@click.option("--max-iterations", default=20, show_default=True, type=COUNT, help="Newton steps at most.")
@click.option("--t-max", default=20.0, show_default=True, type=POSITIVE,
              help="The longest a run may take to come back to the section, s.")
@click.option("--event-tol", default=1e-14, show_default=True, type=Number(0, 1, low_open=True),
              help="Event location tolerance, s (round-off: the map's root, see andyc.runtime.sensitivities).")
@click.option("--continue", "continue_range", default=None, metavar="NAME=A:B",
              help="Continue the orbit in the parameter NAME from A to B (pseudo-arclength), locate its folds and "
                   "period doublings and follow the period-2N orbit from each doubling.")
@click.option("--step", "ds", default=0.01, show_default=True, type=POSITIVE,
              help="--continue: the first step along the branch (Euclidean length in the state and the parameter).")
@click.option("--min-step", "ds_min", default=1e-6, show_default=True, type=POSITIVE,
              help="--continue: stop when a step this short fails.")
@click.option("--max-step", "ds_max", default=0.1, show_default=True, type=POSITIVE,
              help="--continue: the longest step.")
@click.option("--max-points", default=200, show_default=True, type=COUNT, help="--continue: points per branch at most.")
@click.option("--locate-tol", default=1e-10, show_default=True, type=POSITIVE,
              help="--continue: locate folds and period doublings to this in the parameter.")
@click.option("--branch/--no-branch", "branch_switch", default=True, show_default=True,
              help="--continue: follow the period-2N orbit from each period doubling.")
@click.option("--plot-state", default=None, metavar="NAME",
              help="--continue: the state (just after the jump) the bifurcation diagram draws (default: the one that "
                   "varies most).")
@click.option("--basin", "basin", multiple=True, metavar="NAME=FROM:TO:COUNT",
              help="The basin of attraction of the orbit over a grid of two starting states (give it twice): each "
                   "start classified as reaching the cycle, falling, another orbit or other; run on the sweep engine.")
@click.option("--steps", default=50, show_default=True, type=COUNT, help="--basin: steps (crossings) per start at most.")
@click.option("--basin-tol", default=1e-6, show_default=True, type=POSITIVE,
              help="--basin: a start reaches the cycle when a crossing is this close to it (largest component).")
@click.option("--fall", default="", metavar="CONDITION",
              help="--basin: a step after which this holds falls, a comparison of the step's run as a sweep's "
                   "--metric, e.g. 'min(y) < 0.5' (a step that does not reach the section falls too).")
@click.option("--workers", default=None, type=Number(1, 4096, integer=True), metavar="N",
              help="--basin: threads of this process the starts run on (default: one per core).")
@click.option("--batch", default=None, type=Number(1, 1_000_000, integer=True), metavar="N",
              help="--basin: starts per batch (default: about a second's worth).")
@click.option("-o", "--out", default=None, metavar="FILE.json",
              help="Where to write the result (default: runs/<name>_cycle_<JUMP>.json; with --continue "
                   "runs/<name>_continuation_<JUMP>_<NAME>.json, with the branch table FILE.csv and the plot FILE.png "
                   "beside it; with --basin the store runs/<name>_basin_<JUMP>.zarr, with the map .png beside it).")
@build_dir_option()
def cycle(file, section, period, at, dt, tol, max_iterations, t_max, event_tol, continue_range, ds, ds_min, ds_max,
          max_points, locate_tol, branch_switch, plot_state, basin, steps, basin_tol, fall, workers, batch, out,
          build_dir):
    """Find FILE's periodic orbit through the jump JUMP: Newton's method on the Poincaré map with its exact
    Jacobian (rk4 sensitivities and saltation matrices); print the fixed point just after the jump, the period,
    the Floquet multipliers and the residual of each iterate, and write them as JSON. Exit 1 when it does not
    converge or the section is never reached.

    With --continue NAME=A:B, follow the orbit from NAME = A to B by pseudo-arclength continuation, print each
    point and the located folds, branch points and period doublings, and write the branches as JSON and CSV with
    a plot (bifurcation diagram and multipliers). Exit 1 when no orbit is found at A.

    With --basin NAME=FROM:TO:COUNT twice, classify each start of that grid (the other components at the fixed
    point, put on the constraint manifold) as reaching the cycle, falling, another orbit or other, on the sweep
    engine (batched, in this process's threads), into a Zarr store with its map."""
    import andyc
    from andyc.analysis.cycles import CycleError, find_cycle

    parameters = parse_sets(at, "--at")
    swept = _continue_range(continue_range) if continue_range is not None else None
    if basin and swept is not None:
        raise Refused("--basin and --continue: give one of them")
    if basin:
        from andyc.analysis.sweeps import missing_extra

        needs = missing_extra("andyc cycle --basin", "zarr", "xarray")
        if needs:
            raise Refused(needs)
    if out is not None and not basin:
        check_output(out, [file], "cycle file")
    check_folder(build_dir, [file], write=False)     # (an up-to-date build is only read)
    _refuse_contacts(file)
    model, _ = compiled(file, build_dir, integrator=False)   # (its runs, rk4, compile what they call: not every method)
    if section not in model.jump_names:
        raise click.BadParameter(f"{model.name} has no jump '{section}'; jumps: {', '.join(model.jump_names) or 'none'}",
                                 param_hint="--section")
    unknown = sorted(set(parameters) - set(model.parameter_names))
    if unknown:
        raise click.BadParameter(f"no parameter named {', '.join(unknown)}; parameters: "
                                 f"{', '.join(model.parameter_names)}", param_hint="--at")
    points = None
    if basin:
        from andyc.cli.basin import basin_points

        points = basin_points(basin, model, fall)
    if swept is not None:
        return _continuation(file, build_dir, model, section, period, parameters, swept, out, plot_state,
                             dict(dt=dt, tol=tol, t_max=t_max, event_tol=event_tol, ds=ds, ds_min=ds_min,
                                  ds_max=ds_max, max_points=max_points, locate_tol=locate_tol), branch_switch)
    store, out = (out, None) if basin else (None, out)
    out = out or f"runs/{model.name}_cycle_{section}.json"
    check_output(out, [file, model.path], "cycle file")
    try:
        andyc.build_derivatives(file, build_dir)
        at_text = ", ".join(f"{k} = {v:g}" for k, v in parameters.items()) or "the defaults"
        click.echo(f"{model.name}: periodic orbit through '{section}' (period {period}), parameters at {at_text}")
        result = find_cycle(model, section, period, parameters, dt=dt, tol=tol, max_iterations=max_iterations,
                            t_max=t_max, event_tol=event_tol,
                            progress=lambda i, r: click.echo(f"  iteration {i}: residual {r:.3e}"))
    except (SimulationError, CycleError) as exc:
        raise Refused(str(exc))
    click.echo(report(result))
    write_text(out, json.dumps(result.as_dict(), indent=1) + "\n")
    click.echo(f"wrote {out}")
    if not result.converged:
        sys.exit(1)
    if points is not None:
        from andyc.cli.basin import run_basin

        run_basin(file, model, result, points, dict(steps=steps, tol=basin_tol, t_step=t_max, dt=dt,
                                                   event_tol=event_tol, fall=fall), store, workers, batch)


def _refuse_contacts(file) -> None:
    """Refused (before any build) for a model with contacts: the cycle's Newton method differentiates the flow and
    the jumps (andyc.runtime.sensitivities), and a contact's impact, liftoff, stick and slip are decided by a
    complementarity problem it does not differentiate."""
    from andyc.cli.common import fail_spec
    from andyc.errors import SpecError
    from andyc.pipeline import load

    try:
        spec = load(file)
    except SpecError as exc:
        fail_spec(exc)
    if spec.contacts:
        line = spec.source.line(("contacts",))
        raise Refused(f"{file}:{line}: contacts: andyc cycle follows a gait through hand-written jumps, whose "
                      f"derivatives it takes; the impacts and stick-slip changes of contacts "
                      f"({', '.join(c.name for c in spec.contacts[:3])}{', ...' if len(spec.contacts) > 3 else ''}) "
                      "are decided by a complementarity problem it does not differentiate; write them as jumps of "
                      "a hybrid: section to find the gait's cycle (models/compass_gait.yaml)")


def _continue_range(text: str) -> tuple:
    """NAME=A:B -> (NAME, A, B); a usage error otherwise."""
    name, sep, span = text.partition("=")
    parts = span.split(":")
    try:
        if not sep or not name.strip() or len(parts) != 2:
            raise ValueError
        a, b = float(parts[0]), float(parts[1])
    except ValueError:
        raise click.BadParameter(f"'{text}': write NAME=A:B, e.g. slope=0.05:0.1", param_hint="--continue") from None
    if not (math.isfinite(a) and math.isfinite(b)) or a == b:
        raise click.BadParameter(f"'{text}': A and B must be finite and differ", param_hint="--continue")
    return name.strip(), a, b


def _continuation(file, build_dir, model, section, period, parameters, swept, out, plot_state, options,
                  branch_switch):
    """andyc cycle --continue: the branches, printed as they come, then written (JSON, CSV, PNG)."""
    import numpy as np

    import andyc
    from andyc.analysis.continuation import Continuer, Point, describe, save_csv, special_line
    from andyc.analysis.cycles import CycleError

    name, a, b = swept
    if name not in model.parameter_names:
        raise click.BadParameter(f"no parameter named {name}; parameters: {', '.join(model.parameter_names)}",
                                 param_hint="--continue")
    if name in parameters:
        raise click.BadParameter(f"{name} is continued; do not also set it with --at", param_hint="--at")
    names = list(model.state_names) + list(model.discrete_names)
    if plot_state is not None and plot_state not in names:
        raise click.BadParameter(f"no state named {plot_state}; states: {', '.join(names)}", param_hint="--plot-state")
    out = Path(out or f"runs/{model.name}_continuation_{section}_{name}.json")
    table, figure = out.with_suffix(".csv"), out.with_suffix(".png")
    for path, what in ((out, "continuation file"), (table, "branch table"), (figure, "plot")):
        check_output(path, [file, model.path], what)

    def show(obj, n):
        if isinstance(obj, Point):
            mods = np.abs(obj.multipliers)
            click.echo(f"  period {n}: {name} = {obj.parameter:.12g}, period {obj.period:.9g} s, max |mu| "
                       f"{mods.max(initial=0.0):.6g} ({'stable' if obj.stable else 'unstable'}), "
                       f"{obj.iterations} corrector step(s)")
        else:
            click.echo(f"  -> {special_line(name, obj)}")

    try:
        andyc.build_derivatives(file, build_dir)
        held = ", ".join(f"{k} = {v:g}" for k, v in parameters.items()) or "the defaults"
        click.echo(f"{model.name}: periodic orbits through '{section}' (period {period}) continued in {name} from "
                   f"{a:g} to {b:g}; other parameters at {held}")
        result = Continuer(model, section, name, parameters, progress=show, **options).run(a, b, period,
                                                                                          branch_switch)
    except (SimulationError, CycleError) as exc:
        raise Refused(str(exc))
    click.echo(describe(result))
    write_text(out, json.dumps(result.as_dict(), indent=1) + "\n")
    click.echo(f"wrote {out}")
    if result.branches[0].points:
        from andyc.plot.branchplot import plot_branches

        save_csv(result, table)
        click.echo(f"wrote {table}")
        plot_branches(result, figure, None if plot_state is None else names.index(plot_state))
        click.echo(f"wrote {figure}")
    else:
        sys.exit(1)


def report(result) -> str:
    """The result for reading: whether it converged, the fixed point, the period, the multipliers."""
    if not result.converged:
        return f"not converged: {result.message}"
    state = ", ".join(f"{n} = {v:.12g}" for n, v in zip(result.state_names + result.discrete_names,
                                                        [*result.state, *result.discrete]))
    mult = ", ".join((f"{m.real:.12g} {'+' if m.imag >= 0 else '-'} {abs(m.imag):.12g}i" if m.imag else
                      f"{m.real:.12g}") + f" (|.| {abs(m):.6g})" for m in result.multipliers)
    dims = result.basis.shape[1]
    sym = result.symmetries.shape[1] if result.symmetries is not None else 0
    stable = "stable" if len(result.multipliers) and max(abs(result.multipliers)) < 1 else "unstable"
    return "\n".join([f"{result.message}",
                      f"fixed point just after '{result.section}': {state}",
                      f"period: {result.period:.12g} s",
                      f"Floquet multipliers ({dims} on the section; flow direction and {sym} symmetr"
                      f"{'y' if sym == 1 else 'ies'} left out): {mult} -- {stable}"])


__all__ = ["cycle"]
