"""Inputs a run drives (issue 8): expressions in the model and on the command line, tables,
controllers (the cart-pole balanced by LQR), and the messages when they go wrong."""

import textwrap

import h5py
import numpy as np
import pytest

import andyc
from andyc.errors import SimulationError
from andyc.runtime.controller import InputWarning
from tests.support import MODELS
from tests.support.cli import andyc_cli, run_python

# A mass on a spring-less rail pushed by an input F; the model drives F by an
# expression of t and x (a sinusoidal force plus a spring written as an input):
#     m x'' = F0 sin(w t) - k x,   x(0) = x'(0) = 0.
CART = """\
name: driven_cart
parameters: {m: 2.0, k: 8.0, F0: 1.5, w: 3.0}
inputs:
  F: "F0*sin(w*t) - k*x"
coordinates:
  x: {initial: 0}
frames:
  - {name: cart, parent: world, prismatic: x, axis: x}
bodies:
  - {name: cart_mass, frame: cart, mass: m}
forces:
  - {name: push, frame: cart, vector: [F, 0, 0]}
"""
M, K, F0, W = 2.0, 8.0, 1.5, 3.0


def forced_oscillator(t):
    """x(t) of m x'' + k x = F0 sin(w t) from rest at 0."""
    w0 = np.sqrt(K / M)
    return F0 / M / (w0**2 - W**2) * (np.sin(W * t) - W / w0 * np.sin(w0 * t))


@pytest.fixture(scope="module")
def cart(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cart")
    (folder / "driven_cart.yaml").write_text(CART)
    return andyc.compile_model(folder / "driven_cart.yaml", folder / "build")[0]


def write(path, text):
    path.write_text(textwrap.dedent(text))
    return path


# -- expressions and tables -----------------------------------------------------------------------

def test_an_expression_in_the_model_drives_the_input(cart):
    run = andyc.simulate(cart, 4.0, dt=1e-3, progress=False)
    assert np.max(np.abs(run.column("x") - forced_oscillator(run.time))) < 1e-9
    # the logged input is the expression at each sample
    assert np.allclose(run.input_values[:, 0], F0 * np.sin(W * run.time) - K * run.column("x"), rtol=0, atol=1e-12)
    assert run.inputs == {"F": "expression F0*sin(w*t) - k*x"}


def test_a_command_line_expression_or_number_overrides_the_models(cart):
    # F = -k x alone: a free oscillation from x(0) = 0 stays at rest unless pushed; so push with a
    # constant and a spring: m x'' = 2 - k x gives x = (2/k)(1 - cos(w0 t)).
    run = andyc.simulate(cart, 2.0, dt=1e-3, inputs={"F": "2 - k*x"}, progress=False)
    w0 = np.sqrt(K / M)
    assert np.max(np.abs(run.column("x") - 2 / K * (1 - np.cos(w0 * run.time)))) < 1e-9
    held = andyc.simulate(cart, 1.0, dt=1e-3, inputs={"F": 4.0}, progress=False)
    assert np.max(np.abs(held.column("x") - 4.0 / M * held.time**2 / 2)) < 1e-12
    assert np.all(held.input_values == 4.0)


def test_a_table_is_interpolated_linearly(cart, tmp_path):
    # F rises linearly by 0.5 N/s: the table's two rows give it exactly, so x = 0.5 t^3 / (6 m),
    # which RK4 integrates without error; rows between lie on the line, rows past the end are unused.
    table = write(tmp_path / "ramp.csv", """\
        # a ramp, 0.5 N/s
        time,F
        0,0
        1.5,0.75
        4,2.0
        """)
    run = andyc.simulate(cart, 3.0, dt=1e-3, inputs={"F": str(table)}, progress=False)
    assert np.max(np.abs(run.column("x") - 0.5 * run.time**3 / (6 * M))) < 1e-12
    assert np.allclose(run.input_values[:, 0], 0.5 * run.time, rtol=0, atol=1e-14)


@pytest.mark.parametrize("rows, line, message", [
    ("t,F\n0,0\n1,2\n2,\n3,1\n", 4, "column 'F' is empty: a gap in the table"),
    ("t,F\n0,0\n1,nan\n3,1\n", 3, "column 'F' is 'nan', not a finite number: a gap in the table"),
    ("t,F\n0,0\n2,1\n1,3\n4,0\n", 4, "time 1 does not increase (the row before has 2)"),
    ("t,G,H\n0,0,0\n4,1,1\n", 1, "no column 'F' among G, H"),
    ("F\n0\n1\n", 1, "no time column in the header F"),
])
def test_a_bad_table_stops_before_the_run_naming_file_and_line(cart, tmp_path, rows, line, message):
    table = tmp_path / "push.csv"
    table.write_text(rows)
    with pytest.raises(SimulationError) as err:
        andyc.simulate(cart, 3.0, inputs={"F": str(table)}, progress=False)
    assert str(err.value).startswith(f"{table}:{line}: ") and message in str(err.value)


def test_a_table_that_ends_before_the_run_says_so(cart, tmp_path):
    table = tmp_path / "short.csv"
    table.write_text("t,F\n0,0\n2,1\n")
    with pytest.raises(SimulationError, match=r"covers t = 0 \.\. 2 s but the run needs 0 \.\. 3 s"):
        andyc.simulate(cart, 3.0, inputs={"F": str(table)}, progress=False)


def test_an_expression_with_an_unknown_name_is_refused(cart):
    with pytest.raises(SimulationError, match=r"input F: in 'x \+ y': unknown name 'y'.*names allowed here: .*x_dot"):
        andyc.simulate(cart, 1.0, inputs={"F": "x + y"}, progress=False)


# -- controllers ----------------------------------------------------------------------------------

def test_lqr_from_andyc_linearize_balances_the_cart_pole(tmp_path):
    """Issue 8, item 1: the controller's A and B are those `andyc linearize` writes; through
    --controller the pole stays within 1e-3 rad of upright after 5 s from 0.1 rad, and without
    it the pole falls."""
    lin = andyc_cli("linearize", MODELS / "cart_pole.yaml", "--at", "th=0", "-o", tmp_path)
    assert lin.returncode == 0, lin.stderr
    written = np.load(tmp_path / "cart_pole_linearization.npz")
    controller = MODELS / "cart_pole_lqr.py"
    namespace = {"__file__": str(controller)}
    exec(compile(controller.read_text(), str(controller), "exec"), namespace)
    assert np.array_equal(namespace["LINEAR"].A, written["A"]) and np.array_equal(namespace["LINEAR"].B, written["B"])
    closed = np.linalg.eigvals(written["A"] - written["B"] @ namespace["K"][None, :])
    assert np.all(closed.real < 0)

    out = tmp_path / "balanced.h5"
    sim = andyc_cli("sim", MODELS / "cart_pole.yaml", "--controller", controller, "--t-end", 10, "--out", out,
                    "--build-dir", tmp_path / "build")
    assert sim.returncode == 0, sim.stderr
    with h5py.File(out) as f:
        t, names = f["time"][()], list(f["state"].attrs["names"])
        th = f["state"][:, names.index("th")]
        force = f["inputs"][:, 0]
    assert th[0] == pytest.approx(0.1)
    assert np.max(np.abs(th[t >= 5.0])) < 1e-3
    assert force[0] == pytest.approx(-namespace["K"] @ np.array([0, 0.1, 0, 0]))

    falls = andyc_cli("sim", MODELS / "cart_pole.yaml", "--t-end", 3, "--out", tmp_path / "falls.h5",
                      "--build-dir", tmp_path / "build")
    assert falls.returncode == 0, falls.stderr
    with h5py.File(tmp_path / "falls.h5") as f:
        assert np.max(np.abs(f["state"][:, 1])) > 1.0


def test_a_controller_agrees_between_rk4_and_dop853(compiled):
    ctrl = MODELS / "cart_pole_lqr.py"
    model = compiled("cart_pole")
    a = andyc.simulate(model, 2.0, dt=1e-3, controller=ctrl, every=100, progress=False)
    b = andyc.simulate(model, 2.0, dt=0.1, method="DOP853", rtol=1e-12, atol=1e-12, controller=ctrl, progress=False)
    assert np.max(np.abs(a.state - b.state)) < 1e-9
    assert np.max(np.abs(a.input_values - b.input_values)) < 1e-8


def test_a_controller_that_raises_stops_the_run_naming_its_line(compiled, tmp_path):
    ctrl = write(tmp_path / "raises.py", """\
        import numpy as np


        def control(t, x, d, p):
            if t > 0.5:
                raise ValueError("gain table exhausted")
            return -10.0 * x[1]
        """)
    run = andyc.simulate(compiled("cart_pole"), 2.0, dt=1e-3, controller=ctrl, progress=False)
    assert run.status.startswith(f"stopped: {ctrl}:6: control raised ValueError: gain table exhausted at t = 0.50")
    assert "the 501 samples before it are kept" in run.status
    assert run.time[-1] == pytest.approx(0.5) and run.time.shape == (501,)


def test_a_controller_that_raises_at_the_start_is_refused(compiled, tmp_path):
    ctrl = write(tmp_path / "typo.py", """\
        def control(t, x, d, p):
            return -10.0 * x[7]
        """)
    with pytest.raises(SimulationError, match=rf"^{ctrl}:2: control raised IndexError: .* at t = 0"):
        andyc.simulate(compiled("cart_pole"), 1.0, controller=ctrl, progress=False)


def test_a_controller_returning_the_wrong_shape_names_the_return_line(compiled, tmp_path):
    ctrl = write(tmp_path / "shape.py", """\
        import numpy as np


        def control(t, x, d, p):
            if t < 1.0:
                return np.array([0.0])
            return np.array([0.0, 1.0])
        """)
    run = andyc.simulate(compiled("cart_pole"), 2.0, dt=1e-3, controller=ctrl, progress=False)
    assert run.status.startswith(f"stopped: {ctrl}:7: control returned 2 values at t = 1 s; cart_pole has 1 input "
                                 f"(F): return one number")
    write(ctrl, """\
        def control(t, x, d, p):
            u = [x[0], x[1]]
            return u
        """)
    with pytest.raises(SimulationError, match=rf"^{ctrl}:3: control returned a list of 2 values at t = 0; "):
        andyc.simulate(compiled("cart_pole"), 1.0, controller=ctrl, progress=False)


@pytest.mark.parametrize("text, message", [
    ("def control(t, x):\n    return 0.0\n", ":1: control(t, x) must take four arguments (t, x, d, p)"),
    ("def contrl(t, x, d, p):\n    return 0.0\n", ":1: defines no function control(t, x, d, p)"),
    ("import numpy as np\n\nK = np.load('missing.npy')\n", ":3: importing the controller raised FileNotFoundError"),
])
def test_a_controller_file_that_cannot_be_used_is_refused(compiled, tmp_path, text, message):
    ctrl = tmp_path / "bad.py"
    ctrl.write_text(text)
    with pytest.raises(SimulationError) as err:
        andyc.simulate(compiled("cart_pole"), 1.0, controller=ctrl, progress=False)
    assert str(err.value).startswith(f"{ctrl}{message}")


def test_a_controller_numba_cannot_compile_runs_as_python_with_a_warning(compiled, tmp_path):
    python = write(tmp_path / "python_only.py", """\
        class Gains:
            k = 25.0


        def control(t, x, d, p):
            return {"F": Gains.k * x[1]}["F"]
        """)
    numba = write(tmp_path / "numba_ok.py", """\
        def control(t, x, d, p):
            return 25.0 * x[1]
        """)
    model = compiled("cart_pole")
    with pytest.warns(InputWarning, match=rf"^{python}:6: Numba cannot compile control \(Untyped global name 'Gains'"):
        slow = andyc.simulate(model, 1.0, dt=1e-3, controller=python, progress=False)
    fast = andyc.simulate(model, 1.0, dt=1e-3, controller=numba, progress=False)
    assert slow.finished and np.array_equal(slow.state, fast.state)


def test_cli_input_options(tmp_path, cart):
    table = tmp_path / "gap.csv"
    table.write_text("t,F\n0,0\n1,2\n2,\n3,1\n")
    model = tmp_path / "driven_cart.yaml"
    model.write_text(CART)
    proc = andyc_cli("sim", model, "--t-end", 1, "--input", f"F={table}", "--build-dir", tmp_path / "build")
    assert proc.returncode == 2 and f"{table}:4: column 'F' is empty" in proc.stderr
    assert "Traceback" not in proc.stderr
    csv = tmp_path / "run.csv"
    proc = andyc_cli("sim", model, "--t-end", 1, "--input", "F=2 - k*x", "--out", csv, "--build-dir", tmp_path / "build")
    assert proc.returncode == 0, proc.stderr
    header = next(line for line in csv.read_text().splitlines() if line.startswith("time,"))
    assert header.split(",")[:4] == ["time", "x", "x_dot", "F"]
    proc = andyc_cli("sim", model, "--input", "F", "--build-dir", tmp_path / "build")
    assert proc.returncode == 2 and "'F' is not NAME=VALUE" in proc.stderr


def test_a_command_line_expression_is_generated_into_the_build_and_reused(tmp_path):
    """--input F=EXPR goes through the whitelist parser and the code generator into the build folder, as the
    model's own expressions do (nothing is executed as text); a run with the same drives imports that module
    again, Numba's cache of it included, without SymPy."""
    model = tmp_path / "driven_cart.yaml"
    model.write_text(CART)
    script = ("import sys\nfrom andyc.cli import main\ntry:\n"
              f"    main(['sim', {str(model)!r}, '--build-dir', {str(tmp_path / 'build')!r}, '--t-end', '0.1', "
              "'--input', 'F=2 - k*x', '--out', 'run.csv'])\n"
              "except SystemExit as exc:\n    assert exc.code in (0, None), exc.code\n"
              "print('sympy' in sys.modules)")
    first = run_python(script, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    generated = list((tmp_path / "build" / "driven_cart" / "run_inputs").glob("r_*.py"))
    assert len(generated) == 1
    source = generated[0].read_text()
    assert "u[0] = -p[1]*x[0] + 2" in source and "k*x" not in source      # k is p[1], x is x[0]
    cache = generated[0].parent / "__pycache__"
    stamps = {p.name: p.stat().st_mtime_ns for p in cache.iterdir()}
    assert any(name.endswith(".nbc") for name in stamps)
    again = run_python(script, cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert again.stdout.splitlines()[-1] == "False"                       # no SymPy: the module was found
    assert {p.name: p.stat().st_mtime_ns for p in cache.iterdir()} == stamps   # and nothing compiled again
