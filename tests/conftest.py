"""Shared fixtures: models are built once per session into a temporary build folder."""

from pathlib import Path

import pytest

import andyc

ROOT = Path(__file__).resolve().parents[1]
MODELS = ROOT / "models"


@pytest.fixture(scope="session")
def build_dir(tmp_path_factory):
    return tmp_path_factory.mktemp("build")


@pytest.fixture(scope="session")
def compiled(build_dir):
    """compiled(name_or_path) -> CompiledModel, built once per session."""
    cache = {}

    def get(model):
        path = Path(model) if str(model).endswith((".yaml", ".yml")) else MODELS / f"{model}.yaml"
        if path not in cache:
            cache[path] = andyc.compile_model(path, build_dir)[0]
        return cache[path]

    return get


def yaml_text(text: str) -> str:
    """`text` as a YAML double-quoted scalar (every character escaped that YAML needs escaped)."""
    out = []
    for ch in text:
        code = ord(ch)
        if ch in '"\\':
            out.append("\\" + ch)
        elif code < 0x20 or 0xD800 <= code <= 0xDFFF or code in (0x2028, 0x2029):
            out.append(f"\\u{code:04x}")
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'
