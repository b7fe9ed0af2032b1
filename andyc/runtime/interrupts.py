"""Stopping a run from outside: SIGINT, SIGTERM, SIGHUP and a wall-clock limit, keeping what it logged.

While a run integrates, SIGINT, SIGTERM and SIGHUP (the terminal or the SSH session closed) do not raise: a
handler notes the
signal, and the run stops where its loop next returns to Python (the compiled
loop does so after each block of steps, about every 0.25 s; the SciPy loop
after each step), keeping its samples, with the status "interrupted: ...".
The command line then writes them and exits with 128 + the signal's number
(130 for SIGINT, 143 for SIGTERM, 129 for SIGHUP), as shells do. A signal the process was
started ignoring (`nohup andyc sim ...` ignores SIGHUP) stays ignored. A wall-clock limit stops the
run the same way, with the status "stopped: ...".

Code that never returns (a compiled controller in an endless loop) cannot be
stopped from inside. The compiled loop releases the GIL, so a watchdog thread
keeps time beside it and learns of signals from a wakeup file descriptor (the
handler itself runs only when the main thread runs Python). When the run has
not stopped GRACE seconds after a signal or the limit, the watchdog builds the
run from the samples logged so far (`partial`), hands it to `abandon` (the
command line writes the files) and ends the process with the same exit code.
Without `abandon` (the Python API) nothing is given up: the run stops where
its loop next returns, as it would without a watchdog.
"""

from __future__ import annotations

import os
import select
import signal
import socket
import sys
import threading
import time
from contextlib import contextmanager

GRACE = 3.0             # seconds a stop may take before the watchdog gives the run up
SIGNALS = tuple(getattr(signal, name) for name in ("SIGINT", "SIGTERM", "SIGHUP") if hasattr(signal, name))


class Interrupts:
    """What asks a run to stop: a signal, or the wall clock past `wall_limit` seconds."""

    def __init__(self, wall_limit: float | None = None, abandon=None):
        self.wall_limit = wall_limit
        self.abandon = abandon          # abandon(run) before the process ends, when the run does not stop
        self.partial = None             # set by the integrator: partial() -> the Run of the samples so far
        self.signal: int | None = None
        self.start = time.monotonic()
        self.asked_at: float | None = None
        self.stopped = False            # the run saw the request and stopped by itself

    def reason(self) -> str | None:
        """Why the run must stop now, as its status, or None."""
        if self.signal is not None:
            return f"interrupted: {signal.Signals(self.signal).name} received"
        if self.wall_limit is not None and time.monotonic() - self.start > self.wall_limit:
            return f"stopped: the run took longer than its wall-clock limit of {self.wall_limit:g} s"
        return None

    def budget(self, seconds: float) -> float:
        """`seconds`, or less when the wall-clock limit is nearer: how long a block of compiled steps may take
        before the loop looks at reason() again (a run must not finish a block long past its limit)."""
        if self.wall_limit is None:
            return seconds
        return max(min(seconds, self.wall_limit - (time.monotonic() - self.start)), 1e-4)

    @property
    def exit_code(self) -> int:
        """128 + the signal's number, as shells report a process a signal ended; 1 for the wall-clock limit."""
        return 128 + self.signal if self.signal is not None else 1

    def _note(self, signum, frame=None) -> None:
        if self.signal is None:
            self.signal = signum

    @contextmanager
    def watching(self):
        """Install the signal handlers and the watchdog for the duration of a run (main thread only;
        elsewhere, and when nothing is to be watched, a plain block)."""
        self.start = time.monotonic()          # the limit is on the run, not on the compiling before it
        if threading.current_thread() is not threading.main_thread():
            yield self
            return
        previous = {s: signal.signal(s, self._note) for s in SIGNALS if signal.getsignal(s) is not signal.SIG_IGN}
        reader, writer = socket.socketpair()
        reader.setblocking(False)
        writer.setblocking(False)
        old_fd = signal.set_wakeup_fd(writer.fileno(), warn_on_full_buffer=False)
        done = threading.Event()
        watchdog = threading.Thread(target=self._watch, args=(reader, done), name="andyc-watchdog", daemon=True)
        watchdog.start()
        try:
            yield self
        finally:
            done.set()
            try:                                # wake the watchdog's select now, not at its next 0.1 s poll
                writer.send(b"\0")             # (0 is no signal's number)
            except OSError:
                pass
            watchdog.join()
            signal.set_wakeup_fd(old_fd)
            for s, handler in previous.items():
                signal.signal(s, handler)
            reader.close()
            writer.close()

    def _watch(self, reader, done) -> None:
        while not done.is_set():
            if select.select([reader], [], [], 0.1)[0]:
                data = reader.recv(64)
                if data and self.signal is None and data[0] in (int(s) for s in SIGNALS):
                    self.signal = data[0]
            if self.asked_at is None and self.reason() is not None:
                self.asked_at = time.monotonic()
            if (self.asked_at is not None and not self.stopped and self.abandon is not None
                    and self.partial is not None and time.monotonic() - self.asked_at > GRACE and not done.is_set()):
                self._give_up()

    def _give_up(self) -> None:
        """The run did not stop: write what it logged and end the process."""
        print(f"andyc: the run did not stop within {GRACE:g} s of the request (code that does not return, such "
              f"as a compiled controller in an endless loop); writing the samples logged so far", file=sys.stderr,
              flush=True)
        try:
            run = self.partial()
            run.status = (self.reason() or "interrupted") + ("; the run did not return to Python (code that "
                                                             "does not return?)")
            self.abandon(run)
        finally:
            sys.stderr.flush()
            sys.stdout.flush()
            os._exit(self.exit_code)
