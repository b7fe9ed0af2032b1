"""Work-precision sweeps (`andyc bench MODEL`): error against cost, one line per method.

Each fixed-step method runs at each step h (adjusted to divide T) and each
adaptive method at each tolerance (rtol = atol), to T; each run's error is the
largest difference of its final state from the reference's (the model's closed
form where it declares one, else DOP853 at 1e-13),
and its cost the wall time (best of `repeats`, compilation excluded) and the
right-hand-side evaluations. Constraint residuals and energy drift are kept
too. Diagrams: error against wall time and against evaluations, log-log.
"""

from __future__ import annotations

import csv
import math
import textwrap
from dataclasses import asdict
from pathlib import Path

# (the reference function under another name: `reference` is sweep's keyword choosing it)
from andyc.analysis.accuracy import Point, ReferenceSolution, divides, run_point
from andyc.analysis.accuracy import reference_solution
from andyc.runtime.simulate import FIXED_STEP
from andyc.outputs import write_atomic

DEFAULT_TOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)


def default_steps(t_end: float) -> list:
    """Seven steps from T/100 down to T/10000, each dividing T."""
    return [t_end / n for n in (100, 200, 500, 1000, 2000, 5000, 10000)]


def sweep(model, methods, t_end: float, steps=None, tols=DEFAULT_TOLS, repeats: int = 3, progress=None,
          reference: str | ReferenceSolution = "auto", **options) -> tuple[ReferenceSolution, list[Point]]:
    """Every method at every step or tolerance, against the reference: "auto", "closed-form" or "DOP853"
    (andyc.analysis.accuracy.reference_solution), or a ReferenceSolution to t_end made already with the same
    options."""
    ref = reference_solution(model, t_end, reference, **options)
    steps = sorted({divides(h, t_end) for h in (steps or default_steps(t_end))}, reverse=True)
    points = []
    for method in methods:
        for setting in (steps if method in FIXED_STEP else tols):
            points.append(run_point(model, ref, method, setting, repeats, **options))
            if progress:
                progress(points[-1])
    return ref, points


def write_csv(points: list[Point], path: Path) -> None:
    fields = list(asdict(points[0]))
    with write_atomic(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(fields)
        for p in points:
            w.writerow(asdict(p).values())


def draw(points: list[Point], ref: ReferenceSolution, title: str, stem: Path) -> list[Path]:
    """Error against wall time and against right-hand-side evaluations, log-log; PNG and SVG."""
    from matplotlib.figure import Figure

    fig = Figure(figsize=(12, 5), layout="constrained")
    axes = fig.subplots(1, 2, sharey=True)
    for k, method in enumerate(dict.fromkeys(p.method for p in points)):
        mine = [p for p in points if p.method == method and math.isfinite(p.error) and p.error > 0]
        style = {"marker": "os^vD<>p"[k % 8], "label": method, "color": f"C{k}"}
        for ax, cost in zip(axes, ("wall", "rhs")):
            ax.loglog([getattr(p, cost) for p in mine], [p.error for p in mine], **style)
    axes[0].set_xlabel("wall time, s (best of the repeats)")
    axes[1].set_xlabel("right-hand-side evaluations")
    axes[0].set_ylabel(f"error at T: max |x - x_ref| (amplitude {ref.scale:.3g})")
    for ax in axes:
        ax.grid(alpha=0.3, which="both")
    axes[1].legend(loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    fig.suptitle(textwrap.fill(f"{title}: work-precision over T = {ref.t_end:g} s (reference: {ref.source})", 110))
    paths = [stem.with_name(stem.name + ".png"), stem.with_name(stem.name + ".svg")]    # (the stem may hold a '.')
    for path in paths:
        with write_atomic(path) as tmp:
            fig.savefig(tmp, dpi=110, format=path.suffix[1:])
    return paths
