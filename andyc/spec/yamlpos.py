"""Load YAML and remember where every value came from.

PyYAML's composed node tree carries start marks; we construct the plain data
with the safe loader and walk the node tree beside it to map each document
path to its (1-based) line. Duplicate keys, which PyYAML would silently
collapse, are reported instead.

Anchors and aliases are allowed, but a document whose aliases expand past
MAX_VALUES values ("billion laughs": a few hundred bytes that expand to
billions of nodes) or refer to themselves is refused before anything walks
the expanded tree, and so is one nested deeper than MAX_NESTING.
"""

from __future__ import annotations

import re

import yaml

from andyc.errors import Diagnostic, SpecError, format_path

MAX_VALUES = 200_000        # values in the document with its aliases expanded (a large URDF-derived model: ~10^4)
MAX_NESTING = 100           # levels of mappings and lists (a model nests about 6 deep)
MAX_YAML_BYTES = 2_000_000  # a model of a thousand bodies is ~100 kB; parsing YAML in Python takes ~1 s/MB


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


def _check_expansion(root, file: str) -> None:
    """Refuse a node graph whose aliases expand past MAX_VALUES values, refer to their own anchor, or nest
    past MAX_NESTING; in time linear in the distinct nodes (each node's expanded size is computed once)."""
    if root is None:
        return
    size: dict[int, int] = {}
    open_nodes: set[int] = set()
    stack = [(root, 1, False)]
    while stack:
        node, depth, children_done = stack.pop()
        key = id(node)
        if children_done:
            open_nodes.discard(key)
            size[key] = 1 + sum(size[id(c)] for c in _children(node))
            if size[key] > MAX_VALUES:
                raise SpecError([Diagnostic(file, node.start_mark.line + 1, "",
                                            f"the document expands to more than {MAX_VALUES} values through its "
                                            f"anchors and aliases (&name, *name)",
                                            "write the values out, or use fewer aliases of aliases")])
            continue
        if key in size:
            continue
        if key in open_nodes:
            raise SpecError([Diagnostic(file, node.start_mark.line + 1, "",
                                        "an alias (*name) refers to a value that contains it",
                                        "an alias may refer only to a value defined before it, outside it")])
        if depth > MAX_NESTING:
            raise SpecError([Diagnostic(file, node.start_mark.line + 1, "", "the document is nested too deeply",
                                        f"nest mappings and lists at most {MAX_NESTING} levels deep")])
        open_nodes.add(key)
        stack.append((node, depth, True))
        stack.extend((c, depth + 1, False) for c in _children(node) if id(c) not in size)


def _children(node) -> list:
    if isinstance(node, yaml.MappingNode):
        return [n for pair in node.value for n in pair]
    if isinstance(node, yaml.SequenceNode):
        return list(node.value)
    return []


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
        _check_expansion(node, file)
        data = yaml.load(text, Loader=_Loader)
    except yaml.MarkedYAMLError as exc:
        raise SpecError([_syntax_error(exc, text, file)])
    except yaml.YAMLError as exc:
        raise SpecError([Diagnostic(file, 1, "", f"invalid YAML: {exc}", "fix the syntax")])
    except RecursionError:          # PyYAML's composer recurses once per level
        raise SpecError([Diagnostic(file, 1, "", "the document is nested too deeply to read",
                                    f"nest mappings and lists at most {MAX_NESTING} levels deep")])
    lines: dict[tuple, int] = {}
    dups: list = []
    if node is not None:
        _walk(node, (), lines, dups)
    smap = SourceMap(file, lines)
    problems = [Diagnostic(file, line, format_path(p), f"duplicate key '{p[-1]}' (first at line {first})",
                           "remove or rename one (a key may appear once in a mapping)")
                for p, line, first in dups]
    return data, smap, problems
