"""Load YAML and remember where every value came from.

PyYAML's composed node tree carries start marks; we construct the plain data
with the safe loader and walk the node tree beside it to map each document
path to its (1-based) line. Duplicate keys, which PyYAML would silently
collapse, are reported instead.
"""

from __future__ import annotations

import yaml

from andyc.errors import Diagnostic, SpecError, format_path


class SourceMap:
    """Document path -> line number, with fallback to the nearest parent."""

    def __init__(self, file: str, lines: dict[tuple, int]):
        self.file = file
        self._lines = lines

    def line(self, path) -> int:
        path = tuple(path)
        while path:
            if path in self._lines:
                return self._lines[path]
            path = path[:-1]
        return self._lines.get((), 1)

    def diag(self, path, message: str, hint: str = "") -> Diagnostic:
        return Diagnostic(self.file, self.line(path), format_path(path), message, hint)


def _walk(node, path, lines, dups):
    lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        seen = set()
        for key_node, value_node in node.value:
            key = key_node.value
            if key in seen:
                dups.append((path + (key,), key_node.start_mark.line + 1))
            seen.add(key)
            _walk(value_node, path + (key,), lines, dups)
            lines[path + (key,)] = key_node.start_mark.line + 1
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _walk(item, path + (i,), lines, dups)


def load_yaml(text: str, file: str):
    """Parse `text`; return (data, SourceMap). Raise SpecError on bad YAML."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
        data = yaml.safe_load(text)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark else 1
        what = exc.problem or str(exc)
        raise SpecError([Diagnostic(file, line, "", f"invalid YAML: {what}",
                                    "fix the syntax at this line (indentation, a missing ':' or an unclosed bracket)")])
    except yaml.YAMLError as exc:
        raise SpecError([Diagnostic(file, 1, "", f"invalid YAML: {exc}", "fix the syntax")])
    lines: dict[tuple, int] = {}
    dups: list = []
    if node is not None:
        _walk(node, (), lines, dups)
    smap = SourceMap(file, lines)
    if dups:
        raise SpecError([Diagnostic(file, line, format_path(p), "duplicate key",
                                    "each key may appear once in a mapping; remove or rename one")
                         for p, line in dups])
    return data, smap
