"""The pre-commit hooks of this repository (.pre-commit-hooks.yaml), run by the `pre-commit` package as a user
runs them: a temporary git repository of models names this repository (its path) at its HEAD commit, and
`git commit` runs andyc-check and andyc-test on the models it changes. A model with a negative mass is
refused; a good model is committed.

pre-commit installs andyc from the commit into a virtualenv of its own. So that this needs no network, the
virtualenv sees the packages of the interpreter running the tests (PYTHONPATH) and pip looks at no index
(PIP_NO_INDEX) and builds without isolation (it has setuptools already): pre-commit then installs andyc
alone. Should pip still want something it cannot reach offline, the test is skipped, saying so. The
environment is kept in build/pre-commit (one per commit of andyc), so a second run reuses it.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

import pytest

pytest.importorskip("pre_commit")

ROOT = Path(__file__).resolve().parents[1]
UNREACHABLE = ("No matching distribution", "Could not find a version", "Failed to establish a new connection")


def git(*args, cwd, env):
    return subprocess.run(["git", *args], cwd=cwd, env=env, capture_output=True, text=True, timeout=900)


@pytest.fixture(scope="module")
def repo(tmp_path_factory):
    if shutil.which("git") is None:
        pytest.skip("git is not installed")
    head = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True)
    if head.returncode != 0:
        pytest.skip("this andyc is not a git checkout")
    path = tmp_path_factory.mktemp("precommit")
    env = {**os.environ, "PRE_COMMIT_HOME": str(ROOT / "build" / "pre-commit"),
           "PYTHONPATH": sysconfig.get_paths()["purelib"], "PIP_NO_INDEX": "1", "PIP_NO_BUILD_ISOLATION": "0",
           "GIT_AUTHOR_NAME": "t", "GIT_AUTHOR_EMAIL": "t@example.com", "GIT_COMMITTER_NAME": "t",
           "GIT_COMMITTER_EMAIL": "t@example.com"}
    env.pop("PRE_COMMIT", None)
    (path / ".pre-commit-config.yaml").write_text(
        f"repos:\n  - repo: {ROOT}\n    rev: {head.stdout.strip()}\n    hooks:\n      - id: andyc-check\n"
        "      - id: andyc-test\n")
    (path / "models").mkdir()
    for args in (["init", "-q"], ["add", ".pre-commit-config.yaml"], ["commit", "-qm", "config"]):
        assert git(*args, cwd=path, env=env).returncode == 0
    install = subprocess.run([sys.executable, "-m", "pre_commit", "install"], cwd=path, env=env, capture_output=True,
                             text=True)
    assert install.returncode == 0, install.stdout + install.stderr
    ready = subprocess.run([sys.executable, "-m", "pre_commit", "install-hooks"], cwd=path, env=env,
                           capture_output=True, text=True, timeout=900)
    if ready.returncode != 0 and any(u in ready.stdout + ready.stderr for u in UNREACHABLE):
        pytest.skip("pre-commit could not install the hooks' environment offline: " + ready.stdout[-300:])
    assert ready.returncode == 0, ready.stdout + ready.stderr
    return path, env


def test_a_model_with_a_negative_mass_is_not_committed(repo):
    path, env = repo
    good = (ROOT / "models" / "pendulum_a01.yaml").read_text()
    bad = good.replace("m: 1.0      # point mass, kg", "m: -1.0     # point mass, kg")
    assert bad != good
    (path / "models" / "bad.yaml").write_text(bad)
    git("add", "models/bad.yaml", cwd=path, env=env)
    try:
        result = git("commit", "-m", "bad", cwd=path, env=env)
        out = result.stdout + result.stderr         # (git prints what the hooks print on stderr)
        assert result.returncode != 0
        line = next(n for n, text in enumerate(bad.splitlines(), 1) if "mass: m}" in text)
        assert (f"models/bad.yaml:{line}: bodies[0].mass: mass must be positive, got m = -1; give a positive mass "
                "in kg") in out, out
        assert re.search(r"^andyc check\.+Failed$", out, re.M), out
        assert git("log", "--oneline", cwd=path, env=env).stdout.count("\n") == 1    # the config's commit only
    finally:
        git("rm", "-q", "--cached", "models/bad.yaml", cwd=path, env=env)
        (path / "models" / "bad.yaml").unlink()


def test_a_good_model_is_committed(repo):
    path, env = repo
    shutil.copy(ROOT / "models" / "pendulum_a01.yaml", path / "models" / "pendulum.yaml")
    git("add", "models/pendulum.yaml", cwd=path, env=env)
    result = git("commit", "-m", "good", cwd=path, env=env)
    out = result.stdout + result.stderr
    assert result.returncode == 0, out
    assert re.search(r"^andyc check\.+Passed$", out, re.M) and re.search(r"^andyc test\.+Passed$", out, re.M), out
    assert git("log", "--oneline", cwd=path, env=env).stdout.count("\n") == 2
