"""The generated module stands alone (issue 19): imported by its plain name from its folder, with andyc
not importable, after andyc has built and run it, it reuses what andyc compiled, and it is the same
model: its input expressions are in it, so scipy's solve_ivp on its rhs follows andyc's run."""

import json

import numpy as np

import andyc
from tests.support.cli import run_python

CART = """\
name: forced_cart
description: A cart on a spring, pushed by an input the model drives by an expression of t and the state.
parameters: {m: 2.0, k: 3.0, F0: 1.5, w: 2.0}
inputs: {F: "F0*sin(w*t) - k*x"}
coordinates:
  x: {initial: 0.1}
frames:
  - {name: cart, parent: world, prismatic: x, axis: x}
bodies:
  - {name: body, frame: cart, mass: m}
forces:
  - {name: push, frame: cart, vector: [F, 0, 0]}
"""

STANDALONE = """\
import json, sys
sys.modules["andyc"] = None                   # andyc cannot be imported here
import forced_cart as m
from scipy.integrate import solve_ivp
grid = [0.01 * i for i in range(201)]
sol = solve_ivp(m.rhs, (0.0, 2.0), m.initial_state(), method="DOP853", t_eval=grid, rtol=1e-12, atol=1e-12,
                args=(m.INPUT_DEFAULTS, m.PARAMETER_DEFAULTS))
print(json.dumps({"y": sol.y.T.tolist(), "a0": float(m.rhs(0.0, m.initial_state())[1])}))
"""


def test_the_module_imports_by_its_name_reuses_the_cache_and_carries_its_input_expressions(tmp_path):
    path = tmp_path / "forced_cart.yaml"
    path.write_text(CART)
    model, result = andyc.compile_model(path, tmp_path / "build")
    run = andyc.simulate(model, 2.0, dt=0.01, method="DOP853", rtol=1e-12, atol=1e-12)
    assert run.finished
    folder = result.module_path.parent
    cache = folder / "__pycache__"
    before = {p.name: p.stat().st_mtime_ns for p in cache.iterdir()}
    proc = run_python(STANDALONE, cwd=folder)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    # The input at x = 0.1, t = 0 is -k x = -0.3 N, so the acceleration is -0.15 m/s^2 (not 0).
    assert abs(out["a0"] + 0.15) < 1e-15
    assert np.max(np.abs(np.array(out["y"]) - run.state)) < 1e-10
    after = {p.name: p.stat().st_mtime_ns for p in cache.iterdir()}
    assert after == before                    # nothing compiled again: Numba loaded andyc's cache


def test_a_build_missing_its_numerics_fails_to_import_and_leaves_no_half_made_module(compiled, tmp_path):
    """A copy of the module without its andyc_numerics folder: the import fails, and, as with Python's own
    imports, no partly executed module stays in sys.modules to poison the next import of that name."""
    built = compiled("double_pendulum").path.parent
    copy = tmp_path / "double_pendulum"
    copy.mkdir()
    for name in ("double_pendulum.py", "double_pendulum_equations.py"):
        (copy / name).write_bytes((built / name).read_bytes())
    script = ("import json, sys\nsys.modules['andyc'] = None\ntry:\n    import double_pendulum\n"
              "except Exception as exc:\n    failed = type(exc).__name__\nelse:\n    failed = None\n"
              "print(json.dumps({'failed': failed, 'left': [m for m in sys.modules if 'andyc_numerics' in m]}))\n")
    out = run_python(script, cwd=copy)
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["failed"] is not None and result["left"] == []
