"""andyc sweep (issue 25): the points, the metrics, and sweeps on a real dask.distributed LocalCluster of two
worker processes (one cluster for the module), into Zarr stores read back with xarray.

Every point's final state is compared with a serial andyc.simulate of the same point, bit for bit; a worker
is killed in the middle of a sweep; metrics are checked against the bouncing ball's closed-form impact
times and against the run's own arrays."""

import logging
import math
import os
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import andyc
from andyc.analysis.sweeps import points as P
from andyc.analysis.sweeps.metrics import MetricError, compile_metric, evaluate
from andyc.analysis.sweeps.run import SweepError, run_sweep
from andyc.analysis.sweeps.store import StoreError
from andyc.analysis.sweeps.worker import Settings
from andyc.cli import main
from andyc.runtime.status import OUTCOMES
from tests.support import MODELS

xr = pytest.importorskip("xarray")
distributed = pytest.importorskip("dask.distributed")


@pytest.fixture(scope="module")
def client():
    """A LocalCluster of two worker processes, one thread each, shared by the module's sweeps."""
    cluster = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                                       silence_logs=logging.ERROR)
    client = distributed.Client(cluster, set_as_default=False)
    yield client
    client.close()
    cluster.close()


@pytest.fixture(scope="module")
def pendulum(compiled):
    return compiled("double_pendulum")


@pytest.fixture(scope="module")
def ball(compiled):
    return compiled("bouncing_ball")


def serial_final(model, settings: Settings, point) -> np.ndarray:
    """The final state of the point by a plain andyc.simulate, as a user would run it."""
    parameters = {n: float(v) for n, v, (k, _) in zip(settings.names, point, settings.kinds) if k == "parameter"}
    states = {n: float(v) for n, v, (k, _) in zip(settings.names, point, settings.kinds) if k == "state"}
    x0 = None
    if states:
        x0 = model.initial_state(model.parameters(parameters)).copy()
        for n, v in states.items():
            x0[model.state_names.index(n)] = v
    return andyc.simulate(model, settings.t_end, dt=settings.dt, parameters=parameters, x0=x0,
                          progress=False).state[-1]


# ---- points ------------------------------------------------------------------------------------------------

def test_grid_is_the_full_product_in_c_order():
    pts = P.grid(["a=0:1:3", "b=-2:2:5"])
    assert pts.shape == (3, 5) and pts.n == 15
    assert np.array_equal(pts.axes[0], np.linspace(0, 1, 3)) and np.array_equal(pts.axes[1], np.linspace(-2, 2, 5))
    i, j = pts.index(np.arange(15))
    assert np.array_equal(pts.values[:, 0], pts.axes[0][i]) and np.array_equal(pts.values[:, 1], pts.axes[1][j])


def test_samples_are_numpys_generator_draws_in_the_order_given():
    pts = P.samples(50, ["m=normal(1, 0.1)", "g=uniform(9, 10)"], seed=7)
    rng = np.random.default_rng(7)
    assert np.array_equal(pts.values[:, 0], rng.normal(1, 0.1, 50))
    assert np.array_equal(pts.values[:, 1], rng.uniform(9, 10, 50))
    assert np.array_equal(P.samples(50, ["m=normal(1, 0.1)", "g=uniform(9, 10)"], seed=7).values, pts.values)
    assert not np.array_equal(P.samples(50, ["m=normal(1, 0.1)", "g=uniform(9, 10)"], seed=8).values, pts.values)


def test_grid_values_are_the_decimals_a_user_writes_and_sel_finds_them():
    pts = P.grid(["m=0:1:11", "k=0:1:7"])
    assert list(pts.axes[0]) == [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]   # linspace: 0.30000000000000004
    assert np.array_equal(pts.axes[1], np.linspace(0, 1, 7))       # thirds and sixths: no short decimal, linspace's
    assert np.abs(pts.axes[0] - np.linspace(0, 1, 11)).max() <= 2.3e-16
    assert list(P.grid(["e=1e-9:3e-9:5"]).axes[0]) == [1e-9, 1.5e-9, 2e-9, 2.5e-9, 3e-9]


def test_lhs_puts_one_point_in_each_stratum_of_every_name_and_maps_by_the_inverse_cdf():
    from scipy.stats import norm

    n = 40
    pts = P.samples(n, ["a=uniform(2, 6)", "m=normal(1, 0.1)"], seed=5, sampler="lhs")
    assert pts.sampler == "lhs" and pts.values.shape == (n, 2)
    strata = np.floor((pts.values[:, 0] - 2) / 4 * n).astype(int)      # Latin hypercube: a permutation
    assert sorted(strata) == list(range(n))
    u = norm.cdf(pts.values[:, 1], loc=1, scale=0.1)                   # back to the unit interval
    assert sorted(np.floor(u * n).astype(int)) == list(range(n))
    again = P.samples(n, ["a=uniform(2, 6)", "m=normal(1, 0.1)"], seed=5, sampler="lhs")
    assert np.array_equal(again.values, pts.values)
    assert not np.array_equal(P.samples(n, ["a=uniform(2, 6)", "m=normal(1, 0.1)"], seed=6, sampler="lhs").values,
                              pts.values)


@pytest.mark.parametrize("sampler", ["lhs", "sobol", "halton"])
def test_a_designs_points_are_scipys_through_each_distributions_inverse_cdf(sampler):
    """Each name takes its own column of scipy.stats.qmc's design (seeded by numpy's Generator of the seed), a
    uniform one scaled to [A, B), a normal one through SciPy's norm.ppf."""
    from scipy.stats import norm, qmc

    engine = {"lhs": qmc.LatinHypercube, "sobol": qmc.Sobol, "halton": qmc.Halton}[sampler]
    u = engine(2, rng=np.random.default_rng(9)).random(16)
    pts = P.samples(16, ["a=uniform(2, 6)", "m=normal(1, 0.1)"], seed=9, sampler=sampler)
    assert (pts.kind, pts.seed, pts.sampler) == ("samples", 9, sampler)
    assert np.allclose(pts.values[:, 0], 2 + 4 * u[:, 0], rtol=0, atol=1e-15)
    assert np.allclose(pts.values[:, 1], norm.ppf(u[:, 1], loc=1, scale=0.1), rtol=0, atol=1e-12)


def test_sobol_takes_powers_of_two_and_names_the_nearest_ones():
    assert P.samples(1, ["a=uniform(0, 1)"], seed=0, sampler="sobol").n == 1
    with pytest.raises(P.PointsError, match=r"3 samples lose the balance of Sobol' points; give a power of 2 \(2 or 4\)"):
        P.samples(3, ["a=uniform(0, 1)"], seed=0, sampler="sobol")


@pytest.mark.parametrize("sampler", ["sobol", "halton"])
def test_low_discrepancy_samples_cover_the_box_more_evenly_than_random_ones(sampler):
    from scipy.stats import qmc

    specs = ["a=uniform(0, 2)", "b=uniform(-1, 1)", "c=uniform(5, 6)"]
    lows, highs = np.array([0, -1, 5]), np.array([2, 1, 6])
    even = P.samples(256, specs, seed=1, sampler=sampler).values
    draws = P.samples(256, specs, seed=1).values
    assert ((even >= lows) & (even < highs)).all()
    # the centred L2 discrepancy (Hickernell), computed by SciPy: far lower for a low-discrepancy design
    d_even = qmc.discrepancy((even - lows) / (highs - lows))
    d_random = qmc.discrepancy((draws - lows) / (highs - lows))
    assert d_even < d_random / 4, (d_even, d_random)


@pytest.mark.parametrize("make, message", [
    (lambda: P.grid(["a=0:1:0"]), "empty range (0 values)"),
    (lambda: P.grid(["a=1:1:4"]), "empty range (from 1 to 1)"),
    (lambda: P.grid(["a=0:1"]), "not NAME=FROM:TO:COUNT"),
    (lambda: P.grid(["a=0:x:3"]), "'x' is not a number"),
    (lambda: P.samples(5, ["a=normal(0,-1)"], 0), "the standard deviation -1 must be above 0"),
    (lambda: P.samples(5, ["a=uniform(2,1)"], 0), "uniform(A,B) needs A < B"),
    (lambda: P.samples(5, ["a=uniform(1,1)"], 0), "uniform(A,B) needs A < B, got 1, 1"),
    (lambda: P.samples(5, ["=uniform(1,2)"], 0), "a bad distribution; write NAME=normal(MU,SIGMA) or"),
    (lambda: P.samples(5, ["a=uniform(1,2)"], 0, "grid"), "--sampler grid: not a sampler; choose one of random, "),
    (lambda: P.samples(0, ["a=uniform(1,2)"], 0), "--samples 0: give at least 1 sample"),
    (lambda: P.samples(5, ["a=poisson(3)"], 0), "a bad distribution; write NAME=normal(MU,SIGMA) or"),
])
def test_bad_points_get_one_line(make, message):
    with pytest.raises(P.PointsError) as exc:
        make()
    assert message in str(exc.value) and "\n" not in str(exc.value)


def test_csv_points_and_their_errors_name_the_line(tmp_path):
    good = tmp_path / "p.csv"
    good.write_text("m1,q1\n1.0,0.5\n# a comment\n2.0,0.25\n")
    pts = P.from_csv(good)
    assert pts.names == ("m1", "q1") and np.array_equal(pts.values, [[1.0, 0.5], [2.0, 0.25]])
    bad = tmp_path / "bad.csv"
    bad.write_text("m1,q1\n1.0,0.5\n2.0,nan\n")
    with pytest.raises(P.PointsError, match=r"bad.csv:3: q1 is 'nan', not a finite number"):
        P.from_csv(bad)
    bad.write_text("m1,q1\n1.0\n")
    with pytest.raises(P.PointsError, match=r"bad.csv:2: 1 values for 2 names"):
        P.from_csv(bad)


def test_unknown_name_is_refused(pendulum):
    with pytest.raises(P.PointsError, match="unknown name 'mass': double_pendulum has no parameter, input or state"):
        P.check_names(["mass"], pendulum)


# ---- metrics, against the run's arrays and closed forms -----------------------------------------------------

def test_metrics_against_the_run_and_the_closed_form_impact_times(ball):
    run = andyc.simulate(ball, 2.0, dt=1e-3, frames=["ball"], progress=False)
    h0, g, e = 1.0, 9.81, 0.8
    t1 = math.sqrt(2 * h0 / g)
    value = {name: evaluate(compile_metric(name, text, ball), run) for name, text in {
        "first": "time_of(bounce, 1)", "second": "time_of(bounce, 2)", "fifth": "time_of(bounce, 50)",
        "bounces": "count(bounce)", "all": "count()", "top": "max(y)", "low": "min(ball.y)",
        "mid": "at(0.3, y)", "e_end": "energy", "drop": "max(energy) - min(energy)", "fell": "min(y) < -0.01",
        "both": "max(min(y), 0.5) * 2", "speed": "y_dot", "h": "h0 + 1"}.items()}
    assert value["first"] == pytest.approx(t1, abs=1e-6)
    assert value["second"] == pytest.approx(t1 + 2 * e * t1, abs=1e-6)         # docs/reference-cases.md §6
    assert math.isnan(value["fifth"])
    assert value["bounces"] == value["all"] == len(run.events["time"]) == np.count_nonzero(run.events["time"] <= 2.0)
    assert value["top"] == run.column("y").max() and value["low"] == run.frames["ball"][:, 1].min()
    assert value["mid"] == pytest.approx(h0 - g * 0.3 ** 2 / 2, abs=1e-9)      # free fall until t1
    assert value["e_end"] == run.energy[-1] and value["drop"] == np.ptp(run.energy)
    assert value["fell"] == 0.0 and value["both"] == 1.0
    assert value["speed"] == run.state[-1, 1] and value["h"] == 2.0


@pytest.mark.parametrize("text, message", [
    ("max(yy)", "unknown name 'yy'"),
    ("time_of(hop, 1)", "'hop' is not a jump of bouncing_ball"),
    ("time_of(bounce, 0)", "time_of takes a jump's name and a whole number N >= 1"),
    ("max(min(y))", "a run function inside another"),
    ("__import__('os')", "is not allowed"),
    ("y == 1", "one comparison with <, <=, > or >= only"),
    ("nose.x", "unknown frame 'nose'"),
])
def test_bad_metrics_get_one_line(ball, text, message):
    with pytest.raises(MetricError) as exc:
        compile_metric("m", text, ball)
    assert message in str(exc.value) and "\n" not in str(exc.value) and str(exc.value).startswith("--metric m:")


# ---- sweeps on the cluster ----------------------------------------------------------------------------------

def test_grid_sweep_equals_serial_runs_bit_for_bit_and_resumes_with_nothing_new(client, pendulum, tmp_path):
    pts = P.grid(["m1=0.5:2:3", "q1=0.2:1.0:3"])
    settings = Settings.of(pendulum, pts.names, 0.3, metrics=(("emax", "max(energy)"),), trajectory=4)
    store = tmp_path / "grid.zarr"
    first = run_sweep(pendulum, pts, settings, store, client=client, batch=2)
    assert (first.computed, first.already, first.outcomes["finished"]) == (9, 0, 9)
    ds = xr.open_zarr(store)
    assert ds.final.dims == ("m1", "q1", "state") and list(ds.state.values) == list(pendulum.state_names)
    assert np.array_equal(ds.m1.values, pts.axes[0]) and ds.attrs["model"] == "double_pendulum"
    for k, point in enumerate(pts.values):
        i, j = pts.index(k)
        final = ds.final.sel(m1=point[0], q1=point[1]).values
        assert np.array_equal(final, serial_final(pendulum, settings, point)), point
        assert ds.emax.values[i, j] == ds.emax.sel(m1=point[0], q1=point[1]).values
    assert (ds.outcome.values == 1).all() and np.isfinite(ds.trajectory.values).all()
    assert np.array_equal(ds.trajectory.values[..., -1, :], ds.final.values)      # at t_end: the final state
    assert list(ds.trajectory_time.values[0, 0]) == [0.0, 0.1, 0.2, 0.3]      # (linspace: 0.30000000000000004)
    x0 = pendulum.initial_state(pendulum.parameters({"m1": 0.5})).copy()
    x0[0] = 0.2
    assert np.array_equal(ds.trajectory.values[0, 0, 0], x0)                     # at t = 0: the point's start
    assert (ds.cpu.values > 0).all() and (ds.cpu.values <= ds.wall.values + 1e-3).all()   # one thread's time
    again = run_sweep(pendulum, pts, settings, store, client=client, batch=2)
    assert (again.computed, again.already, again.batches) == (0, 9, 0)


def test_tasks_carry_the_build_path_and_each_worker_loads_the_model_once(client, pendulum, tmp_path):
    import pickle

    pts = P.grid(["q1=0:1:8"])
    settings = Settings.of(pendulum, pts.names, 0.05)
    payload = pickle.dumps(settings)
    assert len(payload) < 2000 and b"numba" not in payload and b"CompiledModel" not in payload

    def count_loads():              # (local functions: sent by value to the workers)
        from andyc.analysis.sweeps import worker
        from andyc.runtime import compiled

        worker._LOADED.clear()
        original, calls = compiled.load_compiled, []

        def load(path):
            calls.append(path)
            return original(path)

        compiled.load_compiled = load
        worker.calls, worker.original_load = calls, original

    def loads():
        from andyc.analysis.sweeps import worker
        from andyc.runtime import compiled

        compiled.load_compiled = worker.original_load
        return len(worker.calls)

    client.run(count_loads)
    summary = run_sweep(pendulum, pts, settings, tmp_path / "once.zarr", client=client, batch=1)
    counts = client.run(loads)
    assert summary.batches == 8 and summary.computed == 8
    assert sorted(counts.values()) == sorted([1] * len(summary.pids) + [0] * (len(counts) - len(summary.pids)))


def test_a_worker_killed_mid_sweep_loses_no_point(client, pendulum, tmp_path):
    """One worker process ends itself (os._exit) in the middle of its second batch (its points run, their
    results not yet sent); the scheduler reruns that batch elsewhere; every point is in the store once, each
    equal to its serial run."""
    pts = P.grid(["q1=0.1:1.2:24"])
    settings = Settings.of(pendulum, pts.names, 0.05)
    victim = sorted(client.scheduler_info(n_workers=-1)["workers"])[0]
    victim_pid = client.run(os.getpid, workers=[victim])[victim]

    def die_after(points):          # (a local function: sent by value to the worker)
        import os as os_
        from andyc.analysis.sweeps import batch

        original, seen = batch.run_batched, [0]

        def run_batched(out, model, settings, values, metrics=()):
            original(out, model, settings, values, metrics)
            seen[0] += len(values)
            if seen[0] > points:
                os_._exit(1)

        batch.run_batched = run_batched

    client.run(die_after, 2, workers=[victim])
    summary = run_sweep(pendulum, pts, settings, tmp_path / "killed.zarr", client=client, batch=2)
    with pytest.raises(ProcessLookupError):
        os.kill(victim_pid, 0)                  # the worker did die during the sweep
    assert summary.computed == pts.n            # every batch written once: no point twice, none lost
    assert summary.lost == 1 and ", 1 of them lost during the sweep," in summary.text()   # (issue 40)
    ds = xr.open_zarr(tmp_path / "killed.zarr")
    assert (ds.outcome.values == 1).all()
    for k, point in enumerate(pts.values):
        assert np.array_equal(ds.final.values[k], serial_final(pendulum, settings, point))
    assert run_sweep(pendulum, pts, settings, tmp_path / "killed.zarr", client=client).computed == 0


def test_monte_carlo_same_seed_same_samples_and_results(client, pendulum, tmp_path):
    settings = Settings.of(pendulum, ("m2", "q2_dot"), 0.1)
    stores = []
    for name, seed in (("a", 3), ("b", 3), ("c", 4)):
        pts = P.samples(6, ["m2=normal(0.5, 0.05)", "q2_dot=uniform(-1, 1)"], seed=seed)
        run_sweep(pendulum, pts, settings, tmp_path / f"{name}.zarr", client=client)
        stores.append(xr.open_zarr(tmp_path / f"{name}.zarr").load())
    a, b, c = stores
    assert a.final.dims == ("point", "state") and a.m2.dims == ("point",)
    assert np.array_equal(a.m2.values, b.m2.values) and np.array_equal(a.final.values, b.final.values)
    assert not np.array_equal(a.m2.values, c.m2.values)
    assert np.array_equal(a.final.values[2], serial_final(pendulum, settings, [a.m2.values[2], a.q2_dot.values[2]]))


def test_outcomes_zeno_blow_up_and_failed_points_are_recorded(client, ball, pendulum, tmp_path):
    pts = P.grid(["e=0.5:0.8:2"])
    zeno = run_sweep(ball, pts, Settings.of(ball, pts.names, 10.0, metrics=(("n", "count(bounce)"),)),
                     tmp_path / "zeno.zarr", client=client)
    assert zeno.outcomes["Zeno"] == 2
    ds = xr.open_zarr(tmp_path / "zeno.zarr")
    assert all(m.startswith("stopped: Zeno behaviour") for m in ds.message.values)
    assert (ds.jump_count.sel(jump="bounce").values == ds.n.values).all()
    t1 = math.sqrt(2 / 9.81)
    assert ds.event_time.values[:, 0] == pytest.approx([t1, t1], abs=1e-6)
    pts = P.grid(["q1_dot=1e10:2e10:2"])
    blown = run_sweep(pendulum, pts, Settings.of(pendulum, pts.names, 1.0), tmp_path / "blown.zarr", client=client)
    assert blown.outcomes["blew up"] == 2
    pts = P.grid(["q1=0:1:3"])
    failed = run_sweep(pendulum, pts, Settings.of(pendulum, pts.names, 0.1, fixed=(("no_such", 1.0),)),
                       tmp_path / "failed.zarr", client=client)
    assert failed.outcomes["failed"] == 3
    ds = xr.open_zarr(tmp_path / "failed.zarr")
    assert all("unknown parameter 'no_such'" in m for m in ds.message.values) and ds.final.isnull().all()
    assert OUTCOMES[int(ds.outcome.values[0])] == "failed"


def test_a_store_of_another_sweep_model_or_version_is_refused(client, pendulum, ball, tmp_path):
    import zarr

    pts = P.grid(["q1=0:1:2"])
    settings = Settings.of(pendulum, pts.names, 0.05)
    store = tmp_path / "s.zarr"
    run_sweep(pendulum, pts, settings, store, client=client)
    other = P.grid(["e=0.5:0.8:2"])
    with pytest.raises(StoreError, match="made by another model or version .*model double_pendulum.*this sweep: "
                                         "model bouncing_ball"):
        run_sweep(ball, other, Settings.of(ball, other.names, 0.05), store, client=client)
    with pytest.raises(StoreError, match="with other points"):
        run_sweep(pendulum, P.grid(["q1=0:1:3"]), settings, store, client=client)
    with pytest.raises(StoreError, match="with other run options"):
        run_sweep(pendulum, pts, Settings.of(pendulum, pts.names, 0.06), store, client=client)
    group = zarr.open_group(str(store), mode="r+")
    group.attrs["andyc_version"] = "0.0.1"
    zarr.consolidate_metadata(str(store))
    with pytest.raises(StoreError, match=r"andyc 0\.0\.1; this sweep: .* andyc " + andyc.__version__):
        run_sweep(pendulum, pts, settings, store, client=client)


def test_unreachable_scheduler_is_one_line(pendulum, tmp_path):
    pts = P.grid(["q1=0:1:2"])
    with pytest.raises(SweepError, match=r"cannot reach the Dask scheduler at tcp://127.0.0.1:9 \(.*[Rr]efused"):
        run_sweep(pendulum, pts, Settings.of(pendulum, pts.names, 0.05), tmp_path / "u.zarr",
                  scheduler="tcp://127.0.0.1:9")


# ---- the command line ---------------------------------------------------------------------------------------

MODEL = str(Path(__file__).resolve().parents[1] / "models" / "double_pendulum.yaml")


@pytest.mark.parametrize("args, message", [
    (["--grid", "mass=0:1:3"], "unknown name 'mass': double_pendulum has no parameter, input or state"),
    (["--grid", "m1=0:1:0"], "an empty range (0 values)"),
    (["--samples", "4", "--dist", "m1=gamma(1,2)"], "a bad distribution"),
    (["--samples", "4", "--dist", "m1=normal(1,0)"], "the standard deviation 0 must be above 0"),
    (["--grid", "m1=0:1:2", "--samples", "3"], "choose the points one way"),
    (["--grid", "m1=0:1:2", "--metric", "e=max(energy"], "--metric e: cannot parse"),
    (["--grid", "m1=0:1:2", "--set", "nope=1"], "--set nope: double_pendulum has no parameter or input 'nope'"),
    (["--grid", "m1=0:1:2", "--scheduler", "tcp://127.0.0.1:9", "--workers", "2"], "give one of them"),
    (["--points", "missing.csv"], "missing.csv: no such file (--points)"),
    (["--samples", "1000", "--sampler", "sobol", "--dist", "m1=uniform(1,2)"], "give a power of 2 (512 or 1024)"),
    (["--grid", "m1=0:1:2", "--sampler", "lhs"], "--sampler lhs goes with --samples N"),
    (["--grid", "m1=0:1:2", "--scheduler", "tcp://127.0.0.1:9", "--engine", "inline"], "--engine inline runs the "
                                                                                       "points in this process"),
])
def test_cli_bad_input_is_one_line_exit_2(shipped_build, tmp_path, args, message):
    result = CliRunner().invoke(main, ["sweep", MODEL, "--build-dir", str(shipped_build), "-o",
                                       str(tmp_path / "x.zarr"), *args])
    assert result.exit_code == 2, result.output
    lines = result.output.strip().splitlines()
    assert len(lines) == 1 and message in lines[0], result.output
    assert not (tmp_path / "x.zarr").exists()


def test_cli_sweep_on_a_scheduler_then_plot(client, shipped_build, tmp_path):
    store = tmp_path / "cli.zarr"
    args = ["sweep", MODEL, "--build-dir", str(shipped_build), "--grid", "m1=0.5:1.5:3", "--grid", "q1=0:0.5:2",
            "--t-end", "0.05", "--metric", "top=max(q1)", "--scheduler", client.scheduler.address, "-o", str(store)]
    result = CliRunner().invoke(main, args)
    assert result.exit_code == 0, result.output
    assert "6 points (6 computed now" in result.output and "finished 6" in result.output
    again = CliRunner().invoke(main, args)
    assert again.exit_code == 0 and "6 points, all in the store already (nothing to compute)" in again.output
    ds = xr.open_zarr(store)
    assert ds.top.attrs["expression"] == "max(q1)" and ds.top.dims == ("m1", "q1")
    plot = CliRunner().invoke(main, ["plot", str(store), "-o", str(tmp_path / "map.png")])
    assert plot.exit_code == 0 and (tmp_path / "map.png").stat().st_size > 1000, plot.output
    bad = CliRunner().invoke(main, ["plot", str(store), "--metric", "nope", "-o", str(tmp_path / "m2.png")])
    assert bad.exit_code == 2 and "has no variable 'nope'" in bad.output


def test_cli_unreachable_scheduler_exit_1(shipped_build, tmp_path):
    result = CliRunner().invoke(main, ["sweep", MODEL, "--build-dir", str(shipped_build), "--grid", "m1=0:1:2",
                                       "--scheduler", "tcp://127.0.0.1:9", "-o", str(tmp_path / "u.zarr")])
    assert result.exit_code == 1
    assert result.output.strip().startswith("andyc: cannot reach the Dask scheduler at tcp://127.0.0.1:9")


def test_importing_andyc_and_its_cli_imports_no_dask():
    import subprocess
    import sys

    code = ("import sys, andyc, andyc.cli, andyc.analysis.sweeps.points, andyc.analysis.sweeps.worker; "
            "print([m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed', 'zarr', 'xarray')])")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def test_a_local_sweep_without_metrics_imports_neither_sympy_nor_xarray_nor_dask(pendulum, shipped_build, tmp_path):
    """What a local sweep's first result waits for (issue 42): the store is made with zarr alone, and the metric
    parser (SymPy under it) is imported only for metrics; checked by what the command imported, not by time."""
    import subprocess
    import sys

    code = ("import sys; from andyc.cli import main; main(sys.argv[1:], standalone_mode=False); "
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'sympy', 'xarray', 'dask', 'distributed'}))")
    args = ["sweep", str(MODELS / "double_pendulum.yaml"), "--grid", "q1=0.1:1:3", "--t-end", "0.1", "--build-dir",
            str(shipped_build), "-o", str(tmp_path / "s.zarr")]
    out = subprocess.run([sys.executable, "-c", code, *args], capture_output=True, text=True, check=True).stdout
    assert out.splitlines()[-1] == "[]"
    assert int(xr.open_zarr(tmp_path / "s.zarr").outcome.sum()) == 3      # (three points, finished: code 1)
    with_metric = subprocess.run([sys.executable, "-c", code, *args[:-1], str(tmp_path / "m.zarr"), "--metric",
                                  "top=max(q1)"], capture_output=True, text=True, check=True).stdout
    assert with_metric.splitlines()[-1] == "['sympy']"


# ---- the inline engine: no cluster ---------------------------------------------------------------------------

def test_inline_sweep_equals_serial_runs_with_the_runs_options_and_frame_metrics(pendulum, tmp_path):
    """Each point is andyc.simulate with every run option of the sweep (an adaptive method's tolerances, the
    frames a metric reads), in this process: bit for bit a user's own call."""
    pts = P.grid(["m1=0.5:2:2", "q1=0.2:1.0:2"])
    settings = Settings.of(pendulum, pts.names, 0.5, method="RK45", rtol=1e-4, atol=1e-6,
                           metrics=(("tip", "min(tip.y)"),))
    summary = run_sweep(pendulum, pts, settings, tmp_path / "s.zarr", engine="inline")
    assert (summary.engine, summary.computed) == ("inline", 4) and "in this process" in summary.text()
    ds = xr.open_zarr(tmp_path / "s.zarr")
    for k, point in enumerate(pts.values):
        i, j = pts.index(k)
        x0 = pendulum.initial_state(pendulum.parameters({"m1": point[0]})).copy()
        x0[pendulum.state_names.index("q1")] = point[1]
        run = andyc.simulate(pendulum, 0.5, method="RK45", rtol=1e-4, atol=1e-6, parameters={"m1": point[0]},
                             x0=x0, frames=["tip"], progress=False)
        assert np.array_equal(ds.final.values[i, j], run.state[-1])
        assert ds.tip.values[i, j] == run.frames["tip"][:, 1].min()
    loose = andyc.simulate(pendulum, 0.5, method="RK45", parameters={"m1": 0.5}, progress=False)   # rtol 1e-8
    assert not np.array_equal(ds.final.values[0, 0], loose.state[-1])       # (the tolerances made a difference)


def test_inline_threads_give_every_point_its_serial_answer_and_auto_runs_inline(pendulum, tmp_path):
    """Points on 1 and 3 threads (the compiled loops side by side), in batches of 2: the stores equal to the bit;
    without a scheduler, auto is inline."""
    pts = P.grid(["m1=0.5:2:7"])
    settings = Settings.of(pendulum, pts.names, 0.3)
    one = run_sweep(pendulum, pts, settings, tmp_path / "a.zarr", engine="inline", workers=1)
    three = run_sweep(pendulum, pts, settings, tmp_path / "b.zarr", workers=3, batch=2)
    assert (one.engine, one.workers, three.engine, three.workers, three.batches) == ("inline", 1, "inline", 3, 4)
    assert "in this process on 3 threads" in three.text()
    a, b = xr.open_zarr(tmp_path / "a.zarr"), xr.open_zarr(tmp_path / "b.zarr")
    assert np.array_equal(a.final.values, b.final.values) and (b.outcome.values == 1).all()
    assert np.array_equal(b.final.values[3], serial_final(pendulum, settings, pts.values[3]))


def test_an_inline_sweep_starts_no_cluster(shipped_build, tmp_path):
    import subprocess
    import sys

    code = ("import sys; from andyc.cli import main\n"
            "try:\n    main([" + ", ".join(repr(a) for a in [
                "sweep", MODEL, "--build-dir", str(shipped_build), "--grid", "m1=0.5:1.5:3", "--t-end", "0.05",
                "-o", str(tmp_path / "s.zarr")]) + "])\n"
            "except SystemExit as e:\n    assert not e.code, e.code\n"
            "print([m for m in sys.modules if m.split('.')[0] == 'distributed'])")     # (xarray may import dask)
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert result.returncode == 0, result.stderr
    assert "3 points (3 computed now in" in result.stdout and "in this process" in result.stdout
    assert result.stdout.strip().splitlines()[-1] == "[]"


def test_the_store_follows_xarrays_and_cfs_conventions(pendulum, tmp_path):
    """A grid value found by its decimal (ds.sel), the trajectory over a time coordinate with its units, CF's
    long names and units, and a message kept whole however long."""
    pts = P.grid(["m1=0:1:11"])
    settings = Settings.of(pendulum, pts.names, 0.2, trajectory=5, metrics=(("top", "max(q1)"),))
    run_sweep(pendulum, pts, settings, tmp_path / "s.zarr", engine="inline")
    ds = xr.open_zarr(tmp_path / "s.zarr")
    assert ds.attrs["Conventions"].startswith("CF-")
    assert float(ds.m1.sel(m1=0.3)) == 0.3 and ds.m1.attrs["long_name"] == "parameter m1"
    line = ds.trajectory.sel(m1=0.3, state="q1")
    assert line.dims == ("time",) and np.array_equal(line.time.values, [0.0, 0.05, 0.1, 0.15, 0.2])
    assert ds.time.attrs["units"] == "s" and ds.time.attrs["standard_name"] == "time"
    assert ds.t_final.attrs["units"] == "s" and ds.wall.attrs["units"] == "s"
    assert ds.top.attrs["long_name"] == "metric top = max(q1)"
    assert line.values[0] == ds.trajectory.sel(m1=0.3, state="q1", time=0.0).values     # time found by value
    name = "no_such_" + "x" * 400
    pts = P.grid(["q1=0:1:2"])
    failed = Settings.of(pendulum, pts.names, 0.1, fixed=((name, 1.0),))
    run_sweep(pendulum, pts, failed, tmp_path / "f.zarr", engine="inline")
    message = str(xr.open_zarr(tmp_path / "f.zarr").message.values[0])
    assert f"unknown parameter '{name}'" in message and len(message) > 400


@pytest.mark.parametrize("kind", ["grid", "samples"])
def test_the_store_is_written_as_xarrays_to_zarr_writes_it(pendulum, compiled, tmp_path, kind):
    """andyc writes a new store with zarr alone (xarray's import, with dask.array under its array checks, took over
    a second before a first result could be stored): its metadata (dimensions, CF and xarray's `coordinates`
    attributes, dtypes, fill values, chunks, filters) and every array equal what xarray's own Dataset.to_zarr
    writes for the same Dataset."""
    import json

    import zarr

    from andyc.analysis.sweeps import store

    if kind == "grid":
        model, pts = pendulum, P.grid(["q1=0.1:1.5:7", "m2=0.5:1:3"])
        settings = Settings.of(model, pts.names, 1.0, trajectory=4, metrics=(("peak", "max(q1)"),))
    else:           # (jumps, discrete states, swept names as coordinates along `point`)
        model, pts = compiled("bouncing_ball_contact"), P.samples(300, ["h0=normal(1,0.1)", "e=uniform(0.5,0.9)"], 3)
        settings = Settings.of(model, pts.names, 1.0, trajectory=3, method="projection")
    layout, encoding = store.layout(model, pts, settings), store._encoding(model, pts, settings)
    store.write_layout(tmp_path / "andyc.zarr", layout, encoding)
    ds = xr.Dataset({n: v for n, v in layout.variables.items() if n not in layout.coordinates},
                    coords={n: layout.variables[n] for n in layout.coordinates}, attrs=layout.attrs)
    ds.to_zarr(tmp_path / "xarray.zarr", mode="w", zarr_format=2, consolidated=True, encoding=encoding)
    ours, theirs = (json.loads((tmp_path / f"{w}.zarr" / ".zmetadata").read_text())["metadata"]
                    for w in ("andyc", "xarray"))
    assert ours == theirs
    assert ours["outcome/.zattrs"].get("coordinates") == (None if kind == "grid" else "e h0")     # (CF: sorted)
    a, b = (zarr.open_group(str(tmp_path / f"{w}.zarr"), mode="r") for w in ("andyc", "xarray"))
    assert sorted(a.array_keys()) == sorted(b.array_keys())
    for name in a.array_keys():
        assert a[name].dtype == b[name].dtype
        assert np.array_equal(a[name][...], b[name][...], equal_nan=a[name].dtype.kind == "f"), name


def test_a_metric_map_marks_the_points_whose_run_did_not_finish():
    from matplotlib.collections import PathCollection, QuadMesh

    from andyc.plot.sweepmap import sweep_figure

    x, y = np.array([0.0, 1.0, 2.0]), np.array([5.0, 6.0])
    values = np.arange(6.0).reshape(3, 2)
    code = np.ones((3, 2), int)
    code[1, 0], code[2, 1] = 2, 3                      # stopped at (1, 5), blew up at (2, 6)
    names = {int(c): n for c, n in OUTCOMES.items()}
    fig = sweep_figure(True, [("a", x), ("b", y)], values, "m", runs=(code, names))
    ax = fig.axes[0]
    mesh = next(c for c in ax.collections if isinstance(c, QuadMesh))
    shown = np.ma.masked_invalid(mesh.get_array()).reshape(2, 3).T      # (pcolormesh of values.T)
    assert shown.mask[1, 0] and shown.mask[2, 1] and shown.mask.sum() == 2
    assert shown[0, 0] == 0.0 and shown[2, 0] == 4.0
    crosses = {c.get_label(): c.get_offsets().tolist() for c in ax.collections if isinstance(c, PathCollection)}
    assert crosses == {"stopped": [[1.0, 5.0]], "blew up": [[2.0, 6.0]]}
    assert {t.get_text() for t in ax.get_legend().get_texts()} == {"stopped", "blew up"}


@pytest.mark.parametrize("args, missing, what", [
    (["sweep", MODEL, "--grid", "m1=1:2:2"], "zarr", "andyc sweep"),
    (["sweep", MODEL, "--grid", "m1=1:2:2", "--engine", "cluster"], "dask[distributed]", "andyc sweep"),
    (["cycle", str(MODELS / "compass_gait_step.yaml"), "--section", "strike", "--basin", "th1_dot=-1:-0.5:2",
      "--basin", "th2_dot=-0.5:0:2"], "xarray", "andyc cycle --basin"),
    (["plot", "."], "xarray", "andyc plot STORE"),
], ids=["sweep", "cluster", "basin", "plot-store"])
def test_without_the_sweep_extra_a_command_says_what_to_install(args, missing, what, monkeypatch, tmp_path):
    """The sweep extra (zarr, xarray, dask.distributed) is not in andyc's core: a plain `pip install andyc` has none
    of them. A command that needs one refuses with the package and the extra to install, before any work, and
    never as an internal error."""
    import importlib.util

    import andyc.analysis.sweeps as sweeps

    absent = {"zarr", "xarray", "distributed"}
    monkeypatch.setattr(sweeps, "find_spec", lambda name: None if name in absent else importlib.util.find_spec(name))
    result = CliRunner().invoke(main, [*args, "--build-dir", str(tmp_path / "build")] if args[0] != "plot" else args)
    assert result.exit_code == 2, result.output
    assert f"{what} needs" in result.output and missing in result.output
    assert "pip install 'andyc[sweep]'" in result.output and "internal error" not in result.output
    assert not (tmp_path / "build").exists()            # (refused before any build)
