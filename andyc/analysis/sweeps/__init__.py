"""Sweeps, Monte Carlo and grids of runs (`andyc sweep`), in this process or on Dask, into one result store.

    points.py   the points: a full grid, samples (seeded: Monte Carlo or scipy.stats.qmc designs) or a CSV file's rows
    metrics.py  --metric NAME=EXPR: expressions of a run (its end, max/min/mean, at(T, E), jumps), evaluated
                on the run's arrays without running user text
    worker.py   a batch of points on a worker: the compiled model loaded once per process, a failure recorded
    store.py    the Zarr store xarray opens: the swept names as coordinates, the metrics as variables
    run.py      the driver: batches on threads here or as dask.distributed tasks, written as they end, resumable

Importing this package imports neither Dask nor Zarr (run.py and store.py import them when they work). They
are the `sweep` extra (`pip install 'andyc[sweep]'`), not the core: missing_extra says which are missing.
"""

from importlib.util import find_spec

_PACKAGES = {"zarr": "zarr", "xarray": "xarray", "distributed": "dask[distributed]"}


def missing_extra(what: str, *modules: str) -> str | None:
    """The message for `what` (a command) when any of `modules` (zarr, xarray, distributed: the sweep extra's) is
    not installed, else None. Looked up without importing them (Dask's import alone takes a second)."""
    missing = [_PACKAGES[m] for m in modules if find_spec(m) is None]
    if not missing:
        return None
    return (f"{what} needs {' and '.join(missing)}, not installed with andyc's core; install the sweep extra: "
            f"`pip install 'andyc[sweep]'`")
