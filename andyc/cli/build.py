"""`andyc check` (validate models, print each one's summary) and `andyc build` (derive, generate, compile)."""

from __future__ import annotations

import sys

import click

import andyc
from andyc.cli.common import compiled, report_jumps_file
from andyc.errors import SpecError, plural
from andyc.outputs import check_folder


@click.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
def check(files):
    """Validate model FILES (YAML or URDF); print every problem as FILE:LINE: PATH: what; fix."""
    problems = 0
    for file in files:
        try:
            spec = andyc.load(file)
            model = andyc.derive(spec)
        except SpecError as exc:
            for d in exc.diagnostics:
                click.echo(str(d), err=True)
            problems += len(exc.diagnostics)
            continue
        for w in spec.warnings:
            click.echo(f"{w} (warning)", err=True)
        click.echo(model.summary(file, spec))
        if spec.reduce:
            from andyc.pipeline import reduction_report

            click.echo(reduction_report(file, spec, model))
    if problems:
        click.echo(f"{plural(problems, 'problem')} found", err=True)
    sys.exit(1 if problems else 0)


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("-o", "--out-dir", default="build", show_default=True, help="Build folder; writes DIR/<name>/<name>.py.")
@click.option("--force", is_flag=True, help="Derive, generate and compile again, even if the equations are "
              "unchanged; replaces the build of another model file of the same name.")
def build(file, out_dir, force):
    """Derive the equations of motion of FILE and generate its module."""
    check_folder(out_dir, [file])
    model, result = compiled(file, out_dir, force)
    t = result.timings
    compile = (f"compile {t['compile']:.2f} s ({plural(result.compiled, 'function')} compiled)" if result.compiled
               else f"loaded from Numba's cache in {t['compile']:.2f} s")
    if result.skipped:
        click.echo(f"{result.module_path}: up to date (equations and andyc unchanged); {compile}")
    else:
        ops = sum(result.operations.values())
        click.echo(f"{result.module_path}: built; derive {t['derive']:.2f} s, generate {t['generate']:.2f} s, "
                   f"{compile}; {ops} operations ({', '.join(f'{k} {v}' for k, v in result.operations.items())})")
    report_jumps_file(result)
