"""The batched sweep engine (issue 42): a batch of points in one compiled call (andyc_numerics/batch.py), each
point's answer compared with a plain andyc.simulate of that point, bit for bit: its final state and the
trajectory's samples (the run's own logged states at the sample times), on a free model (parameters and
initial states swept), a rheonomic one with work slots, a constrained one under projection with the energy
correction, and inputs held per point or driven by an expression. Points the batch cannot finish (a start the
single run refuses, a run that blows up) get the single run's outcome and message; a stop ends the batch."""

import numpy as np
import pytest

import andyc
from andyc.analysis.sweeps import batch, worker
from andyc.analysis.sweeps import points as P
from andyc.analysis.sweeps.worker import Settings, empty_results, run_batch, sample_times
from andyc.errors import SimulationError
from andyc.runtime.status import FINISHED, FINISHED_CODE, OUTCOMES


def alone(model, settings: Settings, point):
    """The point's Run by andyc.simulate, as a user calls it (x0 as a mapping, `andyc sim --at`)."""
    parameters, inputs, states = {}, dict(settings.fixed), {}
    for name, value, (kind, _) in zip(settings.names, point, settings.kinds):
        {"parameter": parameters, "input": inputs, "state": states}[kind][name] = float(value)
    return andyc.simulate(model, settings.t_end, dt=settings.dt, method=settings.method, parameters=parameters,
                          inputs=inputs, x0=states or None, progress=False,
                          events=andyc.Events(stop_after=dict(settings.stop_after) or None))


def run_counting(monkeypatch, settings, values):
    """run_batch over the points, with the number of points it ran alone (worker.record)."""
    calls = []
    original = worker.record
    monkeypatch.setattr(worker, "record", lambda *a: (calls.append(a[1]), original(*a)))
    return run_batch(settings, np.arange(len(values)), values), calls


def check_against_single_runs(model, settings, values, out):
    times = sample_times(settings)
    for k, point in enumerate(values):
        run = alone(model, settings, point)
        assert run.status == FINISHED and out["message"][k] == FINISHED and out["outcome"][k] == FINISHED_CODE
        assert np.array_equal(out["final"][k], run.state[-1]), point
        assert out["t_final"][k] == run.time[-1] and out["final_flow"][k] == run.flow[-1]
        assert np.array_equal(out["final_discrete"][k], run.discrete[-1])
        # each sample: the run's state at the grid point nearest its time (times on the grid of dt)
        at = [np.argmin(np.abs(run.time - t)) for t in times]
        assert np.array_equal(out["trajectory"][k], run.state[at]), point
        assert np.array_equal(out["trajectory_time"][k], times)
        jumps = run.events["jump"]
        assert list(out["jump_count"][k]) == [np.count_nonzero(jumps == n) for n in range(model.nj)]
        kept = min(len(jumps), settings.max_events)
        assert np.array_equal(out["event_time"][k][:kept], run.events["time"][:kept])
        assert np.array_equal(out["event_jump"][k][:kept], jumps[:kept])
        assert np.isnan(out["event_time"][k][kept:]).all()


@pytest.mark.parametrize("name, method, t_end, grid, fixed", [
    ("double_pendulum", "rk4", 0.7, ["m2=0.5:2:3", "q1=0.1:1.2:2", "q2_dot=-1:1:2"], ()),
    ("shaken_pendulum", "rk4", 0.6, ["w=2:8:3", "th=0.1:1:2"], ()),
    ("fourbar", "projection", 0.4, ["m2=1:3:3", "a=0.8:1.2:2"], ()),
    ("fourbar", "rk4", 0.4, ["m2=1:3:3", "a=0.8:1.2:2"], ()),
    ("slider_crank", "lagrange", 0.3, ["m2=1:2:2"], ()),
    ("cart_pole", "rk4", 0.5, ["F=-2:2:3", "th=0.1:0.4:2"], ()),
    ("cart_pole", "rk4", 0.5, ["th=0.1:0.4:3"], (("F", "2*sin(3*t) + th"),)),
    ("bouncing_ball", "projection", 1.6, ["e=0.8:0.9:2", "h0=0.5:1:2"], ()),
    ("compass_gait", "projection", 1.6, ["w_stance0=-1.15:-1.05:3"], ()),
    ("bouncing_ball_contact", "projection", 1.2, ["e=0.5:0.8:2"], ()),
    ("rimless_wheel_contact", "projection", 2.5, ["w0=0.35:0.45:3"], ()),
], ids=["free", "rheonomic-work", "projection-energy", "drifting-rk4", "drifting-lagrange", "held-inputs",
        "driven-inputs", "jumps", "walker-jumps", "contact", "contact-friction"])
def test_a_batch_gives_each_point_its_single_runs_answer_bit_for_bit(compiled, monkeypatch, name, method, t_end, grid,
                                                                     fixed):
    model = compiled(name)
    pts = P.grid(grid)
    settings = Settings.of(model, pts.names, t_end, method=method, trajectory=5, fixed=fixed)
    worker.remember(model, settings)
    assert batch.batched(model, settings)
    out, ran_alone = run_counting(monkeypatch, settings, pts.values)
    assert ran_alone == []                                  # every point in the one compiled call
    check_against_single_runs(model, settings, pts.values, out)
    assert (out["cpu"] > 0).all() and len(set(out["wall"])) == 1      # (a batch's time, shared by its points)


def test_a_point_the_batch_cannot_finish_gets_the_single_runs_outcome_and_message(compiled, monkeypatch):
    """A point that blows up mid-batch, one that ends at a jump (Zeno), and one whose start the single run refuses
    (off the four-bar's closure), among points that finish: only those run alone, with the single run's status."""
    pendulum = compiled("double_pendulum")
    values = np.array([[0.3], [1e10], [0.5]])
    settings = Settings.of(pendulum, ("q1_dot",), 1.0)
    worker.remember(pendulum, settings)
    out, ran_alone = run_counting(monkeypatch, settings, values)
    assert ran_alone == [1]
    assert OUTCOMES[int(out["outcome"][1])] == "blew up"
    assert out["message"][1] == alone(pendulum, settings, values[1]).status
    assert list(out["outcome"][[0, 2]]) == [FINISHED_CODE] * 2
    assert np.array_equal(out["final"][2], alone(pendulum, settings, values[2]).state[-1])

    ball = compiled("bouncing_ball")        # e = 0.5: Zeno within the run (its message counts the samples kept)
    settings = Settings.of(ball, ("e",), 1.6, method="projection")
    worker.remember(ball, settings)
    values = np.array([[0.85], [0.5]])
    out, ran_alone = run_counting(monkeypatch, settings, values)
    assert ran_alone == [1] and OUTCOMES[int(out["outcome"][1])] == "Zeno"
    assert out["message"][1] == alone(ball, settings, values[1]).status
    assert out["outcome"][0] == FINISHED_CODE and out["jump_count"][0, 0] == 2

    fourbar = compiled("fourbar")
    settings = Settings.of(fourbar, ("th3",), 0.2, method="projection")
    worker.remember(fourbar, settings)
    values = np.array([[-np.pi / 2], [-1.0]])
    out, ran_alone = run_counting(monkeypatch, settings, values)
    assert ran_alone == [1] and OUTCOMES[int(out["outcome"][1])] == "failed"
    with pytest.raises(SimulationError) as refused:       # (the single run's own refusal)
        alone(fourbar, settings, values[1])
    assert out["message"][1] == str(refused.value) and np.isnan(out["final"][1]).all()
    assert out["outcome"][0] == FINISHED_CODE


def test_sweeps_a_single_run_answers_with_more_than_its_end_run_alone(compiled):
    """A wall-clock limit, a basin's classification and an adaptive method need the single run."""
    pendulum, ball, fourbar = compiled("double_pendulum"), compiled("bouncing_ball"), compiled("fourbar")
    assert batch.batched(pendulum, Settings.of(pendulum, ("m1",), 1.0))
    assert batch.batched(fourbar, Settings.of(fourbar, ("m1",), 1.0, method="baumgarte"))
    assert batch.batched(ball, Settings.of(ball, ("e",), 1.0, method="projection"))
    counted = (("n", "count(bounce)"),)
    assert batch.batched(ball, Settings.of(ball, ("e",), 1.0, method="projection", metrics=counted))
    assert batch.batched(ball, Settings.of(ball, ("e",), 1.0))          # (rk4 on constraint rows: drifting)
    assert not batch.batched(pendulum, Settings.of(pendulum, ("m1",), 1.0, timeout=5.0))
    assert not batch.batched(pendulum, Settings.of(pendulum, ("m1",), 1.0, method="RK45"))
    assert batch.batched(fourbar, Settings.of(fourbar, ("m1",), 1.0, method="rk4"))


@pytest.mark.parametrize("name, method, t_end, grid, fixed, metrics", [
    ("double_pendulum", "rk4", 0.7, ["m2=0.5:2:2", "q1=0.1:1.2:2"], (),
     (("peak", "max(abs(q1))"), ("E", "mean(energy)"), ("tip", "at(0.35, tip.x)"), ("low", "min(tip.y) < -1.5"),
      ("swing", "max(q2) - min(q2)"), ("end", "q1_dot + t"))),
    ("cart_pole", "rk4", 0.5, ["th=0.1:0.4:2"], (("F", "2*sin(3*t) + th"),), (("Fmax", "max(F)"), ("W", "energy"))),
    ("bouncing_ball", "projection", 1.6, ["e=0.8:0.9:2", "h0=0.5:1:2"], (),
     (("n", "count(bounce)"), ("t1", "time_of(bounce, 1)"), ("t2", "time_of(bounce, 2)"), ("t9", "time_of(bounce, 9)"),
      ("top", "max(y)"))),
    ("bouncing_ball_contact", "projection", 1.2, ["e=0.5:0.8:2"], (), (("all", "count()"), ("top", "max(energy)"))),
], ids=["free-frames", "driven-inputs", "jumps", "contact"])
def test_a_batchs_metrics_are_the_single_runs_bit_for_bit(compiled, monkeypatch, name, method, t_end, grid, fixed,
                                                          metrics):
    """Metrics read the whole run: the batch logs every step of its points and assembles each point's Run by
    simulate's own code; each metric equals its value on the point's single run, in groups of points too."""
    from andyc.analysis.sweeps.metrics import compile_metric, evaluate

    model = compiled(name)
    pts = P.grid(grid)
    settings = Settings.of(model, pts.names, t_end, method=method, fixed=fixed, metrics=metrics, trajectory=3)
    worker.remember(model, settings)
    out, ran_alone = run_counting(monkeypatch, settings, pts.values)
    assert ran_alone == []
    check_against_single_runs(model, settings, pts.values, out)
    parsed = [compile_metric(n, text, model) for n, text in metrics]
    frames = [f for m in parsed for f in m.frames]
    for k, point in enumerate(pts.values):
        parameters, inputs, states = {}, dict(fixed), {}
        for n, value, (kind, _) in zip(settings.names, point, settings.kinds):
            {"parameter": parameters, "input": inputs, "state": states}[kind][n] = float(value)
        run = andyc.simulate(model, t_end, dt=settings.dt, method=method, parameters=parameters, inputs=inputs,
                             x0=states or None, frames=frames, progress=False)
        expected = [evaluate(m, run) for m in parsed]
        assert np.array_equal(out["metrics"][k], expected, equal_nan=True), point
    if name == "bouncing_ball":     # the impacts' closed form: t1 = sqrt(2 h0 / g), t2 = t1 + 2 e t1
        e, h0 = pts.values[:, 0], pts.values[:, 1]
        t1 = np.sqrt(2 * h0 / 9.81)
        assert np.allclose(out["metrics"][:, 1], t1, rtol=0, atol=1e-9)
        assert np.allclose(out["metrics"][:, 2], t1 * (1 + 2 * e), rtol=0, atol=1e-9)
        for k in range(len(e)):     # the k-th flight after the first fall lasts 2 e^k t1
            times = t1[k] * (1 + 2 * np.cumsum(np.r_[0.0, e[k] ** np.arange(1, 12)]))
            assert out["metrics"][k, 0] == np.count_nonzero(times <= t_end)
        assert np.isnan(out["metrics"][:, 3]).all()
    # groups whose logs fit LOG_BYTES: a row is the time, the state and work, the inputs, the flow and d, 8 bytes each
    row = 8 * (2 + model.nx + model.nw + len(model.input_names) + model.nd)
    monkeypatch.setattr(batch, "LOG_BYTES", 3 * row * (round(t_end / settings.dt) + 1) - 1)  # (under three points')
    sizes = []

    class Counted(batch.Batch):
        def __init__(self, model, settings, starts, *rest, **options):
            sizes.append(len(starts))
            super().__init__(model, settings, starts, *rest, **options)

    monkeypatch.setattr(batch, "Batch", Counted)
    again, _ = run_counting(monkeypatch, settings, pts.values)
    assert sizes == [2] * (len(pts.values) // 2) + [1] * (len(pts.values) % 2)
    assert np.array_equal(again["metrics"], out["metrics"], equal_nan=True)
    assert np.array_equal(again["final"], out["final"])


def test_a_stopped_batch_runs_no_point_and_is_not_kept(compiled):
    pendulum = compiled("double_pendulum")
    settings = Settings.of(pendulum, ("m1",), 10.0)
    worker.remember(pendulum, settings)
    worker.stop()
    try:
        with pytest.raises(KeyboardInterrupt):
            run_batch(settings, np.arange(2), np.array([[1.0], [2.0]]))
    finally:
        worker.resume()
    out = empty_results(pendulum, settings, 1)
    batch.run_batched(out, pendulum, settings, np.array([[1.0]]))        # (resumed: runs again)
    assert out["outcome"][0] == FINISHED_CODE


@pytest.mark.parametrize("name, values", [("compass_gait", [[-1.1], [-1.05]]), ("bouncing_ball_contact", [[0.6]])])
def test_a_batch_keeps_each_jumps_record_and_work_as_the_single_run(compiled, name, values):
    """Beyond what the store keeps: each point's event log (flows left and entered, states around each jump) and
    its work slots (the `jumps` slot: the energy each jump changed) after the batch, equal to the single run's."""
    from andyc.runtime.simulate import start_run

    model = compiled(name)
    names = ("w_stance0",) if name == "compass_gait" else ("e",)
    settings = Settings.of(model, names, 1.6, method="projection")
    values = np.array(values)
    starts = [start_run(model, settings.t_end, compile=False, **worker.point_arguments(model, settings, v))
              for v in values]
    done = batch.Batch(model, settings, starts, 1600)
    assert done.run().all()
    for j, point in enumerate(values):
        run = alone(model, settings, point)
        assert len(run.events["time"]) > 0
        table = starts[j].jumps.table()
        for key in ("time", "jump", "from_flow", "to_flow", "state_before", "state_after", "discrete_after"):
            assert np.array_equal(table[key], run.events[key]), key
        assert np.array_equal(done.X[j, model.nx:], run.work[-1])


def test_a_batch_point_stop_after_ended_has_the_single_runs_run(compiled):
    """A point that stop_after ends between grid points (the compass gait at its second heel strike, strike1) does not
    finish in the batch; its Run (Batch.run_of, as a basin's step reads it) is the single run's to the bit, the
    sample at the jump's instant, after it, included."""
    from andyc.runtime.simulate import start_run

    model = compiled("compass_gait")
    settings = Settings.of(model, ("w_stance0",), 1.6, method="projection", stop_after=(("strike1", 1),))
    values = np.array([[-1.1], [-1.05]])
    starts = [start_run(model, settings.t_end, compile=False, **worker.point_arguments(model, settings, v))
              for v in values]
    done = batch.Batch(model, settings, starts, 1600, log=True)
    assert not done.run().any() and all(s.jumps.finished for s in starts)
    for j, point in enumerate(values):
        run, mine = alone(model, settings, point), done.run_of(j)
        assert run.status == mine.status == FINISHED and run.events["jump"].size == 2
        assert run.time[-1] == run.events["time"][-1] and run.time[-2] < run.time[-1]     # (the jump's sample)
        for key in ("time", "state", "work", "input_values", "flow", "discrete", "energy", "multipliers",
                    "residual_position", "residual_velocity", "power"):
            assert np.array_equal(getattr(mine, key), getattr(run, key), equal_nan=True), key
