"""--format text|json|github: how check, build, sim and test report.

text    the lines andyc prints anyway (problems on stderr, FILE:LINE: PATH: what; fix)
json    one JSON document on stdout when the command ends, following andyc/schemas/andyc-output.schema.json
        (shipped with the package): the command, whether it succeeded, its exit code, every problem located,
        and the command's results
github  the text, and a GitHub Actions workflow annotation for each problem and failure
        (`::error file=F,line=L::message`), so that they show on the pull request's lines
"""

from __future__ import annotations

import json
import re
import sys

import click

import andyc
from andyc.errors import Diagnostic, printable

FORMATS = ("text", "json", "github")
format_option = click.option("--format", "fmt", type=click.Choice(FORMATS), default="text", show_default=True,
                             help="Report as text, as one JSON document (andyc-output.schema.json), or as text "
                                  "with GitHub Actions annotations (::error file=F,line=L::message).")

_LOCATED = re.compile(r"^(?P<file>.+?):(?P<line>\d+): (?P<rest>.*)$")


def problem(item, severity: str = "error") -> dict:
    """A problem as the JSON report holds it: a Diagnostic, an expectation's Outcome, or a line
    'FILE:LINE: ...' (or any message)."""
    if isinstance(item, Diagnostic):
        return {"file": item.file, "line": item.line, "path": item.path or "<document>", "message": item.message,
                "hint": item.hint, "severity": severity, "text": str(item)}
    if hasattr(item, "measured"):           # an expectation's outcome (andyc.analysis.expectations.Outcome)
        return {"file": item.file, "line": item.line, "path": item.path, "severity": severity, "text": str(item),
                "message": printable(f"measured {item.measured}, expected {item.expected}")}
    text = printable(str(item))
    found = _LOCATED.match(text)
    out = {"file": found["file"], "line": int(found["line"])} if found else {}
    return {**out, "message": found["rest"] if found else text, "severity": severity, "text": text}


def annotation(entry: dict) -> str:
    """The GitHub workflow command of a problem (its properties and message escaped as GitHub requires)."""
    def escape(text: str, prop: bool = False) -> str:
        text = text.replace("%", "%25").replace("\r", "%0D").replace("\n", "%0A")
        return text.replace(":", "%3A").replace(",", "%2C") if prop else text

    where = []
    if "file" in entry:
        where.append(f"file={escape(entry['file'], True)}")
    if "line" in entry:
        where.append(f"line={entry['line']}")
    level = "warning" if entry.get("severity") == "warning" else "error"
    return f"::{level} {','.join(where)}::{escape(entry['text'])}" if where else f"::{level}::{escape(entry['text'])}"


class Report:
    """What a command found, reported at its end in the chosen format (text is printed as it goes)."""

    def __init__(self, command: str, fmt: str):
        self.command, self.fmt = command, fmt
        self.problems: list[dict] = []
        self.results: list[dict] = []

    @property
    def text(self) -> bool:
        return self.fmt != "json"

    def say(self, line: str, err: bool = False) -> None:
        """A line of the text report (not in JSON)."""
        if self.text:
            click.echo(line, err=err)

    def add(self, item, severity: str = "error") -> None:
        """A problem: printed now as text (stderr), kept for the JSON report and the annotations."""
        entry = problem(item, severity)
        self.problems.append(entry)
        self.say(entry["text"] + (" (warning)" if severity == "warning" and isinstance(item, Diagnostic) else ""),
                 err=True)

    def finish(self, code: int) -> None:
        """Print the JSON document or the annotations; exit with `code`."""
        if self.fmt == "json":
            click.echo(json.dumps({"andyc_version": andyc.__version__, "command": self.command, "ok": code == 0,
                                   "exit_code": code, "problems": self.problems, "results": self.results},
                                  ensure_ascii=True))
        elif self.fmt == "github":
            for entry in self.problems:
                click.echo(annotation(entry))
        sys.exit(code)


REPORTING = ("check", "build", "sim", "test")      # the commands that take --format


def json_command(args: list) -> str | None:
    """The command of a command line that asks for --format json (check, build, sim or test), else None: a
    usage error, found before the command runs, then gets its JSON document too (usage_report)."""
    command = next((a for a in args if not a.startswith("-")), None)
    pairs = list(zip(args, args[1:]))
    wants = ("--format", "json") in pairs or "--format=json" in args
    return command if wants and command in REPORTING else None


def usage_report(command: str, message: str, code: int) -> None:
    """The JSON document of a command line andyc refused (exit 2): no results, the one problem. The message
    itself still goes to stderr as click prints it."""
    click.echo(json.dumps({"andyc_version": andyc.__version__, "command": command, "ok": False, "exit_code": code,
                           "problems": [problem(message)], "results": []}, ensure_ascii=True))
