"""andyc.plot on synthetic runs: which panels a figure has and what data their lines carry; the
stick figures; and one real hybrid run (the compass gait) through HDF5, the plots and `andyc plot`."""

import numpy as np
import pytest
from click.testing import CliRunner
from matplotlib.colors import to_rgb

import andyc
from andyc import cli
from andyc.plot import figure_for, plot_run, plot_sticks, snapshot_indices, stick_edges, stick_plane, sticks_figure
from andyc.runtime.run import Run, read_h5


def make_run(state_names, nq, nv, state, frames=None):
    t = np.linspace(0.0, 2.0, state.shape[0])
    return Run(model="synthetic", spec_sha256="0" * 64, method="rk4", dt=1e-3, nq=nq, nv=nv, rtol=1e-8,
               atol=1e-10, t_end=2.0, parameters={}, inputs={}, state_names=state_names, time=t, state=state,
               energy=1.0 + 0.01 * np.sin(t), frames=frames or {})


def swing_bar_like_run(n=50):
    """qh, speeds qh_dot wx wy wz, a unit quaternion and a position signal; bar1 and ball coincide."""
    t = np.linspace(0.0, 2.0, n)
    half = 0.5 * t
    quaternion = np.stack([np.cos(half), 0.6 * np.sin(half), 0.8 * np.sin(half), 0 * t], axis=1)
    state = np.column_stack([t, np.ones(n), np.sin(t), np.cos(t), t**2, quaternion, t, 2 * t, 3 * t])
    names = ["qh", "qh_dot", "wx", "wy", "wz", "ball_qw", "ball_qx", "ball_qy", "ball_qz", "tip_x", "tip_y", "tip_z"]
    bar1 = np.stack([np.cos(t), np.sin(t), 0 * t], axis=1)
    bar2 = bar1 + np.stack([0 * t, 0 * t, -1 - 0.1 * np.sin(3 * t)], axis=1)
    return make_run(names, 1, 4, state, frames={"bar1": bar1, "ball": bar1.copy(), "bar2": bar2})


def axes_by_ylabel(fig):
    return {ax.get_ylabel(): ax for ax in fig.axes if ax.name != "3d"}


def test_swing_bar_like_run_has_3d_trajectories_frame_xyz_and_quaternion_panels():
    run = swing_bar_like_run()
    fig = figure_for(run)
    (ax3d,) = [ax for ax in fig.axes if ax.name == "3d"]
    paths = {line.get_label(): np.array(line.get_data_3d()).T for line in ax3d.get_lines()}
    assert set(paths) == {"bar1 = ball", "bar2"}                      # coincident frames share one line
    assert np.array_equal(paths["bar2"], run.frames["bar2"])
    spans = [np.diff(lim)[0] for lim in (ax3d.get_xlim3d(), ax3d.get_ylim3d(), ax3d.get_zlim3d())]
    assert np.allclose(spans, spans[0])                                 # equal aspect
    assert len(ax3d.collections) == 4                                   # start and end of each path

    panels = axes_by_ylabel(fig)
    assert {"frame x, m", "frame y, m", "frame z, m", "energy E, J"} <= set(panels)
    z = {line.get_label(): line.get_ydata() for line in panels["frame z, m"].get_lines()}
    assert np.array_equal(z["bar2"], run.frames["bar2"][:, 2])
    quaternion = panels["quaternion (w, x, y, z), 1"].get_lines()
    assert [line.get_label() for line in quaternion] == ["ball_qw", "ball_qx", "ball_qy", "ball_qz"]
    for line in quaternion:
        assert np.array_equal(line.get_xdata(), run.time)
        assert np.array_equal(line.get_ydata(), run.column(line.get_label()))
    assert [line.get_label() for line in panels["speeds v, rad/s | m/s"].get_lines()] == ["qh_dot", "wx", "wy", "wz"]
    assert [line.get_label() for line in panels["position signals, m"].get_lines()] == ["tip_x", "tip_y", "tip_z"]
    coordinates = panels["coordinates q, rad | m"]
    assert all(coordinates.get_shared_x_axes().joined(coordinates, ax) for ax in panels.values())


def test_planar_frames_leave_out_the_axis_they_do_not_move_along():
    run = swing_bar_like_run()
    run.frames = {name: xyz * [1, 1, 0] for name, xyz in run.frames.items()}
    labels = set(axes_by_ylabel(figure_for(run)))
    assert {"frame x, m", "frame y, m"} <= labels and "frame z, m" not in labels


def test_run_without_frames_or_signals_has_only_states_and_energy(tmp_path):
    n = 30
    t = np.linspace(0.0, 2.0, n)
    run = make_run(["q1", "q2", "q1_dot", "q2_dot"], 2, 2, np.column_stack([t, -t, np.ones(n), -np.ones(n)]))
    fig = figure_for(run)
    assert not any(ax.name == "3d" for ax in fig.axes)
    assert [ax.get_ylabel() for ax in fig.axes] == [
        "coordinates q, rad | m", "speeds v, rad/s | m/s", "energy E, J", "(E - E(0)) / max|E|, 1"]
    assert np.array_equal(fig.axes[1].get_lines()[1].get_ydata(), -np.ones(n))
    plot_run(run, tmp_path / "run.png")
    assert (tmp_path / "run.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_constrained_run_shows_multipliers_and_residuals_per_row():
    run = make_run(["q", "q_dot"], 1, 1, np.zeros((50, 2)))
    run.multiplier_names = ["lam_a", "lam_b"]
    run.multipliers = np.column_stack([np.linspace(-1, 1, 50), np.ones(50)])
    run.residual_position = np.full((50, 1), 1e-12)
    run.residual_velocity = np.column_stack([np.full(50, 1e-13), np.zeros(50)])   # exact zeros: floored
    panels = axes_by_ylabel(figure_for(run))
    lines = panels["multipliers λ, N | N m"].get_lines()
    assert [line.get_label() for line in lines] == ["lam_a", "lam_b"]
    residuals = panels["constraint residuals"]
    assert residuals.get_yscale() == "log"
    assert [line.get_label() for line in residuals.get_lines()] == ["φ lam_a", "c lam_a", "c lam_b"]
    assert residuals.get_lines()[2].get_ydata().min() == 1e-17


# -- hybrid runs: the flow and discrete panels ---------------------------------------------------

def walker_like_run(n=201):
    """A planar two-legged stick walker: flows stance1/stance2 swapped by strike2 at t = 0.5 and
    strike1 at t = 1.2, strike2 again at 1.7; discrete fx (stance foot) and a step count. Frames:
    hip (parent world), foot1 and foot2 (parent hip), marker (parent 'knee', not logged)."""
    t = np.linspace(0.0, 2.0, n)
    event_times = np.array([0.5, 1.2, 1.7])
    flow = np.searchsorted(event_times, t, side="right") % 2
    steps = np.searchsorted(event_times, t, side="right").astype(float)
    fx = 0.4 * steps
    hip = np.stack([0.4 * t, 1.0 - 0.02 * np.sin(np.pi * t) ** 2, 0 * t], axis=1)
    swing = np.stack([0.8 * t, 0.05 * np.abs(np.sin(2 * np.pi * t)), 0 * t], axis=1)
    stance = np.stack([fx, 0 * t, 0 * t], axis=1)
    foot1 = np.where((flow == 0)[:, None], stance, swing)
    foot2 = np.where((flow == 1)[:, None], stance, swing)
    marker = hip + [0.1, -0.5, 0.0]
    state = np.column_stack([hip[:, 0], hip[:, 1], np.gradient(hip[:, 0], t), np.gradient(hip[:, 1], t)])
    run = make_run(["x", "y", "x_dot", "y_dot"], 2, 2, state,
                   frames={"hip": hip, "foot1": foot1, "foot2": foot2, "marker": marker})
    run.flow, run.flow_names = flow, ["stance1", "stance2"]
    run.discrete_names, run.discrete = ["fx", "steps"], np.column_stack([fx, steps])
    k = np.searchsorted(t, event_times)
    run.jump_names = ["strike2", "strike1"]
    run.events = {"time": event_times, "jump": np.array([0, 1, 0], np.int32),
                  "from_flow": np.array([0, 1, 0], np.int32), "to_flow": np.array([1, 0, 1], np.int32),
                  "state_before": state[k - 1], "state_after": state[k], "discrete_after": run.discrete[k]}
    run.frame_parents = {"hip": "world", "foot1": "hip", "foot2": "hip", "marker": "knee"}
    return run


def test_hybrid_run_has_flow_panel_with_flow_names_and_jumps_marked():
    run = walker_like_run()
    fig = figure_for(run)
    panels = axes_by_ylabel(fig)
    flow = panels["flow"]
    assert [label.get_text() for label in flow.get_yticklabels()] == ["stance1", "stance2"]
    assert list(flow.get_yticks()) == [0, 1]
    (line,) = flow.get_lines()
    assert line.get_drawstyle() == "steps-post"
    assert np.array_equal(line.get_xdata(), run.time) and np.array_equal(line.get_ydata(), run.flow)
    marks = {c.get_label(): c for c in flow.collections}           # one set of dashed lines per jump
    assert set(marks) == {"strike2 (2)", "strike1 (1)"}
    for name, times in (("strike2 (2)", [0.5, 1.7]), ("strike1 (1)", [1.2])):
        xs = [segment[:, 0] for segment in marks[name].get_segments()]
        assert np.allclose(xs, np.array(times)[:, None])           # vertical lines at the jump times
    legend = [text.get_text() for text in flow.get_legend().get_texts()]
    assert legend == ["active flow", "strike2 (2)", "strike1 (1)"]
    # top of the time series, sharing time with the others; only the bottom axis is labelled
    series = [ax for ax in fig.axes if ax.name != "3d" and ax.get_label() != "<colorbar>"]
    assert fig.axes[1] is flow
    assert all(flow.get_shared_x_axes().joined(flow, ax) for ax in series)
    assert flow.get_xlabel() == "" and not any(t.get_visible() and t.get_text() for t in flow.get_xticklabels())


def test_hybrid_run_has_discrete_panel_carrying_the_discrete_states():
    run = walker_like_run()
    panels = axes_by_ylabel(figure_for(run))
    lines = panels["discrete states"].get_lines()
    assert [line.get_label() for line in lines] == ["fx", "steps"]
    for j, line in enumerate(lines):
        assert line.get_drawstyle() == "steps-post"
        assert np.array_equal(line.get_xdata(), run.time)
        assert np.array_equal(line.get_ydata(), run.discrete[:, j])
    order = [ax.get_ylabel() for ax in figure_for(run).axes if ax.name != "3d"]
    assert order[:3] == ["flow", "discrete states", "frame x, m"]


def test_one_flow_with_jumps_has_a_flow_panel_but_no_discrete_panel_without_discrete_states():
    run = walker_like_run()
    run.flow, run.flow_names = np.zeros_like(run.flow), ["roll"]
    run.events["from_flow"][:] = run.events["to_flow"][:] = 0
    run.discrete_names, run.discrete = [], np.zeros((len(run.time), 0))
    panels = axes_by_ylabel(figure_for(run))
    assert [label.get_text() for label in panels["flow"].get_yticklabels()] == ["roll"]
    assert "discrete states" not in panels


def test_run_without_flows_or_jumps_has_no_flow_or_discrete_panel():
    for run in (swing_bar_like_run(), make_run(["q", "q_dot"], 1, 1, np.zeros((20, 2)))):
        labels = set(axes_by_ylabel(figure_for(run)))
        assert "flow" not in labels and "discrete states" not in labels


def test_hybrid_run_without_frames_has_flow_and_discrete_panels_on_top(tmp_path):
    run = walker_like_run()
    run.frames, run.frame_parents = {}, {}
    fig = figure_for(run)
    assert [ax.get_ylabel() for ax in fig.axes] == [
        "flow", "discrete states", "coordinates q, rad | m", "speeds v, rad/s | m/s", "energy E, J",
        "(E - E(0)) / max|E|, 1"]
    plot_run(run, tmp_path / "run.png")
    assert (tmp_path / "run.png").stat().st_size > 0


# -- stick figures ---------------------------------------------------------------------------------

def stick_lines(fig):
    """{(parent, child, sample): ((x0, x1), (y0, y1))} of the stick lines (gid 'parent>child@k')."""
    (ax,) = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    lines = {}
    for line in ax.get_lines():
        gid = line.get_gid() or ""
        if ">" in gid:
            edge, k = gid.split("@")
            lines[(*edge.split(">"), int(k))] = (np.asarray(line.get_xdata()), np.asarray(line.get_ydata()))
    return ax, lines


def test_sticks_join_each_frame_to_its_logged_parent_at_the_snapshot_times():
    run = walker_like_run()
    assert stick_edges(run) == [("hip", "foot1"), ("hip", "foot2")]    # not world, not the unlogged knee
    snaps = snapshot_indices(run, count=5)
    jump_samples = np.searchsorted(run.time, run.events["time"], side="right") - 1
    assert {0, len(run.time) - 1} <= set(snaps) and set(jump_samples) <= set(snaps)
    assert np.array_equal(snaps, np.unique(snaps))
    fig = sticks_figure(run, count=5)
    ax, lines = stick_lines(fig)
    assert set(lines) == {(p, c, k) for p, c in stick_edges(run) for k in snaps}
    for (parent, child, k), (xs, ys) in lines.items():
        assert np.array_equal(xs, [run.frames[parent][k, 0], run.frames[child][k, 0]])
        assert np.array_equal(ys, [run.frames[parent][k, 1], run.frames[child][k, 1]])
    # earlier snapshots lighter
    colour = {k: to_rgb(line.get_color()) for line in ax.get_lines() if ">" in (line.get_gid() or "")
              for k in [int(line.get_gid().split("@")[1])]}
    assert sum(colour[snaps[0]]) > sum(colour[snaps[-1]])
    # snapshots at a jump are dashed, the others solid
    styles = {int(line.get_gid().split("@")[1]): line.get_linestyle() for line in ax.get_lines()
              if ">" in (line.get_gid() or "")}
    assert all((styles[k] == "--") == (k in jump_samples) for k in snaps)
    assert ax.get_aspect() == 1.0 and (ax.get_xlabel(), ax.get_ylabel()) == ("world x, m", "world y, m")
    (ground,) = [line for line in ax.get_lines() if line.get_gid() == "ground"]   # the feet touch y = 0
    assert np.allclose(ground.get_ydata(), 0.0)


def test_sticks_of_a_hanging_pendulum_have_no_ground():
    t = np.linspace(0.0, 2.0, 40)
    rod = np.stack([np.sin(t), -np.cos(t), 0 * t], axis=1)
    run = make_run(["q", "q_dot"], 1, 1, np.column_stack([t, np.ones_like(t)]),
                   frames={"pivot": np.zeros((40, 3)), "bob": rod})
    run.frame_parents = {"pivot": "world", "bob": "pivot"}
    ax, lines = stick_lines(sticks_figure(run, count=4))
    assert len(lines) == 4 and not any(line.get_gid() == "ground" for line in ax.get_lines())


def test_sticks_of_3d_frames_are_drawn_in_the_plane_they_move_most_in():
    t = np.linspace(0.0, 2.0, 40)
    tip = np.stack([np.sin(t), 0.01 * np.sin(t), -np.cos(t)], axis=1)     # swings in x-z
    run = make_run(["q", "q_dot"], 1, 1, np.column_stack([t, np.ones_like(t)]),
                   frames={"base": np.zeros((40, 3)), "tip": tip})
    run.frame_parents = {"base": "world", "tip": "base"}
    assert stick_plane(run) == (0, 2)
    ax, lines = stick_lines(sticks_figure(run, count=3))
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("world x, m", "world z, m")
    for (_, _, k), (xs, ys) in lines.items():
        assert np.array_equal(xs, [0.0, tip[k, 0]]) and np.array_equal(ys, [0.0, tip[k, 2]])


def test_sticks_need_a_frame_with_a_logged_parent(tmp_path):
    run = swing_bar_like_run()                                  # frames logged, parents unknown
    assert stick_edges(run) == []
    with pytest.raises(ValueError, match="no stick figure"):
        sticks_figure(run)
    run = walker_like_run()
    plot_sticks(run, tmp_path / "sticks.png")
    assert (tmp_path / "sticks.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# -- andyc plot --------------------------------------------------------------------------------------

def invoke_plot(*args):
    try:
        runner = CliRunner(mix_stderr=False)          # click 8.1
    except TypeError:
        runner = CliRunner()                          # click >= 8.2 always keeps stderr apart
    return runner.invoke(cli.main, ["plot", *map(str, args)])


def test_cli_plot_writes_sticks_only_for_runs_with_frame_parents(tmp_path):
    walker = walker_like_run().save(tmp_path / "walker.h5")
    result = invoke_plot(walker)
    assert result.exit_code == 0, result.output
    assert (tmp_path / "walker.png").stat().st_size > 0 and (tmp_path / "walker_sticks.png").stat().st_size > 0
    assert "walker_sticks.png" in result.output
    result = invoke_plot(walker, "-o", tmp_path / "other.png")
    assert result.exit_code == 0 and (tmp_path / "other_sticks.png").exists()

    plain = swing_bar_like_run().save(tmp_path / "plain.h5")
    result = invoke_plot(plain)
    assert result.exit_code == 0, result.output
    assert result.output.strip() == f"wrote {tmp_path / 'plain.png'}"
    assert not (tmp_path / "plain_sticks.png").exists()


def test_compass_gait_run_plots_after_an_h5_round_trip(compiled, tmp_path):
    model = compiled("compass_gait")
    run = andyc.simulate(model, 2.0, dt=1e-3, method="projection", frames="all", progress=False)
    assert len(run.events["time"]) >= 2
    run = read_h5(run.save(tmp_path / "r.h5"))
    panels = axes_by_ylabel(figure_for(run))
    assert [label.get_text() for label in panels["flow"].get_yticklabels()] == ["stance1", "stance2"]
    assert np.array_equal(panels["flow"].get_lines()[0].get_ydata(), run.flow)
    assert [line.get_label() for line in panels["discrete states"].get_lines()] == ["fx"]
    _, lines = stick_lines(sticks_figure(run))
    assert {(p, c) for p, c, _ in lines} == {("hip", "leg1"), ("leg1", "foot1"), ("hip", "leg2"), ("leg2", "foot2")}
    plot_run(run, tmp_path / "main.png")
    plot_sticks(run, tmp_path / "sticks.png")
    assert (tmp_path / "main.png").stat().st_size > 0 and (tmp_path / "sticks.png").stat().st_size > 0
    result = invoke_plot(tmp_path / "r.h5")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "r.png").stat().st_size > 0 and (tmp_path / "r_sticks.png").stat().st_size > 0
    assert "r_sticks.png" in result.output
