"""`andyc linearize`: A and B of a flow about a point, with the eigenvalues (andyc.analysis.linearization)."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from pathlib import Path

import click

from andyc.cli.common import derived
from andyc.cli.values import Number, parse_sets, split_sets
from andyc.outputs import check_folder, check_output


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--at", "at", multiple=True, metavar="NAME=VALUE",
              help="The state to linearize about: a coordinate or speed (the others: the model's initial state).")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("--input", "input_values", multiple=True, metavar="NAME=VALUE",
              help="The inputs at the point (default: their held values); the same as --set for an input.")
@click.option("--flow", default=None, help="The flow to linearize (default: the initial flow).")
@click.option("--time", "t", default=0.0, show_default=True, type=Number(), help="Time t of the point, s.")
@click.option("--find-equilibrium", is_flag=True,
              help="First find the rest point (speeds 0, dv/dt = 0) nearest the coordinates given (Newton on G = 0).")
@click.option("--cyclic", default=None, metavar="NAMES",
              help="A steady motion's cyclic coordinates, comma-separated (default: those no equation of the flow "
                   "uses).")
@click.option("--sweep", "sweep_range", default=None, metavar="NAME=FROM:TO:COUNT",
              help="Linearize at COUNT values of a parameter, input, coordinate or speed; print the eigenvalues and "
                   "where stability changes (located to 1e-13 of the range); with -o, a CSV and a plot.")
@click.option("-o", "--out", "out_dir", default=None, metavar="DIR",
              help="Also write DIR/<name>_linearization.npz (A, B, x, u, names, eigenvalues) and DIR/<name>_A.csv, "
                   "DIR/<name>_B.csv.")
def linearize(file, at, sets, input_values, flow, t, find_equilibrium, cyclic, sweep_range, out_dir):
    """Linearize FILE's equations of motion: dx' = A dx + B du, from exact derivatives; print the eigenvalues."""
    from andyc.analysis.linearization import linearize_at, output_paths, report, save

    spec, model = derived(file)
    if out_dir:
        check_folder(out_dir, spec.files)
    parameters, inputs = split_sets(parse_sets(sets), spec.inputs)
    inputs.update(parse_sets(input_values, "--input"))
    states = parse_sets(at, "--at")
    cyclic = [c.strip() for c in cyclic.split(",") if c.strip()] if cyclic is not None else None
    if sweep_range is not None:
        return _sweep(file, spec, model, sweep_range, states, parameters, inputs, flow, t, out_dir)
    for path in output_paths(out_dir, spec.name) if out_dir else ():
        check_output(path, spec.files, "linearization")
    with _exit_on_linearize_error(file):
        lin = linearize_at(model, states, parameters, inputs, flow, t, find_equilibrium, cyclic)
    click.echo(report(lin, spec.name))
    if out_dir:
        npz = save(lin, out_dir, spec.name)[0]
        click.echo(f"wrote {npz}, {spec.name}_A.csv and {spec.name}_B.csv")


def _sweep(file, spec, model, text, states, parameters, inputs, flow, t, out_dir):
    from andyc.analysis.eigensweep import report, save, sweep
    from andyc.analysis.sweeps.points import PointsError, grid

    try:
        points = grid([text], "--sweep")
    except PointsError as exc:
        raise click.BadParameter(str(exc), param_hint="--sweep") from None
    name, values = points.names[0], points.axes[0]
    for suffix in (".csv", ".png") if out_dir else ():
        check_output(Path(out_dir) / f"{spec.name}_sweep_{name}{suffix}", spec.files, "sweep")
    with _exit_on_linearize_error(file):
        sw = sweep(model, name, values, states, parameters, inputs, flow, t)
    click.echo(report(sw, spec.name))
    if out_dir:
        from andyc.plot.eigenplot import plot_eigenvalues

        csv = save(sw, out_dir, spec.name)
        png = csv.with_suffix(".png")
        plot_eigenvalues(name, sw.values, sw.eigenvalues, [c.value for c in sw.changes], png,
                         f"{spec.name}: eigenvalues along {name}")
        click.echo(f"wrote {csv} and {png.name}")


@contextmanager
def _exit_on_linearize_error(file):
    """A point or model the linearization does not handle: its message, FILE first, and exit 1."""
    from andyc.symbolic.linearize import LinearizeError

    try:
        yield
    except LinearizeError as exc:
        click.echo(f"{file}: {exc}", err=True)
        sys.exit(1)
