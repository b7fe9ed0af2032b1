"""Issue 40's findings, each reproduced and held: bounded reads and waits of `andyc sweep`, numbers of
simulate: and expect: checked at `andyc check`, internal errors turned into messages, SIGHUP, a read-only
build, `andyc test` that ran nothing, and the generated module's argument sizes.

Waits here are hang detectors (tests/support/cli.py's HANG), never speed bounds: each fix bounds its own
wait, and the test only sees that it ended with its message."""

from __future__ import annotations

import math
import os
import re
import signal
import subprocess
import sys
import time
import tracemalloc
from pathlib import Path

import numpy as np
import pytest

import andyc
from tests.support import MODELS
from tests.support.cli import HANG, andyc_cli, invoke
from tests.support.diagnostics import LINE_FORMAT, line_of

PENDULUM = (MODELS / "double_pendulum.yaml").read_text()


def one_line_error(result, *fragments):
    """A refusal of an option: exit 2, no traceback, one `Error: ...` line holding every fragment."""
    assert result.exit_code == 2, result.output
    assert "Traceback" not in result.output and "internal error" not in result.output, result.output
    errors = [x for x in result.output.splitlines() if x.startswith("Error:")]
    assert len(errors) == 1, result.output
    for fragment in fragments:
        assert fragment in errors[0], result.output


# ---- 1. and 3. sweep points: bounded before they are read or made ------------------------------------------

def test_points_from_a_device_or_a_pipe_are_refused_without_reading(tmp_path, shipped_build):
    pipe = tmp_path / "points.csv"
    os.mkfifo(pipe)
    for source in ("/dev/zero", pipe):
        result = andyc_cli("sweep", MODELS / "double_pendulum.yaml", "--points", source, "--build-dir",
                           shipped_build, "-o", tmp_path / "s.zarr")      # (a subprocess: a hang is caught)
        assert result.returncode == 2, result.stderr
        assert f"Error: {source}:1: this is a special file, not a CSV file" in result.stderr
        assert "Traceback" not in result.stderr
    assert not (tmp_path / "s.zarr").exists()


def test_a_points_file_past_the_size_limit_is_refused_by_its_size(tmp_path, monkeypatch):
    from andyc.analysis.sweeps import points as P

    big = tmp_path / "big.csv"
    big.write_text("m1\n" + "1.0\n" * 1000)
    monkeypatch.setattr(P, "MAX_CSV_BYTES", 1000)
    with pytest.raises(P.PointsError, match=r"big.csv:1: the file has more than .* past andyc's limit for --points"):
        P.from_csv(big)


def test_a_huge_grid_is_refused_from_its_counts_before_any_value_is_made():
    from andyc.analysis.sweeps import points as P

    tracemalloc.start()
    try:
        for specs in (["m1=1:2:1000000000"], ["m1=1:2:100000", "m2=0:1:100000"], ["m1=1:2:" + "9" * 5000]):
            with pytest.raises(P.PointsError, match="past the limit of 1e"):
                P.grid(specs)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 20e6, f"{peak / 1e6:.0f} MB allocated to refuse a grid"     # (7.9 GB before the fix)


def test_cli_huge_grid_is_one_line(shipped_build, tmp_path):
    result = invoke("sweep", MODELS / "double_pendulum.yaml", "--grid", "m1=1:2:1000000000", "--build-dir",
                    shipped_build, "-o", tmp_path / "s.zarr")
    one_line_error(result, "--grid: 1000000000 points, past the limit of 1e+07")


# ---- 4. simulate: and expect: numbers are finite at check time ------------------------------------------------

@pytest.mark.parametrize("section, path, what", [
    ("simulate: {t_end: .inf}", "simulate.t_end", "inf is not a finite number"),
    ("simulate: {t_end: .nan}", "simulate.t_end", "nan is not a finite number"),
    ("simulate: {method: DOP853, rtol: .nan}", "simulate.rtol", "nan is not a finite number"),
    ("simulate: {atol: .inf}", "simulate.atol", "inf is not a finite number"),
    ("simulate: {init_tol: .nan}", "simulate.init_tol", "nan is not a finite number"),
    ("simulate: {energy_tol: .inf}", "simulate.energy_tol", "inf is not a finite number"),
    ("simulate: {zeno_tol: .nan}", "simulate.zeno_tol", "nan is not a finite number"),
    ("simulate: {every: 100000000000000000000000}", "simulate.every", "past the limit of 1e+12"),
    ("simulate: {t_end: 1.0e+300}", "simulate.t_end", "steps, past the limit of 1e+11"),
    ("expect: [{t_end: .inf}]", "expect[0].t_end", "inf is not a finite number"),
    ("expect: [{t_end: 1e309}]", "expect[0].t_end", "inf is not a finite number"),
    ("expect: [{t_end: 1.0e+300}]", "expect[0].t_end", "steps, past the limit of 1e+11"),
    ("expect: [{t_end: 1, energy_drift: .nan}]", "expect[0].energy_drift", "nan is not a finite number"),
    ("expect: [{t_end: 1, energy_balance: .inf}]", "expect[0].energy_balance", "inf is not a finite number"),
    ("expect: [{t_end: 1, parameters: {m1: .inf}}]", "expect[0].parameters.m1", "inf is not a finite number"),
    ("expect: [{t_end: 1, inputs: {}, final: [{value: q1, min: .nan}]}]", "expect[0].final[0].min",
     "nan is not a finite number"),
    ("expect: [{t_end: 1, final: [{value: q1, max: 1e309}]}]", "expect[0].final[0].max", "inf is not a finite"),
    ("expect: [{t_end: 1, states: [{t: .nan, tol: 1, values: {q1: 0}}]}]", "expect[0].states[0].t",
     "nan is not a finite number"),
    ("expect: [{t_end: 1, states: [{t: 1, tol: .inf, values: {q1: 0}}]}]", "expect[0].states[0].tol",
     "inf is not a finite number"),
    ("expect: [{t_end: 1, states: [{t: 1, tol: 1, values: {q1: .nan}}]}]", "expect[0].states[0].values.q1",
     "nan is not a finite number"),
    ("expect: [{t_end: 1, jumps: {}, jump_times: {times: {}, tol: .nan}}]", "expect[0].jump_times.tol",
     "nan is not a finite number"),
])
def test_simulate_and_expect_numbers_are_finite_at_check(tmp_path, section, path, what):
    text = PENDULUM.split("\nexpect:")[0] + "\n" + section + "\n"
    (tmp_path / "m.yaml").write_text(text)
    result = invoke("check", tmp_path / "m.yaml")
    assert result.exit_code == 1, result.output
    lines = result.stderr.splitlines()
    assert lines[-1] == "1 problem found" and len(lines) == 2, result.stderr
    found = LINE_FORMAT.match(lines[0])
    assert found and found["path"] == path and what in found["what"], lines[0]
    assert int(found["line"]) == line_of(text, section.split(":")[0] + ":")


# ---- 8. andyc test that tested nothing does not pass ---------------------------------------------------------

def test_andyc_test_on_an_empty_folder_exits_5(tmp_path):
    (tmp_path / "empty").mkdir()
    result = invoke("test", tmp_path / "empty", "--build-dir", tmp_path / "build")
    assert result.exit_code == 5, result.output
    assert "0 checks in 0 models: nothing tested" in result.stdout
    assert result.stderr.strip().startswith("andyc test: nothing tested: no model file (*.yaml, *.yml) in ")
    assert not (tmp_path / "build").exists()
    ok = invoke("test", tmp_path / "empty", "--no-tests-ok", "--build-dir", tmp_path / "build")
    assert ok.exit_code == 0, ok.output


def test_andyc_test_on_models_without_expectations_exits_5_and_json_says_so(tmp_path):
    (tmp_path / "m.yaml").write_text(PENDULUM.split("\nexpect:")[0] + "\n")
    result = invoke("test", tmp_path, "--build-dir", tmp_path / "build", "--format", "json")
    assert result.exit_code == 5
    import json
    document = json.loads(result.stdout)
    assert document["exit_code"] == 5 and not document["ok"]
    assert "no model has an expect: section" in document["problems"][0]["message"]


def test_an_unreadable_model_in_the_folder_is_reported_not_skipped(tmp_path):
    (tmp_path / "m.yaml").symlink_to(tmp_path / "nowhere.yaml")       # a broken link
    result = invoke("test", tmp_path, "--build-dir", tmp_path / "build")
    assert result.exit_code == 1, result.output
    assert re.search(r"m\.yaml:1: <document>: cannot read the file", result.stderr), result.output
    assert "0 checks in 1 model: 1 failure" in result.stdout
