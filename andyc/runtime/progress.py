"""Progress of long work, for a person watching: one line on stderr, rewritten in place.

Shown on a terminal only (a pipe, a log or a test gets nothing, so that output never depends on how fast
the machine is), silent for the first second, then at most once a second; once a line is up, the last
count (done = total) is shown too, and close() ends the line. The one printer of andyc's progress: a run's
t / t_end (andyc.simulate, also the reference runs of `andyc bench` and `andyc stability`) and the command
line's long work (the frames of `andyc plot --animate`, the entries `andyc eom` writes out).
"""

from __future__ import annotations

import sys
import time


class Progress:
    """progress(done) or progress(done, total): `label: t = 2 / 10 s (20%), 1 s elapsed, about 4 s left` (unit
    "s", a run's time) or `label: 3 of 10 points, 2.5 points/s, 1 s elapsed, about 3 s left` (another unit: what
    is counted, with its rate); the time left is the rate so far's.

    enabled: print at all (default: when stderr is a terminal; True prints one line per report elsewhere).
    Also a context manager, which closes it."""

    def __init__(self, label: str, total: float | None = None, unit: str = "s", enabled: bool | None = None):
        self.label, self.total, self.unit = label, total, unit
        self.enabled = sys.stderr.isatty() if enabled is None else enabled
        self.start = self.last = time.perf_counter()
        self.shown = False

    def __call__(self, done: float, total: float | None = None) -> None:
        total = self.total if total is None else total
        now = time.perf_counter()
        last = self.shown and total is not None and done >= total
        if not self.enabled or now - self.start < 1.0 or (now - self.last < 1.0 and not last):
            return
        self.last, self.shown = now, True
        terminal = sys.stderr.isatty()          # (elsewhere, when enabled: one line per report)
        line = f"{self.label}: {self.text(done, total, now - self.start)}"
        print("\r" + line if terminal else line, end="" if terminal else "\n", file=sys.stderr, flush=True)

    def text(self, done: float, total: float | None, elapsed: float) -> str:
        """What is done, its rate (counted work), the seconds elapsed and, until the end, those left at the
        rate so far."""
        if self.unit == "s":
            out = f"t = {done:.6g} / {total:g} s ({100 * done / total:.0f}%)"
        else:
            out = f"{done} of {total} {self.unit}, {done / elapsed:.3g} {self.unit}/s"
        out += f", {elapsed:.0f} s elapsed"
        if total is not None and 0 < done < total:
            out += f", about {elapsed * (total - done) / done:.0f} s left"
        return out

    def close(self) -> None:
        """End the line, if one is up."""
        if self.shown and sys.stderr.isatty():
            print(file=sys.stderr, flush=True)
            self.shown = False

    def __enter__(self) -> Progress:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
