"""Stability scans (`andyc stability`): step size against method, each run classified.

Each run to the horizon T is one of

    accurate     finished, state error at T within tol x the reference's amplitude
    inaccurate   finished and bounded, but its error is past that: stable, not accurate
    failed       the run stopped (non-finite state, singular mass matrix, dependent
                 rows, Zeno), blew up (|x| past `blowup` x the reference's largest),
                 lost its constraints (a residual past `residual_tol`), or missed an
                 event (a jump count other than the reference's)

and a failure says what failed and when. On the test equation x'' = -w^2 x
the boundary of explicit RK4 is h w = 2 sqrt(2), where its stability region
meets the imaginary axis (|R(iy)|^2 = 1 - y^6/72 + y^8/576 = 1).
"""

from __future__ import annotations

import csv
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from andyc.analysis.sweep import Point, Reference, divides, reference, run_point

ACCURATE, INACCURATE, FAILED = "accurate", "inaccurate", "failed"
COLOURS = {ACCURATE: "#2ca02c", INACCURATE: "#ffbf00", FAILED: "#d62728"}


@dataclass
class Verdict:
    point: Point
    verdict: str
    reason: str


def classify(point: Point, ref: Reference, tol: float = 1e-3, blowup: float = 1e3,
             residual_tol: float = 1e-6) -> Verdict:
    if not point.finished:
        return Verdict(point, FAILED, point.status.removeprefix("stopped: ").split("; the ")[0])
    if point.growth > blowup:
        return Verdict(point, FAILED, f"blew up: |x| reached {point.growth:.3g} x the reference's largest "
                                      f"(past {blowup:g} x at t = {point.blowup_at:.6g} s)")
    if point.residual > residual_tol:
        return Verdict(point, FAILED, f"lost its constraints: residual {point.residual:.3g} (bound "
                                      f"{residual_tol:g}, passed at t = {point.residual_at:.6g} s)")
    if point.jumps != ref.jumps:
        return Verdict(point, FAILED, f"missed an event: {point.jumps} jumps, the reference {ref.jumps}")
    if point.error > tol * ref.scale:
        return Verdict(point, INACCURATE, f"error {point.error:.3g} at T past {tol:g} x the amplitude "
                                          f"{ref.scale:.3g}")
    return Verdict(point, ACCURATE, f"error {point.error:.3g} at T")


def scan(model, methods, steps, horizon: float, tol: float = 1e-3, blowup: float = 1e3,
         residual_tol: float = 1e-6, progress=None, **options) -> tuple[Reference, list[Verdict]]:
    """Every method (fixed-step) at every step (adjusted to divide the horizon), classified."""
    ref = reference(model, horizon, **options)
    settings = sorted({divides(h, horizon) for h in steps})
    out = []
    for method in methods:
        for h in settings:
            point = run_point(model, ref, method, h, blowup=blowup, residual_tol=residual_tol, **options)
            out.append(classify(point, ref, tol, blowup, residual_tol))
            if progress:
                progress(out[-1])
    return ref, out


def boundaries(verdicts: list[Verdict]) -> dict:
    """method -> (largest accurate step, smallest failing step, its reason), None where there is none."""
    out = {}
    for method in dict.fromkeys(v.point.method for v in verdicts):
        mine = [v for v in verdicts if v.point.method == method]
        accurate = [v.point.setting for v in mine if v.verdict == ACCURATE]
        failed = [v for v in mine if v.verdict == FAILED]
        first = min(failed, key=lambda v: v.point.setting) if failed else None
        out[method] = (max(accurate) if accurate else None, first.point.setting if first else None,
                       first.reason if first else None)
    return out


def write_csv(verdicts: list[Verdict], path: Path) -> None:
    fields = list(asdict(verdicts[0].point)) + ["verdict", "reason"]
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["step" if f == "setting" else f for f in fields])
        for v in verdicts:
            w.writerow([*asdict(v.point).values(), v.verdict, v.reason])


def draw_map(verdicts: list[Verdict], ref: Reference, title: str, stem: Path) -> list[Path]:
    """Method against step, one square per run coloured by its verdict; PNG and SVG."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    methods = list(dict.fromkeys(v.point.method for v in verdicts))
    fig = Figure(figsize=(10, 1.2 + 0.6 * len(methods)), layout="constrained")
    ax = fig.add_subplot()
    for v in verdicts:
        ax.scatter(v.point.setting, methods.index(v.point.method), marker="s", s=90, color=COLOURS[v.verdict],
                   edgecolors="none")
    ax.set_xscale("log")
    ax.set_yticks(range(len(methods)), methods)
    ax.set_ylim(-0.7, len(methods) - 0.3)
    ax.set_xlabel("step h, s")
    ax.set_title(f"{title}: stability over T = {ref.t_end:g} s")
    ax.legend([Line2D([], [], marker="s", ls="", color=c) for c in COLOURS.values()], list(COLOURS),
              loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    ax.grid(alpha=0.3, axis="x", which="both")
    paths = [stem.with_suffix(".png"), stem.with_suffix(".svg")]
    for path in paths:
        fig.savefig(path, dpi=110)
    return paths


def geometric(lo: float, hi: float, n: int) -> list[float]:
    return list(np.geomspace(lo, hi, n)) if n > 1 else [lo]


def rk4_bound(omega: float) -> float:
    """RK4's largest stable step on x'' = -omega^2 x: h omega = 2 sqrt(2)."""
    return 2.0 * math.sqrt(2.0) / omega
