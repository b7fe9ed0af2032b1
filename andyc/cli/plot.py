"""`andyc plot`: a run's states and energy against time, its frames as stick figures, or an animation."""

from __future__ import annotations

from pathlib import Path

import math

import click

from andyc.cli.common import read_run_argument
from andyc.outputs import check_output


@click.command()
@click.argument("run_file", type=click.Path(exists=True))
@click.option("-o", "--out", default=None, help="PNG file; default RUN.png beside the run. With --animate: the "
              "animation, OUT.gif or OUT.mp4 (needs ffmpeg); default RUN.gif beside the run.")
@click.option("--animate", is_flag=True, help="Instead of the plots, write a 3-D stick animation of the frames the "
              "run logged (andyc sim ... --frames all). The model's shapes and meshes, its ground and contact "
              "forces are drawn by `andyc view RUN` instead.")
@click.option("--fps", default=None, type=click.IntRange(1, 100), metavar="N",
              help="With --animate: frames per second (default 30; a GIF frame lasts whole hundredths of a "
                   "second: 30 plays at 33.3).")
@click.option("--frames-max", default=None, type=click.IntRange(min=1), metavar="N",
              help="With --animate: at most N frames, evenly spread in time (default 300); a run longer than "
                   "N / fps seconds plays faster than real time.")
@click.option("--signals", "signals", multiple=True, metavar="NAMES",
              help="Plot only these signals (states, discrete states, inputs, multipliers, energy), by name or "
                   "shell glob, comma-separated or repeated: --signals 'q*,energy'; one axis per kind of "
                   "quantity and scale.")
@click.option("--window", default=None, metavar="T0:T1",
              help="Only the samples with T0 <= t <= T1 (either end may be left out: 2:, :5); also for --animate.")
@click.option("--metric", default=None, metavar="NAME",
              help="With a sweep's STORE.zarr: the variable to map (default: its first metric, else the outcome).")
def plot(run_file, out, animate, fps, frames_max, signals, window, metric):
    """Plot the states and the energy of a run against time (and, for a hybrid run, its flows,
    jumps and discrete states); when the run logged frames with their parents, also draw them as
    stick figures, into RUN_sticks.png (or OUT_sticks.png beside OUT). With --animate, write an
    animation of the logged frames instead. Quantities of different kinds (angles, lengths, speeds,
    ...) or scales get axes of their own. Given a sweep's result store (STORE.zarr, andyc sweep): a heat
    map of a metric over its two swept names, or a line over one."""
    from andyc.plot.select import select_signals
    from andyc.plot.select import window as time_window

    if Path(run_file).is_dir():             # a sweep's result store (andyc sweep)
        from andyc.cli.sweep import plot_store

        given = [name for name, value in (("--signals", signals), ("--window", window), ("--animate", animate))
                 if value]
        if given:
            raise click.BadParameter("only with a run file (RUN.h5), not a sweep's store", param_hint=given[0])
        return plot_store(run_file, out, metric)
    if metric is not None:
        raise click.BadParameter("only with a sweep's result store (STORE.zarr)", param_hint="--metric")
    if Path(run_file).suffix.lower() not in (".h5", ".hdf5"):
        raise click.BadParameter(f"{run_file}: andyc plot reads the HDF5 run file (.h5) that andyc sim writes; "
                                 f"write one with --out RUN.h5", param_hint="RUN_FILE")
    if not animate:
        given = [name for name, value in (("--fps", fps), ("--frames-max", frames_max)) if value is not None]
        if given:
            raise click.BadParameter("only with --animate", param_hint=" and ".join(given))
    elif signals:
        raise click.BadParameter("not with --animate (an animation shows the frames)", param_hint="--signals")
    t0, t1 = parse_window(window) if window is not None else (None, None)
    patterns = [p.strip() for text in signals for p in text.split(",") if p.strip()]
    if signals and not patterns:
        raise click.BadParameter("give at least one signal name or glob", param_hint="--signals")
    out = out or str(Path(run_file).with_suffix(".gif" if animate else ".png"))
    check_output(out, [run_file], "plot")
    if not animate:
        check_image_type(out)
    if not animate and not patterns:
        check_output(sticks_path(out), [run_file], "plot")
    run = read_run_argument(run_file)
    try:
        if window is not None:
            run = time_window(run, t0, t1)
        chosen = select_signals(run, patterns) if patterns else None
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--window" if window is not None and not patterns
                                 else "--signals") from None
    if animate:
        animate_file(run, run_file, out, fps or 30, frames_max or 300)
    else:
        plot_file(run, out, chosen)


def parse_window(text: str) -> tuple:
    """(t0, t1) of `--window T0:T1`, either None where left out; click.BadParameter otherwise."""
    parts = text.split(":")
    try:
        if len(parts) != 2:
            raise ValueError
        t0, t1 = (float(p) if p.strip() else None for p in parts)
    except ValueError:
        raise click.BadParameter(f"'{text}' is not T0:T1 (seconds; e.g. 2:5, 2: or :5)", param_hint="--window") from None
    for t in (t0, t1):
        if t is not None and not math.isfinite(t):
            raise click.BadParameter(f"'{text}': the times must be finite", param_hint="--window")
    if t0 is not None and t1 is not None and t0 > t1:
        raise click.BadParameter(f"'{text}': T0 is after T1", param_hint="--window")
    return t0, t1


def check_image_type(out) -> None:
    """click.BadParameter for -o OUT whose suffix names no image type matplotlib writes (before any work)."""
    from matplotlib.backend_bases import FigureCanvasBase

    known = {k: v for k, v in FigureCanvasBase.get_supported_filetypes().items() if k != "pgf"}  # (needs LaTeX)
    suffix = Path(out).suffix.lower().lstrip(".")
    if suffix not in known:
        others = ", ".join("." + k for k in known if k not in ("png", "svg", "pdf"))
        raise click.BadParameter(f"{out}: " + (f"unknown image type '.{suffix}'" if suffix else "no image type")
                                 + f"; end the name in .png, .svg or .pdf (or {others})", param_hint="'-o' / '--out'")


def sticks_path(out) -> Path:
    """Where the stick figures of a plot OUT go: OUT_sticks.png beside it."""
    return Path(out).with_name(Path(out).stem + "_sticks.png")


def plot_file(run, out, signals=None) -> None:
    """The plots of `run` (only `signals`, if given) into `out`, and, without `signals`, its stick figures
    beside it when it logged frames with parents."""
    from andyc.plot import plot_run, plot_sticks, stick_edges

    plot_run(run, out, signals)
    click.echo(f"wrote {out}" + (f" ({', '.join(signals)})" if signals else ""))
    if signals is None and stick_edges(run):
        plot_sticks(run, sticks_path(out))
        click.echo(f"wrote {sticks_path(out)} (stick figures of the frames)")


def animate_file(run, run_file, out, fps: int, frames_max: int) -> None:
    """The animation of `run`'s logged frames into `out` (GIF or MP4), with its progress on a terminal."""
    from andyc.plot import animate_run, animation_writer
    from andyc.runtime.progress import Progress

    if not run.frames:
        raise click.BadParameter(f"{run_file}: this run of {run.model} logged no frames to animate; re-run it "
                                 f"with `andyc sim MODEL.yaml --frames all --out {run_file}`", param_hint="RUN_FILE")
    try:
        animation_writer(out, fps)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'-o' / '--out'") from None
    with Progress(run.model, unit="frames") as progress:
        info = animate_run(run, out, fps=fps, max_frames=frames_max, progress=progress)
    pace = "real time" if info["speed"] < 1.01 else f"{info['speed']:.2f} x real time"
    click.echo(f"wrote {out} ({info['frames']} frames, {info['seconds']:.1f} s at {info['fps']:.3g} fps, {pace}; "
               f"rendered in {info['render_seconds']:.1f} s)")
    drawn = [what for what, there in (("shapes", run.display.get("shapes")), ("ground and contact forces",
                                                                               run.contact_names)) if there]
    if drawn:       # the sticks show the frames only: say where the rest is drawn
        click.echo(f"the animation draws the frames as sticks; its {' and '.join(drawn)} are drawn by "
                   f"`andyc view {run_file}` (a page that plays in a browser)")
