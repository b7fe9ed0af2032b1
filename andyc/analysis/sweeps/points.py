"""The points of a sweep: a full grid, Monte Carlo samples or the rows of a CSV file, each point a value of
every swept name.

A swept name is a parameter, an input (its held value) or the initial value of a state (a coordinate, a
speed `<coordinate>_dot` or a declared speed, a signal), as `andyc linearize --at` names them. A grid
keeps its shape (one axis per name, the first name slowest, as numpy's C order), its values the decimal
numbers a user would write (0.4, not linspace's 0.39999999999999997, so that xarray's `ds.sel(m=0.4)` finds
them); samples and CSV rows are a flat list of points.

Samples are drawn with the sweep's seed, so that the same seed gives the same samples: "random" (Monte
Carlo: numpy's Generator, PCG64, the names in the order given), or a space-filling design of scipy.stats.qmc
in the unit cube -- "lhs" (Latin hypercube: each of n equal strata of every name holds one point), "sobol"
(scrambled Sobol' points: n a power of 2) or "halton" (scrambled Halton) -- mapped to each name's
distribution by its inverse CDF (uniform(A,B): A + (B - A) u; normal(MU,SIGMA): MU + SIGMA Phi^-1(u)).

Bad input raises PointsError with one line that says what and how to fix it.
"""

from __future__ import annotations

import csv
import hashlib
import io
import math
import os
import re
import stat
from dataclasses import dataclass
from pathlib import Path

import numpy as np

MAX_POINTS = 10_000_000
MAX_CSV_BYTES = 256 * 2**20     # a points file of MAX_POINTS rows of a few names; read whole, so bounded
DISTRIBUTIONS = ("normal(MU,SIGMA)", "uniform(A,B)")
SAMPLERS = ("random", "lhs", "sobol", "halton")
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_DIST = re.compile(r"^\s*(normal|uniform)\s*\(\s*([^,()]+?)\s*,\s*([^,()]+?)\s*\)\s*$")


class PointsError(ValueError):
    """A sweep's points that cannot be made: an unknown name, an empty range, a bad distribution, a bad CSV."""


@dataclass(frozen=True)
class Points:
    """names: the swept names; values: (n, len(names)), point i's value of each name; shape: the grid's shape
    (one axis per name) or (n,); kind: "grid", "samples" or "points"; axes: each grid axis's values."""
    kind: str
    names: tuple
    values: np.ndarray
    shape: tuple
    axes: tuple = ()
    seed: int | None = None
    sampler: str | None = None      # samples: how they were drawn (SAMPLERS)

    @property
    def n(self) -> int:
        return self.values.shape[0]

    def digest(self) -> str:
        """SHA-256 of the points (names, kind, shape and the values' bytes): a store holds one sweep."""
        h = hashlib.sha256(repr((self.kind, self.names, self.shape)).encode())
        h.update(np.ascontiguousarray(self.values, dtype="<f8").tobytes())
        return h.hexdigest()

    def index(self, flat: np.ndarray) -> tuple:
        """The grid indices (one array per axis) of flat point numbers; for samples and rows, the numbers."""
        return np.unravel_index(np.asarray(flat), self.shape)


def sweepable(model) -> dict:
    """{name: (kind, index)} of every name a sweep may set in a CompiledModel: "parameter", "input" or
    "state" (an initial value)."""
    names = {n: ("state", i) for i, n in enumerate(model.state_names)}
    names.update({n: ("input", i) for i, n in enumerate(model.input_names)})
    names.update({n: ("parameter", i) for i, n in enumerate(model.parameter_names)})
    return names


def check_names(names, model) -> None:
    """PointsError for a name that is no parameter, input or state of `model`, or a name given twice."""
    known = sweepable(model)
    seen = set()
    for name in names:
        if name not in known:
            raise PointsError(f"unknown name '{name}': {model.name} has no parameter, input or state of that name; "
                              f"sweepable: {', '.join(known)}")
        if name in seen:
            raise PointsError(f"'{name}' is swept twice; give each name once")
        seen.add(name)


def grid(specs, option: str = "--grid") -> Points:
    """The full grid of ('NAME=A:B:N', ...): N values from A to B (both included) per name; `option` names
    the option in messages."""
    names, ranges = [], []
    for text in specs:
        name, sep, rest = text.partition("=")
        parts = rest.split(":")
        if not sep or len(parts) != 3 or not _NAME.fullmatch(name.strip()):
            raise PointsError(f"{option} '{text}': not NAME=FROM:TO:COUNT (e.g. slope=0:0.1:20)")
        low, high = _number(parts[0], text, option), _number(parts[1], text, option)
        count = parts[2].strip()
        if not count.lstrip("-").isdigit():
            raise PointsError(f"{option} '{text[:80]}': the count '{count[:30]}' is not a whole number")
        if len(count) > 12:                 # (int() of thousands of digits is refused, or slow)
            raise PointsError(f"{option} '{text[:80]}': the count {count[:20]}... is past the limit of "
                              f"{MAX_POINTS:.0e} points; sweep fewer")
        if int(count) < 1:
            raise PointsError(f"{option} '{text}': an empty range ({count} values); give a count of at least 1")
        if int(count) > 1 and low == high:
            raise PointsError(f"{option} '{text}': an empty range (from {low:g} to {high:g}); give two different "
                              f"ends, or a count of 1")
        names.append(name.strip())
        ranges.append((low, high, int(count)))
    shape = tuple(n for _, _, n in ranges)
    _check_count(math.prod(shape), option)  # from the counts, before any value is made
    axes = [decimal_axis(low, high, n) for low, high, n in ranges]
    mesh = np.meshgrid(*axes, indexing="ij")
    values = np.stack([m.ravel() for m in mesh], axis=1) if axes else np.zeros((0, 0))
    return Points("grid", tuple(names), values, shape, tuple(axes))


def decimal_axis(low: float, high: float, n: int) -> np.ndarray:
    """numpy.linspace(low, high, n), each value replaced by the shortest decimal (at most 12 significant
    digits) within 4 units in the last place of it, when there is one: linspace's rounding undone (0.4 for
    0.39999999999999997), a value with no short decimal (a third) left as linspace made it."""
    axis = np.linspace(low, high, n)
    for k, value in enumerate(axis[1:-1], start=1):
        for digits in range(1, 13):
            short = float(f"{value:.{digits}g}")
            if abs(short - value) <= 4 * np.spacing(abs(value)):
                axis[k] = short
                break
    return axis


def samples(n: int, specs, seed: int, sampler: str = "random") -> Points:
    """n samples of ('NAME=normal(MU,SIGMA)' | 'NAME=uniform(A,B)', ...) with the given seed: "random" draws
    them in that order from numpy.random.default_rng(seed); "lhs", "sobol" and "halton" take scipy.stats.qmc's
    design of n points in the unit cube (one dimension per name, in that order; scrambled, seeded with
    default_rng(seed)) through each distribution's inverse CDF."""
    if sampler not in SAMPLERS:
        raise PointsError(f"--sampler {sampler}: not a sampler; choose one of {', '.join(SAMPLERS)}")
    if n < 1:
        raise PointsError(f"--samples {n}: give at least 1 sample")
    _check_count(n)
    if not specs:
        raise PointsError("--samples needs at least one --dist NAME=normal(MU,SIGMA) or NAME=uniform(A,B)")
    if sampler == "sobol" and n & (n - 1):
        raise PointsError(f"--sampler sobol: {n} samples lose the balance of Sobol' points; give a power of 2 "
                          f"({1 << (n - 1).bit_length() >> 1} or {1 << (n - 1).bit_length()}), or --sampler lhs")
    rng = np.random.default_rng(seed)
    unit = None if sampler == "random" else _design(sampler, len(specs), n, rng)
    names, columns = [], []
    for text in specs:
        name, sep, rest = text.partition("=")
        found = _DIST.match(rest)
        if not sep or not _NAME.fullmatch(name.strip()) or found is None:
            raise PointsError(f"--dist '{text}': a bad distribution; write NAME={' or NAME='.join(DISTRIBUTIONS)}")
        kind, a, b = found.group(1), _number(found.group(2), text, "--dist"), _number(found.group(3), text, "--dist")
        if kind == "normal" and not b > 0:
            raise PointsError(f"--dist '{text}': a bad distribution: the standard deviation {b:g} must be above 0")
        if kind == "uniform" and not b > a:
            raise PointsError(f"--dist '{text}': a bad distribution: uniform(A,B) needs A < B, got {a:g}, {b:g}")
        names.append(name.strip())
        if unit is None:
            columns.append(rng.normal(a, b, n) if kind == "normal" else rng.uniform(a, b, n))
        else:
            u = unit[:, len(columns)]
            columns.append(_normal_quantile(u, a, b) if kind == "normal" else a + (b - a) * u)
    return Points("samples", tuple(names), np.stack(columns, axis=1), (n,), seed=seed, sampler=sampler)


def _design(sampler: str, d: int, n: int, rng) -> np.ndarray:
    """n points of scipy.stats.qmc's `sampler` in the unit cube of dimension d."""
    from scipy.stats import qmc

    engine = {"lhs": qmc.LatinHypercube, "sobol": qmc.Sobol, "halton": qmc.Halton}[sampler](d, rng=rng)
    return engine.random(n)


def _normal_quantile(u: np.ndarray, mu: float, sigma: float) -> np.ndarray:
    from scipy.special import ndtri

    return mu + sigma * ndtri(u)


def from_csv(path) -> Points:
    """The rows of a CSV file: a header of names, then one point a row, every value a finite number."""
    path = Path(path)
    try:
        text = read_points_text(path)
        rows = [(k, row) for k, row in enumerate(csv.reader(io.StringIO(text, newline="")), start=1)
                if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
    except FileNotFoundError:
        raise PointsError(f"{path}: no such file (--points)") from None
    except (UnicodeDecodeError, csv.Error, OSError) as exc:
        raise PointsError(f"{path}:1: cannot read it as a CSV text file ({exc})") from None
    if not rows:
        raise PointsError(f"{path}:1: empty; write a header of names, then one point a row")
    line, header = rows[0]
    names = [h.strip() for h in header]
    bad = next((h for h in names if not _NAME.fullmatch(h)), None)
    if bad is not None:
        raise PointsError(f"{path}:{line}: the header's '{bad}' is not a name; write the swept names, e.g. m,g")
    if len(rows) == 1:
        raise PointsError(f"{path}:{line}: a header and no points; add one point a row")
    _check_count(len(rows) - 1)
    values = np.empty((len(rows) - 1, len(names)))
    for r, (k, row) in enumerate(rows[1:]):
        if len(row) != len(names):
            raise PointsError(f"{path}:{k}: {len(row)} values for {len(names)} names; give one value per name")
        for c, cell in enumerate(row):
            try:
                values[r, c] = float(cell)
            except ValueError:
                values[r, c] = math.nan
            if not math.isfinite(values[r, c]):
                raise PointsError(f"{path}:{k}: {names[c]} is {cell.strip()!r}, not a finite number")
    return Points("points", tuple(names), values, (len(values),))


def read_points_text(path: Path) -> str:
    """The text of a points file: a regular file (a pipe or a device such as /dev/zero would be read without
    end) of at most MAX_CSV_BYTES, checked by its size on disk and again while reading (a file that grows)."""
    info = os.stat(path)
    if not stat.S_ISREG(info.st_mode):
        raise PointsError(f"{path}:1: this is a {'folder' if stat.S_ISDIR(info.st_mode) else 'special file'}, "
                          f"not a CSV file; give --points a regular file (a header of names, one point a row)")
    too_large = f"{path}:1: the file has more than {MAX_CSV_BYTES // 2**20} MB, past andyc's limit for --points; " \
                f"sweep fewer points (at most {MAX_POINTS:.0e}), or split the file"
    if info.st_size > MAX_CSV_BYTES:
        raise PointsError(too_large)
    # (O_NONBLOCK: a file replaced by a pipe between the two looks does not block the open)
    with open(os.open(path, os.O_RDONLY | getattr(os, "O_NONBLOCK", 0)), "rb") as fh:
        if not stat.S_ISREG(os.fstat(fh.fileno()).st_mode):
            raise PointsError(f"{path}:1: this is a special file, not a CSV file; give --points a regular file")
        raw = fh.read(MAX_CSV_BYTES + 1)
    if len(raw) > MAX_CSV_BYTES:
        raise PointsError(too_large)
    return raw.decode("utf-8")


def _number(text: str, item: str, option: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise PointsError(f"{option} '{item}': '{text.strip()}' is not a number") from None
    if not math.isfinite(value):
        raise PointsError(f"{option} '{item}': '{text.strip()}' is not a finite number")
    return value


def _check_count(n: int, option: str = "") -> None:
    if n > MAX_POINTS:
        raise PointsError(f"{option + ': ' if option else ''}{n} points, past the limit of {MAX_POINTS:.0e}; "
                          f"sweep fewer")
