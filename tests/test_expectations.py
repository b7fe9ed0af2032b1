"""A model's expect: section (andyc.spec.expect) and its runner (andyc.analysis.expectations): every kind of
expectation holds in one case and fails in another, the failure's message quoted; the loader names what
an expectation gets wrong.

The expectations are written into a copy of a shipped model; a copy's equations are the shipped model's
(expect: is not part of the build key), so each runs on the shipped build (the `compiled` fixture). What
a failing case measures is compared with an independent figure where there is one (the energy a plastic
bounce removes, RK4's phase error, a jump time moved by a known amount).
"""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

import andyc
from andyc.analysis.expectations import run_expectations
from andyc.errors import SpecError

ROOT = Path(__file__).resolve().parents[1]
G, E, H0 = 9.81, 0.8, 1.0                          # bouncing_ball's parameters
BOUNCES = [math.sqrt(2 * H0 / G)]                   # the bounce times: t1 = sqrt(2 h0/g), flights 2 e^k v1/g
for k in range(1, 4):
    BOUNCES.append(BOUNCES[-1] + 2 * E ** k * math.sqrt(2 * G * H0) / G)


def with_expect(tmp_path, name: str, expect: str) -> Path:
    """The shipped model `name` with `expect` (YAML text, the section's entries) as its expect: section."""
    text = (ROOT / "models" / f"{name}.yaml").read_text()
    text = text[:re.search(r"^expect:", text, re.M).start()]
    path = tmp_path / f"{name}.yaml"
    path.write_text(text + "expect:\n" + expect)
    return path


def outcomes(compiled, tmp_path, name: str, expect: str):
    path = with_expect(tmp_path, name, expect)
    return path, run_expectations(andyc.load(path), compiled(name))


def the_check(found, kind: str):
    (o,) = [o for o in found if o.kind == kind]
    return o


def line_of(path: Path, needle: str) -> int:
    """The line of the expect: section holding `needle`."""
    lines = path.read_text().splitlines()
    start = lines.index("expect:")
    return next(n for n, line in enumerate(lines[start:], start + 1) if needle in line)


# -- the run ---------------------------------------------------------------------

def test_the_run_must_finish(compiled, tmp_path):
    _, found = outcomes(compiled, tmp_path, "bouncing_ball", "  - {t_end: 2}\n")
    assert [o.ok for o in found] == [True]
    path, found = outcomes(compiled, tmp_path, "bouncing_ball", "  - {t_end: 5}\n")   # Zeno at 4.06 s
    (o,) = found
    assert not o.ok and o.kind == "run"
    assert str(o).startswith(f"{path}:{line_of(path, 't_end: 5')}: expect[0]: measured stopped: Zeno behaviour")
    assert str(o).endswith(", expected finished at t = 5 s")


def test_a_refused_run_is_a_failed_expectation(compiled, tmp_path):
    path, found = outcomes(compiled, tmp_path, "biped_rheonomic", "  - {t_end: 0.1, init: check}\n")
    (o,) = found
    assert not o.ok
    assert str(o).startswith(f"{path}:{line_of(path, 't_end: 0.1')}: expect[0]: measured a run refused (")
    assert "the initial state is off the constraint manifold" in str(o)


# -- energy ------------------------------------------------------------------------

def test_energy_drift(compiled, tmp_path):
    _, found = outcomes(compiled, tmp_path, "pendulum_a01", "  - {t_end: 1, energy_drift: 1.0e-9}\n")
    assert all(o.ok for o in found)
    # Pushed by F = 1 N from rest (the pole upright-ish), the energy grows by the push's work.
    path, found = outcomes(compiled, tmp_path, "cart_pole", "  - {t_end: 1, inputs: {F: 1}, energy_drift: 1.0e-3}\n")
    o = the_check(found, "energy_drift")
    assert not o.ok
    measured = float(re.search(r"measured largest \|E\(t\) - E\(0\)\| (\S+) J", str(o)).group(1))
    assert measured > 0.1
    assert str(o).startswith(f"{path}:{line_of(path, 'energy_drift')}: expect[0].energy_drift: measured largest "
                             "|E(t) - E(0)| ")
    assert str(o).endswith(" J, expected <= 0.001 J")


def test_energy_balance(compiled, tmp_path):
    _, found = outcomes(compiled, tmp_path, "cart_pole",
                        "  - {t_end: 2, inputs: {F: 2*sin(3*t)}, energy_balance: 1.0e-4}\n")
    assert all(o.ok for o in found)
    # A bounce (e = 0.8) removes (1 - e^2) m g h0 = 3.5316 J: the run's work 'jumps' carries it (andyc.runtime.work),
    # so the balance holds across the impact.
    path, found = outcomes(compiled, tmp_path, "bouncing_ball", "  - {t_end: 1, energy_balance: 1.0e-9}\n")
    assert the_check(found, "energy_balance").ok
    run = andyc.simulate(compiled("bouncing_ball"), 1.0, dt=1e-3)
    assert run.work_names == ["jumps"] and len(run.events["time"]) == 1
    assert run.work[-1, 0] == pytest.approx(-(1 - E ** 2) * G * H0, rel=1e-9)
    # Too tight a bound fails, saying where and what it measured.
    path, found = outcomes(compiled, tmp_path, "cart_pole", "  - {t_end: 2, inputs: {F: 2*sin(3*t)}, "
                           "energy_balance: 1.0e-15}\n")
    o = the_check(found, "energy_balance")
    assert not o.ok
    assert str(o).startswith(f"{path}:{line_of(path, 'energy_balance: 1.0e-15')}: expect[")
    assert "energy_balance: measured largest |E(t) - E(0) - W(t)| " in str(o)
    assert str(o).endswith(" J, expected <= 1e-15 J")


# -- constraints ---------------------------------------------------------------------

def test_residual(compiled, tmp_path):
    _, found = outcomes(compiled, tmp_path, "fourbar", "  - {t_end: 2, residual: 1.0e-9}\n")
    assert all(o.ok for o in found)
    # RK4 alone (no projection) drifts off the closure through the flat configuration.
    path, found = outcomes(compiled, tmp_path, "fourbar", "  - {t_end: 5, method: rk4, residual: 1.0e-6}\n")
    o = the_check(found, "residual")
    assert not o.ok
    assert re.fullmatch(rf"{re.escape(str(path))}:{line_of(path, 'residual')}: expect\[0\].residual: measured "
                        r"largest constraint residual (\S+), expected <= 1e-06", str(o))


# -- jumps ---------------------------------------------------------------------------------

def test_jump_counts(compiled, tmp_path):
    _, found = outcomes(compiled, tmp_path, "bouncing_ball", "  - {t_end: 2, jumps: {bounce: 3}}\n")
    assert all(o.ok for o in found)
    path, found = outcomes(compiled, tmp_path, "bouncing_ball", "  - {t_end: 2, jumps: {bounce: 4}}\n")
    assert str(the_check(found, "jumps")) == (f"{path}:{line_of(path, 'jumps')}: expect[0].jumps: measured "
                                              "bounce 3 jumps, expected bounce 4")


def test_jump_times(compiled, tmp_path):
    times = ", ".join(repr(t) for t in BOUNCES[:3])
    _, found = outcomes(compiled, tmp_path, "bouncing_ball",
                        f"  - {{t_end: 2, jump_times: {{times: {{bounce: [{times}]}}, tol: 1.0e-9}}}}\n")
    assert all(o.ok for o in found)
    moved = ", ".join(repr(t) for t in [BOUNCES[0], BOUNCES[1] + 1e-3, BOUNCES[2]])
    path, found = outcomes(compiled, tmp_path, "bouncing_ball",
                           f"  - {{t_end: 2, jump_times: {{times: {{bounce: [{moved}]}}, tol: 1.0e-6}}}}\n")
    o = the_check(found, "jump_times")
    assert str(o).startswith(f"{path}:{line_of(path, 'jump_times')}: expect[0].jump_times: measured bounce #2 at "
                             f"t = {BOUNCES[1]:.9g} s, off by 0.001 s, expected bounce 3 times (")
    _, found = outcomes(compiled, tmp_path, "bouncing_ball",
                        f"  - {{t_end: 2, jump_times: {{times: {{bounce: [{times}, 2.5]}}, tol: 1.0e-6}}}}\n")
    assert "measured bounce 3 times (0.451524, 1.17396, 1.75191)" in str(the_check(found, "jump_times"))


# -- states -----------------------------------------------------------------------------------

W = 100.0           # stiff_spring: sqrt(k/m)
X0 = 0.01


def test_states_against_values(compiled, tmp_path):
    """x(t) = x0 cos(w t); at t = 0.5 s RK4 (w dt = 0.1) lags 500 (w dt)^5/120 = 4.2e-5 rad."""
    x = X0 * math.cos(W * 0.5)
    _, found = outcomes(compiled, tmp_path, "stiff_spring",
                        f"  - {{t_end: 0.5, states: [{{t: 0.5, values: {{x: {x!r}}}, tol: 1.0e-6}}]}}\n")
    assert all(o.ok for o in found)
    path, found = outcomes(compiled, tmp_path, "stiff_spring",
                           f"  - {{t_end: 0.5, states: [{{t: 0.5, values: {{x: {-x!r}}}, tol: 1.0e-6}}]}}\n")
    o = the_check(found, "states")
    found = re.fullmatch(rf"{re.escape(str(path))}:{line_of(path, 'states')}: expect\[0\].states\[0\]: measured "
                         rf"largest error (\S+) at t = 0.5 s \(x = (\S+), target {-x:.9g}\), expected <= 1e-06 "
                         "from the values given", str(o))
    assert found, str(o)
    assert float(found.group(2)) == pytest.approx(x, abs=1e-6)
    assert float(found.group(1)) == pytest.approx(2 * abs(x), abs=1e-6)


def test_states_against_the_closed_form(compiled, tmp_path):
    """At t = 1 s RK4's phase lag is 1000 (w dt)^5/120 = 8.3e-5 rad: x_dot off by about x0 w 8.3e-5 = 8.3e-5."""
    _, found = outcomes(compiled, tmp_path, "stiff_spring",
                        "  - {t_end: 1, states: [{t: 1, closed_form: true, tol: 2.0e-4}]}\n")
    assert all(o.ok for o in found)
    path, found = outcomes(compiled, tmp_path, "stiff_spring",
                           "  - {t_end: 1, states: [{t: 1, closed_form: true, tol: 1.0e-6}]}\n")
    o = the_check(found, "states")
    measured = float(re.search(r"largest error (\S+) at", str(o)).group(1))
    assert 0.5 * 8.3e-5 < measured < 1.5 * 8.3e-5
    assert str(o).startswith(f"{path}:{line_of(path, 'states')}: expect[0].states[0]: measured largest error ")
    assert str(o).endswith("expected <= 1e-06 from the closed form")


def test_states_against_a_reference_run_file(compiled, tmp_path):
    model = compiled("stiff_spring")
    andyc.simulate(model, 1.0, dt=1e-3, method="DOP853", rtol=1e-12, atol=1e-14, progress=False).save(
        tmp_path / "ref.h5")
    andyc.simulate(model, 1.0, dt=1e-3, method="DOP853", rtol=1e-12, atol=1e-14, parameters={"x0": 0.02},
                   progress=False).save(tmp_path / "other.h5")
    _, found = outcomes(compiled, tmp_path, "stiff_spring",
                        "  - {t_end: 1, states: [{t: 1, reference: ref.h5, tol: 2.0e-4}]}\n")
    assert all(o.ok for o in found)
    path, found = outcomes(compiled, tmp_path, "stiff_spring",
                           "  - {t_end: 1, states: [{t: 1, reference: other.h5, tol: 2.0e-4}]}\n")
    o = the_check(found, "states")
    # Twice the amplitude: x_dot off by x0 w |sin(w)| = 0.506 at t = 1 s.
    measured = float(re.search(r"largest error (\S+) at", str(o)).group(1))
    assert measured == pytest.approx(X0 * W * abs(math.sin(W)), rel=1e-3)
    assert str(o).startswith(f"{path}:{line_of(path, 'states')}: expect[0].states[0]: measured largest error ")
    assert str(o).endswith("expected <= 0.0002 from the run file other.h5")
    (tmp_path / "junk.h5").write_text("not a run file")            # a model may name any file: no traceback
    _, found = outcomes(compiled, tmp_path, "stiff_spring",
                        "  - {t_end: 1, states: [{t: 1, reference: junk.h5, tol: 2.0e-4}]}\n")
    o = the_check(found, "states")
    assert not o.ok and "the run file cannot be read: " in str(o) and "junk.h5: not a run file that andyc sim" in str(o)
    assert str(o).endswith("expected a run file written by andyc sim (.h5)")


# -- final ----------------------------------------------------------------------------------------

def test_final_expression_bounds(compiled, tmp_path):
    """cart_pole unforced: the horizontal momentum (mc + m) x_dot - m l cos(th) th_dot stays 0."""
    momentum = "(mc + m)*x_dot - m*l*cos(th)*th_dot"
    _, found = outcomes(compiled, tmp_path, "cart_pole",
                        f"  - t_end: 1\n    final: [{{value: '{momentum}', min: -1.0e-10, max: 1.0e-10}}]\n")
    assert all(o.ok for o in found)
    path, found = outcomes(compiled, tmp_path, "cart_pole",
                           "  - t_end: 1\n    final: [{value: 'th + t', min: 0, max: 1}]\n")
    o = the_check(found, "final")
    assert not o.ok
    assert re.fullmatch(rf"{re.escape(str(path))}:{line_of(path, 'final')}: expect\[0\].final\[0\]: measured "
                        r"th \+ t = \S+ at t = 1 s, expected >= 0 and <= 1", str(o))
    th = float(re.search(r"th \+ t = (\S+)", str(o)).group(1)) - 1.0
    assert th > 0.5                         # the pole has fallen from 0.1 rad in a second: th + t > 1
    # A value that is not a real number fails, whatever the bounds, and says so (sqrt(-1 - th^2) has none).
    _, found = outcomes(compiled, tmp_path, "cart_pole",
                        "  - t_end: 1\n    final: [{value: 'sqrt(-1 - th**2)', max: 1.0e+300}]\n")
    o = the_check(found, "final")
    assert not o.ok and "= nan (not a real number) at t = 1 s" in str(o)


# -- the loader ------------------------------------------------------------------------------------

@pytest.mark.parametrize("name, entry, where, message", [
    ("bouncing_ball", "{t_end: 1, jumps: {bounse: 1}}", "expect[0].jumps.bounse",
     "jump 'bounse' does not exist; did you mean 'bounce'?"),
    ("pendulum_a01", "{t_end: 1, states: [{t: 1, closed_form: true, tol: 1}]}", "expect[0].states[0].closed_form",
     "the model declares no closed_form"),
    ("pendulum_a01", "{t_end: 1, states: [{t: 1, reference: nowhere.h5, tol: 1}]}",
     "expect[0].states[0].reference", "the run file 'nowhere.h5' does not exist"),
    ("pendulum_a01", "{t_end: 1, states: [{t: 2, values: {theta: 1}, tol: 1}]}", "expect[0].states[0].t",
     "t = 2 s is past the run's end, t_end = 1 s"),
    ("pendulum_a01", "{t_end: 1, residual: 1}", "expect[0].residual", "the model has no constraints"),
    ("pendulum_a01", "{t_end: 1, final: [{value: theta + omega, max: 1}]}", "expect[0].final[0].value",
     "'omega'"),
    ("pendulum_a01", "{t_end: 1, parameters: {LL: 2}}", "expect[0].parameters.LL", "parameter 'LL' does not exist"),
    ("pendulum_a01", "{t_end: 1, energy_drift: -1}", "expect[0].energy_drift", "-1"),
])
def test_the_loader_names_what_an_expectation_gets_wrong(tmp_path, name, entry, where, message):
    path = with_expect(tmp_path, name, f"  - {entry}\n")
    with pytest.raises(SpecError) as err:
        andyc.load(path)
    (d,) = err.value.diagnostics
    assert (d.file, d.line, d.path) == (str(path), line_of(path, entry[:12]), where)
    assert message in str(d)


def test_every_shipped_model_declares_expectations():
    for path in sorted((ROOT / "models").glob("*.yaml")):
        spec = andyc.load(path)
        assert spec.expect, f"{path.name} has no expect: section"
        assert all(e.checks for e in spec.expect), f"{path.name}: an expectation without checks"
