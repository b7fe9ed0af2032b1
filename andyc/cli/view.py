"""`andyc view`: a run as one self-contained HTML page that plays it in 3-D (andyc.plot.view)."""

from __future__ import annotations

from pathlib import Path

import click

from andyc.cli.common import Refused, read_run_argument
from andyc.outputs import check_output


@click.command()
@click.argument("run_file", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", default=None, help="The page, OUT.html; default RUN.html beside the run.")
@click.option("--fps", default=30, show_default=True, type=click.IntRange(1, 240), metavar="N",
              help="Samples kept per second of the run (they play in real time).")
@click.option("--max-samples", default=3000, show_default=True, type=click.IntRange(min=2), metavar="N",
              help="At most N samples, evenly spread in time: a long run is decimated (and plays faster "
                   "only if you choose a speed above 1).")
@click.option("--follow", default=None, metavar="FRAME", help="The camera follows this logged frame.")
@click.option("--trails", default=None, metavar="F1,F2",
              help="The frames that leave a trail (their path up to the time shown); default the end frames "
                   "(feet, tips); '' for none.")
@click.option("--full-meshes", is_flag=True,
              help="Keep every mesh at full resolution (by default a mesh above 10000 faces is simplified, "
                   "so that a robot's page stays small and opens fast).")
def view(run_file, out, fps, max_samples, follow, trails, full_meshes):
    """Write RUN_FILE (the HDF5 run of `andyc sim ... --frames all`) as one HTML page that plays its
    logged frames in 3-D in a browser, offline: play, pause, scrub, speed, the time and the active
    flow, the jumps on the timeline, the ground where the model has one; the model's shapes (shape:, a
    URDF's visuals and meshes) moved by the logged frames, sticks for the frames without one. Needs the
    meshcat package (andyc[view]), whose three.js viewer is inlined into the page."""
    from andyc.plot.view import FACE_BUDGET, meshcat_bundle, write_view

    if Path(run_file).suffix.lower() not in (".h5", ".hdf5"):
        raise click.BadParameter(f"{run_file}: andyc view reads the HDF5 run file (.h5) that andyc sim writes",
                                 param_hint="RUN_FILE")
    out = out or str(Path(run_file).with_suffix(".html"))
    if Path(out).suffix.lower() not in (".html", ".htm"):
        raise click.BadParameter(f"{out}: the page is written as .html", param_hint="'-o' / '--out'")
    try:
        meshcat_bundle()
    except ImportError as exc:
        raise Refused(str(exc)) from None
    check_output(out, [run_file], "page")
    run = read_run_argument(run_file)
    if not run.frames:
        raise click.BadParameter(f"{run_file}: this run of {run.model} logged no frames to view; re-run it with "
                                 f"`andyc sim MODEL.yaml --frames all --out {run_file}`", param_hint="RUN_FILE")
    for name in ([follow] if follow else []) + (trails.split(",") if trails else []):
        if name not in run.frames:
            option = "'--follow'" if name == follow else "'--trails'"
            raise click.BadParameter(f"the run logged no frame '{name}'; logged: {', '.join(run.frames)}",
                                     param_hint=option)
    try:
        info = write_view(run, out, fps=fps, max_samples=max_samples, follow=follow,
                          trails=None if trails is None else [t for t in trails.split(",") if t],
                          face_budget=None if full_meshes else FACE_BUDGET)
    except ValueError as exc:          # a run file from before andyc logged rotations, of a model with shapes
        raise click.BadParameter(f"{run_file}: {exc}", param_hint="RUN_FILE") from None
    for what in info["missing"]:
        click.echo(f"warning: not drawn: {what}", err=True)
    click.echo(f"wrote {out} ({info['samples']} samples of {len(run.time)}, {info['shapes']} shapes, "
               f"{info['bytes'] / 1e6:.2f} MB, in {info['seconds']:.2f} s)")
