"""The pipeline's layers (pyproject.toml's import-linter contract): spec -> symbolic -> codegen -> runtime ->
analysis | plot -> cli, with the numerics every build carries at the bottom. The contract holds on the tree,
and it has teeth: one import upward, planted in a copy of the package, breaks it and is named. The tests
have a layer of their own: a test module imports tests.support, never another test module nor conftest
(pytest loads conftest itself; what test modules share is in tests/support)."""

import ast
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


def imports_of_tests(folder: Path) -> list[str]:
    """`FILE: MODULE` for each import, in the test modules and the support package under `folder`, of a
    module of the tests other than tests.support."""
    found = []
    for path in sorted([*folder.glob("*.py"), *folder.glob("support/*.py")]):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Import):
                names = [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom) and node.module == "tests":
                names = [f"tests.{alias.name}" for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                names = [node.module or ""]
            else:
                continue
            found += [f"{path.relative_to(folder)}: {name}" for name in names
                      if name.split(".")[0] == "tests" and name.split(".")[:2] != ["tests", "support"]]
    return found


def test_test_modules_share_only_the_support_package(tmp_path):
    assert imports_of_tests(ROOT / "tests") == []
    # and the check has teeth: each way of importing another test module, or conftest, is named
    (tmp_path / "support").mkdir()
    (tmp_path / "test_a.py").write_text("from tests.test_b import helper\nimport tests.conftest\n"
                                        "from tests.support import MODELS\nimport tests.support.cli\n")
    (tmp_path / "support" / "runs.py").write_text("from tests import test_plot, support\n")
    assert imports_of_tests(tmp_path) == ["support/runs.py: tests.test_plot", "test_a.py: tests.test_b",
                                          "test_a.py: tests.conftest"]
