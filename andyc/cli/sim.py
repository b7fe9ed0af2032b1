"""`andyc sim`: build a model if needed, simulate it, write its run files and print the run's summary."""

from __future__ import annotations

import warnings
from pathlib import Path

import click

import andyc
from andyc.cli.common import Refused, build_dir_option, compiled, model_options, report_jumps_file
from andyc.cli.formats import Report, format_option
from andyc.cli.values import (COUNT, NON_NEGATIVE, POSITIVE, TOLERANCE, Number, input_drives, parse_sets, split_sets,
                              stop_counts)
from andyc.errors import InitialStateError, SimulationError, plural
from andyc.limits import MAX_STEPS
from andyc.outputs import check_folder, check_output
from andyc.runtime.methods import METHODS


@click.command()
@click.argument("file", type=click.Path(dir_okay=False))
@click.option("--t-end", default=10.0, show_default=True, type=POSITIVE, help="End time, s.")
@click.option("--dt", default=1e-3, show_default=True, type=POSITIVE,
              help="Step (rk4, moreau) or output spacing (adaptive methods), s.")
@click.option("--method", default="rk4", show_default=True,
              type=click.Choice(list(METHODS)))
@click.option("--set", "sets", multiple=True, metavar="NAME=VALUE", help="Override a parameter or input.")
@click.option("--at", "starts", multiple=True, metavar="NAME=VALUE",
              help="Start a state (or discrete state) at this value, the others at the model's initial values "
                   "(rerun a sweep's point: --set for its parameters, --at for its states).")
@click.option("--input", "input_specs", multiple=True, metavar="NAME=VALUE|EXPR|FILE.csv",
              help="Drive an input: a number; an expression of t, the states, parameters and discrete states "
                   "(\"-10*th - 2*th_dot\"); or a CSV table with a time column t and a column NAME, interpolated.")
@click.option("--controller", type=click.Path(dir_okay=False), default=None, metavar="FILE.py",
              help="A Python file defining control(t, x, d, p), returning the inputs (compiled with Numba when it can "
                   "be); it drives every input.")
@click.option("-o", "--out", "outs", multiple=True, metavar="RUN.h5|RUN.csv",
              help="Run file(s) to write; default runs/<name>.h5.")
@click.option("--every", default=1, show_default=True, type=COUNT, help="Log one sample every N steps.")
@click.option("--frames", default=None, metavar="all|F1,F2", help="Log the world positions of these frames.")
@click.option("--init", "init", default="check", show_default=True, type=click.Choice(["check", "project", "as-is"]),
              help="Initial state off the constraint manifold: refuse past --init-tol (check), project it onto "
                   "the manifold (project), or start from it anyway (as-is).")
@click.option("--init-tol", default=1e-6, show_default=True, type=NON_NEGATIVE, help="Largest initial constraint residual accepted by check.")
@click.option("--energy-correction/--no-energy-correction", default=None,
              help="Braun & Goldfarb energy correction of the projection method, to the balance E - E0 - W = 0 "
                   "(W the logged work of every element); default on when the model declares conserves_energy.")
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
@click.option("--theta", default=0.5, show_default=True, type=float,
              help="The moreau method's theta, in [0.5, 1]: M and the forces at q_k + theta h v_k (0.5: trapezoidal).")
@click.option("--timeout", default=None, type=POSITIVE, metavar="SECONDS",
              help="Stop the run after this much wall time, keeping its samples (also when a controller never "
                   "returns).")
@click.option("--sensitivities", is_flag=True, default=False,
              help="Also compute the exact dx(T)/dx0 and dx(T)/dp (rk4, lagrange, projection; through the jumps' saltation "
                   "matrices), "
                   "into the HDF5 run file's /sensitivities.")
@build_dir_option("--out-dir")
@format_option
def sim(file, t_end, dt, method, sets, starts, input_specs, controller, outs, every, frames, init, init_tol, energy_correction,
        energy_tol, event_tol, max_instant_jumps, zeno_tol, stop_after, rtol, atol, theta, timeout, sensitivities,
        build_dir, fmt):
    """Build FILE if needed, simulate it and write run files.

    The model's simulate: section gives the options not given here (then the defaults shown).
    SIGINT (Ctrl-C), SIGTERM or SIGHUP stop the run and write the samples so far, with the status
    "interrupted"; the exit code is then 130, 143 or 129."""
    from andyc.runtime.controller import InputWarning
    from andyc.runtime.interrupts import Interrupts
    from andyc.runtime.runfiles import RUN_SUFFIXES

    overrides = parse_sets(sets)
    starts = parse_sets(starts, "--at")
    stops = stop_counts(stop_after)
    inputs = input_drives(input_specs)
    read = [file, controller] + [v for v in inputs.values() if v.lower().endswith(".csv")]
    for out in outs:
        if Path(out).suffix.lower() not in RUN_SUFFIXES:
            raise click.BadParameter(f"unknown run file type '{Path(out).suffix}'; use .h5 or .csv (-o/--out is "
                                     f"the run file; the build folder is --build-dir)", param_hint="-o/--out")
        check_output(out, read, "run file")
    report = Report("sim", fmt)
    check_folder(build_dir, read, write=False)     # (an up-to-date build is only read)
    model, result = compiled(file, build_dir, report=report, integrator=False)
    given = model_options(click.get_current_context(), model.simulate)
    t_end, dt, method, every, init, init_tol = (given[k] for k in ("t_end", "dt", "method", "every", "init", "init_tol"))
    energy_correction, energy_tol, event_tol = given["energy_correction"], given["energy_tol"], given["event_tol"]
    max_instant_jumps, zeno_tol, rtol, atol = (given[k] for k in ("max_instant_jumps", "zeno_tol", "rtol", "atol"))
    frames = given["frames"]
    stops = model.simulate.get("stop_after", {}) if not stop_after else stops
    if method != "moreau" and click.get_current_context().get_parameter_source("theta").name == "COMMANDLINE":
        raise Refused(f"--theta is the moreau method's, not {method}'s; drop it, or use --method moreau")
    if t_end / dt > MAX_STEPS:
        raise click.BadParameter(f"t_end / dt = {t_end / dt:.3g} steps, past the limit of {MAX_STEPS:.0e}; raise "
                                 f"--dt or shorten --t-end", param_hint="--dt")
    if not result.skipped and report.text:
        report_jumps_file(result)
    outs = outs or (f"runs/{model.name}.h5",)
    read += [model.path, result.jumps_path]
    for out in outs:
        check_output(out, read, "run file")
    if result.compiled:
        report.say(f"{model.name}: compiled {plural(result.compiled, 'function')} in {result.timings['compile']:.1f} s "
                   f"(once per build: Numba caches them)", err=True)
    if sensitivities:
        try:
            andyc.build_derivatives(file, build_dir)
        except SimulationError as exc:
            raise Refused(str(exc))
    params, set_inputs = split_sets(overrides, model.input_names)
    for name, value in set_inputs.items():
        if name in inputs:
            raise click.BadParameter(f"input '{name}' given twice", param_hint="--input")
        inputs[name] = value

    def save(run) -> None:
        for out in outs:
            run.save(out)

    def abandon(run) -> None:       # the watchdog's: the run never returned
        save(run)
        click.echo(f"{run.status}; wrote {', '.join(outs)}", err=True)     # (from the watchdog's thread)

    interrupts = Interrupts(timeout, abandon)
    refused = None
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", InputWarning)
            run = andyc.simulate(model, t_end, dt=dt, method=method, parameters=params, inputs=inputs,
                                 x0={n: v for n, v in starts.items() if n not in model.discrete_names} or None,
                                 d0={n: v for n, v in starts.items() if n in model.discrete_names} or None,
                                 controller=controller, every=every, frames=frames, rtol=rtol, atol=atol,
                                 interrupts=interrupts, init=andyc.Init(mode=init, tol=init_tol),
                                 projection=andyc.Projection(energy_correction=energy_correction,
                                                             energy_tol=energy_tol),
                                 events=andyc.Events(tol=event_tol, max_instant_jumps=max_instant_jumps,
                                                     zeno_tol=zeno_tol, stop_after=stops),
                                 sensitivities=sensitivities, stepping=andyc.TimeStepping(theta=theta))
    except InitialStateError as exc:        # a problem of the model: exit 1, as andyc check's
        refused = exc.located(file)
    except SimulationError as exc:
        raise Refused(str(exc))
    finally:
        for w in caught:
            report.add(f"warning: {w.message}", "warning")
    if refused is not None:
        report.add(refused)
        report.results.append({"file": file, "ok": False})
        report.finish(1)
    save(run)
    report.say(f"{run.summary()}; wrote {', '.join(outs)}")
    if run.sensitivities is not None:
        h5 = [o for o in outs if Path(o).suffix.lower() != ".csv"]
        report.say(f"sensitivities: dx(T)/dx0 ({model.nx} x {model.nx}), dx(T)/dp ({model.nx} x "
                   f"{len(model.parameter_names)}) and dT/d(x0, d0, p) in " + (", ".join(f"{o}:/sensitivities" for o in h5)
                                                                            or "no file")
                   + ("; a CSV run file does not hold them" if len(h5) < len(outs) else ""))
    report.results.append({"file": file, "ok": run.finished, "summary": run.summary(), "outputs": list(outs),
                           "status": run.status})
    if not run.finished:
        report.add(run.status)
    report.finish(0 if run.finished else interrupts.exit_code if run.status.startswith("interrupted") else 1)
