"""The pipeline's layers (pyproject.toml's import-linter contract): spec -> symbolic -> codegen -> runtime ->
analysis | plot -> cli, with the numerics every build carries at the bottom. The contract holds on the tree,
and it has teeth: one import upward, planted in a copy of the package, breaks it and is named."""

import shutil
import subprocess
import sys
from pathlib import Path

from tests.support import ROOT

LINT = Path(sys.executable).with_name("lint-imports")


def lint(root: Path) -> subprocess.CompletedProcess:
    return subprocess.run([str(LINT), "--config", str(root / "pyproject.toml"), "--no-cache"], cwd=root,
                          capture_output=True, text=True, env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin"})


def test_the_layers_hold():
    result = lint(ROOT)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "1 kept, 0 broken" in result.stdout


def test_an_import_upward_breaks_the_contract(tmp_path):
    shutil.copytree(ROOT / "andyc", tmp_path / "andyc", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "pyproject.toml", tmp_path)
    spec = tmp_path / "andyc" / "spec" / "model.py"
    spec.write_text(spec.read_text() + "\nfrom andyc.runtime import compiled  # noqa: E402  (upward, on purpose)\n")
    result = lint(tmp_path)
    assert result.returncode == 1
    assert "BROKEN" in result.stdout and "andyc.spec.model -> andyc.runtime.compiled" in result.stdout
