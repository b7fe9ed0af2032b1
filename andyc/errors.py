"""User-facing errors: one line per problem, `FILE:LINE: PATH: what; fix`."""

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
        return f"{text}; {self.hint}" if self.hint else text


class SpecError(Exception):
    """A model that cannot be compiled; carries every problem found."""

    def __init__(self, diagnostics: list[Diagnostic]):
        self.diagnostics = list(diagnostics)
        super().__init__("\n".join(str(d) for d in self.diagnostics))


class SimulationError(Exception):
    """A run that cannot start (bad option, inconsistent state)."""


def format_path(path) -> str:
    """('frames', 3, 'dh', 1) -> 'frames[3].dh[1]'."""
    out = ""
    for part in path:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += ("." if out else "") + str(part)
    return out
