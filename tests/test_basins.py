"""andyc cycle --basin (andyc.analysis.basins), issue 22's basins: the compass gait's step-to-step map
(models/compass_gait_step.yaml). The fixed point's own start and a small perturbation reach the cycle, a start
with too little speed falls back; the starting states are checked against the stance foot's velocity
constraint written by hand, and the classes the sweep engine writes (a local Dask cluster, through the
command line) against plain runs of the model, one run per start over all its steps (`--stop-after strike=K`
as a user would run it), classified here from the run's own arrays."""

import math

import numpy as np
import pytest

import andyc
from andyc.analysis.basins import CYCLE, FALLS, OTHER_ORBIT, classify, make_basin, start_state
from andyc.analysis.cycles import find_cycle
from andyc.runtime.sensitivities import load_derivatives
from tests.support import MODELS
from tests.support.cli import invoke

xr = pytest.importorskip("xarray")
pytest.importorskip("dask.distributed")

MODEL = MODELS / "compass_gait_step.yaml"
FALL = "min(y) < 0.5"           # the hip below half the leg length: fallen
T_STEP = 3.0
TOL = 1e-6
STEPS = 50
GRID = ("th1_dot=-1.3:-0.5:3", "th2_dot=-0.7:-0.1:3")


@pytest.fixture(scope="module")
def gait(compiled, shipped_build):
    model = compiled(MODEL)
    andyc.build_derivatives(MODEL, shipped_build)
    cycle = find_cycle(model, "strike")
    assert cycle.converged
    basin = make_basin(model, cycle, steps=STEPS, tol=TOL, t_step=T_STEP, dt=1e-3, event_tol=1e-14, fall=FALL)
    return model, cycle, basin


def held(model):
    return [model.state_names.index("th1_dot"), model.state_names.index("th2_dot")]


def by_hand(model, cycle, th1_dot, th2_dot):
    """The start (x, d) with the leg speeds set, the hip's velocity from the stance foot's constraint written
    here: foot1 = (x + L sin th1, y - L cos th1) at rest, so x_dot = -L cos(th1) th1_dot, y_dot = -L sin(th1)
    th1_dot."""
    s = dict(zip(model.state_names, cycle.state))
    L = cycle.parameters["a"] + cycle.parameters["b"]
    s.update(th1_dot=th1_dot, th2_dot=th2_dot, x_dot=-L * math.cos(s["th1"]) * th1_dot,
             y_dot=-L * math.sin(s["th1"]) * th1_dot)
    return np.array([s[n] for n in model.state_names]), cycle.discrete.copy()


def test_the_fixed_point_and_a_small_perturbation_reach_the_cycle(gait):
    model, cycle, basin = gait
    x = dict(zip(model.state_names, cycle.state))
    own = classify(model, basin, held(model), [x["th1_dot"], x["th2_dot"]])
    assert own["class"] == CYCLE and own["steps"] == 1 and own["distance"] < 1e-9
    near = classify(model, basin, held(model), [x["th1_dot"] + 0.02, x["th2_dot"] - 0.02])
    assert near["class"] == CYCLE and near["steps"] > 5 and near["distance"] <= TOL
    assert near["message"] == f"step {near['steps']}: within {TOL:g} of the cycle"


def test_too_little_speed_falls_back(gait):
    model, cycle, basin = gait
    x = dict(zip(model.state_names, cycle.state))
    slow = classify(model, basin, held(model), [-0.3, x["th2_dot"]])
    assert slow["class"] == FALLS and slow["steps"] == 1 and "fall condition" in slow["message"]
    assert slow["run"].state[:, model.state_names.index("y")].min() < 0.5
    # the stance leg swung back: th1 grew (the hip went back up the slope) before it fell
    assert slow["run"].state[-1, model.state_names.index("x")] < x["x"]


def test_past_the_period_doubling_a_start_reaches_the_period_two_gait(compiled):
    """At slope 0.08 rad, past the first period doubling (0.0766 rad, tests/test_continuation.py), the period-1 gait
    is unstable: a start near it ends on another orbit, of period 2: its step times alternate, two distinct ones
    that repeat."""
    model = compiled(MODEL)
    cycle = find_cycle(model, "strike", parameters={"slope": 0.08})
    assert cycle.converged and max(abs(cycle.multipliers)) > 1
    basin = make_basin(model, cycle, steps=100, tol=TOL, t_step=T_STEP, dt=1e-3, event_tol=1e-14, fall=FALL)
    x = dict(zip(model.state_names, cycle.state))
    found = classify(model, basin, held(model), [x["th1_dot"] + 0.01, x["th2_dot"]])
    assert found["class"] == OTHER_ORBIT and found["period"] == 2 and found["distance"] > 100 * TOL
    steps = np.diff(found["times"])[-6:]
    assert np.max(np.abs(steps[2:] - steps[:-2])) < 1e-6 and abs(steps[-1] - steps[-2]) > 1e-3


def test_starting_states_are_on_the_constraint_manifold_with_the_grid_values(gait):
    model, cycle, basin = gait
    derivatives = load_derivatives(model)
    for th1_dot, th2_dot in [(-1.3, -0.7), (-0.5, 0.4), (-2.0, -0.1)]:
        y = start_state(model, derivatives, basin, held(model), [th1_dot, th2_dot])
        x, d = by_hand(model, cycle, th1_dot, th2_dot)
        assert np.max(np.abs(y - np.concatenate([x, d]))) < 1e-12


def test_basin_command_agrees_with_plain_runs(gait, shipped_build, tmp_path):
    """The command runs the grid (on one thread, batched) into a store xarray reads; each start
    is then run by hand: one plain rk4 run over STEPS heel strikes (or until it ends) from the start built by
    hand, classified from its samples: falls if the hip ever drops below 0.5 m before the strike the command
    stopped at, cycle if its last strike is within the tolerance of the fixed point (up to the shift downhill)."""
    model, cycle, basin = gait
    store = tmp_path / "basin.zarr"
    result = invoke("cycle", MODEL, "--section", "strike", "--basin", GRID[0], "--basin", GRID[1], "--fall", FALL,
                    "--t-max", T_STEP, "--steps", STEPS, "--basin-tol", TOL, "--workers", 1, "-o", store,
                    "--build-dir", shipped_build, cwd=tmp_path)
    assert result.exit_code == 0, result.output
    assert store.with_suffix(".png").stat().st_size > 10_000
    ds = xr.open_zarr(store)
    assert ds.basin.dims == ("th1_dot", "th2_dot") and ds.basin.attrs["flag_meanings"].split()[1:4] == [
        "cycle", "other_orbit", "falls"]
    classes = ds.basin.values
    assert {1, 3} <= set(classes.ravel().tolist()), classes      # both reach the cycle and fall in this grid
    keep = [i for i, n in enumerate(model.state_names) if n != "x"]     # the shift downhill: x (and fx) free
    for i, th1_dot in enumerate(ds.th1_dot.values):
        for j, th2_dot in enumerate(ds.th2_dot.values):
            x0, d0 = by_hand(model, cycle, th1_dot, th2_dot)
            n = int(ds.basin_steps.values[i, j])
            run = andyc.simulate(model, T_STEP * STEPS, 1e-3, "rk4", x0=x0, d0=d0, progress=False,
                                 init=andyc.Init("as-is"), events=andyc.Events(stop_after={"strike": n}))
            fell = run.state[:, model.state_names.index("y")].min() < 0.5
            if classes[i, j] == FALLS:
                assert fell, (th1_dot, th2_dot)
            else:
                assert classes[i, j] == CYCLE and not fell and run.events["jump"].size == n
                gap = np.abs(run.state[-1, keep] - cycle.state[keep]).max()
                assert gap < 10 * TOL, (th1_dot, th2_dot, gap)
    assert "classes: cycle " in result.stdout and "wrote " in result.stdout
    drawn = invoke("plot", store, "-o", tmp_path / "again.png")         # andyc plot STORE: the classes by default
    assert drawn.exit_code == 0 and (tmp_path / "again.png").stat().st_size > 10_000, drawn.output


@pytest.mark.parametrize("args, message", [
    (["--basin", "th1_dot=-1:-0.5", "--basin", "th2_dot=0:1:3"], "--basin 'th1_dot=-1:-0.5': not NAME=FROM:TO:COUNT"),
    (["--basin", "th1_dot=-1:-0.5:3"], "--basin: give it twice"),
    (["--basin", "th1_dot=-1:-0.5:3", "--basin", "knee=0:1:3"], "has no state 'knee'"),
    (["--basin", "th1_dot=-1:-0.5:3", "--basin", "th2_dot=0:1:0"], "an empty range"),
    (["--basin", "th1_dot=-1:-0.5:3", "--basin", "th2_dot=0:1:3", "--fall", "min(y)"], "not a comparison"),
])
def test_bad_basin_requests_are_usage_errors(args, message, shipped_build, tmp_path):
    result = invoke("cycle", MODEL, "--section", "strike", *args, "-o", tmp_path / "b.zarr",
                    "--build-dir", shipped_build, cwd=tmp_path)
    assert result.exit_code == 2, result.output
    assert message in result.stderr and len(result.stderr.strip().splitlines()) == 1, result.stderr
    assert not (tmp_path / "b.zarr").exists() and not (tmp_path / "runs").exists()


def test_the_map_draws_each_class_in_its_colour():
    """Each class's cells take that class's colour (the categorical map goes by position in the codes)."""
    from matplotlib.colors import to_rgba

    from andyc.analysis.basins import CLASSES
    from andyc.plot.basinmap import CLASS_COLOURS, basin_figure

    classes = np.array([[1, 3], [2, 4]])
    fig = basin_figure([("a", np.array([0.0, 1.0])), ("b", np.array([0.0, 1.0]))], classes, np.array([[1, 0], [2, 0]]),
                       CLASSES, [(0.0, 0.0)])
    mesh = fig.axes[0].collections[0]
    for code in (1, 2, 3, 4):
        assert np.allclose(mesh.cmap(mesh.norm(code)), to_rgba(CLASS_COLOURS[code]))
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert labels == ["cycle", "orbit of period 2", "falls", "other", "cycle (fixed point)"]


def test_a_start_that_cannot_meet_the_constraints_is_recorded_failed(gait):
    """A hip 1.5 leg lengths up cannot have its stance foot on the ground: the worker records the start as failed,
    class other, with the reason; the batch goes on."""
    from andyc.analysis.sweeps.worker import Settings, empty_results, record
    from andyc.runtime.status import FAILED

    model, cycle, basin = gait
    settings = Settings.of(model, ("y", "th1_dot"), basin.t_step * basin.steps, basin=basin)
    out = empty_results(model, settings, 2)
    record(out, 0, model, [], settings, [1.5, -1.0])
    record(out, 1, model, [], settings, [cycle.state[model.state_names.index("y")], -1.0])
    assert out["outcome"][0] == FAILED and out["basin"][0] == 4
    assert out["message"][0].startswith("cannot put the start on the constraint manifold with y, th1_dot held")
    assert out["outcome"][1] != FAILED and out["basin"][1] in (CYCLE, FALLS)


def _by_engine(model, settings, values, monkeypatch):
    """The rows of worker.empty_results for `values`: by the batched engine (run_basins: each step of every start in
    one compiled call), with the rows it ran alone (record_point), and one by one (record_point)."""
    from andyc.analysis import basins
    from andyc.analysis.basins_batched import run_basins
    from andyc.analysis.sweeps.worker import empty_results

    alone, single = [], basins.record_point

    def counted(out, row, *args):
        alone.append(row)
        single(out, row, *args)
    batched = empty_results(model, settings, len(values))
    monkeypatch.setattr(basins, "record_point", counted)
    run_basins(batched, model, settings, np.asarray(values, float))
    monkeypatch.undo()
    one = empty_results(model, settings, len(values))
    for row, point in enumerate(values):
        single(one, row, model, settings, np.asarray(point, float))
    return batched, one, alone


def _same(a: dict, b: dict) -> list:
    """The fields in which two results differ (but the times they took)."""
    return [k for k in a if k not in ("wall", "cpu") and not (
        list(a[k]) == list(b[k]) if a[k].dtype == object else np.array_equal(a[k], b[k], equal_nan=True))]


def test_the_batched_engine_classifies_as_single_runs_do(gait, monkeypatch):
    """Every start of a grid that holds both classes, with the fixed point's own start and one 0.02 off it (many
    steps to the cycle), classified by the batched engine and by single runs: every field equal to the bit (class,
    steps, distance, end state, crossing times, messages), none of them run alone."""
    from andyc.analysis.sweeps.points import grid
    from andyc.analysis.sweeps.worker import Settings

    model, cycle, basin = gait
    x = dict(zip(model.state_names, cycle.state))
    values = np.vstack([grid(GRID).values, [[x["th1_dot"], x["th2_dot"]], [x["th1_dot"] + 0.02, x["th2_dot"] - 0.02]]])
    settings = Settings.of(model, ("th1_dot", "th2_dot"), basin.t_step * basin.steps, basin=basin)
    batched, one, alone = _by_engine(model, settings, values, monkeypatch)
    assert _same(batched, one) == [] and alone == []
    assert {CYCLE, FALLS} <= set(batched["basin"].tolist()) and batched["basin_steps"].max() > 5


def test_the_batched_engine_runs_alone_what_it_cannot_start(gait, monkeypatch):
    """A start off the constraint manifold runs alone, with the single run's record; the other goes on batched."""
    from andyc.analysis.sweeps.worker import Settings
    from andyc.runtime.status import FAILED

    model, cycle, basin = gait
    settings = Settings.of(model, ("y", "th1_dot"), basin.t_step * basin.steps, basin=basin)
    values = [[1.5, -1.0], [cycle.state[model.state_names.index("y")], -1.0]]
    batched, one, alone = _by_engine(model, settings, values, monkeypatch)
    assert alone == [0] and _same(batched, one) == [] and batched["outcome"][0] == FAILED


def test_the_batched_engine_finds_the_period_two_gait(compiled, monkeypatch):
    """Past the period doubling (see above), the batched engine's other orbit is the single runs' to the bit."""
    from andyc.analysis.sweeps.worker import Settings

    model = compiled(MODEL)
    cycle = find_cycle(model, "strike", parameters={"slope": 0.08})
    basin = make_basin(model, cycle, steps=100, tol=TOL, t_step=T_STEP, dt=1e-3, event_tol=1e-14, fall=FALL)
    x = dict(zip(model.state_names, cycle.state))
    settings = Settings.of(model, ("th1_dot", "th2_dot"), basin.t_step * basin.steps, basin=basin,
                           fixed=(("slope", 0.08),))
    batched, one, alone = _by_engine(model, settings, [[x["th1_dot"] + 0.01, x["th2_dot"]]], monkeypatch)
    assert _same(batched, one) == [] and alone == [] and batched["basin"][0] == OTHER_ORBIT
    assert batched["basin_period"][0] == 2
