"""`andyc bench` (work-precision: error against cost per method) and `andyc stability` (where each fixed-step
method fails), over andyc.analysis; each prints a row per run as it finishes, then writes a table and diagrams."""

from __future__ import annotations

from pathlib import Path

import click

from andyc.cli.common import compiled
from andyc.cli.values import POSITIVE, Number, floats, method_names, parse_sets, split_sets
from andyc.errors import SimulationError
from andyc.outputs import check_folder, check_output
from andyc.runtime.methods import FIXED_STEP

_REFERENCE = click.option(
    "--reference", "reference", default="auto", show_default=True, type=click.Choice(["auto", "closed-form", "DOP853"]),
    help="What runs are compared with: the model's closed form (auto: when it declares one) or DOP853 at rtol = atol "
         "= 1e-13.")


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--methods", default=None, metavar="M1,M2",
              help="Methods to compare (default: rk4 and DOP853; with constraints also projection, lagrange, "
                   "baumgarte).")
@click.option("--steps", default=None, metavar="H1,H2|geom:A:B:N",
              help="Steps of the fixed-step methods, each adjusted to divide --t-end (default: T/100 .. T/10000).")
@click.option("--tols", default=None, metavar="R1,R2|geom:A:B:N",
              help="Tolerances (rtol = atol) of the adaptive methods (default: 1e-3 .. 1e-10).")
@click.option("--t-end", default=10.0, show_default=True, type=POSITIVE, help="Horizon T, s.")
@click.option("--repeats", default=3, show_default=True, type=Number(1, 1000, integer=True), help="Wall time: the best of this many runs.")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("-o", "--out", "out_dir", default="runs", show_default=True, metavar="DIR",
              help="Writes DIR/<name>_work_precision.csv, .png and .svg.")
@_REFERENCE
@click.option("--build-dir", default="build", show_default=True, help="Build folder.")
def bench(file, methods, steps, tols, t_end, repeats, sets, reference, out_dir, build_dir):
    """Work-precision of FILE: each method at each step or tolerance against a reference (the model's closed form,
    or DOP853 at rtol 1e-13); error at T against wall time and evaluations, as a table, a CSV and diagrams."""
    from andyc.analysis.accuracy import reference_solution
    from andyc.analysis.workprecision import DEFAULT_TOLS, draw, sweep, write_csv

    check_folder(out_dir, [file])
    check_folder(build_dir, [file], write=False)
    model = compiled(file, build_dir)[0]
    for suffix in (".csv", ".png", ".svg"):
        check_output(Path(out_dir) / f"{model.name}_work_precision{suffix}", [file], "work-precision file")
    overrides = parse_sets(sets)
    chosen = method_names(methods, "--methods") if methods else (
        ["rk4", "projection", "lagrange", "baumgarte", "DOP853"] if model.nc else ["rk4", "DOP853"])
    parameters, inputs = split_sets(overrides, model.input_names)
    options = {"parameters": parameters, "inputs": inputs}
    try:
        ref = reference_solution(model, t_end, reference, **options)
    except SimulationError as exc:
        raise click.UsageError(str(exc))
    click.echo(f"{model.name}: work-precision over T = {t_end:g} s; reference: {ref.source}")
    click.echo(f"{'method':>10} {'step/tol':>9} {'error':>9} {'residual':>9} {'energy':>9} {'rhs':>8} "
               f"{'wall s':>9}  status")

    def show(p):
        click.echo(f"{p.method:>10} {p.setting:>9.3g} {p.error:>9.2e} {p.residual:>9.1e} {p.energy_drift:>9.1e} "
                   f"{p.rhs:>8} {p.wall:>9.2e}  {p.status[:60]}")

    try:
        ref, points = sweep(model, chosen, t_end, floats(steps, "--steps"),
                            floats(tols, "--tols") or DEFAULT_TOLS, repeats, progress=show, reference=ref,
                            **options)
    except SimulationError as exc:
        raise click.UsageError(str(exc))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(points, out / f"{model.name}_work_precision.csv")
    figures = draw(points, ref, model.name, out / f"{model.name}_work_precision")
    click.echo(f"wrote {out / f'{model.name}_work_precision.csv'}, " + ", ".join(map(str, figures)))


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--methods", default=None, metavar="M1,M2",
              help="Fixed-step methods to scan (default: rk4; with constraints projection, lagrange, baumgarte too).")
@click.option("--steps", default=None, metavar="H1,H2|geom:A:B:N",
              help="Steps, each adjusted to divide the horizon (default: geom:T/20:T/20000:31).")
@click.option("--horizon", "horizons", multiple=True, type=POSITIVE, metavar="T",
              help="Horizon(s), s; one map each (default: 10).")
@click.option("--tol", default=1e-3, show_default=True, type=POSITIVE,
              help="Accurate: the state error at T within TOL x the reference's amplitude.")
@click.option("--blowup", default=1e3, show_default=True, type=Number(1, low_open=True), help="Blown up: |x| past this x the reference's largest.")
@click.option("--residual-tol", default=1e-6, show_default=True, type=POSITIVE, help="Constraints lost: a residual past this.")
@click.option("--gains", default=None, metavar="W1,W2|geom:A:B:N",
              help="A second axis: Baumgarte gains stiffness w^2 and damping 2w at each w, 1/s (critical damping "
                   "at rate w for a unit effective mass; the gains must be parameters).")
@click.option("--scan", "scan_values", default=None, metavar="NAME=V1,V2|NAME=geom:A:B:N",
              help="A second axis: this parameter at each value (each with its own reference).")
@_REFERENCE
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("-o", "--out", "out_dir", default="runs", show_default=True, metavar="DIR",
              help="Writes DIR/<name>_stability_T<horizon>.csv, .png and .svg.")
@click.option("--build-dir", default="build", show_default=True, help="Build folder.")
def stability(file, methods, steps, horizons, tol, blowup, residual_tol, gains, scan_values, reference, sets,
              out_dir, build_dir):
    """Stability map of FILE: each fixed-step method at each step, classified accurate, inaccurate (stable,
    not accurate) or failed (stopped, blown up, constraints lost, event missed: what, and when)."""
    from andyc.analysis.stability import (baumgarte_rates, boundaries, draw_map, geometric, parameter_values, scan,
                                          write_csv)

    if gains and scan_values:
        raise click.UsageError("give --gains or --scan, not both: a map has one second axis")
    check_folder(out_dir, [file])
    check_folder(build_dir, [file], write=False)
    model = compiled(file, build_dir)[0]
    for horizon in horizons or (10.0,):
        for suffix in (".csv", ".png", ".svg"):
            check_output(Path(out_dir) / f"{model.name}_stability_T{horizon:g}{suffix}", [file],
                         "stability file")
    overrides = parse_sets(sets)
    chosen = method_names(methods, "--methods") if methods else (
        ["rk4", "projection", "lagrange", "baumgarte"] if model.nc else ["rk4"])
    adaptive = [m for m in chosen if m not in FIXED_STEP]
    if adaptive:
        raise click.BadParameter(f"{', '.join(adaptive)}: the scan is over steps, for the methods "
                                 f"{', '.join(FIXED_STEP)}", param_hint="--methods")
    parameters, inputs = split_sets(overrides, model.input_names)
    options = {"parameters": parameters, "inputs": inputs}
    try:
        variants = (baumgarte_rates(model, floats(gains, "--gains")) if gains else
                    parameter_values(*_scanned(model, scan_values)) if scan_values else None)
    except SimulationError as exc:
        raise click.BadParameter(str(exc), param_hint="--gains")
    axis, name = (variants[0].axis, variants[0].name) if variants else (None, None)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for horizon in horizons or (10.0,):
        grid = floats(steps, "--steps") or geometric(horizon / 20, horizon / 20000, 31)
        click.echo(f"{model.name}: stability over T = {horizon:g} s, {len(grid)} steps x {len(chosen)} methods"
                   + (f" x {len(variants)} values of {axis}" if variants else ""))

        def show(v):
            at = "" if v.variant is None else f" {name} = {v.variant:<9.4g}"
            click.echo(f"  {v.point.method:>10}{at} h = {v.point.setting:<10.4g} {v.verdict:>10}: {v.reason}")

        try:
            ref, verdicts = scan(model, chosen, grid, horizon, tol, blowup, residual_tol, progress=show,
                                 reference=reference, variants=variants, **options)
        except SimulationError as exc:
            raise click.UsageError(str(exc))
        click.echo(f"reference: {ref.source}")
        for (method, variant), (accurate, failing, why) in boundaries(verdicts).items():
            at = "" if variant is None else f" at {name} = {variant:.4g}"
            click.echo(f"{method}{at}: largest accurate step {'none' if accurate is None else f'{accurate:.4g} s'}; "
                       + (f"fails from h = {failing:.4g} s ({why})" if failing else "no failure in the scan"))
        stem = out / f"{model.name}_stability_T{horizon:g}"
        table = stem.with_name(stem.name + ".csv")          # (not with_suffix: the horizon may hold a '.')
        write_csv(verdicts, table)
        figures = draw_map(verdicts, ref, model.name, stem, axis)
        click.echo(f"wrote {table}, " + ", ".join(map(str, figures)))


def _scanned(model, text: str) -> tuple[str, list]:
    """'k=1e3,1e4' or 'k=geom:1e3:1e5:5' -> ('k', [values]) for a parameter of `model`."""
    name, sep, values = text.partition("=")
    name = name.strip()
    if not sep or name not in model.parameter_names:
        raise click.BadParameter(f"'{text}': give NAME=VALUES with NAME a parameter of {model.name} "
                                 f"({', '.join(model.parameter_names)})", param_hint="--scan")
    return name, floats(values, "--scan")
