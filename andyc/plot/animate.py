"""The animation of a run: `animate_run(run, out)` writes a 3-D stick animation of the logged frames
(GIF, or MP4 with ffmpeg). `animation_samples` picks the samples (one per animation frame),
`stick_segments` gives the sticks' ends at them, `animation_figure` draws a frame at a time, and
`animation_writer` picks the writer: `GifWriter` (Pillow, one palette for the whole GIF) or
matplotlib's FFMpegWriter. The scene (which frames connect, the view, the colours, the ground)
comes from `andyc.plot.scene`.
"""

from __future__ import annotations

import time
from pathlib import Path

import matplotlib.ticker
import numpy as np
from matplotlib import animation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from PIL import Image

from andyc.outputs import write_atomic
from andyc.plot.scene import animation_edges, animation_view, branch_colours, is_hybrid, leaf_colours
from andyc.runtime.run import Run

TRACE_SECONDS = 0.5                 # the trail behind each leaf frame
SCENE_INCHES = {"planar": (8.0, 5.0), "3-D": (6.4, 5.2)}     # the largest size of the drawing (100 px an inch)


def animate_run(run: Run, out, fps: int = 30, max_frames: int = 300, dpi: int = 100, progress=None) -> dict:
    """Write a 3-D stick animation of the logged frames of `run` to `out` (.gif, or .mp4 with
    ffmpeg): `animation_samples` picks the samples, `animation_figure` draws them at `dpi`.
    progress(done, total) is called before each frame and once at the end. Returns {'frames',
    'fps' (as played), 'seconds' (playing time), 'speed' (run time per playing time),
    'render_seconds'}. ValueError if no frames were logged or `out` cannot be written (see
    `animation_writer`)."""
    if not run.frames:
        raise ValueError(f"{run.model}: the run logged no frames to animate; re-run it with "
                         "`andyc sim MODEL.yaml --frames all --out RUN.h5`")
    writer, fps = animation_writer(out, fps)
    start = time.perf_counter()
    samples = animation_samples(run, fps, max_frames)
    fig, update = animation_figure(run, samples, dpi)
    with write_atomic(out) as tmp, writer.saving(fig, tmp, dpi):
        for f in range(len(samples)):
            if progress:
                progress(f, len(samples))       # before each frame: frames done so far
            update(f)
            writer.grab_frame()
    if progress:
        progress(len(samples), len(samples))
    seconds = len(samples) / fps
    played = run.time[samples[-1]] - run.time[samples[0]] if len(samples) else 0.0
    return {"frames": len(samples), "fps": fps, "seconds": seconds, "speed": played * fps / max(len(samples) - 1, 1),
            "render_seconds": time.perf_counter() - start}


def animation_samples(run: Run, fps: int = 30, max_frames: int = 300) -> np.ndarray:
    """Indices of the samples shown, one per animation frame: the samples nearest to times evenly
    spread from the first sample to the last; as many as play the run in real time at `fps`
    (duration * fps + 1), but at most `max_frames` (then it plays faster) and at most all samples."""
    t = run.time
    n = len(t)
    if n == 0:
        return np.zeros(0, dtype=int)
    count = int(min(n, max(max_frames, 1), round((t[-1] - t[0]) * fps) + 1))
    if count >= n:
        return np.arange(n)
    want = np.linspace(t[0], t[-1], count)
    k = np.clip(np.searchsorted(t, want), 1, n - 1)
    k -= want - t[k - 1] < t[k] - want             # the nearer of the two neighbours
    return np.unique(k)


def stick_segments(run: Run, samples) -> tuple:
    """(edges, segments): the sticks (`animation_edges`) and their ends at the given samples,
    segments[f, e] = [parent xyz, child xyz] of edge e at samples[f], shape (frames, edges, 2, 3);
    'world' is the origin."""
    edges = animation_edges(run)
    samples = np.asarray(samples, dtype=int)
    at = lambda name: np.zeros((len(samples), 3)) if name == "world" else run.frames[name][samples]  # noqa: E731
    segments = np.zeros((len(samples), len(edges), 2, 3))
    for e, (parent, child) in enumerate(edges):
        segments[:, e, 0], segments[:, e, 1] = at(parent), at(child)
    return edges, segments


# -- writers ---------------------------------------------------------------------------------------

class GifWriter(animation.AbstractMovieWriter):
    """A GIF writer on public APIs only (matplotlib's writer interface: `saving`, `grab_frame`).
    Each frame is the figure drawn on its Agg canvas (`buffer_rgba`), kept as RGB; `finish` maps
    all frames to one palette of 256 colours (median cut of a few frames over the run, no
    dithering) and writes them with Pillow's `Image.save(save_all=True)`: what does not move keeps
    its colour, so Pillow stores each frame as the small rectangle that changed (the GIF is several
    times smaller), and it takes a fraction of the time of a median cut per frame. A frame lasts
    round(1000 / fps) ms; GIF stores whole hundredths of a second (`animation_writer`)."""

    def setup(self, fig, outfile, dpi=None):
        """Start a GIF of `fig` at `outfile`, drawn at `dpi` (default and best: the figure's own;
        another dpi is set on the figure)."""
        super().setup(fig, outfile, dpi)
        if self.dpi != fig.dpi:
            fig.set_dpi(self.dpi)
        self._canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
        self._images = []

    def grab_frame(self, **savefig_kwargs):
        """Draw the figure and keep it as the next frame (the canvas as drawn: no savefig arguments)."""
        if savefig_kwargs:
            raise TypeError(f"GifWriter.grab_frame takes no savefig arguments, got {sorted(savefig_kwargs)}")
        self._canvas.draw()
        self._images.append(Image.fromarray(np.asarray(self._canvas.buffer_rgba())).convert("RGB"))

    def finish(self):
        """Write the frames grabbed, on one palette; ValueError if there are none."""
        frames, self._images = self._images, []
        if not frames:
            raise ValueError(f"{self.outfile}: no frames to write")
        some = frames[::max(1, len(frames) // 8)]
        w, h = frames[0].size
        montage = Image.new("RGB", (w, h * len(some)))
        for i, im in enumerate(some):
            montage.paste(im, (0, h * i))
        palette = montage.quantize(256, method=Image.Quantize.MEDIANCUT, dither=Image.Dither.NONE)
        frames = [im.quantize(palette=palette, dither=Image.Dither.NONE) for im in frames]
        frames[0].save(self.outfile, format="GIF", save_all=True, append_images=frames[1:],
                       duration=round(1000 / self.fps), loop=0)


def animation_writer(out, fps: int = 30) -> tuple:
    """(writer, frames per second it plays at) for `out`: `GifWriter` for .gif, whose frames last
    whole hundredths of a second (at least 2: browsers slow shorter ones down), so 30 fps plays at
    33.3; FFMpegWriter (H.264) for .mp4 if ffmpeg is installed. ValueError otherwise."""
    suffix = Path(out).suffix.lower()
    if suffix == ".gif":
        hundredths = max(2, round(100 / fps))
        return GifWriter(fps=100 / hundredths), 100 / hundredths
    if suffix == ".mp4":
        if not animation.FFMpegWriter.isAvailable():
            raise ValueError(f"{out}: writing .mp4 needs ffmpeg, which is not installed (not on PATH); "
                             f"install ffmpeg, or write a GIF instead: -o {Path(out).with_suffix('.gif')}")
        return animation.FFMpegWriter(fps=fps, codec="h264", extra_args=["-pix_fmt", "yuv420p"]), fps
    raise ValueError(f"{out}: an animation is written as .gif or .mp4, not '{suffix or 'no suffix'}'")


# -- the figure ------------------------------------------------------------------------------------

def animation_figure(run: Run, samples, dpi: int = 100) -> tuple:
    """(fig, update): the 3-D scene of `run` and update(f), which draws animation frame f
    (samples[f]): sticks (coloured by `branch_colours`), joints, the trace of the last
    TRACE_SECONDS of each leaf frame, in 3-D the shadows of the sticks on the floor, and the title
    with the time (and the flow of a hybrid run). The axes, the world origin and the ground do not
    move: they are drawn once, at `dpi` (the dpi to save at), into a background image. The figure
    is on an Agg canvas of its own (no pyplot)."""
    samples = np.asarray(samples, dtype=int)
    edges, segments = stick_segments(run, samples)
    view = animation_view(run)
    joints = np.stack([run.frames[name][samples] for name in run.frames], axis=1)  # (frames, names, 3)

    fig = Figure(figsize=(12, 10), dpi=dpi)  # generous: `_fit_figure` scales the scene to SCENE_INCHES and crops
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0.25, 0.25, 0.5, 0.5), projection="3d")
    ax.view_init(**view["camera"])
    ax.set_box_aspect(view["span"])
    for setter, lim in zip((ax.set_xlim, ax.set_ylim, ax.set_zlim), view["limits"]):
        setter(*lim)
    for axis, label in zip((ax.xaxis, ax.yaxis, ax.zaxis), "xyz"):
        axis.set_major_locator(matplotlib.ticker.MaxNLocator(4))
        axis.set_label_text(f"{label}, m")
    ax.zaxis.labelpad = 9
    if view["planar"]:
        ax.set_zticks([])
        ax.set_zlabel("")
    ax.tick_params(labelsize="small")
    hybrid = is_hybrid(run)
    digits = len(f"{run.time[-1]:.2f}")     # the title's width stays put

    def heading(k):
        text = f"{run.model}   t = {run.time[k]:{digits}.2f} s"
        return text + f"   flow {run.flow_names[run.flow[k]]}" if hybrid else text

    widest = max((heading(k) for k in samples[np.unique(run.flow[samples], return_index=True)[1]]), key=len)
    title = fig.text(0.5, 1.0, widest, ha="left", va="center", family="monospace")    # placed by `_fit_figure`
    _fit_figure(fig, ax, title, SCENE_INCHES["planar" if view["planar"] else "3-D"])

    still = [ax.plot([0], [0], [0], "s", color="k", ms=5, gid="world")[0]]
    if view["ground"] and view["planar"]:   # the line where the ground meets the plane of motion
        line = np.zeros((2, 3))
        line[:, 1 - view["up"]] = view["limits"][1 - view["up"]]
        line[:, view["up"]] = view["ground_height"]
        still += ax.plot(*line.T, color="saddlebrown", lw=1.5, gid="ground")
    # the background: the 3-D axes take most of the time of drawing a frame, and do not change
    title.set_visible(False)
    canvas.draw()
    fig.figimage(np.asarray(canvas.buffer_rgba()).copy(), zorder=-1, gid="background")
    ax.set_axis_off()
    ax.patch.set_visible(False)
    for artist in still:
        artist.set_visible(False)
    title.set_visible(True)

    traces = {name: ax.plot([], [], [], color=colour, lw=1.5, alpha=0.6, gid=f"trace:{name}")[0]
              for name, colour in leaf_colours(run).items()}
    floor = view["ground_height"] if view["ground"] else view["limits"][2][0]     # 3-D: shadows on the floor show the depth
    shadows = [] if view["planar"] else [ax.plot([], [], [], color="0.6", lw=2, alpha=0.5, gid=f"shadow:{p}>{c}")[0]
                                         for p, c in edges]
    sticks = [ax.plot([], [], [], color=colour, lw=2.5, solid_capstyle="round", gid=f"{parent}>{child}")[0]
              for (parent, child), colour in zip(edges, branch_colours(run, edges))]
    dots = ax.plot([], [], [], "o", color="k", ms=3.5, gid="joints")[0]

    def update(f):
        k = samples[f]
        for line, seg in zip(sticks, segments[f]):
            line.set_data_3d(*seg.T)
        for line, seg in zip(shadows, segments[f]):
            line.set_data_3d(seg[:, 0], seg[:, 1], [floor, floor])
        dots.set_data_3d(*joints[f].T)
        first = np.searchsorted(run.time, run.time[k] - TRACE_SECONDS)
        for name, line in traces.items():
            line.set_data_3d(*run.frames[name][first:k + 1].T)
        title.set_text(heading(k))
        return []

    return fig, update


def _ink(fig) -> tuple:
    """(x0, y0, x1, y1): the box, in inches from the bottom left, of what `fig` draws on its Agg canvas."""
    fig.canvas.draw()
    ink = np.any(np.asarray(fig.canvas.buffer_rgba())[..., :3] < 250, axis=2)      # rows from the top
    rows, cols = np.flatnonzero(ink.any(axis=1)), np.flatnonzero(ink.any(axis=0))
    h = fig.get_size_inches()[1]
    return cols[0] / fig.dpi, h - (rows[-1] + 1) / fig.dpi, (cols[-1] + 1) / fig.dpi, h - rows[0] / fig.dpi


def _fit_figure(fig, ax, title, size, margin: float = 0.1) -> None:
    """Scale the figure so that what `ax` draws is about `size` (width, height) inches at most
    (matplotlib draws a 3-D box small in its axes), then crop the figure to that, plus `margin`
    inches around it and a line above it for `title` (left-aligned, holding its widest text, which
    is centred: the text does not shift as it changes), keeping the axes' size (so the drawing
    keeps its scale)."""
    title.set_visible(False)
    x0, y0, x1, y1 = _ink(fig)
    fig.set_size_inches(fig.get_size_inches() * min(size[0] / (x1 - x0), size[1] / (y1 - y0)))
    x0, y0, x1, y1 = _ink(fig)      # the box scales with the axes (not zoom: the lines are clipped to the axes)
    title.set_visible(True)
    top = 2.2 * title.get_fontsize() / 72                                      # inches
    text_width = title.get_window_extent(fig.canvas.get_renderer()).width / fig.dpi
    w, h = fig.get_size_inches()
    new_w, new_h = max(x1 - x0, text_width) + 2 * margin, y1 - y0 + 2 * margin + top
    new_w, new_h = (2 * np.ceil(v * fig.dpi / 2) / fig.dpi for v in (new_w, new_h))   # even pixels (H.264 needs them)
    left = x0 - margin - (new_w - 2 * margin - (x1 - x0)) / 2                  # the drawing centred
    pos = ax.get_position()
    fig.set_size_inches(new_w, new_h)
    ax.set_position([(pos.x0 * w - left) / new_w, (pos.y0 * h - y0 + margin) / new_h,
                     pos.width * w / new_w, pos.height * h / new_h])
    title.set_position(((new_w - text_width) / 2 / new_w, 1 - top / 2 / new_h))    # the widest title centred
