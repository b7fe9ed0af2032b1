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
from tests.support.processes import STARTED, default_signals, wait_for
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


def _sweep_in_a_terminal(store: Path, shipped_build, *extra):
    """`andyc sweep` of 400 long points in its own process group, as a terminal runs it."""
    return subprocess.Popen([sys.executable, "-m", "andyc.cli", "sweep", str(MODELS / "double_pendulum.yaml"),
                             "--grid", "m1=1:2:400", "--batch", "1", "--build-dir", str(shipped_build), "-o",
                             str(store), *extra], start_new_session=True, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=default_signals)


def _once_a_batch_is_written(proc, store: Path, deadline: float) -> None:
    while not any((store / "outcome").glob("[0-9]*")):
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "no batch was written"
        time.sleep(0.05)


def _ctrl_c(proc) -> str:
    """SIGINT to the sweep's whole process group (the terminal's Ctrl-C); its stderr, checked: exit 130, one
    line, no traceback."""
    os.killpg(proc.pid, signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=HANG)
    assert proc.returncode == 130, stderr
    assert stderr.strip().splitlines()[-1] == "andyc: interrupted"
    assert "Traceback" not in stderr and "KeyboardInterrupt" not in stderr and "Error" not in stderr, stderr
    return stderr


def test_ctrl_c_stops_an_inline_sweep_with_one_line_keeping_the_points_done(tmp_path, shipped_build):
    pytest.importorskip("zarr")
    import zarr

    store = tmp_path / "s.zarr"
    proc = _sweep_in_a_terminal(store, shipped_build, "--t-end", "20", "--engine", "inline")
    _once_a_batch_is_written(proc, store, time.monotonic() + HANG)
    _ctrl_c(proc)
    outcome = np.asarray(zarr.open_group(str(store), mode="r")["outcome"][...])
    # the points written are whole runs (finished, none cut short by the signal), the others not run
    assert 1 <= np.count_nonzero(outcome) < 400 and set(np.unique(outcome)) <= {0, 1}, np.unique(outcome)


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


# ---- 5. internal errors that are messages: damaged run files, an unknown image type ------------------------

def synthetic_run(tmp_path: Path, name: str = "run.h5") -> Path:
    """A small run file of a made-up model with one logged frame (no build)."""
    from andyc.runtime.run import Run

    n = 11
    time = np.linspace(0, 1, n)
    run = Run(model="m", spec_sha256="0", method="rk4", dt=0.1, nq=1, nv=1, rtol=0.0, atol=0.0, t_end=1.0,
              parameters={}, inputs={}, state_names=["y", "y_dot"], time=time, state=np.ones((n, 2)),
              energy=np.zeros(n), frames={"tip": np.zeros((n, 3))}, frame_parents={"tip": "world"})
    return run.save(tmp_path / name)


def _replace(f, key, value):
    attrs = dict(f[key].attrs)
    del f[key]
    f[key] = value
    f[key].attrs.update(attrs)


DAMAGE = {
    "not-hdf5": None,
    "truncated": None,
    "no-state": lambda f: f.__delitem__("state"),
    "no-time": lambda f: f.__delitem__("time"),
    "no-attributes": lambda f: f.attrs.__delitem__("model"),
    "state-columns": lambda f: _replace(f, "state", f["state"][:, :1]),
    "state-rows": lambda f: _replace(f, "state", f["state"][:5]),
    "state-1d": lambda f: _replace(f, "state", f["state"][:, 0]),
    "state-text": lambda f: _replace(f, "state", np.array([b"x"] * 11)),
    "time-short": lambda f: _replace(f, "time", f["time"][:3]),
    "time-nan": lambda f: _replace(f, "time", np.full(11, np.nan)),
    "time-backwards": lambda f: _replace(f, "time", f["time"][()][::-1].copy()),
    "energy-short": lambda f: _replace(f, "energy", f["energy"][:2]),
    "frame-1d": lambda f: _replace(f, "frames/tip", np.zeros(3)),
    "flow-names-number": lambda f: f.attrs.__setitem__("flow_names", "5"),
    "parameters-not-json": lambda f: f.attrs.__setitem__("parameters", "{"),
    "parameters-a-list": lambda f: f.attrs.__setitem__("parameters", "[1]"),
    "nq-text": lambda f: f.attrs.__setitem__("nq", "abc"),
    "nq-past-the-states": lambda f: f.attrs.__setitem__("nq", 5),
    "name-with-escape": lambda f: f["state"].attrs.__setitem__("names", ["\x1b[2J", "y_dot"]),
    "model-with-escape": lambda f: f.attrs.__setitem__("model", "\x1b]0;pwned\x07"),
}


@pytest.mark.parametrize("damage", list(DAMAGE))
@pytest.mark.parametrize("command", ["plot", "plot --animate", "view"])
def test_a_damaged_run_file_is_one_line_not_an_internal_error(tmp_path, damage, command):
    import h5py

    path = synthetic_run(tmp_path)
    if damage == "not-hdf5":
        path.write_bytes(b"garbage, not HDF5\n" * 10)
    elif damage == "truncated":
        path.write_bytes(path.read_bytes()[:3000])
    else:
        with h5py.File(path, "a") as f:
            DAMAGE[damage](f)
    before = path.read_bytes()
    out = tmp_path / ("out.html" if command == "view" else "out.gif" if "animate" in command else "out.png")
    result = invoke(*command.split(), path, "-o", out)
    one_line_error(result, f"Invalid value for RUN_FILE: {path}: ")
    assert "\x1b" not in result.output and "\x07" not in result.output
    assert path.read_bytes() == before and not out.exists()


@pytest.mark.parametrize("command", ["plot", "view"])
def test_a_run_with_no_samples_is_one_line(tmp_path, command):
    import h5py

    path = synthetic_run(tmp_path)
    with h5py.File(path, "a") as f:
        for key in ("time", "state", "energy", "flow", "discrete", "inputs", "multipliers", "residual/position",
                    "residual/velocity", "work", "power", "frames/tip"):
            _replace(f, key, f[key][:0])
    result = invoke(command, path, "-o", tmp_path / ("o.html" if command == "view" else "o.png"))
    one_line_error(result, "holds no samples")


@pytest.mark.parametrize("out, says", [("p.xyz", "unknown image type '.xyz'"), ("p", "no image type"),
                                       ("p.pgf", "unknown image type '.pgf'")])
def test_plot_to_an_unknown_image_type_is_refused_before_any_work(tmp_path, out, says):
    path = synthetic_run(tmp_path)
    result = invoke("plot", path, "-o", tmp_path / out)
    one_line_error(result, "Invalid value for '-o' / '--out'", says, ".png, .svg or .pdf")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.h5"]


# ---- 5. kinks that have no second derivative, axes that overflow, constants past a float -------------------

SLIDER = """\
name: slider
parameters: {m: 1.0, g: 9.81, k: 1.0}
coordinates:
  x: {initial: 1.0}
  y: {initial: 1.0}
gravity: [0, -g, 0]
frames:
  - {name: sx, parent: world, prismatic: x, axis: x}
  - {name: sy, parent: sx, prismatic: y, axis: y}
  - {name: tip, parent: sy, translation: [0, -1, 0]}
bodies:
  - {name: mass, frame: tip, mass: m}
"""


def located(tmp_path, text, path, *fragments, derive=False):
    """The one problem of `text` at `path`, at the line of its entry, holding every fragment."""
    from tests.support.diagnostics import one_problem

    d = one_problem(tmp_path, text, derive=derive)
    assert d.path == path, str(d)
    for fragment in fragments:
        assert fragment in d.message, str(d)
    return d


@pytest.mark.parametrize("row, kink", [("abs(x) - y", "abs"), ("sign(x) - y", "sign"), ("'max(x, 0.5) - y'", "max"),
                                       ("'min(x, y)'", "min"), ("abs(x*y) - 1", "abs"), ("abs(t) + x - y", "abs"),
                                       ("abs(tip.x) - y", "abs")])
def test_a_kink_in_a_holonomic_row_is_refused_at_its_line(tmp_path, row, kink):
    text = SLIDER + f"constraints:\n  - {{name: line, holonomic: {row}}}\n"
    d = located(tmp_path, text, "constraints[0].holonomic", "the constraint is not smooth", f"where {kink} of")
    assert d.line == line_of(text, "name: line")


def test_a_kink_of_a_parameter_in_a_holonomic_row_is_smooth(tmp_path):
    (tmp_path / "m.yaml").write_text(SLIDER + "constraints:\n  - {name: line, holonomic: abs(m)*x - y}\n")
    assert invoke("check", tmp_path / "m.yaml").exit_code == 0


@pytest.mark.parametrize("old, new, path", [
    ("translation: [0, -1, 0]", "translation: [abs(x), -1, 0]", "frames[2].translation[0]"),
    ("translation: [0, -1, 0]", "translation: [sign(y), -1, 0]", "frames[2].translation[0]"),
    ("translation: [0, -1, 0]", "translation: [0, -1, 0], rotation: {axis: z, angle: abs(t)}",
     "frames[2].rotation.angle"),
    ("translation: [0, -1, 0]", "translation: ['max(x, y)', -1, 0]", "frames[2].translation[0]"),
])
def test_a_kink_in_a_link_is_refused_at_its_line(tmp_path, old, new, path):
    text = SLIDER.replace(old, new)
    located(tmp_path, text, path, "the link is not smooth")


@pytest.mark.parametrize("extra, path", [
    ("potentials: [{name: v, energy: k*sign(x)}]", "potentials[0].energy"),
    ("potentials: [{name: v, energy: k*sign(x)*x}]", "potentials[0].energy"),
    ("springs: [{name: s, stiffness: k, length: sign(x) + y}]", "springs[0].length"),
])
def test_a_potential_or_spring_length_that_steps_is_refused_at_its_line(tmp_path, extra, path):
    located(tmp_path, SLIDER + extra + "\n", path, "steps where sign() of x changes")


@pytest.mark.parametrize("old, new, path, says", [
    ("axis: x}", "axis: [1e308, 1e308, 0]}", None, None),
    ("axis: x}", "axis: x, rotation: {quaternion: [1e308, 1e308, 0, 0]}}", "frames[0].rotation.quaternion",
     "has norm 1.41421356237e+308, not 1"),
    ("mass: m}", "mass: m, shape: {cylinder: {radius: 0.1, length: 1, axis: [1e308, 1e308, 0]}}}", None, None),
])
def test_huge_axes_are_normalised_without_overflow(tmp_path, old, new, path, says):
    text = SLIDER.replace(old, new, 1)
    if path is None:
        (tmp_path / "m.yaml").write_text(text)
        result = invoke("check", tmp_path / "m.yaml")
        assert result.exit_code == 0, result.output
    else:
        d = located(tmp_path, text, path, says)
        assert d.hint == "use the unit quaternion [0.707106781187, 0.707106781187, 0, 0]"


@pytest.mark.parametrize("energy, big", [("x*1e308*10", "1.00e+309"), ("1e200*x**2*1e200", "1.00e+400"),
                                         ("(1e308 + x)*10", "1.00e+309"), ("x/1e-320", "1.00e+320")])
def test_constants_that_fold_past_a_float_are_refused_at_their_line(tmp_path, energy, big):
    text = SLIDER + f"potentials: [{{name: v, energy: '{energy}'}}]\n"
    d = located(tmp_path, text, "potentials[0].energy", f"the constant {big} that its numbers make together "
                "overflows a float")
    assert d.line == line_of(text, "potentials:")


def test_a_priority_past_the_limit_is_refused_at_its_line(tmp_path):
    text = (MODELS / "bouncing_ball.yaml").read_text().replace("    - name: bounce\n",
                                                               "    - name: bounce\n      priority: 1e300\n")
    d = located(tmp_path, text, "hybrid.jumps[0].priority", "greater than the maximum of 1000000")
    assert d.line == line_of(text, "priority: 1e300")


def test_a_derived_constant_past_a_float_names_the_model_not_the_module(tmp_path):
    (tmp_path / "m.yaml").write_text(SLIDER.replace("k: 1.0}", "k: 1.0}").replace(
        "name: slider", "name: big") + "springs: [{name: s, stiffness: 1e200, length: 1e200*x}]\n")
    result = invoke("build", tmp_path / "m.yaml", "--build-dir", tmp_path / "build")
    assert result.exit_code == 1, result.output
    assert result.stderr.splitlines() == [
        f"{tmp_path / 'm.yaml'}:1: <document>: a constant of the derived equations, 1.00e+600, overflows a float "
        "(past 1.8e308); scale the model's units so that its products of masses, lengths, stiffnesses and gains "
        "stay below 1e308", "1 problem found"]
    assert "big.py" not in result.output


# ---- 5. an adaptive run that blows up keeps its samples and writes its files --------------------------------

EXPLODES = """\
name: explodes
description: Free motion until t = 0.5 s, then a potential of stiffness k pushing the mass away.
parameters: {k: 1e300}
coordinates:
  x: {initial: 0, velocity: 1}
frames:
  - {name: slider, parent: world, prismatic: x, axis: x}
bodies:
  - {name: mass, frame: slider, mass: 1}
potentials:
  - {name: push, energy: "-k*x**2*(1 + sign(t - 0.5))/4"}
"""


@pytest.fixture(scope="module")
def explodes(tmp_path_factory, build_dir):
    path = tmp_path_factory.mktemp("explodes") / "explodes.yaml"
    path.write_text(EXPLODES)
    return path


@pytest.mark.parametrize("method", ["Radau", "BDF", "LSODA", "DOP853"])
def test_an_adaptive_run_that_blows_up_keeps_its_samples_and_writes_its_files(explodes, build_dir, tmp_path,
                                                                                method):
    from andyc.runtime.runfiles import read_h5

    result = invoke("sim", explodes, "--method", method, "--t-end", 2, "--build-dir", build_dir, "-o",
                    tmp_path / "r.h5", "-o", tmp_path / "r.csv")
    assert result.exit_code == 1, result.output
    assert "Traceback" not in result.output and "internal error" not in result.output and "warning" not in result.output
    run = read_h5(tmp_path / "r.h5")
    assert run.status.startswith(f"stopped: {method} failed at t = 0.5 s")
    assert run.status.endswith("the 501 samples before it are kept")
    assert len(run.time) == 501 and np.all(np.isfinite(run.state))
    assert np.allclose(run.column("x"), run.time, atol=1e-9)       # x = t before the push
    assert (tmp_path / "r.csv").read_text().count("\n") > 501


def test_lsoda_stuck_at_a_discontinuity_stops_instead_of_stepping_forever(explodes, build_dir):
    model = andyc.compile_model(explodes, build_dir)[0]
    run = andyc.simulate(model, 2.0, method="LSODA", parameters={"k": 1e10}, progress=False)
    assert run.status.startswith("stopped: LSODA failed at t = 0.5 s: 1000 steps in a row made no progress")
    assert run.stats["steps"] < 10_000


# ---- 6. SIGHUP: like SIGINT and SIGTERM (tests/test_hostile_runs.py), unless the run was started under nohup ----

def test_a_run_started_ignoring_sighup_goes_on_and_stops_on_sigterm(tmp_path, shipped_build):
    from andyc.runtime.runfiles import read_h5

    flag, out = tmp_path / "started", tmp_path / "run.h5"
    (tmp_path / "started.py").write_text(STARTED.format(flag=str(flag)))
    proc = subprocess.Popen([sys.executable, "-m", "andyc.cli", "sim", str(MODELS / "cart_pole.yaml"), "--t-end",
                             "1e5", "--every", "100", "--controller", "started.py", "--out", str(out), "--build-dir",
                             str(shipped_build)], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, preexec_fn=lambda: signal.signal(signal.SIGHUP, signal.SIG_IGN))   # nohup
    wait_for(flag, proc)
    proc.send_signal(signal.SIGHUP)
    with pytest.raises(subprocess.TimeoutExpired):          # ignored: the run goes on (1e5 s of it)
        proc.wait(timeout=2)
    proc.send_signal(signal.SIGTERM)
    stdout, stderr = proc.communicate(timeout=HANG)
    assert proc.returncode == 143, stderr
    assert read_h5(out).status.startswith("interrupted: SIGTERM received at t = ")


# ---- 7. an up-to-date build in a read-only folder runs ---------------------------------------------------------

def read_only_commands(folder: Path, commands: list) -> list:
    """Run each andyc command (a list of arguments) with `folder` read-only; a CompletedProcess each. Root, whom
    permissions do not stop, gets a read-only bind mount in a mount namespace of its own (unshare); others a
    folder without write permission."""
    run = [sys.executable, "-m", "andyc.cli"]
    if os.geteuid() != 0:
        modes = {p: p.stat().st_mode for p in [folder, *folder.rglob("*")]}
        for p in modes:
            p.chmod(modes[p] & ~0o222)
        try:
            return [subprocess.run(run + list(map(str, c)), capture_output=True, text=True, timeout=HANG)
                    for c in commands]
        finally:
            for p, mode in modes.items():
                p.chmod(mode)
    import shlex
    import shutil

    if shutil.which("unshare") is None or subprocess.run(["unshare", "-rm", "true"]).returncode != 0:
        pytest.skip("no read-only folder for root here (unshare -rm is not allowed)")
    out = []
    for c in commands:
        script = (f"mount --bind {shlex.quote(str(folder))} {shlex.quote(str(folder))} && mount -o remount,bind,ro "
                  f"{shlex.quote(str(folder))} {shlex.quote(str(folder))} && exec {shlex.join(run + list(map(str, c)))}")
        out.append(subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True, text=True,
                                  timeout=HANG, env={**os.environ, "PYTHONPATH": str(Path(andyc.__file__).parents[1])}))
    return out


def test_an_up_to_date_read_only_build_simulates_and_tests(tmp_path):
    folder = tmp_path / "ro"
    folder.mkdir()
    model = folder / "pendulum.yaml"
    model.write_text(PENDULUM.replace("name: double_pendulum", "name: ro_pendulum"))
    build = folder / "build"
    andyc.compile_model(model, build)
    before = sorted((p.relative_to(folder), p.stat().st_mtime_ns) for p in folder.rglob("*"))
    sim, test, again = read_only_commands(folder, [
        ["sim", model, "--t-end", 0.1, "--build-dir", build, "-o", tmp_path / "run.h5"],
        ["test", model, "--build-dir", build],
        ["build", model, "--build-dir", build, "--force"]])
    assert sim.returncode == 0, sim.stderr
    assert (tmp_path / "run.h5").exists()
    assert test.returncode == 0 and "2 checks in 1 model: all hold" in test.stdout, test.stderr
    assert again.returncode == 2 and "Traceback" not in again.stderr          # a build that must write: refused
    assert again.stderr.startswith("Error: ") and "cannot write" in again.stderr, again.stderr
    assert sorted((p.relative_to(folder), p.stat().st_mtime_ns) for p in folder.rglob("*")) == before


# ---- 9. the generated module checks its arguments' sizes -------------------------------------------------------

@pytest.mark.parametrize("call, message", [
    ("m.rhs(0.0, np.array([1.2, -0.5]))",
     "rhs: wrong argument size for x, the state (q1, q2, q1_dot, q2_dot): expected 4, got 2"),
    ("m.rhs(0.0, np.zeros(7))", "expected 4, got 7"),
    ("m.rhs(0.0, np.zeros((4, 1)))", "expected 4, got (4, 1)"),
    ("m.rhs(0.0, [[1, 2], [3]])", "got a ragged list"),
    ("m.rhs(0.0, np.zeros(4), p=[1.0, 2.0])", "rhs: wrong argument size for p, the parameters (L1, L2, m1, m2, g): "
                                              "expected 5, got 2"),
    ("m.rhs(0.0, np.zeros(4), flow=3)", "rhs: flow = 3 is not the index of a flow: expected 0 to 0 (default)"),
    ("m.rhs(0.0, np.zeros(4), None, None, None, True)", "is not the index of a flow"),
    ("m.energy(0.0, np.zeros(4), u=[1.0])", "energy: wrong argument size for u, the inputs (none): expected 0, got 1"),
    ("m.mass_matrix(0.0, np.zeros(3))", "mass_matrix: wrong argument size for x"),
    ("m.generalized_force(0.0, np.zeros(5))", "generalized_force: wrong argument size for x"),
    ("m.power(0.0, np.zeros(4), d=[1.0])", "power: wrong argument size for d, the discrete states (none)"),
    ("m.frame_positions(0.0, np.zeros(4), out=np.zeros((2, 3)))",
     "frame_positions: wrong argument size for out: expected (4, 3), got (2, 3)"),
    ("m.frame_rotations(0.0, np.zeros(1))", "frame_rotations: wrong argument size for x"),
    ("m.frame_poses(0.0, np.zeros(1))", "frame_poses: wrong argument size for x"),
    ("m.multipliers(0.0, np.zeros(1))", "multipliers: wrong argument size for x"),
    ("m.driven(0.0, np.zeros(1))", "driven: wrong argument size for x"),
    ("m.guard(0, 0.0, np.zeros(4))", "guard: the model has no jump"),
    ("m.enabled(0, 0.0, np.zeros(4))", "enabled: the model has no jump"),
    ("m.constraints(0.0, np.zeros(4), m.INPUT_DEFAULTS, m.PARAMETER_DEFAULTS, m.DISCRETE_DEFAULTS, np.zeros(0), "
     "np.zeros(1), np.zeros((0, 2)), np.zeros(0))", "constraints: wrong argument size for c: expected 0, got 1"),
    ("m.signal_rates(0.0, np.zeros(4), m.INPUT_DEFAULTS, m.PARAMETER_DEFAULTS, m.DISCRETE_DEFAULTS, "
     "np.zeros(4, dtype=np.float32))", "signal_rates: xdot is written into: give a writable, C-contiguous float64"),
    ("m.signal_rates(0.0, np.zeros(4), m.INPUT_DEFAULTS, m.PARAMETER_DEFAULTS, m.DISCRETE_DEFAULTS, np.zeros(2))",
     "signal_rates: wrong argument size for xdot"),
    ("m.restitutions([1.0])", "restitutions: wrong argument size for p"),
    ("m.flow_inputs(m.PARAMETER_DEFAULTS, np.zeros((3, 3)))", "flow_inputs: wrong argument size for U"),
    ("m.energy_law(0.0, np.zeros(2))", "energy_law: wrong argument size for x"),
    ("m.initial_state([1.0, 2.0])", "initial_state: wrong argument size for p"),
    ("m.initial_discrete([1.0])", "initial_discrete: wrong argument size for p"),
])
def test_every_entry_point_of_the_generated_module_checks_sizes(compiled, call, message):
    m = compiled("double_pendulum").module
    with pytest.raises(ValueError) as info:
        eval(call, {"m": m, "np": np})
    assert message in str(info.value), str(info.value)


def test_right_sizes_and_the_integrators_longer_state_still_work(compiled):
    model = compiled("bouncing_ball")
    m = model.module
    x = m.initial_state()
    assert np.array_equal(m.rhs(0.0, x), m.rhs.__wrapped__(0.0, x))
    assert m.guard(0, 0.0, np.concatenate([x, np.zeros(m.NW)]), m.INPUT_DEFAULTS, m.PARAMETER_DEFAULTS,
                   m.DISCRETE_DEFAULTS) == m.guard(np.int64(0), 0.0, list(x))
    with pytest.raises(ValueError, match=r"guard: k = 1 is not the index of a jump: expected 0 to 0 \(bounce\)"):
        m.guard(1, 0.0, x)


# ---- 10. --timeout is a bound on each run's wall time, however short ------------------------------------------

def test_a_short_timeout_stops_runs_that_would_finish_in_one_block(compiled):
    from andyc.runtime.interrupts import Interrupts

    model = compiled("double_pendulum")
    for _ in range(3):          # (the first check may or may not come before the limit: either way, stopped)
        run = andyc.simulate(model, 50.0, dt=1e-3, interrupts=Interrupts(0.001), progress=False)
        assert run.status.startswith("stopped: the run took longer than its wall-clock limit of 0.001 s"), run.status
        assert run.time[-1] < 50.0


def test_the_block_budget_shrinks_to_what_is_left_of_the_limit():
    from andyc.runtime.interrupts import Interrupts

    assert Interrupts().budget(0.25) == 0.25
    near = Interrupts(10.0)
    near.start = time.monotonic() - 9.9
    assert 0.0 < near.budget(0.25) <= 0.1
    near.start = time.monotonic() - 20
    assert near.budget(0.25) == 1e-4


# ---- 2. and 10. sweeps: bounded waits for a scheduler, Ctrl-C, the summary ---------------------------------------

def _serve(handler) -> tuple:
    """A TCP server on loopback that gives each connection to handler(sock) in a thread; (port, close)."""
    import socket
    import threading

    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    server.settimeout(0.2)
    stop = threading.Event()
    held = []

    def loop():
        while not stop.is_set():
            try:
                conn, _ = server.accept()
            except OSError:
                continue
            held.append(conn)
            threading.Thread(target=handler, args=(conn,), daemon=True).start()

    threading.Thread(target=loop, daemon=True).start()

    def close():
        stop.set()
        for c in held:
            c.close()
        server.close()
    return server.getsockname()[1], close


def _http(conn):
    """A plain HTTP server's side: it waits for a request line and headers that never come."""
    try:
        conn.recv(65536)
    except OSError:
        pass


def _banner(conn):
    """A service that speaks first, as SSH does (read as a Dask frame count: about 3e18 frames)."""
    conn.sendall(b"SSH-2.0-OpenSSH_9.0\r\n" + b"\xff" * 64)


def _sweep(*args, scheduler, tmp_path, shipped_build):
    return invoke("sweep", MODELS / "double_pendulum.yaml", "--grid", "m1=1:2:2", "--t-end", 0.05, "--build-dir",
                  shipped_build, "--scheduler", scheduler, "-o", tmp_path / "s.zarr", *args)


@pytest.mark.parametrize("handler, says", [
    (_http, "did not answer within 5 s (something else listens there)"),
    (_banner, "is not a Dask scheduler (it begins b'SSH-2.0-')"),
])
def test_a_scheduler_address_where_something_else_listens_is_one_line_and_leaves_no_store(tmp_path, shipped_build,
                                                                                          handler, says):
    pytest.importorskip("distributed")
    port, close = _serve(handler)
    try:
        result = _sweep(scheduler=f"tcp://127.0.0.1:{port}", tmp_path=tmp_path, shipped_build=shipped_build)
    finally:
        close()
    assert result.exit_code == 1, result.output
    assert result.output.strip().splitlines() == [result.output.strip()]
    assert result.output.startswith(f"andyc: ") and says in result.output, result.output
    assert "Traceback" not in result.output and not (tmp_path / "s.zarr").exists()


@pytest.mark.parametrize("address, says", [
    ("tcp://127.0.0.1:9", "Connection refused"),
    ("garbage", "missing port number"),
    ("http://127.0.0.1:1", "unknown address scheme 'http'"),
])
def test_a_bogus_scheduler_address_leaves_no_store(tmp_path, shipped_build, address, says):
    pytest.importorskip("distributed")
    result = _sweep(scheduler=address, tmp_path=tmp_path, shipped_build=shipped_build)
    assert result.exit_code == 1 and says in result.output and "Traceback" not in result.output, result.output
    assert not (tmp_path / "s.zarr").exists()


def test_a_scheduler_without_workers_is_waited_for_a_bounded_time(tmp_path, shipped_build, monkeypatch):
    import logging

    distributed = pytest.importorskip("distributed")
    from andyc.analysis.sweeps import run as R

    monkeypatch.setattr(R, "WORKER_WAIT", 1.0)          # (60 s in use)
    cluster = distributed.LocalCluster(n_workers=0, processes=True, dashboard_address=None,
                                       silence_logs=logging.ERROR)
    try:
        address = cluster.scheduler_address
        assert address.startswith("tcp://127.0.0.1:")
        result = _sweep(scheduler=address, tmp_path=tmp_path, shipped_build=shipped_build)
    finally:
        cluster.close()
    assert result.exit_code == 1, result.output
    assert result.output.startswith(f"andyc: the Dask scheduler at {address} has no worker after 1 s of waiting")
    assert f"start one there: `dask worker {address}`" in result.output
    assert not (tmp_path / "s.zarr").exists()


def _workers_of(pid: int) -> list:
    """The process ids of the multiprocessing children (a LocalCluster's workers) of process pid."""
    out = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
                cmd = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid and b"spawn_main" in cmd:
                out.append(int(entry.name))
    return out


@pytest.mark.parametrize("when", ["as the workers start", "while they run"])
def test_ctrl_c_stops_a_sweep_with_one_line_and_no_worker_tracebacks(tmp_path, shipped_build, when):
    pytest.importorskip("distributed")
    if not Path("/proc/self/stat").exists():
        pytest.skip("needs /proc to find the workers")
    # The terminal sends SIGINT to the whole foreground process group: the sweep, its workers, the tracker.
    store = tmp_path / "s.zarr"
    proc = _sweep_in_a_terminal(store, shipped_build, "--t-end", "200", "--engine", "cluster", "--workers", "2")
    deadline = time.monotonic() + HANG
    while len(_workers_of(proc.pid)) < 2:
        assert proc.poll() is None, proc.communicate()
        assert time.monotonic() < deadline, "the workers did not start"
        time.sleep(0.01)
    workers = _workers_of(proc.pid)
    if when == "while they run":
        _once_a_batch_is_written(proc, store, deadline)
    _ctrl_c(proc)
    for pid in workers:                     # none left behind
        deadline = time.monotonic() + HANG
        while Path(f"/proc/{pid}").exists() and "Z" not in Path(f"/proc/{pid}/stat").read_text().split()[2]:
            assert time.monotonic() < deadline, f"worker {pid} still runs"
            time.sleep(0.05)
