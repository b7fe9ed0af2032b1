"""Work-precision sweeps and stability scans (issue 7): the classifier against RK4's known
stability bound, RK4's order from the sweep, and the files the commands write."""

import csv
import math

import numpy as np
import pytest
from click.testing import CliRunner

from andyc.analysis.stability import ACCURATE, FAILED, boundaries, geometric, rk4_bound, scan
from andyc.analysis.workprecision import sweep
from andyc.cli import main
from tests.conftest import MODELS

OMEGA = 100.0       # models/stiff_spring.yaml: sqrt(k/m)


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
    assert boundaries(verdicts)["rk4"][1] == first


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


def test_cli_bench_and_stability_write_their_tables_and_diagrams(tmp_path, build_dir):
    runner = CliRunner()
    result = runner.invoke(main, ["bench", str(MODELS / "stiff_spring.yaml"), "--t-end", "1", "--repeats", "1",
                                  "--tols", "geom:1e-4:1e-10:5", "-o", str(tmp_path), "--build-dir", str(build_dir)])
    assert result.exit_code == 0, result.output
    with open(tmp_path / "stiff_spring_work_precision.csv") as fh:
        rows = list(csv.DictReader(fh))
    per_method = {m: [r for r in rows if r["method"] == m] for m in ("rk4", "DOP853")}
    assert len(per_method["rk4"]) == 7 and len(per_method["DOP853"]) == 5        # at least five points a line
    assert all(math.isfinite(float(r["error"])) for r in rows)
    for suffix in (".png", ".svg"):
        assert (tmp_path / f"stiff_spring_work_precision{suffix}").stat().st_size > 5000
    result = runner.invoke(main, ["stability", str(MODELS / "stiff_spring.yaml"), "--steps", "0.02,0.025,0.03",
                                  "--horizon", "3", "-o", str(tmp_path), "--build-dir", str(build_dir)])
    assert result.exit_code == 0, result.output
    assert "rk4: largest accurate step none; fails from h = 0.03 s (blew up" in result.output
    assert (tmp_path / "stiff_spring_stability_T3.png").exists()
    result = runner.invoke(main, ["stability", str(MODELS / "stiff_spring.yaml"), "--methods", "DOP853"])
    assert result.exit_code == 2 and "for fixed-step methods" in result.output
