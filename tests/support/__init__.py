"""What several test modules share, as plain functions and constants (pytest fixtures stay in
tests/conftest.py): the repository's folders and YAML text here; running the command line in
support.cli; the loader's diagnostics in support.diagnostics; synthetic runs in support.runs; andyc's state
as Pinocchio's in support.pinocchio_map."""

from pathlib import Path

from andyc.independent.robots import robots_dir

ROOT = Path(__file__).resolve().parents[2]
MODELS = ROOT / "models"
# The URDFs that ship in example-robot-data (a test dependency): real robots nobody here wrote.
ROBOTS_DIR = robots_dir()


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
