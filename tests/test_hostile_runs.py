"""Runs that are interrupted, never return, diverge or race (issue 18).

Each command runs as a user's would, in a subprocess, and each waits for evidence that the run is under
way (a file the controller writes once the integration has started) rather than for a time, so that a
loaded machine changes how long the tests take, never what they see. Timeouts here only detect a hang.
"""

import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

import andyc
from andyc.runtime.run import Run
from andyc.runtime.runfiles import read_h5
from andyc.runtime.status import diverging_constraints
from tests.support import MODELS
from tests.support.processes import STARTED, default_signals, wait_for

HANG = 300          # seconds after which a command counts as hung (a hang detector, not a speed bound)

# Compiled by Numba, and never returns once t > 1 ms (the loop's test reads x, so it cannot be dropped).
ENDLESS = """\
def control(t, x, d, p):
    s = 0.0
    while t > 1e-3 and x[0] == x[0]:
        s += 1.0
    return s
"""


def start(args, cwd):
    return subprocess.Popen([sys.executable, "-m", "andyc.cli", *map(str, args)], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=default_signals)


@pytest.mark.parametrize("sig, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143), (signal.SIGHUP, 129)])
def test_a_signal_stops_the_run_and_keeps_its_samples(tmp_path, shipped_build, sig, code):
    flag, out = tmp_path / "started", tmp_path / "run.h5"
    (tmp_path / "started.py").write_text(STARTED.format(flag=str(flag)))
    proc = start(["sim", MODELS / "cart_pole.yaml", "--t-end", 1e5, "--every", 100, "--controller", "started.py",
                  "--out", out, "--out", tmp_path / "run.csv", "--build-dir", shipped_build], tmp_path)
    wait_for(flag, proc)
    proc.send_signal(sig)
    stdout, stderr = proc.communicate(timeout=HANG)
    assert proc.returncode == code, stderr
    assert "Traceback" not in stderr and f"interrupted: {signal.Signals(sig).name} received" in stderr
    run = read_h5(out)
    assert run.status.startswith(f"interrupted: {signal.Signals(sig).name} received at t = ")
    assert run.time[-1] > 1e-3 and len(run.time) >= 2 and np.all(np.isfinite(run.state))
    assert np.all(np.diff(run.time) > 0)
    assert (tmp_path / "run.csv").read_text().count("\n") == len(run.time) + len(run.attributes()) + 1


def test_a_controller_that_never_returns_is_stopped_by_the_timeout(tmp_path, build_dir):
    out = tmp_path / "run.h5"
    (tmp_path / "endless.py").write_text(ENDLESS)
    proc = start(["sim", MODELS / "cart_pole.yaml", "--t-end", 1, "--controller", "endless.py", "--timeout", 1,
                  "--out", out, "--build-dir", build_dir], tmp_path)
    stdout, stderr = proc.communicate(timeout=HANG)
    assert proc.returncode == 1, stderr
    assert "Traceback" not in stderr and "did not stop" in stderr
    run = read_h5(out)
    assert "wall-clock limit of 1 s" in run.status and "did not return" in run.status
    assert run.time[0] == 0.0 and np.all(np.isfinite(run.state))


def test_sigint_stops_a_run_whose_python_controller_never_returns(tmp_path, build_dir):
    flag, out = tmp_path / "started", tmp_path / "run.h5"
    (tmp_path / "stuck.py").write_text(STUCK.format(flag=str(flag)))
    proc = start(["sim", MODELS / "cart_pole.yaml", "--t-end", 1, "--controller", "stuck.py", "--out", out,
                  "--build-dir", build_dir], tmp_path)
    wait_for(flag, proc)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=HANG)
    assert proc.returncode == 130, stderr
    assert "Traceback" not in stderr and "did not stop" in stderr
    run = read_h5(out)
    assert run.status.startswith("interrupted: SIGINT received") and "did not return" in run.status


# Runs as Python; once past t = 1 ms it says so, then never returns.
STUCK = """\
import os
def control(t, x, d, p):
    if t > 1e-3:
        open({flag!r}, "w").close()
        while True:
            pass
    return 0.0
"""


UNSTABLE = """\
name: unstable
description: Free motion until t = 0.5 s, then a potential that pushes the mass away with stiffness k.
parameters: {{k: {k}}}
coordinates:
  x: {{initial: 0, velocity: 1}}
frames:
  - {{name: slider, parent: world, prismatic: x, axis: x}}
bodies:
  - {{name: mass, frame: slider, mass: 1}}
potentials:
  - {{name: push, energy: "-k*x**2*(1 + sign(t - 0.5))/4"}}
"""


def test_a_diverging_run_stops_at_the_step_that_diverges_and_keeps_the_sound_samples(tmp_path, build_dir):
    path = tmp_path / "unstable.yaml"
    path.write_text(UNSTABLE.format(k=1e10))
    model = andyc.compile_model(path, build_dir)[0]
    run = andyc.simulate(model, 2.0, dt=1e-3)
    assert run.status.startswith("stopped: the solution diverges")
    # h sqrt(k) = 100: RK4 multiplies the state by about 4e5 in the step onto t = 0.5 s and 4e6 in the next.
    assert 0.498 <= run.time[-1] <= 0.502
    assert np.all(np.isfinite(run.state)) and np.abs(run.state).max() < 10.0
    assert np.allclose(run.column("x")[run.time <= 0.5], run.time[run.time <= 0.5], atol=1e-12)
    # A milder instability (h sqrt(k) = 1: a factor 2.7 a step) is followed until the state overflows.
    mild = andyc.simulate(model, 2.0, dt=1e-3, parameters={"k": 1e6})
    assert mild.status.startswith("stopped: the state became non-finite")


def test_near_singular_constraint_rows_are_named_as_the_cause(compiled):
    model = compiled("fourbar")
    p, u, d = model.parameter_defaults, model.input_defaults, model.initial_discrete(model.parameter_defaults)
    hanging = model.initial_state(p)
    assert diverging_constraints(model, 0.0, hanging, u, p, d, 0) == ""
    flat = np.zeros(model.nx)           # every link on the x axis: the closure's rows lose a rank
    why = diverging_constraints(model, 0.0, flat, u, p, d, 0)
    assert "constraint rows (closure) are nearly dependent there" in why


def test_two_concurrent_builds_of_one_model_both_leave_a_whole_module(tmp_path):
    model = tmp_path / "pendulum.yaml"
    model.write_text((MODELS / "double_pendulum.yaml").read_text())
    code = ("import sys, andyc.pipeline as p; p.build(sys.argv[1], sys.argv[2], force=True)")
    procs = [subprocess.Popen([sys.executable, "-c", code, str(model), str(tmp_path / "build")],
                              stderr=subprocess.PIPE, text=True) for _ in range(3)]
    for proc in procs:
        assert proc.wait(timeout=HANG) == 0, proc.stderr.read()
    folder = tmp_path / "build" / "double_pendulum"
    from andyc.runtime.compiled import load_compiled

    module = load_compiled(folder / "double_pendulum.py")
    library = module.module.EQUATIONS.C_LIBRARY        # the leaves in C, where a C compiler made them
    expected = ["double_pendulum.py", "double_pendulum_equations.py"] + (
        [] if library is None else ["double_pendulum_leaves.c", library])
    assert sorted(p.name for p in folder.iterdir() if p.is_file()) == sorted(expected)  # no temporary left
    assert module.nx == 4


def test_an_interrupted_write_leaves_the_old_run_file(tmp_path):
    run = Run(model="m", spec_sha256="0", method="rk4", dt=1e-3, nq=1, nv=1, rtol=0.0, atol=0.0, t_end=1.0,
              parameters={}, inputs={}, state_names=["y", "y_dot"], time=np.linspace(0, 1, 11),
              state=np.ones((11, 2)), energy=np.zeros(11))
    path = run.save(tmp_path / "run.h5")
    before = path.read_bytes()

    class Boom(Exception):
        pass

    broken = andyc.runtime.runfiles
    original = broken.write_h5

    def write_half(r, p):
        with h5py.File(p, "w") as f:
            f["time"] = r.time
        raise Boom

    broken.write_h5 = write_half
    try:
        with pytest.raises(Boom):
            run.save(path)
    finally:
        broken.write_h5 = original
    assert path.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run.h5"]
