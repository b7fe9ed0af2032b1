"""The files of a build, their paths and keys, read without SymPy or Jinja (andyc.pipeline reads them
to tell whether a build is up to date before it loads anything heavier)."""

from __future__ import annotations

import ast
import hashlib
import os
from dataclasses import dataclass, field
from pathlib import Path

import andyc
from andyc.numerics.compiler import cache_folder, library_file
from andyc.outputs import check_folder, update_text

PACKAGE = Path(__file__).resolve().parents[1]
NUMERICS = PACKAGE / "numerics"           # static source, copied into every build (andyc/numerics/__init__.py)
_GENERATOR_SOURCES = ["symbolic", "codegen", "spec", "templates", "schemas", "numerics"]


@dataclass
class BuildResult:
    name: str
    module_path: Path
    skipped: bool
    build_key: str
    timings: dict = field(default_factory=dict)     # seconds per stage
    operations: dict = field(default_factory=dict)  # function -> sympy op count
    jumps_path: Path | None = None                  # the user's <name>_jumps.py, when the model has jumps
    jumps_kept: bool = False                        # it existed and was left as it was
    jumps_missing: list = field(default_factory=list)  # jumps without a function in a kept file
    compiled: int = 0                               # functions Numba compiled (not loaded from its cache)


def generator_fingerprint() -> str:
    h = hashlib.sha256(andyc.__version__.encode())
    for rel in _GENERATOR_SOURCES:
        for path in sorted((PACKAGE / rel).rglob("*")):
            if path.suffix in (".py", ".j2", ".json") and path.is_file():
                h.update(path.relative_to(PACKAGE).as_posix().encode())
                h.update(path.read_bytes())
    return h.hexdigest()


def _numerics_files() -> list[Path]:
    return sorted(NUMERICS.glob("*.py"))


def numerics_package() -> str:
    """The name a build imports its copy of andyc/numerics/ by: `andyc_numerics_<digest of its files>`, so that
    one name means one content, in every build and in Numba's cache of it (andyc/numerics/compiler.py)."""
    h = hashlib.sha256()
    for path in _numerics_files():
        h.update(path.name.encode() + b"\0" + path.read_bytes())
    return f"andyc_numerics_{h.hexdigest()[:16]}"


def numerics_compiled() -> bool:
    """Whether this andyc's numerics are in the cache (compiled once per installation, for every model): the
    integrator's full variant, which event location is compiled for alone (a free-variant-only cache, from a first
    run of a model without rows, jumps or contacts, leaves a constrained model's minute still to come)."""
    folder = Path(cache_folder(numerics_package()))
    return any(folder.glob("*advance*.nbi")) and any(folder.glob("*locate*.nbi"))


def numerics_path(out_dir, name: str) -> Path:
    return Path(out_dir) / name / "andyc_numerics"


def write_numerics(out_dir, name: str) -> None:
    """Copy andyc/numerics/ into the build folder of `name` (the files that differ; each written whole)."""
    folder = check_folder(numerics_path(out_dir, name))
    for path in _numerics_files():
        update_text(folder / path.name, path.read_text(encoding="utf-8"))


def build_key(meaning_sha256: str) -> str:
    """The key of a build: what the model's equations depend on (Spec.meaning_sha256) and andyc's own
    generator. Equal keys, equal <name>_equations.py."""
    return hashlib.sha256((meaning_sha256 + generator_fingerprint()).encode()).hexdigest()


def module_path(out_dir, name: str) -> Path:
    return Path(out_dir) / name / f"{name}.py"


def module_name(name: str, key: str) -> str:
    """The name <name>_equations.py takes in sys.modules, one per build key: Numba's cache refers to its
    functions by it, so andyc and a plain `import <name>` use one cache (see _equations in module.py.j2)."""
    return f"andyc_{name}_{key[:16]}"


def equations_path(out_dir, name: str) -> Path:
    return Path(out_dir) / name / f"{name}_equations.py"


def recorded_path(path, folder) -> str:
    """How a build records the path of a file it was made from (SOURCE_PATH, SPEC_FILES): relative to the build's
    folder, so that the generated module carries no path of the machine that built it and a build moved together
    with its model still knows it; absolute only where no relative path exists (another drive)."""
    try:
        return os.path.relpath(Path(path).resolve(), Path(folder).resolve())
    except ValueError:
        return str(Path(path).resolve())


def recorded_back(text: str, folder) -> Path:
    """The absolute path of a file a build recorded (recorded_path) in `folder`."""
    return Path(os.path.normpath(Path(folder).resolve() / text))


def written_constant(path: Path, constant: str):
    """The value of a generated file's `CONSTANT = <literal>` line (BUILD_KEY, SOURCE_PATH, SPEC_FILES),
    read without importing the file; None when there is no such file or line."""
    try:
        with open(path, encoding="utf-8", errors="replace") as fh:
            for line in fh:
                if line.startswith(f"{constant} = "):
                    return ast.literal_eval(line.split("=", 1)[1].split("  #")[0].strip())
    except (OSError, ValueError, SyntaxError):
        return None
    return None


def library_present(out_dir, name: str) -> bool:
    """Whether the build's leaves are all there: the shared library its equations load (andyc.codegen.c_leaves),
    when they load one."""
    equations = equations_path(out_dir, name)
    stem = written_constant(equations, "C_LEAVES")
    return stem is None or equations.with_name(library_file(str(stem))).is_file()


def jumps_path(out_dir, name: str) -> Path:
    return Path(out_dir) / name / f"{name}_jumps.py"
