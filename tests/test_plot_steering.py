"""Steerable plots (andyc.plot.select, `andyc plot --signals/--window`) on synthetic runs built from
small arrays: globs choose the signals, a window keeps the samples and events inside it, quantities of
different kinds (angles, lengths, ...) or scales (a spin beside a lean) get axes of their own and each
line carries the run's own values; the ground is drawn only where the model defines one, at its
height; planar runs are drawn in their plane. The model side (andyc.spec.display: units and the ground
from the Spec) is checked against the model files, and a compiled model's run carries it."""

from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import andyc
from andyc import cli
from andyc.plot import animation_view, figure_for, sticks_figure
from andyc.plot.select import SCALE_RATIO, group_signals, select_signals, split_by_scale, window
from andyc.runtime.run import Run
from andyc.runtime.runfiles import read_h5
from andyc.spec.display import display

MODELS = Path(__file__).resolve().parents[1] / "models"


def disk_run(n=401, units=True, ground=None) -> Run:
    """A rolling disk: lean (±0.2 rad), spin (0 .. 150 rad), x, y of its contact (m), their rates;
    frames centre (parent world) and rim (parent centre), both moving in 3-D; two jumps."""
    t = np.linspace(0.0, 4.0, n)
    lean, spin = 0.2 * np.sin(3 * t), 37.5 * t
    x, y = 0.5 * np.cos(t), 0.5 * np.sin(t)
    state = np.column_stack([lean, spin, x, y, 0.6 * np.cos(3 * t), np.full(n, 37.5), -0.5 * np.sin(t),
                             0.5 * np.cos(t)])
    names = ["lean", "spin", "x", "y", "lean_dot", "spin_dot", "x_dot", "y_dot"]
    centre = np.column_stack([x, y, 0.3 + 0.01 * np.cos(3 * t)])
    rim = centre + 0.3 * np.column_stack([np.cos(spin), 0 * t, np.sin(spin)])
    unit = {"lean": "rad", "spin": "rad", "x": "m", "y": "m", "lean_dot": "rad/s", "spin_dot": "rad/s",
            "x_dot": "m/s", "y_dot": "m/s"}
    events = {"time": np.array([1.0, 3.0]), "jump": np.array([0, 0], np.int32),
              "from_flow": np.array([0, 0], np.int32), "to_flow": np.array([0, 0], np.int32),
              "state_before": state[[100, 300]], "state_after": state[[100, 300]], "discrete_after": np.zeros((2, 0))}
    return Run(model="disk", spec_sha256="0" * 64, method="rk4", dt=t[1] - t[0], nq=4, nv=4, rtol=0, atol=0,
               t_end=4.0, parameters={}, inputs={}, state_names=names, time=t, state=state,
               energy=1.0 + 1e-3 * np.sin(t), frames={"centre": centre, "rim": rim},
               frame_parents={"centre": "world", "rim": "centre"}, jump_names=["bump"], events=events,
               multiplier_names=["lam_n"], multipliers=np.column_stack([9.81 + np.sin(t)]),
               display={"units": unit if units else {}, "ground": ground})


def walker_run(n=201, ground=None) -> Run:
    """A planar stick walker whose feet touch y = 0 (x-y plane), with the ground given or not."""
    t = np.linspace(0.0, 2.0, n)
    hip = np.column_stack([0.4 * t, 1.0 + 0.02 * np.sin(5 * t), 0 * t])
    foot1 = np.column_stack([0.8 * t, 0.05 * np.abs(np.sin(2 * np.pi * t)), 0 * t])
    foot2 = np.column_stack([0.2 + 0 * t, 0 * t, 0 * t])
    state = np.column_stack([hip[:, 0], hip[:, 1], np.full(n, 0.4), 0.1 * np.cos(5 * t)])
    return Run(model="walker", spec_sha256="0" * 64, method="rk4", dt=t[1] - t[0], nq=2, nv=2, rtol=0, atol=0,
               t_end=2.0, parameters={}, inputs={}, state_names=["x", "y", "x_dot", "y_dot"], time=t, state=state,
               energy=np.ones(n), frames={"hip": hip, "foot1": foot1, "foot2": foot2},
               frame_parents={"hip": "world", "foot1": "hip", "foot2": "hip"}, display={"ground": ground})


def panels(fig) -> dict:
    return {ax.get_gid(): ax for ax in fig.axes if ax.get_gid()}


def drawn(ax) -> dict:
    return {line.get_label(): (np.asarray(line.get_xdata()), np.asarray(line.get_ydata())) for line in ax.get_lines()
            if not line.get_label().startswith("_")}


# -- choosing signals and a window ---------------------------------------------------------------------

def test_globs_choose_signals_in_the_runs_order_and_a_pattern_matching_nothing_names_the_signals():
    run = disk_run()
    assert select_signals(run, ["*_dot"]) == ["lean_dot", "spin_dot", "x_dot", "y_dot"]
    assert select_signals(run, ["energy", "s?in", "lam_*"]) == ["spin", "lam_n", "energy"]
    assert select_signals(run, ["x*", "x"]) == ["x", "x_dot"]
    with pytest.raises(ValueError, match="no signal .* matches 'tilt'.*lean, spin"):
        select_signals(run, ["tilt"])


def test_a_window_keeps_the_samples_and_events_inside_it():
    run = disk_run()
    part = window(run, 0.5, 2.0)
    inside = (run.time >= 0.5) & (run.time <= 2.0)
    assert np.array_equal(part.time, run.time[inside]) and part.time[0] >= 0.5 and part.time[-1] <= 2.0
    assert np.array_equal(part.state, run.state[inside]) and np.array_equal(part.energy, run.energy[inside])
    assert np.array_equal(part.frames["rim"], run.frames["rim"][inside])
    assert np.array_equal(part.multipliers, run.multipliers[inside])
    assert list(part.events["time"]) == [1.0] and part.events["state_after"].shape == (1, 8)
    assert np.array_equal(window(run, None, 1.0).time, run.time[run.time <= 1.0])
    assert np.array_equal(window(run, 3.0, None).time, run.time[run.time >= 3.0])
    with pytest.raises(ValueError, match="no sample"):
        window(run, 5.0, 6.0)


# -- one axis per kind and scale -----------------------------------------------------------------------

def test_a_spin_gets_its_own_axis_so_the_lean_is_not_flattened():
    run = disk_run()
    groups = group_signals(run, ["lean", "spin", "x", "y"])
    assert groups == [("angles", ["spin"]), ("angles", ["lean"]), ("lengths", ["x", "y"])]
    p = panels(figure_for(run))
    assert {"coordinates:angles", "coordinates:angles#2", "coordinates:lengths"} <= set(p)
    lean_axis = p["coordinates:angles#2"]
    assert set(drawn(lean_axis)) == {"lean"}
    x, y = drawn(lean_axis)["lean"]
    assert np.array_equal(x, run.time) and np.array_equal(y, run.column("lean"))
    lo, hi = lean_axis.get_ylim()
    assert hi - lo < 1.0                     # scaled to the lean (0.4 rad peak to peak), not to the spin
    assert "rad" in lean_axis.get_ylabel() and "m" in p["coordinates:lengths"].get_ylabel()
    # speeds: the constant spin rate (37.5 rad/s) would flatten lean_dot (1.2 peak to peak): apart
    assert set(drawn(p["speeds:angular_speeds"])) == {"lean_dot"}
    assert set(drawn(p["speeds:angular_speeds#2"])) == {"spin_dot"}
    assert set(drawn(p["speeds:speeds"])) == {"x_dot", "y_dot"}


def test_without_units_the_signals_split_by_scale_only():
    run = disk_run(units=False)
    assert split_by_scale(run, ["lean", "spin", "x", "y"]) == [["spin"], ["lean", "x", "y"]]
    assert [g for g in panels(figure_for(run)) if g.startswith("coordinates")] == ["coordinates", "coordinates#2"]
    # within SCALE_RATIO, one axis; a constant joins an axis it does not stretch past that
    t = run.time
    lean = np.ptp(run.column("lean"))
    run.state[:, 2], run.state[:, 3] = 0.1, t / t[-1] * lean / (0.5 * SCALE_RATIO)     # y spans lean / 10
    assert split_by_scale(run, ["lean", "x", "y"]) == [["lean", "x", "y"]]
    run.state[:, 3] /= 4        # lean / 40: past SCALE_RATIO below the lean, its own axis
    assert split_by_scale(run, ["lean", "x", "y"]) == [["lean", "x"], ["y"]]
    run.state[:, 2] = 50.0      # a constant far off every line: an axis of the constants
    assert split_by_scale(run, ["lean", "x", "y"]) == [["lean"], ["y"], ["x"]]


def test_chosen_signals_get_one_axis_per_group_each_carrying_the_runs_values():
    run = disk_run()
    fig = figure_for(run, ["lean", "spin", "x", "lam_n", "energy"])
    p = panels(fig)
    assert list(p) == ["flow", "signals:angles", "signals:angles#2", "signals:lengths", "signals:multipliers",
                       "signals:energy"]
    for gid, name in (("signals:angles", "spin"), ("signals:angles#2", "lean"), ("signals:lengths", "x")):
        assert set(drawn(p[gid])) == {name}
        assert np.array_equal(drawn(p[gid])[name][1], run.column(name))
    assert np.array_equal(drawn(p["signals:multipliers"])["lam_n"][1], run.multipliers[:, 0])
    assert np.array_equal(drawn(p["signals:energy"])["energy"][1], run.energy)
    assert not any(ax.name == "3d" for ax in fig.axes)


# -- planes and the ground -----------------------------------------------------------------------------

def test_a_planar_run_is_drawn_in_its_plane_and_a_spatial_one_in_3d():
    assert panels(figure_for(walker_run()))["trajectories"].name == "rectilinear"
    assert panels(figure_for(disk_run()))["trajectories"].name == "3d"
    traj = panels(figure_for(walker_run()))["trajectories"]
    paths = [np.column_stack(line.get_data()) for line in traj.get_lines()]
    assert any(np.array_equal(p, walker_run().frames["foot1"][:, :2]) for p in paths)


@pytest.mark.parametrize("ground, expect", [(None, None), ({"axis": 1, "height": 0.0}, 0.0),
                                            ({"axis": 1, "height": -0.1}, -0.1), ({"axis": 2, "height": 0.0}, None)])
def test_the_ground_is_drawn_only_where_the_model_has_one_at_its_height(ground, expect):
    run = walker_run(ground=ground)                  # the feet touch y = 0 in every case
    (ax,) = [a for a in sticks_figure(run).axes if a.get_label() != "<colorbar>"]
    lines = [line for line in ax.get_lines() if line.get_gid() == "ground"]
    view = animation_view(run)
    if expect is None:
        assert lines == [] and not view["ground"]
    else:
        assert np.allclose(lines[0].get_ydata(), expect) and view["ground"] and view["ground_height"] == expect


# -- the model's side: units and the ground from the Spec ----------------------------------------------

def test_units_and_ground_come_from_the_links_and_the_constraints(tmp_path):
    walker = display(andyc.load(f"{MODELS}/passive_walker.yaml"))
    assert walker["ground"] == {"axis": 1, "height": 0.0}          # iFootY: ifoot.y, gravity along -y (tilted)
    assert {walker["units"][k] for k in ("qi1", "qi2", "qo1", "qo2")} == {"rad"}
    assert walker["units"]["qx"] == "m" and walker["units"]["qx_dot"] == "m/s"
    assert display(andyc.load(f"{MODELS}/double_pendulum.yaml"))["ground"] is None
    assert display(andyc.load(f"{MODELS}/bouncing_ball.yaml"))["ground"] == {"axis": 1, "height": 0.0}
    swing = display(andyc.load(f"{MODELS}/swing_bar.yaml"))
    assert swing["ground"] is None and swing["units"]["wx"] == "rad/s" and swing["units"]["ball_qw"] == "1"
    model = tmp_path / "stilt.yaml"
    model.write_text("""name: stilt
parameters: {h0: 0.25, g: 9.81}
coordinates: {z: {initial: 1}, th: {}, s: {}}
gravity: [0, 0, -g]
frames:
  - {name: top, parent: world, prismatic: z, axis: z}
  - {name: leg, parent: top, revolute: th, axis: x}
  - {name: foot, parent: leg, translation: [0, 0, -1]}
  - {name: slide, parent: world, prismatic: s, axis: x}
bodies: [{name: m, frame: top, mass: 1}, {name: n, frame: slide, mass: 1}]
constraints: [{name: stand, holonomic: foot.z - h0}]
""")
    stilt = display(andyc.load(model))
    assert stilt["ground"] == {"axis": 2, "height": 0.25}
    assert stilt["units"] == {"z": "m", "z_dot": "m/s", "th": "rad", "th_dot": "rad/s", "s": "m", "s_dot": "m/s"}
    model.write_text(model.read_text().replace("gravity: [0, 0, -g]", "gravity: [0, -g, 0]"))
    assert display(andyc.load(model))["ground"] is None              # z is not against gravity there


def test_a_compiled_models_run_file_carries_its_units_and_ground(compiled, tmp_path):
    model = compiled("compass_gait")
    assert model.display == display(andyc.load(f"{MODELS}/compass_gait.yaml"))
    run = andyc.simulate(model, t_end=0.05, dt=1e-3, frames="all")
    assert run.display["ground"] == {"axis": 1, "height": 0.0} and run.display["units"]["th1"] == "rad"
    run.save(tmp_path / "gait.h5")
    assert read_h5(tmp_path / "gait.h5").display == run.display


# -- the command ---------------------------------------------------------------------------------------

def test_plot_command_takes_signals_and_a_window(tmp_path):
    path = disk_run().save(tmp_path / "disk.h5")
    out = tmp_path / "lean.png"
    result = CliRunner().invoke(cli.main, ["plot", str(path), "--signals", "lean,spin", "--signals", "x*",
                                           "--window", "1:2.5", "-o", str(out)])
    assert result.exit_code == 0, result.output
    assert out.exists() and not (tmp_path / "lean_sticks.png").exists()
    assert "lean, spin, x, x_dot" in result.output
    for args, words in ((["--signals", "tilt"], "tilt"), (["--window", "3:1"], "T0 is after T1"),
                        (["--window", "a:b"], "not T0:T1"), (["--window", "9:10"], "no sample"),
                        (["--animate", "--signals", "x"], "not with --animate")):
        result = CliRunner().invoke(cli.main, ["plot", str(path), *args, "-o", str(tmp_path / "x.png")])
        assert result.exit_code == 2 and words in result.output, (args, result.output)
    result = CliRunner().invoke(cli.main, ["plot", str(path), "--window", ":2", "-o", str(tmp_path / "all.png")])
    assert result.exit_code == 0 and (tmp_path / "all_sticks.png").exists()
