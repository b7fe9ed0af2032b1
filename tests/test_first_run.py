"""A fresh install's first run compiles only what its method and model call (issue 39): a fixed-step run of a
model without constraint rows, jumps or contacts takes the integrator's free variant (andyc_numerics'
integrator.advance with full=None and free=True, andyc.runtime.compiled.free_run), which Numba compiles without the
constrained solves, projection, event location, jumps, the contact solver and time-stepping. Asserted by what
Numba compiled (or loaded from its cache) in a fresh process, not by time."""

import json
import subprocess
import sys
from types import SimpleNamespace

from andyc.runtime.compiled import free_run, variant
from andyc.runtime.options import Projection
from tests.support import MODELS, ROOT

# In a child process: whatever this test session compiled before, a run's own process starts with no
# signature in any dispatcher, and a function gets one only when something compiles it or loads it from the cache.
PROBE = """
import json, sys
import andyc
from numba.core.dispatcher import Dispatcher

model, _ = andyc.compile_model(sys.argv[1], sys.argv[2], integrator=False)     # (as `andyc sim` does)
run = andyc.simulate(model, t_end=0.01, dt=1e-3)
numerics = model.numerics
loaded = {name: module for name, module in sys.modules.items() if name.startswith(numerics.__name__ + ".")}
compiled = sorted(f"{name.rpartition('.')[2]}.{key}" for name, module in loaded.items()
                  for key, value in vars(module).items() if isinstance(value, Dispatcher) and value.signatures)
print(json.dumps({"compiled": compiled, "advance": [[str(a) for a in s[-4:]] for s in numerics.integrator.advance.signatures],
                  "rows": [[str(a) for a in s[-4:]] for s in numerics.integrator.evaluate_rows.signatures],
                  "power": dict(zip(run.work_names, run.power[-1].tolist())), "state": run.state[-1].tolist(),
                  "status": run.status}))
"""

NEVER = ("dynamics.rhs_mode_into", "dynamics.multipliers", "dynamics.project", "dynamics.jump", "dynamics.impact",
         "dynamics.slip_direction", "integrator.locate", "integrator.instant", "linalg.solve_gram",
         "sparse_rows.solve_gram_sparse", "slipping.solve_slipping")


def run_probe(build, model: str, method: str = "rk4") -> dict:
    """What a run of `model` by `method` compiled or loaded, in a fresh process (PROBE); the run finished."""
    out = subprocess.run([sys.executable, "-c", PROBE.replace("dt=1e-3)", f"dt=1e-3, method={method!r})"),
                          str(MODELS / f"{model}.yaml"), str(build)], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    probe = json.loads(out.stdout.strip().splitlines()[-1])
    assert probe["status"] == "finished"
    return probe


def test_a_run_without_contacts_compiles_neither_the_constrained_solves_nor_the_contact_solver(shipped_build):
    probe = run_probe(shipped_build, "double_pendulum")
    # the free variant only (full, events, free, quiet = None, None, True, omitted), not the full one (full: True)
    assert probe["advance"] == [["none", "none", "bool", "omitted(default=None)"]]
    # (a function compiled as another's callee, or loaded with it from the cache, has no signature of its own; the
    # full advance would be one of those callers: hence the check of advance's own signatures above)
    assert not [name for name in probe["compiled"] if name in NEVER or name.split(".")[0] in
                ("contact_solver", "timestepping")], probe["compiled"]


def test_a_free_run_with_work_slots_evaluates_their_powers_on_the_free_right_hand_side(shipped_build):
    """The shaken pendulum (a damper's and the shaker's work slots, no rows, jumps or contacts) by rk4: its loop is
    the free variant, and so is the evaluation of the logged powers (evaluate_rows with free=True), which before
    compiled the constrained right-hand side (the rows' solves) for them alone. The hinge damper's power is
    -c th'^2 at the last sample (c = 0.1 in the model file), from the run's own state."""
    probe = run_probe(shipped_build, "shaken_pendulum")         # (its own method is projection: rk4 asked for)
    assert probe["advance"] == [["none", "none", "bool", "omitted(default=None)"]]
    # (full, free = None, True: not the full evaluation; slips, quiet as they come)
    assert probe["rows"] == [["none", "bool", "omitted(default=True)", "omitted(default=None)"]]
    th_dot = probe["state"][1]
    assert abs(th_dot) > 0.01
    assert abs(probe["power"]["hinge"] - -0.1 * th_dot ** 2) <= 1e-12 * th_dot ** 2, probe["power"]
    assert not [name for name in probe["compiled"] if name in NEVER], probe["compiled"]


def test_a_constrained_run_without_jumps_compiles_no_event_location_nor_jumps(shipped_build):
    """The slider-crank (constraint rows, no jumps) with projection: the full loop with events=None and quiet=True,
    so neither the guards' location, nor the jumps, nor the spatial slip's direction, nor the contact solver, nor
    the slipping contacts' solve are compiled; its multipliers and residuals are evaluated likewise."""
    probe = run_probe(shipped_build, "slider_crank", "projection")
    assert probe["advance"] == [["bool", "none", "none", "bool"]]           # (full, events, free, quiet)
    assert probe["rows"] == [["bool", "none", "none", "bool"]]              # (full, free, slips, quiet)
    skipped = ("dynamics.jump", "dynamics.impact", "dynamics.slip_direction", "integrator.locate", "integrator.instant",
               "slipping.solve_slipping", "slipping.slip_rows")
    assert not [name for name in probe["compiled"] if name in skipped or name.split(".")[0] in
                ("contact_solver", "timestepping")], probe["compiled"]


def test_which_runs_take_the_free_variant():
    free = SimpleNamespace(nc=0, nj=0, contact_names=(), quaternions=())
    assert free_run(free, "rk4", Projection())
    assert free_run(free, "lagrange", Projection())             # (no rows: every mode computes the same)
    assert not free_run(free, "RK45", Projection())            # (adaptive: not advance)
    assert not free_run(free, "moreau", Projection())
    assert not free_run(free, "projection", Projection(energy_correction=True))     # projects
    assert not free_run(SimpleNamespace(nc=0, nj=0, contact_names=(), quaternions=(3,)), "rk4", Projection())
    assert free_run(SimpleNamespace(nc=0, nj=0, contact_names=(), quaternions=(3,)), "rk4",
                    Projection(normalize=False))
    assert not free_run(SimpleNamespace(nc=1, nj=0, contact_names=(), quaternions=()), "rk4", Projection())
    assert not free_run(SimpleNamespace(nc=0, nj=1, contact_names=(), quaternions=()), "rk4", Projection())


def test_which_loop_each_run_takes():
    """advance's trailing arguments: the free variant, the full loop without events (no jumps), the full loop."""
    free = SimpleNamespace(nc=0, nj=0, contact_names=(), quaternions=())
    rows = SimpleNamespace(nc=2, nj=0, contact_names=(), quaternions=())
    jumps = SimpleNamespace(nc=2, nj=1, contact_names=(), quaternions=())
    assert variant(free, "rk4", Projection()) == (None, None, True)
    assert variant(free, "rk4", Projection(energy_correction=True)) == (True, None, None, True)    # projects: not free
    assert variant(rows, "projection", Projection()) == (True, None, None, True)
    assert variant(jumps, "rk4", Projection()) == ()
    assert variant(SimpleNamespace(nc=0, nj=3, contact_names=("foot",), quaternions=()), "rk4", Projection()) == ()


BUILD_PROBE = """
import json, sys
from andyc.cli import main
from numba.core.dispatcher import Dispatcher

try:
    main(["build", sys.argv[1], "--build-dir", sys.argv[2], *sys.argv[3:]], standalone_mode=False)
except SystemExit as exc:
    assert not exc.code, exc.code
numerics = sys.modules[next(n for n in sys.modules if n.startswith("andyc_numerics_") and n.count(".") == 0)]
print(json.dumps({"advance": sorted([str(a) for a in s[-4:-1]] for s in numerics.integrator.advance.signatures)}))
"""


def test_andyc_build_compiles_what_the_models_own_method_calls(shipped_build):
    """`andyc build` of the double pendulum (no simulate: method: rk4) compiles the integrator's free variant alone,
    as its first `andyc sim` would (make demo's build on a fresh install: seconds, not the full loop's minute or
    more); `--method DOP853` no fixed-step loop at all; `--method all` every variant, so that no later run
    compiles."""
    def advance(*options):
        out = subprocess.run([sys.executable, "-c", BUILD_PROBE, str(MODELS / "double_pendulum.yaml"),
                              str(shipped_build), *options], cwd=ROOT, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout.strip().splitlines()[-1])["advance"]

    assert advance() == [["none", "none", "bool"]]
    assert advance("--method", "DOP853") == []                              # (adaptive: SciPy's loop, not advance)
    every = advance("--method", "all")
    assert ["none", "none", "bool"] in every and len(every) >= 2


SWEEP_PROBE = """
import json, sys
from andyc.cli import main

try:
    main(["sweep", sys.argv[1], "--build-dir", sys.argv[2], "-o", sys.argv[3], "--t-end", "0.01", *sys.argv[4:]],
         standalone_mode=False)
    refused = None
except Exception as exc:            # (click's standalone_mode=False: the refusal is raised, not printed)
    refused = str(exc)
numerics = sys.modules[next(n for n in sys.modules if n.startswith("andyc_numerics_") and n.count(".") == 0)]
print(json.dumps({"refused": refused,
                  "advance": sorted([str(a) for a in s[-4:-1]] for s in numerics.integrator.advance.signatures)}))
"""


def test_andyc_sweep_checks_its_names_before_compiling_and_compiles_its_method_alone(shipped_build, tmp_path):
    """A sweep of an unknown name is refused before any of the integrator is compiled or loaded (a typo on a fresh
    install answered at once, not after the compile of every method's loop); a sweep of the double pendulum
    (rk4) compiles the loop its points run, the free variant, and no other."""
    def sweep(*grid):
        out = subprocess.run([sys.executable, "-c", SWEEP_PROBE, str(MODELS / "double_pendulum.yaml"),
                              str(shipped_build), str(tmp_path / "store.zarr"), *grid], cwd=ROOT,
                             capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        return json.loads(out.stdout.strip().splitlines()[-1])

    typo = sweep("--grid", "mass=1:2:2")
    assert "unknown name 'mass'" in typo["refused"]
    assert typo["advance"] == []
    swept = sweep("--grid", "m1=1:2:2")
    assert swept["refused"] is None
    assert swept["advance"] == [["none", "none", "bool"]]
    assert (tmp_path / "store.zarr").is_dir()


def test_andyc_cycle_checks_its_section_before_compiling_anything(shipped_build):
    """`andyc cycle` of a jump the model does not have is refused before any of the integrator is compiled or
    loaded; its runs (rk4) compile what they call when they start, not every method's loop up front."""
    probe = SWEEP_PROBE.replace('"sweep", sys.argv[1], "--build-dir", sys.argv[2], "-o", sys.argv[3], "--t-end", "0.01"',
                                '"cycle", sys.argv[1], "--build-dir", sys.argv[2]')
    out = subprocess.run([sys.executable, "-c", probe, str(MODELS / "compass_gait.yaml"), str(shipped_build), "-",
                          "--section", "no_such_jump"], cwd=ROOT, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout.strip().splitlines()[-1])
    assert "no jump 'no_such_jump'" in result["refused"]
    assert result["advance"] == []
