"""`andyc eom`: a model's equations of motion written out for reading (LaTeX, a SymPy file or JSON)."""

from __future__ import annotations

import sys

import click

from andyc.cli.common import derived
from andyc.outputs import check_output, write_text


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--format", "fmt", default="latex", show_default=True, type=click.Choice(["latex", "sympy", "json"]),
              help="latex: an equation block per quantity; sympy: a Python file defining the symbols and matrices; "
                   "json: names and each quantity as sympy str and LaTeX.")
@click.option("--element", default=None, metavar="NAME", help="Only this element's own M and G.")
@click.option("--flow", default=None, metavar="F", help="The flow whose constraint rows and inputs to use "
              "(default: the initial one).")
@click.option("--standalone", is_flag=True, help="latex: a whole document, not a fragment.")
@click.option("-o", "--out", default=None, metavar="FILE", help="Write to FILE (default: standard output).")
def eom(file, fmt, element, flow, standalone, out):
    """Print FILE's equations of motion for reading: M dv/dt = G, the flow's constraint rows phi, A and
    kappa, and each element's own M and G (ANDY eq. 5-8, 10-11), intermediates substituted, simplified."""
    from andyc.runtime.progress import Progress
    from andyc.symbolic.eom import FACTOR_OPS, SIMPLIFY_OPS, EomError, equations, equations_text

    if standalone and fmt != "latex":
        raise click.BadParameter("a whole document is LaTeX: use it with --format latex", param_hint="--standalone")
    spec, model = derived(file)
    if out:
        check_output(out, spec.files, "equations")
    with Progress(spec.name, unit="entries written out") as progress:
        try:
            eq = equations(model, flow=flow, element=element,
                           progress=lambda done, total, seconds: progress(done, total))
        except EomError as exc:
            click.echo(f"{file}: {exc}", err=True)
            sys.exit(1)
    if eq.factored or eq.as_written:
        click.echo(f"{spec.name}: {eq.factored + eq.as_written} of {eq.entries} entries are past the simplification "
                   f"budget ({SIMPLIFY_OPS} operations written out; largest {eq.largest}): only factored"
                   + (f"; {eq.as_written} past {FACTOR_OPS} are left as written out, megabytes of text that take "
                      "minutes to print (--element NAME prints one element)" if eq.as_written else ""), err=True)
    text = equations_text(eq, fmt, standalone)
    if out:
        write_text(out, text)
        click.echo(f"wrote {out} ({eq.entries} entries in {eq.seconds:.2f} s)")
    else:
        click.echo(text, nl=False)
