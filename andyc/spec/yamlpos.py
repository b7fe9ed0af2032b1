"""Load YAML and remember where every value came from.

PyYAML's composed node tree carries start marks; we construct the plain data
with the safe loader and walk the node tree beside it to map each document
path to its (1-based) line. Duplicate keys, which PyYAML would silently
collapse, are reported instead.
"""

from __future__ import annotations

import re

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

    def describe(self, path) -> str:
        """Where `path` is, for messages that point at a second place: 'line 12, frames[3].name'."""
        return f"line {self.line(path)}, {format_path(path)}"


class _Loader(yaml.SafeLoader):
    """SafeLoader that also reads 1e6 and 2.5e-3 as numbers.

    PyYAML follows YAML 1.1, where a float needs a dot and a signed exponent,
    so `1e6` would silently become the string '1e6'; YAML 1.2 reads a number.
    """


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."))


def _walk(node, path, lines, dups):
    lines[path] = node.start_mark.line + 1
    if isinstance(node, yaml.MappingNode):
        seen: dict = {}
        for key_node, value_node in node.value:
            key = key_node.value
            line = key_node.start_mark.line + 1
            if key in seen:
                dups.append((path + (key,), line, seen[key]))
            else:
                seen[key] = line
            _walk(value_node, path + (key,), lines, dups)
            lines[path + (key,)] = line
    elif isinstance(node, yaml.SequenceNode):
        for i, item in enumerate(node.value):
            _walk(item, path + (i,), lines, dups)


def _syntax_error(exc: yaml.MarkedYAMLError, text: str, file: str) -> Diagnostic:
    """PyYAML's error, placed on the line to fix and said in plain words."""
    mark, context = exc.problem_mark or exc.context_mark, exc.context_mark
    line = mark.line + 1 if mark else 1
    problem = exc.problem or str(exc)
    hint = "fix the syntax at this line (indentation, a missing ':' or an unclosed bracket)"
    lines = text.splitlines()
    source = lines[context.line] + " " if context and context.line < len(lines) else " "
    if exc.context == "while scanning a simple key" and context:
        # PyYAML notices the missing ':' only on the next line; the key is on this one.
        line = context.line + 1
        problem = f"no ':' after the key in {source.strip()!r}"
        hint = "write 'key: value' with a space after the ':', or fix the indentation"
    elif (exc.context or "").startswith(("while parsing a flow", "while scanning a quoted")) \
            and context and context.line < mark.line:
        # An unclosed [, { or quote: the problem shows up on a later line.
        opening = source[context.column]
        closing = {"[": "]", "{": "}"}.get(opening, opening)
        line = context.line + 1
        problem = f"the {opening!r} at column {context.column + 1} is not closed ({problem} at line {mark.line + 1})"
        hint = f"close it with {closing!r}"
    elif problem == "but found another document":
        problem = "a second document ('---') in the file"
        hint = "remove the '---' and what follows, or split the file (a model file holds one document)"
    elif "'\\t'" in problem:
        problem = "a tab character where YAML expects spaces"
        hint = "indent with spaces (YAML does not allow tabs)"
    elif problem == "mapping values are not allowed here":
        problem = "unexpected ':' (mapping values are not allowed here)"
        hint = "check the indentation of this line against the line above, or quote a value that contains ': '"
    elif problem.startswith("expected <block end>"):
        problem = "this line's indentation does not match the lines above"
        hint = "indent the entries of one mapping or list by the same number of spaces"
    return Diagnostic(file, line, "", f"invalid YAML: {problem}", hint)


def load_yaml(text: str, file: str):
    """Parse `text`; return (data, SourceMap, duplicate-key problems).

    Raise SpecError on bad YAML. Duplicate keys are returned, not raised, so
    they are reported together with the schema problems.
    """
    try:
        node = yaml.compose(text, Loader=_Loader)
        data = yaml.load(text, Loader=_Loader)
    except yaml.MarkedYAMLError as exc:
        raise SpecError([_syntax_error(exc, text, file)])
    except yaml.YAMLError as exc:
        raise SpecError([Diagnostic(file, 1, "", f"invalid YAML: {exc}", "fix the syntax")])
    lines: dict[tuple, int] = {}
    dups: list = []
    if node is not None:
        _walk(node, (), lines, dups)
    smap = SourceMap(file, lines)
    problems = [Diagnostic(file, line, format_path(p), f"duplicate key '{p[-1]}' (first at line {first})",
                           "remove or rename one (a key may appear once in a mapping)")
                for p, line, first in dups]
    return data, smap, problems
