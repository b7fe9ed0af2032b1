"""Contact modes as flow numbers: each contact's state (open, closed or stick, slip either way; spatial friction: slip) is a digit,
the flow is their number in mixed radix (contact 0 the lowest digit). Plain Python, no SymPy: the runtime and
the run files read it on every run (andyc.spec.contacts builds the modes)."""

from __future__ import annotations


def radices(tangents: list) -> list:
    """The number of states of each contact, from its number of friction tangents (or a flag, True for planar
    friction): 2 without friction (open, closed), 4 planar (open, stick, slip forwards, backwards), 3 spatial
    (open, stick, slip)."""
    return [(2, 4, 3)[int(n)] for n in tangents]


def states_of(flow: int, radix: list) -> list:
    """Each contact's state in `flow` (the flow index is the states in mixed radix, contact 0 the lowest digit)."""
    states = []
    for r in radix:
        states.append(flow % r)
        flow //= r
    return states


def flow_of(states: list, radix: list) -> int:
    """The flow of the contacts' states (the inverse of states_of)."""
    flow, place = 0, 1
    for s, r in zip(states, radix):
        flow += s * place
        place *= r
    return flow
