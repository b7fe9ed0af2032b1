"""`andyc cycle --basin`: the basin of attraction of the orbit the command found, over a grid of two starting
components, run on the sweep engine (andyc.analysis.basins, andyc.analysis.sweeps) into a Zarr store, with
its map (andyc.plot.basinmap)."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from andyc.cli.common import Refused
from andyc.outputs import check_output


def basin_points(specs, model, fall: str):
    """The grid of `--basin NAME=FROM:TO:COUNT` (given twice), each NAME a state of the model, and the fall
    condition parsed; a usage error (Refused, exit 2) otherwise. Checked before any work."""
    from andyc.analysis.basins import BasinError, fall_metric
    from andyc.analysis.sweeps.points import PointsError, grid

    if fall:
        try:
            fall_metric(model, fall)
        except BasinError as exc:
            raise Refused(str(exc)) from None
    if len(specs) != 2:
        raise Refused(f"--basin: give it twice, one starting component each (a 2-D grid), e.g. --basin "
                      f"th1_dot=-2:-0.5:30 --basin th2_dot=-1:0.5:30; got {len(specs)}")
    try:
        points = grid(specs, option="--basin")
    except PointsError as exc:
        raise Refused(str(exc)) from None
    for name in points.names:
        if name not in model.state_names:
            raise Refused(f"--basin {name}: {model.name} has no state '{name}'; states: {', '.join(model.state_names)}")
    if points.names[0] == points.names[1]:
        raise Refused(f"--basin {points.names[0]}: the same state twice; give two different states")
    return points


def run_basin(file, model, result, points, options: dict, out, workers, batch) -> None:
    """Classify every grid point from the converged cycle `result` (andyc.analysis.cycles.Cycle), print the
    counts, write the store and the map; exit 1 when the run fails as a whole."""
    import numpy as np

    from andyc.analysis.basins import CLASSES, BasinError, make_basin
    from andyc.analysis.sweeps.run import SweepError, run_sweep
    from andyc.analysis.sweeps.store import StoreError
    from andyc.analysis.sweeps.worker import Settings
    from andyc.plot.basinmap import plot_basin

    store = Path(out or f"runs/{model.name}_basin_{result.section}.zarr")
    figure = store.with_suffix(".png")
    read = [file, model.path]
    if not store.is_dir():
        check_output(store, read, "result store")
    check_output(figure, read, "plot")
    try:
        basin = make_basin(model, result, **options)
    except BasinError as exc:
        raise Refused(str(exc)) from None
    settings = Settings.of(model, points.names, basin.t_step * basin.steps, dt=basin.dt, method="rk4",
                           fixed=tuple((k, float(v)) for k, v in basin.parameters), basin=basin)
    click.echo(f"basin of the cycle: {points.n} starts over {points.names[0]} x {points.names[1]}, at most "
               f"{basin.steps} steps each, tolerance {basin.tol:g}")
    try:
        summary = run_sweep(model, points, settings, store, workers=workers, batch=batch, inputs=read)
    except StoreError as exc:
        raise Refused(str(exc)) from None
    except SweepError as exc:
        click.echo(f"andyc: {exc}", err=True)
        sys.exit(1)
    click.echo(summary.text())
    import xarray as xr

    ds = xr.open_zarr(store)
    classes, periods = ds["basin"].values, ds["basin_period"].values
    counts = ", ".join(f"{name} {int(np.count_nonzero(classes == code))}" for code, name in CLASSES.items() if code)
    click.echo(f"classes: {counts}")
    index = [list(model.state_names).index(n) for n in points.names]
    marks = np.asarray(basin.orbit)[:, index]
    plot_basin([(n, ds[n].values) for n in points.names], classes, periods, CLASSES, marks, figure,
               f"{model.name}: basin of the cycle through '{result.section}'")
    click.echo(f"wrote {figure}")


__all__ = ["basin_points", "run_basin"]
