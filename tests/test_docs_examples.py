"""The documentation's examples run, and print what the pages say they print (issue 45): the getting-started
page's reading of a run file with h5py, and the sweep guide's session with xarray on the store its first command
makes. The commands and the code are taken from the pages themselves, so that a page that drifts from the code
fails here."""

import doctest
import re
import shlex
import subprocess
import sys

import pytest
from click.testing import CliRunner

from andyc.cli import main
from tests.support import ROOT


def page(name: str) -> str:
    return (ROOT / "docs" / name).read_text(encoding="utf-8")


def in_a_checkout(tmp_path, monkeypatch):
    """Work in tmp_path as in a checkout: the pages' commands name models/...; their outputs and builds go here
    (a build of its own: the shipped models' shared one is not rewritten under the other tests)."""
    (tmp_path / "models").symlink_to(ROOT / "models")
    monkeypatch.chdir(tmp_path)


def andyc_command(line: str) -> list:
    """The arguments of an `andyc ...` line of a page."""
    args = shlex.split(line)
    assert args[0] == "andyc", line
    return args[1:]


def invoke(args):
    result = CliRunner().invoke(main, args, catch_exceptions=False)
    assert result.exit_code == 0, result.output


def test_getting_started_reads_a_run_as_the_page_says(tmp_path, monkeypatch):
    text = page("getting-started.md").split("## Reading a run")[1]
    command = re.search(r"`(andyc sim [^`]+)`", text).group(1)
    code = re.search(r"```python\n(.*?)```", text, re.S).group(1)
    printed = re.search(r"prints `([^`]+)`", text).group(1)
    in_a_checkout(tmp_path, monkeypatch)
    invoke(andyc_command(command))
    out = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, check=True)
    assert out.stdout.strip() == printed


def test_the_sweep_guides_xarray_session_runs_on_the_store_of_its_first_command(tmp_path, monkeypatch):
    pytest.importorskip("xarray")
    text = page("howto/sweep.md")
    first = re.search(r"```sh\n(.*?)\n(?=andyc plot)", text, re.S).group(1).replace("\\\n", " ")
    session = re.search(r"```python\n(>>> .*?)```", text, re.S).group(1)
    in_a_checkout(tmp_path, monkeypatch)
    invoke(andyc_command(first))
    test = doctest.DocTestParser().get_doctest(session, {}, "howto/sweep.md", "docs/howto/sweep.md", 0)
    assert len(test.examples) >= 6
    runner, report = doctest.DocTestRunner(optionflags=doctest.NORMALIZE_WHITESPACE), []
    runner.run(test, out=report.append)
    assert runner.failures == 0, "".join(report)
