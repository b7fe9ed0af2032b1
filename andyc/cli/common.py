"""What the commands share: the refusal of a request (exit 2), a model's problems printed as `andyc check`
prints them (exit 1), a model loaded and derived, a model built and compiled, and what happened to the user's
jump file."""

from __future__ import annotations

import sys

import click

import andyc
from andyc.errors import SimulationError, SpecError, plural, printable


class Refused(click.ClickException):
    """A request andyc will not carry out (an output over an input, say): `Error: ...`, exit 2, no usage text."""
    exit_code = 2

    def __init__(self, message: str):
        super().__init__(printable(message))


def fail_spec(exc: SpecError, report=None) -> None:
    """Print every problem of a model, one a line, then how many, on stderr (or add them to `report`, a
    andyc.cli.formats.Report); exit 1."""
    if report is None:
        for d in exc.diagnostics:
            click.echo(str(d), err=True)
        click.echo(f"{plural(len(exc.diagnostics), 'problem')} found", err=True)
        sys.exit(1)
    for d in exc.diagnostics:
        report.add(d)
    report.say(f"{plural(len(exc.diagnostics), 'problem')} found", err=True)
    report.finish(1)


def _refuse_old_spelling(ctx, param, value):
    if value is not None:
        raise click.UsageError(f"{param.opts[0]} is no longer the build folder: give it as --build-dir DIR "
                               "(-o/--out is the output everywhere: the run file of andyc sim, the plot of andyc "
                               "plot, the folder of andyc bench)", ctx)
    return value


def build_dir_option(*old):
    """--build-dir DIR, the build folder; `old`, its former spellings, refused with a hint."""
    def decorate(f):
        f = click.option("--build-dir", default="build", show_default=True, metavar="DIR",
                         help="Build folder; the build is DIR/<name>/<name>.py.")(f)
        for name in old:
            f = click.option(name, hidden=True, expose_value=False, default=None, callback=_refuse_old_spelling,
                             is_eager=True)(f)
        return f
    return decorate


def model_options(ctx: click.Context, simulate: dict) -> dict:
    """The command's options, each not given on the command line taken from the model's simulate: section
    (andyc.spec.simulate) when it gives it: the command line wins, then the model, then the defaults."""
    from click.core import ParameterSource

    out = dict(ctx.params)
    for name, value in simulate.items():
        if name in out and ctx.get_parameter_source(name) in (ParameterSource.DEFAULT, None):
            out[name] = value
    return out


def derived(file):
    """(Spec, SymbolicModel) of FILE; a model error is printed as andyc check does (exit 1)."""
    try:
        spec = andyc.load(file)
        return spec, andyc.derive(spec)
    except SpecError as exc:
        fail_spec(exc)


def compiled(file, out_dir, force: bool = False, report=None, integrator: bool = True, method: str | None = None):
    """(CompiledModel, BuildResult) of FILE; a model error is printed as andyc check does (exit 1; to
    `report`, a andyc.cli.formats.Report, when given). integrator, method: as andyc.compile_model's."""
    from andyc.codegen.buildfiles import numerics_compiled

    if sys.stderr.isatty() and not numerics_compiled():
        click.echo("andyc: compiling the integrator every model shares, once for this installation (seconds "
                   "for a model without constraints, jumps or contacts, up to a minute with them; a new model then "
                   "compiles in seconds) ...", err=True)
    try:
        return andyc.compile_model(file, out_dir, force, integrator, method)
    except SpecError as exc:
        fail_spec(exc, report)
    except SimulationError as exc:
        raise Refused(str(exc))


def report_jumps_file(result) -> None:
    """Say what happened to the user's jump template."""
    if result.jumps_path is None:
        return
    if not result.jumps_kept:
        click.echo(f"{result.jumps_path}: written, one function per jump: edit it for resets beyond the model file")
        return
    click.echo(f"{result.jumps_path}: kept (yours; never overwritten; delete it to get a fresh template)")
    for name in result.jumps_missing:
        click.echo(f"{result.jumps_path}: warning: no function for jump '{name}' (added to the model since the file "
                   f"was written): it gets no extra resets; add `def {name}(t, x, u, p, d)` with @njit, or delete "
                   f"the file to regenerate it", err=True)


def read_run_argument(run_file):
    """The run in RUN_FILE (plot, view), or a usage error naming it: a damaged file, or a run with no samples."""
    from andyc.runtime.runfiles import RunFileError, read_run_file

    try:
        run = read_run_file(run_file)
    except RunFileError as exc:
        raise click.BadParameter(str(exc), param_hint="RUN_FILE") from None
    if not len(run.time):
        raise click.BadParameter(f"{run_file}: the run of {run.model} holds no samples (its status: {run.status})",
                                 param_hint="RUN_FILE")
    return run
