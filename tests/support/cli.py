"""The command line, two ways: `andyc_cli` in a fresh interpreter (what a user's shell runs: exit codes,
the streams, a process of its own), `invoke` in process with click's CliRunner (no interpreter
start-up; for the many cases that need nothing more)."""

import os
import subprocess
import sys

from click.testing import CliRunner

from andyc import cli

# Seconds after which a command counts as hung: a hang detector, not a speed bound (a cold `andyc sim`
# compiles its model with Numba, on a machine that may be busy).
HANG = 900


def andyc_cli(*args, cwd=None) -> subprocess.CompletedProcess:
    """`andyc ARGS` as `python -m andyc.cli` (the interpreter running the tests, so the andyc under test,
    wherever the `andyc` script is or is not installed); arguments may be paths or numbers."""
    return subprocess.run([sys.executable, "-m", "andyc.cli", *map(str, args)], cwd=cwd, capture_output=True,
                          text=True, timeout=HANG)


def invoke(*args, cwd=None):
    """`andyc ARGS` in process: a click Result, stdout and stderr apart (`.stdout`, `.stderr`; `.output`
    is both as a terminal shows them); arguments may be paths or numbers; `cwd`: the folder it runs in
    (relative paths are the user's, as given)."""
    here = os.getcwd()
    if cwd is not None:
        os.chdir(cwd)
    try:
        return CliRunner().invoke(cli.main, [str(a) for a in args])
    finally:
        os.chdir(here)


def check(*files):
    """`andyc check FILES` in process."""
    return invoke("check", *files)


def run_python(code: str, *args, cwd=None, env=None) -> subprocess.CompletedProcess:
    """`python -c CODE ARGS` in a fresh interpreter (what importing or running something costs from a cold
    start: which modules it loads, which caches it finds)."""
    return subprocess.run([sys.executable, "-c", code, *map(str, args)], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=HANG)
