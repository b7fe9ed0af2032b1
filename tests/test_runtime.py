"""Runtime: run files, stops that keep data, scipy methods, rebuild skipping, the bare module."""

import os
import textwrap

import h5py
import numpy as np
import pytest

import andyc
from andyc.runtime.runfiles import read_h5
from tests.support import MODELS
from tests.support.cli import andyc_cli, run_python


def test_double_pendulum_matches_closed_form_M_and_G(compiled):
    """Relative angle q2: M = [[(m1+m2)L1^2 + m2 L2^2 + 2 m2 L1 L2 c2, m2 L2^2 + m2 L1 L2 c2],
    [., m2 L2^2]]; G from Lagrange's equations, evaluated at non-default parameters."""
    model = compiled("double_pendulum")
    L1, L2, m1, m2, g = 1.3, 0.7, 2.0, 0.6, 9.5
    p = model.parameters({"L1": L1, "L2": L2, "m1": m1, "m2": m2, "g": g})
    rng = np.random.default_rng(1)
    for _ in range(10):
        q1, q2, w1, w2 = rng.uniform(-3, 3, 4)
        c2, s2 = np.cos(q2), np.sin(q2)
        M = np.array([[(m1 + m2) * L1**2 + m2 * L2**2 + 2 * m2 * L1 * L2 * c2, m2 * L2**2 + m2 * L1 * L2 * c2],
                      [m2 * L2**2 + m2 * L1 * L2 * c2, m2 * L2**2]])
        G = np.array([m2 * L1 * L2 * s2 * (2 * w1 * w2 + w2**2)
                      - (m1 + m2) * g * L1 * np.sin(q1) - m2 * g * L2 * np.sin(q1 + q2),
                      -m2 * L1 * L2 * s2 * w1**2 - m2 * g * L2 * np.sin(q1 + q2)])
        x = np.array([q1, q2, w1, w2])
        assert np.allclose(model.module.mass_matrix(0.0, x, model.input_defaults, p), M, rtol=1e-12, atol=1e-12)
        assert np.allclose(model.module.generalized_force(0.0, x, model.input_defaults, p), G, rtol=1e-12, atol=1e-12)


def test_run_files_follow_the_design_layout(compiled, tmp_path):
    model = compiled("double_pendulum")
    run = andyc.simulate(model, 1.0, dt=1e-3, every=10, frames="all")
    run.save(tmp_path / "run.h5")
    run.save(tmp_path / "run.csv")
    with h5py.File(tmp_path / "run.h5") as f:
        n = f["time"].shape[0]
        assert n == 101
        assert f["state"].shape == (n, 4)
        assert list(f["state"].attrs["names"]) == ["q1", "q2", "q1_dot", "q2_dot"]
        assert f["flow"].shape == (n,)
        assert f["multipliers"].shape == (n, 0)
        assert f["residual/position"].shape == (n, 0) and f["residual/velocity"].shape == (n, 0)
        assert f["energy"].shape == (n,)
        assert set(f["frames"]) == {"upper", "elbow", "lower", "tip"}
        assert f["frames/tip"].shape == (n, 3)
        assert f["events"].dtype.names == ("time", "jump", "from_flow", "to_flow")
        for key in ("model", "spec_sha256", "andyc_version", "method", "dt", "rtol", "atol",
                    "parameters", "t_end", "status"):
            assert key in f.attrs
        assert f.attrs["status"] == "finished"
    back = read_h5(tmp_path / "run.h5")
    assert np.array_equal(back.state, run.state)
    lines = (tmp_path / "run.csv").read_text().splitlines()
    meta = [ln for ln in lines if ln.startswith("#")]
    assert any(ln.startswith("# spec_sha256: ") for ln in meta)
    header = lines[len(meta)].split(",")
    assert header[:6] == ["time", "q1", "q2", "q1_dot", "q2_dot", "flow"]
    data = np.loadtxt(tmp_path / "run.csv", delimiter=",", skiprows=len(meta) + 1)
    assert np.array_equal(data[:, 1:5], run.state)   # %.17g round-trips exactly
    assert np.array_equal(data[:, header.index("tip.y")], run.frames["tip"][:, 1])


STIFF = textwrap.dedent("""\
    name: stiff_slider
    parameters: {k: 1e6, m: 1.0}     # YAML 1.2 style float (PyYAML alone reads a string)
    coordinates:
      s: {initial: 0.01}
    frames:
      - {name: cart, parent: world, prismatic: s, axis: x}
    bodies:
      - {name: block, frame: cart, mass: m}
    springs:
      - {name: spring, stiffness: k, length: s}
    """)


def test_blow_up_stops_with_when_and_keeps_the_samples(tmp_path, build_dir):
    path = tmp_path / "stiff.yaml"
    path.write_text(STIFF)
    model = andyc.compile_model(path, build_dir)[0]
    # omega = 1000 rad/s: RK4 at h = 5e-3 has h*omega = 5 > 2.83, far past its stability limit.
    run = andyc.simulate(model, 10.0, dt=5e-3)
    assert run.status.startswith("stopped: the state became non-finite")
    assert " at t = " in run.status
    assert run.time[-1] < 10.0 and len(run.time) > 10
    assert np.all(np.isfinite(run.state))
    run.save(tmp_path / "blown.h5")
    assert read_h5(tmp_path / "blown.h5").status == run.status
    # The CLI says so, keeps the file and exits 1.
    out = tmp_path / "cli.h5"
    proc = andyc_cli("sim", path, "--dt", "5e-3", "--t-end", "10", "--out", out, "--build-dir", build_dir)
    assert proc.returncode == 1
    assert "stopped: the state became non-finite" in proc.stderr and "Traceback" not in proc.stderr
    assert out.exists()


@pytest.mark.parametrize("method", ["DOP853", "Radau", "LSODA"])
def test_scipy_methods_agree_with_rk4(compiled, method):
    model = compiled("double_pendulum")
    reference = andyc.simulate(model, 2.0, dt=1e-4, every=100)
    run = andyc.simulate(model, 2.0, dt=1e-2, method=method, rtol=1e-11, atol=1e-12)
    assert run.finished and run.stats["rhs_evaluations"] > 0
    assert np.allclose(run.time, reference.time)
    assert np.max(abs(run.state - reference.state)) < 1e-6


@pytest.mark.parametrize("t_end, dt", [(0.3, 0.1), (0.7, 0.1), (1.0, 0.3)])
def test_the_adaptive_methods_last_sample_is_at_t_end(compiled, t_end, dt):
    """3 * 0.1 is 0.30000000000000004 > 0.3: the grid's last point must still be logged, at t_end."""
    run = andyc.simulate(compiled("double_pendulum"), t_end, dt=dt, method="DOP853")
    assert run.finished and run.time[-1] == t_end
    expected = [k * dt for k in range(int(t_end / dt + 1e-9) + 1)]
    assert np.allclose(run.time[:len(expected)], expected, rtol=0, atol=1e-15)
    assert len(run.time) == len(expected) + (expected[-1] < t_end - 1e-12)


def test_rebuild_is_skipped_when_the_spec_is_unchanged(tmp_path):
    path = tmp_path / "pendulum.yaml"
    path.write_text((MODELS / "pendulum_a01.yaml").read_text())
    first = andyc.build(path, tmp_path / "build")
    second = andyc.build(path, tmp_path / "build")
    assert not first.skipped and second.skipped
    path.write_text(path.read_text().replace("translation: [L, 0, 0]", "translation: [2*L, 0, 0]"))
    third = andyc.build(path, tmp_path / "build")
    assert not third.skipped and third.build_key != first.build_key


def test_generated_module_runs_without_andyc_or_numba(compiled):
    """The module imports only numpy and math (numba optional): block numba and andyc."""
    model = compiled("double_pendulum")
    source = model.path.read_text()
    assert "andyc" not in [line.split()[1] for line in source.splitlines() if line.startswith(("import ", "from "))]
    script = textwrap.dedent(f"""
        import sys, importlib.util
        sys.modules['numba'] = None      # import numba -> ImportError
        sys.modules['andyc'] = None
        spec = importlib.util.spec_from_file_location('dp', {str(model.path)!r})
        dp = importlib.util.module_from_spec(spec); spec.loader.exec_module(dp)
        from scipy.integrate import solve_ivp
        assert dp.NUMBA is False
        sol = solve_ivp(dp.rhs, (0, 1), dp.initial_state(), rtol=1e-11, atol=1e-12,
                        args=(dp.INPUT_DEFAULTS, dp.PARAMETER_DEFAULTS))
        print(*sol.y[:, -1])
        """)
    proc = run_python(script)
    assert proc.returncode == 0, proc.stderr
    x_end = np.array(proc.stdout.split(), dtype=float)
    reference = andyc.simulate(model, 1.0, dt=1e-4)
    assert np.max(abs(x_end - reference.state[-1])) < 1e-7


def test_parameters_and_inputs_are_checked(compiled):
    model = compiled("double_pendulum")
    with pytest.raises(andyc.errors.SimulationError, match="unknown parameter 'L3'.*L1, L2"):
        andyc.simulate(model, 1.0, parameters={"L3": 1.0})
    with pytest.raises(andyc.errors.SimulationError, match="unknown method"):
        andyc.simulate(model, 1.0, method="euler")
    with pytest.raises(andyc.errors.SimulationError, match="not a whole number of steps"):
        andyc.simulate(model, 1.0005, dt=1e-3)


def test_options_are_small_objects_passed_one_way(compiled):
    """simulate's grouped options: andyc.Events, andyc.Init, andyc.Projection; a bare value where an object belongs
    says which, an unknown init mode is refused when the object is made, and the old keywords are gone."""
    model = compiled("double_pendulum")
    assert andyc.Init() == andyc.Init(mode="check", tol=1e-6)
    with pytest.raises(andyc.errors.SimulationError, match="unknown init 'maybe'; use one of: check, project, as-is"):
        andyc.Init("maybe")
    with pytest.raises(TypeError, match=r"init is an andyc\.Init"):
        andyc.simulate(model, 0.01, init="as-is")
    with pytest.raises(TypeError, match="unexpected keyword argument 'event_tol'"):
        andyc.simulate(model, 0.01, event_tol=1e-10)
    with pytest.raises(andyc.errors.SimulationError, match="energy correction needs the projection method"):
        andyc.simulate(model, 0.01, projection=andyc.Projection(energy_correction=True))
    run = andyc.simulate(model, 0.01, method="projection", progress=False, events=andyc.Events(tol=1e-10),
                         projection=andyc.Projection(normalize=False))
    assert run.finished and not run.energy_correction


def test_the_adaptive_methods_locate_with_the_compiled_illinois(compiled):
    """The adaptive driver's root finder is the integrator's illinois_trial and illinois_bracket, called from
    Python: the near end of a bracket no wider than the tolerance, on the side where g keeps its start's sign."""
    from andyc.runtime.adaptive import illinois

    model = compiled("bouncing_ball")

    def g(t):
        return np.cos(t) - 0.5                  # root pi / 3

    a = illinois(model, g, 0.0, 2.0, g(0.0), g(2.0), 1e-12)
    assert g(a) > 0 and np.pi / 3 - 1e-12 <= a <= np.pi / 3


def test_progress_reports_after_the_first_second_at_most_once_a_second(monkeypatch, capsys):
    from andyc.runtime import progress as progress_module

    clock = iter([0.0, 0.5, 1.2, 1.7, 2.4, 2.5])       # perf_counter readings
    monkeypatch.setattr(progress_module.time, "perf_counter", lambda: next(clock))
    bar = progress_module.Progress("model rk4", 10.0, enabled=True)   # reads 0.0
    for t in (1.0, 2.0, 3.0, 4.0, 5.0):                 # reads 0.5, 1.2, 1.7, 2.4, 2.5
        bar(t)
    lines = [ln for ln in capsys.readouterr().err.replace("\r", "\n").splitlines() if ln]
    assert lines == ["model rk4: t = 2 / 10 s (20%), 1 s elapsed, about 5 s left",      # (1.2 s for 2: 4.8 s for 8)
                     "model rk4: t = 4 / 10 s (40%), 2 s elapsed, about 4 s left"]      # (2.4 s for 4: 3.6 s for 6)


def test_progress_of_counted_work_shows_its_last_count_once_a_line_is_up(monkeypatch, capsys):
    """The command line's long work (an animation's frames) through the same printer: done of total, the
    total given with each report; the last count is shown even within the second, but only after a line."""
    from andyc.runtime import progress as progress_module

    clock = iter([0.0, 0.5, 0.9, 0.0, 1.5, 1.8])       # perf_counter readings
    monkeypatch.setattr(progress_module.time, "perf_counter", lambda: next(clock))
    quick = progress_module.Progress("quick", unit="frames", enabled=True)      # reads 0.0
    quick(1, 2)                                         # reads 0.5: too early
    quick(2, 2)                                         # reads 0.9: the last, but no line is up
    slow = progress_module.Progress("slow", unit="frames", enabled=True)        # reads 0.0
    slow(1, 2)                                          # reads 1.5
    slow(2, 2)                                          # reads 1.8: within the second, but the last
    lines = [ln for ln in capsys.readouterr().err.replace("\r", "\n").splitlines() if ln]
    assert lines == ["slow: 1 of 2 frames, 0.667 frames/s, 2 s elapsed, about 2 s left",   # (1 in 1.5 s)
                     "slow: 2 of 2 frames, 1.11 frames/s, 2 s elapsed"]                   # (2 in 1.8 s; no time left)


def test_generated_code_does_not_depend_on_the_hash_seed(tmp_path):
    """Same spec, same andyc -> the same module text, whatever PYTHONHASHSEED is."""
    texts = []
    for seed in ("1", "2"):
        out = tmp_path / seed
        env = {**os.environ, "PYTHONHASHSEED": seed}
        # andyc.build derives and generates (the CLI's build compiles too, which this test does not need).
        proc = run_python("import sys, andyc; andyc.build(sys.argv[1], sys.argv[2])", MODELS / "chain3d.yaml", out,
                          env=env)
        assert proc.returncode == 0, proc.stderr
        texts.append([(out / "chain3d" / name).read_text() for name in ("chain3d.py", "chain3d_equations.py")])
    assert texts[0] == texts[1]
