"""The loader's diagnostics, checked the same way by every test of bad input: each problem is one line
`FILE:LINE: PATH: what; fix` in the file it was loaded from, and the tests compute the line from the
text they wrote (`line_of`), never from what andyc prints."""

import re

import pytest

import andyc
from andyc.errors import SpecError
from tests.support.cli import check

LINE_FORMAT = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+): (?P<path>\S+): (?P<what>.+?); (?P<fix>.+)$")


def line_of(text: str, needle: str, occurrence: int = 1) -> int:
    """1-based number of the line holding the `occurrence`-th `needle`."""
    hits = [n for n, line in enumerate(text.splitlines(), 1) if needle in line]
    assert len(hits) >= occurrence, f"{needle!r} not in the test model"
    return hits[occurrence - 1]


def edit(text: str, old: str, new: str) -> str:
    """`text` with its one `old` replaced by `new`."""
    assert text.count(old) == 1, f"{old!r} must occur once in the model being edited"
    return text.replace(old, new)


def load_text(tmp_path, text: str, name: str = "model.yaml"):
    """`andyc.load` of `text` written to tmp_path/name."""
    file = tmp_path / name
    file.write_text(text)
    return andyc.load(file)


def problems(tmp_path, text: str, derive: bool = False, name: str = "model.yaml") -> list:
    """Load (and with `derive`, derive) `text` written to tmp_path/name; return the diagnostics it must raise,
    each checked to be one FILE:LINE: PATH: what; fix line of that file."""
    file = tmp_path / name
    with pytest.raises(SpecError) as info:
        spec = load_text(tmp_path, text, name)
        if derive:
            andyc.derive(spec)
    found = info.value.diagnostics
    for d in found:
        assert d.file == str(file)
        assert d.message and d.hint, f"every problem says what is wrong and what to do: {d}"
        match = LINE_FORMAT.match(str(d))
        assert match, f"not FILE:LINE: PATH: what; fix: {d}"
        assert (int(match["line"]), match["path"]) == (d.line, d.path or "<document>")
        assert "\n" not in str(d)
    return found


def one_problem(tmp_path, text: str, derive: bool = False, name: str = "model.yaml"):
    """The one diagnostic `problems` finds."""
    found = problems(tmp_path, text, derive, name)
    assert len(found) == 1, "expected exactly one problem, got:\n" + "\n".join(map(str, found))
    return found[0]


def assert_at(d, line: int, path: str):
    assert (d.line, d.path) == (line, path), f"expected line {line}, path {path!r}: {d}"


def check_all_at_once(tmp_path, monkeypatch, text: str, total: int) -> list:
    """`andyc check` on a model with `total` problems: exit 1, one FILE:LINE: PATH line each, a count.
    Returns the regex matches of the lines, in the order printed."""
    (tmp_path / "bad.yaml").write_text(text)
    monkeypatch.chdir(tmp_path)
    result = check("bad.yaml")
    assert result.exit_code == 1 and result.stdout == ""
    *lines, last = result.stderr.splitlines()
    assert last == f"{total} problems found"
    found = [LINE_FORMAT.match(x) for x in lines]
    assert all(found), lines
    return found
