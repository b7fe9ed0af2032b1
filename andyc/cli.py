"""Command line: a thin layer over the Python API (andyc.pipeline, andyc.simulate).

Exit codes: 0 success, 1 an invalid model or a run that stopped, 2 usage, 130 / 143 a run interrupted by
SIGINT / SIGTERM (its samples written), 70 a bug in andyc.
"""

from __future__ import annotations

import math
import os
import sys
import warnings
from pathlib import Path

import click

import andyc
from andyc.cli_values import COUNT, NON_NEGATIVE, POSITIVE, TOLERANCE, Number, floats, parse_sets
from andyc.errors import SimulationError, SpecError, printable
from andyc.outputs import OutputError, check_folder, check_output, write_atomic, write_text
from andyc.runtime.methods import FIXED_STEP, MAX_STEPS, METHODS


def _fail_spec(exc: SpecError) -> None:
    for d in exc.diagnostics:
        click.echo(str(d), err=True)
    click.echo(f"{_plural(len(exc.diagnostics), 'problem')} found", err=True)
    sys.exit(1)


def _summary(file, spec, model) -> str:
    """One line: what the model is, for `andyc check`."""
    speeds = ", ".join([c.name for c in spec.coordinates] + [s.name for s in spec.speeds])
    cons = model.constraints
    freedom = (f"{_plural(model.dof, 'degree')} of freedom ({speeds})" if not spec.constraints else
               f"{model.dof} speeds ({speeds}) less {_plural(cons.nc, 'constraint row')} ({cons.nh} holonomic) "
               f"in {_plural(len(spec.constraints), 'constraint')}")
    signals = f" incl. {len(model.signals)} nonholonomic signals" if model.signals else ""
    if spec.jumps:
        flows = ", ".join(f"{f.name} ({_plural(sum(len(c.rows) for c in spec.constraints if c.name in f.constraints), 'row')})"
                          for f in spec.flows)
        freedom += (f"; hybrid: {_plural(len(spec.flows), 'flow')} ({flows}), {_plural(len(spec.jumps), 'jump')}, "
                    f"{_plural(len(spec.discrete), 'discrete state')}")
    n_elements = len(spec.loads) + len(spec.dampers) + len(spec.springs) + len(spec.potentials)
    n_frames = len([f for f in spec.frames if not f.internal])
    return (f"{file}: model '{spec.name}' is valid: {freedom}, "
            f"{_plural(len(model.q) + model.dof + len(model.signals), 'state')}{signals}, "
            f"{_plural(len(spec.bodies), 'body').replace('bodys', 'bodies')}, {_plural(n_frames, 'frame')} besides "
            f"world, {_plural(len(spec.parameters), 'parameter')}, {_plural(len(spec.inputs), 'input')}, "
            f"{_plural(n_elements, 'force element')}; {len(model.assignments)} intermediate expressions.")


def _reduction(file, spec, model) -> str:
    """What reduction saved on a URDF robot: the robot as written (every joint free, every body its own)
    against the model derived, with the locked joints held and the bodies fixed to one moving frame merged."""
    from dataclasses import replace

    from andyc.codegen.generate import render

    free = andyc.load(file, unlock=True) if spec.locked else spec
    full_model = andyc.derive(replace(free, reduce=False))
    full = render(full_model, "")[1]
    reduced = render(model, "")[1]
    dof = (f"{full_model.dof} -> {model.dof} degrees of freedom ({_plural(len(spec.locked), 'joint')} locked: "
           f"{', '.join(spec.locked)})" if spec.locked else f"{model.dof} degrees of freedom")
    bodies = _plural(len(spec.bodies), "body").replace("bodys", "bodies")
    merged = (f"{bodies} merged into {len(model.spec.bodies)} (one per moving frame)"
              if len(model.spec.bodies) < len(spec.bodies) else f"{bodies}, none fixed to another's frame")
    return (f"  reduced: {dof}; {merged}; dynamics {full['dynamics']} -> {reduced['dynamics']} operations, "
            f"all functions {sum(full.values())} -> {sum(reduced.values())}")


def _progress(label: str, unit: str):
    """A progress callback (done, total) for long work, on a terminal only (stderr): silent for the first
    second, then one line rewritten once a second; the last call ends the line. Elsewhere (a pipe, a log,
    a test) it prints nothing, so that output never depends on how fast the machine is."""
    import time

    if not sys.stderr.isatty():
        return lambda done, total: None
    start, shown = time.monotonic(), [0.0]

    def show(done: int, total: int) -> None:
        seconds = time.monotonic() - start
        if seconds > 1 and ((done == total and shown[0]) or seconds - shown[0] >= 1):
            shown[0] = seconds
            click.echo(f"\r{label}: {done} of {total} {unit}, {seconds:.0f} s", err=True, nl=done == total)
    return show


def _plural(n: int, word: str) -> str:
    return f"{n} {word}{'' if n == 1 else 's'}"


class Refused(click.ClickException):
    """A request andyc will not carry out (an output over an input, say): `Error: ...`, exit 2, no usage text."""
    exit_code = 2

    def __init__(self, message: str):
        super().__init__(printable(message))


class _Andyc(click.Group):
    """The command group: text that cannot be encoded is escaped, not fatal (a message may quote a file name
    with undecodable bytes); an output that must not be written, Ctrl-C and bugs get a message, not a
    traceback (ANDYC_DEBUG=1 shows the traceback of a bug)."""

    def main(self, *args, **kwargs):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.reconfigure(errors="backslashreplace")
            except (AttributeError, ValueError):
                pass
        return super().main(*args, **kwargs)

    def invoke(self, ctx):
        try:
            return super().invoke(ctx)
        except OutputError as exc:
            raise Refused(str(exc)) from None
        except KeyboardInterrupt:
            click.echo("andyc: interrupted", err=True)
            ctx.exit(130)
        except RecursionError:
            raise Refused("the input is nested too deeply for andyc to process; simplify it") from None
        except (click.ClickException, click.exceptions.Exit, click.exceptions.Abort, SystemExit):
            raise
        except Exception as exc:
            if os.environ.get("ANDYC_DEBUG"):
                raise
            click.echo(f"andyc: internal error ({type(exc).__name__}: {exc}); this is a bug in andyc: please "
                       f"report it with the command and its input (ANDYC_DEBUG=1 shows the traceback)", err=True)
            ctx.exit(70)


@click.group(cls=_Andyc, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(andyc.__version__, prog_name="andyc")
def main():
    """andyc: compile multibody models (YAML or URDF) into fast simulation code.

    \b
    andyc check model.yaml      validate, print a summary (also robot.urdf)
    andyc build model.yaml      write build/<name>/<name>.py
    andyc sim model.yaml        build if needed, simulate, write run files
    andyc plot run.h5           plot states and energy
    andyc linearize model.yaml  A, B and eigenvalues about a state
    andyc bench model.yaml      work-precision: error against cost per method
    andyc stability model.yaml  stability map: step against method, failures named
    andyc eom model.yaml        M, G, constraint Jacobian, per element (LaTeX)
    """


@main.command()
@click.argument("files", nargs=-1, required=True, type=click.Path(dir_okay=False))
def check(files):
    """Validate model FILES (YAML or URDF); print every problem as FILE:LINE: PATH: what; fix."""
    problems = 0
    for file in files:
        try:
            spec = andyc.load(file)
            model = andyc.derive(spec)
        except SpecError as exc:
            for d in exc.diagnostics:
                click.echo(str(d), err=True)
            problems += len(exc.diagnostics)
            continue
        for w in spec.warnings:
            click.echo(f"{w} (warning)", err=True)
        click.echo(_summary(file, spec, model))
        if spec.reduce:
            click.echo(_reduction(file, spec, model))
    if problems:
        click.echo(f"{_plural(problems, 'problem')} found", err=True)
    sys.exit(1 if problems else 0)


@main.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("-o", "--out-dir", default="build", show_default=True, help="Build folder; writes DIR/<name>/<name>.py.")
@click.option("--force", is_flag=True, help="Derive, generate and compile again, even if the equations are "
              "unchanged; replaces the build of another model file of the same name.")
def build(file, out_dir, force):
    """Derive the equations of motion of FILE and generate its module."""
    check_folder(out_dir, [file])
    model, result = _compiled(file, out_dir, force)
    t = result.timings
    compile = (f"compile {t['compile']:.2f} s ({_plural(result.compiled, 'function')} compiled)" if result.compiled
               else f"loaded from Numba's cache in {t['compile']:.2f} s")
    if result.skipped:
        click.echo(f"{result.module_path}: up to date (equations and andyc unchanged); {compile}")
    else:
        ops = sum(result.operations.values())
        click.echo(f"{result.module_path}: built; derive {t['derive']:.2f} s, generate {t['generate']:.2f} s, "
                   f"{compile}; {ops} operations ({', '.join(f'{k} {v}' for k, v in result.operations.items())})")
    _report_jumps_file(result)


def _report_jumps_file(result) -> None:
    """Say what happened to the user's jump template."""
    if result.jumps_path is None:
        return
    if not result.jumps_kept:
        click.echo(f"{result.jumps_path}: written, one function per jump: edit it for resets beyond the model file")
        return
    click.echo(f"{result.jumps_path}: kept (yours; never overwritten; delete it to get a fresh template)")
    for name in result.jumps_missing:
        click.echo(f"{result.jumps_path}: warning: no function for jump '{name}' (added to the model since the file "
                   f"was written): it gets no extra resets; add `def {name}(t, x, u, p, d)` with @njit, or delete "
                   f"the file to regenerate it", err=True)


@main.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--at", "at", multiple=True, metavar="NAME=VALUE",
              help="The state to linearize about: a coordinate or speed (the others: the model's initial state).")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("--input", "input_values", multiple=True, metavar="NAME=VALUE",
              help="The inputs at the point (default: their held values); the same as --set for an input.")
@click.option("--flow", default=None, help="The flow to linearize (default: the initial flow).")
@click.option("--time", "t", default=0.0, show_default=True, type=Number(), help="Time t of the point, s.")
@click.option("--find-equilibrium", is_flag=True,
              help="First find the rest point (speeds 0, dv/dt = 0) nearest the coordinates given (Newton on G = 0).")
@click.option("-o", "--out", "out_dir", default=None, metavar="DIR",
              help="Also write DIR/<name>_linearization.npz (A, B, x, u, names, eigenvalues) and DIR/<name>_A.csv, "
                   "DIR/<name>_B.csv.")
def linearize(file, at, sets, input_values, flow, t, find_equilibrium, out_dir):
    """Linearize FILE's equations of motion: dx' = A dx + B du, from exact derivatives; print the eigenvalues."""
    import numpy as np

    from andyc.symbolic.linearize import LinearizeError, default_point, find_equilibrium as equilibrium
    from andyc.symbolic.linearize import linearize as linearized

    try:
        spec = andyc.load(file)
        model = andyc.derive(spec)
    except SpecError as exc:
        _fail_spec(exc)
    if out_dir:
        check_folder(out_dir, spec.files)
        for suffix in ("_linearization.npz", "_A.csv", "_B.csv"):
            check_output(Path(out_dir) / f"{spec.name}{suffix}", spec.files, "linearization")
    overrides = parse_sets(sets)
    given = parse_sets(input_values, "--input")
    overrides.update(given)
    states = parse_sets(at, "--at")
    try:
        flows = model.hybrid.flows
        if flow is not None and flow not in flows:
            raise LinearizeError(f"{spec.name}: no flow named '{flow}'; flows: {', '.join(flows)}")
        k = flows.index(flow) if flow is not None else None
        unknown = sorted(set(given) - set(spec.inputs))
        if unknown:
            raise LinearizeError(f"{spec.name}: no input named {', '.join(unknown)} (--input); inputs: "
                                 f"{', '.join(spec.inputs) or 'none'}")
        x, u, p, d = default_point(model, {n: v for n, v in overrides.items() if n not in spec.inputs},
                                   {n: v for n, v in overrides.items() if n in spec.inputs}, k)
        names = [c.name for c in spec.coordinates] + list(spec.speed_names)
        for name, value in states.items():
            if name not in names:
                raise LinearizeError(f"{spec.name}: no coordinate or speed named '{name}' (--at); "
                                     f"states: {', '.join(names)}")
            x[names.index(name)] = value
        if find_equilibrium:
            n = len(spec.coordinates)
            x[:n] = equilibrium(model, x[:n], u, p, d, t, k)
            x[n:] = 0.0
        lin = linearized(model, x, u, p, d, t, k)
    except LinearizeError as exc:
        click.echo(f"{file}: {exc}", err=True)
        sys.exit(1)
    np.set_printoptions(precision=6, suppress=False, linewidth=120)
    point = ", ".join(f"{n} = {v:.10g}" for n, v in zip(lin.state_names, lin.x))
    inputs = ", ".join(f"{n} = {v:.10g}" for n, v in zip(lin.input_names, lin.u)) or "none"
    click.echo(f"{spec.name}: linearized in flow '{lin.flow}' at t = {lin.t:g} about {point}; inputs {inputs}")
    if lin.form == "null-space":
        click.echo(f"flow '{lin.flow}' is constrained: null-space form, dq = N_q z, dv = N_v w (orthonormal bases of "
                   f"the null space of its constraint rows at the point)\nN_q =\n{lin.basis_q}\nN_v =\n{lin.basis_v}")
    click.echo(f"states: {', '.join(lin.state_names)}\nA =\n{lin.A}")
    if lin.input_names:
        click.echo(f"inputs: {', '.join(lin.input_names)}\nB =\n{lin.B}")
    ev = lin.eigenvalues
    click.echo("eigenvalues: " + ", ".join(f"{e.real:.10g}{e.imag:+.10g}j" if e.imag else f"{e.real:.10g}" for e in ev))
    unstable = int(np.sum(ev.real > 1e-9 * max(1.0, np.abs(ev).max())))
    click.echo(f"{_plural(unstable, 'eigenvalue')} with positive real part" + (" (unstable)" if unstable else ""))
    if out_dir:
        out = Path(out_dir)
        bases = {"N_q": lin.basis_q, "N_v": lin.basis_v} if lin.form == "null-space" else {}
        with write_atomic(out / f"{spec.name}_linearization.npz") as tmp, open(tmp, "wb") as fh:
            np.savez(fh, A=lin.A, B=lin.B, x=lin.x, u=lin.u, t=lin.t,
                     state_names=np.array(lin.state_names), input_names=np.array(lin.input_names, dtype=str),
                     eigenvalues=ev, flow=lin.flow, form=lin.form, **bases)
        for matrix, names, suffix in ((lin.A, lin.state_names, "A"), (lin.B, lin.input_names, "B")):
            with write_atomic(out / f"{spec.name}_{suffix}.csv") as tmp:
                np.savetxt(tmp, matrix, delimiter=",", header=",".join(names), comments="")
        click.echo(f"wrote {out / f'{spec.name}_linearization.npz'}, {spec.name}_A.csv and {spec.name}_B.csv")


@main.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--t-end", default=10.0, show_default=True, type=POSITIVE, help="End time, s.")
@click.option("--dt", default=1e-3, show_default=True, type=POSITIVE, help="Step (rk4) or output spacing (adaptive methods), s.")
@click.option("--method", default="rk4", show_default=True,
              type=click.Choice(list(METHODS)))
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("--input", "input_specs", multiple=True, metavar="NAME=VALUE|EXPR|FILE.csv",
              help="Drive an input: a number; an expression of t, the states, parameters and discrete states "
                   "(\"-10*th - 2*th_dot\"); or a CSV table with a time column t and a column NAME, interpolated.")
@click.option("--controller", type=click.Path(dir_okay=False), default=None, metavar="FILE.py",
              help="A Python file defining control(t, x, d, p), returning the inputs (compiled with Numba when it can "
                   "be); it drives every input.")
@click.option("--out", "outs", multiple=True, metavar="RUN.h5|RUN.csv",
              help="Run file(s) to write; default runs/<name>.h5.")
@click.option("--every", default=1, show_default=True, type=COUNT, help="Log one sample every N steps.")
@click.option("--frames", default=None, metavar="all|F1,F2", help="Log the world positions of these frames.")
@click.option("--init", "init", default="check", show_default=True, type=click.Choice(["check", "project", "as-is"]),
              help="Initial state off the constraint manifold: refuse past --init-tol (check), project it onto "
                   "the manifold (project), or start from it anyway (as-is).")
@click.option("--init-tol", default=1e-6, show_default=True, type=NON_NEGATIVE, help="Largest initial constraint residual accepted by check.")
@click.option("--energy-correction/--no-energy-correction", default=None,
              help="Braun & Goldfarb energy correction of the projection method; default on when the model "
                   "declares conserves_energy.")
@click.option("--energy-tol", default=1e-6, show_default=True, type=NON_NEGATIVE,
              help="Energy correction only where 2T exceeds this (Braun & Goldfarb eq. 6).")
@click.option("--event-tol", default=1e-12, show_default=True, type=Number(0, 1, low_open=True),
              help="Guard crossings are located to this many seconds (relative beyond t = 1 s).")
@click.option("--max-instant-jumps", default=100, show_default=True, type=COUNT,
              help="Stop after this many jumps at one instant (a jump loop).")
@click.option("--zeno-tol", default=1e-6, show_default=True, type=NON_NEGATIVE,
              help="Stop when jump times accumulate at a point less than this many seconds ahead (Zeno).")
@click.option("--stop-after", "stop_after", multiple=True, metavar="JUMP=N",
              help="End the run right after the N-th occurrence of JUMP.")
@click.option("--rtol", default=1e-8, show_default=True, type=TOLERANCE, help="Relative tolerance (adaptive methods).")
@click.option("--atol", default=1e-10, show_default=True, type=POSITIVE, help="Absolute tolerance (adaptive methods).")
@click.option("--timeout", default=None, type=POSITIVE, metavar="SECONDS",
              help="Stop the run after this much wall time, keeping its samples (also when a controller never "
                   "returns).")
@click.option("-o", "--out-dir", default="build", show_default=True, help="Build folder.")
def sim(file, t_end, dt, method, sets, input_specs, controller, outs, every, frames, init, init_tol, energy_correction,
        energy_tol, event_tol, max_instant_jumps, zeno_tol, stop_after, rtol, atol, timeout, out_dir):
    """Build FILE if needed, simulate it and write run files.

    SIGINT (Ctrl-C) or SIGTERM stop the run and write the samples so far, with the status "interrupted";
    the exit code is then 130 or 143."""
    from andyc.runtime.inputs import InputWarning
    from andyc.runtime.interrupts import Interrupts
    from andyc.runtime.run import RUN_SUFFIXES

    overrides = parse_sets(sets)
    stops = {}
    for item in stop_after:
        name, sep, count = item.partition("=")
        if not sep or not count.strip().isdigit() or int(count) < 1:
            raise click.BadParameter(f"'{item}' is not JUMP=N with N >= 1", param_hint="--stop-after")
        stops[name.strip()] = int(count)
    inputs = {}
    for item in input_specs:
        name, sep, value = item.partition("=")
        if not sep or not value.strip():
            raise click.BadParameter(f"'{item}' is not NAME=VALUE", param_hint="--input")
        if name.strip() in inputs:
            raise click.BadParameter(f"input '{name.strip()}' given twice", param_hint="--input")
        try:
            number = float(value)
        except ValueError:
            number = 0.0
        if not math.isfinite(number):
            raise click.BadParameter(f"'{item}': {value.strip()} is not a finite number", param_hint="--input")
        inputs[name.strip()] = value.strip()
    read = [file, controller] + [v for v in inputs.values() if v.lower().endswith(".csv")]
    for out in outs:
        if Path(out).suffix.lower() not in RUN_SUFFIXES:
            raise click.BadParameter(f"unknown run file type '{Path(out).suffix}'; use .h5 or .csv",
                                     param_hint="--out")
        check_output(out, read, "run file")
    check_folder(out_dir, read)
    if t_end / dt > MAX_STEPS:
        raise click.BadParameter(f"t_end / dt = {t_end / dt:.3g} steps, past the limit of {MAX_STEPS:.0e}; raise "
                                 f"--dt or shorten --t-end", param_hint="--dt")
    model, result = _compiled(file, out_dir)
    if not result.skipped:
        _report_jumps_file(result)
    outs = outs or (f"runs/{model.name}.h5",)
    read += [model.path, result.jumps_path]
    for out in outs:
        check_output(out, read, "run file")
    if result.compiled:
        click.echo(f"{model.name}: compiled {_plural(result.compiled, 'function')} in {result.timings['compile']:.1f} s "
                   f"(once per build: Numba caches them)", err=True)
    params = {k: v for k, v in overrides.items() if k not in model.input_names}
    for name in (k for k in overrides if k in model.input_names):
        if name in inputs:
            raise click.BadParameter(f"input '{name}' given twice", param_hint="--input")
        inputs[name] = overrides[name]

    def save(run) -> None:
        for out in outs:
            run.save(out)

    def abandon(run) -> None:       # the watchdog's: the run never returned
        save(run)
        click.echo(f"{run.status}; wrote {', '.join(outs)}", err=True)

    interrupts = Interrupts(timeout, abandon)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", InputWarning)
            run = andyc.simulate(model, t_end, dt=dt, method=method, parameters=params, inputs=inputs,
                                 controller=controller, every=every, frames=frames, rtol=rtol, atol=atol,
                                 interrupts=interrupts, init=andyc.Init(mode=init, tol=init_tol),
                                 projection=andyc.Projection(energy_correction=energy_correction,
                                                             energy_tol=energy_tol),
                                 events=andyc.Events(tol=event_tol, max_instant_jumps=max_instant_jumps,
                                                     zeno_tol=zeno_tol, stop_after=stops))
    except SimulationError as exc:
        raise Refused(str(exc))
    finally:
        for w in caught:
            click.echo(f"warning: {w.message}", err=True)
    save(run)
    s = run.stats
    constraints = ""
    if model.nc:
        constraints = (f"; largest constraint residuals: position {_largest(run.residual_position):.3g}, "
                       f"velocity {_largest(run.residual_velocity):.3g}")
        if "initial_projection" in s:
            constraints += f" (initial state projected from {s['initial_projection']:.3g})"
    if model.nj:
        counts = {}
        for name in run.event_names():
            counts[name] = counts.get(name, 0) + 1
        constraints += (f"; {_plural(len(run.events['time']), 'jump')}"
                        + (f" ({', '.join(f'{k} {v}' for k, v in counts.items())})" if counts else "")
                        + f", ending in flow {run.flow_names[run.flow[-1]]}")
    click.echo(f"{model.name}: {method}, t = 0 .. {run.time[-1]:.6g} s, {s['steps']} steps, "
               f"{s['rhs_evaluations']} rhs evaluations, {s['wall_seconds']:.3f} s wall; "
               f"energy {run.energy[0]:.10g} -> {run.energy[-1]:.10g} J (change {run.energy[-1] - run.energy[0]:.3g} J)"
               f"{constraints}; wrote {', '.join(outs)}")
    if not run.finished:
        click.echo(run.status, err=True)
        sys.exit(interrupts.exit_code if run.status.startswith("interrupted") else 1)


def _largest(a) -> float:
    """The largest |entry|, skipping NaN (the rows a sample's flow does not use)."""
    import numpy as np

    return float(np.nanmax(np.abs(a), initial=0.0)) if a.size else 0.0


@main.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--format", "fmt", default="latex", show_default=True, type=click.Choice(["latex", "sympy", "json"]),
              help="latex: an equation block per quantity; sympy: a Python file defining the symbols and matrices; "
                   "json: names and each quantity as sympy str and LaTeX.")
@click.option("--element", default=None, metavar="NAME", help="Only this element's own M and G.")
@click.option("--flow", default=None, metavar="F", help="The flow whose constraint rows and inputs to use "
              "(default: the initial one).")
@click.option("--standalone", is_flag=True, help="latex: a whole document, not a fragment.")
@click.option("-o", "--out", default=None, metavar="FILE", help="Write to FILE (default: standard output).")
def eom(file, fmt, element, flow, standalone, out):
    """Print FILE's equations of motion for reading: M dv/dt = G, the flow's constraint rows phi, A and
    kappa, and each element's own M and G (ANDY eq. 5-8, 10-11), intermediates substituted, simplified."""
    from andyc.symbolic.eom import FACTOR_OPS, SIMPLIFY_OPS, EomError, equations, render

    if standalone and fmt != "latex":
        raise click.BadParameter("a whole document is LaTeX: use it with --format latex", param_hint="--standalone")
    try:
        spec = andyc.load(file)
        model = andyc.derive(spec)
    except SpecError as exc:
        _fail_spec(exc)
    if out:
        check_output(out, spec.files, "equations")
    show = _progress(spec.name, "entries written out")
    try:
        eq = equations(model, flow=flow, element=element, progress=lambda done, total, seconds: show(done, total))
    except EomError as exc:
        click.echo(f"{file}: {exc}", err=True)
        sys.exit(1)
    if eq.factored or eq.as_written:
        click.echo(f"{spec.name}: {eq.factored + eq.as_written} of {eq.entries} entries are past the simplification "
                   f"budget ({SIMPLIFY_OPS} operations written out; largest {eq.largest}): only factored"
                   + (f"; {eq.as_written} past {FACTOR_OPS} are left as written out, megabytes of text that take "
                      "minutes to print (--element NAME prints one element)" if eq.as_written else ""), err=True)
    text = render(eq, fmt, standalone)
    if out:
        write_text(out, text)
        click.echo(f"wrote {out} ({eq.entries} entries in {eq.seconds:.2f} s)")
    else:
        click.echo(text, nl=False)


def _methods(text: str, option: str) -> list:
    names = [m.strip() for m in text.split(",") if m.strip()]
    unknown = [m for m in names if m not in METHODS]
    if unknown or not names:
        raise click.BadParameter(f"unknown method(s) {', '.join(unknown) or '(none given)'}; available: "
                                 f"{', '.join(METHODS)}", param_hint=option)
    return names


def _scanned(model, text: str) -> tuple[str, list]:
    """'k=1e3,1e4' or 'k=geom:1e3:1e5:5' -> ('k', [values]) for a parameter of `model`."""
    name, sep, values = text.partition("=")
    name = name.strip()
    if not sep or name not in model.parameter_names:
        raise click.BadParameter(f"'{text}': give NAME=VALUES with NAME a parameter of {model.name} "
                                 f"({', '.join(model.parameter_names)})", param_hint="--scan")
    return name, floats(values, "--scan")


def _compiled(file, out_dir, force: bool = False):
    """(CompiledModel, BuildResult) of FILE; a model error is printed as andyc check does (exit 1)."""
    from andyc.codegen.buildfiles import numerics_compiled

    if sys.stderr.isatty() and not numerics_compiled():
        click.echo("andyc: compiling the integrator every model shares, once for this installation (about a "
                   "minute; a new model then compiles in seconds) ...", err=True)
    try:
        return andyc.compile_model(file, out_dir, force)
    except SpecError as exc:
        _fail_spec(exc)
    except SimulationError as exc:
        raise Refused(str(exc))


@main.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--methods", default=None, metavar="M1,M2",
              help="Methods to compare (default: rk4 and DOP853; with constraints also projection, lagrange, "
                   "baumgarte).")
@click.option("--steps", default=None, metavar="H1,H2|geom:A:B:N",
              help="Steps of the fixed-step methods, each adjusted to divide --t-end (default: T/100 .. T/10000).")
@click.option("--tols", default=None, metavar="R1,R2|geom:A:B:N",
              help="Tolerances (rtol = atol) of the adaptive methods (default: 1e-3 .. 1e-10).")
@click.option("--t-end", default=10.0, show_default=True, type=POSITIVE, help="Horizon T, s.")
@click.option("--repeats", default=3, show_default=True, type=Number(1, 1000, integer=True), help="Wall time: the best of this many runs.")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("-o", "--out", "out_dir", default="runs", show_default=True, metavar="DIR",
              help="Writes DIR/<name>_work_precision.csv, .png and .svg.")
@click.option("--reference", "reference", default="auto", show_default=True,
              type=click.Choice(["auto", "closed-form", "DOP853"]),
              help="What runs are compared with: the model's closed form (auto: when it declares one) or DOP853 "
                   "at rtol = atol = 1e-13.")
@click.option("--build-dir", default="build", show_default=True, help="Build folder.")
def bench(file, methods, steps, tols, t_end, repeats, sets, reference, out_dir, build_dir):
    """Work-precision of FILE: each method at each step or tolerance against a reference (the model's closed form,
    or DOP853 at rtol 1e-13); error at T against wall time and evaluations, as a table, a CSV and diagrams."""
    from andyc.analysis.sweep import reference as reference_run
    from andyc.analysis.workprecision import DEFAULT_TOLS, draw, sweep, write_csv

    check_folder(out_dir, [file])
    check_folder(build_dir, [file])
    model = _compiled(file, build_dir)[0]
    for suffix in (".csv", ".png", ".svg"):
        check_output(Path(out_dir) / f"{model.name}_work_precision{suffix}", [file], "work-precision file")
    overrides = parse_sets(sets)
    chosen = _methods(methods, "--methods") if methods else (
        ["rk4", "projection", "lagrange", "baumgarte", "DOP853"] if model.nc else ["rk4", "DOP853"])
    options = {"parameters": {k: v for k, v in overrides.items() if k not in model.input_names},
               "inputs": {k: v for k, v in overrides.items() if k in model.input_names}}
    try:
        ref = reference_run(model, t_end, reference, **options)
    except SimulationError as exc:
        raise click.UsageError(str(exc))
    click.echo(f"{model.name}: work-precision over T = {t_end:g} s; reference: {ref.source}")
    click.echo(f"{'method':>10} {'step/tol':>9} {'error':>9} {'residual':>9} {'energy':>9} {'rhs':>8} "
               f"{'wall s':>9}  status")

    def show(p):
        click.echo(f"{p.method:>10} {p.setting:>9.3g} {p.error:>9.2e} {p.residual:>9.1e} {p.energy_drift:>9.1e} "
                   f"{p.rhs:>8} {p.wall:>9.2e}  {p.status[:60]}")

    try:
        ref, points = sweep(model, chosen, t_end, floats(steps, "--steps"),
                            floats(tols, "--tols") or DEFAULT_TOLS, repeats, progress=show, reference=ref,
                            **options)
    except SimulationError as exc:
        raise click.UsageError(str(exc))
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(points, out / f"{model.name}_work_precision.csv")
    figures = draw(points, ref, model.name, out / f"{model.name}_work_precision")
    click.echo(f"wrote {out / f'{model.name}_work_precision.csv'}, " + ", ".join(map(str, figures)))


@main.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--methods", default=None, metavar="M1,M2",
              help="Fixed-step methods to scan (default: rk4; with constraints projection, lagrange, baumgarte too).")
@click.option("--steps", default=None, metavar="H1,H2|geom:A:B:N",
              help="Steps, each adjusted to divide the horizon (default: geom:T/20:T/20000:31).")
@click.option("--horizon", "horizons", multiple=True, type=POSITIVE, metavar="T",
              help="Horizon(s), s; one map each (default: 10).")
@click.option("--tol", default=1e-3, show_default=True, type=POSITIVE,
              help="Accurate: the state error at T within TOL x the reference's amplitude.")
@click.option("--blowup", default=1e3, show_default=True, type=Number(1, low_open=True), help="Blown up: |x| past this x the reference's largest.")
@click.option("--residual-tol", default=1e-6, show_default=True, type=POSITIVE, help="Constraints lost: a residual past this.")
@click.option("--gains", default=None, metavar="W1,W2|geom:A:B:N",
              help="A second axis: Baumgarte gains stiffness w^2 and damping 2w at each w, 1/s (critical damping "
                   "at rate w for a unit effective mass; the gains must be parameters).")
@click.option("--scan", "scan_values", default=None, metavar="NAME=V1,V2|NAME=geom:A:B:N",
              help="A second axis: this parameter at each value (each with its own reference).")
@click.option("--reference", "reference", default="auto", show_default=True,
              type=click.Choice(["auto", "closed-form", "DOP853"]),
              help="What runs are compared with: the model's closed form (auto: when it declares one) or DOP853 "
                   "at rtol = atol = 1e-13.")
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("-o", "--out", "out_dir", default="runs", show_default=True, metavar="DIR",
              help="Writes DIR/<name>_stability_T<horizon>.csv, .png and .svg.")
@click.option("--build-dir", default="build", show_default=True, help="Build folder.")
def stability(file, methods, steps, horizons, tol, blowup, residual_tol, gains, scan_values, reference, sets, out_dir,
              build_dir):
    """Stability map of FILE: each fixed-step method at each step, classified accurate, inaccurate (stable,
    not accurate) or failed (stopped, blown up, constraints lost, event missed: what, and when)."""
    from andyc.analysis.stability import (baumgarte_rates, boundaries, draw_map, geometric, parameter_values, scan,
                                          write_csv)

    if gains and scan_values:
        raise click.UsageError("give --gains or --scan, not both: a map has one second axis")
    check_folder(out_dir, [file])
    check_folder(build_dir, [file])
    model = _compiled(file, build_dir)[0]
    for horizon in horizons or (10.0,):
        for suffix in (".csv", ".png", ".svg"):
            check_output(Path(out_dir) / f"{model.name}_stability_T{horizon:g}{suffix}", [file],
                         "stability file")
    overrides = parse_sets(sets)
    chosen = _methods(methods, "--methods") if methods else (
        ["rk4", "projection", "lagrange", "baumgarte"] if model.nc else ["rk4"])
    adaptive = [m for m in chosen if m not in FIXED_STEP]
    if adaptive:
        raise click.BadParameter(f"{', '.join(adaptive)}: the scan is over steps, for fixed-step methods",
                                 param_hint="--methods")
    options = {"parameters": {k: v for k, v in overrides.items() if k not in model.input_names},
               "inputs": {k: v for k, v in overrides.items() if k in model.input_names}}
    try:
        variants = (baumgarte_rates(model, floats(gains, "--gains")) if gains else
                    parameter_values(*_scanned(model, scan_values)) if scan_values else None)
    except SimulationError as exc:
        raise click.BadParameter(str(exc), param_hint="--gains")
    axis, name = (variants[0].axis, variants[0].name) if variants else (None, None)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    for horizon in horizons or (10.0,):
        grid = floats(steps, "--steps") or geometric(horizon / 20, horizon / 20000, 31)
        click.echo(f"{model.name}: stability over T = {horizon:g} s, {len(grid)} steps x {len(chosen)} methods"
                   + (f" x {len(variants)} values of {axis}" if variants else ""))

        def show(v):
            at = "" if v.variant is None else f" {name} = {v.variant:<9.4g}"
            click.echo(f"  {v.point.method:>10}{at} h = {v.point.setting:<10.4g} {v.verdict:>10}: {v.reason}")

        try:
            ref, verdicts = scan(model, chosen, grid, horizon, tol, blowup, residual_tol, progress=show,
                                 reference=reference, variants=variants, **options)
        except SimulationError as exc:
            raise click.UsageError(str(exc))
        click.echo(f"reference: {ref.source}")
        for (method, variant), (accurate, failing, why) in boundaries(verdicts).items():
            at = "" if variant is None else f" at {name} = {variant:.4g}"
            click.echo(f"{method}{at}: largest accurate step {'none' if accurate is None else f'{accurate:.4g} s'}; "
                       + (f"fails from h = {failing:.4g} s ({why})" if failing else "no failure in the scan"))
        stem = out / f"{model.name}_stability_T{horizon:g}"
        table = stem.with_name(stem.name + ".csv")          # (not with_suffix: the horizon may hold a '.')
        write_csv(verdicts, table)
        figures = draw_map(verdicts, ref, model.name, stem, axis)
        click.echo(f"wrote {table}, " + ", ".join(map(str, figures)))


@main.command()
@click.argument("run_file", type=click.Path(exists=True, dir_okay=False))
@click.option("-o", "--out", default=None, help="PNG file; default RUN.png beside the run. With --animate: the "
              "animation, OUT.gif or OUT.mp4 (needs ffmpeg); default RUN.gif beside the run.")
@click.option("--animate", is_flag=True, help="Instead of the plots, write a 3-D stick animation of the frames the "
              "run logged (andyc sim ... --frames all).")
@click.option("--fps", default=None, type=click.IntRange(1, 100), metavar="N",
              help="With --animate: frames per second (default 30; a GIF frame lasts whole hundredths of a "
                   "second: 30 plays at 33.3).")
@click.option("--frames-max", default=None, type=click.IntRange(min=1), metavar="N",
              help="With --animate: at most N frames, evenly spread in time (default 300); a run longer than "
                   "N / fps seconds plays faster than real time.")
def plot(run_file, out, animate, fps, frames_max):
    """Plot the states and the energy of a run against time (and, for a hybrid run, its flows,
    jumps and discrete states); when the run logged frames with their parents, also draw them as
    stick figures, into RUN_sticks.png (or OUT_sticks.png beside OUT). With --animate, write an
    animation of the logged frames instead."""
    from andyc.plot import plot_run, plot_sticks, stick_edges
    from andyc.runtime.run import read_h5

    if Path(run_file).suffix.lower() not in (".h5", ".hdf5"):
        raise click.BadParameter(f"{run_file}: andyc plot reads the HDF5 run file (.h5) that andyc sim writes; "
                                 f"write one with --out RUN.h5", param_hint="RUN_FILE")
    if not animate:
        given = [name for name, value in (("--fps", fps), ("--frames-max", frames_max)) if value is not None]
        if given:
            raise click.BadParameter("only with --animate", param_hint=" and ".join(given))
    out = out or str(Path(run_file).with_suffix(".gif" if animate else ".png"))
    check_output(out, [run_file], "plot")
    if not animate:
        check_output(Path(out).with_name(Path(out).stem + "_sticks.png"), [run_file], "plot")
    try:
        run = read_h5(run_file)
    except (OSError, KeyError, ValueError) as exc:
        raise click.BadParameter(f"{run_file}: not a run file that andyc sim wrote ({exc})",
                                 param_hint="RUN_FILE") from None
    if animate:
        from andyc.plot import animate_run, animation_writer

        fps = fps or 30
        if not run.frames:
            raise click.BadParameter(f"{run_file}: this run of {run.model} logged no frames to animate; re-run it "
                                     f"with `andyc sim MODEL.yaml --frames all --out {run_file}`",
                                     param_hint="RUN_FILE")
        try:
            animation_writer(out, fps)
        except ValueError as exc:
            raise click.BadParameter(str(exc), param_hint="'-o' / '--out'") from None
        info = animate_run(run, out, fps=fps, max_frames=frames_max or 300, progress=_progress(run.model, "frames"))
        pace = "real time" if info["speed"] < 1.01 else f"{info['speed']:.2f} x real time"
        click.echo(f"wrote {out} ({info['frames']} frames, {info['seconds']:.1f} s at {info['fps']:.3g} fps, {pace}; "
                   f"rendered in {info['render_seconds']:.1f} s)")
        return
    plot_run(run, out)
    click.echo(f"wrote {out}")
    if stick_edges(run):
        sticks = Path(out).with_name(Path(out).stem + "_sticks.png")
        plot_sticks(run, sticks)
        click.echo(f"wrote {sticks} (stick figures of the frames)")


if __name__ == "__main__":
    main()
