"""andyc.plot on synthetic runs: which panels a figure has and what data their lines carry."""

import numpy as np

from andyc.plot import figure_for, plot_run
from andyc.runtime.run import Run


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
