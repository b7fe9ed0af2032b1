"""`andyc test`: run the expectations of models (their expect: sections) and say which hold."""

from __future__ import annotations

from pathlib import Path

import click

import andyc
from andyc.cli.common import build_dir_option
from andyc.cli.formats import Report, format_option
from andyc.errors import SimulationError, SpecError, plural
from andyc.outputs import check_folder, check_output, write_text

MODEL_SUFFIXES = (".yaml", ".yml")
# The exit code when nothing was tested (no model, or no model with an expect: section), as pytest's 5 when
# it collected no test: a CI gate pointed at the wrong folder must not pass.
NOTHING_TESTED = 5


def model_files(paths) -> list:
    """The files given, and in each folder given its model files (*.yaml, *.yml, sorted): every entry of that
    suffix but a folder, so that a broken link or an unreadable file is reported, not skipped."""
    out = []
    for path in paths:
        p = Path(path)
        if p.is_dir():
            try:
                found = sorted(f for f in p.iterdir() if f.suffix.lower() in MODEL_SUFFIXES and not f.is_dir())
            except OSError as exc:
                raise click.BadParameter(f"'{path}': cannot list the folder ({exc.strerror})", param_hint="PATHS")
            out += [str(f) for f in found]
        else:
            out.append(str(path))
    return out


@click.command()
@click.argument("paths", nargs=-1, required=True, type=click.Path())
@build_dir_option()
@click.option("--junit", "junit", default=None, type=click.Path(dir_okay=False), metavar="FILE.xml",
              help="Also write the outcomes as JUnit XML.")
@click.option("--no-tests-ok", "no_tests_ok", is_flag=True, default=False,
              help=f"Exit 0, not {NOTHING_TESTED}, when nothing was tested (a hook given changed model files that "
                   f"have no expect: section).")
@format_option
def test(paths, build_dir, junit, no_tests_ok, fmt):
    """Run the expectations (expect:) of model FILES, and of the models in DIRS.

    Each expectation is a short run that must finish and its checks. One line per failed one,
    FILE:LINE: expect[i].<check>: measured ..., expected ...; exit 0 when all hold, 1 otherwise, 5 when
    nothing was tested (no model file, or none with an expect: section)."""
    from andyc.analysis.expectations import run_expectations
    from andyc.analysis.junit import junit_xml

    for path in paths:
        if not Path(path).exists():
            raise click.BadParameter(f"'{path}' does not exist", param_hint="PATHS")
    files = model_files(paths)
    if junit:
        check_output(junit, files, "JUnit file")
    check_folder(build_dir, files, write=False)     # (an up-to-date build is only read)
    report = Report("test", fmt)
    results, failed, checks = [], 0, 0
    for file in files:
        outcomes, problems = [], []
        try:
            spec = andyc.load(file)
            if spec.expect:
                model, _ = andyc.compile_model(file, build_dir)
                outcomes = run_expectations(spec, model, file)
        except SpecError as exc:
            problems = [str(d) for d in exc.diagnostics]
            for d in exc.diagnostics:
                report.add(d)
        except SimulationError as exc:
            problems = [str(exc)]
            report.add(exc)
        bad = [o for o in outcomes if not o.ok]
        for o in bad:
            report.add(o)
        checks += len(outcomes)
        failed += len(bad) + (1 if problems else 0)
        results.append((file, outcomes, problems))
        report.results.append({"file": file, "ok": not bad and not problems,
                               "outcomes": [o.as_dict() for o in outcomes]})
        if problems:
            report.say(f"{file}: not tested (the model has problems)")
        elif not outcomes:
            report.say(f"{file}: no expectations (add an expect: section)")
        else:
            runs = sum(o.seconds for o in outcomes)
            report.say(f"{file}: {plural(len(outcomes), 'check')}, " + (f"{len(bad)} failed" if bad else "all hold")
                       + f" (runs {runs:.2f} s)")
    if junit:
        write_text(junit, junit_xml(results))
    report.say(f"{plural(checks, 'check')} in {plural(len(files), 'model')}: "
               + (f"{plural(failed, 'failure')}" if failed else "all hold" if checks else "nothing tested"))
    if not failed and not checks and not no_tests_ok:
        where = ", ".join(map(str, paths))
        why = f"no model file (*.yaml, *.yml) in {where}" if not files else "no model has an expect: section"
        report.add(f"andyc test: nothing tested: {why}; point it at the models, or add expect: sections (exit "
                   f"{NOTHING_TESTED}, as pytest's when it collects no test)")
        report.finish(NOTHING_TESTED)
    report.finish(1 if failed else 0)
