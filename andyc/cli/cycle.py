"""`andyc cycle`: a periodic orbit through a jump, its period and Floquet multipliers (andyc.analysis.cycles)."""

from __future__ import annotations

import json
import sys

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
@click.option("-o", "--out", default=None, metavar="FILE.json",
              help="Where to write the result (default: runs/<name>_cycle_<JUMP>.json).")
@build_dir_option()
def cycle(file, section, period, at, dt, tol, max_iterations, t_max, event_tol, out, build_dir):
    """Find FILE's periodic orbit through the jump JUMP: Newton's method on the Poincaré map with its exact
    Jacobian (rk4 sensitivities and saltation matrices); print the fixed point just after the jump, the period,
    the Floquet multipliers and the residual of each iterate, and write them as JSON. Exit 1 when it does not
    converge or the section is never reached."""
    import andyc
    from andyc.analysis.cycles import CycleError, find_cycle

    parameters = parse_sets(at, "--at")
    if out is not None:
        check_output(out, [file], "cycle file")
    check_folder(build_dir, [file])
    model, _ = compiled(file, build_dir)
    if section not in model.jump_names:
        raise click.BadParameter(f"{model.name} has no jump '{section}'; jumps: {', '.join(model.jump_names) or 'none'}",
                                 param_hint="--section")
    unknown = sorted(set(parameters) - set(model.parameter_names))
    if unknown:
        raise click.BadParameter(f"no parameter named {', '.join(unknown)}; parameters: "
                                 f"{', '.join(model.parameter_names)}", param_hint="--at")
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
