"""andyc.plot's time series and stick figures, on synthetic runs built from small arrays (no model is
compiled): which panels each kind of run gets, that every line carries the run's own arrays, the
stick figures' sticks, plane, shading and ground; that importing andyc.plot leaves the user's
matplotlib backend alone; and one shipped model (the compass gait) end to end through `andyc plot`.
The synthetic runs are tests/support/runs.py's (test_animate.py draws them too)."""

import os

import numpy as np
import pytest
from matplotlib.colors import to_rgb
from PIL import Image

import andyc
from andyc.plot import figure_for, plot_run, plot_sticks, snapshot_indices, stick_edges, stick_plane, sticks_figure
from tests.support.cli import invoke, run_python
from tests.support.runs import (constrained_run, contact_run, friction_contact_run, hybrid_run, inputs_run, make_run,
                                plain_run, planar_run, quaternion_run, spatial_run)


# -- what a figure holds --------------------------------------------------------------------------------

def panels(fig) -> dict:
    """{gid: axes} of the figure's panels (the gid names the panel)."""
    return {ax.get_gid(): ax for ax in fig.axes if ax.get_gid()}


def lines(ax) -> list:
    """[(label, x, y)] of the axes' lines (2-D axes)."""
    return [(line.get_label(), np.asarray(line.get_xdata()), np.asarray(line.get_ydata())) for line in ax.get_lines()]


def assert_lines(ax, run, expected) -> None:
    """The axes' lines are, in order, the (label, y) of `expected`, each against the run's time."""
    drawn = lines(ax)
    assert [label for label, _, _ in drawn] == [label for label, _ in expected]
    for (_, x, y), (_, want) in zip(drawn, expected):
        assert np.array_equal(x, run.time) and np.array_equal(y, want)


def columns(run, names) -> list:
    return [(name, run.column(name)) for name in names]


ENERGY = ["energy", "energy_change"]


@pytest.mark.parametrize("make, expected", [
    (plain_run, ["coordinates", "speeds"] + ENERGY),
    (planar_run, ["trajectories", "frame_x", "frame_y", "coordinates", "speeds"] + ENERGY),
    (spatial_run, ["trajectories", "frame_x", "frame_y", "frame_z", "coordinates", "speeds"] + ENERGY),
    (quaternion_run, ["trajectories", "frame_x", "frame_y", "frame_z", "speeds", "quaternions", "position_signals",
                      "other_signals"] + ENERGY),
    (constrained_run, ["coordinates", "speeds", "multipliers", "residuals"] + ENERGY),
    (inputs_run, ["coordinates", "speeds", "inputs"] + ENERGY),
    (lambda: inputs_run(changing=False), ["coordinates", "speeds"] + ENERGY),
    (hybrid_run, ["trajectories", "flow", "discrete", "frame_x", "frame_y", "coordinates", "coordinates#2", "speeds",
                  "speeds#2"] + ENERGY),
], ids=["plain", "planar", "spatial", "quaternion", "constrained", "inputs", "constant-inputs", "hybrid"])
def test_each_run_gets_the_panels_that_apply_in_order(make, expected):
    run = make()
    fig = figure_for(run)
    assert [ax.get_gid() for ax in fig.axes] == expected
    planar = run.frames and all(np.all(xyz[:, 2] == 0) for xyz in run.frames.values())   # drawn in their plane
    assert all(ax.name == ("3d" if ax.get_gid() == "trajectories" and not planar else "rectilinear")
               for ax in fig.axes)


def test_states_signals_and_energy_panels_carry_the_runs_columns():
    run = quaternion_run()
    p = panels(figure_for(run))
    assert_lines(p["speeds"], run, columns(run, ["wx", "wy", "wz", "vx", "vy", "vz"]))
    assert_lines(p["quaternions"], run, columns(run, ["body_qw", "body_qx", "body_qy", "body_qz"]))
    assert_lines(p["position_signals"], run, columns(run, ["body_x", "body_y", "body_z"]))
    assert_lines(p["other_signals"], run, columns(run, ["spin"]))
    (energy,) = lines(p["energy"])
    assert np.array_equal(energy[2], run.energy)
    (change,) = lines(p["energy_change"])
    assert np.allclose(change[2], (run.energy - run.energy[0]) / np.abs(run.energy).max())

    run = plain_run()
    assert_lines(panels(figure_for(run))["coordinates"], run, columns(run, ["q1", "q2"]))


def test_time_series_share_one_time_axis_labelled_only_at_the_bottom_of_each_column():
    for run in (plain_run(), hybrid_run()):
        fig = figure_for(run)
        series = [ax for ax in fig.axes if ax.get_gid() != "trajectories"]
        assert all(series[0].get_shared_x_axes().joined(series[0], ax) for ax in series)
        labelled = [ax.get_gid() for ax in series if ax.get_xlabel()]
        # one column: the last panel; with frames, the bottom of each column
        assert labelled == (["energy_change"] if not run.frames else ["speeds#2", "energy_change"])


def test_frame_paths_in_3d_and_along_each_axis_carry_the_frames_and_coincident_frames_share_a_line():
    run = quaternion_run()
    p = panels(figure_for(run))
    paths = [np.array(line.get_data_3d()).T for line in p["trajectories"].get_lines()]
    assert len(paths) == 1 and np.array_equal(paths[0], run.frames["body"])   # body and marker: one line
    assert len(p["trajectories"].collections) == 2                               # its start and end marks
    spans = [np.diff(p["trajectories"].get_w_lims()[2 * k:2 * k + 2])[0] for k in range(3)]
    assert np.allclose(spans, spans[0])                                          # one scale along all axes
    for k, gid in enumerate(["frame_x", "frame_y", "frame_z"]):
        ((label, x, y),) = lines(p[gid])
        assert "body" in label and "marker" in label
        assert np.array_equal(x, run.time) and np.array_equal(y, run.frames["body"][:, k])


def test_inputs_panel_carries_every_input_once_any_changes():
    run = inputs_run()
    assert_lines(panels(figure_for(run))["inputs"], run,
                 [("u", run.input_values[:, 0]), ("v", run.input_values[:, 1])])


def test_constrained_run_shows_multipliers_and_residuals_per_row_on_a_log_scale():
    run = constrained_run()
    p = panels(figure_for(run))
    assert_lines(p["multipliers"], run, [("lam_a", run.multipliers[:, 0]), ("lam_b", run.multipliers[:, 1])])
    residuals = p["residuals"]
    assert residuals.get_yscale() == "log"
    drawn = lines(residuals)
    assert len(drawn) == 3                      # phi of the one position row, c of both velocity rows
    want = [run.residual_position[:, 0], run.residual_velocity[:, 0], run.residual_velocity[:, 1]]
    for (_, x, y), w in zip(drawn, want):
        assert np.array_equal(x, run.time) and np.array_equal(y, np.maximum(np.abs(w), 1e-17))
    assert drawn[2][2].min() == 1e-17           # exact zeros floored, not dropped
    styles = [line.get_linestyle() for line in residuals.get_lines()]
    assert styles == ["-", "--", "--"]          # position solid, velocity dashed


# -- hybrid runs: the flow and discrete panels ---------------------------------------------------------

def test_flow_panel_steps_through_the_flows_named_on_its_axis_with_each_jump_marked():
    run = hybrid_run()
    flow = panels(figure_for(run))["flow"]
    assert [label.get_text() for label in flow.get_yticklabels()] == run.flow_names
    assert list(flow.get_yticks()) == [0, 1]
    (line,) = flow.get_lines()
    assert line.get_drawstyle() == "steps-post"
    assert np.array_equal(line.get_xdata(), run.time) and np.array_equal(line.get_ydata(), run.flow)
    marks = {c.get_gid(): c for c in flow.collections}
    assert set(marks) == {"jump:strike2", "jump:strike1"}
    for gid, times in (("jump:strike2", [0.5, 1.7]), ("jump:strike1", [1.2])):
        xs = [segment[:, 0] for segment in marks[gid].get_segments()]
        assert np.allclose(xs, np.array(times)[:, None])           # vertical lines at the jump times
    assert to_rgb(marks["jump:strike2"].get_color()[0]) != to_rgb(marks["jump:strike1"].get_color()[0])
    assert len(flow.get_legend().get_texts()) == 3                  # the flow and each jump


def test_discrete_panel_steps_through_the_discrete_states():
    run = hybrid_run()
    discrete = panels(figure_for(run))["discrete"]
    assert_lines(discrete, run, columns(run, ["fx", "steps"]))
    assert all(line.get_drawstyle() == "steps-post" for line in discrete.get_lines())


def test_one_flow_with_jumps_has_a_flow_panel_and_no_discrete_panel_without_discrete_states():
    run = hybrid_run()
    run.flow, run.flow_names = np.zeros_like(run.flow), ["roll"]
    run.events["from_flow"][:] = run.events["to_flow"][:] = 0
    run.discrete_names, run.discrete = [], np.zeros((len(run.time), 0))
    p = panels(figure_for(run))
    assert [label.get_text() for label in p["flow"].get_yticklabels()] == ["roll"]
    assert "discrete" not in p


def assert_png_at_110_dpi(path, fig) -> None:
    """`path` is a PNG of `fig` at 110 dots per inch."""
    with Image.open(path) as im:
        assert im.format == "PNG"
        assert im.size == tuple(np.round(fig.get_size_inches() * 110).astype(int))


def test_plot_run_writes_the_figure_as_a_png_at_110_dpi(tmp_path):
    run = plain_run()
    plot_run(run, tmp_path / "run.png")
    assert_png_at_110_dpi(tmp_path / "run.png", figure_for(run))


# -- stick figures ---------------------------------------------------------------------------------------

def stick_lines(fig):
    """(axes, {(parent, child, sample): ((x0, x1), (y0, y1))}) of the stick lines (gid 'parent>child@k')."""
    (ax,) = [ax for ax in fig.axes if ax.get_label() != "<colorbar>"]
    found = {}
    for line in ax.get_lines():
        gid = line.get_gid() or ""
        if ">" in gid:
            edge, k = gid.split("@")
            found[(*edge.split(">"), int(k))] = (np.asarray(line.get_xdata()), np.asarray(line.get_ydata()))
    return ax, found


def test_sticks_join_each_frame_to_its_logged_parent_at_the_snapshot_times():
    run = hybrid_run()
    assert stick_edges(run) == [("hip", "foot1"), ("hip", "foot2")]    # not world, not the unlogged knee
    snaps = snapshot_indices(run, count=5)
    jump_samples = np.searchsorted(run.time, run.events["time"], side="right") - 1
    assert {0, len(run.time) - 1} <= set(snaps) and set(jump_samples) <= set(snaps)
    assert np.array_equal(snaps, np.unique(snaps))
    ax, found = stick_lines(sticks_figure(run, count=5))
    assert ax.name == "rectilinear" and ax.get_aspect() == 1.0
    assert set(found) == {(p, c, k) for p, c in stick_edges(run) for k in snaps}
    for (parent, child, k), (xs, ys) in found.items():
        assert np.array_equal(xs, [run.frames[parent][k, 0], run.frames[child][k, 0]])
        assert np.array_equal(ys, [run.frames[parent][k, 1], run.frames[child][k, 1]])
    sticks = [line for line in ax.get_lines() if ">" in (line.get_gid() or "")]
    sample = {line: int(line.get_gid().split("@")[1]) for line in sticks}
    colour = {sample[line]: sum(to_rgb(line.get_color())) for line in sticks}
    assert colour[snaps[0]] > colour[snaps[-1]]                         # earlier snapshots lighter
    assert all((line.get_linestyle() == "--") == (sample[line] in jump_samples) for line in sticks)
    (ground,) = [line for line in ax.get_lines() if line.get_gid() == "ground"]   # the feet touch y = 0
    assert np.allclose(ground.get_ydata(), 0.0)


def test_sticks_of_a_hanging_pendulum_have_no_ground():
    run = planar_run()
    assert stick_plane(run) == (0, 1)
    ax, found = stick_lines(sticks_figure(run, count=4))
    assert {(p, c) for p, c, _ in found} == {("upper", "elbow"), ("elbow", "lower"), ("lower", "tip")}
    assert len(found) == 3 * 4 and not any(line.get_gid() == "ground" for line in ax.get_lines())


def test_sticks_of_3d_frames_are_drawn_in_the_plane_they_move_most_in():
    t = np.linspace(0.0, 2.0, 40)
    tip = np.stack([np.sin(t), 0.01 * np.sin(t), -np.cos(t)], axis=1)     # swings in x-z
    run = make_run(["q", "q_dot"], 1, 1, np.column_stack([t, np.ones_like(t)]),
                   frames={"base": np.zeros((40, 3)), "tip": tip}, frame_parents={"base": "world", "tip": "base"})
    assert stick_plane(run) == (0, 2)
    _, found = stick_lines(sticks_figure(run, count=3))
    assert len(found) == 3
    for (_, _, k), (xs, ys) in found.items():
        assert np.array_equal(xs, [0.0, tip[k, 0]]) and np.array_equal(ys, [0.0, tip[k, 2]])


def test_sticks_need_a_frame_with_a_logged_parent(tmp_path):
    run = quaternion_run()                                  # frames logged, parents unknown
    assert stick_edges(run) == []
    with pytest.raises(ValueError, match="parent"):
        sticks_figure(run)
    run = hybrid_run()
    plot_sticks(run, tmp_path / "sticks.png")
    assert_png_at_110_dpi(tmp_path / "sticks.png", sticks_figure(run))


# -- matplotlib's state --------------------------------------------------------------------------------

def test_importing_and_plotting_leave_the_users_backend_alone(tmp_path):
    """A user who chose a backend keeps it, and pyplot is never imported."""
    code = f"""
import sys
import matplotlib
matplotlib.use("pdf")
import numpy as np
import andyc.plot
from andyc.runtime.run import Run
t = np.linspace(0, 1, 20)
tip = np.stack([np.sin(t), -np.cos(t), 0 * t], axis=1)
run = Run(model="m", spec_sha256="", method="rk4", dt=0.05, nq=1, nv=1, rtol=0, atol=0, t_end=1.0, parameters={{}},
          inputs={{}}, state_names=["q", "v"], time=t, state=np.zeros((20, 2)), energy=np.ones(20),
          frames={{"pivot": 0 * tip, "tip": tip}}, frame_parents={{"pivot": "world", "tip": "pivot"}})
andyc.plot.plot_run(run, {str(tmp_path / 'run.png')!r})
andyc.plot.plot_sticks(run, {str(tmp_path / 'sticks.png')!r})
andyc.plot.animate_run(run, {str(tmp_path / 'run.gif')!r}, max_frames=3)
print("matplotlib.pyplot" in sys.modules, matplotlib.get_backend())
"""
    env = {k: v for k, v in os.environ.items() if k != "MPLBACKEND"}
    done = run_python(code, env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout.split() == ["False", "pdf"]
    assert all((tmp_path / name).stat().st_size > 0 for name in ("run.png", "sticks.png", "run.gif"))


# -- andyc plot ------------------------------------------------------------------------------------------

def test_cli_plot_writes_sticks_only_for_runs_with_frame_parents(tmp_path):
    walker = hybrid_run().save(tmp_path / "walker.h5")
    result = invoke("plot", walker, "-o", tmp_path / "other.png")
    assert result.exit_code == 0, result.output
    assert (tmp_path / "other.png").stat().st_size > 0 and (tmp_path / "other_sticks.png").stat().st_size > 0
    assert "other_sticks.png" in result.output

    orphans = planar_run()
    orphans.frame_parents = {}                              # the same frames, their parents unknown
    result = invoke("plot", orphans.save(tmp_path / "orphans.h5"))
    assert result.exit_code == 0, result.output
    assert (tmp_path / "orphans.png").stat().st_size > 0
    assert not (tmp_path / "orphans_sticks.png").exists() and "orphans_sticks" not in result.output


def test_compass_gait_through_andyc_plot(compiled, tmp_path):
    """End to end: a shipped hybrid model, simulated with its frames logged, through the run file and
    `andyc plot` (the figure, the stick figures, the animation)."""
    model = compiled("compass_gait")
    run = andyc.simulate(model, 2.0, dt=1e-3, method="projection", frames="all", every=10, progress=False)
    assert len(run.events["time"]) >= 2
    path = run.save(tmp_path / "r.h5")
    result = invoke("plot", path)
    assert result.exit_code == 0, result.output
    for name in ("r.png", "r_sticks.png"):
        with Image.open(tmp_path / name) as im:
            assert im.format == "PNG" and min(im.size) > 300
    assert "r_sticks.png" in result.output
    result = invoke("plot", path, "--animate", "--frames-max", 6)
    assert result.exit_code == 0, result.output
    with Image.open(tmp_path / "r.gif") as im:
        assert im.format == "GIF" and im.n_frames == 6
    assert ("andyc view" in result.output) == bool(run.display.get("shapes"))      # a pointer to the shapes


def test_animating_a_contact_run_points_to_the_viewer_for_its_ground_and_forces(tmp_path):
    run = contact_run()
    run.frames = {"ball": np.column_stack([np.zeros_like(run.time), run.state[:, 0], np.zeros_like(run.time)])}
    run.frame_parents = {"ball": "world"}
    path = run.save(tmp_path / "c.h5")
    result = invoke("plot", path, "--animate", "--frames-max", 3)
    assert result.exit_code == 0, result.output
    assert f"ground and contact forces are drawn by `andyc view {path}`" in result.output


def test_a_contact_with_friction_adds_its_friction_force_dashed():
    """Friction (issue 21): the contacts panel draws the friction force along +tangent, dashed in the contact's
    colour: -mu lam_n = -4.905 N while it slips forwards (t < 1), the stick row's multiplier, 0.25 N, once it sticks."""
    run = friction_contact_run()
    assert run.contact_modes[:, 0].tolist() == np.where(run.time >= 1.0, 1, 2).tolist()
    fig = figure_for(run)
    (ax,) = [a for a in fig.axes if a.get_gid() == "contacts"]
    normal, friction = ax.get_lines()
    np.testing.assert_array_equal(normal.get_ydata(), np.full(len(run.time), 9.81))
    np.testing.assert_allclose(friction.get_ydata(), np.where(run.time >= 1.0, 0.25, -4.905), rtol=0, atol=1e-15)
    assert friction.get_linestyle() == "--" and friction.get_color() == normal.get_color()
    assert ax.get_ylabel() == "contacts: normal and friction force, N"


def test_a_run_with_contacts_gets_their_normal_forces_and_closed_spans():
    """The contacts panel: each contact's normal force (0 while open, whatever the multiplier holds then), and
    its closed span shaded: here t >= 1 s, in the contact's colour."""
    run = contact_run()
    fig = figure_for(run)
    (ax,) = [a for a in fig.axes if a.get_gid() == "contacts"]
    (line,) = ax.get_lines()
    np.testing.assert_array_equal(line.get_ydata(), np.where(run.time >= 1.0, 9.81, 0.0))
    (shade,) = ax.collections
    xs = np.concatenate([path.vertices[:, 0] for path in shade.get_paths()])
    assert xs.min() == pytest.approx(1.0) and xs.max() == pytest.approx(2.0)
    assert [a.get_gid() for a in fig.axes].index("contacts") < [a.get_gid() for a in fig.axes].index("multipliers")


def test_a_run_whose_elements_do_work_gets_its_energy_balance_not_the_change_of_e():
    """A damped run: E falls; the work W of the damper is -(E(0) - E); the lower panel is E - E(0) - W in J
    (the summary's residual), the upper one E beside E(0) + W."""
    t = np.linspace(0.0, 2.0, 41)
    energy = 1.0 * np.exp(-t)
    work = (energy - 1.0 + 1e-6 * np.sin(t))[:, None]           # W with an error of 1e-6 sin t
    run = make_run(["q", "q_dot"], 1, 1, np.column_stack([t, t]), work_names=["damper"], work=work)
    run.energy = energy
    p = panels(figure_for(run))
    (label, x, balance), = lines(p["energy_change"])
    assert label == "E - E(0) - W" and "J" in p["energy_change"].get_ylabel()
    assert np.allclose(balance, -1e-6 * np.sin(t), atol=1e-15)
    drawn = {label: y for label, _, y in lines(p["energy"])}
    assert np.array_equal(drawn["E"], energy) and np.allclose(drawn["E(0) + W"], energy + 1e-6 * np.sin(t))
