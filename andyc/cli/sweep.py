"""`andyc sweep`: a grid, Monte Carlo samples or a CSV file's points of a model, run on Dask into one Zarr
store (andyc.analysis.sweeps); and the sweep plots of `andyc plot STORE` (andyc.plot.sweepmap).

Dask, Zarr and xarray are imported only when a sweep runs or a store is read, so that no other command
imports them."""

from __future__ import annotations

import sys
from pathlib import Path

import click

from andyc.cli.common import Refused, compiled
from andyc.cli.values import COUNT, POSITIVE, TOLERANCE, Number, parse_sets, stop_counts
from andyc.errors import MetricError
from andyc.outputs import check_output
from andyc.runtime.methods import METHODS


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--grid", "grids", multiple=True, metavar="NAME=FROM:TO:COUNT",
              help="Sweep NAME over COUNT values from FROM to TO (both included); repeat for a full grid.")
@click.option("--samples", default=None, type=COUNT, metavar="N", help="N samples of the --dist names, drawn as --sampler says.")
@click.option("--dist", "dists", multiple=True, metavar="NAME=normal(MU,SIGMA)|uniform(A,B)",
              help="With --samples: the distribution of NAME.")
@click.option("--sampler", default="random", show_default=True,
              type=click.Choice(["random", "lhs", "sobol", "halton"]),
              help="With --samples: Monte Carlo draws (random), or scipy.stats.qmc's Latin hypercube (lhs), "
                   "scrambled Sobol' points (sobol; N a power of 2) or scrambled Halton points (halton), mapped "
                   "to each --dist by its inverse CDF.")
@click.option("--seed", default=0, show_default=True, type=Number(0, 2**63 - 1, integer=True),
              help="With --samples: the seed of numpy's random generator, which also scrambles the qmc designs "
                   "(the same seed, the same samples).")
@click.option("--points", "points_file", default=None, type=click.Path(dir_okay=False), metavar="FILE.csv",
              help="The points: a header of names, then one point a row.")
@click.option("--metric", "metrics", multiple=True, metavar="NAME=EXPR",
              help="A value of each run to record: an expression of the final state (x, t, energy, frame.y, ...) "
                   "and of the run (max(E), min(E), mean(E), at(T, E), count(JUMP), time_of(JUMP, N)); a "
                   "comparison gives 1 or 0.")
@click.option("-o", "--out", "out", default=None, metavar="STORE.zarr",
              help="The result store (Zarr); default runs/<name>_sweep.zarr. Rerunning the same sweep into it "
                   "computes only the points it lacks.")
@click.option("--t-end", default=10.0, show_default=True, type=POSITIVE, help="End time of each run, s.")
@click.option("--dt", default=1e-3, show_default=True, type=POSITIVE,
              help="Step (rk4) or output spacing (adaptive methods), s.")
@click.option("--method", default="rk4", show_default=True, type=click.Choice(list(METHODS)))
@click.option("--rtol", default=1e-8, show_default=True, type=TOLERANCE, help="Relative tolerance (adaptive methods).")
@click.option("--atol", default=1e-10, show_default=True, type=POSITIVE, help="Absolute tolerance (adaptive methods).")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="A parameter or input every point shares.")
@click.option("--stop-after", "stop_after", multiple=True, metavar="JUMP=N",
              help="End each run right after the N-th occurrence of JUMP.")
@click.option("--init", default="check", show_default=True, type=click.Choice(["check", "project", "as-is"]),
              help="An initial state off the constraints: the point fails (check), is projected, or runs as is.")
@click.option("--timeout", default=None, type=POSITIVE, metavar="SECONDS",
              help="Stop a run after this much wall time (the point is recorded as stopped).")
@click.option("--trajectory", default=0, show_default=True, type=Number(0, 100_000, integer=True), metavar="N",
              help="Keep each run's state at N evenly spaced times (0: none; else at least 2).")
@click.option("--max-events", default=20, show_default=True, type=Number(1, 100_000, integer=True), metavar="N",
              help="Keep the times of each run's first N jumps.")
@click.option("--scheduler", default=None, metavar="ADDRESS",
              help="An existing Dask scheduler (tcp://HOST:8786); its workers need andyc and the build folder at "
                   "the same path. Without it the points run in this process (--engine).")
@click.option("--engine", default="auto", show_default=True, type=click.Choice(["auto", "inline", "cluster"]),
              help="Where the points run: inline (in this process, on threads: the compiled loop runs without "
                   "the GIL; no cluster), cluster (Dask: --scheduler's, or a local cluster of processes), or "
                   "auto: a --scheduler's cluster if given, else inline.")
@click.option("--workers", default=None, type=Number(1, 4096, integer=True), metavar="N",
              help="Threads (inline) or processes of the local cluster (default: one per core).")
@click.option("--batch", default=None, type=Number(1, 1_000_000, integer=True), metavar="N",
              help="Points per batch (default: inline, about a second's worth; on a cluster, about 8 tasks per "
                   "worker, at most 256 points).")
@click.option("--build-dir", default="build", show_default=True, help="Build folder.")
def sweep(file, grids, samples, dists, sampler, seed, points_file, metrics, out, t_end, dt, method, rtol, atol, sets,
          stop_after, init, timeout, trajectory, max_events, scheduler, engine, workers, batch, build_dir):
    """Run FILE at many points -- a grid (--grid), Monte Carlo samples (--samples, --dist, --seed) or a CSV
    file's rows (--points) -- in this process or on Dask (--engine), into one Zarr store that xarray opens
    (xarray.open_zarr(STORE)).

    A swept name is a parameter, an input or the initial value of a state (a coordinate, a speed). Each
    point records its outcome (finished, stopped, blew up, Zeno, failed), final state, jumps, metrics and,
    with --trajectory, a decimated trajectory; a failed point is recorded and the sweep goes on."""
    from andyc.analysis.sweeps import missing_extra
    from andyc.analysis.sweeps.points import PointsError, sweepable
    from andyc.analysis.sweeps.worker import Settings

    needs = missing_extra("andyc sweep", "zarr", *(("distributed",) if scheduler or engine == "cluster" else ()))
    if needs:
        raise Refused(needs)
    if trajectory == 1:
        raise Refused("--trajectory 1: give 0 (none) or at least 2 samples")
    if scheduler is not None and workers is not None:
        raise Refused("--workers sets the number of threads or of the local cluster's processes; with "
                      "--scheduler, the cluster's own workers run the sweep: give one of them")
    if scheduler is not None and engine == "inline":
        raise Refused("--engine inline runs the points in this process; --scheduler names a cluster: give one "
                      "of them")
    try:
        points = _points(grids, samples, dists, seed, points_file, sampler)
        metric_list = _metric_items(metrics)
    except (PointsError, MetricError) as exc:
        raise Refused(str(exc)) from None
    fixed = parse_sets(sets)
    stops = stop_counts(stop_after)
    model, result = compiled(file, build_dir, integrator=False)    # (the names are checked before compiling the run)
    out = Path(out or f"runs/{model.name}_sweep.zarr")
    read = [file, points_file, model.path, result.jumps_path]
    if not out.is_dir():
        check_output(out, read, "result store")
    try:
        settings = Settings.of(model, points.names, t_end, dt=dt, method=method, rtol=rtol, atol=atol,
                               fixed=tuple(fixed.items()), stop_after=tuple(stops.items()), init=init,
                               timeout=timeout, metrics=tuple(metric_list), max_events=max_events,
                               trajectory=trajectory)
    except PointsError as exc:
        raise Refused(str(exc)) from None
    known = sweepable(model)
    for name in fixed:
        if name not in known or known[name][0] == "state":
            raise Refused(f"--set {name}: {model.name} has no parameter or input '{name}'; parameters: "
                          f"{', '.join(model.parameter_names) or 'none'}; inputs: {', '.join(model.input_names) or 'none'}")
    for name in stops:
        if name not in model.jump_names:
            raise Refused(f"--stop-after {name}: {model.name} has no jump '{name}'; jumps: "
                          f"{', '.join(model.jump_names) or 'none'}")
    from andyc.runtime.simulate import compile_run

    compile_run(model, method)      # what each point's run calls (its method's alone), once, before the first point
    _run(model, points, settings, out, scheduler, engine, workers, batch, read)


def _metric_items(items) -> list:
    if not items:
        return []           # (the metric parser, and SymPy under it, imported only for metrics: a faster start)
    from andyc.analysis.sweeps.metrics import metric_items

    return metric_items(items)


def _points(grids, samples, dists, seed, points_file, sampler="random"):
    from andyc.analysis.sweeps import points as P

    given = [o for o, v in (("--grid", grids), ("--samples", samples), ("--points", points_file)) if v]
    if len(given) != 1:
        raise P.PointsError("choose the points one way: --grid, --samples (with --dist) or --points"
                            + (f" (given: {', '.join(given)})" if given else ""))
    if dists and not samples:
        raise P.PointsError("--dist goes with --samples N")
    if sampler != "random" and not samples:
        raise P.PointsError(f"--sampler {sampler} goes with --samples N")
    if grids:
        return P.grid(grids)
    if samples:
        return P.samples(samples, dists, seed, sampler)
    return P.from_csv(points_file)


def _run(model, points, settings, out, scheduler, engine, workers, batch, read) -> None:
    from andyc.analysis.sweeps.run import SweepError, run_sweep
    from andyc.analysis.sweeps.store import StoreError

    try:
        summary = run_sweep(model, points, settings, out, scheduler=scheduler, workers=workers, batch=batch,
                            inputs=read, engine=engine)
    except (StoreError, MetricError) as exc:
        raise Refused(str(exc)) from None
    except SweepError as exc:
        click.echo(f"andyc: {exc}", err=True)
        sys.exit(1)
    click.echo(summary.text())


def plot_store(store, out, variable) -> None:
    """`andyc plot STORE`: a heat map of a variable over a grid's two swept names, or a line over one (samples:
    a scatter); default variable: the first metric, else a basin's classes, else the outcome. Codes (the outcome,
    the classes) are drawn one colour each, named by the variable's flag_meanings."""
    from andyc.plot.sweepmap import plot_sweep

    ds = _open(store)
    swept = list(ds.attrs.get("swept", []))
    metrics = [n for n in ds.data_vars if "expression" in ds[n].attrs]
    variable = variable or (metrics[0] if metrics else "basin" if "basin" in ds.data_vars else "outcome")
    if variable not in ds.data_vars:
        raise click.BadParameter(f"{store} has no variable '{variable}'; metrics: {', '.join(metrics) or 'none'} "
                                 f"(or outcome, t_final, wall)", param_hint="--metric")
    data = ds[variable]
    if set(data.dims) - set(swept) - {"point"}:
        raise click.BadParameter(f"'{variable}' has more dimensions than the swept names ({', '.join(data.dims)}); "
                                 f"plot a metric, outcome, t_final or wall", param_hint="--metric")
    if not 1 <= len(swept) <= 2:
        raise click.BadParameter(f"{store} sweeps {len(swept)} names; the plot draws one or two",
                                 param_hint="STORE")
    out = out or str(Path(store).with_suffix(".png"))
    from andyc.cli.plot import check_image_type

    check_output(out, [], "plot")
    check_image_type(out)
    axes = [(n, ds[n].values) for n in swept]
    outcomes = colours = None
    if "flag_meanings" in data.attrs:           # codes: the outcome, a basin's classes
        outcomes = {int(c): m.replace("_", " ") for c, m in zip(data.attrs["flag_values"],
                                                              data.attrs["flag_meanings"].split())}
        if variable == "basin":
            from andyc.plot.basinmap import CLASS_COLOURS as colours
    runs = None
    if outcomes is None and variable != "outcome":      # a metric's map marks the runs that did not finish
        meanings = ds.outcome.attrs["flag_meanings"].split()
        runs = (ds.outcome.values, {int(c): m.replace("_", " ") for c, m in zip(ds.outcome.attrs["flag_values"],
                                                                               meanings)})
    plot_sweep(ds.attrs["kind"] == "grid", axes, data.values, variable, data.attrs.get("expression", ""), out,
               title=f"{ds.attrs['model']}: {variable}", outcomes=outcomes, colours=colours, runs=runs)
    click.echo(f"wrote {out}")


def _open(store):
    from andyc.analysis.sweeps import missing_extra

    needs = missing_extra("andyc plot STORE", "zarr", "xarray")
    if needs:
        raise Refused(needs)
    import xarray as xr

    try:
        ds = xr.open_zarr(store)
    except Exception as exc:
        raise click.BadParameter(f"{store}: not a result store of andyc sweep ({type(exc).__name__})",
                                 param_hint="STORE") from None
    if "swept" not in ds.attrs or "kind" not in ds.attrs:
        raise click.BadParameter(f"{store}: not a result store of andyc sweep", param_hint="STORE")
    return ds


__all__ = ["sweep", "plot_store"]
