"""`andyc plot RUN.h5 --animate` (andyc.plot.animate_run): a 3-D stick animation of a run's logged
frames, as a GIF (or an MP4 with ffmpeg).

One double-pendulum run (2 s, frames logged) serves all tests; the GIFs have a few dozen frames.
"""

import dataclasses
import shutil

import numpy as np
import pytest
from click.testing import CliRunner
from PIL import Image

import andyc
from andyc import cli
from andyc.plot import (animate_run, animation_figure, animation_samples, animation_writer, stick_segments,
                        world_links)
from andyc.runtime.run import Run, read_h5

T_END, DT, EVERY = 2.0, 1e-3, 10
GIF_FPS = 100 / 3                   # what --fps 30 plays at: GIF frames last whole hundredths of a second


@pytest.fixture(scope="module")
def run_file(compiled, tmp_path_factory):
    model = compiled("double_pendulum")
    run = andyc.simulate(model, T_END, DT, frames="all", every=EVERY, progress=False)
    return run.save(tmp_path_factory.mktemp("animate") / "pendulum.h5")


@pytest.fixture(scope="module")
def run(run_file):
    return read_h5(run_file)


def invoke(*args):
    try:
        runner = CliRunner(mix_stderr=False)          # click 8.1
    except TypeError:
        runner = CliRunner()                          # click >= 8.2 always keeps stderr apart
    return runner.invoke(cli.main, ["plot", *map(str, args)])


def gif_frames(path) -> list:
    """The frames of a GIF as RGB arrays."""
    with Image.open(path) as im:
        frames = []
        for k in range(im.n_frames):
            im.seek(k)
            frames.append(np.asarray(im.convert("RGB")).astype(int))
        return frames


# -- what is drawn -----------------------------------------------------------------------------------

def test_samples_are_evenly_spread_from_start_to_end(run):
    n = len(run.time)
    assert n == round(T_END / (DT * EVERY)) + 1
    samples = animation_samples(run, fps=30, max_frames=20)
    t = run.time[samples]
    assert len(samples) == 20 and t[0] == 0.0 and t[-1] == pytest.approx(T_END)
    even = np.linspace(0.0, T_END, 20)
    assert np.all(np.abs(t - even) <= DT * EVERY / 2 + 1e-12)       # the sample nearest to each even time
    assert np.all(np.diff(samples) > 0)
    # uncapped: as many frames as play the run in real time, and never more than the samples
    assert len(animation_samples(run, fps=30, max_frames=300)) == round(T_END * 30) + 1
    assert np.array_equal(animation_samples(run, fps=1000, max_frames=10_000), np.arange(n))


def test_stick_ends_are_the_logged_frames_at_the_samples(run):
    samples = animation_samples(run, fps=30, max_frames=24)
    edges, segments = stick_segments(run, samples)
    assert edges == [("upper", "elbow"), ("elbow", "lower"), ("lower", "tip")]   # no world link: upper is at 0
    assert segments.shape == (24, 3, 2, 3)
    e = edges.index(("lower", "tip"))
    for f, k in enumerate(samples):
        assert np.array_equal(segments[f, e, 1], run.frames["tip"][k])
        assert np.array_equal(segments[f, e, 0], run.frames["lower"][k])
    assert np.ptp(segments[:, e, 1, 0]) > 0.5          # the tip swings

    fig, update = animation_figure(run, samples)     # the drawn stick is that segment
    tip = next(a for a in fig.axes[0].get_lines() if a.get_gid() == "lower>tip")
    for f in (0, 11, 23):
        update(f)
        assert np.array_equal(np.array(tip.get_data_3d()).T, segments[f, e])
        assert f"t = {run.time[samples[f]]:.2f} s" in fig.texts[-1].get_text()


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

def test_cli_writes_a_gif_of_the_moving_pendulum(run, run_file):
    result = invoke(run_file, "--animate", "--frames-max", 24)
    gif = run_file.with_suffix(".gif")
    assert result.exit_code == 0, result.output + result.stderr
    assert result.output.startswith(f"wrote {gif} (24 frames, 0.7 s at 33.3 fps, 2.90 x real time")
    frames = gif_frames(gif)
    assert len(frames) == 24 == len(animation_samples(run, GIF_FPS, 24))
    with Image.open(gif) as im:
        assert im.info["duration"] == 30 and im.info["loop"] == 0
    below_title = slice(40, None)                   # the title changes anyway: the drawing must change
    for a, b in zip(frames, frames[1:]):
        assert np.any(a[below_title] != b[below_title])
    changed = np.any(frames[0][below_title] != frames[-1][below_title], axis=2)
    assert changed.sum() > 200                      # pixels, a good part of the sticks


def test_animate_run_reports_progress_and_playing_time(run, tmp_path):
    calls = []
    info = animate_run(run, tmp_path / "a.gif", fps=25, max_frames=12, progress=lambda *a: calls.append(a))
    assert calls == [(k, 12) for k in range(12)] + [(12, 12)]
    assert info["frames"] == 12 and info["fps"] == 25 and info["seconds"] == pytest.approx(12 / 25)
    assert info["speed"] == pytest.approx(T_END * 25 / 11, rel=1e-9)     # 11 steps of 1/25 s play 2 s
    assert len(gif_frames(tmp_path / "a.gif")) == 12


# -- errors ------------------------------------------------------------------------------------------

def test_a_run_without_frames_says_to_log_them(run, tmp_path):
    bare = dataclasses.replace(run, frames={}, frame_parents={})
    bare.save(tmp_path / "bare.h5")
    result = invoke(tmp_path / "bare.h5", "--animate")
    assert result.exit_code == 2
    assert "logged no frames" in result.stderr and "--frames all" in result.stderr
    assert not (tmp_path / "bare.gif").exists()
    with pytest.raises(ValueError, match="--frames all"):
        animate_run(bare, tmp_path / "bare.gif")


def test_mp4_without_ffmpeg_says_so_and_suggests_a_gif(run_file, tmp_path, monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda *args, **kwargs: None)     # matplotlib looks ffmpeg up so
    result = invoke(run_file, "--animate", "-o", tmp_path / "movie.mp4")
    assert result.exit_code == 2
    assert "ffmpeg" in result.stderr and str(tmp_path / "movie.gif") in result.stderr
    assert not (tmp_path / "movie.mp4").exists()
    with pytest.raises(ValueError, match="ffmpeg"):
        animation_writer(tmp_path / "movie.mp4")


def test_other_output_types_and_animation_options_without_animate_are_refused(run_file, tmp_path):
    result = invoke(run_file, "--animate", "-o", tmp_path / "movie.png")
    assert result.exit_code == 2 and ".gif or .mp4" in result.stderr
    result = invoke(run_file, "--fps", 10)
    assert result.exit_code == 2 and "only with --animate" in result.stderr
    assert not run_file.with_suffix(".png").exists()            # nothing plotted either
