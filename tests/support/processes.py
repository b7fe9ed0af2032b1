"""Runs started as child processes that a test then signals: a controller that says when the run is under way,
and the wait for it."""

import signal
import time
from pathlib import Path

HANG = 300          # seconds after which a run counts as not started (a hang detector, not a speed bound)

# Runs as Python (Numba cannot compile open()): once the run has passed t = 1 ms, it says so in a file.
STARTED = """\
import os
def control(t, x, d, p):
    if t > 1e-3 and not os.path.exists({flag!r}):
        open({flag!r}, "w").close()
    return 0.0
"""


def wait_for(path: Path, proc) -> None:
    """Wait until the child `proc` has written `path`; fail with its output if it ended first."""
    deadline = time.monotonic() + HANG
    while not path.exists():
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the run did not start"
        time.sleep(0.05)


def default_signals() -> None:
    """A child's preexec_fn: SIGINT and SIGHUP at their defaults. A test suite started in the background or under
    nohup passes them on ignored, and andyc keeps a signal it was started ignoring ignored (as nohup asks): the
    child would then never see the signal the test sends."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGHUP, signal.SIG_DFL)
