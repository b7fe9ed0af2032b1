"""'did you mean ...?': the start of a hint naming the known name closest to one written wrong.

Every error about an unknown name (a frame, a speed, a field, a URDF joint, a function in an expression)
says it the same way, through `did_you_mean`.
"""

from __future__ import annotations

import difflib


def did_you_mean(written, known, prefix: str = "") -> str:
    """"did you mean 'X'? " for the entry X of `known` closest to `written`, or "" when none is close.

    Close is difflib's ratio of at least 0.6 (its default), so a typo is caught and an unrelated name is
    not guessed at. `prefix` is written before X: 'tip.' suggests 'tip.x' for the attribute 'xx' of 'tip'.
    """
    close = difflib.get_close_matches(str(written), list(known), n=1)
    return f"did you mean '{prefix}{close[0]}'? " if close else ""
