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


def fail_spec(exc: SpecError) -> None:
    """Print every problem of a model, one a line, then how many, on stderr; exit 1."""
    for d in exc.diagnostics:
        click.echo(str(d), err=True)
    click.echo(f"{plural(len(exc.diagnostics), 'problem')} found", err=True)
    sys.exit(1)


def derived(file):
    """(Spec, SymbolicModel) of FILE; a model error is printed as andyc check does (exit 1)."""
    try:
        spec = andyc.load(file)
        return spec, andyc.derive(spec)
    except SpecError as exc:
        fail_spec(exc)


def compiled(file, out_dir, force: bool = False):
    """(CompiledModel, BuildResult) of FILE; a model error is printed as andyc check does (exit 1)."""
    from andyc.codegen.buildfiles import numerics_compiled

    if sys.stderr.isatty() and not numerics_compiled():
        click.echo("andyc: compiling the integrator every model shares, once for this installation (about a "
                   "minute; a new model then compiles in seconds) ...", err=True)
    try:
        return andyc.compile_model(file, out_dir, force)
    except SpecError as exc:
        fail_spec(exc)
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
