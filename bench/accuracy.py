"""Accuracy against cost on the four models of issue 7, for docs/BENCHMARKS.md.

The swing bar, the ball in a bowl, the four-bar through its singular pose and
the passive walker. For each: a work-precision sweep (andyc.analysis.workprecision:
every method at its steps or tolerances, error at T against wall time and
evaluations), a stability scan over steps (andyc.analysis.stability: accurate,
inaccurate or failed, and what failed when), for the constrained models a scan
over Baumgarte gains, and animations of the swing bar and the walker.

The reading under each model's figures is written from the numbers this run
measured: which method is cheapest at each accuracy and where each fails. Only
the paragraph saying what the model is and why it is hard is written by hand.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import andyc
from andyc.analysis import stability, workprecision
from andyc.analysis.accuracy import ReferenceSolution, reference_solution
from andyc.plot import animate_run
from andyc.independent.closed_forms import fourbar_branch
from andyc.runtime.simulate import FIXED_STEP

ROOT = Path(__file__).resolve().parents[1]
TARGETS = (1e-3, 1e-6, 1e-9)        # error at T relative to the reference's amplitude


@dataclass
class Case:
    """One model of the benchmark, and how it is swept and scanned."""
    name: str                        # models/<name>.yaml
    title: str
    about: str                       # what the model is and why it is hard (by hand)
    t_end: float                     # work-precision horizon, s
    methods: list
    steps: list
    horizon: float                   # stability horizon, s
    scan_methods: list
    scan_steps: list
    rates: list | None = None        # Baumgarte rates w, 1/s (constrained models)
    rate_steps: list | None = None
    options: dict = field(default_factory=dict)
    reference: object = "auto"       # "auto" or a function (model, t_end) -> ReferenceSolution
    notes: object = None             # a function (model, t_end) -> more measured facts for the reading


def fourbar_reference(model, t_end: float) -> ReferenceSolution:
    """The four-bar's exact motion: its parallelogram branch, a one-degree-of-freedom pendulum.

    (andyc.independent.closed_forms.fourbar_branch, DOP853 at 1e-13 on the reduced ODE.)
    The coupler translates, so th2 = -th1 and th3 = th1 at all times; velocity is
    continuous through the flat pose, where the crossed branch meets this one at
    another tangent, so the exact motion cannot change branch there.
    """
    p = dict(zip(model.parameter_names, model.parameter_defaults))
    x0 = model.initial_state(model.parameter_defaults)
    tic = time.perf_counter()
    times = np.linspace(0.0, t_end, 201)
    th, w = fourbar_branch(p, x0[0], x0[3], times)
    states = np.column_stack([th, -th, th, w, -w, w])
    return ReferenceSolution(t_end, states[-1].copy(), float(np.abs(states).max()), 0, time.perf_counter() - tic,
                     "the parallelogram branch, a 1-DOF pendulum, DOP853 at 1e-13")


def fourbar_dop853_branch(model, t_end: float) -> list:
    """Where DOP853 at 1e-13 on the full model leaves the parallelogram branch (|th1 + th2|, the coupler's
    angle, passes 1e-3 rad), which is why it is not the four-bar's reference."""
    run = andyc.simulate(model, t_end, dt=0.01, method="DOP853", rtol=1e-13, atol=1e-13, progress=False)
    coupler = np.abs(run.column("th1") + run.column("th2"))
    if not (coupler > 1e-3).any():
        return [f"DOP853 at 1e-13 on the full model stays on the parallelogram branch to {t_end:g} s."]
    k = int(np.argmax(coupler > 1e-3))
    return [f"DOP853 at 1e-13 on the full model leaves the parallelogram branch at t = {run.time[k]:.2f} s "
            f"(th1 = {run.column('th1')[k]:.3f} rad, by a flat pose) and its coupler then turns by up to "
            f"{coupler.max():.2f} rad: a small residual, the wrong motion."]


def geom(hi: float, lo: float, n: int) -> list:
    return list(np.geomspace(hi, lo, n))


CASES = [
    Case("swing_bar", "Swing bar (ANDY §3.1)",
         "A bar driven about the vertical by a constant torque carries a ball joint (a unit quaternion) and two "
         "hanging bars; dampers at each centre of mass. Unconstrained, 9 ODEs, no energy to conserve (the "
         "torque and the dampers work). rk4 renormalizes the quaternion after every step; the adaptive methods "
         "do not.",
         t_end=5.0, methods=["rk4", "DOP853", "RK45", "Radau"], steps=geom(0.05, 2e-4, 7),
         horizon=5.0, scan_methods=["rk4"], scan_steps=geom(0.5, 1e-4, 25)),
    Case("ball_in_bowl", "Ball in a bowl (Braun & Goldfarb Part II, §3.1)",
         "A ball rolls without slipping inside a spherical bowl: one holonomic row (it stays on the bowl) and "
         "two nonholonomic rows (no slip), energy conserved. `rk4` without projection is the same computation "
         "as `lagrange` here (the rows are independent), so it is not drawn twice. The stability scan runs "
         "100 s, the horizon of Braun & Goldfarb's Fig. 2, long enough for the constraints to drift.",
         t_end=10.0, methods=["projection", "lagrange", "baumgarte", "DOP853", "Radau"],
         steps=geom(0.1, 1e-3, 7), horizon=100.0, scan_methods=["projection", "lagrange", "baumgarte"],
         scan_steps=geom(0.5, 1e-3, 19), rates=geom(0.1, 100.0, 7), rate_steps=geom(0.5, 1e-3, 10)),
    Case("fourbar", "Four-bar through its singular pose",
         "A parallelogram four-bar turning over the top: twice a turn all links lie on one line, where the "
         "closure's Jacobian loses a rank and the crossed (anti-parallelogram) branch meets this one. The "
         "reference is the exact motion on the parallelogram branch (a one-degree-of-freedom pendulum, "
         "integrated at 1e-13), not DOP853 on the full model: a method that crosses to the other branch "
         "there is wrong by O(1) however small its residual.",
         t_end=10.0, methods=["projection", "lagrange", "baumgarte", "DOP853", "Radau"],
         steps=geom(0.02, 1e-4, 7), horizon=10.0, scan_methods=["projection", "lagrange", "baumgarte"],
         scan_steps=geom(0.2, 1e-4, 19), rates=geom(0.3, 300.0, 7), rate_steps=geom(0.2, 1e-4, 10),
         reference=fourbar_reference, notes=fourbar_dop853_branch),
    Case("passive_walker", "Passive walker with knees (ANDY §3.2)",
         "A kneed walker down a 0.35 rad slope: six flows switched by knee strikes, knee releases and heel "
         "strikes (plastic impacts), three or four active constraint rows per flow. Error at T is after "
         "several jumps, so it includes the error of every event time; a missed or extra jump is a failure. "
         "`rk4` without projection is the same computation as `lagrange` here, and the walker declares no "
         "Baumgarte gains.",
         t_end=3.0, methods=["projection", "lagrange", "DOP853", "Radau"], steps=geom(0.03, 3e-4, 7),
         horizon=6.0, scan_methods=["projection", "lagrange"], scan_steps=geom(0.1, 1e-4, 19)),
]

ANIMATIONS = {"swing_bar": {"t_end": 5.0, "dt": 1e-3, "every": 10},
              "passive_walker": {"t_end": 12.5, "dt": 1e-3, "every": 10, "method": "projection",
                                 "events": andyc.Events(stop_after={"strike_inner_foot": 10})}}


@dataclass
class Result:
    case: Case
    ref: ReferenceSolution
    points: list
    scan_ref: ReferenceSolution
    verdicts: list
    rate_verdicts: list
    figures: dict                    # what -> path relative to docs/
    seconds: float
    notes: list                      # the case's own measured facts


def run_case(case: Case, build: Path, out: Path, log=print) -> Result:
    tic = time.perf_counter()
    model, _ = andyc.compile_model(ROOT / "models" / f"{case.name}.yaml", build)
    figures = {}

    def ref_for(t_end):
        return case.reference(model, t_end) if callable(case.reference) else reference_solution(model, t_end,
                                                                                       **case.options)

    ref = ref_for(case.t_end)
    ref, points = workprecision.sweep(model, case.methods, case.t_end, case.steps, repeats=3, reference=ref,
                                      **case.options)
    stem = out / f"{case.name}_work_precision"
    workprecision.write_csv(points, stem.with_suffix(".csv"))
    workprecision.draw(points, ref, case.title, stem)
    figures["work-precision"] = stem.with_suffix(".png")
    log(f"  {case.name}: work-precision, {len(points)} runs ({time.perf_counter() - tic:.0f} s)")

    scan_ref = ref if case.horizon == case.t_end else ref_for(case.horizon)     # (one reference, not two)
    scan_ref, verdicts = stability.scan(model, case.scan_methods, case.scan_steps, case.horizon,
                                        reference=scan_ref, **case.options)
    stem = out / f"{case.name}_stability"
    stability.write_csv(verdicts, stem.with_suffix(".csv"))
    stability.draw_map(verdicts, scan_ref, case.title, stem)
    figures["stability"] = stem.with_suffix(".png")
    log(f"  {case.name}: stability, {len(verdicts)} runs ({time.perf_counter() - tic:.0f} s)")

    rate_verdicts = []
    if case.rates:
        variants = stability.baumgarte_rates(model, case.rates)
        _, rate_verdicts = stability.scan(model, ["baumgarte"], case.rate_steps, case.horizon, reference=scan_ref,
                                          variants=variants, **case.options)
        stem = out / f"{case.name}_baumgarte_gains"
        stability.write_csv(rate_verdicts, stem.with_suffix(".csv"))
        stability.draw_map(rate_verdicts, scan_ref, case.title + ", Baumgarte", stem, variants[0].axis)
        figures["Baumgarte gains"] = stem.with_suffix(".png")
        log(f"  {case.name}: Baumgarte gains, {len(rate_verdicts)} runs ({time.perf_counter() - tic:.0f} s)")
    notes = case.notes(model, case.t_end) if case.notes else []
    return Result(case, ref, points, scan_ref, verdicts, rate_verdicts,
                  {k: v.relative_to(out.parent) for k, v in figures.items()}, time.perf_counter() - tic, notes)


def animate(name: str, build: Path, out: Path) -> Path:
    options = dict(ANIMATIONS[name])
    model, _ = andyc.compile_model(ROOT / "models" / f"{name}.yaml", build)
    run = andyc.simulate(model, options.pop("t_end"), frames="all", progress=False, **options)
    path = out / f"{name}.gif"
    animate_run(run, path, fps=25, max_frames=250)
    try:            # and the same run as a page for the browser (andyc view; needs meshcat)
        from andyc.plot.view import write_view

        info = write_view(run, out / f"{name}.html")
        print(f"  {name}: andyc view of the {run.time[-1]:.1f} s run: {info['seconds']:.2f} s, "
              f"{info['bytes'] / 1e6:.2f} MB ({info['samples']} samples of {len(run.time)})", flush=True)
    except ImportError as exc:
        print(f"  {name}: andyc view skipped ({exc})", flush=True)
    return path


# -- the reading ---------------------------------------------------------------

def _setting(p) -> str:
    return f"h = {p.setting:.3g} s" if p.method in FIXED_STEP else f"tol {p.setting:.0e}"


def _ms(seconds: float) -> str:
    return f"{seconds * 1e3:.3g} ms"


def cheapest(points, target: float) -> list:
    """Per method, its cheapest run (wall time) with error at T within `target`; cheapest first."""
    best = {}
    for p in points:
        if p.error <= target and (p.method not in best or p.wall < best[p.method].wall):
            best[p.method] = p
    return sorted(best.values(), key=lambda p: p.wall)


def summary(result: Result) -> str:
    """One sentence: who wins at most accuracies (in wall time), who never gets within 1e-3, who fails."""
    ref, points = result.ref, result.points
    methods = list(dict.fromkeys(p.method for p in points))
    rankings = [ranked for target in TARGETS if (ranked := cheapest(points, target * ref.scale))]
    wins = [ranked[0].method for ranked in rankings]
    never = [m for m in methods if not cheapest([p for p in points if p.method == m], TARGETS[0] * ref.scale)]
    failing = [m for (m, _), (_, fail, _) in stability.boundaries(result.verdicts).items() if fail]
    out = []
    if wins:
        best = max(set(wins), key=wins.count)
        # Within 10% is a tie: the machine's speed varies more than that between runs.
        ties = sorted({r[1].method for r in rankings if r[0].method == best and len(r) > 1 and r[1].wall < 1.1 * r[0].wall})
        out.append(f"**{best}** is the cheapest in wall time at {wins.count(best)} of the {len(TARGETS)} accuracies"
                   + (f" (tied within 10% with {' and '.join(ties)} at some of them)" if ties else ""))
    if never:
        out.append(f"{', '.join(never)} never get{'s' if len(never) == 1 else ''} within 1e-3 of the amplitude")
    stable = [m for m in dict.fromkeys(m for m, _ in stability.boundaries(result.verdicts)) if m not in failing]
    if stable:
        out.append(f"{', '.join(stable)} fail{'s' if len(stable) == 1 else ''} at no step scanned")
    return "In short: " + "; ".join(out) + "."


def reading(result: Result) -> list:
    """Bullet points, each a measured fact."""
    ref, points = result.ref, result.points
    lines = [summary(result)] + result.notes
    for target in TARGETS:
        ranked = cheapest(points, target * ref.scale)
        if not ranked:
            lines.append(f"No method reaches {target:.0e} of the amplitude at T = {ref.t_end:g} s with the steps "
                         f"and tolerances tried.")
            continue
        win = ranked[0]
        fewest = min(ranked, key=lambda p: p.rhs)
        rest = "; ".join(f"{p.method} {p.wall / win.wall:.1f}x slower ({_setting(p)})" for p in ranked[1:])
        missing = [m for m in dict.fromkeys(q.method for q in points) if m not in {p.method for p in ranked}]
        line = (f"Error ≤ {target:.0e} of the amplitude at T: cheapest **{win.method}** at {_setting(win)}, "
                f"{_ms(win.wall)}, {win.rhs} evaluations" + (f"; {rest}" if rest else "")
                + (f"; not reached by {', '.join(missing)}" if missing else ""))
        if fewest is not win:
            line += f". Fewest evaluations: {fewest.method} ({fewest.rhs})"
            if fewest.method not in FIXED_STEP:     # scipy's solvers step in Python; the fixed-step loop is compiled
                line += ", but scipy drives each of its steps from Python"
        lines.append(line + ".")
    for method in dict.fromkeys(p.method for p in points):
        mine = [p for p in points if p.method == method]
        stopped = [p for p in mine if not p.finished]
        if stopped:
            why = stopped[0].status.removeprefix("stopped: ").split("; the ")[0].rstrip(".")
            lines.append(f"{method} stopped in {len(stopped)} of its {len(mine)} sweep runs "
                         f"({', '.join(_setting(p) for p in stopped)}); at {_setting(stopped[0])}: {why}.")
    model_residuals = [p for p in points if p.finished and p.residual > 0]
    if model_residuals:
        worst = {}
        for p in model_residuals:
            worst[p.method] = max(worst.get(p.method, 0.0), p.residual)
        lines.append("Largest constraint residual over the sweep: "
                     + ", ".join(f"{m} {r:.1e}" for m, r in sorted(worst.items(), key=lambda kv: kv[1])) + ".")
    drifts = {}
    for p in points:
        if p.finished and math.isfinite(p.energy_drift):
            drifts[p.method] = max(drifts.get(p.method, 0.0), p.energy_drift)
    if drifts:
        lines.append("Largest relative energy drift over the sweep: "
                     + ", ".join(f"{m} {d:.1e}" for m, d in sorted(drifts.items(), key=lambda kv: kv[1])) + ".")
    horizon = result.scan_ref.t_end
    for (method, _), (accurate, failing, why) in stability.boundaries(result.verdicts).items():
        lines.append(f"Stability over {horizon:g} s, **{method}**: "
                     + (f"accurate up to h = {accurate:.3g} s" if accurate else "accurate at no step scanned")
                     + (f"; fails from h = {failing:.3g} s: {why.rstrip('.')}" if failing else "; no failure in the scan")
                     + ".")
    if result.rate_verdicts:
        lines.append("Baumgarte gains K_s = w², K_d = 2w, by w (1/s): "
                     + "; ".join(f"w = {variant:.3g}: " + (f"accurate to h = {acc:.3g} s" if acc else "never accurate")
                                 + (f", fails from {fail:.3g} s" if fail else "")
                                 for (_, variant), (acc, fail, _) in
                                 stability.boundaries(result.rate_verdicts).items()) + ".")
    return lines


def write_markdown(results: list, animations: dict, speed_text: str, seconds: float, path: Path) -> None:
    """docs/BENCHMARKS.md: figures, readings, animations and the speed tables of bench/run.py."""
    import platform

    out = ["# andyc benchmarks", "",
           f"Written by `make bench` (bench/run.py) on {time.strftime('%Y-%m-%d')}: andyc {andyc.__version__}, "
           f"Python {platform.python_version()}, {platform.machine()}, {_cores()} cores; the whole run took "
           f"{seconds / 60:.1f} min. Regenerate with `make bench`; every figure and number below is from that "
           "one run (this machine's speed varies by up to 1.4x between runs, so compare ratios within it).", "",
           "Work-precision: each method at each step (fixed-step; adjusted to divide T) or tolerance (adaptive, "
           "rtol = atol), error = largest |x(T) - x_ref(T)| over the state, cost = wall time (best of 3, "
           "compilation excluded) and right-hand-side evaluations. Stability: each run is **accurate** (error at T "
           "within 1e-3 of the amplitude), **inaccurate** (finished and bounded, not accurate) or **failed** "
           "(stopped, blew up past 1e3 x the amplitude, constraint residual past 1e-6, or a jump count other than "
           "the reference's). Tables of every run are the CSV files beside the figures.", "",
           "Commands for one model: `andyc bench models/NAME.yaml --t-end T` and "
           "`andyc stability models/NAME.yaml --horizon T [--gains geom:A:B:N]`.", ""]
    for r in results:
        out += [f"## {r.case.title}", "", r.case.about, "",
                f"ReferenceSolution: {r.ref.source}; amplitude (largest |x|) {r.ref.scale:.3g}, {r.ref.jumps} jumps to "
                f"T = {r.ref.t_end:g} s. {len(r.points)} sweep runs, {len(r.verdicts) + len(r.rate_verdicts)} scan "
                f"runs, {r.seconds:.0f} s in all.", ""]
        for what, fig in r.figures.items():
            out += [f"![{r.case.title}: {what}]({fig.as_posix()})", ""]
        out += ["Reading:", ""] + [f"- {line}" for line in reading(r)] + [""]
    out += ["## Animations", ""]
    for name, fig in animations.items():
        out += [f"![{name}]({fig.as_posix()})", ""]
    out += kept_sections(path)
    out += ["## Speed, and everything else `make bench` printed", "", "```", speed_text.strip(), "```", ""]
    path.write_text("\n".join(out))


# sections of docs/BENCHMARKS.md measured by their own scripts (bench/first_run.sh, bench/go1.py)
KEPT = ("First run", "Legged robots: Go1 beside MuJoCo")


def kept_sections(path: Path) -> list:
    """The lines of the KEPT sections of the file at path as it stands, to write again: this run does not measure
    them."""
    if not path.exists():
        return []
    out, keep = [], False
    for line in path.read_text().splitlines():
        if line.startswith("## "):
            keep = line[3:].strip() in KEPT
        if keep:
            out.append(line)
    return out + ([""] if out and out[-1] else [])


def _cores() -> int:
    import os
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
