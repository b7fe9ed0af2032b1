"""Shared fixtures. The shipped models are built into one build folder that every worker and every run
of the suite shares (build/tests: a build is reused by meaning, and Numba's cache with it, so a model
compiles once, not once per worker and run); other models into a temporary folder per session. The
numerics every build shares compile once into andyc's cache (ANDYC_CACHE_DIR), as for any user, so that
`make demo` after `make test` finds them."""

import os
from pathlib import Path

import pytest

import andyc
from tests.support import MODELS, ROOT

SHIPPED_BUILD = ROOT / "build" / "tests"


@pytest.fixture(scope="session")
def build_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("build")


@pytest.fixture(scope="session")
def shipped_build():
    """The build folder of the shipped models, shared by workers and runs (see the module's docstring)."""
    SHIPPED_BUILD.mkdir(parents=True, exist_ok=True)
    return SHIPPED_BUILD


@pytest.fixture(scope="session")
def compiled(build_dir, shipped_build):
    """compiled(name_or_path) -> CompiledModel, built once per session (a shipped model: once for all)."""
    cache = {}

    def get(model):
        path = Path(model) if str(model).endswith((".yaml", ".yml")) else MODELS / f"{model}.yaml"
        if path not in cache:
            shipped = path.resolve().parent == MODELS
            cache[path] = andyc.compile_model(path, shipped_build if shipped else build_dir)[0]
        return cache[path]

    return get


@pytest.fixture(scope="session")
def compiled_text(tmp_path_factory, compiled):
    """compiled_text(name, text) -> CompiledModel of the model file `text` (a test's own small model), written as
    name.yaml and built once per session into the session's build folder."""
    folder = tmp_path_factory.mktemp("models")

    def get(name, text):
        path = folder / f"{name}.yaml"
        if not path.exists():
            path.write_text(text)
        return compiled(path)

    return get


@pytest.fixture(scope="session")
def panda_arm(shipped_build):
    """example-robot-data's panda with its fingers locked (as tests/test_reduce.py reads it), compiled into the
    shipped models' build folder: its build is reused by meaning across runs (a fresh build takes a minute)."""
    from tests.support import ROBOTS_DIR

    # (beside the builds, at one path: a build keeps the model file it came from, and refuses another of its name)
    source = Path(shipped_build) / "panda_arm.yaml"
    text = (f"name: panda_arm\nurdf:\n  file: {ROBOTS_DIR / 'panda_description/urdf/panda.urdf'}\n"
            "  lock: {panda_finger_joint1: 0.02}\n")
    if not source.exists() or source.read_text() != text:
        partial = source.with_name(f"panda_arm.{os.getpid()}.tmp")      # whole, for the other worker too
        partial.write_text(text)
        os.replace(partial, source)
    return andyc.compile_model(source, shipped_build)[0]
