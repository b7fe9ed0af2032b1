"""Work-precision sweeps and stability scans (issue 7): the classifier against RK4's known
stability bounds (the stiff spring; Baumgarte's soft constraint forces on the ball in a bowl),
RK4's order from the sweep, scans over a parameter and over Baumgarte gains, and the files the
commands write."""

import csv
import math

import numpy as np
import pytest

from andyc.analysis.stability import (ACCURATE, FAILED, baumgarte_rates, boundaries, geometric, parameter_values,
                                      rk4_bound, scan)
from andyc.analysis.workprecision import sweep
from tests.support import MODELS
from tests.support.cli import invoke

OMEGA = 100.0       # models/stiff_spring.yaml: sqrt(k/m)
# RK4 on y' = z y is stable on the negative real axis for z >= z*, the real root of
# R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24 = 1, i.e. of z^3 + 4 z^2 + 12 z + 24 = 0.
RK4_REAL_BOUND = -min(r.real for r in np.roots([1, 4, 12, 24]) if abs(r.imag) < 1e-12)    # 2.7853


def test_the_classifier_fails_rk4_past_its_stability_bound(compiled):
    """x'' = -w^2 x: RK4 is stable for h w <= 2 sqrt(2) (|R(iy)| = 1 there). Scanning h from 0.9 to 1.15
    times that bound, the first failing step lies within 5% of it, every failing run blew up (and says
    when), and nothing below the bound fails."""
    bound = rk4_bound(OMEGA)
    ref, verdicts = scan(compiled("stiff_spring"), ["rk4"], geometric(0.9 * bound, 1.15 * bound, 16), horizon=3.0)
    steps = np.array([v.point.setting for v in verdicts])
    failed = np.array([v.verdict == FAILED for v in verdicts])
    first = steps[failed].min()
    assert abs(first / bound - 1) < 0.05
    assert not failed[steps < bound].any() and failed[steps >= first].all()
    for v in verdicts:
        if v.verdict == FAILED:
            assert v.reason.startswith("blew up: |x| reached") and "at t = " in v.reason
    assert boundaries(verdicts)["rk4", None][1] == first


def test_small_steps_are_accurate_and_a_scan_says_so(compiled):
    ref, verdicts = scan(compiled("stiff_spring"), ["rk4"], [1e-4, 2e-4], horizon=1.0)
    assert all(v.verdict == ACCURATE for v in verdicts)
    # RK4 on the oscillator: R(iy) = e^(iy) - i y^5/120 + O(y^6), a phase lag y^5/120 a step, so at T the
    # phase is off by w^5 h^4 T / 120; the speed (amplitude x0 w = 1) is then off by that times |cos(w T)|
    T, x0 = 1.0, 0.01
    for v in verdicts:
        h = v.point.setting
        assert v.point.error == pytest.approx(OMEGA**5 * h**4 * T / 120 * x0 * OMEGA * abs(np.cos(OMEGA * T)),
                                              rel=0.02)


def test_the_sweep_shows_rk4_is_fourth_order(compiled):
    """On the double pendulum (chaotic only at larger amplitude; this start is regular over 5 s) the error at
    T falls as h^4: the log-log slope between the smallest steps is 4 within 0.2; DOP853's error falls with
    its tolerance."""
    ref, points = sweep(compiled("double_pendulum"), ["rk4", "DOP853"], 5.0, steps=[5e-3, 2.5e-3, 1.25e-3, 6.25e-4],
                        tols=(1e-6, 1e-8, 1e-10), repeats=1)
    rk4 = sorted((p.setting, p.error) for p in points if p.method == "rk4")
    h, err = np.array(rk4).T
    slope = np.polyfit(np.log(h), np.log(err), 1)[0]
    assert abs(slope - 4) < 0.2
    dop = [p.error for p in points if p.method == "DOP853"]
    assert dop[0] > dop[1] > dop[2]
    assert all(p.rhs == 4 * round(5.0 / p.setting) for p in points if p.method == "rk4")


def test_cli_bench_and_stability_write_their_tables_and_diagrams(tmp_path, shipped_build):
    result = invoke("bench", str(MODELS / "stiff_spring.yaml"), "--t-end", "1", "--repeats", "1",
                    "--tols", "geom:1e-4:1e-10:5", "-o", str(tmp_path), "--build-dir", str(shipped_build))
    assert result.exit_code == 0, result.output
    with open(tmp_path / "stiff_spring_work_precision.csv") as fh:
        rows = list(csv.DictReader(fh))
    per_method = {m: [r for r in rows if r["method"] == m] for m in ("rk4", "DOP853")}
    assert len(per_method["rk4"]) == 7 and len(per_method["DOP853"]) == 5        # at least five points a line
    assert all(math.isfinite(float(r["error"])) for r in rows)
    for suffix in (".png", ".svg"):
        assert (tmp_path / f"stiff_spring_work_precision{suffix}").stat().st_size > 5000
    result = invoke("stability", str(MODELS / "stiff_spring.yaml"), "--steps", "0.02,0.025,0.03",
                    "--horizon", "3", "-o", str(tmp_path), "--build-dir", str(shipped_build))
    assert result.exit_code == 0, result.output
    assert "rk4: largest accurate step none; fails from h = 0.03 s (blew up" in result.output
    assert (tmp_path / "stiff_spring_stability_T3.png").exists()
    result = invoke("stability", str(MODELS / "stiff_spring.yaml"), "--methods", "DOP853")
    assert result.exit_code == 2 and "DOP853: the scan is over steps, for the methods rk4, projection" in result.output


def test_a_scan_over_a_parameter_moves_the_bound_with_it(compiled):
    """--scan k: at k = 4e4 (w = 200) RK4 fails from h w = 2 sqrt(2) again, at half the step; each value is
    compared with its own reference (the closed form at that k)."""
    spring = compiled("stiff_spring")
    ws = {1e4: 100.0, 4e4: 200.0}
    steps = sorted({h for w in ws.values() for h in geometric(0.9 * rk4_bound(w), 1.15 * rk4_bound(w), 10)})
    ref, verdicts = scan(spring, ["rk4"], steps, horizon=3.0, variants=parameter_values("k", ws))
    assert ref.source == "closed form"
    for (method, k), (accurate, failing, why) in boundaries(verdicts).items():
        assert abs(failing / rk4_bound(ws[k]) - 1) < 0.05 and why.startswith("blew up")
        assert all(v.verdict != FAILED for v in verdicts if v.variant == k and v.point.setting < rk4_bound(ws[k]))


@pytest.fixture(scope="module")
def ball(compiled):
    return compiled("ball_in_bowl")


def test_baumgarte_soft_forces_damp_the_no_slip_residual_at_w_kd(ball):
    """ANDY eq. 15 adds -A^T K_d c as a force, so a no-slip residual decays as c' = -W K_d c with W = A M^-1 A^T
    = 1/m + r^2/I = 7/2 for a solid ball (I = 2 m r^2 / 5), not at K_d."""
    import andyc

    p = dict(zip(ball.parameter_names, ball.parameter_defaults))
    x0 = ball.initial_state(ball.parameter_defaults).copy()
    x0[ball.state_names.index("wy")] += 1e-3                # off the no-slip rows, on the bowl
    k_d = 10.0
    run = andyc.simulate(ball, 0.2, dt=1e-4, method="baumgarte", parameters={"k_s": 0.0, "k_d": k_d}, x0=x0,
                         init=andyc.Init("as-is"), every=10, progress=False)
    W = 1 / p["m"] + p["r"] ** 2 / (2 * p["m"] * p["r"] ** 2 / 5)
    residual = np.abs(run.residual_velocity[:, 1:]).max(axis=1)
    rate = -np.polyfit(run.time, np.log(residual), 1)[0]
    assert rate == pytest.approx(W * k_d, rel=1e-3)


def test_baumgarte_gains_past_rk4s_real_bound_fail(ball):
    """With K_d = 2w the no-slip residual's eigenvalue is -W 2w (W = 7/2), so RK4 goes unstable where
    h W 2w passes RK4_REAL_BOUND: the first failing step at each w lies within 5% of it, and it fails by
    losing its constraints (the residual bound is raised to 0.1, so only the instability trips it)."""
    ws = (100.0, 300.0)
    bound = {w: RK4_REAL_BOUND / (3.5 * 2 * w) for w in ws}
    steps = sorted({h for w in ws for h in geometric(0.85 * bound[w], 1.15 * bound[w], 12)})
    ref, verdicts = scan(ball, ["baumgarte"], steps, horizon=2.0, residual_tol=0.1,
                         variants=baumgarte_rates(ball, ws))
    assert ref.source.startswith("DOP853")
    found = boundaries(verdicts)
    for w in ws:
        accurate, failing, why = found["baumgarte", w]
        assert abs(failing / bound[w] - 1) < 0.05, (w, failing, bound[w])
        below = [v for v in verdicts if v.variant == w and v.point.setting < 0.97 * bound[w]]
        assert below and all(v.verdict != FAILED for v in below)


def test_cli_scans_baumgarte_gains_into_a_map(tmp_path, shipped_build):
    result = invoke("stability", str(MODELS / "ball_in_bowl.yaml"), "--methods", "baumgarte",
                    "--gains", "1,100", "--steps", "0.02,0.005", "--horizon", "1", "-o", str(tmp_path),
                    "--build-dir", str(shipped_build))
    assert result.exit_code == 0, result.output
    with open(tmp_path / "ball_in_bowl_stability_T1.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert sorted((float(r["variant"]), float(r["step"])) for r in rows) == [(1, 0.005), (1, 0.02), (100, 0.005),
                                                                             (100, 0.02)]
    assert "baumgarte at Baumgarte w = 100: " in result.output
    assert (tmp_path / "ball_in_bowl_stability_T1.svg").stat().st_size > 5000
    result = invoke("stability", str(MODELS / "stiff_spring.yaml"), "--gains", "1,10",
                    "--build-dir", str(shipped_build))
    assert result.exit_code == 2 and "has no constraints, so no Baumgarte gains to scan" in result.output
    result = invoke("stability", str(MODELS / "stiff_spring.yaml"), "--scan", "kk=1,2",
                    "--build-dir", str(shipped_build))
    assert result.exit_code == 2 and "NAME a parameter of stiff_spring (m, k, x0)" in result.output
