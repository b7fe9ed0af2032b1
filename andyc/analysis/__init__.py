"""Accuracy against cost, and where methods fail: work-precision sweeps and stability scans; and the
linearization about a point given by name (linearization.py, `andyc linearize`); a model's initial state
checked from its equations (initial_state.py, `andyc check`); its expectations run and measured
(expectations.py, junit.py: `andyc test`).

The sweeps and scans run a compiled model many times through andyc.simulate and compare each
run with a reference over the same horizon: the model's closed form where it
declares one (closed_form:), else DOP853 at rtol = atol = 1e-13.
A fixed step h is adjusted to divide the horizon T (h = T / round(T / h)), so
that every run ends at T and one reference serves them all.

    accuracy.py       one run against the reference solution (closed form or DOP853): its error and cost
    workprecision.py  error against cost per method (andyc bench)
    stability.py      where each fixed-step method fails (andyc stability)
    linearization.py  A, B about a point given by name (andyc linearize)
"""
