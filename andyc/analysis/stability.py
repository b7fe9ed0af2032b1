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

A scan may have a second axis, `variants`: values of a parameter (stiffness,
say) or Baumgarte gains set from one rate w (`baumgarte_rates`); the map is
then step against that value, one panel per method.
"""

from __future__ import annotations

import csv
import math
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

# (the reference function under another name: `reference` is scan's keyword choosing it)
from andyc.analysis.accuracy import Point, ReferenceSolution, divides, run_point
from andyc.errors import SimulationError
from andyc.analysis.accuracy import reference_solution
from andyc.outputs import write_atomic

ACCURATE, INACCURATE, FAILED = "accurate", "inaccurate", "failed"
COLOURS = {ACCURATE: "#2ca02c", INACCURATE: "#ffbf00", FAILED: "#d62728"}


@dataclass
class Verdict:
    point: Point
    verdict: str
    reason: str
    variant: float | None = None     # the value on the scan's second axis, if it has one


@dataclass(frozen=True)
class Variant:
    """A value on a scan's second axis, and the parameters it sets."""
    axis: str                        # the axis label, e.g. "Baumgarte rate w, 1/s"
    value: float
    parameters: dict                 # parameter name -> value
    changes_solution: bool = True    # False: the exact solution does not depend on them (one reference)

    @property
    def name(self) -> str:
        """The axis label without its units and notes: "Baumgarte w"."""
        return self.axis.split(",")[0]


def parameter_values(name: str, values) -> list[Variant]:
    """The parameter `name` at each value; each changes the solution, so each has its own reference."""
    return [Variant(name, float(v), {name: float(v)}) for v in values]


def baumgarte_rates(model, rates) -> list[Variant]:
    """Baumgarte gains K_s = w^2, K_d = 2 w for each w: critical damping at rate w for a unit effective mass.

    ANDY eq. 15 adds the soft terms as generalized forces, -A^T (K_s phi + K_d phi'),
    next to the multipliers, so a holonomic row's error obeys
    e'' + W (K_d e' + K_s e) = 0 and a nonholonomic row's residual e' + W K_d e = 0,
    with W = A M^-1 A^T the row's inverse effective mass: (d/dt + w)^2 e = 0
    where W = 1. The gains must be parameters (gains: {stiffness: k_s, damping:
    k_d}); the exact solution does not depend on them, so one reference serves
    every w.
    """
    roles: dict[str, str] = {}
    for constraint, rows, stiffness, damping in model.constraint_gains:
        holonomic = rows == "holonomic"
        for role, gain in (("stiffness", stiffness), ("damping", damping)):
            if role == "stiffness" and not holonomic:
                continue
            if gain is None:
                raise SimulationError(
                    f"constraint '{constraint}': its {role} gain is not a parameter, so it cannot be scanned; "
                    f"declare gains: {{stiffness: k_s, damping: k_d}} with parameters k_s and k_d "
                    f"({'both gains' if holonomic else 'damping only: it is nonholonomic'})")
            if roles.setdefault(gain, role) != role:
                raise SimulationError(f"parameter '{gain}' is a stiffness gain in one constraint and a damping gain "
                                      f"in another; give each role its own parameter")
    if not roles:
        raise SimulationError(f"{model.name} has no constraints, so no Baumgarte gains to scan")
    return [Variant("Baumgarte w, 1/s (K_s = w^2, K_d = 2w)", float(w),
                    {gain: (w * w if role == "stiffness" else 2.0 * w) for gain, role in roles.items()},
                    changes_solution=False) for w in rates]


def classify(point: Point, ref: ReferenceSolution, tol: float = 1e-3, blowup: float = 1e3,
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
         residual_tol: float = 1e-6, progress=None, reference: str | ReferenceSolution = "auto", variants=None,
         **options) -> tuple[ReferenceSolution, list[Verdict]]:
    """Every method (fixed-step) at every step (adjusted to divide the horizon) and every variant, classified
    against the reference (andyc.analysis.accuracy.reference_solution: "auto", "closed-form" or "DOP853").
    Returns the first variant's reference and the verdicts."""
    if isinstance(reference, ReferenceSolution) and any(v.changes_solution for v in variants or []):
        raise SimulationError("one reference cannot serve a scan over parameters that change the solution")
    settings = sorted({divides(h, horizon) for h in steps})
    parameters = options.pop("parameters", None) or {}
    refs = {}
    out = []
    for variant in variants or [None]:
        run_options = {**options, "parameters": {**parameters, **(variant.parameters if variant else {})}}
        key = variant.value if variant and variant.changes_solution else None
        if key not in refs:
            refs[key] = reference_solution(model, horizon, reference, **run_options)
        ref = refs[key]
        for method in methods:
            for h in settings:
                point = run_point(model, ref, method, h, blowup=blowup, residual_tol=residual_tol, **run_options)
                out.append(classify(point, ref, tol, blowup, residual_tol))
                out[-1].variant = variant.value if variant else None
                if progress:
                    progress(out[-1])
    return next(iter(refs.values())), out


def boundaries(verdicts: list[Verdict]) -> dict:
    """(method, variant) -> (largest accurate step, smallest failing step, its reason), None where there is
    none; variant is None in a scan without a second axis."""
    out = {}
    for method, variant in dict.fromkeys((v.point.method, v.variant) for v in verdicts):
        mine = [v for v in verdicts if v.point.method == method and v.variant == variant]
        accurate = [v.point.setting for v in mine if v.verdict == ACCURATE]
        failed = [v for v in mine if v.verdict == FAILED]
        first = min(failed, key=lambda v: v.point.setting) if failed else None
        out[method, variant] = (max(accurate) if accurate else None, first.point.setting if first else None,
                       first.reason if first else None)
    return out


def write_csv(verdicts: list[Verdict], path: Path) -> None:
    fields = list(asdict(verdicts[0].point)) + ["variant", "verdict", "reason"]
    with write_atomic(path) as tmp, open(tmp, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["step" if f == "setting" else f for f in fields])
        for v in verdicts:
            w.writerow([*asdict(v.point).values(), "" if v.variant is None else v.variant, v.verdict, v.reason])


def draw_map(verdicts: list[Verdict], ref: ReferenceSolution, title: str, stem: Path,
             axis: str | None = None) -> list[Path]:
    """Method against step, one square per run coloured by its verdict; with variants (their axis label
    `axis`), one panel per method, the variant's value against step. PNG and SVG."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D

    methods = list(dict.fromkeys(v.point.method for v in verdicts))
    two_d = any(v.variant is not None for v in verdicts)
    rows = len(methods) if two_d else 1
    fig = Figure(figsize=(10, (3.0 * rows + 0.8) if two_d else 1.2 + 0.6 * len(methods)), layout="constrained")
    axes = fig.subplots(rows, 1, sharex=True, squeeze=False)[:, 0]
    for v in verdicts:
        ax = axes[methods.index(v.point.method)] if two_d else axes[0]
        y = v.variant if two_d else methods.index(v.point.method)
        ax.scatter(v.point.setting, y, marker="s", s=90 if not two_d else 60, color=COLOURS[v.verdict],
                   edgecolors="none")
    for ax, method in zip(axes, methods):
        ax.set_xscale("log")
        ax.grid(alpha=0.3, which="both")
        if two_d:
            ax.set_yscale("log")
            ax.set_ylabel(axis or "variant")
            ax.set_title(method, fontsize=10, loc="left")
    if not two_d:
        axes[0].set_yticks(range(len(methods)), methods)
        axes[0].set_ylim(-0.7, len(methods) - 0.3)
    axes[-1].set_xlabel("step h, s")
    fig.suptitle(f"{title}: stability over T = {ref.t_end:g} s")
    axes[0].legend([Line2D([], [], marker="s", ls="", color=c) for c in COLOURS.values()], list(COLOURS),
                   loc="upper left", bbox_to_anchor=(1.0, 1.0), frameon=False)
    paths = [stem.with_name(stem.name + ".png"), stem.with_name(stem.name + ".svg")]    # (the stem may hold a '.')
    for path in paths:
        with write_atomic(path) as tmp:
            fig.savefig(tmp, dpi=110, format=path.suffix[1:])
    return paths


def geometric(lo: float, hi: float, n: int) -> list[float]:
    return list(np.geomspace(lo, hi, n)) if n > 1 else [lo]


def rk4_bound(omega: float) -> float:
    """RK4's largest stable step on x'' = -omega^2 x: h omega = 2 sqrt(2)."""
    return 2.0 * math.sqrt(2.0) / omega
