"""User-facing errors: one line per problem, `FILE:LINE: PATH: what; fix`; and the helpers of user-facing text
(printable, plural)."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Diagnostic:
    """One problem in a model file, located by line and document path."""

    file: str
    line: int
    path: str
    message: str
    hint: str = ""

    def __str__(self) -> str:
        text = f"{self.file}:{self.line}: {self.path or '<document>'}: {self.message}"
        # Printable: a key or a file name may hold control characters (a terminal's escape sequences).
        return printable(f"{text}; {self.hint}" if self.hint else text)


class SpecError(Exception):
    """A model that cannot be compiled; carries every problem found."""

    def __init__(self, diagnostics: list[Diagnostic]):
        self.diagnostics = list(diagnostics)
        super().__init__("\n".join(str(d) for d in self.diagnostics))


class SimulationError(Exception):
    """A run that cannot start (bad option, inconsistent state)."""


class MetricError(ValueError):
    """A sweep's metric that cannot be parsed (andyc.analysis.sweeps.metrics): the message says which, what and how
    to fix it. Here, not beside the parser, so that a sweep without metrics never imports it (nor SymPy under it)."""


class InitialStateError(SimulationError):
    """A run refused for its model's initial state (off the constraint manifold, dependent rows): a problem
    of the model, located in its file (`andyc sim` exits 1 with it, as with any model problem)."""

    def __init__(self, source: str, line: int, path: str, message: str):
        self.line, self.path, self.message = line, path, message
        super().__init__(f"{source}:{line}: {path}: {message}")

    def located(self, file) -> str:
        """The message, located in `file` (the model file as the user named it)."""
        return printable(f"{file}:{self.line}: {self.path}: {self.message}")


def printable(text: str) -> str:
    """`text` on one line: every character that is not printable (line breaks, NUL, lone surrogates) as its
    backslash escape, so that text from a model or a user's code cannot start a line of its own."""
    return "".join(ch if ch.isprintable() else ch.encode("unicode_escape", "backslashreplace").decode("ascii")
                   for ch in text)


def plural(n: int, word: str, words: str | None = None) -> str:
    """'1 frame', '3 frames', '2 bodies': n and the word, in the plural (words, default word + 's') unless n is 1."""
    return f"{n} {word if n == 1 else words or word + 's'}"


def format_path(path) -> str:
    """('frames', 3, 'dh', 1) -> 'frames[3].dh[1]'."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out
