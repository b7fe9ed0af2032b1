"""andyc.plot's animation (`andyc plot RUN.h5 --animate`): the samples shown, the sticks, joints,
traces and title drawn at each, the view of a planar and of a spatial run, and the GIF (or MP4,
with ffmpeg) written; on the synthetic runs of tests/support/runs.py (no model is compiled)."""

import re
import shutil

import numpy as np
import pytest
from matplotlib import animation
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from PIL import Image

from andyc.plot import (TRACE_SECONDS, GifWriter, animate_run, animation_figure, animation_samples,
                        animation_view, animation_writer, stick_segments, world_links)
from andyc.runtime.run import Run
from tests.support.cli import invoke
from tests.support.runs import hybrid_run, plain_run, planar_run, spatial_run

GIF_FPS = 100 / 3                   # what fps 30 plays at: GIF frames last whole hundredths of a second


def gif_frames(path) -> list:
    """The frames of a GIF as RGB arrays."""
    with Image.open(path) as im:
        frames = []
        for k in range(im.n_frames):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB")).astype(int))
        return frames


def by_gid(fig) -> dict:
    """{gid: line} of the lines of the animation's 3-D axes."""
    return {line.get_gid(): line for line in fig.axes[0].get_lines()}


# -- what is drawn -----------------------------------------------------------------------------------

def test_samples_are_evenly_spread_from_start_to_end():
    run = planar_run()                                  # 201 samples, 0.01 s apart, over 2 s
    n, dt = len(run.time), run.time[1] - run.time[0]
    samples = animation_samples(run, fps=30, max_frames=20)
    t = run.time[samples]
    assert len(samples) == 20 and t[0] == 0.0 and t[-1] == pytest.approx(2.0)
    assert np.all(np.abs(t - np.linspace(0.0, 2.0, 20)) <= dt / 2 + 1e-12)   # the sample nearest each even time
    assert np.all(np.diff(samples) > 0)
    # uncapped: as many frames as play the run in real time, and never more than the samples
    assert len(animation_samples(run, fps=30, max_frames=300)) == round(2.0 * 30) + 1
    assert np.array_equal(animation_samples(run, fps=1000, max_frames=10_000), np.arange(n))


def test_stick_ends_are_the_logged_frames_at_the_samples():
    run = planar_run()
    samples = animation_samples(run, fps=30, max_frames=24)
    edges, segments = stick_segments(run, samples)
    assert edges == [("upper", "elbow"), ("elbow", "lower"), ("lower", "tip")]   # no world link: upper is at 0
    assert segments.shape == (24, 3, 2, 3)
    for e, (parent, child) in enumerate(edges):
        assert np.array_equal(segments[:, e, 0], run.frames[parent][samples])
        assert np.array_equal(segments[:, e, 1], run.frames[child][samples])


def test_each_frame_draws_the_sticks_joints_trace_and_time_at_its_sample():
    run = planar_run()
    samples = animation_samples(run, fps=30, max_frames=24)
    edges, segments = stick_segments(run, samples)
    fig, update = animation_figure(run, samples)
    lines = by_gid(fig)
    title, dt = fig.texts[-1], run.time[1] - run.time[0]
    for f in (0, 11, 23):
        update(f)
        k = samples[f]
        for e, (parent, child) in enumerate(edges):
            assert np.array_equal(np.array(lines[f"{parent}>{child}"].get_data_3d()).T, segments[f, e])
        joints = np.array(lines["joints"].get_data_3d()).T
        assert np.array_equal(joints, np.stack([xyz[k] for xyz in run.frames.values()]))
        trace = np.array(lines["trace:tip"].get_data_3d()).T        # the last TRACE_SECONDS of the leaf
        first = np.searchsorted(run.time, run.time[k] - TRACE_SECONDS)
        assert np.array_equal(trace, run.frames["tip"][first:k + 1])
        shown = [float(x) for x in re.findall(r"\d+(?:\.\d+)?", title.get_text())]
        assert any(abs(x - run.time[k]) <= dt / 2 + 1e-12 for x in shown), title.get_text()   # the sample's time
    assert set(lines) >= {"trace:tip"} and not any(g.startswith("trace:") and g != "trace:tip" for g in lines)


def test_a_hybrid_run_shows_its_flow_and_colours_each_leg_as_its_foot():
    run = hybrid_run()
    samples = animation_samples(run, fps=30, max_frames=40)
    fig, update = animation_figure(run, samples)
    lines = by_gid(fig)
    for f in (0, 20, 39):
        update(f)
        assert run.flow_names[run.flow[samples[f]]] in fig.texts[-1].get_text()
    for foot in ("foot1", "foot2"):
        assert to_rgb(lines[f"hip>{foot}"].get_color()) == to_rgb(lines[f"trace:{foot}"].get_color())
    assert to_rgb(lines["hip>foot1"].get_color()) != to_rgb(lines["hip>foot2"].get_color())
    assert "ground" in lines                            # the stance foot stands on y = 0


def test_a_planar_run_is_seen_square_on_and_a_spatial_one_in_3d_with_shadows():
    planar, spatial = planar_run(), spatial_run()
    view = animation_view(planar)
    assert view["planar"] and view["up"] == 1 and view["camera"]["vertical_axis"] == "y" and not view["ground"]
    fig, update = animation_figure(planar, animation_samples(planar, max_frames=5))
    ax = fig.axes[0]
    assert len(ax.get_zticks()) == 0                     # nothing to read along the depth
    assert not any(g.startswith("shadow:") for g in by_gid(fig))

    view = animation_view(spatial)
    assert not view["planar"] and view["up"] == 2 and view["camera"]["vertical_axis"] == "z"
    samples = animation_samples(spatial, max_frames=5)
    fig, update = animation_figure(spatial, samples)
    assert len(fig.axes[0].get_zticks()) > 0
    lines = by_gid(fig)
    edges, segments = stick_segments(spatial, samples)
    assert edges == [("world", "arm"), ("arm", "tip")]
    update(3)
    floor = view["limits"][2][0]                          # no ground: the bottom of the box
    for e, (parent, child) in enumerate(edges):
        shadow = np.array(lines[f"shadow:{parent}>{child}"].get_data_3d()).T
        assert np.array_equal(shadow[:, :2], segments[3, e, :, :2]) and np.all(shadow[:, 2] == floor)


def test_a_frame_hung_from_the_world_at_a_fixed_distance_gets_a_stick_from_the_origin():
    t = np.linspace(0, 1, 50)
    ring = np.stack([np.cos(3 * t), np.sin(3 * t), 0 * t], axis=1)          # turns about the origin
    base = np.stack([t, 1 + 0 * t, 0 * t], axis=1)                          # floats away (a walker's hip)
    run = Run(model="m", spec_sha256="", method="rk4", dt=0.02, nq=1, nv=1, rtol=0, atol=0, t_end=1.0,
              parameters={}, inputs={}, state_names=["q", "v"], time=t, state=np.zeros((50, 2)),
              energy=np.zeros(50), frames={"ring": ring, "end": 2 * ring, "base": base, "foot": base - [0, 1, 0]},
              frame_parents={"ring": "world", "end": "ring", "base": "world", "foot": "base"})
    assert world_links(run) == [("world", "ring")]
    edges, segments = stick_segments(run, [0, 49])
    assert edges[0] == ("world", "ring")
    assert np.array_equal(segments[:, 0, 0], np.zeros((2, 3)))
    assert np.array_equal(segments[:, 0, 1], ring[[0, 49]])


# -- the GIF -----------------------------------------------------------------------------------------

def test_animate_run_writes_one_gif_frame_per_sample_at_the_figures_size(tmp_path):
    run = planar_run()
    calls = []
    info = animate_run(run, tmp_path / "a.gif", fps=30, max_frames=12, progress=lambda *a: calls.append(a))
    assert calls == [(k, 12) for k in range(12)] + [(12, 12)]      # before each frame, and at the end
    assert info["frames"] == 12 and info["fps"] == pytest.approx(GIF_FPS)
    assert info["seconds"] == pytest.approx(12 / GIF_FPS)
    assert info["speed"] == pytest.approx(2.0 * GIF_FPS / 11, rel=1e-9)    # 11 steps of 0.03 s play 2 s

    frames = gif_frames(tmp_path / "a.gif")
    assert len(frames) == 12
    fig, _ = animation_figure(run, animation_samples(run, GIF_FPS, 12))
    width, height = fig.canvas.get_width_height()
    assert frames[0].shape == (height, width, 3) and width % 2 == 0 and height % 2 == 0
    with Image.open(tmp_path / "a.gif") as im:
        assert im.info["duration"] == 30 and im.info["loop"] == 0
    below_title = slice(40, None)                   # the title changes anyway: the drawing must change
    for a, b in zip(frames, frames[1:]):
        assert np.any(a[below_title] != b[below_title])
    assert np.any(frames[0][below_title] != frames[-1][below_title], axis=2).sum() > 200   # the sticks moved


@pytest.mark.parametrize("fps, hundredths", [(30, 3), (25, 4), (20, 5), (100, 2), (7, 14)])
def test_gif_frames_last_whole_hundredths_of_a_second(tmp_path, fps, hundredths):
    writer, played = animation_writer(tmp_path / "a.gif", fps)
    assert isinstance(writer, GifWriter) and played == pytest.approx(100 / hundredths)
    fig = Figure(figsize=(1, 0.5), dpi=50)
    text = fig.text(0.5, 0.5, "")
    with writer.saving(fig, tmp_path / "a.gif", 50):
        for k in range(3):
            text.set_text(str(k))
            writer.grab_frame()
    with Image.open(tmp_path / "a.gif") as im:
        assert im.n_frames == 3 and im.size == (50, 25) and im.info["duration"] == 10 * hundredths


@pytest.mark.skipif(not animation.FFMpegWriter.isAvailable(), reason="ffmpeg is not installed")
def test_animate_run_writes_an_mp4_with_ffmpeg(tmp_path):
    info = animate_run(spatial_run(), tmp_path / "a.mp4", fps=30, max_frames=8)
    assert info["frames"] == 8 and info["fps"] == 30
    assert (tmp_path / "a.mp4").read_bytes()[4:8] == b"ftyp"


# -- andyc plot --animate ----------------------------------------------------------------------------

def test_cli_writes_a_gif_of_the_run(tmp_path):
    run_file = planar_run().save(tmp_path / "pendulum.h5")
    result = invoke("plot", run_file, "--animate", "--frames-max", 12)
    gif = run_file.with_suffix(".gif")
    assert result.exit_code == 0, result.output + result.stderr
    assert str(gif) in result.output
    # it says the frames, the rate they play at and the pace: 2 s of run in 11 frame intervals at 33.3 fps
    said = [float(x) for x in re.findall(r"\d+(?:\.\d+)?", result.output.replace(str(gif), ""))]
    for fact in (12, GIF_FPS, 2.0 / (11 / GIF_FPS)):
        assert any(x == pytest.approx(fact, rel=5e-3) for x in said), (fact, result.output)
    assert len(gif_frames(gif)) == 12


def test_a_run_without_frames_says_to_log_them(tmp_path):
    bare = plain_run()
    bare.save(tmp_path / "bare.h5")
    result = invoke("plot", tmp_path / "bare.h5", "--animate")
    assert result.exit_code == 2
    assert "--frames all" in result.stderr
    assert not (tmp_path / "bare.gif").exists()
    with pytest.raises(ValueError, match="--frames all"):
        animate_run(bare, tmp_path / "bare.gif")


def test_mp4_without_ffmpeg_says_so_and_suggests_a_gif(tmp_path, monkeypatch):
    run_file = planar_run().save(tmp_path / "pendulum.h5")
    monkeypatch.setattr(shutil, "which", lambda *args, **kwargs: None)     # matplotlib looks ffmpeg up so
    result = invoke("plot", run_file, "--animate", "-o", tmp_path / "movie.mp4")
    assert result.exit_code == 2
    assert "ffmpeg" in result.stderr and str(tmp_path / "movie.gif") in result.stderr
    assert not (tmp_path / "movie.mp4").exists()
    with pytest.raises(ValueError, match="ffmpeg"):
        animation_writer(tmp_path / "movie.mp4")


def test_other_output_types_and_animation_options_without_animate_are_refused(tmp_path):
    run_file = planar_run().save(tmp_path / "pendulum.h5")
    result = invoke("plot", run_file, "--animate", "-o", tmp_path / "movie.png")
    assert result.exit_code == 2 and ".gif or .mp4" in result.stderr
    with pytest.raises(ValueError, match=".gif or .mp4"):
        animation_writer(tmp_path / "movie.png")
    result = invoke("plot", run_file, "--fps", 10)
    assert result.exit_code == 2 and "--animate" in result.stderr
    assert not run_file.with_suffix(".png").exists()            # nothing plotted either
