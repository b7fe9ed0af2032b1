"""`andyc check` (validate models, print each one's summary) and `andyc build` (derive, generate, compile)."""

from __future__ import annotations

import click

import andyc
from andyc.cli.common import build_dir_option, compiled, report_jumps_file
from andyc.cli.formats import Report, format_option
from andyc.errors import SpecError, plural
from andyc.outputs import check_folder
from andyc.runtime.methods import METHODS


@click.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
@format_option
def check(files, fmt):
    """Validate model FILES (YAML or URDF) and their initial states (constraints, guards), without compiling;
    print every problem as FILE:LINE: PATH: what; fix."""
    from andyc.analysis.initial_state import initial_problems

    report = Report("check", fmt)
    problems = 0
    for file in files:
        try:
            spec = andyc.load(file)
            model = andyc.derive(spec)
            # The initial state, checked from the equations (andyc.analysis.initial_state).
            found = initial_problems(model, spec.simulate.get("init", "check"), spec.simulate.get("init_tol", 1e-6))
        except SpecError as exc:
            found, spec = exc.diagnostics, None
        for w in spec.warnings if spec is not None else ():
            report.add(w, "warning")
        for d in found:
            report.add(d)
        problems += len(found)
        if found:
            report.results.append({"file": file, "ok": False})
            continue
        summary = model.summary(file, spec)
        if spec.reduce:
            from andyc.pipeline import reduction_report

            summary += "\n" + reduction_report(file, spec, model)
        summary += "\n  " + model.forward.describe(model.constraints.nc > 0)
        if model.constraints.nc > 0:
            from andyc.codegen.generate import constrained_solve

            summary += "\n  " + constrained_solve(model).describe()
        report.say(summary)
        report.results.append({"file": file, "ok": True, "summary": summary})
    if problems:
        report.say(f"{plural(problems, 'problem')} found", err=True)
    report.finish(1 if problems else 0)


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@build_dir_option("-o", "--out-dir")
@click.option("--force", is_flag=True, help="Derive, generate and compile again, even if the equations are "
              "unchanged; replaces the build of another model file of the same name.")
@click.option("--method", type=click.Choice(METHODS + ("all",)), default=None,
              help="Compile what runs of this method call [default: the model's own, its simulate: method, else rk4]; "
                   "all: every method's, so that no later run compiles (a run compiles what it lacks, once for "
                   "this installation).")
@format_option
def build(file, build_dir, force, method, fmt):
    """Derive the equations of motion of FILE and generate its module, DIR/<name>/<name>.py."""
    report = Report("build", fmt)
    check_folder(build_dir, [file], write=False)     # (an up-to-date build is only read)
    model, result = compiled(file, build_dir, force, report, method=None if method == "all" else method or "model")
    t = result.timings
    compile = (f"compile {t['compile']:.2f} s ({plural(result.compiled, 'function')} compiled)" if result.compiled
               else f"loaded from Numba's cache in {t['compile']:.2f} s")
    if result.skipped:
        summary = f"{result.module_path}: up to date (equations and andyc unchanged); {compile}"
    else:
        ops = sum(result.operations.values())
        cc = f"C compiler {t['cc']:.2f} s, " if "cc" in t else ""
        summary = (f"{result.module_path}: built; derive {t['derive']:.2f} s, generate {t['generate']:.2f} s, "
                   f"{cc}{compile}; {ops} operations ({', '.join(f'{k} {v}' for k, v in result.operations.items())})")
    report.say(summary)
    if report.text:
        report_jumps_file(result)
    report.results.append({"file": file, "ok": True, "summary": summary, "module": str(result.module_path)})
    report.finish(0)
