"""Measures of a run checked on synthetic runs whose answer is known by hand (issue 41's survivors).

The shipped models' energy changes monotonically and their series are symmetric, so a measure taken at the end
instead of over the run, or a median instead of a mean, gave the same number there; these series are built
so that it does not.
"""

from types import SimpleNamespace

import numpy as np
import sympy as sp

from andyc.analysis.expectations import _energy_drift
from andyc.analysis.sweeps.metrics import _run_function


def test_energy_drift_is_the_largest_error_over_the_run_not_the_last():
    # E rises by 0.5 J mid-run and comes back to within 0.01 J of E(0): the drift is 0.5 by hand.
    run = SimpleNamespace(energy=np.array([2.0, 2.2, 2.5, 2.3, 2.01]))
    passed, measured, _ = _energy_drift(SimpleNamespace(data={"bound": 0.1}), run, None, None)
    assert not passed
    assert "0.5" in measured


def test_mean_of_a_skewed_series_is_its_mean_not_its_median():
    # samples 0, 0, 0, 0, 10: mean 2 by hand, median 0
    x = sp.Symbol("x")
    run = SimpleNamespace(events={"time": np.array([]), "jump": np.array([])}, time=np.arange(5.0))
    series = {"x": np.array([0.0, 0.0, 0.0, 0.0, 10.0])}
    assert _run_function("mean", (x,), series, run) == 2.0
    assert _run_function("max", (x,), series, run) == 10.0


def test_stability_flags_a_run_that_missed_an_event():
    # A ball dropped from 1.25 m under g = 10 bounces at t = 0.5 s (sqrt(2 h / g)); a step that skipped the
    # bounce may still end near the reference state (here exactly on it), so only the jump count tells.
    from andyc.analysis.stability import ACCURATE, FAILED, classify

    ref = SimpleNamespace(jumps=1, scale=1.25)
    common = dict(finished=True, status="finished", growth=1.0, residual=0.0, error=0.0)
    missed = classify(SimpleNamespace(jumps=0, **common), ref)
    assert missed.verdict == FAILED and "missed an event" in missed.reason
    assert classify(SimpleNamespace(jumps=1, **common), ref).verdict == ACCURATE
